"""Sensor logs: a run's inputs and commands recorded as ROS 2 messages in MCAP, read back from MCAP
files and ROS bags, and replayed as a robot whose clock plays the log."""

"""Drivers: the robot base, the pan-tilt unit, cameras and the simulator, behind small interfaces.

Behaviours never import an implementation from here: the runner builds a :class:`Robot` from a
profile and hands its interfaces to the tree at setup.
"""

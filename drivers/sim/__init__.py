"""The built-in simulator: the embedded default robot, deterministic for a seed."""

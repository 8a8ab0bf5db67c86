"""Perception: camera models, features, matching and motion estimation on numpy arrays.

Plain functions and frozen dataclasses only: no py_trees, no file or device I/O.
"""

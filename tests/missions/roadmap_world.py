"""The roadmap helpers of the tests, now in the package (:mod:`missions.eval.roadmap_world`, which
``bearings eval roadmap`` uses): re-exported here for the tests that import them from this module."""

from missions.eval.roadmap_world import (
    TrueTrajectory,
    named_poses,
    pose_error,
    random_starts,
    target_errors,
    usable_poses,
    world_path,
    world_with,
    write_target_images,
)

__all__ = ["TrueTrajectory", "named_poses", "pose_error", "random_starts", "target_errors", "usable_poses",
           "world_path", "world_with", "write_target_images"]

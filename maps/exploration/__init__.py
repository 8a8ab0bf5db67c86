"""Exploration with a stereo pair on a pan-tilt unit (algorithm 3, Rozman, Zbořil): the pure part.

Everything is in the odometry frame (REP-103: x, y on the floor, z up); every value is frozen. The
behaviours of :mod:`behaviours.exploration` read the blackboard, call these and write the result.

=================  ==========================================================================
module             what it holds
=================  ==========================================================================
``grid``           the map: :class:`ExplorationMap` (evidence, cells, points, edges, the
                   robot's trail, clearance), its :class:`GridFrame`, the robot's disc marked
                   free (``mark_traversed``), borders
``head``           the stereo pair on the pan-tilt head: ``StereoHead``, a ``CameraView``, the
                   floor footprint and the fields of view
``interest``       interest edges (eq. 2): ``Interest``, ``edge_geometry``, classification,
                   re-evaluation from the current pose, image-neighbour edges
``integrate``      one stereo observation into the map, and its virtual range scan
``travel``         the travel cost G of eq. 1: shortest paths through known free space
``goal``           where to go next: attractive power (eq. 1), frontier mode, done, verification
``gaze``           where the cameras look while the robot drives (eq. 3-5), the look-around survey
``pose``           drift correction: an EKF over the pose and the landmarks it maps
``codec``          the report's text form of a grid of cells (base64 of packed bits)
=================  ==========================================================================

docs/exploration.md is the overview.
"""

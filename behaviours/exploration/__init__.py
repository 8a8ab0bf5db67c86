"""The exploration behaviours (algorithm 3): explore with a stereo pair on a pan-tilt unit until no
border of the explored floor is reachable. Thin over :mod:`maps.exploration` (the map, eq. 1-5, the
drift correction) and :mod:`perception.stereo`.

===============  ====================================================================
module           node types
===============  ====================================================================
``localise``     ``LocalisePose`` (drift correction by landmark bearings, in ``sense:``)
``map_stereo``   ``MapStereo`` (dense stereo into the exploration map)
``select_goal``  ``SelectGoalPoint`` (the next goal: eq. 1, frontier mode, done)
``follow_path``  ``FollowPath`` (the goal's path, with the collision checks)
``gaze``         ``WatchInterestEdges`` (where the cameras look while driving: eq. 2-5)
``look_around``  ``LookAround`` (all around while the robot stands)
===============  ====================================================================

``ports`` holds the ports these nodes share (the map, the goal, the pose, the robot's disc, the
head on the base), ``head`` the head's ports and what the unit reports, ``drawing`` the map's
drawings for the recording. docs/exploration.md is the overview.
"""

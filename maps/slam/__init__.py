"""Visual localisation from the stereo pair on the pan-tilt unit: a small stereo SLAM, the pure part.

The robot's planar pose (x, y, theta in the odometry frame) is estimated from what its own cameras
see: features of the left image matched along the epipolar line of the right one
(:func:`perception.stereo.sparse_stereo`), triangulated into landmarks with their uncertainty
(:mod:`perception.stereo_geometry`), recognised again by their descriptors where the predicted pose
says they should be, and fused with odometry in a filter; keyframes keep what was seen, and seeing
an old place again closes the loop in a pose graph. The head's angles come with each frame (the
cameras move on the pan-tilt unit; the head geometry is :class:`maps.exploration.head.StereoHead`).

One concern per module; callers import from them (nothing is re-exported here):

=================  ==========================================================================
module             what it holds
=================  ==========================================================================
``viewpoint``      where the left camera is for a base pose and head angles: points between
                   the world and the camera, with their Jacobians
``landmarks``      the landmark map: positions with covariances, descriptors, the keyframe
                   each is anchored to, how often it was predicted in view and found
``association``    which feature is which landmark: the gate on the predicted observation,
                   then the descriptor
``tracking``       the pose update: an iterated, robust EKF step on the stereo observations
``keyframes``      a keyframe: the pose, the head, its features in the base frame
``loop``           recognising an old keyframe and the planar motion between the two (RANSAC)
``graph``          the pose graph over keyframes (scipy's least squares)
``odometry``       odometry's turns calibrated against the cameras (for when they see nothing)
``slam``           :class:`~maps.slam.slam.StereoSlam`: the above, frame after frame
=================  ==========================================================================

docs/exploration.md ("Localisation") is the overview.
"""

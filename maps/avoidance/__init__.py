"""Getting around what blocks the way, from range points: the pure part of ``AvoidObstacles``.

==============  =========================================================================
module          what it holds
==============  =========================================================================
``sweep``       how far the footprint goes along an arc or in a direction before it
                touches a point; how far a motion node means to go (is its arc free?)
``directions``  the free direction closest to the wish (a polar histogram, VFH+) and the
                command that takes it (an arc, or a turn on the spot first)
``backoff``     backing away along the robot's own trail when no direction will do
``wayround``    a way round planned on the echoes of tens of seconds, where no direction
                will do (a grid, its distance transform, Dijkstra)
``state``       the values a tick reads and writes: settings, decision, tallies, the
                episode (a wait and the detour it may turn into)
``detour``      one tick's decision: pass the wish on, wait for the way to clear, detour,
                drive a way round, back away, or give up; the tallies the report gets
                (detours, length, time, waits, ways, back-offs)
==============  =========================================================================

Everything is in the base frame (REP-103: x forward, y left) unless a name says odometry. The
obstacle points of the last second, kept in the odometry frame, are :mod:`perception.obstacle_memory`
(the collision monitor remembers them too).
docs/obstacles.md is the overview.
"""

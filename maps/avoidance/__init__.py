"""Getting around what blocks the way, from range points: the pure part of ``AvoidObstacles``.

=========  ==============================================================================
module     what it holds
=========  ==============================================================================
``arcs``   how far the footprint can go along an arc before it touches a point; whether a
           motion node's arc is free for as far as it needs; the free arc closest to its
           wish (a dynamic window cut down to one speed and a fan of curvatures)
``memory`` obstacle points of the last second, kept in the odometry frame
``detour`` one tick's decision: pass the wish on, wait for the way to clear, detour, or
           give up; the tallies the report gets (detours, length, time, waits, give-ups)
=========  ==============================================================================

Everything is in the base frame (REP-103: x forward, y left) unless a name says odometry.
docs/obstacles.md is the overview.
"""

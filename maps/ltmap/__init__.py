"""The Landmark-Tree map (LT-map) of a taught route: Jäger, Mair et al., IROS 2013 (docs/design.md, method 1).

One concern per module; callers import from them (nothing is re-exported here):

- :mod:`maps.ltmap.tree`: :class:`~maps.ltmap.tree.LandmarkTree`, the map (landmarks in a tree
  whose branches are the viewframes), how a viewframe joins it (algorithm 1), its summary.
- :mod:`maps.ltmap.learner`: :class:`~maps.ltmap.learner.RouteLearner`, teaching a route from
  observations (tracking, eq. 1, where viewframes are, online pruning).
- :mod:`maps.ltmap.gaps`: landmarks found again shifted to a common node (gap filling), loops.
- :mod:`maps.ltmap.matching`: a viewframe's landmarks stacked for matching, and their cache.
- :mod:`maps.ltmap.prune`: cutting the lowest level to fit a memory budget.
- :mod:`maps.ltmap.arrays`: the arrays a map is made of (kinds, dtypes, bytes) and their checks.
- :mod:`maps.ltmap.file`: saving and loading map files (kind ``ltmap``).

Each module's docstring records how the paper is read where it is vague.
"""

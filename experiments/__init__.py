"""Experiments on the mission stack: sweeps, evaluations and benchmarks (``bearings sweep | eval | bench``).

The top layer (``experiments -> missions -> behaviours -> ...``): it runs missions through the
``missions`` runner and command line and measures them, and nothing below imports it.

- :mod:`experiments.sweep`: many simulated runs, on this machine or a Dask cluster, one row each;
- :mod:`experiments.eval`: an area's figures (LT-map, roadmap, exploration) from episodes run
  through the sweep, against the simulator's ground truth;
- :mod:`experiments.bench`: speed, accuracy and memory figures, comparable run to run;
- :mod:`experiments.commands`: their ``bearings`` sub-commands, which the command line finds as
  entry points of the group ``bearings.commands`` (``pyproject.toml``).
"""

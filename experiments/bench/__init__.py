"""Benchmarks behind ``bearings bench AREA --json``: one module per area with ``run(quick) -> dict``.

Each figure is named and, where a reference exists, reported as a ratio against a reference
measured in the same run (never a wall-clock assert).
"""

AREAS = {
    "tree": "experiments.bench.tree",
    "sim": "experiments.bench.sim",
    "perception": "experiments.bench.perception",
    "ltmap": "experiments.bench.ltmap",
    "localisation": "experiments.bench.localisation",
    "sweep": "experiments.bench.sweep",
    "run": "experiments.bench.run",
}

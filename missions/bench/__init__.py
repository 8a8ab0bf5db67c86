"""Benchmarks behind ``bearings bench AREA --json``: one module per area with ``run(quick) -> dict``.

Each figure is named and, where a reference exists, reported as a ratio against a reference
measured in the same run (never a wall-clock assert).
"""

AREAS = {
    "tree": "missions.bench.tree",
    "sim": "missions.bench.sim",
    "perception": "missions.bench.perception",
    "ltmap": "missions.bench.ltmap",
    "sweep": "missions.bench.sweep",
}

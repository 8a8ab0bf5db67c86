"""Fixtures for the simulator tests: small worlds written as YAML, like a user would."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from drivers.sim.simulation import Simulation


@pytest.fixture
def sim_from(world_file: Callable[[str], Path]) -> Callable[..., Simulation]:
    """Load a simulation from YAML text."""

    def load(text: str, seed: int = 0, **options: object) -> Simulation:
        return Simulation.load(world_file(text), seed=seed, **options)

    return load


def drive_for(sim: Simulation, v: float, w: float, seconds: float, dt: float = 0.1) -> None:
    """Command (v, w) every step for ``seconds``, as the runner commands the base every tick (a base
    that hears nothing for 2 s stops, as the Pioneer's firmware does)."""
    for _ in range(round(seconds / dt)):
        sim.robot.base.drive(v, w)
        sim.step(dt)

"""What a node reports: named figures for the run report, drawings for the recording.

Behaviours compute; they neither format the report nor call rerun. A node with something to say
implements one or both hooks, and the runner turns what they return into the report and the
recording in one place (:mod:`missions.runner`, :mod:`missions.recording`):

- ``figures() -> Iterable[Figure]``: named values. Each lands in its section of the run report
  (``ltmap``, ``roadmap``, ``exploration``, ...; a dotted name nests: ``search.scans``), and each
  number is also a time series of the recording (``figures/<section>/<name>``), so a count that
  ends in the report can be watched growing during the run.
- ``drawings() -> Iterable[Drawing]``: geometry and events for the recording only (points, line
  strips, arrows, a picture, a text event, a plotted value). Called every recorded tick: return
  a drawing when it changed, nothing otherwise.

Entity paths say the frame: ``odometry_frame/...`` for the odometry frame (never mixed with the
world frame of ground truth), ``<area>/robot_frame/...`` for the robot's own frame.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

Colour = tuple[int, int, int]


@dataclass(frozen=True, slots=True)
class Figure:
    """One named value of the run report (JSON-able); numbers are plotted in the recording too.

    ``headline``: the end-of-run line shows this figure (``bearings run`` prints it under the
    status, and the report lists it under ``headline``): the few figures that say whether the
    capability did its job, such as the area explored or the viewframes reached.
    """

    section: str
    name: str
    value: Any
    unit: str = ""
    headline: bool = False


def section(name: str, values: Mapping[str, Any], *, headline: Iterable[str] = ()) -> list[Figure]:
    """The figures of one report section, from a mapping of names to values; the names in
    ``headline`` are shown on the end-of-run line."""
    shown = set(headline)
    return [Figure(name, key, value, headline=key in shown) for key, value in values.items()]


@dataclass(frozen=True, slots=True)
class Points:
    """Points in 2-D (N x 2) or 3-D (N x 3); one colour for all or one per point."""

    entity: str
    positions: np.ndarray
    colours: Colour | list[Colour]
    radius: float = 0.05
    labels: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True)
class Lines:
    """Line strips in 2-D or 3-D, each K x 2 or K x 3; one colour for all or one per strip."""

    entity: str
    strips: list[np.ndarray] | np.ndarray
    colours: Colour | list[Colour]
    radius: float | None = None


@dataclass(frozen=True, slots=True)
class Arrows:
    """2-D arrows: ``vectors`` (N x 2) from ``origins`` (N x 2, default the frame's origin), each with
    its label (none, or one per arrow)."""

    entity: str
    vectors: np.ndarray
    colours: Colour | list[Colour]
    origins: np.ndarray | None = None
    labels: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True)
class Picture:
    """An image (H x W x 3 or 4, uint8), row 0 at the top."""

    entity: str
    image: np.ndarray


@dataclass(frozen=True, slots=True)
class Event:
    """A line of text on the recording's event log."""

    entity: str
    text: str


@dataclass(frozen=True, slots=True)
class Plot:
    """One value of a time series that the report does not keep (a per-tick estimate)."""

    entity: str
    value: float


Drawing = Points | Lines | Arrows | Picture | Event | Plot


@runtime_checkable
class Reports(Protocol):
    """A node that adds figures to the run report."""

    def figures(self) -> Iterable[Figure]: ...


@runtime_checkable
class Draws(Protocol):
    """A node that draws into the recording."""

    def drawings(self) -> Iterable[Drawing]: ...


@dataclass
class Sections:
    """Figures gathered into report sections (dotted names nested), in the order they came;
    ``headline`` lists the report paths (``section.name``) of the headline figures."""

    sections: dict[str, dict[str, Any]] = field(default_factory=dict)
    headline: list[str] = field(default_factory=list)

    def add(self, figures: Iterable[Figure]) -> None:
        for figure in figures:
            if figure.headline and (path := f"{figure.section}.{figure.name}") not in self.headline:
                self.headline.append(path)
            target = self.sections.setdefault(figure.section, {})
            *parents, leaf = figure.name.split(".")
            for parent in parents:
                target = target.setdefault(parent, {})
            target[leaf] = figure.value


def report_sections(*nodes: object) -> dict[str, dict[str, Any]]:
    """The report sections the figures of ``nodes`` make (what the run report gets from them)."""
    gathered = Sections()
    for node in nodes:
        if isinstance(node, Reports):
            gathered.add(node.figures())
    return gathered.sections

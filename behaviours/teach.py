"""Teaching a route: ``LearnRoute`` records the LT-map while its child drives the robot.

``LearnRoute`` is a decorator: its child is whatever drives the route (``DriveWaypoints`` on
odometry in the simulator, ``KeyboardTeleop`` with an operator on a robot). Every tick it feeds
each new observation, with the camera's heading from odometry, to a
:class:`maps.ltmap.learner.RouteLearner` (algorithm 1: a viewframe whenever ``delta_t`` passes the
threshold; with a budget, pruned online so the route's length need not be known). When the
child succeeds, the route is finished (the goal becomes the last viewframe), saved atomically
to ``path`` and the decorator succeeds. When the child fails, or the run is stopped, nothing is
saved: a file on disk is always a route that was driven to its end.

The map is on ``/map/ltmap`` from the first viewframe on. The report's ``ltmap`` section holds
the map's figures and, per viewframe, the tree time it was made (``taught``); an evaluation
turns those times into places with the simulator's ground-truth trajectory. With gap filling
(``gap_filling``, :mod:`maps.ltmap.gaps`) it also counts the landmarks found again and shifted
to a common node (``shifted``) and lists the loops the route closed (``loops``: the viewframe
pair, as taught, and the landmarks shared; ``loop_closures``: how many stretches of route came
back past earlier places, consecutive viewframes with a loop counting once).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from typing import Any

import numpy as np
import py_trees
from py_trees.common import Status

from behaviours.base import BearingsDecorator
from behaviours.landmark_tree import LTMAP_OUT, save_map, summary_section
from behaviours.motion import ODOMETRY
from behaviours.ports import WRITES, InputPort, Ref
from behaviours.registry import register
from behaviours.telemetry import Drawing, Figure, Points, section
from maps.ltmap.learner import LearnConfig, LearnStep, RouteLearner
from maps.ltmap.prune import DEFAULT_MIN_LANDMARKS, earliest_sources
from maps.ltmap.tree import DEFAULT_THRESHOLD
from maps.store import InputError
from perception.observation import Observation


@register
class LearnRoute(BearingsDecorator):
    """Record an LT-map while the child drives; save it atomically when the child succeeds.

    RUNNING while the child runs; SUCCESS once the finished map is saved; FAILURE when the
    child fails (nothing saved), when nothing was observed, or when the file cannot be written.
    """

    PATH = InputPort("path", str, "", literal_only=True, file=WRITES,
                     doc="the LT-map file written at the end; empty: not saved")
    THRESHOLD = InputPort("threshold", float, DEFAULT_THRESHOLD, minimum=1e-12, literal_only=True,
                          doc="eq. 1: a new viewframe when delta_t passes it (1.085e-6: a 3 deg bearing change)")
    BUDGET = InputPort("budget", int, 0, unit="B", minimum=0, literal_only=True,
                       doc="memory budget, pruned online while teaching; 0: none")
    MIN_LANDMARKS = InputPort("min_landmarks", int, DEFAULT_MIN_LANDMARKS, minimum=0, literal_only=True,
                              doc="pruning deletes viewframes left with fewer landmarks (the paper: 50)")
    GAP_FILLING = InputPort("gap_filling", bool, True, literal_only=True,
                            doc="landmarks found again are shifted to a common node; loops are reported")
    OBSERVATION = InputPort("observation", Observation, Ref("/perception/observation"), doc="the landmarks seen now")
    PORTS = (PATH, THRESHOLD, BUDGET, MIN_LANDMARKS, GAP_FILLING, OBSERVATION, ODOMETRY, LTMAP_OUT)

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, **ports: Any) -> None:
        super().__init__(name=name, child=child, **ports)
        self.config = LearnConfig(threshold=self.get_input(self.THRESHOLD),
                                  budget_bytes=self.get_input(self.BUDGET) or None,
                                  min_landmarks=self.get_input(self.MIN_LANDMARKS),
                                  gap_filling=self.get_input(self.GAP_FILLING))
        self.learner = RouteLearner(self.config)
        self.taught: list[float] = []  # per viewframe, the tree time it was made
        self.prunes = 0
        self.shifted = 0  # landmarks found again and merged into a common node (gap filling)
        self.loops: list[dict[str, int | list[int]]] = []  # viewframe pairs where the route came back
        self.closures = 0  # runs of consecutive viewframes that closed loops: one way back past earlier places
        self._looping = False
        self.saved = False
        self._stamp: float | None = None
        self._logged = -1

    def initialise(self) -> None:
        self.learner = RouteLearner(self.config)
        self.taught, self.prunes, self.saved, self._stamp = [], 0, False, None
        self.shifted, self.loops, self.closures, self._looping = 0, [], 0, False

    def update(self) -> Status:
        self._learn()
        child = self.decorated.status
        if child == Status.FAILURE:
            self.feedback_message = "the drive failed: the route is not saved"
            return Status.FAILURE
        if child != Status.SUCCESS:
            views = self.learner.tree.viewframe_count if self.learner.tree else 0
            self.feedback_message = f"{views} viewframes"
            return Status.RUNNING
        return self._finish()

    def _learn(self) -> None:
        observation = self.get_input(self.OBSERVATION, None)
        pose = self.get_input(ODOMETRY, None)
        if observation is None or pose is None or observation.stamp == self._stamp:
            return
        self._stamp = observation.stamp
        # bearings compensated by the heading; the viewframe keeps where odometry put it
        self._record(self.learner.observe(observation, pose.theta, (pose.x, pose.y)))

    def _record(self, step: LearnStep) -> None:
        self.shifted += step.shifted
        if step.loop is not None:
            self.loops.append({"viewframes": [step.loop.earlier, step.loop.later], "shared": step.loop.shared})
            self.closures += not self._looping
        if step.created:
            self._looping = step.loop is not None
        if step.pruned is not None and step.pruned.fits:
            self.prunes += 1
            kept = earliest_sources(step.pruned.viewframe_index[:-1])  # the last is the new one
            self.taught = [self.taught[old] for old in kept]
            self._logged = -1  # the places drawn changed, whatever their count
        if step.created:
            self.taught.append(round(self.now(), 3))
        tree = self.learner.tree
        if tree is not None and (step.created or step.pruned is not None):
            self.set_output(LTMAP_OUT, tree)
            self.taught = self.taught[:tree.viewframe_count]

    def _finish(self) -> Status:
        if self.learner.tree is None:
            self.feedback_message = "nothing was observed: there is no route to save"
            return Status.FAILURE
        self._record(self.learner.finish())
        tree = self.learner.tree
        path = self.get_input(self.PATH)
        if path:
            try:
                save_map(path, tree)
            except (InputError, OSError) as exc:
                self.feedback_message = f"cannot save the map: {str(exc).splitlines()[0]}"
                return Status.FAILURE
            self.saved = True
        self.set_output(LTMAP_OUT, tree)
        self.feedback_message = f"{tree.viewframe_count} viewframes, {tree.memory_bytes()} bytes" + (
            f", saved to {path}" if path else "")
        return Status.SUCCESS

    def figures(self) -> Iterator[Figure]:
        tree = self.learner.tree
        if tree is None:
            return
        taught = [{"viewframe": i, "time_s": t} for i, t in enumerate(self.taught)]
        path = self.get_input(self.PATH)
        written = os.path.abspath(path) if path else ""  # said at the end of the run: where the map went
        yield from section("ltmap", {**summary_section(tree.summary()), "map_file": written, "saved": self.saved,
                                     "online_prunes": self.prunes, "taught": taught,
                                     "gap_filling": self.config.gap_filling, "shifted": self.shifted,
                                     "loops": list(self.loops), "loop_closures": self.closures},
                           headline=("viewframes", "map_file"))

    def drawings(self) -> Iterator[Drawing]:
        """The viewframes made so far, where odometry put them (when there are new ones)."""
        tree = self.learner.tree
        if tree is None or not tree.has_places or tree.viewframe_count == self._logged:
            return
        self._logged = tree.viewframe_count
        places = np.array([tree.place(i) for i in range(tree.viewframe_count)])
        yield Points("odometry_frame/route/viewframes", places, colours=(255, 200, 0), radius=0.05)

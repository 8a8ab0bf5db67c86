"""LookAround alone: the survey, a unit that reports narrower limits than the defaults, a unit that re-homes."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.exploration.look_around import LookAround
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from drivers.interfaces import PanTiltCommand, PanTiltLimits, PanTiltState
from drivers.ptu_d46 import open_ptu
from maps.exploration.gaze import GazeParams, survey
from tests.drivers.ptu_emulator import PtuEmulator

PTU = "/ptu/command"
STEP = math.radians(185.1428 / 3600)  # a PTU-D46's position: 185.1428 arc-seconds
D46 = PanTiltLimits((-3090 * STEP, 3090 * STEP), (-907 * STEP, 604 * STEP), STEP, STEP, 2902 * STEP, 57 * STEP)


@dataclass
class Unit:
    """A pan-tilt unit as the driver of a PTU-D46 shows it: targets outside its limits raise (as
    ``PtuD46.move`` does), it slews at the commanded speed, it can reset (home) mid-run."""

    limits: PanTiltLimits = D46
    pan: float = 0.0
    tilt: float = 0.0
    target: tuple[float, float] = (0.0, 0.0)
    speed: float = 1.0
    homings: int = 0
    moves: int = 0
    report_homings: bool = True

    def move(self, pan: float, tilt: float, speed: float) -> None:
        low, high = self.limits.pan
        if not low - 1e-9 <= pan <= high + 1e-9:
            raise ValueError(f"pan {math.degrees(pan):.2f} deg is outside the limits")
        self.target, self.speed, self.moves = (pan, tilt), speed, self.moves + 1

    def home(self) -> None:
        """A reset: at home, the target forgotten (the driver does not send it again)."""
        self.pan = self.tilt = 0.0
        self.target = (0.0, 0.0)
        self.homings += 1

    def step(self, dt: float) -> None:
        reach = self.speed * dt
        self.pan += float(np.clip(self.target[0] - self.pan, -reach, reach))
        self.tilt += float(np.clip(self.target[1] - self.tilt, -reach, reach))

    def state(self) -> PanTiltState:
        moving = (self.pan, self.tilt) != self.target
        return PanTiltState(self.pan, self.tilt, moving, 0.0, self.limits, self.homings if self.report_homings else 0)


def run(look: LookAround, unit: Unit, *, seconds: float, dt: float = 0.1, events: dict[int, str] | None = None):
    """Tick ``look`` as the runner does (a command is sent only when it changed), the unit slewing in
    between; ``events``: tick -> "home". Returns the status, the harness and the commands sent."""
    harness = BehaviourHarness(look, blackboard={"/ptu/state": unit.state()})
    sent: list[PanTiltCommand] = []
    status = Status.RUNNING
    for tick in range(int(seconds / dt)):
        if (events or {}).get(tick) == "home":
            unit.home()
            harness.write("/ptu/state", unit.state())
        status = harness.tick()
        command = harness.read(PTU)
        if command is not None and (not sent or command != sent[-1]):
            unit.move(command.pan, command.tilt, command.speed)
            sent.append(command)
        if status != Status.RUNNING:
            break
        unit.step(dt)
        harness.clock.advance(dt)
        harness.write("/ptu/state", unit.state())
    return status, harness, sent


def test_look_around_steps_through_the_survey_then_succeeds():
    look = LookAround(settle=0.4)
    harness = BehaviourHarness(look)
    expected = survey(GazeParams())
    seen = []
    for _ in range(500):
        status = harness.tick()
        cmd = harness.read(PTU)
        if not seen or seen[-1] != (cmd.pan, cmd.tilt):
            seen.append((cmd.pan, cmd.tilt))
        harness.write("/ptu/state", PanTiltState(cmd.pan, cmd.tilt, False))  # a unit that is there at once
        harness.clock.advance(0.2)
        if status == Status.SUCCESS:
            break
    assert status == Status.SUCCESS
    assert np.allclose(np.array(seen), expected)
    assert harness.behaviour.surveys == 1


def test_look_around_holds_a_pose_until_the_unit_is_there():
    harness = BehaviourHarness(LookAround(settle=0.0), blackboard={"/ptu/state": PanTiltState(0.0, 0.0, True)})
    first = harness.read(PTU)
    for _ in range(5):
        assert harness.tick() == Status.RUNNING
        harness.clock.advance(0.2)
    assert first is None and harness.behaviour.index == 0


def test_with_its_defaults_on_a_unit_reporting_158_91_degrees():
    """The mission's defaults ask for +-159 deg; a PTU-D46 reports +-3090 positions of 185.1428
    arc-seconds and refuses anything beyond: the survey keeps inside, on the unit's positions."""
    unit = Unit()
    status, _, sent = run(LookAround(), unit, seconds=120.0)
    assert status == Status.SUCCESS
    pans = np.array([c.pan for c in sent])
    assert math.degrees(pans.min()) == pytest.approx(-158.91, abs=0.01)
    assert math.degrees(pans.max()) == pytest.approx(158.91, abs=0.01)
    positions = np.array([[c.pan, c.tilt] for c in sent]) / STEP
    assert np.allclose(positions, np.round(positions))  # whole positions: read back exactly
    assert all(c.speed == pytest.approx(D46.max_speed) for c in sent)  # 149 deg/s, not the 300 asked for


def test_a_unit_that_re_homes_mid_survey_is_noticed_and_the_view_sent_again():
    unit = Unit()
    look = LookAround(settle=0.4)
    status, harness, sent = run(look, unit, seconds=120.0, events={40: "home"})
    assert status == Status.SUCCESS and unit.homings == 1
    assert report_sections(look)["exploration"] == {"look_arounds_LookAround": 1, "look_around_rehomes_LookAround": 1,
                                                    "look_around_resends_LookAround": 1}
    views = survey(look.params, 0.15)
    assert len({(c.pan, c.tilt) for c in sent}) >= len(views)  # every view, and the unit's home on the way


def test_a_silent_re_home_is_recovered_after_the_timeout():
    """A driver that neither counts the homing nor sends the last move again: the view is not reached
    within its slew time plus ``timeout``, so it is sent again."""
    unit = Unit(report_homings=False)
    look = LookAround(settle=0.0, timeout=2.0)
    status, harness, _ = run(look, unit, seconds=120.0, events={30: "home"})
    assert status == Status.SUCCESS
    assert look.rehomes == 0 and look.resent == 1
    assert harness.clock.now() < 30 * 0.1 + 2.0 + 30.0  # recovered within the timeout, then finished


def test_a_unit_that_never_gets_there_fails_with_the_reason():
    unit = Unit()
    unit.step = lambda dt: None  # type: ignore[method-assign]  # stuck where it is
    look = LookAround(timeout=1.0, retries=2)
    status, harness, _ = run(look, unit, seconds=60.0)
    assert status == Status.FAILURE
    assert look.feedback_message.startswith("the pan-tilt unit did not reach view 1 of")
    assert "after 2 re-sends; it reports (0.00, 0.00) deg" in look.feedback_message
    assert harness.clock.now() < 3 * (158.91 / 149.0 + 1.0) + 1.0  # three budgets of slew time plus timeout


def test_each_look_around_node_counts_its_surveys_under_its_name():
    look = LookAround(name="look around again", settle=0.0)
    harness = BehaviourHarness(look)
    for _ in range(200):
        cmd = harness.read(PTU)
        if cmd is not None:
            harness.write("/ptu/state", PanTiltState(cmd.pan, cmd.tilt, False))
        if harness.tick() == Status.SUCCESS:
            break
    assert report_sections(look) == {"exploration": {"look_arounds_look_around_again": 1}}


def test_on_the_ptu_emulator_with_its_defaults_and_a_reset_mid_survey():
    """The driver of a PTU-D46 over its protocol (the emulator reports +-3090 positions of 185.1428
    arc-seconds): LookAround with its defaults finishes, the unit's reset half way included."""
    emulator = PtuEmulator(time_scale=20.0).start()
    pan_tilt = open_ptu({"port": emulator.port, "reply_timeout": 0.2, "poll_period": 0.02, "init_settle": 0.04})
    try:
        look = LookAround()
        harness = BehaviourHarness(look, blackboard={"/ptu/state": pan_tilt.state()})
        assert pan_tilt.state().limits is not None
        assert math.degrees(pan_tilt.state().limits.pan[1]) == pytest.approx(158.91, abs=0.01)
        last, status = None, Status.RUNNING
        for tick in range(3000):
            if tick == 60:
                emulator.home(duration=0.3)
            status = harness.tick()
            command = harness.read(PTU)
            if command is not None and command != last:
                pan_tilt.move(command.pan, command.tilt, command.speed)  # raises outside the unit's limits
                last = command
            if status != Status.RUNNING:
                break
            time.sleep(0.005)
            harness.clock.advance(0.1)
            harness.write("/ptu/state", pan_tilt.state())
        assert status == Status.SUCCESS
        assert emulator.homings == 1 and pan_tilt.homings == 1 and look.rehomes == 1
        assert pan_tilt.fault is None and pan_tilt.errors == 0
    finally:
        pan_tilt.close()
        emulator.close()
    assert emulator.crashed is None

"""The echoes kept for planning a way round (perception.echo_map): seen through, aged, kept."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.echo_map import EchoMap
from perception.geometry import Pose2D
from perception.ranges import RangeScan, RangeSensor

AHEAD = RangeSensor(0.0, 0.0, 0.0)  # on the centre, looking along +x, a 30 degree cone
LEFT = RangeSensor(0.0, 0.0, math.pi / 2.0)


def scan(ahead: float, left: float, stamp: float) -> RangeScan:
    return RangeScan((AHEAD, LEFT), np.array([ahead, left]), stamp)


def test_an_echo_is_kept_where_odometry_put_it():
    echoes = EchoMap(keep=20.0).added(scan(1.0, math.inf, 0.0), Pose2D(2.0, 0.0, math.pi / 2.0))
    assert echoes.points == pytest.approx(np.array([[2.0, 1.0]]))  # 1 m along +y in the odometry frame
    assert echoes.around(Pose2D(2.0, 0.5, math.pi / 2.0)) == pytest.approx(np.array([[0.5, 0.0]]))


def test_a_newer_echo_farther_along_the_middle_of_a_cone_sees_through_an_older_one():
    echoes = EchoMap(keep=20.0).added(scan(1.0, math.inf, 0.0), Pose2D())
    # 1.2 m now: the echo at 1.0 m is 0.2 m nearer, more than 0.15 m: someone walked away
    through = echoes.added(scan(1.2, math.inf, 0.1), Pose2D())
    assert through.points == pytest.approx(np.array([[1.2, 0.0]]))
    # 1.1 m now: only 0.1 m farther, within what a reading's scatter is: both kept
    kept = echoes.added(scan(1.1, math.inf, 0.1), Pose2D())
    assert kept.points == pytest.approx(np.array([[1.0, 0.0], [1.1, 0.0]]))


def test_only_the_middle_half_of_the_cone_clears():
    # the middle half of a 30 degree cone is 7.5 degrees each side of the axis: an echo 10 degrees off stays
    off = np.array([[math.cos(math.radians(10.0)), math.sin(math.radians(10.0))]])
    echoes = EchoMap(keep=20.0, points=off, stamps=np.zeros(1))
    after = echoes.added(scan(2.0, math.inf, 0.1), Pose2D())
    assert len(after.points) == 2  # the one 10 degrees off, and the new one at 2 m
    inside = np.array([[math.cos(math.radians(5.0)), math.sin(math.radians(5.0))]])
    after = EchoMap(keep=20.0, points=inside, stamps=np.zeros(1)).added(scan(2.0, math.inf, 0.1), Pose2D())
    assert after.points == pytest.approx(np.array([[2.0, 0.0]]))


def test_a_reading_with_no_echo_clears_nothing_and_old_echoes_age_out():
    echoes = EchoMap(keep=5.0).added(scan(1.0, math.inf, 0.0), Pose2D())
    assert len(echoes.added(scan(math.inf, math.inf, 4.9), Pose2D()).points) == 1  # a missed echo: kept
    assert len(echoes.added(scan(math.inf, math.inf, 5.0), Pose2D()).points) == 0  # 5 s old: gone


def test_a_transducer_repeating_its_reading_is_one_echo_the_newest():
    echoes = EchoMap(keep=20.0).added(scan(1.0, 0.5, 0.0), Pose2D()).added(scan(1.0, 0.5, 0.1), Pose2D())
    assert len(echoes.points) == 2 and echoes.stamps.tolist() == [0.1, 0.1]

"""GRBL-style planner: trapezoid profiles, per-axis limits, junction deviation, feed hold."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.sim.plotters.grbl.planner import AxisLimits, Block, Planner, Profile, limit_by_axis

LIMITS = AxisLimits((6000.0, 6000.0, 600.0), (1000.0, 1000.0, 100.0), 0.01)


def test_long_move_trapezoid_time():
    # 200 mm at 100 mm/s, 1000 mm/s²: t = d/v + v/a = 2.0 + 0.1
    p = Profile.trapezoid(0.0, 100.0, 0.0, 1000.0, 200.0)
    assert p.duration == pytest.approx(2.1)
    assert p.at(p.duration) == (pytest.approx(200.0), pytest.approx(0.0))
    assert p.at(0.1) == (pytest.approx(5.0), pytest.approx(100.0))  # end of ramp: v²/2a


def test_short_move_triangle_time():
    # 5 mm never reaches 100 mm/s: t = 2·sqrt(d/a)
    p = Profile.trapezoid(0.0, 100.0, 0.0, 1000.0, 5.0)
    assert p.duration == pytest.approx(2 * math.sqrt(5 / 1000))


@settings(max_examples=100, deadline=None)
@given(st.floats(0, 200), st.floats(1, 200), st.floats(0, 200), st.floats(10, 5000), st.floats(0.01, 500))
def test_profile_invariants(v0, vn, v1, a, length):
    p = Profile.trapezoid(v0, vn, v1, a, length)
    ts = np.linspace(0, p.duration, 50)
    samples = [p.at(t) for t in ts]
    s = np.array([x[0] for x in samples])
    v = np.array([x[1] for x in samples])
    assert s[-1] == pytest.approx(length, rel=1e-6, abs=1e-6)
    assert np.all(np.diff(s) >= -1e-9)  # never goes backwards
    assert np.all(v >= -1e-6) and np.all(v <= max(v0, vn) + 1e-6)
    dv = np.abs(np.diff(v))
    assert np.all(dv <= a * np.diff(ts) + 1e-6)  # acceleration bounded


def test_per_axis_limits_of_a_diagonal():
    unit = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
    assert limit_by_axis((1000.0, 1000.0, 100.0), unit) == pytest.approx(1000 * math.sqrt(2))
    b = Block(np.zeros(3), np.array([10.0, 10.0, 0.0]), rapid=True)
    pl = Planner(15, lambda: LIMITS)
    pl.add(b, 0.0)
    assert b.accel == pytest.approx(1414.2136, rel=1e-6)
    assert b.nominal == pytest.approx(6000 * math.sqrt(2) / 60)


def test_junction_speed_of_a_right_angle():
    # GRBL: v² = a·δ·sin(θ/2)/(1 − sin(θ/2)), θ/2 = 45° for a 90° turn, a from the junction vector
    pl = Planner(15, lambda: LIMITS)
    pl.add(Block(np.zeros(3), np.array([100.0, 0, 0]), feed=6000), 0.0)
    pl.add(Block(np.array([100.0, 0, 0]), np.array([100.0, 100.0, 0]), feed=6000), 0.0)
    a = 1000 * math.sqrt(2)
    s = math.sqrt(0.5)
    expected = math.sqrt(a * 0.01 * s / (1 - s))
    assert pl.blocks[1].entry == pytest.approx(expected)


def test_reversal_stops_and_straight_on_keeps_speed():
    pl = Planner(15, lambda: LIMITS)
    pl.add(Block(np.zeros(3), np.array([100.0, 0, 0]), feed=3000), 0.0)
    pl.add(Block(np.array([100.0, 0, 0]), np.array([0.0, 0, 0]), feed=3000), 0.0)
    assert pl.blocks[1].entry == 0.0
    pl = Planner(15, lambda: LIMITS)
    pl.add(Block(np.zeros(3), np.array([100.0, 0, 0]), feed=3000), 0.0)
    pl.add(Block(np.array([100.0, 0, 0]), np.array([200.0, 0, 0]), feed=3000), 0.0)
    assert pl.blocks[1].entry == pytest.approx(50.0)


def run_to_end(pl: Planner) -> float:
    t = 0.0
    while (te := pl.next_event()) is not None:
        t = te
        pl.step()
    return t


def test_two_collinear_blocks_take_the_time_of_one():
    pl = Planner(15, lambda: LIMITS)
    pl.add(Block(np.zeros(3), np.array([100.0, 0, 0]), feed=3000), 0.0)
    pl.add(Block(np.array([100.0, 0, 0]), np.array([200.0, 0, 0]), feed=3000), 0.0)
    pl.start(0.0)
    assert run_to_end(pl) == pytest.approx(200 / 50 + 50 / 1000)


def test_feed_hold_stops_after_v_squared_over_2a():
    pl = Planner(15, lambda: LIMITS)
    pl.add(Block(np.zeros(3), np.array([200.0, 0, 0]), feed=3000), 0.0)
    pl.start(0.0)
    pl.hold(2.0)  # cruising at 50 mm/s, at 1.25 + 50·1.95 = 98.75 mm
    assert pl.position(2.0)[0] == pytest.approx(98.75)
    te = pl.next_event()
    assert te == pytest.approx(2.05)
    assert pl.step() == ("held", None)
    assert pl.position(te)[0] == pytest.approx(100.0)
    assert pl.stopped()
    pl.start(3.0)  # resume from rest: 100 mm left
    assert run_to_end(pl) == pytest.approx(3.0 + 100 / 50 + 50 / 1000)


def test_capacity_and_zero_length_blocks():
    pl = Planner(2, lambda: LIMITS)
    assert not pl.add(Block(np.zeros(3), np.zeros(3), feed=100), 0.0)
    assert pl.add(Block(np.zeros(3), np.ones(3), feed=100), 0.0)
    assert pl.available == 1 and not pl.full
    pl.add(Block(np.ones(3), 2 * np.ones(3), feed=100), 0.0)
    assert pl.full

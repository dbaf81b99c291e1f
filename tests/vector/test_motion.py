"""Tests of the motion and time model: trapezoids worked by hand, junction deviation, a scalar reference planner."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.profiles.model import DeviceProfile
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.motion import MotionLimits, estimate_time, junction_speeds, plan

SAXI_DOWN = MotionLimits(speed=50.0, accel=200.0, cornering=0.127)


# --- rest-to-rest moves, worked by hand -------------------------------------------------------------------

def test_long_move_reaches_cruise_speed():
    # 100 mm at 50 mm/s, 200 mm/s²: accelerate 0.25 s over 6.25 mm, cruise 87.5 mm in 1.75 s, decelerate 0.25 s
    assert SAXI_DOWN.move_time(100.0) == pytest.approx(0.25 + 1.75 + 0.25)
    assert SAXI_DOWN.move_time(100.0) == pytest.approx(100 / 50 + 50 / 200)


def test_short_move_is_a_triangle():
    # 4 mm never reaches 50 mm/s: half the distance accelerating, 2 mm = a t²/2 -> t = sqrt(0.02); twice that
    assert SAXI_DOWN.move_time(4.0) == pytest.approx(2 * math.sqrt(2 * 2.0 / 200.0))
    assert SAXI_DOWN.move_time(4.0) == pytest.approx(2 * math.sqrt(4.0 / 200.0))


def test_trapezoid_and_triangle_agree_at_the_boundary():
    d = 50.0 ** 2 / 200.0  # 12.5 mm: peak speed is exactly the cruise speed
    assert SAXI_DOWN.move_time(d) == pytest.approx(0.5)
    assert SAXI_DOWN.move_time(d - 1e-9) == pytest.approx(0.5)


def test_move_times_vectorised_matches_scalar():
    d = np.array([0.0, 0.5, 4.0, 12.5, 100.0, 1000.0])
    assert np.allclose(SAXI_DOWN.move_times(d), [SAXI_DOWN.move_time(x) for x in d])
    assert SAXI_DOWN.move_time(0.0) == 0.0


@pytest.mark.parametrize("kwargs", [
    {"speed": 0, "accel": 1}, {"speed": -1, "accel": 1}, {"speed": 1, "accel": float("nan")},
    {"speed": 1, "accel": float("inf")}, {"speed": "fast", "accel": 1}, {"speed": 1, "accel": 1, "cornering": -0.1},
])
def test_limits_reject_bad_values(kwargs):
    with pytest.raises(ConfigError):
        MotionLimits(**kwargs)


# --- junction deviation ----------------------------------------------------------------------------------

def test_right_angle_junction_speed_from_the_formula():
    # theta = 90 deg: sin(45) = 0.7071068; r = 0.127 * 0.7071068 / 0.2928932 = 0.3066051 mm; v = sqrt(200 r)
    v = junction_speeds(np.array([[1.0, 0.0]]), np.array([[0.0, 1.0]]), SAXI_DOWN)
    assert v[0] == pytest.approx(7.83077, rel=1e-5)


def test_straight_on_is_not_slowed_and_reversal_stops():
    v = junction_speeds(np.array([[1.0, 0.0], [1.0, 0.0]]), np.array([[1.0, 0.0], [-1.0, 0.0]]), SAXI_DOWN)
    assert v[0] == pytest.approx(50.0)
    assert v[1] == 0.0


def test_zero_cornering_stops_at_every_corner():
    v = junction_speeds(np.array([[1.0, 0.0]]), np.array([[0.6, 0.8]]), MotionLimits(50, 200, 0.0))
    assert v[0] == 0.0


# --- planning polylines ----------------------------------------------------------------------------------

def test_single_long_block_fields():
    p = plan(np.array([[0.0, 0.0], [100.0, 0.0]]), SAXI_DOWN)
    assert len(p) == 1
    assert (p.entry[0], p.exit[0], p.cruise[0]) == (0.0, 0.0, 50.0)
    assert p.accel_time[0] == pytest.approx(0.25) and p.decel_time[0] == pytest.approx(0.25)
    assert p.cruise_time[0] == pytest.approx(1.75)
    assert p.total_time == pytest.approx(2.25)


def test_short_block_peaks_below_cruise():
    p = plan(np.array([[0.0, 0.0], [0.0, 4.0]]), SAXI_DOWN)
    assert p.cruise[0] == pytest.approx(math.sqrt(200.0 * 4.0))  # v² = a d at the midpoint
    assert p.cruise_time[0] == 0.0
    assert p.total_time == pytest.approx(2 * math.sqrt(4.0 / 200.0))


def test_collinear_points_plan_like_one_move():
    pts = np.column_stack([np.linspace(0, 100, 101), np.zeros(101)])
    assert plan(pts, SAXI_DOWN).total_time == pytest.approx(2.25)


def test_reversal_stops_in_between():
    p = plan(np.array([[0.0, 0.0], [50.0, 0.0], [0.0, 0.0]]), SAXI_DOWN)
    assert p.exit[0] == 0.0 and p.entry[1] == 0.0
    assert p.total_time == pytest.approx(2 * (50 / 50 + 50 / 200))


def test_right_angle_corner_by_hand():
    vj = math.sqrt(200.0 * 0.127 * math.sin(math.pi / 4) / (1 - math.sin(math.pi / 4)))
    # each 100 mm leg: 0 -> 50 mm/s over 6.25 mm (0.25 s), cruise, 50 -> vj over (2500 - vj²)/400 mm
    decel_d = (2500 - vj * vj) / 400
    leg = 0.25 + (50 - vj) / 200 + (100 - 6.25 - decel_d) / 50
    p = plan(np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 100.0]]), SAXI_DOWN)
    assert p.exit[0] == pytest.approx(vj) and p.entry[1] == pytest.approx(vj)
    assert p.total_time == pytest.approx(2 * leg)


def test_repeated_points_are_skipped():
    a = plan(np.array([[0.0, 0.0], [0.0, 0.0], [10.0, 0.0], [10.0, 0.0]]), SAXI_DOWN)
    b = plan(np.array([[0.0, 0.0], [10.0, 0.0]]), SAXI_DOWN)
    assert len(a) == 1 and a.total_time == pytest.approx(b.total_time)


def test_many_polylines_plan_as_separate_ones():
    rng = np.random.default_rng(3)
    polys = [rng.uniform(0, 30, (k, 2)) for k in (2, 5, 1, 7)]
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in polys])])
    joint = plan(np.concatenate(polys), SAXI_DOWN, offsets)
    assert joint.total_time == pytest.approx(sum(plan(p, SAXI_DOWN).total_time for p in polys))
    assert list(np.unique(joint.stroke)) == [0, 1, 3]  # the single point has no block


def test_empty_and_bad_input():
    assert plan(np.zeros((0, 2)), SAXI_DOWN).total_time == 0.0
    assert plan(np.array([[1.0, 2.0]]), SAXI_DOWN).total_time == 0.0
    with pytest.raises(ConfigError):
        plan(np.array([[0.0, 0.0], [np.nan, 1.0]]), SAXI_DOWN)
    with pytest.raises(ConfigError):
        plan(np.zeros((3, 2)), SAXI_DOWN, offsets=[0, 2])


def _reference_time(pts: np.ndarray, lim: MotionLimits) -> float:
    """Textbook planner, one vertex at a time: junction limits, backward then forward pass, block times."""
    pts = [tuple(p) for p in pts]
    pts = [p for i, p in enumerate(pts) if i == 0 or p != pts[i - 1]]
    if len(pts) < 2:
        return 0.0
    segs = [(b[0] - a[0], b[1] - a[1]) for a, b in itertools.pairwise(pts)]
    lengths = [math.hypot(*s) for s in segs]
    units = [(s[0] / d, s[1] / d) for s, d in zip(segs, lengths, strict=False)]
    v = [0.0] * (len(segs) + 1)  # vertex speed limits
    for i in range(1, len(segs)):
        cos_t = -(units[i - 1][0] * units[i][0] + units[i - 1][1] * units[i][1])
        if cos_t >= 0.999999:
            v[i] = 0.0
            continue
        sin_half = math.sqrt(max(0.0, 0.5 * (1 - cos_t)))
        radius = lim.cornering * sin_half / (1 - sin_half) if sin_half < 1 else math.inf
        v[i] = min(lim.speed, math.sqrt(lim.accel * radius))
    for i in range(len(segs) - 1, -1, -1):
        v[i] = min(v[i], math.sqrt(v[i + 1] ** 2 + 2 * lim.accel * lengths[i]))
    for i in range(len(segs)):
        v[i + 1] = min(v[i + 1], math.sqrt(v[i] ** 2 + 2 * lim.accel * lengths[i]))
    total = 0.0
    for i, d in enumerate(lengths):
        ve, vx = v[i], v[i + 1]
        peak = min(lim.speed, math.sqrt((2 * lim.accel * d + ve * ve + vx * vx) / 2))
        da, dd = (peak ** 2 - ve ** 2) / (2 * lim.accel), (peak ** 2 - vx ** 2) / (2 * lim.accel)
        total += (peak - ve) / lim.accel + (peak - vx) / lim.accel + max(0.0, d - da - dd) / peak
    return total


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.tuples(st.integers(-50, 50), st.integers(-50, 50)), min_size=1, max_size=25),
    st.sampled_from([SAXI_DOWN, MotionLimits(200, 400, 0.0), MotionLimits(381, 19600, 0.02)]),
)
def test_vectorised_planner_matches_scalar_reference(points, limits):
    pts = np.array(points, dtype=float)
    assert plan(pts, limits).total_time == pytest.approx(_reference_time(pts, limits), rel=1e-9, abs=1e-12)


# --- plot time -------------------------------------------------------------------------------------------

def _profile(**kw) -> DeviceProfile:
    base = dict(name="test", unit_mm=1.0, pen_down=MotionLimits(50, 200, 0.0), pen_up=MotionLimits(200, 400, 0.0),
                pen_lift_s=0.1, pen_drop_s=0.2, pen_change_s=5.0)
    base.update(kw)
    return DeviceProfile(**base)


def test_estimate_time_adds_up_by_hand():
    dl = DisplayList.from_polylines([[(10, 0), (110, 0)], [(110, 4), (110, 0)]], pens=[1, 2])
    t = estimate_time(dl, _profile(), home=(0, 0), return_home=True)
    down = (100 / 50 + 50 / 200) + 2 * math.sqrt(4 / 200)
    up = [10.0, 4.0, 110.0]  # home -> (10,0); (110,0) -> (110,4); (110,0) -> home
    up_t = 2 * math.sqrt(10 / 400) + 2 * math.sqrt(4 / 400) + (110 / 200 + 200 / 400)
    assert t.pen_down == pytest.approx(down)
    assert t.pen_up == pytest.approx(up_t)
    assert t.pen_up_mm == pytest.approx(sum(up)) and t.pen_down_mm == pytest.approx(104.0)
    assert (t.lifts, t.pen_changes) == (2, 1)
    assert t.pen_lifts == pytest.approx(2 * 0.3) and t.pen_swaps == pytest.approx(5.0)
    assert t.total == pytest.approx(down + up_t + 0.6 + 5.0)


def test_estimate_time_uses_the_unit_and_optional_return():
    dl = DisplayList.from_polylines([[(0, 0), (4000, 0)]], unit_mm=0.025)  # 100 mm
    t = estimate_time(dl, _profile(), home=(0, 0), return_home=False)
    assert t.pen_down == pytest.approx(2.25) and t.pen_up == 0.0
    assert estimate_time(dl, _profile(), return_home=True).pen_up_mm == pytest.approx(100.0)


def test_estimate_time_of_nothing_and_by_profile_name():
    t = estimate_time(DisplayList(), "axidraw_v3")
    assert (t.total, t.lifts, t.pen_changes, t.pen_up_mm) == (0.0, 0, 0, 0.0)

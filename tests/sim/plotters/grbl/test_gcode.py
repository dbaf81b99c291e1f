"""GRBL G-code parser: read_float, the documented error codes, targets, offsets and arcs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.sim.plotters.grbl.gcode import (
    GBlock,
    GcodeState,
    Persistent,
    arc_points,
    parse_block,
    read_float,
)


@pytest.mark.parametrize("text, value, end", [
    ("12.5", 12.5, 4), ("-.5X", -0.5, 3), ("+3", 3.0, 2), ("7.", 7.0, 2),
    ("123456789", 123456780.0, 9),  # GRBL keeps 8 significant digits (MAX_INT_DIGITS)
    ("0.000000001", 0.0, 11),
])
def test_read_float(text, value, end):
    assert read_float(text, 0) == (pytest.approx(value), end)


@pytest.mark.parametrize("text", ["", ".", "-", "+X", "X1"])
def test_read_float_without_digits(text):
    assert read_float(text, 0) is None


def parse(line, state=None, persistent=None, **kw):
    return parse_block(line, state or GcodeState(), persistent or Persistent(), **kw)


# Each case names the rule of doc/csv/error_codes_en_US.csv it breaks.
@pytest.mark.parametrize("line, code", [
    ("1X", 1),              # word without a letter
    ("GX", 2),              # letter without a number
    ("G1X10", 22),          # feed rate never set
    ("G2X10", 22),
    ("G5", 20),             # unsupported G
    ("M100", 20),           # unsupported M
    ("G1X1Q1F10", 20),      # unsupported letter
    ("G38.1X1F10", 20),     # G38.x only .2 .3 .4 .5
    ("G90.1", 20),
    ("G17G18", 21),         # two commands of the plane group
    ("M3M5", 21),
    ("F-1", 4),             # negative F
    ("S-5", 4),
    ("G1.5X1F1", 23),       # non-integer G
    ("G0G1X1", 24),         # two axis commands
    ("G28G1X1", 24),
    ("X1X2", 25),           # repeated word
    ("G10L2P1", 26),        # G10 needs axis words
    ("N10000000", 27),      # line number beyond 9,999,999
    ("G4", 28),             # dwell needs P
    ("G10L2X1", 28),        # G10 needs P and L
    ("G10L2P7X1", 29),      # only G54-G59
    ("G53G2X1I1F10", 30),   # G53 only with G0/G1
    ("G80X1", 31),          # axis words with motion cancelled
    ("G2Z10F100", 32),      # arc without in-plane axis word
    ("G2X10R1F100", 34),    # radius shorter than half the chord
    ("G2X10F100", 35),      # arc without offsets
    ("G1X1P1F10", 36),      # unused word
    ("G2X10R5I1F100", 36),  # I unused in radius format
    ("G43.1X1", 37),        # G43.1 only on Z
    ("T256", 38),           # tool number above 255
])
def test_documented_error_codes(line, code):
    assert parse(line) == code


def test_arc_target_equal_to_start_and_inconsistent_radius_are_invalid_targets():
    assert parse("G2X0Y0R5F100") == 33  # radius format, target = current position
    assert parse("G2X10I3F100") == 33  # start radius 3, end radius 7: off by more than 0.5 mm


def test_jog_errors():
    assert parse("$J=X1", jog=True) == 22  # jog needs its own F
    assert parse("$J=G1X1F10", jog=True) == 16  # motion mode words are not allowed
    assert parse("$J=M3X1F10", jog=True) == 16
    assert parse("$J=F10", jog=True) == 16  # nothing to move


def test_modal_state_units_and_distance():
    b = parse("G20G91G0X1Y-2")
    assert isinstance(b, GBlock)
    assert b.modal.inches and b.modal.incremental
    assert np.allclose(b.target, [25.4, -50.8, 0.0])
    st_ = GcodeState(position=np.array([5.0, 6.0, 7.0]))
    b = parse("G91G1X1F100", st_)
    assert np.allclose(b.target, [6.0, 6.0, 7.0]) and b.feed == 100
    assert np.allclose(b.modal.position, [6.0, 6.0, 7.0])


def test_feed_is_modal_and_converted_to_mm():
    b = parse("G20G1X1F10")
    assert b.feed == pytest.approx(254.0)
    assert b.modal.feed_rate == pytest.approx(254.0)
    b2 = parse("G1X2", b.modal)
    assert b2.feed == pytest.approx(254.0)


def test_work_offsets_g92_and_g10():
    # at machine (10, 20, 0), G92 X0 Y0 makes the current point work zero: offset = (10, 20, 0)
    state = GcodeState(position=np.array([10.0, 20.0, 0.0]))
    b = parse("G92X0Y0", state)
    assert np.allclose(b.modal.coord_offset, [10, 20, 0]) and b.wco_changed
    b2 = parse("G0X5", b.modal)
    assert np.allclose(b2.target, [15, 20, 0])  # work 5 = machine 15
    # G10 L20 P1 X1: G54 x so that the current position reads 1 -> 10 - 0 - 1 = 9
    b3 = parse("G10L20P1X1", state)
    assert b3.g10_index == 0 and np.allclose(b3.g10_values, [9, 0, 0])
    assert np.allclose(b3.modal.coord_system, [9, 0, 0])  # G54 is active
    b4 = parse("G10L2P2X3Y4", state)
    assert b4.g10_index == 1 and np.allclose(b4.g10_values, [3, 4, 0])
    assert np.allclose(b4.modal.coord_system, [0, 0, 0])  # G55 changed, G54 active


def test_g53_is_machine_coordinates_and_g28_goes_home():
    state = GcodeState(coord_system=np.array([100.0, 0.0, 0.0]))
    b = parse("G53G0X5", state)
    assert np.allclose(b.target, [5, 0, 0])
    pers = Persistent(g28=np.array([1.0, 2.0, 3.0]))
    b = parse("G28", GcodeState(position=np.array([9.0, 9.0, 9.0])), pers)
    assert np.allclose(b.home, [1, 2, 3]) and np.allclose(b.modal.position, [1, 2, 3])


def test_radius_arc_centre():
    # G3 from (0,0) to (10,10), R10: the centres are (10,0) and (0,10); the short CCW arc turns
    # about (0,10) (from -90 deg to 0 deg), so the offset from the start is (0, 10)
    b = parse("G3X10Y10R10F100")
    assert np.allclose(b.arc_offset[:2], [0, 10]) and b.arc_radius == pytest.approx(10)
    # negative R asks for the long way round: the other centre
    b = parse("G3X10Y10R-10F100")
    assert np.allclose(b.arc_offset[:2], [10, 0])


def test_arc_segment_count_follows_the_tolerance_formula():
    # semicircle of radius 10 with $12 = 0.002: floor(0.5*pi*10 / sqrt(0.002*(20-0.002))) = 78
    pts = arc_points(np.zeros(3), np.array([20.0, 0, 0]), np.array([10.0, 0, 0]), 10.0, 0, True, 0.002)
    assert len(pts) == 78
    assert np.allclose(pts[-1], [20, 0, 0])


@settings(max_examples=80, deadline=None)
@given(
    st.floats(1.0, 100.0), st.floats(-math.pi, math.pi), st.floats(-math.pi, math.pi),
    st.booleans(), st.floats(0.001, 0.1),
)
def test_arc_points_lie_on_the_circle(r, a0, a1, cw, tol):
    centre = np.array([3.0, -4.0, 0.0])
    start = centre + r * np.array([math.cos(a0), math.sin(a0), 0.0])
    target = centre + r * np.array([math.cos(a1), math.sin(a1), 0.0])
    pts = arc_points(start, target, centre - start, r, 0, cw, tol)
    assert np.allclose(pts[-1], target)
    radii = np.hypot(pts[:, 0] - centre[0], pts[:, 1] - centre[1])
    assert np.allclose(radii, r, atol=1e-9)
    chain = np.vstack([start, pts])[:, :2]
    # GRBL takes floor(arc / allowed chord) segments: one more segment would meet the tolerance
    sweep = (a1 - a0) % (2 * math.pi) if not cw else (a0 - a1) % (2 * math.pi)
    sweep = sweep if sweep > 5e-7 else 2 * math.pi
    n = len(pts)
    assert r * (1 - math.cos(sweep / (2 * (n + 1)))) <= tol * (1 + 1e-9)
    chords = np.hypot(*np.diff(chain, axis=0).T)
    assert np.allclose(chords, chords[0], rtol=1e-6, atol=1e-9)  # equal angular steps
    # direction: the signed area swept around the centre has the arc's sign
    rel = chain - centre[:2]
    cross = rel[:-1, 0] * rel[1:, 1] - rel[:-1, 1] * rel[1:, 0]
    assert np.all(cross <= 1e-9) if cw else np.all(cross >= -1e-9)


@pytest.mark.parametrize(("line", "code"), [
    ("N99999999G1X1", 27),  # [0] line number before [3] feed rate
    ("G1X1", 22),  # [3] feed rate before [20] motion
    ("G4G1X1", 28),  # [10] dwell's P before the motion checks
    ("G43.1X1", 37),  # [14] G43.1 takes Z only
    ("G10L2P7X1", 29),  # [19]
    ("G80X1", 31),  # [20]
    ("G0X1I1", 36),  # [0] unused words last
])
def test_step_3_checks_run_in_the_order_of_execution(line, code):
    assert parse_block(line, GcodeState(), Persistent()) == code

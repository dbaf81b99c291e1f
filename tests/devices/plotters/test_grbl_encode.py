"""GRBL encoding: G-code text of strokes, millimetre formatting, status reports, codes, character counting."""

from __future__ import annotations

from decimal import Decimal

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.devices.plotters.grbl_encode import (
    ALARM_CODES,
    ERROR_CODES,
    CharacterCounter,
    CoordinateFormat,
    PathTrack,
    PenMotion,
    parse_code,
    parse_status,
    parse_welcome,
    stroke_lines,
)
from pixelpen.errors import ConfigError, ParseError

SERVO = PenMotion("servo", 500.0, 50.0, 0.15, 0.15)


# -- coordinates -----------------------------------------------------------------------------------
def test_thousandths_of_a_millimetre_are_written_with_three_decimals():
    fmt = CoordinateFormat(0.001)
    assert fmt.format(np.array([0, 12000, 297000, -500, 1, -1, 7])).tolist() == [
        "0.000", "12.000", "297.000", "-0.500", "0.001", "-0.001", "0.007"]


@pytest.mark.parametrize("unit, units, text", [
    (0.0125, [3, 80, -1], ["0.0375", "1.0000", "-0.0125"]),   # AxiDraw steps
    (0.02488, [40, 1021], ["0.99520", "25.40248"]),           # HP 7475A unit, 5 decimals exactly
    (1.0, [12, -3], ["12", "-3"]),
    (10.0, [3], ["30"]),
])
def test_decimal_units_are_exact(unit, units, text):
    assert CoordinateFormat(unit).format(np.array(units)).tolist() == text


def test_no_drift_over_many_coordinates():
    """Every coordinate equals Decimal arithmetic on its own (absolute values never accumulate error)."""
    n = np.arange(-300_000, 300_001, 7)
    got = CoordinateFormat(0.001).format(n)
    want = [str((Decimal(int(v)) * Decimal("0.001")).quantize(Decimal("0.001"))) for v in n[::997]]
    assert got[::997].tolist() == want


def test_non_decimal_unit_is_rounded_per_coordinate():
    fmt = CoordinateFormat(1 / 3)
    assert fmt.decimals == 6 and not fmt.exact
    assert fmt.format(np.array([1, 3, 3000000])).tolist() == ["0.333333", "1.000000", "1000000.000000"]


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), float("inf"), "0.1"])
def test_bad_unit_is_refused(bad):
    with pytest.raises(ConfigError):
        CoordinateFormat(bad)


# -- strokes ---------------------------------------------------------------------------------------
def test_unit_square_gcode():
    """A 10 mm square: travel G0; servo down + dwell on the first G1 (with F); the lift is left to the next travel."""
    square = np.array([[0, 0], [10000, 0], [10000, 10000], [0, 10000], [0, 0]])
    assert stroke_lines(square, CoordinateFormat(0.001), SERVO, 3000.0) == [
        "G0 X0.000 Y0.000",
        "M3 S50 G4 P0.15 G1 X10.000 Y0.000 F3000",
        "G1 X10.000 Y10.000",
        "G1 X0.000 Y10.000",
        "G1 X0.000 Y0.000",
    ]
    assert stroke_lines(square[:2], CoordinateFormat(0.001), SERVO, 3000.0, lift_first=True) == [
        "M3 S500 G4 P0.15 G0 X0.000 Y0.000", "M3 S50 G4 P0.15 G1 X10.000 Y0.000 F3000"]


def test_pen_lift_variants():
    fmt = CoordinateFormat(0.001)
    dot = np.array([[1500, 2500]])
    assert stroke_lines(dot, fmt, PenMotion("servo", None, 90.0, 0.2, 0.1), 1200.5, lift_first=True) == [
        "M5 G4 P0.2 G0 X1.500 Y2.500", "M3 S90 G4 P0.1"]
    # a Z pen's moves are motions themselves: they keep lines of their own, the lift ends the stroke
    assert stroke_lines(np.array([[0, 0], [1000, 0]]), fmt, PenMotion("z", 2.0, -0.5, 0.0, 0.0), 600.0) == [
        "G0 X0.000 Y0.000", "G1 Z-0.5 F600", "G4 P0", "G1 X1.000 Y0.000 F600", "G0 Z2", "G4 P0"]


def test_profile_servo_commands_are_read():
    assert PenMotion.parse_servo_command("M3 S500", "up") == 500.0
    assert PenMotion.parse_servo_command(" m4s12.5 ", "down") == 12.5
    assert PenMotion.parse_servo_command("M5", "up") is None
    for bad in ("G0 Z5", "M3", "M3 S-1", "S500"):
        with pytest.raises(ConfigError):
            PenMotion.parse_servo_command(bad, "up")


@pytest.mark.parametrize("kwargs", [
    {"mode": "laser", "up": 1.0, "down": 0.0, "dwell_up": 0, "dwell_down": 0},
    {"mode": "z", "up": None, "down": 0.0, "dwell_up": 0, "dwell_down": 0},
    {"mode": "servo", "up": 500.0, "down": 50.0, "dwell_up": -1, "dwell_down": 0},
    {"mode": "servo", "up": 500.0, "down": 50.0, "dwell_up": 0, "dwell_down": float("nan")},
])
def test_bad_pen_motion_is_refused(kwargs):
    with pytest.raises(ConfigError):
        PenMotion(**kwargs)


def test_empty_stroke_is_refused():
    with pytest.raises(ConfigError):
        stroke_lines(np.zeros((0, 2)), CoordinateFormat(0.001), SERVO, 3000.0)


# -- character counting ----------------------------------------------------------------------------
def test_counting_boundary_is_exactly_the_buffer():
    counter = CharacterCounter(128)
    counter.sent("x" * 99)                 # 100 bytes in flight
    assert counter.fits("y" * 27)          # 100 + 28 = 128: fits
    assert not counter.fits("y" * 28)      # 129: does not
    counter.sent("y" * 27)
    assert counter.in_flight == 128 and len(counter) == 2
    assert counter.acknowledged() == ("x" * 99, None)
    assert counter.in_flight == 28


def test_acknowledgements_come_back_in_order_with_tags():
    counter = CharacterCounter(64)
    counter.sent("G0 X1", 7)
    counter.sent("G4 P0", "last")
    assert counter.oldest() == "G0 X1"
    assert counter.acknowledged() == ("G0 X1", 7)
    assert counter.acknowledged() == ("G4 P0", "last")
    with pytest.raises(ParseError):
        counter.acknowledged()


def test_line_larger_than_the_buffer_is_refused():
    with pytest.raises(ConfigError):
        CharacterCounter(16).sent("G1 X100.000 Y100.000")
    with pytest.raises(ConfigError):
        CharacterCounter(8)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(1, 79), st.booleans()), min_size=1, max_size=200))
def test_streaming_by_the_counting_rule_never_overflows(script):
    """Send whenever the rule allows, acknowledge at random: the bytes in flight never exceed the buffer."""
    counter = CharacterCounter(128)
    model: list[int] = []  # independent bookkeeping: bytes (line + newline) of each unacknowledged line
    for length, ack in script:
        while not counter.fits("x" * length):
            counter.acknowledged()
            model.pop(0)
        counter.sent("x" * length)
        model.append(length + 1)
        assert counter.in_flight == sum(model) <= 128
        if ack:
            counter.acknowledged()
            model.pop(0)


# -- status reports, welcome, codes ----------------------------------------------------------------
def test_status_report_from_interface_md():
    s = parse_status("<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>\r\n")
    assert (s.state, s.substate, s.mpos, s.wco, s.feed, s.spindle) == (
        "Idle", None, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 0.0)
    assert not s.busy and not s.held
    s = parse_status("<Hold:0|MPos:5.529,0.560,7.000|Bf:15,128|FS:0,0|Ov:100,100,100|A:S>")
    assert (s.state, s.substate, s.planner_free, s.rx_free, s.overrides, s.accessories) == (
        "Hold", 0, 15, 128, (100, 100, 100), "S")
    assert s.held and s.busy
    s = parse_status("<Run|WPos:1.000,-2.500,3.000|Bf:0,5|Ln:99|F:500.0|Pn:XZ>")
    assert (s.wpos, s.mpos, s.line_number, s.feed, s.spindle, s.pins) == ((1.0, -2.5, 3.0), None, 99, 500.0, None, "XZ")
    assert parse_status("<Door:2|MPos:0,0,0|FS:0,0>").held


@pytest.mark.parametrize("bad", [
    "Idle|MPos:0,0,0>", "<Idle|MPos:0,0,0", "<>", "<Waiting|MPos:0,0,0>", "<Hold:x|MPos:0,0,0>",
    "<Idle|MPos:1.0,abc,0>", "<Idle|MPos>", "<Idle|Bf:15>", "<Idle|FS:1,2,3>", "<Idle|Ov:100,100>",
    "<Idle|MPos:nan,0,0>", "<Idle|Ln:x>",
])
def test_malformed_status_reports_raise(bad):
    with pytest.raises(ParseError):
        parse_status(bad)


def test_welcome_line():
    assert parse_welcome("Grbl 1.1h ['$' for help]\r\n") == (1, 1, "h")
    assert parse_welcome("Grbl 0.9j ['$' for help]") == (0, 9, "j")
    assert parse_welcome("ok") is None
    assert parse_welcome("Grbl 1.1h") is None


def test_code_tables_follow_the_grbl_csv():
    assert ERROR_CODES[9].startswith("G-code lock")
    assert ERROR_CODES[22].startswith("Undefined feed rate")
    assert "max characters per line" in ERROR_CODES[11].lower()
    assert set(ERROR_CODES) == set(range(1, 18)) | set(range(20, 39))
    assert ALARM_CODES[3].startswith("Reset while in motion")
    assert set(ALARM_CODES) == set(range(1, 11))


def test_reply_numbers_are_ascii_digits_only():
    assert parse_code("error:22") == 22 and parse_code("ALARM:1") == 1
    for bad in ("error:\u00b2", "error:\u0662", "ALARM:", "error:1x", "error:" + "9" * 30):
        with pytest.raises(ParseError):
            parse_code(bad)
    for bad in ("<Hold:\u00b2|MPos:0,0,0>", "<Idle|MPos:\u0661,0,0>", "<Idle|Bf:15,\uff11>", "<Idle|MPos:1e3,0,0>",
                "<Idle|MPos:inf,0,0>", "<Idle|MPos:nan,0,0>", "<Idle|MPos:" + "9" * 40 + ",0,0>", "<Idle|MPos:1.0>",
                "<Idle|WPos:1,2,3,4,5,6,7>", "<Idle|MPos:0,0,0|WCO:5>"):
        with pytest.raises(ParseError):
            parse_status(bad)
    assert parse_welcome("Grbl \u0661.1h ['$' for help]") is None


def test_path_track_accepts_the_path_and_refuses_excursions():
    track = PathTrack()
    track.start((0.0, 0.0))
    track.append((1000.0, 0.0), False)   # travel
    n = track.append((1000.0, 1000.0), True)  # draw
    assert track.check((500.0, 0.0), False, 5) is None and track.check((1000.0, 400.0), True, 5) is None
    assert track.check((1000.0, 0.0), True, 5) is None  # at a vertex the pen may be either way
    assert "off the path" in track.check((300.0, 300.0), None, 5)
    assert "pen is down" in track.check((500.0, 0.0), True, 5)  # a pen-up line turned into a pen-down one
    assert "pen is up" in track.check((1000.0, 500.0), False, 5)
    track.done_until(n)
    assert len(track) == 1 and track.end == (1000.0, 1000.0)
    assert track.check((1000.0, 500.0), True, 5) is not None  # the legs before the confirmed point are gone

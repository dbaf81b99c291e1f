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
    Garble,
    PathTrack,
    PenMotion,
    SentLeg,
    explain_position,
    garbled_variants,
    parse_code,
    parse_status,
    parse_welcome,
    stroke_lines,
    words_of,
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


def test_garbled_variants_are_the_valid_lines_one_dropped_byte_leaves():
    """X12.3 -> X1.3 / X2.3 / X123 / X12 ...; a dropped letter or newline leaves no valid line (GRBL rejects it)."""
    targets = {v["X"][0] for v in garbled_variants("G1 X12.3") if "X" in v}
    assert targets == {2.3, 1.3, 123.0, 12.0}
    assert all(set(v) == {"G", "X"} for v in garbled_variants("G1 X12.3"))  # 'G X12.3', '1 X12.3', 'G1 12.3': errors
    assert {v["S"][0] for v in garbled_variants("M3 S500") if "S" in v} == {0.0, 50.0}
    assert words_of("G1 X1 X2") is None and words_of("G1 X") is None and words_of("M3 S50G4 P0.15") is not None


def test_a_position_off_the_path_is_explained_by_the_line_that_lost_a_byte():
    """The first leg whose one-byte variant passes through the reported position; None when nothing explains it."""
    legs = [
        SentLeg(0, None, "G0 X0.000 Y0.000", (0.0, 0.0), (0.0, 0.0), False),
        SentLeg(0, 1, "M3 S50 G4 P0.15 G1 X10.000 Y0.000 F3000", (0.0, 0.0), (10000.0, 0.0), True),
        SentLeg(0, 2, "G1 X10.000 Y12.000", (10000.0, 0.0), (10000.0, 12000.0), True),
        SentLeg(0, 3, "G1 X20.000 Y12.000", (10000.0, 12000.0), (20000.0, 12000.0), True),
    ]
    down = lambda s: s < 275
    # Y12.000 -> Y2.000: to (10, 2) and then on to (20, 12)
    assert explain_position(legs, (15000.0, 7000.0), True, 20, 0.001, down) == Garble(legs[2], (10000.0, 2000.0))
    # S50 -> S5 stays down; S50 -> S0 lifts: the pen up along the drawn legs of the stroke (nothing of them drawn)
    assert explain_position(legs, (10000.0, 6000.0), False, 20, 0.001, down) == Garble(legs[1], None)
    assert explain_position(legs, (50000.0, 90000.0), True, 20, 0.001, down) is None


def test_the_legs_before_the_last_position_seen_on_the_path_ran_as_sent():
    """At (25, 12), 5 mm past the last leg's end: X10.000 -> X10000 on the second leg explains it (a target 10 m
    away, the next leg coming back through it), and so does X20.000 -> X20000 on the third.  The first is taken,
    unless a report saw the pen on the third leg: then the legs before it ran as sent."""
    legs = [
        SentLeg(0, 1, "G1 X10.000 Y0.000", (0.0, 0.0), (10000.0, 0.0), True),
        SentLeg(0, 2, "G1 X10.000 Y12.000", (10000.0, 0.0), (10000.0, 12000.0), True),
        SentLeg(0, 3, "G1 X20.000 Y12.000", (10000.0, 12000.0), (20000.0, 12000.0), True),
    ]
    down = lambda s: s < 275
    assert explain_position(legs, (25000.0, 12000.0), True, 10, 0.001, down) == Garble(legs[1], (10000000.0, 12000.0))
    seen = explain_position(legs, (25000.0, 12000.0), True, 10, 0.001, down, since=(15000.0, 12000.0))
    assert seen == Garble(legs[2], (20000000.0, 12000.0))


LEG = SentLeg(0, 2, "G1 X100.000 Y0.000", (0.0, 0.0), (100000.0, 0.0), True)


@pytest.mark.parametrize(("target", "stop", "inked"), [
    ((50000.0, 20.0), (60000.0, 5000.0), (50000.0, 0.0)),  # a digit short, then on: drawn to its projection
    ((50000.0, 20.0), (20000.0, 8.0), (20000.0, 0.0)),  # held on the way: drawn to where it stopped
    ((200000.0, 0.0), (150000.0, 0.0), (100000.0, 0.0)),  # X100 -> X200: the whole leg, then beyond
    ((50000.0, 5000.0), (10000.0, 1000.0), None),  # it left the leg: stray, the leg again from its start
    ((-5000.0, 0.0), (-5000.0, 0.0), None),  # backwards: nothing of the leg
    ((40.0, 0.0), (40.0, 0.0), None),  # no farther than the tolerance
    (None, (0.0, 0.0), None),  # never ran
])
def test_a_changed_line_has_drawn_its_leg_as_far_as_it_ran_along_it(target, stop, inked):
    """Worked examples on a 100 mm leg along x, tolerance 50 units (0.05 mm)."""
    assert Garble(LEG, target).inked_to(stop, 50.0) == inked


def test_a_changed_travel_draws_nothing_of_its_leg():
    travel = SentLeg(0, None, "G0 X100.000 Y0.000", (0.0, 0.0), (100000.0, 0.0), False)
    assert Garble(travel, (50000.0, 0.0)).inked_to((50000.0, 0.0), 50.0) is None

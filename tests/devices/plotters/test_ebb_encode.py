"""EBB encoding: versions, servo positions, sliced moves and their steps, SM/XM/LM text, reply parsing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.devices.plotters.ebb_encode import (
    SlicedMove,
    move_commands,
    parse_error,
    parse_qc,
    parse_qg,
    parse_qm,
    parse_qs,
    parse_version_reply,
    reply_shape,
    servo_move_ms,
    servo_positions,
    servo_rate_commands,
    slice_polyline,
    step_deltas,
    supports,
    vplus_volts,
)
from pixelpen.errors import ConfigError, ParseError
from pixelpen.profiles.model import ServoSettings, load_profile
from pixelpen.vector.motion import MotionLimits

DOWN = MotionLimits(speed=50.0, accel=200.0, cornering=0.127)   # saxi's pen-down limits (plotters.md §2.4)
STEPS_PER_MM = 80.0


# -- versions and features ---------------------------------------------------------------------------
def test_version_replies_in_both_syntaxes():
    assert parse_version_reply("EBBv13_and_above EB Firmware Version 2.8.1\r\n") == ((2, 8, 1), False)
    assert parse_version_reply("V,EBBv13_and_above EB Firmware Version 3.0.2") == ((3, 0, 2), True)
    for bad in ("OK", "EBBv13_and_above EB Firmware Version 2.8", "!8 Err: Unknown command 'V:56'", ""):
        with pytest.raises(ParseError):
            parse_version_reply(bad)


def test_feature_gates_follow_the_command_reference():
    assert not supports((2, 6, 9), "LM") and supports((2, 7, 0), "LM")
    assert not supports((2, 6, 1), "QG") and supports((2, 6, 2), "QG")
    assert not supports((2, 4, 3), "QM") and supports((2, 4, 4), "QM")
    assert not supports((2, 2, 9), "XM") and supports((2, 3, 0), "XM")
    assert supports((1, 9, 2), "QB")


# -- servo -----------------------------------------------------------------------------------------------
def test_servo_positions_from_pyaxidraw_defaults():
    """min 9855, max 27831 (0.82-2.32 ms), up 60 %, down 30 %: 9855 + 17976 x 0.6 = 20640.6; x 0.3 = 15247.8."""
    assert servo_positions(load_profile("axidraw_v3").servo) == (20641, 15248)
    servo = ServoSettings(min=10000, max=20000, up_percent=50.0, down_percent=25.0)
    assert servo_positions(servo) == (15000, 12500)
    assert servo_positions(servo, up_percent=100, down_percent=0) == (20000, 10000)


def test_servo_defaults_without_a_profile_range():
    assert servo_positions(None) == (12000, 16000)  # SC,4 / SC,5 reset values
    with pytest.raises(ConfigError):
        servo_positions(None, up_percent=50)
    with pytest.raises(ConfigError):
        servo_positions(ServoSettings(min=1000, max=2000, up_percent=50.0, down_percent=20.0), up_percent=120)
    with pytest.raises(ConfigError):
        servo_positions(ServoSettings(min=1000, max=2000))


# -- steps ------------------------------------------------------------------------------------------------
def test_servo_rates_as_pyaxidraw_sends_them():
    """SC,11 raise / SC,12 lower (pyaxidraw pen_handling servo_init, fw >= 2.6.0); slew = |Δ| x 24 ms / rate."""
    assert servo_rate_commands(400, 400) == ["SC,11,400", "SC,12,400"]
    assert servo_rate_commands(1618, 1079) == ["SC,11,1618", "SC,12,1079"]  # pyaxidraw's 75 % / 50 % defaults
    assert supports((2, 6, 0), "SC_rates") and not supports((2, 5, 5), "SC_rates")
    assert servo_move_ms(15248, 20641, 400) == 324  # 5393 x 0.024 / 400 = 0.3236 s
    assert servo_move_ms(20641, 15248, 5393) == 24
    for bad in (0, 65536, 1.5):
        with pytest.raises(ConfigError, match="SC,11/12"):
            servo_rate_commands(bad, 400)


def test_fractional_steps_carry_over_many_tiny_moves():
    """10,000 moves of 0.37 step each: every delta is 0 or 1 and they sum to exactly rint(3700) steps."""
    positions = np.arange(10_001) * 0.37
    deltas = step_deltas(positions[:, None])
    assert set(np.unique(deltas).tolist()) <= {0, 1}
    assert deltas.sum() == 3700
    assert np.abs(np.cumsum(deltas) - positions[1:]).max() <= 0.5  # never more than half a step off


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-3.0, 3.0, allow_nan=False), min_size=1, max_size=400))
def test_step_deltas_sum_exactly_for_any_path(moves):
    positions = np.concatenate([[0.0], np.cumsum(moves)])
    deltas = step_deltas(positions)
    assert deltas.sum() == int(np.rint(positions[-1]))
    assert np.all(np.abs(np.cumsum(deltas) - positions[1:]) <= 0.5 + 1e-9)


def test_ten_millimetre_move_is_800_steps():
    move = slice_polyline(np.array([[0.0, 0.0], [10.0, 0.0]]), DOWN, STEPS_PER_MM, 0.025)
    assert move.steps.sum(axis=0).tolist() == [800, 0]
    # rest to rest, 10 mm < v²/a = 12.5 mm: a triangle of 2·sqrt(d/a) = 0.4472 s, cut into 18 slices <= 25 ms
    assert len(move) == math.ceil(2 * math.sqrt(10 / 200) / 0.025) == 18
    assert abs(move.ms.sum() - 447) <= 1
    speed = move.steps[:, 0] / move.ms  # steps per ms
    assert speed.max() <= 50 * 80 / 1000 + 0.3  # never above 50 mm/s (4 steps/ms) but for rounding
    assert speed[0] < speed[len(speed) // 2] > speed[-1]  # accelerates, then decelerates


def test_slices_end_on_every_vertex():
    square = np.array([[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]], float)
    move = slice_polyline(square, DOWN, STEPS_PER_MM, 0.025)
    path = np.cumsum(move.steps, axis=0)
    corners = {tuple(p) for p in (square[1:] * STEPS_PER_MM).astype(int).tolist()}
    assert corners <= {tuple(p) for p in path.tolist()}
    on_edge = (path[:, 0] == 0) | (path[:, 0] == 800) | (path[:, 1] == 0) | (path[:, 1] == 800)
    assert on_edge.all()  # no slice cuts a corner
    assert move.steps.sum(axis=0).tolist() == [0, 0]


def test_slices_respect_the_step_rate_limit():
    fast = MotionLimits(speed=400.0, accel=4000.0)
    move = slice_polyline(np.array([[0.0, 0.0], [100.0, 100.0]]), fast, STEPS_PER_MM, 0.025)
    motor1 = np.abs(move.steps[:, 0] + move.steps[:, 1])
    assert (motor1 / move.ms).max() <= 25.0  # 25,000 steps/s: ebb.html SM
    assert (move.ms >= 1).all()


def test_zero_length_polyline_makes_no_slices():
    assert len(slice_polyline(np.array([[5.0, 5.0]]), DOWN, STEPS_PER_MM, 0.025)) == 0
    assert len(slice_polyline(np.array([[5.0, 5.0], [5.0, 5.0]]), DOWN, STEPS_PER_MM, 0.025)) == 0


# -- command text -----------------------------------------------------------------------------------------
ONE = SlicedMove(np.array([100, 50]), np.array([[800, 0], [0, -400]]), np.array([0.0, 80.0]), np.array([80.0, 0.0]),
                 np.array([1, 2]))


def test_sm_mixes_axes_xm_does_not():
    """AxiDraw: motor1 = x + y, motor2 = x − y; SM takes motor steps, XM takes A, B with A+B / A−B mixed on board."""
    assert move_commands(ONE, "sm") == ["SM,100,800,800", "SM,50,-400,400"]
    assert move_commands(ONE, "xm") == ["XM,100,800,0", "XM,50,0,-400"]
    with pytest.raises(ConfigError):
        move_commands(ONE, "hm")


def test_lm_pause_slice_is_an_sm_delay():
    pause = SlicedMove(np.array([20]), np.array([[0, 0]]), np.zeros(1), np.zeros(1), np.zeros(1, int))
    assert move_commands(pause, "lm") == ["SM,20,0,0"]


def test_lm_direction_before_firmware_3_is_the_sign_of_rate():
    back = SlicedMove(np.array([25]), np.array([[-20, 0]]), np.array([10.0]), np.array([10.0]), np.ones(1, int))
    (new,) = move_commands(back, "lm")
    (old,) = move_commands(back, "lm", lm_signed_steps=False)
    r1, s1, a1, r2, s2, a2 = (int(v) for v in new.split(",")[1:])
    assert s1 == s2 == -20 and r1 > 0 and r2 > 0
    assert old == f"LM,{-r1},20,{-a1},{-r2},20,{-a2}"


def _lm_steps_at(rate: int, accel: int, ticks: int) -> int:
    """ebb.html LM: Steps = Floor((C0 + Rate·T + ½·Accel·T²) / 2³¹), C0 = 0."""
    return int((rate * ticks + accel * ticks * ticks / 2) // 2**31)


@pytest.mark.parametrize("path", [
    [[0, 0], [10, 0]], [[0, 0], [3, 4], [3, 9], [-2, 9]], [[0, 0], [0.05, 0.0125]], [[0, 0], [40, -25]],
])
def test_lm_slices_finish_their_steps_within_the_slice(path):
    move = slice_polyline(np.array(path, float), DOWN, STEPS_PER_MM, 0.025)
    for cmd, ms in zip(move_commands(move, "lm"), move.ms, strict=True):
        fields = cmd.split(",")
        if fields[0] == "SM":
            continue
        r1, s1, a1, r2, s2, a2 = (int(v) for v in fields[1:])
        ticks = int(ms) * 25
        for rate, steps, accel in ((r1, s1, a1), (r2, s2, a2)):
            if steps == 0:
                assert rate == 0 and accel == 0
                continue
            assert rate >= 0 and rate + accel * ticks >= 0          # never stalls or reverses
            assert _lm_steps_at(rate, accel, ticks) >= abs(steps)   # done by the end of its slice
            assert _lm_steps_at(rate, accel, max(ticks - 25, 0)) < abs(steps)  # ... and not a millisecond early


def test_lm_reproduces_the_documented_example():
    """ebb.html LM example 6: 500 -> 800 steps/s over 50 steps takes 77 ms; our slice of 77 ms, 50 steps agrees."""
    move = SlicedMove(np.array([77]), np.array([[25, 25]]), np.array([500 / 80 * 1.0]), np.array([800 / 80 * 1.0]),
                      np.ones(1, int))
    (cmd,) = move_commands(move, "lm")
    r1, s1, a1, r2, s2, a2 = (int(v) for v in cmd.split(",")[1:])
    assert (s1, s2) == (50, 0) and (r2, a2) == (0, 0)
    assert abs(r1 - 42950000) / 42950000 < 0.02 and abs(a1 - 13400) / 13400 < 0.05


# -- replies ------------------------------------------------------------------------------------------------
def test_reply_shapes_follow_the_legacy_syntax():
    assert reply_shape("SM") == "ack" and reply_shape("sp") == "ack"
    assert reply_shape("QM") == "data" and reply_shape("QG") == "data" and reply_shape("V") == "data"
    assert reply_shape("QB") == "data_ok" and reply_shape("ES") == "data_ok" and reply_shape("QS") == "data_ok"


def test_error_replies_in_both_syntaxes():
    assert parse_error("!8 Err: Unknown command 'B:42'OK\r\n") == (8, "Unknown command 'B:42'")
    assert parse_error("!6 Err: Invalid paramter value") == (6, "Invalid paramter value")
    assert parse_error("SM,!4 Err: Missing parameter(s)") == (4, "Missing parameter(s)")
    assert parse_error("V,!10 Err: No checksum found but required") == (10, "No checksum found but required")
    assert parse_error("OK") is None and parse_error("QM,0,0,0,0") is None and parse_error("!") is None


def test_qm_and_qg_data():
    assert parse_qm("QM,1,0,1,0") == (1, 0, 1, 0)
    assert parse_qm("0,0,0,0") == (0, 0, 0, 0)
    assert parse_qg("3E") == 0x3E and parse_qg("QG,3E") == 0x3E and parse_qg("qg,0f") == 0x0F
    for bad in ("QM,1,0,1", "QM,a,0,0,0", "QM,"):
        with pytest.raises(ParseError):
            parse_qm(bad)
    for bad in ("", "XYZ", "100", "QG"):
        with pytest.raises(ParseError):
            parse_qg(bad)


def test_slices_know_the_vertex_they_have_reached():
    # a zero-length segment (vertex 2 repeats vertex 1) is no block: the third block starts at vertex 2
    path = np.array([[0, 0], [10, 0], [10, 0], [10, 10]], float)
    move = slice_polyline(path, DOWN, STEPS_PER_MM, 0.025)
    ends = np.cumsum(move.steps, axis=0)
    at_corner = np.flatnonzero((ends == [800, 0]).all(axis=1))[0]
    assert (move.vertex[:at_corner] == 0).all() and move.vertex[at_corner] == 1
    assert (move.vertex[at_corner + 1:-1] == 2).all() and move.vertex[-1] == 3
    assert np.all(np.diff(move.vertex) >= 0)


def test_qs_and_qc_data():
    assert parse_qs("QS,-120,35") == (-120, 35) and parse_qs("5,0") == (5, 0)
    assert parse_qc("0394,0293") == (394, 293) and parse_qc("QC,0001,1023") == (1, 1023)
    # saxi's divider: 293 counts -> 293/1023 x 3.3 x 9.2 + 0.3 = 8.9955 V (a 9 V supply)
    assert vplus_volts(293) == pytest.approx(8.9955, abs=1e-4)
    assert vplus_volts(0) == pytest.approx(0.3)
    for bad in ("QS,1", "QS,1,2,3", "QS,a,1", "QS,\u00b2,1", "QS,\u0661,1", "QS," + "9" * 40 + ",1"):
        with pytest.raises(ParseError):
            parse_qs(bad)
    for bad in ("0394", "0394,1024", "0394,-1", "0394,\u00b2", "\u0663\u0662,1"):
        with pytest.raises(ParseError):
            parse_qc(bad)


def test_reply_numbers_are_ascii_digits_only():
    # str.isdigit() accepts superscripts; int() accepts Arabic-Indic digits: neither is an EBB reply
    for bad in ("QM,\u00b2,0,0,0", "QM,\u0661,0,0,0", "QM,1,0,0,\uff10"):
        with pytest.raises(ParseError):
            parse_qm(bad)
    assert parse_error("!\u0668 Err: x") is None
    with pytest.raises(ParseError):
        parse_version_reply("EBBv13_and_above EB Firmware Version \u0662.8.1")

"""Scripted hand motion: shapes from their geometry, the US key usages from the HID Usage Tables (§10)."""

from __future__ import annotations

import itertools
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.sim.hid import motion
from pixelpen.sim.hid.motion import END_GRACE, Hand


def samples(script: motion.Script, hz: float = 200.0) -> list[Hand]:
    """The hand every 1/hz s from 0 to the end of the script."""
    return [script.at(k / hz) for k in range(int(script.duration * hz) + 1)]


def test_line_runs_eased_from_start_to_end_with_the_pen_down_then_lifts() -> None:
    s = motion.line((10.0, 20.0), (110.0, 20.0), 2.0, pen=True)
    assert (s.at(0).x, s.at(0).y) == (10.0, 20.0)
    assert s.at(1.0).x == pytest.approx(60.0)  # halfway in time is halfway in space (smoothstep is symmetric)
    assert s.at(0.2).x - 10.0 < 0.1 * 100.0  # eased: slower than uniform at the start
    assert s.at(1.0).pressure == 0.6 and s.at(1.0).in_range
    end = s.at(2.0)
    assert (end.x, end.pressure, end.in_range, end.contacts) == (110.0, 0.0, False, ())
    (cid, cx, cy), = s.at(1.0).contacts
    assert cid == 0 and cx == pytest.approx(60.0) and cy == 20.0


def test_line_holds_its_button_during_the_stroke_only() -> None:
    s = motion.line((0, 0), (1, 1), 1.0, button=2)
    assert s.at(0.5).buttons == {2} and s.at(1.0).buttons == frozenset()


def test_circle_keeps_its_radius_and_goes_clockwise_from_twelve_o_clock() -> None:
    s = motion.circle((50.0, 40.0), 10.0, 4.0, pen=True)
    for hand in samples(s)[:-1]:
        assert math.hypot(hand.x - 50.0, hand.y - 40.0) == pytest.approx(10.0)
        assert hand.pressure == 0.5
    assert (s.at(0).x, s.at(0).y) == (50.0, 30.0)  # 12 o'clock (y grows downwards)
    assert s.at(1.0).x == pytest.approx(60.0) and s.at(1.0).y == pytest.approx(40.0)  # a quarter: 3 o'clock
    assert s.at(4.0).pressure == 0.0 and s.finished(4.0 + END_GRACE + 1e-9)


def test_a_repeating_circle_never_finishes_and_comes_round_again() -> None:
    s = motion.circle((0, 0), 5.0, 1.0, repeat=True)
    assert not s.finished(1e6)
    assert s.at(2.25).x == pytest.approx(s.at(0.25).x)


def test_signature_hovers_first_writes_three_words_with_pen_up_gaps_and_leaves() -> None:
    s = motion.signature((20.0, 80.0), 150.0)
    hands = samples(s, 500.0)
    assert hands[0].in_range and hands[0].pressure == 0.0  # proximity before contact
    down = [h.pressure > 0 for h in hands]
    strokes = sum(1 for a, b in itertools.pairwise(down) if b and not a)
    assert strokes == len(motion.SIGNATURE_WORDS) + 1  # three words and the underline
    assert all(0.0 < h.pressure <= 1.0 for h in hands if h.pressure > 0)
    last_down = max(i for i, d in enumerate(down) if d)
    assert all(h.in_range for h in hands[:last_down + 1])  # hovering in range between the words
    assert not any(h.in_range for h in hands[last_down + 2:])  # then away
    xs = [h.x for h in hands if h.pressure > 0]
    assert min(xs) >= 20.0 and max(xs) <= 20.0 + 150.0 + 1e-9  # within its width
    assert samples(s, 500.0) == hands  # deterministic


def test_signature_refuses_a_width_that_is_not_positive() -> None:
    with pytest.raises(ConfigError, match="width"):
        motion.signature((0, 0), 0)


def test_sweep_takes_the_stick_to_both_edges_the_hat_round_and_every_button() -> None:
    hands = samples(motion.sweep(3.0, buttons=4), 300.0)
    xs = [h.axes["x"] for h in hands]
    assert min(xs) == pytest.approx(-1.0) and max(xs) == pytest.approx(1.0, abs=1e-2)
    assert {h.hat for h in hands} == {None, *range(8)}
    assert set().union(*(h.buttons for h in hands)) == {1, 2, 3, 4}
    assert all(len(h.buttons) <= 1 for h in hands)
    assert all(0.0 <= h.axes["throttle"] <= 1.0 for h in hands)


def test_orbit_holds_the_stick_at_its_edge_then_lets_go() -> None:
    s = motion.orbit(2.0)
    for hand in samples(s)[:-1]:
        assert math.hypot(hand.axes["x"], hand.axes["y"]) == pytest.approx(1.0)
    assert s.at(0).axes["y"] == pytest.approx(-1.0)  # north first: y negative is forward
    assert s.at(2.0).axes["x"] == 0.0 and s.at(2.0).axes["y"] == 0.0


def test_pinch_opens_and_closes_its_fingers_round_the_centre() -> None:
    s = motion.pinch((100.0, 60.0), 50.0, 1.0, fingers=2)
    (a, ax, ay), (b, bx, by) = s.at(0.5).contacts
    assert (a, b) == (0, 1)
    assert math.hypot(ax - bx, ay - by) == pytest.approx(50.0)  # fully open at half time: spread across
    assert (ax + bx) / 2 == pytest.approx(100.0) and (ay + by) / 2 == pytest.approx(60.0)
    (_, x0, _), (_, x1, _) = s.at(0.0).contacts
    assert abs(x0 - x1) == pytest.approx(10.0)  # 20 % of the spread
    assert s.at(1.0).contacts == ()


def test_pinch_takes_one_to_ten_fingers() -> None:
    assert len(motion.pinch((0, 0), 10, 1, fingers=5).at(0.3).contacts) == 5
    with pytest.raises(ConfigError, match="fingers"):
        motion.pinch((0, 0), 10, 1, fingers=11)


def test_scroll_turns_the_wheel_then_pans() -> None:
    s = motion.scroll(5.0, 2.0)
    assert s.at(0.5).wheel == pytest.approx(2.5) and s.at(0.5).pan == 0.0
    assert (s.at(1.0).wheel, s.at(1.0).pan) == (5.0, 0.0)
    assert (s.at(2.0).wheel, s.at(2.0).pan) == (5.0, 5.0)


def test_key_strokes_are_the_us_usages_of_the_hid_usage_tables() -> None:
    # Keyboard page 0x07: a 0x04 .. z 0x1D, 1 0x1E .. 9 0x26, 0 0x27, Enter 0x28, Space 0x2C, '-' 0x2D, '/' 0x38
    assert motion.key_strokes("az19 0\n-/") == [(0x04, False), (0x1D, False), (0x1E, False), (0x26, False),
                                                (0x2C, False), (0x27, False), (0x28, False), (0x2D, False),
                                                (0x38, False)]
    assert motion.key_strokes("A!)_?~") == [(0x04, True), (0x1E, True), (0x27, True), (0x2D, True), (0x38, True),
                                            (0x35, True)]


def test_key_strokes_name_a_character_with_no_key() -> None:
    with pytest.raises(ConfigError, match=r"position 2"):
        motion.key_strokes("ab€")
    with pytest.raises(ConfigError, match="at most"):
        motion.key_strokes("a" * (motion.MAX_TEXT + 1))


def test_typing_holds_shift_around_a_shifted_key_and_releases_repeated_keys() -> None:
    s = motion.typing("aA", rate=10.0, hold=0.05)
    assert s.at(0.02).keys == {0x04}
    assert s.at(0.07).keys == frozenset()  # released before the next stroke
    assert s.at(0.105).keys == {motion.LEFT_SHIFT}  # shift first ...
    assert s.at(0.13).keys == {motion.LEFT_SHIFT, 0x04}  # ... then the key ...
    assert s.at(0.165).keys == {motion.LEFT_SHIFT}  # ... released 10 ms before shift
    assert s.at(0.2).keys == frozenset() and s.duration == pytest.approx(0.2)


@pytest.mark.parametrize(("rate", "hold"), [(0.0, 0.05), (math.nan, 0.05), (10.0, 0.09), (10.0, 0.0)])
def test_typing_refuses_a_rate_or_hold_that_cannot_type(rate: float, hold: float) -> None:
    with pytest.raises(ConfigError):
        motion.typing("a", rate=rate, hold=hold)


@pytest.mark.parametrize("seconds", [0.0, -1.0, math.inf, math.nan])
def test_durations_must_be_positive_and_finite(seconds: float) -> None:
    with pytest.raises(ConfigError, match="duration"):
        motion.line((0, 0), (1, 1), seconds)


def test_idle_is_an_empty_hand() -> None:
    assert motion.idle().at(5.0) == Hand()


@given(st.floats(-10.0, 100.0))
def test_a_script_is_a_pure_function_of_time(t: float) -> None:
    s = motion.signature((0.0, 50.0), 100.0)
    assert s.at(t) == s.at(t)
    assert s.at(t) == s.at(min(max(t, 0.0), s.duration))

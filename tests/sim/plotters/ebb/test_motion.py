"""EBB step generation checked against the LM/LT worked examples of ebb.html and a tick-by-tick reference."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.sim.plotters.ebb.motion import TICK, TWO31, AccumulatorAxis, ServoTrack


def reference(rate: int, accel: int, ticks: int, acc0: int = 0, limit: int | None = None) -> tuple[int, int]:
    """ebb.html "Methods and consequences", one 40 µs tick at a time: (steps, accumulator)."""
    r = rate - int(accel / 2)
    acc = acc0
    steps = 0
    for _ in range(ticks):
        if limit is not None and steps >= limit:
            break
        r += accel
        if r < 0:
            r += TWO31
        acc += r
        if acc >= TWO31:
            steps += 1
            acc -= TWO31
    return steps, acc


def reference_steps(rate: int, accel: int, ticks: int, acc0: int = 0, limit: int | None = None) -> int:
    """Steps of :func:`reference`."""
    return reference(rate, accel, ticks, acc0, limit)[0]


def test_lm_example_3_is_10_ms():
    # LM,85899346,10,0,17180814,2,0: a 10 ms move, 10 and 2 steps, both finishing together
    a1 = AccumulatorAxis(1, 85899346, 0, steps=10)
    a2 = AccumulatorAxis(1, 17180814, 0, steps=2)
    assert a1.completion() * TICK == pytest.approx(0.010)
    assert a2.completion() * TICK == pytest.approx(0.010)


def test_lm_example_6_takes_77_ms():
    # LM,42950000,50,13400,0,0,0: 500 -> 800 steps/s over 50 steps, "will take 77 ms"
    ax = AccumulatorAxis(1, 42950000, 13400, steps=50)
    assert ax.completion() * TICK == pytest.approx(0.077, abs=0.0005)


def test_lm_example_1_takes_0_4068_s():
    # LM,3865471,60,1732,0,0,0: 45 -> 250 steps/s over 60 steps, 0.4068 s
    ax = AccumulatorAxis(1, 3865471, 1732, steps=60)
    assert ax.completion() * TICK == pytest.approx(0.4068, rel=0.002)


def test_lm_example_7_decelerates_and_takes_500_ms():
    # LM,17179000,75,-687,8592000,75,687: 200 -> 100 and 100 -> 200 steps/s over 75 steps each, 500 ms
    slowing = AccumulatorAxis(1, 17179000, -687, steps=75)
    speeding = AccumulatorAxis(1, 8592000, 687, steps=75)
    assert slowing.completion() * TICK == pytest.approx(0.5) and speeding.completion() * TICK == pytest.approx(0.5)


def test_deceleration_past_zero_rolls_over_and_finishes():
    # Rate falls below 0 after 1000 ticks and rolls over to ~2^31: a step on nearly every tick after that
    ax = AccumulatorAxis(1, 1000 * 1000, -1000, steps=50)
    end = ax.completion()
    assert reference(1000 * 1000, -1000, end, limit=50)[0] == 50 > reference(1000 * 1000, -1000, end - 1)[0]
    assert 1000 < end < 1100


def test_lt_example_3_covers_75_steps_each():
    # LT,12500,17179000,-687,8592000,687: 500 ms, 75 steps on each axis
    assert AccumulatorAxis(1, 17179000, -687).steps_at(12500) == 75
    assert AccumulatorAxis(1, 8592000, 687).steps_at(12500) == 75


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(-20000, 20000), st.integers(0, 3000), st.integers(0, 2**31 - 1))
def test_closed_form_matches_the_tick_by_tick_reference(rate, accel, ticks, acc0):
    ax = AccumulatorAxis(1, rate, accel, acc0=acc0)
    assert ax.steps_at(ticks) == reference_steps(rate, accel, ticks, acc0)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(-(2**31), -1), st.integers(0, 3000), st.integers(0, 2**31 - 1))
def test_closed_form_counts_every_rollover(rate, accel, ticks, acc0):
    ax = AccumulatorAxis(1, rate, accel, acc0=acc0)
    assert ax.steps_at(ticks) == reference_steps(rate, accel, ticks, acc0)


@settings(max_examples=40, deadline=None)
@given(st.integers(1_000_000, 2**31 - 1), st.integers(-50_000, 5000), st.integers(1, 200),
       st.integers(0, 2**31 - 1))
def test_completion_is_the_first_tick_with_all_steps(rate, accel, steps, acc0):
    ax = AccumulatorAxis(1, rate, accel, acc0=acc0, steps=steps)
    t = ax.completion()
    assert reference(rate, accel, t, acc0, limit=steps) == (steps, ax.remainder(t))
    assert reference_steps(rate, accel, t - 1, acc0, limit=steps) < steps


def test_axis_that_never_moves_never_completes():
    assert AccumulatorAxis(1, 0, 0, steps=5).completion() is None
    assert AccumulatorAxis(1, 0, 0, steps=0).completion() == 0


def test_servo_slew_matches_the_faq():
    # FAQ: from 10000 to 15000 at rate 100 takes ((15000-10000) * 0.024) / 100 = 1.2 s
    servo = ServoTrack(10000, 0.0)
    servo.move(0.0, 15000, 100)
    assert servo.arrival() == pytest.approx(1.2)
    assert servo.position(0.6) == pytest.approx(12500)
    assert servo.crossing(12500) == pytest.approx(0.6)
    servo.move(2.0, 10000, 0)  # rate 0: at the target on the next pulse
    assert servo.position(2.0) == 10000 and servo.crossing(12500) == 2.0

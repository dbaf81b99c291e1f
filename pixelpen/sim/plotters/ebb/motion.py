"""EiBotBoard step generation: the 25 kHz accumulator of LM/LT/L3/T3, constant-rate SM/XM/HM, the pen servo.

Written from evil-mad/EggBot ``docs/ebb.html`` (LM "Methods and consequences", SM/XM/HM limits, S2/SC
servo rates and the FAQ's servo timing).  Every 40 µs an axis adds Accel (after Jerk) to Rate, rolls a
negative Rate over by 2³¹, adds Rate to its accumulator and steps when the accumulator passes 2³¹.
Rollovers are counted exactly for jerk-free moves; with Jerk (whose L3 description is "coming soon")
the accumulator follows its closed form without them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["MAX_STEP_RATE", "MIN_STEP_RATE", "TICK", "AccumulatorAxis", "ServoTrack"]

TICK = 40e-6  # ISR period, seconds (25 kHz)
TWO31 = 1 << 31
MAX_STEP_RATE = 25000.0  # steps/s
MIN_STEP_RATE = 0.00001164  # steps/s (fw 3.0)
SERVO_PERIOD = 0.024  # one RC-servo frame: 8 channels x 3 ms
_TICK_CAP = 1 << 36  # ~ 32 days of ticks: a move that would take longer never ends


def _floor_sum(n: int, m: int, a: int, b: int) -> int:
    """Sum of floor((a*i + b) / m) for i in 0..n-1 (m > 0), in O(log m) steps (Euclid-like reduction)."""
    total = 0
    while n > 0:
        qa, a = divmod(a, m)
        qb, b = divmod(b, m)
        total += qa * n * (n - 1) // 2 + qb * n
        y = a * n + b
        if y < m:
            break
        n, b, m, a = y // m, y % m, a, m
    return total


@dataclass(frozen=True)
class AccumulatorAxis:
    """One axis of an LM/LT/L3/T3 move: direction, |Rate|, Accel and Jerk per tick, start accumulator."""

    direction: int
    rate: int
    accel: int
    jerk: int = 0
    acc0: int = 0
    steps: int | None = None  # LM/L3: the axis stops after this many steps

    def _rate_adjusted(self) -> int:
        return self.rate - int(self.accel / 2)

    def _rolled(self, t: int) -> int:
        """Sum over ticks 1..t of the rollovers made so far (each adds 2³¹ to every later Rate).

        A decelerating jerk-free axis rolls over whenever Rate + Accel goes negative, so Rate at tick k
        is (R + A·k) mod 2³¹ once R + A·k < 0: any number of rollovers, counted exactly.
        """
        if self.jerk or self.accel >= 0:
            return 0
        r = self._rate_adjusted()
        k0 = max(1, r // -self.accel + 1)  # first tick at which R + A·k < 0
        if t < k0:
            return 0
        return -_floor_sum(t - k0 + 1, TWO31, self.accel, r + self.accel * k0)

    def accumulated(self, ticks: int) -> int:
        """Accumulator total after ``ticks`` ISR periods (exact integer, before steps are removed)."""
        t = int(ticks)
        if t <= 0:
            return self.acc0
        total = self.acc0 + t * self._rate_adjusted() + self.accel * t * (t + 1) // 2
        total += self.jerk * t * (t + 1) * (t + 2) // 6
        return total + self._rolled(t) * TWO31

    def steps_at(self, ticks: int) -> int:
        """Steps taken after ``ticks`` periods (at most one per tick, capped at ``steps``)."""
        n = max(0, min(self.accumulated(ticks) // TWO31, max(int(ticks), 0)))
        return n if self.steps is None else min(n, self.steps)

    def remainder(self, ticks: int) -> int:
        """The accumulator left after the axis ran ``ticks`` periods (an LM axis stops adding at its last step)."""
        return self.accumulated(ticks) - self.steps_at(ticks) * TWO31

    def completion(self) -> int | None:
        """Ticks until ``steps`` steps are done (0 for none); None when the axis never gets there."""
        if not self.steps:
            return 0
        hi = 1
        while self.steps_at(hi) < self.steps:
            if hi >= _TICK_CAP:
                return None
            hi *= 2
        lo = hi // 2
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if self.steps_at(mid) >= self.steps:
                hi = mid
            else:
                lo = mid
        return hi


class ServoTrack:
    """The pen-lift servo's pulse width over time: slews toward its target at ``rate`` per 24 ms frame."""

    def __init__(self, position: float, t: float) -> None:
        self.start = float(position)
        self.target = float(position)
        self.rate = 0.0
        self.t0 = float(t)

    def position(self, t: float) -> float:
        """Pulse width (units of 83.3 ns) at time ``t``."""
        if self.rate <= 0 or t <= self.t0:
            return self.target if (self.rate <= 0 and t >= self.t0) else self.start
        moved = (t - self.t0) * self.rate / SERVO_PERIOD
        span = self.target - self.start
        return self.target if moved >= abs(span) else self.start + math.copysign(moved, span)

    def move(self, t: float, target: float, rate: float) -> None:
        """Start slewing from wherever the servo is at ``t`` toward ``target``."""
        self.start = self.position(t)
        self.t0 = float(t)
        self.target = float(target)
        self.rate = max(float(rate), 0.0)

    def arrival(self) -> float:
        """Time the servo reaches its target (FAQ: |Δ| × 0.024 s / rate)."""
        if self.rate <= 0:
            return self.t0
        return self.t0 + abs(self.target - self.start) * SERVO_PERIOD / self.rate

    def crossing(self, level: float) -> float | None:
        """When the pulse width passes ``level`` on the current slew (None if it does not)."""
        lo, hi = sorted((self.start, self.target))
        if not lo < level < hi:
            return None
        if self.rate <= 0:
            return self.t0
        return self.t0 + abs(level - self.start) * SERVO_PERIOD / self.rate

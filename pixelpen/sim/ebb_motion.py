"""EiBotBoard step generation: the 25 kHz accumulator of LM/LT/L3/T3, constant-rate SM/XM/HM, the pen servo.

Written from evil-mad/EggBot ``docs/ebb.html`` (LM "Methods and consequences", SM/XM/HM limits, S2/SC
servo rates and the FAQ's servo timing).  Every 40 µs an axis adds Accel (after Jerk) to Rate, rolls a
negative Rate over by 2³¹, adds Rate to its accumulator and steps when the accumulator passes 2³¹.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["MAX_STEP_RATE", "MIN_STEP_RATE", "TICK", "AccumulatorAxis", "ServoTrack"]

TICK = 40e-6  # ISR period, seconds (25 kHz)
TWO31 = 1 << 31
MAX_STEP_RATE = 25000.0  # steps/s
MIN_STEP_RATE = 0.00001164  # steps/s (fw 3.0)
SERVO_PERIOD = 0.024  # one RC-servo frame: 8 channels x 3 ms
_TICK_CAP = 1 << 36  # ~ 32 days of ticks: a move that would take longer never ends


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

    def _rollover_tick(self) -> int | None:
        """First tick at which Rate goes negative and rolls over (jerk-free moves only)."""
        if self.jerk or self.accel >= 0:
            return None
        r = self._rate_adjusted()
        if r + self.accel >= 0:
            return r // (-self.accel) + 1
        return 1

    def accumulated(self, ticks: int) -> int:
        """Accumulator total after ``ticks`` ISR periods (exact integer, before steps are removed)."""
        t = int(ticks)
        if t <= 0:
            return self.acc0
        total = self.acc0 + t * self._rate_adjusted() + self.accel * t * (t + 1) // 2
        total += self.jerk * t * (t + 1) * (t + 2) // 6
        k0 = self._rollover_tick()
        if k0 is not None and t >= k0:
            total += (t - k0 + 1) * TWO31
        return total

    def steps_at(self, ticks: int) -> int:
        """Steps taken after ``ticks`` periods (at most one per tick, capped at ``steps``)."""
        n = max(0, min(self.accumulated(ticks) // TWO31, max(int(ticks), 0)))
        return n if self.steps is None else min(n, self.steps)

    def remainder(self, ticks: int) -> int:
        """The accumulator value left after the move (for a later move that does not clear it)."""
        return self.accumulated(ticks) - self.steps_at(ticks) * TWO31

    def completion(self) -> int | None:
        """Ticks until ``steps`` steps are done (0 for none); None when the axis never gets there."""
        if not self.steps:
            return 0
        if self.steps_at(_TICK_CAP) < self.steps:
            return None
        lo, hi = 0, 1
        while self.steps_at(hi) < self.steps:
            lo, hi = hi, hi * 2
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if self.steps_at(mid) >= self.steps:
                hi = mid
            else:
                lo = mid
        return hi

    def steps_sampled(self, ticks: np.ndarray) -> np.ndarray:
        """Vectorised :meth:`steps_at` (float arithmetic; exact enough for drawing the path)."""
        t = np.maximum(np.asarray(ticks, dtype=np.float64), 0.0)
        acc = self.acc0 + t * self._rate_adjusted() + self.accel * t * (t + 1) / 2
        acc = acc + self.jerk * t * (t + 1) * (t + 2) / 6
        k0 = self._rollover_tick()
        if k0 is not None:
            acc = acc + np.maximum(t - k0 + 1, 0.0) * TWO31
        n = np.clip(np.floor(acc / TWO31), 0, t)
        if self.steps is not None:
            n = np.minimum(n, self.steps)
        return n


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

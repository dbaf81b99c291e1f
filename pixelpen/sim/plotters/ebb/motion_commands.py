"""The EBB's motion commands: SM, XM, TR, HM (constant rate), LM, L3, LT, T3, TD (accumulator), EM, ES, CS.

From ebb.html: SM/XM/TR step rates are capped (SM, TR) or refused (XM) outside 1.164e-5 .. 25 000
steps/s; LM/L3 need a step count and a rate on some axis (unless ``CU,2,0``); HM homes to the step
counters' origin or a given position; EM on fw >= 3.0 enters the FIFO like a move, before 3.0 it acts at
once.
"""

from __future__ import annotations

import math
from typing import Any

from pixelpen.sim.plotters.ebb.machine import MotionCommand
from pixelpen.sim.plotters.ebb.motion import MAX_STEP_RATE, MIN_STEP_RATE, TICK, AccumulatorAxis
from pixelpen.sim.plotters.ebb.params import EbbError, error_text
from pixelpen.sim.plotters.ebb.parser import EbbParser

__all__ = ["MotionCommands"]

Axes = tuple[AccumulatorAxis, AccumulatorAxis]


class MotionCommands(EbbParser):
    """Handlers of the commands that enter the motion FIFO as moves, and of EM, ES and CS."""

    # ---- how moves enter the queue ---------------------------------------------------------------
    def _begin_motion(self, t: float, clear: int) -> None:
        self._split_ink(t)
        if self._auto_enable:
            self._ports.set_enables(True, True)
        for k in range(2):
            if clear & (1 << k):
                self._acc[k] = 0

    def _linear(self, name: str, duration_ms: int, s1: int, s2: int, clear: int, capped: bool) -> None:
        if s1 == 0 and s2 == 0:
            delay = min(duration_ms, 100000) / 1000.0
            self._queue(name, MotionCommand(name, duration=delay))
            return
        duration = duration_ms / 1000.0
        fastest = max(abs(s1), abs(s2)) / MAX_STEP_RATE
        if duration < fastest:
            if not capped:
                raise EbbError(0, "!0 Err: <axis1> step rate too high" if abs(s1) >= abs(s2)
                               else "!0 Err: <axis2> step rate too high")
            duration = fastest
        slowest = min(abs(s) for s in (s1, s2) if s) / MIN_STEP_RATE
        if duration > slowest:
            if not capped:
                raise EbbError(0, "!0 Err: <axis1> step rate too low")
            duration = slowest
        duration = math.ceil(duration / TICK - 1e-9) * TICK
        cmd = MotionCommand(name, duration=duration, linear=(s1, s2), moving=(s1 != 0, s2 != 0))
        cmd.begin = lambda t: self._begin_motion(t, clear)
        self._queue(name, cmd)

    def _accumulator(self, name: str, axes: Axes, ticks: int | None, clear: int, reply: bool = True) -> None:
        if ticks is None:
            ends = [ax.completion() for ax in axes]
            if any(e is None for e in ends):
                raise self._invalid()
            ticks = max(e for e in ends if e is not None)
        a1, a2 = axes
        cmd = MotionCommand(name, duration=ticks * TICK, axes=axes,
                            moving=(self._axis_moves(a1), self._axis_moves(a2)))

        def begin(t: float, cmd: MotionCommand = cmd) -> None:
            self._begin_motion(t, clear)
            b1, b2 = (AccumulatorAxis(a.direction, a.rate, a.accel, a.jerk, self._acc[k], a.steps)
                      for k, a in enumerate(axes))
            cmd.axes = (b1, b2)
            if b1.steps is not None or b2.steps is not None:
                cmd.ends = (b1.completion() or 0, b2.completion() or 0)
                cmd.ticks = max(cmd.ends)
                cmd.duration = cmd.ticks * TICK

        cmd.ticks = ticks
        cmd.ends = (ticks, ticks)
        cmd.begin = begin
        self._queue(name, cmd, reply)

    @staticmethod
    def _axis_moves(ax: AccumulatorAxis) -> bool:
        """Whether QM reports the axis moving during the command."""
        return bool((ax.steps is None and (ax.rate or ax.accel)) or ax.steps)

    @staticmethod
    def _lm_axis(rate: int, steps: int, accel: int, jerk: int = 0) -> AccumulatorAxis:
        direction = -1 if (rate < 0) != (steps < 0) else 1
        return AccumulatorAxis(direction, abs(rate), accel if rate >= 0 else -accel, jerk, 0, abs(steps))

    def _check_lm(self, axes: Axes) -> None:
        if not any(ax.steps and (ax.rate or ax.accel or ax.jerk) for ax in axes):
            raise self._invalid()

    @staticmethod
    def _lt_axes(r1: int, a1: int, j1: int, r2: int, a2: int, j2: int) -> Axes:
        return (AccumulatorAxis(-1 if r1 < 0 else 1, abs(r1), a1, j1),
                AccumulatorAxis(-1 if r2 < 0 else 1, abs(r2), a2, j2))

    # ---- the handlers ----------------------------------------------------------------------------
    def cmd_SM(self, name: str, v: list[Any]) -> None:
        duration, s1, s2, clear = v
        if duration == 0:
            raise self._invalid()
        self._linear(name, duration, s1, s2 or 0, clear or 0, capped=True)

    def cmd_XM(self, name: str, v: list[Any]) -> None:
        duration, a, b, clear = v
        if duration == 0:
            raise self._invalid()
        self._linear(name, duration, a + b, a - b, clear or 0, capped=False)

    def cmd_TR(self, name: str, v: list[Any]) -> None:
        rate, s1, s2, clear = v
        if rate == 0:
            raise self._invalid()
        s2 = s2 or 0
        duration_ms = max(abs(s1), abs(s2)) * 1000.0 / rate
        self._linear(name, max(math.ceil(duration_ms), 1), s1, s2, clear or 0, capped=True)

    def cmd_LM(self, name: str, v: list[Any]) -> None:
        r1, s1, a1, r2, s2, a2, clear = v
        axes = (self._lm_axis(r1, s1, a1), self._lm_axis(r2, s2, a2))
        if self._limit_check:
            self._check_lm(axes)
        self._accumulator(name, axes, None, clear or 0)

    def cmd_L3(self, name: str, v: list[Any]) -> None:
        r1, s1, a1, j1, r2, s2, a2, j2, clear = v
        axes = (self._lm_axis(r1, s1, a1, j1), self._lm_axis(r2, s2, a2, j2))
        if self._limit_check:
            self._check_lm(axes)
        self._accumulator(name, axes, None, clear or 0)

    def cmd_LT(self, name: str, v: list[Any]) -> None:
        intervals, r1, a1, r2, a2, clear = v
        self._accumulator(name, self._lt_axes(r1, a1, 0, r2, a2, 0), intervals, clear or 0)

    def cmd_T3(self, name: str, v: list[Any]) -> None:
        intervals, r1, a1, j1, r2, a2, j2, clear = v
        self._accumulator(name, self._lt_axes(r1, a1, j1, r2, a2, j2), intervals, clear or 0)

    def cmd_TD(self, name: str, v: list[Any]) -> None:
        intervals, r1a, r1b, a1, j1, r2a, r2b, a2, j2, clear = v
        self._accumulator(name, self._lt_axes(r1a, 0, j1, r2a, 0, j2), intervals, clear or 0, reply=False)
        self._accumulator(name, self._lt_axes(r1b, a1, -j1, r2b, a2, -j2), intervals, clear or 0)

    def cmd_HM(self, name: str, v: list[Any]) -> None:
        freq, p1, p2 = v
        if freq < 2 or freq > 25000:
            raise self._invalid()
        if p1 is not None and p2 is None:
            raise EbbError(4, error_text(4, self._fw3))
        target = (p1 or 0, p2 or 0)
        cmd = MotionCommand(name, moving=(True, True))

        def begin(t: float) -> None:
            self._begin_motion(t, 0)
            d1, d2 = target[0] - self._steps[0], target[1] - self._steps[1]
            cmd.linear = (d1, d2)
            longest = max(abs(d1), abs(d2))
            travel = math.ceil(longest / freq / TICK - 1e-9) * TICK if longest else 0.0
            cmd.duration = 0.005 + travel  # the ~5 ms start delay is spread over the move

        cmd.begin = begin
        self._queue(name, cmd)

    def cmd_EM(self, name: str, v: list[Any]) -> None:
        e1, e2 = v

        def begin(t: float) -> None:
            self._split_ink(t)
            if e1:
                self._ports.select_microsteps(e1)
            self._ports.set_enables(bool(e1), None if e2 is None else bool(e2))
            self._steps = [0, 0]
            self._acc = [0, 0]

        if self._fw3:
            self._queue(name, MotionCommand(name, begin=begin))
        else:
            begin(self._now)
            self._reply(name)

    def cmd_ES(self, name: str, v: list[Any]) -> None:
        (disable,) = v
        interrupted = self._stop_motion()
        if disable:
            self._ports.set_enables(False, False)
        self._reply(name, str(int(interrupted)), kind="rev")
        if not self._future:
            self._emit(self._ending("ok").encode())

    def cmd_CS(self, name: str, v: list[Any]) -> None:
        self._steps = [0, 0]
        self._acc = [0, 0]
        self._reply(name)

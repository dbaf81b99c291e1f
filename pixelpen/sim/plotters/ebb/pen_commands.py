"""The EBB's pen and servo commands: SP, TP, S2, SC, SR and SE (the engraver output).

QP reports the commanded state (S2 on RP4 counts as up only at exactly SC,4, as in ebb.c); SP,2/SP,3
(fw >= 3.0.1) raise the pen at once, SP,3 also making SC,5 equal to SC,4.
"""

from __future__ import annotations

from typing import Any

from pixelpen.sim.plotters.ebb.machine import MotionCommand
from pixelpen.sim.plotters.ebb.parser import EbbParser

__all__ = ["PenCommands"]

PEN_SERVO_PIN = 4
"""RP4 = RB1, the pen-lift servo output S2 drives."""


class PenCommands(EbbParser):
    """Handlers of the pen-lift servo's commands (the servo itself is ``pen.PenServo``)."""

    def _pen_command(self, name: str, up: bool | None, duration_ms: int) -> None:
        def begin(t: float) -> None:
            target, rate = self._pen.command(up)
            self._servo_move(t, target, rate)

        self._queue(name, MotionCommand(name, duration=duration_ms / 1000.0, begin=begin))

    def cmd_SP(self, name: str, v: list[Any]) -> None:
        value, duration, _pin = v
        if value > 3 or (value > 1 and self.version < (3, 0, 1)):
            raise self._invalid()
        if value >= 2:
            if value == 3:
                self._pen.down_position = self._pen.up_position
            self._pen.commanded_up = True
            self._servo_move(self._now, self._pen.up_position, self._pen.rate_up)
            self._reply(name)
            return
        self._pen_command(name, value == 1, duration or 0)

    def cmd_TP(self, name: str, v: list[Any]) -> None:
        (duration,) = v
        self._pen_command(name, None, duration or 0)

    def cmd_S2(self, name: str, v: list[Any]) -> None:
        position, pin, rate, delay = v
        if position == 0:
            self._s2.pop(pin, None)
            self._reply(name)
            return

        def begin(t: float) -> None:
            self._s2[pin] = position
            if pin == PEN_SERVO_PIN:
                self._servo_move(t, position, rate or 0)
                self._pen.commanded_up = position == self._pen.up_position  # ebb.c: up only at exactly SC,4

        self._queue(name, MotionCommand(name, duration=(delay or 0) / 1000.0, begin=begin))

    def cmd_SC(self, name: str, v: list[Any]) -> None:
        param, value = v
        self._pen.configure(param, value)
        self._split_ink(self._now)
        self._reply(name)

    def cmd_SR(self, name: str, v: list[Any]) -> None:
        timeout, state = v
        self._pen.set_power(self._now, timeout, state)
        self._reply(name)

    def cmd_SE(self, name: str, v: list[Any]) -> None:
        state, power, queued = v
        if state > 1:
            raise self._invalid()
        setting = (state, 512 if power is None else power)

        def begin(t: float) -> None:
            self._engraver = setting

        if queued:
            self._queue(name, MotionCommand(name, begin=begin))
        else:
            begin(self._now)
            self._reply(name)

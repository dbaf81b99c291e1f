"""The EBB's configuration, reset and I/O commands: CU, R, RB, BL, PD, PO, PI, I, O, C, MR, MW, AC, A, CK.

CU,10 switches the reply syntax (its own non-standard answers, ebb.html); CU,4 resizes the FIFO once it
has drained; R resets to the power-on state (servo power off), RB reboots without a reply, BL enters the
bootloader (the board falls silent until a reset).  The pin commands act on ``ports.Ports``.
"""

from __future__ import annotations

from typing import Any

from pixelpen.sim.plotters.ebb.machine import MAX_FIFO, RA0_READING, MotionCommand
from pixelpen.sim.plotters.ebb.parser import EbbParser, log
from pixelpen.sim.plotters.ebb.ports import PORT_NAMES

__all__ = ["ConfigCommands"]

ANALOG_CHANNELS = 16
"""AC: channels 0..15."""
UNCONNECTED_READING = 23
"""What A reports for an enabled analog channel with nothing on it."""


class ConfigCommands(EbbParser):
    """Handlers of the board's configuration (CU), resets, port pins, RAM, analog inputs and CK."""

    def cmd_CU(self, name: str, v: list[Any]) -> None:
        param, value = v
        fw3 = self._fw3
        if param == 10 and fw3:
            was_future = self._future
            self._future = bool(value)
            if not was_future and self._future:
                self._emit(b"\n")
            elif was_future and not self._future:
                self._emit(b"CUOK\r\n")
            else:
                self._reply(name)
            return
        if param == 1:
            self._ack = bool(value)
        elif param == 2:
            self._limit_check = bool(value)
        elif param == 4 and fw3:
            if value < 1:
                raise self._invalid()
            self._set_fifo_size(name, min(value, MAX_FIFO))
            return
        elif param == 50 and fw3:
            self._auto_enable = bool(value)
        elif param in (51, 52, 53) and fw3:
            if not 0 <= value <= 255:
                raise self._invalid()
            if param == 51:
                self._limit_mask = value
            elif param == 52:
                self._limit_target = value
            else:
                self._limit_replies = value
        elif param == 54 and fw3:
            self._checksums = bool(value)
        elif param == 60 and fw3:
            if not 0 <= value <= 1023:
                raise self._invalid()
            self._power_threshold = value
        elif param == 61 and fw3:
            if not 0 <= value <= 65534:
                raise self._invalid()
            self._stepper_timeout = value
        self._reply(name)

    def _set_fifo_size(self, name: str, size: int) -> None:
        """CU,4 enters the queue like a move: it resizes the FIFO once the commands before it have run."""
        def begin(t: float) -> None:
            self._fifo_size = size

        self._queue(name, MotionCommand(name, begin=begin))

    def cmd_R(self, name: str, v: list[Any]) -> None:
        self._reply(name)
        self._stop_motion()
        self._init_state(power_up=False)

    def cmd_RB(self, name: str, v: list[Any]) -> None:
        self._stop_motion()
        self._init_state(power_up=True)

    def cmd_BL(self, name: str, v: list[Any]) -> None:
        self._stop_motion()
        self._dead = True
        log.warning("%s: entered the bootloader: no more replies until a reset", self.model)

    def cmd_PD(self, name: str, v: list[Any]) -> None:
        port, pin, direction = v
        self._ports.set_direction(port, pin, direction)
        self._reply(name)

    def cmd_PO(self, name: str, v: list[Any]) -> None:
        port, pin, value = v
        self._ports.set_latch(port, pin, value)
        self._reply(name)

    def cmd_PI(self, name: str, v: list[Any]) -> None:
        port, pin = v
        value = self._pins_at(self._now).pin(port, pin)
        self._reply(name, str(value), legacy=f"PI,{value}\r\n")

    def cmd_I(self, name: str, v: list[Any]) -> None:
        ports = self._pins_at(self._now)
        data = ",".join(f"{ports.read(p):03d}" for p in PORT_NAMES)
        self._reply(name, data, legacy=f"I,{data}\r\n")

    def cmd_O(self, name: str, v: list[Any]) -> None:
        for port, value in zip(PORT_NAMES, v, strict=True):
            if value is not None:
                self._ports.lat[port] = value
        self._reply(name)

    def cmd_C(self, name: str, v: list[Any]) -> None:
        for port, value in zip(PORT_NAMES, v, strict=True):
            self._ports.tris[port] = value
        self._reply(name)

    def cmd_MR(self, name: str, v: list[Any]) -> None:
        data = f"{self._ram[v[0]]:03d}"
        self._reply(name, data, legacy=f"MR,{data}\r\n")

    def cmd_MW(self, name: str, v: list[Any]) -> None:
        address, value = v
        self._ram[address] = value
        self._reply(name)

    def cmd_AC(self, name: str, v: list[Any]) -> None:
        channel, enable = v
        if channel >= ANALOG_CHANNELS:
            raise self._invalid()
        (self._analog.add if enable else self._analog.discard)(channel)
        self._reply(name)

    def cmd_A(self, name: str, v: list[Any]) -> None:
        readings = {0: RA0_READING, 11: self._vplus_reading()}
        data = ",".join(f"{ch:02d}:{readings.get(ch, UNCONNECTED_READING):04d}" for ch in sorted(self._analog))
        self._reply(name, data, legacy=f"A,{data}\r\n")

    def cmd_CK(self, name: str, v: list[Any]) -> None:
        lines = [f"Param{k + 1}={value}" for k, value in enumerate(v)]
        if self._future:
            self._emit(("CK\n" + "".join(line + "\n" for line in lines)).encode())
        else:
            self._emit(("\r\n" + "".join(line + "\r\n" for line in lines) + self._ending("ok")).encode())

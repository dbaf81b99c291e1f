"""The EBB's queries and stored values: V, QG, QB, QM, QP, QS, QE, QC, QR, QU, QL/SL, QN/SN/NI/ND, QT/ST.

Reply shapes (legacy syntax) as ebb.html gives them, including the ones that end in ``\\n\\r``; QG and QB
clear the pause-button and power-lost flags they report.  QC reads RA0 (a fixed 394) and V+ through the
board's 9.2:1 divider on a 3.3 V, 10-bit ADC.
"""

from __future__ import annotations

from typing import Any

from pixelpen.sim.plotters.ebb.machine import MAX_FIFO, RA0_READING
from pixelpen.sim.plotters.ebb.parser import EbbParser

__all__ = ["QueryCommands"]

NICKNAME_MAX = 16
"""ST: the longest nickname the board stores."""


class QueryCommands(EbbParser):
    """Handlers of the commands that report the board's state or store small values."""

    def cmd_V(self, name: str, v: list[Any]) -> None:
        text = f"EBBv13_and_above EB Firmware Version {self.firmware}"
        self._reply(name, text, legacy=text + "\r\n")

    def cmd_QG(self, name: str, v: list[Any]) -> None:
        m1, m2 = self._motors_moving()
        bits = 0
        if self._fw3:  # bit 7: limit switch (no switch is fitted), bit 6: power lost
            bits |= 0x40 if self._power_lost_flag else 0
        else:  # 2.x parse_QG_packet: bit 7 reads RB5, bit 6 RB2 (inputs with pull-ups unless PD/PO change them)
            ports = self._pins_at(self._now)
            bits |= ports.pin("B", 5) << 7 | ports.pin("B", 2) << 6
        bits |= 0x20 if self._button else 0
        bits |= 0x10 if self._pen.commanded_up else 0
        bits |= 0x08 if self._exec is not None else 0
        bits |= 0x04 if m1 else 0
        bits |= 0x02 if m2 else 0
        bits |= 0x01 if (self._exec is not None and self._fifo) else 0
        self._button = False
        self._power_lost_flag = False
        self._reply(name, f"{bits:02X}", legacy=f"{bits:02X}\r\n")

    def cmd_QB(self, name: str, v: list[Any]) -> None:
        pressed = int(self._button)
        self._button = False
        self._reply(name, str(pressed), kind="ok", legacy=f"{pressed}\r\n" + self._ending("ok"))

    def cmd_QM(self, name: str, v: list[Any]) -> None:
        m1, m2 = self._motors_moving()
        data = f"{int(self._exec is not None)},{int(m1)},{int(m2)},{int(bool(self._fifo))}"
        self._reply(name, data, legacy=f"QM,{data}\n\r")

    def cmd_QP(self, name: str, v: list[Any]) -> None:
        state = int(self._pen.commanded_up)
        self._reply(name, str(state), legacy=f"{state}\n\r" + self._ending("ok"))

    def cmd_QS(self, name: str, v: list[Any]) -> None:
        s1, s2 = self._steps_now(self._now)
        self._reply(name, f"{s1},{s2}", legacy=f"{s1},{s2}\n\r" + self._ending("ok"))

    def cmd_QE(self, name: str, v: list[Any]) -> None:
        en = self._motors_enabled(self._now)
        ms = self._ports.microsteps()
        data = f"{ms if en[0] else 0},{ms if en[1] else 0}"
        self._reply(name, data, legacy=data + "\r\n" + self._ending("ok"))

    def cmd_QC(self, name: str, v: list[Any]) -> None:
        data = f"{RA0_READING:04d},{self._vplus_reading():04d}"
        self._reply(name, data, legacy=data + "\r\n" + self._ending("ok"))

    def cmd_QR(self, name: str, v: list[Any]) -> None:
        powered = int(self._pen.powered(self._now))
        self._reply(name, str(powered), legacy=f"{powered}\n\r" + self._ending("ok"))

    def cmd_QU(self, name: str, v: list[Any]) -> None:
        (param,) = v
        values = {1: "00", 2: str(MAX_FIFO), 3: str(self._fifo_size), 4: "E40", 5: "E40",
                  6: f"{len(self._fifo):02d}", 60: str(self._power_threshold), 61: str(self._stepper_timeout),
                  200: f"{self._acc[0]},{self._acc[1]}"}
        if param not in values:
            raise self._invalid()
        data = values[param]
        self._reply(name, data, legacy=f"QU,{data}\r\n" + self._ending("ok"))

    def cmd_QL(self, name: str, v: list[Any]) -> None:
        (index,) = v
        value = self._vars[index or 0]
        self._reply(name, str(value), legacy=f"{value}\r\n" + self._ending("ok"))

    def cmd_SL(self, name: str, v: list[Any]) -> None:
        value, index = v
        self._vars[index or 0] = value
        self._reply(name)

    def cmd_QN(self, name: str, v: list[Any]) -> None:
        self._reply(name, str(self._node), legacy=f"{self._node}\r\n" + self._ending("ok"))

    def cmd_SN(self, name: str, v: list[Any]) -> None:
        self._node = v[0]
        self._reply(name)

    def cmd_NI(self, name: str, v: list[Any]) -> None:
        self._node = (self._node + 1) & 0xFFFFFFFF
        self._reply(name)

    def cmd_ND(self, name: str, v: list[Any]) -> None:
        self._node = (self._node - 1) & 0xFFFFFFFF
        self._reply(name)

    def cmd_QT(self, name: str, v: list[Any]) -> None:
        self._reply(name, self.nickname, legacy=self.nickname + "\r\n" + self._ending("ok"))

    def cmd_ST(self, name: str, v: list[Any]) -> None:
        (text,) = v
        if len(text or "") > NICKNAME_MAX:
            raise self._invalid()
        self.nickname = text or ""
        self._reply(name)

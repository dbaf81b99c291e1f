"""What GRBL prints about itself: the welcome and help lines, the ``?`` status report, ``$G`` and ``$#``.

The status report follows interface.md's refresh rules (``WCO:`` every 10 or 30 reports, ``Ov:`` every
10 or 20, both at once after a change) and ``$10``'s mask; ``$13`` reports in inches.
"""

from __future__ import annotations

from abc import abstractmethod

import numpy as np

from pixelpen.sim.plotters.grbl.machine import GrblMachine
from pixelpen.sim.plotters.grbl.modal import MM_PER_INCH, PROBES, fmt_float

__all__ = ["BUILD", "HELP", "VERSION", "WELCOME", "Reports"]

VERSION = "1.1h"
BUILD = "20190830"
WELCOME = b"\r\nGrbl " + VERSION.encode() + b" ['$' for help]\r\n"
HELP = b"[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]\r\n"


class Reports(GrblMachine):
    """The reports GRBL prints from its state (status, modes, parameters)."""

    @property
    @abstractmethod
    def rx_free(self) -> int:
        """Free bytes in the RX buffer (what ``Bf:`` reports second)."""

    def _coord(self, values: np.ndarray) -> str:
        inches = self._flag(13)
        vals = values / MM_PER_INCH if inches else values
        return ",".join(fmt_float(float(v), 4 if inches else 3) for v in vals)

    def _status_report(self) -> str:
        busy = self._state_kind() in ("run", "hold", "jog", "home")
        mpos = self._current_mpos()
        wco = self.gc.wco()
        mask = int(self.settings[10])
        parts = [self._state_name()]
        parts.append(("MPos:" + self._coord(mpos)) if mask & 1 else ("WPos:" + self._coord(mpos - wco)))
        if mask & 2:
            parts.append(f"Bf:{self.planner.available},{self.rx_free}")
        rate = self.planner.speed(self._now) * 60.0
        rate_text = fmt_float(rate / MM_PER_INCH, 1) if self._flag(13) else fmt_float(rate, 0)
        parts.append(f"FS:{rate_text},{fmt_float(self._spindle_rpm(), 0)}")
        if self._wco_counter > 0:
            self._wco_counter -= 1
        else:
            self._wco_counter = 29 if busy else 9
            if self._ovr_counter == 0:
                self._ovr_counter = 1
            parts.append("WCO:" + self._coord(wco))
        if self._ovr_counter > 0:
            self._ovr_counter -= 1
        else:
            self._ovr_counter = 19 if busy else 9
            parts.append(f"Ov:{int(self.feed_ovr)},{int(self.rapid_ovr)},{int(self.spindle_ovr)}")
            acc = ""
            if self._spindle_state != 5 and not self._door_off():
                acc += "S" if self._spindle_state == 3 else "C"
            if self._flood:
                acc += "F"
            if acc:
                parts.append("A:" + acc)
        return "<" + "|".join(parts) + ">\r\n"

    def _gcode_modes(self) -> bytes:
        g = self.gc
        motion = f"38.{g.motion - 380}" if g.motion in PROBES else str(g.motion)
        words = [f"G{motion}", f"G{54 + g.coord_select}", f"G{17 + g.plane}", "G20" if g.inches else "G21",
                 "G91" if g.incremental else "G90", "G93" if g.inverse_time else "G94", f"M{g.spindle}",
                 "M8" if g.flood else "M9", f"T{g.tool}"]
        feed = g.feed_rate / MM_PER_INCH if self._flag(13) else g.feed_rate
        words.append("F" + fmt_float(feed, 1 if self._flag(13) else 0))
        words.append("S" + fmt_float(g.spindle_speed, 0))
        return ("[GC:" + " ".join(words) + "]\r\n").encode()

    def _parameters_report(self) -> bytes:
        p = self.persistent
        lines = [f"[G{54 + k}:{self._coord(p.coords[k])}]" for k in range(6)]
        lines += [f"[G28:{self._coord(p.g28)}]", f"[G30:{self._coord(p.g30)}]",
                  f"[G92:{self._coord(self.gc.coord_offset)}]"]
        tlo = self.gc.tool_length_offset / (MM_PER_INCH if self._flag(13) else 1.0)
        lines.append(f"[TLO:{fmt_float(tlo, 4 if self._flag(13) else 3)}]")
        lines.append(f"[PRB:{self._coord(np.zeros(3))}:0]")
        return ("\r\n".join(lines) + "\r\n").encode()

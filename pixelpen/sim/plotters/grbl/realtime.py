"""GRBL's real-time commands: single bytes that act the moment they arrive, dispatched by one table.

``REALTIME`` maps each byte to a :class:`RealtimeCommand` — its name in the simulator's log, whether it
also acts during a critical alarm or sleep (only reset and status do), the handler method and its
argument (an override's step or value).  Bytes above 0x7F that are not in the table are discarded with
a warning, as GRBL's serial ISR does.  From gnea/grbl ``doc/markdown/commands.md`` and ``config.h``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from pixelpen.sim.plotters.grbl.machine import log
from pixelpen.sim.plotters.grbl.reports import Reports

__all__ = ["ASCII_REALTIME", "REALTIME", "RT_DOOR", "RT_HOLD", "RT_JOG_CANCEL", "RT_RESET", "RT_RESUME",
           "RT_STATUS", "RealtimeCommand", "RealtimeCommands"]

RT_RESET, RT_STATUS, RT_RESUME, RT_HOLD = 0x18, ord("?"), ord("~"), ord("!")
RT_DOOR, RT_JOG_CANCEL = 0x84, 0x85
OVERRIDE_RANGE = (10.0, 200.0)
"""Feed and spindle overrides stay within 10 % .. 200 % (MIN/MAX_FEED_RATE_OVERRIDE in config.h)."""


class RealtimeCommands(Reports):
    """The handlers of the real-time bytes; ``_realtime`` dispatches a byte through ``REALTIME``."""

    def _realtime(self, b: int) -> None:
        """Act on one real-time byte at once (the main loop has parsed what came before it)."""
        command = REALTIME.get(b)
        if b != RT_STATUS:
            self.log.append((self._now, command.label if command and command.label else f"0x{b:02X}"))
        if (command is None or not command.always) and (self._critical or self._sleep):
            return
        if command is None:
            log.warning("grbl: extended byte 0x%02x is not a real-time command: discarded", b)
            return
        command.handler(self, command.argument)

    def _rt_reset(self, _: float | None) -> None:
        """0x18: soft reset."""
        self._soft_reset()

    def _rt_status(self, _: float | None) -> None:
        """``?``: a status report (none in a critical alarm or while homing)."""
        if not self._critical and self._homing_until is None:
            self._emit(self._status_report().encode())

    def _rt_hold(self, _: float | None) -> None:
        """``!``: feed hold."""
        self._feed_hold("hold")

    def _rt_resume(self, _: float | None) -> None:
        """``~``: cycle start / resume."""
        self._cycle_resume()

    def _rt_door(self, _: float | None) -> None:
        """0x84: safety door (a hold that also switches the spindle off)."""
        self._feed_hold("door")

    def _rt_jog_cancel(self, _: float | None) -> None:
        """0x85: cancel a running jog (ignored otherwise)."""
        if self._jogging and self._hold is None:
            self._feed_hold("jog-cancel")

    def _rt_feed_override(self, step: float | None) -> None:
        """0x90-0x94: feed override back to 100 % (``None``) or by ``step`` percent."""
        self.feed_ovr = 100.0 if step is None else _clamp_override(self.feed_ovr + step)
        self._overrides_changed()

    def _rt_rapid_override(self, value: float | None) -> None:
        """0x95-0x97: rapid override to 100, 50 or 25 %."""
        self.rapid_ovr = 100.0 if value is None else value
        self._overrides_changed()

    def _rt_spindle_override(self, step: float | None) -> None:
        """0x99-0x9D: spindle override back to 100 % (``None``) or by ``step`` percent; the pen follows."""
        self.spindle_ovr = 100.0 if step is None else _clamp_override(self.spindle_ovr + step)
        self._split_ink()
        self._pen_update()
        self._overrides_changed()

    def _overrides_changed(self) -> None:
        """The next status report shows ``Ov:``; the planner re-plans its speeds."""
        self._ovr_counter = 0
        self.planner.refresh_speeds(self._now)

    def _rt_spindle_stop(self, _: float | None) -> None:
        """0x9E: toggle the spindle stop override, only while a hold has stopped the machine."""
        if self._hold is not None and self.planner.stopped():
            self._split_ink()
            self._spindle_stop_ovr = not self._spindle_stop_ovr
            self._pen_update()

    def _rt_flood(self, _: float | None) -> None:
        """0xA0: toggle flood coolant."""
        self._flood = not self._flood
        self.gc.flood = self._flood


def _clamp_override(value: float) -> float:
    return min(max(value, OVERRIDE_RANGE[0]), OVERRIDE_RANGE[1])


@dataclass(frozen=True)
class RealtimeCommand:
    """One real-time byte: its handler and argument, its log label ("": the byte in hex), and if it always acts."""

    handler: Callable[[RealtimeCommands, float | None], None]
    argument: float | None = None
    label: str = ""
    always: bool = False
    """True: acts during a critical alarm and in sleep too (reset and status)."""


_C = RealtimeCommand
_R = RealtimeCommands
REALTIME: dict[int, RealtimeCommand] = {
    RT_RESET: _C(_R._rt_reset, label="^X", always=True),
    RT_STATUS: _C(_R._rt_status, label="?", always=True),
    RT_HOLD: _C(_R._rt_hold, label="!"),
    RT_RESUME: _C(_R._rt_resume, label="~"),
    RT_DOOR: _C(_R._rt_door),
    RT_JOG_CANCEL: _C(_R._rt_jog_cancel),
    0x90: _C(_R._rt_feed_override, None),
    0x91: _C(_R._rt_feed_override, +10.0),
    0x92: _C(_R._rt_feed_override, -10.0),
    0x93: _C(_R._rt_feed_override, +1.0),
    0x94: _C(_R._rt_feed_override, -1.0),
    0x95: _C(_R._rt_rapid_override, 100.0),
    0x96: _C(_R._rt_rapid_override, 50.0),
    0x97: _C(_R._rt_rapid_override, 25.0),
    0x99: _C(_R._rt_spindle_override, None),
    0x9A: _C(_R._rt_spindle_override, +10.0),
    0x9B: _C(_R._rt_spindle_override, -10.0),
    0x9C: _C(_R._rt_spindle_override, +1.0),
    0x9D: _C(_R._rt_spindle_override, -1.0),
    0x9E: _C(_R._rt_spindle_stop),
    0xA0: _C(_R._rt_flood),
}
"""Real-time byte -> its command (GRBL 1.1's CMD_* codes)."""

ASCII_REALTIME = frozenset(b for b in REALTIME if b < 0x80)
"""The printable real-time bytes (``?``, ``!``, ``~``) and 0x18; every byte above 0x7F is real-time too."""

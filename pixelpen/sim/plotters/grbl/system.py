"""GRBL's ``$`` system commands, dispatched by one table, and the ``$n=value`` settings they store.

``SYSTEM_COMMANDS`` maps the letter after ``$`` to a :class:`SystemCommand`: the machine states it runs
in (error:8 otherwise), a setting that must be on (error:5: ``$H`` needs homing, ``$22``), the syntax of
what follows the letter (a regular expression; error:3 otherwise) and the handler method.  The checks
run in that order, as ``system_execute_line`` in gnea/grbl's ``system.c`` makes them; a ``$`` line that
names no command is a setting (``$100=80``).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

from pixelpen.sim.plotters.grbl.execute import BlockExecution, Task
from pixelpen.sim.plotters.grbl.machine import SYNC
from pixelpen.sim.plotters.grbl.modal import STATUS, Persistent, read_float
from pixelpen.sim.plotters.grbl.reports import BUILD, HELP, VERSION, Reports
from pixelpen.sim.plotters.grbl.settings import checked_setting, default_settings, settings_report

__all__ = ["SYSTEM_COMMANDS", "SystemCommand", "SystemCommands"]

IDLE_OR_ALARM = frozenset({"idle", "alarm"})


class SystemCommands(BlockExecution, Reports):
    """The handlers of the ``$`` commands; ``_system_command`` dispatches a line through ``SYSTEM_COMMANDS``."""

    rx_size: int
    build_info: str
    startup_lines: list[str]

    def _system_command(self, line: str) -> Task:
        """system_execute_line: check the command's states, setting and syntax, then run its handler."""
        if len(line) == 1:
            self._emit(HELP)
            return 0
        command = SYSTEM_COMMANDS.get(line[1], SETTING)
        if command.states is not None and self._state_kind() not in command.states:
            return STATUS["not_idle"]
        if command.needs is not None and not self._flag(command.needs):
            return STATUS["setting_disabled"]
        if not command.syntax.fullmatch(line[2:]):
            return STATUS["invalid_statement"]
        result = command.handler(self, line)
        if isinstance(result, int):
            return result
        return (yield from result)

    def _sys_jog(self, line: str) -> Task:
        """``$J=line``: a jog block."""
        return (yield from self._gcode(line, jog=True))

    def _sys_settings(self, line: str) -> int:
        """``$$``: list the settings (not while moving)."""
        if self._state_kind() in ("run", "hold"):
            return STATUS["not_idle"]
        self._emit(settings_report(self.settings))
        return 0

    def _sys_modes(self, line: str) -> int:
        """``$G``: the parser's modal state."""
        self._emit(self._gcode_modes())
        return 0

    def _sys_check_mode(self, line: str) -> int:
        """``$C``: toggle check mode (leaving it soft-resets; -1: answered already)."""
        if self._check:
            self._emit(b"[MSG:Disabled]\r\nok\r\n")
            self._boot(power_up=False)
            return -1
        if self._state_kind() != "idle":
            return STATUS["not_idle"]
        self._check = True
        self._emit(b"[MSG:Enabled]\r\n")
        return 0

    def _sys_unlock(self, line: str) -> int:
        """``$X``: leave the alarm state."""
        if self._alarm:
            self._emit(b"[MSG:Caution: Unlocked]\r\n")
            self._alarm = False
        return 0

    def _sys_parameters(self, line: str) -> int:
        """``$#``: coordinate systems, G28/G30, G92, tool length offset, probe."""
        self._emit(self._parameters_report())
        return 0

    def _sys_home(self, line: str) -> Task:
        """``$H``: the homing cycle."""
        self._start_homing()
        yield SYNC
        return 0

    def _sys_sleep(self, line: str) -> int:
        """``$SLP``: spindle off, sleep until a reset (-1: answered already)."""
        self._emit(b"ok\r\n")
        self._spindle_state = 5
        self._pen_update()
        self._sleep = True
        self._emit(b"[MSG:Sleeping]\r\n")
        return -1

    def _sys_build_info(self, line: str) -> int:
        """``$I``: version and options; ``$I=text`` stores the build info text."""
        if len(line) == 2:
            self._emit(f"[VER:{VERSION}.{BUILD}:{self.build_info}]\r\n".encode())
            self._emit(f"[OPT:VZ,{self.planner.capacity},{self.rx_size}]\r\n".encode())
        else:
            self.build_info = line[3:]
        return 0

    def _sys_restore(self, line: str) -> int:
        """``$RST=$`` settings, ``$RST=#`` parameters, ``$RST=*`` everything: restored, then a soft reset."""
        what = line[5]
        if what in "$*":
            self.settings = default_settings((self.paper.width_mm, self.paper.height_mm))
        if what in "#*":
            self.persistent = Persistent()
        if what == "*":
            self.startup_lines = ["", ""]
            self.build_info = ""
        self._emit(b"[MSG:Restoring defaults]\r\nok\r\n")
        self._boot(power_up=False)
        return -1

    def _sys_startup_lines(self, line: str) -> Task:
        """``$N``: list the startup lines; ``$Nx=line`` checks the line as G-code and stores it (idle only)."""
        if len(line) == 2:
            for k, text in enumerate(self.startup_lines):
                self._emit(f"$N{k}={text}\r\n".encode())
            return 0
        if self._state_kind() != "idle":
            return STATUS["not_idle"]
        got = read_float(line, 2)
        if got is None:
            return STATUS["bad_number"]
        param, i = got
        if i >= len(line) or line[i] != "=":
            return STATUS["invalid_statement"]
        text = line[i + 1:]
        code = (yield from self._gcode(text)) if text else 0
        if code:
            return code
        index = int(param)
        if 0 <= index < len(self.startup_lines):
            self.startup_lines[index] = text
        return 0

    def _sys_setting(self, line: str) -> int:
        """``$n=value``: store a setting."""
        got = read_float(line, 1)
        if got is None:
            return STATUS["bad_number"]
        param, i = got
        if i >= len(line) or line[i] != "=":
            return STATUS["invalid_statement"]
        got = read_float(line, i + 1)
        if got is None:
            return STATUS["bad_number"]
        value, j = got
        if j != len(line) or param > 255:
            return STATUS["invalid_statement"]
        return self._store_setting(int(param), value)

    def _store_setting(self, n: int, value: float) -> int:
        """settings_store_global_setting: check, store, and apply what the setting changes at once."""
        code, value = checked_setting(self.settings, n, value)
        if code:
            return code
        self.settings[n] = value
        if n == 22 and not value:
            self.settings[20] = 0.0
        if n == 13:
            self._wco_counter = 0
        self.planner.refresh_speeds(self._now)
        return 0


@dataclass(frozen=True)
class SystemCommand:
    """One ``$`` command: its handler, the syntax after its letter, the states it runs in, a setting it needs on."""

    handler: Callable[[SystemCommands, str], Task | int]
    syntax: re.Pattern[str]
    """What may follow the command letter (``fullmatch``; error:3 otherwise)."""
    states: frozenset[str] | None = None
    """The machine states (``_state_kind``) the command runs in; None: any (the handler may check itself)."""
    needs: int | None = None
    """A ``$`` setting that must be on (error:5 otherwise)."""


def _command(
    handler: Callable[[SystemCommands, str], Task | int], syntax: str = "", states: frozenset[str] | None = None,
    needs: int | None = None,
) -> SystemCommand:
    return SystemCommand(handler, re.compile(syntax, re.DOTALL), states, needs)


_S = SystemCommands
SYSTEM_COMMANDS: dict[str, SystemCommand] = {
    "J": _command(_S._sys_jog, "=.*", frozenset({"idle", "jog"})),
    "$": _command(_S._sys_settings),
    "G": _command(_S._sys_modes),
    "C": _command(_S._sys_check_mode),
    "X": _command(_S._sys_unlock),
    "#": _command(_S._sys_parameters, states=IDLE_OR_ALARM),
    "H": _command(_S._sys_home, states=IDLE_OR_ALARM, needs=22),
    "S": _command(_S._sys_sleep, "LP", IDLE_OR_ALARM),
    "I": _command(_S._sys_build_info, "(=.*)?", IDLE_OR_ALARM),
    "R": _command(_S._sys_restore, "ST=[$#*]", IDLE_OR_ALARM),
    "N": _command(_S._sys_startup_lines, ".*", IDLE_OR_ALARM),
}
"""The letter after ``$`` -> its command (``$`` alone prints the help line)."""

SETTING = _command(_S._sys_setting, ".*", IDLE_OR_ALARM)
"""Any other ``$`` line: ``$n=value`` (a malformed one is error:2 or error:3)."""

"""GRBL 1.1h pen-plotter simulator: serial RX buffer, line protocol, real-time bytes, planner timing, paper.

Written from gnea/grbl's documentation (``doc/markdown/interface.md``, ``commands.md``,
``settings.md``, ``doc/csv/error_codes_en_US.csv``, ``alarm_codes_en_US.csv``) and the plotter notes in
``plotters.md`` §3.  Model "grbl"; URL options:

=====================  ==========================================================================
``size=WxH``           travel in mm: sets $130/$131 and the paper
``pen=servo``          pen on a servo spindle: down while M3/M4 is on with an output S >= ``pen_threshold``
``pen=servo-inverted`` servo mounted the other way: down while M3/M4 outputs less than ``pen_threshold``
                       (plotters.md: "S50 down / S500 up").  In both servo modes M5 (no pulses) is up
``pen=z``              pen on the Z axis: down wherever the work Z is <= 0, once a move has driven Z
                       (GRBL boots assuming Z = 0, but the pen of a parked plotter is up: until the
                       first Z motion after power-up or a reboot it stays up, so nothing inks at home)
``pen_threshold=N``    servo output dividing up from down
``rx_buffer=N``        serial RX ring buffer in bytes, default 128 (GRBL's RX_BUFFER_SIZE)
``planner=N``          BLOCK_BUFFER_SIZE, default 16 (15 usable blocks, as ``Bf:15,128`` shows)
``pen_colour=C``       ink colour for the rendered paper (name or #rrggbb), default black
``pen_width=MM``       line width for the rendered paper
=====================  ==========================================================================

Defaults are the machine of the built-in ``grbl`` profile, the one the GRBL driver plots for
(:func:`machine_defaults`): 297x210 mm (its A4 paper), ``servo-inverted`` with threshold 275 (its
``M3 S500`` up / ``M3 S50`` down), RX buffer 128, 115200 baud for a pty or replay.  A bare
``GrblSimulator()`` keeps the firmware-neutral 300x200 mm, ``servo``, threshold 500 (half of $30=1000).
An Arduino reboots when a host opens its port (DTR auto-reset): the pty bridge reboots the
simulator then, so the program sees the banner (``resets_on_dtr``).

The firmware modelled is a default 1.1h build with HOMING_FORCE_SET_ORIGIN (``[OPT:VZ,15,128]``):
$23=3 homes X and Y to their minimum, so machine space is X∈[0,$130], Y∈[0,$131] (y up on the paper)
and Z∈[−$132,0].  Timing is continuous (no step quantisation); a status report is produced at once.
Simplifications, each as the documentation allows: a hold is resumed only by ``~`` (an arriving line
never resumes it); a soft-reset after a critical alarm discards the offending line without an ``ok``;
homing takes straight seek moves at $25 plus two locate passes of the pull-off at $24.
The package docstring maps the other modules.
"""

from __future__ import annotations

import re
from collections import deque
from collections.abc import Generator
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pixelpen.clock import Clock
from pixelpen.errors import ConfigError, URLError
from pixelpen.options import OptionSpec, choice, colour, integer, non_negative, read_options
from pixelpen.sim.base import Fault, register_simulator
from pixelpen.sim.plotters.grbl.machine import PEN_MODES, RESUMED, ROOM, SYNC, Wait, log
from pixelpen.sim.plotters.grbl.modal import STATUS, fmt_float
from pixelpen.sim.plotters.grbl.realtime import ASCII_REALTIME, RT_HOLD, RealtimeCommands
from pixelpen.sim.plotters.grbl.reports import WELCOME
from pixelpen.sim.plotters.grbl.settings import DEFAULT_SETTINGS
from pixelpen.sim.plotters.grbl.system import SystemCommands
from pixelpen.urls import parse_size

if TYPE_CHECKING:
    from pixelpen.raster.canvas import Canvas

__all__ = ["DEFAULT_SETTINGS", "OPTIONS", "WELCOME", "GrblSimulator", "create", "fmt_float", "machine_defaults"]

PROFILE = "grbl"
"""The built-in profile whose machine ``sim:grbl`` simulates by default (pixelpen/data/profiles/grbl.toml)."""
LINE_BUFFER_SIZE = 80  # protocol.h: 79 characters fit, the 80th overflows (error:11)
LineTask = Generator[Wait, None, None]


class GrblSimulator(SystemCommands, RealtimeCommands):
    """A GRBL 1.1h controller driving a pen plotter, seen from its serial port (a StreamDevice)."""

    model = "grbl"
    FAULTS = frozenset({Fault.RESET, Fault.POWER_LOSS, Fault.PAUSE_BUTTON})
    default_baud = 115200
    """GRBL 1.1's BAUD_RATE (the line speed a pty or replay uses unless told otherwise)."""
    resets_on_dtr = True
    """An Arduino reboots when the host opens its port (DTR through the auto-reset capacitor): a banner."""

    def __init__(
        self,
        clock: Clock | None = None,
        *,
        size: tuple[float, float] = (300.0, 200.0),
        pen: str = "servo",
        pen_threshold: float = 500.0,
        rx_buffer: int = 128,
        planner: int = 16,
        pen_colour: str = "black",
        pen_width: float = 0.3,
    ) -> None:
        if pen not in PEN_MODES:
            raise ConfigError(f"grbl: pen must be servo, servo-inverted or z, got {pen!r}")
        if not (16 <= rx_buffer <= 65536):
            raise ConfigError(f"grbl: rx_buffer must be 16..65536 bytes, got {rx_buffer}")
        if not (2 <= planner <= 256):
            raise ConfigError(f"grbl: planner must be 2..256 blocks, got {planner}")
        super().__init__(clock, size=size, pen=pen, pen_threshold=pen_threshold, planner=planner,
                         pen_colour=pen_colour, pen_width=pen_width)
        self.rx_size = int(rx_buffer)
        self.startup_lines = ["", ""]
        self.build_info = ""
        self.overflowed = 0
        self._boot(power_up=True)

    # ---- SimulatedDevice -------------------------------------------------------------------------
    def _receive(self, data: bytes) -> None:
        """Host bytes: real-time bytes act at once, the rest enter the RX ring buffer (dropped when full)."""
        self._catch_up()
        for b in data:
            self.stats.bytes_received += 1
            if b in ASCII_REALTIME or b > 0x7F:
                self._service()  # the main loop has parsed what came before this byte
                self._realtime(b)
            elif len(self._rx) >= self.rx_size:
                self.overflowed += 1
                log.warning("grbl: RX buffer full (%d bytes): byte 0x%02x lost", self.rx_size, b)
            else:
                self._rx.append(b)
                if b in (0x0A, 0x0D):
                    self._service()
        self._service()

    def _apply_fault(self, fault: Fault) -> None:
        """Reset / power loss: the board reboots (position lost); pause button: the feed-hold input."""
        self._catch_up()
        if fault is Fault.PAUSE_BUTTON:
            self._realtime(RT_HOLD)
            return
        self.log.append((self._now, f"<{fault.value}>"))
        self._abort_motion()
        self._phys_offset[:2] += self._mpos[:2]
        self._mpos = np.zeros(3)
        self._boot(power_up=True)

    # ---- public extras ---------------------------------------------------------------------------
    @property
    def state(self) -> str:
        """The machine state as a status report names it (Idle, Run, Hold:0, Jog, Alarm, ...)."""
        return self._state_name()

    def machine_position(self) -> np.ndarray:
        """Machine position (mm) at the current clock time."""
        self._catch_up()
        return self._current_mpos()

    def push_carriage_home(self) -> None:
        """The operator pushes the stopped carriage by hand to the machine origin (where ``$H`` would leave it).

        A physical act, not a command: GRBL does not see it, its machine position stays what it was (a power-up
        or ``inject(Fault.RESET)`` there makes it 0 again).  Refused while the machine moves or the pen is down.
        """
        self._catch_up()
        if self._state_kind() not in ("idle", "alarm", "sleep"):
            raise ConfigError(f"grbl: the carriage cannot be pushed while the machine is {self._state_name()}")
        if self.paper.pen_is_down:
            raise ConfigError("grbl: lift the pen before pushing the carriage (it would draw)")
        self._phys_offset[:2] = -self._mpos[:2]

    def paper_image(self, dpi: float = 96.0) -> Canvas:
        """The paper with everything drawn so far, as an RGB Canvas."""
        return self.paper.paper_image(dpi)

    def save_paper(self, path: str | Path, dpi: float = 96.0) -> None:
        """Render the paper to an image file."""
        self.paper.save_paper(path, dpi)

    @property
    def rx_free(self) -> int:
        """Free bytes in the RX buffer (what ``Bf:`` reports second)."""
        return self.rx_size - len(self._rx)

    # ---- boot ------------------------------------------------------------------------------------
    def _boot(self, power_up: bool) -> None:
        """Initialise as main() does after power-up or a reset, and print the welcome message."""
        keep_alarm = not power_up and (self._alarm or self._sleep)
        self._rx = bytearray()
        self._line = bytearray()
        self._line_flags = 0
        self._task: LineTask | None = None
        self._startup_queue: deque[str] = deque()
        self._reset_machine(power_up, keep_alarm)
        self._emit(WELCOME)
        if self._alarm:
            self._emit(b"[MSG:'$H'|'$X' to unlock]\r\n")
        else:
            self._queue_startup_lines()

    def _queue_startup_lines(self) -> None:
        self._startup_queue.extend(line for line in self.startup_lines if line)

    def _drop_task(self) -> None:
        self._task = None
        self._wait = None

    # ---- main loop -------------------------------------------------------------------------------
    def _service(self) -> None:
        """protocol_main_loop: take lines from the RX buffer and run them until one blocks."""
        for _ in range(100_000):
            if self._critical or self._sleep or self._homing_until is not None:
                return
            if self._hold is not None:  # protocol_exec_rt_suspend: no line is parsed during a hold
                return
            if self._task is not None:
                if not self._ready(self._wait):
                    self._auto_start()
                    return
                self._step_task()
                continue
            if self._startup_queue:
                startup = self._startup_queue.popleft()
                self._start_task(self._startup_task(startup))
                continue
            line = self._take_line()
            if line is None:
                self._auto_start()
                if self._idle_since is None and self._ever_moved and not self.planner.blocks:
                    self._idle_since = self._now  # starving: nothing to move and nothing to parse
                return
            self.stats.commands_executed += 1
            self.log.append((self._now, line if not isinstance(line, int) else "<overflow>"))
            self._start_task(self._line_task(line))

    def _take_line(self) -> str | int | None:
        """Move RX bytes into the line buffer (GRBL's pre-parser) until an end of line; None if none yet.

        Returns the cleaned line (upper case, no spaces/comments) or the int 11 for an overflowed line.
        """
        while self._rx:
            c = self._rx.pop(0)
            if c in (0x0A, 0x0D):
                overflow = self._line_flags & 4
                text = self._line.decode("ascii", "replace")
                self._line.clear()
                self._line_flags = 0
                return STATUS["overflow"] if overflow else text
            if self._line_flags:
                if c == ord(")") and self._line_flags & 1:
                    self._line_flags &= ~1
                continue
            if c <= 0x20 or c == ord("/"):
                continue
            if c == ord("("):
                self._line_flags |= 1
            elif c == ord(";"):
                self._line_flags |= 2
            elif len(self._line) >= LINE_BUFFER_SIZE - 1:
                self._line_flags |= 4
            elif ord("a") <= c <= ord("z"):
                self._line.append(c - 32)
            else:
                self._line.append(c)
        return None

    def _start_task(self, task: LineTask) -> None:
        self._task = task
        self._wait = None
        self._step_task()

    def _step_task(self) -> None:
        assert self._task is not None
        try:
            self._wait = next(self._task)
        except StopIteration:
            self._task = None
            self._wait = None

    def _ready(self, wait: Wait | None) -> bool:
        if wait is None:
            return True
        if wait == ROOM:
            return not self.planner.full
        if wait == SYNC:
            return not self.planner.blocks and self.planner.stopped() and self._hold is None
        if wait == RESUMED:
            return self._hold is None
        return self._now >= float(wait)

    def _auto_start(self) -> None:
        """protocol_auto_cycle_start: run queued blocks (never resumes a hold)."""
        if self.planner.blocks and not self.planner.running and self._hold is None and not self.planner.holding:
            self._start_cycle()

    def _reply(self, code: int) -> None:
        self._emit(b"ok\r\n" if code == 0 else f"error:{code}\r\n".encode())
        if code:
            log.warning("grbl: error:%d", code)

    # ---- line tasks ------------------------------------------------------------------------------
    def _line_task(self, line: str | int) -> LineTask:
        """One line from the host: run it (waiting as GRBL's main loop blocks) and answer ok/error."""
        if isinstance(line, int):
            self._reply(line)
            return
        if not line:
            self._reply(0)
            return
        if line[0] == "$":
            code = yield from self._system_command(line)
        elif self._alarm or self._jogging:
            code = STATUS["gcode_lock"]
        else:
            code = yield from self._gcode(line)
        if code >= 0:
            self._reply(code)

    def _startup_task(self, line: str) -> LineTask:
        code = yield from self._gcode(line)
        tail = "ok" if code == 0 else f"error:{code}"
        self._emit(f">{line}:{tail}\r\n".encode())


def _size(text: str) -> tuple[float, float]:
    """WxH travel in mm."""
    w, h, unit = parse_size(text, default_unit="mm")
    if unit != "mm":
        raise ValueError(f"travel size must be in mm (e.g. 300x200), got {text!r}")
    return (w, h)


OPTIONS: tuple[OptionSpec[Any], ...] = (
    OptionSpec("size", _size, None,
               "travel WxH in mm: sets $130/$131 and the paper (default: the grbl profile's paper)"),
    OptionSpec("pen", choice(*PEN_MODES), None,
               "servo, servo-inverted (down below pen_threshold) or z (down at work Z <= 0) (default: the profile's)"),
    OptionSpec("pen_threshold", non_negative, None,
               "servo output dividing pen up from down (default: half-way between the profile's up and down S)"),
    OptionSpec("rx_buffer", integer(16, 65536), None, "serial RX buffer in bytes (default: the profile's, or 128)"),
    OptionSpec("planner", integer(2, 256), 16, "planner blocks (BLOCK_BUFFER_SIZE)"),
    OptionSpec("pen_colour", colour, None, "ink colour of the rendered paper (default: the profile's first pen)"),
    OptionSpec("pen_width", non_negative, None, "line width in mm of the rendered paper (default: the profile's)"),
)
"""The URL options of ``sim:grbl`` (``pixelpen devices`` lists them); unset ones take the grbl profile's machine."""

_S_WORD = re.compile(r"S\s*([0-9]+(?:\.[0-9]*)?)", re.IGNORECASE)


def _servo_output(command: str | None) -> float | None:
    """The spindle output a pen command sets: its S word under M3/M4, 0 for M5 (None: no servo command)."""
    if not command:
        return None
    if re.search(r"M0*5(?![0-9])", command, re.IGNORECASE):
        return 0.0
    match = _S_WORD.search(command)
    return float(match.group(1)) if match else None


def machine_defaults(profile: str = PROFILE) -> dict[str, object]:
    """The simulated machine a GRBL profile describes: travel (its default paper), pen, RX buffer, line speed.

    The pen: the profile's ``[servo]`` up/down commands give the S outputs; the pen is ``servo`` when down
    is the larger, ``servo-inverted`` when it is the smaller, with the threshold half-way between.
    """
    return dict(_machine_defaults(profile))


@lru_cache(maxsize=8)
def _machine_defaults(profile: str) -> tuple[tuple[str, object], ...]:
    from pixelpen.profiles import load_profile

    prof = load_profile(profile)
    paper = prof.paper(None)
    size = ((paper.x_range[1] - paper.x_range[0]) * prof.unit_mm, (paper.y_range[1] - paper.y_range[0]) * prof.unit_mm)
    up = _servo_output(prof.servo.up_command if prof.servo else None)
    down = _servo_output(prof.servo.down_command if prof.servo else None)
    out: dict[str, object] = {"size": size, "pen": "servo", "pen_threshold": 500.0}
    if up is not None and down is not None and up != down:
        out["pen"] = "servo" if down > up else "servo-inverted"
        out["pen_threshold"] = (up + down) / 2.0
    if prof.link is not None:
        out["baud"] = prof.link.baudrate
        if prof.link.buffer_bytes:
            out["rx_buffer"] = prof.link.buffer_bytes
    if prof.pen_colours:
        out["pen_colour"] = prof.pen_colours[min(prof.pen_colours)]
    out["pen_width"] = prof.pen_width_mm
    return tuple(out.items())


def create(clock: Clock | None = None, **options: str) -> GrblSimulator:
    """Simulator factory for ``sim:grbl?...`` URLs: the grbl profile's machine unless options say otherwise."""
    values = read_options(OPTIONS, options, "sim:grbl")
    machine: dict[str, Any] = {"rx_buffer": 128, "pen_colour": "black", **machine_defaults()}
    chosen = {name: machine[name] if value is None else value for name, value in values.items()}
    try:
        device = GrblSimulator(clock, **chosen)
    except ConfigError as exc:
        raise URLError(f"sim:grbl: {exc}") from None
    device.default_baud = int(machine.get("baud", GrblSimulator.default_baud))
    return device


register_simulator("grbl", create, OPTIONS)

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
"""

from __future__ import annotations

import logging
import math
import re
from collections import deque
from collections.abc import Generator, Iterator
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.errors import ConfigError
from pixelpen.sim.base import register_simulator
from pixelpen.sim.plotters.grbl.gcode import (
    MM_PER_INCH,
    MOTION_CCW,
    MOTION_CW,
    MOTION_SEEK,
    PROBES,
    STATUS,
    GBlock,
    GcodeState,
    Persistent,
    arc_points,
    parse_block,
    read_float,
)
from pixelpen.sim.plotters.grbl.planner import AxisLimits, Block, Planner
from pixelpen.sim.plotters.sheet import Paper, WireStats, clamp_path, read_options
from pixelpen.urls import parse_size

if TYPE_CHECKING:
    from pixelpen.raster.canvas import Canvas

__all__ = ["DEFAULT_SETTINGS", "WELCOME", "GrblSimulator"]

log = logging.getLogger(__name__)

PROFILE = "grbl"
"""The built-in profile whose machine ``sim:grbl`` simulates by default (pixelpen/data/profiles/grbl.toml)."""
VERSION = "1.1h"
BUILD = "20190830"
WELCOME = b"\r\nGrbl " + VERSION.encode() + b" ['$' for help]\r\n"
HELP = b"[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]\r\n"
LINE_BUFFER_SIZE = 80  # protocol.h: 79 characters fit, the 80th overflows (error:11)
MAX_STEP_RATE_HZ = 30000.0

# settings: number -> (default, kind) where kind is "int" (uint8) or "float"
DEFAULT_SETTINGS: dict[int, tuple[float, str]] = {
    0: (10, "int"), 1: (25, "int"), 2: (0, "int"), 3: (0, "int"), 4: (0, "int"), 5: (0, "int"),
    6: (0, "int"), 10: (1, "int"), 11: (0.010, "float"), 12: (0.002, "float"), 13: (0, "int"),
    20: (0, "int"), 21: (0, "int"), 22: (0, "int"), 23: (3, "int"), 24: (25.0, "float"),
    25: (500.0, "float"), 26: (250, "int"), 27: (1.0, "float"), 30: (1000.0, "rpm"), 31: (0.0, "rpm"),
    32: (0, "int"),
    100: (80.0, "float"), 101: (80.0, "float"), 102: (80.0, "float"),
    110: (5000.0, "float"), 111: (5000.0, "float"), 112: (1000.0, "float"),
    120: (1000.0, "float"), 121: (1000.0, "float"), 122: (500.0, "float"),
    130: (300.0, "float"), 131: (200.0, "float"), 132: (10.0, "float"),
}
"""$ settings of the simulated plotter: GRBL's generic defaults, with a pen plotter's axis values."""

_BOOL_SETTINGS = {4, 5, 6, 13, 20, 21, 22, 32}
RT_RESET, RT_STATUS, RT_RESUME, RT_HOLD = 0x18, ord("?"), ord("~"), ord("!")
RT_DOOR, RT_JOG_CANCEL = 0x84, 0x85

_ROOM, _SYNC, _RESUMED = "room", "sync", "resumed"
Wait = object  # what a line task yields: _ROOM, _SYNC, _RESUMED or a clock time (float)


def fmt_float(n: float, decimals: int) -> str:
    """GRBL's printFloat: sign, then the value rounded half-up to ``decimals`` places."""
    sign = "-" if n < 0 else ""
    n = abs(n) * (10 ** decimals) + 0.5
    digits = str(int(n))
    if decimals:
        digits = digits.rjust(decimals + 1, "0")
        return f"{sign}{digits[:-decimals]}.{digits[-decimals:]}"
    return sign + digits


@dataclass
class _MovePayload:
    """What a planner block carries for the simulator: the spindle it runs with and the work Z offset."""

    spindle: int
    speed: float
    wco_z: float
    rapid: bool


class GrblSimulator:
    """A GRBL 1.1h controller driving a pen plotter, seen from its serial port (WireDevice)."""

    model = "grbl"
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
        if pen not in ("servo", "servo-inverted", "z"):
            raise ConfigError(f"grbl: pen must be servo, servo-inverted or z, got {pen!r}")
        if not (16 <= rx_buffer <= 65536):
            raise ConfigError(f"grbl: rx_buffer must be 16..65536 bytes, got {rx_buffer}")
        if not (2 <= planner <= 256):
            raise ConfigError(f"grbl: planner must be 2..256 blocks, got {planner}")
        self.clock = clock if clock is not None else REAL_CLOCK
        self.pen_mode = pen
        self.pen_threshold = float(pen_threshold)
        self.rx_size = int(rx_buffer)
        self.settings: dict[int, float] = {k: float(v) for k, (v, _) in DEFAULT_SETTINGS.items()}
        self.settings[130], self.settings[131] = float(size[0]), float(size[1])
        self.persistent = Persistent()
        self.startup_lines = ["", ""]
        self.build_info = ""
        self.paper = Paper(size[0], size[1], y_down=False, pen_colours={1: pen_colour}, pen_width_mm=pen_width)
        self.stats = WireStats()
        self.log: list[tuple[float, str]] = []
        self.overflowed = 0
        self.planner = Planner(planner - 1, self._limits, lambda: (self.feed_ovr, self.rapid_ovr))
        self._now = self.clock.now()
        self._out = bytearray()
        self._phys_offset = np.zeros(3)
        self._mpos = np.zeros(3)
        self._closed = False
        self._ever_moved = False
        self._alarm = self._sleep = False
        self._boot(power_up=True)

    # ---- WireDevice ------------------------------------------------------------------------------
    @property
    def ready_to_receive(self) -> bool:
        """GRBL drives no handshake line (the Arduino's USB serial has none): always True."""
        return True

    def receive(self, data: bytes) -> None:
        """Host bytes: real-time bytes act at once, the rest enter the RX ring buffer (dropped when full)."""
        if self._closed:
            return
        self._catch_up()
        for b in bytes(data):
            self.stats.bytes_received += 1
            if b in (RT_RESET, RT_STATUS, RT_RESUME, RT_HOLD) or b > 0x7F:
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

    def take_output(self) -> bytes:
        """Bytes GRBL sent since the last call."""
        out = bytes(self._out)
        self._out.clear()
        return out

    def advance_to(self, t: float) -> None:
        """Run the controller (line parsing, motion, dwells) up to clock time ``t``."""
        if self._closed:
            return
        guard = 0
        while True:
            self._service()
            te = self._next_internal_event()
            if te is None or te > t:
                break
            self._set_time(max(te, self._now))
            self._handle_events()
            guard += 1
            if guard > 10_000_000:  # pragma: no cover - a bug, never a hang
                raise RuntimeError("grbl simulator: event loop does not converge")
        if t > self._now:
            self._set_time(t)
        self._service()

    def next_event_time(self) -> float | None:
        """When the controller's state next changes by itself (a block ends, a hold stops, a dwell ends)."""
        if self._closed:
            return None
        return self._next_internal_event()

    def inject(self, fault: str) -> None:
        """'reset' / 'power-loss': the board reboots (position lost); 'pause-button': the feed-hold input."""
        self._catch_up()
        if fault in ("reset", "power-loss"):
            self.log.append((self._now, f"<{fault}>"))
            self._abort_motion()
            self._phys_offset[:2] += self._mpos[:2]
            self._mpos = np.zeros(3)
            self._boot(power_up=True)
        elif fault == "pause-button":
            self._realtime(RT_HOLD)
        else:
            raise ConfigError(f"grbl: unknown fault {fault!r}; known: reset, power-loss, pause-button")

    def close(self) -> None:
        """Stop the controller; the paper stays readable."""
        self._abort_motion()
        self._closed = True

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
        or ``inject("reset")`` there makes it 0 again).  Refused while the machine moves or the pen is down.
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

    # ---- boot, reset -----------------------------------------------------------------------------
    def _boot(self, power_up: bool) -> None:
        """Initialise as main() does after power-up or a reset, and print the welcome message."""
        keep_alarm = not power_up and (self._alarm or self._sleep)
        self._rx = bytearray()
        self._line = bytearray()
        self._line_flags = 0
        self._task: Generator | None = None
        self._task_is_startup = False
        self._startup_queue: deque[str] = deque()
        self._wait: Wait | None = None
        self.planner.clear()
        self.gc = GcodeState()
        self.gc.coord_system = self.persistent.coords[0].copy()
        self.gc.position = self._mpos.copy()
        self.feed_ovr, self.rapid_ovr, self.spindle_ovr = 100.0, 100.0, 100.0
        self._spindle_state, self._spindle_speed = 5, 0.0
        self._flood = self._mist = False
        self._hold: str | None = None  # "hold", "m0", "door", "jog-cancel", "soft-limit"
        self._door_restore_at: float | None = None
        self._door_spindle_off = False
        self._spindle_stop_ovr = False
        self._check = False
        self._sleep = False
        self._critical = False
        self._homing_until: float | None = None
        self._homing_target: np.ndarray | None = None
        self._jogging = False
        self._soft_limit_pending = False
        self._inked = 0.0
        self._wco_counter = 0
        self._ovr_counter = 0
        self._idle_since: float | None = None
        self._alarm = keep_alarm
        if power_up:
            self._z_parked = True  # the Z pen rests up until a motion drives the Z axis
        if power_up and self._flag(22):
            self._alarm = True
        self._pen_update()
        self._emit(WELCOME)
        if self._alarm:
            self._emit(b"[MSG:'$H'|'$X' to unlock]\r\n")
        else:
            self._startup_queue.extend(line for line in self.startup_lines if line)

    def _soft_reset(self) -> None:
        """0x18: halt (ALARM:3 when in motion), flush everything, re-initialise; position is kept."""
        moving = not self.planner.stopped() or self._homing_until is not None
        if moving:
            code = 6 if self._homing_until is not None else 3
            self._emit(f"ALARM:{code}\r\n".encode())
            self._alarm = True
        self._abort_motion()
        self._boot(power_up=False)

    def _abort_motion(self) -> None:
        """Stop where the carriage is now (ink what was drawn), forget the queue."""
        if self.planner.blocks and (self.planner.running or self.planner.holding):
            b = self.planner.blocks[0]
            s = self.planner.progress(self._now)
            self._ink(b, self._inked, s)
            self._mpos = b.point(s)
        elif self._homing_until is not None:
            self._mpos = self._homing_position(self._now)
        self.planner.clear()
        self._homing_until = None
        self._inked = 0.0
        self._spindle_state = 5
        self._pen_update()

    # ---- time ------------------------------------------------------------------------------------
    def _catch_up(self) -> None:
        now = self.clock.now()
        if now > self._now:
            self.advance_to(now)

    def _set_time(self, t: float) -> None:
        dt = t - self._now
        if dt > 0:
            if self.planner.running and not self.planner.stopped():
                self.stats.moving_time += dt
            self._now = t

    def _next_internal_event(self) -> float | None:
        times = []
        te = self.planner.next_event()
        if te is not None:
            times.append(te)
        if isinstance(self._wait, float) and self._wait > self._now:  # a dwell (not one blocked by a hold)
            times.append(self._wait)
        if self._door_restore_at is not None:
            times.append(self._door_restore_at)
        if self._homing_until is not None:
            times.append(self._homing_until)
        return min(times) if times else None

    def _handle_events(self) -> None:
        now = self._now
        if self._homing_until is not None and self._homing_until <= now:
            self._finish_homing()
        if self._door_restore_at is not None and self._door_restore_at <= now:
            self._door_restore_at = None
            self._resume_motion()
        te = self.planner.next_event()
        while te is not None and te <= now + 1e-12:
            kind, block = self.planner.step()
            if kind == "block":
                assert block is not None
                self._ink(block, self._inked, block.length)
                self._inked = 0.0
                self._mpos = block.target.copy()
                if self.planner.blocks and self.planner.running:
                    self._apply_block_spindle(self.planner.blocks[0])
            else:
                self._hold_complete()
            if not self.planner.blocks:
                self._queue_drained()
            te = self.planner.next_event()

    def _queue_drained(self) -> None:
        """The planner ran empty: a jog ends and a hold that was still decelerating completes."""
        if self._jogging:
            self._jogging = False
            self.gc.position = self._mpos.copy()
        if self._hold is not None and self._hold != "door":
            self._hold_complete()

    # ---- real-time commands ----------------------------------------------------------------------
    def _realtime(self, b: int) -> None:
        names = {RT_RESET: "^X", RT_STATUS: "?", RT_RESUME: "~", RT_HOLD: "!"}
        if b != RT_STATUS:
            self.log.append((self._now, names.get(b, f"0x{b:02X}")))
        if b == RT_RESET:
            self._soft_reset()
        elif b == RT_STATUS:
            if not self._critical and self._homing_until is None:
                self._emit(self._status_report().encode())
        elif self._critical or self._sleep:
            return
        elif b == RT_HOLD:
            self._feed_hold("hold")
        elif b == RT_RESUME:
            self._cycle_resume()
        elif b == RT_DOOR:
            self._feed_hold("door")
        elif b == RT_JOG_CANCEL:
            if self._jogging and self._hold is None:
                self._feed_hold("jog-cancel")
        elif 0x90 <= b <= 0x94 or 0x95 <= b <= 0x97 or 0x99 <= b <= 0x9D:
            self._override(b)
        elif b == 0x9E:
            if self._hold is not None and self.planner.stopped():
                self._split_ink()
                self._spindle_stop_ovr = not self._spindle_stop_ovr
                self._pen_update()
        elif b == 0xA0:
            self._flood = not self._flood
            self.gc.flood = self._flood
        else:
            log.warning("grbl: extended byte 0x%02x is not a real-time command: discarded", b)

    def _override(self, b: int) -> None:
        def clamp(v: float) -> float:
            return min(max(v, 10.0), 200.0)

        if b <= 0x94:
            self.feed_ovr = {0x90: 100.0, 0x91: clamp(self.feed_ovr + 10), 0x92: clamp(self.feed_ovr - 10),
                             0x93: clamp(self.feed_ovr + 1), 0x94: clamp(self.feed_ovr - 1)}[b]
        elif b <= 0x97:
            self.rapid_ovr = {0x95: 100.0, 0x96: 50.0, 0x97: 25.0}[b]
        else:
            self.spindle_ovr = {0x99: 100.0, 0x9A: clamp(self.spindle_ovr + 10),
                                0x9B: clamp(self.spindle_ovr - 10), 0x9C: clamp(self.spindle_ovr + 1),
                                0x9D: clamp(self.spindle_ovr - 1)}[b]
            self._split_ink()
            self._pen_update()
        self._ovr_counter = 0
        self.planner.refresh_speeds(self._now)

    def _feed_hold(self, kind: str) -> None:
        if self._alarm or self._check or self._homing_until is not None:
            return
        if kind == "door":  # supersedes any hold and switches the spindle off
            self._split_ink()
            was_holding = self._hold is not None
            self._hold = "door"
            self._door_spindle_off = True
            self._pen_update()
            if was_holding:
                return
        elif self._hold is not None:
            return
        self._hold = kind
        self.planner.hold(self._now)
        if self.planner.stopped():
            self._hold_complete()

    def _hold_complete(self) -> None:
        """The carriage stopped under a hold: a jog cancel / soft limit flushes the queue; else Hold:0."""
        if self._hold == "jog-cancel" or (self._hold == "hold" and self._jogging):
            self._flush_after_stop()
            self._jogging = False
            self._hold = None
            self.gc.position = self._mpos.copy()
        elif self._hold == "soft-limit":
            self._flush_after_stop()
            self._hold = None
            self._raise_critical(2)

    def _flush_after_stop(self) -> None:
        if self.planner.blocks:
            b = self.planner.blocks[0]
            s = self.planner.progress(self._now)
            self._ink(b, self._inked, s)
            self._mpos = b.point(s)
        self.planner.clear()
        self._inked = 0.0

    def _cycle_resume(self) -> None:
        if self._hold is None or not self.planner.stopped():
            return
        if self._hold == "door":
            self._split_ink()
            self._door_spindle_off = False
            delay = 0.0
            if self._spindle_state != 5:
                delay += 4.0  # SAFETY_DOOR_SPINDLE_DELAY
            if self._flood:
                delay += 1.0  # SAFETY_DOOR_COOLANT_DELAY
            self._pen_update()
            if delay:
                self._door_restore_at = self._now + delay
                self._hold = "door-resuming"
                return
        self._resume_motion()

    def _resume_motion(self) -> None:
        self._hold = None
        if self._spindle_stop_ovr:
            self._split_ink()
            self._spindle_stop_ovr = False
            self._pen_update()
        if self.planner.blocks:
            self._start_cycle()
        else:
            self.planner.holding = False

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
                line = self._startup_queue.popleft()
                self._start_task(self._startup_task(line), startup=True)
                continue
            line = self._take_line()
            if line is None:
                self._auto_start()
                if self._idle_since is None and self._ever_moved and not self.planner.blocks:
                    self._idle_since = self._now  # starving: nothing to move and nothing to parse
                return
            self.stats.commands_executed += 1
            self.log.append((self._now, line if not isinstance(line, int) else "<overflow>"))
            self._start_task(self._line_task(line), startup=False)

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

    def _start_task(self, task: Generator, startup: bool) -> None:
        self._task = task
        self._task_is_startup = startup
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
        if wait == _ROOM:
            return not self.planner.full
        if wait == _SYNC:
            return not self.planner.blocks and self.planner.stopped() and self._hold is None
        if wait == _RESUMED:
            return self._hold is None
        return self._now >= float(wait)  # type: ignore[arg-type]

    def _auto_start(self) -> None:
        """protocol_auto_cycle_start: run queued blocks (never resumes a hold)."""
        if self.planner.blocks and not self.planner.running and self._hold is None and not self.planner.holding:
            self._start_cycle()

    def _start_cycle(self) -> None:
        if self._idle_since is not None:
            self.stats.starved_time += self._now - self._idle_since
            self._idle_since = None
        self._ever_moved = True
        if self.planner.start(self._now):
            self._apply_block_spindle(self.planner.blocks[0])

    def _emit(self, data: bytes) -> None:
        self._out += data

    def _reply(self, code: int) -> None:
        self._emit(b"ok\r\n" if code == 0 else f"error:{code}\r\n".encode())
        if code:
            log.warning("grbl: error:%d", code)

    # ---- line tasks ------------------------------------------------------------------------------
    def _line_task(self, line: str | int) -> Iterator[Wait]:
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

    def _startup_task(self, line: str) -> Iterator[Wait]:
        code = yield from self._gcode(line)
        tail = "ok" if code == 0 else f"error:{code}"
        self._emit(f">{line}:{tail}\r\n".encode())

    def _gcode(self, line: str, jog: bool = False) -> Generator[Wait, None, int]:
        """gc_execute_line: parse, then execute the block's steps in GRBL's order."""
        block = parse_block(line, self.gc, self.persistent, jog=jog)
        if isinstance(block, int):
            return block
        if jog:
            return (yield from self._jog(block))
        new = block.modal
        laser = self._flag(32)
        is_cut = new.motion in (1, MOTION_CW, MOTION_CCW)
        laser_motion = laser and block.motion_command and is_cut and bool(block.axis_words)
        # [4] spindle speed, [7] spindle state, [8] coolant: synchronised with motion
        if block.speed_changed and self.gc.spindle != 5 and not laser_motion:
            yield from self._spindle_sync(self.gc.spindle, new.spindle_speed)
        old_gc = self.gc
        self.gc = new.copy()
        self.gc.position = old_gc.position.copy()
        if block.spindle_changed:
            yield from self._spindle_sync(new.spindle, new.spindle_speed)
        if block.coolant_changed and not self._check:
            yield _SYNC
            self._flood, self._mist = new.flood, new.mist
        if block.non_modal == "G4" and not self._check:
            yield _SYNC
            yield self._now + block.dwell
        if block.wco_changed:
            yield _SYNC  # FORCE_BUFFER_SYNC_DURING_WCO_CHANGE
            self._wco_counter = 0
        if block.g10_index >= 0 and block.g10_values is not None:
            self.persistent.coords[block.g10_index] = block.g10_values.copy()
        if block.non_modal in ("G28.1", "G30.1"):
            target = self.persistent.g28 if block.non_modal == "G28.1" else self.persistent.g30
            target[:] = old_gc.position
        if block.non_modal in ("G28", "G30") and block.home is not None:
            rapid = self._payload(rapid=True)
            if block.axis_words:
                code = yield from self._line_motion(old_gc.position, block.target, rapid=True, payload=rapid)
                if code:
                    return code
            code = yield from self._line_motion(block.target if block.axis_words else old_gc.position,
                                                block.home, rapid=True, payload=rapid)
            if code:
                return code
        if block.motion_command:
            start = old_gc.position
            if new.motion in PROBES:
                code = yield from self._probe(block, start)
                if code:
                    return code
                new.position = self._mpos.copy()
            elif new.motion in (MOTION_CW, MOTION_CCW):
                pts = arc_points(start, block.target, block.arc_offset, block.arc_radius, new.plane,
                                 block.clockwise, self.settings[12])
                feed = block.feed
                if new.inverse_time:
                    feed = block.feed * self._arc_length(start, pts)
                payload = self._payload(rapid=False, laser_on=True)
                prev = start
                for p in pts:
                    code = yield from self._line_motion(prev, p, rapid=False, feed=feed, payload=payload)
                    if code:
                        return code
                    prev = p
            else:
                rapid = new.motion == MOTION_SEEK
                feed = block.feed
                if new.inverse_time and not rapid:
                    feed = block.feed * float(np.linalg.norm(block.target - start))
                code = yield from self._line_motion(start, block.target, rapid=rapid, feed=feed,
                                                    payload=self._payload(rapid=rapid, laser_on=not rapid))
                if code:
                    return code
        self.gc.position = new.position.copy()
        if block.program_flow == 1:
            yield _SYNC
            if not self._check:
                self._hold = "m0"
                yield _RESUMED
        elif block.program_flow in (2, 30):
            yield _SYNC
            if not self._check:
                self.gc.coord_system = self.persistent.coords[0].copy()
                self._wco_counter = 0
                self._spindle_state = 5
                self._flood = self._mist = False
                self._pen_update()
            self._emit(b"[MSG:Pgm End]\r\n")
        return 0

    def _payload(self, rapid: bool, laser_on: bool = False) -> _MovePayload:
        speed = self.gc.spindle_speed if (not self._flag(32) or laser_on) else 0.0
        return _MovePayload(self.gc.spindle, speed, float(self.gc.wco()[2]), rapid)

    @staticmethod
    def _arc_length(start: np.ndarray, pts: np.ndarray) -> float:
        path = np.vstack([start[None, :], pts])
        return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())

    def _spindle_sync(self, state: int, speed: float) -> Generator[Wait, None, None]:
        if self._check:
            return
        yield _SYNC
        self._spindle_state, self._spindle_speed = state, speed
        self._pen_update()

    def _line_motion(
        self, start: np.ndarray, target: np.ndarray, *, rapid: bool, payload: _MovePayload, feed: float = 0.0,
    ) -> Generator[Wait, None, int]:
        """mc_line: soft-limit check, wait for planner room, queue the block."""
        if self._flag(20) and not self._jogging and self._outside_travel(target):
            yield from self._soft_limit()
            return -1
        if self._check:
            return 0
        yield _ROOM
        block = Block(start.copy(), np.asarray(target, dtype=float).copy(), rapid=rapid, feed=feed, data=payload)
        if not self.planner.add(block, self._now) and self._flag(32) and payload.spindle == 3:
            yield from self._spindle_sync(3, payload.speed)
        return 0

    def _outside_travel(self, target: np.ndarray) -> bool:
        for k in range(3):
            travel = self.settings[130 + k]
            if int(self.settings[23]) & (1 << k):
                if target[k] < 0 or target[k] > travel:
                    return True
            elif target[k] > 0 or target[k] < -travel:
                return True
        return False

    def _soft_limit(self) -> Generator[Wait, None, None]:
        """limits_soft_check: controlled stop, then ALARM:2 and the critical lock until a reset."""
        if not self.planner.stopped():
            self._soft_limit_pending = True
            self._hold = "soft-limit"
            self.planner.hold(self._now)
            while self._soft_limit_pending and not self._critical:
                yield _RESUMED
        else:
            self._flush_after_stop()
            self._raise_critical(2)

    def _raise_critical(self, code: int) -> None:
        self._soft_limit_pending = False
        self._abort_motion()
        self._alarm = True
        self._critical = True
        self._task = None
        self._wait = None
        self._emit(f"ALARM:{code}\r\n[MSG:Reset to continue]\r\n".encode())
        log.warning("grbl: ALARM:%d (critical: reset required)", code)

    def _probe(self, block: GBlock, start: np.ndarray) -> Generator[Wait, None, int]:
        """G38.x: a plotter has no probe, so the move always completes without contact."""
        yield _SYNC
        if self._check:
            return 0
        payload = self._payload(rapid=False)
        code = yield from self._line_motion(start, block.target, rapid=False, feed=block.feed, payload=payload)
        if code:
            return code
        yield _SYNC
        self.gc.position = self._mpos.copy()
        pos = ",".join(fmt_float(v, 3) for v in self._mpos)
        self._emit(f"[PRB:{pos}:0]\r\n".encode())
        if not block.probe_no_error:
            self._emit(b"ALARM:5\r\n")
            self._alarm = True
        return 0

    def _jog(self, block: GBlock) -> Generator[Wait, None, int]:
        """jog_execute: soft limits give error:15 instead of an alarm; the jog runs in the Jog state."""
        if self._flag(20) and self._outside_travel(block.target):
            return STATUS["travel_exceeded"]
        yield _ROOM
        payload = _MovePayload(self.gc.spindle, self.gc.spindle_speed, float(self.gc.wco()[2]), False)
        b = Block(self.gc.position.copy(), block.target.copy(), jog=True, feed=block.feed, data=payload)
        if self.planner.add(b, self._now):
            self._jogging = True
        self.gc.position = block.target.copy()
        return 0

    # ---- $ commands ------------------------------------------------------------------------------
    def _system_command(self, line: str) -> Generator[Wait, None, int]:
        idle_or_alarm = self._state_kind() in ("idle", "alarm")
        if len(line) == 1:
            self._emit(HELP)
            return 0
        c = line[1]
        if c == "J":
            if self._state_kind() not in ("idle", "jog"):
                return STATUS["not_idle"]
            if len(line) < 3 or line[2] != "=":
                return STATUS["invalid_statement"]
            return (yield from self._gcode(line, jog=True))
        if c in "$GCX":
            if len(line) != 2:
                return STATUS["invalid_statement"]
            if c == "$":
                if self._state_kind() in ("run", "hold"):
                    return STATUS["not_idle"]
                self._emit(self._settings_report())
            elif c == "G":
                self._emit(self._gcode_modes())
            elif c == "C":
                if self._check:
                    self._emit(b"[MSG:Disabled]\r\nok\r\n")
                    self._boot(power_up=False)
                    return -1
                if self._state_kind() != "idle":
                    return STATUS["not_idle"]
                self._check = True
                self._emit(b"[MSG:Enabled]\r\n")
            elif c == "X" and self._alarm:
                self._emit(b"[MSG:Caution: Unlocked]\r\n")
                self._alarm = False
            return 0
        if not idle_or_alarm:
            return STATUS["not_idle"]
        if c == "#":
            if len(line) != 2:
                return STATUS["invalid_statement"]
            self._emit(self._parameters_report())
            return 0
        if c == "H":
            if not self._flag(22):
                return STATUS["setting_disabled"]
            if len(line) != 2:
                return STATUS["invalid_statement"]
            self._start_homing()
            yield _SYNC
            return 0
        if c == "S":
            if line != "$SLP":
                return STATUS["invalid_statement"]
            self._emit(b"ok\r\n")
            self._spindle_state = 5
            self._pen_update()
            self._sleep = True
            self._emit(b"[MSG:Sleeping]\r\n")
            return -1
        if c == "I":
            if len(line) == 2:
                self._emit(f"[VER:{VERSION}.{BUILD}:{self.build_info}]\r\n".encode())
                self._emit(f"[OPT:VZ,{self.planner.capacity},{self.rx_size}]\r\n".encode())
                return 0
            if line[2] != "=":
                return STATUS["invalid_statement"]
            self.build_info = line[3:]
            return 0
        if c == "R":
            if len(line) != 6 or not line.startswith("$RST=") or line[5] not in "$#*":
                return STATUS["invalid_statement"]
            if line[5] in "$*":
                self.settings = {k: float(v) for k, (v, _) in DEFAULT_SETTINGS.items()}
                self.settings[130], self.settings[131] = self.paper.width_mm, self.paper.height_mm
            if line[5] in "#*":
                self.persistent = Persistent()
            if line[5] == "*":
                self.startup_lines = ["", ""]
                self.build_info = ""
            self._emit(b"[MSG:Restoring defaults]\r\nok\r\n")
            self._boot(power_up=False)
            return -1
        if c == "N" and len(line) == 2:
            for k, text in enumerate(self.startup_lines):
                self._emit(f"$N{k}={text}\r\n".encode())
            return 0
        storing_startup = c == "N"
        if storing_startup and self._state_kind() != "idle":
            return STATUS["not_idle"]
        got = read_float(line, 2 if storing_startup else 1)
        if got is None:
            return STATUS["bad_number"]
        param, i = got
        if i >= len(line) or line[i] != "=":
            return STATUS["invalid_statement"]
        if storing_startup:
            text = line[i + 1:]
            code = yield from self._gcode(text) if text else _no_wait(0)
            if code:
                return code
            index = int(param)
            if 0 <= index < len(self.startup_lines):
                self.startup_lines[index] = text
            return 0
        got = read_float(line, i + 1)
        if got is None:
            return STATUS["bad_number"]
        value, j = got
        if j != len(line) or param > 255:
            return STATUS["invalid_statement"]
        return self._store_setting(int(param), value)

    def _store_setting(self, n: int, value: float) -> int:
        """settings_store_global_setting, with its checks and error codes."""
        if value < 0.0:
            return STATUS["negative_value"]
        if n not in DEFAULT_SETTINGS:
            return STATUS["invalid_statement"]
        kind = DEFAULT_SETTINGS[n][1]
        if n in (100, 101, 102) and value * self.settings[n + 10] > MAX_STEP_RATE_HZ * 60:
            return STATUS["max_step_rate"]
        if n in (110, 111, 112) and value * self.settings[n - 10] > MAX_STEP_RATE_HZ * 60:
            return STATUS["max_step_rate"]
        if n == 0 and int(value) < 3:
            return STATUS["step_pulse_min"]
        if n == 20 and int(value) and not self._flag(22):
            return STATUS["soft_limit_needs_homing"]
        if kind == "int":
            value = float(int(value) & 0xFF)
            if n in _BOOL_SETTINGS:
                value = 1.0 if value else 0.0
        self.settings[n] = value
        if n == 22 and not value:
            self.settings[20] = 0.0
        if n == 13:
            self._wco_counter = 0
        self.planner.refresh_speeds(self._now)
        return 0

    def _start_homing(self) -> None:
        """$H: seek every axis to its switch, locate twice at the pull-off; machine origin there."""
        phys = self._mpos + self._phys_offset
        seek = max(self.settings[25], 1.0) / 60.0
        locate = max(self.settings[24], 1.0) / 60.0
        z_dist = abs(phys[2])
        xy_dist = float(np.max(np.abs(phys[:2])))
        duration = z_dist / seek + xy_dist / seek + 2 * (2 * self.settings[27] / locate) + 4 * self.settings[26] / 1000
        self._homing_start = phys.copy()
        self._homing_t0 = self._now
        self._homing_target = np.zeros(3)
        self._homing_until = self._now + duration
        self._homing_duration = duration

    def _homing_position(self, t: float) -> np.ndarray:
        f = min(max((t - self._homing_t0) / self._homing_duration, 0.0), 1.0) if self._homing_duration else 1.0
        phys = self._homing_start * (1.0 - f)
        return phys - self._phys_offset

    def _finish_homing(self) -> None:
        start_m = self._homing_start - self._phys_offset
        block = Block(start_m, np.zeros(3) - self._phys_offset, data=self._payload(rapid=True))
        self._ink(block, 0.0, block.length)
        self._homing_until = None
        self._phys_offset = np.zeros(3)
        self._mpos = np.zeros(3)
        self.gc.position = np.zeros(3)
        self._alarm = False
        self._startup_queue.extend(line for line in self.startup_lines if line)

    # ---- reports ---------------------------------------------------------------------------------
    def _state_kind(self) -> str:
        if self._sleep:
            return "sleep"
        if self._alarm:
            return "alarm"
        if self._check:
            return "check"
        if self._homing_until is not None:
            return "home"
        if self._hold is not None:
            return "hold"
        if self._jogging:
            return "jog"
        if self.planner.running:
            return "run"
        return "idle"

    def _state_name(self) -> str:
        kind = self._state_kind()
        if kind == "hold":
            moving = not self.planner.stopped()
            if self._hold in ("door", "door-resuming"):
                return "Door:3" if self._hold == "door-resuming" else ("Door:2" if moving else "Door:0")
            if self._hold in ("jog-cancel", "soft-limit"):
                return "Jog" if self._jogging else "Run"
            return "Hold:1" if moving else "Hold:0"
        return {"sleep": "Sleep", "alarm": "Alarm", "check": "Check", "home": "Home", "jog": "Jog",
                "run": "Run", "idle": "Idle"}[kind]

    def _current_mpos(self) -> np.ndarray:
        if self._homing_until is not None:
            return self._homing_position(self._now)
        pos = self.planner.position(self._now) if (self.planner.running or self.planner.holding) else None
        return self._mpos.copy() if pos is None else pos

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
        if self._flag(13):
            rate_text = fmt_float(rate / MM_PER_INCH, 1)
        else:
            rate_text = fmt_float(rate, 0)
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

    def _settings_report(self) -> bytes:
        lines = []
        for n, (_, kind) in DEFAULT_SETTINGS.items():
            v = self.settings[n]
            text = str(int(v)) if kind == "int" else fmt_float(v, 0 if kind == "rpm" else 3)
            lines.append(f"${n}={text}\r\n")
        return "".join(lines).encode()

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

    # ---- pen and paper ---------------------------------------------------------------------------
    def _flag(self, n: int) -> bool:
        return bool(int(self.settings[n]))

    def _limits(self) -> AxisLimits:
        s = self.settings
        return AxisLimits((s[110], s[111], s[112]), (s[120], s[121], s[122]), s[11])

    def _door_off(self) -> bool:
        return self._hold == "door" and self._door_spindle_off

    def _spindle_rpm(self, state: int | None = None, speed: float | None = None) -> float:
        """Spindle output as GRBL computes PWM: 0 when off or S0, else S·override clamped to [$31, $30]."""
        state = self._spindle_state if state is None else state
        speed = self._spindle_speed if speed is None else speed
        if state == 5 or self._door_off() or self._spindle_stop_ovr or speed <= 0:
            return 0.0
        rpm = speed * self.spindle_ovr / 100.0
        return min(max(rpm, self.settings[31]), self.settings[30])

    def _servo_down(self, rpm: float) -> bool:
        if rpm <= 0.0:  # spindle off: no servo pulses, the pen rests up
            return False
        if self.pen_mode == "servo":
            return rpm >= self.pen_threshold
        return rpm < self.pen_threshold

    def _apply_block_spindle(self, block: Block) -> None:
        """Laser mode: a block runs with its own spindle state (G0 runs with the spindle output off)."""
        if not self._flag(32) or not isinstance(block.data, _MovePayload):
            return
        self._pen_update(block)

    def _pen_down_for(self, block: Block | None) -> bool | None:
        """Servo pen: is it down for ``block`` (None: at rest)?  None for the Z pen (depends on Z)."""
        if self.pen_mode == "z":
            return None
        if block is not None and self._flag(32) and isinstance(block.data, _MovePayload):
            rpm = self._spindle_rpm(block.data.spindle, block.data.speed)
        else:
            rpm = self._spindle_rpm()
        return self._servo_down(rpm)

    def _pen_update(self, block: Block | None = None) -> None:
        """Bring the paper's pen state in line with the spindle (or Z) now."""
        down = self._pen_down_for(block)
        if down is None:
            down = not self._z_parked and float(self._current_mpos()[2] - self.gc.wco()[2]) <= 0.0
        if down and not self.paper.pen_is_down:
            self.paper.pen_down(self._phys(self._current_mpos())[:2])
        elif not down and self.paper.pen_is_down:
            self.paper.pen_up()

    def _split_ink(self) -> None:
        """Ink the executing block up to now (before the pen state changes mid-block)."""
        if self.planner.blocks and (self.planner.running or self.planner.holding):
            s = self.planner.progress(self._now)
            self._ink(self.planner.blocks[0], self._inked, s)
            self._inked = s

    def _phys(self, machine: np.ndarray) -> np.ndarray:
        return machine + self._phys_offset

    def _ink(self, block: Block, s0: float, s1: float) -> None:
        """Record the pen's track along ``block`` from s0 to s1 mm (pen-down parts only)."""
        if s1 < s0:
            return
        down = self._pen_down_for(block)
        if down is None:
            self._z_parked = self._z_parked and block.unit[2] == 0.0
            wco_z = block.data.wco_z if isinstance(block.data, _MovePayload) else 0.0
            pieces = [] if self._z_parked else _z_down_pieces(block, s0, s1, wco_z)
        else:
            pieces = [(s0, s1)] if down else []
        cur = s0
        for a, b in pieces:
            if a > cur + 1e-9:
                self.paper.pen_up()
            self._draw(block.point(a), block.point(b))
            cur = b
        if cur < s1 - 1e-9 or not pieces:
            self.paper.pen_up()
        self._lose_steps_at_end_stops(block.point(s1))

    def _draw(self, m0: np.ndarray, m1: np.ndarray) -> None:
        lo = np.zeros(2)
        hi = np.array([self.paper.width_mm, self.paper.height_mm])
        p0, p1 = self._phys(m0)[:2], self._phys(m1)[:2]
        path = clamp_path(p0, p1, lo, hi)
        self.paper.pen_down(path[0])
        self.paper.line_to(path)

    def _lose_steps_at_end_stops(self, machine: np.ndarray) -> None:
        phys = self._phys(machine)[:2]
        if 0.0 <= phys[0] <= self.paper.width_mm and 0.0 <= phys[1] <= self.paper.height_mm:
            return
        clamped = np.clip(phys, 0.0, [self.paper.width_mm, self.paper.height_mm])
        if not np.allclose(clamped, phys):
            log.warning("grbl: carriage ran into the end of travel at %s mm: steps lost", np.round(phys, 3))
            self._phys_offset[:2] += clamped - phys


def _z_down_pieces(block: Block, s0: float, s1: float, wco_z: float) -> list[tuple[float, float]]:
    """Sub-intervals of [s0, s1] along ``block`` where the work Z is <= 0 (the pen touches)."""
    z0 = block.start[2] - wco_z
    dz = block.unit[2]

    def down(s: float) -> bool:
        return z0 + dz * s <= 1e-9

    if abs(dz) < 1e-15:
        return [(s0, s1)] if down(s0) else []
    s_cross = -z0 / dz
    if s0 < s_cross < s1:
        return [(s0, s_cross)] if down(s0) else [(s_cross, s1)]
    return [(s0, s1)] if down(0.5 * (s0 + s1)) else []


def _no_wait(value: int) -> Generator[Wait, None, int]:
    """A line task step that does not wait."""
    return value
    yield  # pragma: no cover - makes this a generator


def _size(text: str) -> tuple[float, float]:
    w, h, unit = parse_size(text, default_unit="mm")
    if unit != "mm":
        raise ValueError(f"travel size must be in mm (e.g. 300x200), got {text!r}")
    return (w, h)


def _positive_int(text: str) -> int:
    value = int(text)
    if value <= 0:
        raise ValueError("expected a positive integer")
    return value


def _non_negative(text: str) -> float:
    value = float(text)
    if not (math.isfinite(value) and value >= 0):
        raise ValueError("expected a number >= 0")
    return value


def _pen_kind(text: str) -> str:
    value = text.strip().lower()
    if value not in ("servo", "servo-inverted", "z"):
        raise ValueError("expected servo, servo-inverted or z")
    return value


def _colour(text: str) -> str:
    from pixelpen.display.picture import parse_colour

    parse_colour(text)
    return text


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
    from pixelpen.profiles.model import load_profile

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
    machine = machine_defaults()
    values = read_options("grbl", options, {
        "size": (_size, machine["size"]),
        "pen": (_pen_kind, machine["pen"]),
        "pen_threshold": (_non_negative, machine["pen_threshold"]),
        "rx_buffer": (_positive_int, machine.get("rx_buffer", 128)),
        "planner": (_positive_int, 16),
        "pen_colour": (_colour, machine.get("pen_colour", "black")),
        "pen_width": (_non_negative, machine["pen_width"]),
    })
    try:
        device = GrblSimulator(clock, **values)  # type: ignore[arg-type]
    except ConfigError as exc:
        from pixelpen.errors import URLError

        raise URLError(f"sim:grbl: {exc}") from None
    device.default_baud = int(machine.get("baud", GrblSimulator.default_baud))  # type: ignore[arg-type]
    return device


register_simulator("grbl", create)

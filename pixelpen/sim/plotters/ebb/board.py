"""AxiDraw / EiBotBoard simulator: the EBB command set over USB CDC, its motion FIFO, servo pen and paper.

Written from evil-mad/EggBot ``docs/ebb.html`` (firmware v3.0+) and ``docs/ebb2.html``, with machine
figures from ``plotters.md`` §2.  Models "axidraw" and "ebb"; URL options:

=======================  ========================================================================
``model=v3``             (alias ``machine``) AxiDraw travel (mm): v2/v3/se_a4 300x218, a3/se_a3 430x297, xlx 595x218,
                         minikit 160x101.6, se_a1 864x594, se_a2 594x432, b6 190x140
``firmware=3.0.2``       version reported by ``V`` and gating the commands (plotters.md §2.2)
``syntax=legacy``        response syntax at boot; ``future`` is what ``CU,10,1`` selects (fw >= 3.0)
``pen_colour=C``         ink colour of the rendered paper (default black)
``pen_width=MM``         line width of the rendered paper (default 0.3)
``contact=17944``        servo pulse width (83.3 ns units) below which the pen touches the paper
=======================  ========================================================================

Commands are ``\\r`` (or ``\\n``) terminated, case-insensitive, at most 255 characters (longer:
``!3 Err: RX Buffer overrun``).  Motion commands enter a FIFO (depth 1 at boot, ``CU,4,n``): one
executes, ``n`` wait, and one more blocks the USB parser, its reply held back until it fits; while the
parser is blocked the board reads only one more 64-byte USB packet (``ready_to_receive`` goes low).
The paper: AxiDraw mixed axes (motor1 = A+B, motor2 = A−B) at 80 steps/mm per axis in 1/16 stepping
(halved per coarser EM mode), x right, y down, origin at the home corner (top left).  The motor enables
(RE0, RC1, active low) and microstep selects (MS1 RE2, MS2 RE1, MS3 RA6) are port pins: EBB_Init drives
them high (disabled, 1/16), EM/ES/PO and the CU,61 timeout change them, and PI, I and QE read them.  The
pen is mechanical: the servo pulse slews at the SC,11/12 or S2 rate and the pen touches the paper while
the pulse is below ``contact`` (on an AxiDraw a larger pulse raises the pen), whatever SC,4/SC,5 say;
QP reports the commanded state (S2 on RP4 counts as up only at exactly SC,4, as in ebb.c).  SC,4 / SC,5
boot at 22565 / 15302 (firmware >= 2.6.0, RCServo2_Init) or 12000 / 16000 (older).  Servo
power (RB1) is off at boot and after ``R`` (SR: "On boot, the power to the RC Servo ... will be off"), so
the pen rests up until a command moves the servo (SP, TP, S2 on RP4); that first move starts from the
pen-up position, SC,4.  Ink is recorded once per move (and where a pen or motor change splits one).
Replies in legacy syntax after an error: the error line ends in ``OK\\r\\n`` on fw >= 3.0 (ebb.html,
"Returned Errors") and in ``\\r\\n`` before.  Timing is exact to the 40 µs tick; the parser itself
takes no time.  Faults: "power-loss" (V+ falls to 0 V: motors unpowered, ``QC`` reads 0, QG bit 6 once
below a ``CU,60`` threshold), "power-restore", "pause-button" (PRG: ``QB`` reads 1), "reset" (reboot).
"""

from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.errors import ConfigError, URLError
from pixelpen.sim.base import register_simulator
from pixelpen.sim.plotters.ebb.motion import MAX_STEP_RATE, MIN_STEP_RATE, TICK, AccumulatorAxis, ServoTrack
from pixelpen.sim.plotters.ebb.params import (
    EbbError,
    ParamSpec,
    ascii_digits,
    checksum,
    error_text,
    parse_params,
    parse_version,
    split_name,
)
from pixelpen.sim.plotters.sheet import Paper, WireStats, clamp_path, read_options

if TYPE_CHECKING:
    from pixelpen.raster.canvas import Canvas

__all__ = ["TRAVEL_MM", "EbbSimulator"]

log = logging.getLogger(__name__)

TRAVEL_MM = {
    "v2": (300.0, 218.0), "v3": (300.0, 218.0), "se_a4": (300.0, 218.0), "a3": (430.0, 297.0),
    "se_a3": (430.0, 297.0), "xlx": (595.0, 218.0), "minikit": (160.0, 101.6), "se_a1": (864.0, 594.0),
    "se_a2": (594.0, 432.0), "b6": (190.0, 140.0),
}
"""AxiDraw travel by model (axidraw_conf.py via plotters.md §2.3)."""

RX_BUF_SIZE = 256  # a command may be at most 255 characters plus its terminator
USB_PACKET = 64  # bytes the board buffers while its parser is blocked
MAX_FIFO = 32  # QU,2 on this simulated build
STEPS_PER_MM_16 = 80.0  # per mixed axis at 1/16 microstepping
SUPPLY_VOLTS = 9.0
SERVO_BOOT = (22565, 15302)
"""SC,4 (up) / SC,5 (down) at boot since firmware 2.6.0 (RCServo2_Init; ebb.html still says 12000 / 16000)."""
SERVO_BOOT_OLD = (12000, 16000)
"""SC,4 / SC,5 at boot before firmware 2.6.0."""
SERVO_RANGE = (9855, 27831)
"""pyaxidraw's servo range (0.82 .. 2.32 ms): pen height 0 % .. 100 %, a larger pulse raising the pen."""
CONTACT_DEFAULT = round(SERVO_RANGE[0] + 0.45 * (SERVO_RANGE[1] - SERVO_RANGE[0]))
"""Pulse width at which the pen meets the paper (17944): 45 % of SERVO_RANGE, midway between pyaxidraw's
30 % (down, 15248) and 60 % (up, 20641) defaults, and between saxi's 15700 (down) and 28000 (up)."""
SERVO_TIMEOUT_MS = 60000

P = ParamSpec
_OPT = False
_I32, _U32 = P("i32"), P("u32")


@dataclass
class _Command:
    """A motion-queue entry: how long it takes and what it does when the engine starts it."""

    name: str
    duration: float = 0.0  # seconds (may be set by ``begin``)
    begin: Callable[[float], None] | None = None
    axes: tuple[AccumulatorAxis, AccumulatorAxis] | None = None  # accumulator moves
    linear: tuple[int, int] | None = None  # constant-rate moves: total motor steps
    t0: float = 0.0
    ticks: int = 0
    ends: tuple[int, int] = (0, 0)  # accumulator moves: the tick at which each axis stops (LM: its last step)
    moving: tuple[bool, bool] = (False, False)


ENABLE_PINS = (("E", 0), ("C", 1))
"""Motor 1 and 2 driver enables, active low (HardwareProfile_EBB_V13_and_above.h: Enable1IO RE0, Enable2IO RC1)."""
MS_PINS = (("E", 2), ("E", 1), ("A", 6))
"""Microstep selects MS1, MS2, MS3 (RE2, RE1, RA6), shared by both drivers."""
MS_LEVELS = {1: (1, 1, 1), 2: (1, 1, 0), 3: (0, 1, 0), 4: (1, 0, 0), 5: (0, 0, 0)}
"""EM mode -> MS1..MS3 levels (ebb.c, COMMAND_EM): 1 = 1/16 ... 5 = full step."""
MS_MICROSTEPS = {(0, 0, 0): 1, (1, 0, 0): 2, (0, 1, 0): 4, (1, 1, 0): 8}
"""MS1..MS3 levels -> microsteps as QE decodes them (parse_QE_packet); anything else reads 16."""


@dataclass
class _Ports:
    """PORTA..E latches and directions (1 = input); inputs on port B read high (weak pull-ups).

    UserInit makes every pin an input with its latch low; EBB_Init then drives MS1..MS3 and both motor
    enables high (1/16 stepping, drivers disabled) and the step/direction pins low.
    """

    lat: dict[str, int] = field(default_factory=lambda: dict.fromkeys("ABCDE", 0))
    tris: dict[str, int] = field(default_factory=lambda: {"A": 0xFF, "B": 0xED, "C": 0xFF, "D": 0x03, "E": 0xFF})

    def __post_init__(self) -> None:
        for port, pin in MS_PINS + ENABLE_PINS:
            self.drive(port, pin, 1)

    def read(self, port: str) -> int:
        """Digital value of every pin of ``port``."""
        pulled = 0xFF if port == "B" else 0x00
        return (self.lat[port] & ~self.tris[port] | pulled & self.tris[port]) & 0xFF

    def pin(self, port: str, pin: int) -> int:
        """Digital value of one pin."""
        return (self.read(port) >> pin) & 1

    def set_latch(self, port: str, pin: int, value: int) -> None:
        """Write one output latch (the pin follows only while it is an output)."""
        bit = 1 << pin
        self.lat[port] = (self.lat[port] | bit) if value else (self.lat[port] & ~bit)

    def drive(self, port: str, pin: int, value: int) -> None:
        """Make ``pin`` an output at ``value``."""
        self.set_latch(port, pin, value)
        self.tris[port] &= ~(1 << pin)


class EbbSimulator:
    """An EiBotBoard (AxiDraw) seen from its USB serial port (WireDevice)."""

    default_baud = 12_000_000
    """USB CDC ignores the line coding: bytes move at USB full speed (12 Mbit/s), not at a baud rate."""

    def __init__(
        self,
        clock: Clock | None = None,
        *,
        model: str = "axidraw",
        machine: str = "v3",
        firmware: str = "3.0.2",
        syntax: str = "legacy",
        pen_colour: str = "black",
        pen_width: float = 0.3,
        contact: int = CONTACT_DEFAULT,
    ) -> None:
        if machine not in TRAVEL_MM:
            raise ConfigError(f"{model}: model must be one of {', '.join(TRAVEL_MM)}, got {machine!r}")
        self.model = model
        self.machine = machine
        self.version = parse_version(firmware)
        self.firmware = firmware
        if syntax not in ("legacy", "future"):
            raise ConfigError(f"{model}: syntax must be legacy or future, got {syntax!r}")
        if syntax == "future" and self.version < (3, 0, 0):
            raise ConfigError(f"{model}: future syntax needs firmware >= 3.0.0, got {firmware}")
        self._boot_syntax = syntax
        if not 1 <= contact <= 65535:
            raise ConfigError(f"{model}: contact must be a servo pulse width 1..65535, got {contact!r}")
        self._contact_pulse = contact
        self._servo_defaults = SERVO_BOOT if self.version >= (2, 6, 0) else SERVO_BOOT_OLD
        self.clock = clock if clock is not None else REAL_CLOCK
        width, height = TRAVEL_MM[machine]
        self._paper = Paper(width, height, y_down=True, pen_colours={1: pen_colour}, pen_width_mm=pen_width)
        self.stats = WireStats()
        self.log: list[tuple[float, str]] = []
        self.nickname = ""
        self._now = self.clock.now()
        self._out = bytearray()
        self._inbox = bytearray()
        self._inpos = 0
        self._xy = np.zeros(2)  # carriage position on the paper, mm
        self._vplus = SUPPLY_VOLTS
        self._closed = False
        self._dead = False
        self._ever_moved = False
        self._init_state(power_up=True)

    # ---- WireDevice ------------------------------------------------------------------------------
    @property
    def ready_to_receive(self) -> bool:
        """USB flow control: False once a blocked parser has a full 64-byte packet waiting."""
        return len(self._inbox) - self._inpos < USB_PACKET

    def receive(self, data: bytes) -> None:
        """Host bytes over USB (never lost: a blocked board just stops reading them)."""
        if self._closed:
            return
        self._catch_up()
        self.stats.bytes_received += len(data)
        self._inbox += data
        self._service()

    def take_output(self) -> bytes:
        """Bytes the board sent since the last call."""
        out = bytes(self._out)
        self._out.clear()
        return out

    def advance_to(self, t: float) -> None:
        """Run the motion engine up to clock time ``t``."""
        if self._closed:
            return
        for _ in range(10_000_000):
            self._service()
            te = self._engine_end()
            if te is None or te > t:
                break
            self._finish(te)
        else:  # pragma: no cover - a bug, never a hang
            raise RuntimeError("ebb simulator: event loop does not converge")
        if t > self._now:
            self._still_pen(t)
            self._now = t
        self._service()

    def next_event_time(self) -> float | None:
        """When the executing motion command ends (None when the engine is idle)."""
        return None if self._closed else self._engine_end()

    def inject(self, fault: str) -> None:
        """'power-loss', 'power-restore', 'pause-button' (PRG pressed) or 'reset' (reboot)."""
        self._catch_up()
        self.log.append((self._now, f"<{fault}>"))
        if fault == "power-loss":
            self._split_ink(self._now)
            self._vplus = 0.0
            if self._power_threshold and self.version >= (3, 0, 0):
                self._power_lost_flag = True
        elif fault == "power-restore":
            self._split_ink(self._now)
            self._vplus = SUPPLY_VOLTS
        elif fault == "pause-button":
            self._button = True
        elif fault == "reset":
            self._stop_motion()
            self._dead = False
            self._init_state(power_up=True)
        else:
            raise ConfigError(
                f"{self.model}: unknown fault {fault!r}; known: power-loss, power-restore, pause-button, reset"
            )

    def close(self) -> None:
        """Stop the board; the paper stays readable."""
        self._stop_motion()
        self._closed = True

    # ---- public extras ---------------------------------------------------------------------------
    @property
    def step_position(self) -> tuple[int, int]:
        """Global motor step counters (what QS reports) at the current clock time."""
        self._catch_up()
        return self._steps_now(self._now)

    @property
    def position_mm(self) -> np.ndarray:
        """Carriage position on the paper (mm, x right, y down) at the current clock time."""
        self._catch_up()
        return self._xy_at(self._now)

    @property
    def pen_up(self) -> bool:
        """Commanded pen state (what QP reports): True when up."""
        return self._pen_state_up

    @property
    def paper(self) -> Paper:
        """The sheet, with the executing move inked up to the current clock time."""
        self._catch_up()
        self._split_ink(self._now)
        return self._paper

    def push_carriage_home(self) -> None:
        """The operator pushes the carriage by hand to the home corner (0, 0) with the motors unpowered, pen up.

        A physical act: the board does not see it, its step counters stay as they were (a motion command it
        runs meanwhile counts steps the unpowered motors do not make).  Refused while powered motors hold
        the carriage, or with the pen on the paper.
        """
        self._catch_up()
        if self._vplus >= 6.0 and any(self._motors_enabled(self._now)):
            raise ConfigError(f"{self.model}: the energised motors hold the carriage: switch them off (EM,0,0) first")
        if self._contact(self._now):
            raise ConfigError(f"{self.model}: lift the pen before pushing the carriage (it would draw)")
        self._xy = np.zeros(2)

    @property
    def syntax(self) -> str:
        """Current response syntax: 'legacy' or 'future'."""
        return "future" if self._future else "legacy"

    def paper_image(self, dpi: float = 96.0) -> Canvas:
        """The paper with everything drawn so far, as an RGB Canvas."""
        return self.paper.paper_image(dpi)

    def save_paper(self, path: str | Path, dpi: float = 96.0) -> None:
        """Render the paper to an image file."""
        self.paper.save_paper(path, dpi)

    # ---- state -----------------------------------------------------------------------------------
    def _init_state(self, power_up: bool) -> None:
        """Default power-on state (UserInit): R, RB and a reboot all come here."""
        self._future = self._boot_syntax == "future" if power_up else False
        self._ack = True
        self._limit_check = True
        self._fifo_size = 1
        self._auto_enable = True
        self._checksums = False
        self._power_threshold = 0
        self._stepper_timeout = 0
        self._limit_mask = self._limit_target = self._limit_replies = 0
        self._power_lost_flag = False
        self._button = False
        self._fifo: deque[_Command] = deque()
        self._exec: _Command | None = None
        self._blocked: deque[tuple[_Command, bytes]] = deque()
        self._line = bytearray()
        self._in_cr = False
        self._steps = [0, 0]
        self._acc = [0, 0]
        self._servo_min, self._servo_max = self._servo_defaults
        self._rate_up = self._rate_down = 0
        self._servo: ServoTrack | None = None  # RB1 servo power is off at boot: the pen rests up
        self._pen_state_up = True
        self._servo_power_until: float | None = None
        self._servo_timeout = SERVO_TIMEOUT_MS
        self._servo_always_on = False
        self._node = 0
        self._vars = [0] * 32
        self._ports = _Ports()
        self._ram = bytearray(4096)
        self._analog: set[int] = set()
        self._engraver = (0, 0)
        self._s2: dict[int, int] = {}
        self._last_motion_end = self._now
        self._inked_until = self._now
        self._idle_since: float | None = None
        self._sync_pen(self._now)

    @property
    def _fw3(self) -> bool:
        return self.version >= (3, 0, 0)

    def _steps_per_mm(self) -> float:
        return STEPS_PER_MM_16 * self._microsteps() / 16

    def _microsteps(self) -> int:
        """Stepping the MS1..MS3 pins select (QE's decoding)."""
        return MS_MICROSTEPS.get(tuple(self._ports.pin(p, n) for p, n in MS_PINS), 16)

    def _set_enables(self, *states: bool | None) -> None:
        """Drive the motor enable pins (active low); None leaves a motor as it is."""
        for (port, pin), on in zip(ENABLE_PINS, states):
            if on is not None:
                self._ports.set_latch(port, pin, 0 if on else 1)

    def _motors_enabled(self, t: float) -> list[bool]:
        """Motor enables as the pins read, after the CU,61 stepper timeout has had its say."""
        if self._stepper_timeout and self._exec is None and t - self._last_motion_end > self._stepper_timeout:
            self._set_enables(False, False)
        return [self._ports.pin(port, pin) == 0 for port, pin in ENABLE_PINS]

    # ---- time and engine -------------------------------------------------------------------------
    def _catch_up(self) -> None:
        now = self.clock.now()
        if now > self._now:
            self.advance_to(now)

    def _engine_end(self) -> float | None:
        return None if self._exec is None else self._exec.t0 + self._exec.duration

    def _still_pen(self, t: float) -> None:
        """Bring the paper's pen in line with the servo while the carriage stands still.

        A move is inked as one segment when it ends, or up to the moment something changes the pen or
        the motors under it (``_split_ink``), so time passing within a move costs nothing.
        """
        cmd = self._exec
        if cmd is None or (cmd.axes is None and cmd.linear is None):
            self._sync_pen(t)

    def _start_next(self, t: float) -> None:
        if self._exec is not None or not self._fifo:
            return
        cmd = self._fifo.popleft()
        cmd.t0 = t
        if self._idle_since is not None:
            self.stats.starved_time += t - self._idle_since
            self._idle_since = None
        self._sync_pen(t)
        if cmd.begin is not None:
            cmd.begin(t)
        self._exec = cmd
        self._inked_until = t
        if cmd.axes is not None or cmd.linear is not None:
            self._ever_moved = True
        if cmd.duration <= 0:
            self._finish(t)

    def _finish(self, te: float) -> None:
        cmd = self._exec
        assert cmd is not None
        self._ink(cmd, self._inked_until, te)
        self._now = max(self._now, te)
        self.stats.moving_time += cmd.duration
        d1, d2 = self._move_steps(cmd, te)
        self._apply_steps(cmd, d1, d2, te)
        if cmd.axes is not None:
            for k in range(2):
                self._acc[k] = cmd.axes[k].remainder(min(cmd.ticks, cmd.ends[k]))
        self._exec = None
        if cmd.axes is not None or cmd.linear is not None or cmd.duration > 0:
            self._last_motion_end = te
        self._start_next(te)
        if self._exec is None and not self._fifo and self._ever_moved:
            self._idle_since = te
        self._sync_pen(te)

    def _move_steps(self, cmd: _Command, t: float) -> tuple[int, int]:
        """Signed motor steps ``cmd`` has taken by time ``t`` (all of them once it has ended)."""
        ticks = cmd.ticks if cmd.linear is None else int(round(cmd.duration / TICK))
        done = min(int(math.floor((t - cmd.t0) / TICK + 1e-6)), ticks)
        if cmd.linear is not None:
            # step k of N falls on tick ceil(k·T/N): after `done` ticks, floor(done·N/T) steps
            return tuple(  # type: ignore[return-value]
                int(math.copysign(abs(n) * done // ticks, n)) if ticks else n for n in cmd.linear
            )
        if cmd.axes is not None:
            return tuple(ax.direction * ax.steps_at(done) for ax in cmd.axes)  # type: ignore[return-value]
        return 0, 0

    def _apply_steps(self, cmd: _Command, d1: int, d2: int, t: float) -> None:
        self._steps[0] += d1
        self._steps[1] += d2
        self._xy = self._xy_after(self._xy, d1, d2, t)

    def _xy_after(self, xy: np.ndarray, d1: float, d2: float, t: float) -> np.ndarray:
        e1, e2 = self._motors_effective(t)
        spm = self._steps_per_mm()
        dx = (d1 * e1 + d2 * e2) / 2.0 / spm
        dy = (d1 * e1 - d2 * e2) / 2.0 / spm
        hi = np.array([self._paper.width_mm, self._paper.height_mm])
        return np.clip(xy + np.array([dx, dy]), 0.0, hi)

    def _motors_effective(self, t: float) -> tuple[float, float]:
        if self._vplus < 6.0:
            return 0.0, 0.0
        en = self._motors_enabled(t)
        return float(en[0]), float(en[1])

    def _steps_now(self, t: float) -> tuple[int, int]:
        if self._exec is None:
            return self._steps[0], self._steps[1]
        d1, d2 = self._move_steps(self._exec, t)
        return self._steps[0] + d1, self._steps[1] + d2

    def _xy_at(self, t: float) -> np.ndarray:
        if self._exec is None:
            return self._xy.copy()
        d1, d2 = self._move_steps(self._exec, t)
        return self._xy_after(self._xy, d1, d2, t)

    def _stop_motion(self) -> bool:
        """ES: stop the executing command where it is and flush the FIFO; True if anything was stopped."""
        interrupted = self._exec is not None or bool(self._fifo)
        if self._exec is not None:
            cmd = self._exec
            self._ink(cmd, self._inked_until, self._now)
            d1, d2 = self._move_steps(cmd, self._now)
            self._apply_steps(cmd, d1, d2, self._now)
            self._exec = None
            self._last_motion_end = self._now
        self._fifo.clear()
        return interrupted

    # ---- pen and paper ---------------------------------------------------------------------------
    def _contact(self, t: float) -> bool:
        """Whether the pen touches the paper: the servo's pulse is below the contact position."""
        return self._servo is not None and self._servo.position(t) < self._contact_pulse

    def _contact_change(self, t0: float, t1: float) -> float | None:
        if self._servo is None:
            return None
        tc = self._servo.crossing(self._contact_pulse)
        return tc if tc is not None and t0 < tc < t1 else None

    def _sync_pen(self, t: float) -> None:
        down = self._contact(t)
        if down and not self._paper.pen_is_down:
            self._paper.pen_down(self._xy_at(t))
        elif not down and self._paper.pen_is_down:
            self._paper.pen_up()

    def _split_ink(self, t: float) -> None:
        """Ink the executing move up to ``t`` (before something changes the pen or the motors)."""
        if self._exec is not None and t > self._inked_until:
            self._ink(self._exec, self._inked_until, t)
            self._inked_until = t
        self._sync_pen(t)

    def _ink(self, cmd: _Command, ta: float, tb: float) -> None:
        """Record the carriage's track during ``cmd`` from ta to tb, pen-down parts only."""
        if tb <= ta or (cmd.axes is None and cmd.linear is None):
            return
        tc = self._contact_change(ta, tb)
        spans = [(ta, tc), (tc, tb)] if tc is not None else [(ta, tb)]
        for a, b in spans:
            mid = 0.5 * (a + b)
            if not self._contact(mid):
                self._paper.pen_up()
                continue
            pts = self._track(cmd, a, b)
            self._paper.pen_down(pts[0])
            self._paper.line_to(pts)

    def _track(self, cmd: _Command, ta: float, tb: float) -> np.ndarray:
        """Carriage positions (mm) along ``cmd`` between ta and tb, clamped at the ends of travel.

        A constant-rate move is a straight line (its exact clamped path); an accelerated one is
        sampled 33 times from the accumulator's closed form.
        """
        hi = np.array([self._paper.width_mm, self._paper.height_mm])
        e1, e2 = self._motors_effective(ta)
        spm = self._steps_per_mm()
        if cmd.linear is not None or cmd.axes is None:
            d = np.array([self._move_steps(cmd, ta), self._move_steps(cmd, tb)], dtype=np.float64)
        else:
            ticks = np.clip(np.floor((np.linspace(ta, tb, 33) - cmd.t0) / TICK + 1e-6), 0, cmd.ticks).astype(int)
            d = np.array([[ax.direction * ax.steps_at(k) for ax in cmd.axes] for k in ticks.tolist()], dtype=np.float64)
        xy = self._xy + np.column_stack([(d[:, 0] * e1 + d[:, 1] * e2), (d[:, 0] * e1 - d[:, 1] * e2)]) / (2 * spm)
        if len(xy) == 2:
            return clamp_path(xy[0], xy[1], np.zeros(2), hi)
        return np.clip(xy, 0.0, hi)

    # ---- USB input and the command parser --------------------------------------------------------
    def _service(self) -> None:
        """ProcessIO: read USB bytes into commands and run them until the parser blocks."""
        while not self._dead:
            if self._blocked:
                if not self._fifo_has_room():
                    return
                cmd, reply = self._blocked.popleft()
                self._enqueue(cmd)
                self._emit(reply)
                continue
            if self._inpos >= len(self._inbox):
                self._inbox.clear()
                self._inpos = 0
                return
            c = self._inbox[self._inpos]
            self._inpos += 1
            self._byte(c)

    def _byte(self, c: int) -> None:
        if c in (0x0D, 0x0A):
            if self._in_cr:
                return
            self._in_cr = True
            line = self._line.decode("latin-1")
            self._line.clear()
            self._command(line)
        elif c == 0x08 and self._line:
            del self._line[-1]
            self._emit(b" \b")
        elif c >= 0x20:
            self._in_cr = False
            self._line.append(c)
            if len(self._line) >= RX_BUF_SIZE:
                self._line.clear()
                self._emit((error_text(3, self._fw3) + self._ending(error=True)).encode())
                log.warning("%s: command longer than %d bytes: !3 RX buffer overrun", self.model, RX_BUF_SIZE - 1)

    def _fifo_has_room(self) -> bool:
        return len(self._fifo) < self._fifo_size or (self._exec is None and not self._fifo)

    def _enqueue(self, cmd: _Command) -> None:
        self._fifo.append(cmd)
        self._start_next(self._now)

    def _emit(self, data: bytes) -> None:
        self._out += data

    def _ending(self, kind: str = "ok", error: bool = False) -> str:
        """print_line_ending: future '\\n'; legacy 'OK\\r\\n' (ack on), '\\r\\n' or '\\n\\r'."""
        if self._future:
            return "\n"
        if error:
            return ("OK\r\n" if self._ack else "\r\n") if self._fw3 else "\r\n"
        if kind == "ok":
            return ("OK" if self._ack else "") + "\r\n"
        return "\n\r" if kind == "rev" else "\r\n"

    def _command(self, line: str) -> None:
        """Parse one command line and run it (or hold its reply while the FIFO is full)."""
        self.stats.commands_executed += 1
        self.log.append((self._now, line))
        if self._checksums:
            line = self._strip_checksum(line)
            if line is None:
                return
        name, rest = split_name(line) if line else ("\r", "")
        handler = _COMMANDS.get(name)
        prefix = (name + ",") if self._future else ""
        if handler is None or self.version < handler[0]:
            if len(name) == 1:
                text = f"!8 Err: Unknown command '{name}:{ord(name):02X}'"
            else:
                text = f"!8 Err: Unknown command '{name}:{ord(name[0]):02X}{ord(name[1]):02X}'"
            self._emit((prefix + text + self._ending(error=True)).encode())
            # a lone '#' is how drivers flush a half-received command (pixelpen's AxiDraw sends it on every
            # connect): the board answers it as unknown like any other, but it is expected, not a fault
            (log.debug if line == "#" else log.warning)("%s: unknown command %r", self.model, line)
            return
        _, specs, method = handler
        try:
            values = parse_params(rest, specs, self._fw3)
            method(self, name, values)
        except EbbError as exc:
            self._emit((prefix + exc.text + self._ending(error=True)).encode())
            log.warning("%s: %r -> %s", self.model, line, exc.text)

    def _strip_checksum(self, line: str) -> str | None:
        cut = line.rfind(",")
        prefix = (split_name(line)[0] + ",") if self._future else ""
        if cut < 0 or not ascii_digits(line[cut + 1:]) or len(line) - cut - 1 > 3:
            self._emit((prefix + "!10 Err: No checksum found but required" + self._ending(error=True)).encode())
            return None
        expected = checksum(line[:cut])
        if int(line[cut + 1:]) != expected:
            self._emit((prefix + f"!9 Err: Checksum incorrect, expected {expected}" + self._ending(error=True)).encode())
            return None
        return line[:cut]

    def _reply(self, name: str, data: str | None = None, kind: str = "ok", legacy: str | None = None) -> None:
        """Answer in the current syntax: future ``NAME[,data]\\n``; legacy ``legacy`` or data + ending."""
        if self._future:
            self._emit(((name if data is None else f"{name},{data}") + "\n").encode())
        elif legacy is not None:
            self._emit(legacy.encode())
        elif data is None:
            self._emit(self._ending(kind).encode())
        else:
            self._emit((data + self._ending(kind)).encode())

    def _queue(self, name: str, cmd: _Command, reply: bool = True) -> None:
        """A motion-queue command: run it now if it fits, else block the parser, holding back its reply."""
        text = ((name + "\n") if self._future else self._ending("ok")) if reply else ""
        if not self._blocked and self._fifo_has_room():
            self._enqueue(cmd)
            self._emit(text.encode())
        else:
            self._blocked.append((cmd, text.encode()))

    # ---- motion commands -------------------------------------------------------------------------
    def _begin_motion(self, t: float, clear: int) -> None:
        self._split_ink(t)
        if self._auto_enable:
            self._set_enables(True, True)
        for k in range(2):
            if clear & (1 << k):
                self._acc[k] = 0

    def _linear(self, name: str, duration_ms: int, s1: int, s2: int, clear: int, capped: bool) -> None:
        if s1 == 0 and s2 == 0:
            delay = min(duration_ms, 100000) / 1000.0
            self._queue(name, _Command(name, duration=delay))
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
        cmd = _Command(name, duration=duration, linear=(s1, s2), moving=(s1 != 0, s2 != 0))
        cmd.begin = lambda t: self._begin_motion(t, clear)
        self._queue(name, cmd)

    def _accumulator(self, name: str, axes: tuple[AccumulatorAxis, AccumulatorAxis], ticks: int | None,
                     clear: int, reply: bool = True) -> None:
        if ticks is None:
            ends = [ax.completion() for ax in axes]
            if any(e is None for e in ends):
                raise EbbError(6, error_text(6, self._fw3))
            ticks = max(int(e) for e in ends)  # type: ignore[arg-type]
        cmd = _Command(name, duration=ticks * TICK, axes=axes,
                       moving=tuple(bool((ax.steps is None and (ax.rate or ax.accel)) or ax.steps) for ax in axes))

        def begin(t: float, cmd: _Command = cmd) -> None:
            self._begin_motion(t, clear)
            cmd.axes = tuple(  # type: ignore[assignment]
                AccumulatorAxis(a.direction, a.rate, a.accel, a.jerk, self._acc[k], a.steps)
                for k, a in enumerate(cmd.axes)  # type: ignore[arg-type]
            )
            if any(a.steps is not None for a in cmd.axes):  # type: ignore[union-attr]
                cmd.ends = tuple(a.completion() or 0 for a in cmd.axes)  # type: ignore[assignment,union-attr]
                cmd.ticks = max(cmd.ends)
                cmd.duration = cmd.ticks * TICK

        cmd.ticks = ticks
        cmd.ends = (ticks, ticks)
        cmd.begin = begin
        self._queue(name, cmd, reply)

    @staticmethod
    def _lm_axis(rate: int, steps: int, accel: int, jerk: int = 0) -> AccumulatorAxis:
        direction = -1 if (rate < 0) != (steps < 0) else 1
        return AccumulatorAxis(direction, abs(rate), accel if rate >= 0 else -accel, jerk, 0, abs(steps))

    def _check_lm(self, axes: tuple[AccumulatorAxis, AccumulatorAxis]) -> None:
        if not any(ax.steps and (ax.rate or ax.accel or ax.jerk) for ax in axes):
            raise EbbError(6, error_text(6, self._fw3))

    def _cmd_SM(self, name: str, v: list) -> None:
        duration, s1, s2, clear = v
        if duration == 0:
            raise EbbError(6, error_text(6, self._fw3))
        self._linear(name, duration, s1, s2 or 0, clear or 0, capped=True)

    def _cmd_XM(self, name: str, v: list) -> None:
        duration, a, b, clear = v
        if duration == 0:
            raise EbbError(6, error_text(6, self._fw3))
        self._linear(name, duration, a + b, a - b, clear or 0, capped=False)

    def _cmd_LM(self, name: str, v: list) -> None:
        r1, s1, a1, r2, s2, a2, clear = v
        axes = (self._lm_axis(r1, s1, a1), self._lm_axis(r2, s2, a2))
        if self._limit_check:
            self._check_lm(axes)
        self._accumulator(name, axes, None, clear or 0)

    def _cmd_L3(self, name: str, v: list) -> None:
        r1, s1, a1, j1, r2, s2, a2, j2, clear = v
        axes = (self._lm_axis(r1, s1, a1, j1), self._lm_axis(r2, s2, a2, j2))
        if self._limit_check:
            self._check_lm(axes)
        self._accumulator(name, axes, None, clear or 0)

    def _lt_axes(self, r1: int, a1: int, j1: int, r2: int, a2: int, j2: int) -> tuple[AccumulatorAxis, AccumulatorAxis]:
        return (AccumulatorAxis(-1 if r1 < 0 else 1, abs(r1), a1, j1),
                AccumulatorAxis(-1 if r2 < 0 else 1, abs(r2), a2, j2))

    def _cmd_LT(self, name: str, v: list) -> None:
        intervals, r1, a1, r2, a2, clear = v
        self._accumulator(name, self._lt_axes(r1, a1, 0, r2, a2, 0), intervals, clear or 0)

    def _cmd_T3(self, name: str, v: list) -> None:
        intervals, r1, a1, j1, r2, a2, j2, clear = v
        self._accumulator(name, self._lt_axes(r1, a1, j1, r2, a2, j2), intervals, clear or 0)

    def _cmd_TD(self, name: str, v: list) -> None:
        intervals, r1a, r1b, a1, j1, r2a, r2b, a2, j2, clear = v
        self._accumulator(name, self._lt_axes(r1a, 0, j1, r2a, 0, j2), intervals, clear or 0, reply=False)
        self._accumulator(name, self._lt_axes(r1b, a1, -j1, r2b, a2, -j2), intervals, clear or 0)

    def _cmd_TR(self, name: str, v: list) -> None:
        rate, s1, s2, clear = v
        if rate == 0:
            raise EbbError(6, error_text(6, self._fw3))
        s2 = s2 or 0
        duration_ms = max(abs(s1), abs(s2)) * 1000.0 / rate
        self._linear(name, max(int(math.ceil(duration_ms)), 1), s1, s2, clear or 0, capped=True)

    def _cmd_HM(self, name: str, v: list) -> None:
        freq, p1, p2 = v
        if freq < 2 or freq > 25000:
            raise EbbError(6, error_text(6, self._fw3))
        if p1 is not None and p2 is None:
            raise EbbError(4, error_text(4, self._fw3))
        target = (p1 or 0, p2 or 0)
        cmd = _Command(name, moving=(True, True))

        def begin(t: float) -> None:
            self._begin_motion(t, 0)
            d1, d2 = target[0] - self._steps[0], target[1] - self._steps[1]
            cmd.linear = (d1, d2)
            longest = max(abs(d1), abs(d2))
            travel = math.ceil(longest / freq / TICK - 1e-9) * TICK if longest else 0.0
            cmd.duration = 0.005 + travel  # the ~5 ms start delay is spread over the move

        cmd.begin = begin
        self._queue(name, cmd)

    def _cmd_EM(self, name: str, v: list) -> None:
        e1, e2 = v

        def begin(t: float) -> None:
            self._split_ink(t)
            if e1:
                for (port, pin), level in zip(MS_PINS, MS_LEVELS[e1]):
                    self._ports.set_latch(port, pin, level)
            self._set_enables(bool(e1), None if e2 is None else bool(e2))
            self._steps = [0, 0]
            self._acc = [0, 0]

        if self._fw3:
            self._queue(name, _Command(name, begin=begin))
        else:
            begin(self._now)
            self._reply(name)

    def _cmd_ES(self, name: str, v: list) -> None:
        (disable,) = v
        interrupted = self._stop_motion()
        if disable:
            self._set_enables(False, False)
        self._reply(name, str(int(interrupted)), kind="rev")
        if not self._future:
            self._emit(self._ending("ok").encode())

    def _cmd_CS(self, name: str, v: list) -> None:
        self._steps = [0, 0]
        self._acc = [0, 0]
        self._reply(name)

    # ---- pen -------------------------------------------------------------------------------------
    def _servo_move(self, t: float, target: float, rate: float) -> None:
        """Power the servo and slew it to ``target`` (its first move starts from the pen-up position)."""
        self._split_ink(t)
        if self._servo is None:
            self._servo = ServoTrack(self._servo_min, t)
        self._servo.move(t, target, rate)
        self._servo_power_until = None if self._servo_timeout == 0 else t + self._servo_timeout / 1000.0
        self._servo_always_on = self._servo_timeout == 0
        self._sync_pen(t)

    def _pen_command(self, name: str, up: bool | None, duration_ms: int) -> None:
        def begin(t: float) -> None:
            new_up = (not self._pen_state_up) if up is None else up
            self._pen_state_up = new_up
            target = self._servo_min if new_up else self._servo_max
            rate = self._rate_up if new_up else self._rate_down
            self._servo_move(t, target, rate)

        self._queue(name, _Command(name, duration=duration_ms / 1000.0, begin=begin))

    def _cmd_SP(self, name: str, v: list) -> None:
        value, duration, _pin = v
        if value > 3 or (value > 1 and self.version < (3, 0, 1)):
            raise EbbError(6, error_text(6, self._fw3))
        if value >= 2:
            if value == 3:
                self._servo_max = self._servo_min
            self._pen_state_up = True
            self._servo_move(self._now, self._servo_min, self._rate_up)
            self._reply(name)
            return
        self._pen_command(name, value == 1, duration or 0)

    def _cmd_TP(self, name: str, v: list) -> None:
        (duration,) = v
        self._pen_command(name, None, duration or 0)

    def _cmd_S2(self, name: str, v: list) -> None:
        position, pin, rate, delay = v
        if position == 0:
            self._s2.pop(pin, None)
            self._reply(name)
            return

        def begin(t: float) -> None:
            self._s2[pin] = position
            if pin == 4:  # RP4 = RB1, the pen-lift servo output
                self._servo_move(t, position, rate or 0)
                self._pen_state_up = position == self._servo_min  # ebb.c: up only at exactly SC,4

        self._queue(name, _Command(name, duration=(delay or 0) / 1000.0, begin=begin))

    def _cmd_SC(self, name: str, v: list) -> None:
        param, value = v
        if param == 4:
            self._servo_min = value
        elif param == 5:
            self._servo_max = value
        elif param == 10:
            self._rate_up = self._rate_down = value
        elif param == 11:
            self._rate_up = value
        elif param == 12:
            self._rate_down = value
        self._split_ink(self._now)
        self._reply(name)

    def _cmd_SR(self, name: str, v: list) -> None:
        timeout, state = v
        self._servo_timeout = timeout
        if state is not None:
            if state:
                self._servo_power_until = None if timeout == 0 else self._now + timeout / 1000.0
                self._servo_always_on = timeout == 0
            else:
                self._servo_power_until = self._now
                self._servo_always_on = False
        self._reply(name)

    def _cmd_SE(self, name: str, v: list) -> None:
        state, power, queued = v
        if state > 1:
            raise EbbError(6, error_text(6, self._fw3))
        setting = (state, 512 if power is None else power)

        def begin(t: float) -> None:
            self._engraver = setting

        if queued:
            self._queue(name, _Command(name, begin=begin))
        else:
            begin(self._now)
            self._reply(name)

    # ---- queries ---------------------------------------------------------------------------------
    def _motors_moving(self) -> tuple[bool, bool]:
        return self._exec.moving if self._exec is not None else (False, False)

    def _cmd_V(self, name: str, v: list) -> None:
        text = f"EBBv13_and_above EB Firmware Version {self.firmware}"
        self._reply(name, text, legacy=text + "\r\n")

    def _cmd_QG(self, name: str, v: list) -> None:
        m1, m2 = self._motors_moving()
        bits = 0
        if self._fw3:  # bit 7: limit switch (no switch is fitted), bit 6: power lost
            bits |= 0x40 if self._power_lost_flag else 0
        else:
            bits |= 0xC0  # RB5 and RB2 inputs, pulled high
        bits |= 0x20 if self._button else 0
        bits |= 0x10 if self._pen_state_up else 0
        bits |= 0x08 if self._exec is not None else 0
        bits |= 0x04 if m1 else 0
        bits |= 0x02 if m2 else 0
        bits |= 0x01 if (self._exec is not None and self._fifo) else 0
        self._button = False
        self._power_lost_flag = False
        self._reply(name, f"{bits:02X}", legacy=f"{bits:02X}\r\n")

    def _cmd_QB(self, name: str, v: list) -> None:
        pressed = int(self._button)
        self._button = False
        self._reply(name, str(pressed), kind="ok", legacy=f"{pressed}\r\n" + self._ending("ok"))

    def _cmd_QM(self, name: str, v: list) -> None:
        m1, m2 = self._motors_moving()
        data = f"{int(self._exec is not None)},{int(m1)},{int(m2)},{int(bool(self._fifo))}"
        self._reply(name, data, legacy=f"QM,{data}\n\r")

    def _cmd_QP(self, name: str, v: list) -> None:
        state = int(self._pen_state_up)
        self._reply(name, str(state), legacy=f"{state}\n\r" + self._ending("ok"))

    def _cmd_QS(self, name: str, v: list) -> None:
        s1, s2 = self._steps_now(self._now)
        self._reply(name, f"{s1},{s2}", legacy=f"{s1},{s2}\n\r" + self._ending("ok"))

    def _cmd_QE(self, name: str, v: list) -> None:
        en = self._motors_enabled(self._now)
        ms = self._microsteps()
        data = f"{ms if en[0] else 0},{ms if en[1] else 0}"
        self._reply(name, data, legacy=data + "\r\n" + self._ending("ok"))

    def _cmd_QC(self, name: str, v: list) -> None:
        ra0 = 394
        vplus = int(round(max(self._vplus - 0.3, 0.0) / 9.2 / 3.3 * 1023)) if self._vplus > 0 else 0
        data = f"{ra0:04d},{vplus:04d}"
        self._reply(name, data, legacy=data + "\r\n" + self._ending("ok"))

    def _cmd_QR(self, name: str, v: list) -> None:
        powered = int(self._servo_always_on or (self._servo_power_until is not None and self._now < self._servo_power_until))
        self._reply(name, str(powered), legacy=f"{powered}\n\r" + self._ending("ok"))

    def _cmd_QL(self, name: str, v: list) -> None:
        (index,) = v
        value = self._vars[index or 0]
        self._reply(name, str(value), legacy=f"{value}\r\n" + self._ending("ok"))

    def _cmd_SL(self, name: str, v: list) -> None:
        value, index = v
        self._vars[index or 0] = value
        self._reply(name)

    def _cmd_QN(self, name: str, v: list) -> None:
        self._reply(name, str(self._node), legacy=f"{self._node}\r\n" + self._ending("ok"))

    def _cmd_SN(self, name: str, v: list) -> None:
        self._node = v[0]
        self._reply(name)

    def _cmd_NI(self, name: str, v: list) -> None:
        self._node = (self._node + 1) & 0xFFFFFFFF
        self._reply(name)

    def _cmd_ND(self, name: str, v: list) -> None:
        self._node = (self._node - 1) & 0xFFFFFFFF
        self._reply(name)

    def _cmd_QT(self, name: str, v: list) -> None:
        self._reply(name, self.nickname, legacy=self.nickname + "\r\n" + self._ending("ok"))

    def _cmd_ST(self, name: str, v: list) -> None:
        (text,) = v
        if len(text or "") > 16:
            raise EbbError(6, error_text(6, self._fw3))
        self.nickname = text or ""
        self._reply(name)

    def _cmd_QU(self, name: str, v: list) -> None:
        (param,) = v
        values = {1: "00", 2: str(MAX_FIFO), 3: str(self._fifo_size), 4: "E40", 5: "E40",
                  6: f"{len(self._fifo):02d}", 60: str(self._power_threshold), 61: str(self._stepper_timeout),
                  200: f"{self._acc[0]},{self._acc[1]}"}
        if param not in values:
            raise EbbError(6, error_text(6, self._fw3))
        data = values[param]
        self._reply(name, data, legacy=f"QU,{data}\r\n" + self._ending("ok"))

    # ---- configuration and I/O -------------------------------------------------------------------
    def _cmd_CU(self, name: str, v: list) -> None:
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
                raise EbbError(6, error_text(6, fw3))
            self._set_fifo_size(name, min(value, MAX_FIFO))
            return
        elif param == 50 and fw3:
            self._auto_enable = bool(value)
        elif param in (51, 52, 53) and fw3:
            if not 0 <= value <= 255:
                raise EbbError(6, error_text(6, fw3))
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
                raise EbbError(6, error_text(6, fw3))
            self._power_threshold = value
        elif param == 61 and fw3:
            if not 0 <= value <= 65534:
                raise EbbError(6, error_text(6, fw3))
            self._stepper_timeout = value
        self._reply(name)

    def _set_fifo_size(self, name: str, size: int) -> None:
        """CU,4 waits until the FIFO is empty and nothing executes, then resizes it."""
        def begin(t: float) -> None:
            self._fifo_size = size

        if self._exec is None and not self._fifo and self._blocked is None:
            begin(self._now)
            self._reply(name)
        else:
            self._queue(name, _Command(name, begin=begin))

    def _cmd_R(self, name: str, v: list) -> None:
        self._reply(name)
        self._stop_motion()
        self._init_state(power_up=False)

    def _cmd_RB(self, name: str, v: list) -> None:
        self._stop_motion()
        self._init_state(power_up=True)

    def _cmd_BL(self, name: str, v: list) -> None:
        self._stop_motion()
        self._dead = True
        log.warning("%s: entered the bootloader: no more replies until a reset", self.model)

    def _cmd_PD(self, name: str, v: list) -> None:
        port, pin, direction = v
        bit = 1 << pin
        self._ports.tris[port] = (self._ports.tris[port] | bit) if direction else (self._ports.tris[port] & ~bit)
        self._reply(name)

    def _cmd_PO(self, name: str, v: list) -> None:
        port, pin, value = v
        self._ports.set_latch(port, pin, value)
        self._reply(name)

    def _cmd_PI(self, name: str, v: list) -> None:
        port, pin = v
        self._motors_enabled(self._now)
        value = self._ports.pin(port, pin)
        self._reply(name, str(value), legacy=f"PI,{value}\r\n")

    def _cmd_I(self, name: str, v: list) -> None:
        self._motors_enabled(self._now)
        data = ",".join(f"{self._ports.read(p):03d}" for p in "ABCDE")
        self._reply(name, data, legacy=f"I,{data}\r\n")

    def _cmd_O(self, name: str, v: list) -> None:
        for port, value in zip("ABCDE", v):
            if value is not None:
                self._ports.lat[port] = value
        self._reply(name)

    def _cmd_C(self, name: str, v: list) -> None:
        for port, value in zip("ABCDE", v):
            self._ports.tris[port] = value
        self._reply(name)

    def _cmd_MR(self, name: str, v: list) -> None:
        data = f"{self._ram[v[0]]:03d}"
        self._reply(name, data, legacy=f"MR,{data}\r\n")

    def _cmd_MW(self, name: str, v: list) -> None:
        address, value = v
        self._ram[address] = value
        self._reply(name)

    def _cmd_AC(self, name: str, v: list) -> None:
        channel, enable = v
        if channel > 15:
            raise EbbError(6, error_text(6, self._fw3))
        (self._analog.add if enable else self._analog.discard)(channel)
        self._reply(name)

    def _cmd_A(self, name: str, v: list) -> None:
        vplus = int(round(max(self._vplus - 0.3, 0.0) / 9.2 / 3.3 * 1023)) if self._vplus > 0 else 0
        readings = {0: 394, 11: vplus}
        data = ",".join(f"{ch:02d}:{readings.get(ch, 23):04d}" for ch in sorted(self._analog))
        self._reply(name, data, legacy=f"A,{data}\r\n")

    def _cmd_CK(self, name: str, v: list) -> None:
        lines = [f"Param{k + 1}={value}" for k, value in enumerate(v)]
        if self._future:
            self._emit(("CK\n" + "".join(line + "\n" for line in lines)).encode())
        else:
            self._emit(("\r\n" + "".join(line + "\r\n" for line in lines) + self._ending("ok")).encode())


_DIR = P("u1")
# name -> (minimum firmware, parameter specs, handler)
_COMMANDS: dict[str, tuple[tuple[int, int, int], tuple[ParamSpec, ...], Callable]] = {
    "A": ((2, 2, 3), (), EbbSimulator._cmd_A),
    "AC": ((2, 2, 3), (P("u8"), _DIR), EbbSimulator._cmd_AC),
    "BL": ((1, 9, 5), (), EbbSimulator._cmd_BL),
    "C": ((0, 0, 0), (P("u8"),) * 5, EbbSimulator._cmd_C),
    "CK": ((0, 0, 0), (P("u8"), P("i8"), P("u16"), P("i16"), P("u32"), P("i32"), P("char"), P("uchar")),
           EbbSimulator._cmd_CK),
    "CS": ((2, 4, 3), (), EbbSimulator._cmd_CS),
    "CU": ((0, 0, 0), (P("u16"), P("i16")), EbbSimulator._cmd_CU),
    "EM": ((0, 0, 0), (P("u5"), P("u5", _OPT)), EbbSimulator._cmd_EM),
    "ES": ((2, 2, 7), (P("u1", _OPT),), EbbSimulator._cmd_ES),
    "HM": ((2, 6, 2), (_U32, P("i32", _OPT), P("i32", _OPT)), EbbSimulator._cmd_HM),
    "I": ((0, 0, 0), (), EbbSimulator._cmd_I),
    "L3": ((3, 0, 0), (_I32,) * 8 + (P("u2", _OPT),), EbbSimulator._cmd_L3),
    "LM": ((2, 7, 0), (_I32,) * 6 + (P("u2", _OPT),), EbbSimulator._cmd_LM),
    "LT": ((2, 7, 0), (_U32,) + (_I32,) * 4 + (P("u2", _OPT),), EbbSimulator._cmd_LT),
    "MR": ((0, 0, 0), (P("u4095"),), EbbSimulator._cmd_MR),
    "MW": ((0, 0, 0), (P("u4095"), P("u8")), EbbSimulator._cmd_MW),
    "ND": ((1, 9, 5), (), EbbSimulator._cmd_ND),
    "NI": ((1, 9, 5), (), EbbSimulator._cmd_NI),
    "O": ((0, 0, 0), (P("u8"),) + (P("u8", _OPT),) * 4, EbbSimulator._cmd_O),
    "PD": ((0, 0, 0), (P("port"), P("u3"), _DIR), EbbSimulator._cmd_PD),
    "PI": ((0, 0, 0), (P("port"), P("u3")), EbbSimulator._cmd_PI),
    "PO": ((0, 0, 0), (P("port"), P("u3"), _DIR), EbbSimulator._cmd_PO),
    "QB": ((1, 9, 2), (), EbbSimulator._cmd_QB),
    "QC": ((2, 2, 3), (), EbbSimulator._cmd_QC),
    "QE": ((2, 8, 0), (), EbbSimulator._cmd_QE),
    "QG": ((2, 6, 2), (), EbbSimulator._cmd_QG),
    "QL": ((1, 9, 2), (P("u31", _OPT),), EbbSimulator._cmd_QL),
    "QM": ((2, 4, 4), (), EbbSimulator._cmd_QM),
    "QN": ((1, 9, 2), (), EbbSimulator._cmd_QN),
    "QP": ((1, 9, 0), (), EbbSimulator._cmd_QP),
    "QR": ((2, 6, 0), (), EbbSimulator._cmd_QR),
    "QS": ((2, 4, 3), (), EbbSimulator._cmd_QS),
    "QT": ((2, 5, 4), (), EbbSimulator._cmd_QT),
    "QU": ((3, 0, 0), (P("u16"),), EbbSimulator._cmd_QU),
    "R": ((0, 0, 0), (), EbbSimulator._cmd_R),
    "RB": ((2, 5, 4), (), EbbSimulator._cmd_RB),
    "S2": ((2, 2, 0), (P("u16"), P("u24"), P("u16", _OPT), P("u16", _OPT)), EbbSimulator._cmd_S2),
    "SC": ((0, 0, 0), (P("u8"), P("u16")), EbbSimulator._cmd_SC),
    "SE": ((2, 1, 0), (P("u8"), P("u10", _OPT), P("u1", _OPT)), EbbSimulator._cmd_SE),
    "SL": ((1, 9, 2), (P("u8"), P("u31", _OPT)), EbbSimulator._cmd_SL),
    "SM": ((0, 0, 0), (_U32, _I32, P("i32", _OPT), P("u2", _OPT)), EbbSimulator._cmd_SM),
    "SN": ((1, 9, 5), (_U32,), EbbSimulator._cmd_SN),
    "SP": ((0, 0, 0), (P("u8"), P("u16", _OPT), P("u3", _OPT)), EbbSimulator._cmd_SP),
    "SR": ((2, 6, 0), (_U32, P("u1", _OPT)), EbbSimulator._cmd_SR),
    "ST": ((2, 5, 5), (P("text", _OPT),), EbbSimulator._cmd_ST),
    "T3": ((3, 0, 0), (_U32,) + (_I32,) * 6 + (P("u2", _OPT),), EbbSimulator._cmd_T3),
    "TD": ((3, 0, 1), (_U32,) + (_I32,) * 8 + (P("u2", _OPT),), EbbSimulator._cmd_TD),
    "TP": ((1, 9, 0), (P("u16", _OPT),), EbbSimulator._cmd_TP),
    "TR": ((3, 0, 0), (_U32, _I32, P("i32", _OPT), P("u2", _OPT)), EbbSimulator._cmd_TR),
    "V": ((0, 0, 0), (), EbbSimulator._cmd_V),
    "XM": ((2, 3, 0), (P("u32"), _I32, _I32, P("u2", _OPT)), EbbSimulator._cmd_XM),
}


def _machine(text: str) -> str:
    value = text.strip().lower().replace("-", "_")
    if value not in TRAVEL_MM:
        raise ValueError(f"expected one of {', '.join(TRAVEL_MM)}")
    return value


def _firmware(text: str) -> str:
    parse_version(text)
    return text.strip()


def _syntax(text: str) -> str:
    value = text.strip().lower()
    if value not in ("legacy", "future"):
        raise ValueError("expected legacy or future")
    return value


def _width(text: str) -> float:
    value = float(text)
    if not (math.isfinite(value) and value > 0):
        raise ValueError("expected a width in mm > 0")
    return value


def _pulse(text: str) -> int:
    if not ascii_digits(text.strip()) or not 1 <= int(text) <= 65535:
        raise ValueError("expected a servo pulse width 1..65535 (units of 83.3 ns)")
    return int(text)


def _colour(text: str) -> str:
    from pixelpen.display.picture import parse_colour

    parse_colour(text)
    return text


def _factory(sim_model: str) -> Callable[..., EbbSimulator]:
    def create(clock: Clock | None = None, **options: str) -> EbbSimulator:
        """Simulator factory for ``sim:axidraw?...`` / ``sim:ebb?...`` URLs (see the module docstring)."""
        if "machine" in options and "model" in options:
            raise URLError(f"sim:{sim_model}: give the AxiDraw model once (model= or its alias machine=)")
        if "machine" in options:  # alias: create_simulator's own first parameter is called model
            options = {("model" if k == "machine" else k): v for k, v in options.items()}
        values = read_options(sim_model, options, {
            "model": (_machine, "v3"),
            "firmware": (_firmware, "3.0.2"),
            "syntax": (_syntax, "legacy"),
            "pen_colour": (_colour, "black"),
            "pen_width": (_width, 0.3),
            "contact": (_pulse, CONTACT_DEFAULT),
        })
        machine = values.pop("model")
        try:
            return EbbSimulator(clock, model=sim_model, machine=machine, **values)  # type: ignore[arg-type]
        except (ConfigError, ValueError) as exc:
            raise URLError(f"sim:{sim_model}: {exc}") from None

    create.__name__ = f"create_{sim_model}"
    return create


register_simulator("axidraw", _factory("axidraw"))
register_simulator("ebb", _factory("ebb"))

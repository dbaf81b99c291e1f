"""The EiBotBoard's state and motion engine: the FIFO of motion commands, step counters, carriage and ink.

Motion commands enter a FIFO (depth 1 at boot, ``CU,4,n``): one executes while ``n`` wait.  The paper:
AxiDraw mixed axes (motor1 = A+B, motor2 = A−B) at 80 steps/mm per axis in 1/16 stepping (halved per
coarser EM mode), x right, y down, origin at the home corner (top left).  Ink is recorded once per move
(and where a pen or motor change splits one).  Timing is exact to the 40 µs tick.  ``EbbMachine`` is the
base the parser and the command groups build on (see ``board.py`` for the whole board).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from pixelpen.clock import Clock
from pixelpen.errors import ConfigError
from pixelpen.sim.base import SimulatedDevice
from pixelpen.sim.plotters.ebb.motion import TICK, AccumulatorAxis
from pixelpen.sim.plotters.ebb.params import parse_version
from pixelpen.sim.plotters.ebb.pen import CONTACT_DEFAULT, SERVO_BOOT, SERVO_BOOT_OLD, PenServo
from pixelpen.sim.plotters.ebb.ports import SERVO_POWER_PIN, Ports
from pixelpen.sim.plotters.sheet import Sheet, WireStats, clamp_path

if TYPE_CHECKING:
    from pixelpen.sim.plotters.ebb.commands import CommandEntry

__all__ = ["MAX_FIFO", "RA0_READING", "SUPPLY_VOLTS", "TRAVEL_MM", "EbbMachine", "MotionCommand"]

TRAVEL_MM = {
    "v2": (300.0, 218.0), "v3": (300.0, 218.0), "se_a4": (300.0, 218.0), "a3": (430.0, 297.0),
    "se_a3": (430.0, 297.0), "xlx": (595.0, 218.0), "minikit": (160.0, 101.6), "se_a1": (864.0, 594.0),
    "se_a2": (594.0, 432.0), "b6": (190.0, 140.0),
}
"""AxiDraw travel by model (axidraw_conf.py via plotters.md §2.3)."""

MAX_FIFO = 32
"""QU,2 on this simulated build."""
STEPS_PER_MM_16 = 80.0
"""Steps per mm per mixed axis at 1/16 microstepping."""
SUPPLY_VOLTS = 9.0
"""V+ with the motor supply plugged in."""
RA0_READING = 394
"""What the ADC reads on RA0 (the current-set pot)."""


@dataclass
class MotionCommand:
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

    @property
    def moves(self) -> bool:
        """True for a move (steps the motors), False for a delay, pen or configuration entry."""
        return self.axes is not None or self.linear is not None

    def steps_by(self, t: float) -> tuple[int, int]:
        """Signed motor steps taken by time ``t`` (all of them once the command has ended)."""
        ticks = self.ticks if self.linear is None else round(self.duration / TICK)
        done = min(math.floor((t - self.t0) / TICK + 1e-6), ticks)
        if self.linear is not None:
            # step k of N falls on tick ceil(k·T/N): after `done` ticks, floor(done·N/T) steps
            s1, s2 = (int(math.copysign(abs(n) * done // ticks, n)) if ticks else n for n in self.linear)
            return s1, s2
        if self.axes is not None:
            a1, a2 = self.axes
            return a1.direction * a1.steps_at(done), a2.direction * a2.steps_at(done)
        return 0, 0


class EbbMachine(SimulatedDevice):
    """The board's state after UserInit, its motion engine on the clock, and the paper under the pen."""

    COMMANDS: ClassVar[Mapping[str, CommandEntry]]
    """The command table the parser dispatches through (set by the board class)."""

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
        self.contact_pulse = contact
        """Servo pulse width (83.3 ns units) below which the pen touches the paper."""
        self._servo_defaults = SERVO_BOOT if self.version >= (2, 6, 0) else SERVO_BOOT_OLD
        super().__init__(clock)
        width, height = TRAVEL_MM[machine]
        self._paper = Sheet(width, height, y_down=True, pen_colours={1: pen_colour}, pen_width_mm=pen_width)
        self.stats = WireStats()
        self.log: list[tuple[float, str]] = []
        self.nickname = ""
        self._inbox = bytearray()
        self._inpos = 0
        self._xy: np.ndarray = np.zeros(2)  # carriage position on the paper, mm
        self._vplus = SUPPLY_VOLTS
        self._dead = False
        self._ever_moved = False
        self._init_state(power_up=True)

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
        self._fifo: deque[MotionCommand] = deque()
        self._exec: MotionCommand | None = None
        self._blocked: deque[tuple[MotionCommand, bytes]] = deque()
        self._line = bytearray()
        self._in_cr = False
        self._steps = [0, 0]
        self._acc = [0, 0]
        self._pen = PenServo(self._servo_defaults, self.contact_pulse)
        self._node = 0
        self._vars = [0] * 32
        self._ports = Ports()
        self._ram = bytearray(4096)
        self._analog: set[int] = {0, 11} if self._fw3 else set()  # 3.x EBB_Init: AnalogConfigure RA0, V+
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
        return STEPS_PER_MM_16 * self._ports.microsteps() / 16

    def _pins_at(self, t: float) -> Ports:
        """The port pins as they read at ``t``: after the stepper timeout, with RA3 showing servo power."""
        self._motors_enabled(t)
        self._ports.set_latch(*SERVO_POWER_PIN, int(self._pen.powered(t)))
        return self._ports

    def _motors_enabled(self, t: float) -> list[bool]:
        """Motor enables as the pins read, after the CU,61 stepper timeout has had its say."""
        if self._stepper_timeout and self._exec is None and t - self._last_motion_end > self._stepper_timeout:
            self._ports.set_enables(False, False)
        return self._ports.enables()

    def _vplus_reading(self) -> int:
        """V+ as the ADC reads it through the board's 9.2:1 divider (0 when unpowered)."""
        return round(max(self._vplus - 0.3, 0.0) / 9.2 / 3.3 * 1023) if self._vplus > 0 else 0

    def _motors_moving(self) -> tuple[bool, bool]:
        return self._exec.moving if self._exec is not None else (False, False)

    # ---- time and engine (the SimulatedDevice hooks) ---------------------------------------------
    def _next_internal_event(self) -> float | None:
        """When the executing motion command ends (None when the engine is idle)."""
        return None if self._exec is None else self._exec.t0 + self._exec.duration

    def _idle_to(self, t: float) -> None:
        """Bring the paper's pen in line with the servo while the carriage stands still.

        A move is inked as one segment when it ends, or up to the moment something changes the pen or
        the motors under it (``_split_ink``), so time passing within a move costs nothing.
        """
        cmd = self._exec
        if cmd is None or not cmd.moves:
            self._sync_pen(t)
        self._now = t

    def _shutdown(self) -> None:
        self._stop_motion()

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
        if cmd.moves:
            self._ever_moved = True
        if cmd.duration <= 0:
            self._handle_event(t)

    def _handle_event(self, t: float) -> None:
        """The executing command ends at ``t``: count its steps, ink its track, start the next one."""
        cmd = self._exec
        assert cmd is not None
        self._ink(cmd, self._inked_until, t)
        self._now = max(self._now, t)
        self.stats.moving_time += cmd.duration
        d1, d2 = cmd.steps_by(t)
        self._apply_steps(d1, d2, t)
        if cmd.axes is not None:
            for k in range(2):
                self._acc[k] = cmd.axes[k].remainder(min(cmd.ticks, cmd.ends[k]))
        self._exec = None
        if cmd.moves or cmd.duration > 0:
            self._last_motion_end = t
        self._start_next(t)
        if self._exec is None and not self._fifo and self._ever_moved:
            self._idle_since = t
        self._sync_pen(t)

    def _apply_steps(self, d1: int, d2: int, t: float) -> None:
        self._steps[0] += d1
        self._steps[1] += d2
        self._xy = self._xy_after(self._xy, d1, d2, t)

    def _xy_after(self, xy: np.ndarray, d1: float, d2: float, t: float) -> np.ndarray:
        e1, e2 = self._motors_effective(t)
        spm = self._steps_per_mm()
        dx = (d1 * e1 + d2 * e2) / 2.0 / spm
        dy = (d1 * e1 - d2 * e2) / 2.0 / spm
        hi = np.array([self._paper.width_mm, self._paper.height_mm])
        clipped: np.ndarray = np.clip(xy + np.array([dx, dy]), 0.0, hi)
        return clipped

    def _motors_effective(self, t: float) -> tuple[float, float]:
        if self._vplus < 6.0:
            return 0.0, 0.0
        en = self._motors_enabled(t)
        return float(en[0]), float(en[1])

    def _steps_now(self, t: float) -> tuple[int, int]:
        if self._exec is None:
            return self._steps[0], self._steps[1]
        d1, d2 = self._exec.steps_by(t)
        return self._steps[0] + d1, self._steps[1] + d2

    def _xy_at(self, t: float) -> np.ndarray:
        if self._exec is None:
            here: np.ndarray = self._xy.copy()
            return here
        d1, d2 = self._exec.steps_by(t)
        return self._xy_after(self._xy, d1, d2, t)

    def _stop_motion(self) -> bool:
        """ES: stop the executing command where it is and flush the FIFO; True if anything was stopped."""
        interrupted = self._exec is not None or bool(self._fifo)
        if self._exec is not None:
            cmd = self._exec
            self._ink(cmd, self._inked_until, self._now)
            d1, d2 = cmd.steps_by(self._now)
            self._apply_steps(d1, d2, self._now)
            self._exec = None
            self._last_motion_end = self._now
        self._fifo.clear()
        return interrupted

    # ---- pen and paper ---------------------------------------------------------------------------
    def _servo_move(self, t: float, target: float, rate: float) -> None:
        """Slew the pen servo at ``t``, inking what went before and lifting or lowering the paper's pen."""
        self._split_ink(t)
        self._pen.slew(t, target, rate)
        self._sync_pen(t)

    def _sync_pen(self, t: float) -> None:
        down = self._pen.touches(t)
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

    def _ink(self, cmd: MotionCommand, ta: float, tb: float) -> None:
        """Record the carriage's track during ``cmd`` from ta to tb, pen-down parts only."""
        if tb <= ta or not cmd.moves:
            return
        tc = self._pen.contact_change(ta, tb)
        spans = [(ta, tc), (tc, tb)] if tc is not None else [(ta, tb)]
        for a, b in spans:
            mid = 0.5 * (a + b)
            if not self._pen.touches(mid):
                self._paper.pen_up()
                continue
            pts = self._track(cmd, a, b)
            self._paper.pen_down(pts[0])
            self._paper.line_to(pts)

    def _track(self, cmd: MotionCommand, ta: float, tb: float) -> np.ndarray:
        """Carriage positions (mm) along ``cmd`` between ta and tb, clamped at the ends of travel.

        A constant-rate move is a straight line (its exact clamped path); an accelerated one is
        sampled 33 times from the accumulator's closed form.
        """
        hi = np.array([self._paper.width_mm, self._paper.height_mm])
        e1, e2 = self._motors_effective(ta)
        spm = self._steps_per_mm()
        if cmd.linear is not None or cmd.axes is None:
            d = np.array([cmd.steps_by(ta), cmd.steps_by(tb)], dtype=np.float64)
        else:
            ticks = np.clip(np.floor((np.linspace(ta, tb, 33) - cmd.t0) / TICK + 1e-6), 0, cmd.ticks).astype(int)
            d = np.array([[ax.direction * ax.steps_at(k) for ax in cmd.axes] for k in ticks.tolist()], dtype=np.float64)
        xy = self._xy + np.column_stack([(d[:, 0] * e1 + d[:, 1] * e2), (d[:, 0] * e1 - d[:, 1] * e2)]) / (2 * spm)
        if len(xy) == 2:
            return clamp_path(xy[0], xy[1], np.zeros(2), hi)
        return np.clip(xy, 0.0, hi)

"""The machine GRBL drives: planner timing, holds, soft limits, homing, machine state, and the pen on paper.

``GrblMachine`` is the simulator's lower half, on :class:`~pixelpen.sim.base.SimulatedDevice`: the clock
and its events (a block ends, a hold stops, the door restore, homing), the feed-hold/resume state
machine, ``mc_line`` with its soft-limit check, ``$H``, and how the pen (a servo on the spindle output, or
the Z axis) inks the paper along each block.  The command layers above it (``execute``, ``realtime``,
``system``) and the line protocol (``controller``) call into it.
"""

from __future__ import annotations

import logging
from abc import abstractmethod
from collections.abc import Generator
from dataclasses import dataclass

import numpy as np

from pixelpen.clock import Clock
from pixelpen.sim.base import SimulatedDevice
from pixelpen.sim.plotters.grbl.modal import GcodeState, Persistent
from pixelpen.sim.plotters.grbl.planner import AxisLimits, Block, Planner
from pixelpen.sim.plotters.grbl.settings import default_settings
from pixelpen.sim.plotters.sheet import Sheet, WireStats, clamp_path

__all__ = ["PEN_MODES", "RESUMED", "ROOM", "SYNC", "GrblMachine", "MovePayload", "Wait"]

log = logging.getLogger("pixelpen.sim.plotters.grbl.controller")
"""The simulator's one logger, under the name it had before the split (every module of the package logs here)."""

PEN_MODES = ("servo", "servo-inverted", "z")
"""How the pen is driven: a servo on the spindle output (down at high or at low output), or the Z axis."""

ROOM, SYNC, RESUMED = "room", "sync", "resumed"
"""What a line task waits for: planner room, an empty planner at rest (a buffer sync), the end of a hold."""
Wait = str | float
"""What a line task yields: ROOM, SYNC, RESUMED or a clock time (a dwell's end)."""


@dataclass
class MovePayload:
    """What a planner block carries for the simulator: the spindle it runs with and the work Z offset."""

    spindle: int
    speed: float
    wco_z: float
    rapid: bool


class GrblMachine(SimulatedDevice):
    """GRBL's machine side: motion on the clock, holds, limits, homing, state names, pen and paper."""

    model = "grbl"
    _wait: Wait | None
    """What the running line task waits for (the controller's main loop sets it)."""

    def __init__(
        self, clock: Clock | None, *, size: tuple[float, float], pen: str, pen_threshold: float, planner: int,
        pen_colour: str, pen_width: float,
    ) -> None:
        super().__init__(clock)
        self.pen_mode = pen
        self.pen_threshold = float(pen_threshold)
        self.settings: dict[int, float] = default_settings(size)
        self.persistent = Persistent()
        self.paper = Sheet(size[0], size[1], y_down=False, pen_colours={1: pen_colour}, pen_width_mm=pen_width)
        self.stats = WireStats()
        self.log: list[tuple[float, str]] = []
        self.planner = Planner(planner - 1, self._limits, lambda: (self.feed_ovr, self.rapid_ovr))
        self._phys_offset = np.zeros(3)
        self._mpos = np.zeros(3)
        self._ever_moved = False
        self._alarm = self._sleep = False
        self._z_parked = True

    def _reset_machine(self, power_up: bool, keep_alarm: bool) -> None:
        """The machine state after power-up or a soft reset (the position is kept; a reboot keeps the alarm)."""
        self._wait = None
        self.planner.clear()
        self.gc = GcodeState()
        self.gc.coord_system = self.persistent.coords[0].copy()
        self.gc.position = self._mpos.copy()
        self.feed_ovr, self.rapid_ovr, self.spindle_ovr = 100.0, 100.0, 100.0
        self._spindle_state, self._spindle_speed = 5, 0.0
        self._flood = self._mist = False
        self._hold: str | None = None  # "hold", "m0", "door", "door-resuming", "jog-cancel", "soft-limit"
        self._door_restore_at: float | None = None
        self._door_spindle_off = False
        self._spindle_stop_ovr = False
        self._check = False
        self._sleep = False
        self._critical = False
        self._homing_until: float | None = None
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

    @abstractmethod
    def _boot(self, power_up: bool) -> None:
        """Initialise as main() does after power-up or a reset, and print the welcome message."""

    @abstractmethod
    def _queue_startup_lines(self) -> None:
        """Run the stored ``$N`` startup lines next (after a boot or homing)."""

    @abstractmethod
    def _drop_task(self) -> None:
        """Forget the line being executed (a critical alarm)."""

    # ---- SimulatedDevice's event loop ------------------------------------------------------------
    def _handle_event(self, t: float) -> None:
        self._set_time(t)
        self._handle_events()

    def _idle_to(self, t: float) -> None:
        self._set_time(t)

    def _shutdown(self) -> None:
        self._abort_motion()

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

    def _start_cycle(self) -> None:
        if self._idle_since is not None:
            self.stats.starved_time += self._now - self._idle_since
            self._idle_since = None
        self._ever_moved = True
        if self.planner.start(self._now):
            self._apply_block_spindle(self.planner.blocks[0])

    # ---- holds -----------------------------------------------------------------------------------
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

    # ---- motion ----------------------------------------------------------------------------------
    def _payload(self, rapid: bool, laser_on: bool = False) -> MovePayload:
        speed = self.gc.spindle_speed if (not self._flag(32) or laser_on) else 0.0
        return MovePayload(self.gc.spindle, speed, float(self.gc.wco()[2]), rapid)

    def _spindle_sync(self, state: int, speed: float) -> Generator[Wait, None, None]:
        if self._check:
            return
        yield SYNC
        self._spindle_state, self._spindle_speed = state, speed
        self._pen_update()

    def _line_motion(
        self, start: np.ndarray, target: np.ndarray, *, rapid: bool, payload: MovePayload, feed: float = 0.0,
    ) -> Generator[Wait, None, int]:
        """mc_line: soft-limit check, wait for planner room, queue the block."""
        if self._flag(20) and not self._jogging and self._outside_travel(target):
            yield from self._soft_limit()
            return -1
        if self._check:
            return 0
        yield ROOM
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
                yield RESUMED
        else:
            self._flush_after_stop()
            self._raise_critical(2)

    def _raise_critical(self, code: int) -> None:
        self._soft_limit_pending = False
        self._abort_motion()
        self._alarm = True
        self._critical = True
        self._drop_task()
        self._emit(f"ALARM:{code}\r\n[MSG:Reset to continue]\r\n".encode())
        log.warning("grbl: ALARM:%d (critical: reset required)", code)

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
        self._homing_until = self._now + duration
        self._homing_duration = duration

    def _homing_position(self, t: float) -> np.ndarray:
        f = min(max((t - self._homing_t0) / self._homing_duration, 0.0), 1.0) if self._homing_duration else 1.0
        phys: np.ndarray = self._homing_start * (1.0 - f) - self._phys_offset
        return phys

    def _finish_homing(self) -> None:
        start_m = self._homing_start - self._phys_offset
        block = Block(start_m, np.zeros(3) - self._phys_offset, data=self._payload(rapid=True))
        self._ink(block, 0.0, block.length)
        self._homing_until = None
        self._phys_offset = np.zeros(3)
        self._mpos = np.zeros(3)
        self.gc.position = np.zeros(3)
        self._alarm = False
        self._queue_startup_lines()

    # ---- machine state ---------------------------------------------------------------------------
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
        if not self._flag(32) or not isinstance(block.data, MovePayload):
            return
        self._pen_update(block)

    def _pen_down_for(self, block: Block | None) -> bool | None:
        """Servo pen: is it down for ``block`` (None: at rest)?  None for the Z pen (depends on Z)."""
        if self.pen_mode == "z":
            return None
        if block is not None and self._flag(32) and isinstance(block.data, MovePayload):
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
            wco_z = block.data.wco_z if isinstance(block.data, MovePayload) else 0.0
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
        return bool(z0 + dz * s <= 1e-9)

    if abs(dz) < 1e-15:
        return [(s0, s1)] if down(s0) else []
    s_cross = -z0 / dz
    if s0 < s_cross < s1:
        return [(s0, s_cross)] if down(s0) else [(s_cross, s1)]
    return [(s0, s1)] if down(0.5 * (s0 + s1)) else []

"""AxiDraw driver (``axidraw:PORT``): the EiBotBoard over USB serial, moves planned and sliced on the host.

URL: ``axidraw:/dev/ttyACM0?model=se_a3&moves=lm`` (PORT is a device path, a pyserial URL in brackets, or
``auto`` for the first USB serial port with the EBB's ID 04D8:FD92); ``sim:axidraw?speed=fast`` plots on
the simulator.  ``model=`` picks the profile: ``v3`` (default; also V2 and SE/A4), ``se_a3``, ``minikit``.

Each stroke is a pen-up travel, two 1 ms pauses, ``SP,0,<drop ms>``, the stroke, ``SP,1,<lift ms>``.  Travel and
stroke are planned with the vector engine's motion model (:func:`pixelpen.vector.motion.plan`: trapezoids,
junction deviation at corners) with the profile's pen-up and pen-down limits and emitted as time slices of at
most 25 ms (``SM``, ``XM`` or ``LM``, option ``moves=``), steps rounded with their fractions carried.  The servo
rates are set as pyaxidraw does (``SC,11`` raise / ``SC,12`` lower, fw >= 2.6.0; default 400, the firmware's
boot value) and each SP delay covers the slew (|SC,4 − SC,5| × 24 ms / rate) or the profile's pen time.

How a stroke is confirmed.  A motion command's ``OK`` comes when it enters the board's motion FIFO, not when
it runs.  The FIFO holds one command at boot and one more executes, so when the ``OK`` of the n-th queued
command arrives every queued command up to n − 2 has finished: a stroke is confirmed once the command
count acknowledged passes its pen lift by two.  At the end of a job (and before a pause) ``QM`` is polled
until the motion system is idle, which confirms everything sent.  One command is in flight at a time
(``WINDOW``): a command the board refuses (a byte garbled on the wire) is sent again in its place, since
nothing behind it has reached the board; refused ``RETRIES`` more times, ``ES`` stops the FIFO and the plot
stops with its stroke marked damaged.

Pause: the PRG button (``QG`` bit 5, or ``QB`` on firmware before 2.6.2), polled at most every 50 ms
between strokes, pauses the plot with the pen up; a second press resumes it.

Motor power.  Without V+ the motors stand still while the board goes on counting steps, so the carriage is
no longer where the counters say.  ``QC`` is read at connect (as pyaxidraw does); inside a stroke a supply check
follows every queued command, written together with it (``QG``, whose bit 6 latches any drop below the
``CU,60`` threshold, on fw >= 3; ``QC`` before).  Two checks in a row bracket exactly one queued command, so a
failure is placed to that command: the moves still queued are stopped (``ES``), the last place reached with
the motors powered is acknowledged to the base (``_acknowledged``), and the plot stops (Disconnected) with the
position lost; after the carriage is put home and the position confirmed, the resume draws from that place.
The two pauses before each pen-down let the checks certify the travel first: the pen never goes down where
the motors stopped short.  A reading below ``VPLUS_MIN_RAW`` (plotink's 250 counts, about 7.7 V) counts as
no supply.

After a fault (``_where``): the board runs its FIFO out (``QM``), then ``QS`` gives the carriage in steps,
``QG``/``QP`` the pen, ``QE`` whether the motors stayed on at 1/16 (off, or a rebooted board: position lost),
``QC`` the supply.  An interrupted job leaves the motors on (as a pyaxidraw pause does) so a later session can
still read the position from the counters.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from typing import Any, ClassVar

import numpy as np

from pixelpen.devices.plotters.base import DeviceWhere, PlotterDisplay
from pixelpen.devices.plotters.ebb_encode import (
    EBB_USB_ID,
    FEATURES,
    SERVO_RATE_DEFAULT,
    VPLUS_MIN_RAW,
    move_commands,
    parse_qg,
    servo_move_ms,
    servo_positions,
    servo_rate_commands,
    slice_polyline,
    strip_name,
    supports,
    vplus_volts,
)
from pixelpen.devices.plotters.ebb_stream import QG_POWER_LOST, EBBStream, Progress
from pixelpen.devices.plotters.resume import ResumePoint
from pixelpen.display.registry import register_display
from pixelpen.drivers.discovery import list_serial_ports
from pixelpen.drivers.stream import Link
from pixelpen.errors import ConfigError, LinkError, ParseError, ProtocolError
from pixelpen.options import OptionSpec, OptionValues, choice, number
from pixelpen.profiles.model import DeviceProfile, load_profile

log = logging.getLogger(__name__)

__all__ = ["MODELS", "AxiDrawPlotter", "find_ebb_port"]

MODELS = {"v3": "axidraw_v3", "v2": "axidraw_v3", "se_a4": "axidraw_v3", "se_a3": "axidraw_se_a3",
          "a3": "axidraw_se_a3", "minikit": "axidraw_minikit"}
"""``model=`` values and the profile each one uses."""
SLICE_S = 0.025
"""Longest motion slice (pyaxidraw's SM slices are 25 ms)."""
BUTTON_POLL_S = 0.05
"""Least time between two button polls (pyaxidraw: QB at least 50 ms apart)."""
USB_BAUD = 12_000_000
"""Line speed of a ``sim:axidraw`` link without ``baud=`` (USB full speed, not a serial port's 9600)."""
FLUSH = "#"
"""Sent alone before the first command: ends any half-received command as a syntax error, so it cannot run."""
MICROSTEPS = 16
"""``EM,1,1``: 1/16 stepping, what QE reports for an enabled motor."""


def _model(text: str) -> str:
    """An AxiDraw model name (``se-a3`` spelled either way)."""
    return _MODEL_NAMES(text.replace("-", "_"))


_MODEL_NAMES = choice(*MODELS)


@register_display("axidraw")
class AxiDrawPlotter(EBBStream):
    """An AxiDraw (EiBotBoard): host-planned sliced moves, servo pen, FIFO-count confirmation, button pause."""

    profile_name: ClassVar[str] = "axidraw_v3"
    family: ClassVar[str] = "axidraw"
    reports_position: ClassVar[bool] = True
    restarts_at_home: ClassVar[bool] = True
    """After a supply failure the carriage is pushed home and ``_rehomed`` clears the counters there: what the
    supply checks certified (``_acknowledged``) is on paper, and a confirmed resume continues from its end."""
    OPTIONS = (
        *PlotterDisplay.OPTIONS,
        OptionSpec("model", _model, "v3", f"AxiDraw model: {', '.join(MODELS)}"),
        OptionSpec("moves", choice("sm", "xm", "lm"), "sm",
                   "motion commands: sm, xm (mixed-axis, fw >= 2.3.0) or lm (accelerated, fw >= 2.7.0)"),
        OptionSpec("pen_up", number(0.0, 100.0), None,
                   "pen-up servo position in percent of the profile's servo range; default the profile's"),
        OptionSpec("pen_down", number(0.0, 100.0), None, "pen-down servo position in percent; default the profile's"),
    )

    def __init__(
        self,
        port: str,
        *,
        profile: DeviceProfile,
        moves: str = "sm",
        pen_up_percent: float | None = None,
        pen_down_percent: float | None = None,
        pen_rate_up: int = SERVO_RATE_DEFAULT,
        pen_rate_down: int = SERVO_RATE_DEFAULT,
        **kwargs: Any,
    ) -> None:
        super().__init__(port, profile=profile, **kwargs)
        if moves not in ("sm", "xm", "lm"):
            raise ConfigError(f"axidraw: moves must be sm, xm or lm, got {moves!r}")
        self.moves = moves
        self.servo_up, self.servo_down = servo_positions(profile.servo, pen_up_percent, pen_down_percent)
        self.servo_rates = (pen_rate_up, pen_rate_down)
        servo_rate_commands(pen_rate_up, pen_rate_down)  # refuse bad rates here, not at connect
        self.steps_per_mm = profile.steps_per_mm or 1.0 / profile.unit_mm
        self.version: tuple[int, int, int] | None = None
        """Firmware version from ``V``."""
        self.future_syntax = False
        """True when the board answers in the future syntax (``CU,10,1``)."""
        self.position = np.zeros(2, dtype=np.int64)
        """Carriage position in steps (x right, y down) after every command sent."""
        self._unanswered = deque()
        self._queued_acked = 0
        self._queued_sent = 0
        self._marks: deque[tuple[int, int]] = deque()
        self._paused = False
        self._button_asked = -math.inf
        self._zeroed = False
        self._adopt: np.ndarray | None = None
        self._lost: str | None = None
        self._reached: tuple[int, int] | None = None
        self._stroke_now: int | None = None
        self._power_good = 0
        """Queued commands (counted like ``_queued_sent``) known to have finished with the motor supply on."""
        self._progress = deque()
        self._certified: Progress | None = None
        self._cut: Progress | None = None

    # -- URL hooks -------------------------------------------------------------------------------
    @classmethod
    def default_profile(cls, options: OptionValues) -> DeviceProfile:
        """``model=`` picks among the AxiDraw profiles."""
        return load_profile(MODELS[options["model"]])

    @classmethod
    def family_options(cls, options: OptionValues, profile: DeviceProfile) -> dict[str, Any]:
        """Read moves, pen_up and pen_down from the URL."""
        return {"moves": options["moves"], "pen_up_percent": options["pen_up"], "pen_down_percent": options["pen_down"]}

    @classmethod
    def simulator_options(
        cls, sim_options: dict[str, str], options: OptionValues, profile: DeviceProfile,
    ) -> dict[str, str]:
        """The simulated AxiDraw of the same model (the EBB simulator has no paper option: it is the travel).

        The board is USB CDC: its simulated line runs at ``USB_BAUD`` unless the URL gives ``baud``.
        """
        out = {k: v for k, v in sim_options.items() if k != "paper"}
        out.setdefault("baud", str(USB_BAUD))
        if "model" in options.given:
            out.setdefault("model", options["model"])
        return out

    def _make_link(self) -> Link:
        if self.port == "auto" and self._link_factory is None:
            self.port = find_ebb_port()
        return super()._make_link()

    def _rehomed(self) -> None:
        """The carriage was pushed home after the board lost count of it: clear the step counters there (EM)."""
        self._command("EM,1,1", queued=self.version is not None and supports(self.version, "queued_EM"))
        self.position = np.zeros(2, dtype=np.int64)
        self._zeroed = True
        self._cut = None

    # -- device core -----------------------------------------------------------------------------
    def _connect(self) -> None:
        """Flush a half command, read ``V``, wait out leftover motion, set 16× stepping and the pen servo."""
        link = self._link()
        self._reset_counts()
        self._paused = False
        link.reset_input()
        link.write(f"{FLUSH}\rV\r".encode("ascii"))
        self.version, self.future_syntax = self._await_version()
        if not supports(self.version, "QM"):
            raise ProtocolError(
                f"EBB firmware {_v(self.version)} is too old: pixelpen needs 2.4.4 or newer (QM); update the firmware",
                code="version", command="V", device="axidraw",
            )
        needs = {"xm": "XM", "lm": "LM"}.get(self.moves)
        if needs and not supports(self.version, needs):
            raise ConfigError(
                f"axidraw: moves={self.moves} needs EBB firmware {_v(FEATURES[needs])} or newer; this board has "
                f"{_v(self.version)} (use moves=sm)"
            )
        self._wait_idle(60.0)
        adopt, self._adopt = self._adopt, None
        if adopt is not None:  # _where found the board as the fault left it, motors on: keep its counters
            self.position = adopt
            log.info("axidraw: reconnected; carriage at %s steps", self.position.tolist())
        elif self._zeroed and supports(self.version, "QS"):
            self.position = self._query_steps()
            log.info("axidraw: reconnected; carriage at %s steps", self.position.tolist())
        else:
            self._command("EM,1,1", queued=self.version is not None and supports(self.version, "queued_EM"))
            self.position = np.zeros(2, dtype=np.int64)
            self._zeroed = True
        self._command(f"SC,4,{self.servo_up}")
        self._command(f"SC,5,{self.servo_down}")
        if supports(self.version, "SC_rates"):
            for command in servo_rate_commands(*self.servo_rates):
                self._command(command)
        if supports(self.version, "queued_EM"):
            self._command(f"CU,60,{VPLUS_MIN_RAW}")  # latch a supply drop in QG bit 6 between checks
        self._certified = Progress(0, (int(self.position[0]), int(self.position[1])), False, None)
        self._pen(up=True)
        self._flush_replies()
        self._supply(self._query_vplus(), self._queued_sent)  # as pyaxidraw does: refuse a board without motor power

    def _send_stroke(self, index: int, points: np.ndarray, pen: int) -> None:
        """Travel, a supply check, pen down, the stroke (a supply check behind every slice), pen up, ``QG``."""
        pts = np.asarray(points, dtype=np.int64).reshape(-1, 2)
        self._stroke_now = index
        self._travel(pts[0])
        self._power_gate()
        self._pen(up=False, reached=(index, 0))
        if len(pts) > 1:
            self._move(pts, self.profile.pen_down, stroke=index)
        self._pen(up=True, reached=(index, len(pts) - 1))
        self._marks.append((self._queued_sent, index))
        self._stroke_now = None
        self._status_check()

    def _poll(self) -> None:
        link = self._link()
        while self._unanswered and link.in_waiting:
            self._read_reply()

    def _drain(self) -> None:
        self._flush_replies()
        self._wait_idle(max(self.timeout, 5.0))
        self._supply(self._query_vplus(), self._queued_sent)  # idle: everything sent has run
        self._cut = None
        while self._marks:
            _, index = self._marks.popleft()
            self._confirm(index + 1)

    def _select_pen(self, pen: int) -> None:
        raise ConfigError(f"axidraw: the plotter holds one pen; cannot select pen {pen}")

    def _device_paused(self) -> bool:
        """Toggled by each press of the PRG button (``QG`` bit 5 / ``QB``), polled at most every 50 ms."""
        now = self.clock.now()
        if now - self._button_asked >= BUTTON_POLL_S:
            self._button_asked = now
            if supports(self.version or (0, 0, 0), "QG"):
                self._command("QG", on_reply=lambda data: self._status_byte(parse_qg(data)))
            else:
                self._command("QB", on_reply=lambda data: self._button(strip_name("QB", data).strip() == "1"))
        self._poll()
        return self._paused

    def _make_safe(self) -> None:
        """Let the few queued slices finish, pen up, park at home after a finished job, wait idle, motors off."""
        try:
            link = self.link
            if link is None or link.closed:
                return
            interrupted = bool(self._unanswered or self._marks) or self._interrupted
            self._flush_replies()
            self._pen(up=True)
            self._flush_replies()
            self._wait_idle(max(self.timeout, 5.0))
            if interrupted:  # motors stay on: the step counters keep the position for an exact resume
                log.warning("axidraw: stopped with the pen up at %s steps; motors left on so the plot can resume",
                            self.position.tolist())
                return
            if self.position.any():
                self._travel(np.zeros(2, dtype=np.int64))
                self._flush_replies()
                self._wait_idle(max(self.timeout, 5.0))
            self._motors_off()
        except (LinkError, ProtocolError, ParseError) as exc:
            log.warning("axidraw: could not leave the plotter safe: %s", exc)

    def _where(self) -> DeviceWhere:
        """After a fault, on a fresh link: wait until the board has run its FIFO, then report its step counters.

        The counters mean the carriage's position only while the motors stayed energised at 1/16 (``QE``) with
        motor power (``QC`` V+, and the ``QG`` bit 6 latch on fw >= 3): a board that rebooted, lost V+ or had its
        motors switched off keeps counting (or restarts at 0) while the carriage did not move with them.
        """
        link = self._link()
        self._reset_counts()
        lost, self._lost = self._lost, None
        reached, self._reached = self._reached, None
        link.reset_input()
        link.write(f"{FLUSH}\rV\r".encode("ascii"))
        self.version, self.future_syntax = self._await_version()
        if not supports(self.version, "QS"):
            return DeviceWhere(None, None, position_lost=True, detail=f"EBB firmware {_v(self.version)} has no QS")
        self._wait_idle(60.0)
        steps = self._query_steps()
        pen_up = self._query_pen_up()
        raw = self._query_vplus()
        if supports(self.version, "QE"):
            enabled = self._query_enabled()
            if enabled != (MICROSTEPS, MICROSTEPS):
                lost = lost or (f"the motors are not energised at 1/{MICROSTEPS} (QE {enabled[0]},{enabled[1]}): "
                                 "the board restarted or they were switched off")
        elif not self._zeroed:
            lost = lost or f"EBB firmware {_v(self.version)} has no QE to tell whether the motors stayed on"
        if raw < VPLUS_MIN_RAW:
            lost = lost or f"no motor power: QC reads V+ {vplus_volts(raw):.1f} V"
        if supports(self.version, "queued_EM") and self._query_status_byte() & QG_POWER_LOST:
            lost = lost or "the motor supply dropped (QG power-lost flag)"
        if lost:
            return self._lost_where(lost)
        self._adopt = steps
        return DeviceWhere((float(steps[0]), float(steps[1])), not pen_up, tolerance=1.0, reached=reached,
                           detail=f"EBB at {steps.tolist()} steps, pen {'up' if pen_up else 'down'}")

    def _lost_where(self, why: str) -> DeviceWhere:
        """Position lost; after a supply failure the detail names the last place reached with the motors powered.

        That place is where drawing stopped, to within the one queued command run between the last good supply
        check and the first bad one; the base has it (``_acknowledged``) for the resume after re-homing.
        """
        cut = self._cut
        if cut is not None:
            why += f"; the motors last ran powered to {list(cut.position)} steps, pen {_pen_word(cut.pen_down)}"
        return DeviceWhere(None, None, position_lost=True, detail=why)

    def _pen_position(self) -> tuple[float, float] | None:
        """Where the carriage will be once everything sent has run (steps = device units), the next travel's start."""
        return (float(self.position[0]), float(self.position[1]))

    def _manual_pen(self, down: bool) -> None:
        self._pen(up=not down)
        self._flush_replies()
        self._wait_idle(max(self.timeout, 5.0))

    def _manual_pen_state(self) -> bool | None:
        return not self._query_pen_up()

    def _manual_home(self) -> None:
        """Pen up and travel to where the step counters are zero (motors enabled there), like pyaxidraw's walk_home."""
        self._manual_pen(False)
        if supports(self.version or (0, 0, 0), "QS"):
            self.position = self._query_steps()
        self._travel(np.zeros(2, dtype=np.int64))
        self._flush_replies()
        self._wait_idle(max(self.timeout, 5.0) + 60.0)

    def _manual_motors_off(self) -> None:
        self._flush_replies()
        self._wait_idle(max(self.timeout, 5.0))
        self._motors_off()

    @property
    def paused(self) -> bool:
        """True while a press of the PRG button holds the plot (pen up); the next press resumes it."""
        return self._paused

    # -- motion ----------------------------------------------------------------------------------
    def _travel(self, target: np.ndarray) -> None:
        """Pen-up move from the carriage position to ``target`` (steps)."""
        target = np.asarray(target, dtype=np.int64)
        if np.array_equal(target, self.position):
            return
        self._move(np.vstack([self.position, target]), self.profile.pen_up)

    def _move(self, pts: np.ndarray, limits: Any, stroke: int | None = None) -> None:
        """Plan ``pts`` (steps, from the carriage) with ``limits`` and send it as slices (of ``stroke``, pen down)."""
        mm = pts.astype(np.float64) / self.steps_per_mm
        sliced = slice_polyline(mm, limits, self.steps_per_mm, SLICE_S)
        signed_steps = supports(self.version or (0, 0, 0), "LM_signed_steps")
        commands = move_commands(sliced, self.moves, signed_steps)
        ends = self.position + np.cumsum(sliced.steps, axis=0)
        at_vertex = (ends == pts[sliced.vertex]).all(axis=1)  # the slice ends on the vertex it has reached
        for cmd, ms, vertex, end, exact in zip(commands, sliced.ms.tolist(), sliced.vertex.tolist(), ends, at_vertex,
                                               strict=True):
            if stroke is None:
                self._queue(cmd, ms / 1000.0, end, pen_down=False)
                continue
            place = ResumePoint(stroke, vertex, None if exact else (float(end[0]), float(end[1])))
            self._queue(cmd, ms / 1000.0, end, pen_down=True, reached=(stroke, vertex), place=place)
        if len(ends):
            self.position = ends[-1]

    def _pen(self, up: bool, reached: tuple[int, int] | None = None) -> None:
        """``SP`` with a delay that covers the profile's pen time and the servo's slew at the SC,11/12 rate."""
        ms = round(1000 * (self.profile.pen_lift_s if up else self.profile.pen_drop_s))
        if supports(self.version or (0, 0, 0), "SC_rates"):
            ms = max(ms, servo_move_ms(self.servo_down, self.servo_up, self.servo_rates[0 if up else 1]))
        place = None if reached is None else ResumePoint(reached[0] + 1) if up else ResumePoint(reached[0])
        self._queue(f"SP,{1 if up else 0},{ms}", ms / 1000.0, self.position, pen_down=not up, reached=reached,
                    place=place)

    def _motors_off(self) -> None:
        """``EM,0,0``: the carriage moves freely, so the step counters no longer tell where it is."""
        self._command("EM,0,0", queued=supports(self.version or (0, 0, 0), "queued_EM"))
        self._flush_replies()
        self._marks.clear()
        self.position = np.zeros(2, dtype=np.int64)
        self._zeroed = False

def _v(version: tuple[int, int, int]) -> str:
    return ".".join(str(p) for p in version)


def find_ebb_port() -> str:
    """``axidraw:auto``: the first serial port with the EiBotBoard's USB ID 04D8:FD92."""
    ports = list_serial_ports()
    for dev in ports:
        if (dev.vid, dev.pid) == EBB_USB_ID:
            log.info("axidraw: auto port %s (%s)", dev.path, dev.description)
            return dev.path
    seen = ", ".join(f"{d.path} ({d.description})" for d in ports) or "none"
    raise LinkError(f"axidraw:auto found no EiBotBoard (USB 04D8:FD92) among the serial ports: {seen}; name the port")


def _pen_word(down: bool) -> str:
    return "down" if down else "up"

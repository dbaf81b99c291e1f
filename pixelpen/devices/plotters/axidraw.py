"""AxiDraw driver (``axidraw:PORT``): the EiBotBoard over USB serial, moves planned and sliced on the host.

Longer than 600 lines because the EBB's command window, FIFO-count confirmation and motor-power checks are
one protocol state on the display (the encoding, reply parsing and firmware table are in ``ebb_encode``).

URL: ``axidraw:/dev/ttyACM0?model=se_a3&moves=lm`` (PORT is a device path, a pyserial URL in brackets, or
``auto`` for the first USB serial port with the EBB's ID 04D8:FD92); ``sim:axidraw?speed=fast`` plots on
the simulator.  ``model=`` picks the profile: ``v3`` (default; also V2 and SE/A4), ``se_a3``, ``minikit``.

Each stroke is a pen-up travel, ``SP,0,<drop ms>``, the stroke, ``SP,1,<lift ms>``.  Travel and stroke are
planned with the vector engine's motion model (:func:`pixelpen.vector.motion.plan`: trapezoids, junction
deviation at corners) with the profile's pen-up and pen-down limits and emitted as time slices of at most
25 ms (``SM``, ``XM`` or ``LM``, option ``moves=``), steps rounded with their fractions carried.

How a stroke is confirmed.  A motion command's ``OK`` comes when it enters the board's motion FIFO, not when
it runs.  The FIFO holds one command at boot and one more executes, so when the ``OK`` of the n-th queued
command arrives every queued command up to n − 2 has finished: a stroke is confirmed once the command
count acknowledged passes its pen lift by two.  At the end of a job (and before a pause) ``QM`` is polled
until the motion system is idle, which confirms everything sent.

Pause: the PRG button (``QG`` bit 5, or ``QB`` on firmware before 2.6.2), polled at most every 50 ms
between strokes, pauses the plot with the pen up; a second press resumes it.

Motor power.  Without V+ the motors stand still while the board goes on counting steps, so the carriage is
no longer where the counters say.  ``QC`` is read at connect (as pyaxidraw does) and after every stroke (plus
the ``QG`` bit 6 latch, armed with ``CU,60``, on firmware 3.x); a stroke is confirmed only once a good
reading taken after it ran came back.  A reading below ``VPLUS_MIN_RAW`` (plotink's 250 counts, about 7.7 V)
stops the plot (Disconnected) with the position lost: the resume asks for the carriage to go home and a
confirmation.  A refused motion command stops the FIFO at once (``ES``) and marks its stroke damaged.

After a fault (``_where``): the board runs its FIFO out (``QM``), then ``QS`` gives the carriage in steps,
``QG``/``QP`` the pen, ``QE`` whether the motors stayed on at 1/16 (off, or a rebooted board: position lost),
``QC`` the supply.  An interrupted job leaves the motors on (as a pyaxidraw pause does) so a later session can
still read the position from the counters.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from pixelpen.devices.plotters.base import DeviceWhere, PlotterDisplay
from pixelpen.devices.plotters.ebb_encode import (
    EBB_USB_ID,
    FEATURES,
    VPLUS_MIN_RAW,
    move_commands,
    parse_error,
    parse_qc,
    parse_qg,
    parse_qm,
    parse_qs,
    parse_version_reply,
    reply_shape,
    servo_positions,
    slice_polyline,
    strip_name,
    supports,
    vplus_volts,
)
from pixelpen.display.registry import register_display
from pixelpen.drivers.discovery import list_serial_ports
from pixelpen.drivers.stream import Link
from pixelpen.errors import ConfigError, Disconnected, LinkError, LinkTimeout, ParseError, ProtocolError
from pixelpen.options import OptionSpec, OptionValues, choice, number
from pixelpen.profiles.model import DeviceProfile, load_profile

log = logging.getLogger(__name__)

__all__ = ["MODELS", "AxiDrawPlotter", "find_ebb_port"]

MODELS = {"v3": "axidraw_v3", "v2": "axidraw_v3", "se_a4": "axidraw_v3", "se_a3": "axidraw_se_a3",
          "a3": "axidraw_se_a3", "minikit": "axidraw_minikit"}
"""``model=`` values and the profile each one uses."""
SLICE_S = 0.025
"""Longest motion slice (pyaxidraw's SM slices are 25 ms)."""
WINDOW = 4
"""Commands written ahead of their replies: the board holds two (FIFO + executing), the rest wait in USB."""
BUTTON_POLL_S = 0.05
"""Least time between two button polls (pyaxidraw: QB at least 50 ms apart)."""
IDLE_POLL_S = 0.01
FIFO_DEPTH = 1
"""Motion FIFO depth at boot (ebb.html CU,4); the driver does not change it."""
USB_BAUD = 12_000_000
"""Line speed of a ``sim:axidraw`` link without ``baud=`` (USB full speed, not a serial port's 9600)."""
FLUSH = "#"
"""Sent alone before the first command: ends any half-received command as a syntax error, so it cannot run."""
MICROSTEPS = 16
"""``EM,1,1``: 1/16 stepping, what QE reports for an enabled motor."""
QG_POWER_LOST, QG_BUTTON, QG_PEN_UP = 0x40, 0x20, 0x10
"""QG status bits (ebb.html QG; bit 6 latches a V+ drop below the CU,60 threshold, fw >= 3.0)."""


@dataclass
class _Sent:
    """A command written to the board and not yet answered."""

    text: str
    queued: bool
    duration_s: float
    on_reply: Callable[[str], None] | None = None
    reached: tuple[int, int] | None = None
    """(stroke, vertex) the pen is down at once this queued command has run."""
    stroke: int | None = None
    """The stroke this command belongs to (its travel, pen moves and slices)."""


def _model(text: str) -> str:
    """An AxiDraw model name (``se-a3`` spelled either way)."""
    return _MODEL_NAMES(text.replace("-", "_"))


_MODEL_NAMES = choice(*MODELS)


@register_display("axidraw")
class AxiDrawPlotter(PlotterDisplay):
    """An AxiDraw (EiBotBoard): host-planned sliced moves, servo pen, FIFO-count confirmation, button pause."""

    profile_name: ClassVar[str] = "axidraw_v3"
    family: ClassVar[str] = "axidraw"
    reports_position: ClassVar[bool] = True
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
        **kwargs: Any,
    ) -> None:
        super().__init__(port, profile=profile, **kwargs)
        if moves not in ("sm", "xm", "lm"):
            raise ConfigError(f"axidraw: moves must be sm, xm or lm, got {moves!r}")
        self.moves = moves
        self.servo_up, self.servo_down = servo_positions(profile.servo, pen_up_percent, pen_down_percent)
        self.steps_per_mm = profile.steps_per_mm or 1.0 / profile.unit_mm
        self.version: tuple[int, int, int] | None = None
        """Firmware version from ``V``."""
        self.future_syntax = False
        """True when the board answers in the future syntax (``CU,10,1``)."""
        self.position = np.zeros(2, dtype=np.int64)
        """Carriage position in steps (x right, y down) after every command sent."""
        self._unanswered: deque[_Sent] = deque()
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
        if supports(self.version, "queued_EM"):
            self._command(f"CU,60,{VPLUS_MIN_RAW}")  # latch a supply drop in QG bit 6 between checks
        self._pen(up=True)
        self._flush_replies()
        self._check_power()  # as pyaxidraw does before plotting: refuse a board without motor power
        self._power_good = self._queued_sent

    def _send_stroke(self, index: int, points: np.ndarray, pen: int) -> None:
        """Travel, pen down, the stroke, pen up; then a supply check that certifies what ran before it."""
        pts = np.asarray(points, dtype=np.int64).reshape(-1, 2)
        self._stroke_now = index
        self._travel(pts[0])
        self._pen(up=False, reached=(index, 0))
        if len(pts) > 1:
            self._move(pts, self.profile.pen_down, stroke=index)
        self._pen(up=True, reached=(index, len(pts) - 1))
        self._marks.append((self._queued_sent, index))
        self._stroke_now = None
        self._power_checkpoint()

    def _poll(self) -> None:
        link = self._link()
        while self._unanswered and link.in_waiting:
            self._read_reply()

    def _drain(self) -> None:
        self._flush_replies()
        self._wait_idle(max(self.timeout, 5.0))
        self._check_power()
        self._power_good = self._queued_sent
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
            return DeviceWhere(None, None, position_lost=True, detail=lost)
        self._adopt = steps
        return DeviceWhere((float(steps[0]), float(steps[1])), not pen_up, tolerance=1.0, reached=reached,
                           detail=f"EBB at {steps.tolist()} steps, pen {'up' if pen_up else 'down'}")

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
        for cmd, ms, vertex in zip(commands, sliced.ms.tolist(), sliced.vertex.tolist(), strict=False):
            self._command(cmd, queued=True, duration_s=ms / 1000.0,
                          reached=None if stroke is None else (stroke, vertex))
        self.position = self.position + sliced.steps.sum(axis=0)

    def _pen(self, up: bool, reached: tuple[int, int] | None = None) -> None:
        ms = round(1000 * (self.profile.pen_lift_s if up else self.profile.pen_drop_s))
        self._command(f"SP,{1 if up else 0},{ms}", queued=True, duration_s=ms / 1000.0, reached=reached)

    def _motors_off(self) -> None:
        """``EM,0,0``: the carriage moves freely, so the step counters no longer tell where it is."""
        self._command("EM,0,0", queued=supports(self.version or (0, 0, 0), "queued_EM"))
        self._flush_replies()
        self._marks.clear()
        self.position = np.zeros(2, dtype=np.int64)
        self._zeroed = False

    def _abort_motion(self) -> None:
        """``ES``: stop now and flush the FIFO, so the moves queued behind a refused one do not run shifted.

        Every move is relative, so once one is refused the ones after it would draw off the path; the step
        counters still say exactly where the carriage stopped.  Best effort: the error is raised either way.
        """
        if not supports(self.version or (0, 0, 0), "ES"):
            return
        try:
            self._link().write(b"ES\r")
            self._link().flush()
        except LinkError as exc:
            log.warning("axidraw: could not stop the motion after the error: %s", exc)

    # -- motor power -----------------------------------------------------------------------------
    def _power_checkpoint(self) -> None:
        """Queue a V+ check (``QC``; ``QG`` too on fw >= 3): a good answer certifies the commands finished before it."""
        certified = self._queued_sent - (FIFO_DEPTH + 1)  # what has run by the time the parser reaches the check
        self._command("QC", on_reply=lambda data: self._supply(parse_qc(data)[1], certified))
        if supports(self.version or (0, 0, 0), "queued_EM"):
            self._command("QG", on_reply=lambda data: self._status_byte(parse_qg(data)))

    def _check_power(self) -> None:
        """Ask ``QC`` now and raise when the motor supply is off."""
        self._supply(self._query_vplus(), self._power_good)

    def _supply(self, raw: int, certified: int) -> None:
        """Act on a V+ reading: below VPLUS_MIN_RAW the motors stood still, so the plot stops with the position lost."""
        if raw < VPLUS_MIN_RAW:
            self._lost = f"the motor supply failed during the plot (QC V+ {vplus_volts(raw):.1f} V)"
            raise Disconnected(
                f"axidraw: motor power lost: QC reads V+ {vplus_volts(raw):.1f} V (a powered board reads "
                f"{vplus_volts(VPLUS_MIN_RAW):.1f} V or more); the carriage stopped while the steps were counted, so "
                "where the pen is is unknown: switch the power on, move the carriage home and resume with the "
                "position confirmed"
            )
        self._power_good = max(self._power_good, certified)

    def _status_byte(self, bits: int) -> None:
        """A ``QG`` byte: PRG button presses toggle the pause; the power-lost latch stops the plot."""
        if bits & QG_POWER_LOST:
            self._lost = "the motor supply dropped during the plot (QG power-lost flag)"
            raise Disconnected("axidraw: motor power dropped (QG power-lost flag): the position is unknown; "
                               "move the carriage home and resume with the position confirmed")
        self._button(bool(bits & QG_BUTTON))

    # -- commands and replies --------------------------------------------------------------------
    def _command(self, text: str, *, queued: bool = False, duration_s: float = 0.0,
                 on_reply: Callable[[str], None] | None = None, reached: tuple[int, int] | None = None) -> None:
        """Write one command (keeping at most WINDOW unanswered); ``queued`` ones enter the motion FIFO."""
        while len(self._unanswered) >= WINDOW:
            self._read_reply()
        self._link().write(text.encode("ascii") + b"\r")
        self._unanswered.append(_Sent(text, queued, duration_s, on_reply, reached, self._stroke_now))
        if queued:
            self._queued_sent += 1

    def _flush_replies(self) -> None:
        while self._unanswered:
            self._read_reply()

    def _read_reply(self) -> str | None:
        """Read the oldest pending command's reply (both syntaxes); ProtocolError names the command on ``!n Err``."""
        sent = self._unanswered[0]
        name = _name(sent.text)
        wait = self.timeout + sum(s.duration_s for s in self._unanswered if s.queued)
        line = self._line(wait, sent.text)
        data: str | None = None
        error = parse_error(line)
        if error is None and self.future_syntax:
            if not line.upper().startswith(name):
                raise ParseError(f"reply to {sent.text!r} should start with {name!r}", source="ebb", token=line)
            data = line[len(name) + 1:] if len(line) > len(name) else ""
        elif error is None:
            shape = reply_shape(name)
            if shape == "ack":
                if line.upper() != "OK":
                    raise ParseError(f"expected OK after {sent.text!r}", source="ebb", token=line)
            else:
                data = line
                if shape == "data_ok":
                    ok = self._line(wait, sent.text)
                    error = parse_error(ok)
                    if error is None and ok.upper() != "OK":
                        raise ParseError(f"expected OK after the data of {sent.text!r}", source="ebb", token=ok)
        self._unanswered.popleft()
        if error is not None:
            if sent.queued:
                self._abort_motion()
            if sent.stroke is not None:
                self._mark_damaged(range(sent.stroke, sent.stroke + 1))  # redrawn whole: a piece of it never ran
            raise ProtocolError(f"EBB rejected a command: !{error[0]} Err: {error[1]}", code=error[0],
                                command=sent.text, device="axidraw")
        if sent.queued:
            self._queued_acked += 1
            if sent.reached is not None:
                self._reached = sent.reached
            done = min(self._queued_acked - (FIFO_DEPTH + 1), self._power_good)
            while self._marks and self._marks[0][0] <= done:
                _, index = self._marks.popleft()
                self._confirm(index + 1)
        if sent.on_reply is not None:
            sent.on_reply(data or "")
        return data

    def _line(self, timeout: float, command: str) -> str:
        """One non-empty reply line (legacy endings \\r\\n and \\n\\r both handled)."""
        link = self._link()
        while True:
            try:
                raw = link.read_until(b"\n", timeout=timeout, max_size=300)
            except LinkTimeout as exc:
                raise LinkTimeout(f"axidraw: no reply to {command!r} within {timeout:.1f}s ({exc})") from exc
            text = raw.decode("ascii", "replace").strip()
            if text:
                return text

    def _await_version(self) -> tuple[tuple[int, int, int], bool]:
        """Read lines after ``#\\rV\\r`` until the version reply (the flush's error and stale replies are skipped)."""
        for _ in range(64):
            line = self._line(self.timeout, "V")
            try:
                return parse_version_reply(line)
            except ParseError:
                log.debug("axidraw: skipped %r while waiting for the version", line)
        raise ParseError("no version reply among 64 lines", source="ebb V")

    def _wait_idle(self, limit_s: float) -> None:
        """Poll ``QM`` until nothing executes and the FIFO is empty (bounded by ``limit_s`` clock seconds)."""
        deadline = self.clock.now() + limit_s
        state: list[tuple[int, int, int, int]] = []
        while True:
            self._command("QM", on_reply=lambda data: state.append(parse_qm(data)))
            self._flush_replies()
            if not any(state[-1]):
                return
            if self.clock.now() >= deadline:
                raise LinkTimeout(f"axidraw: motion still running after {limit_s}s (QM {state[-1]})")
            self.clock.sleep(IDLE_POLL_S)

    def _query(self, command: str, parse: Callable[[str], Any]) -> Any:
        """Send an immediate query and return its parsed reply (after every reply before it)."""
        found: list[Any] = []
        self._command(command, on_reply=lambda data: found.append(parse(data)))
        self._flush_replies()
        return found[0]

    def _query_steps(self) -> np.ndarray:
        """The carriage position in steps (x, y) from the step counters (``QS``: motor1 = x + y, motor2 = x − y)."""
        s1, s2 = self._query("QS", parse_qs)
        return np.array([(s1 + s2) // 2, (s1 - s2) // 2], dtype=np.int64)

    def _query_pen_up(self) -> bool:
        if supports(self.version or (0, 0, 0), "QG"):
            bits = self._query("QG", parse_qg)
            self._button(bool(bits & QG_BUTTON))
            return bool(bits & QG_PEN_UP)
        return self._query("QP", lambda data: strip_name("QP", data).strip()) != "0"

    def _query_vplus(self) -> int:
        return self._query("QC", lambda data: parse_qc(data)[1])

    def _query_enabled(self) -> tuple[int, int]:
        return self._query("QE", lambda data: _fields_pair(data))

    def _query_status_byte(self) -> int:
        bits = self._query("QG", parse_qg)
        self._button(bool(bits & QG_BUTTON))
        return bits

    def _reset_counts(self) -> None:
        """Forget what the previous link had in flight (a new link starts counting afresh)."""
        self._unanswered.clear()
        self._marks.clear()
        self._queued_acked = self._queued_sent = self._power_good = 0

    def _button(self, pressed: bool) -> None:
        if pressed:
            self._paused = not self._paused
            log.info("axidraw: PRG button: %s", "pausing at the next pen-up" if self._paused else "resuming")

    def _link(self) -> Link:
        if self.link is None:
            raise LinkError("axidraw: the plotter is not connected")
        return self.link


def _fields_pair(data: str) -> tuple[int, int]:
    """``QE`` data ``m1,m2`` (microstep divisor of each enabled motor, 0 when off)."""
    fields = strip_name("QE", data.strip()).split(",")
    if len(fields) != 2 or not all(
            f.strip().isascii() and f.strip().isdecimal() and len(f.strip()) <= 3 for f in fields):
        raise ParseError("QE reply must be two numbers", source="ebb QE", token=data)
    return int(fields[0]), int(fields[1])


def _name(command: str) -> str:
    """The one- or two-character command name (the firmware takes the second character unless it is a comma)."""
    head = command.split(",", 1)[0]
    return head[:2].upper()


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

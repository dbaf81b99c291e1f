"""GRBL 1.1 pen plotter driver (``grbl:PORT``): G-code per stroke, character counting, status, holds and resets.

URL: ``grbl:/dev/ttyACM0?stream=counting&pen=servo`` (PORT is a device path, a pyserial URL in brackets
such as ``grbl:[rfc2217://host:4000]``, or ``auto`` for the first port discovery takes for a GRBL board);
``sim:grbl?speed=fast`` plots on the simulator.  Profile ``grbl`` (units of 0.001 mm, y up).

How a stroke is confirmed.  GRBL answers ``ok`` as soon as a line is parsed into its planner, long
before the pen gets there (interface.md; UGS#2496).  Every stroke therefore ends with its pen lift and a
``G4 P<dwell>`` dwell: GRBL runs a dwell only after its planner buffer has emptied
(``protocol_buffer_synchronize``), so the ``ok`` of that dwell arrives once every move of the stroke has
been executed and the pen has lifted.  That ``ok`` confirms the stroke; a resume starts at the first
stroke whose dwell was not acknowledged.

Streaming (``stream=``): ``counting`` (default) keeps GRBL's 128-byte serial buffer full by counting the
bytes of unacknowledged lines (:class:`~pixelpen.devices.plotters.grbl_encode.CharacterCounter`); ``wait`` sends a
line and waits for its ``ok`` (simple, but starves the planner on short segments).  While waiting, a
quiet line is probed with the real-time ``?``: a machine in Run, Jog or Hold is waited for (a hold is the
operator's pause; ``~`` or the cycle-start button resumes it), one that answers nothing raises LinkTimeout.
A line lost on the wire shows as an idle GRBL with acknowledgements missing and raises LinkTimeout too.

Trust.  GRBL has no line checksum, and a byte >= 0x80 is taken as an unknown real-time command and dropped,
so a garbled byte can leave a shorter but valid line (``X12.3`` -> ``X1.3``, ``M3 S500`` -> ``M3 S50``).  Every
status report during a plot (``?`` every ``TRACK_POLL_S`` while the driver waits, one after every confirming
``ok``: a stroke counts as confirmed only once that report is on the path) is checked against the path sent
(:class:`~pixelpen.devices.plotters.grbl_encode.PathTrack`): off the path, or with the pen up along a drawn leg
(down along a travel), the driver feeds hold at once and raises LinkError.  The line that lost a byte is then
found (:func:`~pixelpen.devices.plotters.grbl_garble.explain_position`: the first line sent, from the leg where the
last report saw the pen on the path, whose one-byte variant puts the pen there) and the resume draws from its
start, or from where it left its leg when it ran along it within ``INK_TOLERANCE_MM`` (a digit dropped after the
point: :meth:`~pixelpen.devices.plotters.grbl_garble.Garble.inked_to`); an ``error:N`` names its line itself (it
never ran; GRBL stopped before it or took the shortcut past it).  The pen's state is read before the reset that
ends the driver's hold, and a held GRBL may rest anywhere on the path (``DeviceWhere.held``).  Unexplained: the
strokes in flight are redrawn whole.
A wrong target draws its wrong leg before any report can show it (GRBL has no checksum): that stray is not undone.

After a fault (``_where``, on the fresh link): GRBL is left to run what it received (Idle and silent for
longer than a pen dwell, or a finished hold), a half line is flushed by the ``$$`` query it spoils, ``$$``
gives the step size (the position tolerance), and the status
report the position (work coordinates) and the pen (spindle output or Z).  GRBL parses the ``$$`` only after
every line before it (so after a dwell a garbled byte made long), but may answer it before the motion those
lines queued starts: a busy report after it means waiting for that motion too.  A welcome banner (power, reset,
the Arduino's auto-reset on opening the port), an alarm that loses position, ``$SLP`` or a restart seen
during the plot mean the position is lost: the resume asks for ``$H`` (``go_home()`` with $22=1) or a check.

Limits: ``SETTLE_LIMIT_S`` (120 s) for GRBL to finish after a reconnect, ``HOMING_LIMIT_S`` (120 s) for ``$H``,
``TRACK_TOLERANCE_MM`` (0.03 mm, for machines of >= 67 steps/mm) off the path before a report counts as a garbled
line, ``TRACK_POLL_S`` (0.5 s) between status polls while plotting; module constants.
"""

from __future__ import annotations

import logging
import math
from typing import Any, ClassVar

import numpy as np

from pixelpen.devices.plotters.base import DeviceWhere
from pixelpen.devices.plotters.grbl_encode import (
    REALTIME_HOLD,
    REALTIME_STATUS,
    CharacterCounter,
    CoordinateFormat,
    GrblStatus,
    PathTrack,
    PenMotion,
    number,
    stroke_lines,
)
from pixelpen.devices.plotters.grbl_garble import Garble, SentLeg
from pixelpen.devices.plotters.grbl_stream import (
    INK_TOLERANCE_MM,
    SETTLE_LIMIT_S,
    STATUS_INTERVAL_S,
    STOP_WAIT_S,
    GrblStream,
    Tag,
)
from pixelpen.devices.plotters.resume import near_segment
from pixelpen.display.registry import register_display
from pixelpen.drivers.discovery import list_serial_ports
from pixelpen.drivers.stream import Link
from pixelpen.errors import ConfigError, LinkError, LinkTimeout, ParseError, ProtocolError
from pixelpen.options import OptionSpec, OptionValues, boolean, choice, integer, non_negative, positive
from pixelpen.profiles.model import DeviceProfile

log = logging.getLogger(__name__)

__all__ = ["GrblPlotter", "default_pen_motion", "find_grbl_port"]

BOOT_WAIT_S = 2.5
"""How long a freshly opened port may take to answer: an Arduino resets when its port opens."""
HOMING_LIMIT_S = 120.0
"""Longest wait for ``$H`` to report its ``ok``."""
_Z_UP_DEFAULT, _Z_DOWN_DEFAULT = 2.0, 0.0


def _pen_value(text: str) -> float | None:
    """A servo S value or Z height; ``off`` (or ``m5``) for M5."""
    value = text.strip().lower()
    if value in ("off", "m5"):
        return None
    return _pen_down_value(value)


def _pen_down_value(text: str) -> float:
    """A servo S value or Z height (the pen-down one cannot be M5: that lifts the pen)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise ValueError("expected a finite number (only pen_up may be 'off' for M5)")
    return value


@register_display("grbl")
class GrblPlotter(GrblStream):
    """A pen plotter on a GRBL 1.1 controller: streams G-code per stroke and confirms strokes on execution."""

    profile_name: ClassVar[str] = "grbl"
    family: ClassVar[str] = "grbl"
    reports_position: ClassVar[bool] = True
    OPTIONS = (
        *GrblStream.OPTIONS,
        OptionSpec("stream", choice("counting", "wait"), "counting",
                   "counting (fill GRBL's RX buffer) or wait (send a line, wait for its ok)"),
        OptionSpec("pen", choice("servo", "z"), None,
                   "servo (spindle PWM: M3 S<n>, default when the profile has servo commands) or z (Z axis)"),
        OptionSpec("pen_up", _pen_value, None,
                   "servo S value (or 'off' for M5) / Z height in mm with the pen up; default the profile's"),
        OptionSpec("pen_down", _pen_down_value, None,
                   "servo S value / Z height in mm with the pen down; default the profile's"),
        OptionSpec("dwell", non_negative, None,
                   "seconds to wait after each pen move (G4 P); default the profile's pen lift/drop times"),
        OptionSpec("feed", positive, None, "drawing feed rate in mm/min; default the profile's pen-down speed"),
        OptionSpec("rx_buffer", integer(16), None,
                   "GRBL's serial RX buffer in bytes for character counting; default the profile's (128)"),
        OptionSpec("unlock", boolean, False,
                   "true: send $X when GRBL starts alarm-locked (only if you know where the machine is)"),
    )

    def __init__(
        self,
        port: str,
        *,
        profile: DeviceProfile,
        stream: str = "counting",
        pen_motion: PenMotion | None = None,
        feed: float | None = None,
        rx_buffer: int | None = None,
        unlock: bool = False,
        **kwargs: Any,
    ) -> None:
        super().__init__(port, profile=profile, **kwargs)
        if stream not in ("counting", "wait"):
            raise ConfigError(f"grbl: stream must be counting or wait, got {stream!r}")
        self.stream = stream
        self.pen_motion = pen_motion or default_pen_motion(profile)
        self.feed = float(feed) if feed is not None else profile.pen_down.speed * 60.0
        if not (math.isfinite(self.feed) and self.feed > 0):
            raise ConfigError(f"grbl: feed must be > 0 mm/min, got {feed!r}")
        size = rx_buffer or (profile.link.buffer_bytes if profile.link and profile.link.buffer_bytes else 128)
        self.unlock = unlock
        self.coordinate_format = CoordinateFormat(profile.unit_mm)
        self.counter = CharacterCounter(size)
        self.version: tuple[int, int, str] | None = None
        """GRBL's version from its welcome line, e.g. (1, 1, 'h')."""
        self.last_status: GrblStatus | None = None
        """The most recent status report."""
        self.track = PathTrack()
        """The path sent and not yet confirmed, against which every status report is checked during a plot."""
        self._tracking = False
        self._wco = np.zeros(3)
        self._lost: str | None = None
        self._reached: tuple[int, int] | None = None
        self._lift_pending: tuple[int, int] | None = None
        """(stroke, its last track point) of a servo pen left down for the next travel to lift."""
        # where the pen can rest (the base's locate): a servo pen's moves share lines with the motion (stroke_lines)
        self.lifts_after_each_stroke = self.rests_pen_down_at_start = not self.pen_motion.joins
        self._held = False
        self._status_asked = -math.inf
        self._idle_polls = 0
        self._stale = False
        self._stale_seen = 0
        self.legs: list[SentLeg] = []
        """The motion lines sent and not yet confirmed, to explain a report off the path by a garbled line."""
        self._garbled: Garble | None = None
        """The line that ran garbled or was rejected: the resume draws again from where it left its leg."""
        self._on_path: tuple[float, float] | None = None
        """Where the last status report of the plot found the pen on the path (the legs before it ran as sent)."""
        self._fault_hold = False
        self._unverified: tuple[int, int | None] | None = None
        """(strokes done, track point) of a confirming ok whose position check is still to come."""

    # -- URL hooks -------------------------------------------------------------------------------
    @classmethod
    def family_options(cls, options: OptionValues, profile: DeviceProfile) -> dict[str, Any]:
        """Read stream, pen, pen_up, pen_down, dwell, feed, rx_buffer and unlock from the URL."""
        base = default_pen_motion(profile, options["pen"])
        up = options["pen_up"] if "pen_up" in options.given else base.up
        down = options["pen_down"] if "pen_down" in options.given else base.down
        dwell = options["dwell"]
        motion = PenMotion(
            base.mode, up, down, base.dwell_up if dwell is None else dwell, base.dwell_down if dwell is None else dwell
        )
        return {"stream": options["stream"], "pen_motion": motion, "feed": options["feed"],
                "rx_buffer": options["rx_buffer"], "unlock": options["unlock"]}

    @classmethod
    def simulator_options(
        cls, sim_options: dict[str, str], options: OptionValues, profile: DeviceProfile,
    ) -> dict[str, str]:
        """The simulated machine of the profile: travel covering the paper, the same pen and RX buffer."""
        out = {k: v for k, v in sim_options.items() if k != "paper"}
        paper = profile.paper(options["paper"])
        if "size" not in out:
            w, h = (number(r[1] * profile.unit_mm) for r in (paper.x_range, paper.y_range))
            out["size"] = f"{w}x{h}"
        motion: PenMotion = cls.family_options(options, profile)["pen_motion"]
        if motion.mode == "z":
            out.setdefault("pen", "z")
        else:
            up = 0.0 if motion.up is None else motion.up
            out.setdefault("pen", "servo" if motion.down > up else "servo-inverted")
            out.setdefault("pen_threshold", number(motion.down if motion.up is None else (up + motion.down) / 2))
        if options["rx_buffer"] is not None:
            out.setdefault("rx_buffer", str(options["rx_buffer"]))
        return out

    def _make_link(self) -> Link:
        if self.port == "auto" and self._link_factory is None:
            self.port = find_grbl_port()
        return super()._make_link()

    # -- device core -----------------------------------------------------------------------------
    def _connect(self) -> None:
        """Wake GRBL, let it finish what it had, soft-reset it to a clean line buffer, check version and alarm."""
        link = self._link()
        self._tracking = False
        self._lift_pending = None  # the pen-up lines below lift it
        self.counter.clear()
        self.last_status = None
        self._idle_polls = 0
        link.reset_input()
        link.write(REALTIME_STATUS)
        with self._stale_acks():  # acknowledgements of lines an earlier connection sent may still arrive
            first = self._first_answer(max(self.timeout, BOOT_WAIT_S))
            if first == "status":
                # GRBL was already running (no auto-reset): let it finish the lines it holds, then reset it
                # so that a half-received line from a broken transfer cannot run
                self._wait_until_still(STOP_WAIT_S + 60.0)
                self.soft_reset()
            elif first is None:
                self.soft_reset()
            self._settle()
        status = self.query_status()
        if status.state == "Alarm":
            if not self.unlock:
                raise ProtocolError(
                    "GRBL is alarm-locked: home it ($H) or, if you know the machine position, open with "
                    "unlock=true to send $X", code="Alarm", command=None, device="grbl",
                )
            log.warning("grbl: alarm-locked at connect; unlocking with $X as allowed by unlock=true")
            self._send_line("$X", wait=True)
        for line in ["G21 G90", *self.pen_motion.up_lines()]:
            self._send_line(line, wait=True)
        self.track.start(self._work_units(self.query_status()))
        self.legs = []
        self._on_path = None
        self._fault_hold = False
        self._unverified = None
        self._tracking = True

    def _send_stroke(self, index: int, points: np.ndarray, pen: int) -> None:
        """Stream the stroke's lines; the line with its lift (and dwell) confirms it, each motion extends the track.

        A servo pen's lift rides on the next stroke's travel (or goes alone in ``_drain``), a Z pen's ends the
        stroke (:func:`~pixelpen.devices.plotters.grbl_encode.stroke_lines`).
        """
        pts = np.asarray(points).reshape(-1, 2)
        joins = self.pen_motion.joins
        lifting, self._lift_pending = self._lift_pending, None
        lines = stroke_lines(pts, self.coordinate_format, self.pen_motion, self.feed, lift_first=lifting is not None)
        before = self.track.end
        travel = self.track.append(tuple(pts[0].tolist()), False)
        done = lifting[0] if lifting else None
        self._leg(index, None, lines[0], before, pts[0], False)
        self._send_line(lines[0], Tag(index, None, done, lifting[1] if lifting else None))
        if joins:
            vertices = range(1, len(pts)) if len(pts) > 1 else range(1)
        else:
            down = len(self.pen_motion.down_lines())
            for line in lines[1:1 + down]:
                self._send_line(line, Tag(index, 0))
            vertices = range(1, len(pts))
        first = 1 if joins else 1 + len(self.pen_motion.down_lines())
        for line, k in zip(lines[first:], vertices, strict=False):
            if k:
                self.track.append(tuple(pts[k].tolist()), True)
                self._leg(index, k, line, pts[k - 1], pts[k], True)
            self._send_line(line, Tag(index, k))
        end = self.track.append(tuple(pts[-1].tolist()), False) if len(pts) > 1 else travel
        if joins:
            self._lift_pending = (index, end)
            return
        up = self.pen_motion.up_lines()
        for line in lines[len(lines) - len(up):-1]:
            self._send_line(line, Tag(index, len(pts) - 1))
        self._send_line(lines[-1], Tag(index, len(pts) - 1, index, end))

    def _leg(self, stroke: int, vertex: int | None, line: str, start: Any, end: np.ndarray, down: bool) -> None:
        """Record a motion line before it goes out (``start`` None: from the end point)."""
        a = tuple(float(v) for v in (end if start is None else start))
        self.legs.append(SentLeg(stroke, vertex, line, (a[0], a[1]), (float(end[0]), float(end[1])), down))

    def _poll(self) -> None:
        link = self._link()
        while link.in_waiting:
            line = self._read_line(self.timeout)
            if line is not None:
                self._dispatch(line)

    def _drain(self) -> None:
        """Lift a pen left down for the next travel (the device may now rest lifted there), then wait for every ok."""
        if self._lift_pending is not None:
            index, end = self._lift_pending
            self._lift_pending = None
            self._lifted_in_place(index)
            self._send_line(" ".join(self.pen_motion.up_lines()), Tag(index, None, index, end))
        self._wait_acks()
        if self._unverified is not None:
            self.query_status()  # the last confirmation's position check

    def _select_pen(self, pen: int) -> None:
        raise ConfigError(f"grbl: the plotter holds one pen; cannot select pen {pen}")

    def _device_paused(self) -> bool:
        """True while GRBL holds (feed hold ``!``, the hold pin, or the safety door): polled at most 5 Hz."""
        now = self.clock.now()
        if now - self._status_asked >= STATUS_INTERVAL_S:
            self._link().write(REALTIME_STATUS)
            self._status_asked = now
        self._poll()
        return self._held

    def _make_safe(self) -> None:
        """Feed hold and soft reset if anything is queued or moving, then pen up and ``M5``; never raises."""
        self._tracking = False
        try:
            link = self.link
            if link is None or link.closed:
                return
            status = self.query_status()
            if status.state == "Sleep":
                log.warning("grbl: asleep ($SLP): motors and spindle are off; a reset wakes it")
                return
            if len(self.counter) or status.busy:
                if status.state in ("Run", "Jog"):
                    link.write(REALTIME_HOLD)
                    self._wait_until_still(STOP_WAIT_S, holding=True)
                self.soft_reset()
                status = self.query_status()
            if self._lift_pending is not None:
                self._lifted_in_place(self._lift_pending[0])
                self._lift_pending = None
            if status.state == "Alarm":
                log.warning("grbl: alarm-locked after stopping; the pen is left as the reset left it (spindle off)")
                return
            for line in [*self.pen_motion.up_lines(), "M5"]:
                self._send_line(line, wait=True)
            self.track.start(self._work_units(self.query_status()))
            self.legs, self._on_path = [], None  # the next plot's lines are checked afresh
            self._tracking = True
        except (LinkError, ProtocolError, ParseError) as exc:
            log.warning("grbl: could not leave the plotter safe: %s", exc)

    def _where(self) -> DeviceWhere:
        """After a fault, on a fresh link: wait until GRBL has run what it received, then report where it stands.

        A welcome banner (GRBL just booted: power, reset, an Arduino's auto-reset on opening the port), an alarm
        that loses position, sleep, or a restart seen during the plot mean the position is lost.  A half line
        left by the broken transfer never runs: the ``$$`` query that follows it is rejected with it.  A hold is
        ended by a soft reset (the pen is read before it: the reset lifts it), and motion GRBL still queued when it
        answered ``$$`` (behind a long, garbled dwell) is waited for; all bounded by SETTLE_LIMIT_S.
        """
        link = self._link()
        self._tracking = False
        self._lift_pending = None
        self.counter.clear()
        link.reset_input()
        link.write(REALTIME_STATUS)
        lost, self._lost = self._lost, None
        reached, self._reached = self._reached, None
        garbled, self._garbled = self._garbled, None
        self._unverified = None
        with self._stale_acks():  # acknowledgements of the broken connection's lines may still arrive
            first = self._first_answer(max(self.timeout, BOOT_WAIT_S))
            if first is None:
                raise LinkTimeout(f"grbl: no answer to '?' within {max(self.timeout, BOOT_WAIT_S)}s")
            if first == "welcome":
                return DeviceWhere(None, None, position_lost=True,
                                   detail="GRBL restarted (its welcome banner): power, reset or the port's "
                                   "auto-reset lose its position")
            status = self._settled_status()
            self._settle()
        if lost or status.state in ("Alarm", "Sleep"):
            return DeviceWhere(None, None, position_lost=True, detail=lost or f"GRBL is in {status.state} state")
        deadline = self.clock.now() + SETTLE_LIMIT_S
        while True:
            held = status.held
            if held:  # no line is parsed during a hold: end it as _connect would, position kept when at rest
                pen = self._pen_down_of(status)  # as it came to rest: the reset that ends the hold lifts the pen
                self.soft_reset()
                self._settle()
                if self.query_status().state == "Alarm":
                    return DeviceWhere(None, None, position_lost=True,
                                       detail="GRBL raised an alarm on the reset that ended its hold")
            settings = self._settings()
            status = self.query_status()
            if not status.busy:
                break
            # GRBL answers $$ with motion still queued behind a long (garbled) dwell: let that run out too
            if self.clock.now() >= deadline:
                raise LinkTimeout(f"grbl: still {status.state} {SETTLE_LIMIT_S}s after reconnecting")
            with self._stale_acks():
                status = self._settled_status()
        if not held:
            pen = self._pen_down_of(status)
        steps = min(settings.get(100, math.inf), settings.get(101, math.inf))
        # a hold stops mid-leg: GRBL steps each axis within one step of the straight line
        tolerance_mm = 0.0015 + (math.sqrt(2.0) / steps if math.isfinite(steps) and steps > 0 else 0.0)
        tolerance = max(0.5, tolerance_mm / self.profile.unit_mm)
        at = self._work_units(status)
        if garbled is not None and not self._ran_before(garbled.leg, at, tolerance):
            leg = garbled.leg
            inked = garbled.inked_to(at, INK_TOLERANCE_MM / self.profile.unit_mm)
            if inked is not None:  # the changed line ran along its leg before it parted: that part is drawn
                point, down = inked, True
            else:
                point = leg.end if leg.vertex is None else leg.start
                down = not (leg.vertex is None or leg.vertex <= 1)  # the stroke's first leg: the whole stroke again
            return DeviceWhere(point, down, tolerance=tolerance,
                               detail=f"GRBL {status.state} at {at} units, off the path after the garbled line "
                               f"{leg.line!r}: drawn as sent up to {point}")
        return DeviceWhere(at, pen, tolerance=tolerance, reached=reached, held=held,
                           detail=f"GRBL {status.state} at {at} units" + (" (held)" if held else ""))

    def _ran_before(self, garbled: SentLeg, at: tuple[float, float], tolerance: float) -> bool:
        """True when GRBL stopped at ``at`` on the path sent before the ``garbled`` line (it never reached it)."""
        q = np.asarray(at, dtype=np.float64)
        before = self.legs[: self.legs.index(garbled)] if garbled in self.legs else []
        return any(near_segment(q, np.asarray(leg.start, dtype=np.float64), np.asarray(leg.end, dtype=np.float64),
                                tolerance) is not None for leg in before)

    def _pen_position(self) -> tuple[float, float] | None:
        """Where the pen will be once everything sent has run (device units), the start of the next travel."""
        return self.track.end

    def _manual_pen(self, down: bool) -> None:
        for line in self.pen_motion.down_lines() if down else self.pen_motion.up_lines():
            self._send_line(line, wait=True)

    def _manual_pen_state(self) -> bool | None:
        return self._pen_down_of(self.query_status())

    def _manual_home(self) -> None:
        """Pen up, then ``$H`` when homing is enabled ($22=1), else a rapid to the profile's home (work coordinates)."""
        if self._settings().get(22, 0.0):
            self._home_cycle()
            return
        self._manual_pen(False)
        x, y = self.coordinate_format.format(np.asarray(self.profile.home, dtype=np.float64))
        self.track.append(tuple(float(v) for v in self.profile.home[:2]), False)  # type: ignore[arg-type]
        self._send_line(f"G0 X{x} Y{y}", wait=True)
        self._send_line("G4 P0", wait=True)  # acknowledged once the carriage is there

    def _home_cycle(self) -> None:
        """``$H``: GRBL seeks its limit switches and answers ``ok`` when done (it may not report status meanwhile)."""
        self._drain()
        link = self._link()
        link.write(b"$H\n")
        self.counter.sent("$H")
        while len(self.counter):
            line = self._read_line(HOMING_LIMIT_S)
            if line is None:
                raise LinkTimeout(f"grbl: homing ($H) did not finish within {HOMING_LIMIT_S}s")
            self._dispatch(line)

    def _manual_motors_off(self) -> None:
        """``$SLP`` once idle: GRBL 1.1 cuts the stepper enable, spindle and coolant; a reset wakes it (in alarm)."""
        self._drain()
        self._send_line("$SLP", wait=True)
        self._lost = "GRBL was put to sleep ($SLP): with its motors off the carriage may have moved"


def find_grbl_port() -> str:
    """``grbl:auto``: the first serial port whose USB ID is a board GRBL runs on (Arduino Uno/Mega)."""
    ports = list_serial_ports()
    for dev in ports:
        if dev.model == "grbl":
            log.info("grbl: auto port %s (%s)", dev.path, dev.description)
            return dev.path
    seen = ", ".join(f"{d.path} ({d.description})" for d in ports) or "none"
    raise LinkError(f"grbl:auto found no Arduino-type GRBL board among the serial ports: {seen}; name the port")


def default_pen_motion(profile: DeviceProfile, mode: str | None = None) -> PenMotion:
    """The pen as the profile describes it (servo commands from ``[servo]``, lift/drop times as dwells).

    ``mode`` forces ``servo`` or ``z``: a servo pen the profile does not describe gets S500 up / S50 down
    (plotters.md §3), a Z pen 2 mm up / 0 mm down without dwells.
    """
    servo = profile.servo
    described = servo is not None and bool(servo.up_command and servo.down_command)
    if mode == "z" or (mode is None and not described):
        return PenMotion("z", _Z_UP_DEFAULT, _Z_DOWN_DEFAULT, 0.0, 0.0)
    if not described:
        return PenMotion("servo", 500.0, 50.0, profile.pen_lift_s, profile.pen_drop_s)
    up = PenMotion.parse_servo_command(servo.up_command, "up_command")  # type: ignore[union-attr,arg-type]
    down = PenMotion.parse_servo_command(servo.down_command, "down_command")  # type: ignore[union-attr,arg-type]
    if down is None:
        raise ConfigError(f"profile {profile.name}: servo down_command cannot be M5 (that lifts the pen)")
    return PenMotion("servo", up, down, profile.pen_lift_s, profile.pen_drop_s)

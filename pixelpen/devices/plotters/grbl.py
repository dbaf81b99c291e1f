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
status report during a plot (one at each confirmation, at most 5 Hz between strokes) is checked against the
path sent (:class:`~pixelpen.devices.plotters.grbl_encode.PathTrack`): off the path, or with the pen up along a drawn
leg (down along a travel), the driver feeds hold at once, marks the strokes in flight damaged and raises
LinkError.  An ``error:N`` also holds at once (the lines behind a refused one would draw a shortcut) and marks
its stroke damaged.  A wrong target inside a stroke draws its wrong leg before any report can show it.

After a fault (``_where``, on the fresh link): GRBL is left to run what it received (Idle and silent for
longer than a pen dwell, or a finished hold), a half line is flushed by the ``$$`` query it spoils, ``$$``
gives the step size (the position tolerance), and the status
report the position (work coordinates) and the pen (spindle output or Z).  A welcome banner (power, reset,
the Arduino's auto-reset on opening the port), an alarm that loses position, ``$SLP`` or a restart seen
during the plot mean the position is lost: the resume asks for ``$H`` (``go_home()`` with $22=1) or a check.

Limits: ``SETTLE_LIMIT_S`` (120 s) for GRBL to finish after a reconnect, ``HOMING_LIMIT_S`` (120 s) for ``$H``,
``TRACK_TOLERANCE_MM`` (0.1 mm) off the path before a report counts as a garbled line; module constants.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from pixelpen.devices.plotters.base import DeviceWhere, PlotterDisplay
from pixelpen.devices.plotters.grbl_encode import (
    ALARM_CODES,
    ERROR_CODES,
    REALTIME_HOLD,
    REALTIME_RESET,
    REALTIME_RESUME,
    REALTIME_STATUS,
    CharacterCounter,
    CoordinateFormat,
    GrblStatus,
    PathTrack,
    PenMotion,
    number,
    parse_code,
    parse_status,
    parse_welcome,
    stroke_lines,
)
from pixelpen.display.registry import register_display
from pixelpen.drivers.discovery import list_serial_ports
from pixelpen.drivers.stream import Link
from pixelpen.errors import ConfigError, Disconnected, LinkError, LinkTimeout, ParseError, ProtocolError
from pixelpen.profiles.model import DeviceProfile
from pixelpen.urls import Options, parse_bool

log = logging.getLogger(__name__)

__all__ = ["GrblPlotter", "default_pen_motion", "find_grbl_port"]

STATUS_INTERVAL_S = 0.2
"""Least time between two ``?`` polls for pause detection (interface.md: poll at most 5 Hz)."""
BOOT_WAIT_S = 2.5
"""How long a freshly opened port may take to answer: an Arduino resets when its port opens."""
IDLE_POLLS_BEFORE_LOSS = 3
"""Status polls that find GRBL idle with lines unacknowledged before the bytes are declared lost."""
STOP_WAIT_S = 10.0
"""Longest wait for a feed hold to bring the carriage to rest when stopping safely."""
SETTLE_LIMIT_S = 120.0
"""Longest wait, after a reconnect, for GRBL to finish the lines it still held from the broken connection."""
HOMING_LIMIT_S = 120.0
"""Longest wait for ``$H`` to report its ``ok``."""
TRACK_TOLERANCE_MM = 0.1
"""How far a status report's position may lie off the path sent before the driver calls it a corrupted line."""
GARBLE_ERRORS = frozenset({1, 2, 3, 11, *range(20, 39)})
"""``error:N`` codes a line pixelpen wrote can only earn by being garbled on the wire (syntax, words): said so."""
POSITION_LOSING_ALARMS = frozenset({1, 3, 6, 7, 8, 9, 10})
"""``ALARM:N`` codes after which GRBL's position is likely lost (alarm_codes_en_US.csv: re-homing recommended)."""
_Z_UP_DEFAULT, _Z_DOWN_DEFAULT = 2.0, 0.0


def _stream(text: str) -> str:
    value = text.strip().lower()
    if value not in ("counting", "wait"):
        raise ValueError("expected counting or wait")
    return value


def _pen_kind(text: str) -> str:
    value = text.strip().lower()
    if value not in ("servo", "z"):
        raise ValueError("expected servo or z")
    return value


def _pen_value(text: str) -> float | None:
    value = text.strip().lower()
    if value in ("off", "m5"):
        return None
    number_ = float(value)
    if not math.isfinite(number_):
        raise ValueError("expected a finite number (or 'off' for M5)")
    return number_


def _non_negative(text: str) -> float:
    value = float(text)
    if not (math.isfinite(value) and value >= 0):
        raise ValueError("expected a number >= 0")
    return value


def _positive(text: str) -> float:
    value = float(text)
    if not (math.isfinite(value) and value > 0):
        raise ValueError("expected a number > 0")
    return value


def _buffer(text: str) -> int:
    value = int(text)
    if value < 16:
        raise ValueError("expected an integer >= 16 (bytes)")
    return value


@dataclass(frozen=True)
class _Tag:
    """What a line's ``ok`` tells: stroke ``stroke`` reached its vertex ``vertex`` with the pen down; stroke ``done`` is
    on paper (its lift's dwell ran) and the track may drop the legs before point number ``track``."""

    stroke: int
    vertex: int | None
    """None for the travel to the stroke's start (the pen is not down yet)."""
    done: int | None = None
    track: int | None = None


def _device_where(position: tuple[float, float] | None, pen_down: bool | None, **fields: Any) -> DeviceWhere:
    """A DeviceWhere with the optional fields the base knows (``reached`` is proposed, see the notes)."""
    known = {f.name for f in dataclasses.fields(DeviceWhere)}
    return DeviceWhere(position, pen_down, **{k: v for k, v in fields.items() if k in known})


@register_display("grbl")
class GrblPlotter(PlotterDisplay):
    """A pen plotter on a GRBL 1.1 controller: streams G-code per stroke and confirms strokes on execution."""

    profile_name: ClassVar[str] = "grbl"
    family: ClassVar[str] = "grbl"
    reports_position: ClassVar[bool] = True
    url_options: ClassVar[dict[str, str]] = {
        **PlotterDisplay.url_options,
        "stream": "counting (fill GRBL's RX buffer, default) or wait (send a line, wait for its ok)",
        "pen": "servo (spindle PWM: M3 S<n>, default when the profile has servo commands) or z (Z axis)",
        "pen_up": "servo S value (or 'off' for M5) / Z height in mm with the pen up; default the profile's",
        "pen_down": "servo S value / Z height in mm with the pen down; default the profile's",
        "dwell": "seconds to wait after each pen move (G4 P); default the profile's pen lift/drop times",
        "feed": "drawing feed rate in mm/min; default the profile's pen-down speed",
        "rx_buffer": "GRBL's serial RX buffer in bytes for character counting; default the profile's (128)",
        "unlock": "true: send $X when GRBL starts alarm-locked (only if you know where the machine is)",
    }

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

    # -- URL hooks -------------------------------------------------------------------------------
    @classmethod
    def family_options(cls, options: Options, profile: DeviceProfile) -> dict[str, object]:
        """Read stream, pen, pen_up, pen_down, dwell, feed, rx_buffer and unlock from the URL."""
        base = default_pen_motion(profile, options.get("pen", _pen_kind, None))
        up = options.get("pen_up", _pen_value, base.up)
        down = options.get("pen_down", _pen_value, None) if "pen_down" in options else base.down
        if down is None:
            raise ConfigError(f"{options.url}: pen_down needs a value (only pen_up may be 'off')")
        dwell = options.get("dwell", _non_negative, None)
        try:
            motion = PenMotion(
                base.mode, up, down, base.dwell_up if dwell is None else dwell, base.dwell_down if dwell is None else dwell
            )
        except ConfigError as exc:
            raise ConfigError(f"{options.url}: {exc}") from None
        return {
            "stream": options.get("stream", _stream, "counting"),
            "pen_motion": motion,
            "feed": options.get("feed", _positive, None),
            "rx_buffer": options.get("rx_buffer", _buffer, None),
            "unlock": options.get("unlock", parse_bool, False),
        }

    @classmethod
    def simulator_options(cls, sim_options: dict[str, str], options: Options, profile: DeviceProfile) -> dict[str, str]:
        """The simulated machine of the profile: travel covering the paper, the same pen and RX buffer."""
        out = {k: v for k, v in sim_options.items() if k != "paper"}
        paper = profile.paper(options.get("paper", str, None))
        if "size" not in out:
            w, h = (number(r[1] * profile.unit_mm) for r in (paper.x_range, paper.y_range))
            out["size"] = f"{w}x{h}"
        motion = cls.family_options(options, profile)["pen_motion"]
        assert isinstance(motion, PenMotion)
        if motion.mode == "z":
            out.setdefault("pen", "z")
        else:
            up = 0.0 if motion.up is None else motion.up
            out.setdefault("pen", "servo" if motion.down > up else "servo-inverted")
            out.setdefault("pen_threshold", number(motion.down if motion.up is None else (up + motion.down) / 2))
        if "rx_buffer" in options:
            out.setdefault("rx_buffer", str(options.get("rx_buffer", _buffer, 128)))
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
        self._stale = True  # acknowledgements of lines an earlier connection sent may still arrive
        try:
            first = self._first_answer(max(self.timeout, BOOT_WAIT_S))
            if first == "status":
                # GRBL was already running (no auto-reset): let it finish the lines it holds, then reset it
                # so that a half-received line from a broken transfer cannot run
                self._wait_until_still(STOP_WAIT_S + 60.0)
                self.soft_reset()
            elif first is None:
                self.soft_reset()
            self._settle()
        finally:
            self._stale = False
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
        travel = self.track.append(tuple(pts[0].tolist()), False)
        done = lifting[0] if lifting else None
        self._send_line(lines[0], _Tag(index, None, done, lifting[1] if lifting else None))
        if joins:
            vertices = range(1, len(pts)) if len(pts) > 1 else range(1)
        else:
            down = len(self.pen_motion.down_lines())
            for line in lines[1:1 + down]:
                self._send_line(line, _Tag(index, 0))
            vertices = range(1, len(pts))
        first = 1 if joins else 1 + len(self.pen_motion.down_lines())
        for line, k in zip(lines[first:], vertices):
            if k:
                self.track.append(tuple(pts[k].tolist()), True)
            self._send_line(line, _Tag(index, k))
        end = self.track.append(tuple(pts[-1].tolist()), False) if len(pts) > 1 else travel
        if joins:
            self._lift_pending = (index, end)
            return
        up = self.pen_motion.up_lines()
        for line in lines[len(lines) - len(up):-1]:
            self._send_line(line, _Tag(index, len(pts) - 1))
        self._send_line(lines[-1], _Tag(index, len(pts) - 1, index, end))

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
            self._send_line(" ".join(self.pen_motion.up_lines()), _Tag(index, None, index, end))
        self._wait_acks()

    def _wait_acks(self) -> None:
        while len(self.counter):
            self._wait_reply()

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
            self._tracking = True
        except (LinkError, ProtocolError, ParseError) as exc:
            log.warning("grbl: could not leave the plotter safe: %s", exc)

    def _where(self) -> DeviceWhere:
        """After a fault, on a fresh link: wait until GRBL has run what it received, then report where it stands.

        A welcome banner (GRBL just booted: power, reset, an Arduino's auto-reset on opening the port), an alarm
        that loses position, sleep, or a restart seen during the plot mean the position is lost.  A half line
        left by the broken transfer never runs: the ``$$`` query that follows it is rejected with it.
        """
        link = self._link()
        self._tracking = False
        self._lift_pending = None
        self.counter.clear()
        link.reset_input()
        link.write(REALTIME_STATUS)
        lost, self._lost = self._lost, None
        reached, self._reached = self._reached, None
        self._stale = True  # acknowledgements of the broken connection's lines may still arrive
        try:
            first = self._first_answer(max(self.timeout, BOOT_WAIT_S))
            if first is None:
                raise LinkTimeout(f"grbl: no answer to '?' within {max(self.timeout, BOOT_WAIT_S)}s")
            if first == "welcome":
                return DeviceWhere(None, None, position_lost=True,
                                   detail="GRBL restarted (its welcome banner): power, reset or the port's auto-reset lose its position")
            status = self._settled_status()
            self._settle()
        finally:
            self._stale = False
        if lost or status.state in ("Alarm", "Sleep"):
            return DeviceWhere(None, None, position_lost=True, detail=lost or f"GRBL is in {status.state} state")
        if status.held:  # no line is parsed during a hold: end it as _connect would, position kept when at rest
            self.soft_reset()
            self._settle()
            status = self.query_status()
            if status.state == "Alarm":
                return DeviceWhere(None, None, position_lost=True, detail="GRBL raised an alarm on the reset that ended its hold")
        settings = self._settings()
        status = self.query_status()
        steps = min(settings.get(100, math.inf), settings.get(101, math.inf))
        tolerance_mm = 0.0015 + (0.5 * math.sqrt(2.0) / steps if math.isfinite(steps) and steps > 0 else 0.0)
        return _device_where(self._work_units(status), self._pen_down_of(status),
                             tolerance=max(0.5, tolerance_mm / self.profile.unit_mm), reached=reached,
                             detail=f"GRBL {status.state} at {self._work_units(status)} units")

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

    # -- public controls -------------------------------------------------------------------------
    def query_status(self) -> GrblStatus:
        """Send ``?`` and return the status report (other lines that arrive meanwhile are handled)."""
        link = self._link()
        link.write(REALTIME_STATUS)
        self._status_asked = self.clock.now()
        before = self.last_status
        self.last_status = None
        while self.last_status is None:
            line = self._read_line(self.timeout)
            if line is None:
                self.last_status = before
                raise LinkTimeout(f"grbl: no status report within {self.timeout}s of '?'")
            self._dispatch(line)
        return self.last_status

    def feed_hold(self) -> None:
        """Real-time ``!``: decelerate to a stop and hold (resume with :meth:`resume`)."""
        self._link().write(REALTIME_HOLD)

    def resume(self) -> None:
        """Real-time ``~``: cycle start, resuming a feed hold."""
        self._link().write(REALTIME_RESUME)

    def soft_reset(self) -> None:
        """Real-time Ctrl-X: GRBL stops, flushes its buffers and restarts; returns after its welcome line."""
        link = self._link()
        link.write(REALTIME_RESET)
        self.counter.clear()
        while True:
            line = self._read_line(self.timeout)
            if line is None:
                raise LinkTimeout(f"grbl: no welcome line within {self.timeout}s of the soft reset")
            version = parse_welcome(line)
            if version is not None:
                self._welcomed(version)
                return
            if line.startswith("ALARM:"):
                log.warning("grbl: %s during reset: %s", line, ALARM_CODES.get(parse_code(line), "unknown alarm"))
            elif line not in ("ok",) and not line.startswith("<"):
                log.debug("grbl: before the welcome line: %r", line)

    # -- streaming ---------------------------------------------------------------------------------
    def _send_line(self, line: str, tag: int | None = None, *, wait: bool = False) -> None:
        """Send one G-code line under the streaming mode's flow control; ``tag`` is the stroke it confirms.

        ``wait`` (or ``stream=wait``) sends it alone: everything before it and the line itself acknowledged.
        """
        wait = wait or self.stream == "wait"
        if wait:
            self._wait_acks()
        while not self.counter.fits(line):
            self._wait_reply()
        self._link().write(line.encode("ascii") + b"\n")
        self.counter.sent(line, tag)
        if wait:
            self._wait_acks()

    def _wait_reply(self) -> None:
        """Handle one line from GRBL; on silence probe with ``?`` and keep waiting while it works or holds."""
        line = self._read_line(self.timeout)
        if line is not None:
            self._dispatch(line)
            return
        status = self.query_status()
        if status.busy:
            self._idle_polls = 0
            if status.held:
                log.info("grbl: holding (%s); waiting for a resume (~ or cycle start)", status.state)
            return
        if len(self.counter):
            self._idle_polls += 1
            dwell = max(self.pen_motion.dwell_up, self.pen_motion.dwell_down)  # GRBL is Idle while it dwells
            if self._idle_polls >= IDLE_POLLS_BEFORE_LOSS + math.ceil(dwell / self.timeout):
                raise LinkTimeout(
                    f"grbl: controller is {status.state} but {len(self.counter)} line(s) were never acknowledged "
                    f"(oldest {self.counter.oldest()!r}): bytes were lost on the line"
                )

    def _dispatch(self, line: str) -> None:
        """Act on one line GRBL sent: acknowledgements, errors, alarms, status reports, messages, restarts."""
        if self._stale and (line == "ok" or line.startswith(("error:", "ALARM:"))):
            self._stale_seen += 1
            log.info("grbl: %s from before this connection ignored", line)
        elif line == "ok":
            self._idle_polls = 0
            _, tag = self.counter.acknowledged()
            if isinstance(tag, _Tag):
                if tag.vertex is not None:
                    self._reached = (tag.stroke, tag.vertex)
                if tag.done is not None:
                    self._confirm(tag.done + 1)
                    self.track.done_until(tag.track)  # type: ignore[arg-type]
                    self._link().write(REALTIME_STATUS)  # verify the position at every confirmation point
        elif line.startswith("error:"):
            code = parse_code(line)
            sent, tag = self.counter.acknowledged()
            garbled = code in GARBLE_ERRORS and self._tracking
            self._stop_motion()  # the lines behind the rejected one would draw a shortcut
            if isinstance(tag, _Tag):
                self._mark_damaged(range(tag.stroke, tag.stroke + 1))  # redrawn whole: part of it never ran
            raise ProtocolError(
                f"GRBL rejected a line: error:{code} {ERROR_CODES.get(code, 'unknown error code')}"
                + (" (pixelpen wrote it valid: it was garbled on the line)" if garbled else ""),
                code=code, command=sent, device="grbl",
            )
        elif line.startswith("ALARM:"):
            code = parse_code(line)
            meaning = ALARM_CODES.get(code, "unknown alarm code")
            if code in POSITION_LOSING_ALARMS:
                self._lost = f"GRBL raised ALARM:{code} ({meaning})"
            raise ProtocolError(f"GRBL alarm {code}: {meaning}", code=f"ALARM:{code}", command=self.counter.oldest(),
                                device="grbl")
        elif line.startswith("<"):
            self._status_seen(parse_status(line))
        elif parse_welcome(line) is not None:
            self.counter.clear()
            self._lost = "GRBL restarted during the plot (reset, power or USB glitch) and lost its position"
            raise Disconnected(
                "grbl: the controller restarted by itself (reset button, power or USB glitch): "
                "its buffered lines are lost and its position may be wrong"
            )
        elif line.startswith(("[", ">")):
            log.info("grbl: %s", line)
        else:
            log.warning("grbl: unexpected line %r", line)

    def _read_line(self, timeout: float) -> str | None:
        """One non-empty line from GRBL without its ending, or None when ``timeout`` passed in silence."""
        link = self._link()
        while True:
            try:
                raw = link.read_until(b"\n", timeout=timeout, max_size=256)
            except LinkTimeout as exc:
                if getattr(exc, "partial", b""):
                    raise
                return None
            text = raw.decode("ascii", "replace").strip()
            if text:
                return text

    # -- status and position -------------------------------------------------------------------------
    def _status_seen(self, status: GrblStatus) -> None:
        """Keep a status report: the work offset, the device's own pause, and (plotting) the position check."""
        self.last_status = status
        if status.wco is not None:
            self._wco = np.asarray(status.wco[:3] + (0.0,) * (3 - len(status.wco[:3])), dtype=np.float64)
        stopped = status.held and status.substate in (0, 1, None)
        if stopped != self._held and (stopped or not status.held):
            self._held = stopped
            self._pause_changed(stopped)
        if self._tracking and status.state in ("Run", "Idle", "Hold", "Jog"):
            why = self.track.check(self._work_units(status), self._pen_down_of(status),
                                   TRACK_TOLERANCE_MM / self.profile.unit_mm)
            if why is not None:
                self._stop_motion()
                self._mark_damaged(range(self.confirmed, max(self._sent_end, self.confirmed + 1)))
                raise LinkError(
                    f"grbl: position check failed: {why} (GRBL reports {status.state} at {self._work_units(status)} "
                    "units): a line was changed on the wire (a dropped byte), so the plot stops here"
                )

    def _stop_motion(self) -> None:
        """Feed hold now, so nothing more is drawn after a fault (the reconnect's soft reset clears the rest)."""
        self._tracking = False
        link = self.link
        if link is not None and not link.closed:
            try:
                link.write(REALTIME_HOLD)
                link.flush()  # out before the link is closed for the reconnect
            except LinkError as exc:
                log.warning("grbl: could not send the feed hold: %s", exc)

    def _work_units(self, status: GrblStatus) -> tuple[float, float]:
        """The pen's XY in device units (work coordinates, as the G-code is written) from a status report."""
        if status.wpos is not None:
            xy = np.asarray(status.wpos[:2], dtype=np.float64)
        elif status.mpos is not None:
            xy = np.asarray(status.mpos[:2], dtype=np.float64) - self._wco[:2]
        else:
            raise ParseError("status report has neither MPos nor WPos", source="grbl status report")
        x, y = (xy / self.profile.unit_mm).tolist()
        return (round(x, 3), round(y, 3))

    def _pen_down_of(self, status: GrblStatus) -> bool | None:
        """Whether the pen is down by the report: the spindle output of a servo pen, the work Z of a Z pen."""
        motion = self.pen_motion
        if motion.mode == "z":
            if status.wpos is not None and len(status.wpos) > 2:
                z = status.wpos[2]
            elif status.mpos is not None and len(status.mpos) > 2:
                z = status.mpos[2] - self._wco[2]
            else:
                return None
            return z < (motion.up + motion.down) / 2  # type: ignore[operator]
        if status.spindle is None:
            return None
        up = 0.0 if motion.up is None else motion.up
        return status.spindle > 0 and abs(status.spindle - motion.down) < abs(status.spindle - up)

    def _settled_status(self) -> GrblStatus:
        """Poll until GRBL has run everything it received: a completed hold, or at rest and silent for longer than a dwell.

        GRBL reports Idle while it dwells (``G4``) with lines still waiting behind the dwell, so one Idle report is
        not enough: the state must stay still, with no acknowledgement arriving, for the longest pen dwell and
        two polls.  Bounded by SETTLE_LIMIT_S.
        """
        deadline = self.clock.now() + SETTLE_LIMIT_S
        quiet_s = max(self.pen_motion.dwell_up, self.pen_motion.dwell_down) + 2 * STATUS_INTERVAL_S
        since: float | None = None
        seen = self._stale_seen
        while True:
            status = self.query_status()
            now = self.clock.now()
            if status.held and status.substate in (0, 1):
                return status  # nothing runs before a resume, and the reconnect's soft reset discards it
            if status.busy or self._stale_seen != seen:
                since, seen = None, self._stale_seen
            elif since is None:
                since = now
            elif now - since >= quiet_s:
                return status
            if now >= deadline:
                raise LinkTimeout(f"grbl: still {status.state} {SETTLE_LIMIT_S}s after reconnecting")
            self.clock.sleep(STATUS_INTERVAL_S)

    def _settings(self) -> dict[int, float]:
        """``$$`` as numbers ({100: 80.0, ...}); settings that do not parse are left out."""
        settings: dict[int, float] = {}
        for line in self._system_query("$$"):
            key, eq, value = line.partition("=")
            if eq and key[1:].isascii() and key[1:].isdecimal() and len(key) <= 4:
                try:
                    settings[int(key[1:])] = float(value.split()[0]) if value.split() else 0.0
                except ValueError:
                    continue
        return settings

    def _system_query(self, command: str) -> list[str]:
        """Send a ``$`` query and return the lines before its ``ok``, waiting while GRBL still runs older lines.

        Acknowledgements of lines queued before the query come first and are skipped.  A half line a broken
        transfer left in GRBL's line buffer joins the query and makes it an error (a ``$`` inside a G-code line is
        never valid), so that line never runs; the query is then sent once more.  A silent GRBL is probed with
        ``?`` (it may be dwelling on a ``G4`` a garbled byte made long); bounded by SETTLE_LIMIT_S.
        """
        self._drain()
        link = self._link()
        deadline = self.clock.now() + SETTLE_LIMIT_S
        for attempt in range(2):
            link.write(command.encode("ascii") + b"\n")
            lines: list[str] = []
            probed = False
            while True:
                line = self._read_line(self.timeout)
                if line is None:
                    if probed or self.clock.now() >= deadline:
                        raise LinkTimeout(f"grbl: no answer to {command!r} within {self.timeout}s")
                    link.write(REALTIME_STATUS)
                    probed = True
                    continue
                probed = False
                if line == "ok":
                    if lines:
                        return lines
                    continue  # the acknowledgement of a line queued before this query
                if line.startswith("error:"):
                    if attempt == 0 and not lines:
                        log.info("grbl: a half line from the broken connection was discarded with %r", command)
                        break
                    raise ProtocolError(f"GRBL refused {command}", code=parse_code(line), command=command, device="grbl")
                if line.startswith("<"):
                    self._status_seen(parse_status(line))
                elif line.startswith("ALARM:") or parse_welcome(line) is not None:
                    self._dispatch(line)
                elif line.startswith(("[", "$")):
                    lines.append(line)
        raise ProtocolError(f"GRBL refused {command} twice", code=None, command=command, device="grbl")

    # -- connection helpers ------------------------------------------------------------------------
    def _first_answer(self, timeout: float) -> str | None:
        """After the wake-up ``?``: 'welcome' (GRBL just booted), 'status' (it was running) or None."""
        while True:
            line = self._read_line(timeout)
            if line is None:
                return None
            version = parse_welcome(line)
            if version is not None:
                self._welcomed(version)
                return "welcome"
            if line.startswith("<"):
                self.last_status = parse_status(line)
                return "status"
            log.debug("grbl: stale line at connect ignored: %r", line)

    def _welcomed(self, version: tuple[int, int, str]) -> None:
        self.version = version
        if version[:2] < (1, 1):
            raise ProtocolError(
                f"GRBL {version[0]}.{version[1]}{version[2]} is not supported: pixelpen speaks the GRBL 1.1 interface "
                "(status reports, real-time commands and error codes differ before 1.1)",
                code="version", command=None, device="grbl",
            )

    def _settle(self, quiet_s: float = 0.1) -> None:
        """Read what GRBL prints after a (re)start until it is quiet: welcome lines, unlock hint, startup echoes."""
        while True:
            line = self._read_line(quiet_s)
            if line is None:
                return
            version = parse_welcome(line)
            if version is not None:
                self._welcomed(version)
            elif line.startswith("<"):
                self.last_status = parse_status(line)
            else:
                log.info("grbl: %s", line)

    def _wait_until_still(self, limit_s: float, holding: bool = False) -> None:
        """Poll status until the carriage rests (Idle, Alarm, or Hold:0 when ``holding``); bounded by ``limit_s``."""
        deadline = self.clock.now() + limit_s
        while True:
            status = self.query_status()
            if not status.busy or (holding and status.state == "Hold" and status.substate == 0):
                return
            if status.state in ("Hold", "Door") and not holding:
                return  # an operator's hold: the reset that follows stops it
            if self.clock.now() >= deadline:
                raise LinkTimeout(f"grbl: still {status.state} after {limit_s}s")
            self.clock.sleep(STATUS_INTERVAL_S)

    def _link(self) -> Link:
        if self.link is None:
            raise LinkError("grbl: the plotter is not connected")
        return self.link


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

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
bytes of unacknowledged lines (:class:`~pixelpen.devices.grbl_encode.CharacterCounter`); ``wait`` sends a
line and waits for its ``ok`` (simple, but starves the planner on short segments).  While waiting, a
quiet line is probed with the real-time ``?``: a machine in Run, Jog or Hold is waited for (a hold is the
operator's pause; ``~`` or the cycle-start button resumes it), one that answers nothing raises LinkTimeout.
A line lost on the wire shows as an idle GRBL with acknowledgements missing and raises LinkTimeout too,
but it cannot be located: an ``ok`` carries no line number, so the strokes around it may be incomplete.
"""

from __future__ import annotations

import logging
import math
from typing import Any, ClassVar

import numpy as np

from ..display.registry import register_display
from ..drivers.discovery import list_serial_ports
from ..drivers.link import Link
from ..errors import ConfigError, LinkError, LinkTimeout, ParseError, ProtocolError
from ..urls import Options, parse_bool
from ..vector.profiles import DeviceProfile
from .grbl_encode import (
    ALARM_CODES,
    ERROR_CODES,
    REALTIME_HOLD,
    REALTIME_RESET,
    REALTIME_RESUME,
    REALTIME_STATUS,
    CharacterCounter,
    CoordinateFormat,
    GrblStatus,
    PenMotion,
    number,
    parse_status,
    parse_welcome,
    stroke_lines,
)
from .plotter import PlotterDisplay

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


@register_display("grbl")
class GrblPlotter(PlotterDisplay):
    """A pen plotter on a GRBL 1.1 controller: streams G-code per stroke and confirms strokes on execution."""

    profile_name: ClassVar[str] = "grbl"
    family: ClassVar[str] = "grbl"
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
        self._status_asked = -math.inf
        self._idle_polls = 0
        self._stale = False

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

    def _send_stroke(self, index: int, points: np.ndarray, pen: int) -> None:
        lines = stroke_lines(points, self.coordinate_format, self.pen_motion, self.feed)
        last = len(lines) - 1
        for k, line in enumerate(lines):
            self._send_line(line, index if k == last else None)

    def _poll(self) -> None:
        link = self._link()
        while link.in_waiting:
            line = self._read_line(self.timeout)
            if line is not None:
                self._dispatch(line)

    def _drain(self) -> None:
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
        return self.last_status is not None and self.last_status.held

    def _make_safe(self) -> None:
        """Feed hold and soft reset if anything is queued or moving, then pen up and ``M5``; never raises."""
        try:
            link = self.link
            if link is None or link.closed:
                return
            status = self.query_status()
            if len(self.counter) or status.busy:
                if status.state in ("Run", "Jog"):
                    link.write(REALTIME_HOLD)
                    self._wait_until_still(STOP_WAIT_S, holding=True)
                self.soft_reset()
                status = self.query_status()
            if status.state == "Alarm":
                log.warning("grbl: alarm-locked after stopping; the pen is left as the reset left it (spindle off)")
                return
            for line in [*self.pen_motion.up_lines(), "M5"]:
                self._send_line(line, wait=True)
        except (LinkError, ProtocolError, ParseError) as exc:
            log.warning("grbl: could not leave the plotter safe: %s", exc)

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
                log.warning("grbl: %s during reset: %s", line, ALARM_CODES.get(_code(line), "unknown alarm"))
            elif line not in ("ok",) and not line.startswith("<"):
                log.debug("grbl: before the welcome line: %r", line)

    # -- streaming ---------------------------------------------------------------------------------
    def _send_line(self, line: str, tag: int | None = None, *, wait: bool = False) -> None:
        """Send one G-code line under the streaming mode's flow control; ``tag`` is the stroke it confirms.

        ``wait`` (or ``stream=wait``) sends it alone: everything before it and the line itself acknowledged.
        """
        wait = wait or self.stream == "wait"
        if wait:
            self._drain()
        while not self.counter.fits(line):
            self._wait_reply()
        self._link().write(line.encode("ascii") + b"\n")
        self.counter.sent(line, tag)
        if wait:
            self._drain()

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
            log.info("grbl: %s from before this connection ignored", line)
        elif line == "ok":
            self._idle_polls = 0
            _, tag = self.counter.acknowledged()
            if isinstance(tag, int):
                self._confirm(tag + 1)
        elif line.startswith("error:"):
            code = _code(line)
            sent, _ = self.counter.acknowledged()
            raise ProtocolError(
                f"GRBL rejected a line: error:{code} {ERROR_CODES.get(code, 'unknown error code')}",
                code=code, command=sent, device="grbl",
            )
        elif line.startswith("ALARM:"):
            code = _code(line)
            raise ProtocolError(
                f"GRBL alarm {code}: {ALARM_CODES.get(code, 'unknown alarm code')}",
                code=f"ALARM:{code}", command=self.counter.oldest(), device="grbl",
            )
        elif line.startswith("<"):
            self.last_status = parse_status(line)
        elif parse_welcome(line) is not None:
            self.counter.clear()
            raise LinkError(
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


def _code(line: str) -> int:
    """The number after ``error:`` / ``ALARM:``; ParseError when it is not one."""
    text = line.partition(":")[2].strip()
    if not text.isdigit():
        raise ParseError("expected a number after ':'", source="grbl", token=line)
    return int(text)


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

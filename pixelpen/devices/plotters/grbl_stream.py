"""The GRBL line protocol: lines sent under character counting, replies dispatched, status reports checked.

:class:`GrblStream` is the layer of :class:`~pixelpen.devices.plotters.grbl.GrblPlotter` that talks to the
controller (``ok``/``error:N``/``ALARM:N``, status reports against the path sent, real-time commands, ``$``
queries); the plotter above it connects, encodes strokes, finds where a plot stopped and controls the pen.
See the plotter's module docstring for how strokes are confirmed and checked.
"""

from __future__ import annotations

import contextlib
import logging
import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from pixelpen.devices.plotters.base import PlotterDisplay
from pixelpen.devices.plotters.grbl_encode import (
    ALARM_CODES,
    ERROR_CODES,
    REALTIME_HOLD,
    REALTIME_RESET,
    REALTIME_RESUME,
    REALTIME_STATUS,
    CharacterCounter,
    GrblStatus,
    PathTrack,
    PenMotion,
    parse_code,
    parse_status,
    parse_welcome,
)
from pixelpen.devices.plotters.grbl_garble import Garble, SentLeg, explain_position
from pixelpen.drivers.stream import Link
from pixelpen.errors import Disconnected, LinkError, LinkTimeout, ParseError, ProtocolError

log = logging.getLogger("pixelpen.devices.plotters.grbl")  # the family's one logger, as users filter on it

STATUS_INTERVAL_S = 0.2
"""Least time between two ``?`` polls for pause detection (interface.md: poll at most 5 Hz)."""
TRACK_POLL_S = 0.5
"""Time between two ``?`` while waiting for GRBL during a plot: each report is checked against the path sent."""
IDLE_POLLS_BEFORE_LOSS = 3
"""Status polls that find GRBL idle with lines unacknowledged before the bytes are declared lost."""
STOP_WAIT_S = 10.0
"""Longest wait for a feed hold to bring the carriage to rest when stopping safely."""
SETTLE_LIMIT_S = 120.0
"""Longest wait, after a reconnect, for GRBL to finish the lines it still held from the broken connection."""
TRACK_TOLERANCE_MM = 0.03
"""How far a status report's position may lie off the path sent before the driver calls it a corrupted line
(GRBL steps along a straight leg within one step of it: 0.0125 mm at 80 steps/mm)."""
INK_TOLERANCE_MM = 0.05
"""How near its leg a garbled line must have run to have drawn that leg: a pen's line is 0.1 mm wide or more, so
ink within 0.05 mm of the leg is the leg itself, and the resume does not draw it again."""
GARBLE_ERRORS = frozenset({1, 2, 3, 11, *range(20, 39)})
"""``error:N`` codes a line pixelpen wrote can only earn by being garbled on the wire (syntax, words): said so."""
POSITION_LOSING_ALARMS = frozenset({1, 3, 6, 7, 8, 9, 10})
"""``ALARM:N`` codes after which GRBL's position is likely lost (alarm_codes_en_US.csv: re-homing recommended)."""


@dataclass(frozen=True)
class Tag:
    """What a line's ``ok`` tells: stroke ``stroke`` reached its vertex ``vertex`` with the pen down; stroke ``done`` is
    on paper (its lift's dwell ran) and the track may drop the legs before point number ``track``."""

    stroke: int
    vertex: int | None
    """None for the travel to the stroke's start (the pen is not down yet)."""
    done: int | None = None
    track: int | None = None


class GrblStream(PlotterDisplay):
    """GRBL lines sent and replies handled (the line-protocol layer of GrblPlotter)."""

    stream: str
    """``counting`` (fill the RX buffer) or ``wait`` (one line at a time)."""
    pen_motion: PenMotion
    counter: CharacterCounter
    track: PathTrack
    version: tuple[int, int, str] | None
    last_status: GrblStatus | None
    _tracking: bool
    _wco: np.ndarray
    _lost: str | None
    _reached: tuple[int, int] | None
    _held: bool
    _status_asked: float
    _idle_polls: int
    _stale: bool
    _stale_seen: int
    legs: list[SentLeg]
    _unverified: tuple[int, int | None] | None
    _garbled: Garble | None
    _on_path: tuple[float, float] | None
    _fault_hold: bool

    @contextlib.contextmanager
    def _stale_acks(self) -> Iterator[None]:
        """While inside: acknowledgements and errors are of an earlier connection's lines, counted and ignored."""
        self._stale = True
        try:
            yield
        finally:
            self._stale = False

    def _wait_acks(self) -> None:
        while len(self.counter):
            self._wait_reply()


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
    def _send_line(self, line: str, tag: Tag | None = None, *, wait: bool = False) -> None:
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
        """Handle one line from GRBL; on silence probe with ``?`` and keep waiting while it works or holds.

        While a plot is tracked, GRBL is asked for its status every TRACK_POLL_S meanwhile: each report is
        checked against the path sent, so a garbled line is noticed while it runs, not only at the stroke's end.
        """
        line = self._read_polling(self.timeout)
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
                    f"(oldest {self.counter.oldest()!r}): bytes were lost on the line, or a garbled G4 made it dwell"
                )

    def _read_polling(self, timeout: float) -> str | None:
        """The next line other than a status report (reports are handled), polling ``?`` while tracking a plot."""
        if not self._tracking:
            return self._read_line(timeout)
        deadline = self.clock.now() + timeout
        while True:
            now = self.clock.now()
            if now >= deadline:
                return None
            if now - self._status_asked >= TRACK_POLL_S:
                self._link().write(REALTIME_STATUS)
                self._status_asked = now
            line = self._read_line(max(0.001, min(deadline, self._status_asked + TRACK_POLL_S) - now),
                                   part_ok=True)  # a line still arriving is read on the next turn
            if line is None:
                continue
            if not line.startswith("<"):
                return line
            self._dispatch(line)

    def _dispatch(self, line: str) -> None:
        """Act on one line GRBL sent: acknowledgements, errors, alarms, status reports, messages, restarts."""
        if self._stale and (line == "ok" or line.startswith(("error:", "ALARM:"))):
            self._stale_seen += 1
            log.info("grbl: %s from before this connection ignored", line)
        elif line == "ok":
            self._idle_polls = 0
            sent, tag = self.counter.acknowledged()
            if isinstance(tag, Tag):
                if tag.vertex is not None and "G4" in sent:  # parsed after its dwell: the pen reached the leg's start
                    self._reached = (tag.stroke, max(tag.vertex - 1, 0))
                if tag.done is not None:
                    # confirmed once a report after this ok (GRBL ran the stroke, then the dwell) shows the pen
                    # where the stroke ended: a garbled last vertex is caught before the stroke counts as drawn
                    self._unverified = (tag.done + 1, tag.track) if self._tracking else None
                    if self._unverified is None:
                        self._confirm(tag.done + 1)
                    self._link().write(REALTIME_STATUS)
        elif line.startswith("error:"):
            code = parse_code(line)
            sent, tag = self.counter.acknowledged()
            garbled = code in GARBLE_ERRORS and self._tracking
            self._stop_motion()  # the lines behind the rejected one would draw a shortcut
            leg = next((g for g in self.legs if isinstance(tag, Tag) and g.line == sent
                        and (g.stroke, g.vertex) == (tag.stroke, tag.vertex)), None)
            if leg is not None:
                self._garbled = Garble(leg, None)  # it never ran: the resume draws from its start on
            elif isinstance(tag, Tag):
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

    def _read_line(self, timeout: float, *, part_ok: bool = False) -> str | None:
        """One non-empty line from GRBL without its ending, or None when ``timeout`` passed in silence.

        A line still arriving when ``timeout`` passes raises LinkTimeout, or (``part_ok``) stays buffered: None.
        """
        link = self._link()
        while True:
            try:
                raw = link.read_until(b"\n", timeout=timeout, max_size=256)
            except LinkTimeout as exc:
                if getattr(exc, "partial", b"") and not part_ok:
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
        # paused once the carriage rests: Hold:0 (Hold:1 still decelerates, and GRBL ignores a cycle start then),
        # Door:0/1 (closed ready to resume / stopped, door ajar)
        stopped = status.held and status.substate in ((0, None) if status.state == "Hold" else (0, 1, None))
        if stopped != self._held and (stopped or not status.held) and not self._fault_hold:
            self._held = stopped
            self._pause_changed(stopped)
        if self._tracking and status.state in ("Run", "Idle", "Hold", "Jog"):
            where, pen = self._work_units(status), self._pen_down_of(status)
            tolerance = TRACK_TOLERANCE_MM / self.profile.unit_mm
            why = self.track.check(where, pen, tolerance)
            if why is not None:
                self._stop_motion()
                garble = explain_position(self.legs, where, pen, tolerance, self.profile.unit_mm, self._s_is_down,
                                          since=self._on_path)
                if garble is not None:
                    self._garbled = garble  # that line ran garbled: drawn right up to its start, and along it
                else:
                    self._mark_damaged(range(self.confirmed, max(self._sent_end, self.confirmed + 1)))
                self._unverified = None
                raise LinkError(
                    f"grbl: position check failed: {why} (GRBL reports {status.state} at {self._work_units(status)} "
                    "units): a line was changed on the wire (a dropped byte), so the plot stops here"
                )
            self._on_path = where
            if self._unverified is not None:
                done, track = self._unverified
                self._unverified = None
                self._confirm(done)
                self.track.done_until(track)  # type: ignore[arg-type]
                self.legs = [g for g in self.legs if g.stroke >= done]

    def _stop_motion(self) -> None:
        """Feed hold now, so nothing more is drawn after a fault (the reconnect's soft reset clears the rest).

        The hold is the driver's own: it is not announced as the device's pause (nobody should resume it)."""
        self._tracking = False
        self._fault_hold = True
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
        return self._s_is_down(status.spindle)

    def _s_is_down(self, s: float) -> bool:
        """Whether a servo pen is down at spindle value ``s`` (nearer the pen-down S value than the pen-up one)."""
        motion = self.pen_motion
        up = 0.0 if motion.up is None else motion.up
        return s > 0 and abs(s - motion.down) < abs(s - up)

    def _settled_status(self) -> GrblStatus:
        """Poll until GRBL has run all it received: a completed hold, or at rest and silent for longer than a dwell.

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
            if status.held and status.substate in ((0,) if status.state == "Hold" else (0, 1)):
                return status  # at rest; nothing runs before a resume, and the reconnect's soft reset discards it
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
                    raise ProtocolError(f"GRBL refused {command}", code=parse_code(line), command=command,
                                        device="grbl")
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

"""The EiBotBoard's command stream: one command in flight, refused ones sent again, replies in both syntaxes.

:class:`EBBStream` is the layer of :class:`~pixelpen.devices.plotters.axidraw.AxiDrawPlotter` that writes EBB
commands and reads their replies (``OK``, data, ``!n Err``; the future syntax ``CU,10,1``), confirms strokes by
the motion FIFO count, certifies queued commands with supply checks (and acknowledges where they got to), and
acts on a supply failure and the PRG button; the plotter above it connects, plans and slices moves, finds where
a plot stopped and controls the pen.  See the plotter's module docstring.
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pixelpen.devices.plotters.base import PlotterDisplay
from pixelpen.devices.plotters.ebb_encode import (
    VPLUS_MIN_RAW,
    parse_error,
    parse_qc,
    parse_qg,
    parse_qm,
    parse_qs,
    parse_version_reply,
    reply_shape,
    strip_name,
    supports,
    vplus_volts,
)
from pixelpen.devices.plotters.resume import ResumePoint
from pixelpen.drivers.stream import Link
from pixelpen.errors import Disconnected, LinkError, LinkTimeout, ParseError, ProtocolError

log = logging.getLogger("pixelpen.devices.plotters.axidraw")  # the family's one logger, as users filter on it

WINDOW = 1
"""Commands written ahead of their replies.  One: a command goes out only once the board has answered the one
before it, so when a garbled command is refused nothing behind it has reached the board yet (a move run after
a refused one would run shifted) and the same command can simply be sent again; the motion FIFO still holds the
next move while one executes, so the carriage does not stop between slices."""
RETRIES = 2
"""Times a refused command is sent again (a byte garbled on the wire) before the refusal stops the plot."""
IDLE_POLL_S = 0.01
FIFO_DEPTH = 1
"""Motion FIFO depth at boot (ebb.html CU,4); the driver does not change it."""
QG_POWER_LOST, QG_BUTTON, QG_PEN_UP = 0x40, 0x20, 0x10
"""QG status bits (ebb.html QG; bit 6 latches a V+ drop below the CU,60 threshold, fw >= 3.0)."""


@dataclass
class Sent:
    """A command written to the board and not yet answered."""

    text: str
    queued: bool
    duration_s: float
    on_reply: Callable[[str], None] | None = None
    reached: tuple[int, int] | None = None
    """(stroke, vertex) the pen is down at once this queued command has run."""
    stroke: int | None = None
    """The stroke this command belongs to (its travel, pen moves and slices)."""
    certifies: int | None = None
    """A ``QC`` supply check: the number of queued commands that have finished by the time the board reads it."""
    tries: int = 1


@dataclass(frozen=True)
class Progress:
    """What a queued command leaves behind once it has run: the carriage (steps), the pen, the drawing reached."""

    count: int
    """Its place among the queued commands of this link (1 = the first)."""
    position: tuple[int, int]
    pen_down: bool
    place: ResumePoint | None
    """Where the drawing stands once it has run, in the points given to ``_send_stroke`` (None: a travel)."""


class EBBStream(PlotterDisplay):
    """EBB commands sent and replies handled (the command layer of AxiDrawPlotter)."""

    version: tuple[int, int, int] | None
    """Firmware version from ``V``."""
    future_syntax: bool
    """True when the board answers in the future syntax (``CU,10,1``)."""
    _unanswered: deque[Sent]
    _queued_acked: int
    _queued_sent: int
    _marks: deque[tuple[int, int]]
    """(queued commands sent up to a stroke's pen lift, the stroke): confirmed once the FIFO count passes it."""
    position: np.ndarray
    """Carriage position in steps once everything sent has run."""
    _paused: bool
    _lost: str | None
    _reached: tuple[int, int] | None
    _stroke_now: int | None
    _power_good: int

    _progress: deque[Progress]
    """Queued commands sent and not yet certified, with what each leaves behind once it has run."""
    _certified: Progress | None
    """The last queued command known to have finished with the motor supply on (its count 0: the link's start)."""
    _cut: Progress | None
    """After a supply failure: the last place known to be reached with the motors powered (where drawing stopped)."""

    # -- motor power -----------------------------------------------------------------------------
    def _queue(self, text: str, duration_s: float, position: np.ndarray, pen_down: bool,
               reached: tuple[int, int] | None = None, place: ResumePoint | None = None) -> None:
        """Write a motion-queue command and note what it leaves behind once it has run (carriage in steps, pen).

        Inside a stroke (travel, pen moves, slices) a supply check follows every one of them, written together
        with it: a supply failure is then placed to one queued command.
        """
        self._command(text, queued=True, duration_s=duration_s, reached=reached)
        self._progress.append(Progress(self._queued_sent, (int(position[0]), int(position[1])), pen_down, place))
        if self._stroke_now is not None:
            self._supply_check()

    def _supply_check(self) -> None:
        """A supply check behind the last queued command: a good one certifies every queued command finished before it.

        ``QG`` on fw >= 3 (its bit 6 latches any drop below the CU,60 threshold since the last QG, and the answer
        is 4 bytes), else ``QC``.  The board reads it once the command before it has entered the FIFO, so all but
        the FIFO_DEPTH + 1 newest queued commands have finished by then.  It is written together with that command
        (not waiting for its answer): both reach the board at one moment, so two checks in a row bracket exactly
        one queued command.
        """
        query = "QG" if supports(self.version or (0, 0, 0), "queued_EM") else "QC"
        self._command(query, certifies=self._queued_sent - (FIFO_DEPTH + 1), window=WINDOW + 1)

    def _power_gate(self) -> None:
        """Before the pen goes down: two 1 ms pauses, whose checks certify the travel before the pen command is sent.

        The pen goes down only where the carriage is known to have arrived with the motors powered (never on a
        travel the motors stopped part way).
        """
        for _ in range(FIFO_DEPTH + 1):
            self._queue("SM,1,0,0", 0.001, self.position, pen_down=False)

    def _status_check(self) -> None:
        """``QG`` on fw >= 3: the power-lost latch (a supply dip between two checks) and the PRG button."""
        if supports(self.version or (0, 0, 0), "queued_EM"):
            self._command("QG", on_reply=lambda data: self._status_byte(parse_qg(data)))

    def _supply(self, raw: int, certified: int) -> None:
        """Act on a V+ reading: below VPLUS_MIN_RAW the motors stood still, so the plot stops with the position lost."""
        if raw < VPLUS_MIN_RAW:
            self._supply_failed(f"the motor supply failed during the plot (QC V+ {vplus_volts(raw):.1f} V)")
            raise Disconnected(
                f"axidraw: motor power lost: QC reads V+ {vplus_volts(raw):.1f} V (a powered board reads "
                f"{vplus_volts(VPLUS_MIN_RAW):.1f} V or more); the carriage stopped while the steps were counted, so "
                "where the pen is is unknown: switch the power on, move the carriage home and resume with the "
                "position confirmed"
            )
        self._certify(certified)

    def _certify(self, certified: int) -> None:
        """The first ``certified`` queued commands finished with the motors powered: acknowledge where they got to."""
        self._power_good = max(self._power_good, certified)
        place = None
        while self._progress and self._progress[0].count <= certified:
            self._certified = self._progress.popleft()
            place = self._certified.place or place
        if place is not None:
            self._acknowledge(place)

    def _acknowledge(self, place: ResumePoint) -> None:
        """Tell the base the drawing is on paper up to ``place``, where a confirmed resume after re-homing goes on.

        The base's ``_acknowledged`` takes a vertex; a place inside a segment gets its point added here (a request
        to the base's owner: ``_acknowledged(stroke, k, at)``).
        """
        if place.stroke < self.confirmed:
            return
        self._acknowledged(place.stroke, place.vertex)
        if place.at is not None and self._ack is not None and self._ack.stroke == place.stroke:
            self._ack = replace(self._ack, at=place.at)

    def _supply_failed(self, why: str) -> None:
        """Stop the moves still queued (they would run on once the supply is back); remember the last powered place."""
        self._abort_motion()
        self._lost = why
        if self._cut is None:
            self._cut = self._certified

    def _status_byte(self, bits: int) -> None:
        """A ``QG`` byte: PRG button presses toggle the pause; the power-lost latch stops the plot."""
        if bits & QG_POWER_LOST:
            self._supply_failed("the motor supply dropped during the plot (QG power-lost flag)")
            raise Disconnected(f"axidraw: motor power lost: V+ fell below {vplus_volts(VPLUS_MIN_RAW):.1f} V (QG "
                               "power-lost flag); the carriage stopped while the steps were counted, so where the "
                               "pen is is unknown: switch the power on, move the carriage home and resume with the "
                               "position confirmed")
        self._button(bool(bits & QG_BUTTON))

    # -- commands and replies --------------------------------------------------------------------
    def _command(self, text: str, *, queued: bool = False, duration_s: float = 0.0,
                 on_reply: Callable[[str], None] | None = None, reached: tuple[int, int] | None = None,
                 certifies: int | None = None, window: int = WINDOW) -> None:
        """Write one command (keeping fewer than ``window`` unanswered); ``queued`` ones enter the motion FIFO."""
        while len(self._unanswered) >= window:
            self._read_reply()
        self._send(Sent(text, queued, duration_s, on_reply, reached, self._stroke_now, certifies))
        if queued:
            self._queued_sent += 1

    def _send(self, sent: Sent) -> None:
        self._link().write(sent.text.encode("ascii") + b"\r")
        self._unanswered.append(sent)

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
        if error is not None and sent.tries <= RETRIES:
            self._send_again(sent, error)
            return None
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
        if sent.certifies is not None and _name(sent.text) == "QG":
            self._status_byte(parse_qg(data or ""))
            self._certify(sent.certifies)
        elif sent.certifies is not None:
            self._supply(parse_qc(data or "")[1], sent.certifies)
        if sent.on_reply is not None:
            sent.on_reply(data or "")
        return data

    def _send_again(self, sent: Sent, error: tuple[int, str]) -> None:
        """A refused command (garbled on the wire: pixelpen sends only valid ones) goes out again, in its place.

        Nothing behind it ran (WINDOW); a supply check written together with it was read by the board one queued
        command earlier than counted, so it certifies one command less.
        """
        log.warning("axidraw: the EBB refused %r (!%d Err: %s); sending it again (%d/%d)",
                    sent.text, error[0], error[1], sent.tries, RETRIES)
        if sent.queued:
            for later in self._unanswered:
                if later.certifies is not None:
                    later.certifies -= 1
        self._send(replace(sent, tries=sent.tries + 1))

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
        self._progress.clear()
        self._certified = None
        self._queued_acked = self._queued_sent = self._power_good = 0

    def _button(self, pressed: bool) -> None:
        if pressed:
            self._paused = not self._paused
            log.info("axidraw: PRG button: %s", "pausing at the next pen-up" if self._paused else "resuming")

    def _link(self) -> Link:
        if self.link is None:
            raise LinkError("axidraw: the plotter is not connected")
        return self.link

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

"""The HP-GL byte stream under a handshake: sync points, ESC queries, answers matched to their requests.

:class:`HPGLStream` is the layer of :class:`~pixelpen.devices.plotters.hpgl.HPGLDisplay` that writes HP-GL and
reads answers; the display above it connects, encodes strokes, finds where a plot stopped and controls the pen.

Flow control (option ``handshake``, plotters.md §1.5):

* ``escb`` (default): software checking.  ``ESC.B`` answers the free bytes F of the input buffer at
  the moment the query arrives, i.e. after every byte written before it.  With W the HP-GL bytes
  written so far and W_q those written before the query, the host may write an instruction of L
  bytes only while ``L <= F - (W - W_q) - reserve``: the buffer then never holds more than its
  size minus ``reserve`` (default 128: a real 7475A overflows when filled to the exact figure).
  The plotter is never starved while the host has data: the host writes until the room falls to
  ``LOW_WATER`` bytes, sends ``ESC.B`` behind that data and then writes the rest of the room, so
  the answer returns while data is still on the wire and fresh room is known before the old runs
  out.  A query that finds too little room is repeated after ``POLL_S`` seconds, the gap doubling
  up to ``MAX_POLL_S`` while the plotter takes nothing (a pen change); meanwhile the buffer still
  holds its size minus the reserve minus one instruction, far more than the plotter draws in
  MAX_POLL_S.
* ``xonxoff``: ``ESC.(;ESC.I81;;17:ESC.N;19:`` makes the plotter send XOFF (DC3) below 81 free
  bytes and XON (DC1) at 128; the link holds writes while XOFF is in force (software flow control).
* ``hardwire``: ``ESC.@;1:`` makes the plotter hold DTR low while it is full; the link runs RTS/CTS.
* ``none``: no flow control (for plotters fed slower than they draw; overflows otherwise).

With ``xonxoff`` and ``hardwire`` the plotter's handshake holds every byte, queries included, so a
pause longer than ``stall`` with a full buffer counts as a stall there; ``escb`` asks ESC.O instead.
Writes there go out in chunks of ``WRITE_CHUNK`` bytes, each allowed ``stall`` seconds: the limit is on
the plotter taking nothing, not on the time a long stroke needs at the line's speed.

Confirmation and errors: with ``escb`` an ESC.B answer confirms every stroke whose last byte lies
``CONFIRM_MARGIN`` bytes before what the plotter has taken from its buffer; after every ``sync_strokes``
strokes or ``sync_bytes`` bytes (at pen-up) the driver sends ``PU;OA;OE;`` and ``ESC.E``.  OA and OE are
buffered output instructions, answered when execution reaches them, so their answers confirm every stroke
before them; the answers are read as they arrive, never waited for while there is data to send.  A non-zero
OE (HP-GL error) or ESC.E (RS-232 error) raises :class:`~pixelpen.errors.ProtocolError` with the code, its
meaning and the instructions sent since the previous sync point.  Replies are told apart by form: OA answers
``x,y,pen``, OE follows its OA at once, and numbers arriving otherwise answer the ``ESC`` queries in the
order they were sent.  When nothing moves for ``PAUSE_CHECK_S`` the driver asks ``ESC.O``: VIEW (16) or the
raised paper lever (32) is a pause and waits without limit; no progress for ``stall`` seconds otherwise is a
fault (LinkTimeout).  Ctrl-C and close send ``ESC.K`` then ``PU;SP0;`` and the park move.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from pixelpen.devices.plotters import hpgl_encode as enc
from pixelpen.devices.plotters.base import PlotterDisplay
from pixelpen.devices.plotters.hpgl_replies import (
    BYTES_LOST,
    ERROR_OUTPUT_BUSY,
    HPGL_ERRORS,
    IO_ERRORS,
    MAX_OE,
    MAX_REPLY,
    NUMBER_ANSWER,
    STATUS_PAPER_LEVER,
    STATUS_VIEW,
    clean,
    describe_instructions,
    is_marker,
)
from pixelpen.drivers.stream import Link
from pixelpen.errors import LinkError, LinkTimeout, ProtocolError

log = logging.getLogger("pixelpen.devices.plotters.hpgl")  # the family's one logger, as users filter on it


POLL_S = 0.05
"""Seconds before asking ESC.B again after an answer that found too little room (see ``_wait``)."""
LOW_WATER = 2 * enc.MAX_INSTRUCTION
"""Room (bytes) at which ESC.B is asked behind the data written so far (escb)."""
MAX_POLL_S = 0.25
"""Longest gap between ESC.B queries while waiting; the plotter still holds buffer-size minus reserve bytes."""
PAUSE_CHECK_S = 1.0
"""Seconds without progress after which the driver asks ESC.O whether the plotter is paused."""
CONFIRM_MARGIN = 2 * enc.MAX_INSTRUCTION
"""Bytes the plotter must have taken from its buffer beyond a stroke's last byte before ESC.B confirms the stroke
(the instruction being drawn and one read ahead; the simulator reads one instruction at a time)."""
WRITE_CHUNK = 512
"""Bytes written at a time under xonxoff/hardwire; each chunk must be taken within ``stall`` seconds."""


@dataclass
class SyncPoint:
    """Output requests in the stream: answered once the plotter has executed everything before them."""

    confirms: int | None
    """Strokes < confirms are on paper when the answers come (None: the connect handshake)."""
    instructions: list[bytes]
    """HP-GL sent since the previous sync point (what an error here was caused by)."""
    first_stroke: int
    marker: str = "OA"
    """The answer before OE: ``OA`` (x,y,pen) or ``OI`` (the model name)."""
    seen: str | None = None
    """The marker's answer once it came."""
    expect: tuple[int, int] | None = None
    """Where OA must find the pen (the end of the last stroke before the sync point; None: not checked)."""
    check: Check | None = None
    """The one instruction this checkpoint follows (``verify=instruction``); None: a sync point."""


@dataclass
class Check:
    """What one instruction of a stroke should have done, for the ``OA;OE;`` checkpoint behind it."""

    kind: str
    """``SP`` (pen select), ``PU`` (travel to the stroke's first point) or ``PD`` (a vector list)."""
    stroke: int | None
    """The stroke it belongs to (SP: the stroke after it, set when that stroke is sent)."""
    points: np.ndarray | None = None
    """The points given to ``_send_stroke`` for that stroke."""
    lo: int = 0
    """PD: the first vertex it draws to (its vectors start from the one before); PU: 0."""
    hi: int = 0
    """The vertex the pen stands on once it ran (PU: 0)."""
    last: bool = False
    """The stroke's last instruction: its checkpoint confirms the stroke."""


@dataclass
class Query:
    """An ESC query waiting for its immediate answer."""

    kind: str
    deadline: float
    written: int
    """HP-GL bytes written before the query (ESC.B's answer describes the buffer after them)."""
    sent: int
    """All bytes written before and including the query."""
    sync: SyncPoint | None = None
    """For ESC.E: the sync point whose bytes it covers."""


@dataclass
class Wire:
    """Protocol state of one connection (replaced on every connect)."""

    rx: bytearray = field(default_factory=bytearray)
    syncs: deque[SyncPoint] = field(default_factory=deque)
    queries: deque[Query] = field(default_factory=deque)
    window: list[bytes] = field(default_factory=list)
    window_first: int = 0
    strokes_sent: int = 0
    last_point: tuple[int, int] | None = None
    """End of the last stroke sent (where the next sync point's OA must find the pen)."""
    size: int | None = None
    """The plotter's buffer size (ESC.B on the empty buffer after the connect handshake; escb only)."""
    ends: deque[tuple[int, int]] = field(default_factory=deque)
    """(HP-GL bytes written up to a stroke's end, strokes done then) not yet confirmed by ESC.B."""
    since_sync_strokes: int = 0
    since_sync_bytes: int = 0
    written: int = 0
    """HP-GL bytes written (they take buffer space)."""
    sent: int = 0
    """Every byte written, device control included."""
    delivered: int = 0
    """Bytes known to have reached the plotter (those before an answered ESC query)."""
    free: tuple[int, int] | None = None
    """Last ESC.B answer and the HP-GL bytes written before its query."""
    mark: int | None = None
    """written-before-query + free of the last ESC.B: grows exactly as the plotter consumes bytes."""
    free_answers: int = 0
    """ESC.B answers received."""
    status: int = 0
    """Last ESC.O answer."""
    progress_at: float = 0.0
    last_free_ask: float = -math.inf
    last_status_ask: float = -math.inf
    received_any: bool = False
    connecting: bool = False
    pending_pen: Check | None = None
    """The check of an SP sent before the stroke it selects the pen for."""


class HPGLStream(PlotterDisplay):
    """HP-GL written under the handshake and answers read and matched (the streaming layer of HPGLDisplay)."""

    mnemonics: ClassVar[frozenset[str]]
    """HP-GL instructions the model knows (an error 1 names a sent one outside it)."""
    handshake: str
    verify: str
    reserve: int
    sync_strokes: int
    sync_bytes: int
    stall_s: float
    _wire: Wire

    def _send(self, instructions: list[bytes], before_write: Callable[[int], None] | None = None) -> None:
        """Write HP-GL instructions under the handshake, recording them in the current sync window.

        ``before_write(j)`` is called before instructions up to ``j`` (exclusive) start going out.
        """
        w = self._wire
        w.window.extend(instructions)
        if self.handshake != "escb":
            if before_write is not None:
                before_write(len(instructions))
            self._write(b"".join(instructions), graphics=True)
            return
        i = 0
        while i < len(instructions):
            room = self._room()
            # write down to the low-water mark, ask ESC.B behind that data, then write the rest of the room:
            # the answer comes back while the rest is still on the wire
            limit = room - LOW_WATER if room > LOW_WATER and not self._asking("B") else room
            j, size = i, 0
            while j < len(instructions) and size + len(instructions[j]) <= (limit if j > i else room):
                size += len(instructions[j])
                j += 1
            if j == i:
                self._wait_for_room(len(instructions[i]))
                continue
            if before_write is not None:
                before_write(j)
            self._write(b"".join(instructions[i:j]), graphics=True)
            i = j
            if self._room() <= LOW_WATER and not self._asking("B"):
                self._ask("B")

    def _send_checked(self, items: list[tuple[bytes, Check]]) -> None:
        """Write instructions each followed by its ``OA;OE;`` checkpoint (``verify=instruction``)."""
        w = self._wire
        for instruction, check in items:
            s = check.stroke if check.stroke is not None else 0
            w.syncs.append(SyncPoint(s + 1 if check.last else None, [instruction], s, check=check))

        def going_out(j: int) -> None:  # parts[:j] may reach the plotter: the last instruction among them bounds it
            check = items[(j - 1) // 2][1]
            if check.stroke is not None and check.kind != "SP":
                self._written_to(check.stroke, check.hi)

        self._send([part for instruction, _ in items for part in (instruction, enc.SYNC_REQUEST)], going_out)

    def _wait_for_room(self, need: int) -> None:
        self._wait(lambda: self._room() >= need, "waiting for room in the plotter's buffer", poll=POLL_S, backoff=True)

    def _sync(self) -> None:
        """``PU;OA;OE;`` and ``ESC.E``: confirm every stroke so far and check both error registers."""
        w = self._wire
        point = SyncPoint(w.strokes_sent, w.window, w.window_first, expect=w.last_point)
        w.syncs.append(point)
        if w.strokes_sent:
            self._lifted_in_place(w.strokes_sent - 1)  # the PU; below
        self._send([enc.PEN_UP, enc.SYNC_REQUEST])
        w.window, w.window_first = [], w.strokes_sent
        w.since_sync_strokes = w.since_sync_bytes = 0
        self._ask("E", sync=point)

    def _room(self) -> int:
        """HP-GL bytes the host may write now without eating into the reserve (escb)."""
        w = self._wire
        if w.free is None:
            return 0
        free, written_then = w.free
        return free - (w.written - written_then) - self.reserve

    def _write(self, data: bytes, *, graphics: bool) -> None:
        link = self._require_link()
        # with a device-driven handshake a write may rightly wait as long as the plotter is busy
        # (stall_s per chunk: a stall is no chunk taken for that long, however long the whole stroke takes)
        held = self.handshake in ("xonxoff", "hardwire")
        step = WRITE_CHUNK if held else max(1, len(data))
        for at in range(0, len(data), step):
            chunk = data[at:at + step]
            link.write(chunk, timeout=self._limit(link, self.stall_s) if held else None)
            self._wire.sent += len(chunk)
            if graphics:
                self._wire.written += len(chunk)
            if held:
                self._wire.progress_at = self.clock.now()  # the handshake let it through: the plotter is taking bytes

    def _ask(self, kind: str, *, sync: SyncPoint | None = None) -> None:
        """Send ``ESC.<kind>`` and expect its immediate answer (deadline: time for the bytes ahead + timeout)."""
        w = self._wire
        ahead = w.sent - w.delivered + 3
        limit = self.timeout + ahead * 10.0 / max(1, self.baudrate)
        if self.handshake in ("xonxoff", "hardwire"):
            limit += self.stall_s  # bytes ahead of the query wait for the plotter to take them
        data = {"B": enc.ASK_FREE, "E": enc.ASK_IO_ERROR, "O": enc.ASK_STATUS}[kind]
        self._write(data, graphics=False)
        now = self.clock.now()
        w.queries.append(Query(kind, now + limit, w.written, w.sent, sync))
        if kind == "B":
            w.last_free_ask = now
        elif kind == "O":
            w.last_status_ask = now

    def _asking(self, kind: str) -> bool:
        return any(q.kind == kind for q in self._wire.queries)

    def _ask_status_if_due(self, now: float) -> None:
        link = self._require_link()
        if not self._asking("O") and now - self._wire.last_status_ask >= PAUSE_CHECK_S / 2 and not link.held_off:
            self._ask("O")

    # -- waiting and reading -----------------------------------------------------------------
    def _wait(
        self, done: Callable[[], bool], what: str, *, poll: float | None = None, backoff: bool = False
    ) -> None:
        """Read answers until ``done()``; a paused plotter is waited for, one that stopped for ``stall`` s is a fault.

        With ``poll`` ESC.B is asked every ``poll`` seconds; with ``backoff`` the gap doubles (up to
        MAX_POLL_S) after an answer showing the plotter took nothing since the one before (a pen change),
        and is ``poll`` again after one showing it took bytes.
        """
        w = self._wire
        announced = False
        interval, answers, mark = poll, w.free_answers, w.mark
        while True:
            self._pump()
            if done():
                if announced:
                    log.info("%s: plotting resumed", self.profile.name)
                    self._pause_changed(False)
                return
            now = self.clock.now()
            self._check_overdue(now)
            paused = bool(w.status & (STATUS_VIEW | STATUS_PAPER_LEVER))
            if paused:
                if not announced:
                    why = "the paper lever is raised" if w.status & STATUS_PAPER_LEVER else "VIEW is pressed"
                    log.info("%s: paused (%s); waiting", self.profile.name, why)
                    announced = True
                    self._pause_changed(True)
                w.progress_at = now
            elif now - w.progress_at > self.stall_s:
                raise LinkTimeout(
                    f"{self._name()}: {what}: the plotter made no progress for {self.stall_s:g} s and is not paused "
                    f"(ESC.O answered {w.status})"
                )
            if paused or now - w.progress_at >= PAUSE_CHECK_S:
                self._ask_status_if_due(now)
            slice_s = PAUSE_CHECK_S / 2
            if interval is not None and not paused:
                if backoff and poll is not None and w.free_answers != answers:
                    interval = poll if w.mark != mark else min(2 * interval, MAX_POLL_S)
                    answers, mark = w.free_answers, w.mark
                if not self._asking("B") and not self._held():
                    due = w.last_free_ask + interval
                    if now >= due:
                        self._ask("B")
                    else:
                        slice_s = min(slice_s, due - now)
            self._pump(slice_s)

    def _held(self) -> bool:
        link = self.link
        return link is not None and link.held_off

    def _pump(self, wait: float = 0.0) -> int:
        """Act on every complete answer that arrived, waiting up to ``wait`` s for one; return how many."""
        link = self._require_link()
        w = self._wire
        deadline = self.clock.now() + wait
        handled = 0
        while True:
            remaining = 0.0 if handled else max(0.0, deadline - self.clock.now())
            data = link.read(4096, timeout=remaining)
            if not data:
                return handled
            w.rx += data
            while (end := w.rx.find(b"\r")) >= 0:
                if end > MAX_REPLY:
                    raise LinkError(f"{self._name()}: answer longer than {MAX_REPLY} bytes: {bytes(w.rx[:40])!r}...")
                line = bytes(w.rx[:end])
                del w.rx[: end + 1]
                self._on_answer(clean(line))
                handled += 1
            if len(w.rx) > MAX_REPLY:
                raise LinkError(f"{self._name()}: answer longer than {MAX_REPLY} bytes: {bytes(w.rx[:40])!r}...")

    def _on_answer(self, text: str) -> None:
        """Match one answer line to the request it answers (see the module docstring)."""
        if not text:
            return
        w = self._wire
        w.received_any = True
        head = w.syncs[0] if w.syncs else None
        if head is not None and head.seen is not None:
            if not (NUMBER_ANSWER.fullmatch(text) and 0 <= int(text) <= MAX_OE):
                raise LinkError(
                    f"{self._name()}: expected the OE answer after {head.marker}, got {text!r} "
                    "(the OE request was lost or garbled on the way)"
                )
            self._on_oe(head, int(text))
            return
        if head is not None and is_marker(head.marker, text):
            head.seen = text
            if head.expect is not None:
                x, y, _ = (int(v) for v in text.split(","))
                if (x, y) != head.expect:
                    if self.verify != "instruction":  # with checkpoints every drawing instruction was checked
                        self._mark_damaged(range(head.first_stroke, head.confirms or head.first_stroke))
                    raise LinkError(
                        f"{self._name()}: OA found the pen at {x},{y} after {_strokes(head)}, not at "
                        f"{head.expect[0]},{head.expect[1]} where they end (an instruction was corrupted or lost)"
                    )
            return
        if NUMBER_ANSWER.fullmatch(text) and w.queries:
            self._on_query_answer(w.queries.popleft(), int(text))
            return
        if w.connecting:  # answers to requests of an earlier connection, sent before our ESC.K
            log.debug("%s: stale answer %r before the connect handshake; ignored", self._name(), text)
            return
        expected = [f"{head.marker} answer" if head else None] + [f"ESC.{q.kind} answer" for q in list(w.queries)[:1]]
        raise LinkError(
            f"{self._name()}: unexpected answer {text!r} "
            f"(expected {' or '.join(e for e in expected if e) or 'nothing'})"
        )

    def _on_oe(self, point: SyncPoint, code: int) -> None:
        w = self._wire
        w.syncs.popleft()
        if point.check is not None:
            self._on_check(point, point.check, code)
        elif code and point.confirms is not None and self.verify == "instruction":
            # every instruction before this sync point passed its own checkpoint: the error hit the PU; or
            # bytes outside any drawing instruction (a garbled ESC query), and nothing is missing from the paper
            log.warning("%s: HP-GL error %d (%s) after %s, outside every drawing instruction (each checked); "
                        "nothing is missing", self.profile.name, code, HPGL_ERRORS.get(code, "unknown error"),
                        _strokes(point))
        elif code:
            strokes = "the setup instructions" if point.confirms is None else _strokes(point)
            if point.confirms is not None:
                self._mark_damaged(range(point.first_stroke, point.confirms))
            raise ProtocolError(
                f"HP-GL error {code} ({HPGL_ERRORS.get(code, 'unknown error')}) in {strokes}",
                code=code, command=self._culprit(point.instructions, code), device=self.profile.name,
            )
        w.progress_at = self.clock.now()
        w.status = 0
        if point.confirms is not None:
            self._confirm(point.confirms)

    def _on_check(self, point: SyncPoint, check: Check, code: int) -> None:
        """An instruction's checkpoint answered: fine, or record exactly what of it is missing and raise.

        HP-GL runs on after an erroneous instruction (plotters.md §1.4), so a garbled byte costs one instruction
        at most: an SP not done, a PU not done or gone to a truncated point, or a PD list cut short at a pair
        (a pair whose Y lost its tail digits is drawn to that point first).  OA tells which: the stroke's
        points from where the pen stopped to the instruction's end are missing (``_mark_missing``), nothing else.
        OA where the instruction ends means it ran whole (a garbled terminator); OA elsewhere with OE 0 means
        the answers are out of step (a link fault, nothing marked).
        """
        seen = point.seen or ""
        x, y, pen = (int(v) for v in seen.split(","))
        s = check.stroke if check.stroke is not None else self._sent_end
        what = f"HP-GL error {code} ({HPGL_ERRORS.get(code, 'unknown error')}) in stroke {s}"
        command = describe_instructions(point.instructions)
        if check.kind == "SP":
            if not code:
                return
            job = self._job
            stop = s + 1
            while job is not None and stop < len(job) and int(job.pens[stop]) == int(job.pens[s]):
                stop += 1
            self._mark_damaged(range(s, stop))  # drawn with the pen held before: all of them again, in their pen
            raise ProtocolError(f"{what}: the pen was not changed", code=code, command=command,
                                device=self.profile.name)
        pts = check.points
        assert pts is not None
        end = (int(pts[check.hi, 0]), int(pts[check.hi, 1]))
        if (x, y) == end and bool(pen) == (check.kind == "PD"):
            if check.stroke is not None:
                self._acknowledged(check.stroke, check.hi)
            if code:
                log.warning("%s: %s, but OA shows it drawn as sent (a garbled terminator); nothing is missing",
                            self.profile.name, what)
            if point.confirms is not None:
                self._confirm(point.confirms)
            return
        if not code:
            raise LinkError(f"{self._name()}: OA answered {seen} after stroke {s}'s {check.kind}, not "
                            f"{end[0]},{end[1]}, with no HP-GL error: the answers are out of step")
        missing = self._missing_after(check, (x, y))
        if missing is None:
            self._mark_damaged(range(s, s + 1))  # where it stopped fits no single place: the stroke again whole
        else:
            self._mark_missing(s, missing)
            self._confirm(s + 1)  # the rest of it is on paper; the missing piece is kept apart
        raise ProtocolError(
            f"{what}: the plotter stopped its {check.kind} at {x},{y}; "
            + ("the stroke is drawn again" if missing is None else f"the resume draws the {len(missing) - 1} "
               "missing segment(s) only"),
            code=code, command=command, device=self.profile.name,
        )

    @staticmethod
    def _missing_after(check: Check, at: tuple[int, int]) -> np.ndarray | None:
        """The points of the stroke still to draw after ``check``'s instruction stopped at ``at`` (None: unknown)."""
        pts = check.points
        assert pts is not None
        if check.kind == "PU":
            return pts[: min(2, len(pts))].copy()  # the PD after it drew from the wrong place to point 1
        tail = min(len(pts), check.hi + (1 if check.last else 2))  # a PD after it joined its end to the next point
        start = max(0, check.lo - 1)
        stops = [j for j in range(start, check.hi) if (int(pts[j, 0]), int(pts[j, 1])) == at]
        if len(stops) == 1:
            return pts[stops[0]:tail].copy()  # a pair failed: the list stopped on the vertex before it
        if stops:
            return None
        # a pair whose Y lost its last digits was drawn to (X, truncated Y): the list stopped there
        cut = [j for j in range(max(1, check.lo), check.hi + 1) if int(pts[j, 0]) == at[0]
               and str(int(pts[j, 1])).startswith(str(at[1])) and str(int(pts[j, 1])) != str(at[1])]
        return pts[cut[0] - 1:tail].copy() if len(cut) == 1 else None

    def _on_query_answer(self, q: Query, value: int) -> None:
        w = self._wire
        w.delivered = max(w.delivered, q.sent)
        if q.kind == "B":
            if not 0 <= value <= 1 << 20:
                raise LinkError(f"{self._name()}: ESC.B answered {value}, not a buffer size")
            mark = q.written + value
            if w.mark is None or mark > w.mark:
                w.progress_at = self.clock.now()
                w.status = 0
            w.mark = mark
            w.free = (value, q.written)
            w.free_answers += 1
            if w.size is not None:  # the plotter took every byte before mark - size from its buffer
                while w.ends and w.ends[0][0] + CONFIRM_MARGIN <= mark - w.size:
                    self._confirm(w.ends.popleft()[1])
        elif q.kind == "E":
            if value not in IO_ERRORS:
                raise LinkError(f"{self._name()}: ESC.E answered {value}, not an RS-232 error number")
            if value == ERROR_OUTPUT_BUSY:
                # one of our requests collided with an answer going out and was ignored: answers are out of step
                raise LinkError(f"{self._name()}: ESC.E answered {value} ({IO_ERRORS[value]}); a request was lost")
            if value and q.sync is None:
                log.warning("%s: the plotter held RS-232 error %d (%s) from before; cleared",
                            self.profile.name, value, IO_ERRORS[value])
            elif value and q.sync is not None:
                if q.sync.confirms is not None and value in BYTES_LOST:  # 11..14: device control, no HP-GL hit
                    self._mark_damaged(range(q.sync.first_stroke, q.sync.confirms))
                raise ProtocolError(
                    f"RS-232 error {value} ({IO_ERRORS[value]}) while receiving {_strokes(q.sync)}",
                    code=value, command=describe_instructions(q.sync.instructions), device=self.profile.name,
                )
        else:
            w.status = value

    def _check_overdue(self, now: float | None = None) -> None:
        w = self._wire
        now = self.clock.now() if now is None else now
        if w.queries and now > w.queries[0].deadline:
            q = w.queries[0]
            hint = "" if w.received_any else (
                f"; nothing was received since connecting: is the plotter on, cabled and set to {self.baudrate} 8N1?"
            )
            raise LinkTimeout(f"{self._name()}: no answer to ESC.{q.kind} in time{hint}")

    # -- helpers -----------------------------------------------------------------------------
    def _culprit(self, instructions: list[bytes], code: int) -> str:
        """The instruction an HP-GL error points at: one this model does not know (error 1), else all sent."""
        if code == 1:
            unknown = [i for i in instructions if i[:2].decode("ascii", "replace").upper() not in self.mnemonics]
            if len(unknown) == 1:
                return unknown[0].decode("ascii", "replace")
        return describe_instructions(instructions)

    @staticmethod
    def _limit(link: Link, seconds: float) -> float | None:
        """A write timeout for ``link``: None where the link takes none (its ``write_timeout`` is None)."""
        return None if link.write_timeout is None else seconds

    def _require_link(self) -> Link:
        if self.link is None:
            raise LinkError(f"{self.profile.name}: not connected")
        return self.link

    def _name(self) -> str:
        return f"{self.profile.name} on {self.link.name if self.link else self.port}"


def _strokes(point: SyncPoint) -> str:
    """Which strokes a sync point covers, for messages."""
    last = (point.confirms or 0) - 1
    if last < point.first_stroke:
        return "the instructions after the last stroke"
    return f"stroke {last}" if last == point.first_stroke else f"strokes {point.first_stroke}..{last}"


"""Panel-bus traces: record every frame a PanelBus sends (RecordingBus) and check a program against one (ReplayBus).

A bus trace is a version-1 trace (``docs/trace-format.md``) whose header says ``kind=bus``; its lines are
bus events instead of byte chunks::

    #pixelpen-trace 1 url=st7789%3Aspi%3A0.0 kind=bus bus=spi clock_hz=62500000 max_transfer=4096
    0.000000 R
    0.120010 C 01
    0.270020 C 2a
    0.270031 D 00 00 00 ef

``C`` starts a chip-select frame of command bytes (D/C low; I2C control byte 0x00), ``D`` one of data
bytes (D/C high; control byte 0x40), ``+`` continues the frame above it (a frame longer than 4096 bytes
spans several lines), ``R`` is a reset pulse.  Replay compares the bytes of each run of frames of one
D/C level as a stream, so a program may cut its calls differently from the recorded one.
"""

from __future__ import annotations

import re
from bisect import bisect_right
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Final

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.bus import RESET_RECOVERY, PanelBus, command_bytes
from pixelpen.drivers.trace import (
    DEFAULT_MAX_BYTES,
    MAX_CHUNK,
    TRACE_MAGIC,
    TRACE_VERSION,
    PathOrFile,
    PayloadBudget,
    TraceWriter,
    format_line,
    parse_header,
    parse_hex,
    parse_stamp,
    pieces,
    read_trace_text,
    trace_lines,
)
from pixelpen.errors import InvalidArgument, LinkError, ParseError, TraceMismatch
from pixelpen.profiles.panel import BUS_KINDS

COMMAND: Final = "C"
"""A frame of command bytes (D/C low)."""
DATA: Final = "D"
"""A frame of data bytes (D/C high)."""
MORE: Final = "+"
"""More bytes of the frame on the line above."""
RESET: Final = "R"
"""A pulse on the reset line."""
_LEVEL_NAMES: Final = {COMMAND: "command (D/C low)", DATA: "data (D/C high)"}


@dataclass(frozen=True)
class BusEvent:
    """One trace line: seconds since the start, ``C``/``D``/``+``/``R``, the bytes, and its line number."""

    time: float
    op: str
    data: bytes = b""
    line: int = 0


@dataclass
class BusTrace:
    """A parsed bus trace: the URL, the bus settings, every header setting, and the events in file order."""

    url: str = ""
    bus: str = "spi"
    clock_hz: float = 0.0
    max_transfer: int = MAX_CHUNK
    address: int | None = None
    settings: dict[str, str] = field(default_factory=dict)
    events: list[BusEvent] = field(default_factory=list)
    source: str | None = None

    def stream(self, level: str) -> bytes:
        """Every byte sent at ``level`` (``C`` or ``D``) in order, continuation lines included."""
        return b"".join(bytes(run.data) for run in _runs(self.events) if run.op == level)


def bus_settings(bus: PanelBus) -> dict[str, object]:
    """The header settings recorded for ``bus``: kind, clock_hz, max_transfer and (I2C) address."""
    settings: dict[str, object] = {
        "kind": "bus",
        "bus": bus.kind,
        "clock_hz": f"{float(bus.clock_hz):.6f}".rstrip("0").rstrip("."),
        "max_transfer": bus.max_transfer,
    }
    address = getattr(bus, "address", None)  # I2C buses only
    if isinstance(address, int):
        settings["address"] = f"0x{address:02x}"
    return settings


def format_frame(time: float, level: str, data: bytes) -> list[str]:
    """Trace lines (no newlines) of one chip-select frame: ``C``/``D`` then ``+`` lines of <= 4096 bytes each."""
    if level not in (COMMAND, DATA):
        raise InvalidArgument(f"frame level must be 'C' or 'D', got {level!r}")
    return [format_line(time, level if i == 0 else MORE, piece) for i, piece in enumerate(pieces(data))]


# -- reading ------------------------------------------------------------------------------------------


def parse_bus_trace(lines: Iterable[str], source: str = "<trace>", max_bytes: int = DEFAULT_MAX_BYTES) -> BusTrace:
    """Parse bus-trace lines (each with its ``\\n``); ParseError naming the line and token on anything malformed."""
    trace = BusTrace(source=source)
    budget = PayloadBudget(max_bytes, source)
    last_time = 0.0
    previous = ""  # op of the last event line, for '+'
    for line_no, text in trace_lines(lines, source, f"'{TRACE_MAGIC} {TRACE_VERSION} kind=bus ...'"):
        if line_no == 1:
            _parse_bus_header(trace, text, source)
            continue
        event = _parse_event(text, source, line_no, last_time)
        if event.op == MORE and previous not in (COMMAND, DATA, MORE):
            raise ParseError("'+' continues a frame, but no C or D frame is open", source=source, line=line_no,
                             token=MORE)
        budget.take(len(event.data), line_no)
        previous, last_time = event.op, event.time
        trace.events.append(event)
    return trace


def _parse_bus_header(trace: BusTrace, header: str, source: str) -> None:
    """The stream trace's header parser reads the line; then the bus settings are checked."""
    parsed = parse_header(header, source)
    trace.url, trace.settings = parsed.url, parsed.settings
    settings = parsed.settings
    if settings.get("kind") != "bus":
        raise ParseError("not a bus trace: the header lacks kind=bus (read a stream trace with read_trace)",
                         source=source, line=1, token=settings.get("kind", header[:40]))
    bus = settings.get("bus")
    if bus not in BUS_KINDS:
        raise ParseError(f"header setting bus must be one of {', '.join(BUS_KINDS)}", source=source, line=1,
                         token=f"bus={bus}" if bus is not None else header[:40])
    trace.bus = bus
    if "clock_hz" in settings:
        trace.clock_hz = _header_number(settings["clock_hz"], "clock_hz", source)
    if "max_transfer" in settings:
        trace.max_transfer = int(_header_number(settings["max_transfer"], "max_transfer", source, integer=True))
        if trace.max_transfer < 1:
            raise ParseError("header setting max_transfer must be at least 1", source=source, line=1,
                             token=settings["max_transfer"])
    if "address" in settings:
        address = settings["address"]
        try:
            trace.address = int(address, 0)
        except ValueError:
            trace.address = -1
        if not 0 <= trace.address <= 0x7F or len(address) > 6:
            raise ParseError("header setting address must be a 7-bit I2C address such as 0x3c", source=source,
                             line=1, token=address)


def _header_number(text: str, key: str, source: str, *, integer: bool = False) -> float:
    pattern = r"[0-9]{1,15}" if integer else r"[0-9]{1,15}(\.[0-9]{0,9})?"
    if not re.fullmatch(pattern, text):
        kind = "a whole number" if integer else "a non-negative decimal number"
        raise ParseError(f"header setting {key} must be {kind}", source=source, line=1, token=text)
    return float(text)


def _parse_event(body: str, source: str, line_no: int, last_time: float) -> BusEvent:
    fields = body.split()
    if len(fields) < 2:
        raise ParseError("expected 'SECONDS C|D|+|R [HEX...]' (line cut short?)", source=source, line=line_no,
                         token=body[:40])
    stamp, op, hex_fields = fields[0], fields[1], fields[2:]
    t = parse_stamp(stamp, source, line_no, last_time)
    if op not in (COMMAND, DATA, MORE, RESET):
        raise ParseError("event must be C (command), D (data), + (more of the frame) or R (reset)", source=source,
                         line=line_no, token=op)
    if op == RESET:
        if hex_fields:
            raise ParseError("a reset line takes no bytes", source=source, line=line_no, token=hex_fields[0])
        return BusEvent(t, op, b"", line_no)
    if not hex_fields:
        raise ParseError(f"a {op} line needs at least one byte", source=source, line=line_no, token=body[:40])
    return BusEvent(t, op, parse_hex(hex_fields, source, line_no, limit=MAX_CHUNK), line_no)


def read_bus_trace(source: PathOrFile, max_bytes: int = DEFAULT_MAX_BYTES) -> BusTrace:
    """Read a bus trace from a path or an open text file (ParseError on malformed content or an unreadable file)."""
    return read_trace_text(source, lambda lines, name: parse_bus_trace(lines, name, max_bytes))


# -- recording ----------------------------------------------------------------------------------------


class RecordingBus:
    """A PanelBus passing every call to ``bus`` and writing each frame, reset and failure to a bus trace."""

    def __init__(self, bus: PanelBus, dest: PathOrFile, *, url: str = "", clock: Clock | None = None) -> None:
        self.inner = bus
        inner_clock = getattr(bus, "clock", None)
        self.clock = clock if clock is not None else inner_clock if isinstance(inner_clock, Clock) else REAL_CLOCK
        self._start = self.clock.now()
        self._writer = TraceWriter(dest, url, bus_settings(bus))
        self._closed = False

    @property
    def max_transfer(self) -> int:
        """The wrapped bus's transfer limit."""
        return self.inner.max_transfer

    @property
    def kind(self) -> str:
        """``"spi"`` or ``"i2c"``, from the wrapped bus."""
        return self.inner.kind

    @property
    def clock_hz(self) -> float:
        """The wrapped bus's clock."""
        return float(self.inner.clock_hz)

    @property
    def bytes_sent(self) -> int:
        """The wrapped bus's byte counter."""
        return self.inner.bytes_sent

    @property
    def transfers(self) -> int:
        """The wrapped bus's transfer counter."""
        return self.inner.transfers

    def command(self, *cmd: int | bytes) -> None:
        """Send command bytes through the wrapped bus and record them as one ``C`` frame."""
        payload = command_bytes(*cmd)
        stamp = self._stamp()
        self._call("command", payload, lambda: self.inner.command(payload))
        if payload:
            self._lines(format_frame(stamp, COMMAND, payload))

    def data(self, data: bytes) -> None:
        """Send data bytes through the wrapped bus and record them as ``D`` frames of <= max_transfer bytes."""
        payload = bytes(data)
        stamp = self._stamp()
        self._call("data", payload, lambda: self.inner.data(payload))
        step = max(1, self.max_transfer)
        for i in range(0, len(payload), step):
            self._lines(format_frame(stamp, DATA, payload[i : i + step]))

    def reset(self, recovery: float = RESET_RECOVERY) -> None:
        """Pulse the wrapped bus's reset line and record ``R``."""
        stamp = self._stamp()
        self._call("reset", b"", lambda: self.inner.reset(recovery))
        self._lines([format_line(stamp, RESET)])

    def comment(self, text: str) -> None:
        """Add a comment line to the trace."""
        self._writer.comment(text)

    def close(self) -> None:
        """Close the wrapped bus and the trace; idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            self.inner.close()
        finally:
            self._writer.close()

    def _stamp(self) -> float:
        if self._closed:
            raise LinkError("recording bus is closed")
        return self.clock.now() - self._start

    def _call(self, what: str, payload: bytes, action: Callable[[], None]) -> None:
        try:
            action()
        except BaseException as exc:
            self._writer.comment(
                f"error during {what} of {len(payload)} bytes {payload[:16].hex(' ')}: {type(exc).__name__}: {exc}"
            )
            raise

    def _lines(self, lines: list[str]) -> None:
        for line in lines:
            self._writer.line(line)


class ReplayBus:
    """A PanelBus whose far end is a bus trace: every call is checked; the first divergence raises TraceMismatch."""

    def __init__(self, trace: BusTrace | PathOrFile, *, name: str | None = None) -> None:
        self.trace = trace if isinstance(trace, BusTrace) else read_bus_trace(trace)
        self.name = name or f"replay of {self.trace.source or self.trace.url or 'bus trace'}"
        self.kind = self.trace.bus
        self.clock_hz = self.trace.clock_hz
        self.max_transfer = self.trace.max_transfer
        self.address = self.trace.address
        self.bytes_sent = 0
        self.transfers = 0
        self._runs = _runs(self.trace.events)
        self._run = 0  # index of the run being matched
        self._done = 0  # bytes of that run matched
        self._stream_base = {COMMAND: 0, DATA: 0}  # stream offset where the current run starts
        self._closed = False

    def command(self, *cmd: int | bytes) -> None:
        """Check command bytes (D/C low) against the trace."""
        self._match(COMMAND, command_bytes(*cmd))

    def data(self, data: bytes) -> None:
        """Check data bytes (D/C high) against the trace."""
        self._match(DATA, bytes(data))

    def reset(self, recovery: float = RESET_RECOVERY) -> None:
        """Check that the trace has a reset pulse here (the recovery time is not checked)."""
        self._check_open()
        self._finish_run()
        run = self._current()
        if run is None or run.op != RESET:
            raise self._mismatch(run, RESET, b"", "a reset pulse where the trace has none")
        self._advance()

    def check_complete(self) -> None:
        """Raise TraceMismatch unless the program sent everything the trace holds."""
        self._finish_run()
        run = self._current()
        if run is not None:
            raise self._mismatch(run, "", b"", "the program stopped before the end of the trace")

    def close(self) -> None:
        """Stop checking (call ``check_complete`` to require the whole trace); idempotent."""
        self._closed = True

    def _check_open(self) -> None:
        if self._closed:
            raise LinkError(f"{self.name}: the bus is closed")

    def _current(self) -> _Run | None:
        return self._runs[self._run] if self._run < len(self._runs) else None

    def _finish_run(self) -> None:
        run = self._current()
        if run is not None and run.op != RESET and self._done == len(run.data):
            self._advance()

    def _advance(self) -> None:
        run = self._runs[self._run]
        if run.op in self._stream_base:
            self._stream_base[run.op] += len(run.data)
        self._run += 1
        self._done = 0

    def _match(self, level: str, payload: bytes) -> None:
        self._check_open()
        if not payload:
            return
        self.transfers += 1
        sent = 0
        while sent < len(payload):
            self._finish_run()
            run = self._current()
            if run is None or run.op != level:
                raise self._mismatch(run, level, payload[sent:], "trace mismatch")
            take = min(len(run.data) - self._done, len(payload) - sent)
            want = run.data[self._done : self._done + take]
            got = payload[sent : sent + take]
            if want != got:
                same = next(i for i, (a, b) in enumerate(zip(want, got, strict=True)) if a != b)
                self._done += same
                self.bytes_sent += same
                raise self._mismatch(run, level, payload[sent + same :], "trace mismatch")
            self._done += take
            self.bytes_sent += take
            sent += take

    def _mismatch(self, run: _Run | None, level: str, found: bytes, what: str) -> TraceMismatch:
        if run is None:
            expected_text, line, offset_text, offset = "the end of the trace", _last_line(self._runs), "", None
            expected = b""
        elif run.op == RESET:
            expected_text, line, offset_text, offset, expected = "a reset pulse", run.lines[0], "", None, b""
        else:
            expected = bytes(run.data[self._done : self._done + 16])
            offset = self._stream_base[run.op] + self._done
            line = run.line_at(self._done)
            expected_text = f"{_LEVEL_NAMES[run.op]} bytes {expected.hex(' ')}"
            offset_text = f" at byte offset {offset} of the {run.op} stream"
        found_text = (
            "a reset pulse" if level == RESET else "the end of the program" if not level
            else f"{_LEVEL_NAMES[level]} bytes {found[:16].hex(' ')}"
        )
        exc = TraceMismatch(f"{self.name}: {what}{offset_text} (trace line {line}): expected {expected_text}, "
                            f"found {found_text}")
        exc.offset, exc.level, exc.expected, exc.found, exc.line = (  # type: ignore[attr-defined]
            offset, run.op if run is not None else "", expected, bytes(found[:16]), line
        )
        return exc


@dataclass
class _Run:
    """Consecutive frames of one D/C level (or one reset): their bytes and where each line's bytes start."""

    op: str
    data: bytearray = field(default_factory=bytearray)
    starts: list[int] = field(default_factory=list)
    lines: list[int] = field(default_factory=list)

    def line_at(self, offset: int) -> int:
        """The trace line holding byte ``offset`` of this run."""
        return self.lines[max(0, bisect_right(self.starts, offset) - 1)]


def _runs(events: list[BusEvent]) -> list[_Run]:
    runs: list[_Run] = []
    level = ""
    for event in events:
        if event.op == RESET:
            runs.append(_Run(RESET, lines=[event.line]))
            level = ""
            continue
        if event.op != MORE:
            level = event.op
        if not runs or runs[-1].op != level:
            runs.append(_Run(level))
        run = runs[-1]
        run.starts.append(len(run.data))
        run.lines.append(event.line)
        run.data += event.data
    return runs


def _last_line(runs: list[_Run]) -> int:
    return runs[-1].lines[-1] if runs else 1

"""Wire traces: record every byte a Link moves (RecordingLink) and play a trace back as the device (ReplayLink).

Trace format, version 1 (also in ``docs/trace-format.md``).  A UTF-8 text file of lines ending in
``\\n``::

    #pixelpen-trace 1 url=sim%3A%2F%2Fhp7475a%3Fpaper%3Da4 baudrate=9600 flow=xonxoff
    # recorded by pixelpen
    0.000000 > 49 4e 3b 4f 49 3b  # IN;OI;
    0.041667 < 37 34 37 35 41 0d  # 7475A.

* Line 1, the header: ``#pixelpen-trace``, the format version (the integer 1), then
  ``key=value`` settings separated by spaces; values are percent-encoded (RFC 3986, as
  ``urllib.parse.quote(value, safe="")``).  ``url`` names the device URL (required, may be empty);
  other keys (``baudrate``, ``flow`` ...) record the link settings; ``kind=bus`` marks a bus trace,
  which :func:`read_trace` refuses (read it with ``pixelpen.drivers.bustrace.read_bus_trace``).
* Every later line is blank, a comment (first non-blank character ``#``), or one chunk:
  ``SECONDS DIRECTION HEX [# comment]`` separated by spaces.  ``SECONDS`` is a non-negative decimal
  number of seconds since the recording started, never smaller than the line before.
  ``DIRECTION`` is ``>`` (host to device) or ``<`` (device to host).  ``HEX`` is one or more
  tokens of hexadecimal digit pairs (upper or lower case), at least one byte in all.  Anything after
  the first ``#`` is a comment; writers put the bytes there as text, with ``.`` for bytes outside
  0x20..0x7e.
* A chunk line holds at most 4096 bytes (longer chunks are written as several lines with the same
  time) and no line is longer than 64 KiB; the file's last line ends with ``\\n`` (a file that does
  not was cut short).  Readers refuse traces of more than ``max_bytes`` payload bytes.
* The version is ASCII digits; ``SECONDS`` has at most :data:`MAX_STAMP_DIGITS` digits before the
  point (a longer one would not be a finite float, and no recording runs for 10^15 s).

Replaying compares byte streams, not chunks: the host stream is the concatenation of all ``>``
bytes, and each ``<`` chunk is released to the program once it has sent every ``>`` byte written
before that chunk in the file.  Timestamps are informative; replay runs as fast as the program.
The line-level pieces (``trace_lines``, ``parse_header``, ``parse_stamp``, ``parse_hex``, ``format_line``,
``read_trace_text``, ``TraceWriter.line``) also read and write bus traces (:mod:`pixelpen.drivers.bustrace`).
"""

from __future__ import annotations

import math
import os
import re
from bisect import bisect_right
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import IO, Final, TypeVar
from urllib.parse import quote, unquote

from pixelpen.clock import Clock, SimulatedClock
from pixelpen.drivers.serial import SerialLines
from pixelpen.drivers.stream import Link, printable
from pixelpen.errors import ConfigError, InvalidArgument, LinkError, ParseError, TraceMismatch
from pixelpen.urls import check_path

TRACE_MAGIC: Final = "#pixelpen-trace"
TRACE_VERSION: Final = 1
MAX_CHUNK: Final = 4096
"""Bytes per chunk line; longer chunks are split."""
MAX_LINE: Final = 65536
"""Characters per line a reader accepts."""
DEFAULT_MAX_BYTES: Final = 256 * 1024 * 1024
"""Payload bytes a reader accepts unless told otherwise."""
MAX_STAMP_DIGITS: Final = 15
"""Digits of a timestamp before its decimal point."""
_SECONDS = re.compile(r"([0-9]+)(\.[0-9]*)?")
HOST_TO_DEVICE: Final = ">"
DEVICE_TO_HOST: Final = "<"

PathOrFile = str | os.PathLike[str] | IO[str]
_T = TypeVar("_T")


@dataclass(frozen=True)
class TraceChunk:
    """One chunk: seconds since the start, direction (``>``/``<``), bytes, and the trace line it is on."""

    time: float
    direction: str
    data: bytes
    line: int = 0


@dataclass
class Trace:
    """A parsed trace: the device URL, the link settings and the chunks in file order."""

    url: str = ""
    settings: dict[str, str] = field(default_factory=dict)
    chunks: list[TraceChunk] = field(default_factory=list)
    version: int = TRACE_VERSION
    source: str | None = None

    def sent(self) -> bytes:
        """Every host-to-device byte, in order."""
        return b"".join(c.data for c in self.chunks if c.direction == HOST_TO_DEVICE)

    def received(self) -> bytes:
        """Every device-to-host byte, in order."""
        return b"".join(c.data for c in self.chunks if c.direction == DEVICE_TO_HOST)


def format_header(url: str, settings: Mapping[str, object] | None = None) -> str:
    """The header line (without newline) for a trace of ``url`` with ``settings``."""
    parts = [TRACE_MAGIC, str(TRACE_VERSION), f"url={quote(url, safe='')}"]
    for key, value in (settings or {}).items():
        if not key or not key.replace("_", "").replace("-", "").isalnum() or key == "url":
            raise InvalidArgument(f"trace setting names are letters, digits, '_' and '-' (and not 'url'), got {key!r}")
        parts.append(f"{key}={quote(str(value), safe='')}")
    return " ".join(parts)


def format_line(time: float, op: str, data: bytes = b"") -> str:
    """One trace line (without newline): ``SECONDS OP [HEX...]``, the time to the microsecond."""
    return f"{max(time, 0.0):.6f} {op} {data.hex(' ')}" if data else f"{max(time, 0.0):.6f} {op}"


def pieces(data: bytes) -> list[bytes]:
    """``data`` cut into the MAX_CHUNK-byte pieces a line holds at most."""
    return [data[i : i + MAX_CHUNK] for i in range(0, len(data), MAX_CHUNK)]


def format_chunk(time: float, direction: str, data: bytes) -> list[str]:
    """Chunk lines (without newlines) for ``data`` sent in ``direction`` at ``time`` seconds."""
    if direction not in (HOST_TO_DEVICE, DEVICE_TO_HOST):
        raise InvalidArgument(f"direction must be '>' or '<', got {direction!r}")
    return [f"{format_line(time, direction, piece)}  # {printable(piece)}" for piece in pieces(data)]


def parse_trace(lines: Iterable[str], source: str = "<trace>", max_bytes: int = DEFAULT_MAX_BYTES) -> Trace:
    """Parse trace lines (each with its ``\\n``); ParseError with the line number on anything malformed."""
    trace = Trace(source=source)
    budget = PayloadBudget(max_bytes, source)
    last_time = 0.0
    for line_no, text in trace_lines(lines, source, f"'{TRACE_MAGIC} {TRACE_VERSION} url=...'"):
        if line_no == 1:
            trace = parse_header(text, source)
            if trace.settings.get("kind") == "bus":
                raise ParseError(
                    "a bus trace (kind=bus): read it with pixelpen.drivers.bustrace.read_bus_trace",
                    source=source,
                    line=1,
                    token="kind=bus",
                )
            continue
        chunk = _parse_chunk(text, source, line_no, last_time)
        budget.take(len(chunk.data), line_no)
        last_time = chunk.time
        trace.chunks.append(chunk)
    return trace


def trace_lines(lines: Iterable[str], source: str, header: str) -> Iterator[tuple[int, str]]:
    """(line number, text): the header line, then every later line's body without comment or blank lines.

    ParseError on a line longer than MAX_LINE, an empty file (``header`` names the header it wanted) or a last
    line without its newline.
    """
    line_no = 0
    ended_cleanly = True
    for line_no, raw in enumerate(lines, start=1):
        if len(raw) > MAX_LINE:
            raise ParseError(
                f"line longer than {MAX_LINE} characters", source=source, line=line_no, token=raw[:40] + "..."
            )
        ended_cleanly = raw.endswith("\n")
        text = raw.rstrip("\r\n")
        body = text if line_no == 1 else text.partition("#")[0].strip()
        if body or line_no == 1:
            yield line_no, body
    if line_no == 0:
        raise ParseError(f"empty file: expected a {header} header", source=source, line=1)
    if not ended_cleanly:
        raise ParseError("last line has no newline: the trace looks truncated", source=source, line=line_no)


class PayloadBudget:
    """Counts the payload bytes a reader took; ParseError once they pass ``max_bytes``."""

    def __init__(self, max_bytes: int, source: str) -> None:
        self.max_bytes = max_bytes
        self.source = source
        self.total = 0

    def take(self, count: int, line_no: int) -> None:
        """Count ``count`` more bytes, read on line ``line_no``."""
        self.total += count
        if self.total > self.max_bytes:
            raise ParseError(
                f"trace holds more than {self.max_bytes} bytes (raise max_bytes to read it)",
                source=self.source,
                line=line_no,
            )


def parse_header(text: str, source: str = "<trace>") -> Trace:
    """The header line (without newline) as an empty Trace holding its version, URL and settings."""
    trace = Trace(source=source)
    fields = text.split()
    if not fields or fields[0] != TRACE_MAGIC:
        raise ParseError(
            f"expected the header '{TRACE_MAGIC} {TRACE_VERSION} url=...'", source=source, line=1, token=text[:40]
        )
    if len(fields) < 2 or not (fields[1].isascii() and fields[1].isdigit()) or len(fields[1]) > 9:
        raise ParseError("header lacks the format version number", source=source, line=1, token=text[:40])
    trace.version = int(fields[1])
    if trace.version != TRACE_VERSION:
        raise ParseError(
            f"unsupported trace format version {trace.version} (this reader knows {TRACE_VERSION})",
            source=source,
            line=1,
        )
    seen_url = False
    for item in fields[2:]:
        key, eq, value = item.partition("=")
        if not eq or not key:
            raise ParseError("header settings must be key=value", source=source, line=1, token=item)
        if key == "url":
            trace.url, seen_url = unquote(value), True
        elif key in trace.settings:
            raise ParseError(f"header setting {key!r} given twice", source=source, line=1, token=item)
        else:
            trace.settings[key] = unquote(value)
    if not seen_url:
        raise ParseError("header lacks url=... (it may be empty: 'url=')", source=source, line=1, token=text[:40])
    return trace


def parse_stamp(stamp: str, source: str, line_no: int, last_time: float) -> float:
    """A line's SECONDS field: non-negative decimal, at most MAX_STAMP_DIGITS before the point, not going back."""
    seconds = _SECONDS.fullmatch(stamp)
    if not seconds or len(seconds[1]) > MAX_STAMP_DIGITS:
        raise ParseError(
            f"timestamp must be non-negative decimal seconds like 0.041667 (at most {MAX_STAMP_DIGITS} digits "
            "before the point)",
            source=source,
            line=line_no,
            column=1,
            token=stamp,
        )
    t = float(stamp)
    if t < last_time:
        raise ParseError(
            f"timestamp goes backwards (previous {last_time:.6f})", source=source, line=line_no, column=1, token=stamp
        )
    return t


def parse_hex(tokens: Iterable[str], source: str, line_no: int, limit: int | None = None) -> bytes:
    """The bytes of a line's HEX tokens (digit pairs); ParseError naming the token, also past ``limit`` bytes."""
    data = bytearray()
    for token in tokens:
        if len(token) % 2:
            raise ParseError("odd number of hex digits (truncated byte?)", source=source, line=line_no, token=token)
        try:
            data += bytes.fromhex(token)
        except ValueError:
            raise ParseError("not hexadecimal bytes", source=source, line=line_no, token=token) from None
        if limit is not None and len(data) > limit:
            raise ParseError(
                f"a line carries at most {limit} bytes", source=source, line=line_no, token=token
            )
    return bytes(data)


def _parse_chunk(body: str, source: str, line_no: int, last_time: float) -> TraceChunk:
    fields = body.split()
    if len(fields) < 3:
        raise ParseError(
            "expected 'SECONDS >|< HEX...' (line cut short?)", source=source, line=line_no, token=body[:40]
        )
    stamp, direction, hex_fields = fields[0], fields[1], fields[2:]
    t = parse_stamp(stamp, source, line_no, last_time)
    if direction not in (HOST_TO_DEVICE, DEVICE_TO_HOST):
        raise ParseError(
            "direction must be '>' (host to device) or '<' (device to host)",
            source=source,
            line=line_no,
            token=direction,
        )
    return TraceChunk(t, direction, parse_hex(hex_fields, source, line_no), line_no)


def _cut_lines(f: IO[str]) -> Iterator[str]:
    """Lines of ``f``, each cut at MAX_LINE + 1 characters so an endless line cannot exhaust memory."""
    while True:
        line = f.readline(MAX_LINE + 1)
        if not line:
            return
        yield line


def read_trace_text(source: PathOrFile, parse: Callable[[Iterable[str], str], _T]) -> _T:
    """``parse(lines, name)`` over the lines of a path or an open text file; ParseError when unreadable or not UTF-8."""
    if not isinstance(source, (str, os.PathLike)):
        name = str(getattr(source, "name", "<trace>"))
        try:
            return parse(_cut_lines(source), name)
        except UnicodeDecodeError as exc:
            raise ParseError(f"not UTF-8 text: {exc.reason}", source=name) from None
    name = os.fspath(source)
    try:
        with open(check_path(name, "trace file"), encoding="utf-8", newline="") as f:
            return parse(_cut_lines(f), name)
    except UnicodeDecodeError as exc:
        raise ParseError(f"not UTF-8 text: {exc.reason}", source=name, offset=exc.start) from None
    except ConfigError as exc:
        raise ParseError(str(exc), source="<trace>") from None
    except OSError as exc:
        raise ParseError(f"cannot read trace: {exc.strerror or exc}", source=name) from None


def read_trace(source: PathOrFile, max_bytes: int = DEFAULT_MAX_BYTES) -> Trace:
    """Read a trace from a path or an open text file (ParseError on malformed content or an unreadable file)."""
    return read_trace_text(source, lambda lines, name: parse_trace(lines, name, max_bytes))


class TraceWriter:
    """Writes a trace incrementally, flushing after every line so a crash keeps what happened.

    A file name no file system takes (NUL, over-long) is a ConfigError before anything is opened.
    """

    def __init__(self, dest: PathOrFile, url: str, settings: Mapping[str, object] | None = None) -> None:
        if isinstance(dest, (str, os.PathLike)):
            self._file: IO[str] = open(check_path(dest, "trace file"), "w", encoding="utf-8", newline="\n")  # noqa: SIM115 - the writer owns it until close()
            self._owns = True
        else:
            self._file, self._owns = dest, False
        self._closed = False
        self.line(format_header(url, settings))

    def chunk(self, time: float, direction: str, data: bytes) -> None:
        """Append ``data`` moved in ``direction`` at ``time`` seconds since the start."""
        if data:
            for line in format_chunk(time, direction, data):
                self.line(line)

    def comment(self, text: str) -> None:
        """Append a comment line (one line: newlines become spaces)."""
        self.line("# " + " ".join(text.splitlines()))

    def close(self) -> None:
        """Flush, and close the file if this writer opened it; idempotent."""
        if self._closed:
            return
        self._closed = True
        self._file.flush()
        if self._owns:
            self._file.close()

    def line(self, text: str) -> None:
        """Append one line as it is (``text`` holds no newline) and flush it."""
        if self._closed:
            raise LinkError("trace writer is closed")
        if "\n" in text or "\r" in text:
            raise InvalidArgument(f"a trace line holds no newline, got {text[:40]!r}")
        self._file.write(text + "\n")
        self._file.flush()


def write_trace(trace: Trace, dest: PathOrFile) -> None:
    """Write a whole Trace to a path or an open text file."""
    writer = TraceWriter(dest, trace.url, trace.settings)
    try:
        for chunk in trace.chunks:
            writer.chunk(chunk.time, chunk.direction, chunk.data)
    finally:
        writer.close()


def _link_settings(link: Link) -> dict[str, object]:
    settings: dict[str, object] = {}
    for key in ("baudrate", "flow"):
        try:
            value = getattr(link, key)
        except (AttributeError, LinkError):
            continue
        settings[key] = value
    return settings


class RecordingLink(Link):
    """A Link that passes everything to ``inner`` and records every byte both ways as a trace."""

    def __init__(
        self,
        inner: Link,
        dest: PathOrFile,
        *,
        url: str | None = None,
        settings: Mapping[str, object] | None = None,
    ) -> None:
        super().__init__(inner.name, timeout=inner.timeout, write_timeout=inner.write_timeout, clock=inner.clock)
        self.inner = inner
        self._start = self.clock.now()
        self.writer = TraceWriter(
            dest, url if url is not None else inner.name, _link_settings(inner) if settings is None else settings
        )

    def _stamp(self) -> float:
        return self.clock.now() - self._start

    def _read_raw(self, wait: float | None) -> bytes:
        try:
            data = self.inner.read(65536, timeout=math.inf if wait is None else wait)
        except BaseException as exc:
            self.writer.comment(f"error during read: {type(exc).__name__}: {exc}")
            raise
        self.writer.chunk(self._stamp(), DEVICE_TO_HOST, data)
        return data

    def _write_raw(self, data: bytes, wait: float | None) -> int:
        try:
            self.inner.write(data, timeout=math.inf if wait is None else wait)
        except BaseException as exc:
            self.writer.comment(
                f"error during write of {len(data)} bytes {data[:32].hex(' ')}: {type(exc).__name__}: {exc}"
            )
            raise
        self.writer.chunk(self._stamp(), HOST_TO_DEVICE, data)
        return len(data)

    def _raw_in_waiting(self) -> int:
        return self.inner.in_waiting

    def _flush_raw(self, wait: float | None) -> None:
        self.inner.flush(math.inf if wait is None else wait)

    def _reset_output_raw(self) -> None:
        self.inner.reset_output()

    def _close_raw(self) -> None:
        try:
            self.inner.close()
        finally:
            self.writer.close()

    def _lines(self) -> SerialLines:
        """The inner link's serial line signals (LinkError when it is no serial link)."""
        if isinstance(self.inner, SerialLines):
            return self.inner
        raise LinkError(f"{self.name}: the recorded link has no serial line signals")

    @property
    def cts(self) -> bool:
        """The inner link's CTS."""
        return self._lines().cts

    @property
    def dsr(self) -> bool:
        """The inner link's DSR."""
        return self._lines().dsr

    @property
    def rts(self) -> bool:
        """The inner link's RTS."""
        return self._lines().rts

    @rts.setter
    def rts(self, value: bool) -> None:
        self._lines().rts = value

    @property
    def dtr(self) -> bool:
        """The inner link's DTR."""
        return self._lines().dtr

    @dtr.setter
    def dtr(self, value: bool) -> None:
        self._lines().dtr = value


class ReplayLink(Link):
    """A Link whose far end is a recorded trace: answers as the device did, raises TraceMismatch on divergence."""

    def __init__(
        self,
        trace: Trace | PathOrFile,
        *,
        clock: Clock | None = None,
        timeout: float | None = 2.0,
        write_timeout: float | None = 10.0,
        name: str | None = None,
    ) -> None:
        if not isinstance(trace, Trace):
            trace = read_trace(trace)
        self.trace = trace
        super().__init__(
            name or f"replay of {trace.source or trace.url or 'trace'}",
            timeout=timeout,
            write_timeout=write_timeout,
            clock=clock if clock is not None else SimulatedClock(),
        )
        self._expected = bytearray()
        self._starts: list[int] = []  # host-stream offset where each '>' chunk starts
        self._lines: list[int] = []
        self._replies: list[tuple[int, bytes]] = []  # (host bytes needed first, reply)
        for chunk in trace.chunks:
            if chunk.direction == HOST_TO_DEVICE:
                self._starts.append(len(self._expected))
                self._lines.append(chunk.line)
                self._expected += chunk.data
            else:
                self._replies.append((len(self._expected), chunk.data))
        self._sent = 0
        self._next_reply = 0
        self._pending = bytearray()
        self._rts = self._dtr = True
        self._release()

    @property
    def sent(self) -> int:
        """Host bytes the program sent so far (all matched the trace)."""
        return self._sent

    def check_complete(self) -> None:
        """Raise TraceMismatch unless the program sent every host byte the trace holds."""
        if self._sent < len(self._expected):
            raise self._mismatch(
                self._sent,
                b"",
                f"the program stopped after {self._sent} of {len(self._expected)} host bytes",
            )

    def _line_of(self, offset: int) -> int:
        if not self._lines:
            return 0
        return self._lines[max(0, bisect_right(self._starts, offset) - 1)]

    def _mismatch(self, offset: int, found: bytes, what: str) -> TraceMismatch:
        expected = bytes(self._expected[offset : offset + 16])
        line = self._line_of(offset) if offset < len(self._expected) else (self._lines[-1] if self._lines else 0)
        exc = TraceMismatch(
            f"{self.name}: {what} at byte offset {offset} of the host stream (trace line {line}): "
            f"expected {expected!r}{' (end of trace)' if not expected else ''}, found {found[:16]!r}"
        )
        exc.offset, exc.expected, exc.found, exc.line = offset, expected, bytes(found[:16]), line  # type: ignore[attr-defined]
        return exc

    def _release(self) -> None:
        while self._next_reply < len(self._replies) and self._replies[self._next_reply][0] <= self._sent:
            self._pending += self._replies[self._next_reply][1]
            self._next_reply += 1

    def _write_raw(self, data: bytes, wait: float | None) -> int:
        want = self._expected[self._sent : self._sent + len(data)]
        if want != data:
            same = next((i for i, (a, b) in enumerate(zip(want, data, strict=False)) if a != b), len(want))
            self._sent += same
            self._release()
            what = "the program sent more than the trace holds" if same == len(want) else "trace mismatch"
            raise self._mismatch(self._sent, data[same:], what)
        self._sent += len(data)
        self._release()
        return len(data)

    def _read_raw(self, wait: float | None) -> bytes:
        out = bytes(self._pending)
        self._pending.clear()
        return out

    def _raw_in_waiting(self) -> int:
        return len(self._pending)

    def _close_raw(self) -> None:
        self._pending.clear()

    @property
    def cts(self) -> bool:
        """Always clear to send: a trace never holds the program off."""
        return True

    @property
    def dsr(self) -> bool:
        """Always ready."""
        return True

    @property
    def rts(self) -> bool:
        """RTS as the program set it."""
        return self._rts

    @rts.setter
    def rts(self, value: bool) -> None:
        self._rts = bool(value)

    @property
    def dtr(self) -> bool:
        """DTR as the program set it."""
        return self._dtr

    @dtr.setter
    def dtr(self, value: bool) -> None:
        self._dtr = bool(value)

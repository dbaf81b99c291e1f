"""hid-recorder text files: recorded HID devices (descriptor, name, IDs) and their timed input reports.

The format is the one hid-tools' ``hid-recorder`` (``hidtools.hidraw.HidrawDevice.dump``) and the C
``hid-recorder`` of hid-replay write, and ``hid-replay`` reads; one line each:

* ``# text`` — a comment (hid-recorder writes the name, the descriptor decoded item by item and each report
  decoded); blank lines are skipped too;
* ``D: n`` — the device index; the lines after it belong to device ``n`` (only written when a file holds
  several devices; a file without ``D:`` lines is device 0);
* ``R: len hex...`` — the report descriptor: its length in bytes, then each byte as hex;
* ``N: name`` — the device name (HIDIOCGRAWNAME); ``P: phys`` — the physical path (HIDIOCGRAWPHYS);
* ``I: bus vendor product`` — the kernel's bus type (``BUS_USB`` = 3, ...), vendor and product ID, in hex;
* ``E: sec.usec len hex...`` — an input report as read from hidraw (report-ID byte first when numbered),
  at ``sec`` seconds and ``usec`` (six digits) microseconds after the first report of the recording.

Bytes are one or two hex digits (both tools write two, lower case).  Times must not go backwards within a
device: the recorders take them from the wall clock, which can step back; such a time is warned about
(:class:`RecordingWarning`) and held at the previous one, or is an error with ``strict=True``.  Unknown
``X:`` lines are warned about and skipped (hid-replay ignores them too); any other line is an error.
Errors are :class:`~pixelpen.errors.ParseError` naming the source, the line and the field.  The limits
(:class:`Limits`) bound the memory a file can take: the file size, the line length, the number of reports,
the report length (the kernel's ``HID_MAX_BUFFER_SIZE``, 16384) and the descriptor length
(``HID_MAX_DESCRIPTOR_SIZE``, 4096).
"""

from __future__ import annotations

import heapq
import io
import math
import os
import re
import warnings
from collections.abc import Iterator, Sequence
from contextlib import ExitStack
from dataclasses import dataclass, field
from typing import TextIO

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.identity import DeviceId
from pixelpen.drivers.reports import ReportLink
from pixelpen.errors import InvalidArgument, InvalidArgumentType, ParseError, quote_token

BUS_NAMES = {0x03: "usb", 0x05: "bluetooth", 0x06: "virtual", 0x18: "i2c", 0x1C: "spi"}
"""The kernel's bus types (``linux/input.h`` ``BUS_*``) by the names :class:`DeviceId` uses; others are
``unknown``."""
BUS_NUMBERS = {name: number for number, name in BUS_NAMES.items()} | {"unknown": 0}
"""A DeviceId bus name to the kernel's bus type written in ``I:`` lines."""

MAX_SECONDS_DIGITS = 12
"""Digits of a timestamp's seconds at most (31,000 years; a longer number is not a time but damage)."""


@dataclass(frozen=True)
class Limits:
    """What a hid-recorder file may hold at most; a file beyond one is a ParseError naming the limit."""

    file_bytes: int = 256 * 2**20
    """The file's size (256 MiB: about 4 million mouse reports)."""
    reports: int = 2_000_000
    """Input reports in all (33 minutes at 1000 Hz; each costs ~100 bytes of memory)."""
    report_bytes: int = 16384
    """One report's length: the kernel's HID_MAX_BUFFER_SIZE."""
    descriptor_bytes: int = 4096
    """A report descriptor's length: the kernel's HID_MAX_DESCRIPTOR_SIZE (and HIDIOCGRDESC's buffer)."""
    devices: int = 64
    """Devices in one file (``D:`` indices 0..63)."""
    text_chars: int = 1024
    """An ``N:`` name or ``P:`` path (hid-tools reads names into a 1024-byte buffer)."""

    @property
    def line_chars(self) -> int:
        """A line's length: the longest ``E:`` line (three characters a byte) and some room."""
        return 3 * max(self.report_bytes, self.descriptor_bytes) + 64


LIMITS = Limits()
"""The default limits."""


class RecordingWarning(UserWarning):
    """A hid-recorder file was read with something fixed or skipped (a time going backwards, an unknown line)."""


@dataclass
class HidRecording:
    """One recorded HID device: who it is, its report descriptor, its input reports (seconds, bytes) in order."""

    name: str
    phys: str
    """The kernel's physical path (``usb-0000:00:14.0-2/input0``), empty when not recorded."""
    bus: int
    """The kernel's bus type: 3 USB, 5 Bluetooth, 6 virtual, 0x18 I2C (:data:`BUS_NAMES`)."""
    vendor_id: int
    product_id: int
    descriptor: bytes
    reports: list[tuple[float, bytes]] = field(default_factory=list)
    """(seconds after the recording's first report, report bytes with the ID byte first when numbered)."""

    @property
    def device_id(self) -> DeviceId:
        """The recorded device's identity (the USB interface from a ``.../inputN`` physical path)."""
        match = re.search(r"/input(\d+)$", self.phys)
        return DeviceId(bus=BUS_NAMES.get(self.bus, "unknown"), vendor_id=self.vendor_id,
                        product_id=self.product_id, name=self.name,
                        interface=int(match.group(1)) if match and self.bus == 0x03 else -1, path=self.phys)


# ---- reading ------------------------------------------------------------------------------------------------

_HEX = re.compile(r"[0-9a-fA-F]{1,2}\Z")
_HEX_NUMBER = re.compile(r"[0-9a-fA-F]{1,8}\Z")
_LINE_TYPES = "D:, R:, N:, P:, I:, E: or a # comment"


@dataclass
class _Device:
    """A device while its lines are read."""

    index: int
    line: int
    """The line that first named it."""
    descriptor: bytes | None = None
    descriptor_line: int = 0
    name: str | None = None
    phys: str | None = None
    ids: tuple[int, int, int] | None = None
    reports: list[tuple[float, bytes]] = field(default_factory=list)
    last: float = 0.0
    backwards: int = 0
    first_backwards: int = 0


class _Reader:
    """The state of one read: the devices met so far, the current one, the counts the limits bound."""

    def __init__(self, source: str, strict: bool, limits: Limits) -> None:
        self.source = source
        self.strict = strict
        self.limits = limits
        self.devices: dict[int, _Device] = {}
        self.index = 0
        self.line = 0
        self.reports = 0
        self.unknown: dict[str, int] = {}

    def error(self, message: str, token: object = None) -> ParseError:
        return ParseError(message, source=self.source, line=self.line, token=token)

    def device(self) -> _Device:
        dev = self.devices.get(self.index)
        if dev is None:
            dev = self.devices[self.index] = _Device(self.index, self.line)
        return dev

    def feed(self, text: str) -> None:
        """One line (its end of line included or not)."""
        stripped = text.strip()
        if not stripped or stripped[0] == "#":
            return
        kind, body = stripped[:2], stripped[2:].strip()
        if kind == "E:":
            self.event(body)
        elif kind == "D:":
            self.switch(body)
        elif kind == "R:":
            self.descriptor(body)
        elif kind == "N:" or kind == "P:":
            self.text(kind, body)
        elif kind == "I:":
            self.ids(body)
        elif len(kind) == 2 and kind[0].isalpha() and kind[1] == ":":
            self.unknown.setdefault(kind, self.line)
        else:
            raise self.error(f"not a hid-recorder line: expected {_LINE_TYPES}", stripped[:40])

    def event(self, body: str) -> None:
        dev = self.device()
        if dev.descriptor is None:
            raise self.error(f"E: a report of device {dev.index} before its R: line (its report descriptor)")
        parts = body.split(None, 2)
        if len(parts) < 3:
            raise self.error("E: expected 'E: SECONDS.MICROSECONDS LENGTH HEX-BYTES...'", body)
        stamp, count, hexes = parts
        t = self.time(stamp)
        report = self.hex_bytes("E", "report", count, hexes, self.limits.report_bytes)
        self.reports += 1
        if self.reports > self.limits.reports:
            raise self.error(f"E: more than {self.limits.reports} reports (the limit of a recording)")
        if t < dev.last:
            if self.strict:
                raise self.error(f"E: the time {stamp} s is before the previous report's {dev.last:.6f} s "
                                 "(times must not go backwards)", stamp)
            if not dev.backwards:
                dev.first_backwards = self.line
            dev.backwards += 1
            t = dev.last
        dev.last = t
        dev.reports.append((t, report))

    def time(self, stamp: str) -> float:
        sec, dot, usec = stamp.partition(".")
        if not (dot and len(usec) == 6 and usec.isdecimal() and sec.isdecimal() and usec.isascii()
                and sec.isascii() and len(sec) <= MAX_SECONDS_DIGITS):
            raise self.error("E: the timestamp is not SECONDS.MICROSECONDS (digits, a dot, six digits)", stamp)
        return (int(sec) * 1_000_000 + int(usec)) / 1e6

    def hex_bytes(self, kind: str, what: str, count: str, hexes: str, limit: int) -> bytes:
        """The bytes of an ``R:`` or ``E:`` line, checked against the length it states and ``limit``."""
        if not (count.isdecimal() and count.isascii() and len(count) <= 6):
            raise self.error(f"{kind}: the {what} length is not a decimal number", count)
        length = int(count)
        if not 1 <= length <= limit:
            raise self.error(f"{kind}: a {what} of {length} bytes (1 to {limit} allowed)", length)
        try:
            data = bytes.fromhex(hexes)
        except ValueError:
            data = b""
        if len(hexes) != 3 * len(data) - 1 or len(data) != length:  # not single-spaced pairs: check each token
            tokens = hexes.split()
            for i, token in enumerate(tokens):
                if not _HEX.match(token):
                    raise self.error(f"{kind}: {what} byte {i} is not a hex byte", token)
            if len(tokens) != length:
                raise self.error(f"{kind}: the {what} length says {length} bytes but {len(tokens)} follow",
                                 len(tokens))
            data = bytes(int(token, 16) for token in tokens)
        return data

    def switch(self, body: str) -> None:
        if not (body.isdecimal() and body.isascii() and len(body) <= 6):
            raise self.error("D: the device index is not a decimal number", body)
        index = int(body)
        if index >= self.limits.devices:
            raise self.error(f"D: device index {index} (0 to {self.limits.devices - 1} allowed)", index)
        self.index = index

    def descriptor(self, body: str) -> None:
        dev = self.device()
        if dev.descriptor is not None:
            raise self.error(f"R: a second report descriptor for device {dev.index} (the first is on line "
                             f"{dev.descriptor_line})")
        count, _, hexes = body.partition(" ")
        dev.descriptor = self.hex_bytes("R", "descriptor", count, hexes.strip(), self.limits.descriptor_bytes)
        dev.descriptor_line = self.line

    def text(self, kind: str, body: str) -> None:
        dev = self.device()
        attribute = "name" if kind == "N:" else "phys"
        if getattr(dev, attribute) is not None:
            raise self.error(f"{kind} a second {attribute} for device {dev.index}", body)
        if len(body) > self.limits.text_chars:
            raise self.error(f"{kind} the {attribute} is {len(body)} characters (at most {self.limits.text_chars})")
        setattr(dev, attribute, body)

    def ids(self, body: str) -> None:
        dev = self.device()
        if dev.ids is not None:
            raise self.error(f"I: a second bus/vendor/product line for device {dev.index}", body)
        parts = body.split()
        if len(parts) != 3:
            raise self.error("I: expected 'I: BUS VENDOR PRODUCT' (three hex numbers)", body)
        values = []
        for name, token, top in zip(("bus", "vendor", "product"), parts, (0xFFFFFFFF, 0xFFFF, 0xFFFF), strict=True):
            if not _HEX_NUMBER.match(token) or int(token, 16) > top:
                raise self.error(f"I: the {name} is not a hex number of 0 to {top:x}", token)
            values.append(int(token, 16))
        dev.ids = (values[0], values[1], values[2])

    def finish(self) -> list[HidRecording]:
        for kind, line in self.unknown.items():
            warnings.warn(f"{self.source}: line {line}: skipped {kind} lines (not a hid-recorder line type)",
                          RecordingWarning, stacklevel=3)
        out = []
        for index in sorted(self.devices):
            dev = self.devices[index]
            missing = [k for k, v in (("R:", dev.descriptor), ("I:", dev.ids)) if v is None]
            if missing:
                raise ParseError(f"device {index} has no {' or '.join(missing)} line", source=self.source,
                                 line=dev.line)
            if dev.backwards:
                warnings.warn(f"{self.source}: line {dev.first_backwards}: {dev.backwards} report times of "
                              f"device {index} go backwards; each is held at the time before it",
                              RecordingWarning, stacklevel=3)
            assert dev.descriptor is not None and dev.ids is not None
            bus, vendor, product = dev.ids
            out.append(HidRecording(dev.name or "", dev.phys or "", bus, vendor, product, dev.descriptor,
                                    dev.reports))
        if not out:
            raise ParseError("no device in the recording (no R: line)", source=self.source, line=self.line or None)
        return out


def read_hid_recording(path_or_text: str | bytes | os.PathLike[str] | TextIO, *, source: str | None = None,
                       strict: bool = False, limits: Limits = LIMITS) -> list[HidRecording]:
    """The devices of a hid-recorder file, by ``D:`` index: a path, an open text file, or the text itself.

    A ``str`` holding a line break, or ``bytes``, is the text; any other ``str`` is a path.  Bytes that are
    not UTF-8 (in a name) are replaced.  ``strict`` makes a time going backwards an error instead of a warning.
    """
    with ExitStack() as stack:
        lines, name, size = _open(path_or_text, stack)
        reader = _Reader(source or name, strict, limits)
        if size is not None and size > limits.file_bytes:
            raise ParseError(f"the file is {size} bytes, more than the {limits.file_bytes}-byte limit",
                             source=reader.source)
        chars = 0
        longest = limits.line_chars
        while True:
            text = lines.readline(longest + 1)
            if not text:
                break
            reader.line += 1
            chars += len(text)
            if len(text) > longest and not text.endswith("\n"):
                raise reader.error(f"a line longer than {longest} characters")
            if chars > limits.file_bytes:
                raise reader.error(f"more than the {limits.file_bytes}-byte limit of a file")
            reader.feed(text)
        return reader.finish()


def _open(path_or_text: str | bytes | os.PathLike[str] | TextIO, stack: ExitStack) -> tuple[TextIO, str, int | None]:
    """The lines to read, the source's name, and the file's size when known before reading."""
    if isinstance(path_or_text, bytes):
        return io.StringIO(path_or_text.decode("utf-8", "replace")), "<hid-recorder text>", len(path_or_text)
    if isinstance(path_or_text, str) and ("\n" in path_or_text or "\r" in path_or_text):
        return io.StringIO(path_or_text), "<hid-recorder text>", None
    if isinstance(path_or_text, (str, os.PathLike)):
        try:
            f = stack.enter_context(open(path_or_text, encoding="utf-8", errors="replace"))  # noqa: SIM115
        except OSError as exc:
            raise ParseError(f"cannot read the recording: {exc.strerror or exc}", source=str(path_or_text)) from None
        return f, str(path_or_text), os.fstat(f.fileno()).st_size
    if hasattr(path_or_text, "readline"):
        return path_or_text, str(getattr(path_or_text, "name", "<hid-recorder stream>")), None
    raise InvalidArgumentType(f"read_hid_recording() takes a path, text or a text file, not "
                              f"{type(path_or_text).__name__}")


# ---- writing ------------------------------------------------------------------------------------------------

class HidRecordingWriter:
    """Writes a hid-recorder file as it goes: each device's header, then reports, flushed one by one.

    With ``several`` (a file of more than one device) it writes ``D:`` lines before each header and whenever
    the device changes, as hid-recorder does.
    """

    def __init__(self, file: TextIO, *, several: bool = False, flush: bool = True) -> None:
        self.file = file
        self.several = several
        self.flush = flush
        self._current = 0 if not several else -1
        self._last: dict[int, float] = {}

    def device(self, recording: HidRecording, index: int = 0) -> None:
        """The header lines of device ``index``: ``# name``, ``R:``, ``N:``, ``P:`` (when known), ``I:``."""
        _check_header(recording)
        lines = []
        if self.several:
            lines.append(f"D: {index}")
            self._current = index
        lines += [f"# {recording.name}", f"R: {len(recording.descriptor)} {recording.descriptor.hex(' ')}",
                  f"N: {recording.name}"]
        if recording.phys:
            lines.append(f"P: {recording.phys}")
        lines.append(f"I: {recording.bus:x} {recording.vendor_id:04x} {recording.product_id:04x}")
        self._write(lines)

    def report(self, time: float, report: bytes, index: int = 0) -> None:
        """One ``E:`` line: ``report`` at ``time`` seconds (finite, >= 0, not before the device's last one)."""
        if not isinstance(report, (bytes, bytearray, memoryview)):
            raise InvalidArgumentType(f"a report is bytes, not {type(report).__name__}")
        if not 1 <= len(report) <= LIMITS.report_bytes:
            raise InvalidArgument(f"a report of {len(report)} bytes (1 to {LIMITS.report_bytes} allowed)")
        if not (isinstance(time, (int, float)) and math.isfinite(time) and 0 <= time < 10.0**MAX_SECONDS_DIGITS):
            raise InvalidArgument(f"report time {quote_token(time)}: a finite number of seconds >= 0")
        if time < self._last.get(index, 0.0):
            raise InvalidArgument(f"report time {time} s is before the previous report's {self._last[index]} s "
                                  f"(device {index})")
        self._last[index] = time
        sec, usec = divmod(round(time * 1e6), 1_000_000)
        lines = []
        if self.several and index != self._current:
            lines.append(f"D: {index}")
            self._current = index
        lines.append(f"E: {sec:06d}.{usec:06d} {len(report)} {bytes(report).hex(' ')}")
        self._write(lines)

    def _write(self, lines: list[str]) -> None:
        self.file.write("\n".join(lines) + "\n")
        if self.flush:
            self.file.flush()


def _check_header(recording: HidRecording) -> None:
    """InvalidArgument for what a header line cannot hold (line breaks, sizes and IDs out of range)."""
    if not isinstance(recording, HidRecording):
        raise InvalidArgumentType(f"expected a HidRecording, not {type(recording).__name__}")
    if not isinstance(recording.descriptor, (bytes, bytearray)):
        raise InvalidArgumentType(f"the descriptor is bytes, not {type(recording.descriptor).__name__}")
    if not 1 <= len(recording.descriptor) <= LIMITS.descriptor_bytes:
        raise InvalidArgument(f"a report descriptor of {len(recording.descriptor)} bytes "
                              f"(1 to {LIMITS.descriptor_bytes} allowed)")
    for what, text in (("name", recording.name), ("phys", recording.phys)):
        if "\n" in text or "\r" in text or len(text) > LIMITS.text_chars:
            raise InvalidArgument(f"the {what} {quote_token(text)} has a line break or more than "
                                  f"{LIMITS.text_chars} characters")
    for what, value, top in (("bus", recording.bus, 0xFFFFFFFF), ("vendor ID", recording.vendor_id, 0xFFFF),
                             ("product ID", recording.product_id, 0xFFFF)):
        if not (isinstance(value, int) and 0 <= value <= top):
            raise InvalidArgument(f"the {what} {quote_token(value)} is not 0 to {top:#x}")


def write_hid_recording(recording: HidRecording | Sequence[HidRecording],
                        file: str | os.PathLike[str] | TextIO) -> None:
    """Write one device, or several (``D:`` lines, their reports merged in time order), as hid-recorder does."""
    recordings = [recording] if isinstance(recording, HidRecording) else list(recording)
    if not recordings:
        raise InvalidArgument("write_hid_recording() needs at least one recording")
    with ExitStack() as stack:
        out: TextIO = (stack.enter_context(open(file, "w", encoding="utf-8"))
                       if isinstance(file, (str, os.PathLike)) else file)
        writer = HidRecordingWriter(out, several=len(recordings) > 1, flush=False)
        for index, rec in enumerate(recordings):
            writer.device(rec, index)
        for t, index, report in _merged(recordings):
            writer.report(t, report, index)
        out.flush()


def record_link(link: ReportLink, file: TextIO, device: DeviceId, *, name: str | None = None,
                duration: float | None = None, count: int | None = None, clock: Clock | None = None) -> int:
    """Record ``link``'s input reports into ``file`` as hid-recorder does, each flushed as it comes; the count.

    The header comes from ``device`` (``name`` instead of its name: hidraw names a device "Manufacturer
    Product") and the link's descriptor; times are ``clock`` seconds after the first report.  Recording stops
    after ``duration`` seconds, ``count`` reports, Ctrl-C (KeyboardInterrupt, taken as the end) or when the
    device goes away (Disconnected, raised after what came before it is written).
    """
    if duration is not None and not (isinstance(duration, (int, float)) and duration >= 0 and math.isfinite(duration)):
        raise InvalidArgument(f"duration {quote_token(duration)}: a finite number of seconds >= 0")
    if count is not None and not (isinstance(count, int) and count >= 0):
        raise InvalidArgument(f"count {quote_token(count)}: a whole number >= 0")
    clock = clock if clock is not None else REAL_CLOCK
    writer = HidRecordingWriter(file)
    writer.device(HidRecording(device.name if name is None else name, "", BUS_NUMBERS.get(device.bus, 0),
                               device.vendor_id, device.product_id, link.report_descriptor))
    end = None if duration is None else clock.now() + duration
    first: float | None = None
    done = 0
    try:
        while count is None or done < count:
            wait = None if end is None else end - clock.now()
            if wait is not None and wait <= 0:
                break
            report = link.read_report(wait)
            if report is None:
                continue
            now = clock.now()
            first = now if first is None else first
            writer.report(max(0.0, now - first), report)
            done += 1
    except KeyboardInterrupt:
        pass
    return done


def _merged(recordings: Sequence[HidRecording]) -> Iterator[tuple[float, int, bytes]]:
    """Every device's reports as (time, device index, bytes), in time order (a device's own order kept)."""
    def stream(index: int, rec: HidRecording) -> Iterator[tuple[float, int, bytes]]:
        return ((t, index, report) for t, report in rec.reports)

    return heapq.merge(*(stream(i, rec) for i, rec in enumerate(recordings)), key=lambda item: item[0])


__all__ = ["BUS_NAMES", "LIMITS", "HidRecording", "HidRecordingWriter", "Limits", "RecordingWarning",
           "read_hid_recording", "record_link", "write_hid_recording"]

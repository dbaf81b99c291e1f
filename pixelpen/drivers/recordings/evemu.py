"""evemu files: recorded evdev devices (name, IDs, properties, event bits, axis ranges) and their timed events.

The format is the one ``evemu-record`` writes and ``evemu-device``/``evemu-play`` read (evemu's
``src/evemu.c``, file format 1.3), one line each:

* ``# text`` — a comment; ``# EVEMU 1.3`` on the first line gives the format version, and ``# device
  /dev/input/event3`` (umockdev's events header) the node it was recorded from; blank lines are skipped;
* ``N: name`` — the device name (EVIOCGNAME);
* ``I: bus vendor product version`` — four hex numbers of at most 4 digits (``I: 0003 046d c52b 0111``);
* ``P: b0 .. b7`` — 8 hex bytes of the input-property bitmask (INPUT_PROP_*); a second line continues it;
* ``B: type b0 .. b7`` — the event type and 8 hex bytes of its code bitmask (EVIOCGBIT), bit *n* of byte
  *i* being code ``8·(line·8 + i) + n``; the lines of one type continue each other;
* ``A: code min max fuzz flat resolution`` — an absolute axis (code in hex, the rest decimal; files of
  format 1.0 and 1.1 have no resolution);
* ``L: code state`` / ``S: code state`` — an LED or switch that was on;
* ``E: sec.usec type code value`` — an event: seconds, microseconds (1 to 6 digits, an integer), type and
  code in hex, value decimal; what follows the value (evemu writes a tab and ``# EV_REL / REL_X  1``) is a
  comment.

Header lines come before the first ``E:`` line and are given once (``P:``/``B:`` continue).  Times must not
go backwards: such a time is warned about (:class:`~pixelpen.drivers.recordings.hidrecorder.RecordingWarning`)
and held at the previous one, or is an error with ``strict=True``.  Errors are
:class:`~pixelpen.errors.ParseError` naming the source, line and field.  :class:`Limits` bounds the memory a
file can take (file size, line length, events, name length).

The event types and the highest code of each are the kernel's (``linux/input-event-codes.h``); the
package does not need python-evdev to read files.
"""

from __future__ import annotations

import io
import math
import os
import re
import warnings
from collections.abc import Callable, Iterable, Mapping
from contextlib import ExitStack
from dataclasses import dataclass, field
from typing import ClassVar, NamedTuple, TextIO

from pixelpen.drivers.identity import DeviceId
from pixelpen.drivers.recordings.hidrecorder import BUS_NAMES, RecordingWarning
from pixelpen.errors import InvalidArgument, InvalidArgumentType, ParseError, quote_token

__all__ = ["CODE_MAX", "EV_ABS", "EV_KEY", "EV_LED", "EV_MSC", "EV_REL", "EV_SW", "EV_SYN", "INPUT_PROP_MAX",
           "LIMITS", "AbsInfo", "EvdevRecording", "Limits", "read_evemu", "read_text_source", "write_evemu"]

EV_SYN, EV_KEY, EV_REL, EV_ABS, EV_MSC, EV_SW, EV_LED, EV_SND, EV_REP, EV_FF, EV_PWR, EV_FF_STATUS = (
    0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x11, 0x12, 0x14, 0x15, 0x16, 0x17)
EV_MAX = 0x1F
CODE_MAX: Mapping[int, int] = {EV_SYN: 0x0F, EV_KEY: 0x2FF, EV_REL: 0x0F, EV_ABS: 0x3F, EV_MSC: 0x07,
                               EV_SW: 0x10, EV_LED: 0x0F, EV_SND: 0x07, EV_REP: 0x01, EV_FF: 0x7F,
                               EV_PWR: 0x00, EV_FF_STATUS: 0x01}
"""Event type -> its highest code (SYN_MAX, KEY_MAX, REL_MAX, ABS_MAX, ...); other types have no codes."""
INPUT_PROP_MAX = 0x1F
MAX_SECONDS_DIGITS = 12
"""Digits of an event time's seconds at most (a longer number is damage, not a time)."""
_INT32 = (-(2**31), 2**31 - 1)


class AbsInfo(NamedTuple):
    """An absolute axis as the kernel describes it (struct input_absinfo; python-evdev's AbsInfo order)."""

    value: int
    min: int
    max: int
    fuzz: int
    flat: int
    resolution: int
    """Units per mm for X/Y/Z and the MT positions, units per radian for rotations and tilt (0: unknown)."""


@dataclass(frozen=True)
class Limits:
    """What an evemu file may hold at most; beyond one is a ParseError naming the limit."""

    file_bytes: int = 256 * 2**20
    """The file's size (256 MiB: about 6 million event lines)."""
    events: int = 5_000_000
    """Events in all (each costs ~100 bytes of memory)."""
    line_chars: int = 4096
    """A line's length (evemu's longest, a commented event, is under 100)."""
    name_chars: int = 1024
    """An ``N:`` name (the kernel's EVIOCGNAME answers fit 256 bytes)."""


LIMITS = Limits()
"""The default limits."""


@dataclass
class EvdevRecording:
    """One recorded evdev device: who it is, what it can send, and its events (seconds, type, code, value)."""

    name: str
    bus: int
    """The kernel's bus type (BUS_USB 3, BUS_BLUETOOTH 5, BUS_VIRTUAL 6, BUS_I2C 0x18)."""
    vendor_id: int
    product_id: int
    version: int
    properties: frozenset[int] = frozenset()
    """INPUT_PROP_* bits (0 pointer, 1 direct, 2 buttonpad, ...)."""
    codes: dict[int, frozenset[int]] = field(default_factory=dict)
    """Event type -> the codes the device can send (EV_SYN included when recorded)."""
    absinfo: dict[int, AbsInfo] = field(default_factory=dict)
    """ABS code -> its range, fuzz, flat and resolution (``value`` 0: evemu does not record it)."""
    leds: dict[int, int] = field(default_factory=dict)
    switches: dict[int, int] = field(default_factory=dict)
    events: list[tuple[float, int, int, int]] = field(default_factory=list)
    """(seconds, type, code, value) in order, SYN_REPORT events included."""
    node: str = ""
    """The node it was recorded from, when the file says (``# device /dev/input/event3``)."""

    @property
    def device_id(self) -> DeviceId:
        """The recorded device's identity."""
        return DeviceId(bus=BUS_NAMES.get(self.bus, "unknown"), vendor_id=self.vendor_id,
                        product_id=self.product_id, name=self.name, path=self.node)


# ---- reading -----------------------------------------------------------------------------------------------

_VERSION = re.compile(r"#\s*EVEMU\s+(\d{1,4})\.(\d{1,4})\s*$")
_NODE = re.compile(r"#\s*device\s+(/\S+)\s*$")
_HEX4 = re.compile(r"[0-9a-fA-F]{1,4}\Z")
_HEX2 = re.compile(r"[0-9a-fA-F]{1,2}\Z")
_INT = re.compile(r"[-+]?\d{1,11}\Z")


class _Reader:
    """The state of one read: the header so far, the events, and the counts the limits bound."""

    def __init__(self, source: str, strict: bool, limits: Limits) -> None:
        self.source = source
        self.strict = strict
        self.limits = limits
        self.line = 0
        self.version = (1, 0)
        self.name: str | None = None
        self.ids: tuple[int, int, int, int] | None = None
        self.node = ""
        self.properties: set[int] = set()
        self.prop_bytes = 0
        self.codes: dict[int, set[int]] = {}
        self.mask_bytes: dict[int, int] = {}
        self.absinfo: dict[int, AbsInfo] = {}
        self.leds: dict[int, int] = {}
        self.switches: dict[int, int] = {}
        self.events: list[tuple[float, int, int, int]] = []
        self.last = 0.0
        self.backwards = 0
        self.first_backwards = 0
        self.backwards_source = source
        self.events_only = False
        """Whether this is a separate events file (device lines refused)."""

    def error(self, message: str, token: object = None) -> ParseError:
        return ParseError(message, source=self.source, line=self.line, token=token)

    def feed(self, text: str) -> None:
        stripped = text.strip()
        if not stripped:
            return
        if stripped[0] == "#":
            self.comment(stripped)
            return
        kind, body = stripped[:2], stripped[2:].strip()
        handler = self._HANDLERS.get(kind)
        if handler is None:
            raise self.error("not an evemu line: expected N:, I:, P:, B:, A:, L:, S:, E: or a # comment",
                             stripped[:40])
        if kind != "E:" and self.events_only:
            raise self.error(f"{kind} a device line in an events file (only E: lines and comments)")
        if kind != "E:" and self.events:
            raise self.error(f"{kind} a device line after the events began (line types N: I: P: B: A: L: S: "
                             "come first)")
        handler(self, body)

    def comment(self, text: str) -> None:
        if self.line == 1 and (match := _VERSION.match(text)):
            self.version = (int(match.group(1)), int(match.group(2)))
        elif match := _NODE.match(text):
            self.node = match.group(1)

    def hex_number(self, kind: str, what: str, token: str, pattern: re.Pattern[str], top: int) -> int:
        if not pattern.match(token) or int(token, 16) > top:
            raise self.error(f"{kind} the {what} is not a hex number of 0 to {top:#x}", token)
        return int(token, 16)

    def integer(self, kind: str, what: str, token: str) -> int:
        if not _INT.match(token) or not _INT32[0] <= int(token) <= _INT32[1]:
            raise self.error(f"{kind} the {what} is not a 32-bit decimal integer", token)
        return int(token)

    def fields(self, kind: str, body: str, count: int | tuple[int, ...], form: str) -> list[str]:
        parts = body.split()
        counts = (count,) if isinstance(count, int) else count
        if len(parts) not in counts:
            raise self.error(f"{kind} expected '{kind} {form}'", body)
        return parts

    def name_line(self, body: str) -> None:
        if self.name is not None:
            raise self.error("N: a second device name", body)
        if len(body) > self.limits.name_chars:
            raise self.error(f"N: the name is {len(body)} characters (at most {self.limits.name_chars})")
        self.name = body

    def ids_line(self, body: str) -> None:
        if self.ids is not None:
            raise self.error("I: a second bus/vendor/product/version line", body)
        parts = self.fields("I:", body, 4, "BUS VENDOR PRODUCT VERSION")
        values = [self.hex_number("I:", what, token, _HEX4, 0xFFFF)
                  for what, token in zip(("bus", "vendor", "product", "version"), parts, strict=True)]
        self.ids = (values[0], values[1], values[2], values[3])

    def mask_bits(self, kind: str, tokens: list[str], start: int) -> list[int]:
        """The set bits of 8 hex bytes, numbered from ``start``."""
        out: list[int] = []
        for i, token in enumerate(tokens):
            byte = self.hex_number(kind, f"byte {i}", token, _HEX2, 0xFF)
            out.extend(start + 8 * i + bit for bit in range(8) if byte >> bit & 1)
        return out

    def props_line(self, body: str) -> None:
        parts = self.fields("P:", body, 8, "B0 B1 B2 B3 B4 B5 B6 B7 (hex bytes)")
        for bit in self.mask_bits("P:", parts, 8 * self.prop_bytes):
            if bit > INPUT_PROP_MAX:
                raise self.error(f"P: property bit {bit} is beyond INPUT_PROP_MAX ({INPUT_PROP_MAX:#x})", bit)
            self.properties.add(bit)
        self.prop_bytes += 8

    def mask_line(self, body: str) -> None:
        parts = self.fields("B:", body, 9, "TYPE B0 B1 B2 B3 B4 B5 B6 B7 (hex)")
        ev_type = self.hex_number("B:", "event type", parts[0], _HEX2, EV_MAX)
        offset = self.mask_bytes.get(ev_type, 0)
        top = CODE_MAX.get(ev_type, -1)
        bits = self.mask_bits("B:", parts[1:], 8 * offset)
        if bits and bits[-1] > top:
            raise self.error(f"B: code {bits[-1]:#x} of event type {ev_type:#x} is beyond its highest code "
                             f"({top:#x})", bits[-1])
        if bits:
            self.codes.setdefault(ev_type, set()).update(bits)
        self.mask_bytes[ev_type] = offset + 8

    def abs_line(self, body: str) -> None:
        parts = self.fields("A:", body, (5, 6), "CODE MIN MAX FUZZ FLAT RESOLUTION")
        if len(parts) == 5 and self.version > (1, 1):
            raise self.error(f"A: no resolution (format {self.version[0]}.{self.version[1]} has six fields)", body)
        code = self.hex_number("A:", "axis code", parts[0], _HEX2, CODE_MAX[EV_ABS])
        if code in self.absinfo:
            raise self.error(f"A: a second line for axis {code:#04x}", body)
        numbers = [self.integer("A:", what, token) for what, token in
                   zip(("minimum", "maximum", "fuzz", "flat", "resolution"), parts[1:], strict=False)]
        minimum, maximum, fuzz, flat = numbers[:4]
        self.absinfo[code] = AbsInfo(0, minimum, maximum, fuzz, flat, numbers[4] if len(numbers) == 5 else 0)

    def state_line(self, kind: str, body: str, ev_type: int, table: dict[int, int]) -> None:
        parts = self.fields(kind, body, 2, "CODE STATE")
        code = self.hex_number(kind, "code", parts[0], _HEX2, CODE_MAX[ev_type])
        table[code] = self.integer(kind, "state", parts[1])

    def event_line(self, body: str) -> None:
        parts = body.split(None, 4)
        if len(parts) < 4 or (len(parts) == 5 and not parts[4].lstrip().startswith("#")):
            raise self.error("E: expected 'E: SECONDS.MICROSECONDS TYPE CODE VALUE' (a # comment may follow)",
                             body[:60])
        stamp, type_text, code_text, value_text = parts[:4]
        sec, dot, usec = stamp.partition(".")
        if not (dot and sec.isascii() and sec.isdecimal() and usec.isascii() and usec.isdecimal()
                and len(sec) <= MAX_SECONDS_DIGITS and 1 <= len(usec) <= 6):
            raise self.error("E: the time is not SECONDS.MICROSECONDS (digits, a dot, 1 to 6 digits)", stamp)
        t = int(sec) + int(usec) * 1e-6
        ev_type = self.hex_number("E:", "event type", type_text, _HEX4, 0xFFFF)
        code = self.hex_number("E:", "event code", code_text, _HEX4, 0xFFFF)
        value = self.integer("E:", "event value", value_text)
        if len(self.events) >= self.limits.events:
            raise self.error(f"E: more than {self.limits.events} events (the limit of a recording)")
        if t < self.last:
            if self.strict:
                raise self.error(f"E: the time {stamp} s is before the previous event's {self.last:.6f} s "
                                 "(times must not go backwards)", stamp)
            if not self.backwards:
                self.first_backwards = self.line
                self.backwards_source = self.source
            self.backwards += 1
            t = self.last
        self.last = t
        self.events.append((t, ev_type, code, value))

    _HANDLERS: ClassVar[dict[str, Callable[[_Reader, str], None]]] = {
        "N:": name_line, "I:": ids_line, "P:": props_line, "B:": mask_line, "A:": abs_line, "E:": event_line,
        "L:": lambda self, body: self.state_line("L:", body, EV_LED, self.leds),
        "S:": lambda self, body: self.state_line("S:", body, EV_SW, self.switches),
    }

    def finish(self) -> EvdevRecording:
        missing = [kind for kind, value in (("N:", self.name), ("I:", self.ids)) if value is None]
        if missing:
            raise ParseError(f"no {' or '.join(missing)} line: not an evemu device description", source=self.source,
                             line=self.line or None)
        if self.backwards:
            warnings.warn(f"{self.backwards_source}: line {self.first_backwards}: {self.backwards} event times go "
                          "backwards; each is held at the time before it", RecordingWarning, stacklevel=3)
        if self.absinfo and EV_ABS not in self.codes:
            self.codes[EV_ABS] = set(self.absinfo)
        assert self.name is not None and self.ids is not None
        bus, vendor, product, version = self.ids
        codes = {t: frozenset(c) for t, c in sorted(self.codes.items())}
        return EvdevRecording(self.name, bus, vendor, product, version, frozenset(self.properties), codes,
                              dict(sorted(self.absinfo.items())), self.leds, self.switches, self.events, self.node)


def read_text_source(path_or_text: str | bytes | os.PathLike[str] | TextIO, stack: ExitStack, kind: str,
                     file_bytes: int) -> tuple[TextIO, str]:
    """The text to read and its name: a path, an open text file, ``bytes``, or a ``str`` holding a line break.

    A file larger than ``file_bytes`` is a ParseError before it is read; bytes that are not UTF-8 are replaced.
    """
    if isinstance(path_or_text, bytes):
        stream: TextIO = io.StringIO(path_or_text.decode("utf-8", "replace"))
        name, size = f"<{kind} text>", len(path_or_text)
    elif isinstance(path_or_text, str) and ("\n" in path_or_text or "\r" in path_or_text):
        stream, name, size = io.StringIO(path_or_text), f"<{kind} text>", len(path_or_text)
    elif isinstance(path_or_text, (str, os.PathLike)):
        try:
            stream = stack.enter_context(open(path_or_text, encoding="utf-8", errors="replace"))  # noqa: SIM115
        except OSError as exc:
            raise ParseError(f"cannot open the {kind} file: {exc.strerror or exc}", source=str(path_or_text)) from None
        name, size = str(path_or_text), os.fstat(stream.fileno()).st_size
    elif hasattr(path_or_text, "readline"):
        return path_or_text, str(getattr(path_or_text, "name", f"<{kind} stream>"))
    else:
        raise InvalidArgumentType(f"a {kind} is read from a path, text or a text file, not "
                                  f"{type(path_or_text).__name__}")
    if size > file_bytes:
        raise ParseError(f"the file is {size} bytes, more than the {file_bytes}-byte limit", source=name)
    return stream, name


def read_evemu(path_or_text: str | bytes | os.PathLike[str] | TextIO, *, events: str | bytes | os.PathLike[str]
               | TextIO | None = None, source: str | None = None, strict: bool = False,
               limits: Limits = LIMITS) -> EvdevRecording:
    """The device and events of an evemu file: a path, an open text file, or the text itself.

    A ``str`` holding a line break, or ``bytes``, is the text; any other ``str`` is a path.  ``events`` is a
    separate events file (``E:`` lines and comments only, as older evemu-record and umockdev write them), its
    events after the description's.  ``strict`` makes a time going backwards an error instead of a warning.
    """
    reader = _read(path_or_text, source, strict, limits, None)
    if events is not None and reader.name is not None and reader.ids is not None:  # else finish() says so
        reader = _read(events, None, strict, limits, reader)
    return reader.finish()


def _read(path_or_text: str | bytes | os.PathLike[str] | TextIO, source: str | None, strict: bool, limits: Limits,
          description: _Reader | None) -> _Reader:
    """Feed a file's lines to a new reader, or (an events file) to the one that read the description."""
    with ExitStack() as stack:
        lines, name = read_text_source(path_or_text, stack, "evemu", limits.file_bytes)
        reader = _Reader(source or name, strict, limits)
        if description is not None:  # the events file continues the description's reader, under its own name
            reader, description.source, description.line = description, reader.source, 0
            reader.events_only = True
        chars = 0
        while True:
            text = lines.readline(limits.line_chars + 1)
            if not text:
                break
            reader.line += 1
            chars += len(text)
            if len(text) > limits.line_chars and not text.endswith("\n"):
                raise reader.error(f"a line longer than {limits.line_chars} characters")
            if chars > limits.file_bytes:
                raise reader.error(f"more than the {limits.file_bytes}-byte limit of a file")
            reader.feed(text)
        return reader


# ---- writing -----------------------------------------------------------------------------------------------

def _mask_lines(prefix: str, bits: Iterable[int], top: int) -> list[str]:
    """``P:``/``B:`` lines for a bitmask of codes 0..top, 8 bytes a line, as evemu writes them."""
    mask = bytearray(((top + 1 + 7) // 8 + 7) // 8 * 8)
    for bit in bits:
        mask[bit // 8] |= 1 << bit % 8
    return [f"{prefix}{' '.join(f'{b:02x}' for b in mask[i:i + 8])}" for i in range(0, len(mask), 8)]


def write_evemu(recording: EvdevRecording, file: str | os.PathLike[str] | TextIO, *, events: bool = True,
                description: bool = True) -> None:
    """Write a recording as evemu-record does (format 1.3): the description, then its events.

    ``description=False`` writes only the events (an events file, as umockdev-run ``--evemu-events`` reads).
    """
    if not isinstance(recording, EvdevRecording):
        raise InvalidArgumentType(f"expected an EvdevRecording, not {type(recording).__name__}")
    lines = ["# EVEMU 1.3"]
    if recording.node:
        lines.append(f"# device {recording.node}")
    if description:
        if "\n" in recording.name or "\r" in recording.name:
            raise InvalidArgument(f"the name {quote_token(recording.name)} has a line break")
        for what, value in (("bus", recording.bus), ("vendor ID", recording.vendor_id),
                            ("product ID", recording.product_id), ("version", recording.version)):
            if not (isinstance(value, int) and 0 <= value <= 0xFFFF):
                raise InvalidArgument(f"the {what} {quote_token(value)} is not 0 to 0xffff")
        lines += [f"N: {recording.name}", f"I: {recording.bus:04x} {recording.vendor_id:04x} "
                  f"{recording.product_id:04x} {recording.version:04x}"]
        lines += _mask_lines("P: ", recording.properties, INPUT_PROP_MAX)
        lines.append("B: 00 0b 00 00 00 00 00 00 00")
        for ev_type, top in CODE_MAX.items():
            if ev_type != EV_SYN:
                lines += _mask_lines(f"B: {ev_type:02x} ", recording.codes.get(ev_type, ()), top)
        lines += [f"A: {code:02x} {a.min} {a.max} {a.fuzz} {a.flat} {a.resolution}"
                  for code, a in sorted(recording.absinfo.items())]
        lines += [f"L: {code:02x} {state}" for code, state in sorted(recording.leds.items()) if state]
        lines += [f"S: {code:02x} {state}" for code, state in sorted(recording.switches.items()) if state]
    if events:
        last = 0.0
        for t, ev_type, code, value in recording.events:
            if not (math.isfinite(t) and last <= t < 10.0**MAX_SECONDS_DIGITS):
                raise InvalidArgument(f"event time {quote_token(t)}: finite, >= 0 and not before the previous one")
            last = t
            sec, usec = divmod(round(t * 1e6), 1_000_000)
            lines.append(f"E: {sec}.{usec:06d} {ev_type:04x} {code:04x} {value}")
    with ExitStack() as stack:
        out: TextIO = (stack.enter_context(open(file, "w", encoding="utf-8"))
                       if isinstance(file, (str, os.PathLike)) else file)
        out.write("\n".join(lines) + "\n")
        out.flush()

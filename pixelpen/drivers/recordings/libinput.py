"""libinput record files: the YAML ``libinput record`` writes, read as evdev recordings.

The format is libinput's ``tools/libinput-record.c`` (file ``version: 1``)::

    version: 1
    ndevices: 1
    devices:
      - node: /dev/input/event5
        evdev:
          name: "Logitech USB Optical Mouse"
          id: [3, 1133, 49271, 273]          # bus, vendor, product, version (decimal)
          codes:
            0: [0, 1, 2]                     # event type: the codes it sends
            2: [0, 1, 8]
          absinfo:
            0: [0, 4095, 0, 0, 30]           # code: min, max, fuzz, flat, resolution
          properties: [0]
        events:
          - evdev:
            - [  0,      0,   2,   0,      -1]   # sec, usec, type, code, value
            - [  0,      0,   0,   0,       0]
          - libinput: ...                    # libinput's own events (skipped)

Each device becomes an :class:`~pixelpen.drivers.recordings.evemu.EvdevRecording`; ``hid``, ``udev``,
``quirks`` and libinput's own events are not read.  Key codes are obfuscated by libinput unless it was run
with ``--show-keycodes`` (letters become ``KEY_A``), which this reader cannot undo.  YAML aliases are
refused (libinput writes none, and they could make a small file expand); the file size and the event count
are bounded by :class:`~pixelpen.drivers.recordings.evemu.Limits`.  PyYAML is the ``input`` extra.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from contextlib import ExitStack
from typing import Any, TextIO

from pixelpen.drivers.devnode import require_module
from pixelpen.drivers.recordings.evemu import (
    CODE_MAX,
    EV_ABS,
    EV_MAX,
    INPUT_PROP_MAX,
    LIMITS,
    AbsInfo,
    EvdevRecording,
    Limits,
    read_text_source,
)
from pixelpen.errors import ParseError

__all__ = ["FILE_VERSION", "read_libinput_record"]

FILE_VERSION = 1
"""The libinput record format version this reader knows."""
MAX_NESTING = 64
"""Flow brackets (``[``, ``{``) open at once at most (libinput writes 2; deeper YAML only costs recursion)."""
_INT32 = (-(2**31), 2**31 - 1)


def _loader(yaml: Any) -> type:
    """PyYAML's safe loader, refusing aliases."""

    class Loader(yaml.SafeLoader):
        def compose_node(self, parent: object, index: object) -> object:
            if self.check_event(yaml.AliasEvent):
                mark = self.peek_event().start_mark
                raise ParseError("a YAML alias (libinput record files have none)", line=mark.line + 1)
            return super().compose_node(parent, index)

    return Loader


class _Where:
    """The source and the device being read, for errors."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.path = ""

    def error(self, message: str, token: object = None) -> ParseError:
        where = f"{self.path}: " if self.path else ""
        return ParseError(where + message, source=self.source, token=token)

    def integer(self, value: object, what: str, low: int = _INT32[0], high: int = _INT32[1]) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise self.error(f"{what} is not an integer of {low} to {high}", value)
        return value

    def mapping(self, value: object, what: str) -> Mapping[Any, Any]:
        if not isinstance(value, Mapping):
            raise self.error(f"{what} is not a mapping", value)
        return value

    def sequence(self, value: object, what: str) -> list[Any]:
        if not isinstance(value, list):
            raise self.error(f"{what} is not a list", value)
        return value


def read_libinput_record(path_or_text: str | bytes | os.PathLike[str] | TextIO, *, source: str | None = None,
                         limits: Limits = LIMITS) -> list[EvdevRecording]:
    """The evdev devices of a ``libinput record`` file and their events: a path, a text file or the text."""
    yaml = require_module("yaml", needed_by="libinput record files", install="'pixelpen[input]'",
                          package="PyYAML")
    with ExitStack() as stack:
        stream, name = read_text_source(path_or_text, stack, "libinput record", limits.file_bytes)
        text = stream.read(limits.file_bytes + 1)
    where = _Where(source or name)
    if len(text) > limits.file_bytes:
        raise where.error(f"more than the {limits.file_bytes}-byte limit of a file")
    _check_nesting(where, text)
    try:
        document = yaml.load(text, Loader=_loader(yaml))  # a SafeLoader subclass
    except ParseError as exc:
        raise ParseError(exc.message, source=where.source, line=exc.line) from None
    except RecursionError:
        raise where.error("the YAML is nested too deeply") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise ParseError(f"not YAML: {getattr(exc, 'problem', None) or exc}", source=where.source,
                         line=mark.line + 1 if mark is not None else None) from None
    except ValueError as exc:  # a value PyYAML cannot construct (an integer of over 4300 digits)
        raise where.error(f"a value that cannot be read: {exc}") from None
    top = where.mapping(document, "the file")
    version = top.get("version")
    if version != FILE_VERSION:
        raise where.error(f"version: expected {FILE_VERSION} (a libinput record file)", version)
    devices = where.sequence(top.get("devices"), "devices")
    if not devices:
        raise where.error("devices: no device in the recording")
    budget = [limits.events]
    return [_device(where, i, device, budget) for i, device in enumerate(devices)]


def _check_nesting(where: _Where, text: str) -> None:
    """ParseError where more than MAX_NESTING flow brackets are open (comments after ``#`` not counted)."""
    for number, line in enumerate(text.splitlines(), 1):
        depth = 0
        for char in line.partition("#")[0]:
            depth += (char in "[{") - (char in "]}")
            if depth > MAX_NESTING:
                raise ParseError(f"more than {MAX_NESTING} brackets open at once", source=where.source, line=number)


def _device(where: _Where, index: int, raw: object, budget: list[int]) -> EvdevRecording:
    where.path = f"devices[{index}]"
    device = where.mapping(raw, "the device")
    node = device.get("node", "")
    evdev = where.mapping(device.get("evdev"), "evdev")
    name = evdev.get("name")
    if not isinstance(name, str):
        raise where.error("evdev.name is not text", name)
    ids = where.sequence(evdev.get("id"), "evdev.id")
    if len(ids) != 4:
        raise where.error("evdev.id: expected [bus, vendor, product, version]", ids)
    bus, vendor, product, version = (where.integer(v, f"evdev.id[{i}]", 0, 0xFFFF) for i, v in enumerate(ids))
    codes: dict[int, frozenset[int]] = {}
    for key, values in where.mapping(evdev.get("codes", {}) or {}, "evdev.codes").items():
        ev_type = where.integer(key, "an event type in evdev.codes", 0, EV_MAX)
        top = CODE_MAX.get(ev_type, -1)
        if top < 0:
            raise where.error(f"evdev.codes: event type {ev_type} has no codes", ev_type)
        codes[ev_type] = frozenset(where.integer(c, f"evdev.codes.{ev_type}[{i}]", 0, top)
                                   for i, c in enumerate(where.sequence(values or [], f"evdev.codes.{ev_type}")))
    absinfo: dict[int, AbsInfo] = {}
    for key, values in where.mapping(evdev.get("absinfo", {}) or {}, "evdev.absinfo").items():
        code = where.integer(key, "an axis code in evdev.absinfo", 0, CODE_MAX[EV_ABS])
        numbers = where.sequence(values, f"evdev.absinfo.{code}")
        if len(numbers) != 5:
            raise where.error(f"evdev.absinfo.{code}: expected [min, max, fuzz, flat, resolution]", numbers)
        minimum, maximum, fuzz, flat, resolution = (where.integer(v, f"evdev.absinfo.{code}[{i}]")
                                                    for i, v in enumerate(numbers))
        absinfo[code] = AbsInfo(0, minimum, maximum, fuzz, flat, resolution)
    properties = frozenset(where.integer(p, f"evdev.properties[{i}]", 0, INPUT_PROP_MAX)
                           for i, p in enumerate(where.sequence(evdev.get("properties", []) or [],
                                                                "evdev.properties")))
    events: list[tuple[float, int, int, int]] = []
    for f, frame in enumerate(where.sequence(device.get("events", []) or [], "events")):
        lines = where.mapping(frame, f"events[{f}]").get("evdev")
        if lines is None:
            continue  # a libinput event
        for e, line in enumerate(where.sequence(lines, f"events[{f}].evdev")):
            budget[0] -= 1
            if budget[0] < 0:
                raise where.error("more events than the limit of a recording")
            items = where.sequence(line, f"events[{f}].evdev[{e}]")
            if len(items) != 5:
                raise where.error(f"events[{f}].evdev[{e}]: expected [sec, usec, type, code, value]", items)
            sec = where.integer(items[0], f"events[{f}].evdev[{e}] seconds", 0, 10**12)
            usec = where.integer(items[1], f"events[{f}].evdev[{e}] microseconds", 0, 999_999)
            ev_type = where.integer(items[2], f"events[{f}].evdev[{e}] type", 0, 0xFFFF)
            code = where.integer(items[3], f"events[{f}].evdev[{e}] code", 0, 0xFFFF)
            value = where.integer(items[4], f"events[{f}].evdev[{e}] value")
            t = sec + usec * 1e-6
            if events and t < events[-1][0]:
                raise where.error(f"events[{f}].evdev[{e}]: the time goes backwards", t)
            events.append((t, ev_type, code, value))
    if absinfo and EV_ABS not in codes:
        codes[EV_ABS] = frozenset(absinfo)
    return EvdevRecording(name, bus, vendor, product, version, properties, dict(sorted(codes.items())),
                          dict(sorted(absinfo.items())), events=events, node=node if isinstance(node, str) else "")

"""The Linux ``panel-mipi-dbi`` firmware format (drivers/gpu/drm/tiny/panel-mipi-dbi.c): init tables as files.

Layout: 15 bytes of magic ``"MIPI DBI"`` padded with NULs, a version byte (1), then entries ``command,
num_parameters, parameters...``; the entry ``00 01 ms`` (NOP with one parameter) is a sleep of ``ms``
milliseconds.  Read as the kernel validates it: at least one entry, no entry running past the end, no stray
byte after the last.  Sleeps attach to the step before them (leading sleeps to a parameterless NOP step);
a delay longer than 255 ms is written as several sleeps, a fractional one rounded up to whole ms.
Limits: :data:`MAX_BYTES` per file (64 KiB; the kernel sets none), the steps and parameters of
:mod:`pixelpen.profiles.panel`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from pixelpen.errors import ConfigError, ParseError
from pixelpen.profiles import panel
from pixelpen.profiles.panel import InitStep

MAGIC = b"MIPI DBI" + bytes(7)
"""The 15-byte magic at the start of every file."""
VERSION = 1
"""The only file format version the kernel accepts."""
HEADER = len(MAGIC) + 1
"""Bytes before the first command."""
MAX_BYTES = 64 * 1024
"""Bytes of one firmware file."""
_SLEEP = 0x00
"""NOP: with exactly one parameter, a sleep."""

__all__ = ["MAGIC", "MAX_BYTES", "VERSION", "read_mipi_dbi", "write_mipi_dbi"]


def read_mipi_dbi(data: bytes, source: str = "<panel-mipi-dbi>") -> list[InitStep]:
    """The init steps of a panel-mipi-dbi file; ParseError naming ``source`` and the byte offset if malformed."""
    if len(data) > MAX_BYTES:
        raise ParseError(f"file of {len(data)} bytes is larger than the {MAX_BYTES} allowed", source=source)
    if len(data) < HEADER + 2:
        raise ParseError(f"file of {len(data)} bytes is too small: a {HEADER}-byte header and at least one command "
                         "are needed", source=source, offset=len(data))
    if data[: len(MAGIC)] != MAGIC:
        raise ParseError("bad magic: not a panel-mipi-dbi file", source=source, offset=0,
                         token=bytes(data[: len(MAGIC)]))
    if data[len(MAGIC)] != VERSION:
        raise ParseError(f"file format version {data[len(MAGIC)]} is not supported (only {VERSION})", source=source,
                         offset=len(MAGIC))
    steps: list[InitStep] = []
    i = HEADER
    while i < len(data):
        if i + 1 >= len(data):
            raise ParseError(f"command 0x{data[i]:02x} has no parameter count (one stray byte after the last "
                             "command)", source=source, offset=i)
        command, count = data[i], data[i + 1]
        params = bytes(data[i + 2: i + 2 + count])
        if len(params) < count:
            raise ParseError(f"command 0x{command:02x} declares {count} parameters but only {len(params)} bytes "
                             "remain", source=source, offset=i)
        if command == _SLEEP and count == 1:
            last = steps.pop() if steps else InitStep(_SLEEP)
            if last.delay_ms + params[0] > panel.MAX_DELAY_MS:
                raise ParseError(f"sleeps after one command add up to more than {panel.MAX_DELAY_MS:g} ms",
                                 source=source, offset=i)
            steps.append(InitStep(last.command, last.params, last.delay_ms + params[0]))
        else:
            if len(steps) >= panel.MAX_INIT_STEPS:
                raise ParseError(f"more than {panel.MAX_INIT_STEPS} commands", source=source, offset=i)
            steps.append(InitStep(command, params))
        i += 2 + count
    return steps


def write_mipi_dbi(steps: Iterable[InitStep]) -> bytes:
    """The panel-mipi-dbi file for ``steps`` (each delay as sleeps of at most 255 ms, rounded up to whole ms)."""
    out = bytearray(MAGIC)
    out.append(VERSION)
    count = 0
    for step in steps:
        if not isinstance(step, InitStep):
            raise ConfigError(f"write_mipi_dbi takes InitSteps, got {type(step).__name__}")
        if step.command == _SLEEP and len(step.params) == 1:
            raise ConfigError("a NOP (0x00) with exactly one parameter cannot be written: the format reads it as "
                              "a sleep")
        if not (step.command == _SLEEP and not step.params and step.delay_ms and count == 0):
            out += bytes([step.command, len(step.params)]) + step.params  # a leading bare sleep has no NOP
        count += 1
        delay = math.ceil(step.delay_ms)
        while delay > 0:
            out += bytes([_SLEEP, 1, min(delay, 255)])
            delay -= 255
    if count == 0:
        raise ConfigError("a panel-mipi-dbi file needs at least one command")
    return bytes(out)

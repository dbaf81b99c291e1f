"""Panel modules as data: controller, glass and RAM size, per-rotation offsets and MADCTL, clocks, init table.

A built-in module is a TOML file in ``pixelpen/data/panels``; a user module is any TOML file of the same format
(docs/panel-profiles.md), read as strictly as the plotter profiles: unknown keys are named with their dotted key
and file, every value is type-checked.  Limits (module attributes, read at call time: assign to override):

* :data:`MAX_BYTES` -- bytes of a panel profile file (256 KiB);
* :data:`MAX_INIT_STEPS` -- steps of one init table (512);
* :data:`MAX_PARAMS` -- parameter bytes of one step (255, the panel-mipi-dbi format's count byte);
* :data:`MAX_DELAY_MS` -- the delay after one step (10,000 ms; datasheets ask 500 ms at most);
* :data:`MAX_SIDE` -- pixels of a glass or RAM side (4096); :data:`MAX_CLOCK_HZ` -- a bus clock (1 GHz).
"""

from __future__ import annotations

import functools
import logging
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from importlib.abc import Traversable
from pathlib import Path
from types import MappingProxyType
from typing import Any, TypeGuard

from pixelpen.errors import ConfigError, quote_token
from pixelpen.options import I2C_ADDRESSES
from pixelpen.profiles.toml import Table, one_of, pair_of, profile_file, profile_key, read_file, read_text
from pixelpen.tomltext import read_toml
from pixelpen.urls import check_path

log = logging.getLogger(__name__)

MAX_BYTES = 256 * 1024
"""Bytes of a panel profile file."""
MAX_DEPTH = 8
"""Nesting of arrays and inline tables in a panel profile (the init table needs 3)."""
MAX_INIT_STEPS = 512
"""Steps of one init table."""
MAX_PARAMS = 255
"""Parameter bytes of one init step."""
MAX_DELAY_MS = 10_000.0
"""Milliseconds of the delay after one init step."""
MAX_SIDE = 4096
"""Pixels of a glass or RAM side."""
MAX_CLOCK_HZ = 1e9
"""A bus clock in Hz."""

CONTROLLERS = ("ssd1306", "sh1106", "ssd1309", "st7789", "ili9341", "st7735")
"""Controllers a profile may name."""
OLED_CONTROLLERS = ("ssd1306", "sh1106", "ssd1309")
"""The paged monochrome controllers (SSD1306 family); the others speak MIPI DCS."""
PIXEL_FORMATS = ("rgb565be", "rgb666", "mono-pages")
"""Pixel formats on the wire: 16-bit big-endian RGB565, 18-bit in 3 bytes, SSD1306 pages (8 rows per byte)."""
BYTES_PER_PIXEL: Mapping[str, float] = {"rgb565be": 2.0, "rgb666": 3.0, "mono-pages": 0.125}
"""Bytes one pixel takes on the wire, by pixel format."""
COLMOD: Mapping[str, int] = {"rgb565be": 0x55, "rgb666": 0x66}
"""The COLMOD (3Ah) parameter that selects each MIPI pixel format."""
ROTATIONS = (0, 90, 180, 270)
"""Rotations in degrees; n·90 is Adafruit's ``setRotation(n)``."""
BUS_KINDS = ("spi", "i2c")
"""Bus kinds a profile gives clocks for."""

MADCTL_MY, MADCTL_MX, MADCTL_MV, MADCTL_ML, MADCTL_BGR, MADCTL_MH = 0x80, 0x40, 0x20, 0x10, 0x08, 0x04
"""MADCTL (36h) bits: row order, column order, row/column exchange, refresh orders, BGR colour filter."""
_ROTATION_BITS = MADCTL_MY | MADCTL_MX | MADCTL_MV | MADCTL_ML | MADCTL_MH

__all__ = [
    "BUS_KINDS", "BYTES_PER_PIXEL", "COLMOD", "CONTROLLERS", "MADCTL_BGR", "MADCTL_MH", "MADCTL_ML", "MADCTL_MV",
    "MADCTL_MX", "MADCTL_MY", "OLED_CONTROLLERS", "PIXEL_FORMATS", "ROTATIONS", "InitStep",
    "PanelGeometry", "PanelProfile", "RotationSetup", "builtin_panel_profiles", "load_panel_profile",
    "panel_profile_for", "read_panel_profile",
]


def _is_i2c_address(value: object) -> bool:
    """An int in the non-reserved 7-bit I2C range (options.I2C_ADDRESSES)."""
    return _is_int(value, I2C_ADDRESSES.start, I2C_ADDRESSES.stop - 1)


def _is_int(v: object, low: int, high: int) -> TypeGuard[int]:
    """An integer (not a bool) in low..high."""
    return isinstance(v, int) and not isinstance(v, bool) and low <= v <= high


def _is_clock(v: object) -> bool:
    """A clock in Hz: a number > 0 and <= MAX_CLOCK_HZ."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < v <= MAX_CLOCK_HZ


@dataclass(frozen=True)
class InitStep:
    """One init-table entry: a command byte, its parameter bytes, then a wait of ``delay_ms`` milliseconds."""

    command: int
    params: bytes = b""
    delay_ms: float = 0.0

    def __post_init__(self) -> None:
        if not _is_int(self.command, 0, 255):
            raise ConfigError(f"init step command must be a byte 0..255, got {quote_token(self.command)}")
        if not isinstance(self.params, bytes):
            raise ConfigError(f"init step 0x{self.command:02x}: params must be bytes, got {type(self.params).__name__}")
        if len(self.params) > MAX_PARAMS:
            raise ConfigError(f"init step 0x{self.command:02x}: {len(self.params)} parameter bytes, "
                              f"more than the {MAX_PARAMS} allowed")
        delay = self.delay_ms
        if not (isinstance(delay, (int, float)) and not isinstance(delay, bool) and math.isfinite(delay)
                and 0 <= delay <= MAX_DELAY_MS):
            raise ConfigError(f"init step 0x{self.command:02x}: delay_ms must be 0..{MAX_DELAY_MS:g} ms, "
                              f"got {quote_token(delay)}")


@dataclass(frozen=True)
class RotationSetup:
    """A MIPI module at one rotation: the (x, y) offsets added to CASET/RASET and the MADCTL rotation bits."""

    offset: tuple[int, int]
    madctl: int

    @property
    def exchanged(self) -> bool:
        """True when MV swaps rows and columns (the glass is seen sideways: width and height swap)."""
        return bool(self.madctl & MADCTL_MV)


@dataclass(frozen=True)
class PanelGeometry:
    """What a driver needs at one rotation: visible size, RAM offsets, and the scan-direction settings.

    MIPI: ``madctl`` is the whole MADCTL byte (rotation bits and BGR). SSD1306 family: ``segment_remap`` (A1h
    instead of A0h) and ``com_reverse`` (C8h instead of C0h); ``x_offset`` is the column start.
    """

    rotation: int
    width: int
    height: int
    x_offset: int
    y_offset: int
    madctl: int = 0
    segment_remap: bool = False
    com_reverse: bool = False


@dataclass(frozen=True)
class PanelProfile:
    """Everything pixelpen knows about one panel module; sizes are (width, height) at rotation 0."""

    name: str
    controller: str
    size: tuple[int, int]
    ram_size: tuple[int, int]
    pixel_format: str
    init: tuple[InitStep, ...]
    clock_hz: Mapping[str, float]
    max_clock_hz: Mapping[str, float] = field(default_factory=dict)
    rotations: Mapping[int, RotationSetup] = field(default_factory=dict)
    description: str = ""
    bgr: bool = False
    invert: bool = False
    te: bool = False
    i2c_address: int | None = None
    multiplex: int | None = None
    com_pins: int | None = None
    column_offset: int = 0
    charge_pump: bool | None = None
    contrast: int | None = None
    segment_remap: bool = True
    com_reverse: bool = True
    source: str = ""

    @property
    def oled(self) -> bool:
        """True for the paged monochrome SSD1306 family."""
        return self.controller in OLED_CONTROLLERS

    @property
    def bytes_per_pixel(self) -> float:
        """Bytes per pixel on the wire in the default pixel format."""
        return BYTES_PER_PIXEL[self.pixel_format]

    def __post_init__(self) -> None:
        where = f"panel profile {self.name!r}" + (f" ({self.source})" if self.source else "")
        if self.controller not in CONTROLLERS:
            raise ConfigError(f"{where}: unknown controller {quote_token(self.controller)} "
                              f"(known: {', '.join(CONTROLLERS)})")
        for key in ("size", "ram_size"):
            value = getattr(self, key)
            if not (isinstance(value, tuple) and len(value) == 2 and all(_is_int(v, 1, MAX_SIDE) for v in value)):
                raise ConfigError(f"{where}: {key} must be (width, height) of 1..{MAX_SIDE}, got {quote_token(value)}")
        formats = ("mono-pages",) if self.oled else tuple(COLMOD)
        if self.pixel_format not in formats:
            raise ConfigError(f"{where}: pixel_format must be {' or '.join(formats)} for a {self.controller}, "
                              f"got {quote_token(self.pixel_format)}")
        if not self.clock_hz or any(k not in BUS_KINDS or not _is_clock(v) for k, v in self.clock_hz.items()):
            raise ConfigError(f"{where}: clock_hz must give a clock in Hz for spi and/or i2c, "
                              f"got {quote_token(dict(self.clock_hz))}")
        if any(k not in self.clock_hz or not _is_clock(v) for k, v in self.max_clock_hz.items()):
            raise ConfigError(f"{where}: max_clock_hz must give clocks for the buses of clock_hz only, "
                              f"got {quote_token(dict(self.max_clock_hz))}")
        if len(self.init) > MAX_INIT_STEPS or not all(isinstance(s, InitStep) for s in self.init):
            raise ConfigError(f"{where}: init must be at most {MAX_INIT_STEPS} InitSteps")
        for key in ("clock_hz", "max_clock_hz", "rotations"):  # a shared built-in profile stays unchanged
            object.__setattr__(self, key, MappingProxyType(dict(getattr(self, key))))
        if self.oled:
            self._check_oled(where)
        else:
            self._check_mipi(where)

    def _check_mipi(self, where: str) -> None:
        """Rotation table complete and fitting the RAM; the init table agrees with the format and inversion."""
        if set(self.rotations) != set(ROTATIONS):
            raise ConfigError(f"{where}: a {self.controller} profile needs rotations 0, 90, 180 and 270, "
                              f"got {sorted(self.rotations)}")
        oled_fields = {"multiplex": self.multiplex, "com_pins": self.com_pins, "charge_pump": self.charge_pump,
                       "contrast": self.contrast, "i2c_address": self.i2c_address,
                       "column_offset": self.column_offset or None}
        given = [k for k, v in oled_fields.items() if v is not None]
        if given:
            raise ConfigError(f"{where}: {', '.join(given)}: SSD1306-family settings, not for a {self.controller}")
        for rotation in ROTATIONS:
            setup = self.rotations[rotation]
            if not _is_int(setup.madctl, 0, 255) or setup.madctl & ~_ROTATION_BITS:
                raise ConfigError(f"{where}: rotation {rotation}: madctl must hold only MY MX MV ML MH bits "
                                  f"(0x{_ROTATION_BITS:02x}; BGR comes from bgr), got {quote_token(setup.madctl)}")
            geometry = self.geometry(rotation)
            ram_w, ram_h = self.ram_size[::-1] if setup.exchanged else self.ram_size
            x, y = setup.offset
            if not (_is_int(x, 0, MAX_SIDE) and _is_int(y, 0, MAX_SIDE)
                    and x + geometry.width <= ram_w and y + geometry.height <= ram_h):
                raise ConfigError(f"{where}: rotation {rotation}: a {geometry.width}x{geometry.height} window at "
                                  f"offset {quote_token(setup.offset)} does not fit the {ram_w}x{ram_h} RAM")
        for step in self.init[:-1]:
            if step.command in _MIN_DELAY_MS and step.delay_ms < _MIN_DELAY_MS[step.command]:
                raise ConfigError(f"{where}: init step 0x{step.command:02x} needs >= {_MIN_DELAY_MS[step.command]} ms "
                                  f"before the next command (datasheet), got {step.delay_ms:g}")
        for step in self.init:
            if step.command == 0x3A and step.params and _COLMOD_FORMATS.get(step.params[0] & 7) != self.pixel_format:
                raise ConfigError(f"{where}: init sets COLMOD 0x{step.params[0]:02x}, which is not {self.pixel_format}")
            if step.command in (0x20, 0x21) and (step.command == 0x21) != self.invert:
                raise ConfigError(f"{where}: init sends {'INVON' if step.command == 0x21 else 'INVOFF'} "
                                  f"but invert is {str(self.invert).lower()}")

    def _check_oled(self, where: str) -> None:
        """SSD1306-family fields in range and agreeing with the init table's A8h, DAh, 8Dh, 81h steps."""
        if self.rotations:
            raise ConfigError(f"{where}: a {self.controller} rotates by segment remap and COM direction, not a "
                              "rotation table")
        width, height = self.size
        if height % 8 or width + self.column_offset > self.ram_size[0] or height > self.ram_size[1]:
            raise ConfigError(f"{where}: a {width}x{height} glass at column {self.column_offset} does not fit the "
                              f"{self.ram_size[0]}x{self.ram_size[1]} RAM in whole pages")
        if not _is_int(self.multiplex, max(16, height), 64):
            raise ConfigError(f"{where}: multiplex must be {max(16, height)}..64, got {quote_token(self.multiplex)}")
        if not _is_int(self.com_pins, 0, 255) or self.com_pins & ~0x30 != 0x02:
            raise ConfigError(f"{where}: com_pins must be the DAh parameter 0x02, 0x12, 0x22 or 0x32, "
                              f"got {quote_token(self.com_pins)}")
        if not (self.contrast is None or _is_int(self.contrast, 0, 255)):
            raise ConfigError(f"{where}: contrast must be 0..255, got {quote_token(self.contrast)}")
        if not (self.i2c_address is None or _is_i2c_address(self.i2c_address)):
            raise ConfigError(f"{where}: i2c_address must be 0x08..0x77, got {quote_token(self.i2c_address)}")
        expected = {0xA8: self.multiplex - 1, 0xDA: self.com_pins, 0x81: self.contrast,
                    0x8D: None if self.charge_pump is None else (0x14 if self.charge_pump else 0x10)}
        for step in self.init:
            want = expected.get(step.command)
            if want is not None and step.params[:1] != bytes([want]):
                raise ConfigError(f"{where}: init step 0x{step.command:02x} {step.params.hex(' ')} disagrees with "
                                  f"the profile's setting 0x{want:02x}")

    def geometry(self, rotation: int = 0) -> PanelGeometry:
        """The visible size, offsets and scan settings at ``rotation`` (SSD1306 family: 0 or 180 only)."""
        if rotation not in ROTATIONS:
            raise ConfigError(f"{self.name}: rotation must be 0, 90, 180 or 270, got {quote_token(rotation)}")
        width, height = self.size
        if self.oled:
            if rotation not in (0, 180):
                raise ConfigError(f"{self.name}: a {self.controller} rotates by 0 or 180 degrees only (segment remap "
                                  "and COM scan direction); rotate the image for 90 or 270")
            flip = rotation == 180
            return PanelGeometry(rotation, width, height, self.column_offset, 0,
                                 segment_remap=self.segment_remap != flip, com_reverse=self.com_reverse != flip)
        setup = self.rotations[rotation]
        if setup.exchanged:
            width, height = height, width
        madctl = setup.madctl | (MADCTL_BGR if self.bgr else 0)
        return PanelGeometry(rotation, width, height, setup.offset[0], setup.offset[1], madctl)

    def bus_clock(self, kind: str) -> float:
        """The default clock in Hz on a bus of ``kind`` ("spi" or "i2c"); ConfigError if the module has no such bus."""
        if kind not in self.clock_hz:
            raise ConfigError(f"{self.name}: a {self.controller} module is not driven over {kind} "
                              f"(buses: {', '.join(self.clock_hz)})")
        return float(self.clock_hz[kind])

    def check_clock(self, kind: str, hz: float) -> bool:
        """True when ``hz`` is within the datasheet's limit on ``kind``; logs a warning (never refuses) when not."""
        limit = self.max_clock_hz.get(kind)
        if limit is None or hz <= limit:
            return True
        log.warning("%s: %s clock %.4g MHz is above the %s datasheet limit of %.4g MHz (many modules still work)",
                    self.name, kind, hz / 1e6, self.controller, limit / 1e6)
        return False


_MIN_DELAY_MS = {0x01: 5, 0x11: 5}
"""MIPI DCS commands the controller needs time after: SWRESET and SLPOUT, 5 ms before the next command."""
_COLMOD_FORMATS = {value & 7: name for name, value in COLMOD.items()}
"""COLMOD's MCU-interface bits D[2:0] and the pixel format they select."""

# ---------------------------------------------------------------------------------------------------------------
# the TOML format

_KEYS = ("name", "description", "controller", "size", "ram_size", "pixel_format", "bgr", "invert", "te",
         "i2c_address", "clock_hz", "max_clock_hz", "rotation", "init", "init_file", "oled")
_ROTATION_KEYS = ("offset", "madctl")
_STEP_KEYS = ("command", "params", "delay_ms")
_OLED_KEYS = ("multiplex", "com_pins", "column_offset", "charge_pump", "contrast", "segment_remap", "com_reverse")
_BOOL = (lambda v: isinstance(v, bool), "true or false")
_BYTE = (lambda v: _is_int(v, 0, 255), "an integer 0..255")


def _size(t: Table, key: str) -> tuple[int, int]:
    """A required [width, height] key as a tuple."""
    value = t.get(key, pair_of(lambda v: _is_int(v, 1, MAX_SIDE)), f"a [width, height] pair of 1..{MAX_SIDE}",
                  required=True)
    return value[0], value[1]


def _clocks(t: Table, key: str) -> dict[str, float]:
    """A {spi = Hz, i2c = Hz} table."""
    sub = t.sub(key, BUS_KINDS)
    if sub is None:
        return {}
    return {k: float(sub.get(k, _is_clock, f"a clock in Hz, 0 < clock <= {MAX_CLOCK_HZ:g}")) for k in sub.data}


def _rotations(t: Table) -> dict[int, RotationSetup]:
    """The [rotation.N] tables."""
    sub = t.sub("rotation", tuple(str(r) for r in ROTATIONS))
    if sub is None:
        return {}
    out = {}
    for key in sub.data:
        r = sub.table(key, _ROTATION_KEYS)
        offset = r.get("offset", pair_of(lambda v: _is_int(v, 0, MAX_SIDE)), "an [x, y] pair of pixels", [0, 0])
        out[int(key)] = RotationSetup((offset[0], offset[1]), r.get("madctl", *_BYTE, required=True))
    return out


def _steps(t: Table) -> list[InitStep]:
    """The inline ``init`` array of {command, params, delay_ms} tables."""
    value = t.get("init", lambda v: isinstance(v, list), "an array of {command, params, delay_ms} tables")
    if len(value) > MAX_INIT_STEPS:
        raise t.fail("init", f"expected at most {MAX_INIT_STEPS} steps, found {len(value)}")
    steps = []
    for i, item in enumerate(value):
        s = Table(item, t.source, f"init[{i}]", _STEP_KEYS)
        params = s.get("params", lambda v: isinstance(v, list) and len(v) <= MAX_PARAMS and all(_BYTE[0](b) for b in v),
                       f"an array of at most {MAX_PARAMS} bytes 0..255", [])
        delay = s.get("delay_ms", lambda v: isinstance(v, (int, float)) and not isinstance(v, bool)
                      and 0 <= v <= MAX_DELAY_MS, f"milliseconds 0..{MAX_DELAY_MS:g}", 0)
        steps.append(InitStep(s.get("command", *_BYTE, required=True), bytes(params), float(delay)))
    return steps


def _init_file(t: Table, folder: Traversable | None) -> list[InitStep]:
    """The steps of the panel-mipi-dbi file named by ``init_file`` (relative to the profile's folder)."""
    from pixelpen.profiles import mipidbi

    name = t.get("init_file", lambda v: isinstance(v, str) and v.strip() != "", "a file name")
    file = check_path(name, "init_file").expanduser()
    if file.is_absolute():
        target: Traversable = file
    elif folder is None:
        raise t.fail("init_file", "expected an absolute name (this profile was not read from a file)", name)
    else:
        target = folder.joinpath(name)
    if not target.is_file():
        raise t.fail("init_file", "expected an existing panel-mipi-dbi file", name)
    with target.open("rb") as stream:
        data = stream.read(mipidbi.MAX_BYTES + 1)
    return mipidbi.read_mipi_dbi(data, source=str(target))


def _profile(data: dict[str, Any], source: str, folder: Traversable | None) -> PanelProfile:
    """A whole panel profile document as a PanelProfile."""
    t = Table(data, source, "", _KEYS)
    controller = t.get("controller", one_of(CONTROLLERS), "one of " + ", ".join(CONTROLLERS), required=True)
    if ("init" in t.data) == ("init_file" in t.data):
        raise ConfigError(f"{source}: give the init table inline ('init') or as a panel-mipi-dbi file ('init_file'), "
                          "exactly one of them")
    steps = _steps(t) if "init" in t.data else _init_file(t, folder)
    oled_t = t.sub("oled", _OLED_KEYS)
    oled: dict[str, Any] = {}
    if oled_t is not None:
        oled = {
            "multiplex": oled_t.get("multiplex", lambda v: _is_int(v, 16, 64), "an integer 16..64"),
            "com_pins": oled_t.get("com_pins", *_BYTE),
            "column_offset": oled_t.get("column_offset", lambda v: _is_int(v, 0, MAX_SIDE), "a column >= 0", 0),
            "charge_pump": oled_t.get("charge_pump", *_BOOL),
            "contrast": oled_t.get("contrast", *_BYTE),
            "segment_remap": oled_t.get("segment_remap", *_BOOL, True),
            "com_reverse": oled_t.get("com_reverse", *_BOOL, True),
        }
    size = _size(t, "size")
    return PanelProfile(
        name=t.get("name", lambda v: isinstance(v, str) and re.fullmatch(r"[a-z0-9_]{1,64}", v) is not None,
                   "a name of 1..64 characters a-z 0-9 _", required=True),
        description=t.get("description", lambda v: isinstance(v, str), "a string", ""),
        controller=controller,
        size=size,
        ram_size=_size(t, "ram_size") if "ram_size" in t.data else size,
        pixel_format=t.get("pixel_format", one_of(PIXEL_FORMATS), "one of " + ", ".join(PIXEL_FORMATS),
                           "mono-pages" if controller in OLED_CONTROLLERS else "rgb565be"),
        bgr=t.get("bgr", *_BOOL, False),
        invert=t.get("invert", *_BOOL, False),
        te=t.get("te", *_BOOL, False),
        i2c_address=t.get("i2c_address", _is_i2c_address, "an I2C address 0x08..0x77"),
        clock_hz=_clocks(t, "clock_hz"),
        max_clock_hz=_clocks(t, "max_clock_hz"),
        rotations=_rotations(t),
        init=tuple(steps),
        source=source,
        **oled,
    )


def read_panel_profile(text: str, source: str, folder: Traversable | None = None) -> PanelProfile:
    """A panel profile from TOML text (``folder``: where a relative ``init_file`` is looked for)."""
    return _profile(read_text(text, source, max_bytes=MAX_BYTES, max_depth=MAX_DEPTH), source, folder)


def _read_path(path: Path) -> PanelProfile:
    """A panel profile file; errors name it."""
    tables = read_file(path, max_bytes=MAX_BYTES, max_depth=MAX_DEPTH, what="panel profile")
    return _profile(tables, str(path), path.parent)


@functools.lru_cache(maxsize=1)
def _builtins() -> tuple[PanelProfile, ...]:
    """The shipped profiles, read once."""
    folder = resources.files("pixelpen").joinpath("data").joinpath("panels")
    out = []
    for entry in sorted(folder.iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".toml"):
            source = f"pixelpen/data/panels/{entry.name}"
            out.append(_profile(read_toml(entry.read_text(encoding="utf-8"), source, max_depth=MAX_DEPTH),
                                source, folder))
    return tuple(out)


def builtin_panel_profiles() -> dict[str, PanelProfile]:
    """Every panel profile shipped in ``pixelpen/data/panels``, by name."""
    return {p.name: p for p in _builtins()}


def panel_profile_for(controller: str, size: tuple[int, int]) -> PanelProfile:
    """The built-in profile of ``controller`` whose glass is ``size`` (either orientation: 320x240 finds 240x320)."""
    w, h = size
    found = [p for p in _builtins() if p.controller == controller and p.size in ((w, h), (h, w))]
    if found:
        return found[0]
    known = sorted(f"{p.size[0]}x{p.size[1]}" for p in _builtins() if p.controller == controller)
    if not known:
        raise ConfigError(f"no built-in panel profile for controller {quote_token(controller)} "
                          f"(controllers: {', '.join(CONTROLLERS)})")
    raise ConfigError(f"no built-in {controller} profile of size {w}x{h} (known sizes: {', '.join(known)}); "
                      "give profile=FILE.toml for another module")


_NAME = re.compile(r"^([a-z0-9]+)_(\d{1,4})x(\d{1,4})$")


def load_panel_profile(name_or_path: str | Path) -> PanelProfile:
    """A built-in panel profile by name (``st7789_240x240``; ``ili9341_320x240`` finds 240x320) or a TOML file."""
    path = profile_file(name_or_path, "panel profile")
    if path is not None:
        return _read_path(path)
    text = str(name_or_path)
    builtins = builtin_panel_profiles()
    key = profile_key(text)
    if key in builtins:
        return builtins[key]
    match = _NAME.match(key)
    if match and match[1] in CONTROLLERS:
        return panel_profile_for(match[1], (int(match[2]), int(match[3])))
    raise ConfigError(f"unknown panel profile {quote_token(text)}: not a file, nor one of "
                      f"{', '.join(sorted(builtins))}")

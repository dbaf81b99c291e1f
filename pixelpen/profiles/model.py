"""Device profiles as data: units, paper limits, pens, link, servo and motion limits of each plotter model.

Every value is checked when a profile is made, and the readers (:mod:`pixelpen.profiles.toml`,
:mod:`pixelpen.profiles.vpype`) check with the same rules. Limits (module attributes, read at call time by
the classes and the readers: assign to override):

* :data:`MAX_BYTES` -- bytes of a profile or vpype configuration file (1 MiB);
* :data:`MAX_DEPTH` -- nesting of arrays and inline tables (32; profiles need 2);
* :data:`MAX_PENS` -- pens of one device (1000; carousels hold 6 to 8);
* :data:`MAX_PAPERS` -- papers of one device, and devices in one vpype file (1000);
* :data:`MAX_VALUE` -- magnitude of any number: device units, speeds, times, baud rates (1e9);
* :data:`MIN_UNIT_MM` -- smallest device unit (1e-6 mm).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypeGuard

import numpy as np

from pixelpen.errors import ConfigError, quote_token

if TYPE_CHECKING:  # the readers, re-exported lazily below for importers from before the split
    from pixelpen.profiles.toml import builtin_profiles, load_profile
    from pixelpen.profiles.vpype import load_vpype_config, parse_length_mm

MAX_BYTES = 1 << 20
"""Bytes of a profile or vpype configuration file."""
MAX_DEPTH = 32
"""Nesting of arrays and inline tables."""
MAX_PENS = 1000
"""Pens of one device."""
MAX_PAPERS = 1000
"""Papers of one device; devices of one vpype file."""
MAX_VALUE = 1e9
"""Magnitude of any number in a profile."""
MIN_UNIT_MM = 1e-6
"""Smallest device unit in millimetres."""

__all__ = [
    "PROTOCOLS",
    "DeviceProfile",
    "LinkSettings",
    "MotionLimits",
    "Paper",
    "ServoSettings",
    "builtin_profiles",
    "load_profile",
    "load_vpype_config",
    "parse_length_mm",
]

PROTOCOLS = ("hpgl", "ebb", "grbl", "other")
"""Command languages a profile may name."""
ORIGINS = ("lower-left", "upper-left", "centre")
"""Where a device's origin sits on its plotting area."""
REFERENCES = ("topleft", "botleft")
"""Corners of the sheet a paper's ``origin_mm`` is measured from."""


def is_number(v: object) -> TypeGuard[int | float]:
    """A finite number of magnitude <= MAX_VALUE (a huge TOML integer is refused before float() overflows)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and -MAX_VALUE <= v <= MAX_VALUE


def is_positive(v: object) -> bool:
    """A number (as :func:`is_number`) > 0."""
    return is_number(v) and v > 0


def is_non_negative(v: object) -> bool:
    """A number (as :func:`is_number`) >= 0."""
    return is_number(v) and v >= 0


def is_integer(v: object) -> TypeGuard[int]:
    """An integer (not a bool) of magnitude <= MAX_VALUE."""
    return isinstance(v, int) and not isinstance(v, bool) and -MAX_VALUE <= v <= MAX_VALUE


def is_pen_count(v: object) -> bool:
    """An integer 1..MAX_PENS."""
    return is_integer(v) and 1 <= v <= MAX_PENS


@dataclass(frozen=True)
class MotionLimits:
    """Speed (mm/s), acceleration (mm/s²) and junction deviation ``cornering`` (mm) of one kind of move."""

    speed: float
    accel: float
    cornering: float = 0.0

    def __post_init__(self) -> None:
        for name in ("speed", "accel"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ConfigError(f"MotionLimits.{name} must be a finite number > 0, got {value!r}")
        if not isinstance(self.cornering, (int, float)) or not math.isfinite(self.cornering) or self.cornering < 0:
            raise ConfigError(f"MotionLimits.cornering must be a finite number >= 0, got {self.cornering!r}")

    def move_time(self, distance: float) -> float:
        """Seconds for a rest-to-rest straight move of ``distance`` mm (trapezoid, or triangle when short)."""
        v, a = self.speed, self.accel
        if distance >= v * v / a:
            return distance / v + v / a
        return 2.0 * math.sqrt(max(distance, 0.0) / a)

    def move_times(self, distances: np.ndarray) -> np.ndarray:
        """Vectorised :meth:`move_time` over an array of distances (mm)."""
        d = np.maximum(np.asarray(distances, dtype=np.float64), 0.0)
        v, a = self.speed, self.accel
        result: np.ndarray = np.where(d >= v * v / a, d / v + v / a, 2.0 * np.sqrt(d / a))
        return result


@dataclass(frozen=True)
class Paper:
    """One paper size of a device: hard-clip limits in device units and where the device origin sits on the sheet."""

    name: str
    x_range: tuple[int, int]
    y_range: tuple[int, int]
    size_mm: tuple[float, float] | None = None
    origin_mm: tuple[float, float] | None = None
    origin_reference: str = "topleft"
    orientation: str | None = None
    rotate_180: bool = False
    set_ps: int | None = None
    park: tuple[int, int] | None = None
    aliases: tuple[str, ...] = ()
    info: str = ""
    y_up: bool | None = None
    """Y axis direction on this paper when it differs from the profile's (vpype states it per paper)."""

    @property
    def width_units(self) -> int:
        """Width of the plottable area in device units."""
        return self.x_range[1] - self.x_range[0]

    @property
    def height_units(self) -> int:
        """Height of the plottable area in device units."""
        return self.y_range[1] - self.y_range[0]


@dataclass(frozen=True)
class LinkSettings:
    """Serial link defaults (pyserial names) and device buffer size; USB ids where the device has them."""

    baudrate: int = 9600
    bytesize: int = 8
    parity: str = "N"
    stopbits: float = 1
    xonxoff: bool = False
    rtscts: bool = False
    dsrdtr: bool = False
    timeout_s: float = 8.0
    buffer_bytes: int | None = None
    usb_vid: int | None = None
    usb_pid: int | None = None


@dataclass(frozen=True)
class ServoSettings:
    """Pen servo: EBB pulse limits (83.3 ns units) and up/down positions (%), or G-code lines for a GRBL pen."""

    min: int | None = None
    max: int | None = None
    up_percent: float | None = None
    down_percent: float | None = None
    up_command: str | None = None
    down_command: str | None = None


@dataclass(frozen=True)
class DeviceProfile:
    """Everything pixelpen knows about one plotter model; distances in device units unless named ``_mm``."""

    name: str
    unit_mm: float
    pen_down: MotionLimits
    pen_up: MotionLimits
    description: str = ""
    protocol: str = "other"
    origin: str = "lower-left"
    y_up: bool = True
    home: tuple[float, float] = (0.0, 0.0)
    pens: int = 1
    pen_colours: Mapping[int, str] = field(default_factory=dict)
    pen_width_mm: float = 0.3
    pen_lift_s: float = 0.0
    pen_drop_s: float = 0.0
    pen_change_s: float = 0.0
    papers: Mapping[str, Paper] = field(default_factory=dict)
    default_paper: str | None = None
    steps_per_mm: float | None = None
    link: LinkSettings | None = None
    servo: ServoSettings | None = None
    source: str = ""

    def __post_init__(self) -> None:
        where = f"profile {self.name!r}" + (f" ({self.source})" if self.source else "")
        if not (is_positive(self.unit_mm) and self.unit_mm >= MIN_UNIT_MM):
            raise ConfigError(f"{where}: unit_mm must be a number >= {MIN_UNIT_MM:g}, got {quote_token(self.unit_mm)}")
        if not isinstance(self.pen_down, MotionLimits) or not isinstance(self.pen_up, MotionLimits):
            raise ConfigError(f"{where}: pen_down and pen_up must be MotionLimits")
        if not is_pen_count(self.pens):
            raise ConfigError(f"{where}: pens must be an integer 1..{MAX_PENS}, got {quote_token(self.pens)}")
        if len(self.papers) > MAX_PAPERS:
            raise ConfigError(f"{where}: {len(self.papers)} papers, more than {MAX_PAPERS}")
        for key in ("pen_lift_s", "pen_drop_s", "pen_change_s"):
            if not is_non_negative(getattr(self, key)):
                raise ConfigError(f"{where}: {key} must be a number >= 0, got {quote_token(getattr(self, key))}")

    def paper(self, name: str | None = None) -> Paper:
        """The paper called ``name`` (or one of its aliases, any case); the default paper when ``name`` is None."""
        if name is None:
            if self.default_paper is None:
                raise ConfigError(f"profile {self.name}: no paper named and no default_paper")
            name = self.default_paper
        want = name.lower()
        for paper in self.papers.values():
            if paper.name.lower() == want or want in (a.lower() for a in paper.aliases):
                return paper
        known = ", ".join(sorted(self.papers)) or "none"
        raise ConfigError(f"profile {self.name}: unknown paper {name!r} (known: {known})")


_READERS = {"builtin_profiles": "toml", "load_profile": "toml", "load_vpype_config": "vpype",
            "parse_length_mm": "vpype"}
"""Reader functions that lived here before the split, by the module that holds them now."""


def __getattr__(name: str) -> object:
    """The readers, for ``from pixelpen.profiles.model import load_profile`` (imported on first use: no cycle)."""
    module = _READERS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(f"pixelpen.profiles.{module}"), name)

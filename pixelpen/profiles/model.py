"""Device profiles as data: units, paper limits, pens, motion limits and timing of each plotter model (TOML).

Every value is checked and an error names the file and the key. Limits (module attributes, read at
call time: assign to override):

* :data:`MAX_BYTES` -- bytes of a profile or vpype configuration file (1 MiB);
* :data:`MAX_DEPTH` -- nesting of arrays and inline tables (32; profiles need 2);
* :data:`MAX_PENS` -- pens of one device (1000; carousels hold 6 to 8);
* :data:`MAX_PAPERS` -- papers of one device, and devices in one vpype file (1000);
* :data:`MAX_VALUE` -- magnitude of any number: device units, speeds, times, baud rates (1e9);
* :data:`MIN_UNIT_MM` -- smallest device unit (1e-6 mm).

TOML integers longer than Python's 4300-digit limit and files nested too deep are ParseErrors.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any

from pixelpen.errors import ConfigError, ParseError, quote_token
from pixelpen.tomltext import read_toml
from pixelpen.urls import check_path
from pixelpen.vector.motion import MotionLimits

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
    "DeviceProfile",
    "LinkSettings",
    "Paper",
    "ServoSettings",
    "builtin_profiles",
    "load_profile",
    "load_vpype_config",
    "parse_length_mm",
]

PROTOCOLS = ("hpgl", "ebb", "grbl", "other")
ORIGINS = ("lower-left", "upper-left", "centre")
_REFERENCES = ("topleft", "botleft")
_COLOUR = re.compile(r"^#[0-9a-fA-F]{6}$")


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
        if not (_positive(self.unit_mm) and self.unit_mm >= MIN_UNIT_MM):
            raise ConfigError(f"{where}: unit_mm must be a number >= {MIN_UNIT_MM:g}, got {quote_token(self.unit_mm)}")
        if not isinstance(self.pen_down, MotionLimits) or not isinstance(self.pen_up, MotionLimits):
            raise ConfigError(f"{where}: pen_down and pen_up must be MotionLimits")
        if not _pen_count(self.pens):
            raise ConfigError(f"{where}: pens must be an integer 1..{MAX_PENS}, got {quote_token(self.pens)}")
        if len(self.papers) > MAX_PAPERS:
            raise ConfigError(f"{where}: {len(self.papers)} papers, more than {MAX_PAPERS}")
        for key in ("pen_lift_s", "pen_drop_s", "pen_change_s"):
            if not _non_negative(getattr(self, key)):
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


# ---------------------------------------------------------------------------------------------------------------
# strict reading of TOML tables: every key known, every value of the right type, errors name file and key


class _Table:
    """A TOML table being read: rejects keys outside ``keys`` at once, then hands out typed values by dotted path."""

    def __init__(self, data: Any, source: str, path: str, keys: tuple[str, ...] | None) -> None:
        self.data, self.source, self.path = data, source, path
        if not isinstance(data, dict):
            raise ConfigError(f"{source}: key '{path}': expected a table, found {_kind(data)}")
        if keys is not None:
            extra = [k for k in data if k not in keys]
            if extra:
                raise ConfigError(f"{source}: unknown key '{self.key(extra[0][:80])}' (known: {', '.join(keys)})")

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def fail(self, name: str, what: str, value: Any = None) -> ConfigError:
        found = "" if value is None else f", found {_kind(value)} {quote_token(value)}"
        return ConfigError(f"{self.source}: key '{self.key(name)}': {what}{found}")

    def get(self, name: str, check: Callable[[Any], bool], what: str, default: Any = None,
            required: bool = False) -> Any:
        if name not in self.data:
            if required:
                raise ConfigError(f"{self.source}: missing key '{self.key(name)}' ({what})")
            return default
        value = self.data[name]
        if not check(value):
            raise self.fail(name, f"expected {what}", value)
        return value

    def sub(self, name: str, keys: tuple[str, ...] | None, required: bool = False) -> _Table | None:
        if name not in self.data:
            if required:
                raise ConfigError(f"{self.source}: missing table '{self.key(name)}'")
            return None
        return _Table(self.data[name], self.source, self.key(name), keys)


_PROFILE_KEYS = ("name", "description", "protocol", "unit_mm", "origin", "y_up", "home", "pens", "pen_colours",
                 "pen_width_mm", "pen_down", "pen_up", "pen_lift_s", "pen_drop_s", "pen_change_s", "paper",
                 "default_paper", "steps_per_mm", "link", "servo")
_MOTION_KEYS = ("speed", "accel", "cornering")
_PAPER_KEYS = ("x_range", "y_range", "size_mm", "origin_mm", "origin_reference", "orientation", "rotate_180",
               "set_ps", "park", "aliases", "info")
_LINK_KEYS = ("baudrate", "bytesize", "parity", "stopbits", "xonxoff", "rtscts", "dsrdtr", "timeout_s",
              "buffer_bytes", "usb_vid", "usb_pid")
_SERVO_KEYS = ("min", "max", "up_percent", "down_percent", "up_command", "down_command")
_VPYPE_DEVICE_KEYS = ("name", "plotter_unit_length", "unit", "pen_count", "info", "paper")
_VPYPE_PAPER_KEYS = ("name", "aka_names", "info", "paper_size", "x_range", "y_range", "y_axis_up", "origin_location",
                     "origin_location_reference", "paper_orientation", "rotate_180", "set_ps", "final_pu_params")


def _kind(value: Any) -> str:
    return {bool: "boolean", int: "integer", float: "number", str: "string", list: "array", dict: "table"}.get(
        type(value), type(value).__name__
    )


def _is_num(v: Any) -> bool:
    """A finite number of magnitude <= MAX_VALUE (a huge TOML integer is refused before float() overflows)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and -MAX_VALUE <= v <= MAX_VALUE


def _positive(v: Any) -> bool:
    return _is_num(v) and v > 0


def _non_negative(v: Any) -> bool:
    return _is_num(v) and v >= 0


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and -MAX_VALUE <= v <= MAX_VALUE


def _pen_count(v: Any) -> bool:
    return _is_int(v) and 1 <= v <= MAX_PENS


def _pair(check: Callable[[Any], bool]) -> Callable[[Any], bool]:
    return lambda v: isinstance(v, list) and len(v) == 2 and all(check(x) for x in v)


def _range(v: Any) -> bool:
    return _pair(_is_int)(v) and v[0] < v[1]


def _is_colour(v: Any) -> bool:
    return isinstance(v, str) and _COLOUR.match(v) is not None


def _one_of(options: tuple) -> Callable[[Any], bool]:
    return lambda v: v in options


def _motion(t: _Table) -> MotionLimits:
    return MotionLimits(
        speed=float(t.get("speed", _positive, "a speed in mm/s > 0", required=True)),
        accel=float(t.get("accel", _positive, "an acceleration in mm/s² > 0", required=True)),
        cornering=float(t.get("cornering", _non_negative, "a junction deviation in mm >= 0", 0.0)),
    )


def _floats(value: Any) -> tuple[float, ...] | None:
    return None if value is None else tuple(float(x) for x in value)


def _paper(name: str, t: _Table) -> Paper:
    park = t.get("park", _pair(_is_int), "a [x, y] pair of integers", None)
    return Paper(
        name=name,
        x_range=tuple(t.get("x_range", _range, "a [low, high] pair of integers, low < high", required=True)),
        y_range=tuple(t.get("y_range", _range, "a [low, high] pair of integers, low < high", required=True)),
        size_mm=_floats(t.get("size_mm", _pair(_non_negative), "a [width, height] pair of millimetres")),
        origin_mm=_floats(t.get("origin_mm", _pair(_non_negative), "an [x, y] pair of millimetres")),
        origin_reference=t.get("origin_reference", _one_of(_REFERENCES), "'topleft' or 'botleft'", "topleft"),
        orientation=t.get("orientation", _one_of(("portrait", "landscape")), "'portrait' or 'landscape'", None),
        rotate_180=t.get("rotate_180", lambda v: isinstance(v, bool), "true or false", False),
        set_ps=t.get("set_ps", _is_int, "an integer", None),
        park=None if park is None else tuple(park),
        aliases=tuple(t.get("aliases", lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v),
                            "an array of strings", [])),
        info=t.get("info", lambda v: isinstance(v, str), "a string", ""),
    )


def _link(t: _Table) -> LinkSettings:
    opt_int = lambda key: t.get(key, lambda v: _is_int(v) and v >= 0, "an integer >= 0", None)
    return LinkSettings(
        baudrate=t.get("baudrate", lambda v: _is_int(v) and v > 0, "an integer baud rate > 0", 9600),
        bytesize=t.get("bytesize", _one_of((5, 6, 7, 8)), "5, 6, 7 or 8", 8),
        parity=t.get("parity", _one_of(("N", "E", "O", "M", "S")), "one of N, E, O, M, S", "N"),
        stopbits=t.get("stopbits", lambda v: _is_num(v) and v in (1, 1.5, 2), "1, 1.5 or 2", 1),
        xonxoff=t.get("xonxoff", lambda v: isinstance(v, bool), "true or false", False),
        rtscts=t.get("rtscts", lambda v: isinstance(v, bool), "true or false", False),
        dsrdtr=t.get("dsrdtr", lambda v: isinstance(v, bool), "true or false", False),
        timeout_s=float(t.get("timeout_s", _positive, "seconds > 0", 8.0)),
        buffer_bytes=t.get("buffer_bytes", lambda v: _is_int(v) and v > 0, "an integer > 0", None),
        usb_vid=opt_int("usb_vid"),
        usb_pid=opt_int("usb_pid"),
    )


def _servo(t: _Table) -> ServoSettings:
    percent = lambda v: _is_num(v) and 0 <= v <= 100
    return ServoSettings(
        min=t.get("min", lambda v: _is_int(v) and v >= 0, "an integer >= 0", None),
        max=t.get("max", lambda v: _is_int(v) and v >= 0, "an integer >= 0", None),
        up_percent=t.get("up_percent", percent, "a percentage 0..100", None),
        down_percent=t.get("down_percent", percent, "a percentage 0..100", None),
        up_command=t.get("up_command", lambda v: isinstance(v, str), "a string", None),
        down_command=t.get("down_command", lambda v: isinstance(v, str), "a string", None),
    )


def _profile(data: dict, source: str) -> DeviceProfile:
    t = _Table(data, source, "", _PROFILE_KEYS)
    text = lambda v: isinstance(v, str)
    name = t.get("name", lambda v: isinstance(v, str) and v.strip() != "", "a non-empty string", required=True)
    pens = t.get("pens", _pen_count, f"an integer 1..{MAX_PENS}", 1)
    colours = t.get("pen_colours", lambda v: isinstance(v, list) and all(_is_colour(c) for c in v),
                    "an array of '#rrggbb' strings", [])
    if len(colours) > pens:
        raise t.fail("pen_colours", f"expected at most {pens} colours (one per pen)", colours)
    papers_t = t.sub("paper", None)
    papers = {}
    if papers_t is not None:
        if len(papers_t.data) > MAX_PAPERS:
            raise t.fail("paper", f"expected at most {MAX_PAPERS} papers")
        for paper_name in papers_t.data:
            papers[paper_name] = _paper(paper_name, papers_t.sub(paper_name, _PAPER_KEYS))
    default_paper = t.get("default_paper", text, "a string", None)
    if default_paper is not None and default_paper not in papers:
        known = ", ".join(papers) or "none"
        raise t.fail("default_paper", f"expected one of the [paper] tables ({known})", default_paper)
    link_t, servo_t = t.sub("link", _LINK_KEYS), t.sub("servo", _SERVO_KEYS)
    return DeviceProfile(
        name=name,
        description=t.get("description", text, "a string", ""),
        protocol=t.get("protocol", _one_of(PROTOCOLS), "one of " + ", ".join(PROTOCOLS), "other"),
        unit_mm=float(t.get("unit_mm", lambda v: _positive(v) and v >= MIN_UNIT_MM, f"a unit size in mm >= {MIN_UNIT_MM:g}",
                            required=True)),
        origin=t.get("origin", _one_of(ORIGINS), "one of " + ", ".join(ORIGINS), "lower-left"),
        y_up=t.get("y_up", lambda v: isinstance(v, bool), "true or false", True),
        home=tuple(float(x) for x in t.get("home", _pair(_is_num), "an [x, y] pair of device units", [0, 0])),
        pens=pens,
        pen_colours={i + 1: c.lower() for i, c in enumerate(colours)},
        pen_width_mm=float(t.get("pen_width_mm", _positive, "a width in mm > 0", 0.3)),
        pen_down=_motion(t.sub("pen_down", _MOTION_KEYS, required=True)),
        pen_up=_motion(t.sub("pen_up", _MOTION_KEYS, required=True)),
        pen_lift_s=float(t.get("pen_lift_s", _non_negative, "seconds >= 0", 0.0)),
        pen_drop_s=float(t.get("pen_drop_s", _non_negative, "seconds >= 0", 0.0)),
        pen_change_s=float(t.get("pen_change_s", _non_negative, "seconds >= 0", 0.0)),
        papers=papers,
        default_paper=default_paper,
        steps_per_mm=t.get("steps_per_mm", _positive, "steps per mm > 0"),
        link=None if link_t is None else _link(link_t),
        servo=None if servo_t is None else _servo(servo_t),
        source=source,
    )


def _read_toml(text: str, source: str) -> dict:
    if len(text) > MAX_BYTES:
        raise ParseError(f"file of {len(text)} characters is larger than the {MAX_BYTES} allowed", source=source)
    return read_toml(text, source, max_depth=MAX_DEPTH)


def _read_file(path: Path) -> dict:
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise ParseError(f"file of {size} bytes is larger than the {MAX_BYTES} allowed", source=str(path))
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ParseError("profile is not UTF-8 text", source=str(path), offset=exc.start) from None
    except OSError as exc:
        raise ConfigError(f"cannot read profile {str(path)!r}: {exc.strerror or exc}") from None
    return _read_toml(text, str(path))


def _builtin_dir():
    return resources.files("pixelpen").joinpath("data", "profiles")


def builtin_profiles() -> dict[str, DeviceProfile]:
    """Every profile shipped in ``pixelpen/data/profiles``, by name."""
    out = {}
    for entry in sorted(_builtin_dir().iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".toml"):
            source = f"pixelpen/data/profiles/{entry.name}"
            profile = _profile(_read_toml(entry.read_text(encoding="utf-8"), source), source)
            out[profile.name] = profile
    return out


def load_profile(name_or_path: str | Path) -> DeviceProfile:
    """A built-in profile by name (``hp7475a``, ``axidraw_v3``, …) or a user profile from a TOML file path."""
    text = str(name_or_path)
    path = check_path(text, "profile file name").expanduser()
    if isinstance(name_or_path, Path) or text.endswith(".toml") or path.is_file():
        if not path.is_file():
            raise ConfigError(f"profile file {quote_token(text)} does not exist")
        return _profile(_read_file(path), str(path))
    builtins = builtin_profiles()
    key = text.strip().lower().replace("-", "_")
    if key in builtins:
        return builtins[key]
    raise ConfigError(f"unknown device profile {quote_token(text)}: not a file, nor one of {', '.join(sorted(builtins))}")


# ---------------------------------------------------------------------------------------------------------------
# vpype device configuration ([device.NAME] tables with [[device.NAME.paper]] entries)

_LENGTH_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "inch": 25.4, "ft": 304.8, "yd": 914.4,
              "px": 25.4 / 96.0, "pt": 25.4 / 72.0, "pc": 25.4 / 6.0, "": 25.4 / 96.0}
_XY = re.compile(r"\s*-?\d{1,9}\s*,\s*-?\d{1,9}\s*")
_LENGTH_RE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([a-zA-Z]*)\s*$")


def parse_length_mm(value: Any) -> float:
    """A vpype length in mm: a number (CSS pixels, 1/96 in) or a string with a unit (``"297mm"``, ``"11in"``)."""
    if _is_num(value):
        return float(value) * _LENGTH_MM["px"]
    if isinstance(value, str) and len(value) <= 100:
        m = _LENGTH_RE.match(value)
        if m and m[2].lower() in _LENGTH_MM and abs(float(m[1])) <= MAX_VALUE:
            return float(m[1]) * _LENGTH_MM[m[2].lower()]
    raise ValueError(f"not a length: {quote_token(value)}")


def _is_length(v: Any) -> bool:
    try:
        parse_length_mm(v)
    except ValueError:
        return False
    return True


_LENGTH_WHAT = "a length (a number of px, or a string such as '0.025mm')"


def _vpype_paper(t: _Table) -> Paper:
    length_pair = lambda v: isinstance(v, list) and len(v) == 2 and all(_is_length(x) for x in v)
    name = t.get("name", lambda v: isinstance(v, str) and v != "", "a non-empty string", required=True)
    size = t.get("paper_size", length_pair, "a [width, height] pair of lengths", None)
    origin = t.get("origin_location", length_pair, "an [x, y] pair of lengths", required=True)
    park = t.get("final_pu_params", lambda v: isinstance(v, str) and _XY.fullmatch(v) is not None,
                 "a string 'x,y' of integers", None)
    y_up = t.get("y_axis_up", lambda v: isinstance(v, bool), "true or false", required=True)
    x_range = t.get("x_range", _range, "a [low, high] pair of integers, low < high", None)
    y_range = t.get("y_range", _range, "a [low, high] pair of integers, low < high", None)
    return Paper(
        name=name,
        x_range=tuple(x_range) if x_range else (-32768, 32767),
        y_range=tuple(y_range) if y_range else (-32768, 32767),
        size_mm=None if size is None else tuple(parse_length_mm(x) for x in size),
        origin_mm=tuple(parse_length_mm(x) for x in origin),
        origin_reference=t.get("origin_location_reference", _one_of(_REFERENCES), "'topleft' or 'botleft'", "topleft"),
        orientation=t.get("paper_orientation", _one_of(("portrait", "landscape")), "'portrait' or 'landscape'", None),
        rotate_180=t.get("rotate_180", lambda v: isinstance(v, bool), "true or false", False),
        set_ps=t.get("set_ps", _is_int, "an integer", None),
        park=None if park is None else tuple(int(x) for x in park.split(",")),
        aliases=tuple(t.get("aka_names", lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v),
                            "an array of strings", [])),
        info=t.get("info", lambda v: isinstance(v, str), "a string", ""),
        y_up=y_up,
    )


def load_vpype_config(path: str | Path, base: DeviceProfile | str = "hp7475a") -> dict[str, DeviceProfile]:
    """Devices of a vpype configuration file (``[device.NAME]``) as profiles, by table name.

    vpype states unit, pen count and papers; motion limits and pen timing, which vpype does not know,
    come from ``base`` (a profile or a profile name). Other top-level tables (``pen_config``, …) are ignored.
    """
    path = Path(path)
    source = str(path)
    base_profile = load_profile(base) if isinstance(base, (str, Path)) else base
    data = _read_file(path)
    devices = data.get("device", {})
    top = _Table(data, source, "", None)
    if not isinstance(devices, dict) or len(devices) > MAX_PAPERS:
        raise top.fail("device", f"expected a table of at most {MAX_PAPERS} devices", devices)
    out = {}
    for key, body in devices.items():
        t = _Table(body, source, f"device.{key}", _VPYPE_DEVICE_KEYS)
        name = t.get("name", lambda v: isinstance(v, str) and v != "", "a non-empty string", key)
        unit_key = "plotter_unit_length" if "plotter_unit_length" in t.data or "unit" not in t.data else "unit"
        unit = t.get(unit_key, _is_length, _LENGTH_WHAT, required=True)
        unit_mm = parse_length_mm(unit)
        if unit_mm <= 0:
            raise t.fail(unit_key, "expected a length > 0", unit)
        pens = t.get("pen_count", _pen_count, f"an integer 1..{MAX_PENS}", 1)
        t.get("info", lambda v: isinstance(v, str), "a string", "")  # checked, not kept
        papers_raw = t.get("paper", lambda v: isinstance(v, list) and len(v) <= MAX_PAPERS,
                           f"an array of at most {MAX_PAPERS} [[paper]] tables", [])
        papers = {}
        for i, entry in enumerate(papers_raw):
            paper = _vpype_paper(_Table(entry, source, f"device.{key}.paper[{i}]", _VPYPE_PAPER_KEYS))
            papers[paper.name] = paper
        y_ups = {p.y_up for p in papers.values()}
        out[key] = replace(
            base_profile,
            name=key,
            description=name,
            protocol="hpgl",
            unit_mm=unit_mm,
            pens=pens,
            pen_colours={k: v for k, v in base_profile.pen_colours.items() if k <= pens},
            y_up=y_ups.pop() if len(y_ups) == 1 else base_profile.y_up,
            papers=papers,
            default_paper=next(iter(papers), None),
            source=source,
        )
    return out

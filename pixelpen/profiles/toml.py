"""The TOML profile format: strict reading of tables (every key known, every value typed), built-in profiles.

Errors name the file and the dotted key. TOML integers longer than Python's 4300-digit limit and files nested
too deep are ParseErrors. Limits (:data:`~pixelpen.profiles.model.MAX_BYTES` and the others) are read from
:mod:`pixelpen.profiles.model` at call time.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from importlib import resources
from importlib.abc import Traversable
from pathlib import Path
from typing import Any

from pixelpen.errors import ConfigError, ParseError, quote_token
from pixelpen.profiles import model
from pixelpen.profiles.model import (
    ORIGINS,
    PROTOCOLS,
    REFERENCES,
    DeviceProfile,
    LinkSettings,
    MotionLimits,
    Paper,
    ServoSettings,
    is_integer,
    is_non_negative,
    is_number,
    is_pen_count,
    is_positive,
)
from pixelpen.tomltext import read_toml
from pixelpen.urls import check_path

__all__ = ["Table", "builtin_profiles", "load_profile", "profile_file", "profile_key", "read_file"]

_COLOUR = re.compile(r"^#[0-9a-fA-F]{6}$")

# ---------------------------------------------------------------------------------------------------------------
# strict reading of TOML tables: every key known, every value of the right type, errors name file and key


class Table:
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
        """The dotted path of ``name`` in this table."""
        return f"{self.path}.{name}" if self.path else name

    def fail(self, name: str, what: str, value: Any = None) -> ConfigError:
        """The error for key ``name``: what was expected and what was found."""
        found = "" if value is None else f", found {_kind(value)} {quote_token(value)}"
        return ConfigError(f"{self.source}: key '{self.key(name)}': {what}{found}")

    def get(self, name: str, check: Callable[[Any], bool], what: str, default: Any = None,
            required: bool = False) -> Any:
        """The value of key ``name`` if ``check`` passes (``default`` when absent, unless ``required``)."""
        if name not in self.data:
            if required:
                raise ConfigError(f"{self.source}: missing key '{self.key(name)}' ({what})")
            return default
        value = self.data[name]
        if not check(value):
            raise self.fail(name, f"expected {what}", value)
        return value

    def sub(self, name: str, keys: tuple[str, ...] | None) -> Table | None:
        """The table under ``name`` (its keys checked against ``keys``), None when absent."""
        return self.table(name, keys) if name in self.data else None

    def table(self, name: str, keys: tuple[str, ...] | None) -> Table:
        """The table under ``name``, which must be there."""
        if name not in self.data:
            raise ConfigError(f"{self.source}: missing table '{self.key(name)}'")
        return Table(self.data[name], self.source, self.key(name), keys)


_PROFILE_KEYS = ("name", "description", "protocol", "unit_mm", "origin", "y_up", "home", "pens", "pen_colours",
                 "pen_width_mm", "pen_down", "pen_up", "pen_lift_s", "pen_drop_s", "pen_change_s", "paper",
                 "default_paper", "steps_per_mm", "link", "servo")
_MOTION_KEYS = ("speed", "accel", "cornering")
_PAPER_KEYS = ("x_range", "y_range", "size_mm", "origin_mm", "origin_reference", "orientation", "rotate_180",
               "set_ps", "park", "aliases", "info")
_LINK_KEYS = ("baudrate", "bytesize", "parity", "stopbits", "xonxoff", "rtscts", "dsrdtr", "timeout_s",
              "buffer_bytes", "usb_vid", "usb_pid")
_SERVO_KEYS = ("min", "max", "up_percent", "down_percent", "up_command", "down_command")


def _kind(value: Any) -> str:
    """The TOML name of a value's type."""
    return {bool: "boolean", int: "integer", float: "number", str: "string", list: "array", dict: "table"}.get(
        type(value), type(value).__name__
    )


def pair_of(check: Callable[[Any], bool]) -> Callable[[Any], bool]:
    """A check for a two-item array whose items pass ``check``."""
    return lambda v: isinstance(v, list) and len(v) == 2 and all(check(x) for x in v)


def is_range(v: Any) -> bool:
    """A [low, high] pair of integers, low < high."""
    return pair_of(is_integer)(v) and v[0] < v[1]


def _is_colour(v: Any) -> bool:
    """A '#rrggbb' string."""
    return isinstance(v, str) and _COLOUR.match(v) is not None


def one_of(options: tuple[object, ...]) -> Callable[[Any], bool]:
    """A check for one of ``options``."""
    return lambda v: v in options


def _motion(t: Table) -> MotionLimits:
    """A [pen_down] or [pen_up] table as MotionLimits."""
    return MotionLimits(
        speed=float(t.get("speed", is_positive, "a speed in mm/s > 0", required=True)),
        accel=float(t.get("accel", is_positive, "an acceleration in mm/s² > 0", required=True)),
        cornering=float(t.get("cornering", is_non_negative, "a junction deviation in mm >= 0", 0.0)),
    )


def _floats(value: Any) -> tuple[float, float] | None:
    """A checked [x, y] pair as floats; None stays None."""
    return None if value is None else (float(value[0]), float(value[1]))


def _paper(name: str, t: Table) -> Paper:
    """A [paper.NAME] table as a Paper."""
    park = t.get("park", pair_of(is_integer), "a [x, y] pair of integers", None)
    return Paper(
        name=name,
        x_range=tuple(t.get("x_range", is_range, "a [low, high] pair of integers, low < high", required=True)),
        y_range=tuple(t.get("y_range", is_range, "a [low, high] pair of integers, low < high", required=True)),
        size_mm=_floats(t.get("size_mm", pair_of(is_non_negative), "a [width, height] pair of millimetres")),
        origin_mm=_floats(t.get("origin_mm", pair_of(is_non_negative), "an [x, y] pair of millimetres")),
        origin_reference=t.get("origin_reference", one_of(REFERENCES), "'topleft' or 'botleft'", "topleft"),
        orientation=t.get("orientation", one_of(("portrait", "landscape")), "'portrait' or 'landscape'", None),
        rotate_180=t.get("rotate_180", lambda v: isinstance(v, bool), "true or false", False),
        set_ps=t.get("set_ps", is_integer, "an integer", None),
        park=None if park is None else (park[0], park[1]),
        aliases=tuple(t.get("aliases", lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v),
                            "an array of strings", [])),
        info=t.get("info", lambda v: isinstance(v, str), "a string", ""),
    )


def _link(t: Table) -> LinkSettings:
    """A [link] table as LinkSettings."""
    def opt_int(key: str) -> int | None:
        """An optional integer >= 0."""
        value: int | None = t.get(key, lambda v: is_integer(v) and v >= 0, "an integer >= 0", None)
        return value

    return LinkSettings(
        baudrate=t.get("baudrate", lambda v: is_integer(v) and v > 0, "an integer baud rate > 0", 9600),
        bytesize=t.get("bytesize", one_of((5, 6, 7, 8)), "5, 6, 7 or 8", 8),
        parity=t.get("parity", one_of(("N", "E", "O", "M", "S")), "one of N, E, O, M, S", "N"),
        stopbits=t.get("stopbits", lambda v: is_number(v) and v in (1, 1.5, 2), "1, 1.5 or 2", 1),
        xonxoff=t.get("xonxoff", lambda v: isinstance(v, bool), "true or false", False),
        rtscts=t.get("rtscts", lambda v: isinstance(v, bool), "true or false", False),
        dsrdtr=t.get("dsrdtr", lambda v: isinstance(v, bool), "true or false", False),
        timeout_s=float(t.get("timeout_s", is_positive, "seconds > 0", 8.0)),
        buffer_bytes=t.get("buffer_bytes", lambda v: is_integer(v) and v > 0, "an integer > 0", None),
        usb_vid=opt_int("usb_vid"),
        usb_pid=opt_int("usb_pid"),
    )


def _servo(t: Table) -> ServoSettings:
    """A [servo] table as ServoSettings."""
    percent = lambda v: is_number(v) and 0 <= v <= 100
    return ServoSettings(
        min=t.get("min", lambda v: is_integer(v) and v >= 0, "an integer >= 0", None),
        max=t.get("max", lambda v: is_integer(v) and v >= 0, "an integer >= 0", None),
        up_percent=t.get("up_percent", percent, "a percentage 0..100", None),
        down_percent=t.get("down_percent", percent, "a percentage 0..100", None),
        up_command=t.get("up_command", lambda v: isinstance(v, str), "a string", None),
        down_command=t.get("down_command", lambda v: isinstance(v, str), "a string", None),
    )


def _profile(data: dict[str, Any], source: str) -> DeviceProfile:
    """A whole profile document as a DeviceProfile."""
    t = Table(data, source, "", _PROFILE_KEYS)
    text = lambda v: isinstance(v, str)
    name = t.get("name", lambda v: isinstance(v, str) and v.strip() != "", "a non-empty string", required=True)
    pens = t.get("pens", is_pen_count, f"an integer 1..{model.MAX_PENS}", 1)
    colours = t.get("pen_colours", lambda v: isinstance(v, list) and all(_is_colour(c) for c in v),
                    "an array of '#rrggbb' strings", [])
    if len(colours) > pens:
        raise t.fail("pen_colours", f"expected at most {pens} colours (one per pen)", colours)
    papers_t = t.sub("paper", None)
    papers = {}
    if papers_t is not None:
        if len(papers_t.data) > model.MAX_PAPERS:
            raise t.fail("paper", f"expected at most {model.MAX_PAPERS} papers")
        for paper_name in papers_t.data:
            papers[paper_name] = _paper(paper_name, papers_t.table(paper_name, _PAPER_KEYS))
    default_paper = t.get("default_paper", text, "a string", None)
    if default_paper is not None and default_paper not in papers:
        known = ", ".join(papers) or "none"
        raise t.fail("default_paper", f"expected one of the [paper] tables ({known})", default_paper)
    link_t, servo_t = t.sub("link", _LINK_KEYS), t.sub("servo", _SERVO_KEYS)
    home = t.get("home", pair_of(is_number), "an [x, y] pair of device units", [0, 0])
    return DeviceProfile(
        name=name,
        description=t.get("description", text, "a string", ""),
        protocol=t.get("protocol", one_of(PROTOCOLS), "one of " + ", ".join(PROTOCOLS), "other"),
        unit_mm=float(t.get("unit_mm", lambda v: is_positive(v) and v >= model.MIN_UNIT_MM,
                            f"a unit size in mm >= {model.MIN_UNIT_MM:g}", required=True)),
        origin=t.get("origin", one_of(ORIGINS), "one of " + ", ".join(ORIGINS), "lower-left"),
        y_up=t.get("y_up", lambda v: isinstance(v, bool), "true or false", True),
        home=(float(home[0]), float(home[1])),
        pens=pens,
        pen_colours={i + 1: c.lower() for i, c in enumerate(colours)},
        pen_width_mm=float(t.get("pen_width_mm", is_positive, "a width in mm > 0", 0.3)),
        pen_down=_motion(t.table("pen_down", _MOTION_KEYS)),
        pen_up=_motion(t.table("pen_up", _MOTION_KEYS)),
        pen_lift_s=float(t.get("pen_lift_s", is_non_negative, "seconds >= 0", 0.0)),
        pen_drop_s=float(t.get("pen_drop_s", is_non_negative, "seconds >= 0", 0.0)),
        pen_change_s=float(t.get("pen_change_s", is_non_negative, "seconds >= 0", 0.0)),
        papers=papers,
        default_paper=default_paper,
        steps_per_mm=t.get("steps_per_mm", is_positive, "steps per mm > 0"),
        link=None if link_t is None else _link(link_t),
        servo=None if servo_t is None else _servo(servo_t),
        source=source,
    )


def read_text(text: str, source: str, *, max_bytes: int | None = None, max_depth: int | None = None) -> dict[str, Any]:
    """TOML text as tables, refused beyond ``max_bytes`` or ``max_depth`` (default: model's limits, read now)."""
    max_bytes = model.MAX_BYTES if max_bytes is None else max_bytes
    if len(text) > max_bytes:
        raise ParseError(f"file of {len(text)} characters is larger than the {max_bytes} allowed", source=source)
    return read_toml(text, source, max_depth=model.MAX_DEPTH if max_depth is None else max_depth)


def read_file(path: Path, *, max_bytes: int | None = None, max_depth: int | None = None,
              what: str = "profile") -> dict[str, Any]:
    """A TOML file as tables; errors name the file and call it ``what`` (limits as :func:`read_text`)."""
    max_bytes = model.MAX_BYTES if max_bytes is None else max_bytes
    try:
        size = path.stat().st_size
        if size > max_bytes:
            raise ParseError(f"file of {size} bytes is larger than the {max_bytes} allowed", source=str(path))
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ParseError(f"{what} is not UTF-8 text", source=str(path), offset=exc.start) from None
    except OSError as exc:
        raise ConfigError(f"cannot read {what} {str(path)!r}: {exc.strerror or exc}") from None
    return read_text(text, str(path), max_bytes=max_bytes, max_depth=max_depth)


def _builtin_dir() -> Traversable:
    """The folder of the built-in profiles inside the installed package."""
    return resources.files("pixelpen").joinpath("data").joinpath("profiles")


def builtin_profiles() -> dict[str, DeviceProfile]:
    """Every profile shipped in ``pixelpen/data/profiles``, by name."""
    out: dict[str, DeviceProfile] = {}
    for entry in sorted(_builtin_dir().iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".toml"):
            source = f"pixelpen/data/profiles/{entry.name}"
            profile = _profile(read_text(entry.read_text(encoding="utf-8"), source), source)
            out[profile.name] = profile
    return out


def profile_file(name_or_path: str | Path, what: str = "profile") -> Path | None:
    """The TOML file ``name_or_path`` names (ConfigError when it is missing), or None when it is a built-in's name."""
    text = str(name_or_path)
    path = check_path(text, f"{what} file name").expanduser()
    if isinstance(name_or_path, Path) or text.endswith(".toml") or path.is_file():
        if not path.is_file():
            raise ConfigError(f"{what} file {quote_token(text)} does not exist")
        return path
    return None


def profile_key(name: str | Path) -> str:
    """A built-in profile's name as the tables key it (``HP-7475A`` -> ``hp_7475a``)."""
    return str(name).strip().lower().replace("-", "_")


def load_profile(name_or_path: str | Path) -> DeviceProfile:
    """A built-in profile by name (``hp7475a``, ``axidraw_v3``, …) or a user profile from a TOML file path."""
    path = profile_file(name_or_path)
    if path is not None:
        return _profile(read_file(path), str(path))
    text = str(name_or_path)
    builtins = builtin_profiles()
    key = profile_key(text)
    if key in builtins:
        return builtins[key]
    raise ConfigError(
        f"unknown device profile {quote_token(text)}: not a file, nor one of {', '.join(sorted(builtins))}"
    )



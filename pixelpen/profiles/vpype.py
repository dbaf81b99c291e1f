"""vpype device configurations (``[device.NAME]`` tables with ``[[device.NAME.paper]]`` entries) as profiles."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path
from typing import Any

from pixelpen.errors import InvalidArgument, quote_token
from pixelpen.profiles import model
from pixelpen.profiles.model import REFERENCES, DeviceProfile, Paper, is_integer, is_number, is_pen_count
from pixelpen.profiles.toml import Table, is_range, load_profile, one_of, read_file

__all__ = ["load_vpype_config", "parse_length_mm"]

_DEVICE_KEYS = ("name", "plotter_unit_length", "unit", "pen_count", "info", "paper")
_PAPER_KEYS = ("name", "aka_names", "info", "paper_size", "x_range", "y_range", "y_axis_up", "origin_location",
               "origin_location_reference", "paper_orientation", "rotate_180", "set_ps", "final_pu_params")

_LENGTH_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "inch": 25.4, "ft": 304.8, "yd": 914.4,
              "px": 25.4 / 96.0, "pt": 25.4 / 72.0, "pc": 25.4 / 6.0, "": 25.4 / 96.0}
_XY = re.compile(r"\s*-?\d{1,9}\s*,\s*-?\d{1,9}\s*")
_LENGTH_RE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([a-zA-Z]*)\s*$")


def parse_length_mm(value: Any) -> float:
    """A vpype length in mm: a number (CSS pixels, 1/96 in) or a string with a unit (``"297mm"``, ``"11in"``)."""
    if is_number(value):
        return float(value) * _LENGTH_MM["px"]
    if isinstance(value, str) and len(value) <= 100:
        m = _LENGTH_RE.match(value)
        if m and m[2].lower() in _LENGTH_MM and abs(float(m[1])) <= model.MAX_VALUE:
            return float(m[1]) * _LENGTH_MM[m[2].lower()]
    raise InvalidArgument(f"not a length: {quote_token(value)}")


def _xy(text: str) -> tuple[int, int]:
    """An 'x,y' pair of integers (checked by _XY)."""
    x, y = text.split(",")
    return int(x), int(y)


def _is_length(v: Any) -> bool:
    """Whether :func:`parse_length_mm` reads ``v``."""
    try:
        parse_length_mm(v)
    except InvalidArgument:
        return False
    return True


_LENGTH_WHAT = "a length (a number of px, or a string such as '0.025mm')"


def _vpype_paper(t: Table) -> Paper:
    """One [[device.NAME.paper]] entry as a Paper."""
    length_pair = lambda v: isinstance(v, list) and len(v) == 2 and all(_is_length(x) for x in v)
    name = t.get("name", lambda v: isinstance(v, str) and v != "", "a non-empty string", required=True)
    size = t.get("paper_size", length_pair, "a [width, height] pair of lengths", None)
    origin = t.get("origin_location", length_pair, "an [x, y] pair of lengths", required=True)
    park = t.get("final_pu_params", lambda v: isinstance(v, str) and _XY.fullmatch(v) is not None,
                 "a string 'x,y' of integers", None)
    y_up = t.get("y_axis_up", lambda v: isinstance(v, bool), "true or false", required=True)
    x_range = t.get("x_range", is_range, "a [low, high] pair of integers, low < high", None)
    y_range = t.get("y_range", is_range, "a [low, high] pair of integers, low < high", None)
    return Paper(
        name=name,
        x_range=tuple(x_range) if x_range else (-32768, 32767),
        y_range=tuple(y_range) if y_range else (-32768, 32767),
        size_mm=None if size is None else (parse_length_mm(size[0]), parse_length_mm(size[1])),
        origin_mm=(parse_length_mm(origin[0]), parse_length_mm(origin[1])),
        origin_reference=t.get("origin_location_reference", one_of(REFERENCES), "'topleft' or 'botleft'", "topleft"),
        orientation=t.get("paper_orientation", one_of(("portrait", "landscape")), "'portrait' or 'landscape'", None),
        rotate_180=t.get("rotate_180", lambda v: isinstance(v, bool), "true or false", False),
        set_ps=t.get("set_ps", is_integer, "an integer", None),
        park=None if park is None else _xy(park),
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
    data = read_file(path)
    devices = data.get("device", {})
    top = Table(data, source, "", None)
    if not isinstance(devices, dict) or len(devices) > model.MAX_PAPERS:
        raise top.fail("device", f"expected a table of at most {model.MAX_PAPERS} devices", devices)
    out = {}
    for key, body in devices.items():
        t = Table(body, source, f"device.{key}", _DEVICE_KEYS)
        name = t.get("name", lambda v: isinstance(v, str) and v != "", "a non-empty string", key)
        unit_key = "plotter_unit_length" if "plotter_unit_length" in t.data or "unit" not in t.data else "unit"
        unit = t.get(unit_key, _is_length, _LENGTH_WHAT, required=True)
        unit_mm = parse_length_mm(unit)
        if unit_mm <= 0:
            raise t.fail(unit_key, "expected a length > 0", unit)
        pens = t.get("pen_count", is_pen_count, f"an integer 1..{model.MAX_PENS}", 1)
        t.get("info", lambda v: isinstance(v, str), "a string", "")  # checked, not kept
        papers_raw = t.get("paper", lambda v: isinstance(v, list) and len(v) <= model.MAX_PAPERS,
                           f"an array of at most {model.MAX_PAPERS} [[paper]] tables", [])
        papers = {}
        for i, entry in enumerate(papers_raw):
            paper = _vpype_paper(Table(entry, source, f"device.{key}.paper[{i}]", _PAPER_KEYS))
            papers[paper.name] = paper
        y_ups = {bool(p.y_up) for p in papers.values()}  # every vpype paper states y_axis_up
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

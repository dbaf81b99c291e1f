"""The picture file format: a Picture saved as versioned JSON, loaded with errors that say where.

Format (version 1)::

    {"format": "pixelpen-picture", "version": 1,
     "window": [xmin, ymin, xmax, ymax] | null,
     "items": [ITEM, ...]}

    ITEM    := PRIMITIVE | {"type": "segment", "name": str, "transform": 3x3 | absent,
                            "visible": bool, "pickable": bool, "items": [PRIMITIVE, ...]}
    PRIMITIVE := {"type": T, ...fields of T..., "style": STYLE (optional)}
      polyline  points: [[x, y], ...]          polygon   rings: [[[x, y], ...], ...]
      rectangle x0, y0, x1, y1                 circle    center: [x, y], r
      ellipse   center, rx, ry, angle?         arc       center, rx, ry, start, end, angle?, close?
      bezier    control_points, degree?        bspline   control_points, degree?, knots?
      marker    points, kind?, size?           text      position, text, height?, angle?, slant?, align?, valign?
      image     rect: [x0, y0, x1, y1], png: base64 PNG data
    STYLE   := {"colour": "#rrggbb" | name, "pen": int, "width": mm, "dash": [mm, ...],
                "layer": str, "fill": {"style": ..., "angle": rad, "spacing": mm, "pattern": [[0/1]], "outline": bool}}

Angles are radians; lengths in styles are millimetres; coordinates are world units.

Reading checks every field and names the JSON path (``$.items[3].style.dash``) or byte offset of
anything wrong. Limits (module attributes, read at call time: assign to override): :data:`MAX_BYTES`
(256 MiB), :data:`MAX_DEPTH` (JSON nesting, 32), :data:`MAX_ITEMS` (1,000,000 primitives),
:data:`MAX_POINTS` (20,000,000 points), :data:`MAX_PIXELS` (100,000,000 image pixels); the values of
primitives are bounded by :mod:`pixelpen.display.picture` (coordinates within +-1e15). Integers of more
than 19 digits are read as floats, so Python's 4300-digit limit is never reached.
"""

from __future__ import annotations

import base64
import io
import json
import math
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from PIL import Image as PILImage

from pixelpen.colour import colour_hex
from pixelpen.display.picture import (
    Arc,
    Bezier,
    BSpline,
    Circle,
    Ellipse,
    Fill,
    Image,
    Marker,
    Picture,
    Polygon,
    Polyline,
    Primitive,
    Rectangle,
    Segment,
    Style,
    Text,
)
from pixelpen.errors import ConfigError, ParseError, PixelpenError, quote_token
from pixelpen.urls import check_path

FORMAT = "pixelpen-picture"
VERSION = 1
MAX_BYTES = 256 * 1024 * 1024
"""Bytes of a picture file."""
MAX_DEPTH = 32
"""JSON nesting depth (the format itself needs 8)."""
MAX_ITEMS = 1_000_000
"""Primitives and segments in one file, counting those inside segments."""
MAX_POINTS = 20_000_000
"""Points (polyline, ring, control and marker points) in one file."""
MAX_PIXELS = 100_000_000
"""Pixels of all embedded images together."""
T = TypeVar("T")

_TYPES: dict[str, type] = {
    "polyline": Polyline, "polygon": Polygon, "rectangle": Rectangle, "circle": Circle, "ellipse": Ellipse,
    "arc": Arc, "bezier": Bezier, "bspline": BSpline, "marker": Marker, "text": Text, "image": Image,
}
_NAMES = {cls: name for name, cls in _TYPES.items()}


# -- writing ---------------------------------------------------------------------------------
def picture_to_dict(picture: Picture) -> dict[str, Any]:
    """The JSON-ready dict of a picture."""
    items: list[dict[str, Any]] = []
    for item in picture.items:
        if isinstance(item, Segment):
            items.append({
                "type": "segment", "name": item.name, "transform": np.asarray(item.transform).tolist(),
                "visible": item.visible, "pickable": item.pickable, "items": [_prim_to_dict(p) for p in item.items],
            })
        else:
            items.append(_prim_to_dict(item))
    return {
        "format": FORMAT,
        "version": VERSION,
        "window": list(picture.window) if picture.window else None,
        "items": items,
    }


def _prim_to_dict(prim: Primitive) -> dict[str, Any]:
    out: dict[str, Any] = {"type": _NAMES[type(prim)]}
    for f in fields(prim):
        value = getattr(prim, f.name)
        if f.name == "style":
            if value != Style():
                out["style"] = _style_to_dict(value)
        elif f.name == "pixels":
            buf = io.BytesIO()
            PILImage.fromarray(np.ascontiguousarray(value)).save(buf, format="PNG")
            out["png"] = base64.b64encode(buf.getvalue()).decode("ascii")
        elif isinstance(value, np.ndarray):
            out[f.name] = value.tolist()
        elif isinstance(value, tuple) and value and isinstance(value[0], np.ndarray):
            out[f.name] = [v.tolist() for v in value]
        elif value is not None:
            out[f.name] = list(value) if isinstance(value, tuple) else value
    return out


def _style_to_dict(style: Style) -> dict[str, Any]:
    out: dict[str, Any] = {"colour": colour_hex(style.colour)}
    for key in ("pen", "layer"):
        if getattr(style, key) is not None:
            out[key] = getattr(style, key)
    if style.width:
        out["width"] = style.width
    if style.dash:
        out["dash"] = list(style.dash)
    if style.fill is not None:
        f = style.fill
        fd: dict[str, Any] = {"style": f.style, "angle": f.angle, "outline": f.outline}
        if f.spacing is not None:
            fd["spacing"] = f.spacing
        if f.pattern is not None:
            fd["pattern"] = [list(r) for r in f.pattern]
        out["fill"] = fd
    return out


def save_picture(picture: Picture, path: str | Path) -> None:
    """Write a picture file (a file name no file system takes is a ConfigError)."""
    check_path(path, "picture file").write_text(
        json.dumps(picture_to_dict(picture), separators=(",", ":")), encoding="utf-8"
    )


# -- reading ---------------------------------------------------------------------------------
def load_picture(path: str | Path) -> Picture:
    """Read a picture file; a ParseError names the file and where in it the problem is."""
    name = str(path)
    try:
        path = check_path(path, "picture file")
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise ParseError(f"picture file is {size} bytes, more than the {MAX_BYTES} allowed", source=name)
        data = path.read_bytes()
    except ConfigError as exc:
        raise ParseError(str(exc), source=quote_token(name)) from None
    except OSError as exc:
        raise ParseError(f"cannot read picture file: {exc.strerror or exc}", source=name) from None
    return loads_picture(data, source=name)


def loads_picture(data: str | bytes, source: str = "<picture>") -> Picture:
    """Parse picture JSON text (limits: MAX_BYTES, MAX_DEPTH, MAX_ITEMS, MAX_POINTS, MAX_PIXELS)."""
    raw = data.encode("utf-8", "surrogatepass") if isinstance(data, str) else bytes(data)
    if len(raw) > MAX_BYTES:
        raise ParseError(f"picture is {len(raw)} bytes, more than the {MAX_BYTES} allowed", source=source)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ParseError("picture file is not UTF-8 text", source=source, offset=exc.start) from None
    too_deep = _first_too_deep(raw, MAX_DEPTH)
    if too_deep is not None:
        raise ParseError(f"JSON nested more than {MAX_DEPTH} deep (pictures need 8)", source=source, offset=too_deep)
    try:
        doc = json.loads(text, parse_int=_json_int)
    except json.JSONDecodeError as exc:
        raise ParseError(f"not valid JSON: {exc.msg}", source=source, line=exc.lineno, column=exc.colno) from None
    except (ValueError, RecursionError) as exc:
        raise ParseError(f"not valid JSON: {str(exc)[:200]}", source=source) from None
    return picture_from_dict(doc, source)


def _json_int(text: str) -> int | float:
    """A JSON integer: longer than 18 digits it is read as a float (inf beyond 1e308), never as a 4300-digit int."""
    return int(text) if len(text) <= 19 else float(text)


def _first_too_deep(raw: bytes, limit: int, chunk: int = 1 << 22) -> int | None:
    """Byte offset of the first ``[`` or ``{`` (outside strings) nested more than ``limit`` deep, or None.

    Vectorised over chunks (4 MiB), carrying the depth, whether a string is open and the run of
    backslashes at the end of the previous chunk.
    """
    depth, inside, run = 0, False, 0
    for begin in range(0, len(raw), chunk):
        a = np.frombuffer(raw, np.uint8, count=min(chunk, len(raw) - begin), offset=begin)
        idx = np.arange(len(a))
        plain = np.maximum.accumulate(np.where(a == 92, -1, idx))  # last non-backslash at or before i
        before = np.concatenate([[-1], plain[:-1]])
        run_before = idx - 1 - before + np.where(before < 0, run, 0)  # backslashes just before i
        quotes = (a == 34) & (run_before % 2 == 0)
        in_string = (np.cumsum(quotes) % 2 == 1) ^ inside
        step = np.where(in_string, 0, (a == 91).astype(np.int64) + (a == 123) - (a == 93) - (a == 125))
        levels = depth + np.cumsum(step)
        over = np.flatnonzero(levels > limit)
        if len(over):
            return begin + int(over[0])
        depth, inside = int(levels[-1]), bool(in_string[-1])
        run = len(a) - 1 - int(plain[-1]) + (run if plain[-1] < 0 else 0)
    return None


def picture_from_dict(doc: Any, source: str = "<picture>") -> Picture:
    """Build a Picture from its JSON dict, checking every field (limits MAX_ITEMS, MAX_POINTS, MAX_PIXELS)."""
    r = _Reader(source)
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise r.error(
            "$",
            f'not a pixelpen picture (expected an object with "format": "{FORMAT}")',
            doc.get("format") if isinstance(doc, dict) else type(doc).__name__,
        )
    version = doc.get("version")
    if type(version) is not int or version != VERSION:
        raise r.error("$.version", f"unsupported version (this pixelpen reads version {VERSION})", version)
    r.known(doc, "$", {"format", "version", "window", "items"})
    window = doc.get("window")
    picture = r.build(Picture, "$.window", tuple(r.numbers(window, "$.window", 4)) if window is not None else None)
    for i, item in enumerate(r.items(doc.get("items", []), "$.items")):
        where = f"$.items[{i}]"
        if isinstance(item, dict) and item.get("type") == "segment":
            r.add(picture, r.segment(item, where), where)
        else:
            r.add(picture, r.primitive(item, where), where)
    return picture


class _Reader:
    """Reads the parts of a picture dict, naming the JSON path of anything wrong and counting against the limits."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.count = {"items": 0, "points": 0, "pixels": 0}

    def error(self, where: str, message: str, token: object = None) -> ParseError:
        return ParseError(f"{where}: {message}", source=self.source, token=token)

    def spend(self, what: str, amount: int, limit: int, where: str) -> None:
        """Count ``amount`` of ``what`` against the file's limit."""
        self.count[what] += amount
        if self.count[what] > limit:
            raise self.error(where, f"the picture holds more than {limit} {what} (raise pictfile.MAX_{what.upper()})")

    def build(self, cls: Callable[..., T], where: str, *args: Any, **kwargs: Any) -> T:
        """Construct a picture object; its own checks become errors at ``where``."""
        try:
            return cls(*args, **kwargs)
        except (PixelpenError, TypeError, ValueError) as exc:
            raise self.error(where, f"invalid {getattr(cls, '__name__', str(cls)).lower()}: {exc}") from None

    def add(self, container: Picture | Segment, item: Primitive | Segment, where: str) -> None:
        """Add ``item`` to a picture or (a primitive) to a segment; the container's refusal becomes an error."""
        try:
            container.add(item)  # type: ignore[arg-type]  # Segment.add refuses a segment itself (ConfigError)
        except ConfigError as exc:
            raise self.error(where, str(exc)) from None

    def items(self, value: Any, where: str) -> list[Any]:
        if not isinstance(value, list):
            raise self.error(where, "expected a list", type(value).__name__)
        self.spend("items", len(value), MAX_ITEMS, where)
        return value

    def known(self, obj: dict[str, Any], where: str, allowed: set[str]) -> None:
        extra = sorted(set(obj) - allowed)
        if extra:
            raise self.error(
                where, f"unknown field(s) {', '.join(extra)}; expected some of {', '.join(sorted(allowed))}"[:400]
            )

    def numbers(self, value: Any, where: str, count: int | None = None) -> list[float]:
        if (
            not isinstance(value, list)
            or (count is not None and len(value) != count)
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        ):
            raise self.error(where, f"expected a list of {count or 'some'} numbers", value)
        out = [math.inf if isinstance(v, int) and v.bit_length() > 1000 else float(v) for v in value]
        bad = [k for k, v in enumerate(out) if not math.isfinite(v)]
        if bad:
            raise self.error(f"{where}[{bad[0]}]", "expected a finite number", value[bad[0]])
        return out

    def segment(self, item: dict[str, Any], where: str) -> Segment:
        self.known(item, where, {"type", "name", "transform", "visible", "pickable", "items"})
        transform = item.get("transform", np.eye(3).tolist())
        if not (isinstance(transform, list) and len(transform) == 3):
            raise self.error(where + ".transform", "expected a 3x3 matrix", transform)
        matrix = np.array([self.numbers(row, f"{where}.transform[{k}]", 3) for k, row in enumerate(transform)])
        seg = self.build(
            Segment, where, item.get("name"), [], matrix, item.get("visible", True), item.get("pickable", True)
        )
        for k, prim in enumerate(self.items(item.get("items", []), where + ".items")):
            self.add(seg, self.primitive(prim, f"{where}.items[{k}]"), f"{where}.items[{k}]")
        return seg

    def primitive(self, item: Any, where: str) -> Primitive:
        if not isinstance(item, dict):
            raise self.error(where, "expected an object", type(item).__name__)
        kind = item.get("type")
        cls = _TYPES.get(kind) if isinstance(kind, str) else None
        if cls is None:
            raise self.error(where + ".type", f"unknown primitive type; known: {', '.join(_TYPES)}, segment", kind)
        names = {f.name for f in fields(cls)} - {"pixels"}
        self.known(item, where, names | {"type"} | ({"png"} if cls is Image else set()))
        kwargs: dict[str, Any] = {}
        for key, value in item.items():
            if key == "type":
                continue
            if key == "style":
                kwargs["style"] = self.style(value, where + ".style")
            elif key == "png":
                kwargs["pixels"] = self.png(value, where + ".png")
            elif key == "rings":
                if not isinstance(value, list):
                    raise self.error(f"{where}.rings", "expected a list of rings", value)
                kwargs[key] = tuple(self.points(r, f"{where}.rings[{k}]") for k, r in enumerate(value))
            elif key in ("points", "control_points"):
                kwargs[key] = self.points(value, f"{where}.{key}")
            elif key in ("center", "position"):
                kwargs[key] = tuple(self.numbers(value, f"{where}.{key}", 2))
            elif key in ("rect",):
                kwargs[key] = tuple(self.numbers(value, f"{where}.{key}", 4))
            elif key == "knots":
                kwargs[key] = tuple(self.numbers(value, f"{where}.{key}"))
            else:
                kwargs[key] = value
        primitive: Primitive = self.build(cls, where, **kwargs)
        return primitive

    def points(self, value: Any, where: str) -> np.ndarray:
        if not isinstance(value, list):
            raise self.error(where, "expected a list of [x, y] pairs", type(value).__name__)
        self.spend("points", len(value), MAX_POINTS, where)
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise self.error(where, "expected a list of [x, y] pairs of numbers") from None
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise self.error(where, f"expected a list of [x, y] pairs, got shape {arr.shape}")
        if not np.isfinite(arr).all():
            row = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
            raise self.error(f"{where}[{row}]", "expected finite numbers", value[row])
        return arr

    def style(self, value: Any, where: str) -> Style:
        if not isinstance(value, dict):
            raise self.error(where, "expected an object", type(value).__name__)
        self.known(value, where, {"colour", "color", "pen", "width", "dash", "layer", "fill"})
        kwargs = dict(value)
        if "color" in kwargs:
            kwargs["colour"] = kwargs.pop("color")
        if "fill" in kwargs:
            fill = kwargs["fill"]
            if not isinstance(fill, dict):
                raise self.error(where + ".fill", "expected an object", fill)
            self.known(fill, where + ".fill", {"style", "angle", "spacing", "pattern", "outline"})
            kwargs["fill"] = self.build(Fill, where + ".fill", **fill)
        if "dash" in kwargs:
            kwargs["dash"] = tuple(self.numbers(kwargs["dash"], where + ".dash"))
        return self.build(Style, where, **kwargs)

    def png(self, value: Any, where: str) -> np.ndarray:
        if not isinstance(value, str):
            raise self.error(where, "expected base64 PNG data (a string)", type(value).__name__)
        try:
            raw = base64.b64decode(value, validate=True)
            with PILImage.open(io.BytesIO(raw)) as im:
                self.spend("pixels", im.width * im.height, MAX_PIXELS, where)
                return np.asarray(im.convert("RGBA" if im.mode in ("RGBA", "LA", "P") else "RGB"))
        except ParseError:
            raise
        except Exception as exc:  # noqa: BLE001 - PIL raises many types (OSError, SyntaxError, zlib.error...) on bad data
            raise self.error(where, f"not base64 PNG data: {str(exc)[:200]}") from None

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
"""

from __future__ import annotations

import base64
import io
import json
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image as PILImage, UnidentifiedImageError

from ..errors import ConfigError, ParseError
from .picture import (
    Arc, Bezier, BSpline, Circle, Ellipse, Fill, Image, Marker, Picture, Polygon, Polyline, Primitive, Rectangle,
    Segment, Style, Text, colour_hex,
)

FORMAT = "pixelpen-picture"
VERSION = 1
MAX_BYTES = 256 * 1024 * 1024

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
    return {"format": FORMAT, "version": VERSION, "window": list(picture.window) if picture.window else None, "items": items}


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
    """Write a picture file."""
    Path(path).write_text(json.dumps(picture_to_dict(picture), separators=(",", ":")), encoding="utf-8")


# -- reading ---------------------------------------------------------------------------------
def load_picture(path: str | Path) -> Picture:
    """Read a picture file; a ParseError names the file and where in it the problem is."""
    path = Path(path)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise ParseError(f"cannot read picture file: {exc.strerror}", source=str(path)) from None
    if size > MAX_BYTES:
        raise ParseError(f"picture file is {size} bytes, more than the {MAX_BYTES} allowed", source=str(path))
    return loads_picture(path.read_bytes(), source=str(path))


def loads_picture(data: str | bytes, source: str = "<picture>") -> Picture:
    """Parse picture JSON text."""
    try:
        text = data.decode("utf-8") if isinstance(data, bytes) else data
    except UnicodeDecodeError as exc:
        raise ParseError("picture file is not UTF-8 text", source=source, offset=exc.start) from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ParseError(f"not valid JSON: {exc.msg}", source=source, line=exc.lineno, column=exc.colno) from None
    return picture_from_dict(doc, source)


def picture_from_dict(doc: Any, source: str = "<picture>") -> Picture:
    """Build a Picture from its JSON dict, checking every field."""
    r = _Reader(source)
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise r.error("$", f"not a pixelpen picture (expected an object with \"format\": \"{FORMAT}\")",
                      doc.get("format") if isinstance(doc, dict) else type(doc).__name__)
    version = doc.get("version")
    if version != VERSION:
        raise r.error("$.version", f"unsupported version (this pixelpen reads version {VERSION})", version)
    r.known(doc, "$", {"format", "version", "window", "items"})
    window = doc.get("window")
    picture = Picture(tuple(r.numbers(window, "$.window", 4)) if window is not None else None)  # type: ignore[arg-type]
    items = doc.get("items", [])
    if not isinstance(items, list):
        raise r.error("$.items", "expected a list", type(items).__name__)
    for i, item in enumerate(items):
        where = f"$.items[{i}]"
        if isinstance(item, dict) and item.get("type") == "segment":
            picture.add(r.segment(item, where))
        else:
            picture.add(r.primitive(item, where))
    return picture


class _Reader:
    """Reads the parts of a picture dict, naming the JSON path of anything wrong."""

    def __init__(self, source: str) -> None:
        self.source = source

    def error(self, where: str, message: str, token: object = None) -> ParseError:
        return ParseError(f"{where}: {message}", source=self.source, token=token)

    def known(self, obj: dict, where: str, allowed: set[str]) -> None:
        extra = sorted(set(obj) - allowed)
        if extra:
            raise self.error(where, f"unknown field(s) {', '.join(extra)}; expected some of {', '.join(sorted(allowed))}")

    def numbers(self, value: Any, where: str, count: int | None = None) -> list[float]:
        if not isinstance(value, list) or (count is not None and len(value) != count) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value
        ):
            raise self.error(where, f"expected a list of {count or 'some'} numbers", value)
        return [float(v) for v in value]

    def segment(self, item: dict, where: str) -> Segment:
        self.known(item, where, {"type", "name", "transform", "visible", "pickable", "items"})
        name = item.get("name")
        if not isinstance(name, str) or not name:
            raise self.error(where + ".name", "a segment needs a non-empty name", name)
        transform = item.get("transform", np.eye(3).tolist())
        if not (isinstance(transform, list) and len(transform) == 3):
            raise self.error(where + ".transform", "expected a 3x3 matrix", transform)
        matrix = np.array([self.numbers(row, f"{where}.transform[{k}]", 3) for k, row in enumerate(transform)])
        seg = Segment(name, [], matrix, bool(item.get("visible", True)), bool(item.get("pickable", True)))
        for k, prim in enumerate(item.get("items", [])):
            seg.add(self.primitive(prim, f"{where}.items[{k}]"))
        return seg

    def primitive(self, item: Any, where: str) -> Primitive:
        if not isinstance(item, dict):
            raise self.error(where, "expected an object", type(item).__name__)
        kind = item.get("type")
        cls = _TYPES.get(kind)  # type: ignore[arg-type]
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
        try:
            return cls(**kwargs)
        except (ConfigError, TypeError, ValueError) as exc:
            raise self.error(where, f"invalid {kind}: {exc}") from None

    def points(self, value: Any, where: str) -> np.ndarray:
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise self.error(where, "expected a list of [x, y] pairs", value if not isinstance(value, list) else None) from None
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise self.error(where, f"expected a list of [x, y] pairs, got shape {arr.shape}")
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
            fill = dict(fill)
            if "pattern" in fill:
                fill["pattern"] = tuple(tuple(int(c) for c in row) for row in fill["pattern"])
            try:
                kwargs["fill"] = Fill(**fill)
            except (ConfigError, TypeError, ValueError) as exc:
                raise self.error(where + ".fill", str(exc)) from None
        if "dash" in kwargs:
            kwargs["dash"] = tuple(self.numbers(kwargs["dash"], where + ".dash"))
        try:
            return Style(**kwargs)
        except (ConfigError, TypeError, ValueError) as exc:
            raise self.error(where, str(exc)) from None

    def png(self, value: Any, where: str) -> np.ndarray:
        try:
            raw = base64.b64decode(value, validate=True)
            with PILImage.open(io.BytesIO(raw)) as im:
                return np.asarray(im.convert("RGBA" if im.mode in ("RGBA", "LA", "P") else "RGB"))
        except (ValueError, TypeError, UnidentifiedImageError, OSError) as exc:
            raise self.error(where, f"not base64 PNG data: {exc}") from None

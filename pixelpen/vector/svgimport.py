"""SVG files to display lists in millimetres (svgelements: transforms, units, viewBox) and display lists back to SVG."""

from __future__ import annotations

import io
import logging
import math
import os
import re
from collections import Counter
from collections.abc import Iterable, Iterator
from typing import IO, Any, Literal
from xml.etree.ElementTree import ParseError as XMLParseError
from xml.sax.saxutils import quoteattr

import numpy as np
import svgelements as se

from ..errors import ConfigError, ParseError
from .displaylist import DisplayList

log = logging.getLogger(__name__)

PPI = 96.0
"""CSS/SVG pixels per inch: one user unit without a physical size is 1/96 in."""
MM_PER_PX = 25.4 / PPI
MAX_SEGMENT_POINTS = 100_000
"""Upper bound on the points one curve segment is flattened into (guards absurd tolerances)."""
INKSCAPE_NS = "http://www.inkscape.org/namespaces/inkscape"
LayerBy = Literal["auto", "stroke", "group"]
Source = str | os.PathLike | bytes | IO[bytes] | IO[str]


def _read_bytes(source: Source) -> tuple[bytes, str]:
    """The document bytes and a name for messages."""
    if isinstance(source, (bytes, bytearray)):
        return bytes(source), "<bytes>"
    if isinstance(source, (str, os.PathLike)):
        name = os.fspath(source)
        try:
            with open(name, "rb") as fh:
                return fh.read(), name
        except OSError as exc:
            raise ParseError(f"cannot read SVG file: {exc.strerror or exc}", source=name) from None
    name = str(getattr(source, "name", "<stream>"))
    try:
        data = source.read()
    except (OSError, ValueError) as exc:
        raise ParseError(f"cannot read SVG stream: {exc}", source=name) from None
    return (data.encode("utf-8") if isinstance(data, str) else bytes(data)), name


def _parse(data: bytes, name: str) -> se.SVG:
    if not data.strip():
        raise ParseError("empty file: expected an SVG document", source=name)
    try:
        doc = se.SVG.parse(io.BytesIO(data), reify=True, ppi=PPI)
    except XMLParseError as exc:
        line, column = getattr(exc, "position", (None, None))
        reason = re.sub(r":? line \d+, column \d+$", "", str(exc))
        raise ParseError(f"not well-formed XML, so not an SVG document ({reason})",
                         source=name, line=line, column=None if column is None else column + 1) from None
    except (ValueError, TypeError, IndexError, KeyError, AttributeError, ZeroDivisionError) as exc:
        raise ParseError(f"invalid SVG content: {exc}", source=name) from None
    if not isinstance(doc, se.SVG):
        tag = getattr(doc, "values", {}).get("tag", "?") if doc is not None else "nothing"
        raise ParseError(f"not an SVG document: the root element is <{tag}>, expected <svg>", source=name)
    return doc


def _is_layer(group: se.Group) -> bool:
    return group.values.get(f"{{{INKSCAPE_NS}}}groupmode") == "layer"


def _group_label(group: se.Group, number: int) -> str:
    return (
        group.values.get(f"{{{INKSCAPE_NS}}}label")
        or group.id
        or f"group {number}"
    )


def _walk(
    node: Iterable[Any], layer: str | None, top: bool, by_group: bool, inkscape: bool
) -> Iterator[tuple[Any, str | None]]:
    """Yield (element, layer name) for every element below ``node``; layer = top-level Inkscape layer or group."""
    for number, child in enumerate(node, start=1):
        if isinstance(child, (se.Group, se.Use)):
            child_layer = layer
            if layer is None and isinstance(child, se.Group) and ((inkscape and _is_layer(child)) or (by_group and top)):
                child_layer = _group_label(child, number)
            yield from _walk(child, child_layer, False, by_group, inkscape)
        else:
            yield child, layer


def _has_layers(node: Iterable[Any]) -> bool:
    return any(isinstance(c, se.Group) and (_is_layer(c) or _has_layers(c)) for c in node)


def _colour(paint: object) -> str | None:
    if paint is None or getattr(paint, "value", None) is None:
        return None
    return paint.hexrgb  # type: ignore[attr-defined]


def _flatten(path: se.Path, tol_px: float) -> list[np.ndarray]:
    """Subpaths of ``path`` as polylines in px, curves flattened to within ``tol_px``."""
    out: list[np.ndarray] = []
    pts: list[tuple[float, float]] = []
    for seg in path:
        if isinstance(seg, se.Move):
            if len(pts) >= 2:
                out.append(np.array(pts, dtype=np.float64))
            pts = [(seg.end.x, seg.end.y)]
            continue
        if not pts:  # a drawing command without a preceding move starts at its own start
            pts = [(seg.start.x, seg.start.y)]
        if isinstance(seg, se.Close):
            # end exactly where the subpath started: replace a last point that only differs by round-off
            start, last = pts[0], pts[-1]
            if len(pts) > 1 and math.hypot(last[0] - start[0], last[1] - start[1]) <= 1e-9 * (1 + math.hypot(*start)):
                pts[-1] = start
            elif last != start:
                pts.append(start)
            continue
        if isinstance(seg, se.Line):
            pts.append((seg.end.x, seg.end.y))
            continue
        n = _segment_count(seg, tol_px)
        pts.extend(map(tuple, np.asarray(seg.npoint(np.linspace(0.0, 1.0, n + 1)[1:]), dtype=np.float64).tolist()))
    if len(pts) >= 2:
        out.append(np.array(pts, dtype=np.float64))
    return out


def _segment_count(seg: object, tol_px: float) -> int:
    """Chords needed for a curve segment to stay within ``tol_px`` of the curve."""
    if isinstance(seg, se.CubicBezier):
        p = np.array([[seg.start.x, seg.start.y], [seg.control1.x, seg.control1.y],
                      [seg.control2.x, seg.control2.y], [seg.end.x, seg.end.y]])
        dd = np.hypot(*(p[:-2] - 2 * p[1:-1] + p[2:]).T).max()
        n = math.sqrt(0.75 * dd / tol_px)  # |curve - chords| <= d(d-1)/8 * max|second difference| / n^2
    elif isinstance(seg, se.QuadraticBezier):
        p = np.array([[seg.start.x, seg.start.y], [seg.control.x, seg.control.y], [seg.end.x, seg.end.y]])
        n = math.sqrt(0.25 * float(np.hypot(*(p[0] - 2 * p[1] + p[2]))) / tol_px)
    elif isinstance(seg, se.Arc):
        r = max(abs(seg.rx), abs(seg.ry))
        half_step = math.acos(1 - tol_px / r) if r > tol_px else math.pi
        # sagitta of each chord <= tol
        n = abs(seg.sweep) / (2 * half_step) if half_step > 0 else MAX_SEGMENT_POINTS
    else:
        raise ParseError(f"unsupported SVG path segment {type(seg).__name__}")
    if not math.isfinite(n):
        return MAX_SEGMENT_POINTS
    return int(min(MAX_SEGMENT_POINTS, max(1, math.ceil(n))))


def read_svg(source: Source, *, tolerance: float = 0.05, layer_by: LayerBy = "auto") -> DisplayList:
    """Read an SVG into a display list in millimetres (unit_mm 1.0, y down, origin at the document's top left).

    Paths and basic shapes are flattened to within ``tolerance`` mm after all transforms, viewBox and units are
    applied. ``layer_by``: ``stroke`` makes one layer per stroke colour, ``group`` one per top-level group (or
    Inkscape layer), ``auto`` uses Inkscape layers when the file has them and stroke colours otherwise. Pens are
    numbered by stroke colour in order of appearance, with ``pen_colours`` set. Hidden elements are skipped,
    fill-only shapes are imported as their outlines, text and images are skipped (all with a logged warning).
    """
    if not (isinstance(tolerance, (int, float)) and math.isfinite(tolerance) and tolerance > 0):
        raise ConfigError(f"SVG flattening tolerance must be > 0 mm, got {tolerance!r}")
    if layer_by not in ("auto", "stroke", "group"):
        raise ConfigError(f"layer_by must be 'auto', 'stroke' or 'group', got {layer_by!r}")
    data, name = _read_bytes(source)
    doc = _parse(data, name)
    inkscape = _has_layers(doc) and layer_by in ("auto", "group")
    by_colour = layer_by == "stroke" or (layer_by == "auto" and not inkscape)
    tol_px = tolerance / MM_PER_PX

    polylines: list[np.ndarray] = []
    colours: list[str] = []
    layer_keys: list[str] = []
    skipped: Counter[str] = Counter()
    for element, layer in _walk(doc, None, True, layer_by == "group", inkscape):
        if isinstance(element, se.Text):
            skipped["text element(s) skipped (convert text to paths to plot it)"] += 1
            continue
        if isinstance(element, se.Image):
            skipped["image(s) skipped"] += 1
            continue
        if not isinstance(element, se.Shape):
            continue
        if element.values.get("visibility") in ("hidden", "collapse"):
            skipped["hidden element(s) skipped"] += 1
            continue
        stroke, fill = _colour(element.stroke), _colour(element.fill)
        if stroke is None and fill is None:
            skipped["element(s) with neither stroke nor fill skipped"] += 1
            continue
        if stroke is None:
            skipped["fill-only shape(s) imported as outlines"] += 1
        colour = stroke or fill
        for pts in _flatten(element if isinstance(element, se.Path) else se.Path(element), tol_px):
            if not np.isfinite(pts).all():
                what = element.id or type(element).__name__.lower()
                raise ParseError(f"element {what!r} has a non-finite coordinate after transforms", source=name)
            polylines.append(pts * MM_PER_PX)
            colours.append(colour)  # type: ignore[arg-type]
            layer_keys.append(colour if by_colour else (layer or "root"))  # type: ignore[arg-type]
    for what, count in skipped.items():
        log.warning("%s: %d %s", name, count, what)
    if not polylines:
        log.warning("%s: no drawable elements; the display list is empty", name)

    pen_of = {c: i + 1 for i, c in enumerate(dict.fromkeys(colours))}
    layer_of = {key: i + 1 for i, key in enumerate(dict.fromkeys(layer_keys))}
    return DisplayList.from_polylines(
        polylines,
        pens=[pen_of[c] for c in colours],
        layers=[layer_of[k] for k in layer_keys],
        layer_names={i: k for k, i in layer_of.items()},
        unit_mm=1.0,
        pen_colours={p: c for c, p in pen_of.items()},
    )


def _num(x: float) -> str:
    return format(float(x), ".10g")


def write_svg(
    dl: DisplayList,
    path_or_file: str | os.PathLike | IO[str] | IO[bytes],
    *,
    size_mm: tuple[float, float] | None = None,
    pen_width_mm: float = 0.3,
) -> None:
    """Write ``dl`` as an SVG of its true size: one Inkscape layer (``<g>``) per layer, one ``<path>`` per stroke.

    Coordinates stay in display-list units; the viewBox maps them to millimetres through ``unit_mm``. The page
    is ``size_mm`` (width, height) from the origin, or reaches from the origin (or the drawing's minimum, if
    negative) to the drawing's maximum. Single-point strokes are written as zero-length lines.
    """
    if not (dl.unit_mm > 0 and math.isfinite(dl.unit_mm)):
        raise ConfigError(f"display list unit must be > 0 mm, got {dl.unit_mm!r}")
    bounds = dl.bounds() or (0.0, 0.0, 0.0, 0.0)
    x0, y0 = min(0.0, bounds[0]), min(0.0, bounds[1])
    if size_mm is not None:
        w_mm, h_mm = (float(v) for v in size_mm)
        if not (w_mm > 0 and h_mm > 0 and math.isfinite(w_mm) and math.isfinite(h_mm)):
            raise ConfigError(f"SVG page size must be two sizes > 0 mm, got {size_mm!r}")
        w, h = w_mm / dl.unit_mm, h_mm / dl.unit_mm
    else:
        w, h = max(bounds[2] - x0, 0.0), max(bounds[3] - y0, 0.0)
        if w == 0 or h == 0:  # an empty or flat drawing still gets a valid page
            w, h = max(w, 1.0 / dl.unit_mm), max(h, 1.0 / dl.unit_mm)
        w_mm, h_mm = w * dl.unit_mm, h * dl.unit_mm
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        (f'<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="{INKSCAPE_NS}" '
         f'width="{_num(w_mm)}mm" height="{_num(h_mm)}mm" viewBox="{_num(x0)} {_num(y0)} {_num(w)} {_num(h)}">'),
    ]
    stroke_width = pen_width_mm / dl.unit_mm
    for layer_id in sorted(set(dl.layers.tolist())):
        idx = np.flatnonzero(dl.layers == layer_id)
        label = dl.layer_names.get(layer_id, str(layer_id))
        colours = [dl.pen_colours.get(int(p), "#000000") for p in dl.pens[idx]]
        layer_colour = Counter(colours).most_common(1)[0][0]
        out.append(
            f'<g id="layer{layer_id}" inkscape:groupmode="layer" inkscape:label={quoteattr(label)} '
            f'fill="none" stroke="{layer_colour}" stroke-width="{_num(stroke_width)}" '
            f'stroke-linecap="round" stroke-linejoin="round">'
        )
        for i, colour in zip(idx, colours):
            pts = dl.stroke(int(i))
            if len(pts) == 1:
                pts = np.vstack([pts, pts])
            d = "M" + ("%.10g,%.10g " * len(pts) % tuple(pts.ravel())).strip()
            own = "" if colour == layer_colour else f' stroke="{colour}"'
            out.append(f'<path d="{d}"{own}/>')
        out.append("</g>")
    out.append("</svg>\n")
    text = "\n".join(out)
    if isinstance(path_or_file, (str, os.PathLike)):
        with open(path_or_file, "w", encoding="utf-8") as fh:
            fh.write(text)
    elif isinstance(path_or_file, io.TextIOBase):
        path_or_file.write(text)
    else:
        path_or_file.write(text.encode("utf-8"))  # type: ignore[arg-type]

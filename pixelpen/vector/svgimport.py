"""SVG files to display lists in millimetres (svgelements: transforms, units, viewBox).

Every element is flattened in its own coordinates and then mapped through its full transform (nested groups,
``<use>``, viewBox, units), so shapes land where a browser draws them. The document's page (width and height,
origin at its top left) is kept on the display list and written back by :func:`~pixelpen.vector.svgexport.write_svg`
(re-exported here). Before svgelements sees a file, :mod:`pixelpen.vector.svgcheck` checks it against the
per-file limits (:class:`SvgLimits`, re-exported here; ``read_svg(..., limits=SvgLimits(max_points=...))``).
One curve segment is flattened into at most :data:`MAX_SEGMENT_POINTS` points (guards absurd tolerances).
"""

from __future__ import annotations

import io
import logging
import math
import re
from collections import Counter
from collections.abc import Iterable, Iterator
from typing import Any, Literal

import numpy as np
import svgelements as se

from pixelpen.colour import colour_hex, parse_colour
from pixelpen.errors import ConfigError, ParseError
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.svgcheck import NUMBER, CheckedDocument, Source, SvgLimits, read_source
from pixelpen.vector.svgexport import INKSCAPE_NS, write_svg

__all__ = ["MAX_SEGMENT_POINTS", "LayerBy", "Source", "SvgLimits", "read_svg", "write_svg"]

log = logging.getLogger(__name__)

PPI = 96.0
"""CSS/SVG pixels per inch: one user unit without a physical size is 1/96 in."""
MM_PER_PX = 25.4 / PPI
MAX_SEGMENT_POINTS = 100_000
"""Upper bound on the points one curve segment is flattened into (guards absurd tolerances)."""
MM_PER_UNIT = {"": MM_PER_PX, "px": MM_PER_PX, "mm": 1.0, "cm": 10.0, "q": 0.25, "in": 25.4, "pt": 25.4 / 72,
               "pc": 25.4 / 6}
"""Millimetres per absolute CSS length unit (exact; svgelements rounds the inch to 25.39999 mm)."""
LayerBy = Literal["auto", "stroke", "group"]
_LENGTH = re.compile(rf"\s*({NUMBER})\s*([A-Za-z]*)\s*")


def _length_mm(text: str | None) -> float | None:
    """An absolute CSS length in millimetres, or None (missing, relative or not a length)."""
    m = _LENGTH.fullmatch(text or "")
    if m is None or m.group(2).lower() not in MM_PER_UNIT:
        return None
    return float(m.group(1)) * MM_PER_UNIT[m.group(2).lower()]


def _affine(matrix: se.Matrix) -> np.ndarray:
    """A 3x3 numpy matrix of an svgelements Matrix (x' = a x + c y + e, y' = b x + d y + f)."""
    return np.array([[matrix.a, matrix.c, matrix.e], [matrix.b, matrix.d, matrix.f], [0.0, 0.0, 1.0]])


def _page(doc: se.SVG, root: dict[str, str]) -> tuple[tuple[float, float] | None, np.ndarray]:
    """The page (width, height in mm) of the document, if it has one, and the matrix that makes its units exact.

    svgelements converts the root's mm/cm/in with 0.0393701 in/mm; the correction replaces its viewport
    transform by the one computed from the exact size, so a page written in mm reads back unchanged.
    """
    vb = doc.viewbox
    sides: list[float] = []
    for attr, se_px in (("width", doc.width), ("height", doc.height)):
        side = _length_mm(root.get(attr))
        if side is None and vb is not None:
            side = se_px * MM_PER_PX
        if side is None or not (math.isfinite(side) and side > 0):
            return None, np.eye(3)
        sides.append(float(side))
    page = (sides[0], sides[1])
    if vb is None or vb.width is None or vb.height is None:
        return page, np.eye(3)
    try:
        used = _affine(se.Matrix(doc.viewbox_transform))
        exact_vb = _affine(se.Matrix(se.Viewbox.viewbox_transform(
            doc.x, doc.y, page[0] / MM_PER_PX, page[1] / MM_PER_PX, vb.x, vb.y, vb.width, vb.height,
            vb.preserve_aspect_ratio)))
        own = _affine(se.Matrix(root.get("transform", "")))
        correction = own @ exact_vb @ np.linalg.inv(used) @ np.linalg.inv(own)
    except (ValueError, ZeroDivisionError, np.linalg.LinAlgError):
        return page, np.eye(3)
    return page, (correction if np.isfinite(correction).all() else np.eye(3))


def _parse(data: bytes, name: str, limits: SvgLimits) -> tuple[se.SVG | None, tuple[float, float] | None, np.ndarray]:
    """The svgelements document (None when the root is not displayed), its page and its unit correction."""
    if not data.strip():
        raise ParseError("empty file: expected an SVG document", source=name)
    checked = CheckedDocument(data, name, limits)
    try:
        doc = se.SVG.parse(io.BytesIO(data), reify=False, ppi=PPI)
    except (ValueError, TypeError, IndexError, KeyError, AttributeError, ZeroDivisionError, OverflowError,
            SyntaxError) as exc:
        raise ParseError(f"invalid SVG content: {exc}", source=name) from None
    if not isinstance(doc, se.SVG):
        return None, None, np.eye(3)
    page, correction = _page(doc, checked.root)
    return doc, page, correction


def _is_layer(group: se.Group) -> bool:
    return group.values.get(f"{{{INKSCAPE_NS}}}groupmode") == "layer"


def _group_label(group: se.Group, number: int) -> str:
    return (
        group.values.get(f"{{{INKSCAPE_NS}}}label")
        or group.id
        or f"group {number}"
    )


def _walk(doc: se.SVG, by_group: bool, inkscape: bool) -> Iterator[tuple[Any, str | None]]:
    """Yield (element, layer name) for every element of ``doc``; layer = top-level Inkscape layer or group."""
    stack: list[tuple[Iterator[tuple[int, Any]], str | None, bool]] = [(enumerate(doc, start=1), None, True)]
    while stack:
        children, layer, top = stack[-1]
        item = next(children, None)
        if item is None:
            stack.pop()
            continue
        number, child = item
        if isinstance(child, (se.Group, se.Use)):
            child_layer = layer
            if (layer is None and isinstance(child, se.Group)
                    and ((inkscape and _is_layer(child)) or (by_group and top))):
                child_layer = _group_label(child, number)
            stack.append((enumerate(child, start=1), child_layer, False))
        else:
            yield child, layer


def _has_layers(doc: se.SVG) -> bool:
    """Whether any group below ``doc``, through groups only, is an Inkscape layer."""
    groups = [c for c in doc if isinstance(c, se.Group)]
    while groups:
        group = groups.pop()
        if _is_layer(group):
            return True
        groups.extend(c for c in group if isinstance(c, se.Group))
    return False


def _colour(element: se.Shape, key: str) -> str | None:
    """The ``stroke`` or ``fill`` paint of ``element`` as ``#rrggbb``; None for no paint.

    svgelements resolves the cascade (inheritance, ``currentColor``, CSS); the paint's text is then read by
    :mod:`pixelpen.colour`, so a name or form gives the value it has on the Picture API (svgelements' own table
    has a wrong ``aliceblue``, no ``rebeccapurple`` and truncates percentages). What colour.py does not read
    (``rgba()``, ``url(#gradient)``) keeps svgelements' value.
    """
    paint = getattr(element, key)
    if paint is None or paint.value is None:
        return None
    text = element.values.get(key)
    if isinstance(text, str):
        try:
            return colour_hex(parse_colour(text))
        except ConfigError:
            pass
    return str(paint.hexrgb)


def _segment_count(seg: object, tol: float) -> int:
    """Chords needed for a curve segment to stay within ``tol`` of the curve."""
    if isinstance(seg, se.CubicBezier):
        p = np.array([[seg.start.x, seg.start.y], [seg.control1.x, seg.control1.y],
                      [seg.control2.x, seg.control2.y], [seg.end.x, seg.end.y]])
        dd = np.hypot(*(p[:-2] - 2 * p[1:-1] + p[2:]).T).max()
        n = math.sqrt(0.75 * dd / tol)  # |curve - chords| <= d(d-1)/8 * max|second difference| / n^2
    elif isinstance(seg, se.QuadraticBezier):
        p = np.array([[seg.start.x, seg.start.y], [seg.control.x, seg.control.y], [seg.end.x, seg.end.y]])
        n = math.sqrt(0.25 * float(np.hypot(*(p[0] - 2 * p[1] + p[2]))) / tol)
    elif isinstance(seg, se.Arc):
        r = max(abs(seg.rx), abs(seg.ry))  # an ellipse is a circle of its larger radius, squeezed: no farther off
        half_step = math.acos(1 - tol / r) if r > tol else math.pi
        # sagitta of each chord <= tol
        n = abs(seg.sweep) / (2 * half_step) if half_step > 0 else MAX_SEGMENT_POINTS
    else:
        raise ParseError(f"unsupported SVG path segment {type(seg).__name__}")
    if not math.isfinite(n):
        return MAX_SEGMENT_POINTS
    return int(min(MAX_SEGMENT_POINTS, max(1, math.ceil(n))))


def _largest_stretch(m: np.ndarray) -> float:
    """The largest singular value of the linear part of an affine 3x3 matrix: how much it can lengthen."""
    a, b, c, d = m[0, 0], m[0, 1], m[1, 0], m[1, 1]
    f2 = a * a + b * b + c * c + d * d
    det = a * d - b * c
    return math.sqrt(max(0.0, (f2 + math.sqrt(max(0.0, f2 * f2 - 4 * det * det))) / 2))


class _Subpath:
    """Points of one subpath in the element's own coordinates: runs of line ends and flattened curves."""

    def __init__(self, x: float, y: float) -> None:
        self.start = (x, y)
        self.pieces: list[np.ndarray] = []
        self.run: list[tuple[float, float]] = [self.start]
        self.count = 1
        self.curve_points = 0

    def line(self, x: float, y: float) -> None:
        self.run.append((x, y))
        self.count += 1

    def curve(self, pts: np.ndarray) -> None:
        self._flush()
        self.pieces.append(pts)
        self.count += len(pts)
        self.curve_points += len(pts)

    def close(self) -> None:
        """End exactly where the subpath started: replace a last point that only differs by round-off."""
        last = self.run[-1] if self.run else tuple(self.pieces[-1][-1])
        sx, sy = self.start
        if self.count > 1 and math.hypot(last[0] - sx, last[1] - sy) <= 1e-9 * (1 + math.hypot(sx, sy)):
            if self.run:
                self.run[-1] = self.start
            else:
                self.pieces[-1] = self.pieces[-1].copy()
                self.pieces[-1][-1] = self.start
        elif last != self.start:
            self.line(sx, sy)

    def array(self) -> np.ndarray:
        """All points as one (N, 2) array."""
        self._flush()
        return np.concatenate(self.pieces)

    def _flush(self) -> None:
        if self.run:
            self.pieces.append(np.array(self.run, dtype=np.float64))
            self.run = []


class _Flattener:
    """Flattens elements into polylines in mm within a tolerance, counting strokes and points against the limits."""

    def __init__(self, name: str, tolerance_mm: float, correction: np.ndarray, limits: SvgLimits) -> None:
        self.name, self.limits = name, limits
        self.tol_px = tolerance_mm / MM_PER_PX
        self.correction = correction
        self.strokes = 0
        self.points = 0

    def element(self, element: se.Shape, what: str) -> list[np.ndarray]:
        """The subpaths of ``element`` as (N, 2) polylines in mm, after its full transform."""
        with np.errstate(all="ignore"):
            m = self.correction @ _affine(element.transform)
        if not np.isfinite(m).all():
            raise ParseError(f"{what} has a non-finite transform", source=self.name)
        stretch = _largest_stretch(m)
        tol = self.tol_px / stretch if stretch > 0 else math.inf
        try:
            local = self._subpaths(element.segments(transformed=False), tol, what)
        except (ValueError, TypeError, AttributeError, ZeroDivisionError, OverflowError, IndexError) as exc:
            raise ParseError(f"{what} cannot be flattened: {exc or type(exc).__name__}", source=self.name) from None
        out = []
        for pts in local:
            with np.errstate(all="ignore"):
                pts = (pts @ m[:2, :2].T + m[:2, 2]) * MM_PER_PX
            if not np.isfinite(pts).all():
                raise ParseError(f"{what} has a non-finite coordinate after transforms", source=self.name)
            out.append(pts)
        return out

    def _subpaths(self, segments: Iterable[Any], tol: float, what: str) -> list[np.ndarray]:
        out: list[np.ndarray] = []
        current: _Subpath | None = None
        for seg in segments:
            if isinstance(seg, se.Move):
                self._finish(current, out, what)
                current = _Subpath(seg.end.x, seg.end.y)
                continue
            if current is None:  # a drawing command without a preceding move starts at its own start
                current = _Subpath(seg.start.x, seg.start.y)
            if isinstance(seg, se.Close):
                current.close()
            elif isinstance(seg, se.Line):
                current.line(seg.end.x, seg.end.y)
            else:
                n = _segment_count(seg, tol)
                self._take_points(n, what)
                current.curve(np.asarray(seg.npoint(np.linspace(0.0, 1.0, n + 1)[1:]), dtype=np.float64))
        self._finish(current, out, what)
        return out

    def _finish(self, sub: _Subpath | None, out: list[np.ndarray], what: str) -> None:
        if sub is None or sub.count < 2:
            return
        self.strokes += 1
        if self.strokes > self.limits.max_strokes:
            raise ParseError(f"{what}: more than {self.limits.max_strokes} strokes in the file (limit max_strokes)",
                             source=self.name)
        self._take_points(sub.count - sub.curve_points, what)  # curves were counted before flattening
        out.append(sub.array())

    def _take_points(self, n: int, what: str) -> None:
        self.points += n
        if self.points > self.limits.max_points:
            raise ParseError(f"{what}: more than {self.limits.max_points} points in the file after flattening "
                             f"(limit max_points)", source=self.name)


def _describe(element: se.SVGElement, number: int) -> str:
    tag = element.values.get("tag", type(element).__name__.lower())
    return f"<{tag} id={element.id!r}>" if element.id else f"<{tag}> (drawable element {number})"


def read_svg(
    source: Source, *, tolerance: float = 0.05, layer_by: LayerBy = "auto", limits: SvgLimits | None = None
) -> DisplayList:
    """Read an SVG into a display list in millimetres (unit_mm 1.0, y down, origin at the document's top left).

    Paths and basic shapes are flattened to within ``tolerance`` mm after all transforms, viewBox and units are
    applied. ``layer_by``: ``stroke`` makes one layer per stroke colour, ``group`` one per top-level group (or
    Inkscape layer), ``auto`` uses Inkscape layers when the file has them and stroke colours otherwise. Pens are
    numbered by stroke colour in order of appearance, with ``pen_colours`` set; ``page`` is the document's size
    in mm when it has one. Hidden elements are skipped, fill-only shapes are imported as their outlines, text
    and images are skipped (all with a logged warning). ``limits`` bound the work per file (:class:`SvgLimits`).
    """
    if not (isinstance(tolerance, (int, float)) and math.isfinite(tolerance) and tolerance > 0):
        raise ConfigError(f"SVG flattening tolerance must be > 0 mm, got {tolerance!r}")
    if layer_by not in ("auto", "stroke", "group"):
        raise ConfigError(f"layer_by must be 'auto', 'stroke' or 'group', got {layer_by!r}")
    if limits is None:
        limits = SvgLimits()
    elif not isinstance(limits, SvgLimits):
        raise ConfigError(f"limits must be an SvgLimits, got {type(limits).__name__}")
    data, name = read_source(source, limits.max_bytes)
    doc, page, correction = _parse(data, name, limits)
    inkscape = doc is not None and _has_layers(doc) and layer_by in ("auto", "group")
    by_colour = layer_by == "stroke" or (layer_by == "auto" and not inkscape)
    flattener = _Flattener(name, tolerance, correction, limits)

    polylines: list[np.ndarray] = []
    colours: list[str] = []
    layer_keys: list[str] = []
    skipped: Counter[str] = Counter()
    for number, (element, layer) in enumerate(_walk(doc, layer_by == "group", inkscape) if doc else (), start=1):
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
        stroke, fill = _colour(element, "stroke"), _colour(element, "fill")
        if stroke is None and fill is None:
            skipped["element(s) with neither stroke nor fill skipped"] += 1
            continue
        if stroke is None:
            skipped["fill-only shape(s) imported as outlines"] += 1
        colour = stroke or fill
        for pts in flattener.element(element, _describe(element, number)):
            polylines.append(pts)
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
        page=page,
    )

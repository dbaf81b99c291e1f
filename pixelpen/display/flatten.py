"""Turn a Picture into device-space shapes: transformed, flattened to tolerance, dashed and clipped.

This is the device-independent half of every display: raster devices scan-convert the shapes,
vector devices turn them into pen strokes.  World coordinates go through each segment's transform
and the display's viewing pipeline; curves are flattened to the device's tolerance; markers keep
their size in millimetres whatever the transform; text is drawn with the stroke font.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from pixelpen import geometry as geo
from pixelpen.display.picture import (
    Arc,
    Bezier,
    BSpline,
    Circle,
    Ellipse,
    Image,
    Marker,
    Picture,
    Polygon,
    Polyline,
    Primitive,
    Rectangle,
    Style,
    Text,
)
from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.geometry.viewing import Rect

log = logging.getLogger(__name__)

TWO_PI = 2.0 * np.pi


@dataclass
class DeviceShape:
    """One primitive in device units: open polylines to stroke, rings to fill, or an image to map."""

    kind: Literal["stroke", "area", "image"]
    paths: list[np.ndarray]
    closed: bool
    style: Style
    image: Image | None = None
    matrix: np.ndarray = field(default_factory=lambda: np.eye(3))
    """World-to-device matrix the shape was made with (images use it to map their rectangle)."""
    clip_rect: tuple[float, float, float, float] | None = None
    """Device rectangle an image must be clipped to (paths arrive clipped already)."""


def flatten_picture(
    picture: Picture | Primitive,
    pipeline: geo.ViewingPipeline,
    *,
    tolerance: float,
    unit_mm: float,
    clip: bool = True,
) -> Iterator[DeviceShape]:
    """Yield the device-space shapes of every visible primitive, in drawing order.

    A primitive the geometry cannot draw (its device coordinates overflow, a dash pattern far finer than
    the device, an arc needing millions of points) raises ``InvalidArgument`` naming the item.
    """
    items = picture.walk() if isinstance(picture, Picture) else iter([(picture, np.eye(3), None)])
    rect = pipeline.clip_rect if clip else None
    for index, (prim, seg_transform, segment) in enumerate(items):
        try:
            matrix = geo.compose(pipeline.matrix, seg_transform)
            shapes = list(_shapes_of(prim, matrix, tolerance, unit_mm, rect))
        except InvalidArgument as exc:
            where = f"segment {segment.name!r}, " if segment is not None else ""
            raise InvalidArgument(f"cannot draw {where}visible item {index} ({type(prim).__name__}): {exc}") from exc
        yield from shapes


def _shapes_of(
    prim: Primitive, matrix: np.ndarray, tolerance: float, unit_mm: float, rect: Rect | None
) -> Iterator[DeviceShape]:
    """The device shapes of one primitive: strokes, clipped fill rings, or an image."""
    style = prim.style
    if isinstance(prim, Image):
        yield DeviceShape("image", [], False, style, image=prim, matrix=matrix, clip_rect=rect)
        return
    if isinstance(prim, Marker):
        paths = _marker_paths(geo.apply(matrix, prim.points), prim.kind, prim.size / unit_mm, tolerance)
        yield from _stroke(paths, style, unit_mm, rect, matrix)
        return
    world_tol = tolerance / max(geo.scale_factor(matrix), 1e-300)
    world_paths, closed = _world_paths(prim, world_tol)
    paths = [geo.apply(matrix, p) for p in world_paths]
    fill = style.fill
    if closed and fill is not None and fill.style != "hollow":
        rings = _clip_rings(paths, rect)
        if rings:
            yield DeviceShape("area", rings, True, style, matrix=matrix)
        if not fill.outline:
            return
    if closed:
        paths = [np.vstack([p, p[:1]]) for p in paths]
    yield from _stroke(paths, style, unit_mm, rect, matrix)


def _stroke(
    paths: list[np.ndarray], style: Style, unit_mm: float, rect: Rect | None, matrix: np.ndarray
) -> Iterator[DeviceShape]:
    """Device paths dashed by the style, clipped to ``rect``, as one stroke shape."""
    if style.dash:
        paths = geo.dash_polylines(paths, [d / unit_mm for d in style.dash])
    if rect is not None:
        paths = geo.clip_polylines(paths, rect)
    paths = [p for p in paths if len(p)]
    if paths:
        yield DeviceShape("stroke", paths, False, style, matrix=matrix)


def _clip_rings(rings: list[np.ndarray], rect: Rect | None) -> list[np.ndarray]:
    """Fill rings clipped to ``rect`` (Sutherland–Hodgman), dropping what vanishes."""
    if rect is None:
        return rings
    out: list[np.ndarray] = []
    for ring in rings:
        out.extend(geo.clip_polygon(ring, rect))
    return out


def _world_paths(prim: Primitive, tol: float) -> tuple[list[np.ndarray], bool]:
    """World-space polylines of a primitive and whether they are closed rings."""
    if isinstance(prim, Polyline):
        return [prim.points], False
    if isinstance(prim, Polygon):
        return [_open_ring(r) for r in prim.rings], True
    if isinstance(prim, Rectangle):
        x0, y0, x1, y1 = prim.x0, prim.y0, prim.x1, prim.y1
        return [np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float)], True
    if isinstance(prim, Circle):
        return [_open_ring(_arc(prim.center, prim.r, prim.r, 0.0, TWO_PI, 0.0, tol))], True
    if isinstance(prim, Ellipse):
        return [_open_ring(_arc(prim.center, prim.rx, prim.ry, 0.0, TWO_PI, prim.angle, tol))], True
    if isinstance(prim, Arc):
        pts = _arc(prim.center, prim.rx, prim.ry, prim.start, prim.end, prim.angle, tol)
        if prim.close == "open":
            return [pts], False
        if prim.close == "pie":
            pts = np.vstack([pts, np.asarray(prim.center, float)[None]])
        return [pts], True
    if isinstance(prim, Bezier):
        cp = prim.control_points
        deg = prim.degree or len(cp) - 1
        pieces = geo.flatten_beziers([cp[i : i + deg + 1] for i in range(0, len(cp) - 1, deg)], tol)
        return [np.vstack([pieces[0]] + [p[1:] for p in pieces[1:]])], False
    if isinstance(prim, BSpline):
        return [geo.flatten_bspline(prim.control_points, prim.degree, prim.knots, tolerance=tol)], False
    if isinstance(prim, Text):
        from pixelpen.vector.font import text_strokes

        strokes = text_strokes(
            prim.text, position=prim.position, height=prim.height, angle=prim.angle,
            slant=prim.slant, align=prim.align, valign=prim.valign,
        )
        return list(strokes), False
    raise InvalidArgumentType(f"cannot flatten a {type(prim).__name__}")


def _arc(center: tuple[float, float], rx: float, ry: float, start: float, end: float, angle: float,
         tol: float) -> np.ndarray:
    """A flattened arc; with a zero radius the ellipse is a segment or a point, drawn exactly through its extremes."""
    if rx > 0.0 and ry > 0.0:
        return geo.flatten_arc(center, rx, ry, start, end, angle=angle, tolerance=tol)
    sweep = float(np.clip(end - start, -TWO_PI, TWO_PI))
    quarters = np.arange(np.ceil(min(start, start + sweep) / (np.pi / 2)), max(start, start + sweep) / (np.pi / 2))
    u = np.unique(np.concatenate([[start, start + sweep], quarters * (np.pi / 2)]))
    u = u if sweep >= 0 else u[::-1]
    local = np.stack([rx * np.cos(u), ry * np.sin(u)], axis=1)
    return geo.apply(geo.compose(geo.translate(*center), geo.rotate(angle)), local)


def _open_ring(ring: np.ndarray) -> np.ndarray:
    """Drop a repeated closing vertex so every ring is stored open."""
    if len(ring) > 1 and np.allclose(ring[0], ring[-1]):
        return ring[:-1]
    return ring


_UNIT_SHAPES: dict[str, list[list[list[float]]]] = {
    "plus": [[[-1, 0], [1, 0]], [[0, -1], [0, 1]]],
    "cross": [[[-1, -1], [1, 1]], [[-1, 1], [1, -1]]],
    "star": [[[-1, 0], [1, 0]], [[0, -1], [0, 1]], [[-0.7, -0.7], [0.7, 0.7]], [[-0.7, 0.7], [0.7, -0.7]]],
    "square": [[[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]]],
    "diamond": [[[0, -1], [1, 0], [0, 1], [-1, 0], [0, -1]]],
}


def _marker_paths(centres: np.ndarray, kind: str, size: float, tolerance: float) -> list[np.ndarray]:
    """Marker strokes of ``size`` device units centred on each device-space point."""
    half = size / 2.0
    if kind == "dot":
        unit = [np.zeros((2, 2))]  # a zero-length stroke: one pixel, one pen dab
    elif kind == "circle":
        unit = [geo.flatten_arc((0.0, 0.0), 1.0, 1.0, 0.0, TWO_PI, tolerance=max(tolerance / max(half, 1e-9), 1e-3))]
    else:
        unit = [np.asarray(s, float) for s in _UNIT_SHAPES[kind]]
    return [u * half + c for c in centres for u in unit]

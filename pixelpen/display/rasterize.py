"""Scan-convert device-space shapes onto a raster Canvas (the raster half of every raster display)."""

from __future__ import annotations

import numpy as np

from pixelpen import geometry as geo
from pixelpen.display.flatten import DeviceShape
from pixelpen.display.picture import Fill, Image
from pixelpen.display.vectorize import device_angle
from pixelpen.geometry.hatch import hatch
from pixelpen.raster.canvas import Canvas

DEFAULT_HATCH_MM = 1.0
"""Hatch spacing on raster displays when the fill gives none."""


def rasterize(canvas: Canvas, shapes: list[DeviceShape], unit_mm: float) -> None:
    """Draw each shape onto ``canvas`` in order; device units are pixels, y down."""
    for shape in shapes:
        value = canvas.colour_value(shape.style.colour)
        if shape.kind == "stroke":
            _stroke(canvas, shape, value, unit_mm)
        elif shape.kind == "area":
            _area(canvas, shape, value, unit_mm)
        else:
            _image(canvas, shape)


def _stroke(canvas: Canvas, shape: DeviceShape, value: object, unit_mm: float) -> None:
    """Draw a stroke shape's polylines as lines of the style's width."""
    segments = [np.hstack([p[:-1], p[1:]]) if len(p) > 1 else np.hstack([p, p]) for p in shape.paths]
    seg = np.floor(np.concatenate(segments)).astype(np.int64)
    width = max(1, round(float(shape.style.width / unit_mm)))
    canvas.lines(seg, value, width=width)


def _area(canvas: Canvas, shape: DeviceShape, value: object, unit_mm: float) -> None:
    """Fill an area shape: solid, hatched or patterned."""
    fill: Fill = shape.style.fill  # type: ignore[assignment]
    if fill.style == "solid":
        canvas.polygons([shape.paths], value, rule="evenodd")
    elif fill.style in ("hatch", "crosshatch"):
        spacing = (fill.spacing or DEFAULT_HATCH_MM) / unit_mm
        angle = device_angle(fill.angle, shape.matrix)
        lines = hatch(shape.paths, spacing, angle, cross=fill.style == "crosshatch", join=False)
        if lines:
            segs = np.concatenate([np.hstack([p[:-1], p[1:]]) for p in lines if len(p) > 1])
            canvas.lines(np.floor(segs).astype(np.int64), value)
    else:
        _pattern(canvas, shape.paths, np.asarray(fill.pattern, dtype=bool), value)


def _pattern(canvas: Canvas, rings: list[np.ndarray], cells: np.ndarray, value: object) -> None:
    """Fill the rings with a pattern of cells tiled from the canvas origin."""
    mask = Canvas(canvas.width, canvas.height, "1")
    mask.polygons([rings], 1, rule="evenodd")
    ys, xs = np.nonzero(mask.array)
    on = cells[ys % cells.shape[0], xs % cells.shape[1]]
    canvas.array[ys[on], xs[on]] = canvas.value(value)
    if len(ys):
        canvas.mark_damaged(int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)


def _image(canvas: Canvas, shape: DeviceShape) -> None:
    """Map an image onto its world rectangle by inverse mapping each covered pixel (nearest sample)."""
    img: Image = shape.image  # type: ignore[assignment]
    x0, y0, x1, y1 = img.rect
    h, w = img.pixels.shape[:2]
    # world point of the image's top-left corner is (x0, y1); columns run +x, rows run -y
    img_to_world = geo.compose(geo.translate(x0, y1), geo.scale((x1 - x0) / w, -(y1 - y0) / h))
    img_to_dev = geo.compose(shape.matrix, img_to_world)
    corners = geo.apply(img_to_dev, np.array([[0, 0], [w, 0], [w, h], [0, h]], float))
    x_lo, y_lo, x_hi, y_hi = shape.clip_rect or (0, 0, canvas.width, canvas.height)
    bound_lo = np.maximum([np.ceil(x_lo - 0.5), np.ceil(y_lo - 0.5)], 0).astype(int)
    bound_hi = np.minimum([np.floor(x_hi - 0.5) + 1, np.floor(y_hi - 0.5) + 1], [canvas.width, canvas.height]).astype(
        int
    )
    lo = np.clip(np.floor(corners.min(axis=0)).astype(int), bound_lo, bound_hi)
    hi = np.clip(np.ceil(corners.max(axis=0)).astype(int), bound_lo, bound_hi)
    if (hi <= lo).any():
        return
    gy, gx = np.mgrid[lo[1] : hi[1], lo[0] : hi[0]]
    centres = np.column_stack([gx.ravel() + 0.5, gy.ravel() + 0.5])
    src = geo.apply(geo.invert(img_to_dev), centres)
    col, row = np.floor(src[:, 0]).astype(np.int64), np.floor(src[:, 1]).astype(np.int64)
    inside = (col >= 0) & (col < w) & (row >= 0) & (row < h)
    rgb = _as_rgba(img.pixels)[row[inside], col[inside]]
    canvas.put_colours(gx.ravel()[inside], gy.ravel()[inside], rgb)


def _as_rgba(px: np.ndarray) -> np.ndarray:
    if px.ndim == 2:
        px = np.repeat(px[..., None], 3, axis=2)
    if px.shape[2] == 3:
        px = np.concatenate([px, np.full((*px.shape[:2], 1), 255, np.uint8)], axis=2)
    return px

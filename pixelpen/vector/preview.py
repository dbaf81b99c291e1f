"""Previews of a display list as PNG (Pillow) or SVG: pen-down strokes in pen colours, pen-up travel faint and dashed.

A sheet preview adds outlines (the paper, a plotter's hard-clip limits) and what will be cut (the parts of the
drawing outside the limits) in a warning colour beneath the strokes that will be drawn.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from pixelpen.colour import parse_colour
from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList

DEFAULT_SIZE_PX = 1000
"""Longest side of a preview when no size is given."""
MARGIN = 0.03
"""Blank border around the drawing, as a fraction of the longest side."""
TRAVEL_COLOUR = "#f08080"
BACKGROUND = "#ffffff"
CUT_COLOUR = "#ff8c00"
"""Colour of the parts of a drawing that fall outside the plotter's limits and will not be drawn."""
CUT_WIDTH_PX = 3
"""Least width in pixels of the cut parts, so they show beside thin strokes."""

Frame = tuple[tuple[float, float, float, float], str]
"""An outline to draw: rectangle (x0, y0, x1, y1) in display-list units and its colour."""


def _outlines(frames: Sequence[Frame], cut: DisplayList | None, unit_mm: float) -> DisplayList:
    """The frames as closed strokes (one pen per colour) followed by the cut parts in the warning colour."""
    cut_strokes = [] if cut is None else list(cut.strokes())
    colours = list(dict.fromkeys([c for _, c in frames] + ([CUT_COLOUR] if cut_strokes else [])))
    pen = {c: k + 1 for k, c in enumerate(colours)}
    rings = [np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]], float) for (x0, y0, x1, y1), _ in frames]
    pens = [pen[c] for _, c in frames] + [pen.get(CUT_COLOUR, 0)] * len(cut_strokes)
    polys = rings + cut_strokes
    colour_of = {v: k for k, v in pen.items()}
    return DisplayList.from_polylines(polys, pens=pens or 1, unit_mm=unit_mm, pen_colours=colour_of)


def _travel(dl: DisplayList, home: tuple[float, float]) -> np.ndarray:
    """(S, 4) pen-up moves: from home to the first stroke, then from each stroke's end to the next one's start."""
    if not len(dl):
        return np.zeros((0, 4))
    froms = np.vstack([np.asarray(home, dtype=np.float64)[None], dl.ends[:-1]])
    return np.hstack([froms, dl.starts])


def _frame(dl: DisplayList, under: DisplayList, travel: np.ndarray, size_px: int) -> tuple[np.ndarray, float, int, int]:
    """Drawing-space minimum corner, pixels per unit, and the image size in pixels."""
    pts = [dl.points, under.points] + ([travel[:, :2], travel[:, 2:]] if len(travel) else [])
    allp = np.concatenate(pts) if sum(len(p) for p in pts) else np.zeros((1, 2))
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    span = np.maximum(hi - lo, 1e-9)
    longest = float(span.max())
    lo = lo - MARGIN * longest
    span = span + 2 * MARGIN * longest
    scale = size_px / float(span.max())
    w, h = (max(1, math.ceil(s * scale)) for s in span)
    return lo, scale, w, h


def render_preview(
    dl: DisplayList,
    path: str | os.PathLike,
    *,
    size_px: int | None = None,
    show_travel: bool = True,
    home: tuple[float, float] = (0.0, 0.0),
    pen_width_mm: float | None = None,
    y_up: bool = False,
    frames: Sequence[Frame] = (),
    cut: DisplayList | None = None,
) -> None:
    """Write a preview of ``dl`` to ``path``: PNG (or any raster format Pillow knows) or SVG, by extension.

    ``size_px`` is the longest side (default 1000 px); strokes are drawn in their pens' colours
    (``dl.pen_colours``, black when missing), ``pen_width_mm`` wide (default one pixel); pen-up moves from
    ``home`` through the strokes in order are drawn faint (and dashed in SVG) when ``show_travel``. Device y
    grows downwards in the picture unless ``y_up``. ``frames`` are outlines drawn first; ``cut`` (strokes in
    the units of ``dl``, typically the whole drawing before clipping) is drawn under the strokes in
    :data:`CUT_COLOUR`, so whatever of it ``dl`` does not cover shows as cut.
    """
    size = DEFAULT_SIZE_PX if size_px is None else size_px
    if not isinstance(size, int) or not 16 <= size <= 20000:
        raise ConfigError(f"preview size must be an integer of 16..20000 pixels, got {size_px!r}")
    if pen_width_mm is not None and not pen_width_mm > 0:
        raise ConfigError(f"pen width must be > 0 mm, got {pen_width_mm!r}")
    travel = _travel(dl, home) if show_travel else np.zeros((0, 4))
    under = _outlines(frames, cut, dl.unit_mm)
    lo, scale, w, h = _frame(dl, under, travel, size)
    suffix = Path(path).suffix.lower()
    if suffix == ".svg":
        _write_svg(dl, under, path, travel, lo, scale, w, h, pen_width_mm, y_up)
        return
    fmt = Image.registered_extensions().get(suffix)
    if fmt is None:
        raise ConfigError(f"preview file must end in .svg or an image extension such as .png, got {os.fspath(path)!r}")

    def to_px(p: np.ndarray) -> np.ndarray:
        q = (p - lo) * scale
        if y_up:
            q[:, 1] = h - q[:, 1]
        return q

    img = Image.new("RGB", (w, h), BACKGROUND)
    draw = ImageDraw.Draw(img)
    width_px = 1 if pen_width_mm is None else max(1, round(pen_width_mm / dl.unit_mm * scale))
    cut_pen = next((p for p, c in under.pen_colours.items() if c == CUT_COLOUR), None)
    _draw_strokes(draw, under, to_px(under.points),
                  lambda pen: max(CUT_WIDTH_PX, width_px + 2) if pen == cut_pen else 1)
    for seg in to_px(travel.reshape(-1, 2)).reshape(-1, 4):
        draw.line(seg.tolist(), fill=TRAVEL_COLOUR, width=1)
    _draw_strokes(draw, dl, to_px(dl.points), lambda pen: width_px)
    img.save(path, format=fmt)


def _draw_strokes(draw: ImageDraw.ImageDraw, dl: DisplayList, px: np.ndarray, width_of) -> None:
    """Draw every stroke of ``dl`` (points ``px`` in pixels) in its pen's colour, ``width_of(pen)`` pixels wide."""
    for i in range(len(dl)):
        pts = px[dl.offsets[i]: dl.offsets[i + 1]]
        pen = int(dl.pens[i])
        colour = parse_colour(dl.pen_colours.get(pen, "#000000"))
        width_px = width_of(pen)
        if len(pts) == 1 or np.all(pts == pts[0]):
            r = width_px / 2
            draw.ellipse([pts[0, 0] - r, pts[0, 1] - r, pts[0, 0] + r, pts[0, 1] + r], fill=colour)
        else:
            draw.line(pts.ravel().tolist(), fill=colour, width=width_px, joint="curve" if width_px > 2 else None)


def _write_svg(
    dl: DisplayList, under: DisplayList, path: str | os.PathLike, travel: np.ndarray, lo: np.ndarray, scale: float,
    w: int, h: int, pen_width_mm: float | None, y_up: bool,
) -> None:
    """The SVG preview: viewBox in display-list units, one path per pen, travel as a dashed path."""
    vw, vh = w / scale, h / scale
    flip = f' transform="matrix(1 0 0 -1 0 {2 * lo[1] + vh:.10g})"' if y_up else ""
    stroke_w = (pen_width_mm / dl.unit_mm) if pen_width_mm is not None else 1.0 / scale
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        (f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
         f'viewBox="{lo[0]:.10g} {lo[1]:.10g} {vw:.10g} {vh:.10g}">'),
        f'<rect x="{lo[0]:.10g}" y="{lo[1]:.10g}" width="{vw:.10g}" height="{vh:.10g}" fill="{BACKGROUND}"/>',
        f'<g{flip} fill="none" stroke-linecap="round" stroke-linejoin="round">',
    ]
    for pen, colour in sorted(under.pen_colours.items()):
        width = max(CUT_WIDTH_PX / scale, stroke_w * 1.5) if colour == CUT_COLOUR else 1.0 / scale
        out.append(_svg_path(under, pen, width, ' class="cut"' if colour == CUT_COLOUR else ' class="frame"'))
    if len(travel):
        d = " ".join(f"M{a:.10g},{b:.10g} {c:.10g},{e:.10g}" for a, b, c, e in travel.tolist())
        out.append(
            f'<path d="{d}" stroke="{TRAVEL_COLOUR}" stroke-width="{1.0 / scale:.10g}" '
            f'stroke-dasharray="{4.0 / scale:.10g} {3.0 / scale:.10g}"/>'
        )
    for pen in sorted(set(dl.pens.tolist())):
        out.append(_svg_path(dl, pen, stroke_w))
    out.append("</g>\n</svg>\n")
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(out))


def _svg_path(dl: DisplayList, pen: int, width: float, attrs: str = "") -> str:
    """One ``<path>`` of every stroke of ``pen`` in its colour (a dot as a zero-length line)."""
    parts = []
    for i in np.flatnonzero(dl.pens == pen):
        pts = dl.stroke(int(i))
        if len(pts) == 1:
            pts = np.vstack([pts, pts])
        parts.append("M" + ("%.10g,%.10g " * len(pts) % tuple(pts.ravel())).strip())
    colour = dl.pen_colours.get(int(pen), "#000000")
    return f'<path{attrs} d="{" ".join(parts)}" stroke="{colour}" stroke-width="{width:.10g}"/>'

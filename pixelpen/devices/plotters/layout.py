"""A drawing laid on a plotter's sheet: read from SVG or picture JSON, rotated, scaled, centred, clipped to the limits.

An SVG page is laid on the paper the way the profile says the paper sits under the pen (``origin_mm``: where the
device origin lies on the sheet), true size.  :class:`Layout` then acts in sheet millimetres, in vpype's order:
rotate, scale (or fit), centre in the box (the page less the margin, within the plotter's limits).
:func:`prepare_drawing` gives the drawing in device units, clipped to the device, and its :class:`Placement`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pixelpen import geometry as geo
from pixelpen.errors import ConfigError, ParseError
from pixelpen.urls import PAPER_MM, parse_size, to_mm
from pixelpen.vector.displaylist import DisplayList

if TYPE_CHECKING:  # the display classes import pyserial: a layout alone does not need them
    from pixelpen.devices.plotters.base import PlotterDisplay

CLIP_EPS = 1e-9
"""Relative slack of the device rectangle when clipping: rounding noise on an edge is not a cut."""
CUT_REPORT_MM = 1e-3
"""Clipped lengths below this (rounding noise) are not reported."""


def page_to_world(display: PlotterDisplay) -> np.ndarray:
    """3x3 matrix from SVG page millimetres (top-left origin, y down) to the display's world (mm, y up).

    The profile's paper says where the device origin lies on the sheet (``origin_mm`` from the sheet's top
    left, or bottom left with ``origin_reference = "botleft"``); without it the sheet's top-left corner is
    laid on the plottable area's top-left corner.  World coordinates are millimetres from the plottable
    area's lower-left corner, which is the device origin on a y-up device and lies ``height`` below it on
    a y-down device.
    """
    height_mm = display.capabilities.size_mm[1]
    y_up = not display.capabilities.y_down
    paper = display.paper
    if paper.origin_mm is None:
        ox, oy = 0.0, (height_mm if y_up else 0.0)
    else:
        ox, oy = paper.origin_mm
        if paper.origin_reference == "botleft":
            if paper.size_mm is None:
                raise ConfigError(f"{display.profile.name}: paper {paper.name!r} gives its origin from the bottom "
                                  "left but no size_mm, so the sheet cannot be placed")
            oy = paper.size_mm[1] - oy
    # y up: world = (x - ox, oy - y); y down: device y = y - oy and world y = height - device y
    ty = oy if y_up else height_mm + oy
    return np.array([[1.0, 0.0, -ox], [0.0, -1.0, ty], [0.0, 0.0, 1.0]])


def sheet_to_device(display: PlotterDisplay) -> np.ndarray:
    """3x3 matrix from sheet millimetres (the sheet's top left, y down) to device units, through the default window."""
    return geo.compose(display.pipeline.matrix, page_to_world(display))


@dataclass(frozen=True)
class Layout:
    """How a drawing is laid on the sheet, in this order (vpype's): rotate, scale (or fit), then centre in the box.

    All in sheet millimetres (origin at the sheet's top left, y down the sheet).  ``rotate_deg`` turns the
    drawing clockwise about the centre of its bounds; ``scale`` scales it about that centre; ``fit`` instead
    scales it to fill the box; ``center`` (implied by ``fit``) moves the centre of its bounds to the box's
    centre.  The box is the page less ``margin_mm`` on every side, within the plotter's limits.  The page is
    ``page`` (a paper name or ``WxH[mm|cm|in]``; a paper name takes the orientation of the plotter's paper)
    or the plotter's paper; ``orientation`` ``"landscape"`` or ``"portrait"`` turns the page that way.
    Without ``center`` or ``fit`` the drawing stays where its file puts it (an SVG's page on the sheet).
    """

    rotate_deg: float = 0.0
    scale: float = 1.0
    fit: bool = False
    center: bool = False
    margin_mm: float = 0.0
    page: str | None = None
    orientation: str | None = None

    def __post_init__(self) -> None:
        if self.fit and self.scale != 1.0:
            raise ConfigError("give --scale or --fit, not both (--fit chooses the scale)")
        if self.margin_mm and not (self.center or self.fit):
            raise ConfigError("--margin places the drawing only with --center or --fit")
        if self.orientation not in (None, "landscape", "portrait"):
            raise ConfigError(f"orientation must be landscape or portrait, got {self.orientation!r}")

    def page_size(self, display: PlotterDisplay) -> tuple[float, float]:
        """The page in millimetres (width, height) as it lies under the pen."""
        paper = display.paper.size_mm or display.capabilities.size_mm
        if self.page is None:
            w, h = paper
        else:
            try:
                w, h, unit = parse_size(self.page, "mm")
                w, h = to_mm(w, unit), to_mm(h, unit)
            except (ValueError, KeyError) as exc:
                raise ConfigError(f"--page {self.page}: {exc}") from None
            if not (math.isfinite(w) and math.isfinite(h)):
                raise ConfigError(f"--page {self.page}: the size must be finite")
            if self.page.strip().lower() in PAPER_MM and (w > h) != (paper[0] > paper[1]):
                w, h = h, w
        if self.orientation is not None and (w > h) != (self.orientation == "landscape") and w != h:
            w, h = h, w
        return float(w), float(h)

    def matrix(self, points: np.ndarray, box: tuple[float, float, float, float]) -> tuple[np.ndarray, float]:
        """The 3x3 layout transform of sheet-millimetre ``points`` into ``box`` and its scale factor."""
        if not len(points):
            return np.eye(3), 1.0
        lo, hi = points.min(axis=0), points.max(axis=0)
        rot = geo.rotate(math.radians(self.rotate_deg), about=(lo + hi) / 2)
        turned = geo.apply(rot, points)
        lo, hi = turned.min(axis=0), turned.max(axis=0)
        centre = (lo + hi) / 2
        factor = self.scale
        if self.fit:
            extent = hi - lo
            room = np.array([box[2] - box[0], box[3] - box[1]])
            ratios = room[extent > 0] / extent[extent > 0]
            factor = float(ratios.min()) if len(ratios) else 1.0
        moved = np.array([(box[0] + box[2]) / 2, (box[1] + box[3]) / 2]) if self.center or self.fit else centre
        return geo.compose(geo.translate(*(moved - centre)), geo.scale(factor, factor, about=centre), rot), factor


@dataclass
class Placement:
    """Where a drawing lands on the sheet (sheet millimetres) and what the plotter's limits cut off."""

    page_mm: tuple[float, float]
    limits: tuple[float, float, float, float]
    box: tuple[float, float, float, float]
    bounds: tuple[float, float, float, float] | None
    scale: float
    rotate_deg: float
    total_mm: float
    cut_mm: float

    def lines(self) -> list[str]:
        """The placement in words, for a dry run."""
        w, h = self.page_mm
        x0, y0, x1, y1 = self.limits
        out = [f"page: {w:g} x {h:g} mm; the plotter reaches x {x0:.1f}..{x1:.1f}, y {y0:.1f}..{y1:.1f} mm "
               "from the page's top left"]
        if self.bounds is not None:
            bx0, by0, bx1, by1 = self.bounds
            how = [f"rotated {self.rotate_deg:g} deg"] if self.rotate_deg else []
            how += [f"scaled {self.scale:.4g}x"] if self.scale != 1.0 else []
            out.append(f"drawing: {bx1 - bx0:.1f} x {by1 - by0:.1f} mm at x {bx0:.1f}..{bx1:.1f}, "
                       f"y {by0:.1f}..{by1:.1f} mm" + (f" ({', '.join(how)})" if how else ""))
        share = 100.0 * self.cut_mm / self.total_mm if self.total_mm else 0.0
        out.append(f"clipped: {self.cut_mm:.1f} mm of {self.total_mm:.1f} mm of lines ({share:.1f} %) "
                   "lie outside the plotter's limits" if self.cut_mm > CUT_REPORT_MM else "clipped: nothing")
        return out


def _svg_drawing(path: str, display: PlotterDisplay, layers: Sequence[str] | None, tolerance: float) -> DisplayList:
    """An SVG as a display list in the display's device units, unclipped and as its page lies on the sheet."""
    from pixelpen.colour import parse_colour
    from pixelpen.display.vectorize import nearest_pen
    from pixelpen.vector.svgimport import read_svg

    dl = _select_layers(read_svg(path, tolerance=tolerance), layers, path)
    points = geo.apply(sheet_to_device(display), dl.points) if len(dl.points) else dl.points
    caps = display.capabilities
    pens, colours = dl.pens, dict(dl.pen_colours)
    if len(caps.pens) > 1:  # a carousel: each SVG colour takes the loaded pen nearest to it
        carousel = {p: nearest_pen(parse_colour(c), caps.pens) for p, c in dl.pen_colours.items()}
        pens = np.array([carousel.get(int(p), int(p)) for p in dl.pens], dtype=np.int32)
        colours = {p: caps.pens[p - 1] for p in set(carousel.values())}
    return DisplayList(points, dl.offsets, pens, dl.layers, dict(dl.layer_names), caps.unit_mm, colours)


def _picture_drawing(path: str, display: PlotterDisplay, layers: Sequence[str] | None, tolerance: float) -> DisplayList:
    """A picture file as a display list in the display's device units, unclipped (its window fills the paper)."""
    from pixelpen.display.flatten import flatten_picture
    from pixelpen.display.pictfile import load_picture
    from pixelpen.display.vectorize import PenLayerMap, build_display_list

    picture = load_picture(path)
    if picture.window:
        display.window(*picture.window)
    caps = display.capabilities
    shapes = flatten_picture(picture, display.pipeline, tolerance=tolerance, unit_mm=caps.unit_mm, clip=False)
    mapping = PenLayerMap(list(caps.pens) if len(caps.pens) > 1 else None)
    dl = build_display_list(shapes, unit_mm=caps.unit_mm, pen_width_mm=display.pen_width_mm, mapping=mapping)
    return _select_layers(dl, layers, path)


def _select_layers(dl: DisplayList, wanted: Sequence[str] | None, source: str) -> DisplayList:
    """Only the strokes of the layers named (by number or, ignoring case, by name)."""
    if not wanted:
        return dl
    ids = sorted(set(dl.layers.tolist()))
    by_name = {dl.layer_names.get(i, str(i)).lower(): i for i in ids}
    chosen = set()
    for token in wanted:
        key = token.strip()
        if key.isdecimal() and key.isascii() and int(key) in ids:
            chosen.add(int(key))
        elif key.lower() in by_name:
            chosen.add(by_name[key.lower()])
        else:
            known = ", ".join(f"{i} ({dl.layer_names.get(i, i)})" for i in ids) or "none"
            raise ConfigError(f"{source}: no layer {token!r}; layers: {known}")
    return dl.select(np.isin(dl.layers, sorted(chosen)))


def load_drawing(path: str, display: PlotterDisplay, *, layers: Sequence[str] | None = None,
                 tolerance: float = 0.05, detail: float = 1.0) -> DisplayList:
    """Read an SVG or picture JSON into the display's device units (unclipped, true size, as the file places it).

    ``detail`` > 1 flattens curves that much finer (for a drawing that will be scaled up by that factor).
    """
    suffix = Path(path).suffix.lower()
    if suffix == ".svg":
        return _svg_drawing(path, display, layers, tolerance / detail)
    if suffix == ".json":
        return _picture_drawing(path, display, layers, display.capabilities.tolerance / detail)
    raise ParseError("expected an SVG (.svg) or a pixelpen picture (.json)", source=path, token=suffix or "no suffix")


def clip_to_device(dl: DisplayList, size: tuple[float, float]) -> tuple[DisplayList, float]:
    """Clip the strokes to the device rectangle 0..W x 0..H (device units); return the result and the length cut.

    A stroke leaving and re-entering becomes several strokes; pens and layers are kept.  Points within
    rounding error of an edge (a drawing fitted to the paper touches it) count as inside.
    """
    if not len(dl):
        return dl, 0.0
    width, height = float(size[0]), float(size[1])
    eps = CLIP_EPS * max(width, height)
    pieces, owner = geo.clip_polylines(list(dl.strokes()), (-eps, -eps, width + eps, height + eps),
                                       return_index=True)
    pieces = [np.clip(p, 0.0, [width, height]) for p in pieces]
    clipped = DisplayList.from_polylines(pieces, pens=dl.pens[owner] if len(owner) else 1,
                                         layers=dl.layers[owner] if len(owner) else 0, layer_names=dl.layer_names,
                                         unit_mm=dl.unit_mm, pen_colours=dl.pen_colours)
    return clipped, max(0.0, dl.pen_down_length() - clipped.pen_down_length())


def _rect(points: np.ndarray) -> tuple[float, float, float, float]:
    lo, hi = points.min(axis=0), points.max(axis=0)
    return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])


def prepare_drawing(path: str, display: PlotterDisplay, *, layout: Layout = Layout(),
                    layers: Sequence[str] | None = None, tolerance: float = 0.05) -> tuple[DisplayList, Placement]:
    """The drawing in device units, laid out on the sheet and clipped to the device; where it landed."""
    to_device = sheet_to_device(display)  # before a picture's window changes the display's pipeline
    to_sheet = geo.invert(to_device)
    limits = _rect(geo.apply(to_sheet, np.array([[0.0, 0.0], display.capabilities.size])))
    page = layout.page_size(display)
    m = layout.margin_mm
    box = (max(m, limits[0]), max(m, limits[1]), min(page[0] - m, limits[2]), min(page[1] - m, limits[3]))
    if box[0] >= box[2] or box[1] >= box[3]:
        raise ConfigError(f"a {page[0]:g} x {page[1]:g} mm page less {m:g} mm margins leaves no room within the "
                          f"{display.profile.name}'s limits")
    dl = load_drawing(path, display, layers=layers, tolerance=tolerance)
    matrix, factor = layout.matrix(geo.apply(to_sheet, dl.points) if len(dl.points) else dl.points, box)
    if factor > 1.0 + 1e-9:  # scaled up: flatten the curves finer, so they stay within the tolerance on paper
        dl = load_drawing(path, display, layers=layers, tolerance=tolerance, detail=factor)
    if len(dl.points) and not np.allclose(matrix, np.eye(3)):
        dl = replace(dl, points=geo.apply(geo.compose(to_device, matrix, to_sheet), dl.points))
    total = dl.pen_down_length() * dl.unit_mm
    bounds = _rect(geo.apply(to_sheet, dl.points)) if len(dl.points) else None
    dl, cut = clip_to_device(dl, display.capabilities.size)
    placement = Placement(page, limits, box, bounds, factor, layout.rotate_deg, total, cut * dl.unit_mm)
    if not len(dl):
        raise ConfigError(f"{path}: nothing to plot" + (" inside the plotter's limits" if total else ""))
    return dl, placement


def home_of(display: PlotterDisplay) -> tuple[float, float]:
    """The profile's home in the display list's frame (device units from the plottable area's corner)."""
    home = np.asarray(display.profile.home, float) - [display.paper.x_range[0], display.paper.y_range[0]]
    return float(home[0]), float(home[1])

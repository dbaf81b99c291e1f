"""Device-space shapes (flattened from a Picture) to a display list: strokes as they are, areas hatched, pens chosen."""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable, Sequence
from typing import Protocol

import numpy as np

from pixelpen.colour import colour_hex, parse_colour
from pixelpen.display.picture import Style
from pixelpen.errors import ConfigError
from pixelpen.geometry.hatch import hatch
from pixelpen.vector.displaylist import DisplayList

log = logging.getLogger(__name__)

DEFAULT_LAYER = "default"
"""Name of the layer for shapes whose style names none."""


class ShapeLike(Protocol):
    """What build_display_list reads of a ``pixelpen.display.flatten.DeviceShape``."""

    @property
    def kind(self) -> str:
        """"stroke" or "area" (other kinds are skipped)."""

    @property
    def paths(self) -> list[np.ndarray]:
        """Polylines or rings in device units."""

    @property
    def closed(self) -> bool:
        """Whether the paths are closed rings."""

    @property
    def style(self) -> Style:
        """The primitive's attributes.

        Also read when present: ``matrix``, the 3x3 world-to-device transform (maps the hatch angle).
        """


def nearest_pen(colour: tuple[int, int, int], pens: Sequence[str]) -> int:
    """1-based number of the pen whose colour (``#rrggbb``) is nearest ``colour`` in RGB (ties: lowest number)."""
    if not pens:
        raise ConfigError("no pens to choose from")
    rgb = np.array([parse_colour(p) for p in pens], dtype=np.float64)
    d = np.sum((rgb - np.asarray(colour, dtype=np.float64)) ** 2, axis=1)
    return int(np.argmin(d)) + 1


class PenLayerMap:
    """Pen numbers and layer ids for styles, kept across builds so that all strokes of a display agree.

    Pens: ``style.pen``, else the nearest of ``pens``, else one pen per distinct colour in order of
    appearance. Layers: ``style.layer`` (unnamed shapes in ``default``), ids in order of appearance.
    """

    def __init__(self, pens: Sequence[str] | None = None) -> None:
        self.pens = [colour_hex(parse_colour(p)) for p in pens] if pens is not None else None
        if self.pens is not None and not self.pens:
            raise ConfigError("pens must list at least one colour")
        self.colours: dict[int, str] = {i + 1: c for i, c in enumerate(self.pens or [])}
        self._by_colour: dict[tuple[int, int, int], int] = {}
        self.layer_ids: dict[str, int] = {}

    def layer(self, style: Style) -> int:
        """The layer id of a style."""
        return self.layer_ids.setdefault(style.layer or DEFAULT_LAYER, len(self.layer_ids) + 1)

    def pen(self, style: Style) -> int:
        """The pen number of a style."""
        if style.pen is not None:
            if self.pens is not None and style.pen > len(self.pens):
                raise ConfigError(f"style asks for pen {style.pen} but only {len(self.pens)} pens are loaded")
            self.colours.setdefault(style.pen, colour_hex(style.colour))
            return style.pen
        if style.colour not in self._by_colour:
            if self.pens is not None:
                self._by_colour[style.colour] = nearest_pen(style.colour, self.pens)
            else:
                taken = set(self.colours)
                number = next(n for n in range(1, len(taken) + 2) if n not in taken)
                self._by_colour[style.colour] = number
                self.colours[number] = colour_hex(style.colour)
        return self._by_colour[style.colour]


def _fill_lines(shape: ShapeLike, unit_mm: float, pen_width_mm: float, join: bool) -> list[np.ndarray]:
    """Hatch lines for an area shape according to its style's fill."""
    fill = shape.style.fill
    if fill is None or fill.style == "hollow":
        return []
    if fill.style == "solid":
        spacing_mm, angle, cross = pen_width_mm, 0.0, False
    else:  # hatch, crosshatch; a raster pattern is drawn as a hatch on a plotter
        spacing_mm = fill.spacing if fill.spacing is not None else pen_width_mm
        angle, cross = device_angle(fill.angle, getattr(shape, "matrix", None)), fill.style == "crosshatch"
    return hatch(list(shape.paths), spacing_mm / unit_mm, angle, cross=cross, join=join)


def device_angle(angle: float, matrix: np.ndarray | None) -> float:
    """The device-space direction of a world-space ``angle`` under a 3x3 world-to-device ``matrix``."""
    if matrix is None:
        return angle
    d = np.asarray(matrix, dtype=np.float64)[:2, :2] @ np.array([math.cos(angle), math.sin(angle)])
    if not np.all(np.isfinite(d)) or not np.any(d):
        return angle
    return math.atan2(d[1], d[0])


def build_display_list(
    shapes: Iterable[ShapeLike],
    *,
    unit_mm: float,
    pens: Sequence[str] | None = None,
    pen_width_mm: float = 0.3,
    join: bool = True,
    mapping: PenLayerMap | None = None,
) -> DisplayList:
    """Turn device-space shapes into a display list in device units.

    ``stroke`` paths are drawn as given (closed ones back to their start); ``area`` rings (even-odd) are filled
    per ``style.fill``: hollow draws nothing, solid hatches at the pen width, hatch/crosshatch at the fill's
    angle (world radians, mapped through the shape's ``matrix`` when it has one) and spacing (mm, default the
    pen width), pattern as a hatch; ``image`` shapes cannot be drawn by a
    pen and are skipped with one warning. The pen is ``style.pen``, else the one of ``pens`` (``#rrggbb``
    colours of pens 1, 2, ...) nearest ``style.colour``, else one pen per distinct colour in order of
    appearance. Layers come from ``style.layer`` (ids in order of appearance, unnamed shapes in ``default``).
    Pass the same ``mapping`` to successive builds to keep pen numbers and layer ids consistent.
    """
    if not (isinstance(unit_mm, (int, float)) and math.isfinite(unit_mm) and unit_mm > 0):
        raise ConfigError(f"device unit must be > 0 mm, got {unit_mm!r}")
    if not (isinstance(pen_width_mm, (int, float)) and math.isfinite(pen_width_mm) and pen_width_mm > 0):
        raise ConfigError(f"pen width must be > 0 mm, got {pen_width_mm!r}")
    chooser = mapping if mapping is not None else PenLayerMap(pens)
    polylines: list[np.ndarray] = []
    pen_of: list[int] = []
    layer_of: list[int] = []
    images = 0
    for n, shape in enumerate(shapes):
        if shape.kind == "image":
            images += 1
            continue
        if shape.kind == "stroke":
            lines = []
            for p in shape.paths:
                arr = np.asarray(p, dtype=np.float64).reshape(-1, 2)
                if shape.closed and len(arr) > 1 and not np.array_equal(arr[0], arr[-1]):
                    arr = np.vstack([arr, arr[:1]])
                lines.append(arr)
        elif shape.kind == "area":
            lines = _fill_lines(shape, unit_mm, pen_width_mm, join)
        else:
            raise ConfigError(f"shape {n}: kind must be 'stroke', 'area' or 'image', got {shape.kind!r}")
        lines = [ln for ln in lines if len(ln)]
        if not lines:
            continue
        for arr in lines:
            if not np.isfinite(arr).all():
                raise ConfigError(f"shape {n} ({shape.kind}) has a non-finite coordinate")
        pen = chooser.pen(shape.style)
        layer = chooser.layer(shape.style)
        polylines.extend(lines)
        pen_of.extend([pen] * len(lines))
        layer_of.extend([layer] * len(lines))
    if images:
        log.warning("%d image shape(s) skipped: a vector device cannot draw raster images", images)
    used, used_layers = set(pen_of), set(layer_of)
    return DisplayList.from_polylines(
        polylines,
        pens=pen_of,
        layers=layer_of,
        layer_names={i: name for name, i in chooser.layer_ids.items() if i in used_layers},
        unit_mm=float(unit_mm),
        pen_colours={p: c for p, c in chooser.colours.items() if p in used},
    )

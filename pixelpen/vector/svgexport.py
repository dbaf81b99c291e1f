"""Display lists to SVG: one Inkscape layer per layer, one path per stroke, in the drawing's true size."""

from __future__ import annotations

import io
import math
import os
from collections import Counter
from typing import IO
from xml.sax.saxutils import quoteattr

import numpy as np

from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList

__all__ = ["INKSCAPE_NS", "write_svg"]

INKSCAPE_NS = "http://www.inkscape.org/namespaces/inkscape"
"""Inkscape's namespace: its layers are groups with ``inkscape:groupmode="layer"``."""


def _num(x: float) -> str:
    """A coordinate as SVG text: up to 10 significant digits."""
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
    is ``size_mm`` (width, height) from the origin, else the display list's ``page``, else it reaches from the
    origin (or the drawing's minimum, if negative) to the drawing's maximum. Single-point strokes are written as
    zero-length lines.
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
    elif dl.page is not None:
        x0 = y0 = 0.0
        w, h = dl.page
        w_mm, h_mm = w * dl.unit_mm, h * dl.unit_mm
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
        for i, colour in zip(idx, colours, strict=True):
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

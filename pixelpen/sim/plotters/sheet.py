"""Shared parts of the pen-plotter simulators: paper with its pen-down strokes and its rendering, wire counters."""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Final

import numpy as np

from pixelpen.colour import colour_hex, parse_colour
from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList

if TYPE_CHECKING:
    from pixelpen.raster.canvas import Canvas

__all__ = [
    "PAPER_FORMATS", "Sheet", "WireStats", "blank_sheet", "clamp_path", "draw_segments", "paper_format",
    "write_paper_svg",
]

log = logging.getLogger(__name__)


@dataclass
class WireStats:
    """Counters a benchmark reads from a simulated plotter (times in clock seconds)."""

    bytes_received: int = 0
    commands_executed: int = 0
    starved_time: float = 0.0
    """Seconds the machine stood still with nothing complete to execute, between its first and last motion."""
    moving_time: float = 0.0
    """Seconds the machine spent executing motion (and pen) commands."""


def clamp_path(p0: np.ndarray, p1: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The path a carriage really takes for a straight move p0 -> p1 when each axis stops at [lo, hi].

    Each axis is clamped independently (the carriage rides along the end stop), so the path is the
    straight move with a corner wherever it crosses a limit: returns the (K, 2) polyline, K >= 2.
    """
    p0 = np.asarray(p0, dtype=np.float64)
    p1 = np.asarray(p1, dtype=np.float64)
    if lo[0] <= p0[0] <= hi[0] and lo[1] <= p0[1] <= hi[1] and lo[0] <= p1[0] <= hi[0] and lo[1] <= p1[1] <= hi[1]:
        return np.array([p0, p1])  # the box is convex: a move between inside points stays inside
    d = p1 - p0
    ts = [0.0, 1.0]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # inf/nan crossings are dropped below
        for bound in (lo, hi):
            t = (np.asarray(bound, dtype=np.float64) - p0) / d
            ts.extend(float(v) for v in t[np.isfinite(t)] if 0.0 < v < 1.0)
    t_arr = np.unique(np.asarray(ts))
    pts = np.clip(p0[None, :] + t_arr[:, None] * d[None, :], lo, hi)
    keep = np.ones(len(pts), dtype=bool)
    keep[1:] = np.any(np.abs(np.diff(pts, axis=0)) > 1e-12, axis=1)
    keep[-1] = True
    return pts[keep] if keep.sum() >= 2 else np.vstack([pts[0], pts[-1]])


PAPER_FORMATS: Final = {".png": "png", ".svg": "svg"}
"""File extensions a simulator's paper is saved in (case-insensitive)."""


def paper_format(path: str | Path) -> str:
    """``png`` or ``svg`` from the extension of ``path``; ConfigError naming the path otherwise."""
    fmt = PAPER_FORMATS.get(Path(path).suffix.lower())
    if fmt is None:
        raise ConfigError(f"paper file {str(path)!r}: the name must end in .png or .svg")
    return fmt


def write_paper_svg(
    path: str | Path,
    strokes: list[tuple[int, np.ndarray]],
    page_mm: tuple[float, float],
    pen_colours: Mapping[int, str],
    pen_width_mm: float,
) -> None:
    """Write ``strokes`` ((pen, (N, 2) mm, y down from the top-left page corner)) as a true-size SVG page."""
    from pixelpen.vector.svgimport import write_svg

    dl = DisplayList.from_polylines(
        [pts for _, pts in strokes], pens=[pen for pen, _ in strokes] or 1, unit_mm=1.0,
        pen_colours={k: colour_hex(parse_colour(v)) for k, v in pen_colours.items()},
    )
    write_svg(dl, str(path), size_mm=page_mm, pen_width_mm=pen_width_mm)


def blank_sheet(page_mm: tuple[float, float], dpi: float) -> tuple[Canvas, float]:
    """A white RGB canvas of the page at ``dpi`` and its scale in pixels per millimetre (dpi checked: 1..2400)."""
    from pixelpen.raster.canvas import Canvas

    if not (isinstance(dpi, (int, float)) and math.isfinite(dpi) and 1.0 <= dpi <= 2400.0):
        raise ConfigError(f"paper_image: dpi must be a number in 1..2400, got {dpi!r}")
    scale = dpi / 25.4
    canvas = Canvas(max(1, round(page_mm[0] * scale)), max(1, round(page_mm[1] * scale)), "RGB")
    canvas.fill((255, 255, 255))
    return canvas, scale


def draw_segments(
    canvas: Canvas,
    pixels: np.ndarray,
    pens: np.ndarray,
    widths: np.ndarray,
    pen_colours: Mapping[int, str],
    *,
    cap: str,
) -> None:
    """Ink (N, 4) integer pixel segments pen by pen (in pen order), width by width; a pen without a colour plots dry."""
    for pen in np.unique(pens):
        colour = pen_colours.get(int(pen))
        if colour is None:
            continue
        rgb = parse_colour(colour)
        mine = pens == pen
        for width in np.unique(widths[mine]):
            sel = mine & (widths == width)
            canvas.lines(pixels[sel], rgb, width=int(width), cap=cap)


class Sheet:
    """The sheet under a plotter's pen: every pen-down stroke in millimetres, and its rendering.

    ``y_down`` says how the device's y axis runs on the sheet (True: AxiDraw, origin top-left; False:
    GRBL machine coordinates, origin bottom-left).  Strokes are kept in device millimetres; a stroke
    that was only touched (pen down and up without motion) is a one-point stroke, drawn as a dot.
    """

    def __init__(
        self,
        width_mm: float,
        height_mm: float,
        *,
        y_down: bool,
        pen_colours: Mapping[int, str] | None = None,
        pen_width_mm: float = 0.3,
    ) -> None:
        if not (width_mm > 0 and height_mm > 0):
            raise ConfigError(f"paper size must be positive, got {width_mm} x {height_mm} mm")
        self.width_mm = float(width_mm)
        self.height_mm = float(height_mm)
        self.y_down = y_down
        self.pen_colours = {int(k): v for k, v in (pen_colours or {1: "black"}).items()}
        for colour in self.pen_colours.values():
            parse_colour(colour)
        self.pen_width_mm = float(pen_width_mm)
        self._done: list[tuple[int, np.ndarray]] = []
        self._current: list[np.ndarray] | None = None
        self._pen = 1

    @property
    def pen_is_down(self) -> bool:
        """True while a stroke is open (the pen touches the sheet)."""
        return self._current is not None

    def pen_down(self, point: np.ndarray, pen: int = 1) -> None:
        """The pen touches the sheet at ``point`` (mm): a new stroke starts there."""
        if self._current is not None:
            return
        self._pen = int(pen)
        self._current = [np.asarray(point, dtype=np.float64).reshape(1, 2)]

    def line_to(self, points: np.ndarray) -> None:
        """The pen moved along ``points`` ((N, 2) mm): recorded if it is down."""
        if self._current is None:
            return
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if len(pts) and np.array_equal(pts[0], self._current[-1][-1]):
            pts = pts[1:]
        if len(pts):
            self._current.append(pts)

    def pen_up(self) -> None:
        """The pen leaves the sheet: the open stroke is finished."""
        if self._current is None:
            return
        self._done.append((self._pen, np.concatenate(self._current)))
        self._current = None

    def strokes(self) -> list[tuple[int, np.ndarray]]:
        """Every stroke so far as (pen, (N, 2) mm points), the open one included."""
        out = list(self._done)
        if self._current is not None:
            out.append((self._pen, np.concatenate(self._current)))
        return out

    def display_list(self) -> DisplayList:
        """The strokes as a DisplayList in device millimetres (unit_mm = 1)."""
        strokes = self.strokes()
        return DisplayList.from_polylines(
            [s for _, s in strokes],
            pens=[p for p, _ in strokes] or 1,
            unit_mm=1.0,
            pen_colours={k: v for k, v in self.pen_colours.items()},
        )

    def ink_length(self) -> float:
        """Total pen-down length in millimetres."""
        return float(sum(np.hypot(*np.diff(s, axis=0).T).sum() for _, s in self.strokes() if len(s) > 1))

    def paper_image(self, dpi: float = 96.0) -> Canvas:
        """Render the sheet (white) with every stroke in its pen's colour and width as an RGB Canvas."""
        canvas, scale = blank_sheet((self.width_mm, self.height_mm), dpi)
        height = canvas.height
        line_width = max(1, round(self.pen_width_mm * scale))
        segs: list[np.ndarray] = []
        pens: list[np.ndarray] = []
        strokes = self.strokes()
        for pen, pts in strokes:
            px = pts * scale
            if not self.y_down:
                px = np.column_stack([px[:, 0], height - 1 - px[:, 1]])
            seg = np.hstack([px[:-1], px[1:]]) if len(px) > 1 else np.hstack([px, px])
            segs.append(seg)
            pens.append(np.full(len(seg), pen))
        if segs:
            colours = {pen: self.pen_colours.get(pen, "black") for pen, _ in strokes}
            pixels = np.rint(np.vstack(segs)).astype(np.int64)
            all_pens = np.concatenate(pens)
            draw_segments(canvas, pixels, all_pens, np.full(len(pixels), line_width), colours, cap="square")
        return canvas

    def save_paper(self, path: str | Path, dpi: float = 96.0) -> None:
        """Write the sheet to ``path``: a PNG rendered at ``dpi``, or a true-size SVG (by the extension)."""
        if paper_format(path) == "png":
            self.paper_image(dpi).save(path)
            return
        flip = np.array([1.0, -1.0]) if not self.y_down else np.ones(2)
        shift = np.array([0.0, self.height_mm]) if not self.y_down else np.zeros(2)
        strokes = [(pen, pts * flip + shift) for pen, pts in self.strokes()]
        write_paper_svg(path, strokes, (self.width_mm, self.height_mm), self.pen_colours, self.pen_width_mm)

    def clear(self) -> None:
        """Put in a fresh sheet."""
        self._done.clear()
        self._current = None



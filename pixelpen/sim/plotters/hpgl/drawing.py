"""The ink on an HP-GL plotter's sheet: pen-down segments in physical plotter units (y up), with pens and widths.

Rendering goes through the shared sheet helpers (``blank_sheet``, ``draw_segments``, ``write_paper_svg``):
the page is the loaded paper, the hard-clip area sits at the paper's origin (or centred), and a felt tip
draws round ends.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pixelpen.sim.plotters.hpgl.models import PaperSpec
from pixelpen.sim.plotters.sheet import blank_sheet, draw_segments, paper_format, write_paper_svg
from pixelpen.vector.displaylist import DisplayList

if TYPE_CHECKING:
    from pixelpen.raster.canvas import Canvas

__all__ = ["Drawing"]


class Drawing:
    """Every pen-down segment a plotter inked, in order, and the sheet it makes."""

    def __init__(self, unit_mm: float, pen_colours: dict[int, str]) -> None:
        self.unit_mm = unit_mm
        self.pen_colours = pen_colours
        self._segments: list[np.ndarray] = []
        self._pens: list[int] = []
        self._widths: list[float] = []
        self._cache: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def ink(self, segments: np.ndarray, pen: int, width_mm: float) -> None:
        """Add (K, 4) segments drawn with ``pen``; a bare PD's dot merges into the line drawn from it."""
        last = self._segments[-1] if self._segments else None
        if (last is not None and len(last) == 1 and last[0, 0] == last[0, 2] and last[0, 1] == last[0, 3]
                and self._pens[-1] == pen and np.array_equal(last[0, :2], segments[0, :2])):
            # the dot a bare PD left is the start of the line drawn from it: one mark, not two
            self._segments.pop()
            self._pens.pop()
            self._widths.pop()
        self._segments.append(segments)
        self._pens.append(pen)
        self._widths.append(width_mm)
        self._cache = None

    def segments(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(N, 4) x0, y0, x1, y1 in physical plotter units, pens (N,), widths mm (N,)."""
        if self._cache is None:
            if self._segments:
                counts = [len(s) for s in self._segments]
                self._cache = (
                    np.concatenate(self._segments),
                    np.repeat(np.asarray(self._pens, dtype=np.int32), counts),
                    np.repeat(np.asarray(self._widths, dtype=np.float64), counts),
                )
            else:
                self._cache = (np.zeros((0, 4)), np.zeros(0, np.int32), np.zeros(0))
        return self._cache

    def display_list(self) -> DisplayList:
        """The segments as a DisplayList: touching same-pen segments joined into polylines, in plotter units."""
        seg, pens, _ = self.segments()
        if not len(seg):
            return DisplayList(unit_mm=self.unit_mm, pen_colours=dict(self.pen_colours))
        breaks = np.ones(len(seg), dtype=bool)
        breaks[1:] = np.any(seg[1:, 0:2] != seg[:-1, 2:4], axis=1) | (pens[1:] != pens[:-1])
        starts = np.flatnonzero(breaks)
        ends = np.append(starts[1:], len(seg))
        # each polyline: its first start point, then every segment's end point
        lengths = ends - starts + 1
        offsets = np.concatenate([[0], np.cumsum(lengths)])
        points = np.empty((offsets[-1], 2))
        points[offsets[:-1]] = seg[starts, 0:2]
        rest = np.ones(offsets[-1], dtype=bool)
        rest[offsets[:-1]] = False
        points[rest] = seg[:, 2:4]
        return DisplayList(
            points, offsets, pens[starts], np.zeros(len(starts), np.int32),
            unit_mm=self.unit_mm, pen_colours=dict(self.pen_colours),
        )

    def origin_mm(self, paper: PaperSpec, hard_clip: tuple[int, int]) -> tuple[float, float]:
        """Where plotter unit 0,0 lies on the sheet, from its lower-left corner (mm)."""
        if paper.origin_mm is not None:
            return paper.origin_mm
        u = self.unit_mm
        return (paper.page_mm[0] - hard_clip[0] * u) / 2, (paper.page_mm[1] - hard_clip[1] * u) / 2

    def paper_image(self, paper: PaperSpec, hard_clip: tuple[int, int], dpi: float) -> Canvas:
        """The sheet at ``dpi``: white page of the paper size, every segment in its pen's colour and width."""
        canvas, k = blank_sheet(paper.page_mm, dpi)
        seg, pens, widths = self.segments()
        if not len(seg):
            return canvas
        ox, oy = self.origin_mm(paper, hard_clip)
        u = self.unit_mm
        px = np.empty_like(seg)
        px[:, 0::2] = (ox + seg[:, 0::2] * u) * k
        px[:, 1::2] = canvas.height - (oy + seg[:, 1::2] * u) * k
        pix = np.floor(px).astype(np.int64)
        wpx = np.maximum(1, np.round(widths * k)).astype(np.int64)
        draw_segments(canvas, pix, pens, wpx, self.pen_colours, cap="round")  # a felt tip is round
        return canvas

    def save_paper(self, path: str | Path, paper: PaperSpec, hard_clip: tuple[int, int], dpi: float) -> None:
        """Write the sheet to ``path``: a PNG (``paper_image`` at ``dpi``) or a true-size SVG, by the extension."""
        if paper_format(path) == "png":
            self.paper_image(paper, hard_clip, dpi).save(path)
            return
        dl = self.display_list()
        u = self.unit_mm
        ox, oy = self.origin_mm(paper, hard_clip)
        page_w, page_h = paper.page_mm
        strokes = [
            (int(pen), np.column_stack([ox + pts[:, 0] * u, page_h - (oy + pts[:, 1] * u)]))
            for pen, pts in ((dl.pens[i], dl.stroke(i)) for i in range(len(dl)))
            if int(pen) in self.pen_colours  # an empty stall plots dry
        ]
        widths = self.segments()[2]
        write_paper_svg(path, strokes, (page_w, page_h), self.pen_colours,
                        float(np.median(widths)) if len(widths) else 0.3)

"""The display list of a random-scan device: pen-down polylines in device units, kept as flat numpy arrays."""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from pixelpen.errors import ConfigError


@dataclass
class DisplayList:
    """Pen-down polylines; pen-up travel is implied from the end of one stroke to the start of the next.

    ``points`` is (P, 2) float64 in device units; stroke ``i`` is ``points[offsets[i]:offsets[i+1]]``;
    ``pens[i]`` is its pen number (1-based) and ``layers[i]`` its layer id, named in ``layer_names``.
    """

    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    offsets: np.ndarray = field(default_factory=lambda: np.zeros(1, dtype=np.int64))
    pens: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    layers: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    layer_names: dict[int, str] = field(default_factory=dict)
    unit_mm: float = 1.0
    pen_colours: dict[int, str] = field(default_factory=dict)
    """Colour (``#rrggbb``) of each pen number used, for previews; missing pens draw black."""
    page: tuple[float, float] | None = None
    """Size (width, height) in device units of the page the points refer to, origin at its top left, if known."""

    def __post_init__(self) -> None:
        self.points = np.ascontiguousarray(self.points, dtype=np.float64).reshape(-1, 2)
        self.offsets = np.asarray(self.offsets, dtype=np.int64)
        n = len(self.offsets) - 1
        self.pens = np.asarray(self.pens, dtype=np.int32).reshape(-1)
        self.layers = np.asarray(self.layers, dtype=np.int32).reshape(-1)
        if n < 0 or self.offsets[0] != 0 or self.offsets[-1] != len(self.points) or np.any(np.diff(self.offsets) < 1):
            raise ConfigError(
                "display list offsets must start at 0, end at the point count and give each stroke >= 1 point"
            )
        if len(self.pens) != n or len(self.layers) != n:
            raise ConfigError(f"display list has {n} strokes but {len(self.pens)} pens and {len(self.layers)} layers")
        if self.page is not None:
            try:
                page = tuple(float(v) for v in self.page)
            except (TypeError, ValueError):
                page = ()
            if len(page) != 2 or not all(math.isfinite(v) and v > 0 for v in page):
                raise ConfigError(f"display list page must be (width, height) > 0, got {self.page!r}")
            self.page = page

    @classmethod
    def from_polylines(
        cls,
        polylines: Iterable[np.ndarray],
        pens: Sequence[int] | int = 1,
        layers: Sequence[int] | int = 0,
        layer_names: dict[int, str] | None = None,
        unit_mm: float = 1.0,
        pen_colours: dict[int, str] | None = None,
        page: tuple[float, float] | None = None,
    ) -> DisplayList:
        """Build a display list from a sequence of (N, 2) arrays (empty arrays are skipped)."""
        polys = [np.asarray(p, dtype=np.float64).reshape(-1, 2) for p in polylines]
        keep = [i for i, p in enumerate(polys) if len(p)]
        lengths = np.array([len(polys[i]) for i in keep], dtype=np.int64)
        offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
        points = np.concatenate([polys[i] for i in keep]) if keep else np.zeros((0, 2))
        pen_arr = (
            np.broadcast_to(np.asarray(pens, dtype=np.int32), (len(polys),))[keep] if polys else np.zeros(0, np.int32)
        )
        layer_arr = (
            np.broadcast_to(np.asarray(layers, dtype=np.int32), (len(polys),))[keep] if polys else np.zeros(0, np.int32)
        )
        return cls(points, offsets, pen_arr, layer_arr, dict(layer_names or {}), unit_mm, dict(pen_colours or {}), page)

    def __len__(self) -> int:
        return len(self.offsets) - 1

    def stroke(self, i: int) -> np.ndarray:
        """The points of stroke ``i`` (a view)."""
        return self.points[self.offsets[i] : self.offsets[i + 1]]

    def strokes(self) -> Iterator[np.ndarray]:
        """Iterate over the strokes' point arrays (views)."""
        for i in range(len(self)):
            yield self.stroke(i)

    @property
    def starts(self) -> np.ndarray:
        """(S, 2) first point of each stroke."""
        return self.points[self.offsets[:-1]]

    @property
    def ends(self) -> np.ndarray:
        """(S, 2) last point of each stroke."""
        return self.points[self.offsets[1:] - 1]

    def segments(self) -> np.ndarray:
        """All pen-down segments as an (M, 4) array x0, y0, x1, y1 (single-point strokes give none)."""
        if len(self.points) < 2:
            return np.zeros((0, 4))
        seg = np.hstack([self.points[:-1], self.points[1:]])
        inner = np.ones(len(self.points) - 1, dtype=bool)
        inner[self.offsets[1:-1] - 1] = False
        return seg[inner]

    def pen_down_length(self) -> float:
        """Total pen-down length in device units."""
        s = self.segments()
        return float(np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]).sum())

    def pen_up_length(self, home: tuple[float, float] = (0.0, 0.0), return_home: bool = False) -> float:
        """Total pen-up travel in device units from ``home`` through the strokes in order."""
        if not len(self):
            return 0.0
        starts, ends = self.starts, self.ends
        hops = np.vstack([np.asarray(home, float)[None], ends[:-1]])
        total = float(np.hypot(*(starts - hops).T).sum())
        if return_home:
            total += float(np.hypot(*(ends[-1] - np.asarray(home, float))))
        return total

    def bounds(self) -> tuple[float, float, float, float] | None:
        """(xmin, ymin, xmax, ymax) of all points, or None when empty."""
        if not len(self.points):
            return None
        lo, hi = self.points.min(axis=0), self.points.max(axis=0)
        return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))

    def reordered(
        self, order: Sequence[int] | np.ndarray, reverse: Sequence[bool] | np.ndarray | None = None
    ) -> DisplayList:
        """A new display list with strokes taken in ``order``, each reversed where ``reverse`` says so."""
        order = np.asarray(order, dtype=np.int64)
        rev = np.zeros(len(order), bool) if reverse is None else np.asarray(reverse, bool)
        lengths = np.diff(self.offsets)[order]
        new_offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
        # gather index of every output point, vectorised over all strokes
        stroke_of_point = np.repeat(np.arange(len(order)), lengths)
        k = np.arange(new_offsets[-1]) - new_offsets[:-1][stroke_of_point]
        src_start = self.offsets[order][stroke_of_point]
        src_len = lengths[stroke_of_point]
        idx = np.where(rev[stroke_of_point], src_start + src_len - 1 - k, src_start + k)
        return replace(
            self,
            points=self.points[idx],
            offsets=new_offsets,
            pens=self.pens[order],
            layers=self.layers[order],
            layer_names=dict(self.layer_names),
            pen_colours=dict(self.pen_colours),
        )

    def select(self, mask: np.ndarray) -> DisplayList:
        """A new display list with only the strokes where ``mask`` is true (order kept)."""
        return self.reordered(np.flatnonzero(np.asarray(mask, bool)))

    @staticmethod
    def concat(lists: Sequence[DisplayList]) -> DisplayList:
        """Join display lists in order (unit and page of the first; layer names merged)."""
        lists = [d for d in lists]
        if not lists:
            return DisplayList()
        names: dict[int, str] = {}
        colours: dict[int, str] = {}
        for d in lists:
            names.update(d.layer_names)
            colours.update(d.pen_colours)
        pts = np.concatenate([d.points for d in lists])
        base = np.cumsum([0] + [len(d.points) for d in lists[:-1]])
        offsets = np.concatenate([[0]] + [d.offsets[1:] + b for d, b in zip(lists, base, strict=False)])
        return replace(
            lists[0],
            points=pts,
            offsets=offsets,
            pens=np.concatenate([d.pens for d in lists]),
            layers=np.concatenate([d.layers for d in lists]),
            layer_names=names,
            pen_colours=colours,
        )

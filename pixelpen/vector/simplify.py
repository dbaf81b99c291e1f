"""Douglas–Peucker polyline simplification, vectorised over every stroke of a display list at once."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList

__all__ = ["simplify", "simplify_mask"]


def simplify_mask(points: np.ndarray, offsets: np.ndarray, tolerance: float) -> np.ndarray:
    """Which points Douglas–Peucker keeps in each polyline ``points[offsets[i]:offsets[i+1]]``.

    A range's farthest interior point from the chord between its ends (distance to the segment, so closed
    polylines work) is kept when farther than ``tolerance``, and the range splits there. All ranges of all
    polylines are processed together, one recursion level per numpy pass; end points are always kept.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    offs = np.asarray(offsets, dtype=np.int64)
    keep = np.zeros(len(pts), bool)
    if not len(pts):
        return keep
    keep[offs[:-1]] = True
    keep[offs[1:] - 1] = True
    lo, hi = offs[:-1], offs[1:] - 1
    while True:
        wide = hi - lo >= 2
        lo, hi = lo[wide], hi[wide]
        if not len(lo):
            return keep
        counts = hi - lo - 1  # interior points of each range
        rng = np.repeat(np.arange(len(lo)), counts)
        idx = np.arange(len(rng)) - np.repeat(np.cumsum(counts) - counts, counts) + lo[rng] + 1
        d = _segment_distance(pts[idx], pts[lo[rng]], pts[hi[rng]])
        starts = np.cumsum(counts) - counts
        best = np.maximum.reduceat(d, starts)
        # first index attaining the maximum in each range
        at_max = np.where(d == best[rng], np.arange(len(d)), len(d))
        first = np.minimum.reduceat(at_max, starts)
        split = best > tolerance
        k = idx[first[split]]
        keep[k] = True
        lo = np.concatenate([lo[split], k])
        hi = np.concatenate([k, hi[split]])


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from each point ``p`` to the segment ``a``–``b`` (to ``a`` when the segment has no length)."""
    ab = b - a
    ap = p - a
    den = np.einsum("ij,ij->i", ab, ab)
    t = np.clip(np.divide(np.einsum("ij,ij->i", ap, ab), den, out=np.zeros(len(p)), where=den > 0), 0.0, 1.0)
    return np.hypot(*(ap - t[:, None] * ab).T)


def simplify(dl: DisplayList, tolerance: float) -> DisplayList:
    """Simplify every stroke with Douglas–Peucker to within ``tolerance`` (device units), keeping its end points."""
    if not isinstance(tolerance, (int, float)) or not math.isfinite(tolerance) or tolerance < 0:
        raise ConfigError(f"simplify: tolerance must be a finite number >= 0, got {tolerance!r}")
    keep = simplify_mask(dl.points, dl.offsets, float(tolerance))
    kept_before = np.concatenate([[0], np.cumsum(keep)])
    return dataclasses.replace(dl, points=dl.points[keep], offsets=kept_before[dl.offsets], pens=dl.pens.copy(),
                               layers=dl.layers.copy(), layer_names=dict(dl.layer_names),
                               pen_colours=dict(dl.pen_colours))

"""Dash patterns: cut polylines into pen-down pieces by arc length, vectorised over all polylines at once."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pixelpen.errors import InvalidArgument
from pixelpen.geometry.transforms import ArrayLike, as_number, as_points, split_rows

MAX_DASHES = 5_000_000
"""Dash pieces one call may produce before the pattern is called too fine (read at call time: assign to override)."""


def as_pattern(pattern: Sequence[float]) -> np.ndarray:
    """Validate a dash pattern (on, off, on, off, ...): finite lengths >= 0 with a positive sum.

    An odd number of entries is repeated once (as SVG's stroke-dasharray), so (3,) means 3 on, 3 off.
    """
    try:
        arr = np.asarray(pattern, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"dash pattern must be a sequence of lengths: {exc}") from None
    if arr.ndim != 1 or len(arr) == 0:
        raise InvalidArgument(f"dash pattern must be a non-empty 1-D sequence of lengths, got shape {arr.shape}")
    if not np.isfinite(arr).all() or (arr < 0).any():
        raise InvalidArgument(f"dash pattern lengths must be finite and >= 0, got {arr.tolist()}")
    if arr.sum() <= 0:
        raise InvalidArgument(f"dash pattern must have a positive total length, got {arr.tolist()}")
    return np.concatenate([arr, arr]) if len(arr) % 2 else arr


def dash_polylines(polylines: Sequence[ArrayLike], pattern: Sequence[float], offset: float = 0.0) -> list[np.ndarray]:
    """Cut polylines into the pen-down pieces of a dash pattern; returns a list of (K, 2) arrays in drawing order.

    ``pattern`` is (on, off, on, off, ...) in the units of the points; it runs on across the vertices
    of a polyline and restarts at each polyline, shifted by ``offset`` (the pattern position at the
    start of every polyline, as SVG's stroke-dashoffset). A zero "on" length gives a zero-length
    piece (a dot). Pieces keep the polyline's vertices that fall inside them.
    """
    pat = as_pattern(pattern)
    offset = as_number(offset, "offset")
    arrays = [as_points(p, f"polylines[{i}]", min_rows=1)[0] for i, p in enumerate(polylines)]
    if not arrays:
        return []
    period = float(pat.sum())
    bounds = np.concatenate([[0.0], np.cumsum(pat)])
    on_start, on_end = bounds[0:-1:2], bounds[1::2]  # "on" intervals within one period
    shift = offset % period

    pts = np.concatenate(arrays)
    counts = np.array([len(a) for a in arrays])
    firsts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    seg = np.hypot(*np.diff(pts, axis=0).T)
    seg[(firsts[1:] - 1)] = 1.0  # a unit gap between polylines keeps their arc ranges apart
    arc = np.concatenate([[0.0], np.cumsum(seg)])  # global arc coordinate of every vertex
    base = arc[firsts]
    length = arc[firsts + counts - 1] - base

    # Dash k of period j covers [j P + on_start[k] - shift, j P + on_end[k] - shift] in local arc length;
    # periods j = 0 .. floor((length + shift) / P) reach the end of each polyline.
    periods = np.floor((length + shift) / period) + 1.0  # floats first: a 1e-300 pattern gives inf, not garbage
    total = float(periods.sum()) * len(on_start)
    if not total <= MAX_DASHES:
        raise InvalidArgument(
            f"dash pattern is too fine for these polylines: {total:g} dashes (limit geometry.dashes.MAX_DASHES = "
            f"{MAX_DASHES})"
        )
    per_line = periods.astype(np.int64) * len(on_start)
    line, within = _ragged(per_line)
    j, k = within // len(on_start), within % len(on_start)
    lo = j * period + on_start[k] - shift
    hi = j * period + on_end[k] - shift
    end = length[line]
    a, b = np.clip(lo, 0.0, end), np.clip(hi, 0.0, end)
    keep = (b > a) | ((hi == lo) & (lo >= 0.0) & (lo <= end)) | ((end == 0.0) & (lo <= 0.0) & (hi > 0.0))
    line, a, b = line[keep], a[keep] + base[line[keep]], b[keep] + base[line[keep]]

    first, last = firsts[line], firsts[line] + counts[line] - 1
    inner_from = np.searchsorted(arc, a, side="right")  # first vertex strictly after a
    inner = np.maximum(np.searchsorted(arc, b, side="left") - inner_from, 0)  # vertices strictly inside
    size = inner + 2
    starts = np.cumsum(size) - size
    out = np.empty((int(size.sum()), 2))
    out[starts] = _point_at(pts, arc, a, first, last)
    out[starts + size - 1] = _point_at(pts, arc, b, first, last)
    dash, w = _ragged(inner)
    out[starts[dash] + 1 + w] = pts[inner_from[dash] + w]
    return split_rows(out, starts)


def _ragged(counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For consecutive groups of these sizes: the group of every element and its index within the group."""
    group = np.repeat(np.arange(len(counts)), counts)
    within = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    return group, within


def _point_at(pts: np.ndarray, arc: np.ndarray, where: np.ndarray, first: np.ndarray, last: np.ndarray) -> np.ndarray:
    """Points at global arc coordinates ``where``, each on the polyline spanning vertices first..last."""
    i = np.clip(np.searchsorted(arc, where, side="right") - 1, first, np.maximum(last - 1, first))
    i1 = np.minimum(i + 1, last)
    span = arc[i1] - arc[i]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(span > 0, np.clip((where - arc[i]) / span, 0.0, 1.0), 0.0)
    points: np.ndarray = pts[i] + t[:, None] * (pts[i1] - pts[i])
    return points

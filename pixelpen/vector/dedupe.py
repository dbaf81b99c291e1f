"""Removing ink drawn twice in one layer and pen (repeated points, overlapping segments, repeated dots), short strokes.

Strokes of different layers or pens never remove each other's ink: a second pass of the same lines in another
layer or pen (another colour, or a line darkened on purpose) is kept.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.spatial import cKDTree

from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.merge import group_ids

__all__ = ["DuplicateRemoval", "deduplicate", "filter_min_length", "remove_duplicates", "stroke_lengths"]


@dataclasses.dataclass(frozen=True)
class DuplicateRemoval:
    """What duplicate removal took from one (layer, pen): strokes dropped, strokes cut, ink length (device units)."""

    layer: int
    pen: int
    strokes_removed: int
    strokes_shortened: int
    length: float


def stroke_lengths(dl: DisplayList) -> np.ndarray:
    """Pen-down length of every stroke (device units)."""
    if not len(dl):
        return np.zeros(0)
    step = np.hypot(*np.diff(dl.points, axis=0).T) if len(dl.points) > 1 else np.zeros(0)
    cum = np.concatenate([[0.0], np.cumsum(step)])
    # subtracting at stroke bounds cancels the jumps between strokes
    return cum[dl.offsets[1:] - 1] - cum[dl.offsets[:-1]]


def filter_min_length(dl: DisplayList, min_length: float) -> DisplayList:
    """Drop strokes shorter than ``min_length`` (device units); dots count as length 0."""
    if not isinstance(min_length, (int, float)) or not math.isfinite(min_length) or min_length < 0:
        raise ConfigError(f"filter_min_length: min_length must be a finite number >= 0, got {min_length!r}")
    return dl.select(stroke_lengths(dl) >= min_length)


def remove_duplicates(dl: DisplayList, tolerance: float = 1e-6) -> DisplayList:
    """The display list of :func:`deduplicate`, without its account of what went."""
    return deduplicate(dl, tolerance)[0]


def deduplicate(dl: DisplayList, tolerance: float = 1e-6) -> tuple[DisplayList, list[DuplicateRemoval]]:
    """Draw nothing twice in one layer and pen; returns the result and what was removed per (layer, pen).

    Segments of one layer and pen whose lines agree within ``tolerance`` (device units) share a line; along it,
    each stretch covered by several segments is kept in the earliest one drawn and cut from the later ones, so a
    later stroke may split where it retraced earlier ink. A point within ``tolerance`` of the point before it in
    its stroke is dropped (a stroke keeps at least one point), as is a dot (single-point stroke) within
    ``tolerance`` of an earlier dot of the same layer and pen. Strokes left without ink are removed. The account
    lists each (layer, pen) that lost ink or strokes, in order of first appearance; dropping repeated points
    removes no ink and is not counted.
    """
    if not isinstance(tolerance, (int, float)) or not math.isfinite(tolerance) or tolerance < 0:
        raise ConfigError(f"remove_duplicates: tolerance must be a finite number >= 0, got {tolerance!r}")
    if not len(dl):
        return dl.reordered(np.arange(0)), []
    tol = float(tolerance)
    dl = _drop_repeated_points(dl, tol)
    n = len(dl)
    group = group_ids(dl)
    # segments of every stroke, in drawing order
    owner = np.repeat(np.arange(n), np.diff(dl.offsets))
    inner = np.ones(max(len(dl.points) - 1, 0), bool)
    inner[dl.offsets[1:-1] - 1] = False
    seg_owner = owner[:-1][inner]
    p0 = dl.points[:-1][inner]
    p1 = dl.points[1:][inner]
    keep_seg, pieces = _resolve_overlaps(p0, p1, group[seg_owner], tol)
    # dots: single-point strokes; the later of two close dots of one group goes
    dots = np.flatnonzero(np.diff(dl.offsets) == 1)
    dot_keep = np.ones(len(dots), bool)
    if len(dots) > 1:
        pairs = cKDTree(dl.points[dl.offsets[dots]]).query_pairs(tol, output_type="ndarray")
        pairs = pairs[group[dots[pairs[:, 0]]] == group[dots[pairs[:, 1]]]]
        dot_keep[pairs.max(axis=1)] = False
    # output segments: whole kept segments plus partial pieces, ordered by (segment, position along it)
    whole = np.flatnonzero(keep_seg)
    seg_idx = np.concatenate([whole, pieces[0]])
    seg_t = np.concatenate([np.zeros(len(whole)), pieces[1]])
    a = np.concatenate([p0[whole], pieces[2]])
    b = np.concatenate([p1[whole], pieces[3]])
    o = np.lexsort((seg_t, seg_idx))
    out, sources = _assemble(dl, seg_owner[seg_idx[o]], a[o], b[o], dots[dot_keep])
    # the account: ink lost per source stroke (whole length less what its pieces keep), strokes gone or cut
    seg_len = np.hypot(*(p1 - p0).T)
    kept_len = np.where(keep_seg, seg_len, 0.0) + np.bincount(
        pieces[0], weights=np.hypot(*(pieces[3] - pieces[2]).T), minlength=len(p0))
    lost = np.bincount(seg_owner, weights=np.maximum(seg_len - kept_len, 0.0), minlength=n)
    survives = np.zeros(n, bool)
    survives[sources] = True
    cut = np.zeros(n, bool)
    cut[seg_owner[~keep_seg]] = True
    return out, _account(dl, group, ~survives, cut & survives, lost)


def _account(dl: DisplayList, group: np.ndarray, removed: np.ndarray, cut: np.ndarray, lost: np.ndarray
             ) -> list[DuplicateRemoval]:
    """One :class:`DuplicateRemoval` per group that lost strokes or ink, groups in order of first appearance."""
    n_groups = int(group.max()) + 1
    gone = np.bincount(group, weights=removed, minlength=n_groups)
    shortened = np.bincount(group, weights=cut, minlength=n_groups)
    length = np.bincount(group, weights=lost, minlength=n_groups)
    _, first = np.unique(group, return_index=True)
    return [
        DuplicateRemoval(int(dl.layers[first[g]]), int(dl.pens[first[g]]), int(gone[g]), int(shortened[g]),
                         float(length[g]))
        for g in np.argsort(first).tolist() if gone[g] or shortened[g]
    ]


def _assemble(dl: DisplayList, strokes: np.ndarray, a: np.ndarray, b: np.ndarray, dot_strokes: np.ndarray
              ) -> tuple[DisplayList, np.ndarray]:
    """Strokes from segments ``a``→``b`` (in drawing order, ``strokes`` their source stroke) and kept dots.

    Returns the display list and the source stroke of each of its strokes.
    """
    # a new stroke starts where the source stroke changes or the pen would have to jump
    new = np.ones(len(a), bool)
    new[1:] = (strokes[1:] != strokes[:-1]) | np.any(a[1:] != b[:-1], axis=1)
    run = np.cumsum(new) - 1
    n_runs = int(run[-1]) + 1 if len(run) else 0
    run_first = np.flatnonzero(new)
    run_stroke = strokes[run_first] if n_runs else np.zeros(0, np.int64)
    # points: first point of each run, then the end of each segment
    run_len = np.bincount(run, minlength=n_runs) + 1 if n_runs else np.zeros(0, np.int64)
    pts = np.empty((len(a) + n_runs, 2))
    point_at = np.arange(len(a)) + run + 1
    pts[point_at] = b
    pts[run_first + np.arange(n_runs)] = a[run_first]
    dot_pts = dl.points[dl.offsets[dot_strokes]]
    # runs and dots in source stroke order (stable: a stroke's runs keep their order)
    all_stroke = np.concatenate([run_stroke, dot_strokes])
    all_len = np.concatenate([run_len, np.ones(len(dot_strokes), np.int64)])
    all_pts_start = np.concatenate([np.cumsum(run_len) - run_len, len(pts) + np.arange(len(dot_strokes))])
    all_pts = np.concatenate([pts, dot_pts])
    order = np.argsort(all_stroke, kind="stable")
    lengths = all_len[order]
    offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
    src_start = all_pts_start[order]
    gather = np.repeat(src_start - offsets[:-1], lengths) + np.arange(offsets[-1])
    stroke_of = all_stroke[order]
    out = dataclasses.replace(dl, points=all_pts[gather], offsets=offsets, pens=dl.pens[stroke_of],
                              layers=dl.layers[stroke_of])
    return out, stroke_of


def _drop_repeated_points(dl: DisplayList, tol: float) -> DisplayList:
    """Drop each point within ``tol`` of the point before it in the same stroke."""
    if len(dl.points) < 2:
        return dl
    step = np.hypot(*np.diff(dl.points, axis=0).T)
    drop = np.zeros(len(dl.points), bool)
    drop[1:] = step <= tol
    drop[dl.offsets[:-1]] = False
    if not drop.any():
        return dl
    kept_before = np.concatenate([[0], np.cumsum(~drop)])
    return dataclasses.replace(dl, points=dl.points[~drop], offsets=kept_before[dl.offsets])


def _resolve_overlaps(p0: np.ndarray, p1: np.ndarray, group: np.ndarray, tol: float):
    """Find segments that retrace earlier ones of the same ``group`` on a common line.

    Returns ``keep`` (segments drawn whole) and the partial pieces of the others as
    (segment index, position along the segment, start points, end points).
    """
    m = len(p0)
    keep = np.ones(m, bool)
    empty = (np.zeros(0, np.int64), np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2)))
    if m < 2:
        return keep, empty
    origin = np.minimum(p0.min(axis=0), p1.min(axis=0))
    q0, q1 = p0 - origin, p1 - origin
    extent = max(float(np.max(np.abs(np.vstack([q0, q1])))), 1.0)
    ang_tol = tol / (4.0 * extent)  # a direction error that moves nothing in the drawing by more than tol/4
    d = q1 - q0
    theta = np.mod(np.arctan2(d[:, 1], d[:, 0]), np.pi)
    # fold the wrap-around at pi: directions within ang_tol below pi belong with those just above 0
    theta[theta > np.pi - ang_tol] -= np.pi
    dir_id, ref = _cluster_1d(theta, group, ang_tol)
    ux, uy = np.cos(ref), np.sin(ref)
    offset = -uy * q0[:, 0] + ux * q0[:, 1]
    t0 = ux * q0[:, 0] + uy * q0[:, 1]
    t1 = ux * q1[:, 0] + uy * q1[:, 1]
    line, _ = _cluster_1d(offset, dir_id, tol)
    size = np.bincount(line)
    shared = np.flatnonzero(size[line] > 1)
    if not len(shared):
        return keep, empty
    # only lines carrying several segments can overlap: paint each line's stretches, earliest segment first
    pieces: list[tuple[int, float, np.ndarray, np.ndarray]] = []
    o = shared[np.lexsort((shared, line[shared]))]
    bounds = np.flatnonzero(np.diff(line[o])) + 1
    for members in np.split(o, bounds):
        _paint_line(members, t0[members], t1[members], p0, p1, tol, keep, pieces)
    if not pieces:
        return keep, empty
    idx, pos, a, b = zip(*pieces, strict=False)
    return keep, (np.asarray(idx, np.int64), np.asarray(pos), np.asarray(a), np.asarray(b))


def _cluster_1d(values: np.ndarray, groups: np.ndarray, width: float) -> tuple[np.ndarray, np.ndarray]:
    """Cluster ``values`` within each of ``groups``: a cluster id per value and the smallest value of its cluster.

    Values closer than ``width`` to a neighbour share a cluster; a chain of such values spanning more than
    ``width`` is cut into bins of ``width`` from its smallest value, so no cluster is wider than ``width``.
    """
    o = np.lexsort((values, groups))
    v, g = values[o], groups[o]
    cut = np.ones(len(v), bool)
    cut[1:] = (g[1:] != g[:-1]) | (np.diff(v) > width)
    chain = np.cumsum(cut) - 1
    low = v[cut][chain]
    sub = np.floor((v - low) / width).astype(np.int64) if width > 0 else np.zeros(len(v), np.int64)
    key = np.cumsum(np.concatenate([[True], (chain[1:] != chain[:-1]) | (sub[1:] != sub[:-1])])) - 1
    first = np.flatnonzero(np.concatenate([[True], key[1:] != key[:-1]]))
    ids = np.empty(len(v), np.int64)
    ids[o] = key
    smallest = np.empty(len(v))
    smallest[o] = v[first][key]
    return ids, smallest


def _paint_line(members, t0, t1, p0, p1, tol, keep, pieces) -> None:
    """Give each stretch of one line to the earliest segment covering it; record what later segments keep."""
    lo, hi = np.minimum(t0, t1), np.maximum(t0, t1)
    lo_pt = np.where((t0 <= t1)[:, None], p0[members], p1[members])
    hi_pt = np.where((t0 <= t1)[:, None], p1[members], p0[members])
    marks = np.concatenate([lo, hi])
    mark_pts = np.concatenate([lo_pt, hi_pt])
    o = np.argsort(marks, kind="stable")
    marks, mark_pts = marks[o], mark_pts[o]
    # merge breakpoints closer than tol so that rounding leaves no slivers; a cut falls on a real end point
    first = np.concatenate([[True], np.diff(marks) > tol])
    reps, rep_pts = marks[first], mark_pts[first]
    ilo = np.searchsorted(reps, lo + tol, side="right") - 1
    ihi = np.searchsorted(reps, hi + tol, side="right") - 1
    owner = np.full(max(len(reps) - 1, 0), -1, np.int64)
    for k in range(len(members)):  # members are in drawing order
        span = owner[ilo[k] : ihi[k]]
        span[span < 0] = k
    for k, seg in enumerate(members.tolist()):
        mine = owner[ilo[k] : ihi[k]] == k
        if mine.all():
            continue  # drawn whole
        keep[seg] = False
        # runs of stretches this segment still draws, as sub-segments in its own direction
        edges = np.diff(np.concatenate([[0], mine.astype(np.int8), [0]]))
        run_starts, run_stops = np.flatnonzero(edges == 1) + ilo[k], np.flatnonzero(edges == -1) + ilo[k]
        for r0, r1 in zip(run_starts.tolist(), run_stops.tolist(), strict=False):
            a = lo_pt[k] if r0 == ilo[k] else rep_pts[r0]
            b = hi_pt[k] if r1 == ihi[k] else rep_pts[r1]
            start, stop = (a, b) if t1[k] >= t0[k] else (b, a)
            pieces.append((seg, float(np.hypot(*(start - p0[seg]))), start, stop))

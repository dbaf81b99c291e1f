"""Line, polyline and polygon clipping against rectangles and convex windows, vectorised (Hearn & Baker ch. 6).

Cohen–Sutherland region codes use Hearn & Baker's bit order: LEFT = 1 (x < xmin), RIGHT = 2 (x > xmax),
BOTTOM = 4 (y < ymin), TOP = 8 (y > ymax). Window edges are inside: a point on the border has code 0.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Literal, overload

import numpy as np

from pixelpen.errors import InvalidArgument
from pixelpen.geometry.transforms import ArrayLike, as_points, split_rows
from pixelpen.geometry.viewing import as_rect

LEFT, RIGHT, BOTTOM, TOP = 1, 2, 4, 8
"""Cohen–Sutherland outcode bits, in Hearn & Baker's order."""

ClipMethod = Literal["cohen-sutherland", "liang-barsky"]

# Points closer than this fraction of the window's size to a window edge count as lying on it
# (only convex windows need it: rectangle clipping puts border points exactly on the border).
_BORDER_TOL = 1e-9


def _codes(x: np.ndarray, y: np.ndarray, rect: tuple[float, float, float, float]) -> np.ndarray:
    """Outcodes of coordinate arrays (validated rectangle)."""
    xmin, ymin, xmax, ymax = rect
    codes: np.ndarray = (
        (x < xmin) * np.uint8(LEFT) | (x > xmax) * np.uint8(RIGHT)
        | (y < ymin) * np.uint8(BOTTOM) | (y > ymax) * np.uint8(TOP)
    ).astype(np.uint8)
    return codes


def outcodes(points: ArrayLike, window: Sequence[float]) -> np.ndarray:
    """Cohen–Sutherland 4-bit region codes (LEFT=1, RIGHT=2, BOTTOM=4, TOP=8) of an (N, 2) array or one point."""
    pts, single = as_points(points)
    codes = _codes(pts[:, 0], pts[:, 1], as_rect(window))
    return codes[0] if single else codes


def as_segments(segments: ArrayLike, name: str = "segments") -> np.ndarray:
    """Validate segments given as (N, 4) rows x0, y0, x1, y1 (or (N, 2, 2)); return float64 (N, 4)."""
    try:
        arr = np.asarray(segments, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"{name} must be an (N, 4) array of numbers x0, y0, x1, y1: {exc}") from None
    if arr.ndim == 3 and arr.shape[1:] == (2, 2):
        arr = arr.reshape(-1, 4)
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise InvalidArgument(f"{name} must be an (N, 4) array of rows x0, y0, x1, y1, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        row = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
        raise InvalidArgument(f"{name} contains a non-finite value (NaN or inf) at row {row}: {arr[row].tolist()}")
    return arr


def _cohen_sutherland(cols: np.ndarray, rect: tuple[float, float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised Cohen–Sutherland over (4, N) columns x0, y0, x1, y1; returns (clipped columns, source index).

    Outcodes accept (both codes 0) or reject (a common bit) most segments at once; the rest go through
    one pass per boundary (LEFT, RIGHT, BOTTOM, TOP), each moving every endpoint beyond that boundary
    onto it and rejecting segments with both ends beyond it.
    """
    c0, c1 = _codes(cols[0], cols[1], rect), _codes(cols[2], cols[3], rect)
    accepted = (c0 | c1) == 0
    work = np.flatnonzero(((c0 & c1) == 0) & ~accepted)
    s = np.take(cols, work, axis=1)
    alive = np.ones(len(work), dtype=bool)
    xmin, ymin, xmax, ymax = rect
    for axis, value, beyond in ((0, xmin, np.less), (0, xmax, np.greater), (1, ymin, np.less), (1, ymax, np.greater)):
        out0, out1 = beyond(s[axis], value), beyond(s[2 + axis], value)
        alive &= ~(out0 & out1)
        other = 1 - axis
        for p, q, out in ((0, 2, out0), (2, 0, out1)):  # p: the endpoint beyond, q: the other (not beyond)
            move = out & alive
            if move.any():  # whole-array arithmetic + masked copy beats gathering the few rows that move
                pa, qa, po, qo = s[p + axis], s[q + axis], s[p + other], s[q + other]
                with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # rows not moved
                    np.copyto(po, po + (value - pa) / (qa - pa) * (qo - po), where=move)
                np.copyto(pa, value, where=move)
    result = cols.copy()
    result[:, work] = s
    accepted[work[alive]] = True
    index = np.flatnonzero(accepted)
    return np.take(result, index, axis=1), index


def _parameters(num: np.ndarray, den: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t0, t1, keep) per segment for the constraints num + t den >= 0, t in [0, 1] (num, den: (K, N))."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # rejected columns may hold inf/nan
        ratio = -num / den
        t0 = np.maximum(np.where(den > 0, ratio, -np.inf).max(axis=0), 0.0)
        t1 = np.minimum(np.where(den < 0, ratio, np.inf).min(axis=0), 1.0)
    keep = ~((den == 0) & (num < 0)).any(axis=0) & (t0 <= t1)
    return t0, t1, keep


def _parametric_clip(cols: np.ndarray, num: np.ndarray, den: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Clip P(t) = P0 + t (P1 - P0), t in [0, 1], to the constraints num + t den >= 0 (Liang–Barsky / Cyrus–Beck).

    cols: (4, N) columns x0, y0, x1, y1; num, den: (K, N) per constraint and segment.
    Returns (clipped columns, source index).
    """
    t0, t1, keep = _parameters(num, den)
    index = np.flatnonzero(keep)
    x0, y0, x1, y1 = np.take(cols, index, axis=1)
    t0, t1 = t0[index], t1[index]
    dx, dy = x1 - x0, y1 - y0
    enter, leave = t0 > 0, t1 < 1
    out = np.stack([
        np.where(enter, x0 + t0 * dx, x0), np.where(enter, y0 + t0 * dy, y0),
        np.where(leave, x0 + t1 * dx, x1), np.where(leave, y0 + t1 * dy, y1),
    ])
    return out, index


def _rect_constraints(cols: np.ndarray, rect: tuple[float, float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Liang–Barsky's q_k - p_k t >= 0 for the four boundaries, as (num = q, den = -p)."""
    xmin, ymin, xmax, ymax = rect
    x0, y0, x1, y1 = cols
    dx, dy = x1 - x0, y1 - y0
    return np.stack([x0 - xmin, xmax - x0, y0 - ymin, ymax - y0]), np.stack([dx, -dx, dy, -dy])


def liang_barsky_parameters(
    cols: np.ndarray, rect: tuple[float, float, float, float]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Liang–Barsky parameters of every segment: (t0, t1, keep), the part t0..t1 of each lies in ``rect``.

    ``cols`` are (4, N) float columns x0, y0, x1, y1 and ``rect`` is (xmin, ymin, xmax, ymax), both taken as
    they are (no checks: for engines that already hold valid arrays). Rejected segments have ``keep`` False.
    """
    return _parameters(*_rect_constraints(cols, rect))


def _liang_barsky(cols: np.ndarray, rect: tuple[float, float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised Liang–Barsky clipping of (4, N) columns to ``rect``."""
    return _parametric_clip(cols, *_rect_constraints(cols, rect))


def clip_segments(
    segments: ArrayLike, window: Sequence[float], method: ClipMethod = "cohen-sutherland"
) -> tuple[np.ndarray, np.ndarray]:
    """Clip (N, 4) segments x0, y0, x1, y1 to a rectangle; return (clipped (M, 4), source row index (M,)).

    Segments keep their direction; a segment touching the window in one point becomes a zero-length
    segment. Both methods give the same segments up to rounding.
    """
    cols = np.ascontiguousarray(as_segments(segments).T)
    rect = as_rect(window)
    if method == "cohen-sutherland":
        out, index = _cohen_sutherland(cols, rect)
    elif method == "liang-barsky":
        out, index = _liang_barsky(cols, rect)
    else:
        raise InvalidArgument(f"unknown clipping method {method!r}: use 'cohen-sutherland' or 'liang-barsky'")
    xmin, ymin, xmax, ymax = rect
    np.clip(out[0::2], xmin, xmax, out=out[0::2])  # remove rounding overshoot past the border
    np.clip(out[1::2], ymin, ymax, out=out[1::2])
    return np.ascontiguousarray(out.T), index


def _signed_area(ring: np.ndarray) -> float:
    """Shoelace signed area of a closed ring (positive when counter-clockwise)."""
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def as_convex_window(polygon: ArrayLike, name: str = "convex_polygon") -> np.ndarray:
    """Validate a convex polygon window (either orientation, >= 3 vertices); return it counter-clockwise."""
    w, _ = as_points(polygon, name, min_rows=3)
    edges = np.roll(w, -1, axis=0) - w
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    if (lengths == 0).any():
        i = int(np.flatnonzero(lengths == 0)[0])
        raise InvalidArgument(f"{name} has a zero-length edge at vertex {i} (repeated point {w[i].tolist()})")
    nxt = np.roll(edges, -1, axis=0)
    cross = edges[:, 0] * nxt[:, 1] - edges[:, 1] * nxt[:, 0]
    dot = (edges * nxt).sum(axis=1)
    tol = 1e-12 * lengths * np.roll(lengths, -1)
    if (cross > tol).any() and (cross < -tol).any():
        majority = 1.0 if (cross > tol).sum() >= (cross < -tol).sum() else -1.0
        i = int(np.flatnonzero(majority * cross < -tol)[0])
        raise InvalidArgument(f"{name} is not convex: it turns the other way at vertex {(i + 1) % len(w)}")
    extent = float(np.ptp(w, axis=0).max())
    if abs(_signed_area(w)) <= 1e-12 * extent * extent:
        raise InvalidArgument(f"{name} is degenerate: its vertices are collinear (zero area)")
    turning = float(np.arctan2(cross, dot).sum())
    if abs(abs(turning) - 2 * np.pi) > 1e-6:
        raise InvalidArgument(
            f"{name} is not a simple convex polygon (total turning {turning / np.pi:.3g} pi, expected 2 pi): "
            "it is degenerate or winds more than once"
        )
    return w if turning > 0 else w[::-1].copy()


def _clip_halfplane(v: np.ndarray, d: np.ndarray, snap: tuple[int, float] | None) -> np.ndarray:
    """One Sutherland–Hodgman stage over a whole ring: keep d >= 0, vectorised over the vertex array.

    For each edge prev -> cur: out->in emits the intersection and cur, in->in emits cur, in->out emits
    the intersection, out->out nothing. ``snap`` (axis, value) puts intersections exactly on an
    axis-parallel boundary.
    """
    prev, dprev = np.roll(v, 1, axis=0), np.roll(d, 1)
    inside, prev_inside = d >= 0, dprev >= 0
    cross = inside != prev_inside
    counts = cross.astype(np.intp) + inside
    out = np.empty((int(counts.sum()), 2))
    pos = np.cumsum(counts) - counts
    if cross.any():
        t = dprev[cross] / (dprev[cross] - d[cross])
        hit = prev[cross] + t[:, None] * (v[cross] - prev[cross])
        if snap is not None:
            hit[:, snap[0]] = snap[1]
        out[pos[cross]] = hit
    out[pos[inside] + cross[inside]] = v[inside]
    return out


def _dedupe(ring: np.ndarray) -> np.ndarray:
    """Drop vertices equal to their predecessor (cyclically)."""
    if len(ring) < 2:
        return ring
    keep = (ring != np.roll(ring, 1, axis=0)).any(axis=1)
    return ring[keep] if keep.any() else ring[:1]


class _ConvexWindow:
    """A counter-clockwise convex window: edges, inward unit normals and the perimeter coordinate along them."""

    def __init__(self, corners: np.ndarray) -> None:
        self.corners = corners
        edges = np.roll(corners, -1, axis=0) - corners
        self.lengths = np.hypot(edges[:, 0], edges[:, 1])
        self.units = edges / self.lengths[:, None]
        self.normals = np.stack([-self.units[:, 1], self.units[:, 0]], axis=1)  # left of a CCW edge = inside
        self.starts = np.concatenate([[0.0], np.cumsum(self.lengths)[:-1]])  # perimeter coordinate of each corner
        self.perimeter = float(self.lengths.sum())
        size = float(max(np.ptp(corners, axis=0).max(), np.abs(corners).max()))
        self.tol = _BORDER_TOL * size
        self.area = _signed_area(corners)

    def distances(self, points: np.ndarray) -> np.ndarray:
        """Signed distance of each point to each edge line, (N, K), positive inside."""
        distances: np.ndarray = np.einsum("nkj,kj->nk", points[:, None, :] - self.corners[None], self.normals)
        return distances

    def snap(self, k: int) -> tuple[int, float] | None:
        """(axis, value) when edge k is axis-parallel, so intersections can be placed exactly on it."""
        if self.units[k, 0] == 0.0:
            return (0, float(self.corners[k, 0]))
        if self.units[k, 1] == 0.0:
            return (1, float(self.corners[k, 1]))
        return None

    def sutherland_hodgman(self, ring: np.ndarray) -> np.ndarray:
        """Clip a ring against every edge in turn (the single, possibly degenerate, S-H output ring)."""
        for k in range(len(self.corners)):
            if len(ring) == 0:
                break
            ring = _clip_halfplane(ring, (ring - self.corners[k]) @ self.normals[k], self.snap(k))
        return _dedupe(ring)

    def perimeter_coordinate(self, points: np.ndarray, on: np.ndarray) -> np.ndarray:
        """Arc length from corner 0, counter-clockwise, of points lying on the border (``on``: (N, K) flags)."""
        k = np.argmax(on, axis=1)
        along = np.clip(((points - self.corners[k]) * self.units[k]).sum(axis=1), 0.0, self.lengths[k])
        s = self.starts[k] + along
        return np.where(s >= self.perimeter - self.tol, 0.0, s)

    def border_travel(self, ring: np.ndarray, on: np.ndarray, border: np.ndarray) -> float:
        """Signed distance the ring's border edges run counter-clockwise along the window border, in total."""
        i = np.flatnonzero(border)
        k = np.argmax(on[i] & on[(i + 1) % len(ring)], axis=1)  # the window edge each border edge lies along
        return float(((ring[(i + 1) % len(ring)] - ring[i]) * self.units[k]).sum())

    def link_chains(
        self, s_begin: np.ndarray, s_end: np.ndarray, travel: Callable[[], float]
    ) -> tuple[np.ndarray, np.ndarray]:
        """Each chain's successor and the counter-clockwise border gap from its exit to that chain's entry.

        Exits (the border ahead is covered) and entries (covered behind) alternate along the border; where
        some coincide (zero-width spikes, corners), the order within the group keeps that alternation, so
        every entry follows exactly one exit. When every group holds as many exits as entries (a chain
        ending where it began), that cannot tell a zero gap from a full loop; the geometry can:
        Sutherland–Hodgman keeps the winding number inside the window, so the rings must run along the
        border as far in total as the S-H ring's own border edges do (``travel()``: all of it or nothing).
        """
        m, perimeter = len(s_begin), self.perimeter
        s = np.concatenate([s_end, s_begin])  # events 0..m-1 exits, m..2m-1 entries
        order = np.argsort(s, kind="stable")
        apart = np.diff(s[order], append=s[order[0]] + perimeter) > self.tol  # a real gap after each event
        if apart.any():  # start just after a real gap, so no group of coincident events wraps past the start
            j = (int(np.flatnonzero(apart)[-1]) + 1) % (2 * m)
            order, apart = np.roll(order, -j), np.roll(apart, -j)
        group = np.concatenate([[0], np.cumsum(apart[:-1])])
        exits = order < m
        sign = np.where(exits, 1, -1)
        before = np.cumsum(sign) - sign  # covered depth before each event, less the depth at the start
        first = np.flatnonzero(np.concatenate([[True], apart[:-1]]))
        arrive = before[first]
        start = -int(arrive.min()) if arrive.min() < arrive.max() else int(travel() > 0.5 * perimeter)
        exit_first = start + arrive[group] <= 0
        ranks = np.cumsum(exits) - exits, np.cumsum(~exits) - ~exits  # events of each kind before each event
        nth = np.where(exits, ranks[0] - ranks[0][first][group], ranks[1] - ranks[1][first][group])  # in its group
        seq = np.lexsort((2 * nth + (exits != exit_first), group))
        entry_pos = np.flatnonzero(~exits[seq])
        exit_pos = np.flatnonzero(exits[seq])
        follow = entry_pos[np.searchsorted(entry_pos, exit_pos) % m]
        chain, nxt = order[seq[exit_pos]], order[seq[follow]] - m
        same = group[seq[exit_pos]] == group[seq[follow]]
        gap = np.where(same, np.where(follow > exit_pos, 0.0, perimeter), (s_begin[nxt] - s_end[chain]) % perimeter)
        successor, gaps = np.empty(m, dtype=np.intp), np.empty(m)
        successor[chain], gaps[chain] = nxt, gap
        return successor, gaps

    def split_rings(self, ring: np.ndarray) -> list[np.ndarray]:
        """Cut a Sutherland–Hodgman ring (counter-clockwise input) at its border edges and re-join the pieces.

        Removing every edge that lies along a window edge leaves chains of the polygon's own boundary,
        each entering and leaving the window; following each exit counter-clockwise along the border to
        the next entry (Weiler–Atherton for a convex window) gives the separate output rings, with no
        zero-area connecting edges.
        """
        n = len(ring)
        if n < 3:
            return []
        on = np.abs(self.distances(ring)) <= self.tol
        border = (on & np.roll(on, -1, axis=0)).any(axis=1)  # edge i: ring[i] -> ring[i + 1]
        if not border.any():
            return [ring]
        if border.all():  # region is all of the window or nothing
            return [self.corners.copy()] if _signed_area(ring) > 0.5 * self.area else []
        shift = (int(np.flatnonzero(border)[0]) + 1) % n  # start just after a border edge
        ring, on, border = np.roll(ring, -shift, axis=0), np.roll(on, -shift, axis=0), np.roll(border, -shift)
        ends = np.flatnonzero(border)
        begins = np.concatenate([[0], ends[:-1] + 1])
        real = ends > begins
        begins, ends = begins[real], ends[real]
        chains = [ring[b:e + 1] for b, e in zip(begins, ends, strict=False)]
        s_begin = self.perimeter_coordinate(ring[begins], on[begins])
        s_end = self.perimeter_coordinate(ring[ends], on[ends])
        nxt, gap = self.link_chains(s_begin, s_end, lambda: self.border_travel(ring, on, border))
        ahead = (self.starts[None, :] - s_end[:, None]) % self.perimeter  # distance to each corner
        passed = (ahead > self.tol) & (ahead < gap[:, None] - self.tol)
        used = np.zeros(len(chains), dtype=bool)
        rings = []
        for first in range(len(chains)):
            parts = []
            c = first
            while not used[c]:
                used[c] = True
                corner_ids = np.flatnonzero(passed[c])
                parts += [chains[c], self.corners[corner_ids[np.argsort(ahead[c, corner_ids])]]]
                c = int(nxt[c])
            if parts:
                rings.append(_dedupe(np.concatenate(parts)))
        return rings

    def clip_polygon(self, vertices: ArrayLike) -> list[np.ndarray]:
        """Clip one simple polygon (either orientation) to this window; rings keep the input's orientation."""
        v, _ = as_points(vertices, "vertices", min_rows=3)
        clockwise = _signed_area(v) < 0
        ring = self.sutherland_hodgman(v[::-1] if clockwise else v)
        area_floor = 1e-15 * abs(self.area)
        rings = [r for r in self.split_rings(ring) if len(r) >= 3 and abs(_signed_area(r)) > area_floor]
        return [r[::-1].copy() for r in rings] if clockwise else rings


def _rect_window(rect: tuple[float, float, float, float]) -> _ConvexWindow:
    """The rectangle as a counter-clockwise convex window starting at (xmin, ymin)."""
    xmin, ymin, xmax, ymax = rect
    return _ConvexWindow(np.array([(xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax)]))


def clip_polygon(vertices: ArrayLike, window: Sequence[float]) -> list[np.ndarray]:
    """Clip a simple polygon (concave allowed, either orientation) to a rectangle: a list of (K, 2) rings.

    Sutherland–Hodgman (vectorised per boundary over the vertex array), then the output is cut where it
    runs along the window border and re-joined into separate rings, so a concave polygon that leaves
    and re-enters the window gives several rings with no zero-area connecting edges. Rings are open
    (the first vertex is not repeated) and keep the input's orientation; empty when nothing is inside.
    """
    return _rect_window(as_rect(window)).clip_polygon(vertices)


def clip_segments_convex(segments: ArrayLike, convex_polygon: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Cyrus–Beck: clip (N, 4) segments to a convex polygon (either orientation); returns (clipped, source index)."""
    cols = np.ascontiguousarray(as_segments(segments).T)
    win = _ConvexWindow(as_convex_window(convex_polygon))
    num = win.normals @ cols[:2] - (win.normals * win.corners).sum(axis=1)[:, None]  # n_k . (P0 - V_k)
    den = win.normals @ (cols[2:] - cols[:2])  # n_k . D
    out, index = _parametric_clip(cols, num, den)
    return np.ascontiguousarray(out.T), index


def clip_polygon_convex(vertices: ArrayLike, convex_polygon: ArrayLike) -> list[np.ndarray]:
    """Clip a simple polygon to a convex polygon window (either orientation) by Sutherland–Hodgman: a list of rings.

    Like :func:`clip_polygon`, border-running pieces of concave input are split into separate rings.
    """
    return _ConvexWindow(as_convex_window(convex_polygon)).clip_polygon(vertices)


@overload
def clip_polylines(
    polylines: Sequence[ArrayLike], window: Sequence[float], *, return_index: Literal[False] = False
) -> list[np.ndarray]: ...


@overload
def clip_polylines(
    polylines: Sequence[ArrayLike], window: Sequence[float], *, return_index: Literal[True]
) -> tuple[list[np.ndarray], np.ndarray]: ...


def clip_polylines(
    polylines: Sequence[ArrayLike], window: Sequence[float], *, return_index: bool = False
) -> list[np.ndarray] | tuple[list[np.ndarray], np.ndarray]:
    """Clip polylines (a list of (N, 2) arrays) to a rectangle; a polyline leaving and re-entering gives several pieces.

    All segments of all polylines go through :func:`clip_segments` in one batch; consecutive clipped
    segments are re-joined where they still connect. A one-point polyline inside stays one point. With
    ``return_index`` also returns, per piece, the index of the polyline it came from.
    """
    rect = as_rect(window)
    arrays = [as_points(p, f"polylines[{i}]", min_rows=1)[0] for i, p in enumerate(polylines)]
    if not arrays:
        return ([], np.zeros(0, dtype=np.intp)) if return_index else []
    counts = np.array([len(a) for a in arrays])
    pts = np.concatenate(arrays)
    firsts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    owner_of_point = np.repeat(np.arange(len(arrays)), counts)
    begins = np.ones(len(pts), dtype=bool)
    begins[firsts + counts - 1] = False  # the last point of a polyline begins no segment ...
    begins[firsts[counts == 1]] = True  # ... unless it is the only one (a zero-length segment)
    a = np.flatnonzero(begins)
    single = counts[owner_of_point[a]] == 1
    b = np.where(single, a, a + 1)
    clipped, src = clip_segments(np.hstack([pts[a], pts[b]]), rect)
    owner, single = owner_of_point[a][src], single[src]
    joins = np.zeros(len(src), dtype=bool)
    joins[1:] = (
        (src[1:] == src[:-1] + 1) & (owner[1:] == owner[:-1]) & (clipped[1:, :2] == clipped[:-1, 2:]).all(axis=1)
    )
    new = ~joins
    slots = new.astype(np.intp) + ~single
    pos = np.cumsum(slots) - slots
    flat = np.empty((int(slots.sum()), 2))
    flat[pos[new]] = clipped[new, :2]
    flat[pos[~single] + new[~single]] = clipped[~single, 2:]
    pieces = split_rows(flat, pos[new])
    return (pieces, owner[new]) if return_index else pieces

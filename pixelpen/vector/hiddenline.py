"""Hidden-line removal for plotters: split 3D edges where triangles hide them, keep the visible pieces.

Object-space visibility in screen space (Hearn & Baker, visible-line detection): every coordinate is device
x, y plus NDC depth z (0 at the near plane .. 1 at the far plane, the one z range of pixelpen). Projection
maps planes to planes, so a triangle's depth at a screen point is its plane's (affine in x, y) and an edge's
depth is linear in its screen parameter t ∈ [0, 1]. A point of an edge is hidden where some triangle covers
it in 2D (sides included) and is nearer by more than ``eps``; the triangles an edge lies on (``edge_faces``)
never hide it, and neither does a face coplanar with it (a depth tie is not nearer by more than ``eps``).

Steps, all vectorised: (1) a uniform grid of bins over the edges' bounding box; each triangle and edge is
put in the bins its bounding box overlaps; (2) (edge, triangle) candidate pairs come from shared bins, each
pair counted once, in the bin holding the lower-left corner of the overlap of the two boxes, and pairs whose
boxes do not overlap or whose triangle lies wholly behind the edge are dropped; (3) per pair the hidden
t-interval is the edge's parametric line clipped (Cyrus–Beck) against the triangle's three 2D half-planes and
the depth half-space; (4) the intervals are united per edge (sorted by edge, then start; a running maximum
of the ends per edge by ``np.maximum.accumulate``) and the complement in [0, 1] is the visible part. Pairs
are processed in chunks of at most ``PAIR_CHUNK`` so memory stays bounded however many pairs there are.

Robustness: a triangle's side functions are evaluated at the edge's two endpoints, from the side's endpoints
taken in a canonical (sorted) order, so two triangles sharing a side cut a line at bit-identical parameters
and their hidden intervals meet without a gap, and an edge ending at a vertex is cut at exactly t = 0 or 1;
sides are closed, so an edge running exactly along a side shared by two nearer triangles is hidden. Depth is
compared at the ends of the part inside the triangle (interpolated, never extrapolated). A pair hides only
where the triangle is nearer by more than ``eps``, but once it hides something its interval is widened to
where it is not farther than ``eps``: an occluder meeting an edge at a shared vertex then hides the edge right
up to that vertex instead of leaving a visible stub of length eps / (depth slope). Because a depth tie never
hides, triangles coplanar with an edge (e.g. pieces of its face cut by 3D clipping, not listed in
``edge_faces``) leave it alone. Triangles with (almost) no 2D area cover nothing and are ignored.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.geometry.transforms import ArrayLike, as_batch, as_number
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.merge import merge_paths

__all__ = ["DEFAULT_EPS", "PAIR_CHUNK", "HiddenLineStats", "HiddenLines", "hidden_lines"]

DEFAULT_EPS = 1e-9
"""Default depth tolerance in NDC z units: a triangle hides a point only when nearer by more than this."""

PAIR_CHUNK = 1 << 17
"""Candidate (edge, triangle) pairs expanded and clipped at a time (bounds the working memory)."""

_DEGENERATE = 1e-10  # a triangle with |2·area| <= this · (longest side)² covers no area
_CELLS_PER_ITEM = 2  # the grid has at most this many bins per edge and triangle


@dataclass(frozen=True)
class HiddenLineStats:
    """Counts of one hidden-line run: edges in, pieces out, pairs clipped, fraction of edge length hidden."""

    edges_in: int
    pieces_out: int
    pairs_tested: int
    """(edge, triangle) pairs clipped: candidates from the bins with overlapping boxes, not wholly behind."""
    hidden_fraction: float
    """1 − (2D length of the pieces) / (2D length of the edges); 0 when the edges have no length."""


@dataclass(frozen=True)
class HiddenLines:
    """Visible pieces: ``segments`` (K, 2, 2) device x, y; ``edge`` (K,) the source edge of each; ``stats``.

    Pieces come sorted by source edge, then along it from the edge's first endpoint; a piece ending at an
    edge endpoint has that endpoint's exact coordinates.
    """

    segments: np.ndarray
    edge: np.ndarray
    stats: HiddenLineStats

    def polylines(self, tolerance: float = 1e-6) -> list[np.ndarray]:
        """The pieces joined end to end where their ends lie within ``tolerance`` (device units): (N, 2) arrays."""
        k = len(self.segments)
        dl = DisplayList(self.segments.reshape(-1, 2), np.arange(0, 2 * k + 1, 2), np.ones(k), np.zeros(k))
        return [stroke.copy() for stroke in merge_paths(dl, tolerance).strokes()]


def _as_edge_faces(value: ArrayLike | None, edges: int, triangles: int) -> np.ndarray:
    """Validate edge_faces: (E, 2) integer triangle indices, −1 for none (None means no adjacency)."""
    if value is None:
        return np.full((edges, 2), -1, np.int64)
    arr = np.asarray(value)
    if arr.size == 0 and edges == 0:
        return np.zeros((0, 2), np.int64)
    if arr.dtype.kind not in "iu":
        raise InvalidArgumentType(f"edge_faces must be an array of integer triangle indices, got dtype {arr.dtype}")
    if arr.shape != (edges, 2):
        raise InvalidArgument(f"edge_faces must have shape ({edges}, 2) (two faces per edge), got {arr.shape}")
    bad = ((arr < -1) | (arr >= triangles)).any(axis=1)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise InvalidArgument(
            f"edge_faces row {row} is {arr[row].tolist()}: indices must be −1 or in [0, {triangles})"
        )
    return arr.astype(np.int64)


def _as_tolerance(value: object, name: str) -> float:
    """A finite number >= 0."""
    result = as_number(value, name)
    if result < 0:
        raise InvalidArgument(f"{name} must be >= 0, got {result}")
    return result


@dataclass(frozen=True)
class _Triangles:
    """Per-triangle data for clipping, only for triangles with area: edge functions, depth plane, boxes."""

    index: np.ndarray  # (T,) index into the caller's triangles
    base: np.ndarray  # (T, 3, 2) each side from base to base + along (its endpoints in canonical order) ...
    along: np.ndarray  # (T, 3, 2) ... and the inside is side · cross(along, x − base) > 0
    side: np.ndarray  # (T, 3) ±1
    anchor: np.ndarray  # (T, 3) first vertex a ...
    slope: np.ndarray  # (T, 2) ... and depth gradient g: the plane's depth is a.z + g · (x − a.xy)
    lo: np.ndarray  # (T, 3) box minimum x, y and nearest depth
    hi: np.ndarray  # (T, 2) box maximum x, y


def _prepare_triangles(tris: np.ndarray, segs: np.ndarray, eps: float) -> _Triangles:
    """Edge functions (from sorted endpoints, so shared edges agree bit for bit) and depth planes.

    Only triangles with area that overlap the edges' box and are not wholly behind every edge are kept.
    """
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    n3 = np.cross(b - a, c - a)  # 3D normal in screen space; n3[:, 2] = twice the signed 2D area
    sides = np.stack([b - a, c - b, a - c], axis=1)[:, :, :2]
    longest = (sides**2).sum(axis=2).max(axis=1)
    keep = np.abs(n3[:, 2]) > _DEGENERATE * longest
    if len(segs):
        lo, hi = tris.min(axis=1), tris.max(axis=1)
        keep &= (lo[:, :2] <= segs[:, :, :2].max(axis=(0, 1))).all(axis=1)
        keep &= (hi[:, :2] >= segs[:, :, :2].min(axis=(0, 1))).all(axis=1)
        keep &= lo[:, 2] < segs[:, :, 2].max() - eps
    tris, n3 = tris[keep], n3[keep]
    start, end = tris[:, :, :2], np.roll(tris, -1, axis=1)[:, :, :2]
    # canonical order of each side's endpoints: lexicographic on (x, y)
    swap = (start[..., 0] > end[..., 0]) | ((start[..., 0] == end[..., 0]) & (start[..., 1] > end[..., 1]))
    p = np.where(swap[..., None], end, start)
    q = np.where(swap[..., None], start, end)
    orient = np.sign(n3[:, 2])[:, None]  # the inside is left of each directed side for CCW (orient > 0)
    side = np.where(swap, -orient, orient)
    return _Triangles(
        index=np.flatnonzero(keep),
        base=p,
        along=q - p,
        side=side,
        anchor=tris[:, 0],
        slope=-n3[:, :2] / n3[:, 2:],
        lo=tris.min(axis=1),
        hi=tris.max(axis=1)[:, :2],
    )


@dataclass(frozen=True)
class _Grid:
    """A uniform grid of square bins: origin, bin size and counts."""

    x0: float
    y0: float
    size: float
    nx: int
    ny: int

    def cell_range(self, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """First and last bin (column, row) overlapped by boxes lo..hi (N, 2), clamped to the grid."""
        limit = np.array([self.nx - 1, self.ny - 1])
        origin = np.array([self.x0, self.y0])
        first = np.clip(np.floor((lo - origin) / self.size), 0, limit).astype(np.int64)
        last = np.clip(np.floor((hi - origin) / self.size), 0, limit).astype(np.int64)
        return first, last

    def bins(self, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(item, bin) entries for every bin each box overlaps, items ascending."""
        first, last = self.cell_range(lo, hi)
        span = last - first + 1
        count = span[:, 0] * span[:, 1]
        item = np.repeat(np.arange(len(lo)), count)
        k = np.arange(len(item)) - np.repeat(np.cumsum(count) - count, count)
        col = first[item, 0] + k % span[item, 0]
        row = first[item, 1] + k // span[item, 0]
        return item, row * self.nx + col


def _make_grid(edge_lo: np.ndarray, edge_hi: np.ndarray, tri_lo: np.ndarray, tri_hi: np.ndarray) -> _Grid:
    """Bins over the edges' bounding box, about as large as the typical item, at most a few per item."""
    x0, y0 = edge_lo.min(axis=0)
    width, height = edge_hi.max(axis=0) - (x0, y0)
    extent = np.concatenate([(edge_hi - edge_lo).max(axis=1), (tri_hi - tri_lo[:, :2]).max(axis=1)])
    area = max(float(width) * float(height), 1e-300)
    size = max(float(np.mean(extent)), float(np.sqrt(area / (_CELLS_PER_ITEM * len(extent)))), 1e-300)
    size = max(size, float(width) / 4096, float(height) / 4096)
    nx = int(min(np.floor(width / size) + 1, 4097))
    ny = int(min(np.floor(height / size) + 1, 4097))
    return _Grid(float(x0), float(y0), size, nx, ny)


def _bounds(alpha: np.ndarray, beta: np.ndarray, closed: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Cyrus–Beck: the t-range where every alpha_k + beta_k·t > 0 (>= 0 if ``closed``), as (lo, hi) per row.

    The range is empty when hi <= lo; ``closed`` matters only for a constant constraint that is exactly 0.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        cut = -alpha / beta
    lo = np.where(beta > 0, cut, -np.inf).max(axis=1)
    hi = np.where(beta < 0, cut, np.inf).min(axis=1)
    never = ((beta == 0) & ((alpha < 0) if closed else (alpha <= 0))).any(axis=1)
    return lo, np.where(never, -np.inf, hi)


def _side_values(x: np.ndarray, base: np.ndarray, along: np.ndarray) -> np.ndarray:
    """cross(along, x − base) for points x (N, 2) against sides (N, 3, 2): exactly 0 at either side endpoint."""
    rel = x[:, None, :] - base
    return along[..., 0] * rel[..., 1] - along[..., 1] * rel[..., 0]


def _clip_pairs(
    e: np.ndarray, t: np.ndarray, start: np.ndarray, end: np.ndarray, tri: _Triangles, eps: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hidden t-intervals (edge, lo, hi) of the pairs (e, t) that hide something.

    Each side constraint is affine in t and given by its values at the edge's ends (v0 + (v1 − v0)·t >= 0), so
    an edge ending at a triangle vertex or on a side is cut at exactly t = 0 or 1 there. The sides are closed so
    that an edge running exactly along a side shared by two occluding triangles is hidden by both. The depth difference
    is then taken at the ends of the piece inside the triangle, where the plane is interpolated (accurate even
    for thin, steep triangles), and is linear in between.
    """
    p, q = start[e], end[e]
    base, along, side = tri.base[t], tri.along[t], tri.side[t]
    alpha = side * _side_values(p[:, :2], base, along)
    lo, hi = _bounds(alpha, side * _side_values(q[:, :2], base, along) - alpha, closed=True)
    lo, hi = np.maximum(lo, 0.0), np.minimum(hi, 1.0)
    inside = hi > lo
    e, t, p, q, lo, hi = e[inside], t[inside], p[inside], q[inside], lo[inside], hi[inside]
    # depth difference (edge z − triangle z) at both ends of the piece: d(s) = d0 + (d1 − d0)·s, s ∈ [0, 1]
    anchor, slope = tri.anchor[t], tri.slope[t]
    ends = [(1 - u)[:, None] * p + u[:, None] * q for u in (lo, hi)]
    d0, d1 = (x[:, 2] - anchor[:, 2] - ((x[:, :2] - anchor[:, :2]) * slope).sum(axis=1) for x in ends)
    strict_lo, strict_hi = _bounds((d0 - eps)[:, None], (d1 - d0)[:, None])
    hides = np.minimum(strict_hi, 1.0) > np.maximum(strict_lo, 0.0)  # nearer by more than eps somewhere
    d0, d1, lo, hi = d0[hides], d1[hides], lo[hides], hi[hides]
    loose_lo, loose_hi = _bounds((d0 + eps)[:, None], (d1 - d0)[:, None])  # ... then hidden where not farther
    s0, s1 = np.maximum(loose_lo, 0.0), np.minimum(loose_hi, 1.0)
    return e[hides], (1 - s0) * lo + s0 * hi, (1 - s1) * lo + s1 * hi


def _hidden_intervals(
    start: np.ndarray, end: np.ndarray, own: np.ndarray, tri: _Triangles, eps: float
) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], int]:
    """All hidden intervals (edge, lo, hi) of candidate pairs from the bins, and the number of pairs clipped.

    ``own`` (E, 2) holds each edge's faces as indices of kept triangles (−1: none or not kept).
    """
    empty = (np.zeros(0, np.int64), np.zeros(0), np.zeros(0))
    if not len(start) or not len(tri.index):
        return empty, 0
    edge_lo, edge_hi = np.minimum(start, end), np.maximum(start, end)
    grid = _make_grid(edge_lo[:, :2], edge_hi[:, :2], tri.lo, tri.hi)
    tri_item, tri_bin = grid.bins(tri.lo[:, :2], tri.hi)
    order = np.argsort(tri_bin, kind="stable")
    tri_item = tri_item[order]
    count = np.bincount(tri_bin, minlength=grid.nx * grid.ny)
    first = np.cumsum(count) - count
    edge_item, edge_bin = grid.bins(edge_lo[:, :2], edge_hi[:, :2])
    live = count[edge_bin] > 0
    edge_item, edge_bin = edge_item[live], edge_bin[live]
    pairs_per_entry = count[edge_bin]
    total = np.cumsum(pairs_per_entry)
    # boxes packed for one gather per pair: x, y min, x, y max, then the edge's farthest depth − eps and the
    # triangle's nearest depth (a triangle hides nothing of an edge wholly nearer than it)
    edge_box = np.column_stack([edge_lo[:, :2], edge_hi[:, :2], edge_hi[:, 2] - eps])
    tri_box = np.column_stack([tri.lo[:, :2], tri.hi, tri.lo[:, 2]])
    found: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    tested = 0
    i = 0
    while i < len(edge_item):
        done = int(total[i - 1]) if i else 0
        j = max(int(np.searchsorted(total, done + PAIR_CHUNK, side="right")), i + 1)
        n_pairs = pairs_per_entry[i:j]
        shift = np.repeat(first[edge_bin[i:j]] - (np.cumsum(n_pairs) - n_pairs), n_pairs)
        t = tri_item[shift + np.arange(len(shift))]
        entry = np.repeat(np.arange(i, j), n_pairs)
        e = edge_item[entry]
        eb, tb = edge_box[e], tri_box[t]
        x0, y0 = np.maximum(eb[:, 0], tb[:, 0]), np.maximum(eb[:, 1], tb[:, 1])
        ok = (x0 <= np.minimum(eb[:, 2], tb[:, 2])) & (y0 <= np.minimum(eb[:, 3], tb[:, 3])) & (tb[:, 4] < eb[:, 4])
        keep = np.flatnonzero(ok)
        e, t, entry = e[keep], t[keep], entry[keep]
        # each pair once: in the bin of the lower-left corner of the boxes' overlap; never by the edge's own faces
        home, _ = grid.cell_range(np.column_stack([x0[keep], y0[keep]]), np.zeros((len(keep), 2)))
        keep = (home[:, 1] * grid.nx + home[:, 0] == edge_bin[entry]) & (t != own[e, 0]) & (t != own[e, 1])
        e, t = e[keep], t[keep]
        tested += len(e)
        found.append(_clip_pairs(e, t, start, end, tri, eps))
        i = j
    if not found:
        return empty, tested
    edges, los, his = (np.concatenate(parts) for parts in zip(*found, strict=True))
    return (edges, los, his), tested


def _visible_intervals(
    n_edges: int, edge: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Complement in [0, 1] of the union of hidden intervals per edge: (edge, t0, t1) sorted by edge, t0."""
    order = np.lexsort((lo, edge))
    edge, lo, hi = edge[order], lo[order], hi[order]
    new_edge = np.ones(len(edge), bool)
    new_edge[1:] = edge[1:] != edge[:-1]
    # running maximum of hi within each edge, exactly: accumulate integer keys edge group · N + rank of hi
    n = len(hi)
    rank = np.empty(n, np.int64)
    by_hi = np.argsort(hi, kind="stable")
    rank[by_hi] = np.arange(n)
    group = np.cumsum(new_edge) - 1
    run_max = hi[by_hi][np.maximum.accumulate(group * n + rank) - group * n]
    new_run = new_edge.copy()
    new_run[1:] |= lo[1:] > run_max[:-1]
    starts = np.flatnonzero(new_run)
    run_edge, run_lo = edge[starts], lo[starts]
    run_hi = np.maximum.reduceat(hi, starts) if n else hi
    first_of_edge = new_edge[starts]
    last_of_edge = np.ones(len(starts), bool)
    last_of_edge[:-1] = first_of_edge[1:]
    before = np.where(first_of_edge, 0.0, np.roll(run_hi, 1))  # a gap before each run
    tail = np.zeros(n_edges)  # the piece after the last run of each edge (all of it without runs)
    tail[run_edge[last_of_edge]] = run_hi[last_of_edge]
    out_edge = np.concatenate([run_edge, np.arange(n_edges)])
    t0 = np.concatenate([before, tail])
    t1 = np.concatenate([run_lo, np.ones(n_edges)])
    keep = t1 > t0
    out_edge, t0, t1 = out_edge[keep], t0[keep], t1[keep]
    order = np.lexsort((t0, out_edge))
    return out_edge[order], t0[order], t1[order]


def hidden_lines(
    triangles: ArrayLike,
    edges: ArrayLike,
    edge_faces: ArrayLike | None,
    *,
    eps: float = DEFAULT_EPS,
    min_length: float = 0.0,
) -> HiddenLines:
    """The visible pieces of ``edges`` (E, 2, 3) among ``triangles`` (T, 3, 3), all device x, y + NDC depth z.

    ``edge_faces`` (E, 2) gives the triangles each edge lies on (−1 for none; None: no adjacency); they never
    hide it. ``eps`` is the depth tolerance (NDC units) below which a triangle is not nearer. Pieces shorter
    than ``min_length`` device units, and pieces of no length, are left out.
    """
    tris = as_batch(triangles, "triangles", (3, 3), "x, y, z corners")
    segs = as_batch(edges, "edges", (2, 3), "x, y, z ends")
    faces = _as_edge_faces(edge_faces, len(segs), len(tris))
    eps = _as_tolerance(eps, "eps")
    min_length = _as_tolerance(min_length, "min_length")
    # work relative to the centre of the edges' box: smaller numbers, smaller rounding
    centre = np.zeros(3)
    if len(segs):
        centre[:2] = (segs[:, :, :2].min(axis=(0, 1)) + segs[:, :, :2].max(axis=(0, 1))) / 2
    shifted = segs - centre
    tri = _prepare_triangles(tris - centre, shifted, eps)
    local = np.full(len(tris) + 1, -1)  # caller's triangle index -> kept triangle index; the last entry serves −1
    local[tri.index] = np.arange(len(tri.index))
    (h_edge, h_lo, h_hi), tested = _hidden_intervals(shifted[:, 0], shifted[:, 1], local[faces], tri, eps)
    edge, t0, t1 = _visible_intervals(len(segs), h_edge, h_lo, h_hi)
    length2d = np.hypot(*(segs[:, 1, :2] - segs[:, 0, :2]).T)
    piece_length = length2d[edge] * (t1 - t0)
    keep = (piece_length >= min_length) & (piece_length > 0)
    edge, t0, t1 = edge[keep], t0[keep], t1[keep]
    p, q = segs[edge, 0, :2], segs[edge, 1, :2]
    pieces = np.stack([(1 - t0)[:, None] * p + t0[:, None] * q, (1 - t1)[:, None] * p + t1[:, None] * q], axis=1)
    total = float(length2d.sum())
    hidden = 1.0 - float(piece_length[keep].sum()) / total if total > 0 else 0.0
    stats = HiddenLineStats(len(segs), len(edge), tested, min(max(hidden, 0.0), 1.0))
    return HiddenLines(pieces.reshape(-1, 2, 2), edge.astype(np.int64), stats)

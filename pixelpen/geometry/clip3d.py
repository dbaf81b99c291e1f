"""Clipping in homogeneous clip space against the six planes of the canonical view volume, vectorised.

Clip space (one z range used throughout pixelpen): a point [x, y, z, w] is inside when −w ≤ x ≤ w,
−w ≤ y ≤ w, 0 ≤ z ≤ w and w > 0, so after the perspective divide NDC x, y lie in [−1, 1] and NDC z = z/w
runs from 0 at the near plane to 1 at the far plane. Clipping happens before the divide, so points behind
the viewer (w ≤ 0) never reach it. Each plane is a boundary function d(P) = P · c ≥ 0 that is linear along a
segment. One inside test serves points, segments, polygons and triangles alike: a point is inside a plane
when d(P) ≥ −_ON_TOL·max(|x|, |y|, |z|, |w|) (1e-12 of its own size), so points on a plane, or off it by
rounding only, are inside and pass unchanged (a face lying in a boundary plane, such as a backdrop on the far
plane whose vertices round just outside it, is kept whole; results may lie outside a plane by that
tolerance), while anything further out is cut or rejected. Intersection points are put exactly on the plane they were
cut by (so x = w holds exactly there), and a shared edge is cut from its inside end on both sides, so two
triangles sharing an edge get the same cut points. The one homogeneous point that passes the six planes
but is no point at all, the zero vector (w = 0), is dropped from the results, and so are cut points that
are the zero vector blurred by rounding (an edge from P to about −kP: no edge between world points, whose
images lie in a hyperplane missing 0, does that).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pixelpen.errors import InvalidArgument
from pixelpen.geometry.transforms import ArrayLike, as_batch
from pixelpen.geometry.transforms3d import as_homogeneous

PLANES = np.array([
    [1.0, 0.0, 0.0, 1.0],  # left:   x ≥ −w
    [-1.0, 0.0, 0.0, 1.0],  # right:  x ≤ w
    [0.0, 1.0, 0.0, 1.0],  # bottom: y ≥ −w
    [0.0, -1.0, 0.0, 1.0],  # top:    y ≤ w
    [0.0, 0.0, 1.0, 0.0],  # near:   z ≥ 0
    [0.0, 0.0, -1.0, 1.0],  # far:    z ≤ w
])
"""The six clip planes as rows c of the boundary functions d(P) = P · c ≥ 0 (inside)."""
PLANES.flags.writeable = False

# A cut point this much smaller than the ends of its edge is the zero vector (the cone's apex, no point at
# all) blurred by rounding: the edge ran from P to about −kP, which no segment between world points does.
_APEX_TOL = 1e-12

# A point within this fraction of its largest coordinate outside a plane counts as on it (inside): a face lying
# in a boundary plane (a backdrop on the far plane) is kept whole, not cut or dropped by rounding.
_ON_TOL = 1e-12

# For each plane: the coordinate a point cut by it has, as (index, factor): coordinate = factor · w.
_ON_PLANE = ((0, -1.0), (0, 1.0), (1, -1.0), (1, 1.0), (2, 0.0), (2, 1.0))


def _snap(points: np.ndarray, plane: int) -> None:
    """Put points (..., 4+) cut by the plane exactly on it, in place."""
    index, factor = _ON_PLANE[plane]
    points[..., index] = factor * points[..., 3]


def _distance(points: np.ndarray, plane: int) -> np.ndarray:
    """The boundary function of one plane at points (..., 4+): P · PLANES[plane], written out (a tall matrix
    product goes through BLAS, whose threads make it many times slower on small machines)."""
    x, y, z, w = (points[..., k] for k in range(4))
    d: np.ndarray = (w + x, w - x, w + y, w - y, z, w - z)[plane]
    return d


def _distances(points: np.ndarray) -> np.ndarray:
    """(..., 6) boundary functions of all six planes at points (..., 4+)."""
    d: np.ndarray = np.stack([_distance(points, plane) for plane in range(len(PLANES))], axis=-1)
    return d


def _slack(points: np.ndarray) -> np.ndarray:
    """The lowest boundary value (...) of points (..., 4+) still counted inside a plane: −_ON_TOL times each
    point's largest |coordinate| (the module's one inside test is d(P) ≥ _slack(P), and w > 0)."""
    slack: np.ndarray = np.abs(points[..., :4]).max(axis=-1)
    slack *= -_ON_TOL
    return slack


def _within(rows: np.ndarray, slack: np.ndarray | float) -> np.ndarray:
    """Mask (N,) of (N, 4) points with w > 0 and every boundary value ≥ slack, plane by plane (no table)."""
    inside: np.ndarray = rows[:, 3] > 0.0
    for plane in range(len(PLANES)):
        inside &= _distance(rows, plane) >= slack
    return inside


def _inside(rows: np.ndarray) -> np.ndarray:
    """Inside mask (N,) of (N, 4) homogeneous points by the module's inside test."""
    inside = _within(rows, 0.0)  # a point inside without the tolerance is inside with it
    doubt = np.flatnonzero(~inside)
    if doubt.size:  # the rest, often few: outside, or on a plane but for rounding
        near = rows[doubt]
        inside[doubt] = _within(near, _slack(near))
    return inside


def _at_apex(cut: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cut points that are the zero vector but for rounding: tiny beside the ends of their edge (mask)."""
    size = np.abs(cut[..., :4]).max(axis=-1)
    apex: np.ndarray = size <= _APEX_TOL * (np.abs(a[..., :4]).max(axis=-1) + np.abs(b[..., :4]).max(axis=-1))
    return apex


def clip_points_homogeneous(h: ArrayLike) -> np.ndarray:
    """Inside mask (N,) bool of (N, 4) homogeneous points: −w ≤ x ≤ w, −w ≤ y ≤ w, 0 ≤ z ≤ w (to the module's
    tolerance), w > 0."""
    return _inside(as_homogeneous(h, "h"))


def clip_segments_homogeneous(segments: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Liang–Barsky clip of (N, 2, 4) segments; return (clipped (K, 2, 4), indices (K,) of the segments kept)."""
    segs = as_batch(segments, "segments", (2, 4), "homogeneous endpoint pairs")
    p0, p1 = segs[:, 0], segs[:, 1]
    d0, d1 = _distances(p0), _distances(p1)  # (N, 6)
    out0, out1 = d0 < _slack(p0)[:, None], d1 < _slack(p1)[:, None]
    entering, exiting = out0 & ~out1, out1 & ~out0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(d0 / (d0 - d1), 0.0, 1.0)  # an end within the tolerance outside: the cut is that end
    t_in, t_out = np.where(entering, t, -np.inf), np.where(exiting, t, np.inf)
    enter_plane, exit_plane = t_in.argmax(axis=1), t_out.argmin(axis=1)  # the plane that cuts each end
    rows = np.arange(len(segs))
    te, tx = np.maximum(t_in[rows, enter_plane], 0.0), np.minimum(t_out[rows, exit_plane], 1.0)
    keep = ~(out0 & out1).any(axis=1) & (te <= tx)
    q0, q1 = p0.copy(), p1.copy()
    for q, t_cut, plane_cut, crossing in ((q0, te, enter_plane, entering), (q1, tx, exit_plane, exiting)):
        for plane in range(len(PLANES)):
            cut = keep & crossing[:, plane] & (plane_cut == plane)
            points = (1.0 - t_cut[cut, None]) * p0[cut] + t_cut[cut, None] * p1[cut]
            _snap(points, plane)
            q[cut] = points
    keep &= (q0[:, 3] > 0.0) & (q1[:, 3] > 0.0) & ~_at_apex(q0, p0, p1) & ~_at_apex(q1, p0, p1)
    kept = np.flatnonzero(keep)
    return np.stack([q0[kept], q1[kept]], axis=1), kept.astype(np.int64)


def _compact(candidates: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pack the masked entries of (T, L, C) rows to the front: return (out (T, K, C), counts (T,))."""
    counts = mask.sum(axis=1)
    width = int(counts.max()) if len(counts) else 0
    out = np.zeros((len(candidates), width, candidates.shape[2]))
    rows, cols = np.nonzero(mask)
    out[rows, (np.cumsum(mask, axis=1) - 1)[rows, cols]] = candidates[rows, cols]
    return out, counts


def _clip_polygons(polygons: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sutherland–Hodgman on padded polygons (T, K, 4 + A) with vertex counts (T,); attributes interpolate along.

    Vertices are inside by the module's inside test. Every edge i -> i+1 (cyclic) emits its start vertex if
    inside, then its crossing point if it crosses the plane; the crossing is computed from the inside end.
    Returns the clipped padded polygons and counts.
    """
    for plane in range(len(PLANES)):
        width = polygons.shape[1]
        if width == 0:
            break
        col = np.arange(width)
        valid = col < counts[:, None]
        following = np.where(col + 1 < counts[:, None], col + 1, 0)
        nxt = np.take_along_axis(polygons, following[:, :, None], axis=1)
        d = _distance(polygons, plane)
        d_next = np.take_along_axis(d, following, axis=1)
        inside = d >= _slack(polygons)
        inside_next = np.take_along_axis(inside, following, axis=1)
        crosses = valid & (inside != inside_next)
        a = np.where(inside[:, :, None], polygons, nxt)  # the inside end of each edge
        b = np.where(inside[:, :, None], nxt, polygons)
        da, db = np.where(inside, d, d_next), np.where(inside, d_next, d)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(crosses, np.clip(da / (da - db), 0.0, 1.0), 0.0)
        cut = (1.0 - t[:, :, None]) * a + t[:, :, None] * b  # exact at both ends, whatever their scales
        apex = _at_apex(cut, a, b)
        _snap(cut, plane)
        candidates = np.empty((len(polygons), 2 * width, polygons.shape[2]))
        candidates[:, 0::2], candidates[:, 1::2] = polygons, cut
        mask = np.empty((len(polygons), 2 * width), dtype=bool)
        mask[:, 0::2], mask[:, 1::2] = valid & inside, crosses & ~apex
        polygons, counts = _compact(candidates, mask)
    col = np.arange(polygons.shape[1])
    return _compact(polygons, (col < counts[:, None]) & (polygons[:, :, 3] > 0.0))


def clip_polygon_homogeneous(vertices: ArrayLike) -> np.ndarray:
    """Sutherland–Hodgman clip of one (N, 4) polygon; the clipped (M, 4) polygon, (0, 4) if under 3 vertices remain."""
    rows = as_homogeneous(vertices, "vertices")
    if 0 < len(rows) < 3:
        raise InvalidArgument(f"vertices needs at least 3 points for a polygon, got {len(rows)}")
    out, counts = _clip_polygons(rows[None], np.array([len(rows)]))
    m = int(counts[0])
    return out[0, :m].copy() if m >= 3 else np.zeros((0, 4))


@dataclass(frozen=True)
class FaceClip:
    """Triangles of a vertex table split by the clip (:func:`clip_faces_homogeneous`): the vertices inside,
    the faces that pass whole, and the clipped pieces of the others."""

    inside: np.ndarray
    """(N,) bool: the vertices inside the view volume."""
    whole: np.ndarray
    """(T,) bool: the faces whose three vertices are inside (they pass unchanged)."""
    out: np.ndarray
    """(K, 3, 4) pieces of the other faces that reach into the volume (fan triangles)."""
    source: np.ndarray
    """(K,) int64 ascending: the face each piece comes from."""
    weights: np.ndarray
    """(K, 3, 3): out[k, i] = Σ_j weights[k, i, j] · vertices[faces[source[k], j]] (to rounding)."""


def clip_faces_homogeneous(vertices: ArrayLike, faces: ArrayLike) -> FaceClip:
    """Clip triangles given as (T, 3) indices into (N, 4) homogeneous vertices, each vertex tested once: faces
    with all three vertices inside pass whole, faces with all three outside one plane are dropped, the rest are
    clipped (Sutherland–Hodgman) and each clipped convex polygon fan-triangulated from its first vertex,
    keeping the winding."""
    rows = as_homogeneous(vertices, "vertices")
    index = np.asarray(faces)
    if index.ndim != 2 or index.shape[1] != 3 or (index.size and index.dtype.kind not in "iu"):
        raise InvalidArgument(f"faces must be a (T, 3) integer array, got shape {index.shape} {index.dtype}")
    if index.size and not 0 <= int(index.min()) <= int(index.max()) < len(rows):
        row = int(np.flatnonzero(((index < 0) | (index >= len(rows))).any(axis=1))[0])
        raise InvalidArgument(f"faces row {row} {index[row].tolist()} indexes outside the {len(rows)} vertices")
    return _clip_faces(rows, index.astype(np.int64, copy=False))


def _clip_faces(rows: np.ndarray, faces: np.ndarray) -> FaceClip:
    """clip_faces_homogeneous of validated vertices (N, 4) and faces (T, 3)."""
    inside = _inside(rows)
    whole = np.take(inside, faces[:, 0]) & np.take(inside, faces[:, 1]) & np.take(inside, faces[:, 2])
    rest = np.flatnonzero(~whole)
    tri = rows[faces[rest]]  # (R, 3, 4)
    slack = _slack(tri)
    outside = np.zeros(len(rest), dtype=bool)
    for plane in range(len(PLANES)):
        outside |= (_distance(tri, plane) < slack).all(axis=1)
    straddle = np.flatnonzero(~outside)
    padded = np.concatenate([tri[straddle], np.broadcast_to(np.eye(3), (len(straddle), 3, 3))], axis=2)
    polygons, counts = _clip_polygons(padded, np.full(len(straddle), 3))
    fans = np.maximum(counts - 2, 0)
    owner = np.repeat(np.arange(len(straddle)), fans)
    first = np.repeat(np.cumsum(fans) - fans, fans)
    j = np.arange(len(owner)) - first + 1
    fan = polygons[owner[:, None], np.stack([np.zeros_like(j), j, j + 1], axis=1)]  # (0, j, j + 1) per fan
    fan = fan.reshape(len(owner), 3, 7)
    return FaceClip(inside, whole, fan[:, :, :4], rest[straddle[owner]].astype(np.int64), fan[:, :, 4:])


def clip_triangles_homogeneous(tris: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Clip (T, 3, 4) triangles; return (out (K, 3, 4), source (K,) int64 ascending, weights (K, 3, 3)).

    out[k, i] = Σ_j weights[k, i, j] · tris[source[k], j] (to rounding): the weights re-express every output
    vertex against its source triangle (for interpolating attributes). Triangles wholly inside pass unchanged
    with identity weights; the others as in :func:`clip_faces_homogeneous`.
    """
    tri = as_batch(tris, "tris", (3, 4), "homogeneous triangles")
    split = _clip_faces(tri.reshape(-1, 4), np.arange(3 * len(tri)).reshape(-1, 3))
    if split.whole.all():  # the common case: nothing near the volume's sides
        return tri.copy(), np.arange(len(tri), dtype=np.int64), np.tile(np.eye(3), (len(tri), 1, 1))
    whole = np.flatnonzero(split.whole)
    source = np.concatenate([whole, split.source])
    order = np.argsort(source, kind="stable")
    out = np.concatenate([tri[whole], split.out])
    weights = np.concatenate([np.broadcast_to(np.eye(3), (len(whole), 3, 3)), split.weights])
    return out[order], source[order], weights[order]


def perspective_divide(h: ArrayLike) -> np.ndarray:
    """(..., 4) homogeneous points to (..., 3) NDC x/w, y/w, z/w; InvalidArgument naming a point with w ≤ 0."""
    try:
        arr = np.asarray(h, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"h must be an (..., 4) array of homogeneous points: {exc}") from None
    if arr.ndim == 0 or arr.shape[-1] != 4:
        raise InvalidArgument(f"h must be an (..., 4) array of homogeneous points, got shape {arr.shape}")
    finite = np.isfinite(arr)
    if not (finite.all() and (arr[..., 3] > 0.0).all()):  # the point is found only when something is wrong
        bad = ~finite.all(axis=-1) | ~(arr[..., 3] > 0.0)
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise InvalidArgument(
            f"h has a point with w ≤ 0 or a non-finite value at index {index}: {arr[index].tolist()} "
            "(clip before dividing: points at or behind the viewer have no image)"
        )
    return perspective_divide_unchecked(arr)


def perspective_divide_unchecked(h: np.ndarray) -> np.ndarray:
    """:func:`perspective_divide` of a float64 (..., 4) array already known finite with w > 0 (clipped output)."""
    result: np.ndarray = h[..., :3] / h[..., 3:4]
    return result

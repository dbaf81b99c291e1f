"""A vectorised z-buffer (Hearn & Baker §13-3): triangles in device pixels -> the visible fragments per pixel.

Conventions:

* Device coordinates: x to the right, y down; pixel ``(i, j)`` is the square ``[i, i+1) x [j, j+1)``, sampled
  at its centre ``(i + 0.5, j + 0.5)``.  Depth is NDC z (0 at near, 1 at far): smaller is nearer.
* Coverage follows the *top-left rule*: a centre exactly on an edge belongs to the triangle when the edge is a
  left edge or a horizontal top edge, so triangles sharing an edge cover each pixel exactly once.  Vertices
  are snapped to 1/256 pixel (:data:`pixelpen.raster.polygons.SUBPIXEL`) and each edge's crossing of a pixel
  row is computed exactly on integers below 2**53 (the same crossing whichever triangle the edge belongs to),
  giving the pixels :func:`pixelpen.raster.polygons.triangle_spans` fills for the vertices shifted by -1/2.
  Both windings are drawn (the caller culls); zero-area triangles cover nothing.
* Depth is interpolated linearly in screen space (NDC z is affine there); the barycentric weights of the
  triangle's vertices are perspective-corrected with ``inv_w`` (1/w of each vertex) when it is given.
* Resolution: nearest depth wins; within one :meth:`ZBuffer.rasterize` call equal depths go to the lower
  triangle index; against earlier calls a fragment must be strictly nearer than the stored depth.
* Bands: ``ZBuffer(width, rows, top=t)`` (or :meth:`ZBuffer.clear` with ``top``) covers the frame rows t ..
  t + rows - 1 only; triangles and fragments stay in frame coordinates, and the pixels won are the whole
  frame's in those rows (the snapped vertices are shifted by whole rows, exactly).
* Output: one fragment per pixel won, in no particular order; ``xs``, ``ys``, ``face`` int64, ``depth``
  float64, ``bary`` an (F, 3) float64 view of a (3, F) array.  Depth is evaluated as a plane in the flat pixel
  index (absolute error about 1e-16·|dz/dx|·width·height); weights as planes in x along each row.

Algorithm: per triangle, vertices sorted by y (A, B, C); the long edge AC bounds one side of every row, the
edges AB and BC the other (the nearer of their two crossings, as the triangle is convex).  Every (triangle, row)
is one entry of flat arrays (the triangles' values gathered to their rows) and all rows' exact crossings are one
vectorised pass, with no loop over triangle shapes.
Rows become pixel runs by a ragged expansion in chunks of about :data:`CHUNK` pixels (cache-sized buffers);
pass 1 takes ``np.minimum.at`` of the depths into the buffer; pass 2 (on pass 1's chunks, or regenerated ones
past :data:`KEEP_PIXELS`) keeps the fragments equal to the new depth and strictly nearer than before - all of
them, without comparing, when the number of pixels lowered equals the number of candidates (a convex mesh
after culling); a scatter-and-check finds the (rare) pixels where several triangles tie and keeps the lowest
index.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.geometry.transforms import ArrayLike
from pixelpen.raster.polygons import SUBPIXEL, VERTEX_LIMIT

CHUNK = 1 << 16
"""Pixels expanded per vectorised step of the resolve passes (buffers stay in L2 cache)."""

KEEP_PIXELS = 1 << 21
"""Up to this many candidate pixels per call, pass 1 keeps its expansion for pass 2 (else recomputes it)."""

MAX_SIDE = 1 << 16
"""Largest z-buffer width or height."""

_NEUTRAL = float(1 << 60)
"""Crossing numerator standing for 'no bound' (a horizontal edge): far outside any canvas."""

_NO_FACE = np.iinfo(np.int64).max


def _as_array(value: ArrayLike, name: str, shape: tuple[int, ...]) -> np.ndarray:
    """value as a finite float64 array of the given shape (-1 = any length); errors name the first bad row."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgumentType(f"{name} must be an array of numbers: {exc}") from None
    if arr.ndim != len(shape) or any(want not in (-1, got) for want, got in zip(shape, arr.shape, strict=True)):
        want = "(" + ", ".join("T" if s == -1 else str(s) for s in shape) + ")"
        raise InvalidArgument(f"{name} must have shape {want}, got {arr.shape}")
    if not np.isfinite(arr).all():
        row = int(np.flatnonzero(~np.isfinite(arr.reshape(arr.shape[0], -1)).all(axis=1))[0])
        raise InvalidArgument(f"{name} row {row} is not finite (NaN or inf): {arr[row].tolist()}")
    return arr


def _as_index(value: ArrayLike, name: str) -> np.ndarray:
    """value as a 1-D int64 array of integers."""
    arr = np.asarray(value)
    if arr.ndim != 1 or (arr.size and arr.dtype.kind not in "iu"):
        raise InvalidArgument(f"{name} must be a 1-D integer array, got shape {arr.shape} {arr.dtype}")
    return arr.astype(np.int64, copy=False)


@dataclass
class Fragments:
    """Visible fragments: pixel ``(xs[k], ys[k])`` shows triangle ``face[k]`` at ``depth[k]``.

    ``bary[k]`` are the (perspective-correct) weights of the triangle's three vertices at the pixel centre.
    """

    xs: np.ndarray
    ys: np.ndarray
    face: np.ndarray
    bary: np.ndarray
    depth: np.ndarray

    def __len__(self) -> int:
        """Number of fragments."""
        return int(self.face.shape[0])

    def subset(self, mask: ArrayLike) -> Fragments:
        """The fragments selected by a boolean mask (F,) or an index array."""
        sel = np.asarray(mask)
        if sel.dtype == bool and sel.shape != self.face.shape:
            raise InvalidArgument(f"mask must be a boolean array of shape {self.face.shape}, got {sel.shape}")
        if sel.dtype != bool:
            sel = _as_index(sel, "mask")
        return Fragments(self.xs[sel], self.ys[sel], self.face[sel], self.bary[sel], self.depth[sel])

    def interpolate(self, values: ArrayLike | Interpolant) -> np.ndarray:
        """Per-vertex values (T, 3, K) of the triangles (or an :class:`Interpolant` of them) at each fragment
        -> (F, K)."""
        table = values if isinstance(values, Interpolant) else Interpolant(values)
        return table.at(self)

    def compose(self, source: ArrayLike, weights: ArrayLike) -> Fragments:
        """Re-express against source triangles: face = source[face], bary = bary @ weights[face].

        For triangles made by :func:`pixelpen.geometry.clip3d.clip_triangles_homogeneous`, whose vertex i is
        ``sum_j weights[k, i, j] * tris[source[k], j]``.
        """
        src = _as_index(source, "source")
        wts = _as_array(weights, "weights", (-1, 3, 3))
        if wts.shape[0] != src.shape[0]:
            raise InvalidArgument(f"source has {src.shape[0]} rows but weights has {wts.shape[0]}")
        if len(self) and int(self.face.max()) >= src.shape[0]:
            raise InvalidArgument(f"source has {src.shape[0]} rows but a fragment shows triangle "
                                  f"{int(self.face.max())}")
        bary = np.einsum("fi,fij->fj", self.bary, wts[self.face])
        return Fragments(self.xs, self.ys, src[self.face], bary, self.depth)


class Interpolant:
    """Per-vertex values (T, 3, K) of triangles, prepared once to be interpolated at many sets of fragments.

    In the affine form v0 + b1·(v1 − v0) + b2·(v2 − v0): exact where a triangle's three values agree (a face of
    one colour shows exactly that colour), and computed one component at a time from contiguous (T,) rows,
    about twice as fast on large batches as gathering (F, 3, K) corners.
    """

    def __init__(self, values: ArrayLike, faces: ArrayLike | None = None) -> None:
        """From (T, 3, K) corner values, or with ``faces`` (T, 3) from per-vertex values (N, K) (no corner copy)."""
        vals = np.asarray(values, dtype=np.float64)
        if faces is None:
            if vals.ndim != 3 or vals.shape[1] != 3:
                raise InvalidArgument(f"values must have shape (T, 3, K), got {vals.shape}")
            corners = [vals[:, i].T for i in range(3)]
        else:
            index = np.asarray(faces)
            integral = index.size == 0 or index.dtype.kind in "iu"
            if vals.ndim != 2 or index.ndim != 2 or index.shape[1] != 3 or not integral:
                raise InvalidArgument(f"per-vertex values must be (N, K) and faces (T, 3) integers, got {vals.shape} "
                                      f"and {index.shape} {index.dtype}")
            if index.size and not 0 <= int(index.min()) <= int(index.max()) < vals.shape[0]:
                raise InvalidArgument(f"faces index outside the {vals.shape[0]} vertices")
            columns = np.ascontiguousarray(vals.T)
            corners = [np.take(columns, corner, axis=1, mode="clip") for corner in index.T]
        self.triangles = corners[0].shape[1]
        self._first = np.ascontiguousarray(corners[0])
        self._steps = [np.ascontiguousarray(corner - corners[0]) for corner in corners[1:]]

    def at(self, fragments: Fragments) -> np.ndarray:
        """The values at each fragment (F, K)."""
        face = fragments.face
        if len(face) and not 0 <= int(face.min()) <= int(face.max()) < self.triangles:
            raise InvalidArgument(f"values has {self.triangles} triangles but fragments show triangles "
                                  f"{int(face.min())}..{int(face.max())}")
        return self.at_valid(fragments)

    def at_valid(self, fragments: Fragments) -> np.ndarray:
        """:meth:`at` for fragments whose faces are known to lie in 0..T-1 (checked once by the caller)."""
        face = fragments.face
        weights = [np.ascontiguousarray(fragments.bary[:, i]) for i in (1, 2)]
        out = np.empty((self._first.shape[0], len(face)))
        term = np.empty(len(face))
        for k, row in enumerate(out):  # a few components (3), each over all fragments
            np.take(self._first[k], face, out=row, mode="clip")  # indices in range
            for step, weight in zip(self._steps, weights, strict=True):
                np.take(step[k], face, out=term, mode="clip")
                term *= weight
                row += term
        return out.T


def _empty_fragments() -> Fragments:
    """No fragments."""
    none = np.zeros(0, dtype=np.int64)
    return Fragments(none, none.copy(), none.copy(), np.zeros((0, 3)), np.zeros(0))


@dataclass
class _Rows:
    """Pixel runs, one per (triangle, row): flat index of the first pixel, length, depth = z0 + gz·index."""

    start: np.ndarray
    length: np.ndarray
    z0: np.ndarray
    gz: np.ndarray
    face: np.ndarray
    weight0: np.ndarray  # (K, R): the weight planes of _planes at column 0 of the row


def _sorted_by_y(v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices (2, 3, T) (x and y rows) sorted by y (a stable three-comparator network): A, B, C, each (2, T)."""
    p = [v[:, 0], v[:, 1], v[:, 2]]
    for i, j in ((0, 1), (1, 2), (0, 1)):
        swap = p[i][1] > p[j][1]
        p[i], p[j] = np.where(swap, p[j], p[i]), np.where(swap, p[i], p[j])
    return p[0], p[1], p[2]


def _edges(a: np.ndarray, b: np.ndarray, c: np.ndarray,
           neutral: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Edges AB, BC, AC (top to bottom) as (n0, step, den), each (3, T): the crossing of row r is
    ceil((n0 + step·r) / den); horizontal edges get a constant crossing of ``neutral`` (no bound)."""
    p, q = np.stack([a, b, a], axis=1), np.stack([b, c, c], axis=1)  # (2, 3, T)
    d = q - p
    flat = d[1] == 0
    n0 = np.where(flat, neutral, p[0] * d[1] - p[1] * d[0])
    step = np.where(flat, 0.0, SUBPIXEL * d[0])
    den = np.where(flat, 1.0, SUBPIXEL * d[1])
    return n0, step, den


def _planes(v: np.ndarray, det: np.ndarray, z: np.ndarray, inv_w: np.ndarray | None) -> tuple[np.ndarray, ...]:
    """Per triangle (snapped vertices v (2, 3, T) in pixels, centres at integers, and their determinant
    (v1 − v0) x (v2 − v0) (T,), exact, from :func:`_setup`; depth and 1/w (3, T)): depth's gradient and value at
    the origin (gx, gy, zc), and the weight planes ``slope·x + rise·y + const`` (K, T) each: k = 0, 1 the
    weights of vertices 1 and 2 times their 1/w, and k = 2 their sum over the three vertices (absent without
    ``inv_w``: the sum is 1), so the perspective-correct weights are planes 0 and 1 divided by plane 2."""
    px, py = v
    e1x, e1y = px[1] - px[0], py[1] - py[0]
    e2x, e2y = px[2] - px[0], py[2] - py[0]
    inv = 1.0 / det
    lam = (e2y * inv, -e2x * inv, -e1y * inv, e1x * inv)
    dz1, dz2 = z[1] - z[0], z[2] - z[0]
    gx = dz1 * lam[0] + dz2 * lam[2]
    gy = dz1 * lam[1] + dz2 * lam[3]
    zc = z[0] - gx * px[0] - gy * py[0]
    c1 = -(lam[0] * px[0] + lam[1] * py[0])
    c2 = -(lam[2] * px[0] + lam[3] * py[0])
    planes = [(lam[0], lam[1], c1), (lam[2], lam[3], c2)]
    if inv_w is not None:
        q0, d1, d2 = inv_w[0], inv_w[1] - inv_w[0], inv_w[2] - inv_w[0]
        planes = [(a * inv_w[k + 1], b * inv_w[k + 1], c * inv_w[k + 1]) for k, (a, b, c) in enumerate(planes)]
        planes.append((d1 * lam[0] + d2 * lam[2], d1 * lam[1] + d2 * lam[3], q0 + d1 * c1 + d2 * c2))
    slope, rise, const = (np.stack([plane[i] for plane in planes]) for i in range(3))
    return gx, gy, zc, slope, rise, const


def _setup(xy: np.ndarray, z: np.ndarray, inv_w: np.ndarray | None, width: int, height: int,
           top: int) -> tuple[np.ndarray, _Rows]:
    """Snap the triangles (frame rows from ``top`` on): the weight slopes (K, T) of :func:`_planes` and the pixel
    runs of every row the triangles cover, triangle by triangle."""
    snapped = np.empty((2, 3, len(xy)))  # x and y rows of each vertex, in 1/SUBPIXEL px, centres at integers
    np.multiply(xy.transpose(2, 1, 0), SUBPIXEL, out=snapped)
    np.rint(snapped, out=snapped)
    snapped -= np.array([SUBPIXEL // 2, SUBPIXEL // 2 + top * SUBPIXEL], dtype=np.float64)[:, None, None]
    sx, sy = snapped
    det = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sy[1] - sy[0]) * (sx[2] - sx[0])  # exact
    r0 = np.clip(np.ceil(np.minimum.reduce(sy) / SUBPIXEL), 0, height)
    count = (np.clip(np.ceil(np.maximum.reduce(sy) / SUBPIXEL), 0, height) - r0).astype(np.int64)
    xmin, xmax = np.minimum.reduce(sx), np.maximum.reduce(sx)
    live = (det != 0) & (count > 0) & (xmax >= 0) & (xmin <= (width - 1) * SUBPIXEL)
    # B left of AC (y down) when the y-sorted vertices turn clockwise: the sign of det, flipped by an odd sort
    pair_left = (det < 0) ^ (sy[0] > sy[1]) ^ (sy[0] > sy[2]) ^ (sy[1] > sy[2])
    keep = np.flatnonzero(live)
    slope = np.zeros((2 if inv_w is None else 3, len(xy)))
    if keep.size == 0:
        return slope, _no_rows()
    v = np.take(snapped, keep, axis=2, mode="clip")
    r0, xmin, xmax, count, left_side = (np.take(a, keep, mode="clip") for a in (r0, xmin, xmax, count, pair_left))
    # the determinant in pixels² is the exact one in snapped units scaled by a power of two: exact too
    det_px = np.take(det, keep, mode="clip") / (SUBPIXEL * SUBPIXEL)
    gx, gy, zc, slope_k, rise_w, const = _planes(v / SUBPIXEL, det_px, np.take(z.T, keep, axis=1, mode="clip"),
                                               None if inv_w is None else np.take(inv_w.T, keep, axis=1, mode="clip"))
    slope[:, keep] = slope_k
    # rows carry K + 1 planes along the frame rows: depth at the flat index 0 of the row, then the weights
    rise = np.concatenate([(gy - gx * width)[None], rise_w])
    plane0 = np.concatenate([zc[None], const])
    plane0 += rise * r0
    n0, step, den = _edges(*_sorted_by_y(v), np.where(left_side, -_NEUTRAL, _NEUTRAL))
    n0 += step * r0
    # one row per (triangle, row): its triangle (in keep order) and its row j from the triangle's first
    tri = np.repeat(np.arange(keep.size), count)
    j = np.arange(tri.size, dtype=np.float64)
    j -= np.take(np.cumsum(count) - count, tri, mode="clip")
    cross = np.take(step, tri, axis=1, mode="clip")  # the crossing of row j: ceil((n0 + step·j) / den)
    cross *= j
    cross += np.take(n0, tri, axis=1, mode="clip")
    cross /= np.take(den, tri, axis=1, mode="clip")
    np.ceil(cross, out=cross)
    left = np.take(left_side, tri, mode="clip")
    first = np.where(left, np.maximum(cross[0], cross[1]), cross[2])
    last = np.where(left, cross[2], np.minimum(cross[0], cross[1], out=cross[1]))
    if not ((xmin >= 0) & (xmax <= width * SUBPIXEL - SUBPIXEL)).all():
        np.clip(first, 0, width, out=first)
        np.clip(last, 0, width, out=last)
    length = np.subtract(last, first, out=last)
    first += np.take(r0 * width, tri, mode="clip")
    first += j * width
    planes = np.take(rise, tri, axis=1, mode="clip")
    planes *= j
    planes += np.take(plane0, tri, axis=1, mode="clip")
    rows = _Rows(first, length, planes[0], np.take(gx, tri, mode="clip"), np.take(keep, tri, mode="clip"),
                 planes[1:])
    return slope, rows


def _no_rows() -> _Rows:
    """No pixel runs."""
    return _Rows(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros((3, 0)))


def _chunks(first: np.ndarray) -> list[tuple[int, int]]:
    """Consecutive row ranges of about CHUNK pixels each (a row is never split); ``first`` (R + 1,) is the
    index of each row's first pixel in the expansion, then the total."""
    cuts = np.searchsorted(first[1:], np.arange(CHUNK, int(first[-1]), CHUNK), side="left") + 1
    bounds = np.unique(np.concatenate(([0], cuts, [first.size - 1]))).tolist()
    return list(itertools.pairwise(bounds))


def _expand(rows: _Rows, offset: np.ndarray, first: np.ndarray, lo: int, hi: int,
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixels of rows lo..hi: (flat index, depth, owning row)."""
    owner = np.repeat(np.arange(lo, hi), rows.length[lo:hi])
    pix = np.arange(first[lo], first[hi], dtype=np.int64)
    pix += np.take(offset, owner, mode="clip")
    depth = np.take(rows.gz, owner, mode="clip")
    depth *= pix
    depth += np.take(rows.z0, owner, mode="clip")
    return pix, depth, owner


def _side(name: str, value: int, low: int) -> int:
    """A validated size or offset in pixels, low..MAX_SIDE."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise InvalidArgumentType(f"{name} must be an integer, got {type(value).__name__} {value!r}")
    if not low <= value <= MAX_SIDE:
        raise InvalidArgument(f"{name} must be {low}..{MAX_SIDE}, got {value}")
    return int(value)


class ZBuffer:
    """A width x height depth buffer (``.depth``, +inf where nothing is drawn) that rasterizes triangles.

    ``top`` places it over the frame rows ``top .. top + height - 1`` (a band of a larger frame): triangles are
    given in frame coordinates and fragments come back in them, exactly as a whole-frame buffer would give the
    band's pixels.
    """

    def __init__(self, width: int, height: int, *, top: int = 0) -> None:
        self.width = _side("width", width, 1)
        self.height = _side("height", height, 1)
        self.top = _side("top", top, 0)
        self.depth: np.ndarray = np.full((self.height, self.width), np.inf)
        self._owner: np.ndarray | None = None
        self._spare = np.zeros(0, dtype=np.int64)

    def clear(self, top: int | None = None) -> None:
        """Reset every depth to +inf; with ``top``, move the buffer to the band of frame rows from ``top`` on."""
        if top is not None:
            self.top = _side("top", top, 0)
        self.depth.fill(np.inf)

    def rasterize(self, xy: ArrayLike, depth: ArrayLike, inv_w: ArrayLike | None = None, *,
                  reuse: bool = False) -> Fragments:
        """Draw triangles (device xy (T, 3, 2), NDC depth (T, 3), optional 1/w (T, 3)); return what they won.

        One fragment per pixel won in this call (in no particular order); ``.depth`` is updated. With
        ``reuse``, the fragments' arrays are memory this buffer keeps and overwrites at its next ``reuse``
        call: for a caller done with them by then, it saves the cost of fresh pages.
        """
        pts = _as_array(xy, "xy", (-1, 3, 2))
        count = pts.shape[0]
        z = _as_array(depth, "depth", (count, 3))
        q = None if inv_w is None else _as_array(inv_w, "inv_w", (count, 3))
        if count and max(-float(pts.min()), float(pts.max())) > VERTEX_LIMIT:
            row = int(np.flatnonzero(np.abs(pts).max(axis=(1, 2)) > VERTEX_LIMIT)[0])
            raise InvalidArgument(f"xy row {row} has a vertex beyond ±{VERTEX_LIMIT} px: {pts[row].tolist()}")
        if q is not None and count and float(q.min()) <= 0:
            row = int(np.flatnonzero((q <= 0).any(axis=1))[0])
            raise InvalidArgument(f"inv_w row {row} must be > 0 (clip before rasterizing): {q[row].tolist()}")
        if count == 0:
            return _empty_fragments()
        slope, rows = _setup(pts, z, q, self.width, self.height, self.top)
        np.maximum(rows.length, 0, out=rows.length)
        length = rows.length.astype(np.int64)
        if not length.any():
            return _empty_fragments()
        rows.length = length
        first = np.zeros(length.size + 1, dtype=np.int64)
        np.cumsum(length, out=first[1:])
        offset = rows.start.astype(np.int64) - first[:-1]
        flat = self.depth.reshape(-1)
        lo = int(rows.start.min())
        window = flat[lo:int((rows.start + length).max())]
        # the depths before this call; in a cleared buffer all +inf, seen without copying them
        before: np.ndarray | float = np.inf if float(window.min()) == np.inf else window.copy()
        chunks = _chunks(first)
        keep = first[-1] <= KEEP_PIXELS
        expanded = []
        for a, b in chunks:
            pix, zz, owner = _expand(rows, offset, first, a, b)
            np.minimum.at(flat, pix, zz)
            if keep:
                expanded.append((pix, zz, owner))

        def again(i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            """The pixels of chunk i, kept from pass 1 or expanded again."""
            return expanded[i] if keep else _expand(rows, offset, first, *chunks[i])

        lowered = int(np.count_nonzero(window < before))
        if lowered == first[-1]:  # every candidate is alone at its pixel and nearer: all of them win
            out = _Columns(lowered, self._memory(lowered, reuse))
            for i, (a, _) in enumerate(chunks):
                pix, zz, owner = again(i)
                out.put(int(first[a]), pix, owner, zz, rows, slope, self.width)
            fragments = out.fragments()
        else:
            pieces = []
            for i in range(len(chunks)):
                pix, zz, owner = again(i)
                win = zz == flat[pix]
                win &= zz < (before if isinstance(before, float) else before[pix - lo])
                pieces.append((pix[win], owner[win], zz[win]))
            won = sum(piece[0].size for piece in pieces)
            out = _Columns(won, self._memory(won, reuse))
            pos = 0
            for piece in pieces:
                out.put(pos, *piece, rows, slope, self.width)
                pos += piece[0].size
            fragments = out.fragments()
            if lowered != len(fragments):  # ties: the lowest face (pixels counted in the buffer's rows)
                fragments = fragments.subset(self._lowest_face(fragments.ys * self.width + fragments.xs,
                                                               fragments.face))
        fragments.ys += self.top
        return fragments

    def _memory(self, size: int, reuse: bool) -> np.ndarray:
        """Room for ``size`` fragments: new, or (``reuse``) the memory this buffer keeps for its results."""
        if not reuse:
            return np.empty(7 * size, dtype=np.int64)
        if self._spare.size < 7 * size:
            self._spare = np.empty(7 * max(size, self._spare.size // 7 * 2), dtype=np.int64)
        return self._spare[:7 * size]

    def _lowest_face(self, pix: np.ndarray, face: np.ndarray) -> np.ndarray:
        """Mask keeping, at each pixel won by several equally near triangles, the lowest face."""
        if self._owner is None:
            self._owner = np.empty(self.width * self.height, dtype=np.int64)
        owner = self._owner
        owner[pix] = face
        alone = owner[pix] == face
        owner[pix[~alone]] = _NO_FACE
        tied = owner[pix] == _NO_FACE
        np.minimum.at(owner, pix[tied], face[tied])
        return ~tied | (owner[pix] == face)


class _Columns:
    """Output arrays of a known number of fragments, filled piece by piece."""

    def __init__(self, size: int, memory: np.ndarray) -> None:
        """Seven columns of ``size`` in ``memory`` (int64, at least 7·size): xs, ys, face, depth, 3 weights."""
        column = [memory[k * size:(k + 1) * size] for k in range(4)]
        self.xs, self.ys, self.face = column[:3]
        self.depth = column[3].view(np.float64)
        # one row per vertex: contiguous writes; handed out transposed
        self.bary = memory[4 * size:7 * size].view(np.float64).reshape(3, size)

    def put(self, pos: int, pix: np.ndarray, owner: np.ndarray, depth: np.ndarray, rows: _Rows,
            slope: np.ndarray, width: int) -> None:
        """Store fragments (flat pixel index, owning row, depth) from pos on, with their weights (``slope``: the
        weight slopes (K, T) of :func:`_planes`, by triangle)."""
        sl = slice(pos, pos + pix.size)
        if width & (width - 1):
            ys = np.floor_divide(pix, width, out=self.ys[sl])
            xs = np.subtract(pix, ys * width, out=self.xs[sl])
        else:  # a power of two: a shift and a mask, several times faster than dividing (pix is never negative)
            ys = np.right_shift(pix, width.bit_length() - 1, out=self.ys[sl])
            xs = np.bitwise_and(pix, width - 1, out=self.xs[sl])
        face = np.take(rows.face, owner, out=self.face[sl], mode="clip")
        self.depth[sl] = depth
        l0, l1, l2 = self.bary[0, sl], self.bary[1, sl], self.bary[2, sl]
        for k, out in ((0, l1), (1, l2)):
            np.take(slope[k], face, out=out, mode="clip")  # np.take, unlike fancy indexing, lets other threads run
            out *= xs
            out += np.take(rows.weight0[k], owner, mode="clip")
        if slope.shape[0] == 3:
            total = np.take(slope[2], face, mode="clip")
            total *= xs
            total += np.take(rows.weight0[2], owner, mode="clip")
            np.divide(1.0, total, out=total)
            l1 *= total
            l2 *= total
        np.subtract(1.0, l1, out=l0)
        l0 -= l2

    def fragments(self) -> Fragments:
        """The filled arrays as Fragments (rows of the buffer, from 0)."""
        return Fragments(self.xs, self.ys, self.face, self.bary.T, self.depth)

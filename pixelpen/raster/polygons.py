"""Scan-line polygon fill, vectorised over every edge of every polygon, and the span painter all fills share.

Pixel rule (one rule for every filled primitive): pixel ``(x, y)`` is the unit square centred on the
integer point ``(x, y)`` - the same convention as line endpoints and circle centres - and it is filled
when its centre is inside the polygon under the fill rule ("evenodd" or "nonzero").  A centre exactly on
an edge follows the *top-left rule*: inside when the edge is a left edge or a horizontal top edge,
outside on right and bottom edges.  Implemented as half-open intervals: an edge covers the scanlines
``y_top <= y < y_bottom``, and a span between crossings ``xa`` and ``xb`` fills ``xa <= x < xb``, i.e.
pixels ``ceil(xa) .. ceil(xb) − 1``.  Polygons sharing an edge therefore neither overlap nor leave a gap,
and a mesh of triangles covers each pixel exactly once.

Exactness: vertices are snapped to 1/256 pixel (8 sub-pixel bits, ``SUBPIXEL``), and each crossing is
``ceil((X_top·dY + (256·y − Y_top)·dX) / (256·dY))`` on integers below 2**53, so the float64 division and
``ceil`` are exact: the rule is applied to the true geometry of the snapped polygon, and every part of the
code that meets an edge computes the same crossing for it.  Vertices must lie within ±``VERTEX_LIMIT``.

Algorithm: edge table of all rings -> crossings (edge, scanline) by ragged expansion -> sort by
(polygon, scanline, x) as one int64 key -> spans by the winding/parity rule -> union of spans through a
row-wise difference array (``bincount`` +1 at the start, −1 after the end, ``cumsum``).  Triangles take a
faster path with no sort: each triangle is two trapezoids whose left and right edges are known.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from pixelpen.errors import ConfigError
from pixelpen.raster.lines import ragged

SUBPIXEL = 256
"""Sub-pixel grid vertices are snapped to (8 bits)."""

VERTEX_LIMIT = 1 << 16
"""Largest absolute vertex coordinate, in pixels: keeps every crossing numerator below 2**53."""

RULES = ("evenodd", "nonzero")

_CHUNK = 1 << 15
"""Cells evaluated per vectorised step of the triangle path (float buffers stay in L2 cache)."""


def _ring(values: object, where: str) -> np.ndarray:
    """One ring as an (N, 2) float64 array of finite vertices in range."""
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError(f"{where} is not an (N, 2) array of numbers") from None
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ConfigError(f"{where} must be an (N, 2) array of vertices, found shape {arr.shape}")
    bad = ~np.isfinite(arr).all(axis=1) | (np.abs(arr) > VERTEX_LIMIT).any(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ConfigError(f"{where} vertex {i} {arr[i].tolist()} is not finite or is beyond ±{VERTEX_LIMIT} px")
    return arr


def as_polygons(polygons: object) -> list[list[np.ndarray]]:
    """Normalise input to a list of polygons, each a list of (N, 2) float rings.

    Accepts a single ring ((N, 2) array-like), an (M, N, 2) array of single-ring polygons, or a sequence
    whose items are each a ring or a sequence of rings.
    """
    try:
        arr = np.asarray(polygons, dtype=np.float64)
    except (TypeError, ValueError):
        arr = None
    if arr is not None and arr.ndim == 2:
        return [[_ring(arr, "polygon 0 ring 0")]]
    if arr is not None and arr.ndim == 3:
        return [[_ring(arr[i], f"polygon {i} ring 0")] for i in range(arr.shape[0])]
    if not isinstance(polygons, Sequence) or isinstance(polygons, (str, bytes)):
        raise ConfigError(
            f"polygons must be a ring, an (M, N, 2) array or a list of polygons, found {type(polygons).__name__}"
        )
    out = []
    for i, poly in enumerate(polygons):
        try:
            single = np.asarray(poly, dtype=np.float64)
        except (TypeError, ValueError):
            single = None
        if single is not None and single.ndim == 2:
            out.append([_ring(single, f"polygon {i} ring 0")])
        elif isinstance(poly, Sequence) or (single is not None and single.ndim == 3):
            out.append([_ring(ring, f"polygon {i} ring {j}") for j, ring in enumerate(poly)])
        else:
            raise ConfigError(f"polygon {i} must be a ring or a list of rings, found {type(poly).__name__}")
    return out


def _snap(values: np.ndarray) -> np.ndarray:
    """Coordinates on the sub-pixel grid, as exactly-integral float64."""
    return np.rint(values * SUBPIXEL)


def _row_range(y_top: np.ndarray, y_bottom: np.ndarray, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Scanlines r with y_top <= 256·r < y_bottom (snapped units), clipped to 0..height."""
    first = np.ceil(y_top / SUBPIXEL)
    end = np.ceil(y_bottom / SUBPIXEL)
    return np.clip(first, 0, height).astype(np.int64), np.clip(end, 0, height).astype(np.int64)


def _crossing(
    x_top: np.ndarray, y_top: np.ndarray, dx: np.ndarray, dy: np.ndarray, row: np.ndarray, width: int
) -> np.ndarray:
    """First pixel column right of (or on) an edge at a scanline, clamped to 0..width (exact, see module)."""
    num = x_top * dy + (row * SUBPIXEL - y_top) * dx
    return np.clip(np.ceil(num / (dy * SUBPIXEL)), 0, width).astype(np.int64)


def polygon_spans(
    polygons: object, width: int, height: int, rule: str = "evenodd"
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Filled spans (row, x_start, x_end exclusive) of polygons on a width x height canvas."""
    if rule not in RULES:
        raise ConfigError(f"unknown fill rule {rule!r}: use one of {', '.join(RULES)}")
    polys = as_polygons(polygons)
    rings = [ring for poly in polys for ring in poly]
    if not rings:
        return _no_spans()
    ring_poly = np.repeat(np.arange(len(polys)), [len(p) for p in polys])
    sizes = np.array([r.shape[0] for r in rings], dtype=np.int64)
    verts = _snap(np.concatenate(rings))
    starts = np.cumsum(sizes) - sizes
    ring_of, k = ragged(sizes)
    nxt = starts[ring_of] + (k + 1) % sizes[ring_of]
    a, b = verts, verts[nxt]
    down = b[:, 1] > a[:, 1]
    keep = b[:, 1] != a[:, 1]
    top = np.where(down[:, None], a, b)[keep]
    bottom = np.where(down[:, None], b, a)[keep]
    direction = np.where(down, 1, -1)[keep]
    poly = ring_poly[ring_of][keep]
    r0, r1 = _row_range(top[:, 1], bottom[:, 1], height)
    edge, j = ragged(np.maximum(r1 - r0, 0))
    if edge.size == 0:
        return _no_spans()
    row = r0[edge] + j
    dx = bottom[:, 0] - top[:, 0]
    dy = bottom[:, 1] - top[:, 1]
    col = _crossing(top[edge, 0], top[edge, 1], dx[edge], dy[edge], row, width)
    key = ((poly[edge] * height + row) * (width + 1) + col) * 2 + (direction[edge] > 0)
    key.sort()
    cell = key >> 1
    if rule == "evenodd":
        start, end = cell[0::2], cell[1::2]
    else:
        winding = np.cumsum((key & 1) * 2 - 1)
        before = winding - ((key & 1) * 2 - 1)
        start = cell[(winding != 0) & (before == 0)]
        end = cell[(winding == 0) & (before != 0)]
    row_of = (start // (width + 1)) % height
    return row_of, start % (width + 1), end % (width + 1)


def _no_spans() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An empty span set."""
    empty = np.zeros(0, dtype=np.int64)
    return empty, empty, empty


def as_triangles(tris: ArrayLike) -> np.ndarray:
    """(N, 3, 2) float64 triangles, finite and within ±VERTEX_LIMIT."""
    arr = np.asarray(tris, dtype=np.float64)
    if arr.ndim == 2 and arr.shape == (3, 2):
        arr = arr[None]
    if arr.ndim != 3 or arr.shape[1:] != (3, 2):
        raise ConfigError(f"triangles must be an (N, 3, 2) array, found shape {arr.shape}")
    bad = ~np.isfinite(arr).all(axis=(1, 2)) | (np.abs(arr) > VERTEX_LIMIT).any(axis=(1, 2))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ConfigError(
            f"triangle {i} {arr[i].tolist()} has a vertex that is not finite or beyond ±{VERTEX_LIMIT} px"
        )
    return arr


def triangle_cells(tris: ArrayLike, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Filled spans of triangles as cell indices ``row·(width + 1) + column`` of their starts and ends.

    Same pixels as :func:`polygon_spans` (the same exact crossing per edge), without a sort: each triangle
    (vertices sorted by y: A, B, C) is two trapezoids, rows A..B between AB and AC and rows B..C between BC
    and AC, and the sign of the cross product says which edge is on the left.  The crossings of a
    trapezoid at rows ``r0 + j`` are ``ceil((n0 + j·step) / den)`` with exact integer n0, step, den;
    trapezoids sorted by row count are evaluated in chunks as (trapezoids x rows) outer products, rows past
    a trapezoid's last one repeating its last span (harmless in a union).
    """
    v = _snap(as_triangles(tris))
    order = np.argsort(v[:, :, 1], axis=1, kind="stable")
    v = np.take_along_axis(v, order[:, :, None], axis=1)
    a, b, c = v[:, 0], v[:, 1], v[:, 2]
    cross = (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) - (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
    b_left = np.concatenate([cross > 0, cross > 0])
    top_s, bot_s = np.concatenate([a, b]), np.concatenate([b, c])
    top_l, bot_l = np.concatenate([a, a]), np.concatenate([c, c])
    r0, r1 = _row_range(top_s[:, 1], bot_s[:, 1], height)
    count = r1 - r0
    live = np.flatnonzero(count > 0)
    if live.size == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    live = live[np.argsort(count[live], kind="stable")]
    count, r0, b_left = count[live], r0[live].astype(np.float64), b_left[live]
    inside = (
        (np.minimum(top_s[live, 0], bot_s[live, 0]) >= 0)
        & (np.maximum(top_s[live, 0], bot_s[live, 0]) <= width * SUBPIXEL)
        & (np.minimum(top_l[live, 0], bot_l[live, 0]) >= 0)
        & (np.maximum(top_l[live, 0], bot_l[live, 0]) <= width * SUBPIXEL)
    )
    edges = []
    for top, bottom in ((top_s[live], bot_s[live]), (top_l[live], bot_l[live])):
        dx, dy = bottom[:, 0] - top[:, 0], bottom[:, 1] - top[:, 1]
        n0 = top[:, 0] * dy + (r0 * SUBPIXEL - top[:, 1]) * dx
        edges.append((n0[:, None], (dx * SUBPIXEL)[:, None], (dy * SUBPIXEL)[:, None]))
    (sn, ss, sd), (ln, lstep, ld) = edges
    left = [
        np.where(b_left, sn[:, 0], ln[:, 0]),
        np.where(b_left, ss[:, 0], lstep[:, 0]),
        np.where(b_left, sd[:, 0], ld[:, 0]),
    ]
    right = [
        np.where(b_left, ln[:, 0], sn[:, 0]),
        np.where(b_left, lstep[:, 0], ss[:, 0]),
        np.where(b_left, ld[:, 0], sd[:, 0]),
    ]
    left = [x[:, None] for x in left]
    right = [x[:, None] for x in right]
    row_base = (r0 * (width + 1))[:, None]
    last = (count - 1).astype(np.float64)[:, None]
    # chunks of about _CHUNK cells; the longest trapezoid of a chunk sets its row count
    cum = np.cumsum(count)
    bounds = np.searchsorted(cum, np.arange(_CHUNK, int(cum[-1]) + _CHUNK, _CHUNK), side="right")
    bounds = np.unique(np.concatenate(([0], np.minimum(bounds + 1, live.size), [live.size])))
    total = int(
        sum(int(count[hi - 1]) * (hi - lo) for lo, hi in zip(bounds[:-1].tolist(), bounds[1:].tolist(), strict=False))
    )
    starts = np.empty(total, dtype=np.int64)
    ends = np.empty(total, dtype=np.int64)
    pos = 0
    steps = np.arange(int(count[-1]), dtype=np.float64)
    for lo, hi in zip(bounds[:-1].tolist(), bounds[1:].tolist(), strict=False):
        rows = int(count[hi - 1])
        size = (hi - lo) * rows
        j = steps[:rows]
        if int(count[lo]) != rows:
            j = np.minimum(j, last[lo:hi])
        base = row_base[lo:hi] + j * (width + 1)
        clip = not inside[lo:hi].all()
        for (n0, step, den), out in ((left, starts), (right, ends)):
            x = step[lo:hi] * j
            x += n0[lo:hi]
            x /= den[lo:hi]
            np.ceil(x, out=x)
            if clip:
                np.clip(x, 0, width, out=x)
            x += base
            np.copyto(out[pos : pos + size].reshape(hi - lo, rows), x, casting="unsafe")
        pos += size
    return starts, ends


def triangle_spans(tris: ArrayLike, width: int, height: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Filled spans (row, x_start, x_end exclusive) of triangles: the same pixels as :func:`polygon_spans`.

    A span may be listed more than once (see :func:`triangle_cells`); their union is what is filled.
    """
    starts, ends = triangle_cells(tris, width, height)
    row, col = np.divmod(starts, width + 1)
    return row, col, ends - row * (width + 1)


def paint_cells(target: np.ndarray, starts: np.ndarray, ends: np.ndarray, value: object) -> None:
    """Set the union of spans given as cells ``row·(W + 1) + column`` (start, end exclusive) to value.

    A row-wise difference array over the rows the spans touch: ``bincount`` of starts minus ends,
    ``cumsum``, ``> 0``, one masked assignment.
    """
    if starts.size == 0:
        return
    stride = target.shape[1] + 1
    first = int(starts.min()) // stride
    last = int(ends.max()) // stride + 1
    offset = first * stride
    size = (last - first) * stride
    cover = np.bincount(starts - offset if offset else starts, minlength=size)
    cover -= np.bincount(ends - offset if offset else ends, minlength=size)
    np.cumsum(cover, out=cover)
    mask = (cover > 0).reshape(last - first, stride)[:, :-1]
    target[first:last][mask] = value


def paint_spans(
    target: np.ndarray, row: np.ndarray, start: np.ndarray, end: np.ndarray, value: object
) -> tuple[int, int, int, int] | None:
    """Set the union of spans (row, start..end−1, already clipped to the canvas) to value; return its bbox.

    Few pixels: expanded and scattered directly; many: a row-wise difference array over the spans'
    bounding box (``bincount`` of starts minus ends, ``cumsum``, ``> 0``) and one masked assignment.
    """
    keep = end > start
    if not keep.all():
        row, start, end = row[keep], start[keep], end[keep]
    if row.size == 0:
        return None
    y0, y1 = int(row.min()), int(row.max()) + 1
    x0, x1 = int(start.min()), int(end.max())
    width = x1 - x0
    lengths = end - start
    total = int(lengths.sum())
    if total < 4 * row.size or total < ((y1 - y0) * width) // 4:
        span, k = ragged(lengths)
        columns = target.shape[1]
        flat = target.reshape(target.shape[0] * columns, -1) if target.ndim == 3 else target.reshape(-1)
        flat[row[span] * columns + start[span] + k] = value
        return x0, y0, x1, y1
    cells_base = row * (target.shape[1] + 1)
    paint_cells(target, cells_base + start, cells_base + end, value)
    return x0, y0, x1, y1

"""Scan-line hatching of polygons with holes (even-odd), with hatch lines joined into zig-zags along the boundary."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from pixelpen.errors import ConfigError

MAX_CROSSINGS = 20_000_000
"""Refuse to hatch when the line/edge crossings would exceed this (spacing far too small for the area)."""

JOIN_DETOUR = 2.0
"""A zig-zag connector runs along the boundary; it is used when no longer than this times the straight gap."""


def hatch(
    rings: np.ndarray | Sequence[np.ndarray],
    spacing: float,
    angle: float = 0.0,
    cross: bool = False,
    join: bool = True,
) -> list[np.ndarray]:
    """Hatch lines filling the even-odd interior of ``rings`` at ``spacing`` and ``angle`` (radians), as polylines.

    Hatch lines are parallel to the direction ``angle``, ``spacing`` apart and centred on the polygon's extent
    across them, so a polygon at least ``spacing`` thick gets lines ``spacing / 2`` inside its edges (a solid fill
    at the pen width then covers the area exactly). With ``join`` consecutive lines are linked into zig-zags
    wherever the connector along the boundary between their ends is short; ``cross`` adds a second pass at
    ``angle + pi/2``.
    """
    rings = _as_rings(rings)
    if not (isinstance(spacing, (int, float, np.floating, np.integer)) and math.isfinite(spacing) and spacing > 0):
        raise ConfigError(f"hatch spacing must be a finite number > 0, got {spacing!r}")
    if not math.isfinite(angle):
        raise ConfigError(f"hatch angle must be finite, got {angle!r}")
    lines = _hatch_pass(rings, float(spacing), float(angle), join)
    if cross:
        lines += _hatch_pass(rings, float(spacing), float(angle) + math.pi / 2, join)
    return lines


def _as_rings(rings: np.ndarray | Sequence[np.ndarray]) -> list[np.ndarray]:
    """Validate and convert the input to a list of (N, 2) float arrays (a single array is one ring)."""
    items = [rings] if isinstance(rings, np.ndarray) and rings.ndim == 2 else list(rings)
    out = []
    for i, ring in enumerate(items):
        arr = np.asarray(ring, dtype=np.float64)
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise ConfigError(f"hatch ring {i} must be an (N, 2) array of points, got shape {arr.shape}")
        if not np.isfinite(arr).all():
            raise ConfigError(f"hatch ring {i} has a non-finite coordinate")
        if len(arr) >= 2:
            out.append(arr)
    return out


def _hatch_pass(rings: list[np.ndarray], spacing: float, angle: float, join: bool) -> list[np.ndarray]:
    """One family of parallel hatch lines (see ``hatch``)."""
    if not rings:
        return []
    cos_a, sin_a = math.cos(angle), math.sin(angle)
    pts = np.concatenate(rings)
    # rotate by -angle: hatch lines become horizontal, v = const
    u = pts[:, 0] * cos_a + pts[:, 1] * sin_a
    v = -pts[:, 0] * sin_a + pts[:, 1] * cos_a
    ring_len = np.array([len(r) for r in rings], dtype=np.int64)
    ring_start = np.concatenate([[0], np.cumsum(ring_len)[:-1]])
    ring_of = np.repeat(np.arange(len(rings)), ring_len)
    idx = np.arange(len(pts))
    nxt = np.where(idx + 1 == ring_start[ring_of] + ring_len[ring_of], ring_start[ring_of], idx + 1)

    vmin, vmax = float(v.min()), float(v.max())
    height = vmax - vmin
    if not height > 0:
        return []
    n_lines = max(1, math.ceil(height / spacing - 1e-9))
    v0 = vmin + (height - (n_lines - 1) * spacing) / 2
    # first hatch line at or above each vertex: edge a->b crosses lines k with min(c) <= k < max(c) (half-open)
    c = np.clip(np.ceil((v - v0) / spacing), 0, n_lines).astype(np.int64)
    lo, hi = np.minimum(c, c[nxt]), np.maximum(c, c[nxt])
    count = hi - lo
    total = int(count.sum())
    if total > MAX_CROSSINGS:
        raise ConfigError(
            f"hatch spacing {spacing:g} is too small for a polygon {height:g} units across: "
            f"{total} crossings (limit {MAX_CROSSINGS})"
        )
    if total == 0:
        return []
    edge = np.repeat(idx, count)
    first = np.concatenate([[0], np.cumsum(count)[:-1]])
    local = np.arange(total) - first[edge]
    k = lo[edge] + local
    vk = v0 + k * spacing
    a, b = edge, nxt[edge]
    t = np.clip((vk - v[a]) / (v[b] - v[a]), 0.0, 1.0)
    x = u[a] + t * (u[b] - u[a])

    # pair crossings along each line: sorted by (line, x), every line has an even count
    order = np.argsort(x)
    line_key = k[order].astype(np.int16 if n_lines <= np.iinfo(np.int16).max else np.int64)
    order = order[np.argsort(line_key, kind="stable")]  # radix sort for int16 keys
    left, right = order[0::2], order[1::2]
    seg_k = k[left]
    scale = max(height, float(u.max() - u.min()))
    valid = x[right] - x[left] > 1e-12 * scale
    left, right, seg_k = left[valid], right[valid], seg_k[valid]
    if not len(left):
        return []
    cross_pts = np.column_stack([x, vk])
    if join:
        # position of each crossing walking along its ring: edges in order, along each edge from its start
        ring_pos = np.where(v[b] < v[a], first[edge] + count[edge] - 1 - local, np.arange(total))
        path_pts, path_starts = _zigzag(
            left, right, seg_k, edge, ring_pos, k, cross_pts, u, v, ring_of, ring_start, ring_len
        )
    else:
        flip = seg_k % 2 == 1  # alternate directions: the natural boustrophedon order
        first_end = np.where(flip, right, left)
        second_end = np.where(flip, left, right)
        path_pts = np.stack([cross_pts[first_end], cross_pts[second_end]], axis=1).reshape(-1, 2)
        path_starts = np.arange(0, len(path_pts), 2)
    world = np.column_stack(
        [path_pts[:, 0] * cos_a - path_pts[:, 1] * sin_a, path_pts[:, 0] * sin_a + path_pts[:, 1] * cos_a]
    )
    ends = np.r_[path_starts[1:], len(world)]
    return [world[a:b] for a, b in zip(path_starts.tolist(), ends.tolist(), strict=False)]


def _zigzag(
    left: np.ndarray,
    right: np.ndarray,
    seg_k: np.ndarray,
    edge: np.ndarray,
    ring_pos: np.ndarray,
    k: np.ndarray,
    cross_pts: np.ndarray,
    u: np.ndarray,
    v: np.ndarray,
    ring_of: np.ndarray,
    ring_start: np.ndarray,
    ring_len: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Link hatch segments on consecutive lines through short boundary connectors; return points and path starts."""
    n_cross = len(k)
    n_seg = len(left)
    seg_of = np.full(n_cross, -1, dtype=np.int64)
    seg_of[left] = np.arange(n_seg)
    seg_of[right] = np.arange(n_seg)

    ring_order = np.empty(n_cross, dtype=np.int64)
    ring_order[ring_pos] = np.arange(n_cross)
    ring_sorted = ring_of[edge[ring_order]]
    run_start = np.flatnonzero(np.r_[True, ring_sorted[1:] != ring_sorted[:-1]])
    run_end = np.r_[run_start[1:], n_cross]
    run_of = np.repeat(np.arange(len(run_start)), run_end - run_start)
    j = np.arange(n_cross)
    nj = np.where(j + 1 == run_end[run_of], run_start[run_of], j + 1)
    pj = np.where(j == run_start[run_of], run_end[run_of] - 1, j - 1)
    next_c = np.empty(n_cross, dtype=np.int64)
    prev_c = np.empty(n_cross, dtype=np.int64)
    next_c[ring_order] = ring_order[nj]
    prev_c[ring_order] = ring_order[pj]

    # up-link of a crossing: its ring neighbour on the next hatch line (at most one exists)
    use_next = k[next_c] == k + 1
    use_prev = ~use_next & (k[prev_c] == k + 1)
    cand = np.flatnonzero((use_next | use_prev) & (seg_of >= 0))
    target = np.where(use_next[cand], next_c[cand], prev_c[cand])
    keep = seg_of[target] >= 0
    cand, target = cand[keep], target[keep]
    forward = use_next[cand]

    # boundary vertices between the two crossings, walking along the ring
    r = ring_of[edge[cand]]
    n_r = ring_len[r]
    ea = edge[cand] - ring_start[r]
    eb = edge[target] - ring_start[r]
    n_vert = np.where(forward, (eb - ea) % n_r, (ea - eb) % n_r)
    first_v = np.concatenate([[0], np.cumsum(n_vert)[:-1]])
    link_of_v = np.repeat(np.arange(len(cand)), n_vert)
    m = np.arange(int(n_vert.sum())) - first_v[link_of_v]
    local = np.where(forward[link_of_v], ea[link_of_v] + 1 + m, ea[link_of_v] - m) % n_r[link_of_v]
    conn_vertex = ring_start[r[link_of_v]] + local
    conn_pts = np.column_stack([u[conn_vertex], v[conn_vertex]])

    # connector length along the boundary vs the straight gap
    start_pts, end_pts = cross_pts[cand], cross_pts[target]
    chain = np.concatenate([start_pts, conn_pts, end_pts])
    # each link's chain: start, its vertices, end; lay them out contiguously
    link_base = first_v + 2 * np.arange(len(cand))
    order_idx = np.empty(len(chain), dtype=np.int64)
    order_idx[link_base] = np.arange(len(cand))
    order_idx[link_base[link_of_v] + 1 + m] = len(cand) + np.arange(len(conn_pts))
    order_idx[link_base + n_vert + 1] = len(cand) + len(conn_pts) + np.arange(len(cand))
    laid = chain[order_idx]
    walked = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(laid, axis=0).T))])
    along = walked[link_base + n_vert + 1] - walked[link_base]
    gap = np.hypot(*(end_pts - start_pts).T)
    ok = along <= JOIN_DETOUR * gap + 1e-12 * (1.0 + gap)
    cand, target, n_vert, first_v = cand[ok], target[ok], n_vert[ok], first_v[ok]
    conn_first = np.full(n_cross, -1, dtype=np.int64)
    conn_count = np.zeros(n_cross, dtype=np.int64)
    up = np.full(n_cross, -1, dtype=np.int64)
    up[cand] = target
    conn_first[cand] = first_v
    conn_count[cand] = n_vert

    # one outgoing link per segment: prefer the boustrophedon exit (right on even lines, left on odd)
    pref = np.where(seg_k % 2 == 0, right, left)
    other = np.where(seg_k % 2 == 0, left, right)
    out_c = np.where(up[pref] >= 0, pref, np.where(up[other] >= 0, other, -1))
    src = np.flatnonzero(out_c >= 0)
    dst = seg_of[up[out_c[src]]]
    # one incoming link per segment: the first source wins
    _, first_src = np.unique(dst, return_index=True)
    src, dst = src[first_src], dst[first_src]
    in_c = np.full(n_seg, -1, dtype=np.int64)
    in_c[dst] = up[out_c[src]]
    # a segment cannot enter and leave by the same end
    clash = in_c[src] == out_c[src]
    src, dst = src[~clash], dst[~clash]
    in_c = np.full(n_seg, -1, dtype=np.int64)
    in_c[dst] = up[out_c[src]]
    next_seg = np.full(n_seg, -1, dtype=np.int64)
    next_seg[src] = dst
    prev_seg = np.full(n_seg, -1, dtype=np.int64)
    prev_seg[dst] = src

    # root of each chain by pointer jumping (links always go up one line, so chains are acyclic)
    root = np.where(prev_seg >= 0, prev_seg, np.arange(n_seg))
    while True:
        nroot = root[root]
        if np.array_equal(nroot, root):
            break
        root = nroot
    seq = np.lexsort((seg_k, root))

    has_out = next_seg >= 0
    exit_c = np.where(has_out, out_c, -1)
    entry_c = np.where(in_c >= 0, in_c, np.where(has_out, np.where(out_c == left, right, left), -1))
    default_entry = np.where(seg_k % 2 == 0, left, right)
    entry_c = np.where(entry_c >= 0, entry_c, default_entry)
    exit_c = np.where(exit_c >= 0, exit_c, np.where(entry_c == left, right, left))

    # lay out: entry, exit, connector vertices (for linked segments), per segment in chain order
    n_conn = np.where(has_out, conn_count[exit_c], 0)[seq]
    items = 2 + n_conn
    base = np.concatenate([[0], np.cumsum(items)[:-1]])
    out = np.empty((int(items.sum()), 2))
    out[base] = cross_pts[entry_c[seq]]
    out[base + 1] = cross_pts[exit_c[seq]]
    s_of = np.repeat(np.arange(n_seg), n_conn)
    mm = np.arange(int(n_conn.sum())) - np.concatenate([[0], np.cumsum(n_conn)[:-1]])[s_of]
    out[base[s_of] + 2 + mm] = conn_pts[conn_first[exit_c[seq]][s_of] + mm]

    chain_root = root[seq]
    starts = base[np.r_[True, chain_root[1:] != chain_root[:-1]]]
    # drop repeated points (a hatch line through a vertex makes a crossing equal to a connector vertex)
    dup = np.zeros(len(out), dtype=bool)
    dup[1:] = np.all(out[1:] == out[:-1], axis=1)
    dup[starts] = False
    keep_idx = np.flatnonzero(~dup)
    new_starts = np.searchsorted(keep_idx, starts)
    return out[keep_idx], new_starts

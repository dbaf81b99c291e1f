"""Joining strokes into chains: greedy matching of stroke ends (shortest gap first) and merging touching strokes."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.spatial import cKDTree

from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList

__all__ = ["group_ids", "join_chains", "link_ends", "merge_paths", "walk_chains"]

_CANDIDATES = 8  # nearest other ends considered for joining each end


def group_ids(dl: DisplayList, across_layers: bool = False) -> np.ndarray:
    """A group number per stroke: equal for strokes of the same layer and pen (same pen only if ``across_layers``)."""
    if not len(dl):
        return np.zeros(0, np.int64)
    keys = np.stack([dl.pens, np.zeros_like(dl.pens) if across_layers else dl.layers], axis=1)
    return np.unique(keys, axis=0, return_inverse=True)[1].reshape(-1).astype(np.int64)


def link_ends(n: int, p: np.ndarray, q: np.ndarray, gap: np.ndarray, reverse: bool) -> np.ndarray:
    """Greedy matching of stroke end points: accept candidate links shortest ``gap`` first.

    End point ``2i`` is the start of stroke ``i`` and ``2i + 1`` its end. Each end point takes at most one
    link and no link closes a loop, so the links form chains. Without ``reverse`` only an end may link to
    a start (chains run forward). Returns ``link``: the partner of each end point, or -1.
    """
    p, q, gap = (np.asarray(a).reshape(-1) for a in (p, q, gap))
    ok = (p >> 1) != (q >> 1)
    if not reverse:
        ok &= (p & 1) != (q & 1)
    p, q, gap = p[ok], q[ok], gap[ok]
    # each unordered pair once
    lo, hi = np.minimum(p, q), np.maximum(p, q)
    key = lo * (2 * n) + hi
    key, first = np.unique(key, return_index=True)
    gap = gap[first]
    order = np.argsort(gap, kind="stable")
    lo_list, hi_list = (key[order] // (2 * n)).tolist(), (key[order] % (2 * n)).tolist()
    link = [-1] * (2 * n)
    parent = list(range(n))
    for a, b in zip(lo_list, hi_list, strict=False):
        if link[a] >= 0 or link[b] >= 0:
            continue
        ra, rb = a >> 1, b >> 1
        while parent[ra] != ra:
            parent[ra] = parent[parent[ra]]
            ra = parent[ra]
        while parent[rb] != rb:
            parent[rb] = parent[parent[rb]]
            rb = parent[rb]
        if ra == rb:
            continue
        parent[ra] = rb
        link[a], link[b] = b, a
    return np.asarray(link, dtype=np.int64)


def walk_chains(n: int, link: np.ndarray, reverse: bool) -> tuple[np.ndarray, np.ndarray]:
    """Walk the chains of ``link``: the entry end point of every stroke in chain order, and chain start flags.

    A stroke entered at end point ``e`` is left at ``e ^ 1`` (``e`` odd means the stroke is drawn reversed).
    Without ``reverse`` every chain starts at a stroke start, so no stroke is reversed. With ``reverse`` a
    chain is walked in the direction that reverses the fewer of its strokes.
    """
    links = link.tolist()
    seen = bytearray(n)
    entries: list[int] = []
    heads = np.zeros(n, bool)
    for s in range(2 * n) if reverse else range(0, 2 * n, 2):
        if links[s] >= 0 or seen[s >> 1]:
            continue
        heads[len(entries)] = True
        p = s
        while True:
            seen[p >> 1] = 1
            entries.append(p)
            p = links[p ^ 1]
            if p < 0:
                break
    ent = np.asarray(entries, dtype=np.int64)
    if len(ent) != n:
        raise AssertionError("chains do not cover every stroke")  # links must come from link_ends
    if reverse and n:
        chain = np.cumsum(heads) - 1
        flipped = np.bincount(chain, weights=ent & 1)
        size = np.bincount(chain)
        turn = (2 * flipped > size)[chain]
        start = np.flatnonzero(heads)[chain]
        end = start + size[chain] - 1
        idx = np.arange(n)
        ent = np.where(turn, ent[start + end - idx] ^ 1, ent)
    return ent, heads


def merge_paths(dl: DisplayList, tolerance: float, reverse: bool = True, across_layers: bool = False) -> DisplayList:
    """Join strokes of the same pen and layer whose ends lie within ``tolerance`` (device units).

    Gaps are taken shortest first; a stroke is reversed to join only when ``reverse`` allows. A junction
    whose two points coincide keeps one of them; a gap up to ``tolerance`` is drawn. Merged strokes sit where
    their earliest stroke was.
    """
    if not isinstance(tolerance, (int, float)) or not math.isfinite(tolerance) or tolerance < 0:
        raise ConfigError(f"merge_paths: tolerance must be a finite number >= 0, got {tolerance!r}")
    n = len(dl)
    if n < 2:
        return dl.reordered(np.arange(n))
    ends = np.empty((2 * n, 2))
    ends[0::2], ends[1::2] = dl.starts, dl.ends
    # candidate joins: the nearest few ends within tolerance (bounded work however large the tolerance)
    k = min(_CANDIDATES + 1, 2 * n)
    # the tree's bound is exclusive and compared squared: widen it a hair so gaps equal to tolerance (even 0) join
    bound = max(float(tolerance) * (1 + 1e-9), 1e-150)
    gap, other = cKDTree(ends).query(ends, k=k, distance_upper_bound=bound, workers=-1)
    this = np.repeat(np.arange(2 * n), k)
    gap, other = gap.ravel(), other.ravel()
    group = group_ids(dl, across_layers)
    found = gap <= tolerance
    this, other, gap = this[found], other[found], gap[found]
    same = group[this >> 1] == group[other >> 1]
    link = link_ends(n, this[same], other[same], gap[same], reverse)
    entries, heads = walk_chains(n, link, reverse)
    # chains in the order of their earliest stroke
    chain = np.cumsum(heads) - 1
    earliest = np.full(int(chain[-1]) + 1, n)
    np.minimum.at(earliest, chain, entries >> 1)
    rank = np.argsort(earliest, kind="stable")
    pos_in_chain = np.arange(n) - np.flatnonzero(heads)[chain]
    order = np.lexsort((pos_in_chain, np.argsort(rank)[chain]))
    entries, heads = entries[order], heads[order]
    return join_chains(dl.reordered(entries >> 1, (entries & 1).astype(bool)), ~heads)


def join_chains(dl: DisplayList, join: np.ndarray) -> DisplayList:
    """Concatenate each stroke ``i`` with ``join[i]`` onto the stroke before it; coinciding junction points merge."""
    join = np.asarray(join, bool).copy()
    if len(join):
        join[0] = False
    first = dl.offsets[:-1]
    drop = np.zeros(len(dl.points), bool)
    dup = join & np.all(dl.points[first] == dl.points[np.maximum(first - 1, 0)], axis=1)
    drop[first[dup]] = True
    keep_stroke = ~join
    new_first = first[keep_stroke]
    shift = np.concatenate([[0], np.cumsum(drop)])
    offsets = np.append(new_first - shift[new_first], len(dl.points) - int(drop.sum()))
    return dataclasses.replace(dl, points=dl.points[~drop], offsets=offsets, pens=dl.pens[keep_stroke],
                               layers=dl.layers[keep_stroke])

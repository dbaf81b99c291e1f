"""Pen-up path ordering: nearest neighbour from the pen's home, greedy end matching, 2-opt and Or-opt local search.

Limits (override with ``time_budget`` / ``--time-budget S``, a fixed number of seconds for the whole call): by
default the local search runs to a local optimum but for at most :data:`AUTO_BUDGET_MAX_S` (120 s), and kicks
run for :func:`auto_budget` seconds (:data:`AUTO_BUDGET_MIN_S` + :data:`AUTO_BUDGET_PER_STROKE_S` per stroke,
a little more per stroke beyond 10,000) or until a round of them gains less than :data:`STALL_GAIN`.
"""

from __future__ import annotations

import math
import time
from collections import deque
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial import cKDTree

from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.merge import link_ends, walk_chains

if TYPE_CHECKING:
    from pixelpen.profiles.model import DeviceProfile

__all__ = ["auto_budget", "order_paths", "stroke_groups"]

_NEIGHBOURS = 8  # candidate list length per end point for the local search
_MATCH_NEIGHBOURS = 6  # candidate links per end point for the greedy matching
_OR_SEGMENT = 3  # longest run of strokes an Or-opt move relocates
_REL_EPS = 1e-12  # gains below this fraction of the drawing's extent are rounding noise
_KICK_RUN = 30  # longest run of strokes (each of two) a double-bridge kick swaps
_KICKS_PER_STROKE = 10  # kicks tried per stroke at most, so small inputs finish long before their budget
AUTO_BUDGET_MIN_S = 0.01
"""Least time the adaptive budget (``time_budget=None``) allows a call."""
AUTO_BUDGET_PER_STROKE_S = 30e-6
"""Time the adaptive budget allows per stroke up to 10,000 strokes (vpype's ``linesort`` spends 0.1-0.2 ms a path)."""
AUTO_BUDGET_MAX_S = 120.0
"""Most time an adaptive call (``time_budget=None``) spends, however large the input: a bound on the local search."""
STALL_GAIN = 1e-3
"""Kicks stop when a round of them (an eighth of the strokes, at least 64) cut the cost by less than this fraction."""


def auto_budget(n_strokes: int) -> float:
    """The adaptive time budget (seconds) for the kicks of ordering ``n_strokes`` strokes.

    It grows a little faster than the stroke count beyond 10,000 strokes (by ``(n / 10,000) ** 0.2``), since the
    local search's reversals and splices get longer with the tour.
    """
    n = max(0, int(n_strokes))
    return min(AUTO_BUDGET_MAX_S, AUTO_BUDGET_MIN_S + AUTO_BUDGET_PER_STROKE_S * n * max(1.0, (n / 10_000) ** 0.2))


def _deadlines(time_budget: float | None, n: int) -> tuple[float, float]:
    """Clock times at which kicks stop and at which the local search stops (the same for a fixed budget)."""
    now = time.perf_counter()
    if time_budget is None:
        return now + auto_budget(n), now + AUTO_BUDGET_MAX_S
    return now + time_budget, now + time_budget


def stroke_groups(dl: DisplayList, across_layers: bool = False) -> list[np.ndarray]:
    """Stroke indices in drawing groups: per layer (first-appearance order) then per pen, or per pen only.

    Ordering never moves a stroke out of its group, so layer order is kept and each pen is used in one
    run per group (pen changes are minimised); with ``across_layers`` strokes of the same pen from all
    layers form one group.
    """
    n = len(dl)
    if n == 0:
        return []
    idx = np.arange(n)
    keys = [dl.pens] if across_layers else [dl.layers, dl.pens]
    # rank each key by first appearance, then group stably by the combined rank
    ranks = []
    for key in keys:
        _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
        ranks.append(np.argsort(np.argsort(first))[inverse])
    combined = ranks[0] if len(ranks) == 1 else ranks[0].astype(np.int64) * (ranks[1].max() + 1) + ranks[1]
    order = np.argsort(combined, kind="stable")
    bounds = np.flatnonzero(np.diff(combined[order])) + 1
    return [idx[g] for g in np.split(order, bounds)]


def order_paths(
    dl: DisplayList,
    home: tuple[float, float] = (0.0, 0.0),
    reverse: bool = True,
    time_budget: float | None = None,
    profile: DeviceProfile | None = None,
    across_layers: bool = False,
) -> DisplayList:
    """Reorder (and, if ``reverse``, flip) strokes to cut pen-up travel, starting from ``home`` (device units).

    With ``time_budget`` 0 each group is ordered by greedy nearest neighbour from the pen's position.
    Otherwise near stroke ends are first linked into chains by greedy matching (shortest gap first), the
    chains joined by nearest neighbour, and 2-opt / Or-opt moves on neighbour lists improve the order
    until none gains, then random kicks until their gains stall (below :data:`STALL_GAIN`), all within
    ``time_budget`` seconds for the whole call. With ``time_budget`` None (adaptive) the 2-opt / Or-opt search
    always runs until no move gains (a local optimum, the same on a busy machine as on an idle one; at most
    :data:`AUTO_BUDGET_MAX_S`) and kicks follow while the call is within :func:`auto_budget` of the stroke
    count. With a ``profile`` a hop costs its pen-up travel time under the profile's motion limits instead of
    its length. Groups (see :func:`stroke_groups`) keep their order. The result never has more pen-up travel,
    nor with a profile more pen-up time, than the input's strokes taken group by group in their given order,
    which is the input itself whenever its layers and pens already come in runs.
    """
    if time_budget is not None and (
        isinstance(time_budget, bool)
        or not isinstance(time_budget, (int, float))
        or not time_budget >= 0
        or not math.isfinite(time_budget)
    ):
        raise ConfigError(
            f"order_paths: time_budget must be None or a finite number of seconds >= 0, got {time_budget!r}"
        )
    home_xy = np.asarray(home, dtype=np.float64).reshape(-1)
    if home_xy.shape != (2,) or not np.all(np.isfinite(home_xy)):
        raise ConfigError(f"order_paths: home must be a finite (x, y) pair, got {home!r}")
    if not len(dl):
        return dl.reordered(np.arange(0))
    cost_scalar = float if profile is None else _TravelTime(profile.pen_up, dl.unit_mm)
    t_end, t_cap = _deadlines(time_budget, len(dl))
    starts, ends = dl.starts, dl.ends
    groups = stroke_groups(dl, across_layers)
    order_parts, flip_parts = [], []
    at = home_xy
    remaining = len(dl)
    for g in groups:
        share = len(g) / remaining
        remaining -= len(g)
        now = time.perf_counter()
        deadlines = (now + max(0.0, t_end - now) * share, now + max(0.0, t_cap - now) * share)
        o, f = _order_group(starts[g], ends[g], at, reverse, deadlines, cost_scalar)
        keep = np.arange(len(g)), np.zeros(len(g), bool)
        if _worse_than((starts[g][o], ends[g][o], f), (starts[g], ends[g], keep[1]), at, cost_scalar):
            o, f = keep  # the group as given is at least as good
        order_parts.append(g[o])
        flip_parts.append(f)
        last = g[o[-1]]
        at = starts[last] if f[-1] else ends[last]
    order = np.concatenate(order_parts)
    flips: np.ndarray | None = np.concatenate(flip_parts)
    given = np.concatenate(groups)
    if _worse_than(
        (starts[order], ends[order], flips), (starts[given], ends[given], np.zeros(len(dl), bool)), home_xy, cost_scalar
    ):
        order, flips = given, None
    return dl.reordered(order, flips)


def _worse_than(candidate, baseline, home: np.ndarray, cost_scalar) -> bool:
    """Whether plotting ``candidate`` from ``home`` takes more pen-up travel, or a higher hop cost, than ``baseline``.

    Each is (starts, ends, reversed) of strokes in plotting order.
    """

    def hops(starts, ends, rev):
        entry, exit_ = np.where(rev[:, None], ends, starts), np.where(rev[:, None], starts, ends)
        return np.hypot(*(entry - np.vstack([home[None], exit_[:-1]])).T)

    hc, hb = hops(*candidate), hops(*baseline)
    slack = 1e-9 * max(1.0, float(hb.sum()))
    return bool(hc.sum() > hb.sum() + slack or _apply(cost_scalar, hc).sum() > _apply(cost_scalar, hb).sum() + slack)


class _TravelTime:
    """Pen-up hop cost as travel time: rest-to-rest moves under ``limits`` of distances in device units."""

    def __init__(self, limits, unit_mm: float) -> None:
        self.limits, self.scale = limits, float(unit_mm)

    def __call__(self, d: float) -> float:
        return self.limits.move_time(d * self.scale)

    def vector(self, d: np.ndarray) -> np.ndarray:
        return self.limits.move_times(np.asarray(d, dtype=np.float64) * self.scale)


def _order_group(starts, ends, home, reverse, deadlines, cost_scalar):
    """Order one group of strokes: returns (order, reversed) arrays indexing the group.

    ``deadlines`` are the clock times at which kicks stop and at which the whole search stops.
    """
    deadline = deadlines[1]
    n = len(starts)
    xy = np.empty((2 * n, 2))
    xy[0::2], xy[1::2] = starts, ends
    if time.perf_counter() >= deadline or n < 3:
        entries = _nearest_neighbour(xy, home, reverse)
    else:
        # chains of strokes by greedy matching of near ends, joined by nearest neighbour from home,
        # then local search; all from one batched k-NN query of every end point
        k = min(_NEIGHBOURS + 1, 2 * n)
        dist, nb = cKDTree(xy).query(np.vstack([xy, home]), k=k, workers=-1)
        km = min(_MATCH_NEIGHBOURS + 1, k)
        link = link_ends(n, np.repeat(np.arange(2 * n), km), nb[:-1, :km].ravel(), dist[:-1, :km].ravel(), reverse)
        chain_entries, heads = walk_chains(n, link, reverse)
        tails = np.append(np.flatnonzero(heads)[1:], n) - 1
        chain_xy = np.empty((2 * len(tails), 2))
        chain_xy[0::2] = xy[chain_entries[heads]]
        chain_xy[1::2] = xy[chain_entries[tails] ^ 1]
        chain_order = _nearest_neighbour(chain_xy, home, reverse)
        spans = np.split(chain_entries, np.flatnonzero(heads)[1:])
        entries = np.concatenate([spans[c >> 1][::-1] ^ 1 if c & 1 else spans[c >> 1] for c in chain_order.tolist()])
        # search by distance first: under a concave time cost the search alone stalls in poorer optima;
        # from the distance optimum it goes on to cut the travel time
        if cost_scalar is not float:
            entries = _local_search(xy, home, entries, nb, dist, reverse, (deadline, deadline), float, kicks=False)
        if time.perf_counter() < deadline:
            entries = _local_search(xy, home, entries, nb, dist, reverse, deadlines, cost_scalar)
    return entries >> 1, (entries & 1).astype(bool)


def _nearest_neighbour(xy: np.ndarray, home: np.ndarray, reverse: bool) -> np.ndarray:
    """Greedy nearest neighbour from ``home`` over strokes with end points ``xy[2i]``, ``xy[2i+1]``.

    Returns the entry end point of each stroke in visiting order (odd = entered at its end, so reversed).
    One batched k-NN query serves most steps; when all of a point's neighbours are used, a tree of the
    unused entries answers, rebuilt whenever half of it has gone stale (lazy deletion).
    """
    n = len(xy) // 2
    live = np.arange(0, 2 * n, 1 if reverse else 2)  # entry points a stroke may be started from
    k = min(_NEIGHBOURS + 1, len(live))
    nbl = live[cKDTree(xy[live]).query(np.vstack([xy, home]), k=k, workers=-1)[1].reshape(-1, k)].tolist()
    used = bytearray(n)
    seq = []
    cur = 2 * n  # home
    tree, stale = None, len(live)
    for _ in range(n):
        for q in nbl[cur]:
            if not used[q >> 1]:
                break
        else:
            if tree is None or 2 * stale > len(live):
                live = live[np.frombuffer(bytes(used), dtype=np.uint8)[live >> 1] == 0]
                tree, stale = cKDTree(xy[live]), 0
            q, kk = -1, min(32, len(live))
            while q < 0:
                for j in np.atleast_1d(tree.query(xy[cur] if cur < 2 * n else home, k=kk)[1]).tolist():
                    if not used[live[j] >> 1]:
                        q = int(live[j])
                        break
                else:
                    if kk == len(live):
                        raise AssertionError("nearest neighbour: no unused stroke left")  # cannot happen
                    kk = min(4 * kk, len(live))
        used[q >> 1] = 1
        stale += 2 if reverse else 1
        seq.append(q)
        cur = q ^ 1
    return np.asarray(seq, dtype=np.int64)


def _local_search(xy, home, entries, nb, dist, reverse, deadlines, cost_scalar, kicks: bool = True) -> np.ndarray:
    """Improve a visiting order by 2-opt (when strokes may be reversed) and Or-opt moves, then by kicks.

    The order is held as a cycle of end points: home (``H_out``), each stroke's entry and exit point, then
    the path end ``H_in``, which costs nothing to reach, so the cycle's cost is the open path's pen-up
    cost. A stroke's two points stay adjacent (mates ``p ^ 1``); a point's other cycle neighbour is its
    hop partner. Candidate moves come from each point's k nearest neighbours; points whose hops changed
    are queued again (don't-look bits); reversals and splices take the shorter side of the cycle. Once no
    move gains, and while time is left, ``kicks`` perturbs the order with local double bridges (swapping
    two short adjacent runs of strokes), searches again around them and keeps the result only if it is
    cheaper (iterated local search); kicks stop at ``deadlines[0]``, or when a round of them gains less than
    :data:`STALL_GAIN`, and all search at ``deadlines[1]``. Returns the entry point of each stroke in the
    improved order.
    """
    kick_deadline, deadline = deadlines
    n = len(entries)
    N = 2 * n + 2
    HOUT, HIN = 2 * n, 2 * n + 1
    # number the points in the starting order (mates stay 2i, 2i+1): the points of a stretch of the tour
    # then sit close together in every array, which keeps the bulk updates of long reversals cache-friendly
    old = np.empty(2 * n, dtype=np.int64)
    old[0::2], old[1::2] = entries, entries ^ 1
    new_of_old = np.empty(2 * n + 1, dtype=np.int64)
    new_of_old[old], new_of_old[HOUT] = np.arange(2 * n), HOUT
    rows = np.append(old, HOUT)
    nb, dist = new_of_old[nb[rows]], dist[rows]
    pts = np.vstack([xy[old], home, home])
    seq = np.concatenate([[HOUT], np.arange(2 * n), [HIN]])
    xs, ys = pts[:, 0].tolist(), pts[:, 1].tolist()
    use_cost = cost_scalar is not float
    hypot = math.hypot
    # state in numpy arrays (bulk updates of a move) read and written through memoryviews (fast scalars):
    # tour order, position of each point, hop partner and hop cost of each point
    tour_a = seq.copy()
    pos_a = np.empty(N, dtype=np.int64)
    pos_a[tour_a] = np.arange(N)
    hp_a = np.empty(N, dtype=np.int64)
    hp_a[seq[0::2]], hp_a[seq[1::2]] = seq[1::2], seq[0::2]
    hop_len = np.hypot(*(pts[seq[0::2]] - pts[seq[1::2]]).T)
    hop_len[-1] = 0.0  # last exit -> H_in
    hc_a = np.empty(N)
    hc_a[seq[0::2]] = hc_a[seq[1::2]] = _apply(cost_scalar, hop_len)
    # numpy's stubs give ndarray the buffer protocol only for Python 3.12+ (__buffer__); the target is 3.10
    tour, pos, hp, hc = (memoryview(a) for a in (tour_a, pos_a, hp_a, hc_a))  # type: ignore[arg-type]
    nbl = nb.tolist()
    ncost = _apply(cost_scalar, dist).tolist()
    extent = float(np.ptp(pts, axis=0).max())
    eps = _REL_EPS * max(1.0, cost_scalar(extent) if use_cost else extent)
    journal: list[tuple[int, ...]] | None = None  # undo records while a kick is on trial

    def cost(p, q):
        if p == HIN or q == HIN:
            return 0.0
        d = hypot(xs[p] - xs[q], ys[p] - ys[q])
        return cost_scalar(d) if use_cost else d

    def link(p, q, c):
        if journal is not None:
            journal.append((p, hp[p], hc[p], q, hp[q], hc[q]))
        hp[p], hp[q], hc[p], hc[q] = q, p, c, c

    def place(idx, ids):
        if journal is not None:
            journal.append((idx, tour_a[idx], ids, pos_a[ids]))
        tour_a[idx] = ids
        pos_a[ids] = idx

    def undo():
        for rec in reversed(journal or []):
            if len(rec) == 4:
                tour_a[rec[0]] = rec[1]
                pos_a[rec[2]] = rec[3]
            else:
                p, hpp, hcp, q, hpq, hcq = rec
                hp[p], hc[p], hp[q], hc[q] = hpp, hcp, hpq, hcq

    def reverse_section(a, b):
        """Reverse the cyclic section running forward from point a to point b (or its complement)."""
        i, j = pos[a], pos[b]
        length = (j - i) % N + 1
        if 2 * length > N:
            i, length = (j + 1) % N, N - length
        if journal is None and i + length <= N:  # the common case, on slices
            section = tour_a[i : i + length]
            section[:] = section[::-1].copy()
            pos_a[section] = np.arange(i, i + length)
            return
        idx = np.arange(i, i + length) % N
        place(idx, tour_a[idx[::-1]])

    def move_run(u, v, fwd, x, y):
        """Cut the run u..v (lying forward from u when ``fwd``) and splice it in between x and y, u next to x."""
        first, last = (u, v) if fwd else (v, u)
        i = pos[first]
        L = (pos[last] - i) % N + 1
        run = tour_a[np.arange(i, i + L) % N]
        j = pos[x] + 1
        x_first = tour[j if j < N else 0] == y  # x comes before y going forward
        if run[0] != (u if x_first else v):
            run = run[::-1]
        # arc A runs from after the run to the first edge end; arc B from the second edge end to before the run
        a_len = (pos[x if x_first else y] - (i + L)) % N + 1
        b_len = N - L - a_len
        if a_len <= b_len:
            place(np.arange(i, i + a_len + L) % N, np.concatenate([tour_a[np.arange(i + L, i + L + a_len) % N], run]))
        else:
            place(np.arange(i - b_len, i + L) % N, np.concatenate([run, tour_a[np.arange(i - b_len, i) % N]]))

    def improve(a):
        """Apply the first gaining move that gives point ``a`` a new hop partner; returns the gain (0 if none)."""
        b, dab = hp[a], hc[a]
        cands, ccost = nbl[a], ncost[a]
        if reverse:
            # 2-opt: new hops (a, c) and (b, d) for c a near neighbour of a (or the path end), d its partner
            j = pos[a] + 1
            a_fwd = tour[j if j < N else 0] == b
            for t in range(len(cands) + 1):
                if t < len(cands):
                    c, dac = cands[t], ccost[t]
                    if dac >= dab:
                        c, dac = HIN, 0.0
                else:
                    c, dac = HIN, 0.0
                d = hp[c]
                if c != b and d != a and c != a and c != (a ^ 1):
                    j = pos[c] + 1
                    if (tour[j if j < N else 0] == d) == a_fwd:
                        dbd = cost(b, d)
                        gain = dab + hc[c] - dac - dbd
                        if gain > eps:
                            if a_fwd:
                                reverse_section(b, c)
                            else:
                                reverse_section(a, d)
                            link(a, c, dac)
                            link(b, d, dbd)
                            wake(a, b, c, d)
                            return gain
                if c == HIN:
                    break
        if a == HOUT:
            return 0.0
        # Or-opt: move the run of 1..3 strokes that starts at a (away from its partner b) next to a near neighbour
        u, p = a, b
        j = pos[p] + 1
        fwd = tour[j if j < N else 0] == u
        v = u ^ 1
        for _ in range(_OR_SEGMENT):
            q = hp[v]
            if q == p:
                break
            dpq = cost(p, q)
            g0 = hc[u] + hc[v] - dpq
            if g0 > eps:
                lo, span = pos[u], (pos[v] - pos[u]) % N if fwd else (pos[u] - pos[v]) % N
                for t in range(len(cands) + 1):
                    if t < len(cands):
                        x, dxu = cands[t], ccost[t]
                        if dxu >= g0:
                            x, dxu = HIN, 0.0
                    else:
                        x, dxu = HIN, 0.0
                    if x != p and x != q and ((pos[x] - lo) % N if fwd else (lo - pos[x]) % N) > span:
                        y = hp[x]
                        j = pos[x] + 1
                        if reverse or (tour[j if j < N else 0] == y) == fwd:  # else the run would turn round
                            dvy = cost(v, y)
                            gain = g0 + hc[x] - dxu - dvy
                            if gain > eps:
                                move_run(u, v, fwd, x, y)
                                link(p, q, dpq)
                                link(x, u, dxu)
                                link(v, y, dvy)
                                wake(p, q, u, v, x, y)
                                return gain
                    if x == HIN:
                        break
            if q in (HOUT, HIN):
                break
            v = q ^ 1
        return 0.0

    active = deque(seq[:-1].tolist())
    queued = bytearray(b"\x01") * N
    queued[HIN] = 0

    def wake(*ps):
        for p in ps:
            if not queued[p] and p != HIN:
                queued[p] = 1
                active.append(p)

    clock = time.perf_counter

    def drain() -> float:
        """Improve until no queued point gains or time is up; returns the total gain."""
        total, steps = 0.0, 0
        while active:
            steps += 1
            if not steps & 127 and clock() > deadline:
                break
            a = active.popleft()
            queued[a] = 0
            if a != HOUT or reverse:
                total += improve(a)
        return total

    total = float(hc_a[seq[0::2]].sum())  # the cost of the order, kept up to date below
    total -= drain()
    if kicks and n >= 8:
        rng = np.random.default_rng(0)
        window = min(_KICK_RUN, n // 3)
        tries = 0
        rounds = max(64, n // 8)
        round_start = total
        while tries < _KICKS_PER_STROKE * n and not active and clock() < min(kick_deadline, deadline):
            tries += 1
            if not tries % rounds:
                if round_start - total < STALL_GAIN * total:
                    break  # improvement has stalled
                round_start = total
            # three hop edges at stored positions i1 < i2 < i3: runs B = (i1, i2], C = (i2, i3] swap places
            i1 = int(rng.integers(0, N - 4 * window - 2))
            if hp[tour[i1]] != tour[i1 + 1]:
                i1 += 1  # hop edges and mate edges alternate along the cycle
            i2 = i1 + 2 * int(rng.integers(1, window + 1))
            i3 = i2 + 2 * int(rng.integers(1, window + 1))
            a1, b1, a2, b2, a3, b3 = (tour[i] for i in (i1, i1 + 1, i2, i2 + 1, i3, i3 + 1))
            c1, c2, c3 = cost(a1, b2), cost(a3, b1), cost(a2, b3)
            delta = c1 + c2 + c3 - hc[a1] - hc[a2] - hc[a3]
            journal = []
            place(np.arange(i1 + 1, i3 + 1), np.concatenate([tour_a[i2 + 1 : i3 + 1], tour_a[i1 + 1 : i2 + 1]]))
            link(a1, b2, c1)
            link(a3, b1, c2)
            link(a2, b3, c3)
            wake(a1, b1, a2, b2, a3, b3)
            gain = drain() - delta
            if gain > eps:
                total -= gain
                journal = None
                continue
            while active:  # cut short by the deadline
                queued[active.pop()] = 0
            undo()
            journal = None
    # read the path from H_out, away from H_in
    i = pos[HOUT]
    step = 1 if tour[(i - 1) % N] == HIN else -1
    return old[tour_a[(i + step * (1 + 2 * np.arange(n))) % N]]


def _apply(cost_scalar, d: np.ndarray) -> np.ndarray:
    """The hop cost of every distance in ``d``."""
    if cost_scalar is float:
        return np.asarray(d, dtype=np.float64)
    return cost_scalar.vector(np.asarray(d, dtype=np.float64))

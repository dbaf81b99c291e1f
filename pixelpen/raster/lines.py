"""Scan conversion of straight lines: DDA and Bresenham textbook references, and exact vectorised batches.

Conventions (all of :mod:`pixelpen.raster`): pixel ``(x, y)`` has its centre at integer device coordinates
``(x, y)``, x to the right, y down; a segment's endpoints are pixel centres and both are drawn.

Bresenham (Hearn & Baker §3.5, extended to all octants): with ``major = max(|dx|, |dy|)`` and
``minor = min(|dx|, |dy|)``, start at ``(x0, y0)``, ``p0 = 2·minor − major``; at each major step the minor
coordinate steps when ``p >= 0`` (then ``p += 2·minor − 2·major``, else ``p += 2·minor``).  Ties (the ideal
line passing exactly half-way between two pixels) therefore step *away from the start point*: after ``k``
major steps the minor offset is ``off(k) = floor(k·minor/major + 1/2)``, round-half-up of the ideal line
measured from the start.  Swapping the endpoints can move tie pixels; Pillow's ``ImageDraw.line`` makes the
same choice.

The batch code (:class:`LineRuns`) evaluates that closed form for every pixel of every segment at once:
float32 while exact (``14·major·(n+1) < 2**24`` and the canvas has at most 2**23 pixels), float64 while
``14·major·(n+1) < 2**53``, exact int64 otherwise, with an ``eps`` that lies between the rounding error and
the smallest non-zero distance ``1/(2·major)`` to the next integer (graphics.md §4).  Segments are clipped
first by clamping their step range ``k`` to the steps whose pixel lies on the canvas (inverting ``off``), so
the pixels drawn are exactly the on-canvas pixels of the unclipped line, whatever the endpoints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from pixelpen.errors import ConfigError
from pixelpen.geometry.clip import liang_barsky_parameters

COORD_LIMIT = 1 << 29
"""Largest absolute endpoint coordinate accepted: keeps every intermediate product inside int64."""

_CHUNK = 1 << 15
"""Pixels per vectorised step of the fast path: the float buffers stay in L2 cache."""

_MAX_RUN = 2 * _CHUNK
"""Longest run (pixels of one segment on the canvas) the fast path's step vectors cover."""


def int_args(values: tuple[object, ...], what: str) -> list[int]:
    """The arguments as Python ints, or ConfigError naming the one that is not integral."""
    out = []
    for name, v in zip(("x0", "y0", "x1", "y1", "xc", "yc", "r"), values, strict=False):
        try:
            iv = int(v)  # type: ignore[call-overload]
        except (TypeError, ValueError, OverflowError):
            raise ConfigError(f"{what}: {name} must be an integer, found {v!r}") from None
        if iv != v:
            raise ConfigError(f"{what}: {name} must be an integer, found {v!r}")
        out.append(iv)
    return out


def dda(x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
    """Digital differential analyser (Hearn & Baker §3.5): (N, 2) int pixels from (x0, y0) to (x1, y1).

    ``steps = max(|dx|, |dy|)``; x and y advance by ``dx/steps`` and ``dy/steps`` in floating point and
    each position is rounded half up (``floor(v + 0.5)``, the book's ``ROUND`` for non-negative values).
    A pure-Python reference; accumulated float error can move a tie pixel relative to :func:`bresenham`.
    """
    x0, y0, x1, y1 = int_args((x0, y0, x1, y1), "dda")
    dx, dy = x1 - x0, y1 - y0
    steps = max(abs(dx), abs(dy))
    if steps == 0:
        return np.array([[x0, y0]], dtype=np.int64)
    xinc, yinc = dx / steps, dy / steps
    x, y = float(x0), float(y0)
    out = [(x0, y0)]
    for _ in range(steps):
        x += xinc
        y += yinc
        out.append((int(np.floor(x + 0.5)), int(np.floor(y + 0.5))))
    return np.array(out, dtype=np.int64)


def bresenham(x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
    """Bresenham's integer line (Hearn & Baker), all octants: (N, 2) int pixels in plotting order.

    Decision ``p0 = 2·minor − major``; step the minor axis when ``p >= 0``.  Ties step away from the start
    point (round half up of the ideal line measured from the start).  Pure Python: the reference the
    vectorised :class:`LineRuns` is tested against.
    """
    x0, y0, x1, y1 = int_args((x0, y0, x1, y1), "bresenham")
    dx, dy = abs(x1 - x0), abs(y1 - y0)
    sx = 1 if x1 >= x0 else -1
    sy = 1 if y1 >= y0 else -1
    steep = dy > dx
    major, minor = (dy, dx) if steep else (dx, dy)
    p = 2 * minor - major
    x, y = x0, y0
    out = [(x, y)]
    for _ in range(major):
        if p >= 0:
            if steep:
                x += sx
            else:
                y += sy
            p += 2 * minor - 2 * major
        else:
            p += 2 * minor
        if steep:
            y += sy
        else:
            x += sx
        out.append((x, y))
    return np.array(out, dtype=np.int64)


def ragged(counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Expand per-item counts into (owner, index): item i repeated counts[i] times, index 0..counts[i]-1."""
    counts = np.asarray(counts, dtype=np.int64)
    owner = np.repeat(np.arange(counts.shape[0]), counts)
    starts = np.cumsum(counts) - counts
    index = np.arange(owner.shape[0], dtype=np.int64) - starts[owner]
    return owner, index


def as_int_array(values: ArrayLike, columns: int, what: str, limit: int = COORD_LIMIT) -> np.ndarray:
    """An (N, columns) int64 array from integer-valued input; ConfigError names the first bad row."""
    arr = np.asarray(values)
    if arr.ndim == 1 and arr.shape[0] == columns:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != columns:
        raise ConfigError(f"{what} must be an (N, {columns}) array, found shape {arr.shape}")
    if arr.dtype.kind == "b" or arr.dtype.kind not in "iuf":
        raise ConfigError(f"{what} must hold integers, found dtype {arr.dtype}")
    if arr.dtype.kind == "f":
        bad = ~np.isfinite(arr) | (arr != np.round(arr))
        if bad.any():
            row = int(np.flatnonzero(bad.any(axis=1))[0])
            raise ConfigError(f"{what} row {row} is not integral: {arr[row].tolist()}")
    if arr.size and (np.abs(arr.astype(np.float64)) > limit).any():
        row = int(np.flatnonzero((np.abs(arr.astype(np.float64)) > limit).any(axis=1))[0])
        raise ConfigError(f"{what} row {row} has a coordinate beyond ±{limit}: {arr[row].tolist()}")
    return arr.astype(np.int64)


def _ceil_div(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Exact ceil(a / b) for int64 arrays with b > 0."""
    return -((-a) // b)


@dataclass
class LineRuns:
    """The on-canvas part ("run") of each segment of a batch, ready to be scan-converted.

    Pixel ``j`` of run ``i`` (``0 <= j < count[i]``) is, along the major axis, ``major_start + j·step_major``
    and, along the minor axis, ``minor_start + step_minor·floor((phase + 2·j·minor) / (2·major))``;
    ``first`` is the Bresenham step index of pixel 0 in the whole segment (for dash phases).
    """

    width: int
    height: int
    segment: np.ndarray
    steep: np.ndarray
    major_start: np.ndarray
    minor_start: np.ndarray
    step_major: np.ndarray
    step_minor: np.ndarray
    major: np.ndarray
    minor: np.ndarray
    phase: np.ndarray
    count: np.ndarray
    first: np.ndarray

    @classmethod
    def clip(cls, segments: ArrayLike, width: int, height: int) -> LineRuns:
        """Clip an (N, 4) array of integer segments x0, y0, x1, y1 to a width x height canvas."""
        seg = as_int_array(segments, 4, "segments")
        x0, y0, x1, y1 = seg.T
        dx, dy = x1 - x0, y1 - y0
        adx, ady = np.abs(dx), np.abs(dy)
        steep = ady > adx
        major = np.where(steep, ady, adx)
        minor = np.where(steep, adx, ady)
        s_major = np.where(steep, np.where(dy < 0, -1, 1), np.where(dx < 0, -1, 1))
        s_minor = np.where(steep, np.where(dx < 0, -1, 1), np.where(dy < 0, -1, 1))
        m0_major = np.where(steep, y0, x0)
        m0_minor = np.where(steep, x0, y0)
        len_major = np.where(steep, height, width)
        len_minor = np.where(steep, width, height)
        # steps whose major coordinate is on the canvas
        k_lo = np.maximum(0, np.where(s_major > 0, -m0_major, m0_major - (len_major - 1)))
        k_hi = np.minimum(major, np.where(s_major > 0, len_major - 1 - m0_major, m0_major))
        # steps whose minor offset off(k) lies in [t_lo, t_hi]; off(k) >= t <=> k >= ceil(major(2t-1)/(2minor))
        t_lo = np.where(s_minor > 0, -m0_minor, m0_minor - (len_minor - 1))
        t_hi = np.where(s_minor > 0, len_minor - 1 - m0_minor, m0_minor)
        den = 2 * np.maximum(minor, 1)
        flat = minor == 0
        k_min = np.where(flat, np.where(t_lo <= 0, 0, major + 1), _ceil_div(major * (2 * t_lo - 1), den))
        k_max = np.where(flat, np.where(t_hi >= 0, major, -1), _ceil_div(major * (2 * t_hi + 1), den) - 1)
        k_lo = np.maximum(k_lo, k_min)
        k_hi = np.minimum(k_hi, k_max)
        keep = np.flatnonzero(k_lo <= k_hi)
        major1 = np.maximum(major, 1)[keep]
        k_lo, k_hi, minor = k_lo[keep], k_hi[keep], minor[keep]
        q, r0 = np.divmod(2 * k_lo * minor + major1, 2 * major1)
        s_major, s_minor = s_major[keep], s_minor[keep]
        return cls(
            width=int(width), height=int(height), segment=keep, steep=steep[keep],
            major_start=m0_major[keep] + s_major * k_lo, minor_start=m0_minor[keep] + s_minor * q,
            step_major=s_major, step_minor=s_minor, major=major1, minor=minor, phase=r0,
            count=k_hi - k_lo + 1, first=k_lo,
        )

    def __len__(self) -> int:
        return int(self.count.shape[0])

    @property
    def pixel_count(self) -> int:
        """Total pixels of all runs."""
        return int(self.count.sum())

    def _end_offsets(self) -> np.ndarray:
        """Minor offset of each run's last pixel relative to its first."""
        return (self.phase + 2 * (self.count - 1) * self.minor) // (2 * self.major)

    def bbox(self) -> tuple[int, int, int, int] | None:
        """Half-open pixel bounding box (x0, y0, x1, y1) of all runs, or None when nothing is on the canvas."""
        if len(self) == 0:
            return None
        maj_a = self.major_start
        maj_b = self.major_start + self.step_major * (self.count - 1)
        min_a = self.minor_start
        min_b = self.minor_start + self.step_minor * self._end_offsets()
        xs = np.concatenate([np.where(self.steep, min_a, maj_a), np.where(self.steep, min_b, maj_b)])
        ys = np.concatenate([np.where(self.steep, maj_a, min_a), np.where(self.steep, maj_b, min_b)])
        return int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1

    def pixels(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Exact integer evaluation: (x, y, step, run) for every pixel, runs in order, pixels in plotting order.

        ``step`` is the pixel's Bresenham step index within its whole segment (``first + j``).
        """
        run, j = ragged(self.count)
        off = (self.phase[run] + 2 * j * self.minor[run]) // (2 * self.major[run])
        along = self.major_start[run] + j * self.step_major[run]
        across = self.minor_start[run] + off * self.step_minor[run]
        steep = self.steep[run]
        return np.where(steep, across, along), np.where(steep, along, across), self.first[run] + j, run

    def flat_indices(self, keep: np.ndarray | None = None) -> np.ndarray:
        """Row-major flat pixel indices (y·width + x) of all pixels, optionally only where ``keep`` is true."""
        x, y, _, _ = self.pixels()
        idx = y * self.width + x
        return idx if keep is None else idx[keep]

    def draw(self, target: np.ndarray, value: object) -> None:
        """Write ``value`` into every pixel of every run of ``target`` (an HxW or HxWxC C-contiguous array).

        Large batches take the fast float path below; small ones the exact integer path.
        """
        plane = target.reshape(self.height * self.width, -1) if target.ndim == 3 else target.reshape(-1)
        total = self.pixel_count
        if total == 0:
            return
        if total < max(1 << 14, (self.width * self.height) >> 3):
            plane[self.flat_indices()] = value
            return
        precise = _precision_class(self)
        slow = precise == 2
        if slow.any():
            plane[_subset(self, np.flatnonzero(slow)).flat_indices()] = value
        fast = np.flatnonzero(~slow)
        steep = self.steep[fast]
        flat_runs = fast[~steep]
        steep_runs = fast[steep]
        if flat_runs.size:
            _scatter_fast(plane, _subset(self, flat_runs), precise[flat_runs], value)
        if steep_runs.size:
            mask = np.zeros((self.width, self.height), dtype=np.uint8)
            _scatter_fast(mask.reshape(-1), _subset(self, steep_runs), precise[steep_runs], np.uint8(1))
            where = mask.T.view(bool)
            mask = where[..., None] if target.ndim == 3 else where
            np.copyto(target, np.asarray(value, dtype=target.dtype), where=mask)


def _subset(runs: LineRuns, pick: np.ndarray) -> LineRuns:
    """The runs selected by the index array ``pick``."""
    fields = {
        name: getattr(runs, name)[pick]
        for name in (
            "segment",
            "steep",
            "major_start",
            "minor_start",
            "step_major",
            "step_minor",
            "major",
            "minor",
            "phase",
            "count",
            "first",
        )
    }
    return LineRuns(width=runs.width, height=runs.height, **fields)


def _precision_class(runs: LineRuns) -> np.ndarray:
    """Per run: 0 = float32 is exact, 1 = float64 is exact, 2 = needs int64 (graphics.md §4 bounds)."""
    bound = 14.0 * runs.major.astype(np.float64) * (runs.count + 1)
    small_canvas = runs.width * runs.height <= (1 << 23)
    cls = np.where(bound < 2.0**53, 1, 2)
    if small_canvas:
        cls = np.where(bound < 2.0**24, 0, cls)
    too_long = runs.count > _MAX_RUN
    return np.where(too_long, 2, cls)


_STEPS: dict[type, np.ndarray] = {dtype: np.arange(_MAX_RUN, dtype=dtype) for dtype in (np.float32, np.float64)}


def _schedule(key: np.ndarray, count: np.ndarray) -> list[tuple[int, int, int]]:
    """Split runs sorted by (key, count) into chunks of equal key and count of about _CHUNK pixels."""
    if key.size == 0:
        return []
    change = np.flatnonzero((np.diff(key) != 0) | (np.diff(count) != 0)) + 1
    starts = np.concatenate(([0], change))
    ends = np.concatenate((change, [key.size]))
    per = np.maximum(1, _CHUNK // count[starts])
    pieces = -(-(ends - starts) // per)
    group, part = ragged(pieces)
    lo = starts[group] + part * per[group]
    hi = np.minimum(lo + per[group], ends[group])
    return list(zip(lo.tolist(), hi.tolist(), count[lo].tolist(), strict=False))


def _scatter_fast(plane: np.ndarray, runs: LineRuns, precise: np.ndarray, value: object) -> None:
    """Write the pixels of runs that all share one orientation into ``plane``, with float arithmetic.

    Runs along x go into the row-major canvas plane (index ``x + W·y``), runs along y into a transposed
    plane (index ``y + H·x``), so the major axis has stride 1 and consecutive writes stay in cache lines.
    Per chunk of runs with equal length ``L`` and direction: ``u = j·slope + c`` (outer product),
    ``floor``, ``index = A + S·floor(u) ± j``, cast, scatter - into preallocated buffers.
    """
    stride = runs.height if bool(runs.steep[0]) else runs.width
    forward = runs.step_major > 0
    key = precise * 2 + forward
    order = np.lexsort((runs.count, key))
    count = runs.count[order]
    precise, forward = precise[order], forward[order]
    major = runs.major[order].astype(np.float64)
    slope64 = runs.minor[order] / major
    eps = 4.0 * (count + 1) * np.where(precise == 0, 2.0**-24, 2.0**-53)
    c64 = runs.phase[order] / (2.0 * major) + eps
    s64 = (runs.step_minor[order] * stride).astype(np.float64)
    a64 = (runs.major_start[order] + runs.minor_start[order] * stride).astype(np.float64)
    columns: dict[type, tuple[np.ndarray, ...]] = {}
    for dtype in (np.float32, np.float64):
        columns[dtype] = tuple(v.astype(dtype)[:, None] for v in (slope64, c64, s64, a64))
    bufs = {dtype: (np.empty(2 * _CHUNK, dtype), np.empty(2 * _CHUNK, dtype)) for dtype in (np.float32, np.float64)}
    index = np.empty(2 * _CHUNK, dtype=np.intp)
    steps: dict[type, tuple[np.ndarray, np.ndarray]] = {
        dtype: (-_STEPS[dtype], _STEPS[dtype]) for dtype in (np.float32, np.float64)
    }
    for lo, hi, length in _schedule(key[order], count):
        dtype = np.float32 if precise[lo] == 0 else np.float64
        slope, c, s, a = columns[dtype]
        size = (hi - lo) * length
        buf = bufs[dtype][0][:size].reshape(hi - lo, length)
        buf2 = bufs[dtype][1][:size].reshape(hi - lo, length)
        np.multiply(slope[lo:hi], _STEPS[dtype][:length], out=buf)
        buf += c[lo:hi]
        np.floor(buf, out=buf)
        buf *= s[lo:hi]
        np.add(a[lo:hi], steps[dtype][int(forward[lo])][:length], out=buf2)
        buf += buf2
        idx = index[:size]
        np.copyto(idx, buf.reshape(-1), casting="unsafe")
        plane[idx] = value


def _clip_parameters(
    p0: np.ndarray, p1: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Liang–Barsky parameters (t0, t1, keep) of each segment p0-p1 inside the box lo..hi (geometry's clipper)."""
    cols = np.stack([p0[:, 0], p0[:, 1], p1[:, 0], p1[:, 1]])
    return liang_barsky_parameters(cols, (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])))


def stroke_triangles(
    segments: np.ndarray,
    width: int,
    cap: str,
    canvas_width: int,
    canvas_height: int,
    dash: tuple[np.ndarray, int] | None = None,
    phase: np.ndarray | None = None,
) -> np.ndarray:
    """(M, 3, 2) triangles outlining thick segments (see ``Canvas.lines``); clipped near the canvas first.

    Each (piece of a) segment becomes a rectangle ``width`` wide (two triangles), extended by width/2 for
    square caps; round caps add a regular polygon of radius width/2 at each end.  With a dash table the
    on-runs ``[ka, kb)`` of major-axis steps become butt-ended pieces from step ``ka − 1/2`` to ``kb − 1/2``.
    """
    seg = segments.astype(np.float64)
    p0, p1 = seg[:, :2], seg[:, 2:]
    half = width / 2.0
    margin = width + 2.0
    lo = np.array([-margin, -margin])
    hi = np.array([canvas_width - 1 + margin, canvas_height - 1 + margin])
    t0, t1, keep = _clip_parameters(p0, p1, lo, hi)
    dashing = dash is not None
    if dashing:
        on, period = dash  # type: ignore[misc]
        major = np.abs(segments[:, 2:] - segments[:, :2]).max(axis=1)
        start_phase = np.zeros(seg.shape[0], dtype=np.int64) if phase is None else phase.astype(np.int64)
        k_first = np.where(keep, np.floor(t0 * major) - 1, 0).astype(np.int64)
        k_last = np.where(keep, np.ceil(t1 * major) + 1, -1).astype(np.int64)
        k_first, k_last = np.maximum(k_first, 0), np.minimum(k_last, major)
        owner, step = ragged(np.maximum(k_last - k_first + 1, 0))
        step = step + k_first[owner]
        lit = on[(step + start_phase[owner]) % period]
        same = owner[1:] == owner[:-1]
        begin = lit & ~np.concatenate(([False], lit[:-1] & same))
        finish = lit & ~np.concatenate((lit[1:] & same, [False]))
        own, ka, kb = owner[begin], step[begin], step[finish] + 1
        direction = (p1[own] - p0[own]) / np.maximum(major[own], 1)[:, None]
        p0 = p0[own] + direction * (ka[:, None] - 0.5)
        p1 = p0 + direction * (kb - ka)[:, None]
        zero = (major[own] == 0)[:, None]
        p0 = np.where(zero, seg[own, :2], p0)
        p1 = np.where(zero, seg[own, :2], p1)
        t0, t1, keep = _clip_parameters(p0, p1, lo, hi)
    a = (p0 + (p1 - p0) * t0[:, None])[keep]
    b = (p0 + (p1 - p0) * t1[:, None])[keep]
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    point = length == 0
    u = np.where(point[:, None], [1.0, 0.0], d / np.where(point, 1.0, length)[:, None])
    n = np.stack([-u[:, 1], u[:, 0]], axis=1) * half
    extend = np.where(point, half if cap == "square" else 0.0, 0.0 if dashing or cap != "square" else half)
    ext = u * extend[:, None]
    quads = np.stack([a - ext + n, b + ext + n, b + ext - n, a - ext - n], axis=1)
    quads = quads[~point | (cap == "square")]
    tris = [quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]
    if cap == "round" and not dashing:
        sides = int(min(64, max(8, np.ceil(np.pi * width / 2))))
        angle = np.arange(sides + 1) * (2 * np.pi / sides)
        ring = np.stack([np.cos(angle), np.sin(angle)], axis=1) * half
        centres = np.concatenate([a, b])
        rim = centres[:, None, :] + ring[None, :, :]
        fan = np.stack([np.repeat(centres[:, None, :], sides, axis=1), rim[:, :-1], rim[:, 1:]], axis=2)
        tris.append(fan.reshape(-1, 3, 2))
    return np.concatenate(tris)

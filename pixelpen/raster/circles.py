"""Scan conversion of circles and axis-aligned ellipses: midpoint textbook references and exact batches.

Midpoint circle (Hearn & Baker §3.9): ``x = 0, y = r, p0 = 1 − r``; while ``x < y``: ``x += 1``; if
``p < 0`` then ``p += 2x + 1`` else ``y −= 1, p += 2(x − y) + 1``; each (x, y) is plotted with its eight
symmetric images.  The batch code uses the closed form ``y(x) = ceil(sqrt(r² − x²) − 1/2)`` (the integer y
with ``y² − y < r² − x² <= y² + y``) for ``x = 0 .. X``, ``X`` the last x with ``x <= y(x)``; the
algorithm's final overshoot step (``x > y``, e.g. r = 2, x = 2) only re-plots a mirrored pixel, so
clamping there changes nothing.

Midpoint ellipse (Hearn & Baker §3.10, region 1 then region 2) with the decision parameters evaluated
exactly (scaled by 4, all integer): region 1 ``p1 = f(x + 1, y − 1/2)`` with ``p1_0 = ry² − rx²·ry + rx²/4``,
step y when ``p1 >= 0``, while ``ry²·x < rx²·y``; region 2 ``p2 = f(x + 1/2, y − 1)``, step x when
``p2 <= 0``, until y = 0.  (The book rounds p1_0 and p2_0 with ``ROUND``; exact arithmetic keeps every
decision the sign of the true midpoint function, which rounding would flip when p2 = 1/4.)  ``ry = 0`` is
the degenerate flat ellipse: the horizontal segment ``|x| <= rx``.  The batch closed form: region 1
``y(x) = max(yc(x), yc(x − 1) − 1)``, ``yc(x)`` the smallest y with ``f(x, y + 1/2) >= 0``; region 2
``x(y) = max(xc(y), X1)``, ``xc(y)`` the smallest x with ``f(x + 1/2, y) > 0`` (checked exhaustively
against the loop in the tests).

Filled shapes are the spans between the outline's extreme pixels on each row.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from pixelpen.errors import ConfigError
from pixelpen.raster.lines import COORD_LIMIT, as_int_array, int_args, ragged

RADIUS_LIMIT = (1 << 15) - 1
"""Largest radius accepted (circles and ellipses): keeps the exact integer checks inside int64."""


def _unique_in_order(points: list[tuple[int, int]]) -> np.ndarray:
    """(N, 2) int array of the distinct points in order of first appearance."""
    seen: dict[tuple[int, int], None] = dict.fromkeys(points)
    return np.array(list(seen), dtype=np.int64).reshape(-1, 2)


def _symmetric8(xc: int, yc: int, x: int, y: int) -> list[tuple[int, int]]:
    """Hearn & Baker's circlePlotPoints order."""
    return [(xc + x, yc + y), (xc - x, yc + y), (xc + x, yc - y), (xc - x, yc - y),
            (xc + y, yc + x), (xc - y, yc + x), (xc + y, yc - x), (xc - y, yc - x)]


def _symmetric4(xc: int, yc: int, x: int, y: int) -> list[tuple[int, int]]:
    """Hearn & Baker's ellipsePlotPoints order."""
    return [(xc + x, yc + y), (xc - x, yc + y), (xc + x, yc - y), (xc - x, yc - y)]


def midpoint_circle(xc: int, yc: int, r: int) -> np.ndarray:
    """Midpoint circle (Hearn & Baker): (N, 2) int pixels, each once, in the order first plotted."""
    xc, yc, r = int_args((xc, yc, r), "midpoint_circle")
    if r < 0:
        raise ConfigError(f"midpoint_circle: radius must be >= 0, found {r}")
    x, y, p = 0, r, 1 - r
    out = _symmetric8(xc, yc, x, y)
    while x < y:
        x += 1
        if p < 0:
            p += 2 * x + 1
        else:
            y -= 1
            p += 2 * (x - y) + 1
        out += _symmetric8(xc, yc, x, y)
    return _unique_in_order(out)


def midpoint_ellipse(xc: int, yc: int, rx: int, ry: int) -> np.ndarray:
    """Midpoint ellipse (Hearn & Baker, regions 1 and 2, exact decisions): (N, 2) int pixels in plot order."""
    xc, yc, rx, ry = int_args((xc, yc, rx, ry), "midpoint_ellipse")
    if rx < 0 or ry < 0:
        raise ConfigError(f"midpoint_ellipse: radii must be >= 0, found rx={rx}, ry={ry}")
    out: list[tuple[int, int]] = []
    if ry == 0:
        for x in range(rx + 1):
            out += _symmetric4(xc, yc, x, 0)
        return _unique_in_order(out)
    a2, b2 = rx * rx, ry * ry
    x, y = 0, ry
    out += _symmetric4(xc, yc, x, y)
    p = 4 * b2 - 4 * a2 * ry + a2  # 4·f(1, ry − 1/2)
    while b2 * x < a2 * y:
        x += 1
        if p < 0:
            p += 4 * b2 * (2 * x + 1)
        else:
            y -= 1
            p += 4 * b2 * (2 * x + 1) - 8 * a2 * y
        out += _symmetric4(xc, yc, x, y)
    p = b2 * (2 * x + 1) ** 2 + 4 * a2 * (y - 1) ** 2 - 4 * a2 * b2  # 4·f(x + 1/2, y − 1)
    while y > 0:
        y -= 1
        if p > 0:
            p += 4 * a2 * (1 - 2 * y)
        else:
            x += 1
            p += 4 * a2 * (1 - 2 * y) + 8 * b2 * x
        out += _symmetric4(xc, yc, x, y)
    return _unique_in_order(out)


def _circle_y(r: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Closed-form midpoint circle ordinate ceil(sqrt(r² − x²) − 1/2), 0 where x > r."""
    rf = r.astype(np.float64)
    return np.ceil(np.sqrt(np.maximum(rf * rf - x * x.astype(np.float64), 0.0)) - 0.5).astype(np.int64)


def _octant_end(r: np.ndarray) -> np.ndarray:
    """X per circle: the last x of the first octant, i.e. the largest x with x <= y(x)."""
    t = np.maximum(np.floor(r * np.sqrt(0.5)).astype(np.int64) - 1, 0)
    last = t - 1
    for i in range(4):
        cand = t + i
        last = np.where(cand <= _circle_y(r, cand), cand, last)
    return last


def circle_octant(radii: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """First-octant points (owner, x, y) of midpoint circles of the given radii: x = 0..X, y = y(x) >= x."""
    r = np.asarray(radii, dtype=np.int64)
    owner, x = ragged(_octant_end(r) + 1)
    return owner, x, _circle_y(r[owner], x)


def circle_rows(radii: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(owner, dy, half-width) for dy = 0..r: the extreme outline pixel of row ±dy of each midpoint circle.

    Rows dy <= X hold the mirrored octant point (y(dy), dy); a row dy > X holds the octant points with
    y(x) = dy, the last of which is the largest x with y(x) >= dy, i.e. x² <= r² − dy² + dy − 1.
    """
    r = np.asarray(radii, dtype=np.int64)
    end = _octant_end(r)
    owner, dy = ragged(r + 1)
    rr = r[owner]
    upper = _isqrt_floor(np.maximum(rr * rr - dy * dy + dy - 1, 0))
    return owner, dy, np.where(dy <= end[owner], _circle_y(rr, dy), upper)


def _isqrt_floor(n: np.ndarray) -> np.ndarray:
    """floor(sqrt(n)) for int64 n >= 0 (float estimate, then exact integer correction)."""
    s = np.floor(np.sqrt(n.astype(np.float64))).astype(np.int64)
    s = np.where(s * s > n, s - 1, s)
    return np.where((s + 1) * (s + 1) <= n, s + 1, s)


def _ellipse_yc(a: np.ndarray, b: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Smallest y >= 0 with a²(2y + 1)² >= 4b²(a² − x²) (region 1 of the midpoint ellipse)."""
    rhs = 4 * b * b * np.maximum(a * a - x * x, 0)
    # (2y + 1) >= sqrt(rhs) / a  <=>  2y + 1 >= ceil(sqrt(rhs) / a) for integers; correct by exact checks
    y = np.maximum(np.ceil((np.sqrt(rhs.astype(np.float64)) / np.maximum(a, 1) - 1) / 2), 0).astype(np.int64)
    y = np.where(a * a * (2 * y + 1) ** 2 < rhs, y + 1, y)
    return np.where((y > 0) & (a * a * (2 * y - 1) ** 2 >= rhs), y - 1, y)


def _ellipse_xc(a: np.ndarray, b: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Smallest x >= 0 with b²(2x + 1)² > 4a²(b² − y²) (region 2 of the midpoint ellipse)."""
    rhs = 4 * a * a * np.maximum(b * b - y * y, 0)
    x = np.maximum(np.floor((np.sqrt(rhs.astype(np.float64)) / np.maximum(b, 1) - 1) / 2) + 1, 0).astype(np.int64)
    x = np.where(b * b * (2 * x + 1) ** 2 <= rhs, x + 1, x)
    return np.where((x > 0) & (b * b * (2 * x - 1) ** 2 > rhs), x - 1, x)


def ellipse_quadrant(rx: np.ndarray, ry: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """First-quadrant points (owner, x, y) of midpoint ellipses, in the algorithm's order per ellipse."""
    a = np.asarray(rx, dtype=np.int64)
    b = np.asarray(ry, dtype=np.int64)
    # region 1 candidates x = 0 .. a + 1; X1 = first x with b²x >= a²·y(x)
    own1, x1 = ragged(a + 2)
    aa, bb = a[own1], b[own1]
    yc = _ellipse_yc(aa, bb, x1)
    prev = np.concatenate(([0], yc[:-1]))
    y1 = np.where(x1 == 0, bb, np.maximum(yc, prev - 1))
    stop = (bb * bb * x1 >= aa * aa * y1) | (bb == 0)
    starts = np.cumsum(a + 2) - (a + 2)
    first_stop = np.full(a.shape[0], -1, dtype=np.int64)
    hit = np.flatnonzero(stop)
    # stops are in position order: the first of each owner is its region-1 end
    owners_hit = own1[hit]
    firsts = hit[np.concatenate(([True], owners_hit[1:] != owners_hit[:-1]))] if hit.size else hit
    first_stop[own1[firsts]] = firsts - starts[own1[firsts]]
    if (first_stop < 0).any():
        bad = int(np.flatnonzero(first_stop < 0)[0])
        raise ConfigError(f"ellipse {bad} (rx={int(a[bad])}, ry={int(b[bad])}) has no region-1 end")
    flat_line = b == 0
    x_end = np.where(flat_line, a, first_stop)
    keep1 = x1 <= x_end[own1]
    own1, x1, y1 = own1[keep1], x1[keep1], np.where(flat_line[own1[keep1]], 0, y1[keep1])
    # region 2: y from y(X1) − 1 down to 0
    y_end = y1[np.cumsum(x_end + 1) - 1]
    own2, k = ragged(np.where(flat_line, 0, y_end))
    y2 = y_end[own2] - 1 - k
    x2 = np.maximum(_ellipse_xc(a[own2], b[own2], y2), x_end[own2])
    owner = np.concatenate([own1, own2])
    order = np.argsort(owner, kind="stable")
    return owner[order], np.concatenate([x1, x2])[order], np.concatenate([y1, y2])[order]


def as_centres(centres: ArrayLike, what: str = "centres") -> np.ndarray:
    """(N, 2) int64 centres from integer-valued input."""
    return as_int_array(centres, 2, what, COORD_LIMIT)


def as_radii(radii: ArrayLike, n: int, what: str) -> np.ndarray:
    """(n,) int64 radii (a scalar is broadcast) in 0..RADIUS_LIMIT."""
    arr = np.asarray(radii)
    if arr.ndim == 0:
        arr = np.full(n, arr)
    if arr.ndim != 1 or arr.shape[0] != n:
        raise ConfigError(
            f"{what} must be a scalar or an array of {n} values (one per centre), found shape {arr.shape}"
        )
    arr = as_int_array(arr[:, None], 1, what, RADIUS_LIMIT)[:, 0]
    if arr.size and arr.min() < 0:
        raise ConfigError(f"{what} must be >= 0, found {int(arr.min())} at index {int(np.argmin(arr))}")
    return arr


def symmetric_points(
    centres: np.ndarray, owner: np.ndarray, x: np.ndarray, y: np.ndarray, octants: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Absolute pixel coordinates of the 4 (quadrant) or 8 (octant) symmetric images of each point."""
    cx, cy = centres[owner, 0], centres[owner, 1]
    pairs = [(x, y), (-x, y), (x, -y), (-x, -y)]
    if octants:
        pairs += [(y, x), (-y, x), (y, -x), (-y, -x)]
    px = np.concatenate([cx + dx for dx, _ in pairs])
    py = np.concatenate([cy + dy for _, dy in pairs])
    return px, py


def symmetric_spans(
    centres: np.ndarray, owner: np.ndarray, x: np.ndarray, y: np.ndarray, octants: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row spans (row, x_start, x_end exclusive) joining each row's symmetric outline pixels."""
    cx, cy = centres[owner, 0], centres[owner, 1]
    rows = [cy + y, cy - y]
    half = [x, x]
    if octants:
        rows += [cy + x, cy - x]
        half += [y, y]
    h = np.concatenate(half)
    c = np.concatenate([cx] * len(rows))
    return np.concatenate(rows), c - h, c + h + 1

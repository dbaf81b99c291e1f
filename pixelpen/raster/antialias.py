"""Anti-aliased lines by Xiaolin Wu's algorithm: a scalar reference and a vectorised batch with blending.

Wu's line (with the usual fractional-endpoint handling): along the major axis each column gets the two
pixels straddling the ideal line, weighted ``1 − frac`` and ``frac`` of the line's minor position; each
endpoint column is weighted by the part of its pixel the segment covers along the major axis (``xgap``),
so a segment ending on a pixel centre gives that pixel half weight - and two segments of a polyline
meeting there add up to full weight.  Endpoints may be fractional.

In a batch the coverages of all segments are summed per pixel and clipped to 1, then blended once:
``new = old + (value − old)·coverage``, rounded half up, per channel (alpha too for RGBA).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from pixelpen.errors import ConfigError
from pixelpen.raster.lines import COORD_LIMIT, ragged


def wu_line(x0: float, y0: float, x1: float, y1: float) -> tuple[np.ndarray, np.ndarray]:
    """Wu's anti-aliased line, pure Python: ((N, 2) int pixels in plotting order, (N,) coverages in 0..1)."""
    for name, v in zip(("x0", "y0", "x1", "y1"), (x0, y0, x1, y1), strict=False):
        if not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
            raise ConfigError(f"wu_line: {name} must be a finite number, found {v!r}")
    steep = abs(y1 - y0) > abs(x1 - x0)
    if steep:
        x0, y0, x1, y1 = y0, x0, y1, x1
    if x0 > x1:
        x0, y0, x1, y1 = x1, y1, x0, y0
    dx, dy = x1 - x0, y1 - y0
    gradient = dy / dx if dx else 1.0
    pixels: list[tuple[int, int]] = []
    cover: list[float] = []

    def plot(x: int, y: int, c: float) -> None:
        pixels.append((y, x) if steep else (x, y))
        cover.append(c)

    def fpart(v: float) -> float:
        return v - math.floor(v)

    xend = math.floor(x0 + 0.5)
    yend = y0 + gradient * (xend - x0)
    xgap = 1.0 - fpart(x0 + 0.5)
    xpxl1 = xend
    plot(xpxl1, math.floor(yend), (1.0 - fpart(yend)) * xgap)
    plot(xpxl1, math.floor(yend) + 1, fpart(yend) * xgap)
    intery = yend + gradient
    xend = math.floor(x1 + 0.5)
    yend = y1 + gradient * (xend - x1)
    xgap = fpart(x1 + 0.5)
    xpxl2 = xend
    for x in range(xpxl1 + 1, xpxl2):
        plot(x, math.floor(intery), 1.0 - fpart(intery))
        plot(x, math.floor(intery) + 1, fpart(intery))
        intery += gradient
    plot(xpxl2, math.floor(yend), (1.0 - fpart(yend)) * xgap)
    plot(xpxl2, math.floor(yend) + 1, fpart(yend) * xgap)
    return np.array(pixels, dtype=np.int64).reshape(-1, 2), np.array(cover, dtype=np.float64)


def as_float_segments(segments: ArrayLike) -> np.ndarray:
    """(N, 4) float64 segments, finite and within ±COORD_LIMIT."""
    arr = np.asarray(segments, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == 4:
        arr = arr[None]
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise ConfigError(f"segments must be an (N, 4) array, found shape {arr.shape}")
    bad = ~np.isfinite(arr).all(axis=1) | (np.abs(arr) > COORD_LIMIT).any(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ConfigError(f"segments row {i} is not finite or beyond ±{COORD_LIMIT}: {arr[i].tolist()}")
    return arr


def wu_coverage(segments: ArrayLike, width: int, height: int, dash: tuple[np.ndarray, int] | None = None
                ) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised Wu lines on a width x height canvas: (flat pixel indices, coverage), each pixel once.

    Coverage is summed over all segments and clipped to 1.  ``dash`` = (on-table, period): a column is
    drawn when ``on[step % period]``, step counted in major-axis pixels from the segment's first point.
    """
    seg = as_float_segments(segments)
    x0, y0, x1, y1 = seg.T.copy()
    steep = np.abs(y1 - y0) > np.abs(x1 - x0)
    x0, y0, x1, y1 = (
        np.where(steep, y0, x0),
        np.where(steep, x0, y0),
        np.where(steep, y1, x1),
        np.where(steep, x1, y1),
    )
    swap = x0 > x1
    x0, y0, x1, y1 = np.where(swap, x1, x0), np.where(swap, y1, y0), np.where(swap, x0, x1), np.where(swap, y0, y1)
    dx, dy = x1 - x0, y1 - y0
    gradient = np.where(dx != 0, dy / np.where(dx != 0, dx, 1.0), 1.0)
    xpxl1 = np.floor(x0 + 0.5)
    yend1 = y0 + gradient * (xpxl1 - x0)
    gap1 = 1.0 - ((x0 + 0.5) - np.floor(x0 + 0.5))
    xpxl2 = np.floor(x1 + 0.5)
    yend2 = y1 + gradient * (xpxl2 - x1)
    gap2 = (x1 + 0.5) - np.floor(x1 + 0.5)
    major_len = np.where(steep, height, width)
    # interior columns xpxl1+1 .. xpxl2-1, clamped to the canvas along the major axis
    lo = np.maximum(xpxl1 + 1, -1)
    hi = np.minimum(xpxl2 - 1, major_len)
    line, k = ragged(np.maximum(hi - lo + 1, 0).astype(np.int64))
    col = lo[line] + k
    inter = yend1[line] + gradient[line] * (col - xpxl1[line])
    cols = np.concatenate([xpxl1, xpxl2, col])
    ys = np.concatenate([yend1, yend2, inter])
    gaps = np.concatenate([gap1, gap2, np.ones_like(inter)])
    owner = np.concatenate([np.arange(seg.shape[0]), np.arange(seg.shape[0]), line])
    if dash is not None:
        on, period = dash
        start_col = np.where(swap, xpxl2, xpxl1)
        step = np.abs(cols - start_col[owner]).astype(np.int64)
        keep = on[step % period]
        cols, ys, gaps, owner = cols[keep], ys[keep], gaps[keep], owner[keep]
    base = np.floor(ys)
    frac = ys - base
    major = np.concatenate([cols, cols])
    minor = np.concatenate([base, base + 1])
    cover = np.concatenate([(1.0 - frac) * gaps, frac * gaps])
    st = np.concatenate([steep[owner], steep[owner]])
    px = np.where(st, minor, major)
    py = np.where(st, major, minor)
    keep = (px >= 0) & (px < width) & (py >= 0) & (py < height) & (cover > 0)
    flat = py[keep].astype(np.int64) * width + px[keep].astype(np.int64)
    pixels, inverse = np.unique(flat, return_inverse=True)
    total = np.bincount(inverse, weights=cover[keep], minlength=pixels.shape[0])
    return pixels, np.minimum(total, 1.0)


def blend(target: np.ndarray, pixels: np.ndarray, coverage: np.ndarray, value: np.ndarray) -> None:
    """Blend value into target's flat pixels by coverage: old + (value − old)·coverage, rounded half up."""
    if pixels.size == 0:
        return
    flat = target.reshape(target.shape[0] * target.shape[1], -1)
    old = flat[pixels].astype(np.float64)
    c = coverage[:, None]
    new = np.floor(old + (np.asarray(value, dtype=np.float64).reshape(1, -1) - old) * c + 0.5)
    flat[pixels] = np.clip(new, 0, 255).astype(target.dtype)

"""Damage trimming: a frame's damaged rectangles shrunk to what differs from the shadow of the sent frame.

The changed mask of each rectangle (in the controller's alignment units; ``native`` and ``shadow`` may be HxW
values, such as RGB565, or HxWxC) is cut without labelling.  Small damage (at most :data:`EXACT_TRIM` of the
panel or :data:`EXACT_PIXELS`) is first cut exactly: cropped to its bounding box with ``np.any`` over each
axis, then cut into bands of identical rows and each band into its runs of changed columns (a square moving
by a few pixels costs only the strips it uncovered and covered).  A change making more than
:data:`MAX_BANDS` such bands (text, glyphs changing), and any larger damage (a diagonal across the screen has
the whole screen as its bounding box), is cut into bands of :data:`BAND_ROWS` rows (more for a tall change,
so that there are at most :data:`MAX_WINDOWS` bands), each band into the runs of its changed columns, the
gaps between runs closed where that costs no more than the window it saves, and the cheapest others while
more than :data:`MAX_WINDOWS` windows remain.  A rectangle in which more than :data:`SEND_WHOLE` of its
values changed (a video frame) is sent whole.
"""

from __future__ import annotations

import numpy as np

from pixelpen.devices.panels.windows import MAX_WINDOWS, WindowCost
from pixelpen.raster.damage import Rect, bounding, group_any, mask_runs, pixel_mask

EXACT_TRIM = 1 / 16
"""Damage of at most this share of the panel is cut exactly (bands of identical rows, runs of columns)."""
EXACT_PIXELS = 2048
"""...or of at most this many pixels (a cursor on a 128x64 OLED): small panels are cut exactly too."""
SEND_WHOLE = 0.5
"""A damaged rectangle in which more than this share of the values changed is sent whole (a video frame)."""
MAX_BANDS = 8
"""Bands of identical rows a cut by bands makes at most; a more ragged change is cut by :func:`_band_runs`."""
BAND_ROWS = 4
"""Rows (at least one alignment unit) of the bands a ragged change is cut into."""


def trim_damage(rects: list[Rect], native: np.ndarray, shadow: np.ndarray, cost: WindowCost) -> list[Rect]:
    """The parts of ``rects`` (window space) where ``native`` differs from ``shadow``, aligned to ``cost.align``."""
    height, width = native.shape[:2]
    ax, ay = cost.align
    exact = sum(r.area for r in rects) <= max(EXACT_TRIM * width * height, EXACT_PIXELS)
    if exact and len(rects) > 1:
        box = bounding(rects)
        if box.area <= 2 * sum(r.area for r in rects):
            rects = [box]  # one pass over their bounding box (outside the damage the canvas is the shadow)
    out: list[Rect] = []
    for r in rects:
        a = r.aligned(ax, ay, width, height)
        rows, cols = a.slices
        now, before = native[rows, cols], shadow[rows, cols]
        diff = now != before
        changed = np.count_nonzero(diff)
        if not changed:
            continue
        if changed > SEND_WHOLE * diff.size:
            out.append(a)
            continue
        mask = pixel_mask(diff)
        units = _units(mask, ax, ay)
        cut = _bands(units) if exact else None
        if cut is None:
            band = max(BAND_ROWS // ay, -(-units.shape[0] // MAX_WINDOWS), 1)
            cut = _band_runs(units, band, cost.bytes_per_pixel * ax * ay, cost.window_overhead)
        if ax == ay == 1:
            out.extend(Rect(a.x0 + x0, a.y0 + y0, a.x0 + x1, a.y0 + y1) for x0, y0, x1, y1 in cut)
        else:  # the last units may be cut by the rectangle's edge
            out.extend(Rect(min(a.x0 + x0 * ax, a.x1), min(a.y0 + y0 * ay, a.y1), min(a.x0 + x1 * ax, a.x1),
                            min(a.y0 + y1 * ay, a.y1)) for x0, y0, x1, y1 in cut)
    return out


def _units(diff: np.ndarray, ax: int, ay: int) -> np.ndarray:
    """The changed mask per alignment unit (ax x ay pixels; the last ones may be cut by the rectangle's edge)."""
    if ay > 1:
        diff = group_any(diff, ay)
    if ax > 1:
        diff = group_any(diff.T, ax).T
    return diff


def _bands(mask: np.ndarray) -> list[tuple[int, int, int, int]] | None:
    """An exact cover of the True units of ``mask`` by (x0, y0, x1, y1) boxes: the bounding box, cut into
    bands of identical rows and each band into its runs; None when that makes more than MAX_BANDS bands."""
    rows_any: np.ndarray = np.any(mask, axis=1)
    cols_any: np.ndarray = np.any(mask, axis=0)
    y0, y1 = int(rows_any.argmax()), rows_any.shape[0] - int(rows_any[::-1].argmax())
    x0, x1 = int(cols_any.argmax()), cols_any.shape[0] - int(cols_any[::-1].argmax())
    box = mask[y0:y1, x0:x1]
    if box.all():
        return [(x0, y0, x1, y1)]
    new = np.ones(box.shape[0], dtype=bool)
    new[1:] = (box[1:] != box[:-1]).any(axis=1)
    starts = np.flatnonzero(new).tolist()
    if len(starts) > MAX_BANDS:
        return None
    ends = [*starts[1:], box.shape[0]]
    bands, run_starts, run_ends = mask_runs(box[starts])
    return [(x0 + s, y0 + starts[k], x0 + e, y0 + ends[k])
            for k, s, e in zip(bands.tolist(), run_starts.tolist(), run_ends.tolist(), strict=True)]


def _band_runs(mask: np.ndarray, band: int, unit_bytes: float, window_bytes: int) -> list[tuple[int, int, int, int]]:
    """A cover of the True units of ``mask`` by (x0, y0, x1, y1) boxes: bands of ``band`` rows, each cut into
    the runs of its changed columns; a gap between two runs of a band is closed when its ``unit_bytes`` cost
    no more than a window's ``window_bytes``, then the cheapest gaps while more than MAX_WINDOWS boxes remain."""
    bands, starts, ends = mask_runs(group_any(mask, band) if band > 1 else mask)
    rows = np.minimum(mask.shape[0] - bands * band, band)
    gap = (starts[1:] - ends[:-1]) * rows[1:] * float(unit_bytes)
    other = bands[1:] != bands[:-1]
    gap[other] = np.inf  # never closed: a window does not cross bands
    close = gap <= window_bytes
    surplus = gap.size - int(np.count_nonzero(close)) - max(MAX_WINDOWS - 1, int(np.count_nonzero(other)))
    if surplus > 0:
        gap[close] = np.inf
        close[np.argpartition(gap, surplus - 1)[:surplus]] = True
    first = np.flatnonzero(~close) + 1
    y0 = (bands[first] * band).tolist()
    y0.insert(0, int(bands[0]) * band)
    heights = rows[first].tolist()
    heights.insert(0, int(rows[0]))
    x0 = starts[first].tolist()
    x0.insert(0, int(starts[0]))
    x1 = ends[first - 1].tolist()
    x1.append(int(ends[-1]))
    return [(a, b, c, b + h) for a, b, c, h in zip(x0, y0, x1, heights, strict=True)]

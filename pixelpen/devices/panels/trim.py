"""Damage trimming: a frame's damaged rectangles shrunk to what differs from the shadow of the sent frame.

The changed mask of each rectangle (in the controller's alignment units; ``native`` and ``shadow`` may be HxW
values, such as RGB565, or HxWxC) is cut without labelling.  Small damage (at most :data:`EXACT_TRIM` of the
panel or :data:`EXACT_PIXELS`) is first cut exactly: cropped to its bounding box with ``np.any`` over each
axis, then cut into bands of identical rows and each band into its runs of changed columns (a square moving
by a few pixels costs only the strips it uncovered and covered).  A change making more than
:data:`MAX_BANDS` such bands (text, glyphs changing), and any larger damage (a diagonal across the screen has
the whole screen as its bounding box), is cut into bands of :data:`BAND_ROWS` rows from the top of each run of
rows holding a change (more rows for a tall change, so that there are at most :data:`MAX_WINDOWS` bands; rows
with no change are in no band), each band into the runs of its changed columns, the
gaps between runs closed where that costs no more than the window it saves, and the cheapest others while
more than :data:`MAX_WINDOWS` windows remain.  A rectangle in which more than :data:`SEND_WHOLE` of its
values changed (a video frame) is sent whole.  Rectangles cut into more than :data:`MAX_WINDOWS` windows in
all are cut again as their bounding box (outside the damage ``native`` equals ``shadow``).
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
            cut = _band_runs(units, max(BAND_ROWS // ay, 1), cost.bytes_per_pixel * ax * ay, cost.window_overhead)
        scale, start, end = np.array(((ax, ay, ax, ay), (a.x0, a.y0, a.x0, a.y0), (a.x1, a.y1, a.x1, a.y1)))
        cut *= scale
        cut += start
        np.minimum(cut, end, out=cut)  # the last units may be cut by the rectangle's edge
        out.extend(map(Rect._make, cut.tolist()))
    if len(out) > MAX_WINDOWS and len(rects) > 1:  # cut as one: rows with no change are in no band
        return trim_damage([bounding(rects)], native, shadow, cost)
    return out


def _units(diff: np.ndarray, ax: int, ay: int) -> np.ndarray:
    """The changed mask per alignment unit (ax x ay pixels; the last ones may be cut by the rectangle's edge)."""
    if ay > 1:
        diff = group_any(diff, ay)
    if ax > 1:
        diff = group_any(diff.T, ax).T
    return diff


def _bands(mask: np.ndarray) -> np.ndarray | None:
    """An exact cover of the True units of ``mask`` by (x0, y0, x1, y1) boxes (an Nx4 array): the bounding box,
    cut into bands of identical rows and each band into its runs; None when that makes more than MAX_BANDS bands."""
    rows_any: np.ndarray = np.any(mask, axis=1)
    cols_any: np.ndarray = np.any(mask, axis=0)
    y0, y1 = int(rows_any.argmax()), rows_any.shape[0] - int(rows_any[::-1].argmax())
    x0, x1 = int(cols_any.argmax()), cols_any.shape[0] - int(cols_any[::-1].argmax())
    box = mask[y0:y1, x0:x1]
    if box.all():
        return np.array([(x0, y0, x1, y1)])
    new = np.ones(box.shape[0] + 1, dtype=bool)  # new[k]: a band starts at row k (and one ends at row k - 1)
    new[1:-1] = (box[1:] != box[:-1]).any(axis=1)
    edges = np.flatnonzero(new)
    if edges.size > MAX_BANDS + 1:
        return None
    bands, run_starts, run_ends = mask_runs(box[edges[:-1]])
    boxes = np.empty((bands.size, 4), dtype=np.intp)
    boxes[:, 0], boxes[:, 2] = run_starts, run_ends
    boxes[:, 1], boxes[:, 3] = edges[bands], edges[bands + 1]
    boxes += (x0, y0, x0, y0)
    return boxes


def _row_bands(mask: np.ndarray, band: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The bands of :func:`_band_runs`: each one's OR-ed columns (a bands x W mask), first row and rows."""
    lit = np.flatnonzero(mask.any(axis=1))
    top, span = int(lit[0]), int(lit[-1]) + 1 - int(lit[0])
    band = max(band, -(-lit.size // MAX_WINDOWS))
    if span == lit.size:  # one run of changed rows
        count = -(-span // band)
        tops = top + band * np.arange(count)
        return group_any(mask[top:top + span], band), tops, np.minimum(top + span - tops, band)
    new_run = np.ones(lit.size, dtype=bool)
    new_run[1:] = lit[1:] != lit[:-1] + 1
    run_top = np.flatnonzero(new_run)
    if run_top.size > MAX_WINDOWS:  # too many runs: one from the first changed row to the last
        lit, run_top = np.arange(top, top + span), run_top[:1]
    run_rows = _lengths(run_top, lit.size)
    while int((-(-run_rows // band)).sum()) > MAX_WINDOWS:
        band += 1
    per_run = -(-run_rows // band)
    from_top = np.arange(lit.size) - np.repeat(run_top, run_rows)
    row_band = np.repeat(np.cumsum(per_run) - per_run, run_rows) + from_top // band
    grouped = np.zeros((int(per_run.sum()), band, mask.shape[1]), dtype=bool)
    grouped[row_band, from_top % band] = mask[lit]
    starts = np.ones(lit.size, dtype=bool)
    np.not_equal(row_band[1:], row_band[:-1], out=starts[1:])
    firsts = np.flatnonzero(starts)
    ored = np.asarray(grouped.any(axis=1))
    return ored, lit[firsts], _lengths(firsts, lit.size)


def _lengths(starts: np.ndarray, end: int) -> np.ndarray:
    """Lengths of the runs starting at ``starts`` (increasing), the last one ending at ``end`` (np.diff with an
    appended ``end``, without its concatenation)."""
    out = np.empty_like(starts)
    np.subtract(starts[1:], starts[:-1], out=out[:-1])
    out[-1] = end - starts[-1]
    return out


def _band_runs(mask: np.ndarray, band: int, unit_bytes: float, window_bytes: int) -> np.ndarray:
    """A cover of the True units of ``mask`` by (x0, y0, x1, y1) boxes (an Nx4 array): each run of rows holding a
    change (all of them one run from the first to the last when there are more than MAX_WINDOWS) cut into bands
    from its top (the last one shorter) of ``band`` rows, or the fewest more that make at most MAX_WINDOWS bands,
    each band into the runs of its changed columns; a gap between two runs of a band is closed when its
    ``unit_bytes`` cost no more than a window's ``window_bytes``, then the cheapest gaps while more than
    MAX_WINDOWS boxes remain."""
    ored, tops, heights = _row_bands(mask, band)
    bands, starts, ends = mask_runs(ored)
    rows = heights[bands]
    gap = (starts[1:] - ends[:-1]) * rows[1:] * float(unit_bytes)
    other = bands[1:] != bands[:-1]
    gap[other] = np.inf  # never closed: a window does not cross bands
    close = gap <= window_bytes
    surplus = gap.size - int(np.count_nonzero(close)) - max(MAX_WINDOWS - 1, int(np.count_nonzero(other)))
    if surplus > 0:
        gap[close] = np.inf
        close[np.argpartition(gap, surplus - 1)[:surplus]] = True
    split = np.ones(starts.size + 1, dtype=bool)  # split[k]: a box starts at run k and ends at run k - 1
    np.logical_not(close, out=split[1:-1])
    begin, end = np.flatnonzero(split[:-1]), np.flatnonzero(split[1:])
    boxes = np.empty((begin.size, 4), dtype=np.intp)
    boxes[:, 0], boxes[:, 2] = starts[begin], ends[end]
    boxes[:, 1] = tops[bands[begin]]
    boxes[:, 3] = boxes[:, 1] + rows[begin]
    return boxes

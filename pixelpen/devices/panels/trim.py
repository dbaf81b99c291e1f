"""Damage trimming: a frame's damaged rectangles shrunk to what differs from the shadow of the sent frame.

Small damage (at most :data:`EXACT_TRIM` of the panel or :data:`EXACT_PIXELS`) is cut exactly, without
labelling: the changed mask of each rectangle (in the controller's alignment units) is cropped to its
bounding box with ``np.any`` over each axis, then cut into bands of identical rows and each band into its
runs of changed columns (a square moving by a few pixels costs only the strips it uncovered and covered).
Larger damage (a diagonal across the screen has the whole screen as its bounding box) is cut to the
changed tiles of :data:`TRIM_TILE` pixels, which bounds the planning cost.  A small rectangle whose change
makes more than :data:`MAX_BANDS` bands (text) is cut by ``raster.damage.tile_damage`` at the controller's
alignment instead.  A rectangle in which more than :data:`SEND_WHOLE` of its values changed (a video
frame) is sent whole.
"""

from __future__ import annotations

import numpy as np

from pixelpen.devices.panels.windows import WindowCost
from pixelpen.raster.damage import Rect, bounding, mask_damage, pixel_mask

EXACT_TRIM = 1 / 16
"""Damage of at most this share of the panel is cut exactly (bands of identical rows, runs of columns)."""
EXACT_PIXELS = 2048
"""...or of at most this many pixels (a cursor on a 128x64 OLED): small panels are cut exactly too."""
TRIM_TILE = 8
"""Side of the tiles larger damage is cut to (rounded up to the controller's alignment)."""
SEND_WHOLE = 0.5
"""A damaged rectangle in which more than this share of the values changed is sent whole (a video frame)."""
MAX_BANDS = 8
"""Bands of identical rows a cut by bands makes at most; a more ragged change goes to ``tile_damage``."""


def trim_damage(rects: list[Rect], native: np.ndarray, shadow: np.ndarray, cost: WindowCost) -> list[Rect]:
    """The parts of ``rects`` (window space) where ``native`` differs from ``shadow``, aligned to ``cost.align``."""
    height, width = native.shape[:2]
    ax, ay = cost.align
    exact = sum(r.area for r in rects) <= max(EXACT_TRIM * width * height, EXACT_PIXELS)
    if not exact:
        ax, ay = -(-TRIM_TILE // ax) * ax, -(-TRIM_TILE // ay) * ay
    elif len(rects) > 1:
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
        cut = _bands(_units(mask, ax, ay)) if exact else None
        if cut is None:
            found = mask_damage(mask, (ax, ay), cost.window_bytes, cost.bytes_per_pixel)
            out.extend(Rect(a.x0 + f.x0, a.y0 + f.y0, min(a.x0 + f.x1, width), min(a.y0 + f.y1, height))
                       for f in found)
            continue
        out.extend(Rect(min(a.x0 + x0 * ax, a.x1), min(a.y0 + y0 * ay, a.y1), min(a.x0 + x1 * ax, a.x1),
                        min(a.y0 + y1 * ay, a.y1)) for x0, y0, x1, y1 in cut)
    return out


def _units(diff: np.ndarray, ax: int, ay: int) -> np.ndarray:
    """The changed mask per alignment unit (ax x ay pixels; the last ones may be cut by the rectangle's edge)."""
    if ay > 1:
        diff = np.logical_or.reduceat(diff, np.arange(0, diff.shape[0], ay), axis=0)
    if ax > 1:
        diff = np.logical_or.reduceat(diff, np.arange(0, diff.shape[1], ax), axis=1)
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
    padded = np.zeros((len(starts), box.shape[1] + 2), dtype=np.int8)
    padded[:, 1:-1] = box[starts]
    edges = np.diff(padded, axis=1)
    bands, run_starts = np.nonzero(edges == 1)
    run_ends = np.nonzero(edges == -1)[1]
    return [(x0 + s, y0 + starts[k], x0 + e, y0 + ends[k])
            for k, s, e in zip(bands.tolist(), run_starts.tolist(), run_ends.tolist(), strict=True)]

"""Damage tracking: the rectangles of a canvas that changed, merged by a bytes-on-the-wire cost model.

Rectangles are half-open, like numpy slices and ``pixelpen.raster.formats.Region``: ``Rect(x0, y0, x1, y1)``
covers columns ``x0 .. x1 − 1`` and rows ``y0 .. y1 − 1``.  Panels address inclusive column/page windows
(CASET/RASET, SSD1306 pages; panels.md §5): use :meth:`Rect.inclusive` and :meth:`Rect.aligned`.

Cost model: sending a rectangle costs its pixels' bytes plus a per-window overhead ``merge_cost`` (window
commands, transfer setup).  Two rectangles are merged when sending their bounding union costs no more
than sending both: ``(area(union) − area(a) − area(b))·bytes_per_pixel <= merge_cost``.  Overlapping and
contained rectangles therefore always merge; distant small ones stay apart.  Merging is greedy, cheapest
pair first, until no pair qualifies.
"""

from __future__ import annotations

import heapq
from collections.abc import Iterable
from typing import NamedTuple

import numpy as np

from pixelpen.errors import ConfigError

DEFAULT_MERGE_COST = 128.0
"""Default per-window overhead in bytes: a CASET/RASET/RAMWR window (11 bytes) plus bus turnaround."""

FEW_RECTS = 12
"""Up to this many rectangles are merged in plain Python (a few, as a frame's damage usually is)."""

_MAX_PENDING = 64
"""Rectangles a tracker keeps before compacting them (cheapest merges first) to half as many."""


class Rect(NamedTuple):
    """A half-open pixel rectangle: columns x0..x1−1, rows y0..y1−1."""

    x0: int
    y0: int
    x1: int
    y1: int

    @property
    def width(self) -> int:
        """Columns covered."""
        return self.x1 - self.x0

    @property
    def height(self) -> int:
        """Rows covered."""
        return self.y1 - self.y0

    @property
    def area(self) -> int:
        """Pixels covered."""
        x0, y0, x1, y1 = self
        return (x1 - x0) * (y1 - y0) if x1 > x0 and y1 > y0 else 0

    @property
    def slices(self) -> tuple[slice, slice]:
        """(rows, columns) slices selecting the rectangle from an HxW array."""
        return slice(self.y0, self.y1), slice(self.x0, self.x1)

    def inclusive(self) -> tuple[int, int, int, int]:
        """(x_first, y_first, x_last, y_last): the inclusive window a panel's CASET/RASET take."""
        return self.x0, self.y0, self.x1 - 1, self.y1 - 1

    def union(self, other: Rect) -> Rect:
        """The bounding rectangle of both."""
        return Rect(min(self.x0, other.x0), min(self.y0, other.y0), max(self.x1, other.x1), max(self.y1, other.y1))

    def aligned(self, x_multiple: int, y_multiple: int, width: int, height: int) -> Rect:
        """Grown outwards to multiples (e.g. 8 rows for SSD1306 pages), clipped to width x height."""
        if x_multiple < 1 or y_multiple < 1:
            raise ConfigError(f"alignment multiples must be >= 1, found {x_multiple}, {y_multiple}")
        return Rect(
            self.x0 - self.x0 % x_multiple,
            self.y0 - self.y0 % y_multiple,
            min(-(-self.x1 // x_multiple) * x_multiple, width),
            min(-(-self.y1 // y_multiple) * y_multiple, height),
        )


def bounding(rects: Iterable[Rect]) -> Rect:
    """The bounding rectangle of one or more rectangles."""
    x0, y0, x1, y1 = zip(*rects, strict=True)
    return Rect(min(x0), min(y0), max(x1), max(y1))


def merge_rects(
    rects: Iterable[Rect], merge_cost: float, bytes_per_pixel: float, max_count: int | None = None
) -> list[Rect]:
    """Greedy cost-model merge (cheapest pair first) while a merge saves bytes or more than max_count remain.

    Up to :data:`FEW_RECTS` rectangles are merged in plain Python (numpy's per-call overhead dominates
    there), more with one vectorised pairwise matrix per step; both pick the same pair (the first minimum
    in row-major order)."""
    boxes = [tuple(r) for r in rects if r.area > 0]
    if len(boxes) <= FEW_RECTS:
        return _merge_few(boxes, merge_cost, bytes_per_pixel, max_count)
    return _merge_many(np.array(boxes, dtype=np.int64).reshape(-1, 4), merge_cost, bytes_per_pixel, max_count)


def _merge_few(
    rects: list[tuple[int, ...]], merge_cost: float, bytes_per_pixel: float, max_count: int | None
) -> list[Rect]:
    """:func:`merge_rects` for a few (x0, y0, x1, y1) boxes in plain Python: every pair's cost once in a heap,
    then only the merged box's pairs.  Boxes are numbered in list order and a merged box gets the next
    number, so the heap's (cost, first, second) order is the row-major first minimum of the matrix path."""
    bpp = float(bytes_per_pixel)
    boxes = {k: (x0, y0, x1, y1, (x1 - x0) * (y1 - y0)) for k, (x0, y0, x1, y1) in enumerate(rects)}
    heap = [(_extra(boxes[i], boxes[j], bpp), i, j) for i in boxes for j in boxes if i < j]
    heapq.heapify(heap)
    next_id = len(boxes)
    while len(boxes) > 1:
        extra, i, j = heap[0]
        if i not in boxes or j not in boxes:
            heapq.heappop(heap)
            continue
        if extra > merge_cost and (max_count is None or len(boxes) <= max_count):
            break
        heapq.heappop(heap)
        (ax0, ay0, ax1, ay1, _), (bx0, by0, bx1, by1, _) = boxes.pop(i), boxes.pop(j)
        ux0, uy0, ux1, uy1 = min(ax0, bx0), min(ay0, by0), max(ax1, bx1), max(ay1, by1)
        merged = (ux0, uy0, ux1, uy1, (ux1 - ux0) * (uy1 - uy0))
        for k, box in boxes.items():
            heapq.heappush(heap, (_extra(box, merged, bpp), k, next_id))
        boxes[next_id] = merged
        next_id += 1
    return sorted(Rect(x0, y0, x1, y1) for x0, y0, x1, y1, _ in boxes.values())


def _extra(a: tuple[int, ...], b: tuple[int, ...], bytes_per_pixel: float) -> float:
    """Bytes merging two (x0, y0, x1, y1, area) boxes adds: their union's area minus both areas."""
    union = (max(a[2], b[2]) - min(a[0], b[0])) * (max(a[3], b[3]) - min(a[1], b[1]))
    return (union - a[4] - b[4]) * bytes_per_pixel


def _merge_many(boxes: np.ndarray, merge_cost: float, bytes_per_pixel: float, max_count: int | None) -> list[Rect]:
    """:func:`merge_rects` for an Nx4 int64 array of boxes, one pairwise cost matrix per merge."""
    while boxes.shape[0] > 1:
        x0, y0, x1, y1 = boxes.T
        area = (x1 - x0) * (y1 - y0)
        ux0 = np.minimum(x0[:, None], x0[None, :])
        uy0 = np.minimum(y0[:, None], y0[None, :])
        ux1 = np.maximum(x1[:, None], x1[None, :])
        uy1 = np.maximum(y1[:, None], y1[None, :])
        extra = ((ux1 - ux0) * (uy1 - uy0) - area[:, None] - area[None, :]) * float(bytes_per_pixel)
        np.fill_diagonal(extra, np.inf)
        best = int(np.argmin(extra))
        i, j = divmod(best, boxes.shape[0])
        if extra[i, j] > merge_cost and (max_count is None or boxes.shape[0] <= max_count):
            break
        merged = [ux0[i, j], uy0[i, j], ux1[i, j], uy1[i, j]]
        boxes = np.vstack([np.delete(boxes, [i, j], axis=0), merged])
    return sorted(Rect(*b) for b in boxes.tolist())


class DamageTracker:
    """Collects the bounding boxes of drawing operations on a width x height canvas."""

    def __init__(
        self, width: int, height: int, merge_cost: float = DEFAULT_MERGE_COST, bytes_per_pixel: float = 1.0
    ) -> None:
        if not (isinstance(merge_cost, (int, float)) and merge_cost >= 0):
            raise ConfigError(f"merge_cost must be a number of bytes >= 0, found {merge_cost!r}")
        if not (isinstance(bytes_per_pixel, (int, float)) and bytes_per_pixel > 0):
            raise ConfigError(f"bytes_per_pixel must be > 0, found {bytes_per_pixel!r}")
        self.width = width
        self.height = height
        self.merge_cost = float(merge_cost)
        self.bytes_per_pixel = float(bytes_per_pixel)
        self._rects: list[Rect] = []

    def add(self, x0: int, y0: int, x1: int, y1: int) -> None:
        """Record a changed half-open box (clipped to the canvas; empty boxes are ignored)."""
        r = Rect(max(int(x0), 0), max(int(y0), 0), min(int(x1), self.width), min(int(y1), self.height))
        if r.area == 0:
            return
        self._rects.append(r)
        if len(self._rects) > _MAX_PENDING:
            self._rects = merge_rects(self._rects, self.merge_cost, self.bytes_per_pixel, _MAX_PENDING // 2)

    def add_all(self) -> None:
        """Record the whole canvas as changed."""
        self._rects = [Rect(0, 0, self.width, self.height)]

    def rects(self, merge_cost: float | None = None) -> list[Rect]:
        """The changed rectangles since the last clear, merged by the cost model."""
        cost = self.merge_cost if merge_cost is None else float(merge_cost)
        return merge_rects(self._rects, cost, self.bytes_per_pixel)

    def clear(self) -> None:
        """Forget all recorded damage."""
        self._rects = []

    def copy(self) -> DamageTracker:
        """An independent tracker with the same settings and damage."""
        other = DamageTracker(self.width, self.height, self.merge_cost, self.bytes_per_pixel)
        other._rects = list(self._rects)
        return other


def changed_pixels(current: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """The HxW mask of pixels where two HxW or HxWxC frames differ (in any channel)."""
    return pixel_mask(current != previous)


def pixel_mask(diff: np.ndarray) -> np.ndarray:
    """An HxWxC per-value mask as HxW, true where any channel is (one OR per channel: ``any(axis=2)`` over
    a short last axis is ten times slower); an HxW mask as it is."""
    if diff.ndim != 3:
        return diff
    mask = diff[..., 0].copy()
    for channel in range(1, diff.shape[2]):
        mask |= diff[..., channel]
    return mask


def _tile_size(tile: int | tuple[int, int]) -> tuple[int, int]:
    """(tile width, tile height) from an int or a pair, or ConfigError."""
    tw, th = (tile, tile) if isinstance(tile, (int, np.integer)) else tuple(tile)
    if int(tw) < 1 or int(th) < 1:
        raise ConfigError(f"tile size must be >= 1, found {tile!r}")
    return int(tw), int(th)


def tile_damage(
    current: np.ndarray,
    previous: np.ndarray,
    tile: int | tuple[int, int] = 16,
    merge_cost: float = DEFAULT_MERGE_COST,
    bytes_per_pixel: float = 1.0,
) -> list[Rect]:
    """Tile-aligned rectangles (clipped to the frame) covering every pixel where the two frames differ.

    Vectorised: one comparison, :func:`group_any` over tile rows and columns, then runs of changed tiles per
    tile row, merged by the cost model.
    """
    if current.shape != previous.shape or current.dtype != previous.dtype:
        raise ConfigError(
            f"previous frame is {previous.shape} {previous.dtype}, the canvas is {current.shape} {current.dtype}"
        )
    return mask_damage(changed_pixels(current, previous), tile, merge_cost, bytes_per_pixel)


def mask_damage(
    mask: np.ndarray,
    tile: int | tuple[int, int] = 16,
    merge_cost: float = DEFAULT_MERGE_COST,
    bytes_per_pixel: float = 1.0,
) -> list[Rect]:
    """:func:`tile_damage` of an HxW mask of changed pixels already computed (``changed_pixels``)."""
    tw, th = _tile_size(tile)
    height, width = mask.shape[:2]
    changed = group_any(group_any(mask, th).T, tw).T
    return merge_rects(_tile_runs(changed, tw, th, width, height), merge_cost, bytes_per_pixel, _MAX_PENDING)


def _tile_runs(changed: np.ndarray, tw: int, th: int, width: int, height: int) -> list[Rect]:
    """Rectangles of changed tiles: horizontal runs per tile row, stacked where consecutive rows repeat them.

    When that still leaves more than _MAX_PENDING rectangles, each tile row is first reduced to the run
    from its first to its last changed tile.
    """
    rows, starts, ends = mask_runs(changed)
    if rows.size > _MAX_PENDING:
        rows, starts, ends = mask_runs(
            np.maximum.accumulate(changed, axis=1) & np.maximum.accumulate(changed[:, ::-1], axis=1)[:, ::-1]
        )
    order = np.lexsort((rows, ends, starts))
    rows, starts, ends = rows[order], starts[order], ends[order]
    new = np.ones(rows.shape[0], dtype=bool)
    new[1:] = (starts[1:] != starts[:-1]) | (ends[1:] != ends[:-1]) | (rows[1:] != rows[:-1] + 1)
    group = np.cumsum(new) - 1
    first = rows[new]
    last = np.zeros_like(first)
    last[group] = rows
    return [
        Rect(int(a) * tw, int(r0) * th, min(int(b) * tw, width), min((int(r1) + 1) * th, height))
        for a, b, r0, r1 in zip(starts[new], ends[new], first, last, strict=False)
    ]


def group_any(mask: np.ndarray, k: int) -> np.ndarray:
    """Each group of ``k`` rows of a 2-D mask OR-ed into one (the last group may be shorter): a reshape, ten
    times quicker than ``logical_or.reduceat``."""
    whole = mask.shape[0] // k * k
    out = np.asarray(mask[:whole].reshape(whole // k, k, mask.shape[1]).any(axis=1))
    if whole < mask.shape[0]:
        out = np.concatenate([out, mask[whole:].any(axis=0, keepdims=True)])
    return out


def mask_runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(row, first column, end column) of every run of True in a 2-D mask, in row-major order: the rows laid
    end to end with a False between them, so every run starts and ends at a change of the flat array."""
    height, width = mask.shape
    flat = np.zeros(height * (width + 1) + 1, dtype=np.bool_)
    flat[1:].reshape(height, width + 1)[:, :width] = mask
    rows, cols = np.divmod(np.flatnonzero(flat[1:] != flat[:-1]), width + 1)
    return rows[0::2], cols[0::2], cols[1::2]

"""Hardware vertical scrolling: a frame that is the last one shifted by some rows becomes a scroll plus its new rows.

The controller's memory rows under the glass are a ring (MIPI DCS VSCRDEF 33h: the top fixed area TFA, the
scroll area VSA = the frame's rows, the bottom fixed area BFA, TFA + VSA + BFA = the memory's rows; VSCSAD 37h:
the memory row shown at the scroll area's first line, ST7789VW §8.14 and ILI9341 §8.2.33/8.2.38, each parameter
16-bit big-endian).  Frame row ``y`` is kept at ring row ``(y + offset) % rows``.  Before a frame is converted
into the wire's units its rows are hashed (equal rows always hash equal) and matched against the last frame's: the
shift ``d`` its unique rows vote for (the last shift first), when it at least halves the rows that differ, advances
``offset`` by ``d`` and rolls the shadow (the kept units, equal to it, become a copy of the rolled shadow); then
the rows that differ from the last frame rolled (compared exactly, with a copy of that frame) are the frame's
damage, converted and trimmed against the rolled shadow, so only the rows that came into view and any other
change are sent (a frame that merely resembles a shift is still sent right).  Every later
window is mapped through ``offset`` and split where it wraps the ring.  A full frame puts the ring back at
offset 0 (VSCRDEF and VSCSAD at the area's top) when the controller may be scrolled: after a scroll, or
when a scroll's commands may not have arrived (a bus fault).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pixelpen.profiles.panel import InitStep
from pixelpen.raster.damage import Rect, bounding

VSCRDEF, VSCSAD = 0x33, 0x37
START_LINE = 0x40
"""SSD1306 family: display start line 40h | line (the RAM row shown on COM0, SSD1306 §10.1.6)."""
MIN_DAMAGE = 0.25
"""A frame is checked for a shift only when its damage's bounding box spans the frame's width and at least
this share of its area (a cursor or a clock never pays for the row hashes)."""
MAX_SKIP = 8
"""After a frame checked in vain, the next frames are not checked: 1, 2, 4 ... up to this many (video frames pay for
the row hashes one frame in a few; a steady scroll is found again within that many frames)."""
MAX_WEIGHT = 1 << 20
"""Row hash weights are integers below this: a row of at most 4096 x 4 values below 2**16 sums below 2**53, so
the float64 dot product is exact in any summation order (equal rows always hash equal)."""


@dataclass(frozen=True)
class ScrollArea:
    """The ring of memory rows under a frame: TFA, VSA (the frame's rows) and BFA, and the rows' direction."""

    top: int
    rows: int
    bottom: int
    reversed: bool = False
    """Frame rows run up the memory (MADCTL MY): the ring turns the other way."""
    start_line: bool = False
    """Scrolled by the display start line (SSD1306 family) instead of VSCRDEF/VSCSAD: the window space is then
    the RAM's rows (:meth:`HardwareScroll.to_ram`), as the RAM is written in whole pages."""

    def start(self, offset: int) -> int:
        """VSCSAD's parameter (the memory row shown at the area's first line) that keeps frame rows at ``offset``."""
        return self.top + (-offset if self.reversed else offset) % self.rows

    def steps(self, offset: int) -> list[InitStep]:
        """VSCRDEF for this area and VSCSAD for ``offset`` (a start-line area: 40h | start line alone)."""
        if self.start_line:
            return [InitStep(START_LINE | self.start(offset))]
        return [InitStep(VSCRDEF, b"".join(v.to_bytes(2, "big") for v in (self.top, self.rows, self.bottom))),
                InitStep(VSCSAD, self.start(offset).to_bytes(2, "big"))]


def mipi_scroll_area(memory_rows: int, row_offset: int, rows: int, *, reversed: bool) -> ScrollArea:
    """The area of a frame of ``rows`` rows written at RASET ``row_offset`` (MY set: counted from the bottom)."""
    top = memory_rows - row_offset - rows if reversed else row_offset
    return ScrollArea(top, rows, memory_rows - top - rows, reversed)


@functools.lru_cache(maxsize=8)
def _weights(length: int) -> np.ndarray:
    """Fixed random integer weights (as float64) for row hashes of ``length`` values."""
    return np.random.default_rng(length).integers(1, MAX_WEIGHT, length).astype(np.float64)


def frame_rows(frame: np.ndarray) -> np.ndarray:
    """A contiguous frame (HxW or HxWxC) as H rows of 16-bit words (bytes when a row's size is odd)."""
    rows = np.ascontiguousarray(frame).reshape(frame.shape[0], -1)
    if rows.dtype.itemsize == 1 and rows.shape[1] % 2 == 0:
        return rows.view(np.uint16)
    return rows


def row_hashes(rows: np.ndarray) -> np.ndarray:
    """One float64 per row of :func:`frame_rows` (values below 2**16): equal rows give equal hashes."""
    return rows @ _weights(rows.shape[1])


def shift_pays(new: np.ndarray, old: np.ndarray, d: int) -> bool:
    """True when rolling by ``d`` at least halves the rows whose hashes differ (``new[y]`` against ``old[y + d]``)."""
    height = len(old)
    kept = np.count_nonzero(new[:height - d] == old[d:]) + np.count_nonzero(new[height - d:] == old[:d])
    return bool(2 * (height - kept) <= height - np.count_nonzero(new == old))


def best_shift(new: np.ndarray, old: np.ndarray, hint: int = 0) -> int:
    """The roll ``d`` (1..H-1) for which ``new[y] == old[(y + d) % H]`` holds for the most rows, by the row hashes
    ``new`` and ``old``, when it pays (:func:`shift_pays`); else 0.  A ``hint`` (the last scroll's) that pays is
    taken without the search."""
    if hint and shift_pays(new, old, hint):
        return hint
    height = len(old)
    order = np.argsort(old)
    ranked = old[order]
    unique = np.ones(height, dtype=bool)  # a new row equal to exactly one old row votes for its shift
    unique[1:] = ranked[1:] != ranked[:-1]
    unique[:-1] &= unique[1:]
    at = np.minimum(np.searchsorted(ranked, new), height - 1)
    anchor = np.flatnonzero((ranked[at] == new) & unique[at])
    if not anchor.size:
        return 0
    votes = np.bincount((order[at[anchor]] - anchor) % height, minlength=height)
    votes[0] = 0
    d = int(votes.argmax())
    if votes[d] == 0:
        return 0
    return d if shift_pays(new, old, d) else 0


def changed_rows(new: np.ndarray, old: np.ndarray, d: int) -> np.ndarray:
    """Which rows ``y`` of ``new`` differ from ``old[(y + d) % H]`` (both :func:`frame_rows`), compared exactly."""
    height = len(old)
    changed = np.empty(height, dtype=bool)
    np.any(new[:height - d] != old[d:], axis=1, out=changed[:height - d])
    np.any(new[height - d:] != old[:d], axis=1, out=changed[height - d:])
    return changed


def row_bands(changed: np.ndarray, width: int) -> list[Rect]:
    """Full-width Rects of the runs of True in ``changed`` (one flag per row)."""
    padded = np.zeros(changed.size + 2, dtype=bool)
    padded[1:-1] = changed
    edges = np.flatnonzero(padded[1:] != padded[:-1]).tolist()
    return [Rect(0, y0, width, y1) for y0, y1 in zip(edges[0::2], edges[1::2], strict=True)]


class HardwareScroll:
    """A display's scroll state: the area of the current rotation, the ring offset, the commands still to send."""

    def __init__(self, send: Callable[[InitStep], None]) -> None:
        self._send = send
        self.enabled = True
        self.default: ScrollArea | None = None
        """The controller's reset area (the whole memory, no fixed areas): offset 0 under it is no scroll."""
        self.area: ScrollArea | None = None
        """The ring of the current rotation (None: the frame's rows are not memory rows, so no scroll)."""
        self.offset = 0
        self._pending = False
        self._unsure = False
        self._defined = False
        self._candidate: tuple[np.ndarray, np.ndarray] | None = None
        """The rows (:func:`frame_rows`) and row hashes of the frame being sent, checked for a shift."""
        self._previous: tuple[np.ndarray, np.ndarray] | None = None
        """The same of the last frame that reached the bus (so the shadow holds it)."""
        self._last = 0
        """The last shift found (tried first: a scroll goes on at one speed)."""
        self._skip = self._backoff = 0
        """Frames not to check for a shift, and how many were skipped after the last check in vain."""

    @property
    def pending(self) -> bool:
        """True when a scroll was decided and its commands are still to be sent."""
        return self._pending

    def set_area(self, area: ScrollArea | None) -> None:
        """The ring of a new rotation (or after a reset); the next full frame puts the controller back at 0."""
        self.area = area
        self._candidate = self._previous = None
        self._defined = False
        self._skip = self._backoff = 0

    def detect(self, native: np.ndarray, damage: list[Rect], shadow: np.ndarray,
               units: np.ndarray | None) -> list[Rect]:
        """The damage of a frame ``native`` (window space), before it is converted into ``units`` (the display's
        kept conversion, equal to ``shadow``; None when ``native`` is its own units): ``damage`` as it is, or when
        ``native`` is the frame before rolled by ``d`` rows, the bands of rows that differ from that roll, with
        ``shadow`` (and ``units``) rolled in place and the offset advanced."""
        height, width = shadow.shape[:2]
        previous, self._previous, self._candidate = self._previous, None, None
        area = self.area
        if self._pending and area is not None:  # a scroll decided in a frame that never reached the bus
            return [Rect(0, 0, width, height)]
        box = bounding(damage) if damage else None
        if (not self.enabled or area is None or area.rows != height or box is None or box.x0 > 0
                or box.x1 < width or box.area < MIN_DAMAGE * width * height):
            return damage
        if self._skip:
            self._skip -= 1
            return damage
        rows = frame_rows(native)
        new = row_hashes(rows)
        self._candidate = (rows.copy() if np.may_share_memory(rows, native) else rows), new  # (a rotation's copy)
        if previous is None or previous[0].shape != rows.shape:
            return damage
        d = self._last = best_shift(new, previous[1], self._last)
        self._backoff = 0 if d else min(2 * self._backoff or 1, MAX_SKIP)
        self._skip = self._backoff
        if not d:
            return damage
        changed = changed_rows(rows, previous[0], d)
        if not area.start_line:  # (a start-line controller's shadow is in RAM rows, which stay where they are)
            rolled = np.roll(shadow, -d, axis=0)
            shadow[:] = rolled
            if units is not None:  # the kept units equal the shadow: every changed unit was sent
                units[:] = rolled
        self.offset = (self.offset + d) % height
        self._pending = True
        return row_bands(changed, width)

    def start_frame(self, full: bool) -> None:
        """Send what must precede the frame's windows: a scroll decided, or on a full frame the way back to 0."""
        self._previous, self._candidate = (None if full else self._candidate), None
        if full:
            self._pending = self._defined = False
            back = self.area or self.default
            if back is None or not (self.offset or self._unsure):
                return
            self.offset = 0
            steps = back.steps(0)
        elif self._pending and self.area is not None:
            steps = self.area.steps(self.offset)
            steps = steps[-1:] if self._defined else steps  # VSCRDEF once
        else:
            return
        self._unsure = True  # until every command is out
        for step in steps:
            self._send(step)
        self._unsure = self._pending = False
        self._defined = not full

    def to_ram(self, native: np.ndarray, damage: list[Rect]) -> tuple[np.ndarray, list[Rect]]:
        """A frame and its damage in RAM rows on a start-line controller (frame row ``y`` at RAM row ``(y +
        offset) % rows``, a rectangle that wraps split in two); as they are elsewhere or at offset 0."""
        if self.area is None or not self.area.start_line or not self.offset:
            return native, damage
        ram = [Rect(x0, r0, x1, r1) for x0, y0, x1, y1 in damage for r0, r1 in self.rows(y0, y1)]
        rolled = np.empty_like(native)
        rolled[self.offset:], rolled[:self.offset] = native[:-self.offset], native[-self.offset:]
        return rolled, ram

    def rows(self, y0: int, y1: int) -> list[tuple[int, int]]:
        """Frame rows ``y0..y1`` (half-open) as ring rows: one range, or two where they wrap."""
        if not self.offset or self.area is None:
            return [(y0, y1)]
        n = self.area.rows
        start = (y0 + self.offset) % n
        if start + y1 - y0 <= n:
            return [(start, start + y1 - y0)]
        return [(start, n), (0, start + y1 - y0 - n)]

"""A MIPI-DCS controller's frame memory: the CASET/RASET window, the address counters and the MADCTL mapping.

The column counter c runs over XS..XE (CASET), the row counter p over YS..YE (RASET), c first. A pixel goes
to ``(col, row) = (p, c) if MV else (c, p)``, then ``col = cols-1-col`` if MX and ``row = rows-1-row`` if MY
(ST7789VW §8.12 and Fig. 33, ILI9341 §8.2.29, ST7735 §9.8.3). Addresses past the memory are ignored
("data of out of range will be ignored", CASET/RASET restrictions). After the window's last pixel both
counters return to (XS, YS) (the §8.12 counter table; the WRMEMC page says extra pixels are ignored
instead — the counter table is taken, and the overrun reported). RAMWR starts at (XS, YS); WRMEMC goes on
from the pixel after the last one written.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pixelpen.sim.panels.dcs_pixels import Pixels

MY, MX, MV = 0x80, 0x40, 0x20
"""MADCTL bits D7..D5: row and column order, row/column exchange (the others do not move the address)."""


@dataclass(frozen=True)
class WriteResult:
    """What one write did: pixels stored, pixels that fell outside the memory, and whether the window wrapped."""

    stored: int
    outside: int
    wrapped: bool


class FrameMemory:
    """``rows`` x ``cols`` pixels of three 6-bit components, written through the window and MADCTL."""

    def __init__(self, cols: int, rows: int, *, seed: int = 0) -> None:
        self.cols = cols
        self.rows = rows
        self.ram: NDArray[np.uint8] = np.random.default_rng(seed).integers(0, 64, (rows, cols, 3), dtype=np.uint8)
        """[row, col, component] 6-bit values; power-on contents are random (datasheet), here seeded noise."""
        self.madctl = 0
        self.xs, self.xe, self.ys, self.ye = 0, cols - 1, 0, rows - 1
        self.next_pixel = 0
        """Index in the window of the next pixel a write stores (0 after RAMWR)."""

    def reset_window(self) -> None:
        """The reset values of CASET/RASET: the whole memory in the current MV orientation."""
        across, down = self.logical_size()
        self.xs, self.xe, self.ys, self.ye = 0, across - 1, 0, down - 1

    def logical_size(self) -> tuple[int, int]:
        """The memory's size in counter coordinates (c, p): (cols, rows), exchanged when MV is set."""
        return (self.rows, self.cols) if self.madctl & MV else (self.cols, self.rows)

    def window_pixels(self) -> int:
        """Pixels in the window (0 when a start address is past its end address)."""
        return max(0, self.xe - self.xs + 1) * max(0, self.ye - self.ys + 1)

    def window_outside(self) -> bool:
        """True when part of the window lies past the memory in the current MV orientation."""
        across, down = self.logical_size()
        return self.xe >= across or self.ye >= down

    def addresses(self, first: int, count: int) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.bool_]]:
        """RAM (row, col) of window pixels first..first+count-1 (taken modulo the window), and which are inside."""
        width = max(0, self.xe - self.xs + 1)
        total = self.window_pixels()
        k = (first + np.arange(count, dtype=np.intp)) % total
        c = self.xs + k % width
        p = self.ys + k // width
        col, row = (p, c) if self.madctl & MV else (c, p)
        inside = (col < self.cols) & (row < self.rows)
        if self.madctl & MX:
            col = self.cols - 1 - col
        if self.madctl & MY:
            row = self.rows - 1 - row
        return row, col, inside

    def write(self, pixels: Pixels) -> WriteResult:
        """Store ``pixels`` from the counter on; the counter moves on (and wraps at the window's end)."""
        total = self.window_pixels()
        n = len(pixels)
        if n == 0 or total == 0:
            return WriteResult(0, n if total == 0 else 0, False)
        wrapped = self.next_pixel + n > total
        skip = max(0, n - total)  # a chunk longer than the window: only its last ``total`` pixels stay
        first = (self.next_pixel + skip) % total
        row, col, inside = self.addresses(first, n - skip)
        self.ram[row[inside], col[inside]] = pixels[skip:][inside]
        self.next_pixel = (self.next_pixel + n) % total
        stored = int(np.count_nonzero(inside))
        return WriteResult(stored, n - skip - stored, wrapped)

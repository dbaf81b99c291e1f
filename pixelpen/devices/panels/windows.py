"""Refresh windows: damage rectangles -> the controller windows that put the fewest bytes on the wire.

The cost model lives here and nowhere else.  A window costs its pixel bytes plus the commands that open it
(MIPI DCS: CASET 2Ah + 4, RASET 2Bh + 4, RAMWR 2Ch = 11 bytes; SSD1306 horizontal mode: ``21 s e 22 s e``
= 6; SH1106 page mode: ``B0+p, 0x0L, 0x1H`` = 3 per page), plus framing per transfer on I2C (the control byte
0x00 before commands and 0x40 before each data chunk).  Bytes are what the host sends (a bus's ``bytes_sent``);
an I2C transaction's START, address byte and STOP are wire time, counted per transfer by
:mod:`pixelpen.devices.panels.pacing`.  :func:`plan_windows` rounds every rectangle
outward to the controller's alignment (SSD1306: pages of 8 rows), clips it to the panel, then merges by
cost with :func:`pixelpen.raster.damage.merge_rects`: two windows become their bounding window when that
costs no more; more than ``max_windows`` are merged cheapest-first until they fit.

A display sends ``trim.trim_damage``'s cut (already made by this cost model) through
:meth:`WindowCost.cut_or_bounding` when it has at most ``windows.MAX_WINDOWS`` windows, and plans more.

Guarantees: every damaged pixel is in a window; every window is aligned (up to the panel's edge) and
inside the panel; at most ``max_windows``; the plan costs no more than one bounding window and, when the
aligned rectangles already fit ``max_windows``, no more than sending them unmerged.  Windows may overlap
(two crossing bars cost less than their bounding box): the overlap is sent twice with the same pixels.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

from pixelpen.errors import ConfigError
from pixelpen.profiles.panel import BYTES_PER_PIXEL, OLED_CONTROLLERS
from pixelpen.raster.damage import FEW_RECTS, Rect, bounding, merge_rects

MIPI_WINDOW_BYTES = 11
"""CASET 2Ah + 4 parameter bytes, RASET 2Bh + 4, RAMWR 2Ch."""
SSD1306_WINDOW_BYTES = 6
"""``21 s e 22 s e``: column and page window (horizontal addressing mode)."""
SH1106_PAGE_BYTES = 3
"""``B0+page``, column low nibble ``0x0L``, column high nibble ``0x1H``: one page of a page-mode window."""
MAX_WINDOWS = 32
"""Windows a frame is sent in at most, by default: trim cuts a ragged change into no more, the planner merges to it."""
MAX_RECTS = 64
"""Rectangles planned one by one; more are sent as their bounding window (merging is quadratic per step)."""
_BAND_GAP = 1 << 24
"""Rows put between bands while merging, so that no merge across bands is ever the cheaper one."""

__all__ = ["MAX_RECTS", "PlanCost", "WindowCost", "plan_windows", "window_cost"]


class PlanCost(NamedTuple):
    """Bytes on the wire (commands, pixels, I2C control bytes), transfers (SPI frames or I2C transactions)."""

    bytes: int
    transfers: int


def _bands(rect: Rect, band_rows: int | None) -> list[Rect]:
    """``rect`` cut at every multiple of ``band_rows`` (itself when there are no bands)."""
    if band_rows is None:
        return [rect]
    edges = [rect.y0, *range((rect.y0 // band_rows + 1) * band_rows, rect.y1, band_rows), rect.y1]
    return [Rect(rect.x0, a, rect.x1, b) for a, b in itertools.pairwise(edges)]


def _check_plan_args(width: int, height: int, align: tuple[int, int], bytes_per_pixel: float,
                     window_overhead: float, max_windows: int, band_rows: int | None) -> None:
    """ConfigError for arguments no plan can use."""
    if not all(isinstance(v, int) and not isinstance(v, bool) and v >= 1 for v in (width, height, *align)):
        raise ConfigError(f"panel size and alignment must be integers >= 1, got {width}x{height} align {align}")
    if not (isinstance(bytes_per_pixel, (int, float)) and 0 < bytes_per_pixel < math.inf):
        raise ConfigError(f"bytes_per_pixel must be a number > 0, got {bytes_per_pixel!r}")
    if not (isinstance(window_overhead, (int, float)) and 0 <= window_overhead < math.inf):
        raise ConfigError(f"window_overhead must be a number of bytes >= 0, got {window_overhead!r}")
    if not (isinstance(max_windows, int) and max_windows >= 1):
        raise ConfigError(f"max_windows must be an integer >= 1, got {max_windows!r}")
    if band_rows is not None and not (isinstance(band_rows, int) and band_rows >= 1):
        raise ConfigError(f"band_rows must be an integer >= 1 or None, got {band_rows!r}")


def plan_windows(
    rects: Sequence[Rect],
    *,
    width: int,
    height: int,
    align: tuple[int, int] = (1, 1),
    bytes_per_pixel: float,
    window_overhead: float,
    max_windows: int = MAX_WINDOWS,
    band_rows: int | None = None,
) -> list[Rect]:
    """The windows to send for damage ``rects`` on a ``width`` x ``height`` panel (half-open Rects, sorted).

    ``align`` = (column, row) multiples every window starts on (ends too, except at the panel's edge);
    ``window_overhead`` = bytes one window costs beyond its pixels; ``band_rows``: windows never cross a
    multiple of this many rows (SH1106 page mode writes one page per window); then a plan holds at least
    one window per damaged band, and ConfigError says so when ``max_windows`` is smaller.
    """
    _check_plan_args(width, height, align, bytes_per_pixel, window_overhead, max_windows, band_rows)
    boxes = []
    for r in rects:
        clipped = Rect(max(int(r.x0), 0), max(int(r.y0), 0), min(int(r.x1), width), min(int(r.y1), height))
        if clipped.area > 0:
            boxes.append(clipped.aligned(align[0], align[1], width, height))
    if not boxes:
        return []
    whole = bounding(boxes)
    if len(boxes) > MAX_RECTS:
        boxes = [whole]
    one_band = band_rows is None or len({b.y0 // band_rows for b in boxes} | {(b.y1 - 1) // band_rows
                                                                              for b in boxes}) == 1
    if len(boxes) <= min(FEW_RECTS, max_windows) and one_band:
        few = merge_rects(boxes, window_overhead, bytes_per_pixel)
        few_bytes = sum(b.area for b in few) * bytes_per_pixel + len(few) * window_overhead
        return [whole] if whole.area * bytes_per_pixel + window_overhead < few_bytes else few
    strips = [s for b in boxes for s in _bands(b, band_rows)]
    band = band_rows or height
    damaged_bands = {s.y0 // band for s in strips}
    if len(damaged_bands) > max_windows:
        raise ConfigError(f"damage spans {len(damaged_bands)} bands of {band} rows, each needing its own window, "
                          f"more than max_windows={max_windows}")
    spread = [Rect(s.x0, s.y0 + (s.y0 // band) * _BAND_GAP, s.x1, s.y1 + (s.y0 // band) * _BAND_GAP) for s in strips]
    merged = merge_rects(spread, window_overhead, bytes_per_pixel, max_windows)
    windows = [Rect(m.x0, m.y0 - (m.y0 // (band + _BAND_GAP)) * _BAND_GAP, m.x1,
                    m.y1 - (m.y0 // (band + _BAND_GAP)) * _BAND_GAP) for m in merged]
    per_band = {k: [s for s in strips if s.y0 // band == k] for k in damaged_bands}
    bounding_strips = [bounding(v) for v in per_band.values()]

    def cost(ws: list[Rect]) -> float:
        """Bytes of a plan under the merge model."""
        return sum(w.area for w in ws) * bytes_per_pixel + len(ws) * window_overhead

    return sorted(bounding_strips) if cost(bounding_strips) < cost(windows) else sorted(windows)


@dataclass(frozen=True)
class WindowCost:
    """Bytes and transfers of refresh windows on one controller over one bus (see :func:`window_cost`)."""

    bytes_per_pixel: float
    window_bytes: int
    """Command bytes that open one window (per band when ``band_rows`` is set), I2C control byte included."""
    window_transfers: int
    """Transfers carrying them (SPI chip-select frames, I2C transactions)."""
    data_chunk: int
    """Most pixel bytes in one data transfer."""
    data_framing: int = 0
    """Extra bytes per data transfer (I2C: the 0x40 control byte)."""
    align: tuple[int, int] = (1, 1)
    band_rows: int | None = None

    @property
    def window_overhead(self) -> int:
        """A window's bytes beside its pixels under the merge model: its commands and one data framing."""
        return self.window_bytes + self.data_framing

    def window(self, rect: Rect) -> PlanCost:
        """What sending one window costs (cut into bands first where the controller needs it)."""
        total_bytes = transfers = 0
        for strip in _bands(rect, self.band_rows):
            data = math.ceil(strip.area * self.bytes_per_pixel)
            chunks = -(-data // self.data_chunk)
            total_bytes += self.window_bytes + data + chunks * self.data_framing
            transfers += self.window_transfers + chunks
        return PlanCost(total_bytes, transfers)

    def cost(self, windows: Sequence[Rect]) -> PlanCost:
        """What sending all ``windows`` costs."""
        costs = [self.window(w) for w in windows]
        return PlanCost(sum(c.bytes for c in costs), sum(c.transfers for c in costs))

    def cut_or_bounding(self, rects: list[Rect]) -> list[Rect]:
        """``rects`` as they are, or their bounding window when that costs fewer bytes under the merge model."""
        box, overhead = bounding(rects), self.window_overhead
        if box.area * self.bytes_per_pixel + overhead < sum(r.area for r in rects) * self.bytes_per_pixel + len(
                rects) * overhead:
            return [box]
        return rects

    def plan(self, rects: Sequence[Rect], *, width: int, height: int, max_windows: int = MAX_WINDOWS) -> list[Rect]:
        """:func:`plan_windows` with this controller's alignment, bands and per-window overhead."""
        return plan_windows(rects, width=width, height=height, align=self.align, bytes_per_pixel=self.bytes_per_pixel,
                            window_overhead=self.window_overhead, max_windows=max_windows,
                            band_rows=self.band_rows)


def window_cost(controller: str, *, pixel_format: str | None = None, bus_kind: str = "spi",
                max_transfer: int = 4096) -> WindowCost:
    """The cost model of ``controller`` ("ssd1306", "sh1106", "ssd1309", "st7789", ...) on a ``bus_kind`` bus.

    ``pixel_format`` defaults to the controller's ("mono-pages" or "rgb565be"); ``max_transfer`` is the bus's
    largest transfer (an I2C data chunk holds one byte less: its control byte).
    """
    oled = controller in OLED_CONTROLLERS
    fmt = pixel_format or ("mono-pages" if oled else "rgb565be")
    if fmt not in BYTES_PER_PIXEL or (fmt == "mono-pages") != oled:
        raise ConfigError(f"pixel format {fmt!r} is not one a {controller} takes")
    if bus_kind not in ("spi", "i2c") or (bus_kind == "i2c" and not oled):
        raise ConfigError(f"a {controller} is not driven over {bus_kind!r}")
    if not (isinstance(max_transfer, int) and max_transfer >= 2):
        raise ConfigError(f"max_transfer must be an integer >= 2, got {max_transfer!r}")
    i2c = bus_kind == "i2c"
    bpp = BYTES_PER_PIXEL[fmt]
    if not oled:
        return WindowCost(bpp, MIPI_WINDOW_BYTES, 5, max_transfer)
    command = SH1106_PAGE_BYTES if controller == "sh1106" else SSD1306_WINDOW_BYTES
    return WindowCost(bpp, command + i2c, 1, max_transfer - i2c, int(i2c), (1, 8),
                      8 if controller == "sh1106" else None)

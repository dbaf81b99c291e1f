"""The wire's units of a panel frame: the native frame converted where the wire cannot tell pixels apart, and
refresh windows packed from it.

On an ``rgb565be`` wire a frame is compared and packed as HxW uint16 RGB565 values (two colours the wire
sends alike are no change), converted again only inside the frame's damage; on every other wire the native
frame (window space) is its own units.  Windows are packed by ``raster.formats.pack``: once for their bounding
box when that is at most twice their area or :data:`PACK_ONCE` pixels (then a slice per window), else once
per window (:func:`once_box`); the shadow of the sent frame is updated by the same rule (:func:`keep_windows`).
"""

from __future__ import annotations

import numpy as np

from pixelpen.raster.colour import rgb888_to_rgb565
from pixelpen.raster.damage import Rect, bounding
from pixelpen.raster.formats import pack

PACK_ONCE = 8192
"""Windows whose bounding box has at most this many pixels (a 128x64 OLED's frame) are packed in one
conversion (numpy's per-call cost outweighs converting the pixels between them)."""


def to_units(native: np.ndarray, pixel_format: str) -> np.ndarray | None:
    """The frame's RGB565 values on an ``rgb565be`` wire (a new array, kept and updated by the display); None
    when the native frame is compared and packed as it is."""
    return rgb888_to_rgb565(native) if pixel_format == "rgb565be" else None


def update_units(units: np.ndarray, native: np.ndarray, damage: list[Rect]) -> None:
    """``units`` (:func:`to_units` of the last frame) converted again from ``native`` inside ``damage``."""
    for x0, y0, x1, y1 in damage:
        units[y0:y1, x0:x1] = rgb888_to_rgb565(native[y0:y1, x0:x1])


def once_box(windows: list[Rect]) -> Rect | None:
    """The bounding box of ``windows`` when they are handled as one block (at most twice their area or
    :data:`PACK_ONCE` pixels), else None (one window: None)."""
    if len(windows) <= 1:
        return None
    box = bounding(windows)
    return box if box.area <= max(2 * sum(w.area for w in windows), PACK_ONCE) else None


def keep_windows(shadow: np.ndarray, units: np.ndarray, windows: list[Rect]) -> None:
    """``shadow`` made equal to ``units`` in ``windows`` (every unit that differs is in one): by one copy of
    their :func:`once_box` where they have one (outside the windows the two are equal), else per window."""
    box = once_box(windows)
    for x0, y0, x1, y1 in windows if box is None else [box]:
        shadow[y0:y1, x0:x1] = units[y0:y1, x0:x1]


def pack_windows(units: np.ndarray, windows: list[Rect], pixel_format: str, unit_rows: int = 1) -> list[bytes]:
    """Each window's pixels of ``units`` (HxW RGB565 values, HxW bool, or the native frame) in ``pixel_format``;
    ``unit_rows``: rows a packed unit covers (``mono-pages``: 8, the windows then start on page rows)."""
    box = once_box(windows)
    if box is None:
        return [pack(units[y0:y1, x0:x1], pixel_format) for x0, y0, x1, y1 in windows]
    bx0, by0, bx1, by1 = box
    data = np.frombuffer(pack(units[by0:by1, bx0:bx1], pixel_format), dtype=np.uint8)
    grid = data.reshape(-(-(by1 - by0) // unit_rows), bx1 - bx0, -1)
    return [grid[(y0 - by0) // unit_rows:-(-(y1 - by0) // unit_rows), x0 - bx0:x1 - bx0].tobytes()
            for x0, y0, x1, y1 in windows]

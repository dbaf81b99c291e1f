"""MIPI-DCS serial pixel formats (COLMOD) decoded into the frame memory's 6-bit components.

4-line serial, D/CX high, MSB first (ST7789VW §8.8.40-43, ST7735 §9.7.19-22, ILI9341 §7.6.2): 12-bit is three
bytes per two pixels ``RRRRGGGG BBBBRRRR GGGGBBBB``; 16-bit is two bytes ``RRRRRGGG GGGBBBBB``; 18-bit is three
bytes, each component in the top six bits. 5- and 4-bit components reach the 18-bit memory through the
colour look-up table whose reset values (ST7735 §9.17) repeat the top bits: ``r6 = r5 << 1 | r5 >> 4``,
``r6 = r4 << 2 | r4 >> 2``; green's 6 bits go straight in. The ST7789 and ILI9341 serial paths are taken
to use the same table (their datasheets draw it but list no values).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Pixels = NDArray[np.uint8]
"""(n, 3) uint8 array of 6-bit components (0..63), in the order they were sent (R, G, B unless BGR)."""


@dataclass(frozen=True)
class PixelFormat:
    """One COLMOD interface format: bits per pixel on the wire, and how many bytes carry how many pixels."""

    name: str
    bits: int
    group_bytes: int
    group_pixels: int


FORMAT_12 = PixelFormat("12-bit RGB444", 12, 3, 2)
FORMAT_16 = PixelFormat("16-bit RGB565", 16, 2, 1)
FORMAT_18 = PixelFormat("18-bit RGB666", 18, 3, 1)

DBI_FORMATS: dict[int, PixelFormat] = {0b011: FORMAT_12, 0b101: FORMAT_16, 0b110: FORMAT_18}
"""COLMOD D[2:0] (the MCU interface's format) -> format; each model accepts a subset (ILI9341 serial: no 12-bit)."""

_EXPAND5 = np.array([(v << 1) | (v >> 4) for v in range(32)], dtype=np.uint8)
_EXPAND4 = np.array([(v << 2) | (v >> 2) for v in range(16)], dtype=np.uint8)


def decode(fmt: PixelFormat, data: bytes) -> tuple[Pixels, int]:
    """Whole pixels in ``data`` and how many bytes they used (a trailing partial group is left for later).

    12-bit data is decoded two pixels per three bytes; a caller with a two-byte tail at the end of a
    write gets the completed first pixel of the pair from :func:`decode_tail`.
    """
    used = len(data) - len(data) % fmt.group_bytes
    raw = np.frombuffer(data, dtype=np.uint8, count=used).reshape(-1, fmt.group_bytes)
    if fmt is FORMAT_18:
        return np.right_shift(raw, 2, dtype=np.uint8), used
    if fmt is FORMAT_16:
        value = (raw[:, 0].astype(np.uint16) << 8) | raw[:, 1]
        out = np.empty((len(raw), 3), dtype=np.uint8)
        out[:, 0] = _EXPAND5[value >> 11]
        out[:, 1] = (value >> 5) & 0x3F
        out[:, 2] = _EXPAND5[value & 0x1F]
        return out, used
    nibbles = np.empty((len(raw), 6), dtype=np.uint8)
    nibbles[:, 0::2] = raw >> 4
    nibbles[:, 1::2] = raw & 0x0F
    return _EXPAND4[nibbles.reshape(-1, 3)], used


def decode_tail(fmt: PixelFormat, tail: bytes) -> Pixels:
    """The whole pixels in an incomplete group left when a write ends (12-bit: two bytes hold one pixel)."""
    if fmt is FORMAT_12 and len(tail) >= 2:
        r, g, b = tail[0] >> 4, tail[0] & 0x0F, tail[1] >> 4
        return _EXPAND4[np.array([[r, g, b]], dtype=np.uint8)]
    return np.empty((0, 3), dtype=np.uint8)


def to_8bit(components: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """6-bit components as the 8-bit values a screenshot shows (``v << 2 | v >> 4``: 63 -> 255, 0 -> 0)."""
    return np.bitwise_or(np.left_shift(components, 2, dtype=np.uint8), np.right_shift(components, 4, dtype=np.uint8))

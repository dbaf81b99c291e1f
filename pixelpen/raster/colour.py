"""Colour models on numpy arrays: RGB <-> HSV/HSL (Foley & van Dam, Hearn & Baker), luma, RGB565 <-> RGB888."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from pixelpen.errors import ConfigError

LUMA_WEIGHTS: dict[str, tuple[int, int, int, int]] = {
    "bt601": (299, 587, 114, 1000),
    "bt709": (2126, 7152, 722, 10000),
}
"""Luma weights as integer numerators over a denominator: ITU-R BT.601 (as Pillow's "L") and BT.709."""


def _triples(values: ArrayLike, what: str) -> np.ndarray:
    """``values`` as a float64 array of shape (..., 3), finite; a ConfigError names what is wrong."""
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"{what} must be numbers in an array of shape (..., 3): {exc}") from None
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise ConfigError(f"{what} must have shape (..., 3), found shape {arr.shape}")
    if not np.isfinite(arr).all():
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(arr))[0])
        raise ConfigError(f"{what} must be finite, found {float(arr[bad])} at index {bad}")
    return arr


def _check_unit(arr: np.ndarray, channels: slice, what: str) -> None:
    """Raise ConfigError unless arr[..., channels] lies in [0, 1]; names the first offending element."""
    part = arr[..., channels]
    bad = (part < 0.0) | (part > 1.0)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ConfigError(f"{what} components must lie in [0, 1], found {float(part[index])} at index {index}")


def _uint8_triples(rgb: ArrayLike, what: str) -> np.ndarray:
    """``rgb`` as a uint8 array of shape (..., 3); anything else is a ConfigError."""
    arr = np.asarray(rgb)
    if arr.dtype != np.uint8 or arr.ndim == 0 or arr.shape[-1] != 3:
        raise ConfigError(f"{what} must be a uint8 array of shape (..., 3), found {arr.dtype} with shape {arr.shape}")
    return arr


def _hue_and_extremes(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hue in degrees [0, 360) (0 where undefined, i.e. grey), max and min of r, g, b (Foley's RGB_To_HSV)."""
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    cmax = rgb.max(axis=-1)
    cmin = rgb.min(axis=-1)
    delta = cmax - cmin
    safe = np.where(delta > 0, delta, 1.0)
    hue = np.where(r == cmax, (g - b) / safe, np.where(g == cmax, 2.0 + (b - r) / safe, 4.0 + (r - g) / safe))
    hue = np.where(delta > 0, hue * 60.0, 0.0)
    hue = np.where(hue < 0.0, hue + 360.0, hue)
    return np.where(hue >= 360.0, hue - 360.0, hue), cmax, cmin


def rgb_to_hsv(rgb: ArrayLike) -> np.ndarray:
    """RGB in [0, 1] (shape (..., 3)) to (h, s, v): hue in degrees [0, 360), 0 for greys; s, v in [0, 1]."""
    arr = _triples(rgb, "rgb")
    _check_unit(arr, slice(0, 3), "rgb")
    hue, cmax, cmin = _hue_and_extremes(arr)
    sat = np.where(cmax > 0, (cmax - cmin) / np.where(cmax > 0, cmax, 1.0), 0.0)
    return np.stack([hue, sat, cmax], axis=-1)


# Foley's HSV_To_RGB: per sector i = floor(h / 60), which of (v, q, p, t) each of r, g, b takes.
_HSV_SECTORS = np.array([[0, 3, 2], [1, 0, 2], [2, 0, 3], [2, 1, 0], [3, 2, 0], [0, 2, 1]])


def hsv_to_rgb(hsv: ArrayLike) -> np.ndarray:
    """(h, s, v) with h in degrees (any value, taken modulo 360) and s, v in [0, 1] to RGB in [0, 1]."""
    arr = _triples(hsv, "hsv")
    _check_unit(arr, slice(1, 3), "hsv saturation/value")
    h6 = np.mod(arr[..., 0], 360.0) / 60.0
    sector = np.minimum(np.floor(h6), 5).astype(np.intp)
    frac = h6 - sector
    s, v = arr[..., 1], arr[..., 2]
    choices = np.stack([v, v * (1.0 - s * frac), v * (1.0 - s), v * (1.0 - s * (1.0 - frac))], axis=-1)
    return np.take_along_axis(choices, _HSV_SECTORS[sector], axis=-1)


def rgb_to_hsl(rgb: ArrayLike) -> np.ndarray:
    """RGB in [0, 1] (shape (..., 3)) to (h, s, l): hue in degrees [0, 360), 0 for greys; s, l in [0, 1]."""
    arr = _triples(rgb, "rgb")
    _check_unit(arr, slice(0, 3), "rgb")
    hue, cmax, cmin = _hue_and_extremes(arr)
    light = (cmax + cmin) / 2.0
    delta = cmax - cmin
    denom = np.where(light <= 0.5, cmax + cmin, 2.0 - cmax - cmin)
    sat = np.where(delta > 0, delta / np.where(delta > 0, denom, 1.0), 0.0)
    return np.stack([hue, sat, light], axis=-1)


def _hsl_value(n1: np.ndarray, n2: np.ndarray, hue: np.ndarray) -> np.ndarray:
    """Foley's HSL helper ``Value(n1, n2, hue)``: one RGB component from the two ramps and a hue offset."""
    hue = np.mod(hue, 360.0)
    rising = n1 + (n2 - n1) * hue / 60.0
    falling = n1 + (n2 - n1) * (240.0 - hue) / 60.0
    return np.where(hue < 60.0, rising, np.where(hue < 180.0, n2, np.where(hue < 240.0, falling, n1)))


def hsl_to_rgb(hsl: ArrayLike) -> np.ndarray:
    """(h, s, l) with h in degrees (taken modulo 360) and s, l in [0, 1] to RGB in [0, 1] (Foley's HLS_To_RGB)."""
    arr = _triples(hsl, "hsl")
    _check_unit(arr, slice(1, 3), "hsl saturation/lightness")
    h, s, light = arr[..., 0], arr[..., 1], arr[..., 2]
    m2 = np.where(light <= 0.5, light * (1.0 + s), light + s - light * s)
    m1 = 2.0 * light - m2
    rgb = np.stack([_hsl_value(m1, m2, h + 120.0), _hsl_value(m1, m2, h), _hsl_value(m1, m2, h - 120.0)], axis=-1)
    return np.clip(rgb, 0.0, 1.0)


def _to_rgb8(rgb: np.ndarray) -> np.ndarray:
    """Float RGB in [0, 1] to uint8 by rounding to the nearest of 0..255."""
    return np.clip(np.rint(rgb * 255.0), 0, 255).astype(np.uint8)


def rgb8_to_hsv(rgb: ArrayLike) -> np.ndarray:
    """uint8 RGB (shape (..., 3)) to float (h, s, v), h in degrees."""
    return rgb_to_hsv(_uint8_triples(rgb, "rgb") / 255.0)


def hsv_to_rgb8(hsv: ArrayLike) -> np.ndarray:
    """(h, s, v) to uint8 RGB, each component rounded to the nearest of 0..255."""
    return _to_rgb8(hsv_to_rgb(hsv))


def rgb8_to_hsl(rgb: ArrayLike) -> np.ndarray:
    """uint8 RGB (shape (..., 3)) to float (h, s, l), h in degrees."""
    return rgb_to_hsl(_uint8_triples(rgb, "rgb") / 255.0)


def hsl_to_rgb8(hsl: ArrayLike) -> np.ndarray:
    """(h, s, l) to uint8 RGB, each component rounded to the nearest of 0..255."""
    return _to_rgb8(hsl_to_rgb(hsl))


def luma(rgb: ArrayLike, standard: str = "bt601") -> np.ndarray:
    """Luma Y' of gamma-encoded RGB (shape (..., 3)): uint8 in -> uint8 rounded half up; float in -> float out.

    ``standard`` is "bt601" (0.299, 0.587, 0.114: JPEG, Pillow's "L", SD video) or "bt709"
    (0.2126, 0.7152, 0.0722: HD video). uint8 results are exact: (wr·R + wg·G + wb·B + D/2) // D.
    """
    if standard not in LUMA_WEIGHTS:
        raise ConfigError(f"unknown luma standard {standard!r}: use one of {', '.join(LUMA_WEIGHTS)}")
    wr, wg, wb, denom = LUMA_WEIGHTS[standard]
    arr = np.asarray(rgb)
    if arr.dtype == np.uint8:
        arr = _uint8_triples(arr, "rgb")
        total = np.multiply(arr[..., 0], wr, dtype=np.int32)
        total += np.multiply(arr[..., 1], wg, dtype=np.int32)
        total += np.multiply(arr[..., 2], wb, dtype=np.int32)
        total += denom // 2
        total //= denom
        return total.astype(np.uint8)
    arr = _triples(arr, "rgb")
    return (arr[..., 0] * wr + arr[..., 1] * wg + arr[..., 2] * wb) / denom


CHUNK_PIXELS = 1 << 17
"""Pixels converted per step by the chunked converters here and in formats: byte planes stay in L2 cache."""


_RGB565_CHUNK = CHUNK_PIXELS // 4
"""Pixels :func:`rgb888_to_rgb565` converts per step: its input, output and two scratch planes stay in L2."""
_RGB565_RED, _RGB565_GREEN, _RGB565_BLUE_SHIFT, _THREE = (np.uint16(v) for v in (0xF800, 0x07E0, 11, 3))
"""uint16 constants of :func:`_rgb565_rows` (a numpy scalar operand costs less per call than a Python int)."""


def _rgb565_rows(rgb: np.ndarray, out: np.ndarray, green: np.ndarray, blue: np.ndarray) -> None:
    """RGB565 of HxWx3 uint8 ``rgb`` (a pixel's bytes adjacent) into HxW uint16 ``out``; ``green``, ``blue`` alike.

    Two strided reads of byte pairs instead of three of bytes (``R<<8 | G`` through a big-endian uint16 view,
    ``G | B<<8`` through a little-endian one), then six uint16 operations on contiguous data.
    """
    np.copyto(out, rgb[..., 0:2].view(">u2")[..., 0])
    np.copyto(blue, rgb[..., 1:3].view("<u2")[..., 0])
    np.left_shift(out, _THREE, out=green)
    green &= _RGB565_GREEN
    out &= _RGB565_RED
    out |= green
    blue >>= _RGB565_BLUE_SHIFT
    out |= blue


def rgb888_to_rgb565(rgb: ArrayLike) -> np.ndarray:
    """uint8 RGB (shape (..., 3)) to uint16 RGB565 by truncation: ((R&0xF8)<<8) | ((G&0xFC)<<3) | (B>>3).

    Works in cache-sized chunks of rows (about 3.5 ms for a 1080p frame).
    """
    arr = rgb
    if type(arr) is not np.ndarray or arr.dtype != np.uint8 or arr.ndim != 3 or arr.shape[2] != 3:
        arr = _uint8_triples(rgb, "rgb")
        if arr.ndim != 3:
            return rgb888_to_rgb565(arr.reshape(-1, 1, 3)).reshape(arr.shape[:-1])
    if arr.strides[2] != 1:
        arr = np.ascontiguousarray(arr)
    shape = arr.shape[:2]
    out = np.empty(shape, dtype=np.uint16)
    rows = _RGB565_CHUNK // shape[1] if shape[1] else shape[0]
    if shape[0] <= rows:
        _rgb565_rows(arr, out, np.empty(shape, dtype=np.uint16), np.empty(shape, dtype=np.uint16))
        return out
    green = np.empty((rows, shape[1]), dtype=np.uint16)
    blue = np.empty_like(green)
    for y in range(0, shape[0], rows):
        n = min(rows, shape[0] - y)
        _rgb565_rows(arr[y:y + n], out[y:y + n], green[:n], blue[:n])
    return out


def rgb565_to_rgb888(values: ArrayLike) -> np.ndarray:
    """uint16 RGB565 values (any shape) to uint8 RGB (shape + (3,)), widening each field by bit replication."""
    v = np.asarray(values)
    if v.dtype.kind != "u" or v.dtype.itemsize != 2:
        raise ConfigError(f"RGB565 values must be a uint16 array, found {v.dtype}")
    flat = v.reshape(-1)
    out = np.empty((flat.shape[0], 3), dtype=np.uint8)
    for start in range(0, flat.shape[0], CHUNK_PIXELS):
        part = flat[start:start + CHUNK_PIXELS].astype(np.uint16)
        rgb = out[start:start + CHUNK_PIXELS]
        for channel, shift, bits in ((0, 11, 5), (1, 5, 6), (2, 0, 5)):
            field = ((part >> shift) & ((1 << bits) - 1)).astype(np.uint8)
            np.copyto(rgb[:, channel], (field << (8 - bits)) | (field >> (2 * bits - 8)))
    return out.reshape((*v.shape, 3))

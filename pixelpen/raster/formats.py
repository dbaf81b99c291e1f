"""Pixel formats: packing numpy images into the bytes panels and framebuffers take (and back), vectorised.

Images are numpy arrays in one of these *kinds* (see :func:`image_kind`):

* ``"rgb"``    – HxWx3 uint8, R, G, B;
* ``"grey"``   – HxW uint8 (R = G = B for the colour formats; thresholded ``>= 128`` for mono);
* ``"bitmap"`` – HxW bool, or any integer dtype except uint8/uint16 holding only 0 and 1;
* ``"rgb565"`` – HxW uint16 RGB565 values, packed as they are (rgb565 formats only).

Wire/memory formats (:data:`FORMATS`):

* ``rgb565be`` – 2 bytes/pixel ``RRRRRGGG GGGBBBBB``, MSB first: MIPI-DCS COLMOD 0x55 (ST7789, ILI9341);
  from RGB by truncation ``((R&0xF8)<<8) | ((G&0xFC)<<3) | (B>>3)``.
* ``rgb565le`` – the same 16-bit value stored little-endian: Linux fbdev 16 bpp (red offset 11,
  green 5, blue 0) in memory.
* ``rgb666``   – 3 bytes/pixel R, G, B, each byte's top 6 bits significant (``c & 0xFC``), as ILI9341 /
  ST7789 take with COLMOD 0x66 on a serial interface.
* ``rgb888``, ``bgr888`` – 3 bytes/pixel in that byte order.
* ``xrgb8888`` – 4 bytes/pixel in memory order **B, G, R, X** = the 32-bit word ``0xXXRRGGBB`` stored
  little-endian, i.e. fbdev bitfields red.offset 16, green.offset 8, blue.offset 0 (x86 fbdev and
  DRM_FORMAT_XRGB8888; panels.md §6). X is written as 0xFF (opaque if read as ARGB) and ignored on unpack.
* ``mono-pages`` – SSD1306 GDDRAM: one byte = 8 vertical pixels of one column, bit 0 = top row;
  pages of 8 rows, page-major then column (``byte[page * W + x]``). A height that is not a multiple
  of 8 is padded with off pixels in the last page.
* ``mono-rows`` – 1 bpp row-major, MSB = leftmost pixel, each row padded to whole bytes with 0 bits.

Mono formats light a pixel iff: bitmap value is true; grey ``>= 128``; RGB
``299·R + 587·G + 114·B >= 128000`` (Pillow's ``rgb2bit``, no dithering — dither first with
:mod:`pixelpen.raster.dither` for anything else).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from pixelpen.errors import ConfigError, ParseError
from pixelpen.raster.colour import CHUNK_PIXELS, rgb565_to_rgb888, rgb888_to_rgb565

Region = tuple[int, int, int, int]
"""A window ``(x0, y0, x1, y1)``, half-open like a numpy slice: columns x0..x1-1, rows y0..y1-1."""


@dataclass(frozen=True)
class PixelFormat:
    """One packed pixel layout: storage bits per pixel, significant colour bits, and what it is for."""

    name: str
    bits_per_pixel: int
    """Storage bits per pixel in the packed bytes (1, 16, 24 or 32)."""
    depth: int
    """Significant colour bits per pixel (1, 16, 18 or 24)."""
    description: str

    @property
    def bytes_per_pixel(self) -> int | None:
        """Whole bytes per pixel, or None for the 1-bit formats that pack several pixels per byte."""
        return self.bits_per_pixel // 8 if self.bits_per_pixel >= 8 else None

    @property
    def mono(self) -> bool:
        """True for the 1 bit-per-pixel formats."""
        return self.bits_per_pixel == 1

    def size(self, width: int, height: int) -> int:
        """Exact byte count of a packed width x height image (padding included)."""
        if self.name == "mono-pages":
            return width * ((height + 7) // 8)
        if self.name == "mono-rows":
            return height * ((width + 7) // 8)
        return width * height * (self.bits_per_pixel // 8)


FORMATS: dict[str, PixelFormat] = {
    f.name: f
    for f in (
        PixelFormat("rgb565be", 16, 16, "RGB565, big-endian (MIPI-DCS COLMOD 0x55: ST7789, ILI9341)"),
        PixelFormat("rgb565le", 16, 16, "RGB565, little-endian (fbdev 16 bpp in memory)"),
        PixelFormat("rgb666", 24, 18, "R, G, B bytes with 6 significant MSBs (COLMOD 0x66, serial)"),
        PixelFormat("rgb888", 24, 24, "R, G, B bytes"),
        PixelFormat("bgr888", 24, 24, "B, G, R bytes"),
        PixelFormat("xrgb8888", 32, 24, "B, G, R, X bytes = little-endian 0xXXRRGGBB (fbdev/DRM XRGB8888)"),
        PixelFormat("mono-pages", 1, 1, "SSD1306 GDDRAM: pages of 8 rows, bit 0 = top, page-major then column"),
        PixelFormat("mono-rows", 1, 1, "1 bpp rows, MSB = leftmost pixel, rows padded to whole bytes"),
    )
}
"""Every format :func:`pack` and :func:`unpack` know, by name."""


def pixel_format(fmt: str | PixelFormat) -> PixelFormat:
    """Look a format up by name (a PixelFormat passes through); unknown names are a ConfigError."""
    if isinstance(fmt, PixelFormat):
        return fmt
    try:
        return FORMATS[fmt]
    except (KeyError, TypeError):
        raise ConfigError(f"unknown pixel format {fmt!r}: use one of {', '.join(FORMATS)}") from None


def image_kind(array: np.ndarray) -> str:
    """Classify an image array as "rgb", "grey", "bitmap" or "rgb565" (module doc); anything else is a ConfigError."""
    if not isinstance(array, np.ndarray):
        raise ConfigError(f"an image must be a numpy array, found {type(array).__name__}")
    if array.ndim == 3 and array.shape[2] == 3 and array.dtype == np.uint8:
        return "rgb"
    if array.ndim == 2:
        if array.dtype == np.bool_:
            return "bitmap"
        if array.dtype == np.uint8:
            return "grey"
        if array.dtype == np.uint16:
            return "rgb565"
        if array.dtype.kind in "iu":
            if array.size and (array.min() < 0 or array.max() > 1):
                raise ConfigError(
                    f"an HxW {array.dtype} image is read as a 0/1 bitmap, but it holds values "
                    f"{array.min()}..{array.max()} (use uint8 for grey, uint16 for RGB565)"
                )
            return "bitmap"
    raise ConfigError(
        "an image must be HxWx3 uint8 (RGB), HxW uint8 (grey), HxW bool or 0/1 integers (bitmap) "
        f"or HxW uint16 (RGB565), found {array.dtype} with shape {array.shape}"
    )


def align_region(fmt: str | PixelFormat, region: Region | None, width: int, height: int) -> Region:
    """The window :func:`pack` really encodes for ``region`` on a width x height image.

    ``region`` is half-open ``(x0, y0, x1, y1)`` and must lie inside the image (None = whole image).
    For ``mono-pages`` y0 is rounded down and y1 up to page boundaries (multiples of 8), y1 capped
    at the image height; the packed window then covers whole pages.
    """
    f = pixel_format(fmt)
    if region is None:
        return (0, 0, width, height)
    try:
        x0, y0, x1, y1 = (int(v) for v in region)
        exact = all(int(v) == v for v in region)
    except (TypeError, ValueError, OverflowError):
        exact = False
    if not exact:
        raise ConfigError(f"region must be four integers (x0, y0, x1, y1), found {region!r}")
    if not (0 <= x0 <= x1 <= width and 0 <= y0 <= y1 <= height):
        raise ConfigError(
            f"region {region!r} (x0, y0, x1, y1, half-open) does not lie inside the {width}x{height} image"
        )
    if f.name == "mono-pages":
        y0 = y0 // 8 * 8
        y1 = min(-(-y1 // 8) * 8, height)
    return (x0, y0, x1, y1)


def as_uint8_image(array: ArrayLike, what: str = "this operation") -> np.ndarray:
    """An RGB, grey or bitmap image as uint8: HxWx3 RGB or HxW grey (a bitmap becomes 0/255 grey).

    RGB565 values and anything else are a ConfigError naming ``what`` needed the image.
    """
    arr = np.asarray(array)
    kind = image_kind(arr)
    if kind == "rgb565":
        raise ConfigError(f"{what} needs an RGB, grey or bitmap image, not RGB565 values")
    if kind == "bitmap":
        return np.where(arr != 0, np.uint8(255), np.uint8(0))
    return arr


def as_rgb_image(array: ArrayLike, what: str = "this operation") -> np.ndarray:
    """An RGB, grey or bitmap image as HxWx3 uint8 RGB (grey is broadcast, not copied)."""
    arr = as_uint8_image(array, what)
    return arr if arr.ndim == 3 else np.broadcast_to(arr[..., None], (*arr.shape, 3))


def _lit(view: np.ndarray, kind: str) -> np.ndarray:
    """HxW bool: which pixels a mono format lights (bitmap as is; grey >= 128; RGB by Pillow's rgb2bit)."""
    if kind == "bitmap":
        return view != 0
    if kind == "grey":
        return view >= 128
    if kind != "rgb":
        raise ConfigError("mono packing needs an RGB, grey or bitmap image, not RGB565 values")
    h, w = view.shape[:2]
    lit = np.empty((h, w), dtype=bool)
    rows = max(1, CHUNK_PIXELS // max(w, 1))
    for y in range(0, h, rows):
        part = view[y:y + rows]
        total = np.multiply(np.ascontiguousarray(part[..., 0]), 299, dtype=np.int32)
        total += np.multiply(np.ascontiguousarray(part[..., 1]), 587, dtype=np.int32)
        total += np.multiply(np.ascontiguousarray(part[..., 2]), 114, dtype=np.int32)
        np.greater_equal(total, 128000, out=lit[y:y + rows])
    return lit


_PAGE_GATHER = np.uint64(0x0102040810204080)
"""Multiplier of a little-endian uint64 of eight 0/1 bytes: byte k lands alone on bit 56 + k (no carries)."""


def _pages(lit: np.ndarray) -> np.ndarray:
    """Pack an HxW bool mask into (ceil(H/8), W) SSD1306 page bytes, bit k = row 8·page + k.

    A column's eight rows of a page become one little-endian uint64 of 0/1 bytes, gathered into one byte by
    one multiplication.
    """
    h, w = lit.shape
    if h % 8:
        padded = np.zeros((h + 8 - h % 8, w), dtype=bool)
        padded[:h] = lit
        lit = padded
    columns = np.ascontiguousarray(lit.reshape(lit.shape[0] // 8, 8, w).transpose(0, 2, 1)).view("<u8")[..., 0]
    gathered = columns * _PAGE_GATHER
    gathered >>= np.uint64(56)
    return gathered.astype(np.uint8)


def _reordered(pixels: np.ndarray, order: tuple[int, ...], pad: int | None = None) -> np.ndarray:
    """HxWxC uint8 of the channels of ``pixels`` in ``order``, plus a constant ``pad`` channel if given.

    Channel by channel (np.copyto): several times faster than copying a ``[..., ::-1]`` view.
    """
    out = np.empty((*pixels.shape[:2], len(order) + (pad is not None)), dtype=np.uint8)
    for i, channel in enumerate(order):
        np.copyto(out[..., i], pixels[..., channel])
    if pad is not None:
        out[..., -1] = pad
    return out


def _rgb565(view: np.ndarray, kind: str, order: str) -> bytes:
    """An rgb565 format: uint16 values as they are, anything else converted; ``order`` ">u2" or "<u2"."""
    if kind == "rgb565":
        return view.astype(order, copy=False).tobytes()
    values = rgb888_to_rgb565(view if kind == "rgb" else as_rgb_image(view))
    if values.dtype.str != order:
        values.byteswap(inplace=True)  # our own array: swapped in place, its bytes in ``order``
    return values.tobytes()


def _colour(view: np.ndarray, kind: str, name: str) -> np.ndarray:
    """The window as HxWx3 RGB for the 24/32-bit format ``name`` (RGB565 values are a ConfigError)."""
    if kind == "rgb":
        return view
    if kind == "rgb565":
        raise ConfigError(f"HxW uint16 RGB565 values pack only to rgb565be/rgb565le, not {name}")
    return as_rgb_image(view)


_ENCODERS: dict[str, Callable[[np.ndarray, str], bytes]] = {
    "rgb565be": lambda view, kind: _rgb565(view, kind, ">u2"),
    "rgb565le": lambda view, kind: _rgb565(view, kind, "<u2"),
    "mono-pages": lambda view, kind: _pages(_lit(view, kind)).tobytes(),
    "mono-rows": lambda view, kind: np.packbits(_lit(view, kind), axis=1, bitorder="big").tobytes(),
    "rgb666": lambda view, kind: np.bitwise_and(_colour(view, kind, "rgb666"), 0xFC).tobytes(),
    "rgb888": lambda view, kind: _colour(view, kind, "rgb888").tobytes(),
    "bgr888": lambda view, kind: _reordered(_colour(view, kind, "bgr888"), (2, 1, 0)).tobytes(),
    # xrgb8888: memory B, G, R, X
    "xrgb8888": lambda view, kind: _reordered(_colour(view, kind, "xrgb8888"), (2, 1, 0), 0xFF).tobytes(),
}
"""Each format's packer of one (already windowed) image view of a kind."""


def pack(array: ArrayLike, fmt: str | PixelFormat, region: Region | None = None) -> bytes:
    """Pack an image (module doc for accepted kinds) into ``fmt`` bytes, optionally only ``region``.

    ``region`` is half-open ``(x0, y0, x1, y1)`` inside the image; only that window is converted
    (a view, the frame is not copied). For ``mono-pages`` the window is widened to whole pages —
    :func:`align_region` says which window the bytes cover. Rows are packed tightly (no stride).
    """
    encode = _ENCODERS.get(fmt) if type(fmt) is str else None
    if encode is None:
        encode = _ENCODERS[pixel_format(fmt).name]
    arr = array if type(array) is np.ndarray else np.asarray(array)
    kind = image_kind(arr)
    if region is not None:
        x0, y0, x1, y1 = align_region(fmt, region, arr.shape[1], arr.shape[0])
        arr = arr[y0:y1, x0:x1]
    return encode(arr, kind)


def _frame_bytes(data: object, f: PixelFormat, width: int, height: int) -> np.ndarray:
    """``data`` as a flat uint8 array of exactly the size of a width x height ``f`` frame, else ParseError."""
    for name, value in (("width", width), ("height", height)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
            raise ConfigError(f"{name} must be a non-negative integer, found {value!r}")
    try:
        buf = np.frombuffer(data, dtype=np.uint8)  # type: ignore[call-overload]
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"{f.name} data must be bytes-like, found {type(data).__name__}: {exc}") from None
    expected = f.size(int(width), int(height))
    if buf.size != expected:
        problem = "truncated" if buf.size < expected else "oversized"
        raise ParseError(
            f"{problem} {f.name} data for {width}x{height}: expected {expected} bytes, found {buf.size}",
            source=f.name,
            offset=min(buf.size, expected),
        )
    return buf


def unpack(data: bytes, fmt: str | PixelFormat, width: int, height: int, *, raw: bool = False) -> np.ndarray:
    """Decode exactly one width x height frame of ``fmt`` bytes into an image array.

    Colour formats give HxWx3 uint8 RGB, narrow fields widened by bit replication (RGB565 via
    :func:`~pixelpen.raster.colour.rgb565_to_rgb888`; RGB666 ``c6 << 2 | c6 >> 4``; low bits of
    rgb666 bytes and the X byte of xrgb8888 are ignored, as the hardware does). ``raw=True`` gives
    rgb565 frames as HxW uint16 values instead. Mono formats give HxW bool (padding dropped).
    A byte count other than the frame size is a ParseError naming expected and found counts.
    """
    f = pixel_format(fmt)
    buf = _frame_bytes(data, f, width, height)
    if raw and f.name not in ("rgb565be", "rgb565le"):
        raise ConfigError(f"raw=True applies to rgb565be/rgb565le, not {f.name}")
    if f.name in ("rgb565be", "rgb565le"):
        values = buf.view(">u2" if f.name == "rgb565be" else "<u2").reshape(height, width).astype(np.uint16)
        return values if raw else rgb565_to_rgb888(values)
    if f.name == "mono-pages":
        npages = (height + 7) // 8
        bits = np.unpackbits(buf.reshape(npages, 1, width), axis=1, bitorder="little")
        return bits.reshape(npages * 8, width)[:height].astype(bool)
    if f.name == "mono-rows":
        rows = buf.reshape(height, (width + 7) // 8)
        return np.unpackbits(rows, axis=1, count=width, bitorder="big").astype(bool)
    if f.name == "xrgb8888":
        return _reordered(buf.reshape(height, width, 4), (2, 1, 0))
    pixels = buf.reshape(height, width, 3)
    if f.name == "bgr888":
        return _reordered(pixels, (2, 1, 0))
    if f.name == "rgb666":
        c6 = pixels >> 2
        return (c6 << 2) | (c6 >> 4)
    return pixels.copy()

"""Dithering: ordered (Bayer) and Floyd–Steinberg error diffusion to mono, N levels per channel, or a palette.

Level values. Dithering an 8-bit channel to L levels chooses a level k in 0..L-1 and writes it as
``round(k·255/(L-1))`` (half up). The truncating packers in :mod:`pixelpen.raster.formats` recover
k exactly from that value for power-of-two L (RGB565: 32/64/32, RGB666: 64, RGB332: 8/8/4), so a
dithered image packs without further error.

Floyd–Steinberg (Floyd & Steinberg 1976; Foley et al. §13.1.2; Hearn & Baker "error diffusion"):
rows top to bottom, pixels left to right; each pixel's quantisation error goes 7/16 to the right,
3/16 below-left, 5/16 below and 1/16 below-right; errors leaving the image are dropped. Arithmetic
follows Pillow's C implementation (``Convert.c``): errors are summed as integer sixteenths, divided
once per pixel truncating toward zero, and the corrected value is clamped to 0..255 before choosing.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike
from PIL import Image

from pixelpen.errors import ConfigError
from pixelpen.raster.colour import luma
from pixelpen.raster.formats import as_uint8_image
from pixelpen.raster.palette import Palette

DEPTHS: dict[str, tuple[int, ...]] = {
    "mono": (2,),
    "grey4": (4,),
    "grey16": (16,),
    "rgb332": (8, 8, 4),
    "rgb444": (16, 16, 16),
    "rgb565": (32, 64, 32),
    "rgb666": (64, 64, 64),
}
"""Named level counts per channel for ``levels=``: one entry for grey, three for RGB."""

Levels = int | Sequence[int] | str


def bayer_matrix(n: int) -> np.ndarray:
    """The n x n Bayer index matrix (n a power of two, 1..64), values 0..n²-1, built recursively.

    M₁ = [[0]], M₂ₙ = [[4Mₙ, 4Mₙ+2], [4Mₙ+3, 4Mₙ+1]] (Bayer 1973; Foley et al. §13.1.2), so
    M₂ = [[0, 2], [3, 1]].
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= 64 or n & (n - 1):
        raise ConfigError(f"a Bayer matrix size must be a power of two 1..64, found {n!r}")
    m = np.zeros((1, 1), dtype=np.int32)
    while m.shape[0] < n:
        m = np.block([[4 * m, 4 * m + 2], [4 * m + 3, 4 * m + 1]])
    return m


def _channels(image: ArrayLike, what: str) -> tuple[np.ndarray, bool]:
    """An RGB, grey or bitmap image as HxWxC uint8 (C = 3 or 1) and whether it was RGB."""
    arr = as_uint8_image(image, what)
    return (arr, True) if arr.ndim == 3 else (arr[..., None], False)


def _levels(levels: Levels, channels: int) -> np.ndarray:
    """Per-channel level counts (int64 array of length ``channels``), each 2..256."""
    if isinstance(levels, str):
        if levels not in DEPTHS:
            raise ConfigError(f"unknown depth {levels!r}: use one of {', '.join(DEPTHS)} or level counts")
        levels = DEPTHS[levels]
    counts = np.atleast_1d(np.asarray(levels))
    if counts.ndim != 1 or counts.dtype.kind not in "iu" or (counts < 2).any() or (counts > 256).any():
        raise ConfigError(f"levels must be integers 2..256 (one, or one per channel), found {levels!r}")
    if counts.size == 1:
        counts = np.repeat(counts, channels)
    if counts.size != channels:
        raise ConfigError(f"{counts.size} level counts given for an image of {channels} channel(s)")
    return counts.astype(np.int64)


def _level_values(k: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Level indices k (of L = counts levels) to their 8-bit values round(k·255/(L-1)), half up."""
    return (k * 510 + (counts - 1)) // (2 * (counts - 1))


def _output(values: np.ndarray, rgb: bool) -> np.ndarray:
    """HxWxC integer values as the uint8 image kind the caller gave (HxW for grey)."""
    out = values.astype(np.uint8)
    return out if rgb else out[..., 0]


def ordered(image: ArrayLike, levels: Levels = 2, size: int = 4, origin: tuple[int, int] = (0, 0)) -> np.ndarray:
    """Ordered (Bayer) dither of an RGB or grey uint8 image to ``levels`` per channel; same shape, uint8.

    With q = v·(L-1)/255 and threshold T = (M[y mod n][x mod n] + ½)/n², the level is
    k = floor(q + 1 − T): the fractional part of q is rounded up where it reaches T. Exact integer
    arithmetic, no ties. ``origin`` = (x, y) of the image's top-left pixel in the frame, so a
    window dithered alone matches the same window of the whole frame. ``levels`` is a count, one
    count per channel, or a name from :data:`DEPTHS`.
    """
    pixels, rgb = _channels(image, "ordered dithering")
    counts = _levels(levels, pixels.shape[2])
    if len(origin) != 2 or any(isinstance(v, bool) or not isinstance(v, (int, np.integer)) for v in origin):
        raise ConfigError(f"origin must be (x, y) integers, found {origin!r}")
    matrix = bayer_matrix(size)
    h, w = pixels.shape[:2]
    n2 = size * size
    ox, oy = origin
    index = matrix[(np.arange(h) + oy) % size][:, (np.arange(w) + ox) % size]
    # The result depends only on (v, M): tabulate the formula over all 256·n² pairs, then look up.
    v = np.arange(256, dtype=np.int64)[:, None]
    m = np.arange(n2, dtype=np.int64)[None, :]
    out = np.empty(pixels.shape, dtype=np.uint8)
    for c, count in enumerate(counts):
        k = (v * (2 * n2 * (count - 1)) + 255 * (2 * n2 - 1) - 510 * m) // (510 * n2)
        table = _level_values(k, count).astype(np.uint8).ravel()
        position = pixels[..., c].astype(np.int32)
        position *= n2
        position += index
        np.take(table, position, out=out[..., c])
    return out if rgb else out[..., 0]


def ordered_mono(image: ArrayLike, size: int = 4, origin: tuple[int, int] = (0, 0)) -> np.ndarray:
    """Ordered (Bayer) dither to 1 bit: HxW bool, on iff grey/255 ≥ (M + ½)/n² (RGB through :func:`luma`)."""
    return ordered(_grey(image), 2, size, origin) != 0


def _grey(image: ArrayLike) -> np.ndarray:
    """HxW uint8 grey of an RGB (BT.601 :func:`luma`), grey or bitmap image."""
    pixels, rgb = _channels(image, "mono dithering")
    return luma(pixels) if rgb else pixels[..., 0]


def floyd_steinberg_mono(image: ArrayLike) -> np.ndarray:
    """Floyd–Steinberg to 1 bit with Pillow's C code (``convert("1")``): HxW bool.

    Pillow lights a pixel iff its corrected value is > 128 (so 128 itself goes dark); RGB is first
    reduced to grey by :func:`luma` (Pillow's own RGB path would truncate the luma instead).
    """
    grey = np.ascontiguousarray(_grey(image))
    if grey.size == 0:
        return np.zeros(grey.shape, dtype=bool)
    return np.asarray(Image.fromarray(grey, "L").convert("1", dither=Image.Dither.FLOYDSTEINBERG), dtype=bool)


Chooser = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
"""Maps (K, C) corrected values to (K, C) shown values and K labels (level values or palette indices)."""


def _diffuse(pixels: np.ndarray, choose: Chooser, label_shape: tuple[int, ...]) -> np.ndarray:
    """Floyd–Steinberg over HxWxC ``pixels`` by wavefronts; returns labels of shape HxW + label_shape.

    Pixel (x, y) needs its left neighbour and the three above it, all on earlier fronts
    x + 2y = t, so each front is quantised in one vectorised step (W + 2H steps in all, not W·H).
    Pixels of one front lie W+2 apart minus 2 in a (W+2)-wide padded layout, i.e. a constant
    stride W, so every step works on plain strided slices. Error sums are integer sixteenths,
    independent of the order they are added in, so the result is exactly the sequential one.
    """
    h, w, c = pixels.shape
    labels = np.zeros((h, w + 2, *label_shape), dtype=np.int64)
    if h == 0 or w == 0:
        return labels[:, 1:-1]
    stride = w + 2
    source = np.zeros((h, stride, c), dtype=np.int64)
    source[:, 1:-1] = pixels
    source = source.reshape(-1, c)
    flat_labels = labels.reshape((-1, *label_shape))
    errors = np.zeros(((h + 1) * stride, c), dtype=np.int64)
    offsets = (1, stride - 1, stride, stride + 1)  # right, below-left, below, below-right
    weights = np.array([7, 3, 5, 1]).reshape(4, 1, 1)
    for t in range(w + 2 * (h - 1)):
        y0 = max(0, (t - w + 2) // 2)
        y1 = min(h - 1, t // 2)
        if y1 < y0:
            continue
        first = y0 * stride + (t - 2 * y0) + 1
        front = slice(first, first + (y1 - y0) * w + 1, w)
        sixteenths = errors[front]
        value = source[front] + (sixteenths - np.fmod(sixteenths, 16)) // 16  # C division, toward zero
        np.minimum(np.maximum(value, 0, out=value), 255, out=value)
        shown, label = choose(value)
        flat_labels[front] = label
        shares = weights * (value - shown)
        for offset, share in zip(offsets, shares, strict=True):
            errors[first + offset:first + offset + (y1 - y0) * w + 1:w] += share
    return labels[:, 1:-1]


def floyd_steinberg(image: ArrayLike, levels: Levels = 2) -> np.ndarray:
    """Floyd–Steinberg dither of an RGB or grey uint8 image to ``levels`` per channel; same shape, uint8.

    Each corrected value goes to the nearest level value (the lower one on a tie); see the module
    doc for the arithmetic. Vectorised along anti-diagonal wavefronts, exactly equal to the scalar
    :func:`floyd_steinberg_reference`. For 1 bit through Pillow see :func:`floyd_steinberg_mono`.
    """
    pixels, rgb = _channels(image, "Floyd–Steinberg dithering")
    counts = _levels(levels, pixels.shape[2])

    nearest_level = np.zeros((256, counts.size), dtype=np.int64)
    for c, count in enumerate(counts):
        values = _level_values(np.arange(count), count)
        nearest_level[:, c] = values[np.argmin(np.abs(np.arange(256)[:, None] - values[None, :]), axis=1)]

    channel = np.arange(pixels.shape[2])

    def choose(value: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        shown = nearest_level[value, channel]
        return shown, shown

    return _output(_diffuse(pixels, choose, (pixels.shape[2],)), rgb)


def floyd_steinberg_palette(image: ArrayLike, palette: Palette, engine: str = "exact") -> np.ndarray:
    """Floyd–Steinberg dither of an RGB or grey image to a palette: HxW uint8 indices.

    engine="exact": each corrected colour goes to its exactly nearest entry (lowest index on ties),
    wavefront-vectorised, equal to :func:`floyd_steinberg_reference`. engine="pillow": Pillow's C
    ``quantize(palette=..., dither=FLOYDSTEINBERG)``, far faster on big frames, but its colour cache
    resolves colours on a 6-bit-per-channel grid (not always the nearest entry) and its end-of-row
    error carry mixes channels, so results differ from the reference.
    """
    if not isinstance(palette, Palette):
        raise ConfigError(f"palette must be a Palette, found {type(palette).__name__}")
    pixels, rgb = _channels(image, "palette dithering")
    pixels = pixels if rgb else np.repeat(pixels, 3, axis=2)
    if engine == "pillow":
        return _pillow_palette_dither(np.ascontiguousarray(pixels), palette)
    if engine != "exact":
        raise ConfigError(f"unknown dithering engine {engine!r}: use 'exact' or 'pillow'")

    def choose(value: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        index = palette.nearest_rows(value)
        return palette.colours[index].astype(np.int64), index

    return _diffuse(pixels, choose, ()).astype(np.uint8)


def _pillow_palette_dither(rgb: np.ndarray, palette: Palette) -> np.ndarray:
    """Pillow's Floyd–Steinberg to ``palette``: HxW uint8 indices."""
    if rgb.size == 0:
        return np.zeros(rgb.shape[:2], dtype=np.uint8)
    target = Image.new("P", (1, 1))
    target.putpalette(palette.to_pillow())
    result = Image.fromarray(rgb, "RGB").quantize(palette=target, dither=Image.Dither.FLOYDSTEINBERG)
    return np.asarray(result, dtype=np.uint8)


def floyd_steinberg_reference(image: ArrayLike, nearest: Callable[[tuple[int, ...]], tuple[int, ...]]) -> np.ndarray:
    """Scalar textbook Floyd–Steinberg, for tests: ``nearest`` maps a corrected colour tuple to the shown one.

    A plain double loop over pixels with the arithmetic of the module doc; returns the shown
    colours, HxW for grey input and HxWxC otherwise (int64).
    """
    arr = np.asarray(image)
    grey = arr.ndim == 2
    pixels = arr[..., None] if grey else arr
    h, w, c = pixels.shape
    errors = [[[0] * c for _ in range(w)] for _ in range(h)]
    shown = np.zeros((h, w, c), dtype=np.int64)
    for y in range(h):
        for x in range(w):
            old = []
            for ch in range(c):
                e = errors[y][x][ch]
                correction = -((-e) // 16) if e < 0 else e // 16
                old.append(min(255, max(0, int(pixels[y, x, ch]) + correction)))
            new = nearest(tuple(old))
            shown[y, x] = new
            for ch in range(c):
                err = old[ch] - new[ch]
                if x + 1 < w:
                    errors[y][x + 1][ch] += 7 * err
                if y + 1 < h:
                    if x > 0:
                        errors[y + 1][x - 1][ch] += 3 * err
                    errors[y + 1][x][ch] += 5 * err
                    if x + 1 < w:
                        errors[y + 1][x + 1][ch] += err
    return shown[..., 0] if grey else shown

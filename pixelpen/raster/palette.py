"""Indexed colour: palettes of up to 256 RGB entries, named fixed palettes, exact nearest colour, quantisation."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from numpy.typing import ArrayLike
from PIL import Image

from pixelpen.errors import ConfigError
from pixelpen.raster.formats import as_rgb_image

_BLOCK_ELEMENTS = 1 << 16
"""Distances computed per step in nearest-colour mapping (pixels x entries): 256 KiB, stays in L2 cache
and keeps each matrix product small enough that OpenBLAS does not spin up threads."""

_DIRECT_PIXELS = 1 << 16
"""Above this many pixels, :meth:`Palette.nearest` resolves each distinct colour once through a 2²⁴ table."""

_EGA16 = (
    0x000000, 0x0000AA, 0x00AA00, 0x00AAAA, 0xAA0000, 0xAA00AA, 0xAA5500, 0xAAAAAA,
    0x555555, 0x5555FF, 0x55FF55, 0x55FFFF, 0xFF5555, 0xFF55FF, 0xFFFF55, 0xFFFFFF,
)
_XTERM16 = (
    0x000000, 0xCD0000, 0x00CD00, 0xCDCD00, 0x0000EE, 0xCD00CD, 0x00CDCD, 0xE5E5E5,
    0x7F7F7F, 0xFF0000, 0x00FF00, 0xFFFF00, 0x5C5CFF, 0xFF00FF, 0x00FFFF, 0xFFFFFF,
)


def _hex_colours(values: tuple[int, ...]) -> np.ndarray:
    """Nx3 uint8 from 0xRRGGBB integers."""
    v = np.array(values, dtype=np.uint32)
    return np.stack([(v >> 16) & 0xFF, (v >> 8) & 0xFF, v & 0xFF], axis=1).astype(np.uint8)


def _cube(levels: ArrayLike) -> np.ndarray:
    """All (r, g, b) over the given per-channel levels, red slowest: index = (r·n + g)·n + b."""
    lv = np.asarray(levels, dtype=np.uint8)
    r, g, b = np.meshgrid(lv, lv, lv, indexing="ij")
    return np.stack([r.ravel(), g.ravel(), b.ravel()], axis=1)


def _greys(n: int) -> np.ndarray:
    """n evenly spaced greys from black to white (k·255/(n−1), exact for n = 2, 4, 16)."""
    v = np.arange(n) * 255 // (n - 1)
    return np.stack([v, v, v], axis=1).astype(np.uint8)


def _rgb332() -> np.ndarray:
    """The 256 RGB332 colours, index = the RGB332 byte RRRGGGBB, fields widened by bit replication."""
    i = np.arange(256)
    r3, g3, b2 = i >> 5, (i >> 2) & 7, i & 3
    widened = [(r3 << 5) | (r3 << 2) | (r3 >> 1), (g3 << 5) | (g3 << 2) | (g3 >> 1), b2 * 0x55]
    return np.stack(widened, axis=1).astype(np.uint8)


def _xterm256() -> np.ndarray:
    """xterm's 256-colour table: 16 system colours, a 6x6x6 cube, 24 greys."""
    greys = 8 + 10 * np.arange(24)
    return np.concatenate([
        _hex_colours(_XTERM16),
        _cube([0, 95, 135, 175, 215, 255]),
        np.stack([greys, greys, greys], axis=1).astype(np.uint8),
    ])


NAMED_PALETTES: dict[str, str] = {
    "mono": "black, white",
    "grey4": "4 greys 0, 85, 170, 255 (2-bit grey)",
    "grey16": "16 greys k·17 (4-bit grey, e.g. SSD1322/SSD1327 OLEDs)",
    "ega16": "IBM CGA/EGA default 16 colours (RGBI, brown at 6; IBM EGA Technical Reference)",
    "web216": "6x6x6 cube, levels 0x00..0xFF in steps of 0x33, index 36r+6g+b (Netscape web-safe)",
    "rgb332": "256 colours, index = RGB332 byte RRRGGGBB, fields widened by bit replication",
    "xterm256": "xterm 256 colours: 16 system, 6x6x6 cube (0,95,135,175,215,255), 24 greys 8+10k (256colres.pl)",
}
"""The fixed palettes :meth:`Palette.named` knows, with what they are and where they come from."""

_BUILDERS = {
    "mono": lambda: _greys(2),
    "grey4": lambda: _greys(4),
    "grey16": lambda: _greys(16),
    "ega16": lambda: _hex_colours(_EGA16),
    "web216": lambda: _cube(np.arange(6) * 0x33),
    "rgb332": _rgb332,
    "xterm256": _xterm256,
}


def _colour_codes(rgb: np.ndarray) -> np.ndarray:
    """(P, 3) uint8 colours as int32 codes 0xRRGGBB."""
    return (rgb[:, 0].astype(np.int32) << 16) | (rgb[:, 1].astype(np.int32) << 8) | rgb[:, 2]


def _decode_colours(codes: np.ndarray) -> np.ndarray:
    """int 0xRRGGBB codes back to (P, 3) uint8 colours."""
    return np.stack([codes >> 16, (codes >> 8) & 0xFF, codes & 0xFF], axis=1).astype(np.uint8)


class Palette:
    """An ordered table of 1..256 RGB colours; maps images to indices (exact nearest) and back."""

    def __init__(self, colours: ArrayLike, name: str | None = None) -> None:
        arr = np.asarray(colours)
        if arr.ndim != 2 or arr.shape[1] != 3 or not 1 <= arr.shape[0] <= 256:
            raise ConfigError(f"a palette needs 1..256 (r, g, b) entries as an Nx3 array, found shape {arr.shape}")
        if arr.dtype.kind not in "iu" or arr.min() < 0 or arr.max() > 255:
            raise ConfigError(f"palette entries must be integers 0..255, found {arr.dtype} values")
        self._colours = arr.astype(np.uint8)
        self._colours.flags.writeable = False
        entries = self._colours.astype(np.float32)
        self._distance_table = np.concatenate([-2.0 * entries.T, (entries**2).sum(axis=1)[None, :]])
        """(4, N): [p, 1] @ table = |c|² − 2·p·c, the squared distance less the per-pixel |p|²."""
        self.name = name

    @classmethod
    def named(cls, name: str) -> Palette:
        """One of the fixed palettes in :data:`NAMED_PALETTES`."""
        if name not in _BUILDERS:
            raise ConfigError(f"unknown palette {name!r}: use one of {', '.join(NAMED_PALETTES)}")
        return cls(_BUILDERS[name](), name=name)

    @property
    def colours(self) -> np.ndarray:
        """The entries as a read-only Nx3 uint8 array."""
        return self._colours

    def __len__(self) -> int:
        """Number of entries."""
        return self._colours.shape[0]

    def __getitem__(self, index: int) -> tuple[int, int, int]:
        """Entry ``index`` as an (r, g, b) tuple."""
        r, g, b = (int(c) for c in self._colours[index])
        return (r, g, b)

    def __iter__(self) -> Iterator[tuple[int, int, int]]:
        """The entries in order, as (r, g, b) tuples."""
        return (self[i] for i in range(len(self)))

    def __eq__(self, other: object) -> bool:
        """Equal when the entries are equal, in the same order (the name does not count)."""
        return isinstance(other, Palette) and np.array_equal(self._colours, other._colours)

    def __hash__(self) -> int:
        """Hash of the entries, consistent with ``==``."""
        return hash(self._colours.tobytes())

    def __repr__(self) -> str:
        """``<Palette 'name' of N colours>``."""
        label = f" {self.name!r}" if self.name else ""
        return f"<Palette{label} of {len(self)} colours>"

    def nearest_rows(self, pixels: ArrayLike) -> np.ndarray:
        """Indices (intp) of the nearest entries for a (P, 3) array of colours; ties go to the lowest index.

        Squared Euclidean RGB distance, as |c|² − 2·p·c per entry (|p|² is common to all entries);
        every term is an integer below 2²⁴, so float32 arithmetic is exact. Blocks of pixels bound memory.
        """
        rows = np.asarray(pixels)
        if rows.ndim != 2 or rows.shape[1] != 3:
            raise ConfigError(f"colours to match must have shape (P, 3), found {rows.shape}")
        out = np.empty(rows.shape[0], dtype=np.intp)
        block = max(1, _BLOCK_ELEMENTS // len(self))
        operand = np.ones((min(block, rows.shape[0]), 4), dtype=np.float32)
        for start in range(0, rows.shape[0], block):
            part = operand[: min(block, rows.shape[0] - start)]
            part[:, :3] = rows[start:start + block]
            out[start:start + part.shape[0]] = np.argmin(part @ self._distance_table, axis=1)
        return out

    def nearest(self, image: ArrayLike) -> np.ndarray:
        """Index image (HxW uint8) of the exactly nearest entry for each pixel of an RGB, grey or bitmap image.

        Large images resolve each distinct colour once, through a 2²⁴-entry table.
        """
        rgb = as_rgb_image(image, "nearest-colour mapping")
        flat = rgb.reshape(-1, 3)
        if flat.shape[0] <= _DIRECT_PIXELS:
            return self.nearest_rows(flat).astype(np.uint8).reshape(rgb.shape[:2])
        codes = _colour_codes(flat)
        seen = np.zeros(1 << 24, dtype=bool)
        seen[codes] = True
        distinct = np.flatnonzero(seen)
        table = np.zeros(1 << 24, dtype=np.uint8)
        table[distinct] = self.nearest_rows(_decode_colours(distinct))
        return table[codes].reshape(rgb.shape[:2])

    def lookup(self, indices: ArrayLike) -> np.ndarray:
        """RGB image (shape + (3,), uint8) of an index array; an index outside the palette is a ConfigError."""
        idx = np.asarray(indices)
        if idx.dtype.kind not in "iu":
            raise ConfigError(f"palette indices must be integers, found {idx.dtype}")
        bad = (idx < 0) | (idx >= len(self))
        if bad.any():
            where = tuple(int(i) for i in np.argwhere(bad)[0])
            raise ConfigError(f"palette index {int(idx[where])} at {where} outside 0..{len(self) - 1}")
        return self._colours[idx]

    def to_pillow(self) -> list[int]:
        """The flat [r0, g0, b0, r1, ...] list Pillow's ``Image.putpalette`` takes."""
        return [int(v) for v in self._colours.ravel()]


_PILLOW_METHODS = {
    "mediancut": Image.Quantize.MEDIANCUT,
    "maxcoverage": Image.Quantize.MAXCOVERAGE,
    "octree": Image.Quantize.FASTOCTREE,
}
QUANTIZE_METHODS = (*_PILLOW_METHODS, "kmeans")
"""The palette-choosing methods :func:`quantize` offers."""


def _kmeans(rgb: np.ndarray, seed: Palette, iterations: int) -> Palette:
    """Lloyd's k-means over the distinct colours of (P, 3) ``rgb`` weighted by pixel count, from ``seed``.

    Centres are rounded to integers each round (the best integer centre of a cluster, so the summed
    squared error never grows); a cluster that loses all its colours keeps its centre. Stops when
    the palette no longer changes or after ``iterations`` rounds.
    """
    codes, counts = np.unique(_colour_codes(rgb), return_counts=True)
    colours = _decode_colours(codes)
    weighted = colours.astype(np.float64) * counts[:, None]
    palette = seed
    for _ in range(iterations):
        labels = palette.nearest_rows(colours)
        size = np.bincount(labels, weights=counts, minlength=len(palette))
        sums = np.stack([np.bincount(labels, weights=weighted[:, c], minlength=len(palette)) for c in range(3)], 1)
        centres = np.where(size[:, None] > 0, np.floor(sums / np.maximum(size, 1)[:, None] + 0.5), palette.colours)
        updated = Palette(centres.astype(np.uint8), name=seed.name)
        if updated == palette:
            break
        palette = updated
    return palette


def quantize(
    image: ArrayLike, n: int, method: str = "mediancut", *, iterations: int = 16
) -> tuple[np.ndarray, Palette]:
    """Choose a palette of at most ``n`` (1..256) colours for an RGB or grey image; return (indices, palette).

    "mediancut" (Heckbert), "maxcoverage" and "octree" (fast octree) are Pillow's quantisers;
    "kmeans" refines the median-cut palette by Lloyd's algorithm (at most ``iterations`` rounds).
    Indices are the exact nearest entries (:meth:`Palette.nearest`), never a dithered mapping;
    dither with :func:`pixelpen.raster.dither.floyd_steinberg_palette` if wanted. Cost grows with
    the number of distinct colours: about 3 s for a 1080p frame of random noise.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= 256:
        raise ConfigError(f"the number of colours must be an integer 1..256, found {n!r}")
    if method not in QUANTIZE_METHODS:
        raise ConfigError(f"unknown quantize method {method!r}: use one of {', '.join(QUANTIZE_METHODS)}")
    rgb = np.ascontiguousarray(as_rgb_image(image, "quantize"))
    if rgb.size == 0:
        raise ConfigError(f"cannot quantize an empty {rgb.shape[1]}x{rgb.shape[0]} image")
    quantized = Image.fromarray(rgb, "RGB").quantize(
        colors=int(n), method=_PILLOW_METHODS.get(method, Image.Quantize.MEDIANCUT), dither=Image.Dither.NONE
    )
    entries = np.asarray((quantized.getpalette() or [])[: 3 * n], dtype=np.uint8).reshape(-1, 3)
    palette = Palette(entries, name=f"{method}{n}")
    if method == "kmeans":
        palette = _kmeans(rgb.reshape(-1, 3), palette, iterations)
    return palette.nearest(rgb), palette

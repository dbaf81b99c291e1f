"""Canvas: a numpy framebuffer in one pixel mode, with batch drawing operations and damage tracking.

Pixel ``(0, 0)`` is the top-left, y grows downwards, and integer coordinates are pixel centres (see
:mod:`pixelpen.raster.lines` and :mod:`pixelpen.raster.polygons` for the exact rules).  Every drawing
method takes a whole batch of primitives and one ``value`` - the mode's native pixel value - and records
the bounding box of what it drew (clipped to the canvas) for :meth:`Canvas.damage`.

Modes and their native values:

======== ============================= ==============================================================
mode     ``canvas.array``              value
======== ============================= ==============================================================
"1"      HxW uint8, 0 or 1             0 or 1
"L"      HxW uint8                     0..255 grey
"P"      HxW uint8 palette indices     0..255 index into ``canvas.palette`` ((256, 3) uint8)
"RGB565" HxW uint16                    ``((r & 0xF8) << 8) | ((g & 0xFC) << 3) | (b >> 3)``
"RGB"    HxWx3 uint8                   (r, g, b)
"RGBA"   HxWx4 uint8                   (r, g, b, a) - or (r, g, b), meaning a = 255
======== ============================= ==============================================================
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from PIL import Image

from pixelpen.errors import ConfigError
from pixelpen.raster import antialias as wu
from pixelpen.raster import circles, fill, lines, polygons
from pixelpen.raster.colour import rgb565_to_rgb888
from pixelpen.raster.damage import DEFAULT_MERGE_COST, DamageTracker, Rect, tile_damage
from pixelpen.raster.palette import Palette

MODES: dict[str, tuple[type, int]] = {
    "1": (np.uint8, 1), "L": (np.uint8, 1), "P": (np.uint8, 1), "RGB565": (np.uint16, 1),
    "RGB": (np.uint8, 3), "RGBA": (np.uint8, 4),
}
"""mode -> (dtype, channels)."""

_BYTES_PER_PIXEL = {"1": 0.125, "L": 1.0, "P": 1.0, "RGB565": 2.0, "RGB": 3.0, "RGBA": 4.0}
_MAX_SIDE = 1 << 16
CAPS = ("square", "butt", "round")


def _dash_table(dash: Sequence[int]) -> tuple[np.ndarray, int]:
    """(on-table indexed by step % period, period) from on/off pixel counts, or ConfigError."""
    try:
        counts = [int(c) for c in dash]
    except (TypeError, ValueError):
        raise ConfigError(f"dash must be a sequence of on/off pixel counts, found {dash!r}") from None
    if len(counts) < 2 or len(counts) % 2 or min(counts) < 0 or sum(counts) == 0 or counts != list(dash):
        raise ConfigError(f"dash must be an even-length sequence of counts >= 0 with a positive sum, found {dash!r}")
    on = np.repeat(np.arange(len(counts)) % 2 == 0, counts)
    return on, int(on.shape[0])


class Canvas:
    """A width x height framebuffer (``canvas.array``) in one of :data:`MODES`, drawn in batches."""

    def __init__(self, width: int, height: int, mode: str = "L", palette: ArrayLike | None = None, *,
                 merge_cost: float = DEFAULT_MERGE_COST, bytes_per_pixel: float | None = None) -> None:
        if mode not in MODES:
            raise ConfigError(f"unknown canvas mode {mode!r}: use one of {', '.join(MODES)}")
        for name, v in (("width", width), ("height", height)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 1 <= v <= _MAX_SIDE:
                raise ConfigError(f"canvas {name} must be an integer 1..{_MAX_SIDE}, found {v!r}")
        self.mode = mode
        dtype, channels = MODES[mode]
        shape = (int(height), int(width)) + ((channels,) if channels > 1 else ())
        self.array: np.ndarray = np.zeros(shape, dtype=dtype)
        self.palette = self._make_palette(palette)
        bpp = _BYTES_PER_PIXEL[mode] if bytes_per_pixel is None else bytes_per_pixel
        self._damage = DamageTracker(int(width), int(height), merge_cost, bpp)

    def _make_palette(self, palette: Any) -> np.ndarray | None:
        """The (256, 3) uint8 palette for mode "P" (shorter palettes padded with black; default greys)."""
        if self.mode != "P":
            if palette is not None:
                raise ConfigError(f"a palette is only used in mode 'P', not {self.mode!r}")
            return None
        if palette is None:
            return np.repeat(np.arange(256, dtype=np.uint8)[:, None], 3, axis=1)
        arr = np.asarray(getattr(palette, "colours", palette))
        if arr.ndim != 2 or arr.shape[1] != 3 or not 1 <= arr.shape[0] <= 256 or arr.dtype.kind not in "iu":
            raise ConfigError(f"palette must be 1..256 (r, g, b) integer entries, found shape {arr.shape} {arr.dtype}")
        if arr.min() < 0 or arr.max() > 255:
            raise ConfigError("palette entries must be in 0..255")
        out = np.zeros((256, 3), dtype=np.uint8)
        out[: arr.shape[0]] = arr
        return out

    @classmethod
    def from_array(cls, array: np.ndarray, mode: str, palette: ArrayLike | None = None, **kwargs: Any) -> Canvas:
        """A canvas holding a copy of an existing array of the mode's dtype and shape."""
        if mode not in MODES:
            raise ConfigError(f"unknown canvas mode {mode!r}: use one of {', '.join(MODES)}")
        arr = np.asarray(array)
        if arr.ndim < 2:
            raise ConfigError(f"array must be HxW or HxWxC, found shape {arr.shape}")
        canvas = cls(arr.shape[1], arr.shape[0], mode, palette, **kwargs)
        canvas._check_same_mode(arr, "array")
        canvas.array[...] = arr
        return canvas

    # ----------------------------------------------------------------- basics
    @property
    def width(self) -> int:
        """Columns."""
        return int(self.array.shape[1])

    @property
    def height(self) -> int:
        """Rows."""
        return int(self.array.shape[0])

    @property
    def size(self) -> tuple[int, int]:
        """(width, height)."""
        return self.width, self.height

    def __repr__(self) -> str:
        return f"Canvas({self.width}, {self.height}, mode={self.mode!r})"

    def _check_same_mode(self, arr: np.ndarray, what: str) -> None:
        """ConfigError unless arr has this mode's dtype and channel layout."""
        dtype, channels = MODES[self.mode]
        ok = arr.dtype == dtype and (arr.ndim == 2 if channels == 1 else (arr.ndim == 3 and arr.shape[2] == channels))
        if not ok:
            raise ConfigError(f"{what} must be {'HxW' if channels == 1 else f'HxWx{channels}'} {np.dtype(dtype).name} "
                              f"for mode {self.mode!r}, found shape {arr.shape} {arr.dtype}")
        if self.mode == "1" and arr.size and arr.max() > 1:
            raise ConfigError(f"{what} for mode '1' must hold only 0 and 1")

    def value(self, value: object) -> np.ndarray:
        """Validate a native pixel value: a 0-d array (single-channel modes) or a (C,) array."""
        _, channels = MODES[self.mode]
        if channels == 1:
            top = {"1": 1, "L": 255, "P": 255, "RGB565": 0xFFFF}[self.mode]
            if isinstance(value, (int, np.integer)) and 0 <= int(value) <= top:
                return np.array(int(value), dtype=MODES[self.mode][0])
            raise ConfigError(f"mode {self.mode!r} takes an integer value 0..{top}, found {value!r}")
        if isinstance(value, (tuple, list, np.ndarray)):
            parts = list(value)
            if self.mode == "RGBA" and len(parts) == 3:
                parts.append(255)
            if len(parts) == channels and all(isinstance(p, (int, np.integer)) and 0 <= int(p) <= 255 for p in parts):
                return np.array([int(p) for p in parts], dtype=np.uint8)
        raise ConfigError(f"mode {self.mode!r} takes an ({'r, g, b' if channels == 3 else 'r, g, b[, a]'}) tuple "
                          f"of 0..255, found {value!r}")

    def colour_value(self, rgb: Sequence[int]) -> int | tuple[int, ...]:
        """The native value nearest an (r, g, b) colour (see :meth:`colour_values` for the rules)."""
        try:
            r, g, b = (int(c) for c in rgb)
        except (TypeError, ValueError):
            raise ConfigError(f"colour must be an (r, g, b) triple, found {rgb!r}") from None
        if not all(0 <= c <= 255 for c in (r, g, b)) or list(rgb) != [r, g, b]:
            raise ConfigError(f"colour components must be integers 0..255, found {rgb!r}")
        value = self.colour_values(np.array([[r, g, b]]))[0]
        return tuple(int(c) for c in value) if value.ndim else int(value)

    def colour_values(self, rgb: ArrayLike) -> np.ndarray:
        """Native values nearest an (N, 3) array of 0..255 colours: (N,) or (N, C) in the canvas dtype.

        "L": luma (299R + 587G + 114B + 500) // 1000; "1": 1 iff 299R + 587G + 114B >= 128000;
        "P": the nearest palette entry (squared RGB distance, lowest index on ties); "RGB565": truncation;
        "RGB": the colour; "RGBA": the colour, opaque.
        """
        c = np.asarray(rgb, dtype=np.int64).reshape(-1, 3)
        dtype = MODES[self.mode][0]
        if self.mode in ("L", "1"):
            weighted = c @ np.array([299, 587, 114])
            out = (weighted + 500) // 1000 if self.mode == "L" else weighted >= 128000
            return out.astype(dtype)
        if self.mode == "P":
            assert self.palette is not None
            return Palette(self.palette).nearest_rows(c).astype(dtype)
        if self.mode == "RGB565":
            return (((c[:, 0] & 0xF8) << 8) | ((c[:, 1] & 0xFC) << 3) | (c[:, 2] >> 3)).astype(dtype)
        if self.mode == "RGB":
            return c.astype(dtype)
        return np.concatenate([c, np.full((len(c), 1), 255)], axis=1).astype(dtype)

    def put_colours(self, xs: ArrayLike, ys: ArrayLike, rgba: ArrayLike) -> None:
        """Composite (N, 4) RGBA colours "over" the pixels at (xs, ys) (inside the canvas), any mode."""
        xs, ys = np.asarray(xs, dtype=np.int64), np.asarray(ys, dtype=np.int64)
        src = np.asarray(rgba, dtype=np.uint32).reshape(-1, 4)
        if not (len(xs) == len(ys) == len(src)):
            raise ConfigError(f"put_colours needs as many colours as pixels, found {len(src)} for {len(xs)}")
        if not len(xs):
            return
        if xs.min() < 0 or ys.min() < 0 or xs.max() >= self.width or ys.max() >= self.height:
            raise ConfigError(f"put_colours: a pixel lies outside the {self.width}x{self.height} canvas")
        alpha = src[:, 3:4]
        base = self.to_rgb()[ys, xs].astype(np.uint32)
        mixed = (src[:, :3] * alpha + base * (255 - alpha) + 127) // 255
        self.array[ys, xs] = self.colour_values(mixed)
        self._damage.add(int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)

    def pixel(self, x: int, y: int) -> int | tuple[int, ...]:
        """The native value at (x, y)."""
        if not (0 <= x < self.width and 0 <= y < self.height):
            raise ConfigError(f"pixel ({x}, {y}) is outside the {self.width}x{self.height} canvas")
        v = self.array[y, x]
        return tuple(int(c) for c in v) if self.array.ndim == 3 else int(v)

    def fill(self, value: object) -> None:
        """Set every pixel to value."""
        self.array[...] = self.value(value)
        self._damage.add_all()

    def to_rgb(self) -> np.ndarray:
        """HxWx3 uint8 RGB: the array itself for "RGB", a view for "RGBA", a converted copy otherwise.

        "1" -> 0/255 greys, "L" -> greys, "P" -> palette colours, "RGB565" -> bit-replicated 8-bit channels.
        """
        a = self.array
        if self.mode == "RGB":
            return a
        if self.mode == "RGBA":
            return a[..., :3]
        if self.mode == "RGB565":
            return rgb565_to_rgb888(a)
        if self.mode == "P":
            assert self.palette is not None
            return self.palette[a]
        grey = a * np.uint8(255) if self.mode == "1" else a
        return np.repeat(grey[..., None], 3, axis=2)

    def to_image(self) -> Image.Image:
        """A Pillow Image of the canvas that owns its pixels (never shares memory with ``canvas.array``)."""
        size = (self.width, self.height)
        if self.mode == "1":
            return Image.frombytes("1", size, np.packbits(self.array.astype(bool), axis=1).tobytes())
        if self.mode in ("L", "RGB", "RGBA"):
            return Image.frombytes(self.mode, size, self.array.tobytes())
        if self.mode == "P":
            assert self.palette is not None
            image = Image.frombytes("P", size, self.array.tobytes())
            image.putpalette(self.palette.tobytes())
            return image
        return Image.frombytes("RGB", size, np.ascontiguousarray(self.to_rgb()).tobytes())

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the canvas as a PNG file (flushed and closed on return)."""
        image = self.to_image()
        with open(path, "wb") as f:
            image.save(f, format="PNG")
            f.flush()

    def copy(self) -> Canvas:
        """An independent canvas with the same mode, pixels, palette, settings and damage."""
        other = Canvas.__new__(Canvas)
        other.mode = self.mode
        other.array = self.array.copy()
        other.palette = None if self.palette is None else self.palette.copy()
        other._damage = self._damage.copy()
        return other

    def blit(self, array: np.ndarray, x: int, y: int) -> None:
        """Paste a same-mode array with its top-left at (x, y), clipped to the canvas."""
        arr = np.asarray(array)
        self._check_same_mode(arr, "blit source")
        x, y = int(x), int(y)
        x0, y0 = max(x, 0), max(y, 0)
        x1, y1 = min(x + arr.shape[1], self.width), min(y + arr.shape[0], self.height)
        if x1 <= x0 or y1 <= y0:
            return
        self.array[y0:y1, x0:x1] = arr[y0 - y:y1 - y, x0 - x:x1 - x]
        self._damage.add(x0, y0, x1, y1)

    # ----------------------------------------------------------------- drawing
    def lines(self, segments: ArrayLike, value: object, width: int = 1, dash: Sequence[int] | None = None,
              antialias: bool = False, cap: str = "square") -> None:
        """Draw an (N, 4) batch of segments x0, y0, x1, y1.

        width 1: pixel-identical to :func:`~pixelpen.raster.lines.bresenham` (integer endpoints), clipped to
        the canvas.  ``dash``: on/off pixel counts along the major axis, restarting at each segment.
        ``antialias``: Wu lines blended by coverage (modes "L", "RGB", "RGBA"; float endpoints allowed).
        width > 1: each segment is stroked as a polygon - the rectangle ``width`` wide centred on the
        segment, extended by width/2 at both ends for ``cap="square"``, not extended for "butt", with a
        disc (regular polygon) at each end for "round" - and scan-converted by the polygon rule; dashes of
        a thick line are butt-ended pieces covering their on-pixels along the major axis.
        """
        self._lines(segments, value, width, dash, antialias, cap, None)

    def _lines(self, segments: ArrayLike, value: object, width: int, dash: Sequence[int] | None, antialias: bool,
               cap: str, phase: np.ndarray | None) -> None:
        """lines() with an optional per-segment dash phase (for polylines)."""
        v = self.value(value)
        table = None if dash is None else _dash_table(dash)
        if isinstance(width, bool) or not isinstance(width, (int, np.integer)) or width < 1:
            raise ConfigError(f"line width must be an integer >= 1, found {width!r}")
        if cap not in CAPS:
            raise ConfigError(f"unknown cap {cap!r}: use one of {', '.join(CAPS)}")
        if antialias:
            if self.mode not in ("L", "RGB", "RGBA"):
                raise ConfigError(f"anti-aliased lines need mode 'L', 'RGB' or 'RGBA', not {self.mode!r}")
            if width != 1:
                raise ConfigError(f"anti-aliased lines are 1 px wide; width={width} is not supported")
            pixels, cover = wu.wu_coverage(segments, self.width, self.height, table)
            wu.blend(self.array, pixels, cover, v)
            if pixels.size:
                ys, xs = np.divmod(pixels, self.width)
                self._damage.add(int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)
            return
        if width > 1:
            seg = lines.as_int_array(segments, 4, "segments")
            tris = lines.stroke_triangles(seg, int(width), cap, self.width, self.height, table, phase)
            self._triangles(tris, v)
            return
        runs = lines.LineRuns.clip(segments, self.width, self.height)
        box = runs.bbox()
        if box is None:
            return
        if table is None:
            runs.draw(self.array, v)
        else:
            on, period = table
            x, y, step, run = runs.pixels()
            if phase is not None:
                step = step + phase[runs.segment][run]
            keep = on[step % period]
            self._flat()[y[keep] * self.width + x[keep]] = v
        self._damage.add(*box)

    def polyline(self, points: ArrayLike, value: object, width: int = 1, dash: Sequence[int] | None = None,
                 antialias: bool = False, closed: bool = False, cap: str = "square") -> None:
        """Draw connected segments through (N, 2) points (closing back to the first if ``closed``).

        The dash pattern runs on across vertices; options as for :meth:`lines`.
        """
        pts = np.asarray(points, dtype=np.float64) if antialias else lines.as_int_array(points, 2, "points")
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise ConfigError(f"points must be an (N, 2) array, found shape {pts.shape}")
        if closed and pts.shape[0] > 1:
            pts = np.vstack([pts, pts[:1]])
        if pts.shape[0] == 1:
            pts = np.vstack([pts, pts])
        seg = np.hstack([pts[:-1], pts[1:]])
        phase = None
        if dash is not None and not antialias:
            steps = np.abs(seg[:, 2:] - seg[:, :2]).max(axis=1)
            phase = np.cumsum(steps) - steps
        self._lines(seg, value, width, dash, antialias, cap, phase)

    def circles(self, centers: ArrayLike, radii: ArrayLike, value: object, fill: bool = False) -> None:
        """Draw midpoint circles (outline, or filled spans between the outline's extreme pixels per row)."""
        v = self.value(value)
        c = circles.as_centres(centers, "centers")
        r = circles.as_radii(radii, c.shape[0], "radii")
        if fill:
            owner, dy, half = circles.circle_rows(r)
            row = np.concatenate([c[owner, 1] + dy, c[owner, 1] - dy])
            centre = np.concatenate([c[owner, 0], c[owner, 0]])
            half = np.concatenate([half, half])
            self._spans(row, centre - half, centre + half + 1, v, self._inside(c, r, r))
        else:
            owner, x, y = circles.circle_octant(r)
            self._outline(c, owner, x, y, True, v, self._inside(c, r, r))
        self._curve_damage(c, r, r)

    def ellipses(self, centers: ArrayLike, rx: ArrayLike, ry: ArrayLike, value: object, fill: bool = False) -> None:
        """Draw axis-aligned midpoint ellipses with radii rx, ry (outline or filled)."""
        v = self.value(value)
        c = circles.as_centres(centers, "centers")
        a = circles.as_radii(rx, c.shape[0], "rx")
        b = circles.as_radii(ry, c.shape[0], "ry")
        owner, x, y = circles.ellipse_quadrant(a, b)
        inside = self._inside(c, a, b)
        if fill:
            self._spans(*circles.symmetric_spans(c, owner, x, y, False), v, inside)
        else:
            self._outline(c, owner, x, y, False, v, inside)
        self._curve_damage(c, a, b)

    def _inside(self, c: np.ndarray, rx: np.ndarray, ry: np.ndarray) -> bool:
        """Whether every curve's box lies on the canvas (then nothing needs clipping)."""
        inside = (c[:, 0] >= rx) & (c[:, 1] >= ry) & (c[:, 0] + rx < self.width) & (c[:, 1] + ry < self.height)
        return bool(inside.all())

    def _curve_damage(self, c: np.ndarray, rx: np.ndarray, ry: np.ndarray) -> None:
        """Record the clipped bounding box of all curves."""
        if c.shape[0]:
            self._damage.add(
                int((c[:, 0] - rx).min()),
                int((c[:, 1] - ry).min()),
                int((c[:, 0] + rx).max()) + 1,
                int((c[:, 1] + ry).max()) + 1,
            )

    def _spans(self, row: np.ndarray, start: np.ndarray, end: np.ndarray, v: np.ndarray, inside: bool) -> None:
        """Paint spans (clipping them unless all lie on the canvas)."""
        if not inside:
            keep = (row >= 0) & (row < self.height)
            row, start, end = row[keep], np.clip(start[keep], 0, self.width), np.clip(end[keep], 0, self.width)
        stride = self.width + 1
        polygons.paint_cells(self.array, row * stride + start, row * stride + end, v)

    def _outline(
        self, c: np.ndarray, owner: np.ndarray, x: np.ndarray, y: np.ndarray, octants: bool, v: np.ndarray, inside: bool
    ) -> None:
        """Scatter the symmetric images of curve points (flat indices directly when nothing is clipped)."""
        if inside:
            w = self.width
            base = c[owner, 1] * w + c[owner, 0]
            pairs = [(x, y * w), (y, x * w)] if octants else [(x, y * w)]
            idx = np.empty(4 * len(pairs) * x.shape[0], dtype=np.int64)
            k = 0
            for along, across in pairs:
                for rows in (base + across, base - across):
                    for sign in (1, -1):
                        np.add(rows, along if sign > 0 else -along, out=idx[k * x.shape[0] : (k + 1) * x.shape[0]])
                        k += 1
            self._flat()[idx] = v
            return
        px, py = circles.symmetric_points(c, owner, x, y, octants)
        keep = (px >= 0) & (px < self.width) & (py >= 0) & (py < self.height)
        self._flat()[py[keep] * self.width + px[keep]] = v

    def polygons(self, polys: object, value: object, rule: str = "evenodd") -> None:
        """Fill polygons (each a ring or a list of rings of (N, 2) float vertices) by the scan-line rule.

        An (M, 3, 2) array of triangles takes the :meth:`triangles` fast path (same pixels).
        """
        v = self.value(value)
        if rule not in polygons.RULES:
            raise ConfigError(f"unknown fill rule {rule!r}: use one of {', '.join(polygons.RULES)}")
        if isinstance(polys, np.ndarray) and polys.ndim == 3 and polys.shape[1:] == (3, 2):
            self._triangles(polys, v)
            return
        row, start, end = polygons.polygon_spans(polys, self.width, self.height, rule)
        drawn = polygons.paint_spans(self.array, row, start, end, v)
        if drawn is not None:
            self._damage.add(*drawn)

    def triangles(self, tris: ArrayLike, value: object) -> None:
        """Fill an (N, 3, 2) batch of triangles (pixel rule of :meth:`polygons`, no sort)."""
        self._triangles(tris, self.value(value))

    def _triangles(self, tris: ArrayLike, v: np.ndarray) -> None:
        """Fill triangles with a validated value and record their clipped vertex bounds as damage."""
        t = polygons.as_triangles(tris)
        if t.shape[0] == 0:
            return
        starts, ends = polygons.triangle_cells(t, self.width, self.height)
        if starts.size == 0:
            return
        polygons.paint_cells(self.array, starts, ends, v)
        lo = np.floor(t.reshape(-1, 2).min(axis=0))
        hi = np.ceil(t.reshape(-1, 2).max(axis=0)) + 1
        self._damage.add(
            int(max(lo[0], 0)), int(max(lo[1], 0)), int(min(hi[0], self.width)), int(min(hi[1], self.height))
        )

    def flood_fill(self, seed: Sequence[int], value: object, connectivity: int = 4) -> int:
        """Replace the connected region of the seed pixel's value (4- or 8-connected); returns pixels filled."""
        v = self.value(value)
        x, y = fill.check_seed(seed, self.width, self.height)
        old = self.array[y, x].copy()
        if np.array_equal(old, v):
            fill.check_connectivity(connectivity)
            return 0
        return self._fill_region(fill.equal_mask(self.array, old), (x, y), v, connectivity)

    def boundary_fill(self, seed: Sequence[int], value: object, boundary: object, connectivity: int = 4) -> int:
        """Fill outwards from seed until pixels of value ``boundary`` (or already ``value``); returns pixels filled."""
        v = self.value(value)
        b = self.value(boundary)
        x, y = fill.check_seed(seed, self.width, self.height)
        fillable = ~fill.equal_mask(self.array, b) & ~fill.equal_mask(self.array, v)
        return self._fill_region(fillable, (x, y), v, connectivity)

    def _fill_region(self, fillable: np.ndarray, seed: tuple[int, int], v: np.ndarray, connectivity: int) -> int:
        """Set the component of fillable containing seed to v; record its bounding box."""
        found = fill.connected_region(fillable, seed, fill.check_connectivity(connectivity))
        if found is None:
            return 0
        (rows, cols), mask = found
        self.array[rows, cols][mask] = v
        self._damage.add(cols.start, rows.start, cols.stop, rows.stop)
        return int(np.count_nonzero(mask))

    def _flat(self) -> np.ndarray:
        """The array as (H·W,) or (H·W, C) for scattering flat pixel indices."""
        return self.array.reshape(self.height * self.width, -1) if self.array.ndim == 3 else self.array.reshape(-1)

    # ----------------------------------------------------------------- damage
    def damage(self, merge_cost: float | None = None) -> list[Rect]:
        """Half-open rectangles changed since :meth:`clear_damage`, merged by the cost model (see damage.py)."""
        return self._damage.rects(merge_cost)

    def clear_damage(self) -> None:
        """Forget the recorded damage (call after the changes were sent)."""
        self._damage.clear()

    def mark_damaged(self, x0: int = 0, y0: int = 0, x1: int | None = None, y1: int | None = None) -> None:
        """Record a box as changed (for writes made to ``canvas.array`` directly); default the whole canvas."""
        self._damage.add(x0, y0, self.width if x1 is None else x1, self.height if y1 is None else y1)

    def damage_from(self, previous: np.ndarray, tile: int | tuple[int, int] = 16) -> list[Rect]:
        """Tile-aligned rectangles where ``canvas.array`` differs from a previous frame (vectorised compare)."""
        return tile_damage(
            self.array, np.asarray(previous), tile, self._damage.merge_cost, self._damage.bytes_per_pixel
        )

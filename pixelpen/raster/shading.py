"""Shading z-buffer fragments (flat, Gouraud, Phong; Hearn & Baker §14-5) and writing intensities to a canvas.

:func:`shade` lights the fragments :class:`pixelpen.raster.zbuffer.Fragments` of a triangle mesh with the
model of :mod:`pixelpen.raster.illumination`, in world coordinates (a :class:`Shader` does the per-mesh part
once, for a renderer that shades many sets of fragments of one mesh):

* ``"flat"``: one evaluation per face, at its centroid with its face normal;
* ``"gouraud"``: one evaluation per vertex with its vertex normal, intensities interpolated across the face
  by the fragments' (perspective-correct) barycentric weights;
* ``"phong"``: normals and positions interpolated per fragment, normals renormalised, one evaluation each.

Default face normals are the unit normals (v1 − v0) × (v2 − v0) of counter-clockwise faces; default vertex
normals are the area-weighted sums of the adjacent faces' normals, renormalised.

:func:`write_colours` maps intensities in [0, 1] to the canvas's pixel mode: each channel to the 8-bit value
round(255·c) (clamped), then to the native value by the rules of :meth:`Canvas.colour_values` ("RGB565" by
truncation, :func:`pixelpen.raster.colour.rgb888_to_rgb565`; "L" by BT.601 :func:`pixelpen.raster.colour.luma`),
except "1": ordered 4x4 Bayer dithering of that luma (:func:`pixelpen.raster.dither.ordered_mono`, frame-anchored) and
"P" by ordered dithering to the palette: each channel is offset by g·((M + ½)/16 − ½), M the Bayer index of
the pixel and g the largest gap between the distinct values the palette uses in that channel, before the
nearest palette entry is taken (:func:`native_pixels` converts without writing, and may run on threads for
disjoint pixels; :meth:`NativePixels.store` writes). Each pixel should appear once per call (of repeated
ones, which write wins is unspecified); the bounding box of the pixels written is recorded as damage.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.geometry.mesh import Mesh
from pixelpen.geometry.transforms import ArrayLike
from pixelpen.geometry.transforms3d import as_choice, as_points3d
from pixelpen.raster.canvas import Canvas
from pixelpen.raster.colour import luma, rgb888_to_rgb565
from pixelpen.raster.dither import bayer_matrix, ordered_mono
from pixelpen.raster.illumination import Light, Material, Viewer, as_colours, combine, illumination_terms
from pixelpen.raster.palette import Palette
from pixelpen.raster.zbuffer import Fragments, Interpolant

Box = tuple[int, int, int, int]

SHADING_MODES: tuple[str, ...] = ("flat", "gouraud", "phong")
"""The modes :func:`shade` offers."""

BAYER_SIZE = 4
"""Side of the Bayer matrix :func:`write_colours` dithers with on "1" and "P" canvases (17 grey levels)."""


def _as_faces(faces: ArrayLike, vertex_count: int) -> np.ndarray:
    """Validate (T, 3) integer vertex indices below vertex_count; return them as int64."""
    arr = np.asarray(faces)
    if arr.ndim != 2 or arr.shape[1] != 3 or (arr.size and arr.dtype.kind not in "iu"):
        raise InvalidArgument(f"faces must be a (T, 3) integer array, got shape {arr.shape} {arr.dtype}")
    arr = arr.astype(np.int64, copy=False)
    if arr.size and (arr.min() < 0 or arr.max() >= vertex_count):
        bad = ((arr < 0) | (arr >= vertex_count)).any(axis=1)
        row = int(np.flatnonzero(bad)[0])
        raise InvalidArgument(f"faces row {row} {arr[row].tolist()} indexes outside 0..{vertex_count - 1}")
    return arr


def _normals(values: ArrayLike | None, rows: int, name: str) -> np.ndarray | None:
    """Validate optional (rows, 3) normals."""
    if values is None:
        return None
    arr, _ = as_points3d(values, name)
    if arr.shape[0] != rows:
        raise InvalidArgument(f"{name} must have {rows} rows, got {arr.shape[0]}")
    return arr


def _polygon_groups(polygons: ArrayLike | None, count: int) -> np.ndarray:
    """Validate (T,) polygon ids and renumber them 0..P-1 (default: each face its own polygon)."""
    if polygons is None:
        return np.arange(count)
    arr = np.asarray(polygons)
    if arr.shape != (count,) or (arr.size and arr.dtype.kind not in "iu"):
        raise InvalidArgument(f"polygons must be ({count},) integer polygon ids, got shape {arr.shape} {arr.dtype}")
    group: np.ndarray = np.unique(arr, return_inverse=True)[1].reshape(-1)
    return group


def _polygon_means(group: np.ndarray, size: int, weight: np.ndarray, centroids: np.ndarray,
                   normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per polygon (``group``: each face's polygon 0..size-1): the weighted centroid and mean normal."""
    total = np.bincount(group, weight, size)
    centroid = np.stack([np.bincount(group, weight * centroids[:, k], size) for k in range(3)], axis=1)
    normal = np.stack([np.bincount(group, weight * normals[:, k], size) for k in range(3)], axis=1)
    return centroid / total[:, None], normal


def _used_vertices(faces: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The vertices (U,) ascending that (T, 3) faces over ``count`` vertices use, and the faces renumbered to them."""
    used = np.zeros(count, dtype=bool)
    used[faces.reshape(-1)] = True
    renumber = np.cumsum(used) - 1
    return np.flatnonzero(used), np.take(renumber, faces, mode="clip")


class Shader:
    """One mesh's shading, prepared once (validation, lighting per polygon or vertex) for any number of fragment
    sets: ``Shader(vertices, faces, ...)(fragments)`` -> intensities (F, 3) in [0, 1] (see :func:`shade`)."""

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        *,
        mode: str = "flat",
        material: Material,
        lights: Light | Sequence[Light],
        viewer: Viewer,
        model: str = "phong",
        face_normals: ArrayLike | None = None,
        vertex_normals: ArrayLike | None = None,
        face_colours: ArrayLike | None = None,
        polygons: ArrayLike | None = None,
    ) -> None:
        if not isinstance(material, Material):
            raise InvalidArgumentType(f"material must be a Material, got {type(material).__name__}")
        self.mode = as_choice(mode, "shading mode", SHADING_MODES)
        verts, _ = as_points3d(vertices, "vertices")
        tris = _as_faces(faces, verts.shape[0])
        self.faces = tris.shape[0]
        colours = None if face_colours is None else as_colours(face_colours, self.faces, "face_colours")
        base = np.array(material.colour)
        self._colours = base if colours is None else colours
        self._terms = (material, lights, viewer, model)
        if self.mode == "flat":
            normals = _normals(face_normals, self.faces, "face_normals")
            group = _polygon_groups(polygons, self.faces)
            size = int(group.max()) + 1 if group.size else 0
            mesh = Mesh(verts, tris)
            weight = mesh.face_areas() + 1e-300  # area-weighted over each polygon's faces (all count if degenerate)
            centroid, normal = _polygon_means(group, size, weight, verts[tris].mean(axis=1),
                                              mesh.face_normals() if normals is None else normals)
            scale, specular = illumination_terms(centroid, normal, *self._terms)
            self._flat = (scale[group], specular[group])
            return
        given = _normals(vertex_normals, verts.shape[0], "vertex_normals")
        normals = Mesh(verts, tris).vertex_normals() if given is None else given
        if self.mode == "gouraud":  # lit once at each vertex the faces use (a mesh's back half is often unused)
            used, corners = _used_vertices(tris, verts.shape[0])
            scale, specular = illumination_terms(verts[used], normals[used], *self._terms)
            self._values = [Interpolant(combine(base, scale, specular), corners) if colours is None else Interpolant(
                combine(colours[:, None, :], scale[corners], specular[corners]))]
        else:
            self._values = [Interpolant(verts, tris), Interpolant(normals, tris)]

    def __call__(self, fragments: Fragments) -> np.ndarray:
        """Intensities (F, 3) in [0, 1] of the fragments of this mesh's faces."""
        if not isinstance(fragments, Fragments):
            raise InvalidArgumentType(f"fragments must be Fragments, got {type(fragments).__name__}")
        face = np.asarray(fragments.face, dtype=np.int64)
        if face.size and (face.min() < 0 or face.max() >= self.faces):
            raise InvalidArgument(f"fragments name faces outside 0..{self.faces - 1}")
        if self.mode == "gouraud":  # the colours are in the interpolated values
            return self._values[0].at_valid(fragments)
        colours = self._colours if self._colours.ndim == 1 else self._colours[face]
        if self.mode == "flat":
            scale, specular = self._flat
            return combine(colours, scale[face], specular[face])
        positions, normals = (values.at_valid(fragments) for values in self._values)
        return combine(colours, *illumination_terms(positions, normals, *self._terms))


def shade(fragments: Fragments, vertices: ArrayLike, faces: ArrayLike, **options: Any) -> np.ndarray:
    """Intensities (F, 3) in [0, 1] for the fragments of a mesh (world vertices (N, 3), faces (T, 3)): the
    keyword options of :class:`Shader` (mode, material, lights, viewer, model, face_normals, vertex_normals,
    face_colours, and polygons: (T,) the polygon id of each face, default one per face, which flat shading
    lights once)."""
    return Shader(vertices, faces, **options)(fragments)


def _pixels(canvas: Canvas, xs: ArrayLike, ys: ArrayLike, rows: int) -> tuple[np.ndarray, np.ndarray, Box | None]:
    """Validate integer pixel coordinates (rows,) inside the canvas; return them as int64, with their bounding box
    (x0, y0, x1, y1) half-open (None when there are none)."""
    out, bounds = [], []
    for name, values, size in (("xs", xs, canvas.width), ("ys", ys, canvas.height)):
        arr = np.asarray(values)
        if arr.ndim != 1 or (arr.size and arr.dtype.kind not in "iu"):
            raise InvalidArgument(f"{name} must be a 1-D integer array, got shape {arr.shape} {arr.dtype}")
        if arr.shape[0] != rows:
            raise InvalidArgument(f"{name} has {arr.shape[0]} entries for {rows} colours")
        arr = arr.astype(np.int64, copy=False)
        if arr.size:
            low, high = int(arr.min()), int(arr.max())
            if low < 0 or high >= size:
                i = int(np.flatnonzero((arr < 0) | (arr >= size))[0])
                raise InvalidArgument(f"{name}[{i}] = {int(arr[i])} lies outside the {canvas.width}x{canvas.height} "
                                      "canvas")
            bounds.append((low, high))
        out.append(arr)
    box = (bounds[0][0], bounds[1][0], bounds[0][1] + 1, bounds[1][1] + 1) if bounds else None
    return out[0], out[1], box


def _intensities(rgb: ArrayLike) -> np.ndarray:
    """Validate (F, 3) finite intensities (values outside [0, 1] are clamped later)."""
    try:
        arr = np.asarray(rgb, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"rgb must be an (F, 3) array of numbers: {exc}") from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InvalidArgument(f"rgb must be an (F, 3) array of intensities, got shape {arr.shape}")
    if arr.size and not (np.isfinite(arr.min()) and np.isfinite(arr.max())):  # NaN propagates: no mask pass
        row = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
        raise InvalidArgument(f"rgb row {row} is not finite: {arr[row].tolist()}")
    return arr


def _rgb8(values: np.ndarray, factor: float = 1.0) -> np.ndarray:
    """factor·values (F, C) to uint8: rounded to nearest (ties to even), clamped to 0..255; C-contiguous,
    computed one channel at a time in one reused buffer (no (F, C) float temporaries)."""
    out = np.empty(values.shape, dtype=np.uint8)
    scaled = np.empty(values.shape[0])
    for c in range(values.shape[1]):
        np.multiply(values[:, c], factor, out=scaled)
        np.rint(scaled, out=scaled)
        np.clip(scaled, 0.0, 255.0, out=out[:, c], casting="unsafe")  # integral already: the cast is exact
    return out


def _mono(xs: np.ndarray, ys: np.ndarray, rgb8: np.ndarray) -> np.ndarray:
    """0/1 values: ordered dither of the fragments' luma, anchored to the frame (over their bounding box)."""
    x0, y0 = int(xs.min()), int(ys.min())
    width = int(xs.max()) - x0 + 1
    local = (ys - y0) * width + (xs - x0)
    grey = np.zeros((int(ys.max()) - y0 + 1, width), dtype=np.uint8)
    np.put(grey.reshape(-1), local, luma(rgb8))
    return np.take(ordered_mono(grey, BAYER_SIZE, (x0, y0)).reshape(-1), local).view(np.uint8)


def _palette_gaps(palette: np.ndarray) -> np.ndarray:
    """Per channel, the largest gap between the distinct values the palette uses (0 if only one)."""
    gaps = []
    for c in range(3):
        values = np.unique(palette[:, c].astype(np.float64))
        gaps.append(float(np.diff(values).max()) if values.size > 1 else 0.0)
    return np.array(gaps)


def _indexed(canvas: Canvas, xs: np.ndarray, ys: np.ndarray, scaled: np.ndarray) -> np.ndarray:
    """Palette indices: ordered dither of 255·rgb to the canvas palette (see the module doc)."""
    assert canvas.palette is not None
    n2 = BAYER_SIZE * BAYER_SIZE
    threshold = (bayer_matrix(BAYER_SIZE)[ys % BAYER_SIZE, xs % BAYER_SIZE] + 0.5) / n2 - 0.5
    scaled += threshold[:, None] * _palette_gaps(canvas.palette)
    return Palette(canvas.palette).nearest(_rgb8(scaled)[:, None, :]).reshape(-1)


def _native(mode: str, rgb8: np.ndarray) -> np.ndarray:
    """Native values of (F, 3) uint8 colours in modes "RGB", "RGBA", "RGB565", "L" (as Canvas.colour_values)."""
    if mode == "RGB":
        return rgb8
    if mode == "RGBA":
        return np.concatenate([rgb8, np.full((rgb8.shape[0], 1), 255, dtype=np.uint8)], axis=1)
    return rgb888_to_rgb565(rgb8) if mode == "RGB565" else luma(rgb8)


def _scatter(array: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    """array.flat-by-pixel[index] = values; multi-channel pixels move as one item each (np.put on a void view)."""
    if array.ndim == 2:
        np.put(array.reshape(-1), index, values)
        return
    item = f"V{array.shape[2] * array.itemsize}"
    np.put(array.reshape(-1).view(item), index, np.ascontiguousarray(values, dtype=array.dtype).reshape(-1).view(item))


@dataclass(frozen=True)
class NativePixels:
    """Intensities converted to a canvas's native values (:func:`native_pixels`), ready to store."""

    index: np.ndarray
    """(F,) flat pixel index y·width + x."""
    values: np.ndarray
    """(F,) or (F, C) native values."""
    box: Box | None
    """Bounding box (x0, y0, x1, y1) of the pixels, half-open; None when there are none."""

    def store(self, canvas: Canvas) -> None:
        """Write the values into ``canvas`` (the one they were converted for) and mark the box as damage."""
        if self.box is not None:
            _scatter(canvas.array, self.index, self.values)
            canvas.mark_damaged(*self.box)


def native_pixels(canvas: Canvas, xs: ArrayLike, ys: ArrayLike, rgb: ArrayLike) -> NativePixels:
    """(F, 3) intensities in [0, 1] at pixels (xs[i], ys[i]) as the canvas's native values (module docstring);
    reads the canvas's mode and palette only, so conversions for disjoint pixels may run in parallel."""
    if not isinstance(canvas, Canvas):
        raise InvalidArgumentType(f"canvas must be a Canvas, got {type(canvas).__name__}")
    colours = _intensities(rgb)
    px, py, box = _pixels(canvas, xs, ys, colours.shape[0])
    return _convert(canvas, px, py, colours, box)


def native_pixels_unchecked(canvas: Canvas, xs: np.ndarray, ys: np.ndarray, rgb: np.ndarray) -> NativePixels:
    """:func:`native_pixels` of input known good: int64 pixels inside the canvas (z-buffer fragments) and finite
    float64 (F, 3) intensities (a :class:`Shader`'s), without the validation passes over them."""
    box = (int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1) if xs.size else None
    return _convert(canvas, xs, ys, rgb, box)


def _convert(canvas: Canvas, px: np.ndarray, py: np.ndarray, colours: np.ndarray, box: Box | None) -> NativePixels:
    """Validated pixels, intensities and their box as native values."""
    if box is None:
        return NativePixels(px, np.zeros(0, canvas.array.dtype), None)
    if canvas.mode == "P":
        values = _indexed(canvas, px, py, colours * 255.0)
    elif canvas.mode == "1":
        values = _mono(px, py, _rgb8(colours, 255.0))
    else:
        values = _native(canvas.mode, _rgb8(colours, 255.0))
    return NativePixels(py * canvas.width + px, values, box)


def write_colours(canvas: Canvas, xs: ArrayLike, ys: ArrayLike, rgb: ArrayLike) -> None:
    """Write (F, 3) intensities in [0, 1] to pixels (xs[i], ys[i]) in the canvas's mode; marks the damage."""
    native_pixels(canvas, xs, ys, rgb).store(canvas)

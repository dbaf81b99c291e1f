"""A :class:`~pixelpen.display.scene3d.Scene` to pixels through the z-buffer, or to strokes by hidden-line removal.

Both paths share the front end: every item's world mesh (surfaces tessellated to the device tolerance at the
scale they are seen at), back faces culled unless the material is two-sided (a face is a front face when it is
counter-clockwise seen from the viewer: :func:`front_faces`, in clip space),
world -> clip space (:meth:`Camera.world_to_clip` with the display's window as the view-plane window), the
front triangles of every item clipped (``clip_faces_homogeneous``), divided, and NDC x, y taken to
device units by ``display.pipeline.matrix @ ViewVolume.ndc_to_window``.

* Raster (:func:`render_raster`): the frame is drawn in horizontal bands of about :data:`BAND_PIXELS`
  pixels, on up to :data:`MAX_WORKERS` threads: per band a :class:`~pixelpen.raster.zbuffer.ZBuffer` over its
  rows and the triangles that reach them (depth NDC z, perspective-correct weights from 1/w), fragments
  re-expressed against their source triangles, shaded per item by a :class:`~pixelpen.raster.shading.Shader`
  prepared once per draw (world coordinates) and converted to the canvas's values
  (:func:`~pixelpen.raster.shading.native_pixels_unchecked`: fragments and a shader's output need no checks);
  the calling thread stores them band by band. A band's buffers stay in the CPU's caches, and the result is the
  whole-frame z-buffer's, pixel for pixel. The band z-buffers are kept from draw to draw (:class:`_BufferPool`,
  cleared before each band: no fresh memory pages per draw); a scene drawn over a picture covers it where it
  has pixels.
* Vector (:func:`scene_strokes`): each item's feature edges of its front faces (``Mesh.feature_edges``),
  clipped (``clip_segments_homogeneous``), divided, and split by :func:`pixelpen.vector.hiddenline.hidden_lines`
  against all items' clipped front triangles; the visible pieces, joined, are stroke shapes in the item's style.

:func:`fitted_window` is the view-plane window a display uses when its window was never set: the projected
bounds of everything between the near and far planes, with :data:`FIT_MARGIN`, widened to the viewport's
aspect ratio.
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from pixelpen import geometry as geo
from pixelpen.display.flatten import DeviceShape
from pixelpen.display.scene3d import Camera, Scene, SceneItem
from pixelpen.geometry.clip3d import clip_faces_homogeneous, clip_segments_homogeneous, perspective_divide_unchecked
from pixelpen.geometry.mesh import Mesh
from pixelpen.raster.canvas import Canvas
from pixelpen.raster.shading import NativePixels, Shader, native_pixels_unchecked
from pixelpen.raster.zbuffer import ZBuffer
from pixelpen.vector.hiddenline import HiddenLines, hidden_lines

FIT_MARGIN = 0.05
"""Margin of a fitted window on each side, as a fraction of the projected bounds' larger side."""

EDGE_ON = 1e-9
"""A face whose clip-space determinant is below this fraction of its bound is seen edge-on (a back face)."""

STEP_FACES = 1 << 14
"""Faces per vectorised step of :func:`front_faces`: temporaries this small are reused from the heap, where
larger ones come as fresh memory pages each time (a page fault each, costly on a busy machine)."""

BAND_PIXELS = 1 << 17
"""Pixels per band of the raster path (width x rows): a band's buffers stay in the CPU's caches."""

MAX_WORKERS = 4
"""Most threads drawing bands at once. numpy releases the GIL in much of a band's work, but not in all of it
(np.repeat, ufunc.at, fancy indexing), and on a 2-core machine two threads measured about even with one."""

Rect = tuple[float, float, float, float]


@dataclass(frozen=True)
class RenderStats:
    """What one draw of a scene did: triangles in, after culling and after clipping; pixels or pieces out."""

    triangles: int
    front: int
    clipped: int
    fragments: int = 0
    """Pixels written (raster)."""
    pieces: int = 0
    """Visible edge pieces (vector)."""


@dataclass
class _Item:
    """One item ready to project: its world mesh, front-face mask, and vertices in clip space."""

    item: SceneItem
    mesh: Mesh
    front: np.ndarray
    faces: np.ndarray
    """(F, 3) the front faces (mesh.faces[front])."""
    clip: np.ndarray


@dataclass
class _Triangles:
    """All items' front triangles after clipping, in device x, y + NDC z, with their source triangles."""

    device: np.ndarray
    """(K, 3, 3) device x, y and NDC depth."""
    inv_w: np.ndarray
    source: np.ndarray
    """(K,) index into the concatenated front triangles of all items (ascending)."""
    weights: np.ndarray
    offsets: np.ndarray
    """(items + 1,) start of each item's front triangles in the concatenation."""
    clipped: bool
    """False when every triangle passed the clip whole (source is 0..K-1, weights the identity)."""


def _magnification(camera: Camera, mesh: Mesh) -> float:
    """The largest view-plane units per world unit of a mesh's visible part (perspective: at its nearest point
    no nearer than the near plane; oblique: the receding axis's factor when it exceeds 1)."""
    if camera.z_prp is not None:
        n = mesh.vertices @ camera.world_to_view[2, :3] + camera.world_to_view[2, 3]
        nearest = min(float(n.max()), camera.near) if len(n) else camera.near
        return (camera.z_prp - camera.z_vp) / (camera.z_prp - nearest)
    if camera.alpha is not None:
        return max(1.0, 1.0 / math.tan(camera.alpha))
    return 1.0


def item_meshes(scene: Scene, device_per_unit: float, tolerance: float) -> list[Mesh]:
    """Each item's world mesh, surfaces tessellated to their chord tolerance at ``device_per_unit`` device units
    per view-plane unit (times the perspective magnification of the surface's nearest visible point)."""
    meshes = []
    for item in scene.items:
        mesh = item.mesh_at(device_per_unit, tolerance)
        if item.surface is not None:
            magnification = _magnification(scene.camera, mesh)
            if magnification > 1.0:
                mesh = item.mesh_at(device_per_unit * magnification, tolerance)
        meshes.append(mesh)
    return meshes


def fitted_window(scene: Scene, device_per_unit: float, tolerance: float, aspect: float) -> Rect | None:
    """The view-plane window that shows the whole scene (module docstring) at ``aspect`` = width / height;
    None when nothing lies between the near and far planes."""
    meshes = item_meshes(scene, device_per_unit, tolerance)
    points = np.concatenate([m.vertices for m in meshes]) if meshes else np.zeros((0, 3))
    clip = scene.camera.clip_coordinates(points, (-1.0, -1.0, 1.0, 1.0))
    w = clip[:, 3]
    inside = (w > 0.0) & (clip[:, 2] >= 0.0) & (clip[:, 2] <= w)
    if not inside.any():
        return None
    uv = clip[inside, :2] / w[inside, None]  # with the window (-1, -1, 1, 1), NDC x, y are view-plane u, v
    low, high = uv.min(axis=0), uv.max(axis=0)
    size = max(float((high - low).max()), 1e-9 * max(1.0, float(np.abs(uv).max())))
    width, height = max(high[0] - low[0], 0.0), max(high[1] - low[1], 0.0)
    width, height = width + 2 * FIT_MARGIN * size, height + 2 * FIT_MARGIN * size
    width, height = max(width, height * aspect), max(height, width / aspect)
    cu, cv = (low + high) / 2.0
    return (float(cu - width / 2), float(cv - height / 2), float(cu + width / 2), float(cv + height / 2))


def front_faces(clip: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(M,) bool: True where a face (M, 3) of clip-space vertices (N, 4) is counter-clockwise seen by the viewer.

    The determinant of the face's (x, y, w) rows is, up to a positive factor, the side of the face's plane the
    centre of projection lies on (Olano & Greer's homogeneous test): one test for parallel and perspective
    views, exact also for vertices behind the viewer, and no face normals needed. Computed STEP_FACES faces at
    a time."""
    columns = np.ascontiguousarray(clip[:, (0, 1, 3)].T)
    # a face seen edge-on has det = 0 up to rounding: it is a back face (as a line it would hide edges behind);
    # |det| is at most the product of the rows' lengths, each at most |x| + |y| + |w|
    size = np.abs(columns).sum(axis=0)
    front = np.empty(len(faces), dtype=bool)
    for lo in range(0, len(faces), STEP_FACES):
        corners = np.ascontiguousarray(faces[lo:lo + STEP_FACES].T)
        (x0, x1, x2), (y0, y1, y2), (w0, w1, w2) = ([np.take(c, k) for k in corners] for c in columns)
        det = x0 * (y1 * w2 - w1 * y2) - y0 * (x1 * w2 - w1 * x2) + w0 * (x1 * y2 - y1 * x2)
        bound = np.take(size, corners[0])
        bound *= np.take(size, corners[1])
        bound *= np.take(size, corners[2])
        bound *= EDGE_ON
        np.greater(det, bound, out=front[lo:lo + STEP_FACES])
    return front


def _prepare(scene: Scene, window: Sequence[float], meshes: list[Mesh]) -> list[_Item]:
    """Front-face masks and clip coordinates of every item."""
    prepared = []
    for item, mesh in zip(scene.items, meshes, strict=True):
        clip = scene.camera.clip_coordinates(mesh.vertices, window)
        front = np.ones(len(mesh.faces), dtype=bool) if item.material.two_sided else front_faces(clip, mesh.faces)
        prepared.append(_Item(item, mesh, front, np.compress(front, mesh.faces, axis=0), clip))
    return prepared


def _device_matrix(camera: Camera, pipeline: geo.ViewingPipeline) -> np.ndarray:
    """NDC x, y -> device 3x3: the view-plane window's matrix, then the display's window -> device pipeline."""
    return geo.compose(pipeline.matrix, camera.volume(pipeline.window).ndc_to_window)


def _to_device(ndc: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """(..., 3) NDC points to (..., 3) device x, y and NDC z (the pipeline is affine)."""
    out = np.empty_like(ndc)
    x, y = ndc[..., 0], ndc[..., 1]
    out[..., 0] = matrix[0, 0] * x + matrix[0, 1] * y + matrix[0, 2]
    out[..., 1] = matrix[1, 0] * x + matrix[1, 1] * y + matrix[1, 2]
    out[..., 2] = ndc[..., 2]
    return out


def _joined(parts: list[np.ndarray], shape: tuple[int, ...]) -> np.ndarray:
    """The parts concatenated (a single part as it is, no copy; none: an empty (0, *shape) array)."""
    if len(parts) == 1:
        return parts[0]
    return np.concatenate(parts) if parts else np.zeros((0, *shape))


def _triangles(items: list[_Item], matrix: np.ndarray) -> _Triangles:
    """All items' front triangles clipped (``clip_faces_homogeneous``), in device coordinates: triangles whose
    three vertices are inside the view volume pass whole (projected once per vertex), the rest are clipped."""
    counts = [len(it.faces) for it in items]
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    device, inv_w, source, weights = [], [], [], []
    passed = 0
    for it, offset in zip(items, offsets[:-1].tolist(), strict=True):
        faces = it.faces
        split = clip_faces_homogeneous(it.clip, faces)
        if split.inside.all():  # the common case: no masks
            vertices = _to_device(perspective_divide_unchecked(it.clip), matrix)
            q = 1.0 / it.clip[:, 3]
        else:
            vertices = np.zeros((len(split.inside), 3))
            vertices[split.inside] = _to_device(perspective_divide_unchecked(it.clip[split.inside]), matrix)
            q = 1.0 / np.where(split.inside, it.clip[:, 3], 1.0)
        kept = faces if split.whole.all() else np.compress(split.whole, faces, axis=0)
        passed += len(kept)
        device += [np.take(vertices, kept, axis=0), _to_device(perspective_divide_unchecked(split.out), matrix)]
        inv_w += [np.take(q, kept), 1.0 / split.out[..., 3]]
        source += [offset + np.flatnonzero(split.whole), offset + split.source]
        weights += [np.broadcast_to(np.eye(3), (len(kept), 3, 3)), split.weights]
    if passed == offsets[-1]:  # every triangle passed whole: source is 0..K-1, the weights the identity
        return _Triangles(_joined(device[::2], (3, 3)), _joined(inv_w[::2], (3,)), np.arange(passed),
                          np.broadcast_to(np.eye(3), (passed, 3, 3)), offsets, False)
    order = np.argsort(np.concatenate(source), kind="stable")
    return _Triangles(np.concatenate(device)[order], np.concatenate(inv_w)[order], np.concatenate(source)[order],
                      np.concatenate(weights)[order], offsets, True)


def _bands(y: np.ndarray, rows: int, height: int) -> list[tuple[int, np.ndarray]]:
    """Horizontal bands of ``rows`` rows (the last may be shorter): (top row, indices of the triangles whose
    z-buffer ``y`` (K, 3), the canvas's pixel centres, reach it)."""
    y0, y1, y2 = y[:, 0], y[:, 1], y[:, 2]
    first = np.floor(np.minimum(np.minimum(y0, y1), y2) / rows)
    last = np.floor(np.maximum(np.maximum(y0, y1), y2) / rows)
    bands = []
    for band, top in enumerate(range(0, height, rows)):
        index = np.flatnonzero((first <= band) & (last >= band))
        if index.size:
            bands.append((top, index))
    return bands


class _BufferPool:
    """Band z-buffers kept from draw to draw, with their depth and fragment memory (no fresh pages per draw):
    the threads' count + 1 released last (a draw's full bands and its shorter last one), found by size. Each holds
    at most about 9 float64 a band pixel (depth, fragments, ties), some 10 MB at the default BAND_PIXELS."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._free: list[ZBuffer] = []

    def acquire(self, width: int, height: int, top: int) -> ZBuffer:
        """A cleared width x height z-buffer over the frame rows from ``top`` on, kept or new."""
        with self._lock:
            kept = [i for i, z in enumerate(self._free) if (z.width, z.height) == (width, height)]
            zbuffer = self._free.pop(kept[-1]) if kept else None
        if zbuffer is None:
            return ZBuffer(width, height, top=top)
        zbuffer.clear(top)
        return zbuffer

    def release(self, zbuffer: ZBuffer) -> None:
        """Give a z-buffer back to be kept (the oldest kept one goes when there are too many)."""
        with self._lock:
            self._free.append(zbuffer)
            del self._free[:-(_workers() + 1)]

    def clear(self) -> None:
        """Let every kept z-buffer go."""
        with self._lock:
            self._free.clear()


_BUFFERS = _BufferPool()


def free_buffers() -> None:
    """Release the band z-buffers kept between draws (one per drawing thread plus one, about 10 MB each)."""
    _BUFFERS.clear()


def _workers() -> int:
    """Threads for the bands: the CPUs this process may run on, at most MAX_WORKERS."""
    available = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(MAX_WORKERS, available))


def render_raster(scene: Scene, pipeline: geo.ViewingPipeline, canvas: Canvas, tolerance: float) -> RenderStats:
    """Draw ``scene`` into ``canvas`` through a z-buffer (module docstring); return what was done."""
    matrix = _device_matrix(scene.camera, pipeline)
    items = _prepare(scene, pipeline.window, item_meshes(scene, geo.scale_factor(pipeline.matrix), tolerance))
    tris = _triangles(items, matrix)
    # the canvas's pixel (i, j) is centred on the device point (i, j); the z-buffer samples pixel centres at +0.5
    xy, depth = tris.device[..., :2] + 0.5, tris.device[..., 2]
    viewer, lights = scene.camera.viewer(), scene.effective_lights()
    offsets = tris.offsets.tolist()
    shaders: list[Shader | None] = []
    for it, lo, hi in zip(items, offsets[:-1], offsets[1:], strict=True):
        if lo == hi:  # no front triangle: nothing to light
            shaders.append(None)
            continue
        smooth = it.item.shading != "flat"
        shaders.append(Shader(
            it.mesh.vertices, it.faces, mode=it.item.shading, material=it.item.material,
            lights=lights, viewer=viewer, vertex_normals=it.mesh.vertex_normals() if smooth else None,
            face_colours=None if it.item.face_colours is None else it.item.face_colours[it.front],
            polygons=it.mesh.polygon[it.front] if it.item.shading == "flat" else None))
    rows = max(1, min(canvas.height, BAND_PIXELS // canvas.width))

    def band(top: int, index: np.ndarray) -> list[NativePixels]:
        """One band's pixels per item, shaded and converted to the canvas's values."""
        zbuffer = _BUFFERS.acquire(canvas.width, min(rows, canvas.height - top), top)
        try:
            return shaded(zbuffer, index)
        finally:
            _BUFFERS.release(zbuffer)

    def shaded(zbuffer: ZBuffer, index: np.ndarray) -> list[NativePixels]:
        """The band's pixels drawn with ``zbuffer`` (its fragments live in the buffer's memory until released)."""
        fragments = zbuffer.rasterize(xy[index], depth[index], tris.inv_w[index], reuse=True)
        if tris.clipped:  # the band's triangles only: compose checks what it is given
            fragments = fragments.compose(tris.source[index], tris.weights[index])
        else:
            np.take(index, fragments.face, out=fragments.face)
        out = []
        for shader, lo, hi in zip(shaders, offsets[:-1], offsets[1:], strict=True):
            if shader is None:
                continue
            mine = fragments
            if (lo, hi) != (0, offsets[-1]):
                mine = fragments.subset((fragments.face >= lo) & (fragments.face < hi))
                mine.face -= lo
            if len(mine):
                out.append(native_pixels_unchecked(canvas, mine.xs, mine.ys, shader(mine)))
        return out

    drawn = 0
    with ThreadPoolExecutor(_workers()) as pool:
        for pieces in pool.map(lambda job: band(*job), _bands(xy[..., 1], rows, canvas.height)):
            for pixels in pieces:
                pixels.store(canvas)
                drawn += len(pixels.index)
    return RenderStats(sum(len(it.front) for it in items), int(tris.offsets[-1]), len(tris.source),
                       fragments=drawn)


def scene_strokes(scene: Scene, pipeline: geo.ViewingPipeline, tolerance: float) -> tuple[list[DeviceShape],
                                                                                           RenderStats]:
    """The visible edges of ``scene`` as device stroke shapes, one per item (module docstring)."""
    matrix = _device_matrix(scene.camera, pipeline)
    items = _prepare(scene, pipeline.window, item_meshes(scene, geo.scale_factor(pipeline.matrix), tolerance))
    tris = _triangles(items, matrix)
    segments, edge_faces, owners = [], [], []
    for index, it in enumerate(items):
        if it.item.edges == "none":
            continue
        pairs, faces = it.mesh.feature_edges(it.front, crease_angle=it.item.crease_angle,
                                             outlines=it.item.edges == "outlines")
        segments.append(it.clip[pairs])
        edge_faces.append(_occluder_index(faces, it.front, int(tris.offsets[index]), tris.source))
        owners.append(np.full(len(pairs), index))
    if not segments:
        return [], RenderStats(sum(len(it.front) for it in items), int(tris.offsets[-1]), len(tris.source))
    clipped, kept = clip_segments_homogeneous(np.concatenate(segments).reshape(-1, 2, 4))
    edges = _to_device(perspective_divide_unchecked(clipped), matrix)
    visible = hidden_lines(tris.device, edges, np.concatenate(edge_faces)[kept])
    owner = np.concatenate(owners)[kept][visible.edge]
    shapes = []
    for index, it in enumerate(items):
        mine = owner == index
        if mine.any():
            paths = HiddenLines(visible.segments[mine], visible.edge[mine], visible.stats).polylines()
            shapes.append(DeviceShape("stroke", paths, False, it.item.style, matrix=pipeline.matrix))
    stats = RenderStats(sum(len(it.front) for it in items), int(tris.offsets[-1]), len(tris.source),
                        pieces=len(visible.edge))
    return shapes, stats


def _occluder_index(faces: np.ndarray, front: np.ndarray, offset: int, source: np.ndarray) -> np.ndarray:
    """Edge-adjacent faces (E, 2) of one item (−1 none) as indices of the first clipped triangle of each."""
    front_index = np.full(len(front) + 1, -1, np.int64)  # the extra last entry serves face −1
    front_index[np.flatnonzero(front)] = offset + np.arange(int(front.sum()))
    concatenated = front_index[faces]
    position = np.searchsorted(source, concatenated)
    found = (concatenated >= 0) & (position < len(source))
    found[found] &= source[position[found]] == concatenated[found]
    return np.where(found, position, -1).astype(np.int64)

"""3D benchmark: pixelpen's z-buffer and hidden-line paths against CPU renderers from PyPI, in one process.

Run: ``python3 benchmarks/render3d.py [--runs N] [--peers pixerise,polyhedral,matplotlib] [--images DIR]
[--quick]``.  Workloads (issue 12, Speed; the meshes are numpy grids, the same arrays for every renderer):

* **shaded**: a UV sphere of ~100k triangles (analytic vertex normals) filling a 1024x1024 RGB image in
  perspective, Gouraud-shaded with an ambient and a directional light (diffuse only: the model every peer
  has, C·(a + (1 − a)·max(N·L, 0))).  pixelpen: ``render3d.render_raster`` into a ``png:`` display's canvas
  (what ``display.draw(scene)`` does before it presents the frame; the PNG is written after the timing).
  Peers: **pixerise** (NumPy + Numba-JIT software rasteriser with a z-buffer, Gouraud: the fair peer, a
  CPU rasteriser written in Python) and **matplotlib** mplot3d (``Poly3DCollection(shade=True)`` on Agg:
  flat shading per face, painter's algorithm; context, not the goal).
* **hidden lines**: a torus of 10k triangles in a parallel view, silhouettes and creases (feature edges)
  with hidden parts removed.  pixelpen: ``render3d.scene_strokes`` (the vector display path: cull, clip,
  feature edges, ``hidden_lines``, joined polylines).  Peers: **polyhedral** (pure-Python exact hidden-line
  drawing of planar-facet solids, numpy + shapely; its ``Solid.from_mesh`` model build is reported apart
  and not counted) and matplotlib's painter's-algorithm wireframe (white faces, black edges: every
  triangle's edges, a raster image, no removal of hidden edges as geometry; context).

Each timing is the median of ``--runs`` after one untimed warm-up (Numba compiles pixerise's kernels then:
about 100 s the first time on a machine, cached on disk afterwards).  Printed: triangles/s for every
renderer, the ratios pixelpen/peer (time, < 1 = pixelpen faster), a fidelity check (covered pixels' IoU and
mean colour difference against pixerise; total visible length against polyhedral, which leaves short gaps in
the silhouette at some mesh vertices, so it comes out a few % shorter), and pixelpen's time per
stage, found by wrapping the pipeline's functions during ``--runs`` more runs (median per stage).

Peers considered (2026-12, this 2-core machine, the same 100k-triangle sphere at 1024²): pyjet3d (a C++
tile rasteriser with Python bindings, integer coordinates, RGB565: ~35-65 ms a frame), VTK 9.7 (pyvista's
engine) and pyrender, both on OSMesa's llvmpipe (Debian libosmesa6; pyrender also needs PyOpenGL >= 3.1.5
against its own ==3.1.0 pin): ~0.5-0.7 s a frame with read-back; all three are native renderers, not Python
ones.  Not tried: moderngl, trimesh's scene rendering (pyglet) and open3d, which need a GL context (llvmpipe
again at best).  pixerise is the CPU rasteriser written in Python.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

SIZE = 1024
SHADED_TRIANGLES = 100_000
HLR_TRIANGLES = 10_000
GOAL_TRIANGLES_PER_S = 1e6
COLOUR = (0.9, 0.55, 0.3)
AMBIENT = 0.2
LIGHT = (1.0, -1.0, -1.0)
"""The way the directional light travels (world coordinates): from the viewer's upper left, into the scene."""
Z_PRP = 4.0
"""Shaded view: PRP on the +z axis, the unit sphere at the origin, the view plane z = 0."""
HLR_VPN = (1.0, 0.5, 0.8)
"""Hidden-line view: parallel projection along −HLR_VPN (towards the viewer), up +z."""
PEERS = ("pixerise", "polyhedral", "matplotlib")


# -- meshes -------------------------------------------------------------------------------------------


def uv_sphere(triangles: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A unit sphere with >= ``triangles`` CCW outward triangles: R latitude bands, 2R longitudes, one vertex
    per pole; returns (vertices, faces, unit normals), 4R(R − 1) faces."""
    rings = math.ceil((1 + math.sqrt(1 + triangles)) / 2)
    cols = 2 * rings
    theta = np.arange(1, rings) * math.pi / rings
    phi = np.arange(cols) * 2 * math.pi / cols
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
    vertices = np.concatenate([[[0.0, 0.0, 1.0]], ring, [[0.0, 0.0, -1.0]]])
    south = len(vertices) - 1
    idx = 1 + np.arange((rings - 1) * cols).reshape(rings - 1, cols)
    nxt = np.roll(idx, -1, axis=1)
    a, b, c, d = idx[:-1], nxt[:-1], idx[1:], nxt[1:]  # c, d: the next ring (theta grows)
    faces = np.concatenate([
        np.stack([np.zeros(cols, np.int64), idx[0], nxt[0]], axis=-1),
        np.stack([a, c, b], axis=-1).reshape(-1, 3),
        np.stack([b, c, d], axis=-1).reshape(-1, 3),
        np.stack([idx[-1], np.full(cols, south), nxt[-1]], axis=-1),
    ]).astype(np.int64)
    return vertices, faces, vertices.copy()


def torus(triangles: int, major: float = 1.0, minor: float = 0.4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A torus about z with ~``triangles`` CCW outward triangles, two per planar quad of a 2:1 grid (triangles q
    and q + quads halve quad q); returns (vertices, faces, normals)."""
    nv = max(3, round(math.sqrt(triangles / 4)))
    nu = 2 * nv
    u, w = np.meshgrid(np.arange(nu) * 2 * math.pi / nu, np.arange(nv) * 2 * math.pi / nv, indexing="ij")
    normals = np.stack([np.cos(w) * np.cos(u), np.cos(w) * np.sin(u), np.sin(w)], axis=-1).reshape(-1, 3)
    centres = np.stack([major * np.cos(u), major * np.sin(u), np.zeros_like(u)], axis=-1).reshape(-1, 3)
    idx = np.arange(nu * nv).reshape(nu, nv)
    b = np.roll(idx, -1, axis=0)
    c, d = np.roll(idx, -1, axis=1), np.roll(b, -1, axis=1)
    faces = np.concatenate([np.stack([idx, b, d], -1).reshape(-1, 3), np.stack([idx, d, c], -1).reshape(-1, 3)])
    return centres + minor * normals, faces.astype(np.int64), normals


# -- timing -------------------------------------------------------------------------------------------


def median_time(fn: Callable[[], object], runs: int) -> tuple[float, object]:
    """Median wall time of fn over runs after one untimed warm-up, and the result of the last run."""
    result = fn()
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), result


class StageTimer:
    """Wall time per named stage, counting only the outermost wrapped call (nested stages are not twice)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self._depth = 0

    def wrap(self, stage: str, fn: Callable[..., object]) -> Callable[..., object]:
        """``fn`` timed into ``stage``."""
        def timed(*args: object, **kwargs: object) -> object:
            self._depth += 1
            began = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self._depth -= 1
                if self._depth == 0:
                    self.seconds[stage] = self.seconds.get(stage, 0.0) + time.perf_counter() - began
        return timed

    @contextmanager
    def patched(self, targets: list[tuple[object, str, str]]) -> Iterator[list[str]]:
        """Wrap ``(owner, attribute, stage)`` for the block (missing attributes are skipped and listed)."""
        saved, missing = [], []
        for owner, name, stage in targets:
            original = owner.__dict__.get(name) if isinstance(owner, type) else getattr(owner, name, None)
            if original is None:
                missing.append(f"{getattr(owner, '__name__', owner)}.{name}")
                continue
            saved.append((owner, name, original))
            setattr(owner, name, self.wrap(stage, original))
        try:
            yield missing
        finally:
            for owner, name, original in reversed(saved):
                setattr(owner, name, original)


def stage_breakdown(run: Callable[[], object], order: list[str], runs: int) -> list[str]:
    """pixelpen's time per stage: ``runs`` more runs with the stages wrapped, the median of each stage (ms and
    share of the median total; 'other' = the total less the stages)."""
    timer = StageTimer()
    per_run: list[dict[str, float]] = []
    totals = []
    with timer.patched(stage_targets()) as missing:
        for _ in range(runs):
            timer.seconds = {}
            began = time.perf_counter()
            run()
            totals.append(time.perf_counter() - began)
            per_run.append(timer.seconds)
    total = statistics.median(totals)
    medians = {stage: statistics.median(r.get(stage, 0.0) for r in per_run) for stage in order
               if any(stage in r for r in per_run)}
    lines = [f"  pixelpen stages (median of {runs} instrumented run(s)):"]
    lines += [f"  {stage:<12} {1000 * s:9.1f} ms {100 * s / total:5.1f} %" for stage, s in medians.items()]
    other = total - sum(medians.values())
    lines.append(f"  {'other':<12} {1000 * other:9.1f} ms {100 * other / total:5.1f} %")
    lines.append(f"  {'total':<12} {1000 * total:9.1f} ms")
    if missing:
        lines.append(f"  (not found, so not timed apart: {', '.join(missing)})")
    return lines


# -- pixelpen -----------------------------------------------------------------------------------------


def shaded_window() -> tuple[float, float, float, float]:
    """The view-plane window just holding the unit sphere seen from Z_PRP (its silhouette radius, + 2 %)."""
    r = 1.02 * Z_PRP / math.sqrt(Z_PRP ** 2 - 1.0)
    return (-r, -r, r, r)


def pixelpen_shaded_scene(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray) -> object:
    """The shaded workload as a pixelpen Scene (perspective, Gouraud, ambient + directional)."""
    import pixelpen
    from pixelpen.geometry.mesh import Mesh

    scene = pixelpen.Scene(camera=dict(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), projection="perspective",
                                       z_prp=Z_PRP, z_vp=0.0, near=1.5, far=-1.5))
    scene.add_mesh(Mesh(vertices, faces, normals=normals), material=dict(colour=COLOUR, ka=1.0, kd=1.0, ks=0.0),
                   shading="gouraud")
    scene.add_light("ambient", (AMBIENT,) * 3)
    scene.add_light("directional", (1.0 - AMBIENT,) * 3, direction=LIGHT)
    return scene


RASTER_STAGES = ["clear", "mesh", "cull", "transform", "clip", "bands", "rasterize", "compose", "normals", "shade",
                 "write"]
VECTOR_STAGES = ["mesh", "cull", "transform", "clip", "edges", "hidden", "join"]


def stage_targets() -> list[tuple[object, str, str]]:
    """What to wrap to time pixelpen's stages: render3d's module globals and the classes' methods."""
    from pixelpen.display import render3d, scene3d
    from pixelpen.geometry.mesh import Mesh
    from pixelpen.raster.canvas import Canvas
    from pixelpen.raster.zbuffer import Fragments, ZBuffer
    from pixelpen.vector.hiddenline import HiddenLines

    return [
        (Canvas, "fill", "clear"), (ZBuffer, "__init__", "clear"),
        (render3d, "item_meshes", "mesh"),
        (render3d, "front_faces", "cull"),
        (scene3d.Camera, "clip_coordinates", "transform"), (render3d, "perspective_divide_unchecked", "transform"),
        (render3d, "_to_device", "transform"),
        (render3d, "clip_faces_homogeneous", "clip"),
        (render3d, "clip_segments_homogeneous", "clip"),
        (render3d, "_bands", "bands"), (ZBuffer, "rasterize", "rasterize"),
        (Fragments, "compose", "compose"), (Fragments, "subset", "compose"),
        (Mesh, "vertex_normals", "normals"),
        (render3d.Shader, "__init__", "shade"), (render3d.Shader, "__call__", "shade"),
        (render3d, "native_pixels_unchecked", "write"), (render3d.NativePixels, "store", "write"),
        (Mesh, "feature_edges", "edges"),
        (render3d, "hidden_lines", "hidden"),
        (HiddenLines, "polylines", "join"),
    ]


@dataclass
class Measured:
    """One renderer on one workload: median seconds, triangles in, and what the fidelity check needs."""

    name: str
    seconds: float
    triangles: int
    result: object = None
    note: str = ""

    @property
    def rate(self) -> float:
        return self.triangles / self.seconds


def pixelpen_shaded(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray, size: int, runs: int,
                    workdir: Path) -> tuple[Measured, list[str]]:
    """Time render_raster on a png: display's canvas; return the image and the per-stage table."""
    import pixelpen
    from pixelpen.display import render3d

    scene = pixelpen_shaded_scene(vertices, faces, normals)
    with pixelpen.open(f"png:{workdir / 'pixelpen-shaded.png'}?size={size}x{size}&background=black") as display:
        display.window(*shaded_window())
        pipeline = display.scene_pipeline(scene)
        tolerance = display.capabilities.tolerance

        def run() -> object:
            display.canvas.fill(display.background)
            return render3d.render_raster(scene, pipeline, display.canvas, tolerance)

        seconds, stats = median_time(run, runs)
        image = display.canvas.array.copy()
        workers = render3d._workers()
        render3d.MAX_WORKERS, saved = 1, render3d.MAX_WORKERS  # stages add up on one thread
        try:
            serial, _ = median_time(run, runs)
            stages = stage_breakdown(run, RASTER_STAGES, runs)
        finally:
            render3d.MAX_WORKERS = saved
    stages.insert(1, "  (timed with the bands drawn on one thread)")
    note = (f"{stats.front:,} front, {stats.clipped:,} after clipping, {stats.fragments:,} px; "  # type: ignore[attr-defined]
            f"{workers} thread(s); on 1 thread {serial:.4f} s")
    return Measured("pixelpen", seconds, len(faces), image, note), stages


def hlr_scene(vertices: np.ndarray, faces: np.ndarray) -> object:
    """The hidden-line workload as a pixelpen Scene (parallel, feature edges of the quads, as polyhedral merges
    the coplanar triangle pairs into quads too)."""
    import pixelpen
    from pixelpen.geometry.mesh import Mesh

    scene = pixelpen.Scene(camera=dict(vrp=(0, 0, 0), vpn=HLR_VPN, vup=(0, 0, 1), projection="parallel",
                                       near=2.0, far=-2.0))
    quads = np.arange(len(faces) // 2)
    scene.add_mesh(Mesh(vertices, faces, polygon=np.concatenate([quads, quads])), edges="features")
    return scene


def pixelpen_hidden_lines(vertices: np.ndarray, faces: np.ndarray, runs: int,
                          workdir: Path) -> tuple[Measured, list[str]]:
    """Time scene_strokes for an svg: display; the result is the visible length in view-plane units."""
    import pixelpen
    from pixelpen import geometry as geo
    from pixelpen.display import render3d

    scene = hlr_scene(vertices, faces)
    with pixelpen.open(f"svg:{workdir / 'pixelpen-hlr.svg'}?size=300x300mm") as display:
        display.window(-1.5, -1.5, 1.5, 1.5)
        pipeline = display.scene_pipeline(scene)
        tolerance = display.capabilities.tolerance

        def run() -> object:
            return render3d.scene_strokes(scene, pipeline, tolerance)

        seconds, (shapes, stats) = median_time(run, runs)  # type: ignore[misc]
        stages = stage_breakdown(run, VECTOR_STAGES, runs)
        display.draw(scene)  # for the --images copy; after the timing
    length = sum(polyline_length(p) for s in shapes for p in s.paths) / geo.scale_factor(pipeline.matrix)
    note = f"{stats.pieces:,} visible pieces"
    return Measured("pixelpen", seconds, len(faces), length, note), stages


def polyline_length(points: np.ndarray) -> float:
    """Length of one polyline (K, 2)."""
    return float(np.linalg.norm(np.diff(np.asarray(points, float), axis=0), axis=1).sum())


# -- peers --------------------------------------------------------------------------------------------


def pixerise_shaded(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray, size: int,
                    runs: int) -> Measured:
    """pixerise: the same sphere and view in its camera frame (x right, y up, z away from the viewer)."""
    from pixerise.pixerise import Canvas, Renderer, ShadingMode, ViewPort
    from pixerise.scene import DirectionalLight, Instance, Model, Scene

    flip = np.array([1.0, 1.0, -1.0])  # pixelpen's n towards the viewer -> pixerise's z away from it
    model = Model()
    model.add_group(vertices * flip, faces, normals * flip)
    scene = Scene()
    scene.add_model("sphere", model)
    instance = Instance("sphere")
    instance.set_translation(0.0, 0.0, Z_PRP)
    instance.set_color(*(round(255 * c) for c in COLOUR))
    scene.add_instance("sphere", instance)
    light = np.array(LIGHT) * flip
    scene.set_directional_light(DirectionalLight(light / np.linalg.norm(light), AMBIENT))
    canvas = Canvas((size, size))
    half = shaded_window()[2] / Z_PRP  # the window at distance Z_PRP, scaled to the viewport at distance 1
    renderer = Renderer(canvas, ViewPort((2 * half, 2 * half), 1.0, canvas), background_color=(0, 0, 0))
    began = time.perf_counter()
    renderer.render(scene, ShadingMode.GOURAUD)
    note = f"first render (Numba compile or cache load) {time.perf_counter() - began:.1f} s"

    def run() -> np.ndarray:
        renderer.render(scene, ShadingMode.GOURAUD)
        return canvas.color_buffer.transpose(1, 0, 2).copy()  # its buffer is [x, y], y up from row 0 at top

    seconds, image = median_time(run, runs)
    return Measured("pixerise", seconds, len(faces), image, note)


def matplotlib_figure(size: int) -> tuple[object, object]:
    """A size x size Agg figure with one borderless 3D axes, the view along −z (matching pixelpen's)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(size / 100, size / 100), dpi=100)
    ax = fig.add_axes((0, 0, 1, 1), projection="3d")
    ax.set_axis_off()
    return fig, ax


def matplotlib_render(vertices: np.ndarray, faces: np.ndarray, size: int, runs: int, *, shaded: bool,
                      azim: float, elev: float, limit: float) -> Measured:
    """mplot3d: a Poly3DCollection of all triangles drawn on Agg (painter's algorithm), arrays -> RGBA."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import LightSource
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    fig, ax = matplotlib_figure(size)
    ax.view_init(elev=elev, azim=azim)
    ax.set_xlim(-limit, limit)
    ax.set_ylim(-limit, limit)
    ax.set_zlim(-limit, limit)
    ax.set_box_aspect((1, 1, 1))
    tris = vertices[faces]

    def run() -> np.ndarray:
        for old in list(ax.collections):
            old.remove()
        if shaded:
            poly = Poly3DCollection(tris, shade=True, lightsource=LightSource(315, 45), facecolors=COLOUR)
        else:
            poly = Poly3DCollection(tris, facecolors="white", edgecolors="black", linewidths=0.3)
        ax.add_collection3d(poly)
        fig.canvas.draw()
        return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()

    seconds, image = median_time(run, runs)
    plt.close(fig)
    note = "flat, painter's" if shaded else "all edges, painter's (raster)"
    return Measured("matplotlib", seconds, len(faces), image, note)


def polyhedral_hidden_lines(vertices: np.ndarray, faces: np.ndarray, runs: int) -> Measured:
    """polyhedral: the torus as a Solid (untimed), then ``render`` in the same parallel view."""
    import polyhedral

    began = time.perf_counter()
    solid = polyhedral.Solid.from_mesh(vertices.tolist(), faces.tolist())
    build = time.perf_counter() - began
    view = polyhedral.View.from_direction(tuple(-c for c in HLR_VPN), up=(0, 0, 1))
    seconds, result = median_time(lambda: polyhedral.render([solid], view), runs)
    length = sum(line.length for line in result.visible)  # type: ignore[attr-defined]
    return Measured("polyhedral", seconds, len(faces), length, f"Solid.from_mesh {build:.2f} s (not timed)")


# -- checks -------------------------------------------------------------------------------------------


def image_check(ours: np.ndarray, theirs: np.ndarray) -> str:
    """IoU of the covered (non-black) pixels and mean |ΔRGB| where both cover."""
    a, b = ours.any(axis=-1), theirs.any(axis=-1)
    union = int(np.count_nonzero(a | b))
    both = a & b
    iou = np.count_nonzero(both) / union if union else 1.0
    diff = np.abs(ours[both].astype(int) - theirs[both].astype(int)).mean() if both.any() else 0.0
    return f"coverage IoU {iou:.4f}, mean |ΔRGB| {diff:.2f}"


def length_check(ours: float, theirs: float) -> str:
    """Visible lengths in view-plane units and their relative difference."""
    return f"visible length {ours:.3f} vs {theirs:.3f} ({100 * (ours - theirs) / theirs:+.2f} %)"


def available(peers: list[str]) -> list[str]:
    """The peers asked for that import here (the others are reported as skipped)."""
    found = []
    for name in peers:
        try:
            __import__(name)
        except ImportError as exc:
            print(f"{name} skipped: {exc}", file=sys.stderr)
        else:
            found.append(name)
    return found


def table(title: str, rows: list[Measured], checks: dict[str, str]) -> list[str]:
    """A workload's table: seconds, triangles/s, ratio to pixelpen, check."""
    ours = rows[0]
    lines = [title, f"  {'renderer':<11} {'s':>8} {'triangles/s':>12} {'pp/peer':>8}  notes"]
    for r in rows:
        ratio = "" if r is ours else f"{ours.seconds / r.seconds:8.3f}"
        extra = "; ".join(x for x in (r.note, checks.get(r.name, "")) if x)
        lines.append(f"  {r.name:<11} {r.seconds:8.4f} {r.rate:12,.0f} {ratio:>8}  {extra}")
    return lines


def shaded_workload(peers: list[str], size: int, triangles: int, runs: int, out: Path,
                    images: dict[str, object]) -> list[str]:
    """The shaded sphere on pixelpen and the peers: the table, the goal, pixelpen's stages."""
    v, f, n = uv_sphere(triangles)
    ours, stages = pixelpen_shaded(v, f, n, size, runs, out)
    rows, checks = [ours], {}
    if "pixerise" in peers:
        rows.append(pixerise_shaded(v, f, n, size, runs))
        checks["pixerise"] = image_check(ours.result, rows[-1].result)  # type: ignore[arg-type]
        images["pixerise"] = rows[-1].result
    if "matplotlib" in peers:
        rows.append(matplotlib_render(v, f, size, runs, shaded=True, azim=-90, elev=90, limit=0.62))
        images["matplotlib"] = rows[-1].result
    lines = table(f"shaded: {len(f):,}-triangle sphere, Gouraud, {size}x{size} RGB", rows, checks)
    peer = next((r.rate for r in rows if r.name == "pixerise"), None)
    verdict = "met" if ours.rate >= GOAL_TRIANGLES_PER_S and (peer is None or ours.rate > peer) else "NOT met"
    lines.append(f"  goal: >= {GOAL_TRIANGLES_PER_S:,.0f} shaded triangles/s and ahead of pixerise: {verdict}")
    return [*lines, *stages]


def hidden_line_workload(peers: list[str], size: int, triangles: int, runs: int, out: Path,
                         images: dict[str, object]) -> list[str]:
    """The torus's hidden lines on pixelpen and the peers: the table and pixelpen's stages."""
    v, f, _ = torus(triangles)
    ours, stages = pixelpen_hidden_lines(v, f, runs, out)
    rows, checks = [ours], {}
    if "polyhedral" in peers:
        rows.append(polyhedral_hidden_lines(v, f, runs))
        checks["polyhedral"] = length_check(ours.result, rows[-1].result)  # type: ignore[arg-type]
    if "matplotlib" in peers:
        azim = math.degrees(math.atan2(HLR_VPN[1], HLR_VPN[0]))
        elev = math.degrees(math.atan2(HLR_VPN[2], math.hypot(HLR_VPN[0], HLR_VPN[1])))
        rows.append(matplotlib_render(v, f, size, runs, shaded=False, azim=azim, elev=elev, limit=1.5))
        images["matplotlib-wire"] = rows[-1].result
    lines = table(f"hidden lines: {len(f):,}-triangle torus, parallel view, feature edges", rows, checks)
    return [*lines, *stages]


def main(argv: list[str] | None = None) -> int:
    """Run both workloads and print the tables and pixelpen's stage breakdowns."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="timed runs per renderer (median reported)")
    parser.add_argument("--peers", default=",".join(PEERS), help="comma-separated, of: " + ", ".join(PEERS))
    parser.add_argument("--images", type=Path, help="keep the images here: pixelpen's PNG and SVG, the peers' PNGs")
    parser.add_argument("--quick", action="store_true", help="tiny sizes, one run: a smoke test, not a measurement")
    args = parser.parse_args(argv)
    size, shaded_n, hlr_n, runs = (64, 800, 400, 1) if args.quick else (SIZE, SHADED_TRIANGLES, HLR_TRIANGLES,
                                                                        args.runs)
    peers = available([p.strip() for p in args.peers.split(",") if p.strip()])
    images: dict[str, object] = {}
    with tempfile.TemporaryDirectory(prefix="render3d-") as scratch:
        out = args.images or Path(scratch)
        out.mkdir(parents=True, exist_ok=True)
        lines = shaded_workload(peers, size, shaded_n, runs, out, images)
        lines += hidden_line_workload(peers, size, hlr_n, runs, out, images)
    print(f"3D benchmark, median of {runs} run(s) after a warm-up; pp/peer = pixelpen time / peer time")
    for line in lines:
        print(line)
    if args.images:
        from PIL import Image

        for name, image in images.items():
            Image.fromarray(np.asarray(image, np.uint8)).save(args.images / f"{name}.png")
        print(f"images in {args.images}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

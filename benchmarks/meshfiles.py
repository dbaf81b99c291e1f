"""Mesh file readers benchmark: pixelpen.meshfiles vs trimesh on one sphere's OBJ (three forms), binary and ASCII STL.

Run: ``python3 benchmarks/meshfiles.py [--runs N] [--quick] [--only NAME]``.  The mesh is trimesh's
icosphere (8 subdivisions) cut to 1,000,000 triangles (``--quick``: 2 subdivisions, 200 triangles, one
run), written by trimesh outside the timing: OBJ plain (``v``, ``f a b c``), with normals (``vn``, ``f
a//c``) and with normals and texture vertices (``vt``, ``f a/b/c``, ``mtllib``/``usemtl``); binary and
ASCII STL.  Each timing reads the file's bytes from memory to a mesh, in this process.  trimesh reads OBJ
with ``process=False`` (pixelpen does not merge OBJ vertices either) and STL with its default
``process=True`` (which welds equal vertices, as pixelpen does).  Prints the median of the runs (wall and
this process's CPU time: the machine is shared, CPU time is the steadier), the ratios pixelpen/trimesh
and a check that both read the same triangles.
"""

from __future__ import annotations

import argparse
import io
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pixelpen.meshfiles import Limits, read_obj, read_stl

FORMATS = (("OBJ", "obj", "obj", {"include_normals": False, "include_texture": False}),
           ("OBJ a//c", "obj", "obj", {"include_normals": True, "include_texture": False}),
           ("OBJ a/b/c", "obj", "obj", {"include_normals": True, "include_texture": True}),
           ("binary STL", "stl", "stl", {}), ("ASCII STL", "stl_ascii", "stl", {}))
"""(name, trimesh export type, reader, export options) of each file."""
LIMITS = Limits(max_bytes=2**30)
"""The ASCII STL of a million triangles is 299 MB, past the default max_bytes."""


def sphere(subdivisions: int, triangles: int) -> trimesh.Trimesh:
    """trimesh's icosphere cut to its first ``triangles`` faces, unused vertices dropped."""
    whole = trimesh.creation.icosphere(subdivisions=subdivisions)
    mesh = trimesh.Trimesh(whole.vertices, whole.faces[:triangles], process=False)
    mesh.remove_unreferenced_vertices()
    return mesh


def median_time(fn: Callable[[], object], runs: int) -> tuple[float, float, object]:
    """Median wall and CPU time of fn over runs, and the result of the last run."""
    walls, cpus = [], []
    result = None
    for _ in range(runs):
        started, cpu = time.perf_counter(), time.process_time()
        result = fn()
        walls.append(time.perf_counter() - started)
        cpus.append(time.process_time() - cpu)
    return statistics.median(walls), statistics.median(cpus), result


def triangles_of(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The (F, 9) corner coordinates of each face, rows sorted: the same for any vertex numbering."""
    rows = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)].reshape(len(faces), 9)
    return rows[np.lexsort(rows.T[::-1])]


def main(argv: list[str] | None = None) -> int:
    """Write the files, time both readers on each and print the table."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="timed runs of each reader (median reported)")
    parser.add_argument("--quick", action="store_true", help="tiny mesh, one run: a smoke test, not a measurement")
    parser.add_argument("--only", action="append", help="time only the file of this name (repeatable)")
    args = parser.parse_args(argv)
    mesh = sphere(2, 200) if args.quick else sphere(8, 1_000_000)
    mesh.visual = trimesh.visual.TextureVisuals(uv=mesh.vertices[:, :2] * 0.5 + 0.5)
    runs = 1 if args.quick else args.runs
    print(f"{len(mesh.faces):,}-triangle sphere, {len(mesh.vertices):,} vertices; median of {runs} run(s)")
    print(f"{'file':<11} {'MB':>6} {'pixelpen s':>11} {'trimesh s':>10} {'ratio':>6} {'cpu ratio':>9}  check")
    for name, export, kind, options in FORMATS:
        if args.only and name not in args.only:
            continue
        data = mesh.export(file_type=export, **options)
        data = data.encode() if isinstance(data, str) else data
        ours_s, ours_cpu, ours = median_time(lambda d=data, k=kind: (read_obj if k == "obj" else read_stl)(
            d, f"sphere.{k}", limits=LIMITS), runs)
        theirs_s, theirs_cpu, theirs = median_time(
            lambda d=data, k=kind: trimesh.load(io.BytesIO(d), file_type=k, force="mesh", process=k == "stl"), runs)
        same = np.array_equal(triangles_of(ours.vertices, ours.faces), triangles_of(theirs.vertices, theirs.faces))
        print(f"{name:<11} {len(data) / 1e6:>6.1f} {ours_s:>11.3f} {theirs_s:>10.3f} {ours_s / theirs_s:>6.2f} "
              f"{ours_cpu / theirs_cpu:>9.2f}  {'same triangles' if same else 'DIFFERENT triangles'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

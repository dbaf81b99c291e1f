"""Mesh file readers benchmark: pixelpen.meshfiles vs trimesh on one sphere's OBJ, binary STL and ASCII STL.

Run: ``python3 benchmarks/meshfiles.py [--runs N] [--quick]``.  The mesh is trimesh's icosphere (8
subdivisions) cut to 1,000,000 triangles (``--quick``: 2 subdivisions, 200 triangles, one run), written by
trimesh outside the timing; each timing reads the file's bytes from memory to a mesh, in this process.
trimesh reads OBJ with ``process=False`` (pixelpen does not merge OBJ vertices either) and STL with its
default ``process=True`` (which welds equal vertices, as pixelpen does).  Prints the median of the runs,
the ratio pixelpen/trimesh and a check that both read the same triangles.
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

FORMATS = (("OBJ", "obj", "obj"), ("binary STL", "stl", "stl"), ("ASCII STL", "stl_ascii", "stl"))
"""(name, trimesh export type, reader) of each file."""
LIMITS = Limits(max_bytes=2**30)
"""The ASCII STL of a million triangles is 299 MB, past the default max_bytes."""


def sphere(subdivisions: int, triangles: int) -> trimesh.Trimesh:
    """trimesh's icosphere cut to its first ``triangles`` faces, unused vertices dropped."""
    whole = trimesh.creation.icosphere(subdivisions=subdivisions)
    mesh = trimesh.Trimesh(whole.vertices, whole.faces[:triangles], process=False)
    mesh.remove_unreferenced_vertices()
    return mesh


def median_time(fn: Callable[[], object], runs: int) -> tuple[float, object]:
    """Median wall time of fn over runs, and the result of the last run."""
    times = []
    result = None
    for _ in range(runs):
        started = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - started)
    return statistics.median(times), result


def triangles_of(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The (F, 9) corner coordinates of each face, rows sorted: the same for any vertex numbering."""
    rows = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)].reshape(len(faces), 9)
    return rows[np.lexsort(rows.T[::-1])]


def main(argv: list[str] | None = None) -> int:
    """Write the files, time both readers on each and print the table."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="timed runs of each reader (median reported)")
    parser.add_argument("--quick", action="store_true", help="tiny mesh, one run: a smoke test, not a measurement")
    args = parser.parse_args(argv)
    mesh = sphere(2, 200) if args.quick else sphere(8, 1_000_000)
    runs = 1 if args.quick else args.runs
    print(f"{len(mesh.faces):,}-triangle sphere, {len(mesh.vertices):,} vertices; median of {runs} run(s)")
    print(f"{'file':<12} {'MB':>7} {'pixelpen s':>11} {'trimesh s':>10} {'ratio':>7}  check")
    for name, export, kind in FORMATS:
        data = mesh.export(file_type=export)
        data = data.encode() if isinstance(data, str) else data
        ours_s, ours = median_time(lambda d=data, k=kind: (read_obj if k == "obj" else read_stl)(
            d, f"sphere.{k}", limits=LIMITS), runs)
        theirs_s, theirs = median_time(lambda d=data, k=kind: trimesh.load(io.BytesIO(d), file_type=k, force="mesh",
                                                                           process=k == "stl"), runs)
        same = np.array_equal(triangles_of(ours.vertices, ours.faces), triangles_of(theirs.vertices, theirs.faces))
        print(f"{name:<12} {len(data) / 1e6:>7.1f} {ours_s:>11.3f} {theirs_s:>10.3f} {ours_s / theirs_s:>7.2f}  "
              f"{'same triangles' if same else 'DIFFERENT triangles'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

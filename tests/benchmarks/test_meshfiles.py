"""Smoke test of benchmarks/meshfiles.py: the sphere is as claimed, a --quick run prints every row; untimed."""

import numpy as np
import pytest

pytest.importorskip("trimesh")

from benchmarks.meshfiles import main, sphere, triangles_of


def test_the_cut_sphere_keeps_its_first_faces_on_the_unit_sphere():
    mesh = sphere(2, 200)  # an icosphere of 2 subdivisions has 20 * 4**2 = 320 faces
    assert len(mesh.faces) == 200 and mesh.faces.max() == len(mesh.vertices) - 1
    np.testing.assert_allclose(np.linalg.norm(mesh.vertices, axis=1), 1.0)


def test_triangles_of_ignores_the_vertex_numbering():
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    order = np.array([3, 1, 0, 2])  # vertex k of the renumbered table is old vertex order[k]
    renumbered = np.argsort(order)[faces][::-1]
    assert np.array_equal(triangles_of(vertices, faces), triangles_of(vertices[order], renumbered))


def test_a_quick_run_prints_every_file_reading_the_same_triangles(capsys):
    assert main(["--quick"]) == 0
    out = capsys.readouterr().out
    assert "200-triangle sphere" in out
    for name in ("OBJ", "binary STL", "ASCII STL"):
        assert any(line.startswith(name) and line.endswith("same triangles") for line in out.splitlines())

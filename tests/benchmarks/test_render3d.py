"""Smoke test of benchmarks/render3d.py: the meshes are as claimed, a --quick run prints every table; untimed."""

import math
import time

import numpy as np
import pytest

from benchmarks.render3d import StageTimer, image_check, length_check, main, torus, uv_sphere


def _outward(vertices, faces, centre_of):
    """Fraction of faces whose right-hand normal points away from the surface's inside (centre_of(points))."""
    t = vertices[faces]
    normal = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    centroid = t.mean(axis=1)
    return float(np.mean(np.einsum("ij,ij->i", normal, centroid - centre_of(centroid)) > 0))


def test_the_uv_sphere_has_4r_r_minus_1_outward_triangles_on_the_unit_sphere():
    vertices, faces, normals = uv_sphere(100_000)
    rings = 159  # the least R with 4R(R - 1) >= 100,000: 4 * 158 * 157 = 99,224 < 100,000 <= 4 * 159 * 158
    assert len(faces) == 4 * rings * (rings - 1) == 100_488
    assert len(vertices) == (rings - 1) * 2 * rings + 2  # rings of 2R vertices between the two poles
    np.testing.assert_allclose(np.linalg.norm(vertices, axis=1), 1.0)
    np.testing.assert_array_equal(normals, vertices)
    assert _outward(vertices, faces, lambda p: np.zeros_like(p)) == 1.0
    assert faces.min() == 0 and faces.max() == len(vertices) - 1 and np.unique(faces).size == len(vertices)


def test_the_torus_has_2_nu_nv_outward_triangles_at_the_minor_radius():
    vertices, faces, normals = torus(10_000, major=1.0, minor=0.4)
    assert len(faces) == 2 * 100 * 50
    ring = vertices[:, :2] / np.linalg.norm(vertices[:, :2], axis=1, keepdims=True)  # nearest tube-centre point
    tube = np.column_stack([ring, np.zeros(len(vertices))])
    np.testing.assert_allclose(np.linalg.norm(vertices - tube, axis=1), 0.4)
    np.testing.assert_allclose((vertices - tube) / 0.4, normals, atol=1e-12)

    def tube_centre(p):
        xy = p[:, :2] / np.linalg.norm(p[:, :2], axis=1, keepdims=True)
        return np.column_stack([xy, np.zeros(len(p))])

    assert _outward(vertices, faces, tube_centre) == 1.0


def test_the_stage_timer_counts_only_the_outermost_wrapped_call():
    timer = StageTimer()
    inner = timer.wrap("inner", lambda: time.sleep(0.01))

    def outer():
        inner()
        time.sleep(0.01)

    timer.wrap("outer", outer)()
    assert set(timer.seconds) == {"outer"} and timer.seconds["outer"] >= 0.02
    timer.wrap("inner", inner)()
    assert timer.seconds["inner"] >= 0.01


def test_the_stage_timer_restores_what_it_patched_and_lists_what_is_missing():
    class Owner:
        def method(self):
            return 7

    original = Owner.__dict__["method"]
    timer = StageTimer()
    with timer.patched([(Owner, "method", "m"), (Owner, "absent", "x")]) as missing:
        assert Owner().method() == 7 and "m" in timer.seconds
    assert Owner.__dict__["method"] is original and missing == ["Owner.absent"]


def test_the_checks_compare_coverage_colour_and_length():
    a = np.zeros((4, 4, 3), np.uint8)
    b = a.copy()
    a[:2, :2] = 10  # 4 covered pixels
    b[:2, :3] = 12  # 6 covered, 4 in common: IoU 4/6, |Δ| 2 in every channel of the common ones
    assert image_check(a, b) == "coverage IoU 0.6667, mean |ΔRGB| 2.00"
    assert length_check(10.5, 10.0) == "visible length 10.500 vs 10.000 (+5.00 %)"


def test_a_quick_run_prints_both_tables_and_the_stage_breakdowns(capsys, tmp_path):
    pytest.importorskip("pixelpen.raster.zbuffer")
    pytest.importorskip("pixelpen.geometry.mesh")
    # pixerise is left out: a cold Numba compile of its kernels takes ~100 s (test below, marked slow)
    assert main(["--quick", "--peers", "polyhedral,matplotlib", "--images", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "shaded: 840-triangle sphere, Gouraud, 64x64 RGB" in out  # the least 4R(R - 1) >= 800: R = 15
    assert "hidden lines: 400-triangle torus, parallel view, feature edges" in out
    assert out.count("pixelpen stages (median of 1 instrumented run(s)):") == 2 and out.count("  total ") == 2
    for stage in ("rasterize", "shade", "write", "hidden"):
        assert f"  {stage} " in out
    assert "goal: >= 1,000,000 shaded triangles/s" in out
    assert {p.name for p in tmp_path.iterdir()} >= {"pixelpen-shaded.png", "pixelpen-hlr.svg"}


@pytest.mark.slow
def test_pixerise_draws_the_same_sphere(capsys):
    pytest.importorskip("pixerise")
    pytest.importorskip("pixelpen.raster.zbuffer")
    assert main(["--quick", "--peers", "pixerise"]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("  pixerise "))
    iou = float(line.split("coverage IoU ")[1].split(",")[0])
    assert iou > 0.95 and not math.isnan(iou)

"""Polygon scan-line fill: pixel-centre + top-left rule, fill rules, shared edges, triangles fast path."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image, ImageDraw
from scipy.spatial import Delaunay

from pixelpen.errors import ConfigError
from pixelpen.raster.canvas import Canvas
from pixelpen.raster.polygons import polygon_spans, triangle_spans


def brute_force(rings: list[np.ndarray], width: int, height: int, rule: str) -> np.ndarray:
    """Per pixel centre (x, y): winding number / crossing parity by casting a ray to +x (generic positions)."""
    ys, xs = np.mgrid[0:height, 0:width].astype(float)
    winding = np.zeros((height, width), dtype=int)
    crossings = np.zeros((height, width), dtype=int)
    for ring in rings:
        for (x0, y0), (x1, y1) in zip(ring, np.roll(ring, -1, axis=0), strict=False):
            if y0 == y1:
                continue
            lo, hi = min(y0, y1), max(y0, y1)
            between = (ys >= lo) & (ys < hi)
            xc = x0 + (ys - y0) * (x1 - x0) / (y1 - y0)
            hit = between & (xc <= xs)
            crossings += hit
            winding += np.where(hit, 1 if y1 > y0 else -1, 0)
    return (crossings % 2 == 1) if rule == "evenodd" else (winding != 0)


def paint(polys, width, height, rule="evenodd") -> np.ndarray:
    """Bool mask of polygons filled on a fresh mode-"1" canvas."""
    c = Canvas(width, height, "1")
    c.polygons(polys, 1, rule=rule)
    return c.array.astype(bool)


def coverage_count(tris: np.ndarray, width: int, height: int) -> np.ndarray:
    """How many of the triangles cover each pixel."""
    count = np.zeros((height, width), dtype=int)
    for t in tris:
        mask = np.zeros((height, width), dtype=bool)
        row, a, b = triangle_spans(t[None], width, height)
        for r, x0, x1 in zip(row.tolist(), a.tolist(), b.tolist(), strict=False):
            mask[r, x0:x1] = True
        count += mask
    return count


def test_rectangle_top_left_rule():
    m = paint([[(1, 1), (5, 1), (5, 4), (1, 4)]], 8, 6)
    want = np.zeros((6, 8), dtype=bool)
    want[1:4, 1:5] = True  # left/top edges in, right/bottom edges out
    assert (m == want).all()
    m = paint([[(0.5, 0.5), (3.5, 0.5), (3.5, 2.5), (0.5, 2.5)]], 6, 5)
    want = np.zeros((5, 6), dtype=bool)
    want[1:3, 1:4] = True
    assert (m == want).all()


@pytest.mark.parametrize("rule", ["evenodd", "nonzero"])
def test_random_self_intersecting_polygons_match_brute_force(rule):
    rng = np.random.default_rng(7 if rule == "evenodd" else 8)
    for _ in range(25):
        rings = [rng.uniform(-5, 45, size=(int(rng.integers(3, 9)), 2)) for _ in range(int(rng.integers(1, 3)))]
        rings = [np.rint(r * 256) / 256 for r in rings]  # the documented 1/256 px vertex grid
        assert (paint([rings], 40, 30, rule) == brute_force(rings, 40, 30, rule)).all()


def test_hole_rules():
    outer = np.array([(2, 2), (30, 2), (30, 30), (2, 30)], float)
    inner_same = np.array([(10, 10), (20, 10), (20, 20), (10, 20)], float)
    inner_reverse = inner_same[::-1]
    assert not paint([[outer, inner_same]], 32, 32, "evenodd")[15, 15]
    assert paint([[outer, inner_same]], 32, 32, "nonzero")[15, 15]
    assert not paint([[outer, inner_reverse]], 32, 32, "nonzero")[15, 15]


def test_separate_polygons_union_even_when_overlapping():
    a = [(0, 0), (20, 0), (20, 20), (0, 20)]
    b = [(10, 10), (30, 10), (30, 30), (10, 30)]
    m = paint([a, b], 40, 40)
    assert m[15, 15] and m[5, 5] and m[25, 25]


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0, 2 * np.pi, allow_nan=False), min_size=4, max_size=10, unique=True),
       st.floats(3, 30), st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), st.integers(0, 100))
def test_polygons_sharing_an_edge_neither_overlap_nor_gap(angles, radius, ox, oy, cut):
    pts = np.array([(32 + ox + radius * np.cos(t), 32 + oy + radius * np.sin(t)) for t in sorted(angles)])
    n = len(pts)
    i, j = 0, 2 + cut % (n - 3) if n > 3 else 2
    left, right = pts[i:j + 1], np.vstack([pts[j:], pts[:i + 1]])
    whole = paint([pts], 64, 64).astype(int)
    a = paint([left], 64, 64).astype(int)
    b = paint([right], 64, 64).astype(int)
    assert ((a + b) == whole).all()


def test_triangle_mesh_covers_each_pixel_once():
    rng = np.random.default_rng(1)
    pts = np.vstack([rng.uniform(0, 50, size=(300, 2)), [(0, 0), (50, 0), (50, 50), (0, 50)]])
    tris = pts[Delaunay(pts).simplices]
    count = coverage_count(tris, 50, 50)
    assert (count == 1).all()  # the hull is the 50x50 square: every pixel exactly once


def test_triangles_fast_path_equals_generic_polygons():
    rng = np.random.default_rng(2)
    tris = rng.uniform(-30, 90, size=(400, 3, 2))
    tris[:20] = np.round(tris[:20])
    tris[20:30, 2] = tris[20:30, 1]  # degenerate
    for t in (tris, np.round(tris)):
        row, a, b = polygon_spans(list(t), 64, 48)
        generic = Canvas(64, 48, "1")
        fast = Canvas(64, 48, "1")
        for r, x0, x1 in zip(row.tolist(), a.tolist(), b.tolist(), strict=False):
            generic.array[r, x0:x1] = 1
        fast.triangles(t, 1)
        assert (generic.array == fast.array).all()
        via_polygons = Canvas(64, 48, "1")
        via_polygons.polygons(t, 1)
        assert (via_polygons.array == fast.array).all()


def test_pillow_polygon_fill_is_a_superset():
    rng = np.random.default_rng(4)
    for _ in range(40):
        tri = rng.integers(0, 40, size=(3, 2))
        im = Image.new("1", (40, 40))
        ImageDraw.Draw(im).polygon([tuple(p) for p in tri.tolist()], fill=1)
        ours = paint([tri.astype(float)], 40, 40)
        assert not (ours & ~np.asarray(im)).any()


def test_far_outside_and_clipped_polygons():
    m = paint([[(-1000, -1000), (1000, -1000), (1000, 1000), (-1000, 1000)]], 10, 8)
    assert m.all()
    assert not paint([[(-100, 2), (-50, 2), (-50, 5)]], 10, 8).any()


@pytest.mark.parametrize("polys,match", [
    ([[(0, 0), (1, 1, 1)]], "polygon 0"), ([np.zeros((3, 3))], "polygon 0 ring 0"),
    ([[(0, 0), (float("nan"), 1), (2, 2)]], "vertex 1"), ([[(0, 0), (1e9, 1), (2, 2)]], "beyond"),
    ("abc", "polygons"), ([[[(0, 0), (1, 0), (1, 1)], 5]], "polygon 0 ring 1"), ([5], "polygon 0"),
])
def test_bad_polygons(polys, match):
    with pytest.raises(ConfigError, match=match):
        Canvas(10, 10).polygons(polys, 1)


def test_bad_rule_and_triangles():
    with pytest.raises(ConfigError, match="rule"):
        Canvas(10, 10).polygons([[(0, 0), (1, 0), (1, 1)]], 1, rule="winding")
    with pytest.raises(ConfigError, match="N, 3, 2"):
        Canvas(10, 10).triangles(np.zeros((2, 4, 2)), 1)

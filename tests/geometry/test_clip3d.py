"""Tests for pixelpen.geometry.clip3d: clip-space invariants, scalar Liang–Barsky / Sutherland–Hodgman references."""

import math

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from pixelpen.errors import InvalidArgument
from pixelpen.geometry import clip3d
from pixelpen.geometry.clip import clip_polygon
from pixelpen.geometry.clip3d import (
    clip_faces_homogeneous,
    clip_points_homogeneous,
    clip_polygon_homogeneous,
    clip_segments_homogeneous,
    clip_triangles_homogeneous,
    perspective_divide,
    perspective_divide_unchecked,
)

# ---------------------------------------------------------------------------------------------
# Independent references (plain Python, from the textbook; clip space −w ≤ x, y ≤ w, 0 ≤ z ≤ w)

BOUNDARIES = (
    lambda p: p[3] + p[0],  # x ≥ −w
    lambda p: p[3] - p[0],  # x ≤ w
    lambda p: p[3] + p[1],  # y ≥ −w
    lambda p: p[3] - p[1],  # y ≤ w
    lambda p: p[2],  # z ≥ 0
    lambda p: p[3] - p[2],  # z ≤ w
)


ON_TOL = 1e-12
"""The documented on-plane tolerance: a point within 1e-12 of its largest |coordinate| outside a plane is on it."""


def on_side(f, p, tol=ON_TOL):
    """The point is inside boundary f, to the tolerance scaled by its own size."""
    return f(p) >= -tol * max(abs(float(v)) for v in p)


def inside_reference(p, tol=ON_TOL):
    """The point satisfies the six clip inequalities (with a tolerance scaled by its size) and w > 0."""
    return p[3] > 0 and all(on_side(f, p, tol) for f in BOUNDARIES)


def liang_barsky_reference(p0, p1):
    """Scalar Liang–Barsky in 4D: the kept parameter interval (t0, t1) or None (ends within the tolerance of a
    plane are on it)."""
    t0, t1 = 0.0, 1.0
    for f in BOUNDARIES:
        in0, in1 = on_side(f, p0), on_side(f, p1)
        d0, d1 = f(p0), f(p1)
        if not in0 and not in1:
            return None
        if not in0:
            t0 = max(t0, min(d0 / (d0 - d1), 1.0))
        elif not in1:
            t1 = min(t1, max(d0 / (d0 - d1), 0.0))
    return (t0, t1) if t0 <= t1 else None


def sutherland_hodgman_reference(polygon):
    """Scalar Sutherland–Hodgman in 4D against the six boundaries (a list of 4-vectors); a vertex within 1e-12 of
    its own size outside a boundary counts as on it (the clipper's documented tolerance)."""
    poly = [np.asarray(p, dtype=float) for p in polygon]
    for f in BOUNDARIES:
        out = []
        for i, a in enumerate(poly):
            b = poly[(i + 1) % len(poly)]
            da, db = f(a), f(b)
            if on_side(f, a):
                out.append(a)
            if on_side(f, a) != on_side(f, b):
                out.append(a + min(max(da / (da - db), 0.0), 1.0) * (b - a))
        poly = out
    return [p for p in poly if p[3] > 0]


def shoelace(ring):
    """Signed area of a 2D ring."""
    x, y = np.asarray(ring, dtype=float).T
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def hausdorff(a, b):
    """Largest NDC distance from a vertex of one set (w > 0) to the nearest vertex of the other."""
    a, b = np.asarray(a, dtype=float).reshape(-1, 4), np.asarray(b, dtype=float).reshape(-1, 4)
    a, b = a[:, :3] / a[:, 3:], b[:, :3] / b[:, 3:]
    if len(a) == 0 or len(b) == 0:
        return 0.0 if len(a) == len(b) else math.inf
    d = np.linalg.norm(a[:, None] - b[None], axis=2)
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


@st.composite
def clip_points(draw):
    """Homogeneous points, often exactly on a clip plane, sometimes behind the viewer (w ≤ 0)."""
    w = draw(st.sampled_from([1.0, 0.5, 2.0, -1.0, 0.0]) | st.floats(0.01, 3) | st.floats(-1, -0.01))
    k = st.sampled_from([-1.0, 1.0, 0.0, 0.5]) | st.floats(-2.5, 2.5)
    kz = st.sampled_from([0.0, 1.0, 0.5]) | st.floats(-1.5, 2.5)
    point = [draw(k) * w, draw(k) * w, draw(kz) * w, w]
    if draw(st.booleans()) and w == 0:
        point = [draw(st.floats(-2, 2)) for _ in range(3)] + [w]
    return point


segments_st = st.lists(st.tuples(clip_points(), clip_points()), min_size=0, max_size=12)
TOL = 1e-9


def assert_inside(points):
    """Every point lies in clip space to within 1e-9 of its size, with w > 0."""
    for p in np.asarray(points).reshape(-1, 4):
        assert inside_reference(p, TOL), p


# ---------------------------------------------------------------------------------------------
# Points


def test_points_on_the_planes_are_inside_and_behind_the_viewer_are_not():
    h = [(0, 0, 0.5, 1), (1, -1, 0, 1), (2, 2, 2, 2), (1.01, 0, 0.5, 1), (0, 0, -0.01, 1), (0, 0, 0, -1),
         (0, 0, 0, 0), (-1, 1, 1, 1), (0, 0, 1.1, 1)]
    np.testing.assert_array_equal(clip_points_homogeneous(h), [True, True, True, False, False, False, False, True,
                                                               False])


@settings(max_examples=100, deadline=None)
@given(st.lists(clip_points(), max_size=20))
def test_point_mask_matches_the_scalar_inequalities(points):
    h = np.array(points, dtype=float).reshape(-1, 4)
    assert clip_points_homogeneous(h).tolist() == [inside_reference(p) for p in h]


# ---------------------------------------------------------------------------------------------
# Segments


def test_segment_worked_examples():
    segs = [
        [(-2, 0, 0.5, 1), (2, 0, 0.5, 1)],  # across the volume in x: cut to x = ±1
        [(0, 0, 0.5, 1), (0.2, 0.1, 0.5, 1)],  # inside: unchanged
        [(3, 0, 0.5, 1), (4, 0, 0.5, 1)],  # right of x = w: removed
        [(0, 0, 0.5, 1), (0, 0, 0.5, -1)],  # into w < 0: leaves through z = w at t = 1/4
    ]
    clipped, kept = clip_segments_homogeneous(segs)
    assert kept.tolist() == [0, 1, 3] and kept.dtype == np.int64
    np.testing.assert_allclose(clipped, [
        [(-1, 0, 0.5, 1), (1, 0, 0.5, 1)],
        [(0, 0, 0.5, 1), (0.2, 0.1, 0.5, 1)],
        [(0, 0, 0.5, 1), (0, 0, 0.5, 0.5)],
    ])


def test_fully_inside_segments_are_unchanged_and_fully_outside_removed():
    rng = np.random.default_rng(7)
    w = rng.uniform(0.5, 2, (50, 2, 1))
    inside = np.concatenate([rng.uniform(-1, 1, (50, 2, 2)) * w, rng.uniform(0, 1, (50, 2, 1)) * w, w], axis=2)
    clipped, kept = clip_segments_homogeneous(inside)
    assert kept.tolist() == list(range(50))
    np.testing.assert_array_equal(clipped, inside)
    outside = inside.copy()
    outside[:, :, 2] = outside[:, :, 3] * 1.5  # beyond the far plane
    clipped, kept = clip_segments_homogeneous(np.concatenate([outside, inside[:3]]))
    assert kept.tolist() == [50, 51, 52]
    np.testing.assert_array_equal(clipped, inside[:3])


def test_segment_through_the_zero_vector_is_dropped():
    clipped, kept = clip_segments_homogeneous([[(0.5, 0, 0.25, 1), (-0.5, 0, -0.25, -1)]])
    assert len(kept) == 0 and clipped.shape == (0, 2, 4)


def test_empty_batch():
    clipped, kept = clip_segments_homogeneous(np.zeros((0, 2, 4)))
    assert clipped.shape == (0, 2, 4) and kept.shape == (0,)


@settings(max_examples=150, deadline=None)
@given(segments_st)
@example([([-2.0, 0.0, 0.5, 1.0], [2.0, 0.0, 0.5, 1.0])])
def test_clipped_segments_lie_inside_are_sub_segments_and_match_liang_barsky(segments):
    segs = np.array(segments, dtype=float).reshape(-1, 2, 4)
    clipped, kept = clip_segments_homogeneous(segs)
    assert np.all(np.diff(kept) > 0)
    assert_inside(clipped)
    for (q0, q1), i in zip(clipped, kept, strict=True):
        p0, p1 = segs[i]
        delta = p1 - p0
        scale = 1 + np.abs(segs[i]).max()
        if not delta.any():
            np.testing.assert_array_equal([q0, q1], [p0, p1])
            continue
        k = int(np.abs(delta).argmax())  # the parameter along the segment, read off its longest coordinate
        t0, t1 = ((q[k] - p0[k]) / delta[k] for q in (q0, q1))
        assert -TOL <= t0 <= t1 + TOL and t1 <= 1 + TOL
        np.testing.assert_allclose([q0, q1], [p0 + t0 * delta, p0 + t1 * delta], atol=TOL * scale)
        if inside_reference(p0) and inside_reference(p1):
            np.testing.assert_array_equal([q0, q1], [p0, p1])
    kept_set = set(kept.tolist())
    for i, (p0, p1) in enumerate(segs):
        ref = liang_barsky_reference(p0, p1)
        if ref is not None and ref[1] - ref[0] > 1e-6:
            q0, q1 = p0 + ref[0] * (p1 - p0), p0 + ref[1] * (p1 - p0)
            if q0[3] > 1e-6 and q1[3] > 1e-6:
                assert i in kept_set
                k = int(np.flatnonzero(kept == i)[0])
                np.testing.assert_allclose(clipped[k], [q0, q1], atol=TOL * (1 + np.abs(segs[i]).max()))
        elif ref is None and i in kept_set:  # only borderline touches may differ by rounding
            k = int(np.flatnonzero(kept == i)[0])
            assert np.linalg.norm(clipped[k, 1] - clipped[k, 0]) <= 1e-6 * (1 + np.abs(segs[i]).max())


# ---------------------------------------------------------------------------------------------
# Polygons


def test_polygon_worked_example_triangle_larger_than_the_window():
    out = clip_polygon_homogeneous([(-2, -2, 0.5, 1), (2, -2, 0.5, 1), (0, 2, 0.5, 1)])
    expected = [(1, -1, 0.5, 1), (1, 0, 0.5, 1), (0.5, 1, 0.5, 1), (-0.5, 1, 0.5, 1), (-1, 0, 0.5, 1),
                (-1, -1, 0.5, 1)]
    np.testing.assert_allclose(out, expected, atol=1e-15)


def test_polygon_fully_inside_unchanged_and_fully_outside_empty():
    square = np.array([(-0.5, -0.5, 0.2, 1), (0.5, -0.5, 0.2, 1), (0.5, 0.5, 0.2, 1), (-0.5, 0.5, 0.2, 1)])
    np.testing.assert_array_equal(clip_polygon_homogeneous(square), square)
    behind = square.copy()
    behind[:, 3] = -1
    assert clip_polygon_homogeneous(behind).shape == (0, 4)
    assert clip_polygon_homogeneous(np.zeros((0, 4))).shape == (0, 4)


def test_polygon_crossing_the_near_plane_gets_a_near_edge():
    # a quad from z = −1 (in front of near) to z = 1 (deep), w = 2: the part z < 0 is cut at z = 0
    out = clip_polygon_homogeneous([(0, 0, -1, 2), (1, 0, -1, 2), (1, 0, 1, 2), (0, 0, 1, 2)])
    assert out[:, 2].min() == 0.0  # the cut vertices lie exactly on the plane
    np.testing.assert_allclose(sorted(map(tuple, out)), sorted([(0, 0, 0, 2), (1, 0, 0, 2), (1, 0, 1, 2),
                                                                  (0, 0, 1, 2)]))


@st.composite
def world_triangles(draw):
    """Triangles whose vertices lie in one hyperplane f · P = 1 missing 0, as images of world points do.

    Each clip-space point is rescaled by 1 / (f · P), its representative with world w = 1 (x = w and the
    other planes survive the rescaling exactly). Polygons spanning 0 have no meaning in NDC: an edge from
    P to −kP passes through the apex of the clip cone. Triangles, as more random points would not be
    planar (the planar polygons of more vertices are in convex_polygons_in_front).
    """
    f = np.array([draw(st.floats(-1, 1)), draw(st.floats(-1, 1)), draw(st.floats(-1, 1)), draw(st.floats(0.5, 2))])
    points = np.array(draw(st.lists(clip_points(), min_size=3, max_size=3)), dtype=float)
    dots = points @ f
    assume((np.abs(dots) > 1e-3 * (1 + np.abs(points).max(axis=1))).all())
    poly = points / dots[:, None]
    # a vertex within rounding of a plane (but not on it) makes inside/outside a coin toss for both clippers
    d = np.array([[b(p) for b in BOUNDARIES] for p in poly])
    assume(((d == 0) | (np.abs(d) > 1e-9 * np.abs(poly).max(axis=1, keepdims=True))).all())
    return poly


@settings(max_examples=120, deadline=None)
@given(world_triangles())
# faces lying in a boundary plane (x = w; z = w) with a vertex behind the viewer: their cuts lie in that plane
# only to rounding, which used to decide their side of it (the clipper now counts 1e-12 of the size as on it)
@example(np.array([[128.0, -128.0, 0.0, 128.0], [2.0317460317460316, 2.0317460317460316, 1.0158730158730158,
                                                 2.0317460317460316],
                   [-2.1333333333333333, -0.0, -2.066666666666667, -2.1333333333333333]]))
@example(np.array([[4.0, 4.0, -4.0, -4.0], [-0.8, 0.4, 0.8, 0.8],
                   [0.0, -1.3333333333333333, 1.3333333333333333, 1.3333333333333333]]))
def test_polygon_clip_matches_scalar_sutherland_hodgman(poly):
    out = clip_polygon_homogeneous(poly)
    assert_inside(out)
    ref = np.array(sutherland_hodgman_reference(poly)).reshape(-1, 4)
    both = np.concatenate([out, ref])
    # NDC error: rounding of the input's size, over the w it is divided by
    tol = 1e-9 * (1 + np.abs(poly).max() / both[:, 3].min()) if len(both) else 0.0
    area, ref_area = ndc_area(out), ndc_area(ref)
    assert area == pytest.approx(ref_area, abs=tol)  # (vertex lists may differ by collinear extra vertices)


def ndc_area(polygon):
    """Area of the NDC image of a planar homogeneous polygon (Newell: half the length of Σ p_i × p_i+1)."""
    if len(polygon) < 3:
        return 0.0
    p = polygon[:, :3] / polygon[:, 3:]
    return 0.5 * float(np.linalg.norm(np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)))


@st.composite
def convex_polygons_in_front(draw):
    """A convex polygon (CCW hull of random points) at constant NDC depth with positive w per vertex."""
    pts = draw(st.lists(st.tuples(st.floats(-3, 3), st.floats(-3, 3)), min_size=3, max_size=10, unique=True))
    hull = convex_hull(pts)
    assume(len(hull) >= 3 and abs(shoelace(hull)) > 1e-3)
    w = np.array([draw(st.floats(0.2, 3)) for _ in hull])
    xy = np.array(hull) * w[:, None]
    return np.column_stack([xy, 0.5 * w, w])


def convex_hull(points):
    """Andrew's monotone chain, counter-clockwise, without collinear points."""
    pts = sorted(set(points))

    def half(seq):
        out = []
        for p in seq:
            while len(out) >= 2 and (out[-1][0] - out[-2][0]) * (p[1] - out[-2][1]) - (out[-1][1] - out[-2][1]) * (
                p[0] - out[-2][0]
            ) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(reversed(pts))
    return lower[:-1] + upper[:-1]


@settings(max_examples=100, deadline=None)
@given(convex_polygons_in_front())
def test_ndc_area_of_the_clipped_polygon_equals_2d_clipping_of_its_image(poly):
    # with w > 0 everywhere, clipping before the divide equals clipping the NDC image to the square [−1, 1]²
    out = clip_polygon_homogeneous(poly)
    image = poly[:, :2] / poly[:, 3:]
    expected = sum(shoelace(ring) for ring in clip_polygon(image, (-1, -1, 1, 1)))
    got = shoelace(perspective_divide(out)[:, :2]) if len(out) else 0.0
    assert got == pytest.approx(expected, abs=1e-9)


def test_polygon_area_by_sampling_worked_example():
    # a triangle behind-and-in-front (one vertex with w < 0): sample NDC points, count the ones whose ray
    # hits the triangle's visible part, compare with the clipped polygon's area.
    tri = np.array([(-0.5, -0.5, 0.5, 1), (0.8, -0.3, 0.6, 1.2), (0.2, 0.9, 2.0, -0.5)])
    out = perspective_divide(clip_polygon_homogeneous(tri))
    area = abs(shoelace(out[:, :2]))
    n = 400
    s = (np.arange(n) + 0.5) / n * 2 - 1
    gx, gy = np.meshgrid(s, s)
    # a sample (X, Y) is covered when some P = a·v0 + b·v1 + c·v2 with a, b, c ≥ 0 is inside and divides to it:
    # solve x − X w = 0, y − Y w = 0 with a + b + c = 1 for (a, b, c) (the plane through the three points).
    m = np.stack([tri[:, 0] - gx[..., None] * tri[:, 3], tri[:, 1] - gy[..., None] * tri[:, 3],
                  np.ones((*gx.shape, 3))], axis=-2)
    abc = np.linalg.solve(m, np.broadcast_to([0.0, 0.0, 1.0], (*gx.shape, 3))[..., None])[..., 0]
    p = abc @ tri
    sign = np.sign(p[..., 3])[..., None]  # P and −P are the same projective point
    p = p * sign
    covered = (abc * sign >= 0).all(axis=-1) & (p[..., 3] > 0) & (p[..., 2] >= 0) & (p[..., 2] <= p[..., 3])
    sampled = covered.sum() * (2 / n) ** 2
    assert area == pytest.approx(sampled, rel=0.02)


# ---------------------------------------------------------------------------------------------
# Triangles


def test_triangle_clip_worked_example_and_weights():
    tris = np.array([
        [(-2, -2, 0.5, 1), (2, -2, 0.5, 1), (0, 2, 0.5, 1)],  # clipped to a hexagon: 4 fan triangles
        [(0, 0, 0.5, 1), (0.1, 0, 0.5, 1), (0, 0.1, 0.5, 1)],  # inside
        [(5, 5, 0.5, 1), (6, 5, 0.5, 1), (5, 6, 0.5, 1)],  # outside
    ])
    out, source, weights = clip_triangles_homogeneous(tris)
    assert source.tolist() == [0, 0, 0, 0, 1] and source.dtype == np.int64
    np.testing.assert_array_equal(out[4], tris[1])
    np.testing.assert_array_equal(weights[4], np.eye(3))
    np.testing.assert_allclose(np.einsum("kij,kjc->kic", weights, tris[source]), out, atol=1e-15)
    assert sum(shoelace(t[:, :2]) for t in out[:4]) == pytest.approx(4 - 2 * 0.25)  # the square less two corners


def test_triangles_sharing_an_edge_get_identical_cut_points():
    # the edge (0.5, −2) – (−0.3, 2) crosses y = ±w; both triangles hold it, in opposite directions
    a, b = (0.5, -2, 0.5, 1), (-0.3, 2, 0.5, 1)
    tris = np.array([[a, b, (-0.9, 0, 0.5, 1)], [b, a, (0.9, 0.2, 0.4, 1)]])
    out, source, _ = clip_triangles_homogeneous(tris)
    cut = {tuple(v) for t in out[source == 0] for v in t} & {tuple(v) for t in out[source == 1] for v in t}
    assert len(cut) == 2  # the two crossings of the shared edge, bit for bit the same
    assert {v[1] for v in cut} == {-1.0, 1.0}


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(clip_points(), clip_points(), clip_points()), max_size=6))
def test_triangle_clip_invariants(triangles):
    tris = np.array(triangles, dtype=float).reshape(-1, 3, 4)
    out, source, weights = clip_triangles_homogeneous(tris)
    assert out.shape[1:] == (3, 4) and weights.shape == (len(out), 3, 3) and source.shape == (len(out),)
    assert np.all(np.diff(source) >= 0)
    assert_inside(out)
    scale = 1 + (np.abs(tris).max() if len(tris) else 0)
    np.testing.assert_allclose(np.einsum("kij,kjc->kic", weights, tris[source]), out, atol=1e-9 * scale)
    np.testing.assert_allclose(weights.sum(axis=2), 1.0, atol=1e-9)  # affine combinations ...
    assert (weights >= -1e-9).all()  # ... of the source triangle's own points
    for t in range(len(tris)):
        polygon = clip_polygon_homogeneous(tris[t])
        mine = out[source == t]
        if len(polygon) >= 3 and len(mine):
            assert hausdorff(mine, polygon) <= 1e-9 * scale
        if all(inside_reference(p) for p in tris[t]):
            np.testing.assert_array_equal(mine, tris[t][None])
            np.testing.assert_array_equal(weights[source == t], np.eye(3)[None])


@settings(max_examples=100, deadline=None)
@given(convex_polygons_in_front())
def test_fan_keeps_the_winding_and_the_area(poly):
    tris = np.stack([poly[[0, i, i + 1]] for i in range(1, len(poly) - 1)])
    out, _, _ = clip_triangles_homogeneous(tris)
    ndc = perspective_divide(out)[:, :, :2] if len(out) else np.zeros((0, 3, 2))
    areas = [shoelace(t) for t in ndc]
    assert all(a >= -1e-12 for a in areas)  # counter-clockwise in, counter-clockwise out
    expected = sum(shoelace(ring) for ring in clip_polygon(poly[:, :2] / poly[:, 3:], (-1, -1, 1, 1)))
    assert sum(areas) == pytest.approx(expected, abs=1e-9)


def test_many_triangles_are_vectorised():
    rng = np.random.default_rng(3)
    tris = rng.uniform(-1.5, 1.5, (20000, 3, 4))
    tris[:, :, 3] = rng.uniform(0.5, 1.5, (20000, 3))
    tris[:, :, 2] = tris[:, :, 3] * rng.uniform(-0.2, 1.2, (20000, 3))
    out, source, weights = clip_triangles_homogeneous(tris)
    assert len(out) > 10000
    assert_inside(out[::997])
    np.testing.assert_allclose(np.einsum("kij,kjc->kic", weights, tris[source]), out, atol=1e-12)


# ---------------------------------------------------------------------------------------------
# The on-plane tolerance: one inside test for points, segments, polygons and triangles

JUST_OUT = math.nextafter(3.0, 4.0)  # z/w just beyond the far plane z = w = 3, by rounding only


def backdrop(z):
    """A far-plane triangle, w = 3, all three vertices at depth z."""
    return np.array([(-2.0, -2.0, z, 3.0), (2.0, -2.0, z, 3.0), (0.0, 2.0, z, 3.0)])


def test_a_backdrop_rounding_just_outside_the_far_plane_is_kept_whole_everywhere():
    tri = backdrop(JUST_OUT)
    assert all(not (p[3] - p[2] >= 0) for p in tri)  # outside without the tolerance ...
    assert clip_points_homogeneous(tri).all()  # ... inside with it, for every primitive alike
    out, source, weights = clip_triangles_homogeneous(tri[None])
    np.testing.assert_array_equal(out, tri[None])
    assert source.tolist() == [0]
    np.testing.assert_array_equal(weights, np.eye(3)[None])
    np.testing.assert_array_equal(clip_polygon_homogeneous(tri), tri)
    edges = np.stack([tri, np.roll(tri, -1, axis=0)], axis=1)
    clipped, kept = clip_segments_homogeneous(edges)
    assert kept.tolist() == [0, 1, 2]
    np.testing.assert_array_equal(clipped, edges)


def test_a_backdrop_with_one_vertex_on_the_plane_is_kept_as_before():
    tri = backdrop(JUST_OUT)
    tri[0, 2] = 3.0
    out, _, _ = clip_triangles_homogeneous(tri[None])
    np.testing.assert_array_equal(out, tri[None])


@pytest.mark.parametrize("z", [3.0 * (1 + 1e-9), 3.0 + 1e-6, 4.0])
def test_a_triangle_beyond_the_tolerance_is_still_rejected(z):
    tri = backdrop(z)
    assert not clip_points_homogeneous(tri).any()
    assert len(clip_triangles_homogeneous(tri[None])[0]) == 0
    assert len(clip_polygon_homogeneous(tri)) == 0
    assert len(clip_segments_homogeneous(np.stack([tri, np.roll(tri, -1, axis=0)], axis=1))[1]) == 0


def test_a_triangle_crossing_the_far_plane_is_cut_there_not_at_the_tolerance():
    tri = backdrop(3.0)
    tri[0, 2] = 6.0  # vertex 0 far beyond, the others on the plane
    out, _, _ = clip_triangles_homogeneous(tri[None])
    np.testing.assert_array_equal(out[..., 2], out[..., 3])  # the piece left lies in the far plane
    assert sum(shoelace(t[:, :2] / 3.0) for t in out) == pytest.approx(0.0, abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(clip_points(), clip_points(), clip_points()), min_size=1, max_size=6),
       st.sampled_from([0.0, 1e-13, -1e-13, 1e-11, -1e-11]))
def test_whole_triangles_are_those_whose_points_are_inside(triangles, nudge):
    tris = np.array(triangles, dtype=float)
    tris[..., :3] *= 1 + nudge  # on the planes, just off them within the tolerance, or just beyond it
    inside = clip_points_homogeneous(tris.reshape(-1, 4)).reshape(-1, 3).all(axis=1)
    out, source, _ = clip_triangles_homogeneous(tris)
    for t in np.flatnonzero(inside):
        np.testing.assert_array_equal(out[source == t], tris[t][None])
    assert_inside(out)


# ---------------------------------------------------------------------------------------------
# Faces of a vertex table


@settings(max_examples=40, deadline=None)
@given(st.lists(clip_points(), min_size=3, max_size=10), st.data())
def test_faces_of_a_vertex_table_clip_as_their_triangles(points, data):
    vertices = np.array(points, dtype=float)
    n = len(vertices)
    faces = np.array(data.draw(st.lists(st.tuples(*[st.integers(0, n - 1)] * 3), max_size=8)),
                     dtype=np.int64).reshape(-1, 3)
    split = clip_faces_homogeneous(vertices, faces)
    assert split.inside.tolist() == [inside_reference(p) for p in vertices]
    np.testing.assert_array_equal(split.whole, split.inside[faces].all(axis=1))
    assert np.all(np.diff(split.source) >= 0) and not split.whole[split.source].any()
    out, source, weights = clip_triangles_homogeneous(vertices[faces])
    cut = ~split.whole[source] if len(faces) else np.zeros(0, bool)
    np.testing.assert_array_equal(split.out, out[cut])
    np.testing.assert_array_equal(split.source, source[cut])
    np.testing.assert_array_equal(split.weights, weights[cut])
    np.testing.assert_array_equal(out[~cut], vertices[faces[split.whole]])


def test_faces_are_validated():
    vertices = np.ones((3, 4))
    with pytest.raises(InvalidArgument, match=r"faces must be a \(T, 3\) integer"):
        clip_faces_homogeneous(vertices, [[0.0, 1.0, 2.0]])
    with pytest.raises(InvalidArgument, match=r"faces row 1 \[0, 1, 3\] indexes outside the 3 vertices"):
        clip_faces_homogeneous(vertices, [[0, 1, 2], [0, 1, 3]])
    with pytest.raises(InvalidArgument, match=r"vertices contains a non-finite value"):
        clip_faces_homogeneous([(0, 0, 0, np.nan)], np.zeros((0, 3), np.int64))


# ---------------------------------------------------------------------------------------------
# Perspective divide and bad input


def test_perspective_divide():
    np.testing.assert_array_equal(perspective_divide([(2, 4, 1, 2), (1, 1, 1, 1)]), [(1, 2, 0.5), (1, 1, 1)])
    np.testing.assert_array_equal(perspective_divide_unchecked(np.array([(2.0, 4, 1, 2)])), [(1, 2, 0.5)])
    assert perspective_divide(np.ones((2, 3, 4))).shape == (2, 3, 3)
    h = np.ones((2, 3, 4))
    h[1, 2, 3] = -0.5
    with pytest.raises(InvalidArgument, match=r"w ≤ 0.*\(1, 2\)"):
        perspective_divide(h)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: clip_segments_homogeneous(np.zeros((3, 4))), r"\(N, 2, 4\)"),
        (lambda: clip_segments_homogeneous([[(0, 0, 0, 1), (0, 0, np.nan, 1)]]), "row 0"),
        (lambda: clip_segments_homogeneous("ab"), r"\(N, 2, 4\)"),
        (lambda: clip_polygon_homogeneous([(0, 0, 0, 1), (1, 0, 0, 1)]), "at least 3"),
        (lambda: clip_polygon_homogeneous([(0, 0, 0), (1, 0, 0), (0, 1, 0)]), r"\(N, 4\)"),
        (lambda: clip_polygon_homogeneous([(0, 0, 0, 1), (1, 0, 0, 1), (0, np.inf, 0, 1)]), "row 2"),
        (lambda: clip_triangles_homogeneous(np.zeros((2, 4, 4))), r"\(N, 3, 4\)"),
        (lambda: clip_triangles_homogeneous(np.full((2, 3, 4), np.nan)), "row 0"),
        (lambda: clip_points_homogeneous([(0, 0, 1)]), r"\(N, 4\)"),
        (lambda: perspective_divide([(1, 2, 3)]), r"\(\.\.\., 4\)"),
        (lambda: perspective_divide([(1, 2, 3, np.nan)]), "non-finite"),
        (lambda: perspective_divide([(1, 2, 3, 0)]), "w ≤ 0"),
    ],
)
def test_bad_input_raises_invalid_argument(call, message):
    with pytest.raises(InvalidArgument, match=message):
        call()


def test_the_written_out_boundary_functions_are_the_rows_of_planes():
    points = np.random.default_rng(5).normal(size=(50, 4))
    np.testing.assert_allclose(clip3d._distances(points), points @ clip3d.PLANES.T, rtol=0, atol=1e-15)


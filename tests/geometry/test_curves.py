"""Tests for pixelpen.geometry.curves: Bernstein/Bézier, Cox–de Boor B-splines, basis matrices, flattening."""

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.geometry.curves import (
    BEZIER_BASIS,
    BSPLINE_BASIS,
    basis_to_bezier,
    bernstein,
    bezier_point,
    bspline_basis,
    bspline_point,
    eval_basis,
    flatten_arc,
    flatten_bezier,
    flatten_beziers,
    flatten_bspline,
    open_uniform_knots,
    uniform_knots,
)

# ---------------------------------------------------------------------------------------------
# Scalar references written from the textbook recurrences

def de_casteljau_reference(points, t):
    """Plain de Casteljau: repeated linear interpolation of a list of points."""
    pts = [tuple(p) for p in points]
    while len(pts) > 1:
        pts = [tuple((1 - t) * a + t * b for a, b in zip(p, q, strict=False)) for p, q in itertools.pairwise(pts)]
    return pts[0]


def cox_de_boor_reference(knots, i, p, t, domain_end):
    """Recursive Cox–de Boor N_{i,p}(t), 0/0 = 0; at the domain's right end the last non-empty span is closed."""
    if p == 0:
        if t == domain_end:
            return 1.0 if knots[i] < knots[i + 1] == domain_end else 0.0
        return 1.0 if knots[i] <= t < knots[i + 1] else 0.0
    left = right = 0.0
    if knots[i + p] > knots[i]:
        left = (t - knots[i]) / (knots[i + p] - knots[i]) * cox_de_boor_reference(knots, i, p - 1, t, domain_end)
    if knots[i + p + 1] > knots[i + 1]:
        right = (knots[i + p + 1] - t) / (knots[i + p + 1] - knots[i + 1]) * cox_de_boor_reference(
            knots, i + 1, p - 1, t, domain_end)
    return left + right


def distance_to_polyline(points, polyline):
    """Distance from each point to the nearest segment of an open polyline."""
    a, b = polyline[:-1][None], polyline[1:][None]
    p = points[:, None]
    ab = b - a
    t = np.clip(((p - a) * ab).sum(axis=2) / np.maximum((ab * ab).sum(axis=2), 1e-300), 0, 1)
    return np.hypot(*(p - a - t[..., None] * ab).transpose(2, 0, 1)).min(axis=1)


def assert_within_tolerance(dense, polyline, tol):
    """Hausdorff check both ways: dense curve points near the polyline, and polyline points near the curve."""
    assert distance_to_polyline(dense, polyline).max() <= tol * (1 + 1e-9)
    mids = np.vstack([polyline, (polyline[1:] + polyline[:-1]) / 2])
    spacing = np.hypot(*np.diff(dense, axis=0).T).max()
    assert distance_to_polyline(mids, dense).max() <= tol * (1 + 1e-9) + spacing


# ---------------------------------------------------------------------------------------------
# Bernstein and Bézier evaluation

def test_bernstein_values():
    assert bernstein(3, 1, 0.5) == pytest.approx(3 * 0.5 * 0.25)
    assert bernstein(2, 0, 0.0) == 1.0 and bernstein(2, 2, 1.0) == 1.0
    np.testing.assert_allclose(bernstein(4, 2, [0, 0.5, 1]), [0, 6 / 16, 0])


@settings(max_examples=30, deadline=None)
@given(n=st.integers(0, 12), t=st.lists(st.floats(0, 1), min_size=1, max_size=20))
def test_bernstein_partition_of_unity(n, t):
    np.testing.assert_allclose(sum(bernstein(n, i, t) for i in range(n + 1)), 1.0, rtol=1e-12)


def test_bezier_point_matches_scalar_de_casteljau_on_random_curves():
    rng = np.random.default_rng(3)
    for degree in range(9):
        ctrl = rng.uniform(-50, 50, size=(degree + 1, 2))
        t = rng.uniform(0, 1, size=25)
        expected = [de_casteljau_reference(ctrl, ti) for ti in t]
        np.testing.assert_allclose(bezier_point(ctrl, t), expected, atol=1e-10)
    ctrl3d = rng.uniform(-1, 1, size=(4, 3))
    np.testing.assert_allclose(bezier_point(ctrl3d, 0.3), de_casteljau_reference(ctrl3d, 0.3))


def test_bezier_basis_matrix_is_the_cubic_bernstein_form():
    rng = np.random.default_rng(4)
    g = rng.uniform(-10, 10, size=(4, 2))
    t = np.linspace(0, 1, 9)
    np.testing.assert_allclose(eval_basis(BEZIER_BASIS, g, t), [de_casteljau_reference(g, ti) for ti in t], atol=1e-12)
    np.testing.assert_allclose(basis_to_bezier(BEZIER_BASIS, g), g, atol=1e-12)


def test_uniform_bspline_basis_matrix():
    rng = np.random.default_rng(5)
    g = rng.uniform(-10, 10, size=(4, 2))
    # textbook endpoint values: P(0) = (p0 + 4 p1 + p2) / 6, P(1) = (p1 + 4 p2 + p3) / 6
    np.testing.assert_allclose(eval_basis(BSPLINE_BASIS, g, 0.0), (g[0] + 4 * g[1] + g[2]) / 6)
    np.testing.assert_allclose(eval_basis(BSPLINE_BASIS, g, 1.0), (g[1] + 4 * g[2] + g[3]) / 6)
    # the middle span [3, 4] of a uniform cubic on knots 0..7 is that segment
    t = np.linspace(0, 1, 7)
    knots = np.arange(8.0)
    expected = [[sum(cox_de_boor_reference(knots, i, 3, 3 + u, 4.0) * g[i, d] for i in range(4)) for d in range(2)]
                for u in t]
    np.testing.assert_allclose(eval_basis(BSPLINE_BASIS, g, t), expected, atol=1e-12)
    # and the same segment in Bézier form
    bez = basis_to_bezier(BSPLINE_BASIS, g)
    np.testing.assert_allclose(bezier_point(bez, t), expected, atol=1e-12)


# ---------------------------------------------------------------------------------------------
# Knot vectors and Cox–de Boor

def test_knot_vectors():
    np.testing.assert_array_equal(uniform_knots(5, 3), np.arange(9))
    np.testing.assert_array_equal(open_uniform_knots(6, 3), [0, 0, 0, 0, 1, 2, 3, 3, 3, 3])
    np.testing.assert_array_equal(open_uniform_knots(4, 3), [0, 0, 0, 0, 1, 1, 1, 1])
    np.testing.assert_array_equal(open_uniform_knots(3, 1), [0, 0, 1, 2, 2])


@st.composite
def knot_vectors(draw):
    """Random non-uniform knot vectors with interior multiplicities up to the degree."""
    degree = draw(st.integers(1, 5))
    n = draw(st.integers(degree + 1, degree + 8))
    gaps = draw(st.lists(st.sampled_from([0.0, 0.0, 0.5, 1.0, 1.7, 3.1]), min_size=n + degree, max_size=n + degree))
    knots = np.concatenate([[0.0], np.cumsum(gaps)])
    if not knots[degree] < knots[n]:
        knots[n:] += 1.0
    return degree, knots


@settings(max_examples=40, deadline=None)
@given(kd=knot_vectors(), fractions=st.lists(st.floats(0, 1), min_size=1, max_size=8))
def test_cox_de_boor_matches_the_recursive_reference(kd, fractions):
    degree, knots = kd
    n = len(knots) - degree - 1
    lo, hi = knots[degree], knots[n]
    inside = np.clip(lo + np.array(fractions) * (hi - lo), lo, hi)  # lo + 1.0 * (hi - lo) may round past hi
    t = np.concatenate([inside, [lo, hi]])
    basis = bspline_basis(knots, degree, t)
    assert basis.shape == (len(t), n)
    expected = [[cox_de_boor_reference(knots, i, degree, ti, hi) for i in range(n)] for ti in t]
    np.testing.assert_allclose(basis, expected, atol=1e-12)
    # partition of unity and non-negativity on the domain
    np.testing.assert_allclose(basis.sum(axis=1), 1.0, rtol=1e-12)
    assert (basis >= -1e-15).all()


def test_clamped_bspline_interpolates_its_end_control_points():
    ctrl = np.array([(0, 0), (1, 3), (4, 4), (6, 0), (8, 2)], float)
    ends = bspline_point(ctrl, 3, None, [0.0, 2.0])
    np.testing.assert_allclose(ends, [ctrl[0], ctrl[-1]], atol=1e-15)


def test_bezier_is_the_clamped_bspline_with_one_span():
    ctrl = np.random.default_rng(6).uniform(-5, 5, size=(5, 2))
    t = np.linspace(0, 1, 11)
    np.testing.assert_allclose(bspline_point(ctrl, 4, open_uniform_knots(5, 4), t), bezier_point(ctrl, t), atol=1e-12)


@pytest.mark.parametrize(
    "knots, degree, t, message",
    [([0, 1, 2, 3, 4, 5, 6, 7], 3, 2.9, "outside"), ([0, 1, 2, 3, 4, 5, 6, 7], 3, 4.1, "outside"),
     ([0, 1, 2, 1, 4, 5, 6, 7], 3, 3.5, "non-decreasing"), ([0, 1, 2], 3, 0.5, "at least 8"),
     ([0, 0, 0, 0, 0, 0, 0, 0], 3, 0, "empty"), ([0, 1, 2, np.nan, 4, 5, 6, 7], 3, 3.5, "NaN"),
     ([0, 1, 2, 3, 4, 5, 6, 7], 0, 3.5, "degree"), ([0, 1, 2, 3, 4, 5, 6, 7], 3, np.nan, "NaN")],
)
def test_bad_bspline_input(knots, degree, t, message):
    with pytest.raises(ValueError, match=message):
        bspline_basis(knots, degree, t)


# ---------------------------------------------------------------------------------------------
# Flattening

@settings(max_examples=25, deadline=None)
@given(degree=st.integers(1, 6), seed=st.integers(0, 2**32 - 1), tol=st.sampled_from([0.02, 0.1, 0.5, 2.0]))
def test_flattened_bezier_is_within_tolerance_and_hits_the_end_points(degree, seed, tol):
    ctrl = np.random.default_rng(seed).uniform(-200, 200, size=(degree + 1, 2))
    poly = flatten_bezier(ctrl, tol)
    np.testing.assert_array_equal(poly[0], ctrl[0])
    np.testing.assert_array_equal(poly[-1], ctrl[-1])
    dense = bezier_point(ctrl, np.linspace(0, 1, 800))  # checked against the scalar reference above
    assert_within_tolerance(dense, poly, tol)


def test_flattening_is_adaptive():
    straight = flatten_bezier([(0, 0), (1, 1), (2, 2), (3, 3)], 0.01)
    assert len(straight) == 2  # collinear control points: already flat
    coarse = flatten_bezier([(0, 0), (0, 100), (100, 100), (100, 0)], 1.0)
    fine = flatten_bezier([(0, 0), (0, 100), (100, 100), (100, 0)], 0.01)
    assert 3 < len(coarse) < len(fine)
    # the error of a chord on a cubic falls as h^2: 100x finer tolerance needs about 10x the points
    assert 5 < (len(fine) - 1) / (len(coarse) - 1) < 20


def test_flatten_beziers_batch_equals_one_by_one():
    rng = np.random.default_rng(8)
    curves = [rng.uniform(0, 100, size=(rng.integers(2, 6), 2)) for _ in range(30)]
    batch = flatten_beziers(curves, 0.05)
    for curve, poly in zip(curves, batch, strict=False):
        np.testing.assert_array_equal(poly, flatten_bezier(curve, 0.05))


def test_degenerate_bezier_loops_and_cusps():
    cusp = np.array([(0, 0), (100, 100), (0, 100), (100, 0)], float)  # self-intersecting cubic
    loop_back = np.array([(0, 0), (100, 0), (-50, 0)], float)  # goes past its end and back
    for ctrl in (cusp, loop_back):
        poly = flatten_bezier(ctrl, 0.1)
        dense = np.array([de_casteljau_reference(ctrl, t) for t in np.linspace(0, 1, 1500)])
        assert_within_tolerance(dense, poly, 0.1)


@settings(max_examples=25, deadline=None)
@given(kd=knot_vectors(), seed=st.integers(0, 2**32 - 1), tol=st.sampled_from([0.05, 0.3, 1.0]))
def test_flattened_bspline_is_within_tolerance(kd, seed, tol):
    degree, knots = kd
    n = len(knots) - degree - 1
    _, multiplicity = np.unique(knots[degree + 1:n], return_counts=True)
    if (multiplicity > degree).any():
        with pytest.raises(ValueError, match="discontinuous"):
            flatten_bspline(np.zeros((n, 2)), degree, knots, tolerance=tol)
        return
    ctrl = np.random.default_rng(seed).uniform(-100, 100, size=(n, 2))
    poly = flatten_bspline(ctrl, degree, knots, tolerance=tol)
    lo, hi = knots[degree], knots[n]
    dense = bspline_point(ctrl, degree, knots, np.linspace(lo, hi, 1000))  # basis checked against the reference
    np.testing.assert_allclose(poly[0], dense[0], atol=1e-9)
    np.testing.assert_allclose(poly[-1], dense[-1], atol=1e-9)
    assert_within_tolerance(dense, poly, tol)


def test_clamped_bspline_flattening_passes_through_end_control_points():
    ctrl = np.array([(0, 0), (10, 30), (40, 40), (60, 0), (80, 20), (90, -10)], float)
    poly = flatten_bspline(ctrl, 3, tolerance=0.05)
    np.testing.assert_allclose(poly[0], ctrl[0], atol=1e-12)
    np.testing.assert_allclose(poly[-1], ctrl[-1], atol=1e-12)
    linear = flatten_bspline(ctrl, 1, tolerance=0.05)  # degree 1 is the control polygon
    np.testing.assert_allclose(linear, ctrl, atol=1e-12)


def test_flatten_bspline_rejects_bad_input():
    ctrl = np.zeros((5, 2))
    with pytest.raises(ValueError, match="need 9 knots"):
        flatten_bspline(ctrl, 3, [0, 1, 2])
    with pytest.raises(ValueError, match="at least 4"):
        flatten_bspline(ctrl[:3], 3)
    with pytest.raises(ValueError, match="tolerance"):
        flatten_bspline(ctrl, 3, tolerance=0)
    with pytest.raises(ValueError, match="discontinuous"):
        flatten_bspline(np.zeros((7, 2)), 2, [0, 0, 0, 1, 1, 1, 2, 2, 2, 2])


def test_arc_segment_count_from_the_sagitta_bound():
    # r = 100, tol = 0.1: step = 2 acos(1 - 0.001) = 0.08945 rad -> ceil(2 pi / 0.08945) = 71 chords
    circle = flatten_arc((0, 0), 100, 100, 0, 2 * math.pi, tolerance=0.1)
    assert len(circle) == 72
    np.testing.assert_array_equal(circle[0], circle[-1])
    np.testing.assert_allclose(np.hypot(circle[:, 0], circle[:, 1]), 100)
    # the largest chord error is the sagitta r (1 - cos(step / 2)) <= tol
    step = 2 * math.pi / 71
    assert 100 * (1 - math.cos(step / 2)) <= 0.1


@settings(max_examples=30, deadline=None)
@given(cx=st.floats(-50, 50), cy=st.floats(-50, 50), rx=st.floats(0.5, 200), ry=st.floats(0.5, 200),
       start=st.floats(-7, 7), sweep=st.floats(-8, 8), angle=st.floats(-4, 4),
       tol=st.sampled_from([0.01, 0.1, 1.0]))
def test_flattened_arc_is_within_tolerance(cx, cy, rx, ry, start, sweep, angle, tol):
    pts = flatten_arc((cx, cy), rx, ry, start, start + sweep, angle, tolerance=tol)
    full = abs(sweep) >= 2 * math.pi
    u = np.linspace(start, start + (math.copysign(2 * math.pi, sweep) if full else sweep), 1500)
    c, s = math.cos(angle), math.sin(angle)
    ex, ey = rx * np.cos(u), ry * np.sin(u)
    dense = np.stack([cx + c * ex - s * ey, cy + s * ex + c * ey], axis=1)
    np.testing.assert_allclose(pts[0], dense[0], atol=1e-9)
    np.testing.assert_allclose(pts[-1], dense[-1], atol=1e-9)
    assert_within_tolerance(dense, pts, tol)
    # every vertex lies on the ellipse: ((x', y') rotated back) / radii has unit length
    local = (pts - (cx, cy)) @ np.array([[c, -s], [s, c]])
    np.testing.assert_allclose(np.hypot(local[:, 0] / rx, local[:, 1] / ry), 1.0, atol=1e-9)


def test_arc_direction():
    ccw = flatten_arc((0, 0), 2, 1, 0, 2 * math.pi, tolerance=0.01)
    cw = flatten_arc((0, 0), 2, 1, 0, -2 * math.pi, tolerance=0.01)

    def area(r):
        return 0.5 * float((r[:, 0] * np.roll(r[:, 1], -1) - np.roll(r[:, 0], -1) * r[:, 1]).sum())

    assert area(ccw) > 0 > area(cw)
    assert area(ccw) == pytest.approx(math.pi * 2 * 1, rel=1e-2)
    quarter = flatten_arc((1, 1), 1, 1, math.pi / 2, 0, tolerance=0.01)  # clockwise from top to right
    np.testing.assert_allclose(quarter[[0, -1]], [(1, 2), (2, 1)], atol=1e-15)


def test_bad_curve_input():
    with pytest.raises(ValueError, match="tolerance must be > 0"):
        flatten_bezier([(0, 0), (1, 1)], 0)
    with pytest.raises(ValueError, match="tolerance"):
        flatten_bezier([(0, 0), (1, 1)], float("nan"))
    with pytest.raises(ValueError, match="at least 2 rows"):
        flatten_bezier([(0, 0)], 0.1)
    with pytest.raises(ValueError, match="row 1"):
        flatten_bezier([(0, 0), (np.nan, 1), (2, 2)], 0.1)
    with pytest.raises(ValueError, match=r"curves\[1\]"):
        flatten_beziers([[(0, 0), (1, 1)], [(0, 0, 0)]], 0.1)
    with pytest.raises(ValueError, match="too small"):
        flatten_bezier([(0, 0), (1000, 3000), (3000, -2000), (4000, 0)], 1e-30)
    with pytest.raises(ValueError, match="radii must be > 0"):
        flatten_arc((0, 0), 0, 1, 0, 1)
    with pytest.raises(ValueError, match="center"):
        flatten_arc((0, 0, 0), 1, 1, 0, 1)
    with pytest.raises(ValueError, match="i <= n"):
        bernstein(2, 3, 0.5)
    with pytest.raises(ValueError, match="4x4"):
        eval_basis(np.eye(3), np.zeros((4, 2)), 0.5)
    with pytest.raises(ValueError, match="exactly 4 rows"):
        basis_to_bezier(BSPLINE_BASIS, np.zeros((5, 2)))


# ---------------------------------------------------------------------------------------------
# Bounded work on any input

@settings(max_examples=40, deadline=None)
@given(kd=knot_vectors(), seed=st.integers(0, 2**32 - 1), fractions=st.lists(st.floats(0, 1), min_size=1, max_size=8))
def test_per_span_curve_points_match_the_recursive_basis(kd, seed, fractions):
    degree, knots = kd
    n = len(knots) - degree - 1
    lo, hi = knots[degree], knots[n]
    t = np.concatenate([lo + np.array(fractions) * (hi - lo), [lo, hi]])
    ctrl = np.random.default_rng(seed).uniform(-100, 100, size=(n, 2))
    expected = [[sum(cox_de_boor_reference(knots, i, degree, ti, hi) * ctrl[i, d] for i in range(n)) for d in (0, 1)]
                for ti in t]
    np.testing.assert_allclose(bspline_point(ctrl, degree, knots, t), expected, atol=1e-9)


def test_bspline_memory_does_not_grow_with_the_control_points():
    import tracemalloc

    rng = np.random.default_rng(3)
    ctrl = np.cumsum(rng.uniform(-1, 1, size=(20_000, 2)), axis=0)  # a 20,000-point random walk
    t = np.linspace(0.0, 20_000 - 3, 80_000)  # the open uniform domain of a cubic: [0, n - degree]
    tracemalloc.start()
    try:
        pts = bspline_point(ctrl, 3, None, t)
        poly = flatten_bspline(ctrl, 3, tolerance=0.05)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    # a (samples x control points) basis would be 80,000 x 20,000 doubles = 12.8 GB; per span it is a few MB
    assert peak < 64 * 2**20, f"peak {peak / 2**20:.0f} MB"
    np.testing.assert_allclose(pts[[0, -1]], ctrl[[0, -1]], atol=1e-9)  # clamped: ends on the end points
    np.testing.assert_allclose(poly[[0, -1]], ctrl[[0, -1]], atol=1e-9)


def test_arc_point_count_is_bounded_and_small_tolerances_stay_exact():
    from pixelpen.errors import InvalidArgument
    from pixelpen.geometry import curves

    with pytest.raises(InvalidArgument, match="MAX_ARC_POINTS"):
        flatten_arc((0, 0), 1e15, 1e15, 0, 2 * math.pi, tolerance=0.1)  # acos(1 - 1e-16) = 0: was a ZeroDivisionError
    # tol / r = 1e-10: the old form 2 acos(1 - tol / r) loses half its digits; the sagitta must hold
    r, tol = 1e6, 1e-4
    pts = flatten_arc((0, 0), r, r, 0, 0.01, tolerance=tol)
    mid = (pts[:-1] + pts[1:]) / 2
    assert (r - np.hypot(*mid.T)).max() <= tol * (1 + 1e-6)
    assert len(pts) <= curves.MAX_ARC_POINTS

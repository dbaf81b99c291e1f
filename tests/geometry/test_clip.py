"""Tests for pixelpen.geometry.clip: outcodes, Cohen–Sutherland cases, Liang–Barsky, Cyrus–Beck, polygons."""

import math

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from pixelpen.geometry.clip import (
    BOTTOM,
    LEFT,
    RIGHT,
    TOP,
    clip_polygon,
    clip_polygon_convex,
    clip_polylines,
    clip_segments,
    clip_segments_convex,
    outcodes,
)

WINDOW = (0.0, 0.0, 10.0, 10.0)


# ---------------------------------------------------------------------------------------------
# Independent references and helpers (plain Python, written from the textbook pseudocode)

def cohen_sutherland_reference(x0, y0, x1, y1, xmin, ymin, xmax, ymax):
    """Hearn & Baker's Cohen–Sutherland loop for one segment; None when rejected."""

    def code(x, y):
        c = 0
        if x < xmin:
            c |= 1
        elif x > xmax:
            c |= 2
        if y < ymin:
            c |= 4
        elif y > ymax:
            c |= 8
        return c

    c0, c1 = code(x0, y0), code(x1, y1)
    for _ in range(8):
        if not (c0 | c1):
            return (x0, y0, x1, y1)
        if c0 & c1:
            return None
        c = c0 if c0 else c1
        if c & 1:
            x, y = xmin, y0 + (y1 - y0) * (xmin - x0) / (x1 - x0)
        elif c & 2:
            x, y = xmax, y0 + (y1 - y0) * (xmax - x0) / (x1 - x0)
        elif c & 4:
            x, y = x0 + (x1 - x0) * (ymin - y0) / (y1 - y0), ymin
        else:
            x, y = x0 + (x1 - x0) * (ymax - y0) / (y1 - y0), ymax
        if c == c0:
            x0, y0, c0 = x, y, code(x, y)
        else:
            x1, y1, c1 = x, y, code(x, y)
    raise AssertionError("reference Cohen–Sutherland did not terminate")


def inside_polygon(points, ring):
    """Even-odd rule membership of points (N, 2) in a ring (K, 2), by counting edge crossings."""
    x, y = points[:, 0][:, None], points[:, 1][:, None]
    a, b = ring, np.roll(ring, -1, axis=0)
    straddle = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (straddle & (x < xc)).sum(axis=1) % 2 == 1


def distance_to_edges(points, ring):
    """Distance from each point to the nearest edge of a closed ring."""
    a, b = ring[None], np.roll(ring, -1, axis=0)[None]
    p = points[:, None]
    ab = b - a
    t = np.clip(((p - a) * ab).sum(axis=2) / np.maximum((ab * ab).sum(axis=2), 1e-300), 0, 1)
    return np.hypot(*(p - a - t[..., None] * ab).transpose(2, 0, 1)).min(axis=1)


def signed_area(ring):
    """Shoelace area, positive when counter-clockwise."""
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float((x * np.roll(y, -1) - np.roll(x, -1) * y).sum())


def rect_ring(rect):
    """The rectangle as a counter-clockwise ring."""
    xmin, ymin, xmax, ymax = rect
    return np.array([(xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax)], float)


def check_polygon_clip(polygon, window_ring, rings, grid=120):
    """Check rings = polygon ∩ convex window: inside, same orientation, grid membership, area, no gap edges."""
    lo, hi = window_ring.min(axis=0), window_ring.max(axis=0)
    size = float((hi - lo).max())
    orientation = np.sign(signed_area(polygon))
    for ring in rings:
        assert len(ring) >= 3
        assert not (ring == np.roll(ring, 1, axis=0)).all(axis=1).any(), "repeated consecutive vertex"
        assert np.sign(signed_area(ring)) == orientation, "output ring orientation differs from the input"
        assert (distance_to_edges(ring, window_ring)[~inside_polygon(ring, window_ring)] < 1e-9 * size).all()
    # membership on a grid: (polygon and window) == (union of rings), away from all boundaries
    u = (np.arange(grid) + 0.5) / grid
    gx, gy = np.meshgrid(lo[0] + u * (hi - lo)[0], lo[1] + u * (hi - lo)[1])
    pts = np.stack([gx.ravel(), gy.ravel()], axis=1)
    expected = inside_polygon(pts, polygon) & inside_polygon(pts, window_ring)
    got = np.zeros(len(pts), dtype=bool)
    for ring in rings:
        got ^= inside_polygon(pts, ring)
    near = (distance_to_edges(pts, polygon) < 1e-6 * size) | (distance_to_edges(pts, window_ring) < 1e-6 * size)
    assert (got == expected)[~near].all(), f"{int((got != expected)[~near].sum())} grid points differ"
    # area: exact shoelace sum of the rings vs the grid estimate of polygon ∩ window
    cell = float(np.prod((hi - lo) / grid))
    perimeter = float(np.hypot(*np.diff(np.vstack([polygon, polygon[:1]]), axis=0).T).sum())
    estimate = expected.sum() * cell
    exact = sum(abs(signed_area(r)) for r in rings)
    assert abs(exact - estimate) <= math.sqrt(cell) * (perimeter + 4 * size) + 1e-9
    # an output edge along the window border must have the polygon just inside it (no edge across a gap)
    centre = window_ring.mean(axis=0)
    for ring in rings:
        a, b = ring, np.roll(ring, -1, axis=0)
        along = (distance_to_edges(a, window_ring) < 1e-9 * size) & (distance_to_edges(b, window_ring) < 1e-9 * size)
        along &= np.hypot(*(b - a).T) > 1e-9 * size  # a rounding-length edge (a spike's two border points) spans no gap
        for f in (0.1234, 0.4321, 0.8765):  # sample points along each border edge, pushed inward
            p = a + f * (b - a)
            inward = p + (centre - p) * 1e-6
            on_border = along & (distance_to_edges(p, window_ring) < 1e-9 * size)
            test = on_border & (distance_to_edges(inward, polygon) > 1e-9 * size)
            assert inside_polygon(inward[test], polygon).all(), "an output edge runs along the border across a gap"


# ---------------------------------------------------------------------------------------------
# Outcodes

@pytest.mark.parametrize(
    "point, code",
    [((5, 5), 0), ((-1, 5), LEFT), ((11, 5), RIGHT), ((5, -1), BOTTOM), ((5, 11), TOP),
     ((-1, -1), LEFT | BOTTOM), ((11, -1), RIGHT | BOTTOM), ((-1, 11), LEFT | TOP), ((11, 11), RIGHT | TOP),
     ((0, 0), 0), ((10, 10), 0), ((0, 5), 0), ((10, 5), 0)],
)
def test_outcodes_of_each_region(point, code):
    assert outcodes(point, WINDOW) == code
    assert (LEFT, RIGHT, BOTTOM, TOP) == (1, 2, 4, 8)


def test_outcodes_vectorised():
    codes = outcodes([(-1, 5), (5, 5), (11, 11)], WINDOW)
    assert codes.dtype == np.uint8
    np.testing.assert_array_equal(codes, [1, 0, 10])


# ---------------------------------------------------------------------------------------------
# Cohen–Sutherland cases (both methods)

methods = pytest.mark.parametrize("method", ["cohen-sutherland", "liang-barsky"])


@methods
def test_both_endpoints_inside_is_accepted_unchanged(method):
    out, idx = clip_segments([(1, 2, 3, 4)], WINDOW, method)
    np.testing.assert_array_equal(out, [(1, 2, 3, 4)])
    np.testing.assert_array_equal(idx, [0])


@methods
def test_trivially_rejected(method):
    out, idx = clip_segments([(-5, 1, -1, 9), (1, 11, 9, 12), (12, -1, 15, 20)], WINDOW, method)
    assert out.shape == (0, 4) and idx.shape == (0,)


@methods
def test_outside_in_different_regions_but_missing_the_window(method):
    # codes LEFT and TOP, no common bit; at x = 0 the line is at y = 11.67: rejected after one clip
    out, _ = clip_segments([(-2, 9, 1, 13)], WINDOW, method)
    assert len(out) == 0


@methods
def test_one_clip(method):
    out, _ = clip_segments([(5, 5, 15, 5), (-3, 1, 3, 4)], WINDOW, method)
    np.testing.assert_allclose(out, [(5, 5, 10, 5), (0, 2.5, 3, 4)])


@methods
def test_two_clips(method):
    # slope 1/3 from (-3, 1): y(0) = 2, y(10) = 1 + 13/3
    out, _ = clip_segments([(-5, 5, 15, 5), (-3, 1, 12, 6), (12, 6, -3, 1)], WINDOW, method)
    np.testing.assert_allclose(out, [(0, 5, 10, 5), (0, 2, 10, 16 / 3), (10, 16 / 3, 0, 2)])


@methods
def test_corner_cases(method):
    segs = [
        (-5, -5, 5, 5),  # enters through the corner (0, 0)
        (-1, 11, 11, -1),  # the diagonal x + y = 10 through two corners
        (-1, 1, 1, -1),  # touches the window only at the corner (0, 0)
        (-3, 13, 13, -3),  # the same diagonal from further out
        (0, 10, 10, 10),  # along the top border
    ]
    out, idx = clip_segments(segs, WINDOW, method)
    np.testing.assert_allclose(out, [(0, 0, 5, 5), (0, 10, 10, 0), (0, 0, 0, 0), (0, 10, 10, 0), (0, 10, 10, 10)],
                               atol=1e-12)
    np.testing.assert_array_equal(idx, [0, 1, 2, 3, 4])


@methods
def test_zero_length_segments(method):
    out, idx = clip_segments([(3, 3, 3, 3), (-3, 3, -3, 3)], WINDOW, method)
    np.testing.assert_array_equal(out, [(3, 3, 3, 3)])
    np.testing.assert_array_equal(idx, [0])


def test_vectorised_cohen_sutherland_matches_the_scalar_loop():
    rng = np.random.default_rng(7)
    segs = rng.uniform(-10, 20, size=(3000, 4))
    rect = (0.0, 0.0, 10.0, 7.0)
    expected = [cohen_sutherland_reference(*s, *rect) for s in segs]
    keep = [i for i, e in enumerate(expected) if e is not None]
    for method in ("cohen-sutherland", "liang-barsky"):
        out, idx = clip_segments(segs, rect, method)
        np.testing.assert_array_equal(idx, keep)
        np.testing.assert_allclose(out, [expected[i] for i in keep], atol=1e-9)


coords = st.floats(-30, 40, allow_nan=False)
segments_strategy = st.lists(st.tuples(coords, coords, coords, coords), min_size=1, max_size=30)
rects = st.tuples(st.floats(-10, 10), st.floats(-10, 10), st.floats(0.5, 20), st.floats(0.5, 20)).map(
    lambda r: (r[0], r[1], r[0] + r[2], r[1] + r[3])
)


def same_segments_ignoring_touches(a, ia, b, ib, atol):
    """a and b agree, except that a segment shorter than atol (a touch) may be kept by only one."""
    da, db = dict(zip(ia.tolist(), a, strict=False)), dict(zip(ib.tolist(), b, strict=False))
    for i in set(da) | set(db):
        if i in da and i in db:
            np.testing.assert_allclose(da[i], db[i], atol=atol)
        else:
            s = da.get(i, db.get(i))
            assert math.hypot(s[2] - s[0], s[3] - s[1]) <= atol


@settings(max_examples=80, deadline=None)
@given(segs=segments_strategy, rect=rects)
def test_liang_barsky_equals_cohen_sutherland(segs, rect):
    a, ia = clip_segments(segs, rect, "cohen-sutherland")
    b, ib = clip_segments(segs, rect, "liang-barsky")
    same_segments_ignoring_touches(a, ia, b, ib, 1e-7)


@settings(max_examples=80, deadline=None)
@given(segs=segments_strategy, rect=rects, method=st.sampled_from(["cohen-sutherland", "liang-barsky"]))
def test_clipped_segments_are_inside_on_their_source_and_idempotent(segs, rect, method):
    segs = np.array(segs)
    out, idx = clip_segments(segs, rect, method)
    xmin, ymin, xmax, ymax = rect
    assert ((out[:, 0::2] >= xmin) & (out[:, 0::2] <= xmax) & (out[:, 1::2] >= ymin) & (out[:, 1::2] <= ymax)).all()
    src = segs[idx]
    d = src[:, 2:] - src[:, :2]
    length = np.hypot(d[:, 0], d[:, 1])
    for end in (out[:, :2], out[:, 2:]):  # endpoints lie on the source segment
        cross = np.abs(d[:, 0] * (end[:, 1] - src[:, 1]) - d[:, 1] * (end[:, 0] - src[:, 0]))
        assert (cross <= 1e-7 * (1 + length) ** 2).all()
    # nothing inside is lost: points of the source well inside the window are covered by the output
    for t in np.linspace(0, 1, 11):
        p = segs[:, :2] + t * (segs[:, 2:] - segs[:, :2])
        well_inside = np.flatnonzero((p[:, 0] > xmin + 1e-6) & (p[:, 0] < xmax - 1e-6)
                                     & (p[:, 1] > ymin + 1e-6) & (p[:, 1] < ymax - 1e-6))
        assert set(well_inside) <= set(idx.tolist())
    again, idx2 = clip_segments(out, rect, method)
    np.testing.assert_array_equal(again, out)
    np.testing.assert_array_equal(idx2, np.arange(len(out)))


@pytest.mark.parametrize(
    "segments, message",
    [(np.zeros((3, 3)), "shape"), ([(0, 0, 1, np.nan)], "row 0"), ([(0, 0, 1, 1), (np.inf, 0, 1, 1)], "row 1"),
     ("x", "numbers")],
)
def test_bad_segments_are_rejected(segments, message):
    with pytest.raises(ValueError, match=message):
        clip_segments(segments, WINDOW)


def test_bad_window_and_method_are_rejected():
    with pytest.raises(ValueError, match="degenerate"):
        clip_segments([(0, 0, 1, 1)], (0, 0, 0, 1))
    with pytest.raises(ValueError, match="unknown clipping method"):
        clip_segments([(0, 0, 1, 1)], WINDOW, "sutherland")
    with pytest.raises(ValueError, match="degenerate"):
        outcodes((0, 0), (1, 1, 1, 2))


def test_segments_as_point_pairs():
    out, _ = clip_segments(np.array([[(-5, 5), (15, 5)]]), WINDOW)
    np.testing.assert_array_equal(out, [(0, 5, 10, 5)])


# ---------------------------------------------------------------------------------------------
# Polygon clipping

U_SHAPE = np.array([(1, 1), (9, 1), (9, 12), (7, 12), (7, 3), (3, 3), (3, 12), (1, 12)], float)
COMB = np.array([(1, 5), (3, 5), (3, 12), (4, 12), (4, 5), (6, 5), (6, 12), (7, 12), (7, 5), (9, 5), (9, 15), (1, 15)],
                float)


def as_vertex_set(ring):
    """Vertices as a set of rounded tuples (rings compare independent of start vertex)."""
    return {tuple(np.round(v, 9)) for v in ring}


def test_triangle_with_one_corner_cut():
    rings = clip_polygon([(2, 2), (14, 2), (2, 8)], WINDOW)
    assert len(rings) == 1
    # hypotenuse from (14, 2) to (2, 8): y = 2 + (14 - x) / 2, meets x = 10 at y = 4
    assert as_vertex_set(rings[0]) == {(2, 2), (10, 2), (10, 4), (2, 8)}


def test_concave_polygon_leaving_through_the_top_stays_one_ring():
    rings = clip_polygon(U_SHAPE, WINDOW)
    assert len(rings) == 1
    assert as_vertex_set(rings[0]) == {(1, 1), (9, 1), (9, 10), (7, 10), (7, 3), (3, 3), (3, 10), (1, 10)}
    assert abs(signed_area(rings[0])) == pytest.approx(8 * 9 - 4 * 7)


def test_comb_splits_into_separate_rings_without_border_edges_between_them():
    rings = clip_polygon(COMB, WINDOW)
    assert len(rings) == 3
    assert sorted(map(frozenset, map(as_vertex_set, rings)), key=min) == sorted([
        frozenset({(1, 5), (3, 5), (3, 10), (1, 10)}),
        frozenset({(4, 5), (6, 5), (6, 10), (4, 10)}),
        frozenset({(7, 5), (9, 5), (9, 10), (7, 10)}),
    ], key=min)
    check_polygon_clip(COMB, rect_ring(WINDOW), rings)


def test_clockwise_input_gives_clockwise_rings():
    rings = clip_polygon(COMB[::-1], WINDOW)
    assert len(rings) == 3 and all(signed_area(r) < 0 for r in rings)


def test_window_inside_the_polygon_and_polygon_outside_the_window():
    rings = clip_polygon([(-1, -1), (11, -1), (11, 11), (-1, 11)], WINDOW)
    assert len(rings) == 1 and as_vertex_set(rings[0]) == {(0, 0), (10, 0), (10, 10), (0, 10)}
    assert clip_polygon([(20, 20), (30, 20), (30, 30)], WINDOW) == []
    assert clip_polygon([(-5, -5), (15, -5), (15, -1)], WINDOW) == []
    inside = np.array([(1, 1), (2, 1), (2, 2)], float)
    np.testing.assert_array_equal(clip_polygon(inside, WINDOW)[0], inside)


def test_polygon_touching_the_window_from_outside_gives_nothing():
    assert clip_polygon([(10, 2), (15, 2), (15, 8), (10, 8)], WINDOW) == []  # shares the right border only
    assert clip_polygon([(10, 5), (15, 2), (15, 8)], WINDOW) == []  # a vertex on the border


@st.composite
def star_polygons(draw):
    """Random simple (star-shaped, usually concave) polygons of either orientation around the window."""
    n = draw(st.integers(3, 18))
    cx, cy = draw(st.floats(-6, 16)), draw(st.floats(-6, 16))
    radius = draw(st.floats(2, 16))
    gaps = np.array(draw(st.lists(st.floats(0.55, 1.0), min_size=n, max_size=n)))  # every gap < pi: simple
    angles = 2 * np.pi * np.cumsum(gaps) / gaps.sum()
    radii = radius * np.array(draw(st.lists(st.floats(0.15, 1.0), min_size=n, max_size=n)))
    poly = np.stack([cx + radii * np.cos(angles), cy + radii * np.sin(angles)], axis=1)
    return poly[::-1].copy() if draw(st.booleans()) else poly


@settings(max_examples=30, deadline=None)
@given(poly=star_polygons())
# a sliver tip 6e-8 off the border
@example(poly=np.array([[-1.0, 1.73205087], [-1.0, -1.73205075], [2.0, 5.96046443e-08]]))
def test_clipped_concave_polygon_is_polygon_and_window(poly):
    rings = clip_polygon(poly, WINDOW)
    check_polygon_clip(poly, rect_ring(WINDOW), rings)


@settings(max_examples=30, deadline=None)
@given(poly=star_polygons())
def test_polygon_clipping_is_idempotent(poly):
    for ring in clip_polygon(poly, WINDOW):
        again = clip_polygon(ring, WINDOW)
        assert len(again) == 1 and as_vertex_set(again[0]) == as_vertex_set(ring)


@st.composite
def convex_windows(draw):
    """Random convex polygons: points at sorted angles on a rotated ellipse, either orientation."""
    n = draw(st.integers(3, 9))
    gaps = np.array(draw(st.lists(st.floats(0.3, 1.0), min_size=n, max_size=n)))
    angles = 2 * np.pi * np.cumsum(gaps) / gaps.sum()
    rx, ry, tilt = draw(st.floats(3, 8)), draw(st.floats(3, 8)), draw(st.floats(0, np.pi))
    ex, ey = rx * np.cos(angles), ry * np.sin(angles)
    win = np.stack([5 + ex * np.cos(tilt) - ey * np.sin(tilt), 5 + ex * np.sin(tilt) + ey * np.cos(tilt)], axis=1)
    return win[::-1].copy() if draw(st.booleans()) else win


@settings(max_examples=30, deadline=None)
@given(poly=star_polygons(), win=convex_windows())
def test_convex_window_polygon_clipping(poly, win):
    rings = clip_polygon_convex(poly, win)
    ccw = win if signed_area(win) > 0 else win[::-1]
    check_polygon_clip(poly, ccw, rings)


def test_convex_clipping_with_a_rectangle_matches_rectangle_clipping():
    for poly in (U_SHAPE, COMB, COMB[::-1]):
        a = clip_polygon(poly, WINDOW)
        b = clip_polygon_convex(poly, rect_ring(WINDOW)[::-1])  # clockwise window accepted
        assert sorted(map(frozenset, map(as_vertex_set, a)), key=sorted) == sorted(
            map(frozenset, map(as_vertex_set, b)), key=sorted
        )


def test_convex_window_worked_example():
    triangle = [(0, 0), (10, 0), (0, 10)]
    rings = clip_polygon_convex([(-5, -5), (5, -5), (5, 5), (-5, 5)], triangle)
    assert len(rings) == 1 and as_vertex_set(rings[0]) == {(0, 0), (5, 0), (5, 5), (0, 5)}
    rings = clip_polygon_convex([(0, 0), (10, 0), (10, 10), (0, 10)], triangle)
    assert abs(signed_area(rings[0])) == pytest.approx(50)


@pytest.mark.parametrize(
    "window, message",
    [
        ([(0, 0), (10, 0), (5, 2), (5, 10)], "not convex"),
        ([(0, 0), (1, 1), (2, 2)], "degenerate"),
        ([(0, 0), (1, 0)], "at least 3"),
        ([(0, 0), (0, 0), (1, 1), (0, 1)], "zero-length edge"),
        ([(0, 0), (4, 0), (np.nan, 4)], "row 2"),
        ([(np.cos(a), np.sin(a)) for a in 4 * np.pi * np.arange(5) / 5], "winds"),
    ],  # a pentagram
)
def test_bad_convex_windows_are_rejected(window, message):
    with pytest.raises(ValueError, match=message):
        clip_polygon_convex([(0, 0), (1, 0), (0, 1)], window)
    with pytest.raises(ValueError, match=message):
        clip_segments_convex([(0, 0, 1, 1)], window)


def test_bad_polygons_are_rejected():
    with pytest.raises(ValueError, match="at least 3"):
        clip_polygon([(0, 0), (1, 1)], WINDOW)
    with pytest.raises(ValueError, match="row 1"):
        clip_polygon([(0, 0), (np.nan, 1), (1, 0)], WINDOW)
    with pytest.raises(ValueError, match="degenerate"):
        clip_polygon([(0, 0), (1, 1), (1, 0)], (0, 0, 5, -5))


# ---------------------------------------------------------------------------------------------
# Cyrus–Beck


def test_cyrus_beck_worked_example():
    # triangle (0,0), (10,0), (5,10): at y = 5 the left edge is at x = 2.5, the right edge at x = 7.5
    out, idx = clip_segments_convex([(-5, 5, 15, 5), (20, 20, 30, 30), (5, 5, 5, 1)], [(0, 0), (10, 0), (5, 10)])
    np.testing.assert_allclose(out, [(2.5, 5, 7.5, 5), (5, 5, 5, 1)])
    np.testing.assert_array_equal(idx, [0, 2])


@settings(max_examples=60, deadline=None)
@given(segs=segments_strategy, rect=rects, clockwise=st.booleans())
def test_cyrus_beck_on_a_rectangle_equals_cohen_sutherland(segs, rect, clockwise):
    ring = rect_ring(rect)
    a, ia = clip_segments(segs, rect)
    b, ib = clip_segments_convex(segs, ring[::-1] if clockwise else ring)
    same_segments_ignoring_touches(a, ia, b, ib, 1e-7)


@settings(max_examples=60, deadline=None)
@given(segs=segments_strategy, win=convex_windows())
def test_cyrus_beck_output_is_inside_and_complete(segs, win):
    segs = np.array(segs)
    out, idx = clip_segments_convex(segs, win)
    ccw = win if signed_area(win) > 0 else win[::-1]
    for end in (out[:, :2], out[:, 2:]):
        outside = ~inside_polygon(end, ccw)
        assert (distance_to_edges(end[outside], ccw) < 1e-9).all()
    for t in np.linspace(0, 1, 11):
        p = segs[:, :2] + t * (segs[:, 2:] - segs[:, :2])
        well_inside = np.flatnonzero(inside_polygon(p, ccw) & (distance_to_edges(p, ccw) > 1e-6))
        assert set(well_inside) <= set(idx.tolist())


# ---------------------------------------------------------------------------------------------
# Polylines


def test_polyline_leaving_and_reentering_becomes_several_pieces():
    line = [(-5, 5), (5, 5), (5, 15), (6, 15), (6, 5), (8, 5)]
    pieces, src = clip_polylines([line, [(1, 1)], [(20, 20)], [(2, 2), (3, 3)]], WINDOW, return_index=True)
    assert len(pieces) == 4
    np.testing.assert_array_equal(pieces[0], [(0, 5), (5, 5), (5, 10)])
    np.testing.assert_array_equal(pieces[1], [(6, 10), (6, 5), (8, 5)])
    np.testing.assert_array_equal(pieces[2], [(1, 1)])
    np.testing.assert_array_equal(pieces[3], [(2, 2), (3, 3)])
    np.testing.assert_array_equal(src, [0, 0, 1, 3])


@settings(max_examples=50, deadline=None)
@given(lines=st.lists(st.lists(st.tuples(coords, coords), min_size=2, max_size=12), min_size=1, max_size=6), rect=rects)
def test_polyline_pieces_cover_exactly_the_clipped_segments(lines, rect):
    pieces, src = clip_polylines(lines, rect, return_index=True)
    segs = np.concatenate([np.hstack([np.array(p)[:-1], np.array(p)[1:]]) for p in lines])
    clipped, _ = clip_segments(segs, rect)
    clipped_length = np.hypot(clipped[:, 2] - clipped[:, 0], clipped[:, 3] - clipped[:, 1]).sum()
    piece_length = sum(np.hypot(*np.diff(p, axis=0).T).sum() for p in pieces)
    assert piece_length == pytest.approx(clipped_length, abs=1e-9)
    xmin, ymin, xmax, ymax = rect
    for p in pieces:
        assert ((p[:, 0] >= xmin) & (p[:, 0] <= xmax) & (p[:, 1] >= ymin) & (p[:, 1] <= ymax)).all()
    assert (np.diff(src) >= 0).all()


def test_bad_polylines_are_rejected():
    with pytest.raises(ValueError, match=r"polylines\[1\]"):
        clip_polylines([[(0, 0), (1, 1)], np.zeros((0, 2))], WINDOW)
    with pytest.raises(ValueError, match=r"polylines\[0\].*row 1"):
        clip_polylines([[(0, 0), (np.nan, 1)]], WINDOW)
    assert clip_polylines([], WINDOW) == []


def _liang_barsky_textbook(x0, y0, x1, y1, xmin, ymin, xmax, ymax):
    """Liang & Barsky (1984) as Foley et al. write it, one segment: (t0, t1) or None when rejected."""
    t0, t1 = 0.0, 1.0
    dx, dy = x1 - x0, y1 - y0
    for p, q in ((-dx, x0 - xmin), (dx, xmax - x0), (-dy, y0 - ymin), (dy, ymax - y0)):
        if p == 0:
            if q < 0:
                return None
        elif p < 0:
            t0 = max(t0, q / p)
        else:
            t1 = min(t1, q / p)
    return (t0, t1) if t0 <= t1 else None


def test_liang_barsky_parameters_match_the_textbook_exactly():
    from pixelpen.geometry.clip import liang_barsky_parameters

    rng = np.random.default_rng(9)
    segs = rng.integers(-40, 140, size=(4000, 4)).astype(np.float64)
    segs[::7, 2] = segs[::7, 0]  # vertical and horizontal ones too
    segs[::11, 3] = segs[::11, 1]
    rect = (-3.0, -3.0, 99.0, 63.0)
    t0, t1, keep = liang_barsky_parameters(np.ascontiguousarray(segs.T), rect)
    for i, seg in enumerate(segs):
        want = _liang_barsky_textbook(*seg, *rect)
        assert bool(keep[i]) == (want is not None), i
        if want is not None:
            assert (t0[i], t1[i]) == want, i


# ---------------------------------------------------------------------------------------------
# Zero-width spikes across the border: an exit meeting the next entry is no gap or a full loop

SQUARE = (-1.0, -1.0, 1.0, 1.0)


def quarter_turns(points, k):
    """Points turned k quarter turns counter-clockwise about the origin (exact)."""
    p = np.array(points, float)
    for _ in range(k):
        p = np.stack([-p[:, 1], p[:, 0]], axis=1)
    return p


def turned(points, angle):
    """Points rotated by ``angle`` about the origin."""
    c, s = math.cos(angle), math.sin(angle)
    return np.asarray(points, float) @ np.array([[c, s], [-s, c]])


def total_area(rings):
    """Summed absolute shoelace area of rings."""
    return sum(abs(signed_area(r)) for r in rings)


def test_zero_area_spike_across_the_border_gives_nothing():
    assert clip_polygon(np.array([[0.0, 0.5], [0.0, 0.5], [1.33984375, 1.921875]]), SQUARE) == []


def test_window_covered_but_for_a_zero_width_spike_gives_the_window():
    rings = clip_polygon([(-2, -2), (2, -2), (2, 2), (0.3, 2), (0.3, 0), (0.3, 2), (-2, 2)], SQUARE)
    assert len(rings) == 1 and abs(signed_area(rings[0])) == pytest.approx(4)


def test_notch_of_real_width_is_cut_out():
    # the notch (0.3, 0), (0.31, 2), (0.3, 2) is x = 0.3 .. 0.3 + 0.005 y: inside y <= 1 a triangle 0.005 x 1 / 2
    rings = clip_polygon([(-2, -2), (2, -2), (2, 2), (0.31, 2), (0.3, 0), (0.3, 2), (-2, 2)], SQUARE)
    assert len(rings) == 1 and abs(signed_area(rings[0])) == pytest.approx(4 - 0.0025)


def spike_polygon(family, b, tip):
    """A square with a zero-width spike from (x, b) on its right side to ``tip`` and back, and the clipped area.

    inner: [-0.5, 0.5]^2 inside the window, spiking out through x = 1 (area 1);
    outer: [-2, 2]^2 around the window, spiking in through x = 1 (area 4);
    away: [1.5, 3] x [-0.5, 0.5] right of the window, spiking in through x = 1 (area 0).
    """
    lo, hi, x, area = {"inner": (-0.5, 0.5, 0.5, 1.0), "outer": (-2, 2, 2, 4.0), "away": (-0.5, 0.5, 3, 0.0)}[family]
    left = 1.5 if family == "away" else lo
    return [(left, lo), (x, lo), (x, b), tip, (x, b), (x, hi), (left, hi)], area


SPIKES = [
    (family, b, tip)
    for family, tips in (
        ("inner", [(1.33984375, 0.921875), (1.7, 0.3), (1.3, -0.77), (2.1, 0.123)]),
        ("outer", [(0.3, 0.0), (0.1, 0.7), (-0.3, 0.2), (0.77, -0.41), (-0.9, -0.9)]),
        ("away", [(0.3, 0.0), (0.1, 0.7), (-0.3, 0.2), (0.123, 0.456)]),
    )
    for tip in tips
    for b in (0.0, 0.1, 0.37)
]
CORNER_SPIKES = [  # spikes along the diagonal through the window corner (1, 1)
    ([(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (1.5, 1.5), (0.5, 0.5), (-0.5, 0.5)], 1.0),
    ([(-2, -2), (2, -2), (2, 2), (0.3, 0.3), (2, 2), (-2, 2)], 4.0),
    ([(1.5, 1.5), (3, 1.5), (3, 3), (1.5, 3), (1.5, 1.5), (0.2, 0.2)], 0.0),
    ([(-0.5, -0.5), (0.5, -0.5), (0.5, 0.3), (1.7, 1.2), (0.5, 0.3), (-0.5, 0.5)], 0.9),  # near the corner
]


@pytest.mark.parametrize("side", range(4))
@pytest.mark.parametrize("family, b, tip", SPIKES)
def test_spike_through_each_side(family, b, tip, side):
    polygon, area = spike_polygon(family, b, tip)
    polygon = quarter_turns(polygon, side)  # right, top, left, bottom side of the window
    for poly in (polygon, polygon[::-1]):
        rings = clip_polygon(poly, SQUARE)
        assert total_area(rings) == pytest.approx(area, abs=1e-12)
        assert len(rings) == (1 if area else 0)


@pytest.mark.parametrize("corner", range(4))
@pytest.mark.parametrize("polygon, area", CORNER_SPIKES)
def test_spike_through_a_corner(polygon, area, corner):
    polygon = quarter_turns(polygon, corner)
    for poly in (polygon, polygon[::-1]):
        rings = clip_polygon(poly, SQUARE)
        assert total_area(rings) == pytest.approx(area, abs=1e-12)
        assert len(rings) == (1 if area else 0)


@pytest.mark.parametrize("angle", [0.3, 1.0, 2.5, -0.7])
@pytest.mark.parametrize("polygon, area", [spike_polygon(*s) for s in SPIKES] + CORNER_SPIKES)
def test_spikes_on_a_rotated_convex_window(polygon, area, angle):
    window = turned(rect_ring(SQUARE), angle)
    for poly in (turned(polygon, angle), turned(polygon, angle)[::-1]):
        rings = clip_polygon_convex(poly, window)
        assert total_area(rings) == pytest.approx(area, abs=1e-9)
        assert len(rings) == (1 if area else 0)


def cross(u, v):
    """z component of the cross product of 2-D vectors (broadcasting)."""
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


@st.composite
def spiked_polygons(draw):
    """(base, spiked): a star polygon, and the same with a zero-width spike from a point of one edge to a tip."""
    base = draw(star_polygons())
    i = draw(st.integers(0, len(base) - 1))
    f = draw(st.sampled_from([0.0, 0.5]) | st.floats(0, 1))
    root = base[i] + f * (base[(i + 1) % len(base)] - base[i])
    tip = np.array([draw(st.floats(-8, 18)), draw(st.floats(-8, 18))])
    a, b = base, np.roll(base, -1, axis=0)
    side = np.sign(cross(tip - root, a - root)) * np.sign(cross(tip - root, b - root))
    across = np.sign(cross(b - a, root - a)) * np.sign(cross(b - a, tip - a))
    assume(not ((side < 0) & (across < 0)).any())  # a spike crossing an edge makes the polygon not simple
    spiked = np.vstack([base[:i + 1], [root, tip, root], base[i + 1:]])
    return base, spiked


try:
    import shapely
except ImportError:  # optional oracle: the grid reference below always runs
    shapely = None


@settings(max_examples=60, deadline=None)
@given(polys=spiked_polygons(), win=st.none() | convex_windows())
@example(polys=(np.array([(-2, -2), (2, -2), (2, 2), (-2, 2)], float) + 5,
                np.array([(-2, -2), (2, -2), (2, 2), (0.3, 2), (0.3, 0), (0.3, 2), (-2, 2)]) + 5), win=None)
def test_a_zero_width_spike_changes_no_area(polys, win):
    base, spiked = polys
    window = rect_ring(WINDOW) if win is None else (win if signed_area(win) > 0 else win[::-1])
    rings = clip_polygon(spiked, WINDOW) if win is None else clip_polygon_convex(spiked, win)
    check_polygon_clip(spiked, window, rings)  # the grid reference skips points near the spike's edges
    if shapely is not None:
        want = shapely.Polygon(base).intersection(shapely.Polygon(window)).area
        assert total_area(rings) == pytest.approx(want, abs=1e-9 * 100)

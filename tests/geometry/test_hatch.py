"""Tests of scan-line hatching: against a scalar textbook scan-line fill, an independent inside test, areas."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.geometry.hatch import hatch

# --- independent references -------------------------------------------------------------------------------------


def inside_evenodd(px, py, rings):
    """Ray casting (Hearn & Baker's odd-parity rule): count edge crossings of a ray to +x."""
    crossings = 0
    for ring in rings:
        n = len(ring)
        for i in range(n):
            x0, y0 = ring[i]
            x1, y1 = ring[(i + 1) % n]
            if (y0 > py) != (y1 > py):
                x = x0 + (py - y0) * (x1 - x0) / (y1 - y0)
                if x > px:
                    crossings += 1
    return crossings % 2 == 1


def distance_to_boundary(px, py, rings):
    best = math.inf
    for ring in rings:
        n = len(ring)
        for i in range(n):
            ax, ay = ring[i]
            bx, by = ring[(i + 1) % n]
            dx, dy = bx - ax, by - ay
            L2 = dx * dx + dy * dy
            t = 0.0 if L2 == 0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / L2))
            best = min(best, math.hypot(px - (ax + t * dx), py - (ay + t * dy)))
    return best


def scanline_reference(rings, ys):
    """Textbook scan-line polygon fill: for each scan line, intersect every edge (half-open), sort, pair."""
    spans = []
    for y in ys:
        xs = []
        for ring in rings:
            n = len(ring)
            for i in range(n):
                x0, y0 = ring[i]
                x1, y1 = ring[(i + 1) % n]
                if min(y0, y1) <= y < max(y0, y1):
                    xs.append(x0 + (y - y0) * (x1 - x0) / (y1 - y0))
        xs.sort()
        for a, b in zip(xs[0::2], xs[1::2], strict=False):
            if b > a:
                spans.append((y, a, b))
    return spans


def shoelace(ring):
    x, y = np.asarray(ring).T
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def rotate(points, angle):
    c, s = math.cos(angle), math.sin(angle)
    p = np.asarray(points, float)
    return np.column_stack([p[:, 0] * c - p[:, 1] * s, p[:, 0] * s + p[:, 1] * c])


def segments_of(paths):
    return [(p[i], p[i + 1]) for p in paths for i in range(len(p) - 1)]


SQUARE = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float)


def circle(cx, cy, r, n=48):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t)])


# --- worked examples ---------------------------------------------------------------------------------------------


def test_square_zigzag_is_one_boustrophedon_path():
    # 10 units tall at spacing 2: five lines centred in the extent, at y = 1, 3, 5, 7, 9
    paths = hatch(SQUARE, 2.0)
    assert len(paths) == 1
    expected = [[0, 1], [10, 1], [10, 3], [0, 3], [0, 5], [10, 5], [10, 7], [0, 7], [0, 9], [10, 9]]
    np.testing.assert_allclose(paths[0], expected, atol=1e-12)


def test_unjoined_lines_alternate_direction():
    paths = hatch(SQUARE, 2.0, join=False)
    assert [p.tolist() for p in paths] == [
        [[0, 1], [10, 1]],
        [[10, 3], [0, 3]],
        [[0, 5], [10, 5]],
        [[10, 7], [0, 7]],
        [[0, 9], [10, 9]],
    ]


def test_lines_are_centred_and_at_the_requested_spacing():
    rect = np.array([[0, 0], [7, 0], [7, 10.5], [0, 10.5]], float)
    paths = hatch(rect, 1.5, join=False)
    ys = sorted({round(p[0, 1], 9) for p in paths})
    # ceil(10.5 / 1.5) = 7 lines, centred: first at (10.5 - 6 * 1.5) / 2 = 0.75
    np.testing.assert_allclose(ys, 0.75 + 1.5 * np.arange(7))
    assert all(p[0, 1] == p[1, 1] for p in paths)


def test_thin_shape_still_gets_one_line():
    sliver = np.array([[0, 0], [10, 0], [10, 0.2], [0, 0.2]], float)
    paths = hatch(sliver, 1.0)
    assert len(paths) == 1
    np.testing.assert_allclose(paths[0], [[0, 0.1], [10, 0.1]])


def test_matches_scalar_scanline_reference_with_hole():
    outer = circle(50, 50, 40)
    hole = circle(50, 45, 15)[::-1]
    rings = [outer, hole]
    spacing = 3.0
    paths = hatch(rings, spacing, join=False)
    ys = sorted({p[0, 1] for p in paths})
    ref = scanline_reference(rings, ys)
    got = sorted((p[0, 1], min(p[0, 0], p[1, 0]), max(p[0, 0], p[1, 0])) for p in paths)
    assert len(got) == len(ref)
    np.testing.assert_allclose(np.array(got), np.array(sorted(ref)), atol=1e-9)
    # lines through the hole are split in two, and no hatch midpoint lies in the hole
    for a, b in segments_of(paths):
        mx, my = (a + b) / 2
        assert inside_evenodd(mx, my, rings)
        assert not inside_evenodd(mx, my, [hole])


def test_angle_turns_the_lines():
    angle = math.radians(30)
    paths = hatch(circle(0, 0, 10), 1.0, angle=angle, join=False)
    for p in paths:
        d = p[1] - p[0]
        assert abs(d[0] * math.sin(angle) - d[1] * math.cos(angle)) < 1e-9 * np.hypot(*d)
    # perpendicular offsets of the lines are multiples of the spacing
    offs = sorted({round(-p[0, 0] * math.sin(angle) + p[0, 1] * math.cos(angle), 9) for p in paths})
    np.testing.assert_allclose(np.diff(offs), 1.0, atol=1e-9)


def test_cross_hatch_has_both_directions():
    paths = hatch(SQUARE, 2.0, angle=0.0, cross=True, join=False)
    horizontal = [p for p in paths if abs(p[0, 1] - p[1, 1]) < 1e-12]
    vertical = [p for p in paths if abs(p[0, 0] - p[1, 0]) < 1e-12]
    assert len(horizontal) == 5 and len(vertical) == 5 and len(paths) == 10


def test_zigzag_connectors_follow_the_boundary_and_stay_inside():
    rings = [circle(50, 50, 40), circle(50, 45, 15)]
    paths = hatch(rings, 2.5, angle=0.3)
    unjoined = hatch(rings, 2.5, angle=0.3, join=False)
    assert len(paths) < len(unjoined) / 4  # lines really are joined
    for a, b in segments_of(paths):
        mx, my = (a + b) / 2
        assert inside_evenodd(mx, my, rings) or distance_to_boundary(mx, my, rings) < 1e-9
        # connectors (not along the hatch direction) lie on the boundary
        d = b - a
        along = abs(d[0] * math.sin(0.3) - d[1] * math.cos(0.3)) < 1e-9 * (1 + np.hypot(*d))
        if not along:
            assert distance_to_boundary(mx, my, rings) < 1e-9

    # joined paths contain every hatch span: the length along the hatch direction is the same
    def along_length(ps):
        total = 0.0
        for a, b in segments_of(ps):
            d = b - a
            if abs(d[0] * math.sin(0.3) - d[1] * math.cos(0.3)) < 1e-9 * (1 + np.hypot(*d)):
                total += np.hypot(*d)
        return total

    assert along_length(paths) == pytest.approx(along_length(unjoined), rel=1e-9)


def test_no_join_across_a_long_detour():
    # a U shape: the two arms are only connected far below, so lines in the arms are not joined across the gap
    u = np.array([[0, 0], [30, 0], [30, 30], [20, 30], [20, 10], [10, 10], [10, 30], [0, 30]], float)
    paths = hatch(u, 2.0)
    for a, b in segments_of(paths):
        mx, my = (a + b) / 2
        assert inside_evenodd(mx, my, [u]) or distance_to_boundary(mx, my, [u]) < 1e-9
    # nothing crosses the notch between the arms (10 < x < 20, y > 10)
    for a, b in segments_of(paths):
        if min(a[1], b[1]) > 10:
            assert not (min(a[0], b[0]) < 10 + 1e-9 and max(a[0], b[0]) > 20 - 1e-9)


def test_hatched_length_times_spacing_approximates_area():
    ring = circle(0, 0, 20, n=200)
    spacing = 0.25
    paths = hatch(ring, spacing, angle=0.7, join=False)
    length = sum(np.hypot(*(p[1] - p[0])) for p in paths)
    assert length * spacing == pytest.approx(shoelace(ring), rel=2e-3)


def test_degenerate_and_empty_input():
    assert hatch([], 1.0) == []
    assert hatch(np.array([[0, 0], [10, 0], [20, 0]], float), 1.0) == []  # no area
    assert hatch([np.zeros((0, 2))], 1.0) == []


@pytest.mark.parametrize("spacing", [0, -1, float("nan"), float("inf")])
def test_bad_spacing(spacing):
    with pytest.raises(ConfigError, match="spacing"):
        hatch(SQUARE, spacing)


def test_bad_rings():
    with pytest.raises(ConfigError, match="ring 0"):
        hatch([np.zeros((4, 3))], 1.0)
    with pytest.raises(ConfigError, match="non-finite"):
        hatch([np.array([[0, 0], [1, np.nan], [1, 1]])], 1.0)
    with pytest.raises(ConfigError, match="angle"):
        hatch(SQUARE, 1.0, angle=float("inf"))


def test_spacing_too_small_is_refused_not_hung():
    with pytest.raises(ConfigError, match="too small"):
        hatch(np.array([[0, 0], [1e6, 0], [1e6, 1e6], [0, 1e6]], float), 1e-3)


# --- invariants -------------------------------------------------------------------------------------------------


@st.composite
def star_polygons(draw):
    n = draw(st.integers(3, 14))
    angles = np.sort(
        np.array(draw(st.lists(st.floats(0, 2 * np.pi, exclude_max=True), min_size=n, max_size=n, unique=True)))
    )
    radii = np.array(draw(st.lists(st.floats(1.0, 20.0), min_size=n, max_size=n)))
    ring = np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])
    if shoelace(ring) < 1.0:
        ring = circle(0, 0, 5, 7)
    return ring


@settings(max_examples=25, deadline=None)
@given(star_polygons(), st.floats(0.3, 4.0), st.floats(-3.2, 3.2), st.booleans())
def test_every_piece_lies_inside_the_polygon(ring, spacing, angle, join):
    paths = hatch(ring, spacing, angle=angle, join=join)
    rings = [ring]
    scale = 1e-9 * 40
    for a, b in segments_of(paths):
        for f in (0.25, 0.5, 0.75):
            px, py = a + f * (b - a)
            assert inside_evenodd(px, py, rings) or distance_to_boundary(px, py, rings) < scale
    unjoined = hatch(ring, spacing, angle=angle, join=False)
    # spans match the scalar reference computed in the rotated frame
    rot = rotate(ring, -angle)
    spans = [rotate(p, -angle) for p in unjoined]
    raw = sorted(s[0, 1] for s in spans)
    ys = [y for i, y in enumerate(raw) if i == 0 or y - raw[i - 1] > 1e-9]  # one value per line (round-off)
    ref = scanline_reference([rot], ys)
    got_len = sum(abs(s[1, 0] - s[0, 0]) for s in spans)
    ref_len = sum(b - a for _, a, b in ref)
    assert got_len == pytest.approx(ref_len, rel=1e-7, abs=1e-7)
    if len(ys) > 1:
        steps = np.diff(ys) / spacing
        np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)

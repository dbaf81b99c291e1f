"""Tests of Douglas–Peucker simplification against a scalar recursive reference written from the textbook."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.simplify import simplify, simplify_mask


def _dist(p, a, b) -> float:
    """Distance from p to segment a-b (to a when a == b)."""
    (px, py), (ax, ay), (bx, by) = p, a, b
    dx, dy = bx - ax, by - ay
    den = dx * dx + dy * dy
    t = 0.0 if den == 0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / den))
    return math.hypot(px - ax - t * dx, py - ay - t * dy)


def reference(points: list[tuple[float, float]], tol: float) -> list[int]:
    """Douglas & Peucker (1973), recursive: indices kept."""
    def rec(lo: int, hi: int) -> list[int]:
        best, at = -1.0, -1
        for i in range(lo + 1, hi):
            d = _dist(points[i], points[lo], points[hi])
            if d > best:
                best, at = d, i
        if at < 0 or best <= tol:
            return [lo]
        return rec(lo, at) + rec(at, hi)

    if len(points) == 1:
        return [0]
    return [*rec(0, len(points) - 1), len(points) - 1]


def test_collinear_points_go():
    dl = DisplayList.from_polylines([[(0, 0), (1, 1), (2, 2), (5, 5)]])
    assert simplify(dl, 0.01).stroke(0).tolist() == [[0, 0], [5, 5]]


def test_zigzag_above_tolerance_stays():
    pts = [(0, 0), (1, 1), (2, 0), (3, 1), (4, 0)]
    assert simplify(DisplayList.from_polylines([pts]), 0.5).stroke(0).tolist() == [list(p) for p in pts]
    assert simplify(DisplayList.from_polylines([pts]), 1.0).stroke(0).tolist() == [[0, 0], [4, 0]]


def test_worked_example():
    # farthest from (0,0)-(10,0) is (6, 3) at 3 > 1: kept, and the range splits there
    pts = [(0, 0), (2, 0.4), (6, 3), (8, 0.2), (10, 0)]
    kept = simplify_mask(np.array(pts, float), np.array([0, 5]), 1.0)
    # (2, 0.4) to segment (0,0)-(6,3): |2*3 - 0.4*6| / sqrt(45) = 3.6/6.708 = 0.537 <= 1: dropped
    # (8, 0.2) to segment (6,3)-(10,0): |(8-6)*(-3) - (0.2-3)*4| / 5 = |-6 + 11.2| / 5 = 1.04 > 1: kept
    assert kept.tolist() == [True, False, True, True, True]


def test_closed_stroke_and_end_points():
    square = [(0, 0), (4, 0), (4, 4), (0, 4), (0, 0)]
    out = simplify(DisplayList.from_polylines([square]), 0.5)
    assert out.stroke(0).tolist() == [list(p) for p in square]


def test_several_strokes_and_dots():
    dl = DisplayList.from_polylines([[(0, 0), (1, 0.001), (2, 0)], [(7, 7)], [(0, 0), (3, 3)]], pens=[1, 2, 3])
    out = simplify(dl, 0.01)
    assert [s.tolist() for s in out.strokes()] == [[[0, 0], [2, 0]], [[7, 7]], [[0, 0], [3, 3]]]
    assert out.pens.tolist() == [1, 2, 3]


def test_empty_and_bad_tolerance():
    assert len(simplify(DisplayList(), 1.0)) == 0
    for bad in (-0.1, float("inf"), None):
        with pytest.raises(ConfigError):
            simplify(DisplayList(), bad)


@settings(max_examples=80, deadline=None)
@given(
    st.lists(st.lists(st.tuples(st.integers(-30, 30), st.integers(-30, 30)), min_size=1, max_size=30),
             min_size=1, max_size=6),
    st.sampled_from([0.0, 0.5, 1.0, 2.5, 10.0]),
)
def test_matches_the_scalar_reference(polys, tol):
    dl = DisplayList.from_polylines([np.array(p, float) for p in polys])
    kept = simplify_mask(dl.points, dl.offsets, tol)
    expected = np.zeros(len(dl.points), bool)
    for i, p in enumerate(polys):
        expected[dl.offsets[i] + np.array(reference([tuple(map(float, q)) for q in p], tol))] = True
    assert kept.tolist() == expected.tolist()

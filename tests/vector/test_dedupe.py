"""Tests of duplicate removal (nothing drawn twice, nothing lost) and of the minimum-length filter."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.vector.dedupe import filter_min_length, remove_duplicates, stroke_lengths
from pixelpen.vector.displaylist import DisplayList


def lists(dl: DisplayList) -> list:
    return [s.tolist() for s in dl.strokes()]


def unit_steps(dl: DisplayList) -> list[tuple]:
    """Every segment on the integer grid cut into unit steps (axis or diagonal), each written low end first."""
    steps = []
    for x0, y0, x1, y1 in dl.segments().tolist():
        n = int(max(abs(x1 - x0), abs(y1 - y0)))
        if n == 0:
            continue
        sx, sy = (x1 - x0) / n, (y1 - y0) / n
        for k in range(n):
            a = (x0 + k * sx, y0 + k * sy)
            b = (x0 + (k + 1) * sx, y0 + (k + 1) * sy)
            steps.append(min(a, b) + max(a, b))
    return sorted(steps)


def test_exact_and_reversed_duplicates_go():
    dl = DisplayList.from_polylines([[(0, 0), (3, 4)], [(0, 0), (3, 4)], [(3, 4), (0, 0)], [(9, 9), (8, 8)]])
    assert lists(remove_duplicates(dl)) == [[[0, 0], [3, 4]], [[9, 9], [8, 8]]]


def test_collinear_overlap_is_trimmed_from_the_later_stroke():
    dl = DisplayList.from_polylines([[(0, 0), (2, 0)], [(1, 0), (3, 0)]])
    assert lists(remove_duplicates(dl)) == [[[0, 0], [2, 0]], [[2, 0], [3, 0]]]


def test_later_stroke_around_an_earlier_one_splits():
    dl = DisplayList.from_polylines([[(1, 1), (2, 2)], [(0, 0), (3, 3)]], pens=[1, 2])
    out = remove_duplicates(dl)
    assert lists(out) == [[[1, 1], [2, 2]], [[0, 0], [1, 1]], [[2, 2], [3, 3]]]
    assert out.pens.tolist() == [1, 2, 2]


def test_a_stroke_retracing_itself():
    dl = DisplayList.from_polylines([[(0, 0), (4, 0), (4, 3), (4, 0), (8, 0)]])
    assert lists(remove_duplicates(dl)) == [[[0, 0], [4, 0], [4, 3]], [[4, 0], [8, 0]]]


def test_parallel_touching_and_crossing_segments_are_left_alone():
    dl = DisplayList.from_polylines([[(0, 0), (5, 0)], [(0, 1), (5, 1)], [(5, 0), (9, 0)], [(2, -1), (2, 3)]])
    assert lists(remove_duplicates(dl)) == lists(dl)


def test_near_horizontal_duplicates_across_the_angle_wrap():
    dl = DisplayList.from_polylines([[(0, 0), (10, 1e-12)], [(10, 0), (0, 1e-12)]])
    assert len(remove_duplicates(dl, tolerance=1e-6)) == 1


def test_repeated_points_and_dots():
    dl = DisplayList.from_polylines([[(0, 0), (0, 0), (1, 0), (1, 0)], [(5, 5)], [(5, 5)], [(2, 2), (2, 2)], [(6, 6)]])
    assert lists(remove_duplicates(dl)) == [[[0, 0], [1, 0]], [[5, 5]], [[2, 2]], [[6, 6]]]


def test_tolerance_merges_near_lines_only():
    dl = DisplayList.from_polylines([[(0, 0), (10, 0)], [(0, 0.05), (10, 0.05)]])
    assert len(remove_duplicates(dl, tolerance=0.01)) == 2
    assert len(remove_duplicates(dl, tolerance=0.1)) == 1
    # lines 0.1 apart stay; in a ladder of lines 0.05 apart some merge, but none with a line over 0.06 away
    spaced = DisplayList.from_polylines([[(0, 0.1 * i), (10, 0.1 * i)] for i in range(10)])
    assert len(remove_duplicates(spaced, 0.06)) == 10
    ladder = DisplayList.from_polylines([[(0, 0.05 * i), (10, 0.05 * i)] for i in range(10)])
    out = remove_duplicates(ladder, tolerance=0.06)
    kept_y = out.points[:, 1]
    assert 5 <= len(out) < 10
    assert all(np.min(np.abs(kept_y - 0.05 * i)) <= 0.06 for i in range(10))


def test_empty_and_bad_tolerance():
    assert len(remove_duplicates(DisplayList())) == 0
    for bad in (-1, float("nan"), "x"):
        with pytest.raises(ConfigError):
            remove_duplicates(DisplayList(), bad)


DIRECTIONS = [(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1)]


@st.composite
def grid_polylines(draw):
    """Polylines on the integer grid whose steps run along the axes or diagonals, so overlaps are exact."""
    polys = []
    for _ in range(draw(st.integers(1, 8))):
        x, y = draw(st.integers(0, 6)), draw(st.integers(0, 6))
        pts = [(x, y)]
        for d, k in draw(st.lists(st.tuples(st.integers(0, 7), st.integers(0, 3)), min_size=0, max_size=4)):
            x, y = x + DIRECTIONS[d][0] * k, y + DIRECTIONS[d][1] * k
            pts.append((x, y))
        polys.append(pts)
    return polys


@settings(max_examples=100, deadline=None)
@given(grid_polylines())
def test_ink_is_kept_and_drawn_once(polys):
    dl = DisplayList.from_polylines([np.array(p, float) for p in polys])
    out = remove_duplicates(dl)
    before, after = unit_steps(dl), unit_steps(out)
    assert after == sorted(set(before))  # the same unit steps, each exactly once
    assert len(out.points) <= len(dl.points) + 2 * len(dl.points)


def test_min_length():
    dl = DisplayList.from_polylines([[(0, 0), (3, 4)], [(0, 0), (0.5, 0)], [(7, 7)], [(0, 0), (1, 0), (1, 1)]])
    assert stroke_lengths(dl).tolist() == [5.0, 0.5, 0.0, 2.0]
    assert [len(s) for s in filter_min_length(dl, 2.0).strokes()] == [2, 3]
    assert len(filter_min_length(dl, 0.0)) == 4
    assert len(filter_min_length(DisplayList(), 1.0)) == 0
    with pytest.raises(ConfigError):
        filter_min_length(dl, -1.0)

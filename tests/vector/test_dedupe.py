"""Tests of duplicate removal (nothing drawn twice, nothing lost) and of the minimum-length filter."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.vector.dedupe import DuplicateRemoval, deduplicate, filter_min_length, remove_duplicates, stroke_lengths
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
    dl = DisplayList.from_polylines([[(1, 1), (2, 2)], [(0, 0), (3, 3)]], pens=2, layers=[4, 4])
    out, account = deduplicate(dl)
    assert lists(out) == [[[1, 1], [2, 2]], [[0, 0], [1, 1]], [[2, 2], [3, 3]]]
    assert out.pens.tolist() == [2, 2, 2] and out.layers.tolist() == [4, 4, 4]
    assert account == [DuplicateRemoval(layer=4, pen=2, strokes_removed=0, strokes_shortened=1,
                                        length=pytest.approx(2 ** 0.5))]


def test_second_pass_in_another_layer_or_pen_is_kept():
    square = [(0, 0), (10, 0), (10, 10), (0, 10), (0, 0)]
    for pens, layers in (([1, 2], [0, 0]), ([1, 1], [0, 1]), ([1, 2], [0, 1])):
        dl = DisplayList.from_polylines([square, square[::-1]], pens=pens, layers=layers)
        out, account = deduplicate(dl)
        assert unit_steps(out) == unit_steps(dl) and len(unit_steps(out)) == 2 * 40
        assert out.pens.tolist() == pens and out.layers.tolist() == layers and account == []
    dl = DisplayList.from_polylines([[(3, 3)], [(3, 3)]], pens=[1, 2])
    assert len(remove_duplicates(dl)) == 2  # a dot in each pen


def test_duplicates_within_a_layer_and_pen_are_counted():
    # layer 1 pen 2: a 5 mm segment drawn three times (two go), a dot twice (one goes), a 10 mm line overlapped
    # by 4 mm of a later one (cut); layer 0 pen 1 has a copy of everything and loses only its own repeats
    polys = [[(0, 0), (3, 4)], [(3, 4), (0, 0)], [(0, 0), (3, 4)], [(7, 7)], [(7, 7)],
             [(0, 20), (10, 20)], [(6, 20), (14, 20)]]
    dl = DisplayList.from_polylines(polys + polys[:2], pens=[2] * 7 + [1, 1], layers=[1] * 7 + [0, 0])
    out, account = deduplicate(dl)
    assert account == [
        DuplicateRemoval(layer=1, pen=2, strokes_removed=3, strokes_shortened=1, length=pytest.approx(14.0)),
        DuplicateRemoval(layer=0, pen=1, strokes_removed=1, strokes_shortened=0, length=pytest.approx(5.0)),
    ]
    assert lists(out) == [[[0, 0], [3, 4]], [[7, 7]], [[0, 20], [10, 20]], [[10, 20], [14, 20]], [[0, 0], [3, 4]]]
    assert dl.pen_down_length() - out.pen_down_length() == pytest.approx(sum(r.length for r in account))


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


@settings(max_examples=100, deadline=None)
@given(grid_polylines(), st.data())
def test_each_layer_and_pen_is_deduplicated_on_its_own(polys, data):
    pens = data.draw(st.lists(st.sampled_from([1, 2]), min_size=len(polys), max_size=len(polys)))
    layers = data.draw(st.lists(st.sampled_from([0, 5]), min_size=len(polys), max_size=len(polys)))
    dl = DisplayList.from_polylines([np.array(p, float) for p in polys], pens=pens, layers=layers)
    out, account = deduplicate(dl)
    reported = {(r.layer, r.pen): r for r in account}
    for key in set(zip(layers, pens, strict=False)):
        mine = (dl.layers == key[0]) & (dl.pens == key[1])
        got = out.select((out.layers == key[0]) & (out.pens == key[1]))
        assert unit_steps(got) == sorted(set(unit_steps(dl.select(mine))))  # each group's ink, once
        lost = dl.select(mine).pen_down_length() - got.pen_down_length()
        assert lost == pytest.approx(reported[key].length if key in reported else 0.0, abs=1e-9)
        alone, alone_account = deduplicate(dl.select(mine))
        assert lists(got) == lists(alone) and alone_account == ([reported[key]] if key in reported else [])


def test_min_length():
    dl = DisplayList.from_polylines([[(0, 0), (3, 4)], [(0, 0), (0.5, 0)], [(7, 7)], [(0, 0), (1, 0), (1, 1)]])
    assert stroke_lengths(dl).tolist() == [5.0, 0.5, 0.0, 2.0]
    assert [len(s) for s in filter_min_length(dl, 2.0).strokes()] == [2, 3]
    assert len(filter_min_length(dl, 0.0)) == 4
    assert len(filter_min_length(DisplayList(), 1.0)) == 0
    with pytest.raises(ConfigError):
        filter_min_length(dl, -1.0)

"""Tests of pen-up path ordering: geometry kept, travel never added, greedy from home, direction, layers and pens."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.profiles import load_profile
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.motion import estimate_time
from pixelpen.vector.order import order_paths, stroke_groups
from tests.vector.test_optimize import canonical_segments, display_lists, dots, grouped


def strokes_as_tuples(dl: DisplayList) -> list[tuple]:
    return sorted(tuple(map(tuple, s.tolist())) for s in dl.strokes())


def test_empty_and_single():
    assert len(order_paths(DisplayList())) == 0
    one = DisplayList.from_polylines([[(10, 0), (1, 0)]])
    assert order_paths(one).stroke(0).tolist() == [[1, 0], [10, 0]]  # the end is nearer home: reversed
    assert order_paths(one, reverse=False).stroke(0).tolist() == [[10, 0], [1, 0]]


def test_greedy_from_home_takes_the_nearest_first():
    dl = DisplayList.from_polylines([[(30, 0), (31, 0)], [(5, 5), (6, 6)], [(50, 50), (3, 0)], [(100, 0), (101, 0)]])
    first = order_paths(dl, time_budget=0).stroke(0)
    assert first.tolist() == [[3, 0], [50, 50]]  # nearest end to (0, 0), entered there
    first = order_paths(dl, time_budget=0, reverse=False).stroke(0)
    assert first.tolist() == [[5, 5], [6, 6]]  # nearest start
    assert order_paths(dl, time_budget=0, home=(100, 1)).stroke(0).tolist() == [[100, 0], [101, 0]]


def test_greedy_follows_nearest_neighbour_chain():
    # strokes along a line, given shuffled; nearest neighbour from home walks them left to right
    xs = [0, 3, 6, 9, 12, 15]
    polys = [[(x + 1, 0), (x + 2, 0)] for x in xs]
    shuffled = [polys[i] for i in (4, 0, 5, 2, 1, 3)]
    out = order_paths(DisplayList.from_polylines(shuffled), time_budget=0)
    assert [s[0][0] for s in out.strokes()] == [x + 1 for x in xs]
    assert out.pen_up_length() == pytest.approx(1 + 5 * 2)


def test_local_search_finds_the_optimum_of_a_row():
    rng = np.random.default_rng(5)
    polys = [np.array([(2.0 * i, 0.0), (2.0 * i + 1, 0.0)]) for i in range(40)]
    order = rng.permutation(40)
    shuffled = [polys[i][:: 1 if rng.random() < 0.5 else -1] for i in order]
    out = order_paths(DisplayList.from_polylines(shuffled), time_budget=2.0)
    assert out.pen_up_length() == pytest.approx(39.0)  # every hop 1 unit, home at the row's start


def test_improvement_beats_plain_greedy_on_a_grid_of_strokes():
    rng = np.random.default_rng(8)
    starts = rng.uniform(0, 100, (400, 2))
    dl = DisplayList.from_polylines([np.array([s, s + rng.uniform(-3, 3, 2)]) for s in starts])
    greedy = order_paths(dl, time_budget=0)
    better = order_paths(dl, time_budget=1.0)
    assert better.pen_up_length() < 0.95 * greedy.pen_up_length()
    assert canonical_segments(better) == canonical_segments(dl)


@settings(max_examples=50, deadline=None)
@given(display_lists(max_strokes=14, pens=(1, 2, 3), layers=(0, 1)),
       st.tuples(st.integers(-5, 25), st.integers(-5, 25)), st.booleans(), st.sampled_from([0.0, 0.05, None]))
def test_geometry_kept_and_travel_never_increases(dl, home, reverse, budget):
    out = order_paths(dl, home=home, reverse=reverse, time_budget=budget)
    assert canonical_segments(out) == canonical_segments(dl) and dots(out) == dots(dl)
    assert out.pen_up_length(home) <= grouped(dl).pen_up_length(home) + 1e-9
    assert np.count_nonzero(np.diff(out.layers)) <= max(0, len(set(dl.layers.tolist())) - 1)  # a run per layer
    assert sorted(out.pens.tolist()) == sorted(dl.pens.tolist())


@settings(max_examples=40, deadline=None)
@given(display_lists(max_strokes=14), st.sampled_from([0.0, 0.05]))
def test_no_reverse_never_reverses(dl, budget):
    out = order_paths(dl, reverse=False, time_budget=budget)
    assert strokes_as_tuples(out) == strokes_as_tuples(dl)


def greedy_reference(dl: DisplayList) -> float:
    """Pen-up length of vpype's ``linesort`` rule, step by step: from (0, 0) to the nearest free end, flipping."""
    starts, ends = dl.starts.copy(), dl.ends.copy()
    free = np.ones(len(dl), bool)
    at, total = np.zeros(2), 0.0
    for _ in range(len(dl)):
        d_start = np.where(free, np.hypot(*(starts - at).T), np.inf)
        d_end = np.where(free, np.hypot(*(ends - at).T), np.inf)
        i, j = int(np.argmin(d_start)), int(np.argmin(d_end))
        if d_start[i] <= d_end[j]:
            total, at, free[i] = total + d_start[i], ends[i], False
        else:
            total, at, free[j] = total + d_end[j], starts[j], False
    return total


def test_default_budget_beats_greedy_by_fifteen_percent():
    # 1-5 mm segments as in plotters.md section 4, 2,000 of them in 100 x 70 mm: the adaptive default always
    # reaches a 2-opt / Or-opt local optimum, so the result does not depend on how busy the machine is
    rng = np.random.default_rng(4)
    start = np.column_stack([rng.uniform(0, 100, 2000), rng.uniform(0, 70, 2000)])
    angle = rng.uniform(0, 2 * np.pi, 2000)
    end = start + rng.uniform(1, 5, 2000)[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    dl = DisplayList.from_polylines(list(np.stack([start, end], axis=1)))
    out = order_paths(dl)
    assert out.pen_up_length() <= 0.85 * greedy_reference(dl)
    assert canonical_segments(out) == canonical_segments(dl)


def test_larger_random_input_keeps_every_stroke():
    rng = np.random.default_rng(2)
    polys = [rng.uniform(0, 50, (rng.integers(1, 6), 2)) for _ in range(600)]
    dl = DisplayList.from_polylines(polys)
    for reverse in (True, False):
        out = order_paths(dl, reverse=reverse, time_budget=0.3)
        assert canonical_segments(out) == canonical_segments(dl) and dots(out) == dots(dl)
        assert out.pen_up_length() < 0.2 * dl.pen_up_length()


def test_layer_order_kept_and_pens_grouped():
    polys = [[(i, 0), (i, 1)] for i in range(8)]
    dl = DisplayList.from_polylines(polys, pens=[2, 1, 2, 1, 1, 2, 1, 2], layers=[5, 5, 3, 3, 5, 3, 5, 3])
    out = order_paths(dl, time_budget=0.1)
    assert out.layers.tolist() == [5, 5, 5, 5, 3, 3, 3, 3]  # layer 5 appears first, so it is drawn first
    assert out.pens.tolist() == [2, 1, 1, 1, 2, 2, 2, 1]  # within a layer one run per pen (pens by first use)
    assert stroke_groups(dl)[0].tolist() == [0]


def test_across_layers_groups_by_pen_only():
    polys = [[(i, 0), (i, 1)] for i in range(8)]
    dl = DisplayList.from_polylines(polys, pens=[2, 1, 2, 1, 1, 2, 1, 2], layers=[5, 5, 3, 3, 5, 3, 5, 3])
    out = order_paths(dl, time_budget=0.1, across_layers=True)
    assert out.pens.tolist() == [2, 2, 2, 2, 1, 1, 1, 1]
    assert estimate_time(out, "axidraw_v3").pen_changes == 1


def test_profile_orders_by_time_and_never_adds_time_or_travel():
    rng = np.random.default_rng(4)
    polys = [np.array([s, s + rng.uniform(-20, 20, 2)]) for s in rng.uniform(0, 4000, (200, 2))]
    dl = DisplayList.from_polylines(polys, unit_mm=0.05)
    prof = load_profile("hp7475a")
    out = order_paths(dl, profile=prof, time_budget=0.5)
    assert estimate_time(out, prof).pen_up < estimate_time(dl, prof).pen_up
    assert out.pen_up_length() < dl.pen_up_length()


def test_travel_compared_with_the_input_itself_when_grouped():
    rng = np.random.default_rng(9)
    dl = DisplayList.from_polylines([rng.uniform(0, 9, (2, 2)) for _ in range(30)], pens=[1] * 15 + [2] * 15)
    for budget in (0.0, 0.1):
        assert order_paths(dl, time_budget=budget).pen_up_length() <= dl.pen_up_length() + 1e-9


def test_an_already_good_order_is_kept():
    polys = [[(i, 0), (i + 0.5, 0)] for i in range(10)]
    dl = DisplayList.from_polylines(polys)
    out = order_paths(dl, time_budget=0.2)
    assert out.pen_up_length() == pytest.approx(dl.pen_up_length())


@pytest.mark.parametrize("kwargs", [{"time_budget": -0.1}, {"time_budget": float("inf")}, {"time_budget": "1"},
                                    {"home": (0, 0, 0)}, {"home": (np.nan, 0)}])
def test_bad_arguments(kwargs):
    with pytest.raises(ConfigError):
        order_paths(DisplayList.from_polylines([[(0, 0), (1, 0)]]), **kwargs)

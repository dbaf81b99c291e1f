"""Tests of the optimisation pipeline, with the geometry checks the ordering and merging tests share."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.profiles import load_profile
from pixelpen.vector.dedupe import DuplicateRemoval, remove_duplicates
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.motion import estimate_time
from pixelpen.vector.optimize import OptimizeReport, optimize
from pixelpen.vector.order import auto_budget


def canonical_segments(dl: DisplayList) -> list[tuple[float, float, float, float]]:
    """The pen-down segments as a sorted multiset, each written from its lexicographically smaller end."""
    out = []
    for x0, y0, x1, y1 in dl.segments().tolist():
        out.append((x0, y0, x1, y1) if (x0, y0) <= (x1, y1) else (x1, y1, x0, y0))
    return sorted(out)


def grouped(dl: DisplayList) -> DisplayList:
    """The strokes taken layer by layer (first appearance), pen by pen (first appearance), else in given order."""
    layers = list(dict.fromkeys(dl.layers.tolist()))
    pens = list(dict.fromkeys(dl.pens.tolist()))
    key = [
        (layers.index(l_), pens.index(p), i)
        for i, (l_, p) in enumerate(zip(dl.layers.tolist(), dl.pens.tolist(), strict=False))
    ]
    return dl.reordered([k[2] for k in sorted(key)])


def dots(dl: DisplayList) -> list[tuple[float, float]]:
    """Sorted positions of single-point strokes."""
    return sorted(tuple(s[0]) for s in dl.strokes() if len(s) == 1)


@st.composite
def display_lists(draw, max_strokes=12, max_points=5, pens=(1,), layers=(0,)):
    """Random display lists on an integer grid (so ends often coincide), with pens and layers drawn from the sets."""
    n = draw(st.integers(0, max_strokes))
    polys, p, l_ = [], [], []
    for _ in range(n):
        k = draw(st.integers(1, max_points))
        polys.append(draw(st.lists(st.tuples(st.integers(0, 20), st.integers(0, 20)), min_size=k, max_size=k)))
        p.append(draw(st.sampled_from(pens)))
        l_.append(draw(st.sampled_from(layers)))
    return DisplayList.from_polylines([np.array(q, float) for q in polys], pens=p or 1, layers=l_ or 0)


def test_empty_list():
    assert len(optimize(DisplayList(), merge=1.0, simplify=0.1, min_length=1.0)) == 0


@settings(max_examples=40, deadline=None)
@given(display_lists(pens=(1, 2), layers=(0, 1)), st.booleans(), st.tuples(st.integers(0, 20), st.integers(0, 20)))
def test_ordering_pipeline_keeps_geometry_and_never_adds_travel(dl, reverse, home):
    out = optimize(dl, dedupe=False, reverse=reverse, home=home, time_budget=0.05)
    assert canonical_segments(out) == canonical_segments(dl) and dots(out) == dots(dl)
    assert out.pen_up_length(home) <= grouped(dl).pen_up_length(home) + 1e-9


@settings(max_examples=40, deadline=None)
@given(display_lists(max_strokes=10, pens=(1, 2), layers=(0, 1)))
def test_dedupe_works_within_each_layer_and_pen_only(dl):
    doubled = DisplayList.concat([dl, dl])  # every stroke twice, in the same layer and pen
    swapped = dataclasses.replace(dl, pens=3 - dl.pens)  # and once more in the other pen
    both = DisplayList.concat([doubled, swapped])
    report = OptimizeReport()
    out = optimize(both, time_budget=0.02, report=report)
    for layer in (0, 1):
        for pen in (1, 2):
            mine = (both.layers == layer) & (both.pens == pen)
            got = out.select((out.layers == layer) & (out.pens == pen))
            assert canonical_segments(got) == canonical_segments(remove_duplicates(both.select(mine)))
    assert out.pen_down_length() == pytest.approx(both.pen_down_length() - sum(r.length for r in report.duplicates))
    # a copy of one pen's strokes in another pen survives whole: both pens draw the same ink
    one = dataclasses.replace(dl, pens=np.ones(len(dl), np.int32))
    out = optimize(DisplayList.concat([one, one, dataclasses.replace(one, pens=one.pens + 1)]), time_budget=0.02)
    pen1, pen2 = out.select(out.pens == 1), out.select(out.pens == 2)
    assert canonical_segments(pen1) == canonical_segments(pen2) == canonical_segments(remove_duplicates(one))
    assert dots(pen1) == dots(pen2)


def test_report_counts_and_lines():
    dl = DisplayList.from_polylines(
        [[(0, 0), (10, 0)], [(10, 0), (0, 0)], [(0, 5), (10, 5)], [(50, 50), (50.5, 50)], [(0, 5), (10, 5)]],
        pens=[2, 2, 2, 2, 1],
        layers=[1, 1, 1, 1, 1],
        layer_names={1: "red"},
    )
    report = OptimizeReport()
    out = optimize(dl, min_length=1.0, time_budget=0.01, report=report)
    assert report.duplicates == [DuplicateRemoval(1, 2, 1, 0, pytest.approx(10.0))]
    assert (report.strokes_in, report.short_strokes_dropped, report.strokes_out) == (5, 1, 3) == (5, 1, len(out))
    assert report.short_length_dropped == pytest.approx(0.5)
    assert report.pen_up_after == pytest.approx(out.pen_up_length()) and report.order_budget_s == 0.01
    lines = report.lines()
    assert lines[0] == "removed 1 duplicate stroke (10.0 mm) in layer 1 'red', pen 2"
    assert "dropped 1 strokes shorter than the minimum length (0.5 mm of ink)" in lines
    cut = OptimizeReport(unit_mm=0.5, duplicates=[DuplicateRemoval(0, 1, 3, 2, 25.0)])
    assert cut.lines()[0] == (
        "removed 3 duplicate strokes and the retraced part of 2 strokes (12.5 mm) in layer 0, pen 1"
    )
    assert "duplicate removal off" in OptimizeReport(dedupe=False).lines()[0]


def test_adaptive_budget_scales_with_the_input():
    assert auto_budget(0) > 0
    assert auto_budget(1_000) < auto_budget(10_000) < auto_budget(100_000) <= 60.0
    assert auto_budget(100_000) / auto_budget(10_000) > 10  # a little faster than linear beyond 10k strokes
    report = OptimizeReport()
    optimize(DisplayList.from_polylines([[(0, 0), (1, 1)], [(5, 5), (6, 6)]]), report=report)
    assert report.order_budget_s == auto_budget(2)


def test_pipeline_steps_in_order():
    dl = DisplayList.from_polylines(
        [
            [(0, 0), (5, 0.01), (10, 0)],  # simplifies to a straight line
            [(10, 0), (20, 0)],  # touches the first: merged
            [(20, 0), (10, 0)],  # retraces the second: removed by dedupe
            [(50, 50), (50.5, 50)],  # shorter than min_length
        ]
    )
    out = optimize(dl, merge=0.001, simplify=0.1, min_length=1.0, time_budget=0.1)
    # merged first, then simplified as one stroke: the middle point goes too
    assert len(out) == 1
    assert out.stroke(0).tolist() in ([[0, 0], [20, 0]], [[20, 0], [0, 0]])


def test_time_budget_and_profile_reduce_plot_time():
    rng = np.random.default_rng(11)
    starts = rng.uniform(0, 2000, (300, 2))
    polys = [np.array([s, s + rng.uniform(-50, 50, 2)]) for s in starts]
    dl = DisplayList.from_polylines(polys, unit_mm=0.1)
    prof = load_profile("axidraw_v3")
    out = optimize(dl, profile=prof, time_budget=0.5)
    assert estimate_time(out, prof).total < estimate_time(dl, prof).total
    assert out.pen_up_length() < dl.pen_up_length()


def test_no_reverse_pipeline_keeps_directions():
    dl = DisplayList.from_polylines([[(0, 0), (5, 0)], [(10, 0), (5, 0)], [(9, 9), (9, 8)]])
    out = optimize(dl, reverse=False, dedupe=False, merge=0.5, time_budget=0.1)
    # the two strokes ending at (5, 0) could only join with one of them turned round
    assert sorted(map(lambda s: s.tolist(), out.strokes())) == sorted(map(lambda s: s.tolist(), dl.strokes()))
    assert len(optimize(dl, reverse=True, dedupe=False, merge=0.5, time_budget=0.1)) == 2


@pytest.mark.parametrize("bad", [{"merge": -1.0}, {"simplify": float("nan")}, {"min_length": -2}, {"time_budget": -1}])
def test_bad_options(bad):
    from pixelpen.errors import ConfigError

    with pytest.raises(ConfigError):
        optimize(DisplayList.from_polylines([[(0, 0), (1, 1)], [(2, 2), (3, 3)]]), **bad)


def test_every_step_keeps_the_page_and_names():
    dl = DisplayList.from_polylines(
        [[(0, 0), (1, 0)], [(1, 0), (0, 0)], [(1, 0), (5, 0.001), (9, 0)], [(5, 5)]],
        layer_names={0: "ink"},
        pen_colours={1: "#123456"},
        page=(297.0, 210.0),
    )
    out = optimize(dl, merge=0.1, simplify=0.01, min_length=0.0, time_budget=0.01)
    assert out.page == (297.0, 210.0) and out.layer_names == {0: "ink"} and out.pen_colours == {1: "#123456"}

"""Tests of stroke merging: joins within tolerance, shortest gap first, reversal only when allowed, pens kept apart."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.merge import link_ends, merge_paths, walk_chains
from tests.vector.test_optimize import canonical_segments, display_lists, dots


def lists(dl: DisplayList) -> list[list[list[float]]]:
    return [s.tolist() for s in dl.strokes()]


def test_end_to_start_joins_with_one_junction_point():
    dl = DisplayList.from_polylines([[(0, 0), (1, 0)], [(1, 0), (1, 1)]])
    assert lists(merge_paths(dl, 0.0)) == [[[0, 0], [1, 0], [1, 1]]]


def test_end_to_end_needs_reversal():
    dl = DisplayList.from_polylines([[(0, 0), (1, 0)], [(1, 1), (1, 0)]])
    assert lists(merge_paths(dl, 0.0)) == [[[0, 0], [1, 0], [1, 1]]]
    assert lists(merge_paths(dl, 0.0, reverse=False)) == lists(dl)


def test_start_to_start_with_reversal_keeps_most_strokes_forward():
    dl = DisplayList.from_polylines([[(1, 0), (2, 0)], [(1, 0), (0, 0)], [(2, 0), (3, 0)]])
    assert lists(merge_paths(dl, 0.0)) == [[[0, 0], [1, 0], [2, 0], [3, 0]]]


def test_gap_within_tolerance_is_drawn_and_beyond_is_not():
    dl = DisplayList.from_polylines([[(0, 0), (1, 0)], [(1.04, 0), (2, 0)]])
    assert lists(merge_paths(dl, 0.05)) == [[[0, 0], [1, 0], [1.04, 0], [2, 0]]]
    assert len(merge_paths(dl, 0.03)) == 2


def test_pens_and_layers_are_not_merged():
    polys = [[(0, 0), (1, 0)], [(1, 0), (2, 0)], [(2, 0), (3, 0)]]
    assert len(merge_paths(DisplayList.from_polylines(polys, pens=[1, 2, 2]), 0.0)) == 2
    assert len(merge_paths(DisplayList.from_polylines(polys, layers=[0, 0, 1]), 0.0)) == 2
    assert len(merge_paths(DisplayList.from_polylines(polys, layers=[0, 0, 1]), 0.0, across_layers=True)) == 1


def test_shortest_gap_wins():
    # stroke A's end is 0.3 from B's start and 0.1 from C's start: A joins C
    dl = DisplayList.from_polylines([[(0, 0), (1, 0)], [(1.3, 0), (2, 5)], [(1, 0.1), (1, 3)]])
    out = merge_paths(dl, 0.5, reverse=False)
    assert [[0, 0], [1, 0], [1, 0.1], [1, 3]] in lists(out) and len(out) == 2


def test_shuffled_pieces_of_a_polyline_become_one():
    rng = np.random.default_rng(1)
    line = np.cumsum(rng.uniform(-1, 1, (61, 2)), axis=0)
    pieces = [line[i : i + 3] for i in range(0, 60, 2)]
    shuffled = [pieces[i][:: 1 if rng.random() < 0.5 else -1] for i in rng.permutation(len(pieces))]
    out = merge_paths(DisplayList.from_polylines(shuffled), 0.0)
    assert len(out) == 1
    got = out.stroke(0)
    assert np.array_equal(got, line) or np.array_equal(got, line[::-1])


def test_a_ring_closes_without_looping():
    ring = [[(0, 0), (1, 0)], [(1, 1), (1, 0)], [(1, 1), (0, 1)], [(0, 0), (0, 1)]]
    out = merge_paths(DisplayList.from_polylines(ring), 0.0)
    assert len(out) == 1 and len(out.stroke(0)) == 5
    assert np.array_equal(out.stroke(0)[0], out.stroke(0)[-1])


def test_three_strokes_meeting_in_a_point():
    dl = DisplayList.from_polylines([[(0, 0), (1, 1)], [(2, 0), (1, 1)], [(1, 3), (1, 1)]])
    out = merge_paths(dl, 0.0)
    assert sorted(len(s) for s in out.strokes()) == [2, 3]


def test_link_ends_prefers_short_gaps_and_respects_direction():
    # end points: 0,1 stroke 0; 2,3 stroke 1; 4,5 stroke 2
    link = link_ends(3, np.array([1, 1, 3]), np.array([2, 4, 5]), np.array([0.5, 0.2, 0.1]), reverse=True)
    assert link.tolist() == [-1, 4, -1, 5, 1, 3]
    link = link_ends(3, np.array([1, 1, 3]), np.array([2, 4, 5]), np.array([0.5, 0.2, 0.1]), reverse=False)
    assert link.tolist() == [-1, 4, -1, -1, 1, -1]  # 3 -> 5 would join two ends
    entries, heads = walk_chains(3, link, reverse=False)
    assert entries.tolist() == [0, 4, 2] and heads.tolist() == [True, False, True]


def test_empty_single_and_bad_tolerance():
    assert len(merge_paths(DisplayList(), 1.0)) == 0
    one = DisplayList.from_polylines([[(0, 0), (1, 1)]])
    assert lists(merge_paths(one, 1.0)) == lists(one)
    for bad in (-1.0, float("nan"), "1"):
        with pytest.raises(ConfigError):
            merge_paths(one, bad)


@settings(max_examples=60, deadline=None)
@given(display_lists(max_strokes=14, pens=(1, 2)), st.booleans())
def test_exact_merging_keeps_every_segment(dl, reverse):
    out = merge_paths(dl, 0.0, reverse=reverse)
    # joining at coinciding points draws exactly the same segments; dots may be absorbed into strokes
    assert canonical_segments(out) == canonical_segments(dl)
    assert set(dots(out)) <= set(dots(dl)) and len(out) <= len(dl)
    assert sorted(set(out.pens.tolist())) == sorted(set(dl.pens.tolist()))
    if not reverse:
        # every input segment still runs the same way
        fwd = lambda d: sorted(map(tuple, d.segments().tolist()))
        assert fwd(out) == fwd(dl)

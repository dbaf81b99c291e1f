"""Tests for pixelpen.geometry.dashes: dash patterns along polylines, against a scalar walking reference."""

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import InvalidArgument, PixelpenError
from pixelpen.geometry.dashes import as_pattern, dash_polylines


def dash_reference(poly, pattern, offset):
    """Plain-Python dasher: walk the segments, switching pen state at each pattern boundary."""
    pat = list(pattern) * (2 if len(pattern) % 2 else 1)
    pos = offset % sum(pat)
    idx = 0
    while pos >= pat[idx]:
        pos -= pat[idx]
        idx = (idx + 1) % len(pat)
    remain, on = pat[idx] - pos, idx % 2 == 0
    pieces, current = [], [tuple(poly[0])] if idx % 2 == 0 else None
    for a, b in itertools.pairwise(poly):
        a, b = np.asarray(a, float), np.asarray(b, float)
        length, done = float(np.hypot(*(b - a))), 0.0
        while length - done > remain:
            done += remain
            p = tuple(a + (b - a) * done / length)
            if on:
                current.append(p)
                pieces.append(current)
            else:
                current = [p]
            idx = (idx + 1) % len(pat)
            on, remain = not on, pat[idx]
        remain -= length - done
        if on:
            current.append(tuple(b))
    if on:
        pieces.append(current)
    return [np.array(p) for p in pieces]


def on_measure(length, pattern, offset):
    """Length of [0, length] where the pattern (shifted by offset) is on, period by period."""
    pat = list(pattern) * (2 if len(pattern) % 2 else 1)
    period, shift = sum(pat), offset % sum(pat)
    bounds = np.concatenate([[0.0], np.cumsum(pat)])
    total, j = 0.0, 0
    while j * period - shift <= length:
        for k in range(0, len(pat), 2):
            lo, hi = j * period + bounds[k] - shift, j * period + bounds[k + 1] - shift
            total += max(0.0, min(hi, length) - max(lo, 0.0))
        j += 1
    return total


def polyline_length(p):
    """Arc length of a polyline."""
    return float(np.hypot(*np.diff(np.asarray(p, float), axis=0).T).sum())


def test_pattern_continues_across_a_corner_worked_example():
    # pattern 3 on, 2 off, starting 1 into the first dash: on over arc length [0,2], [4,7], [9,12], [14,17], [19,20]
    pieces = dash_polylines([[(0, 0), (10, 0), (10, 10)]], (3, 2), offset=1)
    expected = [[(0, 0), (2, 0)], [(4, 0), (7, 0)], [(9, 0), (10, 0), (10, 2)], [(10, 4), (10, 7)], [(10, 9), (10, 10)]]
    assert len(pieces) == len(expected)
    for got, want in zip(pieces, expected, strict=False):
        np.testing.assert_allclose(got, want, atol=1e-12)


def test_duty_cycle_on_a_straight_line():
    for offset in (0.0, 1.0, 2.5, -7.0):
        pieces = dash_polylines([[(0, 0), (100, 0)]], (3, 2), offset=offset)
        assert sum(polyline_length(p) for p in pieces) == pytest.approx(60.0)


def test_pattern_restarts_for_every_polyline():
    line = [(0, 0), (7, 0), (7, 4)]
    pieces = dash_polylines([line, line], (2, 1.5))
    half = len(pieces) // 2
    assert len(pieces) == 2 * half
    for a, b in zip(pieces[:half], pieces[half:], strict=False):
        np.testing.assert_array_equal(a, b)


def test_odd_patterns_repeat_and_zero_on_lengths_make_dots():
    np.testing.assert_array_equal(as_pattern([3]), [3, 3])
    np.testing.assert_array_equal(as_pattern([1, 2, 3]), [1, 2, 3, 1, 2, 3])
    dots = dash_polylines([[(0, 0), (10, 0)]], (0, 2.5))
    np.testing.assert_allclose([d[0] for d in dots], [(0, 0), (2.5, 0), (5, 0), (7.5, 0), (10, 0)])
    assert all(len(d) == 2 and (d[0] == d[1]).all() for d in dots)


def test_degenerate_polylines():
    assert [p.tolist() for p in dash_polylines([[(1, 1)]], (2, 1))] == [[[1, 1], [1, 1]]]  # pen down at the start
    assert dash_polylines([[(1, 1)]], (2, 1), offset=2.5) == []  # starts in a gap
    assert dash_polylines([], (2, 1)) == []
    pieces = dash_polylines([[(0, 0), (0, 0), (4, 0)]], (1, 1))  # a repeated vertex
    assert sum(polyline_length(p) for p in pieces) == pytest.approx(2.0)


polylines_strategy = st.lists(
    st.lists(st.tuples(st.floats(-30, 30), st.floats(-30, 30)), min_size=2, max_size=10), min_size=1, max_size=5)
patterns = st.lists(st.floats(1.0, 12), min_size=1, max_size=6)


@settings(max_examples=50, deadline=None)
@given(lines=polylines_strategy, pattern=patterns, offset=st.floats(-40, 40))
def test_dashes_match_the_scalar_reference(lines, pattern, offset):
    pieces = dash_polylines(lines, pattern, offset)
    expected = [p for line in lines for p in dash_reference(np.array(line, float), pattern, offset)]
    # the duty cycle: total pen-down length is the pattern's on-measure over each polyline's length
    total = sum(polyline_length(p) for p in pieces)
    assert total == pytest.approx(sum(on_measure(polyline_length(line), pattern, offset) for line in lines), abs=1e-7)
    # piece by piece, ignoring slivers a rounding tie can add or split
    keep = [p for p in pieces if polyline_length(p) > 1e-7]
    want = [p for p in expected if polyline_length(p) > 1e-7]
    assert len(keep) == len(want)
    for got, ref in zip(keep, want, strict=False):
        np.testing.assert_allclose(got[[0, -1]], ref[[0, -1]], atol=1e-7)
        assert polyline_length(got) == pytest.approx(polyline_length(ref), abs=1e-7)


@pytest.mark.parametrize(
    "pattern, message",
    [([], "non-empty"), ([1, -1], ">= 0"), ([0, 0], "positive total"), ([1, np.nan], "finite"),
     ([[1, 2]], "1-D"), ("ab", "sequence of lengths")],
)
def test_bad_patterns_are_rejected(pattern, message):
    with pytest.raises(ValueError, match=message):
        dash_polylines([[(0, 0), (1, 0)]], pattern)


def test_bad_polylines_and_offsets_are_rejected():
    with pytest.raises(ValueError, match=r"polylines\[0\].*row 1"):
        dash_polylines([[(0, 0), (np.nan, 0)]], (1, 1))
    with pytest.raises(ValueError, match=r"polylines\[1\].*shape"):
        dash_polylines([[(0, 0), (1, 0)], [(0, 0, 0)]], (1, 1))
    with pytest.raises(ValueError, match="offset"):
        dash_polylines([[(0, 0), (1, 0)]], (1, 1), offset=math.inf)
    with pytest.raises(ValueError, match="too fine"):
        dash_polylines([[(0, 0), (1e6, 0)]], (1e-6, 1e-6))


def test_a_vanishingly_fine_pattern_is_refused_before_counting_overflows():
    # 100 / 2e-300 dashes: floor() gives 5e301, which int64 turned into garbage before the limit check
    with pytest.raises(InvalidArgument, match="too fine") as info:
        dash_polylines([np.array([[0.0, 0.0], [100.0, 0.0]])], [1e-300, 1e-300])
    assert isinstance(info.value, PixelpenError) and isinstance(info.value, ValueError)

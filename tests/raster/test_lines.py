"""Lines: textbook Bresenham/DDA references, and the vectorised batch against them (all octants, clipping)."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image, ImageDraw

from pixelpen.errors import ConfigError
from pixelpen.raster.canvas import Canvas
from pixelpen.raster.lines import COORD_LIMIT, LineRuns, bresenham, dda


def ideal_pixels(x0: int, y0: int, x1: int, y1: int) -> list[tuple[int, int]]:
    """The documented rule, independently: minor offset = round-half-up of the ideal line from the start."""
    dx, dy = x1 - x0, y1 - y0
    major = max(abs(dx), abs(dy))
    if major == 0:
        return [(x0, y0)]
    out = []
    for k in range(major + 1):
        fx = x0 + Fraction(dx * k, major)
        fy = y0 + Fraction(dy * k, major)
        # measured from the start: step away from the start on ties
        def rnd(start: int, f: Fraction, sign: int) -> int:
            off = abs(f - start) + Fraction(1, 2)
            return start + sign * (off.numerator // off.denominator)
        out.append((rnd(x0, fx, 1 if dx >= 0 else -1), rnd(y0, fy, 1 if dy >= 0 else -1)))
    return out


def clipped_reference(segments: np.ndarray, width: int, height: int) -> np.ndarray:
    """Canvas mask of the scalar Bresenham pixels of all segments that fall on the canvas."""
    mask = np.zeros((height, width), dtype=bool)
    for s in segments.tolist():
        p = bresenham(*s)
        ok = (p[:, 0] >= 0) & (p[:, 0] < width) & (p[:, 1] >= 0) & (p[:, 1] < height)
        mask[p[ok, 1], p[ok, 0]] = True
    return mask


def test_hearn_baker_worked_example():
    # Hearn & Baker, Bresenham example (20,10)-(30,18): dx=10, dy=8, p0 = 2dy - dx = 6
    pts = bresenham(20, 10, 30, 18)
    assert pts[0].tolist() == [20, 10]
    assert pts[1:, 0].tolist() == list(range(21, 31))
    assert pts[1:, 1].tolist() == [11, 12, 12, 13, 14, 15, 16, 16, 17, 18]


@pytest.mark.parametrize("seg", [(0, 0, 7, 3), (0, 0, 3, 7), (0, 0, -7, 3), (0, 0, -3, 7), (0, 0, 7, -3),
                                 (0, 0, 3, -7), (0, 0, -7, -3), (0, 0, -3, -7), (5, 5, 5, 5), (0, 0, 6, 3),
                                 (0, 0, 6, -3), (0, 0, -6, 3), (2, 1, 2, 9), (9, 4, -3, 4), (0, 0, 5, 5)])
def test_bresenham_is_round_half_up_from_start(seg):
    assert [tuple(p) for p in bresenham(*seg).tolist()] == ideal_pixels(*seg)


def test_tie_rule_depends_on_start():
    # (0,0)-(2,1): the ideal line passes y = 0.5 at x = 1; ties step away from the start point
    assert bresenham(0, 0, 2, 1).tolist() == [[0, 0], [1, 1], [2, 1]]
    assert bresenham(2, 1, 0, 0).tolist() == [[2, 1], [1, 0], [0, 0]]


@settings(max_examples=60, deadline=None)
@given(st.integers(-40, 40), st.integers(-40, 40), st.integers(-40, 40), st.integers(-40, 40))
def test_bresenham_properties_and_rule(x0, y0, x1, y1):
    pts = bresenham(x0, y0, x1, y1)
    assert pts[0].tolist() == [x0, y0] and pts[-1].tolist() == [x1, y1]
    assert len(pts) == max(abs(x1 - x0), abs(y1 - y0)) + 1
    assert (np.abs(np.diff(pts, axis=0)) <= 1).all()
    assert [tuple(p) for p in pts.tolist()] == ideal_pixels(x0, y0, x1, y1)


def test_dda_follows_ideal_line():
    rng = np.random.default_rng(3)
    for x0, y0, x1, y1 in rng.integers(-30, 30, size=(200, 4)).tolist():
        pts = dda(x0, y0, x1, y1)
        steps = max(abs(x1 - x0), abs(y1 - y0))
        assert len(pts) == steps + 1 and pts[-1].tolist() == [x1, y1]
        if steps:
            k = np.arange(steps + 1)
            assert (np.abs(pts[:, 0] - (x0 + (x1 - x0) * k / steps)) <= 0.5 + 1e-9).all()
            assert (np.abs(pts[:, 1] - (y0 + (y1 - y0) * k / steps)) <= 0.5 + 1e-9).all()


def test_scalar_references_reject_non_integers():
    with pytest.raises(ConfigError, match="x1"):
        bresenham(0, 0, 1.5, 2)
    with pytest.raises(ConfigError, match="y0"):
        dda(0, "a", 1, 2)


def test_pillow_line_is_textbook_bresenham():
    rng = np.random.default_rng(11)
    segs = rng.integers(0, 64, size=(400, 4))
    for s in segs.tolist():
        im = Image.new("1", (64, 64))
        ImageDraw.Draw(im).line(s, fill=1)
        got = np.asarray(im)
        want = np.zeros((64, 64), dtype=bool)
        p = bresenham(*s)
        want[p[:, 1], p[:, 0]] = True
        assert (got == want).all(), s


@pytest.mark.parametrize("lo,hi,w,h", [(0, 40, 40, 30), (-200, 260, 50, 37), (0, 12, 12, 12), (-5000, 5000, 64, 48)])
def test_batch_equals_scalar_all_octants_and_clipping(lo, hi, w, h):
    rng = np.random.default_rng(hi)
    segs = rng.integers(lo, hi, size=(300 if hi - lo < 1000 else 40, 4))
    segs[:10, 2:] = segs[:10, :2]  # zero-length lines
    c = Canvas(w, h, "1")
    c.lines(segs, 1)
    assert (c.array.astype(bool) == clipped_reference(segs, w, h)).all()


def test_batch_pixels_in_plotting_order():
    rng = np.random.default_rng(5)
    segs = rng.integers(0, 30, size=(50, 4))
    runs = LineRuns.clip(segs, 30, 30)
    x, y, step, run = runs.pixels()
    for i, s in enumerate(segs.tolist()):
        sel = run == i
        assert np.column_stack([x[sel], y[sel]]).tolist() == bresenham(*s).tolist()
        assert step[sel].tolist() == list(range(len(bresenham(*s))))


def test_fast_path_equals_exact_integer_path():
    rng = np.random.default_rng(8)
    for w, h, n in ((97, 61, 4000), (3000, 2900, 1500)):  # float32 and float64 (canvas > 2**23 px) paths
        segs = rng.integers(-w // 3, w + w // 3, size=(n, 4))
        runs = LineRuns.clip(segs, w, h)
        exact = np.zeros(h * w, dtype=np.uint8)
        exact[runs.flat_indices()] = 1
        fast = np.zeros((h, w), dtype=np.uint8)
        runs.draw(fast, 1)
        assert runs.pixel_count > w * h // 8
        assert (fast.reshape(-1) == exact).all()


def test_huge_coordinates_clip_exactly():
    big = COORD_LIMIT
    segs = np.array([[-big, -7, big, 40], [3, -big, 20, big], [-big, big, big, -big + 13], [big, 5, -big, 6]])
    c = Canvas(64, 48, "1")
    c.lines(segs, 1)
    want = np.zeros((48, 64), dtype=bool)
    for x0, y0, x1, y1 in segs.tolist():
        dx, dy = x1 - x0, y1 - y0
        major, steep = max(abs(dx), abs(dy)), abs(dy) > abs(dx)
        for m in range(48 if steep else 64):  # every major coordinate on the canvas
            k = abs(m - (y0 if steep else x0))
            off = (2 * k * min(abs(dx), abs(dy)) + major) // (2 * major)
            other = (x0 + off * (1 if dx >= 0 else -1)) if steep else (y0 + off * (1 if dy >= 0 else -1))
            x, y = (other, m) if steep else (m, other)
            if 0 <= x < 64 and 0 <= y < 48:
                want[y, x] = True
    assert (c.array.astype(bool) == want).all()
    assert want.any()


def test_lines_wholly_outside_draw_nothing_and_record_no_damage():
    c = Canvas(20, 20)
    c.lines([[-50, -50, -10, 100], [30, 0, 40, 19]], 255)
    assert not c.array.any() and c.damage() == []


def test_dash_pattern_along_major_axis():
    c = Canvas(40, 30, "1")
    segs = np.array([[1, 2, 37, 20], [30, 28, 5, 1]])
    c.lines(segs, 1, dash=(3, 2))
    want = np.zeros((30, 40), dtype=bool)
    for s in segs.tolist():
        p = bresenham(*s)
        lit = np.arange(len(p)) % 5 < 3
        want[p[lit, 1], p[lit, 0]] = True
    assert (c.array.astype(bool) == want).all()


def test_polyline_dash_continues_across_vertices():
    c = Canvas(30, 30, "1")
    c.polyline([(1, 1), (10, 1), (10, 12)], 1, dash=(2, 2))
    want = np.zeros((30, 30), dtype=bool)
    first, second = bresenham(1, 1, 10, 1), bresenham(10, 1, 10, 12)
    for p, offset in ((first, 0), (second, 9)):
        lit = (np.arange(len(p)) + offset) % 4 < 2
        want[p[lit, 1], p[lit, 0]] = True
    assert (c.array.astype(bool) == want).all()


def test_closed_polyline_is_union_of_its_segments():
    pts = [(2, 3), (20, 5), (11, 19)]
    c = Canvas(25, 25, "1")
    c.polyline(pts, 1, closed=True)
    ref = clipped_reference(np.array([[2, 3, 20, 5], [20, 5, 11, 19], [11, 19, 2, 3]]), 25, 25)
    assert (c.array.astype(bool) == ref).all()


def test_thick_lines_square_butt_round():
    c = Canvas(30, 20, "1")
    c.lines([[5, 10, 20, 10]], 1, width=3)
    ys, xs = np.nonzero(c.array)
    assert (ys.min(), ys.max(), xs.min(), xs.max()) == (9, 11, 4, 21)  # square caps add width/2 = 1.5
    assert c.array.sum() == 3 * 18
    c = Canvas(30, 20, "1")
    c.lines([[5, 10, 20, 10]], 1, width=4, cap="butt")
    ys, xs = np.nonzero(c.array)
    assert (ys.min(), ys.max(), xs.min(), xs.max()) == (8, 11, 5, 19)  # half-open: x in [5, 20), y in [8, 12)
    c = Canvas(30, 30, "1")
    c.lines([[8, 15, 20, 15]], 1, width=9, cap="round")
    assert c.array[15, 8 - 4] and c.array[15 + 4, 8] and not c.array[15 + 4, 8 - 4]


def test_thick_dashes_cover_their_major_axis_pixels():
    c = Canvas(40, 10, "1")
    c.lines([[2, 5, 30, 5]], 1, width=3, dash=(4, 3))
    cols = np.flatnonzero(c.array.any(axis=0))
    want = [2 + k for k in range(29) if k % 7 < 4]
    assert cols.tolist() == want
    assert (c.array[:, cols].sum(axis=0) == 3).all()


@pytest.mark.parametrize("segs,match", [
    (np.zeros((3, 3)), "N, 4"), ([[0, 0, 1.5, 2]], "not integral"), ([[0, 0, 2 ** 31, 0]], "beyond"),
    ([["a", 0, 1, 1]], "integers"), ([[0, 0, float("nan"), 1]], "not integral"),
])
def test_bad_segments(segs, match):
    with pytest.raises(ConfigError, match=match):
        Canvas(10, 10).lines(segs, 1)


@pytest.mark.parametrize("kwargs,match", [
    ({"width": 0}, "width"), ({"width": 2.5}, "width"), ({"dash": (3,)}, "dash"), ({"dash": (0, 0)}, "dash"),
    ({"dash": (2, -1)}, "dash"), ({"cap": "arrow"}, "cap"), ({"dash": "ab"}, "dash"),
])
def test_bad_line_options(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        Canvas(10, 10).lines([[0, 0, 5, 5]], 1, **kwargs)

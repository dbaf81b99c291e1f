"""Circles and ellipses: midpoint references (Hearn & Baker examples), closed forms, batches, Pillow oracle."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image, ImageDraw

from pixelpen.errors import ConfigError
from pixelpen.raster.canvas import Canvas
from pixelpen.raster.circles import ellipse_quadrant, midpoint_circle, midpoint_ellipse


def mask_of(points: np.ndarray, width: int, height: int) -> np.ndarray:
    """Bool canvas of the on-canvas points."""
    m = np.zeros((height, width), dtype=bool)
    ok = (points[:, 0] >= 0) & (points[:, 0] < width) & (points[:, 1] >= 0) & (points[:, 1] < height)
    m[points[ok, 1], points[ok, 0]] = True
    return m


def filled_of(points: np.ndarray, width: int, height: int) -> np.ndarray:
    """Bool canvas filled between each row's extreme outline pixels (computed row by row)."""
    m = np.zeros((height, width), dtype=bool)
    for y in np.unique(points[:, 1]):
        if 0 <= y < height:
            xs = points[points[:, 1] == y, 0]
            m[y, max(xs.min(), 0):min(xs.max(), width - 1) + 1] = True
    return m


def test_hearn_baker_circle_example():
    # Example: r = 10, first octant (1,10) (2,10) (3,10) (4,9) (5,9) (6,8) (7,7)
    pts = {tuple(p) for p in midpoint_circle(0, 0, 10).tolist()}
    octant = sorted(p for p in pts if 0 < p[0] <= p[1])
    assert octant == [(1, 10), (2, 10), (3, 10), (4, 9), (5, 9), (6, 8), (7, 7)]
    assert len(pts) == 8 * len(octant) - 4 + 4  # 8 images, axis and diagonal points shared


def test_hearn_baker_ellipse_example():
    # Example: rx = 8, ry = 6: region 1 (1,6) (2,6) (3,6) (4,5) (5,5) (6,4) (7,3); region 2 (8,2) (8,1) (8,0)
    pts = [tuple(p) for p in midpoint_ellipse(0, 0, 8, 6).tolist() if p[0] > 0 and p[1] >= 0]
    assert pts == [(1, 6), (2, 6), (3, 6), (4, 5), (5, 5), (6, 4), (7, 3), (8, 2), (8, 1), (8, 0)]


def test_circle_radius_zero_and_symmetry():
    assert midpoint_circle(4, 5, 0).tolist() == [[4, 5]]
    for r in (1, 2, 3, 17):
        pts = {tuple(p) for p in midpoint_circle(0, 0, r).tolist()}
        assert pts == {(y, x) for x, y in pts} == {(-x, y) for x, y in pts}
        d = np.array(sorted(pts), dtype=float)
        assert (np.abs(np.hypot(d[:, 0], d[:, 1]) - r) <= 0.5 + 1e-9).all()


def test_degenerate_ellipses():
    assert sorted(map(tuple, midpoint_ellipse(0, 0, 3, 0).tolist())) == [(x, 0) for x in range(-3, 4)]
    assert sorted(map(tuple, midpoint_ellipse(0, 0, 0, 2).tolist())) == [(0, y) for y in range(-2, 3)]
    assert midpoint_ellipse(1, 1, 0, 0).tolist() == [[1, 1]]


def test_batch_circles_equal_reference():
    size = 2 * 130 + 3
    for r in range(130):
        c = Canvas(size, size, "1")
        c.circles([[size // 2, size // 2]], [r], 1)
        ref = mask_of(midpoint_circle(size // 2, size // 2, int(r)), size, size)
        assert (c.array.astype(bool) == ref).all(), r


def test_batch_circles_many_at_once_with_clipping_and_fill():
    rng = np.random.default_rng(4)
    centres = rng.integers(-20, 100, size=(60, 2))
    radii = rng.integers(0, 40, size=60)
    outline, filled = Canvas(90, 70, "1"), Canvas(90, 70, "1")
    outline.circles(centres, radii, 1)
    filled.circles(centres, radii, 1, fill=True)
    want_o = np.zeros((70, 90), dtype=bool)
    want_f = np.zeros((70, 90), dtype=bool)
    for (x, y), r in zip(centres.tolist(), radii.tolist(), strict=False):
        pts = midpoint_circle(x, y, r)
        want_o |= mask_of(pts, 90, 70)
        want_f |= filled_of(pts, 90, 70)
    assert (outline.array.astype(bool) == want_o).all()
    assert (filled.array.astype(bool) == want_f).all()


def test_pillow_ellipse_on_square_box_is_midpoint_circle():
    rng = np.random.default_rng(9)
    for _ in range(60):
        r = int(rng.integers(1, 30))  # Pillow fills nothing for a one-pixel box (r = 0)
        xc, yc = (int(v) for v in rng.integers(r, 64 - r, size=2))
        box = [xc - r, yc - r, xc + r, yc + r]
        for fill in (False, True):
            im = Image.new("1", (64, 64))
            ImageDraw.Draw(im).ellipse(box, fill=1 if fill else None, outline=None if fill else 1)
            c = Canvas(64, 64, "1")
            c.circles([[xc, yc]], r, 1, fill=fill)
            assert (np.asarray(im) == c.array.astype(bool)).all(), (r, fill)


def test_ellipse_closed_form_equals_midpoint_loop():
    a, b = (v.ravel() for v in np.meshgrid(np.arange(0, 41), np.arange(0, 41)))
    owner, x, y = ellipse_quadrant(a, b)
    for i, (rx, ry) in enumerate(zip(a.tolist(), b.tolist(), strict=False)):
        sel = owner == i
        got = {
            (sx * p, sy * q)
            for p, q in zip(x[sel].tolist(), y[sel].tolist(), strict=False)
            for sx in (1, -1)
            for sy in (1, -1)
        }
        assert got == set(map(tuple, midpoint_ellipse(0, 0, rx, ry).tolist())), (rx, ry)


def test_batch_ellipses_equal_reference():
    rng = np.random.default_rng(21)
    centres = rng.integers(-10, 110, size=(45, 2))
    a, b = rng.integers(0, 50, size=45), rng.integers(0, 50, size=45)
    outline, filled = Canvas(100, 90, "1"), Canvas(100, 90, "1")
    outline.ellipses(centres, a, b, 1)
    filled.ellipses(centres, a, b, 1, fill=True)
    want_o = np.zeros((90, 100), dtype=bool)
    want_f = np.zeros((90, 100), dtype=bool)
    for (xc, yc), rx, ry in zip(centres.tolist(), a.tolist(), b.tolist(), strict=False):
        pts = midpoint_ellipse(xc, yc, rx, ry)
        want_o |= mask_of(pts, 100, 90)
        want_f |= filled_of(pts, 100, 90)
    assert (outline.array.astype(bool) == want_o).all() and (filled.array.astype(bool) == want_f).all()


def test_large_random_ellipses_equal_reference():
    rng = np.random.default_rng(12)
    for rx, ry in rng.integers(0, 2000, size=(12, 2)).tolist():
        c = Canvas(300, 300, "1")
        c.ellipses([[150, 150]], rx, ry, 1)  # mostly clipped: exercises the on-canvas part
        assert (c.array.astype(bool) == mask_of(midpoint_ellipse(150, 150, rx, ry), 300, 300)).all(), (rx, ry)


def test_damage_covers_circles():
    c = Canvas(50, 50)
    c.circles([[10, 10]], 5, 255)
    (r,) = c.damage(merge_cost=0)
    assert r == (5, 5, 16, 16)


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda c: c.circles([[1, 1]], -1, 1), ">= 0"),
        (lambda c: c.circles([[1, 1]], 1 << 20, 1), "beyond"),
        (lambda c: c.circles([[1, 1], [2, 2]], [1, 2, 3], 1), "one per centre"),
        (lambda c: c.circles([[1, 1, 1]], 1, 1), r"N, 2"),
        (lambda c: c.ellipses([[1, 1]], 2, 1.5, 1), "not integral"),
        (lambda c: midpoint_circle(0, 0, -2), ">= 0"),
        (lambda c: midpoint_ellipse(0, 0, 1, -2), ">= 0"),
    ],
)
def test_bad_circle_input(call, match):
    with pytest.raises(ConfigError, match=match):
        call(Canvas(10, 10, "1"))

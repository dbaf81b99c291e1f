"""Damage tracking: Rect helpers, the merge cost model, coverage of every change, tile comparison."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.raster.canvas import Canvas
from pixelpen.raster.damage import (
    FEW_RECTS,
    DamageTracker,
    Rect,
    bounding,
    group_any,
    mask_runs,
    merge_rects,
    tile_damage,
)


def covered(rects: list[Rect], shape: tuple[int, int]) -> np.ndarray:
    """Bool mask of the union of rectangles."""
    m = np.zeros(shape, dtype=bool)
    for r in rects:
        m[r.slices] = True
    return m


def test_rect_helpers():
    r = Rect(3, 4, 10, 12)
    assert (r.width, r.height, r.area, r.inclusive()) == (7, 8, 56, (3, 4, 9, 11))
    assert r.union(Rect(0, 5, 4, 20)) == Rect(0, 4, 10, 20)
    assert r.aligned(1, 8, 128, 64) == Rect(3, 0, 10, 16)  # SSD1306 pages of 8 rows
    assert Rect(120, 60, 128, 63).aligned(16, 8, 128, 63) == Rect(112, 56, 128, 63)
    with pytest.raises(ConfigError):
        r.aligned(0, 8, 10, 10)


def test_cost_model_merges_only_when_cheaper():
    a, b = Rect(0, 0, 10, 10), Rect(12, 0, 22, 10)  # union adds 2x10 = 20 px
    assert merge_rects([a, b], merge_cost=20, bytes_per_pixel=1) == [Rect(0, 0, 22, 10)]
    assert merge_rects([a, b], merge_cost=19, bytes_per_pixel=1) == [a, b]
    assert merge_rects([a, b], merge_cost=39, bytes_per_pixel=2) == [a, b]
    far = Rect(100, 100, 101, 101)
    assert merge_rects([a, far, Rect(2, 2, 5, 5)], merge_cost=50, bytes_per_pixel=1) == [a, far]  # contained drops


def test_tracker_clips_and_clears():
    t = DamageTracker(20, 10, merge_cost=0)
    t.add(-5, -5, 3, 3)
    t.add(30, 0, 40, 5)  # off-canvas: ignored
    assert t.rects() == [Rect(0, 0, 3, 3)]
    t.clear()
    assert t.rects() == []
    with pytest.raises(ConfigError):
        DamageTracker(5, 5, merge_cost=-1)
    with pytest.raises(ConfigError):
        DamageTracker(5, 5, bytes_per_pixel=0)


def test_tracker_bounds_pending_rects():
    t = DamageTracker(1000, 1000, merge_cost=0)
    for i in range(200):
        t.add(i * 5, 0, i * 5 + 1, 1)
    rects = t.rects()
    assert len(rects) <= 64
    assert covered(rects, (1000, 1000))[0, ::5][:200].all()


OPS = st.sampled_from(["line", "thick", "circle", "disc", "ellipse", "poly", "tri", "flood", "blit", "aa"])


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(OPS, st.lists(st.integers(-20, 80), min_size=8, max_size=8)), min_size=1, max_size=6),
       st.sampled_from([0, 64, 100000]))
def test_damage_covers_every_changed_pixel(ops, cost):
    c = Canvas(60, 40, "L", merge_cost=cost)
    c.array[::7, :] = 9
    before = c.array.copy()
    c.clear_damage()
    bound = np.zeros((40, 60), dtype=bool)  # generous primitive bounds
    bound_area = 0
    for op, v in ops:
        x0, y0, x1, y1, r, a, b, k = v
        lo_x, hi_x = min(x0, x1), max(x0, x1)
        lo_y, hi_y = min(y0, y1), max(y0, y1)
        if op == "line":
            c.lines([[x0, y0, x1, y1]], 200)
        elif op == "thick":
            c.lines([[x0, y0, x1, y1]], 200, width=3)
            lo_x, hi_x, lo_y, hi_y = lo_x - 3, hi_x + 3, lo_y - 3, hi_y + 3
        elif op in ("circle", "disc"):
            c.circles([[x0, y0]], abs(r) % 25, 200, fill=op == "disc")
            lo_x, hi_x, lo_y, hi_y = x0 - 25, x0 + 25, y0 - 25, y0 + 25
        elif op == "ellipse":
            c.ellipses([[x0, y0]], abs(a) % 30, abs(b) % 30, 200, fill=True)
            lo_x, hi_x, lo_y, hi_y = x0 - 30, x0 + 30, y0 - 30, y0 + 30
        elif op in ("poly", "tri"):
            pts = np.array([[x0, y0], [x1, y1], [a, b]], float)
            c.polygons([pts], 200) if op == "poly" else c.triangles(pts[None], 200)
            lo_x, hi_x, lo_y, hi_y = pts[:, 0].min(), pts[:, 0].max(), pts[:, 1].min(), pts[:, 1].max()
        elif op == "flood":
            c.flood_fill((x0 % 60, y0 % 40), k % 256)
            lo_x, hi_x, lo_y, hi_y = 0, 60, 0, 40
        elif op == "blit":
            c.blit(np.full((abs(a) % 9 + 1, abs(b) % 9 + 1), 77, np.uint8), x0, y0)
            lo_x, hi_x, lo_y, hi_y = x0, x0 + 9, y0, y0 + 9
        else:
            c.lines([[x0 + 0.3, y0, x1, y1 - 0.4]], 200, antialias=True)
            lo_x, hi_x, lo_y, hi_y = lo_x - 1, hi_x + 1, lo_y - 1, hi_y + 2
        box = bound[max(int(lo_y), 0):max(int(hi_y) + 1, 0), max(int(lo_x), 0):max(int(hi_x) + 1, 0)]
        box[...] = True
        bound_area += box.size
    changed = c.array != before
    rects = c.damage()
    damaged = covered(rects, (40, 60))
    assert not (changed & ~damaged).any()
    if not bound.any():
        assert rects == []
    elif cost == 0:  # nothing far outside what was drawn: within the bounds' box, never more pixels than them
        ys, xs = np.nonzero(bound)
        assert not damaged[:ys.min()].any() and not damaged[ys.max() + 1:].any()
        assert not damaged[:, :xs.min()].any() and not damaged[:, xs.max() + 1:].any()
        assert sum(r.area for r in rects) <= bound_area


def test_damage_from_previous_frame_tiles():
    c = Canvas(100, 50, "RGB")
    prev = c.array.copy()
    c.array[3, 5] = (1, 2, 3)
    c.array[40:45, 90:99, 1] = 7
    rects = c.damage_from(prev, tile=8)
    assert covered(rects, (50, 100))[3, 5] and covered(rects, (50, 100))[40:45, 90:99].all()
    assert all(r.x0 % 8 == 0 and r.y0 % 8 == 0 for r in rects)
    assert sum(r.area for r in rects) <= 8 * 8 + 16 * 16 + 16 * 8
    assert c.damage_from(c.array.copy()) == []
    with pytest.raises(ConfigError, match="previous frame"):
        c.damage_from(prev[:, :, 0])


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.tuples(st.integers(0, 63), st.integers(0, 47)), max_size=40), st.integers(1, 20), st.integers(0, 500)
)
def test_tile_damage_covers_all_differences(points, tile, cost):
    prev = np.zeros((48, 64), np.uint16)
    cur = prev.copy()
    for x, y in points:
        cur[y, x] = 1
    rects = tile_damage(cur, prev, tile, cost, 2)
    assert not ((cur != prev) & ~covered(rects, (48, 64))).any()
    assert all(0 <= r.x0 < r.x1 <= 64 and 0 <= r.y0 < r.y1 <= 48 for r in rects)


few_rects = st.lists(st.builds(lambda x, y, w, h: Rect(x, y, x + w, y + h), st.integers(0, 60),
                               st.integers(0, 60), st.integers(0, 30), st.integers(1, 30)), max_size=FEW_RECTS)


@settings(max_examples=200, deadline=None)
@given(few_rects, st.sampled_from([0, 3, 6, 11, 128]), st.sampled_from([0.125, 1, 2, 3]),
       st.sampled_from([None, 1, 2]))
def test_few_rects_merge_as_the_vectorised_pairwise_matrix(rects, cost, bpp, max_count):
    # The plain-Python path for a few rectangles against the numpy pairwise-matrix path (ties included:
    # both take the first cheapest pair in row-major order).
    from pixelpen.raster.damage import _merge_many

    boxes = np.array([tuple(r) for r in rects if r.area > 0], dtype=np.int64).reshape(-1, 4)
    assert merge_rects(rects, cost, bpp, max_count) == _merge_many(boxes, cost, bpp, max_count)


@settings(max_examples=50, deadline=None)
@given(st.integers(1, 9), st.integers(1, 9), st.sampled_from([0, 1, 3, 4]), st.integers(0, 2**32 - 1))
def test_changed_pixels_is_any_channel_differing(h, w, channels, seed):
    from pixelpen.raster.damage import changed_pixels

    rng = np.random.default_rng(seed)
    shape = (h, w, channels) if channels else (h, w)
    a = rng.integers(0, 2, shape, dtype=np.uint8)
    b = rng.integers(0, 2, shape, dtype=np.uint8)
    expected = (a != b).any(axis=2) if channels else a != b
    assert np.array_equal(changed_pixels(a, b), expected)


def test_bounding_is_the_union_of_every_rectangle():
    rects = [Rect(5, 2, 9, 4), Rect(1, 7, 3, 8), Rect(4, 0, 6, 1)]
    assert bounding(rects) == Rect(1, 0, 9, 8) == rects[0].union(rects[1]).union(rects[2])
    assert bounding([Rect(2, 3, 4, 5)]) == Rect(2, 3, 4, 5)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 9), st.integers(1, 9), st.integers(1, 4), st.integers(0, 2**32 - 1))
def test_group_any_and_mask_runs_against_plain_references(height, width, k, seed):
    """group_any is logical_or.reduceat over groups of k rows; mask_runs lists each row's runs, row by row."""
    mask = np.random.default_rng(seed).random((height, width)) < 0.4
    if height:
        expected = np.logical_or.reduceat(mask, np.arange(0, height, k), axis=0)
        np.testing.assert_array_equal(group_any(mask, k), expected)
    runs = []
    for y, row in enumerate(mask.tolist()):  # scalar reference: walk each row
        x = 0
        while x < width:
            if row[x]:
                start = x
                while x < width and row[x]:
                    x += 1
                runs.append((y, start, x))
            x += 1
    rows, starts, ends = mask_runs(mask)
    assert list(zip(rows.tolist(), starts.tolist(), ends.tolist(), strict=True)) == runs

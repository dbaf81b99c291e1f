"""Damage trimming against a brute-force oracle: every changed pixel is covered; small damage is cut exactly
(the rectangles hold only changed pixels), larger damage to tiles, mostly-changed damage whole."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.devices.panels.trim import trim_damage
from pixelpen.devices.panels.windows import window_cost
from pixelpen.raster.damage import Rect

W = H = 96


def changed_mask(now: np.ndarray, before: np.ndarray) -> np.ndarray:
    """Pixel by pixel in plain Python loops over rows: True where any component differs."""
    out = np.zeros((H, W), dtype=bool)
    for y in range(H):
        for x in range(W):
            out[y, x] = tuple(now[y, x]) != tuple(before[y, x])
    return out


@st.composite
def frames(draw, max_side: int = 20):
    """A random shadow and a canvas differing from it in a few random blobs, with their damage rectangles."""
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    before = rng.integers(0, 4, (H, W, 3), dtype=np.uint8)
    now = before.copy()
    rects = []
    for _ in range(draw(st.integers(1, 3))):
        x, y = draw(st.integers(0, W - 1)), draw(st.integers(0, H - 1))
        w, h = draw(st.integers(1, max_side)), draw(st.integers(1, max_side))
        r = Rect(x, y, min(x + w, W), min(y + h, H))
        rects.append(r)
        blob = rng.random((r.height, r.width)) < draw(st.sampled_from([0.05, 0.3, 1.0]))
        now[r.slices][blob] ^= 0x80
    return now, before, rects


@settings(max_examples=150, deadline=None)
@given(frames())
def test_small_damage_is_cut_exactly(frame):
    now, before, rects = frame
    mask = changed_mask(now, before)
    out = trim_damage(rects, now, before, window_cost("st7789"))
    cover = np.zeros_like(mask)
    for r in out:
        cover[r.slices] = True
    assert (cover >= mask).all()  # every changed pixel is sent
    if all(mask[r.slices].all() for r in out):  # the exact cut: rectangles of changed pixels only
        assert cover.sum() == mask.sum()
    if len(rects) == 1 and mask.sum() * 2 * 3 < rects[0].area <= W * H / 16 and mask.any(axis=1).sum() == 1:
        assert cover.sum() == mask.sum()  # a sparse change in one row of small damage: exactly its pixels are sent


@settings(max_examples=60, deadline=None)
@given(frames(max_side=96))
def test_any_damage_covers_every_changed_pixel_in_the_controllers_alignment(frame):
    now, before, rects = frame
    mask = changed_mask(now, before)
    for controller, fmt in (("st7789", "rgb565be"), ("ssd1306", "mono-pages")):
        cost = window_cost(controller, pixel_format=fmt)
        out = trim_damage(rects, now, before, cost)
        cover = np.zeros_like(mask)
        for r in out:
            cover[r.slices] = True
            assert r.y0 % cost.align[1] == 0 and (r.y1 % cost.align[1] == 0 or r.y1 == H)
        assert (cover >= mask).all()


def test_a_cursor_moving_diagonally_is_its_four_strips():
    before = np.zeros((240, 240, 3), np.uint8)  # the ST7789 240x240: 800 damaged pixels are exact-trim damage
    before[10:30, 10:30] = 255
    now = np.zeros_like(before)
    now[12:32, 13:33] = 255
    out = trim_damage([Rect(10, 10, 30, 30), Rect(13, 12, 33, 32)], now, before, window_cost("st7789"))
    # old square uncovered: rows 10-11 (cols 10..29) and cols 10-12 of rows 12..29; new: cols 30-32 of rows 12..29
    # and rows 30-31 (cols 13..32): 40 + 54 + 54 + 40 = 188 pixels
    assert sorted(out) == sorted([Rect(10, 10, 30, 12), Rect(10, 12, 13, 30), Rect(30, 12, 33, 30),
                                  Rect(13, 30, 33, 32)])


def test_unchanged_damage_is_nothing_and_a_mostly_changed_rectangle_is_sent_whole():
    before = np.zeros((H, W, 3), np.uint8)
    assert trim_damage([Rect(0, 0, 10, 10)], before.copy(), before, window_cost("st7789")) == []
    now = before.copy()
    now[:, :, :] = 9
    assert trim_damage([Rect(0, 0, W, H)], now, before, window_cost("st7789")) == [Rect(0, 0, W, H)]

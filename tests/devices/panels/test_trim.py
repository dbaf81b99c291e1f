"""Damage trimming against a brute-force oracle: every changed pixel is covered; small damage is cut exactly
(the rectangles hold only changed pixels), ragged and larger damage to bands of runs, mostly-changed damage
whole."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.devices.panels.trim import _band_runs, trim_damage
from pixelpen.devices.panels.windows import MAX_WINDOWS, window_cost
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


def band_runs_oracle(mask: np.ndarray, band: int, unit_bytes: float, window_bytes: int) -> list[tuple[int, ...]]:
    """Plain Python: each run of rows holding a change (one from the first to the last when there are more than
    MAX_WINDOWS) cut into bands of ``band`` rows from its top (the fewest more that make at most MAX_WINDOWS
    bands), per band the runs of its OR-ed columns, a gap closed when its bytes are at most a window's (the rule
    of ``_band_runs`` before it closes more to keep to MAX_WINDOWS)."""
    runs: list[list[int]] = []
    for y in range(mask.shape[0]):
        if mask[y].any() and runs and runs[-1][1] == y:
            runs[-1][1] = y + 1
        elif mask[y].any():
            runs.append([y, y + 1])
    if len(runs) > MAX_WINDOWS:
        runs = [[runs[0][0], runs[-1][1]]]
    band = max(band, -(-sum(b - a for a, b in runs) // MAX_WINDOWS))
    while sum(-(-(b - a) // band) for a, b in runs) > MAX_WINDOWS:
        band += 1
    bands = [[y, min(y + band, b)] for a, b in runs for y in range(a, b, band)]
    out = []
    for y0, y1 in bands:
        cols = [any(mask[y, x] for y in range(y0, y1)) for x in range(mask.shape[1])]
        spans: list[list[int]] = []
        for x, on in enumerate(cols):
            if on and spans and spans[-1][1] == x:
                spans[-1][1] = x + 1
            elif on:
                if spans and (x - spans[-1][1]) * (y1 - y0) * unit_bytes <= window_bytes:
                    spans[-1][1] = x + 1
                else:
                    spans.append([x, x + 1])
        out += [(a, y0, b, y1) for a, b in spans]
    return out


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 90), st.integers(1, 60), st.sampled_from([1, 2, 4, 8]),
       st.sampled_from([0.005, 0.02, 0.1, 0.5]), st.sampled_from([(2.0, 11), (1.0, 6), (3.0, 11)]))
def test_band_runs_cover_every_changed_unit_in_bands_and_follow_the_gap_rule(seed, h, w, band, density, costs):
    unit_bytes, window_bytes = costs
    mask = np.random.default_rng(seed).random((h, w)) < density
    if not mask.any():
        mask[h // 2, w // 2] = True
    out = [tuple(box) for box in _band_runs(mask, band, unit_bytes, window_bytes).tolist()]
    cover = np.zeros_like(mask)
    for x0, y0, x1, y1 in out:
        assert 0 <= y0 < y1 <= h and 0 <= x0 < x1 <= w  # inside the mask
        assert not cover[y0:y1, x0:x1].any()  # no unit sent twice
        cover[y0:y1, x0:x1] = True
    assert (cover >= mask).all()
    bands = len({y0 for _, y0, _, _ in out})
    oracle = band_runs_oracle(mask, band, unit_bytes, window_bytes)
    if len(oracle) <= MAX_WINDOWS:
        assert out == oracle
    else:
        assert len(out) == max(MAX_WINDOWS, bands) and cover.sum() >= sum((b - a) * (d - c) for a, c, b, d in oracle)


def test_a_ticking_clock_sends_its_changed_strokes_not_its_box():
    """ClockFace digits on a 240x240 TFT (damage: the whole clock box each second, more than the exact-trim
    share): over ten ticks the cut covers every changed pixel, in at most MAX_WINDOWS windows a tick, sending
    under twice the changed pixels and under 0.7 of the boxes they span."""
    from pixelpen.animation import ClockFace

    black = np.zeros((240, 240, 3), np.uint8)
    face = ClockFace(black, 40, (255, 255, 255), (0, 0, 0), place="centre")
    now = black.copy()
    changed = sent = spanned = 0
    for tick in range(11):
        before = now.copy()
        x, y, patch = face.tick()
        now[y:y + patch.shape[0], x:x + patch.shape[1]] = patch
        if tick == 0:
            continue
        out = trim_damage([Rect(x, y, x + patch.shape[1], y + patch.shape[0])], now, before, window_cost("st7789"))
        mask = (now != before).any(axis=2)
        cover = np.zeros_like(mask)
        for r in out:
            cover[r.slices] = True
        assert (cover >= mask).all() and len(out) <= MAX_WINDOWS
        ys, xs = np.nonzero(mask)
        changed, sent = changed + mask.sum(), sent + cover.sum()
        spanned += (xs.max() - xs.min() + 1) * (ys.max() - ys.min() + 1)
    assert sent < 2 * changed and sent < 0.7 * spanned


@pytest.mark.parametrize("lines", [3, MAX_WINDOWS + 1])
def test_band_runs_start_a_band_at_each_run_of_changed_rows_and_take_too_many_runs_as_one(lines):
    """Lines of changes 3 rows tall every 5 rows: each line is a band of its own, its blank rows in no band (a
    band of 4 from the first row would send them); more than MAX_WINDOWS lines are banded as one run."""
    mask = np.zeros((5 * lines, 30), bool)
    for k in range(lines):
        mask[5 * k:5 * k + 3, 2 + k % 7] = True
    out = [tuple(box) for box in _band_runs(mask, 4, 2.0, 11).tolist()]
    assert out == band_runs_oracle(mask, 4, 2.0, 11)
    if lines <= MAX_WINDOWS:
        assert out == [(2 + k % 7, 5 * k, 3 + k % 7, 5 * k + 3) for k in range(lines)]
    else:
        assert out[0][1] == 0 and out[-1][3] == 5 * lines - 2 and len(out) <= MAX_WINDOWS

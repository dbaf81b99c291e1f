"""Refresh-window planning: panels.md's byte counts, alignment, merging by cost, and hypothesis invariants."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.devices.panels.windows import MAX_RECTS, PlanCost, plan_windows, window_cost
from pixelpen.errors import ConfigError
from pixelpen.raster.damage import Rect


def covered(rects, width, height):
    """Bool mask of the union of rectangles."""
    m = np.zeros((height, width), dtype=bool)
    for r in rects:
        m[r.slices] = True
    return m


def simple_cost(rects, bpp, overhead):
    """The merge model written out: pixel bytes plus one overhead per window."""
    return sum((r.x1 - r.x0) * (r.y1 - r.y0) * bpp + overhead for r in rects)


def test_full_frames_match_the_reference_byte_counts():
    # panels.md §4 and §9: bytes per full frame (window commands + pixels, I2C control bytes included).
    assert window_cost("st7789").cost([Rect(0, 0, 240, 240)]).bytes == 115_211
    assert window_cost("st7789", pixel_format="rgb666").cost([Rect(0, 0, 240, 240)]).bytes == 172_811
    assert window_cost("st7789").cost([Rect(0, 0, 240, 320)]).bytes == 153_611
    assert window_cost("ili9341").cost([Rect(0, 0, 320, 240)]).bytes == 153_611
    assert window_cost("ili9341", pixel_format="rgb666").cost([Rect(0, 0, 320, 240)]).bytes == 230_411
    assert window_cost("st7789").cost([Rect(0, 0, 20, 20)]).bytes == 811
    assert window_cost("ssd1306", bus_kind="i2c").cost([Rect(0, 0, 128, 64)]) == PlanCost(1032, 2)
    assert window_cost("ssd1306").cost([Rect(0, 0, 128, 64)]).bytes == 1030  # luma: 6 + 1024
    assert window_cost("sh1106").cost([Rect(0, 0, 128, 64)]).bytes == 8 * (3 + 128)  # luma: B0+p, 02, 10 per page


def test_transfers_and_chunks():
    # MIPI: CASET, its 4 bytes, RASET, its 4 bytes, RAMWR = 5 frames, then 115,200 bytes in 4096-byte frames (29).
    assert window_cost("st7789").cost([Rect(0, 0, 240, 240)]).transfers == 5 + 29
    # I2C with 32-byte messages: 31 data bytes + 0x40 per transaction: 34 data transactions for 1024 bytes.
    assert window_cost("ssd1306", bus_kind="i2c", max_transfer=32).cost([Rect(0, 0, 128, 64)]) == PlanCost(
        7 + 1024 + 34, 1 + 34)
    assert window_cost("st7789").cost([]) == PlanCost(0, 0)


def test_ssd1306_rows_round_to_pages():
    m = window_cost("ssd1306")
    assert m.plan([Rect(10, 3, 30, 20)], width=128, height=64) == [Rect(10, 0, 30, 24)]
    assert m.plan([Rect(0, 60, 5, 70)], width=128, height=64) == [Rect(0, 56, 5, 64)]  # clipped at the bottom


def test_sh1106_windows_stay_in_one_page():
    windows = window_cost("sh1106").plan([Rect(10, 3, 30, 20)], width=128, height=64)
    assert windows == [Rect(10, 0, 30, 8), Rect(10, 8, 30, 16), Rect(10, 16, 30, 24)]
    with pytest.raises(ConfigError, match="8 bands of 8 rows"):
        window_cost("sh1106").plan([Rect(0, 0, 1, 64)], width=128, height=64, max_windows=4)


def test_merging_by_cost():
    kw = dict(width=240, height=240, bytes_per_pixel=2.0, window_overhead=11)
    assert plan_windows([Rect(10, 10, 30, 30), Rect(12, 12, 31, 33)], **kw) == [Rect(10, 10, 31, 33)]  # overlap
    assert plan_windows([Rect(0, 0, 20, 20), Rect(5, 5, 6, 6)], **kw) == [Rect(0, 0, 20, 20)]  # contained
    far = [Rect(0, 0, 20, 20), Rect(200, 200, 220, 220)]
    assert plan_windows(far, **kw) == far  # the bounding box would cost 80,000 more bytes
    # Two 1-pixel dots 2 columns apart: the union adds 1 pixel (2 bytes) < 11 bytes of a second window.
    assert plan_windows([Rect(0, 0, 1, 1), Rect(2, 0, 3, 1)], **kw) == [Rect(0, 0, 3, 1)]
    assert plan_windows([Rect(-5, -5, 0, 3), Rect(240, 0, 250, 5)], **kw) == []  # outside the panel


def test_max_windows_and_overflow():
    dots = [Rect(x, y, x + 1, y + 1) for x in range(0, 240, 30) for y in range(0, 240, 30)]  # 64 distant dots
    kw = dict(width=240, height=240, bytes_per_pixel=2.0, window_overhead=11)
    assert len(plan_windows(dots, max_windows=64, **kw)) == 64
    assert len(plan_windows(dots, **kw)) == 32  # the default limit
    assert len(plan_windows(dots, max_windows=32, **kw)) <= 32
    assert len(plan_windows(dots, max_windows=1, **kw)) == 1
    many = [Rect(x, 0, x + 1, 1) for x in range(0, 2 * (MAX_RECTS + 1), 2)]
    assert plan_windows(many, width=600, height=10, bytes_per_pixel=2, window_overhead=0) == [
        Rect(0, 0, 2 * MAX_RECTS + 1, 1)]


def test_even_alignment():
    assert plan_windows([Rect(3, 3, 6, 4)], width=135, height=240, align=(2, 1), bytes_per_pixel=1.5,
                        window_overhead=11) == [Rect(2, 3, 6, 4)]
    assert plan_windows([Rect(133, 0, 135, 1)], width=135, height=240, align=(2, 1), bytes_per_pixel=1.5,
                        window_overhead=11) == [Rect(132, 0, 135, 1)]  # the panel's edge ends it


@pytest.mark.parametrize("kwargs", [
    dict(width=0, height=10), dict(width=10, height=10, align=(0, 1)), dict(width=10, height=10, max_windows=0),
    dict(width=10, height=10, bytes_per_pixel=0), dict(width=10, height=10, window_overhead=-1),
    dict(width=10, height=10, band_rows=0),
])
def test_bad_arguments(kwargs):
    args = dict(bytes_per_pixel=2.0, window_overhead=11) | kwargs
    with pytest.raises(ConfigError):
        plan_windows([Rect(0, 0, 1, 1)], **args)


@pytest.mark.parametrize(("controller", "kw"), [
    ("st7789", dict(bus_kind="i2c")), ("ssd1306", dict(pixel_format="rgb565be")), ("st7789", dict(max_transfer=1)),
    ("ili9341", dict(pixel_format="rgb444")), ("ssd1306", dict(bus_kind="usb")),
])
def test_bad_cost_models(controller, kw):
    with pytest.raises(ConfigError):
        window_cost(controller, **kw)


rects = st.lists(st.builds(lambda x, y, w, h: Rect(x, y, x + w, y + h), st.integers(-10, 140), st.integers(-10, 70),
                           st.integers(0, 60), st.integers(0, 40)), max_size=40)


@settings(max_examples=300, deadline=None)
@given(rects, st.sampled_from(["ssd1306", "sh1106", "st7789"]), st.integers(1, 40))
def test_plan_invariants(damage, controller, max_windows):
    width, height = 128, 64
    model = window_cost(controller)
    if controller == "sh1106":
        max_windows = max(max_windows, 8)
    windows = model.plan(damage, width=width, height=height, max_windows=max_windows)
    clipped = [Rect(max(r.x0, 0), max(r.y0, 0), min(r.x1, width), min(r.y1, height)) for r in damage]
    want = covered([r for r in clipped if r.x1 > r.x0 and r.y1 > r.y0], width, height)
    assert not (want & ~covered(windows, width, height)).any()  # every damaged pixel is sent
    assert len(windows) <= max_windows
    ay = model.align[1]
    for w in windows:
        assert 0 <= w.x0 < w.x1 <= width and 0 <= w.y0 < w.y1 <= height
        assert w.y0 % ay == 0 and (w.y1 % ay == 0 or w.y1 == height)
        if model.band_rows:
            assert w.y0 // 8 == (w.y1 - 1) // 8
    if not windows:
        return
    bpp, overhead = model.bytes_per_pixel, model.window_bytes
    aligned = [r.aligned(1, ay, width, height) for r in clipped if r.x1 > r.x0 and r.y1 > r.y0]
    if model.band_rows:  # one window per page: the unmerged plan is the aligned rects cut at pages
        aligned = [Rect(r.x0, y, r.x1, y + 8) for r in aligned for y in range(r.y0, r.y1, 8)]
    box = Rect(min(r.x0 for r in aligned), min(r.y0 for r in aligned), max(r.x1 for r in aligned),
               max(r.y1 for r in aligned))
    bounding = [Rect(box.x0, y, box.x1, y + 8) for y in range(box.y0, box.y1, 8)] if model.band_rows else [box]
    cost = simple_cost(windows, bpp, overhead)
    assert cost <= simple_cost(bounding, bpp, overhead) + 1e-9
    if len(aligned) <= max_windows:
        assert cost <= simple_cost(aligned, bpp, overhead) + 1e-9


# One window through the real bus classes over the simulated chips: the bytes on the wire (bus.bytes_sent, I2C
# control bytes included) are what the cost model says, so the overheads declared in windows.py (MIPI 11,
# SSD1306 6, SH1106 3 per page) are the ones _write_window sends.
@pytest.mark.parametrize(("url", "changed", "window"), [
    ("sim:st7789", Rect(5, 9, 8, 10), Rect(5, 9, 8, 10)),
    ("sim:ili9341", Rect(5, 9, 8, 10), Rect(5, 9, 8, 10)),
    ("sim:st7735", Rect(5, 9, 8, 10), Rect(5, 9, 8, 10)),
    ("sim:ssd1306", Rect(5, 9, 8, 10), Rect(5, 8, 8, 16)),
    ("sim:ssd1306?dc=24", Rect(5, 9, 8, 10), Rect(5, 8, 8, 16)),
    ("sim:ssd1309", Rect(5, 9, 8, 10), Rect(5, 8, 8, 16)),
    ("sim:sh1106", Rect(5, 9, 8, 10), Rect(5, 8, 8, 16)),
    ("sim:sh1106?dc=24", Rect(5, 6, 8, 10), Rect(5, 0, 8, 16)),
])
def test_the_window_overhead_is_what_the_controller_sends(url, changed, window):
    import pixelpen

    with pixelpen.open(url) as display:
        before = display.bus.bytes_sent
        value = 1 if display.canvas_mode == "1" else (255, 255, 255)
        display.canvas.array[changed.slices] = value
        display.canvas.mark_damaged(changed.x0, changed.y0, changed.x1, changed.y1)
        display.flush()
        assert display.stats.last.windows == 1
        assert display.bus.bytes_sent - before == display.cost.window(window).bytes
        per_window = display.cost.window_bytes - display.cost.data_framing * 0  # commands (+ I2C control byte)
        expected = {"st7": 11, "ili": 11, "ssd": 6, "sh1": 3}[url[4:7]] + (display.bus.kind == "i2c")
        assert per_window == expected


def test_a_cut_is_kept_unless_its_bounding_window_costs_fewer_bytes():
    cost = window_cost("st7789")  # 2 bytes a pixel, 11 a window
    apart = [Rect(0, 0, 4, 1), Rect(100, 0, 104, 1)]  # 2 x (8 + 11) = 38 bytes < 104 x 2 + 11
    near = [Rect(0, 0, 4, 1), Rect(6, 0, 10, 1)]  # 38 bytes > 10 x 2 + 11 = 31
    assert cost.cut_or_bounding(apart) == apart
    assert cost.cut_or_bounding(near) == [Rect(0, 0, 10, 1)]
    assert cost.cut_or_bounding([Rect(3, 4, 5, 6)]) == [Rect(3, 4, 5, 6)]

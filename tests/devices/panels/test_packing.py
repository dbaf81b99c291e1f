"""packing: a frame's wire units and its windows packed once for their bounding box or once each, against
``formats.pack`` window by window and a per-pixel oracle of the wire bytes."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.devices.panels.packing import PACK_ONCE, keep_windows, pack_windows, to_units, update_units
from pixelpen.raster.damage import Rect
from pixelpen.raster.formats import pack


def oracle(units: np.ndarray, window: Rect, fmt: str) -> bytes:
    """Per pixel: RGB565 values high byte first, RGB666 as R, G, B with the low two bits clear, SSD1306 pages as
    one byte per column of 8 rows (bit k = row k of the page, lit = 1)."""
    x0, y0, x1, y1 = window
    out = bytearray()
    if fmt == "mono-pages":
        for page in range(y0 // 8, -(-y1 // 8)):
            for x in range(x0, x1):
                rows = range(8 * page, min(8 * page + 8, units.shape[0]))
                out.append(sum(1 << (y - 8 * page) for y in rows if units[y, x]))
        return bytes(out)
    for y in range(y0, y1):
        for x in range(x0, x1):
            if fmt == "rgb565be":
                out += int(units[y, x]).to_bytes(2, "big")
            else:
                out += bytes(int(c) & 0xFC for c in units[y, x])
    return bytes(out)


def frame(fmt: str, seed: int, width: int, height: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    if fmt == "rgb565be":
        return rng.integers(0, 1 << 16, (height, width), dtype=np.uint16)
    if fmt == "mono-pages":
        return rng.random((height, width)) < 0.5
    return rng.integers(0, 256, (height, width, 3), dtype=np.uint8)


@st.composite
def windows(draw: st.DrawFn, width: int, height: int, page: int) -> list[Rect]:
    out = []
    for _ in range(draw(st.integers(0, 6))):
        x0, y0 = draw(st.integers(0, width - 1)), draw(st.integers(0, (height - 1) // page)) * page
        x1 = draw(st.integers(x0 + 1, width))
        y1 = min(draw(st.integers(y0 // page + 1, -(-height // page))) * page, height)
        out.append(Rect(x0, y0, x1, y1))
    return out


@settings(max_examples=60, deadline=None)
@given(st.sampled_from(["rgb565be", "rgb666", "mono-pages"]), st.integers(0, 2**32 - 1), st.data())
def test_windows_pack_as_formats_pack_and_the_per_pixel_oracle(fmt: str, seed: int, data: st.DataObject) -> None:
    width, height = (40, 21) if fmt != "mono-pages" else (40, 20)  # 20 rows: the last page cut by the edge
    units = frame(fmt, seed, width, height)
    page = 8 if fmt == "mono-pages" else 1
    rects = data.draw(windows(width, height, page))
    packed = pack_windows(units, rects, fmt, page)
    assert packed == [pack(units[r.slices], fmt) for r in rects]
    assert packed == [oracle(units, r, fmt) for r in rects]


def test_spread_windows_are_packed_one_by_one_and_close_ones_from_their_box() -> None:
    units = frame("rgb565be", 1, 200, 100)
    far = [Rect(0, 0, 2, 2), Rect(198, 98, 200, 100)]  # a bounding box of 20,000 pixels for 8
    near = [Rect(0, 0, 10, 10), Rect(12, 0, 20, 10)]
    assert Rect(0, 0, 200, 100).area > PACK_ONCE
    for rects in (far, near):
        assert pack_windows(units, rects, "rgb565be") == [oracle(units, r, "rgb565be") for r in rects]
    assert pack_windows(units, [], "rgb565be") == []


@pytest.mark.parametrize("fmt", ["rgb666", "mono-pages"])
def test_only_an_rgb565_wire_has_units_of_its_own(fmt: str) -> None:
    assert to_units(np.zeros((4, 4, 3), np.uint8), fmt) is None


def test_units_are_rgb565_values_updated_only_inside_the_damage() -> None:
    rgb = np.zeros((6, 8, 3), np.uint8)
    units = to_units(rgb, "rgb565be")
    assert units is not None and units.dtype == np.uint16 and not units.any()
    rgb[:, :] = (0xFF, 0x04, 0x08)  # R 11111, G 000001, B 00001
    update_units(units, rgb, [Rect(1, 2, 3, 4)])
    expected = np.zeros((6, 8), np.uint16)
    expected[2:4, 1:3] = 0xF800 | 0x0020 | 0x0001
    np.testing.assert_array_equal(units, expected)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 95), st.integers(0, 63), st.integers(1, 40), st.integers(1, 30)),
                min_size=1, max_size=6), st.integers(0, 2**32 - 1))
def test_keep_windows_makes_the_shadow_the_sent_frame_whether_copied_by_box_or_per_window(boxes, seed):
    """Where the new frame differs from the shadow only inside the windows, the shadow afterwards is the new frame
    (a copy of the windows' bounding box touches outside them only pixels already equal)."""
    rng = np.random.default_rng(seed)
    shadow = rng.integers(0, 1 << 16, (64, 96), dtype=np.uint16)
    units = shadow.copy()
    windows = [Rect(x, y, min(x + w, 96), min(y + h, 64)) for x, y, w, h in boxes]
    for x0, y0, x1, y1 in windows:
        units[y0:y1, x0:x1] = rng.integers(0, 1 << 16, (y1 - y0, x1 - x0), dtype=np.uint16)
    keep_windows(shadow, units, windows)
    assert np.array_equal(shadow, units)

"""Tests for pixelpen.raster.formats: datasheet byte layouts, Pillow equivalence, round trips, errors."""

from __future__ import annotations

import struct

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from pixelpen.errors import ConfigError, ParseError
from pixelpen.raster.formats import FORMATS, align_region, image_kind, pack, pixel_format, unpack

SETTINGS = settings(max_examples=40, deadline=None)


def rgb_image(h: int, w: int, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (h, w, 3), dtype=np.uint8)


def scalar_rgb565(r: int, g: int, b: int) -> int:
    """RGB565 from the ST7789 datasheet layout RRRRRGGG GGGBBBBB (top bits of each component)."""
    return ((r >> 3) << 11) | ((g >> 2) << 5) | (b >> 3)


def replicate(value: int, bits: int) -> int:
    """Widen a `bits`-bit field to 8 bits by repeating its top bits."""
    out, filled = 0, 0
    while filled < 8:
        out = (out << bits) | value
        filled += bits
    return out >> (filled - 8)


# --- byte sequences worked out by hand from the datasheet layouts ---------------------------

def test_ssd1306_single_pixel_lands_in_page0_column3_bit5():
    img = np.zeros((8, 16), dtype=bool)
    img[5, 3] = True  # (x=3, y=5): page 0, column 3, bit 5 (bit 0 = top row)
    data = pack(img, "mono-pages")
    assert len(data) == 16
    assert data[3] == 0x20
    assert sum(data) == 0x20


def test_ssd1306_second_page_and_padded_height():
    img = np.zeros((10, 4), dtype=bool)  # 10 rows -> 2 pages, last page padded with off pixels
    img[9, 0] = True   # row 9 = page 1 bit 1
    img[0, 2] = True   # row 0 = page 0 bit 0
    img[7, 2] = True   # row 7 = page 0 bit 7
    assert pack(img, "mono-pages") == bytes([0, 0, 0x81, 0, 0x02, 0, 0, 0])


def test_rgb565_primaries_big_and_little_endian():
    pixels = np.array([[[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]]], dtype=np.uint8)
    assert pack(pixels, "rgb565be") == b"\xf8\x00\x07\xe0\x00\x1f\xff\xff"
    assert pack(pixels, "rgb565le") == b"\x00\xf8\xe0\x07\x1f\x00\xff\xff"
    assert pack(pixels[:, :1], "rgb565be") == b"\xf8\x00"


def test_rgb565_truncates_rather_than_rounds():
    # (7, 3, 7) truncates to 0; rounding would give (1, 1, 1) -> 0x0821.
    assert pack(np.array([[[7, 3, 7]]], dtype=np.uint8), "rgb565be") == b"\x00\x00"


def test_rgb666_keeps_six_msbs_of_each_byte():
    assert pack(np.array([[[255, 128, 3]]], dtype=np.uint8), "rgb666") == bytes([0xFC, 0x80, 0x00])


def test_byte_orders_of_24_and_32_bit_formats():
    px = np.array([[[1, 2, 3]]], dtype=np.uint8)
    assert pack(px, "rgb888") == b"\x01\x02\x03"
    assert pack(px, "bgr888") == b"\x03\x02\x01"
    data = pack(px, "xrgb8888")
    assert data == b"\x03\x02\x01\xff"
    # fbdev bitfields red.offset 16, green.offset 8, blue.offset 0 of a little-endian word
    (word,) = struct.unpack("<I", data)
    assert (word >> 16) & 0xFF == 1 and (word >> 8) & 0xFF == 2 and word & 0xFF == 3


def test_mono_rows_msb_first_padded_rows():
    img = np.zeros((2, 10), dtype=bool)
    img[0, 0] = True
    img[1, 9] = True
    assert pack(img, "mono-rows") == bytes([0x80, 0x00, 0x00, 0x40])


def test_mono_threshold_is_pillows_rgb2bit_and_grey_128():
    # 299*1 + 587*189 + 114*147 = 128000 exactly: on; one step of blue less: off.
    px = np.array([[[1, 189, 147], [1, 189, 146]]], dtype=np.uint8)
    assert unpack(pack(px, "mono-rows"), "mono-rows", 2, 1).tolist() == [[True, False]]
    grey = np.array([[128, 127]], dtype=np.uint8)
    assert unpack(pack(grey, "mono-rows"), "mono-rows", 2, 1).tolist() == [[True, False]]


def test_grey_and_bitmap_inputs_to_colour_formats():
    grey = np.array([[0x84]], dtype=np.uint8)
    assert pack(grey, "rgb888") == b"\x84\x84\x84"
    assert pack(grey, "rgb565be") == struct.pack(">H", scalar_rgb565(0x84, 0x84, 0x84))
    bitmap = np.array([[True, False]])
    assert pack(bitmap, "rgb565be") == b"\xff\xff\x00\x00"
    zero_one = np.array([[1, 0]], dtype=np.int64)
    assert pack(zero_one, "mono-rows") == b"\x80"


def test_uint16_values_pack_as_they_are():
    values = np.array([[0x1234, 0xF800]], dtype=np.uint16)
    assert pack(values, "rgb565be") == b"\x12\x34\xf8\x00"
    assert pack(values, "rgb565le") == b"\x34\x12\x00\xf8"


# --- independent references: Pillow and a scalar datasheet packer ----------------------------

@pytest.mark.parametrize("shape", [(24, 40), (21, 13), (8, 1), (1, 9)])
def test_mono_pages_equal_pillow_convert_transpose_tobytes(shape):
    img = rgb_image(*shape, seed=1)
    h, w = shape
    pil = Image.fromarray(img).convert("1", dither=Image.Dither.NONE)
    columns = pil.transpose(Image.Transpose.TRANSPOSE).tobytes("raw", "1;R")  # column-major pages
    pages = np.frombuffer(columns, dtype=np.uint8).reshape(w, (h + 7) // 8).T.tobytes()
    assert pack(img, "mono-pages") == pages


def test_mono_rows_equal_pillow_1bit_raw():
    img = rgb_image(11, 19, seed=2)
    pil = Image.fromarray(img).convert("1", dither=Image.Dither.NONE)
    assert pack(img, "mono-rows") == pil.tobytes()


def test_colour_formats_equal_pillow_raw_packers():
    img = rgb_image(9, 14, seed=3)
    pil = Image.fromarray(img)
    assert pack(img, "rgb888") == pil.tobytes("raw", "RGB")
    assert pack(img, "bgr888") == pil.tobytes("raw", "BGR")
    ours = np.frombuffer(pack(img, "xrgb8888"), dtype=np.uint8).reshape(-1, 4)
    theirs = np.frombuffer(pil.tobytes("raw", "BGRX"), dtype=np.uint8).reshape(-1, 4)
    assert np.array_equal(ours[:, :3], theirs[:, :3])
    assert (ours[:, 3] == 0xFF).all()


def test_rgb565_equals_scalar_datasheet_packer():
    img = rgb_image(7, 9, seed=4)
    expected_be = b"".join(struct.pack(">H", scalar_rgb565(*map(int, px))) for px in img.reshape(-1, 3))
    expected_le = b"".join(struct.pack("<H", scalar_rgb565(*map(int, px))) for px in img.reshape(-1, 3))
    assert pack(img, "rgb565be") == expected_be
    assert pack(img, "rgb565le") == expected_le


def test_large_frame_crosses_chunk_boundaries():
    img = rgb_image(300, 517, seed=5)  # > CHUNK_PIXELS, odd width
    r, g, b = (img[..., i].astype(np.uint32) for i in range(3))
    expected = (((r & 0xF8) << 8) | ((g & 0xFC) << 3) | (b >> 3)).astype(">u2").tobytes()
    assert pack(img, "rgb565be") == expected
    lit = (299 * r + 587 * g + 114 * b) >= 128000
    assert np.array_equal(unpack(pack(img, "mono-pages"), "mono-pages", 517, 300), lit)


# --- round trips --------------------------------------------------------------------------

shapes = st.tuples(st.integers(0, 20), st.integers(0, 20))


@SETTINGS
@given(shape=shapes, fmt=st.sampled_from(sorted(FORMATS)), seed=st.integers(0, 2**32 - 1))
def test_pack_unpack_pack_is_stable(shape, fmt, seed):
    h, w = shape
    img = rgb_image(h, w, seed)
    data = pack(img, fmt)
    assert len(data) == FORMATS[fmt].size(w, h)
    decoded = unpack(data, fmt, w, h)
    assert pack(decoded, fmt) == data


@SETTINGS
@given(shape=shapes, fmt=st.sampled_from(["rgb888", "bgr888", "xrgb8888"]), seed=st.integers(0, 2**32 - 1))
def test_24_bit_formats_round_trip_exactly(shape, fmt, seed):
    img = rgb_image(*shape, seed)
    assert np.array_equal(unpack(pack(img, fmt), fmt, shape[1], shape[0]), img)


@SETTINGS
@given(shape=shapes, fmt=st.sampled_from(["rgb565be", "rgb565le", "rgb666"]), seed=st.integers(0, 2**32 - 1))
def test_narrow_formats_decode_to_bit_replicated_truncation(shape, fmt, seed):
    h, w = shape
    img = rgb_image(h, w, seed)
    bits = (5, 6, 5) if fmt.startswith("rgb565") else (6, 6, 6)
    expected = np.array(
        [[[replicate(int(img[y, x, c]) >> (8 - bits[c]), bits[c]) for c in range(3)] for x in range(w)]
         for y in range(h)],
        dtype=np.uint8,
    ).reshape(h, w, 3)
    assert np.array_equal(unpack(pack(img, fmt), fmt, w, h), expected)


@SETTINGS
@given(shape=shapes, fmt=st.sampled_from(["mono-pages", "mono-rows"]), seed=st.integers(0, 2**32 - 1))
def test_bitmaps_round_trip_exactly(shape, fmt, seed):
    h, w = shape
    bits = np.random.default_rng(seed).random((h, w)) < 0.5
    assert np.array_equal(unpack(pack(bits, fmt), fmt, w, h), bits)


@SETTINGS
@given(shape=shapes, big=st.booleans(), seed=st.integers(0, 2**32 - 1))
def test_raw_rgb565_bytes_round_trip(shape, big, seed):
    h, w = shape
    fmt = "rgb565be" if big else "rgb565le"
    data = np.random.default_rng(seed).integers(0, 256, 2 * h * w, dtype=np.uint8).tobytes()
    values = unpack(data, fmt, w, h, raw=True)
    assert values.dtype == np.uint16 and values.shape == (h, w)
    assert pack(values, fmt) == data


def test_all_rgb565_values_survive_widening_and_truncation():
    values = np.arange(65536, dtype=np.uint16).reshape(256, 256)
    data = pack(values, "rgb565be")
    assert pack(unpack(data, "rgb565be", 256, 256), "rgb565be") == data


# --- regions --------------------------------------------------------------------------------

@SETTINGS
@given(
    fmt=st.sampled_from(sorted(FORMATS)),
    box=st.tuples(st.integers(0, 17), st.integers(0, 13), st.integers(0, 17), st.integers(0, 13)),
)
def test_region_packs_the_window(fmt, box):
    img = rgb_image(13, 17, seed=6)
    x0, x1 = sorted(box[0::2])
    y0, y1 = sorted(box[1::2])
    ax0, ay0, ax1, ay1 = align_region(fmt, (x0, y0, x1, y1), 17, 13)
    if fmt == "mono-pages":
        assert ay0 % 8 == 0 and ay0 <= y0 and ay1 >= y1 and (ay1 % 8 == 0 or ay1 == 13)
    else:
        assert (ax0, ay0, ax1, ay1) == (x0, y0, x1, y1)
    assert pack(img, fmt, (x0, y0, x1, y1)) == pack(img[ay0:ay1, ax0:ax1].copy(), fmt)


def test_mono_pages_region_is_widened_to_whole_pages():
    assert align_region("mono-pages", (2, 3, 5, 12), 128, 64) == (2, 0, 5, 16)
    assert align_region("mono-pages", (0, 8, 128, 16), 128, 64) == (0, 8, 128, 16)
    assert align_region("mono-pages", (0, 9, 4, 10), 4, 10) == (0, 8, 4, 10)
    img = np.zeros((16, 8), dtype=bool)
    img[9, 4] = True
    assert pack(img, "mono-pages", (4, 9, 6, 10)) == bytes([0x02, 0x00])


def test_region_of_whole_image_and_empty_region():
    img = rgb_image(5, 6)
    assert pack(img, "rgb565be", (0, 0, 6, 5)) == pack(img, "rgb565be")
    assert pack(img, "rgb565be", (3, 2, 3, 4)) == b""


# --- table and errors -----------------------------------------------------------------------

def test_format_table():
    assert FORMATS["rgb565be"].bytes_per_pixel == 2 and FORMATS["rgb666"].depth == 18
    assert FORMATS["xrgb8888"].bits_per_pixel == 32 and FORMATS["mono-pages"].bytes_per_pixel is None
    assert FORMATS["mono-pages"].size(128, 64) == 1024 and FORMATS["mono-rows"].size(10, 3) == 6
    assert pixel_format(FORMATS["bgr888"]) is FORMATS["bgr888"]
    assert all(f.mono == (f.bits_per_pixel == 1) for f in FORMATS.values())


def test_unknown_format():
    with pytest.raises(ConfigError, match="unknown pixel format 'rgb555'"):
        pack(rgb_image(1, 1), "rgb555")
    with pytest.raises(ConfigError, match="unknown pixel format"):
        unpack(b"", "argb", 0, 0)


@pytest.mark.parametrize(
    "array, message",
    [
        (np.zeros((2, 2, 4), dtype=np.uint8), "found uint8 with shape \\(2, 2, 4\\)"),
        (np.zeros((2, 2, 3), dtype=np.float32), "found float32"),
        (np.zeros(5, dtype=np.uint8), "shape \\(5,\\)"),
        (np.array([[0, 2]], dtype=np.int32), "holds values 0..2"),
        ([[1, 2]], "numpy array"),
    ],
)
def test_malformed_images(array, message):
    with pytest.raises(ConfigError, match=message):
        pack(array, "rgb888") if isinstance(array, np.ndarray) else image_kind(array)


def test_rgb565_values_only_pack_to_rgb565():
    values = np.zeros((2, 2), dtype=np.uint16)
    with pytest.raises(ConfigError, match="only to rgb565be/rgb565le, not rgb888"):
        pack(values, "rgb888")
    with pytest.raises(ConfigError, match="not RGB565 values"):
        pack(values, "mono-pages")


def test_truncated_and_oversized_data_name_byte_counts():
    with pytest.raises(ParseError, match="truncated rgb565be data for 4x3: expected 24 bytes, found 23") as info:
        unpack(bytes(23), "rgb565be", 4, 3)
    assert info.value.offset == 23
    message = "oversized mono-pages data for 128x64: expected 1024 bytes, found 1025"
    with pytest.raises(ParseError, match=message) as info:
        unpack(bytes(1025), "mono-pages", 128, 64)
    assert info.value.offset == 1024
    with pytest.raises(ParseError, match="expected 6 bytes, found 0"):
        unpack(b"", "mono-rows", 10, 3)


def test_bad_unpack_arguments():
    with pytest.raises(ConfigError, match="width must be a non-negative integer"):
        unpack(b"", "rgb888", -1, 0)
    with pytest.raises(ConfigError, match="height must be a non-negative integer"):
        unpack(b"", "rgb888", 0, 1.5)
    with pytest.raises(ConfigError, match="bytes-like"):
        unpack([1, 2, 3], "rgb888", 1, 1)
    with pytest.raises(ConfigError, match="raw=True applies to rgb565be/rgb565le"):
        unpack(bytes(3), "rgb888", 1, 1, raw=True)


@pytest.mark.parametrize("region", [(0, 0, 7, 5), (-1, 0, 2, 2), (3, 0, 2, 2), (0, 0, 1)])
def test_bad_regions(region):
    with pytest.raises(ConfigError, match="region"):
        pack(rgb_image(5, 6), "rgb888", region)


def test_region_must_be_integers():
    with pytest.raises(ConfigError, match="four integers"):
        pack(rgb_image(5, 6), "rgb888", (0, 0, 2.5, 2))


def test_unpack_accepts_any_bytes_like():
    data = bytearray(b"\x01\x02\x03\x04\x05\x06")
    assert unpack(memoryview(data), "rgb888", 2, 1).tolist() == [[[1, 2, 3], [4, 5, 6]]]

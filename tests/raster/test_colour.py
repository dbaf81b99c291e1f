"""Tests for pixelpen.raster.colour: worked examples, colorsys as an independent reference, exact conversions."""

from __future__ import annotations

import colorsys
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from pixelpen.errors import ConfigError
from pixelpen.raster.colour import (
    hsl_to_rgb,
    hsl_to_rgb8,
    hsv_to_rgb,
    hsv_to_rgb8,
    luma,
    rgb8_to_hsl,
    rgb8_to_hsv,
    rgb565_to_rgb888,
    rgb888_to_rgb565,
    rgb_to_hsl,
    rgb_to_hsv,
)

SETTINGS = settings(max_examples=60, deadline=None)
unit = st.floats(0.0, 1.0, allow_nan=False)


# --- worked examples (Foley et al. §13.3; Hearn & Baker colour models) -------------------

@pytest.mark.parametrize(
    "rgb, hsv",
    [
        ((1, 0, 0), (0, 1, 1)),
        ((0, 1, 0), (120, 1, 1)),
        ((0, 0, 1), (240, 1, 1)),
        ((1, 1, 0), (60, 1, 1)),
        ((0, 1, 1), (180, 1, 1)),
        ((1, 0, 1), (300, 1, 1)),
        ((1, 0.5, 0), (30, 1, 1)),
        ((0.5, 0.5, 0.5), (0, 0, 0.5)),
        ((0, 0, 0), (0, 0, 0)),
        ((0.5, 0.25, 0.25), (0, 0.5, 0.5)),
    ],
)
def test_hsv_worked_examples(rgb, hsv):
    assert np.allclose(rgb_to_hsv(rgb), hsv)
    assert np.allclose(hsv_to_rgb(hsv), rgb)


@pytest.mark.parametrize(
    "rgb, hsl",
    [
        ((1, 0, 0), (0, 1, 0.5)),
        ((1, 1, 1), (0, 0, 1)),
        ((0, 0, 0), (0, 0, 0)),
        ((0.5, 0.25, 0.75), (270, 0.5, 0.5)),  # max b: 4 + (r-g)/delta = 4.5 sectors; s = 0.5 / (0.75+0.25)
        ((0.75, 1.0, 0.5), (90, 1.0, 0.75)),   # l > 1/2: s = 0.5 / (2 - 1.0 - 0.5)
    ],
)
def test_hsl_worked_examples(rgb, hsl):
    assert np.allclose(rgb_to_hsl(rgb), hsl)
    assert np.allclose(hsl_to_rgb(hsl), rgb)


def test_uint8_worked_example():
    assert np.allclose(rgb8_to_hsv(np.array([255, 0, 0], dtype=np.uint8)), (0, 1, 1))
    assert hsv_to_rgb8((0, 1, 1)).tolist() == [255, 0, 0]
    assert hsl_to_rgb8((120, 1, 0.25)).tolist() == [0, 128, 0]  # 0.5 * 255 = 127.5 rounds to 128


# --- colorsys as an independent implementation -------------------------------------------

@SETTINGS
@given(st.tuples(unit, unit, unit))
def test_hsv_matches_colorsys(rgb):
    h, s, v = colorsys.rgb_to_hsv(*rgb)
    ours = rgb_to_hsv(rgb)
    if s > 1e-12:  # hue is undefined for greys
        assert np.isclose(ours[0] % 360, (h * 360) % 360, atol=1e-6) or abs(abs(ours[0] - h * 360) - 360) < 1e-6
    assert np.allclose(ours[1:], (s, v), atol=1e-12)


@SETTINGS
@given(st.tuples(unit, unit, unit))
def test_hsl_matches_colorsys(rgb):
    h, light, s = colorsys.rgb_to_hls(*rgb)
    ours = rgb_to_hsl(rgb)
    if s > 1e-12:
        assert np.isclose(ours[0], (h * 360) % 360, atol=1e-6) or abs(abs(ours[0] - h * 360) - 360) < 1e-6
    assert np.allclose(ours[1:], (s, light), atol=1e-9)


@SETTINGS
@given(st.tuples(st.floats(-720, 720, allow_nan=False), unit, unit))
def test_inverse_conversions_match_colorsys(hsx):
    h, s, x = hsx
    assert np.allclose(hsv_to_rgb(hsx), colorsys.hsv_to_rgb((h / 360) % 1.0, s, x), atol=1e-9)
    assert np.allclose(hsl_to_rgb(hsx), colorsys.hls_to_rgb((h / 360) % 1.0, x, s), atol=1e-9)


# --- round trips and vectorisation -------------------------------------------------------

def test_round_trips_on_arrays():
    rng = np.random.default_rng(7)
    rgb = rng.random((50, 40, 3))
    assert np.allclose(hsv_to_rgb(rgb_to_hsv(rgb)), rgb, atol=1e-12)
    assert np.allclose(hsl_to_rgb(rgb_to_hsl(rgb)), rgb, atol=1e-12)
    hsv = rgb_to_hsv(rgb)
    assert hsv.shape == (50, 40, 3)
    assert ((hsv[..., 0] >= 0) & (hsv[..., 0] < 360)).all()


def test_uint8_round_trips_are_exact_on_a_lattice_of_colours():
    levels = np.arange(0, 256, 5, dtype=np.uint8)
    rgb = np.stack(np.meshgrid(levels, levels, levels, indexing="ij"), axis=-1).reshape(-1, 3)
    corners = np.array([[255, 255, 254], [1, 0, 0], [254, 255, 255], [128, 127, 128]], dtype=np.uint8)
    rgb = np.concatenate([rgb, corners])
    assert np.array_equal(hsv_to_rgb8(rgb8_to_hsv(rgb)), rgb)
    assert np.array_equal(hsl_to_rgb8(rgb8_to_hsl(rgb)), rgb)


def test_hue_wraps_modulo_360():
    assert np.allclose(hsv_to_rgb((360, 1, 1)), hsv_to_rgb((0, 1, 1)))
    assert np.allclose(hsv_to_rgb((-120, 1, 1)), (0, 0, 1))
    assert np.allclose(hsl_to_rgb((480, 1, 0.5)), (0, 1, 0))


# --- luma ---------------------------------------------------------------------------------

def test_luma_uint8_is_exact_rounding_of_bt601():
    rng = np.random.default_rng(8)
    rgb = rng.integers(0, 256, (500, 3), dtype=np.uint8)
    expected = [int(Fraction(299 * int(r) + 587 * int(g) + 114 * int(b), 1000) + Fraction(1, 2)) for r, g, b in rgb]
    assert luma(rgb).tolist() == expected


def test_luma_agrees_with_pillow_l_within_one():
    rgb = np.random.default_rng(9).integers(0, 256, (40, 50, 3), dtype=np.uint8)
    pil = np.asarray(Image.fromarray(rgb).convert("L")).astype(int)
    assert np.abs(luma(rgb).astype(int) - pil).max() <= 1


def test_luma_float_and_bt709():
    assert np.isclose(luma((1.0, 1.0, 1.0)), 1.0)
    assert np.isclose(luma((0.0, 1.0, 0.0), "bt709"), 0.7152)
    assert luma(np.array([255, 255, 255], dtype=np.uint8), "bt709") == 255
    assert luma(np.array([0, 255, 0], dtype=np.uint8)) == 150  # 0.587 * 255 = 149.685


# --- RGB565 -------------------------------------------------------------------------------

def test_rgb565_widening_worked_values():
    values = np.array([0xF800, 0x07E0, 0x001F, 0x8410, 0x0000, 0xFFFF], dtype=np.uint16)
    assert rgb565_to_rgb888(values).tolist() == [
        [255, 0, 0], [0, 255, 0], [0, 0, 255],
        [132, 130, 132],  # r5=16 -> 10000100, g6=32 -> 10000010, b5=16
        [0, 0, 0], [255, 255, 255],
    ]


def test_rgb565_widening_all_values_by_repeating_bit_strings():
    values = np.arange(65536, dtype=np.uint16)
    wide = rgb565_to_rgb888(values)

    def widen(field: int, bits: int) -> int:
        return int((format(field, f"0{bits}b") * 2)[:8], 2)  # repeat the bit pattern, keep 8 bits

    sample = range(0, 65536, 7)  # every residue of each field occurs
    expected = [[widen(v >> 11, 5), widen((v >> 5) & 63, 6), widen(v & 31, 5)] for v in sample]
    assert wide[::7].tolist() == expected
    assert np.array_equal(rgb888_to_rgb565(wide), values)  # widening keeps the top bits


def test_rgb888_to_rgb565_matches_formula_and_keeps_shape():
    rgb = np.random.default_rng(10).integers(0, 256, (2, 3, 4, 3), dtype=np.uint8)
    r, g, b = (rgb[..., i].astype(np.int64) for i in range(3))
    expected = ((r & 0xF8) << 8) | ((g & 0xFC) << 3) | (b >> 3)
    out = rgb888_to_rgb565(rgb)
    assert out.dtype == np.uint16 and out.shape == (2, 3, 4)
    assert np.array_equal(out, expected)


# --- errors -------------------------------------------------------------------------------

def test_errors():
    with pytest.raises(ConfigError, match=r"shape \(..., 3\), found shape \(2,\)"):
        rgb_to_hsv((1, 0))
    with pytest.raises(ConfigError, match="finite"):
        rgb_to_hsl((np.nan, 0, 0))
    with pytest.raises(ConfigError, match=r"must lie in \[0, 1\], found 1.5 at index \(1,\)"):
        rgb_to_hsv((0, 1.5, 0))
    with pytest.raises(ConfigError, match="saturation/value"):
        hsv_to_rgb((0, -0.1, 1))
    with pytest.raises(ConfigError, match="saturation/lightness"):
        hsl_to_rgb((0, 0.5, 2))
    with pytest.raises(ConfigError, match="uint8 array of shape"):
        rgb8_to_hsv(np.array([1.0, 0.0, 0.0]))
    with pytest.raises(ConfigError, match="unknown luma standard 'ntsc'"):
        luma((1, 1, 1), "ntsc")
    with pytest.raises(ConfigError, match="uint16"):
        rgb565_to_rgb888(np.array([1], dtype=np.int32))
    with pytest.raises(ConfigError, match="numbers"):
        rgb_to_hsv("red")

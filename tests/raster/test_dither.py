"""Tests for pixelpen.raster.dither: Bayer matrices, ordered dither, Floyd–Steinberg vs scalar references, Pillow."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.raster.dither import (
    bayer_matrix,
    floyd_steinberg,
    floyd_steinberg_mono,
    floyd_steinberg_palette,
    floyd_steinberg_reference,
    ordered,
    ordered_mono,
)
from pixelpen.raster.formats import pack, unpack
from pixelpen.raster.palette import Palette

SETTINGS = settings(max_examples=25, deadline=None)


def nearest_level(levels: int):
    """Textbook nearest level of an 8-bit value, written as the 8-bit level value round(k·255/(L−1))."""
    values = [math.floor(Fraction(k * 255, levels - 1) + Fraction(1, 2)) for k in range(levels)]

    def choose(value: int) -> int:
        return min(values, key=lambda v: (abs(v - value), v))

    return choose


def per_channel(levels):
    choosers = [nearest_level(n) for n in levels]
    return lambda colour: tuple(f(v) for f, v in zip(choosers, colour, strict=True))


def brute_palette(palette: Palette):
    colours = palette.colours.tolist()

    def choose(colour):
        distances = [sum((a - b) ** 2 for a, b in zip(colour, c, strict=True)) for c in colours]
        return tuple(colours[distances.index(min(distances))])

    return choose


# --- Bayer matrices ------------------------------------------------------------------------

def test_bayer_matrices_known_values():
    assert bayer_matrix(1).tolist() == [[0]]
    assert bayer_matrix(2).tolist() == [[0, 2], [3, 1]]
    assert bayer_matrix(4).tolist() == [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]]
    m8 = bayer_matrix(8)
    assert m8[0].tolist() == [0, 32, 8, 40, 2, 34, 10, 42]
    assert m8[7].tolist() == [63, 31, 55, 23, 61, 29, 53, 21]


@pytest.mark.parametrize("n", [1, 2, 4, 8, 16, 32, 64])
def test_bayer_matrix_is_a_permutation(n):
    assert sorted(bayer_matrix(n).ravel().tolist()) == list(range(n * n))


@pytest.mark.parametrize("n", [0, 3, 6, 128, True, 2.0])
def test_bayer_matrix_size_errors(n):
    with pytest.raises(ConfigError, match="power of two"):
        bayer_matrix(n)


# --- ordered dither ------------------------------------------------------------------------

def ordered_reference(grey: np.ndarray, levels: int, n: int, origin=(0, 0)) -> np.ndarray:
    """Textbook ordered dither: the level below v, plus one where v's fraction reaches (M + ½)/n²."""
    m = bayer_matrix(n)
    out = np.zeros(grey.shape, dtype=np.int64)
    for y in range(grey.shape[0]):
        for x in range(grey.shape[1]):
            q = Fraction(int(grey[y, x]) * (levels - 1), 255)
            base = math.floor(q)
            threshold = Fraction(2 * int(m[(y + origin[1]) % n, (x + origin[0]) % n]) + 1, 2 * n * n)
            k = base + (1 if q - base >= threshold else 0)
            out[y, x] = math.floor(Fraction(k * 255, levels - 1) + Fraction(1, 2))
    return out


@SETTINGS
@given(seed=st.integers(0, 2**32 - 1), levels=st.integers(2, 17), n=st.sampled_from([2, 4, 8]))
def test_ordered_matches_fraction_reference(seed, levels, n):
    grey = np.random.default_rng(seed).integers(0, 256, (9, 11), dtype=np.uint8)
    assert np.array_equal(ordered(grey, levels, n), ordered_reference(grey, levels, n))


def test_ordered_mono_lights_the_expected_share_of_a_flat_tile():
    # v = 128, 4x4: lit iff 128/255 >= (M + 1/2)/16, i.e. M <= 7.53: the 8 cells with M < 8.
    lit = ordered_mono(np.full((4, 4), 128, dtype=np.uint8), 4)
    assert np.array_equal(lit, bayer_matrix(4) < 8)
    assert not ordered_mono(np.zeros((8, 8), dtype=np.uint8), 8).any()
    assert ordered_mono(np.full((8, 8), 255, dtype=np.uint8), 8).all()


def test_ordered_origin_makes_windows_match_the_frame():
    grey = np.random.default_rng(15).integers(0, 256, (20, 23), dtype=np.uint8)
    whole = ordered(grey, 4, 8)
    assert np.array_equal(ordered(grey[5:, 3:], 4, 8, origin=(3, 5)), whole[5:, 3:])


def test_ordered_rgb565_levels_survive_packing():
    rgb = np.random.default_rng(16).integers(0, 256, (8, 12, 3), dtype=np.uint8)
    dithered = ordered(rgb, "rgb565", 4)
    expected = np.stack([ordered_reference(rgb[..., c], lv, 4) for c, lv in enumerate((32, 64, 32))], axis=-1)
    assert np.array_equal(dithered, expected)
    # The truncating packer recovers the level index k exactly: k = value >> (8 - bits).
    widened = unpack(pack(dithered, "rgb565be"), "rgb565be", 12, 8)
    for c, bits in enumerate((5, 6, 5)):
        level = np.rint(dithered[..., c].astype(int) * ((1 << bits) - 1) / 255).astype(int)
        assert np.array_equal(widened[..., c] >> (8 - bits), level)


def test_ordered_rgb_input_to_mono_uses_luma():
    rgb = np.zeros((4, 4, 3), dtype=np.uint8)
    rgb[..., 1] = 218  # luma = 0.587 * 218 = 127.97 -> 128
    assert np.array_equal(ordered_mono(rgb, 4), bayer_matrix(4) < 8)


# --- Floyd–Steinberg -----------------------------------------------------------------------

def test_floyd_steinberg_hand_worked_2x2():
    # Worked by hand with errors in sixteenths: (0,0) 100 -> 0, err 100; (1,0) 100 + 700/16 = 143 -> 255,
    # err -112; (0,1) 100 + (500 - 336)/16 = 110 -> 0, err 110; (1,1) 100 + (100 - 560 + 770)/16 = 119 -> 0.
    grey = np.full((2, 2), 100, dtype=np.uint8)
    expected = [[0, 255], [0, 0]]
    assert floyd_steinberg_reference(grey, lambda v: (255,) if v[0] >= 128 else (0,)).tolist() == expected
    assert floyd_steinberg(grey, 2).tolist() == expected
    assert floyd_steinberg_mono(grey).astype(int).tolist() == [[0, 1], [0, 0]]


@pytest.mark.parametrize("shape", [(1, 1), (1, 9), (9, 1), (2, 2), (7, 13), (16, 5)])
def test_pillow_mono_equals_reference_with_pillows_threshold(shape):
    grey = np.random.default_rng(sum(shape)).integers(0, 256, shape, dtype=np.uint8)
    reference = floyd_steinberg_reference(grey, lambda v: (255,) if v[0] > 128 else (0,))
    assert np.array_equal(floyd_steinberg_mono(grey), reference == 255)


@SETTINGS
@given(
    h=st.integers(1, 12), w=st.integers(1, 12), levels=st.integers(2, 9), seed=st.integers(0, 2**32 - 1)
)
def test_wavefront_grey_equals_scalar_reference(h, w, levels, seed):
    grey = np.random.default_rng(seed).integers(0, 256, (h, w), dtype=np.uint8)
    reference = floyd_steinberg_reference(grey, lambda v: (nearest_level(levels)(v[0]),))
    assert np.array_equal(floyd_steinberg(grey, levels), reference)


@SETTINGS
@given(h=st.integers(1, 9), w=st.integers(1, 9), seed=st.integers(0, 2**32 - 1))
def test_wavefront_rgb565_equals_scalar_reference(h, w, seed):
    rgb = np.random.default_rng(seed).integers(0, 256, (h, w, 3), dtype=np.uint8)
    reference = floyd_steinberg_reference(rgb, per_channel((32, 64, 32)))
    assert np.array_equal(floyd_steinberg(rgb, "rgb565"), reference)


@SETTINGS
@given(
    h=st.integers(1, 8), w=st.integers(1, 8), seed=st.integers(0, 2**32 - 1), name=st.sampled_from(["ega16", "web216"])
)
def test_palette_dither_equals_scalar_reference(h, w, seed, name):
    palette = Palette.named(name)
    rgb = np.random.default_rng(seed).integers(0, 256, (h, w, 3), dtype=np.uint8)
    reference = floyd_steinberg_reference(rgb, brute_palette(palette))
    assert np.array_equal(palette.lookup(floyd_steinberg_palette(rgb, palette)), reference)


def test_error_diffusion_preserves_mean_intensity():
    flat = np.full((64, 64), 100, dtype=np.uint8)
    for lit in (floyd_steinberg_mono(flat), floyd_steinberg(flat, 2) == 255):
        assert abs(lit.mean() - 100 / 255) < 0.01
    grey4 = floyd_steinberg(flat, 4)
    assert set(np.unique(grey4).tolist()) <= {0, 85, 170, 255}
    assert abs(grey4.mean() - 100) < 1.5


def test_pillow_palette_engine_gives_valid_indices_and_keeps_the_mean():
    palette = Palette.named("grey4")
    flat = np.full((32, 48, 3), 100, dtype=np.uint8)
    idx = floyd_steinberg_palette(flat, palette, engine="pillow")
    assert idx.shape == (32, 48) and idx.max() < len(palette)
    assert abs(palette.lookup(idx)[..., 0].mean() - 100) < 2
    grey_idx = floyd_steinberg_palette(flat[..., 0], palette)
    assert abs(palette.lookup(grey_idx)[..., 0].mean() - 100) < 2


def test_bitmap_and_empty_inputs():
    bitmap = np.array([[True, False], [False, True]])
    assert floyd_steinberg(bitmap, 2).tolist() == [[255, 0], [0, 255]]
    assert floyd_steinberg(np.zeros((0, 4), dtype=np.uint8), 2).shape == (0, 4)
    assert floyd_steinberg_mono(np.zeros((3, 0), dtype=np.uint8)).shape == (3, 0)


# --- errors --------------------------------------------------------------------------------

def test_dither_errors():
    grey = np.zeros((4, 4), dtype=np.uint8)
    with pytest.raises(ConfigError, match="3 level counts given for an image of 1 channel"):
        ordered(grey, (2, 2, 2))
    with pytest.raises(ConfigError, match=r"integers 2..256"):
        floyd_steinberg(grey, 1)
    with pytest.raises(ConfigError, match=r"integers 2..256"):
        ordered(grey, 257)
    with pytest.raises(ConfigError, match="origin must be \\(x, y\\) integers"):
        ordered(grey, 2, 4, origin=(0.5, 0))
    with pytest.raises(ConfigError, match="unknown depth 'rgb555'"):
        ordered(grey, "rgb555")
    with pytest.raises(ConfigError, match="not RGB565 values"):
        ordered(np.zeros((2, 2), dtype=np.uint16))
    with pytest.raises(ConfigError, match="must be a Palette"):
        floyd_steinberg_palette(grey, [(0, 0, 0)])
    with pytest.raises(ConfigError, match="unknown dithering engine 'fast'"):
        floyd_steinberg_palette(grey, Palette.named("mono"), engine="fast")
    with pytest.raises(ConfigError, match="HxWx3 uint8"):
        floyd_steinberg(np.zeros((2, 2, 3), dtype=np.float64))

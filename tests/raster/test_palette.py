"""Tests for pixelpen.raster.palette: fixed palette tables, exact nearest colour, quantisation, errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.raster.palette import NAMED_PALETTES, QUANTIZE_METHODS, Palette, quantize


def brute_nearest(colours: np.ndarray, pixel) -> int:
    """Scalar reference: the first entry with the smallest squared RGB distance."""
    best, best_d = 0, None
    for i, c in enumerate(colours.tolist()):
        d = sum((int(a) - int(b)) ** 2 for a, b in zip(pixel, c, strict=True))
        if best_d is None or d < best_d:
            best, best_d = i, d
    return best


# --- fixed palettes (values from their published tables) -----------------------------------

def test_named_palette_sizes_and_entries():
    sizes = {"mono": 2, "grey4": 4, "grey16": 16, "ega16": 16, "web216": 216, "rgb332": 256, "xterm256": 256}
    assert {name: len(Palette.named(name)) for name in NAMED_PALETTES} == sizes
    assert list(Palette.named("mono")) == [(0, 0, 0), (255, 255, 255)]
    assert list(Palette.named("grey4")) == [(0, 0, 0), (85, 85, 85), (170, 170, 170), (255, 255, 255)]
    assert Palette.named("grey16")[1] == (17, 17, 17)
    ega = Palette.named("ega16")
    assert ega[6] == (0xAA, 0x55, 0x00)   # brown, not dark yellow
    assert ega[9] == (0x55, 0x55, 0xFF)   # light blue
    assert Palette.named("web216")[36 * 5 + 0 + 3] == (255, 0, 153)
    rgb332 = Palette.named("rgb332")
    assert rgb332[0b111_000_00] == (255, 0, 0)
    assert rgb332[0b000_111_00] == (0, 255, 0)
    assert rgb332[0b000_000_11] == (0, 0, 255)
    assert rgb332[0b100_010_01] == (0b10010010, 0b01001001, 0x55)
    xterm = Palette.named("xterm256")
    assert xterm[1] == (205, 0, 0) and xterm[12] == (0x5C, 0x5C, 0xFF)
    assert xterm[16] == (0, 0, 0) and xterm[21] == (0, 0, 255) and xterm[196] == (255, 0, 0)
    assert xterm[231] == (255, 255, 255) and xterm[232] == (8, 8, 8) and xterm[255] == (238, 238, 238)


def test_palette_object_behaviour():
    p = Palette([[1, 2, 3], [4, 5, 6]], name="two")
    assert len(p) == 2 and p[1] == (4, 5, 6) and p == Palette(np.array([[1, 2, 3], [4, 5, 6]]))
    assert hash(p) == hash(Palette([[1, 2, 3], [4, 5, 6]]))
    assert p.to_pillow() == [1, 2, 3, 4, 5, 6]
    assert "two" in repr(p)
    with pytest.raises(ValueError):
        p.colours[0, 0] = 9  # read-only


# --- nearest colour ------------------------------------------------------------------------

@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), name=st.sampled_from(sorted(NAMED_PALETTES)))
def test_nearest_matches_scalar_reference(seed, name):
    palette = Palette.named(name)
    img = np.random.default_rng(seed).integers(0, 256, (4, 5, 3), dtype=np.uint8)
    expected = [[brute_nearest(palette.colours, px) for px in row] for row in img]
    assert palette.nearest(img).tolist() == expected


def test_ties_go_to_the_lowest_index():
    p = Palette([[0, 0, 0], [10, 0, 0], [10, 0, 0]])
    img = np.array([[[10, 0, 0], [5, 0, 0], [6, 0, 0]]], dtype=np.uint8)
    assert p.nearest(img).tolist() == [[1, 0, 1]]


def test_large_images_use_the_table_path_with_the_same_answers():
    rng = np.random.default_rng(11)
    colours = rng.integers(0, 256, (5000, 3), dtype=np.uint8)
    img = colours[rng.integers(0, 5000, (300, 300))]  # 90,000 px > the direct-path limit
    palette = Palette.named("xterm256")
    assert np.array_equal(palette.nearest(img).ravel(), palette.nearest_rows(img.reshape(-1, 3)))
    sample = rng.integers(0, 90000, 200)
    flat = img.reshape(-1, 3)
    assert [brute_nearest(palette.colours, flat[i]) for i in sample] == palette.nearest(img).ravel()[sample].tolist()


def test_grey_images_and_lookup_round_trip():
    palette = Palette.named("grey16")
    grey = (np.arange(16, dtype=np.uint8) * 17).reshape(4, 4)
    idx = palette.nearest(grey)
    assert idx.tolist() == np.arange(16).reshape(4, 4).tolist()
    assert np.array_equal(palette.lookup(idx)[..., 0], grey)
    bitmap = np.array([[True, False]])
    assert Palette.named("mono").nearest(bitmap).tolist() == [[1, 0]]
    ega = Palette.named("ega16")
    img = ega.colours[np.random.default_rng(12).integers(0, 16, (6, 7))]
    assert np.array_equal(ega.lookup(ega.nearest(img)), img)


# --- quantize ------------------------------------------------------------------------------

def few_colour_image() -> np.ndarray:
    colours = np.array([[10, 20, 30], [200, 100, 50], [0, 255, 0], [90, 90, 90]], dtype=np.uint8)
    return colours[np.random.default_rng(13).integers(0, 4, (20, 30))]


@pytest.mark.parametrize("method", QUANTIZE_METHODS)
def test_quantize_reproduces_an_image_with_few_colours(method):
    img = few_colour_image()
    indices, palette = quantize(img, 4, method)
    assert len(palette) <= 4 and indices.dtype == np.uint8
    assert np.array_equal(palette.lookup(indices), img)


def sse(img: np.ndarray, indices: np.ndarray, palette: Palette) -> int:
    return int(((palette.lookup(indices).astype(np.int64) - img) ** 2).sum())


def test_quantize_indices_are_exact_nearest_and_kmeans_does_not_worsen_median_cut():
    yy, xx = np.mgrid[0:48, 0:64]
    img = np.stack([xx * 4, yy * 5, (xx + yy) * 2], axis=-1).astype(np.uint8)
    img = img + np.random.default_rng(14).integers(0, 8, img.shape).astype(np.uint8)
    idx_mc, pal_mc = quantize(img, 8, "mediancut")
    idx_km, pal_km = quantize(img, 8, "kmeans")
    assert np.array_equal(idx_mc, pal_mc.nearest(img))
    assert sse(img, idx_km, pal_km) <= sse(img, idx_mc, pal_mc)
    grey_idx, grey_pal = quantize(img[..., 0], 4)
    assert len(grey_pal) <= 4 and grey_idx.shape == (48, 64)


# --- errors --------------------------------------------------------------------------------

@pytest.mark.parametrize(
    "colours, message",
    [
        (np.zeros((0, 3), dtype=np.uint8), "1..256"),
        (np.zeros((257, 3), dtype=np.uint8), "1..256"),
        (np.zeros((4, 4), dtype=np.uint8), "shape \\(4, 4\\)"),
        (np.array([[0, 0, 300]]), "0..255"),
        (np.array([[0, 0, -1]]), "0..255"),
        (np.array([[0.5, 0, 0]]), "integers"),
    ],
)
def test_bad_palettes(colours, message):
    with pytest.raises(ConfigError, match=message):
        Palette(colours)


def test_other_errors():
    with pytest.raises(ConfigError, match="unknown palette 'vga'"):
        Palette.named("vga")
    p = Palette.named("ega16")
    with pytest.raises(ConfigError, match=r"palette index 16 at \(0, 1\) outside 0..15"):
        p.lookup(np.array([[0, 16]]))
    with pytest.raises(ConfigError, match="must be integers"):
        p.lookup(np.array([0.0]))
    with pytest.raises(ConfigError, match="HxWx3 uint8 \\(RGB\\)"):
        p.nearest(np.zeros((2, 2), dtype=np.float64))
    with pytest.raises(ConfigError, match="shape \\(P, 3\\)"):
        p.nearest_rows(np.zeros((3, 4)))
    img = few_colour_image()
    with pytest.raises(ConfigError, match=r"1..256, found 0"):
        quantize(img, 0)
    with pytest.raises(ConfigError, match=r"1..256, found 257"):
        quantize(img, 257)
    with pytest.raises(ConfigError, match="unknown quantize method 'popularity'"):
        quantize(img, 4, "popularity")
    with pytest.raises(ConfigError, match="empty"):
        quantize(np.zeros((0, 5, 3), dtype=np.uint8), 4)

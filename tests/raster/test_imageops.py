"""Tests for pixelpen.raster.imageops against hand-made references, scalar textbook code and Pillow."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.lib.stride_tricks import sliding_window_view
from PIL import Image

from pixelpen.errors import ConfigError
from pixelpen.raster.imageops import (
    SHARPEN,
    SOBEL_X,
    Layer,
    box_blur,
    box_kernel,
    composite,
    convolve,
    correlate,
    crop,
    edge_detect,
    gaussian_blur,
    gaussian_kernel,
    rotate,
    rotate90,
    scale,
    sharpen,
)

SETTINGS = settings(max_examples=30, deadline=None)


def image(h: int, w: int, c: int | None = None, seed: int = 0) -> np.ndarray:
    shape = (h, w) if c is None else (h, w, c)
    return np.random.default_rng(seed).integers(0, 256, shape, dtype=np.uint8)


def half_up(x) -> np.ndarray:
    return np.floor(np.asarray(x, dtype=np.float64) + 0.5).astype(np.int64)


# --- scale -----------------------------------------------------------------------------------

@SETTINGS
@given(h=st.integers(1, 9), w=st.integers(1, 9), fy=st.integers(1, 4), fx=st.integers(1, 4), seed=st.integers(0, 999))
def test_nearest_integer_upscaling_is_np_repeat(h, w, fy, fx, seed):
    img = image(h, w, 3, seed)
    expected = np.repeat(np.repeat(img, fy, axis=0), fx, axis=1)
    assert np.array_equal(scale(img, (w * fx, h * fy), "nearest"), expected)
    assert np.array_equal(scale(img, (w * fx, h * fy), "area"), expected)  # each output pixel inside one source pixel


@SETTINGS
@given(src=st.tuples(st.integers(1, 30), st.integers(1, 30)), dst=st.tuples(st.integers(1, 30), st.integers(1, 30)))
def test_nearest_equals_pillow_nearest_except_on_exact_ties(src, dst):
    (sw, sh), (dw, dh) = src, dst
    columns = np.tile(np.arange(sw, dtype=np.uint8), (sh, 1))
    rows = np.tile(np.arange(sh, dtype=np.uint8)[:, None], (1, sw))
    for ramp, n_src, n_dst, axis in ((columns, sw, dw, 1), (rows, sh, dh, 0)):
        ours = scale(ramp, dst, "nearest")
        pil = np.asarray(Image.fromarray(ramp).resize(dst, Image.Resampling.NEAREST))
        # A destination centre (d + 1/2)·src/dst exactly on a pixel boundary is a tie: we take the pixel
        # to its right (floor); Pillow's float product may land either side.
        tie = ((2 * np.arange(n_dst) + 1) * n_src) % (2 * n_dst) == 0
        tie = tie[None, :] if axis == 1 else tie[:, None]
        diff = ours.astype(int) - pil
        assert (diff[~np.broadcast_to(tie, diff.shape)] == 0).all()
        assert set(np.unique(diff).tolist()) <= {0, 1}


@pytest.mark.parametrize("factor", [(2, 2), (3, 2), (4, 5)])
def test_area_downscaling_by_integer_factors_is_the_block_mean(factor):
    fx, fy = factor
    img = image(fy * 6, fx * 7, 3, seed=2)
    blocks = img.reshape(6, fy, 7, fx, 3).astype(np.int64)
    expected = half_up(blocks.sum(axis=(1, 3)) / (fx * fy))
    assert np.array_equal(scale(img, (7, 6), "area"), expected)
    pil = np.asarray(Image.fromarray(img).resize((7, 6), Image.Resampling.BOX)).astype(int)
    assert np.abs(scale(img, (7, 6), "area").astype(int) - pil).max() <= 1


def test_area_fractional_coverage_worked_by_hand():
    row = np.array([[0, 30, 60]], dtype=np.uint8)
    # 3 -> 2 pixels: output 0 covers [0, 1.5): (0 + 0.5*30)/1.5 = 10; output 1 covers [1.5, 3): (0.5*30 + 60)/1.5 = 50
    assert scale(row, (2, 1), "area").tolist() == [[10, 50]]


def bilinear_reference(img: np.ndarray, w: int, h: int) -> np.ndarray:
    """Scalar bilinear interpolation, pixel centres aligned, coordinates clamped to the image."""
    src_h, src_w = img.shape
    out = np.zeros((h, w))
    for y in range(h):
        for x in range(w):
            sx = min(max((x + 0.5) * src_w / w - 0.5, 0.0), src_w - 1)
            sy = min(max((y + 0.5) * src_h / h - 0.5, 0.0), src_h - 1)
            x0, y0 = math.floor(sx), math.floor(sy)
            x1, y1 = min(x0 + 1, src_w - 1), min(y0 + 1, src_h - 1)
            ax, ay = sx - x0, sy - y0
            top = img[y0, x0] * (1 - ax) + img[y0, x1] * ax
            bottom = img[y1, x0] * (1 - ax) + img[y1, x1] * ax
            out[y, x] = top * (1 - ay) + bottom * ay
    return out


@pytest.mark.parametrize("src, dst", [((5, 4), (13, 9)), ((8, 8), (3, 5)), ((1, 6), (4, 4)), ((7, 3), (7, 3))])
def test_bilinear_matches_scalar_reference(src, dst):
    img = image(src[1], src[0], seed=3)
    reference = bilinear_reference(img.astype(np.float64), *dst)
    assert np.abs(scale(img, dst, "bilinear").astype(int) - half_up(reference)).max() <= 0
    assert np.allclose(scale(img.astype(np.float64), dst, "bilinear"), reference)


def test_bilinear_upscaling_agrees_with_pillow_within_one():
    img = image(9, 11, 3, seed=4)
    ours = scale(img, (31, 20), "bilinear").astype(int)
    pil = np.asarray(Image.fromarray(img).resize((31, 20), Image.Resampling.BILINEAR)).astype(int)
    assert np.abs(ours - pil).max() <= 1


def test_identity_scaling():
    img = image(6, 5, 3, seed=5)
    for method in ("nearest", "bilinear", "area"):
        assert np.array_equal(scale(img, (5, 6), method), img)


# --- crop / rotate90 / rotate -----------------------------------------------------------------

def test_crop_is_a_copy_of_the_window():
    img = image(6, 8, 3)
    window = crop(img, (2, 1, 5, 4))
    assert np.array_equal(window, img[1:4, 2:5])
    window[...] = 0
    assert img[1:4, 2:5].any()
    assert crop(img, (3, 3, 3, 5)).shape == (2, 0, 3)


def test_rotate90_hand_example_and_cycles():
    img = np.array([[1, 2], [3, 4]], dtype=np.uint8)
    assert rotate90(img, 1).tolist() == [[2, 4], [1, 3]]  # counter-clockwise as displayed
    assert rotate90(img, -1).tolist() == [[3, 1], [4, 2]]
    rect = image(3, 5, 3)
    assert rotate90(rect, 1).shape == (5, 3, 3)
    assert np.array_equal(rotate90(rotate90(rect, 3), 1), rect)
    assert np.array_equal(rotate90(rect, 4), rect)


@SETTINGS
@given(
    h=st.integers(1, 9), w=st.integers(1, 9), k=st.integers(-4, 4), resample=st.sampled_from(["nearest", "bilinear"])
)
def test_rotate_by_quarter_turns_equals_rotate90(h, w, k, resample):
    img = image(h, w, 3, seed=h * 10 + w)
    assert np.array_equal(rotate(img, k * math.pi / 2, resample), rotate90(img, k))


def rotate_reference(img: np.ndarray, angle: float, fill: int) -> tuple[np.ndarray, np.ndarray]:
    """Scalar inverse-mapping rotation (nearest), same size, about the centre, CCW as displayed.

    Also returns where the source point lies on a pixel boundary (a tie either neighbour may win).
    """
    h, w = img.shape
    out = np.full((h, w), fill, dtype=img.dtype)
    tie = np.zeros((h, w), dtype=bool)
    c, s = math.cos(angle), math.sin(angle)
    for y in range(h):
        for x in range(w):
            # offset of the output pixel centre from the centre, in y-up coordinates
            u, v = x + 0.5 - w / 2, -(y + 0.5 - h / 2)
            su, sv = u * c + v * s, -u * s + v * c  # rotate back by -angle
            sx, sy = su + w / 2 - 0.5, -sv + h / 2 - 0.5
            tie[y, x] = any(abs((t + 0.5) - round(t + 0.5)) < 1e-9 for t in (sx, sy))
            ix, iy = math.floor(sx + 0.5), math.floor(sy + 0.5)
            if 0 <= ix < w and 0 <= iy < h:
                out[y, x] = img[iy, ix]
    return out, tie


@pytest.mark.parametrize("degrees", [17, 30, 45, 133, -60])
def test_rotate_nearest_matches_scalar_reference_and_pillow(degrees):
    img = image(23, 31, seed=6)
    ours = rotate(img, math.radians(degrees), "nearest", expand=False, fill=0)
    reference, tie = rotate_reference(img, math.radians(degrees), 0)
    assert np.array_equal(ours[~tie], reference[~tie])
    pil = np.asarray(Image.fromarray(img).rotate(degrees, Image.Resampling.NEAREST, expand=False))
    assert np.array_equal(ours[~tie], pil[~tie])


def test_rotate_bilinear_agrees_with_pillow_inside_the_image():
    img = image(40, 60, seed=7)
    inside = rotate(np.ones((40, 60)), math.radians(30), "bilinear", expand=False) >= 1 - 1e-9
    ours = rotate(img, math.radians(30), "bilinear", expand=False).astype(int)
    pil = np.asarray(Image.fromarray(img).rotate(30, Image.Resampling.BILINEAR)).astype(int)
    assert inside.sum() > 1000
    assert np.abs(ours - pil)[inside].max() <= 1


def test_rotate_expand_size_and_fill():
    img = np.full((10, 20, 3), 200, dtype=np.uint8)
    out = rotate(img, math.radians(45), "nearest", expand=True, fill=(1, 2, 3))
    side = math.ceil((10 + 20) / math.sqrt(2))
    assert out.shape == (side, side, 3)
    assert out[0, 0].tolist() == [1, 2, 3]
    assert out[side // 2, side // 2].tolist() == [200, 200, 200]
    assert np.array_equal(rotate(img, 0.0), img)
    assert rotate(img, math.pi / 6, expand=False).shape == img.shape
    mask = np.ones((4, 6), dtype=bool)
    assert rotate(mask, math.pi / 2).shape == (6, 4)


# --- convolution and filters ----------------------------------------------------------------

def mean_filter_by_hand(img: np.ndarray, r: int) -> np.ndarray:
    padded = np.pad(img.astype(np.int64), r, mode="edge")
    windows = sliding_window_view(padded, (2 * r + 1, 2 * r + 1))
    return half_up(windows.sum(axis=(-1, -2)) / (2 * r + 1) ** 2)


@pytest.mark.parametrize("r", [1, 2, 3])
def test_box_blur_is_the_mean_filter(r):
    img = image(12, 15, seed=8)
    expected = mean_filter_by_hand(img, r)
    assert np.array_equal(box_blur(img, r), expected)
    assert np.array_equal(convolve(img, box_kernel(r)), expected)


def test_box_blur_per_channel_and_float():
    rgb = image(7, 9, 3, seed=9)
    blurred = box_blur(rgb, 1)
    for c in range(3):
        assert np.array_equal(blurred[..., c], mean_filter_by_hand(rgb[..., c], 1))
    values = rgb[..., 0].astype(np.float64)
    assert np.allclose(box_blur(values, 1)[3, 4], values[2:5, 3:6].mean())


def test_gaussian_blur_equals_convolution_with_its_kernel():
    img = image(20, 18, 3, seed=10)
    kernel = gaussian_kernel(1.5)
    assert kernel.shape == (11, 11) and np.isclose(kernel.sum(), 1.0) and np.allclose(kernel, kernel.T)
    assert np.array_equal(gaussian_blur(img, 1.5), convolve(img, kernel))
    assert np.array_equal(gaussian_blur(img, 1.0, radius=1), convolve(img, gaussian_kernel(1.0, 1)))


def test_convolution_flips_and_correlation_does_not():
    img = image(9, 10, seed=11)
    kernel = np.array([[0, 0, 0], [1, 0, 0], [0, 0, 0]], dtype=float)  # "take the left neighbour" as a mask
    shifted = correlate(img, kernel)
    assert np.array_equal(shifted[:, 1:], img[:, :-1])
    assert np.array_equal(convolve(img, kernel)[:, :-1], img[:, 1:])
    asym = np.random.default_rng(12).random((3, 5))
    assert np.array_equal(convolve(img, asym), correlate(img, asym[::-1, ::-1]))


def test_sobel_on_a_ramp_worked_by_hand():
    ramp = np.tile(np.arange(8, dtype=np.float64) * 10, (6, 1))
    # each row contributes (-1, 0, 1)·(x-1, x, x+1)·10 = 20, rows weighted 1, 2, 1 -> 80
    assert np.allclose(correlate(ramp, SOBEL_X)[1:-1, 1:-1], 80.0)
    assert np.allclose(edge_detect(ramp, "sobel")[1:-1, 1:-1], 80.0)


def test_edge_detectors_on_a_step():
    step = np.zeros((5, 6), dtype=np.uint8)
    step[:, 3:] = 100
    sobel = edge_detect(step, "sobel")
    assert sobel[:, [0, 1, 4, 5]].max() == 0 and (sobel[:, 2:4] == 255).all()  # 400 saturates
    assert np.allclose(edge_detect(step.astype(float), "sobel")[:, 2:4], 400.0)
    lap = edge_detect(step, "laplacian")
    assert (lap[:, 2] == 100).all() and (lap[:, 3] == 100).all() and lap[:, [0, 1, 4, 5]].max() == 0
    assert not edge_detect(np.full((4, 4), 77, dtype=np.uint8)).any()


def test_sharpen():
    img = image(8, 8, seed=13)
    assert np.array_equal(sharpen(img), convolve(img, SHARPEN))
    flat = np.full((5, 5), 90, dtype=np.uint8)
    assert np.array_equal(sharpen(flat, 2.5), flat)
    assert np.array_equal(sharpen(img, 0.0), img)


@pytest.mark.parametrize("mode", ["nearest", "reflect", "mirror", "wrap", "constant"])
def test_edge_modes_match_numpy_padding(mode):
    img = image(6, 7, seed=14)
    numpy_names = {
        "nearest": "edge", "reflect": "symmetric", "mirror": "reflect", "wrap": "wrap", "constant": "constant"
    }
    pad_mode = numpy_names[mode]
    padded = np.pad(img.astype(np.int64), 1, mode=pad_mode)
    expected = half_up(sliding_window_view(padded, (3, 3)).sum(axis=(-1, -2)) / 9)
    assert np.array_equal(convolve(img, box_kernel(1), mode=mode), expected)


# --- composite ------------------------------------------------------------------------------

def rgba(h, w, colour, alpha=255):
    out = np.empty((h, w, 4), dtype=np.uint8)
    out[..., :3] = colour
    out[..., 3] = alpha
    return out


def test_composite_z_order_clipping_and_ties():
    red, blue = rgba(4, 4, (255, 0, 0)), rgba(4, 4, (0, 0, 255))
    out = composite([(blue, 2, 2, 5, 1.0), (red, 0, 0, 1, 1.0)], (6, 6))
    assert out[0, 0].tolist() == [255, 0, 0, 255]
    assert out[3, 3].tolist() == [0, 0, 255, 255]  # higher z on top though listed first
    assert out[5, 0].tolist() == [0, 0, 0, 0]       # background shows
    tie = composite([Layer(red), Layer(blue)], (4, 4))
    assert tie[0, 0].tolist() == [0, 0, 255, 255]   # same z: later in the list on top
    off = composite([Layer(red, x=-3, y=2)], (4, 4))
    assert off[2:, :1].tolist() == [[[255, 0, 0, 255]]] * 2 and off[:2].max() == 0 and off[2:, 1:].max() == 0
    assert not composite([Layer(red, x=10)], (4, 4)).any()


def test_composite_opacity_and_alpha_worked_by_hand():
    black = rgba(1, 1, (0, 0, 0))
    white = rgba(1, 1, (255, 255, 255))
    half = composite([Layer(black), Layer(white, z=1, opacity=0.5)], (1, 1))
    assert half[0, 0].tolist() == [128, 128, 128, 255]  # 127.5 rounds half up
    glass = composite([Layer(rgba(1, 1, (255, 0, 0), 128))], (1, 1))
    assert glass[0, 0].tolist() == [255, 0, 0, 128]     # straight alpha out
    assert composite([Layer(white, opacity=0.0)], (1, 1), background=(1, 2, 3, 4))[0, 0].tolist() == [1, 2, 3, 4]
    opaque_rgb = composite([Layer(np.full((2, 2, 3), 9, dtype=np.uint8))], (2, 2))
    assert opaque_rgb[0, 0].tolist() == [9, 9, 9, 255]


def test_composite_matches_pillow_alpha_composite():
    rng = np.random.default_rng(15)
    bottom = rng.integers(0, 256, (9, 11, 4), dtype=np.uint8)
    top = rng.integers(0, 256, (9, 11, 4), dtype=np.uint8)
    ours = composite([Layer(bottom), Layer(top, z=1)], (11, 9)).astype(int)
    pil = np.asarray(Image.alpha_composite(Image.fromarray(bottom, "RGBA"), Image.fromarray(top, "RGBA"))).astype(int)
    assert np.abs(ours - pil).max() <= 1


# --- errors ---------------------------------------------------------------------------------

def test_imageops_errors():
    img = image(4, 5)
    with pytest.raises(ConfigError, match="unknown scaling method 'cubic'"):
        scale(img, (2, 2), "cubic")
    with pytest.raises(ConfigError, match="at least 1x1"):
        scale(img, (0, 2))
    with pytest.raises(ConfigError, match="\\(width, height\\) integers"):
        scale(img, (2.5, 2))
    with pytest.raises(ConfigError, match="found bool"):
        scale(img > 3, (2, 2), "bilinear")
    with pytest.raises(ConfigError, match="empty"):
        scale(np.zeros((0, 3), dtype=np.uint8), (2, 2))
    with pytest.raises(ConfigError, match="does not lie inside the 5x4 image"):
        crop(img, (0, 0, 6, 2))
    with pytest.raises(ConfigError, match="crop box must be four integers"):
        crop(img, (0, 0, 2.5, 2))
    with pytest.raises(ConfigError, match="crop box must be four integers"):
        crop(img, (0, 0, 2))
    with pytest.raises(ConfigError, match="quarter turns"):
        rotate90(img, 1.5)
    with pytest.raises(ConfigError, match="finite"):
        rotate(img, float("nan"))
    with pytest.raises(ConfigError, match="finite"):
        rotate(img, "90")
    with pytest.raises(ConfigError, match="unknown resampling 'cubic'"):
        rotate(img, 1.0, "cubic")
    with pytest.raises(ConfigError, match="fill must be one value or 1 values"):
        rotate(img, 1.0, fill=(1, 2))
    with pytest.raises(ConfigError, match=r"0..255"):
        rotate(img, 1.0, fill=300)
    with pytest.raises(ConfigError, match="odd height and width"):
        convolve(img, np.ones((2, 3)))
    with pytest.raises(ConfigError, match="odd height and width"):
        convolve(img, np.ones(3))
    with pytest.raises(ConfigError, match="finite"):
        convolve(img, np.full((3, 3), np.nan))
    with pytest.raises(ConfigError, match="unknown edge mode 'clamp'"):
        convolve(img, np.ones((3, 3)), mode="clamp")
    with pytest.raises(ConfigError, match="HxW or HxWxC uint8, float image, found int64"):
        box_blur(img.astype(np.int64), 1)
    with pytest.raises(ConfigError, match="non-negative integer"):
        box_blur(img, -1)
    with pytest.raises(ConfigError, match="positive number"):
        gaussian_blur(img, 0)
    with pytest.raises(ConfigError, match="unknown edge detector 'canny'"):
        edge_detect(img, "canny")
    with pytest.raises(ConfigError, match="layer 0: needs an HxWx4"):
        composite([Layer(np.zeros((2, 2, 4)))], (2, 2))
    with pytest.raises(ConfigError, match="layer 1: opacity must lie in \\[0, 1\\]"):
        composite([Layer(rgba(1, 1, 0)), Layer(rgba(1, 1, 0), opacity=1.5)], (2, 2))
    with pytest.raises(ConfigError, match="layer 0: x must be an integer"):
        composite([Layer(rgba(1, 1, 0), x=0.5)], (2, 2))
    with pytest.raises(ConfigError, match="layer 0: give a Layer or \\(image, x, y, z, opacity\\)"):
        composite([(rgba(1, 1, 0), 0, 0, 0, 1.0, "extra")], (2, 2))
    with pytest.raises(ConfigError, match="layer 0: z must be a finite number"):
        composite([Layer(rgba(1, 1, 0), z="top")], (2, 2))
    with pytest.raises(ConfigError, match="background"):
        composite([], (2, 2), background=(0, 0, 0))

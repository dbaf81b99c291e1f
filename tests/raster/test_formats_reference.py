"""The vectorised converters against scalar references written from the format definitions, on arbitrary views.

``rgb888_to_rgb565`` against ``r>>3<<11 | g>>2<<5 | b>>3`` per pixel; ``pack`` for every format and every image
kind against a per-pixel transcription of the packer it replaced (the module doc's layouts), on random shapes,
strides (steps, reversed axes, transposed channel planes), regions and values.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError
from pixelpen.raster.colour import rgb888_to_rgb565
from pixelpen.raster.formats import FORMATS, pack

SETTINGS = settings(max_examples=60, deadline=None)


def ref_rgb565(r: int, g: int, b: int) -> int:
    """RGB565 by the definition: the top 5, 6 and 5 bits of R, G and B in RRRRRGGG GGGBBBBB."""
    return (r >> 3) << 11 | (g >> 2) << 5 | (b >> 3)


def ref_rgb(pixel: object, kind: str) -> tuple[int, int, int]:
    """One pixel of an rgb, grey or bitmap image as (R, G, B) bytes (bitmap: 0 or 255 grey)."""
    if kind == "rgb":
        r, g, b = (int(c) for c in pixel)  # type: ignore[attr-defined]
        return r, g, b
    v = int(pixel) if kind == "grey" else 255 * (int(pixel) != 0)  # type: ignore[call-overload]
    return v, v, v


def ref_lit(pixel: object, kind: str) -> int:
    """1 iff a mono format lights the pixel: bitmap nonzero, grey >= 128, RGB 299R + 587G + 114B >= 128000."""
    if kind == "bitmap":
        return int(int(pixel) != 0)  # type: ignore[call-overload]
    if kind == "grey":
        return int(int(pixel) >= 128)  # type: ignore[call-overload]
    r, g, b = (int(c) for c in pixel)  # type: ignore[attr-defined]
    return int(299 * r + 587 * g + 114 * b >= 128000)


def ref_pack(img: np.ndarray, kind: str, fmt: str) -> bytes:
    """``img`` (one window) packed pixel by pixel in Python from the layouts of the formats module doc."""
    h, w = img.shape[:2]
    rows = img.tolist()
    out = bytearray()
    if fmt == "mono-pages":
        for page in range(-(-h // 8)):
            for x in range(w):
                out.append(sum(ref_lit(rows[8 * page + k][x], kind) << k for k in range(8) if 8 * page + k < h))
        return bytes(out)
    if fmt == "mono-rows":
        for y in range(h):
            for byte in range(-(-w // 8)):
                out.append(sum(ref_lit(rows[y][8 * byte + i], kind) << (7 - i)
                               for i in range(8) if 8 * byte + i < w))
        return bytes(out)
    for y in range(h):
        for x in range(w):
            if fmt in ("rgb565be", "rgb565le"):
                v = rows[y][x] if kind == "rgb565" else ref_rgb565(*ref_rgb(rows[y][x], kind))
                pair = [v >> 8, v & 0xFF]
                out += bytes(pair if fmt == "rgb565be" else pair[::-1])
                continue
            r, g, b = ref_rgb(rows[y][x], kind)
            out += {
                "rgb666": bytes([r & 0xFC, g & 0xFC, b & 0xFC]),
                "rgb888": bytes([r, g, b]),
                "bgr888": bytes([b, g, r]),
                "xrgb8888": bytes([b, g, r, 0xFF]),
            }[fmt]
    return bytes(out)


@st.composite
def views(draw: st.DrawFn, kind: str) -> np.ndarray:
    """A random image of ``kind`` as a view of a larger array: random steps, reversed axes, or channel planes."""
    h, w = draw(st.integers(0, 19)), draw(st.integers(0, 19))
    sy, sx = draw(st.integers(1, 3)), draw(st.integers(1, 3))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    planar = kind == "rgb" and draw(st.booleans())
    if kind == "rgb":
        base = rng.integers(0, 256, (3, h * sy, w * sx) if planar else (h * sy, w * sx, 3), dtype=np.uint8)
        base = base.transpose(1, 2, 0) if planar else base  # channel stride h*w, not 1
    elif kind == "grey":
        base = rng.integers(0, 256, (h * sy, w * sx), dtype=np.uint8)
    elif kind == "rgb565":
        base = rng.integers(0, 65536, (h * sy, w * sx), dtype=np.uint16)
    else:
        dtype = draw(st.sampled_from([np.bool_, np.int32, np.uint32, np.int8]))
        base = (rng.random((h * sy, w * sx)) < 0.5).astype(dtype)
    view = base[::sy, ::sx]
    if draw(st.booleans()):
        view = view[::-1]
    if draw(st.booleans()):
        view = view[:, ::-1]
    return view


@SETTINGS
@given(img=views("rgb"))
def test_rgb888_to_rgb565_equals_the_definition_on_any_view(img):
    expected = np.array([[ref_rgb565(*p) for p in row] for row in img.tolist()], dtype=np.uint16)
    got = rgb888_to_rgb565(img)
    assert got.dtype == np.uint16 and got.shape == img.shape[:2]
    assert np.array_equal(got, expected.reshape(img.shape[:2]))


@SETTINGS
@given(shape=st.lists(st.integers(0, 5), min_size=0, max_size=3), seed=st.integers(0, 2**32 - 1))
def test_rgb888_to_rgb565_any_leading_shape(shape, seed):
    rgb = np.random.default_rng(seed).integers(0, 256, (*shape, 3), dtype=np.uint8)
    expected = np.array([ref_rgb565(*p) for p in rgb.reshape(-1, 3).tolist()], dtype=np.uint16).reshape(shape)
    got = rgb888_to_rgb565(rgb)
    assert got.shape == tuple(shape) and np.array_equal(got, expected)


def test_rgb888_to_rgb565_crosses_its_chunks():
    rgb = np.random.default_rng(5).integers(0, 256, (700, 130, 3), dtype=np.uint8)[::-1, 1:]
    flat = rgb.reshape(-1, 3).astype(np.uint32)
    expected = (flat[:, 0] >> 3) << 11 | (flat[:, 1] >> 2) << 5 | flat[:, 2] >> 3
    assert np.array_equal(rgb888_to_rgb565(rgb), expected.reshape(rgb.shape[:2]))


kinds = st.sampled_from(["rgb", "grey", "bitmap", "rgb565"])


@settings(max_examples=150, deadline=None)
@given(data=st.data(), kind=kinds, fmt=st.sampled_from(sorted(FORMATS)))
def test_pack_equals_the_scalar_reference(data, kind, fmt):
    img = data.draw(views(kind))
    h, w = img.shape[:2]
    if data.draw(st.booleans()):
        x0, x1 = sorted(data.draw(st.lists(st.integers(0, w), min_size=2, max_size=2)))
        y0, y1 = sorted(data.draw(st.lists(st.integers(0, h), min_size=2, max_size=2)))
        region: tuple[int, int, int, int] | None = (x0, y0, x1, y1)
        if fmt == "mono-pages":
            y0, y1 = y0 // 8 * 8, min(-(-y1 // 8) * 8, h)
        window = img[y0:y1, x0:x1]
    else:
        region, window = None, img
    if kind == "rgb565" and fmt not in ("rgb565be", "rgb565le"):
        with pytest.raises(ConfigError, match="RGB565"):
            pack(img, fmt, region)
        return
    assert pack(img, fmt, region) == ref_pack(window, kind, fmt)
    assert pack(img, FORMATS[fmt], region) == pack(img.copy(), fmt, region)

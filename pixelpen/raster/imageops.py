"""Image operations on numpy arrays: scaling, cropping, rotation, convolution filters, layer compositing.

Images are HxW or HxWxC arrays. uint8 images are computed in float64 and rounded half up (with a
1e-9 guard so that values which are exactly k + ½ in real arithmetic round the same way whatever
the float error) and clipped to 0..255; float32/float64 images are returned unrounded, unclipped.
Geometric operations that only move pixels (``crop``, ``rotate90``, nearest ``scale``/``rotate``)
also take bool images. Coordinates: x to the right, y down, pixel (x, y) covers [x, x+1) x [y, y+1),
its centre at (x + ½, y + ½); boxes are half-open ``(x0, y0, x1, y1)``; sizes are (width, height).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy import ndimage, sparse

from pixelpen.errors import ConfigError

EDGE_MODES = ("nearest", "reflect", "mirror", "wrap", "constant")
"""Edge handling for filters (scipy.ndimage names): nearest repeats the edge pixel (default); reflect
mirrors including the edge pixel (d c b a | a b c d); mirror excludes it (d c b | a b c d); wrap tiles;
constant pads with ``cval``."""

SHARPEN = np.array([[0, -1, 0], [-1, 5, -1], [0, -1, 0]], dtype=np.float64)
"""The classic 3x3 sharpening kernel: identity plus the 4-neighbour Laplacian."""
LAPLACIAN = np.array([[0, 1, 0], [1, -4, 1], [0, 1, 0]], dtype=np.float64)
"""4-neighbour Laplacian."""
SOBEL_X = np.array([[-1, 0, 1], [-2, 0, 2], [-1, 0, 1]], dtype=np.float64)
"""Sobel horizontal-gradient mask, as a correlation mask: ``correlate(img, SOBEL_X)`` is +∂/∂x."""
SOBEL_Y = SOBEL_X.T.copy()
"""Sobel vertical-gradient mask (y down), as a correlation mask."""

_ROUND_GUARD = 1e-9


def _image(img: ArrayLike, what: str, allow_bool: bool = False) -> np.ndarray:
    """Validate an HxW or HxWxC image of uint8 or float (or bool when ``allow_bool``)."""
    arr = np.asarray(img)
    allowed = arr.dtype == np.uint8 or arr.dtype.kind == "f" or (allow_bool and arr.dtype == np.bool_)
    if arr.ndim not in (2, 3) or not allowed:
        kinds = "uint8, float" + (" or bool" if allow_bool else "")
        raise ConfigError(f"{what} needs an HxW or HxWxC {kinds} image, found {arr.dtype} with shape {arr.shape}")
    return arr


def _finish(values: np.ndarray, dtype: np.dtype) -> np.ndarray:
    """Float results back to the input dtype: uint8 rounded half up and clipped; floats as they are."""
    if dtype == np.uint8:
        return np.clip(np.floor(values + (0.5 + _ROUND_GUARD)), 0, 255).astype(np.uint8)
    return values.astype(dtype, copy=False)


def _integers(values: Sequence[int], count: int, what: str) -> tuple[int, ...]:
    """``count`` integers (floats with a fractional part are refused), else a ConfigError naming ``what``."""
    try:
        out = tuple(int(v) for v in values)
        exact = len(out) == count and not any(isinstance(v, bool) or int(v) != v for v in values)
    except (TypeError, ValueError, OverflowError):
        exact = False
    if not exact:
        raise ConfigError(f"{what}, found {values!r}")
    return out


def _size(size: Sequence[int], what: str) -> tuple[int, int]:
    """A (width, height) pair of positive integers."""
    w, h = _integers(size, 2, f"{what} must be (width, height) integers")
    if w < 1 or h < 1:
        raise ConfigError(f"{what} must be at least 1x1, found {w}x{h}")
    return w, h


def crop(img: ArrayLike, box: Sequence[int]) -> np.ndarray:
    """A copy of the half-open window (x0, y0, x1, y1), which must lie inside the image."""
    arr = _image(img, "crop", allow_bool=True)
    h, w = arr.shape[:2]
    x0, y0, x1, y1 = _integers(box, 4, "a crop box must be four integers (x0, y0, x1, y1)")
    if not (0 <= x0 <= x1 <= w and 0 <= y0 <= y1 <= h):
        raise ConfigError(f"crop box {tuple(box)!r} (half-open) does not lie inside the {w}x{h} image")
    return arr[y0:y1, x0:x1].copy()


def rotate90(img: ArrayLike, k: int = 1) -> np.ndarray:
    """Rotate by k quarter turns counter-clockwise as displayed (y down); exact, any integer k."""
    arr = _image(img, "rotate90", allow_bool=True)
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)):
        raise ConfigError(f"rotate90 takes an integer number of quarter turns, found {k!r}")
    return np.ascontiguousarray(np.rot90(arr, int(k) % 4, axes=(0, 1)))


def _nearest_indices(src: int, dst: int) -> np.ndarray:
    """Source index of each destination pixel centre: floor((d + ½)·src/dst), in exact integers."""
    return ((2 * np.arange(dst) + 1) * src) // (2 * dst)


def _axis_weights(src: int, dst: int, method: str) -> sparse.csr_matrix:
    """(dst, src) resampling matrix along one axis, rows summing to 1.

    bilinear: pixel centres aligned (s = (d + ½)·src/dst − ½), clamped at the edges;
    area: each destination pixel averages the source interval [d·src/dst, (d+1)·src/dst) by overlap.
    """
    d = np.arange(dst)
    if method == "bilinear":
        s = np.clip((d + 0.5) * src / dst - 0.5, 0, src - 1)
        i0 = np.floor(s).astype(np.int64)
        i1 = np.minimum(i0 + 1, src - 1)
        f = s - i0
        rows = np.concatenate([d, d])
        cols = np.concatenate([i0, i1])
        vals = np.concatenate([1.0 - f, f])
    else:  # area: work in units of 1/dst so every boundary is an integer
        span = -(-src // dst) + 1
        first = (d * src) // dst
        cols = first[:, None] + np.arange(span)[None, :]
        lo = np.maximum(d[:, None] * src, cols * dst)
        hi = np.minimum((d[:, None] + 1) * src, (cols + 1) * dst)
        overlap = np.maximum(hi - lo, 0)
        keep = (overlap > 0) & (cols < src)
        rows = np.broadcast_to(d[:, None], cols.shape)[keep]
        vals = overlap[keep] / src
        cols = cols[keep]
    return sparse.csr_matrix((vals, (rows, cols)), shape=(dst, src))


def _apply_axis(values: np.ndarray, weights: sparse.csr_matrix, axis: int) -> np.ndarray:
    """Resample float ``values`` along axis 0 or 1 with a (dst, src) weight matrix."""
    moved = np.moveaxis(values, axis, 0)
    flat = moved.reshape(moved.shape[0], -1)
    out = np.asarray(weights @ flat).reshape((weights.shape[0], *moved.shape[1:]))
    return np.moveaxis(out, 0, axis)


def scale(img: ArrayLike, size: Sequence[int], method: str = "nearest") -> np.ndarray:
    """Resize to size = (width, height).

    nearest: each output pixel centre takes the source pixel under it (integer factors ==
    np.repeat); bilinear: interpolation between the four nearest source centres, centres aligned,
    edges clamped (aliases when shrinking a lot); area: exact area-weighted average of the source
    region each output pixel covers (box filter; the right choice for shrinking).
    """
    w, h = _size(size, "scale size")
    if method not in ("nearest", "bilinear", "area"):
        raise ConfigError(f"unknown scaling method {method!r}: use nearest, bilinear or area")
    arr = _image(img, "scale", allow_bool=method == "nearest")
    src_h, src_w = arr.shape[:2]
    if src_h == 0 or src_w == 0:
        raise ConfigError(f"cannot scale an empty {src_w}x{src_h} image")
    if method == "nearest":
        return np.take(np.take(arr, _nearest_indices(src_h, h), axis=0), _nearest_indices(src_w, w), axis=1)
    values = arr.astype(np.float64)
    values = _apply_axis(values, _axis_weights(src_h, h, method), 0)
    values = _apply_axis(values, _axis_weights(src_w, w, method), 1)
    return _finish(values, arr.dtype)


def _snap(v: float) -> float:
    """cos/sin values within 1e-12 of -1, 0 or 1 made exact, so quarter turns map centres onto centres."""
    r = round(v)
    return float(r) if abs(v - r) < 1e-12 else v


def _fill_values(fill: float | Sequence[float], channels: int, dtype: np.dtype) -> np.ndarray:
    """The fill colour as one value per channel."""
    values = np.atleast_1d(np.asarray(fill, dtype=np.float64))
    if values.ndim != 1 or values.size not in (1, channels):
        raise ConfigError(f"fill must be one value or {channels} values, found {fill!r}")
    if dtype == np.uint8 and ((values < 0) | (values > 255)).any():
        raise ConfigError(f"fill for a uint8 image must lie in 0..255, found {fill!r}")
    return np.broadcast_to(values, (channels,))


def rotate(
    img: ArrayLike,
    angle: float,
    resample: str = "nearest",
    expand: bool = True,
    fill: float | Sequence[float] = 0,
) -> np.ndarray:
    """Rotate counter-clockwise as displayed by ``angle`` radians about the image centre.

    Inverse mapping: each output pixel centre is rotated back into the source and sampled there
    (nearest: the pixel containing it; bilinear: the four nearest centres, taps outside the image
    take ``fill``). ``expand`` grows the output to hold the whole rotated image (its size is
    ceil(|W cos| + |H sin|) by ceil(|W sin| + |H cos|)); otherwise the size is kept. Points that
    fall outside the source are ``fill`` (a value, or one per channel). Quarter turns equal
    :func:`rotate90` exactly.
    """
    if resample not in ("nearest", "bilinear"):
        raise ConfigError(f"unknown resampling {resample!r}: use nearest or bilinear")
    arr = _image(img, "rotate", allow_bool=resample == "nearest")
    number = isinstance(angle, (int, float, np.integer, np.floating)) and not isinstance(angle, bool)
    if not number or not math.isfinite(angle):
        raise ConfigError(f"rotation angle must be a finite number of radians, found {angle!r}")
    c, s = _snap(math.cos(angle)), _snap(math.sin(angle))
    src_h, src_w = arr.shape[:2]
    if expand:
        out_w = max(1, math.ceil(abs(src_w * c) + abs(src_h * s) - 1e-9))
        out_h = max(1, math.ceil(abs(src_w * s) + abs(src_h * c) - 1e-9))
    else:
        out_w, out_h = src_w, src_h
    channels = arr.shape[2] if arr.ndim == 3 else 1
    pixels = arr.reshape(src_h, src_w, channels)
    fill_values = _fill_values(fill, channels, arr.dtype)
    dx = (np.arange(out_w) + 0.5 - out_w / 2)[None, :]
    dy = (np.arange(out_h) + 0.5 - out_h / 2)[:, None]
    # Visual CCW on a y-down raster; the inverse rotation takes output offsets back to the source.
    sx = dx * c - dy * s + src_w / 2 - 0.5
    sy = dx * s + dy * c + src_h / 2 - 0.5
    if resample == "nearest":
        ix = np.floor(sx + 0.5).astype(np.int64)
        iy = np.floor(sy + 0.5).astype(np.int64)
        inside = (ix >= 0) & (ix < src_w) & (iy >= 0) & (iy < src_h)
        out = np.empty((out_h, out_w, channels), dtype=arr.dtype)
        out[...] = fill_values.astype(arr.dtype)
        out[inside] = pixels[iy[inside], ix[inside]]
    else:
        x0 = np.floor(sx).astype(np.int64)
        y0 = np.floor(sy).astype(np.int64)
        fx = (sx - x0)[..., None]
        fy = (sy - y0)[..., None]
        padded = np.empty((src_h + 2, src_w + 2, channels), dtype=np.float64)
        padded[...] = fill_values
        padded[1:-1, 1:-1] = pixels
        xs0, ys0 = np.clip(x0 + 1, 0, src_w + 1), np.clip(y0 + 1, 0, src_h + 1)
        xs1, ys1 = np.clip(x0 + 2, 0, src_w + 1), np.clip(y0 + 2, 0, src_h + 1)
        top = padded[ys0, xs0] * (1 - fx) + padded[ys0, xs1] * fx
        bottom = padded[ys1, xs0] * (1 - fx) + padded[ys1, xs1] * fx
        out = _finish(top * (1 - fy) + bottom * fy, arr.dtype)
    return out if arr.ndim == 3 else out[..., 0]


def _filter(img: ArrayLike, kernel: ArrayLike, mode: str, cval: float, flip: bool, what: str) -> np.ndarray:
    """Correlate (or convolve, ``flip``) each channel with a 2-D kernel, returning float64."""
    arr = _image(img, what)
    k = np.asarray(kernel, dtype=np.float64)
    if k.ndim != 2 or k.shape[0] % 2 == 0 or k.shape[1] % 2 == 0:
        raise ConfigError(f"a kernel must be a 2-D array of odd height and width, found shape {k.shape}")
    if not np.isfinite(k).all():
        raise ConfigError("a kernel must hold finite numbers")
    if mode not in EDGE_MODES:
        raise ConfigError(f"unknown edge mode {mode!r}: use one of {', '.join(EDGE_MODES)}")
    values = arr.astype(np.float64)
    weights = k if arr.ndim == 2 else k[:, :, None]
    run = ndimage.convolve if flip else ndimage.correlate
    return run(values, weights, mode=mode, cval=cval)


def convolve(img: ArrayLike, kernel: ArrayLike, mode: str = "nearest", cval: float = 0.0) -> np.ndarray:
    """2-D convolution of each channel (kernel flipped, odd-sized, centred); edges per ``mode`` (:data:`EDGE_MODES`)."""
    arr = np.asarray(img)
    return _finish(_filter(arr, kernel, mode, cval, True, "convolve"), arr.dtype)


def correlate(img: ArrayLike, kernel: ArrayLike, mode: str = "nearest", cval: float = 0.0) -> np.ndarray:
    """2-D correlation of each channel (kernel not flipped: a mask laid over each pixel); edges per ``mode``."""
    arr = np.asarray(img)
    return _finish(_filter(arr, kernel, mode, cval, False, "correlate"), arr.dtype)


def box_kernel(radius: int) -> np.ndarray:
    """The (2r+1) x (2r+1) mean filter kernel."""
    if isinstance(radius, bool) or not isinstance(radius, (int, np.integer)) or radius < 0:
        raise ConfigError(f"a box radius must be a non-negative integer, found {radius!r}")
    n = 2 * int(radius) + 1
    return np.full((n, n), 1.0 / (n * n))


def _gaussian_1d(sigma: float, radius: int | None) -> np.ndarray:
    """Sampled, normalised 1-D Gaussian of ``sigma`` pixels over [-radius, radius] (default ceil(3σ))."""
    if not (isinstance(sigma, (int, float, np.floating, np.integer)) and math.isfinite(sigma) and sigma > 0):
        raise ConfigError(f"gaussian sigma must be a positive number of pixels, found {sigma!r}")
    r = math.ceil(3 * sigma) if radius is None else radius
    if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r < 0:
        raise ConfigError(f"gaussian radius must be a non-negative integer, found {radius!r}")
    x = np.arange(-r, r + 1, dtype=np.float64)
    g = np.exp(-(x * x) / (2.0 * sigma * sigma))
    return g / g.sum()


def gaussian_kernel(sigma: float, radius: int | None = None) -> np.ndarray:
    """2-D Gaussian kernel: outer product of the sampled, normalised 1-D Gaussian (radius ceil(3σ) by default)."""
    g = _gaussian_1d(sigma, radius)
    return np.outer(g, g)


def box_blur(img: ArrayLike, radius: int, mode: str = "nearest") -> np.ndarray:
    """Mean over the (2r+1)² neighbourhood (separable, equal to ``convolve(img, box_kernel(r))``)."""
    arr = _image(img, "box_blur")
    n = box_kernel(radius).shape[0]
    if mode not in EDGE_MODES:
        raise ConfigError(f"unknown edge mode {mode!r}: use one of {', '.join(EDGE_MODES)}")
    values = ndimage.uniform_filter(arr.astype(np.float64), size=n, mode=mode, axes=(0, 1))
    return _finish(values, arr.dtype)


def gaussian_blur(img: ArrayLike, sigma: float, radius: int | None = None, mode: str = "nearest") -> np.ndarray:
    """Gaussian blur (separable, equal to ``convolve(img, gaussian_kernel(sigma, radius))``)."""
    arr = _image(img, "gaussian_blur")
    g = _gaussian_1d(sigma, radius)
    if mode not in EDGE_MODES:
        raise ConfigError(f"unknown edge mode {mode!r}: use one of {', '.join(EDGE_MODES)}")
    values = ndimage.correlate1d(arr.astype(np.float64), g, axis=0, mode=mode)
    values = ndimage.correlate1d(values, g, axis=1, mode=mode)
    return _finish(values, arr.dtype)


def sharpen(img: ArrayLike, amount: float = 1.0, mode: str = "nearest") -> np.ndarray:
    """Laplacian sharpening: img − amount·∇²img; amount 1 is the classic kernel :data:`SHARPEN`."""
    if not (isinstance(amount, (int, float, np.integer, np.floating)) and math.isfinite(amount)):
        raise ConfigError(f"sharpen amount must be a finite number, found {amount!r}")
    identity = np.zeros((3, 3))
    identity[1, 1] = 1.0
    return convolve(img, identity - amount * LAPLACIAN, mode)


def edge_detect(img: ArrayLike, method: str = "sobel", mode: str = "nearest") -> np.ndarray:
    """Edge strength per channel: "sobel" gradient magnitude sqrt(Gx² + Gy²) or "laplacian" |∇²img|.

    uint8 results saturate at 255.
    """
    arr = np.asarray(img)
    if method == "sobel":
        gx = _filter(arr, SOBEL_X, mode, 0.0, False, "edge_detect")
        gy = _filter(arr, SOBEL_Y, mode, 0.0, False, "edge_detect")
        return _finish(np.hypot(gx, gy), arr.dtype)
    if method == "laplacian":
        return _finish(np.abs(_filter(arr, LAPLACIAN, mode, 0.0, False, "edge_detect")), arr.dtype)
    raise ConfigError(f"unknown edge detector {method!r}: use sobel or laplacian")


@dataclass(frozen=True, eq=False)
class Layer:
    """One image to composite: RGBA (or opaque RGB) uint8 pixels, top-left at (x, y), stacking order z, opacity 0..1."""

    image: np.ndarray
    x: int = 0
    y: int = 0
    z: float = 0
    opacity: float = 1.0


def _layer(item: Layer | Sequence[object], position: int) -> tuple[Layer, np.ndarray]:
    """A validated Layer and its pixels as HxWx4 float64 premultiplied RGBA in 0..1."""
    try:
        layer = item if isinstance(item, Layer) else Layer(*item)  # type: ignore[arg-type]
    except TypeError:
        raise ConfigError(f"layer {position}: give a Layer or (image, x, y, z, opacity), found {item!r}") from None
    arr = np.asarray(layer.image)
    if arr.dtype != np.uint8 or arr.ndim != 3 or arr.shape[2] not in (3, 4):
        raise ConfigError(f"layer {position}: needs an HxWx4 (RGBA) or HxWx3 (RGB) uint8 image, "
                          f"found {arr.dtype} with shape {arr.shape}")
    if not (isinstance(layer.opacity, (int, float)) and 0.0 <= layer.opacity <= 1.0):
        raise ConfigError(f"layer {position}: opacity must lie in [0, 1], found {layer.opacity!r}")
    for name in ("x", "y"):
        value = getattr(layer, name)
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise ConfigError(f"layer {position}: {name} must be an integer pixel position, found {value!r}")
    if not isinstance(layer.z, (int, float, np.integer, np.floating)) or not math.isfinite(layer.z):
        raise ConfigError(f"layer {position}: z must be a finite number, found {layer.z!r}")
    alpha = (arr[..., 3] / 255.0 if arr.shape[2] == 4 else np.ones(arr.shape[:2])) * layer.opacity
    rgba = np.empty((*arr.shape[:2], 4))
    rgba[..., :3] = arr[..., :3] / 255.0 * alpha[..., None]
    rgba[..., 3] = alpha
    return layer, rgba


def composite(
    layers: Iterable[Layer | Sequence[object]],
    size: Sequence[int],
    background: Sequence[int] = (0, 0, 0, 0),
) -> np.ndarray:
    """Porter–Duff "over" of the layers in z order (ties: list order) onto a background; HxWx4 uint8 RGBA.

    Layers are straight-alpha RGBA uint8 (RGB is opaque), given as :class:`Layer` or tuples
    (image, x, y, z, opacity); each is clipped to the canvas of size (width, height). Works in
    premultiplied float: P = αs·Cs + (1 − αs)·P, A = αs + (1 − αs)·A, with αs = alpha·opacity;
    the result is straight alpha, colour P/A (0 where A = 0), rounded half up.
    """
    w, h = _size(size, "composite size")
    bg = np.asarray(background)
    if bg.shape != (4,) or bg.dtype.kind not in "iu" or (bg < 0).any() or (bg > 255).any():
        raise ConfigError(f"background must be (r, g, b, a) integers 0..255, found {background!r}")
    acc = np.empty((h, w, 4))
    acc[..., 3] = bg[3] / 255.0
    acc[..., :3] = bg[:3] / 255.0 * acc[..., 3:4]
    prepared = [_layer(item, i) for i, item in enumerate(layers)]
    for layer, rgba in sorted(prepared, key=lambda pair: pair[0].z):
        lh, lw = rgba.shape[:2]
        x0, y0 = max(layer.x, 0), max(layer.y, 0)
        x1, y1 = min(layer.x + lw, w), min(layer.y + lh, h)
        if x0 >= x1 or y0 >= y1:
            continue
        src = rgba[y0 - layer.y:y1 - layer.y, x0 - layer.x:x1 - layer.x]
        dst = acc[y0:y1, x0:x1]
        dst *= 1.0 - src[..., 3:4]
        dst += src
    alpha = acc[..., 3:4]
    colour = np.divide(acc[..., :3], alpha, out=np.zeros((h, w, 3)), where=alpha > 0)
    return _finish(np.concatenate([colour, alpha], axis=2) * 255.0, np.dtype(np.uint8))

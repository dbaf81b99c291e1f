"""2D homogeneous transforms: 3x3 float64 matrices acting on column vectors [x, y, 1] (Hearn & Baker ch. 5)."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from pixelpen.errors import InvalidArgument, InvalidArgumentType

ArrayLike = np.ndarray | Sequence[Any]

SINGULAR_RATIO = 1e-12
"""A matrix whose :func:`singular_ratio` is below this is singular: its inverse would be rounding error."""


def as_points(points: ArrayLike, name: str = "points", *, min_rows: int = 0, dim: int = 2) -> tuple[np.ndarray, bool]:
    """Validate an (N, dim) array or a single (dim,) point of finite numbers; return (float64 (N, dim), was_single)."""
    axes = "(x, y)" if dim == 2 else "(x, y, z)" if dim == 3 else f"({dim} coordinates)"
    try:
        arr = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"{name} must be an (N, {dim}) array of numbers: {exc}") from None
    single = arr.shape == (dim,)
    if single:
        arr = arr.reshape(1, dim)
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise InvalidArgument(f"{name} must be an (N, {dim}) array or a single {axes} point, got shape {arr.shape}")
    if arr.shape[0] < min_rows:
        raise InvalidArgument(f"{name} needs at least {min_rows} points, got {arr.shape[0]}")
    if not np.isfinite(arr).all():
        row = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
        raise InvalidArgument(f"{name} contains a non-finite value (NaN or inf) at row {row}: {arr[row].tolist()}")
    return arr, single


def as_batch(value: ArrayLike, name: str, shape: tuple[int, ...], what: str) -> np.ndarray:
    """Validate a float64 (N, *shape) array of finite numbers (an empty input gives N = 0); errors name the
    first bad row."""
    dims = f"(N, {', '.join(map(str, shape))})"
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"{name} must be an {dims} array of {what}: {exc}") from None
    if arr.size == 0:
        return np.zeros((0, *shape))
    if arr.ndim != 1 + len(shape) or arr.shape[1:] != shape:
        raise InvalidArgument(f"{name} must be an {dims} array of {what}, got shape {arr.shape}")
    finite = np.isfinite(arr)
    if not finite.all():  # one pass over the data; the row is found only when something is wrong
        row = int(np.flatnonzero(~finite.reshape(len(arr), -1).all(axis=1))[0])
        raise InvalidArgument(f"{name} contains a non-finite value (NaN or inf) at row {row}: {arr[row].tolist()}")
    return arr


def split_rows(array: np.ndarray, starts: np.ndarray) -> list[np.ndarray]:
    """Cut an array into consecutive row blocks beginning at the given (increasing) row offsets, as views."""
    bounds = [*starts.tolist(), len(array)]
    return [array[begin:end] for begin, end in itertools.pairwise(bounds)]


def as_matrix(m: ArrayLike, name: str = "matrix", *, size: int = 3) -> np.ndarray:
    """Validate a size x size homogeneous matrix of finite numbers (3x3 in 2D, 4x4 in 3D) and return it as float64."""
    try:
        arr = np.asarray(m, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"{name} must be a {size}x{size} array of numbers: {exc}") from None
    if arr.shape != (size, size):
        raise InvalidArgument(f"{name} must be a {size}x{size} homogeneous matrix, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise InvalidArgument(f"{name} contains NaN or inf: {arr.tolist()}")
    return arr


def as_number(value: object, name: str) -> float:
    """Return value as a finite float or raise a ValueError/TypeError naming the parameter."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidArgumentType(f"{name} must be a real number, got {type(value).__name__} {value!r}")
    result = float(value)
    if not math.isfinite(result):
        raise InvalidArgument(f"{name} must be finite, got {result}")
    return result


def as_pair(value: object, name: str) -> tuple[float, float]:
    """Return value as a pair of finite floats (a point)."""
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise InvalidArgument(f"{name} must be a pair (x, y), got {value!r}")
    return as_number(value[0], f"{name}[0]"), as_number(value[1], f"{name}[1]")  # type: ignore[index]


def identity() -> np.ndarray:
    """The 3x3 identity transform."""
    return np.eye(3)


def translate(tx: float, ty: float) -> np.ndarray:
    """Translation by (tx, ty)."""
    m = np.eye(3)
    m[0, 2] = as_number(tx, "tx")
    m[1, 2] = as_number(ty, "ty")
    return m


def rotate(theta: float, about: Sequence[float] = (0.0, 0.0)) -> np.ndarray:
    """Counter-clockwise rotation by theta radians about the pivot point ``about``."""
    theta = as_number(theta, "theta")
    xr, yr = as_pair(about, "about")
    c, s = math.cos(theta), math.sin(theta)
    return np.array([
        [c, -s, xr * (1.0 - c) + yr * s],
        [s, c, yr * (1.0 - c) - xr * s],
        [0.0, 0.0, 1.0],
    ])


def scale(sx: float, sy: float, about: Sequence[float] = (0.0, 0.0)) -> np.ndarray:
    """Scaling by (sx, sy) that leaves the fixed point ``about`` in place."""
    sx, sy = as_number(sx, "sx"), as_number(sy, "sy")
    xf, yf = as_pair(about, "about")
    return np.array([
        [sx, 0.0, xf * (1.0 - sx)],
        [0.0, sy, yf * (1.0 - sy)],
        [0.0, 0.0, 1.0],
    ])


_NAMED_REFLECTIONS = {
    "x": ((1.0, 0.0), (0.0, -1.0)),
    "y": ((-1.0, 0.0), (0.0, 1.0)),
    "origin": ((-1.0, 0.0), (0.0, -1.0)),
    "y=x": ((0.0, 1.0), (1.0, 0.0)),
    "y=-x": ((0.0, -1.0), (-1.0, 0.0)),
}


def reflect(axis: str | Sequence[Sequence[float]]) -> np.ndarray:
    """Reflection about "x", "y", "origin", "y=x", "y=-x", or the line through two points ((x0, y0), (x1, y1))."""
    if isinstance(axis, str):
        if axis not in _NAMED_REFLECTIONS:
            raise InvalidArgument(
                f"unknown reflection axis {axis!r}: use one of {sorted(_NAMED_REFLECTIONS)} or two points"
            )
        m = np.eye(3)
        m[:2, :2] = _NAMED_REFLECTIONS[axis]
        return m
    if not hasattr(axis, "__len__") or len(axis) != 2:
        raise InvalidArgument(f"reflection axis must be a name or two points ((x0, y0), (x1, y1)), got {axis!r}")
    x0, y0 = as_pair(axis[0], "axis[0]")
    x1, y1 = as_pair(axis[1], "axis[1]")
    dx, dy = x1 - x0, y1 - y0
    length = math.hypot(dx, dy)
    if length == 0.0:
        raise InvalidArgument(f"reflection line needs two distinct points, got ({x0}, {y0}) twice")
    ux, uy = dx / length, dy / length
    c2, s2 = ux * ux - uy * uy, 2.0 * ux * uy  # cos 2a, sin 2a of the line's angle a
    linear = np.array([[c2, s2], [s2, -c2]])
    m = np.eye(3)
    m[:2, :2] = linear
    m[:2, 2] = np.array([x0, y0]) - linear @ np.array([x0, y0])
    return m


def shear(shx: float = 0.0, shy: float = 0.0, ref: Sequence[float] = (0.0, 0.0)) -> np.ndarray:
    """Shear: x' = x + shx (y - ref[1]) relative to y = ref[1]; y' = y + shy (x - ref[0]) relative to x = ref[0].

    Both shears act simultaneously (one matrix, Hearn & Baker's general form); to apply one after the
    other, compose two single shears.
    """
    shx, shy = as_number(shx, "shx"), as_number(shy, "shy")
    xref, yref = as_pair(ref, "ref")
    return np.array(
        [
            [1.0, shx, -shx * yref],
            [shy, 1.0, -shy * xref],
            [0.0, 0.0, 1.0],
        ]
    )


def place(position: Sequence[float], angle: float = 0.0) -> np.ndarray:
    """Local frame to world: rotate by ``angle`` radians about the local origin, then move it to ``position``.

    The frame of text, markers and symbols: local x runs along the baseline from the reference point.
    """
    px, py = as_pair(position, "position")
    return compose(translate(px, py), rotate(angle))


def compose(*matrices: ArrayLike) -> np.ndarray:
    """Matrix product in the usual order: compose(A, B) applies B first, then A (identity when empty)."""
    result = np.eye(3)
    with np.errstate(over="ignore", invalid="ignore"):
        for index, m in enumerate(matrices):
            result = result @ as_matrix(m, f"matrix {index}")
    if not np.isfinite(result).all():
        raise InvalidArgument(f"the composed matrix overflows (NaN or inf): {result.tolist()}")
    return result


def map_points(mat: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Validated (N, d) points through a validated (d+1, d+1) homogeneous matrix, dividing by w (2D and 3D);
    InvalidArgument naming the row that maps to infinity or overflows."""
    d = pts.shape[1]
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        out = pts @ mat[:d, :d].T + mat[:d, d]
        if not ((mat[d, :d] == 0.0).all() and mat[d, d] == 1.0):
            w = pts @ mat[d, :d] + mat[d, d]
            if (np.abs(w) < 1e-300).any():
                row = int(np.flatnonzero(np.abs(w) < 1e-300)[0])
                raise InvalidArgument(
                    f"point {pts[row].tolist()} (row {row}) maps to infinity (w = 0) under this matrix"
                )
            out = out / w[:, None]
    if not np.isfinite(out).all():
        row = int(np.flatnonzero(~np.isfinite(out).all(axis=1))[0])
        raise InvalidArgument(f"point {pts[row].tolist()} (row {row}) maps beyond the floating-point range")
    result: np.ndarray = out
    return result


def apply(m: ArrayLike, points: ArrayLike) -> np.ndarray:
    """Map an (N, 2) array (or one (2,) point) through the homogeneous matrix m; InvalidArgument if it overflows."""
    pts, single = as_points(points)
    out = map_points(as_matrix(m), pts)
    return out[0] if single else out


def singular_ratio(mat: np.ndarray) -> float:
    """|det| over the product of row norms of a square (homogeneous) matrix: 1 for orthogonal rows, 0 when
    singular (Hadamard's ratio; of the linear part when the matrix is affine)."""
    d = len(mat) - 1
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        if d > 0 and (mat[d, :d] == 0.0).all() and mat[d, d] != 0.0:
            block = mat[:d, :d]  # affine: invertible iff the linear part is
            det = abs(float(np.linalg.det(block)))
            norms = float(np.prod(np.linalg.norm(block, axis=1)))
        else:
            det = abs(float(np.linalg.det(mat)))
            norms = float(np.prod(np.linalg.norm(mat, axis=1)))
    return 0.0 if norms == 0.0 or not math.isfinite(det / norms) else det / norms


def inverse(mat: np.ndarray) -> np.ndarray:
    """Inverse of a validated 3x3 (2D) or 4x4 (3D) homogeneous matrix; InvalidArgument when it is singular."""
    ratio = singular_ratio(mat)
    if ratio < SINGULAR_RATIO:
        collapse = ("the plane onto a line or point" if len(mat) == 3 else
                    "space onto a plane, line or point (a projection or a scale by zero)")
        raise InvalidArgument(
            f"matrix is singular (|det| / row norms = {ratio:.3g}); it collapses {collapse} "
            f"and has no inverse: {mat.tolist()}"
        )
    return np.linalg.inv(mat)


def invert(m: ArrayLike) -> np.ndarray:
    """Inverse of a homogeneous matrix; ValueError when it is singular (e.g. a scale by zero)."""
    return inverse(as_matrix(m))


def scale_factor(m: ArrayLike) -> float:
    """sqrt|det| of the linear part: device units per world unit (to convert lengths such as tolerances)."""
    mat = as_matrix(m)
    return math.sqrt(abs(float(np.linalg.det(mat[:2, :2]))))

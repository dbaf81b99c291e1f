"""3D homogeneous transforms: 4x4 float64 matrices acting on column vectors [x, y, z, 1] (Hearn & Baker ch. 11).

Conventions (the same as the 2D module): ``compose3d(A, B) = A @ B`` applies B first; angles are in radians,
counter-clockwise when looking from the positive end of the axis towards the origin (the right-hand rule).
Points are (N, 3) float64 arrays (one (3,) point is accepted and returned as (3,)); homogeneous points are
(N, 4) rows [x, y, z, w].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

import numpy as np

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.geometry.transforms import (
    SINGULAR_RATIO,
    ArrayLike,
    as_batch,
    as_matrix,
    as_number,
    as_points,
    inverse,
    map_points,
    singular_ratio,
)

Plane = Literal["xy", "yz", "xz"]
Axis = Literal["x", "y", "z"]
RotationMethod = Literal["composition", "quaternion"]


def as_matrix3d(m: ArrayLike, name: str = "matrix") -> np.ndarray:
    """Validate a 4x4 homogeneous matrix of finite numbers and return it as float64."""
    return as_matrix(m, name, size=4)


def as_points3d(points: ArrayLike, name: str = "points", *, min_rows: int = 0) -> tuple[np.ndarray, bool]:
    """Validate an (N, 3) array or a single (3,) point of finite numbers; return (float64 (N, 3), was_single)."""
    return as_points(points, name, min_rows=min_rows, dim=3)


def as_homogeneous(h: ArrayLike, name: str = "points") -> np.ndarray:
    """Validate an (N, 4) array of finite homogeneous points [x, y, z, w]; return it as float64."""
    return as_batch(h, name, (4,), "homogeneous rows x, y, z, w")


def as_triple(value: object, name: str) -> tuple[float, float, float]:
    """Return value as a triple of finite floats (a point or vector (x, y, z))."""
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 3:
        raise InvalidArgument(f"{name} must be a triple (x, y, z), got {value!r}")
    x, y, z = (as_number(value[i], f"{name}[{i}]") for i in range(3))  # type: ignore[index]
    return x, y, z


def _unit(vector: tuple[float, float, float], name: str) -> np.ndarray:
    """The vector divided by its length; InvalidArgument for a zero (or overflowing) vector."""
    v = np.array(vector)
    length = float(np.linalg.norm(v))
    if length == 0.0 or not math.isfinite(length):
        raise InvalidArgument(f"{name} must be a non-zero finite vector, got {list(vector)}")
    unit: np.ndarray = v / length
    return unit


def identity3d() -> np.ndarray:
    """The 4x4 identity transform."""
    return np.eye(4)


def translate3d(tx: float, ty: float, tz: float) -> np.ndarray:
    """Translation by (tx, ty, tz)."""
    m = np.eye(4)
    m[:3, 3] = (as_number(tx, "tx"), as_number(ty, "ty"), as_number(tz, "tz"))
    return m


def scale3d(sx: float, sy: float, sz: float, fixed: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """Scaling by (sx, sy, sz) that leaves the point ``fixed`` in place: x' = sx·x + (1 − sx)·xf, and so on."""
    factors = np.array([as_number(sx, "sx"), as_number(sy, "sy"), as_number(sz, "sz")])
    m = np.diag([*factors, 1.0])
    m[:3, 3] = np.array(as_triple(fixed, "fixed")) * (1.0 - factors)
    return m


def _axis_rotation(axis: int, c: float, s: float) -> np.ndarray:
    """Rotation about coordinate axis 0, 1 or 2 given its cosine and sine (H&B's cyclic x -> y -> z -> x)."""
    i, j = (axis + 1) % 3, (axis + 2) % 3  # the rotation turns axis i towards axis j
    m = np.eye(4)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def rotate_x(theta: float) -> np.ndarray:
    """Rotation by theta about the x axis: y' = y cos θ − z sin θ, z' = y sin θ + z cos θ."""
    theta = as_number(theta, "theta")
    return _axis_rotation(0, math.cos(theta), math.sin(theta))


def rotate_y(theta: float) -> np.ndarray:
    """Rotation by theta about the y axis: z' = z cos θ − x sin θ, x' = z sin θ + x cos θ."""
    theta = as_number(theta, "theta")
    return _axis_rotation(1, math.cos(theta), math.sin(theta))


def rotate_z(theta: float) -> np.ndarray:
    """Rotation by theta about the z axis: x' = x cos θ − y sin θ, y' = x sin θ + y cos θ."""
    theta = as_number(theta, "theta")
    return _axis_rotation(2, math.cos(theta), math.sin(theta))


def quaternion(axis: Sequence[float], theta: float) -> np.ndarray:
    """Unit quaternion (w, x, y, z) = (cos θ/2, u sin θ/2) of a rotation by theta about the direction ``axis``."""
    u = _unit(as_triple(axis, "axis"), "axis")
    half = as_number(theta, "theta") / 2.0
    return np.array([math.cos(half), *(u * math.sin(half))])


def quaternion_matrix(q: ArrayLike) -> np.ndarray:
    """4x4 rotation matrix of the quaternion (w, x, y, z), normalised first (H&B's M_R with s = w, (a, b, c))."""
    rows, single = as_points(q, "q (a quaternion w, x, y, z)", dim=4)
    if not single:
        raise InvalidArgument(f"q must be one quaternion (w, x, y, z), got {len(rows)} rows")
    s, a, b, c = _unit_quaternion(rows[0])
    m = np.eye(4)
    m[:3, :3] = [
        [1 - 2 * b * b - 2 * c * c, 2 * a * b - 2 * s * c, 2 * a * c + 2 * s * b],
        [2 * a * b + 2 * s * c, 1 - 2 * a * a - 2 * c * c, 2 * b * c - 2 * s * a],
        [2 * a * c - 2 * s * b, 2 * b * c + 2 * s * a, 1 - 2 * a * a - 2 * b * b],
    ]
    return m


def _unit_quaternion(q: np.ndarray) -> tuple[float, float, float, float]:
    """q / |q| as four floats; InvalidArgument for a zero or non-finite quaternion."""
    length = float(np.linalg.norm(q))
    if not np.isfinite(q).all() or length == 0.0 or not math.isfinite(length):
        raise InvalidArgument(f"q must be a non-zero finite quaternion (w, x, y, z), got {q.tolist()}")
    s, a, b, c = (float(v) for v in q / length)
    return s, a, b, c


def rotate_axis(
    p1: Sequence[float], p2: Sequence[float], theta: float, method: RotationMethod = "composition"
) -> np.ndarray:
    """Rotation by theta about the axis from p1 to p2 (counter-clockwise looking from p2 towards p1).

    ``"composition"``: Hearn & Baker's T⁻¹ · Rx⁻¹(α) · Ry⁻¹(β) · Rz(θ) · Ry(β) · Rx(α) · T, where T moves p1 to
    the origin, Rx(α) turns the unit axis u = (a, b, c) into the xz plane (cos α = c/d, sin α = b/d,
    d = sqrt(b² + c²); skipped when d = 0) and Ry(β) onto z (cos β = d, sin β = −a). ``"quaternion"``:
    T⁻¹ · M_R(q) · T with q = (cos θ/2, u sin θ/2). Both give the same matrix (to rounding, ~1e-15).
    """
    how = as_choice(method, "method", ("composition", "quaternion"))
    a1, a2 = as_triple(p1, "p1"), as_triple(p2, "p2")
    theta = as_number(theta, "theta")
    direction = (a2[0] - a1[0], a2[1] - a1[1], a2[2] - a1[2])
    if direction == (0.0, 0.0, 0.0):
        raise InvalidArgument(f"rotation axis needs two distinct points p1 and p2, got {list(a1)} twice")
    to_origin, back = translate3d(-a1[0], -a1[1], -a1[2]), translate3d(*a1)
    if how == "quaternion":
        return compose3d(back, quaternion_matrix(quaternion(direction, theta)), to_origin)
    a, b, c = _unit(direction, "p2 - p1")
    d = math.hypot(b, c)
    rx = _axis_rotation(0, c / d, b / d) if d > 0.0 else np.eye(4)
    ry = _axis_rotation(1, d, -a)
    rz = rotate_z(theta)
    # the inverses of rotations are their transposes (exact, unlike rotating by −α)
    return compose3d(back, rx.T, ry.T, rz, ry, rx, to_origin)


_REFLECTIONS: dict[str, int] = {"xy": 2, "yz": 0, "xz": 1}  # the coordinate a plane's reflection negates


def reflect3d(plane: Plane) -> np.ndarray:
    """Reflection through a coordinate plane: "xy" negates z, "yz" negates x, "xz" negates y."""
    k = _REFLECTIONS[as_choice(plane, "plane", list(_REFLECTIONS))]
    m = np.eye(4)
    m[k, k] = -1.0
    return m


def shear3d(axis: Axis, a: float, b: float, ref: float = 0.0) -> np.ndarray:
    """Shear along the other two axes in proportion to ``axis`` − ref (H&B's z-axis shear and its x, y forms).

    "z": x' = x + a·(z − ref), y' = y + b·(z − ref); "x": y' = y + a·(x − ref), z' = z + b·(x − ref);
    "y": x' = x + a·(y − ref), z' = z + b·(y − ref).
    """
    k = "xyz".index(as_choice(axis, "axis", ("x", "y", "z")))
    a, b, ref = as_number(a, "a"), as_number(b, "b"), as_number(ref, "ref")
    first, second = [i for i in range(3) if i != k]
    m = np.eye(4)
    m[first, k], m[second, k] = a, b
    m[first, 3], m[second, 3] = -a * ref, -b * ref
    return m


def compose3d(*matrices: ArrayLike) -> np.ndarray:
    """Matrix product in the usual order: compose3d(A, B) applies B first, then A (identity when empty)."""
    result = np.eye(4)
    with np.errstate(over="ignore", invalid="ignore"):
        for index, m in enumerate(matrices):
            result = result @ as_matrix3d(m, f"matrix {index}")
    if not np.isfinite(result).all():
        raise InvalidArgument(f"the composed matrix overflows (NaN or inf): {result.tolist()}")
    return result


def invert3d(m: ArrayLike) -> np.ndarray:
    """Inverse of a 4x4 homogeneous matrix; InvalidArgument when it is singular (e.g. a projection)."""
    return inverse(as_matrix3d(m))


def normal_matrix(m: ArrayLike) -> np.ndarray:
    """3x3 inverse-transpose of the linear part of m: it maps surface normals (renormalise afterwards)."""
    linear = as_matrix3d(m)[:3, :3]
    ratio = singular_ratio(linear)
    if ratio < SINGULAR_RATIO:
        raise InvalidArgument(
            f"the linear part of the matrix is singular (|det| / row norms = {ratio:.3g}): normals have no image"
        )
    result: np.ndarray = np.linalg.inv(linear).T
    return result


def to_homogeneous(points: ArrayLike) -> np.ndarray:
    """(N, 3) points (or one (3,) point) to (N, 4) homogeneous rows with w = 1."""
    pts, _ = as_points3d(points)
    return np.hstack([pts, np.ones((len(pts), 1))])


def transform_homogeneous(m: ArrayLike, h: ArrayLike) -> np.ndarray:
    """Map (N, 4) homogeneous rows through the 4x4 matrix m, without dividing by w."""
    mat = as_matrix3d(m)
    rows = as_homogeneous(h)
    with np.errstate(over="ignore", invalid="ignore"):
        out: np.ndarray = rows @ mat.T
    if not np.isfinite(out).all():
        row = int(np.flatnonzero(~np.isfinite(out).all(axis=1))[0])
        raise InvalidArgument(f"point {rows[row].tolist()} (row {row}) maps beyond the floating-point range")
    return out


def apply3d(m: ArrayLike, points: ArrayLike) -> np.ndarray:
    """Map an (N, 3) array (or one (3,) point) through m, dividing by w; InvalidArgument naming a row with w = 0."""
    pts, single = as_points3d(points)
    out = map_points(as_matrix3d(m), pts)
    return out[0] if single else out


def as_choice(value: object, name: str, allowed: Sequence[str]) -> str:
    """Return value if it is one of the allowed names, else InvalidArgumentType/InvalidArgument listing them."""
    if not isinstance(value, str):
        raise InvalidArgumentType(f"{name} must be one of {list(allowed)}, got {type(value).__name__} {value!r}")
    if value not in allowed:
        raise InvalidArgument(f"{name} must be one of {list(allowed)}, got {value!r}")
    return value

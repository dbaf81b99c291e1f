"""Bézier and B-spline curves, circular and elliptical arcs, and their flattening to polylines within a tolerance.

Tolerances are in the units of the points: pass device coordinates and a device tolerance (e.g. a
quarter pixel or one plotter step) so the flattened curve is as fine as the device and no finer.

Limits (module attributes, read at call time, so assigning a new value overrides them):
:data:`MAX_ARC_POINTS` points per flattened arc; ``_MAX_PIECES`` pieces alive in one subdivision level.
B-spline evaluation needs O(samples x degree) memory whatever the number of control points.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from pixelpen.errors import InvalidArgument
from pixelpen.geometry.transforms import ArrayLike, as_number, as_points, split_rows

DEFAULT_TOLERANCE = 0.1
"""Default flattening tolerance (units of the points)."""
MAX_ARC_POINTS = 1 << 18
"""Points one flattened arc may have (a radius of 1e9 at tolerance 0.1 would need 220,000); read at call time."""

BEZIER_BASIS = np.array([
    [-1.0, 3.0, -3.0, 1.0],
    [3.0, -6.0, 3.0, 0.0],
    [-3.0, 3.0, 0.0, 0.0],
    [1.0, 0.0, 0.0, 0.0],
])
"""Cubic Bézier basis matrix M_Bez (Hearn & Baker): P(u) = [u^3 u^2 u 1] M_Bez [p0 p1 p2 p3]^T."""

BSPLINE_BASIS = np.array([
    [-1.0, 3.0, -3.0, 1.0],
    [3.0, -6.0, 3.0, 0.0],
    [-3.0, 0.0, 3.0, 0.0],
    [1.0, 4.0, 1.0, 0.0],
]) / 6.0
"""Uniform cubic B-spline basis matrix M_B = 1/6 [...] (Hearn & Baker): one segment from four control points."""

for _matrix in (BEZIER_BASIS, BSPLINE_BASIS):
    _matrix.flags.writeable = False
del _matrix

_MAX_DEPTH = 48  # parameter intervals of 2^-48: below this subdivision only meets rounding noise
_MAX_PIECES = 1 << 20  # pieces alive in one subdivision level before we call the tolerance unreachable
_MIN_RELATIVE_TOLERANCE = 1e-12  # tolerances below this fraction of the coordinates only chase rounding noise


def _tolerance(tolerance: object) -> float:
    """Validate a flattening tolerance: a finite number > 0."""
    tol = as_number(tolerance, "tolerance")
    if tol <= 0.0:
        raise InvalidArgument(f"tolerance must be > 0, got {tol}")
    return tol


def _control_array(control_points: ArrayLike, name: str = "control_points", min_rows: int = 2) -> np.ndarray:
    """Validate an (n, d) array of finite control points with at least min_rows rows."""
    try:
        arr = np.asarray(control_points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"{name} must be an (n, d) array of numbers: {exc}") from None
    if arr.ndim != 2 or arr.shape[0] < min_rows or arr.shape[1] < 1:
        raise InvalidArgument(f"{name} must be an (n, d) array with at least {min_rows} rows, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        row = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
        raise InvalidArgument(f"{name} contains NaN or inf at row {row}: {arr[row].tolist()}")
    return arr


def _parameters(t: ArrayLike, name: str = "t") -> tuple[np.ndarray, bool]:
    """Validate parameter values (scalar or 1-D, finite); return (1-D float64, was_scalar)."""
    try:
        arr = np.asarray(t, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"{name} must be a number or a 1-D array of numbers: {exc}") from None
    if arr.ndim > 1:
        raise InvalidArgument(f"{name} must be a number or a 1-D array, got shape {arr.shape}")
    scalar = arr.ndim == 0
    arr = arr.reshape(-1)
    if not np.isfinite(arr).all():
        raise InvalidArgument(f"{name} contains NaN or inf")
    return arr, scalar


def bernstein(n: int, i: int, t: ArrayLike) -> np.ndarray:
    """Bernstein polynomial B_{i,n}(t) = C(n, i) t^i (1 - t)^(n - i), vectorised over t."""
    if not (isinstance(n, (int, np.integer)) and isinstance(i, (int, np.integer))) or not 0 <= i <= n:
        raise InvalidArgument(f"bernstein needs integers 0 <= i <= n, got n={n!r}, i={i!r}")
    tt, scalar = _parameters(t)
    values = math.comb(int(n), int(i)) * tt ** int(i) * (1.0 - tt) ** int(n - i)
    return values[0] if scalar else values


def _de_casteljau(ctrl: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Points at parameters t of a stack of Bézier curves ctrl (K, n+1, d); t broadcast to (K,)."""
    pts = ctrl
    tt = t.reshape(-1, 1, 1)
    while pts.shape[1] > 1:
        pts = pts[:, :-1] + tt * (pts[:, 1:] - pts[:, :-1])
    return pts[:, 0]


def bezier_point(control_points: ArrayLike, t: ArrayLike) -> np.ndarray:
    """Points at parameters t of the Bézier curve with (n+1, d) control points (de Casteljau, vectorised over t)."""
    ctrl = _control_array(control_points, min_rows=1)
    tt, scalar = _parameters(t)
    pts = _de_casteljau(np.broadcast_to(ctrl, (len(tt), *ctrl.shape)), tt)
    return pts[0] if scalar else pts


def _split_half(ctrl: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split a stack of Bézier curves laid out (n+1, d, K) at t = 1/2 into left and right halves (de Casteljau)."""
    left, right = [ctrl[0]], [ctrl[-1]]
    pts = ctrl
    while len(pts) > 1:
        pts = 0.5 * (pts[:-1] + pts[1:])
        left.append(pts[0])
        right.append(pts[-1])
    return np.stack(left), np.stack(right[::-1])


def _flatness(ctrl: np.ndarray) -> np.ndarray:
    """Largest distance of a curve's inner control points from its chord *segment*, per curve of a (n+1, d, K) stack.

    The curve lies in the convex hull of its control points, so it is within this distance of the chord,
    and (the chord's ends being on the curve) the chord is within it of the curve. The loops run over
    the few control points and coordinates; every operation is vectorised over the K curves.
    """
    worst = np.zeros(ctrl.shape[2])
    a, ab = ctrl[0], ctrl[-1] - ctrl[0]
    length2 = sum(c * c for c in ab)
    safe = np.where(length2 > 0, length2, 1.0)
    for point in ctrl[1:-1]:
        v = point - a
        u = np.clip(sum(vc * abc for vc, abc in zip(v, ab, strict=False)) / safe, 0.0, 1.0)
        np.maximum(worst, sum((vc - u * abc) ** 2 for vc, abc in zip(v, ab, strict=False)), out=worst)
    return np.sqrt(worst)


def _flatten_stack(ctrl: np.ndarray, tol: float) -> list[np.ndarray]:
    """Adaptive de Casteljau subdivision of a (K, n+1, d) stack of same-degree curves, one numpy pass per level."""
    magnitude = float(np.abs(ctrl).max())
    if tol < _MIN_RELATIVE_TOLERANCE * magnitude:
        raise InvalidArgument(
            f"tolerance {tol:g} is too small for coordinates of size {magnitude:g}: below floating-point "
            "resolution; use a tolerance in device units (e.g. 0.1)"
        )
    count = len(ctrl)
    ids, t0 = np.arange(count), np.zeros(count)
    stack = np.ascontiguousarray(ctrl.transpose(1, 2, 0))  # (n+1, d, K): contiguous per control point
    out_ids, out_t0, out_end = [ids], [np.full(count, -1.0)], [stack[0]]  # each curve's start point first
    width = 1.0
    for depth in range(_MAX_DEPTH + 1):
        flat = _flatness(stack) <= tol
        if depth == _MAX_DEPTH:
            flat[:] = True
        out_ids.append(ids[flat])
        out_t0.append(t0[flat])
        out_end.append(stack[-1][:, flat])
        rest = ~flat
        if not rest.any():
            break
        if 2 * int(rest.sum()) > _MAX_PIECES:
            raise InvalidArgument(
                f"tolerance {tol:g} is too small for this curve: more than {_MAX_PIECES} pieces at subdivision "
                f"depth {depth + 1}; use a tolerance in device units (e.g. 0.1)"
            )
        left, right = _split_half(stack[:, :, rest])
        stack = np.concatenate([left, right], axis=2)
        width /= 2.0
        ids = np.concatenate([ids[rest], ids[rest]])
        t0 = np.concatenate([t0[rest], t0[rest] + width])
    all_ids = np.concatenate(out_ids)
    order = np.lexsort((np.concatenate(out_t0), all_ids))
    points = np.concatenate(out_end, axis=1)[:, order].T  # each curve's start, then piece ends in order
    per_curve = np.bincount(all_ids, minlength=count)
    return split_rows(np.ascontiguousarray(points), np.cumsum(per_curve) - per_curve)


def flatten_beziers(curves: Sequence[ArrayLike], tolerance: float) -> list[np.ndarray]:
    """Flatten many Bézier curves (each (n+1, d) control points, any degree >= 1) at once; one polyline each.

    Curves of one degree are subdivided together, so the cost is a few numpy passes per subdivision
    level, not one Python call per piece.
    """
    tol = _tolerance(tolerance)
    arrays = [_control_array(c, f"curves[{i}]") for i, c in enumerate(curves)]
    result: list[np.ndarray] = [np.empty((0, 0))] * len(arrays)
    groups: dict[tuple[int, int], list[int]] = {}
    for index, arr in enumerate(arrays):
        groups.setdefault(arr.shape, []).append(index)
    for members in groups.values():
        for index, polyline in zip(members, _flatten_stack(np.stack([arrays[i] for i in members]), tol), strict=False):
            result[index] = polyline
    return result


def flatten_bezier(control_points: ArrayLike, tolerance: float) -> np.ndarray:
    """Flatten a Bézier curve of any degree to a polyline within ``tolerance`` of it (adaptive de Casteljau).

    The polyline's vertices lie on the curve and it starts and ends exactly at the first and last
    control points; every point of the curve is within ``tolerance`` of the polyline and vice versa.
    """
    return flatten_beziers([control_points], tolerance)[0]


def eval_basis(basis: ArrayLike, geometry: ArrayLike, t: ArrayLike) -> np.ndarray:
    """Evaluate one cubic segment P(u) = [u^3 u^2 u 1] M G for a 4x4 basis matrix M and (4, d) geometry G."""
    m = np.asarray(basis, dtype=np.float64)
    if m.shape != (4, 4):
        raise InvalidArgument(f"basis must be a 4x4 matrix, got shape {m.shape}")
    g = _control_array(geometry, "geometry", min_rows=4)
    if len(g) != 4:
        raise InvalidArgument(f"geometry must have exactly 4 rows for a cubic basis, got {len(g)}")
    tt, scalar = _parameters(t)
    powers = np.stack([tt ** 3, tt ** 2, tt, np.ones_like(tt)], axis=1)
    pts: np.ndarray = powers @ m @ g
    return pts[0] if scalar else pts


def basis_to_bezier(basis: ArrayLike, geometry: ArrayLike) -> np.ndarray:
    """Bézier control points (4, d) of the cubic segment given by a basis matrix and geometry: M_Bez^-1 M G.

    E.g. ``basis_to_bezier(BSPLINE_BASIS, four_points)`` turns a uniform cubic B-spline segment into a
    Bézier curve that :func:`flatten_bezier` can flatten.
    """
    m = np.asarray(basis, dtype=np.float64)
    if m.shape != (4, 4):
        raise InvalidArgument(f"basis must be a 4x4 matrix, got shape {m.shape}")
    g = _control_array(geometry, "geometry", min_rows=4)
    if len(g) != 4:
        raise InvalidArgument(f"geometry must have exactly 4 rows for a cubic basis, got {len(g)}")
    return np.linalg.solve(BEZIER_BASIS, m @ g)


def as_degree(degree: object) -> int:
    """Validate a spline degree (integer >= 1)."""
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or degree < 1:
        raise InvalidArgument(f"degree must be an integer >= 1, got {degree!r}")
    return int(degree)


def _count(n: object, degree: int) -> int:
    """Validate a control-point count for a spline of this degree."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < degree + 1:
        raise InvalidArgument(f"a degree-{degree} B-spline needs at least {degree + 1} control points, got {n!r}")
    return int(n)


def uniform_knots(n: int, degree: int) -> np.ndarray:
    """Uniform (periodic-style) knot vector 0, 1, ..., n + degree for n control points; domain [degree, n]."""
    degree = as_degree(degree)
    return np.arange(_count(n, degree) + degree + 1, dtype=np.float64)


def open_uniform_knots(n: int, degree: int) -> np.ndarray:
    """Open uniform (clamped) knots: degree + 1 zeros, 1 .. n - degree - 1, degree + 1 copies of n - degree."""
    degree = as_degree(degree)
    n = _count(n, degree)
    inner = np.arange(1, n - degree, dtype=np.float64)
    return np.concatenate([np.zeros(degree + 1), inner, np.full(degree + 1, float(n - degree))])


def _knot_vector(knots: ArrayLike, degree: int) -> np.ndarray:
    """Validate a knot vector: 1-D, finite, non-decreasing, with a non-empty domain [k_degree, k_n]."""
    k = np.asarray(knots, dtype=np.float64)
    if k.ndim != 1 or len(k) < 2 * degree + 2:
        raise InvalidArgument(
            f"knots must be a 1-D array of at least {2 * degree + 2} values for degree {degree}, got shape {k.shape}"
        )
    if not np.isfinite(k).all():
        raise InvalidArgument("knots contain NaN or inf")
    drops = np.flatnonzero(np.diff(k) < 0)
    if len(drops):
        i = int(drops[0])
        raise InvalidArgument(f"knots must be non-decreasing: knots[{i}] = {k[i]} > knots[{i + 1}] = {k[i + 1]}")
    n = len(k) - degree - 1
    if not k[degree] < k[n]:
        raise InvalidArgument(f"knot domain [knots[{degree}], knots[{n}]] = [{k[degree]}, {k[n]}] is empty")
    return k


def spline_knots(knots: ArrayLike | None, n: int, degree: int) -> np.ndarray:
    """The knot vector for n control points of this degree: validated, or open uniform when None."""
    if knots is None:
        return open_uniform_knots(n, degree)
    k = np.asarray(knots, dtype=np.float64)
    if k.ndim != 1 or len(k) != n + degree + 1:
        raise InvalidArgument(f"{n} control points of degree {degree} need {n + degree + 1} knots, got shape {k.shape}")
    return _knot_vector(k, degree)


def _span_basis(k: np.ndarray, degree: int, tt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Knot span s of each t and the degree + 1 basis functions N_{s-degree..s} not zero there (The NURBS Book A2.2).

    Vectorised over t; the loops run over the degree only, so memory is O(len(t) x degree) whatever the
    number of control points. t must lie in the domain; its right end belongs to the last non-empty span.
    """
    n = len(k) - degree - 1
    lo, hi = k[degree], k[n]
    outside = (tt < lo) | (tt > hi)
    if outside.any():
        bad = float(tt[np.flatnonzero(outside)[0]])
        raise InvalidArgument(f"t = {bad} is outside the spline's domain [{lo}, {hi}]")
    last = degree + int(np.flatnonzero(k[degree:n] < k[degree + 1:n + 1])[-1])  # last non-empty span
    span = np.minimum(np.searchsorted(k, tt, side="right") - 1, last)
    values = np.ones((len(tt), 1))
    for j in range(1, degree + 1):
        left = tt[:, None] - k[span[:, None] + 1 - np.arange(j + 1)]  # left[:, i] = t - k[s + 1 - i]
        right = k[span[:, None] + np.arange(j + 1)] - tt[:, None]  # right[:, i] = k[s + i] - t
        grown = np.empty((len(tt), j + 1))
        saved = np.zeros(len(tt))
        for r in range(j):
            temp = values[:, r] / (right[:, r + 1] + left[:, j - r])  # denominators >= the span's width > 0
            grown[:, r] = saved + right[:, r + 1] * temp
            saved = left[:, j - r] * temp
        grown[:, j] = saved
        values = grown
    return span, values


def bspline_basis(knots: ArrayLike, degree: int, t: ArrayLike) -> np.ndarray:
    """Cox–de Boor B-spline basis: the (len(t), n) matrix of N_{i,degree}(t), n = len(knots) - degree - 1.

    t must lie in the domain [knots[degree], knots[n]], where the functions sum to 1; the right end
    belongs to the last non-empty span. Only degree + 1 functions are non-zero at any t; to evaluate a
    curve use :func:`bspline_point`, which never builds this (len(t), n) matrix.
    """
    degree = as_degree(degree)
    k = _knot_vector(knots, degree)
    tt, _ = _parameters(t)
    span, values = _span_basis(k, degree, tt)
    basis = np.zeros((len(tt), len(k) - degree - 1))
    basis[np.arange(len(tt))[:, None], span[:, None] - degree + np.arange(degree + 1)] = values
    return basis


def _spline_points(ctrl: np.ndarray, k: np.ndarray, degree: int, tt: np.ndarray) -> np.ndarray:
    """Curve points at parameters tt, summing only the degree + 1 non-zero basis terms per parameter."""
    span, values = _span_basis(k, degree, tt)
    pts = np.zeros((len(tt), ctrl.shape[1]))
    for r in range(degree + 1):
        pts += values[:, r:r + 1] * ctrl[span - degree + r]
    return pts


def bspline_point(control_points: ArrayLike, degree: int, knots: ArrayLike | None, t: ArrayLike) -> np.ndarray:
    """Points of a B-spline curve at parameters t (knots None = open uniform), via the Cox–de Boor basis.

    Memory is O(len(t) x degree): only the degree + 1 basis functions non-zero in each knot span are computed.
    """
    degree = as_degree(degree)
    ctrl = _control_array(control_points, min_rows=degree + 1)
    k = spline_knots(knots, len(ctrl), degree)
    tt, scalar = _parameters(t)
    pts = _spline_points(ctrl, k, degree, tt)
    return pts[0] if scalar else pts


def flatten_bspline(
    control_points: ArrayLike, degree: int, knots: ArrayLike | None = None, tolerance: float = DEFAULT_TOLERANCE
) -> np.ndarray:
    """Flatten a B-spline curve (any degree >= 1; knots None = open uniform/clamped) within ``tolerance``.

    Each non-empty knot span is a polynomial of the spline's degree: it is sampled at degree + 1
    parameters with the Cox–de Boor basis, converted exactly to Bézier form, and all spans are then
    subdivided adaptively together (see :func:`flatten_beziers`). The Bézier control polygon bounds
    the curve, so the tolerance is guaranteed rather than estimated from samples. The result runs over
    the whole domain [knots[degree], knots[n]]; interior knots may repeat up to ``degree`` times.
    """
    degree = as_degree(degree)
    tol = _tolerance(tolerance)
    ctrl = _control_array(control_points, min_rows=degree + 1)
    n, dim = ctrl.shape
    k = spline_knots(knots, n, degree)
    values, multiplicity = np.unique(k[degree + 1:n], return_counts=True)
    if (multiplicity > degree).any():
        bad = float(values[np.argmax(multiplicity > degree)])
        raise InvalidArgument(
            f"interior knot {bad} repeats more than degree={degree} times: the curve is discontinuous"
        )
    j = np.arange(degree, n)
    spans = j[k[j] < k[j + 1]]
    a, b = k[spans], k[spans + 1]
    r = np.arange(degree + 1) / degree
    params = (a[:, None] + (b - a)[:, None] * r).reshape(-1)
    samples = _spline_points(ctrl, k, degree, params).reshape(len(spans), degree + 1, dim)
    bern = np.stack([bernstein(degree, i, r) for i in range(degree + 1)], axis=1)  # samples = bern @ bezier
    bezier = np.einsum("ij,sjd->sid", np.linalg.inv(bern), samples)
    bezier[:, 0], bezier[:, -1] = samples[:, 0], samples[:, -1]  # span ends are curve points: keep them exact
    pieces = _flatten_stack(bezier, tol)
    return np.concatenate([pieces[0]] + [p[1:] for p in pieces[1:]])


def flatten_arc(
    center: Sequence[float],
    rx: float,
    ry: float,
    start: float,
    end: float,
    angle: float = 0.0,
    tolerance: float = DEFAULT_TOLERANCE,
) -> np.ndarray:
    """Flatten a circular or (rotated) elliptical arc: points c + R(angle) (rx cos u, ry sin u), u from start to end.

    Angles are radians, counter-clockwise; end < start runs clockwise; |end - start| >= 2 pi gives the
    full ellipse (closed: last point = first). The step in u is the largest whose sagitta on a circle
    of the larger radius, r (1 - cos(du / 2)), stays within ``tolerance`` (an ellipse is that circle
    squeezed, which only shrinks the chord error), and at most a quarter turn.
    """
    cx, cy = as_points(center, "center")[0][0]
    rx, ry = as_number(rx, "rx"), as_number(ry, "ry")
    if rx <= 0.0 or ry <= 0.0:
        raise InvalidArgument(f"arc radii must be > 0, got rx={rx}, ry={ry}")
    start, end = as_number(start, "start"), as_number(end, "end")
    angle = as_number(angle, "angle")
    tol = _tolerance(tolerance)
    sweep = end - start
    full = abs(sweep) >= 2.0 * math.pi
    if full:
        sweep = math.copysign(2.0 * math.pi, sweep)
    radius = max(rx, ry)
    # r (1 - cos(du / 2)) = 2 r sin^2(du / 4) <= tol, in a form that stays > 0 for tol << r
    step = 4.0 * math.asin(math.sqrt(min(tol / (2.0 * radius), 1.0)))
    pieces = abs(sweep) / step if step > 0.0 else math.inf
    if pieces > MAX_ARC_POINTS:
        raise InvalidArgument(
            f"an arc of radius {radius:g} needs more than {MAX_ARC_POINTS} points at tolerance {tol:g} "
            "(raise geometry.curves.MAX_ARC_POINTS, or use a tolerance in device units)"
        )
    count = max(1, math.ceil(pieces), math.ceil(abs(sweep) / (math.pi / 2.0)))
    u = start + sweep * (np.arange(count + 1) / count)
    u[-1] = start + sweep
    ex, ey = rx * np.cos(u), ry * np.sin(u)
    c, s = math.cos(angle), math.sin(angle)
    pts = np.stack([cx + c * ex - s * ey, cy + s * ex + c * ey], axis=1)
    if full:
        pts[-1] = pts[0]
    return pts

"""Parametric surfaces — sphere, ellipsoid, torus, Bézier and B-spline patches — tessellated to a tolerance.

A surface is P(u, v) over a rectangular domain (u0, u1, v0, v1); its normal is the unit vector along
P_u x P_v, which for the quadrics points outward, and the tessellation's triangles are counter-clockwise
seen from that side (see :func:`pixelpen.geometry.mesh.quad_mesh`).

Tessellation: ``tessellate(tolerance, scale)`` takes the tolerance in device units and ``scale`` device
units per model unit, so the chord error bound is e = tolerance / scale model units. Each grid cell lies
inside one polynomial piece (knot span) and is cut into two right triangles of legs du, dv. For the linear
interpolant L of P on a triangle with smallest enclosing circle radius R, |P - L| <= (M / 2) R^2 where M
bounds the second directional derivative (Taylor with Σλ_i |x_i - x|^2 <= R^2). Scaling u by du and v by dv
makes R^2 = 1/2 and M <= max(du^2 Muu, dv^2 Mvv) + du dv Muv, with Muu, Muv, Mvv bounds on |P_uu|, |P_uv|,
|P_vv| (the quadrics' by hand; a spline's are its second-derivative control nets' largest points, by the
convex-hull property). The steps are chosen so that this bound is <= e: a guarantee, not an estimate.
Rows of the grid that collapse to one point (a sphere's poles) are welded to one vertex. Each triangle is
its own polygon, so silhouettes through a quad's diagonal are kept. :data:`MAX_TRIANGLES` (read at call
time) bounds one tessellation.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from pixelpen.errors import InvalidArgument
from pixelpen.geometry.curves import as_degree, bernstein, bspline_basis, spline_knots
from pixelpen.geometry.mesh import Mesh, quad_mesh
from pixelpen.geometry.transforms import ArrayLike, as_number
from pixelpen.geometry.transforms3d import as_triple

MAX_TRIANGLES = 4_000_000
"""Triangles one tessellation may have (a sphere of radius 1000 device units at tolerance 0.01 needs ~1.3 M)."""

_WELD_RELATIVE = 1e-12  # grid rows within this fraction of the surface's size of one point are one vertex


class Surface(ABC):
    """A parametric surface P(u, v): points, unit normals and a tessellation within a tolerance."""

    domain: tuple[float, float, float, float] = (0.0, 1.0, 0.0, 1.0)
    closed_u = False
    closed_v = False
    _min_steps = (1, 1)

    @abstractmethod
    def _points(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(K, 3) points at 1-D parameter arrays u, v inside the domain."""

    @abstractmethod
    def _normals(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(K, 3) vectors along P_u x P_v (any length; zero where it vanishes)."""

    @abstractmethod
    def _second_derivative_bounds(self) -> tuple[float, float, float]:
        """Upper bounds (Muu, Muv, Mvv) on |P_uu|, |P_uv|, |P_vv| over the domain."""

    def _breaks(self) -> tuple[np.ndarray, np.ndarray]:
        """Parameter values where the surface stops being one polynomial piece, ends included."""
        u0, u1, v0, v1 = self.domain
        return np.array([u0, u1]), np.array([v0, v1])

    def _grid(self, us: np.ndarray, vs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(U, V, 3) points and normal vectors on the grid us x vs."""
        uu, vv = np.meshgrid(us, vs, indexing="ij")
        shape = (*uu.shape, 3)
        u, v = uu.ravel(), vv.ravel()
        return self._points(u, v).reshape(shape), self._normals(u, v).reshape(shape)

    def _parameters_in(
        self, u: ArrayLike | float, v: ArrayLike | float
    ) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
        """u and v broadcast together, checked finite and inside the domain; flattened, with their shape."""
        try:
            uu, vv = np.broadcast_arrays(np.asarray(u, dtype=np.float64), np.asarray(v, dtype=np.float64))
        except (TypeError, ValueError) as exc:
            raise InvalidArgument(f"u and v must be numbers or arrays that broadcast together: {exc}") from None
        u0, u1, v0, v1 = self.domain
        for name, arr, lo, hi in (("u", uu, u0, u1), ("v", vv, v0, v1)):
            bad = ~np.isfinite(arr) | (arr < lo) | (arr > hi)
            if bad.any():
                raise InvalidArgument(f"{name} = {float(arr[bad].ravel()[0])} is outside the domain [{lo}, {hi}]")
        return uu.ravel(), vv.ravel(), uu.shape

    def point(self, u: ArrayLike | float, v: ArrayLike | float) -> np.ndarray:
        """Points P(u, v), shape (*broadcast shape, 3)."""
        uu, vv, shape = self._parameters_in(u, v)
        return self._points(uu, vv).reshape(*shape, 3)

    def normal(self, u: ArrayLike | float, v: ArrayLike | float) -> np.ndarray:
        """Unit normals along P_u x P_v, shape (*broadcast shape, 3) (zero where the surface has no tangent plane)."""
        uu, vv, shape = self._parameters_in(u, v)
        return _unit_rows(self._normals(uu, vv)).reshape(*shape, 3)

    def parameters(self, tolerance: float, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
        """The grid (us, vs) that :meth:`tessellate` samples, both ends included (see the module docstring)."""
        tol, factor = as_number(tolerance, "tolerance"), as_number(scale, "scale")
        if tol <= 0.0 or factor <= 0.0:
            raise InvalidArgument(f"tolerance and scale must be > 0, got tolerance={tol}, scale={factor}")
        e = tol / factor
        muu, muv, mvv = self._second_derivative_bounds()
        bu, bv = self._breaks()
        du = math.sqrt(2.0 * e / muu) if muu > 0.0 else float(np.diff(bu).max())
        dv = math.sqrt(2.0 * e / mvv) if mvv > 0.0 else float(np.diff(bv).max())
        bound = (max(du * du * muu, dv * dv * mvv) + du * dv * muv) / 4.0
        if bound > e:
            du, dv = du * math.sqrt(e / bound), dv * math.sqrt(e / bound)
        steps_u = _steps(np.diff(bu), du, self._min_steps[0])
        steps_v = _steps(np.diff(bv), dv, self._min_steps[1])
        triangles = 2.0 * float(steps_u.sum()) * float(steps_v.sum())
        if triangles > MAX_TRIANGLES:
            raise InvalidArgument(
                f"tolerance {tol:g} at scale {factor:g} needs about {triangles:.3g} triangles, more than "
                f"MAX_TRIANGLES = {MAX_TRIANGLES}; use a tolerance in device units (e.g. 0.25)"
            )
        return _spread(bu, steps_u), _spread(bv, steps_v)

    def tessellate(self, tolerance: float, scale: float = 1.0) -> Mesh:
        """A mesh within tolerance / scale model units of the surface, with the analytic unit vertex normals."""
        us, vs = self.parameters(tolerance, scale)
        us = us[:-1] if self.closed_u else us
        vs = vs[:-1] if self.closed_v else vs
        points, normals = self._grid(us, vs)
        grid = quad_mesh(points, self.closed_u, self.closed_v)
        rows, cols = points.shape[:2]
        index = np.arange(rows * cols).reshape(rows, cols)
        target = np.arange(rows * cols)
        size = float(np.ptp(grid.vertices, axis=0).max()) if len(grid.vertices) else 0.0
        edges = [] if self.closed_u else [index[0], index[-1]]
        edges += [] if self.closed_v else [index[:, 0], index[:, -1]]
        for line in edges:
            if np.abs(grid.vertices[line] - grid.vertices[line[0]]).max() <= _WELD_RELATIVE * size:
                target[line] = line[0]
        faces = target[grid.faces]
        faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])]
        used = np.bincount(faces.ravel(), minlength=rows * cols) > 0
        faces = (np.cumsum(used) - 1)[faces]
        unit = _unit_rows(normals.reshape(-1, 3)[used])
        missing = np.linalg.norm(unit, axis=1) == 0.0
        if missing.any():
            unit[missing] = Mesh(grid.vertices[used], faces).vertex_normals()[missing]
        unit[np.linalg.norm(unit, axis=1) == 0.0] = (0.0, 0.0, 1.0)  # every face at the vertex is degenerate
        return Mesh(grid.vertices[used], faces, normals=unit)


def _unit_rows(vectors: np.ndarray) -> np.ndarray:
    """Rows scaled to unit length (zero rows stay zero)."""
    length = np.linalg.norm(vectors, axis=1)
    result: np.ndarray = np.where(length[:, None] > 0.0, vectors / np.where(length > 0.0, length, 1.0)[:, None], 0.0)
    return result


def _steps(widths: np.ndarray, step: float, minimum: int) -> np.ndarray:
    """Pieces per span so that no piece is wider than step (at least minimum pieces in all)."""
    counts = np.ceil(widths / step) if step > 0.0 else np.full(len(widths), np.inf)
    counts = np.maximum(np.where(np.isfinite(counts), counts, float(MAX_TRIANGLES) + 1.0), 1.0)
    if counts.sum() < minimum:
        counts[:] = math.ceil(minimum / len(counts))
    return counts


def _spread(breaks: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """Parameter values dividing each span [breaks[i], breaks[i+1]] into steps[i] equal pieces (ends exact)."""
    n = steps.astype(np.int64)
    span = np.repeat(np.arange(len(n)), n)
    k = np.arange(int(n.sum())) - (np.cumsum(n) - n)[span]
    values = breaks[span] + (breaks[span + 1] - breaks[span]) * (k / n[span])
    return np.append(values, breaks[-1])


def _positive(value: object, name: str) -> float:
    """A finite number > 0."""
    x = as_number(value, name)
    if x <= 0.0:
        raise InvalidArgument(f"{name} must be > 0, got {x}")
    return x


class Ellipsoid(Surface):
    """Ellipsoid ((x-cx)/a)^2 + ((y-cy)/b)^2 + ((z-cz)/c)^2 = 1: P = c + (a cos v cos u, b cos v sin u, c sin v).

    u is the longitude in [0, 2 pi], v the latitude in [-pi/2, pi/2]; the normals point outward.
    """

    domain = (0.0, 2.0 * math.pi, -0.5 * math.pi, 0.5 * math.pi)
    closed_u = True
    _min_steps = (3, 2)

    def __init__(self, center: tuple[float, float, float], radii: tuple[float, float, float]) -> None:
        """Validate the centre and the three positive semi-axes."""
        self.center = np.array(as_triple(center, "center"))
        self.radii = np.array([_positive(r, f"radii[{i}]") for i, r in enumerate(as_triple(radii, "radii"))])

    def _points(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """c + radii * (cos v cos u, cos v sin u, sin v)."""
        direction = np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], axis=1)
        result: np.ndarray = self.center + self.radii * direction
        return result

    def _normals(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The gradient direction (cos v cos u / a, cos v sin u / b, sin v / c)."""
        direction = np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], axis=1)
        result: np.ndarray = direction / self.radii
        return result

    def _second_derivative_bounds(self) -> tuple[float, float, float]:
        """Each of |P_uu|, |P_uv|, |P_vv| is at most the largest semi-axis."""
        r = float(self.radii.max())
        return r, r, r


class Sphere(Ellipsoid):
    """Sphere of a radius about a centre (an ellipsoid with equal semi-axes)."""

    def __init__(self, center: tuple[float, float, float], radius: float) -> None:
        """Validate the centre and the positive radius."""
        r = _positive(radius, "radius")
        super().__init__(center, (r, r, r))
        self.radius = r


class Torus(Surface):
    """Torus about the z axis through ``center``: P = c + ((R + r cos v) cos u, (R + r cos v) sin u, r sin v)."""

    domain = (0.0, 2.0 * math.pi, 0.0, 2.0 * math.pi)
    closed_u = True
    closed_v = True
    _min_steps = (3, 3)

    def __init__(self, center: tuple[float, float, float], major: float, minor: float) -> None:
        """Validate the centre and the radii, major > minor > 0 (a ring torus)."""
        self.center = np.array(as_triple(center, "center"))
        self.major, self.minor = _positive(major, "major"), _positive(minor, "minor")
        if self.minor >= self.major:
            raise InvalidArgument(f"a torus needs major > minor, got major={self.major}, minor={self.minor}")

    def _points(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Points of the torus."""
        ring = self.major + self.minor * np.cos(v)
        offset = np.stack([ring * np.cos(u), ring * np.sin(u), self.minor * np.sin(v)], axis=1)
        result: np.ndarray = self.center + offset
        return result

    def _normals(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Outward from the tube's centre circle: (cos v cos u, cos v sin u, sin v)."""
        return np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], axis=1)

    def _second_derivative_bounds(self) -> tuple[float, float, float]:
        """|P_uu| <= R + r, |P_uv| <= r, |P_vv| = r."""
        return self.major + self.minor, self.minor, self.minor


def _derivative_net(net: np.ndarray, knots: np.ndarray, degree: int, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Control net and knots of dP/du (axis 0) or dP/dv (axis 1): Q_i = p (P_i+1 - P_i) / (k_i+p+1 - k_i+1)."""
    diff = np.diff(net, axis=axis)
    n = net.shape[axis]
    shape = [1, 1, 1]
    shape[axis] = n - 1
    width = np.broadcast_to((knots[degree + 1:n + degree] - knots[1:n]).reshape(shape), diff.shape)
    # a zero width means the lower-degree basis function is identically zero: its coefficient is 0
    scaled = np.divide(degree * diff, width, out=np.zeros(diff.shape), where=width > 0.0)
    return scaled, knots[1:-1]


class _TensorProduct(Surface):
    """A tensor-product surface P(u, v) = Σ_i Σ_j N_i(u) N_j(v) P_ij of an (R, C, 3) control net."""

    def __init__(self, net: np.ndarray, degree: tuple[int, int], knots: tuple[np.ndarray, np.ndarray]) -> None:
        """Store the validated net, degrees and knots; precompute the first-derivative nets."""
        self.control = net
        self.degree = degree
        self.knots = knots
        (p, q), (ku, kv) = degree, knots
        self._du = _derivative_net(net, ku, p, 0)
        self._dv = _derivative_net(net, kv, q, 1)
        self.domain = (float(ku[p]), float(ku[-p - 1]), float(kv[q]), float(kv[-q - 1]))

    @abstractmethod
    def _basis(self, knots: np.ndarray, degree: int, t: np.ndarray) -> np.ndarray:
        """(len(t), n) basis functions of this degree over these knots."""

    def _evaluate(self, net: np.ndarray, degrees: tuple[int, int], knots: tuple[np.ndarray, np.ndarray],
                  u: np.ndarray, v: np.ndarray, pattern: str) -> np.ndarray:
        """Σ N_i(u) N_j(v) net_ij with einsum pattern "ki,ijd,kj->kd" (paired) or "ui,ijd,vj->uvd" (grid)."""
        result: np.ndarray = np.einsum(pattern, self._basis(knots[0], degrees[0], u), net,
                                       self._basis(knots[1], degrees[1], v))
        return result

    def _tangents(self, u: np.ndarray, v: np.ndarray, pattern: str) -> tuple[np.ndarray, np.ndarray]:
        """P_u and P_v at the parameters, by the derivative nets."""
        (p, q), (ku, kv) = self.degree, self.knots
        pu = self._evaluate(self._du[0], (p - 1, q), (self._du[1], kv), u, v, pattern)
        pv = self._evaluate(self._dv[0], (p, q - 1), (ku, self._dv[1]), u, v, pattern)
        return pu, pv

    def _points(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Points, one per (u, v) pair."""
        return self._evaluate(self.control, self.degree, self.knots, u, v, "ki,ijd,kj->kd")

    def _normals(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """P_u x P_v, one per (u, v) pair."""
        return np.cross(*self._tangents(u, v, "ki,ijd,kj->kd"))

    def _grid(self, us: np.ndarray, vs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points and P_u x P_v on the grid, separably (basis matrices per axis, not per grid point)."""
        points = self._evaluate(self.control, self.degree, self.knots, us, vs, "ui,ijd,vj->uvd")
        return points, np.cross(*self._tangents(us, vs, "ui,ijd,vj->uvd"))

    def _second_derivative_bounds(self) -> tuple[float, float, float]:
        """Largest points of the second-derivative nets (zero along an axis of degree 1)."""
        (p, q), kv = self.degree, self.knots[1]
        uu = _derivative_net(*self._du, p - 1, 0)[0] if p > 1 else np.zeros((1, 1, 3))
        vv = _derivative_net(*self._dv, q - 1, 1)[0] if q > 1 else np.zeros((1, 1, 3))
        uv = _derivative_net(self._du[0], kv, q, 1)[0]
        muu, muv, mvv = (float(np.linalg.norm(d, axis=2).max()) for d in (uu, uv, vv))
        return muu, muv, mvv


def _control_net(control: ArrayLike, rows: int, cols: int) -> np.ndarray:
    """Validate an (R, C, 3) net of finite control points with R >= rows and C >= cols."""
    try:
        net = np.asarray(control, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"control must be an (R, C, 3) array of numbers: {exc}") from None
    if net.ndim != 3 or net.shape[2] != 3 or net.shape[0] < rows or net.shape[1] < cols:
        raise InvalidArgument(f"control must be an (R, C, 3) array with R >= {rows}, C >= {cols}, got {net.shape}")
    bad = ~np.isfinite(net).all(axis=2)
    if bad.any():
        i, j = (int(k) for k in np.argwhere(bad)[0])
        raise InvalidArgument(f"control[{i}, {j}] is not finite: {net[i, j].tolist()}")
    net.flags.writeable = False
    return net


class BezierSurface(_TensorProduct):
    """Bézier patch of an (m+1, n+1, 3) control net: P(u, v) = Σ B_i,m(u) B_j,n(v) P_ij over [0, 1]^2."""

    def __init__(self, control: ArrayLike) -> None:
        """Validate the net (at least 2 x 2 points)."""
        net = _control_net(control, 2, 2)
        m, n = net.shape[0] - 1, net.shape[1] - 1
        clamped = (np.repeat([0.0, 1.0], m + 1), np.repeat([0.0, 1.0], n + 1))
        super().__init__(net, (m, n), clamped)

    def _basis(self, knots: np.ndarray, degree: int, t: np.ndarray) -> np.ndarray:
        """Bernstein polynomials B_i,degree(t)."""
        return np.stack([bernstein(degree, i, t) for i in range(degree + 1)], axis=1)


class BSplineSurface(_TensorProduct):
    """Tensor-product B-spline surface of an (R, C, 3) net; knots None = open uniform in both directions."""

    def __init__(self, control: ArrayLike, degree: tuple[int, int] = (3, 3),
                 knots: tuple[ArrayLike, ArrayLike] | None = None) -> None:
        """Validate the net, the degrees and the knots (interior multiplicity at most the degree)."""
        if not isinstance(degree, tuple | list) or len(degree) != 2:
            raise InvalidArgument(f"degree must be a pair (p, q), got {degree!r}")
        p, q = as_degree(degree[0]), as_degree(degree[1])
        net = _control_net(control, p + 1, q + 1)
        if knots is not None and (not isinstance(knots, tuple | list) or len(knots) != 2):
            raise InvalidArgument("knots must be None or a pair (knots_u, knots_v)")
        pair = []
        for axis, d in ((0, p), (1, q)):
            k = spline_knots(None if knots is None else knots[axis], net.shape[axis], d)
            values, counts = np.unique(k[d + 1:net.shape[axis]], return_counts=True)
            if (counts > d).any():
                raise InvalidArgument(f"interior knot {float(values[counts > d][0])} of axis {axis} repeats more "
                                      f"than degree={d} times: the surface is discontinuous there")
            pair.append(k)
        super().__init__(net, (p, q), (pair[0], pair[1]))

    def _breaks(self) -> tuple[np.ndarray, np.ndarray]:
        """The distinct knots inside each domain: each grid cell lies in one polynomial piece."""
        u0, u1, v0, v1 = self.domain
        ku, kv = self.knots
        return np.unique(ku[(ku >= u0) & (ku <= u1)]), np.unique(kv[(kv >= v0) & (kv <= v1)])

    def _basis(self, knots: np.ndarray, degree: int, t: np.ndarray) -> np.ndarray:
        """Cox–de Boor basis (degree 0: the indicator of each t's knot span, the right end in the last)."""
        if degree >= 1:
            return bspline_basis(knots, degree, t)
        n = len(knots) - 1
        last = int(np.flatnonzero(knots[:-1] < knots[1:])[-1])
        span = np.minimum(np.searchsorted(knots, t, side="right") - 1, last)
        indicator: np.ndarray = (span[:, None] == np.arange(n)).astype(np.float64)
        return indicator

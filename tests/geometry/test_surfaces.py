"""Tests for pixelpen.geometry.surfaces: quadrics, Bézier and B-spline patches, tessellation within tolerance."""

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import InvalidArgument
from pixelpen.geometry import surfaces
from pixelpen.geometry.mesh import Mesh
from pixelpen.geometry.surfaces import BezierSurface, BSplineSurface, Ellipsoid, Sphere, Surface, Torus

# barycentric sample points inside a triangle: centroid, edge midpoints, and points nearer each corner
BARY = np.array([[1, 1, 1], [1, 1, 0], [0, 1, 1], [1, 0, 1], [4, 1, 1], [1, 4, 1], [1, 1, 4], [2, 3, 1]], float)
BARY /= BARY.sum(axis=1, keepdims=True)


def triangle_samples(mesh: Mesh) -> np.ndarray:
    """(T * 8, 3) points inside every triangle of the mesh."""
    return np.einsum("sk,tkd->tsd", BARY, mesh.vertices[mesh.faces]).reshape(-1, 3)


def de_casteljau(control: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Bézier patch by repeated linear interpolation (H&B): first along v in every row, then along u."""
    rows = []
    for row in control:
        pts = [np.broadcast_to(p, (len(v), 3)) for p in row]
        while len(pts) > 1:
            pts = [(1 - v)[:, None] * a + v[:, None] * b for a, b in itertools.pairwise(pts)]
        rows.append(pts[0])
    while len(rows) > 1:
        rows = [(1 - u)[:, None] * a + u[:, None] * b for a, b in itertools.pairwise(rows)]
    return rows[0]


def cox_de_boor(knots: np.ndarray, i: int, p: int, t: np.ndarray) -> np.ndarray:
    """N_{i,p}(t) by the Cox–de Boor recursion, 0/0 = 0; t at the domain's right end counts in the last span."""
    if p == 0:
        last = max(j for j in range(len(knots) - 1) if knots[j] < knots[j + 1])
        inside = (knots[i] <= t) & (t < knots[i + 1])
        return (inside | ((i == last) & (t == knots[last + 1]))).astype(float)
    out = np.zeros_like(t)
    if knots[i + p] > knots[i]:
        out += (t - knots[i]) / (knots[i + p] - knots[i]) * cox_de_boor(knots, i, p - 1, t)
    if knots[i + p + 1] > knots[i + 1]:
        out += (knots[i + p + 1] - t) / (knots[i + p + 1] - knots[i + 1]) * cox_de_boor(knots, i + 1, p - 1, t)
    return out


def bspline_reference(control: np.ndarray, p: int, q: int, ku: np.ndarray, kv: np.ndarray,
                      u: np.ndarray, v: np.ndarray) -> np.ndarray:
    total = np.zeros((len(u), 3))
    for i in range(control.shape[0]):
        nu = cox_de_boor(ku, i, p, u)
        for j in range(control.shape[1]):
            total += (nu * cox_de_boor(kv, j, q, v))[:, None] * control[i, j]
    return total


def grid_error(surface: Surface, reference, tolerance: float, scale: float) -> tuple[float, int]:
    """Largest distance between the linear interpolant on the tessellation grid and the reference surface.

    The triangles are the grid cells' halves; each sample's parameters and position are the same barycentric
    combination of its corners', and the reference is evaluated at the interpolated parameters.
    """
    us, vs = surface.parameters(tolerance, scale)
    uu, vv = np.meshgrid(us, vs, indexing="ij")
    pts = reference(uu.ravel(), vv.ravel()).reshape(len(us), len(vs), 3)
    worst = 0.0
    for corners in (((0, 0), (1, 0), (1, 1)), ((0, 0), (1, 1), (0, 1))):
        cu = np.stack([uu[a:len(us) - 1 + a, b:len(vs) - 1 + b].ravel() for a, b in corners], axis=1)
        cv = np.stack([vv[a:len(us) - 1 + a, b:len(vs) - 1 + b].ravel() for a, b in corners], axis=1)
        cp = np.stack([pts[a:len(us) - 1 + a, b:len(vs) - 1 + b].reshape(-1, 3) for a, b in corners], axis=1)
        su, sv = (cu @ BARY.T).ravel(), (cv @ BARY.T).ravel()
        linear = np.einsum("sk,tkd->tsd", BARY, cp).reshape(-1, 3)
        worst = max(worst, float(np.linalg.norm(linear - reference(su, sv), axis=1).max()))
    return worst, 2 * (len(us) - 1) * (len(vs) - 1)


def oriented_and_closed(mesh: Mesh) -> None:
    directed = [(int(f[i]), int(f[(i + 1) % 3])) for f in mesh.faces for i in range(3)]
    assert len(set(directed)) == len(directed)
    assert mesh.is_closed()
    assert mesh.normals is not None
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0)
    # the winding agrees with the analytic normals at every face
    assert (np.einsum("ij,ij->i", mesh.face_normals(), mesh.normals[mesh.faces].sum(axis=1)) > 0).all()


# --- quadrics ------------------------------------------------------------------------------------------------

@settings(max_examples=15, deadline=None)
@given(st.floats(0.5, 50), st.floats(0.05, 1.0), st.floats(0.5, 20), st.tuples(*[st.floats(-5, 5)] * 3))
def test_sphere_within_tolerance(radius: float, tolerance: float, scale: float, center: tuple) -> None:
    mesh = Sphere(center, radius).tessellate(tolerance, scale)
    c = np.array(center)
    distance = np.abs(np.linalg.norm(triangle_samples(mesh) - c, axis=1) - radius)
    assert distance.max() <= tolerance / scale * (1 + 1e-9) + 1e-12
    np.testing.assert_allclose(np.linalg.norm(mesh.vertices - c, axis=1), radius)
    assert mesh.normals is not None
    np.testing.assert_allclose(mesh.normals, (mesh.vertices - c) / radius, atol=1e-9)


def test_sphere_mesh_is_closed_outward_and_poles_welded() -> None:
    s = Sphere((1, 2, 3), 2.0)
    mesh = s.tessellate(0.1, 10.0)
    oriented_and_closed(mesh)
    assert (np.einsum("ij,ij->i", mesh.face_normals(), mesh.vertices[mesh.faces].mean(axis=1) - [1, 2, 3]) > 0).all()
    poles = np.flatnonzero(np.abs(mesh.vertices[:, 2] - 3).round(9) == 2.0)
    assert len(poles) == 2  # one vertex per pole
    np.testing.assert_allclose(s.normal(0.3, [-math.pi / 2, 0, math.pi / 2]), [[0, 0, -1], [math.cos(0.3),
                               math.sin(0.3), 0], [0, 0, 1]], atol=1e-15)


def test_triangle_count_grows_as_tolerance_shrinks() -> None:
    for surface in (Sphere((0, 0, 0), 1.0), Torus((0, 0, 0), 3.0, 1.0), Ellipsoid((0, 0, 0), (3, 2, 1))):
        counts = [len(surface.tessellate(tol, 100.0).faces) for tol in (4.0, 1.0, 0.25)]
        assert counts[0] < counts[1] < counts[2]
        assert counts[2] > 3 * counts[1]  # about 4x: the step goes as sqrt(tolerance) in each direction


def test_torus_within_tolerance_and_outward() -> None:
    torus = Torus((0.5, 0, -1), 3.0, 1.2)
    mesh = torus.tessellate(0.2, 20.0)
    oriented_and_closed(mesh)
    x = triangle_samples(mesh) - [0.5, 0, -1]
    tube = np.hypot(np.hypot(x[:, 0], x[:, 1]) - 3.0, x[:, 2])
    assert np.abs(tube - 1.2).max() <= 0.2 / 20.0
    v = mesh.vertices - [0.5, 0, -1]
    ring = v * [1, 1, 0]
    ring = 3.0 * ring / np.linalg.norm(ring, axis=1)[:, None]
    assert mesh.normals is not None
    np.testing.assert_allclose(mesh.normals, (v - ring) / 1.2, atol=1e-9)
    assert len(mesh.vertices) - len(mesh.edges().pairs) + len(mesh.faces) == 0


def test_ellipsoid_grid_within_tolerance() -> None:
    radii = np.array([3.0, 2.0, 0.5])

    def reference(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return np.stack([3 * np.cos(v) * np.cos(u), 2 * np.cos(v) * np.sin(u), 0.5 * np.sin(v)], axis=1) + 1.0

    e = Ellipsoid((1, 1, 1), tuple(radii))
    worst, _ = grid_error(e, reference, 0.3, 40.0)
    assert worst <= 0.3 / 40.0
    mesh = e.tessellate(0.3, 40.0)
    oriented_and_closed(mesh)
    assert np.abs((((mesh.vertices - 1) / radii) ** 2).sum(axis=1) - 1).max() < 1e-12
    gradient = (mesh.vertices - 1) / radii**2
    assert mesh.normals is not None
    np.testing.assert_allclose(mesh.normals, gradient / np.linalg.norm(gradient, axis=1)[:, None], atol=1e-9)


def test_sphere_feature_edges_are_only_silhouettes() -> None:
    mesh = Sphere((0, 0, 0), 1.0).tessellate(0.5, 100.0)
    d = np.array([0.3, -0.5, 0.8])
    normals = np.cross(*(np.diff(mesh.vertices[mesh.faces], axis=1).transpose(1, 0, 2)))
    front = normals @ d > 0
    pairs, faces = mesh.feature_edges(front)
    assert len(pairs) > 20 and (faces >= 0).all()
    assert (front[faces[:, 0]] != front[faces[:, 1]]).all()  # every one a silhouette, none internal
    assert (np.bincount(pairs.ravel(), minlength=len(mesh.vertices)) % 2 == 0).all()  # closed loops
    ends = mesh.vertices[pairs.ravel()]
    assert np.abs(ends @ d / np.linalg.norm(d)).max() < 0.1  # near the great circle facing the view


# --- Bézier and B-spline patches -----------------------------------------------------------------------------

BEZ = np.array([
    [[0, 0, 0], [1, 0, 1], [2, 0, 0], [3, 0, 0.5]],
    [[0, 1, 1], [1, 1, 2], [2, 1, 1], [3, 1, 0]],
    [[0, 2, 0], [1, 2, -1], [2, 2, 0.5], [3, 2, 1]],
], dtype=float)


def test_bezier_against_de_casteljau() -> None:
    surface = BezierSurface(BEZ)
    rng = np.random.default_rng(1)
    u, v = rng.random(50), rng.random(50)
    np.testing.assert_allclose(surface.point(u, v), de_casteljau(BEZ, u, v), atol=1e-13)
    np.testing.assert_allclose(surface.point([0, 1, 0, 1], [0, 0, 1, 1]), BEZ[[0, -1, 0, -1], [0, 0, -1, -1]])
    h = 1e-6
    du = (de_casteljau(BEZ, u + h, v) - de_casteljau(BEZ, u - h, v)) / (2 * h)
    dv = (de_casteljau(BEZ, u, v + h) - de_casteljau(BEZ, u, v - h)) / (2 * h)
    n = np.cross(du, dv)
    np.testing.assert_allclose(surface.normal(u, v), n / np.linalg.norm(n, axis=1)[:, None], atol=1e-7)
    assert surface.point(np.zeros((2, 3)), 0.5).shape == (2, 3, 3)


@pytest.mark.parametrize(("tolerance", "scale"), [(0.5, 10.0), (0.1, 10.0), (0.25, 100.0)])
def test_bezier_tessellation_within_tolerance(tolerance: float, scale: float) -> None:
    surface = BezierSurface(BEZ)
    worst, count = grid_error(surface, lambda u, v: de_casteljau(BEZ, u, v), tolerance, scale)
    assert worst <= tolerance / scale
    mesh = surface.tessellate(tolerance, scale)
    assert len(mesh.faces) == count
    us, vs = surface.parameters(tolerance, scale)
    uu, vv = np.meshgrid(us, vs, indexing="ij")
    np.testing.assert_allclose(mesh.vertices, de_casteljau(BEZ, uu.ravel(), vv.ravel()), atol=1e-12)
    assert mesh.normals is not None
    assert (np.einsum("ij,ij->i", mesh.face_normals(), mesh.normals[mesh.faces].sum(axis=1)) > 0).all()


def test_bezier_collapsed_edge_is_welded() -> None:
    cone = BEZ.copy()
    cone[:, 0] = [1.5, 1.0, 3.0]  # the whole v = 0 edge is one apex
    mesh = BezierSurface(cone).tessellate(0.2, 10.0)
    assert (np.linalg.norm(mesh.vertices - [1.5, 1.0, 3.0], axis=1) < 1e-12).sum() == 1
    assert (mesh.face_areas() > 0).all()
    assert mesh.normals is not None and np.isfinite(mesh.normals).all()
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0)


NET = np.random.default_rng(7).normal(size=(6, 5, 3))
KNOTS_U = np.array([0, 0, 0, 1, 1, 2.5, 4, 4, 4], float)  # degree 2, a double interior knot (C0 there)
KNOTS_V = np.array([0, 0, 0, 0, 0.5, 2, 2, 2, 2], float)  # degree 3


@pytest.mark.parametrize(("degree", "knots"), [((2, 3), (KNOTS_U, KNOTS_V)), ((3, 3), None), ((1, 2), None)])
def test_bspline_against_cox_de_boor(degree: tuple[int, int], knots: tuple | None) -> None:
    p, q = degree
    if knots is None:  # open uniform: p + 1 zeros, 1, 2, ..., p + 1 copies of n - p
        knots = tuple(np.concatenate([np.zeros(d), np.arange(n - d + 1), np.full(d, n - d)]).astype(float)
                      for n, d in ((6, p), (5, q)))
    surface = BSplineSurface(NET, degree, knots)
    ku, kv = knots

    def reference(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return bspline_reference(NET, p, q, ku, kv, u, v)

    rng = np.random.default_rng(3)
    u = np.append(rng.uniform(ku[0], ku[-1], 40), [ku[0], ku[-1], 1.0])
    v = np.append(rng.uniform(kv[0], kv[-1], 40), [kv[-1], kv[0], kv[-1]])
    np.testing.assert_allclose(surface.point(u, v), reference(u, v), atol=1e-12)
    worst, count = grid_error(surface, reference, 0.2, 20.0)
    assert worst <= 0.2 / 20.0
    mesh = surface.tessellate(0.2, 20.0)
    assert len(mesh.faces) == count
    us, vs = surface.parameters(0.2, 20.0)
    assert set(np.unique(ku)) <= set(us.tolist()) and set(np.unique(kv)) <= set(vs.tolist())  # spans respected
    h = 1e-6
    uu, vv = np.clip(u[:40], ku[0] + h, ku[-1] - h), np.clip(v[:40], kv[0] + h, kv[-1] - h)
    n = np.cross((reference(uu + h, vv) - reference(uu - h, vv)), (reference(uu, vv + h) - reference(uu, vv - h)))
    on_knot = np.isin(np.round(uu, 5), ku) | np.isin(np.round(vv, 5), kv)
    expected = n / np.linalg.norm(n, axis=1)[:, None]
    np.testing.assert_allclose(surface.normal(uu, vv)[~on_knot], expected[~on_knot], atol=1e-5)


# --- errors --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: Sphere((0, 0, 0), -1.0), "radius must be > 0"),
        (lambda: Sphere((0, 0), 1.0), "center"),
        (lambda: Sphere((0, 0, math.nan), 1.0), "finite"),
        (lambda: Ellipsoid((0, 0, 0), (1, 0, 1)), r"radii\[1\]"),
        (lambda: Torus((0, 0, 0), 1.0, 1.0), "major > minor"),
        (lambda: BezierSurface(np.zeros((1, 3, 3))), r"R >= 2"),
        (lambda: BezierSurface(np.zeros((3, 3, 2))), r"\(R, C, 3\)"),
        (lambda: BezierSurface(np.where(np.arange(27).reshape(3, 3, 3) == 13, np.nan, 0.0)), r"control\[1, 1\]"),
        (lambda: BSplineSurface(NET, (6, 3)), "R >= 7"),
        (lambda: BSplineSurface(NET, (0, 3)), "degree"),
        (lambda: BSplineSurface(NET, 3), "pair"),  # type: ignore[arg-type]
        (lambda: BSplineSurface(NET, (2, 3), (KNOTS_U[:-1], KNOTS_V)), "need 9 knots"),
        (lambda: BSplineSurface(NET, (2, 3), (KNOTS_U[::-1], KNOTS_V)), "non-decreasing"),
        (lambda: BSplineSurface(NET, (2, 3), ([0, 0, 0, 1, 1, 1, 4, 4, 4], KNOTS_V)), "repeats more than"),
    ],
)
def test_construction_errors(make, match: str) -> None:
    with pytest.raises(InvalidArgument, match=match):
        make()


def test_tessellation_and_evaluation_errors(monkeypatch: pytest.MonkeyPatch) -> None:
    s = Sphere((0, 0, 0), 1.0)
    for tol, scale in ((0.0, 1.0), (-1.0, 1.0), (0.1, 0.0)):
        with pytest.raises(InvalidArgument, match="> 0"):
            s.tessellate(tol, scale)
    with pytest.raises(InvalidArgument, match="MAX_TRIANGLES"):
        s.tessellate(1e-9, 1.0)
    monkeypatch.setattr(surfaces, "MAX_TRIANGLES", 100)  # read at call time
    with pytest.raises(InvalidArgument, match="MAX_TRIANGLES = 100"):
        s.tessellate(0.01, 1.0)
    with pytest.raises(InvalidArgument, match="outside the domain"):
        BezierSurface(BEZ).point(1.5, 0.5)
    with pytest.raises(InvalidArgument, match=r"v = nan"):
        s.normal(0.0, math.nan)
    with pytest.raises(InvalidArgument, match="broadcast"):
        s.point([0, 1], [0, 1, 0.5])

"""Tests for pixelpen.geometry.mesh: meshes, edge tables, feature edges, polygon tables, plane equations."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.geometry.mesh import (
    Mesh,
    PolygonTable,
    classify_points,
    inside_convex,
    plane_equation,
    quad_mesh,
    triangle_strip,
)
from pixelpen.geometry.transforms3d import compose3d, reflect3d, rotate_axis, scale3d, translate3d

# The unit cube, vertex index 4x + 2y + z; each face counter-clockwise seen from outside (worked by hand).
CUBE_VERTICES = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
CUBE_FACES = [
    [0, 1, 3, 2],  # x = 0, normal -x
    [4, 6, 7, 5],  # x = 1, normal +x
    [0, 4, 5, 1],  # y = 0, normal -y
    [2, 3, 7, 6],  # y = 1, normal +y
    [0, 2, 6, 4],  # z = 0, normal -z
    [1, 5, 7, 3],  # z = 1, normal +z
]
CUBE_PLANES = np.array(
    [[-1, 0, 0, 0], [1, 0, 0, -1], [0, -1, 0, 0], [0, 1, 0, -1], [0, 0, -1, 0], [0, 0, 1, -1]], dtype=float
)


def cube() -> Mesh:
    return Mesh.from_polygons(CUBE_VERTICES, CUBE_FACES)


def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Divergence theorem: Σ v0 · (v1 × v2) / 6, positive when the faces wind counter-clockwise from outside."""
    v = vertices[faces]
    return float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6.0)


def directed_edges(faces: np.ndarray) -> list[tuple[int, int]]:
    return [(int(f[i]), int(f[(i + 1) % 3])) for f in faces for i in range(3)]


# --- Mesh basics ---------------------------------------------------------------------------------------------

def test_cube_from_polygons_fan_and_normals() -> None:
    m = cube()
    assert m.faces.shape == (12, 3)
    assert m.polygon.tolist() == [0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5]
    assert m.faces[:2].tolist() == [[0, 1, 3], [0, 3, 2]]  # fan (p0, p1, p2), (p0, p2, p3)
    np.testing.assert_allclose(m.face_normals(), np.repeat(CUBE_PLANES[:, :3], 2, axis=0))
    np.testing.assert_allclose(m.plane_equations(), np.repeat(CUBE_PLANES, 2, axis=0), atol=1e-15)
    np.testing.assert_allclose(m.face_areas(), 0.5)
    np.testing.assert_allclose(signed_volume(m.vertices, m.faces), 1.0)
    assert m.is_closed()
    lo, hi = m.bounds()
    assert lo.tolist() == [0, 0, 0] and hi.tolist() == [1, 1, 1]


def test_cube_edge_table() -> None:
    table = cube().edges()
    pairs = {tuple(p) for p in table.pairs.tolist()}
    assert len(table.pairs) == 18 == len(pairs)  # 12 cube edges + 6 diagonals
    assert (table.count == 2).all() and (table.faces >= 0).all()
    assert all(a < b for a, b in pairs)
    for (a, b), (f0, f1) in zip(table.pairs.tolist(), table.faces.tolist(), strict=True):
        for f in (f0, f1):
            assert {a, b} <= set(cube().faces[f].tolist())


def test_vertex_normals_area_weighted() -> None:
    # Two triangles sharing vertex 0: area 2 in z = 0 (normal +z) and area 1/2 in x = 0 (normal +x).
    v = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [0, 1, 0], [0, 0, 1]], float)
    m = Mesh(v, [[0, 1, 2], [0, 3, 4]])
    np.testing.assert_allclose(m.vertex_normals()[0], np.array([0.5, 0, 2]) / math.hypot(0.5, 2))
    given_normals = Mesh(v, [[0, 1, 2]], normals=np.tile([0, 0, 3.0], (5, 1)))
    np.testing.assert_allclose(given_normals.vertex_normals(), np.tile([0, 0, 1.0], (5, 1)))


def test_degenerate_faces() -> None:
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], float)
    m = Mesh(v, [[0, 1, 2], [0, 1, 3], [0, 0, 3]])  # collinear, fine, repeated index
    np.testing.assert_array_equal(m.face_normals(), [[0, 0, 0], [0, 0, 1], [0, 0, 0]])
    assert sorted(m.edges().faces[:, 0].tolist()) == [0, 0, 0, 1, 1]  # face 2 takes no part
    assert not m.is_closed()


def test_non_manifold_edge_is_reported() -> None:
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], float)
    m = Mesh(v, [[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    table = m.edges()
    rows = [i for i, p in enumerate(table.pairs.tolist()) if p == [0, 1]]
    assert len(rows) == 2 and (table.count[rows] == 3).all()
    assert sorted(table.faces[rows].ravel().tolist()) == [-1, 0, 1, 2]
    assert not m.is_closed()


def test_concatenate_offsets() -> None:
    a, b = cube(), cube().transformed(translate3d(3, 0, 0))
    both = Mesh.concatenate([a, b])
    assert both.faces[12:].min() == 8 and both.polygon[12:].tolist() == [6, 6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11]
    assert both.is_closed() and both.normals is None
    with_normals = Mesh.concatenate([a, Mesh(b.vertices, b.faces, normals=b.vertices - 3.5)])
    assert with_normals.normals is not None
    np.testing.assert_allclose(with_normals.normals[:8], a.vertex_normals())
    assert Mesh.concatenate([]).faces.shape == (0, 3)


def test_transformed_mirror_keeps_outward_normals() -> None:
    m = Mesh(CUBE_VERTICES, cube().faces, normals=CUBE_VERTICES - 0.5)
    mirrored = m.transformed(reflect3d("xy"))
    assert signed_volume(mirrored.vertices, mirrored.faces) == pytest.approx(1.0)
    assert mirrored.normals is not None
    np.testing.assert_allclose(mirrored.normals, (CUBE_VERTICES - 0.5) * [1, 1, -1] / math.sqrt(0.75))
    squashed = m.transformed(scale3d(2, 1, 1))  # normals by the inverse transpose: (x/2, y, z), renormalised
    expected = (CUBE_VERTICES - 0.5) * [0.5, 1, 1]
    assert squashed.normals is not None
    np.testing.assert_allclose(squashed.normals, expected / np.linalg.norm(expected, axis=1)[:, None])


# --- feature edges -------------------------------------------------------------------------------------------

def test_cube_feature_edges_generic_view() -> None:
    m = cube()
    front = m.face_normals() @ np.array([1.0, 2.0, 3.0]) > 0  # +x, +y, +z faces seen
    pairs, faces = m.feature_edges(front)
    # By hand: the hexagonal silhouette between seen and unseen faces, and the three creases at (1, 1, 1).
    silhouette = {(4, 5), (4, 6), (2, 6), (2, 3), (1, 3), (1, 5)}
    creases = {(5, 7), (6, 7), (3, 7)}
    assert {tuple(p) for p in pairs.tolist()} == silhouette | creases and len(pairs) == 9
    assert {tuple(p) for p in m.feature_edges(front, crease_angle=math.pi)[0].tolist()} == silhouette
    assert {tuple(p) for p in m.feature_edges(front, outlines=True)[0].tolist()} == silhouette | creases
    for f0, f1 in faces.tolist():
        assert m.polygon[f0] != m.polygon[f1]


def test_feature_edges_from_an_axis_and_open_boundaries() -> None:
    m = cube()
    front = m.face_normals() @ np.array([1.0, 0, 0]) > 0  # only x = 1; its neighbours are edge-on (back)
    assert {tuple(p) for p in m.feature_edges(front)[0].tolist()} == {(4, 5), (4, 6), (6, 7), (5, 7)}
    square = Mesh.from_polygons(CUBE_VERTICES, [CUBE_FACES[1]])  # an open quad: boundary edges of front faces
    assert len(square.feature_edges(np.array([True, True]))[0]) == 4
    assert len(square.feature_edges(np.array([False, False]))[0]) == 0


def test_feature_edges_errors() -> None:
    with pytest.raises(InvalidArgument, match="front"):
        cube().feature_edges(np.ones(11, bool))
    with pytest.raises(InvalidArgument, match="front"):
        cube().feature_edges(np.ones(12))
    with pytest.raises(InvalidArgument, match="crease_angle"):
        cube().feature_edges(np.ones(12, bool), crease_angle=4.0)


# --- hypothesis: closed meshes -------------------------------------------------------------------------------

def bumpy_torus(rows: int, cols: int, bumps: np.ndarray) -> np.ndarray:
    u = np.linspace(0, 2 * np.pi, rows, endpoint=False)[:, None]
    v = np.linspace(0, 2 * np.pi, cols, endpoint=False)[None, :]
    r = 0.5 + 0.5 * bumps
    ring = 3.0 + r * np.cos(v)
    return np.stack([ring * np.cos(u), ring * np.sin(u), r * np.sin(v)], axis=2)


@settings(max_examples=40, deadline=None)
@given(st.integers(3, 9), st.integers(3, 9), st.integers(0, 2**32 - 1), st.booleans())
def test_closed_mesh_invariants(rows: int, cols: int, seed: int, mirror: bool) -> None:
    rng = np.random.default_rng(seed)
    m = quad_mesh(bumpy_torus(rows, cols, rng.random((rows, cols))), closed_u=True, closed_v=True)
    if mirror:
        m = m.transformed(compose3d(reflect3d("yz"), rotate_axis((0, 0, 0), tuple(rng.normal(size=3)), 1.0)))
    table = m.edges()
    assert m.is_closed() and (table.faces >= 0).all()
    assert len(m.vertices) - len(table.pairs) + len(m.faces) == 0  # Euler characteristic of a torus
    directed = directed_edges(m.faces)
    assert len(set(directed)) == len(directed)  # consistent orientation: each directed edge once
    assert signed_volume(m.vertices, m.faces) > 0  # outward
    # silhouettes (each triangle its own polygon, so quad diagonals count): every vertex meets an even number
    front = m.face_normals() @ rng.normal(size=3) > 0
    pairs, _ = Mesh(m.vertices, m.faces).feature_edges(front, crease_angle=math.pi)
    assert (np.bincount(pairs.ravel(), minlength=len(m.vertices)) % 2 == 0).all()


# --- errors --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize(
    ("vertices", "faces", "kwargs", "error", "match"),
    [
        (CUBE_VERTICES, [[0, 1, 8]], {}, InvalidArgument, r"faces\[0\] refers to vertex 8"),
        (CUBE_VERTICES, [[0, 1, 2], [0, -1, 2]], {}, InvalidArgument, r"faces\[1\] refers to vertex -1"),
        (CUBE_VERTICES, [[0, 1, 2, 3]], {}, InvalidArgument, r"faces must be an \(M, 3\)"),
        (CUBE_VERTICES, [[0.0, 1.0, 2.0]], {}, InvalidArgumentType, "integer"),
        (np.vstack([CUBE_VERTICES[:7], [[np.nan, 0, 0]]]), [[0, 1, 2]], {}, InvalidArgument, "row 7"),
        (CUBE_VERTICES[:, :2], [[0, 1, 2]], {}, InvalidArgument, "vertices"),
        (CUBE_VERTICES, [[0, 1, 2]], {"polygon": [0, 1]}, InvalidArgument, "one id per face"),
        (CUBE_VERTICES, [[0, 1, 2]], {"normals": np.zeros((8, 3))}, InvalidArgument, r"normals\[0\]"),
        (CUBE_VERTICES, [[0, 1, 2]], {"normals": np.ones((7, 3))}, InvalidArgument, "one row per vertex"),
    ],
)
def test_mesh_errors(vertices: object, faces: object, kwargs: dict, error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        Mesh(vertices, faces, **kwargs)  # type: ignore[arg-type]


def test_from_polygons_errors() -> None:
    with pytest.raises(InvalidArgument, match=r"polygons\[1\] has 2 vertices"):
        Mesh.from_polygons(CUBE_VERTICES, [[0, 1, 2], [3, 4]])
    with pytest.raises(InvalidArgument, match=r"polygons\[1\] refers to vertex 9"):
        Mesh.from_polygons(CUBE_VERTICES, [[0, 1, 2], [3, 4, 9]])
    with pytest.raises(InvalidArgumentType, match="polygons"):
        Mesh.from_polygons(CUBE_VERTICES, 7)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="empty mesh"):
        Mesh(np.zeros((0, 3)), []).bounds()
    assert Mesh.from_polygons(CUBE_VERTICES, np.array(CUBE_FACES)).faces.tolist() == cube().faces.tolist()


# --- polygon tables ------------------------------------------------------------------------------------------

def test_cube_polygon_table() -> None:
    table = PolygonTable(CUBE_VERTICES, CUBE_FACES)
    assert table.problems() == []
    table.check()
    assert len(table.edges) == 12 and (table.edge_count == 2).all() and (table.edge_polygons >= 0).all()
    # Edge 1-3 (x = 0, z = 1) lies on faces x = 0 (polygon 0) and z = 1 (polygon 5).
    e13 = table.edges.tolist().index([1, 3])
    assert sorted(table.edge_polygons[e13].tolist()) == [0, 5]
    sides = table.polygon_edges[table.polygon_starts[0]:table.polygon_starts[0] + 4]
    assert [sorted(p) for p in table.edges[sides].tolist()] == [[0, 1], [1, 3], [2, 3], [0, 2]]
    np.testing.assert_allclose(table.plane_equations(), CUBE_PLANES, atol=1e-15)
    mesh = table.to_mesh()
    assert mesh.is_closed() and len(mesh.faces) == 12


@pytest.mark.parametrize(
    ("vertices", "polygons", "kind"),
    [
        (CUBE_VERTICES, [*CUBE_FACES[:5], [1, 5, 7, 9]], "bad index"),
        (CUBE_VERTICES, [*CUBE_FACES, [0, 1]], "too few vertices"),
        (CUBE_VERTICES, [*CUBE_FACES[:5], [1, 5, 7, 5, 3]], "repeated vertex"),
        (np.vstack([CUBE_VERTICES, [[1, 1, 1]]]), [*CUBE_FACES[:5], [1, 5, 7, 8, 3]], "zero-length edge"),
        (np.vstack([CUBE_VERTICES, [[5, 5, 5]]]), CUBE_FACES, "unused vertex"),
        (CUBE_VERTICES, [*CUBE_FACES, [0, 1, 5]], "edge in more than two polygons"),
        (CUBE_VERTICES * [1, 1, 1] + np.where(np.arange(8) == 7, 0.1, 0)[:, None] * [0, 0, 1], CUBE_FACES,
         "non-planar"),
        (CUBE_VERTICES, [*CUBE_FACES[:5], [1, 3, 7, 5]], "inconsistent orientation"),
        (np.vstack([CUBE_VERTICES, [[2, 0, 0]]]), [[0, 4, 8]], "zero area"),
    ],
)
def test_polygon_table_problems(vertices: np.ndarray, polygons: list, kind: str) -> None:
    table = PolygonTable(vertices, polygons)
    assert any(p.startswith(kind + ":") for p in table.problems()), table.problems()
    with pytest.raises(InvalidArgument, match=kind):
        table.check()


def test_polygon_table_lists_at_most_ten_per_kind() -> None:
    table = PolygonTable(np.vstack([CUBE_VERTICES, np.zeros((25, 3))]), CUBE_FACES)
    unused = [p for p in table.problems() if p.startswith("unused vertex")]
    assert len(unused) == 11 and unused[-1] == "unused vertex: and 15 more"


def test_polygon_table_to_mesh_needs_valid_indices() -> None:
    with pytest.raises(InvalidArgument, match="refers to vertex 9"):
        PolygonTable(CUBE_VERTICES, [[0, 1, 9]]).to_mesh()
    with pytest.raises(InvalidArgument, match="at least 3"):
        PolygonTable(CUBE_VERTICES, [[0, 1]]).plane_equations()


# --- planes and inside/outside -------------------------------------------------------------------------------

def test_plane_equation_newell() -> None:
    # x + y + z = 1 through the unit points, counter-clockwise seen from (1, 1, 1): A = B = C = 1/sqrt 3.
    expected = np.array([1, 1, 1, -1]) / math.sqrt(3)
    np.testing.assert_allclose(plane_equation([[1, 0, 0], [0, 1, 0], [0, 0, 1]]), expected)
    square = [[0, 0, 2], [1, 0, 2], [1, 1, 2], [0, 1, 2]]
    np.testing.assert_allclose(plane_equation(square), [0, 0, 1, -2])
    np.testing.assert_allclose(plane_equation(square[::-1]), [0, 0, -1, 2])
    # A slightly non-planar quad: Newell's sums by hand give (A, B, C) = (-0.2, -0.2, 2) before normalising.
    bent = [[0, 0, 0], [1, 0, 0], [1, 1, 0.2], [0, 1, 0]]
    n = np.array([-0.2, -0.2, 2.0]) / math.sqrt(4.08)
    np.testing.assert_allclose(plane_equation(bent), [*n, -n @ np.mean(bent, axis=0)])
    with pytest.raises(InvalidArgument, match="no plane"):
        plane_equation([[0, 0, 0], [1, 1, 1], [2, 2, 2]])
    with pytest.raises(InvalidArgument, match="at least 3"):
        plane_equation([[0, 0, 0], [1, 1, 1]])


def test_classify_hearn_baker_sign_convention() -> None:
    plane = [0, 0, 2, -2]  # z = 1 with normal +z (outward of the unit cube), not unit: scaled first
    points = [[0.5, 0.5, 0.5], [0.5, 0.5, 1.0], [0.5, 0.5, 3.0], [0, 0, 1.0005]]
    assert classify_points(plane, points).tolist() == [-1, 0, 1, 1]
    assert classify_points(plane, points, tol=1e-3).tolist() == [-1, 0, 1, 0]
    inside = inside_convex(CUBE_PLANES, [[0.5, 0.5, 0.5], [1, 1, 1], [1.1, 0.5, 0.5], [-1e-9, 0.5, 0.5]])
    assert inside.tolist() == [True, True, False, False]
    with pytest.raises(InvalidArgument, match="zero normal"):
        classify_points([0, 0, 0, 1], points)
    with pytest.raises(InvalidArgument, match="planes"):
        inside_convex(np.ones((2, 3)), points)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_inside_convex_matches_box_test(seed: int) -> None:
    rng = np.random.default_rng(seed)
    lo, size = rng.normal(size=3), rng.random(3) + 0.1
    m = cube().transformed(compose3d(translate3d(*lo), scale3d(*size)))
    planes = PolygonTable(m.vertices, CUBE_FACES).plane_equations()
    pts = lo + size * (rng.random((200, 3)) * 1.4 - 0.2)
    expected = ((pts >= lo - 1e-12) & (pts <= lo + size + 1e-12)).all(axis=1)
    assert (inside_convex(planes, pts, tol=1e-12) == expected).all()


# --- strips and quad meshes ----------------------------------------------------------------------------------

def test_triangle_strip_windings() -> None:
    v = np.array([[0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0], [2, 0, 0], [2, 1, 0]], float)
    m = triangle_strip(v, [1, 0, 3, 2, 5, 4])
    assert m.faces.tolist() == [[1, 0, 3], [3, 0, 2], [3, 2, 5], [5, 2, 4]]
    np.testing.assert_allclose(m.face_normals(), np.tile([0, 0, 1.0], (4, 1)))
    # the two degenerate triangles are dropped; the 4th keeps its odd parity: (3, 2, 5) -> (2, 3, 5)
    assert triangle_strip(v, [1, 0, 3, 3, 2, 5]).faces.tolist() == [[1, 0, 3], [2, 3, 5]]
    with pytest.raises(InvalidArgument, match="at least 3"):
        triangle_strip(v, [0, 1])
    with pytest.raises(InvalidArgument, match=r"indices\[2\] refers to vertex 6"):
        triangle_strip(v, [0, 1, 6])


def test_quad_mesh_plane_and_cylinder() -> None:
    grid = np.array([[[r, c, 0.0] for c in range(4)] for r in range(3)])  # P_u = +x, P_v = +y
    m = quad_mesh(grid)
    assert m.faces.shape == (12, 3) and m.polygon.tolist() == [i // 2 for i in range(12)]
    assert m.faces[:2].tolist() == [[0, 4, 5], [0, 5, 1]]
    np.testing.assert_allclose(m.face_normals(), np.tile([0, 0, 1.0], (12, 1)))
    outline = m.feature_edges(np.ones(12, bool), outlines=True)[0]
    assert len(outline) == 17  # the grid lines: 3 x 3 + 2 x 4, no diagonals
    theta = np.linspace(0, 2 * np.pi, 6, endpoint=False)
    tube = np.stack(np.broadcast_arrays(np.cos(theta)[None], np.sin(theta)[None], np.arange(3.0)[:, None]), axis=2)
    cyl = quad_mesh(tube, closed_v=True)
    assert len(cyl.faces) == 2 * 2 * 6 and (cyl.edges().count <= 2).all()
    assert (cyl.edges().faces[:, 1] == -1).sum() == 12  # the two rims
    with pytest.raises(InvalidArgument, match="grid"):
        quad_mesh(np.zeros((1, 4, 3)))

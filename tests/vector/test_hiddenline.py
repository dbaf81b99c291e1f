"""Tests of hidden-line removal: pieces checked by independent ray casting, and hand-solved scenes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.vector import hiddenline
from pixelpen.vector.hiddenline import HiddenLines, hidden_lines

# ---------------------------------------------------------------- scenes written for the tests


def look_at(eye: np.ndarray, size: float = 1000.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Camera basis (right, up, forward) looking from ``eye`` at the origin, z up."""
    forward = -eye / np.linalg.norm(eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    return right, np.cross(right, forward), forward


def perspective(points: np.ndarray, eye: np.ndarray, near: float = 1.0, far: float = 30.0) -> np.ndarray:
    """Device x, y and NDC depth (0 near .. 1 far, affine in 1/w so planar in screen space) of world points."""
    right, up, forward = look_at(eye)
    rel = points - eye
    w = rel @ forward
    z = (1 / near - 1 / w) / (1 / near - 1 / far)
    return np.stack([500 + 600 * (rel @ right) / w, 500 + 600 * (rel @ up) / w, z], axis=-1)


def torus(nu: int, nv: int, major: float = 2.0, minor: float = 0.8):
    """Torus quad grid: vertices, triangles (two per quad) and every quad side with its two triangles."""
    u, v = np.meshgrid(np.arange(nu) * 2 * np.pi / nu, np.arange(nv) * 2 * np.pi / nv, indexing="ij")
    ring = major + minor * np.cos(v)
    vertices = np.stack([ring * np.cos(u), ring * np.sin(u), minor * np.sin(v)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    vid = lambda a, b: (a % nu) * nv + b % nv
    quads = nu * nv
    a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    # quad (i, j) is triangles vid(i, j) (sides ab, bc) and quads + vid(i, j) (sides cd, da)
    sides_u = np.stack([vid(i, j), vid(i + 1, j)], -1).reshape(-1, 2)  # side ab of quad (i, j), cd of (i, j - 1)
    faces_u = np.stack([vid(i, j), quads + vid(i, j - 1)], -1).reshape(-1, 2)
    sides_v = np.stack([vid(i, j), vid(i, j + 1)], -1).reshape(-1, 2)  # side da of quad (i, j), bc of (i - 1, j)
    faces_v = np.stack([quads + vid(i, j), vid(i - 1, j)], -1).reshape(-1, 2)
    return vertices, faces, np.concatenate([sides_u, sides_v]), np.concatenate([faces_u, faces_v])


CUBE = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)  # vertex 4x + 2y + z
CUBE_QUADS = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]  # CCW outside
CUBE_EDGES = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]


def cube_mesh() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cube triangles (two per face), its 12 edges and the two triangles on each edge."""
    faces = np.array([t for a, b, c, d in CUBE_QUADS for t in ((a, b, c), (a, c, d))])
    edge_faces = []
    for a, b in CUBE_EDGES:
        on = [k for k, (p, q, r, s) in enumerate(CUBE_QUADS) if {a, b} <= {p, q, r, s}]
        # the triangle of each quad that holds the edge
        edge_faces.append([2 * k + (0 if {a, b} <= set(faces[2 * k]) else 1) for k in on])
    return faces, np.array(CUBE_EDGES), np.array(edge_faces)


# ---------------------------------------------------------------- independent references


def screen_hidden(tris, edges, edge_faces, t, eps=hiddenline.DEFAULT_EPS):
    """Ray casting in screen space: (E, S) hidden flags at parameters ``t`` (S,) by brute force over triangles.

    Barycentric coordinates by Cramer's rule; a point is hidden when strictly inside some triangle not on its
    edge whose interpolated depth is nearer by more than eps.
    """
    pts = edges[:, None, 0] + t[None, :, None] * (edges[:, None, 1] - edges[:, None, 0])  # (E, S, 3)
    a, b, c = (tris[:, k] for k in range(3))
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    px, py = pts[..., 0, None], pts[..., 1, None]  # (E, S, 1) against (T,)
    with np.errstate(divide="ignore", invalid="ignore"):
        l1 = ((px - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (py - a[:, 1])) / det
        l2 = ((b[:, 0] - a[:, 0]) * (py - a[:, 1]) - (px - a[:, 0]) * (b[:, 1] - a[:, 1])) / det
    l0 = 1 - l1 - l2
    inside = (l0 > 0) & (l1 > 0) & (l2 > 0) & (det != 0)
    depth = l0 * a[:, 2] + l1 * b[:, 2] + l2 * c[:, 2]
    own = np.zeros((len(edges), len(tris)), bool)
    for k in range(2):
        rows = np.flatnonzero(edge_faces[:, k] >= 0)
        own[rows, edge_faces[rows, k]] = True
    return (inside & (depth < pts[..., 2, None] - eps) & ~own[:, None, :]).any(axis=2)


def world_hidden(vertices, faces, edges, edge_faces, eye, t):
    """Ray casting in world space (Möller–Trumbore from the eye): (E, S) hidden flags at world parameters ``t``."""
    pts = vertices[edges[:, None, 0]] + t[None, :, None] * (vertices[edges[:, None, 1]] - vertices[edges[:, None, 0]])
    d = (pts - eye)[..., None, :]  # rays eye + s·d reach the point at s = 1
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    e1, e2 = v1 - v0, v2 - v0
    h = np.cross(d, e2)
    det = (h * e1).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = 1 / det
        s_vec = eye - v0
        u = f * (s_vec * h).sum(-1)
        q = np.cross(s_vec, e1)
        v = f * (d * q).sum(-1)
        s = f * (e2 * q).sum(-1)
    hit = (np.abs(det) > 1e-15) & (u > 0) & (v > 0) & (u + v < 1) & (s > 0) & (s < 1 - 1e-9)
    own = np.zeros((len(edges), len(faces)), bool)
    own[np.arange(len(edges))[:, None], edge_faces] = True
    return (hit & ~own[:, None, :]).any(axis=2)


def piece_params(out: HiddenLines, edges: np.ndarray) -> np.ndarray:
    """(K, 2) parameters of each piece's ends along its source edge; checks the pieces lie on their edges."""
    p, q = edges[out.edge, 0, :2], edges[out.edge, 1, :2]
    d = q - p
    t = ((out.segments - p[:, None]) * d[:, None]).sum(-1) / (d * d).sum(-1)[:, None]
    on_line = p[:, None] + t[..., None] * d[:, None]
    np.testing.assert_allclose(out.segments, on_line, atol=1e-9 * (1 + np.abs(edges).max()))
    assert np.all(t[:, 0] < t[:, 1]) and t.min() >= -1e-12 and t.max() <= 1 + 1e-12
    return t


def assert_matches(out: HiddenLines, edges: np.ndarray, hidden: np.ndarray, ts: np.ndarray, margin: float) -> int:
    """Samples at screen parameters ``ts`` (S,) or (E, S) further than ``margin`` from a piece end are visible iff
    inside a piece; returns the number of samples compared."""
    params = piece_params(out, edges)
    ts = np.broadcast_to(ts, hidden.shape)
    used = 0
    for e in range(len(edges)):
        t = ts[e]
        mine = params[out.edge == e]
        assert np.all(mine[1:, 0] >= mine[:-1, 1]), f"edge {e}: pieces overlap or are unsorted"
        ends = mine.ravel()
        near_end = (np.abs(t[:, None] - ends[None, :]) < margin).any(axis=1) if len(ends) else np.zeros(len(t), bool)
        inside = ((t[:, None] > mine[None, :, 0]) & (t[:, None] < mine[None, :, 1])).any(axis=1)
        bad = ~near_end & (inside == hidden[e])
        assert not bad.any(), f"edge {e}: samples {t[bad].tolist()} disagree (hidden: {hidden[e, bad].tolist()})"
        used += int((~near_end).sum())
    return used


# ---------------------------------------------------------------- checks against ray casting


@pytest.mark.parametrize("seed", range(6))
def test_random_triangle_soup_matches_screen_ray_casting(seed):
    rng = np.random.default_rng(seed)
    n = 40
    centre = rng.uniform(0, 100, (n, 1, 2))
    tris = np.concatenate([centre + rng.uniform(-25, 25, (n, 3, 2)), rng.uniform(0, 1, (n, 3, 1))], axis=2)
    stray = np.concatenate([rng.uniform(0, 100, (30, 2, 2)), rng.uniform(0, 1, (30, 2, 1))], axis=2)
    own = tris[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2, 3)  # every triangle side, lying on its triangle
    edges = np.concatenate([own, stray])
    edge_faces = np.full((len(edges), 2), -1)
    edge_faces[: 3 * n, 0] = np.repeat(np.arange(n), 3)
    out = hidden_lines(tris, edges, edge_faces)
    t = (np.arange(48) + rng.uniform(0.1, 0.9, 48)) / 48
    hidden = screen_hidden(tris, edges, edge_faces, t)
    used = assert_matches(out, edges, hidden, t, margin=1e-6)
    assert used > 0.95 * hidden.size and 0.1 < hidden.mean() < 0.9  # the scenes really hide things


@pytest.mark.parametrize("eye", [(0.3, -7.0, 4.0), (5.0, 3.0, 1.5), (0.3, 0.2, 8.0), (-6.1, 0.4, -0.2)])
def test_torus_matches_world_ray_casting(eye):
    eye = np.array(eye)
    vertices, faces, edges, edge_faces = torus(18, 9)
    screen = perspective(vertices, eye)
    out = hidden_lines(screen[faces], screen[edges], edge_faces)
    t = (np.arange(10) + 0.5) / 10 + 0.01
    hidden = world_hidden(vertices, faces, edges, edge_faces, eye, t)
    # the world parameter t of each sample, as a parameter along the projected edge
    p, q = vertices[edges[:, 0]], vertices[edges[:, 1]]
    seen = perspective(p[:, None] + t[None, :, None] * (q - p)[:, None], eye)[..., :2]
    a, d = screen[edges[:, 0], :2], screen[edges[:, 1], :2] - screen[edges[:, 0], :2]
    ts = ((seen - a[:, None]) * d[:, None]).sum(-1) / (d * d).sum(-1)[:, None]
    assert_matches(out, screen[edges], hidden, ts, margin=1e-4)
    assert 0.2 < hidden.mean() < 0.9
    assert out.stats.hidden_fraction == pytest.approx(1 - visible_length(out) / total_length(screen[edges]))


def visible_length(out: HiddenLines) -> float:
    return float(np.linalg.norm(out.segments[:, 1] - out.segments[:, 0], axis=1).sum())


def total_length(edges: np.ndarray) -> float:
    return float(np.linalg.norm(edges[:, 1, :2] - edges[:, 0, :2], axis=1).sum())


def test_torus_edge_faces_hold_their_edges():
    _, faces, edges, edge_faces = torus(7, 5)
    assert all({a, b} <= set(faces[f]) for (a, b), pair in zip(edges, edge_faces, strict=True) for f in pair)


def test_chunking_does_not_change_the_result(monkeypatch):
    vertices, faces, edges, edge_faces = torus(16, 8)
    screen = perspective(vertices, np.array([4.0, -5.0, 3.0]))
    whole = hidden_lines(screen[faces], screen[edges], edge_faces)
    monkeypatch.setattr(hiddenline, "PAIR_CHUNK", 7)
    chunked = hidden_lines(screen[faces], screen[edges], edge_faces)
    np.testing.assert_array_equal(whole.segments, chunked.segments)
    np.testing.assert_array_equal(whole.edge, chunked.edge)
    assert whole.stats == chunked.stats


def test_silhouettes_of_a_torus_are_kept_and_pieces_join():
    vertices, faces, edges, edge_faces = torus(32, 16)
    eye = np.array([0.0, -7.0, 4.0])
    screen = perspective(vertices, eye)
    normal = np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]])
    front = ((eye - vertices[faces[:, 0]]) * normal).sum(1) > 0
    silhouette = front[edge_faces[:, 0]] != front[edge_faces[:, 1]]
    out = hidden_lines(screen[faces], screen[edges], edge_faces)
    visible_edges = set(out.edge.tolist())
    # the outer rim of the torus is never hidden
    rim = silhouette & (np.linalg.norm(vertices[edges[:, 0], :2], axis=1) > 2.5)
    assert rim.sum() > 10 and visible_edges >= set(np.flatnonzero(rim).tolist())
    assert out.stats.pairs_tested < 0.05 * len(edges) * len(faces)  # the bins keep pairs near each other only
    lines = out.polylines()
    assert len(lines) < len(out.segments)
    assert sum(float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) for p in lines) == pytest.approx(
        visible_length(out)
    )


# ---------------------------------------------------------------- scenes solved by hand


X0, X1, Y1, Z1 = {0, 1, 2, 3}, {4, 5, 6, 7}, {2, 3, 6, 7}, {1, 3, 5, 7}  # vertices of four faces


@pytest.mark.parametrize(
    ("eye", "front"),
    [((3.0, 4.0, 5.0), [X1, Y1, Z1]), ((-2.5, 3.5, 4.0), [X0, Y1, Z1]), ((0.5, 3.0, 4.0), [Y1, Z1])],
)
def test_cube_shows_exactly_the_edges_of_its_front_faces(eye, front):
    # the faces listed face the viewer (by hand: the eye is beyond those planes); exactly the edges of those
    # faces are drawn, each whole: the three at the far corner (or five, from (0.5, 3, 4)) are hidden
    faces, edges, edge_faces = cube_mesh()
    screen = perspective(CUBE, np.array(eye))
    out = hidden_lines(screen[faces], screen[edges], edge_faces)
    expected = [k for k, (a, b) in enumerate(CUBE_EDGES) if any({a, b} <= f for f in front)]
    assert len(expected) == (9 if len(front) == 3 else 7)
    assert out.edge.tolist() == expected  # one piece per visible edge, nothing of the others
    np.testing.assert_array_equal(out.segments, screen[edges[expected]][:, :, :2])  # whole, exact endpoints
    assert out.stats.edges_in == 12 and out.stats.pieces_out == len(expected)


def test_cube_polylines_cover_the_visible_edges():
    faces, edges, edge_faces = cube_mesh()
    screen = perspective(CUBE, np.array([3.0, 4.0, 5.0]))
    out = hidden_lines(screen[faces], screen[edges], edge_faces)
    lines = out.polylines()
    assert sum(len(p) - 1 for p in lines) == 9 and len(lines) <= 4
    drawn = {tuple(sorted((tuple(p[k]), tuple(p[k + 1])))) for p in lines for k in range(len(p) - 1)}
    assert drawn == {tuple(sorted((tuple(s[0]), tuple(s[1])))) for s in out.segments}


def quad(x0, y0, x1, y1, z):
    """Two triangles of an axis-aligned rectangle at constant depth, and its four sides."""
    c = np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]], float)
    return c[[[0, 1, 2], [0, 2, 3]]], c[[[0, 1], [1, 2], [2, 3], [3, 0]]]


def test_overlapping_quads_hide_exactly_the_overlap():
    near_tris, near_sides = quad(0, 0, 10, 10, 0.2)
    far_tris, far_sides = quad(5, 5, 15, 15, 0.6)
    faces = np.array([[0, -1], [0, -1], [1, -1], [1, -1], [2, -1], [2, -1], [3, -1], [3, -1]])
    out = hidden_lines(np.concatenate([near_tris, far_tris]), np.concatenate([near_sides, far_sides]), faces)
    expected = [
        [[0, 0], [10, 0]], [[10, 0], [10, 10]], [[10, 10], [0, 10]], [[0, 10], [0, 0]],  # near quad: whole
        [[10, 5], [15, 5]], [[15, 5], [15, 15]], [[15, 15], [5, 15]], [[5, 15], [5, 10]],  # far: not behind it
    ]
    assert out.edge.tolist() == list(range(8))
    np.testing.assert_allclose(out.segments, expected, atol=1e-12)
    assert out.stats.hidden_fraction == pytest.approx(10 / 80)


def test_overlapping_quads_swapped_depths():
    near_tris, near_sides = quad(5, 5, 15, 15, 0.2)
    far_tris, far_sides = quad(0, 0, 10, 10, 0.6)
    out = hidden_lines(np.concatenate([near_tris, far_tris]), np.concatenate([near_sides, far_sides]), None)
    assert out.edge.tolist() == [0, 1, 2, 3, 4, 5, 6, 7]
    np.testing.assert_allclose(out.segments[4:], [[[0, 0], [10, 0]], [[10, 0], [10, 5]], [[5, 10], [0, 10]],
                                                  [[0, 10], [0, 0]]], atol=1e-12)


@pytest.mark.parametrize(
    ("edge", "visible"),
    [
        ([[-5, 3], [15, 7]], [[[-5, 3], [0, 4]], [[10, 6], [15, 7]]]),  # crosses the diagonal
        ([[-5, -5], [15, 15]], [[[-5, -5], [0, 0]], [[10, 10], [15, 15]]]),  # runs along the diagonal
        ([[-5, 15], [15, -5]], [[[-5, 15], [0, 10]], [[10, 0], [15, -5]]]),  # through the two other corners
        ([[0, 0], [10, 10]], []),  # is the diagonal
    ],
)
def test_triangles_sharing_a_side_hide_without_a_gap(edge, visible):
    tris, _ = quad(0, 0, 10, 10, 0.2)  # split along its diagonal (0, 0)–(10, 10)
    behind = np.concatenate([np.array(edge, float), [[0.7], [0.7]]], axis=1)[None]
    out = hidden_lines(tris, behind, None)
    assert out.segments.tolist() == visible


@pytest.mark.parametrize("tilt", [0.0, 0.003])
def test_edge_piercing_a_triangle_is_hidden_only_behind_it(tilt):
    # triangle covering x in [-5, 25] along y = 0 at depth 0.5 (+ tilt·y); the edge runs from x = −10 at depth
    # 0.9 (behind) to x = 10 at depth 0.1 (in front), piercing the plane at x = 0
    tri = np.array([[[-5, -10, 0.5 - 10 * tilt], [-5, 10, 0.5 + 10 * tilt], [25, 0, 0.5]]])
    edge = np.array([[[-10, 0, 0.9], [10, 0, 0.1]]])
    out = hidden_lines(tri, edge, None)
    np.testing.assert_allclose(out.segments, [[[-10, 0], [-5, 0]], [[0, 0], [10, 0]]], atol=1e-6)
    reversed_out = hidden_lines(tri, edge[:, ::-1], None)
    np.testing.assert_allclose(reversed_out.segments, [[[10, 0], [0, 0]], [[-5, 0], [-10, 0]]], atol=1e-6)


def test_own_faces_never_hide_and_coplanar_faces_tie():
    tri = np.array([[[0, 0, 0.5], [10, 0, 0.5], [0, 10, 0.5]]], float)
    edge = np.array([[[1, 1, 0.7], [5, 2, 0.7]]])  # behind the triangle, inside it in 2D
    assert len(hidden_lines(tri, edge, None).segments) == 0
    assert len(hidden_lines(tri, edge, [[0, -1]]).segments) == 1  # the triangle is one of its faces
    on_plane = np.array([[[1, 1, 0.5], [5, 2, 0.5]]])
    farther = np.array([0.0, 0.0, 1.0])
    assert len(hidden_lines(tri, on_plane, None).segments) == 1  # a depth tie does not hide
    assert len(hidden_lines(tri, on_plane + 1e-12 * farther, None).segments) == 1  # nor a tie within eps
    assert len(hidden_lines(tri, on_plane + 1e-6 * farther, None).segments) == 0
    assert len(hidden_lines(tri, on_plane + 1e-6 * farther, None, eps=1e-5).segments) == 1


def test_degenerate_triangles_hide_nothing():
    edge = np.array([[[0, 0, 0.9], [10, 10, 0.9]]])
    tris = np.array([
        [[0, 10, 0.1], [10, 0, 0.1], [5, 5, 0.1]],  # collinear, crossing the edge
        [[5, 5, 0.1], [5, 5, 0.1], [5, 5, 0.1]],  # one point on the edge
        [[2, 2, 0.1], [8, 8, 0.2], [2, 2, 0.3]],  # a repeated vertex, along the edge
    ])
    out = hidden_lines(tris, edge, None)
    np.testing.assert_array_equal(out.segments, edge[:, :, :2])


def test_edges_of_no_2d_length_give_no_pieces():
    out = hidden_lines(np.zeros((0, 3, 3)), [[[3, 4, 0.1], [3, 4, 0.9]], [[0, 0, 0], [1, 0, 0]]], None)
    assert out.edge.tolist() == [1] and out.stats.hidden_fraction == 0.0


def test_min_length_drops_short_pieces():
    tri = np.array([[[2, -5, 0.1], [2, 5, 0.1], [12, 0, 0.1]]], float)
    edge = np.array([[[0, 0, 0.5], [10, 0, 0.5]]])  # visible on [0, 2] only
    assert hidden_lines(tri, edge, None).segments.tolist() == [[[0, 0], [2, 0]]]
    assert len(hidden_lines(tri, edge, None, min_length=2.5).segments) == 0


def test_empty_inputs():
    edges = np.array([[[0, 0, 0.5], [10, 0, 0.5]], [[0, 0, 0.5], [0, 10, 0.5]]])
    out = hidden_lines(np.zeros((0, 3, 3)), edges, None)
    np.testing.assert_array_equal(out.segments, edges[:, :, :2])
    assert out.stats.pairs_tested == 0 and out.stats.hidden_fraction == 0.0
    for tris in ([], np.zeros((0, 3, 3)), np.ones((1, 3, 3))):
        none = hidden_lines(tris, np.zeros((0, 2, 3)), np.zeros((0, 2), int))
        assert none.segments.shape == (0, 2, 2) and none.edge.shape == (0,) and none.polylines() == []
        assert (none.stats.edges_in, none.stats.pieces_out, none.stats.hidden_fraction) == (0, 0, 0.0)


@pytest.mark.parametrize(
    ("kwargs", "error", "words"),
    [
        (dict(triangles=np.zeros((2, 3, 2))), InvalidArgument, "triangles must be an (N, 3, 3)"),
        (dict(triangles=[[1, 2, 3]]), InvalidArgument, "triangles must be"),
        (dict(edges=np.zeros((1, 3, 3))), InvalidArgument, "edges must be an (N, 2, 3)"),
        (dict(triangles=np.array([np.zeros((3, 3)), np.full((3, 3), np.nan)])), InvalidArgument, "at row 1"),
        (dict(edges=[[[0, 0, 0], [1, math.inf, 0]]]), InvalidArgument, "edges contains a non-finite"),
        (dict(triangles=[["a", "b", "c"]] * 3), InvalidArgument, "triangles must be"),
        (dict(edge_faces=[[0, 0], [0, 0]]), InvalidArgument, "shape (1, 2)"),
        (dict(edge_faces=[[0, 2]]), InvalidArgument, "edge_faces row 0 is [0, 2]"),
        (dict(edge_faces=[[-2, 0]]), InvalidArgument, "edge_faces row 0"),
        (dict(edge_faces=[[0.0, 1.0]]), InvalidArgumentType, "integer"),
        (dict(eps=-1e-9), InvalidArgument, "eps must be >= 0"),
        (dict(eps=math.nan), InvalidArgument, "eps must be finite"),
        (dict(min_length="1"), InvalidArgumentType, "min_length must be a real number"),
    ],
)
def test_bad_arguments_are_named(kwargs, error, words):
    args = dict(triangles=np.zeros((2, 3, 3)), edges=[[[0, 0, 0], [1, 1, 0]]], edge_faces=None)
    options = {k: kwargs.pop(k) for k in ("eps", "min_length") if k in kwargs}
    args.update(kwargs)
    with pytest.raises(error, match=None) as caught:
        hidden_lines(args["triangles"], args["edges"], args["edge_faces"], **options)
    assert words in str(caught.value)

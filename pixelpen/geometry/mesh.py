"""Triangle meshes, polygon tables, plane equations and inside/outside tests (Hearn & Baker 10-1, 10-2).

Conventions: vertices are (N, 3) float64 points; faces are (M, 3) int64 vertex indices. A face whose
vertices run counter-clockwise when seen from outside (right-hand rule) is a front face and its normal
points outward. A plane is (A, B, C, D) with Ax + By + Cz + D = 0 and (A, B, C) the outward unit normal, so
(H&B) Ax + By + Cz + D < 0 for a point inside (behind the plane) and > 0 for one outside (in front of it).
Each triangle carries the id of the source polygon it was cut from (``Mesh.polygon``): an edge between two
triangles of one polygon is a triangulation diagonal, never a feature edge. Faces that repeat a vertex index
are degenerate: they have zero normals and take no part in the edge table.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.geometry.transforms import ArrayLike, as_number
from pixelpen.geometry.transforms3d import apply3d, as_matrix3d, as_points3d, normal_matrix

_LISTED = 10  # problems of one kind a report lists before "and N more"
_DEGENERATE_SINE = 1e-12  # |e1 x e2| below this fraction of |e1| |e2|: the face has no direction
_PLANAR_RELATIVE = 1e-9  # default non-planarity tolerance, as a fraction of the vertices' bounding-box diagonal


def _int_array(value: object, name: str) -> np.ndarray:
    """np.asarray(value) as int64, InvalidArgumentType unless it holds integers (an empty input is allowed)."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"{name} must be an array of vertex indices: {exc}") from None
    if arr.size == 0:
        return arr.astype(np.int64)
    if arr.dtype.kind not in "iu":
        raise InvalidArgumentType(f"{name} must hold integer vertex indices, got dtype {arr.dtype}")
    return arr.astype(np.int64)


def _check_indices(flat: np.ndarray, count: int, name: str, row_of: np.ndarray | None = None) -> None:
    """InvalidArgument naming the first index outside 0 .. count - 1 (and its row) in a flat index array."""
    bad = (flat < 0) | (flat >= count)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        row = k if row_of is None else int(row_of[k])
        raise InvalidArgument(f"{name}[{row}] refers to vertex {int(flat[k])}, but there are {count} vertices")


def _ragged(polygons: object, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A sequence of index sequences (or a (P, k) int array) as (flat indices, starts, lengths), all int64."""
    if isinstance(polygons, np.ndarray) and polygons.ndim == 2:
        arr = _int_array(polygons, name)
        lengths = np.full(len(arr), arr.shape[1], dtype=np.int64)
        return arr.reshape(-1), np.arange(len(arr), dtype=np.int64) * arr.shape[1], lengths
    if isinstance(polygons, (str, bytes)) or not isinstance(polygons, Sequence | np.ndarray):
        raise InvalidArgumentType(f"{name} must be a sequence of vertex-index sequences, got {type(polygons).__name__}")
    try:
        lengths = np.fromiter((len(p) for p in polygons), dtype=np.int64, count=len(polygons))
    except TypeError:
        raise InvalidArgumentType(f"{name} must be a sequence of vertex-index sequences") from None
    flat = _int_array(list(itertools.chain.from_iterable(polygons)), name)
    return flat.reshape(-1), np.cumsum(lengths) - lengths, lengths


def _next_use(starts: np.ndarray, lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For the flat vertex uses of ragged polygons: the polygon of each use and the index of the next use."""
    owner = np.repeat(np.arange(len(lengths), dtype=np.int64), lengths)
    position = np.arange(int(lengths.sum()), dtype=np.int64) - starts[owner]
    nxt = starts[owner] + (position + 1) % lengths[owner]
    return owner, nxt


def _newell(vertices: np.ndarray, flat: np.ndarray, starts: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(P, 4) planes of ragged polygons by Newell's method (unit outward normal; zero rows where the area is 0)."""
    owner, nxt = _next_use(starts, lengths)
    p, q = vertices[flat], vertices[flat[nxt]]
    count = len(lengths)
    terms = (
        (p[:, 1] - q[:, 1]) * (p[:, 2] + q[:, 2]),  # A = sum (y_i - y_j)(z_i + z_j)
        (p[:, 2] - q[:, 2]) * (p[:, 0] + q[:, 0]),  # B = sum (z_i - z_j)(x_i + x_j)
        (p[:, 0] - q[:, 0]) * (p[:, 1] + q[:, 1]),  # C = sum (x_i - x_j)(y_i + y_j)
    )
    normal = np.stack([np.bincount(owner, weights=t, minlength=count) for t in terms], axis=1)
    sums = np.stack([np.bincount(owner, weights=p[:, c], minlength=count) for c in range(3)], axis=1)
    centroid = sums / np.maximum(lengths, 1)[:, None]
    length = np.linalg.norm(normal, axis=1)
    scale_ = np.bincount(owner, weights=np.einsum("ij,ij->i", q - p, q - p), minlength=count)  # sum |edge|^2
    flat_ok = length > _DEGENERATE_SINE * scale_
    unit = np.where(flat_ok[:, None], normal / np.where(flat_ok, length, 1.0)[:, None], 0.0)
    return np.hstack([unit, -np.einsum("ij,ij->i", unit, centroid)[:, None]])


@dataclass(frozen=True)
class _Uses:
    """Undirected edge uses grouped by vertex pair: sorted (lo, hi, owner, forward), group id, group counts."""

    order: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    owner: np.ndarray
    forward: np.ndarray
    group: np.ndarray
    starts: np.ndarray
    counts: np.ndarray


def _group_uses(a: np.ndarray, b: np.ndarray, owner: np.ndarray) -> _Uses:
    """Sort directed edges a -> b by undirected vertex pair and group them; owner must be non-decreasing."""
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    order = np.argsort(lo * (int(hi.max(initial=0)) + 1) + hi, kind="stable")  # stable: owners stay in order
    lo, hi, owner, forward = lo[order], hi[order], owner[order], (a < b)[order]
    new = np.ones(len(lo), dtype=bool)
    new[1:] = (lo[1:] != lo[:-1]) | (hi[1:] != hi[:-1])
    starts = np.flatnonzero(new)
    counts = np.diff(np.append(starts, len(lo)))
    return _Uses(order, lo, hi, owner, forward, np.cumsum(new) - 1, starts, counts)


@dataclass(frozen=True)
class MeshEdges:
    """Edge table of a mesh: pairs (E, 2) sorted vertex indices, faces (E, 2) adjacent triangles (-1: none).

    An edge shared by k > 2 triangles (non-manifold) is not merged: it takes ceil(k / 2) rows with the same
    pair, its triangles paired in index order; ``count`` (E,) is the number of triangles on the row's pair.
    """

    pairs: np.ndarray
    faces: np.ndarray
    count: np.ndarray


class Mesh:
    """A triangle mesh: vertices (N, 3), faces (M, 3), source-polygon id per face, optional unit vertex normals."""

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        polygon: ArrayLike | None = None,
        normals: ArrayLike | None = None,
    ) -> None:
        """Validate and store the arrays (read-only); polygon defaults to arange(M), each face its own polygon."""
        verts, _ = as_points3d(vertices, "vertices")
        tris = _int_array(faces, "faces")
        if tris.size == 0:
            tris = tris.reshape(0, 3)
        if tris.ndim != 2 or tris.shape[1] != 3:
            raise InvalidArgument(f"faces must be an (M, 3) array of vertex indices, got shape {tris.shape}")
        _check_indices(tris.reshape(-1), len(verts), "faces", np.repeat(np.arange(len(tris)), 3))
        if polygon is None:
            ids = np.arange(len(tris), dtype=np.int64)
        else:
            ids = _int_array(polygon, "polygon")
            ids = ids.reshape(0) if ids.size == 0 else ids
            if ids.shape != (len(tris),):
                raise InvalidArgument(f"polygon must have one id per face, shape ({len(tris)},), got {ids.shape}")
        unit = None
        if normals is not None:
            given, _ = as_points3d(normals, "normals")
            if given.shape != verts.shape:
                raise InvalidArgument(f"normals must have one row per vertex, shape {verts.shape}, got {given.shape}")
            length = np.linalg.norm(given, axis=1)
            if (length == 0.0).any():
                row = int(np.flatnonzero(length == 0.0)[0])
                raise InvalidArgument(f"normals[{row}] is the zero vector")
            unit = given / length[:, None]
            unit.flags.writeable = False
        for arr in (verts, tris, ids):
            arr.flags.writeable = False
        self.vertices: np.ndarray = verts
        self.faces: np.ndarray = tris
        self.polygon: np.ndarray = ids
        self.normals: np.ndarray | None = unit
        self._edges: MeshEdges | None = None

    def __repr__(self) -> str:
        """Sizes only."""
        return f"Mesh({len(self.vertices)} vertices, {len(self.faces)} faces)"

    @classmethod
    def from_polygons(cls, vertices: ArrayLike, polygons: Sequence[Sequence[int]] | np.ndarray) -> Mesh:
        """Fan-triangulate convex polygons (each a sequence of >= 3 vertex indices); face i keeps its polygon id."""
        verts, _ = as_points3d(vertices, "vertices")
        flat, starts, lengths = _ragged(polygons, "polygons")
        return _fan(verts, flat, starts, lengths)

    @staticmethod
    def concatenate(meshes: Sequence[Mesh]) -> Mesh:
        """One mesh holding all of them (indices and polygon ids offset; normals kept when any mesh has them)."""
        parts = list(meshes)
        if not all(isinstance(m, Mesh) for m in parts):
            raise InvalidArgumentType("concatenate needs a sequence of Mesh objects")
        if not parts:
            return Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
        vertex_offset = np.cumsum([0] + [len(m.vertices) for m in parts[:-1]])
        polygon_offset = np.cumsum([0] + [int(m.polygon.max()) + 1 if len(m.polygon) else 0 for m in parts[:-1]])
        normals = None
        if any(m.normals is not None for m in parts):
            normals = np.concatenate([m.vertex_normals() for m in parts])
        return Mesh(
            np.concatenate([m.vertices for m in parts]),
            np.concatenate([m.faces + off for m, off in zip(parts, vertex_offset, strict=True)]),
            np.concatenate([m.polygon + off for m, off in zip(parts, polygon_offset, strict=True)]),
            normals,
        )

    def transformed(self, m: ArrayLike) -> Mesh:
        """The mesh mapped by a 4x4 matrix (normals by its normal matrix); a mirroring matrix reverses the winding."""
        mat = as_matrix3d(m, "m")
        faces = self.faces if np.linalg.det(mat) >= 0.0 else self.faces[:, ::-1]
        normals = None
        if self.normals is not None:
            mapped = self.normals @ normal_matrix(mat).T
            normals = mapped / np.linalg.norm(mapped, axis=1)[:, None]
        return Mesh(apply3d(mat, self.vertices), faces, self.polygon, normals)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(min (3,), max (3,)) corners of the vertices' bounding box."""
        if not len(self.vertices):
            raise InvalidArgument("an empty mesh has no bounds")
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    def _cross(self) -> np.ndarray:
        """(M, 3) cross products (v1 - v0) x (v2 - v0): twice the area along the face normal."""
        v = self.vertices[self.faces]
        return np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])

    def face_areas(self) -> np.ndarray:
        """(M,) triangle areas."""
        areas: np.ndarray = 0.5 * np.linalg.norm(self._cross(), axis=1)
        return areas

    def face_normals(self) -> np.ndarray:
        """(M, 3) unit normals by the right-hand rule (zero rows for degenerate faces)."""
        v = self.vertices[self.faces]
        e1, e2 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
        cross = np.cross(e1, e2)
        length = np.linalg.norm(cross, axis=1)
        ok = length > _DEGENERATE_SINE * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)
        return np.where(ok[:, None], cross / np.where(ok, length, 1.0)[:, None], 0.0)

    def vertex_normals(self) -> np.ndarray:
        """(N, 3) unit vertex normals: the given ones, else area-weighted face normals (zero for unused vertices)."""
        if self.normals is not None:
            return self.normals
        cross = self._cross()
        flat = self.faces.reshape(-1)
        total = np.stack(
            [np.bincount(flat, weights=np.repeat(cross[:, c], 3), minlength=len(self.vertices)) for c in range(3)],
            axis=1,
        )
        length = np.linalg.norm(total, axis=1)
        return np.where(length[:, None] > 0, total / np.where(length > 0, length, 1.0)[:, None], 0.0)

    def plane_equations(self) -> np.ndarray:
        """(M, 4) planes A, B, C, D of the faces with unit outward normal (zero rows for degenerate faces)."""
        normals = self.face_normals()
        d = -np.einsum("ij,ij->i", normals, self.vertices[self.faces[:, 0]])
        return np.hstack([normals, d[:, None]])

    def edges(self) -> MeshEdges:
        """The edge table (computed once): vertex pairs, adjacent faces, and how many faces share each pair."""
        if self._edges is None:
            f = self.faces
            ok = (f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])
            used = f[ok]
            owner = np.repeat(np.flatnonzero(ok), 3)
            uses = _group_uses(used.reshape(-1), np.roll(used, -1, axis=1).reshape(-1), owner)
            rank = np.arange(len(uses.lo)) - uses.starts[uses.group]
            rows = (uses.counts + 1) // 2
            row = (np.cumsum(rows) - rows)[uses.group] + rank // 2
            pairs = np.zeros((int(rows.sum()), 2), dtype=np.int64)
            pairs[row, 0], pairs[row, 1] = uses.lo, uses.hi
            faces = np.full(pairs.shape, -1, dtype=np.int64)
            faces[row, rank % 2] = uses.owner
            for arr in (pairs, faces):
                arr.flags.writeable = False
            self._edges = MeshEdges(pairs, faces, np.repeat(uses.counts, rows))
        return self._edges

    def is_closed(self) -> bool:
        """True when the mesh has edges and every edge is shared by exactly two faces."""
        count = self.edges().count
        return bool(len(count)) and bool((count == 2).all())

    def feature_edges(
        self, front: ArrayLike, crease_angle: float = math.radians(30.0), outlines: bool = False
    ) -> tuple[np.ndarray, np.ndarray]:
        """Edges to draw for a view, as (pairs (K, 2), faces (K, 2)), given which faces are front faces.

        Silhouettes (one adjacent face front, the other back), boundary edges of front faces and creases
        between front faces whose normals differ by more than ``crease_angle``; with ``outlines`` every
        polygon edge with a front face beside it. Never an edge between two faces of one polygon.
        """
        fr = np.asarray(front)
        if fr.shape != (len(self.faces),) or fr.dtype != np.bool_:
            raise InvalidArgument(
                f"front must be a bool array of shape ({len(self.faces)},), got {fr.dtype} of shape {fr.shape}"
            )
        crease = as_number(crease_angle, "crease_angle")
        if not 0.0 <= crease <= math.pi:
            raise InvalidArgument(f"crease_angle must be in [0, pi], got {crease}")
        table = self.edges()
        f0, f1 = table.faces[:, 0], table.faces[:, 1]
        has1 = f1 >= 0
        other = np.where(has1, f1, 0)
        front0, front1 = fr[f0], has1 & fr[other]
        keep = ~(has1 & (self.polygon[f0] == self.polygon[other]))
        if outlines:
            keep &= front0 | front1
        else:
            normals = self.face_normals()
            bent = np.einsum("ij,ij->i", normals[f0], normals[other]) < math.cos(crease)
            keep &= (front0 != front1) | (front0 & front1 & bent)
        return table.pairs[keep], table.faces[keep]


def _fan(vertices: np.ndarray, flat: np.ndarray, starts: np.ndarray, lengths: np.ndarray) -> Mesh:
    """Mesh of the fan triangulations (p0, p_k, p_k+1) of ragged polygons, validated, polygon ids kept."""
    short = np.flatnonzero(lengths < 3)
    if len(short):
        i = int(short[0])
        raise InvalidArgument(f"polygons[{i}] has {int(lengths[i])} vertices; a polygon needs at least 3")
    _check_indices(flat, len(vertices), "polygons", np.repeat(np.arange(len(lengths)), lengths))
    per = lengths - 2
    poly = np.repeat(np.arange(len(lengths), dtype=np.int64), per)
    k = np.arange(int(per.sum()), dtype=np.int64) - (np.cumsum(per) - per)[poly]
    base = starts[poly]
    return Mesh(vertices, np.stack([flat[base], flat[base + k + 1], flat[base + k + 2]], axis=1), poly)


def _listed(kind: str, rows: np.ndarray, describe: Callable[[int], str]) -> list[str]:
    """Problem lines of one kind for the given rows: at most _LISTED described, then a count of the rest."""
    out = [f"{kind}: {describe(int(k))}" for k in rows[:_LISTED]]
    if len(rows) > _LISTED:
        out.append(f"{kind}: and {len(rows) - _LISTED} more")
    return out


class PolygonTable:
    """Vertex, edge and polygon tables of a polygon mesh (H&B 10-1), with consistency checks.

    ``edges`` (E, 2) sorted vertex pairs; ``polygon_edges`` the edge index of each polygon side, flat,
    in the order of ``polygon_starts``; ``edge_polygons`` (E, 2) the first two polygons on each edge
    (-1: none) and ``edge_count`` (E,) how many polygon sides use it.
    """

    def __init__(self, vertices: ArrayLike, polygons: Sequence[Sequence[int]] | np.ndarray,
                 tolerance: float | None = None) -> None:
        """Build the tables; indices are checked by :meth:`problems`, not here (the shapes and types are)."""
        self.vertices, _ = as_points3d(vertices, "vertices")
        self.polygon_vertices, self.polygon_starts, self.polygon_lengths = _ragged(polygons, "polygons")
        if tolerance is None:
            span = np.ptp(self.vertices, axis=0) if len(self.vertices) else np.zeros(3)
            tolerance = _PLANAR_RELATIVE * max(float(np.linalg.norm(span)), 1e-300)
        self.tolerance = as_number(tolerance, "tolerance")
        owner, nxt = _next_use(self.polygon_starts, self.polygon_lengths)
        a, b = self.polygon_vertices, self.polygon_vertices[nxt]
        real = a != b
        uses = _group_uses(a[real], b[real], owner[real])
        self._uses = uses
        self.edges: np.ndarray = np.stack([uses.lo[uses.starts], uses.hi[uses.starts]], axis=1)
        side = np.full(len(a), -1, dtype=np.int64)
        side[np.flatnonzero(real)[uses.order]] = uses.group
        self.polygon_edges: np.ndarray = side
        self.edge_count: np.ndarray = uses.counts
        second = np.minimum(uses.starts + 1, len(uses.owner) - 1)
        self.edge_polygons: np.ndarray = np.stack(
            [uses.owner[uses.starts], np.where(uses.counts > 1, uses.owner[second], -1)], axis=1
        ) if len(uses.starts) else np.zeros((0, 2), dtype=np.int64)

    def problems(self) -> list[str]:
        """Every inconsistency found, one line each (at most ten per kind), or [] for a consistent table."""
        out: list[str] = []
        count, flat, lengths = len(self.vertices), self.polygon_vertices, self.polygon_lengths
        owner, nxt = _next_use(self.polygon_starts, lengths)
        bad = (flat < 0) | (flat >= count)
        out += _listed("bad index", np.flatnonzero(bad),
                       lambda k: f"polygon {owner[k]} refers to vertex {flat[k]} of {count}")
        out += _listed("too few vertices", np.flatnonzero(lengths < 3),
                       lambda i: f"polygon {i} has {lengths[i]} vertices")
        order = np.lexsort((flat, owner))
        so, sf = owner[order], flat[order]
        out += _listed("repeated vertex", np.flatnonzero((so[1:] == so[:-1]) & (sf[1:] == sf[:-1])),
                       lambda k: f"polygon {so[k]} uses vertex {sf[k]} twice")
        safe = np.where(bad, 0, flat)
        zero = ~bad & ~bad[nxt] & (flat != flat[nxt]) & (self.vertices[safe] == self.vertices[safe[nxt]]).all(axis=1)
        out += _listed("zero-length edge", np.flatnonzero(zero),
                       lambda k: f"polygon {owner[k]}: vertices {flat[k]} and {flat[nxt[k]]} coincide")
        out += _listed("unused vertex", np.flatnonzero(np.bincount(flat[~bad], minlength=count) == 0),
                       lambda i: f"vertex {i}")
        out += _listed("edge in more than two polygons", np.flatnonzero(self.edge_count > 2),
                       lambda e: f"edge {self.edges[e].tolist()} is in {self.edge_count[e]} polygons")
        valid = (np.bincount(owner[bad], minlength=len(lengths)) == 0) & (lengths >= 3)
        planes = self._planes(valid)
        dist = np.abs(np.einsum("ij,ij->i", self.vertices[safe], planes[owner, :3]) + planes[owner, 3])
        worst = np.zeros(len(lengths))
        np.maximum.at(worst, owner, dist)
        out += _listed("zero area", np.flatnonzero(valid & (np.abs(planes[:, :3]).sum(axis=1) == 0.0)),
                       lambda i: f"polygon {i} (collinear or coincident vertices)")
        out += _listed("non-planar", np.flatnonzero(valid & (worst > self.tolerance)),
                       lambda i: f"polygon {i}: a vertex is {worst[i]:.3g} from its plane "
                       f"(tolerance {self.tolerance:.3g})")
        u = self._uses
        pair = u.starts[u.counts == 2]
        out += _listed("inconsistent orientation", pair[u.forward[pair] == u.forward[pair + 1]],
                       lambda k: f"polygons {u.owner[k]} and {u.owner[k + 1]} both run edge {u.lo[k]}-{u.hi[k]} "
                       "the same way")
        return out

    def check(self) -> None:
        """Raise InvalidArgument listing every problem, if there are any."""
        found = self.problems()
        if found:
            raise InvalidArgument("inconsistent polygon table:\n  " + "\n  ".join(found))

    def _planes(self, valid: np.ndarray) -> np.ndarray:
        """Newell planes of the polygons, zero rows where ``valid`` is False."""
        keep = np.repeat(valid, self.polygon_lengths)
        flat = np.where(keep, self.polygon_vertices, 0)
        return np.where(valid[:, None], _newell(self.vertices, flat, self.polygon_starts, self.polygon_lengths), 0.0)

    def _require_indices(self) -> None:
        """InvalidArgument for a polygon of < 3 vertices or an index out of range."""
        _fan(self.vertices, self.polygon_vertices, self.polygon_starts, self.polygon_lengths)

    def plane_equations(self) -> np.ndarray:
        """(P, 4) Newell planes A, B, C, D with unit outward normal (zero rows for zero-area polygons)."""
        self._require_indices()
        return self._planes(np.ones(len(self.polygon_lengths), dtype=bool))

    def to_mesh(self) -> Mesh:
        """The triangle mesh of the polygons' fan triangulations (polygon ids kept)."""
        return _fan(self.vertices, self.polygon_vertices, self.polygon_starts, self.polygon_lengths)


def plane_equation(points: ArrayLike) -> np.ndarray:
    """(A, B, C, D) of the plane of a polygon's (K, 3) vertices by Newell's method, (A, B, C) unit, CCW -> outward."""
    pts, _ = as_points3d(points, "points", min_rows=3)
    plane: np.ndarray = _newell(pts, np.arange(len(pts)), np.zeros(1, dtype=np.int64), np.array([len(pts)]))[0]
    if not plane[:3].any():
        raise InvalidArgument(f"points span no plane (collinear or coincident): {pts.tolist()[:4]}")
    return plane


def _unit_planes(planes: ArrayLike, name: str) -> np.ndarray:
    """(P, 4) planes scaled so that (A, B, C) is a unit vector; InvalidArgument for a zero normal."""
    try:
        arr = np.asarray(planes, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"{name} must be an array of planes (A, B, C, D): {exc}") from None
    arr = arr.reshape(1, 4) if arr.shape == (4,) else arr
    if arr.ndim != 2 or arr.shape[1] != 4 or not np.isfinite(arr).all():
        raise InvalidArgument(f"{name} must be finite planes (A, B, C, D) of shape (P, 4), got shape {arr.shape}")
    length = np.linalg.norm(arr[:, :3], axis=1)
    if (length == 0.0).any():
        raise InvalidArgument(f"{name}[{int(np.flatnonzero(length == 0.0)[0])}] has a zero normal (A, B, C)")
    unit: np.ndarray = arr / length[:, None]
    return unit


def classify_points(plane: ArrayLike, points: ArrayLike, tol: float = 0.0) -> np.ndarray:
    """(N,) int8 per point: -1 inside (behind, Ax+By+Cz+D < -tol), 0 on the plane, +1 outside (in front)."""
    p = _unit_planes(plane, "plane")
    if len(p) != 1:
        raise InvalidArgument(f"plane must be one (A, B, C, D), got shape {np.shape(plane)}")
    pts, _ = as_points3d(points, "points")
    t = as_number(tol, "tol")
    s = pts @ p[0, :3] + p[0, 3]
    return np.where(s > t, 1, np.where(s < -t, -1, 0)).astype(np.int8)


def inside_convex(planes: ArrayLike, points: ArrayLike, tol: float = 0.0) -> np.ndarray:
    """(N,) bool: each point is inside or on (within tol of) every plane of a convex solid with outward normals."""
    p = _unit_planes(planes, "planes")
    pts, _ = as_points3d(points, "points")
    inside: np.ndarray = ((pts @ p[:, :3].T + p[:, 3]) <= as_number(tol, "tol")).all(axis=1)
    return inside


def triangle_strip(vertices: ArrayLike, indices: ArrayLike) -> Mesh:
    """Mesh of a triangle strip: triangle k is (i_k, i_k+1, i_k+2), odd ones flipped to the first's winding.

    Triangles that repeat an index (the degenerate ones joining strips) are dropped.
    """
    verts, _ = as_points3d(vertices, "vertices")
    idx = _int_array(indices, "indices").reshape(-1)
    if len(idx) < 3:
        raise InvalidArgument(f"a triangle strip needs at least 3 indices, got {len(idx)}")
    _check_indices(idx, len(verts), "indices")
    tris = np.stack([idx[:-2], idx[1:-1], idx[2:]], axis=1)
    tris[1::2, :2] = tris[1::2, 1::-1]
    keep = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    return Mesh(verts, tris[keep])


def quad_mesh(grid: ArrayLike, closed_u: bool = False, closed_v: bool = False) -> Mesh:
    """Mesh of an (R, C, 3) grid of points: two triangles (one polygon id) per quad; closed_* wraps an axis.

    u runs along axis 0 and v along axis 1; vertex (r, c) is row r * C + c. Triangles are counter-clockwise
    seen from the side P_u x P_v points to (quad (r, c), (r+1, c), (r+1, c+1), (r, c+1)).
    """
    try:
        arr = np.asarray(grid, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"grid must be an (R, C, 3) array of numbers: {exc}") from None
    if arr.ndim != 3 or arr.shape[2] != 3 or arr.shape[0] < 2 or arr.shape[1] < 2:
        raise InvalidArgument(f"grid must be an (R, C, 3) array with R, C >= 2, got shape {arr.shape}")
    rows, cols = arr.shape[:2]
    idx = np.arange(rows * cols, dtype=np.int64).reshape(rows, cols)
    r = np.arange(rows if closed_u and rows > 2 else rows - 1)
    c = np.arange(cols if closed_v and cols > 2 else cols - 1)
    r0, c0 = np.meshgrid(r, c, indexing="ij")
    r1, c1 = (r0 + 1) % rows, (c0 + 1) % cols
    a, b, cc, d = (idx[r0, c0].ravel(), idx[r1, c0].ravel(), idx[r1, c1].ravel(), idx[r0, c1].ravel())
    faces = np.stack([np.stack([a, b, cc], axis=1), np.stack([a, cc, d], axis=1)], axis=1).reshape(-1, 3)
    return Mesh(arr.reshape(-1, 3), faces, np.repeat(np.arange(len(a), dtype=np.int64), 2))

"""Wavefront OBJ polygon meshes: ``v``, ``vn``, ``vt`` and ``f`` read with numpy, odd lines one by one.

Read: ``v x y z [w] [r g b]`` (w and vertex colours ignored), ``vn i j k``, ``vt u [v [w]]`` (checked, not
kept: a Mesh has no texture coordinates), ``f`` with corners ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn``; indices
count from 1, a negative one counts back from the last vertex defined before its line, a positive one may
name any vertex of the file.  Polygons are fanned into triangles by ``Mesh.from_polygons`` (the polygon id of
each triangle is its ``f`` line's order).  Normals: when every corner names a ``vn``, every vertex is used and
each vertex has one normal, they become the mesh's unit vertex normals; otherwise (hard edges, a zero normal)
the mesh computes its own.  Grouping, materials, smoothing, lines (``l``), points (``p``) and the free-form
statements of the format are accepted and ignored; any other statement is a ParseError.  Everything after a
token starting with ``#`` is a comment.

Speed: a plain file (only ``v`` lines, ``f`` lines of plain indices and ``#`` lines) is read by
:func:`_plain_obj`, whole blocks of numbers at once; any other file by the general reader: lines of the common
forms (a keyword, then numbers, or ``a``, ``a/b``, ``a//c``, ``a/b/c`` corners) are parsed together by
:func:`~pixelpen.meshfiles.text.decimals` over a :class:`~pixelpen.meshfiles.text.TextTable`; any other line
(an inline comment, an unknown keyword, a malformed field) goes through the per-line reader, which also finds
and names the first bad field.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import cast

import numpy as np

from pixelpen.errors import ParseError
from pixelpen.geometry.mesh import Mesh
from pixelpen.meshfiles.limits import LIMITS, Limits
from pixelpen.meshfiles.text import (
    BoolArray,
    FloatArray,
    IntArray,
    TextTable,
    decimals,
    keyword_code,
    parse_float,
    plain_numbers,
    ranges,
)

__all__ = ["read_obj"]

V, VN, VT, F = (keyword_code(k) for k in (b"v", b"vn", b"vt", b"f"))
IGNORED = frozenset((b"o", b"g", b"s", b"usemtl", b"mtllib", b"l", b"p", b"mg", b"lod", b"usemap", b"maplib",
                     b"bevel", b"c_interp", b"d_interp", b"shadow_obj", b"trace_obj", b"ctech", b"stech", b"vp",
                     b"cstype", b"deg", b"bmat", b"step", b"curv", b"curv2", b"surf", b"parm", b"trim", b"hole",
                     b"scrv", b"sp", b"end", b"con", b"call", b"csh"))
"""Statements read and ignored: grouping, display attributes, lines, points and free-form geometry."""
VERTEX_NUMBERS = (3, 4, 6, 7)
"""Numbers a ``v`` line may hold: x y z, with w, with r g b, with both."""
CORNER = re.compile(rb"([+-]?\d{1,18})(?:/([+-]?\d{1,18})|/([+-]?\d{1,18})?/([+-]?\d{1,18}))?")
"""One ``f`` corner: v, v/vt, v//vn or v/vt/vn."""
LONG_INDEX = re.compile(rb"[+-]?\d{19,}")
"""An index of more than 18 digits: read as the largest int64 of its sign (so out of range), saturated."""



class _Corners:
    """Face corners gathered by both paths: line, token, and the raw v, vt, vn numbers (0 when absent)."""

    def __init__(self) -> None:
        self.parts: list[tuple[IntArray, IntArray, IntArray, IntArray, IntArray]] = []

    def add(self, line: IntArray, token: IntArray, v: IntArray, vt: IntArray, vn: IntArray) -> None:
        self.parts.append((line, token, v, vt, vn))

    def joined(self) -> tuple[IntArray, IntArray, IntArray, IntArray, IntArray]:
        """All corners in file order (corners of one line keep their order)."""
        cols = [np.concatenate([p[k] for p in self.parts]) if self.parts else np.zeros(0, dtype=np.int64)
                for k in range(5)]
        order = np.argsort(cols[0], kind="stable")
        line, token, v, vt, vn = (c[order].astype(np.int64) for c in cols)
        return line, token, v, vt, vn


def read_obj(data: bytes, source: str, *, limits: Limits = LIMITS) -> Mesh:
    """The mesh of an OBJ file's bytes; a ParseError naming ``source``, the line and column when malformed."""
    limits.check("max_bytes", len(data), "bytes in the file", source)
    mesh = _plain_obj(data, limits)
    return mesh if mesh is not None else _general_obj(data, source, limits)


def _plain_obj(data: bytes, limits: Limits) -> Mesh | None:
    """The mesh of a plain file (only ``v`` numbers, ``f`` vertex indices, ``#`` lines), else None.

    Every line must begin with ``v ``, ``f `` or ``#`` or be empty; ``v`` lines hold 3, 4, 6 or 7 plain
    decimals and ``f`` lines at least 3 plain integer indices, all in range and within ``limits``.  Anything
    else (and every error) is left to the general reader, which reads the same files to the same mesh.
    """
    if b"\r" in data or b"\\\n" in data or not data or data.find(b"/", max(data.find(b"\nv "), 0)) >= 0:
        return None  # (a "/" after the first vertex: a/b corners, left at once; one in a first comment is not)
    if not data.endswith(b"\n"):
        data += b"\n"
    work = np.frombuffer(data, dtype=np.uint8).copy()
    ends = np.flatnonzero(work == 10)
    starts = np.r_[0, ends[:-1] + 1]
    if int((ends - starts).max()) > limits.max_line_chars:
        return None
    head = work[starts]
    spaced = work[np.minimum(starts + 1, len(work) - 1)] == 32
    vertex, face = (head == ord("v")) & spaced, (head == ord("f")) & spaced
    if not (vertex | face | (head == ord("#")) | (starts == ends)).all():
        return None
    work[starts[vertex | face]] = 32
    kind = np.repeat(vertex.view(np.int8) + 2 * face.view(np.int8), ends - starts + 1)
    numbers = plain_numbers(work[kind == 1], integer=False)
    indices = plain_numbers(work[kind == 2], integer=True)
    if numbers is None or indices is None:
        return None
    per_vertex = np.diff(np.searchsorted(numbers[1], numbers[2]), prepend=0)
    per_face = np.diff(np.searchsorted(indices[1], indices[2]), prepend=0)
    total = len(per_vertex)
    if (total > limits.max_vertices or not np.isin(per_vertex, VERTEX_NUMBERS).all() or len(per_face) == 0
            or per_face.min() < 3 or per_face.max() > limits.max_polygon_vertices
            or int((per_face - 2).sum()) > limits.max_faces):
        return None
    first = np.cumsum(per_vertex) - per_vertex
    coords = numbers[0].astype(np.float64, copy=False)
    positions = coords.reshape(-1, 3) if (per_vertex == 3).all() else coords[first[:, None] + np.arange(3)]
    raw = indices[0]
    line = np.repeat(np.arange(len(per_face)), per_face)
    if (raw < 0).any():
        before = np.cumsum(vertex)[face]  # vertices defined before each face line
        index = np.where(raw > 0, raw - 1, before[line] + raw)
    else:
        index = raw - 1
    if (raw == 0).any() or index.min() < 0 or index.max() >= total:
        return None
    return _polygons(positions, index, line)


def _general_obj(data: bytes, source: str, limits: Limits) -> Mesh:
    """The mesh of any OBJ file: plain lines together, odd ones one by one, errors named."""
    table = TextTable(data, source)
    table.check_line_length(limits.max_line_chars)
    keyword, count = table.keyword, table.tokens_per_line
    comment = np.zeros(table.lines, dtype=bool)
    words = np.flatnonzero(count > 0)
    comment[words] = table.bytes[table.token_start[table.first_token[words]]] == ord("#")
    for code, name in ((V, "vertices"), (VN, "normals"), (VT, "texture vertices")):
        _check_count(table, keyword == code, limits, "max_vertices", name)
    face_lines = np.flatnonzero(keyword == F)
    corners = count[face_lines] - 1
    big = np.flatnonzero(corners > limits.max_polygon_vertices)
    if len(big):
        raise ParseError(f"a polygon of {int(corners[big[0]]):,} corners, more than the limit max_polygon_vertices="
                         f"{limits.max_polygon_vertices:,}", source=source,
                         line=table.line_number(int(face_lines[big[0]])))
    _check_count(table, keyword == F, limits, "max_faces", "triangles", np.maximum(count - 3, 1))

    positions = np.full((int((keyword == V).sum()), 3), np.nan)
    normals = np.full((int((keyword == VN).sum()), 3), np.nan)
    vertex_row = np.cumsum(keyword == V) - 1
    normal_row = np.cumsum(keyword == VN) - 1
    slow = [np.flatnonzero(~comment & (count > 0) & ~np.isin(keyword, (V, VN, VT, F)))]
    for code, out, rows, allowed in ((V, positions, vertex_row, VERTEX_NUMBERS), (VN, normals, normal_row, (3,)),
                                     (VT, None, None, (1, 2, 3))):
        lines = np.flatnonzero((keyword == code) & np.isin(count - 1, allowed))
        slow.append(np.flatnonzero((keyword == code) & ~np.isin(count - 1, allowed)))
        read, values, tokens, rest = table.numbers(lines, 1)
        slow.append(rest)
        bad = np.flatnonzero(~np.isfinite(values))
        if len(bad):
            token = int(tokens[bad[0]])  # the per-line reader's words
            raise table.error(f"field {table.field(token)} is out of range", token)
        if out is not None and rows is not None:
            first = np.cumsum(count[read] - 1) - (count[read] - 1)
            out[rows[read]] = values[first[:, None] + np.arange(3)]
    found = _Corners()
    slow.append(_fast_faces(table, face_lines, found))
    _slow_lines(table, np.unique(np.concatenate(slow)), positions, normals, vertex_row, normal_row, found)
    return _mesh(table, positions, normals, found)


def _check_count(table: TextTable, lines: BoolArray, limits: Limits, name: str, what: str,
                 weight: IntArray | None = None) -> None:
    """A ParseError at the line where a count of ``what`` (lines, or ``weight`` per line) passes limit ``name``."""
    total = np.cumsum(np.where(lines, 1 if weight is None else weight, 0))
    limit = int(getattr(limits, name))
    if len(total) and total[-1] > limit:
        line = int(np.searchsorted(total, limit, "right"))
        raise ParseError(f"more {what} than the limit {name}={limit:,}", source=table.source,
                         line=table.line_number(line))


def _fast_faces(table: TextTable, lines: IntArray, found: _Corners) -> IntArray:
    """Read the ``f`` lines of plain ``a``, ``a/b``, ``a//c``, ``a/b/c`` corners at once; return the others.

    Each corner's fields are found from its slashes (the file's slashes are found once) and all fields are
    read together by :func:`~pixelpen.meshfiles.text.decimals` as integers of the CORNER form; a line with a
    corner of another form (``1/``, ``1-2``, a comment) is left to the per-line reader, which names it.
    """
    dropped = lines[table.tokens_per_line[lines] < 4]
    lines = lines[table.tokens_per_line[lines] >= 4]
    first = table.first_token[lines]
    tokens = ranges(first + 1, first + table.tokens_per_line[lines])
    starts, ends = table.token_start[tokens], table.token_end[tokens]
    if len(tokens) == 0:
        return dropped
    base = int(tokens[0])  # the corners' slashes, from the first corner to the last
    slash = np.flatnonzero(table.bytes[starts[0]:ends[-1]] == ord("/")) + starts[0]
    owner = np.searchsorted(table.token_start[base:tokens[-1] + 1], slash, "right") - 1
    slashes = np.bincount(owner, minlength=int(tokens[-1]) + 1 - base)[tokens - base]
    at = np.searchsorted(owner, tokens - base)  # each corner's first slash (when it has one)
    one = slash[np.minimum(at, len(slash) - 1)] if len(slash) else np.zeros(len(tokens), dtype=np.int64)
    two = slash[np.minimum(at + 1, len(slash) - 1)] if len(slash) else one
    v_end = np.where(slashes > 0, one, ends)
    vt_end = np.where(slashes == 2, two, ends)
    with_vt = np.flatnonzero((slashes >= 1) & (vt_end > one + 1))
    with_vn = np.flatnonzero(slashes == 2)
    field_start = np.concatenate([starts, one[with_vt] + 1, two[with_vn] + 1])
    field_end = np.concatenate([v_end, vt_end[with_vt], ends[with_vn]])
    values, ok = decimals(table.bytes, field_start, field_end, integer=True)
    long = np.zeros(0, dtype=np.int64) if ok.all() else np.flatnonzero(~ok & (field_end - field_start > 18))
    for k in long.tolist():  # saturated: out of range below
        field = table.data[field_start[k]:field_end[k]]
        if LONG_INDEX.fullmatch(field):
            values[k], ok[k] = (-(2**63) if field[:1] == b"-" else 2**63 - 1), True
    count = len(tokens)
    v, good = cast(IntArray, values[:count]), ok[:count] & (slashes <= 2)
    vt, vn = np.zeros(count, dtype=np.int64), np.zeros(count, dtype=np.int64)
    for rows, out, offset in ((with_vt, vt, count), (with_vn, vn, count + len(with_vt))):
        out[rows] = values[offset:offset + len(rows)]
        good[rows] &= ok[offset:offset + len(rows)]
    good[(slashes == 1) & (vt_end <= one + 1)] = False  # "1/": an empty texture vertex
    line = table.token_line[tokens]
    if not good.all():
        bad = np.unique(line[~good])
        dropped = np.union1d(dropped, bad)
        keep = ~np.isin(line, bad)
        line, tokens, v, vt, vn = line[keep], tokens[keep], v[keep], vt[keep], vn[keep]
    found.add(line, tokens, v, vt, vn)
    return dropped


def _slow_lines(table: TextTable, lines: IntArray, positions: FloatArray, normals: FloatArray,
                vertex_row: IntArray, normal_row: IntArray, found: _Corners) -> None:
    """Read ``lines`` one by one (statements the fast path does not take), naming the first bad field."""
    corner_line: list[int] = []
    corner_token: list[int] = []
    corner_v: list[int] = []
    corner_vt: list[int] = []
    corner_vn: list[int] = []
    for line in lines.tolist():
        first = int(table.first_token[line])
        tokens = list(range(first, first + int(table.tokens_per_line[line])))
        for k, index in enumerate(tokens):
            if table.data[table.token_start[index]] == ord("#"):
                del tokens[k:]
                break
        if not tokens:
            continue
        word = table.token(tokens[0])
        fields = tokens[1:]
        number = table.line_number(line)
        if word in (b"v", b"vn", b"vt"):
            allowed = {b"v": VERTEX_NUMBERS, b"vn": (3,), b"vt": (1, 2, 3)}[word]
            if len(fields) not in allowed:
                raise ParseError(f"a {word.decode()} line has {len(fields)} numbers, not "
                                 f"{' or '.join(map(str, allowed))}", source=table.source, line=number,
                                 column=table.column(tokens[0]))
            values = [parse_float(table.token(t), f"field {k + 1}", table.source, number, table.column(t))
                      for k, t in enumerate(fields)]
            if word == b"v":
                positions[vertex_row[line]] = values[:3]
            elif word == b"vn":
                normals[normal_row[line]] = values
        elif word == b"f":
            if len(fields) < 3:
                raise ParseError(f"a face of {len(fields)} corners (at least 3)", source=table.source,
                                 line=number, column=table.column(tokens[0]))
            for t in fields:
                match = CORNER.fullmatch(table.token(t))
                if match is None:
                    raise table.error("a face corner is not v, v/vt, v//vn or v/vt/vn", t)
                v, vt2, vt3, vn = match.groups()
                corner_line.append(line)
                corner_token.append(t)
                corner_v.append(int(v))
                corner_vt.append(int(vt2 or vt3 or 0))
                corner_vn.append(int(vn or 0))
        elif word not in IGNORED:
            raise table.error("an unknown OBJ statement", tokens[0])
    if corner_line:
        found.add(*(np.array(c, dtype=np.int64) for c in (corner_line, corner_token, corner_v, corner_vt,
                                                           corner_vn)))


def _resolve(table: TextTable, raw: IntArray, token: IntArray, defined_before: IntArray, total: int,
             what: str, present: BoolArray) -> IntArray:
    """0-based indices of 1-based or negative (relative) ones; a ParseError at the first one out of range."""
    index = np.where(raw > 0, raw - 1, defined_before + raw)
    bad = present & ((raw == 0) | (index < 0) | (index >= total))
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        if raw[k] == 0:
            why = f"{what} index 0 (indices count from 1)"
        elif raw[k] > 0:
            why = f"{what} index {int(raw[k])} out of range: the file has {total}"
        else:
            why = f"{what} index {int(raw[k])} out of range: {int(defined_before[k])} defined before this line"
        raise table.error(why, int(token[k]))
    return index


def _mesh(table: TextTable, positions: FloatArray, normals: FloatArray, found: _Corners) -> Mesh:
    """The mesh of the corners read: indices resolved and checked, polygons fanned, normals kept if consistent."""
    line, token, v, vt, vn = found.joined()
    keyword = table.keyword
    counts = {code: np.cumsum(keyword == code) for code in (V, VT, VN)}
    vi = _resolve(table, v, token, counts[V][line], len(positions), "vertex", np.ones(len(v), dtype=bool))
    _resolve(table, vt, token, counts[VT][line], int(counts[VT][-1]) if len(line) else 0, "texture vertex", vt != 0)
    ni = _resolve(table, vn, token, counts[VN][line], len(normals), "normal", vn != 0)
    if len(line) == 0:
        raise ParseError("no faces: not a polygon mesh", source=table.source)
    mesh = _polygons(positions, vi, line)
    vertex_normals = _normals(positions, normals, vi, ni, vn != 0)
    if vertex_normals is None:
        return mesh
    return Mesh(mesh.vertices, mesh.faces, mesh.polygon, vertex_normals)


def _polygons(positions: FloatArray, vi: IntArray, line: IntArray) -> Mesh:
    """The mesh of polygons given as corner vertex indices ``vi`` and each corner's line (lines ascending)."""
    starts = np.flatnonzero(np.r_[True, line[1:] != line[:-1]])
    sizes = np.diff(np.r_[starts, len(line)])
    if (sizes == sizes[0]).all():  # all triangles, or all quads: one (P, k) array
        return Mesh.from_polygons(positions, vi.reshape(-1, int(sizes[0])))
    polygons = np.split(vi, starts[1:])  # index arrays: sequences of ints to from_polygons
    return Mesh.from_polygons(positions, cast(Sequence[Sequence[int]], polygons))


def _normals(positions: FloatArray, normals: FloatArray, vi: IntArray, ni: IntArray,
             present: BoolArray) -> FloatArray | None:
    """Unit vertex normals from the corners' ``vn``, or None unless every vertex has exactly one non-zero one."""
    if len(vi) == 0 or not present.all():
        return None
    normal_of = np.full(len(positions), -1, dtype=np.int64)
    normal_of[vi] = ni  # one of each vertex's normals: all of them when they agree
    if (normal_of < 0).any() or not np.array_equal(normal_of[vi], ni):
        return None
    chosen = normals[normal_of]
    largest = np.abs(chosen).max(axis=1)
    if not (largest > 0).all():
        return None
    chosen = chosen / largest[:, None]  # first to at most 1: the length of 1e154-long normals would overflow
    out: FloatArray = chosen / np.linalg.norm(chosen, axis=1)[:, None]
    return out

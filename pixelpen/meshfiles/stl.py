"""STL triangle meshes, binary and ASCII, with exactly equal vertices welded into one.

Which kind: a file of exactly 84 + 50·n bytes (n the little-endian count at byte 80) is binary, even when its
80-byte header begins with ``solid`` (many exporters write that), unless the whole file is ASCII text; any
other file beginning with ``solid`` is ASCII.  Binary facets are read at once through a numpy structured
dtype; ASCII files (``solid name``, ``facet normal i j k``, ``outer loop``, three ``vertex x y z``,
``endloop``, ``endfacet``, ``endsolid name``, several solids allowed) are checked and read with numpy, and
only a malformed file is walked line by line to name the bad line.  Facet normals are not used (the winding
says which side is outside, and the Mesh computes its normals), so their fields are not read.  Welding:
vertices with the same three coordinates (``-0.0`` and ``0.0`` are the same) become one, in order of first
use; faces keep the file's order and winding.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from pixelpen.errors import ParseError
from pixelpen.geometry.mesh import Mesh
from pixelpen.meshfiles.limits import LIMITS, Limits
from pixelpen.meshfiles.text import FloatArray, IntArray, TextTable, keyword_code, parse_float, ranges

__all__ = ["FACET", "is_binary_stl", "read_stl"]

FACET = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attributes", "<u2")])
"""One binary STL facet: 50 bytes."""
HEADER = 84
"""Bytes before the first binary facet: an 80-byte header and the uint32 facet count."""

_TEXT = np.zeros(256, dtype=bool)
_TEXT[[9, 10, 12, 13, *range(32, 127)]] = True
_WORDS = ("solid", "facet", "outer", "vertex", "endloop", "endfacet", "endsolid")
SOLID, FACET_WORD, OUTER, VERTEX, ENDLOOP, ENDFACET, ENDSOLID = (keyword_code(w.encode()) for w in _WORDS)
NORMAL, LOOP = keyword_code(b"normal"), keyword_code(b"loop")
PATTERN = np.array([FACET_WORD, OUTER, VERTEX, VERTEX, VERTEX, ENDLOOP, ENDFACET])
"""The keywords of one ASCII facet's seven lines."""
TOKENS = np.array([5, 2, 4, 4, 4, 1, 1])
"""The tokens on each of those lines."""


def is_binary_stl(data: bytes) -> bool:
    """Whether ``data`` is a binary STL by the rule of the module docstring."""
    if len(data) < HEADER or HEADER + 50 * int.from_bytes(data[80:84], "little") != len(data):
        return False
    return not (data.lstrip()[:5] == b"solid" and bool(_TEXT[np.frombuffer(data, dtype=np.uint8)].all()))


def read_stl(data: bytes, source: str, *, limits: Limits = LIMITS) -> Mesh:
    """The mesh of an STL file's bytes (binary or ASCII); a ParseError naming ``source`` and where when malformed."""
    limits.check("max_bytes", len(data), "bytes in the file", source)
    if is_binary_stl(data):
        corners = _binary(data, source, limits)
    elif data.lstrip()[:5] == b"solid":
        corners = _ascii(data, source, limits)
    elif len(data) < HEADER:
        raise ParseError(f"not an STL file: {len(data)} bytes, too short for a binary header and not text "
                         "beginning with 'solid'", source=source, offset=0)
    else:
        count = int.from_bytes(data[80:84], "little")
        limits.check("max_faces", count, "facets in the header", source, offset=80)
        whole = (len(data) - HEADER) // 50
        if whole < count:
            raise ParseError(f"truncated binary STL: facet {whole} of {count} is incomplete",
                             source=source, offset=HEADER + 50 * whole)
        raise ParseError(f"a binary STL of {count} facets has {HEADER + 50 * count} bytes; this one has "
                         f"{len(data) - HEADER - 50 * count} more", source=source, offset=HEADER + 50 * count)
    return _welded(corners, source, limits)


def _binary(data: bytes, source: str, limits: Limits) -> FloatArray:
    """The (3n, 3) corners of a binary STL; a ParseError at the byte offset of a non-finite coordinate."""
    count = int.from_bytes(data[80:84], "little")
    limits.check("max_faces", count, "facets in the header", source, offset=80)
    facets = np.frombuffer(data, dtype=FACET, count=count, offset=HEADER)
    corners = facets["vertices"].reshape(-1, 3).astype(np.float64)
    bad = np.flatnonzero(~np.isfinite(corners).ravel())
    if len(bad):
        k = int(bad[0])
        facet, rest = divmod(k, 9)
        raise ParseError(f"facet {facet}: vertex {rest // 3 + 1} coordinate {'xyz'[rest % 3]} is not finite",
                         source=source, offset=HEADER + 50 * facet + 12 + 4 * rest)
    return corners


def _ascii(data: bytes, source: str, limits: Limits) -> FloatArray:
    """The (3n, 3) corners of an ASCII STL: checked with numpy, walked line by line only when malformed."""
    table = TextTable(data, source)
    table.check_line_length(limits.max_line_chars)
    lines = np.flatnonzero(table.tokens_per_line > 0)
    words = table.keyword[lines]
    facets = np.cumsum(words == FACET_WORD)
    if len(facets) and facets[-1] > limits.max_faces:
        line = int(lines[np.searchsorted(facets, limits.max_faces, "right")])
        raise ParseError(f"more facets than the limit max_faces={limits.max_faces:,}", source=source,
                         line=table.line_number(line))
    vertex_lines = _structure(table, lines, words)
    if vertex_lines is not None:
        _, values, tokens, rest = table.numbers(vertex_lines, 1)
        if len(rest) == 0:
            bad = np.flatnonzero(~np.isfinite(values))
            if len(bad):
                token = int(tokens[bad[0]])  # the per-line reader's words
                raise table.error(f"vertex {'xyz'[table.field(token) - 1]} is out of range", token)
            return values.reshape(-1, 3)
    return _walk(table, lines)


def _structure(table: TextTable, lines: IntArray, words: IntArray) -> IntArray | None:
    """The vertex lines when the non-blank ``lines`` are well-formed solids of facets, else None."""
    starts = np.flatnonzero(words == SOLID)
    ends = np.flatnonzero(words == ENDSOLID)
    if len(starts) == 0 or len(starts) != len(ends) or starts[0] != 0 or ends[-1] != len(words) - 1:
        return None
    if not (starts < ends).all() or not (starts[1:] == ends[:-1] + 1).all() or ((ends - starts - 1) % 7).any():
        return None
    inside = ranges(starts + 1, ends)
    body = words[inside].reshape(-1, 7)
    counts = table.tokens_per_line[lines[inside]].reshape(-1, 7)
    if not ((body == PATTERN).all() and (counts == TOKENS).all()):
        return None
    second = table.second_keyword()[lines[inside]].reshape(-1, 7)
    if not ((second[:, 0] == NORMAL).all() and (second[:, 1] == LOOP).all()):
        return None
    vertex_lines: IntArray = lines[inside].reshape(-1, 7)[:, 2:5].ravel()
    return vertex_lines


_NEXT = {b"solid": (b"facet", b"endsolid"), b"facet": (b"outer",), b"outer": (b"vertex",),
         b"vertex": (b"vertex", b"endloop"), b"endloop": (b"endfacet",), b"endfacet": (b"facet", b"endsolid"),
         b"endsolid": (b"solid",)}
"""Which keyword may follow which (a loop has exactly three vertices: counted separately)."""
_FORM = {b"facet": (5, b"normal"), b"outer": (2, b"loop"), b"vertex": (4, None), b"endloop": (1, None),
         b"endfacet": (1, None)}
"""Tokens on a line of each keyword, and the second token it needs."""


def _walk(table: TextTable, lines: IntArray) -> FloatArray:
    """Read an ASCII STL line by line, raising a ParseError at the first line out of place."""
    source = table.source
    expected: tuple[bytes, ...] = (b"solid",)
    corners: list[list[float]] = []
    in_loop = 0
    word = b""
    for line in lines.tolist():
        first, count = int(table.first_token[line]), int(table.tokens_per_line[line])
        word = table.token(first)
        number = table.line_number(line)
        if word == b"vertex" and in_loop == 3:
            expected = (b"endloop",)
        if word not in expected:
            raise table.error(f"expected {' or '.join(e.decode() for e in expected)}", first)
        if word == b"endloop" and in_loop != 3:
            raise table.error(f"a loop of {in_loop} vertices (an STL facet has 3)", first)
        tokens, second = _FORM.get(word, (count, None))
        if count != tokens or (second is not None and table.token(first + 1) != second):
            form = f"{word.decode()} {second.decode() if second else ''}".strip()
            raise ParseError(f"a {form} line has {count} fields, not {tokens}", source=source, line=number,
                             column=table.column(first))
        if word == b"vertex":
            corners.append([parse_float(table.token(t), f"vertex {'xyz'[t - first - 1]}", source, number,
                                        table.column(t)) for t in range(first + 1, first + 4)])
        in_loop = in_loop + 1 if word == b"vertex" else 0
        expected = _NEXT[word]
    if word != b"endsolid":
        raise ParseError(f"the file ends before endsolid (expected {' or '.join(e.decode() for e in expected)})",
                         source=source, line=table.line_number(int(lines[-1])) if len(lines) else 1)
    return np.array(corners, dtype=np.float64).reshape(-1, 3)


def _mix(x: npt.NDArray[np.uint64]) -> npt.NDArray[np.uint64]:
    """A 64-bit mixing step (xor-shift, multiply): every input bit reaches the high and the low bits."""
    x = x ^ (x >> np.uint64(33))
    x = x * np.uint64(0xFF51AFD7ED558CCD)
    return x ^ (x >> np.uint64(29))


def _welded(corners: FloatArray, source: str, limits: Limits) -> Mesh:
    """The mesh of (3n, 3) corners with exactly equal vertices made one (first-use order).

    The corners are sorted by one 64-bit hash of their coordinates' bits (one argsort, twice as fast as a
    lexsort of three keys); when two different corners share a hash, by a stable lexsort of the bits.
    """
    if len(corners) == 0:
        raise ParseError("no facets: an empty STL solid", source=source)
    keys = np.ascontiguousarray(corners + 0.0).view(np.uint64)  # + 0.0 makes -0.0 into 0.0
    digest = _mix(_mix(_mix(keys[:, 0]) + keys[:, 1]) + keys[:, 2])
    order = np.argsort(digest)
    ordered = digest[order]
    new = np.r_[True, ordered[1:] != ordered[:-1]]
    group = np.cumsum(new) - 1
    first_use = np.minimum.reduceat(order, np.flatnonzero(new))  # a group's first member is its first use
    index = np.empty(len(corners), dtype=np.int64)
    index[order] = group
    if not (keys == keys[first_use[index]]).all():  # a collision: two vertices of one hash
        order = np.lexsort((keys[:, 2], keys[:, 1], keys[:, 0]))
        ordered = keys[order]
        new = np.r_[True, (ordered[1:] != ordered[:-1]).any(axis=1)]
        first_use = order[new]  # lexsort is stable: a group's first member is its first use
        index[order] = np.cumsum(new) - 1
    by_use = np.argsort(first_use)
    rank = np.empty_like(first_use)
    rank[by_use] = np.arange(len(first_use))
    limits.check("max_vertices", len(first_use), "distinct vertices", source)
    return Mesh(corners[first_use[by_use]], rank[index].reshape(-1, 3))

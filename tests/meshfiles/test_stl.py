"""STL reading: binary and ASCII against trimesh, welding checked by a set of tuples, errors with offsets."""

from __future__ import annotations

import io
import struct

import numpy as np
import pytest
import trimesh

from pixelpen.errors import ParseError
from pixelpen.meshfiles import Limits, read_mesh, read_stl
from tests.meshfiles.test_obj import canonical


def binary_stl(triangles: np.ndarray, header: bytes = b"binary") -> bytes:
    """A binary STL written here with struct (independently of the reader)."""
    out = [header.ljust(80, b" ")[:80], struct.pack("<I", len(triangles))]
    for tri in np.asarray(triangles, dtype=np.float32):
        out.append(struct.pack("<12fH", 0, 0, 0, *tri.ravel(), 0))
    return b"".join(out)


def ascii_stl(triangles: np.ndarray, name: str = "thing") -> bytes:
    lines = [f"solid {name}"]
    for tri in triangles.tolist():
        lines += ["  facet normal 0 0 0", "    outer loop"]
        lines += [f"      vertex {x!r} {y!r} {z!r}" for x, y, z in tri]
        lines += ["    endloop", "  endfacet"]
    return ("\n".join([*lines, f"endsolid {name}"]) + "\n").encode()


SPHERE = trimesh.creation.icosphere(subdivisions=2)
TRIANGLES = SPHERE.vertices[SPHERE.faces].astype(np.float32).astype(np.float64)


def test_binary_stl_matches_trimesh_and_welds_exact_duplicates():
    data = binary_stl(TRIANGLES)
    mesh = read_stl(data, "sphere.stl")
    theirs = trimesh.load(io.BytesIO(data), file_type="stl")
    assert np.array_equal(canonical(mesh.vertices[mesh.faces]), canonical(theirs.vertices[theirs.faces]))
    assert len(mesh.vertices) == len({tuple(p) for p in TRIANGLES.reshape(-1, 3).tolist()}) == 162
    assert np.array_equal(mesh.vertices[mesh.faces], TRIANGLES)  # file order and winding kept


def test_a_binary_header_beginning_with_solid_still_reads_as_binary():
    mesh = read_stl(binary_stl(TRIANGLES, b"solid exported by a CAD program"), "s.stl")
    assert np.array_equal(mesh.vertices[mesh.faces], TRIANGLES)


def test_ascii_stl_matches_trimesh_and_the_binary_reading():
    data = ascii_stl(TRIANGLES)
    mesh = read_stl(data, "sphere.stl")
    theirs = trimesh.load(io.BytesIO(data), file_type="stl")
    assert np.array_equal(canonical(mesh.vertices[mesh.faces]), canonical(theirs.vertices[theirs.faces]))
    assert np.array_equal(mesh.vertices[mesh.faces], TRIANGLES)
    assert len(mesh.vertices) == 162


def test_several_ascii_solids_crlf_and_odd_spacing_read_as_one_mesh():
    a, b = ascii_stl(TRIANGLES[:3], "a"), ascii_stl(TRIANGLES[3:5], "b b")
    mesh = read_stl((a + b"\n\n" + b).replace(b"\n", b"\r\n").replace(b"vertex ", b"vertex\t "), "two.stl")
    assert np.array_equal(mesh.vertices[mesh.faces], TRIANGLES[:5])


def test_minus_zero_and_zero_are_one_vertex():
    tris = np.array([[[0.0, 0, 0], [1, 0, 0], [0, 1, 0]], [[-0.0, 0, 0], [0, 1, 0], [0, 0, 1]]])
    assert len(read_stl(binary_stl(tris), "z.stl").vertices) == 4


def test_read_mesh_detects_stl_by_content(tmp_path):
    (tmp_path / "model").write_bytes(binary_stl(TRIANGLES))
    (tmp_path / "model.txt").write_bytes(ascii_stl(TRIANGLES))
    for name in ("model", "model.txt"):
        assert np.array_equal(read_mesh(tmp_path / name).vertices[read_mesh(tmp_path / name).faces], TRIANGLES)


@pytest.mark.parametrize(("data", "offset", "words"), [
    (binary_stl(TRIANGLES[:4])[:-7], 84 + 150, "truncated"),
    (binary_stl(TRIANGLES[:4]) + b"xx", 84 + 200, "2 more"),
    (b"\0" * 40, 0, "too short"),
    (binary_stl(TRIANGLES[:2])[:80] + struct.pack("<I", 10**9) + b"\0" * 100, 80, "max_faces"),
])
def test_malformed_binary_files_name_the_byte_offset(data, offset, words):
    with pytest.raises(ParseError) as caught:
        read_stl(data, "bad.stl")
    assert (caught.value.source, caught.value.offset) == ("bad.stl", offset), str(caught.value)
    assert words in str(caught.value)


def test_a_non_finite_binary_coordinate_names_its_offset():
    data = bytearray(binary_stl(TRIANGLES[:3]))
    data[84 + 50 + 12 + 16:84 + 50 + 12 + 20] = struct.pack("<f", float("nan"))  # facet 1, vertex 2, y
    with pytest.raises(ParseError, match="facet 1: vertex 2 coordinate y") as caught:
        read_stl(bytes(data), "nan.stl")
    assert caught.value.offset == 84 + 50 + 12 + 16


GOOD = ascii_stl(TRIANGLES[:2])


@pytest.mark.parametrize(("data", "line", "words"), [
    (GOOD.replace(b"vertex -", b"vertex nan -", 1), 4, "fields"),
    (GOOD.replace(b"vertex -0.5", b"vertex nan", 1), 4, "not a number"),
    (GOOD.replace(b"vertex -0.5", b"vertex 1e400", 1), 4, "out of range"),
    (GOOD.replace(b"endloop", b"vertex 1 2 3\n endloop", 1), 7, "expected endloop"),
    (b"\n".join(GOOD.split(b"\n")[:4] + GOOD.split(b"\n")[6:]), 5, "a loop of 1 vertices"),
    (GOOD.replace(b"outer loop", b"outer", 1), 3, "outer loop line has 1 fields"),
    (GOOD[:GOOD.index(b"endsolid")], 15, "ends before endsolid"),
    (GOOD.replace(b"facet normal", b"facet nor", 1), 2, "fields"),
])
def test_malformed_ascii_files_name_the_line(data, line, words):
    with pytest.raises(ParseError) as caught:
        read_stl(data, "bad.stl")
    assert (caught.value.source, caught.value.line) == ("bad.stl", line), str(caught.value)
    assert words in str(caught.value)


def test_limits():
    with pytest.raises(ParseError, match="max_faces"):
        read_stl(GOOD, "g.stl", limits=Limits(max_faces=1))
    with pytest.raises(ParseError, match="max_vertices"):
        read_stl(binary_stl(TRIANGLES), "g.stl", limits=Limits(max_vertices=100))
    with pytest.raises(ParseError, match="no facets"):
        read_stl(b"solid empty\nendsolid empty\n", "e.stl")

"""OBJ reading: trimesh as the oracle on generated files, and clean errors naming line and column."""

from __future__ import annotations

import io
import time

import numpy as np
import pytest
import trimesh

from pixelpen.errors import ParseError
from pixelpen.meshfiles import Limits, read_mesh, read_obj


def canonical(triangles: np.ndarray) -> np.ndarray:
    """Triangles (F, 3, 3) as their smallest rotation (winding kept, repeated corners too), rows sorted."""
    tris = np.asarray(triangles, dtype=float)
    keys = [tuple(c) for c in tris.reshape(-1, 3)]
    out = []
    for f in range(len(tris)):
        corners = keys[3 * f:3 * f + 3]
        out.append(min(sum((corners[(k + i) % 3] for i in range(3)), ()) for k in range(3)))
    return np.array(sorted(out))


def oracle(text: bytes) -> np.ndarray:
    """The triangles trimesh reads from OBJ text (no processing)."""
    mesh = trimesh.load(io.BytesIO(text), file_type="obj", process=False, force="mesh")
    return canonical(mesh.vertices[mesh.faces])


def ours(text: bytes) -> np.ndarray:
    mesh = read_obj(text, "test.obj")
    return canonical(mesh.vertices[mesh.faces])


CUBE_QUADS = b"""# a unit cube of quads, CCW from outside
o cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
g sides
usemtl red
s off
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
"""


def obj_text(vertices: np.ndarray, faces: np.ndarray, form: str = "v", negative: bool = False) -> bytes:
    """OBJ text written here (independently of the reader) with corners in one of the four forms."""
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
    lines += [f"vt {k % 2} {k % 3}" for k in range(len(vertices))]
    lines += [f"vn 0 0 {1 + k}" for k in range(len(vertices))]
    n = len(vertices)
    for face in faces.tolist():
        idx = [(i - n if negative else i + 1) for i in face]
        corner = {"v": "{0}", "v/vt": "{0}/{0}", "v//vn": "{0}//{0}", "v/vt/vn": "{0}/{0}/{0}"}[form]
        lines.append("f " + " ".join(corner.format(i) for i in idx))
    return ("\n".join(lines) + "\n").encode()


def test_a_cube_of_quads_is_twelve_triangles_as_trimesh_reads_them():
    mesh = read_obj(CUBE_QUADS, "cube.obj")
    assert mesh.faces.shape == (12, 3)
    assert list(mesh.polygon) == [0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5]
    assert np.array_equal(ours(CUBE_QUADS), oracle(CUBE_QUADS))


@pytest.mark.parametrize("form", ["v", "v/vt", "v//vn", "v/vt/vn"])
@pytest.mark.parametrize("negative", [False, True])
def test_a_sphere_in_every_corner_form_matches_trimesh(form, negative):
    sphere = trimesh.creation.icosphere(subdivisions=2)
    text = obj_text(sphere.vertices, sphere.faces, form, negative)
    mesh = read_obj(text, "sphere.obj")
    assert np.array_equal(mesh.vertices, sphere.vertices)  # the file's vertex order, exact repr round trip
    assert np.array_equal(mesh.faces, sphere.faces)
    assert np.array_equal(ours(text), oracle(text))


def test_negative_indices_count_back_from_the_vertices_defined_so_far():
    text = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -4 -3 -1\n"
    mesh = read_obj(text, "n.obj")
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 1, 3]]
    # (trimesh 4/5 counts back from the file's last vertex instead, against the OBJ specification)


def test_polygons_of_several_sizes_fan_with_their_ids():
    text = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 1 0\nf 1 2 3\nf 1 2 3 4 5\nf 2 3 4 5\n"
    mesh = read_obj(text, "p.obj")
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 1, 2], [0, 2, 3], [0, 3, 4], [1, 2, 3], [1, 3, 4]]
    assert mesh.polygon.tolist() == [0, 1, 1, 1, 2, 2]
    assert np.array_equal(ours(text), oracle(text))


def test_odd_lines_read_one_by_one_agree_with_the_fast_path():
    plain = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n"
    odd = (b"v 0 0 0 1\n  v +1 0 0 # comment\r\nv 0 1 0 0.5 0.5 0.5\nv 0 \\\n0 1\nl 1 2\np 1\nmtllib a.mtl\n"
           b"f +1 2 3\nf 1/1/1 3/1/1 4/1/1\nvt 0\nvn 1 0 0\n")
    a, b = read_obj(plain, "plain.obj"), read_obj(odd, "odd.obj")
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)


def test_consistent_vertex_normals_are_kept_and_made_unit():
    text = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nvn 0 0 3\nf 1//1 2//2 3//1\n"
    assert read_obj(text, "n.obj").normals.tolist() == [[0, 0, 1]] * 3
    hard = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nvn 1 0 0\nf 1//1 2//1 3//1\nf 2//2 4//2 3//2\n"
    assert read_obj(hard, "h.obj").normals is None  # vertex 2 has two normals: the mesh computes its own


def test_read_mesh_takes_paths_and_binary_files(tmp_path):
    path = tmp_path / "cube.obj"
    path.write_bytes(CUBE_QUADS)
    assert read_mesh(path).faces.shape == (12, 3)
    with open(path, "rb") as stream:
        assert read_mesh(stream, format="obj").faces.shape == (12, 3)
    (tmp_path / "cube.model").write_bytes(CUBE_QUADS)
    assert read_mesh(tmp_path / "cube.model").faces.shape == (12, 3)  # not STL by content: OBJ


@pytest.mark.parametrize(("text", "line", "column", "words"), [
    (b"v 0 0 0\nv nan 0 0\n", 2, 3, "not a number"),
    (b"v 0 0 0\nv 1e400 0 0\n", 2, 3, "out of range"),
    (b"v 0 0 0\nv -1e400 0 0 # x\n", 2, 3, "out of range"),
    (b"v 0 0\n", 1, 1, "2 numbers"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", 4, 7, "index 0"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", 4, 7, "the file has 3"),
    (b"v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n", 3, 9, "2 defined before"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n", 4, 3, "texture vertex index 1"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", 4, 1, "2 corners"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/\n", 4, 7, "corner"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1-2\n", 4, 7, "corner"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n", 4, 7, "out of range"),
    (b"v 0 0 0\r\nv 1 0 0\r\nbogus 1\r\n", 3, 1, "unknown OBJ statement"),
    (b"v 0 \\\n0 0\nv 1 1.2.3 0\n", 3, 5, "not a number"),
])
def test_malformed_files_name_the_line_and_column(text, line, column, words):
    with pytest.raises(ParseError) as caught:
        read_obj(text, "bad.obj")
    error = caught.value
    assert (error.source, error.line, error.column) == ("bad.obj", line, column), str(error)
    assert words in str(error)


def test_a_file_without_faces_is_refused():
    with pytest.raises(ParseError, match="no faces"):
        read_obj(b"v 0 0 0\n", "points.obj")


def test_limits_are_checked_before_reading():
    many = b"v 0 0 0\n" * 11
    with pytest.raises(ParseError, match="max_vertices=10") as caught:
        read_obj(many, "m.obj", limits=Limits(max_vertices=10))
    assert caught.value.line == 11
    with pytest.raises(ParseError, match="max_bytes"):
        read_obj(many, "m.obj", limits=Limits(max_bytes=20))
    with pytest.raises(ParseError, match="max_line_chars") as caught:
        read_obj(b"v 0 0 0\nv" + b" 0" * 100 + b"\n", "m.obj", limits=Limits(max_line_chars=100))
    assert caught.value.line == 2
    with pytest.raises(ParseError, match="max_polygon_vertices"):
        read_obj(b"v 0 0 0\nf" + b" 1" * 10 + b"\n", "m.obj", limits=Limits(max_polygon_vertices=8))
    with pytest.raises(ParseError, match="max_faces") as caught:
        read_obj(b"v 0 0 0\n" + b"f 1 1 1 1\n" * 3, "m.obj", limits=Limits(max_faces=5))
    assert caught.value.line == 4


def test_a_long_malformed_number_is_refused_in_linear_time():
    started = time.perf_counter()
    with pytest.raises(ParseError, match="field 3 is not a number"):
        read_obj(b"v 1 2 " + b"9" * 60_000 + b"y\n", "long.obj")
    assert time.perf_counter() - started < 1.0  # a backtracking number pattern took seconds here


def test_the_plain_file_reader_gives_the_general_readers_mesh_or_leaves_the_file_to_it():
    from pixelpen.meshfiles import LIMITS
    from pixelpen.meshfiles.obj import _general_obj, _plain_obj

    sphere = trimesh.creation.icosphere(subdivisions=2)
    plain = [obj_text(sphere.vertices, sphere.faces).split(b"\nvt")[0] + b"\n" + b"\n".join(
        b"f " + b" ".join(str(i + 1).encode() for i in f) for f in sphere.faces.tolist()),
        b"# c\n\nv 0 0 0 1\nv 5. -0.0 0.000\nv 0 1 0 0.5 0.5 0.5\nv 1 1 1 1 0 0 0\nf 1 2 3 4\nf -1 -2 -3\n",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 0 0 1\nf -4 -1 -2 2 3",  # no final line break
        b"v .5 -.25 0.000000000000000000012345678\nf 1 1 1\n"]
    for text in plain:
        fast, general = _plain_obj(text, LIMITS), _general_obj(text, "t.obj", LIMITS)
        assert fast is not None
        for name in ("vertices", "faces", "polygon"):
            assert np.array_equal(getattr(fast, name), getattr(general, name)), name
        assert np.array_equal(np.signbit(fast.vertices), np.signbit(general.vertices))
    for odd in (b"v 1e5 0 0\nf 1 1 1\n", b"v +1 0 0\nf 1 1 1\n", b" v 1 0 0\nf 1 1 1\n",
                b"v 1 0 0\nf 1/1 1/1 1/1\n", b"v 1 0 0\nf 1 1 2\n", b"v 1 0 0\nf 1 1 0\n", b"v 1 0 0\r\nf 1 1 1\n",
                b"v 1 0 0\no x\nf 1 1 1\n", b"v 1 0 0 # c\nf 1 1 1\n", b"v 1-2 0 0\nf 1 1 1\n",
                b"v 1 0 0\nf 1 1 1 -\n", b"v 1 0 0\nf 1 1\n", b"v 1 0\nf 1 1 1\n", b"v 1.2.3 0 0\nf 1 1 1\n",
                b"v 1 0 0\n"):
        assert _plain_obj(odd, LIMITS) is None, odd


def test_plain_decimals_are_read_to_the_same_bits_as_float():
    from pixelpen.meshfiles.text import plain_numbers

    rng = np.random.default_rng(7)
    tokens = [f"{rng.uniform(-1e6, 1e6):.{int(rng.integers(0, 9))}f}" for _ in range(2000)]
    tokens += ["0", "-0", "-0.0", "5.", "123456789012345", "0.1", "-0.30000000000000004", "0.8506508083520399"]
    values, _, _ = plain_numbers(np.frombuffer(" ".join(tokens).encode() + b"\n", np.uint8), integer=False)
    expected = np.array([float(t) for t in tokens])
    assert np.array_equal(values.view(np.uint64), expected.view(np.uint64))

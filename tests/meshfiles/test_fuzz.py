"""Seeded mutation fuzzing of the OBJ and STL readers: every outcome is a mesh or a ParseError, fast and small."""

from __future__ import annotations

import pytest

from pixelpen.meshfiles import read_obj, read_stl
from tests.fuzzing import QUICK_CASES, SLOW_CASES, TOKENS, campaign
from tests.meshfiles.test_obj import CUBE_QUADS
from tests.meshfiles.test_stl import TRIANGLES, ascii_stl, binary_stl

OBJ_SEEDS = [
    CUBE_QUADS,
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\nf -3//1 -2//1 -1//1\nf 1/1 2/1 3/1\n",
    b"o a\r\nv 0 0 0 1\r\nv 1 0 0 # c\r\nv 0 \\\r\n1 0\r\nl 1 2\r\nf +1 2 3\r\n",
]
STL_SEEDS = [ascii_stl(TRIANGLES[:3]), binary_stl(TRIANGLES[:3]), binary_stl(TRIANGLES[:2], b"solid x")]
MESH_TOKENS = (*TOKENS, b"f", b"v", b"vn", b"/", b"//", b"-", b"0", b"-99", b"\\\n", b"facet", b"endsolid",
               b"vertex", b"#", b"\n")
"""The harness's troublemakers and the formats' own keywords and separators."""


def obj(data: bytes) -> None:
    read_obj(data, "fuzz.obj")


def stl(data: bytes) -> None:
    read_stl(data, "fuzz.stl")


@pytest.mark.parametrize(("name", "target", "seeds"), [("obj", obj, OBJ_SEEDS), ("stl", stl, STL_SEEDS)])
def test_mesh_fuzz_quick(name, target, seeds):
    campaign(name, target, seeds, QUICK_CASES, seed=12, tokens=MESH_TOKENS, seconds_per_case=2.0,
             memory_mb=32).check()


@pytest.mark.slow
@pytest.mark.parametrize(("name", "target", "seeds"), [("obj", obj, OBJ_SEEDS), ("stl", stl, STL_SEEDS)])
def test_mesh_fuzz_slow(name, target, seeds):
    result = campaign(name, target, seeds, SLOW_CASES, seed=13, tokens=MESH_TOKENS, seconds_per_case=5.0,
                      memory_mb=64)
    print(result.summary())
    result.check()

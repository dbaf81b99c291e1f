"""Tests of ``pixelpen render``: a small OBJ written here, drawn on file displays through the CLI entry point."""

import math
import re

import numpy as np
import pytest
from PIL import Image

from pixelpen.cli import main
from pixelpen.commands.render import parse_camera_items

CUBE_OBJ = """\
# a unit cube, counter-clockwise quads seen from outside
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 0 0 1
v 1 0 1
v 0 1 1
v 1 1 1
f 1 3 4 2
f 5 6 8 7
f 1 2 6 5
f 3 7 8 4
f 1 5 7 3
f 2 4 8 6
"""


@pytest.fixture(autouse=True)
def no_user_config(monkeypatch):
    monkeypatch.setenv("PIXELPEN_CONFIG", "")


@pytest.fixture
def cube(tmp_path):
    path = tmp_path / "cube.obj"
    path.write_text(CUBE_OBJ)
    return path


def test_render_shades_the_model_on_a_png_and_draws_its_edges_in_an_svg(cube, tmp_path, capsys):
    png, svg = tmp_path / "cube.png", tmp_path / "cube.svg"
    assert main(["render", str(cube), "--to", f"png:{png}?size=120x90", "--to", f"svg:{svg}?size=80x60mm"]) == 0
    err = capsys.readouterr().err
    assert f"rendered {cube} (12 triangles) on png:" in err and "on svg:" in err
    rgb = np.asarray(Image.open(png).convert("RGB")).astype(int)
    model = (rgb != 255).any(axis=2)
    rows, cols = np.flatnonzero(model.any(axis=1)), np.flatnonzero(model.any(axis=0))
    # fitted to the display: the model's projection spans the height less the 5 % margins, centred
    assert len(rows) == pytest.approx(90 / 1.1, abs=2)
    assert (cols.min() + cols.max() + 1) / 2 == pytest.approx(60, abs=2)
    # three faces seen, each flat-shaded in its own grey: three distinct greys make up most of the model
    _, counts = np.unique(rgb[model][:, 0], return_counts=True)
    assert (counts > 0.1 * model.sum()).sum() == 3
    text = svg.read_text()
    assert len(re.findall(r"<(path|polyline)\b", text)) >= 1


def test_render_in_parallel_from_the_front_shows_one_square_face(cube, tmp_path):
    png = tmp_path / "front.png"
    assert main(["render", str(cube), "--to", f"png:{png}?size=100x100", "--camera", "front",
                 "--projection", "parallel"]) == 0
    rgb = np.asarray(Image.open(png).convert("RGB")).astype(int)
    model = (rgb != 255).any(axis=2)
    # the front face z = 1 alone: a square of side 1 in a window of the bounding sphere's ... fitted: 100/1.1 px
    rows, cols = np.flatnonzero(model.any(axis=1)), np.flatnonzero(model.any(axis=0))
    assert len(rows) == pytest.approx(100 / 1.1, abs=1.5) and len(cols) == pytest.approx(100 / 1.1, abs=1.5)
    assert model[rows.min():rows.max() + 1, cols.min():cols.max() + 1].all()
    assert len(np.unique(rgb[model], axis=0)) == 1  # one flat face


def test_camera_items_are_views_or_keys():
    assert parse_camera_items([]) == ("three-quarter", {})
    view, keys = parse_camera_items(["isometric", "vup=0,0,1", "z_prp=5", "alpha=45", "phi=30"])
    assert view == "isometric" and keys["vup"] == (0, 0, 1) and keys["z_prp"] == 5
    assert keys["alpha"] == pytest.approx(math.pi / 4) and keys["phi"] == pytest.approx(math.pi / 6)


@pytest.mark.parametrize(("item", "message"), [
    ("sideways", "not a view"),
    ("fov=60", "unknown camera key(s) fov; known: "),
    ("vpn=1,2", "vpn takes three numbers"),
    ("near=x", "near takes numbers"),
    ("projection=parallel", "use --projection"),
])
def test_bad_camera_items_are_one_line_errors(cube, tmp_path, capsys, item, message):
    assert main(["render", str(cube), "--to", f"png:{tmp_path / 'x.png'}", "--camera", item]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pixelpen render: error:") and message in err


def test_a_malformed_model_is_a_one_line_error_naming_the_file_and_line(tmp_path, capsys):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    assert main(["render", str(bad), "--to", f"png:{tmp_path / 'x.png'}"]) == 2
    err = capsys.readouterr().err
    assert "bad.obj" in err and "4" in err and len(err.strip().splitlines()) == 1


def test_the_model_colour_is_the_material_colour(cube, tmp_path):
    png = tmp_path / "red.png"
    assert main(["render", str(cube), "--to", f"png:{png}?size=60x60", "--camera", "front", "--projection",
                 "parallel", "--model-colour", "red"]) == 0
    rgb = np.asarray(Image.open(png).convert("RGB")).astype(int)
    model = (rgb != 255).any(axis=2)
    r, g, b = rgb[model].T
    assert (g == b).all() and (r > g + 100).all()  # red diffuse light, plus a white specular term on all three

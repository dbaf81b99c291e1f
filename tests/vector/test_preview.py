"""Tests of display-list previews: PNG pixels where strokes and travel are, SVG structure."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest
from PIL import Image

from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.preview import render_preview

SVG_NS = "{http://www.w3.org/2000/svg}"


def drawing():
    # a red horizontal stroke at y=10 and a blue vertical one at x=90, 100 x 100 units with home at the origin
    return DisplayList.from_polylines(
        [np.array([[10, 10], [90, 10]]), np.array([[90, 20], [90, 100]])], pens=[1, 2],
        pen_colours={1: "#ff0000", 2: "#0000ff"},
    )


def colour_mask(img, rgb):
    a = np.asarray(img.convert("RGB")).astype(int)
    return np.all(np.abs(a - rgb) < 40, axis=2)


def test_png_strokes_in_pen_colours_and_travel(tmp_path):
    path = tmp_path / "p.png"
    render_preview(drawing(), path, size_px=200)
    img = Image.open(path)
    assert max(img.size) == 200
    red, blue = colour_mask(img, (255, 0, 0)), colour_mask(img, (0, 0, 255))
    # drawing spans 0..100 in both axes (home included) plus a 3 % margin: scale 200 / 106 px per unit
    scale = 200 / 106

    def px(x, y):
        return round((x + 3) * scale), round((y + 3) * scale)

    x, y = px(50, 10)
    assert red[y - 1: y + 2, x].any()
    x, y = px(90, 60)
    assert blue[y, x - 1: x + 2].any()
    # travel: from home (0,0) to (10,10) along the diagonal, drawn in a light colour
    light = colour_mask(img, (240, 128, 128))
    x, y = px(5, 5)
    assert light[y - 1: y + 2, x - 1: x + 2].any()
    assert not red[: px(0, 9)[1]].any()  # nothing red above the stroke


def test_png_without_travel(tmp_path):
    path = tmp_path / "p.png"
    render_preview(drawing(), path, size_px=200, show_travel=False)
    img = Image.open(path)
    assert not colour_mask(img, (240, 128, 128)).any()
    # without home in the frame the drawing spans 10..90 x 10..100
    assert colour_mask(img, (255, 0, 0)).any()


def test_png_y_up_flips(tmp_path):
    up, down = tmp_path / "up.png", tmp_path / "down.png"
    render_preview(drawing(), up, size_px=100, show_travel=False, y_up=True)
    render_preview(drawing(), down, size_px=100, show_travel=False)
    a, b = np.asarray(Image.open(up)), np.asarray(Image.open(down))
    np.testing.assert_array_equal(a, b[::-1])


def test_svg_preview_structure(tmp_path):
    path = tmp_path / "p.svg"
    render_preview(drawing(), path, size_px=300, pen_width_mm=0.5)
    root = ET.parse(path).getroot()
    assert root.get("height") == "300"  # the drawing is taller (0..100) than wide (0..90)
    paths = root.findall(f".//{SVG_NS}path")
    travel = [p for p in paths if p.get("stroke-dasharray")]
    strokes = {p.get("stroke"): p for p in paths if not p.get("stroke-dasharray")}
    assert len(travel) == 1 and travel[0].get("d").startswith("M0,0 10,10")
    assert set(strokes) == {"#ff0000", "#0000ff"}
    assert strokes["#ff0000"].get("d") == "M10,10 90,10"
    assert float(strokes["#0000ff"].get("stroke-width")) == pytest.approx(0.5)


def test_single_points_and_empty_lists(tmp_path):
    dots = DisplayList.from_polylines([np.array([[5, 5]]), np.array([[50, 50]])])
    render_preview(dots, tmp_path / "d.png", size_px=100, show_travel=False, pen_width_mm=3)
    assert (np.asarray(Image.open(tmp_path / "d.png").convert("L")) < 128).any()
    render_preview(DisplayList(), tmp_path / "e.png", size_px=64)
    assert Image.open(tmp_path / "e.png").size[0] >= 1
    render_preview(DisplayList(), tmp_path / "e.svg")
    ET.parse(tmp_path / "e.svg")


def test_bad_arguments(tmp_path):
    with pytest.raises(ConfigError, match="extension"):
        render_preview(drawing(), tmp_path / "p.xyz")
    with pytest.raises(ConfigError, match="size"):
        render_preview(drawing(), tmp_path / "p.png", size_px=0)
    with pytest.raises(ConfigError, match="pen width"):
        render_preview(drawing(), tmp_path / "p.png", pen_width_mm=0)

"""The svg: file display: page size and pen width checked, file names a file system takes."""

from __future__ import annotations

import pytest

import pixelpen
from pixelpen.display.picture import Polyline
from pixelpen.errors import ConfigError, URLError
from pixelpen.vector.svgimport import read_svg


def test_a_drawing_lands_in_the_file_at_true_size(tmp_path):
    out = tmp_path / "a.svg"
    with pixelpen.open(f"svg:{out}?size=100x50mm") as d:
        d.draw(Polyline([[10, 10], [90, 10]]))
    dl = read_svg(out)
    xs, ys = dl.points[:, 0] * dl.unit_mm, dl.points[:, 1] * dl.unit_mm
    assert sorted(xs.round(6).tolist()) == [10.0, 90.0]
    assert ys.round(6).tolist() == [40.0, 40.0]  # y up in the picture, y down in SVG: 50 - 10


@pytest.mark.parametrize("query, error, words", [
    ("size=1e999x10mm", URLError, "option size="),
    ("pen_width=nan", ConfigError, "pen_width"),
    ("pen_width=1e9", ConfigError, "pen_width"),
])
def test_bad_options_are_refused_naming_them(tmp_path, query, error, words):
    with pytest.raises(error, match=words):
        pixelpen.open(f"svg:{tmp_path / 'a.svg'}?{query}")


@pytest.mark.parametrize("name, words", [("a\x00.svg", "NUL"), ("x" * 300 + ".svg", "255")])
def test_file_names_no_file_system_takes_are_config_errors(name, words):
    with pytest.raises(ConfigError, match=f"svg file name.*{words}"):
        pixelpen.open(f"svg:{name}")


def test_options_are_specs_and_sizes_take_any_unit(tmp_path):
    from pixelpen.devices.files.svg import SvgFileDisplay
    from pixelpen.options import describe

    assert [name for name, _ in describe(SvgFileDisplay.OPTIONS)] == ["size", "pen_width"]
    with pixelpen.open(f"svg:{tmp_path / 'a.svg'}?size=4x2in&pen_width=0.5") as d:
        assert d.capabilities.size_mm == pytest.approx((101.6, 50.8))
    with pixelpen.open(f"svg:{tmp_path / 'b.svg'}?size=a3") as d:
        assert d.capabilities.size_mm == (297.0, 420.0)
    with pytest.raises(URLError, match=r"unknown option\(s\) dpi; known: pen_width, size"):
        pixelpen.open(f"svg:{tmp_path / 'a.svg'}?dpi=96")

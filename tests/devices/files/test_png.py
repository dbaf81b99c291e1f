"""The png: file display: URL options checked before anything is allocated, file names a file system takes."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import pixelpen
from pixelpen.display.picture import Polyline
from pixelpen.errors import ConfigError, URLError


def test_a_drawing_lands_in_the_file(tmp_path):
    out = tmp_path / "sub" / "a.png"
    with pixelpen.open(f"png:{out}?size=40x30&dpi=25.4") as d:  # 1 px = 1 mm, y down on the image
        d.draw(Polyline([[0, 15], [40, 15]]))
    pixels = np.asarray(Image.open(out).convert("L"))
    assert pixels.shape == (30, 40)
    dark_rows = sorted(set(np.flatnonzero((pixels < 128).any(axis=1)).tolist()))
    assert dark_rows and all(13 <= r <= 16 for r in dark_rows)


@pytest.mark.parametrize("query, error, words", [
    ("size=4x1e999", URLError, "option size='4x1e999'"),  # int(inf) raised OverflowError
    ("size=100000x100000", ConfigError, "MAX_PIXELS"),  # a 30 GB framebuffer
    ("size=4.5x3", URLError, "whole pixels"),
    ("dpi=inf", ConfigError, "dpi"),
    ("dpi=0", ConfigError, "dpi"),
])
def test_bad_options_are_refused_naming_them(tmp_path, query, error, words):
    with pytest.raises(error, match=words):
        pixelpen.open(f"png:{tmp_path / 'a.png'}?{query}")


@pytest.mark.parametrize("name, words", [("a\x00.png", "NUL"), ("x" * 300 + ".png", "255")])
def test_file_names_no_file_system_takes_are_config_errors(name, words):
    with pytest.raises(ConfigError, match=f"png file name.*{words}"):
        pixelpen.open(f"png:{name}")


def test_options_are_specs_read_by_the_shared_reader(tmp_path):
    from pixelpen.devices.files.png import PngFileDisplay
    from pixelpen.options import describe

    assert [name for name, _ in describe(PngFileDisplay.OPTIONS)] == ["size", "dpi", "mode", "background"]
    assert dict(describe(PngFileDisplay.OPTIONS))["size"].endswith("(default 800x600)")
    with pixelpen.open(f"png:{tmp_path / 'a.png'}?size=8x4&mode=l&background=%23102030") as d:
        assert d.capabilities.colour_model == "grey" and d.capabilities.size == (8.0, 4.0)
    with pytest.raises(URLError, match=r"option background='nocolour' is not valid"):
        pixelpen.open(f"png:{tmp_path / 'a.png'}?background=nocolour")
    with pytest.raises(URLError, match=r"option mode='CMYK' is not valid: expected one of 1, L, P, RGB565, RGB, RGBA"):
        pixelpen.open(f"png:{tmp_path / 'a.png'}?mode=CMYK")
    with pytest.raises(URLError, match=r"unknown option\(s\) colour; known: background, dpi, mode, size"):
        pixelpen.open(f"png:{tmp_path / 'a.png'}?colour=red")

"""Tests of the picture file format: round trips, and malformed files that must say where they are wrong."""

import json

import numpy as np
import pytest

from pixelpen.display.pictfile import load_picture, loads_picture, picture_to_dict, save_picture
from pixelpen.display.picture import (
    Arc, Bezier, BSpline, Circle, Ellipse, Fill, Image, Marker, Picture, Polygon, Polyline, Rectangle, Segment, Style,
    Text,
)
from pixelpen.errors import ParseError


def _every_primitive() -> Picture:
    pic = Picture(window=(0, 0, 100, 50))
    pic.add(Polyline([[0, 0], [1, 2]], Style(colour="red", width=0.5, dash=(1, 2), layer="a")))
    pic.add(Polygon(([[0, 0], [4, 0], [0, 4]], [[1, 1], [2, 1], [1, 2]]), Style(fill=Fill("hatch", angle=0.5, spacing=2))))
    pic.add(Rectangle(1, 2, 3, 4, Style(fill=Fill("pattern", pattern=((1, 0), (0, 1)), outline=False))))
    pic.add(Circle((5, 5), 2))
    pic.add(Ellipse((5, 5), 3, 1, angle=0.2))
    pic.add(Arc((1, 1), 2, 2, 0.1, 2.0, close="pie", style=Style(pen=3)))
    pic.add(Bezier([[0, 0], [1, 1], [2, 0], [3, 1]], degree=3))
    pic.add(BSpline([[0, 0], [1, 1], [2, 0], [3, 1]], degree=2, knots=(0, 0, 0, 0.5, 1, 1, 1)))
    pic.add(Marker([[1, 1], [2, 2]], kind="star", size=1.5))
    pic.add(Text((3, 4), "Hi", height=2, angle=0.3, align="center"))
    pic.add(Image(np.arange(24, dtype=np.uint8).reshape(2, 4, 3), (0, 0, 4, 2)))
    seg = Segment("s", transform=np.array([[1.0, 0, 5], [0, 1, 6], [0, 0, 1]]), visible=False)
    seg.add(Circle((0, 0), 1))
    pic.add(seg)
    return pic


def test_round_trip_keeps_every_field(tmp_path):
    pic = _every_primitive()
    path = tmp_path / "p.json"
    save_picture(pic, path)
    back = load_picture(path)
    assert picture_to_dict(back) == picture_to_dict(pic)
    # spot-check against the values put in, independent of the writer
    assert back.window == (0, 0, 100, 50)
    assert back.items[0].style.colour == (255, 0, 0) and back.items[0].style.dash == (1.0, 2.0)
    assert np.array_equal(back.items[10].pixels, np.arange(24, dtype=np.uint8).reshape(2, 4, 3))
    assert back.segment("s").visible is False and back.segment("s").transform[0, 2] == 5


def _doc(*items, **extra):
    return json.dumps({"format": "pixelpen-picture", "version": 1, "items": list(items), **extra})


@pytest.mark.parametrize(
    "text, words",
    [
        ("{not json", "line 1"),
        ("[]", "not a pixelpen picture"),
        (json.dumps({"format": "pixelpen-picture", "version": 99, "items": []}), "version"),
        (_doc({"type": "blob"}), r"\$\.items\[0\]\.type"),
        (_doc({"type": "polyline", "points": [[0, 0], [1]]}), r"\$\.items\[0\]\.points"),
        (_doc({"type": "polyline", "points": [[0, 0]], "bogus": 1}), "unknown field"),
        (_doc({"type": "circle", "center": [0, 0], "r": -1}), "radius"),
        (_doc({"type": "circle", "center": [0, 0], "r": 1, "style": {"colour": "nope"}}), "colour"),
        (_doc({"type": "segment", "name": ""}), "name"),
        (_doc({"type": "image", "rect": [0, 0, 1, 1], "png": "!!!"}), "base64 PNG"),
        (_doc(items=[]).replace('"items": []', '"items": 3'), "expected a list"),
        (_doc({"type": "polyline", "points": [[0, 0]]}, window=[0, 1]), r"\$\.window"),
    ],
)
def test_malformed_files_name_the_place(text, words):
    with pytest.raises(ParseError, match=words) as err:
        loads_picture(text, source="bad.json")
    assert "bad.json" in str(err.value)


def test_truncated_and_binary_files(tmp_path):
    good = _doc({"type": "polyline", "points": [[0, 0], [1, 1]]})
    with pytest.raises(ParseError, match="line"):
        loads_picture(good[: len(good) // 2])
    with pytest.raises(ParseError, match="UTF-8"):
        loads_picture(b"\xff\xfe\x00garbage")
    with pytest.raises(ParseError, match="cannot read"):
        load_picture(tmp_path / "missing.json")


def test_oversized_file_is_refused(tmp_path, monkeypatch):
    import pixelpen.display.pictfile as pf

    path = tmp_path / "big.json"
    path.write_text(_doc())
    monkeypatch.setattr(pf, "MAX_BYTES", 10)
    with pytest.raises(ParseError, match="more than"):
        load_picture(path)

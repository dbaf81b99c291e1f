"""Tests of the picture file format: round trips, and malformed files that must say where they are wrong."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.display.pictfile import load_picture, loads_picture, picture_to_dict, save_picture
from pixelpen.display.picture import (
    Arc,
    Bezier,
    BSpline,
    Circle,
    Ellipse,
    Fill,
    Image,
    Marker,
    Picture,
    Polygon,
    Polyline,
    Rectangle,
    Segment,
    Style,
    Text,
)
from pixelpen.errors import ParseError


def _every_primitive() -> Picture:
    pic = Picture(window=(0, 0, 100, 50))
    pic.add(Polyline([[0, 0], [1, 2]], Style(colour="red", width=0.5, dash=(1, 2), layer="a")))
    pic.add(
        Polygon(([[0, 0], [4, 0], [0, 4]], [[1, 1], [2, 1], [1, 2]]), Style(fill=Fill("hatch", angle=0.5, spacing=2)))
    )
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


P2 = [[0, 0], [1, 1]]


@pytest.mark.parametrize(
    "text, words",
    [
        (_doc({"type": {}}), r"\$\.items\[0\]\.type: unknown primitive type"),  # was TypeError: unhashable dict
        (
            _doc(
                {
                    "type": "rectangle",
                    "x0": 0,
                    "y0": 0,
                    "x1": 1,
                    "y1": 1,
                    "style": {"fill": {"style": "pattern", "pattern": 5}},
                }
            ),
            r"\$\.items\[0\]\.style\.fill.*rows",
        ),
        (_doc({"type": "segment", "name": "s", "items": 5}), r"\$\.items\[0\]\.items: expected a list"),
        (_doc({"type": "segment", "name": "s", "items": [5]}), r"\$\.items\[0\]\.items\[0\]: expected an object"),
        (_doc({"type": "text", "position": [0, 0], "text": 5}), r"\$\.items\[0\]: .*text must be a string"),
        (_doc({"type": "marker", "points": P2, "size": "2"}), r"\$\.items\[0\]: .*marker size"),
        (
            _doc({"type": "arc", "center": [0, 0], "rx": 1, "ry": 1, "start": [1], "end": 2}),
            r"\$\.items\[0\]: .*arc start",
        ),
        (_doc({"type": "circle", "center": [0, 0], "r": 1e308}), r"\$\.items\[0\]: .*circle radius"),
        (
            _doc({"type": "ellipse", "center": [0, 0], "rx": 1, "ry": 1, "angle": 1e400}),
            r"\$\.items\[0\]: .*ellipse angle",
        ),
        (_doc({"type": "polyline", "points": P2}, window=[0, 0, 0, 10]), r"\$\.window: .*degenerate"),
        (_doc({"type": "polyline", "points": [[0, 1e400], [1, 1]]}), r"\$\.items\[0\]\.points\[0\]: expected finite"),
        (_doc({"type": "polyline", "points": P2}, window=[0, 0, 10, 1e400]), r"\$\.window\[3\]: expected a finite"),
        (_doc({"type": "polyline", "points": P2, "style": {"width": "1"}}), r"\$\.items\[0\]\.style: .*line width"),
        (_doc({"type": "segment", "name": "s", "visible": "no"}), r"\$\.items\[0\]: .*visible"),
        (_doc({"type": "segment", "name": "s"}, {"type": "segment", "name": "s"}), r"\$\.items\[1\]: .*already exists"),
        (_doc({"type": "polyline", "points": P2}).replace('"version": 1', '"version": true'), r"\$\.version"),
    ],
)
def test_wrong_types_and_values_name_the_json_path(text, words):
    with pytest.raises(ParseError, match=words) as err:
        loads_picture(text, source="bad.json")
    assert "bad.json" in str(err.value)


def test_numbers_beyond_python_limits_are_parse_errors():
    digits = "9" * 5000  # int() of this raises ValueError (the 4300-digit limit); float() of 400 digits is inf
    text = _doc({"type": "polyline", "points": [[0, 0], [1, 1]]}).replace("[1, 1]", f"[1, {digits}]")
    with pytest.raises(ParseError, match=r"\$\.items\[0\]\.points\[1\]: expected finite"):
        loads_picture(text)
    pen = _doc({"type": "polyline", "points": [[0, 0]], "style": {"pen": 1}}).replace('"pen": 1', '"pen": ' + "1" * 400)
    with pytest.raises(ParseError, match="pen number"):
        loads_picture(pen)


@pytest.mark.parametrize("opener", ["[", '{"a":', '[{"b":'])
def test_deep_nesting_is_refused_with_its_byte_offset(opener):
    text = opener * 5000  # json.loads raised RecursionError on this
    with pytest.raises(ParseError, match=r"byte offset \d+: JSON nested more than 32 deep"):
        loads_picture(text)


def test_nesting_inside_strings_does_not_count():
    text = _doc({"type": "text", "position": [0, 0], "text": "[" * 5000 + '"{' * 100})  # dumps escapes the quotes
    assert loads_picture(text).items[0].text == "[" * 5000 + '"{' * 100


def _depth_reference(raw: bytes, limit: int):
    """Scalar scan: the offset of the first bracket outside strings nested more than ``limit`` deep."""
    depth, inside, escaped = 0, False, False
    for offset, char in enumerate(raw.decode("latin-1")):
        if inside:
            escaped, inside = (False, inside) if escaped else (char == "\\", char != '"')
        elif char == '"':
            inside = True
        elif char in "[{":
            depth += 1
            if depth > limit:
                return offset
        elif char in "]}":
            depth -= 1
    return None


@settings(max_examples=100, deadline=None)
@given(
    parts=st.lists(
        st.one_of(
            st.sampled_from(["[", "]", "{", "}", ",", "1"]),
            st.lists(st.sampled_from(["a", "[", "{", "]", '\\"', "\\\\"]), max_size=5).map(
                lambda p: '"' + "".join(p) + '"'
            ),
        ),
        max_size=40,
    ),
    limit=st.integers(0, 5),
    chunk=st.sampled_from([1, 2, 3, 7, 1 << 22]),
)
def test_the_vectorised_depth_scan_matches_a_scalar_scan(parts, limit, chunk):
    from pixelpen.display.pictfile import _first_too_deep

    raw = "".join(parts).encode()
    assert _first_too_deep(raw, limit, chunk) == _depth_reference(raw, limit)  # small chunks split strings, escapes


@pytest.mark.parametrize(
    "limit, value, words",
    [
        ("MAX_ITEMS", 1, "more than 1 items"),
        ("MAX_POINTS", 3, "more than 3 points"),
        ("MAX_DEPTH", 4, "nested more than 4"),  # object, items, polyline, points, point: 5
    ],
)
def test_per_file_limits_are_overridable(monkeypatch, limit, value, words):
    import pixelpen.display.pictfile as pf

    text = _doc(*[{"type": "polyline", "points": [[0, 0], [1, 1]]}] * 2)
    loads_picture(text)  # within the defaults
    monkeypatch.setattr(pf, limit, value)
    with pytest.raises(ParseError, match=words):
        loads_picture(text)


def test_bad_file_names_are_parse_errors(tmp_path):
    with pytest.raises(ParseError, match="NUL"):
        load_picture("a\x00b.json")
    with pytest.raises(ParseError, match="more than the 255"):
        load_picture(tmp_path / ("x" * 300 + ".json"))


def test_saving_under_a_bad_file_name_is_a_config_error(tmp_path):
    from pixelpen.errors import ConfigError

    with pytest.raises(ConfigError, match=r"picture file.*NUL"):
        save_picture(Picture(), str(tmp_path / "a\x00.json"))

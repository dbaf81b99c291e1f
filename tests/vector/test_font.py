"""Tests of Hershey stroke text: glyph data against Hershey's published coordinates, layout, alignment, errors."""

import logging
import math

import numpy as np
import pytest

from pixelpen.errors import ConfigError, ParseError
from pixelpen.vector.font import decode_glyph, font_names, load_font, parse_fonts, text_extent, text_strokes

# Hershey's simplex roman glyphs 501 (A), 508 (H), 509 (I) as distributed in the original data set
# ("  501  9I[RFJ[ RRFZ[ RMTWT", "  508  9G]KFK[ RYFY[ RKPYP", "  509  3NVRFR["), decoded by hand:
# bearings and vertices relative to the glyph centre, y down, cap line -12, baseline 9.
HERSHEY_A = {"left": -9, "right": 9, "strokes": [[(0, -12), (-8, 9)], [(0, -12), (8, 9)], [(-5, 2), (5, 2)]]}
HERSHEY_H = {"left": -11, "right": 11, "strokes": [[(-7, -12), (-7, 9)], [(7, -12), (7, 9)], [(-7, -2), (7, -2)]]}
HERSHEY_I = {"left": -4, "right": 4, "strokes": [[(0, -12), (0, 9)]]}


def strokes_of(glyph):
    return [glyph.points[a:b].tolist() for a, b in zip(glyph.offsets[:-1], glyph.offsets[1:], strict=False)]


@pytest.mark.parametrize("char, ref", [("A", HERSHEY_A), ("H", HERSHEY_H), ("I", HERSHEY_I)])
def test_shipped_simplex_glyphs_match_hersheys_coordinates(char, ref):
    for name in ("futural", "rowmans"):
        g = load_font(name).glyphs[char]
        assert (g.left, g.right) == (ref["left"], ref["right"])
        assert strokes_of(g) == [[list(p) for p in s] for s in ref["strokes"]]


def test_decode_glyph_reads_the_character_pair_encoding():
    g = decode_glyph("I[RFJ[ RRFZ[ RMTWT")  # the published encoding of glyph 501
    assert (g.left, g.right) == (-9, 9)
    assert strokes_of(g) == [[list(p) for p in s] for s in HERSHEY_A["strokes"]]
    space = decode_glyph("JZ")
    assert (space.left, space.right, len(space.points)) == (-8, 8, 0)


def test_a_in_world_units_with_cap_height_21_is_the_font_grid():
    # height 21 = the Hershey cap height, so one world unit per font unit; x measured from the left bearing, y up
    strokes = text_strokes("A", height=21)
    expected = [[[9, 21], [1, 0]], [[9, 21], [17, 0]], [[4, 7], [14, 7]]]
    assert [s.tolist() for s in strokes] == expected


def test_height_scales_glyphs_and_advances():
    strokes = text_strokes("HI", height=10.5)  # half the font grid
    # H at 0..11 wide, I starts after H's advance 22 units = 11 world units, its stem at 11 + 4/2
    assert [s.tolist() for s in strokes] == [
        [[2, 10.5], [2, 0]], [[9, 10.5], [9, 0]], [[2, 5.5], [9, 5.5]], [[13, 10.5], [13, 0]],
    ]
    ext = text_extent("HI", height=10.5)
    assert ext.width == pytest.approx((22 + 8) / 2)
    assert ext.height == pytest.approx(10.5 + 3.5)  # cap + descender (16 - 9 = 7 units)


def test_character_spacing_multiplies_advances():
    wide = text_extent("HHH", height=21, spacing=1.5)
    assert wide.width == pytest.approx(3 * 22 * 1.5)
    third_h = text_strokes("HHH", height=21, spacing=1.5)[6]
    assert third_h[0, 0] == pytest.approx(2 * 22 * 1.5 + 4)


@pytest.mark.parametrize("align, x0", [("left", 0.0), ("center", -15.0), ("right", -30.0)])
def test_horizontal_alignment(align, x0):
    ext = text_extent("HI", height=21, align=align, position=(100, 50))
    np.testing.assert_allclose(ext.corners[:, 0], [100 + x0, 100 + x0 + 30, 100 + x0 + 30, 100 + x0])
    first = text_strokes("HI", height=21, align=align, position=(100, 50))[0]
    assert first[0, 0] == pytest.approx(100 + x0 + 4)


@pytest.mark.parametrize("valign, base_y", [("baseline", 0.0), ("top", -21.0), ("bottom", 7.0), ("middle", -10.5)])
def test_vertical_alignment_single_line(valign, base_y):
    stem = text_strokes("I", height=21, valign=valign)[0]
    assert sorted(stem[:, 1].tolist()) == pytest.approx([base_y, base_y + 21])
    ext = text_extent("I", height=21, valign=valign)
    assert ext.corners[2, 1] == pytest.approx(base_y + 21)  # top = cap line
    assert ext.corners[0, 1] == pytest.approx(base_y - 7)  # bottom = descender line


def test_multiline_layout():
    strokes = text_strokes("I\nII", height=10, line_spacing=2.0, align="right")
    # line 2's baseline is 2 cap heights below line 1's; each line is right-aligned on its own
    assert len(strokes) == 3
    y_lo = sorted(min(s[:, 1]) for s in strokes)
    assert y_lo == pytest.approx([-20, -20, 0])
    first_line_x = [s[0, 0] for s in strokes if min(s[:, 1]) == pytest.approx(0)]
    assert first_line_x == pytest.approx([-4 * 10 / 21])  # stem 4 units right of the bearing, line 8 wide
    ext = text_extent("I\nII", height=10, line_spacing=2.0, align="right", valign="top")
    assert ext.width == pytest.approx(16 * 10 / 21)
    assert ext.height == pytest.approx(10 + 20 + 7 * 10 / 21)
    np.testing.assert_allclose(ext.corners[2], [0, 0], atol=1e-12)


def test_multiline_middle_and_bottom():
    # middle: halfway between the first cap line and the last baseline
    stems = text_strokes("I\nI", height=10, line_spacing=1.5, valign="middle")
    tops = sorted(max(s[:, 1]) for s in stems)
    bottoms = sorted(min(s[:, 1]) for s in stems)
    assert (tops[-1] + bottoms[0]) / 2 == pytest.approx(0)
    stems = text_strokes("I\nI", height=10, line_spacing=1.5, valign="bottom")
    assert min(min(s[:, 1]) for s in stems) == pytest.approx(7 * 10 / 21)


def test_rotation_is_about_the_position():
    plain = text_strokes("AH", height=7, position=(3, 4))
    turned = text_strokes("AH", height=7, position=(3, 4), angle=math.pi / 2)
    for p, q in zip(plain, turned, strict=False):
        rel = p - [3, 4]
        np.testing.assert_allclose(q, np.column_stack([3 - rel[:, 1], 4 + rel[:, 0]]), atol=1e-12)
    ext = text_extent("AH", height=7, position=(3, 4), angle=math.pi / 2)
    np.testing.assert_allclose(ext.corners[0], [3 + 7 / 3, 4], atol=1e-12)  # bottom-left: descender below


def test_slant_leans_by_tan():
    stem = text_strokes("I", height=21, slant=math.radians(20))[0]
    top = stem[np.argmax(stem[:, 1])]
    bottom = stem[np.argmin(stem[:, 1])]
    assert top[0] - bottom[0] == pytest.approx(21 * math.tan(math.radians(20)))
    assert bottom[0] == pytest.approx(4)


def test_unknown_characters_get_a_visible_box_and_a_warning(caplog):
    with caplog.at_level(logging.WARNING, logger="pixelpen.vector.font"):
        strokes = text_strokes("a\u00e9\u4e2d", height=21)
    assert "U+00E9" in caplog.text and "U+4E2D" in caplog.text
    a_only = text_strokes("a", height=21)
    boxes = strokes[len(a_only):]
    assert len(boxes) == 4  # per unknown character: a box with one diagonal, then the other diagonal
    for box in boxes:
        assert box[:, 1].min() == pytest.approx(0) and box[:, 1].max() == pytest.approx(21)
    assert np.array_equal(boxes[0][0], boxes[0][4])  # the box closes
    assert boxes[2][:, 0].min() - boxes[0][:, 0].min() == pytest.approx(text_extent("\u00e9", height=21).width)


def test_every_shipped_font_covers_printable_ascii():
    names = font_names()
    assert names[0] == "futural" and len(names) >= 2
    for name in names:
        f = load_font(name)
        assert set(map(chr, range(32, 127))) <= set(f.glyphs), name
        assert f.cap_height == 21
        h = f.glyphs["H"]
        assert h.points[:, 1].min() == f.cap  # the capital spans cap line to baseline


def test_empty_text():
    assert text_strokes("") == []
    assert text_strokes("   ") == []
    assert text_extent("", height=10).width == 0


def test_bad_arguments():
    with pytest.raises(ConfigError, match=r"unknown font 'nope'.*futural"):
        text_strokes("x", font="nope")
    with pytest.raises(ConfigError, match="height"):
        text_strokes("x", height=0)
    with pytest.raises(ConfigError, match="align"):
        text_strokes("x", align="middle")
    with pytest.raises(ConfigError, match="valign"):
        text_extent("x", valign="centre")
    with pytest.raises(ConfigError, match="spacing"):
        text_strokes("x", spacing=-1)


GOOD = "font demo cap=-12 base=9 bottom=16 A demo\n0041 I[RFJ[ RRFZ[ RMTWT\n"


def test_parse_fonts_reads_our_format():
    fonts = parse_fonts("# comment\n" + GOOD, "demo.txt")
    assert list(fonts) == ["demo"] and fonts["demo"].description == "A demo"
    assert strokes_of(fonts["demo"].glyphs["A"]) == [[list(p) for p in s] for s in HERSHEY_A["strokes"]]


@pytest.mark.parametrize("text, match, line", [
    ("0041 I[RFJ[\n", "before any 'font'", 1),
    ("font x cap=-12 base=9\n", "font line reads", 1),
    ("font x cap=a base=9 bottom=16 d\n0041 JZ\n", "integer", 1),
    ("font x cap=9 base=-12 bottom=16 d\n0041 JZ\n", "cap < base", 1),
    (GOOD + "ZZZZ JZ\n", "hex code point", 3),
    (GOOD + "0042 I[R\n", "even number", 3),
    (GOOD + "0042 I[R\u00e9\n", "printable ASCII", 3),
    (GOOD + "0042 I[ RRF\n", "start or end with a pen-up", 3),
    (GOOD + "0042 I[RF R RRG\n", "two pen-ups", 3),
    (GOOD + "0042\n", "reads 'XXXX GLYPH'", 3),
    (GOOD + GOOD, "defined twice", 3),
    ("font x cap=-12 base=9 bottom=16 d\n", "no glyphs", None),
])
def test_parse_fonts_rejects_malformed_data(text, match, line):
    with pytest.raises(ParseError, match=match) as info:
        parse_fonts(text, "bad.txt")
    assert info.value.source == "bad.txt" and info.value.line == line


REFERENCE_TEXTS = ["Hello, world!", "pixelpen\nreference scene\nthree", "AVATAR gjpqy 0123", "  x  \n\ny"]
REFERENCE_PARAMS = [
    {},
    {"position": (12.5, -3.25), "height": 7.0, "angle": 0.7, "slant": 0.3, "align": "center", "valign": "middle",
     "spacing": 1.2, "line_spacing": 1.4},
    {"position": (-100.0, 55.5), "height": 2.5, "angle": -2.2, "slant": -0.4, "align": "right", "valign": "bottom",
     "font": "futural"},
    {"height": 13.0, "angle": 3.14159 / 2, "valign": "top", "font": "timesr", "spacing": 0.8},
]


def test_glyphs_are_where_the_hand_written_transforms_put_them():
    # data/font_reference.npz: text_strokes/text_extent before they used geometry.transforms (shear, place);
    # the same points to rounding (the sums are associated differently), the same strokes
    from pathlib import Path

    ref = np.load(Path(__file__).parent / "data" / "font_reference.npz")
    cases = [(t, p) for t in REFERENCE_TEXTS for p in REFERENCE_PARAMS]
    for k, (text, params) in enumerate(cases):
        strokes = text_strokes(text, **params)
        assert [len(s) for s in strokes] == ref[f"n{k}"].tolist()
        np.testing.assert_allclose(np.concatenate(strokes), ref[f"s{k}"], rtol=0, atol=1e-12)
        extent = text_extent(text, **params)
        got = np.concatenate([[extent.width, extent.height], np.asarray(extent.corners).ravel()])
        np.testing.assert_allclose(got, ref[f"e{k}"], rtol=0, atol=1e-12)

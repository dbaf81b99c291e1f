"""Tests of SVG import/export: hand-computed transforms, units and viewBox, hiding, layers, errors, round trips."""

import io
import logging
import math

import numpy as np
import pytest

from pixelpen.errors import ConfigError, ParseError
from pixelpen.vector import svgimport
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.svgimport import read_svg, write_svg

NS = 'xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape"'
# svgelements converts mm with 0.0393701 in/mm (not 1/25.4): 5e-7 relative, far below any pen's resolution
REL = 2e-6


def svg(body, attrs='width="100mm" height="100mm" viewBox="0 0 100 100"'):
    return f'<svg {NS} {attrs}>{body}</svg>'.encode()


def strokes(dl):
    return [s for s in dl.strokes()]


def test_nested_translate_scale_rotate():
    body = ('<g transform="translate(10,20)"><g transform="scale(2)">'
            '<line x1="1" y1="1" x2="2" y2="1" stroke="black" transform="rotate(90)"/></g></g>')
    dl = read_svg(svg(body))
    # rotate(90): (x, y) -> (-y, x); scale 2; translate (10, 20)
    # (1, 1) -> (-1, 1) -> (-2, 2) -> (8, 22);  (2, 1) -> (-1, 2) -> (-2, 4) -> (8, 24)
    np.testing.assert_allclose(dl.points, [[8, 22], [8, 24]], rtol=REL)
    assert dl.unit_mm == 1.0


def test_matrix_and_rotate_about_a_point():
    body = ('<g transform="matrix(1 0 0 1 5 0)"><path d="M 10 0 L 20 0" stroke="black" '
            'transform="rotate(180 15 0)"/></g>')
    dl = read_svg(svg(body))
    # rotate 180 about (15, 0): 10 -> 20, 20 -> 10; then x + 5
    np.testing.assert_allclose(dl.points, [[25, 0], [15, 0]], rtol=REL, atol=1e-9)


@pytest.mark.parametrize("attrs, x2, expected_mm", [
    ('width="4in" height="2in"', "96", 25.4),  # no viewBox: user units are px at 96 dpi
    ('width="4in" height="2in"', "1in", 25.4),
    ('width="100mm" height="100mm"', "10mm", 10.0),
    ('width="10cm" height="10cm"', "1cm", 10.0),
    ('', "96", 25.4),  # no size at all: px
    ('width="100mm" height="50mm" viewBox="0 0 200 100"', "10", 5.0),  # viewBox: 2 units per mm
    ('width="200mm" height="100mm" viewBox="0 0 20 10"', "1", 10.0),
])
def test_units_and_viewbox_to_millimetres(attrs, x2, expected_mm):
    dl = read_svg(svg(f'<line x1="0" y1="0" x2="{x2}" y2="0" stroke="black"/>', attrs))
    np.testing.assert_allclose(dl.points[1], [expected_mm, 0], rtol=REL, atol=1e-9)


def test_viewbox_origin_and_aspect_ratio():
    # viewBox 10 x 20 in a 100 x 100 mm page, xMidYMid meet: scale 5, centred horizontally (offset 25 mm)
    dl = read_svg(svg('<line x1="0" y1="0" x2="10" y2="20" stroke="black"/>',
                      'width="100mm" height="100mm" viewBox="0 0 10 20"'))
    np.testing.assert_allclose(dl.points, [[25, 0], [75, 100]], rtol=REL)
    # preserveAspectRatio="none": independent scales 10 and 5
    dl = read_svg(svg('<line x1="0" y1="0" x2="10" y2="20" stroke="black"/>',
                      'width="100mm" height="100mm" viewBox="0 0 10 20" preserveAspectRatio="none"'))
    np.testing.assert_allclose(dl.points, [[0, 0], [100, 100]], rtol=REL)
    # a shifted viewBox origin moves the drawing
    dl = read_svg(svg('<line x1="50" y1="50" x2="60" y2="50" stroke="black"/>',
                      'width="100mm" height="100mm" viewBox="50 50 100 100"'))
    np.testing.assert_allclose(dl.points, [[0, 0], [10, 0]], rtol=REL, atol=1e-9)


def test_basic_shapes():
    body = ('<rect x="1" y="2" width="3" height="4" stroke="red" fill="none"/>'
            '<polyline points="0,0 1,1 2,0" stroke="red" fill="none"/>'
            '<polygon points="0,0 1,1 2,0" stroke="red" fill="none"/>')
    dl = read_svg(svg(body))
    rect, poly, gon = strokes(dl)
    np.testing.assert_allclose(rect, [[1, 2], [4, 2], [4, 6], [1, 6], [1, 2]], rtol=REL)
    np.testing.assert_allclose(poly, [[0, 0], [1, 1], [2, 0]], rtol=REL)
    np.testing.assert_allclose(gon, [[0, 0], [1, 1], [2, 0], [0, 0]], rtol=REL)


def test_subpaths_become_separate_strokes():
    dl = read_svg(svg('<path d="M0,0 L1,0 M5,5 L6,5 L6,6 Z M9,9" stroke="black"/>'))
    assert [s.shape[0] for s in strokes(dl)] == [2, 4]  # the lone move draws nothing


def test_circle_is_flattened_within_tolerance():
    tol = 0.05
    dl = read_svg(svg('<circle cx="50" cy="40" r="30" stroke="black" fill="none"/>'), tolerance=tol)
    pts = dl.stroke(0)
    r = np.hypot(*(pts - [50, 40]).T)
    np.testing.assert_allclose(r, 30, rtol=REL)  # vertices on the circle
    mids = (pts[1:] + pts[:-1]) / 2
    sagitta = 30 - np.hypot(*(mids - [50, 40]).T)
    assert sagitta.max() <= tol * (1 + 1e-6)
    # and not absurdly fine: the chord count is within 2x of the minimum for this tolerance
    n_min = 2 * math.pi / (2 * math.acos(1 - tol / 30))
    assert len(pts) - 1 <= 2 * n_min + 4


def test_cubic_bezier_is_within_tolerance_of_the_curve():
    tol = 0.01
    p = np.array([[0, 0], [10, 30], [40, -20], [50, 10]], float)
    dl = read_svg(svg(f'<path d="M{p[0,0]},{p[0,1]} C{p[1,0]},{p[1,1]} {p[2,0]},{p[2,1]} {p[3,0]},{p[3,1]}" '
                      'stroke="black" fill="none"/>'), tolerance=tol)
    poly = dl.stroke(0)
    t = np.linspace(0, 1, 4001)[:, None]
    curve = (1 - t) ** 3 * p[0] + 3 * (1 - t) ** 2 * t * p[1] + 3 * (1 - t) * t ** 2 * p[2] + t ** 3 * p[3]
    # distance of every dense curve sample to the polyline
    a, b = poly[:-1], poly[1:]
    d = b - a
    w = curve[:, None, :] - a[None]
    s = np.clip((w * d).sum(-1) / (d * d).sum(-1), 0, 1)
    dist = np.hypot(*(w - s[..., None] * d).transpose(2, 0, 1)).min(axis=1)
    assert dist.max() <= tol * 1.01
    np.testing.assert_allclose(poly[[0, -1]], p[[0, 3]], rtol=REL, atol=1e-9)


def test_hidden_elements_are_skipped(caplog):
    body = ('<line x1="0" y1="0" x2="1" y2="0" stroke="black" visibility="hidden"/>'
            '<line x1="0" y1="0" x2="2" y2="0" stroke="black" style="display:none"/>'
            '<line x1="0" y1="0" x2="3" y2="0" stroke="black" style="visibility:hidden"/>'
            '<g style="display:none"><line x1="0" y1="0" x2="4" y2="0" stroke="black"/></g>'
            '<g visibility="hidden"><line x1="0" y1="0" x2="5" y2="0" stroke="black"/>'
            '<line x1="0" y1="0" x2="6" y2="0" stroke="black" visibility="visible"/></g>'
            '<line x1="0" y1="0" x2="7" y2="0" stroke="black"/>')
    with caplog.at_level(logging.WARNING, logger="pixelpen.vector.svgimport"):
        dl = read_svg(svg(body))
    # visibility is inherited but can be overridden by a child; display:none cannot
    np.testing.assert_allclose(sorted(dl.ends[:, 0]), [6, 7], rtol=REL)
    assert "hidden element(s) skipped" in caplog.text


def test_fill_only_shapes_give_outlines_with_a_warning(caplog):
    body = ('<rect x="0" y="0" width="2" height="2" fill="#00ff00"/>'
            '<rect x="5" y="5" width="2" height="2" fill="none"/>'
            '<text x="0" y="10">hello</text>')
    with caplog.at_level(logging.WARNING, logger="pixelpen.vector.svgimport"):
        dl = read_svg(svg(body))
    assert len(dl) == 1 and dl.pen_colours == {1: "#00ff00"}
    np.testing.assert_allclose(dl.stroke(0), [[0, 0], [2, 0], [2, 2], [0, 2], [0, 0]], rtol=REL, atol=1e-9)
    assert "fill-only shape(s) imported as outlines" in caplog.text
    assert "neither stroke nor fill" in caplog.text
    assert "text element(s) skipped" in caplog.text


def test_layers_by_stroke_colour():
    body = ('<line x1="0" y1="0" x2="1" y2="0" stroke="red"/>'
            '<line x1="0" y1="0" x2="2" y2="0" stroke="#0000ff"/>'
            '<line x1="0" y1="0" x2="3" y2="0" stroke="rgb(255,0,0)"/>')
    dl = read_svg(svg(body))
    assert dl.layers.tolist() == [1, 2, 1] and dl.pens.tolist() == [1, 2, 1]
    assert dl.layer_names == {1: "#ff0000", 2: "#0000ff"}
    assert dl.pen_colours == {1: "#ff0000", 2: "#0000ff"}


INKSCAPE = ('<g inkscape:groupmode="layer" inkscape:label="outline" transform="translate(1,0)">'
            '<line x1="0" y1="0" x2="1" y2="0" stroke="red"/>'
            '<g><line x1="0" y1="0" x2="2" y2="0" stroke="blue"/></g></g>'
            '<g inkscape:groupmode="layer" inkscape:label="fill" style="display:none">'
            '<line x1="0" y1="0" x2="9" y2="0" stroke="red"/></g>'
            '<g inkscape:groupmode="layer" inkscape:label="text">'
            '<line x1="0" y1="0" x2="3" y2="0" stroke="red"/></g>')


def test_inkscape_layers_become_layers_in_auto_mode():
    dl = read_svg(svg(INKSCAPE))
    assert dl.layer_names == {1: "outline", 2: "text"}  # the hidden layer is skipped
    assert dl.layers.tolist() == [1, 1, 2]
    assert dl.pens.tolist() == [1, 2, 1]  # pens still follow stroke colours
    np.testing.assert_allclose(dl.ends[:, 0], [2, 3, 3], rtol=REL)
    by_colour = read_svg(svg(INKSCAPE), layer_by="stroke")
    assert by_colour.layer_names == {1: "#ff0000", 2: "#0000ff"}


def test_top_level_groups_become_layers_in_group_mode():
    body = ('<g id="first"><line x1="0" y1="0" x2="1" y2="0" stroke="red"/>'
            '<g id="inner"><line x1="0" y1="0" x2="2" y2="0" stroke="red"/></g></g>'
            '<line x1="0" y1="0" x2="3" y2="0" stroke="red"/>'
            '<g><line x1="0" y1="0" x2="4" y2="0" stroke="red"/></g>')
    dl = read_svg(svg(body), layer_by="group")
    assert dl.layers.tolist() == [1, 1, 2, 3]
    assert dl.layer_names == {1: "first", 2: "root", 3: "group 3"}


def test_use_elements_are_expanded():
    body = ('<defs><line id="l" x1="0" y1="0" x2="1" y2="0" stroke="black"/></defs>'
            '<use href="#l" x="10" y="5"/>')
    dl = read_svg(svg(body))
    np.testing.assert_allclose(dl.points, [[10, 5], [11, 5]], rtol=REL)


def test_empty_drawing_warns_and_gives_an_empty_list(caplog):
    with caplog.at_level(logging.WARNING, logger="pixelpen.vector.svgimport"):
        dl = read_svg(svg(""))
    assert len(dl) == 0 and "no drawable elements" in caplog.text


@pytest.mark.parametrize("data, match", [
    (b"", "empty file"),
    (b"   \n", "empty file"),
    (b"hello world", "not well-formed XML"),
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "not well-formed XML"),
    (b"<html><body>hi</body></html>", "root element is <html>"),
    (f'<svg {NS}><line x1="0" y1="0" x2="1" y2="0" stroke="black"></svg>'.encode(), "mismatched tag"),
    (f'<svg {NS}><line x1="0"'.encode(), "not well-formed|no element|unclosed"),
])
def test_malformed_and_non_svg_input(tmp_path, data, match):
    path = tmp_path / "in.svg"
    path.write_bytes(data)
    with pytest.raises(ParseError, match=match) as info:
        read_svg(path)
    assert info.value.source == str(path) and str(path) in str(info.value)


def test_parse_error_position():
    with pytest.raises(ParseError) as info:
        read_svg(b'<svg>\n  <g>\n  </svg>', layer_by="auto")
    assert info.value.line == 3 and info.value.column is not None


def test_missing_file_is_a_parse_error_naming_it(tmp_path):
    with pytest.raises(ParseError, match="cannot read SVG file") as info:
        read_svg(tmp_path / "nope.svg")
    assert "nope.svg" in str(info.value)


def test_bad_arguments():
    with pytest.raises(ConfigError, match="tolerance"):
        read_svg(svg(""), tolerance=0)
    with pytest.raises(ConfigError, match="layer_by"):
        read_svg(svg(""), layer_by="colour")


def test_reads_from_binary_and_text_streams():
    data = svg('<line x1="0" y1="0" x2="1" y2="0" stroke="black"/>')
    for src in (io.BytesIO(data), io.StringIO(data.decode())):
        assert len(read_svg(src)) == 1


def make_dl(unit_mm=1.0):
    return DisplayList.from_polylines(
        [np.array([[10, 10], [20, 10], [20, 30]]), np.array([[5, 5], [6, 7]]), np.array([[40, 50]]),
         np.array([[1, 1], [2, 2]])],
        pens=[1, 2, 1, 3], layers=[1, 1, 2, 3], layer_names={1: "outline & <more>", 2: "dots", 3: "blue"},
        unit_mm=unit_mm, pen_colours={1: "#000000", 2: "#ff0000", 3: "#0000ff"},
    )


def test_write_svg_has_true_size_and_one_layer_group_each(tmp_path):
    dl = make_dl(unit_mm=0.025)  # HP-GL plotter units
    path = tmp_path / "out.svg"
    write_svg(dl, path)
    text = path.read_text()
    # the drawing reaches 40 x 50 units from the origin = 1 x 1.25 mm
    assert 'width="1mm" height="1.25mm" viewBox="0 0 40 50"' in text
    assert text.count('inkscape:groupmode="layer"') == 3
    assert 'inkscape:label="outline &amp; &lt;more&gt;"' in text
    back = read_svg(path)
    np.testing.assert_allclose(back.stroke(0), dl.stroke(0) * 0.025, rtol=REL)


def test_write_then_read_round_trip(tmp_path):
    dl = make_dl()
    buf = io.BytesIO()
    write_svg(dl, buf, size_mm=(210, 297))
    back = read_svg(buf.getvalue())
    assert 'width="210mm" height="297mm"' in buf.getvalue().decode()
    assert back.layer_names == dl.layer_names
    assert back.layers.tolist() == dl.layers.tolist()
    assert back.pen_colours == dl.pen_colours and back.pens.tolist() == dl.pens.tolist()
    assert len(back) == len(dl)
    for a, b in zip(back.strokes(), dl.strokes(), strict=False):
        if len(b) == 1:  # a dot is written as a zero-length line
            b = np.vstack([b, b])
        np.testing.assert_allclose(a, b, rtol=REL)


def test_write_svg_to_text_stream_and_empty_list():
    buf = io.StringIO()
    write_svg(DisplayList(), buf)
    assert buf.getvalue().startswith("<?xml") and 'width="1mm"' in buf.getvalue()
    assert len(read_svg(buf.getvalue().encode())) == 0
    with pytest.raises(ConfigError, match="page size"):
        write_svg(DisplayList(), io.StringIO(), size_mm=(0, 10))


def test_write_svg_negative_coordinates_extend_the_page():
    dl = DisplayList.from_polylines([np.array([[-10, -5], [10, 5]])])
    buf = io.StringIO()
    write_svg(dl, buf)
    assert 'viewBox="-10 -5 20 10"' in buf.getvalue()


def test_non_finite_coordinates_are_a_parse_error():
    with pytest.raises(ParseError, match=r"'far'.*non-finite"):
        read_svg(svg('<line id="far" x1="0" y1="0" x2="1e400" y2="0" stroke="black"/>'))


def test_huge_arc_with_tiny_tolerance_is_capped_not_hung(monkeypatch):
    monkeypatch.setattr(svgimport, "MAX_SEGMENT_POINTS", 500)
    dl = read_svg(svg('<circle cx="0" cy="0" r="1e9" stroke="black" fill="none"/>'), tolerance=1e-9)
    assert len(dl.points) == 4 * 500 + 1  # move, four capped arcs
    assert np.array_equal(dl.points[0], dl.points[-1])  # a closed subpath ends exactly at its start


def segment_set(dl, digits=6):
    """Pen-down segments as an orientation-free set, rounded to ``digits`` decimals of a mm."""
    seg = np.round(dl.segments() * dl.unit_mm, digits)
    return {tuple(s) if tuple(s[:2]) <= tuple(s[2:]) else tuple(s[2:]) + tuple(s[:2]) for s in seg.tolist()}


def test_page_survives_write_and_read(tmp_path):
    # an A4 landscape page whose drawing sits at (100, 50) mm, far from the page's origin
    body = ('<g transform="translate(100,50)"><rect x="0" y="0" width="30" height="20" stroke="black" fill="none"/>'
            '<circle cx="40" cy="10" r="5" stroke="red" fill="none"/></g>')
    dl = read_svg(svg(body, 'width="297mm" height="210mm" viewBox="0 0 297 210"'))
    assert dl.page == (297.0, 210.0)
    assert dl.bounds()[:2] == pytest.approx((100, 50))
    path = tmp_path / "page.svg"
    write_svg(dl, path)
    assert 'width="297mm" height="210mm" viewBox="0 0 297 210"' in path.read_text()
    back = read_svg(path)
    assert back.page == (297.0, 210.0)
    assert segment_set(back) == segment_set(dl)
    # derived display lists keep the page
    assert dl.reordered(range(len(dl))[::-1]).page == dl.page
    assert dl.select(np.arange(len(dl)) % 2 == 0).page == dl.page
    assert DisplayList.concat([dl, make_dl()]).page == dl.page


@pytest.mark.parametrize("attrs, page", [
    ('width="210mm" height="297mm"', (210, 297)),
    ('width="8.5in" height="11in" viewBox="0 0 816 1056"', (215.9, 279.4)),
    ('width="21cm" height="29.7cm" viewBox="0 0 2100 2970"', (210, 297)),
    ('width="595pt" height="842pt"', (595 * 25.4 / 72, 842 * 25.4 / 72)),
    ('viewBox="0 0 96 48"', (25.4, 12.7)),  # no size: the viewBox in px
    ('width="100%" height="100%" viewBox="0 0 96 48"', (25.4, 12.7)),
    ('', None),  # no size and no viewBox: no page
    ('width="100mm"', None),
])
def test_page_size_from_width_height_and_viewbox(attrs, page):
    dl = read_svg(svg('<line x1="0" y1="0" x2="1" y2="0" stroke="black"/>', attrs))
    assert dl.page == (None if page is None else pytest.approx(page, rel=1e-12))


def test_page_in_device_units_is_written_in_mm():
    dl = DisplayList.from_polylines([np.array([[4000, 2000], [4400, 2000]])], unit_mm=0.025, page=(11880, 8400))
    buf = io.StringIO()
    write_svg(dl, buf)
    assert 'width="297mm" height="210mm" viewBox="0 0 11880 8400"' in buf.getvalue()
    back = read_svg(buf.getvalue().encode())
    assert back.page == pytest.approx((297, 210), rel=1e-12)
    # svgelements prints matrices to 12 digits
    np.testing.assert_allclose(back.points, [[100, 50], [110, 50]], rtol=1e-9)


@pytest.mark.parametrize("page", [(0, 10), (10, -1), (float("inf"), 1), (1, 2, 3), "a4"])
def test_bad_page_is_a_config_error(page):
    with pytest.raises(ConfigError, match="page"):
        DisplayList(page=page)

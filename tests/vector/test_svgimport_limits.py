"""SVG import on hostile input: each per-file limit and pre-check gives a ParseError naming file, element and limit."""

import numpy as np
import pytest

from pixelpen.errors import ConfigError, ParseError
from pixelpen.vector.svgimport import SvgLimits, read_svg

NS = 'xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink"'
LINE = '<line x1="0" y1="0" x2="1" y2="0" stroke="black"/>'


def doc(body, attrs='width="100mm" height="100mm" viewBox="0 0 100 100"'):
    return f"<svg {NS} {attrs}>{body}</svg>".encode()


def refused(data, match, limits=None, tmp_path=None):
    path = tmp_path / "hostile.svg"
    path.write_bytes(data)
    with pytest.raises(ParseError, match=match) as info:
        read_svg(path, limits=limits)
    assert str(path) in str(info.value)
    return info.value


def test_deep_nesting_is_refused_not_a_recursion_error(tmp_path):
    err = refused(
        doc("<g>" * 1000 + LINE + "</g>" * 1000), r"<g>: nested deeper than 200 .*max_depth", tmp_path=tmp_path
    )
    assert err.line == 1 and err.column is not None
    # a nesting just inside the limit still imports (svg + 198 groups + line = 200 levels)
    assert len(read_svg(doc("<g>" * 198 + LINE + "</g>" * 198))) == 1


def test_nesting_through_use_counts(tmp_path):
    chain = '<g id="a0">' + LINE + "</g>" + "".join(f'<g id="a{k}"><use href="#a{k - 1}"/></g>' for k in range(1, 60))
    refused(
        doc(f"<defs>{chain}</defs>" + '<use href="#a59"/>'),
        "once <use> is expanded",
        SvgLimits(max_depth=100),
        tmp_path,
    )
    assert len(read_svg(doc(f"<defs>{chain}</defs>" + '<use href="#a59"/>'))) == 1


def test_use_cycle_is_refused(tmp_path):
    refused(
        doc('<g id="a">' + LINE + '<use xlink:href="#a"/></g>'),
        r"<use>: refers to #a, which contains it",
        tmp_path=tmp_path,
    )


def test_use_fan_out_is_refused_before_expanding(tmp_path):
    # ten copies of ten copies ... of a line: 10^5 strokes from 1.4 kB
    def defs(levels):
        return (
            '<defs><g id="l0">'
            + LINE
            + "</g>"
            + "".join(f'<g id="l{k}">' + f'<use href="#l{k - 1}"/>' * 10 + "</g>" for k in range(1, levels + 1))
            + "</defs>"
        )

    data = doc(defs(5) + '<use href="#l5"/>')
    assert len(data) < 1500
    refused(data, r"<use> elements would copy more than 20000 elements \(limit max_use_elements\)", tmp_path=tmp_path)
    # the same fan-out, smaller, within the limit: every copy is drawn
    small = doc(defs(3) + '<use href="#l3"/>')
    assert len(read_svg(small)) == 1000


def test_element_count_limit(tmp_path):
    refused(doc(LINE * 50), r"more than 40 elements \(limit max_elements\)", SvgLimits(max_elements=40), tmp_path)


def test_byte_limit(tmp_path):
    refused(doc(LINE * 50), r"larger than 1000 bytes \(limit max_bytes\)", SvgLimits(max_bytes=1000), tmp_path)


def test_long_number_is_refused_instead_of_backtracking(tmp_path):
    # svgelements' coordinate-pair regex is cubic in a number's length: 2000 digits took ~60 s
    err = refused(
        doc(f'<polyline id="p" stroke="black" points="0,0 {"1" * 2000}"/>'),
        r"<polyline id='p'>: attribute 'points' has a number longer than 64 characters",
        tmp_path=tmp_path,
    )
    assert err.line == 1
    refused(doc(f'<path stroke="black" d="M0 0 L 1.{"0" * 100} 1"/>'), "'d' has a number longer", tmp_path=tmp_path)
    # numbers as long as real files write them are fine, and ".5.5" runs are several numbers
    dl = read_svg(
        doc(
            '<path stroke="black" d="M0.123456789012345678 0 L.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5'
            '.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5.5"/>'
        )
    )
    assert len(dl.points) == 21


@pytest.mark.parametrize("points", ["1 2 3", "1,2 x", "1 2,, 3 4", "1.5.5"])
def test_points_that_are_not_pairs_are_refused(tmp_path, points):
    refused(
        doc(f'<polyline stroke="black" points="{points}"/>'),
        "'points' is not a list of coordinate pairs",
        tmp_path=tmp_path,
    )


def test_valid_points_syntax_variants_import():
    dl = read_svg(doc('<polyline stroke="black" points=" 0,0 1-1 2 , 2\n3e0 .5 "/>'))
    np.testing.assert_allclose(dl.points, [[0, 0], [1, -1], [2, 2], [3, 0.5]], rtol=1e-5)


def test_malformed_transform_and_css_are_refused(tmp_path):
    refused(doc(f'<g transform="rotate({"rotate(" * 50}"/>'), "'transform' is not a list", tmp_path=tmp_path)
    refused(doc('<g style="transform:rotate(rotate(1)"/>'), "'transform' is not a list", tmp_path=tmp_path)
    refused(doc("<style>/* never closed .a{stroke:red}</style>"), "unclosed /\\* comment", tmp_path=tmp_path)
    refused(doc("<style>" + "a" * 20000 + "</style>"), "not a list of 'selector", tmp_path=tmp_path)


def test_css_classes_still_apply():
    dl = read_svg(
        doc(
            "<style>/* pens */ .st0 { stroke: #ff0000; fill: none }</style>"
            '<line class="st0" x1="0" y1="0" x2="5" y2="0"/>'
        )
    )
    assert dl.pen_colours == {1: "#ff0000"}


def test_inherited_bad_path_data_does_not_break_shapes():
    # svgelements copies a group's "d" onto its children when converting a rect to a path
    dl = read_svg(doc('<g d="M 0 0 Q"><rect width="10" height="5" stroke="black"/></g>'))
    np.testing.assert_allclose(dl.stroke(0), [[0, 0], [10, 0], [10, 5], [0, 5], [0, 0]], rtol=1e-5, atol=1e-9)


def test_points_limit_is_per_file(tmp_path):
    # each circle stays under the per-segment cap, but together they pass the per-file point limit
    circles = '<circle cx="50" cy="50" r="40" stroke="black" fill="none"/>' * 40
    with pytest.raises(ParseError, match=r"more than 20000 points in the file after flattening \(limit max_points\)"):
        read_svg(doc(circles), tolerance=1e-4, limits=SvgLimits(max_points=20_000))


def test_strokes_limit(tmp_path):
    with pytest.raises(ParseError, match=r"<line> \(drawable element 11\): more than 10 strokes"):
        read_svg(doc(LINE * 11), limits=SvgLimits(max_strokes=10))


def test_non_finite_transform_is_refused():
    with pytest.raises(ParseError, match="<line id='x'> has a non-finite"):
        read_svg(
            doc(
                '<g transform="matrix(1e308 0 0 1e308 0 0) scale(1e10)">'
                '<line id="x" x1="0" y1="0" x2="1" y2="0" stroke="black"/></g>'
            )
        )


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "10"])
def test_bad_limits_are_config_errors(bad):
    with pytest.raises(ConfigError, match="max_points"):
        SvgLimits(max_points=bad)
    with pytest.raises(ConfigError, match="SvgLimits"):
        read_svg(doc(""), limits={"max_points": 5})  # type: ignore[arg-type]

"""Tests of building display lists from device-space shapes: strokes, fills by style, pens, layers, images."""

import logging
import math
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np
import pytest

from pixelpen.display.picture import Fill, Style
from pixelpen.display.vectorize import PenLayerMap, build_display_list, device_angle, nearest_pen
from pixelpen.errors import ConfigError


@dataclass
class Shape:
    """A stand-in with the DeviceShape contract: kind, paths (device units), closed, style."""

    kind: str
    paths: list
    closed: bool = False
    style: Style = field(default_factory=Style)


SQUARE = np.array([[0, 0], [50, 0], [50, 50], [0, 50]], float)


def hatch_ys(dl):
    """The distinct y of horizontal pieces in the display list."""
    ys = set()
    for s in dl.strokes():
        for a, b in pairwise(s):
            if abs(a[1] - b[1]) < 1e-9 and a[0] != b[0]:
                ys.add(round(float(a[1]), 9))
    return sorted(ys)


def test_strokes_are_drawn_as_given_and_closed_ones_closed():
    open_path = np.array([[0, 0], [10, 0], [10, 10]], float)
    dl = build_display_list([Shape("stroke", [open_path]), Shape("stroke", [SQUARE], closed=True)], unit_mm=0.1)
    assert len(dl) == 2 and dl.unit_mm == 0.1
    np.testing.assert_array_equal(dl.stroke(0), open_path)
    np.testing.assert_array_equal(dl.stroke(1), np.vstack([SQUARE, SQUARE[:1]]))


def test_solid_fill_hatches_at_the_pen_width():
    # unit 0.1 mm, pen 0.5 mm -> spacing 5 units; 50 units tall -> 10 lines at 2.5, 7.5, ..., 47.5
    dl = build_display_list([Shape("area", [SQUARE], True, Style(fill=Fill("solid")))], unit_mm=0.1, pen_width_mm=0.5)
    np.testing.assert_allclose(hatch_ys(dl), 2.5 + 5 * np.arange(10))
    assert len(dl) == 1  # one zig-zag for a square


def test_hatch_fill_uses_spacing_in_mm_and_angle():
    style = Style(fill=Fill("hatch", angle=math.pi / 2, spacing=2.0))
    dl = build_display_list([Shape("area", [SQUARE], True, style)], unit_mm=0.1, join=False)
    xs = sorted({float(s[0, 0]) for s in dl.strokes()})
    # vertical lines 20 units apart, centred across the 50-unit width
    np.testing.assert_allclose(xs, [5, 25, 45])
    for s in dl.strokes():
        assert s[0, 0] == pytest.approx(s[1, 0], abs=1e-9)


def test_hatch_default_spacing_is_the_pen_width():
    dl = build_display_list([Shape("area", [SQUARE], True, Style(fill=Fill("hatch")))], unit_mm=1.0, pen_width_mm=10)
    np.testing.assert_allclose(hatch_ys(dl), [5, 15, 25, 35, 45])


def test_crosshatch_draws_both_directions():
    style = Style(fill=Fill("crosshatch", spacing=10.0))
    dl = build_display_list([Shape("area", [SQUARE], True, style)], unit_mm=1.0, join=False)
    horizontal = sum(1 for s in dl.strokes() if abs(s[0, 1] - s[1, 1]) < 1e-9)
    vertical = sum(1 for s in dl.strokes() if abs(s[0, 0] - s[1, 0]) < 1e-9)
    assert horizontal == 5 and vertical == 5


def test_pattern_fill_is_hatched_and_hollow_or_missing_fill_draws_nothing():
    pattern = Style(fill=Fill("pattern", pattern=((1, 0), (0, 1))))
    dl = build_display_list([Shape("area", [SQUARE], True, pattern)], unit_mm=1.0, pen_width_mm=10)
    assert len(hatch_ys(dl)) == 5
    empty = build_display_list(
        [Shape("area", [SQUARE], True, Style(fill=Fill("hollow"))), Shape("area", [SQUARE], True, Style())],
        unit_mm=1.0,
    )
    assert len(empty) == 0


def test_area_with_hole_is_hatched_even_odd():
    hole = np.array([[20, 20], [30, 20], [30, 30], [20, 30]], float)
    dl = build_display_list([Shape("area", [SQUARE, hole], True, Style(fill=Fill("solid")))], unit_mm=1.0,
                            pen_width_mm=1.0, join=False)
    for s in dl.strokes():
        mid = s.mean(axis=0)
        assert not (20 < mid[0] < 30 and 20 < mid[1] < 30)


def test_hatch_angle_follows_the_world_to_device_matrix():
    flip_y = np.diag([1.0, -1.0, 1.0])  # a y-down device: world 45 deg is device -45 deg
    assert device_angle(math.pi / 4, flip_y) == pytest.approx(-math.pi / 4)
    assert device_angle(0.3, None) == 0.3
    shape = Shape("area", [SQUARE], True, Style(fill=Fill("hatch", angle=math.pi / 4, spacing=5.0)))
    shape.matrix = flip_y
    dl = build_display_list([shape], unit_mm=1.0, join=False)
    for s in dl.strokes():
        d = s[1] - s[0]
        assert d[0] * d[1] < 0  # slope -1


def test_images_are_skipped_with_one_warning(caplog):
    with caplog.at_level(logging.WARNING, logger="pixelpen.display.vectorize"):
        dl = build_display_list([Shape("image", []), Shape("image", []), Shape("stroke", [SQUARE])], unit_mm=1.0)
    assert len(dl) == 1
    assert len([r for r in caplog.records if "image" in r.message]) == 1 and "2 image" in caplog.text


def test_pen_from_style_nearest_colour_or_per_colour():
    pens = ["#000000", "#ff0000", "#0000ff"]
    shapes = [
        Shape("stroke", [SQUARE], style=Style(colour=(200, 30, 30))),  # nearest red
        Shape("stroke", [SQUARE], style=Style(colour=(10, 10, 90))),  # nearest black (distance 90 vs 165)
        Shape("stroke", [SQUARE], style=Style(colour="red", pen=3)),  # explicit pen wins
    ]
    dl = build_display_list(shapes, unit_mm=1.0, pens=pens)
    assert dl.pens.tolist() == [2, 1, 3]
    assert dl.pen_colours == {1: "#000000", 2: "#ff0000", 3: "#0000ff"}
    auto = build_display_list(shapes, unit_mm=1.0)
    assert auto.pens.tolist() == [1, 2, 3]
    assert auto.pen_colours == {1: "#c81e1e", 2: "#0a0a5a", 3: "#ff0000"}
    assert nearest_pen((250, 250, 250), ["#000000", "#ffffff"]) == 2


def test_layers_from_style_names():
    shapes = [
        Shape("stroke", [SQUARE], style=Style(layer="ink")),
        Shape("stroke", [SQUARE]),
        Shape("stroke", [SQUARE], style=Style(layer="ink")),
        Shape("stroke", [SQUARE], style=Style(layer="fill")),
    ]
    dl = build_display_list(shapes, unit_mm=1.0)
    assert dl.layers.tolist() == [1, 2, 1, 3]
    assert dl.layer_names == {1: "ink", 2: "default", 3: "fill"}


def test_real_device_shapes_from_flatten():
    flatten = pytest.importorskip("pixelpen.display.flatten")
    shapes = [flatten.DeviceShape("area", [SQUARE], True, Style(fill=Fill("solid"))),
              flatten.DeviceShape("stroke", [SQUARE], False, Style())]
    dl = build_display_list(shapes, unit_mm=1.0, pen_width_mm=10)
    assert len(dl) == 2 and len(hatch_ys(dl.select([True, False]))) == 5


def test_bad_input():
    with pytest.raises(ConfigError, match="kind"):
        build_display_list([Shape("text", [SQUARE])], unit_mm=1.0)
    with pytest.raises(ConfigError, match="unit"):
        build_display_list([], unit_mm=0)
    with pytest.raises(ConfigError, match="pen width"):
        build_display_list([], unit_mm=1.0, pen_width_mm=-1)
    with pytest.raises(ConfigError, match="non-finite"):
        build_display_list([Shape("stroke", [np.array([[0, 0], [np.inf, 1]])])], unit_mm=1.0)
    with pytest.raises(ConfigError, match="pen 4"):
        build_display_list([Shape("stroke", [SQUARE], style=Style(pen=4))], unit_mm=1.0, pens=["#000000"])
    with pytest.raises(ConfigError, match="colour"):
        build_display_list([], unit_mm=1.0, pens=["#12345"])
    assert len(build_display_list([], unit_mm=1.0)) == 0


def test_a_shared_mapping_keeps_pens_and_layers_consistent_across_builds():
    line = np.array([[0.0, 0.0], [1.0, 0.0]])
    red, blue = Style(colour="red", layer="a"), Style(colour="blue", layer="b")
    mapping = PenLayerMap()
    first = build_display_list([Shape("stroke", [line], False, red)], unit_mm=1.0, mapping=mapping)
    second = build_display_list(
        [Shape("stroke", [line], False, blue), Shape("stroke", [line], False, red)], unit_mm=1.0, mapping=mapping
    )
    assert first.pens.tolist() == [1] and second.pens.tolist() == [2, 1]
    assert second.pen_colours == {1: "#ff0000", 2: "#0000ff"}
    assert first.layer_names == {1: "a"} and second.layer_names == {1: "a", 2: "b"}
    # without a shared mapping each build numbers from 1
    alone = build_display_list([Shape("stroke", [line], False, blue)], unit_mm=1.0)
    assert alone.pens.tolist() == [1]

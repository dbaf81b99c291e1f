"""Tests of Picture -> device shapes: tolerance, markers in mm, clipping, dashes, segments, fills."""

import numpy as np
import pytest

from pixelpen.display.flatten import flatten_picture
from pixelpen.display.picture import (
    Arc,
    Bezier,
    Circle,
    Ellipse,
    Fill,
    Marker,
    Picture,
    Polygon,
    Polyline,
    Rectangle,
    Segment,
    Style,
    Text,
)
from pixelpen.geometry import ViewingPipeline, rotate


def pipeline(window=(0, 0, 100, 100), size=(1000, 1000), y_down=True):
    return ViewingPipeline(window, (0, 0, 1, 1), device_size=size, y_down=y_down)


def shapes(prim_or_pic, pl=None, tolerance=0.5, unit_mm=0.1):
    pic = prim_or_pic
    if not isinstance(pic, Picture):
        pic = Picture()
        pic.add(prim_or_pic)
    return list(flatten_picture(pic, pl or pipeline(), tolerance=tolerance, unit_mm=unit_mm))


def test_circle_is_flattened_within_tolerance_in_device_units():
    (s,) = shapes(Circle((50, 50), 30), tolerance=0.25)
    ring = s.paths[0]
    assert np.allclose(ring[0], ring[-1])  # outline closed
    # vertices on the circle (radius 300 device units) and chords' midpoints within tolerance
    r_vert = np.hypot(ring[:, 0] - 500, ring[:, 1] - 500)
    mids = (ring[:-1] + ring[1:]) / 2
    r_mid = np.hypot(mids[:, 0] - 500, mids[:, 1] - 500)
    assert np.allclose(r_vert, 300, atol=1e-6) and (300 - r_mid).max() <= 0.25 + 1e-9


def test_y_down_devices_flip_world_y():
    (s,) = shapes(Polyline([[0, 0], [0, 100]]))
    np.testing.assert_allclose(s.paths[0], [[0, 1000], [0, 0]], atol=1e-9)


def test_markers_keep_their_millimetre_size_whatever_the_window():
    for window in [(0, 0, 100, 100), (0, 0, 10, 10)]:
        (s,) = shapes(Marker([[5, 5]], kind="plus", size=2.0), pipeline(window), unit_mm=0.1)
        horiz = s.paths[0]
        assert np.ptp(horiz[:, 0]) == pytest.approx(20.0)  # 2 mm at 0.1 mm per unit


def test_strokes_are_clipped_to_the_viewport():
    (s,) = shapes(Polyline([[-50, 50], [150, 50]]))
    np.testing.assert_allclose(s.paths[0], [[0, 500], [1000, 500]], atol=1e-9)
    assert shapes(Polyline([[200, 200], [300, 300]])) == []


def test_dashes_are_in_millimetres_on_the_device():
    (s,) = shapes(Polyline([[0, 50], [100, 50]], Style(dash=(10.0, 10.0))), unit_mm=0.1)
    # 1000 device units = 100 mm of line; 10 mm on, 10 mm off -> 5 pieces of 100 units
    lengths = [np.hypot(*np.diff(p, axis=0).T).sum() for p in s.paths]
    assert len(lengths) == 5 and np.allclose(lengths, 100)


def test_filled_areas_give_area_then_outline_and_outline_can_be_off():
    sq = Rectangle(10, 10, 20, 20, Style(fill=Fill("solid")))
    kinds = [s.kind for s in shapes(sq)]
    assert kinds == ["area", "stroke"]
    bare = Rectangle(10, 10, 20, 20, Style(fill=Fill("solid", outline=False)))
    assert [s.kind for s in shapes(bare)] == ["area"]
    hollow = Rectangle(10, 10, 20, 20, Style(fill=Fill("hollow")))
    assert [s.kind for s in shapes(hollow)] == ["stroke"]


def test_area_rings_are_clipped_polygons():
    (area, _) = shapes(Polygon([[-10, -10], [50, -10], [50, 50], [-10, 50]], Style(fill=Fill("solid"))))
    ring = area.paths[0]
    assert ring[:, 0].min() >= 0 and ring[:, 1].max() <= 1000 + 1e-9


def test_segment_transform_and_visibility():
    pic = Picture()
    seg = Segment("s", transform=rotate(np.pi / 2, about=(50, 50)))
    seg.add(Polyline([[50, 50], [60, 50]]))
    pic.add(seg)
    hidden = Segment("h", visible=False)
    hidden.add(Polyline([[0, 0], [1, 1]]))
    pic.add(hidden)
    (s,) = shapes(pic)
    np.testing.assert_allclose(s.paths[0], [[500, 500], [500, 400]], atol=1e-9)  # +y world is -y device


def test_curves_arcs_and_text_become_strokes():
    assert [s.kind for s in shapes(Bezier([[0, 0], [50, 100], [100, 0]]))] == ["stroke"]
    (pie,) = shapes(Arc((50, 50), 10, 10, 0, np.pi / 2, close="pie"))
    assert np.allclose(pie.paths[0][-2], [500, 500])  # pie goes back through the centre
    (ell,) = shapes(Ellipse((50, 50), 20, 10, angle=np.pi / 2))
    assert np.ptp(ell.paths[0][:, 1]) == pytest.approx(400, abs=1) and np.ptp(ell.paths[0][:, 0]) == pytest.approx(
        200, abs=1
    )
    (txt,) = shapes(Text((10, 10), "Hi", height=5))
    assert len(txt.paths) >= 3


def test_zero_radius_curves_are_exact_degenerate_shapes():
    dot = shapes(Circle((50, 50), 0))
    assert [s.kind for s in dot] == ["stroke"]
    np.testing.assert_allclose(np.vstack(dot[0].paths), [[500, 500]] * len(np.vstack(dot[0].paths)))
    # a flat ellipse is the segment between its extremes, rotated by its angle: (50 +- 20 cos a, 50 +- 20 sin a)
    line = np.vstack(shapes(Ellipse((50, 50), 20, 0, angle=np.pi / 6))[0].paths)
    world = line / 10 * [1, -1] + [0, 100]  # device -> world for this y-down pipeline
    ends = (
        [50 + 20 * np.cos(np.pi / 6), 50 + 20 * np.sin(np.pi / 6)],
        [50 - 20 * np.cos(np.pi / 6), 50 - 20 * np.sin(np.pi / 6)],
    )
    np.testing.assert_allclose(sorted(map(tuple, world))[:: len(world) - 1], sorted(map(tuple, ends)), atol=1e-9)
    quarter = np.vstack(shapes(Arc((0, 0), 0, 10, 0.0, np.pi / 2), pipeline((-50, -50, 50, 50)))[0].paths)
    assert len(quarter) == 2  # from u = 0 (the centre) to u = pi/2 (10 up): one straight piece


def test_an_undrawable_item_is_named():
    from pixelpen.errors import InvalidArgument

    pic = Picture()
    pic.add(Polyline([[0, 0], [10, 10]]))
    pic.add(Polyline([[0, 0], [100, 0]], Style(dash=(1e-300, 1e-300))))
    with pytest.raises(InvalidArgument, match=r"visible item 1 \(Polyline\).*too fine"):
        shapes(pic)
    seg = Segment("big", transform=np.diag([1e10, 1e10, 1.0]))
    seg.add(Circle((0, 0), 1e5))
    pic = Picture()
    pic.add(seg)
    with pytest.raises(InvalidArgument, match=r"segment 'big', visible item 0 \(Circle\)"):
        shapes(pic)

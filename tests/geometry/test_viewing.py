"""Tests for pixelpen.geometry.viewing: window-to-viewport worked examples and the viewing pipeline."""

import math
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import InvalidArgument
from pixelpen.geometry.viewing import ViewingPipeline, as_rect, window_to_viewport


def test_window_to_viewport_worked_example():
    # sx = (0.5 - 0.1) / (110 - 10) = 0.004, sy = (0.6 - 0.2) / (70 - 20) = 0.008
    # (60, 45): xv = 0.1 + 50 * 0.004 = 0.3, yv = 0.2 + 25 * 0.008 = 0.4
    m = window_to_viewport((10, 20, 110, 70), (0.1, 0.2, 0.5, 0.6))
    np.testing.assert_allclose(m, [[0.004, 0, 0.1 - 10 * 0.004], [0, 0.008, 0.2 - 20 * 0.008], [0, 0, 1]])
    np.testing.assert_allclose(m @ [60, 45, 1], [0.3, 0.4, 1])
    np.testing.assert_allclose(m @ [10, 20, 1], [0.1, 0.2, 1])
    np.testing.assert_allclose(m @ [110, 70, 1], [0.5, 0.6, 1])


def test_window_to_viewport_device_example():
    # window 0..4 x 0..3 onto pixels 100..500 x 50..350: sx = sy = 100; (1, 2) -> (200, 250)
    m = window_to_viewport((0, 0, 4, 3), (100, 50, 500, 350))
    np.testing.assert_allclose(m @ [1, 2, 1], [200, 250, 1])


@pytest.mark.parametrize(
    "window, message",
    [((0, 0, 0, 1), "xmin must be < xmax"), ((0, 5, 1, 5), "ymin must be < ymax"), ((2, 0, 1, 1), "xmin"),
     ((0, 0, 1), "rectangle"), ((0, 0, float("nan"), 1), "finite"), ("abcd", "rectangle")],
)
def test_degenerate_and_malformed_rectangles_are_rejected(window, message):
    with pytest.raises(ValueError, match=message):
        window_to_viewport(window, (0, 0, 1, 1))
    with pytest.raises(ValueError, match=message):
        as_rect(window)


def test_pipeline_maps_window_onto_the_whole_device():
    p = ViewingPipeline((0, 0, 4, 3), device_size=(800, 600))
    np.testing.assert_allclose(p.to_device([(0, 0), (4, 3), (2, 1.5)]), [(0, 0), (800, 600), (400, 300)])
    assert p.scale == pytest.approx(200)
    np.testing.assert_allclose(p.clip_rect, (0, 0, 800, 600))


def test_y_down_flips_device_y():
    p = ViewingPipeline((0, 0, 4, 3), device_size=(800, 600), y_down=True)
    np.testing.assert_allclose(p.to_device([(0, 0), (4, 3), (1, 1)]), [(0, 600), (800, 0), (200, 400)])
    np.testing.assert_allclose(p.clip_rect, (0, 0, 800, 600))


def test_preserve_aspect_centres_the_window():
    # window 2 x 1 on 800 x 600: uniform scale min(400, 600) = 400, image 800 x 400 centred: y 100..500
    p = ViewingPipeline((0, 0, 2, 1), device_size=(800, 600))
    np.testing.assert_allclose(p.to_device([(0, 0), (2, 1)]), [(0, 100), (800, 500)])
    np.testing.assert_allclose(p.clip_rect, (0, 100, 800, 500))
    assert p.scale == pytest.approx(400)


def test_preserve_aspect_lower_left_alignment():
    p = ViewingPipeline((0, 0, 2, 1), device_size=(800, 600), align="lower-left")
    np.testing.assert_allclose(p.to_device([(0, 0), (2, 1)]), [(0, 0), (800, 400)])


def test_without_preserve_aspect_the_window_fills_the_viewport():
    p = ViewingPipeline((0, 0, 2, 1), device_size=(800, 600), preserve_aspect=False)
    np.testing.assert_allclose(p.to_device([(0, 0), (2, 1)]), [(0, 0), (800, 600)])
    assert p.scale == pytest.approx(math.sqrt(400 * 600))


def test_sub_viewport_with_aspect_and_y_down():
    # viewport (0.5, 0.5)-(1, 1) of 200 x 100 is device x 100..200, y 50..100 (100 x 50); a unit window
    # gets scale min(100, 50) = 50, centred in x: 125..175; flipped: y 0..50.
    p = ViewingPipeline((0, 0, 1, 1), (0.5, 0.5, 1, 1), device_size=(200, 100), y_down=True)
    np.testing.assert_allclose(p.clip_rect, (125, 0, 175, 50))
    np.testing.assert_allclose(p.to_device((0, 0)), (125, 50))
    np.testing.assert_allclose(p.to_device((1, 1)), (175, 0))
    np.testing.assert_allclose(p.world_to_normalized @ [1, 1, 1], [0.875, 1, 1])
    np.testing.assert_allclose(p.normalized_to_device @ [0.875, 1, 1], [175, 0, 1])


def test_rotated_window_about_its_centre():
    # viewing x axis along world +y: world (0, 1) lies on the window's "right" edge middle
    p = ViewingPipeline((-1, -1, 1, 1), device_size=(200, 200), window_angle=math.pi / 2)
    np.testing.assert_allclose(p.to_device([(0, 1), (0, 0), (-1, 0)]), [(200, 100), (100, 100), (100, 200)], atol=1e-12)
    np.testing.assert_allclose(p.window_corners, [(1, -1), (1, 1), (-1, 1), (-1, -1)], atol=1e-12)


def test_rotated_window_about_a_given_origin():
    # viewing = R(-90 deg) world: (x, y) -> (y, -x); window (0, 0, 2, 2) in those coordinates.
    p = ViewingPipeline((0, 0, 2, 2), device_size=(100, 100), window_angle=math.pi / 2, window_origin=(0, 0))
    np.testing.assert_allclose(p.to_device([(-1, 1), (-2, 0), (0, 0)]), [(50, 50), (0, 100), (0, 0)], atol=1e-12)


pipelines = st.builds(
    ViewingPipeline,
    st.tuples(st.floats(-100, 100), st.floats(-100, 100), st.floats(0.5, 50), st.floats(0.5, 50)).map(
        lambda r: (r[0], r[1], r[0] + r[2], r[1] + r[3])
    ),
    st.tuples(st.floats(0, 0.4), st.floats(0, 0.4), st.floats(0.6, 1), st.floats(0.6, 1)),
    device_size=st.tuples(st.integers(16, 4000), st.integers(16, 4000)),
    y_down=st.booleans(),
    window_angle=st.floats(-math.pi, math.pi),
    preserve_aspect=st.booleans(),
    align=st.sampled_from(["center", "lower-left"]),
)


@settings(max_examples=60, deadline=None)
@given(p=pipelines, pts=st.lists(st.tuples(st.floats(-200, 200), st.floats(-200, 200)), min_size=1, max_size=10))
def test_pipeline_round_trips_world_device_world(p, pts):
    np.testing.assert_allclose(p.to_world(p.to_device(pts)), pts, atol=1e-8)
    np.testing.assert_allclose(p.inverse @ p.matrix, np.eye(3), atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(p=pipelines)
def test_window_corners_land_on_the_clip_rect(p):
    xmin, ymin, xmax, ymax = p.clip_rect
    assert xmin < xmax and ymin < ymax
    corners = p.to_device(p.window_corners)
    np.testing.assert_allclose(np.sort(corners[:, 0]), [xmin, xmin, xmax, xmax], atol=1e-8)
    np.testing.assert_allclose(np.sort(corners[:, 1]), [ymin, ymin, ymax, ymax], atol=1e-8)
    w, h = p.device_size
    assert xmin >= -1e-9 and xmax <= w + 1e-9 and ymin >= -1e-9 and ymax <= h + 1e-9
    if p.preserve_aspect:
        side = p.window[2] - p.window[0]
        assert (xmax - xmin) == pytest.approx(p.scale * side) or (ymax - ymin) == pytest.approx(p.scale * side)


def test_pickle_and_copies():
    p = ViewingPipeline((0, 0, 10, 5), (0.1, 0.1, 0.9, 0.9), device_size=(640, 480), y_down=True, window_angle=0.2)
    q = pickle.loads(pickle.dumps(p))
    assert q == p and hash(q) == hash(p)
    np.testing.assert_array_equal(q.matrix, p.matrix)
    r = p.with_window((0, 0, 20, 10))
    assert r.window == (0, 0, 20, 10) and r.y_down and r.window_angle == 0.2
    assert r.scale == pytest.approx(p.scale / 2)
    assert p.window == (0, 0, 10, 5)  # the original is unchanged
    s = p.with_viewport((0, 0, 1, 1))
    assert s.viewport == (0, 0, 1, 1) and s.window == p.window and s != p
    assert "ViewingPipeline(" in repr(p)
    with pytest.raises(ValueError, match="read-only"):
        p.matrix[0, 0] = 5
    with pytest.raises(AttributeError, match="immutable"):
        p.window = (0, 0, 1, 1)


def test_bad_pipeline_arguments():
    with pytest.raises(ValueError, match="viewport must lie inside"):
        ViewingPipeline((0, 0, 1, 1), (0, 0, 2, 1), device_size=(10, 10))
    with pytest.raises(ValueError, match="device_size must be positive"):
        ViewingPipeline((0, 0, 1, 1), device_size=(0, 10))
    with pytest.raises(ValueError, match="align"):
        ViewingPipeline((0, 0, 1, 1), device_size=(10, 10), align="top")
    with pytest.raises(ValueError, match="degenerate"):
        ViewingPipeline((0, 0, 1, 0), device_size=(10, 10))
    with pytest.raises(TypeError, match="unknown"):
        ViewingPipeline((0, 0, 1, 1), device_size=(10, 10)).replace(colour="red")
    with pytest.raises(TypeError):
        ViewingPipeline((0, 0, 1, 1))  # device_size is required


@pytest.mark.parametrize("rect, message", [
    ((0, 0, 0, 10), "degenerate"),
    ((0, 0, 10, float("inf")), "finite"),
    ((-1e308, 0, 1e308, 10), "overflows"),  # finite corners, but the width is inf: --fit on such an extent
])
def test_bad_windows_are_pixelpen_errors_and_value_errors(rect, message):
    with pytest.raises(InvalidArgument, match=message):
        as_rect(rect)
    with pytest.raises(ValueError, match=message):
        ViewingPipeline(rect, device_size=(100, 100))

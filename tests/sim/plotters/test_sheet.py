"""Shared plotter-simulator parts: end-stop clamping, the paper's strokes and rendering; simulators' option errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError, URLError
from pixelpen.sim.base import create_simulator
from pixelpen.sim.plotters.sheet import Sheet, blank_sheet, clamp_path, draw_segments

LO = np.array([0.0, 0.0])
HI = np.array([100.0, 50.0])


def test_clamp_path_inside_is_the_straight_move():
    path = clamp_path(np.array([10.0, 10.0]), np.array([20.0, 30.0]), LO, HI)
    assert np.allclose(path, [[10, 10], [20, 30]])


def test_clamp_path_rides_the_end_stop():
    # from (90, 10) to (110, 30): x reaches 100 halfway at (100, 20), then only y moves to 30
    path = clamp_path(np.array([90.0, 10.0]), np.array([110.0, 30.0]), LO, HI)
    assert np.allclose(path, [[90, 10], [100, 20], [100, 30]])


def test_clamp_path_starting_outside():
    path = clamp_path(np.array([-10.0, 10.0]), np.array([10.0, 10.0]), LO, HI)
    assert np.allclose(path, [[0, 10], [10, 10]])


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-200, 200, allow_nan=False), min_size=4, max_size=4))
def test_clamp_path_is_the_pointwise_clamp(v):
    p0, p1 = np.array(v[:2]), np.array(v[2:])
    path = clamp_path(p0, p1, LO, HI)
    assert np.all(path >= LO - 1e-9) and np.all(path <= HI + 1e-9)
    for f in np.linspace(0, 1, 11):  # every clamped point of the move lies on the polyline
        q = np.clip(p0 + f * (p1 - p0), LO, HI)
        seg_a, seg_b = path[:-1], path[1:]
        d = seg_b - seg_a
        denom = np.maximum((d * d).sum(1), 1e-30)
        t = np.clip(((q - seg_a) * d).sum(1) / denom, 0, 1)
        dist = np.hypot(*(seg_a + t[:, None] * d - q).T).min()
        assert dist < 1e-6


def test_paper_strokes_dots_and_length():
    paper = Sheet(100, 50, y_down=True)
    paper.pen_down([1, 2])
    paper.line_to([[1, 2], [4, 6]])
    paper.line_to([[4, 6], [4, 10]])
    paper.pen_up()
    paper.pen_down([50, 25])  # touched and lifted: a dot
    paper.pen_up()
    paper.line_to([[0, 0], [9, 9]])  # pen up: nothing recorded
    strokes = paper.strokes()
    assert [len(s) for _, s in strokes] == [3, 1]
    assert np.allclose(strokes[0][1], [[1, 2], [4, 6], [4, 10]])
    assert paper.ink_length() == pytest.approx(5 + 4)
    dl = paper.display_list()
    assert len(dl) == 2 and dl.unit_mm == 1.0


def test_paper_image_draws_ink_where_the_strokes_are():
    pytest.importorskip("pixelpen.raster.canvas")
    paper = Sheet(100, 50, y_down=False, pen_colours={1: "red"}, pen_width_mm=0.3)
    paper.pen_down([10, 10])
    paper.line_to([[10, 10], [90, 10]])
    paper.pen_up()
    img = np.asarray(paper.paper_image(dpi=25.4).array)  # 1 px per mm
    assert img.shape == (50, 100, 3)
    row = 50 - 1 - 10  # y up: 10 mm from the bottom
    assert tuple(img[row, 50]) == (255, 0, 0)
    assert tuple(img[5, 5]) == (255, 255, 255)


def test_blank_sheet_is_white_at_the_page_size_and_checks_the_dpi():
    canvas, scale = blank_sheet((25.4, 50.8), 10.0)
    assert (canvas.width, canvas.height) == (10, 20) and scale == pytest.approx(10 / 25.4)
    assert np.all(np.asarray(canvas.array) == 255)
    with pytest.raises(ConfigError, match="dpi"):
        blank_sheet((10.0, 10.0), 0)


def test_draw_segments_inks_each_pen_in_its_colour_and_a_pen_without_one_plots_dry():
    canvas, _ = blank_sheet((25.4, 25.4), 20.0)
    pixels = np.array([[2, 2, 17, 2], [2, 10, 17, 10], [2, 15, 17, 15]])
    draw_segments(canvas, pixels, np.array([1, 2, 3]), np.array([1, 3, 1]), {1: "red", 2: "blue"}, cap="round")
    img = np.asarray(canvas.array)
    assert tuple(img[2, 9]) == (255, 0, 0) and tuple(img[11, 9]) == (0, 0, 255) and tuple(img[15, 9]) == (255, 255, 255)


@pytest.mark.parametrize("model, bad", [("hp7475a", "buffer"), ("grbl", "rx_buffer"), ("axidraw", "contact")])
def test_simulator_options_name_the_bad_option_and_list_the_known(model, bad):
    # each simulator reads its URL options through pixelpen.options (sheet.read_options, which did it before, is gone)
    with pytest.raises(URLError, match=rf"^sim:{model}: unknown option\(s\) colourz; known: .*{bad}"):
        create_simulator(model, colourz="red")
    with pytest.raises(URLError, match=rf"^sim:{model}: option {bad}='big' is not valid"):
        create_simulator(model, **{bad: "big"})

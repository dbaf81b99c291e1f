"""Tests of the Display base class: life cycle, deferral, viewing, safe closing — with a recording device."""

import numpy as np
import pytest

from pixelpen.display.base import Display
from pixelpen.display.capabilities import Capabilities
from pixelpen.display.picture import Circle, Picture, Polyline, Segment
from pixelpen.errors import ConfigError, PixelpenError

CAPS = Capabilities(model="rec", category="output", kind="vector", size=(1000, 500), unit_mm=0.1,
                    colour_model="pens", y_down=False, tolerance=0.5)


class RecordingDisplay(Display):
    """A device that records what the base class asks of it."""

    def __init__(self, deferral="asap"):
        super().__init__(CAPS, deferral=deferral)
        self.calls, self.rendered = [], []

    @classmethod
    def from_url(cls, url, **kwargs):
        return cls()

    def _open_device(self):
        self.calls.append("open")

    def _close_device(self):
        self.calls.append("close")

    def _render(self, shapes):
        self.rendered.append(shapes)
        self.calls.append("render")

    def _present(self):
        self.calls.append("present")

    def _erase(self):
        self.calls.append("erase")


def test_default_window_is_device_size_in_mm_so_mm_come_out_true_size():
    with RecordingDisplay() as d:
        d.draw(Polyline([[0, 0], [100, 50]]))  # the device is 100 mm x 50 mm
    (shape,) = d.rendered[0]
    np.testing.assert_allclose(shape.paths[0], [[0, 0], [1000, 500]], atol=1e-9)


def test_window_and_viewport_map_like_the_textbook():
    d = RecordingDisplay().open()
    d.window(0, 0, 10, 10)
    d.viewport(0.5, 0.0, 1.0, 1.0, preserve_aspect=False)
    d.draw(Polyline([[0, 0], [10, 10], [5, 5]]))
    # x: [0,10] -> [500, 1000]; y: [0,10] -> [0, 500]
    np.testing.assert_allclose(d.rendered[0][0].paths[0], [[500, 0], [1000, 500], [750, 250]], atol=1e-9)
    with pytest.raises(ConfigError):
        d.viewport(0, 0, 1.5, 1)


def test_deferral_flush_waits_for_flush():
    d = RecordingDisplay(deferral="flush").open()
    d.draw(Circle((50, 25), 10))
    d.draw(Circle((50, 25), 5))
    assert "render" not in d.calls
    d.flush()
    assert d.calls == ["open", "render", "render", "present"]


def test_close_flushes_and_is_idempotent():
    d = RecordingDisplay(deferral="flush").open()
    d.draw(Circle((50, 25), 10))
    d.close()
    d.close()
    assert d.calls == ["open", "render", "present", "close"]
    with pytest.raises(PixelpenError, match="not open"):
        d.draw(Circle((1, 1), 1))


def test_error_inside_with_leaves_device_safe_without_drawing_pending():
    d = RecordingDisplay(deferral="flush")
    with pytest.raises(RuntimeError):
        with d:
            d.draw(Circle((50, 25), 10))
            raise RuntimeError("boom")
    assert d.calls == ["open", "close"] and not d.is_open


def test_draw_accepts_segments_and_lists_and_clear_erases():
    d = RecordingDisplay().open()
    seg = Segment("s")
    seg.add(Polyline([[0, 0], [1, 1]]))
    d.draw(seg)
    d.draw([Polyline([[0, 0], [1, 1]]), Polyline([[2, 2], [3, 3]])])
    assert [len(r) for r in d.rendered] == [1, 2]
    d.clear()
    assert d.calls[-1] == "erase"
    with pytest.raises(ConfigError):
        RecordingDisplay(deferral="later")


def test_pipeline_inverse_round_trips_for_input_devices():
    d = RecordingDisplay().open()
    d.window(-5, -5, 5, 5, angle=0.3)
    pts = np.array([[1.0, 2.0], [-3.0, 4.0]])
    np.testing.assert_allclose(d.pipeline.to_world(d.pipeline.to_device(pts)), pts, atol=1e-9)
    assert isinstance(Picture(), Picture)


def test_deferred_items_keep_the_pipeline_they_were_drawn_under():
    d = RecordingDisplay(deferral="flush").open()
    d.window(0, 0, 10, 10)
    d.viewport(0, 0, 0.5, 0.5, preserve_aspect=False)
    d.draw(Polyline([[0, 0], [10, 10]]))
    d.window(0, 0, 100, 50)
    d.viewport(0, 0, 1, 1)
    d.flush()
    np.testing.assert_allclose(d.rendered[0][0].paths[0], [[0, 0], [500, 250]], atol=1e-9)


@pytest.mark.parametrize("window", [(0, 0, 0, 10), (0, 0, 10, float("nan")), (-1e308, 0, 1e308, 1)])
def test_a_bad_window_is_refused_at_once_as_pixelpen_and_value_error(window):
    d = RecordingDisplay()
    with pytest.raises(ValueError, match="window") as info:
        d.window(*window)
    assert isinstance(info.value, PixelpenError)
    assert d.pipeline.window == (0.0, 0.0, 100.0, 50.0)  # the old window stays in force
    with pytest.raises(ValueError, match="angle"):
        d.window(0, 0, 1, 1, angle=float("inf"))
    assert d.pipeline.window == (0.0, 0.0, 100.0, 50.0)

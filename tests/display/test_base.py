"""Tests of the Display base class: life cycle, deferral, viewing, safe closing — with a recording device."""

import numpy as np
import pytest

from pixelpen.display.base import Display
from pixelpen.display.capabilities import Capabilities
from pixelpen.display.picture import Circle, Picture, Polyline, Segment
from pixelpen.errors import ConfigError, InvalidArgumentType, PixelpenError, URLError
from pixelpen.options import OptionSpec, integer, text
from pixelpen.urls import DeviceURL, parse_url

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
    with pytest.raises(RuntimeError), d:
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


class OptionedDisplay(RecordingDisplay):
    """A display declaring URL options as specs, some shared with or passed to its simulator."""

    OPTIONS = (OptionSpec("paper", text, "a4", "paper size"), OptionSpec("pens", integer(1, 8), 1, "pens"),
               OptionSpec("baud", integer(1), 9600, "line speed"))
    SIM_SHARED = frozenset({"paper"})
    SIM_TRANSPORT = frozenset({"baud", "flow"})


def test_read_url_options_reads_the_specs_and_refuses_unknown_names_listing_the_known():
    values = OptionedDisplay.read_url_options(parse_url("rec:/dev/x?pens=3"))
    assert dict(values) == {"paper": "a4", "pens": 3, "baud": 9600} and values.given == {"pens"}
    with pytest.raises(URLError, match=r"unknown option\(s\) pen; known: baud, paper, pens"):
        OptionedDisplay.read_url_options(parse_url("rec:/dev/x?pen=3"))
    with pytest.raises(URLError, match=r"option pens='9' is not valid"):
        OptionedDisplay.read_url_options(parse_url("rec:/dev/x?pens=9"))
    with pytest.raises(URLError, match="inside brackets"):
        OptionedDisplay.read_url_options(parse_url("rec:rfc2217://host:4000?logging=debug"))


def test_split_sim_url_keeps_declared_options_and_hands_the_rest_to_the_simulator():
    own, sim = OptionedDisplay.split_sim_url(parse_url("sim:rec?paper=a3&pens=2&baud=300&speed=fast"))
    assert (own.scheme, own.target, dict(own.options)) == ("rec", "", {"paper": "a3", "pens": "2"})
    assert str(own) == "sim:rec?paper=a3&pens=2&baud=300&speed=fast"  # errors name the URL as given
    assert sim == {"paper": "a3", "baud": "300", "speed": "fast"}
    assert RecordingDisplay.split_sim_url(parse_url("sim:rec?speed=fast")) == (
        DeviceURL("rec", "", {}, "sim:rec?speed=fast"), {"speed": "fast"})


@pytest.mark.parametrize("item", [5, None, object()])
def test_drawing_what_is_not_a_picture_or_primitives_is_a_type_error_naming_it(item):
    with RecordingDisplay() as d, pytest.raises(InvalidArgumentType, match="draw takes a Picture"):
        d.draw(item)
    assert d.rendered == []

"""Tests of the reference scene on raster displays: a mono one gets every stroke lit, a colour one the scene."""

import numpy as np

from pixelpen.display.capabilities import Capabilities
from pixelpen.display.kinds import RasterDisplay
from pixelpen.scene import draw_reference, lit_reference, show_reference


class Recorder(RasterDisplay):
    """A raster display counting the frames it was sent."""

    def __init__(self, width: int, height: int, mode: str) -> None:
        caps = Capabilities(model="recorder", category="panel", kind="raster", size=(width, height), unit_mm=0.2,
                            colour_model="mono" if mode == "1" else "rgb565", y_down=True)
        super().__init__(caps, mode=mode, background="black")
        self.shown = 0
        self.open()

    @classmethod
    def from_url(cls, url, **kwargs):
        raise NotImplementedError

    def _open_device(self) -> None:
        pass

    def _close_device(self) -> None:
        pass

    def _show(self, canvas) -> None:
        self.shown += 1


def test_a_mono_raster_lights_every_stroke_of_the_colour_scene():
    mono = Recorder(128, 64, "1")
    show_reference(mono)
    lit = mono.canvas.array.astype(bool)
    assert mono.shown == 1 and lit.shape == (64, 128)
    # the colour scene on a black RGB raster of the same size: its non-black pixels are the lit ones (the strokes'
    # widths may round differently at the file display's pitch: a few edge pixels)
    colour = Recorder(128, 64, "RGB")
    draw_reference(colour)
    strokes = colour.canvas.array.max(axis=2) >= 96
    assert (lit == strokes).mean() > 0.95 and (lit & strokes).sum() > 0.9 * strokes.sum()
    np.testing.assert_array_equal(lit_reference(mono), lit.astype(np.uint8))
    # drawn on the mono canvas directly, its darker colours (red, blue, green) fall below the threshold
    direct = Recorder(128, 64, "1")
    draw_reference(direct)
    assert lit.sum() > 2 * direct.canvas.array.sum() and 0.1 < lit.mean() < 0.6


def test_a_colour_raster_gets_the_scene_itself_and_it_is_sent():
    shown, drawn = Recorder(96, 64, "RGB"), Recorder(96, 64, "RGB")
    show_reference(shown)
    draw_reference(drawn)
    np.testing.assert_array_equal(shown.canvas.array, drawn.canvas.array)
    assert shown.shown >= 1 and not shown.canvas.damage()  # nothing left unsent

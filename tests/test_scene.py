"""Tests of the reference scene on raster displays: a mono one gets every stroke lit, a colour one the scene."""

import numpy as np

from pixelpen.scene import draw_reference, lit_reference, show_reference
from tests.commands.test_sim import RecordingPanel


def test_a_mono_raster_lights_every_stroke_of_the_colour_scene():
    mono = RecordingPanel(128, 64, "1")
    show_reference(mono)
    lit = mono.canvas.array.astype(bool)
    assert len(mono.frames) == 1 and lit.shape == (64, 128)
    # the colour scene on a black RGB raster of the same size: its non-black pixels are the lit ones (the strokes'
    # widths may round differently at the file display's pitch: a few edge pixels)
    colour = RecordingPanel(128, 64, "RGB")
    draw_reference(colour)
    strokes = colour.canvas.array.max(axis=2) >= 96
    assert (lit == strokes).mean() > 0.95 and (lit & strokes).sum() > 0.9 * strokes.sum()
    np.testing.assert_array_equal(lit_reference(mono), lit.astype(np.uint8))
    # drawn on the mono canvas directly, its darker colours (red, blue, green) fall below the threshold
    direct = RecordingPanel(128, 64, "1")
    draw_reference(direct)
    assert lit.sum() > 2 * direct.canvas.array.sum() and 0.1 < lit.mean() < 0.6


def test_a_colour_raster_gets_the_scene_itself_and_it_is_sent():
    shown, drawn = RecordingPanel(96, 64, "RGB"), RecordingPanel(96, 64, "RGB")
    show_reference(shown)
    draw_reference(drawn)
    np.testing.assert_array_equal(shown.canvas.array, drawn.canvas.array)
    assert len(shown.frames) >= 1 and not shown.canvas.damage()  # nothing left unsent

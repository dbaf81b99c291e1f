"""Tests of the plugin's panel fixtures: a user's test file using sim_panel and make_sim_panel, run by pytester."""

from importlib import metadata

import numpy  # noqa: F401 - imported before pytester's in-process runs, which restore sys.modules after each
import pytest
from PIL import Image

import pixelpen.pytest_plugin  # noqa: F401
from pixelpen.display.registry import known_schemes
from pixelpen.sim.base import simulator_models

pytest_plugins = ["pytester"]
known_schemes(), simulator_models()  # load the drivers and simulators once, outside the inner runs

pytestmark = pytest.mark.skipif("st7789" not in simulator_models(), reason="the ST7789 simulator is not registered")

USER_TESTS = '''
import numpy as np
import pytest

import pixelpen


def paint_logo(url):
    """The application under test: it only knows the URL it is given."""
    with pixelpen.open(url) as panel:
        panel.canvas.fill((255, 0, 0))
        panel.canvas.blit(np.full((20, 20, 3), 255, np.uint8), 100, 100)
        panel.flush()


def test_glass_gram_and_bus_of_the_applications_display(sim_panel):
    assert sim_panel.url.startswith("sim:st7789?id=pytest-") and not sim_panel.opened
    with pytest.raises(LookupError, match="not opened"):
        sim_panel.glass()
    paint_logo(sim_panel.url)
    glass = np.asarray(sim_panel.glass().convert("RGB"))
    assert glass.shape == (240, 240, 3)
    assert (glass[:100, :] == (255, 0, 0)).all() and (glass[100:120, 100:120] == 255).all()
    # RGB565 red 0xF800 is 6-bit components (62, 0, 0) in the ST7789's frame memory
    assert sim_panel.gram.ndim == 3 and sim_panel.gram.max() > 0
    # two full frames (the black one of the initialisation, the red one): 2 x 240 x 240 x 2 pixel bytes at least
    assert sim_panel.bus_bytes >= 2 * 115_200 and sim_panel.bus.frames >= 2


def test_frames_of_a_watched_display(sim_panel):
    display = sim_panel.open()
    display.canvas.blit(np.full((20, 20, 3), 255, np.uint8), 10, 10)
    display.flush()
    frames = sim_panel.frames
    assert [f.full for f in frames] == [True, False]
    # panels.md 4: a 20x20 RGB565 window is 811 bytes (CASET 2Ah + 4, RASET 2Bh + 4, RAMWR 2Ch, 800 pixel bytes)
    assert frames[1].bytes == 811 and frames[1].windows == 1
    # 8 SPI clocks a byte at the ST7789's 62.5 MHz default
    assert frames[1].bus_seconds == pytest.approx(811 * 8 / 62.5e6, rel=0.01)
    assert frames[1].host_seconds >= 0


def test_recording_gives_the_command_and_data_frames(make_sim_panel):
    panel = make_sim_panel("st7789", size="240x320")  # the whole frame memory: no RAM offsets
    display = panel.open()
    with panel.recording() as trace:
        display.canvas.blit(np.full((2, 3, 3), 255, np.uint8), 16, 32)
        display.flush()
    ops = [(e.op, e.data.hex()) for e in trace.events]
    # ST7789 datasheet: CASET XS XE, RASET YS YE (16-bit big-endian, inclusive), RAMWR then pixels
    assert ops == [("C", "2a"), ("D", "00100012"), ("C", "2b"), ("D", "00200021"), ("C", "2c"), ("D", "ff" * 12)]


@pytest.mark.parametrize("sim_panel", ["ili9341?size=320x240", {"model": "st7735"}], indirect=True)
def test_parametrised(sim_panel):
    display = sim_panel.open(rotation=90)
    assert sim_panel.model in ("ili9341", "st7735")
    assert display.canvas.size == (display.capabilities.size[0], display.capabilities.size[1])


def test_factory_gives_several_panels(make_sim_panel):
    a = make_sim_panel("st7789", size="240x240")
    b = make_sim_panel("fbdev", size="64x48")
    assert a.id != b.id and not a.opened and not b.opened
    with pytest.raises(LookupError, match="open"):
        a.display


@pytest.mark.parametrize("sim_panel", ["ssd1306?size=128x64"], indirect=True)
def test_a_mono_oled(sim_panel):
    with pixelpen.open(sim_panel.url) as oled:
        oled.canvas.blit(np.ones((8, 16), np.uint8), 0, 0)   # 16 columns of page 0 lit
        oled.flush()
    lit = np.asarray(sim_panel.glass().convert("L")) > 0
    assert lit.shape == (64, 128) and lit[:8, :16].all() and lit.sum() == 8 * 16
    assert sim_panel.gram.shape[0] == 8                  # SSD1306 RAM: 8 pages of 128 column bytes


def test_a_failing_test(sim_panel):
    paint_logo(sim_panel.url)
    assert False, "fails on purpose: its glass is saved"
'''


def _plugin_args():
    installed = any(ep.name == "pixelpen" for ep in metadata.entry_points(group="pytest11"))
    quiet = ["-p", "no:cacheprovider", "-p", "no:benchmark", "-W", "ignore::pytest.PytestAssertRewriteWarning"]
    return quiet + ([] if installed else ["-p", "pixelpen.pytest_plugin"])


def test_panel_fixtures_in_a_user_test_file(pytester, tmp_path):
    pytester.makepyfile(test_user=USER_TESTS)
    glass_dir = tmp_path / "glass"
    result = pytester.runpytest(*_plugin_args(), "--pixelpen-glass-dir", str(glass_dir))
    result.assert_outcomes(passed=7, failed=1)
    # only the failed test's glass is kept, named as the paper of the plotter fixtures
    assert sorted(p.name for p in glass_dir.iterdir()) == ["test_a_failing_test-st7789.png"]
    glass = Image.open(glass_dir / "test_a_failing_test-st7789.png").convert("RGB")
    assert glass.size == (240, 240) and glass.getpixel((5, 5)) == (255, 0, 0)


def test_glass_dir_is_listed_in_help(pytester):
    result = pytester.runpytest(*_plugin_args(), "--help")
    result.stdout.fnmatch_lines(["*--pixelpen-glass-dir*"])


@pytest.mark.parametrize("model", ["hp7475a", "nosuchpanel"])
def test_a_model_that_is_no_panel_is_a_usage_error(model):
    from pixelpen.pytest_plugin import SimPanel

    with pytest.raises(pytest.UsageError, match="no simulated panel"):
        SimPanel(model)


def test_the_id_is_the_fixtures():
    from pixelpen.pytest_plugin import SimPanel

    with pytest.raises(pytest.UsageError, match="'id'"):
        SimPanel("st7789", {"id": "mine"})

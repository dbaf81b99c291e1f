"""Tests of the core commands: demo, draw and devices, run in-process through the CLI entry point."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image as PILImage

from pixelpen.cli import main
from pixelpen.commands.core import SIGNATURE_TOLERANCE_MM, input_demo
from pixelpen.display.pictfile import save_picture
from pixelpen.display.picture import Fill, Picture, Polyline, Rectangle, Style
from pixelpen.drivers.recordings.hidrecorder import read_hid_recording
from pixelpen.scene import reference_scene
from pixelpen.sim.base import simulator_models


@pytest.fixture(autouse=True)
def no_user_config(monkeypatch):
    monkeypatch.setenv("PIXELPEN_CONFIG", "")


def test_demo_writes_the_scene_as_png_svg_and_simulated_plotter_papers(tmp_path, capsys):
    assert main(["demo", "-o", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    out = captured.out
    # the scene's image cannot be plotted: 4 vector displays x 3 draws say so once, and count the repeats
    warning = "warning: 1 image shape(s) skipped: a vector device cannot draw raster images"
    assert captured.err.splitlines().count(warning) == 1
    assert "(11 more of: 1 image shape(s) skipped" in captured.err
    assert not re.search(r"^(WARNING|INFO) pixelpen\.", captured.err, re.M)  # no logger names for the user
    png, svg = tmp_path / "scene.png", tmp_path / "scene.svg"
    assert str(tmp_path.resolve()) in out and png.exists() and svg.exists()
    img = np.asarray(PILImage.open(png).convert("RGB"))
    assert img.shape == (1120, 2080, 3)
    # the scene draws in several colours on a white page: red, blue and lots of white
    assert (img == 255).all(axis=2).mean() > 0.5
    assert ((img[..., 0] > 200) & (img[..., 1] < 60) & (img[..., 2] < 60)).any()  # red
    assert ((img[..., 2] > 200) & (img[..., 0] < 60) & (img[..., 1] < 60)).any()  # blue
    for model in ("hp7475a", "grbl", "axidraw"):  # the scene plotted on each simulated plotter
        paper = np.asarray(PILImage.open(tmp_path / f"paper-{model}.png").convert("L"))
        assert (paper < 128).mean() > 0.005, model
    text = svg.read_text()
    assert 'width="260mm"' in text.replace(".0mm", "mm") and "<g" in text
    # the 3D scene: hidden lines plotted on a simulated plotter, shaded on a simulated panel (red cube, blue
    # sphere, green torus on black)
    assert "3D: a cube, a sphere and a torus" in captured.err
    paper3d = np.asarray(PILImage.open(tmp_path / "paper3d-hp7475a.png").convert("L"))
    assert 0.001 < (paper3d < 128).mean() < 0.05  # outlines, not filled areas
    glass3d = np.asarray(PILImage.open(tmp_path / "panel3d-st7789.png").convert("RGB")).astype(int)
    for channel in range(3):
        others = [c for c in range(3) if c != channel]
        dominant = (glass3d[..., channel] > 1.5 * glass3d[..., others].max(axis=2) + 20)
        assert dominant.mean() > 0.01, channel
    # and on every registered simulated panel: its glass, the animation and the frame statistics
    shown = [line for line in captured.err.splitlines() if "shown on a simulated panel" in line]
    assert len(shown) == len(json.loads((tmp_path / "panels.json").read_text())) >= 1


@pytest.mark.skipif("st7789" not in simulator_models(), reason="the ST7789 simulator is not registered")
def test_panel_demo_writes_glass_animation_and_frame_statistics(tmp_path):
    from pixelpen.commands.core import ANIMATION_FRAMES, panel_demo

    results = {r.url.partition("?")[0]: r for r in panel_demo(tmp_path)}
    st7789 = results["sim:st7789"]
    glass = PILImage.open(tmp_path / st7789.glass).convert("RGB")
    assert glass.size == (240, 240) and np.asarray(glass).max(axis=2).mean() > 5  # the scene, not a black glass
    gif = PILImage.open(tmp_path / st7789.animation)
    assert gif.n_frames == ANIMATION_FRAMES
    gif.seek(ANIMATION_FRAMES - 1)
    last = np.asarray(gif.convert("RGB")).astype(int)
    # the cursor (20x20, a twelfth of 240, orange) started at (5, 5) and moved (6, 4) a frame (a fortieth of the
    # width, a sixtieth of the height): in the last frame it is at (5 + 29 * 6, 5 + 29 * 4) = (179, 121)
    orange = (np.abs(last - (255, 160, 0)).sum(axis=2) < 60)
    assert orange[121:141, 179:199].all() and not orange[5:25, 5:25].all()
    gif.seek(0)
    assert (np.abs(np.asarray(gif.convert("RGB")).astype(int)[5:25, 5:25] - (255, 160, 0)).sum(axis=2) < 60).all()
    # each frame: the cursor's old and new squares (a 20x20 RGB565 window is 811 bytes, panels.md 4) and the
    # clock's changed digits; a full frame would be 115,211 bytes
    assert st7789.frames == ANIMATION_FRAMES and st7789.bytes_per_frame < 4 * 811
    # panels.md 4: full frames of ST7789 240x240 RGB565 at 62.5 MHz: 67.8 fps; ILI9341 320x240 at 10 MHz: 8.1
    assert st7789.full_frame_fps_at_bus_limit == pytest.approx(67.8, abs=0.05)
    if "sim:ili9341" in results:
        assert results["sim:ili9341"].full_frame_fps_at_bus_limit == pytest.approx(8.1, abs=0.05)
        assert PILImage.open(tmp_path / "panel-ili9341.png").size == (320, 240)
    if "sim:ssd1306" in results:  # a mono OLED: 1,030 bytes a full frame (panels.md 4), the animation far less
        ssd1306 = results["sim:ssd1306"]
        oled = np.asarray(PILImage.open(tmp_path / ssd1306.glass).convert("L")) > 0
        assert oled.shape == (64, 128) and 0.05 < oled.mean() < 0.6  # the scene's strokes lit, whatever their colour
        assert ssd1306.bytes_per_frame < 1030 / 4
        # panels.md 4: I2C at 400 kHz carries 43 full SSD1306 frames a second
        assert ssd1306.full_frame_fps_at_bus_limit == pytest.approx(43, abs=0.5)
    stats = json.loads((tmp_path / "panels.json").read_text())
    assert [s["url"] for s in stats] == [r.url for r in results.values()]


def test_a_demo_panel_that_is_not_a_panel_display_is_a_config_error_naming_it(tmp_path):
    from pixelpen.commands.core import panel_demo
    from pixelpen.errors import ConfigError

    if "grbl" not in simulator_models():
        pytest.skip("the grbl simulator is not registered")
    with pytest.raises(ConfigError, match=r"demo panel 'grbl' \(sim:grbl\): opened a \w+, not a panel display"):
        panel_demo(tmp_path, [("grbl", {})])


def test_draw_a_picture_file_on_png(tmp_path):
    pic = Picture(window=(0, 0, 10, 10))
    pic.add(Rectangle(0, 0, 5, 5, Style(colour="black", fill=Fill("solid", outline=False))))
    pic.add(Polyline([[0, 10], [10, 10]]))
    path = tmp_path / "p.json"
    save_picture(pic, path)
    out = tmp_path / "o.png"
    assert main(["draw", str(path), "--to", f"png:{out}?size=100x100"]) == 0
    img = np.asarray(PILImage.open(out).convert("L"))
    # lower-left quarter of the world (y up) is the lower-left quarter of the image (y down)
    assert img[60:95, 5:45].max() == 0 and img[5:45, 55:95].min() == 255


def test_draw_errors_are_one_line_and_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    assert main(["draw", str(bad), "--to", "png:x.png"]) == 2
    err = capsys.readouterr().err
    assert "bad.json" in err and "Traceback" not in err
    save_picture(Picture(), tmp_path / "ok.json")
    assert main(["draw", str(tmp_path / "ok.json"), "--to", "nosuch:x"]) == 2
    assert "known schemes" in capsys.readouterr().err
    assert main(["draw", str(tmp_path / "ok.json"), "--to", "png:x.png?colour=red"]) == 2
    assert "known: background, dpi, mode, size" in capsys.readouterr().err


def test_devices_lists_schemes_with_options(capsys):
    assert main(["devices", "--json", "--no-probe"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert {"png", "svg"} <= set(data["schemes"]) and "size" in data["schemes"]["png"]["options"]
    assert data["schemes"]["png"]["options"]["size"] == "image size in pixels, WxH (default 800x600)"
    line = data["options"]["options of every sim: and sim:// URL (the simulated line)"]
    assert {"speed", "baud", "flow"} <= set(line)
    sections = set(data["options"])
    assert {f"options of the {m} simulator (sim:{m})" for m in ("hp7475a", "grbl", "axidraw")} <= sections
    grbl = data["options"]["options of the grbl simulator (sim:grbl)"]
    assert grbl["rx_buffer"].startswith("serial RX buffer")
    assert set(data["inputs"]) == {"sim", "hid", "replay", "evdev", "evemu"}  # pixelpen.open_input's schemes
    assert data["inputs"]["hid"].startswith("hid:PATH or hid:VID:PID")
    assert "options of the tablet simulator (sim:tablet)" in sections  # the HID simulators' options too


def test_devices_lists_every_option_section_under_its_title(capsys, monkeypatch):
    from pixelpen.commands import core
    from pixelpen.options import OptionSpec, integer

    knobs = OptionSpec("knobs", integer(1), 3, "how many ``knobs``")
    monkeypatch.setattr(core, "option_sections", lambda: [("widgets of the test", (knobs,))])
    assert main(["devices", "--no-probe"]) == 0
    out = capsys.readouterr().out
    assert "\nWidgets of the test:\n      ?knobs=  how many knobs (default 3)\n" in out


def test_devices_reports_what_discovery_finds(capsys, monkeypatch):
    from pixelpen.commands import core
    from pixelpen.drivers.discovery import DiscoveredDevice

    found = [DiscoveredDevice("serial", "/dev/ttyUSB0", "FT232R", 0x0403, 0x6001, model="hp7475a")]
    monkeypatch.setattr(core, "discover", lambda: found)
    assert main(["devices", "--json"]) == 0
    (rec,) = json.loads(capsys.readouterr().out)["present"]
    assert rec == {"kind": "serial", "path": "/dev/ttyUSB0", "description": "FT232R", "model": "hp7475a",
                   "usb_id": "0403:6001"}
    assert main(["devices"]) == 0
    assert "usb_id=0403:6001" in capsys.readouterr().out


def test_devices_prints_plain_text_without_rest_markup(capsys):
    assert main(["devices", "--no-probe"]) == 0
    out = capsys.readouterr().out
    assert "`" not in out and not re.search(r":(func|class|meth|mod|attr):", out)
    assert "Draws into a framebuffer and writes it to PATH (png:PATH?size=800x600&dpi=96)." in out
    assert main(["devices", "--no-probe", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert "`" not in json.dumps(data["schemes"])


@pytest.mark.parametrize("rst, plain", [
    ("writes ``PATH`` (``png:PATH``).", "writes PATH (png:PATH)."),
    ("see :func:`~pixelpen.vector.optimize.optimize`", "see optimize"),
    ("see :mod:`pixelpen.urls` and :py:class:`the map <pixelpen.urls.Options>`", "see pixelpen.urls and the map"),
    ("a `title` and **bold**", "a title and bold"),
    ("Example::", "Example:"),
])
def test_plain_text_of_rest(rst, plain):
    from pixelpen.commands.core import plain_text

    assert plain_text(rst) == plain


def test_input_demo_smooths_a_replayed_signature_and_picks_over_the_scene(tmp_path: Path) -> None:
    result = input_demo(tmp_path)
    # the signature script writes three words and a flourish, each a pen-down stroke (sim/hid/motion.py)
    assert result.strokes == 4
    assert 0 < result.max_error_mm <= SIGNATURE_TOLERANCE_MM
    assert result.control_points < result.stroke_points  # smoothing, not interpolation
    (tablet,) = read_hid_recording(tmp_path / result.signature_recording)
    assert len(tablet.reports) == result.signature_reports and tablet.vendor_id == 0x1209
    glass = np.asarray(PILImage.open(tmp_path / result.signature_glass).convert("RGB"))
    assert ((glass[..., 1] > 150) & (glass[..., 2] > 150) & (glass[..., 0] < 100)).sum() > 300  # cyan ink
    # the echo moved in small frames: far less than a full 240 x 240 RGB565 frame each
    assert result.echo_frames > 50 and result.echo_bytes_per_frame < 0.01 * 240 * 240 * 2
    paper = np.asarray(PILImage.open(tmp_path / result.signature_paper).convert("L"))
    assert (paper < 128).mean() > 0.001
    items = {i.name for i in reference_scene().items if hasattr(i, "name")} | {
        f"{type(i).__name__.lower()} {k}" for k, i in enumerate(reference_scene().items)}
    assert result.picked and set(result.picked) <= items and set(result.hovered) <= items
    assert set(result.picked) <= set(result.hovered)
    assert json.loads((tmp_path / "input.json").read_text())["strokes"] == 4

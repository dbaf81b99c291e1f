"""Echo: the pixels under the cursor restored, damage only around it, and a panel sending only those pixels."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pixelpen.display.kinds import RasterDisplay
from pixelpen.display.picture import Fill, Polygon, Style
from pixelpen.display.registry import display_class, open_display
from pixelpen.errors import ConfigError, InvalidArgument, InvalidArgumentType
from pixelpen.input.echo import Echo
from pixelpen.raster.damage import Rect
from pixelpen.urls import parse_url


def png(tmp_path: Path) -> RasterDisplay:
    shown = display_class("png").from_url(parse_url(f"png:{tmp_path / 'e.png'}?size=64x48&dpi=25.4"))
    shown.open()
    shown.window(0, 0, 64, 48)
    shown.draw(Polygon([(0, 0), (64, 48), (0, 48)], Style(colour="blue", fill=Fill("solid"))))
    shown.flush()
    shown.canvas.clear_damage()
    return shown  # type: ignore[return-value]


def test_a_crosshair_is_drawn_in_its_box_and_moving_restores_what_was_under_it(tmp_path: Path) -> None:
    shown = png(tmp_path)
    before = shown.canvas.array.copy()
    echo = Echo(shown, size=5, colour="red", present=False)
    echo.move(20.3, 30.9)
    # a 5-pixel crosshair centred on pixel (20, 30): rows 28..32 of column 20 and columns 18..22 of row 30
    changed = np.argwhere((shown.canvas.array != before).any(axis=2))
    assert {tuple(p) for p in changed} <= {(30, x) for x in range(18, 23)} | {(y, 20) for y in range(28, 33)}
    assert (shown.canvas.array[30, 18] == (255, 0, 0)).all() and (shown.canvas.array[28, 20] == (255, 0, 0)).all()
    assert shown.canvas.damage() == [Rect(18, 28, 23, 33)]
    shown.canvas.clear_damage()
    echo.move(40, 10)
    assert sorted(shown.canvas.damage(merge_cost=0)) == [Rect(18, 28, 23, 33), Rect(38, 8, 43, 13)]
    assert (shown.canvas.array[28:33, 18:23] == before[28:33, 18:23]).all()
    echo.hide()
    assert (shown.canvas.array == before).all()
    shown.close()


def test_a_rubber_band_from_its_anchor_and_the_edges(tmp_path: Path) -> None:
    shown = png(tmp_path)
    before = shown.canvas.array.copy()
    band = Echo(shown, shape="rectangle", anchor=(60.0, 40.0), present=False)
    band.move(70.0, 50.0)  # past the canvas edge: clipped
    assert shown.canvas.damage() == [Rect(60, 40, 64, 48)]
    band.hide()
    line = Echo(shown, shape="line", present=False)
    line.move(5, 5)
    line.move(15, 9)  # the first position is the anchor
    assert line.segments().tolist() == [[5, 5, 15, 9]]
    line.close()
    assert (shown.canvas.array == before).all()
    shown.close()


def test_drawing_while_hidden_is_kept(tmp_path: Path) -> None:
    shown = png(tmp_path)
    echo = Echo(shown, shape="box", size=9, present=False)
    echo.move(10, 10)
    with echo.hidden():
        shown.canvas.lines(np.array([[6, 10, 14, 10]]), shown.canvas.colour_value((0, 255, 0)))
    assert echo.visible
    echo.move(40, 40)
    assert (shown.canvas.array[10, 7:14] == (0, 255, 0)).all()  # the new line stays; the box's old edges went
    shown.close()


def test_on_a_panel_only_the_cursors_pixels_go_over_the_bus() -> None:
    with open_display("sim:st7789?size=240x240") as panel:
        panel.flush()
        glass = np.asarray(panel.simulator.glass().convert("RGB")).copy()  # type: ignore[attr-defined]
        frames, sent = panel.stats.frames, panel.stats.bytes  # type: ignore[attr-defined]
        echo = Echo(panel, size=7, colour="white")  # type: ignore[arg-type]
        for k in range(5):
            echo.move(100 + 3 * k, 80 + 2 * k, time=0.1 * k)
        echo.hide()
        assert panel.stats.frames - frames == 6  # type: ignore[attr-defined]
        # each frame: at most the old and the new 7 x 7 boxes at 2 bytes a pixel (RGB565), plus window commands
        assert (panel.stats.bytes - sent) / 6 < 2 * (2 * 49) + 40  # type: ignore[attr-defined]
        assert (np.asarray(panel.simulator.glass().convert("RGB")) == glass).all()  # type: ignore[attr-defined]


def test_the_interval_coalesces_frames(tmp_path: Path) -> None:
    with open_display("sim:st7789?size=240x240") as panel:
        echo = Echo(panel, interval=0.05)  # type: ignore[arg-type]
        for k in range(10):
            echo.move(50 + k, 50, time=0.01 * k)
        assert echo.frames == 2  # at t = 0 and t = 0.05


def test_vector_displays_and_bad_options_are_refused(tmp_path: Path) -> None:
    svg = display_class("svg").from_url(parse_url(f"svg:{tmp_path / 'x.svg'}"))
    with pytest.raises(InvalidArgumentType, match="raster"):
        Echo(svg)  # type: ignore[arg-type]
    shown = png(tmp_path)
    with pytest.raises(ConfigError, match="shape"):
        Echo(shown, shape="arrow")  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="size"):
        Echo(shown, size=0)
    shown.close()

"""SSD1306-family hardware scroll by the display start line (40h | line): the window space is the RAM's rows, frame
row y at RAM row (y + offset) % 64, the glass checked against the canvas (PIL) and the RAM against a per-row walk."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

from pixelpen.devices.panels.base import PanelDisplay
from pixelpen.devices.panels.scrolling import START_LINE, ScrollArea
from tests.devices.panels.test_refresh_property import expected_glass, glass, open_panel
from tests.devices.panels.test_scrolling import play, scroll_sequences


def mono_noise(rng: np.random.Generator, height: int, width: int) -> np.ndarray:
    """Random 0/1 rows (64 random rows of 128 bits all differ)."""
    return rng.integers(0, 2, (height, width), dtype=np.uint8)


def shifted(display: PanelDisplay, dy: int, rng: np.random.Generator) -> np.ndarray:
    """The canvas moved up by ``dy`` rows (down for dy < 0), new random rows coming into view."""
    now = display.canvas.array
    fresh = mono_noise(rng, abs(dy), now.shape[1])
    return np.concatenate([now[dy:], fresh]) if dy > 0 else np.concatenate([fresh, now[:dy]])


def ram_rows(display: PanelDisplay) -> np.ndarray:
    """The simulator's GDDRAM as 64 rows of bits (page p bit k = row 8p + k), the glass's columns."""
    sim: Any = display.simulator
    pages = np.asarray(sim.gram)
    bits = np.unpackbits(pages[:, None, :], axis=1, bitorder="little").reshape(64, -1)
    x = display.column_start  # type: ignore[attr-defined]
    return bits[:, x:x + display.canvas.width]


def assert_ring(display: PanelDisplay) -> None:
    """Rotation 0, row by row: frame row y is in RAM row (y + offset) % 64 and the start line is the offset."""
    offset = display._scroll.offset
    sim: Any = display.simulator
    assert sim.start_line == offset
    ram = ram_rows(display)
    for y in range(display.canvas.height):
        assert list(ram[(y + offset) % 64]) == [int(v) for v in display.canvas.array[y]], y


def test_a_two_row_scroll_is_the_start_line_and_one_or_two_pages() -> None:
    display = open_panel("ssd1306", "128x64", 0)
    rng = np.random.default_rng(1)
    display.canvas.blit(mono_noise(rng, 64, 128), 0, 0)
    display.flush()
    for k in range(1, 12):
        display.canvas.blit(shifted(display, 2, rng), 0, 0)
        display.flush()
        assert display._scroll.offset == 2 * k
        assert (glass(display) == expected_glass(display)).all(), k
        assert_ring(display)
        # 40h|line, then the new rows 62..63 at RAM rows 2k-2..2k-1: one page (two where they cross one), each a
        # 6-byte window and up to 128 page bytes (the columns where the page changed; the driver's bytes, I2C
        # control bytes aside)
        pages = 1 + ((2 * k - 2) // 8 != (2 * k - 1) // 8)
        assert 1 + pages * (6 + 120) <= display.stats.last.bytes <= 1 + pages * (6 + 128)
        assert display.stats.last.windows == pages


def test_a_full_frame_puts_the_start_line_back_to_zero() -> None:
    display = open_panel("ssd1306", "128x64", 0)
    rng = np.random.default_rng(2)
    display.canvas.blit(mono_noise(rng, 64, 128), 0, 0)
    display.flush()
    display.canvas.blit(shifted(display, 5, rng), 0, 0)
    display.flush()
    assert display._scroll.offset == 5
    display.reset()
    assert display._scroll.offset == 0 and display.simulator.start_line == 0  # type: ignore[union-attr]
    assert (glass(display) == expected_glass(display)).all()
    assert_ring(display)


def test_hardware_scroll_off_and_panels_not_showing_all_64_rows_never_move_the_start_line() -> None:
    for url, extra in (("ssd1306", "&hardware_scroll=false"), ("ssd1306", "")):
        size = "128x64" if extra else "128x32"
        display = open_panel(url, size, 0, extra)
        height = display.canvas.height
        rng = np.random.default_rng(3)
        display.canvas.blit(mono_noise(rng, height, 128), 0, 0)
        display.flush()
        for _ in range(3):
            display.canvas.blit(shifted(display, 2, rng), 0, 0)
            display.flush()
            assert (glass(display) == expected_glass(display)).all()
        assert display._scroll.offset == 0 and display.simulator.start_line == 0  # type: ignore[union-attr]


def test_a_start_line_area_sends_one_command_per_offset() -> None:
    area = ScrollArea(0, 64, 0, start_line=True)
    assert [(s.command, s.params) for s in area.steps(70)] == [(START_LINE | 6, b"")]


@pytest.mark.parametrize("model", ["ssd1306", "sh1106"])
def test_glass_equals_canvas_after_every_frame_with_start_line_scrolls(model: str) -> None:
    display = open_panel(model, "128x64", 0)
    rng = np.random.default_rng(4)
    scrolls = {"n": 0}
    display.canvas.blit(mono_noise(rng, 64, 128), 0, 0)
    display.flush()

    @settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow], database=None,
              derandomize=True)
    @given(scroll_sequences(128, 64, mono=True))
    def frames(ops: list[tuple[str, Any]]) -> None:
        for kind, arg in ops:
            scrolls["n"] += play(display, kind, arg, rng, shifted, mono_noise, 1, 1)
            assert (glass(display) == expected_glass(display)).all(), (kind, arg)
            if display.rotation == 0 and model == "ssd1306":
                assert_ring(display)

    frames()
    assert scrolls["n"] > 0  # the start line really was used
    display.close()

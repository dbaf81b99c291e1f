"""MIPI-DCS displays: window bytes per module and rotation (Adafruit's offsets), colour depth, BGR, inversion, and
the bytes a moving cursor costs against the pixels that changed."""

from __future__ import annotations

import numpy as np
import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.devices.panels.mipidcs import ILI9341Display, MipiDcsDisplay, ST7789Display
from pixelpen.devices.panels.wiring import Wiring
from pixelpen.profiles.panel import load_panel_profile
from tests.devices.panels.test_base import StubBus, windows


def tft(profile: str, cls: type[MipiDcsDisplay] = ST7789Display, **kwargs: object) -> tuple[MipiDcsDisplay, StubBus]:
    bus = StubBus()
    display = cls(Wiring(bus), profile=load_panel_profile(profile), clock=SimulatedClock(), **kwargs)
    display.open()
    return display, bus


def after(log: list[tuple[str, bytes]], command: int) -> list[bytes]:
    """The parameter bytes that followed each ``command`` in a log."""
    return [log[i + 1][1] for i, (k, p) in enumerate(log) if k == "C" and p == bytes([command])]


# (profile, rotation, CASET first..last, RASET first..last, MADCTL): Adafruit_ST7789::setRotation and init
# (240x240: _rowstart = 320 - 240; 135x240: _colstart = (240 - 135 + 1) / 2 = 53, _colstart2 = 52,
# _rowstart = (320 - 240) / 2 = 40), Adafruit_ILI9341::setRotation (MX|BGR, MV|BGR, MY|BGR, MX|MY|MV|BGR).
FULL_WINDOWS = [
    ("st7789_240x240", 0, "00 00 00 ef", "00 50 01 3f", 0xC0),
    ("st7789_240x240", 90, "00 50 01 3f", "00 00 00 ef", 0xA0),
    ("st7789_240x240", 180, "00 00 00 ef", "00 00 00 ef", 0x00),
    ("st7789_240x240", 270, "00 00 00 ef", "00 00 00 ef", 0x60),
    ("st7789_135x240", 0, "00 35 00 bb", "00 28 01 17", 0xC0),
    ("st7789_135x240", 90, "00 28 01 17", "00 34 00 ba", 0xA0),
    ("st7789_135x240", 180, "00 34 00 ba", "00 28 01 17", 0x00),
    ("st7789_135x240", 270, "00 28 01 17", "00 35 00 bb", 0x60),
    ("ili9341_240x320", 0, "00 00 00 ef", "00 00 01 3f", 0x48),
    ("ili9341_240x320", 90, "00 00 01 3f", "00 00 00 ef", 0x28),
    ("ili9341_240x320", 180, "00 00 00 ef", "00 00 01 3f", 0x88),
    ("ili9341_240x320", 270, "00 00 01 3f", "00 00 00 ef", 0xE8),
]


@pytest.mark.parametrize(("profile", "rotation", "caset", "raset", "madctl"), FULL_WINDOWS)
def test_full_frame_window_and_madctl(profile: str, rotation: int, caset: str, raset: str, madctl: int) -> None:
    cls = ILI9341Display if profile.startswith("ili") else ST7789Display
    display, bus = tft(profile, cls, rotation=rotation)
    log = bus.take()
    assert after(log, 0x36)[-1] == bytes([madctl])
    assert after(log, 0x2A)[-1] == bytes.fromhex(caset)
    assert after(log, 0x2B)[-1] == bytes.fromhex(raset)
    w, h = display.canvas.size
    assert len(after(log, 0x2C)[-1]) == w * h * 2


def test_rgb666_on_request_is_colmod_66_and_three_bytes_with_6_significant_bits() -> None:
    display, bus = tft("st7789_240x240", colour="rgb666")
    assert after(bus.take(), 0x3A)[-1] == b"\x66"
    display.canvas.lines([[3, 3, 3, 3]], (0x13, 0x57, 0x9B))
    display.flush()
    assert bus.take()[-1] == ("D", bytes([0x10, 0x54, 0x98]))  # c & 0xFC (datasheet 18-bit serial format)


def test_rgb565_is_colmod_55() -> None:
    _, bus = tft("st7789_240x240")
    assert set(after(bus.take(), 0x3A)) == {b"\x55"}


def test_bgr_and_invert_options_override_the_profile() -> None:
    _, bus = tft("st7789_240x240", bgr=True, invert=False)
    log = bus.take()
    assert after(log, 0x36)[-1] == b"\xc8"  # MY|MX|BGR
    commands = [p for k, p in log if k == "C"]
    assert commands.index(b"\x20") > commands.index(b"\x21")  # the driver's INVOFF comes after the table's INVON


def move_cursor(display: MipiDcsDisplay, bus: StubBus, moves: list[tuple[int, int]]) -> tuple[int, int]:
    """Draw a 20x20 white square at each position on black; (bytes sent, changed pixels) after the first."""
    black = (0, 0, 0)
    square = np.full((20, 20, 3), 255, dtype=np.uint8)
    x, y = moves[0]
    display.canvas.blit(square, x, y)
    display.flush()
    bus.take()
    sent = changed = 0
    for nx, ny in moves[1:]:
        before = display.canvas.array.copy()
        display.canvas.polygons([[(x, y), (x + 20, y), (x + 20, y + 20), (x, y + 20)]], black)
        display.canvas.blit(square, nx, ny)
        display.flush()
        changed += int((display.canvas.array != before).any(axis=2).sum())
        sent += sum(len(p) for _, p in bus.take())
        x, y = nx, ny
    return sent, changed


@pytest.mark.parametrize(("step", "windows_per_move"), [((5, 0), 2), ((3, 2), 4)])
def test_a_moving_cursor_costs_its_changed_pixels_plus_window_commands(step: tuple[int, int],
                                                                      windows_per_move: int) -> None:
    display, bus = tft("st7789_240x240")
    moves = [(20 + i * step[0], 30 + i * step[1]) for i in range(20)]
    sent, changed = move_cursor(display, bus, moves)
    # the changed pixels of a translated square are covered exactly by 2 (horizontal) or 4 (diagonal) rectangles
    ideal = changed * 2 + 11 * windows_per_move * (len(moves) - 1)
    assert sent <= 1.1 * ideal, (sent, ideal)


def test_te_line_turns_teon_on() -> None:
    class Line:
        def __init__(self) -> None:
            self.waits = 0

        def get(self) -> bool:
            return False

        def wait_edge(self, rising: bool, timeout: float) -> bool:
            self.waits += 1
            return True

        def close(self) -> None:
            pass

    bus, te = StubBus(), Line()
    display = ST7789Display(Wiring(bus, te=te), profile=load_panel_profile("st7789_240x240"), clock=SimulatedClock())
    display.open()
    assert after(bus.take(), 0x35) == [b"\x00"] and te.waits == 1  # TEON V-blank only; the first frame waited
    display.canvas.lines([[0, 0, 1, 1]], (9, 9, 9))  # RGB565 (8, 8, 8): a change on the wire
    display.flush()
    assert te.waits == 2


def test_a_change_below_the_wires_resolution_sends_nothing() -> None:
    bus = StubBus()
    display = ST7789Display(Wiring(bus), profile=load_panel_profile("st7789_240x240"), clock=SimulatedClock())
    display.open()
    bus.take()
    frames = display.stats.frames
    display.canvas.lines([[0, 0, 5, 5]], (7, 3, 7))  # RGB565 truncates to black: the panel already shows it
    display.flush()
    assert display.stats.frames == frames and after(bus.take(), 0x2C) == []


def test_partial_windows_are_inside_the_module() -> None:
    display, bus = tft("st7789_135x240", rotation=90)
    bus.take()
    display.canvas.lines([[0, 0, 239, 134]], (255, 0, 0))
    display.flush()
    for xs, xe, ys, ye, _ in windows(bus.take()):
        assert 40 <= xs <= xe <= 279 and 52 <= ys <= ye <= 186


def test_a_diagonal_across_the_screen_is_not_sent_as_its_bounding_box() -> None:
    display, bus = tft("st7789_240x240")
    bus.take()
    display.canvas.lines([[0, 0, 239, 239]], (255, 255, 255))
    display.flush()
    sent = windows(bus.take())
    assert sum(w[4] for w in sent) < 0.05 * 240 * 240 * 2
    covered = np.zeros((240, 240), dtype=bool)
    for xs, xe, ys, ye, _ in sent:
        covered[ys - 80:ye - 80 + 1, xs:xe + 1] = True  # rotation 0: rows +80
    assert covered[np.arange(240), np.arange(240)].all()  # every pixel of the line is in a window


def test_windows_in_the_same_rows_leave_out_raset_and_the_glass_is_still_right() -> None:
    """Two marks far apart in the same rows: two windows, the second without RASET (the controller keeps the
    rows, RAMWR starts at the window's first pixel); on the simulated ST7789 the glass shows both marks."""
    bus = StubBus()
    display = ST7789Display(Wiring(bus), profile=load_panel_profile("st7789_240x240"), clock=SimulatedClock())
    display.open()
    bus.take()
    display.canvas.blit(np.full((4, 3, 3), 255, np.uint8), 10, 20)
    display.canvas.blit(np.full((4, 3, 3), 255, np.uint8), 200, 20)
    display.flush()
    log = bus.take()
    assert [p for k, p in log if k == "C"] == [b"\x2a", b"\x2b", b"\x2c", b"\x2a", b"\x2c"]
    assert windows(log) == [(10, 12, 100, 103, 24), (200, 202, 100, 103, 24)]  # rows + the module's 80-row offset
    assert display.stats.last.bytes == 11 + 24 + 6 + 24

    import pixelpen

    with pixelpen.open("sim:st7789?size=240x240") as sim:
        sim.canvas.blit(np.full((4, 3, 3), 255, np.uint8), 10, 20)
        sim.canvas.blit(np.full((4, 3, 3), 255, np.uint8), 200, 20)
        sim.flush()
        glass = np.asarray(sim.simulator.glass().convert("RGB"))
        assert (glass == sim.canvas.array).all() and sim.stats.last.windows == 2

"""SSD1306/SSD1309/SH1106 displays: init and window bytes from the datasheets, frame bytes against luma.oled."""

from __future__ import annotations

import numpy as np
import pytest
from luma.oled.device import sh1106, ssd1306
from PIL import Image

from pixelpen.clock import SimulatedClock
from pixelpen.devices.panels.ssd1306 import SH1106Display, SSD1306Display, SSD1309Display
from pixelpen.devices.panels.wiring import Wiring
from pixelpen.profiles.panel import load_panel_profile
from tests.devices.panels.test_base import StubBus

LUMA_INIT = bytes.fromhex("ae d5 80 a8 3f d3 00 40 8d 14 20 00 a1 c8 da 12 d9 f1 db 40 a4 a6")
"""luma.oled's SSD1306 128x64 init (panels.md §1; datasheet Table 9-1), then ``81 cf``."""


class LumaCapture:
    """luma's serial interface, recording what its device sends."""

    def __init__(self) -> None:
        self.log: list[tuple[str, bytes]] = []

    def command(self, *cmd: int) -> None:
        self.log.append(("C", bytes(cmd)))

    def data(self, data: list[int]) -> None:
        self.log.append(("D", bytes(data)))

    def cleanup(self) -> None:
        pass


def oled(cls: type[SSD1306Display], profile: str, **kwargs: object) -> tuple[SSD1306Display, StubBus]:
    bus = StubBus(kind="i2c", clock_hz=400e3)
    display = cls(Wiring(bus), profile=load_panel_profile(profile), clock=SimulatedClock(), **kwargs)
    display.open()
    return display, bus


def picture(width: int, height: int, seed: int = 1) -> Image.Image:
    """A random 1-bit picture."""
    bits = np.random.default_rng(seed).random((height, width)) < 0.3
    return Image.fromarray(bits.astype(np.uint8) * 255).convert("1")


def show(display: SSD1306Display, image: Image.Image) -> None:
    display.canvas.array[...] = np.asarray(image, dtype=np.uint8)
    display.canvas.mark_damaged()
    display.flush()


def test_init_is_the_datasheet_sequence_then_a_whole_frame_then_display_on() -> None:
    display, bus = oled(SSD1306Display, "ssd1306_128x64")
    commands = [p for k, p in bus.take() if k == "C"]
    assert b"".join(commands[:14]) == LUMA_INIT
    assert commands[14:] == [b"\x81\xcf", b"\xa1\xc8\xa6", bytes.fromhex("21 00 7f 22 00 07"), b"\xaf"]
    assert display.clock.now() == pytest.approx(0.100)  # AFh: 100 ms for the SEG/COM outputs


def test_frame_bytes_equal_luma_oled_for_the_same_picture() -> None:
    image = picture(128, 64)
    luma_bus = LumaCapture()
    ssd1306(serial_interface=luma_bus, width=128, height=64).display(image)
    luma_frame = [p for k, p in luma_bus.log if k == "D"][-1]
    display, bus = oled(SSD1306Display, "ssd1306_128x64", refresh="full")
    bus.take()
    show(display, image)
    assert bus.take() == [("C", bytes.fromhex("21 00 7f 22 00 07")), ("D", luma_frame)]


def test_sh1106_pages_with_column_offset_2_equal_luma_oled() -> None:
    image = picture(128, 64, seed=2)
    luma_bus = LumaCapture()
    device = sh1106(serial_interface=luma_bus, width=128, height=64)
    luma_bus.log.clear()
    device.display(image)
    display, bus = oled(SH1106Display, "sh1106_128x64", refresh="full")
    bus.take()
    show(display, image)
    assert bus.take() == luma_bus.log  # per page: B0+p, 02, 10, then 128 bytes


def test_one_pixel_is_a_one_column_one_page_window() -> None:
    display, bus = oled(SSD1306Display, "ssd1306_128x64")
    bus.take()
    display.canvas.lines([[5, 13, 5, 13]], 1)
    display.flush()
    assert bus.take() == [("C", bytes.fromhex("21 05 05 22 01 01")), ("D", b"\x20")]  # row 13 = page 1, bit 5


def test_sh1106_partial_window_is_page_addressed() -> None:
    display, bus = oled(SH1106Display, "sh1106_128x64")
    bus.take()
    display.canvas.lines([[20, 9, 21, 9], [20, 17, 21, 17]], 1)
    display.flush()
    # column 20 + 2 = 0x16: low nibble 06h, high nibble 11h; rows 9 and 17 = pages 1 and 2, bit 1
    assert bus.take() == [("C", b"\xb1\x06\x11"), ("D", b"\x02\x02"), ("C", b"\xb2\x06\x11"), ("D", b"\x02\x02")]


@pytest.mark.parametrize("size", [(128, 32), (64, 48), (96, 16)])
def test_smaller_modules_send_the_window_and_bytes_luma_oled_sends(size: tuple[int, int]) -> None:
    image = picture(*size, seed=3)
    luma_bus = LumaCapture()
    device = ssd1306(serial_interface=luma_bus, width=size[0], height=size[1])
    luma_bus.log.clear()
    device.display(image)
    display, bus = oled(SSD1306Display, f"ssd1306_{size[0]}x{size[1]}", refresh="full")
    bus.take()
    show(display, image)
    assert bus.take() == luma_bus.log  # 64x48: 21 20 5f (columns 32..95); 128x32: pages 0..3


def test_128x32_init_sets_multiplex_32_and_sequential_com_pins() -> None:
    _, bus = oled(SSD1306Display, "ssd1306_128x32")
    commands = b"".join(p for k, p in bus.take() if k == "C")
    assert b"\xa8\x1f" in commands and b"\xda\x02" in commands


def test_rotation_180_flips_segments_and_com_scan_in_the_controller() -> None:
    display, bus = oled(SSD1306Display, "ssd1306_128x64", rotation=180)
    assert b"\xa0\xc0\xa6" in [p for k, p in bus.take() if k == "C"]
    assert display.canvas.size == (128, 64)


def test_rotation_90_turns_the_canvas_clockwise_in_software() -> None:
    display, bus = oled(SSD1306Display, "ssd1306_128x64", rotation=90)
    assert display.canvas.size == (64, 128)
    bus.take()
    display.canvas.lines([[0, 0, 0, 0]], 1)  # the canvas's top-left corner goes to the glass's top-right
    display.flush()
    assert bus.take() == [("C", bytes.fromhex("21 7f 7f 22 00 00")), ("D", b"\x01")]


def test_contrast_invert_and_power() -> None:
    display, bus = oled(SSD1306Display, "ssd1306_128x64", contrast=0x10, invert=True)
    commands = [p for k, p in bus.take() if k == "C"]
    assert b"\xa1\xc8\xa7" in commands and commands[commands.index(b"\xa1\xc8\xa7") + 1] == b"\x81\x10"
    display.set_contrast(0xFF)
    display.set_invert(False)
    display.power(False)
    assert bus.take() == [("C", b"\x81\xff"), ("C", b"\xa6"), ("C", b"\xae")]


def test_ssd1309_uses_the_ssd1306_window() -> None:
    _, bus = oled(SSD1309Display, "ssd1309_128x64")
    assert bytes.fromhex("21 00 7f 22 00 07") in [p for k, p in bus.take() if k == "C"]


def test_close_with_persist_false_sleeps_the_panel() -> None:
    display, bus = oled(SSD1306Display, "ssd1306_128x64", persist=False)
    bus.take()
    display.close()
    assert bus.take() == [("C", b"\xae"), ("X", b"")]


def test_a_glass_off_centre_moves_its_columns_when_rotation_flips_the_segment_remap() -> None:
    # luma's 96x16 is RAM columns 0..95 under A1h (SEG127..SEG32); under A0h the same SEG32..127 are RAM 32..127
    display, bus = oled(SSD1306Display, "ssd1306_96x16", rotation=180, refresh="full")
    bus.take()
    display.canvas.lines([[0, 0, 0, 0]], 1)
    display.flush()
    assert bus.take()[0] == ("C", bytes.fromhex("21 20 7f 22 00 01"))

"""A third-party client on the SSD1306 simulator: luma.oled's ssd1306 and sh1106 over luma's i2c interface.

luma.core's ``i2c(bus=...)`` sends commands with ``write_i2c_block_data(addr, 0x00, cmds)`` and data in
32-byte SMBus blocks; the managed form (``smbus2.SMBus(port)``, here the simulated bus in its place) sends
data with ``i2c_rdwr(i2c_msg.write(addr, [0x40] + chunk))``.  The oracle is the PIL image luma's ``canvas``
was given, turned by PIL for luma's ``rotate`` (luma rotates in software).
"""

from __future__ import annotations

import numpy as np
import pytest
import smbus2
from luma.core.interface.serial import i2c as luma_i2c
from luma.core.render import canvas
from luma.oled.device import sh1106, ssd1306
from PIL import Image, ImageDraw

from pixelpen.clock import SimulatedClock
from pixelpen.sim.panels.ssd1306 import SSD1306Sim
from pixelpen.sim.transports.i2cdev import SimSMBus

TURNS = {0: None, 1: Image.Transpose.ROTATE_270, 2: Image.Transpose.ROTATE_180, 3: Image.Transpose.ROTATE_90}
"""luma's rotate (quarter turns clockwise) as PIL transposes."""


def scene(draw: ImageDraw.ImageDraw, size: tuple[int, int]) -> None:
    width, height = size
    draw.rectangle((0, 0, width - 1, height - 1), outline="white")
    draw.text((2, 1), "luma", fill="white")
    draw.line((0, height - 1, width // 3, 0), fill="white")
    draw.ellipse((width - 14, height - 12, width - 3, height - 3), fill="white")


def drawn(device: object) -> Image.Image:
    """Draw the scene with luma's canvas and return the image luma was given."""
    frame = canvas(device)
    with frame as draw:
        scene(draw, device.size)  # type: ignore[attr-defined]
    return frame.image


def expected(image: Image.Image, rotate: int) -> np.ndarray:
    turn = TURNS[rotate]
    return np.asarray(image if turn is None else image.transpose(turn), dtype=bool)


@pytest.mark.parametrize(("width", "height"), [(128, 64), (128, 32), (64, 48)])
@pytest.mark.parametrize("rotate", [0, 1, 2, 3])
def test_luma_ssd1306_glass_equals_its_canvas(width, height, rotate):
    sim = SSD1306Sim(width, height, clock=SimulatedClock())
    device = ssd1306(luma_i2c(bus=SimSMBus(sim, clock=sim.clock), address=0x3C), width=width, height=height,
                     rotate=rotate)
    device.persist = True
    image = drawn(device)
    assert sim.events == []
    assert np.array_equal(np.asarray(sim.glass(), dtype=bool), expected(image, rotate))


def test_luma_sh1106_glass_equals_its_canvas_and_its_ssd1306_bytes_are_flagged():
    sim = SSD1306Sim(variant="sh1106", clock=SimulatedClock())
    device = sh1106(luma_i2c(bus=SimSMBus(sim, clock=sim.clock), address=0x3C))
    device.persist = True
    image = drawn(device)
    assert np.array_equal(np.asarray(sim.glass(), dtype=bool), expected(image, 0))
    # luma.oled 3.16 sends SSD1306's 20h (addressing mode) and 8Dh (charge pump): not SH1106 commands
    assert [e.command for e in sim.events] == [0x20, 0x8D]


def test_luma_managed_i2c_sends_a_frame_in_two_transactions(monkeypatch):
    sim = SSD1306Sim(clock=SimulatedClock())
    monkeypatch.setattr(smbus2, "SMBus", lambda port: SimSMBus(sim, clock=sim.clock))
    device = ssd1306(luma_i2c(port=1, address=0x3C))
    device.persist = True
    sim.reset_stats()
    image = drawn(device)
    assert np.array_equal(np.asarray(sim.glass(), dtype=bool), expected(image, 0))
    assert sim.stats.transfers == 2 and sim.stats.bytes - sim.stats.transfers == 1032  # panels.md §9
    assert round(sim.stats.bus_seconds * 1e3, 1) == 23.3 and sim.events == []


def test_luma_smbus_blocks_cost_33_transactions():
    sim = SSD1306Sim(clock=SimulatedClock())
    device = ssd1306(luma_i2c(bus=SimSMBus(sim, clock=sim.clock), address=0x3C))
    device.persist = True
    sim.reset_stats()
    drawn(device)
    assert sim.stats.transfers == 33 and sim.stats.bytes - sim.stats.transfers == 1063  # panels.md §9

"""Real clients drive the MIPI-DCS simulator: luma.lcd's st7789 and ili9341 through luma.core's spi interface.

luma sends through ``luma.core.interface.serial.spi(spi=<spidev>, gpio=<RPi.GPIO>)``, here the simulated
wiring's spidev and RPi.GPIO stand-ins: the bytes are luma's own, the glass must equal the image luma was
given (18-bit colour: each component's top six bits).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from PIL import Image, ImageDraw

from pixelpen.clock import SimulatedClock
from pixelpen.sim.panels.mipidcs import MipiDcsSim
from pixelpen.sim.transports.spidev import SimSpiWiring

serial = pytest.importorskip("luma.core.interface.serial")
lcd = pytest.importorskip("luma.lcd.device")


def picture(size: tuple[int, int]) -> Image.Image:
    """Shapes in saturated and mid colours, and a gradient whose low bits the 6-bit memory drops."""
    image = Image.new("RGB", size, (10, 20, 30))
    draw = ImageDraw.Draw(image)
    w, h = size
    draw.rectangle((5, 5, w // 3, h // 3), fill=(255, 0, 0))
    draw.ellipse((w // 2, 10, w - 10, h // 2), fill=(0, 255, 0), outline=(255, 255, 255))
    draw.polygon([(10, h - 10), (w // 2, h // 2), (w - 20, h - 5)], fill=(0, 0, 255))
    for x in range(w):
        draw.point((x, h // 2 + 3), fill=(x % 256, (3 * x) % 256, 255 - x % 256))
    return image


def truncated(image: Image.Image) -> np.ndarray:
    """What an 18-bit panel shows for 8-bit components: top six bits, expanded back as v << 2 | v >> 4."""
    six = np.asarray(image) >> 2
    return (six << 2) | (six >> 4)


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> SimulatedClock:
    """Simulated time, also for luma's own ``time.sleep`` calls (its reset and SLPOUT waits)."""
    clock = SimulatedClock()
    monkeypatch.setattr(lcd, "sleep", clock.sleep)
    monkeypatch.setattr(serial, "sleep", clock.sleep)
    return clock


def luma_device(kind: str, sim: MipiDcsSim, **spi: float) -> Any:
    """luma's ``kind`` device on the simulated wiring (GPIO 24 D/C, 25 RST, 18 backlight), left on at exit."""
    wiring = SimSpiWiring(sim, clock=sim.clock)
    interface = serial.spi(spi=wiring.spidev, gpio=wiring.gpio_module, gpio_DC=24, gpio_RST=25,
                           bus_speed_hz=32_000_000, **spi)
    device = getattr(lcd, kind)(interface, gpio=wiring.gpio_module)
    device.persist = True
    return device


def test_luma_st7789_puts_its_image_on_the_glass(clock):
    # luma's MADCTL 70h (MX|MV|ML) is upright on a 240x240 module held a quarter turn from Adafruit's rotation 0
    sim = MipiDcsSim("st7789", 240, 240, clock=clock, turn=270)
    device = luma_device("st7789", sim)
    image = picture((240, 240))
    device.display(image)
    assert np.array_equal(np.asarray(sim.glass()), truncated(image))
    assert [(e.command, e.message.split(" ms after ")[1].split(" (")[0]) for e in sim.events] == [
        (0x36, "RESX"),    # luma.core's spi() releases RST and sends at once (reset_release_time=0)
        (0x11, "RESX"),    # so SLPOUT comes within RESX's 120 ms too
        (0x29, "SLPOUT"),  # and DISPON straight after SLPOUT (5 ms)
    ]
    assert sim.stats.frames == 2  # the clear() and this image


def test_luma_with_reset_release_time_is_flagged_only_for_its_slpout_dispon(clock):
    sim = MipiDcsSim("st7789", 240, 240, clock=clock)
    luma_device("st7789", sim, reset_hold_time=1e-5, reset_release_time=0.150)
    assert [e.command for e in sim.events] == [0x29]


def test_luma_st7789_at_rotation_0_shows_its_image_a_quarter_turn_from_adafruit_s_rotation_0(clock):
    sim = MipiDcsSim("st7789", 240, 240, clock=clock)
    device = luma_device("st7789", sim)
    image = picture((240, 240))
    device.display(image)
    assert np.array_equal(np.asarray(sim.glass()), truncated(image.transpose(Image.Transpose.ROTATE_90)))


def test_luma_ili9341_puts_its_image_on_the_glass_and_diffs_small_changes(clock):
    sim = MipiDcsSim("ili9341", 320, 240, clock=clock)
    device = luma_device("ili9341", sim)
    image = picture((320, 240))
    device.display(image)
    assert np.array_equal(np.asarray(sim.glass()), truncated(image))
    sent = sim.stats.data_bytes
    ImageDraw.Draw(image).rectangle((100, 100, 119, 119), fill=(255, 255, 0))
    device.display(image)
    assert np.array_equal(np.asarray(sim.glass()), truncated(image))
    assert sim.stats.data_bytes - sent < 320 * 240 * 3 // 4  # luma's diff_to_previous sent a window, not a frame
    assert [(e.command, "after RESX" in e.message) for e in sim.events] == [(0xEF, True), (0x11, True)]
    # luma sleeps 120 ms after SLPOUT on this model: nothing after it is flagged

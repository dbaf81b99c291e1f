"""Frame pacing on a simulated clock and the bus bandwidth estimator against panels.md §4's worked numbers."""

from __future__ import annotations

import math

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.devices.panels.pacing import FramePacer, bus_limit_fps, check_fps, estimate_bandwidth
from pixelpen.errors import ConfigError


@pytest.mark.parametrize(("kind", "clock_hz", "frame_bytes", "transfers", "ms", "fps"), [
    ("spi", 62.5e6, 115_211, 1, 14.7, 67.8),   # ST7789 240x240 RGB565
    ("spi", 62.5e6, 172_811, 1, 22.1, 45.2),   # ST7789 240x240 RGB666 (luma)
    ("spi", 32e6, 115_211, 1, 28.8, 34.7),
    ("spi", 40e6, 115_211, 1, 23.0, 43.4),
    ("spi", 62.5e6, 153_611, 1, 19.7, 50.9),   # ST7789 240x320
    ("spi", 10e6, 153_611, 1, 122.9, 8.1),     # ILI9341 at the datasheet's 10 MHz
    ("spi", 40e6, 153_611, 1, 30.7, 32.5),
    ("spi", 10e6, 230_411, 1, 184.3, 5.4),     # ILI9341 RGB666 (luma)
    ("i2c", 400e3, 1_032, 2, 23.3, 43.0),      # SSD1306: 0x00 + 6 commands, 0x40 + 1024 bytes
    ("i2c", 100e3, 1_032, 2, 93.1, 10.7),
    ("i2c", 1e6, 1_032, 2, 9.3, 107.4),
])
def test_reference_numbers(kind, clock_hz, frame_bytes, transfers, ms, fps):
    estimate = estimate_bandwidth(kind, clock_hz, frame_bytes, transfers)
    assert estimate.seconds * 1e3 == pytest.approx(ms, abs=0.05)
    assert estimate.max_fps == pytest.approx(fps, abs=0.05)
    assert bus_limit_fps(kind, clock_hz, frame_bytes, transfers) == estimate.max_fps


def test_i2c_transaction_overhead_is_counted():
    # 9 clocks per byte + 11 per transaction: 33 transactions of 32-byte SMBus blocks cost 22 * 11 more clocks.
    assert estimate_bandwidth("i2c", 400e3, 1063, 33).seconds == pytest.approx((1063 * 9 + 33 * 11) / 400e3)
    assert estimate_bandwidth("spi", 1e6, 1000, 50).seconds == pytest.approx(8e-3)  # SPI: bytes only
    assert bus_limit_fps("spi", 1e6, 0) == math.inf


def test_impossible_fps_is_refused_with_the_numbers():
    with pytest.raises(ConfigError) as err:
        check_fps(120, kind="spi", clock_hz=32e6, frame_bytes=115_211, what="ST7789 240x240 RGB565")
    assert str(err.value) == ("requested 120 fps but ST7789 240x240 RGB565 over SPI at 32 MHz can do at most "
                              "34.7 fps (115,211 bytes per frame)")
    with pytest.raises(ConfigError, match=r"over I2C at 400 kHz can do at most 42\.9 fps"):
        check_fps(60, kind="i2c", clock_hz=400e3, frame_bytes=1032, transfers=2)
    assert check_fps(60, kind="spi", clock_hz=62.5e6, frame_bytes=115_211).max_fps > 60


@pytest.mark.parametrize("args", [
    ("usb", 1e6, 10, 1), ("spi", 0, 10, 1), ("spi", math.inf, 10, 1), ("spi", 1e6, -1, 1), ("spi", 1e6, 1.5, 1),
    ("i2c", 1e6, 10, -2),
])
def test_bad_bus_arguments(args):
    with pytest.raises(ConfigError):
        estimate_bandwidth(*args)
    with pytest.raises(ConfigError):
        check_fps(0, kind="spi", clock_hz=1e6, frame_bytes=1)


def test_frames_coalesce_at_the_target_rate():
    clock = SimulatedClock()
    pacer = FramePacer(clock, 50)  # one frame per 20 ms
    assert pacer.frame_due()
    pacer.sent()
    sent = 0
    for _ in range(100):  # the app draws every 4 ms for 400 ms: 100 draws, 20 frames
        clock.advance(0.004)
        if pacer.frame_due():
            pacer.sent()
            sent += 1
    assert sent == 20 and pacer.frames == 21 and pacer.skipped == 0
    assert pacer.achieved_fps == pytest.approx(50, rel=0.01)


def test_late_frames_skip_their_slots():
    clock = SimulatedClock()
    pacer = FramePacer(clock, 10)
    pacer.sent()  # slot 0 at t=0; next due at 0.1
    clock.advance(0.35)  # the frame took long: slots at 0.1, 0.2, 0.3 passed
    assert pacer.frame_due()
    pacer.sent()  # fills the 0.3 slot; 0.1 and 0.2 were skipped; next due at 0.4, not queued behind
    assert pacer.skipped == 2
    assert pacer.seconds_until_due() == pytest.approx(0.05)
    assert not pacer.frame_due()
    pacer.wait()
    assert clock.now() == pytest.approx(0.4) and pacer.frame_due()


def test_unpaced_and_validation():
    clock = SimulatedClock()
    pacer = FramePacer(clock, None)
    for _ in range(3):
        assert pacer.frame_due()
        pacer.sent()
    assert pacer.interval == 0 and pacer.achieved_fps == 0.0  # no time passed
    for bad in (0, -1, math.inf, math.nan, "30"):
        with pytest.raises(ConfigError):
            FramePacer(clock, bad)

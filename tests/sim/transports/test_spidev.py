"""SimSpiWiring: spidev.SpiDev's API and errors, frames with D/C, wire time, TE waits, luma driving it end to end."""

from __future__ import annotations

import errno

import numpy as np
import pytest
import spidev
from hypothesis import given, settings
from hypothesis import strategies as st
from luma.core.interface.serial import spi as luma_spi

from pixelpen.clock import SimulatedClock
from pixelpen.sim.base import BusDevice
from pixelpen.sim.transports.spidev import SimSpiWiring
from tests.sim.transports.chips import RecordingChip


def wired(**kw) -> tuple[RecordingChip, SimSpiWiring]:
    chip = RecordingChip(miso=kw.pop("miso", b""), te=kw.pop("te", lambda t: False))
    return chip, SimSpiWiring(chip, **kw)


def test_the_recording_chip_is_a_bus_device():
    assert isinstance(RecordingChip(), BusDevice)


def test_the_fake_has_every_public_method_and_attribute_of_the_real_spidev_that_it_promises():
    real = {name for name in dir(spidev.SpiDev) if not name.startswith("_")}
    promised = {"open", "open_path", "close", "max_speed_hz", "mode", "bits_per_word", "no_cs",
                "writebytes", "writebytes2", "xfer", "xfer2", "xfer3", "readbytes"}
    assert promised <= real
    _, wiring = wired()
    assert all(hasattr(wiring.spidev, name) for name in promised)


def test_each_call_is_one_frame_with_dc_at_the_lines_level():
    # ST7789 CASET 0..239: command byte with D/C low, four parameter bytes with D/C high
    chip, wiring = wired()
    wiring.dc.set(False)
    wiring.spidev.writebytes([0x2A])
    wiring.dc.set(True)
    wiring.spidev.writebytes2(b"\x00\x00\x00\xef")
    assert chip.frames == [(False, b"\x2a"), (True, b"\x00\x00\x00\xef")]


def test_writebytes_takes_4096_bytes_and_refuses_more_as_spidev_does():
    chip, wiring = wired()
    wiring.spidev.writebytes([0x55] * 4096)
    assert [len(f) for _, f in chip.frames] == [4096]
    with pytest.raises(OverflowError, match="exceeds 4096"):
        wiring.spidev.writebytes([0] * 4097)
    with pytest.raises(TypeError, match="Empty argument list"):
        wiring.spidev.writebytes([])
    with pytest.raises(TypeError, match="Non-Int"):
        wiring.spidev.writebytes([1, "2"])
    wiring.spidev.writebytes([0x1FF])  # spidev truncates to 8 bits
    assert chip.frames[-1] == (False, b"\xff")


@settings(max_examples=60, deadline=None)
@given(length=st.integers(0, 20_000), bufsiz=st.sampled_from([1, 7, 64, 4096, 8192, 65535, 100_000]))
def test_writebytes2_splits_by_bufsiz_keeping_every_byte(length, bufsiz):
    chip, wiring = wired(bufsiz=bufsiz)
    payload = bytes(i * 7 % 256 for i in range(length))
    wiring.spidev.writebytes2(payload)
    block = min(bufsiz, 65535)  # py-spidev caps its block at 65535 whatever bufsiz says
    assert b"".join(f for _, f in chip.frames) == payload
    assert [len(f) for _, f in chip.frames] == [min(block, length - at) for at in range(0, length, block)]


def test_writebytes2_takes_buffers_even_empty_ones_and_xfer3_does_not():
    chip, wiring = wired()
    wiring.spidev.writebytes2(b"")
    wiring.spidev.writebytes2(np.array([0xF800], dtype=">u2"))
    assert chip.frames == [(False, b"\xf8\x00")]
    with pytest.raises(TypeError, match="Empty"):
        wiring.spidev.writebytes2([])
    with pytest.raises(TypeError, match="Empty"):
        wiring.spidev.xfer3(b"")


def test_xfer_returns_miso_and_readbytes_clamps_like_spidev():
    chip, wiring = wired(miso=b"\x12\x34")
    assert wiring.spidev.xfer([0x04, 0, 0, 0]) == [0x12, 0x34, 0x12, 0x34]
    assert wiring.spidev.xfer2([0x09, 0]) == [0x12, 0x34]
    assert len(wiring.spidev.readbytes(0)) == 1 and len(wiring.spidev.readbytes(9999)) == 4096
    assert len(wiring.spidev.xfer3([0] * 9000)) == 9000
    assert [len(f) for _, f in chip.frames][-3:] == [4096, 4096, 808]
    with pytest.raises(OverflowError):
        wiring.spidev.xfer([0] * 4097)


def test_a_closed_spidev_fails_with_ebadf_and_settings_are_checked():
    chip = RecordingChip()
    wiring = SimSpiWiring(chip)
    dev = wiring.spidev
    assert dev.opened == (0, 0)  # the wiring comes connected
    dev.close()
    assert (dev.max_speed_hz, dev.mode, dev.bits_per_word) == (0, 0, 0)  # as a closed spidev.SpiDev
    with pytest.raises(OSError) as caught:
        dev.writebytes2(b"\x00")
    assert caught.value.errno == errno.EBADF
    dev.open(0, 1)
    assert dev.opened == (0, 1) and dev.bits_per_word == 8 and dev.max_speed_hz == 125_000_000
    with pytest.raises(TypeError, match="integer"):
        dev.max_speed_hz = 62.5e6
    with pytest.raises(TypeError):
        dev.mode = 4
    dev.mode = 3
    dev.close()
    assert dev.mode == 0
    with pytest.raises(OSError) as caught:
        dev.xfer([0])
    assert caught.value.errno == errno.EBADF
    assert chip.frames == []


def test_wire_time_is_eight_clocks_per_byte_at_the_set_speed():
    chip, wiring = wired()
    clock = chip.clock
    assert isinstance(clock, SimulatedClock)
    wiring.spidev.max_speed_hz = 32_000_000
    wiring.spidev.writebytes2(bytes(4096 * 3))
    # 12288 bytes * 8 bits / 32e6 Hz = 3.072 ms; the frames start at 0, 1.024 and 2.048 ms
    assert clock.now() == pytest.approx(3.072e-3)
    assert chip.frame_times == pytest.approx([0.0, 1.024e-3, 2.048e-3])
    wiring.spidev.xfer([0] * 1000, 1_000_000)  # a per-call speed overrides max_speed_hz
    assert clock.now() == pytest.approx(3.072e-3 + 8e-3)


def test_reset_and_other_lines_reach_the_chip_and_dc_does_not():
    chip, wiring = wired()
    wiring.reset.set(False)
    chip.clock.sleep(1e-5)
    wiring.reset.set(True)
    wiring.output_line("backlight").set(True)
    wiring.dc.set(True)
    assert chip.line_changes == [("reset", False, 0.0), ("reset", True, 1e-5), ("backlight", True, 1e-5)]
    assert wiring.dc.level is True and wiring.dc.writes == 1


def vblank(t: float) -> bool:
    """TE high for the first 1 ms of each 1/60 s frame."""
    return (t * 60) % 1 < 0.06


def test_te_waits_for_the_next_rising_edge_on_the_clock():
    chip, wiring = wired(te=vblank)
    chip.clock.sleep(0.0001)  # inside the first V-blank: TE already high, so the next rising edge is at 1/60 s
    assert wiring.te.get()
    assert wiring.te.wait_edge(True, 0.1)
    assert chip.clock.now() == pytest.approx(1 / 60, abs=25e-6)
    assert wiring.te.wait_edge(False, 0.1)
    assert chip.clock.now() == pytest.approx(1 / 60 + 0.001, abs=25e-6)
    before = chip.clock.now()
    assert not wiring.te.wait_edge(True, 0.005)
    assert chip.clock.now() == pytest.approx(before + 0.005)


def test_the_gpio_shim_behaves_like_rpi_gpio():
    chip, wiring = wired(te=vblank, pins={24: "dc", 25: "reset", 23: "te", 18: "backlight"})
    gpio = wiring.gpio_module
    gpio.setmode(gpio.BCM)
    gpio.setwarnings(False)
    gpio.setup([24, 25, 18], gpio.OUT)
    gpio.setup(23, gpio.IN)
    gpio.setup(5, gpio.OUT, initial=gpio.HIGH)  # not wired: remembered only
    gpio.output(18, gpio.HIGH)
    gpio.output([24, 25], [gpio.HIGH, gpio.LOW])
    assert (wiring.dc.level, wiring.reset.level) == (True, False)
    assert chip.line_changes[-2:] == [("backlight", True, 0.0), ("reset", False, 0.0)]
    assert gpio.input(5) == gpio.HIGH and gpio.input(23) == gpio.HIGH
    assert gpio.wait_for_edge(23, gpio.RISING, timeout=100) == 23
    assert gpio.wait_for_edge(23, gpio.RISING, timeout=1) is None
    with pytest.raises(ValueError, match="not been set up as an OUTPUT"):
        gpio.output(23, gpio.HIGH)
    gpio.cleanup()
    with pytest.raises(ValueError, match="not been set up"):
        gpio.input(23)


def test_luma_spi_drives_the_wiring():
    # luma.core's spi(): reset pulse on RST at construction, D/C low for command(), data() in 4096-byte writebytes
    chip = RecordingChip()
    wiring = SimSpiWiring(chip)
    serial = luma_spi(spi=wiring.spidev, gpio=wiring.gpio_module, port=0, device=0, gpio_DC=24, gpio_RST=25,
                      bus_speed_hz=32_000_000)
    assert [(name, level) for name, level, _ in chip.line_changes] == [("reset", False), ("reset", True)]
    assert wiring.spidev.max_speed_hz == 32_000_000 and wiring.spidev.opened == (0, 0)
    serial.command(0x2A, 0x00, 0x00, 0x00, 0xEF)
    serial.data(list(range(256)) * 20)
    assert chip.frames[0] == (False, b"\x2a\x00\x00\x00\xef")
    assert [(dc, len(f)) for dc, f in chip.frames[1:]] == [(True, 4096), (True, 1024)]
    assert chip.data_bytes() == bytes(range(256)) * 20
    serial.cleanup()
    with pytest.raises(OSError):
        wiring.spidev.writebytes([0])


@pytest.mark.filterwarnings("ignore:Image.Image.getdata is deprecated:DeprecationWarning")
def test_luma_oled_ssd1306_over_spi_sends_its_init_as_one_command_frame():
    from luma.oled.device import ssd1306

    chip = RecordingChip()
    wiring = SimSpiWiring(chip)
    serial = luma_spi(spi=wiring.spidev, gpio=wiring.gpio_module, gpio_DC=24, gpio_RST=25)
    ssd1306(serial).persist = True  # no blanking at interpreter exit
    dc, first = chip.frames[0]
    # SSD1306 datasheet: AE display off, D5 80 clock divide, A8 3F multiplex 64
    assert not dc and first[:5] == b"\xae\xd5\x80\xa8\x3f"
    # then a whole frame: 21 00 7F column window, 22 00 07 page window, 1024 data bytes of zeros
    assert (False, b"\x21\x00\x7f\x22\x00\x07") in chip.frames
    assert chip.data_bytes() == bytes(1024)


def test_luma_gpio_cs_spi_toggles_its_own_chip_select_pin():
    from luma.core.interface.serial import gpio_cs_spi

    chip = RecordingChip()
    wiring = SimSpiWiring(chip)
    serial = gpio_cs_spi(spi=wiring.spidev, gpio=wiring.gpio_module, gpio_DC=24, gpio_RST=25, gpio_CS=8)
    assert wiring.spidev.no_cs and wiring.gpio_module.levels[8] == wiring.gpio_module.HIGH  # idle: deselected
    serial.command(0x29)
    assert chip.frames == [(False, b"\x29")] and wiring.gpio_module.levels[8] == wiring.gpio_module.HIGH


def test_luma_lcd_st7789_full_frame_through_the_wiring():
    from luma.lcd.device import st7789
    from PIL import Image

    chip = RecordingChip()
    wiring = SimSpiWiring(chip, pins={24: "dc", 25: "reset", 18: "backlight"})
    serial = luma_spi(spi=wiring.spidev, gpio=wiring.gpio_module, gpio_DC=24, gpio_RST=25, bus_speed_hz=52_000_000)
    device = st7789(serial, gpio=wiring.gpio_module, gpio_LIGHT=18)
    device.persist = True  # no atexit blanking
    assert ("backlight", True) in [(name, level) for name, level, _ in chip.line_changes]
    chip.frames.clear()
    device.display(Image.new("RGB", (240, 240), "red"))
    # ST7789 CASET/RASET: command byte with D/C low, XS and XE as big-endian 16-bit with D/C high; then RAMWR
    assert chip.frames[:5] == [(False, b"\x2a"), (True, b"\x00\x00\x00\xef"), (False, b"\x2b"),
                               (True, b"\x00\x00\x00\xef"), (False, b"\x2c")]
    pixels = chip.frames[5:]
    assert all(dc for dc, _ in pixels) and max(len(f) for _, f in pixels) == 4096
    assert b"".join(f for _, f in pixels) == b"\xff\x00\x00" * 240 * 240  # luma sends 18-bit RGB as 3 bytes


OPS = st.tuples(st.sampled_from(["writebytes", "writebytes2", "xfer", "xfer2", "xfer3", "close", "open"]),
                st.integers(0, 9000))


@settings(max_examples=200, deadline=None)
@given(ops=st.lists(OPS, max_size=12), seed=st.integers(0, 2**16))
def test_any_call_sequence_gives_spidevs_errors_or_frames_carrying_every_byte(ops, seed):
    chip, wiring = wired()
    dev, opened, expected = wiring.spidev, True, b""
    for name, length in ops:
        if name in ("close", "open"):
            dev.close() if name == "close" else dev.open(0, 0)
            opened = name == "open"
            continue
        payload = bytes((seed + i * 13) % 256 for i in range(length))
        small = name in ("writebytes", "xfer", "xfer2")
        try:
            getattr(dev, name)(list(payload))  # a list: every call refuses an empty one, as spidev's do
        except OverflowError:
            assert small and length > 4096
        except TypeError:
            assert length == 0
        except OSError as e:
            assert e.errno == errno.EBADF and not opened
        else:
            assert opened and length > 0 and (length <= 4096 or not small)
            expected += payload
    assert b"".join(frame for _, frame in chip.frames) == expected
    assert all(len(frame) <= 4096 for _, frame in chip.frames)

"""SpiBus: D/C and chip-select framing of datasheet commands, chunking, counters, reset timing, errors, and open()."""

from __future__ import annotations

import errno
import sys
import types
from typing import ClassVar

import numpy as np
import pytest
import spidev
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.clock import SimulatedClock
from pixelpen.drivers import spi as spi_module
from pixelpen.drivers.bus import PanelBus
from pixelpen.drivers.spi import SpiBus, spidev_bufsiz
from pixelpen.errors import ConfigError, InvalidArgument, InvalidArgumentType, LinkError
from pixelpen.sim.transports.spidev import SimSpiWiring
from tests.sim.transports.chips import RecordingChip


def wired(**kw) -> tuple[RecordingChip, SimSpiWiring, SpiBus]:
    chip = RecordingChip()
    wiring = SimSpiWiring(chip, bufsiz=65535)  # spidev itself would split frames longer than its bufsiz
    bus = SpiBus(wiring.spidev, dc=wiring.dc, reset=kw.pop("reset", wiring.reset), clock=chip.clock,
                 clock_hz=kw.pop("clock_hz", 62.5e6), **kw)
    return chip, wiring, bus


def test_spibus_is_a_panel_bus_with_its_settings_applied():
    _, wiring, bus = wired(mode=3, max_transfer=4096)
    assert isinstance(bus, PanelBus)
    assert (bus.kind, bus.clock_hz, bus.max_transfer) == ("spi", 62.5e6, 4096)
    assert wiring.spidev.max_speed_hz == 62_500_000 and wiring.spidev.mode == 3  # spidev wants an int


def test_st7789_caset_is_a_command_frame_then_a_data_frame():
    # ST7789V datasheet 9.1.20 CASET: 2Ah with D/C low, then XS[15:8] XS[7:0] XE[15:8] XE[7:0] with D/C high
    chip, _, bus = wired()
    bus.command(0x2A)
    bus.data(b"\x00\x00\x00\xef")
    assert chip.frames == [(False, b"\x2a"), (True, b"\x00\x00\x00\xef")]
    assert (bus.bytes_sent, bus.transfers) == (5, 2)


def test_ssd1306_parameters_go_with_dc_low_in_one_frame():
    # SSD1306 4-wire SPI: AE (display off), D5 80 (clock), A8 3F (multiplex): all command bytes, D/C low
    chip, _, bus = wired()
    bus.command(0xAE, 0xD5, 0x80, b"\xa8\x3f")
    assert chip.frames == [(False, b"\xae\xd5\x80\xa8\x3f")]


def test_dc_is_written_only_when_it_changes():
    _, wiring, bus = wired()
    bus.command(0x2A)
    bus.command(0x2B)
    bus.data(b"\x00" * 10)
    bus.data(b"\x00" * 10_000)
    bus.command(0x2C)
    assert wiring.dc.writes == 3


@settings(max_examples=80, deadline=None)
@given(length=st.integers(0, 20_000), max_transfer=st.integers(1, 9000))
def test_data_chunks_preserve_the_bytes_and_respect_the_limit(length, max_transfer):
    chip, _, bus = wired(max_transfer=max_transfer)
    payload = np.random.default_rng(length).integers(0, 256, length, dtype=np.uint8).tobytes()
    bus.data(payload)
    sizes = [len(frame) for _, frame in chip.frames]
    assert all(dc for dc, _ in chip.frames)
    assert b"".join(frame for _, frame in chip.frames) == payload
    assert all(0 < n <= max_transfer for n in sizes)
    assert len(sizes) == -(-length // max_transfer)
    assert (bus.bytes_sent, bus.transfers) == (length, len(sizes))


def test_data_takes_any_contiguous_buffer():
    chip, _, bus = wired()
    bus.data(np.array([0xF800, 0x001F], dtype=">u2"))  # RGB565 big-endian: red, blue
    bus.data(bytearray(b"\x01"))
    bus.data(memoryview(b"\x02\x03"))
    assert chip.data_bytes() == b"\xf8\x00\x00\x1f\x01\x02\x03"


def test_reset_pulses_the_line_and_waits_the_recovery_on_the_clock():
    chip, _, bus = wired()
    bus.reset(recovery=0.005)
    assert chip.line_changes == [("reset", False, 0.0), ("reset", True, pytest.approx(10e-6))]
    assert chip.clock.now() == pytest.approx(10e-6 + 0.005)
    bus.reset()
    assert chip.clock.now() == pytest.approx(2 * 10e-6 + 0.005 + 0.120)


def test_without_a_reset_line_reset_does_nothing():
    chip, _, bus = wired(reset=None)
    bus.reset()
    assert chip.line_changes == [] and chip.clock.now() == 0.0


def test_the_default_transfer_size_is_spidevs_bufsiz(tmp_path, monkeypatch):
    path = tmp_path / "bufsiz"
    assert spidev_bufsiz(path) == 4096  # unreadable
    for text, expected in (("8192\n", 8192), ("65536\n", 65535), ("0\n", 4096), ("lots\n", 4096)):
        path.write_text(text)
        assert spidev_bufsiz(path) == expected
    path.write_text("1024\n")
    monkeypatch.setattr(spi_module, "BUFSIZ_PATH", path)
    _, _, bus = wired()
    assert bus.max_transfer == 1024


def test_bad_commands_and_settings_are_refused():
    _, _, bus = wired(max_transfer=4)
    with pytest.raises(InvalidArgument, match=r"outside 0\.\.255"):
        bus.command(0x100)
    with pytest.raises(InvalidArgumentType):
        bus.command("2A")
    with pytest.raises(InvalidArgument, match="at least one byte"):
        bus.command()
    with pytest.raises(InvalidArgument, match="do not fit in one transfer"):
        bus.command(1, 2, 3, 4, 5)
    chip = RecordingChip()
    wiring = SimSpiWiring(chip)
    with pytest.raises(ConfigError, match="mode"):
        SpiBus(wiring.spidev, dc=wiring.dc, clock_hz=1e6, mode=4)
    with pytest.raises(ConfigError, match="clock"):
        SpiBus(wiring.spidev, dc=wiring.dc, clock_hz=0)


class FailingSpi:
    """A spidev whose writes fail with EIO."""

    max_speed_hz = 0
    mode = 0

    def writebytes2(self, data):
        raise OSError(errno.EIO, "Input/output error")

    def close(self):
        pass


def test_os_errors_are_link_errors_naming_bus_and_operation():
    chip = RecordingChip()
    wiring = SimSpiWiring(chip)
    bus = SpiBus(FailingSpi(), dc=wiring.dc, clock_hz=1e6, max_transfer=4096, name="spi 0.0")
    with pytest.raises(LinkError, match=r"spi 0\.0: write of 4096 bytes failed: \[Errno 5\]"):
        bus.data(bytes(10_000))
    assert (bus.bytes_sent, bus.transfers) == (0, 0)
    closed = SimSpiWiring(chip).spidev
    closed.close()
    with pytest.raises(LinkError, match="setting mode"):
        SpiBus(closed, dc=wiring.dc, clock_hz=1e6)  # a closed spidev: EBADF


def test_a_closed_bus_refuses_and_close_releases_everything_once():
    _, wiring, bus = wired()
    bus.close()
    bus.close()
    assert bus.closed
    for call in (lambda: bus.command(0x29), lambda: bus.data(b"\x00"), lambda: bus.data(b""), bus.reset):
        with pytest.raises(LinkError, match="closed"):
            call()
    with pytest.raises(OSError):
        wiring.spidev.writebytes([0])  # spidev was closed


class FakeSpiDev:
    """spidev.SpiDev stand-in that only answers names the installed spidev.SpiDev has."""

    instances: ClassVar[list[FakeSpiDev]] = []
    open_error: ClassVar[OSError | None] = None

    def __init__(self):
        object.__setattr__(self, "log", [])
        FakeSpiDev.instances.append(self)

    def __setattr__(self, name, value):
        assert name in dir(spidev.SpiDev), name
        self.log.append(("set", name, value))
        object.__setattr__(self, name, value)

    def __getattr__(self, name):
        assert name in dir(spidev.SpiDev), name

        def call(*args):
            self.log.append((name, *args))
            if name == "open" and FakeSpiDev.open_error is not None:
                raise FakeSpiDev.open_error

        return call


@pytest.fixture
def fake_modules(monkeypatch):
    import gpiod

    FakeSpiDev.instances, FakeSpiDev.open_error = [], None
    monkeypatch.setitem(sys.modules, "spidev", types.SimpleNamespace(SpiDev=FakeSpiDev))
    requested = []
    fake_gpiod = types.SimpleNamespace(line=gpiod.line, LineSettings=gpiod.LineSettings, EdgeEvent=gpiod.EdgeEvent,
                                       error=None)

    class Request:
        def set_value(self, line, value):
            requested.append(("set", line, value))

        def release(self):
            requested.append(("release",))

    def request_lines(path, config, consumer=None, event_buffer_size=None, output_values=None):
        if fake_gpiod.error is not None:
            raise fake_gpiod.error
        requested.append((path, config, consumer))
        return Request()

    fake_gpiod.request_lines = request_lines
    monkeypatch.setitem(sys.modules, "gpiod", fake_gpiod)
    return fake_gpiod, requested


def test_open_uses_the_spidev_api_and_gpio_lines(fake_modules):
    import gpiod

    _, requested = fake_modules
    bus = SpiBus.open(0, 1, dc=25, rst=27, clock_hz=62.5e6, gpiochip="/dev/gpiochip4", max_transfer=4096)
    (dev,) = FakeSpiDev.instances
    assert dev.log == [("open", 0, 1), ("set", "mode", 0), ("set", "max_speed_hz", 62_500_000)]
    assert [(path, list(config)) for path, config, _ in requested] == [
        ("/dev/gpiochip4", [25]), ("/dev/gpiochip4", [27])
    ]
    assert requested[0][1][25].output_value == gpiod.line.Value.INACTIVE  # D/C starts low
    assert requested[1][1][27].output_value == gpiod.line.Value.ACTIVE  # reset released
    assert bus.name == "spi 0.1"
    bus.data(b"\x01\x02")
    assert dev.log[-1] == ("writebytes2", memoryview(b"\x01\x02"))
    bus.close()
    assert dev.log[-1] == ("close",) and requested[-2:] == [("release",), ("release",)]


@pytest.mark.parametrize(
    ("error", "words"),
    [
        (FileNotFoundError(errno.ENOENT, "No such file"), ["/dev/spidev0.0 does not exist", "dtparam=spi=on"]),
        (PermissionError(errno.EACCES, "Permission denied"), ["permission denied on /dev/spidev0.0", "'spi' group"]),
        (OSError(errno.EBUSY, "busy"), ["/dev/spidev0.0: cannot open"]),
    ],
)
def test_open_failures_say_which_node_and_what_to_do(fake_modules, error, words):
    FakeSpiDev.open_error = error
    with pytest.raises(LinkError) as caught:
        SpiBus.open(0, 0, dc=25, clock_hz=1e6)
    assert all(word in str(caught.value) for word in words), str(caught.value)


def test_open_closes_spidev_when_a_gpio_line_cannot_be_had(fake_modules):
    fake_gpiod, _ = fake_modules
    fake_gpiod.error = PermissionError(errno.EACCES, "Permission denied")
    with pytest.raises(LinkError, match="gpiochip0"):
        SpiBus.open(0, 0, dc=25, clock_hz=1e6)
    assert FakeSpiDev.instances[0].log[-1] == ("close",)


def test_open_with_the_real_spidev_names_the_missing_node():
    with pytest.raises(LinkError, match=r"/dev/spidev99\.0 does not exist"):
        SpiBus.open(99, 0, dc=25, clock_hz=1e6)


def test_open_without_spidev_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "spidev", None)
    with pytest.raises(ConfigError, match="pip install spidev"):
        SpiBus.open(0, 0, dc=25, clock_hz=1e6)


def test_a_simulated_frame_takes_its_wire_time():
    # 240x240 RGB565 = 115,200 bytes at 62.5 MHz: 115200 * 8 / 62.5e6 = 14.7456 ms
    chip, _, bus = wired()
    assert isinstance(chip.clock, SimulatedClock)
    bus.data(bytes(115_200))
    assert chip.clock.now() == pytest.approx(14.7456e-3)


def test_end_to_end_an_st7789_simulator_shows_what_the_bus_sent():
    from pixelpen.sim.panels import MipiDcsSim

    clock = SimulatedClock()
    sim = MipiDcsSim("st7789", 240, 240, clock=clock, clock_hz=62.5e6)
    wiring = SimSpiWiring(sim)
    bus = SpiBus(wiring.spidev, dc=wiring.dc, reset=wiring.reset, clock_hz=62.5e6, clock=clock)
    # ST7789VW datasheet: RESX low >= 10 us, 120 ms to sleep-out; SLPOUT then 120 ms; COLMOD 55h = 16 bit/pixel;
    # MADCTL 00h; INVON (an IPS module); CASET 0..239, RASET 0..319 (the whole 240x320 memory); RAMWR; DISPON
    bus.reset(recovery=0.120)
    bus.command(0x11)
    clock.sleep(0.120)
    for code, params in ((0x3A, b"\x55"), (0x36, b"\x00"), (0x21, b""), (0x2A, b"\x00\x00\x00\xef"),
                         (0x2B, b"\x00\x00\x01\x3f")):
        bus.command(code)
        bus.data(params)
    bus.command(0x2C)
    start = clock.now()
    bus.data((b"\x00\x1f" * 120 + b"\xf8\x00" * 120) * 320)
    assert clock.now() - start == pytest.approx(240 * 320 * 2 * 8 / 62.5e6)  # 19.66 ms on the wire
    bus.command(0x29)
    assert sim.events == []  # nothing too soon after reset or SLPOUT, no truncated parameters
    glass = np.asarray(sim.glass())
    assert glass.shape == (240, 240, 3)
    blue = np.all(glass == (0, 0, 255), axis=2)
    red = np.all(glass == (255, 0, 0), axis=2)
    # RAM columns 0..119 blue (RGB565 001Fh), 120..239 red (F800h): half the glass each, in whole columns
    assert blue.sum() == red.sum() == 120 * 240
    assert np.all(blue.all(axis=0) | red.all(axis=0))
    assert (sim.stats.bytes, sim.stats.transfers) == (bus.bytes_sent, bus.transfers)


def test_a_failing_spidev_close_still_releases_the_lines_and_is_a_link_error():
    released = []

    class Spi(FailingSpi):
        def close(self):
            raise OSError(errno.EIO, "Input/output error")

    class Line:
        def __init__(self, name):
            self.name = name

        def set(self, level):
            pass

        def close(self):
            released.append(self.name)

    bus = SpiBus(Spi(), dc=Line("dc"), reset=Line("reset"), clock_hz=1e6, max_transfer=4096, name="spi 0.0")
    with pytest.raises(LinkError, match=r"spi 0\.0: closing failed: \[Errno 5\]"):
        bus.close()
    assert released == ["dc", "reset"] and bus.closed
    bus.close()
    assert released == ["dc", "reset"]

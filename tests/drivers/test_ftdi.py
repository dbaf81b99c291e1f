"""FtdiSpiBus through pyftdi and the simulated FT232H: the frames, D/C levels and MPSSE commands on the wire."""

from __future__ import annotations

import io
import sys

import numpy as np
import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.drivers.bus import PanelBus
from pixelpen.drivers.bustrace import RecordingBus, ReplayBus, read_bus_trace
from pixelpen.drivers.ftdi import FtdiSpiBus
from pixelpen.errors import ConfigError, InvalidArgument, LinkError
from pixelpen.sim.transports.ftdi import Ft232hBackend, use_for_urls
from tests.sim.transports.test_mcp2221 import StubBusDevice


@pytest.fixture
def wired():
    device = StubBusDevice(SimulatedClock())
    backend = Ft232hBackend(device)
    bus = FtdiSpiBus.open(backend.find(), dc=4, rst=5, clock_hz=30e6, clock=device.clock)
    yield bus, backend, device
    bus.close()


def test_the_bytes_and_dc_levels_reach_the_device(wired):
    bus, _, device = wired
    assert isinstance(bus, PanelBus) and bus.kind == "spi" and bus.clock_hz == 30e6
    bus.command(0x2A)
    bus.data(b"\x00\x00\x00\xef")
    bus.command(0x2C)
    pixels = bytes(i % 253 for i in range(100_000))
    bus.data(pixels)
    assert device.frames[:3] == [(b"\x2a", False), (b"\x00\x00\x00\xef", True), (b"\x2c", False)]
    assert [len(f) for f, _ in device.frames[3:]] == [0xFF00, 100_000 - 0xFF00]
    assert b"".join(f for f, _ in device.frames[3:]) == pixels and all(dc for _, dc in device.frames[3:])
    assert bus.bytes_sent == 1 + 4 + 1 + 100_000 and bus.transfers == 5


def test_pyftdi_sets_the_chip_up_as_an_108_says(wired):
    _, backend, _ = wired
    out_requests = [(req, value) for kind, req, value, index in backend.control if kind == 0x40]
    assert (0x00, 0) in out_requests  # reset the port
    assert (0x0B, 0x0200 | 0x0B) in out_requests  # bit mode MPSSE with SCK, MOSI and CS0 as outputs
    assert (0x09, 16) in out_requests or (0x09, 1) in out_requests  # latency timer
    assert {(0x06, 0), (0x07, 0)} <= set(out_requests)  # event and error characters off
    assert all(index == 1 for _, _, _, index in backend.control)  # port A
    ops = backend.commands
    assert 0x8A in ops and 0x86 in ops and 0x85 in ops  # 60 MHz base, divisor, loopback off
    assert backend.divisor == 0 and not backend.divide_by_5  # 60 MHz / 2 = 30 MHz
    assert backend.direction & 0x3B == 0x3B  # GPIO 4 (D/C) and 5 (reset) became outputs


def test_a_spi_write_is_cs_low_0x11_cs_high(wired):
    bus, backend, _ = wired
    del backend.commands[:]
    bus.data(b"\x01\x02\x03")
    # D/C change: read-modify-write of the GPIO (0x81, 0x87 then 0x80), then the framed write
    assert backend.commands[:3] == [0x81, 0x87, 0x80]
    write_at = backend.commands.index(0x11)
    assert 0x80 in backend.commands[3:write_at] and backend.commands[write_at + 1] == 0x80
    del backend.commands[:]
    bus.data(b"\x04")
    assert 0x81 not in backend.commands  # D/C already high: no GPIO traffic


def test_an_empty_command_is_refused_and_empty_data_sends_nothing(wired):
    bus, backend, device = wired
    del backend.commands[:]
    with pytest.raises(InvalidArgument, match="ftdi: command\\(\\) needs at least one byte"):
        bus.command()
    with pytest.raises(InvalidArgument, match="command byte 1 is 256"):
        bus.command(0x2A, 0x100)
    bus.data(b"")
    assert device.frames == [] and list(backend.commands) == [] and (bus.bytes_sent, bus.transfers) == (0, 0)


def test_any_contiguous_buffer_is_sent_as_its_bytes(wired):
    bus, _, device = wired
    bus.data(np.array([0xF800, 0x07E0], dtype=">u2"))  # RGB565 red, green, big-endian as the panel takes them
    bus.data(bytearray(b"\x01"))
    bus.data(memoryview(b"\x02\x03"))
    assert device.frames == [(b"\xf8\x00\x07\xe0", True), (b"\x01", True), (b"\x02\x03", True)]


def test_reset_pulses_the_reset_pin(wired):
    bus, _, device = wired
    t0 = device.clock.now()
    bus.reset()
    assert device.lines[-2:] == [("reset", False), ("reset", True)]
    assert device.clock.now() - t0 >= 0.120 + 10e-6
    bus.close()
    with pytest.raises(LinkError, match="ftdi: the bus is closed"):
        bus.reset()


def test_options_are_checked():
    with pytest.raises(ConfigError, match="30 MHz"):
        FtdiSpiBus.open("ftdi://ftdi:232h/1", clock_hz=40e6)
    with pytest.raises(ConfigError, match=r"1\.\.65280"):
        FtdiSpiBus.open("ftdi://ftdi:232h/1", max_transfer=70_000)
    with pytest.raises(ConfigError, match="dc=3 is not a free GPIO pin"):
        FtdiSpiBus.open("ftdi://ftdi:232h/1", dc=3)
    with pytest.raises(ConfigError, match=r"rst=4 is not a free GPIO pin: use 5\.\.15"):
        FtdiSpiBus.open("ftdi://ftdi:232h/1", cs=1, dc=6, rst=4)  # CS1 is ADBUS4
    with pytest.raises(ConfigError, match="both GPIO 6"):
        FtdiSpiBus.open("ftdi://ftdi:232h/1", dc=6, rst=6)


def test_faults_become_link_errors(wired):
    bus, backend, _ = wired
    backend.close()  # unplugged
    with pytest.raises(LinkError, match="ftdi: SPI write of 2 bytes failed"):
        bus.command(0x01, 0x02)
    assert (bus.bytes_sent, bus.transfers) == (0, 0)  # nothing reached the wire
    bus.close()
    bus.close()
    with pytest.raises(LinkError, match="closed"):
        bus.data(b"\x00")


class FailingController:
    """Just what FtdiSpiBus calls on pyftdi's SpiController, with a close that fails as a vanished device's does."""

    def __init__(self) -> None:
        self.written: list[bytes] = []
        self.closes = 0

    def get_port(self, cs, freq, mode):
        return type("Port", (), {"frequency": freq, "write": lambda _, data: self.written.append(data)})()

    def get_gpio(self):
        return type("Gpio", (), {"set_direction": lambda *_: None, "write": lambda *_: None})()

    def close(self, freeze=False):
        self.closes += 1
        raise OSError(19, "No such device")


def test_a_failing_close_is_a_link_error_and_the_bus_is_closed_all_the_same():
    controller = FailingController()
    bus = FtdiSpiBus(controller, clock_hz=10e6)
    bus.command(0x29)
    assert controller.written == [b"\x29"] and bus.clock_hz == 10e6
    with pytest.raises(LinkError, match=r"ftdi: closing failed: \[Errno 19\] No such device"):
        bus.close()
    assert bus.closed
    bus.close()  # once closed, closing again does nothing
    assert controller.closes == 1
    with pytest.raises(LinkError, match="closed"):
        bus.command(0x29)


def test_a_failing_setup_releases_the_device(monkeypatch):
    from pyftdi.spi import SpiController, SpiIOError

    def no_gpio(self):
        raise SpiIOError("GPIO port unavailable")

    device = StubBusDevice(SimulatedClock())
    backend = Ft232hBackend(device)
    monkeypatch.setattr(SpiController, "get_gpio", no_gpio)
    with pytest.raises(LinkError, match=r"ftdi: setting up SPI \(cs 0, 3e\+07 Hz, mode 0\) and GPIO failed: GPIO port"):
        FtdiSpiBus.open(backend.find(), clock=device.clock)
    assert backend.control[-2][:3] == (0x40, 0x0B, 0x0000)  # bit mode reset (AN_108): the chip is handed back


def test_closing_leaves_the_pins_driven_so_the_panel_keeps_its_picture(wired):
    bus, backend, _ = wired
    bus.data(b"\x01")
    bus.close()
    assert backend.bitmode == 0x02  # still MPSSE: no bit mode reset was sent
    assert backend.pins & 0x38 == 0x38 and backend.direction & 0x3B == 0x3B  # CS, D/C and reset still driven high


def test_without_pyftdi_the_error_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "pyftdi.spi", None)  # import fails as if the package were missing
    with pytest.raises(ConfigError, match=r"FT232H panels need pyftdi: pip install pyftdi"):
        FtdiSpiBus.open("ftdi://ftdi:232h/1")


def test_a_url_finds_the_simulated_chip():
    device = StubBusDevice(SimulatedClock())
    backend = Ft232hBackend(device)
    with use_for_urls(backend):
        bus = FtdiSpiBus.open("ftdi://ftdi:232h/1", dc=8, rst=None, clock_hz=10e6, clock=device.clock)
        bus.command(0x11)
        bus.reset()  # no reset pin: nothing
        bus.close()
    assert device.frames == [(b"\x11", False)]
    assert device.lines == []
    with pytest.raises(LinkError, match="cannot open the FTDI device"):
        FtdiSpiBus.open("ftdi://ftdi:232h/9")


def test_a_recorded_ftdi_session_replays(wired):
    bus, _, _ = wired
    out = io.StringIO()
    recording = RecordingBus(bus, out, url="ili9341:ftdi://ftdi:232h/1?dc=4&rst=5")
    recording.command(0x36, b"\x48")
    recording.data(bytes(70_000))
    recording.close()
    trace = read_bus_trace(io.StringIO(out.getvalue()))
    assert (trace.bus, trace.clock_hz, trace.max_transfer) == ("spi", 30e6, 0xFF00)
    replay = ReplayBus(trace)
    replay.command(0x36, 0x48)
    replay.data(bytes(70_000))
    replay.check_complete()


def st7789_session(bus, clock) -> None:
    """Reset, SWRESET, SLPOUT, COLMOD 16-bit, a window and a frame of two colour bands, DISPON (datasheet order)."""
    bus.reset()
    bus.command(0x01)
    clock.sleep(0.150)
    bus.command(0x11)
    clock.sleep(0.120)
    bus.command(0x3A)
    bus.data(b"\x55")
    bus.command(0x36)
    bus.data(b"\x00")
    bus.command(0x21)
    bus.command(0x2A)
    bus.data(b"\x00\x00\x00\xef")
    bus.command(0x2B)
    bus.data(b"\x00\x00\x00\xef")
    bus.command(0x2C)
    bus.data(b"\xf8\x00" * 240 * 100 + b"\x07\xe0" * 240 * 140)
    bus.command(0x29)


class DirectBus:
    """The oracle: the same session sent straight to a simulator's command()/data()/reset()."""

    def __init__(self, sim) -> None:
        self.sim = sim

    def reset(self) -> None:
        self.sim.reset()
        self.sim.clock.sleep(0.120)

    def command(self, code: int) -> None:
        self.sim.command(bytes((code,)))

    def data(self, data: bytes) -> None:
        self.sim.data(data)


def test_an_st7789_simulator_behind_the_ft232h_shows_what_it_shows_when_driven_directly():
    panels = pytest.importorskip("pixelpen.sim.panels")
    through = panels.MipiDcsSim("st7789", 240, 240, clock=SimulatedClock(), clock_hz=30e6)
    backend = Ft232hBackend(through)
    bus = FtdiSpiBus.open(backend.find(), dc=4, rst=5, clock_hz=30e6, clock=through.clock)
    st7789_session(bus, through.clock)
    direct = panels.MipiDcsSim("st7789", 240, 240, clock=SimulatedClock(), clock_hz=30e6)
    st7789_session(DirectBus(direct), direct.clock)
    assert np.array_equal(np.asarray(through.glass()), np.asarray(direct.glass()))
    glass = np.asarray(through.glass()).reshape(-1, 3)
    colours, counts = np.unique(glass, axis=0, return_counts=True)
    assert {tuple(c): n for c, n in zip(colours.tolist(), counts.tolist(), strict=True)} == {
        (255, 0, 0): 240 * 100, (0, 255, 0): 240 * 140}  # every pixel arrived, whichever way the glass is held
    assert not through.events

"""Panel URL targets and wiring: the target grammar, refused targets, hardware that is absent, sim wiring."""

from __future__ import annotations

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.devices.panels.wiring import Pins, Target, Wiring, open_wiring, parse_target, sim_wiring
from pixelpen.errors import ConfigError, LinkError, URLError
from tests.devices.panels.test_base import StubBus
from tests.sim.transports.chips import RecordingChip


@pytest.mark.parametrize(("text", "target"), [
    ("spi:0.0", Target("spi", 0, 0)),
    ("spi:1.2", Target("spi", 1, 2)),
    ("i2c:1", Target("i2c", 1)),
    ("I2C:10", Target("i2c", 10)),
    ("ftdi://ftdi:232h/1", Target("ftdi", where="ftdi://ftdi:232h/1")),
    ("mcp2221:", Target("mcp2221", where="")),
    ("mcp2221:0001234", Target("mcp2221", where="0001234")),
])
def test_targets(text: str, target: Target) -> None:
    assert parse_target(text, "url") == target


@pytest.mark.parametrize("text", ["", "spi:0", "spi:a.b", "spi:0.0.0", "i2c:", "i2c:x", "ftdi:232h", "usb:1",
                                  "/dev/fb0", "spi:-1.0", "i2c:１"])
def test_bad_targets_name_the_grammar(text: str) -> None:
    with pytest.raises(URLError, match=r"url: panel target .* spi:BUS\.DEVICE"):
        parse_target(text, "url")


def test_interfaces() -> None:
    assert parse_target("ftdi://ftdi:232h/1", "u").interface == "spi"
    assert parse_target("mcp2221:", "u").interface == "i2c"


def test_spi_without_dc_is_refused_before_anything_opens() -> None:
    with pytest.raises(ConfigError, match="needs its D/C line: add dc=N"):
        open_wiring(Target("spi", 0, 0), Pins(), clock=SimulatedClock(), where="st7789:spi:0.0")


def test_absent_spidev_is_a_link_error_naming_the_node() -> None:
    with pytest.raises((LinkError, ConfigError), match=r"spidev9\.9|spidev"):
        open_wiring(Target("spi", 9, 9), Pins(dc=25), clock=SimulatedClock(), where="u")


def test_absent_i2c_adapter_is_a_link_error_naming_the_node() -> None:
    with pytest.raises((LinkError, ConfigError), match=r"i2c-99"):
        open_wiring(Target("i2c", 99), Pins(), clock=SimulatedClock(), where="u")


def test_wiring_close_releases_everything_once_and_sets_the_backlight() -> None:
    class Line:
        def __init__(self) -> None:
            self.levels: list[bool] = []
            self.closed = 0

        def set(self, level: bool) -> None:
            self.levels.append(level)

        def close(self) -> None:
            self.closed += 1

    bus, backlight = StubBus(), Line()
    wiring = Wiring(bus, backlight=backlight)
    wiring.close(backlight_on=False)
    wiring.close()
    assert backlight.levels == [False] and backlight.closed == 1 and bus.log == [("X", b"")]


def test_sim_spi_wiring_runs_the_real_spi_bus() -> None:
    chip = RecordingChip()
    wiring = sim_wiring(chip, "spi", Pins(dc=25, rst=27, hz=10e6), clock=chip.clock)
    wiring.bus.command(0x2A)
    wiring.bus.data(b"\x00\x00\x00\xef")
    wiring.bus.reset()
    assert chip.frames == [(False, b"\x2a"), (True, b"\x00\x00\x00\xef")]
    lines = [(name, level) for name, level, _ in chip.line_changes]
    assert ("reset", False) in lines and lines[-1] == ("reset", True)
    assert wiring.simulator is chip and wiring.te is None


def test_sim_i2c_wiring_sends_control_bytes_and_naks_become_link_errors() -> None:
    chip = RecordingChip()
    wiring = sim_wiring(chip, "i2c", Pins(addr=0x3C, hz=400e3), clock=chip.clock)
    wiring.bus.command(0xAE, 0xAF)
    wiring.bus.data(b"\xff")
    assert chip.writes == [(0x3C, b"\x00\xae\xaf"), (0x3C, b"\x40\xff")]
    wrong = sim_wiring(chip, "i2c", Pins(addr=0x3D, hz=400e3), clock=chip.clock)
    with pytest.raises(LinkError):
        wrong.bus.command(0xAE)


@pytest.mark.parametrize(("url", "match"), [
    ("st7789:spi:0.0?size=240x240", "needs its D/C line"),
    ("st7789:i2c:1", "is not driven over i2c"),
    ("ssd1306:usb:1", "panel target"),
    ("st7789:spi:0.0?dc=25&colour=rgb444", "option colour"),
    ("ssd1306:i2c:1?addr=0x99", "option addr"),
    ("st7789:spi:0.0?dc=25&size=100x100", "no built-in st7789 profile of size 100x100"),
    ("st7789:spi:0.0?dc=25&rotation=45", "option rotation"),
    ("st7789:spi:0.0?dc=25&contrast=3", "unknown option"),
])
def test_urls_that_cannot_be_wired_say_why(url: str, match: str) -> None:
    import pixelpen

    with pytest.raises(ConfigError, match=match):
        pixelpen.open(url)


@pytest.mark.parametrize(("target", "pins", "named"), [
    (Target("ftdi", where="ftdi://ftdi:232h/1"), Pins(dc=4, te=6), "te="),
    (Target("ftdi", where="ftdi://ftdi:232h/1"), Pins(dc=4, bl=7), "bl="),
    (Target("mcp2221"), Pins(rst=3), "rst="),
    (Target("mcp2221"), Pins(te=1, bl=2), "te=, bl="),
])
def test_a_pin_a_bridge_cannot_wire_is_refused_naming_it(target: Target, pins: Pins, named: str) -> None:
    with pytest.raises(ConfigError, match=f"{named} cannot be wired on {target.kind}"):
        open_wiring(target, pins, clock=SimulatedClock(), where="u")


def test_wiring_close_closes_the_bus_even_when_a_line_fails_to_close() -> None:
    class BrokenLine:
        def __init__(self) -> None:
            self.closed = False

        def set(self, level: bool) -> None:
            pass

        def get(self) -> bool:
            return False

        def wait_edge(self, rising: bool, timeout: float) -> bool:
            return False

        def close(self) -> None:
            self.closed = True
            raise OSError("line release failed")

    bus, te, backlight = StubBus(), BrokenLine(), BrokenLine()
    wiring = Wiring(bus, te=te, backlight=backlight)
    with pytest.raises(OSError, match="line release failed"):
        wiring.close()
    assert bus.log == [("X", b"")] and te.closed and backlight.closed

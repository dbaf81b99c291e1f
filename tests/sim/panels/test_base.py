"""PanelSim's bus front: SPI framing and chip select, I2C control bytes, RESET, bus time, events, faults.

Oracles: the SSD1306 datasheet's I2C control byte (Co, D/C#) and the three producer styles of panels.md §1,
the wire-time figures of panels.md §4 (1,032 bytes = 23.3 ms at 400 kHz), the I2C specification's reserved
addresses (0x00-0x07, 0x78-0x7F), and hand-counted byte sequences.
"""

from __future__ import annotations

import numpy as np
import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError, InvalidArgument, InvalidArgumentType, ProtocolError
from pixelpen.options import OptionSpec, integer, pixels
from pixelpen.sim import panels
from pixelpen.sim.base import BusDevice, Fault
from pixelpen.sim.panels import base
from pixelpen.sim.panels.base import EVENT_LOG_LIMIT, PanelSim, register_panel_simulators


class Recorder(PanelSim):
    """A controller that records what the bus front hands it."""

    model = "recorder"

    def __init__(self, **kwargs: object) -> None:
        self.seen: list[tuple[object, ...]] = []
        kwargs.setdefault("clock_hz", 400e3)
        kwargs.setdefault("i2c_address", 0x3C)
        super().__init__(**kwargs)  # type: ignore[arg-type]

    def _panel_command(self, code: int) -> None:
        self.seen.append(("cmd", code))
        if code == 0xEE:
            self._report(code, "flagged")

    def _panel_data(self, data: bytes) -> None:
        self.seen.append(("data", data))

    def _panel_reset(self) -> None:
        self.seen.append(("reset",))

    def _panel_select(self, active: bool) -> None:
        self.seen.append(("cs", active))


def commands(sim: Recorder) -> list[tuple[object, ...]]:
    return [s for s in sim.seen if s[0] in ("cmd", "data")]


def test_is_a_bus_device():
    assert isinstance(Recorder(), BusDevice)


def test_each_call_is_one_chip_select_frame_unless_held():
    sim = Recorder()
    sim.command(b"\x2a\x00")
    sim.data(b"\x01\x02")
    assert sim.seen == [("cs", True), ("cmd", 0x2A), ("cmd", 0x00), ("cs", False),
                        ("cs", True), ("data", b"\x01\x02"), ("cs", False)]
    assert sim.stats.transfers == 2
    sim.seen.clear()
    sim.chip_select(True)
    sim.command(b"\x2c")
    sim.data(b"\x05")
    sim.chip_select(False)
    assert sim.seen == [("cs", True), ("cmd", 0x2C), ("data", b"\x05"), ("cs", False)]
    assert sim.stats.transfers == 3


def test_spi_transfer_returns_zeros_on_miso_and_counts_eight_clocks_per_byte():
    sim = Recorder(clock_hz=10e6)
    assert sim.spi_transfer(b"\x01\x02\x03", dc=True) == bytes(3)
    assert sim.stats.bytes == 3 and sim.stats.data_bytes == 3 and sim.stats.command_bytes == 0
    assert sim.stats.bus_seconds == pytest.approx(24 / 10e6)


STREAMS = {  # the same command bytes AE D5 80 and data 11 22 in the producers' styles (panels.md §1)
    "luma 0x00/0x40 streams": [b"\x00\xae\xd5\x80", b"\x40\x11\x22"],
    "adafruit 0x80 per command": [b"\x80\xae", b"\x80\xd5", b"\x80\x80", b"\x40\x11\x22"],
    "displayio [0x80,b] pairs": [b"\x80\xae\x80\xd5\x80\x80", b"\x40\x11\x22"],
    "Co=0 after Co=1 pairs": [b"\x80\xae\x00\xd5\x80", b"\xc0\x11\xc0\x22"],
}


@pytest.mark.parametrize("style", STREAMS)
def test_i2c_control_byte_styles_give_the_same_bytes(style):
    sim = Recorder()
    for payload in STREAMS[style]:
        assert sim.i2c_write(0x3C, payload)
    flat = [(kind, b) for kind, value in commands(sim) for b in (value if isinstance(value, bytes) else [value])]
    assert flat == [("cmd", 0xAE), ("cmd", 0xD5), ("cmd", 0x80), ("data", 0x11), ("data", 0x22)]
    assert sim.stats.command_bytes == 3 and sim.stats.data_bytes == 2 and sim.events == []


def test_i2c_nak_for_another_address_and_for_a_part_without_i2c():
    sim = Recorder()
    assert not sim.i2c_write(0x3D, b"\x00\xae")
    assert sim.seen == [] and sim.stats.bytes == 0
    assert sim.i2c_read(0x3C, 1) is None

    class SpiOnly(Recorder):
        def __init__(self) -> None:
            PanelSim.__init__(self, clock_hz=1e6)

    assert not SpiOnly().i2c_write(0x3C, b"\x00\xae")


def test_i2c_bus_time_reproduces_the_ssd1306_frame_of_panels_md():
    sim = Recorder(clock_hz=400e3)
    sim.i2c_write(0x3C, bytes([0x00, 0x21, 0, 127, 0x22, 0, 7]))
    sim.i2c_write(0x3C, bytes([0x40]) + bytes(1024))
    assert sim.stats.bytes - sim.stats.transfers == 1032  # panels.md §4: 1,032 bytes after the addresses
    assert round(sim.stats.bus_seconds * 1e3, 1) == 23.3  # ... = 23.3 ms at 400 kHz
    assert sim.stats.bus_seconds == pytest.approx((2 + 9 * 8 + 2 + 9 * 1026) / 400e3)  # START/STOP + 9 per byte


def test_i2c_malformed_control_bytes_are_flagged_not_raised():
    sim = Recorder()
    sim.i2c_write(0x3C, b"\x01\xae")  # low bits set
    sim.i2c_write(0x3C, b"\x80")  # Co=1 with nothing after it
    assert [e.message.split(" ")[0] for e in sim.events] == ["I2C", "I2C"]
    assert ("cmd", 0xAE) in sim.seen


def test_reset_line_holds_the_chip_and_resets_on_the_rising_edge():
    sim = Recorder()
    sim.set_line("reset", False)
    assert sim.in_reset and sim.seen == []
    sim.command(b"\xaf")
    assert ("cmd", 0xAF) not in sim.seen and "RES# is low" in sim.events[-1].message
    sim.set_line("reset", True)
    assert ("reset",) in sim.seen and not sim.in_reset
    sim.seen.clear()
    sim.reset()
    assert sim.seen == [("reset",)]


def test_lines_and_unknown_names():
    sim = Recorder()
    assert sim.line("te") is False
    sim.set_line("backlight", False)
    assert sim.lines["backlight"] is False
    with pytest.raises(InvalidArgument, match="no input line 'dc'"):
        sim.set_line("dc", True)
    with pytest.raises(InvalidArgument, match="no output line"):
        sim.line("busy")


def test_events_carry_time_offset_and_command_and_strict_raises():
    sim = Recorder()
    sim.command(b"\x01\x02\xee")
    event = sim.events[-1]
    assert (event.offset, event.command, event.message) == (2, 0xEE, "flagged")
    sim.data(b"\x00" * 5)
    sim.command(b"\xee")
    assert sim.events[-1].offset == 8
    strict = Recorder(strict=True)
    with pytest.raises(ProtocolError, match="flagged"):
        strict.command(b"\xee")


def test_clock_limits_are_reported_once():
    sim = Recorder(clock_hz=1e6, spi_limit_hz=400e3)
    sim.command(b"\x00")
    sim.command(b"\x00")
    assert len(sim.events) == 1 and "faster" in sim.events[0].message and sim.events[0].offset == -1


def test_faults_now_and_at_a_byte_count():
    sim = Recorder()
    sim.inject(Fault.RESET)
    assert sim.seen == [("reset",)]
    sim.seen.clear()
    sim.inject("power-loss", at=2)
    sim.data(b"\x01\x02\x03")
    assert commands(sim) == [("data", b"\x01\x02"), ("data", b"\x03")]
    assert ("reset",) in sim.seen


def test_reset_stats_and_close():
    sim = Recorder()
    sim.command(b"\xee")
    sim.reset_stats()
    assert sim.stats.bytes == 0 and sim.stats.transfers == 0 and len(sim.events) == 1
    sim.close()
    assert not sim.i2c_write(0x3C, b"\x00\xae")
    assert sim.spi_transfer(b"\x01", dc=False) == b"\x00" and sim.stats.bytes == 0


def test_the_package_exports_the_simulators_lazily():
    from pixelpen.sim.panels.ssd1306 import SSD1306Sim

    assert panels.SSD1306Sim is SSD1306Sim and panels.PanelSim is PanelSim
    with pytest.raises(AttributeError, match="no attribute 'Nope'"):
        panels.Nope  # noqa: B018


# ---- bytes only on the bus calls ------------------------------------------------------------------------

CALLS = {
    "command": lambda sim, value: sim.command(value),
    "data": lambda sim, value: sim.data(value),
    "spi_transfer": lambda sim, value: sim.spi_transfer(value, dc=False),
    "i2c_write": lambda sim, value: sim.i2c_write(0x3C, value),
}


@pytest.mark.parametrize("call", CALLS)
@pytest.mark.parametrize(("value", "found"), [
    (0x2C, "found int 44"), ("\x2c", "found str"), ([0x2C], "found list [44]"), (None, "found NoneType None"),
    (2.0, "found float 2.0"), (True, "found bool True"), (np.array([0x2C]), "found a numpy array of int"),
])
def test_bus_calls_refuse_anything_but_bytes_naming_the_call_and_what_to_pass(call, value, found):
    sim = Recorder()
    pattern = rf"^{call}\(\) takes bytes as (data|payload), e\.g\. {call}\("
    with pytest.raises(InvalidArgumentType, match=pattern) as info:
        CALLS[call](sim, value)
    assert found in str(info.value)
    assert sim.seen == [] and sim.stats.bytes == 0 and sim.stats.transfers == 0  # bytes(44) would be 44 NULs


def test_an_int_is_answered_with_the_bytes_literal_it_probably_meant():
    with pytest.raises(InvalidArgumentType) as info:
        Recorder().command(0x2C)  # type: ignore[arg-type]
    assert str(info.value) == "command() takes bytes as data, e.g. command(b'\\x2c'), found int 44"
    with pytest.raises(InvalidArgumentType) as info:
        Recorder().i2c_write(0x3C, 0xAF)  # type: ignore[arg-type]
    assert str(info.value) == "i2c_write() takes bytes as payload, e.g. i2c_write(0x3c, b'\\x00\\xaf'), found int 175"


@pytest.mark.parametrize("value", [b"\x2a\x00\xff", bytearray(b"\x2a\x00\xff"), memoryview(b"\x2a\x00\xff"),
                                   np.array([0x2A, 0x00, 0xFF], dtype=np.uint8),
                                   np.array([[0x2A, 0x01], [0x00, 0x01], [0xFF, 0x01]], dtype=np.uint8)[:, 0]])
def test_bytes_like_values_are_taken_as_their_bytes(value):
    sim = Recorder()
    sim.command(value)
    sim.data(value)
    sim.i2c_write(0x3C, b"\x40" + bytes(value))
    assert commands(sim) == [("cmd", 0x2A), ("cmd", 0x00), ("cmd", 0xFF), ("data", b"\x2a\x00\xff"),
                             ("data", b"\x2a\x00\xff")]


# ---- the event log is bounded ---------------------------------------------------------------------------

def test_the_event_log_keeps_the_latest_ten_thousand_and_counts_the_ones_dropped():
    assert EVENT_LOG_LIMIT == 10_000  # the number docs/panel-simulators.md gives
    sim = Recorder()
    sim.command(b"\xee" * (EVENT_LOG_LIMIT + 5))
    assert len(sim.events) == 10_000 and sim.events_dropped == 5
    assert sim.events[0].offset == 5 and sim.events[-1].offset == 10_004  # the oldest five went
    sim.command(b"\xee")
    assert len(sim.events) == 10_000 and sim.events_dropped == 6 and sim.events[-1].offset == 10_005
    sim.reset_stats()  # statistics only: the log and its count stay
    assert len(sim.events) == 10_000 and sim.events_dropped == 6


def test_events_is_a_list_snapshot():
    sim = Recorder()
    assert sim.events == [] and sim.events_dropped == 0
    snapshot = sim.events
    sim.command(b"\xee")
    assert snapshot == [] and [e.command for e in sim.events] == [0xEE]


# ---- faults at the clock's present ----------------------------------------------------------------------

class ResetReporter(Recorder):
    """Reports each reset, so the event's time says when the controller saw it."""

    def _panel_reset(self) -> None:
        self._report(None, "reset", at=None)


@pytest.mark.parametrize("fault", [Fault.RESET, Fault.POWER_LOSS])
def test_an_injected_fault_happens_at_the_clocks_present(fault):
    clock = SimulatedClock()
    sim = ResetReporter(clock=clock)
    sim.command(b"\x00")
    clock.advance(2.5)  # no bus traffic since: the device's time has not moved
    sim.inject(fault)
    assert [(e.message, e.time) for e in sim.events] == [("reset", 2.5)]


# ---- the registration and option helpers ----------------------------------------------------------------

def test_register_panel_simulators_registers_each_model_with_its_options(monkeypatch):
    registered = {}
    monkeypatch.setattr(base, "register_simulator", lambda model, factory, specs: registered.update(
        {model: (factory, specs)}))
    specs = (OptionSpec("size", pixels, (8, 8), "glass"), OptionSpec("n", integer(0, 9), 1, "a number"))
    built = []

    def build(model, values, clock):
        built.append((model, values["size"], values["n"], clock))
        return Recorder(clock=clock)

    register_panel_simulators(["one", "two"], build, specs)
    assert sorted(registered) == ["one", "two"] and registered["one"][1] == specs
    clock = SimulatedClock()
    sim = registered["two"][0](clock=clock, size="16x4")
    assert isinstance(sim, Recorder) and built == [("two", (16, 4), 1, clock)]
    with pytest.raises(ConfigError, match=r"sim:one: option n='12' is not valid"):
        registered["one"][0](n="12")
    with pytest.raises(ConfigError, match=r"sim:one: unknown option"):
        registered["one"][0](colour="red")


@pytest.mark.parametrize("address", [0x00, 0x07, 0x78, 0x7F, 0x100])
def test_a_part_at_a_reserved_address_is_refused(address):
    pattern = rf"recorder: I2C address 0x{address:02x} is not a 7-bit address 0x08\.\.0x77 "
    with pytest.raises(ConfigError, match=pattern):
        Recorder(i2c_address=address)


@pytest.mark.parametrize("hz", [0.0, -1.0, float("inf"), float("nan")])
def test_a_bus_clock_must_be_a_positive_finite_number(hz):
    with pytest.raises(InvalidArgument, match="bus clock"):
        Recorder(clock_hz=hz)

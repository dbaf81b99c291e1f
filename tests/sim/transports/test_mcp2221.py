"""The fake MCP2221A: reports built by hand from the datasheet's command layouts, answered as the chip does."""

from __future__ import annotations

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.sim.transports.mcp2221 import REPORT_SECONDS, SimMCP2221
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign


class StubBusDevice:
    """A BusDevice that notes I2C writes, SPI frames and line levels; ``acked`` addresses answer."""

    model = "stub"

    def __init__(self, clock=None, *, acked=(0x3C,), read_data=b"\x07\x08\x09") -> None:
        self.clock = clock or SimulatedClock()
        self.acked = set(acked)
        self.read_data = read_data
        self.writes: list[tuple[int, bytes]] = []
        self.reads: list[tuple[int, int]] = []
        self.frames: list[tuple[bytes, bool]] = []
        self.lines: list[tuple[str, bool]] = []

    def spi_transfer(self, data: bytes, *, dc: bool) -> bytes:
        self.frames.append((bytes(data), dc))
        return bytes(len(data))

    def i2c_write(self, address: int, data: bytes) -> bool:
        self.writes.append((address, bytes(data)))
        return address in self.acked

    def i2c_read(self, address: int, length: int) -> bytes | None:
        self.reads.append((address, length))
        return self.read_data[:length] if address in self.acked else None

    def set_line(self, name: str, level: bool) -> None:
        self.lines.append((name, level))

    def line(self, name: str) -> bool:
        return False

    def advance_to(self, t: float) -> None:
        pass

    def next_event_time(self) -> float | None:
        return None

    def inject(self, fault, at=None) -> None:
        pass

    def close(self) -> None:
        pass


def report(*head: int) -> bytes:
    """An output report as hidapi takes it: report ID 0, then 64 bytes."""
    return bytes((0, *head)) + bytes(64 - len(head))


@pytest.fixture
def chip():
    device = StubBusDevice()
    fake = SimMCP2221(device)
    fake.open(0x04D8, 0x00DD)
    return fake, device


def ask(fake: SimMCP2221, *head: int) -> list[int]:
    assert fake.write(report(*head)) == 65
    return fake.read(64, 100)


def test_open_matches_ids_and_serial_as_hidapi_does():
    fake = SimMCP2221(StubBusDevice())
    with pytest.raises(ValueError, match="not open"):
        fake.read(64)
    with pytest.raises(OSError):
        fake.open(0x0403, 0x6014)
    with pytest.raises(OSError):
        fake.open(0x04D8, 0x00DD, "other")
    fake.open(0x04D8, 0x00DD, "0001234567")
    fake.close()
    fake.open_path(b"sim-mcp2221")
    assert fake.get_product_string() == "MCP2221 USB-I2C/UART Combo"
    assert fake.get_manufacturer_string().startswith("Microchip")


def test_status_and_speed(chip):
    fake, _ = chip
    status = ask(fake, 0x10)
    assert len(status) == 64 and status[:2] == [0x10, 0x00]
    assert status[8] == 0x00 and status[14] == 117  # idle; 12 MHz / 100 kHz - 3 at power-on
    speed = ask(fake, 0x10, 0x00, 0x00, 0x20, 27)  # 400 kHz
    assert speed[3] == 0x20 and speed[4] == 27
    assert ask(fake, 0x10)[14] == 27 and fake.clock_hz == pytest.approx(400_000)
    assert ask(fake, 0x10, 0x00, 0x10)[2] == 0x11  # nothing to cancel


def test_a_write_in_one_report_reaches_the_device(chip):
    fake, device = chip
    t0 = fake.clock.now()
    reply = ask(fake, 0x90, 3, 0, 0x3C << 1, 0x00, 0xAE, 0xAF)
    assert reply[:2] == [0x90, 0x00]
    assert device.writes == [(0x3C, b"\x00\xae\xaf")]
    assert fake.clock.now() - t0 == pytest.approx(REPORT_SECONDS)  # one report; the read waited nothing
    assert ask(fake, 0x10)[8] == 0x00


def test_a_long_write_is_collected_from_reports_and_busy_chunks_are_refused(chip):
    fake, device = chip
    payload = bytes(range(100))
    first = ask(fake, 0x90, 100, 0, 0x78, *payload[:60])
    assert first[:3] == [0x90, 0x00, 0x41]  # more data expected
    early = ask(fake, 0x90, 100, 0, 0x78, *payload[60:])  # 60 bytes take 5.5 ms at 100 kHz
    assert early[:3] == [0x90, 0x01, 0x41]  # busy: the first chunk is still on the wire
    assert device.writes == []
    fake.clock.advance(0.01)
    assert ask(fake, 0x90, 100, 0, 0x78, *payload[60:])[:2] == [0x90, 0x00]
    assert device.writes == [(0x3C, payload)]
    status = ask(fake, 0x10)
    assert status[8] == 0x00 and status[20] & 0x40 == 0


def test_an_unacknowledged_address_shows_in_the_status_until_cancelled(chip):
    fake, device = chip
    ask(fake, 0x90, 2, 0, 0x3D << 1, 0x00, 0xAE)
    status = ask(fake, 0x10)
    assert status[8] == 0x25 and status[20] & 0x40
    fake.clock.advance(0.01)
    assert ask(fake, 0x90, 1, 0, 0x78, 0xAE)[:3] == [0x90, 0x01, 0x25]
    assert ask(fake, 0x10, 0x00, 0x10)[2] == 0x10  # marked for cancellation
    status = ask(fake, 0x10)
    assert status[8] == 0x00 and status[20] & 0x40 == 0
    assert device.writes == [(0x3D, b"\x00\xae")]


def test_reads_come_back_through_0x40(chip):
    fake, device = chip
    assert ask(fake, 0x91, 3, 0, (0x3C << 1) | 1)[:2] == [0x91, 0x00]
    fake.clock.advance(0.01)
    data = ask(fake, 0x40)
    assert data[:7] == [0x40, 0x00, 0x55, 3, 7, 8, 9]
    assert device.reads == [(0x3C, 3)]
    ask(fake, 0x91, 1, 0, (0x50 << 1) | 1)
    fake.clock.advance(0.01)
    assert ask(fake, 0x40)[2] == 0x25


def test_unknown_commands_get_no_answer_and_reset_closes_the_handle(chip):
    fake, _ = chip
    t0 = fake.clock.now()
    assert ask(fake, 0x33) == []
    assert fake.clock.now() - t0 == pytest.approx(REPORT_SECONDS + 0.1)  # the read's timeout passed
    assert ask(fake, 0x50)[:2] == [0x50, 0x00]
    fake.write(report(0x70, 0xAB, 0xCD, 0xEF))
    with pytest.raises(ValueError):
        fake.write(report(0x10))


def test_the_report_log_keeps_the_newest_10000_and_counts_the_rest(chip):
    fake, _ = chip
    assert fake.reports.maxlen == 10_000  # as documented
    for i in range(10_003):
        fake.write(report(0x33, i & 0xFF, i >> 8))  # a command the chip does not answer: nothing queues up
    assert len(fake.reports) == 10_000 and fake.reports.dropped == 3
    assert fake.reports[0][:3] == bytes((0x33, 3, 0)) and fake.reports[-1][:3] == bytes((0x33, 0x12, 0x27))
    del fake.reports[:]
    assert len(fake.reports) == 0 and fake.reports.dropped == 3


def test_malformed_writes_are_refused(chip):
    fake, _ = chip
    with pytest.raises(OSError):
        fake.write(b"")
    with pytest.raises(OSError):
        fake.write(b"\x01" + bytes(64))  # report ID 1 does not exist
    with pytest.raises(OSError):
        fake.write(bytes(66))
    assert fake.write(b"\x00\x10") == 2  # a short report is padded
    assert fake.read(64)[0] == 0x10


def fuzz_reports(data: bytes) -> None:
    """The fuzz target: any byte string, cut into reports, never crashes the fake chip."""
    fake = SimMCP2221(StubBusDevice(acked=(0x3C, 0x00)))
    fake.open()
    for i in range(0, len(data), 64):
        try:
            fake.write(b"\x00" + data[i : i + 64])
            fake.read(64, 1)
        except ValueError:  # a reset closed the handle
            fake.open()


REPORT_SEEDS = [
    bytes((0x90, 100, 0, 0x78)) + bytes(60) + bytes((0x90, 100, 0, 0x78)) + bytes(60),
    bytes((0x10, 0, 0x10, 0x20, 27)) + bytes(59) + bytes((0x91, 3, 0, 0x79)) + bytes(60) + b"\x40" + bytes(63),
]


def test_fuzzed_reports_never_crash_the_chip():
    campaign("mcp2221 reports", fuzz_reports, REPORT_SEEDS, QUICK_CASES, seed=5).check()


@pytest.mark.slow
def test_fuzzed_reports_slow():
    result = campaign("mcp2221 reports", fuzz_reports, REPORT_SEEDS, SLOW_CASES, seed=9)
    print(result.summary())
    result.check()

"""The MCP2221A adapter: the reports it sends (written out from the datasheet's layouts), NAKs, timeouts, faults."""

from __future__ import annotations

import errno
import types

import numpy as np
import pytest
from smbus2 import i2c_msg

from pixelpen.clock import SimulatedClock
from pixelpen.drivers.i2c import I2CBus
from pixelpen.drivers.mcp2221 import MCP2221
from pixelpen.errors import ConfigError, InvalidArgument, LinkError, LinkTimeout
from pixelpen.sim.transports.mcp2221 import SimMCP2221
from tests.fuzzing import QUICK_CASES, campaign
from tests.sim.transports.test_mcp2221 import StubBusDevice


def opened(clock_hz: float = 400_000, **device_options) -> tuple[MCP2221, SimMCP2221, StubBusDevice]:
    clock = SimulatedClock()
    device = StubBusDevice(clock, **device_options)
    fake = SimMCP2221(device)
    fake.open(0x04D8, 0x00DD)
    return MCP2221(fake, clock_hz=clock_hz, clock=clock), fake, device


def head(report: bytes, n: int = 4) -> tuple[int, ...]:
    return tuple(report[:n])


def accepted_writes(fake: SimMCP2221) -> list[bytes]:
    """The 0x90 reports, with a busy chunk sent again counted once (consecutive chunks differ in these tests)."""
    out: list[bytes] = []
    for r in fake.reports:
        if r[0] in (0x90, 0x94) and (not out or out[-1] != r):
            out.append(r)
    return out


def test_opening_sets_the_clock_divider():
    adapter, fake, _ = opened(400_000)
    assert fake.reports[0] == bytes((0x10, 0x00, 0x00, 0x20, 27)) + bytes(59)  # 12 MHz / 400 kHz - 3
    assert fake.clock_hz == pytest.approx(400_000) and adapter.clock_hz == pytest.approx(400_000)
    adapter.set_clock(100_000)
    assert fake.reports[-1][:5] == bytes((0x10, 0, 0, 0x20, 117))
    with pytest.raises(ConfigError, match=r"46512\.\.400000 Hz"):
        adapter.set_clock(1_000_000)


def test_a_short_write_is_status_write_status():
    adapter, fake, device = opened()
    del fake.reports[:]
    adapter.i2c_rdwr(i2c_msg.write(0x3C, b"\x00\xae\xd5\x80"))
    assert [head(r, 1) for r in fake.reports] == [(0x10,), (0x90,), (0x10,)]
    assert fake.reports[1] == bytes((0x90, 4, 0, 0x78, 0x00, 0xAE, 0xD5, 0x80)) + bytes(56)
    assert device.writes == [(0x3C, b"\x00\xae\xd5\x80")]


def test_a_1025_byte_ssd1306_data_write_is_18_reports_of_60_and_a_frame_19():
    adapter, fake, device = opened()
    pixels = bytes((i * 7 + 3) % 256 for i in range(1024))
    window = b"\x00\x21\x00\x7f\x22\x00\x07"
    del fake.reports[:]
    adapter.i2c_rdwr(i2c_msg.write(0x3C, window))
    adapter.i2c_rdwr(i2c_msg.write(0x3C, b"\x40" + pixels))
    writes = accepted_writes(fake)
    assert len(writes) == 19
    assert writes[0][:4] == bytes((0x90, 7, 0, 0x78))
    payload = b"\x40" + pixels
    for k, r in enumerate(writes[1:]):
        assert r[:4] == bytes((0x90, 0x01, 0x04, 0x78))  # every chunk repeats the whole length, 1025 = 0x0401
        chunk = payload[60 * k : 60 * k + 60]
        assert r[4 : 4 + len(chunk)] == chunk
    assert [len(payload[60 * k : 60 * k + 60]) for k in range(18)] == [60] * 17 + [5]
    assert device.writes == [(0x3C, window), (0x3C, payload)]
    # simulated time: USB reports at 1 ms each plus busy retries while 60-byte chunks go out at 400 kHz
    assert 0.019 <= adapter.clock.now() <= 0.1


def test_no_acknowledge_is_a_link_error_with_eremoteio():
    adapter, fake, _ = opened(acked=())
    with pytest.raises(LinkError, match="no device acknowledged address 0x3c") as info:
        adapter.i2c_rdwr(i2c_msg.write(0x3C, b"\x00\xae"))
    assert info.value.errno == errno.EREMOTEIO
    assert fake.reports[-1][:3] == bytes((0x10, 0x00, 0x10))  # the transfer was cancelled


def test_a_multi_report_write_to_a_missing_device_fails_too():
    adapter, _, _ = opened(acked=())
    with pytest.raises(LinkError, match="no device acknowledged"):
        adapter.write(0x3C, bytes(200))


def test_a_stuck_engine_is_cancelled_before_the_next_transfer():
    adapter, fake, device = opened(acked=(0x3C,))
    fake.write(b"\x00" + bytes((0x90, 100, 0, 0x78)) + bytes(60))  # someone left a transfer half done
    fake.read(64)
    del fake.reports[:]
    adapter.write(0x3C, b"\x00\xaf")
    assert head(fake.reports[1], 3) == (0x10, 0x00, 0x10)
    assert device.writes == [(0x3C, b"\x00\xaf")]


def test_write_then_read_uses_no_stop_and_repeated_start():
    adapter, fake, device = opened()
    register = i2c_msg.write(0x3C, b"\x00")
    answer = i2c_msg.read(0x3C, 3)
    adapter.i2c_rdwr(register, answer)
    assert list(answer) == [7, 8, 9]
    kinds = [r[0] for r in fake.reports if r[0] != 0x10]
    assert kinds[0] == 0x94 and kinds[1] == 0x93 and set(kinds[2:]) == {0x40}
    assert device.reads == [(0x3C, 3)]


def test_bad_addresses_and_lengths_are_refused_before_anything_is_sent():
    adapter, fake, _ = opened()
    sent = len(fake.reports)
    with pytest.raises(InvalidArgument, match="0x80 is not a 7-bit address"):
        adapter.i2c_rdwr(i2c_msg.write(0x80, b"\x00"))
    with pytest.raises(InvalidArgument, match=r"0\.\.65535 bytes"):
        adapter.write(0x3C, bytes(65536))
    assert len(fake.reports) == sent


def test_a_read_from_a_missing_device_is_a_nak():
    adapter, _, _ = opened(acked=())
    with pytest.raises(LinkError, match="no device acknowledged address 0x50"):
        adapter.read(0x50, 2)


class SilentHid:
    """A HID device that takes reports and never answers (or fails every write)."""

    def __init__(self, fail: bool = False) -> None:
        self.fail = fail
        self.timeouts: list[int] = []

    def write(self, buff) -> int:
        if self.fail:
            raise OSError(5, "Input/output error")
        return len(buff)

    def read(self, max_length: int, timeout_ms: int = 0) -> list[int]:
        self.timeouts.append(timeout_ms)
        return []

    def close(self) -> None:
        pass


def test_every_read_has_a_timeout_and_none_hangs():
    hid = SilentHid()
    with pytest.raises(LinkTimeout, match=r"no answer within 0\.25 s to set the I2C clock"):
        MCP2221(hid, timeout=0.25)
    assert hid.timeouts == [250]


def test_hid_errors_become_link_errors_naming_the_operation():
    with pytest.raises(LinkError, match=r"cannot set the I2C clock: .*Input/output error"):
        MCP2221(SilentHid(fail=True))
    adapter = opened()[0]
    adapter.close()
    adapter.close()
    with pytest.raises(LinkError, match="closed"):
        adapter.write(0x3C, b"\x00")


def test_open_finds_the_chip_through_hidapi(monkeypatch):
    device = StubBusDevice()
    fake = SimMCP2221(device)
    monkeypatch.setitem(__import__("sys").modules, "hid", types.SimpleNamespace(device=lambda: fake))
    adapter = MCP2221.open(clock_hz=100_000, clock=device.clock)
    assert fake.reports[0][:5] == bytes((0x10, 0, 0, 0x20, 117))
    adapter.close()
    with pytest.raises(LinkError, match="cannot open USB HID device 04d8:00dd serial nope"):
        MCP2221.open(serial="nope")


def test_the_i2c_panel_bus_runs_over_the_adapter():
    adapter, fake, device = opened()
    bus = I2CBus(adapter, 0x3C, clock_hz=adapter.clock_hz, max_transfer=4096)
    del fake.reports[:]
    bus.command(0x21, 0x00, 0x7F, 0x22, 0x00, 0x07)
    pixels = bytes((i * 7 + 3) % 256 for i in range(1024))
    bus.data(pixels)
    assert len(accepted_writes(fake)) == 19  # panels.md section 8: an SSD1306 frame is 19 reports
    assert device.writes == [(0x3C, b"\x00\x21\x00\x7f\x22\x00\x07"), (0x3C, b"\x40" + pixels)]
    missing = I2CBus(adapter, 0x3D)
    with pytest.raises(LinkError, match="i2c: no device acknowledged address 0x3d"):
        missing.command(0xAE)
    bus.close()
    with pytest.raises(ValueError, match="not open"):  # closing the bus closed the adapter and its HID device
        fake.read(64)


class ScriptedHid:
    """A HID device answering every report with the next 64 bytes of a script (then nothing)."""

    def __init__(self, script: bytes) -> None:
        self.script = script
        self.at = 0

    def write(self, buff) -> int:
        return len(buff)

    def read(self, max_length: int, timeout_ms: int = 0) -> list[int]:
        reply = self.script[self.at : self.at + 64]
        self.at += 64
        return list(reply)

    def close(self) -> None:
        pass


class BusyHid:
    """A chip whose I2C engine never gets done: write chunks are refused busy, read data never becomes ready."""

    def __init__(self) -> None:
        self.sent: list[int] = []
        self._last = 0

    def write(self, buff) -> int:
        self._last = bytes(buff)[1]
        self.sent.append(self._last)
        return len(buff)

    def read(self, max_length: int, timeout_ms: int = 0) -> list[int]:
        # datasheet 3.1.5: byte 1 0x01 = busy, byte 2 the engine state (0x41: partial data, not fatal);
        # 3.1.8: byte 1 0x41 = the read data is not ready yet
        tail = {0x90: (0x01, 0x41), 0x40: (0x41, 0x54), 0x91: (0x00, 0x54)}.get(self._last, (0x00, 0x00))
        return [self._last, *tail, *bytes(61)]

    def close(self) -> None:
        pass


def test_a_chunk_refused_busy_50_times_cancels_and_fails():
    hid = BusyHid()
    adapter = MCP2221(hid, clock=SimulatedClock())
    del hid.sent[:]
    with pytest.raises(LinkError, match=r"stayed busy writing to 0x3c at byte 0"):
        adapter.write(0x3C, b"\x00\xae")
    assert hid.sent == [0x10] + [0x90] * 50 + [0x10]  # status first; Blinka's 50 tries; then the cancel
    del hid.sent[:]
    with pytest.raises(LinkError, match=r"no read data from 0x3c after 0 of 2 bytes"):
        adapter.read(0x3C, 2)
    assert hid.sent == [0x10, 0x91] + [0x40] * 50 + [0x10]


def drive_with_replies(script: bytes) -> None:
    """The fuzz target: whatever the chip answers, the adapter succeeds or raises a LinkError, never hangs."""
    adapter = MCP2221(ScriptedHid(script), clock=SimulatedClock())
    adapter.write(0x3C, bytes(130))
    adapter.read(0x3C, 70)


def test_garbled_answers_never_hang_the_adapter():
    ok = bytearray()
    for command in (0x10, 0x10, 0x90, 0x90, 0x90, 0x10, 0x10, 0x91):
        ok += bytes((command, 0)) + bytes(62)
    ok += bytes((0x40, 0, 0x54, 60)) + bytes(60) + bytes((0x40, 0, 0x55, 10)) + bytes(60)
    drive_with_replies(bytes(ok))
    campaign("mcp2221 answers", drive_with_replies, [bytes(ok)], QUICK_CASES, seed=8,
             allowed=(LinkError,)).check()


SSD1306_INIT = bytes((0xAE, 0xD5, 0x80, 0xA8, 0x3F, 0xD3, 0x00, 0x40, 0x8D, 0x14, 0x20, 0x00, 0xA1, 0xC8, 0xDA, 0x12,
                      0x81, 0xCF, 0xD9, 0xF1, 0xDB, 0x40, 0xA4, 0xA6, 0xAF))
"""The SSD1306 datasheet's application-note init (charge pump on, horizontal addressing), then display on."""


def test_an_ssd1306_simulator_behind_the_mcp2221_shows_what_it_shows_when_written_directly():
    panels = pytest.importorskip("pixelpen.sim.panels")
    clock = SimulatedClock()
    through = panels.SSD1306Sim(128, 64, clock=clock)
    fake = SimMCP2221(through)
    fake.open()
    bus = I2CBus(MCP2221(fake, clock=clock), 0x3C, clock_hz=400_000, clock=clock)
    pixels = bytes((0x0F if (i // 128) % 2 else 0xF0) ^ (i % 3) for i in range(1024))
    bus.command(SSD1306_INIT)
    bus.command(0x21, 0x00, 0x7F, 0x22, 0x00, 0x07)
    bus.data(pixels)
    direct = panels.SSD1306Sim(128, 64, clock=SimulatedClock())
    for payload in (b"\x00" + SSD1306_INIT, b"\x00\x21\x00\x7f\x22\x00\x07", b"\x40" + pixels):
        assert direct.i2c_write(0x3C, payload)
    assert np.array_equal(np.asarray(through.glass()), np.asarray(direct.glass()))
    assert np.array_equal(through.gram, direct.gram)
    assert int(np.count_nonzero(np.asarray(through.glass()))) == sum(bin(b).count("1") for b in pixels)

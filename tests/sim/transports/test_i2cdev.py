"""SimSMBus: smbus2's write calls and i2c_rdwr messages as addressed transactions, NAKs, limits, wire time, luma."""

from __future__ import annotations

import errno

import pytest
import smbus2
from hypothesis import given, settings
from hypothesis import strategies as st
from luma.core.interface.serial import i2c as luma_i2c
from smbus2 import i2c_msg

from pixelpen.clock import SimulatedClock
from pixelpen.sim.transports.i2cdev import SimSMBus
from tests.sim.transports.chips import RecordingChip


def test_the_fake_offers_the_smbus2_methods_luma_and_pixelpen_call():
    for name in ("i2c_rdwr", "write_i2c_block_data", "write_byte_data", "write_byte", "close", "open",
                 "__enter__", "__exit__"):
        assert hasattr(smbus2.SMBus, name) and hasattr(SimSMBus(RecordingChip()), name)


def test_ssd1306_command_stream_is_one_transaction():
    chip = RecordingChip()
    bus = SimSMBus(chip)
    bus.i2c_rdwr(i2c_msg.write(0x3C, [0x00, 0xAE, 0xD5, 0x80]))
    bus.write_i2c_block_data(0x3C, 0x40, [1, 2, 3])
    bus.write_byte_data(0x3C, 0x80, 0xAF)
    bus.write_byte(0x3C, 0xE3)
    assert chip.writes == [(0x3C, b"\x00\xae\xd5\x80"), (0x3C, b"\x40\x01\x02\x03"), (0x3C, b"\x80\xaf"),
                           (0x3C, b"\xe3")]
    assert bus.transactions == 4


def test_dispatch_by_address_and_nak_is_eremoteio():
    left, right = RecordingChip(addresses=(0x3C,)), RecordingChip(addresses=(0x3D,))
    bus = SimSMBus(left, right)
    bus.i2c_rdwr(i2c_msg.write(0x3D, b"\x00\xaf"), i2c_msg.write(0x3C, b"\x00\xae"))
    assert left.writes == [(0x3C, b"\x00\xae")] and right.writes == [(0x3D, b"\x00\xaf")]
    with pytest.raises(OSError) as caught:
        bus.write_byte(0x27, 0)
    assert caught.value.errno == errno.EREMOTEIO


def test_reads_fill_the_message_buffer():
    chip = RecordingChip(reads=b"\x43\x00")
    bus = SimSMBus(chip)
    read = i2c_msg.read(0x3C, 1)
    bus.i2c_rdwr(i2c_msg.write(0x3C, [0x00]), read)
    assert list(read) == [0x43]
    with pytest.raises(OSError) as caught:
        bus.i2c_rdwr(i2c_msg.read(0x50, 2))
    assert caught.value.errno == errno.EREMOTEIO


def test_the_kernels_limits_and_smbus2s_block_limit():
    bus = SimSMBus(RecordingChip())
    with pytest.raises(OSError) as caught:
        bus.i2c_rdwr(*[i2c_msg.write(0x3C, b"\x00")] * 43)
    assert caught.value.errno == errno.EINVAL
    with pytest.raises(OSError) as caught:
        bus.i2c_rdwr(i2c_msg.write(0x3C, bytes(8193)))
    assert caught.value.errno == errno.EINVAL
    bus.i2c_rdwr(i2c_msg.write(0x3C, bytes(8192)))
    with pytest.raises(ValueError, match="32"):
        bus.write_i2c_block_data(0x3C, 0x40, [0] * 33)


def test_a_closed_bus_fails_with_ebadf_and_the_context_manager_closes():
    chip = RecordingChip()
    with SimSMBus(chip) as bus:
        bus.write_byte(0x3C, 1)
    with pytest.raises(OSError) as caught:
        bus.write_byte(0x3C, 1)
    assert caught.value.errno == errno.EBADF
    bus.open(1)
    bus.write_byte(0x3C, 2)
    assert chip.writes == [(0x3C, b"\x01"), (0x3C, b"\x02")]


@settings(max_examples=40, deadline=None)
@given(lengths=st.lists(st.integers(0, 300), min_size=1, max_size=5), hz=st.sampled_from([100e3, 400e3, 1e6]))
def test_wire_time_is_nine_clocks_a_byte_plus_start_and_stop(lengths, hz):
    clock = SimulatedClock()
    bus = SimSMBus(RecordingChip(clock), clock_hz=hz)
    bus.i2c_rdwr(*[i2c_msg.write(0x3C, bytes(n)) for n in lengths])
    # per message: (re)START + address byte + n bytes, 9 clocks each; one STOP for the transaction
    assert clock.now() == pytest.approx((sum(1 + 9 * (1 + n) for n in lengths) + 1) / hz)


def test_an_ssd1306_frame_at_400_khz():
    # luma's managed frame: 7 + 1025 bytes in two transactions (panels.md §9: 1032 B in 2 tx)
    clock = SimulatedClock()
    bus = SimSMBus(RecordingChip(clock))
    bus.i2c_rdwr(i2c_msg.write(0x3C, bytes([0x00, 0x21, 0, 127, 0x22, 0, 7])))
    bus.i2c_rdwr(i2c_msg.write(0x3C, bytes([0x40]) + bytes(1024)))
    assert clock.now() == pytest.approx(((1 + 9 * 8 + 1) + (1 + 9 * 1026 + 1)) / 400e3)  # 23.27 ms


def test_luma_i2c_with_a_bus_object_sends_32_byte_smbus_blocks():
    chip = RecordingChip()
    serial = luma_i2c(bus=SimSMBus(chip), address=0x3C)
    serial.command(0xAE, 0xD5, 0x80)
    serial.data(list(range(100)))
    assert chip.writes[0] == (0x3C, b"\x00\xae\xd5\x80")
    assert [len(p) for _, p in chip.writes[1:]] == [33, 33, 33, 5]
    assert all(p[0] == 0x40 for _, p in chip.writes[1:])
    assert b"".join(p[1:] for _, p in chip.writes[1:]) == bytes(range(100))


def smbus_opens(monkeypatch: pytest.MonkeyPatch, chip: RecordingChip) -> list[int]:
    """Make ``smbus2.SMBus(n)`` a SimSMBus on ``chip``; the list collects the bus numbers opened."""
    opened: list[int] = []

    def smbus(port: int) -> SimSMBus:
        opened.append(port)
        return SimSMBus(chip)

    monkeypatch.setattr(smbus2, "SMBus", smbus)
    return opened


def test_luma_i2c_managed_sends_one_i2c_rdwr_per_4096_bytes(monkeypatch):
    chip = RecordingChip()
    opened = smbus_opens(monkeypatch, chip)
    serial = luma_i2c(port=1, address=0x3C)
    serial.data(bytes(5000))
    assert opened == [1]
    assert [len(p) for _, p in chip.writes] == [4097, 905]
    serial.cleanup()


def test_luma_reports_a_missing_device_from_the_nak():
    import luma.core.error

    serial = luma_i2c(bus=SimSMBus(RecordingChip(addresses=(0x3D,))), address=0x3C)
    with pytest.raises(luma.core.error.DeviceNotFoundError, match="0x3C"):
        serial.command(0xAE)

"""The simulated FT232H: USB enumeration, FTDI vendor requests and MPSSE byte streams written out from AN_108."""

from __future__ import annotations

import errno
import random

import pytest
import usb.core
import usb.util

from pixelpen.clock import SimulatedClock
from pixelpen.errors import Disconnected
from pixelpen.sim.transports.ftdi import Ft232hBackend, use_for_urls
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign
from tests.sim.transports.test_mcp2221 import StubBusDevice

IDLE, SELECT = 0x08, 0x00  # ADBUS3 (CS) high / low
DIRECTION = 0x3B  # SCK, MOSI, CS, ADBUS4 (D/C), ADBUS5 (reset) outputs


@pytest.fixture
def chip():
    device = StubBusDevice(SimulatedClock())
    backend = Ft232hBackend(device)
    usb_device = backend.find()
    usb_device.ctrl_transfer(0x40, 0x0B, 0x0200 | 0x0B, 1, b"")  # bit mode MPSSE, direction SCK/MOSI/CS
    return backend, usb_device, device


def send(usb_device, data: bytes) -> None:
    assert usb_device.write(0x02, data) == len(data)


def receive(usb_device, size: int = 512) -> bytes:
    return bytes(usb_device.read(0x81, size))


def frame_bytes(dc: bool, payload: bytes) -> bytes:
    """AN_108: set ADBUS (0x80 value direction), clock bytes out on -ve edge MSB first (0x11 len-1 LE), deselect."""
    level = 0x30 if dc else 0x20  # reset (ADBUS5) stays high; D/C is ADBUS4
    n = len(payload) - 1
    return (bytes((0x80, level | SELECT, DIRECTION, 0x11, n & 0xFF, n >> 8)) + payload
            + bytes((0x80, level | IDLE, DIRECTION)))


def test_it_enumerates_as_an_ft232h():
    backend = Ft232hBackend(StubBusDevice())
    dev = usb.core.find(idVendor=0x0403, idProduct=0x6014, backend=backend)
    assert dev is not None and dev.bcdDevice == 0x0900 and dev.speed == 3
    assert usb.util.get_string(dev, dev.iProduct) == "Single RS232-HS"
    assert usb.util.get_string(dev, dev.iSerialNumber) == "FTSIM001"
    interface = dev.get_active_configuration()[(0, 0)]
    assert sorted(ep.bEndpointAddress for ep in interface) == [0x02, 0x81]
    assert {ep.wMaxPacketSize for ep in interface} == {512}
    assert bytes(dev.ctrl_transfer(0xC0, 0x05, 0, 1, 2)) == b"\x32\x60"


def test_vendor_requests_set_the_chip_up(chip):
    backend, dev, _ = chip
    dev.ctrl_transfer(0x40, 0x09, 2, 1, b"")
    assert backend.latency_ms == 2 and bytes(dev.ctrl_transfer(0xC0, 0x0A, 0, 1, 1)) == b"\x02"
    assert backend.bitmode == 0x02 and backend.direction == 0x0B
    for request in (0x02, 0x03, 0x04, 0x06, 0x07):
        dev.ctrl_transfer(0x40, request, 0, 1, b"")
    with pytest.raises(usb.core.USBError):
        dev.ctrl_transfer(0x40, 0x55, 0, 1, b"")


def test_clock_divisor_and_divide_by_5(chip):
    backend, dev, _ = chip
    send(dev, b"\x8a\x86\x00\x00")  # 60 MHz base, divisor 0
    assert backend.mpsse_clock_hz == 30e6
    send(dev, b"\x8b\x86\x05\x00")  # 12 MHz base, divisor 5: 12 MHz / 12
    assert backend.mpsse_clock_hz == 1e6
    send(dev, b"\x8c\x96\x85")
    assert backend.three_phase and backend.adaptive and not backend.loopback
    send(dev, b"\x8d\x97")
    assert not backend.three_phase and not backend.adaptive


def test_chip_select_frames_carry_the_dc_level(chip):
    _, dev, device = chip
    send(dev, bytes((0x80, 0x28, DIRECTION)))  # idle: CS high, reset high, D/C low
    send(dev, frame_bytes(False, b"\x2a") + frame_bytes(True, b"\x00\x00\x00\xef"))
    assert device.frames == [(b"\x2a", False), (b"\x00\x00\x00\xef", True)]
    assert device.lines == [("reset", True)]
    send(dev, bytes((0x80, 0x08, DIRECTION, 0x80, 0x28, DIRECTION)))
    assert device.lines[-2:] == [("reset", False), ("reset", True)]


def test_commands_split_anywhere_across_bulk_transfers(chip):
    _, dev, device = chip
    stream = bytes((0x80, 0x28, DIRECTION)) + frame_bytes(True, bytes(range(200))) + frame_bytes(False, b"\x2c")
    rng = random.Random(7)
    cuts = sorted(rng.sample(range(1, len(stream)), 12))
    for a, b in zip([0, *cuts], [*cuts, len(stream)], strict=True):
        send(dev, stream[a:b])
    assert device.frames == [(bytes(range(200)), True), (b"\x2c", False)]


def test_a_dc_change_inside_a_frame_splits_it_and_unselected_bytes_go_nowhere(chip):
    backend, dev, device = chip
    send(dev, bytes((0x80, 0x20, DIRECTION, 0x11, 0, 0, 0x2a, 0x80, 0x30, DIRECTION, 0x11, 1, 0, 1, 2,
                     0x80, 0x38, DIRECTION)))
    assert device.frames == [(b"\x2a", False), (b"\x01\x02", True)]
    send(dev, bytes((0x11, 2, 0, 9, 9, 9)))  # CS high
    assert backend.unselected_bytes == 3 and len(device.frames) == 2


def test_reading_pins_and_bad_opcodes_answer_on_bulk_in(chip):
    _, dev, _ = chip
    assert receive(dev) == b"\x32\x60"  # nothing to send: modem status alone
    send(dev, bytes((0x80, 0x28, DIRECTION, 0x82, 0x81, 0xFF, 0x81, 0x83, 0x87)))
    assert receive(dev) == b"\x32\x60\x28\x81"
    send(dev, b"\xaa\x87")
    assert receive(dev) == b"\x32\x60\xfa\xaa"  # AN_108 "bad command" echo
    send(dev, b"\x4b\x87")  # a TMS command has no meaning on SPI here
    assert receive(dev) == b"\x32\x60\xfa\x4b"


def test_loopback_reads_and_packets_of_512(chip):
    _, dev, device = chip
    send(dev, bytes((0x80, 0x20, DIRECTION, 0x84)))
    payload = bytes(i % 251 for i in range(1000))
    send(dev, bytes((0x31, 999 & 0xFF, 999 >> 8)) + payload)
    back = receive(dev, 1024)
    assert len(back) == 1004
    assert back[:2] == back[512:514] == b"\x32\x60"
    assert back[2:512] + back[514:] == payload
    assert device.frames == [(payload, False)]


def test_lsb_first_bytes_reach_the_device_bit_reversed(chip):
    _, dev, device = chip
    send(dev, bytes((0x80, 0x20, DIRECTION, 0x19, 1, 0, 0x01, 0x0F, 0x80, 0x28, DIRECTION)))
    assert device.frames == [(b"\x80\xf0", False)]


def test_time_passes_on_a_simulated_clock(chip):
    _, dev, device = chip
    send(dev, b"\x8a\x86\x00\x00")
    t0 = device.clock.now()
    for start in range(0, 30_000, 1024):  # as pyftdi sends it: bulk transfers of the 1 KiB FIFO's size
        send(dev, frame_bytes(True, bytes(30_000))[start : start + 1024])
    send(dev, b"\x81\x87")
    assert len(receive(dev)) == 3  # the answer comes once the engine has shifted everything before it
    spent = device.clock.now() - t0
    wire = 30_000 * 8 / 30e6
    assert wire <= spent <= wire * 1.1  # shift-bound: USB overlaps the shifting


def test_an_unplugged_chip_answers_no_such_device(chip):
    backend, dev, _ = chip
    backend.close()
    with pytest.raises(usb.core.USBError) as info:
        send(dev, b"\x87")
    assert info.value.errno == errno.ENODEV
    with pytest.raises(Disconnected):
        backend.find()


def test_the_command_and_control_logs_keep_the_newest_entries_and_count_the_rest(chip):
    backend, dev, _ = chip
    assert backend.commands.maxlen == 100_000 and backend.control.maxlen == 1_000  # as documented
    send(dev, b"\x87" * 100_000 + b"\x85\x8a\x8d\x97\x8b")  # send immediate x 100,000, then five others
    assert len(backend.commands) == 100_000 and backend.commands.dropped == 5
    assert backend.commands[-5:] == [0x85, 0x8A, 0x8D, 0x97, 0x8B] and backend.commands[0] == 0x87
    before = len(backend.control)  # the fixture's set-bit-mode request
    for latency in range(1, 1_001):
        dev.ctrl_transfer(0x40, 0x09, latency & 0xFF or 1, 1, b"")
    assert len(backend.control) == 1_000 and backend.control.dropped == before
    assert backend.control[-1] == (0x40, 0x09, 1_000 & 0xFF, 1) and backend.latency_ms == 1_000 & 0xFF


def test_get_status_says_bus_powered_and_unknown_standard_requests_stall(chip):
    _, dev, _ = chip
    assert bytes(dev.ctrl_transfer(0x80, 0, 0, 0, 2)) == b"\x00\x00"  # chapter 9: bit 0 clear, bus-powered
    assert dev.get_active_configuration().bmAttributes == 0x80
    with pytest.raises(usb.core.USBError) as info:
        dev.ctrl_transfer(0x80, 0x0C, 0, 0, 2)  # SYNCH_FRAME is for isochronous endpoints only
    assert info.value.errno == errno.EPIPE


MPSSE_SEEDS = [bytes((0x80, 0x28, DIRECTION)) + frame_bytes(True, bytes(range(100))) + b"\x81\x87\xaa",
               b"\x8a\x86\x00\x00\x84\x31\x03\x00abcd\x19\x00\x00\x01\x13\x07\x55\x8e\x03\x8f\x01\x00"]


def fuzz_mpsse(data: bytes) -> None:
    """The fuzz target: any MPSSE stream, in bulk transfers of 97 bytes, never crashes the chip."""
    backend = Ft232hBackend(StubBusDevice())
    dev = backend.find()
    dev.ctrl_transfer(0x40, 0x0B, 0x020B, 1, b"")
    for i in range(0, len(data), 97):
        dev.write(0x02, data[i : i + 97])
    dev.read(0x81, 4096)


def test_fuzzed_mpsse_streams_never_crash_the_chip():
    campaign("ft232h mpsse", fuzz_mpsse, MPSSE_SEEDS, QUICK_CASES, seed=6).check()


@pytest.mark.slow
def test_fuzzed_mpsse_streams_slow():
    result = campaign("ft232h mpsse", fuzz_mpsse, MPSSE_SEEDS, SLOW_CASES, seed=7)
    print(result.summary())
    result.check()


def test_luma_ftdi_spi_drives_the_simulated_chip():
    """A third-party client: luma.core's ftdi_spi (pyftdi underneath) through the URL backend."""
    serial = pytest.importorskip("luma.core.interface.serial")
    device = StubBusDevice(SimulatedClock())
    backend = Ft232hBackend(device, dc=5, rst=6)
    with use_for_urls(backend):
        luma = serial.ftdi_spi(device="ftdi://ftdi:232h/1", bus_speed_hz=8_000_000, gpio_DC=5, gpio_RST=6)
        luma.command(0x2A, 0x00, 0x00, 0x00, 0xEF)
        luma.data([b % 256 for b in range(5000)])
        luma.cleanup()
    assert device.frames[0] == (b"\x2a\x00\x00\x00\xef", False)
    assert [len(f) for f, _ in device.frames[1:]] == [4096, 904]  # luma writes 4096-byte blocks
    assert b"".join(f for f, _ in device.frames[1:]) == bytes(b % 256 for b in range(5000))
    assert all(dc for _, dc in device.frames[1:])
    assert device.lines == [("reset", True)]  # ADBUS6 was low from power-on: luma released the reset

"""PrinterClassBackend: pyusb sees a USB printer-class device and talks to the simulator through it."""

from __future__ import annotations

import array
import errno
import struct

import pytest
import usb.core
import usb.util

from pixelpen.clock import SimulatedClock
from pixelpen.sim.transports.port import Faults
from pixelpen.sim.transports.usbbackend import SPEED_HIGH, PrinterClassBackend, SimUsbBackend, fill
from tests.sim.fakes import EchoDevice

ID = "MFG:Hewlett-Packard;MDL:7475A;CMD:HPGL;"


def make(**kw) -> tuple[PrinterClassBackend, EchoDevice, usb.core.Device]:
    clock = SimulatedClock()
    device = kw.pop("device", None) or EchoDevice(clock, buffer_size=256)
    backend = PrinterClassBackend(device, device_id=ID, serial_number="A1", clock=clock, **kw)
    dev = usb.core.find(idVendor=0x067B, idProduct=0x2305, backend=backend)
    assert dev is not None
    return backend, device, dev


def test_descriptors_describe_a_bidirectional_printer_interface():
    _, _, dev = make()
    assert (dev.idVendor, dev.idProduct, dev.bNumConfigurations) == (0x067B, 0x2305, 1)
    cfg = dev.get_active_configuration()
    intf = cfg[(0, 0)]
    assert (intf.bInterfaceClass, intf.bInterfaceSubClass, intf.bInterfaceProtocol) == (7, 1, 2)
    eps = {e.bEndpointAddress: e for e in intf}
    assert set(eps) == {0x01, 0x82}
    assert all(usb.util.endpoint_type(e.bmAttributes) == usb.util.ENDPOINT_TYPE_BULK for e in eps.values())
    assert dev.manufacturer == "Prolific Technology Inc."
    assert dev.product == "IEEE-1284 Controller"
    assert dev.serial_number == "A1"


def test_unidirectional_interface_has_only_bulk_out():
    _, _, dev = make(bidirectional=False)
    intf = dev.get_active_configuration()[(0, 0)]
    assert intf.bInterfaceProtocol == 1
    assert [e.bEndpointAddress for e in intf] == [0x01]


def test_raw_device_descriptor_matches_chapter_9_layout():
    _, _, dev = make()
    raw = bytes(dev.ctrl_transfer(0x80, 6, 0x0100, 0, 18))
    fields = struct.unpack("<BBHBBBBHHHBBBB", raw)
    assert fields[0] == 18 and fields[1] == 1
    assert (fields[7], fields[8]) == (0x067B, 0x2305)


def test_configuration_descriptor_lists_interface_and_endpoints():
    _, _, dev = make()
    raw = bytes(dev.ctrl_transfer(0x80, 6, 0x0200, 0, 255))
    assert struct.unpack_from("<H", raw, 2)[0] == len(raw) == 9 + 9 + 7 + 7
    assert raw[9 + 5] == 7  # bInterfaceClass printer
    assert {raw[18 + 2], raw[25 + 2]} == {0x01, 0x82}


def test_get_device_id_has_a_big_endian_length_prefix():
    _, _, dev = make()
    reply = bytes(dev.ctrl_transfer(0xA1, 0, 0, 0, 1023))
    assert reply[:2] == bytes([0, len(ID) + 2])
    assert reply[2:].decode() == ID


def test_get_port_status_reflects_device_attributes():
    _backend, device, dev = make()
    assert dev.ctrl_transfer(0xA1, 1, 0, 0, 1)[0] == 0x18  # selected, no error
    device.paper_empty = True
    device.error = True
    assert dev.ctrl_transfer(0xA1, 1, 0, 0, 1)[0] == 0x30  # paper empty, selected, error (0x08 clear)


def test_bulk_out_feeds_the_device_and_bulk_in_returns_its_answer():
    _backend, device, dev = make()
    assert dev.write(0x01, b"IN;\r", 1000) == 4
    answer = bytes(dev.read(0x82, 64, 1000))
    assert answer == b"OK\r"[: len(answer)] and answer
    assert device.lines == [b"IN;"]


def test_bulk_in_with_nothing_to_read_times_out_with_errno_110():
    _, _, dev = make()
    with pytest.raises(usb.core.USBTimeoutError) as info:
        dev.read(0x82, 64, 50)
    assert info.value.errno == errno.ETIMEDOUT


def test_bulk_out_into_a_stalled_device_times_out():
    _, _, dev = make(faults=Faults(stall_after=0), fifo=16)
    with pytest.raises(usb.core.USBTimeoutError):
        dev.write(0x01, b"x" * 64, 100)


def test_soft_reset_flushes_the_adapter_fifo():
    backend, device, dev = make(rate=100, fifo=64)  # 100 bytes/s: 40 bytes take 0.4 s
    dev.write(0x01, b"y" * 40, 1000)
    dev.ctrl_transfer(0x21, 2, 0, 0, None)
    backend.clock.advance(5)
    backend.port.poll()
    assert len(device.received) <= 1


def test_dropped_link_looks_unplugged():
    _, _, dev = make(faults=Faults(drop_after=2))
    with pytest.raises(usb.core.USBError) as info:
        dev.write(0x01, b"abcdef", 1000)
        dev.read(0x82, 64, 1000)
    assert info.value.errno == errno.ENODEV


def test_unsupported_request_stalls():
    _, _, dev = make()
    with pytest.raises(usb.core.USBError) as info:
        dev.ctrl_transfer(0xC0, 0x42, 0, 0, 4)
    assert info.value.errno == errno.EPIPE


def test_get_status_says_self_powered():
    _, _, dev = make()
    assert bytes(dev.ctrl_transfer(0x80, 0, 0, 0, 2)) == b"\x01\x00"  # chapter 9: bit 0 set, self-powered


class BareDevice(SimUsbBackend):
    """A vendor-class device with nothing but the shared chapter-9 part."""

    def __init__(self) -> None:
        super().__init__(kind="bare", vid=0x1234, pid=0x5678, bcd_device=0x0102, speed=SPEED_HIGH,
                         strings={1: "Maker", 2: "Thing"}, interface=(0xFF, 0, 0), endpoints=(0x81, 0x02, 0x83),
                         max_packet=512, self_powered=False)


def test_the_shared_base_describes_one_configuration_and_answers_standard_requests():
    dev = usb.core.find(idVendor=0x1234, idProduct=0x5678, backend=BareDevice())
    assert dev is not None and dev.speed == 3 and dev.iSerialNumber == 0  # no serial number string
    assert usb.util.get_string(dev, dev.iManufacturer) == "Maker" and usb.util.get_string(dev, 2) == "Thing"
    raw = bytes(dev.ctrl_transfer(0x80, 6, 0x0200, 0, 255))
    # USB 2.0 tables 9-10, 9-12, 9-13: configuration (9 bytes, bus-powered 0x80, 100 mA), interface, 3 bulk endpoints
    assert raw == (struct.pack("<BBHBBBBB", 9, 2, 39, 1, 1, 0, 0x80, 50)
                   + struct.pack("<BBBBBBBBB", 9, 4, 0, 0, 3, 0xFF, 0, 0, 0)
                   + b"".join(struct.pack("<BBBBHB", 7, 5, ep, 2, 512, 0) for ep in (0x81, 0x02, 0x83)))
    assert bytes(dev.ctrl_transfer(0x80, 0, 0, 0, 2)) == b"\x00\x00"  # GET_STATUS: bus-powered
    assert bytes(dev.ctrl_transfer(0x80, 8, 0, 0, 1)) == b"\x01"  # GET_CONFIGURATION
    with pytest.raises(usb.core.USBError) as info:
        dev.ctrl_transfer(0xC0, 0x01, 0, 0, 2)  # no vendor requests of its own: it stalls
    assert info.value.errno == errno.EPIPE
    dev.set_configuration(0)
    with pytest.raises(usb.core.USBError):
        dev.write(0x02, b"x")  # unconfigured: interface 0 cannot be claimed


def test_fill_copies_into_a_pyusb_buffer():
    buff = array.array("B", bytes(4))
    assert fill(buff, b"\x01\x02") == 2 and buff.tobytes() == b"\x01\x02\x00\x00"
    assert fill(buff, b"abcdef") == 4 and buff.tobytes() == b"abcd"
    assert fill(array.array("B"), b"") == 0

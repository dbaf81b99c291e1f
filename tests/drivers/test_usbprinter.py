"""UsbPrinterLink and IEEE 1284 device IDs, against hand-written IDs and the simulated printer-class backend."""

from __future__ import annotations

import pytest
import usb.core

from pixelpen.clock import SimulatedClock
from pixelpen.drivers.usbprinter import (
    PortStatus,
    UsbPrinterLink,
    find_printers,
    parse_device_id,
    parse_device_id_string,
)
from pixelpen.errors import Disconnected, LinkError, LinkTimeout, ParseError
from pixelpen.sim.transports.port import Faults
from pixelpen.sim.transports.usbbackend import PrinterClassBackend
from tests.sim.fakes import EchoDevice

# 40 characters of ID + 2 length bytes = 42 = 0x002A
HP_ID = b"\x00\x2aMFG:Hewlett-Packard;MDL:7475A;CMD:HP-GL;"


def test_parse_device_id_with_big_endian_length():
    assert parse_device_id(HP_ID) == {"MFG": "Hewlett-Packard", "MDL": "7475A", "CMD": "HP-GL"}


def test_long_key_names_and_spaces_are_normalised():
    text = "MANUFACTURER:HP;MODEL:DesignJet 450C;COMMAND SET:HPGL2,PCL;CLASS:PRINTER;DESCRIPTION:HP DesignJet;"
    assert parse_device_id_string(text) == {
        "MFG": "HP",
        "MDL": "DesignJet 450C",
        "CMD": "HPGL2,PCL",
        "CLS": "PRINTER",
        "DES": "HP DesignJet",
    }


def test_length_is_honoured_and_trailing_bytes_ignored():
    raw = b"\x00\x0dMFG:HP;MDL:" + b"garbage after the declared length"
    assert parse_device_id(raw) == {"MFG": "HP", "MDL": ""}


def test_little_endian_length_from_buggy_firmware_is_accepted():
    raw = b"\x2a\x00" + HP_ID[2:]
    assert parse_device_id(raw)["MDL"] == "7475A"


@pytest.mark.parametrize(
    "raw, word",
    [
        (b"", "shorter"),
        (b"\x00", "shorter"),
        (b"\x00\x40MFG:HP;", "says 64"),
        (b"\x00\x11MFG:HP;NOCOLON;", "KEY:value"),
    ],
)
def test_malformed_device_ids(raw, word):
    with pytest.raises(ParseError, match=word):
        parse_device_id(raw)


def test_bad_entry_reports_its_offset():
    with pytest.raises(ParseError) as info:
        parse_device_id_string("MFG:HP;junk;MDL:X;")
    assert info.value.offset == 7 and info.value.token == "junk"


def test_port_status_bits():
    assert PortStatus.from_byte(0x18) == PortStatus(0x18, paper_empty=False, selected=True, error=False)
    assert PortStatus.from_byte(0x30) == PortStatus(0x30, paper_empty=True, selected=True, error=True)
    assert PortStatus.from_byte(0x00).error and not PortStatus.from_byte(0x00).selected


class CountingBackend(PrinterClassBackend):
    """Records the size of every bulk OUT transfer."""

    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self.transfers: list[int] = []

    def bulk_write(self, dev_handle, ep, intf, data, timeout):
        self.transfers.append(len(data))
        return super().bulk_write(dev_handle, ep, intf, data, timeout)


def make_link(**kw):
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=4096, drain_rate=1e6)
    cls = kw.pop("cls", PrinterClassBackend)
    backend = cls(device, clock=clock, device_id="MFG:Roland DG;MDL:DXY-1300;CMD:HPGL;", **kw)
    return UsbPrinterLink(0x067B, 0x2305, backend=backend, timeout=0.5, write_timeout=1.0), backend, device


def test_link_reads_device_id_and_status_from_the_backend():
    link, _backend, device = make_link()
    assert link.device_id() == {"MFG": "Roland DG", "MDL": "DXY-1300", "CMD": "HPGL"}
    assert link.port_status() == PortStatus(0x18, False, True, False)
    device.paper_empty = True
    assert link.port_status().paper_empty
    link.close()


def test_writes_go_out_in_max_packet_chunks():
    link, backend, device = make_link(cls=CountingBackend, max_packet=64)
    payload = bytes(range(256)) * 2 + b"tail"
    link.write(payload)
    assert all(n <= 64 for n in backend.transfers) and sum(backend.transfers) == len(payload)
    assert len(backend.transfers) == -(-len(payload) // 64)
    link.flush()
    backend.port.drain(timeout=5)
    assert bytes(device.received) == payload


def test_unidirectional_printer_cannot_be_read():
    link, _, _ = make_link(bidirectional=False)
    assert link.ep_in is None
    link.write(b"IN;")
    with pytest.raises(LinkError, match="unidirectional"):
        link.read(1)


def test_busy_printer_makes_write_time_out():
    link, _, _ = make_link(faults=Faults(stall_after=0), fifo=32)
    with pytest.raises(LinkTimeout, match="bulk OUT"):
        link.write(b"x" * 200)


def test_unplugged_printer_raises_disconnected():
    link, _, _ = make_link(faults=Faults(drop_after=1))
    link.write(b"ab")
    with pytest.raises(Disconnected):
        link.read(1, timeout=0.5)


def test_soft_reset_drops_unread_input():
    link, _, device = make_link()
    device.say(b"stale\r")
    assert link.read(1, timeout=0.5) == b"s"
    link.clock.sleep(0.01)  # the rest arrives in the adapter (100 kB/s)
    link.soft_reset()
    assert link.read(1, timeout=0.1) == b""


def test_missing_device_lists_what_is_there():
    clock = SimulatedClock()
    backend = PrinterClassBackend(EchoDevice(clock), clock=clock, vid=0x1A86, pid=0x7584)
    with pytest.raises(LinkError, match=r"067b:2305.*1a86:7584"):
        UsbPrinterLink(0x067B, 0x2305, backend=backend)
    assert [d.idProduct for d in find_printers(backend=backend)] == [0x7584]


def test_serial_number_filter():
    clock = SimulatedClock()
    backend = PrinterClassBackend(EchoDevice(clock), clock=clock, serial_number="SN42")
    assert len(find_printers(serial_number="SN42", backend=backend)) == 1
    assert find_printers(serial_number="other", backend=backend) == []


def test_no_usb_backend_is_a_clear_link_error(monkeypatch):
    def no_backend(**kw):
        raise usb.core.NoBackendError("No backend available")

    monkeypatch.setattr(usb.core, "find", no_backend)
    with pytest.raises(LinkError, match="libusb"):
        UsbPrinterLink(0x067B, 0x2305)

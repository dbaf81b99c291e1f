"""Discovery: listing without hanging, known USB IDs, and asking devices who they are."""

from __future__ import annotations

import sys
import types

import pytest
from serial.tools import list_ports_common

from pixelpen.clock import SimulatedClock
from pixelpen.drivers import discovery
from pixelpen.drivers.discovery import (
    KNOWN_USB_IDS,
    DiscoveredDevice,
    discover,
    identify,
    list_hid_devices,
    list_serial_ports,
    list_usb_devices,
)
from pixelpen.drivers.serial import SerialLink
from pixelpen.errors import ConfigError
from pixelpen.sim import base
from pixelpen.sim.transports.usbbackend import PrinterClassBackend
from tests.sim.fakes import EchoDevice, ScriptedDevice

HPGL = {b"OI;": b"7475A\r"}
EBB = {b"V\r": b"EBBv13_and_above EB Firmware Version 2.5.3\r\n"}
GRBL = {b"$I\n": b"[VER:1.1h.20190825:]\r\n[OPT:V,15,128]\r\nok\r\n"}


def scripted_link(replies: dict[bytes, bytes]) -> SerialLink:
    return SerialLink("sim://scripted?baud=115200", device=ScriptedDevice(replies, SimulatedClock()), timeout=1.0)


def test_known_ids_cover_the_plotter_controller_and_adapters():
    expected = {
        (0x04D8, 0xFD92): "plotter",
        (0x0403, 0x6001): "usb-serial",
        (0x067B, 0x2303): "usb-serial",
        (0x1A86, 0x7523): "usb-serial",
        (0x10C4, 0xEA60): "usb-serial",
        (0x067B, 0x2305): "usb-parallel",
        (0x1A86, 0x7584): "usb-parallel",
    }
    for usb_id, kind in expected.items():
        assert KNOWN_USB_IDS[usb_id].kind == kind
    assert KNOWN_USB_IDS[(0x04D8, 0xFD92)].model == "axidraw"


@pytest.fixture
def nothing_attached(monkeypatch):
    monkeypatch.setattr(discovery.list_ports, "comports", list)
    monkeypatch.setitem(sys.modules, "hid", types.SimpleNamespace(enumerate=list))

    def no_backend(**kw):
        import usb.core

        raise usb.core.NoBackendError("No backend available")

    monkeypatch.setattr("usb.core.find", no_backend)


def test_discovery_with_no_devices_is_empty(nothing_attached):
    assert list_serial_ports() == []
    assert list_usb_devices() == []
    assert list_hid_devices() == []
    assert discover() == []
    assert discover(probe=True, timeout=0.01) == []


def test_hidapi_failure_gives_an_empty_list(monkeypatch):
    def broken(vendor_id=0, product_id=0):
        raise OSError("hidraw not available")

    monkeypatch.setitem(sys.modules, "hid", types.SimpleNamespace(enumerate=broken))
    assert list_hid_devices() == []


def test_hid_entries_become_records(monkeypatch):
    entry = {
        "path": b"/dev/hidraw3",
        "vendor_id": 0x046D,
        "product_id": 0xC52B,
        "manufacturer_string": "Logitech",
        "product_string": "Trackball",
        "serial_number": "",
        "usage_page": 1,
        "usage": 2,
    }
    monkeypatch.setitem(sys.modules, "hid", types.SimpleNamespace(enumerate=lambda vendor_id=0, product_id=0: [entry]))
    [rec] = list_hid_devices()
    assert (rec.kind, rec.path, rec.vid, rec.pid, rec.serial_number) == ("hid", "/dev/hidraw3", 0x046D, 0xC52B, None)
    assert "Logitech Trackball" in rec.description


def test_serial_ports_get_a_model_guess_from_their_usb_id(monkeypatch):
    ebb = list_ports_common.ListPortInfo("/dev/ttyACM0", skip_link_detection=True)
    ebb.vid, ebb.pid = 0x04D8, 0xFD92
    plain = list_ports_common.ListPortInfo("/dev/ttyS0", skip_link_detection=True)
    monkeypatch.setattr(discovery.list_ports, "comports", lambda: [plain, ebb])
    ports = list_serial_ports()
    assert [p.path for p in ports] == ["/dev/ttyACM0", "/dev/ttyS0"]
    assert ports[0].model == "axidraw" and "EiBotBoard" in ports[0].description
    assert ports[1].model is None


def test_usb_printer_adapter_is_listed_and_probed_for_its_1284_id(monkeypatch):
    monkeypatch.setattr(discovery.list_ports, "comports", list)
    clock = SimulatedClock()
    backend = PrinterClassBackend(EchoDevice(clock), clock=clock, device_id="MFG:HP;MDL:7550A;CMD:HPGL;")
    [listed] = list_usb_devices(backend)
    assert listed.kind == "usb-printer" and listed.vid == 0x067B and "PL2305" in listed.description
    [found] = discover(probe=True, include_hid=False, usb_backend=backend)
    assert found.model == "7550a" and found.identity.family == "ieee1284"


@pytest.mark.parametrize(
    "family, replies, model, firmware",
    [("hpgl", HPGL, "7475A", None), ("ebb", EBB, "EBBv13_and_above", "2.5.3"), ("grbl", GRBL, "grbl", "1.1h.20190825")],
)
def test_identify_each_family(family, replies, model, firmware):
    with scripted_link(replies) as link:
        who = identify(link, family)
    assert (who.family, who.model, who.firmware) == (family, model, firmware)


def test_identify_grbl_prefers_the_version_line_over_the_reset_banner():
    reply = b"\r\nGrbl 1.1h ['$' for help]\r\n[VER:1.1h.20190830:]\r\n[OPT:VZ,15,128]\r\nok\r\n"
    with scripted_link({b"$I\n": reply}) as link:
        assert identify(link, "grbl").firmware == "1.1h.20190830"


def test_identify_grbl_from_an_old_style_version_line():
    with scripted_link({b"$I\n": b"[0.9j.20160726:]\r\nok\r\n"}) as link:
        assert identify(link, "grbl").firmware == "0.9j.20160726"


@pytest.mark.parametrize("family", ["hpgl", "ebb", "grbl"])
def test_silent_device_gives_none_within_the_timeout(family):
    with scripted_link({}) as link:
        start = link.clock.now()
        assert identify(link, family, timeout=0.2) is None
        assert link.clock.now() - start < 1.0


@pytest.mark.parametrize(
    "family, replies",
    [("hpgl", {b"OI;": b"\x00\xff\r"}), ("ebb", {b"V\r": b"hello\r\n"}), ("grbl", {b"$I\n": b"ok\r\n"})],
)
def test_unexpected_answers_give_none(family, replies):
    with scripted_link(replies) as link:
        assert identify(link, family) is None


def test_identify_sends_the_documented_requests():
    device = ScriptedDevice(HPGL, SimulatedClock())
    with SerialLink("sim://scripted", device=device, timeout=0.5) as link:
        identify(link, "hpgl")
        identify(link, "ebb", timeout=0.05)
        identify(link, "grbl", timeout=0.05)
    assert bytes(device.received) == b"IN;OI;V\r$I\n"


def test_unknown_family_is_a_config_error():
    with scripted_link({}) as link, pytest.raises(ConfigError, match="hpgl"):
        identify(link, "postscript")


def test_probe_identifies_a_serial_port(monkeypatch):
    monkeypatch.setitem(base._REGISTRY, "grbl-test", lambda clock=None, **o: ScriptedDevice(GRBL, clock))
    port = DiscoveredDevice("serial", "sim://grbl-test?speed=fast", "test port")
    monkeypatch.setattr(discovery, "list_serial_ports", lambda: [port])
    monkeypatch.setattr(discovery, "list_usb_devices", lambda backend=None: [])
    [found] = discover(probe=True, include_hid=False, timeout=0.2)
    assert found.model == "grbl" and found.identity.firmware == "1.1h.20190825"

"""UsbHidLink over pyusb against the simulated HID backend: claim and kernel driver, GET_DESCRIPTOR, reports, timeouts.

Requests are checked against HID 1.11 §7.1/§7.2 (bmRequestType 0x81 GET_DESCRIPTOR to the interface, 0xA1/0x21
class requests, wValue = report type << 8 | report ID) by a backend wrapper that records every control
transfer; libusb's timeout 0 means "forever", so the link must never pass it.
"""

from __future__ import annotations

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.drivers.usbhid import UsbHidLink, find_hid_interfaces, hid_class_descriptor_length, open_usbhid
from pixelpen.errors import ConfigError, Disconnected, InvalidArgument, LinkError, ProtocolError
from pixelpen.sim.hid.descriptors import BOOT_KEYBOARD, BOOT_MOUSE, TRACKBALL
from pixelpen.sim.hid.device import HidSim
from pixelpen.sim.transports.usbhid import SimUsbHidBackend

INFO = {"vendor_id": 0x1234, "product_id": 0x0001, "serial_number": "U1", "product_string": "USB Mouse"}
MOVES = [(0.5, bytes([0x01, 0x05, 0xFB])), (1.0, bytes([0x00, 0x00, 0x00]))]


class Recording(SimUsbHidBackend):
    """The simulated backend, noting (bmRequestType, bRequest, wValue, wIndex) and interrupt timeouts."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.controls: list[tuple[int, int, int, int]] = []
        self.timeouts: list[int] = []

    def ctrl_transfer(self, dev_handle, bmRequestType, bRequest, wValue, wIndex, data, timeout):
        self.controls.append((bmRequestType, bRequest, wValue, wIndex))
        return super().ctrl_transfer(dev_handle, bmRequestType, bRequest, wValue, wIndex, data, timeout)

    def intr_read(self, dev_handle, ep, intf, buff, timeout):
        self.timeouts.append(timeout)
        return super().intr_read(dev_handle, ep, intf, buff, timeout)


def backend(descriptor=BOOT_MOUSE, reports=MOVES, **kwargs):
    clock = SimulatedClock()
    sim = HidSim.from_descriptor(descriptor, reports, clock=clock, model="mouse", info=INFO)
    return Recording(sim, **kwargs), sim, clock


def test_hid_class_descriptor_length_from_hand_written_bytes():
    # interface extras: HID descriptor 09 21 11 01 00 01 22 32 00 -> report descriptor of 0x32 = 50 bytes
    assert hid_class_descriptor_length(bytes([0x09, 0x21, 0x11, 0x01, 0x00, 0x01, 0x22, 0x32, 0x00])) == 50
    # two class descriptors, the report one second: 0x22 after 0x23 (physical)
    extra = bytes([0x0C, 0x21, 0x11, 0x01, 0x00, 0x02, 0x23, 0x10, 0x00, 0x22, 0x00, 0x01])
    assert hid_class_descriptor_length(extra) == 256
    assert hid_class_descriptor_length(b"") == 0
    assert hid_class_descriptor_length(bytes([0x00, 0x21])) == 0  # a zero length ends the walk
    assert hid_class_descriptor_length(bytes([0x07, 0x05, 0x81, 0x03, 0x40, 0x00, 0x08])) == 0  # no HID one


def test_find_lists_the_hid_interface():
    b, _, _ = backend(boot="mouse")
    (found,) = find_hid_interfaces(backend=b)
    assert (found.interface, found.subclass, found.protocol) == (0, 1, 2)
    assert found.descriptor_length == len(BOOT_MOUSE) and found.in_endpoint == 0x81 and found.out_endpoint is None
    assert found.path == "1-1:1.0" and found.device_id.key == "usb:1234:0001:U1:0"
    assert find_hid_interfaces(backend=b, vendor_id=0x9999) == []
    assert find_hid_interfaces(backend=b, serial="other") == []


def test_open_detaches_the_kernel_driver_reads_the_descriptor_and_reattaches_on_close():
    b, _, _ = backend()
    link = open_usbhid("1234:0001", backend=b)
    assert not b.kernel_driver
    assert link.report_descriptor == BOOT_MOUSE and not link.numbered
    assert (0x81, 0x06, 0x2200, 0) in b.controls  # GET_DESCRIPTOR(Report) to interface 0
    link.close()
    link.close()
    assert b.kernel_driver


def test_without_detach_the_claim_is_refused_busy():
    b, _, _ = backend()
    with pytest.raises(LinkError, match="kernel driver holds it"):
        open_usbhid("1234:0001", backend=b, detach=False)


def test_no_match_lists_the_hid_interfaces():
    b, _, _ = backend()
    with pytest.raises(LinkError, match=r"1-1:1\.0 \(1234:0001 interface 0\)"):
        open_usbhid("1234:0001@3", backend=b)
    assert open_usbhid("1-1:1.0", backend=b).path == "1-1:1.0"


def test_reads_wait_on_the_clock_in_slices_never_forever():
    b, _, clock = backend()
    link = open_usbhid("1234:0001:U1", backend=b)
    assert link.clock is clock  # the backend's clock is found
    assert link.read_report(0.25) is None and clock.now() == pytest.approx(0.25)
    assert link.read_report(1) == b"\x01\x05\xfb" and clock.now() == pytest.approx(0.5)
    assert link.read_report(None) == b"\x00\x00\x00"
    assert link.read_report(0) is None
    assert 0 not in b.timeouts and max(b.timeouts) <= 100


def test_unplug_during_a_read_is_disconnected():
    b, sim, _ = backend(reports=[(3.0, b"\x00\x00\x00")])
    link = open_usbhid("1234:0001", backend=b)
    assert link.read_report(0.5) is None
    sim.close()
    with pytest.raises(Disconnected, match="removed"):
        link.read_report(1)
    link.close()  # releasing a gone device does not raise


def test_output_report_goes_as_set_report_output_without_an_out_endpoint():
    clock = SimulatedClock()
    keyboard = HidSim.from_descriptor(BOOT_KEYBOARD, clock=clock, model="keyboard", info=INFO)
    b = Recording(keyboard, boot="keyboard")
    link = open_usbhid("1234:0001", backend=b)
    link.write_report(b"\x02")  # Caps Lock LED
    assert keyboard.firmware.outputs[0] == b"\x02"
    assert (0x21, 0x09, 0x0200, 0) in b.controls  # SET_REPORT, Output, report ID 0


def test_output_report_uses_the_interrupt_out_endpoint_when_there_is_one():
    clock = SimulatedClock()
    keyboard = HidSim.from_descriptor(BOOT_KEYBOARD, clock=clock, model="keyboard", info=INFO)
    b = Recording(keyboard, out_endpoint=True)
    link = open_usbhid("1234:0001", backend=b)
    link.write_report(b"\x04")
    assert keyboard.firmware.outputs[0] == b"\x04"
    assert not any(c[1] == 0x09 for c in b.controls)


def test_numbered_feature_reports_carry_their_id_in_wvalue_and_data():
    b, _, _ = backend(descriptor=TRACKBALL, reports=[])
    link = open_usbhid("1234:0001", backend=b)
    assert link.numbered
    link.send_feature(b"\x03\x01")
    assert link.get_feature(3) == b"\x03\x01"
    assert (0x21, 0x09, 0x0303, 0) in b.controls and (0xA1, 0x01, 0x0303, 0) in b.controls
    with pytest.raises(ProtocolError, match="STALL"):
        link.get_feature(9)
    with pytest.raises(InvalidArgument, match="starts with its report ID"):
        link.send_feature(b"\x00\x01")


def test_unnumbered_feature_uses_id_zero():
    b, _, _ = backend(reports=[])
    link = open_usbhid("1234:0001", backend=b)
    link.send_feature(b"\x10\x20")
    assert link.get_feature(0) == b"\x10\x20"
    assert (0xA1, 0x01, 0x0300, 0) in b.controls
    with pytest.raises(InvalidArgument, match="unnumbered"):
        link.get_feature(1)


def test_set_protocol_only_on_boot_interfaces():
    b, _, _ = backend(boot="mouse")
    link = open_usbhid("1234:0001", backend=b, protocol="boot")
    assert link.protocol == "boot" and b.protocol == 0
    assert (0x21, 0x0B, 0, 0) in b.controls
    link.set_idle(0)
    assert (0x21, 0x0A, 0, 0) in b.controls
    plain, _, _ = backend()
    with pytest.raises(ConfigError, match="not a boot interface"):
        open_usbhid("1234:0001", backend=plain, protocol="boot")
    assert plain.kernel_driver  # given back after the failed open
    with pytest.raises(ConfigError, match="protocol"):
        UsbHidLink(find_hid_interfaces(backend=plain)[0], protocol="fast")

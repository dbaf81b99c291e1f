"""SimUsbHidBackend seen through raw pyusb: the HID descriptors byte by byte, endpoints, class requests, errors.

Expected bytes are written from HID 1.11 §6.2.1 (HID descriptor: bLength 9, bDescriptorType 0x21, bcdHID
0x0111 LE, bCountryCode, bNumDescriptors, then 0x22 and wDescriptorLength) and USB 2.0 §9.6 (configuration,
interface, endpoint descriptors; interrupt endpoints have bmAttributes 3).
"""

from __future__ import annotations

import errno

import pytest
import usb.core
import usb.util

from pixelpen.clock import SimulatedClock
from pixelpen.sim.hid.descriptors import BOOT_MOUSE, TRACKBALL
from pixelpen.sim.hid.device import HidSim
from pixelpen.sim.transports.usbhid import SimUsbHidBackend


def device(descriptor=BOOT_MOUSE, reports=(), **kwargs):
    clock = SimulatedClock()
    sim = HidSim.from_descriptor(descriptor, reports, clock=clock, model="mouse",
                                 info={"vendor_id": 0x1234, "product_id": 0x0001})
    backend = SimUsbHidBackend(sim, **kwargs)
    dev = usb.core.find(backend=backend)
    return dev, backend, sim, clock


def claimed(dev):
    dev.detach_kernel_driver(0)
    usb.util.claim_interface(dev, 0)
    return dev


def test_configuration_descriptor_carries_the_hid_descriptor_after_the_interface():
    dev, _, _, _ = device(boot="mouse")
    raw = bytes(dev.ctrl_transfer(0x80, 6, 0x0200, 0, 255))
    assert raw[:4] == bytes([0x09, 0x02, 34, 0x00])  # wTotalLength 9 + 9 + 9 + 7 = 34
    assert raw[9:18] == bytes([0x09, 0x04, 0x00, 0x00, 0x01, 0x03, 0x01, 0x02, 0x00])  # class 3, boot, mouse
    assert raw[18:27] == bytes([0x09, 0x21, 0x11, 0x01, 0x00, 0x01, 0x22, len(BOOT_MOUSE), 0x00])
    assert raw[27:34] == bytes([0x07, 0x05, 0x81, 0x03, 0x40, 0x00, 0x08])  # IN 0x81, interrupt, 64 B, 8 ms
    intf = dev.get_active_configuration()[(0, 0)]
    assert bytes(intf.extra_descriptors) == raw[18:27]


def test_get_descriptor_report_and_hid_to_the_interface():
    dev, _, _, _ = device()
    with pytest.raises(usb.core.USBError) as info:
        dev.ctrl_transfer(0x81, 6, 0x2200, 0, 4096)  # usbfs claims the interface first: usbhid holds it
    assert info.value.errno == errno.EBUSY
    claimed(dev)
    assert bytes(dev.ctrl_transfer(0x81, 6, 0x2200, 0, 4096)) == BOOT_MOUSE
    assert bytes(dev.ctrl_transfer(0x81, 6, 0x2100, 0, 9))[:2] == b"\x09\x21"
    with pytest.raises(usb.core.USBError) as info:
        dev.ctrl_transfer(0x81, 6, 0x2300, 0, 64)  # no physical descriptor: STALL
    assert info.value.errno == errno.EPIPE


def test_polling_interval_follows_the_devices_rate():
    clock = SimulatedClock()
    sim = HidSim(HidSim.from_descriptor(BOOT_MOUSE, clock=clock).firmware, hz=1000, clock=clock)
    endpoint = usb.core.find(backend=SimUsbHidBackend(sim)).get_active_configuration()[(0, 0)][0]
    assert endpoint.bInterval == 1 and usb.util.endpoint_type(endpoint.bmAttributes) == usb.util.ENDPOINT_TYPE_INTR


def test_claim_is_busy_until_the_kernel_driver_is_detached():
    dev, backend, _, _ = device()
    assert dev.is_kernel_driver_active(0)
    with pytest.raises(usb.core.USBError) as info:
        usb.util.claim_interface(dev, 0)
    assert info.value.errno == errno.EBUSY
    claimed(dev)
    dev.attach_kernel_driver(0)
    assert backend.kernel_driver


def test_interrupt_in_times_out_then_delivers_on_the_clock():
    dev, _, _, clock = device(reports=[(0.5, b"\x01\x02\x03")])
    claimed(dev)
    with pytest.raises(usb.core.USBTimeoutError) as info:
        dev.read(0x81, 64, 100)
    assert info.value.errno == errno.ETIMEDOUT and clock.now() == pytest.approx(0.1)
    assert bytes(dev.read(0x81, 64, 1000)) == b"\x01\x02\x03" and clock.now() == pytest.approx(0.5)


def test_a_report_longer_than_the_buffer_overflows():
    dev, _, _, _ = device(descriptor=TRACKBALL, reports=[(0.0, bytes(6))])
    claimed(dev)
    with pytest.raises(usb.core.USBError) as info:
        dev.read(0x81, 4, 100)
    assert info.value.errno == errno.EOVERFLOW


def test_feature_reports_and_stalls():
    dev, _, sim, _ = device()
    claimed(dev)
    assert dev.ctrl_transfer(0x21, 0x09, 0x0300, 0, b"\x05\x06") == 2  # SET_REPORT(Feature, ID 0)
    assert sim.firmware.feature(0) == b"\x05\x06"
    assert bytes(dev.ctrl_transfer(0xA1, 0x01, 0x0300, 0, 64)) == b"\x05\x06"
    with pytest.raises(usb.core.USBError) as info:
        dev.ctrl_transfer(0xA1, 0x01, 0x0100, 0, 64)  # GET_REPORT(Input): not answered
    assert info.value.errno == errno.EPIPE


def test_protocol_and_idle_requests():
    dev, backend, _, _ = device(boot="mouse")
    claimed(dev)
    assert bytes(dev.ctrl_transfer(0xA1, 0x03, 0, 0, 1)) == b"\x01"  # report protocol after power-up
    dev.ctrl_transfer(0x21, 0x0B, 0, 0, None)
    assert backend.protocol == 0 and bytes(dev.ctrl_transfer(0xA1, 0x03, 0, 0, 1)) == b"\x00"
    dev.ctrl_transfer(0x21, 0x0A, 0x7D00, 0, None)  # SET_IDLE 500 ms (125 x 4 ms)
    assert bytes(dev.ctrl_transfer(0xA1, 0x02, 0, 0, 1)) == bytes([0x7D])
    plain, _, _, _ = device()
    claimed(plain)
    with pytest.raises(usb.core.USBError):
        plain.ctrl_transfer(0x21, 0x0B, 0, 0, None)  # not a boot interface


def test_unplugged_device_answers_no_such_device():
    dev, _, sim, _ = device(reports=[(5.0, b"\x00\x00\x00")])
    claimed(dev)
    sim.close()
    with pytest.raises(usb.core.USBError) as info:
        dev.read(0x81, 64, 100)
    assert info.value.errno == errno.ENODEV
    with pytest.raises(usb.core.USBError) as info:
        dev.ctrl_transfer(0x81, 6, 0x2200, 0, 64)
    assert info.value.errno == errno.ENODEV

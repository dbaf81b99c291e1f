"""SimUsbHidBackend: a pyusb backend serving one HID interface from a ReportDevice, so drivers/usbhid.py runs unchanged.

Built on :class:`~pixelpen.sim.transports.usbbackend.SimUsbBackend` (chapter-9 descriptors, handles,
configuration, claims, strings).  What a USB HID device adds (HID 1.11 §6.2.1, §7):

* the interface is class 3 (subclass 1 and protocol 1/2 for a boot keyboard/mouse), with the HID class
  descriptor (9 bytes: bcdHID 1.11, country 0, one report descriptor of the device's length) in its extra
  descriptors and in the configuration descriptor after the interface; an interrupt IN endpoint 0x81 polled
  every ``1000 / hz`` ms (the device's ``hz``), and an interrupt OUT endpoint 0x01 when ``out_endpoint``;
* ``GET_DESCRIPTOR`` (0x81) Report 0x22 / HID 0x21; ``GET_REPORT``/``SET_REPORT`` Feature go to the device's
  ``get_feature``/``send_feature``, ``SET_REPORT`` Output to ``write_report``; a report the device does not
  have STALLs (EPIPE); ``SET_IDLE``/``GET_IDLE``; ``SET_PROTOCOL``/``GET_PROTOCOL`` on boot interfaces (the
  device's ``set_protocol(0|1)`` is called when it has one; others keep sending what they send);
* the kernel's usbhid driver is bound at first: ``claim_interface`` fails with EBUSY until
  ``detach_kernel_driver`` (``attach_kernel_driver`` binds it again; ``kernel_driver`` tells) — and so do
  requests to the interface, which pyusb (like usbfs) claims first;
* interrupt IN: the device's reports after ``advance_to(clock.now())``, waiting for the next one up to the
  timeout on the clock (libusb's 0: forever) as the hidapi fake does (``ReportQueue``); none ->
  ``USBTimeoutError`` (errno 110); a report longer than the buffer -> overflow error;
* unplugged (the device closed or without power): every transfer answers "No such device" (errno 19).
"""

from __future__ import annotations

import errno
import struct
from typing import Any

import usb.core

from pixelpen.clock import Clock
from pixelpen.errors import Disconnected, ProtocolError
from pixelpen.sim.base import ReportDevice
from pixelpen.sim.transports.hidapi import ReportQueue, connected
from pixelpen.sim.transports.usbbackend import SPEED_FULL, SimUsbBackend, fill

EP_IN, EP_OUT = 0x81, 0x01
_INTERRUPT = 0x03
_TIMEOUT_CODE, _PIPE_CODE, _BUSY_CODE, _OVERFLOW_CODE = -7, -9, -6, -8  # libusb error codes
BOOT = {"keyboard": 1, "mouse": 2}


class SimUsbHidBackend(SimUsbBackend):
    """pyusb IBackend for one simulated USB HID device (see the module docstring)."""

    def __init__(self, device: ReportDevice, *, vid: int | None = None, pid: int | None = None,
                 manufacturer: str | None = None, product: str | None = None, serial_number: str | None = None,
                 boot: str | None = None, out_endpoint: bool = False, max_packet: int = 64,
                 clock: Clock | None = None, bus: int = 1, address: int = 2) -> None:
        info = dict(getattr(device, "info", None) or {})
        if boot is not None and boot not in BOOT:
            raise ValueError(f"boot must be 'keyboard', 'mouse' or None, got {boot!r}")
        serial = serial_number if serial_number is not None else info.get("serial_number") or None
        strings = {1: manufacturer or info.get("manufacturer_string", "pixelpen"),
                   2: product or info.get("product_string", f"simulated {device.model}")}
        super().__init__(kind="pixelpen-hid", vid=vid if vid is not None else int(info.get("vendor_id", 0)),
                         pid=pid if pid is not None else int(info.get("product_id", 0)), bcd_device=0x0100,
                         speed=SPEED_FULL, strings=strings | ({3: serial} if serial else {}),
                         interface=(3, 1 if boot else 0, BOOT.get(boot or "", 0)),
                         endpoints=[EP_IN, EP_OUT] if out_endpoint else [EP_IN], max_packet=max_packet,
                         self_powered=False, bus=bus, address=address)
        self.device = device
        self.clock = clock if clock is not None else device.clock
        self.queue = ReportQueue(device, self.clock)
        interval = max(1, round(1000 / float(getattr(device, "hz", 125.0))))
        for endpoint in self._endpoints:
            endpoint.bmAttributes = _INTERRUPT
            endpoint.bInterval = interval
        self.hid_descriptor = struct.pack("<BBHBBBH", 9, 0x21, 0x0111, 0, 1, 0x22, len(device.report_descriptor))
        self._interface.extra_descriptors = list(self.hid_descriptor)
        self._config.wTotalLength += len(self.hid_descriptor)
        self.kernel_driver = True
        """True while the (simulated) kernel usbhid driver is bound to the interface."""
        self.idle = 0
        self.protocol = 1
        """1 report protocol (the power-up default), 0 boot protocol."""
        self.boot = boot

    # ---- kernel driver ---------------------------------------------------------------------------
    def is_kernel_driver_active(self, dev_handle: Any, intf: int) -> bool:
        """usbhid is bound until detached."""
        return self.kernel_driver

    def detach_kernel_driver(self, dev_handle: Any, intf: int) -> None:
        """Unbind usbhid (the device stops being a keyboard/mouse for the system)."""
        self._check_present()
        self.kernel_driver = False

    def attach_kernel_driver(self, dev_handle: Any, intf: int) -> None:
        """Bind usbhid again."""
        self._check_present()
        self.kernel_driver = True

    def claim_interface(self, dev_handle: Any, intf: int) -> None:
        """EBUSY while the kernel driver holds the interface, as libusb answers."""
        if self.kernel_driver:
            raise usb.core.USBError("Resource busy", _BUSY_CODE, errno.EBUSY)
        super().claim_interface(dev_handle, intf)

    # ---- transfers -------------------------------------------------------------------------------
    def intr_read(self, dev_handle: Any, ep: int, intf: int, buff: Any, timeout: int) -> int:
        """Interrupt IN: the next report, waiting up to ``timeout`` ms (0: forever); USBTimeoutError when none."""
        self._check_endpoint(ep, EP_IN, intf)
        try:
            report = self.queue.take(timeout / 1000.0 if timeout else None)
        except Disconnected:
            raise self._gone() from None
        if report is None:
            raise usb.core.USBTimeoutError("Operation timed out", _TIMEOUT_CODE, errno.ETIMEDOUT)
        if len(report) > len(buff):
            raise usb.core.USBError("Overflow", _OVERFLOW_CODE, errno.EOVERFLOW)
        return fill(buff, report)

    def intr_write(self, dev_handle: Any, ep: int, intf: int, data: Any, timeout: int) -> int:
        """Interrupt OUT: an output report for the device."""
        self._check_endpoint(ep, EP_OUT, intf)
        return self._to_device(lambda: self.device.write_report(bytes(data)), len(data))

    def ctrl_transfer(self, dev_handle: Any, bmRequestType: int, bRequest: int, wValue: int, wIndex: int,
                      data: Any, timeout: int) -> int:
        """HID descriptors and class requests on interface 0; the rest as every device answers them."""
        self._check_present()
        kind, report_id = wValue >> 8, wValue & 0xFF
        if bmRequestType == 0x81 and bRequest == 6 and wIndex == 0:
            reply = {0x22: self.device.report_descriptor, 0x21: self.hid_descriptor}.get(kind)
            return fill(data, reply) if reply is not None else self._stall(bRequest)
        if bmRequestType == 0xA1 and wIndex == 0:
            if bRequest == 0x01 and kind == 3:
                answer: list[bytes] = []
                self._to_device(lambda: answer.append(self.device.get_feature(report_id)), 0)
                return fill(data, answer[0])
            if bRequest == 0x02:
                return fill(data, bytes((self.idle,)))
            if bRequest == 0x03 and self.boot:
                return fill(data, bytes((self.protocol,)))
            return self._stall(bRequest)
        if bmRequestType == 0x21 and wIndex == 0:
            payload = bytes(data) if data is not None else b""
            if bRequest == 0x09 and kind == 2:
                return self._to_device(lambda: self.device.write_report(payload), len(payload))
            if bRequest == 0x09 and kind == 3:
                return self._to_device(lambda: self.device.send_feature(payload), len(payload))
            if bRequest == 0x0A:
                self.idle = kind
                return 0
            if bRequest == 0x0B and self.boot and wValue in (0, 1):
                self.protocol = wValue
                setter = getattr(self.device, "set_protocol", None)
                if setter is not None:
                    setter(wValue)
                return 0
            return self._stall(bRequest)
        return super().ctrl_transfer(dev_handle, bmRequestType, bRequest, wValue, wIndex, data, timeout)

    # ---- helpers ---------------------------------------------------------------------------------
    def _to_device(self, action: Any, result: int) -> int:
        """Run a request on the device: a STALL for what it refuses, "No such device" once it is gone."""
        try:
            action()
        except Disconnected:
            raise self._gone() from None
        except ProtocolError as exc:
            raise usb.core.USBError(f"Pipe error: {exc}", _PIPE_CODE, errno.EPIPE) from None
        return result

    def _descriptor(self, kind: int, index: int, lang: int) -> bytes | None:
        """The configuration descriptor carries the HID class descriptor right after the interface's."""
        out = super()._descriptor(kind, index, lang)
        if kind == 2 and index == 0 and out is not None:
            return out[:18] + self.hid_descriptor + out[18:]
        return out

    @staticmethod
    def _stall(request: int) -> int:
        raise usb.core.USBError(f"Pipe error: HID request {request:#04x} not supported", _PIPE_CODE, errno.EPIPE)

    def _absence(self) -> str | None:
        return None if connected(self.device) else "it may have been disconnected"

    def _gone(self) -> usb.core.USBError:
        return usb.core.USBError("No such device (it may have been disconnected)", -4, errno.ENODEV)

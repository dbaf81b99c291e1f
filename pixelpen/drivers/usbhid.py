"""Raw USB HID through pyusb: find HID interfaces, read the report descriptor by GET_DESCRIPTOR, UsbHidLink.

USB HID class (HID 1.11 §7): an interface of class 3 (subclass 1 = boot interface, protocol 1 keyboard /
2 mouse) carries a HID class descriptor (type 0x21: bcdHID, country, then (type, length) pairs, 0x22 the
report descriptor) among its extra descriptors, an interrupt IN endpoint and optionally an interrupt OUT one.
On endpoint 0, addressed to the interface (``wIndex`` = interface number):

* ``GET_DESCRIPTOR(Report)``: ``ctrl_transfer(0x81, 6, 0x2200, iface, length)`` (standard request, interface
  recipient);
* ``GET_REPORT`` (0xA1, 0x01) / ``SET_REPORT`` (0x21, 0x09): ``wValue`` = type << 8 | report ID (type 1 input,
  2 output, 3 feature; ID 0 when unnumbered); the data are the report as on the interrupt pipe (ID byte first
  only when numbered);
* ``SET_IDLE`` (0x21, 0x0A), ``SET_PROTOCOL`` (0x21, 0x0B: ``wValue`` 0 boot, 1 report; boot interfaces only).

The kernel's usbhid driver owns a HID interface: the link detaches it to claim the interface and attaches it
again on close (the device stops working as a keyboard or mouse meanwhile; hidraw avoids that, see
:mod:`pixelpen.drivers.hidapi`).  Reads are one interrupt IN transfer of the endpoint's wMaxPacketSize (so
reports longer than one packet are not supported), in timeout slices of at most READ_SLICE: libusb's
timeout 0 means forever and is never passed.  In boot protocol the device sends the fixed HID 1.11
Appendix B layouts, which the report descriptor no longer describes (``protocol`` says which is in force).
"""

from __future__ import annotations

import errno as _errno
from dataclasses import dataclass
from typing import Any

import usb.core
import usb.util

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.hidapi import numbered_reports, parse_hid_spec, read_in_slices
from pixelpen.drivers.identity import DeviceId
from pixelpen.drivers.udev import permission_diagnosis
from pixelpen.errors import (
    ConfigError,
    Disconnected,
    InvalidArgument,
    InvalidArgumentType,
    LinkError,
    LinkTimeout,
    ProtocolError,
)

HID_CLASS = 3
BOOT_SUBCLASS = 1
DESC_HID, DESC_REPORT = 0x21, 0x22
GET_DESCRIPTOR = 0x06
GET_REPORT, GET_IDLE, GET_PROTOCOL = 0x01, 0x02, 0x03
SET_REPORT, SET_IDLE, SET_PROTOCOL = 0x09, 0x0A, 0x0B
STANDARD_IN_INTERFACE, CLASS_IN, CLASS_OUT = 0x81, 0xA1, 0x21
REPORT_INPUT, REPORT_OUTPUT, REPORT_FEATURE = 1, 2, 3
PROTOCOLS = {"boot": 0, "report": 1}
CONTROL_MAX = 4096
"""Longest control transfer asked for (usbfs refuses more than a page on older kernels)."""
CONTROL_TIMEOUT_MS = 1000
_GONE = {_errno.ENODEV, _errno.ENOENT, _errno.ESHUTDOWN}


@dataclass(frozen=True)
class UsbHidInterface:
    """One HID interface of one USB device, as :func:`find_hid_interfaces` found it."""

    device: Any
    """The pyusb ``usb.core.Device``."""
    configuration: int
    interface: int
    subclass: int
    protocol: int
    descriptor_length: int
    """wDescriptorLength of the report descriptor from the HID class descriptor (0 when it has none)."""
    in_endpoint: int
    out_endpoint: int | None
    in_packet: int

    @property
    def path(self) -> str:
        """The libusb path as hidapi's libusb backend writes it: bus-ports:configuration.interface."""
        ports = ".".join(str(p) for p in (getattr(self.device, "port_numbers", None) or ())) or "0"
        return f"{self.device.bus}-{ports}:{self.configuration}.{self.interface}"

    @property
    def device_id(self) -> DeviceId:
        """Who it is (the same key hidapi gives the interface); strings that cannot be read are left empty."""
        return DeviceId("usb", int(self.device.idVendor), int(self.device.idProduct), _string(self.device, "serial"),
                        _string(self.device, "product"), self.interface, self.path)


def _string(device: Any, which: str) -> str:
    """The device's serial number or product string ('' when it has none or it cannot be read)."""
    index = getattr(device, "iSerialNumber" if which == "serial" else "iProduct", 0)
    if not index:
        return ""
    try:
        return usb.util.get_string(device, index) or ""
    except (usb.core.USBError, ValueError, NotImplementedError):
        return ""


def hid_class_descriptor_length(extra: bytes) -> int:
    """wDescriptorLength of the report descriptor in an interface's extra descriptors (HID 1.11 §6.2.1); 0 if none."""
    i = 0
    while i + 2 <= len(extra):
        length, kind = extra[i], extra[i + 1]
        if length < 2:
            return 0
        if kind == DESC_HID and length >= 9:
            for j in range(i + 6, min(i + length, len(extra)) - 2, 3):  # (bDescriptorType, wDescriptorLength)...
                if extra[j] == DESC_REPORT:
                    return int.from_bytes(extra[j + 1 : j + 3], "little")
            return 0
        i += length
    return 0


def find_hid_interfaces(*, vendor_id: int | None = None, product_id: int | None = None, backend: Any = None,
                        serial: str | None = None, interface: int | None = None) -> list[UsbHidInterface]:
    """Every interface of class 3 in the active (or first) configuration of the matching USB devices."""
    match = {k: v for k, v in (("idVendor", vendor_id), ("idProduct", product_id)) if v is not None}
    try:
        devices = list(usb.core.find(find_all=True, backend=backend, **match))
    except usb.core.NoBackendError as exc:
        raise LinkError("no USB backend (pyusb found no libusb): install libusb-1.0") from exc
    found = []
    for dev in devices:
        try:
            configurations = list(dev)
        except (usb.core.USBError, ValueError, NotImplementedError):
            continue
        for cfg in configurations[:1]:
            for intf in cfg:
                if intf.bInterfaceClass != HID_CLASS or intf.bAlternateSetting != 0:
                    continue
                if interface is not None and intf.bInterfaceNumber != interface:
                    continue
                endpoints = list(intf)
                ins = [e for e in endpoints if usb.util.endpoint_direction(e.bEndpointAddress) == usb.util.ENDPOINT_IN
                       and usb.util.endpoint_type(e.bmAttributes) == usb.util.ENDPOINT_TYPE_INTR]
                outs = [e for e in endpoints if usb.util.endpoint_direction(e.bEndpointAddress) == usb.util.ENDPOINT_OUT
                        and usb.util.endpoint_type(e.bmAttributes) == usb.util.ENDPOINT_TYPE_INTR]
                if not ins:
                    continue
                found.append(UsbHidInterface(
                    dev, int(cfg.bConfigurationValue), int(intf.bInterfaceNumber), int(intf.bInterfaceSubClass),
                    int(intf.bInterfaceProtocol), hid_class_descriptor_length(bytes(intf.extra_descriptors or b"")),
                    int(ins[0].bEndpointAddress), int(outs[0].bEndpointAddress) if outs else None,
                    int(ins[0].wMaxPacketSize) or 64))
    if serial is not None:
        found = [f for f in found if _string(f.device, "serial") == serial]
    return found


def open_usbhid(spec: str, *, backend: Any = None, clock: Clock | None = None, protocol: str | None = None,
                detach: bool = True) -> UsbHidLink:
    """Open the HID interface ``spec`` names: ``VID:PID[:SERIAL][@interface]`` or a libusb path ``1-2.3:1.0``."""
    wanted = parse_hid_spec(spec)
    if wanted.path is not None:
        present = find_hid_interfaces(backend=backend)
        matches = [f for f in present if f.path == wanted.path]
    else:
        present = find_hid_interfaces(vendor_id=wanted.vendor_id, product_id=wanted.product_id, backend=backend)
        matches = [f for f in present if wanted.interface is None or f.interface == wanted.interface]
        if wanted.serial is not None:
            matches = [f for f in matches if _string(f.device, "serial") == wanted.serial]
    if not matches:
        listed = ", ".join(f"{f.path} ({f.device.idVendor:04x}:{f.device.idProduct:04x} interface {f.interface})"
                           for f in present) or "none"
        raise LinkError(f"no USB HID interface matches {spec!r}; HID interfaces present: {listed}")
    return UsbHidLink(matches[0], clock=clock, protocol=protocol, detach=detach)


class UsbHidLink:
    """A ReportLink over a claimed USB HID interface: interrupt IN reads in slices, reports over the control pipe."""

    def __init__(self, target: UsbHidInterface, *, clock: Clock | None = None, protocol: str | None = None,
                 detach: bool = True, numbered: bool | None = None) -> None:
        if protocol is not None and protocol not in PROTOCOLS:
            raise ConfigError(f"protocol must be 'boot', 'report' or None, got {protocol!r}")
        self.target = target
        self.device = target.device
        self.path = target.path
        if clock is None:
            clock = getattr(getattr(getattr(self.device, "_ctx", None), "backend", None), "clock", None)
        self.clock: Clock = clock if clock is not None else REAL_CLOCK
        self._detached = False
        self._closed = False
        self._numbered = numbered
        self.protocol: str | None = None
        """``boot`` or ``report`` once set with ``set_protocol`` (None: the device's default, report protocol)."""
        self._claim(detach)
        try:
            self.device_id = target.device_id
            self._descriptor = self._read_descriptor()
            if protocol is not None:
                self.set_protocol(protocol)
        except BaseException:
            self._release()  # the kernel driver gets its interface back
            raise

    def _claim(self, detach: bool) -> None:
        dev, number = self.device, self.target.interface
        try:
            try:
                dev.get_active_configuration()
            except usb.core.USBError:
                dev.set_configuration(self.target.configuration)
            try:
                if detach and dev.is_kernel_driver_active(number):
                    dev.detach_kernel_driver(number)
                    self._detached = True
            except NotImplementedError:
                pass  # the backend cannot tell (not Linux): claim and see
            usb.util.claim_interface(dev, number)
        except usb.core.USBError as exc:
            self._release()
            if exc.errno == _errno.EACCES:
                node = f"/dev/bus/usb/{int(dev.bus):03d}/{int(dev.address):03d}"
                raise LinkError(f"{self.path}: cannot claim HID interface {number}: " + permission_diagnosis(
                    node, vendor_id=int(dev.idVendor), product_id=int(dev.idProduct))) from None
            busy = " (the kernel driver holds it: pass detach=True)" if exc.errno == _errno.EBUSY else ""
            raise self._failure(exc, f"claim HID interface {number}{busy}") from None

    def _read_descriptor(self) -> bytes:
        length = self.target.descriptor_length or CONTROL_MAX
        return bytes(self._control(STANDARD_IN_INTERFACE, GET_DESCRIPTOR, DESC_REPORT << 8, min(length, CONTROL_MAX),
                                   "GET_DESCRIPTOR(Report)"))

    @property
    def report_descriptor(self) -> bytes:
        """The report descriptor the device sent for GET_DESCRIPTOR(Report) at open."""
        return self._descriptor

    @property
    def numbered(self) -> bool:
        """True when the device numbers its reports (a Report ID item in the descriptor)."""
        if self._numbered is None:
            self._numbered = numbered_reports(self._descriptor)
        return self._numbered

    # ---- requests ----------------------------------------------------------------------------------
    def _control(self, request_type: int, request: int, value: int, data: Any, what: str) -> Any:
        self._check_open()
        try:
            return self.device.ctrl_transfer(request_type, request, value, self.target.interface, data,
                                             CONTROL_TIMEOUT_MS)
        except usb.core.USBTimeoutError as exc:
            raise LinkTimeout(f"{self.path}: {what} timed out: {exc}") from None
        except usb.core.USBError as exc:
            raise self._failure(exc, what) from None

    def set_protocol(self, protocol: str) -> None:
        """SET_PROTOCOL boot or report (boot interfaces only: subclass 1)."""
        if protocol not in PROTOCOLS:
            raise ConfigError(f"protocol must be 'boot' or 'report', got {protocol!r}")
        if self.target.subclass != BOOT_SUBCLASS:
            raise ConfigError(f"{self.path}: interface {self.target.interface} is not a boot interface (subclass "
                              f"{self.target.subclass}); only boot keyboards and mice take SET_PROTOCOL")
        self._control(CLASS_OUT, SET_PROTOCOL, PROTOCOLS[protocol], None, f"SET_PROTOCOL({protocol})")
        self.protocol = protocol

    def set_idle(self, duration_ms: int = 0, report_id: int = 0) -> None:
        """SET_IDLE: report only on change (0) or repeat every ``duration_ms`` (4 ms units, up to 1020 ms)."""
        if not 0 <= duration_ms <= 1020:
            raise InvalidArgument(f"{self.path}: idle duration {duration_ms} ms is outside 0..1020")
        self._control(CLASS_OUT, SET_IDLE, (duration_ms // 4) << 8 | report_id, None, "SET_IDLE")

    def read_report(self, timeout: float | None = None) -> bytes | None:
        """The next input report from the interrupt IN endpoint, or None after ``timeout`` clock seconds."""
        self._check_open()
        return read_in_slices(self._read_once, self.clock, timeout, self.path)

    def _read_once(self, ms: int) -> bytes | None:
        """One interrupt IN transfer waiting at most ``ms`` (at least 1: libusb's 0 waits forever)."""
        try:
            data = self.device.read(self.target.in_endpoint, self.target.in_packet, max(1, ms))
        except usb.core.USBTimeoutError:
            return None
        except usb.core.USBError as exc:
            raise self._failure(exc, "interrupt IN read") from None
        return bytes(data) if len(data) else None

    def write_report(self, report: bytes) -> None:
        """An output report: on the interrupt OUT endpoint if there is one, else SET_REPORT(Output)."""
        report = self._outgoing(report, "output")
        if self.target.out_endpoint is not None:
            try:
                self.device.write(self.target.out_endpoint, report, CONTROL_TIMEOUT_MS)
            except usb.core.USBTimeoutError as exc:
                raise LinkTimeout(f"{self.path}: interrupt OUT write timed out: {exc}") from None
            except usb.core.USBError as exc:
                raise self._failure(exc, "interrupt OUT write") from None
            return
        self._control(CLASS_OUT, SET_REPORT, REPORT_OUTPUT << 8 | self._id(report), report, "SET_REPORT(Output)")

    def get_feature(self, report_id: int) -> bytes:
        """GET_REPORT(Feature, report_id): ID byte first when numbered (an unnumbered device has only ID 0)."""
        if not isinstance(report_id, int) or isinstance(report_id, bool):
            raise InvalidArgumentType(f"{self.path}: report ID must be an int, not {type(report_id).__name__}")
        if not (1 <= report_id <= 255 if self.numbered else report_id == 0):
            allowed = "1..255 (the device numbers its reports)" if self.numbered else "0 (unnumbered device)"
            raise InvalidArgument(f"{self.path}: feature report ID must be {allowed}, got {report_id}")
        data = bytes(self._control(CLASS_IN, GET_REPORT, REPORT_FEATURE << 8 | report_id, CONTROL_MAX,
                                   f"GET_REPORT(Feature {report_id})"))
        if not data:
            raise ProtocolError(f"feature report {report_id} came back empty", device=self.path,
                                command=f"GET_REPORT(Feature {report_id})")
        return data

    def send_feature(self, report: bytes) -> None:
        """SET_REPORT(Feature): ID byte first when numbered."""
        report = self._outgoing(report, "feature")
        self._control(CLASS_OUT, SET_REPORT, REPORT_FEATURE << 8 | self._id(report), report, "SET_REPORT(Feature)")

    def _outgoing(self, report: bytes, kind: str) -> bytes:
        self._check_open()
        if not isinstance(report, (bytes, bytearray, memoryview)):
            raise InvalidArgumentType(f"{self.path}: a {kind} report is bytes, not {type(report).__name__}")
        report = bytes(report)
        if not report or len(report) > CONTROL_MAX:
            raise InvalidArgument(f"{self.path}: {kind} report of {len(report)} bytes (1..{CONTROL_MAX})")
        if self.numbered and report[0] == 0:
            raise InvalidArgument(f"{self.path}: this device numbers its reports, so a {kind} report starts with "
                                  "its report ID 1..255, not 0")
        return report

    def _id(self, report: bytes) -> int:
        return report[0] if self.numbered else 0

    def _failure(self, exc: usb.core.USBError, what: str) -> LinkError | ProtocolError:
        if exc.errno in _GONE or "no such device" in str(exc).lower():
            return Disconnected(f"{self.path}: the device was removed during {what}: {exc}")
        if exc.errno == _errno.EPIPE:
            return ProtocolError(f"the device refused {what} (STALL)", device=self.path, command=what)
        return LinkError(f"{self.path}: {what} failed: {exc}")

    def _check_open(self) -> None:
        if self._closed:
            raise LinkError(f"{self.path}: the USB HID link is closed")

    def _release(self) -> None:
        """Give the interface back (to the kernel driver when it was detached) and free pyusb's resources."""
        try:
            usb.util.release_interface(self.device, self.target.interface)
            if self._detached:
                self.device.attach_kernel_driver(self.target.interface)
                self._detached = False
        except (usb.core.USBError, NotImplementedError):
            pass  # the device is gone: nothing to give back
        finally:
            usb.util.dispose_resources(self.device)

    def close(self) -> None:
        """Release the interface and reattach the kernel driver; calling it again does nothing."""
        if not self._closed:
            self._closed = True
            self._release()

    def __enter__(self) -> UsbHidLink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

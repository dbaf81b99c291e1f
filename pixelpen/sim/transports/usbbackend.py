"""Simulated pyusb backends: SimUsbBackend (one device, one configuration, one interface) and a USB printer.

:class:`SimUsbBackend` is the chapter-9 part every simulated device shares (USB 2.0 chapter 9: the
device, configuration, interface, endpoint and string descriptors, handles, SET_CONFIGURATION,
interface claims, no kernel driver, GET_DESCRIPTOR / GET_STATUS / GET_CONFIGURATION on endpoint 0);
a subclass adds its transfers, its class or vendor requests (:meth:`SimUsbBackend._request`) and
says when it is gone (:meth:`SimUsbBackend._absence`).  The FT232H backend (``ftdi.py``) is one.

``usb.core.find(backend=PrinterClassBackend(device))`` finds a full-speed device with one
configuration and one interface of class 7 (printer), subclass 1, protocol 2 (bidirectional: bulk
OUT 0x01 and bulk IN 0x82) or 1 (unidirectional: bulk OUT only).  Written from the USB Printing
Devices class definition 1.1 and the USB 2.0 chapter 9 requests, not from the driver:

* bulk OUT goes into the adapter's FIFO (``fifo`` bytes) and from there to the device through a
  :class:`~pixelpen.sim.transports.port.SimPort` paced at ``rate`` bytes/s with the BUSY handshake
  (the device's ``ready_to_receive``); a write that does not fit before its timeout raises
  ``USBTimeoutError`` as libusb does;
* bulk IN returns what the device sent, or ``USBTimeoutError`` (errno 110) when nothing came in time;
* class requests: GET_DEVICE_ID (0xA1/0) returns ``device_id`` behind its 2-byte big-endian length;
  GET_PORT_STATUS (0xA1/1) one status byte; SOFT_RESET (0x21, or 0x23 as printer class 1.0 had it,
  /2) flushes the adapter's buffers;
* standard GET_DESCRIPTOR (device, configuration, string), GET_STATUS and GET_CONFIGURATION.

Port status bits come from optional device attributes ``paper_empty`` (0x20), ``selected``
(0x10; default: the link is up) and ``error`` (clears 0x08), which a simulator may provide.
Faults (``drop_after`` ...) are the SimPort's; a dropped link answers every transfer with
"No such device" (errno 19), as an unplugged adapter does.
"""

from __future__ import annotations

import errno
import struct
from collections.abc import Mapping, Sequence
from types import SimpleNamespace
from typing import Any

import usb.backend
import usb.core

from pixelpen.clock import Clock
from pixelpen.errors import Disconnected, LinkTimeout
from pixelpen.sim.base import StreamDevice
from pixelpen.sim.transports.options import Faults
from pixelpen.sim.transports.port import SimPort

EP_OUT = 0x01
EP_IN = 0x82
_BULK = 0x02
_GET_STATUS, _GET_DESCRIPTOR, _GET_CONFIGURATION = 0, 6, 8
_DESC_DEVICE, _DESC_CONFIG, _DESC_STRING, _DESC_INTERFACE, _DESC_ENDPOINT = 1, 2, 3, 4, 5
_LANG_EN_US = 0x0409
_TIMEOUT_CODE, _NO_DEVICE_CODE, _PIPE_CODE = -7, -4, -9  # libusb error codes
SPEED_FULL, SPEED_HIGH = 2, 3
"""pyusb's libusb1 speed codes: full speed (12 Mbit/s), high speed (480 Mbit/s)."""


def fill(buff: Any, data: bytes) -> int:
    """Copy the head of ``data`` into a pyusb transfer buffer (an ``array('B')``); the bytes copied."""
    n = min(len(data), len(buff))
    if n:
        memoryview(buff)[:n] = data[:n]
    return n


class SimUsbBackend(usb.backend.IBackend):
    """pyusb IBackend for one simulated device with one configuration and one interface (see the module docstring).

    ``strings`` maps string indexes to text (1 manufacturer, 2 product, 3 serial number when present);
    ``interface`` is (class, subclass, protocol); ``endpoints`` the bulk endpoint addresses in
    descriptor order.
    """

    def __init__(
        self,
        *,
        kind: str,
        vid: int,
        pid: int,
        bcd_device: int,
        speed: int,
        strings: Mapping[int, str],
        interface: tuple[int, int, int],
        endpoints: Sequence[int],
        max_packet: int,
        self_powered: bool,
        interface_string: int = 0,
        bus: int = 1,
        address: int = 2,
    ) -> None:
        self._strings = dict(strings)
        self._self_powered = self_powered
        self._configuration = 1  # the OS configured it on enumeration
        self._claimed: set[int] = set()
        self._open_handles = 0
        self._ident = SimpleNamespace(kind=kind, backend=self)
        self._device_desc = SimpleNamespace(
            bLength=18,
            bDescriptorType=_DESC_DEVICE,
            bcdUSB=0x0200,
            bDeviceClass=0,
            bDeviceSubClass=0,
            bDeviceProtocol=0,
            bMaxPacketSize0=64,
            idVendor=vid,
            idProduct=pid,
            bcdDevice=bcd_device,
            iManufacturer=1,
            iProduct=2,
            iSerialNumber=3 if 3 in self._strings else 0,
            bNumConfigurations=1,
            bus=bus,
            address=address,
            port_number=1,
            port_numbers=(1,),
            speed=speed,
        )
        self._endpoints = [
            SimpleNamespace(
                bLength=7,
                bDescriptorType=_DESC_ENDPOINT,
                bEndpointAddress=ep,
                bmAttributes=_BULK,
                wMaxPacketSize=max_packet,
                bInterval=0,
                bRefresh=0,
                bSynchAddress=0,
                extra_descriptors=[],
            )
            for ep in endpoints
        ]
        self._interface = SimpleNamespace(
            bLength=9,
            bDescriptorType=_DESC_INTERFACE,
            bInterfaceNumber=0,
            bAlternateSetting=0,
            bNumEndpoints=len(endpoints),
            bInterfaceClass=interface[0],
            bInterfaceSubClass=interface[1],
            bInterfaceProtocol=interface[2],
            iInterface=interface_string,
            extra_descriptors=[],
        )
        self._config = SimpleNamespace(
            bLength=9,
            bDescriptorType=_DESC_CONFIG,
            wTotalLength=9 + 9 + 7 * len(endpoints),
            bNumInterfaces=1,
            bConfigurationValue=1,
            iConfiguration=0,
            bmAttributes=0xC0 if self_powered else 0x80,
            bMaxPower=50,
            extra_descriptors=[],
        )  # 100 mA

    # -- enumeration and descriptors --------------------------------------------------------

    def enumerate_devices(self) -> list[Any]:
        """The one simulated device."""
        return [self._ident]

    def get_parent(self, dev: Any) -> None:
        """No hub above it."""
        return None

    def get_device_descriptor(self, dev: Any) -> Any:
        """Device descriptor attributes."""
        return self._device_desc

    def get_configuration_descriptor(self, dev: Any, config: int) -> Any:
        """Configuration descriptor (one configuration)."""
        if config != 0:
            raise IndexError(f"configuration index {config} out of range (one configuration)")
        return self._config

    def get_interface_descriptor(self, dev: Any, intf: int, alt: int, config: int) -> Any:
        """Interface descriptor (one interface, one alternate setting)."""
        if (intf, alt, config) != (0, 0, 0):
            raise IndexError(f"interface {intf} alt {alt} config {config} out of range")
        return self._interface

    def get_endpoint_descriptor(self, dev: Any, ep: int, intf: int, alt: int, config: int) -> Any:
        """Endpoint descriptor by index, in the order the constructor was given them."""
        if (intf, alt, config) != (0, 0, 0) or not 0 <= ep < len(self._endpoints):
            raise IndexError(f"endpoint index {ep} out of range")
        return self._endpoints[ep]

    # -- handles, configuration, interfaces --------------------------------------------------

    def open_device(self, dev: Any) -> Any:
        """Open a handle (fails once the device is gone, like an unplugged one)."""
        self._check_present()
        self._open_handles += 1
        return SimpleNamespace(dev=dev)

    def close_device(self, dev_handle: Any) -> None:
        """Close a handle."""
        self._open_handles = max(0, self._open_handles - 1)

    def set_configuration(self, dev_handle: Any, config_value: int) -> None:
        """Select configuration 1 (or 0: unconfigured)."""
        self._check_present()
        if config_value not in (0, 1):
            raise usb.core.USBError(f"Invalid configuration value {config_value}", _PIPE_CODE, errno.EPIPE)
        self._configuration = config_value
        self._claimed.clear()

    def get_configuration(self, dev_handle: Any) -> int:
        """The active bConfigurationValue."""
        return self._configuration

    def set_interface_altsetting(self, dev_handle: Any, intf: int, altsetting: int) -> None:
        """Only interface 0, alternate setting 0 exists."""
        if (intf, altsetting) != (0, 0):
            raise usb.core.USBError(f"No interface {intf} alt {altsetting}", _PIPE_CODE, errno.EPIPE)

    def claim_interface(self, dev_handle: Any, intf: int) -> None:
        """Claim interface 0 (the configuration must be set)."""
        self._check_present()
        if intf != 0 or self._configuration != 1:
            raise usb.core.USBError(f"Entity not found: interface {intf}", -5, errno.ENOENT)
        self._claimed.add(intf)

    def release_interface(self, dev_handle: Any, intf: int) -> None:
        """Release a claimed interface."""
        self._claimed.discard(intf)

    def is_kernel_driver_active(self, dev_handle: Any, intf: int) -> bool:
        """No kernel driver is bound to a simulated device."""
        return False

    def detach_kernel_driver(self, dev_handle: Any, intf: int) -> None:
        """Nothing to detach."""

    def attach_kernel_driver(self, dev_handle: Any, intf: int) -> None:
        """Nothing to attach."""

    def clear_halt(self, dev_handle: Any, ep: int) -> None:
        """Endpoints never halt here."""

    # -- control transfers ---------------------------------------------------------------------

    def ctrl_transfer(
        self, dev_handle: Any, bmRequestType: int, bRequest: int, wValue: int, wIndex: int, data: Any, timeout: int
    ) -> int:
        """Standard requests and the subclass's own on endpoint 0 (others stall with EPIPE)."""
        self._check_present()
        reply: bytes | None = None
        if bmRequestType == 0x80 and bRequest == _GET_DESCRIPTOR:
            reply = self._descriptor(wValue >> 8, wValue & 0xFF, wIndex)
        elif bmRequestType == 0x80 and bRequest == _GET_STATUS:
            reply = b"\x01\x00" if self._self_powered else b"\x00\x00"  # no remote wake-up
        elif bmRequestType == 0x80 and bRequest == _GET_CONFIGURATION:
            reply = bytes((self._configuration,))
        else:
            reply = self._request(bmRequestType, bRequest, wValue, wIndex)
        if reply is None:
            raise usb.core.USBError(
                f"Pipe error: request type {bmRequestType:#04x} request {bRequest:#04x} not supported",
                _PIPE_CODE,
                errno.EPIPE,
            )
        return fill(data, reply)

    def _request(self, request_type: int, request: int, value: int, index: int) -> bytes | None:
        """A class or vendor request: its answer (b"" when it has none), or None to stall."""
        return None

    # -- helpers -------------------------------------------------------------------------------

    def _absence(self) -> str | None:
        """Why the device is gone (it answers "No such device"), or None while it is there."""
        return None

    def _descriptor(self, kind: int, index: int, lang: int) -> bytes | None:
        if kind == _DESC_DEVICE and index == 0:
            d = self._device_desc
            return struct.pack(
                "<BBHBBBBHHHBBBB",
                d.bLength,
                d.bDescriptorType,
                d.bcdUSB,
                d.bDeviceClass,
                d.bDeviceSubClass,
                d.bDeviceProtocol,
                d.bMaxPacketSize0,
                d.idVendor,
                d.idProduct,
                d.bcdDevice,
                d.iManufacturer,
                d.iProduct,
                d.iSerialNumber,
                d.bNumConfigurations,
            )
        if kind == _DESC_CONFIG and index == 0:
            c, i = self._config, self._interface
            out = struct.pack(
                "<BBHBBBBB",
                c.bLength,
                c.bDescriptorType,
                c.wTotalLength,
                c.bNumInterfaces,
                c.bConfigurationValue,
                c.iConfiguration,
                c.bmAttributes,
                c.bMaxPower,
            )
            out += struct.pack(
                "<BBBBBBBBB",
                i.bLength,
                i.bDescriptorType,
                i.bInterfaceNumber,
                i.bAlternateSetting,
                i.bNumEndpoints,
                i.bInterfaceClass,
                i.bInterfaceSubClass,
                i.bInterfaceProtocol,
                i.iInterface,
            )
            for e in self._endpoints:
                out += struct.pack(
                    "<BBBBHB",
                    e.bLength,
                    e.bDescriptorType,
                    e.bEndpointAddress,
                    e.bmAttributes,
                    e.wMaxPacketSize,
                    e.bInterval,
                )
            return out
        if kind == _DESC_STRING:
            if index == 0:
                return struct.pack("<BBH", 4, _DESC_STRING, _LANG_EN_US)
            if index in self._strings and lang == _LANG_EN_US:
                text = self._strings[index].encode("utf-16-le")
                return bytes((len(text) + 2, _DESC_STRING)) + text
        return None

    def _check_present(self) -> None:
        reason = self._absence()
        if reason is not None:
            raise usb.core.USBError(f"No such device ({reason})", _NO_DEVICE_CODE, errno.ENODEV)

    def _check_endpoint(self, ep: int, expected: int, intf: int) -> None:
        self._check_present()
        if ep != expected or intf not in self._claimed:
            raise usb.core.USBError(
                f"Invalid endpoint {ep:#04x} on interface {intf} (claimed: {sorted(self._claimed)})",
                _PIPE_CODE,
                errno.EPIPE,
            )


class PrinterClassBackend(SimUsbBackend):
    """pyusb IBackend for one simulated USB printer-class device (see the module docstring)."""

    def __init__(
        self,
        device: StreamDevice,
        *,
        vid: int = 0x067B,
        pid: int = 0x2305,
        device_id: str = "MFG:Hewlett-Packard;MDL:7475A;CMD:HPGL;CLS:PRINTER;",
        manufacturer: str = "Prolific Technology Inc.",
        product: str = "IEEE-1284 Controller",
        serial_number: str | None = None,
        bidirectional: bool = True,
        max_packet: int = 64,
        rate: int = 100_000,
        fifo: int = 256,
        faults: Faults | None = None,
        clock: Clock | None = None,
        bus: int = 1,
        address: int = 2,
    ) -> None:
        strings = {1: manufacturer, 2: product} | ({3: serial_number} if serial_number is not None else {})
        super().__init__(
            kind="pixelpen-printer-class",
            vid=vid,
            pid=pid,
            bcd_device=0x0300,
            speed=SPEED_FULL,
            strings=strings,
            interface=(7, 1, 2 if bidirectional else 1),
            endpoints=[EP_OUT, EP_IN] if bidirectional else [EP_OUT],
            max_packet=max_packet,
            self_powered=True,
            bus=bus,
            address=address,
        )
        self.device = device
        self.port = SimPort(device, baud=rate * 10, flow="rtscts", faults=faults, tx_buffer=fifo, clock=clock)
        self.clock = self.port.clock
        self.device_id = device_id
        self.bidirectional = bidirectional
        self.max_packet = max_packet

    def reset_device(self, dev_handle: Any) -> None:
        """USB reset: the adapter's FIFOs are emptied; the configuration is restored as the OS would."""
        self._check_present()
        self.port.reset_output()
        self.port.reset_input()
        self._claimed.clear()

    # -- transfers ---------------------------------------------------------------------------

    def bulk_write(self, dev_handle: Any, ep: int, intf: int, data: Any, timeout: int) -> int:
        """Bulk OUT: queue bytes for the device; USBTimeoutError if they do not fit in time."""
        self._check_endpoint(ep, EP_OUT, intf)
        payload = bytes(data)
        try:
            n = self.port.write(payload, self._seconds(timeout))
        except Disconnected as exc:
            raise self._gone() from exc
        except LinkTimeout as exc:
            raise usb.core.USBTimeoutError(f"Operation timed out: {exc}", _TIMEOUT_CODE, errno.ETIMEDOUT) from exc
        if n < len(payload):
            raise usb.core.USBTimeoutError(
                f"Operation timed out ({n} of {len(payload)} bytes accepted)", _TIMEOUT_CODE, errno.ETIMEDOUT
            )
        return n

    def bulk_read(self, dev_handle: Any, ep: int, intf: int, buff: Any, timeout: int) -> int:
        """Bulk IN: bytes the device sent, copied into ``buff``; USBTimeoutError if none came in time."""
        self._check_endpoint(ep, EP_IN, intf)
        if not self.bidirectional:
            raise usb.core.USBError(f"Invalid endpoint address {ep:#04x}", _PIPE_CODE, errno.EPIPE)
        try:
            data = self.port.read(len(buff), self._seconds(timeout))
        except Disconnected as exc:
            raise self._gone() from exc
        except LinkTimeout as exc:
            raise usb.core.USBTimeoutError(f"Operation timed out: {exc}", _TIMEOUT_CODE, errno.ETIMEDOUT) from exc
        if not data:
            raise usb.core.USBTimeoutError("Operation timed out", _TIMEOUT_CODE, errno.ETIMEDOUT)
        return fill(buff, data)

    def _request(self, request_type: int, request: int, value: int, index: int) -> bytes | None:
        """The printer-class requests: GET_DEVICE_ID, GET_PORT_STATUS, SOFT_RESET."""
        if request_type == 0xA1 and request == 0 and index >> 8 == 0 and value == 0:
            text = self.device_id.encode("latin-1")
            return (len(text) + 2).to_bytes(2, "big") + text
        if request_type == 0xA1 and request == 1 and index & 0xFF == 0:
            return bytes((self.port_status(),))
        if request_type in (0x21, 0x23) and request == 2 and index & 0xFF == 0:
            self.port.reset_output()
            self.port.reset_input()
            return b""
        return None

    def port_status(self) -> int:
        """The GET_PORT_STATUS byte from the device's optional ``paper_empty``/``selected``/``error``."""
        status = 0
        if getattr(self.device, "paper_empty", False):
            status |= 0x20
        if getattr(self.device, "selected", not self.port.dropped):
            status |= 0x10
        if not getattr(self.device, "error", False):
            status |= 0x08
        return status

    def close(self) -> None:
        """Stop the port and the device (its results stay readable)."""
        self.port.close()

    # -- helpers -------------------------------------------------------------------------------

    def _absence(self) -> str | None:
        if self.port.dropped:
            return "it may have been disconnected"
        return "backend closed" if self.port.closed else None

    def _gone(self) -> usb.core.USBError:
        return usb.core.USBError("No such device (it may have been disconnected)", _NO_DEVICE_CODE, errno.ENODEV)

    @staticmethod
    def _seconds(timeout_ms: int) -> float | None:
        """libusb's timeout in ms as seconds (0: forever)."""
        return None if not timeout_ms else timeout_ms / 1000.0

"""UsbPrinterLink: a Link over a USB printer-class interface (class 7) with pyusb, e.g. a USB-parallel adapter.

USB Device Class Definition for Printing Devices 1.1: bulk OUT carries the data stream, an optional
bulk IN (interface protocol 2, bidirectional) carries the device's answers, and three class
requests go to the interface:

* GET_DEVICE_ID (``bmRequestType`` 0xA1, ``bRequest`` 0, ``wValue`` configuration index,
  ``wIndex`` interface << 8 | alternate setting): the IEEE 1284 device ID, a string of
  ``KEY:value;`` pairs after a 2-byte big-endian length that counts itself;
* GET_PORT_STATUS (0xA1, 1): one byte like a Centronics status register: 0x20 paper empty,
  0x10 selected, 0x08 not error;
* SOFT_RESET (0x21, 2): flush the device's buffers and reset its bulk pipes.
"""

from __future__ import annotations

import errno as _errno
import math
from dataclasses import dataclass
from typing import Any

import usb.core
import usb.util

from pixelpen.clock import Clock
from pixelpen.drivers.stream import Link
from pixelpen.errors import Disconnected, LinkError, LinkTimeout, ParseError

PRINTER_CLASS = 7
GET_DEVICE_ID = 0
GET_PORT_STATUS = 1
SOFT_RESET = 2
CLASS_IN = 0xA1  # class request, interface recipient, device to host
CLASS_OUT = 0x21  # class request, interface recipient, host to device

PAPER_EMPTY = 0x20
SELECTED = 0x10
NOT_ERROR = 0x08

LONG_KEYS = {"MANUFACTURER": "MFG", "MODEL": "MDL", "COMMAND SET": "CMD", "CLASS": "CLS", "DESCRIPTION": "DES"}
"""IEEE 1284 long key names and the short forms ``parse_device_id`` reports them under."""

_GONE = {_errno.ENODEV, _errno.ENOENT, _errno.EIO, _errno.ESHUTDOWN}


@dataclass(frozen=True)
class PortStatus:
    """GET_PORT_STATUS decoded."""

    raw: int
    paper_empty: bool
    selected: bool
    error: bool

    @classmethod
    def from_byte(cls, value: int) -> PortStatus:
        """Decode the status byte (0x20 paper empty, 0x10 selected, 0x08 *not* error)."""
        return cls(value, bool(value & PAPER_EMPTY), bool(value & SELECTED), not value & NOT_ERROR)


def parse_device_id_string(text: str, source: str = "IEEE 1284 device ID") -> dict[str, str]:
    """Parse ``MFG:HP;MDL:7475A;CMD:HPGL;`` into a dict (long key names become MFG, MDL, CMD, CLS, DES)."""
    fields: dict[str, str] = {}
    offset = 0
    for entry in text.split(";"):
        if entry.strip():
            key, colon, value = entry.partition(":")
            key = " ".join(key.split()).upper()
            if not colon or not key:
                raise ParseError("expected KEY:value", source=source, offset=offset, token=entry)
            fields.setdefault(LONG_KEYS.get(key, key), value.strip())
        offset += len(entry) + 1
    return fields


def parse_device_id(raw: bytes, source: str = "GET_DEVICE_ID reply") -> dict[str, str]:
    """Parse a GET_DEVICE_ID reply (2-byte length + string) into a dict.

    The length is big-endian and counts its own two bytes; like CUPS, a length that only fits
    read little-endian (a known firmware bug) is accepted that way.
    """
    raw = bytes(raw)
    if len(raw) < 2:
        raise ParseError("reply shorter than its 2-byte length prefix", source=source, offset=0, token=raw)
    length = int.from_bytes(raw[:2], "big")
    if not 2 <= length <= len(raw):
        swapped = int.from_bytes(raw[:2], "little")
        if not 2 <= swapped <= len(raw):
            raise ParseError(
                f"length prefix says {length} bytes but {len(raw)} arrived (truncated reply?)",
                source=source,
                offset=0,
                token=raw[:2],
            )
        length = swapped
    return parse_device_id_string(raw[2:length].decode("latin-1"), source)


def _is_printer(dev: Any) -> bool:
    try:
        return any(intf.bInterfaceClass == PRINTER_CLASS for cfg in dev for intf in cfg)
    except (usb.core.USBError, ValueError, NotImplementedError):
        return False


def find_printers(
    vid: int | None = None, pid: int | None = None, serial_number: str | None = None, backend: Any = None
) -> list[Any]:
    """USB devices with a printer-class interface, optionally filtered (LinkError when there is no USB backend)."""
    match: dict[str, int] = {}
    if vid is not None:
        match["idVendor"] = vid
    if pid is not None:
        match["idProduct"] = pid
    try:
        found = list(usb.core.find(find_all=True, backend=backend, custom_match=_is_printer, **match))
    except usb.core.NoBackendError as exc:
        raise LinkError("no USB backend available (pyusb found no libusb); install libusb-1.0") from exc
    if serial_number is not None:
        found = [d for d in found if _serial_of(d) == serial_number]
    return found


def _serial_of(dev: Any) -> str | None:
    try:
        return dev.serial_number
    except (usb.core.USBError, ValueError, NotImplementedError):
        return None


def _describe(dev: Any) -> str:
    return f"{dev.idVendor:04x}:{dev.idProduct:04x} (bus {dev.bus} address {dev.address})"


class UsbPrinterLink(Link):
    """A Link over a USB printer-class interface: bulk OUT in max-packet chunks, bulk IN if the interface has one."""

    def __init__(
        self,
        vid: int | None = None,
        pid: int | None = None,
        *,
        device: Any = None,
        backend: Any = None,
        serial_number: str | None = None,
        timeout: float | None = 2.0,
        write_timeout: float | None = 10.0,
        clock: Clock | None = None,
    ) -> None:
        if device is None:
            found = find_printers(vid, pid, serial_number, backend)
            if not found:
                others = find_printers(backend=backend)
                wanted = f"{vid:04x}" if vid is not None else "any"
                wanted += f":{pid:04x}" if pid is not None else ":any"
                if serial_number:
                    wanted += f" serial {serial_number!r}"
                raise LinkError(
                    f"no USB printer-class device {wanted}; printer-class devices present: "
                    f"{', '.join(_describe(d) for d in others) or 'none'}"
                )
            device = found[0]
        self.device = device
        name = f"usb:{device.idVendor:04x}:{device.idProduct:04x}"
        if clock is None:
            used_backend = backend if backend is not None else getattr(getattr(device, "_ctx", None), "backend", None)
            clock = getattr(used_backend, "clock", None)
        super().__init__(name, timeout=timeout, write_timeout=write_timeout, clock=clock)
        self._detached = False
        self._stash = b""
        try:
            self._claim()
        except usb.core.USBError as exc:
            usb.util.dispose_resources(device)
            raise LinkError(f"{name}: cannot claim the printer interface: {exc}") from exc

    def _claim(self) -> None:
        dev = self.device
        try:
            cfg = dev.get_active_configuration()
        except usb.core.USBError:
            dev.set_configuration()
            cfg = dev.get_active_configuration()
        printers = [i for i in cfg if i.bInterfaceClass == PRINTER_CLASS]
        if not printers:
            raise LinkError(f"{self.name}: the active configuration has no printer-class (7) interface")
        # prefer the bidirectional protocol (2), then 1284.4 (3), then unidirectional (1)
        rank = {2: 0, 3: 1, 1: 2}
        intf = min(printers, key=lambda i: rank.get(i.bInterfaceProtocol, 3))
        self.interface = intf
        try:
            if dev.is_kernel_driver_active(intf.bInterfaceNumber):
                dev.detach_kernel_driver(intf.bInterfaceNumber)
                self._detached = True
        except (NotImplementedError, usb.core.USBError):
            self._log.debug("%s: kernel driver state unknown; claiming anyway", self.name)
        usb.util.claim_interface(dev, intf)
        if sum(1 for i in cfg if i.bInterfaceNumber == intf.bInterfaceNumber) > 1:
            intf.set_altsetting()

        def endpoint(direction: int) -> Any:
            return usb.util.find_descriptor(
                intf,
                custom_match=lambda e: (
                    usb.util.endpoint_direction(e.bEndpointAddress) == direction
                    and usb.util.endpoint_type(e.bmAttributes) == usb.util.ENDPOINT_TYPE_BULK
                ),
            )

        self.ep_out = endpoint(usb.util.ENDPOINT_OUT)
        self.ep_in = endpoint(usb.util.ENDPOINT_IN)
        if self.ep_out is None:
            raise LinkError(f"{self.name}: printer interface {intf.bInterfaceNumber} has no bulk OUT endpoint")
        self.max_packet = int(self.ep_out.wMaxPacketSize) or 64

    # -- class requests ---------------------------------------------------------------------

    def raw_device_id(self) -> bytes:
        """The GET_DEVICE_ID reply as sent (length prefix included)."""
        intf = self.interface
        cfg_index = self.device.get_active_configuration().index
        reply = self._control(
            CLASS_IN, GET_DEVICE_ID, cfg_index, (intf.bInterfaceNumber << 8) | intf.bAlternateSetting, 1023
        )
        return bytes(reply)

    def device_id(self) -> dict[str, str]:
        """The IEEE 1284 device ID as a dict: MFG, MDL, CMD, CLS, DES and whatever else the device sends."""
        return parse_device_id(self.raw_device_id(), f"{self.name} GET_DEVICE_ID")

    def port_status(self) -> PortStatus:
        """GET_PORT_STATUS: paper empty, selected, error."""
        reply = self._control(CLASS_IN, GET_PORT_STATUS, 0, self.interface.bInterfaceNumber, 1)
        if len(reply) != 1:
            raise ParseError(
                f"expected 1 status byte, got {len(reply)}", source=f"{self.name} GET_PORT_STATUS", token=bytes(reply)
            )
        return PortStatus.from_byte(reply[0])

    def soft_reset(self) -> None:
        """SOFT_RESET: the device flushes its buffers and resets its bulk pipes; unread input is dropped here too."""
        self._control(CLASS_OUT, SOFT_RESET, 0, self.interface.bInterfaceNumber, None)
        self._stash = b""
        self._rx.clear()

    def _control(self, request_type: int, request: int, value: int, index: int, length: int | None) -> Any:
        self._check_open()
        try:
            return self.device.ctrl_transfer(request_type, request, value, index, length, self._ms(self.timeout))
        except usb.core.USBError as exc:
            raise self._failure(exc, f"class request {request}") from exc

    # -- primitives -------------------------------------------------------------------------

    @staticmethod
    def _ms(wait: float | None) -> int:
        """A pyusb timeout in ms (libusb reads 0 as 'forever', so a poll waits 1 ms)."""
        if wait is None or math.isinf(wait):
            return 0
        return max(1, math.ceil(wait * 1000))

    def _write_raw(self, data: bytes, wait: float | None) -> int:
        deadline = None if wait is None else self.clock.now() + wait
        sent = 0
        while sent < len(data):
            chunk = data[sent : sent + self.max_packet]
            remaining = None if deadline is None else deadline - self.clock.now()
            if remaining is not None and remaining <= 0:
                break
            try:
                n = self.device.write(self.ep_out, chunk, self._ms(remaining))
            except usb.core.USBTimeoutError as exc:
                raise LinkTimeout(
                    f"{self.name}: bulk OUT timed out after {sent} of {len(data)} bytes (device busy or off-line?)"
                ) from exc
            except usb.core.USBError as exc:
                raise self._failure(exc, "bulk OUT") from exc
            sent += n
            if n < len(chunk):
                break
        return sent

    def _read_raw(self, wait: float | None) -> bytes:
        if self._stash:
            out, self._stash = self._stash, b""
            return out
        return self._read_packet(wait)

    def _read_packet(self, wait: float | None) -> bytes:
        """One bulk IN transfer of one max packet: any packet ends it, so a timeout never loses data."""
        if self.ep_in is None:
            raise LinkError(
                f"{self.name}: interface {self.interface.bInterfaceNumber} is unidirectional (no bulk IN endpoint); "
                "the device cannot answer"
            )
        try:
            return bytes(self.device.read(self.ep_in, int(self.ep_in.wMaxPacketSize or 64), self._ms(wait)))
        except usb.core.USBTimeoutError:
            return b""
        except usb.core.USBError as exc:
            raise self._failure(exc, "bulk IN") from exc

    def _raw_in_waiting(self) -> int:
        if self.ep_in is not None:
            self._stash += self._read_packet(0.0)
        return len(self._stash)

    def _reset_input_raw(self) -> None:
        self._stash = b""

    def _close_raw(self) -> None:
        try:
            usb.util.release_interface(self.device, self.interface)
            if self._detached:
                self.device.attach_kernel_driver(self.interface.bInterfaceNumber)
        except (usb.core.USBError, NotImplementedError):
            self._log.debug("%s: could not release the interface (device gone?)", self.name)
        finally:
            usb.util.dispose_resources(self.device)

    def _failure(self, exc: usb.core.USBError, what: str) -> LinkError:
        if exc.errno in _GONE or "no such device" in str(exc).lower():
            return Disconnected(f"{self.name}: device disconnected during {what}: {exc}")
        return LinkError(f"{self.name}: {what} failed: {exc}")

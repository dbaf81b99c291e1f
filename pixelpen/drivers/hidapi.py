"""HID devices through cython-hidapi (PyPI ``hidapi``): enumerate with filters, open by path or VID:PID, HidapiLink.

cython-hidapi's Linux wheel holds two modules with one API: ``hidraw`` (``backend="hidraw"``, the default
here: the kernel's hidraw nodes, the kernel driver stays bound, USB, Bluetooth and I²C devices, udev rule on
``KERNEL=="hidraw*"``) and ``hid`` (``backend="libusb"``: libusb, USB only, detaches the kernel driver
while open so the device stops acting as a mouse or keyboard meanwhile; paths look like ``1-2.3:1.0``
(bus-ports:configuration.interface); needs a ``SUBSYSTEM=="usb"`` udev rule).  Other platforms have only
``hid``.

The report-ID rules (hidapi.h; cython-hidapi passes the bytes through) are applied here once, so callers of
:class:`HidapiLink` see reports as the descriptor lays them out (ID byte first when numbered, none otherwise),
as :class:`~pixelpen.drivers.reports.ReportLink` says:

* ``write`` and ``send_feature_report`` take the report ID as the first byte, **0x00 for a device that does
  not number its reports** (hidapi strips it before the report goes out): the link prepends it;
* ``get_feature_report(report_id, max_length)`` returns the report with its ID first, and ID 0 first for an
  unnumbered device: the link strips that 0;
* ``read`` returns the ID byte only for numbered reports: passed through;
* ``read(n, 0)`` blocks forever unless the handle is non-blocking: the link sets non-blocking mode and always
  reads with a timeout of at most :data:`READ_SLICE` seconds, so Ctrl-C is honoured within that time and
  ``read_report(None)`` waits forever in slices;
* a read on a removed device raises ``OSError("read error")``: :class:`~pixelpen.errors.Disconnected`.

hidapi's ``open_path`` says only ``open failed``; when the node exists but this user may not open it, the
error is :func:`pixelpen.drivers.udev.permission_diagnosis` (which udev rule or group is missing).
``module=`` takes any module-like object with cython-hidapi's API (``pixelpen.sim.transports.hidapi.SimHidapi``
runs simulated devices behind it).
"""

from __future__ import annotations

import contextlib
import glob
import importlib
import importlib.util
import math
import os
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.identity import DeviceId
from pixelpen.drivers.udev import permission_diagnosis
from pixelpen.errors import (
    ConfigError,
    Disconnected,
    InvalidArgument,
    InvalidArgumentType,
    LinkError,
    LinkTimeout,
    ParseError,
    PixelpenError,
    ProtocolError,
)

BACKENDS = {"hidraw": "hidraw", "libusb": "hid", "hid": "hid"}
"""Backend name -> cython-hidapi module (``hid`` is an alias of ``libusb``, after the module's name)."""
READ_SLICE = 0.1
"""Longest single wait inside hidapi: a Ctrl-C is seen at most this long after it is pressed."""
MAX_REPORT = 16384
"""The kernel's HID_MAX_BUFFER_SIZE: no report is longer (the read buffer size)."""
MAX_DESCRIPTOR = 4096
"""HID_MAX_DESCRIPTOR_SIZE (hidraw's HIDIOCGRDESC limit)."""
BUS_NAMES = {0: "unknown", 1: "usb", 2: "bluetooth", 3: "i2c", 4: "spi", 5: "virtual"}
"""hidapi's ``bus_type`` (hid_bus_type, hidapi >= 0.13) -> DeviceId.bus."""
_GONE_WORDS = ("no such device", "disconnected", "device not configured", "no device")
_SPEC_SOURCE = "HID device spec"
_HEX_ID = re.compile(r"(?:0[xX])?[0-9A-Fa-f]{1,4}")


# ---- descriptor facts the transports need (the full parser lives in devices/hid, which drivers may not import) ----

def short_items(descriptor: bytes) -> Iterator[tuple[int, int, int, int]]:
    """(offset, tag and type bits, size, unsigned value) of each short item (HID 1.11 §6.2.2.2); long items skipped."""
    i, n = 0, len(descriptor)
    while i < n:
        prefix = descriptor[i]
        if prefix >> 4 == 0xF:  # long item: bDataSize, bLongItemTag, data (§6.2.2.3); any tag-15 prefix, as the
            # kernel's fetch_item and the parser (devices/hid/items.py) read it
            i += 3 + (descriptor[i + 1] if i + 1 < n else 0)
            continue
        size = (0, 1, 2, 4)[prefix & 0x03]
        if i + 1 + size > n:
            return
        yield i, prefix & 0xFC, size, int.from_bytes(descriptor[i + 1 : i + 1 + size], "little")
        i += 1 + size


def numbered_reports(descriptor: bytes) -> bool:
    """True when the descriptor has a Report ID item (0x85): every report then starts with its ID byte."""
    return any(tag == 0x84 for _, tag, _, _ in short_items(descriptor))


def top_level_usages(descriptor: bytes) -> list[tuple[int, int]]:
    """(usage page, usage) of each top-level collection, as hidapi's hidraw backend lists them (one entry each)."""
    found: list[tuple[int, int]] = []
    page = usage = depth = 0
    for _, tag, size, value in short_items(descriptor):
        if tag == 0x04:
            page = value
        elif tag == 0x08:
            usage, page = (value & 0xFFFF, value >> 16) if size == 4 else (value, page)
        elif tag == 0xA0:
            if depth == 0:
                found.append((page, usage))
            depth += 1
            usage = 0
        elif tag == 0xC0:
            depth = max(0, depth - 1)
        elif tag & 0x0C == 0:  # another Main item resets the locals
            usage = 0
    return found


# ---- enumeration ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class HidInfo:
    """One entry of hidapi's enumeration: one top-level collection of one device node."""

    path: str
    vendor_id: int
    product_id: int
    serial: str = ""
    manufacturer: str = ""
    product: str = ""
    interface: int = -1
    usage_page: int = 0
    usage: int = 0
    bus: str = "unknown"
    release: int = 0
    raw_path: bytes = b""
    """The path as hidapi gave it (``open_path`` takes these bytes)."""

    @classmethod
    def from_dict(cls, entry: dict[str, Any]) -> HidInfo:
        """From one dict of ``hid.enumerate()``."""
        raw = entry.get("path", b"")
        raw = raw if isinstance(raw, bytes) else str(raw).encode()
        return cls(path=raw.decode("utf-8", "replace"), vendor_id=int(entry.get("vendor_id") or 0),
                   product_id=int(entry.get("product_id") or 0), serial=entry.get("serial_number") or "",
                   manufacturer=entry.get("manufacturer_string") or "", product=entry.get("product_string") or "",
                   interface=int(entry.get("interface_number", -1)), usage_page=int(entry.get("usage_page") or 0),
                   usage=int(entry.get("usage") or 0), bus=BUS_NAMES.get(int(entry.get("bus_type") or 0), "unknown"),
                   release=int(entry.get("release_number") or 0), raw_path=raw)

    @property
    def device_id(self) -> DeviceId:
        """Who this is (its ``key`` survives replug; ``path`` is where it is now)."""
        name = self.product or self.manufacturer
        return DeviceId(self.bus, self.vendor_id, self.product_id, self.serial, name, self.interface, self.path)

    def __str__(self) -> str:
        name = " ".join(s for s in (self.manufacturer, self.product) if s) or "HID device"
        serial = f" serial {self.serial}" if self.serial else ""
        return (f"{self.path}: {name} {self.vendor_id:04x}:{self.product_id:04x}{serial} interface {self.interface} "
                f"usage {self.usage_page:#06x}:{self.usage:#06x}")


def hid_module(backend: str = "hidraw") -> Any:
    """The cython-hidapi module of ``backend`` (``hidraw`` or ``libusb``); ConfigError saying what to install."""
    try:
        name = BACKENDS[backend]
    except KeyError:
        raise ConfigError(f"unknown hidapi backend {backend!r}; known: hidraw, libusb") from None
    try:
        return importlib.import_module(name)
    except ImportError:
        if name == "hidraw" and importlib.util.find_spec("hid") is not None:
            raise ConfigError("hidapi's hidraw module is Linux-only; use backend='libusb' here") from None
        raise ConfigError("HID devices need cython-hidapi: pip install hidapi") from None


def _check_filter(value: int | None, what: str) -> int | None:
    if value is not None and (not isinstance(value, int) or isinstance(value, bool) or not 0 <= value <= 0xFFFF):
        raise InvalidArgument(f"enumerate_hid: {what} must be 0..0xffff or None, got {value!r}")
    return value


def enumerate_hid(*, vendor_id: int | None = None, product_id: int | None = None, usage_page: int | None = None,
                  usage: int | None = None, serial: str | None = None, interface: int | None = None,
                  backend: str = "hidraw", module: Any = None) -> list[HidInfo]:
    """The HID devices hidapi lists (one entry per top-level collection) that match every filter given."""
    for value, what in ((vendor_id, "vendor_id"), (product_id, "product_id"), (usage_page, "usage_page"),
                        (usage, "usage")):
        _check_filter(value, what)
    mod = module if module is not None else hid_module(backend)
    try:
        entries = mod.enumerate(vendor_id or 0, product_id or 0)
    except OSError as exc:
        raise LinkError(f"hidapi ({backend}) could not enumerate HID devices: {exc}") from exc
    found = []
    for entry in entries:
        info = HidInfo.from_dict(entry)
        if ((vendor_id is None or info.vendor_id == vendor_id) and (product_id is None or info.product_id == product_id)
                and (usage_page is None or info.usage_page == usage_page) and (usage is None or info.usage == usage)
                and (serial is None or info.serial == serial) and (interface is None or info.interface == interface)):
            found.append(info)
    return found


# ---- open specs ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class HidSpec:
    """What ``open_hid`` was asked for: a path, or vendor/product IDs with an optional serial and interface."""

    path: str | None = None
    vendor_id: int | None = None
    product_id: int | None = None
    serial: str | None = None
    interface: int | None = None


def parse_hid_spec(spec: str) -> HidSpec:
    """``/dev/hidraw3``, ``1-2:1.0``, ``sim:mouse:0`` (paths), ``046d:c52b``, ``046d:c52b:SERIAL``, each ``@interface``.

    A spec whose first ``:``-separated field is 1-4 hex digits is VID:PID; anything else is a path
    (``@`` is then part of the path).  Errors name the field and its offset in the spec.
    """
    if not isinstance(spec, str):
        raise InvalidArgumentType(f"a HID device spec is a str, not {type(spec).__name__}")
    if not spec.strip():
        raise ParseError("empty HID device spec (a path, VID:PID, VID:PID:SERIAL, each optionally @interface)",
                         source=_SPEC_SOURCE, offset=0, token=spec)
    head, colon, rest = spec.partition(":")
    if not colon or not _HEX_ID.fullmatch(head):
        return HidSpec(path=spec)
    body, at, iface_text = rest.rpartition("@") if "@" in rest else (rest, "", "")
    interface = None
    if at:
        if not iface_text.isdigit() or int(iface_text) > 255:
            raise ParseError("interface after '@' must be a USB interface number 0..255", source=_SPEC_SOURCE,
                             offset=len(head) + len(body) + 2, token=iface_text)
        interface = int(iface_text)
    pid_text, colon2, serial = body.partition(":")
    if not _HEX_ID.fullmatch(pid_text):
        raise ParseError(f"product ID after vendor ID {head} must be 1-4 hex digits", source=_SPEC_SOURCE,
                         offset=len(head) + 1, token=pid_text)
    if colon2 and not serial:
        raise ParseError("serial number after the second ':' is empty", source=_SPEC_SOURCE,
                         offset=len(head) + len(pid_text) + 2, token=spec)
    return HidSpec(vendor_id=int(head, 16), product_id=int(pid_text, 16), serial=serial if colon2 else None,
                   interface=interface)


def open_hid(spec: str, *, backend: str = "hidraw", module: Any = None, clock: Clock | None = None,
             numbered: bool | None = None, max_report: int = MAX_REPORT, sysfs: str = "/sys") -> HidapiLink:
    """Open the HID device ``spec`` names (see :func:`parse_hid_spec`) as a HidapiLink.

    LinkError when nothing matches (listing what is there), or when the device cannot be opened (with
    the permission diagnosis when the node denies this user).
    """
    wanted = parse_hid_spec(spec)
    mod = module if module is not None else hid_module(backend)
    present = enumerate_hid(backend=backend, module=mod)
    if wanted.path is not None:
        matches = [i for i in present if i.path == wanted.path]
        info = matches[0] if matches else HidInfo(wanted.path, 0, 0, raw_path=os.fsencode(wanted.path))
    else:
        matches = [i for i in present if i.vendor_id == wanted.vendor_id and i.product_id == wanted.product_id
                   and (wanted.serial is None or i.serial == wanted.serial)
                   and (wanted.interface is None or i.interface == wanted.interface)]
        if not matches:
            same = [str(i) for i in present if i.vendor_id == wanted.vendor_id and i.product_id == wanted.product_id]
            ids = sorted({f"{i.vendor_id:04x}:{i.product_id:04x}" for i in present})
            listed = "; ".join(same) or f"none with these IDs (present: {', '.join(ids) or 'no HID devices at all'})"
            raise LinkError(f"no HID device matches {spec!r} ({backend}); {listed}")
        info = matches[0]
    device = mod.device()
    try:
        device.open_path(info.raw_path)
    except OSError as exc:
        raise _open_failure(info, backend, exc, present, sysfs) from None
    return HidapiLink(device, info, backend=backend, clock=clock, numbered=numbered, max_report=max_report,
                      sysfs=sysfs)


def _open_failure(info: HidInfo, backend: str, exc: OSError, present: list[HidInfo], sysfs: str) -> LinkError:
    """Why ``open_path`` failed: not there, not allowed (which udev rule), or hidapi's own words."""
    if not any(i.path == info.path for i in present):
        paths = ", ".join(sorted({i.path for i in present})) or "none"
        return LinkError(f"no HID device at {info.path!r} ({backend}); paths present: {paths}")
    node = info.path
    if node.startswith("/dev/") or re.match(r"^\d+-[\d.]+:\d+\.\d+$", node):
        checked = node if node.startswith("/dev/") else ""
        if not checked or isinstance(exc, PermissionError) or not os.access(checked, os.R_OK | os.W_OK):
            text = permission_diagnosis(node, vendor_id=info.vendor_id or None, product_id=info.product_id or None,
                                        sysfs=sysfs)
            return LinkError(f"cannot open {info}: {text}")
    return LinkError(f"cannot open {info} ({backend}): hidapi: {exc}")


# ---- the link ------------------------------------------------------------------------------------

TOLERANCE = 1e-6
"""A deadline this close (seconds) counts as reached (float sums of slices fall just short of it)."""


def read_in_slices(read_once: Callable[[int], bytes | None], clock: Clock, timeout: float | None,
                   what: str) -> bytes | None:
    """Call ``read_once(ms)`` with waits of at most READ_SLICE until it returns a report or ``timeout`` passes.

    ``timeout`` None waits forever (in slices, so Ctrl-C is seen between them), 0 polls once.  The number of
    slices is bounded by the timeout as well as the clock, so a clock that does not move (a simulated clock
    over real hardware) cannot make a read hang.
    """
    if timeout is not None and (not isinstance(timeout, (int, float)) or math.isnan(timeout)):
        raise InvalidArgument(f"{what}: read timeout must be seconds or None, got {timeout!r}")
    deadline = None if timeout is None or math.isinf(timeout) else clock.now() + max(0.0, timeout)
    slices = None if deadline is None else math.ceil(max(0.0, float(timeout or 0)) / READ_SLICE) + 1
    first = True
    while True:
        wait = READ_SLICE
        if deadline is not None:
            remaining = deadline - clock.now()
            if not first and remaining <= TOLERANCE:
                if remaining > 0:
                    clock.sleep(remaining)  # the clock reaches the deadline, so a caller looping until it ends
                return None
            wait = min(READ_SLICE, max(0.0, remaining))
        first = False
        report = read_once(max(0, math.ceil(wait * 1000 - TOLERANCE * 1000)))
        if report is not None:
            return report
        if slices is not None:
            slices -= 1
            if slices <= 0:
                return None



class HidapiLink:
    """A ReportLink over an open hidapi device: reads with timeouts in slices, the report-ID rules, errors mapped."""

    def __init__(self, device: Any, info: HidInfo, *, backend: str = "hidraw", clock: Clock | None = None,
                 numbered: bool | None = None, max_report: int = MAX_REPORT, sysfs: str = "/sys") -> None:
        if not isinstance(max_report, int) or not 1 <= max_report <= MAX_REPORT:
            raise InvalidArgument(f"{info.path}: max_report must be 1..{MAX_REPORT} bytes, got {max_report!r}")
        self.device = device
        """The open cython-hidapi ``device`` (or a module-like fake's)."""
        self.info = info
        self.backend = backend
        self.clock = clock if clock is not None else REAL_CLOCK
        self.sysfs = sysfs
        self.max_report = max_report
        """The read buffer: the kernel hands out one report per read, cut to this length (the longest input
        report, when known, saves hidapi a 16 KB buffer per read; an emulated node that is a byte stream, as
        umockdev's, needs the exact report length)."""
        self._descriptor: bytes | None = None
        self._numbered = numbered
        self._closed = False
        setter = getattr(device, "set_nonblocking", None)
        try:
            self._nonblocking = callable(setter) and setter(1) == 0
        except (OSError, ValueError):
            self._nonblocking = False

    @property
    def device_id(self) -> DeviceId:
        """Who the device is (stable across replug: ``device_id.key``)."""
        return self.info.device_id

    @property
    def report_descriptor(self) -> bytes:
        """The report descriptor: hidapi >= 0.14's ``get_report_descriptor``, else sysfs for a hidraw or libusb path."""
        if self._descriptor is None:
            self._check_open()
            getter = getattr(self.device, "get_report_descriptor", None)
            error: Exception | None = None
            if getter is not None:
                try:
                    self._descriptor = bytes(getter())
                except OSError as exc:
                    error = exc
            if self._descriptor is None:
                self._descriptor = self._sysfs_descriptor()
            if self._descriptor is None:
                why = f"hidapi: {error}" if error else "this hidapi has no get_report_descriptor (needs >= 0.14)"
                raise LinkError(f"{self.info.path}: cannot read the report descriptor ({why}; no sysfs copy found)")
        return self._descriptor

    def _sysfs_descriptor(self) -> bytes | None:
        """The kernel's copy: /sys/class/hidraw/hidrawN/device/report_descriptor (or under the USB interface)."""
        path = self.info.path
        m = re.match(r"^/dev/(hidraw\d+)$", path)
        candidates = [str(Path(self.sysfs, "class/hidraw", m.group(1), "device/report_descriptor"))] if m else \
            sorted(glob.glob(str(Path(self.sysfs, "bus/usb/devices", glob.escape(path), "*/report_descriptor"))))
        for candidate in candidates:
            try:
                with open(candidate, "rb") as f:
                    return f.read(MAX_DESCRIPTOR + 1)[:MAX_DESCRIPTOR]
            except OSError:
                continue
        return None

    @property
    def numbered(self) -> bool:
        """True when the device numbers its reports (from the descriptor unless given to the constructor)."""
        if self._numbered is None:
            self._numbered = numbered_reports(self.report_descriptor)
        return self._numbered

    # ---- reports ---------------------------------------------------------------------------------
    def read_report(self, timeout: float | None = None) -> bytes | None:
        """The next input report, or None after ``timeout`` seconds on the clock (None: wait, 0: poll)."""
        self._check_open()
        return read_in_slices(self._read_once, self.clock, timeout, self.info.path)

    def _read_once(self, ms: int) -> bytes | None:
        """One hidapi read waiting at most ``ms`` (0 only on a non-blocking handle, where it returns at once)."""
        try:
            data = self.device.read(self.max_report, ms if ms > 0 or self._nonblocking else 1)
        except OSError as exc:
            raise Disconnected(f"{self.info.path}: the device was removed during a read "
                               f"(hidapi: {self._detail(str(exc))})") from None
        except PixelpenError:
            raise
        except ValueError as exc:  # cython-hidapi: "not open"
            raise LinkError(f"{self.info.path}: read on a closed device ({exc})") from None
        return bytes(data) if data else None

    def write_report(self, report: bytes) -> None:
        """Send an output report: ID first when numbered; hidapi's 0x00 is put in front for an unnumbered device."""
        data = self._outgoing(report, "output")
        try:
            result = self.device.write(data)
        except OSError as exc:
            raise self._failure("write an output report", self._detail(str(exc))) from None
        if result < 0:
            raise self._failure("write an output report", self._detail())

    def get_feature(self, report_id: int) -> bytes:
        """GET_REPORT(Feature): ID byte first when numbered; an unnumbered device has only ID 0, returned without it."""
        self._check_open()
        if not isinstance(report_id, int) or isinstance(report_id, bool):
            raise InvalidArgumentType(f"{self.info.path}: report ID must be an int, not {type(report_id).__name__}")
        if self.numbered and not 1 <= report_id <= 255:
            raise InvalidArgument(f"{self.info.path}: this device numbers its reports: feature report ID must be "
                                  f"1..255, got {report_id}")
        if not self.numbered and report_id != 0:
            raise InvalidArgument(f"{self.info.path}: this device does not number its reports: the only feature "
                                  f"report is ID 0, got {report_id}")
        try:
            data = bytes(self.device.get_feature_report(report_id, MAX_REPORT + 1))
        except OSError as exc:
            raise self._failure(f"get feature report {report_id}", self._detail(str(exc))) from None
        if not data:
            raise ProtocolError(f"feature report {report_id} came back empty", device=self.info.path,
                                command=f"get feature {report_id}")
        return data if self.numbered else data[1:]

    def send_feature(self, report: bytes) -> None:
        """SET_REPORT(Feature): ID first when numbered; hidapi's 0x00 is put in front for an unnumbered device."""
        data = self._outgoing(report, "feature")
        try:
            result = self.device.send_feature_report(data)
        except OSError as exc:
            raise self._failure("send a feature report", self._detail(str(exc))) from None
        if result < 0:
            raise self._failure("send a feature report", self._detail())

    def _outgoing(self, report: bytes, kind: str) -> bytes:
        """The buffer hidapi wants for ``report``: as is when numbered (ID 1..255 first), 0x00 + report otherwise."""
        self._check_open()
        if not isinstance(report, (bytes, bytearray, memoryview)):
            raise InvalidArgumentType(f"{self.info.path}: a {kind} report is bytes, not {type(report).__name__}")
        report = bytes(report)
        if not report:
            raise InvalidArgument(f"{self.info.path}: empty {kind} report")
        if len(report) > MAX_REPORT:
            raise InvalidArgument(f"{self.info.path}: {kind} report of {len(report)} bytes exceeds {MAX_REPORT}")
        if self.numbered:
            if report[0] == 0:
                raise InvalidArgument(f"{self.info.path}: this device numbers its reports, so a {kind} report starts "
                                      "with its report ID 1..255, not 0")
            return report
        return b"\x00" + report

    def _detail(self, raised: str = "") -> str:
        """What went wrong in hidapi's words: the exception's text and the device's last error, when it has one."""
        try:
            last = str(self.device.error() or "")
        except (AttributeError, OSError, ValueError):
            last = ""
        return ": ".join(t for t in (raised, "" if last == "Success" else last) if t) or "failed"

    def _failure(self, what: str, detail: str) -> LinkError | ProtocolError:
        """The error for a failed request, from hidapi's words (removed, timed out, stalled, other)."""
        lower = detail.lower()
        message = f"{self.info.path}: cannot {what} (hidapi: {detail})"
        if any(word in lower for word in _GONE_WORDS):
            return Disconnected(message)
        if "timed out" in lower:
            return LinkTimeout(message)
        if "broken pipe" in lower:
            return ProtocolError(f"{message}: the device refused the request (STALL)", device=self.info.path,
                                 command=what)
        return LinkError(message)

    def _check_open(self) -> None:
        if self._closed:
            raise LinkError(f"{self.info.path}: the HID link is closed")

    def close(self) -> None:
        """Close the hidapi handle; calling it again does nothing."""
        if not self._closed:
            self._closed = True
            with contextlib.suppress(OSError):
                self.device.close()

    def __enter__(self) -> HidapiLink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<HidapiLink {self.backend} {self.info}{' closed' if self._closed else ''}>"

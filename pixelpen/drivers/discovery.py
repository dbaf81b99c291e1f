"""Finding devices: serial ports, USB devices, HID devices, known USB IDs, and asking a device who it is.

Nothing here can hang: listing is best effort (a missing libusb or hidapi gives an empty list) and
every probe of a device runs with short timeouts.  ``discover()`` only lists unless asked to probe,
because probing sends bytes (``IN;OI;``, ``V``, ``$I``) to whatever is attached.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any, Final

from serial.tools import list_ports

from pixelpen.drivers.stream import Link
from pixelpen.errors import ConfigError, LinkError, ParseError

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class KnownDevice:
    """What a USB vendor:product ID is: a name, a kind, and the pixelpen model it suggests (if any)."""

    name: str
    kind: str
    """``plotter``, ``usb-serial`` (a UART bridge: anything RS-232 may be behind it) or ``usb-parallel``."""
    model: str | None = None


KNOWN_USB_IDS: Final[dict[tuple[int, int], KnownDevice]] = {
    (0x04D8, 0xFD92): KnownDevice("EiBotBoard (AxiDraw, EggBot)", "plotter", "axidraw"),
    (0x2341, 0x0043): KnownDevice("Arduino Uno (GRBL controller?)", "usb-serial", "grbl"),
    (0x2341, 0x0001): KnownDevice("Arduino Uno (GRBL controller?)", "usb-serial", "grbl"),
    (0x2A03, 0x0043): KnownDevice("Arduino Uno (GRBL controller?)", "usb-serial", "grbl"),
    (0x2341, 0x0042): KnownDevice("Arduino Mega 2560 (GRBL controller?)", "usb-serial", "grbl"),
    (0x0403, 0x6001): KnownDevice("FTDI FT232R USB-serial", "usb-serial"),
    (0x0403, 0x6010): KnownDevice("FTDI FT2232 USB-serial", "usb-serial"),
    (0x0403, 0x6014): KnownDevice("FTDI FT232H USB-serial/MPSSE", "usb-serial"),
    (0x0403, 0x6015): KnownDevice("FTDI FT-X USB-serial", "usb-serial"),
    (0x067B, 0x2303): KnownDevice("Prolific PL2303 USB-serial", "usb-serial"),
    (0x1A86, 0x7523): KnownDevice("QinHeng CH340 USB-serial", "usb-serial"),
    (0x1A86, 0x5523): KnownDevice("QinHeng CH341 USB-serial", "usb-serial"),
    (0x1A86, 0x55D4): KnownDevice("QinHeng CH9102 USB-serial", "usb-serial"),
    (0x10C4, 0xEA60): KnownDevice("Silicon Labs CP210x USB-serial", "usb-serial"),
    (0x067B, 0x2305): KnownDevice("Prolific PL2305 USB-parallel (IEEE-1284 Controller)", "usb-parallel"),
    (0x1A86, 0x7584): KnownDevice("QinHeng CH340S USB-parallel", "usb-parallel"),
}
"""USB IDs of plotter controllers and of the adapters plotters hide behind."""

FAMILIES: Final = ("hpgl", "ebb", "grbl")
_PROBE_BAUD: Final = {"hpgl": 9600, "ebb": 9600, "grbl": 115200}
_MODEL_FAMILY: Final = {"axidraw": "ebb", "grbl": "grbl"}
GRBL_BOOT_SECONDS: Final = 2.0
"""How long a probe waits for a board that looks like a GRBL Arduino (it reboots when the port opens)."""


@dataclass(frozen=True)
class Identity:
    """A device's answer to "who are you": family, model, firmware version and the raw reply."""

    family: str
    model: str
    firmware: str | None
    raw: str


@dataclass(frozen=True)
class DiscoveredDevice:
    """One device found: kind (serial, usb, hid), where to open it, what it seems to be."""

    kind: str
    path: str
    description: str
    vid: int | None = None
    pid: int | None = None
    serial_number: str | None = None
    model: str | None = None
    """Best guess of the pixelpen model (from the USB ID, the IEEE 1284 ID or a probe)."""
    identity: Identity | None = None


def _known(vid: int | None, pid: int | None) -> KnownDevice | None:
    return None if vid is None or pid is None else KNOWN_USB_IDS.get((vid, pid))


def list_serial_ports() -> list[DiscoveredDevice]:
    """Serial ports the OS lists, with USB IDs and a model guess where the adapter is known."""
    try:
        ports = list_ports.comports()
    except Exception as exc:  # noqa: BLE001 - sysfs/registry quirks must not break discovery
        _log.debug("listing serial ports failed: %s", exc)
        return []
    found = []
    for p in sorted(ports, key=lambda p: p.device):
        known = _known(p.vid, p.pid)
        description = p.description if p.description and p.description != "n/a" else (known.name if known else p.device)
        found.append(
            DiscoveredDevice(
                "serial", p.device, description, p.vid, p.pid, p.serial_number, known.model if known else None
            )
        )
    return found


def list_usb_devices(backend: Any = None) -> list[DiscoveredDevice]:
    """USB devices pyusb sees (empty when there is no libusb/backend); kind ``usb-printer`` for printer class."""
    try:
        import usb.core

        devices = list(usb.core.find(find_all=True, backend=backend))
    except Exception as exc:  # noqa: BLE001 - NoBackendError, permission or bus errors: nothing to list
        _log.debug("listing USB devices failed: %s", exc)
        return []
    found = []
    for dev in devices:
        known = _known(dev.idVendor, dev.idProduct)
        printer = _has_printer_interface(dev)
        description = known.name if known else f"USB device {dev.idVendor:04x}:{dev.idProduct:04x}"
        found.append(
            DiscoveredDevice(
                "usb-printer" if printer else "usb",
                f"usb:{dev.idVendor:04x}:{dev.idProduct:04x}:{dev.bus}:{dev.address}",
                description,
                dev.idVendor,
                dev.idProduct,
                None,
                known.model if known else None,
            )
        )
    return found


def _has_printer_interface(dev: Any) -> bool:
    try:
        return any(intf.bInterfaceClass == 7 for cfg in dev for intf in cfg)
    except Exception:  # noqa: BLE001 - descriptors unreadable: not known to be a printer
        return False


def list_hid_devices() -> list[DiscoveredDevice]:
    """HID devices hidapi enumerates (empty when hidapi is missing or fails)."""
    from pixelpen.drivers.hidapi import enumerate_hid

    try:
        entries = enumerate_hid(backend="libusb")
    except Exception as exc:  # noqa: BLE001 - ImportError, missing hidraw, permissions
        _log.debug("listing HID devices failed: %s", exc)
        return []
    found = []
    for e in entries:
        name = " ".join(s for s in (e.manufacturer, e.product) if s) or "HID device"
        found.append(DiscoveredDevice("hid", e.path, f"{name} (usage page {e.usage_page:#06x}, usage {e.usage:#06x})",
                                      e.vendor_id, e.product_id, e.serial or None))
    return found


def identify(link: Link, family: str, timeout: float = 0.5) -> Identity | None:
    """Ask the device on ``link`` who it is in ``family``'s protocol; None if it does not answer so.

    hpgl sends ``IN;OI;`` (a 7475A answers OI only after IN), ebb sends ``V\\r``, grbl sends ``$I\\n``.
    """
    if family not in FAMILIES:
        raise ConfigError(f"identify: family must be one of {', '.join(FAMILIES)}, got {family!r}")
    try:
        link.reset_input()
        if family == "hpgl":
            link.write(b"IN;OI;", timeout=timeout)
            return _parse_hpgl(link.read_until(b"\r", timeout=timeout, max_size=128))
        if family == "ebb":
            link.write(b"V\r", timeout=timeout)
            return _parse_ebb(link.read_until(b"\n", timeout=timeout, max_size=256))
        link.write(b"$I\n", timeout=timeout)
        lines = []
        while True:
            line = link.read_until(b"\n", timeout=timeout, max_size=256).strip()
            lines.append(line.decode("ascii", "replace"))
            if line == b"ok" or line.startswith(b"error:") or len(lines) > 16:
                break
        return _parse_grbl(lines)
    except LinkError as exc:
        _log.debug("%s: no %s identity: %s", link.name, family, exc)
        return None


def _parse_hpgl(reply: bytes) -> Identity | None:
    text = reply.strip().decode("ascii", "replace")
    if not text or not text.isprintable() or not re.fullmatch(r"[0-9A-Za-z][0-9A-Za-z\- ]*", text):
        return None
    return Identity("hpgl", text, None, text)


def _parse_ebb(reply: bytes) -> Identity | None:
    text = reply.strip().decode("ascii", "replace")
    m = re.match(r"(EBB\S*).*?Version\s+(\d+(?:\.\d+)*)", text)
    return Identity("ebb", m.group(1), m.group(2), text) if m else None


def _parse_grbl(lines: list[str]) -> Identity | None:
    """The build from ``[VER:1.1h.20190825:]`` (0.9: ``[0.9j.20160726:]``), else from a ``Grbl 1.1h`` banner."""
    for pattern in (r"\[(?:VER:)?(\d[^:\]]*)", r"Grbl (\S+)"):
        for line in lines:
            m = re.match(pattern, line)
            if m:
                return Identity("grbl", "grbl", m.group(1), "\n".join(lines))
    return None


def _probe_serial(dev: DiscoveredDevice, timeout: float, opener: Callable[..., Link]) -> DiscoveredDevice:
    family = _MODEL_FAMILY.get(dev.model or "")
    for fam in [family] if family else list(FAMILIES):
        # opening an Arduino's port pulses DTR and reboots it: give a known GRBL board time to boot
        wait = max(timeout, GRBL_BOOT_SECONDS) if fam == "grbl" and family == "grbl" else timeout
        try:
            with opener(dev.path, baudrate=_PROBE_BAUD[fam], timeout=wait, write_timeout=wait) as link:
                who = identify(link, fam, wait)
        except LinkError as exc:
            _log.debug("%s: cannot probe: %s", dev.path, exc)
            return dev
        if who is not None:
            model = "axidraw" if fam == "ebb" else "grbl" if fam == "grbl" else who.model.lower()
            return replace(dev, model=model, identity=who)
    return dev


def _probe_usb_printer(dev: DiscoveredDevice, timeout: float, backend: Any) -> DiscoveredDevice:
    from pixelpen.drivers.usbprinter import UsbPrinterLink

    try:
        with UsbPrinterLink(dev.vid, dev.pid, backend=backend, timeout=timeout, write_timeout=timeout) as link:
            fields = link.device_id()
    except (LinkError, ParseError) as exc:
        _log.debug("%s: no IEEE 1284 device ID: %s", dev.path, exc)
        return dev
    model = fields.get("MDL")
    if not model:
        return dev
    raw = ";".join(f"{k}:{v}" for k, v in fields.items()) + ";"
    return replace(dev, model=dev.model or model.lower(), identity=Identity("ieee1284", model, None, raw))


def discover(
    probe: bool = False, timeout: float = 0.3, include_hid: bool = True, usb_backend: Any = None
) -> list[DiscoveredDevice]:
    """Every device pixelpen could drive: serial ports, known or printer-class USB devices not listed as ports, HID.

    With ``probe`` each serial port is asked who it is (a few bytes, ``timeout`` seconds per question)
    and each USB printer for its IEEE 1284 device ID.
    """
    serial_ports = list_serial_ports()
    if probe:
        from pixelpen.drivers.serial import SerialLink

        serial_ports = [_probe_serial(d, timeout, SerialLink) for d in serial_ports]
    shown = {(d.vid, d.pid) for d in serial_ports if d.vid is not None}
    usb_devices = [
        d
        for d in list_usb_devices(usb_backend)
        if (d.vid, d.pid) not in shown and (d.kind == "usb-printer" or _known(d.vid, d.pid) is not None)
    ]
    if probe:
        usb_devices = [
            _probe_usb_printer(d, timeout, usb_backend) if d.kind == "usb-printer" else d for d in usb_devices
        ]
    hid_devices = list_hid_devices() if include_hid else []
    return serial_ports + usb_devices + hid_devices

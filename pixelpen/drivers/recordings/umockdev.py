"""umockdev fixtures from recordings: emulated hidraw and evdev nodes that the real hidapi and python-evdev open.

:func:`export_umockdev` writes, for a :class:`~pixelpen.drivers.recordings.hidrecorder.HidRecording`:

* ``NAME.umockdev`` — the device tree as ``umockdev-record`` writes it (``P:`` sysfs path, ``N:`` node,
  ``E:`` udev properties, ``A:`` attributes, ``H:`` binary attributes in hex, ``L:`` links): the ``hidraw``
  node, its ``hid`` parent (``HID_ID``, ``HID_NAME``, ``HID_PHYS``, ``HID_UNIQ`` in its uevent; the
  ``report_descriptor`` attribute) and, on USB, the interface (``bInterfaceNumber``) and the device
  (``idVendor``, ``idProduct``, ``product``) — what hidapi's ``hid_enumerate`` reads;
* ``NAME.ioctl`` — the ioctls it answers (``HIDIOCGRDESCSIZE``, ``HIDIOCGRDESC``, ``HIDIOCGRAWINFO``,
  ``HIDIOCGRAWNAME``, ``HIDIOCGRAWPHYS``), each entry exactly the size of the caller's buffer (umockdev
  matches the ioctl number, which encodes the size);
* ``NAME.script`` — the reports as ``r <ms> <data>`` lines (the script format: bytes below 32 as ``^`` +
  chr(b + 64), ``^`` as ``^```), ``ms`` the gap to the previous report (0 without ``realtime``), after a
  ``w 0 <data>`` line before each when the replay is to wait for the program (``handshake``).

For an :class:`~pixelpen.drivers.recordings.evemu.EvdevRecording` it writes the ``input``/``eventN``
tree, the evdev ioctls python-evdev asks (``EVIOCGID``, ``EVIOCGNAME``/``PHYS``/``UNIQ`` of 256 bytes,
``EVIOCGVERSION``, ``EVIOCGBIT`` of 4 bytes for the types and 96 for each type's codes, ``EVIOCGABS``,
``EVIOCGPROP``, ``EVIOCGKEY``/``LED``/``SW``/``SND``, ``EVIOCGEFFECTS``, ``EVIOCGREP``) and ``NAME.events``,
the events in evemu's format for ``--evemu-events``.  :meth:`UmockdevFixture.command` gives the
``umockdev-run`` command line.

umockdev backs the node with a pseudo-terminal, so the emulated node is a byte stream: reports (or events)
that arrive before the program reads run together, and a hidraw reader must read exactly one report's
length at a time (or the reports be spaced, ``realtime``).  Two quirks of umockdev 0.17 are worked around:
a script line's data loses its leading spaces, so a report that starts with byte 0x20 is appended to the
report before it (the stream is the same), and refused when it is the first; and an evemu event is turned
into the bytes of a ``struct input_event`` whose first byte is the low byte of its seconds, so event times
are moved to start at 33 s and skip every second whose low byte is 0x20 (a one-second pause in replay).
"""

from __future__ import annotations

import os
import struct
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from pixelpen.drivers.recordings.evemu import (
    CODE_MAX,
    EV_ABS,
    EV_KEY,
    EV_LED,
    EV_SND,
    EV_SW,
    EV_SYN,
    INPUT_PROP_MAX,
    EvdevRecording,
    write_evemu,
)
from pixelpen.drivers.recordings.hidrecorder import HidRecording
from pixelpen.errors import InvalidArgument, InvalidArgumentType

__all__ = ["UmockdevFixture", "encode_script_data", "export_umockdev"]

HIDRAW_MAJOR, INPUT_MAJOR, EVDEV_MINOR_BASE = 240, 13, 64
HID_MAX_DESCRIPTOR_SIZE = 4096
NAME_BUFFER = 256
"""The name/phys/uniq buffers python-evdev and hid tools pass (EVIOCGNAME(256), HIDIOCGRAWNAME(256))."""
EV_BITS_BUFFER, CODE_BITS_BUFFER = 4, 96
"""python-evdev's EVIOCGBIT buffers: EV_MAX/8 + 1 bytes for the types, KEY_MAX/8 + 1 for a type's codes."""
EVENT_TIME_START = 33
"""Seconds the first exported event is moved to (past 32 = 0x20, see the module's notes)."""
BUS_USB = 0x03
_SCRIPT_SPACE = 0x20


@dataclass(frozen=True)
class UmockdevFixture:
    """The files of one exported device and the node it appears as."""

    device: Path
    """The ``.umockdev`` device description (``--device``)."""
    ioctl: Path
    """The ``.ioctl`` answers (``--ioctl NODE=FILE``)."""
    data: Path
    """The ``.script`` of hidraw reads (``--script NODE=FILE``) or the evemu ``.events`` (``--evemu-events``)."""
    node: str
    """``/dev/hidrawN`` or ``/dev/input/eventN``."""

    def command(self, *program: str) -> list[str]:
        """The ``umockdev-run`` command line that runs ``program`` with this device."""
        flag = "--evemu-events" if self.data.suffix == ".events" else "--script"
        return ["umockdev-run", "--device", str(self.device), "--ioctl", f"{self.node}={self.ioctl}",
                flag, f"{self.node}={self.data}", "--", *program]


def encode_script_data(data: bytes) -> bytes:
    """Bytes as a umockdev script line holds them: below 32 as ``^`` + chr(b + 64), ``^`` as ``^```."""
    out = bytearray()
    for b in data:
        if b < 32:
            out += bytes((0x5E, b + 64))
        elif b == 0x5E:
            out += b"^`"
        else:
            out.append(b)
    return bytes(out)


def export_umockdev(recording: HidRecording | EvdevRecording, directory: str | os.PathLike[str], *,
                    number: int = 0, realtime: bool = False, name: str | None = None,
                    handshake: bytes = b"") -> UmockdevFixture:
    """Write the umockdev files of a recorded hidraw or evdev device into ``directory`` (created if missing).

    ``number`` is N of ``/dev/hidrawN`` or ``/dev/input/eventN``; ``realtime`` keeps the recorded gaps
    between reports (else they come back to back); ``name`` is the files' stem (default ``hidrawN``/``eventN``).
    ``handshake`` (hidraw only) makes the replay send each report only after the program wrote these bytes to
    the node (a ``w`` line before each ``r``): without it the reports start when umockdev-run does, and those
    sent before the program reads run together in the stream.
    """
    if not (isinstance(number, int) and 0 <= number < 1024):
        raise InvalidArgument(f"the node number {number!r} is not 0..1023")
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    if isinstance(recording, HidRecording):
        return _export_hidraw(recording, out, number, realtime, name or f"hidraw{number}", bytes(handshake))
    if handshake:
        raise InvalidArgument("handshake is for hidraw scripts: umockdev's evemu events cannot wait for a write")
    if isinstance(recording, EvdevRecording):
        return _export_evdev(recording, out, number, realtime, name or f"event{number}")
    raise InvalidArgumentType(f"export_umockdev() takes a HidRecording or an EvdevRecording, not "
                              f"{type(recording).__name__}")


# ---- the device description --------------------------------------------------------------------------------

def _block(path: str, *, node: str = "", properties: Sequence[tuple[str, str]] = (),
           attributes: Sequence[tuple[str, str]] = (), binary: Sequence[tuple[str, bytes]] = (),
           links: Sequence[tuple[str, str]] = ()) -> str:
    """One device of a ``.umockdev`` file: attribute text escaped as umockdev-record does (``\\n``, ``\\\\``)."""
    for key, value in [*properties, *attributes]:
        if "\n" in value or "\r" in value:
            raise InvalidArgument(f"{key}: a line break in {value!r} cannot be exported")
    lines = [f"P: {path}"]
    if node:
        lines.append(f"N: {node}")
    lines += [f"E: {key}={value}" for key, value in properties]
    lines += [f"A: {key}={value.replace(chr(92), chr(92) * 2)}\\n" for key, value in attributes]
    lines += [f"H: {key}={value.hex().upper()}" for key, value in binary]
    lines += [f"L: {key}={target}" for key, target in links]
    return "\n".join(lines) + "\n"


def _ioctl_line(name: str, ret: int, data: bytes) -> str:
    return f"{name} {ret} {data.hex().upper()}"


def _padded(text: str, size: int = NAME_BUFFER) -> tuple[int, bytes]:
    """(the ioctl's return: bytes copied with the NUL, the buffer) for a name ioctl."""
    raw = text.encode("utf-8")[: size - 1]
    return len(raw) + 1, raw.ljust(size, b"\0")


def _write(path: Path, text: str | bytes) -> Path:
    path.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8"))
    return path


# ---- hidraw ----------------------------------------------------------------------------------------------

def _export_hidraw(rec: HidRecording, out: Path, number: int, realtime: bool, stem: str,
                   handshake: bytes) -> UmockdevFixture:
    if not 1 <= len(rec.descriptor) <= HID_MAX_DESCRIPTOR_SIZE:
        raise InvalidArgument(f"a report descriptor of {len(rec.descriptor)} bytes (1 to "
                              f"{HID_MAX_DESCRIPTOR_SIZE} allowed)")
    node = f"/dev/hidraw{number}"
    interface = rec.device_id.interface
    hid_name = f"{rec.bus:04X}:{rec.vendor_id:04X}:{rec.product_id:04X}.{number + 1:04X}"
    if rec.bus == BUS_USB:
        usb = f"/devices/pci0000:00/0000:00:14.0/usb1/1-{number + 1}"
        parent = f"{usb}/1-{number + 1}:1.{max(interface, 0)}"
    else:
        usb = ""
        parent = "/devices/virtual/misc/uhid"
    hid = f"{parent}/{hid_name}"
    hid_id = f"{rec.bus:04X}:{rec.vendor_id:08X}:{rec.product_id:08X}"
    blocks = [
        _block(f"{hid}/hidraw/hidraw{number}", node=f"hidraw{number}",
               properties=[("DEVNAME", node), ("MAJOR", str(HIDRAW_MAJOR)), ("MINOR", str(number)),
                           ("SUBSYSTEM", "hidraw")],
               attributes=[("dev", f"{HIDRAW_MAJOR}:{number}")], links=[("device", f"../../../{hid_name}")]),
        _block(hid, properties=[("DRIVER", "hid-generic"), ("HID_ID", hid_id), ("HID_NAME", rec.name),
                                ("HID_PHYS", rec.phys), ("HID_UNIQ", ""),
                                ("MODALIAS", f"hid:b{rec.bus:04X}g0001v{rec.vendor_id:08X}p{rec.product_id:08X}"),
                                ("SUBSYSTEM", "hid")],
               binary=[("report_descriptor", rec.descriptor)]),
    ]
    if usb:
        blocks += [
            _block(parent, properties=[("DEVTYPE", "usb_interface"), ("DRIVER", "usbhid"), ("SUBSYSTEM", "usb"),
                                       ("INTERFACE", "3/0/0")],
                   attributes=[("bInterfaceClass", "03"), ("bInterfaceNumber", f"{max(interface, 0):02x}")]),
            _block(usb, node=f"bus/usb/001/{number + 2:03d}",
                   properties=[("DEVTYPE", "usb_device"), ("DRIVER", "usb"), ("SUBSYSTEM", "usb"),
                               ("PRODUCT", f"{rec.vendor_id:x}/{rec.product_id:x}/0"),
                               ("BUSNUM", "001"), ("DEVNUM", f"{number + 2:03d}")],
                   attributes=[("idVendor", f"{rec.vendor_id:04x}"), ("idProduct", f"{rec.product_id:04x}"),
                               ("product", rec.name), ("bcdDevice", "0000")]),
        ]
    size = len(rec.descriptor)
    name_ret, name_buffer = _padded(rec.name)
    phys_ret, phys_buffer = _padded(rec.phys)
    ioctls = [f"@DEV {node}",
              _ioctl_line("HIDIOCGRDESCSIZE", 0, struct.pack("<I", size)),
              _ioctl_line("HIDIOCGRDESC", 0, struct.pack("<I", size) + rec.descriptor.ljust(HID_MAX_DESCRIPTOR_SIZE,
                                                                                          b"\0")),
              _ioctl_line("HIDIOCGRAWINFO", 0, struct.pack("<IHH", rec.bus, rec.vendor_id, rec.product_id)),
              _ioctl_line("HIDIOCGRAWNAME", name_ret, name_buffer),
              _ioctl_line("HIDIOCGRAWPHYS", phys_ret, phys_buffer)]
    return UmockdevFixture(_write(out / f"{stem}.umockdev", "\n".join(blocks)),
                           _write(out / f"{stem}.ioctl", "\n".join(ioctls) + "\n"),
                           _write(out / f"{stem}.script", _script(rec.reports, realtime, handshake)), node)


def _script(reports: Sequence[tuple[float, bytes]], realtime: bool, handshake: bytes) -> bytes:
    """The ``r`` lines of the reports, each after a ``w`` line of the handshake; without one, a report starting
    with a space is joined to the one before (see the notes)."""
    if handshake[:1] == bytes((_SCRIPT_SPACE,)):
        raise InvalidArgument("the handshake starts with byte 0x20, which a umockdev script line cannot hold")
    gaps: list[int] = []
    blocks: list[bytes] = []
    previous = reports[0][0] if reports else 0.0
    for t, report in reports:
        gap = max(0, round((t - previous) * 1000)) if realtime else 0
        previous = t
        if report[:1] == bytes((_SCRIPT_SPACE,)):
            if not blocks or handshake:
                raise InvalidArgument("a report starts with byte 0x20, which a umockdev script cannot hold at "
                                      "the start of a line (and it cannot join the report before it)")
            blocks[-1] += report
            continue
        gaps.append(gap)
        blocks.append(bytes(report))
    step = b"w 0 " + encode_script_data(handshake) + b"\n" if handshake else b""
    return b"".join(step + b"r %d " % gap + encode_script_data(data) + b"\n"
                    for gap, data in zip(gaps, blocks, strict=True))


# ---- evdev -----------------------------------------------------------------------------------------------

def _bits(codes: frozenset[int] | set[int], size: int) -> bytes:
    mask = bytearray(size)
    for code in codes:
        if code < 8 * size:
            mask[code // 8] |= 1 << code % 8
    return bytes(mask)


def _export_evdev(rec: EvdevRecording, out: Path, number: int, realtime: bool, stem: str) -> UmockdevFixture:
    node = f"/dev/input/event{number}"
    input_path = f"/devices/virtual/input/input{number}"
    product = f"{rec.bus:x}/{rec.vendor_id:x}/{rec.product_id:x}/{rec.version:x}"
    blocks = [
        _block(f"{input_path}/event{number}", node=f"input/event{number}",
               properties=[("DEVNAME", node), ("ID_INPUT", "1"), ("MAJOR", str(INPUT_MAJOR)),
                           ("MINOR", str(EVDEV_MINOR_BASE + number)), ("SUBSYSTEM", "input")],
               attributes=[("dev", f"{INPUT_MAJOR}:{EVDEV_MINOR_BASE + number}")], links=[("device", "../../input"
                                                                                            f"{number}")]),
        _block(input_path, properties=[("NAME", f'"{rec.name}"'), ("PRODUCT", product), ("ID_INPUT", "1"),
                                       ("SUBSYSTEM", "input")],
               attributes=[("name", rec.name), ("phys", ""), ("uniq", ""), ("id/bustype", f"{rec.bus:04x}"),
                           ("id/vendor", f"{rec.vendor_id:04x}"), ("id/product", f"{rec.product_id:04x}"),
                           ("id/version", f"{rec.version:04x}")]),
    ]
    types = {t for t, codes in rec.codes.items() if codes} | {EV_SYN}
    if rec.absinfo:
        types.add(EV_ABS)
    name_ret, name_buffer = _padded(rec.name)
    ioctls = [f"@DEV {node}",
              _ioctl_line("EVIOCGVERSION", 0, struct.pack("<i", 0x010001)),
              _ioctl_line("EVIOCGID", 0, struct.pack("<HHHH", rec.bus, rec.vendor_id, rec.product_id, rec.version)),
              _ioctl_line("EVIOCGNAME(0)", name_ret, name_buffer),
              _ioctl_line("EVIOCGPHYS(0)", 1, bytes(NAME_BUFFER)),
              _ioctl_line("EVIOCGUNIQ(0)", 1, bytes(NAME_BUFFER)),
              _ioctl_line("EVIOCGBIT(0)", EV_BITS_BUFFER, _bits(types, EV_BITS_BUFFER)),
              _ioctl_line("EVIOCGBIT(0)", CODE_BITS_BUFFER, _bits(types, CODE_BITS_BUFFER))]
    for ev_type in sorted(types - {EV_SYN}):
        codes = rec.codes.get(ev_type, frozenset()) | (frozenset(rec.absinfo) if ev_type == EV_ABS else frozenset())
        ioctls.append(_ioctl_line(f"EVIOCGBIT({ev_type})", CODE_BITS_BUFFER, _bits(codes, CODE_BITS_BUFFER)))
    for code, info in sorted(rec.absinfo.items()):
        ioctls.append(_ioctl_line(f"EVIOCGABS({code})", 0, struct.pack("<6i", *info)))
    states: tuple[tuple[str, int, set[int]], ...] = (
        ("EVIOCGKEY(0)", EV_KEY, set()), ("EVIOCGLED(0)", EV_LED, {c for c, s in rec.leds.items() if s}),
              ("EVIOCGSW(0)", EV_SW, {c for c, s in rec.switches.items() if s}), ("EVIOCGSND(0)", EV_SND, set()))
    for ioctl_name, ev_type, on in states:  # python-evdev's buffers: (TYPE_MAX + 7) / 8 bytes
        size = (CODE_MAX[ev_type] + 7) // 8
        ioctls.append(_ioctl_line(ioctl_name, size, _bits(on, size)))
    prop_size = (INPUT_PROP_MAX + 7) // 8
    ioctls += [_ioctl_line("EVIOCGPROP(0)", prop_size, _bits(rec.properties, prop_size)),
               _ioctl_line("EVIOCGEFFECTS", 0, struct.pack("<i", 0)),
               _ioctl_line("EVIOCGREP", 0, struct.pack("<II", 250, 33))]
    events = replace(rec, events=_event_times(rec.events, realtime), node=node)
    data = out / f"{stem}.events"
    write_evemu(events, data, description=False)
    return UmockdevFixture(_write(out / f"{stem}.umockdev", "\n".join(blocks)),
                           _write(out / f"{stem}.ioctl", "\n".join(ioctls) + "\n"), data, node)


def _event_times(events: Sequence[tuple[float, int, int, int]], realtime: bool) -> list[tuple[float, int, int, int]]:
    """Events moved to start at EVENT_TIME_START s (all there without ``realtime``), skipping seconds 0x20 mod 256."""
    if not events:
        return []
    first = events[0][0]
    shift = 0
    out = []
    for t, ev_type, code, value in events:
        moved = EVENT_TIME_START + (t - first if realtime else 0.0)
        while int(moved + shift) % 256 == _SCRIPT_SPACE:
            shift += 1
        out.append((moved + shift, ev_type, code, value))
    return out

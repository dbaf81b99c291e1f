"""udev rules that let a user open HID devices without root, and a diagnosis of a node that cannot be opened.

Three kinds of device node matter (see docs/hid-transports.md):

* ``/dev/hidrawN`` — hidapi's ``hidraw`` module (the kernel driver stays bound; USB, Bluetooth, I²C).
  Matched by ``KERNEL=="hidraw*"`` and, for USB devices, ``ATTRS{idVendor}``/``ATTRS{idProduct}`` of the USB
  device above it; a Bluetooth or I²C device has no USB parent, so ``KERNELS=="*:VVVV:PPPP.*"`` matches the
  HID device's own name (``BBBB:VVVV:PPPP.NNNN``, upper-case hex) instead.
* ``/dev/bus/usb/BBB/DDD`` — libusb: hidapi's ``hid`` module and pyusb (:mod:`pixelpen.drivers.usbhid`).
  Matched by ``SUBSYSTEM=="usb", ATTRS{idVendor}, ATTRS{idProduct}``.
* ``/dev/input/eventN`` — python-evdev, matched by ``SUBSYSTEM=="input", KERNEL=="event*"``.

Access is granted either by ``TAG+="uaccess"`` (systemd-logind gives the user at the local seat an ACL;
the rule file must sort before ``73-seat-late.rules``, hence ``70-pixelpen.rules``), or by ``MODE="0660",
GROUP="plugdev"`` (a group; works over ssh too), or ``MODE="0666"`` (everyone; shared lab machines only).
"""

from __future__ import annotations

import grp
import os
import re
import stat as stat_module
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

from pixelpen.errors import InvalidArgument

RULES_FILE = "/etc/udev/rules.d/70-pixelpen.rules"
"""Where the rules go: before 73-seat-late.rules, which turns the uaccess tag into an ACL."""
RELOAD = "sudo udevadm control --reload-rules && sudo udevadm trigger"
"""What makes udev apply a new rule to the devices already plugged in (or unplug and plug in again)."""
NODES = ("hidraw", "usb", "input")
"""The kinds of node a rule can be written for."""
ACCESS = ("uaccess", "group", "world")
"""How a rule grants access: the seat user's ACL, a group with mode 0660, or mode 0666."""
DEFAULT_GROUP = "plugdev"

_HIDRAW = re.compile(r"^/dev/hidraw(\d+)$")
_EVDEV = re.compile(r"^/dev/input/(event\d+)$")
_USBFS = re.compile(r"^/dev/bus/usb/(\d{3})/(\d{3})$")
_LIBUSB_PATH = re.compile(r"^(\d+)-([\d.]+):(\d+)\.(\d+)$")
"""hidapi's libusb backend path: bus-ports:configuration.interface (``1-2.3:1.0``)."""
_HID_ID = re.compile(r"^HID_ID=([0-9A-Fa-f]+):([0-9A-Fa-f]+):([0-9A-Fa-f]+)$", re.MULTILINE)


def _check_id(value: int, what: str) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value <= 0xFFFF:
        raise InvalidArgument(f"udev rule: {what} must be an integer 0..0xffff, got {value!r}")
    return value


def _access(access: str, group: str) -> str:
    if access == "uaccess":
        return 'TAG+="uaccess"'
    if access == "group":
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_.-]*", group):
            raise InvalidArgument(f"udev rule: {group!r} is not a group name")
        return f'MODE="0660", GROUP="{group}"'
    if access == "world":
        return 'MODE="0666"'
    raise InvalidArgument(f"udev rule: access {access!r} is not one of {', '.join(ACCESS)}")


def rule_line(vendor_id: int, product_id: int, node: str, *, access: str = "uaccess", group: str = DEFAULT_GROUP,
              usb: bool = True) -> str:
    """One rule line for ``node`` (``hidraw``, ``usb``, ``input``) of VID:PID; ``usb=False``: Bluetooth/I²C."""
    vid, pid = _check_id(vendor_id, "vendor ID"), _check_id(product_id, "product ID")
    grant = _access(access, group)
    ids = f'ATTRS{{idVendor}}=="{vid:04x}", ATTRS{{idProduct}}=="{pid:04x}"'
    if node == "hidraw":
        match = ids if usb else f'KERNELS=="*:{vid:04X}:{pid:04X}.*"'
        return f'KERNEL=="hidraw*", SUBSYSTEM=="hidraw", {match}, {grant}'
    if node == "usb":
        return f'SUBSYSTEM=="usb", ENV{{DEVTYPE}}=="usb_device", {ids}, {grant}'
    if node == "input":
        match = ids if usb else f'KERNELS=="*:{vid:04X}:{pid:04X}.*"'
        return f'SUBSYSTEM=="input", KERNEL=="event*", {match}, {grant}'
    raise InvalidArgument(f"udev rule: node kind {node!r} is not one of {', '.join(NODES)}")


def udev_rule(vendor_id: int, product_id: int, *, nodes: Sequence[str] = ("hidraw", "usb"), access: str = "uaccess",
              group: str = DEFAULT_GROUP, usb: bool = True, name: str = "") -> str:
    """The lines of a 70-pixelpen.rules block for device VID:PID: a comment, then one rule per node kind."""
    label = f"{_check_id(vendor_id, 'vendor ID'):04x}:{_check_id(product_id, 'product ID'):04x}"
    label += f" {name}" if name else ""
    what = {"hidraw": "hidraw (hidapi's hidraw module)", "usb": "libusb (hidapi's hid module, pyusb)",
            "input": "evdev (python-evdev)"}
    lines = [f"# {label}: {', '.join(what.get(n, n) for n in nodes)}"]
    lines += [rule_line(vendor_id, product_id, n, access=access, group=group, usb=usb) for n in nodes]
    return "\n".join(lines) + "\n"


def rules_file(devices: Iterable[tuple[int, int, str]], **options: object) -> str:
    """A whole 70-pixelpen.rules: a header saying where it goes and how to apply it, then ``udev_rule`` per device."""
    header = (f"# {RULES_FILE}: lets the user open these HID devices without root (pixelpen udev-rules).\n"
              f"# Install: copy this file there, then: {RELOAD}\n")
    body = [udev_rule(vid, pid, name=name, **options) for vid, pid, name in devices]  # type: ignore[arg-type]
    return header + "".join(body)


# ---- diagnosis ----------------------------------------------------------------------------------

def _read(path: Path) -> str:
    try:
        return path.read_text(encoding="ascii", errors="replace").strip()
    except OSError:
        return ""


def node_of(path: str, *, sysfs: str = "/sys") -> tuple[str, str]:
    """(node kind, device node) for a hidraw/evdev/usbfs node or a libusb path (``1-2:1.0`` -> its usbfs node)."""
    if _HIDRAW.match(path):
        return "hidraw", path
    if _EVDEV.match(path):
        return "input", path
    if _USBFS.match(path):
        return "usb", path
    m = _LIBUSB_PATH.match(path)
    if m:
        device = Path(sysfs, "bus/usb/devices", f"{m.group(1)}-{m.group(2)}")
        bus, dev = _read(device / "busnum"), _read(device / "devnum")
        if bus.isdigit() and dev.isdigit():
            return "usb", f"/dev/bus/usb/{int(bus):03d}/{int(dev):03d}"
        return "usb", f"/dev/bus/usb/{int(m.group(1)):03d}/???"
    return "", path


def ids_of(path: str, *, sysfs: str = "/sys") -> tuple[int, int, bool] | None:
    """(vendor, product, on USB) of the device behind a node, from sysfs; None when sysfs does not say."""
    m = _HIDRAW.match(path) or _EVDEV.match(path)
    if m:
        sub = "hidraw" if path.startswith("/dev/hidraw") else "input"
        name = f"hidraw{m.group(1)}" if sub == "hidraw" else m.group(1)
        found = _HID_ID.search(_read(Path(sysfs, "class", sub, name, "device", "uevent")))
        if sub == "input" and not found:
            found = _HID_ID.search(_read(Path(sysfs, "class", sub, name, "device", "device", "uevent")))
        if found:
            return int(found.group(2), 16), int(found.group(3), 16), int(found.group(1), 16) == 3
        return None
    m = _LIBUSB_PATH.match(path)
    if m:
        device = Path(sysfs, "bus/usb/devices", f"{m.group(1)}-{m.group(2)}")
        vid, pid = _read(device / "idVendor"), _read(device / "idProduct")
        if vid and pid:
            return int(vid, 16), int(pid, 16), True
    return None


def permission_diagnosis(path: str, *, vendor_id: int | None = None, product_id: int | None = None,
                         stat: Callable[[str], os.stat_result] = os.stat, uid: int | None = None,
                         groups: Sequence[int] | None = None, group_name: Callable[[int], str] | None = None,
                         sysfs: str = "/sys") -> str:
    """Why this user cannot open ``path`` (a hidraw, evdev or usbfs node, or a libusb path) and the one fix.

    Looks at the node's owner, group and mode (``stat``) and the user's uid and groups: a group that may
    read and write the node but that the user is not in -> join it; no grant at all (root:root 0600, the
    kernel's default) -> the missing udev rule, written out for the device's VID:PID (from the arguments or
    sysfs); mode bits that would allow it -> an ACL or exclusive use is the cause, not a rule.
    """
    kind, node = node_of(path, sysfs=sysfs)
    if vendor_id is None or product_id is None:
        found = ids_of(path, sysfs=sysfs)
        vendor_id, product_id, on_usb = found if found else (vendor_id, product_id, True)
    else:
        on_usb = True
    try:
        st = stat(node)
    except FileNotFoundError:
        return f"{node} does not exist: the device is unplugged, or its driver did not create the node"
    except OSError as exc:
        return f"{node}: cannot look at the node: {exc}"
    me = os.getuid() if uid is None else uid
    mine = set(os.getgroups() if groups is None else groups) | ({os.getgid()} if groups is None else set())
    name_of = group_name or _group_name
    mode = stat_module.S_IMODE(st.st_mode)
    gname = name_of(st.st_gid)
    where = f"{node} is {_owner(st.st_uid)}:{gname} mode {mode:04o}"
    if me == 0 or (st.st_uid == me and mode & 0o600 == 0o600) or mode & 0o006 == 0o006 \
            or (st.st_gid in mine and mode & 0o060 == 0o060):
        return (f"{where}, which lets this user read and write it: the refusal is not a missing udev rule "
                "(another program holds the device exclusively, or a security module denies it)")
    if mode & 0o060 == 0o060 and st.st_gid != 0:
        return (f"{where}: a udev rule gives it to group '{gname}', but this user is not in that group: "
                f"sudo usermod -aG {gname} $USER, then log in again")
    if kind == "":
        return f"{where}: this user may not open it (give the user read and write access to it)"
    ids_known = vendor_id is not None and product_id is not None
    rule = rule_line(vendor_id if vendor_id is not None else 0, product_id if product_id is not None else 0,
                     kind, usb=on_usb)
    if not ids_known:
        rule = rule.replace('"0000"', '"VVVV"', 1).replace('"0000"', '"PPPP"', 1)
    acl = " (TAG+=\"uaccess\" only serves the user at the local seat; over ssh use MODE=\"0660\", " \
          f"GROUP=\"{DEFAULT_GROUP}\" instead)"
    ids = "" if ids_known else " (VVVV:PPPP: the device's vendor and product IDs, as lsusb shows them)"
    return (f"{where}: no udev rule grants this user access. Add to {RULES_FILE}:\n  {rule}\n"
            f"then: {RELOAD}{ids}{acl}")


def _group_name(gid: int) -> str:
    try:
        return grp.getgrgid(gid).gr_name
    except KeyError:
        return str(gid)


def _owner(uid: int) -> str:
    try:
        import pwd

        return pwd.getpwuid(uid).pw_name
    except (ImportError, KeyError):
        return str(uid)

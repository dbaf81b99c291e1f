"""``pixelpen udev-rules [VID:PID ...] [--all-sims]``: print a 70-pixelpen.rules that lets the user open HID devices.

For each device: a hidraw rule (hidapi's ``hidraw`` module), a ``SUBSYSTEM=="usb"`` rule (libusb: hidapi's
``hid`` module, pyusb) and, with ``--nodes``, an evdev one; access by ``TAG+="uaccess"`` (the user at the
seat; default), ``--access group`` (``MODE="0660", GROUP=...``; works over ssh) or ``--access world``.
``--all-sims`` adds the IDs the HID simulators enumerate with (a uhid replay or umockdev run of them then opens
without root).  The text goes to standard output (``| sudo tee /etc/udev/rules.d/70-pixelpen.rules``).
"""

from __future__ import annotations

import argparse
import sys

from pixelpen.clock import SimulatedClock
from pixelpen.drivers.hidapi import parse_hid_spec
from pixelpen.drivers.udev import ACCESS, DEFAULT_GROUP, NODES, RULES_FILE, rules_file
from pixelpen.errors import ConfigError, ParseError
from pixelpen.sim.base import BUILTIN_SIMULATORS, ReportDevice, create_simulator, simulator_models

HID_SIM_MODULES = "pixelpen.sim.hid."
"""Simulators whose module lives here are the HID ones --all-sims asks for their IDs."""


def vid_pid(text: str) -> tuple[int, int]:
    """``046d:c52b`` -> (0x046d, 0xc52b); argparse's error naming the field otherwise."""
    try:
        spec = parse_hid_spec(text)
    except ParseError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    if spec.vendor_id is None or spec.product_id is None:
        raise argparse.ArgumentTypeError(f"expected VID:PID (4 hex digits each, e.g. 046d:c52b), got {text!r}")
    if spec.serial is not None or spec.interface is not None:
        raise argparse.ArgumentTypeError(f"a udev rule matches VID:PID only, without serial or @interface: {text!r}")
    return spec.vendor_id, spec.product_id


def simulator_ids() -> list[tuple[int, int, str]]:
    """(vendor, product, model) of each built-in HID simulator with IDs (its module imported, one device built)."""
    found = []
    for model in simulator_models():
        if not BUILTIN_SIMULATORS.get(model, "").startswith(HID_SIM_MODULES):
            continue
        device = create_simulator(model, clock=SimulatedClock())
        try:
            if isinstance(device, ReportDevice):
                info = dict(getattr(device, "info", None) or {})
                vid, pid = int(info.get("vendor_id", 0)), int(info.get("product_id", 0))
                if vid or pid:
                    found.append((vid, pid, f"simulated {model}"))
        finally:
            device.close()
    return found


def run_udev_rules(args: argparse.Namespace) -> int:
    """Print the rules for the devices asked for."""
    devices = [(vid, pid, "") for vid, pid in args.devices]
    if args.all_sims:
        devices += simulator_ids()
    if not devices:
        raise ConfigError("name at least one device as VID:PID (lsusb shows them), or --all-sims")
    unique = list(dict.fromkeys(devices))
    nodes = tuple(dict.fromkeys(n.strip() for n in args.nodes.split(",") if n.strip()))
    unknown = [n for n in nodes if n not in NODES]
    if unknown or not nodes:
        raise ConfigError(f"--nodes: {', '.join(unknown) or 'none given'}; choose from {', '.join(NODES)}")
    sys.stdout.write(rules_file(unique, nodes=nodes, access=args.access, group=args.group, usb=not args.bluetooth))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add pixelpen udev-rules to the ``pixelpen`` parser."""
    p = sub.add_parser(
        "udev-rules", help="print udev rules that let this user open HID devices without root",
        description=f"Print a {RULES_FILE} for the HID devices named (VID:PID) and/or the simulators' IDs: "
                    "a hidraw rule for hidapi's hidraw module and a usb rule for libusb (hidapi's hid module, pyusb).")
    p.add_argument("devices", nargs="*", type=vid_pid, metavar="VID:PID", help="a device's USB IDs, e.g. 046d:c52b")
    p.add_argument("--all-sims", action="store_true", help="also the IDs the HID simulators enumerate with")
    p.add_argument("--access", choices=ACCESS, default="uaccess",
                   help="uaccess: the user at the seat (default); group: MODE 0660 and --group; world: MODE 0666")
    p.add_argument("--group", default=DEFAULT_GROUP, help=f"the group for --access group (default {DEFAULT_GROUP})")
    p.add_argument("--nodes", default="hidraw,usb", metavar="LIST",
                   help=f"node kinds to write rules for, comma-separated from {', '.join(NODES)} (default hidraw,usb)")
    p.add_argument("--bluetooth", action="store_true",
                   help="match the HID device name (Bluetooth, I2C) instead of the USB parent's idVendor/idProduct")
    p.set_defaults(func=run_udev_rules)

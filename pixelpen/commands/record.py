"""The ``record-input`` command: record a HID device's input reports in the hid-recorder text format.

``pixelpen record-input DEVICE [-o FILE] [--duration S] [--count N]`` opens ``DEVICE`` through hidapi (a
hidraw path, ``VID:PID``, ``VID:PID:SERIAL``, each optionally ``@INTERFACE``; ``--backend libusb`` for
hidapi's libusb module) or a simulated one (``sim:MODEL?option=value``, e.g. ``sim:tablet?script=signature``,
behind the same hidapi module API), writes its header and then every report as it arrives, flushed line by
line, to ``FILE`` (default: stdout), until the duration, the count, Ctrl-C or SIGTERM.  ``--list`` lists the
devices hidapi sees.  The file replays with ``pixelpen.open_input("replay:FILE")`` and with hid-tools'
``hid-replay``.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from typing import Any, TextIO

from pixelpen.clock import REAL_CLOCK
from pixelpen.commands import argtypes
from pixelpen.commands.sim import sigterm_stops
from pixelpen.drivers.hidapi import BACKENDS, HidapiLink, enumerate_hid, open_hid
from pixelpen.drivers.recordings.hidrecorder import record_link
from pixelpen.errors import URLError
from pixelpen.urls import parse_url


def register(sub: argparse._SubParsersAction) -> None:
    """Add pixelpen record-input to the ``pixelpen`` parser."""
    p = sub.add_parser("record-input", help="record a HID device's reports in hid-recorder format",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("device", nargs="?", metavar="DEVICE",
                   help="hidraw path, VID:PID[:SERIAL][@INTERFACE], or sim:MODEL?options")
    p.add_argument("-o", "--output", metavar="FILE", help="the file to write (default: stdout)")
    p.add_argument("--duration", type=argtypes.non_negative, metavar="S", help="stop after S seconds")
    p.add_argument("--count", type=argtypes.non_negative_int, metavar="N", help="stop after N reports")
    p.add_argument("--backend", choices=sorted(BACKENDS), default="hidraw", help="hidapi module (default hidraw)")
    p.add_argument("--list", action="store_true", help="list the HID devices hidapi sees and stop")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """List the devices, or record one until the duration, the count, Ctrl-C or SIGTERM."""
    if args.list:
        devices = enumerate_hid(backend=args.backend)
        for info in devices:
            print(info)
        if not devices:
            print("pixelpen record-input: no HID devices found", file=sys.stderr)
        return 0 if devices else 1
    if not args.device:
        raise URLError("record-input: name a DEVICE (a hidraw path, VID:PID, or sim:MODEL), or give --list")
    link = open_device(args.device, args.backend)
    with contextlib.ExitStack() as stack:
        stack.callback(link.close)
        out: TextIO = (stack.enter_context(open(args.output, "w", encoding="utf-8"))
                       if args.output else sys.stdout)
        start = REAL_CLOCK.now()
        name = " ".join(s for s in (link.info.manufacturer, link.info.product) if s)
        with sigterm_stops():
            count = record_link(link, out, link.device_id, name=name, duration=args.duration, count=args.count)
        print(f"pixelpen record-input: {count} reports from {link.info} in {REAL_CLOCK.now() - start:.1f} s"
              + (f" to {args.output}" if args.output else ""), file=sys.stderr)
    return 0


def open_device(spec: str, backend: str) -> HidapiLink:
    """The hidapi link of ``spec``: a real device, or ``sim:MODEL?options`` behind the simulated hidapi module."""
    if not spec.startswith("sim:"):
        return open_hid(spec, backend=backend)
    from pixelpen.sim.base import create_simulator
    from pixelpen.sim.transports.hidapi import SimHidapi

    url = parse_url(spec)
    options: dict[str, Any] = dict(url.options)
    module = SimHidapi([create_simulator(url.target, clock=REAL_CLOCK, **options)])
    return open_hid(module.paths()[0], module=module, clock=REAL_CLOCK)

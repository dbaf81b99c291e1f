"""The ``hid`` command group: ``pixelpen hid dump SOURCE`` prints a HID report descriptor item by item.

SOURCE is a binary descriptor file (a hidraw node's ``/sys/class/hidraw/hidrawN/device/report_descriptor``
among them), ``-`` for standard input, hex text (``"05 01 09 02 ..."``, ``0x05, 0x01, ...`` or ``050109...``,
as an argument or in a file), or a hid-recorder file (its ``R:`` line; a whole recording with ``I:`` lines
also gives the device's IDs, so its quirks apply).  ``--format json`` prints the same as data.  Bad input
exits with status 2 and one line naming where (file, byte offset or hex token).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys

from pixelpen.devices.hid.descriptor import MAX_DESCRIPTOR_SIZE, parse_descriptor
from pixelpen.devices.hid.dump import descriptor_dict, dump_descriptor
from pixelpen.errors import InvalidArgument, ParseError

MAX_SOURCE_BYTES = 1 << 20
"""Bytes read from a file or standard input (a hid-recorder file with reports can be long; a descriptor
itself is at most 4096 bytes)."""

_HEX_TEXT = re.compile(rb"[\s,;0-9a-fA-FxX]*")
_RECORDING_LINE = re.compile(rb"^\s*R:", re.MULTILINE)
_IDS_LINE = re.compile(rb"^\s*I:", re.MULTILINE)


def parse_hex(text: str, *, source: str = "hex text") -> bytes:
    """Bytes from hex text: pairs separated by spaces or commas, ``0x`` prefixes allowed, or one run of pairs."""
    out = bytearray()
    position = 0
    for token in re.split(r"[\s,;]+", text):
        if not token:
            continue
        position = text.index(token, position)
        digits = token[2:] if token[:2].lower() == "0x" else token
        if not digits or len(digits) % 2 or not re.fullmatch(r"[0-9a-fA-F]+", digits):
            raise ParseError(f"character {position + 1}: not hex bytes (pairs of hex digits, optionally "
                             "0x-prefixed)", source=source, token=token)
        out += bytes.fromhex(digits)
        if len(out) > MAX_DESCRIPTOR_SIZE:
            raise ParseError(f"character {position + 1}: more than {MAX_DESCRIPTOR_SIZE} bytes (the kernel's "
                             "descriptor limit)", source=source)
        position += len(token)
    if not out:
        raise ParseError("no hex bytes", source=source)
    return bytes(out)


def recording_descriptor(text: str, *, source: str) -> bytes:
    """The descriptor of a hid-recorder ``R: SIZE HEX...`` line (the first one; its size must match)."""
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("R:"):
            size_text, _, rest = line.lstrip()[2:].strip().partition(" ")
            if not size_text.isdigit():
                raise ParseError("an R: line starts with the descriptor's size in bytes", source=source,
                                 line=number, token=size_text)
            data = parse_hex(rest, source=f"{source}, line {number}")
            if len(data) != int(size_text):
                raise ParseError(f"the R: line announces {size_text} bytes but holds {len(data)}", source=source,
                                 line=number)
            return data
    raise ParseError("no R: line", source=source)


def read_source(spec: str, *, device: int = 0) -> tuple[bytes, int | None, int | None, str]:
    """The descriptor SOURCE names, the device's vendor and product IDs when known, and the source's name."""
    if spec == "-":
        raw, name = sys.stdin.buffer.read(MAX_SOURCE_BYTES + 1), "<stdin>"
    elif os.path.exists(spec):  # False, not an error, for hex text too long to be a file name
        with open(spec, "rb") as f:
            raw, name = f.read(MAX_SOURCE_BYTES + 1), spec
    elif spec.lstrip().startswith("R:"):
        return recording_descriptor(spec, source="the R: line"), None, None, "the R: line"
    elif re.search(r"[\s,]", spec) or _HEX_TEXT.fullmatch(spec.encode("utf-8", "replace")):
        return parse_hex(spec, source="the hex bytes"), None, None, "the hex bytes"
    else:
        raise InvalidArgument(f"{spec!r}: no such file, and not hex bytes or a hid-recorder R: line")
    if len(raw) > MAX_SOURCE_BYTES:
        raise ParseError(f"more than {MAX_SOURCE_BYTES} bytes", source=name)
    if _RECORDING_LINE.search(raw):
        text = raw.decode("utf-8", "replace")
        if _IDS_LINE.search(raw):
            from pixelpen.drivers.recordings.hidrecorder import read_hid_recording

            recordings = read_hid_recording(text, source=name)
            if not 0 <= device < len(recordings):
                raise InvalidArgument(f"{name} holds {len(recordings)} device(s); there is no device {device}")
            rec = recordings[device]
            return rec.descriptor, rec.vendor_id, rec.product_id, name
        return recording_descriptor(text, source=name), None, None, name
    if raw.strip() and _HEX_TEXT.fullmatch(raw):
        return parse_hex(raw.decode("ascii"), source=name), None, None, name
    return raw, None, None, name


def cmd_dump(args: argparse.Namespace) -> int:
    """Print the descriptor SOURCE names (text or JSON)."""
    data, vendor_id, product_id, name = read_source(args.source, device=args.device)
    descriptor = parse_descriptor(data, reject_long_items=args.reject_long_items, vendor_id=vendor_id,
                                  product_id=product_id, source=name)
    if args.format == "json":
        print(json.dumps(descriptor_dict(descriptor), indent=2))
    else:
        sys.stdout.write(dump_descriptor(descriptor))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``pixelpen hid`` (``hid dump``) to the ``pixelpen`` parser."""
    p = sub.add_parser("hid", help="HID tools: dump a report descriptor",
                       description="HID report descriptors: `pixelpen hid dump SOURCE` lists one item by item "
                                   "with offsets, then its reports and fields.")
    actions = p.add_subparsers(dest="hid_command", metavar="ACTION", required=True)
    d = actions.add_parser("dump", help="print a report descriptor item by item, then its reports",
                           description="Parse a HID report descriptor as the Linux kernel does and print it: every "
                                       "item with its byte offset, bytes and meaning, then each report's fields "
                                       "and the parser's warnings. Exit status: 0 done, 2 bad input.")
    d.add_argument("source", metavar="SOURCE",
                   help="binary file (e.g. /sys/class/hidraw/hidraw0/device/report_descriptor), - for stdin, "
                        "hex bytes (\"05 01 09 02 ...\"), or a hid-recorder file or R: line")
    d.add_argument("--format", choices=("text", "json"), default="text", help="text (default) or json")
    d.add_argument("--reject-long-items", action="store_true",
                   help="refuse a descriptor with long items, as the kernel does (default: warn and skip)")
    d.add_argument("--device", type=int, default=0, metavar="N",
                   help="the device of a hid-recorder file holding several (its D: index; default 0)")
    d.set_defaults(func=cmd_dump)

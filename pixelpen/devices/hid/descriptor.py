"""The report-descriptor parser: items to fields and reports, by the Linux kernel's rules (hid-core.c).

:func:`parse_descriptor` follows ``hid_open_report`` item by item: ``hid_parser_global`` (signedness: a
Logical/Physical Maximum is read signed only when the minimum before it is negative; Unit Exponent as a
4-bit nibble 0..15 or as a signed byte; Push/Pop copy every global, the report ID included, on a stack of
4), ``hid_parser_local`` (usages, extended 4-byte usages, Usage Minimum/Maximum ranges with the kernel's
clamp at 12288 usages, delimiters: only the first alternative set counts), ``hid_parser_main`` with
``hid_concatenate_last_usage_page`` (1–2-byte usages take the Usage Page current at the Main item unless
an earlier page was already used) and ``hid_add_field`` (logical range check, report length, the last
usage repeats when Report Count exceeds the usages).  Differences from the kernel, all documented here:

* a field with no usages (padding) is kept, with ``usages == ()``, so a layout covers every bit; the kernel
  registers no ``hid_field`` for it.  Fields with usages past the kernel's 256 per report are dropped with a
  warning, as the kernel drops them.
* a long item is skipped with a warning (the kernel rejects the descriptor; ``reject_long_items=True``
  does too); a reserved item or an unknown Main item is ignored with a warning.
* an unsigned Logical/Physical Maximum above 2**31 - 1 keeps its unsigned value (the kernel stores it in an
  s32 but compares it unsigned).
* trailing zero bytes (0x00 reads as an unknown Main item) reset the local state as in the kernel, without
  a warning per byte.
* in a report space that has numbered reports, items with no Report ID in effect (before the first one, or
  after a Pop back to none) make report 0, keyed ``0`` and read with an ID byte 0, as the kernel reads it.
* limits beyond the kernel's: descriptors over 4096 bytes (``HID_MAX_DESCRIPTOR_SIZE``, which usbhid,
  uhid and hidraw enforce) and collections nested over :data:`MAX_COLLECTION_DEPTH` deep are refused.

Every error is a :class:`~pixelpen.errors.ParseError` whose ``offset`` is the byte offset of the item at fault.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from pixelpen.devices.hid.fields import Collection, Field, ReportDescriptor, ReportKind, ReportLayout
from pixelpen.devices.hid.items import exponent_value, s32, scan, signed_value
from pixelpen.devices.hid.quirks import fixup
from pixelpen.errors import ParseError

MAX_DESCRIPTOR_SIZE = 4096
"""Bytes (``HID_MAX_DESCRIPTOR_SIZE``: usbhid, uhid and hidraw refuse longer descriptors)."""
GLOBAL_STACK_SIZE = 4
"""Push depth (``HID_GLOBAL_STACK_SIZE``)."""
MAX_USAGES = 12288
"""Usages one Main item may collect, and the largest Report Count (``HID_MAX_USAGES``)."""
MAX_REPORT_SIZE = 256
"""Bits per element (``hid_parser_global`` refuses a larger Report Size)."""
MAX_BUFFER_SIZE = 16384
"""Bytes of a report, its ID byte included (``HID_MAX_BUFFER_SIZE``)."""
MAX_IDS = 256
"""Report IDs are 1..255 (``HID_MAX_IDS``)."""
MAX_FIELDS = 256
"""Fields with usages per report (``HID_MAX_FIELDS``; the kernel drops the rest)."""
MAX_COLLECTION_DEPTH = 256
"""Collections open at once (the kernel has no bound; no real device nests more than a few)."""

_M32 = 0xFFFFFFFF
_KINDS = {8: ReportKind.INPUT, 9: ReportKind.OUTPUT, 11: ReportKind.FEATURE}
_LOCAL_EXTRAS = {0x38: "designator_index", 0x48: "designator_minimum", 0x58: "designator_maximum",
                 0x78: "string_index", 0x88: "string_minimum", 0x98: "string_maximum"}
"""Local items kept for the dump, by prefix without its size bits."""
_REPORT_BITS = (MAX_BUFFER_SIZE - 1) * 8
"""Bits a report may hold after its ID byte (``hid_add_field``'s check)."""


@dataclass(slots=True)
class _Report:
    """A report being built: its fields and its length in bits (without the ID byte, as the kernel counts)."""

    kind: ReportKind
    report_id: int | None
    fields: list[Field] = field(default_factory=list)
    bits: int = 0
    with_usages: int = 0


def _parse(items: list[tuple[int, int, int]], data: bytes, source: str | None, reject_long_items: bool,
           warnings: list[str]) -> tuple[dict[tuple[int, int], _Report], list[Collection]]:
    """The kernel's ``hid_open_report`` over :func:`scan`'s items: the reports by (Main tag, report ID) and the
    collections.  One loop with the parser state in local variables: ``hid_parser_global``,
    ``hid_parser_local`` and ``hid_parser_main`` are its three branches (the state as attributes and a
    method per item cost more than the parsing itself)."""

    def error(message: str, offset: int, token: object = None) -> ParseError:
        return ParseError(message, source=source, offset=offset, token=token)

    # globals (struct hid_global), pushed and popped as one tuple
    usage_page = lmin = lmax = pmin = pmax = exponent = unit = report_size = rid = report_count = 0
    stack: list[tuple[int, ...]] = []
    # locals (struct hid_local), reset after every Main item
    usages: list[int] = []
    extended: set[int] = set()  # indices of 4-byte usages, which keep their own page
    usage_min = delimiter_depth = delimiter_branch = 0
    extra: dict[str, object] = {}
    open_: list[Collection] = []
    collections: list[Collection] = []
    reports: dict[tuple[int, int], _Report] = {}
    last = len(items)
    while last and items[last - 1][1] == 0:  # trailing zero bytes
        last -= 1
    for offset, prefix, value in items if last == len(items) else items[:last]:
        if prefix >= 0xF0:  # tag nibble 15: a long item
            what = f"long item (tag 0x{data[offset + 2]:02X}, {value} data bytes)"
            if reject_long_items:
                raise error(f"{what}: the kernel rejects descriptors with long items", offset)
            warnings.append(f"{what} at offset {offset} skipped")
            continue
        t = prefix & 0xFC
        kind = t & 0x0C
        if kind == 4:  # -- hid_parser_global ----------------------------------------------------------------
            if t == 0x74:
                if value > MAX_REPORT_SIZE:
                    raise error(f"Report Size {value} bits is over the kernel's {MAX_REPORT_SIZE}", offset)
                report_size = value
            elif t == 0x94:
                if value > MAX_USAGES:
                    raise error(f"Report Count {value} is over the kernel's {MAX_USAGES}", offset)
                report_count = value
            elif t == 0x14:
                lmin = signed_value(prefix, value)
            elif t == 0x24:  # signed only when the minimum before it is negative
                lmax = signed_value(prefix, value) if lmin < 0 else value
            elif t == 0x04:
                usage_page = value
            elif t == 0x84:
                if value == 0 or value >= MAX_IDS:
                    raise error(f"Report ID {value} is invalid (1..{MAX_IDS - 1})", offset)
                rid = value
            elif t == 0x34:
                pmin = signed_value(prefix, value)
            elif t == 0x44:
                pmax = signed_value(prefix, value) if pmin < 0 else value
            elif t == 0x54:
                exponent = exponent_value(prefix, value)
            elif t == 0x64:
                unit = value
            elif t == 0xA4:
                if len(stack) == GLOBAL_STACK_SIZE:
                    raise error(f"Push: the global stack is full ({GLOBAL_STACK_SIZE} deep)", offset)
                stack.append((usage_page, lmin, lmax, pmin, pmax, exponent, unit, report_size, rid, report_count))
            elif t == 0xB4:
                if not stack:
                    raise error("Pop without a Push (global stack underflow)", offset)
                usage_page, lmin, lmax, pmin, pmax, exponent, unit, report_size, rid, report_count = stack.pop()
            else:
                raise error(f"unknown global item tag {prefix >> 4}", offset, f"0x{prefix:02X}")
        elif kind == 8:  # -- hid_parser_local -----------------------------------------------------------------
            if t == 0x08 or t == 0x28:  # Usage, Usage Maximum
                if delimiter_branch > 1:  # an alternative usage set: ignored
                    continue
                if t == 0x08:
                    first, count = value, 1
                else:
                    top = value
                    if ((top - usage_min) + len(usages)) & _M32 >= MAX_USAGES:
                        warnings.append(f"Usage Maximum at offset {offset}: range cut at {MAX_USAGES} usages")
                        top = (MAX_USAGES - len(usages) + usage_min - 1) & _M32
                        if top == 0:
                            raise error("no more usages available", offset)
                    if usage_min > top:
                        continue
                    first, count = usage_min, top - usage_min + 1
                if len(usages) + count > MAX_USAGES:
                    raise error(f"more than {MAX_USAGES} usages before one Main item", offset)
                if prefix & 3 == 3:  # 4 bytes: an extended usage carries its page
                    extended.update(range(len(usages), len(usages) + count))
                    usages.extend(range(first, first + count))
                elif count == 1:
                    usages.append((usage_page & 0xFFFF) << 16 | first)
                else:
                    page = (usage_page & 0xFFFF) << 16
                    usages.extend(range(page | first, page | (first + count)) if first + count <= 0x10000
                                  else (page | (u & 0xFFFF) for u in range(first, first + count)))
            elif t == 0x18:
                if delimiter_branch <= 1:
                    usage_min = value
            elif t == 0xA8:
                if value:
                    if delimiter_depth:
                        raise error("nested delimiters", offset)
                    delimiter_depth += 1
                    delimiter_branch += 1
                else:
                    if delimiter_depth < 1:
                        raise error("close delimiter without an open one", offset)
                    delimiter_depth -= 1
            elif t in _LOCAL_EXTRAS:
                extra[_LOCAL_EXTRAS[t]] = value
        elif kind == 0:  # -- hid_parser_main ------------------------------------------------------------------
            if usages:  # hid_concatenate_last_usage_page; the page is compared whole, as the kernel does
                prefix16 = (usage_page & 0xFFFF) << 16
                for i in range(len(usages) - 1, -1, -1):
                    if i in extended:
                        continue
                    if usages[i] >> 16 == usage_page:
                        break
                    usages[i] = prefix16 | (usages[i] & 0xFFFF)
            if t == 0x80 or t == 0x90 or t == 0xB0:  # hid_add_field
                tag = prefix >> 4
                report = reports.get((tag, rid))
                if report is None:
                    report = reports[tag, rid] = _Report(_KINDS[tag], rid or None)
                lo, hi = lmin, lmax
                if lo < 0:
                    hi = s32(hi)
                    if hi < lo:
                        raise error(f"Logical Maximum {hi} is below Logical Minimum {lo}", offset)
                elif hi & _M32 < lo:
                    raise error(f"Logical Maximum {hi & _M32} is below Logical Minimum {lo}", offset)
                else:
                    hi &= _M32
                start = report.bits
                report.bits = start + report_size * report_count
                if report.bits > _REPORT_BITS:
                    raise error(f"{report.kind.value} report {report.report_id} is longer than "
                                f"{MAX_BUFFER_SIZE - 1} bytes ({report.bits} bits)", offset)
                if usages and report.with_usages == MAX_FIELDS:
                    warnings.append(f"{report.kind.value} report {report.report_id}: field at offset {offset} "
                                    f"dropped (the kernel keeps {MAX_FIELDS} fields per report)")
                else:
                    if usages:
                        report.with_usages += 1
                        listed = usages if report_count <= len(usages) else \
                            usages + [usages[-1]] * (report_count - len(usages))  # the last usage repeats
                        # a variable has one usage per element; an array the usages an index lo..hi can name
                        kept = tuple(listed[:report_count] if value & 2 else listed[:hi - lo + 1])
                        page = kept[0] >> 16 if kept else usage_page & 0xFFFF
                    else:  # padding: kept, with no usages (the kernel registers no field for it)
                        kept = ()
                        page = usage_page & 0xFFFF
                    report.fields.append(Field(
                        report.kind, report.report_id, page, kept, start + 8 if rid else start, report_size,
                        report_count, lo, hi, pmin, s32(pmax) if pmin < 0 else pmax & _M32, unit, exponent,
                        value, open_[-1] if open_ else None, offset, dict(extra) if extra else {}))
            elif t == 0xA0:
                if len(open_) == MAX_COLLECTION_DEPTH:
                    raise error(f"collections nested over {MAX_COLLECTION_DEPTH} deep", offset)
                c = Collection(value & 0xFF, usages[0] if usages else 0, offset, open_[-1] if open_ else None)
                open_.append(c)
                collections.append(c)
            elif t == 0xC0:
                if not open_:
                    raise error("End Collection without a Collection", offset)
                open_.pop()
            else:
                warnings.append(f"unknown main item 0x{prefix:02X} at offset {offset} ignored")
            if usages or usage_min or delimiter_branch or extra:
                usages = []
                extended = set()
                usage_min = delimiter_depth = delimiter_branch = 0
                extra = {}
        else:
            warnings.append(f"reserved item 0x{prefix:02X} at offset {offset} ignored")
    if last < len(items):  # the kernel reads the zeros as unknown Main items, which reset the local state
        delimiter_depth = 0
    if open_:
        raise ParseError(f"unbalanced collection: {len(open_)} still open at the end of the descriptor "
                         f"(the innermost opened here)", source=source, offset=open_[-1].offset)
    if delimiter_depth:
        raise ParseError("unbalanced delimiter at the end of the descriptor", source=source,
                         offset=items[last - 1][0] if last else 0)
    return reports, collections


def _descriptor(data: bytes, reports: dict[tuple[int, int], _Report], collections: list[Collection],
                warnings: list[str]) -> ReportDescriptor:
    """The parsed descriptor from the reports built."""
    numbered = {_KINDS[tag] for tag, rid in reports if rid}
    layouts = []
    for r in reports.values():
        fields = tuple(r.fields)
        if r.report_id is None and r.kind in numbered:
            # the kernel reads every report of a numbered kind with an ID byte, 0 for this one
            warnings.append(f"{r.kind.value} items with no Report ID in effect make {r.kind.value} "
                            "report 0, read with an ID byte 0 like the numbered ones")
            r.report_id = 0
            fields = tuple(replace(f, report_id=0, bit_offset=f.bit_offset + 8) for f in fields)
        layouts.append(ReportLayout(r.kind, r.report_id, fields,
                                    (r.bits + 7) // 8 + (1 if r.report_id is not None else 0)))
    return ReportDescriptor(data, layouts, tuple(collections), tuple(warnings))


def parse_descriptor(data: bytes, *, reject_long_items: bool = False, vendor_id: int | None = None,
                     product_id: int | None = None, source: str | None = None) -> ReportDescriptor:
    """Parse a report descriptor as the Linux kernel does (quirks applied when the device's IDs are given)."""
    data = bytes(data)
    if len(data) > MAX_DESCRIPTOR_SIZE:  # checked before the quirks, as usbhid checks before report_fixup
        raise ParseError(f"report descriptor of {len(data)} bytes is over the kernel's {MAX_DESCRIPTOR_SIZE}",
                         source=source, offset=MAX_DESCRIPTOR_SIZE)
    notes: list[str] = []
    if vendor_id is not None and product_id is not None:
        data, notes = fixup(data, vendor_id, product_id)
    if not data:
        raise ParseError("empty report descriptor", source=source, offset=0)
    reports, collections = _parse(scan(data, source=source), data, source, reject_long_items, notes)
    return _descriptor(data, reports, collections, notes)

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

from collections.abc import Callable
from dataclasses import dataclass, field, replace

from pixelpen.devices.hid.fields import Collection, Field, ReportDescriptor, ReportKind, ReportLayout
from pixelpen.devices.hid.items import GLOBAL, LOCAL, LONG_ITEM_TAG, MAIN, exponent_value, scan, signed_value
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
_LOCAL_EXTRAS = {3: "designator_index", 4: "designator_minimum", 5: "designator_maximum",
                 7: "string_index", 8: "string_minimum", 9: "string_maximum"}


def _s32(value: int) -> int:
    value &= _M32
    return value - (1 << 32) if value & 0x80000000 else value


@dataclass(slots=True)
class _Globals:
    """The global state (the kernel's ``struct hid_global``)."""

    usage_page: int = 0
    logical_min: int = 0
    logical_max: int = 0
    physical_min: int = 0
    physical_max: int = 0
    unit_exponent: int = 0
    unit: int = 0
    report_size: int = 0
    report_id: int = 0
    report_count: int = 0

    def copy(self) -> _Globals:
        """A copy for Push."""
        return _Globals(self.usage_page, self.logical_min, self.logical_max, self.physical_min, self.physical_max,
                        self.unit_exponent, self.unit, self.report_size, self.report_id, self.report_count)


@dataclass(slots=True)
class _Locals:
    """The local state (the kernel's ``struct hid_local``), reset after every Main item."""

    usages: list[int] = field(default_factory=list)
    extended: list[bool] = field(default_factory=list)
    """Per usage: given as a 4-byte (extended) usage, so no Usage Page is put in front of it."""
    usage_min: int = 0
    delimiter_depth: int = 0
    delimiter_branch: int = 0
    extra: dict[str, object] = field(default_factory=dict)


@dataclass(slots=True)
class _Report:
    """A report being built: its fields and its length in bits (without the ID byte, as the kernel counts)."""

    kind: ReportKind
    report_id: int | None
    fields: list[Field] = field(default_factory=list)
    bits: int = 0
    with_usages: int = 0


class _Parser:
    """One pass over the items, holding the kernel parser's state."""

    def __init__(self, data: bytes, source: str | None) -> None:
        self.data = data
        self.source = source
        self.g = _Globals()
        self.stack: list[_Globals] = []
        self.local = _Locals()
        self.open: list[Collection] = []
        self.collections: list[Collection] = []
        self.reports: dict[tuple[int, int], _Report] = {}
        """By (Main item tag, report ID): Input 8, Output 9, Feature 11."""
        self.warnings: list[str] = []
        self.reject_long_items = False

    def error(self, message: str, offset: int, token: object = None) -> ParseError:
        """A ParseError at an item's offset."""
        return ParseError(message, source=self.source, offset=offset, token=token)

    def run(self, items: list[tuple[int, int, int]], reject_long_items: bool) -> None:
        """Process every item (``(offset, prefix, value)`` from :func:`scan`), then check that collections and
        delimiters are closed."""
        last = len(items)
        while last and items[last - 1][1] == 0:  # trailing zero bytes
            last -= 1
        self.reject_long_items = reject_long_items
        dispatch = _DISPATCH
        for offset, prefix, value in items if last == len(items) else items[:last]:
            dispatch[prefix](self, offset, prefix, value)
        if last < len(items):  # the kernel reads the zeros as unknown Main items, which reset the local state
            self.local = _Locals()
        if self.open:
            inner = self.open[-1]
            raise ParseError(f"unbalanced collection: {len(self.open)} still open at the end of the descriptor "
                             f"(the innermost opened here)", source=self.source, offset=inner.offset)
        if self.local.delimiter_depth:
            raise ParseError("unbalanced delimiter at the end of the descriptor", source=self.source,
                             offset=items[last - 1][0] if last else 0)

    def long_item(self, offset: int, prefix: int, size: int) -> None:
        """A long item: skipped with a warning, or an error with ``reject_long_items``."""
        what = f"long item (tag 0x{self.data[offset + 2]:02X}, {size} data bytes)"
        if self.reject_long_items:
            raise self.error(f"{what}: the kernel rejects descriptors with long items", offset)
        self.warnings.append(f"{what} at offset {offset} skipped")

    def reserved_item(self, offset: int, prefix: int, value: int) -> None:
        """An item of the reserved type 3: ignored, as the kernel's ``hid_parser_reserved``."""
        self.warnings.append(f"reserved item 0x{prefix:02X} at offset {offset} ignored")

    # -- hid_parser_global: one method per tag, dispatched by prefix byte -----------------------------------------
    def usage_page(self, offset: int, prefix: int, value: int) -> None:
        """Usage Page."""
        self.g.usage_page = value

    def logical_min(self, offset: int, prefix: int, value: int) -> None:
        """Logical Minimum (signed)."""
        self.g.logical_min = signed_value(prefix, value)

    def logical_max(self, offset: int, prefix: int, value: int) -> None:
        """Logical Maximum: signed only when the Logical Minimum before it is negative."""
        g = self.g
        g.logical_max = signed_value(prefix, value) if g.logical_min < 0 else value

    def physical_min(self, offset: int, prefix: int, value: int) -> None:
        """Physical Minimum (signed)."""
        self.g.physical_min = signed_value(prefix, value)

    def physical_max(self, offset: int, prefix: int, value: int) -> None:
        """Physical Maximum: signed only when the Physical Minimum before it is negative."""
        g = self.g
        g.physical_max = signed_value(prefix, value) if g.physical_min < 0 else value

    def unit_exponent(self, offset: int, prefix: int, value: int) -> None:
        """Unit Exponent: 0..15 is the spec's 4-bit two's complement nibble, anything else a signed number."""
        self.g.unit_exponent = exponent_value(prefix, value)

    def unit(self, offset: int, prefix: int, value: int) -> None:
        """Unit."""
        self.g.unit = value

    def report_size(self, offset: int, prefix: int, value: int) -> None:
        """Report Size, at most 256 bits."""
        if value > MAX_REPORT_SIZE:
            raise self.error(f"Report Size {value} bits is over the kernel's {MAX_REPORT_SIZE}", offset)
        self.g.report_size = value

    def report_id(self, offset: int, prefix: int, value: int) -> None:
        """Report ID, 1..255."""
        if value == 0 or value >= MAX_IDS:
            raise self.error(f"Report ID {value} is invalid (1..{MAX_IDS - 1})", offset)
        self.g.report_id = value

    def report_count(self, offset: int, prefix: int, value: int) -> None:
        """Report Count, at most 12288."""
        if value > MAX_USAGES:
            raise self.error(f"Report Count {value} is over the kernel's {MAX_USAGES}", offset)
        self.g.report_count = value

    def push(self, offset: int, prefix: int, value: int) -> None:
        """Push: a copy of every global, the report ID included, on the stack."""
        if len(self.stack) == GLOBAL_STACK_SIZE:
            raise self.error(f"Push: the global stack is full ({GLOBAL_STACK_SIZE} deep)", offset)
        self.stack.append(self.g.copy())

    def pop(self, offset: int, prefix: int, value: int) -> None:
        """Pop: every global back from the stack."""
        if not self.stack:
            raise self.error("Pop without a Push (global stack underflow)", offset)
        self.g = self.stack.pop()

    def unknown_global(self, offset: int, prefix: int, value: int) -> None:
        """Global tags 12..14: an error, as in the kernel."""
        raise self.error(f"unknown global item tag {prefix >> 4}", offset, f"0x{prefix:02X}")

    # -- hid_parser_local --------------------------------------------------------------------------------------
    def usage(self, offset: int, prefix: int, value: int) -> None:
        """Usage (the most frequent local item, dispatched on its own)."""
        if self.local.delimiter_branch <= 1:
            self.add_usages(offset, prefix, value, 1)

    def local_item(self, offset: int, prefix: int, value: int) -> None:
        """The other local items (the kernel's ``hid_parser_local``)."""
        local = self.local
        tag = prefix >> 4
        if tag == 1:
            if local.delimiter_branch <= 1:
                local.usage_min = value
        elif tag == 2:
            if local.delimiter_branch <= 1:
                self.usage_range(offset, prefix, value)
        elif tag == 10:
            if value:
                if local.delimiter_depth:
                    raise self.error("nested delimiters", offset)
                local.delimiter_depth += 1
                local.delimiter_branch += 1
            else:
                if local.delimiter_depth < 1:
                    raise self.error("close delimiter without an open one", offset)
                local.delimiter_depth -= 1
        elif tag in _LOCAL_EXTRAS:
            local.extra[_LOCAL_EXTRAS[tag]] = value

    def usage_range(self, offset: int, prefix: int, top: int) -> None:
        """Usage Maximum: add Usage Minimum..Maximum, clamped at 12288 usages as the kernel does."""
        local = self.local
        index = len(local.usages)
        if ((top - local.usage_min) + index) & _M32 >= MAX_USAGES:
            self.warnings.append(f"Usage Maximum at offset {offset}: range cut at {MAX_USAGES} usages")
            top = (MAX_USAGES - index + local.usage_min - 1) & _M32
            if top == 0:
                raise self.error("no more usages available", offset)
        if local.usage_min <= top:
            self.add_usages(offset, prefix, local.usage_min, top - local.usage_min + 1)

    def add_usages(self, offset: int, prefix: int, first: int, count: int) -> None:
        """Add ``count`` usages from ``first`` (the kernel's ``hid_add_usage``, completed with the page if short)."""
        local = self.local
        if len(local.usages) + count > MAX_USAGES:
            raise self.error(f"more than {MAX_USAGES} usages before one Main item", offset)
        if prefix & 3 == 3:  # a 4-byte (extended) usage carries its page
            local.usages.extend(range(first, first + count))
            local.extended.extend([True] * count)
            return
        page = (self.g.usage_page & 0xFFFF) << 16
        if count == 1:
            local.usages.append(page | first)
        elif first + count <= 0x10000:
            local.usages.extend(range(page | first, page | (first + count)))
        else:
            local.usages.extend(page | (u & 0xFFFF) for u in range(first, first + count))
        local.extended.extend([False] * count)

    # -- hid_parser_main ---------------------------------------------------------------------------------------
    def concatenate_last_usage_page(self) -> None:
        """Put the current Usage Page on the last short usages until one already has it (as the kernel)."""
        usages = self.local.usages
        page = self.g.usage_page  # compared whole, as the kernel does: a page over 0xFFFF never matches
        prefix = (page & 0xFFFF) << 16
        extended = self.local.extended
        for i in range(len(usages) - 1, -1, -1):
            if extended[i]:
                continue
            if usages[i] >> 16 == page:
                break
            usages[i] = prefix | (usages[i] & 0xFFFF)

    def main_item(self, offset: int, prefix: int, value: int) -> None:
        """One main item (the kernel's ``hid_parser_main``); local state is reset after it."""
        local = self.local
        if local.usages:
            self.concatenate_last_usage_page()
        tag = prefix >> 4
        if tag in _KINDS:
            self.add_field(offset, tag, value)
        elif tag == 10:
            if len(self.open) == MAX_COLLECTION_DEPTH:
                raise self.error(f"collections nested over {MAX_COLLECTION_DEPTH} deep", offset)
            usages = local.usages
            c = Collection(value & 0xFF, usages[0] if usages else 0, offset, self.open[-1] if self.open else None)
            self.open.append(c)
            self.collections.append(c)
        elif tag == 12:
            if not self.open:
                raise self.error("End Collection without a Collection", offset)
            self.open.pop()
        else:
            self.warnings.append(f"unknown main item 0x{prefix:02X} at offset {offset} ignored")
        if local.usages or local.usage_min or local.delimiter_branch or local.extra:
            self.local = _Locals()

    def add_field(self, offset: int, tag: int, flags: int) -> None:
        """An Input, Output or Feature item (the kernel's ``hid_add_field``)."""
        g = self.g
        rid = g.report_id
        report = self.reports.get((tag, rid))
        if report is None:
            report = self.reports[tag, rid] = _Report(_KINDS[tag], rid or None)
        lmin, lmax = g.logical_min, g.logical_max
        if lmin < 0:
            lmax = _s32(lmax)
            if lmax < lmin:
                raise self.error(f"Logical Maximum {lmax} is below Logical Minimum {lmin}", offset)
        elif lmax & _M32 < lmin:
            raise self.error(f"Logical Maximum {lmax & _M32} is below Logical Minimum {lmin}", offset)
        else:
            lmax &= _M32
        pmin, pmax = g.physical_min, g.physical_max
        pmax = _s32(pmax) if pmin < 0 else pmax & _M32
        start = report.bits
        count = g.report_count
        report.bits += g.report_size * count
        if report.bits > (MAX_BUFFER_SIZE - 1) * 8:
            raise self.error(f"{report.kind.value} report {report.report_id} is longer than {MAX_BUFFER_SIZE - 1} "
                             f"bytes ({report.bits} bits)", offset)
        usages = self.local.usages
        if usages:
            if report.with_usages == MAX_FIELDS:
                self.warnings.append(f"{report.kind.value} report {report.report_id}: field at offset {offset} "
                                     f"dropped (the kernel keeps {MAX_FIELDS} fields per report)")
                return
            report.with_usages += 1
            if count > len(usages):
                usages = usages + [usages[-1]] * (count - len(usages))
            # a variable has one usage per element; an array the usages an index lmin..lmax can name
            kept = tuple(usages[:count] if flags & 2 else usages[:lmax - lmin + 1])
            page = kept[0] >> 16 if kept else g.usage_page & 0xFFFF
        else:
            kept = ()
            page = g.usage_page & 0xFFFF
        extra = self.local.extra
        report.fields.append(Field(
            report.kind, report.report_id, page, kept, start + (8 if rid else 0), g.report_size, count,
            lmin, lmax, pmin, pmax, g.unit, g.unit_exponent, flags, self.open[-1] if self.open else None,
            offset, dict(extra) if extra else {}))

    def descriptor(self, data: bytes) -> ReportDescriptor:
        """The parsed descriptor."""
        numbered = {_KINDS[tag] for tag, rid in self.reports if rid}
        layouts = []
        for r in self.reports.values():
            fields = tuple(r.fields)
            if r.report_id is None and r.kind in numbered:
                # the kernel reads every report of a numbered kind with an ID byte, 0 for this one
                self.warnings.append(f"{r.kind.value} items with no Report ID in effect make {r.kind.value} "
                                     "report 0, read with an ID byte 0 like the numbered ones")
                r.report_id = 0
                fields = tuple(replace(f, report_id=0, bit_offset=f.bit_offset + 8) for f in fields)
            layouts.append(ReportLayout(r.kind, r.report_id, fields,
                                        (r.bits + 7) // 8 + (1 if r.report_id is not None else 0)))
        return ReportDescriptor(data, layouts, tuple(self.collections), tuple(self.warnings))


def _dispatch_table() -> list[Callable[[_Parser, int, int, int], None]]:
    """The handler of each prefix byte (the size bits do not matter; tag nibble 15 is a long item)."""
    p = _Parser
    by_tag = [p.usage_page, p.logical_min, p.logical_max, p.physical_min, p.physical_max, p.unit_exponent, p.unit,
              p.report_size, p.report_id, p.report_count, p.push, p.pop]
    table: list[Callable[[_Parser, int, int, int], None]] = []
    for prefix in range(256):
        tag, kind = prefix >> 4, (prefix >> 2) & 3
        if tag == LONG_ITEM_TAG:
            table.append(p.long_item)
        elif kind == MAIN:
            table.append(p.main_item)
        elif kind == GLOBAL:
            table.append(by_tag[tag] if tag < len(by_tag) else p.unknown_global)
        elif kind == LOCAL:
            table.append(p.usage if tag == 0 else p.local_item)
        else:
            table.append(p.reserved_item)
    return table


_DISPATCH = _dispatch_table()


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
    parser = _Parser(data, source)
    parser.warnings.extend(notes)
    parser.run(scan(data, source=source), reject_long_items)
    return parser.descriptor(data)

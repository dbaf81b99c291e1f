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
from pixelpen.devices.hid.items import GLOBAL, LOCAL, MAIN, Item, tokenize
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

    def __init__(self, source: str | None) -> None:
        self.source = source
        self.g = _Globals()
        self.stack: list[_Globals] = []
        self.local = _Locals()
        self.open: list[Collection] = []
        self.collections: list[Collection] = []
        self.reports: dict[tuple[ReportKind, int], _Report] = {}
        self.warnings: list[str] = []

    def error(self, message: str, item: Item, token: object = None) -> ParseError:
        """A ParseError at the item's offset."""
        return ParseError(message, source=self.source, offset=item.offset, token=token)

    def run(self, items: list[Item], reject_long_items: bool) -> None:
        """Process every item, then check that collections and delimiters are closed."""
        last = len(items)
        while last and items[last - 1].prefix == 0:  # trailing zero bytes
            last -= 1
        global_item, local_item, main_item = self.global_item, self.local_item, self.main_item
        for item in items[:last]:
            kind = item.type
            if item.long:
                if reject_long_items:
                    raise self.error(f"long item (tag 0x{item.tag:02X}, {item.size} data bytes): the kernel "
                                     "rejects descriptors with long items", item)
                self.warnings.append(f"long item (tag 0x{item.tag:02X}, {item.size} data bytes) at offset "
                                     f"{item.offset} skipped")
            elif kind == GLOBAL:
                global_item(item)
            elif kind == LOCAL:
                local_item(item)
            elif kind == MAIN:
                main_item(item)
            else:
                self.warnings.append(f"reserved item 0x{item.prefix:02X} at offset {item.offset} ignored")
        if last < len(items):  # the kernel reads the zeros as unknown Main items, which reset the local state
            self.local = _Locals()
        if self.open:
            inner = self.open[-1]
            raise ParseError(f"unbalanced collection: {len(self.open)} still open at the end of the descriptor "
                             f"(the innermost opened here)", source=self.source, offset=inner.offset)
        if self.local.delimiter_depth:
            raise ParseError("unbalanced delimiter at the end of the descriptor", source=self.source,
                             offset=items[last - 1].offset if last else 0)

    # -- hid_parser_global -------------------------------------------------------------------------------------
    def global_item(self, item: Item) -> None:
        """One global item (the kernel's ``hid_parser_global``)."""
        g = self.g
        tag = item.tag
        if tag == 0:
            g.usage_page = item.value
        elif tag == 1:
            g.logical_min = item.signed
        elif tag == 2:
            g.logical_max = item.signed if g.logical_min < 0 else item.value
        elif tag == 3:
            g.physical_min = item.signed
        elif tag == 4:
            g.physical_max = item.signed if g.physical_min < 0 else item.value
        elif tag == 7:
            if item.value > MAX_REPORT_SIZE:
                raise self.error(f"Report Size {item.value} bits is over the kernel's {MAX_REPORT_SIZE}", item)
            g.report_size = item.value
        elif tag == 9:
            if item.value > MAX_USAGES:
                raise self.error(f"Report Count {item.value} is over the kernel's {MAX_USAGES}", item)
            g.report_count = item.value
        elif tag == 8:
            if item.value == 0 or item.value >= MAX_IDS:
                raise self.error(f"Report ID {item.value} is invalid (1..{MAX_IDS - 1})", item)
            g.report_id = item.value
        elif tag == 5:
            raw = item.signed
            g.unit_exponent = (raw - 16 if raw & 8 else raw) if 0 <= raw <= 15 else raw
        elif tag == 6:
            g.unit = item.value
        elif tag == 10:
            if len(self.stack) == GLOBAL_STACK_SIZE:
                raise self.error(f"Push: the global stack is full ({GLOBAL_STACK_SIZE} deep)", item)
            self.stack.append(g.copy())
        elif tag == 11:
            if not self.stack:
                raise self.error("Pop without a Push (global stack underflow)", item)
            self.g = self.stack.pop()
        else:
            raise self.error(f"unknown global item tag {tag}", item, f"0x{item.prefix:02X}")

    # -- hid_parser_local --------------------------------------------------------------------------------------
    def local_item(self, item: Item) -> None:
        """One local item (the kernel's ``hid_parser_local``)."""
        local = self.local
        tag = item.tag
        if tag == 0:
            if local.delimiter_branch <= 1:
                self.add_usages(item, item.value, 1)
        elif tag == 1:
            if local.delimiter_branch <= 1:
                local.usage_min = item.value
        elif tag == 2:
            if local.delimiter_branch <= 1:
                self.usage_range(item)
        elif tag == 10:
            if item.value:
                if local.delimiter_depth:
                    raise self.error("nested delimiters", item)
                local.delimiter_depth += 1
                local.delimiter_branch += 1
            else:
                if local.delimiter_depth < 1:
                    raise self.error("close delimiter without an open one", item)
                local.delimiter_depth -= 1
        elif tag in _LOCAL_EXTRAS:
            local.extra[_LOCAL_EXTRAS[tag]] = item.value

    def usage_range(self, item: Item) -> None:
        """Usage Maximum: add Usage Minimum..Maximum, clamped at 12288 usages as the kernel does."""
        local = self.local
        top = item.value
        index = len(local.usages)
        if ((top - local.usage_min) + index) & _M32 >= MAX_USAGES:
            self.warnings.append(f"Usage Maximum at offset {item.offset}: range cut at {MAX_USAGES} usages")
            top = (MAX_USAGES - index + local.usage_min - 1) & _M32
            if top == 0:
                raise self.error("no more usages available", item)
        if local.usage_min <= top:
            self.add_usages(item, local.usage_min, top - local.usage_min + 1)

    def add_usages(self, item: Item, first: int, count: int) -> None:
        """Add ``count`` usages from ``first`` (the kernel's ``hid_add_usage``, completed with the page if short)."""
        local = self.local
        if len(local.usages) + count > MAX_USAGES:
            raise self.error(f"more than {MAX_USAGES} usages before one Main item", item)
        if item.size > 2:
            local.usages.extend(range(first, first + count))
            local.extended.extend([True] * count)
            return
        page = (self.g.usage_page & 0xFFFF) << 16
        if first + count <= 0x10000:
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

    def main_item(self, item: Item) -> None:
        """One main item (the kernel's ``hid_parser_main``); local state is reset after it."""
        if self.local.usages:
            self.concatenate_last_usage_page()
        tag = item.tag
        if tag in _KINDS:
            self.add_field(item, _KINDS[tag])
        elif tag == 10:
            if len(self.open) == MAX_COLLECTION_DEPTH:
                raise self.error(f"collections nested over {MAX_COLLECTION_DEPTH} deep", item)
            usages = self.local.usages
            c = Collection(item.value & 0xFF, usages[0] if usages else 0, item.offset,
                           self.open[-1] if self.open else None)
            self.open.append(c)
            self.collections.append(c)
        elif tag == 12:
            if not self.open:
                raise self.error("End Collection without a Collection", item)
            self.open.pop()
        else:
            self.warnings.append(f"unknown main item 0x{item.prefix:02X} at offset {item.offset} ignored")
        if self.local.usages or self.local.usage_min or self.local.delimiter_branch or self.local.extra:
            self.local = _Locals()

    def add_field(self, item: Item, kind: ReportKind) -> None:
        """An Input, Output or Feature item (the kernel's ``hid_add_field``)."""
        g = self.g
        key = (kind, g.report_id)
        report = self.reports.get(key)
        if report is None:
            report = self.reports[key] = _Report(kind, g.report_id or None)
        lmin, lmax = g.logical_min, g.logical_max
        if lmin < 0:
            lmax = _s32(lmax)
            if lmax < lmin:
                raise self.error(f"Logical Maximum {lmax} is below Logical Minimum {lmin}", item)
        elif lmax & _M32 < lmin:
            raise self.error(f"Logical Maximum {lmax & _M32} is below Logical Minimum {lmin}", item)
        else:
            lmax &= _M32
        pmin, pmax = g.physical_min, g.physical_max
        pmax = _s32(pmax) if pmin < 0 else pmax & _M32
        offset = report.bits
        report.bits += g.report_size * g.report_count
        if report.bits > (MAX_BUFFER_SIZE - 1) * 8:
            raise self.error(f"{kind.value} report {report.report_id} is longer than {MAX_BUFFER_SIZE - 1} "
                             f"bytes ({report.bits} bits)", item)
        usages = self.local.usages
        count = g.report_count
        if usages:
            if report.with_usages == MAX_FIELDS:
                self.warnings.append(f"{kind.value} report {report.report_id}: field at offset {item.offset} "
                                     f"dropped (the kernel keeps {MAX_FIELDS} fields per report)")
                return
            report.with_usages += 1
            if count > len(usages):
                usages = usages + [usages[-1]] * (count - len(usages))
            if item.value & 2:  # variable: one usage per element
                kept = tuple(usages[:count])
            else:  # array: the usages an index lmin..lmax can name
                kept = tuple(usages[:lmax - lmin + 1])
            page = kept[0] >> 16 if kept else g.usage_page & 0xFFFF
        else:
            kept = ()
            page = g.usage_page & 0xFFFF
        extra = self.local.extra
        report.fields.append(Field(
            kind, report.report_id, page, kept, offset + (8 if g.report_id else 0), g.report_size, count,
            lmin, lmax, pmin, pmax, g.unit, g.unit_exponent, item.value, self.open[-1] if self.open else None,
            item.offset, dict(extra) if extra else {}))

    def descriptor(self, data: bytes) -> ReportDescriptor:
        """The parsed descriptor."""
        numbered = {kind for kind, rid in self.reports if rid}
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
    parser = _Parser(source)
    parser.warnings.extend(notes)
    parser.run(tokenize(data, source=source), reject_long_items)
    return parser.descriptor(data)

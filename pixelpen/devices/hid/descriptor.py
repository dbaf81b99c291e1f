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
  uhid and hidraw enforce), collections nested over :data:`MAX_COLLECTION_DEPTH` deep, and fields holding
  over :data:`MAX_TOTAL_USAGES` usages in all are refused (the kernel's limits let 4 KB name 4.9 million
  usages: 200 MB and half a second here).

Every error is a :class:`~pixelpen.errors.ParseError` whose ``offset`` is the byte offset of the item at fault.
"""

from __future__ import annotations

from dataclasses import replace

from pixelpen.devices.hid.fields import Collection, Field, ReportDescriptor, ReportKind, ReportLayout
from pixelpen.devices.hid.items import SIGN, exponent_value, s32, scan
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
MAX_TOTAL_USAGES = 131072
"""Usages the fields of one descriptor may hold in all (ours: ten full Report Count ranges; about 5 MB)."""

_M32 = 0xFFFFFFFF
_INPUT, _OUTPUT, _FEATURE = ReportKind
_TAG_KINDS = {8: _INPUT, 9: _OUTPUT, 11: _FEATURE}
_KINDS = tuple(_TAG_KINDS.get(prefix >> 4) if prefix & 0x0C == 0 else None for prefix in range(256))
"""The report space of each prefix byte that is an Input, Output or Feature item."""
_MAIN_KEYS = tuple(prefix >> 4 << 8 for prefix in range(256))
"""A Main item's tag << 8: the key of its reports, with the report ID in the low byte."""
_BIT_OF_KIND = {_INPUT: 1, _OUTPUT: 2, _FEATURE: 4}
_KIND_BITS = tuple(_BIT_OF_KIND[kind] if kind else 0 for kind in _KINDS)
"""The bit of each Input, Output and Feature prefix byte's report space in a mask of spaces."""
_NUMBERED = tuple(frozenset(k for k, bit in _BIT_OF_KIND.items() if mask & bit) for mask in range(8))
"""The report spaces, as a set, of each mask of :data:`_KIND_BITS`."""
_LOCAL_EXTRAS = {0x38: "designator_index", 0x48: "designator_minimum", 0x58: "designator_maximum",
                 0x78: "string_index", 0x88: "string_minimum", 0x98: "string_maximum"}
"""Local items kept for the dump, by prefix without its size bits."""
_REPORT_BITS = (MAX_BUFFER_SIZE - 1) * 8
"""Bits a report may hold after its ID byte (``hid_add_field``'s check)."""

# What the item loop does per prefix byte, numbered by how often descriptors use them: the loop sends the Main items
# (numbered last) to their branch with one comparison, the next six (_USAGE .. _PAGE) with a second one to a small
# tree, and tries the rest in this order.
(_USAGE, _COUNT, _SIZE, _LMAX, _LMIN, _PAGE, _PMAX, _PMIN, _UNIT, _USAGE_MIN, _USAGE_MAX, _REPORT_ID, _EXPONENT,
 _EXT_USAGE, _PUSH, _POP, _DELIMITER, _EXTRA, _IGNORED, _BAD_GLOBAL, _RESERVED,
 _FIELD, _COLLECTION, _END, _BAD_MAIN) = range(25)
_WIDE, _LONG = 25, 26
"""Not a branch: a short item of 0, 2 or 4 data bytes (its branch is then read from :data:`_WIDE_OPS`), a long item."""
_GLOBAL_OPS = {0x04: _PAGE, 0x14: _LMIN, 0x24: _LMAX, 0x34: _PMIN, 0x44: _PMAX, 0x54: _EXPONENT, 0x64: _UNIT,
               0x74: _SIZE, 0x84: _REPORT_ID, 0x94: _COUNT, 0xA4: _PUSH, 0xB4: _POP}
_LOCAL_OPS = {0x08: _USAGE, 0x18: _USAGE_MIN, 0x28: _USAGE_MAX, 0xA8: _DELIMITER} | dict.fromkeys(_LOCAL_EXTRAS, _EXTRA)
_MAIN_OPS = {0x80: _FIELD, 0x90: _FIELD, 0xB0: _FIELD, 0xA0: _COLLECTION, 0xC0: _END}


def _op(prefix: int) -> int:
    """The item loop's branch for one prefix byte."""
    t, kind = prefix & 0xFC, prefix & 0x0C
    if prefix >= 0xF0:
        return _LONG
    if kind == 4:
        return _GLOBAL_OPS.get(t, _BAD_GLOBAL)
    if kind == 8:
        return _EXT_USAGE if prefix == 0x0B else _LOCAL_OPS.get(t, _IGNORED)
    return _MAIN_OPS.get(t, _BAD_MAIN) if kind == 0 else _RESERVED


_WIDE_OPS = [_op(prefix) for prefix in range(256)]
"""The branch of every prefix byte (a list: its items are read faster than a tuple's)."""
_OPS = [op if prefix & 3 == 1 or op == _LONG else _WIDE for prefix, op in enumerate(_WIDE_OPS)]
"""What the loop reads first: the branch of a one-data-byte item, else :data:`_WIDE` or :data:`_LONG`."""
_ALTERNATIVE = {_USAGE: _IGNORED, _USAGE_MIN: _IGNORED, _USAGE_MAX: _IGNORED, _EXT_USAGE: _IGNORED}
_ALTERNATIVE_WIDE_OPS = [_ALTERNATIVE.get(op, op) for op in _WIDE_OPS]
_ALTERNATIVE_OPS = [_ALTERNATIVE.get(op, op) for op in _OPS]
"""The tables in the second and later alternative usage sets of a delimiter, whose usages are ignored."""


def _error(data: bytes, source: str | None, message: str, offset: int, token: object = None) -> ParseError:
    """The error of the item at ``offset``, unless an item cut short by the end comes first (raised then)."""
    scan(data, source=source)
    return ParseError(message, source=source, offset=offset, token=token)


# The per-usage work is done in these small functions, not in the item loop: an int allocated from a frame costs
# a walk of that frame's line table under tracemalloc (Python 3.11 caches the line of an instruction only while a
# tracer runs), and the item loop's table is long, so 12288 usages allocated from it took a second.
def _add_usages(usages: list[int], first: int, count: int, page16: int | None) -> None:
    """Append the usages ``first .. first + count - 1``: as 16-bit IDs under ``page16``, or whole when it is None."""
    if page16 is None:
        usages.extend(range(first, first + count))
    elif first + count <= 0x10000:
        usages.extend(range(page16 | first, page16 | (first + count)))
    else:
        usages.extend([page16 | (u & 0xFFFF) for u in range(first, first + count)])


def _concatenate_last_usage_page(usages: list[int], extended: list[tuple[int, int]], usage_page: int,
                                 page16: int) -> None:
    """``hid_concatenate_last_usage_page``: from the last usage back, give the current page to the 1–2-byte
    usages until one already has it, stepping over the runs of 4-byte usages (the page is compared whole, as
    the kernel does)."""
    k, run = len(usages) - 1, len(extended) - 1
    while k >= 0:
        if run >= 0 and k < extended[run][1]:  # runs are in index order, k walks down over them
            k = min(k, extended[run][0] - 1)
            run -= 1
        elif usages[k] >> 16 == usage_page:
            break
        else:
            usages[k] = page16 | (usages[k] & 0xFFFF)
            k -= 1


_BITS, _PADDING, _FIELDS, _KIND, _ID, _ID_BITS = range(6)
"""A report being built is a list: its length in bits (without the ID byte, as the kernel counts), its fields
without usages, its Field objects, its kind, its report ID (None when unnumbered) and the bits of its ID byte
(a list is made and read faster than an object with attributes)."""


def _parse(data: bytes, source: str | None, reject_long_items: bool, warnings: list[str]) -> ReportDescriptor:
    """The kernel's ``hid_open_report`` over the bytes, as a :class:`ReportDescriptor`.

    One loop cuts the items (as :func:`~pixelpen.devices.hid.items.scan` does) and parses each at once, with
    the parser state in local variables and a branch per prefix byte from :data:`_OPS`:
    ``hid_parser_global``, ``hid_parser_local`` and ``hid_parser_main`` are its branches (an item tuple, the
    state as attributes or a method per item cost more than the parsing itself).  The bytes are read from a
    list with four zeros after it, so the last item reads its data without a bounds check; an item cut short
    by the end is then found by :func:`scan`, which is run before any error is raised, so that a truncation is
    reported first wherever it is, as when the items are cut before they are parsed."""

    # globals (struct hid_global), pushed and popped as one tuple; page16 is the Usage Page as a usage's top half
    usage_page = lmin = lmax = pmin = pmax = exponent = unit = report_size = rid = report_count = page16 = 0
    stack: list[tuple[int, ...]] = []
    # locals (struct hid_local), reset after every Main item
    usages: list[int] = []
    extended: list[tuple[int, int]] = []  # index runs [start, stop) of 4-byte usages, which keep their own page
    usage_min = delimiter_depth = delimiter_branch = 0
    extra: dict[str, object] = {}
    parent: Collection | None = None  # the innermost open collection
    depth = 0
    collections: list[Collection] = []
    reports: dict[int, list] = {}  # by Main tag << 8 | report ID
    order: list[tuple[ReportKind, int | None, list]] = []
    spaces: dict[ReportKind, dict[int | None, list[Field]]] = {_INPUT: {}, _OUTPUT: {}, _FEATURE: {}}
    numbered = unnumbered = 0  # masks of _KIND_BITS: the spaces with reports with and without an ID
    total_usages = 0
    n = len(data)
    zeros = len(data.rstrip(b"\0"))  # a 0x00 item from here on starts the trailing zero bytes
    buf = [*data, 0, 0, 0, 0]  # a list: its items are read faster than a bytes object's
    ops, wide_ops = _OPS, _WIDE_OPS
    sign = SIGN  # items.signed_value, inline: a call per item costs more than the item
    kinds = _KINDS
    field = Field
    i = offset = 0
    while i < n:
        offset = i
        prefix = buf[i]
        op = ops[prefix]
        if op < _WIDE:  # one data byte: most items
            value = buf[i + 1]
            i += 2
        elif op == _WIDE:  # 0, 2 or 4 data bytes: the op of the prefix, when the value is read
            size = prefix & 3
            if size == 2:
                value = buf[i + 1] | buf[i + 2] << 8
                i += 3
            elif size:
                value = buf[i + 1] | buf[i + 2] << 8 | buf[i + 3] << 16 | buf[i + 4] << 24
                i += 5
            else:
                value = 0
                i += 1
            op = wide_ops[prefix]
        else:  # a long item
            value = buf[offset + 1]
            i = offset + 3 + value
            what = f"long item (tag 0x{buf[offset + 2]:02X}, {value} data bytes)"
            if reject_long_items:
                raise _error(data, source, f"{what}: the kernel rejects descriptors with long items", offset)
            warnings.append(f"{what} at offset {offset} skipped")
            continue
        if op >= _FIELD:  # -- hid_parser_main -------------------------------------------------------------------
            if usages and (extended or usages[-1] >> 16 != usage_page):
                _concatenate_last_usage_page(usages, extended, usage_page, page16)
            if op == _FIELD:  # hid_add_field
                report = reports.get(_MAIN_KEYS[prefix] | rid)
                if report is None:
                    kind = kinds[prefix]
                    report = reports[_MAIN_KEYS[prefix] | rid] = [0, 0, [], kind, rid or None, 8 if rid else 0]
                    order.append((kind, rid or None, report))
                    spaces[kind][rid or None] = report[_FIELDS]
                    if rid:
                        numbered |= _KIND_BITS[prefix]
                    else:
                        unnumbered |= _KIND_BITS[prefix]
                # the logical range as the kernel compares it: signed when the minimum is negative (the maximum
                # is then an s32), unsigned otherwise; items.s32 inline, as the maximum is -2**31 .. 2**32 - 1
                lo, hi = lmin, lmax
                if lo < 0:
                    if hi > 0x7FFFFFFF:
                        hi -= 0x100000000
                elif hi < 0:
                    hi += 0x100000000
                if hi < lo:
                    raise _error(data, source, f"Logical Maximum {hi} is below Logical Minimum {lo}", offset)
                start = report[_BITS]
                bits = report[_BITS] = start + report_size * report_count
                if bits > _REPORT_BITS:
                    raise _error(data, source, f"{report[_KIND].value} report {report[_ID]} is longer than "
                                 f"{MAX_BUFFER_SIZE - 1} bytes ({bits} bits)", offset)
                fields = report[_FIELDS]
                if usages and len(fields) >= MAX_FIELDS and len(fields) - report[_PADDING] == MAX_FIELDS:
                    warnings.append(f"{report[_KIND].value} report {report[_ID]}: field at offset {offset} "
                                    f"dropped (the kernel keeps {MAX_FIELDS} fields per report)")
                else:
                    if usages:
                        if report_count == len(usages) and value & 2:  # one usage per element
                            kept = tuple(usages)
                        else:
                            listed = usages if report_count <= len(usages) else \
                                usages + [usages[-1]] * (report_count - len(usages))  # the last usage repeats
                            # a variable has one usage per element; an array the usages an index lo..hi can name
                            kept = tuple(listed[:report_count] if value & 2 else listed[:hi - lo + 1])
                        page = kept[0] >> 16 if kept else usage_page & 0xFFFF
                        total_usages += len(kept)
                        if total_usages > MAX_TOTAL_USAGES:
                            raise _error(data, source, f"the fields hold over {MAX_TOTAL_USAGES} usages in all "
                                         "(pixelpen's limit; the kernel's per item)", offset)
                    else:  # padding: kept, with no usages (the kernel registers no field for it)
                        kept = ()
                        page = usage_page & 0xFFFF
                        report[_PADDING] += 1
                    fields.append(field(report[_KIND], report[_ID], page, kept, start + report[_ID_BITS],
                                        report_size, report_count, lo, hi, pmin,
                                        s32(pmax) if pmin < 0 else pmax & _M32, unit, exponent,
                                        value, parent, offset, extra))
                    extra = {}  # the field's own
            elif op == _COLLECTION:
                if depth == MAX_COLLECTION_DEPTH:
                    raise _error(data, source, f"collections nested over {MAX_COLLECTION_DEPTH} deep", offset)
                parent = Collection(value & 0xFF, usages[0] if usages else 0, offset, parent)
                collections.append(parent)
                depth += 1
            elif op == _END:
                if parent is None:
                    raise _error(data, source, "End Collection without a Collection", offset)
                parent = parent.parent
                depth -= 1
            elif prefix == 0 and offset >= zeros:
                # the kernel reads trailing zeros as unknown Main items, which reset the local state
                delimiter_depth = 0
                break
            else:
                warnings.append(f"unknown main item 0x{prefix:02X} at offset {offset} ignored")
            if usages or usage_min or delimiter_branch or extra:
                usages = []
                if extended:
                    extended = []
                if delimiter_branch:
                    ops, wide_ops = _OPS, _WIDE_OPS
                usage_min = delimiter_depth = delimiter_branch = 0
                if extra:
                    extra = {}
        elif op < _PMAX:  # the six commonest items, in a tree of comparisons one down from the Main items
            if op < _LMAX:
                if op == _USAGE:  # -- hid_parser_local ---------------------------------------------------------
                    if len(usages) >= MAX_USAGES:
                        raise _error(data, source, f"more than {MAX_USAGES} usages before one Main item", offset)
                    usages.append(page16 | value)
                elif op == _COUNT:  # -- hid_parser_global --------------------------------------------------
                    if value > MAX_USAGES:
                        raise _error(data, source, f"Report Count {value} is over the kernel's {MAX_USAGES}", offset)
                    report_count = value
                else:  # _SIZE
                    if value > MAX_REPORT_SIZE:
                        raise _error(data, source, f"Report Size {value} bits is over the kernel's "
                                     f"{MAX_REPORT_SIZE}", offset)
                    report_size = value
            elif op == _LMAX:  # signed only when the minimum before it is negative
                lmax = value - ((value << 1) & sign[prefix]) if lmin < 0 else value
            elif op == _LMIN:
                lmin = value - ((value << 1) & sign[prefix])
            else:  # _PAGE
                usage_page = value
                page16 = (value & 0xFFFF) << 16
        elif op == _PMAX:
            pmax = value - ((value << 1) & sign[prefix]) if pmin < 0 else value
        elif op == _PMIN:
            pmin = value - ((value << 1) & sign[prefix])
        elif op == _UNIT:
            unit = value
        elif op == _USAGE_MIN:
            usage_min = value
        elif op in (_USAGE_MAX, _EXT_USAGE):
            if op == _EXT_USAGE:
                first = value
                count = 1
            else:
                top = value
                if ((top - usage_min) + len(usages)) & _M32 >= MAX_USAGES:
                    warnings.append(f"Usage Maximum at offset {offset}: range cut at {MAX_USAGES} usages")
                    top = (MAX_USAGES - len(usages) + usage_min - 1) & _M32
                    if top == 0:
                        raise _error(data, source, "no more usages available", offset)
                if usage_min > top:
                    continue
                first, count = usage_min, top - usage_min + 1
            if len(usages) + count > MAX_USAGES:
                raise _error(data, source, f"more than {MAX_USAGES} usages before one Main item", offset)
            if prefix & 3 == 3:  # 4 bytes: an extended usage carries its page
                extended.append((len(usages), len(usages) + count))
                _add_usages(usages, first, count, None)
            else:
                _add_usages(usages, first, count, page16)
        elif op == _REPORT_ID:
            if value == 0 or value >= MAX_IDS:
                raise _error(data, source, f"Report ID {value} is invalid (1..{MAX_IDS - 1})", offset)
            rid = value
        elif op == _EXPONENT:
            exponent = exponent_value(prefix, value)
        elif op == _PUSH:
            if len(stack) == GLOBAL_STACK_SIZE:
                raise _error(data, source, f"Push: the global stack is full ({GLOBAL_STACK_SIZE} deep)", offset)
            stack.append((usage_page, lmin, lmax, pmin, pmax, exponent, unit, report_size, rid, report_count))
        elif op == _POP:
            if not stack:
                raise _error(data, source, "Pop without a Push (global stack underflow)", offset)
            usage_page, lmin, lmax, pmin, pmax, exponent, unit, report_size, rid, report_count = stack.pop()
            page16 = (usage_page & 0xFFFF) << 16
        elif op == _DELIMITER:
            if value:
                if delimiter_depth:
                    raise _error(data, source, "nested delimiters", offset)
                delimiter_depth += 1
                delimiter_branch += 1
                if delimiter_branch > 1:  # an alternative usage set: its usages are ignored
                    ops, wide_ops = _ALTERNATIVE_OPS, _ALTERNATIVE_WIDE_OPS
            else:
                if delimiter_depth < 1:
                    raise _error(data, source, "close delimiter without an open one", offset)
                delimiter_depth -= 1
        elif op == _EXTRA:
            extra[_LOCAL_EXTRAS[prefix & 0xFC]] = value
        elif op == _BAD_GLOBAL:
            raise _error(data, source, f"unknown global item tag {prefix >> 4}", offset, f"0x{prefix:02X}")
        elif op == _RESERVED:
            warnings.append(f"reserved item 0x{prefix:02X} at offset {offset} ignored")
    if i > n:  # the last item is cut short
        scan(data, source=source)
    if parent is not None:
        raise ParseError(f"unbalanced collection: {depth} still open at the end of the descriptor "
                         f"(the innermost opened here)", source=source, offset=parent.offset)
    if delimiter_depth:  # (trailing zeros reset it: offset is the last item's)
        raise ParseError("unbalanced delimiter at the end of the descriptor", source=source, offset=offset)
    if numbered & unnumbered:
        _number_report_0(order, spaces, _NUMBERED[numbered], warnings)
    layouts = {(kind, rid): ReportLayout(kind, rid, tuple(report[_FIELDS]),
                                         (report[_BITS] + 7) // 8 + (0 if rid is None else 1))
               for kind, rid, report in order}
    return ReportDescriptor.parsed(data, spaces, layouts, tuple(collections), tuple(warnings), _NUMBERED[numbered])


def _number_report_0(order: list[tuple[ReportKind, int | None, list]],
                     spaces: dict[ReportKind, dict[int | None, list[Field]]], numbered: frozenset[ReportKind],
                     warnings: list[str]) -> None:
    """Make the reports with no ID in a space that numbers its reports report 0 (in place)."""
    for k, (kind, rid, report) in enumerate(order):
        if rid is None and kind in numbered:
            # the kernel reads every report of a numbered kind with an ID byte, 0 for this one
            warnings.append(f"{kind.value} items with no Report ID in effect make {kind.value} "
                            "report 0, read with an ID byte 0 like the numbered ones")
            report[_FIELDS] = [replace(f, report_id=0, bit_offset=f.bit_offset + 8) for f in report[_FIELDS]]
            order[k] = (kind, 0, report)
            spaces[kind] = {0 if r is None else r: report[_FIELDS] if r is None else fields
                            for r, fields in spaces[kind].items()}


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
        data = bytes(data)  # (the descriptor keeps it as it was parsed)
    if not data:
        raise ParseError("empty report descriptor", source=source, offset=0)
    return _parse(data, source, reject_long_items, notes)

"""A human-readable dump of a parsed report descriptor, item by item like hid-decode, then report by report.

:func:`dump_descriptor` lists every item with its byte offset, its bytes in hex and its decoded meaning,
indented by collection; then each report (kind, ID, length) with its fields (bit offset, size x count,
usages, logical and physical ranges, unit), then the parser's warnings.  :func:`descriptor_dict` gives the
same as plain data (for ``pixelpen hid dump --format json``).
"""

from __future__ import annotations

from typing import NamedTuple

from pixelpen.devices.hid.fields import (
    MAIN_BUFFERED_BYTES,
    MAIN_CONSTANT,
    MAIN_NO_PREFERRED,
    MAIN_NONLINEAR,
    MAIN_NULL_STATE,
    MAIN_RELATIVE,
    MAIN_VARIABLE,
    MAIN_VOLATILE,
    MAIN_WRAP,
    CollectionKind,
    Field,
    ReportDescriptor,
    ReportLayout,
)
from pixelpen.devices.hid.items import GLOBAL, LOCAL, MAIN, Item, exponent_value, tokenize
from pixelpen.devices.hid.units import describe_unit
from pixelpen.devices.hid.usages import page_name, usage_name

SHOWN_BYTES = 8
"""Data bytes of a long item shown in hex (the rest is counted)."""
SHOWN_USAGES = 8
"""Usages listed per field before the list is cut short (contiguous runs count as one)."""

_FLAG_WORDS = ((MAIN_WRAP, "Wrap"), (MAIN_NONLINEAR, "Non Linear"), (MAIN_NO_PREFERRED, "No Preferred State"),
               (MAIN_NULL_STATE, "Null State"), (MAIN_VOLATILE, "Volatile"), (MAIN_BUFFERED_BYTES, "Buffered Bytes"))


class ItemRow(NamedTuple):
    """One item of the dump: where it is, its bytes, its collection depth and its decoded text."""

    offset: int
    data: bytes
    depth: int
    text: str


def flag_text(flags: int, main_tag: int = 8) -> str:
    """A Main item's data bits as text: ``"Data,Var,Abs"`` and the set ones of Wrap ... Buffered Bytes."""
    words = ["Const" if flags & MAIN_CONSTANT else "Data", "Var" if flags & MAIN_VARIABLE else "Arr",
             "Rel" if flags & MAIN_RELATIVE else "Abs"]
    words += [w for bit, w in _FLAG_WORDS if flags & bit and not (bit == MAIN_VOLATILE and main_tag == 8)]
    return ",".join(words)


def _collection_text(kind: int) -> str:
    if kind in CollectionKind._value2member_map_:
        return CollectionKind(kind).name.replace("_", " ").title()
    return f"Vendor-defined 0x{kind:02X}" if kind >= 0x80 else f"Reserved 0x{kind:02X}"


class _State:
    """What the dump needs to name values: the Usage Page and the minima (for the Maxima's sign), with Push/Pop."""

    def __init__(self) -> None:
        self.page = self.lmin = self.pmin = 0
        self.stack: list[tuple[int, int, int]] = []

    def text(self, item: Item) -> str:
        """The item's decoded value, in parentheses after its name."""
        t, tag = item.type, item.tag
        if item.long:
            return f"Long item (tag 0x{item.tag:02X}, {item.size} data bytes)"
        if t == MAIN:
            if tag in (8, 9, 11):
                return f"{item.name} ({flag_text(item.value, tag)})"
            if tag == 10:
                return f"Collection ({_collection_text(item.value & 0xFF)})"
            return item.name
        if t == GLOBAL:
            return self._global(item)
        if t == LOCAL:
            if tag in (0, 1, 2):
                usage = item.value if item.size > 2 else (self.page & 0xFFFF) << 16 | item.value
                return f"{item.name} ({usage_name(usage)})"
            if tag == 10:
                return f"Delimiter ({'Open' if item.value else 'Close'})"
            return f"{item.name} ({item.value})"
        return f"Reserved item tag {tag} ({item.value})"

    def _global(self, item: Item) -> str:
        tag, name = item.tag, item.name
        if tag == 0:
            self.page = item.value
            return f"{name} ({page_name(item.value)})"
        if tag == 10:
            self.stack.append((self.page, self.lmin, self.pmin))
            return name
        if tag == 11:
            if self.stack:
                self.page, self.lmin, self.pmin = self.stack.pop()
            return name
        if tag in (1, 3):
            if tag == 1:
                self.lmin = item.signed
            else:
                self.pmin = item.signed
            return f"{name} ({item.signed})"
        if tag in (2, 4):
            signed = (self.lmin if tag == 2 else self.pmin) < 0
            return f"{name} ({item.signed if signed else item.value})"
        if tag == 5:
            return f"{name} ({exponent_value(item.prefix, item.value)})"
        if tag == 6:
            return f"{name} ({describe_unit(item.value)}, 0x{item.value:X})" if item.value else f"{name} (None)"
        return f"{name} ({item.value})"


def item_rows(descriptor: ReportDescriptor) -> list[ItemRow]:
    """Every item of the descriptor with its offset, bytes, collection depth and decoded text."""
    data = descriptor.data
    state = _State()
    depth = 0
    rows = []
    for item in tokenize(data):
        if item.type == MAIN and item.tag == 12 and not item.long:
            depth = max(0, depth - 1)
        rows.append(ItemRow(item.offset, bytes(data[item.offset:item.end]), depth, state.text(item)))
        if item.type == MAIN and item.tag == 10 and not item.long:
            depth += 1
    return rows


def _runs(usages: tuple[int, ...]) -> list[tuple[int, int]]:
    """Usages as (first, last) runs of consecutive values."""
    runs: list[tuple[int, int]] = []
    for u in usages:
        if runs and u == runs[-1][1] + 1:
            runs[-1] = (runs[-1][0], u)
        else:
            runs.append((u, u))
    return runs


def usages_text(usages: tuple[int, ...]) -> str:
    """A field's usages, consecutive runs as ``first .. last``, cut after :data:`SHOWN_USAGES` runs."""
    runs = [r for a, b in _runs(usages) for r in (((a, a), (b, b)) if b == a + 1 else ((a, b),))]
    parts = [usage_name(a) if a == b else f"{usage_name(a)} .. {usage_name(b)}" for a, b in runs[:SHOWN_USAGES]]
    if len(runs) > SHOWN_USAGES:
        parts.append(f"... ({len(runs) - SHOWN_USAGES} more)")
    return ", ".join(parts)


def field_text(f: Field) -> str:
    """One field on one line: bits, size x count, kind, usages, ranges, unit, flags."""
    head = f"bit {f.bit_offset:4d}  {f.bit_size:2d} x {f.count:<3d}"
    if not f.usages:
        return f"{head}  padding ({flag_text(f.flags)})"
    what = "array of" if f.is_array else ""
    parts = [f"{head}  {what + ' ' if what else ''}{usages_text(f.usages)}",
             f"logical {f.logical_min}..{f.logical_max}"]
    if f.physical_min or f.physical_max:
        parts.append(f"physical {f.physical_min}..{f.physical_max}")
    if f.unit or f.unit_exponent:
        parts.append(f"unit {describe_unit(f.unit, f.unit_exponent)}")
    parts.append(f"({flag_text(f.flags, {'input': 8, 'output': 9}.get(f.kind.value, 11))})")
    return "  ".join(parts)


def report_title(layout: ReportLayout) -> str:
    """``"Input report 1: 8 bytes (ID byte + 7)"`` or ``"Input report (unnumbered): 3 bytes"``."""
    kind = layout.kind.value.capitalize()
    size = f"{layout.length} byte{'' if layout.length == 1 else 's'}"
    if layout.report_id is None:
        return f"{kind} report (unnumbered): {size}"
    return f"{kind} report {layout.report_id}: {size} (ID byte + {layout.length - 1})"


def dump_descriptor(descriptor: ReportDescriptor) -> str:
    """The descriptor item by item (offset, hex bytes, decoded, indented by collection), its reports, warnings."""
    rows = item_rows(descriptor)
    lines = [f"Report descriptor: {len(descriptor.data)} bytes, {len(rows)} items", "offset  bytes           item"]
    for row in rows:
        shown = row.data[:1 + 2 + SHOWN_BYTES] if len(row.data) > 5 else row.data
        hexed = shown.hex(" ").upper() + (f" ... (+{len(row.data) - len(shown)})" if len(shown) < len(row.data)
                                          else "")
        lines.append(f"{row.offset:6d}  {hexed:<15s} {'  ' * row.depth}{row.text}")
    for layout in descriptor.layouts.values():
        lines.append("")
        lines.append(report_title(layout))
        lines.extend("  " + field_text(f) for f in layout.fields)
    if descriptor.warnings:
        lines.append("")
        lines.append("Warnings:")
        lines.extend(f"  {w}" for w in descriptor.warnings)
    return "\n".join(lines) + "\n"


def field_dict(f: Field) -> dict[str, object]:
    """One field as plain data (the public Field attributes, usages with their names)."""
    return {
        "bit_offset": f.bit_offset, "bit_size": f.bit_size, "count": f.count, "usage_page": f.usage_page,
        "usages": list(f.usages), "usage_names": [usage_name(u) for u in _unique(f.usages)],
        "logical_min": f.logical_min, "logical_max": f.logical_max, "physical_min": f.physical_min,
        "physical_max": f.physical_max, "unit": f.unit, "unit_exponent": f.unit_exponent,
        "unit_text": describe_unit(f.unit, f.unit_exponent), "flags": f.flags, "is_array": f.is_array,
        "is_constant": f.is_constant, "is_relative": f.is_relative, "descriptor_offset": f.offset,
    }


def _unique(usages: tuple[int, ...]) -> list[int]:
    return list(dict.fromkeys(usages))


def descriptor_dict(descriptor: ReportDescriptor) -> dict[str, object]:
    """The dump as plain data: items, reports with their fields, warnings."""
    return {
        "size": len(descriptor.data),
        "items": [{"offset": r.offset, "bytes": r.data.hex(" "), "depth": r.depth, "text": r.text}
                  for r in item_rows(descriptor)],
        "reports": [{"kind": lay.kind.value, "report_id": lay.report_id, "length": lay.length,
                     "fields": [field_dict(f) for f in lay.fields]} for lay in descriptor.layouts.values()],
        "warnings": list(descriptor.warnings),
    }

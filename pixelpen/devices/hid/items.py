"""The items of a HID report descriptor: short items (0, 1, 2 or 4 data bytes) and long items, with their offsets.

A short item's prefix is ``bTag(4) bType(2) bSize(2)`` (HID 1.11 §6.2.2.2); size code 3 means four data
bytes, little-endian.  A long item is ``prefix, bDataSize, bLongItemTag, data`` (§6.2.2.3): the spec's prefix
is 0xFE, and like the kernel's ``fetch_item`` (drivers/hid/hid-core.c) every prefix whose tag nibble is 15
(0xF0..0xFF) is read as one.  :func:`tokenize` cuts the bytes into :class:`Item` tuples (for the dump), :func:`scan`
into plain ``(offset, prefix, value)`` tuples; a truncated item is a ParseError naming its offset.  The parser
cuts the items in its own loop (a tuple per item costs more than the parsing) and calls :func:`scan` for the
error of a truncated item.
"""

from __future__ import annotations

from typing import NamedTuple

from pixelpen.errors import ParseError

MAIN, GLOBAL, LOCAL, RESERVED = 0, 1, 2, 3
"""The item types (bType)."""

TYPE_NAMES = ("Main", "Global", "Local", "Reserved")
"""Item type names by bType."""

ITEM_NAMES: dict[tuple[int, int], str] = {
    (MAIN, 8): "Input", (MAIN, 9): "Output", (MAIN, 10): "Collection", (MAIN, 11): "Feature",
    (MAIN, 12): "End Collection",
    (GLOBAL, 0): "Usage Page", (GLOBAL, 1): "Logical Minimum", (GLOBAL, 2): "Logical Maximum",
    (GLOBAL, 3): "Physical Minimum", (GLOBAL, 4): "Physical Maximum", (GLOBAL, 5): "Unit Exponent",
    (GLOBAL, 6): "Unit", (GLOBAL, 7): "Report Size", (GLOBAL, 8): "Report ID", (GLOBAL, 9): "Report Count",
    (GLOBAL, 10): "Push", (GLOBAL, 11): "Pop",
    (LOCAL, 0): "Usage", (LOCAL, 1): "Usage Minimum", (LOCAL, 2): "Usage Maximum",
    (LOCAL, 3): "Designator Index", (LOCAL, 4): "Designator Minimum", (LOCAL, 5): "Designator Maximum",
    (LOCAL, 7): "String Index", (LOCAL, 8): "String Minimum", (LOCAL, 9): "String Maximum",
    (LOCAL, 10): "Delimiter",
}
"""Item names by (type, tag) (HID 1.11 §6.2.2.4–6.2.2.8)."""

_SIZES = (0, 1, 2, 4)
SIGN = tuple((0, 0x100, 0x10000, 0x100000000)[prefix & 3] for prefix in range(256))
"""Per prefix byte, what ``value - ((value << 1) & SIGN[prefix])`` subtracts to read its data signed."""


class Item(NamedTuple):
    """One item: where it starts and ends, its prefix byte, type, tag, data size and unsigned value."""

    offset: int
    end: int
    prefix: int
    type: int
    tag: int
    size: int
    """Data bytes: 0, 1, 2 or 4 for a short item; bDataSize for a long one."""
    value: int
    """The data as an unsigned little-endian number (0 for a long item)."""
    long: bool = False

    @property
    def signed(self) -> int:
        """The data as a two's complement number of its size (the kernel's ``item_sdata``; 0 for a long item)."""
        return 0 if self.long else signed_value(self.prefix, self.value)

    @property
    def name(self) -> str:
        """The item's name ("Usage Page", "Input", ...; "Long item" or "Reserved" otherwise)."""
        if self.long:
            return "Long item"
        return ITEM_NAMES.get((self.type, self.tag)) or f"{TYPE_NAMES[self.type]} item tag {self.tag}"

    def data(self, descriptor: bytes) -> bytes:
        """The item's data bytes, cut from the descriptor it came from."""
        return bytes(descriptor[self.end - self.size:self.end])


def signed_value(prefix: int, value: int) -> int:
    """A short item's unsigned data as two's complement of the size its prefix gives (``item_sdata``)."""
    return value - ((value << 1) & SIGN[prefix])


def s32(value: int) -> int:
    """An int wrapped to the kernel's ``__s32`` (how it stores item data and how its wrapping multiplies end)."""
    value &= 0xFFFFFFFF
    return value - (1 << 32) if value & 0x80000000 else value


def exponent_value(prefix: int, value: int) -> int:
    """A Unit Exponent item's value: 0..15 is the spec's 4-bit two's complement nibble (0x0E is -2), anything
    else the signed value itself (0xFE is -2 too), as the kernel reads both."""
    raw = signed_value(prefix, value)
    return (raw - 16 if raw & 8 else raw) if 0 <= raw <= 15 else raw


def scan(data: bytes, *, source: str | None = None) -> list[tuple[int, int, int]]:
    """``(offset, prefix, value)`` per item, the parser's fast form: a short item's unsigned data, or a long
    item's data size; a ParseError names the offset of an item cut short by the end."""
    items: list[tuple[int, int, int]] = []
    append = items.append
    n = len(data)
    i = 0
    while i < n:
        b = data[i]
        code = b & 3
        if b >= 0xF0:  # tag nibble 15: a long item
            if n - i < 3:
                raise ParseError(f"long item 0x{b:02X} cut short: its header needs 3 bytes, {n - i} left",
                                 source=source, offset=i)
            size = data[i + 1]
            end = i + 3 + size
            if end > n:
                raise ParseError(f"long item cut short: {size} data bytes announced, {n - i - 3} left",
                                 source=source, offset=i)
            append((i, b, size))
        else:
            end = i + 1 + _SIZES[code]
            if end > n:
                name = ITEM_NAMES.get(((b >> 2) & 3, b >> 4), f"item 0x{b:02X}")
                raise ParseError(f"{name} cut short: {_SIZES[code]} data bytes needed, {n - i - 1} left",
                                 source=source, offset=i)
            if code == 1:
                append((i, b, data[i + 1]))
            elif code == 2:
                append((i, b, data[i + 1] | data[i + 2] << 8))
            elif code == 3:
                append((i, b, int.from_bytes(data[i + 1:end], "little")))
            else:
                append((i, b, 0))
        i = end
    return items


def tokenize(data: bytes, *, source: str | None = None) -> list[Item]:
    """The items of ``data`` in order, as :class:`Item` tuples (see :func:`scan` for the errors)."""
    items = []
    for offset, b, value in scan(data, source=source):
        if b >= 0xF0:
            items.append(Item(offset, offset + 3 + value, b, (b >> 2) & 3, data[offset + 2], value, 0, True))
        else:
            size = _SIZES[b & 3]
            items.append(Item(offset, offset + 1 + size, b, (b >> 2) & 3, b >> 4, size, value))
    return items

"""Items of a report descriptor: short items of 0/1/2/4 data bytes, long items, offsets, truncation errors."""

from __future__ import annotations

import pytest

from pixelpen.devices.hid.items import GLOBAL, LOCAL, MAIN, RESERVED, scan, signed_value, tokenize
from pixelpen.errors import ParseError


def test_short_items_of_every_size():
    data = bytes([
        0xA4,                          # Push: Global tag 10, no data
        0x05, 0x01,                    # Usage Page (1): Global tag 0, 1 byte
        0x26, 0xFF, 0x00,              # Logical Maximum (255): Global tag 2, 2 bytes
        0x0B, 0x78, 0x56, 0x34, 0x12,  # Usage 0x12345678: Local tag 0, size code 3 = 4 bytes
        0x81, 0x02,                    # Input (Data, Variable): Main tag 8
    ])
    items = tokenize(data)
    assert [(i.offset, i.end) for i in items] == [(0, 1), (1, 3), (3, 6), (6, 11), (11, 13)]
    assert [(i.type, i.tag, i.size, i.value) for i in items] == [
        (GLOBAL, 10, 0, 0), (GLOBAL, 0, 1, 1), (GLOBAL, 2, 2, 255), (LOCAL, 0, 4, 0x12345678), (MAIN, 8, 1, 2)]
    assert [i.name for i in items] == ["Push", "Usage Page", "Logical Maximum", "Usage", "Input"]
    assert items[3].data(data) == bytes([0x78, 0x56, 0x34, 0x12])
    assert not any(i.long for i in items)


@pytest.mark.parametrize("data, signed", [
    (bytes([0x15, 0x81]), -127),                    # one byte 0x81
    (bytes([0x15, 0x7F]), 127),
    (bytes([0x16, 0x00, 0x83]), -32000),            # 0x8300 as int16
    (bytes([0x17, 0xFF, 0xFF, 0xFF, 0xFF]), -1),    # 0xFFFFFFFF as int32
    (bytes([0x17, 0x00, 0x00, 0x00, 0x80]), -2**31),
    (bytes([0x14]), 0),                             # no data: 0, as the kernel's item_sdata
])
def test_signed_value_is_twos_complement_of_the_item_size(data, signed):
    assert tokenize(data)[0].signed == signed


def test_long_item_and_every_tag_15_prefix():
    data = bytes([0xFE, 0x02, 0x10, 0xAA, 0xBB, 0xF1, 0x00, 0x22, 0x05, 0x01])
    items = tokenize(data)
    assert [(i.offset, i.end, i.long) for i in items] == [(0, 5, True), (5, 8, True), (8, 10, False)]
    assert (items[0].tag, items[0].size, items[0].data(data)) == (0x10, 2, b"\xaa\xbb")
    assert items[1].tag == 0x22 and items[1].size == 0  # 0xF1: the kernel reads any tag nibble 15 as long
    assert items[0].name == "Long item"


def test_reserved_type_and_unknown_tags_are_named():
    items = tokenize(bytes([0x0C, 0xD5, 0x00, 0xE9, 0x01]))
    assert items[0].type == RESERVED and items[0].name == "Reserved item tag 0"
    assert items[1].name == "Global item tag 13"
    assert items[2].name == "Local item tag 14"


@pytest.mark.parametrize("data, offset", [
    (bytes([0x05]), 0),                              # Usage Page needs 1 data byte
    (bytes([0x05, 0x01, 0x26, 0xFF]), 2),            # Logical Maximum needs 2
    (bytes([0x05, 0x01, 0x27, 1, 2, 3]), 2),         # size code 3 needs 4
    (bytes([0xFE, 0x01]), 0),                        # long item header is 3 bytes
    (bytes([0x05, 0x01, 0xFE, 0x05, 0x00, 1, 2]), 2),  # 5 long data bytes announced, 2 left
])
def test_truncated_item_is_an_error_at_its_offset(data, offset):
    with pytest.raises(ParseError) as err:
        tokenize(data, source="dev.bin")
    assert err.value.offset == offset
    assert "dev.bin" in str(err.value) and f"byte offset {offset}" in str(err.value)


def test_empty_input_has_no_items():
    assert tokenize(b"") == []


def test_scan_gives_offset_prefix_and_value_or_long_size():
    data = bytes([0x05, 0x01, 0xFE, 0x02, 0x10, 0xAA, 0xBB, 0x27, 0x01, 0x02, 0x03, 0x04, 0xC0])
    assert scan(data) == [(0, 0x05, 1), (2, 0xFE, 2), (7, 0x27, 0x04030201), (12, 0xC0, 0)]


@pytest.mark.parametrize("prefix, value, signed", [
    (0x15, 0xFF, -1), (0x16, 0xFFFF, -1), (0x17, 0x7FFFFFFF, 2**31 - 1), (0x14, 0, 0), (0x16, 0x8000, -32768),
])
def test_signed_value(prefix, value, signed):
    assert signed_value(prefix, value) == signed

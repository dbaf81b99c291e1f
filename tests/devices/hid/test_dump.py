"""The descriptor dump: items with offsets, bytes, indentation and decoded values; reports; warnings."""

from __future__ import annotations

import json

from pixelpen.devices.hid import parse_descriptor
from pixelpen.devices.hid.dump import descriptor_dict, dump_descriptor, flag_text, item_rows, usages_text
from tests.devices.hid.test_descriptor import BOOT_KEYBOARD, BOOT_MOUSE, MS_WHEEL_MOUSE

BOOT_MOUSE_ITEMS = """\
     0  05 01           Usage Page (Generic Desktop)
     2  09 02           Usage (Mouse)
     4  A1 01           Collection (Application)
     6  09 01             Usage (Pointer)
     8  A1 00             Collection (Physical)
    10  05 09               Usage Page (Button)
    12  19 01               Usage Minimum (Button 1)
    14  29 03               Usage Maximum (Button 3)
    16  15 00               Logical Minimum (0)
    18  25 01               Logical Maximum (1)
    20  95 03               Report Count (3)
    22  75 01               Report Size (1)
    24  81 02               Input (Data,Var,Abs)
    26  95 01               Report Count (1)
    28  75 05               Report Size (5)
    30  81 01               Input (Const,Arr,Abs)
    32  05 01               Usage Page (Generic Desktop)
    34  09 30               Usage (X)
    36  09 31               Usage (Y)
    38  15 81               Logical Minimum (-127)
    40  25 7F               Logical Maximum (127)
    42  75 08               Report Size (8)
    44  95 02               Report Count (2)
    46  81 06               Input (Data,Var,Rel)
    48  C0                End Collection
    49  C0              End Collection
"""


def test_boot_mouse_dump_item_by_item():
    text = dump_descriptor(parse_descriptor(BOOT_MOUSE))
    lines = text.splitlines()
    assert lines[0] == "Report descriptor: 50 bytes, 26 items"
    assert "\n".join(lines[2:28]) + "\n" == BOOT_MOUSE_ITEMS


def test_boot_mouse_dump_reports():
    lines = dump_descriptor(parse_descriptor(BOOT_MOUSE)).splitlines()
    start = lines.index("Input report (unnumbered): 3 bytes")
    assert lines[start + 1:] == [
        "  bit    0   1 x 3    Button 1 .. Button 3  logical 0..1  (Data,Var,Abs)",
        "  bit    3   5 x 1    padding (Const,Arr,Abs)",
        "  bit    8   8 x 2    X, Y  logical -127..127  (Data,Var,Rel)",
    ]


def test_numbered_reports_units_and_arrays():
    text = dump_descriptor(parse_descriptor(MS_WHEEL_MOUSE))
    assert "Input report 2: 6 bytes (ID byte + 5)" in text
    assert "Feature report 3: 2 bytes (ID byte + 1)" in text
    assert "  bit   40   8 x 1    AC Pan  logical -127..127  (Data,Var,Rel)" in text
    assert "physical 1..4" in text
    keyboard = dump_descriptor(parse_descriptor(BOOT_KEYBOARD))
    assert "  bit   16   8 x 6    array of Reserved .. Application  logical 0..101  (Data,Arr,Abs)" in keyboard
    assert "Output report (unnumbered): 1 byte" in keyboard
    assert "Usage Minimum (LeftControl)" in keyboard and "Usage Maximum (Kana)" in keyboard


def test_values_are_decoded_with_the_parser_rules():
    data = bytes([0x05, 0x0D, 0x09, 0x02, 0xA1, 0x01,
                  0x15, 0x80, 0x25, 0xFF,        # maximum 0xFF after a negative minimum: -1
                  0x55, 0x0E, 0x65, 0x11,        # exponent nibble 0xE: -2; unit 0x11: cm
                  0xA4, 0x05, 0x01, 0xB4,        # Push, Usage Page (GD), Pop: back to Digitizers
                  0x09, 0x42, 0x0B, 0x38, 0x02, 0x0C, 0x00,   # Tip Switch, extended AC Pan
                  0x75, 0x08, 0x95, 0x02, 0xA9, 0x01, 0xA9, 0x00, 0x81, 0x62,
                  0xFE, 0x01, 0x10, 0xAA, 0xC0])
    d = parse_descriptor(data)
    texts = [r.text for r in item_rows(d)]
    assert texts[4:7] == ["Logical Maximum (-1)", "Unit Exponent (-2)", "Unit (cm, 0x11)"]
    assert texts[7:12] == ["Push", "Usage Page (Generic Desktop)", "Pop", "Usage (Tip Switch)", "Usage (AC Pan)"]
    assert texts[14:17] == ["Delimiter (Open)", "Delimiter (Close)",
                            "Input (Data,Var,Abs,No Preferred State,Null State)"]
    assert texts[17] == "Long item (tag 0x10, 1 data bytes)"
    assert item_rows(d)[17].depth == 1 and item_rows(d)[18].depth == 0
    text = dump_descriptor(d)
    assert "Warnings:\n  long item (tag 0x10, 1 data bytes) at offset 35 skipped" in text
    assert "unit cm·10^-2" in text


def test_flag_and_usage_helpers():
    assert flag_text(0x02) == "Data,Var,Abs"
    assert flag_text(0x1FF, 9) == "Const,Var,Rel,Wrap,Non Linear,No Preferred State,Null State,Volatile,Buffered Bytes"
    assert "Volatile" not in flag_text(0x80, 8)   # not defined for Input
    assert usages_text((0x00090001, 0x00090002)) == "Button 1, Button 2"
    assert usages_text(tuple(range(0x00090001, 0x00090011, 2))) .count(",") == 7
    assert usages_text(tuple(range(0x00090001, 0x00090031, 2))).endswith("... (16 more)")


def test_descriptor_dict_is_json():
    d = descriptor_dict(parse_descriptor(BOOT_MOUSE))
    again = json.loads(json.dumps(d))
    assert again["size"] == 50 and len(again["items"]) == 26
    assert again["items"][4] == {"offset": 8, "bytes": "a1 00", "depth": 1, "text": "Collection (Physical)"}
    (report,) = again["reports"]
    assert (report["kind"], report["report_id"], report["length"]) == ("input", None, 3)
    xy = report["fields"][2]
    assert (xy["bit_offset"], xy["bit_size"], xy["count"], xy["usages"]) == (8, 8, 2, [0x00010030, 0x00010031])
    assert xy["usage_names"] == ["X", "Y"] and xy["is_relative"] and not xy["is_array"]

"""Usage and usage-page names, checked against hid-tools' copy of the HID Usage Tables."""

from __future__ import annotations

import re

import pytest

from pixelpen.devices.hid.usages import PAGE_NAMES, USAGE_NAMES, page_name, usage_name

HUT_DIFFERENCES = {
    # hid-tools' tables hold older or shortened names; ours follow HUT 1.4.
    (0x01, 0x08): "Multi Axis", (0x01, 0x3C): "Motion", (0x01, 0x47): "Feature",
    (0x01, 0x87): "System Help Menu", (0x01, 0xB5): "System Display Toggle Internal External",
    (0x02, 0x0C): "Bicycle", (0x02, 0xBC): "Flight Communication",
    (0x07, 0x03): "ErrorUndefine", **{(0x07, 0x87 + i): f"Kanji{i + 1}" for i in range(9)},
    (0x08, 0x0F): "Surround field On",
    (0x08, 0x54): "Greed LEDChannel", (0x08, 0x55): "Blue LEDChannel",   # swapped (and misspelt) in hid-tools
    (0x0C, 0xE9): "Volume Up", (0x0C, 0xEA): "Volume Down",
    (0x0C, 0x181): "AL Launch Button Config Tool", (0x0C, 0x182): "AL Programmable Button Config",
    (0x0C, 0x183): "AL Consumer Control Config",
    (0x0D, 0x47): "Confidence", (0x0D, 0x51): "Contact Id", (0x0D, 0x52): "Inputmode", (0x0D, 0x53): "Device Index",
    (0x0D, 0x55): "Contact Max", (0x0D, 0x59): "Button Type", (0x0D, 0x5C): "Preferred Inking Color",
    (0x0D, 0x65): "UTF8 Character Gesture Encoding Sel",
    (0x0D, 0x66): "UTF16 Little Endian Character Gesture Encoding Sel",
    (0x0D, 0x67): "UTF16 Big Endian Character Gesture Encoding Sel",
    (0x0D, 0x6A): "Gesture Character Enable", (0x0D, 0x84): "Err Full Trans Features Unavail",
}
"""Where hid-tools' name differs from the HUT 1.4 name we use: hid-tools' spelling."""


def _norm(name: str) -> str:
    return re.sub(r"[^a-z0-9]", "", name.lower().replace("keyboard", "").replace("keypad", ""))


@pytest.mark.parametrize("page", sorted(USAGE_NAMES))
def test_names_agree_with_hid_tools_usage_tables(page):
    hut = pytest.importorskip("hidtools.hut").HUT
    theirs = hut[page]
    compared = 0
    for uid, name in USAGE_NAMES[page].items():
        if uid not in theirs:
            continue
        compared += 1
        expected = HUT_DIFFERENCES.get((page, uid), name)
        assert _norm(theirs[uid].name) == _norm(expected), (hex(page), hex(uid), name, theirs[uid].name)
    assert compared >= 0.75 * len(USAGE_NAMES[page])  # hid-tools lacks some keypad and LED usages


def test_page_names_agree_with_hid_tools():
    hut = pytest.importorskip("hidtools.hut").HUT
    for page in (0x01, 0x02, 0x09, 0x0D, 0x84, 0x85):
        assert _norm(hut[page].page_name) in (_norm(PAGE_NAMES[page]), _norm(PAGE_NAMES[page]) + "device")


@pytest.mark.parametrize("usage, name", [
    (0x00010030, "X"), (0x00010039, "Hat Switch"), (0x00010048, "Resolution Multiplier"),
    (0x000200BB, "Throttle"), (0x00070004, "a and A"), (0x0007001E, "1 and !"), (0x00070027, "0 and )"),
    (0x0007003A, "F1"), (0x00070073, "F24"), (0x000700E7, "Right GUI"), (0x00080002, "Caps Lock"),
    (0x00090001, "Button 1"), (0x00090100, "Button 256"), (0x00090000, "No Button Pressed"),
    (0x000A0003, "Instance 3"), (0x000C0238, "AC Pan"), (0x000C00CD, "Play/Pause"),
    (0x000D0042, "Tip Switch"), (0x000D0030, "Tip Pressure"), (0x000D005B, "Transducer Serial Number"),
    (0x000100FF, "Generic Desktop 0x00FF"), (0xFF000001, "Vendor-defined 0xFF00 0x0001"),
    (0x00130001, "Reserved 0x0013 0x0001"), (0x00840001, "Power 0x0001"),
])
def test_usage_name(usage, name):
    assert usage_name(usage) == name


def test_page_name():
    assert page_name(0x0D) == "Digitizers" and page_name(0xFFFF) == "Vendor-defined 0xFFFF"
    assert page_name(0x1234) == "Reserved 0x1234" and page_name(0x10001) == "Generic Desktop"  # 16 bits count

"""Quirks: per-VID/PID fixes of broken report descriptors, as the kernel's report_fixup hooks apply them."""

from __future__ import annotations

import pytest

from pixelpen.devices.hid import parse_descriptor
from pixelpen.devices.hid.quirks import QUIRKS, Quirk, fixup, register_quirk
from pixelpen.errors import ConfigError, ParseError


def holtek_a04a_descriptor() -> bytes:
    """113 bytes with Usage Maximum 0x7FFF at 106..107 and Logical Maximum 0x7FFF at 111..112, the broken
    consumer array of the Holtek a04a/a081 mice (hid-holtek-mouse.c checks exactly these offsets)."""
    head = [0x05, 0x01, 0x09, 0x02, 0xA1, 0x01, 0x05, 0x0C,  # GD Mouse application, Usage Page (Consumer)
            0x16, 0x00, 0x00, 0x75, 0x10, 0x95, 0x01]         # Logical Minimum (0, 2 bytes), Size 16, Count 1
    filler = [0x75, 0x10] * 44                                 # Report Size (16) again, up to offset 103
    consumer = [0x19, 0x00,                                    # 103: Usage Minimum (0)
                0x2A, 0xFF, 0x7F,                              # 105: Usage Maximum (0x7FFF)
                0x15, 0x00,                                    # 108: Logical Minimum (0)
                0x26, 0xFF, 0x7F]                              # 110: Logical Maximum (0x7FFF)
    tail = [0x81, 0x00, 0xC0]                                  # Input (Data, Array), End Collection
    data = bytes(head + filler + consumer + tail)
    assert data[106:108] == b"\xff\x7f" and data[111:113] == b"\xff\x7f"
    return data


def test_holtek_fix_patches_the_two_maxima_to_0x2fff():
    data = holtek_a04a_descriptor()
    fixed, notes = fixup(data, 0x04D9, 0xA04A)
    assert fixed[107] == 0x2F and fixed[112] == 0x2F and len(fixed) == len(data)
    assert fixed[:107] == data[:107] and fixed[108:112] == data[108:112] and fixed[113:] == data[113:]
    assert len(notes) == 1 and "hid-holtek-mouse.c" in notes[0] and "04d9:a04a" in notes[0]
    for product in (0xA070, 0xA081):  # the other ids of the same case in Linux 6.6's holtek_mouse_report_fixup
        assert fixup(data, 0x04D9, product)[0] == fixed


def test_holtek_fix_needs_the_ids_and_the_original_bytes():
    data = holtek_a04a_descriptor()
    assert fixup(data, 0x04D9, 0x1234) == (data, [])                 # another product
    assert fixup(data, 0x046D, 0xA04A) == (data, [])                 # another vendor
    changed = data[:106] + b"\x00" + data[107:]
    assert fixup(changed, 0x04D9, 0xA04A) == (changed, [])           # not the broken bytes
    assert fixup(data[:110], 0x04D9, 0xA04A) == (data[:110], [])     # too short for the offsets


def test_parse_descriptor_applies_quirks_only_with_both_ids():
    data = holtek_a04a_descriptor()
    plain = parse_descriptor(data)
    (arr,) = [f for f in plain.input_reports[None] if f.is_array]
    assert any("Usage Maximum" in w for w in plain.warnings)        # without the fix: cut at 12288 usages
    fixed = parse_descriptor(data, vendor_id=0x04D9, product_id=0xA04A)
    (arr,) = [f for f in fixed.input_reports[None] if f.is_array]
    assert arr.logical_max == 0x2FFF and len(arr.usages) == 0x3000
    assert any("quirk" in w for w in fixed.warnings)


def test_keytouch_descriptor_is_replaced_by_a_boot_keyboard():
    fixed, notes = fixup(b"\x05\x01", 0x0926, 0x3333)
    d = parse_descriptor(b"\x05\x01", vendor_id=0x0926, product_id=0x3333)
    assert d.data == fixed and len(fixed) == 65 and notes
    assert d.applications == (0x00010006,)
    keys = d.input_reports[None][-1]
    assert keys.is_array and (keys.logical_min, keys.logical_max, keys.bit_offset, keys.count) == (0, 255, 16, 6)


def test_glorious_model_o_consts_become_data():
    data = bytearray(213)
    for o in (84, 112, 140):
        data[o], data[o + 1] = 0x81, 0x03
    fixed, notes = fixup(bytes(data), 0x258A, 0x0036)
    assert [fixed[o] for o in (85, 113, 141)] == [0x06] * 3 and notes
    assert fixup(bytes(data[:212]), 0x258A, 0x0036)[1] == []        # the kernel wants exactly 213 bytes


def test_registered_quirk_runs_after_the_built_in_ones(monkeypatch):
    monkeypatch.setattr("pixelpen.devices.hid.quirks.QUIRKS", list(QUIRKS))
    register_quirk(Quirk("test", 0x1234, (0x5678,), "a test", expect=((1, 0x01),), patch=((1, 0x09),)))
    d = parse_descriptor(bytes([0x05, 0x01, 0x09, 0x02, 0xA1, 0x01, 0xC0]), vendor_id=0x1234, product_id=0x5678)
    assert d.data[1] == 0x09 and "quirk test" in d.warnings[0]


def test_quirk_must_patch_or_replace_not_both():
    with pytest.raises(ConfigError):
        Quirk("empty", 1, (2,), "x")
    with pytest.raises(ConfigError):
        Quirk("both", 1, (2,), "x", patch=((0, 0),), replacement=b"\x00")


def test_oversized_descriptor_is_refused_before_any_quirk():
    with pytest.raises(ParseError) as err:
        parse_descriptor(bytes(5000), vendor_id=0x0926, product_id=0x3333)
    assert err.value.offset == 4096

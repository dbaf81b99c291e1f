"""Keyboard semantics: the HID 1.11 E.6 boot keyboard and an NKRO keyboard written byte by byte, reports by hand."""

from __future__ import annotations

import warnings

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.devices.hid.codec import ShortReportWarning
from pixelpen.devices.hid.descriptor import parse_descriptor
from pixelpen.devices.hid.events import DeviceId, Key
from pixelpen.devices.hid.fields import ReportKind
from pixelpen.devices.hid.keyboard import Keyboard
from pixelpen.devices.hid.keymaps import LAYOUTS
from pixelpen.devices.hid.semantics import CompositeSemantics, semantics_for
from pixelpen.errors import ConfigError, InvalidArgument, ParseError

DEVICE = DeviceId("usb", 0x046D, 0xC31C, name="test keyboard")

# HID 1.11 Appendix E.6, "Example keyboard", item by item (63 bytes).
BOOT = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x06,        # Usage (Keyboard)
    0xA1, 0x01,        # Collection (Application)
    0x05, 0x07,        #   Usage Page (Key Codes)
    0x19, 0xE0,        #   Usage Minimum (224)
    0x29, 0xE7,        #   Usage Maximum (231)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x01,        #   Logical Maximum (1)
    0x75, 0x01,        #   Report Size (1)
    0x95, 0x08,        #   Report Count (8)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): modifier byte
    0x95, 0x01,        #   Report Count (1)
    0x75, 0x08,        #   Report Size (8)
    0x81, 0x01,        #   Input (Constant): reserved byte
    0x95, 0x05,        #   Report Count (5)
    0x75, 0x01,        #   Report Size (1)
    0x05, 0x08,        #   Usage Page (LEDs)
    0x19, 0x01,        #   Usage Minimum (1)
    0x29, 0x05,        #   Usage Maximum (5)
    0x91, 0x02,        #   Output (Data, Variable, Absolute): LED report
    0x95, 0x01,        #   Report Count (1)
    0x75, 0x03,        #   Report Size (3)
    0x91, 0x01,        #   Output (Constant): LED report padding
    0x95, 0x06,        #   Report Count (6)
    0x75, 0x08,        #   Report Size (8)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x65,        #   Logical Maximum (101)
    0x05, 0x07,        #   Usage Page (Key Codes)
    0x19, 0x00,        #   Usage Minimum (0)
    0x29, 0x65,        #   Usage Maximum (101)
    0x81, 0x00,        #   Input (Data, Array): key arrays (6 bytes)
    0xC0,              # End Collection
])

# An N-key-rollover keyboard: report 1 = modifiers + a bitmap of usages 0x00..0x67 (13 bytes); three LEDs only;
# and a Consumer Control application in report 2 (no semantics: its reports give nothing).
NKRO = bytes([
    0x05, 0x01, 0x09, 0x06, 0xA1, 0x01,  # Usage Page (Generic Desktop), Usage (Keyboard), Collection (Application)
    0x85, 0x01,                          #   Report ID (1)
    0x05, 0x07, 0x19, 0xE0, 0x29, 0xE7,  #   Usage Page (Keyboard), Usage Minimum (0xE0), Usage Maximum (0xE7)
    0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02,  # 8 modifier bits: byte 1
    0x19, 0x00, 0x29, 0x67, 0x95, 0x68, 0x81, 0x02,  # Usage 0x00..0x67, Report Count (104): bytes 2-14, one bit each
    0x05, 0x08, 0x19, 0x01, 0x29, 0x03, 0x95, 0x03, 0x91, 0x02,  # LEDs Num, Caps, Scroll: output byte 1 bits 0-2
    0x95, 0x05, 0x91, 0x03,              #   Output (Constant): 5 bits of padding
    0xC0,
    0x05, 0x0C, 0x09, 0x01, 0xA1, 0x01,  # Usage Page (Consumer), Usage (Consumer Control), Collection (Application)
    0x85, 0x02,                          #   Report ID (2)
    0x19, 0x00, 0x2A, 0x3C, 0x02, 0x15, 0x00, 0x26, 0x3C, 0x02, 0x75, 0x10, 0x95, 0x01, 0x81, 0x00,  # 16-bit array
    0xC0,
])

SHIFT, CTRL, RIGHT_ALT = 0x02, 0x01, 0x40
A, B, C, Q, CAPS, NUM, KP1 = 0x04, 0x05, 0x06, 0x14, 0x39, 0x53, 0x59


def boot(modifiers: int = 0, *keys: int) -> bytes:
    return bytes([modifiers, 0, *keys, *[0] * (6 - len(keys))])


def nkro(modifiers: int = 0, *keys: int) -> bytes:
    bitmap = bytearray(13)
    for k in keys:
        bitmap[k // 8] |= 1 << (k % 8)
    return bytes([1, modifiers]) + bytes(bitmap)


def summary(events: list) -> list[tuple[str, bool, str]]:
    return [(e.key, e.pressed, e.char) for e in events]


@pytest.fixture
def keyboard() -> Keyboard:
    return Keyboard(parse_descriptor(BOOT), DEVICE)


def test_semantics_for_picks_the_keyboard_and_its_leds(keyboard):
    assert isinstance(semantics_for(parse_descriptor(BOOT), DEVICE), Keyboard)
    assert "6-key array" in keyboard.describe() and "LEDs" in keyboard.describe()
    [leds] = keyboard.output_reports()
    assert (leds.kind, leds.report_id, leds.data) == (ReportKind.OUTPUT, None, b"\x00")


def test_shifted_letters_releases_and_modifier_order(keyboard):
    events = keyboard.feed(boot(SHIFT, A), 0.25)
    assert summary(events) == [("left_shift", True, ""), ("a", True, "A")]
    assert all(isinstance(e, Key) and e.time == 0.25 and e.device == DEVICE for e in events)
    assert events[1].usage == A and events[1].modifiers == frozenset({"shift"})
    assert summary(keyboard.feed(boot(SHIFT, A, B), 0.3)) == [("b", True, "B")]
    assert summary(keyboard.feed(boot(0, B), 0.35)) == [("left_shift", False, ""), ("a", False, "")]
    assert keyboard.pressed == ("b",)
    assert summary(keyboard.feed(boot(), 0.4)) == [("b", False, "")]
    assert keyboard.feed(boot(), 0.5) == []


def test_error_roll_over_keeps_the_keys_as_the_kernel_does(keyboard):
    keyboard.feed(boot(0, A, B), 0.0)
    # too many keys: every slot says ErrorRollOver (0x01); the modifier byte still counts
    assert summary(keyboard.feed(boot(SHIFT, 1, 1, 1, 1, 1, 1), 0.1)) == [("left_shift", True, "")]
    assert keyboard.pressed == ("left_shift", "a", "b")
    assert summary(keyboard.feed(boot(0, B), 0.2)) == [("left_shift", False, ""), ("a", False, "")]


def test_caps_lock_toggles_and_changes_letters(keyboard):
    events = keyboard.feed(boot(0, CAPS), 0.0)
    assert summary(events) == [("caps_lock", True, "")]
    assert keyboard.locks["caps_lock"] and keyboard.leds_changed
    assert "caps_lock" in events[0].modifiers
    keyboard.feed(boot(), 0.1)
    assert summary(keyboard.feed(boot(0, A), 0.2)) == [("a", True, "A")]
    assert summary(keyboard.feed(boot(SHIFT, A), 0.3))[0] == ("left_shift", True, "")
    keyboard.feed(boot(), 0.4)
    assert summary(keyboard.feed(boot(SHIFT, A), 0.5)) == [("left_shift", True, ""), ("a", True, "a")]
    assert summary(keyboard.feed(boot(SHIFT, 0x1E), 0.6))[-1] == ("1", True, "!")  # digits: Shift only
    assert keyboard.led_report().data == b"\x02" and not keyboard.leds_changed
    keyboard.feed(boot(0, CAPS), 0.7)
    assert not keyboard.locks["caps_lock"]


def test_num_lock_decides_the_keypad(keyboard):
    assert summary(keyboard.feed(boot(0, KP1), 0.0)) == [("kp_1", True, "")]
    keyboard.feed(boot(0, NUM), 0.1)
    assert summary(keyboard.feed(boot(0, KP1), 0.2)) == [("num_lock", False, ""), ("kp_1", True, "1")]
    assert keyboard.led_report().data == b"\x01"
    on = Keyboard(parse_descriptor(BOOT), DEVICE, num_lock=True)
    assert on.output_reports()[0].data == b"\x01"
    assert summary(on.feed(boot(0, 0x58), 0.0)) == [("kp_enter", True, "\r")]


def test_led_reports_encoded_by_the_descriptor(keyboard):
    # bit 0 Num Lock, 1 Caps Lock, 2 Scroll Lock, 3 Compose, 4 Kana, bits 5-7 padding
    assert keyboard.led_report(num_lock=True, scroll_lock=True, compose=True, kana=True).data == bytes([0b11101])
    assert keyboard.led_report(caps_lock=True).data == bytes([0b00010])
    nkro_keyboard = Keyboard(parse_descriptor(NKRO), DEVICE)
    report = nkro_keyboard.led_report(num_lock=True, scroll_lock=True, compose=True, kana=True)
    assert (report.report_id, report.data) == (1, bytes([1, 0b101]))  # no Compose or Kana LED: left out
    no_leds = BOOT[:32] + BOOT[46:]  # E.6 without bytes 32-45: the LED usages and the two Output items
    plain = Keyboard(parse_descriptor(no_leds), DEVICE)
    assert plain.output_reports() == [] and "no LEDs" in plain.describe()
    with pytest.raises(InvalidArgument, match="no LED output report"):
        plain.led_report()


def test_shortcuts_type_no_characters(keyboard):
    [_, c] = keyboard.feed(boot(CTRL, C), 0.0)
    assert (c.key, c.char, c.modifiers) == ("c", "", frozenset({"ctrl"}))
    keyboard.feed(boot(), 0.1)
    [_, q] = keyboard.feed(boot(RIGHT_ALT, Q), 0.2)  # Right Alt is plain Alt on the US layout
    assert (q.char, q.modifiers) == ("", frozenset({"alt"}))


def test_layouts_and_altgr(keyboard):
    keyboard.set_layout("de")
    [_, at] = keyboard.feed(boot(RIGHT_ALT, Q), 0.0)
    assert (at.key, at.char, at.modifiers) == ("q", "@", frozenset({"altgr"}))
    keyboard.feed(boot(), 0.1)
    assert summary(keyboard.feed(boot(0, 0x1C), 0.2)) == [("y", True, "z")]  # QWERTZ: the Y key types z
    keyboard.set_layout("FR")
    keyboard.feed(boot(), 0.3)
    assert summary(keyboard.feed(boot(0, Q), 0.4)) == [("q", True, "a")]  # AZERTY
    with pytest.raises(ConfigError, match="known: us, uk, de, fr"):
        keyboard.set_layout("dvorak")
    with pytest.raises(ConfigError, match="layout"):
        Keyboard(parse_descriptor(BOOT), DEVICE, layout="xx")


def test_dead_keys_compose_with_the_next_character():
    keyboard = Keyboard(parse_descriptor(BOOT), DEVICE, layout="de", dead_keys=True)

    def typed(*strokes: tuple[int, int]) -> str:
        text = ""
        for modifiers, usage in strokes:
            text += "".join(e.char for e in keyboard.feed(boot(modifiers, usage), 0.0))
            keyboard.feed(boot(), 0.0)
        return text

    assert typed((0, 0x35), (0, A)) == "â"  # ^ then a
    assert typed((0, 0x35), (SHIFT, A)) == "Â"  # the Shift press between does not use the dead key up
    assert typed((SHIFT, 0x2E), (0, 0x08)) == "è"  # Shift+´ is the dead grave
    assert typed((0, 0x2E), (0, 0x2C)) == "´"  # then Space: the accent itself
    assert typed((0, 0x35), (0, 0x1B)) == "^x"  # no x with a circumflex: both
    assert typed((0, 0x24)) == "7"
    keyboard.set_layout("fr")
    assert typed((0, 0x2F), (0, 0x08)) == "ê" and typed((SHIFT, 0x2F), (0, 0x0C)) == "ï"
    assert typed((RIGHT_ALT, 0x1F), (0, 0x11)) == "ñ"  # AltGr+é is the dead tilde
    assert typed((RIGHT_ALT, 0x26), (0, 0x08)) == "^e"  # AltGr+ç is a plain ^
    plain = Keyboard(parse_descriptor(BOOT), DEVICE, layout="de")
    assert plain.feed(boot(0, 0x35), 0.0)[0].char == "^"  # without dead_keys: the spacing character at once


def test_nkro_bitmaps_report_any_number_of_keys():
    keyboard = Keyboard(parse_descriptor(NKRO), DEVICE)
    assert "100-key bitmap" in keyboard.describe()  # usages 0x04..0x67
    keys = [0x04, 0x05, 0x06, 0x07, 0x08, 0x09, 0x0A, 0x0B, 0x2C]  # a..h and space: nine at once
    events = keyboard.feed(nkro(SHIFT, *keys), 0.0)
    assert summary(events) == [("left_shift", True, "")] + [(n, True, n.upper()) for n in "abcdefgh"] + [
        ("space", True, " ")]
    assert summary(keyboard.feed(nkro(0, 0x2C), 0.1))[1:] == [(n, False, "") for n in "abcdefgh"]
    assert keyboard.feed(nkro(0, 0x00, 0x01, 0x2C), 0.2) == []  # usages 0..3 are never keys


def test_composite_routes_the_consumer_reports_nowhere():
    sem = semantics_for(parse_descriptor(NKRO), DEVICE)
    assert isinstance(sem, CompositeSemantics) and sem.unsupported == (0x000C0001,)
    assert sem.feed(b"\x02\xe9\x00", 0.0) == []  # Volume Increment, no semantics for Consumer Control
    assert summary(sem.feed(nkro(0, A), 0.1)) == [("a", True, "a")]
    assert [r.data for r in sem.output_reports()] == [bytes([1, 0])]


def test_boot_protocol_reads_the_fixed_report_whatever_the_descriptor():
    keyboard = Keyboard(parse_descriptor(NKRO), DEVICE, protocol="boot")
    assert "boot protocol" in keyboard.describe()
    assert summary(keyboard.feed(boot(SHIFT, A, 0xE1), 0.0)) == [("left_shift", True, ""), ("a", True, "A")]
    assert keyboard.feed(boot(SHIFT, 1, 1, 1, 1, 1, 1), 0.1) == []
    assert keyboard.led_report(caps_lock=True).data == b"\x02" and keyboard.led_report().report_id is None


def test_bad_reports_give_clear_errors(keyboard):
    nkro_keyboard = Keyboard(parse_descriptor(NKRO), DEVICE)
    with pytest.raises(ParseError, match="report 9"):
        nkro_keyboard.feed(b"\x09" + bytes(14), 0.0)
    with pytest.raises(ParseError, match="empty"):
        keyboard.feed(b"", 0.0)
    with pytest.warns(ShortReportWarning):
        assert summary(keyboard.feed(bytes([SHIFT, 0, A]), 0.0)) == [("left_shift", True, ""), ("a", True, "A")]
    not_a_keyboard = bytes([0x05, 0x01, 0x09, 0x06, 0xA1, 0x01, 0x05, 0x09, 0x09, 0x01, 0x15, 0x00, 0x25, 0x01,
                            0x75, 0x08, 0x95, 0x01, 0x81, 0x02, 0xC0])
    with pytest.raises(ConfigError, match="no input report has Keyboard-page usages"):
        Keyboard(parse_descriptor(not_a_keyboard), DEVICE)


@pytest.mark.parametrize("name", sorted(LAYOUTS))
def test_every_character_typed_by_the_reverse_mapping_comes_back(name):
    strokes = LAYOUTS[name].strokes()
    boot_keyboard = Keyboard(parse_descriptor(BOOT), DEVICE, layout=name, num_lock=True)
    nkro_keyboard = Keyboard(parse_descriptor(NKRO), DEVICE, layout=name, num_lock=True)
    for char, (usage, shift, altgr) in strokes.items():
        modifiers = SHIFT * shift | RIGHT_ALT * altgr
        if usage <= 0x65:  # the E.6 array's range
            events, _ = boot_keyboard.feed(boot(modifiers, usage), 0.0), boot_keyboard.feed(boot(), 0.0)
        else:  # the keypad's "=" (0x67: German "=" is Shift+0 on the main row) is past it: the NKRO bitmap
            events, _ = nkro_keyboard.feed(nkro(modifiers, usage), 0.0), nkro_keyboard.feed(nkro(), 0.0)
        assert (events[-1].usage, events[-1].char) == (usage, char)


def test_every_printable_us_character_is_typed_back():
    strokes = LAYOUTS["us"].strokes()
    keyboard = Keyboard(parse_descriptor(BOOT), DEVICE)
    typed = []
    for char in map(chr, range(0x20, 0x7F)):
        usage, shift, _ = strokes[char]
        typed.append(keyboard.feed(boot(SHIFT * shift, usage), 0.0)[-1].char)
        keyboard.feed(boot(), 0.0)
    assert "".join(typed) == "".join(map(chr, range(0x20, 0x7F)))


@given(st.lists(st.binary(min_size=1, max_size=10), max_size=20))
def test_any_reports_give_key_events(reports):
    keyboard = Keyboard(parse_descriptor(BOOT), DEVICE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ShortReportWarning)
        for data in reports:
            events = keyboard.feed(data, 0.0)
            assert all(isinstance(e, Key) and len(e.char) <= 1 for e in events)
            assert len(keyboard.pressed) <= 8 + 6

"""Key names after the HID Usage Tables' Keyboard page, and the layouts' characters checked key by key by hand."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.devices.hid.keymaps import DEAD_MARKS, KEY_NAMES, LAYOUTS, NUMLOCK_KEYS, compose, key_name, layout
from pixelpen.errors import ConfigError


@pytest.mark.parametrize(("usage", "name"), [
    (0x04, "a"), (0x1D, "z"), (0x1E, "1"), (0x27, "0"), (0x28, "enter"), (0x2A, "backspace"), (0x2C, "space"),
    (0x31, "backslash"), (0x32, "non_us_hash"), (0x35, "grave"), (0x39, "caps_lock"), (0x3A, "f1"), (0x45, "f12"),
    (0x4C, "delete"), (0x4F, "right"), (0x52, "up"), (0x53, "num_lock"), (0x58, "kp_enter"), (0x59, "kp_1"),
    (0x62, "kp_0"), (0x63, "kp_period"), (0x64, "non_us_backslash"), (0x65, "application"), (0x67, "kp_equal"),
    (0x68, "f13"), (0x73, "f24"), (0x7F, "mute"), (0x82, "locking_caps_lock"), (0x87, "international1"),
    (0x8F, "international9"), (0x90, "lang1"), (0x98, "lang9"), (0x9A, "sysreq"), (0xA4, "exsel"), (0xB0, "kp_00"),
    (0xC1, "kp_f"), (0xDD, "kp_hexadecimal"), (0xE0, "left_ctrl"), (0xE2, "left_alt"), (0xE7, "right_gui"),
])
def test_key_names_from_the_usage_tables(usage, name):
    assert key_name(usage) == name


def test_reserved_usages_and_the_count_of_names():
    # HUT 1.4 §10 defines 0x00..0xA4, 0xB0..0xDD and 0xE0..0xE7: 165 + 46 + 8 names
    assert len(KEY_NAMES) == 165 + 46 + 8 and len(set(KEY_NAMES.values())) == len(KEY_NAMES)
    assert key_name(0xA5) == "key_0xa5" and key_name(0xDE) == "key_0xde" and key_name(0x1234) == "key_0x1234"


def test_every_usage_hid_tools_knows_has_a_name():
    hut = pytest.importorskip("hidtools.hut", reason="hid-tools (the bench extra) is the oracle here").HUT
    assert {u for u in hut[0x07] if u} <= {u for u in KEY_NAMES if not KEY_NAMES[u].startswith("key_0x")}


@pytest.mark.parametrize(("name", "usage", "state", "char"), [
    ("us", 0x1F, "shift", "@"), ("us", 0x35, "", "`"), ("us", 0x35, "shift", "~"), ("us", 0x34, "shift", '"'),
    ("us", 0x32, "", "\\"), ("us", 0x14, "altgr", ""),
    ("uk", 0x1F, "shift", '"'), ("uk", 0x20, "shift", "£"), ("uk", 0x34, "shift", "@"), ("uk", 0x32, "", "#"),
    ("uk", 0x32, "shift", "~"), ("uk", 0x21, "altgr", "€"), ("uk", 0x35, "shift", "¬"), ("uk", 0x08, "altgr", "é"),
    ("de", 0x1C, "", "z"), ("de", 0x1D, "", "y"), ("de", 0x20, "shift", "§"), ("de", 0x24, "shift", "/"),
    ("de", 0x24, "altgr", "{"), ("de", 0x14, "altgr", "@"), ("de", 0x08, "altgr", "€"), ("de", 0x64, "altgr", "|"),
    ("de", 0x2D, "", "ß"), ("de", 0x2D, "altgr", "\\"), ("de", 0x33, "", "ö"), ("de", 0x2F, "caps", "Ü"),
    ("de", 0x2D, "caps", "ß"), ("de", 0x30, "altgr", "~"), ("de", 0x63, "", ","), ("de", 0x35, "", "^"),
    ("fr", 0x14, "", "a"), ("fr", 0x04, "", "q"), ("fr", 0x1A, "", "z"), ("fr", 0x1D, "", "w"), ("fr", 0x33, "", "m"),
    ("fr", 0x10, "", ","), ("fr", 0x1F, "", "é"), ("fr", 0x1F, "shift", "2"), ("fr", 0x1F, "caps", "2"),
    ("fr", 0x1F, "caps shift", "é"), ("fr", 0x27, "altgr", "@"), ("fr", 0x22, "altgr", "["), ("fr", 0x35, "caps", "²"),
    ("fr", 0x34, "", "ù"), ("fr", 0x38, "shift", "§"), ("fr", 0x30, "altgr", "¤"), ("fr", 0x63, "", "."),
])
def test_characters_by_layout_from_the_windows_tables(name, usage, state, char):
    words = state.split()
    got = LAYOUTS[name].char(usage, shift="shift" in words, altgr="altgr" in words, caps_lock="caps" in words,
                             num_lock=True)
    assert got == char


def test_control_characters_and_the_keypad():
    for lay in LAYOUTS.values():
        assert [lay.char(u) for u in (0x28, 0x29, 0x2A, 0x2B, 0x2C, 0x4C, 0x58)] == [
            "\r", "\x1b", "\b", "\t", " ", "\x7f", "\r"]
        assert all(lay.char(u) == "" for u in NUMLOCK_KEYS)
        assert lay.char(0x59, num_lock=True) == "1" and lay.char(0x54) == "/"
        assert lay.char(0x3A) == "" and lay.char(0xE1) == ""  # F1 and Shift type nothing


def test_layout_lookup():
    assert layout(" DE ") is LAYOUTS["de"]
    with pytest.raises(ConfigError, match="known: us, uk, de, fr"):
        layout("colemak")


@given(st.sampled_from(sorted(LAYOUTS)), st.data())
def test_strokes_reverse_the_layouts(name, data):
    lay = LAYOUTS[name]
    strokes = lay.strokes()
    char = data.draw(st.sampled_from(sorted(strokes)))
    usage, shift, altgr = strokes[char]
    assert lay.char(usage, shift=shift, altgr=altgr, num_lock=True) == char
    assert not (altgr and not lay.altgr)


def test_us_strokes_cover_printable_ascii_without_altgr():
    strokes = LAYOUTS["us"].strokes()
    assert all(chr(c) in strokes and not strokes[chr(c)][2] for c in range(0x20, 0x7F))
    assert strokes["a"] == (0x04, False, False) and strokes["A"] == (0x04, True, False)
    assert strokes["1"] == (0x1E, False, False)  # the main row before the keypad's 0x59


@pytest.mark.parametrize(("dead", "char", "typed"), [
    ("^", "a", "â"), ("^", "E", "Ê"), ("´", "e", "é"), ("`", "e", "è"), ("`", "A", "À"), ("¨", "u", "ü"),
    ("¨", "y", "ÿ"), ("~", "n", "ñ"), ("~", "O", "Õ"), ("^", " ", "^"), ("´", " ", "´"), ("^", "x", "^x"),
    ("^", "^", "^^"), ("¨", "1", "¨1"),
])
def test_dead_keys_compose_by_hand(dead, char, typed):
    assert compose(dead, char) == typed


def test_dead_keys_are_the_windows_ones():
    def spelled(name):
        lay = LAYOUTS[name]
        return sorted(lay.keys[usage][level] for usage, level in lay.dead)

    assert spelled("de") == ["^", "`", "´"] and spelled("fr") == ["^", "`", "~", "¨"]
    assert not LAYOUTS["us"].dead and not LAYOUTS["uk"].dead
    assert all(LAYOUTS[n].keys[u][lv] in DEAD_MARKS for n in LAYOUTS for u, lv in LAYOUTS[n].dead)
    # a level as the characters are chosen: AltGr over Shift, Caps Lock as Shift where it applies
    fr = LAYOUTS["fr"]
    assert fr.level(0x2F) == 0 and fr.level(0x2F, caps_lock=True) == 1 and fr.level(0x2F, shift=True, altgr=True) == 2

"""Keyboard-page usages as key names, and keyboard layouts as data: usage -> (plain, shift, AltGr) characters.

:data:`KEY_NAMES` names every usage of the HID Usage Tables' Keyboard/Keypad page (0x07) in lower
case with underscores after the table's own names (``0x04`` "a", ``0x28`` "enter", ``0x32``
"non_us_hash", ``0x64`` "non_us_backslash", ``0xE0`` "left_ctrl"); :func:`key_name` gives
``key_0xNN`` for the reserved ones.

:data:`LAYOUTS` holds ``us``, ``uk``, ``de`` (German QWERTZ) and ``fr`` (French AZERTY) as
Windows's layout tables (KBDUS, KBDUK, KBDGR, KBDFR) give their characters for each key: plain,
with Shift, with AltGr (Right Alt; Ctrl+Alt on Windows), "" where the key types nothing at that
level.  Caps Lock acts as Shift on the keys the table marks for it (its CAP column): the letters on
every layout, and on the French layout the digit row and most punctuation too (Caps Lock + "é"
types "2").  Dead keys (German "^", "´", "`"; French "^", "¨", AltGr "~" and "`"; :attr:`Layout.dead`)
type their spacing character; :func:`compose` gives what a dead key then a character type (the
keyboard semantics do so with ``dead_keys=true``).  The keypad's digits and decimal key type only
with Num Lock on; Enter, Tab, Backspace, Escape and Delete type "\\r", "\\t", "\\b", "\\x1b" and
"\\x7f" on every layout.
"""

from __future__ import annotations

import unicodedata
from collections.abc import Mapping
from dataclasses import dataclass, field

from pixelpen.errors import ConfigError

__all__ = ["DEAD_MARKS", "KEY_NAMES", "LAYOUTS", "MODIFIER_NAMES", "NUMLOCK_KEYS", "Layout", "compose", "key_name",
           "layout"]


def _names() -> dict[int, str]:
    names: dict[int, str] = {0x00: "reserved", 0x01: "error_roll_over", 0x02: "post_fail", 0x03: "error_undefined"}
    names.update({0x04 + i: chr(ord("a") + i) for i in range(26)})
    names.update({0x1E + i: str((i + 1) % 10) for i in range(10)})
    names.update(dict(enumerate((
        "enter", "escape", "backspace", "tab", "space", "minus", "equal", "left_bracket", "right_bracket",
        "backslash", "non_us_hash", "semicolon", "apostrophe", "grave", "comma", "period", "slash", "caps_lock"),
        start=0x28)))
    names.update({0x3A + i: f"f{i + 1}" for i in range(12)})
    names.update(dict(enumerate((
        "print_screen", "scroll_lock", "pause", "insert", "home", "page_up", "delete", "end", "page_down",
        "right", "left", "down", "up", "num_lock", "kp_slash", "kp_asterisk", "kp_minus", "kp_plus", "kp_enter"),
        start=0x46)))
    names.update({0x59 + i: f"kp_{(i + 1) % 10}" for i in range(10)})
    names.update(dict(enumerate(("kp_period", "non_us_backslash", "application", "power", "kp_equal"), start=0x63)))
    names.update({0x68 + i: f"f{13 + i}" for i in range(12)})
    names.update(dict(enumerate((
        "execute", "help", "menu", "select", "stop", "again", "undo", "cut", "copy", "paste", "find", "mute",
        "volume_up", "volume_down", "locking_caps_lock", "locking_num_lock", "locking_scroll_lock", "kp_comma",
        "kp_equal_sign"), start=0x74)))
    names.update({0x87 + i: f"international{i + 1}" for i in range(9)})
    names.update({0x90 + i: f"lang{i + 1}" for i in range(9)})
    names.update(dict(enumerate((
        "alternate_erase", "sysreq", "cancel", "clear", "prior", "return", "separator", "out", "oper",
        "clear_again", "crsel", "exsel"), start=0x99)))
    names.update(dict(enumerate((
        "kp_00", "kp_000", "thousands_separator", "decimal_separator", "currency_unit", "currency_sub_unit",
        "kp_left_paren", "kp_right_paren", "kp_left_brace", "kp_right_brace", "kp_tab", "kp_backspace",
        "kp_a", "kp_b", "kp_c", "kp_d", "kp_e", "kp_f", "kp_xor", "kp_caret", "kp_percent", "kp_less",
        "kp_greater", "kp_ampersand", "kp_double_ampersand", "kp_bar", "kp_double_bar", "kp_colon", "kp_hash",
        "kp_space", "kp_at", "kp_exclamation", "kp_memory_store", "kp_memory_recall", "kp_memory_clear",
        "kp_memory_add", "kp_memory_subtract", "kp_memory_multiply", "kp_memory_divide", "kp_plus_minus",
        "kp_clear", "kp_clear_entry", "kp_binary", "kp_octal", "kp_decimal", "kp_hexadecimal"), start=0xB0)))
    names.update(dict(enumerate(("left_ctrl", "left_shift", "left_alt", "left_gui",
                                 "right_ctrl", "right_shift", "right_alt", "right_gui"), start=0xE0)))
    return names


KEY_NAMES: Mapping[int, str] = _names()
"""Keyboard-page usage ID -> key name (HID Usage Tables 1.4 §10; 0xA5..0xAF and 0xDE..0xDF are reserved)."""

MODIFIER_NAMES: Mapping[int, str] = {0xE0: "ctrl", 0xE1: "shift", 0xE2: "alt", 0xE3: "gui",
                                     0xE4: "ctrl", 0xE5: "shift", 0xE6: "alt", 0xE7: "gui"}
"""Modifier usage -> the modifier it holds, either side alike (Right Alt is "altgr" on layouts with AltGr)."""

NUMLOCK_KEYS = frozenset(range(0x59, 0x64))
"""Keypad 1..9, 0 and the decimal key: they type only with Num Lock on."""


DEAD_MARKS: Mapping[str, str] = {"^": "\u0302", "´": "\u0301", "`": "\u0300", "¨": "\u0308", "~": "\u0303"}
"""A dead key's spacing character -> the combining mark it puts on the next letter."""


def compose(dead: str, char: str) -> str:
    """What a dead key then ``char`` type: the accented letter, the dead key's own character before a space,
    else both characters (as Windows does: "^" then "x" is "^x")."""
    if char == " ":
        return dead
    combined = unicodedata.normalize("NFC", char + DEAD_MARKS[dead])
    return combined if len(combined) == 1 else dead + char


def key_name(usage: int) -> str:
    """The name of a Keyboard-page usage ID (``key_0xNN`` for reserved and vendor ones)."""
    return KEY_NAMES.get(usage, f"key_0x{usage:02x}")


@dataclass(frozen=True)
class Layout:
    """One keyboard layout: for each usage, the characters it types plain, with Shift and with AltGr."""

    name: str
    description: str
    keys: Mapping[int, tuple[str, str, str]]
    altgr: bool
    """Whether Right Alt is AltGr (else it is a second Alt)."""
    caps: frozenset[int] = field(default=frozenset())
    """Keys besides the letters on which Caps Lock acts as Shift."""
    dead: frozenset[tuple[int, int]] = field(default=frozenset())
    """The dead keys, as (usage, level): level 0 plain, 1 Shift, 2 AltGr (see :meth:`level`)."""

    def caps_applies(self, usage: int) -> bool:
        """Whether Caps Lock acts as Shift on this key (a letter, or a key the layout marks)."""
        plain, shifted, _ = self.keys.get(usage, ("", "", ""))
        return usage in self.caps or (len(plain) == 1 and plain.isalpha() and shifted == plain.upper() != plain)

    def level(self, usage: int, *, shift: bool = False, altgr: bool = False, caps_lock: bool = False) -> int:
        """Which of a key's characters this state types: 0 plain, 1 Shift (or Caps Lock where it applies), 2 AltGr."""
        if altgr:
            return 2
        if caps_lock and self.caps_applies(usage):
            shift = not shift
        return 1 if shift else 0

    def char(self, usage: int, *, shift: bool = False, altgr: bool = False, caps_lock: bool = False,
             num_lock: bool = False) -> str:
        """The character a key types in this state ("" for none; a dead key's spacing character)."""
        if usage in NUMLOCK_KEYS and not num_lock:
            return ""
        return self.keys.get(usage, ("", "", ""))[self.level(usage, shift=shift, altgr=altgr, caps_lock=caps_lock)]

    def strokes(self) -> dict[str, tuple[int, bool, bool]]:
        """For every character the layout types: a key and state typing it, ``(usage, shift, altgr)``.

        The plainest way first (no modifier, then Shift, then AltGr, then the lowest usage); Num Lock on,
        Caps Lock off.
        """
        found: dict[str, tuple[int, bool, bool]] = {}
        for shift, altgr in ((False, False), (True, False), (False, True)):
            if altgr and not self.altgr:
                continue
            for usage in sorted(self.keys):
                c = self.char(usage, shift=shift, altgr=altgr, num_lock=True)
                if c and c not in found:
                    found[c] = (usage, shift, altgr)
        return found


def _row(start: int, plain: str, shifted: str, third: str = "") -> dict[int, tuple[str, str, str]]:
    """Consecutive usages from ``start``, one character of each string per key (a space in ``third``: none)."""
    return {start + i: (p, s, t.strip()) for i, (p, s, t) in
            enumerate(zip(plain, shifted, third.ljust(len(plain)), strict=True))}


_COMMON = {
    0x28: ("\r", "\r", ""), 0x29: ("\x1b", "\x1b", ""), 0x2A: ("\b", "\b", ""), 0x2B: ("\t", "\t", ""),
    0x2C: (" ", " ", ""), 0x4C: ("\x7f", "\x7f", ""),
    0x54: ("/", "/", ""), 0x55: ("*", "*", ""), 0x56: ("-", "-", ""), 0x57: ("+", "+", ""), 0x58: ("\r", "\r", ""),
    **{0x59 + i: (d, d, "") for i, d in enumerate("1234567890")},
    0x63: (".", ".", ""), 0x67: ("=", "=", ""),
}
"""Keys that type the same on every layout here (the keypad's decimal key aside: "," on the German one)."""

_LETTERS = _row(0x04, "abcdefghijklmnopqrstuvwxyz", "ABCDEFGHIJKLMNOPQRSTUVWXYZ")

_US = {**_COMMON, **_LETTERS, **_row(0x1E, "1234567890", "!@#$%^&*()"),
       **_row(0x2D, "-=[]\\\\;'`,./", "_+{}||:\"~<>?"), 0x64: ("\\", "|", "")}

_UK = {**_US, 0x1F: ("2", '"', ""), 0x20: ("3", "£", ""), 0x21: ("4", "$", "€"), 0x34: ("'", "@", ""),
       0x31: ("#", "~", ""), 0x32: ("#", "~", ""), 0x35: ("`", "¬", "¦"),
       0x04: ("a", "A", "á"), 0x08: ("e", "E", "é"), 0x0C: ("i", "I", "í"), 0x12: ("o", "O", "ó"),
       0x18: ("u", "U", "ú")}

_DE = {**_COMMON, **_LETTERS, **_row(0x1E, "1234567890", "!\"§$%&/()=", " ²³   {[]}"),
       0x1C: ("z", "Z", ""), 0x1D: ("y", "Y", ""), 0x14: ("q", "Q", "@"), 0x08: ("e", "E", "€"),
       0x10: ("m", "M", "µ"),
       0x2D: ("ß", "?", "\\"), 0x2E: ("´", "`", ""), 0x2F: ("ü", "Ü", ""), 0x30: ("+", "*", "~"),
       0x31: ("#", "'", ""), 0x32: ("#", "'", ""), 0x33: ("ö", "Ö", ""), 0x34: ("ä", "Ä", ""),
       0x35: ("^", "°", ""), 0x36: (",", ";", ""), 0x37: (".", ":", ""), 0x38: ("-", "_", ""),
       0x64: ("<", ">", "|"), 0x63: (",", ",", "")}

_FR = {**_COMMON, **_LETTERS, **_row(0x1E, "&é\"'(-è_çà", "1234567890", " ~#{[|`\\^@"),
       0x04: ("q", "Q", ""), 0x14: ("a", "A", ""), 0x1A: ("z", "Z", ""), 0x1D: ("w", "W", ""),
       0x33: ("m", "M", ""), 0x10: (",", "?", ""), 0x08: ("e", "E", "€"),
       0x2D: (")", "°", "]"), 0x2E: ("=", "+", "}"), 0x2F: ("^", "¨", ""), 0x30: ("$", "£", "¤"),
       0x31: ("*", "µ", ""), 0x32: ("*", "µ", ""), 0x34: ("ù", "%", ""), 0x35: ("²", "", ""),
       0x36: (";", ".", ""), 0x37: (":", "/", ""), 0x38: ("!", "§", ""), 0x64: ("<", ">", "")}

LAYOUTS: Mapping[str, Layout] = {
    "us": Layout("us", "US English (ANSI QWERTY)", _US, altgr=False),
    "uk": Layout("uk", "United Kingdom (ISO QWERTY, AltGr)", _UK, altgr=True),
    "de": Layout("de", "German (ISO QWERTZ, AltGr)", _DE, altgr=True,
                 dead=frozenset({(0x35, 0), (0x2E, 0), (0x2E, 1)})),  # ^, ´ and `
    "fr": Layout("fr", "French (ISO AZERTY, AltGr; Caps Lock shifts the digit row)", _FR, altgr=True,
                 caps=frozenset({*range(0x1E, 0x28), 0x2D, 0x2E, 0x2F, 0x30, 0x31, 0x32, 0x34, 0x10, 0x36, 0x37,
                                 0x38}),
                 dead=frozenset({(0x2F, 0), (0x2F, 1), (0x1F, 2), (0x24, 2)})),  # ^, ¨, AltGr ~ and `
}
"""The layouts by name."""


def layout(name: str) -> Layout:
    """A layout by name (case-insensitive); ConfigError lists the known ones."""
    try:
        return LAYOUTS[name.strip().lower()]
    except KeyError:
        raise ConfigError(f"unknown keyboard layout {name!r}; known: {', '.join(LAYOUTS)}") from None

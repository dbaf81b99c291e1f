"""Fixes for known broken report descriptors, per USB vendor/product ID, as the kernel's ``report_fixup`` hooks.

A :class:`Quirk` matches a device's IDs and then, like the kernel drivers, the descriptor's size and the
original bytes at a few offsets; it either patches bytes or replaces the whole descriptor.  The built-in
quirks are taken from Linux drivers (the file is named in each); :func:`register_quirk` adds more.
:func:`fixup` applies every matching quirk and says what it did (the parser puts that in its warnings).
"""

from __future__ import annotations

from dataclasses import dataclass

from pixelpen.errors import ConfigError


@dataclass(frozen=True)
class Quirk:
    """One fix: which devices, which descriptors (size and bytes to find), and the patch or replacement."""

    name: str
    vendor_id: int
    product_ids: tuple[int, ...]
    source: str
    """Where the fix comes from (a kernel driver file)."""
    expect: tuple[tuple[int, int], ...] = ()
    """(offset, original byte) pairs that must all match."""
    patch: tuple[tuple[int, int], ...] = ()
    """(offset, new byte) pairs written when the quirk matches."""
    size: int | None = None
    """The exact descriptor size required (None: any size that holds every offset)."""
    min_size: int = 0
    replacement: bytes | None = None
    """A whole new descriptor instead of a patch."""

    def __post_init__(self) -> None:
        if self.replacement is None and not self.patch:
            raise ConfigError(f"quirk {self.name!r} has neither a patch nor a replacement")
        if self.replacement is not None and self.patch:
            raise ConfigError(f"quirk {self.name!r} has both a patch and a replacement")

    def matches(self, data: bytes, vendor_id: int, product_id: int) -> bool:
        """Whether this quirk applies to this device's descriptor."""
        if vendor_id != self.vendor_id or product_id not in self.product_ids:
            return False
        if self.size is not None and len(data) != self.size:
            return False
        needed = max((o for o, _ in self.expect + self.patch), default=-1) + 1
        if len(data) < max(needed, self.min_size):
            return False
        return all(data[o] == b for o, b in self.expect)

    def apply(self, data: bytes) -> bytes:
        """The fixed descriptor."""
        if self.replacement is not None:
            return self.replacement
        out = bytearray(data)
        for offset, value in self.patch:
            out[offset] = value
        return bytes(out)


HOLTEK_ALT = 0x04D9
SINOWEALTH = 0x258A
LAVIEW = 0x22D4
KEYTOUCH = 0x0926

_KEYTOUCH_KEYBOARD = bytes([
    0x05, 0x01, 0x09, 0x06, 0xA1, 0x01,        # Generic Desktop, Keyboard, Collection (Application)
    0x05, 0x07, 0x19, 0xE0, 0x29, 0xE7,        # Keyboard page, Usage Minimum LeftControl .. Maximum Right GUI
    0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02,  # 8 modifier bits: Input (Data, Var, Abs)
    0x95, 0x01, 0x75, 0x08, 0x81, 0x01,        # 1 reserved byte: Input (Const)
    0x95, 0x03, 0x75, 0x01, 0x05, 0x08, 0x19, 0x01, 0x29, 0x03, 0x91, 0x02,  # 3 LEDs Num..Scroll: Output
    0x95, 0x05, 0x75, 0x01, 0x91, 0x01,        # 5 bits of LED padding: Output (Const)
    0x95, 0x06, 0x75, 0x08, 0x15, 0x00, 0x26, 0xFF, 0x00,  # 6 key slots of 8 bits, 0..255
    0x05, 0x07, 0x19, 0x00, 0x2A, 0xFF, 0x00, 0x81, 0x00,  # Keyboard usages 0..255: Input (Data, Array)
    0xC0,                                      # End Collection
])

QUIRKS: list[Quirk] = [
    # Usage Maximum and Logical Maximum 0x7FFF (over HID_MAX_USAGES) become 0x2FFF on interface 1; the kernel
    # also checks the interface number, which a descriptor alone does not carry.
    Quirk("holtek-mouse a067/a072/a0c2", HOLTEK_ALT, (0xA067, 0xA072, 0xA0C2), "drivers/hid/hid-holtek-mouse.c",
          expect=((115, 0xFF), (116, 0x7F), (120, 0xFF), (121, 0x7F)), patch=((116, 0x2F), (121, 0x2F)),
          min_size=122),
    Quirk("holtek-mouse a04a/a070/a081", HOLTEK_ALT, (0xA04A, 0xA070, 0xA081), "drivers/hid/hid-holtek-mouse.c",
          expect=((106, 0xFF), (107, 0x7F), (111, 0xFF), (112, 0x7F)), patch=((107, 0x2F), (112, 0x2F)),
          min_size=113),
    # Model O/O-/D: consumer Inputs marked Constant (0x81 0x03) become Data, Variable, Relative (0x81 0x06).
    Quirk("glorious model o/d consumer", SINOWEALTH, (0x0036, 0x0033), "drivers/hid/hid-glorious.c",
          expect=((84, 0x81), (112, 0x81), (140, 0x81), (85, 0x03), (113, 0x03), (141, 0x03)),
          patch=((85, 0x06), (113, 0x06), (141, 0x06)), size=213),
    # Model I: the keyboard report's Usage Minimum 1 becomes 0.
    Quirk("glorious model i keyboard", LAVIEW, (0x1503,), "drivers/hid/hid-glorious.c",
          expect=((41, 0x01),), patch=((41, 0x00),), size=156),
    # Keytouch IEC 60945: the whole descriptor is replaced by a boot keyboard with 0..255 key usages.
    Quirk("keytouch iec", KEYTOUCH, (0x3333,), "drivers/hid/hid-keytouch.c", replacement=_KEYTOUCH_KEYBOARD),
]
"""The built-in quirks, in the order they are tried."""


def register_quirk(quirk: Quirk) -> None:
    """Add a quirk (tried after the built-in ones)."""
    QUIRKS.append(quirk)


def fixup(data: bytes, vendor_id: int, product_id: int) -> tuple[bytes, list[str]]:
    """The descriptor with every matching quirk applied, and a note per quirk applied."""
    notes = []
    for quirk in QUIRKS:
        if quirk.matches(data, vendor_id, product_id):
            data = quirk.apply(data)
            what = "replaced the descriptor" if quirk.replacement is not None else \
                "patched offsets " + ", ".join(str(o) for o, _ in quirk.patch)
            notes.append(f"quirk {quirk.name} ({quirk.source}) {what} for {vendor_id:04x}:{product_id:04x}")
    return data, notes

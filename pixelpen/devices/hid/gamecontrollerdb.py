"""SDL GameControllerDB mapping strings: parse them, find one by a device's SDL GUID, apply it to a joystick.

A mapping line (SDL's ``SDL_gamepad.c`` and the community ``gamecontrollerdb.txt`` format) is
``GUID,name,target:source,...,platform:Linux,``:

* **GUID** — 32 hex digits, 16 bytes: bus (LE16), CRC16 of the name (LE16, usually 0 in the
  database), vendor (LE16), 0, product (LE16), 0, version (LE16), driver signature and data
  bytes; a device without a vendor ID has its name's first 11 characters in bytes 4..15 instead.
  SDL's special GUIDs ``xinput`` and ``default`` are accepted.
* **targets** — gamepad buttons :data:`BUTTONS` and axes :data:`AXES`; an axis target may take
  an output half prefix (``+leftx:h0.2,-leftx:h0.8``).
* **sources** — ``bN`` joystick button N, ``aN`` axis N, ``+aN``/``-aN`` its upper/lower half,
  ``aN~`` inverted, ``hH.M`` hat H with mask M (1 up, 2 right, 4 down, 8 left).
* **fields** — ``platform:``, ``crc:`` (hex CRC16 the device name must have),
  ``hint:[!]NAME:=VALUE``, ``sdk>=:N``/``sdk<=:N`` (Android), ``type:``, ``face:``.

:func:`parse_mapping` raises ParseError naming the field (its number and text, the column where it
starts).  :func:`sdl_guid` computes the GUID SDL's Linux backend gives a device
(``SDL_CreateJoystickGUID``: CRC-16/ARC of the name, poly 0xA001 reflected, initial 0), and
:meth:`MappingDatabase.find` matches as SDL does: the CRC is cleared on both sides, a mapping whose
``crc`` equals the device's wins, else one without a CRC; then the version is ignored.
:meth:`GamepadMapping.apply` turns a :class:`~pixelpen.devices.hid.joystick.JoystickState` into named
buttons and axes with SDL's integer arithmetic (``HandleJoystickAxis``/``Button``/``Hat``: the first
axis binding whose input range holds the value wins; axis-to-button presses beyond the middle of
the range); evaluated on one state, outputs bound to several sources are pressed when any is.

Limits: a mapping line at most :data:`MAX_LINE` characters, a database file :data:`MAX_DATABASE_BYTES`.
"""

from __future__ import annotations

import dataclasses
import re
import struct
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pixelpen.errors import InvalidArgument, ParseError

if TYPE_CHECKING:
    from pixelpen.devices.hid.events import DeviceId
    from pixelpen.devices.hid.joystick import JoystickState

__all__ = ["AXES", "BUTTONS", "Binding", "GamepadMapping", "GamepadState", "Hint", "MappingDatabase", "SdlGuid",
           "Source", "crc16", "parse_guid", "parse_mapping", "sdl_guid"]

BUTTONS = ("a", "b", "x", "y", "back", "guide", "start", "leftstick", "rightstick", "leftshoulder",
           "rightshoulder", "dpup", "dpdown", "dpleft", "dpright", "misc1", "paddle1", "paddle2", "paddle3",
           "paddle4", "touchpad", "misc2", "misc3", "misc4", "misc5", "misc6")
"""Gamepad buttons in SDL's ``SDL_GamepadButton`` order (a = south ... misc6)."""

AXES = ("leftx", "lefty", "rightx", "righty", "lefttrigger", "righttrigger")
"""Gamepad axes in SDL's ``SDL_GamepadAxis`` order; the triggers are 0..1, the sticks -1..1 (+y down)."""

TRIGGERS = frozenset({"lefttrigger", "righttrigger"})
META_FIELDS = ("platform", "crc", "hint", "sdk>=", "sdk<=", "type", "face")
SPECIAL_GUIDS = ("xinput", "default")
AXIS_MIN, AXIS_MAX = -32768, 32767
MAX_LINE = 8192
MAX_INDEX = 1023
MAX_DATABASE_BYTES = 16 << 20
GUID_BYTES = 16
VIRTUAL_BUS = 0xFF
"""SDL_HARDWARE_BUS_VIRTUAL."""
NAME_BYTES_WITH_SIGNATURE = 9
"""A name-form GUID's name beside a driver signature: 10 bytes of room, NUL included."""

BUS_IDS = {"usb": 0x03, "bluetooth": 0x05, "virtual": 0x06, "i2c": 0x18, "unknown": 0x00}
"""DeviceId.bus -> the Linux bus type (``linux/input.h`` BUS_*) SDL's Linux backend puts in the GUID."""

_AXIS_SOURCE = re.compile(r"([+-]?)a(\d+)(~?)")
_BUTTON_SOURCE = re.compile(r"b(\d+)")
_HAT_SOURCE = re.compile(r"h(\d+)\.(\d+)")

FieldError = Callable[[str], ParseError]
"""Builds the ParseError of one field of a mapping from a message."""


def crc16(data: bytes, crc: int = 0) -> int:
    """SDL_crc16: CRC-16/ARC (reflected polynomial 0xA001, initial value ``crc``); "123456789" gives 0xBB3D."""
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


@dataclass(frozen=True)
class SdlGuid:
    """An SDL joystick GUID taken apart (``SDL_GetJoystickGUIDInfo``); ``name`` for the no-vendor form."""

    bus: int
    crc: int
    vendor: int
    product: int
    version: int
    driver_signature: int = 0
    driver_data: int = 0
    name: str = ""

    @classmethod
    def from_bytes(cls, data: bytes) -> SdlGuid:
        """The fields of 16 GUID bytes, as ``SDL_GetJoystickGUIDInfo`` reads them.

        With a bus number (below 0x20, or 0xFF virtual): the standard form when words 3 and 5 are zero,
        else the name form (a driver signature in bytes 14-15 when the name leaves them free).  Other
        GUIDs (SDL's legacy forms) give only their bus, CRC 0; :meth:`MappingDatabase.find` compares the
        bytes themselves, so nothing is lost for matching.
        """
        if len(data) != GUID_BYTES:
            raise InvalidArgument(f"an SDL GUID is {GUID_BYTES} bytes, not {len(data)}")
        words = struct.unpack("<8H", data)
        bus = words[0]
        if not _is_bus(bus):
            return cls(bus, 0, 0, 0, 0)
        if words[3] == 0 and words[5] == 0:
            return cls(bus, words[1], words[2], words[4], words[6], data[14], data[15])
        name = data[4:].split(b"\0")[0]
        signature = data[14:16] if len(name) <= NAME_BYTES_WITH_SIGNATURE and data[14] else b"\0\0"
        return cls(bus, words[1], 0, 0, 0, signature[0], signature[1], name.decode("utf-8", "surrogateescape"))

    def to_bytes(self) -> bytes:
        """The 16 bytes in ``SDL_CreateJoystickGUID``'s layout: the standard form, or the name form when
        ``name`` is set (the name's UTF-8 bytes cut to 11, or 9 beside a driver signature, NUL-terminated)."""
        if not self.name:
            return struct.pack("<7H2B", self.bus, self.crc, self.vendor, 0, self.product, 0, self.version,
                               self.driver_signature, self.driver_data)
        head = struct.pack("<2H", self.bus, self.crc)
        space = 12 - (2 if self.driver_signature else 0)
        body = self.name.encode("utf-8", "surrogateescape")[: space - 1].ljust(space, b"\0")
        tail = bytes([self.driver_signature, self.driver_data]) if self.driver_signature else b""
        return head + body + tail

    @property
    def hex(self) -> str:
        """The GUID as SDL writes it: 32 lower-case hex digits."""
        return self.to_bytes().hex()

    def replace(self, **changes: Any) -> SdlGuid:
        """A copy with some fields changed (``crc=0`` for matching)."""
        return dataclasses.replace(self, **changes)

    @property
    def uses_version(self) -> bool:
        """Whether a lookup may retry without the version (SDL: when vendor and product are known)."""
        return bool(self.vendor and self.product)


def _is_bus(word: int) -> bool:
    """Whether a GUID's first word is a bus number (``SDL_GetJoystickGUIDInfo``: below 0x20, or 0xFF virtual)."""
    return word < 0x20 or word == VIRTUAL_BUS


def _cleared(data: bytes, *, version: bool) -> bytes:
    """GUID bytes with the CRC word (and the version word) zeroed, as SDL's ``SDL_SetJoystickGUIDCRC`` and
    ``SDL_SetJoystickGUIDVersion`` write them before comparing."""
    out = bytearray(data)
    out[2:4] = b"\0\0"
    if version:
        out[12:14] = b"\0\0"
    return bytes(out)


def parse_guid(text: str, *, source: str | None = None, line: int | None = None) -> SdlGuid:
    """32 hex digits -> :class:`SdlGuid`; a ParseError names the GUID field otherwise."""
    if len(text) != 32 or not all(c in "0123456789abcdefABCDEF" for c in text):
        raise ParseError("field 1 (GUID): expected 32 hexadecimal digits, 'xinput' or 'default'", source=source,
                         line=line, column=1, token=text)
    return SdlGuid.from_bytes(bytes.fromhex(text))


def sdl_guid(device: DeviceId, *, version: int = 0, name: str | None = None, bus: int | None = None,
             driver_signature: int = 0, driver_data: int = 0, with_crc: bool = True) -> SdlGuid:
    """The GUID SDL's Linux backend gives ``device``: its bus, the CRC16 of its name, vendor, product, version.

    ``SDL_CreateJoystickGUID``: the standard form when both vendor and product IDs are known, else the
    name form (the name's first 11 bytes instead of the IDs and the version).  ``name`` defaults to the
    device's (SDL uses the evdev name); ``with_crc=False`` gives the CRC-less form the database uses.
    The DeviceId has no version: pass the USB ``bcdDevice``.
    """
    product_name = device.name if name is None else name
    checksum = crc16(product_name.encode("utf-8")) if with_crc and product_name else 0
    bus_type = BUS_IDS.get(device.bus, 0) if bus is None else bus
    for what, value, bits in (("bus", bus_type, 16), ("version", version, 16), ("driver_signature",
                              driver_signature, 8), ("driver_data", driver_data, 8)):
        if not 0 <= value < 1 << bits:
            raise ValueError(f"{what} {value} does not fit in {bits} bits")
    if device.vendor_id and device.product_id:
        return SdlGuid(bus_type, checksum, device.vendor_id, device.product_id, version, driver_signature, driver_data)
    return SdlGuid(bus_type, checksum, 0, 0, 0, driver_signature, driver_data, product_name)


@dataclass(frozen=True)
class Source:
    """What a binding reads: joystick button, axis (optionally a half, optionally inverted) or hat mask."""

    kind: str
    """``button``, ``axis`` or ``hat``."""
    index: int
    half: str = ""
    """``+`` or ``-`` for a half axis (``+a1``), else empty."""
    inverted: bool = False
    mask: int = 0
    """A hat's direction mask (1 up, 2 right, 4 down, 8 left)."""

    @property
    def axis_range(self) -> tuple[int, int]:
        """SDL's ``axis_min, axis_max`` of an axis source (swapped when inverted)."""
        low, high = {"+": (0, AXIS_MAX), "-": (0, AXIS_MIN)}.get(self.half, (AXIS_MIN, AXIS_MAX))
        return (high, low) if self.inverted else (low, high)

    def __str__(self) -> str:
        if self.kind == "button":
            return f"b{self.index}"
        if self.kind == "hat":
            return f"h{self.index}.{self.mask}"
        return f"{self.half}a{self.index}{'~' if self.inverted else ''}"


@dataclass(frozen=True)
class Binding:
    """One ``target:source`` field: the gamepad output (``half`` for ``+leftx``), what drives it."""

    target: str
    source: Source
    half: str = ""

    @property
    def is_axis(self) -> bool:
        """Whether the target is a gamepad axis."""
        return self.target in AXES

    @property
    def output_range(self) -> tuple[int, int]:
        """SDL's output ``axis_min, axis_max`` (triggers always 0..max, whatever the prefix)."""
        if self.target in TRIGGERS:
            return 0, AXIS_MAX
        return {"+": (0, AXIS_MAX), "-": (0, AXIS_MIN)}.get(self.half, (AXIS_MIN, AXIS_MAX))

    def __str__(self) -> str:
        return f"{self.half}{self.target}:{self.source}"


@dataclass(frozen=True)
class Hint:
    """A ``hint:[!]NAME:=VALUE`` field: the mapping applies when the hint has (or, negated, has not) the value."""

    name: str
    value: str
    negated: bool = False

    def __str__(self) -> str:
        return f"hint:{'!' if self.negated else ''}{self.name}:={self.value}"


@dataclass(frozen=True)
class GamepadState:
    """Named gamepad outputs: axes (sticks -1..1, triggers 0..1) and buttons, for the targets a mapping has."""

    axes: dict[str, float] = field(default_factory=dict)
    buttons: dict[str, bool] = field(default_factory=dict)

    @classmethod
    def released(cls) -> GamepadState:
        """Nothing known yet (no axis reported, no button pressed)."""
        return cls()

    @staticmethod
    def button_number(name: str) -> int:
        """The button's SDL index + 1 (``a`` is 1, the primary button)."""
        return BUTTONS.index(name) + 1


@dataclass(frozen=True)
class GamepadMapping:
    """A parsed mapping string: GUID, name, bindings in order, and the extra fields."""

    guid: str
    name: str
    bindings: tuple[Binding, ...]
    platform: str | None = None
    crc: int | None = None
    """The ``crc:`` field (or a CRC found in the GUID itself, which SDL moves there)."""
    hints: tuple[Hint, ...] = ()
    sdk_min: int | None = None
    sdk_max: int | None = None
    type: str | None = None
    face: str | None = None

    @property
    def guid_info(self) -> SdlGuid | None:
        """The GUID's fields (None for ``xinput``/``default``)."""
        return None if self.guid in SPECIAL_GUIDS else SdlGuid.from_bytes(bytes.fromhex(self.guid))

    def __str__(self) -> str:
        fields = [self.guid, self.name, *map(str, self.bindings)]
        fields += [str(h) for h in self.hints]
        for key, value in (("crc", None if self.crc is None else f"{self.crc:04x}"), ("sdk>=", self.sdk_min),
                           ("sdk<=", self.sdk_max), ("type", self.type), ("face", self.face),
                           ("platform", self.platform)):
            if value is not None:
                fields.append(f"{key}:{value}")
        return ",".join(fields) + ","

    def apply(self, state: JoystickState) -> GamepadState:
        """The gamepad outputs for one joystick state (SDL's arithmetic; see the module docstring)."""
        axes: dict[str, float] = {}
        buttons: dict[str, bool] = {}
        for b in self.bindings:
            if b.is_axis:
                axes.setdefault(b.target, 0.0)
            else:
                buttons.setdefault(b.target, False)

        def drive(binding: Binding, value: int | None, down: bool) -> None:
            if binding.is_axis:
                assert value is not None
                if value or binding.target not in axes or not axes[binding.target]:
                    axes[binding.target] = max(-1.0, min(1.0, value / AXIS_MAX))
            elif down:
                buttons[binding.target] = True

        for index, raw in enumerate(state.axes):
            value = _int16(raw)
            match = next((b for b in self.bindings if b.source.kind == "axis" and b.source.index == index
                          and min(b.source.axis_range) <= value <= max(b.source.axis_range)), None)
            if match is None:
                continue
            low, high = match.source.axis_range
            if match.is_axis:
                out_low, out_high = match.output_range
                out = value
                if (low, high) != (out_low, out_high):
                    out = out_low + int((value - low) / (high - low) * (out_high - out_low))
                drive(match, out, False)
            else:
                threshold = low + int((high - low) / 2)
                drive(match, None, value <= threshold if high < low else value >= threshold)
        for index, down in enumerate(state.buttons):
            match = next((b for b in self.bindings if b.source.kind == "button" and b.source.index == index), None)
            if match is not None:
                drive(match, match.output_range[1 if down else 0] if match.is_axis else None, down)
        for index, mask in enumerate(state.hats):
            for b in self.bindings:
                if b.source.kind == "hat" and b.source.index == index and mask & b.source.mask:
                    drive(b, b.output_range[1] if b.is_axis else None, True)
        return GamepadState(axes, buttons)


def _int16(value: float) -> int:
    """A -1..1 axis value as SDL's Sint16."""
    return max(AXIS_MIN, min(AXIS_MAX, round(value * (AXIS_MAX if value >= 0 else -AXIS_MIN))))


def parse_mapping(text: str, *, source: str | None = None, line: int | None = None) -> GamepadMapping:
    """One mapping string -> :class:`GamepadMapping`; a ParseError names the bad field and where it starts."""
    text = text.strip()
    if len(text) > MAX_LINE:
        raise ParseError(f"a mapping of {len(text)} characters is longer than {MAX_LINE}", source=source, line=line)
    parts = text.split(",")
    columns = []
    position = 1
    for part in parts:
        columns.append(position)
        position += len(part) + 1

    def error(n: int) -> FieldError:
        return lambda message: ParseError(f"field {n + 1} {parts[n]!r}: {message}", source=source, line=line,
                                          column=columns[n], token=parts[n])

    if len(parts) < 2 or not parts[1].strip():
        raise ParseError("a mapping needs a GUID and a name (GUID,name,bindings...)", source=source, line=line,
                         token=text)
    guid = parts[0].strip()
    if guid.lower() not in SPECIAL_GUIDS:
        info = parse_guid(guid, source=source, line=line)
        guid = guid.lower()
    else:
        info = None
        guid = guid.lower()
    meta: dict[str, str] = {}
    numbers: dict[str, int] = {}
    bindings: list[Binding] = []
    hints: list[Hint] = []
    for n in range(2, len(parts)):
        item = parts[n].strip()
        if not item:
            continue
        key, sep, value = item.partition(":")
        if not sep:
            raise error(n)("expected target:source or key:value")
        if key == "hint":
            hints.append(_hint(value, error(n)))
        elif key in META_FIELDS:
            if key in meta:
                raise error(n)(f"{key} given twice")
            meta[key] = value
            numbers[key] = n
        else:
            bindings.append(_binding(key, value, error(n)))
    ints = {key: _meta_int(meta[key], 16 if key == "crc" else 10, error(numbers[key]))
            for key in ("crc", "sdk>=", "sdk<=") if key in meta}
    crc = ints.get("crc")
    if info is not None and info.crc:  # SDL_PrivateAddMappingForGUID: a CRC in the GUID replaces the crc field
        crc = info.crc
    return GamepadMapping(guid, parts[1], tuple(bindings), meta.get("platform"), crc, tuple(hints),
                          ints.get("sdk>="), ints.get("sdk<="), meta.get("type"), meta.get("face"))


def _meta_int(text: str, base: int, error: FieldError) -> int | None:
    """A crc (4 hex digits) or sdk (decimal) field's number."""
    limit = 0xFFFF if base == 16 else 10**6
    if text.isascii() and text.isalnum() and len(text) <= 7:
        try:
            value = int(text, base)
        except ValueError:
            value = -1
        if 0 <= value <= limit:
            return value
    raise error(f"expected {'4 hex digits' if base == 16 else 'a whole number'}")


def _hint(value: str, error: FieldError) -> Hint:
    negated = value.startswith("!")
    name, sep, wanted = value.removeprefix("!").partition(":=")
    if not sep or not name:
        raise error("expected hint:[!]NAME:=VALUE")
    return Hint(name, wanted, negated)


def _binding(key: str, value: str, error: FieldError) -> Binding:
    half = key[0] if key[:1] in ("+", "-") else ""
    target = (key[1:] if half else key).lower()  # SDL compares target names with SDL_strcasecmp
    if target not in AXES and target not in BUTTONS:
        raise error(f"unknown gamepad target {target!r} (buttons: {' '.join(BUTTONS)}; axes: {' '.join(AXES)})")
    if half and target not in AXES:
        raise error(f"the output half prefix {half} applies to axes only, not the button {target}")
    if m := _AXIS_SOURCE.fullmatch(value):
        src = Source("axis", int(m[2]), m[1], bool(m[3]))
    elif m := _BUTTON_SOURCE.fullmatch(value):
        src = Source("button", int(m[1]))
    elif m := _HAT_SOURCE.fullmatch(value):
        src = Source("hat", int(m[1]), mask=int(m[2]))
        if not 1 <= src.mask <= 15:
            raise error(f"hat mask {src.mask} is not 1..15 (1 up, 2 right, 4 down, 8 left)")
    else:
        raise error("expected a source bN, aN, +aN, -aN, aN~ or hH.M")
    if src.index > MAX_INDEX:
        raise error(f"joystick index {src.index} is above {MAX_INDEX}")
    return Binding(target, src, half)


class MappingDatabase:
    """Mappings by GUID, looked up as SDL does (CRC cleared, ``crc:`` preferred, then without the version)."""

    def __init__(self, mappings: Iterable[GamepadMapping] = ()) -> None:
        self._mappings: dict[str, GamepadMapping] = {}
        for mapping in mappings:
            self.add(mapping)

    def add(self, mapping: GamepadMapping) -> None:
        """Add a mapping (one for the same GUID and CRC replaces the older, as SDL's does)."""
        self._mappings[self._key(mapping)] = mapping

    @staticmethod
    def _key(mapping: GamepadMapping) -> str:
        guid = mapping.guid if mapping.guid in SPECIAL_GUIDS else _cleared(bytes.fromhex(mapping.guid),
                                                                           version=False).hex()
        return f"{guid}/{mapping.crc or 0:04x}"

    def __len__(self) -> int:
        return len(self._mappings)

    def __iter__(self) -> Iterator[GamepadMapping]:
        return iter(self._mappings.values())

    @classmethod
    def from_text(cls, text: str, *, platform: str | None = "Linux", source: str | None = None) -> MappingDatabase:
        """Parse a ``gamecontrollerdb.txt``: comments and blank lines skipped; with ``platform``, as SDL,
        only the lines whose ``platform:`` field names it (case-insensitive)."""
        if len(text) > MAX_DATABASE_BYTES:
            raise ParseError(f"a mapping database of {len(text)} characters is larger than {MAX_DATABASE_BYTES}",
                             source=source)
        db = cls()
        for number, line in enumerate(text.splitlines(), start=1):
            stripped = line.strip()
            if not stripped or stripped.startswith("#"):
                continue
            mapping = parse_mapping(stripped, source=source, line=number)
            if platform is None or (mapping.platform or "").lower() == platform.lower():
                db.add(mapping)
        return db

    @classmethod
    def read(cls, path: str | Path, *, platform: str | None = "Linux") -> MappingDatabase:
        """Read a database file (at most :data:`MAX_DATABASE_BYTES`)."""
        file = Path(path)
        with file.open("rb") as handle:
            data = handle.read(MAX_DATABASE_BYTES + 1)
        if len(data) > MAX_DATABASE_BYTES:
            raise ParseError(f"larger than {MAX_DATABASE_BYTES} bytes", source=str(file))
        return cls.from_text(data.decode("utf-8", "replace"), platform=platform, source=str(file))

    def find(self, guid: SdlGuid | str) -> GamepadMapping | None:
        """The mapping for a device's GUID, or None (SDL's ``SDL_PrivateGetGamepadMappingForGUID``)."""
        if isinstance(guid, str):
            parse_guid(guid)  # a ParseError names the GUID when it is not 32 hex digits
            data = bytes.fromhex(guid)
        else:
            data = guid.to_bytes()
        info = SdlGuid.from_bytes(data)
        found = self._match(data, info.crc, match_version=True)
        if found is None and info.uses_version:
            found = self._match(data, info.crc, match_version=False)
        return found

    def _match(self, data: bytes, crc: int, *, match_version: bool) -> GamepadMapping | None:
        """SDL's ``SDL_PrivateMatchGamepadMappingForGUID``: the bytes compared with the CRC (and the version)
        cleared; a mapping whose ``crc`` is the device's wins, else the first without one."""
        wanted = _cleared(data, version=not match_version)
        best = None
        for mapping in self._mappings.values():
            if mapping.guid in SPECIAL_GUIDS or _cleared(bytes.fromhex(mapping.guid),
                                                         version=not match_version) != wanted:
                continue
            if mapping.crc:
                if mapping.crc == crc:
                    return mapping
            elif best is None:
                best = mapping
        return best

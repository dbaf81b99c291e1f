"""HID units (HID 1.11 §6.2.2.7): their names, the kernel's axis resolution, and logical values in physical units.

A Unit item is seven nibbles, least significant first: the system (1 SI linear, 2 SI rotation, 3 English
linear, 4 English rotation), then signed 4-bit exponents of length, mass, time, temperature, current and
luminous intensity.  ``0x11`` is centimetres, ``0x13`` inches, ``0x12`` radians, ``0x14`` degrees.  The
Unit Exponent is a power of ten; the functions here take it signed, as the parser gives it (the parser
reads both the spec's nibble ``0x0D`` and the byte ``0xFD`` as -3, as the kernel does).
"""

from __future__ import annotations

import math

from pixelpen.devices.hid.fields import Field
from pixelpen.devices.hid.items import s32
from pixelpen.errors import InvalidArgument, ParseError

BASE_UNITS = {
    1: ("cm", "g", "s", "K", "A", "cd"),
    2: ("rad", "g", "s", "K", "A", "cd"),
    3: ("in", "slug", "s", "°F", "A", "cd"),
    4: ("deg", "slug", "s", "°F", "A", "cd"),
}
"""Per system, the base unit of each nibble after the system's (length or angle, mass, time, temperature,
current, luminous intensity)."""

UNIT_CM, UNIT_RADIAN, UNIT_INCH, UNIT_DEGREE = 0x11, 0x12, 0x13, 0x14
UNIT_GRAM, UNIT_NEWTON = 0x0101, 0xE111
"""The units the kernel's resolution formula converts (hid-input.c, HID_UNIT_GRAM/HID_UNIT_NEWTON)."""

LENGTH_USAGES = frozenset({0x00010030, 0x00010031, 0x00010032, 0x000D0048, 0x000D0049})
"""Usages the kernel maps to a length axis: X, Y, Z (ABS_X..Z, ABS_MT_POSITION_X/Y), Width, Height
(ABS_MT_TOUCH_MAJOR/MINOR)."""
ANGLE_USAGES = frozenset({0x00010033, 0x00010034, 0x00010035, 0x00010038, 0x000D003D, 0x000D003E})
"""Usages the kernel maps to an angle axis: Rx, Ry, Rz, Wheel (ABS_RX..RZ, ABS_WHEEL), X Tilt, Y Tilt."""
PRESSURE_USAGES = frozenset({0x000D0030})
"""Tip Pressure (ABS_PRESSURE, ABS_MT_PRESSURE)."""

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _nibble(value: int) -> int:
    """A 4-bit two's complement nibble as an int (0x0D -> -3)."""
    return value - 16 if value & 8 else value


def describe_unit(unit: int, exponent: int = 0) -> str:
    """A unit and exponent as text: ``describe_unit(0x11, -3)`` is ``"cm·10^-3"``, 0xE121 ``"g·cm²·s⁻²"``."""
    system = unit & 0xF
    parts = []
    if system in BASE_UNITS:
        names = BASE_UNITS[system]
        powers = [(names[i], _nibble(unit >> (4 * (i + 1)) & 0xF)) for i in range(6)]
        # mass first as physicists write it (g·cm²·s⁻²), then the rest in nibble order
        for name, power in sorted(powers, key=lambda p: p[0] not in ("g", "slug")):
            if power:
                parts.append(name + (str(power).translate(_SUPERSCRIPT) if power != 1 else ""))
    elif unit & 0xFFFFFFF:
        parts.append(f"unit 0x{unit:x} (reserved system {system})" if system else f"unit 0x{unit:x} (no system)")
    if unit >> 28:
        parts.append(f"(reserved nibble 0x{unit >> 28:x})")
    if not parts:
        return f"10^{exponent}" if exponent else "none"
    text = "·".join(parts)
    return text + f"·10^{exponent}" if exponent else text


def axis_kind(field: Field, usage: int | None = None) -> str | None:
    """``"length"``, ``"angle"`` or ``"pressure"``: by the usage when it is an axis the kernel knows, else by
    the unit (an extension: the kernel gives such usages no absolute axis); None for anything else."""
    u = usage if usage is not None else (field.usages[0] if field.usages else None)
    if u in LENGTH_USAGES:
        return "length"
    if u in ANGLE_USAGES:
        return "angle"
    if u in PRESSURE_USAGES:
        return "pressure"
    if field.unit in (UNIT_CM, UNIT_INCH):
        return "length"
    if field.unit in (UNIT_DEGREE, UNIT_RADIAN):
        return "angle"
    if field.unit in (UNIT_GRAM, UNIT_NEWTON):
        return "pressure"
    return None


def resolution(field: Field, usage: int | None = None) -> int | None:
    """The kernel's ``hidinput_calc_abs_res``: units per mm (lengths), per radian (angles) or per gram
    (pressure), rounded to the closest integer; None where the kernel gives 0 (no or unknown unit, empty or
    inverted extents, an overflow of its 32-bit arithmetic).  ``usage`` picks the axis (default: the field's
    first usage; see :func:`axis_kind`)."""
    exponent = field.unit_exponent
    logical = s32(field.logical_max - field.logical_min)
    physical = s32(field.physical_max - field.physical_min)
    if logical <= 0 or physical <= 0:
        return None
    kind = axis_kind(field, usage)
    if kind == "length":
        if field.unit == UNIT_CM:  # centimetres to millimetres
            exponent += 1
        elif field.unit == UNIT_INCH:  # inches to millimetres: x 25.4
            physical, prev = s32(physical * 254), physical
            if physical < prev:
                return None
            exponent -= 1
        else:
            return None
    elif kind == "angle":
        if field.unit == UNIT_DEGREE:  # degrees to radians: x 57.3
            logical, prev = s32(logical * 573), logical
            if logical < prev:
                return None
            exponent += 1
        elif field.unit != UNIT_RADIAN:
            return None
    elif kind == "pressure":
        if field.unit == UNIT_NEWTON:  # newtons to grams: x 101.97
            physical, prev = s32(physical * 10197), physical
            if physical < prev:
                return None
            exponent -= 2
        elif field.unit != UNIT_GRAM:
            return None
    else:
        return None
    for _ in range(max(0, -exponent)):
        logical, prev = s32(logical * 10), logical
        if logical < prev:
            return None
    for _ in range(max(0, exponent)):
        physical, prev = s32(physical * 10), physical
        if physical < prev:
            return None
    res = (logical + physical // 2) // physical  # DIV_ROUND_CLOSEST of two positive values
    return res or None


def to_physical(field: Field, value: float) -> float:
    """A logical value in the field's physical units, the unit exponent applied (``describe_unit`` names the
    unit); physical minimum = maximum = 0 means physical = logical (HID 1.11 §6.2.2.7)."""
    pmin, pmax = field.physical_min, field.physical_max
    if pmin == 0 and pmax == 0:
        pmin, pmax = field.logical_min, field.logical_max
    span = field.logical_max - field.logical_min
    physical = pmin + (value - field.logical_min) * (pmax - pmin) / span if span else float(pmin)
    if abs(field.unit_exponent) > MAX_UNIT_EXPONENT:
        raise ParseError(f"report {field.report_id}, field at bit {field.bit_offset}: unit exponent "
                         f"{field.unit_exponent} is outside ±{MAX_UNIT_EXPONENT} (no physical quantity)",
                         offset=field.offset, token=field.unit_exponent)
    return physical * 10.0 ** field.unit_exponent


MAX_UNIT_EXPONENT = 38
"""Unit exponents beyond this size (a 2- or 4-byte Unit Exponent item, which the kernel accepts) give no physical
value: 10**±38 is past any real device's range and near float32's, and 10**±309 overflows a float."""


def _unit_error(field: Field, wanted: str) -> InvalidArgument:
    usage = f"usage 0x{field.usages[0]:08x}" if field.usages else "a field without usage"
    return InvalidArgument(f"report {field.report_id}, {usage} at bit {field.bit_offset}: its unit "
                           f"{describe_unit(field.unit)!r} (0x{field.unit:x}) is not {wanted}")


def to_mm(field: Field, value: float) -> float:
    """A logical value of a length field (unit cm or inch) in millimetres; InvalidArgument for other units."""
    if field.unit == UNIT_CM:
        return to_physical(field, value) * 10.0
    if field.unit == UNIT_INCH:
        return to_physical(field, value) * 25.4
    raise _unit_error(field, "a length (cm or inch)")


def to_degrees(field: Field, value: float) -> float:
    """A logical value of an angle field (unit degree or radian) in degrees; InvalidArgument for other units."""
    if field.unit == UNIT_DEGREE:
        return to_physical(field, value)
    if field.unit == UNIT_RADIAN:
        return math.degrees(to_physical(field, value))
    raise _unit_error(field, "an angle (degree or radian)")

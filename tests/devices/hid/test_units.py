"""HID units: names, the kernel's hidinput_calc_abs_res worked by hand, and physical values."""

from __future__ import annotations

import dataclasses
import math

import pytest

from pixelpen.devices.hid.fields import MAIN_VARIABLE, Field, ReportKind
from pixelpen.devices.hid.units import describe_unit, resolution, to_degrees, to_mm, to_physical
from pixelpen.errors import InvalidArgument, ParseError

X, Y, RZ, WHEEL, TILT_X, PRESSURE, VENDOR = 0x10030, 0x10031, 0x10035, 0x10038, 0xD003D, 0xD0030, 0xFF000001


def axis(usage: int, lmin: int, lmax: int, pmin: int, pmax: int, unit: int, exponent: int) -> Field:
    return Field(ReportKind.INPUT, None, usage >> 16, (usage,), 0, 16, 1, lmin, lmax, pmin, pmax, unit, exponent,
                 MAIN_VARIABLE)


@pytest.mark.parametrize(("unit", "exponent", "text"), [
    (0x11, -3, "cm·10^-3"), (0x13, 0, "in"), (0x12, 0, "rad"), (0x14, 0, "deg"), (0x1001, -3, "s·10^-3"),
    (0xE121, 0, "g·cm²·s⁻²"), (0xE111, 0, "g·cm·s⁻²"), (0x0101, 0, "g"), (0, 0, "none"), (0, -2, "10^-2"),
    (0xF011, 0, "cm·s⁻¹"), (0xF00011, 0, "cm·A⁻¹"), (0x5, 0, "unit 0x5 (reserved system 5)"),
])
def test_describe_unit(unit, exponent, text):
    assert describe_unit(unit, exponent) == text


def test_textbook_resolutions():
    # X 0..44800 over 0..22400 x 10^-3 cm: 44800 / (22400 x 10^-3 x 10 mm) = 200 units/mm
    assert resolution(axis(X, 0, 44800, 0, 22400, 0x11, -3)) == 200
    # tilt -64..63 over -64..63 degrees: 127 x 573 / (127 x 10) = 57.3 -> 57 units/rad
    assert resolution(axis(TILT_X, -64, 63, -64, 63, 0x14, 0)) == 57


def test_inches_radians_and_newtons_as_the_kernel_converts_them():
    # inch: physical x 254, exponent - 1 -> 10000 x 10 / (5 x 254) = 78.74 -> 79 units/mm
    assert resolution(axis(Y, 0, 10000, 0, 5, 0x13, 0)) == 79
    # radian: no conversion; 6283 x 1000 / 6283 = 1000 units/rad
    assert resolution(axis(RZ, 0, 6283, 0, 6283, 0x12, -3)) == 1000
    # newton: physical x 10197, exponent - 2 -> 4095 x 100 / (10 x 10197) = 4.016 -> 4 units/g
    assert resolution(axis(PRESSURE, 0, 4095, 0, 10, 0xE111, 0)) == 4
    # gram: 1023 / 400 = 2.56 -> 3 (DIV_ROUND_CLOSEST)
    assert resolution(axis(PRESSURE, 0, 1023, 0, 400, 0x0101, 0)) == 3
    # a positive exponent multiplies the physical extent: 100000 / (100 x 10 cm x 10 mm/cm) = 10 units/mm
    assert resolution(axis(X, 0, 100000, 0, 100, 0x11, 1)) == 10


def test_the_kernel_gives_no_resolution():
    assert resolution(axis(X, 0, 100, 0, 0, 0x11, 0)) is None  # no physical extent
    assert resolution(axis(X, 100, 0, 0, 10, 0x11, 0)) is None  # inverted logical extent
    assert resolution(axis(X, 0, 100, 0, 10, 0, 0)) is None  # no unit
    assert resolution(axis(X, 0, 100, 0, 10, 0x14, 0)) is None  # a length axis in degrees
    assert resolution(axis(WHEEL, 0, 100, 0, 10, 0x11, 0)) is None  # an angle axis in cm
    # __s32 overflow: 2^31 - 1 x 10 wraps below the previous value
    assert resolution(axis(X, 0, 2**31 - 1, 0, 10, 0x11, -3)) is None
    assert resolution(axis(X, -(2**31), 2**31 - 1, 0, 10, 0x11, 0)) is None  # the extent itself wraps to -1
    # a rounding to 0 is "no resolution" too (the kernel's 0)
    assert resolution(axis(X, 0, 1, 0, 1000, 0x11, 0)) is None


def test_a_vendor_usage_is_classed_by_its_unit_and_usage_overrides():
    assert resolution(axis(VENDOR, 0, 44800, 0, 22400, 0x11, -3)) == 200
    assert resolution(axis(VENDOR, 0, 44800, 0, 22400, 0x11, -3), usage=WHEEL) is None


def test_physical_values():
    x = axis(X, 0, 44800, 0, 22400, 0x11, -3)
    assert to_physical(x, 44800) == pytest.approx(22.4)  # cm
    assert to_mm(x, 44800) == pytest.approx(224.0) and to_mm(x, 200) == pytest.approx(1.0)
    inch = axis(Y, 0, 10000, 0, 5, 0x13, 0)
    assert to_mm(inch, 5000) == pytest.approx(2.5 * 25.4)
    tilt = axis(TILT_X, -64, 63, -64, 63, 0x14, 0)
    assert to_degrees(tilt, -64) == -64 and to_degrees(tilt, 63) == 63
    rad = axis(RZ, 0, 6283, 0, 6283, 0x12, -3)
    assert to_degrees(rad, 1000 * math.pi) == pytest.approx(180.0)
    assert math.isclose(to_physical(axis(X, 0, 255, 0, 0, 0, 0), 17), 17)  # physical 0..0: logical
    assert to_physical(axis(X, 5, 5, 1, 9, 0, 0), 5) == 1.0  # no logical extent
    with pytest.raises(InvalidArgument, match=r"usage 0x00010030 at bit 0: its unit 'deg' \(0x14\) is not a length"):
        to_mm(dataclasses.replace(tilt, usages=(X,)), 1)
    with pytest.raises(InvalidArgument, match="is not an angle"):
        to_degrees(x, 1)


@pytest.mark.parametrize("exponent", [1024, -400, 39])
def test_an_unphysical_unit_exponent_is_a_parse_error_not_an_overflow(exponent):
    x = axis(X, 0, 44800, 0, 22400, 0x11, exponent)  # a 2-byte Unit Exponent item, which the kernel accepts
    with pytest.raises(ParseError, match=f"unit exponent {exponent} is outside"):
        to_mm(x, 100)
    assert to_mm(axis(X, 0, 44800, 0, 22400, 0x11, 38), 1) > 1e30  # the largest accepted

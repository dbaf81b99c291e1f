"""Tablet semantics: Microsoft-style pen descriptors written byte by byte, reports packed by hand, values by hand."""

from __future__ import annotations

import math
import re
import struct
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.devices.hid.codec import ShortReportWarning
from pixelpen.devices.hid.descriptor import parse_descriptor
from pixelpen.devices.hid.events import DeviceId, Pen
from pixelpen.devices.hid.semantics import output_reports_of, semantics_for
from pixelpen.devices.hid.tablet import PressureCurve, Tablet
from pixelpen.errors import ConfigError, ParseError

DEVICE = DeviceId("usb", 0x056A, 0x0357, name="test pen")

# A pen after Microsoft's sample pen descriptor ("Windows pen devices"), in inches with exponent -3.
PEN = bytes([
    0x05, 0x0D,        # Usage Page (Digitizers)
    0x09, 0x02,        # Usage (Pen)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x01,        #   Report ID (1)
    0x09, 0x20,        #   Usage (Stylus)
    0xA1, 0x00,        #   Collection (Physical)
    0x09, 0x42,        #     Usage (Tip Switch)          bit 0
    0x09, 0x44,        #     Usage (Barrel Switch)       bit 1
    0x09, 0x3C,        #     Usage (Invert)              bit 2
    0x09, 0x45,        #     Usage (Eraser)              bit 3
    0x09, 0x32,        #     Usage (In Range)            bit 4
    0x09, 0x5A,        #     Usage (Secondary Barrel)    bit 5
    0x15, 0x00,        #     Logical Minimum (0)
    0x25, 0x01,        #     Logical Maximum (1)
    0x75, 0x01,        #     Report Size (1)
    0x95, 0x06,        #     Report Count (6)
    0x81, 0x02,        #     Input (Data, Variable, Absolute)
    0x95, 0x02,        #     Report Count (2)
    0x81, 0x03,        #     Input (Constant): bits 6-7
    0x05, 0x01,        #     Usage Page (Generic Desktop)
    0x09, 0x30,        #     Usage (X)
    0x75, 0x10,        #     Report Size (16)
    0x95, 0x01,        #     Report Count (1)
    0xA4,              #     Push
    0x55, 0x0D,        #     Unit Exponent (-3)
    0x65, 0x13,        #     Unit (English Linear: inch)
    0x35, 0x00,        #     Physical Minimum (0)
    0x46, 0x3A, 0x20,  #     Physical Maximum (8250): 8.250 in
    0x26, 0x74, 0x40,  #     Logical Maximum (16500)
    0x81, 0x02,        #     Input: X, bytes 2-3
    0x09, 0x31,        #     Usage (Y)
    0x46, 0x82, 0x14,  #     Physical Maximum (5250): 5.250 in
    0x26, 0x04, 0x29,  #     Logical Maximum (10500)
    0x81, 0x02,        #     Input: Y, bytes 4-5
    0xB4,              #     Pop (Generic Desktop, 16 bits, 0..1, no unit)
    0x05, 0x0D,        #     Usage Page (Digitizers)
    0x09, 0x30,        #     Usage (Tip Pressure)
    0x26, 0xFF, 0x03,  #     Logical Maximum (1023)
    0x81, 0x02,        #     Input: pressure, bytes 6-7
    0x09, 0x3D,        #     Usage (X Tilt)
    0x09, 0x3E,        #     Usage (Y Tilt)
    0x16, 0xD8, 0xDC,  #     Logical Minimum (-9000)
    0x26, 0x28, 0x23,  #     Logical Maximum (9000)
    0x36, 0xD8, 0xDC,  #     Physical Minimum (-9000)
    0x46, 0x28, 0x23,  #     Physical Maximum (9000)
    0x65, 0x14,        #     Unit (English Rotation: degrees)
    0x55, 0x0E,        #     Unit Exponent (-2): 0.01 degree per count
    0x95, 0x02,        #     Report Count (2)
    0x81, 0x02,        #     Input: tilt X, Y int16, bytes 8-11
    0x65, 0x00,        #     Unit (None)
    0x55, 0x00,        #     Unit Exponent (0)
    0x35, 0x00,        #     Physical Minimum (0)
    0x45, 0x00,        #     Physical Maximum (0)
    0x09, 0x5B,        #     Usage (Transducer Serial Number)
    0x15, 0x00,        #     Logical Minimum (0)
    0x27, 0xFF, 0xFF, 0xFF, 0xFF,  # Logical Maximum (4294967295: unsigned, the minimum is not negative)
    0x75, 0x20,        #     Report Size (32)
    0x95, 0x01,        #     Report Count (1)
    0x81, 0x02,        #     Input: serial, bytes 12-15
    0xC0,              #   End Collection
    0xC0,              # End Collection
])
TIP, BARREL, INVERT, ERASER, IN_RANGE, BARREL2 = 1, 2, 4, 8, 16, 32
PEN_DESCRIPTOR = parse_descriptor(PEN)

# A cheap tablet: unnumbered, no units at all, tilt -127..127 without a unit.
PLAIN = bytes([
    0x05, 0x0D, 0x09, 0x01, 0xA1, 0x01,  # Usage Page (Digitizers), Usage (Digitizer), Collection (Application)
    0x09, 0x20, 0xA1, 0x00,              #   Usage (Stylus), Collection (Physical)
    0x09, 0x42, 0x09, 0x32,              #     Usage (Tip Switch), Usage (In Range)
    0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x02, 0x81, 0x02,  # 2 bits: byte 0 bits 0-1
    0x95, 0x06, 0x81, 0x03,              #     6 bits of padding
    0x05, 0x01, 0x09, 0x30, 0x09, 0x31,  #     Usage Page (Generic Desktop), Usage (X), Usage (Y)
    0x26, 0xFF, 0x7F, 0x75, 0x10, 0x95, 0x02, 0x81, 0x02,  # 0..32767, 16 bits x 2: bytes 1-4
    0x05, 0x0D, 0x09, 0x30,              #     Usage Page (Digitizers), Usage (Tip Pressure)
    0x26, 0xFF, 0x07, 0x95, 0x01, 0x81, 0x02,  # 0..2047, 16 bits: bytes 5-6
    0x09, 0x3D, 0x09, 0x3E,              #     Usage (X Tilt), Usage (Y Tilt)
    0x15, 0x81, 0x25, 0x7F, 0x75, 0x08, 0x95, 0x02, 0x81, 0x02,  # -127..127, int8 x 2: bytes 7-8
    0xC0, 0xC0,
])


def pen_report(bits: int, x: int, y: int, pressure: int = 0, tilt_x: int = 0, tilt_y: int = 0,
               serial: int = 0) -> bytes:
    return struct.pack("<BBHHHhhI", 1, bits, x, y, pressure, tilt_x, tilt_y, serial)


@pytest.fixture
def tablet() -> Tablet:
    return Tablet(parse_descriptor(PEN), DEVICE)


def test_semantics_for_picks_the_tablet_and_it_describes_the_pen():
    sem = semantics_for(parse_descriptor(PEN), DEVICE)
    assert isinstance(sem, Tablet)
    # 8.25 in x 25.4 = 209.55 mm; 5.25 in = 133.35 mm (one decimal either way of the 5)
    assert re.search(r"209\.[56] x 133\.[34] mm", sem.describe()) and "1024 pressure levels" in sem.describe()
    assert output_reports_of(sem) == []


def test_position_pressure_tilt_and_serial_decoded_by_hand(tablet):
    [pen] = tablet.feed(pen_report(IN_RANGE | TIP, 8250, 2625, 1023, -4500, 1234, 0xDEADBEEF), 2.5)
    assert isinstance(pen, Pen) and pen.time == 2.5 and pen.device == DEVICE
    # X 8250 of 16500 over 8.250 in: 4.125 in = 104.775 mm; Y 2625 of 10500 over 5.25 in: 1.3125 in = 33.3375 mm
    assert pen.x == 0.5 and pen.y == 0.25
    assert pen.x_mm == pytest.approx(104.775) and pen.y_mm == pytest.approx(33.3375)
    assert pen.pressure == 1.0
    # tilt: -4500 x 10^-2 degrees = -45 degrees, 1234 x 10^-2 = 12.34 degrees
    assert pen.tilt_x == pytest.approx(-45.0) and pen.tilt_y == pytest.approx(12.34)
    assert pen.in_range and pen.touching and not pen.eraser and not pen.inverted
    assert pen.barrel == (False, False)
    assert pen.serial == 0xDEADBEEF


def test_a_position_past_the_logical_range_is_held_at_the_edge_in_mm_too(tablet):
    [pen] = tablet.feed(pen_report(IN_RANGE | TIP, 20000, 11000), 0.0)  # logical maxima 16500 and 10500
    assert (pen.x, pen.y) == (1.0, 1.0)
    assert pen.x_mm == pytest.approx(8.25 * 25.4) and pen.y_mm == pytest.approx(5.25 * 25.4)  # the surface's edge


def test_linear_pressure_and_the_pressure_range(tablet):
    [pen] = tablet.feed(pen_report(IN_RANGE | TIP, 0, 0, 512), 0.0)
    assert pen.pressure == pytest.approx(512 / 1023)
    ranged = Tablet(parse_descriptor(PEN), DEVICE, pressure_range="0.1:0.9")
    [pen] = ranged.feed(pen_report(IN_RANGE | TIP, 0, 0, 512), 0.0)
    assert pen.pressure == pytest.approx((512 / 1023 - 0.1) / 0.8)
    [pen] = ranged.feed(pen_report(IN_RANGE | TIP, 0, 0, 50), 0.1)  # 50/1023 = 0.049 < 0.1: nothing
    assert pen.pressure == 0.0
    [pen] = ranged.feed(pen_report(IN_RANGE | TIP, 0, 0, 1000), 0.2)  # 0.978 > 0.9: full
    assert pen.pressure == 1.0


def test_gamma_and_bezier_pressure_curves_through_the_tablet():
    gamma = Tablet(parse_descriptor(PEN), DEVICE, pressure_curve="gamma:2")
    [pen] = gamma.feed(pen_report(IN_RANGE | TIP, 0, 0, 512), 0.0)
    assert pen.pressure == pytest.approx((512 / 1023) ** 2)
    # control points (1/3, 1) and (2/3, 1): x(t) = t exactly, so y = 3(1-p)^2 p + 3(1-p) p^2 + p^3
    bezier = Tablet(parse_descriptor(PEN), DEVICE, pressure_curve=(1 / 3, 1, 2 / 3, 1))
    [pen] = bezier.feed(pen_report(IN_RANGE | TIP, 0, 0, 300), 0.0)
    p = 300 / 1023
    assert pen.pressure == pytest.approx(3 * (1 - p) ** 2 * p + 3 * (1 - p) * p * p + p ** 3, abs=1e-12)


def test_bezier_values_by_hand():
    assert PressureCurve("bezier", (1 / 3, 1, 2 / 3, 1))(0.5) == pytest.approx(0.875, abs=1e-12)
    # control points on the diagonal: the identity
    identity = PressureCurve("bezier", (0.25, 0.25, 0.75, 0.75))
    assert identity.batch(np.linspace(0, 1, 11)) == pytest.approx(np.linspace(0, 1, 11), abs=1e-12)
    # out of range pressures are clamped
    assert identity(-3.0) == 0.0 and identity(7.0) == 1.0


@given(st.lists(st.floats(0.0, 1.0), min_size=4, max_size=4), st.lists(st.floats(0.0, 1.0), min_size=2, max_size=40))
def test_bezier_curves_are_monotonic_and_keep_their_ends(points, pressures):
    curve = PressureCurve("bezier", points)
    xs = np.sort(np.array([*pressures, 0.0, 1.0]))
    ys = curve.batch(xs)
    assert curve(0.0) == 0.0 and curve(1.0) == 1.0
    assert np.all((ys >= 0.0) & (ys <= 1.0))
    assert np.all(np.diff(ys) >= -1e-12)  # monotonic up to rounding of the Bernstein sums


@given(st.floats(0.05, 20.0), st.lists(st.floats(0.0, 1.0), min_size=2, max_size=40))
def test_gamma_curves_are_monotonic_and_keep_their_ends(gamma, pressures):
    curve = PressureCurve("gamma", gamma=gamma)
    ys = curve.batch(np.sort(np.array(pressures)))
    assert curve(0.0) == 0.0 and curve(1.0) == 1.0
    assert np.all(np.diff(ys) >= 0.0)


def test_events_only_on_change_and_proximity_out_once(tablet):
    hover = pen_report(IN_RANGE, 1000, 2000, serial=7)
    [first] = tablet.feed(hover, 0.0)
    assert first.in_range and not first.touching and first.pressure == 0.0
    assert tablet.feed(hover, 0.01) == []  # nothing changed
    [down] = tablet.feed(pen_report(IN_RANGE | TIP, 1000, 2000, 400, serial=7), 0.02)
    assert down.touching and down.pressure == pytest.approx(400 / 1023)
    [out] = tablet.feed(pen_report(0, 0, 0), 0.03)  # leaving: the device zeroes everything
    assert not out.in_range and not out.touching and out.pressure == 0.0
    assert (out.x, out.y) == (down.x, down.y) and out.serial == 7  # at the last position, the same tool
    assert tablet.feed(pen_report(0, 0, 0), 0.04) == []
    assert tablet.feed(pen_report(0, 500, 500), 0.05) == []  # out of range, whatever it says
    [back] = tablet.feed(hover, 0.06)
    assert back.in_range and back.x == first.x


def test_eraser_invert_and_barrels(tablet):
    [near] = tablet.feed(pen_report(IN_RANGE | INVERT, 100, 100), 0.0)
    assert near.eraser and near.inverted and not near.touching
    [rubbing] = tablet.feed(pen_report(IN_RANGE | INVERT | ERASER, 100, 100, 800), 0.1)
    assert rubbing.eraser and rubbing.touching and rubbing.pressure == pytest.approx(800 / 1023)
    [buttons] = tablet.feed(pen_report(IN_RANGE | BARREL | BARREL2, 100, 100), 0.2)
    assert buttons.barrel == (True, True) and not buttons.eraser
    [one] = tablet.feed(pen_report(IN_RANGE | BARREL2, 100, 100), 0.3)
    assert one.barrel == (False, True)


def test_a_new_tool_serial_is_an_event(tablet):
    tablet.feed(pen_report(IN_RANGE, 10, 10, serial=1), 0.0)
    [other] = tablet.feed(pen_report(IN_RANGE, 10, 10, serial=2), 0.1)
    assert other.serial == 2


def test_without_units_positions_in_mm_are_nan_unless_a_size_is_given():
    plain = Tablet(parse_descriptor(PLAIN), DEVICE)
    assert "size unknown" in plain.describe()
    report = struct.pack("<BHHHbb", 0b11, 32767, 0, 2047, 127, -127)
    [pen] = plain.feed(report, 0.0)
    assert math.isnan(pen.x_mm) and math.isnan(pen.y_mm) and (pen.x, pen.y) == (1.0, 0.0)
    assert plain.feed(report, 0.1) == []  # NaN positions still compare as unchanged
    # tilt without a unit: libinput's -64..64 degrees over the logical range
    assert (pen.tilt_x, pen.tilt_y) == (64.0, -64.0)
    sized = Tablet(parse_descriptor(PLAIN), DEVICE, size="200x100")
    [pen] = sized.feed(struct.pack("<BHHHbb", 0b11, 32767, 16383, 0, 0, 0), 0.0)
    assert pen.x_mm == pytest.approx(200.0) and pen.y_mm == pytest.approx(16383 / 32767 * 100.0)
    assert (pen.tilt_x, pen.tilt_y) == (0.0, 0.0)
    inches = Tablet(parse_descriptor(PLAIN), DEVICE, size="8x5in")
    [pen] = inches.feed(struct.pack("<BHHHbb", 0b11, 32767, 32767, 0, 0, 0), 0.0)
    assert (pen.x_mm, pen.y_mm) == (pytest.approx(203.2), pytest.approx(127.0))


@pytest.mark.parametrize(("options", "message"), [
    ({"pressure_curve": "cubic"}, "pressure_curve"),
    ({"pressure_curve": "0:0:1"}, "pressure_curve"),
    ({"pressure_curve": "0:0:1.5:1"}, "pressure_curve"),
    ({"pressure_curve": "gamma:-1"}, "pressure_curve"),
    ({"pressure_curve": "gamma:x"}, "pressure_curve"),
    ({"pressure_range": "0.9:0.1"}, "pressure_range"),
    ({"size": "100x50px"}, "size"),
    ({"size": "big"}, "size"),
    ({"speed": "1"}, "unknown option"),
])
def test_bad_options_are_config_errors_naming_the_option(options, message):
    with pytest.raises(ConfigError, match=message):
        Tablet(parse_descriptor(PEN), DEVICE, **options)


def test_bad_reports_give_clear_errors_or_documented_padding(tablet):
    with pytest.raises(ParseError, match="report 2"):
        tablet.feed(b"\x02" + bytes(15), 0.0)  # an ID the pen does not have
    with pytest.raises(ParseError, match="empty"):
        tablet.feed(b"", 0.0)
    with warnings.catch_warnings(record=True) as caught:  # short: zero-padded as the kernel does, with a warning
        warnings.simplefilter("always")
        [pen] = tablet.feed(pen_report(IN_RANGE | TIP, 16500, 10500)[:6], 0.0)
    assert any(issubclass(w.category, ShortReportWarning) for w in caught)
    assert (pen.x, pen.y, pen.pressure) == (1.0, 1.0, 0.0)
    assert tablet.feed(pen_report(IN_RANGE | TIP, 16500, 10500) + b"junk", 0.1) == []  # the tail is ignored


@given(st.binary(min_size=1, max_size=40))
def test_any_report_gives_events_or_a_parse_error(data):
    tablet = Tablet(parse_descriptor(PEN), DEVICE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ShortReportWarning)
        try:
            events = tablet.feed(data, 0.0)
        except ParseError:
            return
    assert all(isinstance(e, Pen) and 0.0 <= e.pressure <= 1.0 and 0.0 <= e.x <= 1.0 for e in events)


@given(st.text(max_size=30), st.text(max_size=12))
def test_any_option_text_gives_a_tablet_or_a_config_error(curve, pressure_range):
    try:
        tablet = Tablet(PEN_DESCRIPTOR, DEVICE, pressure_curve=curve, pressure_range=pressure_range)
    except ConfigError:
        return
    [pen] = tablet.feed(pen_report(IN_RANGE | TIP, 0, 0, 700), 0.0)
    assert 0.0 <= pen.pressure <= 1.0

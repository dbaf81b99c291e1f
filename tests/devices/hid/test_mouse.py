"""Mouse and trackball semantics: hand-packed reports, mm from the resolution, hi-res wheels, libinput's profiles."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.devices.hid import parse_descriptor
from pixelpen.devices.hid.events import Axis, Button, Motion, Wheel
from pixelpen.devices.hid.fields import MAIN_VARIABLE, Field, ReportKind
from pixelpen.devices.hid.mouse import BUTTON_NAMES, AdaptiveProfile, FlatProfile, Mouse, effective_multiplier
from pixelpen.devices.hid.semantics import OutputReport
from pixelpen.drivers.identity import DeviceId
from pixelpen.errors import ConfigError, ParseError
from pixelpen.sim.hid.descriptors import BOOT_MOUSE, TRACKBALL

DEV = DeviceId("usb", 0x046D, 0xC408, name="Test trackball")

# A wheel mouse whose Resolution Multiplier sits in no logical collection (HUT §4.3.1: then it applies to every
# control of the report), and whose wheel counts 1/4 detents at multiplier 1..4.
WHEEL_NO_LOGICAL = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x02,        # Usage (Mouse)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x01,        #   Report ID (1)
    0x05, 0x09,        #   Usage Page (Button)
    0x19, 0x01,        #   Usage Minimum (1)
    0x29, 0x05,        #   Usage Maximum (5)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x01,        #   Logical Maximum (1)
    0x75, 0x01,        #   Report Size (1)
    0x95, 0x05,        #   Report Count (5)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): buttons 1-5, byte 1 bits 0-4
    0x95, 0x03,        #   Report Count (3)
    0x81, 0x01,        #   Input (Constant): padding, byte 1 bits 5-7
    0x05, 0x01,        #   Usage Page (Generic Desktop)
    0x09, 0x38,        #   Usage (Wheel)
    0x15, 0x81,        #   Logical Minimum (-127)
    0x25, 0x7F,        #   Logical Maximum (127)
    0x75, 0x08,        #   Report Size (8)
    0x95, 0x01,        #   Report Count (1)
    0x81, 0x06,        #   Input (Data, Variable, Relative): wheel, byte 2
    0x85, 0x02,        #   Report ID (2)
    0x09, 0x48,        #   Usage (Resolution Multiplier)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x03,        #   Logical Maximum (3)
    0x35, 0x01,        #   Physical Minimum (1)
    0x45, 0x04,        #   Physical Maximum (4)
    0x75, 0x08,        #   Report Size (8)
    0xB1, 0x02,        #   Feature (Data, Variable, Absolute): feature report 2 byte 1
    0xC0,              # End Collection
])

# An absolute pointer, as a virtual machine's USB tablet: 3 buttons, X and Y 0..32767 absolute.
ABSOLUTE_POINTER = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x02,        # Usage (Mouse)
    0xA1, 0x01,        # Collection (Application)
    0x09, 0x01,        #   Usage (Pointer)
    0xA1, 0x00,        #   Collection (Physical)
    0x05, 0x09,        #     Usage Page (Button)
    0x19, 0x01,        #     Usage Minimum (1)
    0x29, 0x03,        #     Usage Maximum (3)
    0x15, 0x00,        #     Logical Minimum (0)
    0x25, 0x01,        #     Logical Maximum (1)
    0x95, 0x03,        #     Report Count (3)
    0x75, 0x01,        #     Report Size (1)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): byte 0 bits 0-2
    0x95, 0x01,        #     Report Count (1)
    0x75, 0x05,        #     Report Size (5)
    0x81, 0x01,        #     Input (Constant): byte 0 bits 3-7
    0x05, 0x01,        #     Usage Page (Generic Desktop)
    0x09, 0x30,        #     Usage (X)
    0x09, 0x31,        #     Usage (Y)
    0x15, 0x00,        #     Logical Minimum (0)
    0x26, 0xFF, 0x7F,  #     Logical Maximum (32767)
    0x75, 0x10,        #     Report Size (16)
    0x95, 0x02,        #     Report Count (2)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): X bytes 1-2, Y bytes 3-4
    0xC0,              #   End Collection
    0xC0,              # End Collection
])


def mouse(data: bytes = BOOT_MOUSE, **options: object) -> Mouse:
    return Mouse(parse_descriptor(data), DEV, **options)


def multiplier_field(lmin: int, lmax: int, pmin: int, pmax: int) -> Field:
    return Field(ReportKind.FEATURE, 2, 1, (0x00010048,), 8, 8, 1, lmin, lmax, pmin, pmax, 0, 0, MAIN_VARIABLE)


# -- boot mouse ------------------------------------------------------------------------------------------

def test_boot_mouse_motion_and_buttons_in_counts():
    m = mouse()
    # byte 0 = 0x05: buttons 1 and 3; byte 1 = 0x05: X +5; byte 2 = 0xFD: Y -3 (towards the top of the screen)
    events = m.feed(bytes([0x05, 0x05, 0xFD]), 1.0)
    assert events == [Motion(1.0, DEV, dx=5, dy=-3),
                      Button(1.0, DEV, button=1, pressed=True, name="left"),
                      Button(1.0, DEV, button=3, pressed=True, name="middle")]
    # no motion and button 3 still down: only button 1's release
    assert m.feed(bytes([0x04, 0x00, 0x00]), 1.1) == [Button(1.1, DEV, button=1, pressed=False, name="left")]
    assert m.feed(bytes([0x04, 0x00, 0x00]), 1.2) == []
    assert m.resolution == (None, None) and not m.absolute
    assert m.output_reports() == []


def test_dpi_option_gives_mm():
    m = mouse(dpi=800)
    (motion,) = m.feed(bytes([0x00, 0x20, 0xE0]), 0.0)  # X +32, Y -32 counts
    assert motion.dx_mm == pytest.approx(32 * 25.4 / 800) and motion.dy_mm == pytest.approx(-32 * 25.4 / 800)


# -- trackball -------------------------------------------------------------------------------------------

def test_trackball_resolution_from_physical_range_unit_and_exponent():
    m = mouse(TRACKBALL)
    # X: logical -32000..32000 over physical -8000..8000 x 10^-2 inch = 160 in: 400 counts per inch, exactly
    # 400 / 25.4 per mm (the kernel's hidinput_calc_abs_res would round this to 16)
    assert m.resolution == pytest.approx((400 / 25.4, 400 / 25.4))
    assert "400 dpi" in m.describe() and "5 buttons" in m.describe()


def test_trackball_report_gives_mm_wheel_pan_and_buttons():
    m = mouse(TRACKBALL)
    report = bytes([
        0x01,        # report ID 1
        0x18,        # buttons 4 (side) and 5 (extra)
        0x90, 0x01,  # X = 0x0190 = +400 counts: one inch to the right
        0xF0, 0xFF,  # Y = 0xFFF0 = -16 counts: up
        0x10,        # wheel +16: with multiplier 8, two detents away from the user
        0xFC,        # AC Pan -4: half a detent to the left
    ])
    events = m.feed(report, 2.0)
    motion, wheel, side, extra = events
    assert (motion.dx, motion.dy) == (400, -16)
    assert motion.dx_mm == pytest.approx(25.4) and motion.dy_mm == pytest.approx(-16 * 25.4 / 400)
    assert wheel == Wheel(2.0, DEV, vertical=2.0, horizontal=-0.5)
    assert (side.name, extra.name) == ("side", "extra") and side.pressed and extra.pressed


def test_trackball_hires_feature_report_hand_packed():
    m = mouse(TRACKBALL)
    # feature report 2: byte 0 = 0x02; byte 1 bits 0-1 wheel multiplier = 1 (its logical maximum), bits 2-3 pan
    # multiplier = 1, bits 4-7 padding -> 0b0101
    assert m.output_reports() == [OutputReport(ReportKind.FEATURE, 2, bytes([0x02, 0x05]))]
    assert "wheel x1/8" in m.describe() and "AC pan x1/8" in m.describe()


def test_hires_off_keeps_whole_detents_and_sends_nothing():
    m = mouse(TRACKBALL, hires=False)
    assert m.output_reports() == []
    (wheel,) = m.feed(bytes([0x01, 0x00, 0, 0, 0, 0, 0x03, 0x00]), 0.0)
    assert wheel.vertical == 3.0 and wheel.horizontal == 0.0


def test_multiplier_outside_a_logical_collection_applies_to_the_wheel():
    m = mouse(WHEEL_NO_LOGICAL)
    assert m.output_reports() == [OutputReport(ReportKind.FEATURE, 2, bytes([0x02, 0x03]))]
    (wheel,) = m.feed(bytes([0x01, 0x00, 0xFE]), 0.0)  # wheel -2 quarter detents
    assert wheel.vertical == -0.5


@pytest.mark.parametrize(("limits", "value", "expected"), [
    ((0, 1, 1, 8), 1, 8),        # Microsoft's "Enhanced Wheel Support" sample: 1 -> 8 counts per detent
    ((0, 1, 1, 8), 0, 1),
    ((0, 15, 1, 16), 15, 16),
    ((0, 15, 1, 16), 7, 1),      # C integer division: 7 / 15 is 0, so 0 * 15 + 1
    ((0, 1, 1, 1000), 1, 1),     # beyond 255: the kernel warns and uses 1
    ((0, 1, 0, 0), 1, 1),        # 0 would divide by zero: 1
    ((3, 3, 1, 8), 3, 1),        # empty logical range: 1
    ((0, 1, -4, -1), 0, -4),     # negative multipliers are allowed down to -255
])
def test_effective_multiplier_is_the_kernels(limits, value, expected):
    assert effective_multiplier(multiplier_field(*limits), value) == expected


# -- absolute pointers -----------------------------------------------------------------------------------

def test_absolute_pointer_gives_normalised_axes_on_change():
    m = mouse(ABSOLUTE_POINTER)
    assert m.absolute
    # X = 0x4000 = 16384, Y = 0x7FFF = 32767
    events = m.feed(bytes([0x00, 0x00, 0x40, 0xFF, 0x7F]), 0.5)
    assert events == [Axis(0.5, DEV, axis="x", value=16384 / 32767, raw=16384),
                      Axis(0.5, DEV, axis="y", value=1.0, raw=32767)]
    assert m.feed(bytes([0x01, 0x00, 0x40, 0xFF, 0x7F]), 0.6) == [Button(0.6, DEV, button=1, pressed=True,
                                                                          name="left")]


# -- acceleration ----------------------------------------------------------------------------------------

def test_flat_profile_is_one_plus_speed():
    assert FlatProfile(0.5)(123.0) == 1.5
    assert FlatProfile(-1.0)(0.0) == 0.005  # libinput's floor
    m = mouse(acceleration="flat", speed=0.5)
    (motion,) = m.feed(bytes([0x00, 0x0A, 0x00]), 0.0)
    assert (motion.dx, motion.dy) == (15, 0)


def test_adaptive_profile_values_from_libinput():
    # pointer_accel_profile_linear at speed 0: threshold 0.4, incline 1.1, max 2.0 (units: 1000-dpi counts / ms)
    p = AdaptiveProfile(0.0)
    assert p(0.0) == pytest.approx(0.3)
    assert p(0.05) == pytest.approx(0.8)    # 10 v + 0.3 below 0.07
    assert p(0.2) == 1.0                    # the plateau
    assert p(0.5) == pytest.approx(1.11)    # 1.1 (0.5 - 0.4) + 1
    assert p(10.0) == 2.0                   # capped
    fast = AdaptiveProfile(1.0)             # threshold max(0.2, 0.15), incline 1.85, max 3.5
    assert (fast.threshold, fast.incline, fast.max_factor) == (0.2, 1.85, 3.5)
    assert fast(1.0) == pytest.approx(1.85 * 0.8 + 1)


@given(st.floats(-1, 1), st.floats(0, 50), st.floats(0, 50))
def test_adaptive_profile_is_monotonic_and_capped(speed, v1, v2):
    p = AdaptiveProfile(speed)
    low, high = sorted((v1, v2))
    assert p(low) <= p(high) <= p.max_factor


def test_adaptive_acceleration_by_simpsons_rule():
    m = mouse(acceleration="adaptive", dpi=1000)
    # first motion: no previous report, so the velocity is over libinput's 1 s timeout: 20 counts / 1000 ms = 0.02;
    # factor (f(0.02) + f(0) + 4 f(0.01)) / 6 = (0.5 + 0.3 + 4 * 0.4) / 6 = 0.4 -> 20 * 0.4 = 8 counts
    (first,) = m.feed(bytes([0x00, 0x14, 0x00]), 10.0)
    assert first.dx == 8 and first.dx_mm == pytest.approx(20 * 25.4 / 1000)
    # 1 ms later another 20 counts: 20 counts/ms, capped at 2; (2 + f(0.02) + 4 * 2) / 6 = (2 + 0.5 + 8) / 6 = 1.75
    (second,) = m.feed(bytes([0x00, 0x14, 0x00]), 10.001)
    assert second.dx == 35 and second.dx_mm == pytest.approx(20 * 25.4 / 1000)


def test_acceleration_carries_fractions():
    m = mouse(acceleration="flat", speed=-0.5)  # factor 0.5
    moved = [m.feed(bytes([0x00, 0x01, 0x00]), t / 100)[0].dx for t in range(10)]
    assert sum(moved) == 5


# -- options and bad input ---------------------------------------------------------------------------------

@pytest.mark.parametrize(("options", "name"), [
    ({"acceleration": "turbo"}, "acceleration"),
    ({"acceleration": "flat", "speed": 2}, "speed"),
    ({"speed": 0.5}, "speed"),
    ({"dpi": 0}, "dpi"),
    ({"dpi": "lots"}, "dpi"),
    ({"hires": "maybe"}, "hires"),
    ({"dpii": 400}, "dpii"),
])
def test_bad_options_name_the_option(options, name):
    with pytest.raises(ConfigError, match=name):
        mouse(**options)


def test_text_options_as_in_a_url():
    m = mouse(TRACKBALL, dpi="1600", acceleration="adaptive", speed="-0.25", hires="false")
    assert m.resolution == (1600 / 25.4, 1600 / 25.4) and m.output_reports() == []


def test_bad_reports_raise_parse_error():
    m = mouse(TRACKBALL)
    with pytest.raises(ParseError):
        m.feed(b"", 0.0)
    with pytest.raises(ParseError):
        m.feed(bytes([0x07, 0, 0, 0, 0, 0, 0, 0]), 0.0)  # no input report 7


# -- against the simulated trackball (its firmware packs reports itself, from the descriptor's documentation) --

def run_trackball(script: str, *, send_features: bool, **options: object) -> tuple[float, float, float, float]:
    """Feed a simulated trackball's reports for one script to Mouse; the summed mm and detents."""
    from pixelpen.clock import SimulatedClock
    from pixelpen.sim.base import create_simulator

    sim = create_simulator("trackball", clock=SimulatedClock(), script=script)
    m = Mouse(parse_descriptor(sim.report_descriptor), DEV, **options)
    if send_features:
        for report in m.output_reports():
            sim.send_feature(report.data)
    x = y = wheel = pan = 0.0
    while (t := sim.next_event_time()) is not None and t < 60.0:
        sim.advance_to(t)
        for report in sim.take_reports():
            for event in m.feed(report, t):
                if isinstance(event, Motion):
                    x, y = x + event.dx_mm, y + event.dy_mm
                elif isinstance(event, Wheel):
                    wheel, pan = wheel + event.vertical, pan + event.horizontal
    return x, y, wheel, pan


def test_simulated_trackball_line_in_mm():
    # the "line" script moves the hand from 20 % to 80 % of the model's 100 mm wide surface: 60 mm right;
    # the firmware sends it as 400-cpi counts, so the sum is within one count (25.4 / 400 mm) of it
    x, y, _, _ = run_trackball("line", send_features=True)
    assert x == pytest.approx(60.0, abs=25.4 / 400) and y == pytest.approx(0.0, abs=25.4 / 400)


def test_simulated_trackball_scroll_after_the_multiplier_feature():
    _, _, wheel, pan = run_trackball("scroll", send_features=True)
    assert (wheel, pan) == (5.0, 5.0)
    # without the feature report the device stays at multiplier 1; hires=false reads whole detents
    _, _, wheel, pan = run_trackball("scroll", send_features=False, hires=False)
    assert (wheel, pan) == (5.0, 5.0)


def test_button_names_follow_the_kernels_btn_codes():
    ecodes = pytest.importorskip("evdev.ecodes")
    # hid-input.c: Button page usage u of a mouse is BTN_MOUSE + (u - 1), BTN_MOUSE being BTN_LEFT
    for usage, name in BUTTON_NAMES.items():
        kernel = ecodes.BTN[ecodes.BTN_LEFT + usage - 1]
        kernel = kernel[0] if isinstance(kernel, (tuple, list)) else kernel
        assert kernel == "BTN_" + name.upper()

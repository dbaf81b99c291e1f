"""Joystick and game pad semantics: hand-packed reports, calibration, dead zones, curves, hats, SDL indexing."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.devices.hid import parse_descriptor
from pixelpen.devices.hid.events import Axis, Button, Hat
from pixelpen.devices.hid.fields import MAIN_NULL_STATE, MAIN_VARIABLE, Field, ReportKind
from pixelpen.devices.hid.joystick import (
    AXES,
    HAT_DIRECTIONS,
    AxisCalibration,
    Joystick,
    ResponseCurve,
    axial_deadzone,
    hat_direction,
    radial_deadzone,
)
from pixelpen.drivers.identity import DeviceId
from pixelpen.errors import ConfigError
from pixelpen.sim.hid.descriptors import GAMEPAD, JOYSTICK

DEV = DeviceId("usb", 0x044F, 0xB10A, name="Test stick")

# A stick with two hats, each its own Input item, and a second X axis in a field of its own (a twin-stick
# arcade panel).  Input report, unnumbered, 4 bytes: byte 0 X int8, byte 1 Y int8, byte 2 bits 0-3 hat 0,
# bits 4-7 hat 1 (0..7, 45° each, 8..15 centred), byte 3 the second X int8.
TWIN = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x04,        # Usage (Joystick)
    0xA1, 0x01,        # Collection (Application)
    0x09, 0x30,        #   Usage (X)
    0x09, 0x31,        #   Usage (Y)
    0x15, 0x81,        #   Logical Minimum (-127)
    0x25, 0x7F,        #   Logical Maximum (127)
    0x75, 0x08,        #   Report Size (8)
    0x95, 0x02,        #   Report Count (2)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): X, Y
    0x09, 0x39,        #   Usage (Hat Switch)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x07,        #   Logical Maximum (7)
    0x75, 0x04,        #   Report Size (4)
    0x95, 0x01,        #   Report Count (1)
    0x81, 0x42,        #   Input (Data, Variable, Absolute, Null State): hat 0
    0x09, 0x39,        #   Usage (Hat Switch)
    0x81, 0x42,        #   Input (Data, Variable, Absolute, Null State): hat 1
    0x09, 0x30,        #   Usage (X)
    0x15, 0x81,        #   Logical Minimum (-127)
    0x25, 0x7F,        #   Logical Maximum (127)
    0x75, 0x08,        #   Report Size (8)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): the second X
    0xC0,              # End Collection
])

# The Sony PS4 line of SDL_GameControllerDB (copied literally): sticks a0 a1 / a2 a5, triggers a3 a4, face
# buttons b0-b3 -- the SDL indices of GAMEPAD (X, Y, Z, Rx, Ry, Rz by ABS code; buttons by usage).
PS4_0111 = ("030000004c050000c405000011010000,PS4 Controller,a:b1,b:b2,back:b8,dpdown:h0.4,dpleft:h0.8,"
            "dpright:h0.2,dpup:h0.1,guide:b12,leftshoulder:b4,leftstick:b10,lefttrigger:a3,leftx:a0,lefty:a1,"
            "rightshoulder:b5,rightstick:b11,righttrigger:a4,rightx:a2,righty:a5,start:b9,touchpad:b13,x:b0,"
            "y:b3,platform:Linux,")

KERNEL_HAT_TO_AXIS = [(0, 0), (0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1)]
"""hid-input.c hid_hat_to_axis: hat_dir 0 (centre), 1 (up) .. 8 clockwise, as ABS_HAT0X/Y (y down)."""


def stick(data: bytes = JOYSTICK, **options: object) -> Joystick:
    return Joystick(parse_descriptor(data), DEV, **options)


def hat_field(lmin: int, lmax: int, pmin: int = 0, pmax: int = 0, unit: int = 0) -> Field:
    return Field(ReportKind.INPUT, None, 1, (0x00010039,), 0, 4, 1, lmin, lmax, pmin, pmax, unit, 0,
                 MAIN_VARIABLE | MAIN_NULL_STATE)


def kernel_hat_dir(value: int, lmin: int, lmax: int) -> int:
    """hidinput_hid_event: (value - hat_min) * 8 / (hat_max - hat_min + 1) + 1 in C, 0 outside 0..8."""
    numerator = (value - lmin) * 8
    denominator = lmax - lmin + 1
    quotient = abs(numerator) // denominator * (1 if numerator >= 0 else -1)
    direction = quotient + 1
    return direction if 0 <= direction <= 8 else 0


# -- the HID 1.11 E.10-style joystick --------------------------------------------------------------------------

def test_first_report_sends_every_axis_and_pressed_buttons():
    j = stick()
    # byte 0 0x7F: X +127 (right); byte 1 0x81: Y -127 (forward); byte 2 0x81: throttle -127 (its minimum);
    # byte 3: hat 8 = null state (centred), bits 4-7 = 0b0001: button 1
    events = j.feed(bytes([0x7F, 0x81, 0x81, 0x18]), 3.0)
    assert events == [Axis(3.0, DEV, axis="x", value=1.0, raw=127),
                      Axis(3.0, DEV, axis="y", value=-1.0, raw=-127),
                      Axis(3.0, DEV, axis="throttle", value=0.0, raw=-127),
                      Button(3.0, DEV, button=1, pressed=True, name="button1")]
    assert j.feed(bytes([0x7F, 0x81, 0x81, 0x18]), 3.1) == []  # nothing changed


def test_hat_positions_clockwise_from_north():
    j = stick()
    j.feed(bytes([0, 0, 0x81, 0x08]), 0.0)
    names = []
    for position in range(8):
        (hat,) = j.feed(bytes([0, 0, 0x81, position]), 0.1 * position)
        names.append((hat.direction, hat.dx, hat.dy))
    assert names == [("up", 0, 1), ("up-right", 1, 1), ("right", 1, 0), ("down-right", 1, -1),
                     ("down", 0, -1), ("down-left", -1, -1), ("left", -1, 0), ("up-left", -1, 1)]
    assert j.feed(bytes([0, 0, 0x81, 0x0F]), 1.0) == [Hat(1.0, DEV, hat=0, direction="centre", dx=0, dy=0)]
    assert j.state().hats == (0,)


def test_hat_directions_match_the_kernels_table():
    for direction, (name, dx, dy, mask) in enumerate(HAT_DIRECTIONS):
        assert (dx, -dy) == KERNEL_HAT_TO_AXIS[direction], name
        # SDL's hat mask: 1 up, 2 right, 4 down, 8 left
        assert mask == (1 if dy > 0 else 0) | (2 if dx > 0 else 0) | (4 if dy < 0 else 0) | (8 if dx < 0 else 0)


def test_hat_vectors_are_unit_steps_at_45_degrees():
    assert HAT_DIRECTIONS[0][1:3] == (0, 0)
    for k, (_, dx, dy, _) in enumerate(HAT_DIRECTIONS[1:]):
        assert max(abs(dx), abs(dy)) == 1
        assert math.degrees(math.atan2(dx, dy)) % 360 == pytest.approx(45 * k)
        assert (dx / math.hypot(dx, dy)) ** 2 + (dy / math.hypot(dx, dy)) ** 2 == pytest.approx(1.0)


@given(st.integers(-3, 3), st.sampled_from([3, 7]), st.integers(-20, 20))
def test_hat_direction_agrees_with_the_kernel_without_units(lmin, span, offset):
    field = hat_field(lmin, lmin + span)
    assert hat_direction(field, lmin + offset) == kernel_hat_dir(lmin + offset, lmin, lmin + span)


@given(st.integers(-4, 12))
def test_hat_direction_from_degrees_agrees_with_the_kernel(value):
    # 1..8 with Physical 0..315 degrees (English Rotation 0x14), as many pads have it: 0 and 9.. are centred
    assert hat_direction(hat_field(1, 8, 0, 315, 0x14), value) == kernel_hat_dir(value, 1, 8)
    # a 4-way hat 0..3 over 0..270 degrees
    if 0 <= value <= 3:
        assert hat_direction(hat_field(0, 3, 0, 270, 0x14), value) == 2 * value + 1


# -- separate fields with the same usage ----------------------------------------------------------------------

def test_repeated_usages_in_separate_fields_read_their_own_values():
    j = stick(TWIN)
    # X +127, Y 0; byte 2: hat 0 = 0 (up) in bits 0-3, hat 1 = 4 (down) in bits 4-7; second X -127
    events = j.feed(bytes([0x7F, 0x00, 0x40, 0x81]), 0.0)
    assert [e for e in events if isinstance(e, Hat)] == [Hat(0.0, DEV, hat=0, direction="up", dx=0, dy=1),
                                                         Hat(0.0, DEV, hat=1, direction="down", dx=0, dy=-1)]
    assert j.values()["x"] == 1.0 and j.values()["x2"] == -1.0
    # SDL's Linux backend sees no second X (the kernel drops a usage whose ABS code is taken)
    assert [a.name for a in j.axes] == ["x", "x2", "y"]
    assert j.state().axes == (1.0, 0.0) and j.state().hats == (1, 4)


# -- calibration, dead zones, curves ------------------------------------------------------------------------

def test_calibration_option_recentres_and_rescales():
    j = stick(GAMEPAD, calibration={"x": (0, 128, 255), "rx": (0, 255)})
    # report 1: sticks 0x80 0x80 0x80 0x80, hat 8 (centred), no buttons, triggers 0xFF and 0x00
    events = {e.axis: e for e in j.feed(bytes([0x01, 0x80, 0x80, 0x80, 0x80, 0x08, 0, 0, 0xFF, 0x00]), 0.0)
              if isinstance(e, Axis)}
    assert events["x"].value == 0.0                                   # 128 is the calibrated centre
    assert events["y"].value == pytest.approx((128 - 127.5) / 127.5)  # the logical range's middle
    assert events["rx"].value == 1.0                                  # a 0..1 axis now
    assert events["ry"].value == -1.0                                 # Ry: -1..1 over 0..255 by default


def test_calibration_clamps_outside_its_range():
    cal = AxisCalibration(10, 30, 20)
    assert (cal.normalise(0), cal.normalise(10), cal.normalise(25), cal.normalise(99)) == (-1.0, -1.0, 0.5, 1.0)
    assert AxisCalibration(0, 100).normalise(150) == 1.0


def test_radial_deadzone_on_the_stick_pairs():
    j = stick(GAMEPAD, radial_deadzone=0.2, sticks="x:y,z:rz", calibration="x=0:128:255,y=0:128:255")
    # left stick slightly off centre on both axes: magnitude below 0.2 -> both 0
    values = {e.axis: e.value for e in j.feed(bytes([0x01, 0x90, 0x90, 0x80, 0x80, 0x08, 0, 0, 0, 0]), 0.0)
              if isinstance(e, Axis)}
    assert values["x"] == 0.0 and values["y"] == 0.0
    assert [pair for pair in j.sticks] == [("x", "y"), ("z", "rz")]


def test_axial_deadzone_and_power_curve_in_order():
    j = stick(deadzone=0.5, curve="power", exponent=2)
    # X +127 -> 1.0 -> dead zone keeps 1.0 -> curve 1.0; Y -64 -> -0.504 -> (0.504 - 0.5) / 0.5 -> squared
    values = {e.axis: e.value for e in j.feed(bytes([0x7F, 0xC0, 0x81, 0x08]), 0.0) if isinstance(e, Axis)}
    assert values["x"] == 1.0
    assert values["y"] == pytest.approx(-(((64 / 127) - 0.5) / 0.5) ** 2)


@given(st.floats(-1, 1), st.floats(-1, 1), st.floats(0, 0.99))
def test_axial_deadzone_monotonic_odd_and_full_range(a, b, zone):
    low, high = sorted((a, b))
    assert axial_deadzone(low, zone) <= axial_deadzone(high, zone)
    assert axial_deadzone(-a, zone) == -axial_deadzone(a, zone)
    assert abs(axial_deadzone(a, zone)) <= 1.0
    assert axial_deadzone(1.0, zone) == pytest.approx(1.0) and axial_deadzone(-1.0, zone) == pytest.approx(-1.0)
    if abs(a) <= zone:
        assert axial_deadzone(a, zone) == 0.0


@given(st.floats(-1, 1), st.floats(-1, 1), st.floats(0.001, 0.99), st.floats(0.01, 1))
def test_radial_deadzone_keeps_direction_and_unit_disc(x, y, zone, scale):
    ox, oy = radial_deadzone(x, y, zone)
    assert math.hypot(ox, oy) <= 1.0 + 1e-12
    assert ox * y - oy * x == pytest.approx(0.0, abs=1e-9)  # same line
    assert ox * x + oy * y >= 0.0                           # same side
    sx, sy = radial_deadzone(x * scale, y * scale, zone)    # a smaller deflection never gives more
    assert math.hypot(sx, sy) <= math.hypot(ox, oy) + 1e-12
    if math.hypot(x, y) <= zone:
        assert (ox, oy) == (0.0, 0.0)


def test_radial_deadzone_zero_is_off():
    assert radial_deadzone(1.0, 1.0, 0.0) == (1.0, 1.0)
    assert radial_deadzone(0.6, 0.8, 0.5) == pytest.approx((0.6, 0.8))  # full deflection stays full


@given(st.sampled_from(["linear", "power", "cubic"]), st.floats(0.1, 5), st.floats(0, 1), st.floats(-1, 1),
       st.floats(-1, 1))
def test_curves_keep_ends_are_odd_and_monotonic(kind, exponent, weight, a, b):
    curve = ResponseCurve(kind, exponent, weight)
    assert curve(0.0) == 0.0
    assert curve(1.0) == pytest.approx(1.0) and curve(-1.0) == pytest.approx(-1.0)
    assert curve(-a) == -curve(a)
    low, high = sorted((a, b))
    assert curve(low) <= curve(high) + 1e-12


def test_cubic_curve_value():
    assert ResponseCurve("cubic", cubic_weight=0.5)(0.5) == pytest.approx(0.5 * 0.5 + 0.5 * 0.125)


# -- game pad with a GameControllerDB mapping ------------------------------------------------------------------

def test_gamepad_with_the_ps4_mapping_gives_named_events():
    j = stick(GAMEPAD, mapping=PS4_0111)
    report = bytes([
        0x01,        # report ID 1
        0xFF,        # left X: full right
        0x00,        # left Y: full up
        0x80, 0x80,  # right stick (Z, Rz) near the centre
        0x20,        # bits 0-3 hat 0 (up); bits 4-7 buttons 1-4 = 0b0010: button 2 (SDL b1: "a")
        0x00, 0x00,  # buttons 5-14 released
        0xFF,        # Rx (SDL a3, lefttrigger) fully pressed
        0x00,        # Ry (SDL a4, righttrigger) at rest
    ])
    events = j.feed(report, 5.0)
    axes = {e.axis: e.value for e in events if isinstance(e, Axis)}
    buttons = {e.name: (e.pressed, e.button) for e in events if isinstance(e, Button)}
    assert axes["leftx"] == 1.0 and axes["lefty"] == -1.0
    assert axes["lefttrigger"] == 1.0 and axes["righttrigger"] == 0.0
    # edges only: the pressed buttons, no "released" for buttons never pressed
    assert buttons == {"a": (True, 1), "dpup": (True, 12)}
    # the d-pad released: only dpup changes
    released = j.feed(report[:5] + bytes([0x28]) + report[6:], 5.1)
    assert [(e.name, e.pressed) for e in released if isinstance(e, Button)] == [("dpup", False)]
    assert "mapped as 'PS4 Controller'" in j.describe()


def test_sdl_indices_of_the_gamepad():
    j = stick(GAMEPAD)
    assert [a.name for a in j.sdl_axes] == ["x", "y", "z", "rx", "ry", "rz"]
    assert j.buttons == tuple(range(1, 15)) and j.hat_count == 1
    # before any report: centred axes at 0, nothing pressed, hat centred
    assert j.state().axes == (0.0,) * 6 and not any(j.state().buttons) and j.state().hats == (0,)


# -- options ---------------------------------------------------------------------------------------------------

@pytest.mark.parametrize(("options", "name"), [
    ({"calibration": "x=1:0"}, "calibration"),
    ({"calibration": "x=a:b:c"}, "calibration"),
    ({"calibration": "q=0:1"}, "calibration"),
    ({"deadzone": 1}, "deadzone"),
    ({"radial_deadzone": -0.1}, "radial_deadzone"),
    ({"sticks": "x"}, "sticks"),
    ({"curve": "wobbly"}, "curve"),
    ({"exponent": 3}, "exponent"),
    ({"curve": "power", "exponent": 0}, "exponent"),
    ({"cubic_weight": 0.3}, "cubic_weight"),
    ({"mapping": "nonsense"}, "mapping"),
    ({"dead_zone": 0.1}, "dead_zone"),
])
def test_bad_options_name_the_option(options, name):
    with pytest.raises(ConfigError, match=name):
        stick(**options)


def test_too_many_buttons_are_refused():
    many = bytes([0x05, 0x01, 0x09, 0x04, 0xA1, 0x01,   # Generic Desktop Joystick application
                  0x05, 0x09, 0x19, 0x01, 0x2A, 0x00, 0x08,  # Button 1 .. Button 2048
                  0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x96, 0x00, 0x08,  # 0..1, 1 bit, Report Count 2048
                  0x81, 0x02, 0xC0])
    with pytest.raises(ConfigError, match="buttons"):
        stick(many)


def test_axis_codes_are_the_kernels_abs_codes():
    ecodes = pytest.importorskip("evdev.ecodes")
    # hid-input.c hidinput_configure_usage: Generic Desktop X..Wheel map to ABS_X + (usage & 0xf); Simulation
    # Controls Rudder, Throttle, Accelerator, Brake, Steering to ABS_RUDDER, ABS_THROTTLE, ABS_GAS, ABS_BRAKE, ABS_WHEEL
    kernel = {0x00010030: "ABS_X", 0x00010031: "ABS_Y", 0x00010032: "ABS_Z", 0x00010033: "ABS_RX",
              0x00010034: "ABS_RY", 0x00010035: "ABS_RZ", 0x00010036: "ABS_THROTTLE", 0x00010037: "ABS_RUDDER",
              0x00010038: "ABS_WHEEL", 0x000200BA: "ABS_RUDDER", 0x000200BB: "ABS_THROTTLE",
              0x000200C4: "ABS_GAS", 0x000200C5: "ABS_BRAKE", 0x000200C8: "ABS_WHEEL"}
    assert set(AXES) == set(kernel)
    for usage, (name, code, _) in AXES.items():
        assert code == ecodes.ecodes[kernel[usage]], name


def test_simulated_gamepad_sweep_through_the_ps4_mapping():
    # the simulated game pad's firmware packs its reports itself; its "sweep" script moves every axis end to
    # end and presses every button in turn
    from pixelpen.clock import SimulatedClock
    from pixelpen.sim.base import create_simulator

    sim = create_simulator("gamepad", clock=SimulatedClock(), script="sweep")
    j = Joystick(parse_descriptor(sim.report_descriptor), DEV, mapping=PS4_0111)
    low: dict[str, float] = {}
    high: dict[str, float] = {}
    pressed = set()
    while (t := sim.next_event_time()) is not None and t < 10.0:
        sim.advance_to(t)
        for report in sim.take_reports():
            for event in j.feed(report, t):
                if isinstance(event, Axis):
                    low[event.axis] = min(low.get(event.axis, 1.0), event.value)
                    high[event.axis] = max(high.get(event.axis, -1.0), event.value)
                elif event.pressed:
                    pressed.add(event.name)
    assert low["lefttrigger"] == 0.0 and high["lefttrigger"] == 1.0
    assert low["righttrigger"] == 0.0 and high["righttrigger"] == 1.0
    for stick_axis in ("leftx", "lefty", "rightx", "righty"):
        assert low[stick_axis] == -1.0 and high[stick_axis] >= 0.99
    assert {"a", "b", "x", "y", "start", "back", "guide", "dpup", "dpdown", "dpleft", "dpright"} <= pressed

"""Choosing device semantics: dispatch by application usage, composites routed by report ID, options, errors."""

from __future__ import annotations

import warnings

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.devices.hid import parse_descriptor
from pixelpen.devices.hid.codec import ShortReportWarning
from pixelpen.devices.hid.events import Button, InputEvent, Key, Motion
from pixelpen.devices.hid.fields import ReportDescriptor, ReportKind
from pixelpen.devices.hid.joystick import Joystick
from pixelpen.devices.hid.mouse import Mouse
from pixelpen.devices.hid.semantics import (
    SEMANTICS,
    CompositeSemantics,
    OutputReport,
    Semantics,
    application_descriptor,
    output_reports_of,
    read_semantics_options,
    semantics_class,
    semantics_for,
)
from pixelpen.drivers.identity import DeviceId
from pixelpen.errors import ConfigError, ParseError
from pixelpen.options import OptionSpec, boolean, text
from pixelpen.sim.hid.descriptors import BOOT_MOUSE, GAMEPAD, JOYSTICK, TRACKBALL

DEV = DeviceId("usb", 0x046D, 0xC52B, name="Unifying receiver")

# A wireless receiver: a keyboard (report 1), a mouse (report 2) and a vendor-defined application (report 3).
KEYBOARD_MOUSE_VENDOR = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x06,        # Usage (Keyboard)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x01,        #   Report ID (1)
    0x05, 0x07,        #   Usage Page (Keyboard/Keypad)
    0x19, 0xE0,        #   Usage Minimum (Left Control)
    0x29, 0xE7,        #   Usage Maximum (Right GUI)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x01,        #   Logical Maximum (1)
    0x75, 0x01,        #   Report Size (1)
    0x95, 0x08,        #   Report Count (8)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): byte 1, the modifiers
    0x95, 0x01,        #   Report Count (1)
    0x75, 0x08,        #   Report Size (8)
    0x81, 0x01,        #   Input (Constant): byte 2, reserved
    0x95, 0x06,        #   Report Count (6)
    0x75, 0x08,        #   Report Size (8)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x65,        #   Logical Maximum (101)
    0x19, 0x00,        #   Usage Minimum (0)
    0x29, 0x65,        #   Usage Maximum (101)
    0x81, 0x00,        #   Input (Data, Array): bytes 3-8, the keys down
    0xC0,              # End Collection
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x02,        # Usage (Mouse)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x02,        #   Report ID (2)
    0x09, 0x01,        #   Usage (Pointer)
    0xA1, 0x00,        #   Collection (Physical)
    0x05, 0x09,        #     Usage Page (Button)
    0x19, 0x01,        #     Usage Minimum (1)
    0x29, 0x03,        #     Usage Maximum (3)
    0x15, 0x00,        #     Logical Minimum (0)
    0x25, 0x01,        #     Logical Maximum (1)
    0x75, 0x01,        #     Report Size (1)
    0x95, 0x03,        #     Report Count (3)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): byte 1 bits 0-2
    0x95, 0x05,        #     Report Count (5)
    0x81, 0x01,        #     Input (Constant): byte 1 bits 3-7
    0x05, 0x01,        #     Usage Page (Generic Desktop)
    0x09, 0x30,        #     Usage (X)
    0x09, 0x31,        #     Usage (Y)
    0x15, 0x81,        #     Logical Minimum (-127)
    0x25, 0x7F,        #     Logical Maximum (127)
    0x75, 0x08,        #     Report Size (8)
    0x95, 0x02,        #     Report Count (2)
    0x81, 0x06,        #     Input (Data, Variable, Relative): bytes 2-3, X and Y
    0xC0,              #   End Collection
    0xC0,              # End Collection
    0x06, 0x00, 0xFF,  # Usage Page (Vendor Defined 0xFF00)
    0x09, 0x01,        # Usage (0x01)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x03,        #   Report ID (3)
    0x09, 0x02,        #   Usage (0x02)
    0x15, 0x00,        #   Logical Minimum (0)
    0x26, 0xFF, 0x00,  #   Logical Maximum (255)
    0x75, 0x08,        #   Report Size (8)
    0x95, 0x04,        #   Report Count (4)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): bytes 1-4, vendor data
    0xC0,              # End Collection
])

# A 3D mouse (Multi-axis Controller, Generic Desktop 0x08): six 16-bit axes.
MULTI_AXIS = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x08,        # Usage (Multi-axis Controller)
    0xA1, 0x01,        # Collection (Application)
    0x09, 0x30, 0x09, 0x31, 0x09, 0x32,  # Usage (X), (Y), (Z)
    0x09, 0x33, 0x09, 0x34, 0x09, 0x35,  # Usage (Rx), (Ry), (Rz)
    0x16, 0xA2, 0xFE,  #   Logical Minimum (-350)
    0x26, 0x5E, 0x01,  #   Logical Maximum (350)
    0x75, 0x10,        #   Report Size (16)
    0x95, 0x06,        #   Report Count (6)
    0x81, 0x02,        #   Input (Data, Variable, Absolute)
    0xC0,              # End Collection
])

VENDOR_ONLY = bytes([0x06, 0x00, 0xFF, 0x09, 0x01, 0xA1, 0x01, 0x15, 0x00, 0x25, 0x01, 0x75, 0x08, 0x95, 0x01,
                     0x81, 0x02, 0xC0])  # Vendor page 0xFF00 application 0x01 with one byte of data


def test_dispatch_by_application_usage():
    assert isinstance(semantics_for(parse_descriptor(BOOT_MOUSE), DEV), Mouse)
    assert isinstance(semantics_for(parse_descriptor(TRACKBALL), DEV), Mouse)
    assert isinstance(semantics_for(parse_descriptor(JOYSTICK), DEV), Joystick)
    assert isinstance(semantics_for(parse_descriptor(GAMEPAD), DEV), Joystick)
    three_d = semantics_for(parse_descriptor(MULTI_AXIS), DEV)
    assert isinstance(three_d, Joystick) and [a.name for a in three_d.axes] == ["x", "y", "z", "rx", "ry", "rz"]


def test_pointer_application_is_a_mouse():
    pointer = bytearray(BOOT_MOUSE)
    assert pointer[2:4] == bytes([0x09, 0x02])
    pointer[3] = 0x01  # Usage (Pointer) for the application
    assert isinstance(semantics_for(parse_descriptor(bytes(pointer)), DEV), Mouse)


def test_every_table_entry_names_a_semantics_class():
    for usage in SEMANTICS:
        cls = semantics_class(usage)
        assert callable(getattr(cls, "feed", None)) and callable(getattr(cls, "describe", None)), hex(usage)
        assert all(isinstance(spec, OptionSpec) for spec in cls.OPTIONS)


def test_unknown_application_is_refused_with_its_usage():
    with pytest.raises(ConfigError, match="0xff000001"):
        semantics_for(parse_descriptor(VENDOR_ONLY), DEV)
    with pytest.raises(ConfigError, match="no top-level collection"):
        semantics_for(ReportDescriptor(b"", [], ()), DEV)


def test_options_reach_the_class_and_bad_ones_name_the_option():
    m = semantics_for(parse_descriptor(BOOT_MOUSE), DEV, dpi="800")
    assert isinstance(m, Mouse) and m.resolution[0] == pytest.approx(800 / 25.4)
    with pytest.raises(ConfigError, match="dpx"):
        semantics_for(parse_descriptor(BOOT_MOUSE), DEV, dpx=800)
    with pytest.raises(ConfigError, match="deadzone"):
        semantics_for(parse_descriptor(JOYSTICK), DEV, deadzone=2)


# -- composites ----------------------------------------------------------------------------------------------

def composite(**options: object) -> CompositeSemantics:
    pytest.importorskip("pixelpen.devices.hid.keyboard")
    sem = semantics_for(parse_descriptor(KEYBOARD_MOUSE_VENDOR), DEV, **options)
    assert isinstance(sem, CompositeSemantics)
    return sem


def test_composite_routes_each_report_to_its_application():
    sem = composite()
    assert [type(p).__name__ for p in sem.parts] == ["Keyboard", "Mouse"]
    assert sem.unsupported == (0xFF000001,)
    # report 2: ID byte, button 1, X +5, Y -5 (0xFB)
    assert sem.feed(bytes([0x02, 0x01, 0x05, 0xFB]), 1.0) == [
        Motion(1.0, DEV, dx=5, dy=-5), Button(1.0, DEV, button=1, pressed=True, name="left")]
    # report 1: ID byte, Left Shift (bit 1), reserved, key 0x04 ("a") in the first slot
    keys = sem.feed(bytes([0x01, 0x02, 0x00, 0x04, 0, 0, 0, 0, 0]), 1.1)
    assert keys and all(isinstance(k, Key) for k in keys)
    assert any(k.usage == 0x04 and k.pressed for k in keys)
    # the vendor application's report and an undeclared report ID give nothing
    assert sem.feed(bytes([0x03, 1, 2, 3, 4]), 1.2) == []
    assert sem.feed(bytes([0x09, 0, 0, 0]), 1.3) == []
    assert "ignored applications 0xff000001" in sem.describe()


def test_composite_empty_report_is_a_parse_error():
    with pytest.raises(ParseError):
        composite().feed(b"", 0.0)


def test_composite_options_go_to_the_parts_that_declare_them():
    sem = composite(dpi=400, layout="us")
    mouse = next(p for p in sem.parts if isinstance(p, Mouse))
    assert mouse.resolution[0] == pytest.approx(400 / 25.4)
    with pytest.raises(ConfigError, match="dpx"):
        composite(dpx=400)
    with pytest.raises(ConfigError, match="dpi"):
        composite(dpi=-1)


def test_application_descriptor_keeps_only_its_fields_and_offsets():
    whole = parse_descriptor(KEYBOARD_MOUSE_VENDOR)
    mouse_app = next(c for c in whole.collections if c.parent is None and c.usage == 0x00010002)
    part = application_descriptor(whole, mouse_app)
    assert list(part.input_reports) == [2]
    assert [f.bit_offset for f in part.input_reports[2] if not f.is_constant] == [
        f.bit_offset for f in whole.input_reports[2] if not f.is_constant]
    assert part.decode(bytes([0x02, 0x04, 0x01, 0xFF])) == whole.decode(bytes([0x02, 0x04, 0x01, 0xFF]))


def test_composite_of_unknown_applications_only_is_refused():
    two_vendor = VENDOR_ONLY[:5] + bytes([0x85, 0x01]) + VENDOR_ONLY[5:] + VENDOR_ONLY[:5] + bytes(
        [0x85, 0x02]) + VENDOR_ONLY[5:]
    with pytest.raises(ConfigError, match="no device semantics"):
        CompositeSemantics(parse_descriptor(two_vendor), DEV)


# -- output reports and option text ---------------------------------------------------------------------------

def test_output_reports_of():
    assert output_reports_of(semantics_for(parse_descriptor(TRACKBALL), DEV)) == [
        OutputReport(ReportKind.FEATURE, 2, bytes([0x02, 0x05]))]

    class Plain:
        def feed(self, report: bytes, time: float) -> list:
            return []

        def describe(self) -> str:
            return "plain"

    assert isinstance(Plain(), Semantics) and output_reports_of(Plain()) == []


def test_python_values_become_url_text():
    specs = (OptionSpec("calibration", text, "", ""), OptionSpec("flag", boolean, False, ""),
             OptionSpec("pair", text, "", ""))
    values = read_semantics_options(specs, {"calibration": {"x": (0, 512, 1023), "y": [1, 2]}, "flag": True,
                                            "pair": ("x", "y")}, "here")
    assert values["calibration"] == "x=0:512:1023,y=1:2"
    assert values["flag"] is True and values["pair"] == "x:y"
    with pytest.raises(ConfigError, match=r"here.*flag"):
        read_semantics_options(specs, {"flag": "perhaps"}, "here")


# -- any bytes: events or a ParseError, never another exception ----------------------------------------------

@pytest.mark.parametrize("data", [BOOT_MOUSE, TRACKBALL, JOYSTICK, GAMEPAD, MULTI_AXIS, KEYBOARD_MOUSE_VENDOR],
                         ids=["boot_mouse", "trackball", "joystick", "gamepad", "multi_axis", "composite"])
@settings(max_examples=60, deadline=None)
@given(reports=st.lists(st.tuples(st.binary(max_size=24), st.floats(-1e6, 1e6)), max_size=8))
def test_random_reports_give_events_or_parse_errors(data, reports):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ShortReportWarning)
        sem = semantics_for(parse_descriptor(data), DEV, acceleration="adaptive") if data in (
            BOOT_MOUSE, TRACKBALL) else semantics_for(parse_descriptor(data), DEV)
        for report, time in reports:  # times in any order: a replay may jump back
            try:
                events = sem.feed(report, time)
            except ParseError:
                continue
            assert all(isinstance(e, InputEvent) and e.device == DEV for e in events)

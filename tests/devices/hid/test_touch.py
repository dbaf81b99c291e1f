"""Touch semantics: multi-touch descriptors after Microsoft's samples, written byte by byte; frames packed by hand."""

from __future__ import annotations

import struct
import warnings

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.devices.hid.codec import ShortReportWarning
from pixelpen.devices.hid.descriptor import parse_descriptor
from pixelpen.devices.hid.events import Button, Contact, DeviceId, TouchFrame
from pixelpen.devices.hid.fields import ReportKind
from pixelpen.devices.hid.semantics import CompositeSemantics, application_descriptor, output_reports_of, semantics_for
from pixelpen.devices.hid.touch import MAX_CONTACTS, DeviceConfiguration, TouchScreen
from pixelpen.errors import ConfigError, ParseError

DEVICE = DeviceId("i2c", 0x04F3, 0x2A1C, name="test touch")


def finger(contact_id_max: int = 0x3F) -> list[int]:
    """One Finger logical collection: 6 bytes of report (tip/confidence, contact ID, X, Y)."""
    return [
        0x09, 0x22,        #   Usage (Finger)
        0xA1, 0x02,        #   Collection (Logical)
        0x09, 0x42,        #     Usage (Tip Switch)   bit 0
        0x09, 0x47,        #     Usage (Confidence)   bit 1
        0x15, 0x00,        #     Logical Minimum (0)
        0x25, 0x01,        #     Logical Maximum (1)
        0x75, 0x01,        #     Report Size (1)
        0x95, 0x02,        #     Report Count (2)
        0x81, 0x02,        #     Input (Data, Variable, Absolute)
        0x95, 0x06,        #     Report Count (6)
        0x81, 0x03,        #     Input (Constant): padding
        0x09, 0x51,        #     Usage (Contact Identifier)
        0x25, contact_id_max,  # Logical Maximum
        0x75, 0x08,        #     Report Size (8)
        0x95, 0x01,        #     Report Count (1)
        0x81, 0x02,        #     Input: the contact ID byte
        0xA4,              #     Push
        0x05, 0x01,        #     Usage Page (Generic Desktop)
        0x75, 0x10,        #     Report Size (16)
        0x55, 0x0E,        #     Unit Exponent (-2)
        0x65, 0x13,        #     Unit (English Linear: inch)
        0x35, 0x00,        #     Physical Minimum (0)
        0x46, 0xE8, 0x03,  #     Physical Maximum (1000): 10 in = 254 mm
        0x26, 0xEC, 0x09,  #     Logical Maximum (2540): 10 counts per mm
        0x09, 0x30,        #     Usage (X)
        0x81, 0x02,        #     Input: X
        0x46, 0x58, 0x02,  #     Physical Maximum (600): 6 in = 152.4 mm
        0x26, 0xF4, 0x05,  #     Logical Maximum (1524): 10 counts per mm
        0x09, 0x31,        #     Usage (Y)
        0x81, 0x02,        #     Input: Y
        0xB4,              #     Pop
        0xC0,              #   End Collection
    ]


# A touch screen after Microsoft's Windows 8 multi-touch sample: two fingers per report (hybrid beyond two),
# Contact Count Maximum in feature 2, Input Mode in feature 3 inside the same application.
TOUCH = bytes([
    0x05, 0x0D,        # Usage Page (Digitizers)
    0x09, 0x04,        # Usage (Touch Screen)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x01,        #   Report ID (1)
    *finger(),         #   bytes 1-6
    *finger(),         #   bytes 7-12
    0x05, 0x0D,        #   Usage Page (Digitizers)
    0x09, 0x54,        #   Usage (Contact Count)
    0x25, 0x7F,        #   Logical Maximum (127)
    0x95, 0x01,        #   Report Count (1)
    0x75, 0x08,        #   Report Size (8)
    0x81, 0x02,        #   Input: byte 13
    0x85, 0x02,        #   Report ID (2)
    0x09, 0x55,        #   Usage (Contact Count Maximum)
    0x25, 0x0A,        #   Logical Maximum (10)
    0xB1, 0x02,        #   Feature: byte 1
    0x85, 0x03,        #   Report ID (3)
    0x09, 0x52,        #   Usage (Input Mode)
    0x09, 0x53,        #   Usage (Device Index)
    0x95, 0x02,        #   Report Count (2)
    0xB1, 0x02,        #   Feature: Input Mode byte 1, Device Index byte 2
    0xC0,              # End Collection
])

# A precision touch pad after Microsoft's sample: one finger per report (hybrid), a button, and a separate
# Device Configuration application with Input Mode (feature 5) and the Surface/Button Switches (feature 6).
TOUCHPAD = bytes([
    0x05, 0x0D,        # Usage Page (Digitizers)
    0x09, 0x05,        # Usage (Touch Pad)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x04,        #   Report ID (4)
    *finger(),         #   bytes 1-6
    0x05, 0x0D,        #   Usage Page (Digitizers)
    0x09, 0x54,        #   Usage (Contact Count)
    0x25, 0x05,        #   Logical Maximum (5)
    0x75, 0x07,        #   Report Size (7)
    0x95, 0x01,        #   Report Count (1)
    0x81, 0x02,        #   Input: byte 7 bits 0-6
    0x05, 0x09,        #   Usage Page (Button)
    0x09, 0x01,        #   Usage (Button 1)
    0x25, 0x01,        #   Logical Maximum (1)
    0x75, 0x01,        #   Report Size (1)
    0x81, 0x02,        #   Input: byte 7 bit 7, the click
    0xC0,              # End Collection
    0x05, 0x0D,        # Usage Page (Digitizers)
    0x09, 0x0E,        # Usage (Device Configuration)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x05,        #   Report ID (5)
    0x09, 0x22,        #   Usage (Finger)
    0xA1, 0x02,        #   Collection (Logical)
    0x09, 0x52,        #     Usage (Input Mode)
    0x15, 0x00,        #     Logical Minimum (0)
    0x25, 0x0A,        #     Logical Maximum (10)
    0x75, 0x08,        #     Report Size (8)
    0x95, 0x01,        #     Report Count (1)
    0xB1, 0x02,        #     Feature: byte 1
    0xC0,              #   End Collection
    0x09, 0x22,        #   Usage (Finger)
    0xA1, 0x00,        #   Collection (Physical)
    0x85, 0x06,        #     Report ID (6)
    0x09, 0x57,        #     Usage (Surface Switch)  bit 0
    0x09, 0x58,        #     Usage (Button Switch)   bit 1
    0x75, 0x01,        #     Report Size (1)
    0x95, 0x02,        #     Report Count (2)
    0x25, 0x01,        #     Logical Maximum (1)
    0xB1, 0x02,        #     Feature
    0x95, 0x06,        #     Report Count (6)
    0xB1, 0x03,        #     Feature (Constant): padding
    0xC0,              #   End Collection
    0xC0,              # End Collection
])

# No Contact Count: every report is a frame of its two slots (no confidence, no units: a size option is needed).
NO_COUNT = bytes([
    0x05, 0x0D, 0x09, 0x04, 0xA1, 0x01,       # Usage Page (Digitizers), Usage (Touch Screen), Collection (Application)
    *[b for _ in range(2) for b in (
        0x09, 0x22, 0xA1, 0x02,               #   Usage (Finger), Collection (Logical)
        0x05, 0x0D, 0x09, 0x42, 0x15, 0x00, 0x25, 0x01, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02,  # tip: a byte
        0x09, 0x51, 0x81, 0x02,               #     Usage (Contact Identifier): a byte, 0..1
        0x05, 0x01, 0x09, 0x30, 0x09, 0x31, 0x26, 0xFF, 0x00, 0x95, 0x02, 0x81, 0x02,  # X, Y: a byte each
        0xC0)],
    0xC0,
])


# A single-touch (resistive) screen without Finger collections: tip and in range at the application level,
# X/Y in a Pointer physical collection, 0..4095 without units.
SINGLE = bytes([
    0x05, 0x0D, 0x09, 0x04, 0xA1, 0x01,  # Usage Page (Digitizers), Usage (Touch Screen), Collection (Application)
    0x09, 0x42, 0x09, 0x32, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x02, 0x81, 0x02,  # tip, in range: bits 0-1
    0x95, 0x06, 0x81, 0x03,              #   6 bits of padding
    0x05, 0x01, 0x09, 0x01, 0xA1, 0x00,  #   Usage Page (Generic Desktop), Usage (Pointer), Collection (Physical)
    0x09, 0x30, 0x09, 0x31, 0x26, 0xFF, 0x0F, 0x75, 0x10, 0x95, 0x02, 0x81, 0x02,  # X, Y 0..4095: bytes 1-4
    0xC0,
    0xC0,
])


def slot(tip: bool, contact_id: int, x: int, y: int, confidence: bool = True) -> bytes:
    return struct.pack("<BBHH", int(tip) | int(confidence) << 1, contact_id, x, y)


EMPTY = bytes(6)


def touch_report(first: bytes, second: bytes, count: int) -> bytes:
    return b"\x01" + first + second + bytes([count])


@pytest.fixture
def screen() -> TouchScreen:
    return TouchScreen(parse_descriptor(TOUCH), DEVICE)


def ids(frame: TouchFrame) -> list[tuple[int, bool]]:
    return [(c.contact_id, c.touching) for c in frame.contacts]


def test_semantics_for_picks_the_touch_screen_and_its_modes(screen):
    assert isinstance(semantics_for(parse_descriptor(TOUCH), DEVICE), TouchScreen)
    text = screen.describe()
    assert "touch screen, 254.0 x 152.4 mm" in text and "2 slots per report" in text and "up to 10 contacts" in text
    # Input Mode 2 (multi-input) in feature 3, the Device Index beside it left 0
    [mode] = screen.output_reports()
    assert (mode.kind, mode.report_id, mode.data) == (ReportKind.FEATURE, 3, bytes([3, 2, 0]))
    assert screen.feature_report_ids == (2,)
    [mouse] = TouchScreen(parse_descriptor(TOUCH), DEVICE, input_mode="mouse").output_reports()
    assert mouse.data == bytes([3, 0, 0])


def test_parallel_frame_positions_by_hand(screen):
    [frame] = screen.feed(touch_report(slot(True, 5, 1270, 762), slot(True, 9, 2540, 0, confidence=False), 2), 1.5)
    assert frame.time == 1.5 and frame.device == DEVICE
    first, second = frame.contacts
    # 1270 counts at 10 per mm = 127 mm, half of 2540; 762 = 76.2 mm, half of 1524
    assert (first.contact_id, first.x, first.y) == (5, 0.5, 0.5)
    assert first.x_mm == pytest.approx(127.0) and first.y_mm == pytest.approx(76.2)
    assert first.touching and first.confidence
    assert (second.contact_id, second.x, second.y, second.x_mm, second.y_mm) == (9, 1.0, 0.0,
                                                                                  pytest.approx(254.0), 0.0)
    assert not second.confidence


def test_parallel_mode_ignores_slots_past_the_count(screen):
    [frame] = screen.feed(touch_report(slot(True, 3, 100, 100), slot(True, 60, 1, 1), 1), 0.0)
    assert ids(frame) == [(3, True)]


def test_hybrid_mode_assembles_a_frame_over_reports(screen):
    assert screen.feed(touch_report(slot(True, 1, 10, 10), slot(True, 2, 20, 20), 3), 0.0) == []
    [frame] = screen.feed(touch_report(slot(True, 3, 30, 30), slot(True, 50, 0, 0), 0), 0.001)
    assert ids(frame) == [(1, True), (2, True), (3, True)]  # the second report's second slot is past the count
    assert frame.time == 0.001
    assert {c.contact_id for c in screen.active} == {1, 2, 3}


def test_lifts_are_reported_once_and_not_seen_means_up(screen):
    screen.feed(touch_report(slot(True, 1, 10, 10), slot(True, 2, 20, 20), 2), 0.0)
    [frame] = screen.feed(touch_report(slot(False, 1, 11, 11), slot(True, 2, 21, 21), 2), 0.01)
    assert ids(frame) == [(1, False), (2, True)]
    assert frame.contacts[0].x_mm == pytest.approx(1.1)  # where it was lifted
    [frame] = screen.feed(touch_report(slot(False, 1, 11, 11), slot(True, 2, 22, 22), 2), 0.02)
    assert ids(frame) == [(2, True)]  # a second lift of contact 1 is not reported again
    [frame] = screen.feed(touch_report(slot(True, 7, 5, 5), EMPTY, 1), 0.03)
    assert ids(frame) == [(7, True), (2, False)]  # contact 2 missing from the frame: lifted
    assert frame.contacts[1].x_mm == pytest.approx(2.2)
    [frame] = screen.feed(touch_report(EMPTY, EMPTY, 0), 0.04)  # a count of 0 outside a frame: all lifted
    assert ids(frame) == [(7, False)]
    assert screen.feed(touch_report(EMPTY, EMPTY, 0), 0.05) == []  # nothing left to say
    assert screen.active == ()


def test_a_lost_report_closes_the_incomplete_frame(screen):
    assert screen.feed(touch_report(slot(True, 1, 10, 10), slot(True, 2, 20, 20), 4), 0.0) == []
    frames = screen.feed(touch_report(slot(True, 1, 12, 12), EMPTY, 1), 0.01)  # a new frame began
    assert [ids(f) for f in frames] == [[(1, True), (2, True)], [(1, True), (2, False)]]


def test_duplicate_ids_in_a_frame_keep_the_first(screen):
    [frame] = screen.feed(touch_report(slot(True, 4, 10, 10), slot(True, 4, 99, 99), 2), 0.0)
    assert [(c.contact_id, c.x_mm) for c in frame.contacts] == [(4, pytest.approx(1.0))]


def test_contact_count_maximum_caps_the_frames(screen):
    screen.feed_feature(bytes([2, 1]))  # the device tracks one contact
    assert screen.max_contacts == 1
    [frame] = screen.feed(touch_report(slot(True, 1, 10, 10), slot(True, 2, 20, 20), 2), 0.0)
    assert ids(frame) == [(1, True)]
    screen.feed_feature(bytes([2, 0]))  # 0 would mean no contacts at all: ignored
    assert screen.max_contacts == 1
    with pytest.raises(ParseError, match="feature report 9"):
        screen.feed_feature(bytes([9, 1]))


def test_touch_pad_in_a_composite_with_its_device_configuration():
    descriptor = parse_descriptor(TOUCHPAD)
    sem = semantics_for(descriptor, DEVICE)
    assert isinstance(sem, CompositeSemantics)
    [pad] = [p for p in sem.parts if isinstance(p, TouchScreen)]
    assert any(isinstance(p, DeviceConfiguration) for p in sem.parts)  # the SEMANTICS table routes it
    assert (5, bytes([5, 3])) in [(r.report_id, r.data) for r in output_reports_of(sem)]  # a precision touch pad
    assert pad.touchpad and pad.input_mode == 3 and "touch pad" in pad.describe() and "1 buttons" in pad.describe()
    # one finger per report, the count in the first: a two-finger frame over two reports, then the click
    assert sem.feed(bytes([4]) + slot(True, 1, 100, 200) + bytes([2]), 0.0) == []
    [frame] = sem.feed(bytes([4]) + slot(True, 2, 300, 400) + bytes([0]), 0.001)
    assert ids(frame) == [(1, True), (2, True)]
    frame_and_click = sem.feed(bytes([4]) + slot(True, 1, 100, 200) + bytes([0x80 | 1]), 0.002)
    assert isinstance(frame_and_click[0], TouchFrame)
    assert ids(frame_and_click[0]) == [(1, True), (2, False)]
    assert frame_and_click[1] == Button(0.002, DEVICE, button=1, pressed=True, name="left")
    # the Device Configuration application, on its own: Input Mode 3, Surface and Button Switch on
    config_app = next(c for c in descriptor.collections if c.parent is None and c.usage == 0x000D000E)
    config = DeviceConfiguration(application_descriptor(descriptor, config_app), DEVICE)  # switches: a touch pad
    assert [(r.report_id, r.data) for r in config.output_reports()] == [(5, bytes([5, 3])), (6, bytes([6, 0b11]))]
    assert config.feed(b"\x05\x03", 0.0) == [] and "input mode 3" in config.describe()
    multi = DeviceConfiguration(application_descriptor(descriptor, config_app), DEVICE, input_mode="multi")
    assert multi.output_reports()[0].data == bytes([5, 2])
    # a touch screen's configuration (Microsoft's sample: Input Mode and Device Index only) gets multi-input
    screen_config = bytes([0x05, 0x0D, 0x09, 0x0E, 0xA1, 0x01, 0x85, 0x07, 0x09, 0x52, 0x09, 0x53, 0x15, 0x00,
                           0x25, 0x0A, 0x75, 0x08, 0x95, 0x02, 0xB1, 0x02, 0xC0])
    assert DeviceConfiguration(parse_descriptor(screen_config), DEVICE).output_reports()[0].data == bytes([7, 2, 0])


def test_without_contact_count_every_report_is_a_frame():
    screen = TouchScreen(parse_descriptor(NO_COUNT), DEVICE, size="100x50")
    assert "no contact count" in screen.describe()
    [frame] = screen.feed(bytes([1, 0, 255, 0, 0, 1, 0, 0]), 0.0)  # slot 0 touching at (255, 0); slot 1 not
    assert ids(frame) == [(0, True)]
    assert (frame.contacts[0].x_mm, frame.contacts[0].y_mm) == (pytest.approx(100.0), 0.0)
    [frame] = screen.feed(bytes([0, 0, 255, 0, 1, 1, 51, 255]), 0.01)
    assert ids(frame) == [(0, False), (1, True)]
    assert frame.contacts[1].x_mm == pytest.approx(20.0) and frame.contacts[1].y_mm == pytest.approx(50.0)


def test_a_single_touch_screen_without_fingers_is_one_slot():
    screen = TouchScreen(parse_descriptor(SINGLE), DEVICE, size="100x60")
    assert "1 slots per report" in screen.describe()
    [frame] = screen.feed(struct.pack("<BHH", 0b11, 4095, 2048), 0.0)
    [contact] = frame.contacts
    assert (contact.contact_id, contact.touching, contact.x_mm) == (0, True, pytest.approx(100.0))
    assert contact.y_mm == pytest.approx(2048 / 4095 * 60.0)
    [frame] = screen.feed(struct.pack("<BHH", 0b10, 4095, 2048), 0.01)  # the tip lifts, still in range
    assert ids(frame) == [(0, False)]
    assert screen.feed(struct.pack("<BHH", 0b00, 0, 0), 0.02) == []


def test_options_and_descriptors_it_cannot_use():
    with pytest.raises(ConfigError, match="input_mode"):
        TouchScreen(parse_descriptor(TOUCH), DEVICE, input_mode="stylus")
    with pytest.raises(ConfigError, match="size"):
        TouchScreen(parse_descriptor(TOUCH), DEVICE, size="-1x5")
    no_fingers = bytes([0x05, 0x0D, 0x09, 0x04, 0xA1, 0x01, 0x09, 0x54, 0x15, 0x00, 0x25, 0x0A, 0x75, 0x08,
                        0x95, 0x01, 0x81, 0x02, 0xC0])
    with pytest.raises(ConfigError, match="no input report has a finger"):
        TouchScreen(parse_descriptor(no_fingers), DEVICE)


def test_bad_reports_give_clear_errors(screen):
    with pytest.raises(ParseError, match="report 7"):
        screen.feed(b"\x07" + bytes(13), 0.0)
    with pytest.raises(ParseError, match="empty"):
        screen.feed(b"", 0.0)
    with pytest.warns(ShortReportWarning):  # short: zero-padded as the kernel does, so the count reads 0
        assert screen.feed(b"\x01" + slot(True, 1, 10, 10), 0.0) == []  # a frame of nothing, nothing to lift
    screen.feed(touch_report(slot(True, 1, 10, 10), EMPTY, 1), 0.1)
    with pytest.warns(ShortReportWarning):
        [frame] = screen.feed(b"\x01" + slot(True, 1, 10, 10), 0.2)
    assert ids(frame) == [(1, False)]


@given(st.lists(st.binary(min_size=1, max_size=20), max_size=30))
def test_any_reports_give_bounded_frames_or_parse_errors(reports):
    screen = TouchScreen(parse_descriptor(TOUCH), DEVICE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ShortReportWarning)
        for data in reports:
            try:
                events = screen.feed(b"\x01" + data, 0.0)
            except ParseError:
                continue
            for e in events:
                assert isinstance(e, TouchFrame) and all(isinstance(c, Contact) for c in e.contacts)
                assert len({c.contact_id for c in e.contacts}) == len(e.contacts)
            assert len(screen.active) <= min(MAX_CONTACTS, screen.max_contacts)

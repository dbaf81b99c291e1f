"""The report-descriptor parser, rule by rule against the Linux kernel (drivers/hid/hid-core.c), on
descriptors from the HID 1.11 spec and Microsoft's samples with hand-computed layouts, and against
hid-tools' parser as an oracle for field layouts."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.devices.hid import parse_descriptor
from pixelpen.devices.hid.descriptor import MAX_COLLECTION_DEPTH, MAX_TOTAL_USAGES, MAX_USAGES
from pixelpen.devices.hid.fields import ReportDescriptor, ReportKind
from pixelpen.devices.hid.items import scan
from pixelpen.errors import ParseError
from pixelpen.sim.hid.descriptors import DESCRIPTORS

GD, BUTTON, KEYBOARD, LED, CONSUMER = 0x01, 0x09, 0x07, 0x08, 0x0C
X, Y, WHEEL = 0x00010030, 0x00010031, 0x00010038

APP = [0x05, 0x01, 0x09, 0x02, 0xA1, 0x01]   # Usage Page (GD), Usage (Mouse), Collection (Application)
END = [0xC0]


def parse(*parts: list[int], **kw: object):
    """Parse the concatenated byte lists."""
    return parse_descriptor(bytes(b for p in parts for b in p), **kw)


def one_field(*body: list[int], kind: ReportKind = ReportKind.INPUT, rid=None):
    """The single field with usages of a descriptor made of APP + body + END."""
    d = parse(APP, *body, END)
    fields = [f for f in d.layout(kind, rid).fields if f.usages]
    assert len(fields) == 1
    return fields[0]


def error_of(*parts: list[int], **kw: object) -> ParseError:
    with pytest.raises(ParseError) as err:
        parse(*parts, **kw)
    return err.value


# -- HID 1.11 Appendix B.1: boot keyboard ---------------------------------------------------------------------
BOOT_KEYBOARD = bytes([
    0x05, 0x01, 0x09, 0x06, 0xA1, 0x01,  # Usage Page (GD), Usage (Keyboard), Collection (Application)
    0x05, 0x07, 0x19, 0xE0, 0x29, 0xE7,  # Usage Page (Key Codes), Usage Minimum (224), Usage Maximum (231)
    0x15, 0x00, 0x25, 0x01,              # Logical Minimum (0), Logical Maximum (1)
    0x75, 0x01, 0x95, 0x08, 0x81, 0x02,  # Report Size (1), Report Count (8), Input (Data, Variable, Absolute)
    0x95, 0x01, 0x75, 0x08, 0x81, 0x01,  # Report Count (1), Report Size (8), Input (Constant): reserved byte
    0x95, 0x05, 0x75, 0x01,              # Report Count (5), Report Size (1)
    0x05, 0x08, 0x19, 0x01, 0x29, 0x05,  # Usage Page (LEDs), Usage Minimum (1), Usage Maximum (5)
    0x91, 0x02,                          # Output (Data, Variable, Absolute): LED report
    0x95, 0x01, 0x75, 0x03, 0x91, 0x01,  # Report Count (1), Report Size (3), Output (Constant): padding
    0x95, 0x06, 0x75, 0x08,              # Report Count (6), Report Size (8)
    0x15, 0x00, 0x25, 0x65,              # Logical Minimum (0), Logical Maximum (101)
    0x05, 0x07, 0x19, 0x00, 0x29, 0x65,  # Usage Page (Key Codes), Usage Minimum (0), Usage Maximum (101)
    0x81, 0x00,                          # Input (Data, Array): key arrays (6 bytes)
    0xC0,                                # End Collection
])

# -- HID 1.11 Appendix B.2: boot mouse ------------------------------------------------------------------------
BOOT_MOUSE = bytes([
    0x05, 0x01, 0x09, 0x02, 0xA1, 0x01,  # Usage Page (GD), Usage (Mouse), Collection (Application)
    0x09, 0x01, 0xA1, 0x00,              # Usage (Pointer), Collection (Physical)
    0x05, 0x09, 0x19, 0x01, 0x29, 0x03,  # Usage Page (Buttons), Usage Minimum (1), Usage Maximum (3)
    0x15, 0x00, 0x25, 0x01,              # Logical Minimum (0), Logical Maximum (1)
    0x95, 0x03, 0x75, 0x01, 0x81, 0x02,  # Report Count (3), Report Size (1), Input (Data, Variable, Absolute)
    0x95, 0x01, 0x75, 0x05, 0x81, 0x01,  # Report Count (1), Report Size (5), Input (Constant): 5 bit padding
    0x05, 0x01, 0x09, 0x30, 0x09, 0x31,  # Usage Page (GD), Usage (X), Usage (Y)
    0x15, 0x81, 0x25, 0x7F,              # Logical Minimum (-127), Logical Maximum (127)
    0x75, 0x08, 0x95, 0x02, 0x81, 0x06,  # Report Size (8), Report Count (2), Input (Data, Variable, Relative)
    0xC0, 0xC0,                          # End Collection, End Collection
])

# -- after Microsoft's "Enhanced Wheel Support in Windows" sample: wheel and AC Pan, each with a Resolution
# Multiplier in its own Logical collection, in Feature report 3 ------------------------------------------------
MS_WHEEL_MOUSE = bytes([
    0x05, 0x01, 0x09, 0x02, 0xA1, 0x01,              # Usage Page (GD), Usage (Mouse), Collection (Application)
    0x05, 0x01, 0x09, 0x02, 0xA1, 0x02,              #   Usage Page (GD), Usage (Mouse), Collection (Logical)
    0x85, 0x02, 0x09, 0x01, 0xA1, 0x00,              #     Report ID (2), Usage (Pointer), Collection (Physical)
    0x05, 0x09, 0x19, 0x01, 0x29, 0x05,              #       Usage Page (Button), Usage Min (1), Usage Max (5)
    0x95, 0x05, 0x75, 0x01, 0x15, 0x00, 0x25, 0x01,  #       Report Count (5), Size (1), Logical 0..1
    0x81, 0x02,                                      #       Input (Data, Var, Abs): bits 8..12
    0x95, 0x01, 0x75, 0x03, 0x81, 0x01,              #       Report Count (1), Size (3), Input (Const): 13..15
    0x05, 0x01, 0x09, 0x30, 0x09, 0x31,              #       Usage Page (GD), Usage (X), Usage (Y)
    0x95, 0x02, 0x75, 0x08, 0x15, 0x81, 0x25, 0x7F,  #       Report Count (2), Size (8), Logical -127..127
    0x81, 0x06,                                      #       Input (Data, Var, Rel): bits 16..31
    0xA1, 0x02,                                      #       Collection (Logical)
    0x85, 0x03, 0x09, 0x48, 0x95, 0x01, 0x75, 0x02,  #         Report ID (3), Usage (Resolution Multiplier)
    0x15, 0x00, 0x25, 0x01, 0x35, 0x01, 0x45, 0x04,  #         Logical 0..1, Physical 1..4
    0xB1, 0x02,                                      #         Feature (Data, Var, Abs): report 3 bits 8..9
    0x85, 0x02, 0x09, 0x38, 0x35, 0x00, 0x45, 0x00,  #         Report ID (2), Usage (Wheel), Physical 0..0
    0x95, 0x01, 0x75, 0x08, 0x15, 0x81, 0x25, 0x7F,  #         Report Count (1), Size (8), Logical -127..127
    0x81, 0x06,                                      #         Input (Data, Var, Rel): report 2 bits 32..39
    0xC0,                                            #       End Collection
    0xA1, 0x02,                                      #       Collection (Logical)
    0x85, 0x03, 0x09, 0x48, 0x95, 0x01, 0x75, 0x02,  #         Report ID (3), Usage (Resolution Multiplier)
    0x15, 0x00, 0x25, 0x01, 0x35, 0x01, 0x45, 0x04,  #         Logical 0..1, Physical 1..4
    0xB1, 0x02,                                      #         Feature (Data, Var, Abs): report 3 bits 10..11
    0x35, 0x00, 0x45, 0x00, 0x75, 0x04, 0xB1, 0x01,  #         Physical 0..0, Size (4), Feature (Const): 12..15
    0x85, 0x02, 0x05, 0x0C, 0x95, 0x01, 0x75, 0x08,  #         Report ID (2), Usage Page (Consumer), Count 1, Size 8
    0x15, 0x81, 0x25, 0x7F, 0x0A, 0x38, 0x02,        #         Logical -127..127, Usage (AC Pan, 2 bytes)
    0x81, 0x06,                                      #         Input (Data, Var, Rel): report 2 bits 40..47
    0xC0, 0xC0, 0xC0, 0xC0,                          #       End Collection x 4
])


def layout_of(d, kind=ReportKind.INPUT, rid=None):
    """(bit_offset, bit_size, count, usages) per field."""
    return [(f.bit_offset, f.bit_size, f.count, f.usages) for f in d.layout(kind, rid).fields]


def test_boot_keyboard_layout():
    d = parse_descriptor(BOOT_KEYBOARD)
    assert set(d.input_reports) == {None} and set(d.output_reports) == {None} and not d.feature_reports
    assert layout_of(d) == [
        (0, 1, 8, tuple(range(0x000700E0, 0x000700E8))),   # byte 0: the 8 modifier bits
        (8, 8, 1, ()),                                       # byte 1: reserved
        (16, 8, 6, tuple(range(0x00070000, 0x00070066))),   # bytes 2..7: 6 key slots, usages 0..101
    ]
    assert d.layout(ReportKind.INPUT, None).length == 8
    assert layout_of(d, ReportKind.OUTPUT) == [(0, 1, 5, tuple(range(0x00080001, 0x00080006))), (5, 3, 1, ())]
    assert d.layout(ReportKind.OUTPUT, None).length == 1
    keys = d.input_reports[None][2]
    assert keys.is_array and not keys.is_constant and (keys.logical_min, keys.logical_max) == (0, 101)
    assert d.input_reports[None][1].is_constant
    assert d.applications == (0x00010006,)


def test_boot_mouse_layout():
    d = parse_descriptor(BOOT_MOUSE)
    assert layout_of(d) == [(0, 1, 3, (0x00090001, 0x00090002, 0x00090003)), (3, 5, 1, ()), (8, 8, 2, (X, Y))]
    assert d.layout(ReportKind.INPUT, None).length == 3
    xy = d.input_reports[None][2]
    assert (xy.logical_min, xy.logical_max, xy.is_relative, xy.is_array) == (-127, 127, True, False)
    assert xy.usage_page == GD and d.input_reports[None][0].usage_page == BUTTON
    pointer = xy.collection
    assert pointer is not None and pointer.kind == 0 and pointer.usage == 0x00010001
    assert pointer.parent is not None and pointer.parent.usage == 0x00010002 and pointer.parent.kind == 1
    assert d.numbered is False


def test_microsoft_wheel_mouse_layout():
    d = parse_descriptor(MS_WHEEL_MOUSE)
    assert set(d.input_reports) == {2} and set(d.feature_reports) == {3}
    assert layout_of(d, rid=2) == [
        (8, 1, 5, tuple(range(0x00090001, 0x00090006))), (13, 3, 1, ()), (16, 8, 2, (X, Y)),
        (32, 8, 1, (WHEEL,)), (40, 8, 1, (0x000C0238,))]
    assert d.layout(ReportKind.INPUT, 2).length == 6
    assert layout_of(d, ReportKind.FEATURE, 3) == [
        (8, 2, 1, (0x00010048,)), (10, 2, 1, (0x00010048,)), (12, 4, 1, ())]
    assert d.layout(ReportKind.FEATURE, 3).length == 2
    multiplier = d.feature_reports[3][0]
    assert (multiplier.physical_min, multiplier.physical_max) == (1, 4)
    wheel = d.input_reports[2][3]
    assert wheel.collection is not None and wheel.collection.kind == 2  # its own Logical collection
    assert wheel.collection is multiplier.collection


# -- signedness -----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("items, lmin, lmax", [
    ([0x15, 0x00, 0x25, 0xFF], 0, 255),             # min >= 0: the maximum is unsigned
    ([0x15, 0x80, 0x25, 0xFF], -128, -1),           # min < 0: the maximum is signed (0xFF = -1)
    ([0x15, 0x00, 0x26, 0xFF, 0xFF], 0, 65535),
    ([0x16, 0x00, 0x80, 0x26, 0xFF, 0x7F], -32768, 32767),
    ([0x25, 0xFF, 0x15, 0x80], -128, 255),          # the maximum is read when it comes: min was 0 then
    ([0x15, 0x00, 0x27, 0xFF, 0xFF, 0xFF, 0xFF], 0, 0xFFFFFFFF),  # unsigned 32-bit stays unsigned
    ([0x17, 0x00, 0x00, 0x00, 0x80, 0x27, 0xFF, 0xFF, 0xFF, 0x7F], -2**31, 2**31 - 1),
])
def test_logical_maximum_is_signed_only_when_the_minimum_is_negative(items, lmin, lmax):
    f = one_field(items, [0x09, 0x30, 0x75, 0x20, 0x95, 0x01, 0x81, 0x02])
    assert (f.logical_min, f.logical_max) == (lmin, lmax)


@pytest.mark.parametrize("items, pmin, pmax", [
    ([0x35, 0x00, 0x45, 0xFF], 0, 255),
    ([0x35, 0x81, 0x45, 0xFF], -127, -1),
    ([0x36, 0xC0, 0xE0, 0x46, 0x40, 0x1F], -8000, 8000),
])
def test_physical_maximum_follows_the_same_rule(items, pmin, pmax):
    f = one_field([0x15, 0x00, 0x25, 0x01], items, [0x09, 0x30, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02])
    assert (f.physical_min, f.physical_max) == (pmin, pmax)


@pytest.mark.parametrize("limits", [
    [0x15, 0x0A, 0x25, 0x05],                 # 10..5
    [0x15, 0xFF, 0x25, 0xFB],                 # -1..-5 (signed, since the minimum is negative)
])
def test_inverted_logical_range_is_an_error_at_the_main_item(limits):
    body = [*limits, 0x09, 0x30, 0x75, 0x08, 0x95, 0x01]
    err = error_of(APP, body, [0x81, 0x02], END)
    assert err.offset == len(APP) + len(body) and "Logical Maximum" in err.message


# -- unit exponent: the spec's 4-bit nibble, or a signed byte -------------------------------------------------
@pytest.mark.parametrize("item, exponent", [
    ([0x55, 0x0E], -2), ([0x55, 0xFE], -2),   # nibble 0xE and byte 0xFE are both -2
    ([0x55, 0x0D], -3), ([0x55, 0xFD], -3),
    ([0x55, 0x07], 7), ([0x55, 0x08], -8),    # nibble 8 is -8
    ([0x55, 0x10], 16), ([0x55, 0xF0], -16),  # outside 0..15: the signed value itself
    ([0x56, 0x0D, 0x00], -3),                 # two bytes holding 13: still a nibble
    ([0x54], 0),
])
def test_unit_exponent_nibble_or_byte(item, exponent):
    f = one_field([0x15, 0x00, 0x25, 0x01, 0x65, 0x11], item, [0x09, 0x30, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02])
    assert f.unit_exponent == exponent and f.unit == 0x11


# -- Push / Pop ----------------------------------------------------------------------------------------------
def test_push_pop_restores_every_global_including_the_report_id():
    d = parse(APP, [
        0x85, 0x01,                                  # Report ID (1)
        0x05, 0x01, 0x15, 0x00, 0x25, 0x7F, 0x35, 0x00, 0x45, 0x0A,
        0x55, 0x0E, 0x65, 0x13, 0x75, 0x08, 0x95, 0x01,
        0xA4,                                        # Push
        0x85, 0x02, 0x05, 0x09, 0x15, 0x81, 0x25, 0x7F, 0x35, 0x81, 0x45, 0x7F,
        0x55, 0x03, 0x65, 0x14, 0x75, 0x10, 0x95, 0x02,
        0x09, 0x01, 0x81, 0x02,                      # Input in report 2 with all the new globals
        0xB4,                                        # Pop
        0x09, 0x30, 0x81, 0x02,                      # Input in report 1 with the pushed globals
    ], END)
    (b,) = d.input_reports[2]
    assert (b.usages, b.logical_min, b.logical_max, b.physical_min, b.physical_max, b.unit_exponent, b.unit,
            b.bit_size, b.count, b.bit_offset) == ((0x00090001,) * 2, -127, 127, -127, 127, 3, 0x14, 16, 2, 8)
    (x,) = d.input_reports[1]
    assert (x.usages, x.logical_min, x.logical_max, x.physical_min, x.physical_max, x.unit_exponent, x.unit,
            x.bit_size, x.count, x.bit_offset) == ((X,), 0, 127, 0, 10, -2, 0x13, 8, 1, 8)


def test_global_stack_overflow_names_the_fifth_push():
    err = error_of(APP, [0xA4] * 5, END)
    assert err.offset == len(APP) + 4 and "stack" in err.message


def test_global_stack_underflow_names_the_pop():
    err = error_of(APP, [0xA4, 0xB4, 0xB4], END)
    assert err.offset == len(APP) + 2 and "Pop" in err.message


# -- long items ----------------------------------------------------------------------------------------------
def test_long_item_is_skipped_with_a_warning_or_rejected():
    body = [0xFE, 0x02, 0x33, 0xAA, 0xBB]
    d = parse(APP, body, END)
    assert any("long item" in w and f"offset {len(APP)}" in w for w in d.warnings)
    err = error_of(APP, body, END, reject_long_items=True)
    assert err.offset == len(APP) and "long item" in err.message


# -- report IDs -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("item", [[0x85, 0x00], [0x86, 0x00, 0x01]])   # 0, and 256 in two bytes
def test_invalid_report_id_is_an_error(item):
    err = error_of(APP, item, END)
    assert err.offset == len(APP) and "Report ID" in err.message


def test_report_id_spaces_are_separate_and_bit_offsets_include_the_id_byte():
    d = parse(APP, [0x85, 0x01, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x03, 0x05, 0x09, 0x19, 0x01, 0x29, 0x03,
                    0x81, 0x02,                       # input 1: 3 bits at 8
                    0x95, 0x02, 0x05, 0x08, 0x19, 0x01, 0x29, 0x02, 0x91, 0x02,  # output 1: 2 bits at 8
                    0x75, 0x10, 0x95, 0x01, 0x05, 0x01, 0x09, 0x48, 0xB1, 0x02,  # feature 1: 16 bits at 8
                    0x85, 0x02, 0x75, 0x08, 0x09, 0x30, 0x81, 0x02],             # input 2: 8 bits at 8
              END)
    assert set(d.input_reports) == {1, 2} and set(d.output_reports) == {1} and set(d.feature_reports) == {1}
    assert layout_of(d, ReportKind.INPUT, 1) == [(8, 1, 3, (0x00090001, 0x00090002, 0x00090003))]
    assert layout_of(d, ReportKind.OUTPUT, 1) == [(8, 1, 2, (0x00080001, 0x00080002))]
    assert layout_of(d, ReportKind.FEATURE, 1) == [(8, 16, 1, (0x00010048,))]
    assert layout_of(d, ReportKind.INPUT, 2) == [(8, 8, 1, (X,))]
    assert [d.layout(k, 1).length for k in ReportKind] == [2, 2, 3]
    assert d.numbered


def test_items_without_a_report_id_in_a_numbered_space_are_report_0_with_an_id_byte():
    d = parse(APP, [0x15, 0x00, 0x25, 0x7F, 0x75, 0x08, 0x95, 0x01, 0x09, 0x30, 0x81, 0x02,  # no ID yet
                    0x85, 0x01, 0x09, 0x31, 0x81, 0x02], END)
    assert set(d.input_reports) == {0, 1}
    assert layout_of(d, rid=0) == [(8, 8, 1, (X,))] and d.layout(ReportKind.INPUT, 0).length == 2
    assert any("report 0" in w for w in d.warnings)


# -- usages ---------------------------------------------------------------------------------------------------
def test_usage_range_and_extended_usages():
    f = one_field([0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x05, 0x05, 0x09,
                   0x19, 0x01, 0x29, 0x02,                          # Button 1..2
                   0x0B, 0x38, 0x02, 0x0C, 0x00,                    # extended Usage 0x000C0238 (AC Pan)
                   0x1B, 0x30, 0x00, 0x01, 0x00, 0x2B, 0x31, 0x00, 0x01, 0x00,  # extended range GD X..Y
                   0x81, 0x02])
    assert f.usages == (0x00090001, 0x00090002, 0x000C0238, X, Y)


def test_usage_before_its_usage_page_takes_the_page_current_at_the_main_item():
    f = one_field([0x05, 0x00, 0x09, 0x30, 0x05, 0x01, 0x15, 0x00, 0x25, 0x01, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02])
    assert f.usages == (X,)


def test_usage_page_concatenation_stops_at_a_usage_that_has_the_current_page():
    # GD X, then Button page and Button 1: at the Input the last usage already has page 9, so X keeps page 1
    f = one_field([0x09, 0x30, 0x05, 0x09, 0x09, 0x01, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x02, 0x81, 0x02])
    assert f.usages == (X, 0x00090001)
    # Button 1 and 2, then GD page: no usage has page 1, so both are completed with it (kernel behaviour)
    f = one_field([0x05, 0x09, 0x09, 0x01, 0x09, 0x02, 0x05, 0x01, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x02,
                   0x81, 0x02])
    assert f.usages == (0x00010001, 0x00010002)
    # an extended usage is never completed
    f = one_field([0x0B, 0x01, 0x00, 0x09, 0x00, 0x05, 0x01, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01,
                   0x81, 0x02])
    assert f.usages == (0x00090001,)


def test_variable_repeats_the_last_usage_and_array_lists_what_its_range_can_name():
    var = one_field([0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x03, 0x09, 0x30, 0x81, 0x02])
    assert var.usages == (X, X, X) and not var.is_array
    arr = one_field([0x15, 0x01, 0x25, 0x03, 0x75, 0x02, 0x95, 0x02, 0x09, 0x30, 0x09, 0x31, 0x09, 0x32, 0x09, 0x33,
                     0x81, 0x00])
    assert arr.usages == (X, Y, 0x00010032) and arr.is_array and arr.count == 2   # indices 1..3 name 3 usages


def test_usage_range_over_the_kernel_limit_is_cut_with_a_warning():
    d = parse(APP, [0x15, 0x00, 0x26, 0xFF, 0x7F, 0x75, 0x10, 0x95, 0x01, 0x05, 0x0C,
                    0x19, 0x00, 0x2A, 0xFF, 0x7F, 0x81, 0x00], END)   # Usage 0..0x7FFF (the Holtek bug)
    (f,) = d.input_reports[None]
    assert len(f.usages) == MAX_USAGES and f.usages[-1] == 0x000C0000 + MAX_USAGES - 1
    assert any("Usage Maximum" in w for w in d.warnings)


def test_a_cut_range_from_a_4_byte_minimum_wraps_its_ids_under_the_current_page():
    # Usage Minimum 0x00020000 (4 bytes), Usage Maximum 5 (1 byte): the range wraps, is cut at MAX_USAGES, and
    # each 1-byte-maximum usage keeps only its low 16 bits under the Usage Page (hid_add_usage with size 1)
    d = parse(APP, [0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x96, 0x00, 0x30, 0x05, 0x0C,
                    0x1B, 0x00, 0x00, 0x02, 0x00, 0x29, 0x05, 0x81, 0x02], END)
    (f,) = d.input_reports[None]
    assert f.usages == tuple(0x000C0000 | (u & 0xFFFF) for u in range(0x20000, 0x20000 + MAX_USAGES))
    assert any("range cut" in w for w in d.warnings)


def test_delimiters_keep_only_the_first_alternative_set():
    f = one_field([0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x03,
                   0x09, 0x30,                          # before any delimiter: kept
                   0xA9, 0x01, 0x09, 0x31, 0x09, 0x32, 0xA9, 0x00,   # first set: kept
                   0xA9, 0x01, 0x09, 0x33, 0xA9, 0x00,  # second set: ignored
                   0x09, 0x34,                          # after the second set: ignored too (kernel)
                   0x81, 0x02])
    assert f.usages == (X, Y, 0x00010032)


@pytest.mark.parametrize("body, offset, words", [
    ([0xA9, 0x01, 0xA9, 0x01], 2, "nested"),
    ([0xA9, 0x00], 0, "delimiter"),
])
def test_bad_delimiters_are_errors(body, offset, words):
    err = error_of(APP, body, END)
    assert err.offset == len(APP) + offset and words in err.message


def test_unbalanced_delimiter_at_the_end_is_an_error():
    err = error_of(APP, END, [0xA9, 0x01])
    assert "delimiter" in err.message


# -- main items, padding, limits ---------------------------------------------------------------------------------
def test_padding_is_a_field_without_usages():
    d = parse_descriptor(BOOT_MOUSE)
    pad = d.input_reports[None][1]
    assert pad.usages == () and pad.is_constant and (pad.bit_offset, pad.bit_size, pad.count) == (3, 5, 1)


@pytest.mark.parametrize("body, offset, words", [
    ([0x75, 0xFF, 0x75, 0x01, 0x76, 0x01, 0x01], 4, "Report Size"),   # 257 bits
    ([0x96, 0x01, 0x30], 0, "Report Count"),                         # 12289
    ([0xC5, 0x00], 0, "global"),                                     # global tag 12 does not exist
])
def test_global_limits_are_errors_at_the_item(body, offset, words):
    err = error_of(APP, body, END)
    assert err.offset == len(APP) + offset and words in err.message


def test_report_longer_than_the_kernel_buffer_is_an_error():
    body = [0x09, 0x30, 0x15, 0x00, 0x25, 0x01, 0x76, 0x00, 0x01, 0x96, 0x00, 0x02]  # 256 bits x 512
    err = error_of(APP, body, [0x81, 0x02], END)
    assert err.offset == len(APP) + len(body) and "longer" in err.message


def test_collection_errors():
    assert error_of(APP, END, END).offset == len(APP) + 1                     # End Collection without one
    err = error_of(APP, [0xA1, 0x00])
    assert err.offset == len(APP) and "unbalanced" in err.message             # the innermost still open
    depth = MAX_COLLECTION_DEPTH
    parse([0xA1, 0x00] * depth, [0xC0] * depth)                               # at the limit: fine
    err = error_of([0xA1, 0x00] * (depth + 1), [0xC0] * (depth + 1))
    assert err.offset == 2 * depth


def test_the_usages_of_all_fields_are_bounded():
    """Each report 1..k holds ten arrays of Usage Minimum 0 .. Maximum 0x2FFF (12,288 usages, the kernel's limit
    per item): the fields of 4 KB could name 4.9 million usages; the first field past MAX_TOTAL_USAGES in all is
    an error at its own offset, and a descriptor at the limit parses."""
    head = [0x05, 0x07, 0x15, 0x00, 0x27, 0xFF, 0xFF, 0xFF, 0x7F, 0x75, 0x01]  # LMax 2**31 - 1, 1-bit elements
    field = [0x19, 0x00, 0x2A, 0xFF, 0x2F, 0x96, 0x00, 0x30, 0x81, 0x00]      # Usage 0..0x2FFF, Count 12288, Input
    full = MAX_TOTAL_USAGES // MAX_USAGES                                     # whole fields under the limit
    body = [b for rid in (1, 2) for b in [0x85, rid] + field * (full // 2 + 1)]
    err = error_of(APP, head, body, END)
    first_over = full + 1                                                     # its position, counted by hand
    per_report = 2 + len(field) * (full // 2 + 1)
    rid, k = divmod(first_over - 1, full // 2 + 1)
    assert err.offset == len(APP) + len(head) + rid * per_report + 2 + k * len(field) + 8  # at its Input item
    assert "usages in all" in err.message
    rest = MAX_TOTAL_USAGES - full * MAX_USAGES                               # fill to exactly the limit
    last = [0x19, 0x00, 0x2A, *(rest - 1).to_bytes(2, "little"), 0x96, *rest.to_bytes(2, "little"), 0x81, 0x00]
    d = parse(APP, head, [0x85, 1], field * (full // 2), [0x85, 2], field * (full - full // 2), last, END)
    assert sum(len(f.usages) for fields in d.input_reports.values() for f in fields) == MAX_TOTAL_USAGES


def test_fields_past_256_per_report_are_dropped_as_the_kernel_drops_them():
    d = parse(APP, [0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01], [0x09, 0x30, 0x81, 0x02] * 257, END)
    layout = d.layout(ReportKind.INPUT, None)
    assert len(layout.fields) == 256 and layout.length == 33      # the 257th field's bit still counts
    assert any("dropped" in w for w in d.warnings)


def test_trailing_zeros_reserved_items_and_size_limits():
    d = parse_descriptor(BOOT_MOUSE + bytes(3))
    assert d.warnings == () and len(d.input_reports[None]) == 3
    d = parse(APP, [0x0C], END)                                  # a reserved-type item: ignored, warned
    assert any("reserved" in w for w in d.warnings)
    assert error_of([]).offset == 0
    big = bytes(APP) + bytes([0x09, 0x30]) * 2100 + bytes(END)
    assert error_of(list(big)).offset == 4096


def test_errors_name_the_source():
    err = error_of([0x05], source="dev.bin")
    assert str(err).startswith("dev.bin, byte offset 0:")


# -- the item loop and the parser's own ReportDescriptor ------------------------------------------------------
def test_an_item_cut_short_at_the_end_is_reported_before_an_earlier_error():
    data = bytes([0x85, 0x00, 0x26, 0xFF])       # Report ID 0 (an error), then a Logical Maximum cut short
    assert (error_of(list(data)).offset, error_of(list(data[:2])).offset) == (2, 0)
    assert "cut short" in error_of(list(data)).message and "Report ID 0" in error_of(list(data[:2])).message
    long_cut = bytes(APP) + bytes([0xFE, 0x05, 0x10, 0xAA])   # a long item announcing 5 data bytes, 1 there
    for reject in (False, True):
        with pytest.raises(ParseError) as err:
            parse_descriptor(long_cut, reject_long_items=reject)
        assert err.value.offset == 6 and "cut short" in err.value.message


def test_items_after_a_long_item_are_read_from_its_end():
    d = parse(APP, [0xFE, 0x02, 0x33, 0xAA, 0xBB, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01, 0x09, 0x30,
                    0x81, 0x02], END)
    (f,) = d.input_reports[None]
    assert f.offset == len(APP) + 5 + 10 and f.usages == (X,) and d.layout(ReportKind.INPUT, None).length == 1


@st.composite
def mutants(draw):
    """A simulator's descriptor, cut, with a few bytes overwritten: items cut short, unknown and long items."""
    data = bytearray(draw(st.sampled_from(sorted(DESCRIPTORS.values()))))
    for _ in range(draw(st.integers(0, 3))):
        data[draw(st.integers(0, len(data) - 1))] = draw(st.integers(0, 255))
    return bytes(data[:draw(st.integers(0, len(data)))])


@settings(max_examples=300, deadline=None)
@given(st.one_of(mutants(), st.binary(max_size=48)))
def test_the_parser_cuts_items_where_scan_does(data):
    """A truncation error exactly when scan finds one (the same error); otherwise every field and collection
    starts at an item scan found, of its Main tag (an independent tokenizer checks the parser's own loop)."""
    try:
        items, expected = scan(data), None
    except ParseError as exc:
        items, expected = [], (exc.message, exc.offset)
    try:
        d = parse_descriptor(data)
    except ParseError as exc:
        assert expected is None or (exc.message, exc.offset) == expected
        return
    assert expected is None
    tags = {offset: prefix & 0xFC for offset, prefix, _ in items}
    main = {ReportKind.INPUT: 0x80, ReportKind.OUTPUT: 0x90, ReportKind.FEATURE: 0xB0}
    assert all(tags[f.offset] == main[f.kind] for r in d.layouts.values() for f in r.fields)
    assert all(tags[c.offset] == 0xA0 for c in d.collections)


REPORT_0 = bytes([*APP, 0x15, 0x00, 0x25, 0x7F, 0x75, 0x08, 0x95, 0x01, 0x09, 0x30, 0x81, 0x02,  # no Report ID yet
                  0x85, 0x01, 0x09, 0x31, 0x81, 0x02, *END])


@pytest.mark.parametrize("data", [*DESCRIPTORS.values(), MS_WHEEL_MOUSE, REPORT_0])
def test_the_parsers_descriptor_equals_one_made_from_its_layouts(data):
    parsed = parse_descriptor(data)
    spaces = (parsed.feature_reports, parsed.output_reports, parsed.input_reports)
    public = ReportDescriptor(data, list(parse_descriptor(data).layouts.values()), parsed.collections,
                              parsed.warnings)
    assert (public.feature_reports, public.output_reports, public.input_reports) == spaces
    assert public.layouts == parsed.layouts and list(public.layouts) == list(parsed.layouts)
    assert (public.numbered, public.numbered_kinds) == (parsed.numbered, parsed.numbered_kinds)
    assert all(f.report_id == rid and f.kind is kind for (kind, rid), r in parsed.layouts.items() for f in r.fields)


# -- hid-tools as an oracle -----------------------------------------------------------------------------------
hidtools_hid = pytest.importorskip("hidtools.hid")


def unrepeated(usages):
    """Usages without the repeats of the last one (the kernel repeats it up to Report Count; hid-tools not)."""
    out = list(usages)
    while len(out) > 1 and out[-1] == out[-2]:
        out.pop()
    return tuple(out)


def ours(d):
    """Per report (kind, ID or -1): its length and elements as hid-tools lists them."""
    out = {}
    for (kind, rid), layout in d.layouts.items():
        elements = []
        for f in layout.fields:
            if not f.usages:
                elements.append(("pad", f.bit_offset, f.bit_size * f.count))
            elif f.is_array:
                elements.append(("array", f.bit_offset, f.bit_size, f.count, unrepeated(f.usages), len(f.usages)))
            else:
                elements += [("var", f.bit_offset + i * f.bit_size, f.bit_size, u) for i, u in enumerate(f.usages)]
        out[kind.value, -1 if rid is None else rid] = (layout.length, elements)
    return out


def theirs(data, ours_map):
    """The same from hid-tools; arrays' usages cut to as many as ours (hid-tools ignores the logical range)
    and compared without repeats of the last."""
    rd = hidtools_hid.ReportDescriptor.from_bytes(list(data))
    out = {}
    for kind, reports in (("input", rd.input_reports), ("output", rd.output_reports),
                          ("feature", rd.feature_reports)):
        for rid, report in reports.items():
            elements = []
            for f in report.fields:
                if f.usages is not None:
                    ref = [e for e in ours_map.get((kind, rid), (0, []))[1] if e[0] == "array" and e[1] == f.start]
                    n = ref[0][5] if ref else len(f.usages)
                    elements.append(("array", f.start, f.size, f.count, unrepeated(f.usages[:n]), n))
                elif f.usage & 0xFFFF or f.type & 0x3 == 0x2:
                    elements.append(("var", f.start, f.size, f.usage))
                else:
                    elements.append(("pad", f.start, f.size))
            out[kind, rid] = ((report.bitsize + 7) // 8, elements)
    return out


@pytest.mark.parametrize("name", [n for n, d in DESCRIPTORS.items() if 0xA4 not in d])  # no Push: hid-tools
def test_simulator_descriptors_match_hid_tools(name):                                   # does not pop report IDs
    d = parse_descriptor(DESCRIPTORS[name])
    mine = ours(d)
    assert mine == theirs(DESCRIPTORS[name], mine)


def test_spec_descriptors_match_hid_tools():
    for data in (BOOT_KEYBOARD, BOOT_MOUSE, MS_WHEEL_MOUSE):
        mine = ours(parse_descriptor(data))
        assert mine == theirs(data, mine)


PAGES = st.sampled_from([0x01, 0x09, 0x0C, 0x0D])


@st.composite
def main_block(draw):
    """Items for one Input/Output/Feature main item: page, usages or a range, limits, size, count."""
    kind = draw(st.sampled_from([0x80, 0x90, 0xB0]))
    style = draw(st.sampled_from(["var", "array", "pad"]))
    size = draw(st.integers(1, 16))
    count = draw(st.integers(1, 6))
    items = [0x05, draw(PAGES), 0x75, size, 0x95, count]
    top = (1 << size) - 1
    if style == "pad":
        return [*items, kind | 1, 0x01]
    if draw(st.booleans()):
        first = draw(st.integers(1, 200))
        items += [0x19, first, 0x29, min(255, first + draw(st.integers(0, 8)))]
    else:
        for _ in range(draw(st.integers(1, 4))):
            items += [0x09, draw(st.integers(1, 255))]
    if style == "array":
        hi = min(top, draw(st.integers(1, 12)))
        return [*items, 0x15, 0x00, 0x26, hi & 0xFF, hi >> 8, kind | 1, 0x00]
    return [*items, 0x15, 0x00, 0x27, *top.to_bytes(4, "little"), kind | 1, 0x02]


@st.composite
def descriptors(draw):
    """An application collection of main blocks, all numbered (report IDs 1..3) or none."""
    numbered = draw(st.booleans())
    body = list(APP)
    for block in draw(st.lists(main_block(), min_size=1, max_size=8)):
        if numbered:
            body += [0x85, draw(st.integers(1, 3))]
        body += block
    return bytes(body + END)


@settings(max_examples=150, deadline=None)
@given(descriptors())
def test_generated_descriptors_match_hid_tools(data):
    mine = ours(parse_descriptor(data))
    assert mine == theirs(data, mine)

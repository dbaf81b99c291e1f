"""The compiled report codec: hand-decoded reports, the kernel's length and ID rules, batches, round trips."""

from __future__ import annotations

import random
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.devices.hid import codec, parse_descriptor
from pixelpen.devices.hid.codec import WHOLE_INT_BYTES, ReportDecoder, ReportEncoder, ShortReportWarning
from pixelpen.devices.hid.fields import (
    MAIN_CONSTANT,
    MAIN_NULL_STATE,
    MAIN_RELATIVE,
    MAIN_VARIABLE,
    Field,
    ReportKind,
    ReportLayout,
)
from pixelpen.errors import InvalidArgument, ParseError

IN = ReportKind.INPUT
VAR, REL = MAIN_VARIABLE, MAIN_VARIABLE | MAIN_RELATIVE
BUTTON, GD, KEYBOARD = 0x9, 0x1, 0x7


def field(offset: int, size: int, count: int, usages, lmin: int, lmax: int, flags: int = VAR,
          report_id: int | None = None) -> Field:
    usages = tuple(usages)
    return Field(IN, report_id, usages[0] >> 16 if usages else 0, usages, offset, size, count, lmin, lmax,
                 0, 0, 0, 0, flags)


def pad(offset: int, size: int) -> Field:
    return field(offset, size, 1, (), 0, 0, MAIN_CONSTANT)


def layout(*fields: Field, report_id: int | None = None) -> ReportLayout:
    end = max(f.bit_end for f in fields)
    return ReportLayout(IN, report_id, fields, -(-end // 8))


# HID 1.11 appendix B.2: the boot mouse, 3 buttons + 5 bits padding + X, Y (int8 -127..127); a wheel byte added
MOUSE = layout(field(0, 1, 3, [0x90001, 0x90002, 0x90003], 0, 1), pad(3, 5),
               field(8, 8, 3, [0x10030, 0x10031, 0x10038], -127, 127, REL))
# HID 1.11 appendix B.1: the boot keyboard, 8 modifier bits, a reserved byte, 6 key array bytes 0..101
KEYS = layout(field(0, 1, 8, range(0x700E0, 0x700E8), 0, 1), pad(8, 8),
              field(16, 8, 6, range(0x70000, 0x70066), 0, 101, 0))


def test_boot_mouse_report_decoded_by_hand():
    # 0x05 = buttons 1 and 3; 0xFF = X -1; 0x03 = Y +3; 0x81 = wheel -127
    assert ReportDecoder(MOUSE).decode(bytes([0x05, 0xFF, 0x03, 0x81])) == {
        (BUTTON, 1): 1, (BUTTON, 2): 0, (BUTTON, 3): 1, (GD, 0x30): -1, (GD, 0x31): 3, (GD, 0x38): -127}


def test_boot_keyboard_reports_pressed_keys_and_not_empty_slots():
    # 0x22 = Left Shift (E1) + Left Alt (E5); keys 'a' (04) and 'b' (05); empty slots 00 report nothing
    values = ReportDecoder(KEYS).decode(bytes([0x22, 0, 0x04, 0x05, 0, 0, 0, 0]))
    assert {k for k, v in values.items() if v} == {(KEYBOARD, 0xE1), (KEYBOARD, 0xE5), (KEYBOARD, 4), (KEYBOARD, 5)}
    assert values[(KEYBOARD, 4)] == 1 and (KEYBOARD, 0) not in values
    # ErrorRollOver (01) in every slot is reported as the usage it is; 0x66 is past Logical Maximum 101
    assert ReportDecoder(KEYS).decode(bytes([0, 0, 1, 1, 1, 1, 1, 0x66])) == {
        **{(KEYBOARD, u): 0 for u in range(0xE0, 0xE8)}, (KEYBOARD, 1): 1}


def test_values_gives_every_element_in_layout_order():
    assert ReportDecoder(MOUSE).values(bytes([0x02, 0x80, 0x7F, 0x00])) == [0, 1, 0, -128, 127, 0]
    assert ReportDecoder(KEYS).values(bytes([0x01, 0, 0x1E, 0, 0, 0, 0, 0]))[8:10] == [0x1E, 0]


@pytest.mark.parametrize(("size", "raw", "value"), [
    (4, 0x8, -8), (4, 0x7, 7), (4, 0xF, -1), (4, 0x0, 0), (8, 0x80, -128), (16, 0x8000, -32768),
    (16, 0x7FFF, 32767), (32, 0x80000000, -2**31), (32, 0xFFFFFFFF, -1), (1, 1, -1), (2, 0b10, -2),
])
def test_sign_extension_when_logical_minimum_is_negative(size, raw, value):
    f = field(0, size, 1, [0x10030], -1, 0)
    lay = layout(f, pad(size, (-size) % 8 or 8))
    report = raw.to_bytes(lay.length, "little")
    assert ReportDecoder(lay).decode(report)[(GD, 0x30)] == value
    assert ReportDecoder(lay).decode_batch(report * 3)[(GD, 0x30)].tolist() == [value] * 3


def test_logical_minimum_zero_reads_unsigned_whatever_the_maximum():
    # the kernel's rule: 15 00 25 FF is 0..255, so 0xFF is 255, and a 32-bit 0xFFFFFFFF is 4294967295
    lay = layout(field(0, 8, 1, [0x10030], 0, 255), field(8, 32, 1, [0x10031], 0, 2**32 - 1))
    report = bytes([0xFF, 0xFF, 0xFF, 0xFF, 0xFF])
    assert ReportDecoder(lay).decode(report) == {(GD, 0x30): 255, (GD, 0x31): 2**32 - 1}
    assert ReportDecoder(lay).decode_batch(report)[(GD, 0x31)].tolist() == [2**32 - 1]


def test_fields_crossing_byte_boundaries():
    # 4 bits padding, X 12 bits (bits 4..15), Y 12 bits signed (16..27), 4 bits padding: the tablet packing
    lay = layout(pad(0, 4), field(4, 12, 1, [0x10030], 0, 4095), field(16, 12, 1, [0x10031], -2048, 2047), pad(28, 4))
    x, y = 0xABC, -0x123
    word = x << 4 | (y & 0xFFF) << 16
    report = word.to_bytes(4, "little")
    assert report == bytes([0xC0, 0xAB, 0xDD, 0x0E])  # by hand: 0x0EDDABC0 little-endian
    assert ReportDecoder(lay).decode(report) == {(GD, 0x30): x, (GD, 0x31): y}


def test_32_bit_and_wide_fields_at_odd_offsets():
    lay = layout(pad(0, 3), field(3, 32, 1, [0xD005B], 0, 2**32 - 1), field(35, 61, 1, [0xFF000001], -1, 0),
                 field(96, 64, 1, [0xFF000002], 0, -1), pad(160, 8))
    serial, wide, top = 0xDEADBEEF, -(2**60) + 12345, 2**64 - 2
    word = serial << 3 | (wide & (2**61 - 1)) << 35 | top << 96
    report = word.to_bytes(lay.length, "little")
    dec = ReportDecoder(lay)
    assert dec.decode(report) == {(0xD, 0x5B): serial, (0xFF00, 1): wide, (0xFF00, 2): top}
    batch = dec.decode_batch(report * 2)
    assert batch[(0xD, 0x5B)].tolist() == [serial] * 2 and batch[(0xFF00, 1)].tolist() == [wide] * 2
    assert batch[(0xFF00, 2)].dtype == np.uint64 and batch[(0xFF00, 2)].tolist() == [top] * 2


def test_an_element_wider_than_64_bits():
    lay = layout(pad(0, 4), field(4, 100, 1, [0xFF000003], 0, 1), pad(104, 8))
    value = (1 << 99) | 0x123456789ABCDEF
    report = (value << 4).to_bytes(lay.length, "little")
    dec = ReportDecoder(lay)
    assert dec.decode(report)[(0xFF00, 3)] == value
    column = dec.decode_batch(report)[(0xFF00, 3)]  # its bytes, little-endian
    assert column.shape == (1, 13) and int.from_bytes(column[0].tobytes(), "little") == value


def test_arrays_with_a_logical_minimum_other_than_zero():
    # an array of 2 elements, values 1..3 report buttons 1..3; 0 and 4..7 are outside the range: nothing
    lay = layout(field(0, 3, 2, [0x90001, 0x90002, 0x90003], 1, 3, 0), pad(6, 2))
    dec = ReportDecoder(lay)
    assert dec.decode(bytes([2 | 3 << 3])) == {(BUTTON, 2): 1, (BUTTON, 3): 1}
    assert dec.decode(bytes([0 | 4 << 3])) == {}
    assert dec.decode(bytes([1 | 1 << 3])) == {(BUTTON, 1): 1}
    # a signed array: -2..0 report usages 1..3
    lay = layout(field(0, 4, 2, [0xFF000001, 0xFF000002, 0xFF000003], -2, 0, 0))
    assert ReportDecoder(lay).decode(bytes([0xE | 0x0 << 4])) == {(0xFF00, 1): 1, (0xFF00, 3): 1}
    assert ReportDecoder(lay).decode(bytes([0x1 | 0x7 << 4])) == {}


def test_a_wide_array_without_a_table():
    lay = layout(field(0, 16, 2, range(0xC0001, 0xC0400), 1, 0x3FF, 0))
    dec = ReportDecoder(lay)
    assert dec.decode(bytes([0xE9, 0x00, 0x00, 0x04])) == {(0xC, 0xE9): 1}  # 0x0400 is past the maximum
    assert dec.decode_batch(bytes([0xE9, 0x00, 0x00, 0x04]))[(0xC, 0xE9)].tolist() == [True]


def test_null_state_values_are_given_as_read():
    # a hat switch 0..7 (4 bits) with the Null State bit: 8..15 means "centred"; the value comes as read
    hat = field(0, 4, 1, [0x10039], 0, 7, VAR | MAIN_NULL_STATE)
    lay = layout(hat, pad(4, 4))
    assert hat.has_null_state
    assert ReportDecoder(lay).decode(bytes([0x0F])) == {(GD, 0x39): 15}
    assert ReportDecoder(lay).decode(bytes([0x03])) == {(GD, 0x39): 3}


def test_a_repeated_usage_gives_a_list():
    # Report Count 3 with one usage: the usage repeats (HID 1.11 6.2.2.8); a second field repeats it again
    lay = layout(field(0, 8, 3, [0xFF000001], 0, 255), field(24, 8, 1, [0xFF000001], 0, 255))
    dec = ReportDecoder(lay)
    assert dec.decode(bytes([1, 2, 3, 4])) == {(0xFF00, 1): [1, 2, 3, 4]}
    assert dec.decode_batch(bytes([1, 2, 3, 4]) * 2)[(0xFF00, 1)].tolist() == [[1, 2, 3, 4]] * 2
    assert ReportEncoder(lay).encode({(0xFF00, 1): [1, 2, 3, 4]}) == bytes([1, 2, 3, 4])
    assert ReportEncoder(lay).encode({(0xFF00, 1): 9}) == bytes([9, 9, 9, 9])


def test_numbered_reports_carry_their_id_and_reject_another():
    lay = ReportLayout(IN, 2, (field(8, 8, 2, [0x10030, 0x10031], -127, 127, REL, report_id=2),), 3)
    dec = ReportDecoder(lay)
    assert dec.decode(bytes([2, 0xFE, 5])) == {(GD, 0x30): -2, (GD, 0x31): 5}
    with pytest.raises(ParseError, match=r"input report 3 given to the decoder of report 2"):
        dec.decode(bytes([3, 0xFE, 5]))
    with pytest.raises(ParseError, match=r"row 1: input report 7 given to the decoder of report 2"):
        dec.decode_batch(bytes([2, 0, 0, 7, 0, 0]))
    assert ReportEncoder(lay).encode({(GD, 0x30): -2, (GD, 0x31): 5}) == bytes([2, 0xFE, 5])


def test_short_reports_are_zero_padded_with_a_warning_or_rejected_when_strict():
    with pytest.warns(ShortReportWarning, match=r"input report None is too short: 2 bytes, expected 4"):
        assert ReportDecoder(MOUSE).decode(bytes([1, 5])) == {
            (BUTTON, 1): 1, (BUTTON, 2): 0, (BUTTON, 3): 0, (GD, 0x30): 5, (GD, 0x31): 0, (GD, 0x38): 0}
    strict = ReportDecoder(MOUSE, strict=True)
    with pytest.raises(ParseError, match=r"report None is too short: 3 bytes, expected 4") as info:
        strict.decode(bytes([1, 5, 6]))
    assert info.value.offset == 3
    with pytest.raises(ParseError, match="empty"):
        ReportDecoder(MOUSE).decode(b"")
    with pytest.warns(ShortReportWarning):
        assert ReportDecoder(MOUSE).decode_batch(np.array([[1, 5], [2, 6]], np.uint8))[(GD, 0x31)].tolist() == [0, 0]
    with pytest.raises(ParseError, match="too short: 2 bytes, expected 4"):
        strict.decode_batch(np.array([[1, 5]], np.uint8))


def test_long_reports_are_read_up_to_the_layout_length():
    # the kernel reads report->size bits and ignores the rest
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert ReportDecoder(MOUSE).decode(bytes([1, 2, 3, 4, 99, 99]))[(GD, 0x38)] == 4
        batch = ReportDecoder(MOUSE).decode_batch(np.array([[1, 2, 3, 4, 99, 99]], np.uint8))
    assert batch[(GD, 0x38)].tolist() == [4]


def test_batch_input_checks():
    dec = ReportDecoder(MOUSE)
    with pytest.raises(ParseError, match="5 bytes are not a whole number of 4-byte reports"):
        dec.decode_batch(bytes(5))
    with pytest.raises(InvalidArgument):
        dec.decode_batch(np.zeros((2, 4), np.int32))
    assert dec.decode_batch(b"")[(GD, 0x30)].shape == (0,)
    # a non-contiguous view of a wider array decodes the same
    wide = np.arange(48, dtype=np.uint8).reshape(4, 12)
    view = wide[:, ::3]
    assert dec.decode_batch(view)[(GD, 0x31)].tolist() == [dec.decode(bytes(r))[(GD, 0x31)] for r in view]


def test_batch_array_usages():
    dec = ReportDecoder(KEYS)
    rows = np.array([[0, 0, 4, 5, 0, 0, 0, 0], [2, 0, 0, 0, 0, 0, 0, 0x29]], np.uint8)
    batch = dec.decode_batch(rows)
    assert batch[(KEYBOARD, 4)].tolist() == [True, False] and batch[(KEYBOARD, 0x29)].tolist() == [False, True]
    assert (KEYBOARD, 6) not in batch and batch[(KEYBOARD, 0xE1)].tolist() == [0, 1]
    assert dec.array_usages_batch(rows).tolist() == [[0x70004, 0x70005, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0x70029]]


def test_encoder_errors_name_the_usage():
    enc = ReportEncoder(MOUSE)
    with pytest.raises(InvalidArgument, match=r"usage 0x0001:0x0030 value 200 does not fit signed 8 bits"):
        enc.encode({(GD, 0x30): 200})
    with pytest.raises(InvalidArgument, match="has 1 elements, 2 values were given"):
        enc.encode({(GD, 0x30): [1, 2]})
    with pytest.raises(InvalidArgument, match="7 usages for an array of 6 elements"):
        ReportEncoder(KEYS).encode({(KEYBOARD, k): 1 for k in range(4, 11)})
    assert ReportEncoder(KEYS).encode({(KEYBOARD, 4): 1, (KEYBOARD, 0xE0): 1, (KEYBOARD, 5): 0}) == bytes(
        [1, 0, 4, 0, 0, 0, 0, 0])


def test_array_without_a_no_usage_value_needs_all_its_elements():
    # 2 bits 0..3 over 4 usages: every value reports a usage, so an empty slot cannot be encoded
    lay = layout(field(0, 2, 2, [0x90001, 0x90002, 0x90003, 0x90004], 0, 3, 0), pad(4, 4))
    with pytest.raises(InvalidArgument, match="no value meaning"):
        ReportEncoder(lay).encode({(BUTTON, 1): 1})
    assert ReportEncoder(lay).encode({(BUTTON, 1): 1, (BUTTON, 4): 1}) == bytes([0 | 3 << 2])


def test_long_reports_decode_field_by_field():
    count = WHOLE_INT_BYTES + 8
    lay = layout(field(0, 8, count, range(0xFF000001, 0xFF000001 + count), -128, 127), pad(8 * count, 4))
    report = bytes(range(count)) + b"\x00"
    dec = ReportDecoder(lay)
    assert "_from(r[" in "\n".join(dec.source.lines)
    values = dec.decode(report)
    assert [values[(0xFF00, i + 1)] for i in range(count)] == [b - 256 if b > 127 else b for b in range(count)]


# -- random layouts ----------------------------------------------------------------------------------------

@st.composite
def layouts(draw: st.DrawFn) -> ReportLayout:
    """Random layouts: variables of 1..40 bits (signed or not, some repeating a usage), arrays, padding."""
    numbered = draw(st.booleans())
    rid = draw(st.integers(1, 255)) if numbered else None
    offset = 8 if numbered else 0
    fields = []
    next_usage = 1
    for _ in range(draw(st.integers(1, 6))):
        kind = draw(st.sampled_from(["var", "var", "array", "pad"]))
        size = draw(st.integers(1, 40 if kind == "var" else 10))
        count = draw(st.integers(1, 4))
        if kind == "pad":
            fields.append(Field(IN, rid, 0, (), offset, size, count, 0, 0, 0, 0, 0, 0, MAIN_CONSTANT))
        elif kind == "var":
            signed = draw(st.booleans()) and size > 1
            lmin, lmax = (-(1 << (size - 1)), (1 << (size - 1)) - 1) if signed else (0, (1 << size) - 1)
            n = draw(st.integers(1, count))
            usages = tuple(0xFF000000 + next_usage + i for i in range(n))
            next_usage += n
            fields.append(Field(IN, rid, 0xFF00, usages, offset, size, count, lmin, lmax, 0, 0, 0, 0, VAR))
        else:
            lmin = draw(st.integers(-(1 << (size - 1)) if size > 1 else 0, 1))
            n = draw(st.integers(1, min((1 << size) - 1, 300)))  # one value left to mean "no usage"
            lmax = min(lmin + n - 1 + draw(st.integers(0, 2)), (1 << (size - 1)) - 1 if lmin < 0 else (1 << size) - 1)
            usages = tuple(0x00090000 + next_usage + i for i in range(n))
            next_usage += n
            fields.append(Field(IN, rid, 9, usages, offset, size, count, lmin, lmax, 0, 0, 0, 0, 0))
        offset += size * count
    return ReportLayout(IN, rid, tuple(fields), -(-offset // 8))


def random_values(lay: ReportLayout, rnd: random.Random) -> dict:
    values: dict = {}
    for f in lay.fields:
        if f.is_constant:
            continue
        if f.is_array:
            top = min(f.logical_max, f.logical_min + len(f.usages) - 1)
            keys = [(u >> 16, u & 0xFFFF) for u in f.usages[:top - f.logical_min + 1]]
            for k in rnd.sample(keys, rnd.randint(0, min(len(keys), f.count - 1))):
                values[k] = 1
        else:
            keys = [(u >> 16, u & 0xFFFF) for u in f.usages]
            per = [rnd.randint(f.logical_min, f.logical_max) for _ in range(f.count)]
            for i, k in enumerate(keys):
                mine = per[i:] if i == len(keys) - 1 else [per[i]]
                values[k] = mine[0] if len(mine) == 1 else mine
    return values


@settings(max_examples=150, deadline=None)
@given(layouts(), st.randoms(use_true_random=False))
def test_encode_then_decode_gives_the_values_back(lay, rnd):
    values = random_values(lay, rnd)
    report = ReportEncoder(lay).encode(values)
    assert len(report) == lay.length
    decoded = ReportDecoder(lay).decode(report)
    arrays = {k for k, v in decoded.items() if k[0] == 9}
    assert {k: v for k, v in decoded.items() if k[0] != 9} == {k: v for k, v in values.items() if k[0] != 9}
    assert arrays == {k for k, v in values.items() if k[0] == 9}


@settings(max_examples=150, deadline=None)
@given(layouts(), st.binary(min_size=0, max_size=400))
def test_decode_batch_agrees_with_decode_row_by_row(lay, noise):
    rows = 5
    size = rows * lay.length
    data = bytearray((noise * (size // max(len(noise), 1) + 1))[:size] or bytes(size))
    if lay.report_id is not None:
        data[::lay.length] = bytes([lay.report_id]) * rows
    dec = ReportDecoder(lay)
    batch = dec.decode_batch(bytes(data))
    single = [dec.decode(bytes(data[i * lay.length:(i + 1) * lay.length])) for i in range(rows)]
    array_keys = {k for s in single for k in s if k[0] == 9}
    assert {k for k in batch if k[0] == 9} == array_keys
    for key, column in batch.items():
        got = column.tolist()
        want = [s.get(key, 0) for s in single]
        assert [int(g) if not isinstance(g, list) else g for g in got] == want, key


@settings(max_examples=100, deadline=None)
@given(layouts(), st.binary(min_size=0, max_size=80))
def test_the_loop_decoder_of_huge_reports_agrees_with_the_compiled_one(lay, noise):
    report = (noise * (lay.length // max(len(noise), 1) + 1))[:lay.length] or bytes(lay.length)
    if lay.report_id is not None:
        report = bytes([lay.report_id]) + report[1:]
    compiled = ReportDecoder(lay)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(codec, "MAX_COMPILED_ELEMENTS", -1)
        looped = ReportDecoder(lay)
    assert looped.source is None and compiled.source is not None
    assert looped.decode(report) == compiled.decode(report)
    assert looped.values(report) == compiled.values(report)


@settings(max_examples=100, deadline=None)
@given(layouts(), st.binary(min_size=0, max_size=80))
def test_one_bit_variables_decoded_by_their_set_bits_agree_with_the_loop_decoder(lay, noise):
    report = (noise * (lay.length // max(len(noise), 1) + 1))[:lay.length] or bytes(lay.length)
    if lay.report_id is not None:
        report = bytes([lay.report_id]) + report[1:]
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(codec, "BITMAP_MIN_BITS", 1)
        by_bits = ReportDecoder(lay)
        mp.setattr(codec, "MAX_COMPILED_ELEMENTS", -1)
        looped = ReportDecoder(lay)
    assert by_bits.decode(report) == looped.decode(report)


@pytest.mark.parametrize("lead_bytes", [1, WHOLE_INT_BYTES + 3])  # read as one int, and field by field
def test_an_nkro_bitmap_gives_every_key_with_the_pressed_ones_at_1(lead_bytes):
    keys = 160
    lay = layout(field(0, 8, lead_bytes, range(0xFF000001, 0xFF000001 + lead_bytes), 0, 255),
                 field(8 * lead_bytes, 1, keys, range(0x70000, 0x70000 + keys), 0, 1))
    report = bytearray(lay.length)
    pressed = [0x04, 0x1D, 0x2C, 0x9F]  # a, z, space, the last bit
    for u in pressed:
        report[lead_bytes + u // 8] |= 1 << (u % 8)  # usage u is bit u % 8 of byte lead + u // 8, by hand
    dec = ReportDecoder(lay)
    assert "while b:" in "\n".join(dec.source.lines)
    values = dec.decode(bytes(report))
    assert {u: values[(KEYBOARD, u)] for u in range(keys)} == {u: int(u in pressed) for u in range(keys)}
    assert [values[(0xFF00, i + 1)] for i in range(lead_bytes)] == [0] * lead_bytes


@pytest.mark.slow
def test_random_reports_never_crash_the_decoder():
    rnd = random.Random(11)
    decoders = [ReportDecoder(MOUSE), ReportDecoder(KEYS), ReportDecoder(MOUSE, strict=True)]
    for _ in range(50_000):
        report = bytes(rnd.randrange(256) for _ in range(rnd.randrange(0, 20)))
        for dec in decoders:
            try:
                dec.decode(report)
                dec.values(report)
            except ParseError:
                pass


@pytest.mark.parametrize("hexdesc", [
    "0509a101090115002501754895018102090175088102c0",  # Button 1 as a 72-bit and an 8-bit element
    "0509a1010901150027ffffffff754095018102090175088102c0",  # as a 64-bit unsigned and an 8-bit one
    "0509a101090115002501754895018102090175018102c0",  # as a 72-bit and a one-bit (bool) element
    "0507a1011900296515ff2505754895018100c0",  # an array of 72-bit elements
])
def test_batches_refuse_what_they_cannot_hold_exactly(hexdesc):
    d = parse_descriptor(bytes.fromhex(hexdesc))
    (kind, rid), lay = next(iter(d.layouts.items()))
    with pytest.raises(InvalidArgument, match="one by one"):
        d.decoder(kind, rid).decode_batch(bytes(3 * lay.length))
    d.decode(bytes(lay.length))  # one by one they decode


def test_a_usage_in_a_one_bit_and_a_byte_element_stacks_into_one_int64_matrix():
    """Button 1 as a 1-bit and then an 8-bit element (bits 0 and 1..8): the bool column and the int64 one stack."""
    d = parse_descriptor(bytes.fromhex("0509a10109011500257f75019501810209017508810275078101c0"))
    dec = d.decoder()
    rows = np.array([[0b00000011, 0], [0b11111110, 0b1]], np.uint8)  # by hand: bit 0; bits 1..8
    batch = dec.decode_batch(rows)[(9, 1)]
    assert batch.dtype == np.int64 and batch.tolist() == [[1, 1], [0, 0xFF]]
    assert batch.tolist() == [d.decode(bytes(r))[(9, 1)] for r in rows]


@pytest.mark.parametrize("gap", [0, 3, 200])
def test_a_batch_of_bitmap_reports_unpacks_their_bits_as_the_elements_decode_one_by_one(gap):
    """An NKRO-style bitmap (8 modifiers, 3 padding bits, 40 keys, then a byte): the batch's one unpacking of the
    bitmap bytes (gap 0, 3) and the per-element path (gap 200: too sparse to unpack) both give bool columns (int64
    for the byte) equal to the bit read by hand, to each element's own extraction and to decode row by row."""
    lay = layout(field(0, 1, 8, range(0x700E0, 0x700E8), 0, 1), pad(8, 3 + gap),
                 field(11 + gap, 1, 40, range(0x70004, 0x7002C), 0, 1), field(51 + gap, 8, 1, [0x10030], -127, 127))
    dec = ReportDecoder(lay)
    assert bool(dec._bitmap_batch(np.zeros((1, lay.length), np.uint8))) == (gap < 200)
    rows = np.random.default_rng(gap).integers(0, 256, (64, lay.length), dtype=np.uint8)
    batch = dec.decode_batch(rows)
    single = [dec.decode(bytes(r)) for r in rows]
    for e in dec.elements:
        column = batch[e.key]
        assert column.dtype == (bool if e.bit_size == 1 else np.int64)
        assert column.tolist() == dec._element_batch(rows, e).tolist() == [s[e.key] for s in single]
        if e.bit_size == 1:
            assert column.tolist() == ((rows[:, e.bit_offset // 8] >> (e.bit_offset % 8)) & 1).tolist()
    assert all(column.shape == (0,) for column in dec.decode_batch(b"").values())

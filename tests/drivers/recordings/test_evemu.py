"""evemu files: read what evemu-record writes (bitmasks decoded by hand), write what evemu reads, reject bad ones."""

from __future__ import annotations

import io
import random
import warnings

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.drivers.recordings.evemu import (
    CODE_MAX,
    EV_ABS,
    EV_KEY,
    EV_LED,
    EV_MSC,
    EV_REL,
    EV_SW,
    EV_SYN,
    INPUT_PROP_MAX,
    AbsInfo,
    EvdevRecording,
    Limits,
    read_evemu,
    write_evemu,
)
from pixelpen.drivers.recordings.hidrecorder import RecordingWarning
from pixelpen.errors import InvalidArgument, ParseError
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign

evdev = pytest.importorskip("evdev", reason="python-evdev (the input extra) is the oracle for the kernel's codes")
ecodes = evdev.ecodes

_ZERO = "00 00 00 00 00 00 00 00"
# A mouse as evemu-record 2.7 prints it: the EV_KEY mask's 5th line (codes 256..319) has byte 2 = 0x07,
# i.e. codes 256 + 16 + {0, 1, 2} = BTN_LEFT, BTN_RIGHT, BTN_MIDDLE; EV_REL's byte 0 = 0x03 (REL_X, REL_Y),
# byte 1 = 0x01 (code 8, REL_WHEEL); EV_MSC byte 0 = 0x10 (code 4, MSC_SCAN).
MOUSE = "\n".join([
    "# EVEMU 1.3",
    "# Kernel: 6.1.0",
    "# Input device name: \"Logitech USB Optical Mouse\"",
    "N: Logitech USB Optical Mouse",
    "I: 0003 046d c077 0111",
    "P: " + _ZERO,
    "B: 00 0b 00 00 00 00 00 00 00",
    *(["B: 01 " + _ZERO] * 4), "B: 01 00 00 07 00 00 00 00 00", *(["B: 01 " + _ZERO] * 7),
    "B: 02 03 01 00 00 00 00 00 00",
    "B: 03 " + _ZERO,
    "B: 04 10 00 00 00 00 00 00 00",
    "E: 0.000001 0004 0004 589825\t# EV_MSC / MSC_SCAN             589825",
    "E: 0.000001 0001 0110 0001\t# EV_KEY / BTN_LEFT                1",
    "E: 0.000001 0000 0000 0000\t# ------------ SYN_REPORT (0) ---------- +0ms",
    "E: 0.008012 0002 0000 -002\t# EV_REL / REL_X                  -2",
    "E: 0.008012 0002 0008 0001\t# EV_REL / REL_WHEEL               1",
    "E: 0.008012 0000 0000 0000\t# ------------ SYN_REPORT (0) ---------- +8ms",
    "",
])

# A pen tablet: P: byte 0 = 0x01 -> property 0 (INPUT_PROP_POINTER) only.
# EV_ABS byte 0 = 0x03 (ABS_X, ABS_Y), byte 3 = 0x0f (codes 24..27: PRESSURE, DISTANCE, TILT_X, TILT_Y).
TABLET = "\n".join([
    "# EVEMU 1.3",
    "N: Wacom Intuos S Pen",
    "I: 0003 056a 0374 0110",
    "P: 01 00 00 00 00 00 00 00",
    "B: 00 0b 00 00 00 00 00 00 00",
    "B: 03 03 00 00 0f 00 00 00 00",
    "A: 00 0 15200 4 0 100",
    "A: 01 0 9500 4 0 100",
    "A: 18 0 4095 0 0 0",
    "A: 19 0 63 0 0 0",
    "A: 1a -64 63 0 0 57",
    "A: 1b -64 63 0 0 57",
    "L: 01 1",
    "S: 00 1",
    "E: 1.500000 0003 0000 7600",
    "E: 1.500000 0000 0000 0000",
    "",
])


def test_mouse_description_decoded_as_the_bitmasks_say():
    rec = read_evemu(MOUSE)
    assert (rec.name, rec.bus, rec.vendor_id, rec.product_id, rec.version) == (
        "Logitech USB Optical Mouse", 3, 0x046D, 0xC077, 0x0111)
    assert rec.properties == frozenset()
    assert rec.codes[EV_SYN] == {ecodes.SYN_REPORT, ecodes.SYN_CONFIG, ecodes.SYN_DROPPED}
    assert rec.codes[EV_KEY] == {ecodes.BTN_LEFT, ecodes.BTN_RIGHT, ecodes.BTN_MIDDLE}
    assert rec.codes[EV_REL] == {ecodes.REL_X, ecodes.REL_Y, ecodes.REL_WHEEL}
    assert rec.codes[EV_MSC] == {ecodes.MSC_SCAN}
    assert rec.device_id.bus == "usb" and rec.device_id.vendor_id == 0x046D


def test_mouse_events_with_evemu_comments_and_zero_padded_values():
    rec = read_evemu(MOUSE)
    assert rec.events == [
        (0.000001, ecodes.EV_MSC, ecodes.MSC_SCAN, 589825),
        (0.000001, ecodes.EV_KEY, ecodes.BTN_LEFT, 1),
        (0.000001, ecodes.EV_SYN, ecodes.SYN_REPORT, 0),
        (0.008012, ecodes.EV_REL, ecodes.REL_X, -2),
        (0.008012, ecodes.EV_REL, ecodes.REL_WHEEL, 1),
        (0.008012, ecodes.EV_SYN, ecodes.SYN_REPORT, 0),
    ]


def test_tablet_axes_properties_leds_and_switches():
    rec = read_evemu(TABLET)
    assert rec.properties == {ecodes.INPUT_PROP_POINTER}
    assert rec.codes[EV_ABS] == {ecodes.ABS_X, ecodes.ABS_Y, ecodes.ABS_PRESSURE, ecodes.ABS_DISTANCE,
                                 ecodes.ABS_TILT_X, ecodes.ABS_TILT_Y}
    assert rec.absinfo[ecodes.ABS_X] == AbsInfo(0, 0, 15200, 4, 0, 100)
    assert rec.absinfo[ecodes.ABS_TILT_X] == AbsInfo(0, -64, 63, 0, 0, 57)
    assert rec.leds == {ecodes.LED_CAPSL: 1}
    assert rec.switches == {ecodes.SW_LID: 1}
    assert rec.events[0] == (1.5, ecodes.EV_ABS, ecodes.ABS_X, 7600)


def test_code_table_is_the_kernels():
    assert (EV_SYN, EV_KEY, EV_REL, EV_ABS, EV_MSC, EV_SW, EV_LED) == (
        ecodes.EV_SYN, ecodes.EV_KEY, ecodes.EV_REL, ecodes.EV_ABS, ecodes.EV_MSC, ecodes.EV_SW, ecodes.EV_LED)
    maxima = {ecodes.EV_KEY: ecodes.KEY_MAX, ecodes.EV_REL: ecodes.REL_MAX, ecodes.EV_ABS: ecodes.ABS_MAX,
              ecodes.EV_MSC: ecodes.MSC_MAX, ecodes.EV_SW: ecodes.SW_MAX, ecodes.EV_LED: ecodes.LED_MAX,
              ecodes.EV_SND: ecodes.SND_MAX, ecodes.EV_REP: ecodes.REP_MAX, ecodes.EV_FF: ecodes.FF_MAX,
              ecodes.EV_SYN: ecodes.SYN_MAX}
    assert {t: CODE_MAX[t] for t in maxima} == maxima
    assert INPUT_PROP_MAX == ecodes.INPUT_PROP_MAX


def test_write_then_read_is_the_same_recording_and_masks_are_evemus_line_counts():
    rec = read_evemu(TABLET)
    out = io.StringIO()
    write_evemu(rec, out)
    text = out.getvalue()
    assert read_evemu(text) == rec
    # evemu writes ((max + 1) + 7) / 8 bytes per type, 8 a line: KEY_MAX 0x2ff -> 96 bytes, 12 lines
    assert sum(line.startswith("B: 01 ") for line in text.splitlines()) == 12
    assert sum(line.startswith("B: 03 ") for line in text.splitlines()) == 1


def test_events_only_output_for_umockdev():
    rec = read_evemu(MOUSE)
    out = io.StringIO()
    write_evemu(rec, out, description=False)
    lines = out.getvalue().splitlines()
    assert lines[0] == "# EVEMU 1.3" and all(line.startswith("E: ") for line in lines[1:])
    assert lines[1] == "E: 0.000001 0004 0004 589825"


def test_format_1_1_has_no_resolution_and_1_3_must():
    old = "# EVEMU 1.1\nN: x\nI: 0003 0001 0002 0003\nA: 00 0 100 0 0\n"
    assert read_evemu(old).absinfo[0] == AbsInfo(0, 0, 100, 0, 0, 0)
    with pytest.raises(ParseError, match=r"line 4.*resolution"):
        read_evemu(old.replace("1.1", "1.3"))


def test_node_from_umockdev_header():
    assert read_evemu("# device /dev/input/event3\nN: x\nI: 0003 0001 0002 0003\n").node == "/dev/input/event3"


def test_times_going_backwards_warn_or_fail_strict():
    text = "N: x\nI: 0003 0001 0002 0003\nE: 1.000000 0000 0000 0\nE: 0.500000 0000 0000 0\n"
    with pytest.warns(RecordingWarning, match="line 4: 1 event times go backwards"):
        rec = read_evemu(text)
    assert [e[0] for e in rec.events] == [1.0, 1.0]
    with pytest.raises(ParseError, match=r"line 4.*backwards"):
        read_evemu(text, strict=True)


@pytest.mark.parametrize(("text", "where"), [
    ("N: x\n", "no I: line"),
    ("I: 0003 0001 0002 0003\n", "no N: line"),
    ("N: x\nN: y\n", "line 2.*second device name"),
    ("N: x\nI: 0003 0001 0002\n", "line 2.*I: expected"),
    ("N: x\nI: 0003 10000 0002 0003\n", "line 2.*vendor"),
    ("N: x\nI: 0003 0001 0002 0003\nP: 00 00\n", "line 3.*P: expected"),
    ("N: x\nI: 0003 0001 0002 0003\nP: 00 00 00 00 01 00 00 00\n", "property bit 32"),
    ("N: x\nI: 0003 0001 0002 0003\nB: 20 00 00 00 00 00 00 00 00\n", "line 3.*event type"),
    ("N: x\nI: 0003 0001 0002 0003\nB: 02 00 00 01 00 00 00 00 00\n", "code 0x10 .*REL|code 0x10"),
    ("N: x\nI: 0003 0001 0002 0003\nB: 01 zz 00 00 00 00 00 00 00\n", "byte 0"),
    ("N: x\nI: 0003 0001 0002 0003\nA: 40 0 1 0 0 0\n", "axis code"),
    ("N: x\nI: 0003 0001 0002 0003\nA: 00 0 1 0 0 0\nA: 00 0 1 0 0 0\n", "line 4.*second line"),
    ("N: x\nI: 0003 0001 0002 0003\nA: 00 0 99999999999 0 0 0\n", "maximum"),
    ("N: x\nI: 0003 0001 0002 0003\nE: 1.5 0000 0000 0\nN: y\n", "line 4.*after the events"),
    ("N: x\nI: 0003 0001 0002 0003\nE: 1 0000 0000 0\n", "line 3.*time"),
    ("N: x\nI: 0003 0001 0002 0003\nE: 1.0000000 0000 0000 0\n", "time"),
    ("N: x\nI: 0003 0001 0002 0003\nE: 1.000000 0000 0000\n", "expected 'E:"),
    ("N: x\nI: 0003 0001 0002 0003\nE: 1.000000 0000 0000 0 junk\n", "expected 'E:"),
    ("N: x\nI: 0003 0001 0002 0003\nE: 1.000000 10000 0000 0\n", "event type"),
    ("N: x\nI: 0003 0001 0002 0003\nE: 1.000000 0000 0000 2147483648\n", "event value"),
    ("N: x\nI: 0003 0001 0002 0003\nX: 1\n", "line 3.*not an evemu line"),
])
def test_malformed_lines_name_line_and_field(text, where):
    with pytest.raises(ParseError, match=where):
        read_evemu(text, source="bad.evemu")


def test_limits_bound_events_lines_and_file_size(tmp_path):
    head = "N: x\nI: 0003 0001 0002 0003\n"
    many = head + "E: 0.000001 0000 0000 0\n" * 11
    with pytest.raises(ParseError, match="more than 10 events"):
        read_evemu(many, limits=Limits(events=10))
    with pytest.raises(ParseError, match="longer than 64"):
        read_evemu(head + "# " + "x" * 100 + "\n", limits=Limits(line_chars=64))
    big = tmp_path / "big.evemu"
    big.write_text(many)
    with pytest.raises(ParseError, match="more than the 100-byte limit"):
        read_evemu(big, limits=Limits(file_bytes=100))
    with pytest.raises(ParseError, match="characters"):
        read_evemu("N: " + "n" * 50 + "\nI: 0003 0001 0002 0003\n", limits=Limits(name_chars=20))


def test_truncated_file_gives_a_clean_error_or_its_prefix_at_every_cut():
    for cut in range(1, len(TABLET), 7):
        try:
            rec = read_evemu(TABLET[:cut] + "\n")
        except ParseError as exc:
            assert exc.source == "<evemu text>"
            continue
        assert "Wacom Intuos S Pen".startswith(rec.name) and len(rec.events) <= 2


def test_missing_file_is_a_parse_error(tmp_path):
    with pytest.raises(ParseError, match="cannot open"):
        read_evemu(tmp_path / "absent.evemu")


def test_writer_refuses_what_a_file_cannot_hold():
    rec = EvdevRecording("a\nb", 3, 1, 2, 3)
    with pytest.raises(InvalidArgument, match="line break"):
        write_evemu(rec, io.StringIO())
    with pytest.raises(InvalidArgument, match="vendor"):
        write_evemu(EvdevRecording("x", 3, 0x10000, 2, 3), io.StringIO())
    with pytest.raises(InvalidArgument, match="event time"):
        write_evemu(EvdevRecording("x", 3, 1, 2, 3, events=[(1.0, 0, 0, 0), (0.5, 0, 0, 0)]), io.StringIO())


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 0x1F), st.integers(0, 0x2FF),
                          st.integers(-(2**31), 2**31 - 1)), max_size=30),
       st.dictionaries(st.integers(0, 0x3F), st.tuples(*[st.integers(-(2**31), 2**31 - 1)] * 5), max_size=5),
       st.frozensets(st.integers(0, INPUT_PROP_MAX), max_size=4))
def test_round_trip_of_random_recordings(events, axes, props):
    micros = sorted(e[0] for e in events)
    rec = EvdevRecording("dev", 3, 1, 2, 3, props, {EV_KEY: frozenset(e[2] for e in events)},
                         {code: AbsInfo(0, *values) for code, values in axes.items()},
                         events=[(m / 1e6, t, c, v) for m, (_, t, c, v) in zip(micros, events, strict=True)])
    out = io.StringIO()
    write_evemu(rec, out)
    back = read_evemu(out.getvalue())
    codes = dict(rec.codes)
    if rec.absinfo:
        codes[EV_ABS] = frozenset(rec.absinfo)
    codes[EV_SYN] = frozenset({0, 1, 3})
    assert back.codes == {t: c for t, c in codes.items() if c}
    assert back.absinfo == rec.absinfo and back.properties == rec.properties
    assert [(round(t * 1e6), ty, c, v) for t, ty, c, v in back.events] == [
        (round(t * 1e6), ty, c, v) for t, ty, c, v in rec.events]


def _target(data: bytes) -> object:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RecordingWarning)
        return read_evemu(data, limits=Limits(events=10_000, file_bytes=1 << 20))


def test_fuzzed_files_give_clean_errors():
    campaign("evemu", _target, [MOUSE.encode(), TABLET.encode()], QUICK_CASES, seed=23).check()


@pytest.mark.slow
def test_fuzzed_files_give_clean_errors_long_campaign():
    campaign("evemu", _target, [MOUSE.encode(), TABLET.encode()], SLOW_CASES,
             seed=random.Random(2311).randrange(10**6)).check()


def test_types_without_codes_in_b_lines_are_refused():
    with pytest.raises(ParseError, match="beyond its highest code"):
        read_evemu(f"N: x\nI: 0003 0001 0002 0003\nB: {EV_SW:02x} 00 00 00 01 00 00 00 00\n")
    assert read_evemu(f"N: x\nI: 0003 0001 0002 0003\nB: {EV_LED:02x} ff ff 00 00 00 00 00 00\n").codes[
        EV_LED] == frozenset(range(16))


def test_separate_events_file_as_older_evemu_and_umockdev_write_it(tmp_path):
    events = tmp_path / "tap.events"
    events.write_text("# device /dev/input/event9\nE: 1330495931.101111 0003 0039 0\n"
                      "E: 1330495931.101135 0000 0000 0\n")
    rec = read_evemu(TABLET, events=events)
    assert rec.events[-2:] == [(1330495931.101111, ecodes.EV_ABS, ecodes.ABS_MT_TRACKING_ID, 0),
                               (1330495931.101135, ecodes.EV_SYN, ecodes.SYN_REPORT, 0)]
    assert rec.node == "/dev/input/event9" and rec.name == "Wacom Intuos S Pen"
    events.write_text("E: 1.000000 0000 0000 0\nN: other\n")
    with pytest.raises(ParseError, match=r"tap.events, line 2: N: a device line in an events file"):
        read_evemu(TABLET, events=events)
    with pytest.raises(ParseError, match=r"<evemu text>.*no I: line"):
        read_evemu("N: x\n", events=events)

"""hid-recorder files: read what hid-tools' recorder writes, write what its replay reads, reject bad files cleanly."""

from __future__ import annotations

import io
import math
import random
import warnings

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.drivers.identity import DeviceId
from pixelpen.drivers.recordings.hidrecorder import (
    HidRecording,
    HidRecordingWriter,
    Limits,
    RecordingWarning,
    read_hid_recording,
    record_link,
    write_hid_recording,
)
from pixelpen.errors import InvalidArgument, ParseError
from pixelpen.sim.hid.descriptors import BOOT_MOUSE, TRACKBALL
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign

MOUSE_TEXT = """\
# Logitech USB Optical Mouse
# 0x05, 0x01,  // Usage Page (Generic Desktop)   0
R: 50 05 01 09 02 a1 01 09 01 a1 00 05 09 19 01 29 03 15 00 25 01 95 03 75 01 81 02 95 01 75 05 81 01 05 01 09 30 \
09 31 15 81 25 7f 75 08 95 02 81 06 c0 c0
N: Logitech USB Optical Mouse
P: usb-0000:00:14.0-2/input0
I: 3 046d c077
#  Button: 1  0  0 | # | X:    2 | Y:    3
E: 000000.000000 3 01 02 03
E: 000000.008012 3 00 ff 81
E: 000001.500000 3 04 00 00
"""
"""Written by hand in hid-recorder's format (the header as the C hid-recorder prints it, with P:)."""


def _hidtools_device(name, bus, vendor, product, descriptor, events):
    """A hidtools HidrawDevice without a hidraw node: its own dump() writes the file."""
    from hidtools.hid import ReportDescriptor
    from hidtools.hidraw import HidrawDevice, HidrawEvent
    from hidtools.util import BusType

    device = HidrawDevice.__new__(HidrawDevice)
    device.name, device.bustype, device.vendor_id, device.product_id = name, BusType(bus), vendor, product
    device.report_descriptor = ReportDescriptor.from_bytes(list(descriptor))
    device.events = [HidrawEvent(sec, usec, tuple(data)) for sec, usec, data in events]
    device._dump_offset, device.time_offset = -1, None
    return device


def test_the_hand_written_recording_reads_field_by_field():
    (rec,) = read_hid_recording(MOUSE_TEXT)
    assert rec.name == "Logitech USB Optical Mouse" and rec.phys == "usb-0000:00:14.0-2/input0"
    assert (rec.bus, rec.vendor_id, rec.product_id) == (3, 0x046D, 0xC077)
    assert rec.descriptor == BOOT_MOUSE
    assert rec.reports == [(0.0, b"\x01\x02\x03"), (0.008012, b"\x00\xff\x81"), (1.5, b"\x04\x00\x00")]
    assert rec.device_id == DeviceId("usb", 0x046D, 0xC077, name="Logitech USB Optical Mouse", interface=0)


def test_a_recording_written_by_hid_tools_own_recorder_reads_back():
    device = _hidtools_device("Test Trackball", 3, 0x047D, 0x2041, TRACKBALL,
                              [(0, 0, b"\x01\x01\x10\x00\xf0\xff"), (0, 7999, b"\x02\x01"), (2, 5, b"\x01\x00" * 3)])
    out = io.StringIO()
    device.dump(out)
    (rec,) = read_hid_recording(out.getvalue())
    assert rec.descriptor == TRACKBALL and rec.name == "Test Trackball" and rec.phys == ""
    assert (rec.bus, rec.vendor_id, rec.product_id) == (3, 0x047D, 0x2041)
    assert rec.reports == [(0.0, b"\x01\x01\x10\x00\xf0\xff"), (0.007999, b"\x02\x01"), (2.000005, b"\x01\x00" * 3)]


def test_several_devices_recorded_by_hid_tools_main_loop(monkeypatch, tmp_path):
    """hidtools.cli.record.main itself, with its hidraw nodes and poll() replaced by two prepared devices."""
    record = pytest.importorskip("hidtools.cli.record")
    from click.testing import CliRunner
    from hidtools.hidraw import HidrawEvent

    mouse = _hidtools_device("Mouse", 3, 0x1, 0x2, BOOT_MOUSE, [])
    ball = _hidtools_device("Ball", 5, 0x3, 0x4, TRACKBALL, [])
    devices = iter([mouse, ball])
    monkeypatch.setattr(record, "HidrawDevice", lambda fd: next(devices))
    paths = [tmp_path / "hidraw0", tmp_path / "hidraw1"]
    for p in paths:
        p.write_text("")
    script = [(0, (0, 0, b"\x01\x00\x00")), (1, (0, 10, b"\x02\x01")), (1, (0, 20, b"\x02\x00")),
              (0, (1, 0, b"\x00\x05\x05"))]

    class Poll:
        def register(self, fd, mask):
            self.fds = [*getattr(self, "fds", []), fd.fileno()]

        def poll(self):
            if not script:
                raise KeyboardInterrupt
            which, (sec, usec, data) = script.pop(0)
            (mouse, ball)[which].events.append(HidrawEvent(sec, usec, tuple(data)))
            return [(self.fds[which], 1)]

    monkeypatch.setattr(record.select, "poll", Poll)
    (mouse, ball)[0].read_events = (mouse, ball)[1].read_events = lambda: None
    out = tmp_path / "two.hid"
    result = CliRunner().invoke(record.main, ["--output", str(out), *map(str, paths)])
    assert result.exit_code == 0, result.output
    text = out.read_text()
    assert text.count("D: 0") == 3 and text.count("D: 1") == 2  # before each header, then at each switch
    first, second = read_hid_recording(out)
    assert (first.name, first.descriptor, first.bus) == ("Mouse", BOOT_MOUSE, 3)
    assert first.reports == [(0.0, b"\x01\x00\x00"), (1.0, b"\x00\x05\x05")]
    assert (second.name, second.descriptor, second.bus, second.vendor_id) == ("Ball", TRACKBALL, 5, 3)
    assert second.reports == [(0.00001, b"\x02\x01"), (0.00002, b"\x02\x00")]
    assert second.device_id.bus == "bluetooth" and second.device_id.interface == -1


def test_the_writer_writes_the_lines_hid_tools_writes():
    device = _hidtools_device("Mouse", 3, 0x046D, 0xC077, BOOT_MOUSE,
                              [(0, 0, b"\x01\x02\x03"), (12, 34, b"\x00\xff\x81")])
    theirs = io.StringIO()
    device.dump(theirs)
    ours = io.StringIO()
    write_hid_recording(HidRecording("Mouse", "", 3, 0x046D, 0xC077, BOOT_MOUSE,
                                     [(0.0, b"\x01\x02\x03"), (12.000034, b"\x00\xff\x81")]), ours)
    def data_lines(text):
        return [line for line in text.splitlines() if line and not line.startswith("#")]
    assert data_lines(ours.getvalue()) == data_lines(theirs.getvalue())


def test_hid_replay_reads_what_the_writer_writes(tmp_path, monkeypatch):
    """hidtools.cli.replay's own parser (its uhid device replaced by one that keeps what it is given)."""
    try:
        replay = pytest.importorskip("hidtools.cli.replay")
    except OSError as exc:  # its import loads libevdev.so
        pytest.skip(f"hid-tools' replay cannot be imported here: {exc}")
    made = []

    class Kept:
        def __init__(self, name, application, input_info, rdesc):
            from hidtools.hid import ReportDescriptor  # what hidtools.uhid.UHIDDevice's rdesc setter does

            self.rdesc = ReportDescriptor.from_string(f"XXX {rdesc}").bytes
            self.name, self.info, self.events, self.device_nodes, self.phys = name, input_info, [], [1], ""
            made.append(self)

        def create_kernel_device(self):
            pass

        def call_input_event(self, data):
            self.events.append(list(data))

        def destroy(self):
            pass

    monkeypatch.setattr(replay.HIDReplay, "determine_device_type_by_info", lambda self, info: Kept)
    one = tmp_path / "one.hid"
    write_hid_recording(HidRecording("A", "usb-1/input0", 3, 1, 2, BOOT_MOUSE,
                                     [(0.0, b"\x01\x02\x03"), (0.001, b"\x00\xff\x81")]), one)
    replay.HIDReplay(str(one)).inject_events()
    assert [(m.name, m.info, bytes(m.rdesc), m.phys) for m in made] == [("A", (3, 1, 2), BOOT_MOUSE, "usb-1/input0")]
    assert made[0].events == [[1, 2, 3], [0, 0xFF, 0x81]]
    made.clear()
    two = tmp_path / "two.hid"
    write_hid_recording([HidRecording("A", "", 3, 1, 2, BOOT_MOUSE, [(0.0, b"\x01\x02\x03")]),
                         HidRecording("B", "p", 0x18, 3, 4, TRACKBALL, [(0.001, b"\x02\x7f")])], two)
    replay.HIDReplay(str(two))  # the headers; its inject_events cannot read D: lines (it parses them unstripped)
    assert [(m.name, m.info, bytes(m.rdesc)) for m in made] == [("A", (3, 1, 2), BOOT_MOUSE),
                                                                 ("B", (0x18, 3, 4), TRACKBALL)]


def test_several_devices_round_trip_with_d_lines_in_time_order():
    a = HidRecording("A", "usb-1/input2", 3, 1, 2, BOOT_MOUSE, [(0.0, b"\x01\x00\x00"), (0.5, b"\x00\x00\x00")])
    b = HidRecording("B", "", 6, 3, 4, TRACKBALL, [(0.25, b"\x02\x01"), (0.75, b"\x02\x00")])
    out = io.StringIO()
    write_hid_recording([a, b], out)
    lines = [line for line in out.getvalue().splitlines() if line[:2] in ("D:", "E:")]
    assert [line[:2] if line[0] == "E" else line for line in lines] == [
        "D: 0", "D: 1", "D: 0", "E:", "D: 1", "E:", "D: 0", "E:", "D: 1", "E:"]
    assert read_hid_recording(out.getvalue()) == [a, b]
    assert a.device_id.interface == 2


names = st.text(st.characters(blacklist_categories=("Cc", "Cs", "Zl", "Zp", "Zs")), max_size=40)


@settings(max_examples=60, deadline=None)
@given(name=names, phys=names, bus=st.integers(0, 0xFFFFFFFF), vid=st.integers(0, 0xFFFF),
       pid=st.integers(0, 0xFFFF), descriptor=st.binary(min_size=1, max_size=300),
       gaps=st.lists(st.integers(0, 10**8), max_size=30), data=st.data())
def test_round_trip_of_any_device(name, phys, bus, vid, pid, descriptor, gaps, data):
    micros = 0
    reports = []
    for gap in gaps:
        micros += gap
        reports.append((micros / 1e6, data.draw(st.binary(min_size=1, max_size=64))))
    rec = HidRecording(name, phys, bus, vid, pid, descriptor, reports)
    out = io.StringIO()
    write_hid_recording(rec, out)
    assert read_hid_recording(out.getvalue(), strict=True) == [rec]


def test_a_path_a_stream_and_bytes_read_alike(tmp_path):
    path = tmp_path / "mouse.hid"
    path.write_text(MOUSE_TEXT)
    expected = read_hid_recording(MOUSE_TEXT)
    assert read_hid_recording(path) == read_hid_recording(str(path)) == expected
    assert read_hid_recording(io.StringIO(MOUSE_TEXT)) == read_hid_recording(MOUSE_TEXT.encode()) == expected
    with pytest.raises(ParseError, match=r"mouse\.hid, line 3: R:"):
        path.write_text(MOUSE_TEXT.replace("R: 50", "R: 49"), encoding="utf-8")
        read_hid_recording(path)


def test_streamed_reports_are_flushed_one_by_one():
    class Counting(io.StringIO):
        flushes = 0

        def flush(self):
            Counting.flushes += 1

    out = Counting()
    writer = HidRecordingWriter(out)
    writer.device(HidRecording("M", "", 3, 1, 2, BOOT_MOUSE))
    writer.report(0.0, b"\x00\x00\x00")
    writer.report(0.001, b"\x01\x00\x00")
    assert Counting.flushes == 3
    assert out.getvalue().splitlines()[-1] == "E: 000000.001000 3 01 00 00"


BAD = [
    ("R: 3 05 01\n", r"line 1: R: the descriptor length says 3 bytes but 2 follow"),
    ("R: 2 05 0g\nI: 3 1 2\n", r"line 1: R: descriptor byte 1 is not a hex byte \(found '0g'\)"),
    ("R: 0\nI: 3 1 2\n", r"line 1: R: a descriptor of 0 bytes \(1 to 4096 allowed\)"),
    ("R: 4097 " + "00 " * 4097 + "\nI: 3 1 2\n", r"line 1: R: a descriptor of 4097 bytes"),
    ("R: 1 00\nI: 3 1\n", r"line 2: I: expected 'I: BUS VENDOR PRODUCT'"),
    ("R: 1 00\nI: 3 10000 2\n", r"line 2: I: the vendor is not a hex number of 0 to ffff \(found '10000'\)"),
    ("R: 1 00\nI: 3 0x1 2\n", r"line 2: I: the vendor is not a hex number"),
    ("R: 1 00\nI: 3 1 2\nE: 0.5 1 00\n", r"line 3: E: the timestamp is not SECONDS.MICROSECONDS"),
    ("R: 1 00\nI: 3 1 2\nE: -1.000000 1 00\n", r"line 3: E: the timestamp"),
    ("R: 1 00\nI: 3 1 2\nE: nan 1 00\n", r"line 3: E: the timestamp"),
    ("R: 1 00\nI: 3 1 2\nE: 1e400.000000 1 00\n", r"line 3: E: the timestamp"),
    ("R: 1 00\nI: 3 1 2\nE: 0.000000 2 00\n", r"line 3: E: the report length says 2 bytes but 1 follow"),
    ("R: 1 00\nI: 3 1 2\nE: 0.000000 1\n", r"line 3: E: expected 'E: SECONDS.MICROSECONDS LENGTH"),
    ("R: 1 00\nI: 3 1 2\nE: 0.000000 16385 " + "00 " * 16385 + "\n", r"line 3: E: a report of 16385 bytes"),
    ("E: 0.000000 1 00\n", r"line 1: E: a report of device 0 before its R: line"),
    ("R: 1 00\nI: 3 1 2\nD: 1\nE: 0.000000 1 00\n", r"line 4: E: a report of device 1 before its R: line"),
    ("D: 64\n", r"line 1: D: device index 64 \(0 to 63 allowed\)"),
    ("D: x\n", r"line 1: D: the device index is not a decimal number"),
    ("R: 1 00\nR: 1 00\n", r"line 2: R: a second report descriptor for device 0 \(the first is on line 1\)"),
    ("R: 1 00\nN: a\nN: b\n", r"line 3: N: a second name for device 0"),
    ("R: 1 00\nI: 3 1 2\nI: 3 1 2\n", r"line 3: I: a second bus/vendor/product line"),
    ("R: 1 00\n", r"line 1: device 0 has no I: line"),
    ("N: x\nI: 3 1 2\n", r"line 1: device 0 has no R: line"),
    ("# nothing\n\n", r"no device in the recording"),
    ("hello\n", r"line 1: not a hid-recorder line"),
    ("R: 1 00\nN: " + "x" * 1025 + "\n", r"line 2: N: the name is 1025 characters"),
]


@pytest.mark.parametrize(("text", "message"), BAD, ids=[m[:40] for _, m in BAD])
def test_malformed_files_name_the_line_and_field(text, message):
    with pytest.raises(ParseError, match=message) as info:
        read_hid_recording(text, source="bad.hid")
    assert str(info.value).startswith("bad.hid")


def test_truncated_files_are_errors_or_fewer_reports_never_crashes():
    full = MOUSE_TEXT.encode()
    complete = read_hid_recording(full)[0]
    for cut in range(len(full)):
        try:
            (rec,) = read_hid_recording(full[:cut])
        except ParseError:
            continue
        assert rec.descriptor == BOOT_MOUSE
        whole = max(len(rec.reports) - 1, 0)  # the last report may be cut short (a shorter report or time)
        assert rec.reports[:whole] == complete.reports[:whole]


def test_limits_bound_the_file_the_lines_and_the_reports(tmp_path):
    small = Limits(file_bytes=len(MOUSE_TEXT) - 1)
    path = tmp_path / "m.hid"
    path.write_text(MOUSE_TEXT)
    with pytest.raises(ParseError, match=r"m\.hid: the file is \d+ bytes, more than the \d+-byte limit"):
        read_hid_recording(path, limits=small)
    with pytest.raises(ParseError, match=r"line 10: more than the \d+-byte limit of a file"):
        read_hid_recording(io.StringIO(MOUSE_TEXT), limits=small)
    with pytest.raises(ParseError, match=r"line 10: E: more than 2 reports"):
        read_hid_recording(MOUSE_TEXT, limits=Limits(reports=2))
    with pytest.raises(ParseError, match=r"line 1: a line longer than"):
        read_hid_recording("# " + "x" * 60_000 + "\n")  # longer than 3 * 16384 + 64: refused before it is all read


def test_times_going_backwards_are_held_with_a_warning_or_refused_when_strict():
    text = MOUSE_TEXT.replace("000001.500000", "000000.004000")
    with pytest.warns(RecordingWarning, match=r"line 10: 1 report times of device 0 go backwards"):
        (rec,) = read_hid_recording(text)
    assert [t for t, _ in rec.reports] == [0.0, 0.008012, 0.008012]
    with pytest.raises(ParseError, match=r"line 10: E: the time 000000.004000 s is before the previous"):
        read_hid_recording(text, strict=True)


def test_unknown_line_types_are_skipped_with_a_warning():
    with pytest.warns(RecordingWarning, match=r"line 2: skipped X: lines"):
        (rec,) = read_hid_recording("R: 1 00\nX: future field\nI: 3 1 2\n")
    assert rec.descriptor == b"\x00"


def test_bytes_may_be_one_digit_upper_case_or_spaced_widely():
    (rec,) = read_hid_recording("R: 2 5   1\nI: 3 A b\nE: 0.000001 3 FF a  0\n")
    assert rec.descriptor == b"\x05\x01" and (rec.vendor_id, rec.product_id) == (10, 11)
    assert rec.reports == [(0.000001, b"\xff\x0a\x00")]


@pytest.mark.parametrize("bad", [
    {"name": "two\nlines"}, {"vendor_id": 0x10000}, {"bus": -1}, {"descriptor": b""}, {"descriptor": bytes(4097)}])
def test_the_writer_refuses_headers_the_format_cannot_hold(bad):
    fields = {"name": "M", "phys": "", "bus": 3, "vendor_id": 1, "product_id": 2, "descriptor": BOOT_MOUSE} | bad
    with pytest.raises(InvalidArgument):
        write_hid_recording(HidRecording(**fields), io.StringIO())


@pytest.mark.parametrize("reports", [
    [(math.nan, b"\x00")], [(math.inf, b"\x00")], [(-0.5, b"\x00")], [(1.0, b"\x00"), (0.5, b"\x00")],
    [(0.0, b"")], [(0.0, bytes(16385))]])
def test_the_writer_refuses_reports_the_format_cannot_hold(reports):
    with pytest.raises(InvalidArgument):
        write_hid_recording(HidRecording("M", "", 3, 1, 2, BOOT_MOUSE, reports), io.StringIO())


def _seeds() -> list[bytes]:
    out = io.StringIO()
    write_hid_recording([HidRecording("A", "usb-1/input0", 3, 1, 2, BOOT_MOUSE, [(0.0, b"\x01\x02\x03")] * 3),
                         HidRecording("B", "", 5, 3, 4, TRACKBALL, [(0.5, b"\x02\x7f")])], out)
    return [MOUSE_TEXT.encode(), out.getvalue().encode()]


def _target(data: bytes) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RecordingWarning)
        read_hid_recording(data, limits=Limits(reports=10_000))


def test_fuzzed_recordings_give_clean_errors():
    campaign("hid-recorder", _target, _seeds(), QUICK_CASES, seed=11).check()


@pytest.mark.slow
def test_fuzzed_recordings_give_clean_errors_long_campaign():
    campaign("hid-recorder", _target, _seeds(), SLOW_CASES, seed=random.Random(1102).randrange(10**6)).check()


def test_record_link_writes_each_report_and_what_came_before_an_unplug():
    from pixelpen.clock import SimulatedClock
    from pixelpen.drivers.hidapi import open_hid
    from pixelpen.errors import Disconnected
    from pixelpen.sim.hid.replay import replay_device
    from pixelpen.sim.transports.hidapi import SimHidapi

    clock = SimulatedClock()
    source = HidRecording("M", "", 3, 1, 2, BOOT_MOUSE, [(0.5, b"\x01\x00\x00"), (0.75, b"\x00\x00\x00"),
                                                         (9.0, b"\x02\x00\x00")])
    sim = replay_device(source, clock=clock)
    module = SimHidapi([sim])
    link = open_hid(module.paths()[0], module=module, clock=clock)
    out = io.StringIO()
    assert record_link(link, out, link.device_id, count=2, clock=clock) == 2
    (rec,) = read_hid_recording(out.getvalue())
    assert rec.reports == [(0.0, b"\x01\x00\x00"), (0.25, b"\x00\x00\x00")]  # times from the first report
    sim.inject("power-loss")
    out = io.StringIO()
    with pytest.raises(Disconnected):
        record_link(link, out, link.device_id, clock=clock)
    assert read_hid_recording(out.getvalue())[0].reports == []
    with pytest.raises(InvalidArgument):
        record_link(link, io.StringIO(), link.device_id, duration=math.nan)


def test_a_missing_file_is_a_parse_error_naming_it(tmp_path):
    missing = tmp_path / "nope.hid"
    with pytest.raises(ParseError, match="cannot read the recording") as caught:
        read_hid_recording(missing)
    assert str(missing) in str(caught.value)

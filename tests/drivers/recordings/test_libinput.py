"""libinput record files: the YAML libinput-record.c writes, read as evdev recordings; bad files are clean errors."""

from __future__ import annotations

import random

import pytest

from pixelpen.drivers.recordings.evemu import AbsInfo, Limits
from pixelpen.drivers.recordings.libinput import read_libinput_record
from pixelpen.errors import ParseError
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign

pytest.importorskip("yaml", reason="PyYAML (the input extra) reads libinput record files")
evdev = pytest.importorskip("evdev", reason="python-evdev (the input extra) is the oracle for the kernel's codes")
e = evdev.ecodes

# As libinput-record.c prints it (iprintf indentation, "# " comments, "- [%3lu, %6u, %3d, %3d, %7d] # desc")
RECORD = """\
# libinput record
version: 1
ndevices: 2
libinput:
  version: "1.22.1"
  git: "unknown"
system:
  os: "debian:12"
  kernel: "6.1.0-13-amd64"
  dmi: "dmi:bvnLENOVO:..."
devices:
- node: /dev/input/event5
  evdev:
    # Name: Logitech USB Optical Mouse
    # ID: bus 0x3 vendor 0x46d product 0xc077 version 0x111
    # Supported Events:
    # Event type 0 (EV_SYN)
    # Event type 1 (EV_KEY)
    #   Event code 272 (BTN_LEFT)
    # Properties:
    name: "Logitech USB Optical Mouse"
    id: [3, 1133, 49271, 273]
    codes:
      0: [0, 1, 2] # EV_SYN
      1: [272, 273, 274] # EV_KEY
      2: [0, 1, 8, 11] # EV_REL
      4: [4] # EV_MSC
    properties: []
  hid: [5, 1, 9, 2, 161, 1]
  udev:
    properties:
    - ID_INPUT=1
    - ID_INPUT_MOUSE=1
  quirks:
  events:
  - evdev:
    - [  0,      0,   4,   4,  589825] # EV_MSC / MSC_SCAN               589825
    - [  0,      0,   1, 272,       1] # EV_KEY / BTN_LEFT                    1
    - [  0,      0,   0,   0,       0] # ------------ SYN_REPORT (0) ---------- +0ms
  - libinput:
    - {time: 0.000000, type: POINTER_BUTTON, button: 272, state: pressed, seat_count: 1}
  - evdev:
    - [  0,   8012,   2,   0,      -2] # EV_REL / REL_X                      -2
    - [  0,   8012,   2,  11,     120] # EV_REL / REL_WHEEL_HI_RES          120
    - [  0,   8012,   0,   0,       0] # ------------ SYN_REPORT (0) ---------- +8ms
- node: /dev/input/event7
  evdev:
    name: "Wacom Intuos S Pen"
    id: [3, 1386, 884, 272]
    codes:
      0: [0, 1, 3, 4] # EV_SYN
      1: [320, 321, 330, 331] # EV_KEY
      3: [0, 1, 24] # EV_ABS
    absinfo:
      0: [0, 15200, 4, 0, 100]
      1: [0, 9500, 4, 0, 100]
      24: [0, 4095, 0, 0, 0]
    properties: [0]
  events:
  - evdev:
    - [  1, 500000,   3,   0,    7600] # EV_ABS / ABS_X                    7600 (+7600)
    - [  1, 500000,   0,   0,       0] # ------------ SYN_REPORT (0) ---------- +1500ms
"""


def test_two_devices_with_ids_codes_and_absinfo():
    mouse, pen = read_libinput_record(RECORD)
    assert (mouse.name, mouse.bus, mouse.vendor_id, mouse.product_id, mouse.version, mouse.node) == (
        "Logitech USB Optical Mouse", e.BUS_USB, 0x046D, 0xC077, 0x0111, "/dev/input/event5")
    assert mouse.codes[e.EV_KEY] == {e.BTN_LEFT, e.BTN_RIGHT, e.BTN_MIDDLE}
    assert mouse.codes[e.EV_REL] == {e.REL_X, e.REL_Y, e.REL_WHEEL, e.REL_WHEEL_HI_RES}
    assert pen.absinfo[e.ABS_X] == AbsInfo(0, 0, 15200, 4, 0, 100)
    assert pen.properties == {e.INPUT_PROP_POINTER}
    assert pen.device_id.name == "Wacom Intuos S Pen" and pen.device_id.path == "/dev/input/event7"


def test_evdev_events_in_order_and_libinput_events_skipped():
    mouse, pen = read_libinput_record(RECORD)
    assert mouse.events == [(0.0, e.EV_MSC, e.MSC_SCAN, 589825), (0.0, e.EV_KEY, e.BTN_LEFT, 1),
                            (0.0, e.EV_SYN, e.SYN_REPORT, 0), (0.008012, e.EV_REL, e.REL_X, -2),
                            (0.008012, e.EV_REL, e.REL_WHEEL_HI_RES, 120), (0.008012, e.EV_SYN, e.SYN_REPORT, 0)]
    assert pen.events == [(1.5, e.EV_ABS, e.ABS_X, 7600), (1.5, e.EV_SYN, e.SYN_REPORT, 0)]


def test_a_path_works_and_the_events_drive_the_semantics(tmp_path):
    from pixelpen.devices.hid.evdev import EvdevSemantics
    from pixelpen.devices.hid.events import Button, Motion, Wheel

    path = tmp_path / "mouse.yml"
    path.write_text(RECORD)
    mouse, _ = read_libinput_record(path)
    sem = EvdevSemantics(mouse.device_id, mouse.absinfo)
    events = sem.feed_events(mouse.events)
    assert [type(x) for x in events] == [Button, Motion, Wheel]
    assert (events[1].dx, events[2].vertical) == (-2, 1.0)


@pytest.mark.parametrize(("text", "where"), [
    ("version: 2\ndevices: []\n", "version: expected 1"),
    ("- 1\n- 2\n", "the file is not a mapping"),
    ("version: 1\ndevices: []\n", "no device"),
    ("version: 1\ndevices: {a: 1}\n", "devices is not a list"),
    ("version: 1\ndevices:\n- evdev: {id: [3, 1, 2, 3]}\n", r"devices\[0\]: evdev.name"),
    ("version: 1\ndevices:\n- evdev: {name: x, id: [3, 1, 2]}\n", "evdev.id: expected"),
    ("version: 1\ndevices:\n- evdev: {name: x, id: [3, 70000, 2, 3]}\n", r"evdev.id\[1\]"),
    ("version: 1\ndevices:\n- evdev: {name: x, id: [true, 1, 2, 3]}\n", r"evdev.id\[0\]"),
    ("version: 1\ndevices:\n- evdev: {name: x, id: [3, 1, 2, 3], codes: {2: [16]}}\n", r"evdev.codes.2\[0\]"),
    ("version: 1\ndevices:\n- evdev: {name: x, id: [3, 1, 2, 3], codes: {40: [1]}}\n", "event type"),
    ("version: 1\ndevices:\n- evdev: {name: x, id: [3, 1, 2, 3], absinfo: {0: [0, 1]}}\n", "absinfo.0: expected"),
    ("version: 1\ndevices:\n- evdev: {name: x, id: [3, 1, 2, 3]}\n  events: [{evdev: [[0, 0, 0, 0]]}]\n",
     r"events\[0\].evdev\[0\]: expected"),
    ("version: 1\ndevices:\n- evdev: {name: x, id: [3, 1, 2, 3]}\n  events: [{evdev: [[0, 1000000, 0, 0, 0]]}]\n",
     "microseconds"),
    ("version: 1\ndevices:\n- evdev: {name: x, id: [3, 1, 2, 3]}\n  events: [{evdev: [[0, 0, 0, 0, 1.5]]}]\n",
     "value"),
    ("version: 1\ndevices:\n- evdev: {name: x, id: [3, 1, 2, 3]}\n"
     "  events: [{evdev: [[1, 0, 0, 0, 0], [0, 0, 0, 0, 0]]}]\n", "backwards"),
    ("version: 1\ndevices: [\n", "not YAML"),
    ("a: &x [1]\nb: *x\n", "alias"),
])
def test_malformed_files_say_where(text, where):
    with pytest.raises(ParseError, match=where):
        read_libinput_record(text, source="bad.yml")


def test_error_names_the_source_and_yaml_line():
    with pytest.raises(ParseError, match=r"bad.yml, line 4: not YAML"):
        read_libinput_record("version: 1\ndevices:\n  - [\n  :\n", source="bad.yml")


def test_limits_bound_events_and_size():
    with pytest.raises(ParseError, match="more events than the limit"):
        read_libinput_record(RECORD, limits=Limits(events=5))
    with pytest.raises(ParseError, match="byte limit"):
        read_libinput_record(RECORD, limits=Limits(file_bytes=100))


def test_huge_number_is_a_clean_error():
    with pytest.raises(ParseError, match="cannot be read"):
        read_libinput_record("version: " + "9" * 5000 + "\n")


def test_deep_nesting_is_a_clean_error():
    with pytest.raises(ParseError, match="line 2: more than 64 brackets"):
        read_libinput_record("version: 1\ndevices: " + "[" * 5000 + "\n")
    with pytest.raises(ParseError, match="nested too deeply"):  # block nesting, one level a line
        read_libinput_record("version: 1\ndevices:\n" + "".join(" " * i + "-\n" for i in range(2000)))


def _target(data: bytes) -> object:
    return read_libinput_record(data, limits=Limits(events=10_000, file_bytes=1 << 20))


def test_fuzzed_files_give_clean_errors():
    campaign("libinput-record", _target, [RECORD.encode()], QUICK_CASES // 10, seed=5).check()


@pytest.mark.slow
def test_fuzzed_files_give_clean_errors_long_campaign():
    campaign("libinput-record", _target, [RECORD.encode()], SLOW_CASES,
             seed=random.Random(517).randrange(10**6)).check()

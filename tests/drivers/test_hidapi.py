"""HidapiLink and enumeration against hand-written stand-ins of cython-hidapi: the buffers hidapi.h prescribes.

hidapi.h: ``hid_write`` — "The first byte of data[] must contain the Report ID. For devices which only support
a single report, this must be set to 0x0"; ``hid_get_feature_report`` — "Upon return, the first byte will still
contain the Report ID"; ``hid_read`` — "If the device has multiple reports, the first byte returned will be the
report number".  cython-hidapi: ``read(n, 0)`` calls the blocking ``hid_read``; a failed read raises
``IOError('read error')``; ``write`` returns -1 on failure.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.clock import SimulatedClock
from pixelpen.drivers import hidapi
from pixelpen.drivers.hidapi import (
    READ_SLICE,
    HidapiLink,
    HidInfo,
    enumerate_hid,
    numbered_reports,
    open_hid,
    parse_hid_spec,
    short_items,
    top_level_usages,
)
from pixelpen.drivers.recordings.hidrecorder import HidRecording
from pixelpen.drivers.recordings.umockdev import encode_script_data, export_umockdev
from pixelpen.drivers.reports import ReportLink
from pixelpen.errors import (
    ConfigError,
    Disconnected,
    InvalidArgument,
    LinkError,
    LinkTimeout,
    ParseError,
    ProtocolError,
)
from pixelpen.sim.hid.descriptors import BOOT_KEYBOARD, BOOT_MOUSE, TRACKBALL

# a keyboard and a consumer-control collection in one descriptor (two top-level collections, numbered 1 and 2)
COMPOSITE = bytes([
    0x05, 0x01, 0x09, 0x06, 0xA1, 0x01,  # Usage Page (Generic Desktop), Usage (Keyboard), Collection (Application)
    0x85, 0x01, 0x05, 0x07, 0x19, 0xE0, 0x29, 0xE7, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02,
    0xC0,
    0x05, 0x0C, 0x09, 0x01, 0xA1, 0x01,  # Usage Page (Consumer), Usage (Consumer Control), Collection (Application)
    0x85, 0x02, 0x09, 0xE9, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01, 0x81, 0x02, 0x75, 0x07, 0x81, 0x01,
    0xC0,
])


class StubDevice:
    """A cython-hidapi ``device`` that records what it is given and answers from lists."""

    def __init__(self, descriptor: bytes = BOOT_MOUSE, reads=(), clock=None, nonblocking=True):
        self.descriptor = descriptor
        self.reads = list(reads)
        self.clock = clock
        self.timeouts: list[int] = []
        self.written: list[bytes] = []
        self.features_sent: list[bytes] = []
        self.feature_requests: list[tuple[int, int]] = []
        self.feature_answer: list[int] = []
        self.write_result: int | None = None
        self.last_error = ""
        self.closed = 0
        if not nonblocking:
            self.set_nonblocking = None  # an old fake without it: the link must never pass 0

    def set_nonblocking(self, v):
        return 0

    def read(self, max_length, timeout_ms=0):
        self.timeouts.append(timeout_ms)
        if self.reads:
            item = self.reads.pop(0)
            if isinstance(item, BaseException):
                raise item
            if item:
                return list(item)
        if self.clock is not None:
            self.clock.advance(timeout_ms / 1000)
        return []

    def write(self, buff):
        self.written.append(bytes(buff))
        return len(buff) if self.write_result is None else self.write_result

    def send_feature_report(self, buff):
        self.features_sent.append(bytes(buff))
        return len(buff) if self.write_result is None else self.write_result

    def get_feature_report(self, report_num, max_length):
        self.feature_requests.append((report_num, max_length))
        if self.last_error:
            raise OSError("read error")
        return list(self.feature_answer)

    def get_report_descriptor(self):
        return list(self.descriptor)

    def error(self):
        return self.last_error or "Success"

    def close(self):
        self.closed += 1


def link(device: StubDevice, clock=None, path="/dev/hidraw7") -> HidapiLink:
    return HidapiLink(device, HidInfo(path, 0x1234, 0x5678), clock=clock or SimulatedClock())


# ---- descriptor facts ------------------------------------------------------------------------------

def test_short_items_of_the_boot_mouse_start_as_written():
    items = list(short_items(BOOT_MOUSE))
    assert items[:3] == [(0, 0x04, 1, 0x01), (2, 0x08, 1, 0x02), (4, 0xA0, 1, 0x01)]
    assert items[-1] == (49, 0xC0, 0, 0)


def test_numbered_reports_needs_a_report_id_item():
    assert not numbered_reports(BOOT_MOUSE)
    assert numbered_reports(TRACKBALL)
    assert numbered_reports(bytes([0xFE, 0x02, 0xF0, 0xAA, 0xBB, 0x85, 0x01]))  # after a long item
    assert not numbered_reports(bytes([0xFE, 0x02, 0xF0, 0x85, 0x01]))  # 85 01 is the long item's data
    assert not numbered_reports(bytes([0xF1, 0x02, 0x00, 0x85, 0x01]))  # any tag-15 prefix is a long item (kernel)


def test_top_level_usages_one_per_application_collection():
    assert top_level_usages(BOOT_MOUSE) == [(0x01, 0x02)]  # the Physical collection inside does not count
    assert top_level_usages(COMPOSITE) == [(0x01, 0x06), (0x0C, 0x01)]
    assert top_level_usages(bytes([0x0B, 0x02, 0x00, 0x0D, 0x00, 0xA1, 0x01, 0xC0])) == [(0x0D, 0x02)]  # extended


@given(st.binary(max_size=300))
def test_descriptor_walk_never_fails_on_any_bytes(data):
    offsets = [offset for offset, *_ in short_items(data)]
    assert offsets == sorted(set(offsets)) and all(o < len(data) for o in offsets)
    numbered_reports(data)
    top_level_usages(data)


# ---- specs -------------------------------------------------------------------------------------------

def test_spec_forms():
    assert parse_hid_spec("046d:c52b") == hidapi.HidSpec(vendor_id=0x046D, product_id=0xC52B)
    assert parse_hid_spec("046D:C52B:0123ABC@2") == hidapi.HidSpec(None, 0x046D, 0xC52B, "0123ABC", 2)
    assert parse_hid_spec("0x46d:0xc52b@0").interface == 0
    for path in ("/dev/hidraw3", "1-2.3:1.0", "sim:mouse:0", "IOService:/XHC@14000000"):
        assert parse_hid_spec(path) == hidapi.HidSpec(path=path)


@pytest.mark.parametrize(("spec", "field", "offset"), [
    ("046d:xyz", "product ID", 5),
    ("046d:", "product ID", 5),
    ("046d:c52b:", "serial number", 10),
    ("046d:c52b@one", "interface", 10),
    ("046d:c52b@300", "interface", 10),
    ("  ", "empty", 0),
])
def test_spec_errors_name_the_field_and_offset(spec, field, offset):
    with pytest.raises(ParseError) as info:
        parse_hid_spec(spec)
    assert field in str(info.value) and info.value.offset == offset


# ---- enumeration -------------------------------------------------------------------------------------

class StubModule:
    def __init__(self, entries, device=None):
        self.entries = entries
        self.asked: list[tuple[int, int]] = []
        self._device = device or StubDevice()
        self.opened: list[bytes] = []

    def enumerate(self, vendor_id=0, product_id=0):
        self.asked.append((vendor_id, product_id))
        return [dict(e) for e in self.entries]  # this stub ignores the IDs: the filters must still hold

    def device(self):
        module = self

        class Opener:
            def __getattr__(self, name):
                return getattr(module._device, name)

            def open_path(self, path):
                module.opened.append(path)
                if getattr(module, "refuse", False):
                    raise OSError("open failed")

        return Opener()


def entry(path, vid, pid, serial="", page=1, usage=2, interface=0, bus=1):
    return {"path": path, "vendor_id": vid, "product_id": pid, "serial_number": serial, "release_number": 0x0111,
            "manufacturer_string": "Maker", "product_string": "Thing", "usage_page": page, "usage": usage,
            "interface_number": interface, "bus_type": bus}


ENTRIES = [
    entry(b"/dev/hidraw0", 0x046D, 0xC52B, "AAA", 1, 6, 0),
    entry(b"/dev/hidraw0", 0x046D, 0xC52B, "AAA", 0x0C, 1, 0),
    entry(b"/dev/hidraw1", 0x046D, 0xC52B, "AAA", 1, 2, 1),
    entry(b"/dev/hidraw2", 0x046D, 0xC52B, "BBB", 1, 2, 1),
    entry(b"/dev/hidraw3", 0x056A, 0x0357, "", 0x0D, 2, 0, bus=2),
]


def test_enumerate_filters_each_field():
    module = StubModule(ENTRIES)
    paths = lambda **f: [i.path for i in enumerate_hid(module=module, **f)]
    assert paths(vendor_id=0x046D, product_id=0xC52B, usage_page=1, usage=2) == ["/dev/hidraw1", "/dev/hidraw2"]
    assert paths(usage_page=0x0C) == ["/dev/hidraw0"]
    assert paths(serial="BBB") == ["/dev/hidraw2"]
    assert paths(interface=0, vendor_id=0x056A) == ["/dev/hidraw3"]
    assert module.asked[0] == (0x046D, 0xC52B)  # hidapi is asked with the IDs (0 = any)
    with pytest.raises(InvalidArgument, match="vendor_id"):
        enumerate_hid(module=module, vendor_id=0x10000)


def test_hid_info_and_its_device_id():
    info = HidInfo.from_dict(ENTRIES[4])
    assert info.bus == "bluetooth" and info.raw_path == b"/dev/hidraw3" and info.usage_page == 0x0D
    device = info.device_id
    assert device.key == "bluetooth:056a:0357::0" and device.path == "/dev/hidraw3" and device.name == "Thing"


def test_unknown_backend_is_a_config_error():
    with pytest.raises(ConfigError, match="libusb"):
        enumerate_hid(backend="serial")


# ---- open --------------------------------------------------------------------------------------------

def test_open_by_ids_serial_and_interface_opens_that_path():
    module = StubModule(ENTRIES)
    assert open_hid("046d:c52b:BBB", module=module).info.path == "/dev/hidraw2"
    assert open_hid("046d:c52b@1", module=module).info.path == "/dev/hidraw1"
    assert open_hid("/dev/hidraw3", module=module).info.vendor_id == 0x056A
    assert module.opened == [b"/dev/hidraw2", b"/dev/hidraw1", b"/dev/hidraw3"]


def test_open_of_nothing_matching_lists_what_is_there():
    module = StubModule(ENTRIES)
    with pytest.raises(LinkError, match=r"no HID device matches '046d:c52b:CCC'.*hidraw0"):
        open_hid("046d:c52b:CCC", module=module)
    with pytest.raises(LinkError, match=r"none with these IDs \(present: 046d:c52b, 056a:0357\)"):
        open_hid("1234:5678", module=module)


def test_refused_open_of_a_node_gives_the_permission_diagnosis(monkeypatch):
    module = StubModule(ENTRIES)
    module.refuse = True
    asked = []
    monkeypatch.setattr(hidapi.os, "access", lambda path, mode: False)
    monkeypatch.setattr(hidapi, "permission_diagnosis",
                        lambda path, **kw: asked.append((path, kw)) or "NO RULE FOR IT")
    with pytest.raises(LinkError, match="NO RULE FOR IT"):
        open_hid("046d:c52b:BBB", module=module)
    assert asked[0][0] == "/dev/hidraw2"
    assert (asked[0][1]["vendor_id"], asked[0][1]["product_id"]) == (0x046D, 0xC52B)


def test_refused_open_of_an_accessible_node_keeps_hidapis_words(monkeypatch):
    module = StubModule(ENTRIES)
    module.refuse = True
    monkeypatch.setattr(hidapi.os, "access", lambda path, mode: True)
    with pytest.raises(LinkError, match="hidapi: open failed"):
        open_hid("/dev/hidraw0", module=module)


# ---- report-ID rules ---------------------------------------------------------------------------------

def test_the_link_is_a_report_link():
    assert isinstance(link(StubDevice()), ReportLink)


def test_unnumbered_write_gets_hidapis_leading_zero():
    device = StubDevice(BOOT_MOUSE)
    hl = link(device)
    hl.write_report(b"\x05")
    hl.send_feature(b"\x01\x02")
    assert device.written == [b"\x00\x05"] and device.features_sent == [b"\x00\x01\x02"]


def test_numbered_write_goes_as_is_and_refuses_id_zero():
    device = StubDevice(TRACKBALL)
    hl = link(device)
    hl.write_report(b"\x03\x01")
    hl.send_feature(b"\x02\x04")
    assert device.written == [b"\x03\x01"] and device.features_sent == [b"\x02\x04"]
    with pytest.raises(InvalidArgument, match=r"report ID 1\.\.255"):
        hl.write_report(b"\x00\x01")


def test_unnumbered_feature_comes_back_without_hidapis_zero():
    device = StubDevice(BOOT_MOUSE)
    device.feature_answer = [0x00, 0x10, 0x20]  # hidapi: report ID 0 kept in byte 0
    assert link(device).get_feature(0) == b"\x10\x20"
    assert device.feature_requests[0][0] == 0
    with pytest.raises(InvalidArgument, match="only feature report is ID 0"):
        link(device).get_feature(2)


def test_numbered_feature_keeps_its_id():
    device = StubDevice(TRACKBALL)
    device.feature_answer = [0x02, 0x01]
    assert link(device).get_feature(2) == b"\x02\x01"
    with pytest.raises(InvalidArgument, match=r"1\.\.255"):
        link(device).get_feature(0)


def test_reads_pass_reports_through():
    assert link(StubDevice(BOOT_MOUSE, reads=[[1, 5, 251]])).read_report(1) == b"\x01\x05\xfb"
    assert link(StubDevice(TRACKBALL, reads=[[2, 1]])).read_report(1) == b"\x02\x01"


def test_numbered_can_be_given_when_there_is_no_descriptor():
    device = StubDevice()
    device.get_report_descriptor = None
    hl = HidapiLink(device, HidInfo("x", 1, 2), numbered=True, sysfs="/nonexistent")
    hl.write_report(b"\x01\x02")
    assert device.written == [b"\x01\x02"]
    with pytest.raises(LinkError, match="report descriptor"):
        _ = hl.report_descriptor


# ---- timeouts ---------------------------------------------------------------------------------------

def test_a_timeout_is_waited_in_slices_on_the_clock():
    clock = SimulatedClock()
    device = StubDevice(clock=clock)
    assert link(device, clock).read_report(1.0) is None
    assert clock.now() == pytest.approx(1.0)
    assert all(0 < ms <= READ_SLICE * 1000 for ms in device.timeouts) and len(device.timeouts) == 10


def test_poll_never_blocks():
    device = StubDevice()
    assert link(device).read_report(0) is None
    assert device.timeouts == [0]  # non-blocking handle: 0 returns at once
    blocking = StubDevice(nonblocking=False)
    assert link(blocking).read_report(0) is None
    assert blocking.timeouts == [1]  # a blocking handle never gets 0 (hid_read would wait forever)


def test_a_clock_that_does_not_move_cannot_hang_a_read():
    device = StubDevice()  # never advances the (simulated) clock
    assert link(device).read_report(0.35) is None
    assert len(device.timeouts) == 5  # ceil(0.35 / 0.1) + 1 slices at most


def test_no_timeout_waits_in_slices_until_a_report():
    device = StubDevice(reads=[[]] * 40 + [[7, 0, 0]])
    assert link(device).read_report(None) == b"\x07\x00\x00"
    assert len(device.timeouts) == 41 and set(device.timeouts) == {100}


def test_ctrl_c_inside_a_slice_reaches_the_caller():
    device = StubDevice(reads=[[], KeyboardInterrupt()])
    with pytest.raises(KeyboardInterrupt):
        link(device).read_report(None)


# ---- errors -----------------------------------------------------------------------------------------

def test_read_error_is_disconnected():
    device = StubDevice(reads=[OSError("read error")])
    device.last_error = "hid_read_timeout: unexpected poll error (device disconnected)"
    with pytest.raises(Disconnected, match=r"removed during a read.*device disconnected"):
        link(device).read_report(1)


@pytest.mark.parametrize(("text", "error"), [
    ("No such device", Disconnected), ("Connection timed out", LinkTimeout), ("Broken pipe", ProtocolError),
    ("Invalid argument", LinkError),
])
def test_failed_write_is_mapped_from_hidapis_error(text, error):
    device = StubDevice()
    device.write_result = -1
    device.last_error = text
    with pytest.raises(error, match=text):
        link(device).write_report(b"\x01")


def test_failed_get_feature_stall_is_a_protocol_error():
    device = StubDevice()
    device.last_error = "ioctl (GFEATURE): Broken pipe"
    with pytest.raises(ProtocolError, match="STALL"):
        link(device).get_feature(0)


def test_bad_arguments():
    hl = link(StubDevice())
    with pytest.raises(InvalidArgument, match="empty"):
        hl.write_report(b"")
    with pytest.raises(InvalidArgument, match="exceeds"):
        hl.write_report(bytes(hidapi.MAX_REPORT + 1))
    with pytest.raises(InvalidArgument, match="timeout"):
        hl.read_report(float("nan"))


def test_close_is_idempotent_and_final():
    device = StubDevice()
    hl = link(device)
    hl.close()
    hl.close()
    assert device.closed == 1
    with pytest.raises(LinkError, match="closed"):
        hl.read_report(0)


# ---- descriptor from sysfs --------------------------------------------------------------------------

def test_descriptor_falls_back_to_sysfs_for_hidraw(tmp_path):
    node = tmp_path / "class/hidraw/hidraw7/device"
    node.mkdir(parents=True)
    (node / "report_descriptor").write_bytes(TRACKBALL)
    device = StubDevice()
    device.get_report_descriptor = None  # hidapi < 0.14
    hl = HidapiLink(device, HidInfo("/dev/hidraw7", 1, 2), sysfs=str(tmp_path))
    assert hl.report_descriptor == TRACKBALL and hl.numbered


def test_descriptor_falls_back_to_sysfs_for_a_libusb_path(tmp_path):
    node = tmp_path / "bus/usb/devices/1-2.3:1.0/0003:1234:5678.0004"
    node.mkdir(parents=True)
    (node / "report_descriptor").write_bytes(BOOT_MOUSE)
    device = StubDevice()

    def fails():
        raise OSError("read error")

    device.get_report_descriptor = fails
    hl = HidapiLink(device, HidInfo("1-2.3:1.0", 1, 2), backend="libusb", sysfs=str(tmp_path))
    assert hl.report_descriptor == BOOT_MOUSE and not hl.numbered


# ---- the real hidraw module, against a node umockdev emulates (no root) -----------------------------

REAL_RUN = '''
import sys
from pixelpen.drivers.hidapi import enumerate_hid, open_hid
print(sorted((i.path, i.vendor_id, i.product_id, i.usage_page, i.usage) for i in enumerate_hid()))
link = open_hid(sys.argv[1], max_report=int(sys.argv[2]))
print(link.report_descriptor.hex(), link.numbered, link.device_id.key)
print(link.read_report(2.0).hex())
if link.numbered:
    print(link.read_report(2.0).hex())
else:
    link.write_report(bytes([0x02]))
    print("written")
link.close()
'''


def _umockdev_run(tmp_path, recording, spec, size, writes=b""):
    if shutil.which("umockdev-run") is None:
        pytest.skip("umockdev-run is not installed (Debian: umockdev)")
    pytest.importorskip("hidraw", reason="cython-hidapi's hidraw module is not installed")
    fixture = export_umockdev(recording, tmp_path)
    if writes:
        with open(fixture.data, "ab") as f:  # umockdev checks the bytes the program writes to the node
            f.write(b"w 0 " + encode_script_data(writes) + b"\n")
    script = tmp_path / "run.py"
    script.write_text(REAL_RUN)
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))
    done = subprocess.run(fixture.command(sys.executable, str(script), spec, str(size)), capture_output=True,
                          text=True, timeout=60, env=env, check=False)
    assert done.returncode == 0 and "ERROR" not in done.stderr, done.stderr
    return done.stdout.splitlines()


def test_real_hidraw_unnumbered_reads_and_a_write_with_hidapis_leading_zero(tmp_path):
    keyboard = HidRecording("Keyboard", "usb-0000:00:14.0-3/input0", 3, 0x1209, 0x0007, BOOT_KEYBOARD,
                            [(0.0, bytes([0x02, 0, 0x04, 0, 0, 0, 0, 0]))])  # Left Shift + 'a'
    lines = _umockdev_run(tmp_path, keyboard, "1209:0007", 8, writes=bytes([0x00, 0x02]))
    assert lines[0] == "[('/dev/hidraw0', 4617, 7, 1, 6)]"  # hidraw read usage page/usage from the descriptor
    assert lines[1] == f"{BOOT_KEYBOARD.hex()} False usb:1209:0007::0"
    assert lines[2:] == ["0200040000000000", "written"]  # the node received 00 02 (umockdev checked it)


def test_real_hidraw_numbered_reads_keep_the_id(tmp_path):
    ball = HidRecording("Trackball", "usb-0000:00:14.0-4/input0", 3, 0x1209, 0x0002, TRACKBALL,
                        [(0.0, bytes([0x01, 0x01, 0x10, 0x00, 0xF0, 0xFF])), (0.01, bytes([0x02, 0x01]))])
    lines = _umockdev_run(tmp_path, ball, "/dev/hidraw0", 6)
    assert lines[1].endswith(" True usb:1209:0002::0")
    assert lines[2:] == ["01011000f0ff", "0201"]

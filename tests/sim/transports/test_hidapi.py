"""SimHidapi: cython-hidapi's module API over HidSim simulators, and the real HidapiLink running on it.

Expected buffers follow hidapi.h (report ID first on write and feature reports, 0x00 for unnumbered devices;
``hid_get_feature_report`` keeps the ID in byte 0; ``hid_read`` has the ID only when numbered) and the hidraw
backend (one enumeration entry per top-level collection; a removed device's read fails with "read error").
Reports are packed by hand from the layouts in pixelpen/sim/hid/descriptors.py.
"""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.clock import SimulatedClock
from pixelpen.drivers.hidapi import enumerate_hid, open_hid
from pixelpen.errors import ConfigError, Disconnected, LinkError, ProtocolError
from pixelpen.sim.base import Fault
from pixelpen.sim.hid.descriptors import BOOT_KEYBOARD, BOOT_MOUSE, TRACKBALL
from pixelpen.sim.hid.device import HidSim
from pixelpen.sim.transports.hidapi import SimHidapi
from tests.drivers.test_hidapi import COMPOSITE

MOUSE_INFO = {"vendor_id": 0x1234, "product_id": 0x0001, "serial_number": "M1", "product_string": "Sim Mouse"}
# boot mouse: byte 0 buttons, byte 1 X int8, byte 2 Y int8
MOVES = [(0.5, bytes([0x01, 0x05, 0xFB])), (1.0, bytes([0x00, 0x00, 0x00]))]
# trackball report 1: ID, buttons (5 bits + 3 padding), X int16 LE, Y int16 LE
BALL = [(0.25, bytes([0x01, 0x02, 0x10, 0x00, 0xF0, 0xFF]))]


def mouse(clock, reports=MOVES, info=MOUSE_INFO):
    return HidSim.from_descriptor(BOOT_MOUSE, reports, clock=clock, model="mouse", info=info)


def trackball(clock, reports=BALL):
    return HidSim.from_descriptor(TRACKBALL, reports, clock=clock, model="trackball",
                                  info={"vendor_id": 0x1234, "product_id": 0x0002})


def opened(bus, path):
    handle = bus.device()
    handle.open_path(path.encode())
    return handle


# ---- the raw module API ------------------------------------------------------------------------------

def test_enumerate_lists_each_top_level_collection():
    clock = SimulatedClock()
    composite = HidSim.from_descriptor(COMPOSITE, clock=clock, model="combo", info={"vendor_id": 0x1234,
                                                                                     "product_id": 0x0003})
    bus = SimHidapi([mouse(clock), composite])
    entries = bus.enumerate()
    assert [(e["path"], e["usage_page"], e["usage"]) for e in entries] == [
        (b"sim:mouse:0", 1, 2), (b"sim:combo:1", 1, 6), (b"sim:combo:1", 0x0C, 1)]
    assert entries[0]["serial_number"] == "M1" and entries[0]["bus_type"] == 5  # virtual unless info says
    assert [e["path"] for e in bus.enumerate(0x1234, 0x0003)] == [b"sim:combo:1"] * 2
    assert bus.enumerate(0x9999) == []


def test_open_and_open_path_as_hidapi():
    clock = SimulatedClock()
    bus = SimHidapi([mouse(clock)])
    handle = bus.device()
    handle.open(0x1234, 0x0001, "M1")
    assert handle.get_product_string() == "Sim Mouse" and handle.get_serial_number_string() == "M1"
    with pytest.raises(RuntimeError, match="already open"):
        handle.open_path(b"sim:mouse:0")
    with pytest.raises(OSError, match="open failed"):
        bus.device().open(0x1234, 0x0001, "other")
    with pytest.raises(TypeError, match="bytes"):
        bus.device().open_path("sim:mouse:0")
    with pytest.raises(ValueError, match="not open"):
        bus.device().read(64, 10)


def test_unnumbered_write_strips_the_zero_and_refuses_another_first_byte():
    clock = SimulatedClock()
    keyboard = HidSim.from_descriptor(BOOT_KEYBOARD, clock=clock, model="keyboard")
    handle = opened(SimHidapi([keyboard]), "sim:keyboard:0")
    assert handle.write([0x00, 0x02]) == 2  # report ID 0 + the LED byte (Caps Lock)
    assert keyboard.firmware.outputs[0] == b"\x02"
    assert handle.write([0x02]) == -1 and handle.error() == "Broken pipe"
    assert handle.write([]) == -1 and handle.error() == "Zero buffer/length"


def test_numbered_write_keeps_the_id_and_refuses_zero():
    clock = SimulatedClock()
    ball = trackball(clock)
    handle = opened(SimHidapi([ball]), "sim:trackball:0")
    assert handle.send_feature_report([0x03, 0x01]) == 2
    assert handle.get_feature_report(3, 64) == [0x03, 0x01]  # the ID stays in byte 0
    assert handle.write([0x00, 0x01]) == -1 and handle.error() == "Broken pipe"


def test_unnumbered_feature_comes_back_behind_id_zero():
    clock = SimulatedClock()
    sim = mouse(clock)
    handle = opened(SimHidapi([sim]), "sim:mouse:0")
    assert handle.send_feature_report([0x00, 0xAA, 0xBB]) == 3
    assert sim.firmware.feature(0) == b"\xaa\xbb"
    assert handle.get_feature_report(0, 64) == [0x00, 0xAA, 0xBB]
    assert handle.get_feature_report(0, 2) == [0x00, 0xAA]  # cut to max_length
    with pytest.raises(OSError, match="read error"):
        handle.get_feature_report(5, 64)


def test_a_feature_the_device_lacks_stalls():
    clock = SimulatedClock()
    handle = opened(SimHidapi([trackball(clock)]), "sim:trackball:0")
    with pytest.raises(OSError, match="read error"):
        handle.get_feature_report(7, 64)
    assert handle.error() == "ioctl (GFEATURE): Broken pipe"


def test_reads_have_the_id_only_when_numbered_and_are_cut_to_max_length():
    clock = SimulatedClock()
    bus = SimHidapi([mouse(clock), trackball(clock)])
    plain, ball = opened(bus, "sim:mouse:0"), opened(bus, "sim:trackball:1")
    assert ball.read(3, 1000) == [0x01, 0x02, 0x10]
    assert plain.read(64, 1000) == [0x01, 0x05, 0xFB]


def test_a_read_waits_for_the_next_report_or_the_timeout_on_the_clock():
    clock = SimulatedClock()
    handle = opened(SimHidapi([mouse(clock)]), "sim:mouse:0")
    assert handle.read(64, 200) == [] and clock.now() == pytest.approx(0.2)
    assert handle.read(64, 1000) == [0x01, 0x05, 0xFB] and clock.now() == pytest.approx(0.5)
    handle.set_nonblocking(1)
    assert handle.read(64, 0) == [] and clock.now() == pytest.approx(0.5)  # a poll takes no time
    handle.set_nonblocking(0)
    assert handle.read(64) == [0x00, 0x00, 0x00] and clock.now() == pytest.approx(1.0)  # blocks until it comes


def test_reports_sent_before_the_open_are_not_read():
    clock = SimulatedClock()
    bus = SimHidapi([mouse(clock)])
    clock.advance(0.7)  # the first move (0.5 s) went out while nobody had the node open
    assert opened(bus, "sim:mouse:0").read(64, 1000) == [0x00, 0x00, 0x00]


def test_a_report_sent_at_the_instant_of_the_open_is_read():
    clock = SimulatedClock()
    bus = SimHidapi([mouse(clock, reports=[(0.0, bytes([0x01, 0x02, 0x03])), *MOVES])])
    assert opened(bus, "sim:mouse:0").read(64, 0) == [0x01, 0x02, 0x03]  # a replay's first report, at t = 0


def test_every_open_handle_gets_every_report():
    clock = SimulatedClock()
    bus = SimHidapi([mouse(clock)])
    first, second = opened(bus, "sim:mouse:0"), opened(bus, "sim:mouse:0")
    assert first.read(64, 2000) == [0x01, 0x05, 0xFB]
    assert second.read(64, 0) == [0x01, 0x05, 0xFB]  # already there: the same report for the second reader
    first.close()
    assert second.read(64, 2000) == [0x00, 0x00, 0x00]


STREAM = [(i / 100, bytes([i, 0, 0])) for i in range(1, 101)]  # report i carries i in byte 0


@pytest.mark.parametrize(("backend", "kept"), [("hidraw", list(range(1, 64))), ("libusb", list(range(69, 101)))])
def test_a_slow_reader_loses_reports_as_each_backend_does(backend, kept):
    clock = SimulatedClock()
    bus = SimHidapi([mouse(clock, reports=STREAM)], backend=backend)
    handle = opened(bus, "sim:mouse:0")
    handle.set_nonblocking(1)
    clock.advance(2.0)  # nobody reads while all 100 arrive
    got = []
    while report := handle.read(64, 0):
        got.append(report[0])
    assert got == kept  # hidraw: its ring of 64 holds 63, the arriving ones are dropped; libusb: the last 32


def test_a_blocking_read_with_nothing_to_come_raises_instead_of_hanging():
    clock = SimulatedClock()
    handle = opened(SimHidapi([mouse(clock, reports=[])]), "sim:mouse:0")
    with pytest.raises(RuntimeError, match="wait forever"):
        handle.read(64)


def test_unplug_kills_the_handle_and_replug_gets_a_new_path():
    clock = SimulatedClock()
    sim = mouse(clock)
    bus = SimHidapi([sim])
    handle = opened(bus, "sim:mouse:0")
    bus.unplug("sim:mouse:0")
    with pytest.raises(OSError, match="read error"):
        handle.read(64, 100)
    assert "device disconnected" in handle.error()
    assert handle.write([0, 1]) == -1 and handle.error() == "No such device"
    assert bus.enumerate() == []
    assert bus.plug(mouse(clock)) == "sim:mouse:1"


def test_power_loss_looks_like_removal():
    clock = SimulatedClock()
    sim = mouse(clock)
    bus = SimHidapi([sim])
    handle = opened(bus, "sim:mouse:0")
    sim.inject(Fault.POWER_LOSS)
    assert bus.enumerate() == []
    with pytest.raises(OSError, match="read error"):
        handle.read(64, 100)
    sim.inject(Fault.POWER_RESTORE)
    assert bus.paths() == ["sim:mouse:0"]
    with pytest.raises(OSError):
        handle.read(64, 100)  # the old handle stays dead


# ---- HidapiLink unchanged on the fake -----------------------------------------------------------------

def test_link_reads_reports_and_times_out_on_the_fake_clock():
    clock = SimulatedClock()
    bus = SimHidapi([mouse(clock), trackball(clock)])
    link = open_hid("1234:0001:M1", module=bus, clock=clock)
    ball = open_hid("sim:trackball:1", module=bus, clock=clock)
    assert link.report_descriptor == BOOT_MOUSE and not link.numbered
    assert link.read_report(0.1) is None and clock.now() == pytest.approx(0.1)
    assert link.read_report(5) == b"\x01\x05\xfb" and clock.now() == pytest.approx(0.5)
    assert link.read_report(None) == b"\x00\x00\x00"
    assert link.read_report(2) is None and clock.now() == pytest.approx(3.0)
    assert link.device_id.key == "virtual:1234:0001:M1:0" and link.device_id.path == "sim:mouse:0"
    assert ball.numbered and ball.read_report(0) == bytes([0x01, 0x02, 0x10, 0x00, 0xF0, 0xFF])


def test_a_tiny_timeout_still_brings_the_clock_to_its_deadline():
    clock = SimulatedClock()
    link = open_hid("1234:0001:M1", module=SimHidapi([mouse(clock)]), clock=clock)
    clock.advance(0.1)
    for tiny in (1e-14, 1e-9, 5e-7):  # under the driver's rounding to whole milliseconds
        start = clock.now()
        assert link.read_report(tiny) is None
        assert clock.now() == pytest.approx(start + tiny, abs=1e-15)  # a caller looping to a deadline gets there


@pytest.mark.timeout(60)
def test_a_link_read_without_timeout_on_a_finished_device_raises_instead_of_spinning():
    clock = SimulatedClock()
    link = open_hid("1234:0001:M1", module=SimHidapi([mouse(clock)]), clock=clock)
    assert link.read_report(None) == b"\x01\x05\xfb" and link.read_report(None) == b"\x00\x00\x00"
    with pytest.raises(RuntimeError, match="would wait forever"):
        link.read_report(None)  # HidapiLink waits in 0.1 s slices; the fake sees an hour of them with nothing due
    assert link.read_report(5.0) is None  # a read with a timeout still just times out


def test_a_recording_out_of_order_is_a_config_error_through_the_link():
    clock = SimulatedClock()
    sim = mouse(clock, reports=[(1.0, bytes([1, 5, 0xFD])), (0.5, bytes(3))])
    link = open_hid("1234:0001:M1", module=SimHidapi([sim]), clock=clock)
    with pytest.raises(ConfigError, match=r"report 1 at 0\.5 s comes before report 0"):
        link.read_report(2.0)


def test_link_feature_round_trip_numbered_and_not():
    clock = SimulatedClock()
    bus = SimHidapi([mouse(clock), trackball(clock)])
    plain = open_hid("sim:mouse:0", module=bus, clock=clock)
    plain.send_feature(b"\x11\x22")
    assert plain.get_feature(0) == b"\x11\x22"
    ball = open_hid("sim:trackball:1", module=bus, clock=clock)
    ball.send_feature(b"\x03\x01")
    assert ball.get_feature(3) == b"\x03\x01"
    with pytest.raises(ProtocolError, match="STALL"):
        ball.get_feature(9)


def test_link_output_report_reaches_the_keyboard():
    clock = SimulatedClock()
    keyboard = HidSim.from_descriptor(BOOT_KEYBOARD, clock=clock, model="keyboard")
    link = open_hid("sim:keyboard:0", module=SimHidapi([keyboard]), clock=clock)
    link.write_report(b"\x01")  # Num Lock
    assert keyboard.firmware.outputs[0] == b"\x01"


class UnplugClock(SimulatedClock):
    """A simulated clock that unplugs a device when time reaches ``at`` (the hand pulls the cable mid-read)."""

    def __init__(self, at):
        super().__init__()
        self.at = at
        self.device = None

    def advance(self, seconds):
        super().advance(seconds)
        if self.device is not None and self.now() >= self.at:
            self.device.close()


def test_unplug_during_a_read_is_disconnected_within_the_timeout():
    clock = UnplugClock(at=0.35)
    sim = mouse(clock, reports=[(5.0, b"\x00\x00\x00")])
    clock.device = sim
    link = open_hid("sim:mouse:0", module=SimHidapi([sim]), clock=clock)
    with pytest.raises(Disconnected, match="removed during a read"):
        link.read_report(2.0)
    assert 0.35 <= clock.now() <= 0.35 + 0.1 + 1e-9  # noticed within the slice the unplug fell in


def test_unplug_during_a_read_without_timeout_is_disconnected_too():
    clock = UnplugClock(at=1.0)
    sim = mouse(clock, reports=[])
    clock.device = sim
    link = open_hid("sim:mouse:0", module=SimHidapi([sim]), clock=clock)
    with pytest.raises(Disconnected):
        link.read_report(None)
    assert clock.now() <= 1.0 + 0.1 + 1e-9  # at most one slice after the unplug


def test_enumerate_hid_filters_on_the_fake():
    clock = SimulatedClock()
    bus = SimHidapi([mouse(clock), trackball(clock)])
    assert [i.path for i in enumerate_hid(module=bus, product_id=0x0002)] == ["sim:trackball:1"]
    assert [i.path for i in enumerate_hid(module=bus, usage_page=1, usage=2)] == ["sim:mouse:0", "sim:trackball:1"]


# ---- the same API as the real modules ----------------------------------------------------------------

@pytest.mark.parametrize("name", ["hid", "hidraw"])
def test_the_fake_has_every_method_of_the_real_module(name):
    real = pytest.importorskip(name, reason=f"cython-hidapi's {name} module is not installed")
    public = {n for n in dir(real.device) if not n.startswith("_")}
    assert public <= {n for n in dir(SimHidapi().device()) if not n.startswith("_")}
    assert {"enumerate", "device", "version_str"} <= set(dir(SimHidapi()))


@pytest.mark.parametrize("backend", ["hidraw", "libusb"])
def test_the_real_modules_enumerate_and_refuse_a_missing_path(backend):
    pytest.importorskip("hidraw" if backend == "hidraw" else "hid", reason="cython-hidapi is not installed")
    found = enumerate_hid(backend=backend)  # whatever this machine has: a list of HidInfo, no exception
    assert all(info.path for info in found)
    with pytest.raises(LinkError, match="no HID device at '/dev/hidraw-none'"):
        open_hid("/dev/hidraw-none", backend=backend)


@given(st.binary(min_size=1, max_size=64), st.booleans())
def test_any_report_reaches_the_device_unchanged_through_link_and_fake(report, numbered):
    clock = SimulatedClock()
    descriptor = TRACKBALL if numbered else BOOT_KEYBOARD
    if numbered and report[0] == 0:
        report = b"\x01" + report[1:]
    sim = HidSim.from_descriptor(descriptor, clock=clock, model="dev")
    link = open_hid("sim:dev:0", module=SimHidapi([sim]), clock=clock)
    link.write_report(report)
    link.send_feature(report)
    rid = report[0] if numbered else 0
    assert sim.firmware.outputs[rid] == report and link.get_feature(rid) == report


def test_a_plotter_simulator_cannot_be_plugged_in_as_a_hid_device():
    from pixelpen.sim.base import create_simulator

    plotter = create_simulator("hp7475a", clock=SimulatedClock())
    with pytest.raises(ConfigError, match="hp7475a simulator is reached through a byte stream"):
        SimHidapi([plotter])

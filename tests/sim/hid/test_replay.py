"""Replaying a hid-recorder recording: the recorded reports at the recorded times, on a simulated or the real clock."""

from __future__ import annotations

import importlib.util

import pytest

from pixelpen.clock import REAL_CLOCK, SimulatedClock
from pixelpen.drivers.recordings.hidrecorder import HidRecording, write_hid_recording
from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.sim.hid.descriptors import BOOT_MOUSE, TRACKBALL
from pixelpen.sim.hid.replay import hidapi_info, replay_device

REPORTS = [(0.0, b"\x01\x02\x03"), (0.001, b"\x00\xff\x81"), (0.001, b"\x00\x01\x01"), (2.5, b"\x04\x00\x00")]
MOUSE = HidRecording("Recorded Mouse", "usb-0000:00:14.0-2/input1", 3, 0x046D, 0xC077, BOOT_MOUSE, REPORTS)


def test_reports_come_at_their_recorded_times_on_the_simulated_clock():
    clock = SimulatedClock(100.0)
    sim = replay_device(MOUSE, clock=clock)
    assert sim.report_descriptor == BOOT_MOUSE
    clock.advance(0.0005)  # HidSim runs its events once the clock has moved past its start
    assert sim.take_timed_reports() == [(100.0, b"\x01\x02\x03")]  # sent at its recorded time, not when read
    clock.advance(0.0004)
    assert sim.take_reports() == []
    clock.advance(0.0001)
    assert sim.take_timed_reports() == [(100.001, b"\x00\xff\x81"), (100.001, b"\x00\x01\x01")]
    assert sim.next_event_time() == 102.5
    clock.advance(10.0)
    assert sim.take_reports() == [b"\x04\x00\x00"] and sim.next_event_time() is None and sim.sent == 4


def test_the_default_clock_is_a_fresh_simulated_one_and_realtime_takes_the_real_one():
    fast = replay_device(MOUSE)
    assert isinstance(fast.clock, SimulatedClock) and fast.clock.now() == 0.0
    real = replay_device(MOUSE, realtime=True)
    assert real.clock is REAL_CLOCK
    assert real.take_reports() == [b"\x01\x02\x03"]  # due at once; the others 1 ms and 2.5 s later
    assert real.next_event_time() == pytest.approx(real._origin + 0.001)


def test_a_simulated_clock_cannot_be_real_time_and_a_clock_given_is_used_as_it_is():
    with pytest.raises(InvalidArgument, match="real-time replay needs a real clock"):
        replay_device(MOUSE, clock=SimulatedClock(), realtime=True)
    assert replay_device(MOUSE, clock=REAL_CLOCK).clock is REAL_CLOCK
    with pytest.raises(InvalidArgumentType):
        replay_device(42)  # type: ignore[arg-type]


def test_a_file_with_several_devices_replays_the_one_asked_for(tmp_path):
    ball = HidRecording("Ball", "", 5, 1, 2, TRACKBALL, [(0.5, b"\x02\x01")])
    path = tmp_path / "two.hid"
    write_hid_recording([MOUSE, ball], path)
    clock = SimulatedClock()
    sim = replay_device(path, clock=clock, device=1)
    assert sim.report_descriptor == TRACKBALL and sim.info["product_string"] == "Ball"
    clock.advance(0.5)
    assert sim.take_reports() == [b"\x02\x01"]
    with pytest.raises(InvalidArgument, match=r"no device 2 \(the file holds 2\)"):
        replay_device(path, device=2)


def test_hidapi_lists_the_recorded_identity_and_top_level_usage():
    # BOOT_MOUSE opens with Usage Page (Generic Desktop) Usage (Mouse) Collection (Application): 0x01:0x02
    assert hidapi_info(MOUSE) == {
        "vendor_id": 0x046D, "product_id": 0xC077, "serial_number": "", "release_number": 0,
        "manufacturer_string": "", "product_string": "Recorded Mouse", "usage_page": 1, "usage": 2,
        "interface_number": 1, "bus_type": 1}  # hidapi's HID_API_BUS_USB is 1 (the kernel's BUS_USB is 3)


def test_power_loss_stops_the_replay_and_restore_skips_what_was_missed():
    clock = SimulatedClock()
    sim = replay_device(MOUSE, clock=clock)
    sim.take_reports()
    sim.inject("power-loss")
    clock.advance(0.01)
    assert sim.take_reports() == [] and not sim.connected
    sim.inject("power-restore")
    clock.advance(5.0)
    assert sim.take_reports() == [b"\x04\x00\x00"]


@pytest.mark.skipif(importlib.util.find_spec("pixelpen.sim.transports.hidapi") is None,
                    reason="the hidapi fake (pixelpen.sim.transports.hidapi) is not there yet")
def test_the_real_hidapi_link_reads_the_replay_as_fast_as_it_asks():
    from pixelpen.drivers.hidapi import enumerate_hid, open_hid
    from pixelpen.sim.transports.hidapi import SimHidapi

    clock = SimulatedClock()
    module = SimHidapi([replay_device(MOUSE, clock=clock)])
    (info,) = enumerate_hid(module=module)
    assert (info.vendor_id, info.product_id, info.product, info.usage_page, info.usage) == (
        0x046D, 0xC077, "Recorded Mouse", 1, 2)
    link = open_hid(info.path, module=module, clock=clock)
    got = [link.read_report(10.0) for _ in range(4)]
    assert got == [r for _, r in REPORTS]
    assert clock.now() == pytest.approx(2.5, abs=0.01)  # the reads waited on the simulated clock only
    assert link.read_report(1.0) is None


def test_a_delay_shifts_every_report():
    clock = SimulatedClock()
    sim = replay_device(MOUSE, clock=clock, delay=1.0)
    clock.advance(0.999)
    assert sim.take_reports() == []
    clock.advance(0.002)
    assert sim.take_timed_reports() == [(1.0, b"\x01\x02\x03"), (1.001, b"\x00\xff\x81"), (1.001, b"\x00\x01\x01")]
    with pytest.raises(InvalidArgument):
        replay_device(MOUSE, delay=-1.0)

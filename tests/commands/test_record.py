"""pixelpen record-input: hid-recorder files from a hidapi device (simulated behind the hidapi module API)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import pytest

import pixelpen.drivers.hidapi as hidapi
from pixelpen.cli import main
from pixelpen.clock import SimulatedClock
from pixelpen.drivers.recordings.hidrecorder import HidRecording, read_hid_recording
from pixelpen.sim.base import create_simulator
from pixelpen.sim.hid.descriptors import BOOT_MOUSE, PEN_TABLET
from pixelpen.sim.hid.replay import replay_device
from pixelpen.sim.transports.hidapi import SimHidapi

RECORDED = HidRecording("Old Mouse", "", 3, 0x046D, 0xC077, BOOT_MOUSE,
                        [(0.0, b"\x01\x02\x03"), (0.002, b"\x00\xff\x81"), (0.004, b"\x00\x01\x01")])


def test_a_simulated_device_is_recorded_report_for_report(tmp_path, capsys):
    out = tmp_path / "tablet.hid"
    assert main(["record-input", "sim:tablet?script=signature", "-o", str(out), "--count", "40"]) == 0
    assert "pixelpen record-input: 40 reports from sim:tablet:0" in capsys.readouterr().err
    (rec,) = read_hid_recording(out, strict=True)
    assert rec.descriptor == PEN_TABLET and rec.name == "pixelpen Simulated pen tablet"
    assert rec.reports[0][0] == 0.0 and len(rec.reports) == 40
    assert all(len(r) == 14 and r[0] == 2 for _, r in rec.reports)  # PEN_TABLET's input report 2
    # the same model on a simulated clock sends the same reports (its firmware samples the script at its own
    # ticks): equal up to the pen touching down at 0.2 s, where real clock arithmetic may land a tick off it
    clock = SimulatedClock()
    twin = create_simulator("tablet", clock=clock, script="signature")
    expected: list[bytes] = []
    while len(expected) < 30:
        clock.advance(0.001)
        expected += twin.take_reports()
    assert [r for _, r in rec.reports[:30]] == expected[:30]


def test_a_device_named_by_vid_pid_through_the_hidapi_module(tmp_path, monkeypatch, capsys):
    # hidraw gives a reader only the reports sent after it opened the device: the replay waits 0.3 s for that
    module = SimHidapi([replay_device(RECORDED, realtime=True, delay=0.3)])
    monkeypatch.setattr(hidapi, "hid_module", lambda backend="hidraw": module)
    out = tmp_path / "mouse.hid"
    assert main(["record-input", "046d:c077", "--count", "3", "--duration", "20", "-o", str(out)]) == 0
    (rec,) = read_hid_recording(out)
    assert (rec.vendor_id, rec.product_id, rec.name) == (0x046D, 0xC077, "Old Mouse")
    assert [r for _, r in rec.reports] == [r for _, r in RECORDED.reports]
    times = [t for t, _ in rec.reports]
    assert times[0] == 0.0 and times == sorted(times)
    assert main(["record-input", "--list"]) == 0
    assert "sim:replay:0: Old Mouse 046d:c077" in capsys.readouterr().out


def test_the_duration_ends_a_recording_of_a_device_that_sends_nothing(tmp_path, monkeypatch):
    module = SimHidapi([replay_device(HidRecording("Idle", "", 3, 1, 2, BOOT_MOUSE), realtime=True)])
    monkeypatch.setattr(hidapi, "hid_module", lambda backend="hidraw": module)
    out = tmp_path / "idle.hid"
    assert main(["record-input", "0001:0002", "--duration", "0.05", "-o", str(out)]) == 0
    (rec,) = read_hid_recording(out)
    assert rec.reports == [] and rec.descriptor == BOOT_MOUSE


def test_errors_are_one_line_and_status_2(monkeypatch, capsys):
    monkeypatch.setattr(hidapi, "hid_module", lambda backend="hidraw": SimHidapi([]))
    assert main(["record-input"]) == 2
    assert "name a DEVICE" in capsys.readouterr().err
    assert main(["record-input", "dead:beef"]) == 2
    assert "no HID device matches 'dead:beef'" in capsys.readouterr().err
    assert main(["record-input", "--list"]) == 1
    assert "no HID devices found" in capsys.readouterr().err
    assert main(["record-input", "sim:mouse", "--count", "-1"]) == 2


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_ctrl_c_and_sigterm_stop_cleanly_with_every_report_written(stop):
    proc = subprocess.Popen([sys.executable, "-m", "pixelpen", "record-input", "sim:mouse?script=circle"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        lines = []
        while sum(line.startswith("E:") for line in lines) < 5:  # each report is flushed as it is written
            line = proc.stdout.readline()
            assert line, f"the recorder stopped early: {proc.stderr.read()}"
            lines.append(line)
        proc.send_signal(stop)
        rest, err = proc.communicate(timeout=30)
        assert proc.returncode == 0, err
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
    (rec,) = read_hid_recording("".join(lines) + rest, strict=True)
    assert len(rec.reports) >= 5 and "reports from sim:mouse:0" in err

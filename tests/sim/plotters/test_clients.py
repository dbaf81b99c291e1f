"""The simulators against software nobody here wrote: plotink (the vendor's EBB library), vpype's HP-GL
output, chiplotle3's HP-GL, gnea/grbl's stream.py logic and the grbl-streamer library over a pty.

Each third-party package is optional (``pytest.importorskip``): plotink, vpype, chiplotle3, grbl-streamer.
"""

from __future__ import annotations

import math
import os
import threading
import time
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import serial

import pixelpen.sim.transports.urlhandler  # noqa: F401  (registers sim://)
from pixelpen.clock import SimulatedClock
from pixelpen.sim.base import create_simulator
from pixelpen.sim.transports.port import SimPort
from pixelpen.sim.transports.pty import PtyBridge

SVG_NS = "{http://www.w3.org/2000/svg}"


def svg_paths(path) -> list[np.ndarray]:
    """The polylines of an SVG pixelpen wrote (``M x,y x,y ...`` paths), in mm."""
    out = []
    for p in ET.parse(path).getroot().iter(SVG_NS + "path"):
        out.append(np.array([[float(v) for v in pair.split(",")] for pair in p.get("d")[1:].split()]))
    return out


# -- plotink: the EBB library the AxiDraw software is built on ----------------------------------------


@pytest.fixture
def ebb_port():
    pytest.importorskip("plotink")
    port = serial.serial_for_url("sim://axidraw?speed=fast", timeout=1.0)
    yield port
    port.close()


def wait_until_still(port) -> None:
    """Poll QG, as the AxiDraw software does, until nothing executes, moves or waits in the FIFO (bits 0-3)."""
    from plotink import ebb_serial

    for _ in range(10_000):
        if int(ebb_serial.query(port, "QG\r").strip(), 16) & 0x0F == 0:
            return
    raise AssertionError("the EBB never came to rest")


def test_plotink_reads_the_motor_enables_and_resolution_from_the_pins(ebb_port):
    from plotink import ebb_motion

    assert ebb_motion.query_enable_motors(ebb_port) == (0, 0)  # boot: drivers disabled
    for res in (1, 2, 3, 4, 5):
        ebb_motion.sendEnableMotors(ebb_port, res)
        assert ebb_motion.query_enable_motors(ebb_port) == (res, res)
    ebb_motion.sendDisableMotors(ebb_port)
    assert ebb_motion.query_enable_motors(ebb_port) == (0, 0)


def test_a_walk_home_from_plotinks_queries_lands_at_home(ebb_port):
    # the AxiDraw API's walk_home: the step counters (QS) at the resolution PI reports, moved back with XM
    from plotink import ebb_motion

    ebb_motion.sendEnableMotors(ebb_port, 1)
    ebb_motion.doABMove(ebb_port, 4800, 800, 1000)  # 60 mm right, 10 mm down at 16x
    wait_until_still(ebb_port)
    device = ebb_port.sim_device
    np.testing.assert_allclose(device.position_mm, [60.0, 10.0])
    res_1, res_2 = ebb_motion.query_enable_motors(ebb_port)
    assert res_1 == res_2 == 1
    steps_1, steps_2 = ebb_motion.query_steps(ebb_port)
    a, b = (steps_1 + steps_2) // 2, (steps_1 - steps_2) // 2
    ebb_motion.doABMove(ebb_port, -a, -b, 1000)
    wait_until_still(ebb_port)
    np.testing.assert_allclose(device.position_mm, [0.0, 0.0])


def test_plotink_pen_and_motion_draw_only_pen_down_moves(ebb_port):
    from plotink import ebb_motion, ebb_serial

    assert ebb_serial.min_version(ebb_port, "2.5.5") is True
    ebb_motion.setPenUpPos(ebb_port, 20641)  # pyaxidraw: 60 % / 30 % of 9855..27831
    ebb_motion.setPenDownPos(ebb_port, 15248)
    ebb_motion.sendEnableMotors(ebb_port, 1)
    ebb_motion.sendPenUp(ebb_port, 200)
    ebb_motion.doABMove(ebb_port, 800, 800, 500)
    ebb_motion.sendPenDown(ebb_port, 200)
    wait_until_still(ebb_port)  # QP reports the pen command the motion queue has reached (ebb.c)
    assert ebb_motion.QueryPenUp(ebb_port) is False
    ebb_motion.doABMove(ebb_port, 1600, 0, 500)
    ebb_motion.sendPenUp(ebb_port, 200)
    ebb_motion.doABMove(ebb_port, -2400, -800, 800)
    wait_until_still(ebb_port)
    (_, ink), = ebb_port.sim_device.paper.strokes()
    np.testing.assert_allclose(ink[[0, -1]], [[10.0, 10.0], [30.0, 10.0]])
    assert ebb_motion.queryVoltage(ebb_port) is True
    ebb_port.sim_device.inject("power-loss")
    assert ebb_motion.queryVoltage(ebb_port) is False


# -- vpype: its hp7475a HP-GL output plotted by the HP-GL simulator -----------------------------------


def test_a_vpype_hp7475a_file_plots_the_svg_where_it_is_on_the_page(tmp_path):
    vpype_cli = pytest.importorskip("vpype_cli")
    svg = tmp_path / "in.svg"
    svg.write_text(
        '<svg xmlns="http://www.w3.org/2000/svg" width="297mm" height="210mm" viewBox="0 0 297 210">'
        '<rect x="40" y="30" width="50" height="20" fill="none" stroke="black"/>'
        '<line x1="150" y1="150" x2="250" y2="100" stroke="black"/>'
        '<circle cx="200" cy="60" r="25" fill="none" stroke="black"/></svg>'
    )
    hpgl = tmp_path / "out.hpgl"
    # a landscape A4 sheet: vpype places the page on the 7475A's A4 paper without rotating it
    vpype_cli.execute(f"read {svg} write --device hp7475a --page-size a4 --landscape {hpgl}")
    data = hpgl.read_bytes()
    assert data.startswith(b"IN;DF;PS4;")
    clock = SimulatedClock()
    device = create_simulator("hp7475a", clock=clock)
    port = SimPort(device, clock=clock, flow="xonxoff")
    port.write(b"\x1b.I81;;17:\x1b.N;19:" + data)  # Xon/Xoff as a host would configure it
    port.drain()
    while (t := port.next_event_time()) is not None:
        clock.advance(max(0.0, t - clock.now()))
        port.poll()
    port.close()
    assert device.error_log == []
    device.save_paper(tmp_path / "sheet.svg")
    polys = svg_paths(tmp_path / "sheet.svg")
    unit = 0.02488  # the 7475A plotter unit: vpype rounds to whole units, so points land within half a unit
    tol = 0.6 * unit * math.sqrt(2)
    rect = [p for p in polys if len(p) == 5]
    line = [p for p in polys if len(p) == 2]
    circle = [p for p in polys if len(p) > 5]
    assert len(rect) == len(line) == len(circle) == 1
    corners = {(40, 30), (90, 30), (90, 50), (40, 50)}
    assert all(min(math.dist(pt, c) for c in corners) < tol for pt in rect[0])
    assert {tuple(np.round(pt)) for pt in rect[0]} == corners
    np.testing.assert_allclose(sorted(map(tuple, line[0])), [(150, 150), (250, 100)], atol=tol)
    radii = np.hypot(circle[0][:, 0] - 200, circle[0][:, 1] - 60)
    assert np.all(np.abs(radii - 25) < 0.1 + tol)  # vpype's flattening tolerance is 0.1 mm by default


# -- chiplotle3: its HP-GL command objects, as it would send them to a 7475A --------------------------


def test_chiplotle3_hpgl_plots_as_its_commands_say(tmp_path, monkeypatch):
    monkeypatch.setenv("HOME", str(tmp_path))
    monkeypatch.setattr("builtins.input", lambda *prompt: "")  # chiplotle asks on stdin before making ~/.chiplotle
    hpgl = pytest.importorskip("chiplotle3.hpgl.commands")
    commands = [hpgl.IN(), hpgl.SP(1), hpgl.PU([(1000, 1000)]), hpgl.PD([(3000, 1000), (3000, 2000)]), hpgl.PU(),
                hpgl.PA([(5000, 5000)]), hpgl.CI(500), hpgl.PU(), hpgl.SP(0)]
    data = b"".join(c.format.encode("ascii") if isinstance(c.format, str) else c.format for c in commands)
    clock = SimulatedClock()
    device = create_simulator("hp7475a", clock=clock)
    device.receive(data)
    while (t := device.next_event_time()) is not None:
        clock.advance(max(0.0, t - clock.now()))
        device.advance_to(clock.now())
    assert device.error_log == []
    seg, _, _ = device.segments()
    np.testing.assert_allclose(seg[:2], [[1000, 1000, 3000, 1000], [3000, 1000, 3000, 2000]])
    circle = seg[2:]
    radii = np.hypot(circle[:, 0::2] - 5000, circle[:, 1::2] - 5000)
    np.testing.assert_allclose(radii, 500, atol=1.0)  # CI500 around the pen position (7470A manual CI)
    assert len(circle) == 72  # the default chord angle of 5 degrees


# -- GRBL streaming clients over a pty -----------------------------------------------------------------

GCODE = ["G21", "G90", "G0 X20 Y20", "M3 S50", "G4 P0.15", "G1 X80 Y20 F3000", "G1 X80 Y60", "G1 X20 Y60",
         "G1 X20 Y20", "M3 S500", "G4 P0.15", "G0 X100 Y100", "M3 S50", "G4 P0.15", "G1 X150 Y120", "M3 S500",
         "G4 P0.15", "G0 X0 Y0"]
SQUARE = [[20, 20], [80, 20], [80, 60], [20, 60], [20, 20]]


def assert_plotted(device) -> None:
    """The paper holds the square and the line of GCODE (the grbl profile's pen: S50 down, S500 up)."""
    strokes = [pts for _, pts in device.paper.strokes()]
    assert len(strokes) == 2
    np.testing.assert_allclose(strokes[0], SQUARE, atol=1e-6)
    np.testing.assert_allclose(strokes[1][[0, -1]], [[100, 100], [150, 120]], atol=1e-6)


def test_gnea_stream_py_character_counting_over_the_pty():
    # gnea/grbl doc/script/stream.py, aggressive mode: wake up, flush, then keep the 128-byte RX buffer full
    device = create_simulator("grbl", clock=SimulatedClock())
    with PtyBridge(device) as bridge:
        with serial.Serial(bridge.path, 115200, timeout=10) as s:
            s.write(b"\r\n\r\n")
            time.sleep(0.5)  # stream.py sleeps 2 s: "Wait for grbl to initialize"
            s.reset_input_buffer()
            counts: list[int] = []
            errors = 0
            for line in GCODE:
                block = line.strip() + "\n"
                counts.append(len(block))
                while sum(counts) >= 128 or s.in_waiting:
                    reply = s.readline().strip()
                    assert reply, "GRBL stopped answering"
                    if reply.find(b"ok") < 0 and reply.find(b"error") >= 0:
                        errors += 1
                    del counts[0]
                s.write(block.encode())
            while counts:
                reply = s.readline().strip()
                assert reply, "GRBL stopped answering"
                errors += reply.startswith(b"error")
                del counts[0]
            s.write(b"G4 P0\n")  # the planner is empty once this dwell is acknowledged
            assert s.readline().strip() == b"ok"
        assert errors == 0
    assert_plotted(device)


def test_grbl_streamer_library_over_the_pty():
    streamer_mod = pytest.importorskip("grbl_streamer")
    device = create_simulator("grbl", clock=SimulatedClock())
    events: dict[str, threading.Event] = {"on_boot": threading.Event()}
    errors: list[tuple] = []

    def callback(event: str, *data: object) -> None:
        if event in events:
            events[event].set()
        if event in ("on_error", "on_alarm"):
            errors.append((event, *data))

    with PtyBridge(device) as bridge:
        grbl = streamer_mod.GrblStreamer(callback)
        grbl.setup_logging()
        grbl.cnect(bridge.path, 115200)  # opening resets the Arduino; cnect soft-resets it again
        try:
            deadline = time.monotonic() + 20
            while "^X" not in [line for _, line in device.log] and time.monotonic() < deadline:
                time.sleep(0.01)
            assert events["on_boot"].wait(10), "grbl-streamer never saw the banner"
            time.sleep(1.0)  # both boots are seen (a boot arriving later would clear the job)
            grbl.write("\n".join([*GCODE, "G4 P0"]))
            grbl.job_run()
            deadline = time.monotonic() + 60
            def finished() -> bool:  # the closing G4 P0 waits for the planner: after it, all has moved
                return "G04P0" in [line for _, line in device.log] and device.state == "Idle"

            while time.monotonic() < deadline and not finished():
                time.sleep(0.02)
        finally:
            grbl.disconnect()
    assert errors == []
    assert_plotted(device)


pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="the pty tests need POSIX ptys")

"""Tests of ``pixelpen sim``: replaying byte files paced so the device never overflows, the pty mode, errors."""

import io
import json
import os
import signal
import subprocess
import sys
import threading
import urllib.request

import numpy as np
import pytest
import serial
from PIL import Image

from pixelpen.cli import main
from pixelpen.commands import sim as simcmd
from pixelpen.display.capabilities import Capabilities
from pixelpen.display.kinds import RasterDisplay
from pixelpen.errors import URLError
from pixelpen.scene import show_reference
from pixelpen.sim.transports.port import SimPort, TransportOptions


def zigzag_hpgl(n: int) -> bytes:
    """IN, pen 1, then one PD instruction per short vector: n vectors of 40 plotter units (1 mm)."""
    body = b"".join(b"PD%d,%d;" % (1000 + 40 * (i + 1), 1000 + 40 * (i % 2)) for i in range(n))
    return b"IN;SP1;PU1000,1000;" + body + b"PU;SP0;"


def test_hpgl_replay_never_overflows_a_small_buffer():
    data = zigzag_hpgl(150)
    device, transport = simcmd.open_simulator("hp7475a", {"buffer": "64", "reserve_bug": "false"}, "fast")
    result = simcmd.replay(device, data, transport)
    assert device.stats.bytes_overflowed == 0 and device.error_log == [] and result.errors == []
    seg, _, _ = device.segments()
    assert len(seg) == 150
    np.testing.assert_allclose(seg[-1, 2:], [1000 + 40 * 150, 1000 + 40 * (149 % 2)])
    assert result.bytes_fed == len(data) == result.link.bytes_sent
    # the same bytes without pacing overrun the 64-byte buffer: the pacing is what keeps them
    raw, _ = simcmd.open_simulator("hp7475a", {"buffer": "64", "reserve_bug": "false"}, "fast")
    port = SimPort(raw, baud=9600, flow="none", clock=raw.clock)
    port.write(data)
    port.drain()
    assert raw.stats.bytes_overflowed > 0


def test_grbl_replay_keeps_the_rx_buffer_from_overflowing():
    lines = [b"G21", b"G90", b"M3 S50"] + [b"G1 X%.2f Y%.2f F3000" % (10 + i * 0.5, 10 + (i % 2)) for i in range(60)]
    data = b"\n".join(lines) + b"\n"
    device, transport = simcmd.open_simulator("grbl", {"baud": "115200"}, "fast")
    result = simcmd.replay(device, data, transport)
    assert device.overflowed == 0 and result.errors == []
    assert result.replies.count(b"ok") == len(lines)
    assert device.stats.commands_executed == len(lines)
    np.testing.assert_allclose(device.machine_position()[:2], [10 + 59 * 0.5, 10 + 59 % 2], atol=1e-6)
    raw, _ = simcmd.open_simulator("grbl", {}, "fast")
    port = SimPort(raw, baud=115200, flow="none", clock=raw.clock)
    port.write(data)
    port.drain()
    assert raw.overflowed > 0


def test_ebb_replay_waits_for_the_usb_handshake():
    commands = [b"EM,1,1", b"SP,0,100"] + [b"SM,30,40,40"] * 40 + [b"SP,1,100"]
    device, transport = simcmd.open_simulator("axidraw", {}, "fast")
    result = simcmd.replay(device, b"\r".join(commands) + b"\r", transport)
    assert result.errors == []
    assert [text for _, text in device.log] == [c.decode() for c in commands]
    assert result.link.held_off > 0  # the board's FIFO filled and held the line


def test_device_errors_come_from_the_error_log_and_from_error_replies():
    device, transport = simcmd.open_simulator("hp7475a", {}, "fast")
    result = simcmd.replay(device, b"IN;XX;PA0,0;", transport)
    assert len(result.errors) == 1 and "HP-GL error 1" in result.errors[0] and "XX" in result.errors[0]
    assert simcmd.device_errors(device, b"ok\r\nerror:20\r\nALARM:2\r\n!8 Err: Unknown command\r\n")[1:] == [
        "error:20", "ALARM:2", "!8 Err: Unknown command"]


def test_cli_replay_writes_the_paper_and_reports(tmp_path, capsys):
    src = tmp_path / "drawing.hpgl"
    data = b"IN;SP1;PU2000,2000;PD6000,2000,6000,6000,2000,6000,2000,2000;PU;XX;SP0;"
    src.write_bytes(data)
    out = tmp_path / "paper.png"
    assert main(["sim", "hp7475a", "--replay", str(src), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert f"replayed {len(data)} bytes" in text and "errors: 1" in text and "HP-GL error 1" in text
    img = np.asarray(Image.open(out).convert("L"))
    assert (img < 128).any() and (img == 255).mean() > 0.9


@pytest.mark.parametrize("argv, needle", [
    (["sim", "hp9999", "--replay", "x"], "known: "),
    (["sim", "grbl", "--replay", "/nonexistent/file.nc"], "cannot read /nonexistent/file.nc"),
    (["sim", "grbl"], "give --pty, --replay FILE or --view"),
    (["sim", "grbl", "--view", "--host", "nonsense.invalid"], "cannot listen on nonsense.invalid"),
    (["sim", "grbl", "--pty", "--replay", "x"], "either --pty or --replay"),
])
def test_cli_errors_are_one_line(argv, needle, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert needle in err and len(err.strip().splitlines()) == 1


def test_options_are_key_value_pairs():
    assert simcmd.parse_options(["paper=a3", "Pens = black,red"]) == {"paper": "a3", "pens": "black,red"}
    for bad in (["paper"], ["=a3"], ["paper=a3", "paper=a4"]):
        with pytest.raises(URLError):
            simcmd.parse_options(bad)
    with pytest.raises(URLError, match="unknown option"):
        simcmd.open_simulator("grbl", {"bogus": "1"}, "fast")
    with pytest.raises(URLError, match="--speed"):
        simcmd.open_simulator("grbl", {"speed": "fast"}, "fast")


def test_pty_serves_the_device_until_stopped(capsys):
    device, _ = simcmd.open_simulator("hp7475a", {}, "fast")
    stop = threading.Event()
    server = threading.Thread(target=simcmd.run_pty, args=(device, TransportOptions(), stop))
    server.start()
    try:
        for _ in range(500):
            path = capsys.readouterr().out.strip()
            if path:
                break
            stop.wait(0.01)
        with serial.Serial(path, timeout=10) as port:
            port.write(b"IN;SP1;PU0,0;PD2000,0;OA;")
            assert port.read_until(b"\r").strip() == b"2000,0,1"
    finally:
        stop.set()
        server.join(10)
    seg, _, _ = device.segments()
    np.testing.assert_allclose(seg, [[0, 0, 2000, 0]])


def test_pty_command_writes_the_paper_on_ctrl_c(tmp_path):
    out = tmp_path / "pty.png"
    proc = subprocess.Popen(
        [sys.executable, "-m", "pixelpen", "sim", "grbl", "--pty", "--speed", "fast", "-o", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        path = proc.stdout.readline().strip()
        with serial.Serial(path, timeout=20) as port:
            port.write(b"G21\nG90\nM3 S50\nG1 X10 Y10 F3000\nG1 X60 Y10\nM3 S500\nG4 P0.1\n")
            replies = b""
            while replies.count(b"ok") < 7:
                chunk = port.read(max(1, port.in_waiting))
                assert chunk, f"no reply from the simulator; got {replies!r}"
                replies += chunk
        proc.send_signal(signal.SIGINT)
        assert proc.wait(30) == 0
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
    img = np.asarray(Image.open(out).convert("L"))
    assert (img < 128).any()


_SIM_MAIN = (
    "import argparse, sys\n"
    "from pixelpen.commands import sim\n"
    "parser = argparse.ArgumentParser()\n"
    "sim.register(parser.add_subparsers())\n"
    "args = parser.parse_args(sys.argv[1:])\n"
    "sys.exit(args.func(args))\n"
)
"""``pixelpen sim`` on its own (the command module's parser, not the whole CLI)."""


def test_pty_command_writes_the_paper_on_sigterm(tmp_path):
    # a service manager stops the simulator with SIGTERM: the sheet must be written as on Ctrl-C
    import xml.etree.ElementTree as ET

    out = tmp_path / "pty.svg"
    proc = subprocess.Popen(
        [sys.executable, "-c", _SIM_MAIN, "sim", "grbl", "--pty", "--speed", "fast", "-o", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        path = proc.stdout.readline().strip()
        with serial.Serial(path, timeout=20) as port:
            assert port.read_until(b"]\r\n").endswith(b"Grbl 1.1h ['$' for help]\r\n")  # the Arduino reset on open
            # the grbl profile's pen: M3 S50 down, M3 S500 up
            port.write(b"G21\nG90\nG0 X10 Y10\nM3 S50\nG1 X60 Y10 F3000\nM3 S500\nG4 P0.1\n")
            replies = b""
            while replies.count(b"ok") < 7:
                chunk = port.read(max(1, port.in_waiting))
                assert chunk, f"no reply from the simulator; got {replies!r}"
                replies += chunk
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(30) == 0
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
    paths = [p.get("d") for p in ET.parse(out).getroot().iter("{http://www.w3.org/2000/svg}path")]
    assert paths == ["M10,200 60,200"]  # 297 x 210 sheet, y up: the line 10 mm above the bottom edge


def test_grbl_simulator_defaults_are_the_machine_the_driver_plots_for():
    # one machine description: what the GRBL driver asks a sim:grbl for equals what pixelpen sim grbl builds
    from pixelpen.devices.plotters.grbl import GrblPlotter
    from pixelpen.profiles import load_profile
    from pixelpen.urls import parse_url

    profile = load_profile("grbl")
    wanted = GrblPlotter.simulator_options({}, GrblPlotter.read_url_options(parse_url("grbl:x")), profile)
    device, transport = simcmd.open_simulator("grbl", {}, "fast")
    width, height = (float(v) for v in wanted["size"].split("x"))
    assert (device.paper.width_mm, device.paper.height_mm) == (width, height) == (297.0, 210.0)
    assert device.pen_mode == wanted["pen"] == "servo-inverted"
    assert device.pen_threshold == float(wanted["pen_threshold"])
    assert transport.baud == profile.link.baudrate == 115200


@pytest.mark.parametrize("model, options, baud", [
    ("axidraw", {}, 12_000_000),  # USB CDC: no baud pacing
    ("hp7475a", {}, 9600),
    ("grbl", {"baud": "57600"}, 57600),
])
def test_the_line_runs_at_the_devices_own_speed(model, options, baud):
    _, transport = simcmd.open_simulator(model, options, "fast")
    assert transport.baud == baud


def _wait_for(url_of: str, predicate, what: str) -> object:
    """GET ``url_of`` until ``predicate(body)`` holds (a simulator in real time needs a moment); the last body."""
    for _ in range(200):
        with urllib.request.urlopen(url_of, timeout=10) as reply:
            body = reply.read()
        if predicate(body):
            return body
        threading.Event().wait(0.05)
    raise AssertionError(f"{what}: never seen at {url_of}; last {body[:200]!r}")


def _has_ink(png: bytes) -> bool:
    return bool((np.asarray(Image.open(io.BytesIO(png)).convert("L")) < 128).any())


def test_pty_with_view_serves_the_paper_as_it_is_drawn(tmp_path):
    out = tmp_path / "paper.png"
    proc = subprocess.Popen(
        [sys.executable, "-c", _SIM_MAIN, "sim", "grbl", "--pty", "--view", "--speed", "fast", "-o", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        path = proc.stdout.readline().strip()
        url = proc.stdout.readline().strip()
        assert path.startswith("/dev/pts/") and url.startswith("http://127.0.0.1:")
        assert not _has_ink(_wait_for(url + "frame.png", lambda b: True, "a blank sheet"))
        program = b"G21\nG90\nG0 X10 Y10\nM3 S50\nG1 X60 Y10 F3000\nM3 S500\nG4 P0.1\n"
        with serial.Serial(path, timeout=20) as port:
            port.read_until(b"]\r\n")  # the banner of the Arduino reset on open
            port.write(program)
            replies = b""
            while replies.count(b"ok") < 7:
                chunk = port.read(max(1, port.in_waiting))
                assert chunk, f"no reply from the simulator; got {replies!r}"
                replies += chunk
        stats = json.loads(_wait_for(url + "stats.json", lambda b: json.loads(b)["commands_executed"] >= 7,
                                     "the executed commands"))
        assert stats["bytes_received"] == len(program)
        _wait_for(url + "frame.png", _has_ink, "the line on the paper")
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(30) == 0
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
    assert _has_ink(out.read_bytes())
    with pytest.raises(OSError):  # the view is gone with the simulator
        urllib.request.urlopen(url, timeout=5)


def test_replay_with_view_keeps_serving_until_stopped(tmp_path):
    plot = tmp_path / "square.hpgl"
    plot.write_bytes(b"IN;SP1;PU1000,1000;PD3000,1000,3000,3000,1000,3000,1000,1000;PU;SP0;")
    out = tmp_path / "paper.svg"
    proc = subprocess.Popen(
        [sys.executable, "-c", _SIM_MAIN, "sim", "hp7475a", "--replay", str(plot), "--view", "-o", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        url = proc.stdout.readline().strip()
        assert url.startswith("http://127.0.0.1:")
        assert proc.stdout.readline().startswith(f"replayed {plot.stat().st_size} bytes")
        assert _has_ink(_wait_for(url + "frame.png", _has_ink, "the square"))
        assert proc.poll() is None  # still serving after the replay
        proc.send_signal(signal.SIGINT)
        assert proc.wait(30) == 0
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
    assert out.read_text().count("<path") == 1


_PANEL_MAIN = (
    "import sys\n"
    "from dataclasses import dataclass\n"
    "from PIL import Image\n"
    "from pixelpen.cli import main\n"
    "from pixelpen.clock import REAL_CLOCK\n"
    "from pixelpen.sim.base import register_simulator\n"
    "@dataclass\n"
    "class BusStats:\n"
    "    bytes: int = 4242\n"
    "    transfers: int = 7\n"
    "class StubPanel:\n"
    "    model = 'stubpanel'\n"
    "    def __init__(self, clock=None, **options):\n"
    "        self.clock = clock or REAL_CLOCK\n"
    "        self.stats, self.events = BusStats(), ['one']\n"
    "        self.image = Image.new('RGB', (6, 4), (0, 0, 255))\n"
    "        self.image.putpixel((5, 3), (255, 255, 0))\n"
    "        self.closed = False\n"
    "    def glass(self):\n"
    "        return self.image.copy()\n"
    "    def close(self):\n"
    "        self.closed = True\n"
    "register_simulator('stubpanel', StubPanel)\n"
    "sys.exit(main(sys.argv[1:]))\n"
)
"""``pixelpen`` with a panel simulator registered (the panel surface of the shared design: glass, stats, events)."""


def test_a_panel_simulator_is_viewed_and_its_glass_written(tmp_path):
    out = tmp_path / "glass.png"
    proc = subprocess.Popen([sys.executable, "-c", _PANEL_MAIN, "sim", "stubpanel", "--view", "-o", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = proc.stdout.readline().strip()
        assert url.startswith("http://127.0.0.1:")
        glass = np.asarray(Image.open(io.BytesIO(_wait_for(url + "frame.png", lambda b: True, "the glass"))))
        expected = np.zeros((4, 6, 3), np.uint8)
        expected[..., 2] = 255
        expected[3, 5] = (255, 255, 0)
        np.testing.assert_array_equal(glass, expected)
        assert json.loads(_wait_for(url + "stats.json", lambda b: True, "stats")) == \
            {"bytes": 4242, "transfers": 7, "events": 1}
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(30) == 0
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
    np.testing.assert_array_equal(np.asarray(Image.open(out)), expected)


def test_a_hid_simulator_is_not_served(capsys):
    assert main(["sim", "keyboard", "--pty"]) == 2
    assert "keyboard is reached through HID reports" in capsys.readouterr().err


def test_a_panel_has_no_pty():
    proc = subprocess.run([sys.executable, "-c", _PANEL_MAIN, "sim", "stubpanel", "--pty"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert "stubpanel is a panel: it is reached through a bus, not a byte stream; watch it with --view" in proc.stderr


class RecordingPanel(RasterDisplay):
    """A raster display standing in for a panel display: it keeps each frame's damage rectangles and sets
    ``stop`` (when given) once it has sent ``frames_to_stop`` frames."""

    def __init__(self, width: int = 64, height: int = 48, mode: str = "RGB", stop: threading.Event | None = None,
                 frames_to_stop: int = 0) -> None:
        caps = Capabilities(model="recording", category="panel", kind="raster", size=(width, height),
                            unit_mm=0.2, colour_model="mono" if mode == "1" else "rgb565", y_down=True)
        super().__init__(caps, mode=mode, background="black")
        self.frames: list[list] = []
        self.pictures: list[np.ndarray] = []
        self.stop, self.frames_to_stop = stop, frames_to_stop
        self.open()

    @classmethod
    def from_url(cls, url, **kwargs):
        raise NotImplementedError

    def _open_device(self) -> None:
        pass

    def _close_device(self) -> None:
        pass

    def _show(self, canvas) -> None:
        self.frames.append(list(canvas.damage()))
        self.pictures.append(canvas.array.copy())
        if self.stop is not None and len(self.frames) >= self.frames_to_stop:
            self.stop.set()


def _run_demo(panel: RecordingPanel) -> None:
    runner = threading.Thread(target=simcmd.run_panel_demo, args=(panel, threading.Lock(), panel.stop, 500.0))
    runner.start()
    runner.join(30)
    assert not runner.is_alive()


def _scene(width: int, height: int, mode: str = "RGB") -> RecordingPanel:
    """A panel showing only the reference scene, and the frames it took."""
    panel = RecordingPanel(width, height, mode)
    show_reference(panel)
    return panel


def test_the_panel_demo_draws_the_scene_then_a_cursor_and_a_clock_in_small_frames():
    stop = threading.Event()
    reference = _scene(96, 64)
    panel = RecordingPanel(96, 64, stop=stop, frames_to_stop=len(reference.frames) + 40)
    _run_demo(panel)
    scene = reference.pictures[-1]
    assert (scene != 0).any(axis=2).mean() > 0.02  # the reference scene is on the glass
    start = len(reference.frames) - 1
    np.testing.assert_array_equal(panel.pictures[start], scene)
    side, clock_box = 64 // 12, 50 * 13  # a twelfth of the short side; the clock: 10 px digits, bottom right
    orange = np.array([255, 160, 0], np.uint8)
    positions = []
    for damage, before, after in zip(panel.frames[start + 1:], panel.pictures[start:], panel.pictures[start + 1:],
                                     strict=False):
        changed = np.argwhere((after != before).any(axis=2))
        damaged = np.zeros(after.shape[:2], bool)
        for rect in damage:
            damaged[rect.y0:rect.y1, rect.x0:rect.x1] = True
        assert damaged[tuple(changed.T)].all()  # every changed pixel was in the frame sent
        assert damaged.sum() <= (side + 3) * (side + 2) + clock_box  # the cursor's old and new squares, the clock
        ys, xs = np.nonzero((after == orange).all(axis=2))
        assert np.ptp(ys) == np.ptp(xs) == side - 1 and len(ys) == side * side  # one solid square
        positions.append((int(xs.min()), int(ys.min())))
        differs = (after != scene).any(axis=2)
        differs[ys.min():ys.max() + 1, xs.min():xs.max() + 1] = False
        differs[-13:, -50:] = False  # the clock's box
        assert not differs.any()  # elsewhere the scene is as it was
    # from (5, 5), (3, 2) a frame up to x = 96 - 5 = 91, y = 64 - 5 = 59; a step past an edge turns it back
    # instead: x 89 -> (92) 86, y 59 -> (61) 57
    assert len(positions) == 40
    assert [x for x, _ in positions] == [5 + 3 * k for k in range(29)] + [86 - 3 * k for k in range(11)]
    assert [y for _, y in positions] == [5 + 2 * k for k in range(28)] + [57 - 2 * k for k in range(12)]


def test_the_panel_demo_lights_the_scene_on_a_mono_panel():
    stop = threading.Event()
    panel = RecordingPanel(128, 64, mode="1", stop=stop, frames_to_stop=3)
    _run_demo(panel)
    lit = panel.pictures[0].astype(bool)  # one frame: the scene drawn in colour, then lit
    # the scene's strokes are lit whatever their colour: drawn in mono directly only ~5 % were (409 pixels)
    assert 0.1 < lit.mean() < 0.6


def test_panel_demo_runs_until_stopped():
    panel = RecordingPanel(32, 24)
    lock, stop = threading.Lock(), threading.Event()
    runner = threading.Thread(target=simcmd.run_panel_demo, args=(panel, lock, stop, 200.0))
    runner.start()
    for _ in range(500):
        if len(panel.frames) >= 5:
            break
        stop.wait(0.01)
    stop.set()
    runner.join(10)
    assert not runner.is_alive() and len(panel.frames) >= 5


@pytest.mark.parametrize("model, size", [("st7789", (240, 240)), ("ssd1306", (128, 64)), ("fbdev", (320, 240))])
def test_a_simulated_display_is_viewed_through_the_demo(tmp_path, model, size):
    from pixelpen.sim.base import simulator_models

    if model not in simulator_models():
        pytest.skip(f"the {model} simulator is not registered yet (pixelpen.sim.panels)")
    out = tmp_path / "glass.png"
    proc = subprocess.Popen([sys.executable, "-c", _SIM_MAIN, "sim", model, "--view", "-o", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = proc.stdout.readline().strip()
        assert url.startswith("http://127.0.0.1:"), proc.stderr.read() if proc.poll() is not None else url
        frames = []
        for _ in range(200):  # the ball moves: the frames differ
            with urllib.request.urlopen(url + "frame.png", timeout=10) as reply:
                frames.append(np.asarray(Image.open(io.BytesIO(reply.read())).convert("RGB")))
            if len(frames) > 1 and not np.array_equal(frames[0], frames[-1]):
                break
            threading.Event().wait(0.05)
        assert frames[-1].shape == (size[1], size[0], 3) and not np.array_equal(frames[0], frames[-1])
        assert len(np.unique(frames[-1].reshape(-1, 3), axis=0)) >= 2  # the scene, not a blank glass
        if model == "ssd1306":  # the scene's strokes lit whatever their colour (drawn in mono directly: 5 %)
            assert (frames[-1].max(axis=2) > 0).mean() > 0.1
        stats = json.loads(_wait_for(url + "stats.json", lambda b: True, "stats"))
        if "frames" in stats:  # a panel's bus: the ball's frames are partial refreshes
            later = json.loads(_wait_for(url + "stats.json", lambda b: json.loads(b)["frames"] > stats["frames"] + 3,
                                         "more demo frames"))
            assert (later["bytes"] - stats["bytes"]) / (later["frames"] - stats["frames"]) < size[0] * size[1] / 4
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(30) == 0
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
    assert Image.open(out).size == size


def test_a_real_time_replay_is_watched_and_stopped_with_ctrl_c(tmp_path):
    plot = tmp_path / "zigzag.nc"  # the grbl profile's pen: M3 S50 down; 20 mm strokes at 50 mm/s take a while
    plot.write_bytes(b"G21\nG90\nM3 S50\n" + b"".join(b"G1 X%d Y%d F3000\n" % (i, (i % 2) * 20) for i in range(400)))
    out = tmp_path / "paper.png"
    proc = subprocess.Popen(
        [sys.executable, "-c", _SIM_MAIN, "sim", "grbl", "--replay", str(plot), "--speed", "real", "--view",
         "-o", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        url = proc.stdout.readline().strip()
        _wait_for(url + "frame.png", _has_ink, "the first strokes")
        stats = json.loads(_wait_for(url + "stats.json", lambda b: True, "stats"))
        assert 0 < stats["bytes_received"] < plot.stat().st_size  # seen while the file is still arriving
        proc.send_signal(signal.SIGINT)
        assert proc.wait(30) == 0
        assert "replay stopped" in proc.stderr.read()
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
    assert _has_ink(out.read_bytes())


def test_the_guarded_device_holds_the_lock_around_every_call(tmp_path):
    device, _ = simcmd.open_simulator("grbl", {}, "fast")
    lock = threading.Lock()
    guarded = simcmd.GuardedDevice(device, lock)
    held = []
    for name in ("receive", "take_output", "advance_to", "next_event_time", "inject", "save_paper", "close"):
        original = getattr(device, name)

        def spy(*args, _original=original, **kwargs):
            held.append(lock.locked())
            return _original(*args, **kwargs)

        setattr(device, name, spy)
    assert guarded.resets_on_dtr is True and guarded.model == "grbl" and guarded.clock is device.clock
    guarded.receive(b"$I\n")
    guarded.advance_to(device.clock.now() + 1)
    assert b"[VER:1.1h" in guarded.take_output()
    guarded.next_event_time()
    guarded.inject("reset")
    assert guarded.ready_to_receive is True
    guarded.save_paper(tmp_path / "paper.png")
    guarded.close()
    assert (tmp_path / "paper.png").exists() and device.closed
    assert held == [True] * 7

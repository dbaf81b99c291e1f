"""Tests of ``pixelpen show``: stills, animations and video frames on raster displays, pacing, skips, errors, Ctrl-C."""

import json
import re
import shutil
import stat
import sys
import textwrap

import numpy as np
import pytest
from PIL import Image, ImageDraw

from pixelpen.cli import main
from pixelpen.clock import SimulatedClock
from pixelpen.commands.show import Frame, Player, fit_image
from pixelpen.display.capabilities import Capabilities
from pixelpen.display.kinds import RasterDisplay
from pixelpen.errors import ConfigError
from pixelpen.sim.base import simulator_models


@pytest.fixture(autouse=True)
def no_user_config(monkeypatch):
    monkeypatch.setenv("PIXELPEN_CONFIG", "")


def pixels(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(int)


def moving_box_gif(path, frames=10, ms=50):
    images = []
    for i in range(frames):
        im = Image.new("RGB", (80, 60), (0, 0, 128))
        ImageDraw.Draw(im).rectangle([i * 6, 20, i * 6 + 9, 29], fill=(255, 255, 0))
        images.append(im)
    images[0].save(path, save_all=True, append_images=images[1:], duration=ms, loop=0)
    return images


def test_a_still_is_letterboxed_into_the_display(tmp_path, capsys):
    src, out = tmp_path / "red.png", tmp_path / "out.png"
    Image.new("RGB", (100, 50), (255, 0, 0)).save(src)
    assert main(["show", str(src), "--to", f"png:{out}?size=64x48"]) == 0
    img = pixels(out)
    # 100x50 scaled to fit 64 wide is 64x32, centred: rows 8..39 red, 8 black rows above and below
    assert (img[8:40] == (255, 0, 0)).all() and (img[:8] == 0).all() and (img[40:] == 0).all()
    assert "shown 1 frame, skipped 0" in capsys.readouterr().out


@pytest.mark.parametrize(("fit", "top_left"), [("cover", (255, 0, 0)), ("stretch", (0, 255, 0))])
def test_cover_crops_and_stretch_distorts(tmp_path, fit, top_left):
    # left quarter green, the rest red: cover crops the sides (64/48 of the height -> the middle 2/3 of the
    # width stays), stretch keeps the green quarter
    src, out = tmp_path / "src.png", tmp_path / "out.png"
    im = Image.new("RGB", (400, 100), (255, 0, 0))
    ImageDraw.Draw(im).rectangle([0, 0, 99, 99], fill=(0, 255, 0))
    im.save(src)
    assert main(["show", str(src), "--to", f"png:{out}?size=64x48", "--fit", fit]) == 0
    assert tuple(pixels(out)[24, 2]) == top_left
    assert tuple(pixels(out)[24, 40]) == (255, 0, 0)


def test_rotate_turns_a_portrait_picture_clockwise_onto_a_landscape_display():
    im = Image.new("RGB", (50, 100), (0, 0, 255))
    ImageDraw.Draw(im).rectangle([0, 0, 49, 49], fill=(255, 0, 0))  # top half red
    turned = np.asarray(fit_image(im, (100, 50), "stretch", rotate=True))
    # clockwise: the top of the picture comes to the right-hand side
    assert (turned[:, 60:] == (255, 0, 0)).all() and (turned[:, :40] == (0, 0, 255)).all()
    same = np.asarray(fit_image(im, (100, 50), "stretch", rotate=False))
    assert (same[:20] == (255, 0, 0)).all()


def test_a_mono_display_gets_an_ordered_dither(tmp_path):
    src, out = tmp_path / "grey.png", tmp_path / "out.png"
    Image.new("RGB", (32, 32), (128, 128, 128)).save(src)
    assert main(["show", str(src), "--to", f"png:{out}?size=32x32&mode=1", "--fit", "stretch"]) == 0
    lit = np.asarray(Image.open(out).convert("L")) > 0
    # a 4x4 Bayer matrix lights the thresholds below 128/255 of 16 levels: 8 of every 16 pixels
    assert lit.mean() == pytest.approx(0.5) and (lit[:4, :4].sum() == 8)


def test_an_animation_plays_every_frame_for_its_duration(tmp_path, capsys):
    src, out = tmp_path / "anim.gif", tmp_path / "out.png"
    images = moving_box_gif(src)
    assert main(["show", str(src), "--to", f"png:{out}?size=80x60"]) == 0
    text = capsys.readouterr().out
    # ten frames of 50 ms in 0.5 s of the file display's simulated clock: 20 fps
    assert "shown 10 frames, skipped 0, 20.0 fps achieved" in text
    assert np.abs(pixels(out) - np.asarray(images[-1]).astype(int)).max() <= 8  # the last frame (GIF palette)


def test_loop_and_fps_override_the_files_timing(tmp_path, capsys):
    src = tmp_path / "anim.gif"
    moving_box_gif(src, frames=4)
    assert main(["show", str(src), "--to", f"png:{tmp_path / 'o.png'}?size=80x60", "--loop", "3", "--fps", "8"]) == 0
    assert "shown 12 frames, skipped 0, 8.0 fps achieved" in capsys.readouterr().out


class SlowDisplay(RasterDisplay):
    """A raster display whose every frame takes ``frame_seconds`` of a simulated clock; counts frames."""

    def __init__(self, clock, frame_seconds, interrupt_at=None):
        caps = Capabilities(model="slow", category="output", kind="raster", size=(8.0, 8.0), unit_mm=1.0,
                            colour_model="rgb888")
        super().__init__(caps, mode="RGB")
        self.clock, self.frame_seconds, self.interrupt_at = clock, frame_seconds, interrupt_at
        self.sent = []

    @classmethod
    def from_url(cls, url, **kwargs):
        raise NotImplementedError

    def _open_device(self):
        pass

    def _close_device(self):
        self.closed_with = self.canvas.array.copy()

    def _show(self, canvas):
        if self.interrupt_at is not None and len(self.sent) == self.interrupt_at:
            self.interrupt_at = None
            raise KeyboardInterrupt
        self.clock.advance(self.frame_seconds)
        self.sent.append(int(canvas.array[0, 0, 0]))


def numbered_frames(count, seconds):
    return [Frame(Image.new("RGB", (8, 8), (i * 10, 0, 0)), seconds) for i in range(count)]


def test_late_frames_are_skipped_and_counted_never_queued():
    clock = SimulatedClock()
    display = SlowDisplay(clock, 0.12).open()
    player = Player(display, clock)
    player.play(iter(numbered_frames(10, 0.05)))
    stats = player.finish()
    # slots of 50 ms; a frame takes 120 ms: frame 0 ends at 0.12 (slot 1 over: skip), frame 2 (slot 0.10-0.15)
    # ends at 0.24, frame 4 (0.20-0.25) at 0.36, frames 5 and 6 are over, frame 7 (0.35-0.40) ends at 0.48,
    # frame 8 is over, the last frame is always shown: ends at 0.60
    assert display.sent == [0, 20, 40, 70, 90]
    assert (stats.shown, stats.skipped) == (5, 5)
    assert stats.seconds == pytest.approx(0.60) and stats.fps == pytest.approx(5 / 0.6)


def test_ctrl_c_stops_after_the_frame_and_closes_the_display(monkeypatch, tmp_path, capsys):
    clock = SimulatedClock()
    display = SlowDisplay(clock, 0.01, interrupt_at=3)
    monkeypatch.setattr("pixelpen.commands.show.open_display", lambda url: display.open())
    monkeypatch.setattr("pixelpen.commands.show.display_class", lambda scheme: SlowDisplay)
    src = tmp_path / "anim.gif"
    moving_box_gif(src)
    assert main(["show", str(src), "--to", "png:ignored.png"]) == 130
    captured = capsys.readouterr()
    assert "shown 3 frames" in captured.out and "stopped" in captured.err
    assert not display.is_open and hasattr(display, "closed_with")


@pytest.mark.parametrize("name", ["missing.png", "text.png"])
def test_an_unreadable_image_is_exit_2_naming_the_file(tmp_path, capsys, name):
    (tmp_path / "text.png").write_text("not an image")
    path = tmp_path / name
    assert main(["show", str(path), "--to", f"png:{tmp_path / 'o.png'}"]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and err.count("\n") == 1
    assert not (tmp_path / "o.png").exists()


def test_a_vector_display_is_exit_2(tmp_path, capsys):
    src = tmp_path / "red.png"
    Image.new("RGB", (4, 4)).save(src)
    assert main(["show", str(src), "--to", "sim:hp7475a"]) == 2
    assert "show needs a raster display" in capsys.readouterr().err


def test_a_video_without_ffmpeg_says_what_to_install(tmp_path, capsys, monkeypatch):
    src = tmp_path / "clip.mp4"
    src.write_bytes(b"\x00" * 64)
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    assert main(["show", str(src), "--to", f"png:{tmp_path / 'o.png'}"]) == 2
    err = capsys.readouterr().err
    assert "ffmpeg" in err and "apt install ffmpeg" in err and str(src) in err


def fake_tools(folder, width, height, rate, count, fail=""):
    """ffprobe and ffmpeg stand-ins on PATH: the probe's JSON, then ``count`` raw RGB frames of grey levels
    (then, with ``fail``, that message on stderr and exit status 1)."""
    folder.mkdir()
    probe = {"streams": [{"width": width, "height": height, "avg_frame_rate": rate, "r_frame_rate": rate}]}
    scripts = {
        "ffprobe": f"import sys\nprint({json.dumps(json.dumps(probe))})\n",
        "ffmpeg": textwrap.dedent(f"""\
            import sys
            assert sys.argv[-5:] == ["-f", "rawvideo", "-pix_fmt", "rgb24", "-"], sys.argv
            for i in range({count}):
                sys.stdout.buffer.write(bytes([i * 20]) * {width * height * 3})
            if {fail!r}:
                sys.stderr.write({fail!r} + "\\n")
                sys.exit(1)
            """),
    }
    for name, body in scripts.items():
        path = folder / name
        path.write_text(f"#!{sys.executable}\n{body}")
        path.chmod(path.stat().st_mode | stat.S_IEXEC)


def test_video_frames_come_from_ffmpeg_through_a_pipe_at_its_rate(tmp_path, capsys, monkeypatch):
    fake_tools(tmp_path / "bin", 16, 12, "25/1", 5)
    monkeypatch.setenv("PATH", str(tmp_path / "bin"))
    src, out = tmp_path / "clip.mp4", tmp_path / "o.png"
    src.write_bytes(b"\x00")
    assert main(["show", str(src), "--to", f"png:{out}?size=16x12"]) == 0
    assert "shown 5 frames, skipped 0, 25.0 fps achieved" in capsys.readouterr().out
    assert (pixels(out) == 80).all()  # the last frame: grey level 4 * 20


def test_a_video_ffmpeg_cannot_decode_is_exit_2_with_its_message(tmp_path, capsys, monkeypatch):
    fake_tools(tmp_path / "bin", 16, 12, "25/1", 0, fail="Invalid data found when processing input")
    monkeypatch.setenv("PATH", str(tmp_path / "bin"))
    src = tmp_path / "clip.mkv"
    src.write_bytes(b"\x00")
    assert main(["show", str(src), "--to", f"png:{tmp_path / 'o.png'}?size=16x12"]) == 2
    err = capsys.readouterr().err
    assert f"cannot decode {src}: ffmpeg says Invalid data found" in err


def stalled_video(tmp_path, monkeypatch, probe_hangs):
    """A video whose ffprobe (``probe_hangs``) or ffmpeg (after one 4x2 frame) hangs, their timeouts 0.5 s."""
    from pixelpen.commands import show as showcmd

    folder = tmp_path / "bin"
    fake_tools(folder, 4, 2, "25/1", 0)
    hang = "import time\ntime.sleep(600)\n"
    if probe_hangs:
        (folder / "ffprobe").write_text(f"#!{sys.executable}\n{hang}")
    else:
        (folder / "ffmpeg").write_text(f"#!{sys.executable}\nimport sys\nsys.stdout.buffer.write(bytes(24))\n"
                                       f"sys.stdout.flush()\n{hang}")
    monkeypatch.setenv("PATH", str(folder))
    monkeypatch.setattr(showcmd, "PROBE_TIMEOUT_S", 0.5)
    monkeypatch.setattr(showcmd, "FRAME_TIMEOUT_S", 0.5)
    src = tmp_path / "clip.mp4"
    src.write_bytes(b"\x00")
    return src


def test_an_ffprobe_that_never_answers_is_exit_2_naming_the_file(tmp_path, capsys, monkeypatch):
    src = stalled_video(tmp_path, monkeypatch, probe_hangs=True)
    assert main(["show", str(src), "--to", f"png:{tmp_path / 'o.png'}?size=4x2"]) == 2
    assert f"cannot read {src} as a video: ffprobe gave no answer in 0.5 s" in capsys.readouterr().err


def test_an_ffmpeg_that_stalls_is_killed_with_a_clear_error(tmp_path, capsys, monkeypatch):
    from pixelpen.commands.show import open_source

    src = stalled_video(tmp_path, monkeypatch, probe_hangs=False)
    frames = open_source(src).frames()
    assert next(frames).image.size == (4, 2)  # the one frame it sent
    with pytest.raises(ConfigError, match=f"cannot decode {re.escape(str(src))}: ffmpeg sent no frame for 0.5 s; "
                                          "stopped it"):
        next(frames)
    assert main(["show", str(src), "--to", f"png:{tmp_path / 'o.png'}?size=4x2"]) == 2
    assert "ffmpeg sent no frame for 0.5 s" in capsys.readouterr().err


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not installed")
def test_a_real_video_decoded_by_ffmpeg(tmp_path, capsys):
    import subprocess

    src = tmp_path / "clip.mp4"
    subprocess.run(["ffmpeg", "-v", "error", "-f", "lavfi", "-i", "testsrc=size=64x48:rate=10", "-t", "1",
                    "-pix_fmt", "yuv420p", str(src)], check=True)
    assert main(["show", str(src), "--to", f"png:{tmp_path / 'o.png'}?size=32x24"]) == 0
    assert "shown 10 frames, skipped 0, 10.0 fps achieved" in capsys.readouterr().out


@pytest.mark.skipif("st7789" not in simulator_models(), reason="the ST7789 simulator is not registered yet")
def test_an_animation_on_a_simulated_panel_sends_only_what_changed(tmp_path, capsys):
    from pixelpen.sim.base import forget_simulator, named_simulator

    src = tmp_path / "anim.gif"
    images = moving_box_gif(src, frames=6)
    assert main(["show", str(src), "--to", "sim:st7789?size=240x240&id=show-test", "--fit", "stretch"]) == 0
    out = capsys.readouterr().out
    assert "shown 6 frames, skipped 0" in out
    sent = int(out.split(" bytes on the bus")[0].rsplit(" ", 1)[1].replace(",", ""))
    # the black frame of the init and the first picture are full frames (115,200 pixel bytes + 11 window bytes
    # each), then five moves of a 30x30 box by 18 pixels: each within 4x3 changed 16-pixel tiles (6,144 bytes)
    full = 115_211
    assert 2 * full < sent < 2 * full + 5 * 6_500
    try:
        glass = np.asarray(named_simulator("show-test").glass().convert("RGB")).astype(int)
    finally:
        forget_simulator("show-test")
    want = np.asarray(images[-1].resize((240, 240), Image.Resampling.BILINEAR)).astype(int)
    assert np.abs(glass - want).mean() < 12


class InterruptingBus:
    """A panel bus passing calls on, that raises KeyboardInterrupt once in the middle of the ``at``-th data call."""

    def __init__(self, bus, at):
        self.bus, self.at, self.calls = bus, at, 0

    def __getattr__(self, name):
        return getattr(self.bus, name)

    def data(self, data):
        self.calls += 1
        if self.calls == self.at:
            self.interrupted = len(data)
            self.bus.data(data[: len(data) // 2])
            raise KeyboardInterrupt
        self.bus.data(data)


@pytest.mark.skipif("st7789" not in simulator_models(), reason="the ST7789 simulator is not registered yet")
def test_ctrl_c_in_the_middle_of_a_frame_leaves_the_panel_showing_a_whole_one(tmp_path, monkeypatch, capsys):
    from pixelpen.commands import show as show_module
    from pixelpen.sim.base import forget_simulator, named_simulator

    opened, buses = [], []

    def open_and_interrupt(url):
        display = pixelpen_open(url)
        # data calls: CASET, RASET and the pixels of the first picture, then the second picture's
        display.wiring.bus = InterruptingBus(display.wiring.bus, at=6)
        opened.append(display)
        buses.append(display.wiring.bus)
        return display

    pixelpen_open = show_module.open_display
    monkeypatch.setattr(show_module, "open_display", open_and_interrupt)
    src = tmp_path / "anim.gif"
    moving_box_gif(src, frames=6)
    try:
        assert main(["show", str(src), "--to", "sim:st7789?size=240x240&id=show-interrupted"]) == 130
        display = opened[0]
        assert not display.is_open and buses[0].interrupted > 1000  # stopped inside a window's pixels
        glass = np.asarray(named_simulator("show-interrupted").glass().convert("RGB")).astype(int)
    finally:
        forget_simulator("show-interrupted")
    # the close sent the canvas whole: the glass is the canvas (RGB565 resolution: within 8 levels)
    assert np.abs(glass - display.canvas.array.astype(int)).max() <= 8
    assert "stopped" in capsys.readouterr().err


def test_sigterm_stops_a_show_that_loops_forever(tmp_path):
    import os
    import signal
    import subprocess
    import time

    src, out = tmp_path / "anim.gif", tmp_path / "o.png"
    moving_box_gif(src, frames=3)
    env = {**os.environ, "PIXELPEN_CONFIG": ""}
    process = subprocess.Popen([sys.executable, "-m", "pixelpen", "show", str(src), "--to", f"png:{out}?size=40x30",
                                "--loop", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        for _ in range(600):  # the file appears with the first frame: the show is running
            if out.exists() or process.poll() is not None:
                break
            time.sleep(0.05)
        process.send_signal(signal.SIGTERM)
        stdout, stderr = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 130, stderr
    assert "shown" in stdout and "stopped" in stderr
    assert Image.open(out).size == (40, 30)  # written whole at the close

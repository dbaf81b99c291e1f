"""The ``show`` command: a still image, an animation or a video's frames on any raster display, at their pace.

``pixelpen show IMAGE --to URL``: IMAGE is anything Pillow reads (PNG, JPEG, BMP, ...; an animated GIF, APNG
or WebP plays its frames for their durations) or, with ``ffmpeg`` on PATH, a video (known by its file name's
ending; decoded by ffmpeg through a pipe as raw RGB frames, at its frame rate).  Each frame is scaled to the
display (``--fit``: contain, cover or stretch; ``--rotate`` turns it 90 degrees when that fills the display
better), dithered for a mono panel, and only its changed tiles are drawn, so a panel sends just the pixels
that differ.

Frames are paced on the display's clock (a ``sim:`` panel's SimulatedClock: simulated time, bus time
included) by their presentation times, with the FramePacer's rule: frames never queue; a frame whose
successor is already due when its turn comes is skipped and counted.  At the end the command prints frames
shown and skipped, the achieved frame rate and the bytes the display put on its bus.  Ctrl-C or SIGTERM stop
the show (exit status 130); the display is then closed normally, and a panel sends a frame that was cut
short again whole, so it is left showing a whole frame.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import shutil
import subprocess
import sys
import tempfile
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import numpy as np
from PIL import Image, ImageOps, ImageSequence, UnidentifiedImageError

from pixelpen.clock import REAL_CLOCK, Clock, SimulatedClock
from pixelpen.commands import argtypes
from pixelpen.commands.sim import sigterm_stops
from pixelpen.display.kinds import RasterDisplay
from pixelpen.display.registry import display_class, open_display
from pixelpen.errors import ConfigError
from pixelpen.raster.canvas import Canvas
from pixelpen.raster.damage import tile_damage
from pixelpen.raster.dither import ordered_mono
from pixelpen.urls import parse_url

log = logging.getLogger(__name__)

FITS = ("contain", "cover", "stretch")
"""How a frame is scaled to the display: whole and letterboxed, filling it and cropped, or distorted to it."""
DEFAULT_FRAME_SECONDS = 0.1
"""Duration of an animation frame that names none (or 0), as browsers play GIFs."""
VIDEO_SUFFIXES = frozenset({".mp4", ".m4v", ".mkv", ".webm", ".mov", ".avi", ".mpg", ".mpeg", ".ogv", ".y4m",
                            ".flv", ".wmv", ".ts"})
"""File name endings taken for video (decoded by ffmpeg) rather than an image Pillow cannot read."""
TILE = 16
"""Side of the tiles compared between frames: only changed tiles are drawn."""
PROBE_TIMEOUT_S = 30.0
"""Seconds ffprobe may take to describe a video before the file is given up as unreadable."""
FRAME_TIMEOUT_S = 30.0
"""Seconds ffmpeg may take to send the next frame before it is taken as stalled and killed (wall time)."""


@dataclass(frozen=True)
class Frame:
    """One frame of the source: an RGB image and how long it stays (seconds; 0 for a still)."""

    image: Image.Image
    seconds: float


@dataclass
class ShowStats:
    """What ``show`` did: frames shown and skipped, seconds on the display's clock, bytes on the display's bus."""

    shown: int = 0
    skipped: int = 0
    seconds: float = 0.0
    bus_bytes: int | None = None

    @property
    def fps(self) -> float:
        """Frames shown per second of the display's clock (0 when no time passed)."""
        return self.shown / self.seconds if self.seconds > 0 else 0.0


# -- sources --------------------------------------------------------------------------------------------------


class ImageSource:
    """A still or animated image read by Pillow: its frames with their durations, composited onto black."""

    def __init__(self, path: Path) -> None:
        self.path = path
        try:
            with Image.open(path) as image:
                image.load()
                self.animated = bool(getattr(image, "is_animated", False))
                self.size = image.size
        except (UnidentifiedImageError, OSError, ValueError) as exc:
            raise ConfigError(f"cannot read {path} as an image: {_reason(exc)}") from None

    def frames(self) -> Iterator[Frame]:
        """Every frame once (a still: one frame of 0 s)."""
        with Image.open(self.path) as image:
            if not self.animated:
                yield Frame(_flatten(image), 0.0)
                return
            for frame in ImageSequence.Iterator(image):
                ms = frame.info.get("duration") or 0
                yield Frame(_flatten(frame), ms / 1000.0 if ms > 0 else DEFAULT_FRAME_SECONDS)


class VideoSource:
    """A video decoded by ffmpeg through a pipe into raw RGB frames, at its frame rate."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.animated = True
        ffmpeg, ffprobe = shutil.which("ffmpeg"), shutil.which("ffprobe")
        if ffmpeg is None or ffprobe is None:
            raise ConfigError(f"{path} is a video: showing video needs ffmpeg and ffprobe on PATH "
                              "(Debian/Ubuntu: apt install ffmpeg; macOS: brew install ffmpeg)")
        self.ffmpeg = ffmpeg
        try:
            probe = subprocess.run([ffprobe, "-v", "error", "-select_streams", "v:0", "-show_entries",
                                    "stream=width,height,avg_frame_rate,r_frame_rate", "-of", "json", str(path)],
                                   capture_output=True, text=True, check=False, timeout=PROBE_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            raise ConfigError(f"cannot read {path} as a video: ffprobe gave no answer in {PROBE_TIMEOUT_S:g} s"
                              ) from None
        try:
            stream = json.loads(probe.stdout)["streams"][0]
            self.size = (int(stream["width"]), int(stream["height"]))
        except (ValueError, KeyError, IndexError, TypeError):
            raise ConfigError(f"cannot read {path} as a video: ffprobe says "
                              f"{probe.stderr.strip() or 'no video stream'}") from None
        self._rate = _ratio(stream.get("avg_frame_rate")) or _ratio(stream.get("r_frame_rate")) or 25.0

    def frames(self) -> Iterator[Frame]:
        """Every frame once, read from ``ffmpeg -f rawvideo -pix_fmt rgb24`` (its messages go to a temporary file,
        so a chatty decoder never blocks on a full pipe); ConfigError when ffmpeg decodes no frame at all or stalls."""
        width, height = self.size
        size = width * height * 3
        decoded = 0
        with tempfile.TemporaryFile() as messages:
            process = subprocess.Popen([self.ffmpeg, "-v", "error", "-nostdin", "-i", str(self.path), "-f", "rawvideo",
                                        "-pix_fmt", "rgb24", "-"], stdout=subprocess.PIPE, stderr=messages)
            stdout = process.stdout
            if stdout is None:  # pragma: no cover - PIPE always gives one
                raise ConfigError("ffmpeg started without an output pipe")
            try:
                while len(raw := self._read(process, stdout, size)) == size:
                    decoded += 1
                    yield Frame(Image.frombuffer("RGB", (width, height), raw), 1.0 / self._rate)
            finally:
                stdout.close()
                process.kill()
                status = process.wait()
            messages.seek(0)
            error = messages.read().decode(errors="replace").strip()
        if status != 0 and error:
            if not decoded:
                raise ConfigError(f"cannot decode {self.path}: ffmpeg says {error.splitlines()[-1]}")
            log.warning("%s: ffmpeg: %s", self.path, error.splitlines()[-1])

    def _read(self, process: subprocess.Popen[bytes], stdout: IO[bytes], size: int) -> bytes:
        """Up to ``size`` bytes of ffmpeg's output; ConfigError, ffmpeg killed, if they take FRAME_TIMEOUT_S."""
        stalled = threading.Event()

        def kill() -> None:
            stalled.set()
            process.kill()

        watchdog = threading.Timer(FRAME_TIMEOUT_S, kill)
        watchdog.daemon = True
        watchdog.start()
        try:
            raw = stdout.read(size)
        finally:
            watchdog.cancel()
        if stalled.is_set():
            raise ConfigError(f"cannot decode {self.path}: ffmpeg sent no frame for {FRAME_TIMEOUT_S:g} s; stopped it")
        return raw


def open_source(path: str | Path) -> ImageSource | VideoSource:
    """The frames of ``path``: a video for ffmpeg when its name says so (:data:`VIDEO_SUFFIXES`), else an image."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"cannot read {path}: no such file")
    if path.suffix.lower() in VIDEO_SUFFIXES:
        return VideoSource(path)
    return ImageSource(path)


def _flatten(image: Image.Image) -> Image.Image:
    """An RGB copy of ``image`` with any transparency composited onto black."""
    rgba = image.convert("RGBA")
    background = Image.new("RGBA", rgba.size, (0, 0, 0, 255))
    return Image.alpha_composite(background, rgba).convert("RGB")


def _ratio(text: object) -> float | None:
    """``"30000/1001"`` as a number (None for missing, zero or malformed)."""
    num, _, den = str(text or "").partition("/")
    try:
        value = float(num) / float(den or 1)
    except (ValueError, ZeroDivisionError):
        return None
    return value if math.isfinite(value) and value > 0 else None


def _reason(exc: BaseException) -> str:
    return getattr(exc, "strerror", None) or str(exc) or type(exc).__name__


# -- frames onto the canvas ---------------------------------------------------------------------------------


def fit_image(image: Image.Image, size: tuple[int, int], fit: str = "contain", rotate: bool = False) -> Image.Image:
    """``image`` scaled to ``size``: ``contain`` (letterboxed on black), ``cover`` (cropped) or ``stretch``;
    ``rotate`` turns it 90 degrees clockwise first when its orientation is the display's opposite."""
    if fit not in FITS:
        raise ConfigError(f"fit must be one of {', '.join(FITS)}, got {fit!r}")
    if rotate and (image.width > image.height) != (size[0] > size[1]) and image.width != image.height:
        image = image.transpose(Image.Transpose.ROTATE_270)
    resample = Image.Resampling.BILINEAR
    if fit == "stretch":
        return image.resize(size, resample)
    if fit == "cover":
        return ImageOps.fit(image, size, resample)
    inner = ImageOps.contain(image, size, resample)
    out = Image.new("RGB", size)
    out.paste(inner, ((size[0] - inner.width) // 2, (size[1] - inner.height) // 2))
    return out


def canvas_pixels(canvas: Canvas, image: Image.Image) -> np.ndarray:
    """An RGB image of the canvas's size as the canvas's native array (mono: ordered dither, stable frame to frame)."""
    rgb = np.asarray(image.convert("RGB"))
    if canvas.mode == "RGB":
        return rgb
    if canvas.mode == "1":
        return ordered_mono(rgb).astype(np.uint8)
    return canvas.colour_values(rgb.reshape(-1, 3)).reshape(canvas.array.shape)


def draw_changes(canvas: Canvas, pixels: np.ndarray) -> None:
    """Draw ``pixels`` (the canvas's shape and dtype) into the canvas, only the tiles where they differ."""
    for r in tile_damage(pixels, canvas.array, TILE):
        rows, cols = r.slices
        canvas.blit(pixels[rows, cols], r.x0, r.y0)


# -- playing ------------------------------------------------------------------------------------------------


def display_clock(display: RasterDisplay) -> Clock:
    """The clock frames are paced on: the display's (a simulated panel's), its simulator's, simulated for files."""
    for owner in (display, getattr(display, "simulator", None)):
        clock = getattr(owner, "clock", None)
        if isinstance(clock, Clock):
            return clock
    return SimulatedClock() if display.capabilities.category == "file" else REAL_CLOCK


def bus_bytes(display: RasterDisplay) -> int | None:
    """Bytes the display has put on its bus since it was opened (a panel's, a framebuffer's pixel writes)."""
    stats = getattr(display, "stats", None)
    if isinstance(getattr(stats, "bytes", None), int):
        return int(stats.bytes)  # type: ignore[union-attr]
    written = getattr(display, "bytes_written", None)
    return written if isinstance(written, int) else None


class Player:
    """Shows frames on an open raster display at their presentation times on ``clock`` (see the module doc)."""

    def __init__(self, display: RasterDisplay, clock: Clock, *, fit: str = "contain", rotate: bool = False,
                 fps: float | None = None) -> None:
        self.display = display
        self.clock = clock
        self.fit = fit
        self.rotate = rotate
        self.fps = fps
        self.stats = ShowStats()
        self._start = clock.now()
        self._due = self._start

    def play(self, frames: Iterator[Frame]) -> None:
        """Show ``frames`` in order; a frame whose successor is already due is skipped (never the last one)."""
        previous: Frame | None = None
        for frame in frames:
            if previous is not None:
                self._offer(previous, last=False)
            previous = frame
        if previous is not None:
            self._offer(previous, last=True)

    def _seconds(self, frame: Frame) -> float:
        return 1.0 / self.fps if self.fps is not None and frame.seconds > 0 else frame.seconds

    def _offer(self, frame: Frame, *, last: bool) -> None:
        """Show ``frame`` at its time, or skip it when its time is already over (the next frame is due)."""
        seconds = self._seconds(frame)
        now = self.clock.now()
        if not last and seconds > 0 and now >= self._due + seconds:
            self.stats.skipped += 1
        else:
            self.clock.sleep(self._due - now)
            canvas = self.display.canvas
            draw_changes(canvas, canvas_pixels(canvas, fit_image(frame.image, canvas.size, self.fit, self.rotate)))
            self.display.flush()
            self.stats.shown += 1
        self._due += seconds

    def finish(self, *, wait: bool = True) -> ShowStats:
        """The totals, after waiting out the last frame's time (``wait``; not when interrupted)."""
        if wait:
            self.clock.sleep(self._due - self.clock.now())
        self.stats.seconds = self.clock.now() - self._start
        return self.stats


def show(path: str | Path, url: str, *, fps: float | None = None, loops: int = 1, fit: str = "contain",
         rotate: bool = False) -> tuple[ShowStats, bool]:
    """Show ``path`` on the display ``url`` (``loops`` times; 0: until interrupted); (totals, True if interrupted)."""
    source = open_source(path)
    parsed = parse_url(url)
    cls = display_class(parsed.target if parsed.scheme == "sim" else parsed.scheme)
    if not issubclass(cls, RasterDisplay):
        raise ConfigError(f"{url}: show needs a raster display (a panel, fbdev: or png:); {cls.__name__} draws "
                          "with a pen")
    display = open_display(url)
    if not isinstance(display, RasterDisplay):
        display.close()
        raise ConfigError(f"{url}: opened a {type(display).__name__}, not a raster display")
    player = Player(display, display_clock(display), fit=fit, rotate=rotate, fps=fps)
    interrupted = False
    try:
        with sigterm_stops():
            try:
                rounds = 0
                while loops == 0 or rounds < loops:
                    player.play(source.frames())
                    rounds += 1
                    if not source.animated:
                        break
                stats = player.finish()
            except KeyboardInterrupt:
                interrupted = True
                stats = player.finish(wait=False)
    finally:
        display.close()  # sends the frame in progress whole: the panel is left consistent
    stats.bus_bytes = bus_bytes(display)
    return stats, interrupted


def cmd_show(args: argparse.Namespace) -> int:
    """Run ``pixelpen show`` and print what it did."""
    stats, interrupted = show(args.image, args.to, fps=args.fps, loops=args.loop, fit=args.fit, rotate=args.rotate)
    line = f"shown {stats.shown} frame{'s' if stats.shown != 1 else ''}, skipped {stats.skipped}"
    if stats.shown > 1:
        line += f", {stats.fps:.1f} fps achieved"
    if stats.bus_bytes is not None:
        line += f", {stats.bus_bytes:,} bytes on the bus"
    print(f"{args.to}: {line}")
    if interrupted:
        print("pixelpen show: stopped; the display was left showing a whole frame", file=sys.stderr)
        return 130
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``pixelpen show`` to the ``pixelpen`` parser."""
    p = sub.add_parser("show", help="show an image, an animated GIF/APNG/WebP or a video on a raster display",
                       description="Put a still image, an animation (its frames for their durations) or a video's "
                                   "frames (with ffmpeg) on a panel, a framebuffer or a PNG file, scaled to it and "
                                   "paced by its clock; prints frames shown and skipped, fps and bus bytes.")
    p.add_argument("image", metavar="IMAGE", help="image, animation (GIF, APNG, WebP) or video file")
    p.add_argument("--to", required=True, metavar="URL",
                   help="raster display URL (sim:st7789, fbdev:/dev/fb0, png:x.png)")
    p.add_argument("--fps", type=argtypes.positive, default=None, metavar="N",
                   help="play an animation or video at N frames a second instead of its own timing")
    p.add_argument("--loop", type=argtypes.non_negative_int, default=1, metavar="N",
                   help="play an animation N times (0: until Ctrl-C; default 1)")
    p.add_argument("--fit", choices=FITS, default="contain",
                   help="contain (whole, letterboxed; default), cover (fill, cropped) or stretch")
    p.add_argument("--rotate", action="store_true",
                   help="turn the picture 90 degrees when its orientation is the display's opposite")
    p.set_defaults(func=cmd_show)


__all__ = ["Frame", "ImageSource", "Player", "ShowStats", "VideoSource", "canvas_pixels", "fit_image", "open_source",
           "show"]

"""Panel benchmark: luma.oled/luma.lcd against pixelpen on one set of workloads (SSD1306, ST7789, ILI9341).

Run: ``python3 benchmarks/panels.py [--frames N] [--panels ssd1306,st7789,ili9341] [--workloads cursor,clock]``.

Workloads (seeded, the same frames for both): a 20x20 cursor moving over a gradient and a clock's digits
changing every frame (the demo animation's :class:`~pixelpen.animation.Cursor` and
:class:`~pixelpen.animation.ClockFace`), and the benchmark's own whole-screen changes, which the demo does not
make: a list of text lines scrolling by 2 rows a frame and full-screen video frames (a moving gradient).
Each frame is a list of patches pasted onto the picture: luma's application pastes them into a PIL image and
calls ``device.display(image)``; pixelpen's blits them onto the canvas and calls ``flush()``.
Only that call is timed (host time per frame: conversion, diffing, window planning, packing, the bus
calls).  Both drive counting buses: luma a serial interface with ``command(*cmd)``/``data(data)`` (the shape
of ``luma.core.interface.serial.noop``), pixelpen a PanelBus stub, both only counting (pixelpen's wire time,
for its fps, is computed from its bytes afterwards); bytes are command + data bytes as the driver hands them
over (I2C control bytes would add to both alike).  luma uses its defaults: full frames on
ssd1306 and st7789 (RGB666 there), ``diff_to_previous(25)`` on ili9341 (panels.md §5).

Goals (issue 10, Speed): pixelpen's bytes <= 1.1x the ideal (changed pixels in the native format + one
window's commands per 4-connected changed region: a lower bound, as a window is a rectangle, so a region that
is not one costs more windows or unchanged pixels — glyph edges of the clock and the scroll are far from
rectangles); host time per frame <= 0.5x luma's; full frames on the
simulated ST7789 240x240 RGB565 at 62.5 MHz (the real SpiBus, the simulated spidev and MipiDcsSim) >= 95 % of
the bus limit of ``devices/panels/pacing.py`` (67.8 fps), judged on the driver's host time per frame added to
its simulated bus time (the simulated time alone holds only bus time, so it cannot miss the goal).
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pixelpen.animation import ClockFace, Cursor
from pixelpen.clock import SimulatedClock
from pixelpen.devices.panels.base import PanelDisplay
from pixelpen.devices.panels.mipidcs import ILI9341Display, ST7789Display
from pixelpen.devices.panels.pacing import bus_limit_fps
from pixelpen.devices.panels.ssd1306 import SSD1306Display
from pixelpen.devices.panels.windows import MIPI_WINDOW_BYTES, SSD1306_WINDOW_BYTES
from pixelpen.devices.panels.wiring import Wiring
from pixelpen.drivers.bus import RESET_RECOVERY, spi_wire_seconds
from pixelpen.profiles.panel import panel_profile_for

SEED = 20261202
CURSOR = 20
FULL_FRAME_GOAL = 0.95
BYTES_GOAL = 1.10
HOST_GOAL = 0.50


@dataclass(frozen=True)
class Panel:
    """One module on both libraries: size, bus clock, native bytes per pixel and window overhead."""

    name: str
    width: int
    height: int
    mono: bool
    clock_hz: float
    window_bytes: int

    @property
    def mode(self) -> str:
        return "1" if self.mono else "RGB"


PANELS = {
    "ssd1306": Panel("ssd1306", 128, 64, True, 10e6, SSD1306_WINDOW_BYTES),
    "st7789": Panel("st7789", 240, 240, False, 62.5e6, MIPI_WINDOW_BYTES),
    "ili9341": Panel("ili9341", 320, 240, False, 10e6, MIPI_WINDOW_BYTES),
}
"""The modules compared, at the bus clocks of panels.md §4 (SSD1306 on 4-wire SPI at 10 MHz)."""

Patch = tuple[int, int, np.ndarray]
"""(x, y, pixels): an HxWx3 uint8 RGB array (HxW uint8 0/1 on a mono panel) pasted at (x, y)."""


# -- counting buses ---------------------------------------------------------------------------------------


class CountingSerial:
    """A luma serial interface (``luma.core.interface.serial.noop``'s shape) counting bytes and calls."""

    def __init__(self) -> None:
        self.command_bytes = self.data_bytes = self.calls = 0

    def command(self, *cmd: int) -> None:
        self.command_bytes += len(cmd)
        self.calls += 1

    def data(self, data: Sequence[int] | bytes) -> None:
        self.data_bytes += len(data)
        self.calls += 1

    def cleanup(self) -> None:
        pass

    @property
    def bytes(self) -> int:
        return self.command_bytes + self.data_bytes


class CountingBus:
    """A PanelBus stub counting what pixelpen's driver sends, as cheaply as :class:`CountingSerial` counts luma's;
    :meth:`wire_seconds` is the SPI wire time of what it counted (the SimulatedClock only takes reset waits)."""

    kind = "spi"
    max_transfer = 4096

    def __init__(self, clock: SimulatedClock, clock_hz: float) -> None:
        self.clock = clock
        self.clock_hz = clock_hz
        self.bytes_sent = 0
        self.transfers = 0

    def command(self, *cmd: int | bytes) -> None:
        self.bytes_sent += sum(1 if isinstance(c, int) else len(c) for c in cmd)
        self.transfers += 1

    def data(self, data: bytes) -> None:
        self.bytes_sent += len(data)
        self.transfers += -(-len(data) // self.max_transfer)

    def reset(self, recovery: float = RESET_RECOVERY) -> None:
        self.clock.advance(recovery)

    def close(self) -> None:
        pass

    def wire_seconds(self, nbytes: int) -> float:
        """SPI wire time of ``nbytes`` at the bus clock."""
        return spi_wire_seconds(nbytes, self.clock_hz)


# -- workloads --------------------------------------------------------------------------------------------


def _native(rgb: np.ndarray, panel: Panel) -> np.ndarray:
    """An RGB array as the panel's pixels (mono: lit where the grey is at least half)."""
    if not panel.mono:
        return rgb
    return (rgb.astype(np.uint16).sum(axis=2) >= 384).astype(np.uint8)


def _gradient(panel: Panel, phase: float = 0.0) -> np.ndarray:
    y, x = np.mgrid[0:panel.height, 0:panel.width].astype(np.float64)
    r = 127.5 + 127.5 * np.sin(x / 23.0 + phase)
    g = 127.5 + 127.5 * np.sin(y / 17.0 - 1.3 * phase)
    b = 127.5 + 127.5 * np.sin((x + y) / 31.0 + 0.7 * phase)
    return np.stack([r, g, b], axis=2).astype(np.uint8)


def cursor(panel: Panel, frames: int) -> tuple[np.ndarray, list[list[Patch]]]:
    """The demo animation's solid white 20x20 cursor moving 3 columns and 2 rows a frame over a gradient (mono: a
    grid of dots every 4 pixels, so the cursor always changes what it covers), bouncing off the edges."""
    if panel.mono:
        background = np.zeros((panel.height, panel.width), np.uint8)
        background[::4, ::4] = 1
    else:
        background = _gradient(panel)
    square = Cursor(background, CURSOR, 1 if panel.mono else (255, 255, 255))
    start = background.copy()
    _paste_array(start, [square.drawn()])
    return start, [square.move() for _ in range(frames)]


def clock(panel: Panel, frames: int) -> tuple[np.ndarray, list[list[Patch]]]:
    """The demo animation's ``HH:MM:SS`` ticking a second a frame, white in the middle of a black screen."""
    black = np.zeros((panel.height, panel.width) if panel.mono else (panel.height, panel.width, 3), np.uint8)
    face = ClockFace(black, max(10, panel.height // 6), 1 if panel.mono else (255, 255, 255),
                     0 if panel.mono else (0, 0, 0), place="centre")
    start = black.copy()
    _paste_array(start, [face.tick()])
    return start, [[face.tick()] for _ in range(frames)]


def _paste_array(frame: np.ndarray, patches: list[Patch]) -> None:
    for x, y, pixels in patches:
        frame[y:y + pixels.shape[0], x:x + pixels.shape[1]] = pixels


def scrolling_list(panel: Panel, frames: int) -> tuple[np.ndarray, list[list[Patch]]]:
    """Lines of text ("item 17 ...") scrolling up by 2 rows a frame over the whole screen."""
    line = max(10, panel.height // 8)
    rng = np.random.default_rng(SEED)
    words = ["alpha", "bravo", "delta", "echo", "kilo", "lima", "oscar", "tango"]
    count = (panel.height + 2 * frames) // line + 2
    sheet = Image.new("RGB", (panel.width, count * line))
    draw = ImageDraw.Draw(sheet)
    font = ImageFont.load_default(size=line - 2)
    for k in range(count):
        draw.text((2, k * line), f"item {k:02d} {words[int(rng.integers(len(words)))]}", fill=(255, 255, 255),
                  font=font)
    tall = _native(np.asarray(sheet), panel)
    out = [[(0, 0, tall[2 * i:2 * i + panel.height])] for i in range(1, frames + 1)]
    return tall[:panel.height].copy(), out


def video(panel: Panel, frames: int) -> tuple[np.ndarray, list[list[Patch]]]:
    """Full-screen frames of a moving gradient: every pixel changes every frame."""
    return _native(_gradient(panel, 0.0), panel), [[(0, 0, _native(_gradient(panel, 0.2 * i), panel))]
                                                   for i in range(1, frames + 1)]


WORKLOADS: dict[str, Callable[[Panel, int], tuple[np.ndarray, list[list[Patch]]]]] = {
    "cursor": cursor, "clock": clock, "scroll": scrolling_list, "video": video,
}


# -- the ideal: changed pixels in the native format plus a window per changed region ----------------------


def _native_units(frame: np.ndarray, panel: Panel) -> np.ndarray:
    """What the controller stores: RGB565 words, or SSD1306 page bytes (8 rows a byte)."""
    if panel.mono:
        return np.packbits(frame.reshape(panel.height // 8, 8, panel.width), axis=1, bitorder="little")[:, 0]
    f = frame.astype(np.uint16)
    return ((f[..., 0] & 0xF8) << 8) | ((f[..., 1] & 0xFC) << 3) | (f[..., 2] >> 3)


def ideal_bytes(before: np.ndarray, after: np.ndarray, panel: Panel) -> int:
    """Changed native units x their bytes + one window's commands per 4-connected changed region."""
    changed = _native_units(before, panel) != _native_units(after, panel)
    regions = ndimage.label(changed)[1]
    return int(changed.sum()) * (1 if panel.mono else 2) + regions * panel.window_bytes


# -- the two libraries ---------------------------------------------------------------------------------------


def luma_device(panel: Panel, serial: CountingSerial) -> object:
    """luma's device for ``panel`` with its default framebuffer."""
    from luma.core.interface.serial import noop

    if panel.name == "ssd1306":
        from luma.oled.device import ssd1306

        device = ssd1306(serial, width=panel.width, height=panel.height)
    elif panel.name == "st7789":
        from luma.lcd.device import st7789

        device = st7789(serial, width=panel.width, height=panel.height, gpio=noop())  # no backlight pin
    else:
        from luma.lcd.device import ili9341

        # diff_to_previous(25) by default
        device = ili9341(serial, width=panel.width, height=panel.height, gpio=noop())
    device.persist = True  # no blanking at exit
    return device


def pixelpen_display(panel: Panel, bus: CountingBus) -> PanelDisplay:
    """pixelpen's display for ``panel`` on the counting bus (ILI9341: the 240x320 module turned 90 degrees)."""
    wiring = Wiring(bus)
    if panel.name == "ssd1306":
        return SSD1306Display(wiring, profile=panel_profile_for("ssd1306", (128, 64)), clock=bus.clock)
    if panel.name == "st7789":
        return ST7789Display(wiring, profile=panel_profile_for("st7789", (240, 240)), clock=bus.clock)
    return ILI9341Display(wiring, profile=panel_profile_for("ili9341", (240, 320)), rotation=90, clock=bus.clock)


@dataclass
class Row:
    """One workload on one panel: per-frame means for both libraries."""

    panel: str
    workload: str
    luma_ms: float
    luma_bytes: float
    pixelpen_ms: float
    pixelpen_bytes: float
    windows: float
    ideal_bytes: float
    achieved_fps: float
    limit_fps: float


def _paste(image: Image.Image, patches: list[Patch], mode: str) -> None:
    for x, y, pixels in patches:
        image.paste(Image.fromarray(pixels * 255 if mode == "1" else pixels).convert(mode), (x, y))


def run_workload(panel: Panel, workload: str, frames: int) -> Row:
    """Both libraries on one workload; the pictures they were given are checked to agree."""
    start, steps = WORKLOADS[workload](panel, frames)
    serial = CountingSerial()
    device = luma_device(panel, serial)
    picture = Image.fromarray(start * 255 if panel.mono else start).convert(panel.mode)
    device.display(picture)  # type: ignore[attr-defined]
    clock = SimulatedClock()
    bus = CountingBus(clock, panel.clock_hz)
    display = pixelpen_display(panel, bus)
    display.open()
    display.canvas.blit(start, 0, 0)
    display.flush()
    previous = start
    luma_times, pp_times, ideal = [], [], 0
    luma_before, pp_before, windows_before = serial.bytes, bus.bytes_sent, display.stats.windows
    for patches in steps:
        _paste(picture, patches, panel.mode)
        began = time.perf_counter()
        device.display(picture)  # type: ignore[attr-defined]
        luma_times.append(time.perf_counter() - began)
        for x, y, pixels in patches:
            display.canvas.blit(pixels, x, y)
        began = time.perf_counter()
        display.flush()
        pp_times.append(time.perf_counter() - began)
        current = display.canvas.array
        ideal += ideal_bytes(previous, current, panel)
        previous = current.copy()
    n = len(steps)
    lit = np.asarray(picture.convert("L")) > 0 if panel.mono else np.asarray(picture)
    if not np.array_equal(lit, display.canvas.array.astype(bool) if panel.mono else display.canvas.array):
        raise AssertionError(f"{panel.name} {workload}: luma and pixelpen were given different pictures")
    pp_bytes = (bus.bytes_sent - pp_before) / n
    seconds = bus.wire_seconds(bus.bytes_sent - pp_before)
    display.close()
    return Row(panel.name, workload, 1000 * statistics.median(luma_times), (serial.bytes - luma_before) / n,
               1000 * statistics.median(pp_times), pp_bytes, (display.stats.windows - windows_before) / n, ideal / n,
               n / seconds if seconds else math.inf, bus_limit_fps("spi", panel.clock_hz, round(pp_bytes)))


@dataclass
class FullFrames:
    """Full frames on the simulated ST7789: fps in bus time alone and with the driver's host time added."""

    bus_fps: float
    host_bus_fps: float
    limit_fps: float


def simulated_full_frames(frames: int) -> FullFrames:
    """Full frames on ``sim:st7789?size=240x240``: bus time from the simulated clock, host time from the driver."""
    import pixelpen
    from pixelpen.raster.damage import Rect

    panel = PANELS["st7789"]
    start, steps = video(panel, frames)
    display = pixelpen.open("sim:st7789?size=240x240")
    if not isinstance(display, PanelDisplay):
        raise TypeError("sim:st7789 did not open a panel display")
    with display:
        display.canvas.blit(start, 0, 0)
        display.flush()
        t0, host0 = display.clock.now(), display.stats.host_seconds
        for patches in steps:
            for x, y, pixels in patches:
                display.canvas.blit(pixels, x, y)
            display.flush()
        bus_s, host_s = display.clock.now() - t0, display.stats.host_seconds - host0
        full = display.cost.window(Rect(0, 0, 240, 240))
        bus = display.wiring.bus
        limit = bus_limit_fps(bus.kind, bus.clock_hz, full.bytes, full.transfers)
    return FullFrames(len(steps) / bus_s, len(steps) / (bus_s + host_s), limit)


def _goal(met: bool) -> str:
    return "met" if met else "NOT met"


def format_table(rows: list[Row]) -> list[str]:
    """The comparison table, one line per panel and workload, goals beside the numbers."""
    head = (f"{'panel':8} {'workload':8} | {'luma ms':>8} {'luma B':>9} | {'pixelpen ms':>11} {'pp B':>8} "
            f"{'windows':>7} | {'host pp/luma':>12} {'bytes pp/luma':>13} | {'ideal B':>8} {'pp/ideal':>8} | "
            f"{'pp fps':>8} {'limit':>8} {'luma fps':>8}")
    lines = [head, "-" * len(head)]
    for r in rows:
        host, vs_ideal = r.pixelpen_ms / r.luma_ms, r.pixelpen_bytes / max(r.ideal_bytes, 1e-9)
        lines.append(
            f"{r.panel:8} {r.workload:8} | {r.luma_ms:8.3f} {r.luma_bytes:9,.0f} | {r.pixelpen_ms:11.3f} "
            f"{r.pixelpen_bytes:8,.0f} {r.windows:7.1f} | {host:6.2f} {_goal(host <= HOST_GOAL):>5} "
            f"{r.pixelpen_bytes / r.luma_bytes:13.4f} | {r.ideal_bytes:8,.0f} {vs_ideal:5.2f} "
            f"{_goal(vs_ideal <= BYTES_GOAL):>7} | {r.achieved_fps:8,.1f} {r.limit_fps:8,.1f} "
            f"{bus_limit_fps('spi', PANELS[r.panel].clock_hz, round(r.luma_bytes)):8,.1f}")
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=60, help="frames per workload (default 60)")
    parser.add_argument("--panels", default=",".join(PANELS), help="comma-separated: " + ", ".join(PANELS))
    parser.add_argument("--workloads", default=",".join(WORKLOADS), help="comma-separated: " + ", ".join(WORKLOADS))
    args = parser.parse_args(argv)
    warnings.filterwarnings("ignore", "Image.Image.getdata is deprecated", DeprecationWarning)  # luma.oled's own
    rows = [run_workload(PANELS[p], w, args.frames) for p in args.panels.split(",") for w in args.workloads.split(",")]
    print(f"luma.oled/luma.lcd vs pixelpen, {args.frames} frames per workload; ms = median host time per frame, "
          "B = bytes per frame (command + data)")
    print(f"goals: host pp/luma <= {HOST_GOAL}, pp/ideal bytes <= {BYTES_GOAL}; pp fps: in simulated time "
          "(bus time only), limit: pacing.py's bus limit of pixelpen's bytes, luma fps: the bus limit of luma's")
    for line in format_table(rows):
        print(line)
    full = simulated_full_frames(min(args.frames, 30))
    share = full.host_bus_fps / full.limit_fps
    print(f"\nfull frames, sim:st7789?size=240x240 (SpiBus -> simulated spidev -> MipiDcsSim, RGB565, 62.5 MHz): "
          f"bus time alone {full.bus_fps:.1f} fps, host + bus time {full.host_bus_fps:.1f} fps, of the "
          f"{full.limit_fps:.1f} fps bus limit = {100 * share:.1f} % (goal >= {100 * FULL_FRAME_GOAL:.0f} % on "
          f"host + bus: {_goal(share >= FULL_FRAME_GOAL)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""What a MIPI-DCS panel module shows: the known modules' glass geometry and the scan-out from frame memory.

A module's glass is a window of the frame memory at the module's offset (given at MADCTL 0), seen the
way Adafruit's drivers call rotation 0 upright: ST7789 and ST7735 modules turned 180° from the memory
(their rotation 0 is MX|MY), ILI9341 modules mirrored (rotation 0 is MX); with RGB or BGR colour filters
and a normally-white (TN) or normally-black (IPS, needs INVON) liquid crystal. A module held landscape
is its portrait glass turned by 90° (Adafruit rotation 1, MY|MV or MV, upright). The facts are written
here from the makers' published drivers (not from pixelpen's own panel profiles, so each checks the other):

* ST7789 240x240: RAM rows 0..239 (Adafruit ``_rowstart = 320 - height`` when MY is set, TFT_eSPI
  rowstart 80 for its MX|MY rotation); 135x240 at column 52, row 40 (TFT_eSPI colstart 52/53, Pimoroni
  240x135 offsets 40/53 with MADCTL 70h); 240x280 at row 20 (TFT_eSPI PR #1681); 170x320 at column 35;
  172x320 at column 34; all IPS (every maker's init sends INVON), RGB filters.
* ILI9341 240x320: BGR filters (luma's default and Adafruit send BGR), TN.
* ST7735R/S 128x160 "black tab" (Adafruit's default ``INITR_BLACKTAB``: MX|MY, RGB, no offsets, so the
  GM pins strap the 128x160 memory); 80x160 (0.96"): RAM 132x162 at column 26, row 1, BGR, IPS
  (TFT_eSPI GREENTAB160x80 offsets 26/1 under MX|MY, INVON). A "green tab" 128x160 (132x162 memory at
  column 2, row 1, BGR) is ``ram=(132, 162), offset=(2, 1), bgr=True``.

Other sizes get offset (0, 0) and the model's common wiring. Display off and sleep show a blank (black) page;
PTLON blanks the rows outside PTLAR; IDMON keeps each component's top bit (8 colours); VSCRDEF/VSCSAD
scroll the lines between the fixed areas.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from PIL import Image

from pixelpen.sim.panels.dcs_pixels import to_8bit


@dataclass(frozen=True)
class Module:
    """A panel module's glass: where it sits in frame memory and how it is wired."""

    offset: tuple[int, int]
    """RAM (column, row) of the glass's top-left pixel at MADCTL 0 (before the module's turn)."""
    flipped: bool = False
    """Mounted turned 180° from the memory (the upright MADCTL has MX and MY set)."""
    mirrored: bool = False
    """Source outputs wired right to left (the upright MADCTL has MX set)."""
    bgr: bool = False
    """Colour filters in B, G, R order: MADCTL BGR=1 shows true colours."""
    normally_black: bool = False
    """IPS liquid crystal: true colours need INVON."""
    ram: tuple[int, int] | None = None
    """The frame memory's (columns, rows) when the module straps a smaller one than the chip's."""


KNOWN_MODULES: dict[tuple[str, int, int], Module] = {
    ("st7789", 240, 240): Module((0, 0), flipped=True, normally_black=True),
    ("st7789", 240, 320): Module((0, 0), flipped=True, normally_black=True),
    ("st7789", 135, 240): Module((52, 40), flipped=True, normally_black=True),
    ("st7789", 240, 280): Module((0, 20), flipped=True, normally_black=True),
    ("st7789", 170, 320): Module((35, 0), flipped=True, normally_black=True),
    ("st7789", 172, 320): Module((34, 0), flipped=True, normally_black=True),
    ("ili9341", 240, 320): Module((0, 0), mirrored=True, bgr=True),
    ("st7735", 128, 160): Module((0, 0), flipped=True, ram=(128, 160)),
    ("st7735", 80, 160): Module((26, 1), flipped=True, bgr=True, normally_black=True),
}
"""(model, portrait width, portrait height) -> module facts."""


GENERIC_MODULES: dict[str, Module] = {
    "st7789": Module((0, 0), flipped=True, normally_black=True),
    "ili9341": Module((0, 0), mirrored=True, bgr=True),
    "st7735": Module((0, 0), flipped=True),
}
"""An unlisted size of each model: wired like the model's common modules, at offset (0, 0)."""


def known_module(model: str, portrait: tuple[int, int]) -> Module:
    """The module of that model and portrait size, or the model's generic one."""
    return KNOWN_MODULES.get((model, *portrait), GENERIC_MODULES.get(model, Module((0, 0))))


@dataclass(frozen=True)
class ScanOut:
    """The controller state the scan-out reads: what is on, the colour settings and the line mapping."""

    showing: bool
    """Sleep out, display on and not in reset."""
    inverted: bool
    bgr: bool
    idle: bool
    partial: tuple[int, int] | None
    """PTLON's PSL..PEL rows (inclusive; PEL < PSL wraps), None in normal mode."""
    scroll: tuple[int, int, int] | None
    """(TFA, VSA, VSP) in vertical scroll mode, None otherwise."""


def line_map(rows: int, scroll: tuple[int, int, int] | None) -> NDArray[np.intp]:
    """The frame-memory row each panel line shows (VSCRDEF/VSCSAD rolling scroll, ST7789VW §8.14)."""
    lines = np.arange(rows, dtype=np.intp)
    if scroll is None:
        return lines
    tfa, vsa, vsp = scroll
    area = (lines >= tfa) & (lines < tfa + vsa)
    lines[area] = tfa + (lines[area] - tfa + vsp - tfa) % vsa
    return lines


def render(ram: NDArray[np.uint8], module: Module, size: tuple[int, int], turn: int, state: ScanOut) -> Image.Image:
    """The glass as a person sees it: ``size`` (width, height) RGB, the portrait window turned ``turn`` degrees."""
    width, height = size
    pw, ph = (height, width) if turn % 180 else (width, height)
    if not state.showing:
        return Image.new("RGB", size)
    col, row = module.offset
    rows = line_map(ram.shape[0], state.scroll)
    window = ram[rows[row:row + ph]][:, col:col + pw]
    if window.shape[:2] != (ph, pw):  # a glass larger than the memory past its offset: the rest stays dark
        padded = np.zeros((ph, pw, 3), dtype=np.uint8)
        padded[:window.shape[0], :window.shape[1]] = window
        window = padded
    if state.idle:
        window = np.where(window >= 32, 63, 0).astype(np.uint8)
    if state.inverted != module.normally_black:
        window = 63 - window
    if state.bgr != module.bgr:
        window = window[:, :, ::-1]
    glass = to_8bit(window)
    if state.partial is not None:  # the non-display area shows a blank page
        first, last = state.partial
        lines = np.arange(row, row + ph)
        shown = (lines >= first) & (lines <= last) if first <= last else (lines >= first) | (lines <= last)
        glass[~shown] = 0
    if module.mirrored:
        glass = glass[:, ::-1]
    pixels = np.ascontiguousarray(np.rot90(glass, (turn + (180 if module.flipped else 0)) // 90))
    return Image.fromarray(pixels, "RGB")

"""SSD1306Sim: an SSD1306, SH1106 or SSD1309 OLED module decoded from the wire (I2C or 4-wire SPI) to the glass.

GDDRAM is 8 pages x 128 columns (SH1106: 132), one byte = 8 rows, bit 0 on top (SSD1306 Rev 1.1 §8.7).
The module is mounted as the common ones are: with segment remap A1h and COM scan C8h the glass shows RAM
upright from column ``colstart`` (64-wide modules: 32; SH1106: 2); its rows are wired for its own COM pin
configuration (DAh 12h for 64/48-row modules, 02h for 32/16-row ones), so a different DAh value shows the
interleaving a real module shows.  See docs/panel-simulators.md for what is flagged and known differences.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from PIL import Image

from pixelpen.clock import Clock
from pixelpen.errors import ConfigError
from pixelpen.options import OptionSpec, OptionValues, boolean, i2c_address, integer, number, pixels
from pixelpen.sim.panels.base import PanelSim, register_panel_simulators

HORIZONTAL, VERTICAL, PAGE = 0, 1, 2
"""Memory addressing modes (20h parameter)."""


@dataclass(frozen=True)
class Variant:
    """What differs between the controllers of the family."""

    name: str
    ram_columns: int
    commands: dict[int, tuple[str, int]]
    """Command byte -> (name, parameter count), besides the ranges every variant has."""
    high_nibbles: int
    """Column high-nibble commands 10h.. that address the RAM (SSD1306: 10h-17h; SH1106: 10h-18h)."""
    spi_limit_hz: float
    i2c_limit_hz: float = 400e3
    charge_pump: bool = True
    """The module runs from the controller's charge pump (8Dh 14h must precede AFh)."""


_FUNDAMENTAL = {0x81: ("contrast", 1), 0xA4: ("follow RAM", 0), 0xA5: ("entire display on", 0),
                0xA6: ("normal", 0), 0xA7: ("inverse", 0), 0xAE: ("display off", 0), 0xAF: ("display on", 0),
                0xA0: ("segment normal", 0), 0xA1: ("segment remap", 0), 0xA8: ("multiplex", 1),
                0xD3: ("display offset", 1), 0xD5: ("clock divide", 1), 0xD9: ("pre-charge", 1),
                0xDA: ("COM pins", 1), 0xDB: ("VCOMH", 1), 0xE3: ("NOP", 0)}
_SSD = {**_FUNDAMENTAL, 0x20: ("addressing mode", 1), 0x21: ("column address", 2), 0x22: ("page address", 2),
        0x26: ("right scroll", 6), 0x27: ("left scroll", 6), 0x29: ("vertical right scroll", 5),
        0x2A: ("vertical left scroll", 5), 0x2E: ("deactivate scroll", 0), 0x2F: ("activate scroll", 0),
        0xA3: ("vertical scroll area", 2), 0x8D: ("charge pump", 1)}

VARIANTS = {
    "ssd1306": Variant("ssd1306", 128, _SSD, 8, 10e6),
    "ssd1309": Variant("ssd1309", 128, {**_SSD, 0xFD: ("command lock", 1)}, 8, 10e6, charge_pump=False),
    "sh1106": Variant("sh1106", 132, {**_FUNDAMENTAL, 0xAD: ("DC-DC", 1), 0x30: ("pump voltage", 0),
                                      0x31: ("pump voltage", 0), 0x32: ("pump voltage", 0),
                                      0x33: ("pump voltage", 0), 0xE0: ("read-modify-write", 0),
                                      0xEE: ("end", 0)}, 9, 4e6),
}
"""SH1106: SPI clock cycle 250 ns (4 MHz); SSD1306/SSD1309: 100 ns (10 MHz)."""

_COM_SPLIT = 32
FOSC_HZ = 370e3
"""The oscillator's typical frequency at the reset setting D5h[7:4] = 1000b (the only one the datasheet gives)."""
SCROLL_FRAMES = {0: 5, 1: 64, 2: 128, 3: 256, 4: 3, 5: 4, 6: 25, 7: 2}
"""Scroll step interval code (26h/27h/29h/2Ah parameter C) -> frames per step."""


def com_pin_rows(config: int) -> NDArray[np.intp]:
    """Physical pad row (0..63) of each COM signal 0..63 for a DAh parameter (bit 4 alternative, bit 5 L/R remap)."""
    c = np.arange(64)
    half = c % _COM_SPLIT
    upper = c >= _COM_SPLIT
    if config & 0x20:
        upper = ~upper
    if config & 0x10:
        return np.asarray(2 * half + upper, dtype=np.intp)
    return np.asarray(half + _COM_SPLIT * upper, dtype=np.intp)


class SSD1306Sim(PanelSim):
    """An SSD1306-family OLED module, ``width`` x ``height`` glass pixels (``variant`` ssd1306, sh1106, ssd1309).

    ``address``: its I2C address; ``clock_hz``: the bus clock for bus time (default: 10 MHz SPI, 400 kHz I2C;
    SH1106 4 MHz SPI); ``colstart``: the RAM column of the glass's left edge under A1h; ``com_pins``: the DAh
    value the module's rows are wired for; ``external_vcc``: the module has its own VCC (no charge pump needed;
    default for SSD1309).  ``glass()`` is mode "1" (lit = white); ``glass(shaded=True)`` mode "L" with lit
    pixels at the contrast's level ``255 * (contrast + 1) / 256``.
    """

    def __init__(self, width: int = 128, height: int = 64, *, variant: str = "ssd1306", address: int = 0x3C,
                 clock: Clock | None = None, clock_hz: float | None = None, colstart: int | None = None,
                 com_pins: int | None = None, external_vcc: bool | None = None, strict: bool = False) -> None:
        if variant not in VARIANTS:
            raise ConfigError(f"SSD1306Sim: unknown variant {variant!r}; known: {', '.join(sorted(VARIANTS))}")
        spec = VARIANTS[variant]
        self.model = variant
        self.variant = spec
        if colstart is None:
            colstart = 2 if variant == "sh1106" else (32 if width == 64 else 0)
        if not (width >= 8 and colstart >= 0 and colstart + width <= spec.ram_columns):
            raise ConfigError(f"{variant}: a {width}-pixel-wide glass from column {colstart} does not fit "
                              f"{spec.ram_columns} RAM columns")
        if height not in (16, 24, 32, 40, 48, 56, 64):
            raise ConfigError(f"{variant}: glass height must be a multiple of 8 from 16 to 64, got {height}")
        self.width, self.height, self.colstart = width, height, colstart
        self.module_com_pins = com_pins if com_pins is not None else (0x12 if height >= 48 or width == 64 else 0x02)
        self.external_vcc = (not spec.charge_pump) if external_vcc is None else external_vcc
        hz = clock_hz
        super().__init__(clock=clock, clock_hz=hz if hz is not None else spec.spi_limit_hz, strict=strict,
                         i2c_address=address, i2c_clock_hz=hz if hz is not None else spec.i2c_limit_hz,
                         spi_limit_hz=spec.spi_limit_hz, i2c_limit_hz=spec.i2c_limit_hz)
        self._rng = np.random.default_rng(address)
        self._ram = self._power_on_ram()
        self._wired = np.argsort(com_pin_rows(self.module_com_pins))
        """Pad row -> the module's row in die order (the inverse of its own COM pin configuration)."""
        self._panel_reset()

    # ---- state -------------------------------------------------------------------------------------
    def _power_on_ram(self) -> NDArray[np.uint8]:
        """GDDRAM at power-up: undefined (here seeded noise, so a missing clear shows)."""
        return self._rng.integers(0, 256, (8, self.variant.ram_columns), dtype=np.uint8)

    def _panel_reset(self) -> None:
        """RES#: the datasheet's reset values (§8.9); GDDRAM keeps its contents."""
        self.contrast = 0x7F
        self.entire_on = False
        self.inverse = False
        self.display_on = False
        self.multiplex = 64
        self.display_offset = 0
        self.start_line = 0
        self.segment_remap = False
        self.com_reverse = False
        self.com_pins = 0x12
        self.clock_divide, self.precharge, self.vcomh = 0x80, 0x22, 0x20
        self.charge_pump = self.variant.name == "sh1106"  # SH1106: DC-DC on at reset (ADh 8Bh)
        self.mode = PAGE
        self.window = (0, self.variant.ram_columns - 1, 0, 7)
        """(column start, column end, page start, page end) of 21h/22h."""
        self.column, self.page = 0, 0
        self.scrolling = False
        self.scroll: tuple[int, bytes] | None = None
        """The last scroll setup (26h/27h/29h/2Ah): (command, parameters)."""
        self.scroll_area = (0, 64)
        """A3h: (top fixed rows, scrolling rows)."""
        self._scroll_start = 0.0
        self.locked = False
        self._pending: list[int] = []
        self._code: int | None = None
        self._wrote = False

    def _panel_power_loss(self) -> None:
        self._ram = self._power_on_ram()
        self._panel_reset()

    # ---- bytes -------------------------------------------------------------------------------------
    def _panel_command(self, code: int) -> None:
        if self._wrote:
            self._wrote = False
            self._count_frame()
        if self._code is not None:
            self._pending.append(code)
            if len(self._pending) == self.variant.commands[self._code][1]:
                command, params = self._code, bytes(self._pending)
                self._code, self._pending = None, []
                self._execute(command, params)
            return
        if self.locked and code != 0xFD:
            self._report(code, f"command 0x{code:02X} ignored: commands are locked (FDh 16h)")
            return
        if code in self.variant.commands:
            if self.variant.commands[code][1]:
                self._code = code
            else:
                self._execute(code, b"")
        elif code <= 0x0F:
            self._set_column((self.column & 0xF0) | code)
        elif code < 0x10 + self.variant.high_nibbles:
            self._set_column((self.column & 0x0F) | (code - 0x10) << 4)
        elif 0x40 <= code <= 0x7F:
            self.start_line = code - 0x40
        elif 0xB0 <= code <= 0xB7:
            self.page = code - 0xB0
        elif 0xC0 <= code <= 0xCF:
            self.com_reverse = bool(code & 0x08)
        else:
            self._report(code, f"prohibited command byte 0x{code:02X} (not in the {self.model} command table)")

    def _set_column(self, column: int) -> None:
        """A nibble of the column address: the value may pass the RAM until the other nibble arrives."""
        self.column = column

    def _panel_data(self, data: bytes) -> None:
        if self._code is not None:
            name, count = self.variant.commands[self._code]
            self._report(self._code, f"{name} (0x{self._code:02X}) truncated: {len(self._pending)} of {count} "
                                     "parameter bytes before data")
            self._code, self._pending = None, []
        if self.scrolling:
            self._report(None, "GDDRAM written while scrolling is active (datasheet: RAM may be corrupted)")
        self._write(np.frombuffer(data, dtype=np.uint8))
        self._wrote = True

    def _write(self, data: NDArray[np.uint8]) -> None:
        """Store bytes at the pointer and move it by the datasheet's rules for the addressing mode (§10.1.3)."""
        ram_columns = self.variant.ram_columns
        if self.column >= ram_columns:
            self._report(None, f"column address {self.column} is past the {ram_columns} RAM columns: wraps")
            self.column %= ram_columns
        cs, ce, ps, pe = self.window
        n = len(data)
        inside = cs <= self.column <= ce and ps <= self.page <= pe
        steps = np.arange(max(0, n - ram_columns * 8), n)  # the pointer visits at most 8 x RAM columns cells
        if self.mode == PAGE:
            cols = (self.column + steps) % ram_columns
            pages = np.full(len(steps), self.page)
            self.column = int(cols[-1] + 1) % ram_columns
        elif inside and cs <= ce and ps <= pe:
            wc, wp = ce - cs + 1, pe - ps + 1
            major, minor = (self.page - ps, self.column - cs) if self.mode == HORIZONTAL else \
                (self.column - cs, self.page - ps)
            size = wc if self.mode == HORIZONTAL else wp
            q = (major * size + minor + steps) % (wc * wp)
            if self.mode == HORIZONTAL:
                pages, cols = ps + q // wc, cs + q % wc
            else:
                cols, pages = cs + q // wp, ps + q % wp
            self.column, self.page = self._step(int(cols[-1]), int(pages[-1]))
        else:  # a pointer outside its window or a window with start > end: stepped, the path's cycle tiled
            steps, cols, pages = self._walk(n)
            self.column, self.page = self._step(int(cols[-1]), int(pages[-1]))
        self._ram[pages, cols] = data[steps]  # in step order: later bytes win where the pointer came round

    def _walk(self, n: int) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
        """(steps, columns, pages) of what ``n`` bytes from the pointer leave in RAM, by ``_step``: the pointer
        has 8 x RAM columns states, so its path repeats within that many steps; the path is walked once and
        only its first visits before the cycle and the cycle's last lap are kept (the last step included)."""
        seen: dict[tuple[int, int], int] = {}
        path: list[tuple[int, int]] = []
        state = (self.column, self.page)
        while len(path) < n and state not in seen:
            seen[state] = len(path)
            path.append(state)
            state = self._step(*state)
        steps = np.arange(n)
        if len(path) < n:  # path[start:] is the cycle
            start = seen[state]
            lap = len(path) - start
            steps = np.concatenate([np.arange(start), np.arange(max(start, n - lap), n)])
            steps_on_path = np.where(steps < len(path), steps, start + (steps - start) % lap)
        else:
            steps_on_path = steps
        walked = np.asarray(path, dtype=np.intp)[steps_on_path]
        return steps, walked[:, 0], walked[:, 1]

    def _step(self, column: int, page: int) -> tuple[int, int]:
        """The pointer after a byte at (column, page) in horizontal or vertical mode (wraps at window ends)."""
        cs, ce, ps, pe = self.window
        if self.mode == HORIZONTAL:
            if column == ce:
                return cs, (ps if page == pe else (page + 1) % 8)
            return (column + 1) % self.variant.ram_columns, page
        if page == pe:
            return (cs if column == ce else (column + 1) % self.variant.ram_columns), ps
        return column, (page + 1) % 8

    # ---- commands ----------------------------------------------------------------------------------
    def _execute(self, code: int, params: bytes) -> None:
        p = params[0] if params else 0
        if code == 0x81:
            self.contrast = p
        elif code in (0xA4, 0xA5):
            self.entire_on = code == 0xA5
        elif code in (0xA6, 0xA7):
            self.inverse = code == 0xA7
        elif code in (0xA0, 0xA1):
            self.segment_remap = code == 0xA1
        elif code == 0xAE:
            self.display_on = False
        elif code == 0xAF:
            self.display_on = True
            if not (self.charge_pump or self.external_vcc):
                self._report(code, "display on (AFh) with the charge pump off: 8Dh 14h must come first; "
                                   "the glass stays dark")
        elif code == 0xA8:
            self._set_multiplex(p)
        elif code == 0xD3:
            self.display_offset = p & 0x3F
        elif code == 0xDA:
            if p & 0xCF != 0x02:
                self._report(code, f"COM pins parameter 0x{p:02X}: bits other than 4 and 5 must be 02h")
            self.com_pins = p & 0x30 | 0x02
        elif code == 0xD5:
            self.clock_divide = p
        elif code == 0xD9:
            if p & 0x0F == 0 or p & 0xF0 == 0:
                self._report(code, f"pre-charge 0x{p:02X}: a phase of 0 DCLKs is invalid")
            self.precharge = p
        elif code == 0xDB:
            self.vcomh = p
        elif code == 0x8D:
            self.charge_pump = bool(p & 0x04)
        elif code == 0xAD:
            self.charge_pump = bool(p & 0x01)
        elif code == 0xFD:
            self.locked = p & 0x04 != 0
        else:
            self._addressing(code, params)

    def _set_multiplex(self, p: int) -> None:
        if p & 0x3F < 15 and self.model != "sh1106":
            self._report(0xA8, f"multiplex ratio {p & 0x3F} + 1 is invalid (16 to 64)")
            return
        self.multiplex = (p & 0x3F) + 1

    def _addressing(self, code: int, params: bytes) -> None:
        if code == 0x20:
            if params[0] & 0x03 == 3:
                self._report(code, "addressing mode 11b is invalid")
            else:
                self.mode = params[0] & 0x03
        elif code == 0x21:
            cs, ce = params[0] & 0x7F, params[1] & 0x7F
            if cs > ce:
                self._report(code, f"column window start {cs} is past its end {ce}")
            self.window = (cs, ce, *self.window[2:])
            self.column = cs
        elif code == 0x22:
            ps, pe = params[0] & 0x07, params[1] & 0x07
            if ps > pe:
                self._report(code, f"page window start {ps} is past its end {pe}")
            self.window = (*self.window[:2], ps, pe)
            self.page = ps
        elif code in (0x26, 0x27, 0x29, 0x2A, 0xA3):
            if self.scrolling:
                self._report(code, "scroll set up while scrolling is active (2Eh must come first)")
            if code == 0xA3:
                self.scroll_area = (params[0] & 0x3F, params[1] & 0x7F)
            else:
                self.scroll = (code, params)
                if params[1] & 7 > params[3] & 7:
                    self._report(code, f"scroll end page {params[3] & 7} is before its start page {params[1] & 7}")
        elif code == 0x2E:
            if self.scrolling:
                self._ram[:] = self._scrolled(self._ram, bits=False)  # horizontal scrolling moved RAM itself
            self.scrolling = False
        elif code == 0x2F:
            if self.scroll is None:
                self._report(code, "activate scroll (2Fh) with no scroll set up (26h/27h/29h/2Ah)")
            else:
                self.scrolling, self._scroll_start = True, self._now

    # ---- what it shows -----------------------------------------------------------------------------
    @property
    def gram(self) -> NDArray[np.uint8]:
        """GDDRAM, read-only: (8 pages, RAM columns) uint8 bytes as stored, bit 0 the top row of its page."""
        view = self._ram.view()
        view.flags.writeable = False
        return view

    @property
    def frame_rate(self) -> float:
        """Frames per second: Fosc / (D x K x MUX), D = D5h[3:0] + 1, K = phase 1 + phase 2 + 50 (typical Fosc)."""
        phases = (self.precharge & 0x0F) + (self.precharge >> 4)
        return FOSC_HZ / (((self.clock_divide & 0x0F) + 1) * (phases + 50) * self.multiplex)

    def scroll_steps(self) -> int:
        """Scroll steps taken since 2Fh (0 when not scrolling)."""
        if not self.scrolling or self.scroll is None:
            return 0
        frames = (self._now - self._scroll_start) * self.frame_rate
        return int(frames // SCROLL_FRAMES[self.scroll[1][2] & 7])

    def _scrolled(self, ram: NDArray[Any], *, bits: bool) -> NDArray[Any]:
        """RAM (pages x columns bytes, or rows x columns pixels when ``bits``) as continuous scrolling shows it."""
        steps = self.scroll_steps()
        if not steps or self.scroll is None:
            return ram
        code, params = self.scroll
        out = ram.copy()
        first, last = params[1] & 7, params[3] & 7
        rows = slice(8 * first, 8 * last + 8) if bits else slice(first, last + 1)
        out[rows] = np.roll(ram[rows], steps if code in (0x26, 0x29) else -steps, axis=1)
        if bits and code in (0x29, 0x2A):
            top, count = self.scroll_area
            count = min(count, 64 - top)
            if count:
                area = slice(top, top + count)
                out[area] = np.roll(out[area], -(steps * (params[4] & 0x3F)) % count, axis=0)
        return out

    def row_sources(self) -> NDArray[np.intp]:
        """The RAM row (0..63) each glass row shows, -1 for a row no COM drives (§10.1.12-19 scan-out)."""
        k = np.arange(self.multiplex)
        line = (k - self.display_offset) % 64
        signal = (self.multiplex - 1 - line) % 64 if self.com_reverse else line
        die_row = self._wired[com_pin_rows(self.com_pins)[signal]]
        sources = np.full(64, -1, dtype=np.intp)
        sources[die_row] = (self.start_line + k) % 64
        return sources[: self.height][::-1].copy()

    def column_sources(self) -> NDArray[np.intp]:
        """The RAM column each glass column shows (A0h/A1h)."""
        x = np.arange(self.width)
        if self.segment_remap:
            return self.colstart + x
        return self.variant.ram_columns - 1 - self.colstart - x

    def lit(self) -> NDArray[np.bool_]:
        """(height, width) bool: the pixels that are lit now."""
        self._catch_up()
        dark = not self.display_on or self.in_reset or not (self.charge_pump or self.external_vcc)
        if dark:
            return np.zeros((self.height, self.width), dtype=bool)
        if self.entire_on:
            pixels = np.ones((64, self.variant.ram_columns), dtype=bool)
        else:
            ram = np.unpackbits(self._ram, axis=0, bitorder="little").astype(bool)
            pixels = self._scrolled(ram, bits=True) ^ self.inverse
        rows = self.row_sources()
        out = pixels[np.maximum(rows, 0)][:, self.column_sources()]
        out[rows < 0] = False
        return out

    def glass(self, shaded: bool = False) -> Image.Image:
        """The module's glass: mode "1" (lit white), or "L" at the contrast's level when ``shaded``."""
        lit = self.lit()
        if not shaded:
            return Image.fromarray(lit)
        level = round(255 * (self.contrast + 1) / 256)
        return Image.fromarray(np.where(lit, level, 0).astype(np.uint8), "L")


def _byte(text: str) -> int:
    value = int(text.strip(), 0)
    if not 0 <= value <= 0xFF:
        raise ValueError("expected a byte 0..0xff")
    return value


OPTIONS: tuple[OptionSpec[Any], ...] = (
    OptionSpec("size", pixels, (128, 64), "glass size WxH"),
    OptionSpec("address", i2c_address, 0x3C, "I2C address, 0x08..0x77 (modules: 0x3c or 0x3d)"),
    OptionSpec("hz", number(1, above=True), None, "bus clock in Hz for bus time (default: the datasheet's)"),
    OptionSpec("colstart", integer(0, 131), None, "RAM column of the glass's left edge (default: 64-wide 32, "
                                                  "SH1106 2, else 0)"),
    OptionSpec("compins", _byte, None, "the DAh value the module's rows are wired for (default 0x12, 32/16 rows 0x02)"),
    OptionSpec("external_vcc", boolean, None, "the module has its own VCC (default: SSD1309 yes, else no)"),
    OptionSpec("strict", boolean, False, "raise ProtocolError for what the controller would flag"),
)


def _build(variant: str, values: OptionValues, clock: Clock | None) -> SSD1306Sim:
    """The simulator of a ``sim:MODEL?...`` URL (options: ``OPTIONS``)."""
    width, height = values["size"]
    return SSD1306Sim(width, height, variant=variant, address=values["address"], clock=clock, clock_hz=values["hz"],
                      colstart=values["colstart"], com_pins=values["compins"], external_vcc=values["external_vcc"],
                      strict=values["strict"])


register_panel_simulators(VARIANTS, _build, OPTIONS)

"""The MIPI-DCS command tables of the ST7789VW, ILI9341 and ST7735S/R, and the per-model facts the simulator needs.

One row per command byte: its name, how many parameter bytes it takes (a range where datasheets and
common init tables differ; RAMWR/WRMEMC take a pixel stream), and the simulator action that carries it
out (``register``: stored, no visible effect; ``read``: a read command, its data phase is the host
clocking dummy bytes). Counts are from the command lists: ST7789VW v1.0 §9.1/§9.2 (VDVVRHEN: 1 or 2, its
fixed FFh second byte is left out by every common init), ILI9341 v1.11 §8.1
(plus the "extend register" commands §8.4 and the undocumented EF with the three parameters of the
Adafruit/luma init), ST7735 v1.2 §10.1/§10.2 with the ST7735R/S counts of Adafruit's tables (PWCTR1 3,
VMCTR1 1). Undefined bytes are "treated as NOP" (ILI9341 and ST7735 notes).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

from pixelpen.sim.panels.dcs_pixels import DBI_FORMATS, FORMAT_18, PixelFormat

STREAM = 1 << 62
"""``most`` of a command that takes pixel data until the next command."""

Registers = Mapping[int, bytes]
"""The last parameters written to each ``register`` command (reset values included)."""


@dataclass(frozen=True)
class Command:
    """One command byte: name, parameter byte count (least..most) and the simulator's action."""

    code: int
    name: str
    least: int
    most: int
    action: str


@dataclass(frozen=True)
class FrameTiming:
    """The panel's refresh: seconds per frame and the vertical blanking at each frame's end (TE high)."""

    period: float
    blanking: float


@dataclass(frozen=True)
class Waits:
    """The datasheet's waits (seconds): no command this long after RESX, SWRESET, SLPIN, SLPOUT; and the sleep toggle.

    ``sleep_toggle`` separates SLPOUT and SLPIN either way, and RESX or SWRESET from the next SLPOUT.
    """

    reset: float
    swreset: float
    slpin: float
    slpout: float
    sleep_toggle: float


@dataclass(frozen=True)
class Model:
    """A controller: memory size, commands, interface formats, bus limit, the datasheet's waits and frame timing."""

    name: str
    cols: int
    rows: int
    commands: Mapping[int, Command]
    formats: Mapping[int, PixelFormat]
    max_write_hz: float
    default_clock_hz: float
    waits: Waits
    reset_registers: Registers
    frame_timing: Callable[[Registers], FrameTiming]
    madctl_xor: Callable[[Registers], tuple[int, bool]]
    """MADCTL bits (and whether inversion) a register exchanges (ST7789 LCMCTRL, ILI9341 interface control)."""


def _table(*rows: tuple[int, str, int | tuple[int, int], str]) -> dict[int, Command]:
    out = {}
    for code, name, count, action in rows:
        least, most = count if isinstance(count, tuple) else (count, count)
        out[code] = Command(code, name, least, most, action)
    return out


_PIXELS = (0, STREAM)

_DCS = _table(
    (0x00, "NOP", 0, "nop"), (0x01, "SWRESET", 0, "swreset"),
    (0x04, "RDDID", 0, "read"), (0x09, "RDDST", 0, "read"), (0x0A, "RDDPM", 0, "read"),
    (0x0B, "RDDMADCTL", 0, "read"), (0x0C, "RDDCOLMOD", 0, "read"), (0x0D, "RDDIM", 0, "read"),
    (0x0E, "RDDSM", 0, "read"), (0x0F, "RDDSDR", 0, "read"),
    (0x10, "SLPIN", 0, "slpin"), (0x11, "SLPOUT", 0, "slpout"), (0x12, "PTLON", 0, "ptlon"),
    (0x13, "NORON", 0, "noron"), (0x20, "INVOFF", 0, "invoff"), (0x21, "INVON", 0, "invon"),
    (0x26, "GAMSET", 1, "gamset"), (0x28, "DISPOFF", 0, "dispoff"), (0x29, "DISPON", 0, "dispon"),
    (0x2A, "CASET", 4, "caset"), (0x2B, "RASET", 4, "raset"), (0x2C, "RAMWR", _PIXELS, "ramwr"),
    (0x2E, "RAMRD", 0, "read"), (0x30, "PTLAR", 4, "ptlar"), (0x33, "VSCRDEF", 6, "vscrdef"),
    (0x34, "TEOFF", 0, "teoff"), (0x35, "TEON", 1, "teon"), (0x36, "MADCTL", 1, "madctl"),
    (0x37, "VSCSAD", 2, "vscsad"), (0x38, "IDMOFF", 0, "idmoff"), (0x39, "IDMON", 0, "idmon"),
    (0x3A, "COLMOD", 1, "colmod"),
    (0xDA, "RDID1", 0, "read"), (0xDB, "RDID2", 0, "read"), (0xDC, "RDID3", 0, "read"),
)
"""The core every model has (ST7735 v1.2 lists 33h/37h only in its V-sync note; the ST7735R/S have them)."""

_DCS_BRIGHTNESS = _table(
    (0x3C, "WRMEMC", _PIXELS, "wrmemc"), (0x3E, "RDMEMC", 0, "read"), (0x44, "STE", 2, "register"),
    (0x45, "GSCAN", 0, "read"), (0x51, "WRDISBV", 1, "register"), (0x52, "RDDISBV", 0, "read"),
    (0x53, "WRCTRLD", 1, "register"), (0x54, "RDCTRLD", 0, "read"), (0x55, "WRCACE", 1, "register"),
    (0x56, "RDCABC", 0, "read"), (0x5E, "WRCABCMB", 1, "register"), (0x5F, "RDCABCMB", 0, "read"),
)
"""Memory-continue, tear scanline and brightness commands of the ST7789 and ILI9341."""

_ST7789_ONLY = _table(
    (0x68, "RDABCSDR", 0, "read"),
    (0xB0, "RAMCTRL", 2, "register"), (0xB1, "RGBCTRL", 3, "register"), (0xB2, "PORCTRL", 5, "register"),
    (0xB3, "FRCTRL1", 3, "register"), (0xB5, "PARCTRL", 1, "register"), (0xB7, "GCTRL", 1, "register"),
    (0xB8, "GTADJ", 4, "register"), (0xBA, "DGMEN", 1, "register"), (0xBB, "VCOMS", 1, "register"),
    (0xBC, "POWSAVE", 1, "register"), (0xBD, "DLPOFFSAVE", 1, "register"), (0xC0, "LCMCTRL", 1, "register"),
    (0xC1, "IDSET", 3, "register"), (0xC2, "VDVVRHEN", (1, 2), "register"), (0xC3, "VRHS", 1, "register"),
    (0xC4, "VDVS", 1, "register"), (0xC5, "VCMOFSET", 1, "register"), (0xC6, "FRCTRL2", 1, "register"),
    (0xC7, "CABCCTRL", 1, "register"), (0xC8, "REGSEL1", 1, "register"), (0xCA, "REGSEL2", 1, "register"),
    (0xCC, "PWMFRSEL", 1, "register"), (0xD0, "PWCTRL1", 2, "register"), (0xD2, "VAPVANEN", 1, "register"),
    (0xDF, "CMD2EN", 4, "register"), (0xE0, "PVGAMCTRL", 14, "register"), (0xE1, "NVGAMCTRL", 14, "register"),
    (0xE2, "DGMLUTR", 64, "register"), (0xE3, "DGMLUTB", 64, "register"), (0xE4, "GATECTRL", 3, "register"),
    (0xE7, "SPI2EN", 1, "register"), (0xE8, "PWCTRL2", 1, "register"), (0xE9, "EQCTRL", 3, "register"),
    (0xEC, "PROMCTRL", 1, "register"), (0xFA, "PROMEN", 4, "register"), (0xFC, "NVMSET", 2, "register"),
    (0xFE, "PROMACT", 2, "register"),
)

_ILI9341_ONLY = _table(
    (0x2B, "PASET", 4, "raset"), (0x2D, "RGBSET", 128, "register"),
    (0xB0, "IFMODE", 1, "register"), (0xB1, "FRMCTR1", 2, "register"), (0xB2, "FRMCTR2", 2, "register"),
    (0xB3, "FRMCTR3", 2, "register"), (0xB4, "INVTR", 1, "register"), (0xB5, "PRCTR", 4, "register"),
    (0xB6, "DISCTRL", (3, 4), "register"), (0xB7, "ETMOD", 1, "register"), (0xB8, "BLCTRL1", 1, "register"),
    (0xB9, "BLCTRL2", 1, "register"), (0xBA, "BLCTRL3", 1, "register"), (0xBB, "BLCTRL4", 1, "register"),
    (0xBC, "BLCTRL5", 1, "register"), (0xBE, "BLCTRL7", 1, "register"), (0xBF, "BLCTRL8", 1, "register"),
    (0xC0, "PWCTRL1", 1, "register"), (0xC1, "PWCTRL2", 1, "register"), (0xC5, "VMCTRL1", 2, "register"),
    (0xC7, "VMCTRL2", 1, "register"), (0xD0, "NVMWR", 2, "register"), (0xD1, "NVMPKEY", 3, "register"),
    (0xD2, "RDNVM", 0, "read"), (0xD3, "RDID4", 0, "read"), (0xE0, "PGAMCTRL", 15, "register"),
    (0xE1, "NGAMCTRL", 15, "register"), (0xE2, "DGAMCTRL1", 16, "register"), (0xE3, "DGAMCTRL2", 64, "register"),
    (0xF6, "IFCTL", 3, "register"),
    (0xCB, "PWCTRLA", 5, "register"), (0xCF, "PWCTRLB", 3, "register"), (0xE8, "DTCTRLA", 3, "register"),
    (0xE9, "DTCTRLA2", 3, "register"), (0xEA, "DTCTRLB", 2, "register"), (0xED, "PWONSEQ", 4, "register"),
    (0xF2, "EN3G", 1, "register"), (0xF7, "PUMPRATIO", 1, "register"), (0xEF, "UNDOC_EF", 3, "register"),
)

_ST7735_ONLY = _table(
    (0x2D, "RGBSET", 128, "register"),
    (0xB1, "FRMCTR1", 3, "register"), (0xB2, "FRMCTR2", 3, "register"), (0xB3, "FRMCTR3", 6, "register"),
    (0xB4, "INVCTR", 1, "register"), (0xB6, "DISSET5", 2, "register"), (0xC0, "PWCTR1", (2, 3), "register"),
    (0xC1, "PWCTR2", 1, "register"), (0xC2, "PWCTR3", 2, "register"), (0xC3, "PWCTR4", 2, "register"),
    (0xC4, "PWCTR5", 2, "register"), (0xC5, "VMCTR1", (1, 2), "register"), (0xC7, "VMOFCTR", 1, "register"),
    (0xD1, "WRID2", 1, "register"), (0xD2, "WRID3", 1, "register"), (0xD9, "NVCTR1", 1, "register"),
    (0xDE, "NVCTR2", 1, "register"), (0xDF, "NVCTR3", 3, "register"), (0xE0, "GMCTRP1", 16, "register"),
    (0xE1, "GMCTRN1", 16, "register"), (0xF0, "EXTCTRL", 1, "register"), (0xFC, "PWCTR6", 2, "register"),
    (0xFF, "VCOM4L", 3, "register"),
)


def _st7789_timing(regs: Registers) -> FrameTiming:
    """ST7789VW FRCTRL2 note 1: 10 MHz / ((320 + FPA + BPA) * (250 + RTNA * 16)); porches from PORCTRL."""
    bpa, fpa = regs[0xB2][0] & 0x7F, regs[0xB2][1] & 0x7F
    rtna = regs[0xC6][0] & 0x1F
    lines = 320 + fpa + bpa
    period = lines * (250 + rtna * 16) / 10e6
    return FrameTiming(period, period * (fpa + bpa) / lines)


ILI9341_FOSC = 615e3
"""ILI9341 internal oscillator (Hz): the FRMCTR1 table's 70 Hz at RTNA 27 clocks and 324 lines."""


def _ili9341_timing(regs: Registers) -> FrameTiming:
    """ILI9341 FRMCTR1: fosc / (clocks per line * division * (320 + VFP + VBP)); RTNA < 16 is prohibited."""
    diva = regs[0xB1][0] & 0x03
    clocks = max(16, regs[0xB1][1] & 0x1F)
    vfp, vbp = regs[0xB5][0] & 0x7F, regs[0xB5][1] & 0x7F
    lines = 320 + vfp + vbp
    period = clocks * (1 << diva) * lines / ILI9341_FOSC
    return FrameTiming(period, period * (vfp + vbp) / lines)


ST7735_FOSC = 850e3
"""ST7735S/R oscillator (Hz) of the FRMCTR1 formula ``fosc / ((RTNA * 2 + 40) * (LINE + FPA + BPA + 2))``."""


def _st7735_timing(regs: Registers) -> FrameTiming:
    """ST7735S/R FRMCTR1 (the v1.2 sheet's simpler formula is for the older part)."""
    rtna, fpa, bpa = regs[0xB1][0] & 0x0F, regs[0xB1][1] & 0x3F, regs[0xB1][2] & 0x3F
    lines = 160 + fpa + bpa + 2
    period = (rtna * 2 + 40) * lines / ST7735_FOSC
    return FrameTiming(period, period * (fpa + bpa + 2) / lines)


ST7789_LCMCTRL_RESET = 0x2C


def _st7789_xor(regs: Registers) -> tuple[int, bool]:
    """LCMCTRL (C0h) XMY/XBGR/XINV/XMX/XMV, counted from its reset value 2Ch (which modules are built for)."""
    diff = regs[0xC0][0] ^ ST7789_LCMCTRL_RESET
    bits = (0x80 if diff & 0x40 else 0) | (0x08 if diff & 0x20 else 0) | (0x40 if diff & 0x08 else 0)
    return bits | (0x20 if diff & 0x02 else 0), bool(diff & 0x10)


def _ili9341_xor(regs: Registers) -> tuple[int, bool]:
    """Interface control (F6h) 1st parameter: MY_EOR MX_EOR MV_EOR - BGR_EOR (reset 01h: none)."""
    return regs[0xF6][0] & 0xE8, False


def _no_xor(regs: Registers) -> tuple[int, bool]:
    return 0, False


MODELS: dict[str, Model] = {
    "st7789": Model(
        "st7789", 240, 320, {**_DCS, **_DCS_BRIGHTNESS, **_ST7789_ONLY},
        {**DBI_FORMATS, 0b111: FORMAT_18}, 1e9 / 16, 62.5e6, Waits(0.005, 0.005, 0.005, 0.005, 0.120),
        {0xB2: bytes([0x0C, 0x0C, 0x00, 0x33, 0x33]), 0xC6: bytes([0x0F]), 0xC0: bytes([ST7789_LCMCTRL_RESET])},
        _st7789_timing, _st7789_xor),
    "ili9341": Model(
        "ili9341", 240, 320, {**_DCS, **_DCS_BRIGHTNESS, **_ILI9341_ONLY},
        {k: v for k, v in DBI_FORMATS.items() if v.bits != 12}, 1e9 / 100, 10e6,
        Waits(0.005, 0.005, 0.005, 0.005, 0.120),
        {0xB1: bytes([0x00, 0x1B]), 0xB5: bytes([0x02, 0x02, 0x0A, 0x14]), 0xF6: bytes([0x01, 0x00, 0x00])},
        _ili9341_timing, _ili9341_xor),
    "st7735": Model(
        "st7735", 132, 162, {**_DCS, **_ST7735_ONLY},
        dict(DBI_FORMATS), 1e9 / 66, 15e6, Waits(0.005, 0.120, 0.120, 0.120, 0.120),
        {0xB1: bytes([0x02, 0x2C, 0x2D])},
        _st7735_timing, _no_xor),
}
"""The simulated controllers by model name."""

"""MipiDcsSim: an ST7789VW, ILI9341 or ST7735R/S panel module on 4-wire SPI, decoded from the wire to the glass.

The controller (commands, waits, frame memory) is :mod:`dcs_controller`; the module's glass (offset,
turn, mirroring, colour filters, IPS) is :mod:`dcs_glass`. ``gram`` is the frame memory as stored:
(RAM rows, RAM columns, 3) uint8 of 6-bit components (0..63), indexed [row, column], the first
component being the one sent first (red unless the host sends BGR): (320, 240, 3) for ST7789 and
ILI9341, (160, 128, 3) for an ST7735 128x160 "black tab" (GM 011), (162, 132, 3) for other ST7735
modules. ``glass()`` is the module's width x height RGB image (8-bit components ``v << 2 | v >> 4``),
upright as Adafruit's rotation 0 draws it; a landscape size (width > height) is the portrait module
turned 90° (Adafruit's rotation 1 upright: MY|MV on ST77xx, MV on ILI9341, which is luma's ILI9341
default). The TE output follows FRCTRL2/PORCTRL (ST7789), FRMCTR1/PRCTR (ILI9341) or FRMCTR1 (ST7735);
TEM=1's H-blank pulses are not modelled.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray
from PIL import Image

from pixelpen.clock import Clock
from pixelpen.errors import ConfigError
from pixelpen.options import OptionSpec, OptionValues, boolean, choice, number, pixels
from pixelpen.sim.panels.base import PanelSim, register_panel_simulators
from pixelpen.sim.panels.dcs_commands import MODELS
from pixelpen.sim.panels.dcs_controller import DcsController
from pixelpen.sim.panels.dcs_glass import Module, known_module, render
from pixelpen.sim.panels.dcs_pixels import PixelFormat


@dataclass(frozen=True)
class DcsState:
    """A snapshot of the controller's modes, for tests and the live view."""

    sleeping: bool
    display_on: bool
    inverted: bool
    idle: bool
    partial: bool
    madctl: int
    """The MADCTL parameter as written."""
    pixel_format: PixelFormat
    window: tuple[int, int, int, int]
    """(XS, XE, YS, YE) as CASET/RASET set them."""
    tearing: int | None
    """TEON's mode (0: V-blank), None when off."""
    frame_rate: float
    """Frames per second from the frame-rate registers."""


class MipiDcsSim(PanelSim):
    """A MIPI-DCS TFT module: ``model`` "st7789", "ili9341" or "st7735", glass ``width`` x ``height``.

    ``offset`` overrides the module table's RAM (column, row) of the glass's top-left at MADCTL 0, ``ram``
    its frame memory size, ``bgr`` its colour filter order; ``turn`` (0, 90, 180, 270) how the glass is
    held (default: 90 for a landscape size, else 0);
    ``te=False``: the TE pin is not wired (reads low); ``clock_hz``: the SPI clock for bus time (default
    the datasheet's write-clock limit; faster writes are reported).
    """

    def __init__(
        self,
        model: str,
        width: int,
        height: int,
        *,
        clock: Clock | None = None,
        clock_hz: float | None = None,
        offset: tuple[int, int] | None = None,
        turn: int | None = None,
        ram: tuple[int, int] | None = None,
        bgr: bool | None = None,
        te: bool = True,
        strict: bool = False,
    ) -> None:
        key = model.lower()
        if key not in MODELS:
            raise ConfigError(f"MipiDcsSim: unknown model {model!r}; known: {', '.join(sorted(MODELS))}")
        spec = MODELS[key]
        self.model = key
        turn = (90 if width > height else 0) if turn is None else turn
        if turn not in (0, 90, 180, 270):
            raise ConfigError(f"{key}: turn={turn} is not 0, 90, 180 or 270")
        self.width, self.height, self.turn, self.te_wired = width, height, turn, te
        self.module = _module(key, (height, width) if turn % 180 else (width, height), offset=offset, ram=ram,
                              bgr=bgr)
        """The module's glass facts (offset, turn, mirroring, colour filters, IPS, memory size)."""
        super().__init__(clock=clock, clock_hz=spec.default_clock_hz if clock_hz is None else clock_hz,
                         strict=strict, spi_limit_hz=spec.max_write_hz)
        self._power_ups = 0
        self._chip = self._power_up()
        self._chip.settle()  # powered before the program started: only a RESX pulse or a power cut restarts waits

    def _power_up(self) -> DcsController:
        """A controller just powered: registers at their reset values, the frame memory seeded noise."""
        self._power_ups += 1
        chip = DcsController(MODELS[self.model], self._report, self._count_frame, ram=self.module.ram,
                             seed=self._power_ups)
        chip.hardware_reset(self._now)
        return chip

    # ---- the controller side of the bus -----------------------------------------------------------
    def _panel_command(self, code: int) -> None:
        self._chip.command(code, self._now)

    def _panel_data(self, data: bytes) -> None:
        self._chip.data(data, self._now)

    def _panel_reset(self) -> None:
        self._chip.hardware_reset(self._now)

    def _panel_power_loss(self) -> None:
        self._chip = self._power_up()

    # ---- what it shows ---------------------------------------------------------------------------
    def glass(self) -> Image.Image:
        """The module's width x height glass as a person sees it (RGB)."""
        self._catch_up()
        return render(self._chip.memory.ram, self.module, (self.width, self.height), self.turn,
                      self._chip.scan_out(in_reset=self.in_reset))

    @property
    def gram(self) -> NDArray[np.uint8]:
        """The frame memory, read-only: (RAM rows, RAM cols, 3) uint8 6-bit components, [row, col]."""
        view = self._chip.memory.ram.view()
        view.flags.writeable = False
        return view

    @property
    def state(self) -> DcsState:
        """The controller's modes now."""
        chip = self._chip
        m = chip.memory
        return DcsState(chip.sleeping, chip.display_on, chip.inverted, chip.idle, chip.partial, chip.madctl_raw,
                        chip.pixel_format, (m.xs, m.xe, m.ys, m.ye), chip.tearing, 1 / chip.frame_timing().period)

    def line(self, name: str) -> bool:
        """``"te"``: high in V-blank after TEON (low when unwired, asleep or after TEOFF)."""
        if name != "te":
            return super().line(name)
        self._catch_up()
        return self.te_wired and not self.in_reset and self._chip.tearing_line(self._now)

    def _next_internal_event(self) -> float | None:
        return self._chip.next_tearing_edge(self._now) if self.te_wired else None


def _module(model: str, portrait: tuple[int, int], *, offset: tuple[int, int] | None, ram: tuple[int, int] | None,
            bgr: bool | None) -> Module:
    """The known module of that portrait size with the caller's overrides, checked against the memory."""
    module = known_module(model, portrait)
    changes: dict[str, Any] = {"offset": offset, "ram": ram, "bgr": bgr}
    module = replace(module, **{k: v for k, v in changes.items() if v is not None})
    spec = MODELS[model]
    cols, rows = module.ram if module.ram is not None else (spec.cols, spec.rows)
    if module.ram is not None and not (0 < cols <= spec.cols and 0 < rows <= spec.rows):
        raise ConfigError(f"{model}: ram={cols}x{rows} is not within the chip's {spec.cols}x{spec.rows}")
    col, row = module.offset
    if min(portrait) < 1 or col < 0 or row < 0 or col + portrait[0] > cols or row + portrait[1] > rows:
        raise ConfigError(f"{model}: a {portrait[0]}x{portrait[1]} glass at offset {module.offset} does not fit "
                          f"the {cols}x{rows} frame memory")
    return module


def _offset(text: str) -> tuple[int, int]:
    col, sep, row = text.partition(",")
    if not sep:
        raise ValueError("expected COLUMN,ROW (the RAM address of the glass's top-left at MADCTL 0)")
    return int(col), int(row)


_DEFAULT_SIZES = {"st7789": (240, 240), "ili9341": (320, 240), "st7735": (128, 160)}

OPTIONS: tuple[OptionSpec[Any], ...] = (
    OptionSpec("size", pixels, None, "glass size WxH (default: st7789 240x240, ili9341 320x240, st7735 128x160)"),
    OptionSpec("hz", number(1, above=True), None, "SPI clock in Hz for bus time (default: the datasheet's)"),
    OptionSpec("offset", _offset, None, "RAM COL,ROW of the glass's top-left at MADCTL 0 (default: known modules)"),
    OptionSpec("turn", choice("0", "90", "180", "270"), None, "how the module is held (default: 90 if landscape)"),
    OptionSpec("ram", pixels, None, "frame memory WxH the module straps (ST7735 green tab: 132x162)"),
    OptionSpec("panel_bgr", boolean, None, "the glass's colour filters are BGR (default: known modules; the "
                                           "display's own bgr option is the MADCTL bit its driver sends)"),
    OptionSpec("te", boolean, True, "the TE pin is wired"),
    OptionSpec("strict", boolean, False, "raise ProtocolError for what the controller would flag"),
)


def _build(model: str, values: OptionValues, clock: Clock | None) -> MipiDcsSim:
    """The simulator of a ``sim:MODEL?...`` URL (options: ``OPTIONS``)."""
    width, height = values["size"] or _DEFAULT_SIZES[model]
    turn = None if values["turn"] is None else int(values["turn"])
    return MipiDcsSim(model, width, height, clock=clock, clock_hz=values["hz"], offset=values["offset"], turn=turn,
                      ram=values["ram"], bgr=values["panel_bgr"], te=values["te"], strict=values["strict"])


register_panel_simulators(MODELS, _build, OPTIONS)

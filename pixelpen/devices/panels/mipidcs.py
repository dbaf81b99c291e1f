"""MIPI-DCS TFT panels (ST7789, ILI9341, ST7735) on one class; each module's facts come from its profile.

Rotation is MADCTL (MY/MX/MV) with the module's CASET/RASET offsets for that rotation (profile
``rotation.N``); colour order (BGR) and inversion (INVON) come from the profile unless the URL says
``bgr=``/``invert=``.  Pixels are RGB565 big-endian (COLMOD 0x55) by default, RGB666 in three bytes
(COLMOD 0x66) with ``colour=rgb666``.  A window is ``2A xs xe``, ``2B ys ye``, ``2C`` + pixels: 11
command and parameter bytes, 6 when the window before it in the frame had the same rows or columns (the
controller keeps CASET/RASET; RAMWR starts at the window's first pixel).  With a ``te`` line wired TEON
(35h 00h) is sent and every frame starts at the V-blank pulse.  Where the frame's rows are the memory's rows
(MADCTL MV clear) a frame that is the last one shifted vertically is scrolled by VSCRDEF/VSCSAD over the glass's
rows (``scrolling``; ``hardware_scroll=off`` turns it off), and every window's rows are mapped through the scroll.
"""

from __future__ import annotations

import struct
from typing import Any, ClassVar

from pixelpen.devices.panels.base import PanelDisplay
from pixelpen.devices.panels.scrolling import mipi_scroll_area
from pixelpen.display.registry import register_display
from pixelpen.errors import ConfigError
from pixelpen.options import OptionSpec, OptionValues, boolean, choice
from pixelpen.profiles.panel import COLMOD, MADCTL_BGR, MADCTL_MV, MADCTL_MY, PanelGeometry, PanelProfile
from pixelpen.raster.damage import Rect

CASET, RASET, RAMWR = 0x2A, 0x2B, 0x2C
INVOFF, INVON, DISPOFF, DISPON = 0x20, 0x21, 0x28, 0x29
TEON, MADCTL, COLMOD_CMD = 0x35, 0x36, 0x3A
_FORMATS = {"rgb565": "rgb565be", "rgb666": "rgb666"}
_PAIR = struct.Struct(">HH")
"""CASET/RASET parameters: first and last column (row), 16-bit big-endian."""


class MipiDcsDisplay(PanelDisplay):
    """A MIPI-DCS TFT (``st7789:spi:0.0?dc=25&rst=27&size=240x240&rotation=90``); the model is its profile's."""

    controller: ClassVar[str] = "st7789"
    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        *PanelDisplay.OPTIONS,
        OptionSpec("bgr", boolean, None, "panel colour filter is B-G-R (MADCTL bit 3); default the profile's"),
        OptionSpec("colour", choice("rgb565", "rgb666"), None,
                   "pixels on the wire: rgb565 (COLMOD 0x55, 2 bytes) or rgb666 (0x66, 3 bytes); "
                   "default the profile's"),
        OptionSpec("hardware_scroll", boolean, True,
                   "scroll in the controller (VSCRDEF/VSCSAD) when a frame is the last one shifted vertically"),
    )

    def __init__(self, *args: Any, bgr: bool | None = None, colour: str | None = None, hardware_scroll: bool = True,
                 **kwargs: Any) -> None:
        profile: PanelProfile = kwargs["profile"]
        if colour is not None and colour not in _FORMATS:
            raise ConfigError(f"colour must be rgb565 or rgb666, got {colour!r}")
        self._format = _FORMATS[colour] if colour else profile.pixel_format
        self.bgr = profile.bgr if bgr is None else bgr
        self._offsets = (0, 0)
        super().__init__(*args, **kwargs)
        g = self.geometry
        self._offsets = (g.x_offset, g.y_offset)
        self._scroll.enabled = bool(hardware_scroll)
        rows = self.profile.ram_size[1]
        self._scroll.default = mipi_scroll_area(rows, 0, rows, reversed=False)

    @classmethod
    def compatible_controllers(cls) -> tuple[str, ...]:
        """Any MIPI-DCS controller: a profile for another one may be given with ``profile=``."""
        return ("st7789", "ili9341", "st7735")

    @classmethod
    def controller_options(cls, opts: OptionValues, profile: PanelProfile) -> dict[str, Any]:
        """``bgr``, ``colour`` and ``hardware_scroll``."""
        return {"bgr": opts["bgr"], "colour": opts["colour"], "hardware_scroll": opts["hardware_scroll"]}

    @property
    def pixel_format(self) -> str:
        """``rgb565be`` or ``rgb666``."""
        return self._format

    @property
    def geometry(self) -> PanelGeometry:
        """Window size, offsets and MADCTL at the current rotation."""
        return self.profile.geometry(self.rotation)

    @property
    def madctl(self) -> int:
        """The MADCTL byte sent: the rotation's bits with the BGR bit as configured."""
        return (self.geometry.madctl & ~MADCTL_BGR) | (MADCTL_BGR if self.bgr else 0)

    def _window_size(self) -> tuple[int, int]:
        g = self.geometry
        return g.width, g.height

    def _setup(self) -> None:
        """COLMOD, MADCTL, INVON/INVOFF and (with a TE line) TEON; the rotation's CASET/RASET offsets and scroll
        area (the glass's rows in the memory; none when MV makes the frame's rows memory columns) are kept."""
        g = self.geometry
        self._offsets = (g.x_offset, g.y_offset)
        self._scroll.set_area(None if g.madctl & MADCTL_MV else mipi_scroll_area(
            self.profile.ram_size[1], g.y_offset, g.height, reversed=bool(g.madctl & MADCTL_MY)))
        self._command(COLMOD_CMD)
        self._data(bytes([COLMOD[self._format]]))
        self._command(MADCTL)
        self._data(bytes([self.madctl]))
        self._command(INVON if self.invert else INVOFF)
        if self.wiring.te is not None:
            self._command(TEON)
            self._data(b"\x00")

    def _write_windows(self, windows: list[Rect], packed: list[bytes]) -> None:
        """Per window CASET and RASET (each left out when the window before set the same columns or rows: the
        controller keeps them), RAMWR and the pixels; the rows mapped through the hardware scroll, a window
        wrapping its ring sent as two.  Each call's bytes are counted once the bus has taken them."""
        bus = self.wiring.bus
        command, data, pair, ring = bus.command, bus.data, _PAIR.pack, self._scroll.rows
        x, y = self._offsets
        columns: tuple[int, int] | None = None
        rows: tuple[int, int] | None = None
        sent = 0
        try:
            for (x0, y0, x1, y1), pixels in zip(windows, packed, strict=True):
                if columns != (x0, x1):
                    columns = (x0, x1)
                    command(CASET)
                    sent += 1
                    data(pair(x0 + x, x1 - 1 + x))
                    sent += 4
                spans = ring(y0, y1)
                row_bytes = len(pixels) // (y1 - y0)
                start = 0
                for span in spans:
                    if rows != span:
                        rows = span
                        command(RASET)
                        sent += 1
                        data(pair(span[0] + y, span[1] - 1 + y))
                        sent += 4
                    command(RAMWR)
                    sent += 1
                    end = start + (span[1] - span[0]) * row_bytes
                    chunk = pixels if len(spans) == 1 else pixels[start:end]
                    data(chunk)
                    sent += len(chunk)
                    start = end
        finally:
            self._frame.bytes += sent

    def _power(self, on: bool) -> None:
        self._command(DISPON if on else DISPOFF)

    def set_invert(self, invert: bool) -> None:
        """Inversion on or off now (INVON/INVOFF)."""
        self._require_open()
        self.invert = bool(invert)
        self._command(INVON if self.invert else INVOFF)


@register_display("st7789")
class ST7789Display(MipiDcsDisplay):
    """Sitronix ST7789 modules (240x240, 240x320, 135x240, 240x280, 170x320)."""

    controller: ClassVar[str] = "st7789"
    default_size: ClassVar[tuple[int, int]] = (240, 240)


@register_display("ili9341")
class ILI9341Display(MipiDcsDisplay):
    """ILITEK ILI9341 modules (240x320, often used as 320x240)."""

    controller: ClassVar[str] = "ili9341"
    default_size: ClassVar[tuple[int, int]] = (240, 320)


@register_display("st7735")
class ST7735Display(MipiDcsDisplay):
    """Sitronix ST7735 modules (128x160, 80x160)."""

    controller: ClassVar[str] = "st7735"
    default_size: ClassVar[tuple[int, int]] = (128, 160)

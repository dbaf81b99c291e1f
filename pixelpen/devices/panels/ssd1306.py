"""Monochrome OLEDs of the SSD1306 family: SSD1306, SSD1309 (horizontal-mode windows) and SH1106 (page mode).

The canvas is mode "1" (1 = lit).  Rotation 0 and 180 are done by the controller (segment remap A0h/A1h and
COM scan direction C0h/C8h, as the profile orients rotation 0); 90 and 270 turn the picture in software
(the canvas is then height x width) on top of the controller's 0 or 180.  Windows cover whole pages of 8 rows:
SSD1306/SSD1309 ``21 cs ce 22 ps pe`` + page bytes (6 command bytes, column start added for modules narrower
than the RAM); SH1106 has no window, so per page ``B0+p, 0x(c & 15), 0x1(c >> 4)`` + that page's bytes, with
its column offset (usually 2).  Parameters are command bytes (D/C low; I2C control byte 0x00).  On a module whose
glass shows all 64 RAM rows a frame that is the last one shifted vertically is scrolled by the display start line
(40h | line, ``scrolling.HardwareScroll``; ``hardware_scroll=off`` turns it off): the window space is then the
RAM's rows, frame row y at RAM row (y + line) % 64.
"""

from __future__ import annotations

from typing import Any, ClassVar

from pixelpen.devices.panels.base import PanelDisplay
from pixelpen.devices.panels.scrolling import ScrollArea
from pixelpen.devices.panels.wiring import Interface, Pins
from pixelpen.display.registry import register_display
from pixelpen.errors import ConfigError
from pixelpen.options import OptionSpec, OptionValues, boolean, i2c_address, integer
from pixelpen.profiles.panel import InitStep, PanelGeometry, PanelProfile
from pixelpen.raster.damage import Rect
from pixelpen.sim.base import simulator_options as simulator_specs

SET_CONTRAST, NORMAL, INVERSE, DISPLAY_OFF, DISPLAY_ON = 0x81, 0xA6, 0xA7, 0xAE, 0xAF
SEGMENT_NORMAL, SEGMENT_REMAP, COM_NORMAL, COM_REVERSE = 0xA0, 0xA1, 0xC0, 0xC8
COLUMN_ADDRESS, PAGE_ADDRESS, PAGE_START = 0x21, 0x22, 0xB0


def _same_address(text: str) -> int | None:
    """``text`` as an address for comparison (None when it is no number: the simulator then names the error)."""
    try:
        return int(text.strip(), 0)
    except ValueError:
        return None


@register_display("ssd1306")
class SSD1306Display(PanelDisplay):
    """An SSD1306 OLED (``ssd1306:i2c:1?addr=0x3c``, ``ssd1306:spi:0.0?dc=24&rst=25``, ``sim:ssd1306?size=128x32``)."""

    controller: ClassVar[str] = "ssd1306"
    default_size: ClassVar[tuple[int, int]] = (128, 64)
    interfaces: ClassVar[tuple[Interface, ...]] = ("i2c", "spi")
    canvas_mode: ClassVar[str] = "1"
    display_on: ClassVar[int] = DISPLAY_ON
    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        *PanelDisplay.OPTIONS,
        OptionSpec("addr", i2c_address, None, "I2C address (0x3c or 0x3d); default the profile's"),
        OptionSpec("contrast", integer(0, 255), None, "contrast 0..255 (81h); default the profile's"),
        OptionSpec("hardware_scroll", boolean, True,
                   "scroll by the display start line (40h) when a frame is the last one shifted vertically"),
    )

    def __init__(self, *args: Any, contrast: int | None = None, hardware_scroll: bool = True,
                 **kwargs: Any) -> None:
        if contrast is not None and not 0 <= contrast <= 255:
            raise ConfigError(f"contrast must be 0..255, got {contrast!r}")
        self.contrast = contrast
        super().__init__(*args, **kwargs)
        self._scroll.enabled = bool(hardware_scroll)
        self._scroll.default = self._start_line_area()

    @classmethod
    def controller_options(cls, opts: OptionValues, profile: PanelProfile) -> dict[str, Any]:
        """``contrast`` and ``hardware_scroll``."""
        return {"contrast": opts["contrast"], "hardware_scroll": opts["hardware_scroll"]}

    def _start_line_area(self) -> ScrollArea | None:
        """The ring the start line turns: the RAM's 64 rows, when the glass shows them all (64 COM lines)."""
        rows = self.profile.ram_size[1]
        return ScrollArea(0, rows, 0, start_line=True) if rows == self.profile.size[1] == 64 else None

    @classmethod
    def simulator_options(cls, model: str, sim_options: dict[str, str], opts: OptionValues, profile: PanelProfile,
                          pins: Pins, *, held: int = 0) -> dict[str, str]:
        """The base's, with the display's I2C address (``addr``) as the simulator's ``address``: one chip, one
        address (an ``address=`` for the simulator that disagrees is a ConfigError)."""
        out = super().simulator_options(model, sim_options, opts, profile, pins, held=held)
        if "address" in {spec.name for spec in simulator_specs(model)}:
            given = out.get("address")
            if given is not None and _same_address(given) != pins.addr:
                raise ConfigError(f"address={given} (the simulator's) disagrees with the display's "
                                  f"addr=0x{pins.addr:02x}; give addr= alone")
            out["address"] = f"0x{pins.addr:02x}"
        return out

    @property
    def pixel_format(self) -> str:
        """``mono-pages``."""
        return "mono-pages"

    @property
    def geometry(self) -> PanelGeometry:
        """The controller's part of the rotation (0 or 180) with its scan settings."""
        return self.profile.geometry(self.rotation // 180 * 180)

    def _soft_turn(self) -> int:
        return 90 if self.rotation in (90, 270) else 0

    def _window_size(self) -> tuple[int, int]:
        return self.profile.size

    def _send_step(self, step: InitStep) -> None:
        self._command(step.command, step.params)

    def _setup(self) -> None:
        """Segment remap and COM direction of the rotation, normal/inverse, the contrast when set; the start-line
        ring of the rotation (window space: RAM rows)."""
        self._scroll.set_area(self._start_line_area())
        g = self.geometry
        self._command(SEGMENT_REMAP if g.segment_remap else SEGMENT_NORMAL,
                      COM_REVERSE if g.com_reverse else COM_NORMAL, INVERSE if self.invert else NORMAL)
        if self.contrast is not None:
            self._command(SET_CONTRAST, self.contrast)

    @property
    def column_start(self) -> int:
        """RAM column of the glass's left edge: the profile's at its own segment remap, mirrored over the RAM
        width when the rotation flips the remap (a 96-wide glass on SEG32..127 is RAM 0..95 under A1h but
        32..127 under A0h)."""
        p = self.profile
        if self.geometry.segment_remap == p.segment_remap:
            return p.column_offset
        return p.ram_size[0] - p.size[0] - p.column_offset

    def _write_windows(self, windows: list[Rect], packed: list[bytes]) -> None:
        """Per window its column and page window (``21 cs ce 22 ps pe``), then its page bytes (counted once sent)."""
        bus, x, sent = self.wiring.bus, self.column_start, 0
        try:
            for (x0, y0, x1, y1), pixels in zip(windows, packed, strict=True):
                bus.command(COLUMN_ADDRESS, x0 + x, x1 - 1 + x, PAGE_ADDRESS, y0 // 8, (y1 - 1) // 8)
                sent += 6
                bus.data(pixels)
                sent += len(pixels)
        finally:
            self._frame.bytes += sent

    def _power(self, on: bool) -> None:
        self._command(DISPLAY_ON if on else DISPLAY_OFF)

    def set_contrast(self, contrast: int) -> None:
        """Contrast 0..255 now (81h)."""
        self._require_open()
        if not (isinstance(contrast, int) and 0 <= contrast <= 255):
            raise ConfigError(f"contrast must be 0..255, got {contrast!r}")
        self.contrast = contrast
        self._command(SET_CONTRAST, contrast)

    def set_invert(self, invert: bool) -> None:
        """Inverse display (A7h) or normal (A6h) now."""
        self._require_open()
        self.invert = bool(invert)
        self._command(INVERSE if self.invert else NORMAL)



@register_display("ssd1309")
class SSD1309Display(SSD1306Display):
    """An SSD1309 OLED (the SSD1306 command set, external VCC: no charge pump)."""

    controller: ClassVar[str] = "ssd1309"


@register_display("sh1106")
class SH1106Display(SSD1306Display):
    """An SH1106 OLED: 132-column RAM, page addressing only (``B0+p``, column low/high nibbles per page)."""

    controller: ClassVar[str] = "sh1106"

    def _write_windows(self, windows: list[Rect], packed: list[bytes]) -> None:
        """Per page of each window ``B0+p``, the column's low and high nibbles, then that page's bytes."""
        for (x0, y0, x1, y1), pixels in zip(windows, packed, strict=True):
            column, width = x0 + self.column_start, x1 - x0
            for i, page in enumerate(range(y0 // 8, -(-y1 // 8))):
                self._command(PAGE_START | page, column & 0x0F, 0x10 | column >> 4)
                self._data(pixels[i * width:(i + 1) * width])

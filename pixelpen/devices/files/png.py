"""The ``png:`` file display: a raster display drawn by the raster engine and saved as PNG.

Limits (class attributes of :class:`PngFileDisplay`, read at call time): ``MAX_PIXELS`` (width x height,
default 100 million: a 300 MB RGB framebuffer), ``MAX_DPI`` (100,000); the file name must suit the file
system (:func:`pixelpen.urls.check_path`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

from pixelpen.display.capabilities import Capabilities, ColourModel
from pixelpen.display.kinds import RasterDisplay
from pixelpen.display.registry import register_display
from pixelpen.errors import ConfigError
from pixelpen.options import OptionSpec, choice, colour, positive
from pixelpen.raster.canvas import Canvas
from pixelpen.urls import DeviceURL, Size, check_path, parse_size

_MODES: dict[str, ColourModel] = {
    "1": "mono", "L": "grey", "P": "indexed", "RGB565": "rgb565", "RGB": "rgb888", "RGBA": "rgba",
}


def pixel_size(text: str) -> Size:
    """A ``WxH`` size in whole pixels (``800x600``)."""
    size = parse_size(text, "px")
    if size.unit != "px" or size.width != int(size.width) or size.height != int(size.height):
        raise ValueError("png size is whole pixels, WxH (e.g. 800x600)")
    return size


@register_display("png")
class PngFileDisplay(RasterDisplay):
    """Draws into a framebuffer and writes it to ``PATH`` (``png:PATH?size=800x600&dpi=96``)."""

    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("size", pixel_size, Size(800, 600, "px"), "image size in pixels, WxH"),
        OptionSpec("dpi", positive, 96.0, "pixels per inch, sets the millimetre size of a pixel"),
        OptionSpec("mode", choice(*_MODES), "RGB", "pixel mode: 1, L, P, RGB565, RGB or RGBA"),
        OptionSpec("background", colour, "white", "background colour, a name or #rrggbb"),
    )
    MAX_PIXELS = 100_000_000
    """Pixels of the image (width x height)."""
    MAX_DPI = 100_000.0
    """Pixels per inch."""

    def __init__(
        self, path: str | Path, *, size: tuple[int, int] = (800, 600), dpi: float = 96.0, mode: str = "RGB",
        background: object = "white",
    ) -> None:
        if mode not in _MODES:
            raise ConfigError(f"png mode must be one of {', '.join(_MODES)}, got {mode!r}")
        path = check_path(path, "png file name (the URL target)")
        width, height = size
        if not (isinstance(width, int) and isinstance(height, int) and width > 0 and height > 0):
            raise ConfigError(f"png size must be whole pixels > 0, got {size!r}")
        if width * height > self.MAX_PIXELS:
            raise ConfigError(
                f"png size {width}x{height} is more than PngFileDisplay.MAX_PIXELS = {self.MAX_PIXELS} pixels"
            )
        if not 0 < dpi <= self.MAX_DPI:
            raise ConfigError(f"png dpi must be > 0 and at most {self.MAX_DPI:g}, got {dpi!r}")
        caps = Capabilities(
            model="png", category="file", kind="raster", size=(float(size[0]), float(size[1])), unit_mm=25.4 / dpi,
            colour_model=_MODES[mode], y_down=True, can_erase=True, tolerance=0.25, limits={"file": str(path)},
        )
        super().__init__(caps, mode=mode, background=background, deferral="flush")
        self.path = Path(path)

    @classmethod
    def from_url(cls, url: DeviceURL, **kwargs: object) -> PngFileDisplay:
        """``png:PATH?options`` (see ``OPTIONS``)."""
        opts = cls.read_url_options(url)
        size = opts["size"]
        return cls(url.target, size=(int(size.width), int(size.height)), dpi=opts["dpi"], mode=opts["mode"],
                   background=opts["background"])

    def _open_device(self) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)

    def _close_device(self) -> None:
        self.canvas.save(self.path)

    def _show(self, canvas: Canvas) -> None:
        canvas.save(self.path)

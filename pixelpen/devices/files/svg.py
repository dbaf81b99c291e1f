"""The ``svg:`` file display: a vector display writing an SVG of true millimetre size, one group per layer.

Limits: the page size comes through :func:`pixelpen.urls.parse_size` (at most ``urls.MAX_SIZE`` in its
unit); ``pen_width`` is finite and at most :data:`MAX_PEN_WIDTH_MM`; the file name must suit the file
system (:func:`pixelpen.urls.check_path`).
"""

from __future__ import annotations

from functools import partial
from pathlib import Path
from typing import Any, ClassVar

from pixelpen.display.capabilities import Capabilities
from pixelpen.display.kinds import VectorDisplay
from pixelpen.display.registry import register_display
from pixelpen.errors import ConfigError
from pixelpen.options import OptionSpec, positive
from pixelpen.urls import DeviceURL, Size, check_path, parse_size
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.svgimport import write_svg

MAX_PEN_WIDTH_MM = 1000.0
"""Widest pen width in millimetres."""


@register_display("svg")
class SvgFileDisplay(VectorDisplay):
    """Writes what a plotter would draw to ``PATH`` as SVG (``svg:PATH?size=210x297mm``)."""

    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("size", partial(parse_size, default_unit="mm"), Size(210.0, 297.0, "mm"),
                   "page size, WxH with a unit (mm, cm, in, px) or a paper name (a4 is 210x297mm)"),
        OptionSpec("pen_width", positive, 0.3, "pen width in mm for stroke width and hatch spacing"),
    )

    def __init__(
        self, path: str | Path, *, size_mm: tuple[float, float] = (210.0, 297.0), pen_width_mm: float = 0.3
    ) -> None:
        path = check_path(path, "svg file name (the URL target)")
        if not 0 < pen_width_mm <= MAX_PEN_WIDTH_MM:
            raise ConfigError(f"svg pen_width must be > 0 and at most {MAX_PEN_WIDTH_MM:g} mm, got {pen_width_mm!r}")
        caps = Capabilities(
            model="svg", category="file", kind="vector", size=size_mm, unit_mm=1.0, colour_model="rgb888",
            y_down=True, native_primitives=frozenset({"polyline"}), can_erase=True, tolerance=0.02,
            limits={"file": str(path)},
        )
        super().__init__(caps, pen_width_mm=pen_width_mm, deferral="flush")
        self.path = Path(path)

    @classmethod
    def from_url(cls, url: DeviceURL, **kwargs: object) -> SvgFileDisplay:
        """``svg:PATH?options`` (see ``OPTIONS``)."""
        opts = cls.read_url_options(url)
        return cls(url.target, size_mm=opts["size"].mm(), pen_width_mm=opts["pen_width"])

    def _open_device(self) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)

    def _close_device(self) -> None:
        self._write()

    def _plot(self, strokes: DisplayList) -> None:
        self._write()

    def _new_sheet(self) -> None:
        self._write()

    def _write(self) -> None:
        write_svg(self.display_list, self.path, size_mm=self.capabilities.size_mm)

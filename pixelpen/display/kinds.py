"""The two kinds of output display: raster (a framebuffer Canvas) and vector (a display list of strokes)."""

from __future__ import annotations

from abc import abstractmethod
from typing import TYPE_CHECKING

from pixelpen import geometry as geo
from pixelpen.colour import parse_colour
from pixelpen.display.base import Deferral, Display
from pixelpen.display.capabilities import Capabilities
from pixelpen.display.flatten import DeviceShape
from pixelpen.display.rasterize import rasterize
from pixelpen.display.vectorize import PenLayerMap, build_display_list
from pixelpen.raster.canvas import Canvas
from pixelpen.vector.displaylist import DisplayList

if TYPE_CHECKING:
    from pixelpen.display.scene3d import Scene


class RasterDisplay(Display):
    """A display refreshed from a pixel buffer; devices implement ``_show`` to send changed pixels."""

    def __init__(
        self,
        capabilities: Capabilities,
        *,
        mode: str = "RGB",
        background: object = "white",
        deferral: Deferral = "asap",
    ) -> None:
        super().__init__(capabilities, deferral=deferral)
        width, height = (round(float(v)) for v in capabilities.size)
        self.canvas = Canvas(width, height, mode)
        self.background = self.canvas.colour_value(parse_colour(background))
        self.canvas.fill(self.background)

    def _render(self, shapes: list[DeviceShape]) -> None:
        rasterize(self.canvas, shapes, self.capabilities.unit_mm)

    def _render_scene(self, scene: Scene, pipeline: geo.ViewingPipeline) -> None:
        """Shade a 3D scene into the canvas through the z-buffer."""
        from pixelpen.display.render3d import render_raster

        render_raster(scene, pipeline, self.canvas, self.capabilities.tolerance)

    def _erase(self) -> None:
        self.canvas.fill(self.background)

    def _present(self) -> None:
        self._show(self.canvas)
        self.canvas.clear_damage()

    @abstractmethod
    def _show(self, canvas: Canvas) -> None:
        """Send the canvas's damaged regions (``canvas.damage()``) to the device."""


class VectorDisplay(Display):
    """A random-scan display: shapes become pen strokes; devices implement ``_plot`` for new strokes."""

    def __init__(self, capabilities: Capabilities, *, pen_width_mm: float = 0.3, deferral: Deferral = "asap") -> None:
        super().__init__(capabilities, deferral=deferral)
        self.pen_width_mm = pen_width_mm
        self.display_list = DisplayList(unit_mm=capabilities.unit_mm)
        """Everything drawn on the current sheet."""
        self._unplotted: list[DisplayList] = []
        self._mapping = PenLayerMap(list(capabilities.pens) or None)

    def _render(self, shapes: list[DeviceShape]) -> None:
        self._unplotted.append(
            build_display_list(
                shapes, unit_mm=self.capabilities.unit_mm, pen_width_mm=self.pen_width_mm, mapping=self._mapping
            )
        )

    def _present(self) -> None:
        if not self._unplotted:
            return
        new = DisplayList.concat(self._unplotted)
        self._unplotted = []
        self.display_list = DisplayList.concat([self.display_list, new])
        if len(new):
            self._plot(new)

    def _erase(self) -> None:
        self._unplotted = []
        self.display_list = DisplayList(unit_mm=self.capabilities.unit_mm)
        self._new_sheet()

    @abstractmethod
    def _plot(self, strokes: DisplayList) -> None:
        """Draw new strokes on the device."""

    @abstractmethod
    def _new_sheet(self) -> None:
        """Start a fresh sheet (a plotter cannot erase: ask for new paper, or start a new file page)."""

"""The Display base class: what every output device offers, with a small core that devices implement.

A device implements ``_open_device``, ``_close_device``, ``_render(shapes)``, ``_present()`` and
``_erase()`` (RasterDisplay and VectorDisplay already implement ``_render`` for their kind); shared
code does the viewing pipeline, flattening, clipping, deferral and safe closing.  A 3D ``Scene`` is drawn
through :mod:`pixelpen.display.render3d` (imported on first use): as hidden-line strokes here, shaded through
the z-buffer by ``RasterDisplay``.
"""

from __future__ import annotations

import logging
import sys
from abc import ABC, abstractmethod
from collections.abc import Iterable
from types import TracebackType
from typing import TYPE_CHECKING, Any, ClassVar, Literal, TypeGuard, cast

from pixelpen import geometry as geo
from pixelpen.display.capabilities import Capabilities
from pixelpen.display.flatten import DeviceShape, flatten_picture
from pixelpen.display.picture import PRIMITIVE_TYPES, Picture, Primitive, Segment
from pixelpen.errors import ConfigError, InvalidArgumentType, PixelpenError
from pixelpen.options import OptionSpec, OptionValues, read_options
from pixelpen.urls import DeviceURL

if TYPE_CHECKING:
    from typing import TypeAlias

    from pixelpen.display.scene3d import Scene

    Drawable: TypeAlias = Picture | Primitive | Segment | Scene
    """What ``Display.draw`` takes (besides an iterable of primitives)."""

log = logging.getLogger(__name__)

Deferral = Literal["asap", "flush"]
Rect = tuple[float, float, float, float]


class Display(ABC):
    """An output device that draws pictures: open, set window/viewport, draw, flush, close."""

    schemes: ClassVar[tuple[str, ...]] = ()
    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = ()
    """The options the scheme's URLs accept, as specs (read by ``read_url_options``, listed by ``pixelpen devices``)."""
    simulated: ClassVar[bool] = False
    """True when ``sim:<scheme>`` gives a simulated device of this model."""
    SIM_SHARED: ClassVar[frozenset[str]] = frozenset()
    """Display options of a ``sim:`` URL that the simulator is given too (e.g. ``paper``)."""
    SIM_TRANSPORT: ClassVar[frozenset[str]] = frozenset()
    """Display options that on a ``sim:`` URL go to the simulator's transport instead (e.g. ``baud``, ``flow``)."""

    def __init__(self, capabilities: Capabilities, *, deferral: Deferral = "asap") -> None:
        if deferral not in ("asap", "flush"):
            raise ConfigError(f"deferral must be 'asap' or 'flush', got {deferral!r}")
        self.capabilities = capabilities
        self.deferral: Deferral = deferral
        self.is_open = False
        w_mm, h_mm = capabilities.size_mm
        self._window: Rect = (0.0, 0.0, w_mm, h_mm)
        self._window_set = False
        """True once ``window()`` was called: a Scene drawn before that is fitted to the viewport instead."""
        self._window_angle = 0.0
        self._viewport: Rect = (0.0, 0.0, 1.0, 1.0)
        self._preserve_aspect = True
        self._pending: list[tuple[Drawable, geo.ViewingPipeline]] = []
        """Items drawn but not yet rendered, each with the pipeline in force when it was drawn."""
        self._pipeline: geo.ViewingPipeline | None = None

    # -- construction from URLs -------------------------------------------------------------
    @classmethod
    @abstractmethod
    def from_url(cls, url: DeviceURL, **kwargs: object) -> Display:
        """Build the display a parsed URL describes; read options with ``cls.read_url_options(url)``."""

    @classmethod
    def read_url_options(cls, url: DeviceURL) -> OptionValues:
        """The URL's options read against ``OPTIONS``; unknown names are refused, listing the known ones."""
        return read_options(cls.OPTIONS, url.options, str(url))

    @classmethod
    def split_sim_url(cls, url: DeviceURL) -> tuple[DeviceURL, dict[str, str]]:
        """Split ``sim:MODEL?options`` into the display's own URL and the options for the simulator.

        The display keeps the options it declares (``OPTIONS``) except ``SIM_TRANSPORT``; the simulator gets
        every other option, and ``SIM_SHARED`` ones as well.
        """
        declared = {spec.name for spec in cls.OPTIONS}
        own = {k: v for k, v in url.options.items() if k in declared and k not in cls.SIM_TRANSPORT}
        sim = {k: v for k, v in url.options.items() if k not in own or k in cls.SIM_SHARED}
        return DeviceURL(url.target, "", own, str(url)), sim

    # -- life cycle --------------------------------------------------------------------------
    def open(self) -> Display:
        """Connect to the device (idempotent)."""
        if not self.is_open:
            self._open_device()
            self.is_open = True
        return self

    def close(self) -> None:
        """Draw what is pending, leave the device safe and release it (idempotent)."""
        if not self.is_open:
            return
        try:
            self.flush()
        finally:
            self.is_open = False
            self._close_device()

    def abort(self) -> None:
        """Leave the device safe without drawing what is pending (used on errors and Ctrl-C)."""
        self._pending.clear()
        if self.is_open:
            self.is_open = False
            self._close_device()

    def __enter__(self) -> Display:
        return self.open()

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if exc_type is None:
            self.close()
        else:
            log.info("closing %s safely after %s", type(self).__name__, exc_type.__name__)
            self.abort()

    # -- viewing -----------------------------------------------------------------------------
    def window(self, xmin: float, ymin: float, xmax: float, ymax: float, *, angle: float = 0.0) -> None:
        """Set the world-coordinate window (optionally rotated by ``angle`` radians about its corner).

        A degenerate, non-finite or overflowing window raises ``InvalidArgument`` (a ValueError) at once.
        """
        window, window_angle = geo.as_rect((xmin, ymin, xmax, ymax), "window"), geo.as_number(angle, "window angle")
        self._window, self._window_angle = window, window_angle
        self._window_set = True
        self._pipeline = None

    def viewport(self, xmin: float, ymin: float, xmax: float, ymax: float, *, preserve_aspect: bool = True) -> None:
        """Set the viewport in normalized device coordinates [0, 1]^2."""
        viewport = geo.as_rect((xmin, ymin, xmax, ymax), "viewport")
        if not all(0.0 <= v <= 1.0 for v in viewport):
            raise ConfigError(f"viewport coordinates are normalized to [0, 1], got {viewport}")
        self._viewport = viewport
        self._preserve_aspect = preserve_aspect
        self._pipeline = None

    @property
    def pipeline(self) -> geo.ViewingPipeline:
        """The current world-to-device viewing pipeline."""
        if self._pipeline is None:
            self._pipeline = self._pipeline_for(self._window)
        return self._pipeline

    def _pipeline_for(self, window: Rect) -> geo.ViewingPipeline:
        """The viewing pipeline of ``window`` with the display's viewport, angle and aspect rule."""
        caps = self.capabilities
        return geo.ViewingPipeline(
            window, self._viewport, device_size=caps.size, y_down=caps.y_down,
            window_angle=self._window_angle, preserve_aspect=self._preserve_aspect,
        )

    def scene_pipeline(self, scene: Scene) -> geo.ViewingPipeline:
        """The pipeline a Scene is drawn with: the current one, or (window never set) one whose view-plane
        window fits the scene's projected bounds to the viewport, aspect kept."""
        if self._window_set:
            return self.pipeline
        caps = self.capabilities
        x0, y0, x1, y1 = self._viewport
        aspect = (x1 - x0) * caps.size[0] / ((y1 - y0) * caps.size[1])
        from pixelpen.display.render3d import fitted_window

        window = fitted_window(scene, geo.scale_factor(self.pipeline.matrix), caps.tolerance, aspect)
        return self.pipeline if window is None else self._pipeline_for(window)

    # -- drawing -----------------------------------------------------------------------------
    def draw(self, item: Drawable | Iterable[Primitive]) -> None:
        """Draw a picture, segment, primitive or 3D Scene now (deferral 'asap') or at the next ``flush()``."""
        self._require_open()
        if _is_scene(item):
            self._pending.append((item, self.scene_pipeline(item)))
            if self.deferral == "asap":
                self.flush()
            return
        if not isinstance(item, (Picture, Segment, *PRIMITIVE_TYPES)):
            if not isinstance(item, Iterable):
                raise InvalidArgumentType(f"draw takes a Picture, Segment, primitive or an iterable of primitives, "
                                          f"got {type(item).__name__}")
            items = list(item)
            picture = Picture()
            for prim in items:
                picture.add(prim)
            item = picture
        self._pending.append((item, self.pipeline))
        if self.deferral == "asap":
            self.flush()

    def flush(self) -> None:
        """Render everything pending and push it to the device."""
        self._require_open()
        pending, self._pending = self._pending, []
        for item, pipeline in pending:
            if _is_scene(item):
                self._render_scene(item, pipeline)
            else:
                self._render(list(self.shapes(cast("Picture | Primitive | Segment", item), pipeline)))
        self._present()

    def clear(self) -> None:
        """Start a new frame (raster) or a new sheet (vector devices that cannot erase)."""
        self._require_open()
        self._pending.clear()
        self._erase()

    def shapes(
        self, item: Picture | Primitive | Segment, pipeline: geo.ViewingPipeline | None = None
    ) -> Iterable[DeviceShape]:
        """The device-space shapes of an item under ``pipeline`` (default: the current one)."""
        if isinstance(item, Segment):
            picture = Picture()
            picture.add(item)
            item = picture
        return flatten_picture(
            item, pipeline or self.pipeline, tolerance=self.capabilities.tolerance, unit_mm=self.capabilities.unit_mm
        )

    def _require_open(self) -> None:
        if not self.is_open:
            raise PixelpenError(f"{type(self).__name__} is not open: call open() or use it in a 'with' block")

    def _render_scene(self, scene: Scene, pipeline: geo.ViewingPipeline) -> None:
        """Render a 3D scene: its visible edges as strokes (raster displays shade it instead)."""
        from pixelpen.display.render3d import scene_strokes

        shapes, _ = scene_strokes(scene, pipeline, self.capabilities.tolerance)
        self._render(shapes)

    # -- the device's core -------------------------------------------------------------------
    @abstractmethod
    def _open_device(self) -> None:
        """Connect to the hardware or create the output."""

    @abstractmethod
    def _close_device(self) -> None:
        """Leave the device safe (pen up, motors off, files flushed) and release it."""

    @abstractmethod
    def _render(self, shapes: list[DeviceShape]) -> None:
        """Turn device-space shapes into the device's representation (pixels, strokes)."""

    @abstractmethod
    def _present(self) -> None:
        """Push what was rendered to the device (send the frame, plot the strokes, write the file)."""

    @abstractmethod
    def _erase(self) -> None:
        """Clear the drawing surface."""


def _is_scene(item: object) -> TypeGuard[Scene]:
    """True for a 3D Scene (one exists only once its module is imported, so the 3D code loads on first use)."""
    module = sys.modules.get("pixelpen.display.scene3d")
    return module is not None and isinstance(item, module.Scene)

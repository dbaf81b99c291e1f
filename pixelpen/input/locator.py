"""The locator: a position in the world coordinates of a display, through the inverse of its viewing pipeline.

The position is kept in device coordinates and answered in world coordinates by the inverse of the bound
display's current viewing pipeline (``ViewingPipeline.inverse``: device -> normalized -> viewing -> world):

* **relative devices** (mouse, trackball: :class:`~pixelpen.devices.hid.events.Motion`) move it by their
  motion — in millimetres times ``gain`` on the display when the device's resolution is known, else
  ``gain`` device units per count — and it stays inside the viewport's device rectangle
  (``pipeline.clip_rect``); HID's +y is towards the user, i.e. down on the display;
* **absolute devices** (tablet :class:`~pixelpen.devices.hid.events.Pen`, touch screen
  :class:`~pixelpen.devices.hid.events.TouchFrame`, an absolute pointer's ``x``/``y`` axes) map their 0..1
  range (y down, as HID reports it) onto the viewport: (0, 0) is its top-left corner, (1, 1) its bottom-right.
  With ``preserve_aspect`` (the display's default) that is the part of the viewport the window fills, so the
  whole tablet is the whole window: a window the size of the tablet in mm gives the pen's position in mm.
  Axes report over ``axis_range`` (default 0..1, an absolute pointer; (-1, 1) makes a joystick's stick an
  absolute locator, its centre the viewport's); positions outside the range stay at its edge.

The trigger is a press of one of ``buttons`` (default the primary button), the pen tip or a finger touching
down.  An ``echo`` (:mod:`pixelpen.input.echo`) follows the position on the display.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from pixelpen import geometry as geo
from pixelpen.devices.hid.events import Axis, Button, InputEvent, Motion, Pen, TouchFrame
from pixelpen.display.base import Display
from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.input.queue import LogicalDevice, Mode

if TYPE_CHECKING:
    from pixelpen.input.echo import Echo


class Location(NamedTuple):
    """A locator measure: world coordinates and the device coordinates they came from."""

    x: float
    y: float
    device_x: float
    device_y: float


class Locator(LogicalDevice):
    """A position in world coordinates of ``display`` (a Display, or a bare ViewingPipeline)."""

    kind = "locator"

    def __init__(self, display: Display | geo.ViewingPipeline, *, mode: Mode = "request", gain: float = 1.0,
                 buttons: Iterable[int] = (1,), initial: tuple[float, float] | None = None,
                 axis_range: tuple[float, float] = (0.0, 1.0), echo: Echo | None = None) -> None:
        super().__init__(mode=mode)
        if isinstance(display, geo.ViewingPipeline):
            self.display: Display | None = None
            self._pipeline: geo.ViewingPipeline | None = display
            self.unit_mm = 1.0
        elif isinstance(display, Display):
            self.display, self._pipeline = display, None
            self.unit_mm = float(display.capabilities.unit_mm)
        else:
            raise InvalidArgumentType(f"a locator is bound to a Display or a ViewingPipeline, "
                                      f"not {type(display).__name__}")
        if not (isinstance(gain, (int, float)) and 0 < gain < 1e6):
            raise InvalidArgument(f"locator gain must be a number in (0, 1e6), got {gain!r}")
        self.gain = float(gain)
        low, high = axis_range
        if not (isinstance(low, (int, float)) and isinstance(high, (int, float)) and low < high):
            raise InvalidArgument(f"locator axis_range must be (low, high) with low < high, got {axis_range!r}")
        self.axis_range = (float(low), float(high))
        self.buttons = frozenset(buttons)
        self.echo = echo
        self._axes: dict[str, float] = {}
        self._unit: tuple[geo.ViewingPipeline, np.ndarray] | None = None
        x0, y0, x1, y1 = self.pipeline.clip_rect
        start = ((x0 + x1) / 2, (y0 + y1) / 2) if initial is None else tuple(self.pipeline.to_device(initial))
        self.position = self._clamp(float(start[0]), float(start[1]))
        """The position in device coordinates."""
        self.pressed = False
        """True while the trigger button, the pen tip or a finger is down."""

    @property
    def pipeline(self) -> geo.ViewingPipeline:
        """The bound display's current viewing pipeline."""
        if self._pipeline is not None:
            return self._pipeline
        assert self.display is not None
        return self.display.pipeline

    def value(self) -> Location:
        """The position in world coordinates (and device coordinates)."""
        wx, wy = self.pipeline.to_world(self.position)
        return Location(float(wx), float(wy), *self.position)

    def handle(self, event: InputEvent) -> bool:
        """Move with motion or absolute positions; True at a trigger press or touch-down."""
        if isinstance(event, Motion):
            self.move_by(event.dx, event.dy, event.dx_mm, event.dy_mm, time=event.time)
            return False
        if isinstance(event, Pen):
            if event.in_range:
                self.move_to_unit(event.x, event.y, time=event.time)
            return self._press(event.touching and event.in_range)
        if isinstance(event, TouchFrame):
            down = [c for c in event.contacts if c.touching]
            if down:
                self.move_to_unit(down[0].x, down[0].y, time=event.time)
            return self._press(bool(down))
        if isinstance(event, Axis) and event.axis in ("x", "y"):
            self._axes[event.axis] = event.value
            if len(self._axes) == 2:
                low, high = self.axis_range
                self.move_to_unit((self._axes["x"] - low) / (high - low), (self._axes["y"] - low) / (high - low),
                                  time=event.time)
            return False
        if isinstance(event, Button) and event.button in self.buttons:
            return self._press(event.pressed)
        return False

    def _press(self, down: bool) -> bool:
        """Track the pressed state; True on the press edge (the trigger)."""
        edge = down and not self.pressed
        self.pressed = down
        return edge

    def move_by(self, dx: float, dy: float, dx_mm: float | None = None, dy_mm: float | None = None, *,
                time: float | None = None) -> None:
        """Move by relative motion (HID axes: +y towards the user), kept inside the viewport."""
        if dx_mm is not None and dy_mm is not None:
            ddx, ddy = dx_mm * self.gain / self.unit_mm, dy_mm * self.gain / self.unit_mm
        else:
            ddx, ddy = dx * self.gain, dy * self.gain
        x, y = self.position
        self._set(self._clamp(x + ddx, y + (ddy if self.pipeline.y_down else -ddy)), time)

    def move_to_unit(self, u: float, v: float, *, time: float | None = None) -> None:
        """Move to the point (u, v) of the unit square (v down) mapped onto the viewport the window fills."""
        m = self._unit_matrix()
        u, v = min(max(u, 0.0), 1.0), min(max(v, 0.0), 1.0)
        self._set((float(m[0, 0] * u + m[0, 1] * v + m[0, 2]), float(m[1, 0] * u + m[1, 1] * v + m[1, 2])), time)

    def _unit_matrix(self) -> np.ndarray:
        """The unit square (v down) -> device matrix of the current pipeline (computed once per pipeline)."""
        p = self.pipeline
        if self._unit is None or self._unit[0] is not p:
            corners = geo.apply(p.world_to_normalized, p.window_corners)
            (nx0, ny0), (nx1, ny1) = corners.min(axis=0), corners.max(axis=0)
            square = np.array([[nx1 - nx0, 0.0, nx0], [0.0, ny0 - ny1, ny1], [0.0, 0.0, 1.0]])
            self._unit = (p, p.normalized_to_device @ square)
        return self._unit[1]

    def move_to(self, x: float, y: float, *, time: float | None = None) -> None:
        """Move to a world point (an application warping the cursor), kept inside the viewport."""
        dx, dy = self.pipeline.to_device((x, y))
        self._set(self._clamp(float(dx), float(dy)), time)

    def _set(self, position: tuple[float, float], time: float | None) -> None:
        self.position = position
        if self.echo is not None:
            self.echo.move(*position, time=time)

    def _clamp(self, x: float, y: float) -> tuple[float, float]:
        """(x, y) kept inside the viewport's device rectangle."""
        x0, y0, x1, y1 = self.pipeline.clip_rect
        return float(np.clip(x, x0, x1)), float(np.clip(y, y0, y1))

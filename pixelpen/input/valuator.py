"""The valuator: a number bounded to [low, high], from an absolute axis, the pen's pressure or a wheel.

* an axis (``source`` = an :class:`~pixelpen.devices.hid.events.Axis` name such as ``slider`` or ``z``)
  maps its normalised value over ``axis_range`` (default -1..1, a stick; 0..1 for a trigger) linearly onto
  [low, high];
* ``pressure`` maps the tablet pen's pressure (0..1) onto [low, high];
* ``wheel`` (``wheel-horizontal`` for AC Pan) moves the value by ``step`` x (high - low) per detent, clamped.

The trigger is a press of ``button`` (default 1, the primary); ``button=None`` makes every change a trigger.
"""

from __future__ import annotations

import math

from pixelpen.devices.hid.events import Axis, Button, InputEvent, Pen, Wheel
from pixelpen.errors import InvalidArgument
from pixelpen.input.queue import LogicalDevice, Mode


class Valuator(LogicalDevice):
    """A bounded scalar from an axis, the pen pressure or a wheel."""

    kind = "valuator"

    def __init__(self, *, source: str = "wheel", low: float = 0.0, high: float = 1.0, initial: float | None = None,
                 step: float = 0.05, axis_range: tuple[float, float] = (-1.0, 1.0), button: int | None = 1,
                 mode: Mode = "request") -> None:
        super().__init__(mode=mode)
        if not (_finite(low) and _finite(high) and low < high):
            raise InvalidArgument(f"valuator bounds must be finite numbers with low < high, got {low!r}, {high!r}")
        if not (_finite(axis_range[0]) and _finite(axis_range[1]) and axis_range[0] < axis_range[1]):
            raise InvalidArgument(f"axis_range must be (min, max) with min < max, got {axis_range!r}")
        if not _finite(step):
            raise InvalidArgument(f"valuator step must be a finite number, got {step!r}")
        self.source = source
        self.low, self.high = float(low), float(high)
        self.step = float(step)
        self.axis_range = (float(axis_range[0]), float(axis_range[1]))
        self.button = button
        self.current = self._clamp(self.low if initial is None else float(initial))

    def value(self) -> float:
        """The current value."""
        return self.current

    def handle(self, event: InputEvent) -> bool:
        """Follow the source; True at a press of the trigger button (or at any change when it is None)."""
        before = self.current
        if isinstance(event, Axis) and event.axis == self.source:
            a0, a1 = self.axis_range
            self.current = self._clamp(self.low + (event.value - a0) / (a1 - a0) * (self.high - self.low))
        elif isinstance(event, Pen) and self.source == "pressure":
            self.current = self._clamp(self.low + event.pressure * (self.high - self.low))
        elif isinstance(event, Wheel) and self.source in ("wheel", "wheel-horizontal"):
            detents = event.vertical if self.source == "wheel" else event.horizontal
            self.current = self._clamp(self.current + detents * self.step * (self.high - self.low))
        elif isinstance(event, Button) and self.button is not None:
            return event.button == self.button and event.pressed
        return self.button is None and self.current != before

    def _clamp(self, value: float) -> float:
        return min(max(value, self.low), self.high)


def _finite(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)

"""Echo: a cursor or rubber band drawn over a raster display's picture, restoring what was under it.

An :class:`Echo` saves the pixels of the small rectangle its shape covers, draws the shape there, and on
moving puts the saved pixels back before saving and drawing at the new place; the canvas's damage is then
exactly those rectangles, so a panel sends only them (its partial refresh trims them further to the pixels
that changed).  Shapes: ``crosshair`` and ``box`` (``size`` pixels across) at the position, ``line`` (a
rubber band from the anchor) and ``rectangle`` (a rubber rectangle from the anchor).  Frames are sent at most
every ``interval`` seconds of event time (``present=False``: never; the application flushes).

The saved pixels are what was there when the echo was drawn: draw on the display inside ``with
echo.hidden():`` (or ``hide()`` first), so that new drawing is not undone by the next move.  A vector display
cannot erase, so it has no echo (InvalidArgumentType).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Literal

import numpy as np

from pixelpen.colour import parse_colour
from pixelpen.display.kinds import RasterDisplay
from pixelpen.errors import ConfigError, InvalidArgument, InvalidArgumentType

EchoShape = Literal["crosshair", "box", "line", "rectangle"]
SHAPES: tuple[EchoShape, ...] = ("crosshair", "box", "line", "rectangle")
MAX_SIZE = 1024
"""Largest cursor, in pixels across."""


class Echo:
    """A cursor (``crosshair``, ``box``) or rubber band (``line``, ``rectangle``) over a raster display."""

    def __init__(self, display: RasterDisplay, *, shape: EchoShape = "crosshair", size: int = 9,
                 colour: object = "orange", anchor: tuple[float, float] | None = None, interval: float = 0.0,
                 present: bool = True) -> None:
        if not isinstance(display, RasterDisplay):
            raise InvalidArgumentType(f"echo needs a raster display (one that can erase), not {type(display).__name__}")
        if shape not in SHAPES:
            raise ConfigError(f"echo shape must be one of {', '.join(SHAPES)}, got {shape!r}")
        if isinstance(size, bool) or not isinstance(size, int) or not 1 <= size <= MAX_SIZE:
            raise InvalidArgument(f"echo size must be an integer in 1..{MAX_SIZE} pixels, got {size!r}")
        if not (isinstance(interval, (int, float)) and interval >= 0):
            raise InvalidArgument(f"echo interval must be a number of seconds >= 0, got {interval!r}")
        self.display = display
        self.shape: EchoShape = shape
        self.size = size
        self.value = display.canvas.colour_value(parse_colour(colour))
        self.anchor = anchor
        """The rubber band's fixed end, device coordinates (None: the first position given)."""
        self.interval = float(interval)
        self.present = present
        self.position: tuple[float, float] | None = None
        self.visible = True
        """Whether the echo is drawn when it has a position."""
        self.frames = 0
        """Frames the echo sent."""
        self._saved: tuple[int, int, np.ndarray] | None = None
        self._last = -math.inf

    def move(self, x: float, y: float, *, time: float | None = None) -> None:
        """Put the echo at device point (x, y); a frame is sent when ``interval`` has passed since the last."""
        if self.anchor is None and self.shape in ("line", "rectangle"):
            self.anchor = (x, y)
        self.position = (x, y)
        if not self.visible:
            return
        self._restore()
        self._draw()
        if time is None or time - self._last >= self.interval:
            self._show(time)

    def hide(self) -> None:
        """Take the echo off the display (its pixels restored) and send the frame."""
        self.visible = False
        if self._restore():
            self._show(None)

    def show(self) -> None:
        """Draw the echo again where it is and send the frame."""
        self.visible = True
        if self.position is not None and self._saved is None:
            self._draw()
            self._show(None)

    @contextmanager
    def hidden(self) -> Iterator[None]:
        """Hide the echo while the block draws on the display, then show it over the new picture."""
        was = self.visible
        self.hide()
        try:
            yield
        finally:
            if was:
                self.show()

    def close(self) -> None:
        """Remove the echo for good (idempotent)."""
        if self.display.is_open:
            self.hide()
        self._saved = None

    # -- drawing -----------------------------------------------------------------------------------------
    def segments(self) -> np.ndarray:
        """The shape's pixel segments (N, 4) at the current position."""
        assert self.position is not None
        px, py = (math.floor(v) for v in self.position)
        h = self.size // 2
        if self.shape == "crosshair":
            return np.array([[px - h, py, px + h, py], [px, py - h, px, py + h]])
        if self.shape == "box":
            x0, y0, x1, y1 = px - h, py - h, px + h, py + h
        else:
            ax, ay = (math.floor(v) for v in (self.anchor or self.position))
            if self.shape == "line":
                return np.array([[ax, ay, px, py]])
            x0, y0, x1, y1 = ax, ay, px, py
        return np.array([[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]])

    def _draw(self) -> None:
        """Save the pixels of the shape's bounding box, then draw the shape."""
        canvas = self.display.canvas
        seg = self.segments()
        xs, ys = seg[:, 0::2], seg[:, 1::2]
        x0, y0 = max(int(xs.min()), 0), max(int(ys.min()), 0)
        x1, y1 = min(int(xs.max()) + 1, canvas.width), min(int(ys.max()) + 1, canvas.height)
        if x1 <= x0 or y1 <= y0:
            return
        self._saved = (x0, y0, canvas.array[y0:y1, x0:x1].copy())
        canvas.lines(seg, self.value)

    def _restore(self) -> bool:
        """Put back the pixels under the echo; True when there were any."""
        if self._saved is None:
            return False
        x, y, pixels = self._saved
        self._saved = None
        self.display.canvas.blit(pixels, x, y)
        return True

    def _show(self, time: float | None) -> None:
        """Send the damaged rectangles (when presenting)."""
        if self.present and self.display.is_open:
            self.display.flush()
            self.frames += 1
            if time is not None:
                self._last = time

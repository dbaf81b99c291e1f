"""The panel demo animation: a cursor bouncing over the picture and a clock ticking a second a frame.

Each frame changes two small areas, as a user interface does.  Frames are patches of native pixels, so
``pixelpen demo``, ``pixelpen sim PANEL --view`` and ``benchmarks/panels.py`` give any canvas the same frames.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from pixelpen.display.kinds import RasterDisplay
from pixelpen.errors import InvalidArgument

Patch = tuple[int, int, np.ndarray]
"""(x, y, pixels): native pixels (the frame's dtype and trailing shape) pasted with their top-left at (x, y)."""
Native = int | tuple[int, ...]
"""A native pixel value (``Canvas.colour_value``): 0/1 on a mono canvas, (r, g, b) on an RGB one."""
START_SECONDS = 12 * 3600 + 34 * 60 + 50
"""The clock's first reading, 12:34:50: the minutes carry at the tenth frame."""
CURSOR_RGB = (255, 160, 0)
"""The cursor's colour on a colour panel (white on a mono one)."""


def _solid(shape: tuple[int, int], like: np.ndarray, value: Native) -> np.ndarray:
    """An HxW patch of ``value`` in ``like``'s dtype and trailing shape."""
    patch = np.empty((*shape, *like.shape[2:]), like.dtype)
    patch[...] = value
    return patch


def _bounce(position: int, velocity: int, high: int) -> tuple[int, int]:
    """One step along an axis from 0 to ``high``, reflected at either end: (position, velocity)."""
    position += velocity
    if not 0 <= position <= high:
        velocity = -velocity
        position += 2 * velocity
    return min(max(position, 0), high), velocity


class Cursor:
    """A solid square moving ``velocity`` pixels a frame over ``background``, bouncing off its edges."""

    def __init__(self, background: np.ndarray, side: int, ink: Native, position: tuple[int, int] = (5, 5),
                 velocity: tuple[int, int] = (3, 2)) -> None:
        height, width = background.shape[:2]
        if not 0 < side <= min(width, height):
            raise InvalidArgument(f"cursor side {side} does not fit a {width}x{height} frame")
        self.background = background
        self.side = side
        self.square = _solid((side, side), background, ink)
        self._high = (width - side, height - side)
        self.x, self.y = (min(max(p, 0), h) for p, h in zip(position, self._high, strict=True))
        self.dx, self.dy = velocity

    def drawn(self) -> Patch:
        """The square where it is now."""
        return self.x, self.y, self.square

    def move(self) -> list[Patch]:
        """Move one frame: the background back over the old square, then the square at its new place."""
        x, y, s = self.x, self.y, self.side
        old = (x, y, self.background[y:y + s, x:x + s])
        self.x, self.dx = _bounce(x, self.dx, self._high[0])
        self.y, self.dy = _bounce(y, self.dy, self._high[1])
        return [old, self.drawn()]


class ClockFace:
    """``HH:MM:SS`` (Pillow's default font, ``font_px`` high) in a box of a frame like ``like``, ticking a second."""

    def __init__(self, like: np.ndarray, font_px: int, ink: Native, paper: Native,
                 place: Literal["centre", "bottom-right"] = "bottom-right", seconds: int = START_SECONDS) -> None:
        height, width = like.shape[:2]
        self.size = (min(width, 5 * font_px), min(height, font_px + font_px // 3))
        """The box's (width, height): eight digits and colons fit in five font heights."""
        if place == "centre":
            self.at = ((width - self.size[0]) // 2, (height - self.size[1]) // 2)
        else:
            self.at = (width - self.size[0], height - self.size[1])
        self.like, self.ink, self.paper = like, ink, paper
        self.font = ImageFont.load_default(size=font_px)
        self.seconds = seconds

    def tick(self) -> Patch:
        """The box showing the current second, then the clock one second on."""
        h, rest = divmod(self.seconds % 86400, 3600)
        image = Image.new("L", self.size)
        ImageDraw.Draw(image).text((1, 0), f"{h:02d}:{rest // 60:02d}:{rest % 60:02d}", fill=255, font=self.font)
        patch = _solid((self.size[1], self.size[0]), self.like, self.paper)
        patch[np.asarray(image) >= 128] = self.ink
        self.seconds += 1
        return (*self.at, patch)


class PanelAnimation:
    """The cursor and the clock over what an open raster display shows now; ``step`` draws and sends a frame."""

    def __init__(self, display: RasterDisplay) -> None:
        self.display = display
        canvas = display.canvas
        background = canvas.array.copy()
        short = min(canvas.width, canvas.height)
        white, black = canvas.colour_value((255, 255, 255)), canvas.colour_value((0, 0, 0))
        self.cursor = Cursor(background, max(4, short // 12), white if canvas.mode == "1" else
                             canvas.colour_value(CURSOR_RGB),
                             velocity=(max(3, canvas.width // 40), max(2, canvas.height // 60)))
        self.clock = ClockFace(background, max(10, short // 16), white, black)
        self.frames = 0

    def patches(self) -> list[Patch]:
        """The next frame: the cursor's old square restored, the clock, then the cursor on top."""
        cursor = [self.cursor.drawn()] if self.frames == 0 else self.cursor.move()
        return [*cursor[:-1], self.clock.tick(), cursor[-1]]

    def step(self) -> None:
        """Draw the next frame and send it."""
        canvas = self.display.canvas
        for x, y, pixels in self.patches():
            canvas.blit(pixels, x, y)
        self.display.flush()
        self.frames += 1

"""Raster engine: scan conversion into a numpy framebuffer, pixel formats, colour, image operations, damage."""

from .canvas import MODES, Canvas
from .circles import midpoint_circle, midpoint_ellipse
from .formats import FORMATS, pack, unpack
from .lines import bresenham, dda

__all__ = ["Canvas", "MODES", "bresenham", "dda", "midpoint_circle", "midpoint_ellipse", "pack", "unpack", "FORMATS"]

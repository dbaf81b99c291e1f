"""Raster engine: scan conversion into a numpy framebuffer, pixel formats, colour, image operations, damage."""

from pixelpen.raster.canvas import MODES, Canvas
from pixelpen.raster.circles import midpoint_circle, midpoint_ellipse
from pixelpen.raster.formats import FORMATS, pack, unpack
from pixelpen.raster.lines import bresenham, dda

__all__ = ["FORMATS", "MODES", "Canvas", "bresenham", "dda", "midpoint_circle", "midpoint_ellipse", "pack", "unpack"]

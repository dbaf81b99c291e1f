"""Raster engine: scan conversion into a numpy framebuffer, pixel formats, colour, image operations, damage."""

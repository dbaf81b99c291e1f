"""pixelpen: one drawing API for pen plotters, framebuffer panels and files, with wire-level simulators.

``pixelpen.open(url)`` opens a display (``png:out.png``, ``svg:out.svg?size=a4``, ``sim:hp7475a``);
pictures are built from the primitives in ``pixelpen.display.picture``.
"""

from __future__ import annotations

from pixelpen import _moved
from pixelpen.display.base import Display
from pixelpen.display.picture import (
    Arc,
    Bezier,
    BSpline,
    Circle,
    Ellipse,
    Fill,
    Image,
    Marker,
    Picture,
    Polygon,
    Polyline,
    Rectangle,
    Segment,
    Style,
    Text,
)
from pixelpen.display.registry import known_schemes
from pixelpen.display.registry import open_display as open
from pixelpen.errors import ConfigError, LinkError, ParseError, PixelpenError, ProtocolError, URLError

_moved.install()

__version__ = "0.1.0"

__all__ = [
    "Arc",
    "BSpline",
    "Bezier",
    "Circle",
    "ConfigError",
    "Display",
    "Ellipse",
    "Fill",
    "Image",
    "LinkError",
    "Marker",
    "ParseError",
    "Picture",
    "PixelpenError",
    "Polygon",
    "Polyline",
    "ProtocolError",
    "Rectangle",
    "Segment",
    "Style",
    "Text",
    "URLError",
    "known_schemes",
    "open",
]

"""pixelpen: one drawing API for pen plotters, framebuffer panels and files, with wire-level simulators.

``pixelpen.open(url)`` opens a display (``png:out.png``, ``svg:out.svg?size=a4``, ``sim:hp7475a``);
pictures are built from the primitives in ``pixelpen.display.picture``.  ``pixelpen.open_input(url)`` opens
an input device (``sim:tablet?script=signature``, ``hid:046d:c52b``, ``replay:FILE``; see ``docs/input.md``).
``pixelpen.Scene(camera=dict(...))`` is a 3D scene that ``display.draw(scene)`` shows on any display
(``docs/3d.md``).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from pixelpen import _moved
from pixelpen.display.registry import known_schemes
from pixelpen.display.registry import open_display as open
from pixelpen.errors import ConfigError, LinkError, ParseError, PixelpenError, ProtocolError, URLError
from pixelpen.input.registry import open_input

if TYPE_CHECKING:
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
    from pixelpen.display.scene3d import Scene

_moved.install()

__version__ = "0.1.0"

_LAZY = {"Display": "pixelpen.display.base", "Scene": "pixelpen.display.scene3d"} | dict.fromkeys(
    ("Arc", "BSpline", "Bezier", "Circle", "Ellipse", "Fill", "Image", "Marker", "Picture", "Polygon", "Polyline",
     "Rectangle", "Segment", "Style", "Text"), "pixelpen.display.picture")
"""Public names imported on first use (so ``import pixelpen`` loads neither numpy nor Pillow)."""


def __getattr__(name: str) -> object:
    """Import a lazily exported name's module on first access, then keep the name here."""
    if name not in _LAZY:
        raise AttributeError(f"module 'pixelpen' has no attribute {name!r}")
    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The module's names, the lazily exported ones included."""
    return sorted(set(globals()) | set(_LAZY))

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
    "Scene",
    "Segment",
    "Style",
    "Text",
    "URLError",
    "known_schemes",
    "open",
    "open_input",
]

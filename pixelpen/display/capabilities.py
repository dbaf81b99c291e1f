"""The capability table of a device, as data (the GKS workstation description table, modernised)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

Category = Literal["output", "input", "output+input", "file"]
Kind = Literal["raster", "vector", "none"]
ColourModel = Literal["mono", "grey", "indexed", "rgb565", "rgb666", "rgb888", "rgba", "pens"]



@dataclass(frozen=True)
class Capabilities:
    """What a device is and can do: category, raster/vector, size, unit, colours, primitives, limits."""

    model: str
    category: Category
    kind: Kind
    size: tuple[float, float]
    """Drawable area in device units (width, height)."""
    unit_mm: float
    """Length of one device unit in millimetres (a pixel's pitch, a plotter unit, a motor step)."""
    colour_model: ColourModel
    y_down: bool = True
    """True when device y grows downwards (panels, images, SVG); False for plotters (HPGL: y up)."""
    pens: tuple[str, ...] = ()
    """Pen colours (``#rrggbb``) for pen devices, pen 1 first."""
    native_primitives: frozenset[str] = frozenset({"polyline"})
    can_erase: bool = True
    tolerance: float = 0.5
    """Curve flattening tolerance in device units."""
    limits: dict[str, object] = field(default_factory=dict)

    @property
    def size_mm(self) -> tuple[float, float]:
        """Drawable area in millimetres."""
        return (self.size[0] * self.unit_mm, self.size[1] * self.unit_mm)

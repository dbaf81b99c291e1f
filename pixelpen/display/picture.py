"""Device-independent pictures: primitives in world coordinates with their attributes, and named segments."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterator, Literal, Union

import numpy as np

from ..errors import ConfigError

FillStyle = Literal["hollow", "solid", "hatch", "crosshatch", "pattern"]
Align = Literal["left", "center", "right"]
VAlign = Literal["bottom", "baseline", "middle", "top"]
MarkerKind = Literal["dot", "plus", "cross", "star", "circle", "square", "diamond"]

NAMED_COLOURS = {
    "black": (0, 0, 0), "white": (255, 255, 255), "red": (255, 0, 0), "green": (0, 160, 0),
    "blue": (0, 0, 255), "cyan": (0, 255, 255), "magenta": (255, 0, 255), "yellow": (255, 255, 0),
    "orange": (255, 140, 0), "brown": (139, 69, 19), "purple": (128, 0, 128), "grey": (128, 128, 128),
    "gray": (128, 128, 128),
}


def parse_colour(colour: object) -> tuple[int, int, int]:
    """Read a colour given as a name, ``#rgb``/``#rrggbb`` or an (r, g, b) tuple of 0-255 integers."""
    if isinstance(colour, str):
        text = colour.strip().lower()
        if text in NAMED_COLOURS:
            return NAMED_COLOURS[text]
        if text.startswith("#") and len(text) in (4, 7):
            digits = text[1:]
            if len(digits) == 3:
                digits = "".join(c * 2 for c in digits)
            try:
                return (int(digits[0:2], 16), int(digits[2:4], 16), int(digits[4:6], 16))
            except ValueError:
                pass
        raise ConfigError(f"unknown colour {colour!r}: use a name ({', '.join(sorted(NAMED_COLOURS))}) or #rrggbb")
    if isinstance(colour, (tuple, list)) and len(colour) == 3 and all(isinstance(c, (int, np.integer)) for c in colour):
        if all(0 <= int(c) <= 255 for c in colour):
            return (int(colour[0]), int(colour[1]), int(colour[2]))
    raise ConfigError(f"colour must be a name, '#rrggbb' or (r, g, b) in 0..255, got {colour!r}")


def colour_hex(rgb: tuple[int, int, int]) -> str:
    """Format an (r, g, b) colour as ``#rrggbb``."""
    return "#%02x%02x%02x" % rgb


@dataclass(frozen=True)
class Fill:
    """How an area is filled: hollow, solid, hatch/crosshatch (angle in radians, spacing in mm), or a pattern."""

    style: FillStyle = "solid"
    angle: float = 0.0
    spacing: float | None = None
    """Hatch spacing in millimetres; None = the pen/line width of the device."""
    pattern: tuple[tuple[int, ...], ...] | None = None
    """For ``pattern``: rows of 0/1 cells, repeated across the area in device pixels."""
    outline: bool = True
    """Also draw the boundary with the line attributes (GKS fill areas have none; plotters want one)."""

    def __post_init__(self) -> None:
        if self.style not in ("hollow", "solid", "hatch", "crosshatch", "pattern"):
            raise ConfigError(f"fill style must be hollow, solid, hatch, crosshatch or pattern, got {self.style!r}")
        if self.spacing is not None and not self.spacing > 0:
            raise ConfigError(f"hatch spacing must be > 0 mm, got {self.spacing!r}")
        if self.style == "pattern" and not self.pattern:
            raise ConfigError("a 'pattern' fill needs a pattern (rows of 0/1 cells)")


@dataclass(frozen=True)
class Style:
    """Attributes of a primitive: colour, pen, line width and type, fill, layer."""

    colour: tuple[int, int, int] = (0, 0, 0)
    pen: int | None = None
    """Plotter pen number (1-based); None = chosen from the colour by the device."""
    width: float = 0.0
    """Line width in millimetres; 0 = the thinnest line the device draws (1 pixel, one pen stroke)."""
    dash: tuple[float, ...] | None = None
    """Dash pattern in millimetres: on, off, on, off, ...; None = solid."""
    fill: Fill | None = None
    """Area fill for closed primitives; None = outline only."""
    layer: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "colour", parse_colour(self.colour))
        if self.width < 0:
            raise ConfigError(f"line width must be >= 0 mm, got {self.width}")
        if self.dash is not None:
            dash = tuple(float(d) for d in self.dash)
            if not dash or len(dash) % 2 or any(d < 0 for d in dash) or sum(dash) <= 0:
                raise ConfigError(f"dash pattern must be an even number of lengths >= 0 with a positive sum, got {self.dash!r}")
            object.__setattr__(self, "dash", dash)
        if self.pen is not None and self.pen < 1:
            raise ConfigError(f"pen numbers start at 1, got {self.pen}")


def _points(data: object, name: str, min_count: int = 1) -> np.ndarray:
    arr = np.asarray(data, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 2 or len(arr) < min_count:
        raise ConfigError(f"{name} needs an (N, 2) array of points with N >= {min_count}, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise ConfigError(f"{name} has a non-finite coordinate")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Polyline:
    """An open chain of straight segments through ``points``."""

    points: np.ndarray
    style: Style = Style()

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", _points(self.points, "polyline", 1))


@dataclass(frozen=True, eq=False)
class Polygon:
    """A fill area: the first ring is the outline, further rings are holes (even-odd rule)."""

    rings: tuple[np.ndarray, ...]
    style: Style = Style()

    def __post_init__(self) -> None:
        rings = self.rings
        if isinstance(rings, np.ndarray) or (len(rings) and np.ndim(rings[0]) == 1):
            rings = (rings,)
        object.__setattr__(self, "rings", tuple(_points(r, "polygon ring", 3) for r in rings))
        if not self.rings:
            raise ConfigError("a polygon needs at least one ring")


@dataclass(frozen=True, eq=False)
class Rectangle:
    """An axis-aligned rectangle in world coordinates (corners x0, y0 and x1, y1)."""

    x0: float
    y0: float
    x1: float
    y1: float
    style: Style = Style()


@dataclass(frozen=True, eq=False)
class Circle:
    """A circle of radius ``r`` about ``center``."""

    center: tuple[float, float]
    r: float
    style: Style = Style()

    def __post_init__(self) -> None:
        if not self.r >= 0:
            raise ConfigError(f"circle radius must be >= 0, got {self.r}")


@dataclass(frozen=True, eq=False)
class Ellipse:
    """An ellipse with semi-axes ``rx``, ``ry`` about ``center``, rotated by ``angle`` radians."""

    center: tuple[float, float]
    rx: float
    ry: float
    angle: float = 0.0
    style: Style = Style()

    def __post_init__(self) -> None:
        if not (self.rx >= 0 and self.ry >= 0):
            raise ConfigError(f"ellipse semi-axes must be >= 0, got {self.rx}, {self.ry}")


@dataclass(frozen=True, eq=False)
class Arc:
    """An elliptical arc from angle ``start`` to ``end`` (radians, counter-clockwise); optionally closed."""

    center: tuple[float, float]
    rx: float
    ry: float
    start: float
    end: float
    angle: float = 0.0
    close: Literal["open", "chord", "pie"] = "open"
    style: Style = Style()


@dataclass(frozen=True, eq=False)
class Bezier:
    """A Bézier path: one curve of any degree, or consecutive curves of ``degree`` sharing end points."""

    control_points: np.ndarray
    degree: int | None = None
    style: Style = Style()

    def __post_init__(self) -> None:
        pts = _points(self.control_points, "Bezier", 2)
        object.__setattr__(self, "control_points", pts)
        if self.degree is not None:
            if self.degree < 1 or (len(pts) - 1) % self.degree:
                raise ConfigError(
                    f"a Bezier path of degree {self.degree} needs k*{self.degree}+1 control points, got {len(pts)}"
                )


@dataclass(frozen=True, eq=False)
class BSpline:
    """A B-spline curve of ``degree`` over ``control_points``; ``knots`` None = open uniform (clamped)."""

    control_points: np.ndarray
    degree: int = 3
    knots: tuple[float, ...] | None = None
    style: Style = Style()

    def __post_init__(self) -> None:
        pts = _points(self.control_points, "B-spline", 2)
        object.__setattr__(self, "control_points", pts)
        if not 1 <= self.degree < len(pts):
            raise ConfigError(f"a B-spline of degree {self.degree} needs more than {self.degree} control points, got {len(pts)}")
        if self.knots is not None:
            knots = tuple(float(k) for k in self.knots)
            if len(knots) != len(pts) + self.degree + 1:
                raise ConfigError(f"a B-spline needs n + degree + 1 = {len(pts) + self.degree + 1} knots, got {len(knots)}")
            if any(b < a for a, b in zip(knots, knots[1:])):
                raise ConfigError("B-spline knots must not decrease")
            object.__setattr__(self, "knots", knots)


@dataclass(frozen=True, eq=False)
class Marker:
    """Markers of one kind centred on ``points``; ``size`` in millimetres."""

    points: np.ndarray
    kind: MarkerKind = "plus"
    size: float = 2.0
    style: Style = Style()

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", _points(self.points, "marker", 1))
        if self.kind not in ("dot", "plus", "cross", "star", "circle", "square", "diamond"):
            raise ConfigError(f"unknown marker kind {self.kind!r}")


@dataclass(frozen=True, eq=False)
class Text:
    """A string at ``position``; ``height`` of a capital in world units, ``angle`` and ``slant`` in radians."""

    position: tuple[float, float]
    text: str
    height: float = 5.0
    angle: float = 0.0
    slant: float = 0.0
    align: Align = "left"
    valign: VAlign = "baseline"
    style: Style = Style()

    def __post_init__(self) -> None:
        if not self.height > 0:
            raise ConfigError(f"text height must be > 0, got {self.height}")


@dataclass(frozen=True, eq=False)
class Image:
    """A raster image (HxW grey, HxWx3 RGB or HxWx4 RGBA uint8) mapped onto a world rectangle."""

    pixels: np.ndarray
    rect: tuple[float, float, float, float]
    style: Style = Style()

    def __post_init__(self) -> None:
        px = np.asarray(self.pixels)
        if px.dtype != np.uint8 or not (px.ndim == 2 or (px.ndim == 3 and px.shape[2] in (3, 4))) or px.size == 0:
            raise ConfigError(f"image pixels must be a non-empty uint8 HxW, HxWx3 or HxWx4 array, got {px.dtype} {px.shape}")
        object.__setattr__(self, "pixels", px)


Primitive = Union[Polyline, Polygon, Rectangle, Circle, Ellipse, Arc, Bezier, BSpline, Marker, Text, Image]
PRIMITIVE_TYPES = (Polyline, Polygon, Rectangle, Circle, Ellipse, Arc, Bezier, BSpline, Marker, Text, Image)


@dataclass(eq=False)
class Segment:
    """A named group of primitives with its own 3x3 transform, visibility and pickability (GKS segment)."""

    name: str
    items: list[Primitive] = field(default_factory=list)
    transform: np.ndarray = field(default_factory=lambda: np.eye(3))
    visible: bool = True
    pickable: bool = True

    def add(self, item: Primitive) -> Primitive:
        """Append a primitive to the segment and return it."""
        if not isinstance(item, PRIMITIVE_TYPES):
            raise ConfigError(f"a segment holds primitives, not {type(item).__name__}")
        self.items.append(item)
        return item


class Picture:
    """An ordered list of primitives and named segments in world coordinates."""

    def __init__(self, window: tuple[float, float, float, float] | None = None) -> None:
        self.items: list[Primitive | Segment] = []
        self.window = window
        """The world-coordinate window the picture was composed for (None: its bounds)."""

    def add(self, item: Primitive | Segment) -> Primitive | Segment:
        """Append a primitive or segment (segment names are unique) and return it."""
        if isinstance(item, Segment):
            if any(isinstance(i, Segment) and i.name == item.name for i in self.items):
                raise ConfigError(f"a segment named {item.name!r} already exists")
        elif not isinstance(item, PRIMITIVE_TYPES):
            raise ConfigError(f"a picture holds primitives and segments, not {type(item).__name__}")
        self.items.append(item)
        return item

    def segment(self, name: str) -> Segment:
        """Return the segment called ``name`` (KeyError naming the known ones otherwise)."""
        for item in self.items:
            if isinstance(item, Segment) and item.name == name:
                return item
        known = [i.name for i in self.items if isinstance(i, Segment)]
        raise KeyError(f"no segment {name!r}; segments: {', '.join(known) or 'none'}")

    def walk(self) -> Iterator[tuple[Primitive, np.ndarray, Segment | None]]:
        """Yield each visible primitive with the 3x3 transform of its segment (identity outside one)."""
        identity = np.eye(3)
        for item in self.items:
            if isinstance(item, Segment):
                if item.visible:
                    for prim in item.items:
                        yield prim, item.transform, item
            else:
                yield item, identity, None

    def __len__(self) -> int:
        return len(self.items)

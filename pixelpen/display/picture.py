"""Device-independent pictures: primitives in world coordinates with their attributes, and named segments.

Every field is checked when a primitive is made: a wrong type raises ``InvalidArgumentType`` (also a
TypeError), a bad value ``ConfigError`` (also a ValueError). Limits (module attributes, read at call time):

* :data:`MAX_COORDINATE` -- world coordinates, radii and lengths beyond +-1e15 are refused (their
  differences would have no precision left and their extents overflow on the way to a device);
* :data:`MAX_PEN` -- pen numbers; :data:`MAX_TEXT` -- characters of one text primitive;
  :data:`MAX_LENGTH_MM` -- line widths and marker sizes;
  :data:`MAX_PATTERN` -- rows and columns of a fill pattern; :data:`MIN_SPACING_MM` -- hatch spacing;
* :data:`MAX_DEGREE` -- degree of a Bézier curve (a path without ``degree`` is one curve) or B-spline.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike

from pixelpen import geometry as geo
from pixelpen.colour import NAMED_COLOURS as NAMED_COLOURS  # re-exported for importers from before colour.py
from pixelpen.colour import colour_hex as colour_hex
from pixelpen.colour import parse_colour as parse_colour
from pixelpen.errors import ConfigError, InvalidArgumentType, quote_token

FillStyle = Literal["hollow", "solid", "hatch", "crosshatch", "pattern"]
Align = Literal["left", "center", "right"]
VAlign = Literal["bottom", "baseline", "middle", "top"]
MarkerKind = Literal["dot", "plus", "cross", "star", "circle", "square", "diamond"]
ColourLike = str | tuple[int, int, int] | Sequence[int]
"""What a Style's colour may be given as: a CSS name or form (see :mod:`pixelpen.colour`) or (r, g, b)."""

# The classes below store checked, normalised values (an (r, g, b) tuple, read-only float arrays) but accept
# the wider input forms; each declares that wider signature for type checkers under TYPE_CHECKING, while the
# dataclass generates the real __init__.


MAX_COORDINATE = 1e15
"""Largest magnitude of a world coordinate, radius or length."""
MAX_PEN = 65535
"""Largest pen number."""
MAX_TEXT = 10_000
"""Characters of one text primitive (the stroke font lays out about 4,000 a second)."""
MAX_LENGTH_MM = 10_000.0
"""Longest line width or marker size in millimetres."""
MAX_PATTERN = 256
"""Rows and columns of a fill pattern."""
MIN_SPACING_MM = 0.01
"""Smallest hatch spacing in millimetres (a tenth of the finest technical pen; an A4 sheet then holds 30,000 lines)."""
MAX_DEGREE = 16
"""Highest degree of a Bézier curve or B-spline (flattening costs grow with its square; the exact Bézier form of a
B-spline span, through the inverse Bernstein matrix, loses digits fast above it)."""


def _number(value: object, name: str, low: float | None = None, *, above: bool = False) -> float:
    """A finite real number of magnitude <= MAX_COORDINATE (and >= or > ``low``), as float."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidArgumentType(f"{name} must be a number, got {type(value).__name__}")
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not abs(number) <= MAX_COORDINATE:
        raise ConfigError(f"{name} must be a finite number of magnitude <= {MAX_COORDINATE:g}, got {number}")
    if low is not None and (number <= low if above else number < low):
        raise ConfigError(f"{name} must be {'>' if above else '>='} {low:g}, got {number}")
    return number


def _length_mm(value: object, name: str) -> float:
    """A length in millimetres, 0..MAX_LENGTH_MM."""
    length = _number(value, name, 0.0)
    if length > MAX_LENGTH_MM:
        raise ConfigError(f"{name} must be at most {MAX_LENGTH_MM:g} mm, got {length:g}")
    return length


def _pair(value: object, name: str) -> tuple[float, float]:
    """An (x, y) pair of numbers."""
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__") or len(value) != 2:
        raise InvalidArgumentType(f"{name} must be a pair (x, y) of numbers, got {type(value).__name__}")
    return _number(value[0], f"{name}[0]"), _number(value[1], f"{name}[1]")  # type: ignore[index]


def _choice(value: object, name: str, options: tuple[str, ...]) -> str:
    """One of the names in ``options``."""
    if not isinstance(value, str) or value not in options:
        raise ConfigError(f"{name} must be one of {', '.join(options)}, got {quote_token(value)}")
    return value


def _flag(value: object, name: str) -> bool:
    """A boolean."""
    if not isinstance(value, (bool, np.bool_)):
        raise InvalidArgumentType(f"{name} must be true or false, got {type(value).__name__}")
    return bool(value)


def _integer(value: object, name: str, low: int, high: int) -> int:
    """An integer in low..high."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise InvalidArgumentType(f"{name} must be an integer, got {type(value).__name__}")
    if not low <= value <= high:
        raise ConfigError(f"{name} must be in {low}..{high}, got {quote_token(value)}")
    return int(value)


def _set(obj: object, **values: object) -> None:
    """Store checked values on a frozen dataclass."""
    for key, value in values.items():
        object.__setattr__(obj, key, value)


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
        _choice(self.style, "fill style", ("hollow", "solid", "hatch", "crosshatch", "pattern"))
        _set(self, angle=_number(self.angle, "fill angle"), outline=_flag(self.outline, "fill outline"))
        if self.spacing is not None:
            _set(self, spacing=_number(self.spacing, "hatch spacing (mm)", MIN_SPACING_MM))
        if self.pattern is not None:
            _set(self, pattern=_pattern(self.pattern))
        if self.style == "pattern" and not self.pattern:
            raise ConfigError("a 'pattern' fill needs a pattern (rows of 0/1 cells)")


def _pattern(rows: object) -> tuple[tuple[int, ...], ...]:
    """Rows of 0/1 cells, all of one length, at most MAX_PATTERN by MAX_PATTERN."""
    if not isinstance(rows, (list, tuple)) or not all(isinstance(r, (list, tuple)) for r in rows):
        raise InvalidArgumentType(f"a fill pattern must be rows (lists) of 0/1 cells, got {quote_token(rows)}")
    if not rows or len(rows) > MAX_PATTERN or len({len(r) for r in rows}) != 1 or not 0 < len(rows[0]) <= MAX_PATTERN:
        raise ConfigError(f"a fill pattern needs 1..{MAX_PATTERN} rows of one length 1..{MAX_PATTERN}")
    if not all(isinstance(c, (int, np.integer)) and int(c) in (0, 1) for r in rows for c in r):
        raise ConfigError("fill pattern cells must be 0 or 1")
    return tuple(tuple(int(c) for c in r) for r in rows)


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

    if TYPE_CHECKING:
        def __init__(self, colour: ColourLike = ..., pen: int | None = ..., width: float = ...,
                     dash: Sequence[float] | None = ..., fill: Fill | None = ..., layer: str | None = ...) -> None:
            """Typed signature (see the note above ColourLike)."""

    def __post_init__(self) -> None:
        _set(self, colour=parse_colour(self.colour), width=_length_mm(self.width, "line width (mm)"))
        if self.dash is not None:
            if not isinstance(self.dash, (list, tuple, np.ndarray)):
                raise InvalidArgumentType(f"a dash pattern is a sequence of lengths, got {type(self.dash).__name__}")
            dash = tuple(_number(d, f"dash[{i}] (mm)", 0.0) for i, d in enumerate(self.dash))
            if not dash or len(dash) % 2 or sum(dash) <= 0:
                raise ConfigError(
                    f"dash pattern must be an even number of lengths >= 0 with a positive sum, got {dash!r}"[:300]
                )
            _set(self, dash=dash)
        if self.pen is not None:
            _set(self, pen=_integer(self.pen, "pen number", 1, MAX_PEN))
        if self.fill is not None and not isinstance(self.fill, Fill):
            raise InvalidArgumentType(f"fill must be a Fill, got {type(self.fill).__name__}")
        if self.layer is not None and not isinstance(self.layer, str):
            raise InvalidArgumentType(f"layer must be a string, got {type(self.layer).__name__}")


def _points(data: object, name: str, min_count: int = 1) -> np.ndarray:
    if isinstance(data, (str, bytes, dict)):
        raise InvalidArgumentType(f"{name} needs an (N, 2) array of points, got {type(data).__name__}")
    try:
        arr = np.asarray(data, dtype=float)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ConfigError(f"{name} needs an (N, 2) array of numbers: {str(exc)[:200]}") from None
    if arr.ndim != 2 or arr.shape[1] != 2 or len(arr) < min_count:
        raise ConfigError(f"{name} needs an (N, 2) array of points with N >= {min_count}, got shape {arr.shape}")
    if not (np.abs(arr) <= MAX_COORDINATE).all():
        row = int(np.flatnonzero(~(np.abs(arr) <= MAX_COORDINATE).all(axis=1))[0])
        raise ConfigError(f"{name} point {row} is not finite or beyond +-{MAX_COORDINATE:g}: {arr[row].tolist()}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Polyline:
    """An open chain of straight segments through ``points``."""

    points: np.ndarray
    style: Style = Style()

    if TYPE_CHECKING:
        def __init__(self, points: ArrayLike, style: Style = ...) -> None:
            """Typed signature (see the note above ColourLike)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", _points(self.points, "polyline", 1))


@dataclass(frozen=True, eq=False)
class Polygon:
    """A fill area: the first ring is the outline, further rings are holes (even-odd rule)."""

    rings: tuple[np.ndarray, ...]
    style: Style = Style()

    if TYPE_CHECKING:
        def __init__(self, rings: ArrayLike | Sequence[ArrayLike], style: Style = ...) -> None:
            """Typed signature (see the note above ColourLike)."""

    def __post_init__(self) -> None:
        rings = self.rings
        if isinstance(rings, (str, bytes, dict)) or not hasattr(rings, "__len__"):
            raise InvalidArgumentType(
                f"polygon rings must be a sequence of (N, 2) point arrays, got {type(rings).__name__}"
            )
        one_ring = isinstance(rings, np.ndarray) or (len(rings) and np.ndim(rings[0]) == 1)
        given = (rings,) if one_ring else rings
        object.__setattr__(self, "rings", tuple(_points(r, "polygon ring", 3) for r in given))
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

    def __post_init__(self) -> None:
        _set(self, **{key: _number(getattr(self, key), f"rectangle {key}") for key in ("x0", "y0", "x1", "y1")})


@dataclass(frozen=True, eq=False)
class Circle:
    """A circle of radius ``r`` about ``center``."""

    center: tuple[float, float]
    r: float
    style: Style = Style()

    def __post_init__(self) -> None:
        _set(self, center=_pair(self.center, "circle center"), r=_number(self.r, "circle radius", 0.0))


@dataclass(frozen=True, eq=False)
class Ellipse:
    """An ellipse with semi-axes ``rx``, ``ry`` about ``center``, rotated by ``angle`` radians."""

    center: tuple[float, float]
    rx: float
    ry: float
    angle: float = 0.0
    style: Style = Style()

    def __post_init__(self) -> None:
        _set(
            self,
            center=_pair(self.center, "ellipse center"),
            rx=_number(self.rx, "ellipse rx", 0.0),
            ry=_number(self.ry, "ellipse ry", 0.0),
            angle=_number(self.angle, "ellipse angle"),
        )


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

    def __post_init__(self) -> None:
        _set(
            self,
            center=_pair(self.center, "arc center"),
            rx=_number(self.rx, "arc rx", 0.0),
            ry=_number(self.ry, "arc ry", 0.0),
            start=_number(self.start, "arc start"),
            end=_number(self.end, "arc end"),
            angle=_number(self.angle, "arc angle"),
        )
        _choice(self.close, "arc close", ("open", "chord", "pie"))


@dataclass(frozen=True, eq=False)
class Bezier:
    """A Bézier path: one curve of any degree, or consecutive curves of ``degree`` sharing end points."""

    control_points: np.ndarray
    degree: int | None = None
    style: Style = Style()

    if TYPE_CHECKING:
        def __init__(self, control_points: ArrayLike, degree: int | None = ..., style: Style = ...) -> None:
            """Typed signature (see the note above ColourLike)."""

    def __post_init__(self) -> None:
        pts = _points(self.control_points, "Bezier", 2)
        object.__setattr__(self, "control_points", pts)
        degree = _integer(len(pts) - 1 if self.degree is None else self.degree, "Bezier degree", 1, MAX_DEGREE)
        if (len(pts) - 1) % degree:
            raise ConfigError(f"a Bezier path of degree {degree} needs k*{degree}+1 control points, got {len(pts)}")


@dataclass(frozen=True, eq=False)
class BSpline:
    """A B-spline curve of ``degree`` over ``control_points``; ``knots`` None = open uniform (clamped)."""

    control_points: np.ndarray
    degree: int = 3
    knots: tuple[float, ...] | None = None
    style: Style = Style()

    if TYPE_CHECKING:
        def __init__(self, control_points: ArrayLike, degree: int = ..., knots: Sequence[float] | None = ...,
                     style: Style = ...) -> None:
            """Typed signature (see the note above ColourLike)."""

    def __post_init__(self) -> None:
        pts = _points(self.control_points, "B-spline", 2)
        object.__setattr__(self, "control_points", pts)
        _integer(self.degree, "B-spline degree", 1, MAX_DEGREE)
        if not 1 <= self.degree < len(pts):
            raise ConfigError(
                f"a B-spline of degree {self.degree} needs more than {self.degree} control points, got {len(pts)}"
            )
        if self.knots is not None:
            if not isinstance(self.knots, (list, tuple, np.ndarray)):
                raise InvalidArgumentType(f"B-spline knots are a sequence of numbers, got {type(self.knots).__name__}")
            knots = tuple(_number(k, f"knots[{i}]") for i, k in enumerate(self.knots))
            if len(knots) != len(pts) + self.degree + 1:
                raise ConfigError(
                    f"a B-spline needs n + degree + 1 = {len(pts) + self.degree + 1} knots, got {len(knots)}"
                )
            if any(b < a for a, b in itertools.pairwise(knots)):
                raise ConfigError("B-spline knots must not decrease")
            object.__setattr__(self, "knots", knots)


@dataclass(frozen=True, eq=False)
class Marker:
    """Markers of one kind centred on ``points``; ``size`` in millimetres."""

    points: np.ndarray
    kind: MarkerKind = "plus"
    size: float = 2.0
    style: Style = Style()

    if TYPE_CHECKING:
        def __init__(self, points: ArrayLike, kind: MarkerKind = ..., size: float = ..., style: Style = ...) -> None:
            """Typed signature (see the note above ColourLike)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", _points(self.points, "marker", 1))
        _choice(self.kind, "marker kind", ("dot", "plus", "cross", "star", "circle", "square", "diamond"))
        _set(self, size=_length_mm(self.size, "marker size (mm)"))


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
        if not isinstance(self.text, str):
            raise InvalidArgumentType(f"text must be a string, got {type(self.text).__name__}")
        if len(self.text) > MAX_TEXT:
            raise ConfigError(f"text of {len(self.text)} characters is longer than {MAX_TEXT}")
        _set(
            self,
            position=_pair(self.position, "text position"),
            height=_number(self.height, "text height", 0.0, above=True),
            angle=_number(self.angle, "text angle"),
            slant=_number(self.slant, "text slant"),
        )
        _choice(self.align, "text align", ("left", "center", "right"))
        _choice(self.valign, "text valign", ("bottom", "baseline", "middle", "top"))


@dataclass(frozen=True, eq=False)
class Image:
    """A raster image (HxW grey, HxWx3 RGB or HxWx4 RGBA uint8) mapped onto a world rectangle."""

    pixels: np.ndarray
    rect: tuple[float, float, float, float]
    style: Style = Style()

    def __post_init__(self) -> None:
        px = np.asarray(self.pixels)
        if px.dtype != np.uint8 or not (px.ndim == 2 or (px.ndim == 3 and px.shape[2] in (3, 4))) or px.size == 0:
            raise ConfigError(
                f"image pixels must be a non-empty uint8 HxW, HxWx3 or HxWx4 array, got {px.dtype} {px.shape}"
            )
        if isinstance(self.rect, (str, bytes, dict)) or not hasattr(self.rect, "__len__") or len(self.rect) != 4:
            raise InvalidArgumentType(f"image rect must be (x0, y0, x1, y1), got {type(self.rect).__name__}")
        _set(self, pixels=px, rect=tuple(_number(v, f"image rect[{i}]") for i, v in enumerate(self.rect)))


Primitive = Polyline | Polygon | Rectangle | Circle | Ellipse | Arc | Bezier | BSpline | Marker | Text | Image
PRIMITIVE_TYPES = (Polyline, Polygon, Rectangle, Circle, Ellipse, Arc, Bezier, BSpline, Marker, Text, Image)


@dataclass(eq=False)
class Segment:
    """A named group of primitives with its own 3x3 transform, visibility and pickability (GKS segment)."""

    name: str
    items: list[Primitive] = field(default_factory=list)
    transform: np.ndarray = field(default_factory=lambda: np.eye(3))
    visible: bool = True
    pickable: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InvalidArgumentType(f"a segment needs a non-empty string name, got {quote_token(self.name)}")
        self.transform = geo.as_matrix(self.transform, f"segment {self.name!r} transform")
        self.visible, self.pickable = _flag(self.visible, "segment visible"), _flag(self.pickable, "segment pickable")

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
        self.window = None if window is None else geo.as_rect(window, "picture window")
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

"""The 2D viewing pipeline: world -> viewing frame -> normalized [0,1]^2 -> device (Hearn & Baker ch. 6, GKS)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence, Sized
from typing import Any, Literal, cast

import numpy as np

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.geometry.transforms import (
    ArrayLike,
    apply,
    as_number,
    as_pair,
    compose,
    invert,
    rotate,
    scale_factor,
    translate,
)

Rect = tuple[float, float, float, float]
Align = Literal["center", "lower-left"]


def as_rect(rect: object, name: str = "window") -> Rect:
    """Validate a rectangle (xmin, ymin, xmax, ymax) with xmin < xmax and ymin < ymax; return it as floats."""
    if isinstance(rect, (str, bytes)) or not isinstance(rect, Sized) or len(rect) != 4:
        raise InvalidArgument(f"{name} must be a rectangle (xmin, ymin, xmax, ymax), got {rect!r}")
    xmin, ymin, xmax, ymax = (as_number(v, f"{name}[{i}]") for i, v in enumerate(cast("Iterable[object]", rect)))
    if not xmin < xmax:
        raise InvalidArgument(f"{name} is degenerate: xmin must be < xmax, got xmin={xmin}, xmax={xmax}")
    if not ymin < ymax:
        raise InvalidArgument(f"{name} is degenerate: ymin must be < ymax, got ymin={ymin}, ymax={ymax}")
    if not (math.isfinite(xmax - xmin) and math.isfinite(ymax - ymin)):
        raise InvalidArgument(f"{name} is too large: its width or height overflows, got {(xmin, ymin, xmax, ymax)}")
    return (xmin, ymin, xmax, ymax)


def window_to_viewport(window: Sequence[float], viewport: Sequence[float]) -> np.ndarray:
    """3x3 matrix mapping the window rectangle onto the viewport rectangle.

    Hearn & Baker: sx = (xvmax - xvmin) / (xwmax - xwmin), sy likewise, and
    xv = xvmin + (xw - xwmin) sx, yv = yvmin + (yw - ywmin) sy.
    """
    xwmin, ywmin, xwmax, ywmax = as_rect(window, "window")
    xvmin, yvmin, xvmax, yvmax = as_rect(viewport, "viewport")
    sx = (xvmax - xvmin) / (xwmax - xwmin)
    sy = (yvmax - yvmin) / (ywmax - ywmin)
    return np.array([
        [sx, 0.0, xvmin - xwmin * sx],
        [0.0, sy, yvmin - ywmin * sy],
        [0.0, 0.0, 1.0],
    ])


class ViewingPipeline:
    """World -> device mapping of one display: a (possibly rotated) window shown in a viewport of the device.

    * world -> viewing frame: the viewing origin ``window_origin`` (default: the window's centre) moves to
      0 and the axes rotate by -window_angle; the window rectangle is given in world coordinates as it
      lies before that rotation, so with window_angle = 0 it is an ordinary world rectangle.
    * viewing -> normalized: the window maps onto the viewport, a rectangle inside [0, 1]^2. With
      ``preserve_aspect`` the scale is uniform in *device* units and the window's image sits centred
      (``align="center"``) or at the lower-left corner of the viewport.
    * normalized -> device: [0, 1]^2 maps to [0, W] x [0, H]; with ``y_down``, device y = H - y.
    """

    def __init__(
        self,
        window: Sequence[float],
        viewport: Sequence[float] = (0.0, 0.0, 1.0, 1.0),
        *,
        device_size: Sequence[float],
        y_down: bool = False,
        window_angle: float = 0.0,
        window_origin: Sequence[float] | None = None,
        preserve_aspect: bool = True,
        align: Align = "center",
    ) -> None:
        self.window = as_rect(window, "window")
        self.viewport = as_rect(viewport, "viewport")
        if min(self.viewport) < 0.0 or max(self.viewport) > 1.0:
            raise InvalidArgument(f"viewport must lie inside the normalized square [0, 1]^2, got {self.viewport}")
        width, height = as_pair(device_size, "device_size")
        if width <= 0.0 or height <= 0.0:
            raise InvalidArgument(f"device_size must be positive (W, H), got ({width}, {height})")
        self.device_size = (width, height)
        self.y_down = bool(y_down)
        self.window_angle = as_number(window_angle, "window_angle")
        xmin, ymin, xmax, ymax = self.window
        self._origin_arg = None if window_origin is None else as_pair(window_origin, "window_origin")
        centre = ((xmin + xmax) / 2.0, (ymin + ymax) / 2.0)
        self.window_origin = centre if self._origin_arg is None else self._origin_arg
        """The viewing frame's origin in world coordinates (the window's centre unless given)."""
        self.preserve_aspect = bool(preserve_aspect)
        if align not in ("center", "lower-left"):
            raise InvalidArgument(f"align must be 'center' or 'lower-left', got {align!r}")
        self.align: Align = align
        self._build()

    def _build(self) -> None:
        """Compute the matrices from the parameters."""
        ox, oy = self.window_origin
        xmin, ymin, xmax, ymax = self.window
        width, height = self.device_size
        world_to_viewing = compose(rotate(-self.window_angle), translate(-ox, -oy))
        window_v = (xmin - ox, ymin - oy, xmax - ox, ymax - oy)
        effective = self._effective_viewport()
        self.world_to_normalized = compose(window_to_viewport(window_v, effective), world_to_viewing)
        flip = np.array([[width, 0.0, 0.0], [0.0, -height, height], [0.0, 0.0, 1.0]])
        self.normalized_to_device = flip if self.y_down else np.diag([width, height, 1.0])
        self.matrix = compose(self.normalized_to_device, self.world_to_normalized)
        self.inverse = invert(self.matrix)
        corners = apply(self.normalized_to_device, [(effective[0], effective[1]), (effective[2], effective[3])])
        low, high = corners.min(axis=0), corners.max(axis=0)
        self.clip_rect: tuple[float, float, float, float] = (
            float(low[0]), float(low[1]), float(high[0]), float(high[1])
        )
        self.scale = scale_factor(self.matrix)
        for array in (self.world_to_normalized, self.normalized_to_device, self.matrix, self.inverse):
            array.flags.writeable = False
        self._frozen = True

    def __setattr__(self, name: str, value: Any) -> None:
        """Pipelines are immutable once built: use replace(), with_window() or with_viewport() for a changed copy."""
        if getattr(self, "_frozen", False):
            raise AttributeError(f"ViewingPipeline is immutable: cannot set {name!r}; use replace(...) for a copy")
        super().__setattr__(name, value)

    def _effective_viewport(self) -> tuple[float, float, float, float]:
        """The part of the viewport (normalized units) the window maps onto: all of it unless preserve_aspect."""
        if not self.preserve_aspect:
            return self.viewport
        xmin, ymin, xmax, ymax = self.window
        vx0, vy0, vx1, vy1 = self.viewport
        width, height = self.device_size
        s = min((vx1 - vx0) * width / (xmax - xmin), (vy1 - vy0) * height / (ymax - ymin))  # device/world
        used_w, used_h = s * (xmax - xmin) / width, s * (ymax - ymin) / height  # normalized units
        if self.align == "center":
            x0, y0 = vx0 + ((vx1 - vx0) - used_w) / 2.0, vy0 + ((vy1 - vy0) - used_h) / 2.0
        else:
            x0, y0 = vx0, vy0
        return (x0, y0, x0 + used_w, y0 + used_h)

    @property
    def window_corners(self) -> np.ndarray:
        """The window's four corners in world coordinates (counter-clockwise, rotated by window_angle)."""
        xmin, ymin, xmax, ymax = self.window
        corners = np.array([(xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax)])
        return apply(rotate(self.window_angle, self.window_origin), corners)

    def to_device(self, points: ArrayLike) -> np.ndarray:
        """World -> device coordinates for an (N, 2) array or a single point."""
        return apply(self.matrix, points)

    def to_world(self, points: ArrayLike) -> np.ndarray:
        """Device -> world coordinates for an (N, 2) array or a single point (e.g. locator input)."""
        return apply(self.inverse, points)

    def _params(self) -> dict[str, Any]:
        """The constructor arguments that reproduce this pipeline."""
        return {
            "window": self.window, "viewport": self.viewport, "device_size": self.device_size,
            "y_down": self.y_down, "window_angle": self.window_angle, "window_origin": self._origin_arg,
            "preserve_aspect": self.preserve_aspect, "align": self.align,
        }

    def replace(self, **changes: Any) -> ViewingPipeline:
        """A copy with some constructor arguments changed."""
        unknown = set(changes) - set(self._params())
        if unknown:
            raise InvalidArgumentType(f"unknown ViewingPipeline parameter(s): {', '.join(sorted(unknown))}")
        params = self._params()
        params.update(changes)
        return ViewingPipeline(**params)

    def with_window(self, window: Sequence[float], **changes: Any) -> ViewingPipeline:
        """A copy showing another window (window_angle and window_origin may change too)."""
        return self.replace(window=window, **changes)

    def with_viewport(self, viewport: Sequence[float]) -> ViewingPipeline:
        """A copy with another viewport."""
        return self.replace(viewport=viewport)

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickle by constructor arguments."""
        return (_rebuild, (self._params(),))

    def __eq__(self, other: object) -> bool:
        """Pipelines are equal when built from equal parameters."""
        return isinstance(other, ViewingPipeline) and self._params() == other._params()

    def __hash__(self) -> int:
        """Hash of the parameters."""
        return hash(tuple(self._params().values()))

    def __repr__(self) -> str:
        """Constructor-style representation."""
        args = ", ".join(f"{k}={v!r}" for k, v in self._params().items())
        return f"ViewingPipeline({args})"


def _rebuild(params: dict[str, Any]) -> ViewingPipeline:
    """Unpickle helper."""
    return ViewingPipeline(**params)



"""The stroke: the world points of one pen-down sequence, optionally smoothed to a cubic B-spline.

A stroke starts when the pen tip touches (a tablet), a finger touches down, or a stroke button (default the
primary) is pressed on a pointer, and ends — its trigger — when it lifts or the button is released, or when
``max_points`` points were taken (GKS's full stroke buffer).  Positions come from a
:class:`~pixelpen.input.locator.Locator` on the same display; a point is kept when it lies at least
``spacing`` device units from the last one kept (the last position is always kept).

:func:`smooth` fits a B-spline to the points (least squares, the Cox–de Boor basis of
:func:`pixelpen.geometry.bspline_basis` over open uniform knots, chord-length parameters, the two ends
interpolated) with the fewest control points that bring every point within ``tolerance`` world units of the
curve at its parameter (at most :data:`MAX_CONTROL_POINTS`); the result is a drawable
:class:`~pixelpen.display.picture.BSpline`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pixelpen import geometry as geo
from pixelpen.devices.hid.events import Button, InputEvent, Pen, TouchFrame
from pixelpen.display.picture import BSpline, Style
from pixelpen.errors import InvalidArgument
from pixelpen.input.locator import Locator
from pixelpen.input.queue import LogicalDevice, Mode

if TYPE_CHECKING:
    from pixelpen.display.base import Display
    from pixelpen.input.echo import Echo

MAX_POINTS = 100_000
"""The largest stroke buffer allowed."""
MAX_CONTROL_POINTS = 512
"""The most control points a smoothed stroke gets (the fit's matrix is points x control points)."""


@dataclass(frozen=True)
class SmoothStroke:
    """A fitted B-spline: control points, the full knot vector, degree, and each input point's parameter."""

    control_points: np.ndarray
    knots: np.ndarray
    degree: int
    params: np.ndarray
    max_error: float
    """The largest distance of an input point from the curve at its parameter (world units)."""

    def primitive(self, style: Style | None = None) -> BSpline:
        """The spline as a drawable primitive."""
        return BSpline(self.control_points, degree=self.degree, knots=tuple(self.knots.tolist()),
                       style=style or Style())


@dataclass(frozen=True)
class StrokeValue:
    """A stroke measure: world points (N, 2), their event times and pen pressures, and the fit if smoothed."""

    points: np.ndarray
    times: np.ndarray
    pressures: np.ndarray
    spline: SmoothStroke | None = None

    def __len__(self) -> int:
        return len(self.points)


def chord_parameters(points: np.ndarray, span: float) -> np.ndarray:
    """Chord-length parameters of the points scaled to [0, span] (uniform when all points coincide)."""
    steps = np.hypot(*np.diff(points, axis=0).T)
    total = float(steps.sum())
    if total == 0.0:
        return np.linspace(0.0, span, len(points))
    t = np.concatenate([[0.0], np.cumsum(steps)]) * (span / total)
    t[-1] = span
    return t


def fit_bspline(points: np.ndarray, n: int, degree: int = 3) -> SmoothStroke:
    """The least-squares B-spline of ``n`` control points through the end points of ``points`` (M >= n)."""
    knots = geo.open_uniform_knots(n, degree)
    params = chord_parameters(points, float(knots[-1]))
    basis = geo.bspline_basis(knots, degree, params)
    ctrl = np.empty((n, 2))
    ctrl[0], ctrl[-1] = points[0], points[-1]
    if n > 2:
        rhs = points - np.outer(basis[:, 0], points[0]) - np.outer(basis[:, -1], points[-1])
        ctrl[1:-1] = np.linalg.lstsq(basis[:, 1:-1], rhs, rcond=None)[0]
    error = float(np.hypot(*(basis @ ctrl - points).T).max())
    return SmoothStroke(ctrl, knots, degree, params, error)


def smooth(points: np.ndarray, *, tolerance: float, degree: int = 3) -> SmoothStroke:
    """A B-spline within ``tolerance`` of every point with the fewest control points (doubled from degree + 1 until
    it fits, then bisected), or the best of :data:`MAX_CONTROL_POINTS` (at most one per point)."""
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2:
        raise InvalidArgument(f"smoothing needs an (N, 2) array of N >= 2 points, got shape {pts.shape}")
    if not (isinstance(tolerance, (int, float)) and tolerance > 0 and math.isfinite(tolerance)):
        raise InvalidArgument(f"smoothing tolerance must be a positive number, got {tolerance!r}")
    degree = min(degree, len(pts) - 1)
    limit = min(len(pts), MAX_CONTROL_POINTS)
    low, fit = degree, fit_bspline(pts, degree + 1, degree)
    while fit.max_error > tolerance and len(fit.control_points) < limit:  # double until it fits ...
        low, fit = len(fit.control_points), fit_bspline(pts, min(2 * len(fit.control_points), limit), degree)
    high = len(fit.control_points)
    while high - low > 1 and fit.max_error <= tolerance:  # ... then the fewest that fit, by bisection
        middle = fit_bspline(pts, (low + high) // 2, degree)
        if middle.max_error <= tolerance:
            high, fit = len(middle.control_points), middle
        else:
            low = len(middle.control_points)
    return fit


class Stroke(LogicalDevice):
    """Pen-down sequences of world points on ``display``; with ``tolerance``, smoothed to a B-spline."""

    kind = "stroke"

    def __init__(self, display: Display | geo.ViewingPipeline, *, mode: Mode = "request", spacing: float = 1.0,
                 max_points: int = 10_000, tolerance: float | None = None, buttons: Iterable[int] = (1,),
                 gain: float = 1.0, echo: Echo | None = None) -> None:
        super().__init__(mode=mode)
        if isinstance(max_points, bool) or not isinstance(max_points, int) or not 2 <= max_points <= MAX_POINTS:
            raise InvalidArgument(f"max_points must be an integer in 2..{MAX_POINTS}, got {max_points!r}")
        if not (isinstance(spacing, (int, float)) and spacing >= 0):
            raise InvalidArgument(f"stroke spacing must be a number of device units >= 0, got {spacing!r}")
        self.locator = Locator(display, gain=gain, buttons=buttons, echo=echo)
        self.spacing = float(spacing)
        self.max_points = max_points
        self.tolerance = tolerance
        self.down = False
        self._device: list[tuple[float, float]] = []
        self._times: list[float] = []
        self._pressures: list[float] = []
        self._pending: tuple[tuple[float, float], float, float] | None = None
        self._last: StrokeValue | None = None

    def handle(self, event: InputEvent) -> bool:
        """Collect points while down; True when the stroke ends (lifted, released, or the buffer is full)."""
        loc = self.locator
        loc.handle(event)
        if isinstance(event, Pen):
            down = event.in_range and event.touching
            pressure = event.pressure
        elif isinstance(event, TouchFrame):
            down, pressure = loc.pressed, 1.0
        elif isinstance(event, Button) and event.button in loc.buttons:
            down, pressure = event.pressed, 1.0
        else:
            down, pressure = self.down, 1.0
        if down:
            self._add(loc.position, event.time, pressure, force=not self.down)
            self.down = True
            return len(self._device) >= self.max_points
        if self.down:
            self.down = False
            self._finish()
            return bool(self._device)
        return False

    def _add(self, position: tuple[float, float], time: float, pressure: float, *, force: bool) -> None:
        """Keep the point when it lies ``spacing`` from the last kept one (else hold it as the possible last)."""
        if not force and self._device:
            lx, ly = self._device[-1]
            if math.hypot(position[0] - lx, position[1] - ly) < self.spacing:
                self._pending = (position, time, pressure)
                return
        self._pending = None
        self._device.append(position)
        self._times.append(time)
        self._pressures.append(pressure)

    def _finish(self) -> None:
        """The stroke ends: its last position is kept."""
        if self._pending is not None:
            position, time, pressure = self._pending
            self._pending = None
            self._device.append(position)
            self._times.append(time)
            self._pressures.append(pressure)

    def value(self) -> StrokeValue:
        """The stroke so far (or the last one, between strokes), in world coordinates; smoothed if asked."""
        if not self._device and self._last is not None:
            return self._last
        pts = self.locator.pipeline.to_world(np.array(self._device, dtype=float).reshape(-1, 2))
        spline = None
        if self.tolerance is not None and len(pts) >= 2:
            spline = smooth(pts, tolerance=self.tolerance)
        return StrokeValue(pts, np.array(self._times), np.array(self._pressures), spline)

    def triggered(self) -> None:
        """Keep the finished stroke as the measure and start an empty buffer."""
        self._last = self.value()
        self._device, self._times, self._pressures, self._pending = [], [], [], None

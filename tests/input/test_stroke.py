"""Strokes from pen-down sequences, and their smoothing checked against the B-spline definition.

The oracle is the Cox–de Boor recursion written here as the textbook states it (de Boor 1972; Piegl &
Tiller eq. 2.5), point by point in plain Python: N_i,0(t) = 1 on [k_i, k_i+1) (the last non-empty span
closed at the right end), N_i,p(t) = (t - k_i) / (k_i+p - k_i) N_i,p-1(t) + (k_i+p+1 - t) / (k_i+p+1 -
k_i+1) N_i+1,p-1(t), 0/0 taken as 0.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pixelpen import geometry as geo
from pixelpen.devices.hid.events import Button, Motion, Pen
from pixelpen.display.picture import BSpline
from pixelpen.errors import InvalidArgument
from pixelpen.input.stroke import Stroke, smooth
from tests.input.scripted import DEVICE

PIPELINE = geo.ViewingPipeline((0, 0, 100, 100), device_size=(100, 100), y_down=True)


def basis(i: int, p: int, t: float, k: list[float]) -> float:
    if p == 0:
        last = max(j for j in range(len(k) - 1) if k[j] < k[j + 1])
        return 1.0 if (k[i] <= t < k[i + 1]) or (i == last and t == k[i + 1]) else 0.0
    left = 0.0 if k[i + p] == k[i] else (t - k[i]) / (k[i + p] - k[i]) * basis(i, p - 1, t, k)
    right = 0.0 if k[i + p + 1] == k[i + 1] else (k[i + p + 1] - t) / (k[i + p + 1] - k[i + 1]) * basis(
        i + 1, p - 1, t, k)
    return left + right


def curve_point(ctrl: np.ndarray, p: int, k: list[float], t: float) -> np.ndarray:
    return sum(basis(i, p, t, k) * ctrl[i] for i in range(len(ctrl)))  # type: ignore[return-value]


def arc_points(m: int) -> np.ndarray:
    s = np.linspace(0.0, 1.0, m) ** 1.3  # uneven spacing along a half circle with a wobble
    return np.column_stack([40 * np.cos(np.pi * s), 25 * np.sin(np.pi * s) + 3 * np.sin(9 * s)])


def test_smoothed_curve_interpolates_the_ends_and_is_the_least_squares_fit() -> None:
    points = arc_points(60)
    fit = smooth(points, tolerance=0.2)
    knots = fit.knots.tolist()
    p = fit.degree
    assert p == 3 and knots[:4] == [0.0] * 4 and knots[-4:] == [knots[-1]] * 4  # clamped, open uniform
    assert np.allclose(curve_point(fit.control_points, p, knots, fit.params[0]), points[0])
    assert np.allclose(curve_point(fit.control_points, p, knots, fit.params[-1]), points[-1])
    n = len(fit.control_points)
    matrix = np.array([[basis(i, p, t, knots) for i in range(n)] for t in fit.params])
    residual = matrix @ fit.control_points - points
    # least squares over the free (interior) control points: the residual is orthogonal to their basis functions
    assert np.allclose(matrix[:, 1:-1].T @ residual, 0.0, atol=1e-8)
    errors = np.hypot(*residual.T)
    assert errors.max() <= 0.2 and errors.max() == pytest.approx(fit.max_error)


def test_points_on_a_line_are_fitted_exactly_whatever_their_spacing() -> None:
    s = np.array([0.0, 0.1, 0.15, 0.5, 0.55, 0.9, 1.0])
    points = np.column_stack([10 + 30 * s, 5 - 12 * s])
    fit = smooth(points, tolerance=1e-9)
    # chord-length parameters are linear in the position, and a line is in every spline space
    assert len(fit.control_points) == 4 and fit.max_error < 1e-9
    for t, point in zip(fit.params, points, strict=True):
        assert np.allclose(curve_point(fit.control_points, 3, fit.knots.tolist(), t), point)


def test_fit_adds_control_points_until_the_tolerance_holds() -> None:
    points = arc_points(200)
    coarse, fine = smooth(points, tolerance=5.0), smooth(points, tolerance=0.05)
    assert len(coarse.control_points) < len(fine.control_points) <= 200
    assert coarse.max_error <= 5.0 and fine.max_error <= 0.05


def test_the_fit_is_a_drawable_bspline() -> None:
    fit = smooth(arc_points(30), tolerance=0.5)
    prim = fit.primitive()
    assert isinstance(prim, BSpline) and prim.degree == 3
    flat = geo.flatten_bspline(prim.control_points, prim.degree, prim.knots, tolerance=0.01)
    assert np.allclose(flat[0], arc_points(30)[0]) and np.allclose(flat[-1], arc_points(30)[-1])


def test_bad_input_to_smoothing_is_refused() -> None:
    with pytest.raises(InvalidArgument, match="N >= 2"):
        smooth(np.zeros((1, 2)), tolerance=1.0)
    with pytest.raises(InvalidArgument, match="tolerance"):
        smooth(np.zeros((3, 2)), tolerance=0.0)


def pen(t: float, x: float, y: float, touching: bool, pressure: float = 0.5) -> Pen:
    return Pen(t, DEVICE, x_mm=0, y_mm=0, x=x, y=y, touching=touching, pressure=pressure)


def test_a_pen_down_sequence_is_one_stroke_in_world_coordinates() -> None:
    stroke = Stroke(PIPELINE, spacing=2.0)
    events = [pen(0.0, 0.10, 0.5, False), pen(0.1, 0.10, 0.5, True, 0.2), pen(0.2, 0.11, 0.5, True),
              pen(0.3, 0.20, 0.5, True), pen(0.4, 0.30, 0.4, True, 0.9), pen(0.5, 0.31, 0.4, True),
              pen(0.6, 0.31, 0.4, False)]
    ends = [stroke.handle(e) for e in events]
    assert ends == [False] * 6 + [True]
    value = stroke.value()
    # device = (100 x, 100 y) (y down, square), world y = 100 - device y; 0.11 is under 2 units from 0.10: skipped,
    # 0.31 is under 2 from 0.30 but is the last point: kept
    assert np.allclose(value.points, [[10, 50], [20, 50], [30, 60], [31, 60]])
    assert value.times.tolist() == [0.1, 0.3, 0.4, 0.5]
    assert value.pressures.tolist() == [0.2, 0.5, 0.9, 0.5]
    assert value.spline is None
    stroke.triggered()
    assert len(stroke.value()) == 4  # the finished stroke stays the measure until the next begins


def test_a_button_drag_is_a_stroke_and_a_full_buffer_ends_it() -> None:
    stroke = Stroke(PIPELINE, spacing=0.0, max_points=3)
    assert not stroke.handle(Button(0.0, DEVICE, button=1, pressed=True))
    assert not stroke.handle(Motion(0.1, DEVICE, dx=1, dy=0))
    assert stroke.handle(Motion(0.2, DEVICE, dx=1, dy=0))  # three points: the buffer is full
    assert len(stroke.value()) == 3


def test_smoothing_on_request_gives_the_spline() -> None:
    stroke = Stroke(PIPELINE, spacing=0.5, tolerance=0.5)
    stroke.handle(pen(0.0, 0.5, 0.5, True))
    for k in range(1, 40):
        a = k / 39 * math.pi
        stroke.handle(pen(0.01 * k, 0.5 + 0.3 * math.cos(a), 0.5 - 0.3 * math.sin(a), True))
    assert stroke.handle(pen(1.0, 0.2, 0.5, False))
    value = stroke.value()
    assert value.spline is not None and value.spline.max_error <= 0.5
    assert np.allclose(value.spline.control_points[0], value.points[0])

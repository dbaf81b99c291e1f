"""Time on an HP-GL plotter's mechanism: rest-to-rest trapezoid moves per axis, and one timed motion."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["Motion", "axis_distance", "axis_time", "axis_times"]


def axis_time(distance: float, velocity: float, accel: float) -> float:
    """Seconds for a rest-to-rest move of ``distance`` limited by ``velocity`` and ``accel`` (trapezoid)."""
    if distance <= 0.0:
        return 0.0
    if distance * accel <= velocity * velocity:
        return 2.0 * math.sqrt(distance / accel)
    return distance / velocity + velocity / accel


def axis_times(distance: np.ndarray, velocity: float, accel: float) -> np.ndarray:
    """``axis_time`` over an array of distances."""
    d = np.asarray(distance, dtype=np.float64)
    triangle = d * accel <= velocity * velocity
    return np.where(triangle, 2.0 * np.sqrt(np.maximum(d, 0.0) / accel), d / velocity + velocity / accel)


def axis_distance(t: float, distance: float, velocity: float, accel: float) -> float:
    """Distance covered ``t`` seconds into the rest-to-rest move of ``axis_time``."""
    total = axis_time(distance, velocity, accel)
    if t >= total:
        return distance
    if t <= 0.0:
        return 0.0
    ramp = min(velocity / accel, total / 2.0)
    if t <= ramp:
        return 0.5 * accel * t * t
    if t <= total - ramp:
        return 0.5 * accel * ramp * ramp + accel * ramp * (t - ramp)
    rest = total - t
    return distance - 0.5 * accel * rest * rest


class Motion:
    """One thing the mechanism does in time: a move (maybe drawing), a pen lift/drop or a pen change."""

    __slots__ = ("accel", "draw", "duration", "end", "pen", "start", "velocity", "width_mm")

    def __init__(
        self,
        duration: float,
        start: tuple[float, float],
        end: tuple[float, float],
        draw: np.ndarray | None = None,
        pen: int | None = None,
        width_mm: float = 0.3,
        velocity: float = 1.0,
        accel: float = 1.0,
    ) -> None:
        self.duration = duration
        self.start = start
        self.end = end
        self.draw = draw
        self.pen = pen
        self.width_mm = width_mm
        self.velocity = velocity
        self.accel = accel

    def drawn_until(self, elapsed: float) -> np.ndarray | None:
        """The part of ``draw`` inked ``elapsed`` seconds into the move (for a power loss mid-vector)."""
        if self.draw is None or elapsed <= 0.0:
            return None
        (x0, y0), (x1, y1) = self.start, self.end
        dx, dy = x1 - x0, y1 - y0
        span = max(abs(dx), abs(dy))
        if span == 0.0:
            return self.draw
        frac = axis_distance(elapsed, span, self.velocity, self.accel) / span
        d2 = dx * dx + dy * dy
        seg = self.draw
        t0 = ((seg[:, 0] - x0) * dx + (seg[:, 1] - y0) * dy) / d2
        t1 = ((seg[:, 2] - x0) * dx + (seg[:, 3] - y0) * dy) / d2
        keep = np.minimum(t0, t1) <= frac
        seg, t0, t1 = seg[keep].copy(), t0[keep], t1[keep]
        cut = t1 > frac
        if np.any(cut):
            span_t = np.where(t1[cut] - t0[cut] == 0, 1.0, t1[cut] - t0[cut])
            k = ((frac - t0[cut]) / span_t)[:, None]
            seg[cut, 2:4] = seg[cut, 0:2] + k * (seg[cut, 2:4] - seg[cut, 0:2])
        return seg if len(seg) else None

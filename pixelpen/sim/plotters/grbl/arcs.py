"""The chords GRBL's ``mc_arc`` cuts an arc into (motion_control.c), exactly on the circle."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["arc_points"]


def arc_points(
    start: np.ndarray, target: np.ndarray, offset: np.ndarray, radius: float, plane: int,
    clockwise: bool, tolerance: float,
) -> np.ndarray:
    """Chord end points GRBL's ``mc_arc`` feeds the planner for an arc (the last one is the target).

    The segment count is floor(½·|θ|·r / √(tol·(2r − tol))), as in motion_control.c; points lie
    exactly on the circle (vectorised, no small-angle drift).  Returns (N, 3) machine mm, N >= 1.
    """
    a0, a1, al = ((0, 1, 2), (2, 0, 1), (1, 2, 0))[plane]
    c0 = start[a0] + offset[a0]
    c1 = start[a1] + offset[a1]
    r0, r1 = -offset[a0], -offset[a1]
    rt0, rt1 = target[a0] - c0, target[a1] - c1
    travel = math.atan2(r0 * rt1 - r1 * rt0, r0 * rt0 + r1 * rt1)
    eps = 5e-7
    if clockwise:
        if travel >= -eps:
            travel -= 2 * math.pi
    elif travel <= eps:
        travel += 2 * math.pi
    denom = math.sqrt(max(tolerance * (2 * radius - tolerance), 1e-30))
    segments = math.floor(abs(0.5 * travel * radius) / denom) if radius > 0 else 0
    segments = min(segments, 100_000)
    if segments <= 1:
        single: np.ndarray = target.reshape(1, 3).copy()
        return single
    k = np.arange(1, segments)
    theta = math.atan2(r1, r0) + travel * k / segments
    pts = np.empty((segments, 3))
    pts[:-1, a0] = c0 + radius * np.cos(theta)
    pts[:-1, a1] = c1 + radius * np.sin(theta)
    pts[:-1, al] = start[al] + (target[al] - start[al]) * k / segments
    pts[-1] = target
    return pts

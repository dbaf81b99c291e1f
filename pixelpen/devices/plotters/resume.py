"""Where a plot stopped: what a device says after a fault (:class:`DeviceWhere`) and :func:`locate`, which finds
that place among the strokes in doubt (:class:`ResumePoint`).

Strokes from the last confirmed one to the last one sent are in doubt; :func:`locate` finds the device's
position in them (pen-up travel in a straight line to a stroke's first point, pen down along it, pen up at
its end).  A position that matches nothing, or several different amounts of drawing (a closed stroke seen
with the pen up at its start/end, a path that revisits a point), gives no single place: the caller then
refuses to guess (:class:`~pixelpen.errors.PositionUnknown`).  Cost: one pass over the points in doubt.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class DeviceWhere:
    """What a device says after a fault: where the pen is (device units of the sent points) and whether it knows."""

    position: tuple[float, float] | None
    pen_down: bool | None
    settled: bool = True
    """The device will not move any more on bytes of the old connection (drained or aborted)."""
    position_lost: bool = False
    """The device restarted or lost steps: its position says nothing about the job."""
    tolerance: float = 0.5
    """Device units within which the position counts as on a vertex or a segment."""
    detail: str = ""
    """What the device said, for messages."""
    held: bool = False
    """A hold stopped the device mid-instruction: it may rest anywhere on the path, also where the family's
    instructions never end (the pen down on a stroke's first point, or lifted at a stroke's last, where lowering and
    drawing, or lifting and travelling, are one instruction)."""
    reached: tuple[int, int] | None = None
    """(stroke, k): acknowledgements prove the device ran at least to point k of the points given to ``_send_stroke``
    for that stroke (k = 0: the pen-up travel to points[0]); None: no such lower bound."""


@dataclass(frozen=True)
class ResumePoint:
    """Where drawing stopped: strokes < ``stroke`` done, ``stroke`` drawn to vertex ``vertex`` (then to ``at``)."""

    stroke: int
    vertex: int = 0
    at: tuple[float, float] | None = None
    """A point inside segment vertex..vertex+1 where the pen stopped (None: at the vertex)."""

    def remainder(self, points: np.ndarray) -> np.ndarray | None:
        """The stroke's points still to draw (None: the whole stroke)."""
        if self.vertex == 0 and self.at is None:
            return None
        if self.at is None:
            return points[self.vertex:]
        head = np.rint(np.asarray([self.at], float)).astype(points.dtype)
        return np.concatenate([head, points[self.vertex + 1:]])


def locate(
    window: list[tuple[int, np.ndarray]], where: DeviceWhere, before: np.ndarray | None, *,
    lifts: Callable[[int], bool] = lambda stroke: True, down_at_start: bool = True,
) -> list[ResumePoint]:
    """Every distinct place in the strokes ``window`` ((index, sent points) in order) the device may be, earliest first.

    ``before`` is the pen position before the window's first stroke (the end of the stroke before it), or None.
    ``lifts(s)``: the device may rest with the pen lifted at stroke s's end (False where lifting and travelling
    to the next stroke are one instruction); ``down_at_start``: it may rest with the pen down at a stroke's
    first point before drawing (False where lowering and drawing are one instruction).  A pen reported up
    rests only between strokes (the base lifts it nowhere else); a device that lifts by itself inside a
    stroke must report ``pen_down=None``.  A device stopped by a hold (``where.held``) may rest anywhere on the
    path: ``lifts`` and ``down_at_start`` are then taken as true.  ``where.reached`` (stroke, k) drops every place
    before point k of that stroke (in the window's points).
    """
    if where.position is None:
        return []
    q = np.asarray(where.position, float)
    tol = float(where.tolerance)
    found: list[ResumePoint] = []
    up_ok, down_ok = where.pen_down is not True, where.pen_down is not False
    if where.held:  # stopped mid-motion: after a lift that shares its line with the travel, or right after a drop
        lifts, down_at_start = (lambda stroke: True), True
    prev, prev_index = before, None
    for index, pts in window:
        p = np.asarray(pts, float)
        t = near_segment(q, prev, p[0], tol) if prev is not None and up_ok else None
        if t is not None and not (prev_index is not None and not lifts(prev_index)
                                  and np.hypot(*(q - prev)) <= tol and np.hypot(*(q - p[0])) > tol):
            found.append(ResumePoint(index))  # travelling to the stroke's start, or there with the pen still up
        if len(p) == 1:
            if np.hypot(*(q - p[0])) <= tol:
                if up_ok:
                    found.append(ResumePoint(index))
                if down_ok or lifts(index):
                    found.append(ResumePoint(index + 1))
        else:
            for j in range(len(p) - 1):
                t = near_segment(q, p[j], p[j + 1], tol)
                if t is None:
                    continue
                length = float(np.hypot(*(p[j + 1] - p[j])))
                if t * length >= length - tol:
                    last = j + 1 == len(p) - 1
                    if not down_ok and not (last and lifts(index)):
                        continue  # the pen is lifted only between strokes, where the family says it may rest
                    found.append(ResumePoint(index + 1) if last else ResumePoint(index, j + 1))
                elif t * length <= tol:
                    if (j == 0 and not up_ok and not down_at_start) or (j > 0 and not down_ok):
                        continue  # not down on a start before drawing (if the family says so), not up inside
                    found.append(ResumePoint(index, j))
                elif down_ok:
                    found.append(ResumePoint(index, j, (float(q[0]), float(q[1]))))
        prev, prev_index = p[-1], index
    if where.reached is not None:
        floor = where.reached
        found = [r for r in found if (r.stroke, r.vertex) >= floor]
    return _distinct(found, tol)


def near_segment(q: np.ndarray, a: np.ndarray, b: np.ndarray, tol: float) -> float | None:
    """Parameter t in 0..1 of the point of segment a-b nearest q (float64 arrays), if q lies within ``tol`` of it."""
    d = b - a
    dd = float(d @ d)
    t = 0.0 if dd == 0 else min(1.0, max(0.0, float((q - a) @ d) / dd))
    return t if float(np.hypot(*(a + t * d - q))) <= tol else None


def _distinct(points: list[ResumePoint], tol: float) -> list[ResumePoint]:
    """``points`` in order without repeats (places inside one segment within ``2 * tol`` of each other are one)."""
    out: list[ResumePoint] = []
    for r in sorted(points, key=lambda r: (r.stroke, r.vertex, r.at is not None)):
        if not any(_same_place(o, r, 2 * tol) for o in out):
            out.append(r)
    return out


def _same_place(a: ResumePoint, b: ResumePoint, tol: float) -> bool:
    if (a.stroke, a.vertex) != (b.stroke, b.vertex):
        return False
    if a.at is None or b.at is None:
        return a.at is None and b.at is None
    return bool(np.hypot(a.at[0] - b.at[0], a.at[1] - b.at[1]) <= tol)



def in_full_stroke(r: ResumePoint, stroke: int, offset: int, head: ResumePoint) -> ResumePoint:
    """A place found in the sent remainder of ``stroke`` (from ``head``, ``offset`` points short), in the whole one."""
    if r.stroke != stroke:
        return r
    if r.vertex == 0 and r.at is None:
        return head  # nothing of the remainder drawn: where the last resume started
    return ResumePoint(stroke, r.vertex + offset, r.at)


def not_after(r: ResumePoint, top: ResumePoint, length: Callable[[int], int]) -> bool:
    """True unless place ``r`` needs more drawing than place ``top`` (``length(s)``: points of stroke s)."""

    def drawn(p: ResumePoint) -> tuple[int, int]:
        if p.at is not None:
            return p.stroke, p.vertex + 1
        if p.vertex == 0 and p.stroke > 0:
            return p.stroke - 1, length(p.stroke - 1) - 1  # stroke s not begun: stroke s - 1 done
        return p.stroke, p.vertex

    return drawn(r) <= drawn(top)

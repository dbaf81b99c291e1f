"""Motion and time model of a pen plotter: constant-acceleration trapezoid planning, junction-deviation cornering."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pixelpen.errors import ConfigError
from pixelpen.profiles.model import MotionLimits
from pixelpen.vector.displaylist import DisplayList

if TYPE_CHECKING:
    from pixelpen.profiles.model import DeviceProfile

__all__ = ["MotionLimits", "Plan", "PlotTime", "estimate_time", "junction_speeds", "plan"]

_REVERSAL_COS = 0.999999  # GRBL: a junction this close to a full reversal is taken at zero speed


@dataclass
class Plan:
    """Planned blocks, one per non-zero segment: straight moves with entry, cruise (peak) and exit speeds.

    Speeds are mm/s, lengths mm and times s. ``stroke[i]`` is the index of the polyline block ``i`` belongs to;
    every polyline starts and ends at rest. A block accelerates for ``accel_time``, cruises for
    ``cruise_time`` and decelerates for ``decel_time``; ``duration`` is their sum.
    """

    start: np.ndarray
    end: np.ndarray
    length: np.ndarray
    entry: np.ndarray
    cruise: np.ndarray
    exit: np.ndarray
    accel_time: np.ndarray
    cruise_time: np.ndarray
    decel_time: np.ndarray
    duration: np.ndarray
    stroke: np.ndarray

    def __len__(self) -> int:
        return len(self.length)

    @property
    def total_time(self) -> float:
        """Seconds for all blocks."""
        return float(self.duration.sum())


@dataclass(frozen=True)
class PlotTime:
    """Estimated plot time (seconds) split by activity, with the distances (mm) and counts behind it."""

    pen_down: float
    pen_up: float
    pen_lifts: float
    pen_swaps: float
    pen_down_mm: float
    pen_up_mm: float
    lifts: int
    pen_changes: int

    @property
    def total(self) -> float:
        """All seconds: drawing, travelling, lifting and dropping the pen, changing pens."""
        return self.pen_down + self.pen_up + self.pen_lifts + self.pen_swaps


def junction_speeds(unit_in: np.ndarray, unit_out: np.ndarray, limits: MotionLimits) -> np.ndarray:
    """Highest speed (mm/s) through corners from directions ``unit_in`` to ``unit_out`` ((K, 2) unit vectors).

    Junction deviation (GRBL, saxi): v = sqrt(a·r), r = δ·sin(θ/2)/(1 − sin(θ/2)), θ the angle between the
    reversed incoming and the outgoing direction (θ = π straight on, 0 a full reversal); capped at ``speed``.
    """
    u_in, u_out = np.asarray(unit_in, float).reshape(-1, 2), np.asarray(unit_out, float).reshape(-1, 2)
    cos_theta = -np.einsum("ij,ij->i", u_in, u_out)
    sin_half = np.sqrt(np.clip(0.5 * (1.0 - cos_theta), 0.0, 1.0))
    with np.errstate(divide="ignore"):
        v2 = np.where(sin_half < 1.0, limits.accel * limits.cornering * sin_half / (1.0 - sin_half), np.inf)
    v2 = np.minimum(v2, limits.speed * limits.speed)
    v2[cos_theta >= _REVERSAL_COS] = 0.0
    return np.sqrt(v2)


def plan(points: np.ndarray, limits: MotionLimits, offsets: np.ndarray | None = None) -> Plan:
    """Plan polylines (mm) as constant-acceleration blocks, starting and ending each polyline at rest.

    ``points`` is one (P, 2) polyline, or with ``offsets`` many (polyline ``i`` is
    ``points[offsets[i]:offsets[i+1]]``). Repeated points are skipped. Corner speeds follow
    :func:`junction_speeds`; the backward (deceleration) and forward (acceleration) passes are solved at once
    for every vertex of every polyline as running minima over squared speeds, so nothing loops per vertex.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    offs = np.array([0, len(pts)], dtype=np.int64) if offsets is None else np.asarray(offsets, dtype=np.int64)
    if len(offs) < 1 or offs[0] != 0 or offs[-1] != len(pts) or np.any(np.diff(offs) < 0):
        raise ConfigError("plan: offsets must rise from 0 to the number of points")
    if not np.all(np.isfinite(pts)):
        raise ConfigError("plan: points must be finite")
    a, vmax = limits.accel, limits.speed
    # segments between consecutive points of the same polyline, zero-length ones dropped
    owner = np.repeat(np.arange(len(offs) - 1), np.diff(offs))
    same = owner[1:] == owner[:-1] if len(pts) > 1 else np.zeros(0, bool)
    delta = np.diff(pts, axis=0)
    length = np.hypot(delta[:, 0], delta[:, 1])
    keep = same & (length > 0)
    start, end = pts[:-1][keep], pts[1:][keep]
    length, delta, seg_owner = length[keep], delta[keep], owner[:-1][keep]
    m = len(length)
    if m == 0:
        empty = np.zeros(0)
        return Plan(np.zeros((0, 2)), np.zeros((0, 2)), empty, empty, empty, empty, empty, empty, empty, empty,
                    np.zeros(0, np.int64))
    unit = delta / length[:, None]
    # squared speed limit at vertex j (before segment j; vertex m ends the last one): rest where a polyline
    # starts or ends (the vertex between two polylines is both), the junction speed inside a polyline
    first = np.ones(m, bool)
    first[1:] = seg_owner[1:] != seg_owner[:-1]
    w_lim = np.zeros(m + 1)
    inner = np.flatnonzero(~first)
    w_lim[inner] = junction_speeds(unit[inner - 1], unit[inner], limits) ** 2
    s = np.concatenate([[0.0], np.cumsum(2.0 * a * length)])  # s[j] = 2a x distance up to vertex j
    # backward pass w[j] = min(w_lim[j], w[j+1] + 2aL[j]) is a running minimum: min_{k>=j}(w_lim[k] + s[k]) - s[j]
    back = np.minimum.accumulate((w_lim + s)[::-1])[::-1] - s
    # forward pass w[j] = min(back[j], w[j-1] + 2aL[j-1]) likewise: min_{k<=j}(back[k] - s[k]) + s[j]
    w = np.clip(np.minimum.accumulate(back - s) + s, 0.0, vmax * vmax)
    w_entry, w_exit = w[:m], w[1:]
    ve, vx = np.sqrt(w_entry), np.sqrt(w_exit)
    peak = np.minimum(vmax, np.sqrt(np.maximum((2.0 * a * length + w_entry + w_exit) / 2.0, 0.0)))
    peak = np.maximum(peak, np.maximum(ve, vx))
    d_acc = (peak * peak - w_entry) / (2.0 * a)
    d_dec = (peak * peak - w_exit) / (2.0 * a)
    d_cruise = np.maximum(length - d_acc - d_dec, 0.0)
    t_acc = (peak - ve) / a
    t_dec = (peak - vx) / a
    t_cruise = np.divide(d_cruise, peak, out=np.zeros(m), where=peak > 0)
    return Plan(start, end, length, ve, peak, vx, t_acc, t_cruise, t_dec, t_acc + t_cruise + t_dec, seg_owner)


def estimate_time(
    dl: DisplayList,
    profile: DeviceProfile | str,
    home: tuple[float, float] = (0.0, 0.0),
    return_home: bool = True,
) -> PlotTime:
    """Estimate the time to plot ``dl`` in order on a device described by ``profile`` (a profile, name or path).

    Strokes are planned with the pen-down limits; pen-up hops (from ``home``, between strokes and, with
    ``return_home``, back) are rest-to-rest moves with the pen-up limits; every stroke costs one pen drop and
    one lift; every change of pen between consecutive strokes costs the profile's pen change time.
    """
    if isinstance(profile, str):
        from pixelpen.profiles.toml import load_profile

        profile = load_profile(profile)
    scale = float(dl.unit_mm)
    blocks = plan(dl.points * scale, profile.pen_down, dl.offsets)
    if len(dl):
        h = np.asarray(home, dtype=np.float64).reshape(2)
        prev = np.vstack([h[None], dl.ends[:-1]])
        hops = np.hypot(*(dl.starts - prev).T)
        if return_home:
            hops = np.append(hops, np.hypot(*(dl.ends[-1] - h)))
        hops = hops * scale
    else:
        hops = np.zeros(0)
    lifts = len(dl)
    changes = int(np.count_nonzero(dl.pens[1:] != dl.pens[:-1])) if len(dl) else 0
    return PlotTime(
        pen_down=blocks.total_time,
        pen_up=float(profile.pen_up.move_times(hops).sum()),
        pen_lifts=lifts * (profile.pen_lift_s + profile.pen_drop_s),
        pen_swaps=changes * profile.pen_change_s,
        pen_down_mm=float(blocks.length.sum()),
        pen_up_mm=float(hops.sum()),
        lifts=lifts,
        pen_changes=changes,
    )

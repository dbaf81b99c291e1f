"""Plot progress for progress bars: strokes and pen-down millimetres done, elapsed time and an ETA."""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pixelpen.errors import ConfigError, URLError
from pixelpen.profiles.model import DeviceProfile
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.motion import estimate_time

log = logging.getLogger(__name__)


@dataclass
class PlotProgress:
    """Where a plot stands, for progress bars: strokes and pen-down millimetres done, time and ETA."""

    strokes_done: int
    strokes_total: int
    pen_down_mm_done: float
    pen_down_mm_total: float
    elapsed_s: float
    eta_s: float

    @property
    def fraction(self) -> float:
        """Share of the pen-down distance confirmed, 0..1."""
        return self.pen_down_mm_done / self.pen_down_mm_total if self.pen_down_mm_total else 1.0


ProgressCallback = Callable[[PlotProgress], None]


def cumulative_pen_down_mm(dl: DisplayList) -> np.ndarray:
    """Pen-down millimetres drawn once strokes < k are done, for k = 0..len(dl)."""
    seg = np.hypot(*np.diff(dl.points, axis=0).T) if len(dl.points) > 1 else np.zeros(0)
    per_stroke = np.add.reduceat(np.append(seg, 0.0), dl.offsets[:-1]) - np.where(
        dl.offsets[1:] < len(dl.points), np.append(seg, 0.0)[np.minimum(dl.offsets[1:] - 1, len(seg))], 0.0
    ) if len(dl) else np.zeros(0)
    return np.concatenate([[0.0], np.cumsum(per_stroke)]) * dl.unit_mm


def estimate_seconds(dl: DisplayList, profile: DeviceProfile) -> float:
    """Estimated plot time of ``dl``, or 0 when the profile has no motion limits to estimate with."""
    try:
        return float(estimate_time(dl, profile).total)
    except (ConfigError, URLError) as exc:
        log.debug("no time estimate for %s: %s", profile.name, exc)
        return 0.0

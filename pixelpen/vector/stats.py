"""Plot statistics of a display list: pen-down and pen-up distance, lifts, pen changes and estimated time, per layer."""

from __future__ import annotations

import json
import logging
from typing import Any

import numpy as np

from ..errors import ConfigError
from .displaylist import DisplayList

log = logging.getLogger(__name__)

DEFAULT_PROFILE = "axidraw_v3"
"""Device profile used for the time estimate when none is given."""


def _resolve_profile(profile: Any) -> Any:
    """The profile object for ``profile``: a profile, a name or path, None for the default, False for none."""
    if profile is False:
        return None
    if profile is not None and not isinstance(profile, str):
        return profile
    try:
        from .profiles import load_profile
    except ImportError:
        if profile is not None:
            raise ConfigError(f"cannot load device profile {profile!r}: pixelpen.vector.profiles is not available") from None
        return None
    if profile is not None:
        return load_profile(profile)
    try:
        return load_profile(DEFAULT_PROFILE)
    except ConfigError:
        log.info("default profile %s not found; no time estimate", DEFAULT_PROFILE)
        return None


def _counts(dl: DisplayList, home: tuple[float, float], return_home: bool) -> dict[str, Any]:
    """Distances (mm) and counts of ``dl`` plotted in order from ``home``."""
    pens = dl.pens
    return {
        "strokes": len(dl),
        "points": len(dl.points),
        "pen_down_mm": dl.pen_down_length() * dl.unit_mm,
        "pen_up_mm": dl.pen_up_length(home, return_home=return_home) * dl.unit_mm,
        "pen_lifts": len(dl),
        "pen_changes": int(np.count_nonzero(pens[1:] != pens[:-1])),
        "pens": sorted({int(p) for p in pens}),
    }


def _time(dl: DisplayList, profile: Any, home: tuple[float, float], return_home: bool) -> dict[str, float] | None:
    if profile is None:
        return None
    from .motion import estimate_time

    t = estimate_time(dl, profile, home=home, return_home=return_home)
    return {
        "total_s": float(t.total),
        "pen_down_s": float(t.pen_down),
        "pen_up_s": float(t.pen_up),
        "pen_lifts_s": float(t.pen_lifts),
        "pen_changes_s": float(getattr(t, "pen_swaps", 0.0)),
    }


def plot_stats(
    dl: DisplayList, profile: Any = None, home: tuple[float, float] = (0.0, 0.0), *, return_home: bool = True
) -> dict[str, Any]:
    """Totals and per-layer figures for plotting ``dl`` from ``home`` (device units), as a JSON-ready dict.

    Distances are in millimetres, pen-up travel from ``home`` through the strokes (and back, with
    ``return_home``); a pen lift is counted per stroke; a pen change wherever consecutive strokes use
    different pens. ``time`` (seconds, or None when no profile is available) comes from
    ``motion.estimate_time`` with ``profile`` (a DeviceProfile, a name or a path; None: ``axidraw_v3`` when
    available; False: no estimate).
    Each layer's figures are for its own strokes plotted alone, in order, from ``home``.
    """
    home = (float(home[0]), float(home[1]))
    prof = _resolve_profile(profile)
    totals = _counts(dl, home, return_home)
    totals["time"] = _time(dl, prof, home, return_home)
    layers = []
    for layer_id in sorted({int(x) for x in dl.layers}):
        sub = dl.select(dl.layers == layer_id)
        entry = {"id": layer_id, "name": dl.layer_names.get(layer_id, str(layer_id)), **_counts(sub, home, return_home)}
        entry["time"] = _time(sub, prof, home, return_home)
        layers.append(entry)
    bounds = dl.bounds()
    return {
        "unit_mm": dl.unit_mm,
        "profile": getattr(prof, "name", None),
        "bounds_mm": None if bounds is None else [b * dl.unit_mm for b in bounds],
        "total": totals,
        "layers": layers,
    }


def _fmt_time(t: dict[str, float] | None) -> str:
    if t is None:
        return "-"
    s = round(t["total_s"])
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"


def format_stats(stats: dict[str, Any]) -> str:
    """A human-readable table of ``plot_stats`` output."""
    rows = [("layer", "strokes", "pen down mm", "pen up mm", "lifts", "pen changes", "time")]
    for entry in stats["layers"] + [dict(stats["total"], name="total")]:
        rows.append((
            str(entry["name"]), str(entry["strokes"]), f"{entry['pen_down_mm']:.1f}", f"{entry['pen_up_mm']:.1f}",
            str(entry["pen_lifts"]), str(entry["pen_changes"]), _fmt_time(entry["time"]),
        ))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = ["  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths))) for r in rows]
    lines.insert(1, "-" * len(lines[0]))
    lines.insert(len(lines) - 1, "-" * len(lines[0]))
    b = stats["bounds_mm"]
    extent = "empty" if b is None else f"{b[2] - b[0]:.1f} x {b[3] - b[1]:.1f} mm at ({b[0]:.1f}, {b[1]:.1f})"
    lines.append(f"extent: {extent}; time estimate: " + (f"profile {stats['profile']}" if stats["profile"] else "none (no profile)"))
    return "\n".join(lines)


def stats_json(stats: dict[str, Any]) -> str:
    """``plot_stats`` output as indented JSON."""
    return json.dumps(stats, indent=2)

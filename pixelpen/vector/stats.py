"""Plot statistics of a display list: pen-down and pen-up distance, lifts, pen changes and estimated time, per layer."""

from __future__ import annotations

import json
import logging
from typing import Any

import numpy as np

from pixelpen.errors import ConfigError
from pixelpen.profiles import load_profile
from pixelpen.vector.dedupe import stroke_lengths
from pixelpen.vector.displaylist import DisplayList

log = logging.getLogger(__name__)

DEFAULT_PROFILE = "axidraw_v3"
"""Device profile used for the time estimate when none is given."""


def _resolve_profile(profile: Any) -> Any:
    """The profile object for ``profile``: a profile, a name or path, None for the default, False for none."""
    if profile is False:
        return None
    if profile is not None and not isinstance(profile, str):
        return profile
    if profile is not None:
        return load_profile(profile)
    try:
        return load_profile(DEFAULT_PROFILE)
    except ConfigError:
        log.info("default profile %s not found; no time estimate", DEFAULT_PROFILE)
        return None


_TIME_KEYS = ("total_s", "pen_down_s", "pen_up_s", "pen_lifts_s", "pen_changes_s")


def _split(dl: DisplayList, prof: Any, home: tuple[float, float], return_home: bool, layer_ids: list[int]
           ) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """Each layer's share of the plot in order, and what lies between layers; the parts add up to the whole.

    A layer owns its strokes (pen-down, lifts) and the hops and pen changes between two of its strokes that
    follow each other; the hop from home, hops and pen changes between strokes of different layers, and the
    hop back home lie between layers.
    """
    n, k = len(dl), len(layer_ids)
    idx = np.searchsorted(np.asarray(layer_ids), dl.layers)  # layer index of each stroke
    down = stroke_lengths(dl)
    h = np.asarray(home, dtype=np.float64)
    prev = np.vstack([h[None], dl.ends[:-1]]) if n else np.zeros((0, 2))
    hops = np.hypot(*(dl.starts - prev).T) * dl.unit_mm if n else np.zeros(0)
    back = float(np.hypot(*(dl.ends[-1] - h))) * dl.unit_mm if n and return_home else 0.0
    inner = np.zeros(n, bool)  # hop i leads from a stroke of the same layer
    inner[1:] = idx[1:] == idx[:-1]
    change = np.zeros(n, bool)
    change[1:] = dl.pens[1:] != dl.pens[:-1]

    def per_layer(values: np.ndarray, where: np.ndarray | None = None) -> np.ndarray:
        w = values if where is None else np.where(where, values, 0)
        return np.bincount(idx, weights=w, minlength=k) if n else np.zeros(k)

    points = per_layer(np.diff(dl.offsets))
    strokes = per_layer(np.ones(n))
    down_mm = per_layer(down) * dl.unit_mm
    up_mm = per_layer(hops, inner)
    changes = per_layer(change & inner)
    between: dict[str, float | int | dict[str, float] | None] = {
        "pen_up_mm": float(hops[~inner].sum()) + back,
        "pen_changes": int(np.count_nonzero(change & ~inner)),
        "hops": int(np.count_nonzero(~inner)) + (1 if n and return_home else 0),
        "time": None,
    }
    times: list[dict[str, float] | None] = [None] * k
    if prof is not None:
        from pixelpen.vector.motion import plan

        blocks = plan(dl.points * dl.unit_mm, prof.pen_down, dl.offsets)
        down_s = np.bincount(idx[blocks.stroke], weights=blocks.duration, minlength=k) if len(blocks) else np.zeros(k)
        hop_s = prof.pen_up.move_times(hops)
        up_s = per_layer(hop_s, inner)
        lift = prof.pen_lift_s + prof.pen_drop_s
        times = [_time_entry(down_s[j], up_s[j], strokes[j] * lift, changes[j] * prof.pen_change_s) for j in range(k)]
        back_s = float(prof.pen_up.move_times(np.array([back]))[0])
        between["time"] = _time_entry(0.0, float(hop_s[~inner].sum()) + back_s, 0.0,
                                      between["pen_changes"] * prof.pen_change_s)
    layers = [{
        "id": layer_id, "name": dl.layer_names.get(layer_id, str(layer_id)),
        "strokes": int(strokes[j]), "points": int(points[j]), "pen_down_mm": float(down_mm[j]),
        "pen_up_mm": float(up_mm[j]), "pen_lifts": int(strokes[j]), "pen_changes": int(changes[j]),
        "pens": sorted({int(p) for p in dl.pens[idx == j]}), "time": times[j],
    } for j, layer_id in enumerate(layer_ids)]
    return layers, between


def _time_entry(down: float, up: float, lifts: float, changes: float) -> dict[str, float]:
    """A ``time`` entry (seconds) from its parts."""
    return {"total_s": float(down + up + lifts + changes), "pen_down_s": float(down), "pen_up_s": float(up),
            "pen_lifts_s": float(lifts), "pen_changes_s": float(changes)}


def plot_stats(
    dl: DisplayList, profile: Any = None, home: tuple[float, float] = (0.0, 0.0), *, return_home: bool = True
) -> dict[str, Any]:
    """Totals and per-layer figures for plotting ``dl`` in order from ``home`` (device units), as a JSON-ready dict.

    Distances are in millimetres, pen-up travel from ``home`` through the strokes (and back, with
    ``return_home``); a pen lift is counted per stroke; a pen change wherever consecutive strokes use
    different pens. ``time`` (seconds, or None when no profile is available) follows ``motion.estimate_time``
    with ``profile`` (a DeviceProfile, a name or a path; None: ``axidraw_v3`` when available; False: no
    estimate). Each layer's figures are its share of this one plot (its strokes, and the hops and pen changes
    between two of its strokes in a row); ``between_layers`` holds the rest (the hop from home, hops and pen
    changes between strokes of different layers, the hop back home), so layers plus ``between_layers`` make
    the total.
    """
    home = (float(home[0]), float(home[1]))
    prof = _resolve_profile(profile)
    layers, between = _split(dl, prof, home, return_home, sorted({int(x) for x in dl.layers}))
    total = {
        "strokes": len(dl), "points": len(dl.points), "pen_down_mm": sum(e["pen_down_mm"] for e in layers),
        "pen_up_mm": sum(e["pen_up_mm"] for e in layers) + between["pen_up_mm"], "pen_lifts": len(dl),
        "pen_changes": sum(e["pen_changes"] for e in layers) + between["pen_changes"],
        "pens": sorted({int(p) for p in dl.pens}), "time": None,
    }
    if prof is not None:
        total["time"] = {key: sum(e["time"][key] for e in layers) + between["time"][key] for key in _TIME_KEYS}
    bounds = dl.bounds()
    return {
        "unit_mm": dl.unit_mm,
        "profile": getattr(prof, "name", None),
        "bounds_mm": None if bounds is None else [b * dl.unit_mm for b in bounds],
        "total": total,
        "layers": layers,
        "between_layers": between,
        "return_home": return_home,
    }


def _fmt_time(t: dict[str, float] | None) -> str:
    if t is None:
        return "-"
    s = round(t["total_s"])
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"


def format_stats(stats: dict[str, Any]) -> str:
    """A human-readable table of ``plot_stats`` output."""
    rows = [("layer", "strokes", "pen down mm", "pen up mm", "lifts", "pen changes", "time")]
    between = dict(stats["between_layers"], name="between layers", strokes=0, pen_down_mm=0.0, pen_lifts=0)
    for entry in stats["layers"] + [between, dict(stats["total"], name="total")]:
        rows.append((
            str(entry["name"]), str(entry["strokes"]), f"{entry['pen_down_mm']:.1f}", f"{entry['pen_up_mm']:.1f}",
            str(entry["pen_lifts"]), str(entry["pen_changes"]), _fmt_time(entry["time"]),
        ))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = [
        "  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True)))
        for r in rows
    ]
    lines.insert(1, "-" * len(lines[0]))
    lines.insert(len(lines) - 1, "-" * len(lines[0]))
    b = stats["bounds_mm"]
    extent = "empty" if b is None else f"{b[2] - b[0]:.1f} x {b[3] - b[1]:.1f} mm at ({b[0]:.1f}, {b[1]:.1f})"
    t, changes = between["time"], between["pen_changes"]
    lines.append(
        f"between layers: {changes} pen change{'s' * (changes != 1)}, {between['pen_up_mm']:.1f} mm travel"
        + (f", {t['total_s']:.1f} s" if t else "")
        + (
            " (from home, from layer to layer, back home)"
            if stats["return_home"]
            else " (from home, from layer to layer)"
        )
        + "; total = the layers + between layers"
    )
    lines.append(
        f"extent: {extent}; time estimate: "
        + (f"profile {stats['profile']}" if stats["profile"] else "none (no profile)")
    )
    return "\n".join(lines)


def stats_json(stats: dict[str, Any]) -> str:
    """``plot_stats`` output as indented JSON."""
    return json.dumps(stats, indent=2)

"""The plot optimisation pipeline: deduplicate, merge, simplify, drop short strokes, order for least pen-up time."""

from __future__ import annotations

import dataclasses
import time
from typing import TYPE_CHECKING

from pixelpen.vector.dedupe import DuplicateRemoval, deduplicate, filter_min_length, remove_duplicates
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.merge import merge_paths
from pixelpen.vector.order import auto_budget, order_paths
from pixelpen.vector.simplify import simplify as simplify_strokes

if TYPE_CHECKING:
    from pixelpen.profiles.model import DeviceProfile

__all__ = [
    "OptimizeReport",
    "filter_min_length",
    "merge_paths",
    "optimize",
    "order_paths",
    "remove_duplicates",
    "simplify_strokes",
]


@dataclasses.dataclass
class OptimizeReport:
    """What :func:`optimize` did: duplicates removed per (layer, pen), strokes joined or dropped, travel saved.

    Lengths are in device units; ``unit_mm`` converts them. ``optimize`` fills in a report passed to it.
    """

    unit_mm: float = 1.0
    layer_names: dict[int, str] = dataclasses.field(default_factory=dict)
    duplicates: list[DuplicateRemoval] = dataclasses.field(default_factory=list)
    dedupe: bool = True
    strokes_in: int = 0
    strokes_merged: int = 0
    points_simplified: int = 0
    short_strokes_dropped: int = 0
    short_length_dropped: float = 0.0
    strokes_out: int = 0
    pen_up_before: float = 0.0
    pen_up_after: float = 0.0
    order_budget_s: float = 0.0
    """Seconds the ordering was allowed (the adaptive budget unless one was given)."""
    order_s: float = 0.0

    def _layer(self, layer: int) -> str:
        name = self.layer_names.get(layer)
        return f"layer {layer}" if name is None or name == str(layer) else f"layer {layer} {name!r}"

    def lines(self) -> list[str]:
        """Human-readable lines, one per (layer, pen) that lost duplicates, then what else changed the drawing."""
        out = []
        for r in self.duplicates:
            what = []
            if r.strokes_removed:
                what.append(f"{r.strokes_removed} duplicate stroke{'s' * (r.strokes_removed != 1)}")
            if r.strokes_shortened:
                what.append(f"the retraced part of {r.strokes_shortened} stroke{'s' * (r.strokes_shortened != 1)}")
            out.append(f"removed {' and '.join(what)} ({r.length * self.unit_mm:.1f} mm) in "
                       f"{self._layer(r.layer)}, pen {r.pen}")
        if not self.dedupe:
            out.append("duplicate removal off: lines drawn twice in one layer and pen are plotted twice")
        if self.strokes_merged:
            out.append(f"joined {self.strokes_merged} strokes onto others")
        if self.points_simplified:
            out.append(f"simplify dropped {self.points_simplified} points")
        if self.short_strokes_dropped:
            out.append(f"dropped {self.short_strokes_dropped} strokes shorter than the minimum length "
                       f"({self.short_length_dropped * self.unit_mm:.1f} mm of ink)")
        out.append(f"ordered {self.strokes_out} strokes in {self.order_s:.2f} s (budget {self.order_budget_s:.2f} s):"
                   f" pen-up {self.pen_up_before * self.unit_mm:.1f} -> {self.pen_up_after * self.unit_mm:.1f} mm")
        return out


def optimize(
    dl: DisplayList,
    *,
    merge: float | None = None,
    reverse: bool = True,
    simplify: float | None = None,
    dedupe: bool = True,
    min_length: float | None = None,
    home: tuple[float, float] = (0.0, 0.0),
    time_budget: float | None = None,
    profile: DeviceProfile | None = None,
    across_layers: bool = False,
    report: OptimizeReport | None = None,
) -> DisplayList:
    """Prepare ``dl`` for plotting; every length is in the display list's device units.

    In order: :func:`~pixelpen.vector.dedupe.deduplicate` within each layer and pen (if ``dedupe``),
    :func:`merge_paths` of ends within ``merge``, Douglas–Peucker :func:`~pixelpen.vector.simplify.simplify` to
    ``simplify``, :func:`filter_min_length` below ``min_length``, and :func:`order_paths` from ``home`` within
    ``time_budget`` seconds (None: adaptive, see :func:`~pixelpen.vector.order.auto_budget`; by pen-up time under
    ``profile`` when given). Strokes are reversed only if ``reverse``; strokes change layer order only with
    ``across_layers``. A step whose option is None is skipped. ``report``, when given, is filled in.
    """
    rep = OptimizeReport() if report is None else report
    rep.unit_mm, rep.layer_names, rep.dedupe, rep.strokes_in = dl.unit_mm, dict(dl.layer_names), dedupe, len(dl)
    rep.pen_up_before = dl.pen_up_length(home)
    if dedupe:
        dl, rep.duplicates = deduplicate(dl)
    if merge is not None:
        before = len(dl)
        dl = merge_paths(dl, merge, reverse=reverse, across_layers=across_layers)
        rep.strokes_merged = before - len(dl)
    if simplify is not None:
        before = len(dl.points)
        dl = simplify_strokes(dl, simplify)
        rep.points_simplified = before - len(dl.points)
    if min_length is not None:
        before, ink = len(dl), dl.pen_down_length()
        dl = filter_min_length(dl, min_length)
        rep.short_strokes_dropped, rep.short_length_dropped = before - len(dl), ink - dl.pen_down_length()
    t0 = time.perf_counter()
    rep.order_budget_s = auto_budget(len(dl)) if time_budget is None else time_budget
    dl = order_paths(dl, home=home, reverse=reverse, time_budget=time_budget, profile=profile,
                     across_layers=across_layers)
    rep.order_s = time.perf_counter() - t0
    rep.strokes_out, rep.pen_up_after = len(dl), dl.pen_up_length(home)
    return dl

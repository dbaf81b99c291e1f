"""The plot optimisation pipeline: deduplicate, merge, simplify, drop short strokes, order for least pen-up time."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .dedupe import filter_min_length, remove_duplicates
from .displaylist import DisplayList
from .merge import merge_paths
from .order import order_paths
from .simplify import simplify as simplify_strokes

if TYPE_CHECKING:
    from .profiles import DeviceProfile

__all__ = [
    "optimize", "merge_paths", "order_paths", "simplify_strokes", "remove_duplicates", "filter_min_length",
]


def optimize(
    dl: DisplayList,
    *,
    merge: float | None = None,
    reverse: bool = True,
    simplify: float | None = None,
    dedupe: bool = True,
    min_length: float | None = None,
    home: tuple[float, float] = (0.0, 0.0),
    time_budget: float = 1.0,
    profile: "DeviceProfile | None" = None,
    across_layers: bool = False,
) -> DisplayList:
    """Prepare ``dl`` for plotting; every length is in the display list's device units.

    In order: :func:`remove_duplicates` (if ``dedupe``), :func:`merge_paths` of ends within ``merge``,
    Douglas–Peucker :func:`~pixelpen.vector.simplify.simplify` to ``simplify``, :func:`filter_min_length`
    below ``min_length``, and :func:`order_paths` from ``home`` within ``time_budget`` seconds (by pen-up
    time under ``profile`` when given). Strokes are reversed only if ``reverse``; strokes change layer
    order only with ``across_layers``. A step whose option is None is skipped.
    """
    if dedupe:
        dl = remove_duplicates(dl)
    if merge is not None:
        dl = merge_paths(dl, merge, reverse=reverse, across_layers=across_layers)
    if simplify is not None:
        dl = simplify_strokes(dl, simplify)
    if min_length is not None:
        dl = filter_min_length(dl, min_length)
    return order_paths(dl, home=home, reverse=reverse, time_budget=time_budget, profile=profile,
                       across_layers=across_layers)

"""The pick device: the segment or primitive under the locator, hit-tested against what the display drew.

A display keeps pixels or strokes, not what they came from, so a :class:`PickRecord` keeps it: ``draw(item)``
draws on the display and records the item with the viewing pipeline in force (``add(item, pipeline)`` records
what was drawn otherwise).  Each primitive is recorded as the display's own device shapes
(``Display.shapes``: transformed, flattened, clipped to the viewport), so only what is visible can be picked,
where it is visible.  Primitives of a segment that is invisible or not ``pickable`` are not recorded.

A hit is a recorded stroke passing within the aperture (``aperture_mm``, a square's half side in GKS; here a
circle of that radius, in millimetres on the display) of the locator's device position, or a filled area
(even-odd) or image containing it.  The nearest wins; between equals, the one drawn last (on top).  The
measure is a :class:`PickResult` (segment name, the primitive's index in its segment or picture, the
primitive, distance) or None.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pixelpen import geometry as geo
from pixelpen.devices.hid.events import InputEvent
from pixelpen.display.picture import PRIMITIVE_TYPES, Picture, Primitive, Segment
from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.input.locator import Locator
from pixelpen.input.queue import LogicalDevice, Mode

if TYPE_CHECKING:
    from pixelpen.display.base import Display
    from pixelpen.input.echo import Echo


@dataclass(frozen=True)
class PickResult:
    """What was picked: its segment's name (None outside one), its index there, the primitive, the distance."""

    segment: str | None
    index: int
    primitive: Primitive
    distance: float
    """Device units from the locator to the primitive (0 inside an area)."""


@dataclass(frozen=True)
class _Entry:
    segment: str | None
    index: int
    primitive: Primitive


class PickRecord:
    """What was drawn on a display, as device shapes per primitive, for pick to hit-test."""

    def __init__(self, display: Display) -> None:
        self.display = display
        self.clear()

    def clear(self) -> None:
        """Forget everything recorded (the display was cleared)."""
        self.entries: list[_Entry] = []
        self._segments: list[np.ndarray] = []
        self._segment_owner: list[np.ndarray] = []
        self._edges: list[np.ndarray] = []
        self._edge_owner: list[np.ndarray] = []
        self._cache: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None

    def draw(self, item: Picture | Segment | Primitive) -> None:
        """Draw ``item`` on the display and record it."""
        self.display.draw(item)
        self.add(item)

    def add(self, item: Picture | Segment | Primitive, pipeline: geo.ViewingPipeline | None = None) -> None:
        """Record an item drawn under ``pipeline`` (default: the display's current one)."""
        pipeline = pipeline or self.display.pipeline
        if isinstance(item, Picture):
            for index, part in enumerate(item.items):
                self._add_one(part, index, pipeline)
        elif isinstance(item, (Segment, *PRIMITIVE_TYPES)):
            self._add_one(item, 0, pipeline)
        else:
            raise InvalidArgumentType(f"pick records pictures, segments and primitives, not {type(item).__name__}")

    def _add_one(self, item: Segment | Primitive, index: int, pipeline: geo.ViewingPipeline) -> None:
        if isinstance(item, Segment):
            if item.visible and item.pickable:
                for j, prim in enumerate(item.items):
                    self._record(_Entry(item.name, j, prim), Segment(item.name, [prim], item.transform), pipeline)
            return
        self._record(_Entry(None, index, item), item, pipeline)

    def _record(self, entry: _Entry, item: Segment | Primitive, pipeline: geo.ViewingPipeline) -> None:
        """The entry's device shapes as stroke segments and area edges."""
        owner = len(self.entries)
        segments, edges = [], []
        for shape in self.display.shapes(item, pipeline):
            if shape.kind == "stroke":
                segments += [np.hstack([p[:-1], p[1:]]) if len(p) > 1 else np.hstack([p, p]) for p in shape.paths]
            elif shape.kind == "area":
                edges += [np.hstack([r, np.roll(r, -1, axis=0)]) for r in shape.paths]
            elif shape.image is not None:
                x0, y0, x1, y1 = shape.image.rect
                ring = geo.apply(shape.matrix, [(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
                edges.append(np.hstack([ring, np.roll(ring, -1, axis=0)]))
        self.entries.append(entry)
        for parts, store, owners in ((segments, self._segments, self._segment_owner),
                                     (edges, self._edges, self._edge_owner)):
            if parts:
                block = np.concatenate(parts).reshape(-1, 4)
                store.append(block)
                owners.append(np.full(len(block), owner))
        self._cache = None

    def _arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        if self._cache is None:
            def join(blocks: list[np.ndarray], width: int) -> np.ndarray:
                return np.concatenate(blocks) if blocks else np.zeros((0, width))
            self._cache = (join(self._segments, 4), join(self._segment_owner, 1).reshape(-1).astype(int),
                           join(self._edges, 4), join(self._edge_owner, 1).reshape(-1).astype(int))
        return self._cache

    def distances(self, point: tuple[float, float]) -> np.ndarray:
        """Each recorded entry's distance (device units) from ``point``: inf when it has no shape left."""
        segs, seg_owner, edges, edge_owner = self._arrays()
        px, py = float(point[0]), float(point[1])
        best = np.full(len(self.entries), np.inf)
        if len(segs):
            np.minimum.at(best, seg_owner, _segment_distance(segs, px, py))
        if len(edges):
            np.minimum.at(best, edge_owner, _segment_distance(edges, px, py))
            x0, y0, x1, y1 = edges.T
            crosses = ((y0 > py) != (y1 > py)) & (px < x0 + (py - y0) * (x1 - x0) / np.where(y1 == y0, 1.0, y1 - y0))
            inside = np.bincount(edge_owner[crosses], minlength=len(self.entries)) % 2 == 1
            best[inside] = 0.0
        return best

    def pick(self, point: tuple[float, float], aperture: float) -> PickResult | None:
        """The entry nearest ``point`` (device units) within ``aperture``; the last drawn between equals."""
        best = self.distances(point)
        if not len(best):
            return None
        reversed_best = best[::-1]
        i = len(best) - 1 - int(np.argmin(reversed_best))
        if not best[i] <= aperture:
            return None
        entry = self.entries[i]
        return PickResult(entry.segment, entry.index, entry.primitive, float(best[i]))


def _segment_distance(segs: np.ndarray, px: float, py: float) -> np.ndarray:
    """Distance from (px, py) to each segment x0, y0, x1, y1 (vectorised)."""
    x0, y0, x1, y1 = segs.T
    dx, dy = x1 - x0, y1 - y0
    length2 = dx * dx + dy * dy
    t = np.clip(((px - x0) * dx + (py - y0) * dy) / np.where(length2 == 0, 1.0, length2), 0.0, 1.0)
    return np.hypot(x0 + t * dx - px, y0 + t * dy - py)


class Pick(LogicalDevice):
    """The segment or primitive under a locator on the recorded display; the trigger is the locator's."""

    kind = "pick"

    def __init__(self, record: PickRecord, *, aperture_mm: float = 2.0, mode: Mode = "request",
                 buttons: Iterable[int] = (1,), gain: float = 1.0, echo: Echo | None = None) -> None:
        super().__init__(mode=mode)
        if not (isinstance(aperture_mm, (int, float)) and 0 <= aperture_mm < 1e6):
            raise InvalidArgument(f"pick aperture must be a number of millimetres >= 0, got {aperture_mm!r}")
        self.record = record
        self.aperture_mm = float(aperture_mm)
        self.locator = Locator(record.display, gain=gain, buttons=buttons, echo=echo)

    @property
    def aperture(self) -> float:
        """The aperture in device units."""
        return self.aperture_mm / self.locator.unit_mm

    def handle(self, event: InputEvent) -> bool:
        """Move the locator; its trigger is the pick's."""
        return self.locator.handle(event)

    def value(self) -> PickResult | None:
        """What lies under the locator now (None: nothing within the aperture)."""
        return self.record.pick(self.locator.position, self.aperture)

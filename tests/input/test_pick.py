"""Pick on a known scene: a 200 x 100 px display at 1 mm a pixel showing the window (0, 0)-(200, 100), so world
(x, y) is device (x, 100 - y) and distances in world units are pixels."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen import geometry as geo
from pixelpen.devices.hid.events import Button, Motion
from pixelpen.display.kinds import RasterDisplay
from pixelpen.display.picture import Circle, Fill, Picture, Polygon, Polyline, Rectangle, Segment, Style
from pixelpen.display.registry import display_class
from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.input.pick import Pick, PickRecord
from pixelpen.input.queue import InputQueue
from pixelpen.urls import parse_url
from tests.input.scripted import DEVICE, scripted


def display(tmp_path: Path) -> RasterDisplay:
    shown = display_class("png").from_url(parse_url(f"png:{tmp_path / 'scene.png'}?size=200x100&dpi=25.4"))
    shown.window(0, 0, 200, 100)
    return shown  # type: ignore[return-value]


def scene() -> Picture:
    pic = Picture()
    box = Segment("box")
    box.add(Rectangle(20, 20, 60, 60))
    tri = Segment("tri")
    tri.add(Polygon([(100, 10), (180, 10), (140, 90)], Style(fill=Fill("solid"))))
    hidden = Segment("hidden", pickable=False)
    hidden.add(Circle((30, 80), 5))
    moved = Segment("moved", transform=geo.translate(150, 60))
    moved.add(Rectangle(0, 0, 10, 10))
    cross = Segment("cross")
    cross.add(Polyline([(120, 40), (160, 40)]))
    cross.add(Polyline([(120, 45), (190, 45)]))
    for item in (box, tri, Polyline([(0, 95), (200, 95)]), hidden, moved, cross):
        pic.add(item)
    return pic


def device_point(x: float, y: float) -> tuple[float, float]:
    return (x, 100.0 - y)


@pytest.mark.parametrize(("world", "segment", "index", "distance"), [
    ((20, 40), "box", 0, 0.0),  # on the rectangle's left edge
    ((40, 21.5), "box", 0, 1.5),  # 1.5 above its bottom edge, inside the 2 mm aperture
    ((140, 30), "tri", 0, 0.0),  # inside the filled triangle
    ((100, 95), None, 2, 0.0),  # the loose polyline, third item of the picture
    ((155, 70), "moved", 0, 0.0),  # top edge of the rectangle moved by its segment's transform
    ((140, 40), "cross", 0, 0.0),  # on the line over the triangle: the one drawn last wins
    ((185, 45.5), "cross", 1, 0.5),  # the segment's second primitive, outside the triangle
])
def test_hits(tmp_path: Path, world: tuple[float, float], segment: str | None, index: int, distance: float) -> None:
    record = PickRecord(display(tmp_path))
    record.add(scene())
    hit = record.pick(device_point(*world), aperture=2.0)
    assert hit is not None
    assert (hit.segment, hit.index) == (segment, index)
    assert hit.distance == pytest.approx(distance, abs=1e-9)


@pytest.mark.parametrize("world", [(40, 40), (30, 80), (35, 80), (5, 5)])
def test_misses(tmp_path: Path, world: tuple[float, float]) -> None:
    """The hollow box's inside, a segment that is not pickable (centre and outline), empty paper."""
    record = PickRecord(display(tmp_path))
    record.add(scene())
    assert record.pick(device_point(*world), aperture=2.0) is None


def test_only_what_is_visible_in_the_viewport_is_recorded(tmp_path: Path) -> None:
    shown = display(tmp_path)
    # the left half: 100 x 100 px; the window's aspect is kept, so it is 100 x 50 px centred, device y 25..75
    shown.viewport(0.0, 0.0, 0.5, 1.0)
    record = PickRecord(shown)
    pic = Picture()
    pic.add(Polyline([(-200, 50), (400, 50)]))  # world y 50 -> device y 75 - 50 / 2 = 50
    record.add(pic)
    assert record.pick((50.0, 50.0), aperture=0.5) is not None
    assert record.pick((150.0, 50.0), aperture=0.5) is None  # beyond the viewport: clipped away


def test_pick_device_follows_the_locator_and_triggers_on_the_button(tmp_path: Path) -> None:
    shown = display(tmp_path)
    record = PickRecord(shown)
    record.add(scene())
    # the locator starts at the viewport centre, world (100, 50); move to world (140, 30): device +40, +20
    dev = scripted([Motion(0.1, DEVICE, dx=40, dy=20), Button(0.2, DEVICE, button=1, pressed=True)])
    pick = InputQueue([dev]).attach(Pick(record, aperture_mm=2.0))
    hit = pick.request(1.0)
    assert hit is not None and hit.segment == "tri"
    assert pick.aperture == 2.0


def test_record_refuses_what_it_cannot_record(tmp_path: Path) -> None:
    record = PickRecord(display(tmp_path))
    with pytest.raises(InvalidArgumentType):
        record.add("box")  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument):
        Pick(record, aperture_mm=-1)
    assert record.pick((0, 0), 10.0) is None  # nothing recorded yet


def scalar_distance(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    """Point to segment, the textbook way: project, clamp to the segment, measure."""
    (px, py), (ax, ay), (bx, by) = p, a, b
    length2 = (bx - ax) ** 2 + (by - ay) ** 2
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((px - ax) * (bx - ax) + (py - ay) * (by - ay)) / length2))
    return math.hypot(ax + t * (bx - ax) - px, ay + t * (by - ay) - py)


coordinate = st.floats(1, 99, allow_nan=False)


@given(st.lists(st.tuples(coordinate, coordinate), min_size=2, max_size=8), st.tuples(coordinate, coordinate))
def test_vectorised_distance_matches_the_scalar_one(points: list[tuple[float, float]],
                                                    probe: tuple[float, float]) -> None:
    shown = display_class("png").from_url(parse_url("png:unused.png?size=200x100&dpi=25.4"))
    shown.window(0, 0, 200, 100)
    record = PickRecord(shown)  # type: ignore[arg-type]
    pic = Picture()
    pic.add(Polyline(points))
    record.add(pic)
    device = [(x, 100.0 - y) for x, y in points]  # world -> device on this display
    expected = min(scalar_distance(device_point(*probe), a, b) for a, b in itertools.pairwise(device))
    assert record.distances(device_point(*probe))[0] == pytest.approx(expected, abs=1e-9)

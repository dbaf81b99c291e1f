"""Fuzzing the picture file reader: seeded mutations of valid pictures, read and flattened to a device."""

from __future__ import annotations

import numpy as np
import pytest

from pixelpen import geometry as geo
from pixelpen.display.flatten import flatten_picture
from pixelpen.display.pictfile import loads_picture, picture_to_dict
from pixelpen.display.picture import (
    Arc,
    Bezier,
    BSpline,
    Circle,
    Ellipse,
    Fill,
    Image,
    Marker,
    Picture,
    Polygon,
    Polyline,
    Rectangle,
    Segment,
    Style,
    Text,
)
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign

PIPELINE = geo.ViewingPipeline((0.0, 0.0, 100.0, 80.0), device_size=(400.0, 320.0), y_down=True)


def _seeds() -> list[bytes]:
    """Valid pictures using every primitive, style and segment feature."""
    import json

    full = Picture(window=(0, 0, 100, 80))
    full.add(Polyline([[0, 0], [10, 20], [30, 5]], Style(colour="red", width=0.5, dash=(1, 2), layer="a", pen=2)))
    full.add(
        Polygon(
            ([[0, 0], [40, 0], [0, 40]], [[5, 5], [10, 5], [5, 10]]), Style(fill=Fill("hatch", angle=0.5, spacing=2))
        )
    )
    full.add(Rectangle(1, 2, 30, 40, Style(fill=Fill("pattern", pattern=((1, 0), (0, 1)), outline=False))))
    full.add(Circle((50, 50), 20))
    full.add(Ellipse((50, 40), 30, 10, angle=0.2, style=Style(fill=Fill("solid"))))
    full.add(Arc((10, 10), 20, 10, 0.1, 2.0, close="pie", style=Style(pen=3)))
    full.add(Bezier([[0, 0], [10, 10], [20, 0], [30, 10]], degree=3))
    full.add(BSpline([[0, 0], [10, 10], [20, 0], [30, 10]], degree=2, knots=(0, 0, 0, 0.5, 1, 1, 1)))
    full.add(Marker([[10, 10], [20, 20]], kind="circle", size=1.5))
    full.add(Text((30, 40), "Hi", height=5, angle=0.3, align="center"))
    full.add(Image(np.arange(24, dtype=np.uint8).reshape(2, 4, 3), (0, 0, 4, 2)))
    seg = Segment("s", transform=geo.rotate(0.3, (50, 40)))
    seg.add(Circle((0, 0), 10, Style(dash=(2, 1))))
    seg.add(Polyline([[0, 0], [5, 5]]))
    full.add(seg)
    small = Picture()
    small.add(Polyline([[0, 0], [1, 1]]))
    return [json.dumps(picture_to_dict(p)).encode() for p in (full, small)]


TROUBLE: tuple[object, ...] = (
    1e308,
    -1e308,
    1e16,
    0,
    -1,
    1e-300,
    float("inf"),
    float("nan"),
    10**30,
    "x",
    "",
    {},
    [],
    [[1, 2]],
    [[[0]]],
    True,
    None,
    [1e308, -1e308],
    [[1e308, 0], [-1e308, 0]],
)
"""Values put in place of each part of a seed by the structural variants."""


def _paths(node: object, path: tuple = ()) -> list[tuple]:
    """Every path (tuple of keys and indices) to a part of a JSON document."""
    out = [path] if path else []
    if isinstance(node, dict):
        for key, value in node.items():
            out += _paths(value, (*path, key))
    elif isinstance(node, list):
        for index, value in enumerate(node):
            out += _paths(value, (*path, index))
    return out


def _variants(seed: bytes, count: int, rng_seed: int) -> list[bytes]:
    """``count`` valid-JSON variants of a seed, each with one part replaced by a troublesome value."""
    import copy
    import json
    import random

    rng = random.Random(rng_seed)
    doc = json.loads(seed)
    paths = _paths(doc)
    out = []
    for _ in range(count):
        variant = copy.deepcopy(doc)
        *parent_path, last = rng.choice(paths)
        parent = variant
        for key in parent_path:
            parent = parent[key]
        parent[last] = rng.choice(TROUBLE)
        out.append(json.dumps(variant).encode())
    return out


SEEDS = _seeds()


def read_and_draw(data: bytes) -> None:
    """The fuzz target: read a picture file and flatten it for a 400x320 device, clipped and unclipped."""
    picture = loads_picture(data, source="fuzz.json")
    for clip in (True, False):
        for _ in flatten_picture(picture, PIPELINE, tolerance=0.25, unit_mm=0.25, clip=clip):
            pass


def test_the_seeds_are_valid_pictures():
    for seed in SEEDS:
        read_and_draw(seed)


def test_picture_reader_fuzz_quick():
    campaign("pictures", read_and_draw, SEEDS + _variants(SEEDS[0], 150, 1), QUICK_CASES, seed=1).check()


@pytest.mark.slow
def test_picture_reader_fuzz_slow():
    result = campaign("pictures", read_and_draw, SEEDS + _variants(SEEDS[0], 4000, 2), SLOW_CASES, seed=2)
    print(result.summary())
    result.check()

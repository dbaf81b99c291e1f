"""Tests of plot statistics against hand-computed small drawings."""

import json
import math
from dataclasses import dataclass

import numpy as np
import pytest

from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.stats import format_stats, plot_stats, stats_json


def drawing(unit_mm=1.0):
    # stroke 1: (0,0)-(3,4), length 5, pen 1, layer 1
    # stroke 2: (10,0)-(10,2)-(12,2), length 4, pen 2, layer 2
    # stroke 3: (12,5)-(12,9), length 4, pen 2, layer 1
    return DisplayList.from_polylines(
        [np.array([[0, 0], [3, 4]]), np.array([[10, 0], [10, 2], [12, 2]]), np.array([[12, 5], [12, 9]])],
        pens=[1, 2, 2], layers=[1, 2, 1], layer_names={1: "ink", 2: "red"}, unit_mm=unit_mm,
        pen_colours={1: "#000000", 2: "#ff0000"},
    )


@dataclass(frozen=True)
class Limits:
    speed: float
    accel: float


def trapezoid_time(length, limits):
    """Rest-to-rest move with constant acceleration: triangle when too short to reach full speed."""
    if length <= 0:
        return 0.0
    if length >= limits.speed ** 2 / limits.accel:
        return length / limits.speed + limits.speed / limits.accel
    return 2 * math.sqrt(length / limits.accel)


def test_totals_hand_computed():
    s = plot_stats(drawing(unit_mm=0.5), profile=False, return_home=False)
    t = s["total"]
    assert t["strokes"] == 3 and t["points"] == 7 and t["pen_lifts"] == 3
    assert t["pen_down_mm"] == pytest.approx((5 + 4 + 4) * 0.5)
    # home (0,0) -> (0,0): 0; (3,4) -> (10,0): sqrt(65); (12,2) -> (12,5): 3
    assert t["pen_up_mm"] == pytest.approx((math.sqrt(65) + 3) * 0.5)
    assert t["pen_changes"] == 1 and t["pens"] == [1, 2]
    assert s["bounds_mm"] == pytest.approx([0, 0, 6, 4.5])
    assert s["unit_mm"] == 0.5


def test_return_home_adds_the_last_hop():
    s = plot_stats(drawing(), profile=False, return_home=True)
    assert s["total"]["pen_up_mm"] == pytest.approx(math.sqrt(65) + 3 + math.hypot(12, 9))


def test_per_layer_figures_are_each_layers_share_of_the_plot():
    four = DisplayList.concat([drawing(), DisplayList.from_polylines([np.array([[20, 9], [20, 0]])], pens=1, layers=1)])
    s = plot_stats(four, profile=False, home=(1, 1), return_home=True)
    ink, red = s["layers"]
    between, total = s["between_layers"], s["total"]
    assert (ink["id"], ink["name"], red["id"], red["name"]) == (1, "ink", 2, "red")
    assert ink["strokes"] == 3 and ink["pen_down_mm"] == pytest.approx(18) and ink["pens"] == [1, 2]
    # inside "ink": only the hop (12,9) -> (20,9) and its pen change 2 -> 1 follow a stroke of the same layer
    assert ink["pen_up_mm"] == pytest.approx(8) and ink["pen_changes"] == 1
    assert red["strokes"] == 1 and red["pen_up_mm"] == 0 and red["pen_changes"] == 0
    # between: home -> (0,0), (3,4) -> (10,0) with the change 1 -> 2, (12,2) -> (12,5), back home from (20,0)
    assert between["pen_up_mm"] == pytest.approx(math.sqrt(2) + math.sqrt(65) + 3 + math.hypot(19, 1))
    assert between["pen_changes"] == 1 and between["hops"] == 4
    for key in ("strokes", "points", "pen_down_mm", "pen_lifts"):
        assert total[key] == pytest.approx(ink[key] + red[key])
    for key in ("pen_up_mm", "pen_changes"):
        assert total[key] == pytest.approx(ink[key] + red[key] + between[key])
    assert total["pen_up_mm"] == pytest.approx(four.pen_up_length((1, 1), return_home=True))
    text = format_stats(s)
    assert "between layers: 1 pen change," in text and f"{between['pen_up_mm']:.1f} mm travel" in text


def test_layer_times_add_up_to_the_motion_model_total():
    profiles = pytest.importorskip("pixelpen.profiles.model")
    from pixelpen.vector.motion import estimate_time

    prof = profiles.load_profile("axidraw_v3")
    dl = DisplayList.concat([drawing(unit_mm=2.0),
                             DisplayList.from_polylines([np.array([[20, 9], [20, 0]])], pens=1, layers=1)])
    s = plot_stats(dl, prof, home=(1, 1))
    whole = estimate_time(dl, prof, home=(1, 1), return_home=True)
    parts = s["layers"] + [s["between_layers"]]
    assert sum(p["time"]["total_s"] for p in parts) == pytest.approx(whole.total, rel=1e-9)
    assert s["total"]["time"]["total_s"] == pytest.approx(whole.total, rel=1e-9)
    assert s["total"]["time"]["pen_changes_s"] == pytest.approx(whole.pen_swaps)
    assert s["total"]["pen_up_mm"] == pytest.approx(whole.pen_up_mm)
    # the one-stroke layer "red": its pen-down time is its own stroke's, and no hop of its own
    red = s["layers"][1]["time"]
    alone = estimate_time(dl.select(dl.layers == 2), prof)
    assert red["pen_down_s"] == pytest.approx(alone.pen_down) and red["pen_up_s"] == 0


def test_time_from_a_profile_matches_trapezoid_motion():
    profiles = pytest.importorskip("pixelpen.profiles.model")
    prof = profiles.load_profile("axidraw_v3")
    dl = DisplayList.from_polylines([np.array([[10, 0], [10, 40]])], unit_mm=1.0)
    s = plot_stats(dl, prof, return_home=True)
    t = s["total"]["time"]
    assert s["profile"] == prof.name
    assert t["pen_down_s"] == pytest.approx(trapezoid_time(40, prof.pen_down), rel=1e-6)
    hops = trapezoid_time(10, prof.pen_up) + trapezoid_time(math.hypot(10, 40), prof.pen_up)
    assert t["pen_up_s"] == pytest.approx(hops, rel=1e-6)
    assert t["pen_lifts_s"] == pytest.approx(prof.pen_lift_s + prof.pen_drop_s)
    assert t["total_s"] == pytest.approx(t["pen_down_s"] + t["pen_up_s"] + t["pen_lifts_s"] + t["pen_changes_s"])
    by_name = plot_stats(dl, "axidraw_v3")
    assert by_name["total"]["time"] == pytest.approx(t)


def test_default_profile_is_used_when_it_exists():
    profiles = pytest.importorskip("pixelpen.profiles.model")
    if "axidraw_v3" not in profiles.builtin_profiles():
        pytest.skip("no axidraw_v3 profile")
    s = plot_stats(drawing())
    assert s["profile"] == "axidraw_v3" and s["total"]["time"]["total_s"] > 0
    assert all(layer["time"] is not None for layer in s["layers"])


def test_unknown_profile_is_a_config_error():
    pytest.importorskip("pixelpen.profiles.model")
    with pytest.raises(ConfigError):
        plot_stats(drawing(), "no-such-plotter")


def test_empty_list():
    s = plot_stats(DisplayList(), profile=False)
    assert s["total"]["strokes"] == 0 and s["total"]["pen_up_mm"] == 0 and s["layers"] == []
    assert s["bounds_mm"] is None
    assert "empty" in format_stats(s)


def test_human_and_json_formats():
    s = plot_stats(drawing(), profile=False, return_home=False)
    text = format_stats(s)
    lines = text.splitlines()
    assert lines[0].split()[:2] == ["layer", "strokes"]
    assert any(line.split()[:3] == ["ink", "2", "9.0"] for line in lines)
    assert any(line.split()[:4] == ["total", "3", "13.0", f"{math.sqrt(65) + 3:.1f}"] for line in lines)
    assert json.loads(stats_json(s)) == json.loads(json.dumps(s))

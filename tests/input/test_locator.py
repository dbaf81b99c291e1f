"""The locator in world coordinates against the textbook inverse window-to-viewport mapping, worked by hand.

The pipeline: window (10, 20)-(110, 70), viewport (0.1, 0.2)-(0.9, 0.8), a 400 x 300 device with y down,
no aspect preservation.  Device -> normalized: xn = xd / 400, yn = (300 - yd) / 300; normalized -> world
(Hearn & Baker's window-to-viewport solved for the window): xw = xwmin + (xn - xvmin) (xwmax - xwmin) /
(xvmax - xvmin), yw likewise.  The viewport's device rectangle is x 40..360, y 60..240.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen import geometry as geo
from pixelpen.devices.hid.events import Axis, Button, Contact, Motion, Pen, TouchFrame
from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.input.locator import Locator
from tests.input.scripted import DEVICE

WINDOW, VIEWPORT = (10.0, 20.0, 110.0, 70.0), (0.1, 0.2, 0.9, 0.8)
PIPELINE = geo.ViewingPipeline(WINDOW, VIEWPORT, device_size=(400, 300), y_down=True, preserve_aspect=False)


def textbook_world(xd: float, yd: float) -> tuple[float, float]:
    xn, yn = xd / 400.0, (300.0 - yd) / 300.0
    return (10.0 + (xn - 0.1) * 100.0 / 0.8, 20.0 + (yn - 0.2) * 50.0 / 0.6)


def pen(x: float, y: float, *, touching: bool = False, in_range: bool = True, t: float = 0.0) -> Pen:
    return Pen(t, DEVICE, x_mm=0.0, y_mm=0.0, x=x, y=y, touching=touching, in_range=in_range)


def test_starts_at_the_viewport_centre() -> None:
    loc = Locator(PIPELINE).value()
    assert (loc.device_x, loc.device_y) == (200.0, 150.0)
    assert textbook_world(200, 150) == pytest.approx((60.0, 45.0))
    assert (loc.x, loc.y) == pytest.approx(textbook_world(200, 150))


def test_relative_motion_integrates_in_device_units_y_down() -> None:
    loc = Locator(PIPELINE)
    loc.handle(Motion(0.0, DEVICE, dx=10, dy=20))  # 1 count = 1 device unit; HID +y is down
    value = loc.value()
    assert (value.device_x, value.device_y) == (210.0, 170.0)
    assert (value.x, value.y) == pytest.approx((63.125, 39.4444444444))
    assert (value.x, value.y) == pytest.approx(textbook_world(210, 170))


def test_relative_motion_in_mm_uses_the_gain_and_the_unit() -> None:
    loc = Locator(PIPELINE, gain=2.0)  # a bare pipeline: 1 mm per device unit
    loc.handle(Motion(0.0, DEVICE, dx=99, dy=99, dx_mm=2.5, dy_mm=-1.0))
    assert loc.position == (205.0, 148.0)


def test_motion_stays_inside_the_viewport() -> None:
    loc = Locator(PIPELINE)
    loc.handle(Motion(0.0, DEVICE, dx=10_000, dy=-10_000))
    assert loc.position == (360.0, 60.0)
    assert (loc.value().x, loc.value().y) == pytest.approx((110.0, 70.0))  # the window's top-right corner


def test_absolute_pen_maps_its_unit_square_onto_the_viewport() -> None:
    loc = Locator(PIPELINE)
    loc.handle(pen(0.25, 0.5))
    # normalized (0.1 + 0.8 * 0.25, 0.8 - 0.6 * 0.5) = (0.3, 0.5) -> world (10 + 0.2 * 125, 20 + 0.3 * 250 / 3)
    assert (loc.value().x, loc.value().y) == pytest.approx((35.0, 45.0))
    loc.handle(pen(0.0, 0.0))
    assert (loc.value().x, loc.value().y) == pytest.approx((10.0, 70.0))  # top-left of the viewport
    loc.handle(pen(0.9, 0.9, in_range=False))  # out of range: the position stays
    assert (loc.value().x, loc.value().y) == pytest.approx((10.0, 70.0))


def test_with_the_aspect_kept_the_unit_square_is_the_window() -> None:
    # a 224 x 140 window on a 240 x 240 device: it fills 240 x 150 px, centred; the tablet covers the window
    loc = Locator(geo.ViewingPipeline((0, 0, 224, 140), device_size=(240, 240), y_down=True))
    loc.handle(pen(0.0, 0.0))
    assert loc.position == pytest.approx((0.0, 45.0)) and loc.value()[:2] == pytest.approx((0.0, 140.0))
    loc.handle(pen(0.5, 0.75))
    assert loc.value()[:2] == pytest.approx((112.0, 35.0))


def test_touch_and_absolute_axes_move_it_too() -> None:
    loc = Locator(PIPELINE)
    loc.handle(TouchFrame(0.0, DEVICE, contacts=(Contact(3, 0, 0, 1.0, 1.0),)))
    assert (loc.value().x, loc.value().y) == pytest.approx((110.0, 20.0))
    loc.handle(Axis(0.0, DEVICE, axis="x", value=0.5, raw=0))
    loc.handle(Axis(0.0, DEVICE, axis="y", value=0.5, raw=0))
    assert (loc.value().x, loc.value().y) == pytest.approx((60.0, 45.0))


def test_a_stick_is_an_absolute_locator_over_its_axis_range() -> None:
    loc = Locator(PIPELINE, axis_range=(-1.0, 1.0))
    for axis, value in (("x", -1.0), ("y", 0.0)):
        loc.handle(Axis(0.0, DEVICE, axis=axis, value=value, raw=0))
    assert (loc.value().x, loc.value().y) == pytest.approx((10.0, 45.0))  # left edge, half way up
    loc.handle(Axis(0.0, DEVICE, axis="x", value=3.0, raw=0))  # beyond the range: held at the edge
    assert loc.value().x == pytest.approx(110.0)


def test_triggers_are_press_edges_of_the_button_the_tip_or_a_finger() -> None:
    loc = Locator(PIPELINE, buttons=(1, 3))
    assert not loc.handle(Button(0.0, DEVICE, button=2, pressed=True))
    assert loc.handle(Button(0.0, DEVICE, button=3, pressed=True))
    assert not loc.handle(Button(0.0, DEVICE, button=3, pressed=False))
    assert loc.handle(pen(0.5, 0.5, touching=True))
    assert not loc.handle(pen(0.6, 0.5, touching=True))  # still down: no new trigger
    assert not loc.handle(pen(0.6, 0.5, touching=False))
    assert loc.handle(TouchFrame(0.0, DEVICE, contacts=(Contact(0, 0, 0, 0.5, 0.5),)))


@given(st.floats(0, 1), st.floats(0, 1), st.floats(-math.pi, math.pi))
def test_rotated_window_round_trip(u: float, v: float, angle: float) -> None:
    pipeline = PIPELINE.replace(window_angle=angle)
    loc = Locator(pipeline)
    loc.handle(pen(u, v))
    world = loc.value()
    assert np.allclose(pipeline.to_device((world.x, world.y)), loc.position, atol=1e-6)


def test_bad_bindings_and_gains_are_refused() -> None:
    with pytest.raises(InvalidArgumentType, match="Display or a ViewingPipeline"):
        Locator("png:x.png")  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="gain"):
        Locator(PIPELINE, gain=0)

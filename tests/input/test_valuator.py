"""Valuators from axes, pressure and wheels: linear maps worked by hand, clamping, triggers."""

from __future__ import annotations

import pytest

from pixelpen.devices.hid.events import Axis, Button, Pen, Wheel
from pixelpen.errors import InvalidArgument
from pixelpen.input.valuator import Valuator
from tests.input.scripted import DEVICE


def test_a_stick_axis_maps_linearly_onto_the_bounds() -> None:
    v = Valuator(source="slider", low=10.0, high=20.0)
    v.handle(Axis(0.0, DEVICE, axis="slider", value=0.5, raw=0))
    assert v.value() == pytest.approx(17.5)  # (0.5 - -1) / 2 = 0.75 of the way
    v.handle(Axis(0.0, DEVICE, axis="z", value=-1.0, raw=0))  # another axis: ignored
    assert v.value() == pytest.approx(17.5)


def test_a_trigger_axis_range_and_the_pen_pressure() -> None:
    v = Valuator(source="rz", low=0.0, high=100.0, axis_range=(0.0, 1.0))
    v.handle(Axis(0.0, DEVICE, axis="rz", value=0.25, raw=0))
    assert v.value() == pytest.approx(25.0)
    p = Valuator(source="pressure", low=1.0, high=3.0)
    p.handle(Pen(0.0, DEVICE, x_mm=0, y_mm=0, x=0, y=0, pressure=0.5, touching=True))
    assert p.value() == pytest.approx(2.0)


def test_the_wheel_steps_and_clamps() -> None:
    v = Valuator(low=0.0, high=10.0, initial=5.0, step=0.1)
    v.handle(Wheel(0.0, DEVICE, vertical=2.0))
    assert v.value() == pytest.approx(7.0)
    v.handle(Wheel(0.0, DEVICE, vertical=0.125))  # a hi-res eighth of a detent
    assert v.value() == pytest.approx(7.125)
    v.handle(Wheel(0.0, DEVICE, vertical=50.0))
    assert v.value() == 10.0
    h = Valuator(source="wheel-horizontal", step=0.5)
    h.handle(Wheel(0.0, DEVICE, vertical=1.0, horizontal=1.0))
    assert h.value() == 0.5


def test_triggers_a_button_or_every_change() -> None:
    v = Valuator(button=2)
    assert not v.handle(Wheel(0.0, DEVICE, vertical=1.0))
    assert not v.handle(Button(0.0, DEVICE, button=1, pressed=True))
    assert v.handle(Button(0.0, DEVICE, button=2, pressed=True))
    every = Valuator(button=None)
    assert every.handle(Wheel(0.0, DEVICE, vertical=1.0))
    assert not every.handle(Wheel(0.0, DEVICE, vertical=0.0))


def test_bad_bounds_are_refused() -> None:
    with pytest.raises(InvalidArgument, match="low < high"):
        Valuator(low=1.0, high=1.0)
    with pytest.raises(InvalidArgument, match="axis_range"):
        Valuator(axis_range=(1.0, -1.0))

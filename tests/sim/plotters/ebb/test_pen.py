"""The pen-lift servo: where the pen meets the paper, its first move from SC,4, power timeouts, SC settings."""

from __future__ import annotations

import pytest

from pixelpen.sim.plotters.ebb.motion import SERVO_PERIOD
from pixelpen.sim.plotters.ebb.pen import CONTACT_DEFAULT, SERVO_BOOT, SERVO_RANGE, PenServo


def test_contact_default_is_45_percent_of_the_servo_range():
    assert CONTACT_DEFAULT == 17944
    assert SERVO_RANGE[0] < CONTACT_DEFAULT < SERVO_RANGE[1]


def test_an_unpowered_servo_rests_up_and_its_first_move_starts_at_sc4():
    pen = PenServo(SERVO_BOOT, CONTACT_DEFAULT)
    assert not pen.touches(0.0) and pen.contact_change(0.0, 10.0) is None
    pen.slew(1.0, 15000, 100)  # from SC,4 = 22565 down at 100 units per 24 ms frame
    assert pen.track is not None and pen.track.position(1.0) == SERVO_BOOT[0]
    crossing = pen.contact_change(0.0, 10.0)
    assert crossing == pytest.approx(1.0 + (SERVO_BOOT[0] - CONTACT_DEFAULT) * SERVO_PERIOD / 100)
    assert not pen.touches(crossing - 1e-6) and pen.touches(crossing + 1e-6)


def test_sp_and_tp_targets_and_rates():
    pen = PenServo((20000, 15000), CONTACT_DEFAULT)
    pen.configure(11, 700)
    pen.configure(12, 300)
    assert pen.command(False) == (15000, 300) and not pen.commanded_up
    assert pen.command(None) == (20000, 700) and pen.commanded_up  # TP toggles
    pen.configure(10, 50)
    pen.configure(4, 21000)
    assert pen.command(True) == (21000, 50)


def test_servo_power_follows_the_sr_timeout():
    pen = PenServo(SERVO_BOOT, CONTACT_DEFAULT)
    assert not pen.powered(0.0)
    pen.slew(0.0, 15000, 0)
    assert pen.powered(59.9) and not pen.powered(60.0)  # 60 s by default
    pen.set_power(1.0, 0, 1)
    assert pen.powered(1e9)  # SR,0,1: always on
    pen.set_power(2.0, 500, 0)
    assert not pen.powered(2.0)

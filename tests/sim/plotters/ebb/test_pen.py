"""The pen-lift servo: where the pen meets the paper, its boot state and first move, power timeouts, SC settings."""

from __future__ import annotations

import pytest

from pixelpen.sim.plotters.ebb.motion import SERVO_PERIOD
from pixelpen.sim.plotters.ebb.pen import CONTACT_DEFAULT, SERVO_BOOT, SERVO_RANGE, PenServo


def test_contact_default_is_45_percent_of_the_servo_range():
    assert CONTACT_DEFAULT == 17944
    assert SERVO_RANGE[0] < CONTACT_DEFAULT < SERVO_RANGE[1]


def test_an_unpowered_servo_rests_up_and_its_first_move_starts_at_the_boot_sc4():
    pen = PenServo(SERVO_BOOT, CONTACT_DEFAULT)
    assert not pen.touches(0.0) and pen.contact_change(0.0, 10.0) is None
    pen.slew(1.0, 15000, 100)  # from SC,4 = 22565 down at 100 units per 24 ms frame
    assert pen.track is not None and pen.track.position(1.0) == SERVO_BOOT[0]
    crossing = pen.contact_change(0.0, 10.0)
    assert crossing is not None
    assert crossing == pytest.approx(1.0 + (SERVO_BOOT[0] - CONTACT_DEFAULT) * SERVO_PERIOD / 100)
    assert not pen.touches(crossing - 1e-6) and pen.touches(crossing + 1e-6)


def test_power_on_state_is_rcservo2_init():
    # EggBot EBB_firmware/app.X/source/RCServo2.c, RCServo2_Init (lines 214-222, fw 3.0.3): g_servo2_max = 15302
    # (SC,5), g_servo2_min = 22565 (SC,4), g_servo2_rate_up = g_servo2_rate_down = 400, process_SP(PEN_UP, 0),
    # RCServoPowerIO = RCSERVO_POWER_OFF
    pen = PenServo(SERVO_BOOT, CONTACT_DEFAULT)
    assert (pen.up_position, pen.down_position, pen.rate_up, pen.rate_down) == (22565, 15302, 400, 400)
    assert pen.commanded_up and not pen.powered(0.0) and pen.track is None
    assert pen.command(False) == (15302, 400) and pen.command(True) == (22565, 400)


def test_the_first_move_slews_from_the_boot_pulse_whatever_sc4_says_since():
    # the boot pen-up parked the channel at 22565 (gRC2Value); SC,4 only changes g_servo2_min
    pen = PenServo(SERVO_BOOT, CONTACT_DEFAULT)
    pen.configure(4, 20641)  # pyaxidraw's 60 % pen-up
    target, rate = pen.command(True)
    pen.slew(2.0, target, rate)
    assert pen.track is not None and pen.track.position(2.0) == 22565
    assert pen.track.arrival() == pytest.approx(2.0 + (22565 - 20641) * 0.024 / 400)  # 115.44 ms
    assert pen.contact_change(0.0, 10.0) is None  # 22565 -> 20641 stays above the contact (17944)


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

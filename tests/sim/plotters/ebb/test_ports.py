"""The PIC's port pins as EBB_Init leaves them, and the motor enable and microstep pins EM drives."""

from __future__ import annotations

from pixelpen.sim.plotters.ebb.ports import ENABLE_PINS, MS_LEVELS, Ports


def test_boot_state_is_sixteenth_steps_with_both_drivers_off():
    ports = Ports()
    assert ports.microsteps() == 16 and ports.enables() == [False, False]
    assert all(ports.pin(port, pin) == 1 for port, pin in ENABLE_PINS)
    assert ports.read("B") == 0xE5  # RB1 (servo pulse), RB3 (engraver), RB4 (pen) are low outputs; inputs pulled up
    # EBB_Init: RCServoPowerIO (RA3) a low output, MS3 (RA6) a high one; the rest of port A inputs without pull-ups
    assert ports.tris["A"] == 0xB7 and ports.read("A") == 0x40


def test_em_modes_select_the_microsteps_qe_decodes():
    ports = Ports()
    for mode, steps in zip(sorted(MS_LEVELS), (16, 8, 4, 2, 1), strict=True):
        ports.select_microsteps(mode)
        assert ports.microsteps() == steps


def test_enables_are_active_low_and_none_leaves_a_motor_alone():
    ports = Ports()
    ports.set_enables(True, None)
    assert ports.enables() == [True, False]
    ports.set_enables(None, True)
    assert ports.enables() == [True, True]


def test_a_latch_shows_on_its_pin_only_while_the_pin_is_an_output():
    ports = Ports()
    ports.set_latch("D", 4, 1)
    assert ports.pin("D", 4) == 1  # port D boots with pins 2..7 as outputs
    ports.set_direction("D", 4, 1)
    assert ports.pin("D", 4) == 0  # an input on port D has no pull-up
    ports.set_direction("D", 4, 0)
    assert ports.pin("D", 4) == 1

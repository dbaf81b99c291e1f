"""Which GRBL line lost a byte: its one-byte-shorter variants, the explanation of a position, what it drew."""

from __future__ import annotations

import pytest

from pixelpen.devices.plotters.grbl_garble import Garble, SentLeg, explain_position, garbled_variants, words_of


def test_garbled_variants_are_the_valid_lines_one_dropped_byte_leaves():
    """X12.3 -> X1.3 / X2.3 / X123 / X12 ...; a dropped letter or newline leaves no valid line (GRBL rejects it)."""
    targets = {v["X"][0] for v in garbled_variants("G1 X12.3") if "X" in v}
    assert targets == {2.3, 1.3, 123.0, 12.0}
    assert all(set(v) == {"G", "X"} for v in garbled_variants("G1 X12.3"))  # 'G X12.3', '1 X12.3', 'G1 12.3': errors
    assert {v["S"][0] for v in garbled_variants("M3 S500") if "S" in v} == {0.0, 50.0}
    assert words_of("G1 X1 X2") is None and words_of("G1 X") is None and words_of("M3 S50G4 P0.15") is not None


def test_a_position_off_the_path_is_explained_by_the_line_that_lost_a_byte():
    """The first leg whose one-byte variant passes through the reported position; None when nothing explains it."""
    legs = [
        SentLeg(0, None, "G0 X0.000 Y0.000", (0.0, 0.0), (0.0, 0.0), False),
        SentLeg(0, 1, "M3 S50 G4 P0.15 G1 X10.000 Y0.000 F3000", (0.0, 0.0), (10000.0, 0.0), True),
        SentLeg(0, 2, "G1 X10.000 Y12.000", (10000.0, 0.0), (10000.0, 12000.0), True),
        SentLeg(0, 3, "G1 X20.000 Y12.000", (10000.0, 12000.0), (20000.0, 12000.0), True),
    ]
    down = lambda s: s < 275
    # Y12.000 -> Y2.000: to (10, 2) and then on to (20, 12)
    assert explain_position(legs, (15000.0, 7000.0), True, 20, 0.001, down) == Garble(legs[2], (10000.0, 2000.0))
    # S50 -> S5 stays down; S50 -> S0 lifts: the pen up along the drawn legs of the stroke (nothing of them drawn)
    assert explain_position(legs, (10000.0, 6000.0), False, 20, 0.001, down) == Garble(legs[1], None)
    assert explain_position(legs, (50000.0, 90000.0), True, 20, 0.001, down) is None


def test_the_legs_before_the_last_position_seen_on_the_path_ran_as_sent():
    """At (25, 12), 5 mm past the last leg's end: X10.000 -> X10000 on the second leg explains it (a target 10 m
    away, the next leg coming back through it), and so does X20.000 -> X20000 on the third.  The first is taken,
    unless a report saw the pen on the third leg: then the legs before it ran as sent."""
    legs = [
        SentLeg(0, 1, "G1 X10.000 Y0.000", (0.0, 0.0), (10000.0, 0.0), True),
        SentLeg(0, 2, "G1 X10.000 Y12.000", (10000.0, 0.0), (10000.0, 12000.0), True),
        SentLeg(0, 3, "G1 X20.000 Y12.000", (10000.0, 12000.0), (20000.0, 12000.0), True),
    ]
    down = lambda s: s < 275
    assert explain_position(legs, (25000.0, 12000.0), True, 10, 0.001, down) == Garble(legs[1], (10000000.0, 12000.0))
    seen = explain_position(legs, (25000.0, 12000.0), True, 10, 0.001, down, since=(15000.0, 12000.0))
    assert seen == Garble(legs[2], (20000000.0, 12000.0))


LEG = SentLeg(0, 2, "G1 X100.000 Y0.000", (0.0, 0.0), (100000.0, 0.0), True)


@pytest.mark.parametrize(("target", "stop", "inked"), [
    ((50000.0, 20.0), (60000.0, 5000.0), (50000.0, 0.0)),  # a digit short, then on: drawn to its projection
    ((50000.0, 20.0), (20000.0, 8.0), (20000.0, 0.0)),  # held on the way: drawn to where it stopped
    ((200000.0, 0.0), (150000.0, 0.0), (100000.0, 0.0)),  # X100 -> X200: the whole leg, then beyond
    ((50000.0, 5000.0), (10000.0, 1000.0), None),  # it left the leg: stray, the leg again from its start
    ((-5000.0, 0.0), (-5000.0, 0.0), None),  # backwards: nothing of the leg
    ((40.0, 0.0), (40.0, 0.0), None),  # no farther than the tolerance
    (None, (0.0, 0.0), None),  # never ran
])
def test_a_changed_line_has_drawn_its_leg_as_far_as_it_ran_along_it(target, stop, inked):
    """Worked examples on a 100 mm leg along x, tolerance 50 units (0.05 mm)."""
    assert Garble(LEG, target).inked_to(stop, 50.0) == inked


def test_a_changed_travel_draws_nothing_of_its_leg():
    travel = SentLeg(0, None, "G0 X100.000 Y0.000", (0.0, 0.0), (100000.0, 0.0), False)
    assert Garble(travel, (50000.0, 0.0)).inked_to((50000.0, 0.0), 50.0) is None

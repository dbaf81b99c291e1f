"""AxiDraw / EBB simulator on its wire: replies byte for byte as ebb.html gives them, FIFO, motion, paper."""

from __future__ import annotations

import functools
import logging
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError, URLError
from pixelpen.options import describe
from pixelpen.sim.base import Fault, SimulatedDevice, StreamDevice, simulator_factory
from pixelpen.sim.plotters.ebb.board import OPTIONS, EbbSimulator, create
from pixelpen.sim.plotters.ebb.pen import CONTACT_DEFAULT
from tests.sim.fakes import DeviceRig

VERSION = b"EBBv13_and_above EB Firmware Version 3.0.2"


class Rig(DeviceRig):
    """An EBB simulator on a simulated clock."""

    def __init__(self, **options):
        clock = SimulatedClock()
        super().__init__(EbbSimulator(clock, **options), clock)


def test_is_a_wire_device():
    rig = Rig()
    assert isinstance(rig.dev, StreamDevice) and rig.dev.model == "axidraw"
    assert rig.dev.take_output() == b""  # the EBB says nothing until asked


def test_version_in_both_syntaxes():
    rig = Rig()
    assert rig.send("V\r") == VERSION + b"\r\n"
    assert rig.send("v\r\n") == VERSION + b"\r\n"  # case-insensitive; CR LF is one terminator
    assert rig.send("CU,10,1\r") == b"\n"  # the documented non-standard answer when switching
    assert rig.send("V\r") == b"V," + VERSION + b"\n"
    assert rig.send("CU,10,0\r") == b"CUOK\r\n"


def test_legacy_and_future_reply_formats():
    rig = Rig()
    assert rig.send("QG\r") == b"10\r\n"  # pen up (bit 4), idle
    assert rig.send("QP\r") == b"1\n\rOK\r\n"
    assert rig.send("QB\r") == b"0\r\nOK\r\n"
    assert rig.send("QE\r") == b"0,0\r\nOK\r\n"  # both motors off at boot
    assert rig.send("QS\r") == b"0,0\n\rOK\r\n"
    assert rig.send("QM\r") == b"QM,0,0,0,0\n\r"
    assert rig.send("ES\r") == b"0\n\rOK\r\n"
    assert rig.send("QL\r") == b"0\r\nOK\r\n"
    assert rig.send("QR\r") == b"0\n\rOK\r\n"  # servo power off at boot
    assert rig.send("QC\r") == b"0394,0293\r\nOK\r\n"  # 9 V supply: (9 - 0.3) / 9.2 / 3.3 x 1023
    assert rig.send("CS\r") == b"OK\r\n"
    rig.send("CU,10,1\r")
    assert rig.send("QG\r") == b"QG,10\n"
    assert rig.send("QP\r") == b"QP,1\n"
    assert rig.send("QS\r") == b"QS,0,0\n"
    assert rig.send("QM\r") == b"QM,0,0,0,0\n"
    assert rig.send("ES\r") == b"ES,0\n"
    assert rig.send("SM,10,0,0\r") == b"SM\n"
    assert rig.send("CU,1,0\r") == b"CU\n"  # CU,1 has no effect in future syntax


def test_ack_off_in_legacy_syntax():
    rig = Rig()
    assert rig.send("CU,1,0\r") == b"\r\n"
    assert rig.send("SC,4,10000\r") == b"\r\n"


def test_unknown_commands():
    rig = Rig()
    assert rig.send("ZZ\r") == b"!8 Err: Unknown command 'ZZ:5A5A'OK\r\n"  # legacy fw 3: ends OK\r\n
    rig.send("CU,10,1\r")
    assert rig.send("BB\r") == b"BB,!8 Err: Unknown command 'BB:4242'\n"  # the docs' example
    assert rig.send("B\r") == b"B,!8 Err: Unknown command 'B:42'\n"
    old = Rig(firmware="2.8.1")
    assert old.send("ZZ\r") == b"!8 Err: Unknown command 'ZZ:5A5A'\r\n"


def test_the_flush_hash_is_answered_as_unknown_but_logged_only_at_debug(caplog):
    rig = Rig()
    with caplog.at_level(logging.DEBUG, logger="pixelpen.sim.plotters.ebb.board"):
        assert rig.send("#\rV\r") == b"!8 Err: Unknown command '#:23'OK\r\n" + VERSION + b"\r\n"
        assert rig.send("ZZ\r") == b"!8 Err: Unknown command 'ZZ:5A5A'OK\r\n"
    levels = {r.getMessage().rpartition(" ")[2]: r.levelno
              for r in caplog.records if "unknown command" in r.getMessage()}
    assert levels == {"'#'": logging.DEBUG, "'ZZ'": logging.WARNING}


def test_parameter_errors_as_documented():
    rig = Rig(syntax="future")
    assert rig.send("SM,100\r") == b"SM,!4 Err: Missing parameter(s)\n"
    assert rig.send("SM,100A\r") == b"SM,!5 Err: Need comma next, found: 'A'\n"
    assert rig.send("TP,-1\r") == b"TP,!6 Err: Invalid parameter value\n"
    assert rig.send("SM,1,1,1,0,0\r") == b"SM,!7 Err: Extra parameter\n"
    assert rig.send("QG,1\r") == b"QG,!7 Err: Extra parameter\n"
    assert rig.send("SM,0,1,1\r") == b"SM,!6 Err: Invalid parameter value\n"  # duration 0 is rejected
    legacy = Rig()
    assert legacy.send("SM,100\r") == b"!4 Err: Missing parameter(s)OK\r\n"


def test_firmware_gating():
    old = Rig(firmware="2.6.0")
    assert old.send("LM,1,1,1,1,1,1\r") == b"!8 Err: Unknown command 'LM:4C4D'\r\n"  # LM >= 2.7.0
    assert old.send("QG\r") == b"!8 Err: Unknown command 'QG:5147'\r\n"  # QG >= 2.6.2
    assert old.send("SR,1000\r") == b"OK\r\n"  # SR >= 2.6.0
    assert old.send("CU,10,1\r") == b"OK\r\n" and old.dev.syntax == "legacy"  # no future syntax before 3.0
    assert Rig(firmware="2.8.1").send("QG\r") == b"D0\r\n"  # 2.x: bits 7/6 show the pulled-up RB5/RB2
    assert Rig(firmware="3.0.0").send("SP,2\r") == b"!6 Err: Invalid parameter valueOK\r\n"  # SP,2 >= 3.0.1
    with pytest.raises(ConfigError, match="future syntax"):
        EbbSimulator(SimulatedClock(), firmware="2.8.1", syntax="future")


def test_checksums():
    rig = Rig()
    assert rig.send("CU,54,1\r") == b"OK\r\n"
    assert rig.send("SM,1000,1000,1000,153\r") == b"OK\r\n"  # the docs' example checksum
    assert rig.send("V\r") == b"!10 Err: No checksum found but required" + b"OK\r\n"
    assert rig.send(b"V,\xb2\r") == b"!10 Err: No checksum found but required" + b"OK\r\n"  # '\u00b2'.isdigit()
    assert rig.send("CU,54,0,0\r") == b"!9 Err: Checksum incorrect, expected 119OK\r\n"
    assert rig.send("CU,54,0,119\r") == b"OK\r\n"
    assert rig.send("V\r") == VERSION + b"\r\n"


def test_sm_xm_lm_sequence_ends_at_hand_computed_positions():
    rig = Rig()
    rig.send("EM,1,1\rXM,1000,8000,8000\r")  # to (100, 100) mm: A = B = 8000 steps at 80/mm
    rig.until_idle()
    assert rig.send("QS\r") == b"16000,0\n\rOK\r\n"  # motor1 = A + B, motor2 = A - B
    assert np.allclose(rig.dev.position_mm, [100, 100])
    rig.send("SM,1000,250,-766\r")  # A = (250 - 766)/2 = -258, B = (250 + 766)/2 = 508
    rig.until_idle()
    assert rig.send("QS\r") == b"16250,-766\n\rOK\r\n"
    assert np.allclose(rig.dev.position_mm, [100 - 258 / 80, 100 + 508 / 80])
    rig.send("LM,85899346,10,0,17180814,2,0\r")  # 10 and 2 motor steps in 10 ms
    assert rig.dev.next_event_time() == pytest.approx(rig.clock.now() + 0.010)
    rig.until_idle()
    assert rig.send("QS\r") == b"16260,-764\n\rOK\r\n"
    assert rig.dev.step_position == (16260, -764)  # the counters QS reports, read without a command
    assert np.allclose(rig.dev.position_mm, [100 - 258 / 80 + 6 / 80, 100 + 508 / 80 + 4 / 80])
    rig.send("EM,2\r")  # 1/8 stepping clears the counters and halves the resolution
    rig.until_idle()
    before = rig.dev.position_mm
    rig.send("XM,500,40,0\r")
    rig.until_idle()
    assert rig.send("QS\r") == b"40,40\n\rOK\r\n"
    assert np.allclose(rig.dev.position_mm, before + np.array([1.0, 0.0]))  # 40 steps at 40/mm


@pytest.mark.parametrize("command, seconds, steps", [
    ("LM,3865471,60,1732,0,0,0", 0.4068, b"60,0"),  # example 1: 45 -> 250 steps/s
    ("LM,33865471,1000,0,0,0,0", 1000 / (33865471 / 85899.35), b"1000,0"),  # example 2 (Rate ~ 85,899.35 x F)
    ("LM,85899346,10,0,17180814,2,0", 0.010, b"10,2"),  # example 3
    ("LM,85899346,500,0,85899346,250,0", 0.500, b"500,250"),  # example 4: axis 2 is done after 250 ms
    ("LM,17180814,6,0,57266231,20,0", 0.030, b"6,20"),  # example 5
    ("LM,42950000,50,13400,0,0,0", 0.077, b"50,0"),  # example 6: 500 -> 800 steps/s
    ("LM,17179000,75,-687,8592000,75,687", 0.500, b"75,75"),  # example 7: axis 1 decelerates
    ("LM,-17179000,75,687,8592000,-75,687", 0.500, b"-75,-75"),  # 7 backwards: a negative Rate flips Accel too
])
def test_documented_lm_examples(command, seconds, steps):
    rig = Rig()
    assert rig.send(command + "\r") == b"OK\r\n"
    assert rig.dev.next_event_time() == pytest.approx(seconds, rel=0.002)
    rig.until_idle()
    assert rig.send("QS\r") == steps + b"\n\rOK\r\n"


def test_lm_axis_that_finishes_first_stops_accumulating():
    rig = Rig()
    rig.send("LM,85899346,500,0,85899346,250,0\r")  # example 4: axis 2 stops after 250 steps (6250 ticks)
    rig.until_idle()
    assert rig.send("QU,200\r") == b"QU,1000,500\r\nOK\r\n"  # 12500 and 6250 ticks of 85899346, less the steps


def test_lm_is_rejected_only_when_no_axis_can_move():
    rig = Rig()
    assert rig.send("LM,85899346,0,0,0,10,0\r") == b"!6 Err: Invalid parameter valueOK\r\n"  # ebb.html restriction
    assert rig.send("LM,0,10,-5,0,0,0\r") == b"OK\r\n"  # Rate 2 - 5 rolls over to 2^31 - 3 on tick 1
    rig.until_idle()
    assert rig.send("QS\r") == b"10,0\n\rOK\r\n" and rig.clock.now() == pytest.approx(11 * 40e-6)  # ticks 2..11


def test_fifo_depth_blocks_the_parser_and_its_reply():
    rig = Rig()
    assert rig.send("SM,1000,100,100\rSM,1000,100,100\r") == b"OK\r\nOK\r\n"  # executing + queued
    assert rig.send("SM,1000,100,100\rQS\r") == b""  # the third waits in the parser
    rig.dev.receive(b"V\r" * 40)  # 80 more bytes: the board stops reading after one USB packet
    assert not rig.dev.ready_to_receive
    assert rig.run(0.999) == b""
    out = rig.run(0.002)
    assert out.startswith(b"OK\r\n100,100\n\rOK\r\n")  # QS ran when the first move had finished
    assert out.count(VERSION) == 40 and rig.dev.ready_to_receive
    deeper = Rig()
    assert deeper.send("CU,4,3\r") == b"OK\r\n"
    assert deeper.send("SM,1000,1,1\r" * 4) == b"OK\r\n" * 4
    assert deeper.send("QU,3\r") == b"QU,3\r\nOK\r\n"


def test_qg_and_qm_while_moving():
    rig = Rig()
    rig.send("SP,0,200\rXM,1000,800,0\r")
    assert rig.send("QG\r") == b"09\r\n"  # pen down, command executing, one waiting in the FIFO
    rig.run(0.5)
    assert rig.send("QG\r") == b"0E\r\n"  # the move: executing, both motors stepping
    assert rig.send("QM\r") == b"QM,1,1,1,0\n\r"
    rig.run(1.0)
    assert rig.send("QG\r") == b"00\r\n"


def test_lt_hm_and_td_through_the_board():
    rig = Rig()
    rig.send("LT,12500,17179000,-687,8592000,687,3\r")  # ebb.html LT example 3: 500 ms, 75 steps each
    assert rig.dev.next_event_time() == pytest.approx(0.5)
    rig.until_idle()
    assert rig.send("QS\r") == b"75,75\n\rOK\r\n"
    rig.send("HM,1000\r")  # home: straight back to the step origin at 1000 steps/s (+ ~5 ms)
    assert rig.dev.next_event_time() == pytest.approx(0.5 + 0.005 + 0.075)
    rig.until_idle()
    assert rig.send("QS\r") == b"0,0\n\rOK\r\n" and np.allclose(rig.dev.position_mm, [0, 0])
    rig.send("HM,2000,400,-400\r")  # absolute move: motor1 400, motor2 -400 = (0, 5) mm
    rig.until_idle()
    assert np.allclose(rig.dev.position_mm, [0, 5])
    assert rig.send("TD,1000,0,0,0,0,0,0,0,0\r") == b"OK\r\n"  # two T3 moves, one reply


def test_es_aborts_and_reports():
    rig = Rig()
    rig.send("XM,1000,800,0\rXM,1000,800,0\r")
    rig.run(0.25)
    assert rig.send("ES\r") == b"1\n\rOK\r\n"
    assert rig.send("QS\r") == b"200,200\n\rOK\r\n"  # stopped a quarter of the way
    assert rig.dev.next_event_time() is None


def test_pen_strokes_on_the_paper():
    rig = Rig()  # the SP delays cover the slew at the boot rate 400: 22565 -> 17944 in 277 ms, 15302 -> 17944 in 159
    rig.send("EM,1,1\rXM,500,800,800\rSP,0,300\rXM,1000,1600,0\rSP,1,200\rXM,500,0,800\r")
    rig.until_idle()
    strokes = rig.dev.paper.strokes()
    assert len(strokes) == 1
    assert np.allclose(strokes[0][1][[0, -1]], [[10, 10], [30, 10]])  # y down, mm
    assert np.allclose(rig.dev.position_mm, [30, 20])


def test_unpowered_servo_leaves_no_ink_until_a_servo_command():
    rig = Rig()  # SR: servo power (RA3) is off at boot; SC,4/SC,5 only configure it
    rig.send("EM,1,1\rSC,4,20641\rSC,5,15248\rSM,500,800,800\r")
    rig.until_idle()
    assert rig.dev.paper.strokes() == [] and rig.send("QR\r") == b"0\n\rOK\r\n"
    rig.send("SP,1,120\rSM,500,800,0\r")  # the first servo move starts at the boot SC,4 (22565): no touch
    rig.until_idle()
    assert rig.dev.paper.strokes() == [] and rig.send("QR\r") == b"1\n\rOK\r\n"
    rig.send("SP,0,200\rSM,500,800,0\rSP,1,200\r")  # 20641 <-> 17944 at rate 400: 162 ms
    rig.until_idle()
    (_, ink), = rig.dev.paper.strokes()
    assert np.allclose(ink, [[15, 5], [20, 10]])
    rig.send("SP,0,200\r")  # a dot where the pen lands
    rig.until_idle()
    rig.send("R\rSM,500,800,0\r")  # R stops the servo output: the pen rests up again
    rig.until_idle()
    assert len(rig.dev.paper.strokes()) == 2 and rig.dev.paper.strokes()[1][1].shape == (1, 2)


def test_ink_is_one_point_per_move_however_the_bytes_arrive():
    moves = "".join(f"SM,20,{40 * (k % 3)},{-30 * (k % 2)}\r" for k in range(40))
    at_once, by_byte = Rig(), Rig()
    for rig in (at_once, by_byte):
        rig.send("SC,10,0\rCU,4,8\rSP,0\r")  # an instant servo: every move inks from its start
    at_once.send(moves)
    for b in moves.encode():
        by_byte.run(0.0005)
        by_byte.send(bytes([b]))
    for rig in (at_once, by_byte):
        rig.until_idle()
    (_, a), = at_once.dev.paper.strokes()
    (_, b), = by_byte.dev.paper.strokes()
    assert len(a) == len(b) == 1 + sum(1 for k in range(40) if k % 3 or k % 2)
    assert np.array_equal(a, b)


def test_paper_read_mid_move_shows_the_ink_so_far():
    rig = Rig()
    rig.send("SC,10,0\rSP,0\rXM,1000,800,0\r")  # an instant servo; 10 mm along x in 1 s
    rig.run(0.25)
    (_, ink), = rig.dev.paper.strokes()
    assert np.allclose(ink, [[0.0, 0.0], [2.5, 0.0]])
    rig.until_idle()
    (_, ink), = rig.dev.paper.strokes()
    assert np.allclose(ink, [[0.0, 0.0], [2.5, 0.0], [10.0, 0.0]])


def test_pen_contact_follows_the_servo_slew():
    # SC,4,20000 -> SC,5,14000 at rate 100: the FAQ's |delta| x 24 ms / rate = 1.44 s slew; the pen meets
    # the paper when the pulse passes the contact position 17944: (20000 - 17944) x 0.024 / 100 = 0.49344 s
    rig = Rig()
    rig.send("SC,4,20000\rSC,5,14000\rSC,11,0\rSC,12,100\rSP,1\rSP,0\rXM,1440,1440,0\r")  # 18 mm in 1.44 s
    rig.until_idle()
    strokes = rig.dev.paper.strokes()
    assert len(strokes) == 1
    assert np.allclose(strokes[0][1][[0, -1]], [[0.49344 * 12.5, 0.0], [18.0, 0.0]], atol=0.02)


def test_saxi_style_s2_pen_moves_lift_the_pen():
    # saxi never sends SC,4/SC,5: it moves the pen with S2 on RP4 (up 28000, down 15700, ebb.ts)
    rig = Rig()
    rig.send("EM,1,1\rS2,28000,4,0,0\rXM,500,800,0\rS2,15700,4,0,0\rXM,500,0,800\rS2,28000,4,0,0\rXM,500,-800,0\r")
    rig.until_idle()
    (_, ink), = rig.dev.paper.strokes()  # only the pen-down move, from (10, 0) to (10, 10)
    assert np.allclose(ink[[0, -1]], [[10, 0], [10, 10]])
    assert rig.send("QP\r") == b"0\n\rOK\r\n"  # ebb.c: only a move to exactly SC,4 reports the pen up


def test_contact_position_is_an_option():
    # with the contact at 15000, pyaxidraw's 30 % down position (15248) no longer reaches the paper
    for contact, inked in ((15000, 0), (15300, 1)):
        rig = Rig(contact=contact)
        rig.send("SC,4,20641\rSC,5,15248\rSP,0\rXM,500,800,0\rSP,1\r")
        rig.until_idle()
        assert len(rig.dev.paper.strokes()) == inked
    assert create("axidraw", contact="16000").contact_pulse == 16000
    for bad in ("0", "70000", "\u00b2", "1.5"):
        with pytest.raises(URLError, match="contact"):
            create("axidraw", contact=bad)


def test_boot_servo_positions_follow_the_firmware_version():
    # RCServo2_Init: SC,4 22565 / SC,5 15302 since 2.6.0 (AxiDraw-ready); 12000 / 16000 before, both below
    # the AxiDraw's contact position, so an old board without SC,4/SC,5 inks its pen-up moves too
    for firmware, inked in (("3.0.2", [[0, 0], [10, 0]]), ("2.5.3", [[0, 0], [10, 0], [10, 10]])):
        rig = Rig(firmware=firmware)
        rig.send("SP,0,500\rXM,500,800,0\rSP,1,500\rXM,500,0,800\r")  # delays cover the slews at rate 400
        rig.until_idle()
        (_, ink), = rig.dev.paper.strokes()
        assert np.allclose(ink, inked), firmware


def test_power_on_servo_slews_at_the_firmwares_rate_400_also_after_r():
    # RCServo2.c RCServo2_Init: rates 400; the pulse falls from SC,4 22565 to 15302 and meets the paper
    # (contact 17944) after (22565 - 17944) x 24 ms / 400 = 277.26 ms, 2.77 mm into a 10 mm/s move
    for setup in ("", "SC,10,0\rR\r"):  # R runs UserInit, RCServo2_Init included: the rates are 400 again
        rig = Rig()
        rig.send(setup + "SP,0\rXM,1000,800,0\r")
        rig.until_idle()
        (_, ink), = rig.dev.paper.strokes()
        assert np.allclose(ink[[0, -1]], [[2.7726, 0.0], [10.0, 0.0]], atol=0.02), setup


def test_power_on_defaults_of_ebb_init_and_userinit():
    # ebb.c EBB_Init (fw 3.0.3): PenState = PEN_UP (l. 1698), NodeCount = 0, gSL_Storage[] = 0,
    # gCurrentFIFOLength = 1 (l. 1710), enables and MS1..3 high (l. 1633-1644); UserInit: servo power timeout
    # RCSERVO_POWEROFF_DEFAULT_MS, counter 0 (off)
    rig = Rig()
    assert rig.send("QG\r") == b"10\r\n"  # bit 4 pen up; nothing moving, no power drop, no limit switch
    assert rig.send("QE\r") == b"0,0\r\nOK\r\n"  # drivers disabled (the microstep pins are 1/16)
    assert rig.send("QN\r") == b"0\r\nOK\r\n" and rig.send("QL,31\r") == b"0\r\nOK\r\n"
    assert rig.send("QU,3\r") == b"QU,1\r\nOK\r\n" and rig.send("QR\r") == b"0\n\rOK\r\n"


def test_qg_bits_6_and_7_read_rb2_and_rb5_on_2x():
    # ebb.c 2.6.5 parse_QG_packet: "if (PORTBbits.RB2) result |= 1 << 6; if (PORTBbits.RB5) result |= 1 << 7"
    rig = Rig(firmware="2.6.5")
    assert rig.send("QG\r") == b"D0\r\n"  # both pulled-up inputs high, pen up
    assert rig.send("PD,B,2,0\rQG\r") == b"OK\r\n90\r\n"  # RB2 now a low output
    assert rig.send("PO,B,5,0\rPD,B,5,0\rQG\r") == b"OK\r\nOK\r\n10\r\n"


def test_analog_channels_ra0_and_vplus_are_enabled_at_boot_on_3x():
    # ebb.c EBB_Init (3.x, l. 1629-1631): AnalogConfigure(RA0_CUR_ADJ_ADC_CHANNEL, 1) and
    # AnalogConfigure(RA11_VPLUS_POWER_ADC_CHANNEL, 1); 2.x firmware boots with none (2.6.5's EBB_Init has no call)
    # V+ 9 V: (9 - 0.3) / 9.2 / 3.3 x 1023 = 293.2 through the divider; RA0 reads 394 (the current-set pot)
    assert Rig().send("A\r") == b"A,00:0394,11:0293\r\n"
    assert Rig(firmware="2.6.5").send("A\r") == b"A,\r\n"
    rig = Rig()
    assert rig.send("AC,11,0\rA\r") == b"OK\r\nA,00:0394\r\n"
    rig.send("R\r")
    assert rig.send("A\r") == b"A,00:0394,11:0293\r\n"


def test_pi_reads_servo_power_on_ra3_and_the_engraver_low_on_rb3():
    # HardwareProfile_EBB_V13_and_above.h: RCServoPowerIO = LATA3 (RCSERVO_POWER_ON 1); EBB_Init: RA3 a low
    # output (l. 1693-1694), TRISB3 = 0 / RB3 = 0 (the engraver output starts off)
    rig = Rig()
    assert rig.send("PI,A,3\rPI,B,3\r") == b"PI,0\r\nPI,0\r\n"
    rig.send("SP,1\r")  # process_SP: RCServoPowerIO = RCSERVO_POWER_ON
    assert rig.send("PI,A,3\r") == b"PI,1\r\n"
    rig.send("SR,60000,0\r")
    assert rig.send("PI,A,3\r") == b"PI,0\r\n"


def test_pi_reads_the_motor_enable_and_microstep_pins():
    # HardwareProfile_EBB_V13_and_above.h: enables RE0 / RC1 (active low), MS1 RE2, MS2 RE1, MS3 RA6;
    # EBB_Init drives them all high: drivers disabled, 1/16 stepping
    rig = Rig()
    pins = ("PI,E,0\r", "PI,C,1\r", "PI,E,2\r", "PI,E,1\r", "PI,A,6\r")

    def read() -> tuple[int, ...]:
        return tuple(int(rig.send(p)[3:4]) for p in pins)

    assert read() == (1, 1, 1, 1, 1)
    assert rig.send("EM,1,1\rQE\r") == b"OK\r\n16,16\r\nOK\r\n"
    assert read() == (0, 0, 1, 1, 1)
    assert rig.send("EM,3,0\rQE\r") == b"OK\r\n4,0\r\nOK\r\n"
    assert read() == (0, 1, 0, 1, 0)  # 1/4: MS1 0, MS2 1, MS3 0
    assert rig.send("EM,5,5\rQE\r") == b"OK\r\n1,1\r\nOK\r\n"
    assert read() == (0, 0, 0, 0, 0)
    assert rig.send("EM,0,0\rQE\r") == b"OK\r\n0,0\r\nOK\r\n"
    assert read() == (1, 1, 0, 0, 0)  # EM,0 leaves the microstep pins alone
    assert rig.send("I\r") == b"I,000,229,002,000,001\r\n"  # port B: pulled-up inputs but RB1, RB3, RB4; RC1, RE0 high
    rig.send("EM,2,2\r")
    assert rig.send("ES,1\r") == b"0\n\rOK\r\n"
    assert read() == (1, 1, 1, 1, 0)  # ES,1 disables both drivers
    assert rig.send("PO,E,0,0\rQE\r") == b"OK\r\n8,0\r\nOK\r\n"  # the pins are the state: PO drives them
    rig.send("R\r")
    assert read() == (1, 1, 1, 1, 1)  # R runs UserInit again


def test_stepper_timeout_releases_the_enable_pins():
    rig = Rig()
    rig.send("CU,61,1\rXM,100,80,0\r")
    rig.until_idle()
    assert rig.send("PI,E,0\r") == b"PI,0\r\n"
    rig.run(1.5)
    assert rig.send("PI,E,0\rPI,C,1\rQE\r") == b"PI,1\r\nPI,1\r\n0,0\r\nOK\r\n"


def test_button_power_loss_and_reset_faults():
    rig = Rig()
    rig.dev.inject("pause-button")
    assert rig.send("QB\r") == b"1\r\nOK\r\n"
    assert rig.send("QB\r") == b"0\r\nOK\r\n"
    rig.dev.inject("pause-button")
    assert rig.send("QG\r") == b"30\r\n"  # PRG bit 5 until the next query
    assert rig.send("CU,60,404\r") == b"OK\r\n"  # 12 V threshold
    rig.dev.inject("power-loss")
    assert rig.send("QG\r") == b"50\r\n"  # power lost (bit 6), cleared by reading
    assert rig.send("QG\r") == b"10\r\n"
    assert rig.send("QC\r") == b"0394,0000\r\nOK\r\n"
    rig.send("XM,100,80,0\r")
    rig.until_idle()
    assert rig.send("QS\r") == b"80,80\n\rOK\r\n"  # the firmware counts steps the motors did not make
    assert np.allclose(rig.dev.position_mm, [0, 0])
    rig.dev.inject("power-restore")
    rig.send("CU,10,1\r")
    rig.dev.inject("reset")
    assert rig.dev.syntax == "legacy" and rig.send("QS\r") == b"0,0\n\rOK\r\n"
    with pytest.raises(ConfigError, match="paper-lever"):
        rig.dev.inject("paper-lever")


def test_misc_commands():
    rig = Rig()
    assert rig.send("SL,125,19\rQL,19\r") == b"OK\r\n125\r\nOK\r\n"
    assert rig.send("ST,East EBB\rQT\r") == b"OK\r\nEast EBB\r\nOK\r\n"
    assert rig.send("SN,41\rNI\rQN\r") == b"OK\r\nOK\r\n42\r\nOK\r\n"
    assert rig.send("MW,422,71\rMR,422\r") == b"OK\r\nMR,071\r\n"
    assert rig.send("PI,B,0\r") == b"PI,1\r\n"  # pulled-up input
    assert rig.send("EM,3,3\rQE\r") == b"OK\r\n4,4\r\nOK\r\n"
    assert rig.send("CK,1,-1,2,-2,3,-3,a,b\r") == (
        b"\r\nParam1=1\r\nParam2=-1\r\nParam3=2\r\nParam4=-2\r\nParam5=3\r\nParam6=-3\r\n"
        b"Param7=a\r\nParam8=B\r\nOK\r\n"
    )
    assert rig.send("R\r") == b"OK\r\n"
    assert rig.send("RB\r") == b""


def test_oversized_command_and_backspace():
    rig = Rig()
    out = rig.send("SM," + "1" * 300 + "\r")
    assert b"!3 Err: RX Buffer overrun" in out
    assert rig.send("VX\x08\r") == b" \b" + VERSION + b"\r\n"


def test_starved_time_between_moves():
    rig = Rig()
    rig.send("SM,100,10,10\r")
    rig.until_idle()
    rig.run(0.5)
    rig.send("SM,100,10,10\r")
    rig.until_idle()
    assert rig.dev.stats.starved_time == pytest.approx(0.5)
    assert rig.dev.stats.commands_executed == 2


def test_factories():
    axi = functools.partial(create, "axidraw")
    dev = axi(clock=SimulatedClock(), model="minikit", firmware="2.8.1")
    assert dev.paper.width_mm == 160 and dev.firmware == "2.8.1"
    assert create("ebb", clock=SimulatedClock(), model="se_a3").paper.height_mm == 297
    with pytest.raises(URLError, match=r"unknown option.*colour.*known:"):
        axi(colour="red")
    with pytest.raises(URLError, match="model='nano'"):
        axi(model="nano")
    with pytest.raises(URLError, match="firmware"):
        axi(firmware="three")
    assert axi(clock=SimulatedClock(), machine="a3").paper.width_mm == 430  # alias of model=
    with pytest.raises(URLError, match="once"):
        axi(model="v3", machine="a3")


_ERROR = re.compile(rb"!(\d+) Err: ")


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=400), st.floats(0, 3))
def test_fuzz_random_bytes(data, wait):
    rig = Rig()
    out = rig.send(data) + rig.run(wait) + rig.until_idle()
    assert {int(m) for m in _ERROR.findall(out)} <= {0, 3, 4, 5, 6, 7, 8, 9, 10}  # documented codes only
    assert rig.dev.next_event_time() is None


_CMDS = ["SM,100,10,-10", "XM,50,5,5", "LM,85899346,10,0,17180814,2,0", "LT,250,85899346,0,0,0", "SP,0,50",
         "SP,1,50", "TP", "EM,1,1", "EM,0,0", "QG", "QS", "QM", "ES", "CU,4,2", "CU,10,1", "HM,1000",
         "S2,14000,4,0,10", "SC,4,9000", "QB", "V", "SM,1", "XM,0,1,1", "ZZ", "LM,0,10,0,0,0,0",
         "TD,100,1,2,3,4,5,6,7,8", "L3,1,1,1,1,1,1,1,1"]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.sampled_from(_CMDS), max_size=30), st.integers(0, 800), st.booleans())
def test_fuzz_command_streams_cut_anywhere(cmds, cut, lowercase):
    text = "".join(c + "\r" for c in cmds)
    if lowercase:
        text = text.lower()
    rig = Rig()
    out = rig.send(text.encode()[:cut])
    out += rig.until_idle()
    assert b"Err: Unknown command" not in out.replace(b"Err: Unknown command 'ZZ:5A5A'", b"")
    assert rig.dev.next_event_time() is None


def test_end_to_end_through_the_sim_url():
    serial = pytest.importorskip("serial")
    pytest.importorskip("pixelpen.sim.transports.urlhandler")
    import pixelpen.sim.transports.urlhandler  # noqa: F401

    port = serial.serial_for_url("sim://axidraw?speed=fast&baud=115200&flow=rtscts", timeout=2)
    try:
        port.write(b"V\rEM,1,1\rXM,500,400,0\rXM,500,400,0\rXM,500,400,0\rQS\r")
        assert port.readline() == VERSION + b"\r\n"
        assert [port.readline() for _ in range(4)] == [b"OK\r\n"] * 4
        assert port.readline() == b"400,400\n"  # QS answers only once the third move fits the FIFO
        assert port.readline() == b"\rOK\r\n"
    finally:
        port.close()


def test_pushing_the_carriage_home_needs_unpowered_motors_and_leaves_the_counters():
    """The operator's push moves the carriage, not the step counters the board reports (QS)."""
    rig = Rig()
    rig.send("EM,1,1\rXM,500,800,800\r")
    rig.until_idle()
    with pytest.raises(ConfigError, match="energised motors hold the carriage"):
        rig.dev.push_carriage_home()
    rig.dev.inject("power-loss")
    before = rig.dev.paper.strokes()
    rig.dev.push_carriage_home()
    assert np.allclose(rig.dev.position_mm, [0, 0]) and rig.dev.paper.strokes() == before
    assert rig.send("QS\r") == b"1600,0\n\rOK\r\n"  # XM,500,800,800: motor 1 = A + B, motor 2 = A - B
    rig.send("EM,0,0\rSP,0,300\r")  # the pen lands 277 ms after SP,0 (22565 -> 17944 at rate 400)
    rig.until_idle()
    with pytest.raises(ConfigError, match="lift the pen"):
        rig.dev.push_carriage_home()


def test_is_a_simulated_device_with_the_shared_faults():
    rig = Rig()
    assert isinstance(rig.dev, SimulatedDevice)
    assert {Fault.POWER_LOSS, Fault.POWER_RESTORE, Fault.PAUSE_BUTTON, Fault.RESET} == EbbSimulator.FAULTS
    rig.dev.inject(Fault.PAUSE_BUTTON)  # a member works as well as its name
    assert rig.send("QB\r") == b"1\r\nOK\r\n"
    with pytest.raises(ConfigError, match="known: pause-button, power-loss, power-restore, reset"):
        rig.dev.inject(Fault.PAPER_LEVER)


def test_a_fault_injected_at_a_byte_count_falls_between_the_bytes():
    rig = Rig()
    rig.dev.inject(Fault.POWER_LOSS, at=3)
    rig.dev.inject("pause-button", at=6)  # the old string names still work
    assert rig.send("QC\rQC\rQB\r") == b"0394,0293\r\nOK\r\n0394,0000\r\nOK\r\n1\r\nOK\r\n"
    assert [entry for _, entry in rig.dev.log] == ["QC", "<power-loss>", "QC", "<pause-button>", "QB"]


def test_the_url_options_are_declared_as_specs():
    assert [spec.name for spec in OPTIONS] == ["model", "firmware", "syntax", "pen_colour", "pen_width", "contact"]
    assert {spec.name: spec.default for spec in OPTIONS}["contact"] == CONTACT_DEFAULT
    assert all(help_text for _, help_text in describe(OPTIONS))
    with pytest.raises(URLError, match=r"option pen_width='-1' is not valid"):
        create("axidraw", pen_width="-1")
    with pytest.raises(URLError, match=r"option pen_colour='nocolour' is not valid"):
        create("axidraw", pen_colour="nocolour")
    assert create("axidraw", clock=SimulatedClock(), pen_colour="steelblue").paper.pen_colours == {1: "steelblue"}


def test_both_models_register_when_the_module_is_imported():
    assert simulator_factory("axidraw")(clock=SimulatedClock()).model == "axidraw"
    assert simulator_factory("ebb")(clock=SimulatedClock(), syntax="future").syntax == "future"

"""GRBL 1.1h simulator on its wire: replies and reports as gnea/grbl documents them, timing, buffers, faults."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError, URLError
from pixelpen.sim.base import StreamDevice, create_simulator
from pixelpen.sim.plotters.grbl.controller import GrblSimulator, fmt_float
from tests.sim.fakes import DeviceRig

WELCOME = b"\r\nGrbl 1.1h ['$' for help]\r\n"
UNLOCK = b"[MSG:'$H'|'$X' to unlock]\r\n"


class Rig(DeviceRig):
    """A GRBL simulator on a simulated clock, past its welcome line."""

    def __init__(self, **options):
        clock = SimulatedClock()
        super().__init__(GrblSimulator(clock, **options), clock)
        self.dev.take_output()

    def status(self) -> str:
        return self.send(b"?").decode()


def test_is_a_wire_device_with_a_welcome():
    clock = SimulatedClock()
    dev = GrblSimulator(clock)
    assert isinstance(dev, StreamDevice) and dev.model == "grbl" and dev.clock is clock
    assert dev.take_output() == WELCOME
    assert dev.ready_to_receive


def test_ok_error_and_empty_lines():
    rig = Rig()
    assert rig.send("G21G90\n") == b"ok\r\n"
    assert rig.send("\n") == b"ok\r\n"  # an empty line is acknowledged
    assert rig.send("G5\n") == b"error:20\r\n"  # unsupported G-code
    assert rig.send("G1X10\n") == b"error:22\r\n"  # feed rate undefined
    assert rig.send("g0 x1 (comment) ; tail\n") == b"ok\r\n"  # lower case, spaces and comments


def test_line_overflow_is_error_11():
    rig = Rig()
    line = "G0X1" + "0" * 76  # 80 significant characters: one more than the 79 that fit
    assert rig.send(line + "\n") == b"error:11\r\n"
    assert rig.send("G0X1" + "0" * 75 + "\n") == b"ok\r\n"  # 79 fit


def test_build_info_and_help():
    rig = Rig()
    assert rig.send("$I\n") == b"[VER:1.1h.20190830:]\r\n[OPT:VZ,15,128]\r\nok\r\n"
    assert rig.send("$\n") == b"[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]\r\nok\r\n"
    assert rig.send("$G\n") == b"[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n"
    assert rig.send("$N\n") == b"$N0=\r\n$N1=\r\nok\r\n"
    # the pre-parser upper-cases every line, the stored string included
    assert rig.send("$I=plotter\n$I\n").startswith(b"ok\r\n[VER:1.1h.20190830:PLOTTER]\r\n")


def test_settings_listing_and_errors():
    rig = Rig()
    listing = rig.send("$$\n").decode().split("\r\n")
    assert listing[0] == "$0=10" and "$11=0.010" in listing and "$130=300.000" in listing
    assert listing[-2:] == ["ok", ""]
    assert rig.send("$110=100000\n") == b"error:12\r\n"  # 80 steps/mm x 100000 mm/min > 30 kHz
    assert rig.send("$11=-1\n") == b"error:4\r\n"
    assert rig.send("$999=1\n") == b"error:3\r\n"
    assert rig.send("$0=2\n") == b"error:6\r\n"
    assert rig.send("$20=1\n") == b"error:10\r\n"  # soft limits need homing
    assert rig.send("$Z\n") == b"error:2\r\n"
    assert rig.send("$11=0.02\n") == b"ok\r\n"
    assert b"$11=0.020\r\n" in rig.send("$$\n")


def test_status_report_fields_follow_the_refresh_rules():
    rig = Rig()
    first = rig.status()
    assert first == "<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>\r\n"  # WCO in the first
    assert rig.status() == "<Idle|MPos:0.000,0.000,0.000|FS:0,0|Ov:100,100,100>\r\n"  # Ov in the second
    assert rig.status() == "<Idle|MPos:0.000,0.000,0.000|FS:0,0>\r\n"
    rig.send("$10=2\n")  # WPos and buffer state
    assert re.fullmatch(r"<Idle\|WPos:0\.000,0\.000,0\.000\|Bf:15,128\|FS:0,0(\|[^>]*)?>\r\n", rig.status())


def test_printfloat_rounding():
    assert fmt_float(1.0005, 3) == "1.001"
    assert fmt_float(-0.0004, 3) == "-0.000"
    assert fmt_float(1000, 0) == "1000"
    assert fmt_float(0.25, 1) == "0.3"


def test_single_long_move_takes_d_over_v_plus_v_over_a():
    rig = Rig()
    rig.send("G1X200F3000\nG4P0\n")  # 50 mm/s, $120 = 1000 mm/s²; G4 answers when motion is done
    t = 200 / 50 + 50 / 1000
    assert rig.run(t - 0.001) == b""
    assert rig.status().startswith("<Run|")
    assert rig.run(0.002) == b"ok\r\n"
    assert rig.status().startswith("<Idle|MPos:200.000,0.000,0.000")


def test_diagonal_rapid_is_limited_per_axis():
    rig = Rig()
    rig.send("G0X100Y100\nG4P0\n")
    # unit (1,1)/√2: rate min(5000/(1/√2)) mm/min, accel min(1000/(1/√2)) mm/s²
    v = 5000 * math.sqrt(2) / 60
    a = 1000 * math.sqrt(2)
    t = 100 * math.sqrt(2) / v + v / a
    assert rig.run(t - 0.001) == b""
    assert rig.run(0.002) == b"ok\r\n"


def test_position_mid_move_and_feed_in_the_report():
    rig = Rig()
    rig.send("G1X200F3000\n")
    rig.run(2.0)  # 1.25 mm of ramp, then 50 mm/s for 1.95 s
    assert rig.status().startswith("<Run|MPos:98.750,0.000,0.000|FS:3000,0")


def test_reset_while_moving_raises_alarm_3():
    rig = Rig()
    rig.send("G1X200F3000\n")
    rig.run(1.0)
    assert rig.send(b"\x18") == b"ALARM:3\r\n" + WELCOME + UNLOCK
    assert rig.status().startswith("<Alarm|")
    assert rig.send("G0X1\n") == b"error:9\r\n"  # G-code locked
    assert rig.send("$X\n") == b"[MSG:Caution: Unlocked]\r\nok\r\n"
    assert rig.status().startswith("<Idle|MPos:48.750")  # position kept: 1.25 + 50 x 0.95


def test_reset_while_idle_has_no_alarm():
    rig = Rig()
    assert rig.send(b"\x18") == WELCOME
    assert rig.status().startswith("<Idle|")


def test_feed_hold_and_resume():
    rig = Rig()
    rig.send("G1X200F3000\nG4P0\n")
    rig.run(2.0)
    rig.send(b"!")
    assert rig.status().startswith("<Hold:1|")
    rig.run(0.06)  # decelerates over v/a = 0.05 s and v²/2a = 1.25 mm
    assert rig.status().startswith("<Hold:0|MPos:100.000,0.000,0.000")
    assert rig.run(5.0) == b""  # holds indefinitely
    rig.send(b"~")
    assert rig.status().startswith("<Run|")
    assert rig.run(100 / 50 + 50 / 1000 + 0.001) == b"ok\r\n"


def test_safety_door_lifts_the_pen_and_restores_the_spindle_after_4_s():
    rig = Rig()
    rig.send("M3S1000\nG1X100F3000\nM5\n")
    rig.run(1.0)  # at 48.75 mm, pen down
    rig.send(b"\x84")
    assert rig.status().startswith("<Door:2|")
    rig.run(0.1)
    assert rig.status().startswith("<Door:0|MPos:50.000")  # 1.25 mm to stop
    assert not rig.dev.paper.pen_is_down
    rig.send(b"~")
    assert rig.status().startswith("<Door:3|")  # spindle back on, SAFETY_DOOR_SPINDLE_DELAY
    rig.run(4.0)
    assert rig.status().startswith("<Run|")
    rig.until_idle()
    strokes = [s[1] for s in rig.dev.paper.strokes()]
    assert len(strokes) == 2 and strokes[0][-1][0] == pytest.approx(48.75) and strokes[1][0][0] == pytest.approx(50)


def test_feed_override_changes_speed_and_the_ov_field():
    rig = Rig()
    rig.status()  # the first report carries WCO, which delays Ov by one report
    rig.send("G1X200F3000\n")
    rig.run(1.0)
    rig.send(b"\x91")  # +10 %
    rig.run(0.5)
    report = rig.status()
    assert "FS:3300," in report and "Ov:110,100,100" in report
    rig.send(b"\x90\x97")  # feed back to 100 %, rapids to 25 %
    assert "Ov:100,25,100" in rig.status()


def test_laser_mode_lifts_the_pen_for_rapids():
    rig = Rig()
    rig.send("$32=1\nM3S1000\nG1X10F1000\nG0X20\nG1X30\nM5\n")
    rig.until_idle()
    assert [s[1][[0, -1]].tolist() for s in rig.dev.paper.strokes()] == [[[0, 0], [10, 0]], [[20, 0], [30, 0]]]


def test_m0_pauses_until_cycle_start():
    rig = Rig()
    assert rig.send("M0\n") == b""
    assert rig.status().startswith("<Hold:0|")
    assert rig.send(b"~") == b"ok\r\n"
    assert rig.send("M2\n") == b"[MSG:Pgm End]\r\nok\r\n"


def test_jog_and_jog_cancel():
    rig = Rig()
    assert rig.send("$J=X100F6000\n") == b"ok\r\n"
    rig.run(0.5)
    assert rig.status().startswith("<Jog|")
    assert rig.send("G0X1\n") == b"error:9\r\n"  # G-code locked while jogging
    rig.send(b"\x85")
    rig.run(0.2)
    status = rig.status()
    assert status.startswith("<Idle|")
    x = float(re.search(r"MPos:([-\d.]+)", status).group(1))
    assert 40 < x < 100
    assert rig.send("$J=G91X-1F600\n") == b"ok\r\n"
    rig.until_idle()
    assert rig.status().startswith(f"<Idle|MPos:{x - 1:.3f}")


def test_soft_limit_alarm_2_is_critical():
    rig = Rig()
    assert rig.send("$22=1\n$20=1\n") == b"ok\r\nok\r\n"
    assert rig.send("G0X400\n") == b"ALARM:2\r\n[MSG:Reset to continue]\r\n"
    assert rig.send(b"?") == b""  # no status report in a critical alarm
    assert rig.send("$X\n") == b""  # nothing is parsed until a reset
    assert rig.send(b"\x18") == WELCOME + UNLOCK


def test_check_mode_parses_without_moving():
    rig = Rig()
    assert rig.send("$C\n") == b"[MSG:Enabled]\r\nok\r\n"
    assert rig.send("G1X100F100\nG4P10\nG5\n") == b"ok\r\nok\r\nerror:20\r\n"
    assert rig.status().startswith("<Check|MPos:0.000,0.000,0.000")
    assert rig.send("$C\n") == b"[MSG:Disabled]\r\nok\r\n" + WELCOME


def test_sleep_until_reset_then_alarm():
    rig = Rig()
    assert rig.send("$SLP\n") == b"ok\r\n[MSG:Sleeping]\r\n"
    assert rig.status().startswith("<Sleep|")
    assert rig.send("G0X1\n") == b""
    assert rig.send(b"\x18") == WELCOME + UNLOCK


def test_startup_lines_run_after_reset():
    rig = Rig()
    assert rig.send("$N0=G91\n") == b"ok\r\n"
    assert rig.send("$N\n") == b"$N0=G91\r\n$N1=\r\nok\r\n"
    assert rig.send(b"\x18") == WELCOME + b">G91:ok\r\n"
    assert b"G91" in rig.send("$G\n")


def test_parameters_report():
    rig = Rig()
    rig.send("G10L2P1X1Y2\nG92X0\n")
    out = rig.send("$#\n").decode().split("\r\n")
    assert out[0] == "[G54:1.000,2.000,0.000]"
    assert out[8] == "[G92:-1.000,0.000,0.000]"  # machine 0 reads work 0 with G54 x = 1: G92 x = 0 - 1 - 0
    assert out[9:12] == ["[TLO:0.000]", "[PRB:0.000,0.000,0.000:0]", "ok"]


def test_homing():
    rig = Rig()
    assert rig.send("$H\n") == b"error:5\r\n"  # homing disabled
    rig.send("$22=1\nG0X50Y20\n")
    rig.until_idle()
    assert rig.send("$H\n") == b""
    assert rig.dev.state == "Home"
    assert rig.status() == ""  # no status report during a homing cycle
    assert rig.until_idle() == b"ok\r\n"
    assert rig.status().startswith("<Idle|MPos:0.000,0.000,0.000")


def test_rx_buffer_and_planner_fill_under_character_counting():
    rig = Rig()
    rig.send("$10=3\n")
    lines = [f"G1X{10 + (i % 2) * 0.5:.1f}Y{i * 0.5:.1f}F1000\n".encode() for i in range(60)]
    pending: list[int] = []  # bytes of lines not yet acknowledged (stream.py)
    acked = 0
    min_blocks, max_rx_used = 99, 0
    i = 0
    for _ in range(100_000):
        while i < len(lines) and sum(pending) + len(lines[i]) < 128:
            rig.dev.receive(lines[i])
            pending.append(len(lines[i]))
            i += 1
        out = rig.send(b"?").decode()
        bf = re.search(r"Bf:(\d+),(\d+)", out)
        min_blocks = min(min_blocks, int(bf.group(1)))
        max_rx_used = max(max_rx_used, 128 - int(bf.group(2)))
        te = rig.dev.next_event_time()
        if te is None and i == len(lines) and not pending:
            break
        if te is not None:
            rig.clock.advance(te - rig.clock.now())
            rig.dev.advance_to(te)
        out += rig.dev.take_output().decode()
        for _ in range(out.count("ok\r\n")):
            pending.pop(0)
            acked += 1
        assert "error" not in out
    assert acked == 60 and rig.dev.overflowed == 0
    assert min_blocks == 0  # the planner filled up: 15 blocks queued
    assert max_rx_used > 60  # and lines waited in the RX buffer meanwhile
    assert rig.dev.stats.starved_time == pytest.approx(0.0, abs=1e-9)


def test_flooding_the_rx_buffer_loses_bytes():
    rig = Rig()
    rig.send("G1X100F100\n")
    rig.send(b"G1X1Y1F100\n" * 40)  # 440 bytes while the planner is far from full
    rig.send(b"".join(f"G1X{i}Y{i}\n".encode() for i in range(200)))
    assert rig.dev.overflowed > 0
    assert rig.dev.rx_free == 0


def test_arcs_end_where_the_gcode_says_and_stay_on_the_circle():
    rig = Rig()
    rig.send("G0X50Y50\nM3S1000\nG2X70Y50I10J0F3000\nG2X50Y50R10\nM5\n")
    rig.until_idle()
    assert rig.status().startswith("<Idle|MPos:50.000,50.000,0.000")
    strokes = rig.dev.paper.strokes()
    assert len(strokes) == 1
    pts = strokes[0][1]
    assert np.allclose(np.hypot(pts[:, 0] - 60, pts[:, 1] - 50), 10, atol=1e-6)
    assert pts[:, 1].max() == pytest.approx(60, abs=0.01)  # CW from the left goes over the top
    assert pts[:, 1].min() == pytest.approx(40, abs=0.01)  # and CW back from the right passes below
    rig.send("M3\nG3X70Y50R10\nM5\n")  # CCW from the left passes below too
    rig.until_idle()
    last = rig.dev.paper.strokes()[-1][1]
    assert last[:, 1].max() == pytest.approx(50) and last[:, 1].min() == pytest.approx(40, abs=0.01)


def test_servo_pen_draws_only_while_down():
    rig = Rig()
    rig.send("G0X10Y10\nM3S1000\nG1X20F1000\nM5\nG0X30\nM3S100\nG1X40\nM5\n")  # S100 < 500: up
    rig.until_idle()
    strokes = rig.dev.paper.strokes()
    assert len(strokes) == 1 and np.allclose(strokes[0][1], [[10, 10], [20, 10]])


def test_servo_inverted_and_z_pens():
    rig = Rig(pen="servo-inverted")
    rig.send("M3S1000\nG0X10\nM3S50\nG1X20F1000\nM3S1000\n")
    rig.until_idle()
    assert [s[1].tolist() for s in rig.dev.paper.strokes()] == [[[10, 0], [20, 0]]]
    rig = Rig(pen="z")
    rig.send("G0Z5\nG0X10\nG1Z-1F500\nG1X20F1000\nG0Z5\nG0X30\n")
    rig.until_idle()
    strokes = [s[1] for s in rig.dev.paper.strokes()]
    assert any(np.allclose(s[[0, -1]], [[10, 0], [20, 0]]) for s in strokes)
    assert not any(np.any(s[:, 0] > 20.001) for s in strokes)


def test_z_pen_is_parked_up_until_a_move_drives_z():
    rig = Rig(pen="z")  # boots at work Z = 0, but a plotter powers up with its pen up
    rig.run(1.0)
    assert rig.dev.paper.strokes() == [] and not rig.dev.paper.pen_is_down
    rig.send("G1X10F1000\n")  # XY only: the pen stays parked
    rig.until_idle()
    assert rig.dev.paper.strokes() == []
    rig.send("G1Z-1F500\nG1X20F1000\nG0Z5\n")  # the first Z move lowers it onto the paper
    rig.until_idle()
    (_, ink), = rig.dev.paper.strokes()
    assert np.allclose(ink[[0, -1]], [[10, 0], [20, 0]])
    rig.send("G0Z0\n")
    rig.until_idle()
    rig.dev.inject("reset")  # a reboot parks it again, whatever the Z it assumes
    assert len(rig.dev.paper.strokes()) == 2 and not rig.dev.paper.pen_is_down


def test_starved_time_counts_waits_for_the_host():
    rig = Rig()
    rig.send("G1X10F600\n")  # 1 s + ramps
    rig.until_idle()
    rig.run(2.0)
    rig.send("G1X20F600\n")
    rig.until_idle()
    assert rig.dev.stats.starved_time == pytest.approx(2.0, abs=1e-6)
    assert rig.dev.stats.bytes_received == 20 and rig.dev.stats.commands_executed == 2


def test_faults():
    rig = Rig()
    rig.send("G1X100F3000\n")
    rig.run(0.5)
    rig.dev.inject("pause-button")
    assert rig.status().startswith("<Hold:1|")
    rig.dev.inject("reset")
    assert rig.dev.take_output() == WELCOME
    assert rig.status().startswith("<Idle|MPos:0.000,0.000,0.000")  # reboot: position lost
    with pytest.raises(ConfigError, match=r"paper-lever.*known"):
        rig.dev.inject("paper-lever")


def test_factory_options():
    dev = create_simulator("grbl", clock=SimulatedClock(), size="200x100", pen="z", rx_buffer="256", planner="8")
    assert dev.rx_free == 256 and dev.planner.capacity == 7
    assert dev.paper.width_mm == 200 and dev.settings[131] == 100
    with pytest.raises(URLError, match=r"unknown option.*colour.*known:"):
        create_simulator("grbl", colour="red")
    with pytest.raises(URLError, match="pen='pencil'"):
        create_simulator("grbl", pen="pencil")
    with pytest.raises(URLError, match="rx_buffer"):
        create_simulator("grbl", rx_buffer="4")


_REPLY = re.compile(
    rb"(ok|error:\d+|ALARM:\d+|<[^>\r\n]*>|\[[^\]\r\n]*\]|\$N?\d+=[^\r\n]*|>[^\r\n]*:(ok|error:\d+)|"
    rb"Grbl 1\.1h \['\$' for help\]|)"
)


def _check_replies(out: bytes) -> None:
    for line in out.split(b"\r\n"):
        assert _REPLY.fullmatch(line), line


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=400), st.floats(0, 2))
def test_fuzz_random_bytes(data, wait):
    rig = Rig()
    out = rig.send(data)
    out += rig.run(wait)
    out += rig.send(b"\x18")
    _check_replies(out)


_WORDS = ["G0", "G1", "G2", "G3", "G4P0.01", "G17", "G20", "G21", "G90", "G91", "G92X0", "M3S600", "M5", "M0",
          "X", "Y", "Z", "I", "J", "R", "F", "$J=", "$X", "$$", "$G", "$#", "~", "!", "?", "%", "(c)", ";c",
          "G10L2P1", "G28", "G53", "N5", "T1", "M8", "M9", "G80", "G38.2", "$C"]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.sampled_from(_WORDS), st.floats(-50, 50, allow_nan=False), st.booleans()),
                max_size=40), st.integers(0, 2000))
def test_fuzz_gcode_streams_cut_anywhere(items, cut):
    text = "".join(f"{w}{v:.2f}" if w in "XYZIJRF" else w + ("\n" if nl else "") for w, v, nl in items)
    stream = text.encode()[:cut]
    rig = Rig()
    out = rig.send(stream)
    for _ in range(20):
        out += rig.run(5.0)
        out += rig.send(b"~")
    _check_replies(out)
    assert rig.dev.next_event_time() is None or rig.dev.next_event_time() > rig.clock.now() - 1e-9


def test_end_to_end_through_the_sim_url():
    serial = pytest.importorskip("serial")
    pytest.importorskip("pixelpen.sim.transports.urlhandler")
    import pixelpen.sim.transports.urlhandler  # noqa: F401

    port = serial.serial_for_url("sim://grbl?speed=fast&baud=115200", timeout=2)
    try:
        assert port.readline() == b"\r\n" and port.readline() == b"Grbl 1.1h ['$' for help]\r\n"
        port.write(b"G1X20F1200\nG4P0\n?")
        assert port.readline() == b"ok\r\n"
        assert port.readline().startswith(b"<Run|")
        assert port.readline() == b"ok\r\n"  # the dwell answers once the 1 s move is done
    finally:
        port.close()


def test_pushing_the_carriage_home_by_hand_realigns_it_with_a_rebooted_controller():
    """After a power loss GRBL reads MPos 0 where the carriage stopped; the operator's push puts it at 0 too."""
    rig = Rig()
    rig.send("G0X50Y20\n")
    rig.run(0.1)
    with pytest.raises(ConfigError, match="while the machine is Run"):
        rig.dev.push_carriage_home()
    rig.until_idle()
    rig.send("M3S1000\nG4P0.1\n")
    rig.until_idle()
    with pytest.raises(ConfigError, match="lift the pen"):
        rig.dev.push_carriage_home()
    rig.dev.inject("power-loss")
    rig.dev.take_output()
    assert rig.status().startswith("<Idle|MPos:0.000,0.000,0.000")  # it believes 0 ...
    rig.send("M3S1000\nG1X10F3000\nM5\n")
    rig.until_idle()
    assert np.allclose(rig.dev.paper.strokes()[-1][1][[0, -1]], [[50, 20], [60, 20]])  # ... the carriage was at 50,20
    rig.dev.inject("power-loss")
    rig.dev.take_output()
    rig.dev.push_carriage_home()
    rig.send("M3S1000\nG1X10F3000\nM5\n")
    rig.until_idle()
    assert np.allclose(rig.dev.paper.strokes()[-1][1][[0, -1]], [[0, 0], [10, 0]])  # pushed to the origin: they agree


def test_is_a_simulated_device_with_the_shared_faults():
    from pixelpen.sim.base import Fault, SimulatedDevice

    rig = Rig()
    assert isinstance(rig.dev, SimulatedDevice)
    assert set(rig.dev.FAULTS) == {Fault.RESET, Fault.POWER_LOSS, Fault.PAUSE_BUTTON}
    rig.dev.inject(Fault.RESET, at=14)  # falls due inside the second line
    assert rig.send("G1X100F3000\n") == b"ok\r\n"
    rig.run(0.5)
    assert rig.send("G1Y10\n") == WELCOME + b"ok\r\n"  # the board rebooted after "G1"; "Y10" is a G0 move
    assert [entry for _, entry in rig.dev.log[-2:]] == ["<reset>", "Y10"]
    with pytest.raises(ConfigError, match="known: pause-button, power-loss, reset"):
        rig.dev.inject(Fault.PAPER_LEVER)


def test_url_options_are_declared_as_specs():
    from pixelpen.options import OptionSpec, describe
    from pixelpen.sim.plotters.grbl.controller import OPTIONS

    assert all(isinstance(spec, OptionSpec) for spec in OPTIONS)
    names = [name for name, _ in describe(OPTIONS)]
    assert names == ["size", "pen", "pen_threshold", "rx_buffer", "planner", "pen_colour", "pen_width"]
    for spec in OPTIONS:  # every declared option is one the factory takes
        create_simulator("grbl", clock=SimulatedClock(), **{spec.name: {"size": "100x100", "pen": "z",
                         "pen_colour": "steelblue"}.get(spec.name, "20")})
    with pytest.raises(URLError, match=r"sim:grbl: option pen_width='-1' is not valid"):
        create_simulator("grbl", pen_width="-1")

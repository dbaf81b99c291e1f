"""HP 7475A / 7550A / 7440A simulators: replies from the manuals, geometry by hand, buffer, handshakes, time, faults."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError, URLError
from pixelpen.sim.base import StreamDevice, create_simulator, simulator_models
from pixelpen.sim.plotters.hpgl.plotter import HPGLPlotter

UNIT_MM = 0.02488  # 7475A plotter unit (plotters.md §1.1, 7475A manual p. 22)
ESC = b"\x1b"


def make(model: str = "hp7475a", **options: str) -> tuple[HPGLPlotter, SimulatedClock]:
    clock = SimulatedClock(100.0)
    plotter = create_simulator(model, clock=clock, **options)
    assert isinstance(plotter, HPGLPlotter)
    return plotter, clock


def advance(plotter: HPGLPlotter, clock: SimulatedClock, seconds: float) -> None:
    clock.advance(seconds)
    plotter.advance_to(clock.now())


def finish(plotter: HPGLPlotter, clock: SimulatedClock, limit: int = 100_000) -> None:
    """Run until the plotter has nothing left to do by itself."""
    for _ in range(limit):
        t = plotter.next_event_time()
        if t is None:
            return
        clock.advance(max(0.0, t - clock.now()))
        plotter.advance_to(clock.now())
    raise AssertionError("the plotter never went idle")


def ask(plotter: HPGLPlotter, clock: SimulatedClock, data: bytes) -> bytes:
    plotter.receive(data)
    finish(plotter, clock)
    return plotter.take_output()


def segments(plotter: HPGLPlotter) -> np.ndarray:
    return plotter.segments()[0]


def move_time(distance_units: float, v_cm_s: float, a_cm_s2: float) -> float:
    """Rest-to-rest trapezoid (or triangle) time, from the manual's velocity and acceleration."""
    v = v_cm_s * 10 / UNIT_MM
    a = a_cm_s2 * 10 / UNIT_MM
    if distance_units * a <= v * v:
        return 2 * math.sqrt(distance_units / a)
    return distance_units / v + v / a


# -- registration and options --------------------------------------------------------------------


def test_models_are_registered_and_are_wire_devices():
    assert {"hp7475a", "hp7550a", "hp7440a"} <= set(simulator_models())
    for model in ("hp7475a", "hp7550a", "hp7440a"):
        plotter, _ = make(model)
        assert isinstance(plotter, StreamDevice) and plotter.model == model


def test_unknown_and_bad_options_name_the_problem():
    known = "known: buffer, paper, pens, reserve_bug"
    with pytest.raises(URLError, match=rf"sim:hp7475a: unknown option\(s\) colour; {known}"):
        make(colour="red")
    with pytest.raises(URLError, match="a4, letter"):
        make("hp7440a", paper="a3")
    with pytest.raises(URLError, match="7 colours for a 6-pen carousel"):
        make(pens="black,red,green,blue,cyan,magenta,yellow")
    with pytest.raises(URLError, match="unknown colour 'chartreuse-ish'"):
        make(pens="black,chartreuse-ish")
    with pytest.raises(URLError, match="option buffer='lots' is not valid"):
        make(buffer="lots")
    with pytest.raises(URLError, match="true/false"):
        make(reserve_bug="maybe")


def test_paper_option_sets_hard_clip_and_default_p1_p2():
    # plotters.md §1.2
    for paper, oh, op in [
        ("a4", b"0,0,11040,7721\r", b"603,521,10603,7721\r"),
        ("a3", b"0,0,16158,11040\r", b"170,602,15370,10602\r"),
        ("a", b"0,0,10365,7962\r", b"250,596,10250,7796\r"),
        ("tabloid", b"0,0,16640,10365\r", b"522,259,15722,10259\r"),
    ]:
        plotter, clock = make(paper=paper)
        assert ask(plotter, clock, b"IN;OH;OP;") == oh + op
    plotter, clock = make("hp7550a", paper="a3")
    assert ask(plotter, clock, b"OH;") == b"0,0,15970,10870\r"


def test_buffer_option_and_esc_l():
    plotter, clock = make()
    assert ask(plotter, clock, ESC + b".L") == b"1024\r"
    plotter, clock = make(buffer="2048")
    assert ask(plotter, clock, ESC + b".L" + ESC + b".B") == b"2048\r2048\r"


# -- output instructions: byte sequences from the manuals -----------------------------------------


def test_oi_after_in_and_the_7475a_silence_before_it():
    plotter, clock = make()
    assert ask(plotter, clock, b"OI;") == b""  # plotters.md §1.3: a 7475A answers OI only after IN
    assert ask(plotter, clock, b"IN;OI;") == b"7475A\r"
    for model, ident in (("hp7550a", b"7550A\r"), ("hp7440a", b"7440A\r")):
        plotter, clock = make(model)
        assert ask(plotter, clock, b"OI;") == ident


def test_power_up_status_24_and_the_initialized_bit_clears_when_read():
    # 7470A manual p. 7-8: power-up status 24 = initialized (8) + ready (16); bit 3 clears after output
    plotter, clock = make()
    assert ask(plotter, clock, b"OS;OS;IN;OS;") == b"24\r16\r24\r"


def test_oe_reports_and_clears_the_error():
    plotter, clock = make()
    # unknown instruction -> error 1; the error bit (32) shows in OS until OE is read
    assert ask(plotter, clock, b"ZZ;OS;OE;OE;OS;") == b"56\r1\r0\r16\r"


@pytest.mark.parametrize(
    "stream, code",
    [
        (b"IP1,2,3;", 2),  # wrong number of parameters
        (b"SP9;", 3),  # 6-pen carousel
        (b"VS97;", 3),  # 7470A manual: velocities >= 97 are error 3
        (b"SC0,0,1,2;", 3),
        (b"LT7;", 3),
        (b"CS9;", 5),  # unknown character set
        (b"PA40000,0;", 3),  # coordinate parameter outside -32768..32767
        (b"PA32000,0;PR1000,0;", 6),  # position overflow
        (b"OT;", 1),  # the 7475A has no OT
    ],
)
def test_error_numbers(stream, code):
    plotter, clock = make()
    assert ask(plotter, clock, b"IN;" + stream + b"OE;") == b"%d\r" % code


def test_position_overflow_sets_the_os_error_bit_as_the_input_mask_says():
    # OE reports 6 either way; the default IM e-mask (223) leaves error 6 out of the OS error bit, IM255 puts it in
    plotter, clock = make()
    assert ask(plotter, clock, b"IN;OS;PA32000,0;PR1000,0;OS;OE;") == b"24\r16\r6\r"
    assert ask(plotter, clock, b"IM255;PA32000,0;PR1000,0;OS;OE;OS;") == b"48\r6\r16\r"


def test_model_specific_instructions():
    plotter, clock = make("hp7550a")
    assert ask(plotter, clock, b"IN;OT;PS0;OH;FS4;OE;") == b"1,255\r0,0,15970,10870\r0\r"
    plotter, clock = make("hp7550a", pens="black,red")
    assert ask(plotter, clock, b"OT;") == b"1,3\r"
    plotter, clock = make("hp7440a")
    assert ask(plotter, clock, b"OD;OE;") == b"1\r"  # no digitizing on the 7440A
    plotter, clock = make("hp7440a")
    assert ask(plotter, clock, b"IN;PS4;OE;") == b"1\r"  # not in the 7440A's HP-GL


def test_a_vpype_hp7475a_file_plots_in_full():
    # vpype write --device hp7475a --page-size a4: IN;DF;PS4; first (chiplotle3's 7475A list has PS too)
    plotter, clock = make()
    ask(plotter, clock, b"IN;DF;PS4;SP1;PU1000,1000;PD2000,1000,2000,2000;PU;SP0;IN;PU11040,7721;")
    assert plotter.error_log == []
    assert np.allclose(segments(plotter), [[1000, 1000, 2000, 1000], [2000, 1000, 2000, 2000]])
    # a model without PS reports error 1 (OE, the OS error bit, ESC.E untouched) and plots the rest
    plotter, clock = make("hp7440a")
    assert ask(plotter, clock, b"IN;DF;PS4;SP1;PU1000,1000;PD2000,1000;PU;OS;OE;OE;") == b"56\r1\r0\r"
    assert np.allclose(segments(plotter), [[1000, 1000, 2000, 1000]])


def test_a_bare_pd_leaves_a_dot():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA1500,1200;PD;PU;PD;PD;PU;PA3000,1200;PD;PA3000,1500;PU;")
    # two touches at one point make one dot; a dot a line then starts from is part of the line
    assert np.allclose(segments(plotter), [[1500, 1200, 1500, 1200], [3000, 1200, 3000, 1500]])
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;IW2000,2000,4000,4000;PA1500,1200;PD;PU;")
    assert len(segments(plotter)) == 0  # outside the window: the pen does not come down there


def test_output_factors_window_options():
    plotter, clock = make()
    assert ask(plotter, clock, b"IN;OF;OW;IW100,200,3000,4000;OW;OO;") == (
        b"40,40\r0,0,11040,7721\r100,200,3000,4000\r0,1,0,0,1,0,0,0\r"
    )


def test_op_sets_and_clears_the_p1_p2_changed_bit():
    plotter, clock = make()
    assert ask(plotter, clock, b"IN;OS;IP100,200;OS;OP;OS;") == b"24\r18\r100,200,10100,7400\r16\r"


def test_digitize_point_and_od():
    plotter, clock = make()
    assert ask(plotter, clock, b"IN;PA300,400;DP;OS;OD;OS;") == b"28\r300,400,0\r16\r"


# -- geometry -----------------------------------------------------------------------------------


def test_pa_pr_vectors_in_plotter_units():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA100,100;PD200,100,200,300;PR-100,0,0,-200;PU;")
    np.testing.assert_allclose(
        segments(plotter),
        [[100, 100, 200, 100], [200, 100, 200, 300], [200, 300, 100, 300], [100, 300, 100, 100]],
    )


def test_vpype_golden_output_plots_one_relative_stroke():
    # plotters.md §1.6: vpype's golden HP-GL for one path
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;DF;SP1;PU2,3;PR;PD4,1;PA;PU;SP0;IN;OE;OA;")
    np.testing.assert_allclose(segments(plotter), [[2, 3, 6, 4]])
    assert out == b"0\r6,4,0\r" and plotter.selected_pen == 0


def test_separator_free_producer_stream_executes_cleanly():
    plotter, clock = make()
    assert ask(plotter, clock, b"INCA2IP0,0,10300,7650DI0,1SP2PA100,100PD200,200PUOE") == b"0\r"
    np.testing.assert_allclose(segments(plotter), [[100, 100, 200, 200]])


def test_sc_scaling_maps_user_units_between_p1_and_p2():
    plotter, clock = make()
    # P1=(1000,1000), P2=(3000,2000); SC0,100,0,50: 20 plotter units per user unit in x and in y
    out = ask(plotter, clock, b"IN;SP1;IP1000,1000,3000,2000;SC0,100,0,50;PA10,10;PD20,20;OC;OA;PR5,0;OC;")
    np.testing.assert_allclose(segments(plotter), [[1200, 1200, 1400, 1400], [1400, 1400, 1500, 1400]])
    assert out == b"20,20,1\r1400,1400,1\r25,20,1\r"


def test_circle_with_90_degree_chords_is_a_square_of_its_radius():
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;SP1;PA1000,1000;CI100,90;OA;")
    # positive radius starts at 0 degrees, counter-clockwise; the pen returns, up, to the centre
    np.testing.assert_allclose(
        segments(plotter),
        [[1100, 1000, 1000, 1100], [1000, 1100, 900, 1000], [900, 1000, 1000, 900], [1000, 900, 1100, 1000]],
        atol=1e-9,
    )
    assert out == b"1000,1000,0\r"


def test_circle_default_chord_angle_is_5_degrees_and_negative_radius_starts_at_180():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA2000,2000;CI-300;")
    seg = segments(plotter)
    assert len(seg) == 72
    np.testing.assert_allclose(seg[0, :2], [1700, 2000], atol=1e-9)
    np.testing.assert_allclose(np.hypot(seg[:, 0] - 2000, seg[:, 1] - 2000), 300)
    ends = np.arctan2(seg[:, 3] - 2000, seg[:, 2] - 2000)
    step = np.degrees(ends - np.arctan2(seg[:, 1] - 2000, seg[:, 0] - 2000)) % 360
    np.testing.assert_allclose(step, 5.0)


def test_arcs_absolute_and_relative():
    r = 100 / math.sqrt(2)
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;SP1;PA1100,1000;PD;AA1000,1000,90,45;OA;")
    np.testing.assert_allclose(segments(plotter), [[1100, 1000, 1000 + r, 1000 + r], [1000 + r, 1000 + r, 1000, 1100]],
                               atol=1e-9)
    assert out == b"1000,1100,1\r"
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;SP1;PA1100,1000;PD;AR-100,0,-90,45;OA;")  # clockwise
    np.testing.assert_allclose(segments(plotter)[-1], [1000 + r, 1000 - r, 1000, 900], atol=1e-9)
    assert out == b"1000,900,1\r"


def test_edge_rectangle_returns_the_pen_to_its_corner():
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;SP1;PA100,100;EA300,200;OA;ER-50,-50;")
    np.testing.assert_allclose(
        segments(plotter)[:4], [[100, 100, 300, 100], [300, 100, 300, 200], [300, 200, 100, 200], [100, 200, 100, 100]]
    )
    assert out == b"100,100,0\r"
    assert len(segments(plotter)) == 8


def test_hatch_and_crosshatch_fill_of_a_rectangle():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA0,0;FT3,100,0;RA1000,1000;")
    seg = segments(plotter)
    # 10 horizontal lines 100 apart, centred in the 1000-unit height: y = 50, 150, ..., 950, each 0..1000
    np.testing.assert_allclose(np.sort(seg[:, 1]), np.arange(50, 1000, 100))
    np.testing.assert_allclose(np.sort(np.abs(seg[:, 2] - seg[:, 0])), 1000)
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA0,0;FT4,250;RR1000,500;")
    seg = segments(plotter)
    horizontal = seg[np.isclose(seg[:, 1], seg[:, 3])]
    vertical = seg[np.isclose(seg[:, 0], seg[:, 2])]
    assert len(horizontal) == 2 and len(vertical) == 4  # 500/250 and 1000/250 lines


def test_solid_fill_line_spacing_is_the_pen_thickness():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PT0.5;PA0,0;FT1;RA1000,400;")
    seg = segments(plotter)
    ys = np.unique(np.round(seg[seg[:, 1] == seg[:, 3]][:, 1], 6))
    np.testing.assert_allclose(np.diff(ys), 0.5 / UNIT_MM)


def test_wedge_fill_stays_inside_its_sector():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA5000,4000;FT3,50,45;WG1000,0,90;")
    pts = segments(plotter).reshape(-1, 2) - [5000, 4000]
    assert np.all(pts >= -1e-6) and np.all(np.hypot(pts[:, 0], pts[:, 1]) <= 1000 + 1e-6)


def test_line_type_dash_lengths_follow_the_manual_percentages():
    diagonal = math.hypot(10603 - 603, 7721 - 521)  # default A4 P1-P2
    period = 0.02 * diagonal  # LT2,2: pattern length 2 % of the diagonal; 50 % down, 50 % up
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;LT2,2;PA0,0;PD1000,0;")
    seg = segments(plotter)
    starts = np.arange(0, 1000, period)
    np.testing.assert_allclose(seg[:, 0], starts)
    np.testing.assert_allclose(seg[:, 2], np.minimum(starts + period / 2, 1000))
    # the pattern runs on from one vector into the next (the residue carries over): 400 falls in a gap,
    # so two vectors 0-400-1000 ink exactly what one vector 0-1000 does
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;LT2,2;PA0,0;PD400,0,1000,0;")
    np.testing.assert_allclose(segments(plotter), seg)


def test_line_type_4_has_a_dot_and_lt0_marks_only_end_points():
    diagonal = math.hypot(10000, 7200)
    period = 0.04 * diagonal  # default pattern length: 4 %
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;LT4;PA0,0;PD%d,0;" % round(period * 3 - 1))
    seg = segments(plotter)
    lengths = seg[:, 2] - seg[:, 0]
    # 80 % dash, 10 % gap, 0 % dot, 10 % gap
    np.testing.assert_allclose(lengths[:4], [0.8 * period, 0.0, 0.8 * period, 0.0])
    np.testing.assert_allclose(seg[1, 0], 0.9 * period)
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;LT0;PA0,0;PD100,0,100,100;")
    np.testing.assert_allclose(segments(plotter), [[100, 0, 100, 0], [100, 100, 100, 100]])


def test_window_clips_strokes():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;IW0,0,500,500;PA0,250;PD1000,250;")
    np.testing.assert_allclose(segments(plotter), [[0, 250, 500, 250]])


def test_rotation_90_turns_the_coordinate_system():
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;RO90;OH;SP1;PA0,0;PD100,0;")
    assert out == b"0,0,7721,11040\r"
    # logical x runs along physical +y from the lower-right corner
    np.testing.assert_allclose(segments(plotter), [[11040, 0, 11040, 100]])


def test_edge_wedge_outline():
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;SP1;PA1000,1000;EW100,0,90,90;OA;")
    np.testing.assert_allclose(
        segments(plotter), [[1000, 1000, 1100, 1000], [1100, 1000, 1000, 1100], [1000, 1100, 1000, 1000]], atol=1e-9
    )
    assert out == b"1000,1000,0\r"


def test_tick_marks_are_half_a_percent_of_p1_p2_by_default():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA1000,1000;XT;YT;")
    # default P1-P2 on A4: 10000 x 7200 plotter units; TL default 0.5 % up/right and 0.5 % down/left
    np.testing.assert_allclose(segments(plotter), [[1000, 1036, 1000, 964], [1050, 1000, 950, 1000]])


def test_user_defined_character_grid():
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;SP1;SI0.4,0.8;PA1000,1000;UC99,4,8,-99,4,-8;OC;")
    w, h = 4.0 / UNIT_MM, 8.0 / UNIT_MM  # increments: x in width/4, y in height/8 (7470A UC grid)
    np.testing.assert_allclose(segments(plotter), [[1000, 1000, 1000 + w, 1000 + h]])
    assert out == b"%d,1000,0\r" % round(1000 + 1.5 * w)  # then one character cell on


def test_oc_reports_user_units_with_decimals_when_scaled():
    plotter, clock = make()
    assert ask(plotter, clock, b"IN;SC0,3,0,3;PA1,1;PR0.5,0;OC;SC;OC;") == b"1.5,1,0\r%d,%d,0\r" % (
        round(603 + 1.5 * 10000 / 3), round(521 + 7200 / 3)
    )


# -- labels -----------------------------------------------------------------------------------


def test_label_character_size_and_advance():
    w, h = 5.0 / UNIT_MM, 10.0 / UNIT_MM  # SI0.5,1: 0.5 cm wide, 1 cm high
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;SP1;SI0.5,1;PA1000,1000;LBH\x03OC;")
    seg = segments(plotter)
    assert seg[:, 0::2].min() == pytest.approx(1000) and seg[:, 0::2].max() == pytest.approx(1000 + w)
    assert seg[:, 1::2].min() == pytest.approx(1000) and seg[:, 1::2].max() == pytest.approx(1000 + h)
    assert out == b"%d,1000,0\r" % round(1000 + 1.5 * w)  # character cell 1.5 x width


def test_label_direction_line_feed_and_cp():
    w, h = 5.0 / UNIT_MM, 10.0 / UNIT_MM
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;SP1;SI0.5,1;DI0,1;PA5000,1000;LBAB\x03OC;")
    assert out == b"5000,%d,0\r" % round(1000 + 3 * w)
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;SP1;SI0.5,1;PA1000,5000;LBAB\r\nC\x03OC;CP2,1;OC;")
    # CR returns to the start of the line, LF goes one line (2 x height) down, then C advances one cell
    assert out == b"%d,%d,0\r%d,%d,0\r" % (
        round(1000 + 1.5 * w), round(5000 - 2 * h), round(1000 + 4.5 * w), round(5000 - 2 * h + 2 * h)
    )


def test_relative_size_default_equals_absolute_default_with_default_p1_p2():
    # 7470A manual, SR: "SR with no parameters ... when P1 and P2 are at default values, produces letters
    # the same size as an SI command without parameters"
    a, ca = make()
    ask(a, ca, b"IN;SP1;PA2000,2000;SI;LBHE\x03")
    b, cb = make()
    ask(b, cb, b"IN;SP1;PA2000,2000;SR;LBHE\x03")
    np.testing.assert_allclose(segments(a), segments(b), atol=0.6)


def test_label_terminator_change_and_slant():
    plotter, clock = make()
    out = ask(plotter, clock, b"IN;SP1;DT*;SI0.5,1;SL1;PA0,0;LBH*OC;")
    seg = segments(plotter)
    # SL1 leans 45 degrees: the top of the H sits one height to the right
    assert seg[:, 0::2].max() == pytest.approx(5.0 / UNIT_MM + 10.0 / UNIT_MM)
    assert out == b"%d,0,0\r" % round(7.5 / UNIT_MM)


def test_symbol_mode_marks_every_point():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;SM*;PU100,100,2000,2000;")
    seg = segments(plotter)
    near_first = np.hypot(seg[:, 0] - 100, seg[:, 1] - 100) < 200
    near_second = np.hypot(seg[:, 0] - 2000, seg[:, 1] - 2000) < 200
    assert near_first.any() and near_second.any() and np.all(near_first | near_second)


# -- time ------------------------------------------------------------------------------------------


def test_pen_down_move_takes_the_trapezoid_time_at_the_default_velocity_and_acceleration():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA0,0;PD;")
    t0 = clock.now()
    plotter.receive(b"PD10000,0;")
    # 7470A manual, VS: default 38.1 cm/s and 2 g
    assert plotter.next_event_time() - t0 == pytest.approx(move_time(10000, 38.1, 2 * 980))
    finish(plotter, clock)
    t0 = clock.now()
    plotter.receive(b"PD0,0;")  # a vertical or horizontal move is the slowest: diagonals are not slower
    t_back = plotter.next_event_time() - t0
    finish(plotter, clock)
    t0 = clock.now()
    plotter.receive(b"PD10000,10000;")
    assert plotter.next_event_time() - t0 == pytest.approx(t_back)


def test_vs_rounds_to_0_38_cm_s_steps_and_slows_acceleration_to_half_a_g():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;VS10;PA0,0;PD;")
    t0 = clock.now()
    plotter.receive(b"PD5000,0;")
    assert plotter.next_event_time() - t0 == pytest.approx(move_time(5000, 26 * 0.38, 0.5 * 980))


def test_commands_leave_the_buffer_as_they_execute():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;")
    plotter.receive(b"PA10000,7000;")  # starts moving at once: its bytes have left the buffer
    n = 120
    plotter.receive(b"PD1,1;" * (n // 6) + ESC + b".B")
    assert plotter.take_output() == b"%d\r" % (1024 - n)
    plotter.receive(b"PD1,1;")
    assert plotter.free_bytes == 1024 - n - 6
    finish(plotter, clock)
    assert plotter.free_bytes == 1024


def test_buffered_outputs_wait_for_earlier_graphics():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;")
    plotter.receive(b"PA10000,7000;OA;" + ESC + b".B")
    assert plotter.take_output() == b"1021\r"  # ESC.B answers at once; "OA;" is still in the buffer
    finish(plotter, clock)
    assert plotter.take_output() == b"10000,7000,0\r"


def test_starved_time_counts_the_gap_the_host_left():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA1000,0;")
    advance(plotter, clock, 5.0)
    plotter.receive(b"PA2000,0;")
    finish(plotter, clock)
    assert plotter.stats.starved_time == pytest.approx(5.0)
    assert plotter.stats.commands_executed == 4
    assert [c for _, c in plotter.command_log] == ["IN", "SP1", "PA1000,0", "PA2000,0"]


# -- buffer, overflow and handshakes --------------------------------------------------------------


def busy(**options: str) -> tuple[HPGLPlotter, SimulatedClock]:
    """A plotter in the middle of a long pen-up move, so nothing leaves the buffer for a while."""
    plotter, clock = make(**options)
    ask(plotter, clock, b"IN;SP1;")
    plotter.receive(b"PA11000,7700;")
    return plotter, clock


def test_overflow_with_handshake_off_loses_bytes_and_sets_esc_e_16():
    plotter, clock = busy(reserve_bug="false")
    plotter.receive(b"PD1,1;" * 200)  # 1200 bytes into 1024
    assert plotter.stats.bytes_overflowed == 176
    assert ask(plotter, clock, ESC + b".E" + ESC + b".E") == b"16\r0\r"  # ESC.E clears on read


def test_reserve_bug_overflows_when_filled_to_the_exact_esc_b_figure():
    # plotters.md §1.5: a 7475A reported 252 free and a 252-byte write still gave ESC.E 16
    plotter, clock = busy()
    plotter.receive(ESC + b".B")
    free = int(plotter.take_output())
    plotter.receive(b" " * (free - 1))
    assert plotter.take_output() == b"" and plotter.stats.bytes_overflowed == 0
    plotter.receive(b" ")
    assert plotter.stats.bytes_overflowed == 1
    plotter.receive(ESC + b".E")
    assert plotter.take_output() == b"16\r"
    plotter, clock = busy(reserve_bug="false")
    plotter.receive(b" " * plotter.free_bytes)
    assert plotter.stats.bytes_overflowed == 0
    assert ask(plotter, clock, ESC + b".B" + ESC + b".E") == b"0\r0\r"


def test_device_control_works_with_a_full_buffer_and_esc_k_flushes_it():
    plotter, _ = busy(reserve_bug="false")
    plotter.receive(b"PD1,1;" * 200)
    plotter.receive(ESC + b".B" + ESC + b".O")
    assert plotter.take_output() == b"0\r0\r"
    plotter.receive(ESC + b".K" + ESC + b".B")
    assert plotter.take_output() == b"1024\r"


def test_hardwire_handshake_follows_the_block_size():
    plotter, clock = busy()
    assert plotter.ready_to_receive  # handshake off: the line is held high
    plotter.receive(ESC + b".@;1:")
    plotter.receive(b" " * (plotter.free_bytes - 80))
    assert plotter.free_bytes == 80 and plotter.ready_to_receive
    plotter.receive(b" ")
    assert not plotter.ready_to_receive
    finish(plotter, clock)
    assert plotter.ready_to_receive


def xon_xoff_run(threshold: int) -> tuple[list[int], int]:
    """Fill a busy plotter to just above the threshold, cross it, then drain; return frees seen and XON free."""
    plotter, clock = busy(reserve_bug="false")
    plotter.receive(ESC + b".I%d;;17:" % threshold + ESC + b".N;19:")
    filler = b"PD1,1;" * 200
    plotter.receive(filler[: plotter.free_bytes - threshold] + b" " * 6)
    # (6 separator bytes pad whatever instruction the cut left open)
    plotter.receive(b"")
    assert plotter.take_output() == b"\x13"  # the padding took free space below the threshold
    assert threshold - 6 <= plotter.free_bytes < threshold
    frees = []
    for _ in range(1000):
        t = plotter.next_event_time()
        assert t is not None, "XON never came"
        advance(plotter, clock, t - clock.now())
        out = plotter.take_output()
        frees.append(plotter.free_bytes)
        if out:
            assert out == b"\x11"
            return frees, plotter.free_bytes
    raise AssertionError("XON never came")


def test_xon_xoff_thresholds():
    # 7470A manual p. 10-20: Xoff below the threshold, Xon at 128 free, or threshold + 1 when that is larger
    frees, xon_free = xon_xoff_run(81)
    assert xon_free >= 128 and all(f < 128 for f in frees[:-1])
    frees, xon_free = xon_xoff_run(200)
    assert xon_free >= 201 and all(f < 201 for f in frees[:-1])


def test_enq_ack_handshakes():
    plotter, clock = make()
    assert ask(plotter, clock, ESC + b".I80;5;6:\x05") == b"\x06"  # mode 2: the acknowledgement alone
    plotter, clock = make()
    assert ask(plotter, clock, ESC + b".H80;5;6:\x05") == b"\x06\r"  # mode 1: with the output terminator
    plotter, clock = busy()
    plotter.receive(ESC + b".I100;5;6:" + b" " * (plotter.free_bytes - 50) + b"\x05")
    assert plotter.take_output() == b""  # no room for a block: the ACK waits
    finish(plotter, clock)
    assert plotter.take_output() == b"\x06"


def test_output_mode_terminator_turnaround_and_trigger():
    plotter, clock = make()
    assert ask(plotter, clock, ESC + b".M;;;10:OS;") == b"24\n"
    plotter, clock = make()
    plotter.receive(ESC + b".M100:" + ESC + b".B")
    assert plotter.take_output() == b""
    delay = ((100 * 1.1875) % 65536) / 1.2 / 1000  # 7470A manual p. 10-33
    assert plotter.next_event_time() - clock.now() == pytest.approx(delay)
    finish(plotter, clock)
    assert plotter.take_output() == b"1024\r"
    plotter, clock = make()
    plotter.receive(ESC + b".M;63:OS;")
    finish(plotter, clock)
    assert plotter.take_output() == b""
    plotter.receive(b"?")  # the output trigger character releases the answer
    assert plotter.take_output() == b"24\r"


def test_second_output_while_one_is_going_out_is_esc_e_10():
    plotter, clock = make()
    plotter.receive(ESC + b".M1000:OS;OS;")
    finish(plotter, clock)
    assert plotter.take_output() == b"24\r"
    assert ask(plotter, clock, ESC + b".M:" + ESC + b".E") == b"10\r"


def test_device_control_errors_reach_esc_e():
    plotter, clock = make()
    assert ask(plotter, clock, ESC + b".X" + ESC + b".E") == b"11\r"
    assert ask(plotter, clock, ESC + b".@1;2;3:" + ESC + b".E") == b"14\r"
    assert ask(plotter, clock, ESC + b".M;;;;;200:" + ESC + b".E") == b"13\r"


def test_plotter_off_ignores_everything_but_on():
    plotter, clock = make()
    assert ask(plotter, clock, ESC + b".)IN;OI;" + ESC + b".B" + ESC + b".(" + ESC + b".B") == b"1024\r"
    assert plotter.stats.bytes_ignored == len(b"IN;OI;")


# -- faults ---------------------------------------------------------------------------------------


def test_power_loss_mid_stroke_keeps_the_inked_part_and_answers_nothing_until_reset():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA0,0;PD;")
    t0 = clock.now()
    plotter.receive(b"PD10000,0;OS;")
    half = (plotter.next_event_time() - t0) / 2
    advance(plotter, clock, half)
    plotter.inject("power-loss")
    np.testing.assert_allclose(segments(plotter), [[0, 0, 5000, 0]])  # symmetric trapezoid: half way
    plotter.receive(b"IN;OI;" + ESC + b".B")
    advance(plotter, clock, 10)
    assert plotter.take_output() == b"" and not plotter.ready_to_receive and plotter.next_event_time() is None
    plotter.inject("reset")
    assert ask(plotter, clock, b"OS;" + ESC + b".B") == b"24\r1024\r"
    assert len(segments(plotter)) == 1  # the paper survives


def test_paper_lever_pauses_and_release_resumes():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA0,0;PD;")
    plotter.receive(b"PD1000,0,1000,1000,0,1000,0,0;")
    plotter.inject("paper-lever")
    advance(plotter, clock, 60)
    assert len(segments(plotter)) == 1  # the vector under way finishes, then plotting holds
    assert ask(plotter, clock, ESC + b".O") == b"32\r"
    plotter.release_paper_lever()
    finish(plotter, clock)
    assert len(segments(plotter)) == 4
    assert ask(plotter, clock, ESC + b".O") == b"8\r"


def test_view_button_pauses_and_toggles():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;PA0,0;PD;")
    plotter.receive(b"PD1000,0,1000,1000;")
    plotter.inject("pause-button")
    advance(plotter, clock, 60)
    assert ask(plotter, clock, ESC + b".O") == b"16\r"
    plotter.press_view()
    finish(plotter, clock)
    assert len(segments(plotter)) == 2 and ask(plotter, clock, ESC + b".O") == b"8\r"


def test_unknown_fault_is_a_config_error():
    plotter, _ = make()
    with pytest.raises(ConfigError, match="power-loss"):
        plotter.inject("lightning")


# -- paper --------------------------------------------------------------------------------------


def test_display_list_joins_touching_strokes_per_pen():
    plotter, clock = make(pens="black,red")
    ask(plotter, clock, b"IN;SP1;PA0,0;PD100,0,100,100;PU;SP2;PD200,100;SP3;PD300,300;")
    dl = plotter.display_list()
    assert len(dl) == 2 and list(dl.pens) == [1, 2]  # pen 3's stall is empty: it plots dry
    np.testing.assert_allclose(dl.stroke(0), [[0, 0], [100, 0], [100, 100]])
    assert dl.unit_mm == UNIT_MM and dl.pen_colours[2] == "#ff0000"


def test_paper_image_renders_strokes_in_pen_colours():
    pytest.importorskip("pixelpen.raster.canvas")
    plotter, clock = make(pens="black,#ff0000")
    ask(plotter, clock, b"IN;SP2;PA0,4000;PD11040,4000;")
    canvas = plotter.paper_image(dpi=50)
    img = np.asarray(canvas.array)
    assert img.shape == (round(210 / 25.4 * 50), round(297 / 25.4 * 50), 3)
    y = img.shape[0] - int((4.0 + 4000 * UNIT_MM) / 25.4 * 50) - 1
    row = img[max(0, y - 1) : y + 2]
    assert np.any(np.all(row == [255, 0, 0], axis=-1))
    assert np.all(img[0, 0] == 255)


def test_save_paper_writes_a_png_of_the_sheet(tmp_path):
    pytest.importorskip("pixelpen.raster.canvas")
    from PIL import Image

    plotter, clock = make("hp7440a", paper="letter", pens="black,red,#00ff00")
    ask(plotter, clock, b"IN;SP3;PA0,0;PD10365,7962;")
    plotter.save_paper(tmp_path / "sheet.png", dpi=40)
    with Image.open(tmp_path / "sheet.png") as image:
        assert image.size == (round(279.4 / 25.4 * 40), round(215.9 / 25.4 * 40))
        colours = {c for _, c in image.convert("RGB").getcolors(1 << 16)}
    assert (0, 255, 0) in colours
    with pytest.raises(ConfigError, match="dpi"):
        plotter.paper_image(dpi=0)


# -- end to end through pyserial ---------------------------------------------------------------------


def test_sim_url_through_pyserial():
    serial = pytest.importorskip("serial")
    pytest.importorskip("pixelpen.sim.transports.urlhandler.protocol_sim")
    import pixelpen.sim.transports.urlhandler  # noqa: F401 - registers sim://

    port = serial.serial_for_url("sim://hp7475a?paper=a3&speed=fast", timeout=5)
    try:
        port.write(b"IN;OI;OH;SP1;PA1000,1000;PD2000,1000;OA;")
        assert port.read_until(b"\r") == b"7475A\r"
        assert port.read_until(b"\r") == b"0,0,16158,11040\r"
        assert port.read_until(b"\r") == b"2000,1000,1\r"
    finally:
        port.close()


# -- robustness ------------------------------------------------------------------------------------


def check_invariants(plotter: HPGLPlotter, clock: SimulatedClock) -> None:
    assert 0 <= plotter.free_bytes <= plotter.buffer_size
    t = plotter.next_event_time()
    assert t is None or t >= plotter.now - 1e-9
    for _, kind, code, _ in plotter.error_log:
        assert code in ((1, 2, 3, 5, 6) if kind == "HP-GL" else (10, 11, 12, 13, 14, 16))


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.binary(max_size=200), st.floats(0, 5)), max_size=8))
def test_random_bytes_never_crash_or_hang(chunks):
    plotter, clock = make()
    for data, dt in chunks:
        plotter.receive(data)
        plotter.take_output()
        advance(plotter, clock, dt)
        check_invariants(plotter, clock)
    plotter.receive(ESC + b".K")  # whatever the stream left, the plotter returns to idle
    finish(plotter, clock, limit=200_000)
    check_invariants(plotter, clock)


commands = st.one_of(
    st.sampled_from(
        [b"IN;", b"DF;", b"SP1;", b"SP2;", b"PU;", b"PD;", b"OS;", b"OE;", b"OA;", b"OC;", b"LT;", b"LT2;",
         b"FT3,80,45;",
         b"SC0,100,0,100;", b"SC;", b"IP;", b"RO90;", b"RO;", b"DI0,1;", b"SI0.3,0.5;", b"SL0.5;", b"CP1,1;", b"VS5;",
         b"IW0,0,5000,5000;", b"DT#;", b"SM*;", b"SM;", b"XT;", b"TL2,2;", b"UC99,4,8,-99,4,0;", b"PT1;", b"IM255;",
         ESC + b".B", ESC + b".O", ESC + b".E", ESC + b".@;1:", ESC + b".I81;;17:", ESC + b".N;19:", ESC + b".K",
         ESC + b".M;;;10:", ESC + b".R", ESC + b".)", ESC + b".(", b"\x05", b"\x03", b"#"]
    ),
    st.builds(lambda m, a, b: b"%s%d,%d;" % (m, a, b),
              st.sampled_from([b"PA", b"PR", b"PD", b"PU", b"EA", b"ER", b"RA", b"RR"]),
              st.integers(-40000, 40000), st.integers(-40000, 40000)),
    st.builds(lambda r, c: b"CI%d,%d;" % (r, c), st.integers(-2000, 2000), st.integers(-400, 400)),
    st.builds(lambda x, y, a: b"AA%d,%d,%d;" % (x, y, a), st.integers(-5000, 5000), st.integers(-5000, 5000),
              st.integers(-720, 720)),
    st.builds(lambda r, a, b: b"WG%d,%d,%d;" % (r, a, b), st.integers(-3000, 3000), st.integers(-360, 360),
              st.integers(-400, 400)),
    st.builds(lambda t: b"LB" + t + b"\x03",
              st.text("AZaz09 .,;\r\n\x08", max_size=20).map(lambda s: s.encode("latin-1"))),
)


@settings(max_examples=40, deadline=None)
@given(st.lists(commands, min_size=1, max_size=25), st.data())
def test_valid_ish_streams_cut_anywhere_never_crash_or_hang(parts, data):
    stream = b"".join(parts)
    cut = data.draw(st.integers(0, len(stream)))
    stream = stream[:cut]
    step = data.draw(st.integers(1, 64))
    model = data.draw(st.sampled_from(["hp7475a", "hp7550a", "hp7440a"]))
    plotter, clock = make(model)
    for i in range(0, len(stream), step):
        plotter.receive(stream[i : i + step])
        advance(plotter, clock, data.draw(st.floats(0, 2)))
        plotter.take_output()
        check_invariants(plotter, clock)
    plotter.receive(ESC + b".(" + ESC + b".K")
    finish(plotter, clock, limit=500_000)
    check_invariants(plotter, clock)
    seg = segments(plotter)
    assert np.isfinite(seg).all()
    w, h = plotter.paper.hard_clip
    assert np.all(seg[:, 0::2] >= -1e-6) and np.all(seg[:, 0::2] <= w + 1e-6)
    assert np.all(seg[:, 1::2] >= -1e-6) and np.all(seg[:, 1::2] <= h + 1e-6)


def test_oversized_label_streams_through_the_buffer():
    plotter, clock = make()
    ask(plotter, clock, b"IN;SP1;SI0.1,0.15;PA100,7000;")
    text = b"LB" + (b"HELLO " * 5 + b"\r\n") * 34  # 1090 bytes of label: more than the buffer holds
    for i in range(0, len(text), 64):
        while plotter.free_bytes <= 64:  # keep one byte of reserve (plotters.md §1.5)
            advance(plotter, clock, 0.05)
        plotter.receive(text[i : i + 64])
    plotter.receive(b"\x03OE;")
    finish(plotter, clock)
    assert plotter.take_output() == b"0\r"
    assert plotter.stats.bytes_overflowed == 0

"""HP-GL/1 encoder: byte-exact instructions from the manual's syntax, vpype's golden file, splitting, bad input."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.devices.plotters import hpgl_encode as enc
from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList


def test_vpype_golden_file_in_absolute_form():
    # vpype tests/test_hpgl.py golden: IN;DF;SP1;PU2,3;PR;PD4,1;PA;PU;SP0;IN; -- one line from (2,3) by (+4,+1).
    # Absolute form of the same drawing (vpype --absolute) is IN;DF;SP1;PU2,3;PD6,4;PU;SP0;IN;  pixelpen leaves
    # out DF (IN already defaults everything) and the final IN (it would undo PS/VS for a following job).
    dl = DisplayList.from_polylines([np.array([[2, 3], [6, 4]])], pens=1)
    assert enc.program(dl) == b"IN;SP1;PU2,3;PD6,4;PU;SP0;"


def test_square_as_the_manual_writes_it():
    # 7470A manual PU/PD examples: pen up to the first corner, then one PD with the remaining X,Y pairs
    square = np.array([[1000, 1000], [3000, 1000], [3000, 3000], [1000, 3000], [1000, 1000]])
    assert enc.stroke(square) == [b"PU1000,1000;", b"PD3000,1000,3000,3000,1000,3000,1000,1000;"]


def test_negative_and_extreme_coordinates_are_plain_decimal():
    pts = np.array([[-32768, 32767], [0, -1]])
    assert b"".join(enc.stroke(pts)) == b"PU-32768,32767;PD0,-1;"


def test_single_point_is_a_zero_length_vector():
    assert enc.stroke(np.array([[5, 7]])) == [b"PU5,7;", b"PD5,7;"]


def test_float_points_with_whole_values_are_accepted():
    assert enc.stroke(np.array([[1.0, 2.0], [3.0, -4.0]])) == [b"PU1,2;", b"PD3,-4;"]


def test_long_pd_lists_split_at_pairs_within_the_limit():
    pts = np.array([[i * 1000, 20000 + i] for i in range(8)])
    out = enc.stroke(pts, max_length=32)
    # pairs: "1000,20001" (10) "2000,20002" ... each PD: "PD" + pairs + commas + ";" <= 32 -> two pairs each
    assert out == [
        b"PU0,20000;",
        b"PD1000,20001,2000,20002;",
        b"PD3000,20003,4000,20004;",
        b"PD5000,20005,6000,20006;",
        b"PD7000,20007;",
    ]


_PAIR = re.compile(rb"(-?\d+),(-?\d+)")


def _parse(instructions: list[bytes]) -> tuple[np.ndarray, list[bytes]]:
    """Independent reading of PU/PD instructions back into points and mnemonics."""
    points, mnemonics = [], []
    for ins in instructions:
        assert ins.endswith(b";")
        mnemonics.append(ins[:2])
        points += [(int(x), int(y)) for x, y in _PAIR.findall(ins[2:-1])]
    return np.array(points), mnemonics


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.tuples(st.integers(-32768, 32767), st.integers(-32768, 32767)), min_size=2, max_size=80),
    st.integers(16, 200),
)
def test_split_strokes_round_trip_and_respect_the_limit(pairs, limit):
    pts = np.array(pairs)
    out = enc.stroke(pts, max_length=limit)
    assert all(len(i) <= limit for i in out)
    back, mnemonics = _parse(out)
    assert mnemonics[0] == b"PU" and set(mnemonics[1:]) == {b"PD"}
    assert np.array_equal(back, pts)


def test_out_of_range_point_names_stroke_and_point():
    with pytest.raises(ConfigError, match=r"stroke 7: point 1 \(40000, 1\) is outside the HP-GL range -32768..32767"):
        enc.stroke(np.array([[0, 0], [40000, 1]]), index=7)
    with pytest.raises(ConfigError, match="point 0"):
        enc.stroke(np.array([[-32769, 0]]))


@pytest.mark.parametrize(
    "points, message",
    [
        (np.array([[0.0, 0.5]]), "not a whole number"),
        (np.array([[np.nan, 0.0]]), "not a whole number"),
        (np.array([[np.inf, 0.0]]), "not a whole number"),
        (np.zeros((0, 2)), "has no points"),
        (np.zeros((3, 3)), r"expected \(N, 2\) points"),
        (np.array([["a", "b"]]), "must be numbers"),
    ],
)
def test_malformed_points_are_refused(points, message):
    with pytest.raises(ConfigError, match=message):
        enc.stroke(points, index=2)


def test_max_length_too_small_for_one_pair():
    with pytest.raises(ConfigError, match="max_length"):
        enc.stroke(np.array([[0, 0], [1, 1]]), max_length=10)


def test_initialize_paper_size_and_velocity():
    assert enc.initialize() == [b"IN;"]
    assert enc.initialize(4, 10) == [b"IN;", b"PS4;", b"VS10;"]
    assert enc.initialize(velocity_cm_s=12.5) == [b"IN;", b"VS12.5;"]
    assert enc.velocity(0.38) == b"VS0.38;"


@pytest.mark.parametrize("bad", [0, -1, float("nan"), float("inf")])
def test_bad_velocity(bad):
    with pytest.raises(ConfigError, match="VS"):
        enc.velocity(bad)


def test_bad_paper_size():
    with pytest.raises(ConfigError, match="PS"):
        enc.initialize(-1)


def test_select_pen():
    assert enc.select_pen(0) == b"SP0;"
    assert enc.select_pen(np.int32(6)) == b"SP6;"
    with pytest.raises(ConfigError, match="SP"):
        enc.select_pen(-1)


def test_trailer_stores_the_pen_then_parks():
    assert enc.trailer() == [b"PU;", b"SP0;"]
    assert b"".join(enc.trailer((11040, 7721))) == b"PU;SP0;PU11040,7721;"


def test_handshake_preambles_from_the_reference():
    # plotters.md §1.5: ESC.(;ESC.I81;;17:ESC.N;19: = plotter on, Xon/Xoff threshold 81, Xon DC1, Xoff DC3
    assert enc.handshake_preamble("xonxoff") == b"\x1b.(;\x1b.I81;;17:\x1b.N;19:"
    assert enc.handshake_preamble("hardwire") == b"\x1b.(;\x1b.@;1:"
    assert enc.handshake_preamble("escb") == b"\x1b.(;"
    with pytest.raises(ConfigError, match="escb, xonxoff, hardwire, none"):
        enc.handshake_preamble("enq")


def test_device_control_queries_are_escape_dot_letter():
    assert (enc.ASK_FREE, enc.ASK_IO_ERROR, enc.ASK_STATUS, enc.ABORT_GRAPHICS) == (
        b"\x1b.B", b"\x1b.E", b"\x1b.O", b"\x1b.K"
    )


def test_program_selects_pens_only_when_they_change():
    a, b = np.array([[0, 0], [10, 0]]), np.array([[0, 10], [10, 10]])
    dl = DisplayList.from_polylines([a, b, a, b], pens=[1, 1, 2, 1])
    assert enc.program(dl, paper_size=4, park=(100, 200)) == (
        b"IN;PS4;SP1;PU0,0;PD10,0;PU0,10;PD10,10;SP2;PU0,0;PD10,0;SP1;PU0,10;PD10,10;PU;SP0;PU100,200;"
    )


def test_program_names_the_bad_stroke():
    dl = DisplayList.from_polylines([np.array([[0, 0], [1, 1]]), np.array([[0, 0], [99999, 0]])], pens=1)
    with pytest.raises(ConfigError, match="stroke 1"):
        enc.program(dl)

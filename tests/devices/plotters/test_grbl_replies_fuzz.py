"""Fuzzing GRBL's reply parsers and the driver's reply handling: mutated replies give PixelpenErrors, never crashes."""

from __future__ import annotations

import numpy as np
import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.devices.plotters.grbl import GrblPlotter
from pixelpen.devices.plotters.grbl_encode import parse_code, parse_status, parse_welcome
from pixelpen.errors import PixelpenError
from pixelpen.vector.displaylist import DisplayList
from tests.devices.plotters.test_grbl import MM, PROFILE, FakeGrbl
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign

LINES = [
    b"<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>",
    b"<Run|MPos:12.345,-6.500,0.000|Bf:15,128|FS:3000,50|Ov:100,100,100|A:S>",
    b"<Hold:0|WPos:1.000,2.000,3.000|F:500|Pn:XYZ|Ln:99>",
    b"<Door:1|MPos:0.0000,0.0000,0.0000|FS:0.0,0>",
    b"<Alarm|MPos:-1.000,-1.000,-2.000|FS:0,0>",
    b"ok", b"error:22", b"ALARM:3", b"Grbl 1.1h ['$' for help]", b"[MSG:'$H'|'$X' to unlock]",
    b"[GC:G1 G54 G17 G21 G90 G94 M3 M9 T0 F3000 S50]", b"[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]",
    b"$100=80.000", b">G21:ok",
]
"""Reply lines from gnea/grbl doc/markdown/interface.md and commands.md (status, acks, alarms, messages, $$)."""


def _text(data: bytes) -> str:
    """As the driver reads a line: ASCII with replacement characters."""
    return data.decode("ascii", "replace")


def parse_any_line(data: bytes) -> None:
    """Every pure parser on the mutated line."""
    line = _text(data)
    parse_welcome(line)
    for parser in (parse_status, parse_code):
        try:
            parser(line)
        except PixelpenError:  # the clean refusal; anything else escapes to the campaign as a crash
            continue


STROKE = DisplayList.from_polylines([np.array([[20, 20], [30, 20], [30, 30]], float) * MM], unit_mm=PROFILE.unit_mm)


def plot_through_garbled_replies(data: bytes) -> None:
    """A plot while the mutated bytes arrive among GRBL's replies: it finishes or stops with a PixelpenError."""
    clock = SimulatedClock()
    fake = FakeGrbl(clock)
    plotter = GrblPlotter("fake", profile=PROFILE, clock=clock, link_factory=lambda: fake, timeout=0.5)
    plotter.open()
    try:
        fake.out += data + b"\r\n"
        plotter.plot(STROKE)
    finally:
        plotter.abort()


def test_grbl_reply_parsers_fuzz():
    campaign("grbl reply lines", parse_any_line, LINES, QUICK_CASES, seed=8).check()


def test_grbl_driver_replies_fuzz():
    campaign("grbl driver replies", plot_through_garbled_replies, LINES, QUICK_CASES // 3, seed=9).check()


@pytest.mark.slow
def test_grbl_reply_parsers_fuzz_slow():
    result = campaign("grbl reply lines", parse_any_line, LINES, SLOW_CASES, seed=80)
    print(result.summary())
    result.check()


@pytest.mark.slow
def test_grbl_driver_replies_fuzz_slow():
    result = campaign("grbl driver replies", plot_through_garbled_replies, LINES, SLOW_CASES, seed=90)
    print(result.summary())
    result.check()

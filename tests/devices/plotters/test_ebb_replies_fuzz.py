"""Fuzzing the EBB reply parsers and the AxiDraw driver's reply handling (legacy and future syntax)."""

from __future__ import annotations

import numpy as np
import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.devices.plotters.axidraw import AxiDrawPlotter
from pixelpen.devices.plotters.ebb_encode import (
    parse_error,
    parse_qc,
    parse_qg,
    parse_qm,
    parse_qs,
    parse_version_reply,
    strip_name,
)
from pixelpen.errors import PixelpenError
from pixelpen.vector.displaylist import DisplayList
from tests.devices.plotters.test_axidraw import PROFILE, STEPS, FakeEbb, future_reply, legacy_reply
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign

REPLIES = [
    b"OK\r\n", b"QM,0,0,0,0\n\r", b"QM,1,1,0,1\n\r", b"3E\r\n", b"0,0\n\rOK\r\n", b"-120,35\n\rOK\r\n",
    b"0394,0293\r\nOK\r\n", b"16,16\r\nOK\r\n", b"1\n\rOK\r\n", b"!8 Err: Unknown command 'XX:58'OK\r\n",
    b"!4 Err: Missing parameter(s)\r\n", b"EBBv13_and_above EB Firmware Version 2.8.1\r\n",
    b"SM\n", b"QM,QM,0,0,0,0\n", b"QG,3E\n", b"QS,10,-5\n", b"QC,0394,0293\n", b"QE,16,16\n",
    b"V,EBBv13_and_above EB Firmware Version 3.0.2\n", b"SM,!4 Err: Missing parameter(s)\n",
]
"""Replies in both syntaxes from evil-mad/EggBot docs/ebb.html (legacy endings \\r\\n and \\n\\r, future NAME,...)."""


def parse_any_reply(data: bytes) -> None:
    """Every pure EBB reply parser on each mutated line."""
    for line in data.decode("ascii", "replace").replace("\r", "\n").split("\n"):
        parse_error(line)
        for parser in (parse_qm, parse_qg, parse_qs, parse_qc, parse_version_reply):
            try:
                parser(line)
            except PixelpenError:  # the clean refusal; anything else escapes to the campaign as a crash
                continue
        strip_name("QM", line)


STROKE = DisplayList.from_polylines([np.array([[10, 10], [12, 10], [12, 12]], float) * STEPS], unit_mm=PROFILE.unit_mm)


def plot_through_garbled_replies(data: bytes) -> None:
    """A plot while the mutated bytes arrive ahead of the board's replies: done, or a PixelpenError."""
    clock = SimulatedClock()
    syntax = future_reply if data[:1] in (b"Q", b"S", b"V") else legacy_reply
    fake = FakeEbb(clock, "3.0.2", syntax)
    plotter = AxiDrawPlotter("fake", profile=PROFILE, clock=clock, link_factory=lambda: fake, timeout=0.5)
    plotter.open()
    try:
        fake.out += data
        plotter.plot(STROKE)
    finally:
        plotter.abort()


def test_ebb_reply_parsers_fuzz():
    campaign("ebb replies", parse_any_reply, REPLIES, QUICK_CASES, seed=5).check()


def test_axidraw_driver_replies_fuzz():
    campaign("axidraw driver replies", plot_through_garbled_replies, REPLIES, QUICK_CASES // 3, seed=6).check()


@pytest.mark.slow
def test_ebb_reply_parsers_fuzz_slow():
    result = campaign("ebb replies", parse_any_reply, REPLIES, SLOW_CASES, seed=50)
    print(result.summary())
    result.check()


@pytest.mark.slow
def test_axidraw_driver_replies_fuzz_slow():
    result = campaign("axidraw driver replies", plot_through_garbled_replies, REPLIES, SLOW_CASES, seed=60)
    print(result.summary())
    result.check()

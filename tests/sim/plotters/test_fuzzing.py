"""Mutation fuzzing of the HP-GL, GRBL and EBB simulators: any bytes in, only the device's own answers out.

Seeds are real plots (``data/*_plot.bin``: the bytes pixelpen's drivers sent for a square, a circle, a line
and a dot, recorded through the simulators) and hand-written streams in the style of other clients (vpype's
HP-GL files and chiplotle's labels and arcs, GRBL streaming scripts with real-time bytes, saxi's and the
AxiDraw API's EBB commands).  Each mutant is fed through ``receive()`` in 64-byte packets with
``advance_to()`` running the device from event to event between them: the outcome must be the device's
own error replies (or a PixelpenError), never a Python exception, a hang or unbounded memory.
"""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.sim.base import create_simulator
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign

DATA = Path(__file__).with_name("data")
PACKET = 64
STEP_S = 600.0
"""Simulated seconds per ``advance_to`` (at least; more when the next event is later), so a step runs many events."""
MAX_STEPS = 1_000
"""Steps after each packet at most (a mutant may queue days of motion; the time limit is the test)."""

HPGL_SEEDS = [
    (DATA / "hp7475a_plot.bin").read_bytes(),
    # vpype write --device hp7475a --page-size a4
    b"IN;DF;PS4;SP1;PU1050,1050;PD2050,1050,2050,2050,1050,2050,1050,1050;PU;SP2;PU3000,3000;PD4000,3500;PU;"
    b"SP0;IN;PU11040,7721;",
    # chiplotle-style: labels, arcs, circles, fills, line types, windows, scaling, status queries
    b"IN;SP1;IP0,0,10000,7000;SC0,100,0,100;PA10,10;LBHello, world\x03;DT*;LBagain*;DT;SI0.3,0.4;SL0.2;"
    b"DI0,1;LBup\x03;CI500,5;AA50,50,90;AR10,0,-180,10;LT2,5;PD80,80,90,10;LT;FT3,100,45;RA60,60;"
    b"DT;ER20,20;EW300,0,90;WG200,45,120;IW1000,1000,6000,6000;PR100,100,-50,30;OS;OE;OA;OC;OW;OP;OI;OH;"
    b"\x1b.B\x1b.E\x1b.O\x1b.@1024;17:\x1b.M0;;;13:\x1b.N;19:VS10;TL2;XT;YT;SM*;PA20,20,30,30;SM;SP0;",
]
GRBL_SEEDS = [
    (DATA / "grbl_plot.bin").read_bytes(),
    # gnea/grbl stream.py: wake up, settings, then line by line; real-time status, hold, resume, reset
    b"\r\n\r\n$$\n$G\n$#\n$I\nG21 G90 G17\nG0 X10 Y10\nM3 S50\nG1 X50 Y10 F2000\n?G2 X50 Y50 I0 J20\n!?~"
    b"G91 G1 X-10 Y5\nG90\nM5\n$J=G91 X5 F500\n\x85G4 P0.5\n$X\n$H\n\x18$C\nG1 X1\n$C\n\x90\x91\x99\x9a\x9e\xa0",
    b"$130=297\n$131=210\n$N0=G21\n$RST=#\nG10 L20 P1 X0 Y0\nG54\nG28.1\nG38.2 Z-5 F100\nN10 G1 X1e3 F1\n"
    b"G1 X3 Y4 F999999\nM4 S1000\nT1 M6\nM30\n$SLP\n",
]
EBB_SEEDS = [
    (DATA / "axidraw_plot.bin").read_bytes(),
    # saxi: servo by S2 with rates, LM moves, queries
    b"V\rEM,1,1\rSR,60000000,1\rS2,28000,4,800,0\rLM,85899,400,0,85899,400,0\rS2,15700,4,800,120\r"
    b"LM,171798,800,-5000,0,0,0,3\rXM,500,100,-100\rHM,5000\rQS\rQM\rQG\rES\rEM,0,0\r",
    # the AxiDraw API / plotink: pins, servo config, checksums, future syntax, timed moves
    b"QE\rPI,E,0\rPI,C,1\rPI,E,2\rPI,E,1\rPI,A,6\rSC,4,20641\rSC,5,15248\rSC,11,1200\rSC,12,900\r"
    b"SP,0,200\rSM,1000,800,-800\rSP,1\rTP,100\rQP\rQC\rQB\rQR\rQL\rSL,5\rQN\rCS\rCU,4,8\rT3,100,1,2,3,4,5,6\r"
    b"L3,1000,200,10,1,1000,200,10,1\rTD,100,1,2,3,4,5,6,7,8\rCU,10,1\rV\rCU,54,1\rQS,53\rQU,2\rCU,10,0\r"
    b"MR,100\rMW,100,9\rPO,B,3,1\rPD,B,3,0\rI\rO,255\rC,1,2,3,4,5\rA\rAC,0,1\rCK,1,-1,2,-2,3,-3,a,b\rST,abc\rQT\rR\r",
]

CAMPAIGNS = {
    "hp7475a": HPGL_SEEDS,
    "grbl": GRBL_SEEDS,
    "axidraw": EBB_SEEDS,
}


def feed(model: str, data: bytes) -> None:
    """Feed ``data`` to a fresh ``model`` simulator packet by packet, running it between packets."""
    clock = SimulatedClock()
    device = create_simulator(model, clock=clock)
    try:
        for i in range(0, len(data), PACKET):
            device.receive(data[i : i + PACKET])
            for _ in range(MAX_STEPS):
                t = device.next_event_time()
                if t is None:
                    break
                clock.advance(max(t - clock.now(), STEP_S))
                device.advance_to(clock.now())
            device.take_output()
        device.advance_to(clock.now() + 1.0)
        device.take_output()
    finally:
        device.close()


QUICK_SEED_BYTES = 256
"""The default suite mutates the first bytes of each recorded plot (the whole plots go to the slow run)."""


@pytest.fixture(autouse=True)
def _quiet_devices():
    """The devices log every error they report; thousands of mutants would spend their time in logging."""
    logging.disable(logging.WARNING)
    yield
    logging.disable(logging.NOTSET)


@pytest.mark.parametrize("model", sorted(CAMPAIGNS))
def test_seeds_are_valid_plots(model):
    for seed in CAMPAIGNS[model]:
        feed(model, seed)  # every seed runs cleanly before it is mutated


@pytest.mark.parametrize("model", sorted(CAMPAIGNS))
def test_quick_fuzz(model):
    seeds = [seed[:QUICK_SEED_BYTES] for seed in CAMPAIGNS[model]]
    result = campaign(f"sim {model}", lambda data: feed(model, data), seeds, QUICK_CASES, seed=1,
                      seconds_per_case=10.0, memory_mb=128.0)
    result.check()


@pytest.mark.slow
@pytest.mark.parametrize("model", sorted(CAMPAIGNS))
def test_slow_fuzz(model):
    result = campaign(f"sim {model}", lambda data: feed(model, data), CAMPAIGNS[model], SLOW_CASES, seed=2,
                      seconds_per_case=10.0, memory_mb=128.0)
    print(result.summary())
    result.check()

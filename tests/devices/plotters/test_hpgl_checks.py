"""HP-GL checkpoints (verify=instruction): a garbled byte costs only what it missed, a power cut only what ran unseen.

Every test compares the simulator's sheet as a multiset of segments with the uninterrupted plot's: a piece drawn
twice or missing shows, which pixels would not.
"""

from __future__ import annotations

import numpy as np
import pytest

import pixelpen
from pixelpen.devices.plotters.base import PlotState
from pixelpen.devices.plotters.hpgl_stream import Check, HPGLStream
from pixelpen.errors import ProtocolError
from pixelpen.sim.transports.port import open_sim_port
from pixelpen.vector.displaylist import DisplayList
from tests.devices.plotters.test_hpgl import (
    UNIT,
    PortLink,
    Rig,
    _plot_through_faults,
    _reference,
    _segments,
    drawing,
)

ZIGZAG = np.array([[500 + 400 * i, 1000 + 3000 * (i % 2)] for i in range(8)], float)
"""One PD list of 7 pairs; its X values are unique, so a truncated Y reads one way only."""
BOX = np.array([[6000, 5000], [7000, 5000], [7000, 6000]], float)


def _plot(pens: tuple[int, ...] = (1, 1, 1)) -> DisplayList:
    return DisplayList.from_polylines([BOX - 4000, ZIGZAG, BOX], pens=list(pens), unit_mm=UNIT)


def _corrupted(dl: DisplayList, needle: bytes, at: int, options: str = "sync_strokes=1"):
    """Plot with byte ``at`` of the first ``needle`` in the wire inverted; resume; the rig and what was raised."""
    _, _ = _reference(dl, options)
    clean = Rig(options=options)
    clean.display.plot(dl)
    clean.display.close()
    offset = bytes(clean.links[0].sent).find(needle)
    assert offset >= 0
    rig, n, asked = _plot_through_faults(dl, {"corrupt_at": str(offset + at)}, options)
    return rig, n, asked


def _extra(have: list[tuple], expected: list[tuple]) -> list[tuple]:
    """What ``have`` holds beyond ``expected`` (asserting that nothing of ``expected`` is missing or doubled)."""
    rest = list(have)
    for s in expected:
        assert s in rest, f"segment {s} is missing"
        rest.remove(s)
    return rest


def test_a_pair_lost_in_a_pd_list_costs_only_the_rest_of_that_list():
    dl = _plot()
    expected, _ = _reference(dl, "sync_strokes=1")
    rig, n, asked = _corrupted(dl, b"PD900,4000,1300", len("PD900,4000,"))  # the X of pair 2: pairs 2.. skipped
    assert (n, asked) == (1, [])
    assert _segments(rig.device) == expected  # vertex 0..2 drawn once, 2..7 by the resume, once


def test_a_pair_whose_y_lost_digits_is_drawn_there_and_the_rest_is_drawn_once():
    dl = _plot()
    expected, _ = _reference(dl, "sync_strokes=1")
    rig, n, asked = _corrupted(dl, b"PD900,4000,1300,1000", len("PD900,4000,1300,10"))  # pair 2 drawn to 1300,10
    assert (n, asked) == (1, [])
    assert _extra(_segments(rig.device), expected) == [(900.0, 4000.0, 1300.0, 10.0, 1)]  # the plotter's own stray


def test_a_garbled_travel_costs_its_first_segment_only():
    dl = _plot()
    expected, _ = _reference(dl, "sync_strokes=1")
    rig, n, asked = _corrupted(dl, b"PU500,1000;", 0)  # 'P' of stroke 1's PU: the PD draws from stroke 0's end
    assert (n, asked) == (1, [])
    assert _extra(_segments(rig.device), expected) == [(3000.0, 2000.0, 900.0, 4000.0, 1)]


def test_a_garbled_terminator_is_no_fault_when_oa_shows_the_instruction_ran(caplog):
    dl = _plot()
    expected, _ = _reference(dl, "sync_strokes=1")
    rig, n, asked = _corrupted(dl, b"PU500,1000;", len("PU500,1000"))
    assert (n, asked) == (0, []) and _segments(rig.device) == expected
    assert "nothing is missing" in caplog.text


def test_a_pen_not_changed_redraws_its_strokes_in_their_pen():
    dl = _plot(pens=(1, 2, 2))
    expected, _ = _reference(dl, "sync_strokes=1")
    rig, n, asked = _corrupted(dl, b"SP2;", 2)
    assert (n, asked) == (1, [])
    extra = _extra(_segments(rig.device), expected)
    assert extra and all(s[4] == 1 for s in extra)  # strokes 1..2 also in pen 1 (what the plotter did), none lost


def test_what_was_missed_is_kept_in_the_state_file_for_a_new_session(tmp_path):
    dl = _plot()
    expected, _ = _reference(dl, "sync_strokes=1")
    clean = Rig(options="sync_strokes=1")
    clean.display.plot(dl)
    clean.display.close()
    offset = bytes(clean.links[0].sent).find(b"PD900,4000,1300") + len("PD900,4000,")
    state = tmp_path / "plot.json"
    first = Rig(first_link={"corrupt_at": str(offset)}, options=f"sync_strokes=1&state={state}")
    with pytest.raises(ProtocolError):
        first.display.plot(dl)
    first.display.close()
    saved = PlotState.load(state)
    assert saved.missing == [[1, *ZIGZAG[1:].astype(int).ravel().tolist()]] and saved.confirmed == 2
    d = pixelpen.open(f"sim:hp7475a?state={state}&sync_strokes=1",
                      link_factory=lambda: PortLink(open_sim_port("hp7475a", {}, clock=first.clock,
                                                                  device=first.device)))
    d.plot(dl, resume=True)
    d.close()
    assert _segments(first.device) == expected and PlotState.load(state).missing is None


def test_a_power_cut_resumes_from_the_last_acknowledged_point():
    dl = drawing(n=10, seed=5, pens=(1, 2, 3))
    expected, total = _reference(dl, "sync_strokes=4")
    longest = max(len(dl.stroke(i)) for i in range(len(dl)))
    extras = 0
    for at in np.random.default_rng(3).integers(300, total - 40, size=3):
        rig, n, asked = _plot_through_faults(dl, {"power_loss_after": str(int(at))}, "sync_strokes=4")
        assert n == 1 and len(asked) == 1 and "switched off or reset" in str(asked[0])
        extra = _extra(_segments(rig.device), expected)
        # at most the one PD list under way when the power went is drawn again (the part drawn, then all of it):
        # never what the plotter had acknowledged before it
        assert len(extra) <= longest, f"power_loss_after={at}: {extra}"
        extras += len(extra)
    assert extras <= 1  # verify=sync, resuming from the last confirmed stroke, draws 5 segments again here


def test_what_an_instruction_missed_is_read_from_where_it_stopped():
    pts = np.array([[0, 0], [100, 0], [100, 100], [0, 100], [0, 0]])
    pd = Check("PD", 3, pts, lo=1, hi=4, last=True)
    assert HPGLStream._missing_after(pd, (100, 100)).tolist() == pts[2:].tolist()  # pair 3 failed
    assert HPGLStream._missing_after(pd, (0, 1)).tolist() == pts[2:].tolist()  # pair 3 drawn to 0,1 (Y cut)
    assert HPGLStream._missing_after(pd, (0, 0)).tolist() == pts.tolist()  # pen down at the end is no damage
    back = np.array([[0, 0], [100, 0], [100, 100], [100, 0], [200, 0]])  # passes 100,0 twice: which is unknowable
    assert HPGLStream._missing_after(Check("PD", 3, back, lo=1, hi=4, last=True), (100, 0)) is None
    assert HPGLStream._missing_after(pd, (55, 55)) is None
    first = Check("PD", 3, pts, lo=1, hi=2, last=False)  # another PD list follows: it joined 2 to 3
    assert HPGLStream._missing_after(first, (100, 0)).tolist() == pts[1:4].tolist()
    assert HPGLStream._missing_after(Check("PU", 3, pts), (7, 7)).tolist() == pts[:2].tolist()


def test_a_closed_stroke_before_a_sync_point_is_told_apart_by_its_late_checkpoints():
    # the plotter stops with the pen up on the square's corner: before it (travelled there) or after it (the sync
    # point's PU;)?  The sync point's OA never came; the square's own checkpoint did (verify=sync asks here)
    last = np.array([[5000, 1000], [5500, 1500]], float)
    dl = DisplayList.from_polylines([ZIGZAG, BOX - 3000, np.vstack([BOX, BOX[:1]]), last], pens=1, unit_mm=UNIT)
    expected, _ = _reference(dl, "sync_strokes=3")
    clean = Rig(options="sync_strokes=3")
    clean.display.plot(dl)
    clean.display.close()
    wire = bytes(clean.links[0].sent)
    at = wire.find(b"PU;OA;OE;", wire.find(b"PU6000,5000;")) + 3  # the plotter takes the sync's PU; but not its OA
    rig, n, asked = _plot_through_faults(dl, {"stall_after": str(at)}, "sync_strokes=3&stall=5")
    assert (n, asked) == (1, []) and _segments(rig.device) == expected

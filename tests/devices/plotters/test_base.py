"""The plotter core: locating where a device stopped, resuming each stroke once, state files, pause and manual hooks."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from benchmarks.faults import Tally, compare
from pixelpen.clock import SimulatedClock
from pixelpen.devices.plotters.base import (
    DeviceWhere,
    PlotInterrupted,
    PlotState,
    PlotterDisplay,
    PositionUnknown,
    ResumePoint,
    locate,
)
from pixelpen.devices.plotters.resume import not_after
from pixelpen.devices.plotters.state import unfinished
from pixelpen.drivers.stream import Link
from pixelpen.errors import ConfigError, Disconnected, ParseError
from pixelpen.profiles.model import load_profile
from pixelpen.vector.displaylist import DisplayList

A = np.array([[0, 0], [10, 0], [10, 10]])
B = np.array([[20, 0], [30, 0]])
WINDOW = [(5, A), (6, B)]
BEFORE = np.array([-5, -5])


def where(x, y, pen):
    return DeviceWhere((x, y), pen)


# -- locate ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "x, y, pen, expected",
    [
        (5, 0, True, ResumePoint(5, 0, (5.0, 0.0))),  # stopped inside the first segment
        (10, 0, True, ResumePoint(5, 1)),  # at the middle vertex
        (10, 10, True, ResumePoint(6)),  # at the end, pen not yet lifted: stroke 5 is done
        (10, 10, False, ResumePoint(6)),
        (15, 5, False, ResumePoint(6)),  # half way along the travel from stroke 5's end to stroke 6's start
        (20, 0, False, ResumePoint(6)),  # at stroke 6's start, pen still up
        (20, 0, True, ResumePoint(6)),  # pen down at the start: nothing of stroke 6 drawn yet
        (30, 0, False, ResumePoint(7)),  # everything sent is done
        (0, 0, False, ResumePoint(5)),  # travelled to the first stroke's start
        (-5, -5, False, ResumePoint(5)),  # still where the last confirmed stroke ended
        (-2, -2, None, ResumePoint(5)),  # on the travel; the device cannot tell the pen (travel is pen-up anyway)
        (5, 0.4, True, ResumePoint(5, 0, (5.0, 0.4))),  # within the tolerance of 0.5
    ],
)
def test_locate_reads_one_place(x, y, pen, expected):
    assert locate(WINDOW, where(x, y, pen), BEFORE) == [expected]


@pytest.mark.parametrize("x, y, pen", [(15, 5, True), (5, 0.6, True), (50, 50, False), (3, 3, None),
                                      (5, 0, False), (10, 5, False)])  # pen up inside a stroke: never lifted there
def test_locate_finds_nothing_off_the_strokes_and_their_travels(x, y, pen):
    assert locate(WINDOW, where(x, y, pen), BEFORE) == []


def test_a_closed_stroke_seen_pen_up_at_its_start_has_two_readings():
    loop = np.array([[0, 0], [10, 0], [10, 10], [0, 0]])
    found = locate([(3, loop)], where(0, 0, False), np.array([50, 50]))
    assert found == [ResumePoint(3), ResumePoint(4)]  # not started, or done: a resume must not guess
    assert locate([(3, loop)], where(10, 0, True), None) == [ResumePoint(3, 1)]  # elsewhere it is clear
    # the base lifts the pen only between strokes: lifted inside one is no place it can be (unless it cannot tell)
    assert locate([(3, loop)], where(10, 0, False), None) == []
    assert locate([(3, loop)], where(10, 0, None), None) == [ResumePoint(3, 1)]


def test_a_device_that_lifts_only_with_its_travel_reads_a_closed_stroke_once():
    # HP-GL: PUx,y lifts and travels in one instruction, so the pen rests lifted at a stroke's end only where
    # the driver sent a bare PU (a sync point); PD comes with its vectors, so it never rests down at a start
    loop = np.array([[0, 0], [10, 0], [10, 10], [0, 0]])
    never = dict(lifts=lambda s: False, down_at_start=False)
    assert locate([(3, loop)], where(0, 0, False), np.array([50, 50]), **never) == [ResumePoint(3)]
    assert locate([(3, loop)], where(0, 0, True), np.array([50, 50]), **never) == [ResumePoint(4)]
    synced = dict(lifts=lambda s: s == 3, down_at_start=False)
    assert locate([(3, loop)], where(0, 0, False), np.array([50, 50]), **synced) == [ResumePoint(3), ResumePoint(4)]


def test_a_lift_only_with_travel_leaves_no_rest_at_a_stroke_end():
    # HP-GL: after stroke 5 comes PUx,y (lift and travel), so pen up at stroke 5's end is not a resting place
    assert locate(WINDOW, where(10, 10, False), BEFORE, lifts=lambda s: False) == []
    assert locate(WINDOW, where(15, 5, False), BEFORE, lifts=lambda s: False) == [ResumePoint(6)]  # mid travel
    assert locate(WINDOW, where(10, 10, False), BEFORE, lifts=lambda s: s == 5) == [ResumePoint(6)]


def test_a_path_through_its_own_line_is_ambiguous_where_it_crosses():
    cross = np.array([[0, 0], [10, 0], [10, 10], [5, 10], [5, -10]])
    found = locate([(0, cross)], where(5, 0, True), None)
    assert found == [ResumePoint(0, 0, (5.0, 0.0)), ResumePoint(0, 3, (5.0, 0.0))]


def test_acknowledgements_rule_out_what_came_before_them():
    loop = np.array([[0, 0], [10, 0], [10, 10], [0, 0]])
    up_at_start = DeviceWhere((0, 0), False, reached=(3, 3))  # the move back to the start was acknowledged
    assert locate([(3, loop)], up_at_start, np.array([50, 50])) == [ResumePoint(4)]
    # k = 0 is only the travel: that proves nothing about the pen, so the closed stroke still has two readings
    where = DeviceWhere((0, 0), False, reached=(3, 0))
    assert locate([(3, loop)], where, np.array([50, 50])) == [ResumePoint(3), ResumePoint(4)]
    cross = np.array([[0, 0], [10, 0], [10, 10], [5, 10], [5, -10]])
    assert locate([(0, cross)], DeviceWhere((5, 0), True, reached=(0, 3)), None) == [ResumePoint(0, 3, (5.0, 0.0))]
    assert locate([(0, cross)], DeviceWhere((5, 0), True, reached=(0, 1)), None) == [ResumePoint(0, 3, (5.0, 0.0))]
    assert locate([(0, cross)], DeviceWhere((5, 0), True, reached=(0, 0)), None) == [
        ResumePoint(0, 0, (5.0, 0.0)), ResumePoint(0, 3, (5.0, 0.0))]
    # at a vertex it acknowledged, or past it: still there; behind everything it acknowledged: nowhere
    assert locate(WINDOW, DeviceWhere((10, 0), True, reached=(5, 1)), BEFORE) == [ResumePoint(5, 1)]
    assert locate(WINDOW, DeviceWhere((10, 10), True, reached=(6, 0)), BEFORE) == [ResumePoint(6)]
    assert locate(WINDOW, DeviceWhere((-5, -5), False, reached=(5, 1)), BEFORE) == []


def test_no_position_locates_nothing():
    assert locate(WINDOW, DeviceWhere(None, None), BEFORE) == []


def test_a_remainder_starts_where_the_pen_stopped():
    pts = A.astype(np.int64)
    assert ResumePoint(5).remainder(pts) is None
    assert ResumePoint(5, 1).remainder(pts).tolist() == [[10, 0], [10, 10]]
    assert ResumePoint(5, 0, (4.6, 0.2)).remainder(pts).tolist() == [[5, 0], [10, 0], [10, 10]]


def test_a_place_after_what_went_out_is_not_possible():
    length = {0: 3, 1: 4, 2: 2}.__getitem__
    top = ResumePoint(1, 2)  # bytes up to stroke 1's vertex 2 went out
    assert not_after(ResumePoint(1), top, length) and not_after(ResumePoint(1, 2), top, length)
    assert not_after(ResumePoint(1, 1, (3.0, 4.0)), top, length)  # inside segment 1..2
    assert not not_after(ResumePoint(1, 2, (3.0, 4.0)), top, length) and not not_after(ResumePoint(2), top, length)
    assert not_after(ResumePoint(2), ResumePoint(1, 3), length)  # stroke 1 done = stroke 2 not begun


def test_pieces_still_missing_keep_a_job_unfinished(tmp_path):
    path = tmp_path / "s.json"
    PlotState("x", "f", 3, 3, missing=[[1, 0, 0, 5, 5]], reached=[2, 1], written=[2, 1, 3.5, 4.0]).save(path)
    state = PlotState.load(path)
    assert unfinished(path) and state.missing == [[1, 0, 0, 5, 5]] and state.written == [2, 1, 3.5, 4.0]


# -- the state file ---------------------------------------------------------------------------------------


def test_where_a_held_device_stopped_is_kept_with_its_hold(tmp_path):
    """[x, y, pen, tolerance, held]; a file of the older 4-field form still loads (not held)."""
    path = tmp_path / "s.json"
    PlotState("x", "f", 3, 1, stopped_at=[10.0, 20.0, 0, 0.5, 1]).save(path)
    assert PlotState.load(path).stopped_at == [10.0, 20.0, 0, 0.5, 1]
    PlotState("x", "f", 3, 1, stopped_at=[10.0, 20.0, 0, 0.5]).save(path)
    assert PlotState.load(path).stopped_at == [10.0, 20.0, 0, 0.5]


def test_a_version_1_state_file_still_loads_with_every_unconfirmed_stroke_in_doubt(tmp_path):
    path = tmp_path / "s.json"
    path.write_text(json.dumps({"url": "x", "fingerprint": "f", "strokes": 5, "confirmed": 2, "version": 1}))
    state = PlotState.load(path)
    assert (state.confirmed, state.sent, state.position_lost, state.version) == (2, None, False, 2)


@pytest.mark.parametrize(
    "fields, message",
    [({"sent": 9}, "'sent' is out of range"), ({"sent": 1}, "'sent' is out of range"),
     ({"position_lost": "yes"}, "'position_lost' is not true or false"), ({"version": 3}, "not a version-2"),
     ({"start": [9, 0, 0]}, "'start' is not"), ({"start": [1.5, 0, 0]}, "'start' is not"),
     ({"start": [0, 1]}, "'start' is not"), ({"missing": [[9, 0, 0]]}, "'missing' is not"),
     ({"missing": [[1, 0]]}, "'missing' is not"), ({"reached": [1]}, "'reached' is not"),
     ({"written": [1, -1]}, "'written' is not"), ({"written": [7, 0]}, "'written' is not"),
     ({"stopped_at": [1, 2, 1, 0.5, 2]}, "'stopped_at' is not"), ({"stopped_at": [1, 2, 1]}, "'stopped_at' is not")],
)
def test_bad_state_fields_are_named(tmp_path, fields, message):
    path = tmp_path / "s.json"
    path.write_text(json.dumps({"url": "x", "fingerprint": "f", "strokes": 5, "confirmed": 2, "version": 2, **fields}))
    with pytest.raises(ParseError, match=message) as info:
        PlotState.load(path)
    assert str(path) in str(info.value)


# -- the base's resume against a device model ------------------------------------------------------------


class NullLink(Link):
    """A link to nowhere (the fake device below lives in the display)."""

    def __init__(self, clock) -> None:
        super().__init__("null", clock=clock)

    def _read_raw(self, wait):
        return b""

    def _write_raw(self, data, wait):
        return len(data)

    def _raw_in_waiting(self):
        return 0

    def _flush_raw(self, wait):
        pass

    def _close_raw(self):
        pass


class FakePlotter(PlotterDisplay):
    """A device that draws what it is sent at once, until a cut after each of ``budget`` units of pen-down travel.

    At a cut it stops mid-segment (pen down) and the link fails; ``_where`` reports the position and, as
    ``reached``, the last point of the sent stroke it got to (its acknowledgements).  ``cut_travel``: the travel
    to that stroke stops half way instead; ``skip``: that stroke's first segment is not inked and the device
    reports the stroke damaged at the next cut.
    """

    reports_position = True

    def __init__(self, budget=None, tell=True, *, home=(0.0, 0.0), cut_travel=None, skip=None, **kw) -> None:
        clock = SimulatedClock()
        super().__init__("fake", profile=load_profile("hp7475a"), clock=clock, link_factory=lambda: NullLink(clock),
                         **kw)
        self.budgets = [] if budget is None else [float(b) for b in np.atleast_1d(budget)]
        self.tell, self.cut_travel, self.skip = tell, cut_travel, skip
        self.inked: list[tuple[float, float, float, float, int]] = []
        self.pos, self.down, self.lost = tuple(map(float, home)), False, False
        self.reached: tuple[int, int] | None = None
        self.unconfirmed = 0

    def _connect(self):
        pass

    def _pen_position(self):
        return self.pos

    def _cut(self, index):
        if self.skip is not None and index >= self.skip:
            self._mark_damaged(range(self.skip, self.skip + 1))
            self.skip = None
        raise Disconnected("fake: cable pulled")

    def _send_stroke(self, index, points, pen):
        p = points.astype(float)
        if index == self.cut_travel:
            self.cut_travel = None
            self.pos, self.down = tuple((np.asarray(self.pos) + p[0]) / 2), False
            self._cut(index)
        self.pos, self.down, self.reached = tuple(p[0]), True, (index, 0)
        for k, (a, b) in enumerate(itertools.pairwise(p), start=1):
            step = float(np.hypot(*(b - a)))
            if self.budgets and step > self.budgets[0]:
                cut = a + (b - a) * self.budgets.pop(0) / step
                self.inked.append((*a, *cut, pen))
                self.pos = tuple(cut)
                self._cut(index)
            if self.budgets:
                self.budgets[0] -= step
            if not (index == self.skip and k == 1):
                self.inked.append((*a, *b, pen))
            self.pos, self.reached = tuple(b), (index, k)
        self.down = False
        self.unconfirmed = index + 1  # confirmed only at a drain: everything since is in doubt

    def _poll(self):
        pass

    def _drain(self):
        self._confirm(self.unconfirmed)

    def _select_pen(self, pen):
        pass

    def _device_paused(self):
        return False

    def _make_safe(self):
        pass

    def _where(self):
        if not self.tell:
            return super()._where()
        return DeviceWhere(self.pos, self.down, position_lost=self.lost, reached=self.reached)

    def sheet(self) -> DisplayList:
        return DisplayList.from_polylines([np.array([s[:2], s[2:4]]) for s in self.inked],
                                          pens=[s[4] for s in self.inked], unit_mm=self.profile.unit_mm)


def _job(n=8, seed=4) -> DisplayList:
    rng = np.random.default_rng(seed)
    polys = [rng.integers(100, 7000, (int(rng.integers(2, 6)), 2)).astype(float) for _ in range(n)]
    return DisplayList.from_polylines(polys, pens=1, unit_mm=0.02488)


def _reference(dl) -> DisplayList:
    d = FakePlotter()
    d.open()
    d.plot(dl)
    return d.sheet()


def test_a_cut_anywhere_resumes_with_the_rest_of_the_stroke_and_nothing_twice():
    dl = _job()
    ref = _reference(dl)
    total = sum(float(np.hypot(*np.diff(s, axis=0).T).sum()) for s in dl.strokes())
    for budget in np.linspace(0.03, 0.97, 9) * total:
        d = FakePlotter(budget=float(budget))
        d.open()
        with pytest.raises(PlotInterrupted):
            d.plot(dl)
        d.resume_after_fault()
        assert compare(ref, d.sheet()) == Tally(), f"cut after {budget:.0f} units"
        assert d.confirmed == len(dl)


def test_two_cuts_in_one_stroke_resume_the_remainder_in_the_whole_stroke():
    # the second cut is located in the remainder that was sent: its place must be read back in the whole stroke
    dl = DisplayList.from_polylines([np.array([[100, 100], [900, 100], [900, 900], [100, 900], [100, 300]], float),
                                     np.array([[2000, 2000], [2500, 2000]], float)], pens=1, unit_mm=0.02488)
    ref = _reference(dl)
    for budgets in ([300.0, 400.0], [300.0, 500.0], [800.0, 1000.0], [900.0, 50.0]):
        d = FakePlotter(budget=budgets)
        d.open()
        with pytest.raises(PlotInterrupted):
            d.plot(dl)
        with pytest.raises(PlotInterrupted):
            d.resume_after_fault()
        d.resume_after_fault()
        assert compare(ref, d.sheet()) == Tally(), f"cuts after {budgets}"
        assert d.confirmed == len(dl)


def test_a_stop_on_the_first_travel_is_read_from_where_the_job_started():
    dl = _job()
    ref = _reference(dl)
    d = FakePlotter(home=(-400.0, 3000.0), cut_travel=0)
    d.open()
    with pytest.raises(PlotInterrupted):
        d.plot(dl)
    d.resume_after_fault()  # half way along the travel from home: nothing drawn yet, no question
    assert compare(ref, d.sheet()) == Tally() and d.confirmed == len(dl)


def test_the_first_travel_from_a_state_file_in_a_new_session(tmp_path):
    dl = _job()
    ref = _reference(dl)
    state = tmp_path / "plot.json"
    d = FakePlotter(home=(-400.0, 3000.0), cut_travel=0, state_file=state)
    d.open()
    with pytest.raises(PlotInterrupted):
        d.plot(dl)
    assert PlotState.load(state).start == [0, -400.0, 3000.0]
    later = FakePlotter(state_file=state)  # a new process: the device still stands half way along the travel
    later.pos = d.pos
    later.open()
    later.plot(dl, resume=True)
    later.inked[:0] = d.inked
    assert compare(ref, later.sheet()) == Tally() and later.confirmed == len(dl)


def test_a_damaged_stroke_is_drawn_again_from_its_start_when_the_stop_is_inside_it():
    dl = _job()
    ref = _reference(dl)
    lengths = [np.hypot(*np.diff(p, axis=0).T) for p in dl.strokes()]
    budget = float(sum(length.sum() for length in lengths[:3]) + lengths[3][0] + lengths[3][1] / 2)
    d = FakePlotter(budget=budget, skip=3)  # segment 0 of stroke 3 never inked; the stop is half way along segment 1
    d.open()
    with pytest.raises(PlotInterrupted):
        d.plot(dl)
    d.resume_after_fault()
    tally = compare(ref, d.sheet())
    assert tally.lost == 0 and tally.stray == 0 and tally.doubled > 0  # the good part of stroke 3 twice, nothing lost


def test_a_damaged_stroke_with_the_device_off_every_stroke_resumes_at_the_damage():
    class OffPath(FakePlotter):
        def _cut(self, index):
            self.pos, self.down = (6999.0, 99.0), False  # held on a corrupted leg, away from every stroke
            super()._cut(index)

    dl = _job()
    ref = _reference(dl)
    for damaged in (0, 2, 4):
        d = OffPath(cut_travel=damaged + 1, skip=damaged)
        d.open()
        with pytest.raises(PlotInterrupted):
            d.plot(dl)
        d.resume_after_fault()  # known position, on no stroke: redraw from the damaged stroke on, no question
        tally = compare(ref, d.sheet())
        assert tally.lost == 0 and tally.stray == 0, f"damaged {damaged}"
        assert d.confirmed == len(dl)
    d = OffPath(cut_travel=3)  # nothing damaged: the same stop is a question, not a guess
    d.open()
    with pytest.raises(PlotInterrupted):
        d.plot(dl)
    with pytest.raises(PositionUnknown, match="on none of the strokes"):
        d.resume_after_fault()


def test_a_device_that_cannot_tell_makes_the_resume_ask_and_the_confirmed_resume_redraws():
    dl = _job()
    ref = _reference(dl)
    d = FakePlotter(budget=5000.0, tell=False)
    d.open()
    with pytest.raises(PlotInterrupted):
        d.plot(dl)
    with pytest.raises(PositionUnknown, match=r"cannot ask where it stopped.*position_confirmed=True") as info:
        d.resume_after_fault()
    assert info.value.resume_from == 0 and info.value.strokes.start == 0
    d.resume_after_fault(position_confirmed=True)
    tally = compare(ref, d.sheet())
    assert tally.lost == 0 and tally.stray == 0 and tally.doubled > 0  # redrawn, never lost


def test_a_lost_position_is_remembered_in_the_state_file(tmp_path):
    dl = _job()
    state = tmp_path / "plot.json"
    d = FakePlotter(budget=5000.0, state_file=state)
    d.open()
    with pytest.raises(PlotInterrupted) as info:
        d.plot(dl)
    assert "fake" not in str(info.value).split("cable pulled")[1]  # the device is named once, by its own error
    d.lost = True
    with pytest.raises(PositionUnknown):
        d.resume_after_fault()
    assert PlotState.load(state).position_lost
    d.lost = False  # the device now reports a plausible place: still not trusted until confirmed
    with pytest.raises(PositionUnknown):
        d.resume_after_fault()
    d.resume_after_fault(position_confirmed=True)
    assert d.confirmed == len(dl) and not PlotState.load(state).position_lost


def test_resuming_from_a_missing_state_file_names_it(tmp_path):
    d = FakePlotter(state_file=tmp_path / "gone.json")
    d.open()
    with pytest.raises(ConfigError, match=r"gone\.json: no plot state to resume"):
        d.plot(_job(), resume=True)


def test_on_pause_hears_each_change_once():
    heard = []
    d = FakePlotter(on_pause=heard.append)
    d._pause_changed(True)
    d._pause_changed(True)
    d._pause_changed(False)
    assert heard == [True, False]


def test_manual_control_a_driver_lacks_is_a_clear_config_error():
    d = FakePlotter()
    d.open()
    for call, what in ((d.pen_up, "pen up"), (d.pen_down, "pen down"), (d.go_home, "home"),
                       (d.motors_off, "motors off")):
        with pytest.raises(ConfigError, match=f"{what} is not supported by this driver"):
            call()
    with pytest.raises(ConfigError, match="cannot tell whether the pen is up or down"):
        d.toggle_pen()


# -- the fault-injection campaign (slow) -------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("family, strokes", [("hp7475a", 24), ("grbl", 12), ("axidraw", 6)])
def test_fault_campaign_loses_nothing_and_resumes_drops_and_stalls_exactly(family, strokes):
    from benchmarks.faults import PATHS, campaign, format_table

    table = campaign((family,), PATHS, runs=100, seed=2026, strokes=strokes)
    print(format_table(table))
    rows = {key: row for key, row in table.items() if key[0] == family}
    assert sum(row["runs"] for row in rows.values()) == 200
    assert all(row["failed"] == 0 and row["lost"] == 0 for row in rows.values())
    for (_, _, kind), row in rows.items():
        if kind in ("drop", "stall", "pause"):  # the device knows where it stopped: exact, or it asked
            assert row["stray"] == 0 and (row["doubled"] == 0 or row["asked"] > 0), (kind, row)
        if kind == "power":  # it cannot know: every such plot asked before going on
            assert row["asked"] == row["interrupted"], row


def test_resuming_another_drawing_is_refused_naming_the_state_file_once(tmp_path):
    state = tmp_path / "plot.json"
    d = FakePlotter(budget=3000.0, state_file=state)
    d.open()
    with pytest.raises(PlotInterrupted):
        d.plot(_job(seed=4))
    other = FakePlotter(state_file=state)
    other.open()
    with pytest.raises(ConfigError) as info:
        other.plot(_job(seed=5), resume=True)
    text = str(info.value)
    assert text.count(str(state)) == 1 and text.count("plot.json") == 1
    assert "belongs to another drawing" in text


def test_a_state_file_given_as_keyword_and_a_bad_state_name_are_clear(tmp_path):
    import pixelpen
    from pixelpen.errors import ConfigError

    state = tmp_path / "job.json"
    with pixelpen.open("sim:hp7475a?speed=fast", state_file=state) as display:
        assert display.state_file == state
    with pytest.raises(ConfigError, match="state"):
        pixelpen.open("sim:hp7475a?speed=fast&state=a%00b")

"""Plot jobs in the library: a plot stopped by a fault resumes in a new process from its state file, each stroke once.

The plotter outlives the host: a simulated HP 7475A sits behind a pty (as a real plotter sits behind its
cable) while the plotting program dies and another starts.  The paper is compared with the uninterrupted
plot's as segment sets (``benchmarks.faults.compare``: lost, doubled and stray segments), not as pixels.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from benchmarks.faults import Tally, compare
from pixelpen.clock import SimulatedClock
from pixelpen.devices.plotters.base import PlotterDisplay
from pixelpen.devices.plotters.job import PlotJob, PlotResult, drawing_file, plotter_for
from pixelpen.errors import ConfigError, PlotInterrupted
from pixelpen.sim.base import create_simulator
from pixelpen.sim.transports.port import Faults
from pixelpen.sim.transports.pty import PtyBridge
from pixelpen.vector.displaylist import DisplayList

ROOT = Path(__file__).resolve().parents[3]
RESUME = """\
import sys
from pixelpen.devices.plotters.job import PlotJob

result = PlotJob.resume(sys.argv[1], to=sys.argv[2], confirm_position=False).run()
print(result.strokes, result.confirmed, result.retries)
"""
"""The documented call, run in a new process: ``python -c RESUME STATE URL``."""


def ladder(tmp_path: Path, n: int = 24, pitch: float = 6.0) -> str:
    """An SVG of n vertical 40 mm rungs, and two diagonals across them (strokes longer than a buffer's worth)."""
    lines = [f'<path d="M{10 + pitch * i},20 L{10 + pitch * i},60" stroke="black" fill="none"/>' for i in range(n)]
    lines += ['<path d="M10,70 L150,110 L10,150" stroke="black" fill="none"/>']
    path = tmp_path / "ladder.svg"
    path.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="297mm" height="210mm" viewBox="0 0 297 210">'
                    + "".join(lines) + "</svg>")
    return str(path)


def reference_paper(svg: str, make_sim_plotter, tmp_path: Path) -> DisplayList:
    """The paper of the same plot, uninterrupted."""
    plotter = make_sim_plotter("hp7475a", buffer=256)
    PlotJob.prepare(svg, to=plotter.url, optimize=False, state=tmp_path / "reference.json").run()
    return plotter.device.display_list()


def interrupted(svg: str, make_sim_plotter, state: Path, **faults: int):
    """Plot ``svg`` on a simulator that fails as ``faults`` say, with no retries; the SimPlotter."""
    plotter = make_sim_plotter("hp7475a", buffer=256, **faults)
    with pytest.raises(PlotInterrupted):
        PlotJob.prepare(svg, to=plotter.url, optimize=False, state=state, retries=0).run()
    saved = json.loads(state.read_text())
    assert 0 < saved["confirmed"] < saved["strokes"]
    return plotter


# -- resuming in a new process ---------------------------------------------------------------------------


def test_a_plot_stopped_by_a_dropped_link_resumes_in_a_new_process_each_stroke_once(tmp_path, make_sim_plotter):
    # about 20 s: the new process asks the plotter where it stopped in real time (hpgl.SETTLE_S and the longest move)
    svg = ladder(tmp_path)
    reference = reference_paper(svg, make_sim_plotter, tmp_path)
    clock = SimulatedClock()
    device = create_simulator("hp7475a", clock=clock, buffer="256")
    state = tmp_path / "plot.state"
    first = PtyBridge(device, clock=clock, faults=Faults(drop_after=550))
    second = None
    try:
        with pytest.raises(PlotInterrupted) as stopped:  # the cable is pulled after drop_after bytes
            PlotJob.prepare(svg, to=f"hp7475a:{first.path}?timeout=3", optimize=False, state=state, retries=0).run()
        assert stopped.value.state_file == state and 0 < stopped.value.resume_from < 25
        assert state.is_file() and drawing_file(state).is_file()
        second = PtyBridge(device, clock=clock)  # the cable back in: the same plotter, with its paper and buffer
        done = subprocess.run([sys.executable, "-c", RESUME, str(state), f"hp7475a:{second.path}?timeout=3"],
                              cwd=ROOT, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        assert done.stdout.split() == ["25", "25", "0"]
    finally:
        for bridge in (second, first):
            if bridge is not None:
                bridge.close()
    assert compare(reference, device.display_list()) == Tally()
    assert not state.exists() and not drawing_file(state).exists()


def test_a_job_run_again_after_an_interruption_continues_it(tmp_path, make_sim_plotter):
    svg = ladder(tmp_path)
    reference = reference_paper(svg, make_sim_plotter, tmp_path)
    plotter = make_sim_plotter("hp7475a", buffer=256, drop_after=700)  # every connection drops after 700 bytes
    job = PlotJob.prepare(svg, to=plotter.url, optimize=False, state=tmp_path / "again.json", retries=1)
    heard: list[tuple[str, int]] = []
    job.on_interrupted = lambda failure, attempt: heard.append(("stopped", attempt))
    job.on_retry = lambda attempt: heard.append(("retry", attempt))
    for _ in range(10):
        try:
            result = job.run()
            break
        except PlotInterrupted:
            assert job.resuming and job.state_file.is_file()
    else:
        pytest.fail("the plot never finished")
    assert isinstance(result, PlotResult) and result.strokes == result.confirmed == 25
    assert ("stopped", 0) in heard and ("retry", 1) in heard
    assert compare(reference, plotter.device.display_list()) == Tally()
    assert not job.state_file.exists() and not drawing_file(job.state_file).exists()


def test_resume_takes_the_plotter_the_plot_was_started_on(tmp_path, make_sim_plotter):
    state = tmp_path / "plot.state"
    plotter = interrupted(ladder(tmp_path), make_sim_plotter, state, drop_after=700)
    job = PlotJob.resume(state)
    assert isinstance(job.display, PlotterDisplay) and job.url == plotter.url
    assert job.resuming and job.state_file == state and job.placement is None


# -- refusing to resume, before any device is opened ------------------------------------------------------


def test_resuming_a_missing_or_mistyped_state_file_names_it_and_opens_nothing(tmp_path, make_sim_plotter):
    state = tmp_path / "plot.state"
    interrupted(ladder(tmp_path), make_sim_plotter, state, drop_after=700)
    fresh = make_sim_plotter("hp7475a")
    url = fresh.url
    typo = tmp_path / "plot.stat"
    with pytest.raises(ConfigError, match=f"no plot state file {typo}"):
        PlotJob.resume(typo, to=url)
    drawing_file(state).rename(drawing_file(typo))  # the drawing of a plot without its state file
    with pytest.raises(ConfigError, match=f"no plot state file {typo}"):
        PlotJob.resume(typo, to=url)
    with pytest.raises(ConfigError, match=f"cannot read {drawing_file(state)}"):  # a state without its drawing
        PlotJob.resume(state, to=url)
    assert not fresh.opened  # the plotter was never opened


@pytest.mark.parametrize("content", ["not json at all", '{"version": 99}', '["a", "list"]',
                                     '{"version": 2, "url": "x", "fingerprint": "y", "strokes": 3, "confirmed": 9}'])
def test_resuming_a_file_that_is_no_plot_state_names_it_and_opens_nothing(tmp_path, make_sim_plotter, content):
    state = tmp_path / "notes.json"
    state.write_text(content)
    fresh = make_sim_plotter("hp7475a")
    with pytest.raises(ConfigError, match="nothing to resume") as info:
        PlotJob.resume(state, to=fresh.url)
    assert str(state) in str(info.value) and not fresh.opened


def test_resuming_a_state_file_of_another_drawing_or_plotter_is_refused(tmp_path, make_sim_plotter):
    one, other = tmp_path / "one.state", tmp_path / "other.state"
    interrupted(ladder(tmp_path), make_sim_plotter, one, drop_after=700)
    (tmp_path / "b").mkdir()
    interrupted(ladder(tmp_path / "b", 30), make_sim_plotter, other, drop_after=700)
    shutil.copyfile(drawing_file(other), drawing_file(one))  # one's state beside another plot's drawing
    hp, grbl = make_sim_plotter("hp7475a"), make_sim_plotter("grbl")
    with pytest.raises(ConfigError, match="does not match the drawing saved beside it") as info:
        PlotJob.resume(one, to=hp.url)
    assert str(one) in str(info.value)
    with pytest.raises(ConfigError, match="planned for a hp7475a") as info:  # a plan in HP-GL units on a GRBL
        PlotJob.resume(other, to=grbl.url)
    assert str(other) in str(info.value)
    assert not hp.opened and not grbl.opened


def one_line() -> DisplayList:
    return DisplayList.from_polylines([np.array([[100.0, 100.0], [900.0, 100.0]])], unit_mm=0.02488)


def test_a_job_needs_a_state_file_and_sane_retries(tmp_path):
    with pytest.raises(ConfigError, match="state file"):
        PlotJob(plotter_for("sim:hp7475a?speed=fast"), one_line())
    with pytest.raises(ConfigError, match="retries"):
        PlotJob(plotter_for(f"sim:hp7475a?speed=fast&state={tmp_path / 's.json'}"), one_line(), retries=-1)
    with pytest.raises(ConfigError, match="state must be a file name"):
        PlotJob.resume(42)
    with pytest.raises(ConfigError, match="named twice"):
        PlotJob.prepare("x.svg", to=f"sim:hp7475a?state={tmp_path / 'a.json'}", state=tmp_path / "b.json")

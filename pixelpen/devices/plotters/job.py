"""A plot job: a drawing planned for one plotter, plotted with confirmed progress, retried, resumable in a new process.

Prepare a job from an SVG or picture JSON (laid out on the sheet, clipped, optimised) and run it::

    from pixelpen.devices.plotters.job import PlotJob
    from pixelpen.devices.plotters.layout import Layout

    job = PlotJob.prepare("drawing.svg", to="hp7475a:/dev/ttyUSB0", layout=Layout(fit=True, margin_mm=10),
                          state="plot.state")
    result = job.run()  # PlotResult: strokes, confirmed, retries, elapsed_s, pen_down_mm

A link fault is retried in process (``retries``, default 2: reconnect, ask the device where it stopped, go on).
When the retries do not overcome it, :meth:`PlotJob.run` raises :class:`~pixelpen.errors.PlotInterrupted`
and leaves the state file; any later process continues the plot from that file alone, each stroke drawn once::

    from pixelpen.devices.plotters.job import PlotJob

    PlotJob.resume("plot.state", to="hp7475a:/dev/ttyUSB0", confirm_position=False).run()

``to`` defaults to the URL the plot was started on.  A plotter that cannot tell where it stopped (after a power
loss, or a GRBL/AxiDraw on a new connection) makes ``run()`` raise :class:`~pixelpen.errors.PositionUnknown`:
re-home it or check the sheet, then resume with ``confirm_position=True`` (it may redraw, it never loses).
Resuming a missing, unreadable or foreign state file (another drawing, another plotter) raises
:class:`~pixelpen.errors.ConfigError` naming the file before any device is opened.

The state file (default ``FILE.plot-state.json``) is written by the display after every confirmation; beside
it ``STATE.drawing.npz`` keeps the planned drawing with the plotter's URL and profile, so that a resume plots
exactly the strokes the first run planned (the optimiser works within a time budget, so re-optimising could
order them differently).  Both are removed when the plot completes.

Interaction is by callbacks, set on the job before :meth:`~PlotJob.run`: ``on_progress(PlotProgress)`` after
every confirmation; ``on_pen_change(pen)`` on a single-pen plotter with a drawing of several pens (asked for the
first pen too; returns once the pen is in); ``pause_requested()`` polled between strokes (True: hold at the next
pen-up); ``on_pause(paused)`` once the plotter holds or goes on; ``on_interrupted(failure, attempt)`` when the
plot stops on a fault (attempt 0) or retry ``attempt`` fails; ``on_retry(attempt)`` before each retry.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pixelpen.devices.plotters.base import PlotProgress, PlotState, PlotterDisplay, fingerprint
from pixelpen.devices.plotters.layout import Layout, Placement, home_of, prepare_drawing
from pixelpen.display.registry import display_class
from pixelpen.errors import ConfigError, LinkError, ParseError, PlotInterrupted
from pixelpen.urls import check_path, format_url, parse_url
from pixelpen.vector.displaylist import DisplayList

if TYPE_CHECKING:  # the optimiser is imported when a job is optimised
    from pixelpen.vector.optimize import OptimizeReport

log = logging.getLogger(__name__)

MERGE_MM = 0.05
"""Stroke ends closer than this are joined when optimising (vpype's linemerge default)."""
STATE_SUFFIX = ".plot-state.json"
"""A drawing's default state file is the drawing's name with this added."""


def plotter_for(url: str, **kwargs: object) -> PlotterDisplay:
    """The (unopened) plotter display a URL names; ConfigError for a URL of another kind of display."""
    parsed = parse_url(url)
    scheme = parsed.target.partition("?")[0] if parsed.scheme == "sim" else parsed.scheme
    cls = display_class(scheme)
    if not issubclass(cls, PlotterDisplay):
        raise ConfigError(f"{url}: not a pen plotter (hp7475a:, grbl:, axidraw:, sim:MODEL ...); use 'pixelpen draw' "
                          "for other displays")
    return cls.from_url(parsed, **kwargs)


def with_state_file(url: str, state: str | Path | None, default: str | Path | None = None) -> tuple[str, Path]:
    """The plotter URL with the plot's state file as its ``state=`` option, and that file.

    The file is the URL's own ``state=``, else ``state``, else ``default``; ConfigError when the URL and
    ``state`` name two different files, or none is named.
    """
    parsed = parse_url(url)
    in_url = parsed.options.get("state")
    if in_url is not None and state is not None and Path(in_url) != Path(state):
        raise ConfigError(f"the state file is named twice ({state} and state={in_url} in the URL); give one")
    if in_url is not None:
        return url, Path(in_url)
    chosen = state if state is not None else default
    if chosen is None:
        raise ConfigError(f"{url}: a plot job needs a state file to resume from (state=FILE)")
    return format_url(parsed.scheme, parsed.target, {**parsed.options, "state": str(chosen)}), Path(chosen)


def optimise_for(dl: DisplayList, display: PlotterDisplay, time_budget: float | None, *,
                 dedupe: bool = True) -> tuple[DisplayList, OptimizeReport]:
    """Deduplicate (within each layer and pen), merge ends within MERGE_MM and order the strokes by pen-up time."""
    from pixelpen.vector.optimize import OptimizeReport, optimize

    report = OptimizeReport()
    result = optimize(dl, merge=MERGE_MM / dl.unit_mm, home=home_of(display), time_budget=time_budget,
                      profile=display.profile, dedupe=dedupe, report=report)
    return result, report


def drawing_file(state: Path) -> Path:
    """Where the planned drawing of the plot whose state is ``state`` is kept."""
    return Path(str(state) + ".drawing.npz")


@dataclass(frozen=True)
class SavedPlan:
    """The drawing a plot planned, kept beside its state file: what a resume plots, and for which plotter."""

    drawing: DisplayList
    source: str
    """Fingerprint of the prepared drawing before optimisation (a drawing prepared again must match it)."""
    url: str | None = None
    """The plotter URL the plot was started on (None: a file written before pixelpen kept it)."""
    profile: str | None = None
    paper: str | None = None

    def save(self, path: Path) -> None:
        """Write the plan whole, then rename it into place; ConfigError naming the place when that fails."""
        dl = self.drawing
        tmp = path.with_name(path.name + ".tmp.npz")
        try:
            np.savez(tmp, points=dl.points, offsets=dl.offsets, pens=dl.pens, layers=dl.layers,
                     unit_mm=np.float64(dl.unit_mm), source=np.str_(self.source),
                     pen_numbers=np.array(list(dl.pen_colours), dtype=np.int64),
                     pen_colours=np.array(list(dl.pen_colours.values()), dtype=np.str_),
                     url=np.str_(self.url or ""), profile=np.str_(self.profile or ""), paper=np.str_(self.paper or ""))
            os.replace(tmp, path)
        except OSError as exc:
            raise ConfigError(f"cannot write the plot state beside {path.parent or '.'}/ ({exc.strerror or exc}); "
                              "choose another place with --state FILE") from None

    @classmethod
    def load(cls, path: Path) -> SavedPlan:
        """Read a plan; ConfigError when the file cannot be read, ParseError when it is not a plot drawing."""
        try:
            with np.load(path, allow_pickle=False) as data:
                colours = dict(zip(data["pen_numbers"].tolist(), data["pen_colours"].tolist(), strict=True))
                dl = DisplayList(data["points"], data["offsets"], data["pens"], data["layers"],
                                 unit_mm=float(data["unit_mm"]), pen_colours=colours)
                said = {key: str(data[key]) or None for key in ("url", "profile", "paper") if key in data.files}
                return cls(dl, str(data["source"]), **said)
        except OSError as exc:
            raise ConfigError(f"nothing to resume: cannot read {path} ({exc.strerror or exc})") from None
        except (KeyError, ValueError) as exc:
            raise ParseError(f"not a pixelpen plot drawing: {exc}", source=str(path)) from None

    @classmethod
    def of_state(cls, state: Path, source: str | None = None) -> SavedPlan:
        """The plan of the interrupted plot recorded in ``state``; ConfigError naming the file unless it can resume.

        It refuses a missing state file (a mistyped name), one that is not a plot state, a drawing missing
        beside it, and, given the ``source`` fingerprint of a drawing prepared again, a state made for another
        drawing (another file, layers, layout or plotter).
        """
        if not state.is_file():
            raise ConfigError(f"nothing to resume: there is no plot state file {state}")
        try:
            recorded = PlotState.load(state)
            plan = cls.load(drawing_file(state))
        except ParseError as exc:
            raise ConfigError(f"nothing to resume: {exc}") from None
        if source is not None and plan.source != source:
            raise ConfigError(f"{state}: the plot state belongs to another drawing (another file, layers, layout or "
                              "plotter); refusing to resume")
        if recorded.fingerprint != fingerprint(plan.drawing) or recorded.strokes != len(plan.drawing):
            raise ConfigError(f"{state}: the plot state does not match the drawing saved beside it "
                              f"({drawing_file(state).name}); refusing to resume")
        return plan

    def check_plotter(self, display: PlotterDisplay, state: Path) -> None:
        """ConfigError unless ``display`` is the kind of plotter (profile, paper, unit) the plan was made for."""
        caps = display.capabilities
        planned = (self.profile or display.profile.name, self.paper or display.paper.name, self.drawing.unit_mm)
        if planned != (display.profile.name, display.paper.name, caps.unit_mm):
            raise ConfigError(f"{state}: the plot was planned for a {planned[0]} with paper {planned[1]}, not a "
                              f"{display.profile.name} with paper {display.paper.name}; refusing to resume")


@dataclass(frozen=True)
class PlotResult:
    """What a finished plot did."""

    strokes: int
    confirmed: int
    """Strokes the plotter confirmed on paper (all of them)."""
    retries: int
    """Retries the plot took in this run (0: no fault)."""
    elapsed_s: float
    """Seconds on the plotter's clock since the plot last (re)started."""
    pen_down_mm: float


class PlotJob:
    """A drawing planned for one plotter, with its state file and retries; :meth:`run` plots or resumes it.

    Make one with :meth:`prepare` (from a drawing file) or :meth:`resume` (from a state file), or directly
    from an unopened ``display`` whose ``state_file`` is set and a ``drawing`` in its device units.
    """

    def __init__(self, display: PlotterDisplay, drawing: DisplayList, *, source: str | None = None,
                 url: str | None = None, placement: Placement | None = None,
                 optimisation: OptimizeReport | None = None, resuming: bool = False,
                 confirm_position: bool = False, retries: int = 2) -> None:
        if display.state_file is None:
            raise ConfigError(f"{display.profile.name}: a plot job needs a display with a state file")
        if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
            raise ConfigError(f"retries must be a whole number, 0 or more, got {retries!r}")
        self.display = display
        self.drawing = drawing
        self.source = source if source is not None else fingerprint(drawing)
        self.url = url
        self.placement = placement
        """Where the drawing landed on the sheet (None: not prepared from a file in this process)."""
        self.optimisation = optimisation
        """What the optimiser did (None: not optimised in this process)."""
        self.resuming = resuming
        """The next :meth:`run` continues the plot in the state file (set once a run has saved its plan)."""
        self.confirm_position = confirm_position
        self.retries = retries
        self.on_progress: Callable[[PlotProgress], None] | None = None
        self.on_pen_change: Callable[[int], None] | None = None
        self.pause_requested: Callable[[], bool] | None = None
        self.on_pause: Callable[[bool], None] | None = None
        self.on_interrupted: Callable[[PlotInterrupted, int], None] | None = None
        self.on_retry: Callable[[int], None] | None = None

    @property
    def state_file(self) -> Path:
        """The file the plot's state is kept in (its planned drawing beside it)."""
        assert self.display.state_file is not None  # checked when the job was made
        return self.display.state_file

    @classmethod
    def prepare(cls, path: str, *, to: str, layout: Layout | None = None, layers: Sequence[str] | None = None,
                tolerance: float = 0.05, optimize: bool = True, optimize_time: float | None = None,
                dedupe: bool = True, state: str | Path | None = None, resume: bool = False,
                confirm_position: bool = False, retries: int = 2) -> PlotJob:
        """The plot of the SVG or picture JSON ``path`` on the plotter at ``to``, laid out and optimised.

        ``layout`` places it on the sheet (:class:`~pixelpen.devices.plotters.layout.Layout`); ``layers``
        keeps only those layers; ``optimize`` dedupes (unless ``dedupe`` is False), merges and orders the
        strokes within ``optimize_time`` seconds.  ``state`` is the state file (default ``PATH.plot-state.json``).
        With ``resume`` the drawing prepared from ``path`` must be the one the state file's plot was made from,
        and the job continues that plot with the strokes it planned.
        """
        url, state_file = with_state_file(to, state, path + STATE_SUFFIX)
        display = plotter_for(url)
        source, placement = prepare_drawing(path, display, layout=layout or Layout(), layers=layers,
                                            tolerance=tolerance)
        source_fp = fingerprint(source)
        report = None
        if resume:
            drawing = SavedPlan.of_state(state_file, source_fp).drawing
        elif optimize:
            drawing, report = optimise_for(source, display, optimize_time, dedupe=dedupe)
        else:
            drawing = source
        return cls(display, drawing, source=source_fp, url=to, placement=placement, optimisation=report,
                   resuming=resume, confirm_position=confirm_position, retries=retries)

    @classmethod
    def resume(cls, state: str | Path, *, to: str | None = None, confirm_position: bool = False,
               retries: int = 2) -> PlotJob:
        """The interrupted plot recorded in the state file ``state``, to continue on the plotter at ``to``.

        ``to`` defaults to the URL the plot was started on.  ConfigError naming the file, before any device
        is opened, for a missing or unreadable state file, one of another drawing, or a plotter of another
        profile or paper than the plot was planned for.  ``confirm_position``: see the module docstring.
        """
        state_file = check_path(state, "state")
        plan = SavedPlan.of_state(state_file)
        target = to if to is not None else plan.url
        if not target:
            raise ConfigError(f"{state_file}: the plot state does not say which plotter it was made on; give to=URL")
        url, state_file = with_state_file(target, state_file)
        display = plotter_for(url)
        plan.check_plotter(display, state_file)
        return cls(display, plan.drawing, source=plan.source, url=target, resuming=True,
                   confirm_position=confirm_position, retries=retries)

    def run(self) -> PlotResult:
        """Plot (or continue) the job, retrying link faults; the result once every stroke is confirmed.

        Raises PlotInterrupted when the retries did not overcome a fault and PositionUnknown when a resume
        cannot tell where the plotter stopped: the state file is kept and a later ``run()`` (or
        :meth:`resume` in another process) continues.  The state file and the drawing beside it are removed
        when the plot completes.
        """
        display, dl = self.display, self.drawing
        display.on_progress = self.on_progress
        display.on_pause = self.on_pause
        display.pause_requested = self.pause_requested
        fresh = not self.resuming
        with display:
            if fresh:
                SavedPlan(dl, self.source, self.url, display.profile.name, display.paper.name).save(
                    drawing_file(self.state_file))
                self.resuming = True
            if self.on_pen_change is not None and display.profile.pens == 1 and len(set(dl.pens.tolist())) > 1:
                display.on_pen_change = self.on_pen_change
                if fresh:  # the display asks from the second pen on: ask for the first one too
                    self.on_pen_change(int(dl.pens[0]))
            retries = 0
            try:
                display.plot(dl, resume=not fresh, position_confirmed=self.confirm_position)
            except PlotInterrupted as exc:
                if self.on_interrupted is not None:
                    self.on_interrupted(exc, 0)
                retries = self._retry(exc)
            p = display.progress()
        self.resuming = False
        for done in (self.state_file, drawing_file(self.state_file)):
            done.unlink(missing_ok=True)
        return PlotResult(p.strokes_total, p.strokes_done, retries, p.elapsed_s, p.pen_down_mm_total)

    def _retry(self, first: PlotInterrupted) -> int:
        """Resume the plot in process up to ``retries`` times; the retries taken, else the last fault raised."""
        failure = first
        for attempt in range(1, self.retries + 1):
            if self.on_retry is not None:
                self.on_retry(attempt)
            try:
                self.display.resume_after_fault()
                return attempt
            except PlotInterrupted as exc:
                failure = exc
            except LinkError as exc:
                failure = PlotInterrupted(f"reconnecting failed: {exc}", resume_from=self.display.confirmed,
                                          state_file=self.display.state_file, cause=exc)
            if self.on_interrupted is not None:
                self.on_interrupted(failure, attempt)
        raise failure

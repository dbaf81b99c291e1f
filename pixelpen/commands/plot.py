"""The ``plot`` command: an SVG or picture file onto a pen plotter, with layout, progress, pause, pen changes, retries.

``pixelpen plot FILE --to URL``: FILE is an SVG (millimetres, y down, origin at the page's top left) or a
pixelpen picture JSON (world coordinates, y up), laid on the sheet as the profile's paper says
(:mod:`pixelpen.devices.plotters.layout`); the layout options act in sheet millimetres, in vpype's order:
``--rotate``, ``--scale`` (or ``--fit``), ``--center`` in the box (the ``--page`` less ``--margin``, within the
plotter's limits).  What falls outside the device limits is clipped with a warning saying how much; the rest is
optimised (duplicates removed within each layer and pen unless ``--no-dedupe``, ends merged, order) and plotted
stroke by stroke with confirmed progress by a :class:`~pixelpen.devices.plotters.job.PlotJob`, which keeps the
state file (default ``FILE.plot-state.json``) and does the retries and the resume.  ``--dry-run`` prints the
placement, the length clipped and the time estimate without opening the device; ``--sheet FILE`` draws the
planned sheet (page, limits, margin box, strokes) into an SVG or PNG.

This module is the interaction: a progress bar on stderr; on a terminal ``p`` or space asks for a pause ("pause
requested - waiting for the pen to lift") and the plotter's own word that it holds with the pen up is shown
("paused (pen up) - press p or space to continue").  A single-pen plotter asks for each pen ("insert pen 2
(#ff0000) and press Enter").  Ctrl-C leaves the pen up and the device idle.  A plot stopped by a link fault is
resumed in process up to ``--retries`` times; after that the command prints the state file to resume from and
exits with status 3.  ``--resume`` continues from that state file, refusing a missing state file and a different
drawing (status 2).  Other errors exit with status 2 and one line.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import math
import shlex
import sys
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import IO, TYPE_CHECKING

import numpy as np

from pixelpen import geometry as geo
from pixelpen.commands import argtypes
from pixelpen.commands.keys import KeyControl
from pixelpen.devices.plotters.layout import CUT_REPORT_MM, Layout, Placement, home_of, sheet_to_device
from pixelpen.display.registry import display_class, open_display
from pixelpen.errors import ConfigError, PixelpenError, PlotInterrupted, PositionUnknown
from pixelpen.urls import format_url, parse_url
from pixelpen.vector.displaylist import DisplayList

if TYPE_CHECKING:  # the drivers and the plot job are imported when a plot runs, not at start-up
    from pixelpen.devices.plotters.base import PlotProgress, PlotterDisplay

log = logging.getLogger(__name__)

EXIT_INTERRUPTED = 3
"""Exit status of a plot stopped by a fault that retries did not overcome (resume with --resume)."""
DEMO_MODELS = ("hp7475a", "grbl", "axidraw")
"""The simulated plotters ``plot_demo`` draws the reference scene on."""
SHEET_COLOURS = ("#999999", "#6fa8dc", "#f6b26b")
"""Colours of the page outline, the plotter's limits and the margin box on a ``--sheet`` drawing."""


# ---------------------------------------------------------------------------------------------------------
# interaction: progress bar, keys, pen prompts


def _clock_text(seconds: float) -> str:
    seconds = round(max(0.0, seconds))
    h, rest = divmod(seconds, 3600)
    return f"{h}:{rest // 60:02d}:{rest % 60:02d}" if h else f"{rest // 60}:{rest % 60:02d}"


class ProgressBar:
    """A one-line progress display on a stream, redrawn at most every ``interval`` seconds of real time.

    On a terminal the line is redrawn in place; elsewhere a line is written at each ``step`` of the
    pen-down distance (10 % by default), so logs stay short.
    """

    def __init__(self, stream: IO[str] | None = None, *, interval: float = 0.2, width: int = 24,
                 now: Callable[[], float] = time.monotonic) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.interval = interval
        self.width = width
        self.now = now
        try:
            self.tty = self.stream.isatty()
        except (AttributeError, ValueError):
            self.tty = False
        self._last_time = -math.inf
        self._last_tenth = -1
        self._open_line = False

    def format(self, p: PlotProgress) -> str:
        """The progress line: bar, percent, pen-down millimetres, strokes, elapsed and ETA."""
        share = min(max(p.fraction, 0.0), 1.0)
        filled = round(share * self.width)
        bar = "#" * filled + "." * (self.width - filled)
        return (f"[{bar}] {100.0 * share:5.1f}%  {p.pen_down_mm_done:.0f}/{p.pen_down_mm_total:.0f} mm  "
                f"strokes {p.strokes_done}/{p.strokes_total}  elapsed {_clock_text(p.elapsed_s)}  "
                f"ETA {_clock_text(p.eta_s)}")

    def __call__(self, p: PlotProgress) -> None:
        """Show ``p`` unless the last line was drawn less than ``interval`` ago (the last stroke always shows)."""
        done = p.strokes_done >= p.strokes_total
        now = self.now()
        if self.tty:
            if done or now - self._last_time >= self.interval:
                self.stream.write("\r" + self.format(p))
                self._open_line = True
                self._last_time = now
        else:
            tenth = int(min(max(p.fraction, 0.0), 1.0) * 10)
            if done or tenth > self._last_tenth:
                self.stream.write(self.format(p) + "\n")
                self._last_tenth = tenth
        self.stream.flush()

    def message(self, text: str) -> None:
        """Print a message on its own line (ending the progress line first)."""
        self.end()
        self.stream.write(text + "\n")
        self.stream.flush()

    def end(self) -> None:
        """Finish the progress line on a terminal."""
        if self._open_line:
            self.stream.write("\n")
            self._open_line = False

    @contextlib.contextmanager
    def log_lines(self, logger: logging.Logger) -> Iterator[None]:
        """While inside, a record printed by ``logger``'s handlers starts on its own line, not after the bar."""
        guard = _EndLine(self)
        handlers = list(logger.handlers)
        for handler in handlers:
            handler.addFilter(guard)
        try:
            yield
        finally:
            for handler in handlers:
                handler.removeFilter(guard)


class _EndLine(logging.Filter):
    """A handler filter that ends the progress bar's line before the record is printed."""

    def __init__(self, bar: ProgressBar) -> None:
        super().__init__()
        self.bar = bar

    def filter(self, record: logging.LogRecord) -> bool:
        self.bar.end()
        return True


class PenPrompt:
    """``on_pen_change`` for single-pen plotters: asks the operator to insert the next pen and waits for Enter."""

    def __init__(self, colours: dict[int, str], bar: ProgressBar, keys: KeyControl | None,
                 stdin: IO[str] | None = None) -> None:
        self.colours = colours
        self.bar = bar
        self.keys = keys
        self.stdin = stdin

    def __call__(self, pen: int) -> None:
        """Ask for ``pen`` and return once it is in (PixelpenError if nobody can answer)."""
        what = f"insert pen {pen} ({self.colours.get(pen, 'any colour')}) and press Enter"
        self.bar.message(what)
        if self.keys is not None:
            answered = self.keys.wait_enter()
        else:
            answered = (self.stdin if self.stdin is not None else sys.stdin).readline() != ""
        if not answered:
            raise PixelpenError(f"the plot needs a pen change ({what}) but the input is closed")


# ---------------------------------------------------------------------------------------------------------
# the command


def _stdin_keys(on_toggle: Callable[[bool], None]) -> KeyControl | None:
    """A KeyControl on stdin when it is a terminal."""
    try:
        if sys.stdin is None or not sys.stdin.isatty():
            return None
        fd = sys.stdin.fileno()
    except (AttributeError, ValueError, OSError):
        return None
    return KeyControl(fd, on_toggle)


def _fault_text(failure: PlotInterrupted) -> str:
    """What went wrong, once: the link's own words when there is a cause."""
    return str(failure.cause) if failure.cause is not None else str(failure)


class PauseMessages:
    """The operator's view of a pause: the request at the key, the pause once the device holds with the pen up."""

    def __init__(self, bar: ProgressBar) -> None:
        self.bar = bar
        self.requested = False

    def key(self, paused: bool) -> None:
        """``p`` or space was pressed: a pause was requested or withdrawn."""
        self.requested = paused
        self.bar.message("pause requested - waiting for the pen to lift" if paused else "continuing")

    def device(self, paused: bool) -> None:
        """The plotter reports that it holds (pen up) or goes on; a pause nobody asked for is the plotter's own."""
        if not paused:
            self.bar.message("resumed")
        elif self.requested:
            self.bar.message("paused (pen up) - press p or space to continue")
        else:
            self.bar.message("paused at the plotter (pen up: its pause button, VIEW or paper lever) - "
                             "release it there to continue")


class FaultMessages:
    """The operator's view of faults and retries: the first fault in full, each failed retry against it."""

    def __init__(self, bar: ProgressBar, strokes: int, retries: int) -> None:
        self.bar = bar
        self.strokes = strokes
        self.retries = retries
        self.first = ""

    def interrupted(self, failure: PlotInterrupted, attempt: int) -> None:
        """The plot stopped on a fault (attempt 0) or retry ``attempt`` did."""
        text = _fault_text(failure)
        if attempt == 0:
            self.first = text
            self.bar.message(f"plot interrupted after {failure.resume_from} of {self.strokes} strokes: {text}")
        else:
            same = text == self.first
            self.bar.message(f"retry {attempt}/{self.retries} stopped" + (" the same way" if same else f": {text}"))

    def retrying(self, attempt: int) -> None:
        """Retry ``attempt`` reconnects."""
        self.bar.message(f"retry {attempt}/{self.retries}: reconnecting")


def _estimate(dl: DisplayList, display: PlotterDisplay) -> str:
    """The plot's lengths, lifts, pen changes and estimated time, in words."""
    from pixelpen.vector.motion import estimate_time

    try:
        t = estimate_time(dl, display.profile, home=home_of(display))
    except ConfigError as exc:
        return f"no time estimate ({exc})"
    return (f"{t.pen_down_mm:.0f} mm pen down, {t.pen_up_mm:.0f} mm pen up, {t.lifts} lifts, "
            f"{t.pen_changes} pen changes; estimated {_clock_text(t.total)}")


def _check_sheet(path: str, drawing: str) -> None:
    """ConfigError, before any work, for a --sheet file that cannot be written as SVG or an image."""
    from PIL import Image

    if Path(path).resolve() == Path(drawing).resolve():
        raise ConfigError(f"--sheet {path} would overwrite the drawing; name another file")
    suffix = Path(path).suffix.lower()
    if suffix != ".svg" and suffix not in Image.registered_extensions():
        raise ConfigError(f"--sheet {path}: the file name must end in .svg or an image extension such as .png")


def write_sheet(path: str, dl: DisplayList, display: PlotterDisplay, placement: Placement) -> None:
    """Draw the sheet as it will come out (page, plotter limits, margin box, strokes) into an SVG or PNG."""
    from pixelpen.vector.preview import render_preview

    to_sheet = geo.invert(sheet_to_device(display))
    strokes = [geo.apply(to_sheet, s) for s in dl.strokes()]
    pens = dl.pens.tolist()
    first = max(pens, default=0) + 1
    w, h = placement.page_mm
    frames = [((0, 0, w, h), SHEET_COLOURS[0]), (placement.limits, SHEET_COLOURS[1]), (placement.box, SHEET_COLOURS[2])]
    colours = dict(dl.pen_colours)
    for k, ((x0, y0, x1, y1), colour) in enumerate(frames):
        strokes.insert(k, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]], float))
        colours[first + k] = colour
    pens = [first + k for k in range(len(frames))] + pens
    sheet = DisplayList.from_polylines(strokes, pens=pens, unit_mm=1.0, pen_colours=colours)
    render_preview(sheet, path, show_travel=False, pen_width_mm=display.pen_width_mm)


def _print_dry_run(args: argparse.Namespace, display: PlotterDisplay, dl: DisplayList, placement: Placement) -> None:
    """What a plot would do, on stdout: the sheet, the placement, the cut, the estimate."""
    print(f"dry run: {args.file} on {args.to} ({display.profile.name}, paper {display.paper.name}); nothing was sent")
    for text in placement.lines():
        print("  " + text)
    print(f"  plot: {len(dl)} stroke{'s' * (len(dl) != 1)}; {_estimate(dl, display)}")
    if args.sheet:
        print(f"  sheet: {args.sheet}")


DRAWING_OPTIONS = (("--layers", "layers", None), ("--tolerance", "tolerance", 0.05), ("--rotate", "rotate", 0.0),
                   ("--scale", "scale", 1.0), ("--fit", "fit", False), ("--center", "center", False),
                   ("--margin", "margin", 0.0), ("--page", "page", None), ("--landscape", "landscape", False),
                   ("--portrait", "portrait", False))
"""The options that shape the drawing a state file belongs to (flag, argparse dest, default): a resume repeats them."""


def resume_command(args: argparse.Namespace) -> str:
    """The command line that resumes this plot: the same file, plotter, state and drawing options, with --resume."""
    words = ["pixelpen", "plot", args.file, "--to", args.to]
    for flag, dest, default in DRAWING_OPTIONS:
        value = getattr(args, dest)
        if value == default:
            continue
        if isinstance(value, bool):
            words.append(flag)
        elif isinstance(value, list):
            words += [flag, *value]
        else:
            words += [flag, str(value)]
    if args.state:
        words += ["--state", args.state]
    return shlex.join([*words, "--resume"])


def _layout(args: argparse.Namespace) -> Layout:
    orientation = "landscape" if args.landscape else "portrait" if args.portrait else None
    return Layout(rotate_deg=args.rotate, scale=args.scale, fit=args.fit, center=args.center,
                  margin_mm=args.margin, page=args.page, orientation=orientation)


def _state_file(args: argparse.Namespace) -> Path:
    """The plot's state file (``--state``, ``state=`` in the URL or FILE.plot-state.json), named once."""
    from pixelpen.devices.plotters.job import STATE_SUFFIX, with_state_file

    in_url = parse_url(args.to).options.get("state")
    if in_url is not None and args.state:
        raise ConfigError(f"the state file is named twice (--state {args.state} and state={in_url} in the URL); "
                          "give one")
    return with_state_file(args.to, args.state, args.file + STATE_SUFFIX)[1]


def run_plot(args: argparse.Namespace) -> int:
    """Plot FILE on the plotter at --to (see the module docstring); the exit status."""
    from pixelpen.devices.plotters.job import PlotJob

    if args.confirm_position and not args.resume:
        raise ConfigError("--confirm-position goes with --resume (after a plot stopped without knowing where)")
    if args.sheet:
        _check_sheet(args.sheet, args.file)
    state = _state_file(args)
    if args.resume and not state.is_file():
        raise ConfigError(f"nothing to resume: there is no plot state file {state} (give the --state an "
                          "interrupted plot printed)")
    bar = ProgressBar()
    job = PlotJob.prepare(args.file, to=args.to, layout=_layout(args), layers=args.layers, tolerance=args.tolerance,
                          optimize=args.optimize, optimize_time=args.optimize_time, dedupe=args.dedupe,
                          state=args.state, resume=args.resume, confirm_position=args.confirm_position,
                          retries=args.retries)
    display, dl, placement = job.display, job.drawing, job.placement
    assert placement is not None  # a prepared job has one
    for text in job.optimisation.lines() if job.optimisation is not None else ():
        bar.message(text)
    if args.sheet:
        write_sheet(args.sheet, dl, display, placement)
    if args.dry_run:
        _print_dry_run(args, display, dl, placement)
        return 0
    if placement.cut_mm > CUT_REPORT_MM:
        log.warning("%s: %.1f mm of %.1f mm of lines (%.1f %%) lie outside the %s's limits and were cut "
                    "(--fit scales the drawing into the paper; --dry-run shows the placement)",
                    args.file, placement.cut_mm, placement.total_mm, 100.0 * placement.cut_mm / placement.total_mm,
                    display.profile.name)
    if not args.resume and state.is_file():
        log.warning("%s holds an unfinished plot; plotting from the start (--resume continues it)", state)
    pauses = PauseMessages(bar)
    faults = FaultMessages(bar, len(dl), args.retries)
    keys = _stdin_keys(pauses.key)
    job.on_progress, job.on_pause = bar, pauses.device
    job.pause_requested = keys.pause_requested if keys is not None else None
    job.on_pen_change = PenPrompt(dl.pen_colours, bar, keys)
    job.on_interrupted, job.on_retry = faults.interrupted, faults.retrying
    hint = resume_command(args)
    try:
        with bar.log_lines(logging.getLogger("pixelpen")):
            try:
                result = job.run()
            except PlotInterrupted as failure:
                tries = f" after {args.retries} retries" if args.retries else ""
                bar.message(f"pixelpen plot: stopped{tries}; {failure.resume_from} of {len(dl)} strokes "
                            f"confirmed on paper; the plot state is in {state}")
                bar.message(f"resume with: {hint}")
                return EXIT_INTERRUPTED
            except PositionUnknown as exc:
                bar.message(f"pixelpen plot: stopped: {exc}")
                bar.message(f"after checking: {hint} --confirm-position")
                return EXIT_INTERRUPTED
            bar.end()
    except KeyboardInterrupt:
        bar.message(f"stopped with the pen up; continue with: {hint}")
        raise
    finally:
        if keys is not None:
            keys.close()
    print(f"plotted {args.file} on {args.to}: {result.strokes} stroke{'s' * (result.strokes != 1)}, "
          f"{result.pen_down_mm:.0f} mm of lines in {_clock_text(result.elapsed_s)}", file=sys.stderr)
    return 0


PLOT_DESCRIPTION = """\
Plot FILE on the plotter at URL.  Keys while plotting (on a terminal): p or space pauses at the
next pen-up and resumes; Ctrl-C stops with the pen up.  Exit status: 0 done, 2 error, 3 stopped
by a fault (resume with --resume)."""

PLOT_EPILOG = """\
layout, in this order (as vpype's rotate, scale, layout): --rotate, then --scale or --fit, then
--center in the box (the --page less --margin, within the plotter's limits).  Without --center or
--fit a drawing stays where its file puts it (an SVG's page top left at the sheet's top left).

simulated plotters: --to 'sim:MODEL?speed=fast' plots in simulated time; add out=PAPER.png to save
the paper when the plot ends (--to 'sim:hp7475a?speed=fast&out=paper.png'), id=NAME to reach the
device again, drop_after=N and the other fault options to rehearse a recovery
(docs/testing-with-simulators.md).

defaults for every option, --to included, can be set in the configuration file ($PIXELPEN_CONFIG,
else $XDG_CONFIG_HOME/pixelpen/config.toml or ~/.config/pixelpen/config.toml), e.g.
  [plot]
  to = "axidraw:auto"
  margin = 10
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``pixelpen plot`` to the ``pixelpen`` parser."""
    p = subparsers.add_parser(
        "plot", help="plot an SVG or picture file on a pen plotter (layout, progress, pause, pen changes, resume)",
        description=PLOT_DESCRIPTION, epilog=PLOT_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", metavar="FILE", help="SVG (millimetres) or pixelpen picture JSON")
    p.add_argument("--to", required=True, metavar="URL", help="plotter URL: hp7475a:/dev/ttyUSB0, grbl:auto, "
                   "sim:axidraw?speed=fast&out=paper.png ... (default: the configuration file's)")
    g = p.add_argument_group("layout")
    g.add_argument("--rotate", type=argtypes.finite, default=0.0, metavar="DEG",
                   help="turn the drawing clockwise by DEG degrees about its centre (first)")
    g.add_argument("--scale", type=argtypes.positive, default=1.0, metavar="S",
                   help="scale the drawing by S about its centre (after --rotate)")
    g.add_argument("--fit", action=argparse.BooleanOptionalAction, default=False,
                   help="scale the drawing to fill the box (page less margins, within the limits), centred")
    g.add_argument("--center", "--centre", action="store_true", help="centre the drawing in the box (last)")
    g.add_argument("--margin", type=argtypes.non_negative, default=0.0, metavar="MM",
                   help="keep MM millimetres free on every side of the page (with --center or --fit)")
    g.add_argument("--page", metavar="SIZE", help="page size: a4, a3, letter ... or WxH[mm|cm|in] "
                   "(default the plotter's paper; a name takes the paper's orientation)")
    turn = g.add_mutually_exclusive_group()
    turn.add_argument("--landscape", action="store_true", help="lay the page landscape (wider than high)")
    turn.add_argument("--portrait", action="store_true", help="lay the page portrait (higher than wide)")
    p.add_argument("--dry-run", action="store_true",
                   help="print the placement, what the limits cut and the time estimate; send nothing")
    p.add_argument("--sheet", metavar="SHEET.svg", help="draw the sheet as planned (page, limits, strokes) into an "
                   "SVG or PNG file")
    p.add_argument("--optimize", action=argparse.BooleanOptionalAction, default=True,
                   help="remove duplicates, merge ends and order strokes for least pen-up time (default on)")
    p.add_argument("--dedupe", action=argparse.BooleanOptionalAction, default=True,
                   help="drop a stroke that repeats another of its layer and pen (default on; --no-dedupe keeps "
                        "repeats, e.g. a line drawn twice to darken it)")
    p.add_argument("--optimize-time", type=argtypes.non_negative, default=None, metavar="S",
                   help="seconds the optimiser may spend improving the order (default: by the drawing's size)")
    p.add_argument("--layers", nargs="+", metavar="LAYER", help="plot only these layers (numbers or names)")
    p.add_argument("--state", metavar="STATE", help="plot state file for resuming (default FILE.plot-state.json)")
    p.add_argument("--resume", action="store_true", help="continue the plot recorded in the state file")
    p.add_argument("--confirm-position", action="store_true",
                   help="with --resume: the plotter was re-homed or the sheet checked; continue from the last "
                        "confirmed stroke even though the plotter cannot tell where it stopped (may redraw)")
    p.add_argument("--retries", type=argtypes.non_negative_int, default=2, metavar="N",
                   help="reconnect and resume up to N times after a link fault (default 2)")
    p.add_argument("--tolerance", type=argtypes.positive, default=0.05, metavar="MM",
                   help="SVG curve flattening tolerance in mm (default 0.05)")
    p.set_defaults(func=run_plot)


# ---------------------------------------------------------------------------------------------------------
# the demo


def plot_demo(out: Path, *, models: Sequence[str] = DEMO_MODELS) -> list[Path]:
    """Plot the reference scene on each simulated plotter model and save each paper as ``OUT/paper-MODEL.png``.

    A model whose driver or simulator cannot be loaded is skipped with a logged warning.
    """
    from pixelpen.devices.plotters.base import PlotterDisplay
    from pixelpen.scene import draw_reference
    from pixelpen.sim.base import forget_simulator, named_simulator, simulator_models

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    for model in models:
        try:
            if not issubclass(display_class(model), PlotterDisplay) or model not in simulator_models():
                raise ConfigError(f"no simulated plotter {model!r}")
        except Exception as exc:  # noqa: BLE001 - a driver or simulator that does not import must not stop the demo
            log.warning("demo: skipping %s: %s", model, exc)
            continue
        ident = f"demo-{model}-{uuid.uuid4().hex[:8]}"
        try:
            with open_display(format_url("sim", model, {"speed": "fast", "id": ident})) as display:
                draw_reference(display)
            path = out / f"paper-{model}.png"
            named_simulator(ident).save_paper(path)
            written.append(path)
        finally:
            forget_simulator(ident)
    return written

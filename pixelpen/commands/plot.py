"""The ``plot`` command: an SVG or picture file onto a pen plotter, with progress, pause, pen changes, retries, resume.

``pixelpen plot FILE --to URL``: FILE is an SVG (millimetres, y down, origin at the page's top left) or a
pixelpen picture JSON (world coordinates, y up).  The drawing goes through the plotter display's viewing
pipeline: an SVG page is laid on the paper the way the profile says the paper sits under the pen
(``origin_mm``: where the device origin lies on the sheet), true size; ``--fit`` instead scales the drawing
to fill the plottable area.  What falls outside the device limits is clipped with a warning saying how much;
the rest is optimised for plotting (duplicates removed, ends merged, order) with the device profile's
motion model, then plotted stroke by stroke with confirmed progress.

Interaction: a progress bar on stderr; on a terminal ``p`` or space pauses at the next pen-up and resumes;
a single-pen plotter asks for each pen ("insert pen 2 (#ff0000) and press Enter").  Ctrl-C leaves the pen
up and the device idle.  A plot stopped by a link fault is resumed in process up to ``--retries`` times;
after that the command prints the state file to resume from and exits with status 3.  ``--resume`` continues
from that state file, refusing a different drawing.  Other errors exit with status 2 and one line.

The state file (default ``FILE.plot-state.json``) is written by the display after every confirmation; beside
it ``STATE.drawing.npz`` keeps the optimised drawing, so that a resume plots exactly the strokes the first run
planned (the optimiser works within a time budget, so re-optimising could order them differently).  Both are
removed when the plot completes.
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import select
import sys
import threading
import time
import uuid
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import IO, TYPE_CHECKING

import numpy as np

from .. import geometry as geo
from ..display.registry import display_class, open_display
from ..errors import ConfigError, LinkError, ParseError, PixelpenError
from ..urls import format_url, parse_url
from ..vector.displaylist import DisplayList

if TYPE_CHECKING:  # the drivers, optimiser and file readers are imported when a plot runs, not at start-up
    from ..devices.plotter import PlotInterrupted, PlotProgress, PlotterDisplay

log = logging.getLogger(__name__)

EXIT_INTERRUPTED = 3
"""Exit status of a plot stopped by a fault that retries did not overcome (resume with --resume)."""
MERGE_MM = 0.05
"""Stroke ends closer than this are joined when optimising (vpype's linemerge default)."""
CLIP_EPS = 1e-9
"""Relative slack of the device rectangle when clipping: rounding noise on an edge is not a cut."""
CUT_REPORT_MM = 1e-3
"""Clipped lengths below this (rounding noise) are not reported."""
DEMO_MODELS = ("hp7475a", "grbl", "axidraw")
"""The simulated plotters ``plot_demo`` draws the reference scene on."""
PAUSE_KEYS = b"p "
ENTER_KEYS = b"\r\n"


# ---------------------------------------------------------------------------------------------------------
# the drawing: file -> display list in device units, clipped, optimised


def page_to_world(display: PlotterDisplay) -> np.ndarray:
    """3x3 matrix from SVG page millimetres (top-left origin, y down) to the display's world (mm, y up).

    The profile's paper says where the device origin lies on the sheet (``origin_mm`` from the sheet's top
    left, or bottom left with ``origin_reference = "botleft"``); without it the sheet's top-left corner is
    laid on the plottable area's top-left corner.  World coordinates are millimetres from the plottable
    area's lower-left corner, which is the device origin on a y-up device and lies ``height`` below it on
    a y-down device.
    """
    height_mm = display.capabilities.size_mm[1]
    y_up = not display.capabilities.y_down
    paper = display.paper
    if paper.origin_mm is None:
        ox, oy = 0.0, (height_mm if y_up else 0.0)
    else:
        ox, oy = paper.origin_mm
        if paper.origin_reference == "botleft":
            if paper.size_mm is None:
                raise ConfigError(f"{display.profile.name}: paper {paper.name!r} gives its origin from the bottom "
                                  "left but no size_mm, so the sheet cannot be placed")
            oy = paper.size_mm[1] - oy
    # y up: world = (x - ox, oy - y); y down: device y = y - oy and world y = height - device y
    ty = oy if y_up else height_mm + oy
    return np.array([[1.0, 0.0, -ox], [0.0, -1.0, ty], [0.0, 0.0, 1.0]])


def _fit_window(display: PlotterDisplay, lo: np.ndarray, hi: np.ndarray) -> None:
    """Point the display's window at the world box lo..hi (zero extents padded), so the drawing fills the paper."""
    extent = hi - lo
    pad = np.where(extent > 0, 0.0, max(float(extent.max()) / 2.0, 1.0))
    display.window(*(lo - pad), *(hi + pad))


def _svg_drawing(path: str, display: PlotterDisplay, fit: bool, layers: Sequence[str] | None,
                 tolerance: float) -> DisplayList:
    """An SVG as a display list in the display's device units, unclipped."""
    from ..display.picture import parse_colour
    from ..vector.build import nearest_pen
    from ..vector.svgimport import read_svg

    dl = _select_layers(read_svg(path, tolerance=tolerance), layers, path)
    to_world = page_to_world(display)
    if fit and len(dl.points):
        world = geo.apply(to_world, dl.points)
        _fit_window(display, world.min(axis=0), world.max(axis=0))
    matrix = geo.compose(display.pipeline.matrix, to_world)
    points = geo.apply(matrix, dl.points) if len(dl.points) else dl.points
    caps = display.capabilities
    pens, colours = dl.pens, dict(dl.pen_colours)
    if len(caps.pens) > 1:  # a carousel: each SVG colour takes the loaded pen nearest to it
        carousel = {p: nearest_pen(parse_colour(c), caps.pens) for p, c in dl.pen_colours.items()}
        pens = np.array([carousel.get(int(p), int(p)) for p in dl.pens], dtype=np.int32)
        colours = {p: caps.pens[p - 1] for p in set(carousel.values())}
    return DisplayList(points, dl.offsets, pens, dl.layers, dict(dl.layer_names), caps.unit_mm, colours)


def _picture_drawing(path: str, display: PlotterDisplay, fit: bool, layers: Sequence[str] | None) -> DisplayList:
    """A picture file as a display list in the display's device units, unclipped."""
    from ..display.flatten import flatten_picture
    from ..display.pictfile import load_picture
    from ..vector.build import PenLayerMap, build_display_list

    picture = load_picture(path)
    if picture.window:
        display.window(*picture.window)
    caps = display.capabilities

    def build() -> DisplayList:
        shapes = flatten_picture(picture, display.pipeline, tolerance=caps.tolerance, unit_mm=caps.unit_mm, clip=False)
        mapping = PenLayerMap(list(caps.pens) if len(caps.pens) > 1 else None)
        return build_display_list(shapes, unit_mm=caps.unit_mm, pen_width_mm=display.pen_width_mm, mapping=mapping)

    dl = _select_layers(build(), layers, path)
    if fit and len(dl.points):
        corners = display.pipeline.to_world(np.array([dl.points.min(axis=0), dl.points.max(axis=0)]))
        _fit_window(display, corners.min(axis=0), corners.max(axis=0))
        dl = _select_layers(build(), layers, path)
    return dl


def _select_layers(dl: DisplayList, wanted: Sequence[str] | None, source: str) -> DisplayList:
    """Only the strokes of the layers named (by number or, ignoring case, by name)."""
    if not wanted:
        return dl
    ids = sorted(set(dl.layers.tolist()))
    by_name = {dl.layer_names.get(i, str(i)).lower(): i for i in ids}
    chosen = set()
    for token in wanted:
        key = token.strip()
        if key.isdigit() and int(key) in ids:
            chosen.add(int(key))
        elif key.lower() in by_name:
            chosen.add(by_name[key.lower()])
        else:
            known = ", ".join(f"{i} ({dl.layer_names.get(i, i)})" for i in ids) or "none"
            raise ConfigError(f"{source}: no layer {token!r}; layers: {known}")
    return dl.select(np.isin(dl.layers, sorted(chosen)))


def load_drawing(path: str, display: PlotterDisplay, *, fit: bool = False, layers: Sequence[str] | None = None,
                 tolerance: float = 0.05) -> DisplayList:
    """Read an SVG or picture JSON into the display's device units (unclipped), laid out true size or fitted."""
    suffix = Path(path).suffix.lower()
    if suffix == ".svg":
        return _svg_drawing(path, display, fit, layers, tolerance)
    if suffix == ".json":
        return _picture_drawing(path, display, fit, layers)
    raise ParseError("expected an SVG (.svg) or a pixelpen picture (.json)", source=path, token=suffix or "no suffix")


def clip_to_device(dl: DisplayList, size: tuple[float, float]) -> tuple[DisplayList, float]:
    """Clip the strokes to the device rectangle 0..W x 0..H (device units); return the result and the length cut.

    A stroke leaving and re-entering becomes several strokes; pens and layers are kept.  Points within
    rounding error of an edge (a drawing fitted to the paper touches it) count as inside.
    """
    if not len(dl):
        return dl, 0.0
    width, height = float(size[0]), float(size[1])
    eps = CLIP_EPS * max(width, height)
    pieces, owner = geo.clip_polylines(list(dl.strokes()), (-eps, -eps, width + eps, height + eps),
                                       return_index=True)
    pieces = [np.clip(p, 0.0, [width, height]) for p in pieces]
    clipped = DisplayList.from_polylines(pieces, pens=dl.pens[owner] if len(owner) else 1,
                                         layers=dl.layers[owner] if len(owner) else 0, layer_names=dl.layer_names,
                                         unit_mm=dl.unit_mm, pen_colours=dl.pen_colours)
    return clipped, max(0.0, dl.pen_down_length() - clipped.pen_down_length())


def prepare_drawing(path: str, display: PlotterDisplay, *, fit: bool = False, layers: Sequence[str] | None = None,
                    tolerance: float = 0.05) -> DisplayList:
    """The drawing in device units, clipped to the device (with a warning naming how much was cut)."""
    dl = load_drawing(path, display, fit=fit, layers=layers, tolerance=tolerance)
    total_mm = dl.pen_down_length() * dl.unit_mm
    dl, cut = clip_to_device(dl, display.capabilities.size)
    cut_mm = cut * dl.unit_mm
    if cut_mm > CUT_REPORT_MM:
        log.warning("%s: %.1f mm of %.1f mm of lines (%.1f %%) lie outside the %s's limits and were cut "
                    "(use --fit to scale the drawing into the paper)",
                    path, cut_mm, total_mm, 100.0 * cut_mm / total_mm, display.profile.name)
    if not len(dl):
        raise ConfigError(f"{path}: nothing to plot" + (" inside the plotter's limits" if total_mm else ""))
    return dl


def optimise_for(dl: DisplayList, display: PlotterDisplay, time_budget: float) -> DisplayList:
    """Deduplicate, merge ends within MERGE_MM and order the strokes by pen-up time on the display's device."""
    from ..vector.optimize import optimize

    profile = display.profile
    home = np.asarray(profile.home, float) - [display.paper.x_range[0], display.paper.y_range[0]]
    return optimize(dl, merge=MERGE_MM / dl.unit_mm, home=(float(home[0]), float(home[1])),
                    time_budget=time_budget, profile=profile)


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


class KeyControl:
    """Keys typed while a plot runs, read from ``fd`` by a thread: ``p`` or space toggles a pause, Enter answers.

    A terminal is put in cbreak mode (keys arrive without Enter, Ctrl-C still interrupts) and restored by
    :meth:`close`.  The pause is only a request: the plotter stops at its next pen-up.
    """

    def __init__(self, fd: int, on_toggle: Callable[[bool], None] | None = None) -> None:
        self.fd = fd
        self.on_toggle = on_toggle
        self.paused = False
        self.eof = False
        self._enters = 0
        self._typed = threading.Condition()
        self._stop = threading.Event()
        self._saved: list | None = None
        if os.isatty(fd):
            import termios
            import tty

            self._saved = termios.tcgetattr(fd)
            tty.setcbreak(fd)
        self._thread = threading.Thread(target=self._run, name="pixelpen plot keys", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            ready, _, _ = select.select([self.fd], [], [], 0.1)
            if not ready:
                continue
            try:
                data = os.read(self.fd, 64)
            except OSError:
                data = b""
            if not data:
                with self._typed:
                    self.eof = True
                    self._typed.notify_all()
                return
            for byte in data:
                if byte in PAUSE_KEYS:
                    self.paused = not self.paused
                    if self.on_toggle is not None:
                        self.on_toggle(self.paused)
                elif byte in ENTER_KEYS:
                    with self._typed:
                        self._enters += 1
                        self._typed.notify_all()

    def pause_requested(self) -> bool:
        """True while the operator wants the plot paused."""
        return self.paused

    def wait_enter(self) -> bool:
        """Wait for Enter typed from now on (an earlier one does not count); False when the input ended instead."""
        with self._typed:
            before = self._enters
            while self._enters == before and not self.eof:
                self._typed.wait(0.1)  # with a timeout, so that Ctrl-C gets through
            return self._enters != before

    def close(self) -> None:
        """Stop reading and restore the terminal."""
        self._stop.set()
        self._thread.join(timeout=1.0)
        if self._saved is not None:
            import termios

            termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)
            self._saved = None


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


def plotter_for(url: str, **kwargs: object) -> PlotterDisplay:
    """The (unopened) plotter display a URL names; ConfigError for a URL of another kind of display."""
    from ..devices.plotter import PlotterDisplay

    parsed = parse_url(url)
    scheme = parsed.target.partition("?")[0] if parsed.scheme == "sim" else parsed.scheme
    cls = display_class(scheme)
    if not issubclass(cls, PlotterDisplay):
        raise ConfigError(f"{url}: not a pen plotter; 'pixelpen plot' drives plotters (hp7475a:, grbl:, axidraw:, "
                          "sim:MODEL) - use 'pixelpen draw' for other displays")
    return cls.from_url(parsed, **kwargs)


def _drawing_file(state: Path) -> Path:
    return Path(str(state) + ".drawing.npz")


def _save_drawing(path: Path, dl: DisplayList, source_fp: str) -> None:
    """Keep the drawing a plot plans beside its state file (written whole, then renamed into place)."""
    tmp = path.with_name(path.name + ".tmp.npz")
    try:
        np.savez(tmp, points=dl.points, offsets=dl.offsets, pens=dl.pens, layers=dl.layers,
                 unit_mm=np.float64(dl.unit_mm), source=np.str_(source_fp),
                 pen_numbers=np.array(list(dl.pen_colours), dtype=np.int64),
                 pen_colours=np.array(list(dl.pen_colours.values()), dtype=np.str_))
        os.replace(tmp, path)
    except OSError as exc:
        raise ConfigError(f"cannot write the plot state beside {path.parent or '.'}/ ({exc.strerror or exc}); "
                          "choose another place with --state FILE") from None


def _load_drawing(path: Path, source_fp: str) -> DisplayList:
    """The drawing a state file's plot planned; ConfigError if it was made from another source drawing."""
    try:
        with np.load(path, allow_pickle=False) as data:
            if str(data["source"]) != source_fp:
                raise ConfigError(f"{path}: the plot state belongs to another drawing (another file, layers, "
                                  "placement or plotter); refusing to resume")
            colours = dict(zip(data["pen_numbers"].tolist(), data["pen_colours"].tolist()))
            return DisplayList(data["points"], data["offsets"], data["pens"], data["layers"],
                               unit_mm=float(data["unit_mm"]), pen_colours=colours)
    except OSError as exc:
        raise ConfigError(f"nothing to resume: cannot read {path} ({exc.strerror or exc})") from None
    except (KeyError, ValueError) as exc:
        raise ParseError(f"not a pixelpen plot drawing: {exc}", source=str(path)) from None


def _retry(display: PlotterDisplay, first: PlotInterrupted, retries: int, bar: ProgressBar) -> PlotInterrupted | None:
    """Resume an interrupted plot in process up to ``retries`` times; the last interruption if all fail."""
    from ..devices.plotter import PlotInterrupted

    failure = first
    for attempt in range(1, retries + 1):
        bar.message(f"plot interrupted: {failure}; retry {attempt}/{retries}: reconnecting")
        try:
            display.resume_after_fault()
            return None
        except PlotInterrupted as exc:
            failure = exc
        except LinkError as exc:
            failure = PlotInterrupted(f"reconnecting failed: {exc}", resume_from=display.confirmed,
                                      state_file=display.state_file, cause=exc)
    return failure


def run_plot(args: argparse.Namespace) -> int:
    """Plot FILE on the plotter at --to (see the module docstring); the exit status."""
    from ..devices.plotter import PlotInterrupted, fingerprint

    bar = ProgressBar()
    display = plotter_for(args.to, on_progress=bar)
    state = Path(args.state) if args.state else display.state_file or Path(args.file + ".plot-state.json")
    display.state_file = state
    source = prepare_drawing(args.file, display, fit=args.fit, layers=args.layers, tolerance=args.tolerance)
    source_fp = fingerprint(source)
    if args.resume:
        dl = _load_drawing(_drawing_file(state), source_fp)
    else:
        dl = optimise_for(source, display, args.optimize_time) if args.optimize else source
    keys = _stdin_keys(lambda paused: bar.message(
        "pause requested: the plotter stops at the next pen-up; press p or space to go on" if paused
        else "resuming"))
    display.pause_requested = keys.pause_requested if keys is not None else None
    hint = f"pixelpen plot {args.file} --to '{args.to}' --state {state} --resume"
    try:
        with display:
            if not args.resume:
                _save_drawing(_drawing_file(state), dl, source_fp)
            if display.profile.pens == 1 and len(set(dl.pens.tolist())) > 1:
                display.on_pen_change = PenPrompt(dl.pen_colours, bar, keys)
                if not args.resume:  # the display asks from the second pen on: ask for the first one too
                    display.on_pen_change(int(dl.pens[0]))
            try:
                display.plot(dl, resume=args.resume)
            except PlotInterrupted as exc:
                failure = _retry(display, exc, args.retries, bar)
                if failure is not None:
                    bar.message(f"pixelpen plot: {failure}")
                    bar.message(f"resume with: {hint}")
                    return EXIT_INTERRUPTED
            bar.end()
            p = display.progress()
    except KeyboardInterrupt:
        bar.message(f"stopped with the pen up; continue with: {hint}")
        raise
    finally:
        if keys is not None:
            keys.close()
    for done in (state, _drawing_file(state)):
        done.unlink(missing_ok=True)
    print(f"plotted {args.file} on {args.to}: {p.strokes_total} strokes, {p.pen_down_mm_total:.0f} mm of lines in "
          f"{_clock_text(p.elapsed_s)}", file=sys.stderr)
    return 0


def cmd_plot(args: argparse.Namespace) -> int:
    """Run ``pixelpen plot``; pixelpen and file errors print one line and give exit status 2."""
    try:
        return run_plot(args)
    except (PixelpenError, OSError) as exc:
        print(f"pixelpen plot: error: {exc}", file=sys.stderr)
        return 2


def _non_negative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def _number(minimum: float, inclusive: bool) -> Callable[[str], float]:
    """An argparse type: a finite number above ``minimum`` (or equal to it when ``inclusive``)."""
    bound = f">= {minimum:g}" if inclusive else f"> {minimum:g}"

    def convert(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not (math.isfinite(value) and (value >= minimum if inclusive else value > minimum)):
            raise argparse.ArgumentTypeError(f"expected a number {bound}, got {text!r}")
        return value

    return convert


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``pixelpen plot`` to the ``pixelpen`` parser."""
    p = subparsers.add_parser(
        "plot", help="plot an SVG or picture file on a pen plotter (progress, pause, pen changes, resume)",
        description="Plot FILE on the plotter at URL. Keys while plotting (on a terminal): p or space pauses at the "
                    "next pen-up and resumes; Ctrl-C stops with the pen up. Exit status: 0 done, 2 error, 3 stopped by "
                    "a fault (resume with --resume).")
    p.add_argument("file", metavar="FILE", help="SVG (millimetres) or pixelpen picture JSON")
    p.add_argument("--to", required=True, metavar="URL", help="plotter URL: hp7475a:/dev/ttyUSB0, grbl:auto, "
                   "sim:axidraw?speed=fast ...")
    p.add_argument("--optimize", action=argparse.BooleanOptionalAction, default=True,
                   help="remove duplicates, merge ends and order strokes for least pen-up time (default on)")
    p.add_argument("--optimize-time", type=_number(0.0, True), default=1.0, metavar="S",
                   help="seconds the optimiser may spend improving the order (default 1)")
    p.add_argument("--fit", action=argparse.BooleanOptionalAction, default=False,
                   help="scale the drawing to fill the paper (default: true size, placed as on the page)")
    p.add_argument("--layers", nargs="+", metavar="LAYER", help="plot only these layers (numbers or names)")
    p.add_argument("--state", metavar="STATE", help="plot state file for resuming (default FILE.plot-state.json)")
    p.add_argument("--resume", action="store_true", help="continue the plot recorded in the state file")
    p.add_argument("--retries", type=_non_negative_int, default=2, metavar="N",
                   help="reconnect and resume up to N times after a link fault (default 2)")
    p.add_argument("--tolerance", type=_number(0.0, False), default=0.05, metavar="MM",
                   help="SVG curve flattening tolerance in mm (default 0.05)")
    p.set_defaults(func=cmd_plot)


# ---------------------------------------------------------------------------------------------------------
# the demo


def plot_demo(out: Path, *, models: Sequence[str] = DEMO_MODELS) -> list[Path]:
    """Plot the reference scene on each simulated plotter model and save each paper as ``OUT/paper-MODEL.png``.

    A model whose driver or simulator cannot be loaded is skipped with a logged warning.
    """
    from ..devices.plotter import PlotterDisplay
    from ..scene import draw_reference
    from ..sim.base import forget_simulator, named_simulator, simulator_models

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
            named_simulator(ident).save_paper(path)  # type: ignore[attr-defined]
            written.append(path)
        finally:
            forget_simulator(ident)
    return written

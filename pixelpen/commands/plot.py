"""The ``plot`` command: an SVG or picture file onto a pen plotter, with layout, progress, pause, pen changes, retries, resume.

``pixelpen plot FILE --to URL``: FILE is an SVG (millimetres, y down, origin at the page's top left) or a
pixelpen picture JSON (world coordinates, y up).  An SVG page is laid on the paper the way the profile says the
paper sits under the pen (``origin_mm``: where the device origin lies on the sheet), true size.  The layout
options then act in sheet millimetres, in vpype's order (:class:`Layout`): ``--rotate``, ``--scale`` (or
``--fit``), ``--center`` in the box (the ``--page`` less ``--margin``, within the plotter's limits).  What falls
outside the device limits is clipped with a warning saying how much; the rest is optimised for plotting
(duplicates removed within each layer and pen unless ``--no-dedupe``, ends merged, order) with the device
profile's motion model, then plotted stroke by stroke with confirmed progress.  ``--dry-run`` prints the
placement, the length clipped and the time estimate without opening the device; ``--sheet FILE`` draws the
planned sheet (page, limits, margin box, strokes) into an SVG or PNG.

Interaction: a progress bar on stderr; on a terminal ``p`` or space asks for a pause ("pause requested -
waiting for the pen to lift") and the plotter's own word that it holds with the pen up is shown ("paused (pen
up) - press p or space to continue").  A single-pen plotter asks for each pen ("insert pen 2 (#ff0000) and press
Enter").  Ctrl-C leaves the pen up and the device idle.  A plot stopped by a link fault is resumed in process up
to ``--retries`` times; after that the command prints the state file to resume from and exits with status 3.
``--resume`` continues from that state file, refusing a missing state file and a different drawing (status 2).
Other errors exit with status 2 and one line.

The state file (default ``FILE.plot-state.json``) is written by the display after every confirmation; beside
it ``STATE.drawing.npz`` keeps the optimised drawing, so that a resume plots exactly the strokes the first run
planned (the optimiser works within a time budget, so re-optimising could order them differently).  Both are
removed when the plot completes.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import math
import os
import select
import shlex
import sys
import threading
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import IO, TYPE_CHECKING

import numpy as np

from pixelpen import geometry as geo
from pixelpen.display.registry import display_class, open_display
from pixelpen.errors import ConfigError, LinkError, ParseError, PixelpenError
from pixelpen.urls import PAPER_MM, format_url, parse_size, parse_url, to_mm
from pixelpen.vector.displaylist import DisplayList

if TYPE_CHECKING:  # the drivers, optimiser and file readers are imported when a plot runs, not at start-up
    from pixelpen.devices.plotters.base import PlotInterrupted, PlotProgress, PlotterDisplay
    from pixelpen.vector.optimize import OptimizeReport

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
SHEET_COLOURS = ("#999999", "#6fa8dc", "#f6b26b")
"""Colours of the page outline, the plotter's limits and the margin box on a ``--sheet`` drawing."""


# ---------------------------------------------------------------------------------------------------------
# the drawing: file -> display list in device units, laid out on the sheet, clipped, optimised


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


def sheet_to_device(display: PlotterDisplay) -> np.ndarray:
    """3x3 matrix from sheet millimetres (the sheet's top left, y down) to device units, through the default window."""
    return geo.compose(display.pipeline.matrix, page_to_world(display))


@dataclass(frozen=True)
class Layout:
    """How a drawing is laid on the sheet, in this order (vpype's): rotate, scale (or fit), then centre in the box.

    All in sheet millimetres (origin at the sheet's top left, y down the sheet).  ``rotate_deg`` turns the
    drawing clockwise about the centre of its bounds; ``scale`` scales it about that centre; ``fit`` instead
    scales it to fill the box; ``center`` (implied by ``fit``) moves the centre of its bounds to the box's
    centre.  The box is the page less ``margin_mm`` on every side, within the plotter's limits.  The page is
    ``page`` (a paper name or ``WxH[mm|cm|in]``; a paper name takes the orientation of the plotter's paper)
    or the plotter's paper; ``orientation`` ``"landscape"`` or ``"portrait"`` turns the page that way.
    Without ``center`` or ``fit`` the drawing stays where its file puts it (an SVG's page on the sheet).
    """

    rotate_deg: float = 0.0
    scale: float = 1.0
    fit: bool = False
    center: bool = False
    margin_mm: float = 0.0
    page: str | None = None
    orientation: str | None = None

    def __post_init__(self) -> None:
        if self.fit and self.scale != 1.0:
            raise ConfigError("give --scale or --fit, not both (--fit chooses the scale)")
        if self.margin_mm and not (self.center or self.fit):
            raise ConfigError("--margin places the drawing only with --center or --fit")
        if self.orientation not in (None, "landscape", "portrait"):
            raise ConfigError(f"orientation must be landscape or portrait, got {self.orientation!r}")

    def page_size(self, display: PlotterDisplay) -> tuple[float, float]:
        """The page in millimetres (width, height) as it lies under the pen."""
        paper = display.paper.size_mm or display.capabilities.size_mm
        if self.page is None:
            w, h = paper
        else:
            try:
                w, h, unit = parse_size(self.page, "mm")
                w, h = to_mm(w, unit), to_mm(h, unit)
            except (ValueError, KeyError) as exc:
                raise ConfigError(f"--page {self.page}: {exc}") from None
            if not (math.isfinite(w) and math.isfinite(h)):
                raise ConfigError(f"--page {self.page}: the size must be finite")
            if self.page.strip().lower() in PAPER_MM and (w > h) != (paper[0] > paper[1]):
                w, h = h, w
        if self.orientation is not None and (w > h) != (self.orientation == "landscape") and w != h:
            w, h = h, w
        return float(w), float(h)

    def matrix(self, points: np.ndarray, box: tuple[float, float, float, float]) -> tuple[np.ndarray, float]:
        """The 3x3 layout transform of sheet-millimetre ``points`` into ``box`` and its scale factor."""
        if not len(points):
            return np.eye(3), 1.0
        lo, hi = points.min(axis=0), points.max(axis=0)
        rot = geo.rotate(math.radians(self.rotate_deg), about=(lo + hi) / 2)
        turned = geo.apply(rot, points)
        lo, hi = turned.min(axis=0), turned.max(axis=0)
        centre = (lo + hi) / 2
        factor = self.scale
        if self.fit:
            extent = hi - lo
            room = np.array([box[2] - box[0], box[3] - box[1]])
            ratios = room[extent > 0] / extent[extent > 0]
            factor = float(ratios.min()) if len(ratios) else 1.0
        moved = np.array([(box[0] + box[2]) / 2, (box[1] + box[3]) / 2]) if self.center or self.fit else centre
        return geo.compose(geo.translate(*(moved - centre)), geo.scale(factor, factor, about=centre), rot), factor


@dataclass
class Placement:
    """Where a drawing lands on the sheet (sheet millimetres) and what the plotter's limits cut off."""

    page_mm: tuple[float, float]
    limits: tuple[float, float, float, float]
    box: tuple[float, float, float, float]
    bounds: tuple[float, float, float, float] | None
    scale: float
    rotate_deg: float
    total_mm: float
    cut_mm: float

    def lines(self) -> list[str]:
        """The placement in words, for a dry run."""
        w, h = self.page_mm
        x0, y0, x1, y1 = self.limits
        out = [f"page: {w:g} x {h:g} mm; the plotter reaches x {x0:.1f}..{x1:.1f}, y {y0:.1f}..{y1:.1f} mm "
               "from the page's top left"]
        if self.bounds is not None:
            bx0, by0, bx1, by1 = self.bounds
            how = [f"rotated {self.rotate_deg:g} deg"] if self.rotate_deg else []
            how += [f"scaled {self.scale:.4g}x"] if self.scale != 1.0 else []
            out.append(f"drawing: {bx1 - bx0:.1f} x {by1 - by0:.1f} mm at x {bx0:.1f}..{bx1:.1f}, "
                       f"y {by0:.1f}..{by1:.1f} mm" + (f" ({', '.join(how)})" if how else ""))
        share = 100.0 * self.cut_mm / self.total_mm if self.total_mm else 0.0
        out.append(f"clipped: {self.cut_mm:.1f} mm of {self.total_mm:.1f} mm of lines ({share:.1f} %) "
                   "lie outside the plotter's limits" if self.cut_mm > CUT_REPORT_MM else "clipped: nothing")
        return out


def _svg_drawing(path: str, display: PlotterDisplay, layers: Sequence[str] | None, tolerance: float) -> DisplayList:
    """An SVG as a display list in the display's device units, unclipped and as its page lies on the sheet."""
    from pixelpen.display.picture import parse_colour
    from pixelpen.display.vectorize import nearest_pen
    from pixelpen.vector.svgimport import read_svg

    dl = _select_layers(read_svg(path, tolerance=tolerance), layers, path)
    points = geo.apply(sheet_to_device(display), dl.points) if len(dl.points) else dl.points
    caps = display.capabilities
    pens, colours = dl.pens, dict(dl.pen_colours)
    if len(caps.pens) > 1:  # a carousel: each SVG colour takes the loaded pen nearest to it
        carousel = {p: nearest_pen(parse_colour(c), caps.pens) for p, c in dl.pen_colours.items()}
        pens = np.array([carousel.get(int(p), int(p)) for p in dl.pens], dtype=np.int32)
        colours = {p: caps.pens[p - 1] for p in set(carousel.values())}
    return DisplayList(points, dl.offsets, pens, dl.layers, dict(dl.layer_names), caps.unit_mm, colours)


def _picture_drawing(path: str, display: PlotterDisplay, layers: Sequence[str] | None, tolerance: float) -> DisplayList:
    """A picture file as a display list in the display's device units, unclipped (its window fills the paper)."""
    from pixelpen.display.flatten import flatten_picture
    from pixelpen.display.pictfile import load_picture
    from pixelpen.display.vectorize import PenLayerMap, build_display_list

    picture = load_picture(path)
    if picture.window:
        display.window(*picture.window)
    caps = display.capabilities
    shapes = flatten_picture(picture, display.pipeline, tolerance=tolerance, unit_mm=caps.unit_mm, clip=False)
    mapping = PenLayerMap(list(caps.pens) if len(caps.pens) > 1 else None)
    dl = build_display_list(shapes, unit_mm=caps.unit_mm, pen_width_mm=display.pen_width_mm, mapping=mapping)
    return _select_layers(dl, layers, path)


def _select_layers(dl: DisplayList, wanted: Sequence[str] | None, source: str) -> DisplayList:
    """Only the strokes of the layers named (by number or, ignoring case, by name)."""
    if not wanted:
        return dl
    ids = sorted(set(dl.layers.tolist()))
    by_name = {dl.layer_names.get(i, str(i)).lower(): i for i in ids}
    chosen = set()
    for token in wanted:
        key = token.strip()
        if key.isdecimal() and key.isascii() and int(key) in ids:
            chosen.add(int(key))
        elif key.lower() in by_name:
            chosen.add(by_name[key.lower()])
        else:
            known = ", ".join(f"{i} ({dl.layer_names.get(i, i)})" for i in ids) or "none"
            raise ConfigError(f"{source}: no layer {token!r}; layers: {known}")
    return dl.select(np.isin(dl.layers, sorted(chosen)))


def load_drawing(path: str, display: PlotterDisplay, *, layers: Sequence[str] | None = None,
                 tolerance: float = 0.05, detail: float = 1.0) -> DisplayList:
    """Read an SVG or picture JSON into the display's device units (unclipped, true size, as the file places it).

    ``detail`` > 1 flattens curves that much finer (for a drawing that will be scaled up by that factor).
    """
    suffix = Path(path).suffix.lower()
    if suffix == ".svg":
        return _svg_drawing(path, display, layers, tolerance / detail)
    if suffix == ".json":
        return _picture_drawing(path, display, layers, display.capabilities.tolerance / detail)
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


def _rect(points: np.ndarray) -> tuple[float, float, float, float]:
    lo, hi = points.min(axis=0), points.max(axis=0)
    return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])


def prepare_drawing(path: str, display: PlotterDisplay, *, layout: Layout = Layout(),
                    layers: Sequence[str] | None = None, tolerance: float = 0.05) -> tuple[DisplayList, Placement]:
    """The drawing in device units, laid out on the sheet and clipped to the device; where it landed."""
    to_device = sheet_to_device(display)  # before a picture's window changes the display's pipeline
    to_sheet = geo.invert(to_device)
    limits = _rect(geo.apply(to_sheet, np.array([[0.0, 0.0], display.capabilities.size])))
    page = layout.page_size(display)
    m = layout.margin_mm
    box = (max(m, limits[0]), max(m, limits[1]), min(page[0] - m, limits[2]), min(page[1] - m, limits[3]))
    if box[0] >= box[2] or box[1] >= box[3]:
        raise ConfigError(f"a {page[0]:g} x {page[1]:g} mm page less {m:g} mm margins leaves no room within the "
                          f"{display.profile.name}'s limits")
    dl = load_drawing(path, display, layers=layers, tolerance=tolerance)
    matrix, factor = layout.matrix(geo.apply(to_sheet, dl.points) if len(dl.points) else dl.points, box)
    if factor > 1.0 + 1e-9:  # scaled up: flatten the curves finer, so they stay within the tolerance on paper
        dl = load_drawing(path, display, layers=layers, tolerance=tolerance, detail=factor)
    if len(dl.points) and not np.allclose(matrix, np.eye(3)):
        dl = replace(dl, points=geo.apply(geo.compose(to_device, matrix, to_sheet), dl.points))
    total = dl.pen_down_length() * dl.unit_mm
    bounds = _rect(geo.apply(to_sheet, dl.points)) if len(dl.points) else None
    dl, cut = clip_to_device(dl, display.capabilities.size)
    placement = Placement(page, limits, box, bounds, factor, layout.rotate_deg, total, cut * dl.unit_mm)
    if not len(dl):
        raise ConfigError(f"{path}: nothing to plot" + (" inside the plotter's limits" if total else ""))
    return dl, placement


def home_of(display: PlotterDisplay) -> tuple[float, float]:
    """The profile's home in the display list's frame (device units from the plottable area's corner)."""
    home = np.asarray(display.profile.home, float) - [display.paper.x_range[0], display.paper.y_range[0]]
    return float(home[0]), float(home[1])


def optimise_for(dl: DisplayList, display: PlotterDisplay, time_budget: float | None, *,
                 dedupe: bool = True) -> tuple[DisplayList, OptimizeReport]:
    """Deduplicate (within each layer and pen), merge ends within MERGE_MM and order the strokes by pen-up time."""
    from pixelpen.vector.optimize import OptimizeReport, optimize

    report = OptimizeReport()
    result = optimize(dl, merge=MERGE_MM / dl.unit_mm, home=home_of(display), time_budget=time_budget,
                      profile=display.profile, dedupe=dedupe, report=report)
    return result, report


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
    from pixelpen.devices.plotters.base import PlotterDisplay

    parsed = parse_url(url)
    scheme = parsed.target.partition("?")[0] if parsed.scheme == "sim" else parsed.scheme
    cls = display_class(scheme)
    if not issubclass(cls, PlotterDisplay):
        raise ConfigError(f"{url}: not a pen plotter (hp7475a:, grbl:, axidraw:, sim:MODEL ...); use 'pixelpen draw' "
                          "for other displays")
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


def _load_drawing(path: Path) -> tuple[DisplayList, str]:
    """The drawing a state file's plot planned and the fingerprint of the source drawing it was made from."""
    try:
        with np.load(path, allow_pickle=False) as data:
            colours = dict(zip(data["pen_numbers"].tolist(), data["pen_colours"].tolist()))
            dl = DisplayList(data["points"], data["offsets"], data["pens"], data["layers"],
                             unit_mm=float(data["unit_mm"]), pen_colours=colours)
            return dl, str(data["source"])
    except OSError as exc:
        raise ConfigError(f"nothing to resume: cannot read {path} ({exc.strerror or exc})") from None
    except (KeyError, ValueError) as exc:
        raise ParseError(f"not a pixelpen plot drawing: {exc}", source=str(path)) from None


def resumable_drawing(state: Path, source_fp: str) -> DisplayList:
    """The planned drawing of the interrupted plot recorded in ``state``; ConfigError unless it can resume.

    It refuses a missing state file (a mistyped ``--state``), a drawing missing beside it, and a state made
    for another drawing (another file, layers, layout or plotter).
    """
    from pixelpen.devices.plotters.base import PlotState, fingerprint

    if not state.is_file():
        raise ConfigError(f"nothing to resume: there is no plot state file {state} (give the --state an "
                          "interrupted plot printed)")
    recorded = PlotState.load(state)
    dl, made_from = _load_drawing(_drawing_file(state))
    if made_from != source_fp:
        raise ConfigError(f"{state}: the plot state belongs to another drawing (another file, layers, layout or "
                          "plotter); refusing to resume")
    if recorded.fingerprint != fingerprint(dl) or recorded.strokes != len(dl):
        raise ConfigError(f"{state}: the plot state does not match the drawing saved beside it "
                          f"({_drawing_file(state).name}); refusing to resume")
    return dl


def _fault_text(failure: PlotInterrupted) -> str:
    """What went wrong, once: the link's own words when there is a cause."""
    return str(failure.cause) if failure.cause is not None else str(failure)


def _retry(display: PlotterDisplay, first: PlotInterrupted, retries: int, bar: ProgressBar) -> PlotInterrupted | None:
    """Resume an interrupted plot in process up to ``retries`` times; the last interruption if all fail."""
    from pixelpen.devices.plotters.base import PlotInterrupted

    failure = first
    for attempt in range(1, retries + 1):
        bar.message(f"retry {attempt}/{retries}: reconnecting")
        try:
            display.resume_after_fault()
            return None
        except PlotInterrupted as exc:
            failure = exc
        except LinkError as exc:
            failure = PlotInterrupted(f"reconnecting failed: {exc}", resume_from=display.confirmed,
                                      state_file=display.state_file, cause=exc)
        same = _fault_text(failure) == _fault_text(first)
        bar.message(f"retry {attempt}/{retries} stopped" + (" the same way" if same else f": {_fault_text(failure)}"))
    return failure


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
    return shlex.join(words + ["--resume"])


def _layout(args: argparse.Namespace) -> Layout:
    orientation = "landscape" if args.landscape else "portrait" if args.portrait else None
    return Layout(rotate_deg=args.rotate, scale=args.scale, fit=args.fit, center=args.center,
                  margin_mm=args.margin, page=args.page, orientation=orientation)


def _with_state(args: argparse.Namespace) -> tuple[str, Path]:
    """The plotter URL with the plot's state file as its ``state=`` option, and that file."""
    parsed = parse_url(args.to)
    in_url = parsed.options.get("state")
    if in_url is not None and args.state:
        raise ConfigError(f"the state file is named twice (--state {args.state} and state={in_url} in the URL); "
                          "give one")
    if in_url is not None:
        return args.to, Path(in_url)
    state = args.state or args.file + ".plot-state.json"
    return format_url(parsed.scheme, parsed.target, {**parsed.options, "state": state}), Path(state)


def run_plot(args: argparse.Namespace) -> int:
    """Plot FILE on the plotter at --to (see the module docstring); the exit status."""
    from pixelpen.devices.plotters.base import PlotInterrupted, PositionUnknown, fingerprint

    if args.confirm_position and not args.resume:
        raise ConfigError("--confirm-position goes with --resume (after a plot stopped without knowing where)")
    if args.sheet:
        _check_sheet(args.sheet, args.file)
    bar = ProgressBar()
    pauses = PauseMessages(bar)
    url, state = _with_state(args)
    display = plotter_for(url, on_progress=bar, on_pause=pauses.device)
    source, placement = prepare_drawing(args.file, display, layout=_layout(args), layers=args.layers,
                                        tolerance=args.tolerance)
    source_fp = fingerprint(source)
    if args.resume:
        dl = resumable_drawing(state, source_fp)
    elif args.optimize:
        dl, report = optimise_for(source, display, args.optimize_time, dedupe=args.dedupe)
        for text in report.lines():
            bar.message(text)
    else:
        dl = source
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
    keys = _stdin_keys(pauses.key)
    display.pause_requested = keys.pause_requested if keys is not None else None
    hint = resume_command(args)
    try:
        with display, bar.log_lines(logging.getLogger("pixelpen")):
            if not args.resume:
                _save_drawing(_drawing_file(state), dl, source_fp)
            if display.profile.pens == 1 and len(set(dl.pens.tolist())) > 1:
                display.on_pen_change = PenPrompt(dl.pen_colours, bar, keys)
                if not args.resume:  # the display asks from the second pen on: ask for the first one too
                    display.on_pen_change(int(dl.pens[0]))
            try:
                try:
                    display.plot(dl, resume=args.resume, position_confirmed=args.confirm_position)
                except PlotInterrupted as exc:
                    bar.message(f"plot interrupted after {exc.resume_from} of {len(dl)} strokes: {_fault_text(exc)}")
                    failure = _retry(display, exc, args.retries, bar)
                    if failure is not None:
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
            p = display.progress()
    except KeyboardInterrupt:
        bar.message(f"stopped with the pen up; continue with: {hint}")
        raise
    finally:
        if keys is not None:
            keys.close()
    for done in (state, _drawing_file(state)):
        done.unlink(missing_ok=True)
    print(f"plotted {args.file} on {args.to}: {p.strokes_total} stroke{'s' * (p.strokes_total != 1)}, "
          f"{p.pen_down_mm_total:.0f} mm of lines in "
          f"{_clock_text(p.elapsed_s)}", file=sys.stderr)
    return 0


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


def _angle(text: str) -> float:
    return _number(-math.inf, False)(text)


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
    g.add_argument("--rotate", type=_angle, default=0.0, metavar="DEG",
                   help="turn the drawing clockwise by DEG degrees about its centre (first)")
    g.add_argument("--scale", type=_number(0.0, False), default=1.0, metavar="S",
                   help="scale the drawing by S about its centre (after --rotate)")
    g.add_argument("--fit", action=argparse.BooleanOptionalAction, default=False,
                   help="scale the drawing to fill the box (page less margins, within the limits), centred")
    g.add_argument("--center", "--centre", action="store_true", help="centre the drawing in the box (last)")
    g.add_argument("--margin", type=_number(0.0, True), default=0.0, metavar="MM",
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
    p.add_argument("--optimize-time", type=_number(0.0, True), default=None, metavar="S",
                   help="seconds the optimiser may spend improving the order (default: by the drawing's size)")
    p.add_argument("--layers", nargs="+", metavar="LAYER", help="plot only these layers (numbers or names)")
    p.add_argument("--state", metavar="STATE", help="plot state file for resuming (default FILE.plot-state.json)")
    p.add_argument("--resume", action="store_true", help="continue the plot recorded in the state file")
    p.add_argument("--confirm-position", action="store_true",
                   help="with --resume: the plotter was re-homed or the sheet checked; continue from the last "
                        "confirmed stroke even though the plotter cannot tell where it stopped (may redraw)")
    p.add_argument("--retries", type=_non_negative_int, default=2, metavar="N",
                   help="reconnect and resume up to N times after a link fault (default 2)")
    p.add_argument("--tolerance", type=_number(0.0, False), default=0.05, metavar="MM",
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
            named_simulator(ident).save_paper(path)  # type: ignore[attr-defined]
            written.append(path)
        finally:
            forget_simulator(ident)
    return written

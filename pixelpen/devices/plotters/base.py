"""What every pen plotter shares: the link, stroke-by-stroke plotting with confirmed progress,
pause at pen-up, pen changes, resume after faults (in process or from a state file), and safe stops.

A plotter family (HPGL, GRBL, EBB) subclasses :class:`PlotterDisplay` and implements the device core
(:class:`~pixelpen.devices.plotters.family.PlotterFamily`: handshake, stroke streaming, polling, draining,
pens, the device's pause, the safe stop; where it stopped and manual control with safe defaults).

Confirmation is the device's word that a stroke is on paper (an output request answered after it,
a status report, an idle motor query), not merely that its bytes were received.

Resuming draws each stroke exactly once: strokes from the last confirmed one to the last one sent
are in doubt; after reconnecting the base asks the device where it stopped (``_where``) and
:func:`locate` finds that point in the strokes in doubt (pen-up travel in a straight line to a
stroke's first point, pen down along it, pen up at its end).  The plot continues with the rest of
the interrupted stroke.  A position that matches nothing, matches several different amounts of
drawing (a closed stroke seen with the pen up at its start/end, a path that revisits a point), or
that the device lost (power loss, reset) raises :class:`PositionUnknown` instead of guessing; a
resume with ``position_confirmed=True`` then continues from the earliest possible point (the last
confirmed stroke when nothing is known): it may redraw, it never loses.  A device error in known strokes
(``_mark_damaged``) has those strokes drawn again whole before the plot goes on from where it stopped; one whose
damage the family measured (``_mark_missing``: the exact piece the device skipped) has only that piece drawn.
Families also say what the device acknowledged reaching (``_acknowledged``: after a power cycle a device that
restarts at home, ``restarts_at_home``, continues from there once confirmed) and what went out
(``_written_to``: no place after it is a candidate for :func:`locate`).

Limits: the strokes in doubt are those sent since the last confirmation (bounded by the family's
confirmation interval); :func:`locate` costs one pass over their points.  A display opened with an
unfinished state file asks the device where it stopped before its handshake (HP-GL: at least
``hpgl.SETTLE_S`` seconds).

Longer than 600 lines because the resume is one piece of state (confirmed, sent, written, acknowledged,
damaged, missing, lifts) read and written by the plot loop, the fault handlers and the state file alike.

Beside this module: ``family`` (the device core), ``manual`` (pen up/down, home, motors off), ``resume``
(DeviceWhere, locate, ResumePoint), ``state`` (the state file, fingerprint), ``progress`` (PlotProgress and
the ETA); the names importers used are importable from here too.  URL options are
declared as specs (``OPTIONS``; each family adds its own) and ``sim:`` URLs are split by the generic
``Display.split_sim_url`` (``SIM_SHARED``: paper; ``SIM_TRANSPORT``: baud, flow).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.devices.plotters.manual import ManualControl
from pixelpen.devices.plotters.progress import (
    PlotProgress,
    ProgressCallback,
    cumulative_pen_down_mm,
    estimate_seconds,
)
from pixelpen.devices.plotters.resume import DeviceWhere, ResumePoint, in_full_stroke, locate, not_after
from pixelpen.devices.plotters.state import STATE_VERSION, PlotState, fingerprint, unfinished
from pixelpen.display.capabilities import Capabilities
from pixelpen.display.kinds import VectorDisplay
from pixelpen.drivers.serial import SerialLink
from pixelpen.drivers.stream import Link
from pixelpen.errors import (
    ConfigError,
    DeviceFault,
    LinkError,
    ParseError,
    PixelpenError,
    PlotInterrupted,
    PositionUnknown,
    ProtocolError,
    URLError,
)
from pixelpen.options import OptionSpec, OptionValues, choice, integer, positive, text
from pixelpen.profiles.model import DeviceProfile, load_profile
from pixelpen.urls import DeviceURL, check_path, format_url
from pixelpen.vector.displaylist import DisplayList

__all__ = [  # the names importers find here; resume, state file and progress live in their own modules
    "STATE_VERSION", "DeviceFault", "DeviceWhere", "PauseCallback", "PenChange", "PlotInterrupted", "PlotProgress",
    "PlotState", "PlotterDisplay", "PositionUnknown", "ProgressCallback", "ResumePoint", "fingerprint", "locate",
]

log = logging.getLogger(__name__)


PenChange = Callable[[int], None]
"""Called on single-pen devices when the next stroke needs another pen; returns when it is in."""
PauseCallback = Callable[[bool], None]
"""Called with True once the device has actually paused (idle, pen up), with False when it goes on."""


class PlotterDisplay(VectorDisplay, ManualControl):
    """A pen plotter reached through a Link: plots, confirms, pauses at pen-up, resumes, stops safe."""

    simulated: ClassVar[bool] = True
    profile_name: ClassVar[str] = ""
    """Built-in profile the scheme uses unless the URL names another."""
    family: ClassVar[str] = ""
    """Simulator model name for ``sim:`` URLs (usually the scheme)."""
    lifts_after_each_stroke: bool = True
    """The device may rest with the pen lifted at the end of any stroke (False: only after ``_lifted_in_place``)."""
    rests_pen_down_at_start: bool = True
    """The device may rest with the pen lowered on a stroke's first point before drawing it."""
    restarts_at_home: ClassVar[bool] = False
    """After a power cycle the device stands at home with its coordinates unchanged (HP-GL): the points it
    acknowledged before (``_acknowledged``) still hold, and a confirmed resume continues from the last one."""
    reports_position: ClassVar[bool] = False
    """True when the family implements ``_where``; otherwise a resume restarts at the last confirmed stroke
    (strokes drawn since are drawn again) without asking the device."""
    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("paper", text, None, "paper size known to the profile (a4, a3, letter, ...); default the profile's"),
        OptionSpec("baud", integer(1), None, "serial speed; default the profile's"),
        OptionSpec("flow", choice("none", "rtscts", "xonxoff"), None,
                   "flow control: none, rtscts or xonxoff; default the profile's"),
        OptionSpec("timeout", positive, None, "seconds to wait for any reply; default the profile's"),
        OptionSpec("profile", load_profile, None, "a device profile TOML file instead of the built-in one"),
        OptionSpec("state", text, None, "file to keep the plot state in, for resuming after a fault"),
    )
    SIM_SHARED: ClassVar[frozenset[str]] = frozenset({"paper"})
    SIM_TRANSPORT: ClassVar[frozenset[str]] = frozenset({"baud", "flow"})

    def __init__(
        self,
        port: str,
        *,
        profile: DeviceProfile,
        paper: str | None = None,
        baudrate: int | None = None,
        flow: str | None = None,
        timeout: float | None = None,
        clock: Clock | None = None,
        state_file: str | Path | None = None,
        link_factory: Callable[[], Link] | None = None,
        on_progress: ProgressCallback | None = None,
        on_pen_change: PenChange | None = None,
        pause_requested: Callable[[], bool] | None = None,
        on_pause: PauseCallback | None = None,
    ) -> None:
        self.profile = profile
        self.paper = profile.paper(paper)
        x0, x1 = self.paper.x_range
        y0, y1 = self.paper.y_range
        caps = Capabilities(
            model=profile.name, category="output", kind="vector", size=(float(x1 - x0), float(y1 - y0)),
            unit_mm=profile.unit_mm, colour_model="pens", y_down=not profile.y_up,
            pens=tuple(profile.pen_colours.get(p, "#000000") for p in range(1, profile.pens + 1)),
            can_erase=False, tolerance=max(0.5, 0.02 / profile.unit_mm),
            limits={"x_range": (x0, x1), "y_range": (y0, y1), "paper": self.paper.name},
        )
        super().__init__(caps, pen_width_mm=profile.pen_width_mm, deferral="flush")
        self.port = port
        link = profile.link
        self.baudrate = baudrate or (link.baudrate if link else 9600)
        self.flow = flow or ("rtscts" if link and link.rtscts else "xonxoff" if link and link.xonxoff else "none")
        self.timeout = timeout if timeout is not None else (link.timeout_s if link else 8.0)
        self.clock = clock or REAL_CLOCK
        self._clock_given = clock is not None
        self.state_file = check_path(state_file, "state_file") if state_file else None
        self._link_factory = link_factory
        self.on_progress = on_progress
        self.on_pen_change = on_pen_change
        self.pause_requested = pause_requested
        self.on_pause = on_pause
        self.link: Link | None = None
        self.pen: int | None = None
        """Pen the device holds now (None: unknown or none)."""
        self.confirmed = 0
        """Strokes of the current job the device has confirmed on paper."""
        self._job: DisplayList | None = None
        self._job_state: PlotState | None = None
        self._cum_mm = np.zeros(1)
        self._estimate_s = 0.0
        self._started = 0.0
        self._sent_end = 0
        """One past the last stroke whose bytes started going out."""
        self._head: tuple[int, np.ndarray, ResumePoint] | None = None
        """The first stroke of a resumed run, the remainder of it that was sent, and the point it resumed at."""
        self._run_start: tuple[int, tuple[float, float]] | None = None
        """The first stroke of the current run and the pen position before its travel (``_pen_position()``)."""
        self._interrupted = False
        self._position_lost = False
        self._where_found: DeviceWhere | None = None
        """What ``_where()`` said on the last fresh link opened for a resume."""
        self._paused_now = False
        self._left_as_set = False
        """The last thing done was a manual action: closing leaves the pen and carriage where the user put them."""
        self._stopped_at: DeviceWhere | None = None
        """Where an interrupted job's device stopped, asked before the safe stop parked it."""
        self._damaged: range | None = None
        """Strokes the device reported it did not draw as sent (an error, a wrong position)."""
        self._lifts: set[int] | None = set()
        """Strokes after which the family lifted the pen without moving (None: unknown, any may be)."""
        self._redo = range(0)
        """Whole strokes a resume draws again before it continues (a damaged stretch)."""
        self._ceiling: ResumePoint | None = None
        """The furthest place the bytes that went out in the current run can draw to (``_written_to``)."""
        self._ack: ResumePoint | None = None
        """(stroke, vertex) the device last acknowledged reaching (``_acknowledged``), in the job's whole strokes."""
        self._missing: list[tuple[int, np.ndarray]] = []
        """(stroke, points): pieces of strokes the device skipped, found exactly (``_mark_missing``); a resume
        draws them first."""

    # -- construction ------------------------------------------------------------------------
    @classmethod
    def from_url(cls, url: DeviceURL, **kwargs: Any) -> PlotterDisplay:
        """``MODEL:PORT?options`` for hardware, ``sim:MODEL?options`` for the simulator."""
        sim_options: dict[str, str] | None = None
        if url.scheme == "sim":
            url, sim_options = cls.split_sim_url(url)
        options = cls.read_url_options(url)
        profile = options["profile"] or cls.default_profile(options)
        port = url.target
        if sim_options is not None:
            port = format_url("sim", "//" + url.scheme, cls.simulator_options(sim_options, options, profile))
        try:
            family = cls.family_options(options, profile)
        except URLError:
            raise
        except ConfigError as exc:  # options that do not fit together: named with the URL
            raise ConfigError(f"{url}: {exc}") from None
        return cls(
            port, profile=profile, paper=options["paper"], baudrate=options["baud"], flow=options["flow"],
            timeout=options["timeout"], state_file=kwargs.pop("state_file", None) or options["state"],
            **family, **kwargs,
        )

    @classmethod
    def default_profile(cls, options: OptionValues) -> DeviceProfile:
        """The built-in profile of a URL without ``profile=`` (a family with several models reads its option)."""
        return load_profile(cls.profile_name)

    @classmethod
    def family_options(cls, options: OptionValues, profile: DeviceProfile) -> dict[str, Any]:
        """Constructor keywords read from the family's own URL options (the base has none)."""
        return {}

    @classmethod
    def simulator_options(
        cls, sim_options: dict[str, str], options: OptionValues, profile: DeviceProfile,
    ) -> dict[str, str]:
        """Options for the simulator of a ``sim:`` URL: as given, paper included (a family translates its own)."""
        return sim_options

    # -- life cycle ----------------------------------------------------------------------------
    def _open_device(self) -> None:
        link = self._make_link()
        self._attach(link)
        try:
            if self.reports_position and self.state_file is not None and unfinished(self.state_file):
                self._where_found = self._where()
            self._connect()
        except BaseException:
            link.close()
            self.link = None
            raise

    def _make_link(self) -> Link:
        if self._link_factory is not None:
            return self._link_factory()
        return SerialLink(self.port, baudrate=self.baudrate, flow=self.flow, timeout=self.timeout)

    def _close_device(self) -> None:
        link, self.link = self.link, None
        if link is None:
            return
        try:
            if not link.closed and not self._left_as_set:
                self._make_safe_on(link)
        finally:
            link.close()

    def _make_safe_on(self, link: Link) -> None:
        self.link = link
        try:
            if self._interrupted and self.reports_position:
                self._note_where_stopped()
            self._make_safe()
        except Exception as exc:  # noqa: BLE001  (leaving the device safe is best effort on a failing link)
            log.warning("could not leave %s safe: %s", self.profile.name, exc)
        finally:
            self.link = None

    def reconnect(self) -> None:
        """Close the link (if any), open a new one and handshake again (after an unplug or reset)."""
        if self.link is not None:
            try:
                self.link.close()
            finally:
                self.link = None
        self.pen = None
        self._attach(self._make_link())
        self._where_found = self._where() if self._interrupted and self.reports_position else None
        self._connect()

    def _attach(self, link: Link) -> None:
        """Use ``link``; a display given no clock keeps time on the link's (a ``speed=fast`` simulator's)."""
        self.link = link
        self._paused_now = False  # a fresh link knows of no pause yet: the next one is announced again
        if not self._clock_given:
            self.clock = link.clock

    # -- VectorDisplay hooks -------------------------------------------------------------------
    def _plot(self, strokes: DisplayList) -> None:
        self.plot(strokes)

    def _new_sheet(self) -> None:
        self._make_safe()
        if self.on_pen_change is None:
            log.warning("%s: a plotter cannot erase; put in a new sheet before the next drawing", self.profile.name)

    # -- plotting ------------------------------------------------------------------------------
    def plot(self, dl: DisplayList, *, resume: bool = False, position_confirmed: bool = False) -> None:
        """Plot a display list in device units; with ``resume`` continue the interrupted job exactly where it stopped.

        ``position_confirmed`` (after :class:`PositionUnknown`): the device was re-homed or checked; continue
        from the earliest point it may have reached.
        """
        if self.link is None:
            raise PixelpenError(f"{self.profile.name} is not open")
        self._left_as_set = False
        pts = self._device_points(dl)
        start = self._start_job(dl, resume, pts, position_confirmed)
        self._head = None
        redo, self._redo = self._redo, range(0)
        try:
            self._draw_missing(dl)
            for i in [*redo, *range(start.stroke, len(dl))]:
                self._hold_while_paused()
                pen = int(dl.pens[i])
                if pen != self.pen:
                    self._change_pen(pen)
                stroke = pts[dl.offsets[i] : dl.offsets[i + 1]]
                if i == start.stroke and (rest := start.remainder(stroke)) is not None:
                    stroke = rest
                    self._head = (i, rest, start)
                self._sent_end = i + 1
                self._send_stroke(i, stroke, pen)
                self._poll()
            self._drain()
        except ProtocolError as exc:  # the device refused something: said as it is, and the job is resumable
            self._interrupted = True
            self._save_state(sent=self._sent_end)
            raise DeviceFault(exc, resume_from=self.confirmed, state_file=self.state_file) from exc
        except (LinkError, ParseError) as exc:  # a garbled reply on a live link is a link fault
            self._poll_quietly()
            self._interrupted = True
            self._save_state(sent=self._sent_end)
            raise PlotInterrupted(
                f"plot interrupted: {exc}", resume_from=self.confirmed, state_file=self.state_file, cause=exc,
            ) from exc
        except KeyboardInterrupt:
            self._make_safe()
            raise
        self._interrupted = False
        self._confirm(len(dl))

    def resume_after_fault(self, attempts: int = 3, wait_s: float = 1.0, *, position_confirmed: bool = False) -> None:
        """Reconnect, ask the device where it stopped and plot the rest of the interrupted job from exactly there."""
        if self._job is None:
            raise PixelpenError("there is no interrupted plot to resume")
        for attempt in range(1, attempts + 1):
            try:
                self.reconnect()
                break
            except LinkError as exc:
                if attempt == attempts:
                    raise
                log.warning("reconnect %d/%d failed: %s", attempt, attempts, exc)
                self.clock.sleep(wait_s)
        self.plot(self._job, resume=True, position_confirmed=position_confirmed)

    def _start_job(
        self, dl: DisplayList, resume: bool, pts: np.ndarray, position_confirmed: bool = False,
    ) -> ResumePoint:
        fp = fingerprint(dl)
        start = ResumePoint(0)
        if resume and self._job is not None and fingerprint(self._job) == fp:
            start = self._resume_point(dl, pts, self.confirmed, self._sent_end, position_confirmed)
        elif resume and self.state_file is not None:
            if not self.state_file.exists():
                raise ConfigError(f"{self.state_file}: no plot state to resume (the file does not exist)")
            state = PlotState.load(self.state_file)
            if state.fingerprint != fp or state.strokes != len(dl):
                raise ConfigError(f"{self.state_file}: the plot state belongs to another drawing; refusing to resume")
            self._position_lost = self._position_lost or state.position_lost
            if state.damaged is not None:
                self._mark_damaged(range(*state.damaged))
            self._missing = [(int(m[0]), np.asarray(m[1:], np.int64).reshape(-1, 2)) for m in state.missing or []]
            self._ceiling = None if state.written is None else ResumePoint(
                int(state.written[0]), int(state.written[1]),
                None if len(state.written) == 2 else (float(state.written[2]), float(state.written[3])))
            self._ack = None if state.reached is None else ResumePoint(
                int(state.reached[0]), int(state.reached[1]),
                None if len(state.reached) == 2 else (float(state.reached[2]), float(state.reached[3])))
            self._lifts = None if state.lifts is None else set(state.lifts)
            if self._where_found is None and self.reports_position:
                self._interrupted = True
                self.reconnect()  # the display was opened without the state file: ask the device now
            now = self._where_found
            if state.stopped_at is not None and now is not None and not now.position_lost:
                # the last session asked where the device stopped before it parked it
                x, y, pen, tol, *held = state.stopped_at
                self._where_found = DeviceWhere(
                    (x, y), None if pen < 0 else bool(pen), tolerance=tol, held=held == [1],
                    detail=f"stopped at {x:g},{y:g} (asked before the last session parked it)")
            sent = len(dl) if state.sent is None else state.sent
            self._job, self._head, self._job_state = dl, None, state  # a PositionUnknown below keeps the file current
            self._run_start = None if state.start is None else (int(state.start[0]), (state.start[1], state.start[2]))
            self.confirmed = state.confirmed
            start = self._resume_point(dl, pts, state.confirmed, sent, position_confirmed)
        elif resume:
            raise ConfigError("nothing to resume: no interrupted plot in this process and no state file")
        else:
            self._lifts, self._damaged, self._position_lost, self._redo = set(), None, False, range(0)
            self._missing, self._ack = [], None
        self._job, self._ack, self._ceiling = dl, None, None  # both describe one run of the job
        self._job_state = PlotState(self.port, fp, len(dl), self._redo.start if self._redo else start.stroke)
        self._cum_mm = cumulative_pen_down_mm(dl)
        self._estimate_s = estimate_seconds(dl, self.profile)
        self._started = self.clock.now()
        self.confirmed = self._redo.start if self._redo else start.stroke
        self._sent_end = self.confirmed
        at = self._pen_position()
        self._run_start = None if at is None else (self.confirmed, (float(at[0]), float(at[1])))
        self._job_state.start = None if at is None else [self.confirmed, float(at[0]), float(at[1])]
        self._save_state()
        return start

    def _resume_point(
        self, dl: DisplayList, pts: np.ndarray, confirmed: int, sent: int, confirmed_by_user: bool,
    ) -> ResumePoint:
        """Where to continue the job: located from ``_where()`` among strokes confirmed..sent, or PositionUnknown."""
        where, self._where_found = self._where_found, None
        self._stopped_at = None
        if not self.reports_position:
            log.warning("%s: resuming at stroke %d, the last confirmed one: strokes drawn since are drawn again",
                        self.profile.name, confirmed)
            return ResumePoint(confirmed)
        window = [(i, pts[dl.offsets[i] : dl.offsets[i + 1]]) for i in range(confirmed, sent)]
        head = self._head if self._head is not None and confirmed <= self._head[0] < sent else None
        if head is not None:
            window[head[0] - confirmed] = (head[0], head[1])  # the points sent, the frame of the device's answer
        run = self._run_start
        if run is not None and run[0] == confirmed:
            before: np.ndarray | None = np.asarray(run[1], float)
        else:
            before = pts[dl.offsets[confirmed] - 1] if confirmed > 0 else None
        if where is not None and where.position_lost:
            self._position_lost = True
        lost = self._position_lost or where is None or not where.settled
        lifts = self._lifts
        found = [] if lost or where is None else locate(
            window, where, before, down_at_start=self.rests_pen_down_at_start,
            lifts=(lambda s: True) if self.lifts_after_each_stroke or lifts is None else lifts.__contains__,
        )
        if head is not None:
            short = len(pts[dl.offsets[head[0]] : dl.offsets[head[0] + 1]]) - len(head[1])
            found = [in_full_stroke(r, head[0], short, head[2]) for r in found]
        length = lambda i: len(dl.stroke(i))
        if self._ceiling is not None:
            top = self._ceiling
            found = [r for r in found if not_after(r, top, length)]
        if self._ack is not None:  # the device said it got there: no place before it
            floor = self._ack
            found = [r for r in found if not_after(floor, r, length)]
        damaged, self._damaged = self._damaged, None
        self._redo = range(0)
        first = max(confirmed, damaged.start) if damaged is not None else confirmed
        if damaged is not None and len(found) == 1 and not lost:
            if found[0].stroke < first or found[0] == ResumePoint(first):
                return found[0]
            if found[0].stroke < damaged.stop:
                return ResumePoint(first)  # inside a damaged stroke: that stroke again from its start
            self._redo = range(first, damaged.stop)
            return found[0]
        if damaged is not None and not lost and where is not None and where.position is not None and (
                not found or found[0].stroke >= first):
            found = [ResumePoint(first)]  # off every stroke, or several places after the damage: redraw from it on
        if len(found) == 1 and not self._position_lost:
            return found[0]
        acked = self._acked_since(confirmed) if lost and self.restarts_at_home else None
        if confirmed_by_user:
            self._position_lost = False
            if lost:
                self._rehomed()
            if acked is not None:
                return acked  # the device restarted at home: what it acknowledged is on paper, the rest is not
            return found[0] if found and not lost else ResumePoint(confirmed)
        if confirmed == sent:
            return ResumePoint(confirmed)  # nothing was in doubt
        strokes = range(confirmed, sent)
        if lost or where is None:
            why = (where.detail if where is not None and where.detail else "the device cannot tell where it stopped")
        elif not found:
            why = (f"it stands at {where.position} (pen {_pen_word(where.pen_down)}), "
                   "on none of the strokes sent since the last confirmation")
        else:
            why = f"its position {where.position} (pen {_pen_word(where.pen_down)}) fits {len(found)} places: "
            why += ", ".join(
                f"stroke {r.stroke}" + (f" after vertex {r.vertex}" if r.vertex or r.at else "") for r in found)
        self._damaged = damaged  # still to be drawn again by the confirmed resume
        self._stopped_at = where if where is not None and where.position is not None and not lost else None
        self._save_state(sent=sent)
        raise PositionUnknown(
            f"{self.profile.name}: cannot tell which of strokes {confirmed}..{sent - 1} are on paper: {why}. "
            f"Re-home the device or check the sheet, then resume with position_confirmed=True "
            "(pixelpen plot --resume --confirm-position): it continues from stroke "
            f"{found[0].stroke if found else confirmed}"
            + ("" if found else f" after vertex {acked.vertex}, the last point the device acknowledged; it may redraw "
               "the part of the next instruction it drew before it stopped" if acked is not None and acked.vertex
               else ", redrawing what was drawn since"),
            resume_from=found[0].stroke if found else acked.stroke if acked is not None else confirmed, strokes=strokes,
        )

    def _device_points(self, dl: DisplayList) -> np.ndarray:
        """Stroke points in integer device units, offset to the paper's hard-clip origin."""
        if not np.isclose(dl.unit_mm, self.profile.unit_mm):
            raise ConfigError(
                f"display list is in {dl.unit_mm} mm units but {self.profile.name} plots in "
                f"{self.profile.unit_mm} mm units"
            )
        offset = np.array([self.paper.x_range[0], self.paper.y_range[0]], float)
        points: np.ndarray = np.rint(dl.points + offset).astype(np.int64)
        return points

    def _confirm(self, k: int) -> None:
        """Record the device's word that strokes < k are on paper (families call this)."""
        if self._job is None or k <= self.confirmed:
            return
        self.confirmed = min(k, len(self._job))
        self._save_state()
        if self.on_progress is not None:
            self.on_progress(self.progress())

    def progress(self) -> PlotProgress:
        """The current job's progress, with an ETA scaled by how the device keeps to the estimate."""
        total = len(self._job) if self._job is not None else 0
        done_mm, total_mm = float(self._cum_mm[self.confirmed]), float(self._cum_mm[-1])
        elapsed = self.clock.now() - self._started
        share = done_mm / total_mm if total_mm else (self.confirmed / total if total else 1.0)
        eta = max(0.0, self._estimate_s * (1.0 - share))
        return PlotProgress(self.confirmed, total, done_mm, total_mm, elapsed, eta)

    def _save_state(self, sent: int | None = None) -> None:
        """Write the state file: confirmed strokes, ``sent`` when known (at a fault), the lost-position flag."""
        if self.state_file is not None and self._job_state is not None:
            self._job_state.confirmed = self.confirmed
            self._job_state.sent = sent
            self._job_state.position_lost = self._position_lost
            self._job_state.damaged = [self._damaged.start, self._damaged.stop] if self._damaged else None
            self._job_state.missing = [[s, *(int(v) for v in p.ravel())] for s, p in self._missing] or None
            ack, top = self._ack, self._ceiling
            self._job_state.reached = None if ack is None else [ack.stroke, ack.vertex, *(ack.at or ())]
            self._job_state.written = None if top is None else [top.stroke, top.vertex, *(top.at or ())]
            lifts = self._lifts
            self._job_state.lifts = None if lifts is None else sorted(s for s in lifts if s >= self.confirmed)
            at = self._stopped_at
            self._job_state.stopped_at = None if at is None or at.position is None else [
                float(at.position[0]), float(at.position[1]), -1 if at.pen_down is None else int(at.pen_down),
                at.tolerance, *([1] if at.held else [])]  # 4 fields unless held, as readers before held expect
            self._job_state.save(self.state_file)

    def _hold_while_paused(self) -> None:
        """Wait between strokes (pen up) while the user or the device asks for a pause."""
        announced = False
        while (self.pause_requested is not None and self.pause_requested()) or self._device_paused():
            if not announced:
                self._drain()
                log.info("%s: paused with the pen up", self.profile.name)
                self._pause_changed(True)
                announced = True
            self.clock.sleep(0.05)
        if announced:
            log.info("%s: resumed", self.profile.name)
            self._pause_changed(False)

    def _draw_missing(self, dl: DisplayList) -> None:
        """Draw the pieces the device skipped (``_mark_missing``) and wait until they are confirmed."""
        patches = list(self._missing)
        if not patches:
            return
        for stroke, points in patches:
            pen = int(dl.pens[stroke])
            if pen != self.pen:
                self._change_pen(pen)
            self._send_stroke(stroke, points, pen)
            self._poll()
        self._drain()
        self._missing = self._missing[len(patches):]
        self._save_state()

    def _acknowledged(self, stroke: int, k: int) -> None:
        """Families call this when the device acknowledged reaching point k of the points sent for ``stroke``."""
        if stroke >= self.confirmed:  # else a piece drawn again (``_mark_missing``), or confirmed whole already
            self._ack = self._in_job(stroke, k)

    def _written_to(self, stroke: int, k: int) -> None:
        """Families call this before the bytes up to point k of the points sent for ``stroke`` start going out.

        Nothing after that point can have reached the device: a resume drops the places after it.
        """
        if stroke >= self.confirmed:
            self._ceiling = self._in_job(stroke, k)

    def _in_job(self, stroke: int, k: int) -> ResumePoint:
        """Point k of the points sent for ``stroke`` (a resumed remainder, ``_head``) as a place in the whole stroke."""
        head = self._head
        if head is not None and head[0] == stroke and self._job is not None:
            short = len(self._job.stroke(stroke)) - len(head[1])
            return in_full_stroke(ResumePoint(stroke, k), stroke, short, head[2])
        return ResumePoint(stroke, k)


    def _acked_since(self, confirmed: int) -> ResumePoint | None:
        """The last point the device acknowledged, if it is at or after stroke ``confirmed``'s start."""
        ack = self._ack
        return None if ack is None or ack.stroke < confirmed else ack

    def _mark_missing(self, stroke: int, points: np.ndarray) -> None:
        """Families call this before raising for an error when they know exactly what the device skipped.

        ``points`` (device units, as given to ``_send_stroke``) is the piece of ``stroke`` that is not on paper;
        the resume draws it before it continues where the device stopped: nothing drawn twice.
        """
        self._missing.append((stroke, np.asarray(points, np.int64).reshape(-1, 2).copy()))

    def _mark_damaged(self, strokes: range) -> None:
        """Families call this before raising for an error the device found in ``strokes`` (skipped or misread).

        The resume draws those strokes again whole (never losing one; their good parts are drawn twice),
        then continues where the device stopped.
        """
        if self._damaged is not None:
            strokes = range(min(self._damaged.start, strokes.start), max(self._damaged.stop, strokes.stop))
        self._damaged = strokes

    def _note_where_stopped(self) -> None:
        """Before the safe stop parks an interrupted job's device, ask where it stopped; keep it in the state file."""
        try:
            where = self._where()
        except PixelpenError as exc:  # the link that failed the plot may be gone: the next session asks the device
            log.debug("%s: cannot ask where the plot stopped: %s", self.profile.name, exc)
            return
        if where.position_lost:
            self._position_lost = True
        elif where.position is not None and where.settled:
            self._stopped_at = where
        self._save_state(sent=self._sent_end)

    def _lifted_in_place(self, stroke: int) -> None:
        """Families whose pen lift is part of the travel call this when they lift the pen in place after ``stroke``."""
        if self._lifts is not None:
            self._lifts.add(stroke)

    def _pause_changed(self, paused: bool) -> None:
        """Tell ``on_pause`` the device has paused (True) or goes on (False); families call it for their own pauses."""
        if paused != self._paused_now:
            self._paused_now = paused
            if self.on_pause is not None:
                self.on_pause(paused)

    def _change_pen(self, pen: int) -> None:
        if pen < 1:
            raise ConfigError(f"pen numbers start at 1, got {pen}")
        if self.profile.pens > 1:
            if pen > self.profile.pens:
                raise ConfigError(f"{self.profile.name} has {self.profile.pens} pens; stroke wants pen {pen}")
            self._select_pen(pen)
        elif self.pen is not None and self.on_pen_change is not None:
            self._drain()
            self._make_safe()
            self.on_pen_change(pen)
        self.pen = pen

    def _poll_quietly(self) -> None:
        try:
            self._poll()
        except Exception as exc:  # noqa: BLE001  (the link is already failing; keep the first error)
            log.debug("poll after fault failed: %s", exc)


def _pen_word(down: bool | None) -> str:
    return "unknown" if down is None else "down" if down else "up"

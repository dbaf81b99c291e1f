"""What every pen plotter shares: the link, stroke-by-stroke plotting with confirmed progress,
pause at pen-up, pen changes, resume after faults (in process or from a state file), and safe stops.

A plotter family (HPGL, GRBL, EBB) subclasses :class:`PlotterDisplay` and implements the device core:

* ``_connect()`` — handshake and initialise the device on ``self.link`` (called on every (re)connect);
* ``_send_stroke(index, points, pen)`` — encode one stroke (integer device units, pen down along it,
  pen up at its end) and stream it with the family's flow control; it may block while the device's
  buffer is full, and must call ``self._confirm(k)`` whenever the device confirms strokes < k done;
* ``_poll()`` — read whatever the device has said without blocking (confirmations, errors);
* ``_drain()`` — wait until every stroke sent is confirmed;
* ``_select_pen(pen)`` — take pen ``pen`` (multi-pen devices; single-pen devices never get it);
* ``_device_paused()`` — True while the device's own pause (button, VIEW, paper lever) holds;
* ``_make_safe()`` — best effort, never raising: stop motion, pen up, park, motors off.

Confirmation is the device's word that a stroke is on paper (an output request answered after it,
a status report, an idle motor query), not merely that its bytes were received.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
from abc import abstractmethod
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable, ClassVar

import numpy as np

from ..clock import REAL_CLOCK, Clock
from ..display.capabilities import Capabilities
from ..display.kinds import VectorDisplay
from ..drivers.link import Link
from ..drivers.serial import SerialLink
from ..errors import ConfigError, LinkError, ParseError, PixelpenError, URLError
from ..urls import DeviceURL, Options, format_url
from ..vector.displaylist import DisplayList
from ..vector.motion import estimate_time
from ..vector.profiles import DeviceProfile, load_profile

log = logging.getLogger(__name__)

STATE_VERSION = 1


@dataclass
class PlotProgress:
    """Where a plot stands, for progress bars: strokes and pen-down millimetres done, time and ETA."""

    strokes_done: int
    strokes_total: int
    pen_down_mm_done: float
    pen_down_mm_total: float
    elapsed_s: float
    eta_s: float

    @property
    def fraction(self) -> float:
        """Share of the pen-down distance confirmed, 0..1."""
        return self.pen_down_mm_done / self.pen_down_mm_total if self.pen_down_mm_total else 1.0


class PlotInterrupted(PixelpenError):
    """A plot stopped on a fault; ``resume_from`` is the first stroke the device did not confirm."""

    def __init__(self, message: str, *, resume_from: int, state_file: Path | None, cause: BaseException | None = None) -> None:
        self.resume_from = resume_from
        self.state_file = state_file
        self.cause = cause
        where = f"; state saved to {state_file} (plot again with --resume)" if state_file else ""
        super().__init__(f"{message}; {resume_from} strokes were confirmed{where}")


def fingerprint(dl: DisplayList) -> str:
    """A hash of a display list's strokes and pens, to tell a state file's drawing from another."""
    h = hashlib.sha256()
    for arr in (np.round(dl.points, 6), dl.offsets, dl.pens):
        h.update(np.ascontiguousarray(arr).tobytes())
    return h.hexdigest()[:32]


@dataclass
class PlotState:
    """The resumable state of a plot, saved as JSON after every confirmation."""

    url: str
    fingerprint: str
    strokes: int
    confirmed: int
    version: int = STATE_VERSION

    def save(self, path: Path) -> None:
        """Write the state atomically (temp file + rename), so a crash never leaves half a file."""
        tmp = path.with_name(path.name + ".tmp")
        with open(tmp, "w", encoding="utf-8") as fh:
            json.dump(asdict(self), fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)

    @classmethod
    def load(cls, path: Path) -> "PlotState":
        """Read a state file; a ParseError names the file and the field that is wrong."""
        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except OSError as exc:
            raise ParseError(f"cannot read plot state: {exc.strerror}", source=str(path)) from None
        except json.JSONDecodeError as exc:
            raise ParseError(f"plot state is not JSON: {exc.msg}", source=str(path), line=exc.lineno, column=exc.colno) from None
        if not isinstance(data, dict) or data.get("version") != STATE_VERSION:
            raise ParseError(f"not a version-{STATE_VERSION} pixelpen plot state", source=str(path))
        try:
            state = cls(**data)
        except TypeError as exc:
            raise ParseError(f"plot state has wrong fields: {exc}", source=str(path)) from None
        if not (isinstance(state.confirmed, int) and 0 <= state.confirmed <= state.strokes):
            raise ParseError("plot state field 'confirmed' is out of range", source=str(path), token=state.confirmed)
        return state


PenChange = Callable[[int], None]
"""Called on single-pen devices when the next stroke needs another pen; returns when it is in."""
ProgressCallback = Callable[[PlotProgress], None]


class PlotterDisplay(VectorDisplay):
    """A pen plotter reached through a Link: plots, confirms, pauses at pen-up, resumes, stops safe."""

    simulated: ClassVar[bool] = True
    profile_name: ClassVar[str] = ""
    """Built-in profile the scheme uses unless the URL names another."""
    family: ClassVar[str] = ""
    """Simulator model name for ``sim:`` URLs (usually the scheme)."""
    url_options = {
        "paper": "paper size known to the profile (a4, a3, letter, ...); default the profile's",
        "baud": "serial speed; default the profile's",
        "flow": "flow control: none, rtscts or xonxoff; default the profile's",
        "timeout": "seconds to wait for any reply; default the profile's",
        "profile": "a device profile TOML file instead of the built-in one",
        "state": "file to keep the plot state in, for resuming after a fault",
    }

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
        self.state_file = Path(state_file) if state_file else None
        self._link_factory = link_factory
        self.on_progress = on_progress
        self.on_pen_change = on_pen_change
        self.pause_requested = pause_requested
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

    # -- construction ------------------------------------------------------------------------
    @classmethod
    def from_url(cls, url: DeviceURL, **kwargs: object) -> "PlotterDisplay":
        """``MODEL:PORT?options`` for hardware, ``sim:MODEL?options`` for the simulator."""
        sim_opts: dict[str, str] | None = None
        if url.scheme == "sim":
            model = url.target
            own = {k: v for k, v in url.options.items() if k in cls.url_options and k not in ("baud", "flow")}
            sim_opts = {k: v for k, v in url.options.items() if k not in own or k == "paper"}
            opts, port = DeviceURL(model, "", own, str(url)), ""
        else:
            opts, port = url, url.target
        options = cls.options_of(opts)
        profile = options.get("profile", load_profile, None) or cls.default_profile(options)
        if sim_opts is not None:
            port = format_url("sim", "//" + model, cls.simulator_options(sim_opts, options, profile))
        return cls(
            port, profile=profile, paper=options.get("paper", str, None), baudrate=options.get("baud", int, None),
            flow=options.get("flow", _flow, None), timeout=options.get("timeout", float, None),
            state_file=options.get("state", str, None), **cls.family_options(options, profile), **kwargs,  # type: ignore[arg-type]
        )

    @classmethod
    def default_profile(cls, options: Options) -> DeviceProfile:
        """The built-in profile of a URL without ``profile=`` (a family with several models reads its option)."""
        return load_profile(cls.profile_name)

    @classmethod
    def family_options(cls, options: Options, profile: DeviceProfile) -> dict[str, object]:
        """Constructor keywords read from the family's own URL options (the base has none)."""
        return {}

    @classmethod
    def simulator_options(cls, sim_options: dict[str, str], options: Options, profile: DeviceProfile) -> dict[str, str]:
        """Options for the simulator of a ``sim:`` URL: as given, paper included (a family translates its own)."""
        return sim_options

    # -- life cycle ----------------------------------------------------------------------------
    def _open_device(self) -> None:
        self._attach(self._make_link())
        try:
            self._connect()
        except BaseException:
            self.link.close()
            self.link = None
            raise

    def _make_link(self) -> Link:
        if self._link_factory is not None:
            return self._link_factory()
        return SerialLink(self.port, baudrate=self.baudrate, flow=self.flow, timeout=self.timeout)  # type: ignore[arg-type]

    def _close_device(self) -> None:
        link, self.link = self.link, None
        if link is None:
            return
        try:
            if not link.closed:
                self._make_safe_on(link)
        finally:
            link.close()

    def _make_safe_on(self, link: Link) -> None:
        self.link = link
        try:
            self._make_safe()
        except Exception as exc:  # leaving the device safe is best effort on a failing link
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
        self._connect()

    def _attach(self, link: Link) -> None:
        """Use ``link``; a display given no clock keeps time on the link's (a ``speed=fast`` simulator's)."""
        self.link = link
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
    def plot(self, dl: DisplayList, *, resume: bool = False) -> None:
        """Plot a display list in device units; with ``resume`` continue a job from its state file."""
        if self.link is None:
            raise PixelpenError(f"{self.profile.name} is not open")
        start = self._start_job(dl, resume)
        pts = self._device_points(dl)
        try:
            for i in range(start, len(dl)):
                self._hold_while_paused()
                pen = int(dl.pens[i])
                if pen != self.pen:
                    self._change_pen(pen)
                self._send_stroke(i, pts[dl.offsets[i] : dl.offsets[i + 1]], pen)
                self._poll()
            self._drain()
        except LinkError as exc:
            self._poll_quietly()
            raise PlotInterrupted(
                f"{self.profile.name}: plot interrupted by {type(exc).__name__}: {exc}",
                resume_from=self.confirmed, state_file=self.state_file, cause=exc,
            ) from exc
        except KeyboardInterrupt:
            self._make_safe()
            raise
        self._confirm(len(dl))

    def resume_after_fault(self, attempts: int = 3, wait_s: float = 1.0) -> None:
        """Reconnect and plot the rest of the interrupted job from its last confirmed stroke."""
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
        self._plot_rest()

    def _plot_rest(self) -> None:
        job = self._job
        assert job is not None
        self.plot(job, resume=True)

    def _start_job(self, dl: DisplayList, resume: bool) -> int:
        fp = fingerprint(dl)
        if resume and self._job is not None and fingerprint(self._job) == fp:
            start = self.confirmed
        elif resume and self.state_file is not None and self.state_file.exists():
            state = PlotState.load(self.state_file)
            if state.fingerprint != fp or state.strokes != len(dl):
                raise ConfigError(f"{self.state_file}: the plot state belongs to another drawing; refusing to resume")
            start = state.confirmed
        elif resume:
            raise ConfigError("nothing to resume: no interrupted plot in this process and no state file")
        else:
            start = 0
        self._job = dl
        self._job_state = PlotState(self.port, fp, len(dl), start)
        seg = np.hypot(*np.diff(dl.points, axis=0).T) if len(dl.points) > 1 else np.zeros(0)
        per_stroke = np.add.reduceat(np.append(seg, 0.0), dl.offsets[:-1]) - np.where(
            dl.offsets[1:] < len(dl.points), np.append(seg, 0.0)[np.minimum(dl.offsets[1:] - 1, len(seg))], 0.0
        ) if len(dl) else np.zeros(0)
        self._cum_mm = np.concatenate([[0.0], np.cumsum(per_stroke)]) * dl.unit_mm
        self._estimate_s = _estimate_seconds(dl, self.profile)
        self._started = self.clock.now()
        self.confirmed = start
        self._save_state()
        return start

    def _device_points(self, dl: DisplayList) -> np.ndarray:
        """Stroke points in integer device units, offset to the paper's hard-clip origin."""
        if not np.isclose(dl.unit_mm, self.profile.unit_mm):
            raise ConfigError(
                f"display list is in {dl.unit_mm} mm units but {self.profile.name} plots in {self.profile.unit_mm} mm units"
            )
        offset = np.array([self.paper.x_range[0], self.paper.y_range[0]], float)
        return np.rint(dl.points + offset).astype(np.int64)

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

    def _save_state(self) -> None:
        if self.state_file is not None and self._job_state is not None:
            self._job_state.confirmed = self.confirmed
            self._job_state.save(self.state_file)

    def _hold_while_paused(self) -> None:
        """Wait between strokes (pen up) while the user or the device asks for a pause."""
        announced = False
        while (self.pause_requested is not None and self.pause_requested()) or self._device_paused():
            if not announced:
                self._drain()
                log.info("%s: paused with the pen up", self.profile.name)
                announced = True
            self.clock.sleep(0.05)
        if announced:
            log.info("%s: resumed", self.profile.name)

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
        except Exception as exc:  # the link is already failing; keep the first error
            log.debug("poll after fault failed: %s", exc)

    # -- the family's core ---------------------------------------------------------------------
    @abstractmethod
    def _connect(self) -> None:
        """Handshake and initialise the device on ``self.link``."""

    @abstractmethod
    def _send_stroke(self, index: int, points: np.ndarray, pen: int) -> None:
        """Stream one stroke (pen down along it, up at its end) with the family's flow control."""

    @abstractmethod
    def _poll(self) -> None:
        """Read what the device said without blocking; confirm strokes, raise its errors."""

    @abstractmethod
    def _drain(self) -> None:
        """Wait until every stroke sent is confirmed on paper."""

    @abstractmethod
    def _select_pen(self, pen: int) -> None:
        """Take pen ``pen`` from the carousel."""

    @abstractmethod
    def _device_paused(self) -> bool:
        """True while the device's own pause holds (button, VIEW, paper lever)."""

    @abstractmethod
    def _make_safe(self) -> None:
        """Stop, pen up, park, motors off — best effort on ``self.link``."""


def _flow(text: str) -> str:
    if text not in ("none", "rtscts", "xonxoff"):
        raise ValueError("expected none, rtscts or xonxoff")
    return text


def _estimate_seconds(dl: DisplayList, profile: DeviceProfile) -> float:
    """Estimated plot time of ``dl``, or 0 when the profile has no motion limits to estimate with."""
    try:
        return float(estimate_time(dl, profile).total)
    except (ConfigError, URLError) as exc:
        log.debug("no time estimate for %s: %s", profile.name, exc)
        return 0.0

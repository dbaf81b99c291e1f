"""pytest plugin ``pixelpen``: simulated plotters, panels and input devices for testing the applications that use them.

Installed with pixelpen (entry point ``pytest11``), it offers:

* ``sim_plotter`` - a :class:`SimPlotter` whose ``url`` (``sim:MODEL?speed=fast&id=...``) the application
  under test opens with ``pixelpen.open`` (or passes to whatever opens it); afterwards the test looks at the
  simulated device through ``device``, ``paper()``, ``save_paper()``, ``commands`` and ``elapsed``.  The
  model is ``hp7475a`` unless the test parametrises the fixture indirectly with ``"MODEL"`` or
  ``"MODEL?key=value&..."``;
* ``sim_port`` - the same for applications that use pyserial themselves: ``url`` is a ``sim://MODEL?...``
  port URL for ``serial.serial_for_url`` (the plugin registers the ``sim://`` handler);
* ``make_sim_plotter`` - a factory, ``make_sim_plotter("grbl", pen="z")`` or ``make_sim_plotter("grbl",
  port=True)``, for tests that need several devices or options chosen in the test;
* ``--pixelpen-paper-dir DIR`` - save the paper of every simulated device a test used, as
  ``DIR/<test name>-<model>[-N].png``, for inspection;
* ``sim_panel`` - a :class:`SimPanel`: ``url`` (``sim:MODEL?id=...``) for the application, or ``open()`` to
  open the display and keep watching it; then ``glass()``, ``gram``, ``bus`` / ``bus_bytes`` (the
  simulator's bus counters), ``events``, ``frames`` (per frame: bytes, windows, bus and host seconds) and
  ``recording()`` (the command and data frames on the bus).  ``st7789`` 240x240 unless parametrised
  indirectly like ``sim_plotter``; ``make_sim_panel(model, **options)`` is the factory;
* ``--pixelpen-glass-dir DIR`` - save the glass of every simulated panel a failed test used, as
  ``DIR/<test name>-<model>[-N].png``;
* ``sim_input`` - a factory: ``sim_input(source, clock=None, **options)`` opens a simulated HID input device as
  a ``pixelpen.input.InputDevice`` (``read(timeout)``, ``events()``) on a SimulatedClock of its own (or
  ``clock``).  ``source`` is a model name (``"tablet"``: the ``sim:`` URL an application would open, options
  the simulator declares, e.g. ``script="signature"``, go to it, the others to the device semantics), report
  descriptor bytes (a device with that descriptor sending the ``reports=[(seconds, bytes), ...]`` given), or a
  ``HidRecording``.  ``sim_input.simulator(device)`` is the simulated device behind it (``HidSim``: faults,
  LEDs, feature settings), reached through the fake hidapi module just as the hardware would be;
* ``replay_input`` - a factory: ``replay_input(path, clock=None, **options)`` opens a hid-recorder file
  (``replay:`` URL; ``device=N``, ``realtime=``) the same way, as fast as it is read.

Input devices opened by the two input fixtures are closed when the test ends.

The simulated device is created when the application first opens the URL and reached again by its ``id``
(also after a reconnect); it lives in the test's process, so the application must run in that process
(not in a subprocess).  Simulators run in simulated time (``speed=fast``): a long plot takes milliseconds.
Every device is forgotten (closed) when its test ends.
"""

from __future__ import annotations

import contextlib
import itertools
import re
import uuid
from collections.abc import Callable, Generator, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    import numpy as np
    from PIL import Image

    from pixelpen.devices.panels.frames import FrameStats
    from pixelpen.display.kinds import RasterDisplay
    from pixelpen.drivers.bustrace import BusTrace
    from pixelpen.drivers.recordings.hidrecorder import HidRecording
    from pixelpen.input.device import InputDevice
    from pixelpen.sim.base import StreamDevice
    from pixelpen.sim.hid.device import HidSim

DEFAULT_MODEL = "hp7475a"
"""The model ``sim_plotter`` and ``sim_port`` simulate unless parametrised."""
DEFAULT_PANEL = "st7789?size=240x240"
"""The panel ``sim_panel`` simulates unless parametrised."""
_ids = itertools.count(1)
_REPORTS = pytest.StashKey[dict[str, pytest.TestReport]]()


class _Simulated:
    """What both fixtures' objects share: a URL naming a simulator instance by ``id``, and its lookup."""

    id: str
    url: str

    def __str__(self) -> str:
        """The URL, so the object can be handed on where a URL string is expected."""
        return self.url

    @property
    def opened(self) -> bool:
        """True once the application has opened the URL (the simulator exists)."""
        from pixelpen.sim.base import named_simulator

        try:
            named_simulator(self.id)
        except KeyError:
            return False
        return True

    def _named(self, what: str) -> Any:
        """The simulator behind the URL; LookupError naming ``what`` before the URL is opened."""
        from pixelpen.sim.base import named_simulator

        try:
            return named_simulator(self.id)
        except KeyError:
            raise LookupError(f"the application has not opened {self.url} yet, so there is no {what}") from None


class SimPlotter(_Simulated):
    """A simulated device for one test: the URL to hand the application, and the device behind it."""

    def __init__(self, model: str, options: dict[str, str] | None = None, *, port: bool = False) -> None:
        from pixelpen.sim.base import simulator_models
        from pixelpen.urls import format_url

        known = simulator_models()
        if model.lower() not in known:
            raise pytest.UsageError(f"pixelpen: no simulator for model {model!r}; known: {', '.join(known)}")
        options = dict(options or {})
        for key in ("speed", "id"):
            if key in options:
                raise pytest.UsageError(f"pixelpen: option {key!r} is set by the fixture (speed=fast, a unique id)")
        self.model = model.lower()
        self.id = f"pytest-{next(_ids)}-{uuid.uuid4().hex[:8]}"
        """The simulator instance's name (the URL's ``id=``)."""
        query = {"speed": "fast", "id": self.id, **options}
        self.url = format_url("sim", ("//" if port else "") + self.model, query)
        """``sim:MODEL?...`` for ``pixelpen.open``, or ``sim://MODEL?...`` for pyserial with ``port=True``."""

    def __repr__(self) -> str:
        return f"SimPlotter({self.url!r})"

    @property
    def device(self) -> StreamDevice:
        """The simulated device the application opened (its paper, logs, counters and state)."""
        return self._named("device")

    def paper(self, dpi: float = 96.0) -> np.ndarray:
        """The paper as an (H, W, 3) uint8 RGB array (white sheet, strokes in their pens' colours)."""
        return self.device.paper_image(dpi).to_rgb()  # type: ignore[attr-defined]

    def save_paper(self, path: str | Path, dpi: float = 96.0) -> Path:
        """Write the paper image to ``path`` (format from the extension); return the path."""
        path = Path(path)
        self.device.save_paper(path, dpi)  # type: ignore[attr-defined]
        return path

    @property
    def commands(self) -> list[str]:
        """Every command the device executed, in order (HP-GL instructions, G-code lines, EBB commands)."""
        device = self.device
        log = getattr(device, "command_log", None)  # HP-GL plotters; GRBL and the EBB call it ``log``
        return [text for _, text in (log if log is not None else device.log)]  # type: ignore[attr-defined]

    @property
    def elapsed(self) -> float:
        """Simulated seconds since the device was created (clock starts at 0): initialising, pen changes, parking."""
        return float(self.device.clock.now())


def _new_id() -> str:
    return f"pytest-{next(_ids)}-{uuid.uuid4().hex[:8]}"


class SimPanel(_Simulated):
    """A simulated panel (or framebuffer) for one test: the URL to hand the application, the chip behind it,
    and, for a display opened with :meth:`open`, its frames and bus traffic."""

    def __init__(self, model: str, options: dict[str, str] | None = None) -> None:
        from pixelpen.display.registry import scheme_names
        from pixelpen.urls import format_url

        model = model.lower()
        if not _is_simulated_panel(model):
            panels = [name for name in scheme_names() if _is_simulated_panel(name)]
            raise pytest.UsageError(f"pixelpen: no simulated panel {model!r}; known: {', '.join(panels)}")
        options = dict(options or {})
        if "id" in options:
            raise pytest.UsageError("pixelpen: option 'id' is set by the fixture (a unique id)")
        self.model = model
        self.id = _new_id()
        """The simulator instance's name (the URL's ``id=``)."""
        self.url = format_url("sim", model, {"id": self.id, **options})
        """``sim:MODEL?id=...&options`` for ``pixelpen.open``."""
        self._display: RasterDisplay | None = None

    def __repr__(self) -> str:
        return f"SimPanel({self.url!r})"

    # -- the display ---------------------------------------------------------------------------------
    def open(self, **options: Any) -> RasterDisplay:
        """Open the display of :attr:`url` (plus display ``options``, e.g. ``rotation=90``) and watch it:
        its frames are counted in :attr:`frames` from the first (the full frame of the initialisation) until the
        display is opened again (``open()`` after ``close()`` starts new statistics)."""
        import pixelpen
        from pixelpen.display.kinds import RasterDisplay
        from pixelpen.errors import ConfigError
        from pixelpen.urls import format_url, parse_url

        parsed = parse_url(self.url)
        display = pixelpen.open(format_url("sim", self.model, {**parsed.options,
                                                               **{k: str(v) for k, v in options.items()}}))
        if not isinstance(display, RasterDisplay):  # pragma: no cover - every panel scheme is raster
            display.close()
            raise ConfigError(f"{self.url} did not open a raster display")
        self._display = display
        return display

    @property
    def display(self) -> RasterDisplay:
        """The display :meth:`open` opened (LookupError before)."""
        if self._display is None:
            raise LookupError(f"{self.url}: no display was opened with open() (an application's own display "
                              "is reached through simulator, glass(), gram and bus)")
        return self._display

    @property
    def frames(self) -> list[FrameStats]:
        """The frames the display of :meth:`open` sent since it was opened (its ``stats.history``: the last
        ``pixelpen.devices.panels.frames.HISTORY``): ``bytes``, ``windows``, ``bus_seconds``, ``host_seconds``,
        ``full`` (``FrameStats``)."""
        history = getattr(getattr(self.display, "stats", None), "history", None)
        if history is None:
            raise LookupError(f"{self.model}: this display keeps no per-frame statistics")
        return list(history)

    @contextlib.contextmanager
    def recording(self) -> Iterator[BusTrace]:
        """Record the bus traffic of the display of :meth:`open` meanwhile (its ``recording()``): a
        ``BusTrace`` whose ``events`` are its command (``C``) and data (``D``) frames, filled in when the block
        ends."""
        recording = getattr(self.display, "recording", None)
        if recording is None:
            raise LookupError(f"{self.model}: this display has no panel bus to record")
        with recording() as trace:
            yield trace

    # -- the simulated chip ------------------------------------------------------------------------------
    @property
    def simulator(self) -> Any:
        """The simulated chip (``MipiDcsSim``, ``SSD1306Sim``, ``FbdevSim``); LookupError before the URL is opened."""
        return self._named("panel")

    def glass(self) -> Image.Image:
        """What the panel shows now, as a PIL image (RGB for a TFT, "1"/"L" for a mono OLED)."""
        return self.simulator.glass()

    def save_glass(self, path: str | Path) -> Path:
        """Write the glass to ``path`` (format from the extension); return the path."""
        path = Path(path)
        self.glass().save(path)
        return path

    @property
    def gram(self) -> np.ndarray:
        """The controller's memory as the simulator stores it (see its class)."""
        return self.simulator.gram

    @property
    def bus(self) -> Any:
        """The simulator's bus counters (``BusStats``: bytes, command_bytes, data_bytes, transfers, bus_seconds,
        frames)."""
        return self.simulator.stats

    @property
    def bus_bytes(self) -> int:
        """Every byte the panel received on its bus (I2C address and control bytes included)."""
        return int(self.bus.bytes)

    @property
    def events(self) -> list[Any]:
        """What the controller flagged (``PanelEvent``: time, offset, command, message); empty when all was well."""
        return list(getattr(self.simulator, "events", []))

    def close(self) -> None:
        """Close the display of :meth:`open`, if still open."""
        if self._display is not None:
            self._display.close()


def _is_simulated_panel(scheme: str) -> bool:
    """True for a scheme whose display is raster and simulated (panels, framebuffers: ``sim:SCHEME``)."""
    from pixelpen.display.kinds import RasterDisplay
    from pixelpen.display.registry import display_class
    from pixelpen.errors import URLError

    try:
        cls = display_class(scheme)
    except URLError:
        return False
    return issubclass(cls, RasterDisplay) and bool(cls.simulated)


class _Session:
    """The SimPlotters of one test, saved (if asked) and forgotten when it ends."""

    def __init__(self, request: pytest.FixtureRequest) -> None:
        self.request = request
        self.made: list[SimPlotter] = []

    def make(self, model: str, *, port: bool = False, **options: Any) -> SimPlotter:
        """A new SimPlotter of ``model`` with URL options (values become strings)."""
        plotter = SimPlotter(model, {k: str(v) for k, v in options.items()}, port=port)
        self.made.append(plotter)
        return plotter

    def finish(self) -> None:
        from pixelpen.sim.base import forget_simulator

        paper_dir = self.request.config.getoption("pixelpen_paper_dir")
        try:
            if paper_dir:
                self._save(Path(paper_dir))
        finally:
            for plotter in self.made:
                forget_simulator(plotter.id)

    def _save(self, folder: Path) -> None:
        for plotter, path in _image_paths(folder, self.request, self.made):
            plotter.save_paper(path)


class _PanelSession:
    """The SimPanels of one test: displays closed, glass saved when the test failed (if asked), chips forgotten."""

    def __init__(self, request: pytest.FixtureRequest) -> None:
        self.request = request
        self.made: list[SimPanel] = []

    def make(self, model: str, **options: Any) -> SimPanel:
        """A new SimPanel of ``model`` with URL options (values become strings)."""
        panel = SimPanel(model, {k: str(v) for k, v in options.items()})
        self.made.append(panel)
        return panel

    def finish(self) -> None:
        from pixelpen.sim.base import forget_simulator

        glass_dir = self.request.config.getoption("pixelpen_glass_dir")
        try:
            for panel in self.made:
                panel.close()
            reports = self.request.node.stash.get(_REPORTS, {})
            if glass_dir and any(r.failed for r in reports.values()):
                for panel, path in _image_paths(Path(glass_dir), self.request, self.made):
                    panel.save_glass(path)
        finally:
            for panel in self.made:
                forget_simulator(panel.id)


class SimInput:
    """The ``sim_input`` factory of one test: opens simulated input devices, closes them when the test ends."""

    def __init__(self) -> None:
        self._opened: list[tuple[InputDevice, HidSim | None]] = []
        self._named: list[str] = []

    def __call__(self, source: str | bytes | HidRecording, *, clock: Any = None, **options: Any) -> InputDevice:
        """An opened InputDevice over the simulated ``source`` (a model, descriptor bytes or a HidRecording)."""
        from pixelpen.clock import SimulatedClock
        from pixelpen.drivers.recordings.hidrecorder import HidRecording
        from pixelpen.sim.hid.device import HidSim

        clock = clock if clock is not None else SimulatedClock()
        if isinstance(source, str):
            return self._model(source, clock, options)
        if isinstance(source, (bytes, bytearray, memoryview)):
            sim = HidSim.from_descriptor(bytes(source), options.pop("reports", ()), clock=clock, model="hid")
        elif isinstance(source, HidRecording):
            from pixelpen.sim.hid.replay import replay_device

            sim = replay_device(source, clock=clock)
        else:
            raise pytest.UsageError(f"pixelpen: sim_input takes a model name, descriptor bytes or a HidRecording, "
                                    f"not {type(source).__name__}")
        from pixelpen.input.registry import open_report_device

        device = open_report_device(sim, clock=clock, **options)
        self._opened.append((device, sim))
        return device

    def _model(self, model: str, clock: Any, options: dict[str, Any]) -> InputDevice:
        """``sim:MODEL?...`` opened as an application opens it; the simulator's options in the URL."""
        from pixelpen.input.registry import open_input
        from pixelpen.sim.base import named_simulator, simulator_options
        from pixelpen.urls import format_url

        if "id" in options:
            raise pytest.UsageError("pixelpen: option 'id' is set by sim_input (a unique id)")
        names = {spec.name for spec in simulator_options(model)}
        name = _new_id()
        query = {"id": name, **{k: str(v) for k, v in options.items() if k in names}}
        self._named.append(name)
        device = open_input(format_url("sim", model, query), clock=clock,
                            **{k: v for k, v in options.items() if k not in names})
        self._opened.append((device, named_simulator(name)))
        return device

    def simulator(self, device: InputDevice) -> HidSim:
        """The simulated HID device behind ``device`` (one this factory opened)."""
        for opened, sim in self._opened:
            if opened is device and sim is not None:
                return sim
        raise LookupError(f"{device!r} was not opened by sim_input")

    def track(self, device: InputDevice) -> InputDevice:
        """Close ``device`` when the test ends."""
        self._opened.append((device, None))
        return device

    def finish(self) -> None:
        """Close every device opened, forget the named simulators."""
        from pixelpen.sim.base import forget_simulator

        try:
            for device, _ in self._opened:
                device.close()
        finally:
            for name in self._named:
                forget_simulator(name)


def _image_paths(folder: Path, request: pytest.FixtureRequest, made: list[Any]) -> list[tuple[Any, Path]]:
    """``folder/<test name>-<model>[-N].png`` for each device of ``made`` that was opened (folder created)."""
    folder.mkdir(parents=True, exist_ok=True)
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", request.node.name).strip("_")
    used = [d for d in made if d.opened]
    return [(d, folder / f"{stem}-{d.model}{f'-{n}' if len(used) > 1 else ''}.png") for n, d in enumerate(used, 1)]


def _parse_param(param: object, default: str = DEFAULT_MODEL) -> tuple[str, dict[str, str]]:
    """An indirect parameter: ``"MODEL"``, ``"MODEL?key=value&..."`` or a ``{"model": ..., key: value}`` dict."""
    if isinstance(param, dict):
        options = {k: str(v) for k, v in param.items()}
        return options.pop("model", default), options
    if isinstance(param, str):
        from pixelpen.urls import parse_url

        model, _, query = param.partition("?")
        return model, dict(parse_url(f"sim:{model}?{query}").options) if query else {}
    raise pytest.UsageError(f"pixelpen: parametrise with 'MODEL', 'MODEL?key=value' or a dict, got {param!r}")


def pytest_addoption(parser: pytest.Parser) -> None:
    """``--pixelpen-paper-dir DIR``: save every test's simulated paper there; ``--pixelpen-glass-dir DIR``: the
    glass of the simulated panels of failed tests."""
    group = parser.getgroup("pixelpen", "pixelpen simulated devices")
    group.addoption("--pixelpen-paper-dir", dest="pixelpen_paper_dir", default=None, metavar="DIR",
                    help="save the paper of every simulated plotter a test used as DIR/<test>-<model>.png")
    group.addoption("--pixelpen-glass-dir", dest="pixelpen_glass_dir", default=None, metavar="DIR",
                    help="save the glass of every simulated panel a failed test used as DIR/<test>-<model>.png")


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Generator[None, Any, Any]:
    """Keep each phase's report on the test item, so the panel fixtures know whether the test failed."""
    report: pytest.TestReport = yield
    item.stash.setdefault(_REPORTS, {})[report.when] = report
    return report


def pytest_configure(config: pytest.Config) -> None:
    """Register the ``sim://`` pyserial URL handler for the applications under test."""
    import pixelpen.sim.transports.urlhandler  # noqa: F401  (makes serial.serial_for_url("sim://...") work)


@pytest.fixture
def make_sim_plotter(request: pytest.FixtureRequest) -> Iterator[Callable[..., SimPlotter]]:
    """Factory ``make_sim_plotter(model, port=False, **options) -> SimPlotter``; devices forgotten after the test."""
    session = _Session(request)
    try:
        yield session.make
    finally:
        session.finish()


@pytest.fixture
def sim_plotter(request: pytest.FixtureRequest, make_sim_plotter: Callable[..., SimPlotter]) -> SimPlotter:
    """A simulated plotter whose ``url`` (``sim:MODEL?...``) the application opens with ``pixelpen.open``."""
    model, options = _parse_param(getattr(request, "param", DEFAULT_MODEL))
    return make_sim_plotter(model, **options)


@pytest.fixture
def sim_port(request: pytest.FixtureRequest, make_sim_plotter: Callable[..., SimPlotter]) -> SimPlotter:
    """A simulated device whose ``url`` (``sim://MODEL?...``) the application opens with pyserial."""
    model, options = _parse_param(getattr(request, "param", DEFAULT_MODEL))
    return make_sim_plotter(model, port=True, **options)


@pytest.fixture
def make_sim_panel(request: pytest.FixtureRequest) -> Iterator[Callable[..., SimPanel]]:
    """Factory ``make_sim_panel(model, **options) -> SimPanel``; displays closed and chips forgotten after the test."""
    session = _PanelSession(request)
    try:
        yield session.make
    finally:
        session.finish()


@pytest.fixture
def sim_panel(request: pytest.FixtureRequest, make_sim_panel: Callable[..., SimPanel]) -> SimPanel:
    """A simulated panel (ST7789 240x240 unless parametrised) whose ``url`` the application opens."""
    model, options = _parse_param(getattr(request, "param", DEFAULT_PANEL), DEFAULT_PANEL.partition("?")[0])
    return make_sim_panel(model, **options)


@pytest.fixture
def sim_input() -> Iterator[SimInput]:
    """Factory ``sim_input(model | descriptor bytes | HidRecording, clock=None, **options) -> InputDevice`` on a
    simulated clock; ``sim_input.simulator(device)`` is the simulated device.  Devices are closed after the test."""
    factory = SimInput()
    try:
        yield factory
    finally:
        factory.finish()


@pytest.fixture
def replay_input(sim_input: SimInput) -> Callable[..., InputDevice]:
    """Factory ``replay_input(path, clock=None, **options) -> InputDevice`` replaying a hid-recorder file (the
    ``replay:`` URL: ``device=N`` picks a device of the file, ``realtime=True`` paces it; other options go to the
    semantics), as fast as it is read on a simulated clock.  Devices are closed after the test."""
    from pixelpen.input.registry import open_input
    from pixelpen.input.sources import REPLAY_OPTIONS
    from pixelpen.urls import format_url

    names = {spec.name for spec in REPLAY_OPTIONS}

    def replay(path: str | Path, *, clock: Any = None, **options: Any) -> InputDevice:
        query = {k: str(v) for k, v in options.items() if k in names}
        url = format_url("replay", str(path), query)
        return sim_input.track(open_input(url, clock=clock, **{k: v for k, v in options.items() if k not in names}))

    return replay

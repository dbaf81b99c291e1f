"""pytest plugin ``pixelpen``: simulated plotters for testing the applications that drive them.

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
  ``DIR/<test name>-<model>[-N].png``, for inspection.

The simulated device is created when the application first opens the URL and reached again by its ``id``
(also after a reconnect); it lives in the test's process, so the application must run in that process
(not in a subprocess).  Simulators run in simulated time (``speed=fast``): a long plot takes milliseconds.
Every device is forgotten (closed) when its test ends.
"""

from __future__ import annotations

import itertools
import re
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    import numpy as np

    from pixelpen.sim.base import StreamDevice

DEFAULT_MODEL = "hp7475a"
"""The model ``sim_plotter`` and ``sim_port`` simulate unless parametrised."""
_ids = itertools.count(1)


class SimPlotter:
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

    def __str__(self) -> str:
        """The URL, so the object can be handed on where a URL string is expected."""
        return self.url

    @property
    def opened(self) -> bool:
        """True once the application has opened the URL (the device exists)."""
        from pixelpen.sim.base import named_simulator

        try:
            named_simulator(self.id)
        except KeyError:
            return False
        return True

    @property
    def device(self) -> StreamDevice:
        """The simulated device the application opened (its paper, logs, counters and state)."""
        from pixelpen.sim.base import named_simulator

        try:
            return named_simulator(self.id)
        except KeyError:
            raise LookupError(f"the application has not opened {self.url} yet, so there is no device") from None

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
        folder.mkdir(parents=True, exist_ok=True)
        stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", self.request.node.name).strip("_")
        used = [p for p in self.made if p.opened]
        for n, plotter in enumerate(used, start=1):
            suffix = f"-{n}" if len(used) > 1 else ""
            plotter.save_paper(folder / f"{stem}-{plotter.model}{suffix}.png")


def _parse_param(param: object) -> tuple[str, dict[str, str]]:
    """An indirect parameter: ``"MODEL"``, ``"MODEL?key=value&..."`` or a ``{"model": ..., key: value}`` dict."""
    if isinstance(param, dict):
        options = {k: str(v) for k, v in param.items()}
        return options.pop("model", DEFAULT_MODEL), options
    if isinstance(param, str):
        from pixelpen.urls import parse_url

        model, _, query = param.partition("?")
        return model, dict(parse_url(f"sim:{model}?{query}").options) if query else {}
    raise pytest.UsageError(f"pixelpen: parametrise with 'MODEL', 'MODEL?key=value' or a dict, got {param!r}")


def pytest_addoption(parser: pytest.Parser) -> None:
    """``--pixelpen-paper-dir DIR``: save every test's simulated paper there."""
    group = parser.getgroup("pixelpen", "pixelpen simulated devices")
    group.addoption("--pixelpen-paper-dir", dest="pixelpen_paper_dir", default=None, metavar="DIR",
                    help="save the paper of every simulated plotter a test used as DIR/<test>-<model>.png")


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

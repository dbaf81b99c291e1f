"""What every simulated device offers its transports: bytes in, bytes out, time, faults; and the model registry."""

from __future__ import annotations

from typing import Callable, Protocol, runtime_checkable

from pixelpen.clock import Clock
from pixelpen.errors import URLError


@runtime_checkable
class WireDevice(Protocol):
    """The device side of a wire protocol, as a transport (pty, pyserial URL, pyusb backend) sees it.

    The transport calls ``advance_to(clock.now())`` before it looks at the device, feeds host bytes
    with ``receive`` (only while ``ready_to_receive`` when hardware handshake is on), and drains the
    device's answers with ``take_output``.  Devices keep time on ``clock``: a simulated plot takes the
    device's real time unless the clock is a SimulatedClock.  A device produces output only inside
    ``receive``, ``advance_to`` or ``inject``; output it makes by itself later is due at a time it
    announces through ``next_event_time``.  Printer-class devices may also offer ``paper_empty``,
    ``selected`` and ``error`` attributes for the USB port-status request.
    """

    model: str
    clock: Clock

    def receive(self, data: bytes) -> None:
        """Accept bytes from the host (any chunking; a full buffer behaves as the device's does)."""

    def take_output(self) -> bytes:
        """Return and forget the bytes the device has sent to the host so far."""

    def advance_to(self, t: float) -> None:
        """Run the device (execute buffered commands, move the pen) up to clock time ``t``."""

    @property
    def ready_to_receive(self) -> bool:
        """Hardware handshake line (CTS/DTR as the device drives it): True while it can take bytes."""

    def next_event_time(self) -> float | None:
        """Clock time at which the device's state next changes by itself (None: idle until fed)."""

    def inject(self, fault: str) -> None:
        """Apply a device-level fault now: 'power-loss', 'paper-lever', 'pause-button', 'reset'."""

    def close(self) -> None:
        """Stop the device and release what it holds (its paper stays readable)."""


SimulatorFactory = Callable[..., WireDevice]
_REGISTRY: dict[str, SimulatorFactory] = {}
_NAMED: dict[str, WireDevice] = {}


def register_simulator(model: str, factory: SimulatorFactory) -> None:
    """Make ``model`` available to ``create_simulator`` and ``sim:``/``sim://`` URLs."""
    _REGISTRY[model.lower()] = factory


def create_simulator(model: str, /, *, clock: Clock | None = None, **options: str) -> WireDevice:
    """Build the simulator of ``model`` with URL options (strings) on ``clock``; unknown models list the known ones.

    The option ``id=NAME`` names the instance: a later URL with the same ``id`` reaches the same
    simulated device (its paper, buffer and state) instead of a new one — a reconnect after an
    unplug, or a test fixture that looks at the device an application opened by URL.
    """
    _load_builtin()
    name = options.pop("id", None)
    if name is not None and name in _NAMED:
        device = _NAMED[name]
        if device.model.lower() != model.lower():
            raise URLError(f"simulator id={name!r} is a {device.model}, not a {model}")
        return device
    try:
        factory = _REGISTRY[model.lower()]
    except KeyError:
        raise URLError(f"no simulator for model {model!r}; known: {', '.join(sorted(_REGISTRY)) or 'none'}") from None
    device = factory(clock=clock, **options)
    if name is not None:
        _NAMED[name] = device
    return device


def named_simulator(name: str) -> WireDevice:
    """The simulator created with ``id=name`` (KeyError naming the known ids otherwise)."""
    try:
        return _NAMED[name]
    except KeyError:
        raise KeyError(f"no simulator with id {name!r}; ids: {', '.join(sorted(_NAMED)) or 'none'}") from None


def forget_simulator(name: str) -> None:
    """Drop the named instance (closing it), so the next ``id=name`` builds a fresh device."""
    device = _NAMED.pop(name, None)
    if device is not None:
        device.close()


def simulator_models() -> list[str]:
    """Names of all registered simulator models."""
    _load_builtin()
    return sorted(_REGISTRY)


def _load_builtin() -> None:
    """Import the simulator modules shipped with pixelpen so they register themselves."""
    import importlib
    import pkgutil

    from pixelpen.sim import plotters

    for info in pkgutil.walk_packages(plotters.__path__, f"{plotters.__name__}."):
        if not info.name.rpartition(".")[2].startswith("_"):
            importlib.import_module(info.name)

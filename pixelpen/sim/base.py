"""What every simulated device offers its transports, the shared simulator base and faults, and the model registry.

Three device-side protocols, one per kind of transport (the mirror of the host side in ``drivers/``):

* ``StreamDevice`` — a byte stream (serial, USB CDC, USB printer class): bytes in, bytes out;
* ``BusDevice`` — a panel on an SPI bus (D/C line, chip select) or an I2C bus (address, control byte);
* ``ReportDevice`` — a HID device: a report descriptor, input reports out, output and feature reports in.

``SimulatedDevice`` is the base the simulators share: the clock and the event loop run on it, the
output queue, the closed guard, and ``inject(Fault.X, at=N)``.  Simulators are found by model name
through a table of module names (``BUILTIN_SIMULATORS``) and the entry-point group
``pixelpen.simulators``, so creating one imports only its own modules.
"""

from __future__ import annotations

import bisect
import enum
import importlib
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from importlib import metadata
from typing import Any, ClassVar, Protocol, runtime_checkable

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.errors import ConfigError, InvalidArgumentType, URLError
from pixelpen.options import OptionSpec

MAX_EVENTS_PER_ADVANCE = 10_000_000
"""A simulator's event loop that has not caught up after this many events has a bug (never a hang)."""


class Fault(enum.Enum):
    """Faults a test or campaign injects; the value is the name URLs and ``pixelpen sim`` use."""

    POWER_LOSS = "power-loss"
    """The device loses power: motion stops where it is; what it held in RAM is gone."""
    POWER_RESTORE = "power-restore"
    """Power comes back (the EBB's motor supply V+; the logic kept running on USB)."""
    RESET = "reset"
    """The device reboots as at power-up."""
    PAUSE_BUTTON = "pause-button"
    """The operator presses the device's pause (VIEW, feed hold, PRG) button."""
    PAPER_LEVER = "paper-lever"
    """The operator raises the paper lever (HP plotters suspend plotting)."""

    @classmethod
    def of(cls, fault: Fault | str) -> Fault:
        """The Fault a name (``"power-loss"``) or member stands for; ConfigError listing the names otherwise."""
        if isinstance(fault, Fault):
            return fault
        try:
            return cls(fault)
        except ValueError:
            raise ConfigError(f"unknown fault {fault!r}; known: {', '.join(f.value for f in cls)}") from None


@runtime_checkable
class StreamDevice(Protocol):
    """The device side of a byte stream, as a transport (pty, pyserial URL, pyusb backend) sees it.

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

    def inject(self, fault: Fault | str, at: int | None = None) -> None:
        """Apply a device-level fault now, or once ``at`` host bytes have arrived."""

    def close(self) -> None:
        """Stop the device and release what it holds (its paper stays readable)."""


WireDevice = StreamDevice
"""The name ``StreamDevice`` had before panels and input devices joined (kept for existing imports)."""


@runtime_checkable
class BusDevice(Protocol):
    """The device side of a panel bus: a controller chip on SPI (D/C, chip select) or I2C (address, control byte).

    SPI: the host asserts chip select, sets D/C (low: command, high: data) and clocks bytes; the chip
    answers on MISO during reads.  I2C: each write is an addressed transaction whose bytes start with a
    control byte (SSD1306: 0x00 commands follow, 0x40 data follow; bit 7 Co); a missing device NAKs the
    address.  ``set_line`` drives the wired GPIO lines the chip has (``"reset"``, ``"backlight"``);
    ``line`` reads the ones it drives (``"te"``, the tearing-effect output).
    """

    model: str
    clock: Clock

    def spi_transfer(self, data: bytes, *, dc: bool) -> bytes:
        """One chip-select frame of ``data`` with D/C at ``dc``; returns the bytes read on MISO meanwhile."""

    def i2c_write(self, address: int, data: bytes) -> bool:
        """One I2C write transaction to 7-bit ``address``; False when the address is not acknowledged."""

    def i2c_read(self, address: int, length: int) -> bytes | None:
        """One I2C read of ``length`` bytes from ``address``; None when the address is not acknowledged."""

    def set_line(self, name: str, level: bool) -> None:
        """Drive an input line of the chip (``"reset"`` is active low, as on the glass)."""

    def line(self, name: str) -> bool:
        """The level of an output line of the chip (``"te"``)."""

    def advance_to(self, t: float) -> None:
        """Run the chip (delays after SWRESET/SLPOUT, the refresh scan) up to clock time ``t``."""

    def next_event_time(self) -> float | None:
        """Clock time at which the chip's state next changes by itself (None: idle until written)."""

    def inject(self, fault: Fault | str, at: int | None = None) -> None:
        """Apply a device-level fault now, or once ``at`` host bytes have arrived."""

    def close(self) -> None:
        """Stop the chip (what it shows stays readable)."""


@runtime_checkable
class ReportDevice(Protocol):
    """The device side of a HID report link: a descriptor, input reports to the host, output/feature reports in.

    Reports are whole byte strings starting with the report ID when the descriptor numbers its
    reports.  Input reports the device produced by clock time ``t`` are taken with ``take_reports``
    after ``advance_to(t)`` (a HID device sends them on its interrupt endpoint at its polling interval).
    """

    model: str
    clock: Clock
    report_descriptor: bytes

    def take_reports(self) -> list[bytes]:
        """Return and forget the input reports the device has sent so far, oldest first."""

    def take_timed_reports(self) -> list[tuple[float, bytes]]:
        """The same as ``take_reports``, each with the clock time the device sent it."""

    def write_report(self, report: bytes) -> None:
        """An output report from the host (keyboard LEDs, force feedback)."""

    def get_feature(self, report_id: int) -> bytes:
        """The feature report ``report_id`` as the device answers a GET_REPORT request."""

    def send_feature(self, report: bytes) -> None:
        """A feature report from the host (SET_REPORT)."""

    def advance_to(self, t: float) -> None:
        """Run the device (its hand-held motion script, its polling interval) up to clock time ``t``."""

    def next_event_time(self) -> float | None:
        """Clock time of the device's next input report (None: nothing scheduled)."""

    def inject(self, fault: Fault | str, at: int | None = None) -> None:
        """Apply a device-level fault now, or once ``at`` host bytes have arrived."""

    def close(self) -> None:
        """Unplug the device."""


def reached_through(device: object) -> str:
    """What a simulator is reached through, for messages: a byte stream, a panel bus, HID reports, or a framebuffer."""
    model = getattr(device, "model", "MODEL")
    if isinstance(device, BusDevice):  # checked first: every SimulatedDevice also has the byte-stream methods
        return f"a panel bus (pixelpen.open('sim:{model}'))"
    if isinstance(device, ReportDevice):
        return f"HID reports: an input device (pixelpen.open_input('sim:{model}'))"
    if isinstance(device, StreamDevice):
        return f"a byte stream (sim://{model}, a pty)"
    return f"its own interface (pixelpen.open('sim:{model}'))"


def is_stream_device(device: object) -> bool:
    """True for a simulator reached through a byte stream (panel and HID simulators have those methods too)."""
    return isinstance(device, StreamDevice) and not isinstance(device, (BusDevice, ReportDevice))


class SimulatedDevice(ABC):
    """The base of every simulator: clock and event loop, output queue, closed guard and fault injection.

    A subclass implements ``_receive`` (host bytes), ``_next_internal_event`` and ``_handle_event`` (its
    own timed changes: a move ends, a reply falls due), ``_apply_fault`` for the faults it lists in
    ``FAULTS``, and may override ``_service`` (work that needs no time: parse what arrived), ``_idle_to``
    (time passing with nothing due) and ``_shutdown``.  Output goes through ``_emit``.
    """

    model: str
    FAULTS: ClassVar[frozenset[Fault]] = frozenset()
    """The faults this device models; ``inject`` refuses the others, naming these."""

    def __init__(self, clock: Clock | None = None) -> None:
        self.clock = clock if clock is not None else REAL_CLOCK
        self._now = self.clock.now()
        self._out = bytearray()
        self._closed = False
        self._received = 0
        self._due: list[tuple[int, int, Fault]] = []
        """Faults waiting for a host byte count: (byte count, order of injection, fault)."""

    # ---- the stream side -------------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        """True once ``close`` was called."""
        return self._closed

    @property
    def ready_to_receive(self) -> bool:
        """Hardware handshake as the device drives it (a device with no handshake line: always True)."""
        return True

    def receive(self, data: bytes | bytearray | memoryview) -> None:
        """Host bytes (bytes, bytearray or memoryview), split where a fault injected ``at`` a byte count falls due.

        Ignored once closed; anything else (an int, str, list) raises InvalidArgumentType.
        """
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise InvalidArgumentType(f"{self.model}: receive() takes bytes, bytearray or memoryview, "
                                      f"not {type(data).__name__} {data!r:.40}")
        data = bytes(data)
        if self._closed:
            self._ignore(data)
            return
        while self._due and data:
            take = self._due[0][0] - self._received
            if take > 0:
                chunk, data = data[:take], data[take:]
                self._received += len(chunk)
                self._receive(chunk)
            if self._due and self._received >= self._due[0][0]:
                self._apply_fault(self._due.pop(0)[2])
        if data:
            self._received += len(data)
            self._receive(data)

    def take_output(self) -> bytes:
        """Bytes the device has sent since the last call."""
        out = bytes(self._out)
        self._out.clear()
        return out

    def advance_to(self, t: float) -> None:
        """Run the device's own events in time order up to clock time ``t`` (never backwards)."""
        if self._closed:
            return
        for _ in range(MAX_EVENTS_PER_ADVANCE):
            self._service()
            te = self._next_internal_event()
            if te is None or te > t:
                break
            self._handle_event(max(te, self._now))
        else:  # pragma: no cover - a bug, never a hang
            raise RuntimeError(f"{self.model} simulator: event loop does not converge")
        if t > self._now:
            self._idle_to(t)
        self._service()

    def next_event_time(self) -> float | None:
        """When the device's state next changes by itself (None when closed or idle)."""
        return None if self._closed else self._next_internal_event()

    def inject(self, fault: Fault | str, at: int | None = None) -> None:
        """Apply ``fault`` now, or once ``at`` host bytes have arrived in all (a name or a Fault member)."""
        member = Fault.of(fault)
        if member not in self.FAULTS:
            known = ", ".join(sorted(f.value for f in self.FAULTS)) or "none"
            raise ConfigError(f"{self.model}: unknown fault {member.value!r}; known: {known}")
        if at is None or at <= self._received:
            self._apply_fault(member)
        else:
            bisect.insort(self._due, (at, len(self._due), member))

    def close(self) -> None:
        """Stop the device; what it drew or shows stays readable (idempotent)."""
        if not self._closed:
            self._shutdown()
            self._closed = True

    # ---- what a simulator implements -------------------------------------------------------------
    @abstractmethod
    def _receive(self, data: bytes) -> None:
        """Take host bytes at the current device time."""

    @abstractmethod
    def _next_internal_event(self) -> float | None:
        """Clock time of the device's next timed change (None: nothing scheduled)."""

    @abstractmethod
    def _handle_event(self, t: float) -> None:
        """Move device time to ``t`` and carry out what falls due then."""

    @abstractmethod
    def _apply_fault(self, fault: Fault) -> None:
        """Carry out one of ``FAULTS`` at the current device time."""

    def _service(self) -> None:
        """Work that takes no device time (parse what arrived, answer queries); by default none."""

    def _idle_to(self, t: float) -> None:
        """Let time pass to ``t`` with no event due."""
        self._now = t

    def _shutdown(self) -> None:
        """Stop what runs when the device is closed; by default nothing."""

    def _ignore(self, data: bytes) -> None:
        """Bytes that arrived after ``close``; by default dropped."""

    def _catch_up(self) -> None:
        """Run the device up to the clock's present (before acting on bytes, a fault or a query)."""
        now = self.clock.now()
        if now > self._now:
            self.advance_to(now)

    def _emit(self, data: bytes) -> None:
        """Queue bytes for the host."""
        self._out += data


# ---- the model registry -----------------------------------------------------------------------------

SimDevice = Any
"""What a simulator factory returns: a ``StreamDevice`` (plotters), a ``BusDevice`` (panels) or another device
(the framebuffer simulator); callers check the protocol they need (``isinstance(d, BusDevice)``)."""

SimulatorFactory = Callable[..., SimDevice]

BUILTIN_SIMULATORS: dict[str, str] = {
    "hp7475a": "pixelpen.sim.plotters.hpgl.plotter",
    "hp7550a": "pixelpen.sim.plotters.hpgl.plotter",
    "hp7440a": "pixelpen.sim.plotters.hpgl.plotter",
    "grbl": "pixelpen.sim.plotters.grbl.controller",
    "axidraw": "pixelpen.sim.plotters.ebb.board",
    "ebb": "pixelpen.sim.plotters.ebb.board",
    "ssd1306": "pixelpen.sim.panels.ssd1306",
    "sh1106": "pixelpen.sim.panels.ssd1306",
    "ssd1309": "pixelpen.sim.panels.ssd1306",
    "st7789": "pixelpen.sim.panels.mipidcs",
    "ili9341": "pixelpen.sim.panels.mipidcs",
    "st7735": "pixelpen.sim.panels.mipidcs",
    "fbdev": "pixelpen.sim.panels.fbdev",
    "mouse": "pixelpen.sim.hid.models",
    "trackball": "pixelpen.sim.hid.models",
    "joystick": "pixelpen.sim.hid.models",
    "gamepad": "pixelpen.sim.hid.models",
    "tablet": "pixelpen.sim.hid.models",
    "touchscreen": "pixelpen.sim.hid.models",
    "keyboard": "pixelpen.sim.hid.models",
}
"""Model -> the module that registers its simulator when imported (only that module is loaded)."""

ENTRY_POINT_GROUP = "pixelpen.simulators"
"""Third-party simulators: ``model = "package.module:factory"`` in this entry-point group."""

_REGISTRY: dict[str, SimulatorFactory] = {}
_OPTIONS: dict[str, tuple[OptionSpec[Any], ...]] = {}
_NAMED: dict[str, SimDevice] = {}


def register_simulator(model: str, factory: SimulatorFactory, options: Sequence[OptionSpec[Any]] = ()) -> None:
    """Make ``model`` available to ``create_simulator`` and ``sim:``/``sim://`` URLs, with the URL options it reads."""
    _REGISTRY[model.lower()] = factory
    _OPTIONS[model.lower()] = tuple(options) or tuple(getattr(factory, "OPTIONS", ()))


def simulator_options(model: str) -> tuple[OptionSpec[Any], ...]:
    """The URL options the simulator of ``model`` reads (its module is imported if it was not yet)."""
    simulator_factory(model)
    return _OPTIONS.get(model.lower(), ())


def create_simulator(model: str, /, *, clock: Clock | None = None, **options: str) -> SimDevice:
    """Build the simulator of ``model`` with URL options (strings) on ``clock``; unknown models list the known ones.

    The option ``id=NAME`` names the instance: a later URL with the same ``id`` reaches the same
    simulated device (its paper, buffer and state) instead of a new one — a reconnect after an
    unplug, or a test fixture that looks at the device an application opened by URL.
    """
    name = options.pop("id", None)
    if name is not None and name in _NAMED:
        device = _NAMED[name]
        if device.model.lower() != model.lower():
            raise URLError(f"simulator id={name!r} is a {device.model}, not a {model}")
        return device
    device = simulator_factory(model)(clock=clock, **options)
    if name is not None:
        _NAMED[name] = device
    return device


def simulator_factory(model: str) -> SimulatorFactory:
    """The factory of ``model``, importing its module on first use; URLError listing the known models otherwise."""
    key = model.lower()
    if key not in _REGISTRY:
        if key in BUILTIN_SIMULATORS:
            importlib.import_module(BUILTIN_SIMULATORS[key])
        else:
            for entry in _entry_points():
                if entry.name.lower() == key:
                    try:
                        register_simulator(key, entry.load())
                    except Exception as exc:  # a broken plug-in: say which one, as a URL error
                        raise URLError(f"simulator plug-in {entry.name} ({entry.value}) failed to load: {exc}") from exc
    try:
        return _REGISTRY[key]
    except KeyError:
        raise URLError(f"no simulator for model {model!r}; known: {', '.join(simulator_models())}") from None


def named_simulator(name: str) -> SimDevice:
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
    """Names of all simulator models: built in, registered, and from entry points (none imported)."""
    return sorted(set(BUILTIN_SIMULATORS) | set(_REGISTRY) | {e.name.lower() for e in _entry_points()})


def _entry_points() -> list[metadata.EntryPoint]:
    """The third-party simulators declared in the ``pixelpen.simulators`` group."""
    return list(metadata.entry_points(group=ENTRY_POINT_GROUP))

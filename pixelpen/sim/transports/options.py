"""The options of a simulated line: TRANSPORT_OPTIONS (one OptionSpec each), Faults, TransportOptions, split_options.

A ``sim://`` URL (and ``pixelpen sim --option``) mixes the line's options with the simulator's; the
line's are read here against their specs and the rest go to the simulator factory.  What each
option does to the line is described in :mod:`pixelpen.sim.transports.port`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any, Final

from pixelpen.clock import REAL_CLOCK, Clock, SimulatedClock
from pixelpen.options import OptionSpec, choice, integer, read_options
from pixelpen.sim.base import Fault
from pixelpen.sim.plotters.sheet import paper_format

FLOWS: Final = ("none", "rtscts", "xonxoff")
SPEEDS: Final = ("real", "fast")
DEVICE_FAULTS: Final = {
    "power_loss_after": Fault.POWER_LOSS,
    "paper_lever_after": Fault.PAPER_LEVER,
    "pause_after": Fault.PAUSE_BUTTON,
}
"""URL option -> the fault the device is given (``inject(Fault.POWER_LOSS)``)."""


@dataclass(frozen=True)
class Faults:
    """Fault injection by host byte count (None: never); see the module docstring."""

    drop_after: int | None = None
    stall_after: int | None = None
    corrupt_at: int | None = None
    power_loss_after: int | None = None
    paper_lever_after: int | None = None
    pause_after: int | None = None

    def device_faults(self) -> list[tuple[int, Fault]]:
        """(byte count, fault) pairs in the order they fire (equal counts by the fault's name)."""
        pairs = [(getattr(self, key), fault) for key, fault in DEVICE_FAULTS.items()]
        return sorted(((n, f) for n, f in pairs if n is not None), key=lambda pair: (pair[0], pair[1].value))


@dataclass(frozen=True)
class TransportOptions:
    """The transport half of a ``sim://`` URL's options."""

    baud: int | None = None
    """None: the device's ``default_baud`` (see :func:`line_baud`)."""
    flow: str = "none"
    speed: str = "real"
    tx_buffer: int = 4096
    faults: Faults = field(default_factory=Faults)
    out: str | None = None
    """File the paper is saved to when the host closes the port (``.png`` or ``.svg``)."""

    def make_clock(self) -> Clock:
        """The clock a device behind these options runs on: real time, or a fresh SimulatedClock."""
        return SimulatedClock() if self.speed == "fast" else REAL_CLOCK


DEFAULT_BAUD: Final = 9600
"""Line speed of a device that names none (an RS-232 plotter's factory setting)."""


def paper_file(value: str) -> str:
    """A file name the paper can be saved as (``.png`` or ``.svg``)."""
    paper_format(value)
    return value


def _count(what: str) -> str:
    return f"{what} once N host bytes were delivered"


TRANSPORT_OPTIONS: Final[tuple[OptionSpec[Any], ...]] = (
    OptionSpec("baud", integer(1), None, "line speed in bit/s (default: the device's own, else 9600)"),
    OptionSpec("flow", choice(*FLOWS), "none", "host-side handshake: none, rtscts or xonxoff"),
    OptionSpec("speed", choice(*SPEEDS), "real", "real time, or fast: simulated time that jumps while the host waits"),
    OptionSpec("tx_buffer", integer(1), 4096, "host transmit buffer in bytes (a write blocks while it is full)"),
    OptionSpec("out", paper_file, None, "save the device's paper to FILE (.png or .svg) when the host closes the port"),
    OptionSpec("drop_after", integer(0), None, "the link drops after N host bytes: later host operations raise"),
    OptionSpec("stall_after", integer(0), None, "the device stops reading after N bytes: writes block"),
    OptionSpec("corrupt_at", integer(0), None, "host byte number N (from 0) arrives with every bit inverted"),
    OptionSpec("power_loss_after", integer(0), None, _count("the device loses power")),
    OptionSpec("paper_lever_after", integer(0), None, _count("the paper lever is raised")),
    OptionSpec("pause_after", integer(0), None, _count("the pause (VIEW) button is pressed")),
)
"""The transport options of a ``sim://`` URL (and ``pixelpen sim --option``), one spec each."""
TRANSPORT_NAMES: Final = frozenset(spec.name for spec in TRANSPORT_OPTIONS)


def line_baud(device: object, baud: int | None = None) -> int:
    """``baud`` if given, else the device's own ``default_baud``, else DEFAULT_BAUD."""
    return baud if baud is not None else int(getattr(device, "default_baud", DEFAULT_BAUD))


def split_options(options: Mapping[str, str], source: str = "sim") -> tuple[TransportOptions, dict[str, str]]:
    """Split URL options into transport options read against TRANSPORT_OPTIONS and the rest (for the simulator)."""
    values = read_options(TRANSPORT_OPTIONS, {k: v for k, v in options.items() if k in TRANSPORT_NAMES}, source)
    faults = Faults(**{f.name: values[f.name] for f in fields(Faults)})
    transport = TransportOptions(
        baud=values["baud"],
        flow=values["flow"],
        speed=values["speed"],
        tx_buffer=values["tx_buffer"],
        faults=faults,
        out=values["out"],
    )
    return transport, {k: v for k, v in options.items() if k not in TRANSPORT_NAMES}

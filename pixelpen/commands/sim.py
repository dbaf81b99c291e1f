"""The ``sim`` command: run a simulated device on a pty for any program, or replay a raw byte file into it.

``pixelpen sim MODEL --pty`` starts the simulator behind a pseudo-terminal and prints its path (the first
line on stdout), so any plotting program can open it like a serial port; Ctrl-C stops it and the paper is
written (SIGTERM stops it the same way).  The line runs at the device's own speed unless ``baud`` says
otherwise: an EBB is USB CDC (no baud pacing), GRBL 115200, HP plotters 9600.
``pixelpen sim MODEL --replay FILE`` feeds a raw byte file (an HP-GL file, a G-code file, EBB
commands) to the simulator through a :class:`~pixelpen.sim.transports.port.SimPort` at the line's speed, in
simulated time by default, then writes what the paper shows and prints the device's errors and counters.

A replayed file carries no flow control of its own, so the port is paced by the device's own readiness
(the port's RTS/CTS handshake wired to it): an HP-GL plotter takes a byte while its input buffer has room
(``free_bytes``), a GRBL controller while its serial RX buffer has (``rx_free``), any other device while
its handshake line (``ready_to_receive``, the EBB's USB flow control) is high.  The device is therefore
never overrun, whatever the file holds.

``--option KEY=VALUE`` passes simulator options (``paper=a3``, ``pens=black,red``, ``model=se_a3``) and
line options (``baud``, ``flow`` for ``--pty``, ``tx_buffer`` and the faults of ``sim://`` URLs).
"""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
from dataclasses import asdict, dataclass, field, is_dataclass, replace
from pathlib import Path

from pixelpen.clock import REAL_CLOCK, SimulatedClock
from pixelpen.errors import ConfigError, PixelpenError, URLError
from pixelpen.sim.base import Fault, StreamDevice, create_simulator, simulator_models
from pixelpen.sim.transports.options import TransportOptions, line_baud, split_options
from pixelpen.sim.transports.port import LinkStats, SimPort

log = logging.getLogger(__name__)

READY_MARGIN = 2
"""Bytes a paced replay leaves free in a device buffer (a byte may be on the wire when the line is sampled)."""
MAX_SETTLE_S = 24 * 3600.0
"""Simulated seconds a replay waits at most, after its last byte, for the device to finish."""
_ERROR_PREFIXES = ("error:", "alarm:", "!")
"""Reply lines that report errors: GRBL ``error:N`` / ``ALARM:N``, EBB ``!N Err: ...``."""


class PacedDevice:
    """A StreamDevice whose handshake line is high only while the device can take another byte (see module doc)."""

    def __init__(self, device: StreamDevice) -> None:
        self.device = device
        self.model = device.model
        self.clock = device.clock

    @property
    def ready_to_receive(self) -> bool:
        """True while the device's buffer has room beyond READY_MARGIN and its own handshake allows."""
        device = self.device
        for room in ("free_bytes", "rx_free"):
            if hasattr(device, room):
                return getattr(device, room) > READY_MARGIN and device.ready_to_receive
        return device.ready_to_receive

    def receive(self, data: bytes) -> None:
        """Hand host bytes to the device."""
        self.device.receive(data)

    def take_output(self) -> bytes:
        """The device's answers."""
        return self.device.take_output()

    def advance_to(self, t: float) -> None:
        """Run the device up to ``t``."""
        self.device.advance_to(t)

    def next_event_time(self) -> float | None:
        """The device's next event."""
        return self.device.next_event_time()

    def inject(self, fault: Fault | str, at: int | None = None) -> None:
        """Pass a fault on to the device."""
        self.device.inject(fault, at=at)

    def close(self) -> None:
        """Close the device."""
        self.device.close()


@dataclass
class ReplayResult:
    """What a replay did: bytes fed, simulated seconds, the line's counters and the device's replies."""

    bytes_fed: int
    seconds: float
    link: LinkStats
    replies: bytes
    errors: list[str] = field(default_factory=list)


def parse_options(items: list[str] | None) -> dict[str, str]:
    """``KEY=VALUE`` strings as a dict; URLError naming a malformed or repeated one."""
    options: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        key = key.strip().lower()
        if not sep or not key:
            raise URLError(f"option {item!r}: expected KEY=VALUE (for example paper=a3)")
        if key in options:
            raise URLError(f"option {key!r} is given twice")
        options[key] = value.strip()
    return options


def open_simulator(model: str, options: dict[str, str], speed: str) -> tuple[StreamDevice, TransportOptions]:
    """The simulator of ``model`` on a real or simulated clock, and the line options split from ``options``."""
    known = simulator_models()
    if model.lower() not in known:
        raise URLError(f"unknown simulator model {model!r}; known: {', '.join(known)}")
    if "speed" in options:
        raise URLError("give the speed with --speed real|fast, not as an option")
    transport, device_options = split_options(options, f"sim {model}")
    clock = SimulatedClock() if speed == "fast" else REAL_CLOCK
    device = create_simulator(model, clock=clock, **device_options)
    return device, replace(transport, baud=line_baud(device, transport.baud))


def device_errors(device: StreamDevice, replies: bytes) -> list[str]:
    """The errors a device reported: its error log, if it keeps one, and error replies on the wire."""
    errors = [f"t={t:.3f}s {kind} error {code}: {what}" for t, kind, code, what in getattr(device, "error_log", [])]
    for line in replies.decode("ascii", "replace").replace("\r", "\n").split("\n"):
        if line.strip().lower().startswith(_ERROR_PREFIXES):
            errors.append(line.strip())
    return errors


def replay(device: StreamDevice, data: bytes, transport: TransportOptions) -> ReplayResult:
    """Feed ``data`` to ``device`` through a SimPort paced by the device's readiness, then let it finish."""
    port = SimPort(PacedDevice(device), baud=transport.baud, flow="rtscts", faults=transport.faults,
                   tx_buffer=transport.tx_buffer, clock=device.clock)
    clock = port.clock
    start = clock.now()
    replies = bytearray()
    try:
        port.write(data)
        port.drain()
        fed_at = clock.now()
        while (nxt := port.next_event_time()) is not None:
            if nxt - fed_at > MAX_SETTLE_S:
                log.warning("%s: still busy %.0f s after the last byte; stopped waiting", device.model, nxt - fed_at)
                break
            clock.sleep(max(0.0, nxt - clock.now()))
            port.poll()
            replies += port.read(1 << 20, 0.0)
        replies += port.read(1 << 20, 0.0)
        stats = port.stats()
    finally:
        port.close(close_device=False)
    return ReplayResult(len(data), clock.now() - start, stats, bytes(replies), device_errors(device, bytes(replies)))


def _stop_on_sigterm(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def run_pty(device: StreamDevice, transport: TransportOptions, stop: threading.Event | None = None) -> None:
    """Serve ``device`` on a pty (path printed on stdout) until Ctrl-C, SIGTERM or ``stop`` is set."""
    from pixelpen.sim.transports.pty import PtyBridge

    with PtyBridge(device, flow=transport.flow, baud=transport.baud, faults=transport.faults,
                   tx_buffer=transport.tx_buffer, clock=device.clock, out=transport.out) as bridge:
        print(bridge.path, flush=True)
        print(f"pixelpen sim: {device.model} on {bridge.path} ({bridge.port.baud} baud, flow {transport.flow}); "
              "press Ctrl-C to stop", file=sys.stderr, flush=True)
        waiter = stop if stop is not None else threading.Event()
        main = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGTERM, _stop_on_sigterm) if main else None
        try:
            while not waiter.wait(0.2):
                if not bridge.running:
                    raise PixelpenError(f"the pty bridge stopped: {bridge.error}")
        except KeyboardInterrupt:
            print("pixelpen sim: stopped", file=sys.stderr)
        finally:
            if main:
                signal.signal(signal.SIGTERM, previous)


def _counters(device: StreamDevice) -> str:
    """The device's ``stats`` counters as ``name=value`` text ("none" for a device without them)."""
    stats = getattr(device, "stats", None)
    if not is_dataclass(stats) or isinstance(stats, type):
        return "none"
    return ", ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}" for k, v in asdict(stats).items())


def run_sim(args: argparse.Namespace) -> int:
    """The ``sim`` command's work (see the module docstring)."""
    if args.pty == (args.replay is not None):
        raise ConfigError("give either --pty or --replay FILE")
    speed = args.speed or ("fast" if args.replay is not None else "real")
    device, transport = open_simulator(args.model, parse_options(args.option), speed)
    try:
        if args.pty:
            run_pty(device, transport)
        else:
            try:
                data = Path(args.replay).read_bytes()
            except OSError as exc:
                raise ConfigError(f"cannot read {args.replay}: {exc.strerror or exc}") from None
            result = replay(device, data, transport)
            link = result.link
            print(f"replayed {result.bytes_fed} bytes of {args.replay} into {device.model} in "
                  f"{result.seconds:.2f} s {'simulated' if speed == 'fast' else 'real'} time "
                  f"({transport.baud} baud, paced by the device's readiness)")
            print(f"line: {link.bytes_sent} bytes sent, {link.bytes_received} received, "
                  f"busy {100 * link.utilisation:.1f} %, held off {link.held_off:.2f} s")
            print(f"device counters: {_counters(device)}")
            print(f"errors: {len(result.errors)}" + "".join(f"\n  {e}" for e in result.errors))
    finally:
        device.close()
    device.save_paper(args.output)  # type: ignore[attr-defined]
    print(f"paper: {args.output}")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``pixelpen sim`` to the ``pixelpen`` parser."""
    p = subparsers.add_parser(
        "sim", help="run a simulated device on a pty, or replay a byte file into it, and save its paper",
        description="Run the simulator of MODEL on a pseudo-terminal (--pty) for any program to open, or feed "
                    "it a raw byte file (--replay), then write the paper as an image.")
    p.add_argument("model", metavar="MODEL", help="simulator model (hp7475a, hp7550a, hp7440a, grbl, axidraw, ebb)")
    p.add_argument("--pty", action="store_true", help="serve the device on a pty until Ctrl-C; prints the path")
    p.add_argument("--replay", metavar="FILE", help="feed this raw byte file (HP-GL, G-code, EBB commands)")
    p.add_argument("-o", "--output", default="paper.png", metavar="PAPER.png",
                   help="paper to write at the end: PNG, or SVG by the extension (default paper.png)")
    p.add_argument("--speed", choices=("real", "fast"), default=None,
                   help="real time, or simulated time (default: fast for --replay, real for --pty)")
    p.add_argument("--option", action="append", metavar="KEY=VALUE",
                   help="simulator or line option, e.g. paper=a3, baud=19200, flow=xonxoff (repeatable)")
    p.set_defaults(func=run_sim)

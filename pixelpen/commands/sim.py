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

``--view`` also serves a live web page (:mod:`pixelpen.sim.view`) of the paper as it is drawn, with the device's
counters, on 127.0.0.1 (``--host``/``--port``; another host only when given explicitly) and prints its URL
on stdout (after the pty path with ``--pty``); with ``--replay`` the page stays up after the replay until
Ctrl-C.  A panel simulator (``pixelpen sim st7789 --view``, also ``sim fbdev``) has no byte stream: when
its model is a display scheme, a demo (the reference scene, then :class:`~pixelpen.animation.PanelAnimation`)
is drawn through the real display ``sim:MODEL`` (the ``--option`` values go into that URL) and the page shows
the glass of the simulator behind it; a panel simulator without a display is shown as it is.  The glass is
written at the end (``glass.png``).  The pty bridge, the replay, the demo and the page share one lock
around the device (:class:`GuardedDevice`).

``--option KEY=VALUE`` passes simulator options (``paper=a3``, ``pens=black,red``, ``model=se_a3``) and
line options (``baud``, ``flow`` for ``--pty``, ``tx_buffer`` and the faults of ``sim://`` URLs).
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field, is_dataclass, replace
from pathlib import Path
from typing import Any

from pixelpen.animation import PanelAnimation
from pixelpen.clock import REAL_CLOCK, SimulatedClock
from pixelpen.commands import argtypes
from pixelpen.display.kinds import RasterDisplay
from pixelpen.display.registry import open_display, scheme_names
from pixelpen.errors import ConfigError, PixelpenError, URLError
from pixelpen.options import integer
from pixelpen.scene import show_reference
from pixelpen.sim.base import Fault, StreamDevice, create_simulator, is_stream_device, reached_through, simulator_models
from pixelpen.sim.transports.options import TransportOptions, line_baud, split_options
from pixelpen.sim.transports.port import LinkStats, SimPort
from pixelpen.sim.view import MAX_FPS, ViewServer, source_for
from pixelpen.urls import format_url

log = logging.getLogger(__name__)

READY_MARGIN = 2
"""Bytes a paced replay leaves free in a device buffer (a byte may be on the wire when the line is sampled)."""
DEMO_FPS = 25.0
"""Frames a second of the panel demo (wall time; the live view shows at most its own --fps of them)."""
MAX_SETTLE_S = 24 * 3600.0
"""Simulated seconds a replay waits at most, after its last byte, for the device to finish."""
_ERROR_PREFIXES = ("error:", "alarm:", "!")
"""Reply lines that report errors: GRBL ``error:N`` / ``ALARM:N``, EBB ``!N Err: ...``."""


class GuardedDevice:
    """A StreamDevice whose every call holds ``lock``, so the live view can look at it from another thread."""

    def __init__(self, device: StreamDevice, lock: threading.Lock | threading.RLock | None = None) -> None:
        self.device = device
        self.model = device.model
        self.clock = device.clock
        self.lock = lock if lock is not None else threading.Lock()
        self.resets_on_dtr = bool(getattr(device, "resets_on_dtr", False))
        """An Arduino's board reboots when a program opens the port (the pty bridge reads this)."""

    @property
    def ready_to_receive(self) -> bool:
        """The device's handshake line."""
        with self.lock:
            return self.device.ready_to_receive

    def receive(self, data: bytes) -> None:
        """Hand host bytes to the device."""
        with self.lock:
            self.device.receive(data)

    def take_output(self) -> bytes:
        """The device's answers."""
        with self.lock:
            return self.device.take_output()

    def advance_to(self, t: float) -> None:
        """Run the device up to ``t``."""
        with self.lock:
            self.device.advance_to(t)

    def next_event_time(self) -> float | None:
        """The device's next event."""
        with self.lock:
            return self.device.next_event_time()

    def inject(self, fault: Fault | str, at: int | None = None) -> None:
        """Pass a fault on to the device."""
        with self.lock:
            self.device.inject(fault, at=at)

    def close(self) -> None:
        """Close the device."""
        with self.lock:
            self.device.close()

    def save_paper(self, path: str | Path) -> None:
        """Write the device's paper (``out=`` of the line)."""
        with self.lock:
            self.device.save_paper(path)  # type: ignore[attr-defined]


class PacedDevice(GuardedDevice):
    """A guarded device whose handshake line is high only while it can take another byte (see module doc)."""

    @property
    def ready_to_receive(self) -> bool:
        """True while the device's buffer has room beyond READY_MARGIN and its own handshake allows."""
        with self.lock:
            device = self.device
            for room in ("free_bytes", "rx_free"):
                if hasattr(device, room):
                    return getattr(device, room) > READY_MARGIN and device.ready_to_receive
            return device.ready_to_receive


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


def replay(device: StreamDevice, data: bytes, transport: TransportOptions,
           lock: threading.Lock | None = None) -> ReplayResult:
    """Feed ``data`` to ``device`` through a SimPort paced by its readiness (``lock`` held per call); let it finish."""
    port = SimPort(PacedDevice(device, lock), baud=transport.baud, flow="rtscts", faults=transport.faults,
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


@contextlib.contextmanager
def sigterm_stops() -> Iterator[None]:
    """SIGTERM raises KeyboardInterrupt meanwhile (in the main thread), so a service manager stops it like Ctrl-C."""
    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _stop_on_sigterm) if main else None
    try:
        yield
    finally:
        if main:
            signal.signal(signal.SIGTERM, previous)


def wait_for_stop(stop: threading.Event | None = None, check: Callable[[], None] | None = None) -> None:
    """Block until Ctrl-C, SIGTERM or ``stop`` is set; ``check`` runs every 0.2 s (it raises to end early)."""
    waiter = stop if stop is not None else threading.Event()
    with sigterm_stops():
        try:
            while not waiter.wait(0.2):
                if check is not None:
                    check()
        except KeyboardInterrupt:
            print("pixelpen sim: stopped", file=sys.stderr)


def run_pty(device: StreamDevice, transport: TransportOptions, stop: threading.Event | None = None,
            lock: threading.Lock | None = None, view: ViewServer | None = None) -> None:
    """Serve ``device`` on a pty (``lock`` held per call), printing its path, until Ctrl-C, SIGTERM or ``stop``."""
    from pixelpen.sim.transports.pty import PtyBridge

    with PtyBridge(GuardedDevice(device, lock), flow=transport.flow, baud=transport.baud, faults=transport.faults,
                   tx_buffer=transport.tx_buffer, clock=device.clock, out=transport.out) as bridge:
        print(bridge.path, flush=True)
        if view is not None:
            print(view.url, flush=True)
        print(f"pixelpen sim: {device.model} on {bridge.path} ({bridge.port.baud} baud, flow {transport.flow})"
              + (f", live view on {view.url}" if view is not None else "") + "; press Ctrl-C to stop",
              file=sys.stderr, flush=True)

        def check() -> None:
            if not bridge.running:
                raise PixelpenError(f"the pty bridge stopped: {bridge.error}")

        wait_for_stop(stop, check)


def start_view(device: object, args: argparse.Namespace, lock: threading.Lock) -> ViewServer:
    """The live view of ``device`` on ``--host``/``--port`` (a remote host only when given explicitly), serving."""
    host = args.host if args.host is not None else "127.0.0.1"
    return ViewServer(source_for(device, lock=lock), host=host, port=args.port, allow_remote=args.host is not None,
                      max_fps=args.fps).start()


def _counters(device: StreamDevice) -> str:
    """The device's ``stats`` counters as ``name=value`` text ("none" for a device without them)."""
    stats = getattr(device, "stats", None)
    if not is_dataclass(stats) or isinstance(stats, type):
        return "none"
    return ", ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}" for k, v in asdict(stats).items())


def run_panel_demo(display: RasterDisplay, lock: threading.Lock, stop: threading.Event, fps: float = DEMO_FPS) -> None:
    """The reference scene, then the PanelAnimation at ``fps`` frames a second of wall time until ``stop``."""
    with lock:
        show_reference(display)
        demo = PanelAnimation(display)
    while not stop.wait(1.0 / fps):
        with lock:
            demo.step()


def _open_simulated_display(model: str, options: dict[str, str]) -> RasterDisplay:
    """The raster display ``sim:MODEL?options`` with its simulator (``display.simulator``) behind its bus."""
    display = open_display(format_url("sim", model, options))
    if not isinstance(display, RasterDisplay) or getattr(display, "simulator", None) is None:
        display.close()
        raise ConfigError(f"sim:{model} is not a raster display with a simulator behind it")
    return display


def _report_replay(result: ReplayResult, device: StreamDevice, name: str, baud: int | None, speed: str) -> None:
    """Print what a replay did: bytes and time, the line's counters, the device's counters and errors."""
    link = result.link
    print(f"replayed {result.bytes_fed} bytes of {name} into {device.model} in "
          f"{result.seconds:.2f} s {'simulated' if speed == 'fast' else 'real'} time "
          f"({baud} baud, paced by the device's readiness)")
    print(f"line: {link.bytes_sent} bytes sent, {link.bytes_received} received, "
          f"busy {100 * link.utilisation:.1f} %, held off {link.held_off:.2f} s")
    print(f"device counters: {_counters(device)}")
    print(f"errors: {len(result.errors)}" + "".join(f"\n  {e}" for e in result.errors))


def _is_panel(device: object) -> bool:
    """True for a panel simulator (it shows a glass and is reached through a bus, not a byte stream)."""
    return callable(getattr(device, "glass", None))


def run_sim(args: argparse.Namespace) -> int:
    """The ``sim`` command's work (see the module docstring)."""
    if args.pty and args.replay is not None:
        raise ConfigError("give either --pty or --replay FILE")
    if not (args.pty or args.replay is not None or args.view):
        raise ConfigError("give --pty, --replay FILE or --view")
    speed = args.speed or ("fast" if args.replay is not None else "real")
    device, transport = open_simulator(args.model, parse_options(args.option), speed)
    if not is_stream_device(device) and not _is_panel(device):
        device.close()
        raise ConfigError(f"{device.model} is reached through {reached_through(device)}: `pixelpen sim` serves "
                          "byte-stream and panel simulators")
    panel = _is_panel(device)
    if panel and (args.pty or args.replay is not None):
        device.close()
        raise ConfigError(f"{device.model} is a panel: it is reached through a bus, not a byte stream; "
                          "watch it with --view")
    data = None
    if args.replay is not None:
        try:
            data = Path(args.replay).read_bytes()
        except OSError as exc:
            device.close()
            raise ConfigError(f"cannot read {args.replay}: {exc.strerror or exc}") from None
    lock = threading.Lock()
    view = None
    display: RasterDisplay | None = None
    stop = threading.Event()
    animator = None
    shown: Any = device
    """What the view shows and the glass or paper comes from: the panel display's simulator in the demo."""
    try:
        if panel and args.model.lower() in scheme_names():
            device.close()
            display = _open_simulated_display(args.model, parse_options(args.option))
            shown = display.simulator  # type: ignore[attr-defined]
            animator = threading.Thread(target=run_panel_demo, args=(display, lock, stop), name="panel-demo",
                                        daemon=True)
        if args.view:
            view = start_view(shown, args, lock)
            if not args.pty:
                print(view.url, flush=True)
                print(f"pixelpen sim: live view of {shown.model} on {view.url}"
                      + (f" (a demo drawn through the display sim:{args.model})" if display is not None else "")
                      + "; press Ctrl-C to stop", file=sys.stderr, flush=True)
        if animator is not None:
            animator.start()
        if args.pty:
            run_pty(device, transport, lock=lock, view=view)
        elif data is not None:
            try:
                with sigterm_stops():
                    result = replay(device, data, transport, lock)
            except KeyboardInterrupt:
                print("pixelpen sim: replay stopped", file=sys.stderr)
            else:
                _report_replay(result, device, args.replay, transport.baud, speed)
                if view is not None:
                    sys.stdout.flush()
                    wait_for_stop()
        else:
            wait_for_stop()
    finally:
        stop.set()
        if animator is not None and animator.is_alive():
            animator.join(10)
        if view is not None:
            view.close()
        with lock:
            if display is not None:
                display.close()
            shown.close()
    output = args.output or ("glass.png" if panel else "paper.png")
    if panel:
        shown.glass().save(output)
        print(f"glass: {output}")
    else:
        shown.save_paper(output)
        print(f"paper: {output}")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``pixelpen sim`` to the ``pixelpen`` parser."""
    p = subparsers.add_parser(
        "sim", help="run a simulated device on a pty, replay a byte file into it, or watch it live; save its paper",
        description="Run the simulator of MODEL on a pseudo-terminal (--pty) for any program to open, or feed "
                    "it a raw byte file (--replay), and/or watch it live in a web browser (--view; a panel "
                    "shows a demo drawn through its display), then write the paper or glass as an image.")
    p.add_argument("model", metavar="MODEL",
                   help="simulator model (hp7475a, hp7550a, hp7440a, grbl, axidraw, ebb; panels: ssd1306, st7789, ...)")
    p.add_argument("--pty", action="store_true", help="serve the device on a pty until Ctrl-C; prints the path")
    p.add_argument("--replay", metavar="FILE", help="feed this raw byte file (HP-GL, G-code, EBB commands)")
    p.add_argument("--view", action="store_true",
                   help="also serve a live web page of the paper (a panel: its glass) and counters; prints its URL")
    p.add_argument("--host", default=None, metavar="ADDRESS",
                   help="address the live view listens on (default 127.0.0.1; another one opens it to the network)")
    p.add_argument("--port", type=argtypes.argtype(integer(0, 65535)), default=0, metavar="N",
                   help="port of the live view (default: any free port)")
    p.add_argument("--fps", type=argtypes.positive, default=MAX_FPS, metavar="N",
                   help=f"frames the live view encodes a second at most (default {MAX_FPS:g})")
    p.add_argument("-o", "--output", default=None, metavar="PAPER.png",
                   help="paper (or glass) to write at the end: PNG, or SVG by the extension for paper "
                        "(default paper.png; glass.png for a panel)")
    p.add_argument("--speed", choices=("real", "fast"), default=None,
                   help="real time, or simulated time (default: fast for --replay, real for --pty)")
    p.add_argument("--option", action="append", metavar="KEY=VALUE",
                   help="simulator or line option, e.g. paper=a3, baud=19200, flow=xonxoff (repeatable)")
    p.set_defaults(func=run_sim)

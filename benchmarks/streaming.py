"""Streaming benchmark: how well each flow control keeps a simulated plotter's link busy and its mechanism fed.

Run by hand: ``python3 benchmarks/streaming.py [--segments N] [--strokes K] [--devices hp7475a grbl axidraw]
[--quick]``.
Every run is a real driver plotting through the ``sim://`` transport (a SimPort at the device's real line
speed: 9600 baud for the HP 7475A, 115200 for GRBL, USB full speed for the EBB) on a simulated clock, so
minutes of plotting take seconds; the naive baseline sends the same commands one at a time and waits for a
reply to each.  Two drawings per device:

* **link-bound**: a spiral of ``--segments`` (10,000) segments in ``--strokes`` (1) strokes, the segments
  short enough that the mechanism draws them faster than the line can carry them (HP-GL 0.25 mm, G-code
  0.05 mm, EBB 0.25 mm): what counts is the link *utilisation* - host bytes on the wire per second over
  the link's capacity (``SimPort.stats()``: busy time / elapsed time while plotting) - and the plot time;
* **device-bound**: ``--segments / 5`` segments of 3 mm, slower to draw than to send: what counts is whether
  the device ever *starved* (stood idle with nothing complete to execute, its own ``stats.starved_time``)
  while the host still had data.

Columns: mode, link utilisation and plot time on the link-bound spiral, the ideal time (bytes / capacity),
and the device's starved seconds on the device-bound spiral.  Goal: >= 95 % utilisation for GRBL character
counting and for HP-GL ESC.B polling at 9600 baud.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import pixelpen
from pixelpen.clock import SimulatedClock
from pixelpen.sim.base import create_simulator, forget_simulator, named_simulator
from pixelpen.sim.transports.port import SimPort
from pixelpen.vector.displaylist import DisplayList

USB_BAUD = 12_000_000
"""USB full speed (12 Mbit/s) as a byte rate of 1.2 MB/s: the EBB's CDC link is never slow."""
LINK_BOUND_MM = {"hp7475a": 0.25, "grbl": 0.05, "axidraw": 0.25}
DEVICE_BOUND_MM = 3.0


@dataclass
class Run:
    """One plot's figures."""

    utilisation: float = float("nan")
    seconds: float = float("nan")
    ideal: float = float("nan")
    starved: float = float("nan")
    bytes_sent: int = 0


def spiral(segments: int, step_mm: float, strokes: int = 20, centre=(110.0, 100.0), r_in: float = 10.0,
           r_out: float = 80.0) -> list[np.ndarray]:
    """An Archimedean spiral (mm, y up) of ``segments`` equal segments of ``step_mm``, cut into ``strokes``."""
    length = segments * step_mm
    pitch = np.pi * (r_out**2 - r_in**2) / length  # mm between turns, so that the spiral is ``length`` long
    turns = (r_out - r_in) / pitch
    theta = np.linspace(0.0, 2 * np.pi * turns, 200 * int(np.ceil(turns)) + 2000)
    r = r_in + pitch * theta / (2 * np.pi)
    fine = np.column_stack([centre[0] + r * np.cos(theta), centre[1] + r * np.sin(theta)])
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(fine, axis=0).T))])
    at = np.linspace(0.0, segments * step_mm, segments + 1)
    at = at[at <= s[-1]]
    pts = np.column_stack([np.interp(at, s, fine[:, 0]), np.interp(at, s, fine[:, 1])])
    bounds = np.linspace(0, len(pts) - 1, strokes + 1).astype(int)
    return [pts[a : b + 1] for a, b in itertools.pairwise(bounds)]


def drawing(display, polylines_mm: list[np.ndarray]) -> DisplayList:
    """The polylines (world mm) in the display's device units, through its viewing pipeline."""
    pipe = display.pipeline
    return DisplayList.from_polylines([pipe.to_device(p) for p in polylines_mm], unit_mm=display.capabilities.unit_mm)


def driver_run(model: str, options: dict[str, str], polylines: list[np.ndarray], prime: bool
               ) -> tuple[Run, list[str], int]:
    """Plot with the driver; the figures over the plot, the commands the device executed and how many came first.

    With ``prime`` a dot at the drawing's start is plotted first and not measured, so the pen pick-up and
    the first travel do not count against the link (not for starvation: the pause between the two plots,
    when the host has no data, would count as the device starving).
    """
    ident = f"bench-{uuid.uuid4().hex[:8]}"
    query = "&".join(f"{k}={v}" for k, v in {"speed": "fast", "id": ident, **options}.items())
    try:
        with pixelpen.open(f"sim:{model}?{query}") as display:
            dl = drawing(display, polylines)
            if prime:
                display.plot(DisplayList.from_polylines([dl.points[:1]], unit_mm=dl.unit_mm))
            port: SimPort = display.link.port.sim_port
            device = named_simulator(ident)
            primed = len(_log(device))
            s0, starved0 = port.stats(), device.stats.starved_time
            display.plot(dl)
            s1, starved1 = port.stats(), device.stats.starved_time
            done = len(_log(device))  # the safe stop when the display closes is not measured
        return _figures(port, s0, s1, starved1 - starved0), _log(device)[:done], primed
    finally:
        forget_simulator(ident)


def _log(device) -> list[str]:
    log = getattr(device, "command_log", None)
    return [text for _, text in (log if log is not None else device.log)]


def _figures(port: SimPort, s0, s1, starved: float) -> Run:
    busy, elapsed, sent = s1.tx_busy - s0.tx_busy, s1.elapsed - s0.elapsed, s1.bytes_sent - s0.bytes_sent
    return Run(busy / elapsed if elapsed > 0 else 0.0, elapsed, sent * 10.0 / port.baud, starved, sent)


def naive_run(model: str, baud: int, commands: list[bytes], primed: int, reply_end: bytes) -> Run:
    """Send each command, wait for the reply ending in ``reply_end``, then send the next; measure after ``primed``."""
    device = create_simulator(model, clock=SimulatedClock())
    port = SimPort(device, baud=baud, clock=device.clock)
    s0, starved0 = port.stats(), device.stats.starved_time
    for k, command in enumerate(commands):
        if k == primed:
            s0, starved0 = port.stats(), device.stats.starved_time
        port.write(command)
        answer = b""
        while not answer.endswith(reply_end):
            chunk = port.read(256, timeout=60.0)
            if not chunk:
                raise RuntimeError(f"{model}: no reply to {command!r}")
            answer += chunk
    s1, starved1 = port.stats(), device.stats.starved_time
    port.close()
    return _figures(port, s0, s1, starved1 - starved0)


def hpgl_naive(log: list[str], primed: int) -> tuple[list[bytes], int]:
    """The HP-GL instructions the device executed, each followed by ``OA;`` (answered once it has run)."""
    keep = [(i, t) for i, t in enumerate(log) if not t.startswith("ESC") and t[:2] not in ("OA", "OE", "OI", "OS")]
    return [f"{t};OA;".encode() for _, t in keep], sum(1 for i, _ in keep if i < primed)


def ebb_naive(log: list[str], primed: int) -> tuple[list[bytes], int]:
    """The EBB motion, pen and set-up commands the device executed (each answered ``OK``)."""
    keep = [(i, t) for i, t in enumerate(log) if t[:2] in ("SM", "XM", "LM", "SP", "EM", "SC")]
    return [f"{t}\r".encode() for _, t in keep], sum(1 for i, _ in keep if i < primed)


@dataclass
class Mode:
    """A flow-control mode of one device: driver URL options, or a naive replay of another mode's commands."""

    model: str
    name: str
    options: dict[str, str] | None
    naive: Callable[[list[str], int], tuple[list[bytes], int]] | None = None
    reply_end: bytes = b""
    baud: int = 9600


MODES = [
    Mode("hp7475a", "ESC.B polling", {"handshake": "escb"}),
    Mode("hp7475a", "XON/XOFF", {"handshake": "xonxoff"}),
    Mode("hp7475a", "hardwire (DTR/CTS)", {"handshake": "hardwire"}),
    Mode("hp7475a", "naive: instruction, OA, wait", None, hpgl_naive, b"\r", 9600),
    Mode("grbl", "character counting", {"stream": "counting"}),
    Mode("grbl", "naive: send and wait for ok", {"stream": "wait"}),
    Mode("axidraw", "reply per command, 4 ahead", {"baud": str(USB_BAUD)}),
    Mode("axidraw", "naive: command, wait for OK", None, ebb_naive, b"OK\r\n", USB_BAUD),
]


def run_mode(mode: Mode, fast: list[np.ndarray], slow: list[np.ndarray], logs: dict[str, tuple[list[str], int]]
             ) -> Run:
    """One mode on both drawings: utilisation from the link-bound one, starvation from the device-bound one.

    Driver modes record the device's commands in ``logs`` (the first one of a device), for its naive mode.
    """
    if mode.options is not None:
        link, *fast_log = driver_run(mode.model, mode.options, fast, prime=True)
        dev, *slow_log = driver_run(mode.model, mode.options, slow, prime=False)
        logs.setdefault("fast", tuple(fast_log))  # type: ignore[arg-type]
        logs.setdefault("slow", tuple(slow_log))  # type: ignore[arg-type]
        link.starved = dev.starved
        return link
    assert mode.naive is not None
    link = naive_run(mode.model, mode.baud, *mode.naive(*logs["fast"]), mode.reply_end)
    link.starved = naive_run(mode.model, mode.baud, *mode.naive(*logs["slow"]), mode.reply_end).starved
    return link


def main(argv: list[str] | None = None) -> int:
    """Run every mode on both drawings and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--segments", type=int, default=10_000, help="segments of the link-bound spiral")
    ap.add_argument("--devices", nargs="+", default=["hp7475a", "grbl", "axidraw"])
    ap.add_argument("--strokes", type=int, default=1, help="strokes the link-bound spiral is cut into (default 1)")
    ap.add_argument("--quick", action="store_true", help="1,000 segments (a smoke run)")
    args = ap.parse_args(argv)
    n = 1000 if args.quick else args.segments
    print(f"{'device':9} {'mode':32} {'util %':>7} {'plot s':>8} {'ideal s':>8} {'bytes':>8} "
          f"{'starved s (device-bound)':>25} {'wall s':>7}")
    for model in args.devices:
        fast = spiral(n, LINK_BOUND_MM[model], strokes=args.strokes)
        slow = spiral(max(n // 5, 20), DEVICE_BOUND_MM, strokes=20)
        logs: dict[str, tuple[list[str], int]] = {}
        for mode in (m for m in MODES if m.model == model):
            t0 = time.perf_counter()
            try:
                link = run_mode(mode, fast, slow, logs)
            except Exception as exc:  # noqa: BLE001 - one failing mode must not hide the others
                print(f"{model:9} {mode.name:32} failed: {type(exc).__name__}: {exc}", flush=True)
                continue
            print(f"{model:9} {mode.name:32} {100 * link.utilisation:7.1f} {link.seconds:8.1f} {link.ideal:8.1f} "
                  f"{link.bytes_sent:8d} {link.starved:25.3f} {time.perf_counter() - t0:7.1f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""HID benchmark: hid-tools against pixelpen on the same descriptors and reports, in one process.

Run: ``python3 benchmarks/hid.py [--reports N] [--batch N] [--repeat N] [--latency N]`` (``--tiny`` for a smoke run,
``--parse-only`` for the parse columns alone).

Descriptors: the simulators' (``pixelpen.sim.hid.descriptors``, 49–200 bytes) and a composite one of about
2.3 KB composed here (a ten-finger touch screen, a pen, a mouse, a keyboard, consumer keys and a vendor page
of many feature and input reports — the shape of a convertible laptop's I²C HID panel).  Reports: what the
simulators send for their default scripts (``create_simulator`` on a simulated clock), and for the
composite seeded random bytes behind each input report ID.

Measured (hid-tools is GPL-2.0 and only an oracle here; pixelpen never imports it):

* parse: ``hidtools.hid.ReportDescriptor.from_bytes`` against ``parse_descriptor`` followed by a read of every
  report's length and field list and of each field's usages, offset and range (all that hid-tools builds), and
  that with every input decoder compiled as well; per call, the best of ``--repeat`` samples of about 1 ms
  each, the three taken in turn (:func:`parse_times`, which ``--parse-only`` prints alone);
* per report: hid-tools ``rdesc.get(id, len)`` and ``get_values`` of each field, against pixelpen's
  ``descriptor.decode(report)`` (ID dispatch included) and a report's own compiled ``decoder(...).decode``;
* batch: ``decode_batch`` of an (N, length) uint8 array per report ID;
* latency: each simulator recorded at 1000 Hz into a hid-recorder file, read back, replayed by
  ``replay_device`` behind the hidapi module fake and read by the real ``HidapiLink``; per report the time
  of ``semantics_for(...).feed`` alone and of ``read_report`` + ``feed`` (p50, p99, max).

Goals (issue 11, Speed): parse >= 10x hid-tools, >= 400,000 reports/s per report, >= 10 M reports/s batched,
report-to-event latency p99 < 1 ms at 1 kHz replay.
"""

from __future__ import annotations

import argparse
import io
import random
import statistics
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pixelpen.clock import SimulatedClock
from pixelpen.devices.hid import parse_descriptor
from pixelpen.devices.hid.fields import ReportDescriptor, ReportKind
from pixelpen.devices.hid.semantics import semantics_for
from pixelpen.drivers.hidapi import open_hid
from pixelpen.drivers.recordings.hidrecorder import HidRecording, read_hid_recording, write_hid_recording
from pixelpen.sim.base import create_simulator
from pixelpen.sim.hid import descriptors
from pixelpen.sim.hid.replay import replay_device
from pixelpen.sim.transports.hidapi import SimHidapi

SEED = 20261202
PARSE_GOAL = 10.0
REPORTS_GOAL = 400_000.0
BATCH_GOAL = 10e6
LATENCY_GOAL_S = 1e-3
LATENCY_HZ = "1000"

MODELS = {  # descriptor name -> the simulator sending its reports, with its options
    "BOOT_MOUSE": ("mouse", {}), "TRACKBALL": ("trackball", {}), "JOYSTICK": ("joystick", {}),
    "GAMEPAD": ("gamepad", {}), "PEN_TABLET": ("tablet", {}), "TOUCHSCREEN": ("touchscreen", {}),
    "BOOT_KEYBOARD": ("keyboard", {"script": "typing:the quick brown fox jumps over the lazy dog"}),
    "NKRO_KEYBOARD": ("keyboard", {"protocol": "nkro", "script": "typing:the quick brown fox jumps over the dog"}),
}


# ---- the composite descriptor -----------------------------------------------------------------------------

def item(prefix: int, value: int | None = None, size: int | None = None) -> bytes:
    """One short item (HID 1.11 §6.2.2.2): ``prefix`` with its size bits 0, the value in the fewest bytes."""
    if value is None:
        return bytes([prefix])
    if size is None:
        size = next(n for n in (1, 2, 4) if -(1 << (8 * n - 1)) <= value < (1 << (8 * n)))
    code = {1: 1, 2: 2, 4: 3}[size]
    return bytes([prefix | code]) + (value & ((1 << (8 * size)) - 1)).to_bytes(size, "little")


def signed(prefix: int, value: int) -> bytes:
    """A Logical/Physical Minimum or Maximum: the fewest bytes holding ``value`` as two's complement."""
    size = next(n for n in (1, 2, 4) if -(1 << (8 * n - 1)) <= value < (1 << (8 * n - 1)))
    return item(prefix, value, size)


PAGE, USAGE, UMIN, UMAX, LMIN, LMAX, PMIN, PMAX, UEXP, UNIT, RSIZE, RID, RCOUNT = (
    0x04, 0x08, 0x18, 0x28, 0x14, 0x24, 0x34, 0x44, 0x54, 0x64, 0x74, 0x84, 0x94)
INPUT, OUTPUT, FEATURE, COLLECTION, END = 0x80, 0x90, 0xB0, 0xA0, 0xC0


def field(usages: Sequence[int], lmin: int, lmax: int, size: int, count: int | None = None,
          main: int = INPUT, flags: int = 0x02) -> bytes:
    """Usages, logical range, size and count, then the Main item (Data, Variable, Absolute by default)."""
    out = b"".join(item(USAGE, u) for u in usages)
    return out + signed(LMIN, lmin) + signed(LMAX, lmax) + item(RSIZE, size) + item(
        RCOUNT, count if count is not None else len(usages)) + item(main, flags)


def finger() -> bytes:
    """One contact of a Microsoft-style multi-touch report: tip, confidence, ID, X, Y, width, height, azimuth."""
    return b"".join([
        item(PAGE, 0x0D), item(USAGE, 0x22), item(COLLECTION, 0x02),  # Finger, logical
        field([0x42, 0x47], 0, 1, 1), field([], 0, 1, 6, 1, flags=0x03),  # Tip Switch, Confidence, padding
        field([0x51], 0, 127, 8),  # Contact Identifier
        item(PAGE, 0x01), signed(PMIN, 0), signed(PMAX, 2940), item(UNIT, 0x11), item(UEXP, 0x0E),
        field([0x30], 0, 29400, 16), signed(PMAX, 1650), field([0x31], 0, 16500, 16),
        item(PAGE, 0x0D), item(UNIT, 0), item(UEXP, 0), signed(PMAX, 0),
        field([0x48, 0x49], 0, 4095, 16),  # Width, Height
        field([0x3F], 0, 62831, 16),  # Azimuth (centiradians)
        item(END),
    ])


def composite_descriptor() -> bytes:
    """About 2.3 KB: touch screen (10 fingers), pen, mouse, keyboard, consumer keys, a vendor page."""
    parts = [
        item(PAGE, 0x0D), item(USAGE, 0x04), item(COLLECTION, 0x01), item(RID, 1),
        *[finger() for _ in range(10)],
        item(PAGE, 0x0D), field([0x56], 0, 65535, 16), field([0x54], 0, 10, 8),  # Scan Time, Contact Count
        item(RID, 2), field([0x55], 0, 10, 8, main=FEATURE),  # Contact Count Maximum
        item(RID, 3), item(USAGE, 0x0E), item(COLLECTION, 0x02),  # Device Configuration / Device Mode
        field([0x52, 0x53], 0, 10, 8, main=FEATURE), item(END),
        item(END),
        item(PAGE, 0x0D), item(USAGE, 0x02), item(COLLECTION, 0x01), item(RID, 4),  # Pen
        item(USAGE, 0x20), item(COLLECTION, 0x00),  # Stylus
        field([0x42, 0x44, 0x45, 0x3C, 0x32, 0x5A], 0, 1, 1), field([], 0, 1, 2, 1, flags=0x03),
        item(PAGE, 0x01), signed(PMAX, 2940), item(UNIT, 0x11), item(UEXP, 0x0E),
        field([0x30], 0, 29400, 16), signed(PMAX, 1650), field([0x31], 0, 16500, 16),
        item(PAGE, 0x0D), item(UNIT, 0), item(UEXP, 0), signed(PMAX, 0), field([0x30], 0, 4095, 16),
        signed(PMIN, -9000), signed(PMAX, 9000), item(UNIT, 0x14), item(UEXP, 0x0E),
        field([0x3D, 0x3E], -9000, 9000, 16), item(UNIT, 0), item(UEXP, 0), signed(PMIN, 0), signed(PMAX, 0),
        field([0x5B], 0, 0x7FFFFFFF, 32),  # Transducer Serial Number
        item(END), item(END),
        item(PAGE, 0x01), item(USAGE, 0x02), item(COLLECTION, 0x01), item(RID, 5),  # Mouse
        item(USAGE, 0x01), item(COLLECTION, 0x00), item(PAGE, 0x09), item(UMIN, 1), item(UMAX, 5),
        signed(LMIN, 0), signed(LMAX, 1), item(RSIZE, 1), item(RCOUNT, 5), item(INPUT, 0x02),
        item(RCOUNT, 1), item(RSIZE, 3), item(INPUT, 0x03), item(PAGE, 0x01),
        field([0x30, 0x31], -32767, 32767, 16, flags=0x06), field([0x38], -127, 127, 8, flags=0x06),
        item(PAGE, 0x0C), item(USAGE, 0x238, 2), field([], -127, 127, 8, 1, flags=0x06), item(END), item(END),
        item(PAGE, 0x01), item(USAGE, 0x06), item(COLLECTION, 0x01), item(RID, 6),  # Keyboard
        item(PAGE, 0x07), item(UMIN, 0xE0), item(UMAX, 0xE7), signed(LMIN, 0), signed(LMAX, 1),
        item(RSIZE, 1), item(RCOUNT, 8), item(INPUT, 0x02), item(RCOUNT, 1), item(RSIZE, 8), item(INPUT, 0x03),
        item(PAGE, 0x08), item(UMIN, 1), item(UMAX, 5), item(RCOUNT, 5), item(RSIZE, 1), item(OUTPUT, 0x02),
        item(RCOUNT, 1), item(RSIZE, 3), item(OUTPUT, 0x03),
        item(PAGE, 0x07), item(UMIN, 0), item(UMAX, 0xFF, 2), signed(LMIN, 0), signed(LMAX, 255),
        item(RSIZE, 8), item(RCOUNT, 6), item(INPUT, 0x00), item(END),
        item(PAGE, 0x0C), item(USAGE, 0x01), item(COLLECTION, 0x01), item(RID, 7),  # Consumer Control
        item(UMIN, 0), item(UMAX, 0x3FF, 2), signed(LMIN, 0), signed(LMAX, 0x3FF), item(RSIZE, 16),
        item(RCOUNT, 2), item(INPUT, 0x00), item(END),
        item(PAGE, 0xFF00, 2), item(USAGE, 0x01), item(COLLECTION, 0x01),  # vendor: firmware, calibration
    ]
    for rid in range(16, 45):  # feature reports: settings of 1..8 bytes
        parts += [item(RID, rid), field([rid], 0, 255, 8, 1 + rid % 8, main=FEATURE)]
    for rid in range(64, 80):  # input reports: raw sensor frames
        parts += [item(RID, rid), field([0x100 + rid], -32768, 32767, 16, 4 + rid % 12)]
    parts.append(item(END))
    return b"".join(parts)


# ---- workloads ---------------------------------------------------------------------------------------------

def sim_reports(model: str, options: dict[str, str], n: int, hz: str | None = None) -> list[tuple[float, bytes]]:
    """Up to ``n`` (time, report) pairs a simulator sends on a simulated clock (its script run once)."""
    clock = SimulatedClock()
    sim = create_simulator(model, clock=clock, **options, **({"hz": hz} if hz else {}))
    out: list[tuple[float, bytes]] = []
    for _ in range(100 * n):
        if len(out) >= n:
            break
        t = sim.next_event_time()
        if t is None:
            break
        clock.advance(max(t - clock.now(), 1e-6))
        out += sim.take_timed_reports()
    return out[:n]


def random_reports(rd: ReportDescriptor, n: int, rng: random.Random) -> list[bytes]:
    """``n`` seeded random input reports, each behind one of the descriptor's input report IDs."""
    layouts = [rd.layout(ReportKind.INPUT, rid) for rid in rd.input_reports]
    out = []
    for _ in range(n):
        layout = rng.choice(layouts)
        body = bytes(rng.randrange(256) for _ in range(layout.length))
        out.append(body if layout.report_id is None else bytes([layout.report_id]) + body[1:])
    return out


@dataclass
class Workload:
    """One descriptor and the reports decoded with it."""

    name: str
    data: bytes
    reports: list[bytes]


def workloads(n: int) -> list[Workload]:
    """The simulators' descriptors with their reports (cycled to ``n``), then the composite with random ones."""
    out = []
    for name, (model, options) in MODELS.items():
        reports = [r for _, r in sim_reports(model, options, n)] or [bytes(8)]
        out.append(Workload(name, getattr(descriptors, name), (reports * (n // len(reports) + 1))[:n]))
    big = composite_descriptor()
    out.append(Workload(f"composite {len(big)} B", big, random_reports(parse_descriptor(big), n, random.Random(SEED))))
    return out


def best(fn: Callable[[], object], repeat: int) -> float:
    """The shortest of ``repeat`` runs of ``fn``, in seconds."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def touch(rd: ReportDescriptor) -> int:
    """Read every report's length, its field list and each field's usages, bit offset and logical range (what
    hid-tools builds when it parses), so that nothing pixelpen might make on first use escapes the parse timings."""
    elements = 0
    for layout in rd.layouts.values():
        elements += layout.length
    for space in (rd.input_reports, rd.output_reports, rd.feature_reports):
        for fields in space.values():
            for f in fields:
                elements += len(f.usages) + (f.bit_offset >= 0) + (f.logical_min <= f.logical_max)
    return elements


@dataclass
class ParseTimes:
    """Seconds per parse of one descriptor."""

    hidtools: float
    parse: float
    """``parse_descriptor`` and :func:`touch`."""
    parse_compile: float
    """That, and every input report's decoder compiled."""


def parse_times(data: bytes, repeat: int, sample: float = 1e-3) -> ParseTimes:
    """hid-tools' and pixelpen's parse times of ``data``: per call, the best of ``repeat`` samples of about
    ``sample`` seconds, hid-tools' and pixelpen's taken in turn so that the machine's load weighs on both."""
    from hidtools.hid import ReportDescriptor as HidtoolsDescriptor

    as_list = list(data)

    def parse() -> ReportDescriptor:
        rd = parse_descriptor(data)
        touch(rd)
        return rd

    def parse_and_compile() -> None:
        rd = parse()
        for rid in rd.input_reports:
            rd.decoder(ReportKind.INPUT, rid)

    runs: list[Callable[[], object]] = [lambda: HidtoolsDescriptor.from_bytes(as_list), parse, parse_and_compile]
    calls = [max(1, round(sample / best(fn, 3))) for fn in runs]
    times = [float("inf")] * len(runs)
    for _ in range(repeat):
        for k, (fn, n) in enumerate(zip(runs, calls, strict=True)):
            t0 = time.perf_counter()
            for _ in range(n):
                fn()
            times[k] = min(times[k], (time.perf_counter() - t0) / n)
    return ParseTimes(*times)


@dataclass
class Row:
    """One descriptor's numbers."""

    name: str
    size: int
    hidtools_parse: float
    parse: float
    parse_compile: float
    hidtools_rate: float
    rate: float
    direct_rate: float
    batch_rate: float


def measure(w: Workload, repeat: int, batch: int) -> Row:
    """Parse and decode one workload with both libraries."""
    from hidtools.hid import ReportDescriptor as HidtoolsDescriptor

    parse = parse_times(w.data, repeat)
    ht = HidtoolsDescriptor.from_bytes(list(w.data))
    lists = [list(r) for r in w.reports]

    def hidtools_decode() -> None:
        for r in lists:
            report = ht.get(r[0], len(r))
            if report is not None:
                for f in report:
                    f.get_values(r)

    rd = parse_descriptor(w.data)
    decoders = {rid: rd.decoder(ReportKind.INPUT, rid) for rid in rd.input_reports}
    decode = rd.decode
    for r in w.reports:  # warm up: every decoder compiled, every report valid
        decode(r)
    routed = [(decoders[rd.report_id_of(r)].decode, r) for r in w.reports]

    def pixelpen_decode() -> None:
        for r in w.reports:
            decode(r)

    def pixelpen_direct() -> None:
        for fn, r in routed:
            fn(r)

    n = len(w.reports)
    ht_rate = n / best(hidtools_decode, max(1, repeat // 4))
    px_rate = n / best(pixelpen_decode, repeat)
    direct_rate = n / best(pixelpen_direct, repeat)
    # batch: every input report ID's reports stacked into one (N, length) array, N = batch rows in all
    groups: dict[int | None, list[bytes]] = {}
    for r in w.reports:
        groups.setdefault(rd.report_id_of(r), []).append(r)
    arrays = []
    for rid, rows in groups.items():
        length = decoders[rid].length
        block = np.frombuffer(b"".join(r[:length].ljust(length, b"\0") for r in rows), np.uint8).reshape(-1, length)
        arrays.append((decoders[rid], np.resize(block, (max(1, batch * len(rows) // n), length))))
    rows_total = sum(a.shape[0] for _, a in arrays)
    batch_time = best(lambda: [d.decode_batch(a) for d, a in arrays], repeat)
    return Row(w.name, len(w.data), parse.hidtools, parse.parse, parse.parse_compile, ht_rate, px_rate, direct_rate,
               rows_total / batch_time)


@dataclass
class Latency:
    """Per-report times at 1 kHz replay of one simulator's recording."""

    model: str
    reports: int
    events: int
    feed: list[float]
    read_feed: list[float]


def percentile(values: list[float], q: float) -> float:
    """The ``q`` quantile (0..1) of ``values`` (nearest rank)."""
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, max(0, round(q * len(ordered)) - 1))]


def latency(model: str, options: dict[str, str], n: int) -> Latency:
    """Record ``model`` at 1 kHz into a hid-recorder file, replay it through the hidapi fake; time each report."""
    reports = sim_reports(model, options, n, hz=LATENCY_HZ)
    sim = create_simulator(model, clock=SimulatedClock(), **options)
    t0 = reports[0][0] if reports else 0.0
    text = io.StringIO()
    write_hid_recording(HidRecording(f"recorded {model}", "", 3, sim.info["vendor_id"], sim.info["product_id"],
                                     sim.report_descriptor, [(t - t0, r) for t, r in reports]), text)
    (recording,) = read_hid_recording(text.getvalue())
    clock = SimulatedClock()
    module = SimHidapi([replay_device(recording, clock=clock)])
    link = open_hid(module.paths()[0], module=module, clock=clock)
    semantics = semantics_for(parse_descriptor(link.report_descriptor), link.device_id)
    feed, read_feed, events = [], [], 0
    perf = time.perf_counter
    for _ in recording.reports:
        start = perf()
        report = link.read_report(1.0)
        if report is None:
            break
        got = perf()
        events += len(semantics.feed(report, clock.now()))
        end = perf()
        feed.append(end - got)
        read_feed.append(end - start)
    link.close()
    return Latency(model, len(feed), events, feed, read_feed)


def format_rows(rows: list[Row]) -> list[str]:
    """The parse and decode table."""
    head = (f"{'descriptor':<20}{'bytes':>6} {'parse hid-tools':>15} {'pixelpen':>9} {'x':>6} {'+compile':>9} "
            f"{'x':>6} | {'reports/s hid-tools':>19} {'pixelpen':>10} {'direct':>10} {'x':>6} | {'batch/s':>11}")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r.name:<20}{r.size:>6} {r.hidtools_parse * 1e3:>12.3f} ms {r.parse * 1e3:>6.3f} ms "
                     f"{r.hidtools_parse / r.parse:>5.1f}x {r.parse_compile * 1e3:>6.3f} ms "
                     f"{r.hidtools_parse / r.parse_compile:>5.1f}x | {r.hidtools_rate:>19,.0f} {r.rate:>10,.0f} "
                     f"{r.direct_rate:>10,.0f} {r.rate / r.hidtools_rate:>5.1f}x | {r.batch_rate:>11,.0f}")
    return lines


def summary(rows: list[Row], lat: list[Latency]) -> list[str]:
    """The goals, each with its worst case."""
    parse = min(rows, key=lambda r: r.hidtools_parse / r.parse)
    rate = min(rows, key=lambda r: r.rate)
    direct = min(rows, key=lambda r: r.direct_rate)
    batch = min(rows, key=lambda r: r.batch_rate)
    p99 = max(lat, key=lambda x: percentile(x.read_feed, 0.99)) if lat else None
    lines = [
        f"parse speedup, worst: {parse.hidtools_parse / parse.parse:.1f}x ({parse.name}; goal >= {PARSE_GOAL:g}x)"
        f" -> {'met' if parse.hidtools_parse / parse.parse >= PARSE_GOAL else 'MISSED'}",
        f"reports/s per report, worst: {rate.rate:,.0f} ({rate.name}; goal >= {REPORTS_GOAL:,.0f})"
        f" -> {'met' if rate.rate >= REPORTS_GOAL else 'MISSED'}",
        f"reports/s per report by the report's own decoder, worst: {direct.direct_rate:,.0f} ({direct.name})"
        f" -> {'met' if direct.direct_rate >= REPORTS_GOAL else 'MISSED'}",
        f"batch reports/s, worst: {batch.batch_rate:,.0f} ({batch.name}; goal >= {BATCH_GOAL:,.0f})"
        f" -> {'met' if batch.batch_rate >= BATCH_GOAL else 'MISSED'}",
    ]
    for x in lat:
        lines.append(f"latency at {LATENCY_HZ} Hz replay, {x.model:<11} {x.reports:>6} reports {x.events:>6} events: "
                     f"feed p50 {percentile(x.feed, 0.5) * 1e6:6.1f} us p99 {percentile(x.feed, 0.99) * 1e6:6.1f} us"
                     f" | read+feed p50 {percentile(x.read_feed, 0.5) * 1e6:6.1f} us p99 "
                     f"{percentile(x.read_feed, 0.99) * 1e6:6.1f} us max {max(x.read_feed) * 1e6:7.1f} us")
    if p99 is not None:
        worst = percentile(p99.read_feed, 0.99)
        lines.append(f"latency p99, worst: {worst * 1e6:.1f} us ({p99.model}; goal < {LATENCY_GOAL_S * 1e6:.0f} us)"
                     f" -> {'met' if worst < LATENCY_GOAL_S else 'MISSED'}")
    return lines


def parse_only(repeat: int) -> int:
    """Print hid-tools' and pixelpen's parse times per descriptor and their ratios (the worst first)."""
    rows = [(w.name, len(w.data), parse_times(w.data, repeat)) for w in workloads(1)]
    for name, size, t in sorted(rows, key=lambda row: row[2].hidtools / row[2].parse):
        print(f"{name:<20}{size:>6} hid-tools {t.hidtools * 1e3:8.3f} ms  pixelpen {t.parse * 1e3:7.4f} ms "
              f"{t.hidtools / t.parse:5.1f}x  | +compile {t.parse_compile * 1e3:7.4f} ms "
              f"{t.hidtools / t.parse_compile:5.1f}x")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Run every measurement and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reports", type=int, default=20_000, help="reports decoded one by one per descriptor")
    parser.add_argument("--batch", type=int, default=1_000_000, help="rows decoded in batches per descriptor")
    parser.add_argument("--repeat", type=int, default=20, help="runs of each measurement (the best is kept)")
    parser.add_argument("--latency", type=int, default=5_000, help="reports replayed per model at 1 kHz")
    parser.add_argument("--tiny", action="store_true", help="a smoke run: a few of everything")
    parser.add_argument("--parse-only", action="store_true", help="only the parse times (no decoding, no latency)")
    args = parser.parse_args(argv)
    if args.tiny:
        args.reports, args.batch, args.repeat, args.latency = 50, 500, 2, 30
    if args.parse_only:
        return parse_only(args.repeat)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short reports of random data are padded as the kernel does; fine here
        rows = [measure(w, args.repeat, args.batch) for w in workloads(args.reports)]
    for line in format_rows(rows):
        print(line)
    lat = [latency(model, options, args.latency) for model, options in dict(MODELS.values()).items()]
    print()
    for line in summary(rows, lat):
        print(line)
    print(f"(python {sys.version.split()[0]}, numpy {np.__version__}, "
          f"median hid-tools parse {statistics.median(r.hidtools_parse for r in rows) * 1e3:.2f} ms)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Fault-injection campaign: every plotter family, random seeded faults, resumed through the API and the CLI.

For each family (hp7475a, grbl, axidraw) and each fault kind (drop, stall, corrupt, power loss, device
error, pause) a random drawing is plotted on a named simulator (``sim:FAMILY?speed=fast&id=...``) with
the fault in the URL (``drop_after=N``, ``stall_after=N``, ``corrupt_at=N``, ``power_loss_after=N``,
``pause_after=N``; N uniform over the bytes of the uninterrupted plot).  After the fault the operator's
part is played (power back on, the cable fixed: the resume uses the URL without the fault; after a
PositionUnknown on GRBL and AxiDraw the carriage is put home, :func:`rehome`: ``go_home()`` / ``pixelpen pen
home`` while the step counters are right, after a power loss pushed home by hand with the pen up, on an
AxiDraw after ``motors-off``) and the plot is resumed — through ``resume_after_fault()`` (path ``api``) or
through ``pixelpen plot --resume`` run in process with a state file (path ``cli``; ``--no-optimize``, so
that the reference plot and the interrupted one plan the same strokes).  A resume that answers
PositionUnknown counts as ``asked``; it is then resumed with ``position_confirmed=True``
(``--confirm-position``) and checked too.

The simulator's paper is compared with the intended drawing AS SEGMENT SETS (see :func:`compare`; path
``cli``: the uninterrupted plot's paper, as the CLI places the SVG on its page; either must match the
uninterrupted plot exactly, else the scenario fails): ``lost`` intended segments not fully covered,
``doubled`` segments covered more than once over more than ``TOL_MM``, ``stray`` drawn pieces on no
segment of their pen.  A scenario that neither finishes nor asks counts as ``failed`` (with its error).

    python3 benchmarks/faults.py [--runs 100] [--family hp7475a ...] [--path api cli] [--seed 2026]

Limits: ``MAX_RESUMES`` resumes per scenario, ``SCENARIO_S`` wall seconds per scenario (SIGALRM).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import itertools
import re
import signal
import sys
import tempfile
from collections import Counter, defaultdict
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import pixelpen
from pixelpen import cli
from pixelpen.devices.plotters.base import PlotInterrupted, PositionUnknown
from pixelpen.errors import LinkError, PixelpenError, ProtocolError
from pixelpen.sim.base import forget_simulator, named_simulator
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.simplify import simplify

FAMILIES = ("hp7475a", "grbl", "axidraw")
KINDS = ("drop", "stall", "corrupt", "power", "device_error", "pause")
PATHS = ("api", "cli")
FAULT_OPTION = {
    "drop": "drop_after", "stall": "stall_after", "corrupt": "corrupt_at", "device_error": "corrupt_at",
    "power": "power_loss_after", "pause": "pause_after",
}
FAMILY_OPTIONS = {"hp7475a": "sync_strokes=4&stall=5", "grbl": "", "axidraw": ""}
"""Per-family URL options of every run (HP-GL: a short stall limit so a stalled link is noticed in 5 s)."""
TOL_MM = 0.05
"""Distance (mm) within which a drawn piece lies on a reference segment; also the overlap/gap allowed."""
MAX_RESUMES = 6
SCENARIO_S = 120
STROKES = 24
_FAULTS = re.compile(r"([?&])(?:drop_after|stall_after|corrupt_at|power_loss_after|pause_after)=\d+&?")


@dataclass
class Tally:
    """What a plot's paper has against the reference, as segment sets."""

    lost: int = 0
    doubled: int = 0
    stray: int = 0


def segments_of(dl: DisplayList) -> tuple[np.ndarray, np.ndarray]:
    """(N, 4) segments in mm and their pens, one per consecutive point pair of every stroke."""
    pts = dl.points * dl.unit_mm
    if len(pts) < 2:
        return np.zeros((0, 4)), np.zeros(0, int)
    crosses = np.zeros(len(pts) - 1, dtype=bool)  # pair i..i+1 joins two strokes
    crosses[dl.offsets[1:-1] - 1] = True
    idx = np.flatnonzero(~crosses)
    stroke = np.searchsorted(dl.offsets, idx, side="right") - 1
    return np.hstack([pts[idx], pts[idx + 1]]), dl.pens[stroke].astype(int)


def compare(intended: DisplayList, drawn: DisplayList, tol: float = TOL_MM) -> Tally:
    """Lost, doubled and stray segments of a simulator's paper ``drawn`` against the ``intended`` drawing.

    The paper is first simplified to within ``tol / 4`` (a simulator that inks a move as the points it sampled
    along it, as the EBB one does, splits a line wherever its timing fell).  A drawn piece lies on a segment of
    its pen when both its ends are within ``tol`` of it; of several (a corner, a path along itself) it is
    credited to the nearest (largest end distance, within ``tol / 4``), then the most parallel in its drawing
    direction, then the one with the least ink so far.
    """
    rseg, rpen = segments_of(intended)
    dseg, dpen = segments_of(simplify(drawn, tol / 4 / drawn.unit_mm))
    keep = np.hypot(rseg[:, 2] - rseg[:, 0], rseg[:, 3] - rseg[:, 1]) > 1e-9
    rseg, rpen = rseg[keep], rpen[keep]
    length = np.hypot(rseg[:, 2] - rseg[:, 0], rseg[:, 3] - rseg[:, 1])
    unit = (rseg[:, 2:] - rseg[:, :2]) / length[:, None]
    pieces: dict[int, list[tuple[float, float]]] = defaultdict(list)
    tally = Tally()
    for seg, pen in zip(*_split_at_vertices(dseg, dpen, rseg, rpen, tol), strict=True):
        off = np.maximum(_distance(seg[:2], rseg, length), _distance(seg[2:], rseg, length))
        hits = np.flatnonzero((off <= tol) & (rpen == pen))
        if not len(hits):
            tally.stray += 1
            continue
        hits = hits[off[hits] <= off[hits].min() + tol / 4]
        way = seg[2:] - seg[:2]
        along = unit[hits] @ (way / max(float(np.hypot(*way)), 1e-12))
        k = int(hits[min(range(len(hits)), key=lambda i: (-round(float(along[i]), 3), len(pieces[hits[i]])))])
        a = rseg[k, :2]
        t0, t1 = sorted(float((p - a) @ unit[k]) for p in (seg[:2], seg[2:]))
        pieces[k].append((t0, t1))
    for k in range(len(rseg)):
        covered, total, gap = _coverage(sorted(pieces.get(k, [])), float(length[k]))
        tally.lost += gap > tol
        tally.doubled += total - covered > tol
    return tally


def _split_at_vertices(dseg: np.ndarray, dpen: np.ndarray, rseg: np.ndarray, rpen: np.ndarray,
                       tol: float) -> tuple[list[np.ndarray], list[int]]:
    """Drawn pieces cut where an intended vertex of their pen lies on them (within ``tol``, inside the piece).

    Simplifying the paper may merge two collinear intended segments into one drawn piece (a resume splits a
    stroke, which moves the simplifier's anchors); cut there, each part is credited to its own segment.
    """
    segs: list[np.ndarray] = []
    pens: list[int] = []
    for seg, pen in zip(dseg, dpen, strict=True):
        a, d = seg[:2], seg[2:] - seg[:2]
        span = float(d @ d)
        cuts: list[float] = []
        if span > 0:
            ends = np.vstack([rseg[rpen == pen, :2], rseg[rpen == pen, 2:]])
            t = ((ends - a) @ d) / span
            near = np.hypot(*(a + t[:, None] * d - ends).T) <= tol
            inside = (t * np.sqrt(span) > tol) & ((1 - t) * np.sqrt(span) > tol)
            cuts = sorted({round(float(x), 9) for x in t[near & inside]})
        points = [a + x * d for x in (0.0, *cuts, 1.0)]
        for p, q in itertools.pairwise(points):
            segs.append(np.concatenate([p, q]))
            pens.append(int(pen))
    return segs, pens


def _distance(p: np.ndarray, seg: np.ndarray, length: np.ndarray) -> np.ndarray:
    """Distance of point p from each segment."""
    a, d = seg[:, :2], seg[:, 2:] - seg[:, :2]
    t = np.clip(((p - a) * d).sum(1) / np.maximum(length * length, 1e-12), 0, 1)
    return np.hypot(*(a + t[:, None] * d - p).T)


def _coverage(spans: list[tuple[float, float]], length: float) -> tuple[float, float, float]:
    """Union length, summed length and largest uncovered stretch of ``spans`` (sorted) over [0, length]."""
    covered = total = gap = 0.0
    reach = 0.0
    for t0, t1 in spans:
        t0, t1 = max(0.0, t0), min(length, t1)
        total += max(0.0, t1 - t0)
        gap = max(gap, t0 - reach)
        covered += max(0.0, t1 - max(t0, reach))
        reach = max(reach, t1)
    return covered, total, max(gap, length - reach)


# -- drawings and devices -----------------------------------------------------------------------------


def drawing(family: str, rng: np.random.Generator, strokes: int = STROKES) -> DisplayList:
    """A random drawing in the family's device units: open polylines and a few closed ones, no dots."""
    d = pixelpen.open(f"sim:{family}?speed=fast")
    try:
        w, h = d.capabilities.size
        unit = d.profile.unit_mm
        pens = d.profile.pens
    finally:
        d.close()
    polys = []
    for i in range(strokes):
        n = int(rng.integers(3 if i % 5 == 4 else 2, 7))
        pts = np.column_stack([rng.uniform(0.05, 0.95, n) * w, rng.uniform(0.05, 0.95, n) * h]).round()
        if i % 5 == 4:
            pts = np.vstack([pts, pts[:1]])  # closed
        polys.append(pts)
    pen_of = [1 + i % pens for i in range(strokes)] if pens > 1 else 1
    return DisplayList.from_polylines(polys, pens=pen_of, unit_mm=unit)


def write_svg(dl: DisplayList, path: Path) -> None:
    """The drawing as an SVG in millimetres (one single-pen polyline per stroke), for the CLI path."""
    w = max(10.0, float(dl.points[:, 0].max() * dl.unit_mm) + 10)
    h = max(10.0, float(dl.points[:, 1].max() * dl.unit_mm) + 10)
    lines = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w:.3f}mm" height="{h:.3f}mm" '
             f'viewBox="0 0 {w:.3f} {h:.3f}">']
    for pts in dl.strokes():
        coords = " ".join(f"{x * dl.unit_mm:.3f},{y * dl.unit_mm:.3f}" for x, y in pts)
        lines.append(f'<polyline points="{coords}" fill="none" stroke="black"/>')
    lines.append("</svg>")
    path.write_text("\n".join(lines), encoding="utf-8")


def paper_of(ident: str) -> DisplayList:
    """The named simulator's sheet as a DisplayList (HP-GL: plotter units; GRBL, EBB: their Sheet in mm)."""
    device = named_simulator(ident)
    paper = getattr(device, "paper", None)
    return paper.display_list() if hasattr(paper, "display_list") else device.display_list()


def recover(family: str, kind: str, ident: str) -> None:
    """The operator's part after a fault: power back on."""
    if kind != "power":
        return
    device = named_simulator(ident)
    if family == "axidraw":
        device.inject("power-restore")
    elif family != "grbl":  # a GRBL board reboots by itself when its power comes back
        device.inject("reset")


REHOMES = ("grbl", "axidraw")
"""Families whose lost position the operator restores by homing before confirming (HP-GL homes at power-up)."""


MANUAL = {"up": "pen_up", "home": "go_home", "motors-off": "motors_off"}
"""``pixelpen pen ACTION`` -> the display's method."""


def rehome(family: str, kind: str, ident: str, pen: Callable[[str], None]) -> None:
    """After PositionUnknown: the operator puts the carriage where the driver's home is, then confirms.

    ``pen(action)`` is ``pixelpen pen ACTION`` (API: the display's method).  The counters survived (every
    fault but power): ``home``.  Power lost: GRBL with homing switches ($22=1) homes with ``$H`` (``home``);
    without, the operator lifts the pen, pushes the carriage to the origin by hand (the simulator's
    ``push_carriage_home``) and power-cycles the board there (a rebooted GRBL may have run lines since);
    an AxiDraw's carriage is pushed home after ``motors-off`` (as its manual says).
    """
    device = named_simulator(ident)
    if kind != "power" or (family == "grbl" and device.settings.get(22)):
        pen("home")
        return
    pen("up")
    if family == "axidraw":
        pen("motors-off")
    device.push_carriage_home()
    if family == "grbl":  # GRBL zeroes its machine position only at power-up: switch it off and on there
        device.inject("reset")


def release(family: str, ident: str) -> None:
    """The operator ends a device pause (VIEW pressed again, PRG button released, cycle start)."""
    device = named_simulator(ident)
    if family.startswith("hp"):
        device.inject("pause-button")  # VIEW toggles
    elif family == "grbl":
        device.receive(b"~")
    else:
        device.inject("pause-button")


def url(family: str, ident: str, extra: str = "") -> str:
    """The sim URL of a campaign run."""
    opts = "&".join(o for o in (f"speed=fast&id={ident}", FAMILY_OPTIONS[family], extra) if o)
    return f"sim:{family}?{opts}"


# -- scenarios -------------------------------------------------------------------------------------------


@dataclass
class Outcome:
    """One scenario's result."""

    tally: Tally = field(default_factory=Tally)
    asked: bool = False
    interrupted: bool = False
    failed: str | None = None
    faults: list[str] = field(default_factory=list)
    """The messages of the faults met, in order (for -v)."""


class _Timeout(Exception):
    pass


@contextlib.contextmanager
def _deadline(seconds: int):
    def on_alarm(signum, frame):
        raise _Timeout(f"no end within {seconds} s")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def reference_api(family: str, dl: DisplayList, ident: str) -> tuple[DisplayList, int]:
    """The uninterrupted plot's paper and the number of host bytes it took."""
    d = pixelpen.open(url(family, ident))
    try:
        d.plot(dl)
        sent = d.link.port.sim_port.stats().bytes_sent
    finally:
        d.close()
    paper = paper_of(ident)
    forget_simulator(ident)
    return paper, sent


def run_api(family: str, kind: str, at: int, dl: DisplayList, ident: str) -> Outcome:
    """Plot with the fault, resume through resume_after_fault(), compare."""
    out = Outcome()
    d = pixelpen.open(url(family, ident, f"{FAULT_OPTION[kind]}={at}"),
                      on_pause=lambda paused: paused and release(family, ident))
    try:
        try:
            d.plot(dl)
        except (PlotInterrupted, ProtocolError) as exc:  # a device error leaves the job resumable too
            out.interrupted = True
            out.faults.append(str(exc))
            recover(family, kind, ident)
            d.port = _FAULTS.sub(lambda m: m.group(1) if m.group(0).endswith("&") else "", d.port).rstrip("?&")
            confirmed = False
            for _ in range(MAX_RESUMES):
                try:
                    d.resume_after_fault(position_confirmed=confirmed)
                    break
                except PositionUnknown as exc:
                    out.asked = confirmed = True
                    out.faults.append(str(exc))
                    if family in REHOMES:  # the operator homes the machine, then confirms
                        rehome(family, kind, ident, lambda action: getattr(d, MANUAL[action])())
                except (PlotInterrupted, ProtocolError, LinkError) as exc:  # a reconnect that failed is tried again
                    out.faults.append(str(exc))
            else:
                raise PixelpenError(f"not finished after {MAX_RESUMES} resumes")
    finally:
        with contextlib.suppress(Exception):
            d.close()
    out.tally = compare(dl, paper_of(ident))
    return out


def run_cli(family: str, kind: str, at: int, svg: Path, dl: DisplayList, ident: str, state: Path) -> Outcome:
    """Plot with the fault through ``pixelpen plot``, then ``--resume`` (``--confirm-position`` if asked); compare."""
    out = Outcome()
    base = ["plot", str(svg), "--state", str(state), "--retries", "0", "--no-optimize"]
    code, text = _main([*base, "--to", url(family, ident, f"{FAULT_OPTION[kind]}={at}")])
    if code != 0:
        out.interrupted = True
        out.faults.append(_said(text))
        if code != 3:
            raise PixelpenError(f"first run exit {code}: {text.strip()[-300:]}")
        recover(family, kind, ident)
        extra: list[str] = []
        for _ in range(MAX_RESUMES):
            code, text = _main([*base, "--to", url(family, ident), "--resume", *extra])
            out.faults.append(_said(text))
            if code == 0:
                break
            if "--confirm-position" in text and not extra:
                out.asked = True
                extra = ["--confirm-position"]
                if family in REHOMES:  # the operator homes the machine, then confirms
                    rehome(family, kind, ident, lambda action: _pen(family, ident, action))
            elif code != 3:
                raise PixelpenError(f"resume exit {code}: {text.strip()[-300:]}")
        else:
            raise PixelpenError(f"not finished after {MAX_RESUMES} resumes")
    out.tally = compare(dl, paper_of(ident))
    return out


def _pen(family: str, ident: str, action: str) -> None:
    """``pixelpen pen ACTION --to URL`` in process."""
    code, said = _main(["pen", action, "--to", url(family, ident)])
    if code != 0:
        raise PixelpenError(f"pixelpen pen {action} exit {code}: {_said(said)[-300:]}")


def reference_cli(family: str, svg: Path, ident: str, state: Path) -> tuple[DisplayList, int]:
    """The uninterrupted CLI plot's paper and its host bytes (read from the simulator's counters)."""
    code, text = _main(["plot", str(svg), "--to", url(family, ident), "--state", str(state), "--no-optimize"])
    if code != 0:
        raise PixelpenError(f"reference plot exit {code}: {_said(text)[-300:]}")
    received = named_simulator(ident).stats.bytes_received
    paper = paper_of(ident)
    forget_simulator(ident)
    return paper, received


def _said(text: str) -> str:
    """The CLI's messages without its progress bar lines."""
    return "\n".join(line for line in text.splitlines() if line and not line.lstrip().startswith("[")).strip()


def _main(argv: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = cli.main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 2
    return int(code or 0), err.getvalue()


# -- the campaign ----------------------------------------------------------------------------------------


Row = tuple[str, str, str]


def campaign(families=FAMILIES, paths=PATHS, runs: int = 100, seed: int = 2026,
             log: Callable[[str], None] = lambda s: None, strokes: int = STROKES,
             each: Callable[[dict[Row, Counter]], None] = lambda table: None) -> dict[Row, Counter]:
    """Run ``runs`` scenarios per family and path (kinds in turn); counters per (family, path, kind)."""
    table: dict[Row, Counter] = defaultdict(Counter)
    rng = np.random.default_rng(seed)
    with tempfile.TemporaryDirectory() as tmp:
        for family in families:
            for path in paths:
                for run in range(runs):
                    kind = KINDS[run % len(KINDS)]
                    if path == "cli" and kind == "pause":
                        kind = KINDS[(run + 1) % len(KINDS)]  # a CLI pause needs the operator's key: api only
                    row = table[(family, path, kind)]
                    dl = drawing(family, rng, strokes)
                    ident = f"faults-{family}-{path}-{run}"
                    svg, state = Path(tmp, f"{ident}.svg"), Path(tmp, f"{ident}.state.json")
                    try:
                        with _deadline(SCENARIO_S):
                            if path == "api":
                                ref, total = reference_api(family, dl, ident)
                            else:
                                write_svg(dl, svg)
                                ref, total = reference_cli(family, svg, ident, state)
                                state.unlink(missing_ok=True)
                            # the CLI places the SVG on its page: there the intended drawing is the reference paper
                            intended = dl if path == "api" else simplify(ref, TOL_MM / 4 / ref.unit_mm)
                            differs = compare(intended, ref)
                            if differs != Tally():
                                raise PixelpenError(f"the uninterrupted plot differs from the drawing: {differs}")
                            at = int(rng.integers(min(60, total // 4), max(61, total - 10)))
                            if kind == "device_error":
                                at = int(rng.integers(total // 4, max(total // 4 + 1, total - 10)))
                            out = (run_api(family, kind, at, dl, ident) if path == "api"
                                   else run_cli(family, kind, at, svg, intended, ident, state))
                    except (_Timeout, Exception) as exc:  # noqa: BLE001  (a campaign reports every failure, whatever it is)
                        out = Outcome(failed=f"{type(exc).__name__}: {exc}")
                    finally:
                        with contextlib.suppress(KeyError):
                            forget_simulator(ident)
                    row["runs"] += 1
                    row["interrupted"] += out.interrupted
                    row["lost"] += out.tally.lost
                    row["doubled"] += out.tally.doubled
                    row["stray"] += out.tally.stray
                    row["asked"] += out.asked
                    row["failed"] += out.failed is not None
                    each(table)
                    if out.failed or out.tally.lost or out.tally.doubled or out.tally.stray:
                        log(f"{family} {path} {kind} at={locals().get('at')}: {out}")
    return table


def format_table(table: dict[Row, Counter]) -> str:
    """The campaign table: family x path x kind x runs x interrupted x lost x doubled x stray x asked x failed."""
    cols = ("runs", "interrupted", "lost", "doubled", "stray", "asked", "failed")
    lines = [f"{'family':<8} {'path':<4} {'kind':<13}" + "".join(f"{c:>12}" for c in cols)]
    for (family, path, kind), row in sorted(table.items()):
        lines.append(f"{family:<8} {path:<4} {kind:<13}" + "".join(f"{row[c]:>12}" for c in cols))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Command line: run the campaign and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=100, help="scenarios per family and path (default 100)")
    ap.add_argument("--family", nargs="+", default=list(FAMILIES), choices=FAMILIES)
    ap.add_argument("--path", nargs="+", default=list(PATHS), choices=PATHS)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--strokes", type=int, default=STROKES, help=f"strokes per random drawing (default {STROKES})")
    ap.add_argument("-v", "--verbose", action="store_true", help="print every scenario that was not clean")
    ap.add_argument("--table", help="file the table so far is written to after every scenario")
    args = ap.parse_args(argv)
    def save(t: dict) -> None:
        if args.table:
            Path(args.table).write_text(format_table(t) + "\n")

    table = campaign(args.family, args.path, args.runs, args.seed, log=print if args.verbose else (lambda s: None),
                     strokes=args.strokes, each=save)
    print(format_table(table))
    return 0


if __name__ == "__main__":
    sys.exit(main())

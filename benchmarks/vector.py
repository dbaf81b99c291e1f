"""Benchmark ``pixelpen optimize`` at its DEFAULT settings against ``vpype read IN linesort write OUT``.

Run by hand: ``python3 benchmarks/vector.py [--quick] [--keep DIR] [--svg FILE ...]``; needs the ``bench`` extra
(``pip install vpype``). Every input is written to an SVG file (mm) and both tools run as their command lines do,
in this one process after a warm-up run of each, taking the fastest of several interleaved runs for inputs that
take under 10 s: ``pixelpen.cli.main(["optimize", IN, "-o", OUT])`` (read, dedupe, order with the default
adaptive budget, before/after stats, write) and ``vpype_cli.execute("read IN linesort write OUT")``. Both outputs
are read back with pixelpen's SVG reader and measured the same way: pen-up travel from (0, 0) in mm, and the
pen-down length (a check that neither tool lost ink). Inputs: a synthetic ~120 kB map (contour lines of a smooth
random field cut into short ways sharing their end points, as OSM roads and contours come), random 1–5 mm
segments in 300 × 200 mm with seed 0 (plotters.md §4, moved 5 mm in from the page edge; 10k and 100k of them),
an A4 page of Hershey text, and any SVG given. Ratios are pixelpen / vpype: the goal is pen-up <= 0.85 and
wall <= 1.0 on every input.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from pixelpen.cli import main as pixelpen_main
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.merge import merge_paths
from pixelpen.vector.svgimport import read_svg

PAGE_MM = (300.0, 200.0)
PEN_UP_GOAL, WALL_GOAL = 0.85, 1.0

# marching squares: for each corner-sign case (bit k set when corner k is above the level; corners 0 (i, j),
# 1 (i+1, j), 2 (i+1, j+1), 3 (i, j+1)), the cell edges joined by its segments (edge 0 j-side, 1 i+1-side,
# 2 j+1-side, 3 i-side); saddles (5, 10) take the two segments that keep the corner 0 region apart
_CASES = {1: [(3, 0)], 2: [(0, 1)], 3: [(3, 1)], 4: [(1, 2)], 5: [(3, 0), (1, 2)], 6: [(0, 2)], 7: [(3, 2)],
          8: [(2, 3)], 9: [(2, 0)], 10: [(0, 1), (2, 3)], 11: [(2, 1)], 12: [(1, 3)], 13: [(1, 0)], 14: [(0, 3)]}


def random_segments(n: int, seed: int = 0) -> list[np.ndarray]:
    """``n`` segments 1–5 mm long at uniform random places and angles in 300 × 200 mm (plotters.md §4)."""
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(5, 305, n), rng.uniform(5, 205, n)  # plotters.md's 300 x 200 mm area, 5 mm in from the page
    length, angle = rng.uniform(1, 5, n), rng.uniform(0, 2 * np.pi, n)
    start = np.column_stack([x, y])
    end = start + length[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    return list(np.stack([start, end], axis=1))


def contour_segments(field: np.ndarray, level: float, cell_mm: float) -> np.ndarray:
    """(M, 2, 2) marching-squares segments of ``field`` (rows = y) at ``level``; shared edge points are identical."""
    above = field > level
    ny, nx = field.shape
    j, i = np.mgrid[0 : ny - 1, 0 : nx - 1]
    case = (above[j, i] * 1 + above[j, i + 1] * 2 + above[j + 1, i + 1] * 4 + above[j + 1, i] * 8).ravel()
    # crossing point on every grid edge, computed once per edge so neighbouring cells share it exactly
    with np.errstate(divide="ignore", invalid="ignore"):
        th = (level - field[:, :-1]) / (field[:, 1:] - field[:, :-1])  # along x, edge (i, j)-(i+1, j)
        tv = (level - field[:-1, :]) / (field[1:, :] - field[:-1, :])  # along y, edge (i, j)-(i, j+1)
    yy, xx = np.mgrid[0:ny, 0:nx].astype(float)
    hpt = np.stack([(xx[:, :-1] + th) * cell_mm, yy[:, :-1] * cell_mm], axis=-1)
    vpt = np.stack([xx[:-1, :] * cell_mm, (yy[:-1, :] + tv) * cell_mm], axis=-1)
    ci, cj = i.ravel(), j.ravel()
    edge_pts = np.stack([hpt[cj, ci], vpt[cj, ci + 1], hpt[cj + 1, ci], vpt[cj, ci]], axis=1)  # (cells, 4, 2)
    out = []
    for c, pairs in _CASES.items():
        cells = np.flatnonzero(case == c)
        for a, b in pairs:
            out.append(np.stack([edge_pts[cells, a], edge_pts[cells, b]], axis=1))
    return np.concatenate(out)


def map_polylines(seed: int = 0, target_kb: float = 120.0) -> list[np.ndarray]:
    """A map-like drawing of about ``target_kb`` kB as SVG: contours of a smooth random field cut into short ways."""
    rng = np.random.default_rng(seed)
    cell = 1.5
    nx, ny = int(PAGE_MM[0] / cell) + 1, int(PAGE_MM[1] / cell) + 1
    yy, xx = np.mgrid[0:ny, 0:nx] * cell
    field = np.zeros((ny, nx))
    for _ in range(12):  # a few smooth Fourier modes
        kx, ky = rng.normal(0, 0.03, 2)
        field += rng.normal() * np.cos(kx * xx + ky * yy + rng.uniform(0, 2 * np.pi))
    levels = np.linspace(field.min(), field.max(), 16)[1:-1]
    segs = np.concatenate([contour_segments(field, lv, cell) for lv in levels])
    whole = merge_paths(DisplayList.from_polylines(list(segs)), 0.0)
    ways: list[np.ndarray] = []
    for s in whole.strokes():  # cut each contour into ways of 2..12 segments sharing their end points
        cuts = np.cumsum(rng.integers(2, 13, len(s) // 2 + 1))
        cuts = cuts[cuts < len(s) - 1]
        ways += [s[a : b + 1] for a, b in zip(np.r_[0, cuts], np.r_[cuts, len(s) - 1], strict=True)]
    order = rng.permutation(len(ways))  # map files list ways in no useful order
    ways = [ways[k] for k in order]
    size = len(svg_text(ways)) / 1000
    return ways[: int(len(ways) * min(1.0, target_kb / size))]


def text_page() -> list[np.ndarray]:
    """An A4 page of Hershey text (2.5 mm capitals)."""
    from pixelpen.vector.font import text_strokes

    rng = np.random.default_rng(0)
    words = [
        "plot", "pen", "paper", "ink", "vector", "raster", "stroke", "path", "line", "curve", "point", "hatch",
        "font", "order", "merge", "travel", "lift", "drop", "carousel", "servo", "motor", "step", "speed", "corner",
        "junction", "plan", "time",
    ]
    lines = [" ".join(rng.choice(words, 12)) for _ in range(62)]
    return text_strokes("\n".join(lines), position=(10.0, 287.0), height=2.5, valign="top", font="futural")


def svg_text(polylines: list[np.ndarray]) -> str:
    """An SVG document in mm, one ``<path>`` per polyline, on a page from (0, 0) that holds them all (vpype crops)."""
    hi = np.max([p.max(axis=0) for p in polylines], axis=0)
    if np.min([p.min(axis=0) for p in polylines]) < 0:
        raise ValueError("svg_text: the drawing must lie at x, y >= 0")
    w, h = np.ceil(hi + 5.0)
    body = "\n".join('<path d="M' + " ".join(f"{x:.2f},{y:.2f}" for x, y in p.tolist()) + '"/>' for p in polylines)
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{w:g}mm" height="{h:g}mm" viewBox="0 0 {w:g} {h:g}">\n'
            f'<g fill="none" stroke="#000000" stroke-width="0.3">\n{body}\n</g>\n</svg>\n')


def run_pixelpen(src: Path, dst: Path) -> float:
    """``pixelpen optimize SRC -o DST`` (default settings) in this process; returns the wall time."""
    t0 = time.perf_counter()
    with contextlib.redirect_stderr(io.StringIO()):
        status = pixelpen_main(["optimize", str(src), "-o", str(dst)])
    wall = time.perf_counter() - t0
    if status:
        raise SystemExit(f"pixelpen optimize {src} failed with status {status}")
    return wall


def run_vpype(src: Path, dst: Path) -> float:
    """``vpype read SRC linesort write DST`` in this process; returns the wall time."""
    import vpype_cli

    t0 = time.perf_counter()
    vpype_cli.execute(f"read '{src}' linesort write '{dst}'")
    return time.perf_counter() - t0


def repeats(wall: float) -> int:
    """How many runs of each tool to take the fastest of: more for short runs, whose times vary most."""
    return 7 if wall < 1.0 else 3 if wall < 10.0 else 1


def measure(path: Path) -> tuple[float, float, int]:
    """Pen-up mm from (0, 0), pen-down mm and stroke count of an SVG plotted in file order."""
    dl = read_svg(path)
    return dl.pen_up_length() * dl.unit_mm, dl.pen_down_length() * dl.unit_mm, len(dl)


def main(argv: list[str] | None = None) -> int:
    """Run the cases and print the comparison table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the 100,000-segment case")
    ap.add_argument("--keep", type=Path, default=None, metavar="DIR", help="keep the input and output SVGs here")
    ap.add_argument("--svg", nargs="*", default=[], help="SVG files to add as cases")
    args = ap.parse_args(argv)
    try:
        import vpype_cli  # noqa: F401
    except ImportError:
        print("vpype is not installed: pip install vpype (the 'bench' extra)", file=sys.stderr)
        return 2
    cases: list[tuple[str, Callable[[], list[np.ndarray]]]] = [
        ("map SVG", map_polylines),
        ("10k segments", lambda: random_segments(10_000)),
        ("100k segments", lambda: random_segments(100_000)),
        ("Hershey text page", text_page),
    ]
    if args.quick:
        cases = [c for c in cases if not c[0].startswith("100k")]
    with tempfile.TemporaryDirectory() as tmp:
        work = args.keep or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        warm = work / "warm.svg"
        warm.write_text(svg_text(random_segments(50, seed=1)))
        run_pixelpen(warm, work / "warm-pixelpen.svg")
        run_vpype(warm, work / "warm-vpype.svg")
        inputs = []
        for name, make in cases:
            src = work / (name.replace(" ", "-") + ".svg")
            src.write_text(svg_text(make()))
            inputs.append((name, src))
        inputs += [(f"SVG {p}", Path(p)) for p in args.svg]
        header = (f"{'input':18s} {'kB':>6s} {'paths':>7s} {'vpype up mm':>12s} {'pixelpen up mm':>14s} "
                  f"{'vpype s':>8s} {'pixelpen s':>10s} {'pen-up':>7s} {'wall':>6s}  goal")
        print(header)
        print("-" * len(header))
        for name, src in inputs:
            out_v, out_p = work / f"{src.stem}-vpype.svg", work / f"{src.stem}-pixelpen.svg"
            wall_v, wall_p = run_vpype(src, out_v), run_pixelpen(src, out_p)
            for _ in range(repeats(max(wall_v, wall_p)) - 1):  # interleaved, so both see the same machine load
                wall_v, wall_p = min(wall_v, run_vpype(src, out_v)), min(wall_p, run_pixelpen(src, out_p))
            (up_v, down_v, _), (up_p, down_p, n_p) = measure(out_v), measure(out_p)
            r_up, r_wall = up_p / up_v, wall_p / wall_v
            ok = "met" if r_up <= PEN_UP_GOAL and r_wall <= WALL_GOAL else "MISSED"
            print(f"{name:18s} {src.stat().st_size / 1000:6.0f} {n_p:7d} {up_v:12,.0f} {up_p:14,.0f} "
                  f"{wall_v:8.2f} {wall_p:10.2f} {r_up:7.3f} {r_wall:6.2f}  {ok}", flush=True)
            if abs(down_p - down_v) > 1e-3 * max(down_v, 1.0):
                print(f"  warning: pen-down differs: vpype {down_v:.1f} mm, pixelpen {down_p:.1f} mm")
    return 0


if __name__ == "__main__":
    sys.exit(main())

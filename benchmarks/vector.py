"""Benchmark pixelpen's plot optimiser against vpype's ``linesort`` (and ``linemerge`` + ``linesort``).

Run by hand: ``python3 benchmarks/vector.py [--quick] [--budget S] [--svg FILE ...]``; needs the ``bench``
extra (``pip install vpype``). Every case is optimised by both tools in this one process, and both results
are measured the same way: pen-up travel from (0, 0) in mm, the estimated plot time under one motion model
(``pixelpen.vector.motion.estimate_time`` with the ``axidraw_v3`` profile: pen-up moves are rest-to-rest
trapezoids at 200 mm/s and 400 mm/s², as in shared/reference/plotters.md §4), and wall time. Inputs follow
plotters.md §4: random 1–5 mm segments in a 300 × 200 mm area with seed 0 (vpype's greedy gives
17,022 mm / 50,448 mm pen-up on 10k / 100k of them), random 8-vertex walks, a page of Hershey text, and
any SVG given. Ratios are pixelpen / vpype (below 1 is better for pixelpen).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Callable

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from pixelpen.vector.displaylist import DisplayList  # noqa: E402
from pixelpen.vector.motion import estimate_time  # noqa: E402
from pixelpen.vector.optimize import optimize  # noqa: E402
from pixelpen.vector.order import order_paths  # noqa: E402
from pixelpen.vector.profiles import load_profile  # noqa: E402

PROFILE = load_profile("axidraw_v3")
MERGE_MM = 0.05  # vpype linemerge's default tolerance


def random_segments(n: int, seed: int = 0) -> list[np.ndarray]:
    """``n`` segments 1–5 mm long at uniform random places and angles in 300 × 200 mm (plotters.md §4)."""
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(0, 300, n), rng.uniform(0, 200, n)
    length, angle = rng.uniform(1, 5, n), rng.uniform(0, 2 * np.pi, n)
    start = np.column_stack([x, y])
    end = start + length[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    return list(np.stack([start, end], axis=1))


def random_walks(n: int, vertices: int = 8, seed: int = 0) -> list[np.ndarray]:
    """``n`` random walks of ``vertices`` points, steps 1–5 mm in random directions, from anywhere in 300 × 200 mm."""
    rng = np.random.default_rng(seed)
    start = np.column_stack([rng.uniform(0, 300, n), rng.uniform(0, 200, n)])
    steps = rng.uniform(1, 5, (n, vertices - 1))[..., None] * _unit(rng.uniform(0, 2 * np.pi, (n, vertices - 1)))
    return list(np.concatenate([start[:, None], start[:, None] + np.cumsum(steps, axis=1)], axis=1))


def _unit(angle: np.ndarray) -> np.ndarray:
    return np.stack([np.cos(angle), np.sin(angle)], axis=-1)


def text_page() -> list[np.ndarray] | None:
    """An A4 page of Hershey text (2.5 mm capitals), or None when ``pixelpen.vector.font`` is not there."""
    try:
        from pixelpen.vector.font import text_strokes
    except ImportError:
        return None
    rng = np.random.default_rng(0)
    words = ("plot pen paper ink vector raster stroke path line curve point hatch font order merge travel "
             "lift drop carousel servo motor step speed corner junction plan time").split()
    lines = [" ".join(rng.choice(words, 12)) for _ in range(62)]
    return text_strokes("\n".join(lines), position=(10.0, 287.0), height=2.5, valign="top", font="futural")


def svg_strokes(path: str) -> list[np.ndarray]:
    """The polylines (mm) of an SVG file, read by pixelpen's importer."""
    from pixelpen.vector.svgimport import read_svg

    dl = read_svg(path)
    return [s * dl.unit_mm for s in dl.strokes()]


def measure(dl: DisplayList) -> tuple[float, float, float]:
    """Pen-up mm from (0, 0), estimated total plot time and pen-up time (s) of ``dl`` (in mm)."""
    t = estimate_time(dl, PROFILE, home=(0.0, 0.0), return_home=False)
    return t.pen_up_mm, t.total, t.pen_up


def vpype_run(polylines: list[np.ndarray], merge: bool) -> tuple[DisplayList, float]:
    """vpype ``[linemerge] linesort`` on one layer; returns the result (mm) and the wall time."""
    import vpype as vp
    from vpype_cli.operations import linesort

    sort = getattr(linesort.callback, "__wrapped__", None)
    if sort is None:
        raise SystemExit("this vpype has no undecorated linesort (vpype_cli.operations.linesort.callback.__wrapped__)")
    lc = vp.LineCollection([p[:, 0] + 1j * p[:, 1] for p in polylines])
    t0 = time.perf_counter()
    if merge:
        lc.merge(tolerance=MERGE_MM, flip=True)
    lc = sort(lc, no_flip=False, two_opt=False, passes=250)
    wall = time.perf_counter() - t0
    return DisplayList.from_polylines([np.column_stack([ln.real, ln.imag]) for ln in lc]), wall


def pixelpen_run(polylines: list[np.ndarray], merge: bool, budget: float) -> tuple[DisplayList, float]:
    """pixelpen's optimiser (ordering by pen-up time under the profile); returns the result and the wall time."""
    dl = DisplayList.from_polylines(polylines)
    t0 = time.perf_counter()
    if merge:
        out = optimize(dl, merge=MERGE_MM, dedupe=False, time_budget=budget, profile=PROFILE)
    else:
        out = order_paths(dl, time_budget=budget, profile=PROFILE)
    return out, time.perf_counter() - t0


def run_case(name: str, polylines: list[np.ndarray], budget: float | None) -> None:
    """Optimise one input with both tools (plain sort, then merge + sort) and print the comparison."""
    before = measure(DisplayList.from_polylines(polylines))
    print(f"{name}: {len(polylines)} paths, as given: pen-up {before[0]:,.0f} mm, time {before[1]:,.0f} s", flush=True)
    for merge in (False, True):
        ref, ref_wall = vpype_run(polylines, merge)
        # by default pixelpen gets 90 % of vpype's wall time for the whole call
        mine, wall = pixelpen_run(polylines, merge, 0.9 * ref_wall if budget is None else budget)
        (ru, rt, rp), (mu, mt, mp) = measure(ref), measure(mine)
        label = "linemerge+linesort" if merge else "linesort"
        print(f"  {label:19s} vpype    {ru:11,.0f} mm {rt:9,.0f} s (pen-up {rp:7,.0f} s) {ref_wall:6.2f} s wall,"
              f" {len(ref)} paths")
        print(f"  {'':19s} pixelpen {mu:11,.0f} mm {mt:9,.0f} s (pen-up {mp:7,.0f} s) {wall:6.2f} s wall,"
              f" {len(mine)} paths")
        print(f"  {'':19s} ratio    {mu / ru:11.3f}    {mt / rt:9.3f}   (pen-up {mp / rp:7.3f})"
              f"   {wall / ref_wall:6.2f}", flush=True)


def main(argv: list[str] | None = None) -> int:
    """Run the cases and print the comparison table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the 100,000-segment case")
    ap.add_argument("--budget", type=float, default=None,
                    help="pixelpen time budget in seconds (default: 90%% of vpype's wall time per case)")
    ap.add_argument("--svg", nargs="*", default=[], help="SVG files to add as cases")
    args = ap.parse_args(argv)
    try:
        import vpype  # noqa: F401
    except ImportError:
        print("vpype is not installed: pip install vpype (the 'bench' extra)", file=sys.stderr)
        return 2
    cases: list[tuple[str, Callable[[], list[np.ndarray] | None]]] = [
        ("10k random segments", lambda: random_segments(10_000)),
        ("100k random segments", lambda: random_segments(100_000)),
        ("5k random 8-vertex walks", lambda: random_walks(5_000)),
        ("A4 page of Hershey text", text_page),
    ]
    if args.quick:
        cases = [c for c in cases if not c[0].startswith("100k")]
    cases += [(f"SVG {p}", lambda p=p: svg_strokes(p)) for p in args.svg]
    for name, make in cases:
        polylines = make()
        if polylines is None:
            print(f"{name}: skipped (pixelpen.vector.font is not available)")
            continue
        run_case(name, polylines, args.budget)
    return 0


if __name__ == "__main__":
    sys.exit(main())

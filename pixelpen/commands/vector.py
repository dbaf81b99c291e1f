"""Vector commands: ``optimize`` (reorder/merge an SVG for plotting), ``stats`` (plot figures), ``preview`` (PNG/SVG)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from ..errors import PixelpenError


def _guarded(name: str, run: Callable[[argparse.Namespace], int]) -> Callable[[argparse.Namespace], int]:
    """Wrap a command so that pixelpen and file errors print one line to stderr and give exit status 2."""

    def func(args: argparse.Namespace) -> int:
        try:
            return run(args)
        except (PixelpenError, OSError) as exc:
            print(f"pixelpen {name}: error: {exc}", file=sys.stderr)
            return 2

    func.__doc__ = run.__doc__
    return func


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def run_optimize(args: argparse.Namespace) -> int:
    """Read an SVG, optimise its plotting order, write the result and print before/after figures to stderr."""
    from ..vector.optimize import optimize
    from ..vector.stats import format_stats, plot_stats
    from ..vector.svgimport import read_svg, write_svg

    profile = None
    if args.device is not None:
        from ..vector.profiles import load_profile

        profile = load_profile(args.device)
    dl = read_svg(args.input, tolerance=args.tolerance)
    before = plot_stats(dl, profile)
    per_mm = 1.0 / dl.unit_mm  # the optimiser's lengths are in display-list units (mm for SVG input)
    out = optimize(
        dl, merge=None if args.merge is None else args.merge * per_mm, reverse=not args.no_reverse,
        simplify=None if args.simplify is None else args.simplify * per_mm,
        time_budget=args.time_budget, across_layers=args.across_layers, profile=profile,
    )
    after = plot_stats(out, profile)
    write_svg(out, args.output)
    print(f"before ({args.input}):\n{format_stats(before)}\n", file=sys.stderr)
    print(f"after ({args.output}):\n{format_stats(after)}", file=sys.stderr)
    return 0


def run_stats(args: argparse.Namespace) -> int:
    """Print plot statistics of an SVG: distances, lifts, pen changes and time, per layer."""
    from ..vector.stats import format_stats, plot_stats, stats_json
    from ..vector.svgimport import read_svg

    stats = plot_stats(read_svg(args.input, tolerance=args.tolerance), args.device)
    print(stats_json(stats) if args.json else format_stats(stats))
    return 0


def run_preview(args: argparse.Namespace) -> int:
    """Render an SVG's plot as a PNG or SVG preview with pen-up travel."""
    from ..vector.preview import render_preview
    from ..vector.svgimport import read_svg

    dl = read_svg(args.input, tolerance=args.tolerance)
    render_preview(dl, args.output, size_px=args.size, show_travel=not args.no_travel, pen_width_mm=args.pen_width)
    print(f"wrote {args.output}", file=sys.stderr)
    return 0


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", metavar="FILE.svg", help="SVG drawing (millimetres; Inkscape layers or stroke colours)")
    p.add_argument("--tolerance", type=_positive, default=0.05, metavar="MM",
                   help="curve flattening tolerance in mm (default 0.05)")


def add_optimize(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``pixelpen optimize IN.svg -o OUT.svg``."""
    p = subparsers.add_parser("optimize", help="reorder, reverse, merge and simplify an SVG's paths for plotting")
    _common(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT.svg", help="optimised SVG to write")
    p.add_argument("--no-reverse", action="store_true", help="never draw a path backwards")
    p.add_argument("--merge", type=_positive, default=None, metavar="TOL_MM",
                   help="join paths whose ends are within TOL_MM")
    p.add_argument("--simplify", type=_positive, default=None, metavar="TOL_MM",
                   help="drop points that deviate less than TOL_MM")
    p.add_argument("--time-budget", type=_positive, default=1.0, metavar="S",
                   help="seconds to spend improving the order (default 1)")
    p.add_argument("--across-layers", action="store_true", help="order paths across layers, not layer by layer")
    p.add_argument("--device", default=None, metavar="PROFILE", help="device profile for the time estimates")
    p.set_defaults(func=_guarded("optimize", run_optimize))
    return p


def add_stats(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``pixelpen stats FILE.svg [--device PROFILE] [--json]``."""
    p = subparsers.add_parser("stats", help="pen-down/pen-up distance, lifts, pen changes and plot time of an SVG")
    _common(p)
    p.add_argument("--device", default=None, metavar="PROFILE",
                   help="device profile name or TOML path for the time estimate (default axidraw_v3)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.set_defaults(func=_guarded("stats", run_stats))
    return p


def add_preview(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``pixelpen preview FILE.svg -o preview.png``."""
    p = subparsers.add_parser("preview", help="render an SVG's plot, with pen-up travel, to PNG or SVG")
    _common(p)
    p.add_argument("-o", "--output", required=True, metavar="PREVIEW.png", help="preview file (.png or .svg)")
    p.add_argument("--size", type=int, default=None, metavar="PX", help="longest side in pixels (default 1000)")
    p.add_argument("--pen-width", type=_positive, default=None, metavar="MM", help="draw strokes this wide")
    p.add_argument("--no-travel", action="store_true", help="do not draw pen-up moves")
    p.set_defaults(func=_guarded("preview", run_preview))
    return p


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the vector subcommands (optimize, stats, preview) to the ``pixelpen`` parser."""
    add_optimize(subparsers)
    add_stats(subparsers)
    add_preview(subparsers)

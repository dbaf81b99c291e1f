"""Vector commands: ``optimize`` (reorder/merge an SVG for plotting), ``stats`` (plot figures), ``preview`` (PNG/SVG).

``preview --device PROFILE`` is a dry run: the sheet, the plotter's hard-clip limits and the drawing as the
file places it on the sheet (the placement ``pixelpen plot`` uses without layout options), with the parts
that will be cut drawn in a warning colour.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

import numpy as np

from pixelpen.commands import argtypes
from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList


def run_optimize(args: argparse.Namespace) -> int:
    """Read an SVG, optimise its plotting order, write the result and print what changed to stderr."""
    from pixelpen.vector.optimize import OptimizeReport, optimize
    from pixelpen.vector.stats import format_stats, plot_stats
    from pixelpen.vector.svgimport import read_svg, write_svg

    profile = None
    if args.device is not None:
        from pixelpen.profiles import load_profile

        profile = load_profile(args.device)
    dl = read_svg(args.input, tolerance=args.tolerance)
    before = plot_stats(dl, profile)
    per_mm = 1.0 / dl.unit_mm  # the optimiser's lengths are in display-list units (mm for SVG input)
    report = OptimizeReport()
    out = optimize(
        dl, merge=None if args.merge is None else args.merge * per_mm, reverse=not args.no_reverse,
        simplify=None if args.simplify is None else args.simplify * per_mm, dedupe=not args.no_dedupe,
        time_budget=args.time_budget, across_layers=args.across_layers, profile=profile, report=report,
    )
    after = plot_stats(out, profile)
    write_svg(out, args.output)
    print(f"before ({args.input}):\n{format_stats(before)}\n", file=sys.stderr)
    print(f"after ({args.output}):\n{format_stats(after)}\n", file=sys.stderr)
    for line in report.lines():
        print(line, file=sys.stderr)
    return 0


def run_stats(args: argparse.Namespace) -> int:
    """Print plot statistics of an SVG: distances, lifts, pen changes and time, per layer."""
    from pixelpen.vector.stats import format_stats, plot_stats, stats_json
    from pixelpen.vector.svgimport import read_svg

    stats = plot_stats(read_svg(args.input, tolerance=args.tolerance), args.device)
    print(stats_json(stats) if args.json else format_stats(stats))
    return 0


def run_preview(args: argparse.Namespace) -> int:
    """Render an SVG's plot as a PNG or SVG preview with pen-up travel; with ``--device``, on the plotter's sheet."""
    from pixelpen.vector.preview import render_preview
    from pixelpen.vector.svgimport import read_svg

    if args.device is not None:
        for line in _device_preview(args):
            print(line, file=sys.stderr)
    else:
        if args.paper is not None:
            raise ConfigError("--paper needs --device (the paper is one of the device profile's)")
        dl = read_svg(args.input, tolerance=args.tolerance)
        render_preview(dl, args.output, size_px=args.size, show_travel=not args.no_travel,
                       pen_width_mm=args.pen_width)
    print(f"wrote {args.output}", file=sys.stderr)
    return 0


PREVIEW_SCHEMES = {"ebb": "axidraw", "grbl": "grbl", "hpgl": "hp7475a"}
"""The plotter driver that places a drawing for a device profile of each protocol (unless named after the profile)."""


def _outside(dl: DisplayList, size: tuple[float, float]) -> DisplayList:
    """The parts of the strokes outside the rectangle 0..W x 0..H (device units): clipped to four bands around it."""
    from pixelpen import geometry as geo

    if not len(dl):
        return dl
    w, h = float(size[0]), float(size[1])
    lo, hi = dl.points.min(axis=0), dl.points.max(axis=0)
    big = float(max(np.abs(lo).max(), np.abs(hi).max(), w, h)) * 2.0 + 1.0
    bands = [(-big, -big, 0.0, big), (w, -big, big, big), (0.0, -big, w, 0.0), (0.0, h, w, big)]
    pieces: list[np.ndarray] = []
    owners: list[np.ndarray] = []
    for band in bands:
        got, owner = geo.clip_polylines(list(dl.strokes()), band, return_index=True)
        pieces += got
        owners.append(np.asarray(owner, np.int64))
    owner = np.concatenate(owners)
    return DisplayList.from_polylines(pieces, pens=dl.pens[owner] if len(owner) else 1,
                                      layers=dl.layers[owner] if len(owner) else 0, unit_mm=dl.unit_mm)


def _device_preview(args: argparse.Namespace) -> list[str]:
    """Draw the sheet, the hard-clip limits and the drawing on them (cut parts in a warning colour); say what is cut."""
    from pixelpen import geometry as geo
    from pixelpen.commands.plot import SHEET_COLOURS
    from pixelpen.devices.plotters.job import plotter_for
    from pixelpen.devices.plotters.layout import CUT_REPORT_MM, Layout, clip_to_device, load_drawing, sheet_to_device
    from pixelpen.display.registry import display_class
    from pixelpen.profiles import load_profile
    from pixelpen.urls import format_url
    from pixelpen.vector.preview import CUT_COLOUR, render_preview

    profile = load_profile(args.device)
    try:
        scheme = profile.name if display_class(profile.name) else None
    except ConfigError:
        scheme = PREVIEW_SCHEMES.get(profile.protocol)
    if scheme is None:
        raise ConfigError(f"profile {profile.name}: protocol {profile.protocol!r} has no plotter driver to place a "
                          f"drawing with (known: {', '.join(sorted(PREVIEW_SCHEMES))})")
    options = {"profile": args.device} | ({} if args.paper is None else {"paper": args.paper})
    display = plotter_for(format_url("sim", scheme, options))
    to_sheet = geo.invert(sheet_to_device(display))
    whole = load_drawing(args.input, display, tolerance=args.tolerance)
    inside, cut = clip_to_device(whole, display.capabilities.size)
    w, h = Layout().page_size(display)
    corners = geo.apply(to_sheet, np.array([[0.0, 0.0], display.capabilities.size]))
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    limits = (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))

    def on_sheet(dl: DisplayList) -> DisplayList:
        return dataclasses.replace(dl, points=geo.apply(to_sheet, dl.points) if len(dl.points) else dl.points,
                                   unit_mm=1.0)

    home = tuple(geo.apply(to_sheet, np.asarray(profile.home, float).reshape(1, 2))[0])
    render_preview(on_sheet(inside), args.output, size_px=args.size, show_travel=not args.no_travel, home=home,
                   pen_width_mm=args.pen_width or profile.pen_width_mm,
                   frames=[((0.0, 0.0, w, h), SHEET_COLOURS[0]), (limits, SHEET_COLOURS[1])],
                   cut=on_sheet(_outside(whole, display.capabilities.size)))
    total_mm, cut_mm = whole.pen_down_length() * whole.unit_mm, cut * whole.unit_mm
    lines = [f"sheet: {w:g} x {h:g} mm (paper {display.paper.name} of {profile.name}, grey); the plotter reaches "
             f"x {limits[0]:.1f}..{limits[2]:.1f}, y {limits[1]:.1f}..{limits[3]:.1f} mm from its top left (blue)"]
    if cut_mm > CUT_REPORT_MM:
        share = 100.0 * cut_mm / total_mm
        lines.append(f"cut: {cut_mm:.1f} mm of {total_mm:.1f} mm of lines ({share:.1f} %) lie outside the limits "
                     f"and will not be drawn (shown in orange, {CUT_COLOUR})")
    else:
        lines.append(f"cut: nothing; all {total_mm:.1f} mm of lines lie within the limits")
    return lines


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", metavar="FILE.svg", help="SVG drawing (millimetres; Inkscape layers or stroke colours)")
    p.add_argument("--tolerance", type=argtypes.positive, default=0.05, metavar="MM",
                   help="curve flattening tolerance in mm (default 0.05)")


def add_optimize(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``pixelpen optimize IN.svg -o OUT.svg``."""
    p = subparsers.add_parser("optimize", help="reorder, reverse, merge and simplify an SVG's paths for plotting")
    _common(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT.svg", help="optimised SVG to write")
    p.add_argument("--no-reverse", action="store_true", help="never draw a path backwards")
    p.add_argument("--merge", type=argtypes.positive, default=None, metavar="TOL_MM",
                   help="join paths whose ends are within TOL_MM")
    p.add_argument("--simplify", type=argtypes.positive, default=None, metavar="TOL_MM",
                   help="drop points that deviate less than TOL_MM")
    p.add_argument("--time-budget", type=argtypes.positive, default=None, metavar="S",
                   help="most seconds to spend improving the order (default: adaptive, stopping when the gains stall;"
                        " about 30 us per path)")
    p.add_argument("--no-dedupe", action="store_true",
                   help="keep lines drawn twice in one layer and pen (other layers and pens are never deduplicated)")
    p.add_argument("--across-layers", action="store_true", help="order paths across layers, not layer by layer")
    p.add_argument("--device", default=None, metavar="PROFILE", help="device profile for the time estimates")
    p.set_defaults(func=run_optimize)
    return p


def add_stats(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``pixelpen stats FILE.svg [--device PROFILE] [--json]``."""
    p = subparsers.add_parser("stats", help="pen-down/pen-up distance, lifts, pen changes and plot time of an SVG")
    _common(p)
    p.add_argument("--device", default=None, metavar="PROFILE",
                   help="device profile name or TOML path for the time estimate (default axidraw_v3)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.set_defaults(func=run_stats)
    return p


def add_preview(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``pixelpen preview FILE.svg -o preview.png``."""
    p = subparsers.add_parser("preview", help="render an SVG's plot, with pen-up travel, to PNG or SVG")
    _common(p)
    p.add_argument("-o", "--output", required=True, metavar="PREVIEW.png", help="preview file (.png or .svg)")
    p.add_argument("--size", type=int, default=None, metavar="PX", help="longest side in pixels (default 1000)")
    p.add_argument("--pen-width", type=argtypes.positive, default=None, metavar="MM", help="draw strokes this wide")
    p.add_argument("--no-travel", action="store_true", help="do not draw pen-up moves")
    p.add_argument("--device", default=None, metavar="PROFILE",
                   help="dry run on this plotter: show the sheet, its hard-clip limits and what will be cut")
    p.add_argument("--paper", default=None, metavar="NAME", help="paper of the device profile (default its own)")
    p.set_defaults(func=run_preview)
    return p


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the vector subcommands (optimize, stats, preview) to the ``pixelpen`` parser."""
    add_optimize(subparsers)
    add_stats(subparsers)
    add_preview(subparsers)

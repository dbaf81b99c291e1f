"""Core commands: ``devices`` (what pixelpen knows and what is plugged in), ``draw`` and ``demo``.

``demo`` draws the reference scene on the file displays, plots it on the simulated plotters and shows it on
each simulated panel whose simulator is registered (:data:`DEMO_PANELS`), then plays a short animation there
(a cursor moving, a clock's digits changing: :class:`pixelpen.animation.PanelAnimation`), in simulated time;
it writes each panel's glass (``panel-MODEL.png``), the animation's glass frames (``panel-MODEL.gif``) and
the frame statistics of all panels (``panels.json``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import re
import sys
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from pixelpen.animation import PanelAnimation
from pixelpen.commands.plot import plot_demo
from pixelpen.display.base import Display
from pixelpen.display.pictfile import load_picture
from pixelpen.display.registry import known_schemes, open_display
from pixelpen.drivers.discovery import DiscoveredDevice, discover
from pixelpen.errors import ConfigError
from pixelpen.options import OptionSpec, describe
from pixelpen.scene import draw_reference, show_reference
from pixelpen.urls import format_url

log = logging.getLogger(__name__)

DEMO_PANELS: tuple[tuple[str, dict[str, str]], ...] = (
    ("st7789", {"size": "240x240"}),
    ("ili9341", {"size": "320x240", "rotation": "90"}),
    ("st7735", {"size": "128x160"}),
    ("ssd1306", {"size": "128x64"}),
)
"""The simulated panels the demo shows the scene and the animation on (those whose simulator is registered)."""
ANIMATION_FRAMES = 30
"""Frames of the panel demo's animation."""

_ROLE = re.compile(r":[a-z]+(?::[a-z]+)?:`(?:([^`<]*?)\s*<[^`>]*>|~(?:[\w.]*\.)?([^`]*)|([^`]*))`")
_LITERAL = re.compile(r"``(.+?)``|`([^`]+)`|\*\*(.+?)\*\*")


OptionSection = tuple[str, Sequence[OptionSpec[Any]]]
"""A titled group of option specs that ``pixelpen devices`` lists after the schemes'."""


def option_sections() -> list[OptionSection]:
    """The simulated line's options, then every registered simulator's (imported here only, for the listing)."""
    from pixelpen.sim.base import simulator_models, simulator_options
    from pixelpen.sim.transports.options import TRANSPORT_OPTIONS

    return [
        ("options of every sim: and sim:// URL (the simulated line)", TRANSPORT_OPTIONS),
        *((f"options of the {model} simulator (sim:{model}, sim://{model})", simulator_options(model))
          for model in simulator_models()),
    ]


def plain_text(text: str) -> str:
    """reStructuredText inline markup as plain words: ``code``, :func:`~a.b` (b), `title <target>` (title)."""
    text = _ROLE.sub(lambda m: next(g for g in m.groups() if g is not None), text)
    text = _LITERAL.sub(lambda m: next(g for g in m.groups() if g is not None), text)
    return re.sub(r"::$", ":", text)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the core subcommands to the ``pixelpen`` parser."""
    p = sub.add_parser("devices", help="list known device schemes and the devices actually present")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--no-probe", action="store_true", help="do not look for attached hardware")
    p.set_defaults(func=cmd_devices)

    p = sub.add_parser("draw", help="draw a picture file onto one or more displays")
    p.add_argument("picture", help="picture file (pixelpen JSON, see docs/picture-format.md)")
    p.add_argument("--to", action="append", required=True, metavar="URL",
                   help="display URL, e.g. png:out.png (repeatable)")
    p.set_defaults(func=cmd_draw)

    p = sub.add_parser("demo", help="draw the reference scene on every display pixelpen has (simulated devices too)")
    p.add_argument("-o", "--out", default="pixelpen-demo", help="output folder (default: ./pixelpen-demo)")
    p.set_defaults(func=cmd_demo)


def cmd_devices(args: argparse.Namespace) -> int:
    """Print the schemes with their options, the other option groups, then the serial, USB and HID devices present."""
    schemes: dict[str, dict[str, Any]] = {
        name: {"class": cls.__name__, "description": plain_text((cls.__doc__ or "").strip().partition("\n")[0]),
               "options": scheme_options(cls), "simulated": cls.simulated}
        for name, cls in known_schemes().items()
    }
    sections = {title: {name: plain_text(text) for name, text in describe(specs)} for title, specs in option_sections()}
    present: list[dict[str, object]] = []
    if not args.no_probe:
        present = [_record(device) for device in discover()]
    if args.json:
        json.dump({"schemes": schemes, "options": sections, "present": present}, sys.stdout, indent=2, default=str)
        print()
        return 0
    print("Known schemes:")
    for name, info in schemes.items():
        sim = f"  (sim:{name} too)" if info["simulated"] else ""
        print(f"  {name + ':':10} {info['description']}{sim}")
        _print_options(info["options"])
    for title, options in sections.items():
        print(f"\n{title[0].upper()}{title[1:]}:")
        _print_options(options)
    print("\nDevices present:" if present else "\nDevices present: none found")
    for rec in present:
        print("  " + "  ".join(f"{k}={v}" for k, v in rec.items() if v not in (None, "")))
    return 0


def scheme_options(cls: type[Display]) -> dict[str, str]:
    """A display's URL options as name -> plain help text, from its ``OPTIONS`` specs."""
    return {name: plain_text(text) for name, text in describe(cls.OPTIONS)}


def _print_options(options: dict[str, str]) -> None:
    """One ``?name=  help`` line per option."""
    for name, text in options.items():
        print(f"      ?{name}=  {text}")


def _record(device: DiscoveredDevice) -> dict[str, object]:
    """A discovered device as a flat dict, USB IDs as VID:PID hex."""
    rec = {k: v for k, v in asdict(device).items() if k not in ("vid", "pid", "identity") and v not in (None, "")}
    if device.vid is not None and device.pid is not None:
        rec["usb_id"] = f"{device.vid:04X}:{device.pid:04X}"
    if device.identity is not None:
        rec["identity"] = str(device.identity)
    return rec


def cmd_draw(args: argparse.Namespace) -> int:
    """Draw a picture file onto each URL given with --to."""
    picture = load_picture(args.picture)
    for url in args.to:
        with open_display(url) as display:
            if picture.window:
                display.window(*picture.window)
            display.draw(picture)
        print(f"drew {args.picture} on {url}", file=sys.stderr)
    return 0


def demo_targets(out: Path) -> list[str]:
    """The file displays the demo draws on (simulated plotters are plotted by ``plot_demo``)."""
    return [
        format_url("png", str(out / "scene.png"), {"size": "2080x1120"}),
        format_url("svg", str(out / "scene.svg"), {"size": "260x140mm"}),
    ]


def cmd_demo(args: argparse.Namespace) -> int:
    """Draw the reference scene on every display and print where the results are."""
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for url in demo_targets(out):
        with open_display(url) as display:
            draw_reference(display)
        print(f"  {url}", file=sys.stderr)
    for paper in plot_demo(out):
        print(f"  plotted on a simulated plotter: {paper}", file=sys.stderr)
    for r in panel_demo(out):
        print(f"  shown on a simulated panel: {r.url}: {r.glass}, {r.animation} ({r.frames} frames, "
              f"{r.bytes_per_frame:,.0f} bytes and {r.windows_per_frame:.1f} windows a frame, "
              f"{r.fps_at_bus_limit:,.0f} fps at the bus limit; full frames {r.full_frame_fps_at_bus_limit:.1f} fps)",
              file=sys.stderr)
    print(f"pixelpen demo: the reference scene was drawn into {out.resolve()}/")
    for path in sorted(out.iterdir()):
        print(f"  {path}")
    return 0


@dataclass
class PanelDemoResult:
    """What the demo did on one panel: files written and the animation's frame statistics."""

    url: str
    glass: str
    animation: str
    frames: int
    bytes_per_frame: float
    windows_per_frame: float
    bus_ms_per_frame: float
    host_ms_per_frame: float
    fps_at_bus_limit: float
    """Animation frames a second the bus carries (its wire time per frame)."""
    full_frame_fps_at_bus_limit: float
    """Full frames a second the bus carries (the bandwidth estimator)."""


def panel_demo(out: Path, panels: Sequence[tuple[str, dict[str, str]]] = DEMO_PANELS) -> list[PanelDemoResult]:
    """Show the reference scene and the PanelAnimation on each simulated panel of ``panels``; write
    ``OUT/panel-MODEL.png`` (the scene's glass), ``OUT/panel-MODEL.gif`` (the animation) and ``OUT/panels.json``."""
    from pixelpen.devices.panels.base import PanelDisplay
    from pixelpen.devices.panels.pacing import estimate_bandwidth
    from pixelpen.raster.damage import Rect
    from pixelpen.sim.base import simulator_models

    results: list[PanelDemoResult] = []
    for model, options in panels:
        if model not in simulator_models():
            log.info("demo: no %s simulator registered; skipped", model)
            continue
        url = format_url("sim", model, options)
        with open_display(url) as display:
            if not isinstance(display, PanelDisplay):
                raise ConfigError(f"demo panel {model!r} ({url}): opened a {type(display).__name__}, "
                                  "not a panel display")
            sim: Any = display.simulator
            show_reference(display)
            glass = out / f"panel-{model}.png"
            sim.glass().save(glass)
            before = dataclasses.replace(display.stats)
            animation = PanelAnimation(display)
            images = []
            for _ in range(ANIMATION_FRAMES):
                animation.step()
                images.append(sim.glass().convert("RGB"))
            stats, n = display.stats, display.stats.frames - before.frames
            bus = display.wiring.bus
            full = display.cost.window(Rect(0, 0, display.canvas.width, display.canvas.height))
            limit = estimate_bandwidth(bus.kind, bus.clock_hz, full.bytes, full.transfers).max_fps
        gif = out / f"panel-{model}.gif"
        images[0].save(gif, save_all=True, append_images=images[1:], duration=100, loop=0)
        bus_s = (stats.bus_seconds - before.bus_seconds) / max(n, 1)
        results.append(PanelDemoResult(
            url, glass.name, gif.name, n, (stats.bytes - before.bytes) / max(n, 1),
            (stats.windows - before.windows) / max(n, 1), 1000 * bus_s,
            1000 * (stats.host_seconds - before.host_seconds) / max(n, 1), 1 / bus_s if bus_s else 0.0, limit))
    (out / "panels.json").write_text(json.dumps([asdict(r) for r in results], indent=2) + "\n")
    return results

"""Core commands: ``devices`` (what pixelpen knows and what is plugged in), ``draw`` and ``demo``.

``demo`` draws the reference scene on the file displays, plots it on the simulated plotters and shows it on
each simulated panel whose simulator is registered (:data:`DEMO_PANELS`), then plays a short animation there
(a cursor moving, a clock's digits changing: :class:`pixelpen.animation.PanelAnimation`), in simulated time;
it writes each panel's glass (``panel-MODEL.png``), the animation's glass frames (``panel-MODEL.gif``) and
the frame statistics of all panels (``panels.json``).  Its input part (:func:`input_demo`) records a simulated
tablet's signature and a trackball in hid-recorder files, replays the signature into strokes smoothed to
B-splines, drawn with a cursor echo on a simulated panel and plotted on a simulated plotter, and lets the
trackball move a locator over the reference scene, picking what lies under it (``input.json``).  Its 3D
part (:func:`scene3d_demo`) shows one 3D scene (:func:`demo_scene3d`: a cube, a sphere and a torus in
perspective) as a hidden-line drawing on a simulated plotter and shaded on a simulated panel.
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
from typing import TYPE_CHECKING, Any

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

if TYPE_CHECKING:
    from pixelpen.display.scene3d import Scene

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
INPUT_PANEL = ("st7789", {"size": "240x240"})
"""The simulated panel the input demo draws the signature and the locator on."""
INPUT_PLOTTER = "hp7475a"
"""The simulated plotter the input demo plots the smoothed signature on."""
SIGNATURE_TOLERANCE_MM = 0.5
"""How far the smoothed signature may stray from the pen's points."""
TABLET_MM = (224.0, 140.0)
"""The simulated tablet's active area (sim/hid/descriptors.py PEN_TABLET): the signature's world window."""
SCENE3D_PLOTTER = "hp7475a"
"""The simulated plotter the 3D scene is plotted on (hidden lines)."""
SCENE3D_PANEL = ("st7789", {"size": "240x240"})
"""The simulated panel the 3D scene is shaded on."""

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
        *((f"options of the {model} simulator (sim:{model})", simulator_options(model))
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
    inputs = input_schemes()
    present: list[dict[str, object]] = []
    if not args.no_probe:
        present = [_record(device) for device in discover()]
    if args.json:
        json.dump({"schemes": schemes, "inputs": inputs, "options": sections, "present": present}, sys.stdout,
                  indent=2, default=str)
        print()
        return 0
    print("Known schemes:")
    for name, info in schemes.items():
        sim = f"  (sim:{name} too)" if info["simulated"] else ""
        print(f"  {name + ':':10} {info['description']}{sim}")
        _print_options(info["options"])
    print("\nInput schemes (pixelpen.open_input):")
    for name, description in inputs.items():
        print(f"  {name + ':':10} {description}")
    for title, options in sections.items():
        print(f"\n{title[0].upper()}{title[1:]}:")
        _print_options(options)
    print("\nDevices present:" if present else "\nDevices present: none found")
    for rec in present:
        print("  " + "  ".join(f"{k}={v}" for k, v in rec.items() if v not in (None, "")))
    return 0


def input_schemes() -> dict[str, str]:
    """The input schemes of ``pixelpen.open_input``, each with the first line of its opener's docstring."""
    from pixelpen.input.registry import input_opener, input_scheme_names

    return {name: plain_text((input_opener(name).__doc__ or "").strip().partition("\n")[0])
            for name in input_scheme_names()}


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
    plotted, shown = scene3d_demo(out)
    print(f"  3D: a cube, a sphere and a torus in perspective, hidden lines plotted on {SCENE3D_PLOTTER}: "
          f"{plotted.name}; shaded on {SCENE3D_PANEL[0]}: {shown.name}", file=sys.stderr)
    try:
        result = input_demo(out)
    except Exception as exc:  # noqa: BLE001 - a missing input piece must not stop the rest of the demo
        log.warning("demo: the input part failed: %s", exc)
    else:
        print(f"  input: a tablet signature ({result.signature_reports} reports, {result.strokes} strokes, "
              f"{result.stroke_points} points) smoothed to {result.control_points} B-spline control points "
              f"(within {result.max_error_mm:.2f} mm), drawn on {result.panel} under a cursor echo "
              f"({result.echo_frames} frames, {result.echo_bytes_per_frame:,.0f} bytes a frame): "
              f"{result.signature_glass}; plotted: {result.signature_paper}", file=sys.stderr)
        print(f"  input: a trackball moved a locator over the reference scene ({result.trackball_reports} reports) "
              f"and picked {', '.join(result.picked) or 'nothing'}; passed over {len(result.hovered)} items: "
              f"{result.pick_glass}", file=sys.stderr)
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


@dataclass
class InputDemoResult:
    """What the input demo did: recordings replayed, the smoothed signature, the echo's frames, what was picked."""

    panel: str
    signature_recording: str
    signature_reports: int
    strokes: int
    stroke_points: int
    control_points: int
    max_error_mm: float
    echo_frames: int
    echo_bytes_per_frame: float
    signature_glass: str
    signature_paper: str
    trackball_recording: str
    trackball_reports: int
    picked: list[str]
    """What lay under the locator at each trackball button press (segment names, or primitive kinds)."""
    hovered: list[str]
    """Everything the locator passed over, in order, each once."""
    pick_glass: str


def record_simulated(url: str, path: Path, seconds: float) -> int:
    """Record the first ``seconds`` of the simulated HID device ``url`` (``sim:MODEL?...``) in a hid-recorder file;
    the number of reports."""
    from pixelpen.clock import SimulatedClock
    from pixelpen.drivers.recordings.hidrecorder import HidRecording, write_hid_recording
    from pixelpen.sim.base import create_simulator
    from pixelpen.urls import parse_url

    parsed = parse_url(url)
    sim: Any = create_simulator(parsed.target, clock=SimulatedClock(), **dict(parsed.options))
    sim.advance_to(seconds)
    timed = sim.take_timed_reports()
    start = timed[0][0] if timed else 0.0
    write_hid_recording(HidRecording(sim.info.get("product_string", parsed.target), "", 0x03,
                                     sim.info.get("vendor_id", 0), sim.info.get("product_id", 0),
                                     sim.report_descriptor, [(t - start, report) for t, report in timed]), path)
    return len(timed)


def _picked_name(hit: Any) -> str:
    """A pick result as the demo names it: the segment, or the primitive's kind and index."""
    return hit.segment or f"{type(hit.primitive).__name__.lower()} {hit.index}"


def input_demo(out: Path) -> InputDemoResult:
    """The input part of the demo (see the module docstring); writes ``OUT/tablet-signature.hid``,
    ``OUT/trackball.hid``, ``OUT/signature-panel.png``, ``OUT/signature-PLOTTER.png``, ``OUT/pick-panel.png``
    and ``OUT/input.json``."""
    import uuid

    from pixelpen.display.picture import Polyline, Style
    from pixelpen.input import open_input
    from pixelpen.input.echo import Echo
    from pixelpen.input.pick import Pick, PickRecord
    from pixelpen.input.queue import InputQueue
    from pixelpen.input.stroke import Stroke, StrokeValue
    from pixelpen.scene import PAGE, WORLD, reference_scene
    from pixelpen.sim.base import forget_simulator, named_simulator

    model, options = INPUT_PANEL
    panel_url = format_url("sim", model, options)
    signature, trackball = out / "tablet-signature.hid", out / "trackball.hid"
    signature_reports = record_simulated("sim:tablet?script=signature", signature, 8.0)
    trackball_reports = record_simulated("sim:trackball?script=signature", trackball, 8.0)

    strokes: list[StrokeValue] = []
    with open_display(panel_url) as panel:
        panel.window(0.0, 0.0, *TABLET_MM)
        sim: Any = panel.simulator  # type: ignore[attr-defined]
        echo = Echo(panel, interval=1 / 30)  # type: ignore[arg-type]
        before_frames, before_bytes = panel.stats.frames, panel.stats.bytes  # type: ignore[attr-defined]
        with open_input(f"replay:{signature}", display=panel) as tablet:
            queue = InputQueue([tablet])
            queue.attach(Stroke(panel, spacing=1.0, tolerance=SIGNATURE_TOLERANCE_MM, echo=echo), "event")
            while (event := queue.await_event(5.0)) is not None:  # a word takes up to 1.3 s
                if event.kind != "stroke":
                    continue
                strokes.append(event.value)
                with echo.hidden():
                    panel.draw(Polyline(event.value.points, Style(colour="grey")))
                    panel.draw(event.value.spline.primitive(Style(colour="cyan", width=0.4)))
        echo.close()
        frames = panel.stats.frames - before_frames  # type: ignore[attr-defined]
        echo_bytes = (panel.stats.bytes - before_bytes) / max(frames, 1)  # type: ignore[attr-defined]
        signature_glass = out / "signature-panel.png"
        sim.glass().save(signature_glass)

    ident = f"demo-input-{uuid.uuid4().hex[:8]}"
    signature_paper = out / f"signature-{INPUT_PLOTTER}.png"
    try:
        with open_display(format_url("sim", INPUT_PLOTTER, {"speed": "fast", "id": ident})) as plotter:
            plotter.window(0.0, 0.0, *TABLET_MM)
            for value in strokes:
                if value.spline is not None:
                    plotter.draw(value.spline.primitive())
        named_simulator(ident).save_paper(signature_paper)
    finally:
        forget_simulator(ident)

    picked: list[str] = []
    hovered: list[str] = []
    with open_display(panel_url) as panel:
        show_reference(panel)  # type: ignore[arg-type]
        panel.window(*WORLD)
        panel.viewport(0.0, 0.0, WORLD[2] / PAGE[2], 1.0)
        record = PickRecord(panel)
        record.add(reference_scene())
        echo = Echo(panel, shape="box", size=7, colour="magenta", interval=1 / 30)  # type: ignore[arg-type]
        with open_input(f"replay:{trackball}", display=panel) as ball:
            queue = InputQueue([ball])
            pick = queue.attach(Pick(record, aperture_mm=1.5, gain=0.45, echo=echo), "event")
            pick.locator.move_to(20.0, 40.0)
            while queue.pump(1.0):
                hit = pick.value()
                if hit is not None and _picked_name(hit) not in hovered:
                    hovered.append(_picked_name(hit))
                while (event := queue.await_event(0.0)) is not None:
                    if event.kind == "pick" and event.value is not None:
                        picked.append(_picked_name(event.value))
        pick_glass = out / "pick-panel.png"
        panel.simulator.glass().save(pick_glass)  # type: ignore[attr-defined]

    result = InputDemoResult(
        panel_url, signature.name, signature_reports, len(strokes), sum(len(v) for v in strokes),
        sum(len(v.spline.control_points) for v in strokes if v.spline is not None),
        max((v.spline.max_error for v in strokes if v.spline is not None), default=0.0), frames, echo_bytes,
        signature_glass.name, signature_paper.name, trackball.name, trackball_reports, picked, hovered,
        pick_glass.name)
    (out / "input.json").write_text(json.dumps(asdict(result), indent=2) + "\n")
    return result


def demo_scene3d() -> Scene:
    """The demo's 3D scene (millimetres, z up): a cube, a sphere and a torus, lit from above, left and behind."""
    from pixelpen.display.scene3d import Scene
    from pixelpen.geometry.mesh import Mesh
    from pixelpen.geometry.surfaces import Sphere, Torus

    scene = Scene(camera={"vrp": (0.0, 0.0, 10.0), "vpn": (1.0, -1.4, 0.9), "vup": (0.0, 0.0, 1.0),
                          "projection": "perspective", "z_prp": 260.0, "z_vp": 0.0, "near": 90.0, "far": -90.0})
    corners = [(x, y, z) for z in (0.0, 30.0) for y in (-15.0, 15.0) for x in (-60.0, -30.0)]
    cube = Mesh.from_polygons(corners, [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2),
                                        (1, 3, 7, 5)])
    scene.add_mesh(cube, material={"colour": (0.9, 0.3, 0.2), "ka": 0.3, "kd": 0.7})
    scene.add_surface(Sphere((5.0, 5.0, 18.0), 18.0),
                      material={"colour": (0.2, 0.5, 0.9), "ka": 0.2, "kd": 0.7, "ks": 0.5, "n": 30.0})
    scene.add_surface(Torus((50.0, 0.0, 8.0), 20.0, 8.0), material={"colour": (0.3, 0.8, 0.3), "ka": 0.2,
                                                                     "kd": 0.8, "ks": 0.3, "n": 15.0})
    scene.add_light("ambient", (1.0, 1.0, 1.0))
    scene.add_light("directional", (1.0, 1.0, 1.0), direction=(0.4, 0.8, -1.0))
    return scene


def scene3d_demo(out: Path) -> tuple[Path, Path]:
    """Plot :func:`demo_scene3d` with hidden lines removed on the simulated :data:`SCENE3D_PLOTTER` and shade it on
    the simulated :data:`SCENE3D_PANEL`; write ``OUT/paper3d-PLOTTER.png`` and ``OUT/panel3d-PANEL.png``."""
    import uuid

    from pixelpen.sim.base import forget_simulator, named_simulator

    scene = demo_scene3d()
    ident = f"demo-3d-{uuid.uuid4().hex[:8]}"
    paper = out / f"paper3d-{SCENE3D_PLOTTER}.png"
    try:
        with open_display(format_url("sim", SCENE3D_PLOTTER, {"speed": "fast", "id": ident})) as plotter:
            plotter.draw(scene)
        named_simulator(ident).save_paper(paper)
    finally:
        forget_simulator(ident)
    model, options = SCENE3D_PANEL
    glass = out / f"panel3d-{model}.png"
    with open_display(format_url("sim", model, options)) as panel:
        panel.draw(scene)
        panel.simulator.glass().save(glass)  # type: ignore[attr-defined]
    return paper, glass

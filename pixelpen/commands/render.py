"""The ``render`` command: a mesh file (OBJ, STL) as a 3D scene on any display.

``pixelpen render MODEL.obj --to URL [--to URL ...] [--camera VIEW | --camera KEY=VALUE ...] [--projection P]``:
the model is read by :func:`pixelpen.meshfiles.read_mesh` and drawn with ``display.draw(scene)``: shaded
through the z-buffer on raster displays, as hidden-line drawings on vector ones. The camera looks at the
centre of the model's bounding box from the view ``VIEW`` (one of :data:`VIEWS`; default ``three-quarter``),
with the view plane through the centre, near and far planes just outside the bounding sphere and, for a
perspective, the projection reference point :data:`PRP_RADII` radii from the centre. ``--camera KEY=VALUE``
items override any of the camera keys (``vrp``, ``vpn``, ``vup`` as ``x,y,z``; ``z_prp``, ``z_vp``, ``near``,
``far`` as numbers; ``alpha`` and ``phi`` in degrees). The display's window is fitted to the model.
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any

import numpy as np

from pixelpen.colour import parse_colour
from pixelpen.display.registry import open_display
from pixelpen.display.scene3d import CAMERA_KEYS, Scene
from pixelpen.errors import ConfigError, InvalidArgument
from pixelpen.geometry.mesh import Mesh
from pixelpen.geometry.viewing3d import CABINET, STANDARD_VIEWS
from pixelpen.options import check_known
from pixelpen.raster.shading import SHADING_MODES

Vector = tuple[float, float, float]

VIEWS: dict[str, tuple[Vector, Vector]] = {
    "three-quarter": ((1.0, 0.8, 1.4), (0.0, 1.0, 0.0)),
    "isometric": ((1.0, 1.0, 1.0), (0.0, 1.0, 0.0)),
    **STANDARD_VIEWS,
}
"""Named views as (vpn, vup): the viewer on the +vpn side of the model, vup up the page."""
PROJECTIONS = ("perspective", "parallel", "oblique")
"""The projections ``--projection`` offers."""
PRP_RADII = 3.0
"""Distance of a perspective's projection reference point from the model's centre, in bounding-sphere radii."""
OBLIQUE_PHI_DEGREES = 30.0
"""Default receding angle phi of an oblique view (alpha: the cabinet projection)."""
ANGLE_KEYS = ("alpha", "phi")
VECTOR_KEYS = ("vrp", "vpn", "vup")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``render`` subcommand to the ``pixelpen`` parser."""
    p = sub.add_parser("render", help="draw a mesh file (OBJ, STL) as a 3D scene on displays")
    p.add_argument("model", help="mesh file: .obj or .stl (text or binary)")
    p.add_argument("--to", action="append", required=True, metavar="URL",
                   help="display URL, e.g. png:out.png or sim:hp7475a (repeatable)")
    p.add_argument("--camera", action="append", default=[], metavar="VIEW|KEY=VALUE",
                   help=f"a view ({', '.join(VIEWS)}) or a camera key, e.g. vpn=1,1,1 or z_prp=300 "
                        "(repeatable; alpha and phi in degrees)")
    p.add_argument("--projection", choices=PROJECTIONS, default="perspective", help="default: perspective")
    p.add_argument("--shading", choices=SHADING_MODES, default="flat", help="default: flat")
    p.add_argument("--model-colour", default="#c0c0c0", metavar="COLOUR",
                   help="the model's colour (CSS colour; default #c0c0c0)")
    p.add_argument("--edges", choices=("features", "outlines", "none"), default="features",
                   help="edges drawn on vector displays (default: features: silhouettes, boundaries, creases)")
    p.set_defaults(func=cmd_render)


def parse_camera_items(items: list[str]) -> tuple[str, dict[str, Any]]:
    """The view name and the camera keys given by ``--camera`` items (angles converted to radians)."""
    view, keys = "three-quarter", {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep:
            if name not in VIEWS:
                raise ConfigError(f"--camera {item!r}: not a view ({', '.join(VIEWS)}) nor KEY=VALUE")
            view = name
            continue
        check_known(CAMERA_KEYS, [name], f"--camera {item!r}", kind="camera key", error=ConfigError)
        if name == "projection":
            raise ConfigError("--camera projection=...: use --projection")
        try:
            numbers = [float(v) for v in value.split(",")]
        except ValueError:
            raise ConfigError(f"--camera {item!r}: {name} takes numbers, got {value!r}") from None
        if len(numbers) != (3 if name in VECTOR_KEYS else 1) or not all(map(math.isfinite, numbers)):
            what = "three numbers x,y,z" if name in VECTOR_KEYS else "one finite number"
            raise ConfigError(f"--camera {item!r}: {name} takes {what}")
        keys[name] = tuple(numbers) if name in VECTOR_KEYS else (
            math.radians(numbers[0]) if name in ANGLE_KEYS else numbers[0])
    return view, keys


def model_camera(mesh: Mesh, view: str, projection: str, overrides: dict[str, Any]) -> dict[str, Any]:
    """The camera dict that frames ``mesh`` from ``view`` (module docstring), with ``overrides`` applied."""
    low, high = mesh.bounds()
    centre = (low + high) / 2.0
    radius = max(float(np.linalg.norm(high - low)) / 2.0, 1e-9)
    vpn, vup = VIEWS[view]
    camera: dict[str, Any] = {"vrp": tuple(float(c) for c in centre), "vpn": vpn, "vup": vup,
                              "projection": projection, "near": 1.01 * radius, "far": -1.01 * radius}
    if projection == "perspective":
        camera["z_prp"] = PRP_RADII * radius
    if projection == "oblique":
        camera["alpha"], camera["phi"] = CABINET, math.radians(OBLIQUE_PHI_DEGREES)
    camera.update(overrides)
    return camera


def model_scene(mesh: Mesh, camera: dict[str, Any], *, colour: object = "#c0c0c0", shading: str = "flat",
                edges: str = "features") -> Scene:
    """A scene of one mesh under a soft ambient light and a key light from the viewer's upper left."""
    scene = Scene(camera=camera)
    rgb = tuple(c / 255.0 for c in parse_colour(colour))
    scene.add_mesh(mesh, material={"colour": rgb, "ka": 0.3, "kd": 0.7, "ks": 0.2, "n": 20.0},
                   shading=shading, edges=edges)
    u, v, n = (scene.camera.world_to_view[i, :3] for i in range(3))
    scene.add_light("ambient", (1.0, 1.0, 1.0))
    scene.add_light("directional", (1.0, 1.0, 1.0), direction=tuple(float(c) for c in 0.5 * u - 0.5 * v - n))
    return scene


def cmd_render(args: argparse.Namespace) -> int:
    """Read the model and draw it on each URL given with --to."""
    from pixelpen.meshfiles import read_mesh

    view, keys = parse_camera_items(args.camera)
    mesh = read_mesh(args.model)
    if not len(mesh.faces):
        raise InvalidArgument(f"{args.model}: the model has no faces to draw")
    scene = model_scene(mesh, model_camera(mesh, view, args.projection, keys), colour=args.model_colour,
                        shading=args.shading, edges=args.edges)
    for url in args.to:
        with open_display(url) as display:
            display.draw(scene)
        print(f"rendered {args.model} ({len(mesh.faces)} triangles) on {url}", file=sys.stderr)
    return 0

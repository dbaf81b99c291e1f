"""A 3D scene: a camera, meshes and surfaces with their materials, and lights; drawn by ``display.draw(scene)``.

``Scene(camera=dict(vrp=..., vpn=..., vup=..., projection=..., z_prp=..., z_vp=..., near=..., far=...))``
(the keys of :data:`CAMERA_KEYS`; an unknown key is refused naming it). The camera follows Hearn & Baker:
world -> viewing coordinates (u, v, n) by :func:`pixelpen.geometry.viewing3d.view_orientation`, the viewer on
the +n side looking towards −n, near > far as n coordinates; the view-plane window is the display's 2D
window (``display.window(...)``), and the normalised view volume is
:class:`pixelpen.geometry.viewing3d.ViewVolume`. Meshes are counter-clockwise seen from outside (front
faces), in world coordinates after their modelling ``transform`` (4x4, column vectors).

A scene without lights is lit by a headlight (:meth:`Scene.effective_lights`): a white ambient light and a
white directional light travelling along the view direction, so a face turned to the viewer shows (ka + kd)·C.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from pixelpen.display.picture import Style
from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.geometry.mesh import Mesh
from pixelpen.geometry.surfaces import Surface
from pixelpen.geometry.transforms import ArrayLike, as_number
from pixelpen.geometry.transforms3d import as_choice, as_matrix3d, as_triple, compose3d
from pixelpen.geometry.viewing3d import ViewVolume, view_orientation
from pixelpen.options import check_known
from pixelpen.raster.illumination import Light, Material, Viewer, as_colours
from pixelpen.raster.shading import SHADING_MODES

Triple = tuple[float, float, float]

CAMERA_KEYS: tuple[str, ...] = ("vrp", "vpn", "vup", "projection", "z_prp", "z_vp", "near", "far", "alpha", "phi")
"""The keys a camera dict may hold (the fields of :class:`Camera`; near and far are required)."""
EDGE_MODES: tuple[str, ...] = ("features", "outlines", "none")
"""What a mesh draws on a vector display: feature edges (silhouettes, boundaries, creases), every polygon edge
with a front face, or nothing (it still hides what lies behind it)."""
DEFAULT_CREASE = math.radians(30.0)
"""Default crease angle: edges between front faces whose normals differ by more are drawn."""
HEADLIGHT_AMBIENT = (1.0, 1.0, 1.0)
"""Intensity of the headlight's ambient light (the lights of a scene that has none)."""


@dataclass(frozen=True)
class Camera:
    """Where the scene is seen from and how it is projected (the keys of :data:`CAMERA_KEYS`, validated)."""

    near: float
    far: float
    vrp: Triple = (0.0, 0.0, 0.0)
    vpn: Triple = (0.0, 0.0, 1.0)
    vup: Triple = (0.0, 1.0, 0.0)
    projection: str = "parallel"
    z_prp: float | None = None
    z_vp: float = 0.0
    alpha: float | None = None
    phi: float | None = None
    world_to_view: np.ndarray = field(init=False, repr=False, compare=False)
    """World -> viewing (u, v, n) 4x4."""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for name in ("vrp", "vpn", "vup"):
            set_(self, name, as_triple(getattr(self, name), f"camera {name}"))
        set_(self, "world_to_view", view_orientation(self.vrp, self.vpn, self.vup))
        volume = self.volume((-1.0, -1.0, 1.0, 1.0))  # validates projection, near, far, z_prp, z_vp, alpha, phi
        for name in ("projection", "near", "far", "z_prp", "z_vp", "alpha", "phi"):
            set_(self, name, getattr(volume, name))

    @classmethod
    def from_dict(cls, values: Mapping[str, object]) -> Camera:
        """A camera from a dict with keys among :data:`CAMERA_KEYS`; near and far are required."""
        if not isinstance(values, Mapping):
            raise InvalidArgumentType(f"camera must be a dict, got {type(values).__name__} {values!r}")
        check_known(CAMERA_KEYS, values, "camera", kind="key", error=InvalidArgument)
        missing = [key for key in ("near", "far") if key not in values]
        if missing:
            raise InvalidArgument(f"camera needs {' and '.join(missing)} (n coordinates of the clipping planes, "
                                  "near > far; the viewer looks towards −n)")
        return cls(**values)  # type: ignore[arg-type]

    def volume(self, window: Sequence[float]) -> ViewVolume:
        """The normalised view volume with ``window`` (umin, vmin, umax, vmax) on the view plane."""
        return ViewVolume(self.projection, tuple(window), self.near, self.far,  # type: ignore[arg-type]
                          z_prp=self.z_prp, z_vp=self.z_vp, alpha=self.alpha, phi=self.phi)

    def world_to_clip(self, window: Sequence[float]) -> np.ndarray:
        """World -> clip space 4x4 for the view-plane ``window``."""
        return compose3d(self.volume(window).matrix, self.world_to_view)

    def viewer(self) -> Viewer:
        """The viewer for lighting: the PRP (perspective) or the direction towards the viewer (parallel, oblique)."""
        volume = self.volume((-1.0, -1.0, 1.0, 1.0))
        position = volume.viewer(self.world_to_view)
        if position is not None:
            return Viewer(position=as_triple(position, "viewer position"))
        return Viewer(direction=as_triple(volume.view_direction(self.world_to_view), "viewer direction"))

    def clip_coordinates(self, points: np.ndarray, window: Sequence[float]) -> np.ndarray:
        """(N, 4) homogeneous clip coordinates of world ``points`` (N, 3)."""
        matrix = self.world_to_clip(window)
        # einsum, not @: BLAS's threads make a tall (N, 3) @ (3, 4) product many times slower on small machines
        clip: np.ndarray = np.einsum("ij,kj->ik", points, matrix[:, :3]) + matrix[:, 3]
        return clip


def _transform_scale(matrix: np.ndarray) -> float:
    """The largest stretch of the linear part of a 4x4 modelling transform (model units -> world units)."""
    return float(np.linalg.svd(matrix[:3, :3], compute_uv=False)[0])


@dataclass
class SceneItem:
    """One mesh or surface of a scene with its material, shading, vector-display edges and stroke style."""

    material: Material
    shading: str
    edges: str
    crease_angle: float
    style: Style
    transform: np.ndarray
    mesh: Mesh | None = None
    """The mesh in world coordinates (None for a surface: tessellated per display by :meth:`mesh_at`)."""
    surface: Surface | None = None
    tolerance: float | None = None
    """Chord tolerance of a surface's tessellation in device units (None: the display's tolerance)."""
    face_colours: np.ndarray | None = None
    _cache: dict[tuple[float, float], Mesh] = field(default_factory=dict, repr=False)

    def mesh_at(self, device_per_world: float, tolerance: float) -> Mesh:
        """The item's world mesh; a surface tessellated to its tolerance (else ``tolerance``) in device units
        at ``device_per_world`` device units per world unit."""
        if self.mesh is not None:
            return self.mesh
        assert self.surface is not None
        chord = tolerance if self.tolerance is None else self.tolerance
        scale = device_per_world * _transform_scale(self.transform)
        key = (chord, scale)
        if key not in self._cache:
            self._cache.clear()
            self._cache[key] = self.surface.tessellate(chord, scale=scale).transformed(self.transform)
        return self._cache[key]


def _as_transform(transform: ArrayLike | None) -> np.ndarray:
    """A validated 4x4 modelling transform (identity when None)."""
    return np.eye(4) if transform is None else as_matrix3d(transform, "transform")


def _as_material(material: Mapping[str, object] | Material | None) -> Material:
    """A Material from a dict of its fields (None: the defaults)."""
    if material is None:
        return Material()
    if isinstance(material, Material):
        return material
    return Material.from_dict(material)


def _as_style(style: Style | None) -> Style:
    """The stroke style of an item on vector displays (None: the default pen)."""
    if style is None:
        return Style()
    if not isinstance(style, Style):
        raise InvalidArgumentType(f"style must be a Style, got {type(style).__name__}")
    return style


class Scene:
    """A camera, meshes and surfaces, and lights; ``display.draw(scene)`` shows it on any display."""

    def __init__(self, camera: Mapping[str, object] | Camera) -> None:
        self.camera = camera if isinstance(camera, Camera) else Camera.from_dict(camera)
        self.items: list[SceneItem] = []
        self.lights: list[Light] = []

    def add_mesh(
        self,
        vertices: ArrayLike | Mesh,
        faces: ArrayLike | None = None,
        face_colours: ArrayLike | None = None,
        material: Mapping[str, object] | Material | None = None,
        shading: str = "flat",
        *,
        transform: ArrayLike | None = None,
        edges: str = "features",
        crease_angle: float = DEFAULT_CREASE,
        style: Style | None = None,
    ) -> SceneItem:
        """Add a triangle mesh: (N, 3) vertices and (M, 3) CCW faces, or a Mesh (faces None); return its item.

        ``face_colours`` (M, 3) in 0..1 replaces the material's colour per face; ``shading`` is "flat",
        "gouraud" or "phong"; ``transform`` a 4x4 modelling transform; ``edges`` what a vector display draws
        (:data:`EDGE_MODES`) in ``style``.
        """
        if isinstance(vertices, Mesh):
            if faces is not None:
                raise InvalidArgument("add_mesh takes faces only with a vertex array, not with a Mesh")
            mesh = vertices
        else:
            if faces is None:
                raise InvalidArgument("add_mesh needs faces (M, 3) with a vertex array")
            mesh = Mesh(vertices, faces)
        matrix = _as_transform(transform)
        if transform is not None:
            mesh = mesh.transformed(matrix)
        colours = None if face_colours is None else as_colours(face_colours, len(mesh.faces), "face_colours")
        item = SceneItem(_as_material(material), as_choice(shading, "shading", SHADING_MODES),
                         as_choice(edges, "edges", EDGE_MODES), _as_crease(crease_angle), _as_style(style),
                         matrix, mesh=mesh, face_colours=colours)
        self.items.append(item)
        return item

    def add_surface(
        self,
        surface: Surface,
        material: Mapping[str, object] | Material | None = None,
        shading: str = "phong",
        tolerance: float | None = None,
        *,
        transform: ArrayLike | None = None,
        edges: str = "features",
        crease_angle: float = DEFAULT_CREASE,
        style: Style | None = None,
    ) -> SceneItem:
        """Add a surface, tessellated when drawn to ``tolerance`` device units (None: the display's own)."""
        if not isinstance(surface, Surface):
            raise InvalidArgumentType(f"surface must be a Surface, got {type(surface).__name__}")
        chord = None if tolerance is None else as_number(tolerance, "tolerance")
        if chord is not None and not chord > 0.0:
            raise InvalidArgument(f"tolerance must be > 0 device units, got {chord}")
        item = SceneItem(_as_material(material), as_choice(shading, "shading", SHADING_MODES),
                         as_choice(edges, "edges", EDGE_MODES), _as_crease(crease_angle), _as_style(style),
                         _as_transform(transform), surface=surface, tolerance=chord)
        self.items.append(item)
        return item

    def add_light(
        self,
        kind: str = "ambient",
        intensity: Sequence[float] = (1.0, 1.0, 1.0),
        position: Sequence[float] | None = None,
        direction: Sequence[float] | None = None,
        attenuation: Sequence[float] = (1.0, 0.0, 0.0),
        *,
        spot_exponent: float = 1.0,
        cutoff: float = math.pi / 4,
    ) -> Light:
        """Add a light (see :class:`pixelpen.raster.illumination.Light`: directions are the way light travels)."""
        light = Light(kind, intensity, position, direction, attenuation,
                      spot_exponent=spot_exponent, cutoff=cutoff)
        self.lights.append(light)
        return light

    def effective_lights(self) -> list[Light]:
        """The scene's lights; with none, a headlight: ambient (1, 1, 1) and directional (1, 1, 1) along the view."""
        if self.lights:
            return list(self.lights)
        camera = self.camera
        travel = -camera.volume((-1.0, -1.0, 1.0, 1.0)).view_direction(camera.world_to_view)
        return [Light("ambient", HEADLIGHT_AMBIENT), Light("directional", (1.0, 1.0, 1.0),
                                                             direction=as_triple(travel, "headlight direction"))]


def _as_crease(angle: float) -> float:
    """A crease angle in [0, pi] radians."""
    value = as_number(angle, "crease_angle")
    if not 0.0 <= value <= math.pi:
        raise InvalidArgument(f"crease_angle must be in [0, pi] radians, got {value}")
    return value

"""The 3D viewing pipeline: world -> viewing (u, v, n) -> projection and normalisation -> clip space (H&B ch. 12).

Conventions:

* Viewing coordinates (u, v, n) are right-handed; the viewer is on the +n side looking towards −n
  (Hearn & Baker). The view plane is n = z_vp; near and far are n coordinates with near > far.
* A perspective projection has its projection reference point (PRP) on the n axis at n = z_prp > near
  (the PRP is in front of the view volume) and z_vp < z_prp.
* Clip space is the one of :mod:`pixelpen.geometry.clip3d`: −w ≤ x, y ≤ w, 0 ≤ z ≤ w, w > 0, so NDC z runs
  from 0 at the near plane to 1 at the far plane, and NDC x, y in [−1, 1] map to the view-plane window
  (:attr:`ViewVolume.ndc_to_window`), whence the display's 2D pipeline takes over.

One-, two- and three-point perspectives are made by placement: the principal vanishing points of the world
axes that are not parallel to the view plane (:func:`vanishing_point`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Literal

import numpy as np

from pixelpen.errors import InvalidArgument
from pixelpen.geometry.clip3d import (
    PLANES,
    FaceClip,
    clip_faces_homogeneous,
    clip_points_homogeneous,
    clip_polygon_homogeneous,
    clip_segments_homogeneous,
    clip_triangles_homogeneous,
    perspective_divide,
)
from pixelpen.geometry.transforms import ArrayLike, as_number
from pixelpen.geometry.transforms3d import (
    as_choice,
    as_matrix3d,
    as_triple,
    compose3d,
    invert3d,
    shear3d,
    translate3d,
)
from pixelpen.geometry.viewing import as_rect, window_to_viewport

__all__ = [
    "CABINET",
    "CAVALIER",
    "PLANES",
    "STANDARD_VIEWS",
    "FaceClip",
    "ViewVolume",
    "clip_faces_homogeneous",
    "clip_points_homogeneous",
    "clip_polygon_homogeneous",
    "clip_segments_homogeneous",
    "clip_triangles_homogeneous",
    "oblique",
    "orthographic",
    "perspective",
    "perspective_divide",
    "vanishing_point",
    "view_orientation",
]

Vector = tuple[float, float, float]
Projection = Literal["parallel", "perspective", "oblique"]

CAVALIER = math.pi / 4.0
"""Oblique angle alpha of a cavalier projection (tan alpha = 1): lines along n keep their length."""
CABINET = math.atan(2.0)
"""Oblique angle alpha of a cabinet projection (tan alpha = 2): lines along n are drawn at half length."""

STANDARD_VIEWS: Mapping[str, tuple[Vector, Vector]] = MappingProxyType({
    "front": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    "back": ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),
    "top": ((0.0, 1.0, 0.0), (0.0, 0.0, -1.0)),
    "bottom": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
    "side": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "left": ((-1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
})
"""Elevation views as (vpn, vup): the viewer on the +z (front), +y (top, +z down the page), +x (side) ... axis."""

# |vup × n| below this fraction of |vup| means vup is parallel to the view-plane normal.
_PARALLEL_TOL = 1e-12

ISOMETRIC_ELEVATION = math.asin(1.0 / math.sqrt(3.0))
"""Elevation of the isometric view direction (1, 1, 1) above the xz plane (≈ 35.26°)."""
DIMETRIC_ELEVATION = math.asin(1.0 / 3.0)
"""Default elevation of the dimetric and trimetric views (≈ 19.47°)."""
TRIMETRIC_AZIMUTH = math.radians(30.0)
"""Default azimuth of the trimetric view."""


def view_orientation(vrp: Sequence[float], vpn: Sequence[float], vup: Sequence[float]) -> np.ndarray:
    """World -> viewing 4x4: T(−vrp), then the rows u, v, n (n = vpn/|vpn|, u = vup × n/|..|, v = n × u)."""
    origin = as_triple(vrp, "vrp")
    normal, up = np.array(as_triple(vpn, "vpn")), np.array(as_triple(vup, "vup"))
    length = float(np.linalg.norm(normal))
    if length == 0.0 or not math.isfinite(length):
        raise InvalidArgument(f"vpn (the view-plane normal) must be a non-zero finite vector, got {normal.tolist()}")
    n = normal / length
    side = np.cross(up, n)
    up_length, side_length = float(np.linalg.norm(up)), float(np.linalg.norm(side))
    if not math.isfinite(up_length) or side_length <= _PARALLEL_TOL * up_length or side_length == 0.0:
        raise InvalidArgument(
            f"vup {up.tolist()} must be a finite vector not parallel to vpn {normal.tolist()}: it fixes which way is up"
        )
    u = side / side_length
    v = np.cross(n, u)
    rotation = np.eye(4)
    rotation[:3, :3] = np.stack([u, v, n])
    return compose3d(rotation, translate3d(-origin[0], -origin[1], -origin[2]))


def _axonometric_direction(azimuth: float, elevation: float) -> Vector:
    """Unit vector towards the viewer: azimuth about y from +z towards +x, elevation above the xz plane."""
    if not -math.pi / 2.0 < elevation < math.pi / 2.0:
        raise InvalidArgument(f"elevation must lie strictly between −π/2 and π/2 radians, got {elevation}")
    c = math.cos(elevation)
    return (c * math.sin(azimuth), math.sin(elevation), c * math.cos(azimuth))


def orthographic(
    kind: str,
    *,
    azimuth: float | None = None,
    elevation: float | None = None,
    vrp: Sequence[float] = (0.0, 0.0, 0.0),
) -> np.ndarray:
    """World -> viewing 4x4 of an orthographic view; dropping n then gives the parallel projection.

    ``kind`` is an elevation view of :data:`STANDARD_VIEWS` ("front", "top", "side", ...: true length along
    two axes, the third vanishes) or an axonometric view, with vup = world y and the viewer in the direction
    (cos e sin a, sin e, cos e cos a) for azimuth a and elevation e. A unit world axis k is foreshortened to
    f_k = sqrt(1 − n_k²):

    * "isometric": a = 45°, e = asin(1/√3): f_x = f_y = f_z = sqrt(2/3) (no angles accepted);
    * "dimetric": a = 45°, e = ``elevation`` (default asin(1/3)): f_x = f_z = sqrt(1 − cos²e / 2), f_y = cos e
      (with the default √5/3 and 2√2/3);
    * "trimetric": a = ``azimuth`` (default 30°), e = ``elevation`` (default asin(1/3)):
      f_x = sqrt(1 − cos²e sin²a), f_y = cos e, f_z = sqrt(1 − cos²e cos²a) (defaults √7/3, 2√2/3, 1/√3).
    """
    kind = as_choice(kind, "kind", [*STANDARD_VIEWS, "isometric", "dimetric", "trimetric"])
    if azimuth is not None and kind != "trimetric":
        raise InvalidArgument(f"azimuth applies to trimetric views only, got azimuth={azimuth!r} for {kind!r}")
    if elevation is not None and kind not in ("dimetric", "trimetric"):
        raise InvalidArgument(
            f"elevation applies to dimetric and trimetric views only, got elevation={elevation!r} for {kind!r}"
        )
    if kind in STANDARD_VIEWS:
        vpn, vup = STANDARD_VIEWS[kind]
        return view_orientation(vrp, vpn, vup)
    if kind == "isometric":
        a, e = math.pi / 4.0, ISOMETRIC_ELEVATION
    else:
        e = DIMETRIC_ELEVATION if elevation is None else as_number(elevation, "elevation")
        if kind == "dimetric":
            a = math.pi / 4.0
        else:
            a = TRIMETRIC_AZIMUTH if azimuth is None else as_number(azimuth, "azimuth")
    return view_orientation(vrp, _axonometric_direction(a, e), (0.0, 1.0, 0.0))


def _oblique_factor(alpha: float) -> float:
    """L1 = 1 / tan(alpha) for an oblique angle in (0, π/2]."""
    alpha = as_number(alpha, "alpha")
    if not 0.0 < alpha <= math.pi / 2.0:
        raise InvalidArgument(f"alpha must lie in (0, π/2] radians (the projectors' angle to the view plane): {alpha}")
    return 0.0 if alpha == math.pi / 2.0 else 1.0 / math.tan(alpha)


def oblique(alpha: float, phi: float) -> np.ndarray:
    """Oblique parallel projection 4x4: x_p = x + L cos φ, y_p = y + L sin φ with L = z / tan α, z kept for depth.

    A line of length 1 along z is drawn with length 1 / tan α: 1 for :data:`CAVALIER`, 1/2 for :data:`CABINET`.
    """
    factor = _oblique_factor(alpha)
    phi = as_number(phi, "phi")
    return shear3d("z", factor * math.cos(phi), factor * math.sin(phi))


def perspective(z_prp: float, z_vp: float) -> np.ndarray:
    """Hearn & Baker's perspective 4x4: PRP (0, 0, z_prp), view plane z = z_vp, h = (z_prp − z)/(z_prp − z_vp).

    After dividing by h: x_p = x·(z_prp − z_vp)/(z_prp − z), y_p likewise, z_p = z_vp.
    """
    z_prp, z_vp = as_number(z_prp, "z_prp"), as_number(z_vp, "z_vp")
    dp = z_prp - z_vp
    if dp == 0.0 or not math.isfinite(dp):
        raise InvalidArgument(f"z_prp and z_vp must differ (the PRP cannot lie in the view plane), got both {z_prp}")
    return np.array([
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, -z_vp / dp, z_vp * z_prp / dp],
        [0.0, 0.0, -1.0 / dp, z_prp / dp],
    ])


def vanishing_point(matrix: ArrayLike, direction: Sequence[float]) -> np.ndarray | None:
    """Where lines along ``direction`` (world) converge under a world->projection or world->clip 4x4: (2,) or None.

    The image of the point at infinity [d, 0]; None when the direction is parallel to the view plane (or the
    projection is parallel), since then such lines stay parallel. The point is in the matrix's 2D output
    units: view-plane coordinates for a world->projection matrix, NDC x, y for a world->clip matrix.
    """
    mat = as_matrix3d(matrix)
    d = np.array(as_triple(direction, "direction"))
    if not d.any():
        raise InvalidArgument("direction must be a non-zero vector, got (0, 0, 0)")
    image = mat[:, :3] @ d
    scale = float(np.linalg.norm(mat[3, :3]) * np.linalg.norm(d))
    if abs(image[3]) <= _PARALLEL_TOL * scale or scale == 0.0:
        return None
    point: np.ndarray = image[:2] / image[3]
    return point


@dataclass(frozen=True)
class ViewVolume:
    """A normalised view volume: the window on the view plane, near and far planes, and the projection kind.

    ``matrix`` maps viewing coordinates (u, v, n) to clip space (module docstring), a linear map of u, n:

    * parallel: x_c = 2(u − umin)/(umax − umin) − 1 (y_c likewise), z_c = (near − n)/(near − far), w = 1;
    * oblique: the same after the shear u' = u + (n − z_vp) cos φ / tan α, v' = v + (n − z_vp) sin φ / tan α;
    * perspective: w = (z_prp − n)/(z_prp − z_vp), x_c = x_ndc·w where x_ndc is the parallel map of the
      projected x_p = u / w, and z_c = A·n + B with z_c/w = 0 at near and 1 at far.
    """

    projection: Projection
    window: tuple[float, float, float, float]
    near: float
    far: float
    z_prp: float | None = None
    z_vp: float = 0.0
    alpha: float | None = None
    phi: float | None = None
    _matrix: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        """Validate and normalise the parameters, then build the matrix."""
        set_ = object.__setattr__
        set_(self, "projection", as_choice(self.projection, "projection", ("parallel", "perspective", "oblique")))
        set_(self, "window", as_rect(self.window, "window"))
        near, far = as_number(self.near, "near"), as_number(self.far, "far")
        if not near > far:
            raise InvalidArgument(f"near must be > far (n coordinates; the viewer looks towards −n), got {near}, {far}")
        set_(self, "near", near)
        set_(self, "far", far)
        set_(self, "z_vp", as_number(self.z_vp, "z_vp"))
        if self.projection == "perspective":
            if self.z_prp is None:
                raise InvalidArgument("a perspective view volume needs z_prp (the PRP's n coordinate)")
            z_prp = as_number(self.z_prp, "z_prp")
            if not z_prp > near:
                raise InvalidArgument(f"z_prp must be > near (the PRP in front of the view volume): {z_prp}, {near}")
            if not self.z_vp < z_prp:
                raise InvalidArgument(f"z_vp must be < z_prp (the view plane in front of the PRP), got {self.z_vp}")
            set_(self, "z_prp", z_prp)
        elif self.z_prp is not None:
            raise InvalidArgument(f"z_prp applies to perspective view volumes only, got z_prp={self.z_prp!r}")
        if self.projection == "oblique":
            if self.alpha is None or self.phi is None:
                raise InvalidArgument("an oblique view volume needs alpha and phi (radians)")
            _oblique_factor(self.alpha)
            set_(self, "alpha", as_number(self.alpha, "alpha"))
            set_(self, "phi", as_number(self.phi, "phi"))
        elif self.alpha is not None or self.phi is not None:
            raise InvalidArgument(f"alpha and phi apply to oblique view volumes only, got {self.alpha!r}, {self.phi!r}")
        matrix = self._build()
        matrix.flags.writeable = False
        set_(self, "_matrix", matrix)

    def _build(self) -> np.ndarray:
        """The viewing -> clip matrix of the validated parameters."""
        umin, vmin, umax, vmax = self.window
        du, dv = umax - umin, vmax - vmin
        if self.projection == "perspective":
            assert self.z_prp is not None
            dp = self.z_prp - self.z_vp
            a = (self.z_prp - self.far) / (dp * (self.far - self.near))
            cu, cv = (umin + umax) / du, (vmin + vmax) / dv
            return np.array([
                [2.0 / du, 0.0, cu / dp, -cu * self.z_prp / dp],
                [0.0, 2.0 / dv, cv / dp, -cv * self.z_prp / dp],
                [0.0, 0.0, a, -a * self.near],
                [0.0, 0.0, -1.0 / dp, self.z_prp / dp],
            ])
        normalise = np.array([
            [2.0 / du, 0.0, 0.0, -(umin + umax) / du],
            [0.0, 2.0 / dv, 0.0, -(vmin + vmax) / dv],
            [0.0, 0.0, -1.0 / (self.near - self.far), self.near / (self.near - self.far)],
            [0.0, 0.0, 0.0, 1.0],
        ])
        if self.projection == "parallel":
            return normalise
        return compose3d(normalise, self._oblique_shear())

    def _oblique_shear(self) -> np.ndarray:
        """The oblique shear about the view plane n = z_vp (identity for the other projections)."""
        if self.alpha is None or self.phi is None:
            return np.eye(4)
        factor = _oblique_factor(self.alpha)
        return shear3d("z", factor * math.cos(self.phi), factor * math.sin(self.phi), ref=self.z_vp)

    @property
    def matrix(self) -> np.ndarray:
        """Viewing (u, v, n) -> clip space 4x4 (read-only)."""
        return self._matrix

    @property
    def ndc_to_window(self) -> np.ndarray:
        """3x3 2D matrix taking NDC x, y in [−1, 1] to the view-plane window's u, v."""
        return window_to_viewport((-1.0, -1.0, 1.0, 1.0), self.window)

    def viewer(self, world_to_view: ArrayLike) -> np.ndarray | None:
        """The PRP in world coordinates (3,) for a perspective volume; None for parallel and oblique ones."""
        if self.z_prp is None:
            return None
        prp: np.ndarray = invert3d(as_matrix3d(world_to_view, "world_to_view")) @ np.array([0.0, 0.0, self.z_prp, 1.0])
        position: np.ndarray = prp[:3] / prp[3]
        return position

    def view_direction(self, world_to_view: ArrayLike) -> np.ndarray:
        """Unit world vector pointing towards the viewer: against the projectors (the +n axis for perspective)."""
        towards = np.array([0.0, 0.0, 1.0])
        if self.alpha is not None and self.phi is not None:
            factor = _oblique_factor(self.alpha)
            towards = np.array([-factor * math.cos(self.phi), -factor * math.sin(self.phi), 1.0])
        inverse = invert3d(as_matrix3d(world_to_view, "world_to_view"))
        world = inverse[:3, :3] @ towards
        unit: np.ndarray = world / np.linalg.norm(world)
        return unit

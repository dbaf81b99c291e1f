"""The basic illumination model (Hearn & Baker §14-2): ambient + Lambert diffuse + Phong or Blinn–Phong specular.

Per colour channel, at a surface point P with unit normal N, unit vector V towards the viewer and, per light,
unit vector L from P towards the light:

    I = Σ_ambient ka·Ia·C + Σ_other f_att·spot·Il·(kd·C·max(N·L, 0) + ks·S·spec)

with C the surface colour, S the specular colour and spec = max(R·V, 0)^n (Phong, R = 2(N·L)N − L) or
max(N·H, 0)^n (Blinn, H = (L + V)/|L + V|), counted only where N·L > 0. The result is clamped to [0, 1].

Lights (all vectors in world coordinates):

* ``"ambient"``: intensity only.
* ``"directional"``: ``direction`` is the way the light travels (from the source into the scene), so
  L = −direction; f_att = 1.
* ``"point"``: at ``position``; d = |position − P|, f_att = min(1, 1/(c0 + c1·d + c2·d²)) with
  ``attenuation`` = (c0, c1, c2).
* ``"spot"``: a point light at ``position`` aimed along ``direction``; Warn's model: with cos α = −L·D the
  angle between the spot axis D and the ray to P, spot = cos^e α inside the cone α ≤ ``cutoff`` and 0
  outside (``spot_exponent`` = e).

``Viewer(position=...)`` is a perspective eye (V varies per point); ``Viewer(direction=...)`` is a unit
direction towards a viewer at infinity (parallel projections). A two-sided material flips normals facing
away from the viewer (N·V < 0) before lighting. With only an ambient light (1, 1, 1) and ka = 1 the result
is exactly C.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.geometry.transforms import ArrayLike, as_number
from pixelpen.geometry.transforms3d import as_choice, as_points3d, as_triple
from pixelpen.options import check_known

LightKind = Literal["ambient", "point", "directional", "spot"]
Model = Literal["phong", "blinn"]
LIGHT_KINDS: tuple[str, ...] = ("ambient", "point", "directional", "spot")
"""The kinds of :class:`Light`."""
MODELS: tuple[str, ...] = ("phong", "blinn")
"""The specular models :func:`illuminate` offers."""

HALFWAY_MIN = 1e-9
"""Blinn: below this length of L + V (unit vectors) the halfway vector is undefined and gives no highlight."""

Triple = tuple[float, float, float]


def _unit_triple(value: object, name: str) -> Triple:
    """A non-zero finite triple scaled to unit length."""
    x, y, z = as_triple(value, name)
    length = math.sqrt(x * x + y * y + z * z)
    if length == 0.0 or not math.isfinite(length):
        raise InvalidArgument(f"{name} must be a non-zero finite vector, got {[x, y, z]}")
    return x / length, y / length, z / length


def _non_negative_triple(value: object, name: str, top: float = math.inf) -> Triple:
    """A triple of finite numbers each in [0, top]."""
    triple = as_triple(value, name)
    for i, v in enumerate(triple):
        if not 0.0 <= v <= top:
            raise InvalidArgument(f"{name}[{i}] must lie in [0, {top:g}], got {v}")
    return triple


def _in_range(value: object, name: str, low: float, high: float) -> float:
    """A finite number in [low, high]."""
    v = as_number(value, name)
    if not low <= v <= high:
        raise InvalidArgument(f"{name} must lie in [{low:g}, {high:g}], got {v}")
    return v


@dataclass(frozen=True)
class Light:
    """A light source: kind "ambient" | "point" | "directional" | "spot" (see the module doc for each)."""

    kind: str
    intensity: Sequence[float] = (1.0, 1.0, 1.0)
    position: Sequence[float] | None = None
    direction: Sequence[float] | None = None
    attenuation: Sequence[float] = (1.0, 0.0, 0.0)
    spot_exponent: float = 1.0
    cutoff: float = math.pi / 4

    def __post_init__(self) -> None:
        """Validate the fields for the kind; store triples as floats and the direction as a unit vector."""
        kind = as_choice(self.kind, "light kind", LIGHT_KINDS)
        set_ = object.__setattr__
        set_(self, "intensity", _non_negative_triple(self.intensity, "light intensity"))
        needs_position = kind in ("point", "spot")
        needs_direction = kind in ("directional", "spot")
        for name, needed in (("position", needs_position), ("direction", needs_direction)):
            given = getattr(self, name)
            if needed and given is None:
                raise InvalidArgument(f"a {kind} light needs a {name}")
            if not needed and given is not None:
                raise InvalidArgument(f"a {kind} light takes no {name}, got {given!r}")
        if self.position is not None:
            set_(self, "position", as_triple(self.position, "light position"))
        if self.direction is not None:
            set_(self, "direction", _unit_triple(self.direction, "light direction"))
        attenuation = _non_negative_triple(self.attenuation, "light attenuation")
        if sum(attenuation) == 0.0:
            raise InvalidArgument("light attenuation (c0, c1, c2) must not be all zero")
        set_(self, "attenuation", attenuation)
        set_(self, "spot_exponent", _in_range(self.spot_exponent, "spot_exponent", 0.0, math.inf))
        cutoff = as_number(self.cutoff, "cutoff")
        if not 0.0 < cutoff <= math.pi / 2:
            raise InvalidArgument(f"cutoff must be an angle in (0, pi/2] radians, got {cutoff}")
        set_(self, "cutoff", cutoff)


MATERIAL_KEYS: tuple[str, ...] = ("colour", "ka", "kd", "ks", "n", "specular_colour", "two_sided")
"""The keys :meth:`Material.from_dict` accepts (the fields of :class:`Material`)."""


@dataclass(frozen=True)
class Material:
    """Surface reflectance: colour C, coefficients ka, kd, ks in [0, 1], specular exponent n >= 0."""

    colour: Sequence[float] = (1.0, 1.0, 1.0)
    ka: float = 0.2
    kd: float = 0.8
    ks: float = 0.0
    n: float = 10.0
    specular_colour: Sequence[float] = (1.0, 1.0, 1.0)
    two_sided: bool = False

    def __post_init__(self) -> None:
        """Validate the fields and store them as floats."""
        set_ = object.__setattr__
        set_(self, "colour", _non_negative_triple(self.colour, "material colour", 1.0))
        set_(self, "specular_colour", _non_negative_triple(self.specular_colour, "material specular_colour", 1.0))
        for name in ("ka", "kd", "ks"):
            set_(self, name, _in_range(getattr(self, name), f"material {name}", 0.0, 1.0))
        set_(self, "n", _in_range(self.n, "material n", 0.0, math.inf))
        if not isinstance(self.two_sided, (bool, np.bool_)):
            raise InvalidArgumentType(f"material two_sided must be a bool, got {self.two_sided!r}")
        set_(self, "two_sided", bool(self.two_sided))

    @classmethod
    def from_dict(cls, values: Mapping[str, object]) -> Material:
        """A material from a dict with keys among :data:`MATERIAL_KEYS` (the others keep their defaults)."""
        if not isinstance(values, Mapping):
            raise InvalidArgumentType(f"material must be a dict, got {type(values).__name__} {values!r}")
        check_known(MATERIAL_KEYS, values, "material", kind="key", error=InvalidArgument)
        return cls(**values)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Viewer:
    """Where the viewer is: exactly one of ``position`` (an eye point) or ``direction`` (towards the viewer)."""

    position: Sequence[float] | None = None
    direction: Sequence[float] | None = None

    def __post_init__(self) -> None:
        """Validate that exactly one is given; store the direction as a unit vector."""
        if (self.position is None) == (self.direction is None):
            raise InvalidArgument("a Viewer needs exactly one of position or direction")
        if self.position is not None:
            object.__setattr__(self, "position", as_triple(self.position, "viewer position"))
        else:
            object.__setattr__(self, "direction", _unit_triple(self.direction, "viewer direction"))


# The arithmetic works on components as rows, (3, F) arrays (or (3, 1) for one vector for all points), so each
# numpy step runs over F contiguous values rather than F rows of three.


def _column(vector: Sequence[float]) -> np.ndarray:
    """One vector as a (3, 1) column broadcasting against (3, F) rows."""
    return np.array(vector, dtype=np.float64).reshape(3, 1)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot products of (3, F) or (3, 1) component rows: (F,) or (1,)."""
    if b.shape[1] == 1:
        a, b = b, a
    out: np.ndarray = np.einsum("i,ij->j", a[:, 0], b) if a.shape[1] == 1 else np.einsum("ij,ij->j", a, b)
    return out


def _normalised(vectors: np.ndarray) -> np.ndarray:
    """(3, F) vectors scaled to unit length; zero vectors stay zero."""
    scale = np.sqrt(_dot(vectors, vectors))
    np.divide(1.0, scale, out=scale, where=scale > 0.0)  # zero lengths stay zero
    out: np.ndarray = vectors * scale
    return out


def _components(values: ArrayLike, name: str) -> np.ndarray:
    """Validate (F, 3) finite rows (or one (3,) point); return them as contiguous (3, F) components."""
    arr = np.asarray(values, dtype=np.float64) if isinstance(values, np.ndarray) else None
    if arr is None or arr.ndim != 2 or arr.shape[1] != 3 or not np.isfinite(arr).all():
        arr, _ = as_points3d(values, name)  # the full check, naming the bad row
    return np.ascontiguousarray(arr.T)


def _check_inputs(
    material: object, lights: object, viewer: object, model: object
) -> tuple[Material, list[Light], Viewer, str]:
    """Type-check the lighting arguments; lights may be one Light or a sequence of them."""
    if not isinstance(material, Material):
        raise InvalidArgumentType(f"material must be a Material, got {type(material).__name__}")
    if not isinstance(viewer, Viewer):
        raise InvalidArgumentType(f"viewer must be a Viewer, got {type(viewer).__name__}")
    light_list = [lights] if isinstance(lights, Light) else lights
    if not isinstance(light_list, Sequence) or isinstance(light_list, str):
        raise InvalidArgumentType(f"lights must be a sequence of Light, got {type(lights).__name__}")
    for i, light in enumerate(light_list):
        if not isinstance(light, Light):
            raise InvalidArgumentType(f"lights[{i}] must be a Light, got {type(light).__name__}")
    return material, list(light_list), viewer, as_choice(model, "model", MODELS)


def illumination_terms(
    points: ArrayLike,
    normals: ArrayLike,
    material: Material,
    lights: Light | Sequence[Light],
    viewer: Viewer,
    model: str = "phong",
) -> tuple[np.ndarray, np.ndarray]:
    """The colour-independent parts (A, S), each (F, 3), of I = C·A + S (before clamping) at each point.

    A = Σ ka·Ia + Σ f_att·spot·Il·kd·max(N·L, 0) multiplies the surface colour; S is the specular sum.
    """
    material, light_list, viewer, model = _check_inputs(material, lights, viewer, model)
    p = _components(points, "points")
    n_unit = _normalised(_components(normals, "normals"))
    if n_unit.shape != p.shape:
        raise InvalidArgument(f"normals must match points, got {n_unit.shape[1]} normals for {p.shape[1]} points")
    if viewer.position is None:
        assert viewer.direction is not None
        v = _column(viewer.direction)
    else:
        v = _normalised(_column(viewer.position) - p)
    n_dot_v = _dot(n_unit, v)
    if material.two_sided:
        away = n_dot_v < 0.0
        n_unit = np.where(away, -n_unit, n_unit)
        n_dot_v = np.abs(n_dot_v)
    scale = np.zeros_like(p)
    specular = np.zeros_like(p)
    ks_s = material.ks * _column(material.specular_colour)
    for light in light_list:
        il = _column(light.intensity)
        if light.kind == "ambient":
            scale += material.ka * il
            continue
        factor: np.ndarray | float = 1.0
        if light.kind == "directional":
            assert light.direction is not None
            to_light = -_column(light.direction)
        else:
            assert light.position is not None
            offset = _column(light.position) - p
            distance = np.sqrt(_dot(offset, offset))
            to_light = _normalised(offset)
            c0, c1, c2 = light.attenuation
            factor = np.minimum(1.0, 1.0 / (c0 + distance * (c1 + c2 * distance)))
            if light.kind == "spot":
                assert light.direction is not None
                cos_alpha = -_dot(to_light, _column(light.direction))
                inside = cos_alpha >= math.cos(light.cutoff)
                factor *= np.where(inside, np.maximum(cos_alpha, 0.0) ** light.spot_exponent, 0.0)
        n_dot_l = _dot(n_unit, to_light)
        scale += (material.kd * il) * (factor * np.maximum(n_dot_l, 0.0))
        if material.ks == 0.0:
            continue
        if model == "phong":  # R·V with R = 2(N·L)N − L
            cosine = 2.0 * n_dot_l * n_dot_v - _dot(to_light, v)
        else:  # N·H with H = (L + V)/|L + V|, from L + V itself: N·L + N·V and L·V cancel as L nears −V
            halfway = to_light + v
            length = np.sqrt(_dot(halfway, halfway))
            total = _dot(n_unit, halfway)
            # L = −V (a light straight behind what the viewer sees) leaves H undefined: no highlight there
            cosine = np.divide(total, length, out=np.zeros_like(total), where=length > HALFWAY_MIN)
        highlight = np.where(n_dot_l > 0.0, np.maximum(cosine, 0.0) ** material.n, 0.0)
        specular += (ks_s * il) * (factor * highlight)
    return scale.T, specular.T


def as_colours(colours: ArrayLike, rows: int, name: str = "colours") -> np.ndarray:
    """Validate an (rows, 3) array of colours in [0, 1]; return it as float64."""
    arr, _ = as_points3d(colours, name)
    if arr.shape[0] != rows:
        raise InvalidArgument(f"{name} must have {rows} rows, got {arr.shape[0]}")
    bad = (arr < 0.0) | (arr > 1.0)
    if bad.any():
        row = int(np.flatnonzero(bad.any(axis=1))[0])
        raise InvalidArgument(f"{name} components must lie in [0, 1], got {arr[row].tolist()} at row {row}")
    return arr


def combine(colour: np.ndarray, scale: np.ndarray, specular: np.ndarray) -> np.ndarray:
    """I = clamp(C·A + S, 0, 1) from the terms of :func:`illumination_terms` and a colour (3,) or (F, 3)."""
    out: np.ndarray = np.clip(colour * scale + specular, 0.0, 1.0)
    return np.ascontiguousarray(out)


def illuminate(
    points: ArrayLike,
    normals: ArrayLike,
    material: Material,
    lights: Light | Sequence[Light],
    viewer: Viewer,
    model: str = "phong",
    colours: ArrayLike | None = None,
) -> np.ndarray:
    """Intensities (F, 3) in [0, 1] at (F, 3) points with (F, 3) normals; ``colours`` (F, 3) overrides C."""
    scale, specular = illumination_terms(points, normals, material, lights, viewer, model)
    colour = np.array(material.colour) if colours is None else as_colours(colours, scale.shape[0])
    return combine(colour, scale, specular)

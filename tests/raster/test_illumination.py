"""Tests for pixelpen.raster.illumination: hand-computed intensities (H&B §14-2) and a scalar textbook reference."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.raster.illumination import Light, Material, Viewer, illuminate

UP = (0.0, 0.0, 1.0)
ORIGIN = [[0.0, 0.0, 0.0]]
OVERHEAD = Viewer(direction=UP)


def _sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def _dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def _unit(a):
    length = math.sqrt(_dot(a, a))
    return [0.0, 0.0, 0.0] if length == 0.0 else [c / length for c in a]


def reference_intensity(point, normal, material, lights, viewer, model="phong", colour=None):
    """Scalar textbook model (H&B eq. 14-13 with attenuation, Warn spots, Phong/Blinn), one point, plain floats."""
    c = list(material.colour if colour is None else colour)
    n = _unit(list(normal))
    v = _unit(_sub(viewer.position, point)) if viewer.position is not None else _unit(list(viewer.direction))
    if material.two_sided and _dot(n, v) < 0.0:
        n = [-x for x in n]
    out = [0.0, 0.0, 0.0]
    for light in lights:
        if light.kind == "ambient":
            for k in range(3):
                out[k] += material.ka * light.intensity[k] * c[k]
            continue
        if light.kind == "directional":
            to_light, f = [-x for x in light.direction], 1.0
        else:
            offset = _sub(light.position, point)
            d = math.sqrt(_dot(offset, offset))
            to_light = _unit(offset)
            c0, c1, c2 = light.attenuation
            f = min(1.0, 1.0 / (c0 + c1 * d + c2 * d * d))
            if light.kind == "spot":
                cos_alpha = -_dot(to_light, _unit(list(light.direction)))
                f *= max(cos_alpha, 0.0) ** light.spot_exponent if cos_alpha >= math.cos(light.cutoff) else 0.0
        n_dot_l = _dot(n, to_light)
        spec = 0.0
        if n_dot_l > 0.0:
            if model == "phong":
                r = [2.0 * n_dot_l * n[k] - to_light[k] for k in range(3)]
                spec = max(_dot(r, v), 0.0) ** material.n
            else:
                total = [to_light[k] + v[k] for k in range(3)]
                h = _unit(total)  # undefined (no highlight) when L = −V to rounding: the library's HALFWAY_MIN
                spec = max(_dot(n, h), 0.0) ** material.n if math.sqrt(_dot(total, total)) > 1e-9 else 0.0
        for k in range(3):
            out[k] += f * light.intensity[k] * (material.kd * c[k] * max(n_dot_l, 0.0)
                                                + material.ks * material.specular_colour[k] * spec)
    return [min(1.0, max(0.0, x)) for x in out]


# ------------------------------------------------------------------ hand-computed worked numbers
def test_point_light_attenuation_worked_example():
    # light 2 units above the point, f = 1/(1 + 0.5·2 + 0.25·4) = 1/3; N·L = 1; I = f·kd·C = 0.2·C
    light = Light("point", position=(0, 0, 2), attenuation=(1.0, 0.5, 0.25))
    material = Material(colour=(1.0, 0.5, 0.25), ka=0.0, kd=0.6, ks=0.0)
    out = illuminate(ORIGIN, [UP], material, [light], OVERHEAD)
    np.testing.assert_allclose(out, [[0.2, 0.1, 0.05]], rtol=1e-12)


def test_attenuation_never_amplifies():
    # 1/(0.5 + 0·d) = 2 would brighten: f_att = min(1, ...) keeps it at 1
    light = Light("point", position=(0, 0, 3), attenuation=(0.5, 0.0, 0.0))
    out = illuminate(ORIGIN, [UP], Material(ka=0.0, kd=0.5), [light], OVERHEAD)
    np.testing.assert_allclose(out, [[0.5, 0.5, 0.5]], rtol=1e-12)


def test_lambert_cosine_at_sixty_degrees_is_one_half():
    towards = (math.sin(math.radians(60)), 0.0, math.cos(math.radians(60)))
    light = Light("directional", direction=tuple(-x for x in towards))
    out = illuminate(ORIGIN, [UP], Material(colour=(1, 1, 1), ka=0.0, kd=1.0), [light], OVERHEAD)
    np.testing.assert_allclose(out, [[0.5, 0.5, 0.5]], rtol=1e-12)


def test_phong_and_blinn_highlights_at_known_angles():
    # L at 30° from N, V along N: Phong R·V = cos 30°, Blinn N·H = cos 15° (H halves the 30° angle)
    towards = (math.sin(math.radians(30)), 0.0, math.cos(math.radians(30)))
    light = Light("directional", direction=tuple(-x for x in towards))
    material = Material(ka=0.0, kd=0.0, ks=1.0, n=10)
    phong = illuminate(ORIGIN, [UP], material, [light], OVERHEAD, model="phong")
    blinn = illuminate(ORIGIN, [UP], material, [light], OVERHEAD, model="blinn")
    np.testing.assert_allclose(phong[0], [math.cos(math.radians(30)) ** 10] * 3, rtol=1e-12)
    np.testing.assert_allclose(blinn[0], [math.cos(math.radians(15)) ** 10] * 3, rtol=1e-12)
    assert blinn[0, 0] > 0.7 > 0.24 > phong[0, 0]


def test_mirror_direction_gives_full_highlight():
    # viewer exactly along R: (R·V)^n = 1 for any n; specular colour tints the highlight
    a = math.radians(40)
    light = Light("directional", direction=(-math.sin(a), 0.0, -math.cos(a)))
    viewer = Viewer(direction=(-math.sin(a), 0.0, math.cos(a)))
    material = Material(ka=0.0, kd=0.0, ks=0.5, n=50, specular_colour=(1.0, 0.5, 0.0))
    np.testing.assert_allclose(illuminate(ORIGIN, [UP], material, [light], viewer), [[0.5, 0.25, 0.0]], atol=1e-12)


def test_spot_cone_edge():
    # spot 5 above the plane aimed straight down, cutoff 30°, exponent 2: I = kd·cos²α·cos α inside, 0 outside
    spot = Light("spot", position=(0, 0, 5), direction=(0, 0, -1), cutoff=math.radians(30), spot_exponent=2)
    angles = np.radians([0.0, 20.0, 29.9, 30.1, 45.0])
    points = np.stack([5 * np.tan(angles), np.zeros(5), np.zeros(5)], axis=1)
    out = illuminate(points, np.tile(UP, (5, 1)), Material(ka=0.0, kd=1.0), [spot], OVERHEAD)
    expected = [math.cos(a) ** 3 if math.degrees(a) <= 30 else 0.0 for a in angles]
    np.testing.assert_allclose(out[:, 0], expected, rtol=1e-12, atol=1e-15)
    assert out[2, 0] > 0.6 and out[3, 0] == 0.0


def test_ambient_alone_with_ka_one_gives_exactly_the_colour():
    rng = np.random.default_rng(5)
    colours = rng.random((200, 3))
    points, normals = rng.normal(size=(200, 3)), rng.normal(size=(200, 3))
    ambient = [Light("ambient", intensity=(1, 1, 1))]
    material = Material(colour=(0.3, 0.6, 0.9), ka=1.0, kd=0.7, ks=0.4)
    viewer = Viewer(position=(0, 0, 10))
    out = illuminate(points, normals, material, ambient, viewer, colours=colours)
    np.testing.assert_array_equal(out, colours)
    plain = illuminate(points, normals, material, ambient, viewer)
    np.testing.assert_array_equal(plain, np.tile([0.3, 0.6, 0.9], (200, 1)))


def test_energy_is_clamped_to_one():
    lights = [Light("ambient"), Light("directional", direction=(0, 0, -1)), Light("point", position=(0, 0, 1))]
    out = illuminate(ORIGIN, [UP], Material(colour=(1, 0.2, 0), ka=1.0, kd=1.0, ks=1.0, n=1), lights, OVERHEAD)
    np.testing.assert_array_equal(out, [[1.0, 1.0, 1.0]])  # unclamped: 3, 2.4, 2


def test_no_specular_when_the_light_is_behind_the_surface():
    # L 60° below the surface plane: N·L < 0, although R·V > 0 for this viewer
    light = Light("directional", direction=(0.0, -math.cos(math.radians(-30)), -math.sin(math.radians(-30))))
    viewer = Viewer(direction=(0.0, -0.6, -0.8))
    out = illuminate(ORIGIN, [UP], Material(ka=0.0, kd=1.0, ks=1.0, n=1), [light], viewer)
    np.testing.assert_array_equal(out, [[0.0, 0.0, 0.0]])


def test_two_sided_material_flips_normals_facing_away():
    light = Light("directional", direction=(0, 0, -1))  # shines down onto the viewer's side
    down = [(0.0, 0.0, -1.0)]  # a face whose normal points away from the overhead viewer
    one = illuminate(ORIGIN, down, Material(ka=0.1, kd=0.5), [Light("ambient"), light], OVERHEAD)
    two = illuminate(ORIGIN, down, Material(ka=0.1, kd=0.5, two_sided=True), [Light("ambient"), light], OVERHEAD)
    np.testing.assert_allclose(one, [[0.1] * 3], rtol=1e-12)
    np.testing.assert_allclose(two, [[0.6] * 3], rtol=1e-12)


def test_perspective_viewer_varies_per_point():
    # eye at (0, 0, 1): V is the unit vector from each point to the eye
    light = Light("directional", direction=(0, 0, -1))
    material = Material(ka=0.0, kd=0.0, ks=1.0, n=1)
    points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
    out = illuminate(points, [UP, UP], material, [light], Viewer(position=(0, 0, 1)))
    np.testing.assert_allclose(out[:, 0], [1.0, 1 / math.sqrt(2)], rtol=1e-12)


def test_unnormalised_and_zero_normals():
    light = [Light("directional", direction=(0, 0, -1))]
    out = illuminate([[0, 0, 0], [0, 0, 0]], [[0, 0, 7.0], [0, 0, 0]], Material(ka=0.0, kd=0.5), light, OVERHEAD)
    np.testing.assert_allclose(out[:, 0], [0.5, 0.0])


# ------------------------------------------------------------------ against the scalar reference
@st.composite
def scenes(draw):
    floats = st.floats(-4, 4)
    triple = st.tuples(floats, floats, floats)
    unit = triple.filter(lambda v: _dot(v, v) > 1e-3)
    colour = st.tuples(*[st.floats(0, 1)] * 3)
    light = st.one_of(
        st.builds(Light, st.just("ambient"), colour),
        st.builds(Light, st.just("directional"), colour, direction=unit),
        st.builds(Light, st.just("point"), colour, position=triple,
                  attenuation=st.tuples(st.floats(0.1, 2), st.floats(0, 1), st.floats(0, 1))),
        st.builds(Light, st.just("spot"), colour, position=triple, direction=unit,
                  spot_exponent=st.floats(0, 20), cutoff=st.floats(0.05, math.pi / 2)),
    )
    material = st.builds(Material, colour, st.floats(0, 1), st.floats(0, 1), st.floats(0, 1), st.floats(0, 60),
                         colour, st.booleans())
    viewer = st.one_of(st.builds(Viewer, position=triple.map(lambda p: (p[0], p[1], p[2] + 10.0))),
                       st.builds(Viewer, direction=unit))
    model = st.sampled_from(["phong", "blinn"])
    return draw(material), draw(st.lists(light, min_size=1, max_size=4)), draw(viewer), draw(model)


@settings(max_examples=60, deadline=None)
@given(scenes(), st.integers(0, 2**32 - 1))
@example((Material((0.0, 0.0, 0.0), 0.0, 0.0, 1.0, 1.0, (0.0, 0.0, 1.0), False),  # Blinn with L = −V exactly
          [Light("directional", (0.0, 0.0, 1.0), direction=(1.3125, 3.0, 2.0))],
          Viewer(direction=(1.3125, 3.0, 2.0)), "blinn"), 0)
@example((Material((0.0, 0.0, 0.0), 0.0, 0.0, 1.0, 1.0, (1.0, 0.0, 0.0), False),  # Blinn with L 6e-8 from −V:
          [Light("directional", (1.0, 0.0, 0.0), direction=(0.0, 1.192092896e-07, -2.0))],  # N·L + N·V cancelled
          Viewer(direction=(0.0, 0.0, -1.0)), "blinn"), 0)
def test_matches_scalar_reference(scene, seed):
    material, lights, viewer, model = scene
    rng = np.random.default_rng(seed)
    points, normals = rng.uniform(-2, 2, (20, 3)), rng.normal(size=(20, 3))
    out = illuminate(points, normals, material, lights, viewer, model)
    expected = [reference_intensity(p, q, material, lights, viewer, model)
                for p, q in zip(points, normals, strict=True)]
    np.testing.assert_allclose(out, expected, rtol=1e-9, atol=1e-9)
    assert out.min() >= 0.0 and out.max() <= 1.0


# ------------------------------------------------------------------ bad arguments
@pytest.mark.parametrize(("make", "message"), [
    (lambda: Light("laser"), "light kind"),
    (lambda: Light("point"), "needs a position"),
    (lambda: Light("spot", position=(0, 0, 1)), "needs a direction"),
    (lambda: Light("directional", direction=(0, 0, 1), position=(1, 2, 3)), "takes no position"),
    (lambda: Light("ambient", direction=(0, 0, 1)), "takes no direction"),
    (lambda: Light("directional", direction=(0, 0, 0)), "non-zero"),
    (lambda: Light("ambient", intensity=(1, -1, 1)), r"intensity\[1\]"),
    (lambda: Light("point", position=(0, 0, 1), attenuation=(0, 0, 0)), "all zero"),
    (lambda: Light("spot", position=(0, 0, 1), direction=(0, 0, -1), cutoff=0.0), "cutoff"),
    (lambda: Light("point", position=(0, float("nan"), 1)), "finite"),
    (lambda: Material(ka=1.5), "material ka"),
    (lambda: Material(colour=(0.5, 2, 0)), r"colour\[1\]"),
    (lambda: Material(n=-1), "material n"),
    (lambda: Material.from_dict({"colour": (1, 1, 1), "shine": 3}), "shine"),
    (lambda: Viewer(), "exactly one"),
    (lambda: Viewer(position=(0, 0, 1), direction=(0, 0, 1)), "exactly one"),
    (lambda: illuminate(ORIGIN, [UP, UP], Material(), [Light("ambient")], OVERHEAD), "normals must match"),
    (lambda: illuminate(ORIGIN, [UP], Material(), [Light("ambient")], OVERHEAD, model="gouraud"), "model"),
    (lambda: illuminate(ORIGIN, [UP], Material(), [Light("ambient")], OVERHEAD, colours=[[2, 0, 0]]), "colours"),
    (lambda: illuminate([[0, 0]], [UP], Material(), [Light("ambient")], OVERHEAD), "points"),
])
def test_bad_arguments_raise_clear_errors(make, message):
    with pytest.raises(InvalidArgument, match=message):
        make()


@pytest.mark.parametrize("make", [
    lambda: Light(3),
    lambda: Light("ambient", spot_exponent="2"),
    lambda: Material(two_sided="yes"),
    lambda: illuminate(ORIGIN, [UP], {"ka": 1}, [Light("ambient")], OVERHEAD),
    lambda: illuminate(ORIGIN, [UP], Material(), ["ambient"], OVERHEAD),
    lambda: illuminate(ORIGIN, [UP], Material(), [Light("ambient")], (0, 0, 1)),
])
def test_wrong_types_raise_invalid_argument_type(make):
    with pytest.raises(InvalidArgumentType):
        make()


def test_material_from_dict_and_single_light():
    material = Material.from_dict({"colour": (1, 0, 0), "ka": 1.0, "kd": 0.0, "ks": 0.0, "n": 5})
    assert material == Material(colour=(1.0, 0.0, 0.0), ka=1.0, kd=0.0, ks=0.0, n=5.0)
    np.testing.assert_array_equal(illuminate(ORIGIN, [UP], material, Light("ambient"), OVERHEAD), [[1.0, 0.0, 0.0]])

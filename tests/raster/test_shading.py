"""Tests for pixelpen.raster.shading: flat/Gouraud/Phong against hand values and a scalar reference; write_colours."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.raster.canvas import Canvas
from pixelpen.raster.illumination import Light, Material, Viewer
from pixelpen.raster.shading import Shader, native_pixels, native_pixels_unchecked, shade, write_colours
from pixelpen.raster.zbuffer import Fragments
from tests.raster.test_illumination import reference_intensity

# Two CCW triangles in the plane z = 0 (normals +z) sharing the edge (1,0,0)-(0,1,0).
VERTICES = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]])
FACES = np.array([[0, 1, 2], [1, 3, 2]])
OVERHEAD = Viewer(direction=(0.0, 0.0, 1.0))
BAYER4 = np.array([[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]])  # Foley et al. §13.1.2


def fragments(face, bary):
    """Fragments at made-up pixels (0, 0), (1, 0), ... with the given faces and barycentric weights."""
    face = np.asarray(face, dtype=np.int64)
    count = face.shape[0]
    return Fragments(xs=np.arange(count), ys=np.zeros(count, dtype=np.int64), face=face,
                     bary=np.asarray(bary, dtype=np.float64), depth=np.zeros(count))


def random_bary(rng, count):
    weights = rng.random((count, 3)) + 1e-3
    return weights / weights.sum(axis=1, keepdims=True)


# ------------------------------------------------------------------ shade
def test_flat_is_constant_per_face_with_hand_value():
    rng = np.random.default_rng(1)
    face = rng.integers(0, 2, 50)
    lights = [Light("ambient", intensity=(0.5, 0.5, 0.5)), Light("directional", direction=(0, 0, -1))]
    material = Material(colour=(0.8, 0.4, 0.2), ka=0.2, kd=0.5)
    out = shade(fragments(face, random_bary(rng, 50)), VERTICES, FACES, mode="flat", material=material,
                lights=lights, viewer=OVERHEAD, face_colours=[[0.8, 0.4, 0.2], [1.0, 1.0, 1.0]])
    # I = ka·Ia·C + kd·C·(N·L = 1) = 0.6·C
    expected = np.where((face == 0)[:, None], [0.48, 0.24, 0.12], [0.6, 0.6, 0.6])
    np.testing.assert_allclose(out, expected, rtol=1e-12)


def test_flat_lights_the_centroid_with_the_face_normal():
    rng = np.random.default_rng(2)
    vertices = rng.normal(size=(3, 3))
    light = [Light("point", position=(3, 1, 2), attenuation=(1, 0.1, 0.01))]
    material = Material(ka=0.1, kd=0.6, ks=0.5, n=8)
    viewer = Viewer(position=(0, 0, 6))
    out = shade(fragments([0] * 5, random_bary(rng, 5)), vertices, [[0, 1, 2]], mode="flat", material=material,
                lights=light, viewer=viewer, model="blinn")
    v0, v1, v2 = vertices
    normal = np.cross(v1 - v0, v2 - v0)
    expected = reference_intensity(list((v0 + v1 + v2) / 3), list(normal), material, light, viewer, "blinn")
    np.testing.assert_allclose(out, np.tile(expected, (5, 1)), rtol=1e-12)


def test_flat_lights_a_polygon_once_at_its_centroid_so_a_quad_shows_no_seam():
    # the unit square (two triangles of one polygon) under a point light: one intensity, that of the square's
    # centre (0.5, 0.5, 0) with normal +z, worked by the scalar reference
    light = [Light("point", position=(2, 0.3, 1.5), attenuation=(1, 0.2, 0))]
    material = Material(ka=0.1, kd=0.7, ks=0.4, n=5)
    frags = fragments([0, 0, 1, 1], random_bary(np.random.default_rng(3), 4))
    seamless = shade(frags, VERTICES, FACES, mode="flat", material=material, lights=light, viewer=OVERHEAD,
                     polygons=[7, 7])
    expected = reference_intensity([0.5, 0.5, 0.0], [0.0, 0.0, 1.0], material, light, OVERHEAD, "phong")
    np.testing.assert_allclose(seamless, np.tile(expected, (4, 1)), rtol=1e-12)
    per_triangle = shade(frags, VERTICES, FACES, mode="flat", material=material, lights=light, viewer=OVERHEAD)
    assert not np.allclose(per_triangle[0], per_triangle[2])  # each triangle at its own centroid: a seam


def test_gouraud_is_linear_in_the_barycentric_weights():
    rng = np.random.default_rng(3)
    normals = rng.normal(size=(4, 3)) + np.array([0.0, 0.0, 2.0])
    lights = [Light("ambient"), Light("point", position=(0.3, 0.2, 2)), Light("directional", direction=(1, 0, -1))]
    material = Material(colour=(0.9, 0.5, 0.1), ka=0.1, kd=0.5, ks=0.6, n=20)
    viewer = Viewer(position=(0.5, 0.5, 3))
    face = rng.integers(0, 2, 40)
    bary = random_bary(rng, 40)
    out = shade(fragments(face, bary), VERTICES, FACES, mode="gouraud", material=material, lights=lights,
                viewer=viewer, vertex_normals=normals)
    at_vertex = [reference_intensity(list(p), list(n), material, lights, viewer) for p, n in zip(VERTICES, normals,
                                                                                                   strict=True)]
    for k in range(40):
        expected = sum(bary[k, i] * np.array(at_vertex[FACES[face[k], i]]) for i in range(3))
        np.testing.assert_allclose(out[k], expected, rtol=1e-12, atol=1e-15)


def test_gouraud_with_face_colours_uses_each_face_colour_at_its_corners():
    lights = [Light("ambient", intensity=(0.5, 0.5, 0.5)), Light("directional", direction=(0, 0, -1))]
    material = Material(ka=1.0, kd=0.5)
    colours = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    bary = [[1, 0, 0], [0.2, 0.3, 0.5]]
    out = shade(fragments([0, 1], bary), VERTICES, FACES, mode="gouraud", material=material, lights=lights,
                viewer=OVERHEAD, face_colours=colours)
    np.testing.assert_allclose(out, [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], rtol=1e-12)  # (0.5 + 0.5)·C


def test_phong_differs_from_gouraud_on_a_highlight():
    # A big equilateral triangle with vertex normals tilted 45° outwards (a cap of a sphere): the light and viewer
    # straight above the centroid see a highlight there that no vertex has: Gouraud misses it, Phong finds it.
    angles = np.radians([90.0, 210.0, 330.0])
    outward = np.stack([np.cos(angles), np.sin(angles), np.zeros(3)], axis=1)
    vertices = 5.0 * outward
    normals = outward + np.array([0.0, 0.0, 1.0])
    material = Material(colour=(0.2, 0.2, 0.2), ka=0.0, kd=0.0, ks=1.0, n=30)
    light = [Light("directional", direction=(0, 0, -1))]
    centre = fragments([0], [[1 / 3, 1 / 3, 1 / 3]])
    kwargs = {"material": material, "lights": light, "viewer": OVERHEAD, "vertex_normals": normals}
    phong = shade(centre, vertices, [[0, 1, 2]], mode="phong", **kwargs)
    gouraud = shade(centre, vertices, [[0, 1, 2]], mode="gouraud", **kwargs)
    # Gouraud: each vertex has R·V = cos 90° = 0; Phong: the interpolated normal is (0, 0, 1), R·V = 1
    np.testing.assert_allclose(gouraud, [[0.0, 0.0, 0.0]], atol=1e-12)
    np.testing.assert_allclose(phong, [[1.0, 1.0, 1.0]], rtol=1e-12)


def test_phong_matches_reference_at_interpolated_position_and_normal():
    rng = np.random.default_rng(4)
    vertices = rng.normal(size=(5, 3))
    faces = np.array([[0, 1, 2], [2, 3, 4]])
    normals = rng.normal(size=(5, 3))
    lights = [Light("spot", position=(0, 0, 4), direction=(0, 0, -1), cutoff=1.2, spot_exponent=3)]
    material = Material(ka=0.0, kd=0.7, ks=0.5, n=12, two_sided=True)
    viewer = Viewer(position=(1, 1, 5))
    face, bary = rng.integers(0, 2, 30), random_bary(rng, 30)
    out = shade(fragments(face, bary), vertices, faces, mode="phong", material=material, lights=lights,
                viewer=viewer, vertex_normals=normals)
    for k in range(30):
        corners = faces[face[k]]
        point = bary[k] @ vertices[corners]
        normal = bary[k] @ normals[corners]
        np.testing.assert_allclose(out[k], reference_intensity(list(point), list(normal), material, lights, viewer),
                                   rtol=1e-10, atol=1e-12)


def test_default_normals_are_face_and_area_weighted_vertex_normals():
    # a tent: two faces at 90° to each other, the ridge vertices get the (equal-area) average normal
    vertices = np.array([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 1.0], [-1.0, 0.0, 1.0]])
    faces = np.array([[0, 2, 1], [0, 1, 3]])
    light = [Light("directional", direction=(0, 0, -1))]
    material = Material(ka=0.0, kd=1.0)
    frags = fragments([0, 1, 0], [[1, 0, 0], [0, 0, 1], [0, 1, 0]])
    flat = shade(frags, vertices, faces, mode="flat", material=material, lights=light, viewer=OVERHEAD)
    np.testing.assert_allclose(flat[:, 0], [math.sqrt(0.5)] * 3, rtol=1e-12)  # faces tilted 45°
    gouraud = shade(frags, vertices, faces, mode="gouraud", material=material, lights=light, viewer=OVERHEAD)
    np.testing.assert_allclose(gouraud[:, 0], [1.0, math.sqrt(0.5), math.sqrt(0.5)], rtol=1e-12)


def test_ambient_only_shows_exactly_the_face_colours_in_every_mode():
    rng = np.random.default_rng(6)
    colours = rng.random((2, 3))
    frags = fragments(rng.integers(0, 2, 20), random_bary(rng, 20))
    for mode in ("flat", "gouraud", "phong"):
        out = shade(frags, VERTICES, FACES, mode=mode, material=Material(ka=1.0, kd=0.9, ks=0.9),
                    lights=[Light("ambient")], viewer=OVERHEAD, face_colours=colours)
        np.testing.assert_array_equal(out, colours[frags.face])


@pytest.mark.parametrize("mode", ["flat", "gouraud", "phong"])
def test_a_prepared_shader_gives_each_fragment_set_what_shade_gives_them_all(mode):
    rng = np.random.default_rng(7)
    face, bary = rng.integers(0, 2, 40), random_bary(rng, 40)
    options = {"mode": mode, "material": Material(colour=(0.9, 0.5, 0.2), ks=0.5), "viewer": OVERHEAD,
               "lights": [Light("ambient", (0.2, 0.2, 0.2)), Light("point", (1, 1, 1), position=(0.3, 0.2, 2.0))]}
    whole = shade(fragments(face, bary), VERTICES, FACES, **options)
    shader = Shader(VERTICES, FACES, **options)
    parts = [shader(fragments(face[part], bary[part])) for part in (slice(0, 13), slice(13, None))]
    assert np.array_equal(np.concatenate(parts), whole)
    assert whole.std(axis=0).max() > 0.01  # the light varies across the fragments
    with pytest.raises(InvalidArgument, match=r"outside 0\.\.1"):
        shader(fragments([2], [[1, 0, 0]]))


def test_no_fragments_gives_no_colours():
    empty = fragments(np.zeros(0, dtype=np.int64), np.zeros((0, 3)))
    for mode in ("flat", "gouraud", "phong"):
        out = shade(empty, VERTICES, FACES, mode=mode, material=Material(), lights=[Light("ambient")], viewer=OVERHEAD)
        assert out.shape == (0, 3)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"mode": "wireframe"}, "shading mode"),
    ({"faces": [[0, 1, 9]]}, "indexes outside"),
    ({"faces": [[0.0, 1.0, 2.0]]}, "integer"),
    ({"face_colours": [[1, 0, 0]]}, "face_colours must have 2 rows"),
    ({"face_colours": [[1, 0, 0], [0, 0, 1.5]]}, "face_colours components"),
    ({"vertex_normals": [[0, 0, 1]], "mode": "gouraud"}, "vertex_normals must have 4 rows"),
    ({"face_normals": [[0, 0, 1]]}, "face_normals must have 2 rows"),
    ({"vertices": [[0, 0, 0, 1]]}, "vertices"),
])
def test_shade_bad_arguments(kwargs, message):
    args = {"vertices": VERTICES, "faces": FACES, "mode": "flat", "material": Material(), "lights": [Light("ambient")],
            "viewer": OVERHEAD, **kwargs}
    vertices, faces = args.pop("vertices"), args.pop("faces")
    with pytest.raises(InvalidArgument, match=message):
        shade(fragments([0, 1], [[1, 0, 0], [0, 1, 0]]), vertices, faces, **args)


def test_shade_wrong_types():
    with pytest.raises(InvalidArgumentType, match="Fragments"):
        shade("pixels", VERTICES, FACES, mode="flat", material=Material(), lights=[], viewer=OVERHEAD)
    with pytest.raises(InvalidArgumentType, match="material"):
        shade(fragments([0], [[1, 0, 0]]), VERTICES, FACES, mode="flat", material=None, lights=[], viewer=OVERHEAD)


# ------------------------------------------------------------------ write_colours
def grid(width, height):
    ys, xs = np.divmod(np.arange(width * height), width)
    return xs, ys


def test_rgb_rounds_each_channel_and_clamps():
    values = np.array([0.0, 0.5 / 255, 1.5 / 255, 127.5 / 255, 0.49999 / 255, 1.0, -0.3, 1.7, 200.2 / 255])
    rgb = np.stack([values, values[::-1], np.roll(values, 3)], axis=1)
    xs, ys = grid(3, 3)
    for mode, layout in (("RGB", rgb), ("RGBA", rgb), ("RGB", np.asfortranarray(rgb))):  # F order: a shader's
        canvas = Canvas(3, 3, mode)
        write_colours(canvas, xs, ys, layout)
        expected = [[min(255, max(0, round(255 * c))) for c in row] for row in rgb.tolist()]  # Python round: ties even
        np.testing.assert_array_equal(canvas.array.reshape(9, -1)[:, :3], expected)
        if mode == "RGBA":
            assert (canvas.array[..., 3] == 255).all()


def test_rgb565_and_luminance_modes():
    rng = np.random.default_rng(7)
    rgb = rng.random((64, 3))
    xs, ys = grid(8, 8)
    eight = [[round(255 * c) for c in row] for row in rgb.tolist()]
    packed = Canvas(8, 8, "RGB565")
    write_colours(packed, xs, ys, rgb)
    np.testing.assert_array_equal(packed.array.ravel(), [((r & 0xF8) << 8) | ((g & 0xFC) << 3) | (b >> 3)
                                                         for r, g, b in eight])
    grey = Canvas(8, 8, "L")
    write_colours(grey, xs, ys, rgb)
    np.testing.assert_array_equal(grey.array.ravel(), [(299 * r + 587 * g + 114 * b + 500) // 1000
                                                       for r, g, b in eight])


def test_mono_is_ordered_bayer_dither_of_the_luma_anchored_to_the_frame():
    rng = np.random.default_rng(8)
    xs, ys = rng.integers(0, 32, 300), rng.integers(0, 16, 300)
    keep = np.unique(ys * 32 + xs, return_index=True)[1]
    xs, ys = xs[keep], ys[keep]
    rgb = rng.random((xs.size, 3))
    canvas = Canvas(32, 16, "1")
    write_colours(canvas, xs, ys, rgb)
    for x, y, colour in zip(xs, ys, rgb.tolist(), strict=True):
        r, g, b = (round(255 * c) for c in colour)
        grey = (299 * r + 587 * g + 114 * b + 500) // 1000
        assert canvas.array[y, x] == (grey / 255 >= (BAYER4[y % 4, x % 4] + 0.5) / 16)


@pytest.mark.parametrize("level", [0.0, 0.1, 0.3333, 0.5, 0.77, 0.97, 1.0])
def test_mono_mean_of_a_flat_area_is_within_one_level(level):
    xs, ys = grid(64, 64)
    canvas = Canvas(70, 70, "1")
    write_colours(canvas, xs + 3, ys + 5, np.full((xs.size, 3), level))
    assert abs(canvas.array[5:69, 3:67].mean() - level) <= 1 / 16


@pytest.mark.parametrize("level", [0.05, 0.2, 0.5, 0.6, 0.9])
def test_palette_mean_of_a_flat_area_is_within_one_level(level):
    greys = np.array([[0, 0, 0], [85, 85, 85], [170, 170, 170], [255, 255, 255]])
    canvas = Canvas(64, 64, "P", palette=greys)
    xs, ys = grid(64, 64)
    write_colours(canvas, xs, ys, np.full((xs.size, 3), level))
    shown = canvas.to_rgb()[..., 0] / 255.0
    assert abs(shown.mean() - level) <= 1 / 3 / 16 + 1 / 255
    assert np.unique(canvas.array).size == 2  # a mix of the two levels around the input


def test_palette_of_colours_picks_the_nearest_entry_after_the_offset():
    palette = np.array([[0, 0, 0], [255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]])
    canvas = Canvas(4, 4, "P", palette=palette)
    xs, ys = grid(4, 4)
    write_colours(canvas, xs, ys, np.tile([1.0, 0.0, 0.0], (16, 1)))
    assert (canvas.array == 1).all()  # an exact palette colour stays itself under the dither offset


def test_damage_covers_the_written_pixels():
    canvas = Canvas(40, 30, "RGB565")
    canvas.clear_damage()
    xs, ys = np.array([5, 9, 7]), np.array([12, 3, 20])
    write_colours(canvas, xs, ys, np.ones((3, 3)))
    covered = np.zeros((30, 40), dtype=bool)
    for rect in canvas.damage():
        covered[rect.slices] = True
    assert covered[ys, xs].all()
    assert not covered[:3].any() and not covered[:, :5].any() and not covered[21:].any() and not covered[:, 10:].any()


def test_native_pixels_leave_the_canvas_alone_until_stored():
    canvas = Canvas(6, 4, "RGB565")
    canvas.clear_damage()
    xs, ys, rgb = np.array([1, 5]), np.array([3, 0]), np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    pixels = native_pixels(canvas, xs, ys, rgb)
    assert not canvas.array.any() and canvas.damage() == []
    assert pixels.values.tolist() == [0xF800, 0x001F]  # RGB565 red and blue (datasheet bit layout)
    assert pixels.index.tolist() == [3 * 6 + 1, 5] and pixels.box == (1, 0, 6, 4)
    pixels.store(canvas)
    assert canvas.array[3, 1] == 0xF800 and canvas.array[0, 5] == 0x001F and canvas.damage() != []


@pytest.mark.parametrize("mode", ["RGB", "RGBA", "RGB565", "L", "1", "P"])
def test_unchecked_native_pixels_equal_the_checked_ones_on_good_input(mode):
    rng = np.random.default_rng(11)
    palette = np.array([[0, 0, 0], [255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]]) if mode == "P" else None
    canvas = Canvas(9, 7, mode, palette=palette)
    index = rng.choice(63, 40, replace=False)
    xs, ys = index % 9, index // 9
    rgb = rng.uniform(-0.05, 1.05, (40, 3))  # a little outside [0, 1] too: both clamp
    checked, unchecked = native_pixels(canvas, xs, ys, rgb), native_pixels_unchecked(canvas, xs, ys, rgb)
    assert unchecked.box == checked.box == (int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)
    np.testing.assert_array_equal(unchecked.index, checked.index)
    np.testing.assert_array_equal(unchecked.values, checked.values)
    none = native_pixels_unchecked(canvas, xs[:0], ys[:0], rgb[:0])
    assert none.box is None and none.index.size == 0


def test_empty_write_changes_nothing():
    canvas = Canvas(4, 4, "RGB")
    canvas.clear_damage()
    write_colours(canvas, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros((0, 3)))
    assert canvas.damage() == [] and not canvas.array.any()


@pytest.mark.parametrize(("xs", "ys", "rgb", "message"), [
    ([0, 4], [0, 0], [[0, 0, 0]] * 2, r"xs\[1\] = 4"),
    ([0, 1], [0, -1], [[0, 0, 0]] * 2, r"ys\[1\] = -1"),
    ([0.0, 1.0], [0, 0], [[0, 0, 0]] * 2, "integer"),
    ([0, 1], [0], [[0, 0, 0]] * 2, "ys has 1 entries"),
    ([0], [0], [[0, 0]], "shape"),
    ([0], [0], [[0, float("nan"), 0]], "row 0 is not finite"),
])
def test_write_colours_bad_arguments(xs, ys, rgb, message):
    with pytest.raises(InvalidArgument, match=message):
        write_colours(Canvas(4, 4, "RGB"), np.array(xs), np.array(ys), rgb)


def test_write_colours_needs_a_canvas():
    with pytest.raises(InvalidArgumentType, match="Canvas"):
        write_colours(np.zeros((4, 4, 3)), [0], [0], [[0, 0, 0]])


def test_ambient_alone_with_ka_one_shows_exactly_the_face_colours_through_the_zbuffer():
    # the contract of issue 12, through the z-buffer: every covered pixel holds round(255·C) of its face, even
    # where 255·C is a rounding tie (0.5, 0.9): Gouraud interpolation must reproduce a constant exactly
    from pixelpen.raster.zbuffer import ZBuffer

    xy = np.array([[[1.0, 1.0], [30.0, 2.0], [3.0, 25.0]], [[30.0, 2.0], [31.0, 28.0], [3.0, 25.0]]])
    colours = np.array([[0.2, 0.5, 0.9], [1.0, 0.25, 0.0]])
    frags = ZBuffer(32, 32).rasterize(xy, np.full((2, 3), 0.5))
    vertices = np.concatenate([xy.reshape(6, 2), np.zeros((6, 1))], axis=1)
    rgb = shade(frags, vertices, [[0, 1, 2], [3, 4, 5]], mode="gouraud", material=Material(ka=1.0, kd=0.5, ks=0.5),
                lights=[Light("ambient")], viewer=OVERHEAD, face_colours=colours)
    canvas = Canvas(32, 32, "RGB")
    write_colours(canvas, frags.xs, frags.ys, rgb)
    expected = [[round(255 * c) for c in row] for row in colours.tolist()]
    assert len(frags) > 300
    np.testing.assert_array_equal(canvas.array[frags.ys, frags.xs], np.array(expected)[frags.face])


@pytest.mark.parametrize("face_colours", [None, [[0.3, 0.6, 0.9]]])
def test_gouraud_lights_only_the_vertices_the_faces_use_with_the_same_values(face_colours):
    # one face over vertices 1, 3, 2 of four (vertex 0 unused): each fragment is the barycentric mix of the scalar
    # reference at the corners it uses
    normals = np.array([[0.0, 0.0, 1.0], [0.3, 0.1, 1.0], [-0.2, 0.4, 1.0], [0.1, -0.3, 1.0]])
    lights = [Light("ambient", (0.2, 0.2, 0.2)), Light("point", (0.9, 0.8, 0.7), position=(0.3, 0.2, 2.0))]
    material = Material(colour=(0.9, 0.5, 0.1), ka=0.5, kd=0.6, ks=0.4, n=7)
    viewer = Viewer(position=(0.5, 0.5, 3.0))
    bary = random_bary(np.random.default_rng(9), 25)
    out = shade(fragments([0] * 25, bary), VERTICES, [[1, 3, 2]], mode="gouraud", material=material, lights=lights,
                viewer=viewer, vertex_normals=normals, face_colours=face_colours)
    colour = material if face_colours is None else Material(colour=tuple(face_colours[0]), ka=0.5, kd=0.6, ks=0.4,
                                                             n=7)
    corners = [np.array(reference_intensity(list(VERTICES[i]), list(normals[i]), colour, lights, viewer))
               for i in (1, 3, 2)]
    np.testing.assert_allclose(out, bary @ np.array(corners), rtol=1e-12, atol=1e-15)

"""Tests of the 3D Scene: the camera dict, items, lights, and the front-face rule, against hand-worked values."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import pixelpen
from pixelpen.display.render3d import front_faces
from pixelpen.display.scene3d import CAMERA_KEYS, Camera, Scene
from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.geometry.mesh import Mesh

FRONT = {"vrp": (0, 0, 0), "vpn": (0, 0, 1), "vup": (0, 1, 0), "near": 5.0, "far": -5.0}
SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
SQUARE_FACES = np.array([[0, 1, 2], [0, 2, 3]])


def test_scene_is_exported_lazily_from_pixelpen():
    assert pixelpen.Scene is Scene and "Scene" in dir(pixelpen)


def test_an_unknown_camera_key_is_refused_naming_it_and_listing_the_known_ones():
    with pytest.raises(InvalidArgument, match=r"camera: unknown key\(s\) fov; known: ") as info:
        Scene(camera={**FRONT, "fov": 60})
    assert all(key in str(info.value) for key in CAMERA_KEYS)


def test_near_and_far_are_required_and_checked():
    with pytest.raises(InvalidArgument, match="camera needs near and far"):
        Scene(camera={"vpn": (0, 0, 1)})
    with pytest.raises(InvalidArgument, match="camera needs far"):
        Scene(camera={"near": 1.0})
    with pytest.raises(InvalidArgument, match="near must be > far"):
        Scene(camera={**FRONT, "near": -5.0, "far": 5.0})


@pytest.mark.parametrize(("extra", "message"), [
    ({"projection": "perspective"}, "needs z_prp"),
    ({"projection": "perspective", "z_prp": 2.0}, "z_prp must be > near"),
    ({"projection": "fisheye"}, "projection must be one of"),
    ({"projection": "oblique"}, "needs alpha and phi"),
    ({"z_prp": 20.0}, "z_prp applies to perspective"),
    ({"vup": (0, 0, 3)}, "vup"),
    ({"vpn": (0, 0, 0)}, "vpn"),
])
def test_bad_camera_values_raise_at_once(extra, message):
    with pytest.raises(InvalidArgument, match=message):
        Scene(camera={**FRONT, **extra})


def test_the_camera_must_be_a_dict():
    with pytest.raises(InvalidArgumentType, match="camera must be a dict"):
        Scene(camera=[1, 2, 3])


def test_world_to_view_follows_hearn_and_baker():
    # vpn along +x, vup +z: n = x, u = vup x n = z x x = y, v = n x u = x x y = z; vrp moves to the origin
    camera = Camera.from_dict({"vrp": (1, 2, 3), "vpn": (2, 0, 0), "vup": (0, 0, 1), "near": 1, "far": -1})
    point = np.array([4.0, 6.0, 8.0, 1.0])
    np.testing.assert_allclose(camera.world_to_view @ point, [6 - 2, 8 - 3, 4 - 1, 1], atol=1e-12)


def test_front_faces_point_towards_the_prp_in_perspective_and_against_the_projectors_in_parallel():
    # CCW triangles with normals +z, −z and +x (the last one in the plane x = −3)
    triangles = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 0], [0, 1, 0], [1, 0, 0]],
                          [[-3, 0, 0], [-3, 1, 0], [-3, 0, 1]]], float)
    window = (-5, -5, 5, 5)
    parallel = Camera.from_dict(FRONT)
    faces = np.arange(9).reshape(3, 3)
    clip = parallel.clip_coordinates(triangles.reshape(-1, 3), window)
    assert front_faces(clip, faces).tolist() == [True, False, False]
    # a perspective PRP at n = 10: the side face at x = -3 with normal +x sees the PRP (0, 0, 10)
    perspective = Camera.from_dict({**FRONT, "projection": "perspective", "z_prp": 10.0})
    clip = perspective.clip_coordinates(triangles.reshape(-1, 3), window)
    assert front_faces(clip, faces).tolist() == [True, False, True]
    assert perspective.viewer().position == pytest.approx((0, 0, 10))
    assert parallel.viewer().direction == pytest.approx((0, 0, 1))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-20, 20), min_size=9, max_size=9), st.sampled_from(["parallel", "perspective"]),
       st.floats(0.3, 3.0))
def test_the_clip_space_test_agrees_with_the_world_space_one_also_behind_the_viewer(coords, projection, tilt):
    camera = Camera.from_dict({"vrp": (0, 0, 0), "vpn": (tilt, 1.0, 2.0), "vup": (0, 0, 1), "near": 5.0,
                               "far": -25.0, "projection": projection,
                               **({"z_prp": 10.0} if projection == "perspective" else {})})
    triangle = np.array(coords).reshape(1, 3, 3)
    normal = np.cross(triangle[0, 1] - triangle[0, 0], triangle[0, 2] - triangle[0, 0])
    viewer = camera.viewer()  # the normal points towards the PRP (perspective) or the viewer (parallel)
    eye_side = np.dot(normal, np.array(viewer.position) - triangle[0, 0]) if viewer.position is not None else \
        np.dot(normal, viewer.direction)
    assume(abs(eye_side) > 1e-6 * max(1.0, float(np.linalg.norm(normal))) * 40)
    clip = camera.clip_coordinates(triangle.reshape(-1, 3), (-5, -5, 5, 5))
    assert front_faces(clip, np.array([[0, 1, 2]])).tolist() == [bool(eye_side > 0)]  # the textbook world-space test


def test_add_mesh_checks_its_arguments():
    scene = Scene(camera=FRONT)
    with pytest.raises(InvalidArgument, match="needs faces"):
        scene.add_mesh(SQUARE)
    with pytest.raises(InvalidArgument, match="face_colours must have 2 rows"):
        scene.add_mesh(SQUARE, SQUARE_FACES, face_colours=[(1, 0, 0)])
    with pytest.raises(InvalidArgument, match=r"face_colours components must lie in \[0, 1\]"):
        scene.add_mesh(SQUARE, SQUARE_FACES, face_colours=[(1, 0, 0), (2, 0, 0)])
    with pytest.raises(InvalidArgument, match="shading must be one of"):
        scene.add_mesh(SQUARE, SQUARE_FACES, shading="toon")
    with pytest.raises(InvalidArgument, match="edges must be one of"):
        scene.add_mesh(SQUARE, SQUARE_FACES, edges="all")
    with pytest.raises(InvalidArgument, match=r"material: unknown key\(s\) shine; known: colour, ka"):
        scene.add_mesh(SQUARE, SQUARE_FACES, material={"shine": 1})
    with pytest.raises(InvalidArgument, match="crease_angle"):
        scene.add_mesh(SQUARE, SQUARE_FACES, crease_angle=4.0)
    with pytest.raises(InvalidArgument, match="faces only with a vertex array"):
        scene.add_mesh(Mesh(SQUARE, SQUARE_FACES), SQUARE_FACES)
    assert scene.items == []


def test_add_mesh_applies_the_modelling_transform_and_keeps_the_material():
    scene = Scene(camera=FRONT)
    move = np.eye(4)
    move[:3, 3] = (10, 20, 30)
    item = scene.add_mesh(SQUARE, SQUARE_FACES, material={"colour": (0.5, 0.25, 1.0), "ka": 1.0}, transform=move)
    np.testing.assert_allclose(item.mesh.vertices, SQUARE + np.array([10, 20, 30]))
    assert item.material.colour == (0.5, 0.25, 1.0) and item.material.ka == 1.0 and item.shading == "flat"


def test_a_scene_without_lights_has_a_headlight_along_the_view_direction():
    scene = Scene(camera={**FRONT, "vpn": (0, 0, 2)})
    ambient, key = scene.effective_lights()
    assert ambient.kind == "ambient" and ambient.intensity == (1, 1, 1)
    assert key.kind == "directional" and key.direction == pytest.approx((0, 0, -1))  # travelling along −n
    light = scene.add_light("point", (1, 0.5, 0.5), position=(0, 0, 10), attenuation=(1, 0.1, 0))
    assert scene.effective_lights() == [light]


def test_add_light_checks_its_kind_and_needs():
    scene = Scene(camera=FRONT)
    with pytest.raises(InvalidArgument, match="light kind"):
        scene.add_light("laser")
    with pytest.raises(InvalidArgument, match="needs a position"):
        scene.add_light("point", (1, 1, 1))
    with pytest.raises(InvalidArgument, match="cutoff"):
        scene.add_light("spot", (1, 1, 1), position=(0, 0, 1), direction=(0, 0, -1), cutoff=math.pi)

"""Tests for pixelpen.geometry.viewing3d: view orientation, projections' textbook ratios, vanishing points, volumes."""

import math

import numpy as np
import pytest

from pixelpen.errors import InvalidArgument
from pixelpen.geometry.transforms3d import apply3d, compose3d, rotate_y, transform_homogeneous
from pixelpen.geometry.viewing3d import (
    CABINET,
    CAVALIER,
    STANDARD_VIEWS,
    ViewVolume,
    clip_segments_homogeneous,
    oblique,
    orthographic,
    perspective,
    vanishing_point,
    view_orientation,
)

AXES = np.eye(3)


def foreshortening(world_to_view):
    """Projected lengths of the three unit world axes (drop n): sqrt(u_k² + v_k²), from the matrix's images."""
    images = apply3d(world_to_view, AXES) - apply3d(world_to_view, (0, 0, 0))
    return np.hypot(images[:, 0], images[:, 1])


def test_view_orientation_maps_the_frame_onto_u_v_n():
    m = view_orientation((1, 2, 3), (0, 0, 5), (0, 3, 0))
    np.testing.assert_allclose(apply3d(m, [(1, 2, 3), (2, 2, 3), (1, 3, 3), (1, 2, 4)]),
                               [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)], atol=1e-15)
    # H&B: vup need not be perpendicular to vpn; v is its projection onto the view plane
    m = view_orientation((0, 0, 0), (0, 0, 1), (0, 1, 5))
    np.testing.assert_allclose(apply3d(m, [(1, 0, 0), (0, 1, 0)]), [(1, 0, 0), (0, 1, 0)], atol=1e-15)
    # looking along −x with vup (0, 1, 1): v = (0, 1, 1)/√2, u = vup × n /|..| = (0, 1, −1)/√2
    m = view_orientation((0, 0, 0), (1, 0, 0), (0, 1, 1))
    r = math.sqrt(2)
    np.testing.assert_allclose(apply3d(m, [(1, 0, 0), (0, 1, 1), (0, 1, -1)]), [(0, 0, 1), (0, r, 0), (r, 0, 0)],
                               atol=1e-15)


def test_view_orientation_errors():
    with pytest.raises(InvalidArgument, match="vpn"):
        view_orientation((0, 0, 0), (0, 0, 0), (0, 1, 0))
    with pytest.raises(InvalidArgument, match="parallel"):
        view_orientation((0, 0, 0), (0, 2, 0), (0, 1, 0))
    with pytest.raises(InvalidArgument, match="vrp"):
        view_orientation((0, 0), (0, 0, 1), (0, 1, 0))


@pytest.mark.parametrize("kind, lengths", [("front", (1, 1, 0)), ("top", (1, 0, 1)), ("side", (0, 1, 1))])
def test_elevations_show_two_axes_at_true_length(kind, lengths):
    np.testing.assert_allclose(foreshortening(orthographic(kind)), lengths, atol=1e-15)
    assert kind in STANDARD_VIEWS


def test_top_view_puts_the_front_down_the_page_and_side_view_the_front_left():
    np.testing.assert_allclose(apply3d(orthographic("top"), (0, 0, 1))[:2], (0, -1), atol=1e-15)
    np.testing.assert_allclose(apply3d(orthographic("side"), (0, 0, 1))[:2], (-1, 0), atol=1e-15)


def test_isometric_foreshortens_every_axis_by_sqrt_two_thirds():
    np.testing.assert_allclose(foreshortening(orthographic("isometric")), [math.sqrt(2 / 3)] * 3, atol=1e-15)
    # the viewer is in the direction (1, 1, 1)
    np.testing.assert_allclose(apply3d(orthographic("isometric"), (1, 1, 1)), (0, 0, math.sqrt(3)), atol=1e-15)


def test_dimetric_and_trimetric_defaults_and_formulae():
    np.testing.assert_allclose(foreshortening(orthographic("dimetric")),
                               [math.sqrt(5) / 3, 2 * math.sqrt(2) / 3, math.sqrt(5) / 3], atol=1e-15)
    np.testing.assert_allclose(foreshortening(orthographic("trimetric")),
                               [math.sqrt(7) / 3, 2 * math.sqrt(2) / 3, 1 / math.sqrt(3)], atol=1e-15)
    e, a = 0.4, 1.1
    np.testing.assert_allclose(foreshortening(orthographic("trimetric", azimuth=a, elevation=e)), [
        math.sqrt(1 - math.cos(e) ** 2 * math.sin(a) ** 2), math.cos(e),
        math.sqrt(1 - math.cos(e) ** 2 * math.cos(a) ** 2)], atol=1e-15)


def test_orthographic_errors():
    with pytest.raises(InvalidArgument, match="kind"):
        orthographic("perspective")
    with pytest.raises(InvalidArgument, match="azimuth"):
        orthographic("dimetric", azimuth=0.3)
    with pytest.raises(InvalidArgument, match="elevation"):
        orthographic("isometric", elevation=0.3)
    with pytest.raises(InvalidArgument, match="elevation"):
        orthographic("trimetric", elevation=math.pi / 2)


@pytest.mark.parametrize("alpha, length", [(CAVALIER, 1.0), (CABINET, 0.5)])
def test_oblique_cavalier_and_cabinet_ratios(alpha, length):
    phi = math.radians(30)
    m = oblique(alpha, phi)
    p = apply3d(m, (0, 0, 1))  # a unit line along z drawn at angle phi with length 1 / tan(alpha)
    np.testing.assert_allclose(p, (length * math.cos(phi), length * math.sin(phi), 1), atol=1e-15)
    np.testing.assert_allclose(apply3d(m, (2, 3, 0)), (2, 3, 0))  # the view plane is unchanged
    assert math.tan(CABINET) == pytest.approx(2) and math.tan(CAVALIER) == pytest.approx(1)


def test_oblique_errors():
    with pytest.raises(InvalidArgument, match="alpha"):
        oblique(0.0, 0.3)
    with pytest.raises(InvalidArgument, match="alpha"):
        oblique(2.0, 0.3)


@pytest.mark.parametrize("x, y, z", [(1, 2, -3), (-4, 0.5, 2), (0, 0, -10), (3, -3, 4.5)])
def test_perspective_matches_the_textbook_formula(x, y, z):
    z_prp, z_vp = 5.0, 1.0
    p = apply3d(perspective(z_prp, z_vp), (x, y, z))
    scale = (z_prp - z_vp) / (z_prp - z)
    np.testing.assert_allclose(p, (x * scale, y * scale, z_vp), atol=1e-14)


def test_perspective_errors():
    with pytest.raises(InvalidArgument, match="differ"):
        perspective(2.0, 2.0)


def test_one_two_and_three_point_perspectives_by_placement():
    proj = perspective(10.0, 0.0)
    front = view_orientation((0, 0, 0), (0, 0, 1), (0, 1, 0))
    one = compose3d(proj, front)  # face-on: only z converges, to the centre
    np.testing.assert_allclose(vanishing_point(one, (0, 0, 1)), (0, 0), atol=1e-15)
    assert vanishing_point(one, (1, 0, 0)) is None and vanishing_point(one, (0, 1, 0)) is None
    two = compose3d(proj, view_orientation((0, 0, 0), (1, 0, 1), (0, 1, 0)))  # turned about y: x and z converge
    points = [vanishing_point(two, axis) for axis in AXES]
    assert points[1] is None and points[0] is not None and points[2] is not None
    # the textbook: the vanishing points of x and z lie on the horizon v = 0, at u = ±d / tan(45°) = ±10
    np.testing.assert_allclose(sorted([points[0][0], points[2][0]]), (-10, 10), atol=1e-12)
    np.testing.assert_allclose([points[0][1], points[2][1]], (0, 0), atol=1e-12)
    three = compose3d(proj, view_orientation((0, 0, 0), (1, 1, 1), (0, 1, 0)))
    assert all(vanishing_point(three, axis) is not None for axis in AXES)
    # lines along the axis really converge there: far points of a line approach it
    far = apply3d(three, [(0.3 + 1e7, 0.2, 0.1)])[0, :2]
    np.testing.assert_allclose(far, vanishing_point(three, (1, 0, 0)), atol=1e-4)
    assert vanishing_point(orthographic("isometric"), (1, 0, 0)) is None  # parallel: none


def test_parallel_view_volume_normalisation():
    vv = ViewVolume("parallel", (-2, -1, 2, 3), near=1, far=-3)
    h = transform_homogeneous(vv.matrix, [(-2, -1, 1, 1), (2, 3, -3, 1), (0, 1, -1, 1)])
    np.testing.assert_allclose(h, [(-1, -1, 0, 1), (1, 1, 1, 1), (0, 0, 0.5, 1)])
    np.testing.assert_allclose(vv.ndc_to_window @ (1, 1, 1), (2, 3, 1))
    assert vv.viewer(np.eye(4)) is None
    # world -> view Ry(90°) takes world −x to +n: the viewer lies towards world −x
    np.testing.assert_allclose(vv.view_direction(rotate_y(math.pi / 2)), (-1, 0, 0), atol=1e-15)
    assert not vv.matrix.flags.writeable


def test_perspective_view_volume_near_far_and_window():
    vv = ViewVolume("perspective", (-1, -1, 1, 1), near=-1, far=-11, z_prp=4, z_vp=0)
    # a point on the near plane at the window corner's projector: NDC (1, 1, 0); on the far plane: z = 1
    corner_near = (1 * (4 - -1) / 4, 1 * 5 / 4, -1, 1)
    corner_far = (1 * 15 / 4, 15 / 4, -11, 1)
    h = transform_homogeneous(vv.matrix, [corner_near, corner_far])
    np.testing.assert_allclose(h[:, :3] / h[:, 3:], [(1, 1, 0), (1, 1, 1)], atol=1e-15)
    # x_ndc = x_p mapped by the window, with x_p the H&B perspective formula
    x, y, n = 0.7, -0.2, -5.0
    hp = transform_homogeneous(vv.matrix, [(x, y, n, 1)])[0]
    np.testing.assert_allclose(hp[:2] / hp[3], (x * 4 / (4 - n), y * 4 / (4 - n)), atol=1e-15)
    np.testing.assert_allclose(vv.viewer(np.eye(4)), (0, 0, 4))
    _, kept = clip_segments_homogeneous([[(0, 0, 10, 1), (0, 0, -20, 1)]])  # re-exported
    assert kept.tolist() == [0]


def test_oblique_view_volume_shears_about_the_view_plane():
    vv = ViewVolume("oblique", (-1, -1, 1, 1), near=2, far=-2, z_vp=1, alpha=CAVALIER, phi=0.0)
    h = transform_homogeneous(vv.matrix, [(0, 0, 1, 1), (0, 0, 2, 1)])
    np.testing.assert_allclose(h, [(0, 0, 0.25, 1), (1, 0, 0, 1)], atol=1e-15)
    d = vv.view_direction(np.eye(4))
    np.testing.assert_allclose(d, np.array([-1, 0, 1]) / math.sqrt(2))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"projection": "fisheye"}, "projection"),
        ({"near": -5}, "near"),
        ({"projection": "perspective"}, "z_prp"),
        ({"projection": "perspective", "z_prp": 0.5}, "z_prp"),
        ({"projection": "perspective", "z_prp": 5, "z_vp": 6}, "z_vp"),
        ({"z_prp": 5}, "perspective"),
        ({"projection": "oblique"}, "alpha"),
        ({"alpha": 0.5, "phi": 0.1}, "oblique"),
        ({"window": (1, 0, 0, 1)}, "window"),
    ],
)
def test_view_volume_validation(kwargs, message):
    args = {"projection": "parallel", "window": (-1, -1, 1, 1), "near": 1, "far": -1, **kwargs}
    with pytest.raises(InvalidArgument, match=message):
        ViewVolume(**args)

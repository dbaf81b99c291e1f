"""Tests for pixelpen.geometry.transforms3d: textbook matrices, axis rotations, quaternions, inverses, bad input."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from pixelpen.errors import InvalidArgument, InvalidArgumentType, PixelpenError
from pixelpen.geometry.transforms3d import (
    apply3d,
    as_choice,
    as_homogeneous,
    as_matrix3d,
    as_points3d,
    as_triple,
    compose3d,
    identity3d,
    invert3d,
    normal_matrix,
    quaternion,
    quaternion_matrix,
    reflect3d,
    rotate_axis,
    rotate_x,
    rotate_y,
    rotate_z,
    scale3d,
    shear3d,
    to_homogeneous,
    transform_homogeneous,
    translate3d,
)

finite = st.floats(-100, 100, allow_nan=False, allow_infinity=False)
angles = st.floats(-2 * math.pi, 2 * math.pi, allow_nan=False)
factors = st.floats(0.1, 10) | st.floats(-10, -0.1)
triples = st.tuples(finite, finite, finite)


def rodrigues(p1, p2, theta, point):
    """Rodrigues' rotation formula about the axis p1 -> p2, written from the textbook for one point."""
    k = np.subtract(p2, p1, dtype=float)
    k /= math.sqrt(k @ k)
    v = np.subtract(point, p1, dtype=float)
    c, s = math.cos(theta), math.sin(theta)
    return p1 + v * c + np.cross(k, v) * s + k * (k @ v) * (1 - c)


@st.composite
def affine_matrices(draw):
    """Random invertible affine 4x4 matrices built from rotations, scales, shears and translations."""
    p1 = draw(triples)
    direction = draw(st.tuples(st.floats(0.5, 2), st.floats(-2, 2), st.floats(-2, 2)))
    m = compose3d(
        translate3d(*draw(triples)),
        rotate_axis(p1, np.add(p1, direction), draw(angles)),
        scale3d(draw(factors), draw(factors), draw(factors)),
        shear3d(draw(st.sampled_from("xyz")), draw(st.floats(-2, 2)), draw(st.floats(-2, 2))),
    )
    return m


# ---------------------------------------------------------------------------------------------
# Textbook matrices and worked examples


def test_translate_moves_points_by_the_offset():
    m = translate3d(3, -2, 5)
    assert m.dtype == np.float64 and m.shape == (4, 4)
    np.testing.assert_array_equal(apply3d(m, [(1, 1, 1), (0, 0, 0)]), [(4, -1, 6), (3, -2, 5)])


@pytest.mark.parametrize(
    "rotation, point, expected",
    [
        # H&B: a quarter turn about z takes x to y, about x takes y to z, about y takes z to x (cyclic).
        (rotate_z, (1, 0, 0), (0, 1, 0)),
        (rotate_z, (0, 1, 0), (-1, 0, 0)),
        (rotate_x, (0, 1, 0), (0, 0, 1)),
        (rotate_x, (0, 0, 1), (0, -1, 0)),
        (rotate_y, (0, 0, 1), (1, 0, 0)),
        (rotate_y, (1, 0, 0), (0, 0, -1)),
        (rotate_z, (2, 3, 7), (-3, 2, 7)),
    ],
)
def test_quarter_turns_about_the_coordinate_axes(rotation, point, expected):
    np.testing.assert_allclose(apply3d(rotation(math.pi / 2), point), expected, atol=1e-15)


def test_axis_rotations_match_the_textbook_matrices():
    theta = 0.3
    c, s = math.cos(theta), math.sin(theta)
    np.testing.assert_allclose(rotate_z(theta), [[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    np.testing.assert_allclose(rotate_x(theta), [[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]])
    np.testing.assert_allclose(rotate_y(theta), [[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1]])


def test_rotation_about_the_main_diagonal_by_120_degrees_permutes_the_axes():
    for method in ("composition", "quaternion"):
        m = rotate_axis((0, 0, 0), (1, 1, 1), 2 * math.pi / 3, method=method)
        np.testing.assert_allclose(apply3d(m, [(1, 0, 0), (0, 1, 0), (0, 0, 1)]),
                                   [(0, 1, 0), (0, 0, 1), (1, 0, 0)], atol=1e-15)


def test_rotation_about_an_axis_parallel_to_x_worked_example():
    # the axis y = 2, z = 0 along +x: a quarter turn takes (5, 3, 0) (1 above the axis) to (5, 2, 1)
    for method in ("composition", "quaternion"):
        m = rotate_axis((0, 2, 0), (1, 2, 0), math.pi / 2, method=method)
        np.testing.assert_allclose(apply3d(m, (5, 3, 0)), (5, 2, 1), atol=1e-14)
        np.testing.assert_allclose(apply3d(m, (-4, 2, 0)), (-4, 2, 0), atol=1e-14)  # on the axis: fixed


@pytest.mark.parametrize("axis, single", [((1, 0, 0), rotate_x), ((0, 1, 0), rotate_y), ((0, 0, 1), rotate_z)])
def test_rotation_about_a_coordinate_axis_equals_the_axis_rotation(axis, single):
    for method in ("composition", "quaternion"):
        np.testing.assert_allclose(rotate_axis((0, 0, 0), axis, 0.8, method=method), single(0.8), atol=1e-15)
    # reversing the axis direction reverses the sense of rotation
    np.testing.assert_allclose(rotate_axis(axis, (0, 0, 0), 0.8), single(-0.8), atol=1e-15)


@settings(max_examples=200, deadline=None)
@given(triples, triples, angles, st.lists(triples, min_size=1, max_size=5))
def test_rotate_axis_matches_rodrigues_by_both_methods(p1, p2, theta, points):
    assume(np.linalg.norm(np.subtract(p2, p1)) > 1e-3)
    composed = rotate_axis(p1, p2, theta)
    by_quaternion = rotate_axis(p1, p2, theta, method="quaternion")
    scale = 1 + max(map(abs, (*p1, *p2)))
    np.testing.assert_allclose(composed, by_quaternion, atol=1e-13 * scale)
    expected = np.array([rodrigues(p1, p2, theta, p) for p in points])
    np.testing.assert_allclose(apply3d(composed, points), expected, atol=1e-12 * scale**2)
    np.testing.assert_allclose(apply3d(by_quaternion, points), expected, atol=1e-12 * scale**2)


def test_quaternion_worked_example_and_matrix():
    q = quaternion((0, 0, 2), math.pi / 2)  # axis normalised: (cos 45°, 0, 0, sin 45°)
    np.testing.assert_allclose(q, (math.sqrt(0.5), 0, 0, math.sqrt(0.5)))
    np.testing.assert_allclose(quaternion_matrix(q), rotate_z(math.pi / 2), atol=1e-15)
    np.testing.assert_allclose(quaternion_matrix(3 * q), rotate_z(math.pi / 2), atol=1e-15)  # normalised first
    np.testing.assert_array_equal(quaternion_matrix((1, 0, 0, 0)), np.eye(4))


def test_fixed_point_scaling_matches_the_textbook_matrix():
    # H&B: [[sx, 0, 0, (1 - sx) xf], [0, sy, 0, (1 - sy) yf], [0, 0, sz, (1 - sz) zf], [0, 0, 0, 1]]
    m = scale3d(2, 3, 4, fixed=(1, 1, 1))
    np.testing.assert_array_equal(m, [[2, 0, 0, -1], [0, 3, 0, -2], [0, 0, 4, -3], [0, 0, 0, 1]])
    np.testing.assert_array_equal(apply3d(m, [(1, 1, 1), (2, 2, 2)]), [(1, 1, 1), (3, 4, 5)])
    np.testing.assert_array_equal(scale3d(2, 2, 2), np.diag([2.0, 2, 2, 1]))


@pytest.mark.parametrize("plane, expected", [("xy", (1, 2, -3)), ("yz", (-1, 2, 3)), ("xz", (1, -2, 3))])
def test_reflections_through_coordinate_planes(plane, expected):
    np.testing.assert_array_equal(apply3d(reflect3d(plane), (1, 2, 3)), expected)
    np.testing.assert_array_equal(compose3d(reflect3d(plane), reflect3d(plane)), np.eye(4))


@pytest.mark.parametrize(
    "axis, expected",
    [
        # the contract: "z": x' = x + a z, y' = y + b z; "x": y' = y + a x, z' = z + b x;
        # "y": x' = x + a y, z' = z + b y
        ("z", (1 + 2 * 3, 2 + 5 * 3, 3)),
        ("x", (1, 2 + 2 * 1, 3 + 5 * 1)),
        ("y", (1 + 2 * 2, 2, 3 + 5 * 2)),
    ],
)
def test_shears_follow_the_contract(axis, expected):
    np.testing.assert_array_equal(apply3d(shear3d(axis, 2, 5), (1, 2, 3)), expected)


def test_shear_relative_to_a_reference_plane():
    m = shear3d("z", 2, 5, ref=1)  # H&B's z shear relative to z_ref: x' = x + a (z - z_ref)
    np.testing.assert_array_equal(apply3d(m, [(1, 2, 1), (1, 2, 3)]), [(1, 2, 1), (5, 12, 3)])


def test_compose_applies_the_last_matrix_first():
    t, r = translate3d(1, 0, 0), rotate_z(math.pi / 2)
    np.testing.assert_allclose(apply3d(compose3d(t, r), (1, 0, 0)), (1, 1, 0), atol=1e-15)  # rotate, then move
    np.testing.assert_allclose(apply3d(compose3d(r, t), (1, 0, 0)), (0, 2, 0), atol=1e-15)  # move, then rotate
    np.testing.assert_array_equal(compose3d(), np.eye(4))
    np.testing.assert_array_equal(identity3d(), np.eye(4))


@settings(max_examples=100, deadline=None)
@given(affine_matrices(), affine_matrices(), affine_matrices(), st.lists(triples, min_size=1, max_size=4))
def test_composition_is_associative_and_matches_sequential_application(a, b, c, points):
    left, right = compose3d(compose3d(a, b), c), compose3d(a, compose3d(b, c))
    scale = np.abs(left).max() + 1
    np.testing.assert_allclose(left, right, atol=1e-9 * scale)
    sequential = apply3d(a, apply3d(b, apply3d(c, points)))
    np.testing.assert_allclose(apply3d(left, points), sequential, atol=1e-9 * scale * 100)


@settings(max_examples=100, deadline=None)
@given(affine_matrices(), st.lists(triples, min_size=1, max_size=4))
def test_inverse_round_trip(m, points):
    back = apply3d(invert3d(m), apply3d(m, points))
    np.testing.assert_allclose(back, points, atol=1e-7 * (1 + np.abs(m).max()) ** 2)
    np.testing.assert_allclose(compose3d(invert3d(m), m), np.eye(4), atol=1e-8 * (1 + np.abs(m).max()) ** 2)


def test_inverse_of_a_projective_matrix():
    m = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0.5, 1], [0, 0, -0.25, 2.0]])
    np.testing.assert_allclose(invert3d(m) @ m, np.eye(4), atol=1e-15)


@pytest.mark.parametrize(
    "matrix",
    [
        scale3d(1, 0, 1),
        np.diag([1.0, 1, 0, 1]),  # drop z: a parallel projection
        np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 0], [0, 0, -1, 1.0]]),  # perspective onto z = 0
    ],
)
def test_singular_matrices_have_no_inverse(matrix):
    with pytest.raises(InvalidArgument, match="singular"):
        invert3d(matrix)


@settings(max_examples=100, deadline=None)
@given(affine_matrices(), triples, triples)
def test_normal_matrix_keeps_normals_perpendicular_to_transformed_tangents(m, t1, t2):
    t1, t2 = np.array(t1), np.array(t2)
    normal = np.cross(t1, t2)
    assume(np.linalg.norm(normal) > 1e-3 * (1 + np.linalg.norm(t1) * np.linalg.norm(t2)))
    mapped = normal_matrix(m) @ normal
    for tangent in (t1, t2):
        image = m[:3, :3] @ tangent
        assert abs(mapped @ image) <= 1e-9 * np.linalg.norm(mapped) * np.linalg.norm(image) * 1e3


def test_normal_matrix_of_a_nonuniform_scale_worked_example():
    # the plane x + y = 0 (normal (1, 1, 0)) scaled by 2 in x becomes x/2 + y = 0: normal ∝ (1/2, 1, 0)
    np.testing.assert_allclose(normal_matrix(scale3d(2, 1, 1)) @ (1, 1, 0), (0.5, 1, 0))
    with pytest.raises(InvalidArgument, match="singular"):
        normal_matrix(scale3d(0, 1, 1))


def test_homogeneous_points_and_transform_without_divide():
    h = to_homogeneous([(1, 2, 3), (4, 5, 6)])
    np.testing.assert_array_equal(h, [(1, 2, 3, 1), (4, 5, 6, 1)])
    np.testing.assert_array_equal(to_homogeneous((1, 2, 3)), [(1, 2, 3, 1)])
    projective = np.array([[2, 0, 0, 0], [0, 2, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1.0]])
    out = transform_homogeneous(projective, h)
    np.testing.assert_array_equal(out, [(2, 4, 3, 4), (8, 10, 6, 7)])
    np.testing.assert_allclose(apply3d(projective, [(1, 2, 3), (4, 5, 6)]), out[:, :3] / out[:, 3:])


def test_apply_returns_a_single_point_for_a_single_point():
    assert apply3d(np.eye(4), (1, 2, 3)).shape == (3,)
    assert apply3d(np.eye(4), [(1, 2, 3)]).shape == (1, 3)
    assert apply3d(np.eye(4), np.zeros((0, 3))).shape == (0, 3)


# ---------------------------------------------------------------------------------------------
# Bad input


def test_apply_names_the_row_mapping_to_infinity():
    m = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, -1, 1.0]])  # w = 1 - z
    with pytest.raises(InvalidArgument, match=r"row 1.*w = 0"):
        apply3d(m, [(0, 0, 0), (1, 2, 1)])


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: apply3d(np.eye(3), [(1, 2, 3)]), "4x4"),
        (lambda: apply3d(np.full((4, 4), np.nan), [(1, 2, 3)]), "NaN"),
        (lambda: apply3d(np.eye(4), [(1, 2)]), r"\(N, 3\)"),
        (lambda: apply3d(np.eye(4), [(1, 2, 3), (1, np.nan, 3)]), "row 1"),
        (lambda: apply3d(np.eye(4), [("a", 2, 3)]), "numbers"),
        (lambda: as_points3d([(1, 2, 3)], min_rows=2), "at least 2"),
        (lambda: as_homogeneous([(1, 2, 3)]), r"\(N, 4\)"),
        (lambda: as_homogeneous([(1, 2, 3, 1), (1, 2, np.inf, 1)]), "row 1"),
        (lambda: as_matrix3d("x"), "4x4"),
        (lambda: as_triple((1, 2), "vrp"), "vrp"),
        (lambda: as_triple("abc", "vrp"), "vrp"),
        (lambda: translate3d(1, math.nan, 0), "ty"),
        (lambda: scale3d(1, 1, 1, fixed=(0, 0)), "fixed"),
        (lambda: rotate_x(math.inf), "theta"),
        (lambda: rotate_axis((1, 2, 3), (1, 2, 3), 1.0), "distinct"),
        (lambda: rotate_axis((0, 0, 0), (1, 0, 0), 1.0, method="euler"), "method"),
        (lambda: quaternion((0, 0, 0), 1.0), "axis"),
        (lambda: quaternion_matrix((0, 0, 0, 0)), "non-zero"),
        (lambda: quaternion_matrix((1, 0, 0)), "quaternion"),
        (lambda: reflect3d("xx"), "plane"),
        (lambda: shear3d("w", 1, 1), "axis"),
        (lambda: compose3d(np.eye(4), np.eye(3)), "matrix 1"),
        (lambda: compose3d(np.full((4, 4), 1e200), np.full((4, 4), 1e200)), "overflows"),
        (lambda: transform_homogeneous(np.full((4, 4), 1e300), [(1e300, 1, 1, 1)]), "row 0"),
    ],
)
def test_bad_input_raises_invalid_argument_naming_the_problem(call, message):
    with pytest.raises(InvalidArgument, match=message) as info:
        call()
    assert isinstance(info.value, (PixelpenError, ValueError))


def test_wrong_types_raise_invalid_argument_type():
    with pytest.raises(InvalidArgumentType, match="theta"):
        rotate_z("1")
    with pytest.raises(InvalidArgumentType, match="plane"):
        reflect3d(3)
    with pytest.raises(InvalidArgumentType):
        translate3d(True, 0, 0)
    assert as_choice("a", "kind", ("a", "b")) == "a"

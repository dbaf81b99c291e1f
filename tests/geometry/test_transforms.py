"""Tests for pixelpen.geometry.transforms: textbook matrices, composition order, inverses, bad input."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from pixelpen.errors import InvalidArgument, PixelpenError
from pixelpen.geometry.transforms import (
    apply,
    compose,
    identity,
    invert,
    reflect,
    rotate,
    scale,
    scale_factor,
    shear,
    translate,
)

finite = st.floats(-100, 100, allow_nan=False, allow_infinity=False)
angles = st.floats(-2 * math.pi, 2 * math.pi, allow_nan=False)
factors = st.floats(0.1, 10) | st.floats(-10, -0.1)


def test_translate_moves_points_by_the_offset():
    m = translate(3, -2)
    assert m.dtype == np.float64 and m.shape == (3, 3)
    np.testing.assert_array_equal(apply(m, [(1, 1), (0, 0)]), [(4, -1), (3, -2)])


def test_rotation_about_origin_is_counter_clockwise():
    np.testing.assert_allclose(apply(rotate(math.pi / 2), (1, 0)), (0, 1), atol=1e-15)
    np.testing.assert_allclose(apply(rotate(math.pi), (2, 3)), (-2, -3), atol=1e-15)


def test_pivot_point_rotation_matches_the_textbook_matrix():
    # Hearn & Baker: R(xr, yr, theta) = T(xr, yr) R(theta) T(-xr, -yr), written out.
    theta, xr, yr = 0.7, 2.0, -1.5
    c, s = math.cos(theta), math.sin(theta)
    textbook = np.array([
        [c, -s, xr * (1 - c) + yr * s],
        [s, c, yr * (1 - c) - xr * s],
        [0, 0, 1],
    ])
    np.testing.assert_allclose(rotate(theta, about=(xr, yr)), textbook, atol=1e-15)
    t_to = np.array([[1, 0, xr], [0, 1, yr], [0, 0, 1]])
    t_back = np.array([[1, 0, -xr], [0, 1, -yr], [0, 0, 1]])
    r = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    np.testing.assert_allclose(rotate(theta, about=(xr, yr)), t_to @ r @ t_back, atol=1e-15)


def test_quarter_turn_about_a_pivot_worked_example():
    # (3, 1) is 1 unit right of the pivot (2, 1); a quarter turn puts it 1 unit above: (2, 2).
    np.testing.assert_allclose(apply(rotate(math.pi / 2, about=(2, 1)), (3, 1)), (2, 2), atol=1e-15)
    np.testing.assert_allclose(apply(rotate(1.0, about=(2, 1)), (2, 1)), (2, 1), atol=1e-15)


def test_fixed_point_scaling_matches_the_textbook_matrix():
    # Hearn & Baker: [[sx, 0, xf (1 - sx)], [0, sy, yf (1 - sy)], [0, 0, 1]]
    m = scale(2, 3, about=(1, 1))
    np.testing.assert_array_equal(m, [[2, 0, -1], [0, 3, -2], [0, 0, 1]])
    np.testing.assert_array_equal(apply(m, [(1, 1), (2, 2)]), [(1, 1), (3, 4)])


@pytest.mark.parametrize(
    "axis, expected",
    [("x", (3, -2)), ("y", (-3, 2)), ("origin", (-3, -2)), ("y=x", (2, 3)), ("y=-x", (-2, -3))],
)
def test_named_reflections(axis, expected):
    np.testing.assert_array_equal(apply(reflect(axis), (3, 2)), expected)


def test_reflection_about_a_line_through_two_points():
    np.testing.assert_allclose(reflect(((0, 0), (1, 1))), reflect("y=x"), atol=1e-15)
    np.testing.assert_allclose(reflect(((0, 0), (-2, 2))), reflect("y=-x"), atol=1e-15)
    np.testing.assert_allclose(apply(reflect(((0, 1), (5, 1))), (2, 3)), (2, -1), atol=1e-14)  # line y = 1
    np.testing.assert_allclose(apply(reflect(((2, 0), (2, 7))), (5, 4)), (-1, 4), atol=1e-14)  # line x = 2


@settings(max_examples=60, deadline=None)
@given(x0=finite, y0=finite, angle=angles, t=finite, px=finite, py=finite)
def test_reflection_fixes_its_line_and_is_an_involution(x0, y0, angle, t, px, py):
    p0, p1 = (x0, y0), (x0 + math.cos(angle), y0 + math.sin(angle))
    m = reflect((p0, p1))
    on_line = (x0 + t * math.cos(angle), y0 + t * math.sin(angle))
    np.testing.assert_allclose(apply(m, on_line), on_line, atol=1e-9)
    np.testing.assert_allclose(apply(m @ m, (px, py)), (px, py), atol=1e-9)
    assert np.linalg.det(m[:2, :2]) == pytest.approx(-1.0)


def test_shear_worked_examples_from_the_textbook():
    square = np.array([(0, 0), (1, 0), (1, 1), (0, 1)], float)
    # x-shear shx = 1/2 relative to y_ref = -1 (Hearn & Baker figure)
    np.testing.assert_allclose(apply(shear(shx=0.5, ref=(0, -1)), square), [(0.5, 0), (1.5, 0), (2, 1), (1, 1)])
    # y-shear shy = 1/2 relative to x_ref = -1
    np.testing.assert_allclose(apply(shear(shy=0.5, ref=(-1, 0)), square), [(0, 0.5), (1, 1), (1, 2), (0, 1.5)])


def test_compose_applies_the_last_matrix_first():
    m = compose(translate(1, 0), scale(2, 2))
    np.testing.assert_array_equal(apply(m, (1, 1)), (3, 2))  # scaled to (2, 2), then moved
    np.testing.assert_array_equal(compose(), identity())


transforms = st.one_of(
    st.builds(translate, finite, finite),
    st.builds(lambda a, x, y: rotate(a, (x, y)), angles, finite, finite),
    st.builds(lambda a, b, x, y: scale(a, b, (x, y)), factors, factors, finite, finite),
    st.builds(lambda a, b: shear(a, b), st.floats(-3, 3), st.floats(-3, 3)),
    st.sampled_from(["x", "y", "origin", "y=x", "y=-x"]).map(reflect),
)


@settings(max_examples=60, deadline=None)
@given(ms=st.lists(transforms, min_size=1, max_size=5), pts=st.lists(st.tuples(finite, finite), min_size=1, max_size=8))
def test_composite_equals_sequential_application(ms, pts):
    sequential = np.array(pts, float)
    for m in reversed(ms):  # compose(A, B, C) applies C first
        sequential = apply(m, sequential)
    scale_of_values = 1 + np.abs(sequential).max()
    np.testing.assert_allclose(apply(compose(*ms), pts), sequential, atol=1e-9 * scale_of_values)


@settings(max_examples=60, deadline=None)
@given(ms=st.lists(transforms, min_size=1, max_size=4), pts=st.lists(st.tuples(finite, finite), min_size=1, max_size=8))
def test_inverse_round_trips(ms, pts):
    m = compose(*ms)
    assume(abs(np.linalg.det(m)) > 1e-6)  # shear(a, 1/a) is singular: test_singular_matrices_are_rejected_clearly
    back = apply(invert(m), apply(m, pts))
    np.testing.assert_allclose(back, pts, atol=1e-7)


def test_singular_matrices_are_rejected_clearly():
    nearly = [[1, 1, 0], [1, 1 + 1e-15, 0], [0, 0, 1]]
    for m in (scale(0, 1), np.zeros((3, 3)), [[1, 2, 0], [2, 4, 0], [0, 0, 1]], nearly):
        with pytest.raises(ValueError, match="singular"):
            invert(m)


def test_invertible_but_extreme_scales_still_invert():
    m = compose(scale(1e-6, 1e-6), translate(1e5, -3e4))
    np.testing.assert_allclose(apply(invert(m), apply(m, (7, 8))), (7, 8), rtol=1e-9)


def test_scale_factor_is_device_units_per_world_unit():
    assert scale_factor(scale(2, 8)) == pytest.approx(4)
    assert scale_factor(compose(rotate(0.3), translate(5, 5))) == pytest.approx(1)
    assert scale_factor(compose(scale(3, 3), reflect("x"))) == pytest.approx(3)


def test_apply_shapes():
    assert apply(identity(), (1, 2)).shape == (2,)
    assert apply(identity(), [(1, 2)]).shape == (1, 2)
    assert apply(identity(), np.zeros((0, 2))).shape == (0, 2)


def test_apply_projective_matrix_divides_by_w_and_rejects_points_at_infinity():
    m = np.array([[1, 0, 0], [0, 1, 0], [1, 0, 1]], float)  # w = x + 1
    np.testing.assert_allclose(apply(m, (1, 4)), (0.5, 2))
    with pytest.raises(ValueError, match="infinity"):
        apply(m, (-1, 0))


@pytest.mark.parametrize(
    "points, message",
    [
        (np.zeros((3, 3)), "shape"),
        ([1, 2, 3], "shape"),
        ([(0, 0), (np.nan, 1)], "row 1"),
        ([(0, 0), (1, np.inf)], "row 1"),
        ("ab", "numbers"),
    ],
)
def test_apply_rejects_bad_points(points, message):
    with pytest.raises(ValueError, match=message):
        apply(identity(), points)


def test_bad_matrices_and_parameters_are_rejected():
    with pytest.raises(ValueError, match="3x3"):
        apply(np.eye(2), (0, 0))
    with pytest.raises(ValueError, match="NaN"):
        compose(np.full((3, 3), np.nan))
    with pytest.raises(ValueError, match="finite"):
        translate(float("nan"), 0)
    with pytest.raises(TypeError, match="tx"):
        translate("1", 0)
    with pytest.raises(ValueError, match="about"):
        rotate(1.0, about=(1, 2, 3))
    with pytest.raises(ValueError, match="unknown reflection axis"):
        reflect("z")
    with pytest.raises(ValueError, match="distinct"):
        reflect(((1, 1), (1, 1)))


@pytest.mark.parametrize("points", [[[0.0, np.inf]], [[np.nan, 1.0]], [[1e308, 0.0], [-np.inf, 0.0]]])
def test_non_finite_points_are_a_pixelpen_error_and_a_value_error(points):
    with pytest.raises(InvalidArgument, match="non-finite") as info:
        apply(identity(), points)
    assert isinstance(info.value, PixelpenError) and isinstance(info.value, ValueError)


def test_overflow_on_the_way_is_refused_not_returned_as_inf():
    with pytest.raises(InvalidArgument, match="floating-point range"):
        apply(scale(1e300, 1e300), [[1e10, 0.0]])
    with pytest.raises(InvalidArgument, match="overflows"):
        compose(scale(1e200, 1e200), scale(1e200, 1e200))
    with pytest.raises(TypeError) as info:
        translate("1", 0)
    assert isinstance(info.value, PixelpenError)


def test_place_rotates_about_the_local_origin_then_moves_it():
    from pixelpen.geometry.transforms import apply, place

    m = place((10.0, 20.0), math.pi / 2)
    np.testing.assert_allclose(apply(m, [[0.0, 0.0], [1.0, 0.0], [0.0, 2.0]]), [[10, 20], [10, 21], [8, 20]],
                               atol=1e-12)
    np.testing.assert_array_equal(place((3.0, 4.0)), [[1, 0, 3], [0, 1, 4], [0, 0, 1]])

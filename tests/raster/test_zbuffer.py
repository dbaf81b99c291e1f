"""The z-buffer against a brute-force per-pixel reference (exact rationals), fill-rule and depth-rule cases."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.raster import zbuffer
from pixelpen.raster.zbuffer import CHUNK, Fragments, Interpolant, ZBuffer

# ---------------------------------------------------------------- the scalar reference (textbook, exact)


def snap(v):
    """A coordinate on the 1/256-pixel grid, exactly (the z-buffer's documented snapping)."""
    return Fraction(int(np.rint(float(v) * 256)), 256)


def covers(tri, px, py):
    """Pixel centre (px, py) inside triangle tri (3 snapped (x, y)) under the top-left rule (y down)."""
    a, b, c = tri
    area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    if area == 0:
        return False
    if area < 0:
        b, c = c, b
    for p, q in ((a, b), (b, c), (c, a)):
        dx, dy = q[0] - p[0], q[1] - p[1]
        e = dx * (py - p[1]) - dy * (px - p[0])
        top_left = dy < 0 or (dy == 0 and dx > 0)  # left edge, or horizontal edge with the inside below
        if e < 0 or (e == 0 and not top_left):
            return False
    return True


def screen_weights(tri, px, py):
    """Screen-space barycentric weights of (px, py), exact."""
    a, b, c = tri
    area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    l1 = ((px - a[0]) * (c[1] - a[1]) - (py - a[1]) * (c[0] - a[0])) / area
    l2 = ((b[0] - a[0]) * (py - a[1]) - (b[1] - a[1]) * (px - a[0])) / area
    return 1 - l1 - l2, l1, l2


def reference(xy, depth, width, height, inv_w=None):
    """{(x, y): (face, depth, bary)} of the pixels this call wins, by brute force over pixels x triangles."""
    tris = [[(snap(x), snap(y)) for x, y in t] for t in xy]
    out = {}
    for y in range(height):
        for x in range(width):
            px, py = Fraction(2 * x + 1, 2), Fraction(2 * y + 1, 2)
            best = None
            for k, tri in enumerate(tris):
                if not covers(tri, px, py):
                    continue
                lam = screen_weights(tri, px, py)
                z = sum(w * Fraction(float(d)) for w, d in zip(lam, depth[k], strict=True))
                if best is None or z < best[1]:  # equal depth: the earlier (lower) index stays
                    best = (k, z, lam)
            if best is None:
                continue
            k, z, lam = best
            if inv_w is not None:
                lam = [w * Fraction(float(q)) for w, q in zip(lam, inv_w[k], strict=True)]
                lam = [w / sum(lam) for w in lam]
            out[(x, y)] = (k, float(z), [float(w) for w in lam])
    return out


def as_dict(fr):
    """{(x, y): (face, depth, bary)} of Fragments, checking one fragment per pixel."""
    out = {(int(x), int(y)): (int(f), float(d), b.tolist())
           for x, y, f, d, b in zip(fr.xs, fr.ys, fr.face, fr.depth, fr.bary, strict=True)}
    assert len(out) == len(fr)
    return out


def assert_matches(got, want, xy, depth):
    """Same pixels, faces, depths and weights; a different face only where two depths tie within rounding."""
    assert got.keys() == want.keys()
    for key, (face, z, bary) in want.items():
        gface, gz, gbary = got[key]
        assert gz == pytest.approx(z, abs=1e-9)
        if gface != face:  # a near-tie: the reference's winner must be as near as ours
            assert abs(gz - z) < 1e-9, (key, face, gface)
            continue
        assert gbary == pytest.approx(bary, abs=1e-9)


# ---------------------------------------------------------------- brute force on small random scenes

coord = st.integers(-12, 60).map(lambda v: v / 4)  # quarter pixels: centres often land exactly on edges
tri_xy = st.lists(st.tuples(coord, coord), min_size=3, max_size=3)
depth3 = st.lists(st.sampled_from([0.0, 0.25, 0.5, 0.75, 1.0]) | st.floats(0, 1), min_size=3, max_size=3)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(tri_xy, depth3, st.lists(st.floats(0.1, 4.0), min_size=3, max_size=3)),
                min_size=1, max_size=6), st.booleans(), st.sampled_from([13, 16]))
def test_matches_brute_force_reference(scene, perspective, width):
    # width 16: a power of two, whose flat pixel indices the buffer splits by a shift and a mask
    xy = np.array([s[0] for s in scene], dtype=float)
    depth = np.array([s[1] for s in scene], dtype=float)
    inv_w = np.array([s[2] for s in scene], dtype=float) if perspective else None
    zb = ZBuffer(width, 11)
    fr = zb.rasterize(xy, depth, inv_w)
    assert_matches(as_dict(fr), reference(xy, depth, width, 11, inv_w), xy, depth)
    covered = np.isin(np.arange(width * 11), fr.ys * width + fr.xs).reshape(11, width)
    assert np.array_equal(np.isfinite(zb.depth), covered)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(tri_xy, depth3, st.lists(st.floats(0.1, 4.0), min_size=3, max_size=3)),
                min_size=1, max_size=6), st.integers(0, 10), st.integers(1, 6))
def test_a_band_buffer_wins_the_reference_pixels_of_its_rows(scene, top, rows):
    xy = np.array([s[0] for s in scene], dtype=float)
    depth = np.array([s[1] for s in scene], dtype=float)
    inv_w = np.array([s[2] for s in scene], dtype=float)
    rows = min(rows, 11 - top)
    want = {k: v for k, v in reference(xy, depth, 13, 11, inv_w).items() if top <= k[1] < top + rows}
    band = ZBuffer(13, 6)
    band.clear(top)  # moved over the frame's rows from top on: only its first `rows` rows are compared
    got = {k: v for k, v in as_dict(band.rasterize(xy, depth, inv_w)).items() if k[1] < top + rows}
    assert_matches(got, want, xy, depth)
    assert all(top <= y < top + 6 for _, y in as_dict(band.rasterize(xy, depth, inv_w)))


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(tri_xy, depth3), min_size=1, max_size=4),
       st.lists(st.tuples(tri_xy, depth3), min_size=1, max_size=4))
def test_second_call_must_be_strictly_nearer(first, second):
    zb = ZBuffer(13, 11)
    zb.rasterize(np.array([s[0] for s in first]), np.array([s[1] for s in first]))
    before = zb.depth.copy()
    xy, depth = np.array([s[0] for s in second]), np.array([s[1] for s in second])
    got, want = as_dict(zb.rasterize(xy, depth)), reference(xy, depth, 13, 11)
    # strictly nearer than the first call's depth wins; within rounding of it either outcome is right
    unclear = {k for k, v in want.items() if abs(v[1] - before[k[1], k[0]]) < 1e-9}
    want = {k: v for k, v in want.items() if k not in unclear and v[1] < before[k[1], k[0]]}
    assert_matches({k: v for k, v in got.items() if k not in unclear}, want, xy, depth)
    assert (zb.depth <= before).all()


@settings(max_examples=60, deadline=None)
@given(tri_xy)
def test_no_pixel_outside_the_bounding_box(tri):
    xy = np.array([tri], dtype=float)
    fr = ZBuffer(13, 11).rasterize(xy, np.zeros((1, 3)))
    lo, hi = xy[0].min(axis=0), xy[0].max(axis=0)
    assert ((fr.xs + 0.5 >= lo[0]) & (fr.xs + 0.5 <= hi[0]) & (fr.ys + 0.5 >= lo[1]) & (fr.ys + 0.5 <= hi[1])).all()


# ---------------------------------------------------------------- fill rule: shared edges exactly once


def coverage_counts(tris, width, height):
    """How many of the triangles, each drawn into its own buffer, cover each pixel."""
    count = np.zeros((height, width), dtype=int)
    for t in tris:
        fr = ZBuffer(width, height).rasterize(np.array([t], dtype=float), np.zeros((1, 3)))
        count[fr.ys, fr.xs] += 1
    return count


@pytest.mark.parametrize("corners", [
    [(2.5, 2.5), (12.5, 2.5), (12.5, 9.5), (2.5, 9.5)],  # corners on pixel centres: edges through centres
    [(7.5, 0.5), (14.5, 7.5), (7.5, 14.5), (0.5, 7.5)],  # a diamond: diagonal edges through centres
    [(1.25, 3.0), (13.0, 1.5), (14.75, 12.25), (2.0, 14.0)],
])
@pytest.mark.parametrize("diagonal", [0, 1])
def test_square_split_in_two_covers_each_pixel_once(corners, diagonal):
    p = corners[diagonal:] + corners[:diagonal]
    count = coverage_counts([[p[0], p[1], p[2]], [p[0], p[2], p[3]]], 16, 16)
    whole = coverage_counts([[p[0], p[1], p[2]]], 16, 16) + coverage_counts([[p[0], p[2], p[3]]], 16, 16)
    assert count.max() == 1
    assert np.array_equal(count, whole)
    ref = np.zeros((16, 16), dtype=int)
    quad = [(snap(x), snap(y)) for x, y in p]
    for y in range(16):
        for x in range(16):
            c = (Fraction(2 * x + 1, 2), Fraction(2 * y + 1, 2))
            ref[y, x] = covers(quad[:3], *c) or covers([quad[0], quad[2], quad[3]], *c)
    assert np.array_equal(count, ref)


@pytest.mark.parametrize("centre", [(8.5, 8.5), (8.0, 8.0), (8.3, 7.9)])
def test_fan_around_a_vertex_covers_each_pixel_once(centre):
    angles = np.linspace(0, 2 * np.pi, 13)[:-1] + 0.1
    rim = np.stack([centre[0] + 7 * np.cos(angles), centre[1] + 7 * np.sin(angles)], axis=1)
    rim[::3] = np.round(rim[::3] * 2) / 2  # some rim vertices exactly on pixel centres
    fan = [[centre, tuple(rim[i]), tuple(rim[(i + 1) % 12])] for i in range(12)]
    count = coverage_counts(fan, 17, 17)
    assert count.max() == 1
    # one call with the whole fan at equal depth: the same pixels, each once
    fr = ZBuffer(17, 17).rasterize(np.array(fan), np.full((12, 3), 0.5))
    assert len(fr) == count.sum()
    assert count[fr.ys, fr.xs].all()


def test_both_windings_draw_the_same_pixels():
    tri = np.array([[[1.2, 1.7], [11.4, 3.3], [4.1, 9.6]]])
    a = as_dict(ZBuffer(13, 11).rasterize(tri, np.zeros((1, 3))))
    b = as_dict(ZBuffer(13, 11).rasterize(tri[:, ::-1], np.zeros((1, 3))))
    assert a.keys() == b.keys() and len(a) > 20


# ---------------------------------------------------------------- depth, weights, persistence


def test_perspective_correct_weights_against_projection():
    # clip-space vertices (x, y, z, w) with different w; the weights must give the clip-space point that
    # projects onto each pixel centre, and depth must be its z / w.
    clip = np.array([[-0.9, -0.8, 0.2, 1.0], [2.4, -1.5, 1.5, 3.0], [0.1, 1.8, 1.2, 2.0]])
    size = 40
    ndc = clip[:, :3] / clip[:, 3:]
    xy = np.stack([(ndc[:, 0] + 1) * size / 2, (1 - ndc[:, 1]) * size / 2], axis=1)
    fr = ZBuffer(size, size).rasterize(xy[None], ndc[None, :, 2], 1 / clip[None, :, 3])
    assert len(fr) > 300
    point = fr.bary @ clip
    assert np.allclose((point[:, 0] / point[:, 3] + 1) * size / 2, fr.xs + 0.5, atol=0.01)  # 1/256 px snapping
    assert np.allclose((1 - point[:, 1] / point[:, 3]) * size / 2, fr.ys + 0.5, atol=0.01)
    assert np.allclose(point[:, 2] / point[:, 3], fr.depth, atol=1e-3)
    assert np.allclose(fr.bary.sum(axis=1), 1)


def test_weights_are_exact_for_vertices_on_the_grid():
    xy = np.array([[[0.5, 0.5], [10.5, 0.5], [0.5, 10.5]]])
    fr = ZBuffer(12, 12).rasterize(xy, np.array([[0.0, 1.0, 0.5]]), np.array([[1.0, 0.5, 0.25]]))
    at = {(int(x), int(y)): (b, d) for x, y, b, d in zip(fr.xs, fr.ys, fr.bary, fr.depth, strict=True)}
    b, d = at[(5, 0)]  # halfway along the top edge: screen weights (1/2, 1/2, 0), 1/w = (1, 1/2)
    assert b == pytest.approx([2 / 3, 1 / 3, 0]) and d == pytest.approx(0.5)
    b, d = at[(0, 0)]
    assert b == pytest.approx([1, 0, 0]) and d == pytest.approx(0.0)


def test_depth_buffer_persists_across_calls():
    zb = ZBuffer(10, 10)
    square = np.array([[[0, 0], [10, 0], [10, 10]], [[0, 0], [10, 10], [0, 10]]], dtype=float)
    first = zb.rasterize(square, np.full((2, 3), 0.5))
    assert len(first) == 100 and (zb.depth == 0.5).all()
    assert len(zb.rasterize(square, np.full((2, 3), 0.5))) == 0  # equal depth does not win again
    assert len(zb.rasterize(square, np.full((2, 3), 0.7))) == 0
    near = zb.rasterize(square[:1], np.full((1, 3), 0.25))  # the diagonal is its left edge: 45 + 10 px
    assert len(near) == 55 and (near.face == 0).all() and (zb.depth[near.ys, near.xs] == 0.25).all()
    zb.clear()
    assert np.isinf(zb.depth).all() and len(zb.rasterize(square, np.ones((2, 3)))) == 100


def test_nearest_wins_and_ties_go_to_the_lower_index():
    big = [[-1, -1], [30, -1], [-1, 30]]
    xy = np.array([big, big, big], dtype=float)
    fr = ZBuffer(12, 12).rasterize(xy, np.array([[0.5] * 3, [0.3] * 3, [0.3] * 3]))
    assert len(fr) == 144 and (fr.face == 1).all()
    sloped = ZBuffer(12, 12).rasterize(xy[:2], np.array([[0.0, 1.0, 1.0], [0.5, 0.5, 0.5]]))
    nearer = sloped.depth < 0.5
    assert (sloped.face[nearer] == 0).all() and (sloped.face[~nearer] == 1).all() and nearer.any()


@pytest.mark.parametrize("keep", [True, False])
def test_many_chunks_with_ties_across_chunks(keep, monkeypatch):
    if not keep:  # pass 2 regenerates the chunks instead of keeping pass 1's
        monkeypatch.setattr(zbuffer, "KEEP_PIXELS", 0)
    size = 300  # 90,000 px per layer > CHUNK: rows of one triangle spread over several chunks
    assert size * size > CHUNK
    cover = [[-5, -5], [3 * size, -5], [-5, 3 * size]]
    xy = np.array([cover] * 4, dtype=float)
    depth = np.array([[0.6] * 3, [0.4] * 3, [0.4] * 3, [0.9] * 3])
    fr = ZBuffer(size, size).rasterize(xy[::-1], depth[::-1])  # indices 0..3 = layers 3, 2, 1, 0
    assert len(fr) == size * size and (fr.face == 1).all() and (fr.depth == 0.4).all()
    assert np.array_equal(np.sort(fr.ys * size + fr.xs), np.arange(size * size))


def test_huge_and_offscreen_triangles():
    zb = ZBuffer(20, 10)
    xy = np.array([[[-60000, -60000], [60000, -60000], [0, 60000]],  # covers everything
                   [[30, 0], [40, 0], [35, 5]], [[0, -10], [10, -10], [5, -1]]], dtype=float)  # off-screen
    fr = zb.rasterize(xy, np.array([[0.5] * 3, [0.1] * 3, [0.1] * 3]))
    assert len(fr) == 200 and (fr.face == 0).all()


@pytest.mark.parametrize("tri", [
    [[1, 1], [5, 5], [9, 9]],  # collinear
    [[3, 3], [3, 3], [3, 3]],  # a point
    [[2, 2], [2, 2], [8, 5]],  # two equal vertices
    [[2.6, 2.6], [2.9, 2.6], [2.6, 2.9]],  # positive area, no pixel centre inside
])
def test_degenerate_triangles_draw_nothing(tri):
    zb = ZBuffer(10, 10)
    fr = zb.rasterize(np.array([tri], dtype=float), np.zeros((1, 3)), np.ones((1, 3)))
    assert len(fr) == 0 and np.isinf(zb.depth).all()
    assert fr.bary.shape == (0, 3)


def test_empty_input():
    fr = ZBuffer(4, 4).rasterize(np.zeros((0, 3, 2)), np.zeros((0, 3)))
    assert len(fr) == 0 and fr.xs.dtype.kind == "i"


# ---------------------------------------------------------------- Fragments: subset, interpolate, compose


def test_interpolate_and_subset():
    xy = np.array([[[0, 0], [8, 0], [0, 8]]], dtype=float)
    fr = ZBuffer(8, 8).rasterize(xy, np.zeros((1, 3)))
    values = np.array([[[1.0, 0.0], [0.0, 10.0], [5.0, 5.0]]])
    out = fr.interpolate(values)
    expected = fr.bary[:, :1] * [1, 0] + fr.bary[:, 1:2] * [0, 10] + fr.bary[:, 2:] * [5, 5]
    assert np.allclose(out, expected)
    # screen-space: value 10·l1 is linear in x: l1 = (x + 0.5) / 8
    assert np.allclose(out[:, 1], 10 * (fr.xs + 0.5) / 8 + 5 * (fr.ys + 0.5) / 8)
    part = fr.subset(fr.xs < 2)
    assert len(part) == int((fr.xs < 2).sum()) and (part.xs < 2).all()
    assert len(fr.subset(np.array([0, 2]))) == 2
    assert (fr.interpolate(np.full((1, 3, 1), 0.1)) == 0.1).all()  # equal corners: exactly their value
    with pytest.raises(InvalidArgument, match="values"):
        fr.interpolate(np.zeros((1, 2, 2)))
    with pytest.raises(InvalidArgument, match="mask"):
        fr.subset(np.ones(3, dtype=bool))


def test_per_vertex_interpolant_equals_the_corner_form_bit_for_bit():
    rng = np.random.default_rng(3)
    vertices, faces = rng.uniform(-2, 2, (30, 4)), rng.integers(0, 30, (50, 3))
    xy = rng.uniform(-2, 22, (50, 3, 2))
    fr = ZBuffer(20, 20).rasterize(xy, rng.uniform(0, 1, (50, 3)), rng.uniform(0.5, 2, (50, 3)))
    assert len(fr) > 100
    got = Interpolant(vertices, faces).at(fr)
    assert np.array_equal(got, Interpolant(vertices[faces]).at(fr))
    assert np.array_equal(got, fr.interpolate(vertices[faces]))
    assert np.array_equal(got, Interpolant(vertices, faces).at_valid(fr))  # the same, without the range check
    with pytest.raises(InvalidArgument, match="per-vertex values"):
        Interpolant(vertices, faces[:, :2])
    with pytest.raises(InvalidArgument, match="outside the 30 vertices"):
        Interpolant(vertices, faces + 1)
    with pytest.raises(InvalidArgument, match="values has 1 triangles"):
        Interpolant(vertices, faces[:1]).at(fr)
    bad = Fragments(fr.xs[:1], fr.ys[:1], np.array([-1]), fr.bary[:1], fr.depth[:1])
    with pytest.raises(InvalidArgument, match="fragments show triangles -1"):
        Interpolant(vertices, faces).at(bad)


def test_compose_with_hand_clipped_triangles():
    # source triangle S = (P0, P1, P2); cut at M = (P0 + P1) / 2 into (P0, M, P2) and (M, P1, P2)
    src_xy = np.array([[1.0, 1.0], [19.0, 3.0], [6.0, 17.0]])
    src_z, src_q = np.array([0.1, 0.9, 0.5]), np.array([1.0, 0.25, 0.5])
    half = [[1, 0, 0], [0.5, 0.5, 0], [0, 0, 1]], [[0.5, 0.5, 0], [0, 1, 0], [0, 0, 1]]
    weights = np.array(half)
    # clipping interpolates homogeneous coordinates: vertex = sum_j w_ij (x_j w_j, y_j w_j, z_j w_j, w_j)
    w = 1 / src_q
    hom = np.column_stack([src_xy * w[:, None], src_z * w, w])
    pieces = weights @ hom
    xy = pieces[:, :, :2] / pieces[:, :, 3:]
    depth = pieces[:, :, 2] / pieces[:, :, 3]
    split = ZBuffer(20, 20).rasterize(xy, depth, 1 / pieces[:, :, 3])
    composed = split.compose(np.array([4, 4]), weights)
    whole = ZBuffer(20, 20).rasterize(src_xy[None], src_z[None], src_q[None])
    assert (composed.face == 4).all()
    a = {(int(x), int(y)): b for x, y, b in zip(composed.xs, composed.ys, composed.bary, strict=True)}
    b = {(int(x), int(y)): b for x, y, b in zip(whole.xs, whole.ys, whole.bary, strict=True)}
    common = a.keys() & b.keys()
    assert len(common) > 0.95 * len(b)  # M is not on the 1/256 grid: a few edge pixels may move
    for key in common:
        assert a[key] == pytest.approx(b[key], abs=1e-3)
    with pytest.raises(InvalidArgument, match="source"):
        split.compose(np.array([0]), weights[:1])


# ---------------------------------------------------------------- argument errors


@pytest.mark.parametrize(("args", "match"), [
    ((np.zeros((2, 3, 3)), np.zeros((2, 3))), "xy must have shape"),
    ((np.zeros((2, 3, 2)), np.zeros((3, 3))), "depth must have shape"),
    ((np.zeros((2, 3, 2)), np.zeros((2, 3)), np.zeros((2, 2))), "inv_w must have shape"),
    ((np.array([[[0, 0], [1, np.nan], [2, 2]]]), np.zeros((1, 3))), "xy row 0 is not finite"),
    ((np.zeros((2, 3, 2)), np.array([[0, 0, 0], [0, np.inf, 0]])), "depth row 1 is not finite"),
    ((np.zeros((1, 3, 2)), np.zeros((1, 3)), np.array([[1, 0, 1]])), "inv_w row 0 must be > 0"),
    ((np.full((1, 3, 2), 1e6), np.zeros((1, 3))), "xy row 0 has a vertex beyond"),
])
def test_bad_arguments(args, match):
    with pytest.raises(InvalidArgument, match=match):
        ZBuffer(4, 4).rasterize(*args)


def test_reused_result_memory_gives_the_same_fragments_until_the_next_reuse():
    xy = np.array([[[0.5, 0.5], [9.5, 0.5], [0.5, 7.5]], [[2.0, 1.0], [12.0, 9.0], [1.0, 10.0]]])
    depth = np.array([[0.2, 0.4, 0.6], [0.5, 0.1, 0.3]])
    fresh = as_dict(ZBuffer(13, 11).rasterize(xy, depth))
    buffer = ZBuffer(13, 11)
    first = buffer.rasterize(xy, depth, reuse=True)
    assert as_dict(first) == fresh
    buffer.clear()
    second = buffer.rasterize(xy[:1], depth[:1], reuse=True)  # fewer fragments, in the same memory
    assert as_dict(second) == as_dict(ZBuffer(13, 11).rasterize(xy[:1], depth[:1]))
    assert np.shares_memory(first.xs, second.xs)


def test_a_band_validates_its_top_row():
    with pytest.raises(InvalidArgument, match="top must be 0"):
        ZBuffer(4, 4, top=-1)
    with pytest.raises(InvalidArgumentType, match="top must be an integer"):
        ZBuffer(4, 4).clear(1.5)
    assert ZBuffer(4, 4, top=7).top == 7


def test_bad_sizes_and_types():
    with pytest.raises(InvalidArgument, match="width"):
        ZBuffer(0, 4)
    with pytest.raises(InvalidArgumentType, match="height"):
        ZBuffer(4, 2.5)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentType, match="xy"):
        ZBuffer(4, 4).rasterize([["a"]], np.zeros((1, 3)))
    assert isinstance(ZBuffer(3, 2).rasterize(np.zeros((0, 3, 2)), np.zeros((0, 3))), Fragments)


def test_coverage_equals_the_scanline_fill_of_the_same_triangles():
    # an independent algorithm (trapezoid scan conversion, integer pixel centres): shift by half a pixel
    from pixelpen.raster.polygons import triangle_spans

    rng = np.random.default_rng(12)
    xy = rng.uniform(-10, 74, (400, 3, 2))
    xy[::4] = np.round(xy[::4] * 2) / 2  # many vertices on pixel centres and edges
    fr = ZBuffer(64, 48).rasterize(xy, rng.uniform(0, 1, (400, 3)))
    row, start, end = triangle_spans(xy - 0.5, 64, 48)
    want = np.zeros((48, 64), dtype=bool)
    for r, a, b in zip(row, start, end, strict=True):
        want[r, a:b] = True
    got = np.zeros((48, 64), dtype=bool)
    got[fr.ys, fr.xs] = True
    assert np.array_equal(got, want) and len(fr) == want.sum()

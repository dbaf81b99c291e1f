"""SVG elements land where the SVG spec puts them: every element type under nested transforms, viewBox and units.

Two independent oracles: hand-written matrices (SVG 1.1 transforms and the viewBox rule of SVG 2 section 8.2)
with hand-parametrised shapes, and svgelements' own transformed geometry (``shape.segments(transformed=True)``
evaluated with ``point``). Each check is two-sided: every oracle point lies within the flattening tolerance of
our strokes, and every vertex of ours lies on the oracle curve.
"""

import io
import math

import numpy as np
import pytest
import svgelements as se
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pixelpen.vector.svgimport import read_svg

NS = 'xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink"'
PX_MM = 25.4 / 96
TOL = 0.05
UNIT_PX = {"": 1.0, "px": 1.0, "mm": 96 / 25.4, "cm": 96 / 2.54, "in": 96.0, "pt": 96 / 72, "pc": 16.0}


# ---- hand oracle: matrices -------------------------------------------------------------------------------------

def m_translate(tx, ty=0.0):
    return np.array([[1, 0, tx], [0, 1, ty], [0, 0, 1]], float)


def m_scale(sx, sy=None):
    return np.diag([sx, sx if sy is None else sy, 1.0])


def m_rotate(deg, cx=0.0, cy=0.0):
    a = math.radians(deg)
    r = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    return m_translate(cx, cy) @ r @ m_translate(-cx, -cy)


def m_skew_x(deg):
    return np.array([[1, math.tan(math.radians(deg)), 0], [0, 1, 0], [0, 0, 1]])


def m_skew_y(deg):
    return np.array([[1, 0, 0], [math.tan(math.radians(deg)), 1, 0], [0, 0, 1]])


def m_matrix(a, b, c, d, e, f):
    return np.array([[a, c, e], [b, d, f], [0, 0, 1]], float)


MATRIX_OF = {"translate": m_translate, "scale": m_scale, "rotate": m_rotate, "skewX": m_skew_x, "skewY": m_skew_y,
             "matrix": m_matrix}


def compose(functions):
    """transform="f1 f2 ..." is f1 @ f2 @ ... (SVG 1.1 section 7.6)."""
    m = np.eye(3)
    for name, args in functions:
        m = m @ MATRIX_OF[name](*args)
    return m


def viewport(width_px, height_px, viewbox, par):
    """SVG 2 section 8.2: the viewBox-to-viewport matrix of the root (x = y = 0)."""
    if viewbox is None:
        return np.eye(3)
    vx, vy, vw, vh = viewbox
    align, _, meet_or_slice = (par or "xMidYMid meet").partition(" ")
    sx, sy = width_px / vw, height_px / vh
    if align != "none":
        sx = sy = min(sx, sy) if meet_or_slice != "slice" else max(sx, sy)
    tx, ty = -vx * sx, -vy * sy
    if "xMid" in align:
        tx += (width_px - vw * sx) / 2
    if "xMax" in align:
        tx += width_px - vw * sx
    if "YMid" in align:
        ty += (height_px - vh * sy) / 2
    if "YMax" in align:
        ty += height_px - vh * sy
    return np.array([[sx, 0, tx], [0, sy, ty], [0, 0, 1]])


def apply(m, pts):
    return pts @ m[:2, :2].T + m[:2, 2]


# ---- hand oracle: shapes, densely sampled in their own coordinates -----------------------------------------------

def ellipse_arc(cx, cy, rx, ry, t0, t1, n=600):
    t = np.linspace(t0, t1, n)
    return np.column_stack([cx + rx * np.cos(t), cy + ry * np.sin(t)])


def rect_outline(x, y, w, h, rx=0.0, ry=0.0):
    if rx == 0:
        return np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h], [x, y]], float)
    pi = math.pi
    return np.vstack([
        ellipse_arc(x + w - rx, y + ry, rx, ry, -pi / 2, 0), ellipse_arc(x + w - rx, y + h - ry, rx, ry, 0, pi / 2),
        ellipse_arc(x + rx, y + h - ry, rx, ry, pi / 2, pi), ellipse_arc(x + rx, y + ry, rx, ry, pi, 3 * pi / 2),
        [[x + w - rx, y]],
    ])


# element, its outline in local user units
SHAPES = [
    ('<rect x="-20" y="-10" width="40" height="20"/>', rect_outline(-20, -10, 40, 20)),
    ('<rect x="5" y="6" width="30" height="20" rx="6" ry="4"/>', rect_outline(5, 6, 30, 20, 6, 4)),
    ('<rect x="0" y="0" width="12" height="10" rx="3"/>', rect_outline(0, 0, 12, 10, 3, 3)),  # ry = rx
    ('<circle cx="10" cy="-5" r="15"/>', ellipse_arc(10, -5, 15, 15, 0, 2 * math.pi, 2000)),
    ('<ellipse cx="-8" cy="4" rx="25" ry="9"/>', ellipse_arc(-8, 4, 25, 9, 0, 2 * math.pi, 2000)),
    ('<line x1="-3" y1="7" x2="30" y2="-12"/>', np.array([[-3, 7], [30, -12]], float)),
    ('<line x1="1mm" y1="0" x2="0.5in" y2="3pt"/>',
     np.array([[96 / 25.4, 0], [48, 4]], float)),
    ('<polyline points="0,0 10,5 20,-5 30,10"/>', np.array([[0, 0], [10, 5], [20, -5], [30, 10]], float)),
    ('<polygon points="0,0 10,0 5,8"/>', np.array([[0, 0], [10, 0], [5, 8], [0, 0]], float)),
    ('<path d="M 0 0 L 10 0 10 10 Z"/>', np.array([[0, 0], [10, 0], [10, 10], [0, 0]], float)),
]
COLOURS = [f"#{(37 * k + 16) % 256:02x}{(91 * k + 7) % 256:02x}{(53 * k + 200) % 256:02x}" for k in range(20)]

# more elements for the svgelements oracle: every path command, relative and absolute, arcs, <use>
EXTRA = [
    '<path d="M 1 2 H 20 V 15 h -5 v 3 L 3 18 l -2 -4 z"/>',
    '<path d="M 0 0 C 5 20 25 -20 30 0 S 50 20 60 0 c 3 4 6 4 9 0 s 6 -4 9 0"/>',
    '<path d="M 0 30 Q 10 10 20 30 T 40 30 q 5 -10 10 0 t 10 0"/>',
    '<path d="M 10 50 A 20 10 30 0 1 50 50 A 20 10 30 1 0 10 50 a 5 8 -20 1 1 10 5 Z"/>',
    '<path d="m 60 60 a 10 10 0 0 0 20 0 a 10 10 0 0 0 -20 0 m 30 0 l 5 5"/>',
    '<use xlink:href="#proto" x="7" y="-3"/>',
    '<use href="#proto" transform="rotate(45) scale(0.5, 2)"/>',
]
DEFS = '<defs><path id="proto" d="M 0 0 L 8 0 A 4 4 0 0 1 8 8 L 0 8 z" stroke="#123456" fill="none"/></defs>'


def document(root_attrs, groups, body):
    opening = "".join(f'<g transform="{t}">' for t in groups)
    return f'<svg {NS} {root_attrs}>{DEFS}{opening}{body}{"</g>" * len(groups)}</svg>'.encode()


def transform_text(functions):
    return " ".join(f"{name}({', '.join(format(a, '.12g') for a in args)})" for name, args in functions)


# ---- comparison --------------------------------------------------------------------------------------------------

def point_to_polylines(points, polylines):
    """Distance from each point to the nearest segment of any polyline."""
    segs = np.vstack([np.hstack([p[:-1], p[1:]]) for p in polylines if len(p) > 1])
    a, d = segs[:, :2], segs[:, 2:] - segs[:, :2]
    best = np.full(len(points), np.inf)
    for chunk in range(0, len(points), 512):
        w = points[chunk:chunk + 512, None, :] - a[None]
        dd = np.maximum((d * d).sum(-1), 1e-300)
        s = np.clip((w * d).sum(-1) / dd, 0, 1)
        dist = np.hypot(*(w - s[..., None] * d).transpose(2, 0, 1)).min(axis=1)
        best[chunk:chunk + 512] = dist
    return best


def assert_same_curves(ours, oracle, tol, eps):
    """Every oracle point within tol + eps of our strokes; every vertex of ours within eps of the oracle."""
    assert ours, "no strokes imported"
    dense = np.vstack(oracle)
    assert point_to_polylines(dense, ours).max() <= tol + eps
    assert point_to_polylines(np.vstack(ours), oracle).max() <= eps


def strokes_by_colour(dl):
    colour_of_pen = dl.pen_colours
    out = {}
    for i, pts in enumerate(dl.strokes()):
        out.setdefault(colour_of_pen[int(dl.pens[i])], []).append(pts)
    return out


# ---- strategies --------------------------------------------------------------------------------------------------

angles = st.floats(-180, 180)
offsets = st.floats(-40, 40)
factors = st.one_of(st.floats(0.3, 2.5), st.floats(-2.5, -0.3))
functions = st.one_of(
    st.tuples(st.just("translate"), st.tuples(offsets, offsets)),
    st.tuples(st.just("rotate"), st.tuples(angles)),
    st.tuples(st.just("rotate"), st.tuples(angles, offsets, offsets)),
    st.tuples(st.just("scale"), st.tuples(factors, factors)),
    st.tuples(st.just("scale"), st.tuples(factors)),
    st.tuples(st.just("skewX"), st.tuples(st.floats(-50, 50))),
    st.tuples(st.just("skewY"), st.tuples(st.floats(-50, 50))),
    st.tuples(st.just("matrix"), st.tuples(factors, st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), factors,
                                           offsets, offsets)),
)
group_stacks = st.lists(st.lists(functions, min_size=1, max_size=3), min_size=0, max_size=3)
pars = st.sampled_from([None, "none", "xMidYMid meet", "xMinYMin meet", "xMaxYMax meet", "xMidYMid slice",
                        "xMinYMax slice", "xMaxYMin meet"])
roots = st.tuples(
    st.sampled_from(list(UNIT_PX)), st.floats(50, 300), st.floats(50, 300),
    st.one_of(st.none(), st.tuples(offsets, offsets, st.floats(40, 300), st.floats(40, 300))), pars,
)


def root_of(unit, w, h, viewbox, par):
    attrs = f'width="{w:.6g}{unit}" height="{h:.6g}{unit}"'
    if viewbox is not None:
        attrs += ' viewBox="{}"'.format(" ".join(f"{v:.6g}" for v in viewbox))
        if par is not None:
            attrs += f' preserveAspectRatio="{par}"'
    w_px, h_px = float(f"{w:.6g}") * UNIT_PX[unit], float(f"{h:.6g}") * UNIT_PX[unit]
    vb = None if viewbox is None else tuple(float(f"{v:.6g}") for v in viewbox)
    return attrs, viewport(w_px, h_px, vb, par)


def eps_for(points):
    """Round-off allowance: svgelements' mm constant is 5e-7 off, floating point far less."""
    return 2e-6 * max(1.0, float(np.abs(np.vstack(points)).max()))


# ---- tests -------------------------------------------------------------------------------------------------------

@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(root=roots, stacks=group_stacks)
def test_basic_shapes_match_hand_computed_matrices(root, stacks):
    attrs, vp = root_of(*root)
    groups = [transform_text(fs) for fs in stacks]
    m = vp
    for fs in stacks:
        m = m @ compose(fs)
    body = "".join(el.replace("/>", f' stroke="{COLOURS[k]}" fill="none"/>') for k, (el, _) in enumerate(SHAPES))
    dl = read_svg(document(attrs, groups, body), tolerance=TOL)
    ours = strokes_by_colour(dl)
    for k, (_el, local) in enumerate(SHAPES):
        expected = apply(m, local) * PX_MM
        assert_same_curves(ours[COLOURS[k]], [expected], TOL, eps_for([expected]) + 1e-6 * TOL)


def svgelements_oracle(data):
    """Per stroke colour, svgelements' segments sampled densely and mapped through svgelements' matrices, in mm.

    Points are mapped, not segments: svgelements' ``Arc * Matrix`` is wrong for a rotated arc under a
    non-uniform scale (see :func:`test_svgelements_transformed_arcs_are_not_used`).
    """
    doc = se.SVG.parse(io.BytesIO(data), reify=False, ppi=96)
    out = {}
    for element in doc.elements():
        if not isinstance(element, se.Shape) or isinstance(element, (se.Text, se.Image)):
            continue
        matrix = element.transform
        for seg in element.segments(transformed=False):
            if isinstance(seg, se.Move) or seg.start is None:
                continue
            n = 2 if isinstance(seg, se.Linear) else 301
            pts = [matrix.point_in_matrix_space(seg.point(t)) for t in np.linspace(0, 1, n)]
            out.setdefault(element.stroke.hexrgb, []).append(np.array([[p.x, p.y] for p in pts]) * PX_MM)
    return out


def sampling_error(curves):
    """How far the oracle's own chords are from its curves: odd samples measured against the even ones' polyline."""
    sparse = [c[::2] for c in curves if len(c) > 2]
    if not sparse:
        return 0.0
    long_enough = [c for c in curves if len(c) > 2]
    return float(max(point_to_polylines(c[1::2], [s]).max() for c, s in zip(long_enough, sparse, strict=False)))


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(root=roots, stacks=group_stacks)
def test_every_element_type_matches_svgelements_geometry(root, stacks):
    attrs, _ = root_of(*root)
    groups = [transform_text(fs) for fs in stacks]
    elements = [el for el, _ in SHAPES] + EXTRA
    body = "".join(el.replace("/>", f' stroke="{COLOURS[k]}" fill="none"/>') for k, el in enumerate(elements))
    data = document(attrs, groups, body)
    ours, oracle = strokes_by_colour(read_svg(data, tolerance=TOL)), svgelements_oracle(data)
    assert set(ours) == set(oracle) and len(oracle) >= len(elements) - 1  # the two <use> share #123456's colour
    for colour, curves in oracle.items():
        # dense samples of a curve are themselves chords: allow their sagitta on top of round-off
        assert_same_curves(ours[colour], curves, TOL, eps_for(curves) + sampling_error(curves))


def test_rotated_rect_corners_by_hand():
    # the example on an A4 landscape page in mm: rotate(30) then translate(150, 50)
    data = document(
        'width="297mm" height="210mm" viewBox="0 0 297 210"',
        ["translate(150,50) rotate(30)"],
        '<rect x="-20" y="-10" width="40" height="20" stroke="black"/>',
    )
    dl = read_svg(data)
    c, s = math.sqrt(3) / 2, 0.5
    # (x, y) -> (150 + x c - y s, 50 + x s + y c)
    corners = [
        (150 - 20 * c + 10 * s, 50 - 20 * s - 10 * c),
        (150 + 20 * c + 10 * s, 50 + 20 * s - 10 * c),
        (150 + 20 * c - 10 * s, 50 + 20 * s + 10 * c),
        (150 - 20 * c - 10 * s, 50 - 20 * s + 10 * c),
    ]
    np.testing.assert_allclose(dl.stroke(0), corners + corners[:1], atol=1e-9)
    np.testing.assert_allclose(dl.stroke(0)[0], [137.67949192431, 31.33974596216], atol=1e-9)
    assert dl.page == (297.0, 210.0)


def test_units_scale_the_page_exactly():
    # 4 in x 2 in, 96 user units per inch: the point (48, 24) is (1.27 cm, 0.635 cm) exactly
    dl = read_svg(
        document(
            'width="4in" height="2in" viewBox="0 0 384 192"', [], '<line x1="0" y1="0" x2="48" y2="24" stroke="black"/>'
        )
    )
    np.testing.assert_allclose(dl.points, [[0, 0], [12.7, 6.35]], rtol=1e-12, atol=1e-12)
    assert dl.page == pytest.approx((101.6, 50.8), rel=1e-12)


def test_circle_under_skew_is_an_ellipse_through_the_mapped_points():
    # skewX(45) maps the circle's points (r cos t, r sin t) to (r cos t + r sin t, r sin t)
    dl = read_svg(
        document(
            'width="100mm" height="100mm" viewBox="0 0 100 100"',
            ["translate(50,50) skewX(45)"],
            '<circle r="20" stroke="black" fill="none"/>',
        ),
        tolerance=0.01,
    )
    pts = dl.stroke(0) - [50, 50]
    y = pts[:, 1]
    x = pts[:, 0] - y  # undo the skew
    np.testing.assert_allclose(np.hypot(x, y), 20, rtol=1e-9)
    assert np.ptp(pts[:, 0]) == pytest.approx(2 * 20 * math.sqrt(2), rel=1e-3)  # widest at t = 45 degrees


def test_mirrored_arc_keeps_its_direction():
    # scale(-1, 1) mirrors a sweep-flag arc: the upper half circle from (0,0) to (20,0) lands at x <= 0
    dl = read_svg(
        document(
            'width="100mm" height="100mm" viewBox="0 0 100 100"',
            ["translate(50,50) scale(-1,1)"],
            '<path d="M 0 0 A 10 10 0 0 1 20 0" stroke="black" fill="none"/>',
        )
    )
    pts = dl.stroke(0) - [50, 50]
    np.testing.assert_allclose(np.hypot(pts[:, 0] + 10, pts[:, 1]), 10, rtol=1e-9)
    assert pts[:, 1].min() == pytest.approx(-10, abs=0.05) and pts[:, 0].max() <= 1e-9


def test_svgelements_transformed_arcs_are_not_used():
    # a rotated elliptical arc under scale(-2.5, 0.3): the arc's own points mapped by the hand matrix are the truth
    d = "M 10 50 A 20 10 30 0 1 50 50"
    data = document('width="50" height="50"', ["scale(-2.5, 0.3)"], f'<path d="{d}" stroke="black" fill="none"/>')
    m = m_scale(-2.5, 0.3)
    arc = list(se.Path(d))[1]
    truth = apply(m, np.array([[p.x, p.y] for p in (arc.point(t) for t in np.linspace(0, 1, 1000))])) * PX_MM
    assert_same_curves([read_svg(data).stroke(0)], [truth], TOL, 1e-4)
    # svgelements' own transformed arc (what reify=True gives) is several mm off: importing it would be wrong
    moved = arc * se.Matrix("scale(-2.5, 0.3)")
    theirs = np.array([[p.x, p.y] for p in (moved.point(t) for t in np.linspace(0, 1, 1000))]) * PX_MM
    assert point_to_polylines(theirs, [truth]).max() > 1.0

"""Tests of the picture data model: validation of primitives and styles, segments, walking."""

import numpy as np
import pytest

from pixelpen.display.picture import (
    Arc,
    Bezier,
    BSpline,
    Circle,
    Ellipse,
    Fill,
    Image,
    Marker,
    Picture,
    Polygon,
    Polyline,
    Rectangle,
    Segment,
    Style,
    Text,
    parse_colour,
)
from pixelpen.errors import ConfigError, PixelpenError


def test_colours():
    assert parse_colour("#f00") == (255, 0, 0)
    assert parse_colour("#0080ff") == (0, 128, 255)
    assert parse_colour((1, 2, 3)) == (1, 2, 3)
    for bad in ("#12", "nocolour", (256, 0, 0), (1.5, 0, 0), "#gggggg"):
        with pytest.raises(ConfigError):
            parse_colour(bad)


@pytest.mark.parametrize(
    "make",
    [
        lambda: Polyline(np.zeros((0, 2))),
        lambda: Polyline([[0, 0, 0]]),
        lambda: Polyline([[0, np.nan]]),
        lambda: Polygon([[0, 0], [1, 1]]),
        lambda: Circle((0, 0), -1),
        lambda: Bezier([[0, 0], [1, 1], [2, 2]], degree=3),
        lambda: BSpline([[0, 0], [1, 1]], degree=2),
        lambda: BSpline([[0, 0], [1, 1], [2, 2]], degree=2, knots=(0, 1, 0, 1, 1, 1)),
        lambda: Image(np.zeros((2, 2), np.float32), (0, 0, 1, 1)),
        lambda: Style(width=-1),
        lambda: Style(dash=(1,)),
        lambda: Style(pen=0),
        lambda: Fill("zigzag"),
        lambda: Fill("hatch", spacing=0),
        lambda: Fill("pattern"),
    ],
)
def test_invalid_primitives_are_refused(make):
    with pytest.raises(ConfigError):
        make()


def test_points_are_read_only_copies():
    pts = np.array([[0.0, 0.0], [1.0, 1.0]])
    line = Polyline(pts)
    with pytest.raises(ValueError):
        line.points[0, 0] = 5


def test_segments_walk_with_their_transform_and_hide():
    pic = Picture()
    pic.add(Circle((0, 0), 1))
    seg = Segment("s", transform=np.diag([2.0, 2.0, 1.0]))
    seg.add(Circle((1, 1), 1))
    pic.add(seg)
    hidden = Segment("h", visible=False)
    hidden.add(Circle((9, 9), 1))
    pic.add(hidden)
    walked = list(pic.walk())
    assert len(walked) == 2 and walked[1][1][0, 0] == 2.0 and walked[1][2] is seg
    with pytest.raises(ConfigError, match="already exists"):
        pic.add(Segment("s"))
    with pytest.raises(KeyError, match="s, h"):
        pic.segment("x")
    with pytest.raises(ConfigError):
        pic.add("not a primitive")


@pytest.mark.parametrize(
    "make, error, words",
    [
        (lambda: Text((0, 0), 5), TypeError, "text must be a string"),
        (lambda: Marker([[0, 0]], size="2"), TypeError, "marker size"),
        (lambda: Arc((0, 0), 1, 1, [0.5], 2.0), TypeError, "arc start"),
        (lambda: Ellipse((0, 0), 1, 1, angle=float("inf")), ValueError, "ellipse angle"),
        (lambda: Circle((0, 0), 1e308), ValueError, "circle radius"),  # finite, but its extent overflows
        (lambda: Circle((0, 0), 10**400), ValueError, "circle radius"),  # float() would raise OverflowError
        (lambda: Rectangle(0, 0, "1", 1), TypeError, "rectangle x1"),
        (lambda: Polyline([[0, 0], [1e300, 0]]), ValueError, "beyond"),
        (lambda: Style(dash=(1, float("nan"))), ValueError, "dash"),
        (lambda: Style(pen=10**30), ValueError, "pen number"),
        (lambda: Style(pen=2.0), TypeError, "pen number"),
        (lambda: Style(layer=["a"]), TypeError, "layer"),
        (lambda: Fill("pattern", pattern=5), TypeError, "rows"),
        (lambda: Fill("pattern", pattern=((1, 2),)), ValueError, "0 or 1"),
        (lambda: Fill("pattern", pattern=((1, 0), (1,))), ValueError, "one length"),
        (lambda: Fill("hatch", spacing=1e-300), ValueError, "hatch spacing"),
        (lambda: Text((0, 0), "a", align={}), ValueError, "align"),
        (lambda: Segment("s", transform=np.full((3, 3), np.inf)), ValueError, "transform"),
        (lambda: Segment("s", visible="no"), TypeError, "visible"),
        (lambda: Picture(window=(0, 0, 0, 10)), ValueError, "degenerate"),
    ],
)
def test_bad_fields_are_pixelpen_errors_of_the_matching_builtin(make, error, words):
    with pytest.raises(error, match=words) as info:
        make()
    assert isinstance(info.value, PixelpenError)


def test_checked_fields_are_stored_as_floats():
    arc = Arc((1, 2), 3, 4, 0, 1)
    assert arc.center == (1.0, 2.0) and isinstance(arc.rx, float)
    assert Style(pen=np.int64(3)).pen == 3 and type(Style(pen=np.int64(3)).pen) is int
    assert Fill("pattern", pattern=[[1, 0], [0, 1]]).pattern == ((1, 0), (0, 1))


def test_curve_degrees_are_bounded():
    from pixelpen.display import picture

    Bezier(np.zeros((picture.MAX_DEGREE + 1, 2)))  # one curve of the highest degree
    with pytest.raises(ConfigError, match="Bezier degree"):  # flattening a degree-1000 curve took seconds per level
        Bezier(np.zeros((picture.MAX_DEGREE + 2, 2)))
    with pytest.raises(ConfigError, match="B-spline degree"):
        BSpline(np.zeros((100, 2)), degree=picture.MAX_DEGREE + 1)
    Bezier(np.zeros((3 * 1000 + 1, 2)), degree=3)  # long paths of low degree are fine


def test_lengths_in_millimetres_and_text_are_bounded():
    from pixelpen.display import picture

    with pytest.raises(ConfigError, match="line width"):  # the raster engine refused a 1e12 mm wide stroke late
        Style(width=picture.MAX_LENGTH_MM * 2)
    with pytest.raises(ConfigError, match="marker size"):
        Marker([[0, 0]], size=picture.MAX_LENGTH_MM * 2)
    with pytest.raises(ConfigError, match="longer than"):
        Text((0, 0), "W" * (picture.MAX_TEXT + 1))
    assert Style(width=picture.MAX_LENGTH_MM).width == picture.MAX_LENGTH_MM

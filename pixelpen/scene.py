"""The reference scene of ``pixelpen demo``: every primitive, attribute and viewing feature on one page."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from pixelpen import geometry as geo
from pixelpen.display.base import Display
from pixelpen.display.kinds import RasterDisplay
from pixelpen.display.picture import (
    Arc,
    Bezier,
    BSpline,
    Circle,
    Ellipse,
    Fill,
    Image,
    Marker,
    MarkerKind,
    Picture,
    Polygon,
    Polyline,
    Rectangle,
    Segment,
    Style,
    Text,
)
from pixelpen.display.registry import open_display
from pixelpen.urls import format_url

WORLD = (0.0, 0.0, 200.0, 140.0)
"""The scene's world window, in millimetres: a 200 x 140 area, y up."""
PAGE = (0.0, 0.0, 260.0, 140.0)
"""The demo page: the scene on the left, two magnified insets in a 60 mm strip on the right."""
GREEN = "#00a000"
"""The scene's green, lighter than CSS ``green`` (#008000): the one the picture layer named green before colour.py."""
LIT_LEVEL = 96
"""A mono raster lights a pixel of the colour scene (on black) whose brightest channel reaches this."""
INSETS = (
    # (world window, window angle, page rectangle of the inset's viewport)
    ((15.0, 60.0, 55.0, 90.0), np.pi / 10, (205.0, 73.0, 255.0, 135.0)),
    ((100.0, 10.0, 150.0, 50.0), 0.0, (205.0, 5.0, 255.0, 67.0)),
)


def reference_scene() -> Picture:
    """Build the reference scene in world coordinates (millimetres, y up)."""
    pic = Picture(window=WORLD)
    ink, red, blue, green = Style(), Style(colour="red"), Style(colour="blue"), Style(colour=GREEN)
    pic.add(Rectangle(2, 2, 198, 138, Style(width=0.5)))
    pic.add(Text((6, 128), "pixelpen reference scene", height=6, style=ink))

    # line types and widths
    for k, dash in enumerate([None, (3.0, 1.5), (0.5, 1.0), (4.0, 1.0, 0.5, 1.0)]):
        pic.add(Polyline([[6, 115 - 5 * k], [60, 115 - 5 * k]], Style(dash=dash, width=0.25 * k)))

    # a concave polygon with a hole, hatched; a solid one; a cross-hatched one
    star = _star((30, 75), 18, 8, 5)
    hole = _regular((30, 75), 4, 6)
    pic.add(Polygon((star, hole), Style(colour="blue", fill=Fill("hatch", angle=np.pi / 4, spacing=1.5))))
    pic.add(Polygon(_regular((70, 75), 12, 6), Style(colour="darkorange", fill=Fill("solid"))))
    pic.add(Rectangle(90, 62, 115, 88, Style(colour="purple", fill=Fill("crosshatch", angle=0.3, spacing=2.0))))

    # conics
    pic.add(Circle((135, 110), 14, red))
    pic.add(Ellipse((170, 110), 20, 9, angle=np.pi / 6, style=Style(colour=GREEN, fill=Fill("solid", outline=True))))
    pic.add(Arc((135, 75), 12, 12, 0.0, 1.5 * np.pi, style=blue))
    pic.add(Arc((165, 75), 14, 10, np.pi / 4, 5 * np.pi / 4, close="chord", style=red))
    pic.add(
        Arc(
            (185, 75),
            10,
            10,
            0.0,
            np.pi / 2,
            close="pie",
            style=Style(colour="saddlebrown", fill=Fill("hatch", spacing=1.0)),
        )
    )

    # curves: a cubic Bezier path, a degree-5 Bezier, a B-spline with its control polygon
    pic.add(Bezier([[6, 20], [20, 55], [40, -5], [55, 30], [70, 65], [80, 10], [95, 35]], degree=3, style=red))
    ctrl = np.array([[105, 15], [115, 50], [130, 20], [145, 50], [160, 15], [175, 45], [192, 20]])
    pic.add(Polyline(ctrl, Style(colour="grey", dash=(1.0, 1.0))))
    pic.add(BSpline(ctrl, degree=3, style=Style(colour="blue", width=0.4)))
    pic.add(Bezier([[6, 8], [30, 16], [60, 0], [90, 14], [100, 4], [120, 10]], style=green))
    pic.add(Marker(ctrl, kind="circle", size=2.0, style=Style(colour="grey")))
    kinds: tuple[MarkerKind, ...] = ("dot", "plus", "cross", "star", "square", "diamond")
    for k, kind in enumerate(kinds):
        pic.add(Marker([[128 + 10 * k, 6]], kind=kind, size=3.0, style=ink))

    # an image (a colour ramp) and rotated, slanted text
    yy, xx = np.mgrid[0:32, 0:48]
    ramp = np.stack([xx * 5, yy * 7, 255 - xx * 5], axis=-1).clip(0, 255).astype(np.uint8)
    pic.add(Image(ramp, (70, 100, 100, 120)))
    pic.add(Text((108, 96), "rotated", height=4, angle=np.pi / 12, slant=0.25, style=Style(colour="purple")))

    # a segment with its own transform (rotated copy of a small house), partly outside the window: clipped
    house = Segment("house", transform=geo.rotate(np.pi / 8, about=(190, 50)))
    house.add(Polygon([[180, 40], [205, 40], [205, 58], [192, 68], [180, 58]], Style(colour="black", width=0.3)))
    pic.add(house)
    return pic


def draw_reference(display: Display) -> None:
    """Draw the scene on the left of the page and, framed on the right, two insets: the star through a rotated
    window and the curves magnified, each clipped to its viewport."""
    scene = reference_scene()
    pw, ph = PAGE[2], PAGE[3]
    display.window(*WORLD)
    display.viewport(0.0, 0.0, WORLD[2] / pw, 1.0)
    display.draw(scene)
    frames = Picture()
    for window, angle, (x0, y0, x1, y1) in INSETS:
        display.window(*window, angle=angle)
        display.viewport(x0 / pw, y0 / ph, x1 / pw, y1 / ph)
        display.draw(scene)
        frames.add(Rectangle(x0, y0, x1, y1, Style(width=0.3)))
    display.window(*PAGE)
    display.viewport(0.0, 0.0, 1.0, 1.0)
    display.draw(frames)


def lit_reference(display: RasterDisplay) -> np.ndarray:
    """The reference scene for a mono raster (HxW 0/1): drawn in colour on black at its size and pitch, every stroke
    lit (drawn on the mono canvas itself, its darker colours would fall below the lit threshold)."""
    canvas, unit_mm = display.canvas, display.capabilities.unit_mm
    with tempfile.TemporaryDirectory() as folder:
        size, dpi = f"{canvas.width}x{canvas.height}", f"{25.4 / unit_mm:g}"
        url = format_url("png", str(Path(folder) / "scene.png"), {"size": size, "dpi": dpi, "background": "black"})
        with open_display(url) as colour:
            draw_reference(colour)
            colour.flush()
            rgb = colour.canvas.array.copy()  # type: ignore[attr-defined]
    return (rgb.max(axis=2) >= LIT_LEVEL).astype(np.uint8)


def show_reference(display: RasterDisplay) -> None:
    """Draw the reference scene on an open raster display (a mono one: :func:`lit_reference`) and send it."""
    if display.canvas.mode == "1":
        display.canvas.blit(lit_reference(display), 0, 0)
    else:
        draw_reference(display)
    display.flush()


def _regular(centre: tuple[float, float], r: float, n: int) -> np.ndarray:
    t = np.arange(n) * 2 * np.pi / n
    return np.column_stack([centre[0] + r * np.cos(t), centre[1] + r * np.sin(t)])


def _star(centre: tuple[float, float], r_out: float, r_in: float, points: int) -> np.ndarray:
    t = np.arange(2 * points) * np.pi / points + np.pi / 2
    r = np.where(np.arange(2 * points) % 2 == 0, r_out, r_in)
    return np.column_stack([centre[0] + r * np.cos(t), centre[1] + r * np.sin(t)])

"""Tests of drawing a 3D Scene: the z-buffer path on raster displays, hidden lines on vector ones.

Expected values are worked by hand from the textbook formulas in each test (Hearn & Baker's viewing
coordinates and projections); the only library piece used for them is the 2D window-to-device pipeline.
"""

import math

import numpy as np
import pytest

from pixelpen import geometry as geo
from pixelpen.display.capabilities import Capabilities
from pixelpen.display.kinds import RasterDisplay, VectorDisplay
from pixelpen.display.registry import open_display
from pixelpen.display.scene3d import Scene
from pixelpen.geometry.mesh import Mesh
from pixelpen.geometry.surfaces import Sphere
from pixelpen.raster.canvas import Canvas
from pixelpen.sim.base import simulator_models


class CanvasDisplay(RasterDisplay):
    """A raster display that only keeps its canvas (black background)."""

    def __init__(self, size=(20, 20), mode="RGB"):
        caps = Capabilities("canvas", "output", "raster", size, 1.0, "rgb888", y_down=True, tolerance=0.5)
        super().__init__(caps, mode=mode, background="black")

    @classmethod
    def from_url(cls, url, **kwargs):
        return cls()

    def _open_device(self):
        pass

    def _close_device(self):
        pass

    def _show(self, canvas):
        pass


class StrokeDisplay(VectorDisplay):
    """A vector display that keeps its display list (device units, y up, 1 unit = 0.1 mm)."""

    def __init__(self, size=(1000, 1000)):
        caps = Capabilities("strokes", "output", "vector", size, 0.1, "pens", y_down=False, tolerance=0.5)
        super().__init__(caps)

    @classmethod
    def from_url(cls, url, **kwargs):
        return cls()

    def _open_device(self):
        pass

    def _close_device(self):
        pass

    def _plot(self, strokes):
        pass

    def _new_sheet(self):
        pass


FRONT = {"vrp": (0, 0, 0), "vpn": (0, 0, 1), "vup": (0, 1, 0), "near": 5.0, "far": -25.0}
SQUARE = np.array([[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]], float)
SQUARE_FACES = np.array([[0, 1, 2], [0, 2, 3]])


def pixels(display):
    return np.asarray(display.canvas.to_rgb())


def test_contract_ambient_light_alone_and_ka_one_show_exactly_each_faces_colour():
    scene = Scene(camera=FRONT)
    scene.add_mesh(SQUARE, SQUARE_FACES, face_colours=[(0.2, 0.4, 0.6), (1.0, 0.8, 0.0)], material={"ka": 1.0})
    scene.add_light("ambient", (1, 1, 1))
    with CanvasDisplay() as display:
        display.window(0, 0, 10, 10)  # 2 pixels a unit, y down
        display.draw(scene)
    rgb = pixels(display).astype(int)
    # pixel (i, j) is centred on x = i / 2, y = 10 − j / 2 (as in 2D drawing): face 0 (0,0),(10,0),(10,10) where
    # y < x, i.e. i + j > 20; face 1 where i + j < 20; centres on the diagonal (i + j = 20) go to one of the two
    i, j = np.meshgrid(np.arange(20), np.arange(20))
    assert (rgb[(i + j > 20) & (i > 0) & (j > 0)] == (51, 102, 153)).all()  # round(255 · (0.2, 0.4, 0.6))
    assert (rgb[(i + j < 20) & (i > 0) & (j > 0)] == (255, 204, 0)).all()
    diagonal = rgb[(i + j == 20) & (j > 0)]
    assert ((diagonal == (51, 102, 153)).all(axis=1) | (diagonal == (255, 204, 0)).all(axis=1)).all()


def test_contract_material_colour_without_face_colours_and_on_a_panel_canvas():
    scene = Scene(camera=FRONT)
    scene.add_mesh(SQUARE, SQUARE_FACES, material={"colour": (0.2, 0.4, 0.6), "ka": 1.0, "kd": 0.5})
    scene.add_light("ambient", (1, 1, 1))
    with CanvasDisplay(size=(30, 30)) as display:
        display.window(-5, -5, 15, 15)  # the square covers pixels 7.5 .. 22.5
        display.draw(scene)
    rgb = pixels(display).astype(int)
    assert (rgb[8:22, 8:22] == (51, 102, 153)).all()
    assert (rgb[:7] == 0).all() and (rgb[23:] == 0).all() and (rgb[:, :7] == 0).all()


def test_a_shaded_face_covers_the_pixels_the_same_polygon_drawn_in_2d_covers():
    quad = np.array([[1.3, 2.7, 0], [17.6, 1.2, 0], [15.1, 16.4, 0], [3.2, 13.9, 0]])
    scene = Scene(camera=FRONT)
    scene.add_mesh(quad, SQUARE_FACES, material={"colour": (1, 1, 1), "ka": 1.0})
    scene.add_light("ambient", (1, 1, 1))
    with CanvasDisplay() as display:
        display.window(0, 0, 20, 20)
        display.draw(scene)
        shaded = pixels(display).any(axis=2)
        filled = Canvas(20, 20, "L")  # the 2D scan-line fill of the same quad in device units
        filled.polygons([geo.apply(display.pipeline.matrix, quad[:, :2])], 255)
    assert shaded.sum() > 150
    assert (shaded == (filled.array > 0)).all()


def test_back_faces_are_culled_unless_the_material_is_two_sided():
    backwards = SQUARE_FACES[:, ::-1]  # clockwise seen from the viewer: a back face
    for two_sided, lit in ((False, 0), (True, 20 * 20)):
        scene = Scene(camera=FRONT)
        scene.add_mesh(SQUARE, backwards, material={"colour": (1, 1, 1), "ka": 1.0, "two_sided": two_sided})
        scene.add_light("ambient", (1, 1, 1))
        with CanvasDisplay() as display:
            display.window(0, 0, 10, 10)
            display.draw(scene)
        assert (pixels(display).max(axis=2) > 0).sum() == lit


def test_the_nearer_of_two_overlapping_items_wins_in_either_order():
    near = SQUARE + np.array([0, 0, 1.0])
    far = SQUARE + np.array([5, 0, -1.0])
    red, blue = (near, (1, 0, 0)), (far, (0, 0, 1))
    for order in ((red, blue), (blue, red)):
        scene = Scene(camera=FRONT)
        for vertices, colour in order:
            scene.add_mesh(vertices, SQUARE_FACES, material={"colour": colour, "ka": 1.0})
        scene.add_light("ambient", (1, 1, 1))
        with CanvasDisplay(size=(40, 20)) as display:
            display.window(0, 0, 20, 10)
            display.draw(scene)
        rgb = pixels(display)
        assert (rgb[:, 0:20] == (255, 0, 0)).all()  # x 0..10: only the near (red) square
        assert (rgb[:, 20:30] == (0, 0, 255)).all()  # x 10..15: the far (blue) square shows beyond it


def painted(rgb, colour):
    mask = (rgb == colour).all(axis=2)
    ys, xs = np.nonzero(mask)
    return mask.sum(), xs.mean() + 0.5, ys.mean() + 0.5


def test_perspective_shrinks_the_far_square_by_the_textbook_ratio_and_parallel_does_not():
    # two 4 x 4 squares facing the viewer, centred at x = −5 (z = 0) and x = +5 (z = −10)
    near = np.array([[-7, -2, 0], [-3, -2, 0], [-3, 2, 0], [-7, 2, 0]], float)
    far = near + np.array([10, 0, -10])
    results = {}
    for projection in ("parallel", "perspective"):
        extra = {"projection": projection} | ({"z_prp": 20.0} if projection == "perspective" else {})
        scene = Scene(camera={**FRONT, **extra})
        scene.add_mesh(near, SQUARE_FACES, material={"colour": (1, 0, 0), "ka": 1.0})
        scene.add_mesh(far, SQUARE_FACES, material={"colour": (0, 1, 0), "ka": 1.0})
        scene.add_light("ambient", (1, 1, 1))
        with CanvasDisplay(size=(200, 200)) as display:
            display.window(-10, -10, 10, 10)  # 10 pixels a unit, device x = 10 (u + 10)
            display.draw(scene)
        rgb = pixels(display)
        results[projection] = painted(rgb, (255, 0, 0)), painted(rgb, (0, 255, 0))
    (near_area, near_x, _), (far_area, far_x, far_y) = results["parallel"]
    assert near_area == far_area == 40 * 40 and near_x == pytest.approx(50) and far_x == pytest.approx(150)
    # H&B: x_p = x · (z_prp − z_vp) / (z_prp − z): the view plane z = 0 keeps the near square; the far one at
    # z = −10 is scaled by 20 / 30 about the axis: side 8/3 units (26.7 px), centre x = 10/3 (device 133.3)
    (near_area, near_x, _), (far_area, far_x, far_y) = results["perspective"]
    assert near_area == 1600 and near_x == pytest.approx(50)
    assert far_area == pytest.approx((80 / 3) ** 2, abs=2 * 4 * 80 / 3)  # within a pixel along the perimeter
    assert far_x == pytest.approx(100 + 100 / 3, abs=0.5) and far_y == pytest.approx(100, abs=0.5)


def test_a_display_whose_window_was_never_set_fits_the_scene_keeping_the_aspect():
    scene = Scene(camera=FRONT)
    scene.add_mesh(SQUARE, SQUARE_FACES, material={"colour": (1, 1, 1), "ka": 1.0})
    scene.add_light("ambient", (1, 1, 1))
    with CanvasDisplay(size=(100, 50)) as display:
        display.draw(scene)
    lit = pixels(display).max(axis=2) > 0
    rows, cols = np.flatnonzero(lit.any(axis=1)), np.flatnonzero(lit.any(axis=0))
    # bounds 10 x 10, a 5 % margin each side: 11 x 11 units over 50 pixels, widened to 22 x 11 for the 2:1 device
    side = 50 * 10 / 11
    assert len(rows) == pytest.approx(side, abs=1) and len(cols) == pytest.approx(side, abs=1)
    assert (rows.min() + rows.max() + 1) / 2 == pytest.approx(25, abs=0.5)
    assert (cols.min() + cols.max() + 1) / 2 == pytest.approx(50, abs=0.5)


def corner_uv(vpn, vup, corners):
    """Hand-worked H&B viewing coordinates with vrp = 0: n = vpn/|vpn|, u = vup × n/|…|, v = n × u."""
    n = np.asarray(vpn, float) / math.sqrt(sum(c * c for c in vpn))
    u = np.cross(vup, n)
    u /= math.sqrt(u @ u)
    v = np.cross(n, u)
    return np.array([[p @ u, p @ v] for p in np.asarray(corners, float)])


def unit_cube():
    corners = [(x, y, z) for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)]  # index x + 2y + 4z
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return corners, Mesh.from_polygons(corners, quads)


def assert_same_segments(got, expected, tolerance):
    """Every expected segment drawn once (either direction) within tolerance, and nothing else."""
    got = np.asarray(got, float).reshape(-1, 4)
    assert len(got) == len(expected), (len(got), len(expected))
    for a, b in expected:
        forward = np.abs(got - np.r_[a, b]).max(axis=1)
        backward = np.abs(got - np.r_[b, a]).max(axis=1)
        assert min(forward.min(), backward.min()) < tolerance, (a, b)


VIEW = {"vpn": (1.0, 2.0, 3.0), "vup": (0.0, 0.0, 1.0)}
"""A general view from the all-positive octant: faces x = 1, y = 1, z = 1 are the front faces."""
VISIBLE_EDGES = [(1, 3), (3, 2), (2, 6), (6, 4), (4, 5), (5, 1), (7, 3), (7, 5), (7, 6)]
"""The cube's edges a viewer there sees: the six-edge silhouette, and the three edges meeting at (1, 1, 1)."""


def cube_scene(projection="parallel"):
    corners, cube = unit_cube()
    extra = {"z_prp": 6.0} if projection == "perspective" else {}
    scene = Scene(camera={"vrp": (0.5, 0.5, 0.5), **VIEW, "projection": projection, "near": 2.0, "far": -2.0,
                          **extra})
    scene.add_mesh(cube)
    return corners, scene


def test_a_cube_on_a_vector_display_draws_exactly_its_nine_visible_edges():
    corners, scene = cube_scene()
    with StrokeDisplay() as display:
        display.window(-1.5, -1.5, 1.5, 1.5)
        display.draw(scene)
    uv = corner_uv(VIEW["vpn"], VIEW["vup"], np.asarray(corners) - 0.5)
    device = geo.apply(display.pipeline.matrix, uv)
    expected = [(device[a], device[b]) for a, b in VISIBLE_EDGES]
    assert_same_segments(display.display_list.segments(), expected, tolerance=1e-6)


@pytest.mark.skipif("hp7475a" not in simulator_models(), reason="no HP 7475A simulator")
def test_a_cube_in_perspective_on_a_simulated_plotter_draws_its_visible_edges(sim_plotter):
    corners, scene = cube_scene("perspective")
    with open_display(sim_plotter.url) as plotter:
        plotter.window(-1.0, -1.0, 1.0, 1.0)
        plotter.draw(scene)
        matrix = plotter.pipeline.matrix
    # H&B perspective: viewing (u, v, n) projects to (u, v) · (z_prp − z_vp) / (z_prp − n), z_vp = 0
    n = np.asarray(VIEW["vpn"]) / np.linalg.norm(VIEW["vpn"])
    centred = np.asarray(corners) - 0.5
    uv = corner_uv(VIEW["vpn"], VIEW["vup"], centred) * (6.0 / (6.0 - centred @ n))[:, None]
    device = geo.apply(matrix, uv)
    expected = [(device[a], device[b]) for a, b in VISIBLE_EDGES]
    assert_same_segments(plotter.display_list.segments(), expected, tolerance=1e-6)
    # and the simulated plotter drew them: as much ink as the nine edges (its units are the display's)
    drawn, _, _ = sim_plotter.device.segments()
    assert np.hypot(drawn[:, 2] - drawn[:, 0], drawn[:, 3] - drawn[:, 1]).sum() == pytest.approx(
        sum(np.hypot(*(device[a] - device[b])) for a, b in VISIBLE_EDGES), rel=0.01)


def sphere_scene(projection="parallel"):
    scene = Scene(camera={"vrp": (0, 0, 0), "vpn": (0, 0, 1), "vup": (0, 1, 0), "projection": projection,
                          "near": 2.0, "far": -2.0})
    scene.add_surface(Sphere((0.0, 0.0, 0.0), 1.0), material={"colour": (1.0, 1.0, 1.0), "ka": 0.1, "kd": 0.9})
    scene.add_light("ambient", (1, 1, 1))
    scene.add_light("point", (1, 1, 1), position=(-3.0, 3.0, 3.0))  # upper left, in front
    return scene


def test_a_plotted_sphere_is_its_silhouette_circle_only():
    with StrokeDisplay() as display:
        display.window(-1.25, -1.25, 1.25, 1.25)  # 400 device units a world unit: radius 400 about (500, 500)
        display.draw(sphere_scene())
    points = np.concatenate(list(display.display_list.strokes()))
    radius = np.hypot(points[:, 0] - 500, points[:, 1] - 500)
    assert radius.max() <= 400 + 1e-6 and radius.min() >= 400 - 4 * 0.5  # on the circle within the tolerance
    angles = np.degrees(np.arctan2(points[:, 1] - 500, points[:, 0] - 500)) % 360
    segments = display.display_list.segments()
    assert np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1]).sum() == pytest.approx(
        2 * math.pi * 400, rel=0.01)  # once round: no hidden back half drawn over it
    assert len(np.unique(np.floor(angles / 10))) == 36


@pytest.mark.skipif("st7789" not in simulator_models(), reason="no ST7789 simulator")
def test_a_shaded_sphere_on_a_simulated_panel_is_brighter_towards_the_light(sim_panel):
    with open_display(sim_panel.url) as panel:
        panel.window(-1.2, -1.2, 1.2, 1.2)  # 100 pixels a unit, the sphere a disc of radius 100 about (120, 120)
        panel.draw(sphere_scene())
    glass = np.asarray(sim_panel.glass().convert("L")).astype(float)
    y, x = np.mgrid[0:240, 0:240] + 0.5
    inside = np.hypot(x - 120, y - 120) < 95
    outside = np.hypot(x - 120, y - 120) > 105
    assert (glass[inside] > 0).all() and glass[outside].max() == 0  # the disc on the panel's black
    upper_left = glass[inside & (x < 120) & (y < 120)].mean()
    lower_right = glass[inside & (x > 120) & (y > 120)].mean()
    assert upper_left > lower_right + 50
    # the brightest pixel lies towards the light: the normal (−1, 1, 1)/√3 at device (120 − 57.7, 120 − 57.7)
    row, col = np.unravel_index(np.argmax(np.where(inside, glass, 0)), glass.shape)
    assert col < 120 - 30 and row < 120 - 30


def test_a_scene_draws_on_file_displays_of_both_kinds(tmp_path):
    from PIL import Image

    _, scene = cube_scene()
    for url in (f"png:{tmp_path / 'cube.png'}?size=64x64", f"svg:{tmp_path / 'cube.svg'}?size=50x50mm"):
        with open_display(url) as display:
            display.draw(scene)
    png = np.asarray(Image.open(tmp_path / "cube.png").convert("RGB"))
    assert (png != 255).any(axis=2).mean() > 0.2
    assert (tmp_path / "cube.svg").read_text().count("<path") + (tmp_path / "cube.svg").read_text().count(
        "<polyline") >= 1


def test_on_a_mono_canvas_the_shading_is_dithered_denser_towards_the_light():
    with CanvasDisplay(size=(120, 120), mode="1") as display:
        display.window(-1.2, -1.2, 1.2, 1.2)
        display.draw(sphere_scene())
    lit = np.asarray(display.canvas.to_rgb()).max(axis=2) > 0
    y, x = np.mgrid[0:120, 0:120] + 0.5
    inside = np.hypot(x - 60, y - 60) < 45
    assert not lit[np.hypot(x - 60, y - 60) > 52].any()
    upper_left, lower_right = lit[inside & (x < 60) & (y < 60)].mean(), lit[inside & (x > 60) & (y > 60)].mean()
    assert upper_left > 0.6 and lower_right < 0.4  # intermediate intensities: a mixture of lit and dark pixels
    assert 0.05 < lit[inside].mean() < 0.95


def test_a_cavalier_oblique_cube_draws_the_textbook_projection_of_its_visible_edges():
    # H&B oblique: x_p = x + L cos φ, y_p = y + L sin φ, L = z / tan α; cavalier tan α = 1, φ = 30°. Projectors
    # run along (cos φ, sin φ, −1) into the scene, so the faces z = 1, x = 0 and y = 0 face the viewer and only
    # the corner (1, 1, 0) (index 3) is hidden, with its three edges
    phi = math.radians(30)
    corners, cube = unit_cube()
    scene = Scene(camera={"vrp": (0.5, 0.5, 0.5), "vpn": (0, 0, 1), "vup": (0, 1, 0), "projection": "oblique",
                          "alpha": math.pi / 4, "phi": phi, "near": 2.0, "far": -2.0})
    scene.add_mesh(cube)
    with StrokeDisplay() as display:
        display.window(-1.5, -1.5, 1.5, 1.5)
        display.draw(scene)
    c = np.asarray(corners) - 0.5
    uv = np.stack([c[:, 0] + c[:, 2] * math.cos(phi), c[:, 1] + c[:, 2] * math.sin(phi)], axis=1)
    device = geo.apply(display.pipeline.matrix, uv)
    edges = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1 and 3 not in (a, b)]
    assert_same_segments(display.display_list.segments(), [(device[a], device[b]) for a, b in edges], 1e-6)


def test_an_empty_scene_or_one_beyond_the_far_plane_draws_nothing():
    scene = Scene(camera=FRONT)
    for _ in range(2):
        with CanvasDisplay() as raster, StrokeDisplay() as vector:
            raster.draw(scene)
            vector.draw(scene)
        assert not pixels(raster).any() and len(vector.display_list) == 0
        scene.add_mesh(SQUARE + np.array([0, 0, -100.0]), SQUARE_FACES)  # far is −25


def test_a_backdrop_on_the_far_plane_is_drawn_though_its_clip_depth_rounds_just_beyond():
    camera = {**FRONT, "near": 1.0, "far": -1.05}
    backdrop = SQUARE * 2 + np.array([-5, -5, -1.05])  # at n = far, covering the window
    scene = Scene(camera=camera)
    scene.add_mesh(backdrop, SQUARE_FACES, material={"colour": (1, 1, 1), "ka": 1.0}, edges="outlines")
    scene.add_light("ambient", (1, 1, 1))
    clip = scene.camera.clip_coordinates(backdrop, (0, 0, 10, 10))
    assert (clip[:, 2] > clip[:, 3]).all()  # the precondition: z/w = 1 + 2e-16, beyond the far plane by rounding
    with CanvasDisplay() as raster, StrokeDisplay() as vector:
        raster.window(0, 0, 10, 10)
        vector.window(-10, -10, 20, 20)
        raster.draw(scene)
        vector.draw(scene)
    assert (pixels(raster) == 255).all()
    assert len(vector.display_list) > 0


def test_triangles_cut_by_the_window_keep_their_own_colours_beside_whole_ones():
    # a huge square (two faces, red below its diagonal y = x, blue above) is clipped by the view volume's sides;
    # a small green square in front of it passes whole: each pixel shows the face the textbook geometry puts there
    huge = np.array([[-100, -100, 0], [100, -100, 0], [100, 100, 0], [-100, 100, 0]], float)
    small = SQUARE * 0.2 + np.array([14, 1, 1.0])  # x 14..16, y 1..3, nearer than the huge square
    scene = Scene(camera=FRONT)
    scene.add_mesh(small, SQUARE_FACES, material={"colour": (0, 1, 0), "ka": 1.0})
    scene.add_mesh(huge, SQUARE_FACES, face_colours=[(1, 0, 0), (0, 0, 1)], material={"ka": 1.0})
    scene.add_light("ambient", (1, 1, 1))
    with CanvasDisplay(size=(40, 20)) as display:
        display.window(0, 0, 20, 10)  # 2 px a unit; pixel (i, j) centred on world ((i + ½)/2, 10 − (j + ½)/2)
        display.draw(scene)
    rgb = pixels(display)
    j, i = np.mgrid[0:20, 0:40]
    x, y = (i + 0.5) / 2, 10 - (j + 0.5) / 2
    green = (x > 14) & (x < 16) & (y > 1) & (y < 3)
    assert (rgb[green] == (0, 255, 0)).all()
    assert (rgb[~green & (y < x)] == (255, 0, 0)).all()
    assert (rgb[~green & (y > x)] == (0, 0, 255)).all()


@pytest.mark.parametrize("band_pixels, workers", [(64 * 3, 4), (64 * 7, 1), (1 << 30, 2)])
def test_drawing_in_bands_on_threads_gives_the_whole_frames_pixels(monkeypatch, band_pixels, workers):
    from pixelpen.display import render3d

    def draw():
        with CanvasDisplay(size=(64, 64)) as display:
            display.window(-1.2, -1.2, 1.2, 1.2)
            display.draw(sphere_scene())
        return pixels(display)

    whole = draw()  # the default bands
    monkeypatch.setattr(render3d, "BAND_PIXELS", band_pixels)  # bands of 3 or 7 rows, or one band
    monkeypatch.setattr(render3d, "MAX_WORKERS", workers)
    banded = draw()
    assert (whole.max(axis=2) > 0).mean() > 0.3  # the sphere is there
    assert np.array_equal(banded, whole)


def test_band_buffers_kept_from_draw_to_draw_start_cleared():
    from pixelpen.display import render3d

    def draw(scene, size=(20, 20)):
        with CanvasDisplay(size=size) as display:
            display.window(0, 0, 10, 10)
            display.draw(scene)
        return pixels(display)

    near, far = Scene(camera=FRONT), Scene(camera=FRONT)
    near.add_mesh(SQUARE + np.array([0, 0, 4.0]), SQUARE_FACES, material={"colour": (1, 0, 0), "ka": 1.0})
    far.add_mesh(SQUARE + np.array([0, 0, -20.0]), SQUARE_FACES, material={"colour": (0, 0, 1), "ka": 1.0})
    for scene in (near, far):
        scene.add_light("ambient", (1, 1, 1))
    first = draw(far)
    draw(near)  # leaves nearer depths in the kept buffers ...
    np.testing.assert_array_equal(draw(far), first)  # ... which must not hide the far square
    assert (first[1:-1, 1:-1] == (0, 0, 255)).all()
    draw(far, size=(30, 30))  # another size lets the kept buffers go
    assert len(render3d._BUFFERS._free) <= render3d._workers() + 1
    np.testing.assert_array_equal(draw(far), first)
    render3d.free_buffers()
    assert not render3d._BUFFERS._free
    np.testing.assert_array_equal(draw(far), first)  # fresh buffers after the release


@pytest.mark.parametrize("step", [1, 5, 1 << 14])
def test_front_faces_in_steps_match_the_determinant_of_each_face(monkeypatch, step):
    from pixelpen.display import render3d

    rng = np.random.default_rng(4)
    clip = rng.normal(size=(40, 4))
    faces = rng.integers(0, 40, (203, 3))
    monkeypatch.setattr(render3d, "STEP_FACES", step)
    front = render3d.front_faces(clip, faces)
    det = np.array([np.linalg.det(clip[face][:, (0, 1, 3)]) for face in faces])  # rows (x, y, w) of each corner
    clear = np.abs(det) > 1e-6
    assert clear.mean() > 0.9 and 0.3 < front.mean() < 0.7
    assert np.array_equal(front[clear], det[clear] > 0)

"""Tests of ``pixelpen plot``: placement on the paper, fitting, clipping, layers, pens, faults, resume, Ctrl-C, demo.

Every plot runs on a simulator reached by a named instance (``id=``), and the expected positions come from the
device profiles' documented paper origins (vpype's ``origin_location``) and the SVG/world conventions, not from
the command's own output.
"""

import argparse
import io
import json
import logging
import os
import threading
import time
import uuid

import numpy as np
import pytest

from pixelpen.cli import main
from pixelpen.commands import argtypes
from pixelpen.commands import plot as plotcmd
from pixelpen.devices.plotters.base import PlotProgress
from pixelpen.devices.plotters.job import plotter_for
from pixelpen.devices.plotters.layout import Layout, clip_to_device, page_to_world
from pixelpen.display.pictfile import save_picture
from pixelpen.display.picture import Picture, Polyline, Style
from pixelpen.sim.base import forget_simulator, named_simulator
from pixelpen.vector.displaylist import DisplayList

HP_UNIT = 0.02488  # hp7475a.toml unit_mm
HP_ORIGIN = (10.0, 206.0)  # hp7475a.toml [paper.a4] origin_mm: device origin 10 mm right of, 206 mm below the top left
GRBL_ORIGIN_Y = 210.0  # grbl.toml [paper.a4] origin_mm = [0, 210]: the origin is the sheet's lower-left corner


@pytest.fixture(autouse=True)
def no_user_config(monkeypatch):
    monkeypatch.setenv("PIXELPEN_CONFIG", "")


@pytest.fixture
def sim():
    """Unique simulator ids for one test, forgotten afterwards; ``sim(model, **opts)`` gives the URL."""
    made = []

    def url(model, **options):
        ident = f"t-{uuid.uuid4().hex[:10]}"
        made.append(ident)
        query = "&".join(f"{k}={v}" for k, v in {"speed": "fast", "id": ident, **options}.items())
        return f"sim:{model}?{query}", ident

    yield url
    for ident in made:
        forget_simulator(ident)


def svg(tmp_path, body, name="d.svg", size=(297, 210)):
    path = tmp_path / name
    w, h = size
    path.write_text(
        f'<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
        f'width="{w}mm" height="{h}mm" viewBox="0 0 {w} {h}">{body}</svg>'
    )
    return str(path)


def line(x0, y0, x1, y1, colour="black"):
    return f'<path d="M{x0},{y0} L{x1},{y1}" stroke="{colour}" fill="none"/>'


def run(*argv, stdin=""):
    """Run the CLI in-process with ``stdin`` as the operator's input."""
    import sys

    old = sys.stdin
    sys.stdin = io.StringIO(stdin)
    try:
        return main(["plot", *argv])
    finally:
        sys.stdin = old


def grbl_strokes(ident):
    return [pts for _, pts in named_simulator(ident).paper.strokes()]


# ---------------------------------------------------------------------------------------------------------
# placement


def test_svg_lands_true_size_where_the_profile_puts_the_sheet_on_grbl(tmp_path, sim):
    url, ident = sim("grbl")
    assert run(svg(tmp_path, line(10, 20, 50, 20)), "--to", url) == 0
    (stroke,) = grbl_strokes(ident)
    # GRBL machine y runs up from the sheet's lower-left corner: page y 20 mm down is 190 mm up
    np.testing.assert_allclose(stroke[[0, -1]], [[10, 190], [50, 190]], atol=0.002)


def test_svg_on_hp7475a_is_offset_by_the_paper_origin(tmp_path, sim):
    url, ident = sim("hp7475a")
    assert run(svg(tmp_path, line(30, 50, 130, 50)), "--to", url) == 0
    seg, _, _ = named_simulator(ident).segments()
    xs, ys = seg[:, 0::2].ravel(), seg[:, 1::2].ravel()
    # device mm = (x - 10, 206 - y) -> plotter units of 0.02488 mm
    assert xs.min() == pytest.approx((30 - HP_ORIGIN[0]) / HP_UNIT, abs=1)
    assert xs.max() == pytest.approx((130 - HP_ORIGIN[0]) / HP_UNIT, abs=1)
    assert np.allclose(ys, (HP_ORIGIN[1] - 50) / HP_UNIT, atol=1)


def test_svg_on_a_y_down_axidraw_keeps_page_coordinates(tmp_path, sim):
    url, ident = sim("axidraw")
    assert run(svg(tmp_path, line(10, 20, 50, 20)), "--to", url) == 0
    strokes = [pts for _, pts in named_simulator(ident).paper.strokes()]
    assert len(strokes) == 1
    # the AxiDraw origin is the home corner at the sheet's top left, y down the page (axidraw_v3.toml)
    np.testing.assert_allclose(strokes[0][[0, -1]], [[10, 20], [50, 20]], atol=0.02)


def test_fit_scales_the_drawing_into_the_paper_centred(tmp_path, sim):
    url, ident = sim("grbl")
    square = '<path d="M0,0 H10 V10 H0 Z" stroke="black" fill="none"/>'
    assert run(svg(tmp_path, square, size=(10, 10)), "--to", url, "--fit") == 0
    pts = np.vstack(grbl_strokes(ident))
    # a 10 mm square fills the 210 mm height of a 297 x 210 mm area, centred: x from 43.5 to 253.5
    np.testing.assert_allclose([pts[:, 0].min(), pts[:, 0].max()], [43.5, 253.5], atol=0.01)
    np.testing.assert_allclose([pts[:, 1].min(), pts[:, 1].max()], [0.0, 210.0], atol=0.01)


def test_picture_world_millimetres_are_device_millimetres(tmp_path, sim):
    pic = Picture()
    pic.add(Polyline([[10, 10], [60, 10]]))
    path = tmp_path / "p.json"
    save_picture(pic, path)
    url, ident = sim("grbl")
    assert run(str(path), "--to", url) == 0
    (stroke,) = grbl_strokes(ident)
    np.testing.assert_allclose(stroke[[0, -1]], [[10, 10], [60, 10]], atol=0.002)


def test_page_to_world_puts_the_profile_origin_at_the_device_origin():
    for url in ("sim:hp7475a", "sim:hp7475a?paper=a3", "sim:grbl", "sim:axidraw"):
        display = plotter_for(url)
        matrix = page_to_world(display)
        origin = display.paper.origin_mm
        device = display.pipeline.to_device(matrix[:2, :2] @ np.asarray(origin) + matrix[:2, 2])
        np.testing.assert_allclose(device, [0.0, 0.0], atol=1e-6)


def ends_on_sheet(ident):
    """The GRBL paper's strokes as sets of end points in sheet millimetres (x right, y down from the top left)."""
    return {frozenset((round(float(x), 2), round(float(GRBL_ORIGIN_Y - y), 2)) for x, y in pts[[0, -1]])
            for pts in grbl_strokes(ident)}


def test_layout_rotates_then_scales_about_the_centre_of_the_drawing(tmp_path, sim):
    path = svg(tmp_path, line(10, 20, 50, 20) + line(10, 40, 50, 40))  # bounds 40 x 20 mm, centre (30, 30)
    url, ident = sim("grbl")
    assert run(path, "--to", url, "--rotate", "90", "--no-optimize") == 0
    # a quarter turn clockwise on the sheet about (30, 30): (x, y) -> (30 - (y - 30), 30 + (x - 30))
    assert ends_on_sheet(ident) == {frozenset({(40.0, 10.0), (40.0, 50.0)}), frozenset({(20.0, 10.0), (20.0, 50.0)})}
    url, ident = sim("grbl")
    assert run(path, "--to", url, "--rotate", "90", "--scale", "0.5", "--no-optimize") == 0
    # then half the size about the same centre
    assert ends_on_sheet(ident) == {frozenset({(35.0, 20.0), (35.0, 40.0)}), frozenset({(25.0, 20.0), (25.0, 40.0)})}


def test_center_puts_the_drawing_in_the_middle_of_the_page_less_the_margins(tmp_path, sim):
    path = svg(tmp_path, line(10, 20, 50, 20) + line(10, 40, 50, 40))
    url, ident = sim("grbl")
    assert run(path, "--to", url, "--center", "--margin", "20", "--no-optimize") == 0
    # the GRBL area is the whole 297 x 210 page: the box is 20..277 x 20..190, centre (148.5, 105)
    assert ends_on_sheet(ident) == {frozenset({(128.5, 95.0), (168.5, 95.0)}),
                                    frozenset({(128.5, 115.0), (168.5, 115.0)})}
    url, ident = sim("grbl")
    assert run(path, "--to", url, "--center", "--page", "a5", "--no-optimize") == 0
    # a5 on a landscape bed is laid landscape, 210 x 148 mm from the sheet's top left: centre (105, 74)
    assert ends_on_sheet(ident) == {frozenset({(85.0, 64.0), (125.0, 64.0)}), frozenset({(85.0, 84.0), (125.0, 84.0)})}
    url, ident = sim("grbl")
    assert run(path, "--to", url, "--center", "--page", "200x100mm", "--portrait", "--no-optimize") == 0
    # turned portrait: 100 x 200 mm, centre (50, 100)
    assert ends_on_sheet(ident) == {frozenset({(30.0, 90.0), (70.0, 90.0)}), frozenset({(30.0, 110.0), (70.0, 110.0)})}


def test_fit_fills_the_box_within_the_margins(tmp_path, sim):
    url, ident = sim("grbl")
    square = '<path d="M0,0 H10 V10 H0 Z" stroke="black" fill="none"/>'
    assert run(svg(tmp_path, square, size=(10, 10)), "--to", url, "--fit", "--margin", "10") == 0
    pts = np.vstack(grbl_strokes(ident))
    # 190 mm high (210 less two margins), centred on the page: x 53.5..243.5, machine y 10..200
    np.testing.assert_allclose([pts[:, 0].min(), pts[:, 0].max()], [53.5, 243.5], atol=0.01)
    np.testing.assert_allclose([pts[:, 1].min(), pts[:, 1].max()], [10.0, 200.0], atol=0.01)


def test_on_hp7475a_the_box_stays_inside_the_hard_clip_limits(tmp_path, sim):
    url, ident = sim("hp7475a")
    square = '<path d="M0,0 H10 V10 H0 Z" stroke="black" fill="none"/>'
    assert run(svg(tmp_path, square, size=(10, 10)), "--to", url, "--fit") == 0
    seg, _, _ = named_simulator(ident).segments()
    # the A4 hard-clip area is 0..7721 plotter units high (192.1 mm): the fitted square is that tall, not 210 mm
    assert seg[:, 1::2].min() == pytest.approx(0, abs=1) and seg[:, 1::2].max() == pytest.approx(7721, abs=1)


def test_scaling_up_flattens_curves_finer(tmp_path, sim):
    url, ident = sim("grbl")
    circle = '<circle cx="148.5" cy="105" r="1" stroke="black" fill="none"/>'
    assert run(svg(tmp_path, circle), "--to", url, "--scale", "50", "--tolerance", "0.05") == 0
    (stroke,) = grbl_strokes(ident)
    centre = np.array([148.5, GRBL_ORIGIN_Y - 105.0])
    radius = np.hypot(*(stroke - centre).T)
    mids = (stroke[1:] + stroke[:-1]) / 2
    # a 50 mm circle within 0.05 mm on paper: vertices on it, chords' midpoints no further in than the tolerance
    np.testing.assert_allclose(radius, 50.0, atol=0.002)
    assert (50.0 - np.hypot(*(mids - centre).T)).max() <= 0.05 + 0.002


def test_picture_files_take_the_layout_too(tmp_path, sim):
    pic = Picture()
    pic.add(Polyline([[10, 10], [60, 10]]))  # world mm, y up: 10 mm above the sheet's lower edge
    path = tmp_path / "p.json"
    save_picture(pic, path)
    url, ident = sim("grbl")
    assert run(str(path), "--to", url, "--rotate", "-90") == 0
    (stroke,) = grbl_strokes(ident)
    # a quarter turn anticlockwise on the sheet about (35, 10) up: the line now runs up from y = -15 to 35 mm,
    # clipped at the machine's y = 0
    assert sorted(np.round(stroke[[0, -1], 1], 2).tolist()) == [0.0, 35.0]
    np.testing.assert_allclose(stroke[:, 0], 35.0, atol=0.002)


def test_layout_options_that_contradict_are_errors(tmp_path, sim, capsys):
    path = svg(tmp_path, line(10, 20, 50, 20))
    url, _ = sim("grbl")
    for argv, needle in [(["--margin", "5"], "--margin places the drawing only with --center or --fit"),
                         (["--fit", "--scale", "2"], "give --scale or --fit, not both"),
                         (["--center", "--margin", "150"], "leaves no room"),
                         (["--page", "a9"], "--page a9"),
                         (["--page", "infx3mm"], "--page infx3mm")]:
        assert run(path, "--to", url, *argv) == 2, argv
        assert needle in capsys.readouterr().err
    assert run(path, "--to", url, "--landscape", "--portrait") == 2
    assert "not allowed with argument" in capsys.readouterr().err


def test_dry_run_prints_the_placement_and_sends_nothing(tmp_path, sim, capsys):
    path = svg(tmp_path, line(-10, 20, 50, 20) + line(10, 40, 50, 40))
    url, ident = sim("hp7475a")
    sheet = tmp_path / "sheet.svg"
    assert run(path, "--to", url, "--dry-run", "--sheet", str(sheet)) == 0
    out = capsys.readouterr().out
    with pytest.raises(KeyError):
        named_simulator(ident)  # the plotter was never opened
    # hp7475a A4: the plotter reaches x 10 .. 10 + 11040 units, y 206 - 7721 units .. 206 mm from the top left
    assert f"x 10.0..{10 + 11040 * HP_UNIT:.1f}, y {206 - 7721 * HP_UNIT:.1f}..206.0 mm" in out
    assert "drawing: 60.0 x 20.0 mm at x -10.0..50.0, y 20.0..40.0 mm" in out
    assert "clipped: 20.0 mm of 100.0 mm of lines (20.0 %)" in out  # x -10..10 of the first line
    assert "plot: 2 strokes; 80 mm pen down" in out and "estimated 0:" in out
    text = sheet.read_text()
    for colour in plotcmd.SHEET_COLOURS:
        assert colour in text
    assert not os.path.exists(f"{path}.plot-state.json")
    assert run(path, "--to", url, "--sheet", path) == 2
    assert "would overwrite the drawing" in capsys.readouterr().err


def test_no_dedupe_keeps_a_line_drawn_twice_and_the_report_says_what_went(tmp_path, sim, capsys):
    path = svg(tmp_path, line(10, 20, 50, 20) * 2 + line(10, 40, 50, 40))
    url, ident = sim("grbl")
    assert run(path, "--to", url) == 0
    err = capsys.readouterr().err
    assert len(grbl_strokes(ident)) == 2 and "removed 1 duplicate stroke (40.0 mm)" in err
    url, ident = sim("grbl")
    assert run(path, "--to", url, "--no-dedupe") == 0
    err = capsys.readouterr().err
    ink = sum(float(np.hypot(*np.diff(s, axis=0).T).sum()) for s in grbl_strokes(ident))
    assert ink == pytest.approx(120.0, abs=0.01) and "duplicate removal off" in err  # 40 mm twice, and 40 mm


def test_a_second_pass_in_another_layer_is_plotted(tmp_path, sim, capsys):
    body = ('<g inkscape:groupmode="layer" inkscape:label="first">' + line(10, 20, 50, 20) + "</g>"
            '<g inkscape:groupmode="layer" inkscape:label="darken">' + line(10, 20, 50, 20) + "</g>")
    url, ident = sim("grbl")
    assert run(svg(tmp_path, body), "--to", url) == 0
    assert len(grbl_strokes(ident)) == 2 and "duplicate" not in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------------------
# clipping, layers, pens


def test_lines_beyond_the_limits_are_cut_with_a_warning_naming_how_much(tmp_path, sim, caplog):
    url, ident = sim("grbl")
    caplog.set_level(logging.WARNING, logger="pixelpen.commands.plot")
    assert run(svg(tmp_path, line(-10, 20, 50, 20)), "--to", url) == 0
    assert "10.0 mm of 60.0 mm" in caplog.text
    (stroke,) = grbl_strokes(ident)
    np.testing.assert_allclose(stroke[[0, -1]], [[0, 190], [50, 190]], atol=0.002)


def test_clip_to_device_splits_a_stroke_that_leaves_and_returns():
    dl = DisplayList.from_polylines([np.array([[1, 1], [5, 1], [5, 20], [8, 20], [8, 1], [9, 1]])])
    clipped, cut = clip_to_device(dl, (10, 10))
    assert len(clipped) == 2 and cut == pytest.approx(10 + 3 + 10)
    np.testing.assert_allclose(clipped.stroke(0), [[1, 1], [5, 1], [5, 10]])
    np.testing.assert_allclose(clipped.stroke(1), [[8, 10], [8, 1], [9, 1]])


def test_layers_select_what_is_plotted(tmp_path, sim, capsys):
    body = (
        '<g inkscape:groupmode="layer" inkscape:label="outline">' + line(10, 20, 50, 20) + "</g>"
        '<g inkscape:groupmode="layer" inkscape:label="detail">' + line(10, 40, 30, 40) + "</g>"
    )
    path = svg(tmp_path, body)
    url, ident = sim("grbl")
    assert run(path, "--to", url, "--layers", "detail") == 0
    (stroke,) = grbl_strokes(ident)
    np.testing.assert_allclose(stroke[[0, -1]], [[10, 170], [30, 170]], atol=0.002)
    url2, _ = sim("grbl")
    assert run(path, "--to", url2, "--layers", "shading") == 2
    err = capsys.readouterr().err
    assert "no layer 'shading'" in err and "outline" in err and "detail" in err


def test_single_pen_plotter_asks_for_each_pen(tmp_path, sim, capsys):
    url, ident = sim("grbl")
    path = svg(tmp_path, line(10, 20, 50, 20) + line(10, 30, 50, 30, "#ff0000"))
    assert run(path, "--to", url, stdin="\n\n") == 0
    err = capsys.readouterr().err
    assert "insert pen 1 (#000000) and press Enter" in err
    assert "insert pen 2 (#ff0000) and press Enter" in err
    assert len(grbl_strokes(ident)) == 2


def test_a_pen_change_with_no_operator_is_an_error(tmp_path, sim, capsys):
    url, ident = sim("grbl")
    path = svg(tmp_path, line(10, 20, 50, 20) + line(10, 30, 50, 30, "#ff0000"))
    assert run(path, "--to", url, stdin="\n") == 2
    assert "input is closed" in capsys.readouterr().err
    assert len(grbl_strokes(ident)) == 1
    assert not named_simulator(ident).paper.pen_is_down


def test_carousel_pens_are_chosen_by_colour(tmp_path, sim):
    url, ident = sim("hp7475a")
    # pen 2 of the hp7475a profile is red (#d62728), pen 4 blue (#1f77b4)
    path = svg(tmp_path, line(30, 50, 80, 50, "#ff0000") + line(30, 70, 80, 70, "#0000ff"))
    assert run(path, "--to", url) == 0
    seg, pens, _ = named_simulator(ident).segments()
    y_mm = HP_ORIGIN[1] - seg[:, 1] * HP_UNIT
    assert set(pens[np.isclose(y_mm, 50, atol=0.1)].tolist()) == {2}
    assert set(pens[np.isclose(y_mm, 70, atol=0.1)].tolist()) == {4}


# ---------------------------------------------------------------------------------------------------------
# errors


def test_errors_are_one_line_and_exit_2(tmp_path, sim, capsys):
    good = svg(tmp_path, line(10, 20, 50, 20))
    url, _ = sim("grbl")
    cases = [
        ([str(tmp_path / "missing.svg"), "--to", url], "missing.svg"),
        ([good, "--to", f"png:{tmp_path / 'x.png'}"], "not a pen plotter"),
        ([good, "--to", "nosuch:x"], "known schemes"),
        ([svg(tmp_path, "<g>", name="bad.svg"), "--to", url], "bad.svg"),
        ([svg(tmp_path, "", name="empty.svg"), "--to", url], "nothing to plot"),
        ([str(tmp_path / "d.txt"), "--to", url], "expected an SVG"),
        ([good, "--to", url, "--resume", "--state", str(tmp_path / "none.json")], "nothing to resume"),
        ([good, "--to", f"{url}&state=a.json", "--state", "b.json"], "the state file is named twice"),
        ([good, "--to", url, "--dry-run", "--sheet", str(tmp_path / "sheet.txt")], "must end in .svg"),
    ]
    for argv, needle in cases:
        assert run(*argv) == 2, argv
        err = capsys.readouterr().err
        errors = [text for text in err.splitlines() if not text.startswith("warning: ")]
        assert needle in err and "Traceback" not in err and len(errors) == 1, err


# ---------------------------------------------------------------------------------------------------------
# faults, retries, resume, Ctrl-C


def ladder(tmp_path, n=12, pitch=10.0):
    """n vertical 40 mm rungs at x = 10, 10 + pitch, ... mm."""
    return svg(tmp_path, "".join(line(10 + pitch * i, 20, 10 + pitch * i, 60) for i in range(n)), name="ladder.svg")


def ink_per_rung(seg, n, pitch):
    """Pen-down length (mm) on each of the n ladder rungs, from HP-GL segments; and the length drawn elsewhere."""
    x_mm = seg[:, 0] * HP_UNIT + HP_ORIGIN[0]
    y_mm = HP_ORIGIN[1] - seg[:, 1::2] * HP_UNIT
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]) * HP_UNIT
    rung = np.rint((x_mm - 10) / pitch).astype(int)
    on = (np.isclose(seg[:, 0], seg[:, 2]) & np.isclose(x_mm, 10 + pitch * rung, atol=0.05) & (rung >= 0)
          & (rung < n) & (y_mm >= 20 - 0.05).all(axis=1) & (y_mm <= 60 + 0.05).all(axis=1))
    return np.bincount(rung[on], weights=length[on], minlength=n), float(length[~on].sum())


def test_a_fault_beyond_the_retries_exits_3_and_resume_draws_every_line_exactly_once(tmp_path, sim, capsys):
    path = ladder(tmp_path, 40, pitch=5)
    state = tmp_path / "job.json"
    broken, ident = sim("hp7475a", drop_after=900, buffer=256)
    assert run(path, "--to", broken, "--retries", "0", "--no-optimize", "--state", str(state)) == 3
    err = capsys.readouterr().err
    assert f"--state {state} --resume" in err
    saved = json.loads(state.read_text())
    assert saved["strokes"] == 40 and saved["confirmed"] < 40
    # the same plotter, reached again by its id over a healthy link, is asked where it stopped
    healthy = f"sim:hp7475a?speed=fast&id={ident}&buffer=256"
    assert run(path, "--to", healthy, "--no-optimize", "--state", str(state), "--resume") == 0
    seg, _, _ = named_simulator(ident).segments()
    rungs, stray = ink_per_rung(seg, 40, 5)
    # 40 rungs of 40 mm: each drawn once (not twice, not missing), nothing drawn anywhere else
    np.testing.assert_allclose(rungs, 40.0, atol=0.05)
    assert stray < 0.05
    assert not state.exists() and not os.path.exists(f"{state}.drawing.npz")


def test_the_printed_resume_command_repeats_the_layout_and_finishes_the_plot(tmp_path, sim, capsys, monkeypatch):
    import shlex

    monkeypatch.chdir(tmp_path)
    path = ladder(tmp_path, 40, pitch=4)
    broken, ident = sim("hp7475a", drop_after=900, buffer=256)
    layout = ["--rotate", "90", "--center", "--margin", "12.5", "--page", "a4", "--tolerance", "0.02"]
    assert run(path, "--to", broken, "--retries", "0", *layout) == 3
    (command,) = [t.partition("resume with: ")[2] for t in capsys.readouterr().err.splitlines() if "resume with:" in t]
    argv = shlex.split(command)
    assert argv[:2] == ["pixelpen", "plot"] and argv[-1] == "--resume"
    assert {"--rotate", "--center", "--margin", "--page", "--tolerance"} <= set(argv)
    # the command as printed, on the same plotter reached over a healthy link, finishes the job
    argv[argv.index("--to") + 1] = f"sim:hp7475a?speed=fast&id={ident}&buffer=256"
    assert main(argv[1:]) == 0
    assert not os.path.exists(f"{path}.plot-state.json")


def test_resume_on_a_plotter_that_cannot_say_where_it_stopped_needs_confirmation(tmp_path, sim, capsys):
    path = ladder(tmp_path)
    state = tmp_path / "job.json"
    broken, _ = sim("grbl", drop_after=700)
    assert run(path, "--to", broken, "--retries", "0", "--no-optimize", "--state", str(state)) == 3
    done = json.loads(state.read_text())["confirmed"]
    assert 0 < done < 12
    url, ident = sim("grbl")  # another (re-homed) plotter: it knows nothing of the job
    capsys.readouterr()
    assert run(path, "--to", url, "--no-optimize", "--state", str(state), "--resume") == 3
    err = capsys.readouterr().err
    assert "--resume --confirm-position" in err and grbl_strokes(ident) == []
    assert run(path, "--to", url, "--no-optimize", "--state", str(state), "--resume", "--confirm-position") == 0
    xs = [pts[0, 0] for pts in grbl_strokes(ident)]
    # confirmed: the plot continues from the first stroke the first plotter did not confirm
    np.testing.assert_allclose(xs, [10 + 10 * i for i in range(done, 12)], atol=0.002)
    assert not state.exists()


def test_resume_refuses_a_missing_state_file_naming_it(tmp_path, sim, capsys):
    path = ladder(tmp_path)
    state = tmp_path / "job.json"
    broken, _ = sim("grbl", drop_after=700)
    assert run(path, "--to", broken, "--retries", "0", "--state", str(state)) == 3
    url, ident = sim("grbl")
    capsys.readouterr()
    typo = tmp_path / "jbo.json"
    assert run(path, "--to", url, "--state", str(typo), "--resume") == 2
    err = capsys.readouterr().err
    assert f"no plot state file {typo}" in err and len(err.strip().splitlines()) == 1
    state.unlink()  # the drawing beside it is still there: still nothing to resume
    assert run(path, "--to", url, "--state", str(state), "--resume") == 2
    assert f"no plot state file {state}" in capsys.readouterr().err
    assert run(path, "--to", url, "--resume") == 2  # the default state file FILE.plot-state.json
    assert f"no plot state file {path}.plot-state.json" in capsys.readouterr().err
    with pytest.raises(KeyError):  # the plotter was never even opened
        named_simulator(ident)
    assert run(path, "--to", url, "--confirm-position") == 2
    assert "--confirm-position goes with --resume" in capsys.readouterr().err


def test_resume_refuses_another_drawing_in_one_clean_line(tmp_path, sim, capsys):
    state = tmp_path / "job.json"
    broken, _ = sim("grbl", drop_after=700)
    assert run(ladder(tmp_path), "--to", broken, "--retries", "0", "--state", str(state)) == 3
    other = svg(tmp_path, line(10, 20, 50, 20), name="other.svg")
    url, ident = sim("grbl")
    capsys.readouterr()
    assert run(other, "--to", url, "--state", str(state), "--resume") == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert err == (f"pixelpen plot: error: {state}: the plot state belongs to another drawing (another file, layers, "
                   "layout or plotter); refusing to resume")
    assert run(ladder(tmp_path), "--to", url, "--state", str(state), "--resume", "--rotate", "1") == 2
    assert "another drawing" in capsys.readouterr().err  # the same file laid out otherwise is another drawing
    with pytest.raises(KeyError):  # refused before the plotter was opened
        named_simulator(ident)


def test_fault_lines_name_the_fault_once(tmp_path, sim, capsys):
    path = ladder(tmp_path, 40, pitch=5)
    broken, _ = sim("hp7475a", drop_after=250, buffer=256)
    assert run(path, "--to", broken, "--retries", "2", "--no-optimize", "--state", str(tmp_path / "s.json")) == 3
    err = capsys.readouterr().err
    ours = "\n".join(text for text in err.splitlines() if not text.startswith("warning: "))
    # the port URL is in the fault's own words once; the resume line repeats the user's URL, nothing else does
    assert ours.count("sim://hp7475a?") == 1 and ours.count(broken) == 1, err
    assert "retry 1/2: reconnecting" in err and "resume with: pixelpen plot" in err


def test_retries_reconnect_and_finish_the_plot(tmp_path, sim, capsys):
    path = ladder(tmp_path, 30, pitch=5)
    # every reconnection reaches the same plotter (id=) over a link that drops again after 700 bytes,
    # so the job takes several connections; the plotter says where it stopped each time
    broken, ident = sim("hp7475a", drop_after=700, buffer=256)
    assert run(path, "--to", broken, "--retries", "8", "--no-optimize", "--state", str(tmp_path / "s.json")) == 0
    err = capsys.readouterr().err
    assert "retry 1/8" in err and "plotted" in err and "30 strokes" in err
    seg, _, _ = named_simulator(ident).segments()
    rungs, stray = ink_per_rung(seg, 30, 5)
    np.testing.assert_allclose(rungs, 40.0, atol=0.05)  # every stroke once, on the one sheet
    assert stray < 0.05


def test_ctrl_c_leaves_the_pen_up_and_the_device_idle(tmp_path, sim, monkeypatch):
    calls = []

    def interrupt(self, progress):
        calls.append(progress)
        raise KeyboardInterrupt

    monkeypatch.setattr(plotcmd.ProgressBar, "__call__", interrupt)
    state = tmp_path / "s.json"
    url, ident = sim("grbl")
    assert main(["plot", ladder(tmp_path), "--to", url, "--state", str(state)]) == 130
    device = named_simulator(ident)
    assert calls and device.state == "Idle"
    assert not device.paper.pen_is_down and device.next_event_time() is None
    assert len(device.paper.strokes()) < 12 and state.exists()


def test_ctrl_c_on_hpgl_stores_the_pen_and_empties_the_buffer(tmp_path, sim, monkeypatch):
    monkeypatch.setattr(plotcmd.ProgressBar, "__call__", lambda self, p: (_ for _ in ()).throw(KeyboardInterrupt))
    url, ident = sim("hp7475a", sync_strokes=1)
    assert main(["plot", ladder(tmp_path), "--to", url]) == 130
    device = named_simulator(ident)
    assert device.selected_pen == 0 and device.buffered_bytes == 0 and device.next_event_time() is None


def test_ctrl_c_on_an_axidraw_lifts_the_pen_and_stops_moving(tmp_path, sim, monkeypatch, capsys):
    monkeypatch.setattr(plotcmd.ProgressBar, "__call__", lambda self, p: (_ for _ in ()).throw(KeyboardInterrupt))
    url, ident = sim("axidraw")
    assert main(["plot", ladder(tmp_path, 4), "--to", url]) == 130
    device = named_simulator(ident)
    assert device.pen_up and device.next_event_time() is None
    assert "continue with: pixelpen plot" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------------------
# progress, keys


def progress(done, total, mm, total_mm, eta=10.0):
    return PlotProgress(done, total, mm, total_mm, 5.0, eta)


def test_progress_bar_text():
    bar = plotcmd.ProgressBar(io.StringIO(), width=10)
    text = bar.format(progress(3, 10, 60.0, 200.0, eta=83.0))
    assert text.startswith("[###.......]") and " 30.0%" in text
    assert "60/200 mm" in text and "strokes 3/10" in text and "ETA 1:23" in text and "elapsed 0:05" in text


class _Tty(io.StringIO):
    def isatty(self):
        return True


def test_progress_bar_throttles_on_a_terminal_and_steps_in_a_log():
    t = [0.0]
    tty = _Tty()
    bar = plotcmd.ProgressBar(tty, interval=0.5, now=lambda: t[0])
    for k in range(1, 10):
        bar(progress(k, 10, k, 10))
        t[0] += 0.2
    bar(progress(10, 10, 10, 10))
    # redrawn at t = 0, 0.6, 1.2 (every 0.5 s at most) and at the end
    assert tty.getvalue().count("\r") == 4
    log = io.StringIO()
    bar = plotcmd.ProgressBar(log)
    for k in range(101):
        bar(progress(k, 100, k, 100))
    assert len(log.getvalue().splitlines()) == 11  # 0 %, 10 %, ..., 100 %


def test_a_warning_during_the_plot_starts_on_its_own_line():
    tty = _Tty()
    bar = plotcmd.ProgressBar(tty, interval=0.0)
    logger = logging.getLogger("pixelpen.test_progress")
    handler = logging.StreamHandler(tty)
    logger.addHandler(handler)
    try:
        with bar.log_lines(logger):
            bar(progress(3, 10, 3, 10))
            logger.warning("reconnect 1/3 failed")
        bar(progress(4, 10, 4, 10))
        logger.warning("after the plot")  # outside: no filter left behind
    finally:
        logger.removeHandler(handler)
    lines = tty.getvalue().split("\n")
    assert lines[0].startswith("\r[") and lines[1] == "reconnect 1/3 failed"
    assert lines[2].startswith("\r[") and lines[2].endswith("after the plot")


def _until(cond, limit=5.0):
    end = time.monotonic() + limit
    while not cond():
        assert time.monotonic() < end, "condition not reached"
        time.sleep(0.01)


def test_keys_toggle_the_pause_and_answer_prompts():
    r, w = os.pipe()
    toggles = []
    keys = plotcmd.KeyControl(r, toggles.append)
    try:
        os.write(w, b"p")
        _until(lambda: keys.pause_requested())
        os.write(w, b" ")
        _until(lambda: not keys.pause_requested())
        assert toggles == [True, False]
        stop = threading.Event()

        def press_enter():  # keeps pressing, so that one Enter surely comes after wait_enter began
            while not stop.is_set():
                os.write(w, b"x\n")
                stop.wait(0.02)

        presser = threading.Thread(target=press_enter)
        presser.start()
        try:
            assert keys.wait_enter() is True
        finally:
            stop.set()
            presser.join()
        os.close(w)
        w = None
        assert keys.wait_enter() is False
    finally:
        keys.close()
        for fd in (r, w):
            if fd is not None:
                os.close(fd)


def test_a_simulated_plotter_saves_its_paper_with_out(tmp_path, sim):
    from PIL import Image

    paper = tmp_path / "paper.png"
    url, _ = sim("hp7475a", out=str(paper))
    assert run(svg(tmp_path, line(30, 50, 130, 50)), "--to", url) == 0
    img = np.asarray(Image.open(paper).convert("L"))
    ink_rows = np.flatnonzero((img < 128).any(axis=1))
    # one horizontal 100 mm line: dark pixels in a thin band, across about 100/297 of the sheet's width
    assert len(ink_rows) and np.ptp(ink_rows) < img.shape[0] * 0.02
    dark_cols = np.flatnonzero((img < 128).any(axis=0))
    assert np.ptp(dark_cols) / img.shape[1] == pytest.approx(100 / 297, abs=0.02)


class ScriptedKeys:
    """The operator presses p before the third stroke and again a few polls later (a KeyControl stand-in)."""

    def __init__(self, on_toggle, hold_polls=5):
        self.on_toggle = on_toggle
        self.polls = 0
        self.hold = hold_polls

    def pause_requested(self):
        self.polls += 1
        if self.polls in (3, 3 + self.hold):
            self.on_toggle(self.polls == 3)
        return 3 <= self.polls < 3 + self.hold

    def wait_enter(self):
        return True

    def close(self):
        pass


def test_the_pause_is_confirmed_only_once_the_plotter_holds_with_the_pen_up(tmp_path, sim, monkeypatch, capsys):
    url, ident = sim("grbl")
    seen = []
    device_said = plotcmd.PauseMessages.device

    def device(self, paused):  # what the simulated plotter is doing when the paused line is printed
        sim_device = named_simulator(ident)
        seen.append((paused, sim_device.paper.pen_is_down, sim_device.state, len(sim_device.paper.strokes())))
        device_said(self, paused)

    monkeypatch.setattr(plotcmd.PauseMessages, "device", device)
    monkeypatch.setattr(plotcmd, "_stdin_keys", lambda on_toggle: ScriptedKeys(on_toggle))
    assert run(ladder(tmp_path, 5), "--to", url, "--no-optimize") == 0
    err = capsys.readouterr().err.splitlines()
    asked = err.index("pause requested - waiting for the pen to lift")
    held = err.index("paused (pen up) - press p or space to continue")
    assert asked < held < err.index("continuing") < err.index("resumed")
    # when it said "paused", the plotter had finished the first two strokes, stood idle, pen up
    assert seen[0] == (True, False, "Idle", 2) and seen[1][0] is False
    assert len(grbl_strokes(ident)) == 5


def test_a_pause_at_the_plotter_is_shown_as_the_plotters_own(tmp_path, sim, monkeypatch, capsys):
    url, ident = sim("hp7475a", pause_after=400, buffer=256)
    device_said = plotcmd.PauseMessages.device

    def device(self, paused):  # the operator releases VIEW on the plotter once pixelpen says it holds
        device_said(self, paused)
        if paused:
            named_simulator(ident).press_view()

    monkeypatch.setattr(plotcmd.PauseMessages, "device", device)
    assert run(ladder(tmp_path, 30, pitch=5), "--to", url, "--no-optimize") == 0
    err = capsys.readouterr().err
    assert "paused at the plotter (pen up" in err and "press p or space" not in err
    seg, _, _ = named_simulator(ident).segments()
    rungs, stray = ink_per_rung(seg, 30, 5)
    np.testing.assert_allclose(rungs, 40.0, atol=0.05)  # and the plot went on, every rung once
    assert stray < 0.05


# ---------------------------------------------------------------------------------------------------------
# demo


def test_plot_demo_saves_each_paper_and_skips_unknown_models(tmp_path, monkeypatch, caplog):
    def small_scene(display):
        display.draw(Polyline([[10, 10], [80, 60]], Style(width=0.5)))

    monkeypatch.setattr("pixelpen.scene.draw_reference", small_scene)
    caplog.set_level(logging.WARNING, logger="pixelpen.commands.plot")
    paths = plotcmd.plot_demo(tmp_path, models=("hp7475a", "grbl", "nosuch"))
    assert paths == [tmp_path / "paper-hp7475a.png", tmp_path / "paper-grbl.png"]
    from PIL import Image

    for path in paths:
        img = np.asarray(Image.open(path).convert("L"))
        assert (img < 128).any() and (img == 255).mean() > 0.9
    assert "skipping nosuch" in caplog.text


# ---------------------------------------------------------------------------------------------------------
# fuzzing: layout values from the command line or the configuration file give a layout or a PixelpenError

LAYOUT_SEEDS = [b"a4 90 1.5 10", b"210x297mm -45 0.5 0", b"11x8.5in 180 2 5", b"letter 0 1 0", b"30x20cm 1e-3 3 1"]


def layout_campaign(cases, seed):
    from tests.fuzzing import campaign

    display = plotter_for("sim:hp7475a")
    points = np.array([[10.0, 20.0], [50.0, 20.0], [30.0, 60.0]])

    def target(data):
        page, rotate, scale, margin = [*data.decode("utf-8", "replace").split(" "), "", "", "", ""][:4]
        numbers = []
        for text, convert in ((rotate, argtypes.finite), (scale, argtypes.positive), (margin, argtypes.non_negative)):
            try:
                numbers.append(convert(text))
            except argparse.ArgumentTypeError:  # argparse turns it into a usage error
                return
        layout = Layout(rotate_deg=numbers[0], scale=numbers[1], center=True, margin_mm=numbers[2],
                        page=page or None)
        w, h = layout.page_size(display)
        assert np.isfinite([w, h]).all() and w > 0 and h > 0
        matrix, factor = layout.matrix(points, (numbers[2], numbers[2], w - numbers[2], h - numbers[2]))
        assert np.isfinite(matrix).all() and factor > 0

    return campaign("plot layout options", target, LAYOUT_SEEDS, cases, seed=seed, seconds_per_case=2.0)


def test_layout_options_fuzz_quick():
    from tests.fuzzing import QUICK_CASES

    result = layout_campaign(QUICK_CASES, seed=3)
    result.check()
    assert result.accepted >= len(LAYOUT_SEEDS)


@pytest.mark.slow
def test_layout_options_fuzz_slow():
    from tests.fuzzing import SLOW_CASES

    result = layout_campaign(SLOW_CASES, seed=4)
    print(result.summary())
    result.check()

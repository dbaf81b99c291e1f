"""Tests of the vector commands (optimize, stats, preview), run in-process through the command line."""

import argparse
import json
import math
import sys
import types

import numpy as np
import pytest
from PIL import Image

from pixelpen.cli import main
from pixelpen.commands.vector import add_optimize, add_preview, add_stats
from pixelpen.vector.svgimport import read_svg

SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="50mm" viewBox="0 0 100 50">
<path d="M 50 10 L 50 20" stroke="black" fill="none"/>
<path d="M 0 0 L 30 40" stroke="black" fill="none"/>
<path d="M 60 10 L 90 10" stroke="red" fill="none"/>
</svg>"""


def run(argv):
    return main(argv)


@pytest.fixture
def drawing(tmp_path):
    path = tmp_path / "in.svg"
    path.write_text(SVG)
    return path


def test_register_adds_the_three_commands():
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="command")
    for add in (add_optimize, add_stats, add_preview):
        assert isinstance(add(sub), argparse.ArgumentParser)
    assert set(sub.choices) == {"optimize", "stats", "preview"}


def test_stats_table_and_json(drawing, capsys):
    assert run(["stats", str(drawing), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    t = data["total"]
    assert t["strokes"] == 3 and t["pen_changes"] == 1
    assert t["pen_down_mm"] == pytest.approx(10 + 50 + 30, rel=1e-5)
    # home -> (50,10) -> from (50,20) to (0,0) -> from (30,40) to (60,10) -> back home from (90,10)
    hops = math.hypot(50, 10) + math.hypot(50, 20) + math.hypot(30, 30) + math.hypot(90, 10)
    assert t["pen_up_mm"] == pytest.approx(hops, rel=1e-5)
    assert [layer["name"] for layer in data["layers"]] == ["#000000", "#ff0000"]
    assert run(["stats", str(drawing)]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].split()[0] == "layer" and "total" in out


def test_stats_with_a_device_profile(drawing, capsys):
    pytest.importorskip("pixelpen.profiles.model")
    assert run(["stats", str(drawing), "--device", "axidraw_v3", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["total"]["time"]["total_s"] > 0
    assert run(["stats", str(drawing), "--device", "no-such-device"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pixelpen stats: error:") and "Traceback" not in err


def test_preview_writes_png(drawing, tmp_path, capsys):
    out = tmp_path / "p.png"
    assert run(["preview", str(drawing), "-o", str(out), "--size", "300"]) == 0
    img = Image.open(out)
    assert max(img.size) == 300
    assert (np.asarray(img.convert("RGB"))[..., 0] > 200).any()
    assert "wrote" in capsys.readouterr().err


def test_preview_without_travel_to_svg(drawing, tmp_path):
    out = tmp_path / "p.svg"
    assert run(["preview", str(drawing), "-o", str(out), "--no-travel"]) == 0
    assert "stroke-dasharray" not in out.read_text()


def test_optimize_passes_options_and_reports_before_after(drawing, tmp_path, capsys, monkeypatch):
    calls = {}

    def fake_optimize(dl, **kw):
        calls.update(kw)
        return dl.reordered([1, 0, 2], [True, False, False])

    fake = types.ModuleType("pixelpen.vector.optimize")
    fake.optimize = fake_optimize
    fake.OptimizeReport = lambda: types.SimpleNamespace(lines=lambda: ["report line"])
    monkeypatch.setitem(sys.modules, "pixelpen.vector.optimize", fake)
    out = tmp_path / "out.svg"
    argv = ["optimize", str(drawing), "-o", str(out), "--no-reverse", "--merge", "0.1", "--simplify", "0.02",
            "--time-budget", "2.5", "--across-layers"]
    assert run(argv) == 0
    report = calls.pop("report")
    assert calls == {"merge": 0.1, "reverse": False, "simplify": 0.02, "time_budget": 2.5, "across_layers": True,
                     "profile": None, "dedupe": True}
    err = capsys.readouterr().err
    assert "before" in err and "after" in err and err.count("\ntotal ") == 2
    assert err.rstrip().endswith("report line") and report.lines() == ["report line"]
    assert run(["optimize", str(drawing), "-o", str(out), "--no-dedupe"]) == 0
    assert calls["dedupe"] is False and calls["time_budget"] is None  # None: the adaptive budget
    back = read_svg(out)
    assert len(back) == 3
    np.testing.assert_allclose(back.stroke(0), [[30, 40], [0, 0]], rtol=1e-5, atol=1e-9)


def test_optimize_end_to_end_with_the_real_optimizer(drawing, tmp_path, capsys):
    pytest.importorskip("pixelpen.vector.optimize")
    out = tmp_path / "out.svg"
    assert run(["optimize", str(drawing), "-o", str(out), "--time-budget", "0.2"]) == 0
    before, after = read_svg(drawing), read_svg(out)
    assert after.pen_down_length() == pytest.approx(before.pen_down_length(), rel=1e-5)
    assert after.pen_up_length() <= before.pen_up_length() + 1e-6


TWICE = """<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape"
 width="100mm" height="50mm" viewBox="0 0 100 50">
<g inkscape:groupmode="layer" inkscape:label="black" id="a">
<path d="M 10 10 L 40 10" stroke="black" fill="none"/>
<path d="M 40 10 L 10 10" stroke="black" fill="none"/>
<path d="M 10 30 L 20 30" stroke="black" fill="none"/>
</g>
<g inkscape:groupmode="layer" inkscape:label="red" id="b">
<path d="M 10 10 L 40 10" stroke="red" fill="none"/>
</g>
</svg>"""


def segment_set(dl):
    """Pen-down segments rounded to 1e-6 mm, each written from its smaller end, as a sorted multiset."""
    out = []
    for x0, y0, x1, y1 in np.round(dl.segments() * dl.unit_mm, 6).tolist():
        out.append((x0, y0, x1, y1) if (x0, y0) <= (x1, y1) else (x1, y1, x0, y0))
    return sorted(out)


def test_optimize_dedupes_within_a_layer_only_and_says_so(tmp_path, capsys):
    src, out = tmp_path / "twice.svg", tmp_path / "out.svg"
    src.write_text(TWICE)
    assert run(["optimize", str(src), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    # the 30 mm line drawn twice in layer "black" goes once; its pass in layer "red" stays
    assert segment_set(read_svg(out)) == sorted([(10, 10, 40, 10), (10, 10, 40, 10), (10, 30, 20, 30)])
    line = [ln for ln in err.splitlines() if ln.startswith("removed")]
    assert len(line) == 1 and "1 duplicate stroke (30.0 mm)" in line[0] and "'black'" in line[0]
    assert run(["optimize", str(src), "-o", str(out), "--no-dedupe"]) == 0
    assert segment_set(read_svg(out)) == segment_set(read_svg(src))
    assert "duplicate removal off" in capsys.readouterr().err


def test_preview_on_a_device_shows_what_is_cut(tmp_path, capsys):
    # a line from the sheet's left edge inward: the part left of the plotter's limits is cut
    src, out = tmp_path / "edge.svg", tmp_path / "sheet.svg"
    src.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="297mm" height="210mm" viewBox="0 0 297 210">'
                   '<path d="M 0 100 L 50 100" stroke="black" fill="none"/></svg>')
    assert run(["preview", str(src), "-o", str(out), "--device", "hp7475a", "--no-travel"]) == 0
    err = capsys.readouterr().err
    first = err.splitlines()[0]
    x0 = float(first.split("reaches x ")[1].split("..")[0])
    assert first.startswith("sheet: 297 x 210 mm (paper a4 of hp7475a") and 0 < x0 < 50
    assert f"cut: {x0:.1f} mm of 50.0 mm" in err
    import xml.etree.ElementTree as ET

    paths = ET.parse(out).getroot().findall(".//{http://www.w3.org/2000/svg}path")
    cut = [p for p in paths if p.get("class") == "cut"]
    frames = [p for p in paths if p.get("class") == "frame"]
    drawn = [p for p in paths if p.get("class") is None]
    assert len(cut) == 1 and len(frames) == 2 and len(drawn) == 1
    pts = lambda p: np.array([[float(v) for v in xy.split(",")] for xy in p.get("d")[1:].split()])
    np.testing.assert_allclose(pts(cut[0]), [[0, 100], [x0, 100]], atol=0.05)
    np.testing.assert_allclose(sorted(pts(drawn[0]).tolist()), [[x0, 100], [50, 100]], atol=0.05)
    np.testing.assert_allclose(pts(frames[0])[[0, 2]], [[0, 0], [297, 210]])
    assert run(["preview", str(src), "-o", str(out), "--device", "axidraw_v3"]) == 0
    assert "cut: nothing" in capsys.readouterr().err
    assert run(["preview", str(src), "-o", str(out), "--paper", "a4"]) == 2
    assert "--paper needs --device" in capsys.readouterr().err


@pytest.mark.parametrize("argv_tail, message", [
    (["stats", "{missing}"], "cannot read SVG file"),
    (["stats", "{bad}"], "not well-formed XML"),
    (["preview", "{good}", "-o", "{tmp}/p.unknownext"], "extension"),
    (["preview", "{good}", "-o", "{tmp}/no/such/dir/p.png"], "No such file"),
])
def test_errors_give_status_2_and_one_line(tmp_path, drawing, capsys, argv_tail, message):
    bad = tmp_path / "bad.svg"
    bad.write_text("this is not svg")
    names = {"missing": str(tmp_path / "missing.svg"), "bad": str(bad), "good": str(drawing), "tmp": str(tmp_path)}
    argv = [a.format(**names) for a in argv_tail]
    assert run(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pixelpen {argv[0]}: error:") and message in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_bad_option_values_are_rejected_by_argparse(drawing, capsys):
    assert run(["optimize", str(drawing), "-o", "x.svg", "--merge", "-1"]) == 2
    assert "expected a finite number > 0" in capsys.readouterr().err

"""Tests of the vector commands (optimize, stats, preview) run in-process through their argparse functions."""

import argparse
import json
import math
import sys
import types

import numpy as np
import pytest
from PIL import Image

from pixelpen.commands.vector import add_optimize, add_preview, add_stats, register
from pixelpen.vector.svgimport import read_svg

SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="50mm" viewBox="0 0 100 50">
<path d="M 50 10 L 50 20" stroke="black" fill="none"/>
<path d="M 0 0 L 30 40" stroke="black" fill="none"/>
<path d="M 60 10 L 90 10" stroke="red" fill="none"/>
</svg>"""


def run(argv):
    parser = argparse.ArgumentParser(prog="pixelpen")
    sub = parser.add_subparsers(dest="command", required=True)
    register(sub)
    args = parser.parse_args(argv)
    return args.func(args)


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
    pytest.importorskip("pixelpen.vector.profiles")
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
    monkeypatch.setitem(sys.modules, "pixelpen.vector.optimize", fake)
    out = tmp_path / "out.svg"
    argv = ["optimize", str(drawing), "-o", str(out), "--no-reverse", "--merge", "0.1", "--simplify", "0.02",
            "--time-budget", "2.5", "--across-layers"]
    assert run(argv) == 0
    assert calls == {"merge": 0.1, "reverse": False, "simplify": 0.02, "time_budget": 2.5, "across_layers": True,
                     "profile": None}
    err = capsys.readouterr().err
    assert "before" in err and "after" in err and err.count("total") == 2
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
    with pytest.raises(SystemExit) as info:
        run(["optimize", str(drawing), "-o", "x.svg", "--merge", "-1"])
    assert info.value.code == 2 and "expected a number > 0" in capsys.readouterr().err

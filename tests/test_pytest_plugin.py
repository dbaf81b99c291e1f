"""Tests of the pytest plugin: a user's test file using sim_plotter, sim_port and make_sim_plotter, run by pytester."""

import re
import shlex
from importlib import metadata
from pathlib import Path

import numpy  # noqa: F401 - imported before pytester's in-process runs, which restore sys.modules after each
import pytest
import serial  # noqa: F401

import pixelpen
import pixelpen.pytest_plugin  # noqa: F401
from pixelpen.display.registry import known_schemes
from pixelpen.sim.base import simulator_models

pytest_plugins = ["pytester"]
known_schemes(), simulator_models()  # load the drivers and simulators once, outside the inner runs

USER_TESTS = '''
import numpy as np
import pytest
import serial

import pixelpen
from pixelpen.sim.base import named_simulator

SEEN = []


def application(url):
    """The application under test: it only knows the URL it is given."""
    with pixelpen.open(url) as plotter:
        plotter.draw(pixelpen.Polyline([[20, 20], [120, 20]]))


def test_default_model(sim_plotter):
    assert sim_plotter.url.startswith("sim:hp7475a?") and "speed=fast" in sim_plotter.url
    assert not sim_plotter.opened
    with pytest.raises(LookupError, match="not opened"):
        sim_plotter.device
    application(sim_plotter.url)
    assert sim_plotter.opened and sim_plotter.device.model == "hp7475a"
    paper = sim_plotter.paper()
    assert paper.dtype == np.uint8 and paper.ndim == 3 and paper.shape[2] == 3
    assert (paper.max(axis=2) < 100).any() and (paper == 255).all(axis=2).mean() > 0.9
    assert any(c.startswith("PD") for c in sim_plotter.commands)
    # 100 mm cannot be drawn faster than the 7475A's top speed of 38.1 cm/s
    assert sim_plotter.elapsed > 0.100 / 0.381
    application(sim_plotter.url)  # opening the URL again reaches the same plotter
    assert sim_plotter.commands.count("IN") == 2
    SEEN.append(sim_plotter.id)


def test_devices_are_forgotten_after_their_test():
    with pytest.raises(KeyError):
        named_simulator(SEEN[0])


@pytest.mark.parametrize("sim_plotter", ["grbl", "hp7475a?paper=a3", {"model": "hp7550a", "pens": "black,red"}],
                         indirect=True)
def test_parametrised(sim_plotter, tmp_path):
    application(sim_plotter.url)
    assert sim_plotter.device.model in ("grbl", "hp7475a", "hp7550a")
    saved = sim_plotter.save_paper(tmp_path / "paper.png")
    assert saved.stat().st_size > 0


def test_pyserial_port(sim_port):
    assert sim_port.url.startswith("sim://hp7475a?")
    assert str(sim_port) == sim_port.url
    with serial.serial_for_url(sim_port.url, timeout=5) as port:
        port.write(b"IN;SP1;PU100,100;PD2100,100;OA;")
        answer = port.read_until(b"\\r")
    # OA answers x,y,pen-status once the move before it was executed; the pen is still down
    assert answer.strip() == b"2100,100,1"
    assert sim_port.commands == ["IN", "SP1", "PU100,100", "PD2100,100", "OA"]


def test_factory_gives_several_devices(make_sim_plotter):
    a = make_sim_plotter("grbl")
    b = make_sim_plotter("hp7475a", paper="a3")
    assert a.id != b.id and "paper=a3" in b.url
    application(a.url)
    assert a.opened and not b.opened


def test_unknown_model(make_sim_plotter):
    with pytest.raises(pytest.UsageError, match="known"):
        make_sim_plotter("hp9999")
'''


def _plugin_args():
    """Load the plugin by module name unless its entry point is installed (then pytest loads it by itself)."""
    installed = any(ep.name == "pixelpen" for ep in metadata.entry_points(group="pytest11"))
    quiet = ["-p", "no:cacheprovider", "-p", "no:benchmark", "-W", "ignore::pytest.PytestAssertRewriteWarning"]
    return quiet + ([] if installed else ["-p", "pixelpen.pytest_plugin"])


def test_fixtures_in_a_user_test_file(pytester):
    pytester.makepyfile(test_user=USER_TESTS)
    result = pytester.runpytest(*_plugin_args())
    result.assert_outcomes(passed=8)


def test_paper_dir_keeps_every_tests_paper(pytester, tmp_path):
    pytester.makepyfile(test_user=USER_TESTS)
    papers = tmp_path / "papers"
    result = pytester.runpytest(*_plugin_args(), "--pixelpen-paper-dir", str(papers),
                                "-k", "default_model or factory or grbl")
    result.assert_outcomes(passed=3, deselected=5)
    names = sorted(p.name for p in papers.iterdir())
    # one file per device a test opened; the factory test's second device was never opened
    assert names == ["test_default_model-hp7475a.png", "test_factory_gives_several_devices-grbl.png",
                     "test_parametrised_grbl-grbl.png"]


def test_option_is_listed_in_help(pytester):
    result = pytester.runpytest(*_plugin_args(), "--help")
    result.stdout.fnmatch_lines(["*--pixelpen-paper-dir*"])


@pytest.mark.parametrize("param", [42, "hp7475a?speed=real"])
def test_bad_parameters_are_usage_errors(param):
    from pixelpen.pytest_plugin import SimPlotter, _parse_param

    with pytest.raises(pytest.UsageError):
        model, options = _parse_param(param)
        SimPlotter(model, options)


# ---------------------------------------------------------------------------------------------------------
# every example of docs/testing-with-simulators.md runs

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "testing-with-simulators.md"


def _blocks(language):
    return re.findall(rf"^```{language}\n(.*?)^```", GUIDE.read_text(encoding="utf-8"), re.M | re.S)


def test_every_python_example_of_the_testing_guide_passes(pytester):
    blocks = _blocks("python")
    assert len(blocks) >= 4
    for k, code in enumerate(blocks):
        pytester.makepyfile(**{f"test_guide_{k}": code})
    result = pytester.runpytest(*_plugin_args())
    # each example is a test file of its own (so each states its own imports); every test in them passes
    tests = sum(len(re.findall(r"^def test_", code, re.M)) for code in blocks)
    outcomes = result.parseoutcomes()
    assert outcomes["passed"] >= tests and set(outcomes) == {"passed"}, outcomes


def test_every_command_of_the_testing_guide_runs(tmp_path, monkeypatch, capsys):
    from pixelpen.cli import main

    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PIXELPEN_CONFIG", "")
    rungs = "".join(f'<path d="M{10 + 10 * i},20 V60" stroke="black" fill="none"/>' for i in range(12))
    (tmp_path / "drawing.svg").write_text('<svg xmlns="http://www.w3.org/2000/svg" width="297mm" height="210mm" '
                                          f'viewBox="0 0 297 210">{rungs}</svg>')
    (tmp_path / "drawing.hpgl").write_bytes(b"IN;SP1;PU100,100;PD2100,100,2100,2100;PU;")
    (tmp_path / "drawing.nc").write_bytes(b"G21 G90\nM3 S500\nG0 X10 Y10\nM3 S50\nG1 X60 Y10 F3000\nM3 S500\n")
    commands = [line for block in _blocks("sh") for line in block.splitlines()
                if line.startswith("pixelpen ") and "--pty" not in line]
    assert len(commands) >= 6
    for command in commands:
        text, _, comment = command.partition("#")
        expected = int(comment.split("exit status")[1]) if "exit status" in comment else 0
        assert main(shlex.split(text)[1:]) == expected, (command, capsys.readouterr().err)
    assert (tmp_path / "paper.png").stat().st_size and "<svg" in (tmp_path / "paper.svg").read_text()
    assert (tmp_path / "sheet.png").stat().st_size
    assert not (tmp_path / "drawing.svg.plot-state.json").exists()  # the resume finished the job

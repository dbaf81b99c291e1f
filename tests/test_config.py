"""Tests of the user configuration file: where it is, what it sets, and the errors for bad files."""

import re
from pathlib import Path

import numpy as np
import pytest

from pixelpen.cli import main
from pixelpen.config import MAX_CONFIG_BYTES, config_path, load_config
from pixelpen.errors import ParseError
from pixelpen.sim.base import forget_simulator, named_simulator


@pytest.fixture
def config(tmp_path, monkeypatch):
    """Write the text as the configuration file named by $PIXELPEN_CONFIG."""
    path = tmp_path / "config.toml"
    monkeypatch.setenv("PIXELPEN_CONFIG", str(path))

    def write(text):
        path.write_text(text)
        return path

    return write


@pytest.fixture
def ident():
    name = "cfg-plotter"
    yield name
    forget_simulator(name)


def drawing(tmp_path):
    path = tmp_path / "d.svg"
    path.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="297mm" height="210mm" viewBox="0 0 297 210">'
                    '<path d="M10,20 L50,20" stroke="black" fill="none"/></svg>')
    return str(path)


def test_the_file_is_found_by_env_var_then_xdg_then_home():
    assert config_path({"PIXELPEN_CONFIG": "/x/c.toml", "XDG_CONFIG_HOME": "/y"}) == (Path("/x/c.toml"), True)
    assert config_path({"PIXELPEN_CONFIG": ""}) == (None, True)
    assert config_path({"XDG_CONFIG_HOME": "/y", "HOME": "/h"}) == (Path("/y/pixelpen/config.toml"), False)
    assert config_path({"HOME": "/h"}) == (Path("/h/.config/pixelpen/config.toml"), False)


def test_plot_takes_its_device_and_options_from_the_file(tmp_path, config, ident, capsys):
    config(f'to = "sim:grbl?speed=fast&id={ident}"\n[plot]\ncenter = true\noptimize = false\n')
    assert main(["plot", drawing(tmp_path)]) == 0
    (stroke,) = [pts for _, pts in named_simulator(ident).paper.strokes()]
    # centred on the 297 x 210 page: the 40 mm line runs from x 128.5 to 168.5 at mid height
    np.testing.assert_allclose(stroke[[0, -1]], [[128.5, 105.0], [168.5, 105.0]], atol=0.002)
    assert "ordered" not in capsys.readouterr().err  # optimize = false: no optimiser report


def test_the_command_line_wins_and_replaces_a_configured_list(tmp_path, config, capsys):
    from pixelpen.display.pictfile import save_picture
    from pixelpen.display.picture import Picture

    picture = tmp_path / "p.json"
    save_picture(Picture(), picture)
    first, second = tmp_path / "a.png", tmp_path / "b.png"
    config(f'[draw]\nto = ["png:{first}"]\n[plot]\nto = "sim:grbl?speed=fast"\n')
    assert main(["draw", str(picture), "--to", f"png:{second}"]) == 0
    assert second.exists() and not first.exists()  # the command line's --to replaced the configured one
    assert main(["plot", drawing(tmp_path), "--to", "png:x.png"]) == 2
    assert "not a pen plotter" in capsys.readouterr().err


def test_without_a_device_anywhere_the_error_says_where_to_set_one(tmp_path, config, capsys):
    config("[plot]\ncenter = true\n")
    assert main(["plot", drawing(tmp_path)]) == 2
    assert "the following arguments are required: --to" in capsys.readouterr().err


@pytest.mark.parametrize("text, needle", [
    ("[plot]\nmargn = 3\n", "[plot] margn: 'pixelpen plot' has no option --margn (did you mean margin?)"),
    ("[plto]\nmargin = 3\n", "[plto]: no such command (did you mean [plot]?)"),
    ("colour = 3\n", "colour: no command has this option"),
    ("[plot]\ncenter = 1\n", "[plot] center: expected true or false (found 1)"),
    ("[plot]\nmargin = -1\n", "[plot] margin: expected a finite number >= 0, got '-1' (found -1)"),
    ("[plot]\nmargin = [1, 2]\n", "[plot] margin: expected one value, not a list"),
    ("[plot]\nmargin = 1979-05-27\n", "[plot] margin: expected a string or a number"),
    ("[plot]\nretries = 1e400\n", "[plot] retries: expected an integer >= 0"),
    ("[sim]\nspeed = \"slow\"\n", "[sim] speed: expected one of real, fast"),
    ("[plot.x]\ny = 1\n", "[plot] x: a [COMMAND] section holds options, not tables"),
    ("[plot]\nfile = \"a.svg\"\n", "[plot] file: 'pixelpen plot' has no option --file"),
    ("[plot\n", "not valid TOML"),
    ("x = " + "[" * 5000 + "]" * 5000 + "\n", "not valid TOML"),
    ("x = " + "9" * 5000 + "\n", "not valid TOML"),
])
def test_a_bad_file_is_one_error_line_naming_the_file_and_the_key(tmp_path, config, capsys, text, needle):
    path = config(text)
    assert main(["plot", drawing(tmp_path), "--to", "sim:grbl"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    where = rf"pixelpen: error in the configuration file: {re.escape(str(path))}(, line \d+(, column \d+)?)?: "
    assert re.match(where, line), line
    assert needle in line, line


def test_bounded_reading(tmp_path, monkeypatch):
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * MAX_CONFIG_BYTES + "\n")
    with pytest.raises(ParseError, match="at most"):
        load_config(big, required=True)
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b"to = \"\xff\"\n")
    with pytest.raises(ParseError, match="not UTF-8 text"):
        load_config(bad)


def test_a_missing_named_file_is_an_error_a_missing_default_is_none(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PIXELPEN_CONFIG", str(tmp_path / "nope.toml"))
    assert main(["devices", "--no-probe", "--json"]) == 2
    assert "nope.toml: no such file (named by $PIXELPEN_CONFIG)" in capsys.readouterr().err
    monkeypatch.delenv("PIXELPEN_CONFIG")
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    assert load_config().common == {} and main(["devices", "--no-probe", "--json"]) == 0


# ---------------------------------------------------------------------------------------------------------
# fuzzing: mutants of valid configuration files give a configuration or a ParseError, nothing else

CONFIG_SEEDS = [
    b'to = "axidraw:auto"\n[plot]\nmargin = 10\ncenter = true\noptimize-time = 2\nlayers = ["1", "outline"]\n',
    b'[plot]\nto = "sim:grbl?speed=fast"\nrotate = 90.5\nfit = false\npage = "a4"\nretries = 3\n',
    b'[sim]\nspeed = "fast"\noption = ["baud=9600", "flow=xonxoff"]\n[draw]\nto = ["png:a.png"]\n',
]


def config_campaign(tmp_path, cases, seed):
    from pixelpen.cli import build_parser
    from tests.fuzzing import campaign

    commands = build_parser().commands
    path = tmp_path / "fuzz.toml"

    def target(data):
        path.write_bytes(data)
        load_config(path, required=True).apply(commands)

    return campaign("user configuration", target, CONFIG_SEEDS, cases, seed=seed, seconds_per_case=2.0,
                    memory_mb=64)


def test_config_reader_fuzz_quick(tmp_path):
    from tests.fuzzing import QUICK_CASES

    result = config_campaign(tmp_path, QUICK_CASES, seed=1)
    result.check()
    assert result.accepted >= len(CONFIG_SEEDS) and result.rejected > 0


@pytest.mark.slow
def test_config_reader_fuzz_slow(tmp_path):
    from tests.fuzzing import SLOW_CASES

    result = config_campaign(tmp_path, SLOW_CASES, seed=2)
    print(result.summary())
    result.check()

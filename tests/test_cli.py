"""Tests of the command line's own behaviour: message format, repeated warnings, usage and spelling hints."""

import logging

import pytest

from pixelpen.cli import RepeatFilter, main


@pytest.fixture(autouse=True)
def no_user_config(monkeypatch):
    monkeypatch.setenv("PIXELPEN_CONFIG", "")


def warn_twice(args):
    log = logging.getLogger("pixelpen.display.vectorize")
    for _ in range(12):
        log.warning("1 image shape(s) skipped: a vector device cannot draw raster images")
    logging.getLogger("pixelpen.commands.core").warning("another warning")
    logging.getLogger("pixelpen.commands.core").info("a progress detail")
    return 0


@pytest.fixture
def noisy(monkeypatch):
    """`pixelpen devices` replaced by a command that logs a warning 12 times, another once and an INFO line."""
    from pixelpen.commands import core

    monkeypatch.setattr(core, "cmd_devices", warn_twice)


def test_user_lines_are_plain_and_a_repeated_warning_prints_once(noisy, capsys):
    assert main(["devices"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == ["warning: 1 image shape(s) skipped: a vector device cannot draw raster images",
                   "warning: another warning",
                   "(11 more of: 1 image shape(s) skipped: a vector device cannot draw raster images)"]


def test_v_adds_details_and_vv_shows_every_record_with_its_logger(noisy, capsys):
    assert main(["-v", "devices"]) == 0
    assert "a progress detail" in capsys.readouterr().err.splitlines()
    assert main(["-vv", "devices"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err.count("WARNING pixelpen.display.vectorize: 1 image shape(s) skipped: a vector device cannot draw "
                     "raster images") == 12
    assert "INFO pixelpen.commands.core: a progress detail" in err


def test_main_leaves_logging_as_it_found_it(noisy):
    logger = logging.getLogger("pixelpen")
    before = (list(logger.handlers), logger.level)
    main(["-vv", "devices"])
    assert (list(logger.handlers), logger.level) == before


def test_repeat_filter_counts_by_level_and_text():
    f = RepeatFilter()
    records = [logging.LogRecord("x", level, "", 0, msg, args, None)
               for level, msg, args in [(30, "a %d", (1,)), (30, "a 1", ()), (40, "a 1", ()), (30, "b", ())]]
    assert [f.filter(r) for r in records] == [True, False, True, True]
    assert f.summary() == ["(1 more of: a 1)"]


def test_a_mistyped_option_gets_the_subcommands_usage_and_a_suggestion(capsys):
    assert main(["plot", "d.svg", "--to", "sim:grbl", "--retris", "2"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: pixelpen plot ")
    assert "pixelpen plot: error: unrecognized arguments: --retris" in err and "(did you mean --retries?)" in err
    assert main(["stats", "d.svg", "--jsno"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: pixelpen stats ") and "(did you mean --json?)" in err


def test_a_mistyped_command_or_choice_gets_a_suggestion(capsys):
    assert main(["plto", "d.svg"]) == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'plto'" in err and "(did you mean plot?)" in err
    assert main(["pen", "dwon", "--to", "sim:grbl"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: pixelpen pen ") and "(did you mean down?)" in err


def test_help_and_version_exit_0(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.startswith("pixelpen ")
    assert main(["plot", "--help"]) == 0
    out = capsys.readouterr().out
    # the layout order, the simulator's paper option and the configuration file are documented in --help
    assert "rotate, scale, layout" in out and "out=PAPER.png" in out and "config.toml" in out
    assert max(len(line) for line in out.splitlines()) <= 100  # wrapped for a terminal

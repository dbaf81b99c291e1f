"""Command-line value types are the URL option converters: same checks, argparse's error with the value."""

from __future__ import annotations

import argparse

import pytest

from pixelpen.commands import argtypes


@pytest.mark.parametrize(("convert", "text", "value"), [
    (argtypes.positive, "2.5", 2.5), (argtypes.non_negative, "0", 0.0), (argtypes.non_negative_int, "3", 3),
    (argtypes.finite, "-90", -90.0),
])
def test_good_values(convert, text, value) -> None:
    assert convert(text) == value


@pytest.mark.parametrize(("convert", "text", "message"), [
    (argtypes.positive, "0", "expected a finite number > 0, got '0'"),
    (argtypes.positive, "nan", "expected a finite number > 0, got 'nan'"),
    (argtypes.non_negative, "-1", "expected a finite number >= 0, got '-1'"),
    (argtypes.non_negative_int, "1.5", "expected an integer >= 0, got '1.5'"),
    (argtypes.finite, "inf", "expected a finite number, got 'inf'"),
])
def test_bad_values_are_argparse_errors_naming_the_value(convert, text, message) -> None:
    with pytest.raises(argparse.ArgumentTypeError) as caught:
        convert(text)
    assert str(caught.value) == message


def test_a_parser_reports_them_as_usage_errors(capsys) -> None:
    parser = argparse.ArgumentParser(prog="p")
    parser.add_argument("--margin", type=argtypes.non_negative)
    with pytest.raises(SystemExit):
        parser.parse_args(["--margin", "-2"])
    assert "argument --margin: expected a finite number >= 0, got '-2'" in capsys.readouterr().err

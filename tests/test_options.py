"""URL options declared once: specs read, refuse and describe options the same way for every device."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.errors import PixelpenError, URLError
from pixelpen.options import (
    OptionSpec,
    boolean,
    check_known,
    choice,
    colour,
    describe,
    i2c_address,
    integer,
    non_negative,
    number,
    pixels,
    positive,
    read_options,
    text,
)

SPECS = (
    OptionSpec("paper", text, "a4", "paper size"),
    OptionSpec("speed", positive, 10.0, "mm/s"),
    OptionSpec("pens", integer(1, 8), 1, "pens in the carousel"),
    OptionSpec("flow", choice("none", "rtscts", "xonxoff"), "none", "handshake"),
    OptionSpec("mirror", boolean, False, "mirror the sheet"),
)


def test_absent_options_take_their_defaults_and_given_ones_are_converted() -> None:
    values = read_options(SPECS, {"speed": "2.5", "flow": "RTSCTS"}, "sim:hp7475a")
    assert dict(values) == {"paper": "a4", "speed": 2.5, "pens": 1, "flow": "rtscts", "mirror": False}
    assert values.given == {"speed", "flow"}


def test_an_unknown_option_names_the_url_the_known_ones_and_the_closest() -> None:
    with pytest.raises(URLError) as caught:
        read_options(SPECS, {"papr": "a3"}, "hp7475a:/dev/ttyUSB0")
    message = str(caught.value)
    assert message.startswith("hp7475a:/dev/ttyUSB0: unknown option(s) papr; known: flow, mirror, paper, pens, speed")
    assert "did you mean 'paper'?" in message


def test_port_options_outside_brackets_get_the_bracket_hint() -> None:
    with pytest.raises(URLError, match="inside brackets"):
        check_known(["paper"], ["logging"], "hp7475a:rfc2217://host:4000")


@pytest.mark.parametrize(("name", "raw", "expected"), [
    ("speed", "0", "expected a finite number > 0"),
    ("speed", "inf", "expected a finite number > 0"),
    ("speed", "nan", "expected a finite number > 0"),
    ("pens", "9", "expected an integer in [1, 8]"),
    ("pens", "1.5", "expected an integer in [1, 8]"),
    ("pens", "²", "expected an integer in [1, 8]"),
    ("pens", "9" * 400, "expected an integer in [1, 8]"),
    ("flow", "dsrdtr", "expected one of none, rtscts, xonxoff"),
    ("mirror", "maybe", "expected true/false"),
])
def test_a_bad_value_names_url_option_value_and_what_was_expected(name: str, raw: str, expected: str) -> None:
    with pytest.raises(URLError) as caught:
        read_options(SPECS, {name: raw}, "sim:hp7475a")
    message = str(caught.value)
    assert message.startswith(f"sim:hp7475a: option {name}=")
    assert "is not valid" in message and expected in message
    assert isinstance(caught.value, PixelpenError) and isinstance(caught.value, ValueError)


@pytest.mark.parametrize("raw", ["1", "true", "YES", " on "])
def test_boolean_true_spellings(raw: str) -> None:
    assert boolean(raw) is True


@pytest.mark.parametrize("raw", ["0", "false", "No", "off"])
def test_boolean_false_spellings(raw: str) -> None:
    assert boolean(raw) is False


def test_number_bounds_are_inclusive_unless_above() -> None:
    assert number(0, 1)("1") == 1.0 and number(0, 1)("0") == 0.0
    assert non_negative("0") == 0.0
    with pytest.raises(ValueError, match=r"expected a finite number in \(0, 1\]"):
        number(0, 1, above=True)("0")


@given(st.integers(min_value=-10**6, max_value=10**6))
def test_integer_reads_every_decimal_integer_in_range(value: int) -> None:
    convert = integer(-10**6, 10**6)
    assert convert(str(value)) == value


@given(st.floats(allow_nan=False, allow_infinity=False, width=64))
def test_number_reads_back_what_repr_writes(value: float) -> None:
    assert number()(repr(value)) == value


def test_colour_checks_but_keeps_the_text() -> None:
    assert colour("SteelBlue") == "SteelBlue"
    with pytest.raises(PixelpenError, match="unknown colour"):
        colour("bleu")


def test_describe_gives_help_with_defaults_in_declaration_order() -> None:
    rows = describe((*SPECS, OptionSpec("pen_colours", text, ("black", "red"), "pen colours"),
                     OptionSpec("state", text, None, "state file")))
    assert [name for name, _ in rows] == ["paper", "speed", "pens", "flow", "mirror", "pen_colours", "state"]
    assert rows[1] == ("speed", "mm/s (default 10.0)")
    assert rows[5] == ("pen_colours", "pen colours (default black,red)")
    assert rows[6] == ("state", "state file")


def test_option_values_is_a_read_only_mapping() -> None:
    values = read_options(SPECS, {}, "x:")
    assert len(values) == len(SPECS) and set(values) == {s.name for s in SPECS}
    with pytest.raises(TypeError):
        values["paper"] = "a3"  # type: ignore[index]
    assert math.isclose(values["speed"], 10.0)


@pytest.mark.parametrize(("text", "size"), [("128x64", (128, 64)), (" 240X320 ", (240, 320)), ("1x1", (1, 1))])
def test_pixels_reads_whole_pixels(text, size):
    assert pixels(text) == size


@pytest.mark.parametrize("text", ["128", "12.5x8", "10x10mm", "a4", "0x8", "x", ""])
def test_pixels_refuses_anything_else_with_a_value_error(text):
    with pytest.raises(ValueError):
        pixels(text)


@pytest.mark.parametrize(("text", "address"), [("0x3c", 0x3C), ("0X3D", 0x3D), ("8", 8), ("0x77", 0x77)])
def test_i2c_address_option_reads_non_reserved_7_bit_addresses(text, address):
    assert i2c_address(text) == address


@pytest.mark.parametrize("text", ["0x07", "0", "0x78", "0x7f", "0x80", "0x3c3", "-1"])
def test_i2c_address_option_refuses_reserved_and_out_of_range_addresses(text):
    with pytest.raises(ValueError, match=r"0x08\.\.0x77 \(0x00\.\.0x07 and 0x78\.\.0x7f are reserved\)"):
        i2c_address(text)


@pytest.mark.parametrize("text", ["sixty", "", "3c"])
def test_i2c_address_option_refuses_what_is_no_number(text):
    with pytest.raises(ValueError, match="such as 0x3c"):
        i2c_address(text)

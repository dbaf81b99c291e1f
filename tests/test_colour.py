"""Colour text read the CSS way: names from the CSS table, hex and functional forms, tuples of bytes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.colour import NAMED_COLOURS, colour_hex, parse_colour
from pixelpen.errors import ConfigError

CSS_SAMPLES = {  # CSS Color Module Level 3, section 4.3 (extended colour keywords), read from the spec
    "aliceblue": (240, 248, 255), "rebeccapurple": (102, 51, 153), "steelblue": (70, 130, 180),
    "yellowgreen": (154, 205, 50), "grey": (128, 128, 128), "darkslategray": (47, 79, 79),
}


def test_the_table_is_the_css_one() -> None:
    assert len(NAMED_COLOURS) == 148
    for name, rgb in CSS_SAMPLES.items():
        assert parse_colour(name) == rgb
        assert parse_colour(name.upper()) == rgb


@pytest.mark.parametrize(("text", "rgb"), [
    ("#abc", (0xAA, 0xBB, 0xCC)), ("#A0b1C2", (0xA0, 0xB1, 0xC2)), ("rgb(1, 2, 3)", (1, 2, 3)),
    ("rgb(100%, 0%, 50%)", (255, 0, 128)), ("hsl(120, 100%, 50%)", (0, 255, 0)), ("  red ", (255, 0, 0)),
])
def test_hex_and_functional_forms(text: str, rgb: tuple[int, int, int]) -> None:
    assert parse_colour(text) == rgb


@pytest.mark.parametrize("bad", ["bleu", "#12", "#12345", "#ggg", "rgba(1,2,3,0.5)", "#11223344", "x" * 10_000, ""])
def test_unknown_colour_text_is_a_config_error_quoting_it(bad: str) -> None:
    with pytest.raises(ConfigError, match="unknown colour"):
        parse_colour(bad)


@pytest.mark.parametrize("bad", [(1, 2), (1, 2, 256), (-1, 0, 0), (True, 0, 0), (1.0, 2, 3), None, 7])
def test_bad_tuples_and_types(bad: object) -> None:
    with pytest.raises(ConfigError):
        parse_colour(bad)


@given(st.tuples(*[st.integers(0, 255)] * 3))
def test_hex_round_trip(rgb: tuple[int, int, int]) -> None:
    assert parse_colour(colour_hex(rgb)) == rgb
    assert parse_colour(tuple(np.uint8(c) for c in rgb)) == rgb

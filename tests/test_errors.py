"""Tests of the exception hierarchy: combined classes, and token quoting that stays short on any value."""

from __future__ import annotations

import pytest

from pixelpen.errors import (
    TOKEN_CHARS,
    ConfigError,
    InvalidArgument,
    InvalidArgumentType,
    ParseError,
    PixelpenError,
    quote_token,
)


def test_argument_errors_are_both_families():
    assert issubclass(InvalidArgument, PixelpenError) and issubclass(InvalidArgument, ValueError)
    assert issubclass(InvalidArgumentType, PixelpenError) and issubclass(InvalidArgumentType, TypeError)
    assert not issubclass(InvalidArgument, ConfigError)


def _nested(depth: int) -> list:
    value: list = []
    for _ in range(depth):
        value = [value]
    return value


def test_a_deeply_nested_token_is_quoted_without_recursing():
    # repr() of this list raises RecursionError; the message must still be made, and be short
    with pytest.raises(RecursionError):
        repr(_nested(100_000))
    err = ParseError("too deep", source="f.json", token=_nested(100_000))
    assert str(err).startswith("f.json: too deep (found [[[") and len(str(err)) < 80
    assert isinstance(err.token, list)  # the token itself is kept whole


@pytest.mark.parametrize("value, shown", [
    (10**5000, "<integer of about 5001 digits>"),  # str() of it raises ValueError (4300-digit limit)
    ([10**400], "[<integer of about 401 digits>]"),
    ("abc", "'abc'"),
    (3.5, "3.5"),
    ({"a": {"b": {"c": {"d": 1}}}}, "{'a': {'b': {'c': {...}}}}"),
], ids=["huge-int", "huge-int-in-list", "str", "float", "nested-dict"])
def test_quote_token_bounds_depth_and_size(value, shown):
    assert quote_token(value) == shown


def test_quote_token_bounds_length():
    assert len(quote_token("x" * 10_000)) <= TOKEN_CHARS
    assert len(quote_token(list(range(10_000)))) <= TOKEN_CHARS
    assert len(str(ParseError("bad", token="y" * 10_000))) < TOKEN_CHARS + 20

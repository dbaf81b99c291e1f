"""Command-line value types made from the URL option converters (``pixelpen.options``): one set of checks for both."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import TypeVar

from pixelpen import options

T = TypeVar("T")


def argtype(convert: Callable[[str], T]) -> Callable[[str], T]:
    """An argparse ``type=`` from an option converter: its complaint becomes argparse's, with the value given."""

    def parse(text: str) -> T:
        try:
            return convert(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(f"{exc}, got {text!r}") from None

    parse.__name__ = getattr(convert, "__name__", "value")
    return parse


positive = argtype(options.positive)
"""A finite number > 0."""
non_negative = argtype(options.non_negative)
"""A finite number >= 0."""
non_negative_int = argtype(options.integer(0))
"""A whole number >= 0."""
finite = argtype(options.number())
"""Any finite number (an angle in degrees)."""

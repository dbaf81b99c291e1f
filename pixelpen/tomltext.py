"""Bounded TOML reading shared by device profiles and the user configuration: nesting and number size checked.

tomllib recurses once per nested array or inline table and converts integers with ``int()``, so a file nested a
thousand deep or holding a 5,000-digit number escapes as RecursionError or ValueError.  :func:`read_toml` scans
the nesting first (strings and comments skipped) and turns every failure into a ParseError naming the source and,
where known, the line and column.
"""

from __future__ import annotations

import re
import sys

from pixelpen.errors import ParseError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.10 only
    import tomli as tomllib

_TOML_TOKEN = re.compile(
    r'"""[\s\S]*?"""'  # multi-line basic string
    r"|'''[\s\S]*?'''"  # multi-line literal string
    r'|"(?:[^"\\\n]|\\.)*"'  # basic string
    r"|'[^'\n]*'"  # literal string
    r"|#[^\n]*"  # comment
    r"|[\[\]{}]"  # what nests
)


def _check_depth(text: str, source: str, max_depth: int) -> None:
    """ParseError at the first array or inline table nested more than ``max_depth`` deep."""
    depth = 0
    for token in _TOML_TOKEN.finditer(text):
        bracket = token[0]
        if bracket in ("[", "{"):
            depth += 1
            if depth > max_depth:
                line = text.count("\n", 0, token.start()) + 1
                column = token.start() - text.rfind("\n", 0, token.start())
                raise ParseError(f"not valid TOML: arrays or tables nested more than {max_depth} deep", source=source,
                                 line=line, column=column)
        elif bracket in ("]", "}"):
            depth = max(depth - 1, 0)


def read_toml(text: str, source: str, *, max_depth: int) -> dict:
    """Parse TOML text; any failure is a ParseError naming ``source`` (and the line and column where tomllib says)."""
    _check_depth(text, source, max_depth)
    try:
        return tomllib.loads(text)
    except (ValueError, RecursionError) as exc:
        if not isinstance(exc, tomllib.TOMLDecodeError):  # int() past 4300 digits, or nesting the scan missed
            long = re.search(r"[0-9_]{4300,}", text)
            line = None if long is None else text.count("\n", 0, long.start()) + 1
            raise ParseError(f"not valid TOML: {str(exc)[:200]}", source=source, line=line) from None
        msg = str(exc)
        where = re.search(r"\(at line (\d+), column (\d+)\)", msg)
        if where:
            msg = msg[: where.start()].strip()
            line, column = int(where[1]), int(where[2])
            raise ParseError(f"not valid TOML: {msg}", source=source, line=line, column=column) from None
        raise ParseError(f"not valid TOML: {msg}", source=source) from None

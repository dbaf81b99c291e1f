"""The guard pass before svgelements reads an SVG: limits per file, checked in one expat pass over the bytes.

Limits per file (:class:`SvgLimits`; pass ``read_svg(..., limits=SvgLimits(max_points=...))`` to change them),
each exceeded one a :class:`~pixelpen.errors.ParseError` naming the file, the element and the limit:

- ``max_bytes`` (64 MiB): size of the document.
- ``max_elements`` (200,000): elements as written (svgelements needs ~2.5 kB and ~0.2 ms per element).
- ``max_use_elements`` (20,000): elements instantiated by ``<use>`` (each copy costs as much as an element).
- ``max_depth`` (200): element nesting, counting what ``<use>`` nests; a ``<use>`` that contains itself is an error.
- ``max_number_chars`` (64): characters of one number in an attribute (svgelements' regexes are cubic in it).
- ``max_strokes`` (1,000,000) and ``max_points`` (10,000,000): polylines and points after flattening.

Malformed syntax that would make svgelements' regexes backtrack for minutes is refused up front: a ``points``
list that is not pairs of numbers, a ``<style>`` with an unclosed comment or a rule that is not
``selector { declarations }`` (beyond 10,000 characters). The flattening limits (``max_strokes``,
``max_points``) are applied by :mod:`pixelpen.vector.svgimport`.
"""

from __future__ import annotations

import functools
import os
import re
from collections.abc import Iterator
from dataclasses import dataclass, fields
from typing import IO
from xml.parsers import expat

from pixelpen.errors import ConfigError, ParseError

__all__ = ["CSS_CHECKED_CHARS", "NUMBER", "CheckedDocument", "Source", "SvgLimits", "read_source"]

SVG_NS = "http://www.w3.org/2000/svg"
XLINK_HREF = "{http://www.w3.org/1999/xlink}href"
CSS_CHECKED_CHARS = 10_000
"""A ``<style>`` longer than this must be plain ``selector { declarations }`` rules (svgelements' CSS regex is
quadratic in anything else)."""
Source = str | os.PathLike[str] | bytes | IO[bytes] | IO[str]
"""Where an SVG comes from: a path, the document's bytes, or an open file."""

# svgelements' number and separator grammar, written possessively so that checking is linear
NUMBER = r"[-+]?+(?:[0-9]*+\.[0-9]++|[0-9]++)(?:[eE][-+]?+[0-9]++)?+"
_SEP = r"(?:\s*+,\s*+|\s++|(?=-))"
_PAIR = rf"{NUMBER}{_SEP}{NUMBER}"
_POINTS = re.compile(rf"\s*+(?:{_PAIR}(?:{_SEP}{_PAIR})*+)?+\s*+")
_TRANSFORM = re.compile(r"\s*+(?:[A-Za-z]++\s*+(?:\([^()]*+\))?+[\s,]*+)*+")
_CSS_RULES = re.compile(r"(?:[^{}]*+\{[^{}]*+\})*+\s*+")
_CSS_COMMENT = re.compile(r"/\*.*?\*/", re.S)



@dataclass(frozen=True)
class SvgLimits:
    """Per-file limits of :func:`read_svg` (see the module docstring); each exceeded one is a ParseError."""

    max_bytes: int = 64 * 2**20
    max_elements: int = 200_000
    max_use_elements: int = 20_000
    max_depth: int = 200
    max_number_chars: int = 64
    max_strokes: int = 1_000_000
    max_points: int = 10_000_000

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= 1):
                raise ConfigError(f"SvgLimits.{f.name} must be an integer >= 1, got {value!r}")


def read_source(source: Source, limit: int) -> tuple[bytes, str]:
    """The document bytes (at most ``limit``) and a name for messages."""
    if isinstance(source, (bytes, bytearray)):
        data, name = bytes(source), "<bytes>"
    elif isinstance(source, (str, os.PathLike)):
        name = os.fspath(source)
        try:
            with open(name, "rb") as fh:
                data = fh.read(limit + 1)
        except (OSError, ValueError) as exc:
            raise ParseError(f"cannot read SVG file: {getattr(exc, 'strerror', None) or exc}", source=name) from None
    else:
        name = str(getattr(source, "name", "<stream>"))
        try:
            raw = source.read(limit + 1)
        except (OSError, ValueError) as exc:
            raise ParseError(f"cannot read SVG stream: {exc}", source=name) from None
        data = raw.encode("utf-8") if isinstance(raw, str) else bytes(raw)
    if len(data) > limit:
        raise ParseError(f"file larger than {limit} bytes (limit max_bytes)", source=name)
    return data, name


@functools.lru_cache(maxsize=8)
def _number_run(max_chars: int) -> re.Pattern[str]:
    """A run of digits and dots longer than ``max_chars`` (cached per limit)."""
    return re.compile(rf"[0-9.]{{{max_chars + 1},}}")


def _longest_number(run: str) -> int:
    """Characters of the longest number in a run of digits and dots (a second dot starts a new number)."""
    parts = run.split(".")
    head = len(parts[0]) + (len(parts[1]) + 1 if len(parts) > 1 else 0)
    return max([head] + [len(p) + 1 for p in parts[2:]])


def _declarations(text: str) -> Iterator[tuple[str, str]]:
    """(property, value) of each ``name: value`` in a style attribute or CSS rule body, as svgelements splits them."""
    for item in text.split(";"):
        pair = item.split(":")
        if len(pair) == 2:
            yield pair[0].strip(), pair[1].strip()


class CheckedDocument:
    """One expat pass over an SVG: its element tree with ids and ``<use>`` links, checked against the limits.

    Syntax that svgelements' regular expressions would take minutes over (over-long numbers, malformed
    ``points`` and ``transform`` lists, unclosed CSS) is refused here, before svgelements sees the text.
    """

    def __init__(self, data: bytes, name: str, limits: SvgLimits) -> None:
        self.name, self.limits = name, limits
        self.tags: list[str] = []
        self.ids: list[str | None] = []
        self.where: list[tuple[int, int]] = []
        self.children: list[list[int]] = []
        self.href: dict[int, str] = {}
        self.by_id: dict[str, int] = {}
        self.root: dict[str, str] = {}
        self._open: list[int] = []
        self._text: list[str] = []
        self._parser = expat.ParserCreate(namespace_separator="}")
        self._parser.buffer_text = True
        self._parser.StartElementHandler = self._start
        self._parser.EndElementHandler = self._end
        self._parser.CharacterDataHandler = self._chars
        try:
            self._parser.Parse(data, True)
        except expat.ExpatError as exc:
            reason = re.sub(r":? line \d+, column \d+$", "", str(exc))
            raise ParseError(f"not well-formed XML, so not an SVG document ({reason})",
                             source=name, line=exc.lineno, column=exc.offset + 1) from None
        self._check_expansion()

    def error(self, i: int, message: str) -> ParseError:
        """A ParseError about element ``i``, naming it and its position."""
        line, column = self.where[i]
        what = f"<{self.tags[i]}" + (f" id={self.ids[i]!r}>" if self.ids[i] else ">")
        return ParseError(f"{what}: {message}", source=self.name, line=line, column=column)

    def _start(self, tag: str, attrs: dict[str, str]) -> None:
        """Record an element, its id and <use> link; check its attributes and style."""
        i = len(self.tags)
        if i >= self.limits.max_elements:
            raise ParseError(f"more than {self.limits.max_elements} elements (limit max_elements)", source=self.name,
                             line=self._parser.CurrentLineNumber, column=self._parser.CurrentColumnNumber + 1)
        tag = tag.removeprefix(SVG_NS + "}")
        tag = "{" + tag if "}" in tag else tag
        attrs = {("{" + k if "}" in k else k): v for k, v in attrs.items()}
        self.tags.append(tag)
        self.ids.append(attrs.get("id"))
        self.where.append((self._parser.CurrentLineNumber, self._parser.CurrentColumnNumber + 1))
        self.children.append([])
        if self._open:
            self.children[self._open[-1]].append(i)
        elif tag != "svg":
            raise ParseError(f"not an SVG document: the root element is <{tag}>, expected <svg>", source=self.name)
        else:
            self.root = attrs
        if len(self._open) >= self.limits.max_depth:
            raise self.error(i, f"nested deeper than {self.limits.max_depth} elements (limit max_depth)")
        self._open.append(i)
        self._text = []
        if "id" in attrs:
            self.by_id[attrs["id"]] = i
        href = attrs.get("href", attrs.get(XLINK_HREF))
        if tag == "use" and href is not None:
            self.href[i] = href[1:]  # as svgelements resolves it: the id after the first character
        for key, value in attrs.items():
            self._check_value(i, key, value)
        for key, value in _declarations(attrs.get("style", "")):
            self._check_value(i, key, value)

    def _chars(self, text: str) -> None:
        """Collect character data (a <style> sheet's text)."""
        self._text.append(text)

    def _end(self, tag: str) -> None:
        """Close an element; a <style> sheet is checked whole."""
        i = self._open.pop()
        if self.tags[i] == "style":
            self._check_css(i, "".join(self._text))
        self._text = []

    def _check_value(self, i: int, key: str, value: str) -> None:
        """Refuse over-long numbers and malformed points/transform lists in one attribute value."""
        run = _number_run(self.limits.max_number_chars).search(value)
        if run and _longest_number(run.group()) > self.limits.max_number_chars:
            raise self.error(i, f"attribute {key!r} has a number longer than {self.limits.max_number_chars} "
                                f"characters (limit max_number_chars)")
        if key == "points" and not _POINTS.fullmatch(value):
            raise self.error(i, "'points' is not a list of coordinate pairs")
        if key == "transform" and not _TRANSFORM.fullmatch(value):
            raise self.error(i, f"'transform' is not a list of transform functions: {value[:60]!r}")

    def _check_css(self, i: int, text: str) -> None:
        """Refuse unclosed comments and (in long sheets) text that is not plain rules."""
        start = text.rfind("/*")
        if start >= 0 and text.find("*/", start + 2) < 0:
            raise self.error(i, "unclosed /* comment in the style sheet")
        text = _CSS_COMMENT.sub("", text)
        if len(text) > CSS_CHECKED_CHARS and not _CSS_RULES.fullmatch(text):
            raise self.error(i, "style sheet is not a list of 'selector { declarations }' rules")
        for body in re.split(r"[{}]", text):
            self._check_value(i, "style", body)
            for key, value in _declarations(body):
                self._check_value(i, key, value)

    def _successors(self, i: int) -> list[int]:
        """Children of element ``i`` and, for a <use>, the element it copies."""
        target = self.by_id.get(self.href.get(i, ""), -1) if i in self.href else -1
        return self.children[i] + ([target] if target >= 0 else [])

    def _check_expansion(self) -> None:
        """Refuse ``<use>`` cycles, and fan-out or nesting beyond the limits once every ``<use>`` is expanded."""
        n, limits = len(self.tags), self.limits
        cap = n + limits.max_use_elements + 1
        size, depth, state = [0] * n, [0] * n, bytearray(n)
        stack = [0]
        while stack:
            i = stack[-1]
            if state[i] == 0:
                state[i] = 1
                for j in self._successors(i):
                    if state[j] == 1:
                        raise self.error(i, f"refers to #{self.href[i]}, which contains it (a <use> cycle)")
                    if state[j] == 0:
                        stack.append(j)
                continue
            stack.pop()
            if state[i] == 1:
                succ = self._successors(i)
                size[i] = min(cap, 1 + sum(size[j] for j in succ))
                depth[i] = 1 + max((depth[j] for j in succ), default=0)
                state[i] = 2
        if size[0] - n > limits.max_use_elements:
            worst = max(self.href, key=lambda u: size[self.by_id.get(self.href[u], int(u))])
            raise self.error(worst, f"<use> elements would copy more than {limits.max_use_elements} elements "
                                    f"(limit max_use_elements)")
        if depth[0] > limits.max_depth:
            i = 0
            for _ in range(limits.max_depth):
                i = max(self._successors(i), key=depth.__getitem__)
            raise self.error(i, f"nested deeper than {limits.max_depth} elements once <use> is expanded "
                                f"(limit max_depth)")

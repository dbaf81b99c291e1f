"""Vectorised tables of a text file's lines and whitespace-separated tokens, for the fast paths of the readers.

A :class:`TextTable` finds every line and token of a file with numpy (no Python loop over lines): line starts
and ends, token starts and ends, the line of each token, and each line's keyword (its first token) packed into
one integer.  :meth:`TextTable.numbers` parses the numeric tokens of chosen lines at once with
``numpy.fromstring``; it only ever accepts what :func:`parse_float` accepts token by token, so a reader's
per-line slow path and its vectorised fast path agree.  Line breaks are ``\\n``, ``\\r\\n`` or ``\\r``; a line
ending in a backslash continues on the next line (the OBJ rule).  Normalising keeps every byte offset, so
columns and line numbers name the bytes of the file as written.
"""

from __future__ import annotations

import re

import numpy as np
import numpy.typing as npt

from pixelpen.errors import ParseError

__all__ = ["NUMBER", "SPACE", "TextTable", "decimals", "keyword_code", "parse_float", "plain_numbers", "ranges"]

NUMBER = re.compile(rb"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")
"""A decimal number as the readers accept it (no ``nan``, ``inf``, hex or ``_``); linear, never backtracking."""

KEYWORD_BYTES = 8
"""Keywords up to this many bytes are packed into one integer code."""

SPACE = np.zeros(256, dtype=bool)
SPACE[list(b" \t\n\r\x0b\x0c")] = True
_FLOAT_CHARS = SPACE.copy()
_FLOAT_CHARS[list(b"0123456789+-.eE")] = True

_PLAIN = np.full(256, 5, dtype=np.uint8)  # byte classes of plain_numbers: 0 digit, 1 space or LF, 2 "-", 3 "."
_PLAIN[list(b"0123456789")] = 0
_PLAIN[[32, 10]] = 1
_PLAIN[ord("-")] = 2
_PLAIN[ord(".")] = 3
PLAIN_DIGITS = 15
"""Most digits of a number read by one division: m < 2**53 and 10**k exact, so m / 10**k is correctly rounded."""
EXTENDED = np.finfo(np.longdouble).nmant >= 63
"""Whether numpy's longdouble holds any 18-digit mantissa exactly (x86 extended or quad precision)."""

IntArray = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


def keyword_code(word: bytes) -> int:
    """The integer a keyword of up to KEYWORD_BYTES bytes packs into (0 is no keyword or a longer one)."""
    return int.from_bytes(word.ljust(KEYWORD_BYTES, b"\0"), "little")


def parse_float(token: bytes, what: str, source: str, line: int, column: int) -> float:
    """One decimal number of a file; a ParseError naming the place unless it is a finite number."""
    if NUMBER.fullmatch(token) is None:
        raise ParseError(f"{what} is not a number", source=source, line=line, column=column, token=token)
    value = float(token)
    if not np.isfinite(value):
        raise ParseError(f"{what} is out of range", source=source, line=line, column=column, token=token)
    return value


def ranges(starts: IntArray, stops: IntArray) -> IntArray:
    """The concatenation of ``arange(start, stop)`` for each pair, without a Python loop."""
    lengths = np.maximum(stops - starts, 0)
    offsets = np.cumsum(lengths) - lengths
    return np.repeat(starts - offsets, lengths) + np.arange(int(lengths.sum()), dtype=np.int64)


def plain_numbers(text: npt.NDArray[np.uint8], integer: bool,
                  ) -> tuple[FloatArray | IntArray, IntArray, IntArray] | None:
    """The space- or LF-separated tokens of ``text`` as numbers when all are plain ``-?d+`` (or ``-?d*.d*``).

    Returns (values, token starts, positions of the LFs), or None when a token is of another form (an
    exponent, ``+``, an integer of more than 18 digits) or a byte is not of these forms.  The values are
    :func:`decimals` of the tokens, bit for bit what :func:`parse_float` gives.
    """
    classes = _PLAIN[text]
    count = [np.count_nonzero(classes == k) for k in range(6)]  # (bincount widens the bytes: 10x slower)
    if count[5] or (integer and count[3]):
        return None
    separator = (classes == 1).view(np.int8)
    del classes
    edges = np.flatnonzero(np.diff(separator, prepend=np.int8(1), append=np.int8(1)))
    del separator
    starts, ends = edges[0::2], edges[1::2]
    if int(np.count_nonzero(text[starts] == ord("-"))) != count[2]:  # a minus inside a token
        return None
    values, ok = decimals(text, starts, ends, integer)
    if not ok.all():
        return None
    return values, starts.astype(np.int64, copy=False), np.flatnonzero(text == 10).astype(np.int64, copy=False)


def decimals(text: npt.NDArray[np.uint8], starts: IntArray, ends: IntArray, integer: bool = False,
             ) -> tuple[FloatArray | IntArray, BoolArray]:
    """The tokens ``text[starts[i]:ends[i]]`` as numbers, and whether each is of the plain form read here.

    A plain token is ``[+-]`` then digits with at most one point (``5``, ``-0.25``, ``5.``, ``.5``; no point
    when ``integer``) and at most 18 digits; its value is bit for bit :func:`parse_float`'s (``int`` when
    ``integer``).  Tokens of other forms (an exponent, 19 digits, a letter) have ``ok`` False and value 0
    for the caller to read otherwise.  Tokens are gathered in buckets of one length and read digit column
    by digit column.  A decimal m / 10**k of at most PLAIN_DIGITS digits is one correctly rounded division;
    a longer one (the repr of a double has up to 17 digits) is divided in 64-bit extended precision and
    rounded to a double, which is correct unless the extended quotient lies exactly half-way between two
    doubles: those few (and all longer ones where numpy has no extended type) are not ok.
    """
    lead = text[starts]
    first = starts + ((lead == ord("-")) | (lead == ord("+")))
    length = ends - first
    values: FloatArray | IntArray = (np.zeros(len(starts), dtype=np.int64) if integer
                                     else np.zeros(len(starts), dtype=np.float64))
    ok = np.zeros(len(starts), dtype=bool)
    for width in np.unique(length[(length >= 1) & (length <= 19)]).tolist():
        chosen = np.flatnonzero(length == width)
        mantissa, scale, digits, good = _digit_columns(text, first[chosen], width, integer)
        if integer:
            values[chosen] = mantissa
        else:
            values[chosen] = mantissa / 10.0 ** scale  # m < 2**53 and 10**k exact: one rounding
            long = np.flatnonzero(digits > PLAIN_DIGITS)
            if len(long) and EXTENDED:
                values[chosen[long]], exact = _extended_quotient(mantissa[long], scale[long])
                good[long] &= exact
            else:
                good[long] = False
        ok[chosen] = good
    negative = lead == ord("-")
    values[negative] = -values[negative]
    return values, ok


def _digit_columns(text: npt.NDArray[np.uint8], first: IntArray, width: int, integer: bool,
                   ) -> tuple[IntArray, IntArray, IntArray, BoolArray]:
    """(mantissa, digits after the point, digits, plain) of the ``width``-byte tokens starting at ``first``."""
    mantissa = np.zeros(len(first), dtype=np.int64)
    point = np.full(len(first), -1, dtype=np.int64)
    bad = np.zeros(len(first), dtype=bool)
    for column in range(width):  # a loop over the bytes of one bucket's tokens, not over tokens
        byte = text[first + column]
        digit = byte - np.uint8(48)  # wraps: every non-digit is above 9
        is_point = byte == ord(".")
        if is_point.any():
            bad |= (point >= 0) & is_point  # a second point
            point[is_point] = column
            bad |= (digit > 9) & ~is_point
            mantissa = np.where(is_point, mantissa, mantissa * 10 + digit)
        else:
            bad |= digit > 9
            mantissa = mantissa * 10 + digit
    scale = np.where(point >= 0, width - 1 - point, 0)
    digits = width - (point >= 0)
    good = ~bad & (digits >= 1) & (digits <= 18)
    if integer:
        good &= point < 0
    return mantissa, scale, digits, good


def _extended_quotient(mantissa: IntArray, scale: IntArray) -> tuple[FloatArray, BoolArray]:
    """m / 10**k rounded to doubles through the extended type, and which are surely correctly rounded."""
    quotient = mantissa.astype(np.longdouble) / np.longdouble(10) ** scale.astype(np.longdouble)
    values = quotient.astype(np.float64)
    rest = np.abs(quotient - values.astype(np.longdouble))
    half = np.spacing(np.abs(values)).astype(np.longdouble) / 2
    return values, (rest != half) & (rest != half / 2)  # not exactly half-way (above or below a power of 2)


class TextTable:
    """The lines and tokens of a text file, found with numpy; positions are byte offsets into the file."""

    def __init__(self, data: bytes, source: str) -> None:
        """Index ``data``: its lines (after joining continued lines), tokens and keywords."""
        self.source = source
        if b"\r" in data:  # keep every offset: CRLF -> " \n", a lone CR -> "\n"
            data = data.replace(b"\r\n", b" \n").replace(b"\r", b"\n")
        joined = b"\\\n" in data
        if joined:  # a continued line: the backslash and break become spaces, offsets kept
            self._physical = np.flatnonzero(np.frombuffer(data, dtype=np.uint8) == 10)
            data = data.replace(b"\\\n", b"  ")
        self.data = data
        self.bytes = np.frombuffer(data, dtype=np.uint8)
        self._joined = joined
        size = len(data)
        newlines = np.flatnonzero(self.bytes == 10)
        self.line_start: IntArray = np.r_[0, newlines + 1].astype(np.int64, copy=False)
        self.line_end: IntArray = np.r_[newlines, size].astype(np.int64, copy=False)
        if size and data.endswith(b"\n"):  # no empty last line after a final break
            self.line_start, self.line_end = self.line_start[:-1], self.line_end[:-1]
        space = SPACE[self.bytes].view(np.int8)  # token edges: where space and non-space meet
        edges = np.flatnonzero(np.diff(space, prepend=np.int8(1), append=np.int8(1)))
        del space
        self.token_start: IntArray = edges[0::2]
        self.token_end: IntArray = edges[1::2]
        del edges
        self.first_token: IntArray = np.searchsorted(self.token_start, self.line_start).astype(np.int64, copy=False)
        self.tokens_per_line: IntArray = np.diff(self.first_token, append=len(self.token_start))
        self.token_line: IntArray = np.repeat(np.arange(len(self.line_start), dtype=np.int64), self.tokens_per_line)
        self.keyword: IntArray = self._codes(self.first_token, self.tokens_per_line > 0)

    @property
    def lines(self) -> int:
        """The number of lines."""
        return len(self.line_start)

    def check_line_length(self, limit: int) -> None:
        """ParseError naming the first line longer than ``limit`` bytes (the limit max_line_chars)."""
        lengths = self.line_end - self.line_start
        long = np.flatnonzero(lengths > limit)
        if len(long):
            raise ParseError(f"a line of {int(lengths[long[0]]):,} bytes, more than the limit max_line_chars="
                             f"{limit:,}", source=self.source, line=self.line_number(int(long[0])))

    def _codes(self, token: IntArray, present: BoolArray) -> IntArray:
        """The packed keyword code of token ``token[i]`` where ``present[i]``, else 0 (and 0 when too long)."""
        codes = np.zeros(len(token), dtype=np.int64)
        chosen = np.flatnonzero(present)
        if len(chosen) == 0:
            return codes
        start = self.token_start[token[chosen]]
        length = self.token_end[token[chosen]] - start
        padded = np.concatenate([self.bytes, np.zeros(KEYWORD_BYTES, dtype=np.uint8)])
        packed = np.lib.stride_tricks.sliding_window_view(padded, KEYWORD_BYTES)[start]
        packed[np.arange(KEYWORD_BYTES) >= length[:, None]] = 0
        values = packed.view("<u8")[:, 0].astype(np.int64, copy=False)
        codes[chosen] = np.where(length <= KEYWORD_BYTES, values, 0)
        return codes

    def second_keyword(self) -> IntArray:
        """Each line's second token as a keyword code (0 where a line has fewer than two tokens)."""
        present = self.tokens_per_line > 1
        return self._codes(np.where(present, self.first_token + 1, 0), present)

    def line_number(self, line: int) -> int:
        """The 1-based line number (as an editor counts) of line index ``line``."""
        if not self._joined:
            return line + 1
        return int(np.searchsorted(self._physical, self.line_start[line])) + 1

    def column(self, token: int) -> int:
        """The 1-based column of token index ``token`` on its line."""
        return int(self.token_start[token] - self.line_start[self.token_line[token]]) + 1

    def token(self, index: int) -> bytes:
        """The bytes of token ``index``."""
        return self.data[self.token_start[index]:self.token_end[index]]

    def line_text(self, line: int) -> bytes:
        """The bytes of line index ``line`` (no line break)."""
        return self.data[self.line_start[line]:self.line_end[line]]

    def error(self, message: str, token: int) -> ParseError:
        """A ParseError at token index ``token``, quoting it."""
        line = int(self.token_line[token])
        return ParseError(message, source=self.source, line=self.line_number(line), column=self.column(token),
                          token=self.token(token))

    def token_text(self, lines: IntArray, skip: int, chars: BoolArray,
                   ) -> tuple[IntArray, IntArray, npt.NDArray[np.uint8], IntArray]:
        """The tokens after the first ``skip`` of ``lines`` whose bytes are all ``chars``, as text.

        Returns (lines kept, their tokens, the file's bytes with everything but those tokens made spaces,
        lines dropped for a byte not in ``chars``).
        """
        dropped = np.zeros(0, dtype=np.int64)
        size = len(self.bytes)
        lines = lines[self.tokens_per_line[lines] > skip]
        if len(lines) == 0:
            return lines, lines, np.zeros(0, dtype=np.uint8), dropped
        for _ in range(2):
            lines = lines[self.tokens_per_line[lines] > skip]
            marks = np.zeros(size + 1, dtype=np.int8)
            marks[self.token_start[self.first_token[lines] + skip]] += 1
            marks[self.line_end[lines]] -= 1
            inside = np.cumsum(marks[:-1], dtype=np.int8).view(np.bool_)
            bad = np.flatnonzero(inside & ~chars[self.bytes])
            if len(bad) == 0:
                break
            dropped = np.unique(np.searchsorted(self.line_start, bad, "right") - 1)
            lines = np.setdiff1d(lines, dropped)
        tokens = ranges(self.first_token[lines] + skip, self.first_token[lines] + self.tokens_per_line[lines])
        text = np.where(inside, self.bytes, np.uint8(32))
        return lines, tokens, text, dropped

    def numbers(self, lines: IntArray, skip: int) -> tuple[IntArray, FloatArray, IntArray, IntArray]:
        """The tokens after the first ``skip`` of ``lines`` as floats, where :func:`parse_float` would read them.

        Returns (lines read, their values, the token index of each value, lines left for the caller to read
        one by one, which names a bad field).  Non-finite values (``1e400``) are returned for the caller to name.
        """
        kept, tokens, text, dropped = self.token_text(lines, skip, _FLOAT_CHARS)
        try:
            values = np.fromstring(text.tobytes(), sep=" ") if len(tokens) else np.zeros(0)
        except ValueError:
            values = None
        if values is None or len(values) != len(tokens):  # "1e", "1.2.3" or "1-2" (read as two numbers)
            return np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0, dtype=np.int64), np.union1d(kept, dropped)
        return kept, values, tokens, dropped

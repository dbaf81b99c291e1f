"""Vectorised tables of a text file's lines and whitespace-separated tokens, for the fast paths of the readers.

A :class:`TextTable` finds every line and token of a file with numpy (no Python loop over lines): line starts
and ends, token starts and ends, the line of each token, and each line's keyword (its first token) packed into
one integer.  :func:`decimals` reads chosen tokens as numbers at once, bit for bit what :func:`parse_float`
reads token by token (it accepts exactly the tokens :data:`NUMBER` matches), so a reader's per-line slow path
and its vectorised fast path agree.  Line breaks are ``\\n``, ``\\r\\n`` or ``\\r``; a line ending in a
backslash continues on the next line (the OBJ rule).  Normalising keeps every byte offset, so columns and line
numbers name the bytes of the file as written.
"""

from __future__ import annotations

import re
from typing import cast

import numpy as np
import numpy.typing as npt

from pixelpen.errors import ParseError

__all__ = ["NUMBER", "TextTable", "decimals", "keyword_code", "parse_float", "plain_numbers", "ranges"]

NUMBER = re.compile(rb"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")
"""A decimal number as the readers accept it (no ``nan``, ``inf``, hex or ``_``); linear, never backtracking."""

KEYWORD_BYTES = 8
"""Keywords up to this many bytes are packed into one integer code."""


_PLAIN = np.full(256, 5, dtype=np.uint8)  # byte classes of plain_numbers: 0 digit, 1 space or LF, 2 "-", 3 "."
_PLAIN[list(b"0123456789")] = 0
_PLAIN[[32, 10]] = 1
_PLAIN[ord("-")] = 2
_PLAIN[ord(".")] = 3
EXTENDED = np.finfo(np.longdouble).nmant >= 63
"""Whether numpy's longdouble holds any 18-digit mantissa exactly (x86 extended or quad precision)."""
_ZEROS, _SIXES, _HIGH_NIBBLES = (np.uint64(int.from_bytes(bytes([b]) * 8, "little")) for b in (0x30, 0x06, 0xF0))
_PAIRS, _QUADS, _LOW32 = np.uint64(0x00FF00FF00FF00FF), np.uint64(0x0000FFFF0000FFFF), np.uint64(0xFFFFFFFF)
"""Constants of the eight-digits-a-word conversion in :func:`_digit_columns`."""
CHUNK = 1 << 16
"""Tokens :func:`decimals` reads at once."""
_MOST_BYTES = 24
"""Longest mantissa read vectorised (its value, less than 10**18, fits in an int64)."""
_TENS = np.cumprod(np.r_[1, np.full(27, 10)].astype(np.longdouble))
"""10**0 .. 10**27, exact in the extended type (5**27 < 2**64)."""

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
    """The tokens ``text[starts[i]:ends[i]]`` as numbers, and whether each is one (``ok``; else its value is 0).

    Floats: a token is one when :data:`NUMBER` matches it, and its value is bit for bit ``float(token)``
    (``1e400`` is inf, for the caller to name).  Integers: ``[+-]`` and at most 18 digits.  Plain tokens
    (digits with at most one point and a value m < 10**18, then maybe an exponent) are read vectorised: in
    buckets of one length, digit column by digit column; then m·10**j is one correctly rounded operation
    when m < 2**53 and |j| <= 22 (both exact doubles), else one in 64-bit extended precision rounded to a
    double, which is correct unless the extended result lies exactly half-way between two doubles.  Those
    few, and tokens of other forms, go through ``float`` one by one.  Tokens are read in chunks of CHUNK
    (the work arrays of one chunk stay in the processor's cache: several times faster than whole arrays).
    """
    if len(starts) > CHUNK:
        parts = [decimals(text, starts[k:k + CHUNK], ends[k:k + CHUNK], integer)
                 for k in range(0, len(starts), CHUNK)]
        return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
    if len(starts) == 0:
        return (np.zeros(0, dtype=np.int64) if integer else np.zeros(0)), np.zeros(0, dtype=bool)
    lead = np.where(ends > starts, text[np.minimum(starts, len(text) - 1)], 0)  # (an empty token has none)
    negative = lead == ord("-")
    first = starts + (negative | (lead == ord("+")))
    mantissa, scale, ok = _parts(text, first, ends - first, integer)
    if integer:
        return np.where(negative, -mantissa, mantissa), ok
    power = -scale
    odd = np.flatnonzero(~ok & (ends - first <= _MOST_BYTES + 8))
    if len(odd):  # a mantissa and an exponent
        split, at = _exponent_at(text, first[odd], ends[odd])
        split = odd[split]
        mantissa[split], scale, ok[split] = _parts(text, first[split], at - first[split], False)
        sign = text[at + 1]
        exponent = at + 1 + ((sign == ord("-")) | (sign == ord("+")))
        value, _, good = _parts(text, exponent, ends[split] - exponent, True)
        power[split] = np.where(sign == ord("-"), -value, value) - scale
        ok[split] &= good
    quick = ok & (mantissa < 2**53) & (np.abs(power) <= 22)
    values = np.zeros(len(starts), dtype=np.float64)
    if quick.all() and not power.any():  # the common case: no exponent, no extended
        values = mantissa / 10.0 ** scale
    else:
        up = np.where(quick & (power > 0), power, 0)
        down = np.where(quick & (power < 0), -power, 0)
        values[quick] = (mantissa * 10.0 ** up / 10.0 ** down)[quick]  # one of the two is 10**0
    extended = np.flatnonzero(ok & ~quick & (np.abs(power) <= 27)) if EXTENDED else np.zeros(0, dtype=np.int64)
    values[extended], exact = _extended(mantissa[extended], power[extended])
    done = quick.copy()
    done[extended[exact]] = True
    values[negative] = -values[negative]
    for k in np.flatnonzero(~done).tolist():  # half-way, long, or not plain: one by one
        token = text[starts[k]:ends[k]].tobytes()
        ok[k] = NUMBER.fullmatch(token) is not None
        values[k] = float(token) if ok[k] else 0.0
    return values, ok


def _parts(text: npt.NDArray[np.uint8], first: IntArray, length: IntArray, integer: bool,
           ) -> tuple[IntArray, IntArray, BoolArray]:
    """(mantissa, digits after the point, plain) of the tokens ``text[first:first + length]``."""
    mantissa = np.zeros(len(first), dtype=np.int64)
    scale = np.zeros(len(first), dtype=np.int64)
    ok = np.zeros(len(first), dtype=bool)
    limit = 18 if integer else _MOST_BYTES
    bucket = np.clip(length, 0, limit + 1).astype(np.uint8)
    order = np.argsort(bucket, kind="stable")  # (a radix sort of bytes)
    edges = np.r_[0, np.cumsum(np.bincount(bucket, minlength=limit + 2))]
    for width in range(1, limit + 1):
        chosen = order[edges[width]:edges[width + 1]]
        if len(chosen):
            mantissa[chosen], scale[chosen], ok[chosen] = _digit_columns(text, first[chosen], width, integer)
    return mantissa, scale, ok


def _digit_columns(text: npt.NDArray[np.uint8], first: IntArray, width: int, integer: bool,
                   ) -> tuple[IntArray, IntArray, BoolArray]:
    """(mantissa, digits after the point, plain) of the ``width``-byte tokens starting at ``first``.

    The tokens are read right-aligned into rows of 8·g bytes (the bytes before a token made ``0``), the point
    made a 0 digit, each 64-bit word of eight digits checked and combined within the word (two digits in 16
    bits, four in 32, eight in 64), and the point's 0 taken out of the mantissa by one division.
    """
    size = 8 * -(-width // 8)
    block = byte_block(text, first + width - size, size)
    block[:, :size - width] = ord("0")
    flat = block.reshape(-1)
    points = np.flatnonzero(flat == ord("."))
    row, column = np.divmod(points, size)
    has_point = np.zeros(len(first), dtype=bool)
    has_point[row] = True
    flat[points] = ord("0")
    bad = np.zeros(len(first), dtype=bool)
    bad[row[1:][row[1:] == row[:-1]]] = True  # two points
    scale = np.zeros(len(first), dtype=np.int64)
    scale[row] = size - 1 - column
    words = block.view("<u8")  # eight digits a word, the first in the lowest byte
    eights = np.empty(words.shape, dtype=np.int64)
    for k in range(size // 8):
        word = words[:, k]
        bad |= ((word & _HIGH_NIBBLES) != _ZEROS) | (((word + _SIXES) & _HIGH_NIBBLES) != _ZEROS)  # a non-digit
        value = word - _ZEROS
        value = (value * np.uint64(10) + (value >> np.uint64(8))) & _PAIRS  # d0·10 + d1 in each 16 bits
        value = (value * np.uint64(100) + (value >> np.uint64(16))) & _QUADS
        eights[:, k] = ((value * np.uint64(10_000) + (value >> np.uint64(32))) & _LOW32).view(np.int64)
    low = eights[:, -1] + (eights[:, -2] * 10**8 if size > 8 else 0)  # the last 16 digits
    high = eights[:, 0] if size > 16 else np.zeros(len(first), dtype=np.int64)
    if len(points) == 0:  # integers
        good = ~bad & (high < 100)  # m < 10**18
        return np.where(good, high * 10**16 + low, 0), scale, good
    # the point's 0 is digit ``scale`` from the right: in the last 16 (low) or in the first 8 (high)
    cut = 10 ** np.minimum(scale, 15)
    in_low = high * 10**15 + (low // (cut * 10)) * cut + low % cut
    above = 10 ** np.clip(scale - 15, 1, 8)
    joined = (high // above) * (above // 10) + high % (above // 10)  # the high digits without the point's 0
    mantissa = np.where(~has_point, high * 10**16 + low, np.where(scale < 16, in_low, joined * 10**16 + low))
    limit = np.where(~has_point, high >= 100, np.where(scale < 16, high >= 1000, joined >= 100))  # m >= 10**18
    bad |= limit
    good = ~bad & (width - has_point >= 1)
    if integer:
        good &= ~has_point
    return np.where(good, mantissa, 0), scale, good


def byte_block(text: npt.NDArray[np.uint8], start: IntArray, size: int) -> npt.NDArray[np.uint8]:
    """The bytes ``text[start[i]:start[i] + size]`` as rows of a new (n, size) array, size a multiple of 8.

    Bytes before the start or past the end of ``text`` are 0.  Read eight at a time: one gather of unaligned
    64-bit words per eight columns.
    """
    count = size // 8
    margin = size + 8
    padded = np.zeros(len(text) + 2 * margin, dtype=np.uint8) if len(text) < 4 * margin else None
    if padded is not None:  # a short text: read from a padded copy
        padded[margin:margin + len(text)] = text
        text, start = padded, start + margin
    out = np.zeros((len(start), count), dtype="<u8")
    words = np.ndarray((len(text) - 7,), dtype="<u8", buffer=text, strides=(1,))
    head = np.zeros(2 * margin, dtype=np.uint8)
    head[margin:] = text[:margin]
    tail = np.zeros(2 * margin, dtype=np.uint8)
    tail[:margin] = text[len(text) - margin:]
    ends = {"head": (head, -margin), "tail": (tail, len(text) - margin)}
    early, late = start < 0, start + size > len(text)
    for k in range(count):
        out[:, k] = words[np.clip(start + 8 * k, 0, len(text) - 8)]
    for chosen, (copy, origin) in ((early, ends["head"]), (late, ends["tail"])):
        if chosen.any():  # rows reaching past either end of the text: from a padded copy of that end
            copy_words = np.ndarray((len(copy) - 7,), dtype="<u8", buffer=copy, strides=(1,))
            for k in range(count):
                out[chosen, k] = copy_words[start[chosen] - origin + 8 * k]
    return out.view(np.uint8)


def _exponent_at(text: npt.NDArray[np.uint8], first: IntArray, ends: IntArray) -> tuple[IntArray, IntArray]:
    """Which of the tokens ``text[first:ends]`` hold an ``e`` or ``E`` after their first byte, and where."""
    at = np.full(len(first), -1, dtype=np.int64)
    last = len(text) - 1
    for column in range(1, int((ends - first).max()) - 1):
        place = first + column
        hit = (place < ends - 1) & (at < 0) & ((text[np.minimum(place, last)] | np.uint8(32)) == ord("e"))
        at[hit] = place[hit]
    split = np.flatnonzero(at >= 0)
    return split, at[split]


def _extended(mantissa: IntArray, power: IntArray) -> tuple[FloatArray, BoolArray]:
    """m·10**j rounded to doubles through the extended type (10**27 is exact), and which are surely right."""
    ten = _TENS[np.abs(power)]
    wide = mantissa.astype(np.longdouble)
    result = np.where(power >= 0, wide * ten, wide / ten)
    values = result.astype(np.float64)
    rest = np.abs(result - values.astype(np.longdouble))
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
        text = self.bytes  # token edges: where space (" \t\n\v\f\r") and non-space meet
        space = text <= 32  # the exact test when every control byte is a space (counted)
        spaces = sum(data.count(b) for b in (b"\t", b"\v", b"\f") if b in data)  # (CR are gone)
        if np.count_nonzero(text < 32) != len(newlines) + spaces:
            space = (text == 32) | ((text >= 9) & (text <= 13))
        edges = np.flatnonzero(space[1:] != space[:-1]) + 1
        head, tail = [0] if size and not space[0] else [], [size] if size and not space[-1] else []
        del space
        if head or tail:
            edges = np.concatenate([np.array(head, dtype=np.int64), edges, np.array(tail, dtype=np.int64)])
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
        packed = byte_block(self.bytes, start, KEYWORD_BYTES).view("<u8")[:, 0]
        keep = np.left_shift(np.uint64(1), (8 * np.minimum(length, 7)).astype(np.uint64)) - np.uint64(1)
        packed &= np.where(length >= KEYWORD_BYTES, ~np.uint64(0), keep)  # the bytes of the token only
        codes[chosen] = np.where(length <= KEYWORD_BYTES, packed.view(np.int64), 0)
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

    def field(self, token: int) -> int:
        """Token index ``token``'s place on its line (0: the keyword)."""
        return int(token - self.first_token[self.token_line[token]])

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

    def numbers(self, lines: IntArray, skip: int) -> tuple[IntArray, FloatArray, IntArray, IntArray]:
        """The tokens after the first ``skip`` of ``lines`` as floats, where :func:`parse_float` would read them.

        Returns (lines read, their values, the token index of each value, lines left for the caller to read
        one by one, which names a bad field).  Non-finite values (``1e400``) are returned for the caller to name.
        """
        lines = lines[self.tokens_per_line[lines] > skip]
        first = self.first_token[lines]
        tokens = ranges(first + skip, first + self.tokens_per_line[lines])
        numbers, ok = decimals(self.bytes, self.token_start[tokens], self.token_end[tokens])
        values = cast(FloatArray, numbers)
        if ok.all():
            return lines, values, tokens, np.zeros(0, dtype=np.int64)
        dropped: IntArray = np.unique(self.token_line[tokens[~ok]])
        kept = ~np.isin(self.token_line[tokens], dropped)
        return np.setdiff1d(lines, dropped).astype(np.int64), values[kept], tokens[kept], dropped

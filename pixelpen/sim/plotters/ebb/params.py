"""EiBotBoard command-line parsing: parameter types, the !4-!10 error texts, checksums, firmware versions.

Written from evil-mad/EggBot ``docs/ebb.html`` (firmware v3.0+: "Returned Errors", ``CU,54``) and
``docs/ebb2.html`` for the 2.x wording.  A command is ``NAME[,param...]``: one or two characters,
case-insensitive, then comma-separated parameters whose types and ranges the command reference gives.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["EbbError", "ParamSpec", "checksum", "error_text", "parse_params", "parse_version", "split_name"]


class EbbError(Exception):
    """A parse error the board reports: its number and its text (without line ending)."""

    def __init__(self, code: int, text: str) -> None:
        super().__init__(text)
        self.code = code
        self.text = text


_RANGES = {
    "u1": (0, 1), "u2": (0, 3), "u3": (0, 7), "u8": (0, 255), "i8": (-128, 127), "u16": (0, 65535),
    "i16": (-32768, 32767), "u32": (0, 4294967295), "i32": (-2147483648, 2147483647),
    "u5": (0, 5), "u10": (0, 1023), "u24": (0, 24), "u31": (0, 31), "u4095": (0, 4095),
}


@dataclass(frozen=True)
class ParamSpec:
    """One parameter: its type (a key of the integer ranges, 'char', 'uchar', 'port' or 'text')."""

    kind: str
    required: bool = True


def error_text(code: int, fw3: bool, detail: str = "") -> str:
    """The documented text of error ``code`` (2.x firmware spells two of them differently)."""
    if code == 4:
        return "!4 Err: Missing parameter(s)"
    if code == 5:
        return f"!5 Err: Need comma next, found: '{detail}'"
    if code == 6:
        return "!6 Err: Invalid parameter value" if fw3 else "!6 Err: Invalid paramter value"
    if code == 7:
        return "!7 Err: Extra parameter" if fw3 else "!7 Err: Extra parmater"
    if code == 3:
        return "!3 Err: RX Buffer overrun"
    raise ValueError(f"no fixed text for EBB error {code}")


def split_name(line: str) -> tuple[str, str]:
    """The command name (one or two characters, upper-cased) and the rest of the line.

    The firmware takes the second character unless it is a comma (or the end of the line).
    """
    if not line:
        return "", ""
    if len(line) >= 2 and line[1] != ",":
        return line[:2].upper(), line[2:]
    return line[:1].upper(), line[1:]


def parse_params(rest: str, specs: tuple[ParamSpec, ...], fw3: bool) -> list[object]:
    """Parse ``rest`` (what follows the command name) against ``specs``; raises EbbError(4..7).

    Missing optional parameters come back as None.  Rules of the firmware's extract_number: a
    required parameter needs a comma (!5, naming what was found instead) and a value (!4 at the end of
    the line); a value must be of its type and range (!6); anything left over is an extra parameter (!7).
    """
    pos = 0
    n = len(rest)
    values: list[object] = []
    for spec in specs:
        if pos >= n:
            if spec.required:
                raise EbbError(4, error_text(4, fw3))
            values.append(None)
            continue
        if rest[pos] != ",":
            if spec.required:
                raise EbbError(5, error_text(5, fw3, rest[pos]))
            raise EbbError(7, error_text(7, fw3))
        pos += 1
        if pos >= n:
            if spec.required:
                raise EbbError(4, error_text(4, fw3))
            values.append(None)
            continue
        value, pos = _value(rest, pos, spec.kind, fw3)
        values.append(value)
    if pos < n:
        raise EbbError(7, error_text(7, fw3))
    return values


def _value(rest: str, pos: int, kind: str, fw3: bool) -> tuple[object, int]:
    if kind == "text":
        end = rest.find(",", pos)
        end = len(rest) if end < 0 else end
        return rest[pos:end], end
    if kind in ("char", "uchar", "port"):
        c = rest[pos]
        if kind == "port":
            c = c.upper()
            if c not in "ABCDE":
                raise EbbError(6, error_text(6, fw3))
        return (c.upper() if kind == "uchar" else c), pos + 1
    lo, hi = _RANGES[kind]
    start = pos
    if pos < len(rest) and rest[pos] in "+-":
        pos += 1
    digits_start = pos
    while pos < len(rest) and rest[pos].isdigit() and rest[pos].isascii():
        pos += 1
    if pos == digits_start:
        raise EbbError(6, error_text(6, fw3))
    value = int(rest[start:pos])
    if not lo <= value <= hi:
        raise EbbError(6, error_text(6, fw3))
    return value, pos


def ascii_digits(text: str) -> bool:
    """True when ``text`` is one or more ASCII digits 0-9 (``str.isdigit`` also accepts '²' and other scripts)."""
    return bool(text) and text.isascii() and text.isdigit()


def checksum(text: str) -> int:
    """The CU,54 checksum: 0x100 minus the byte sum, modulo 256 (8-bit two's complement)."""
    return (-sum(text.encode("latin-1", "replace"))) & 0xFF


def parse_version(text: str) -> tuple[int, int, int]:
    """Read a firmware version like ``3.0.2`` into a comparable tuple."""
    parts = text.strip().split(".")
    if len(parts) != 3 or not all(ascii_digits(p) for p in parts):
        raise ValueError(f"firmware version must look like 3.0.2, got {text!r}")
    return (int(parts[0]), int(parts[1]), int(parts[2]))

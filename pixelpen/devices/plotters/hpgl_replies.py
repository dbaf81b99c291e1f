"""HP-GL plotter answers: the error tables, the forms answers take (OA, a number, an OI name), cleaning a line."""

from __future__ import annotations

import re

HPGL_ERRORS: dict[int, str] = {
    0: "no error",
    1: "instruction not recognised",
    2: "wrong number of parameters",
    3: "bad parameter value",
    5: "unknown character set",
    6: "position overflow",
    8: "vector received while the pinch wheels are raised",
}
"""OE error numbers (plotters.md §1.4)."""
IO_ERRORS: dict[int, str] = {
    0: "no error",
    10: "output instruction received while another output was in progress",
    11: "invalid byte after ESC .",
    12: "invalid byte inside a device-control instruction",
    13: "device-control parameter out of range",
    14: "too many device-control parameters",
    15: "framing, parity or overrun error",
    16: "input buffer overflow",
}
"""ESC.E RS-232 error numbers (plotters.md §1.4)."""
BYTES_LOST = frozenset({15, 16})
"""ESC.E errors that lose received bytes (framing/overrun, buffer overflow); 11..14 concern device control only."""
ERROR_OUTPUT_BUSY = 10
"""ESC.E 10: an output request came while an answer went out and was ignored (a link hiccup, not a drawing error)."""
STATUS_VIEW = 16
STATUS_PAPER_LEVER = 32
"""ESC.O bits that mean the plotter pauses on the operator's word (plotters.md §1.4)."""
MAX_REPLY = 256
"""Longest answer line (bytes) before it counts as garbage."""
MAX_OE = 31
"""Largest number taken as an OE answer (HP-GL/1 error numbers are 0..8)."""
OA_ANSWER = re.compile(r"\s*-?\d+\s*,\s*-?\d+\s*,\s*\d+\s*")
NUMBER_ANSWER = re.compile(r"\s*-?\d+\s*")
IDENT_ANSWER = re.compile(r"[0-9A-Za-z][0-9A-Za-z\- ]*")
_STRIP = bytes((0x00, 0x0A, 0x11, 0x13))  # NUL, LF, XON, XOFF never belong to an answer


def clean(line: bytes) -> str:
    """An answer line as text, without NUL, LF, XON and XOFF."""
    return line.translate(None, _STRIP).decode("ascii", "replace").strip()


def is_marker(marker: str, text: str) -> bool:
    """True when ``text`` is an answer of the form ``marker`` asks for: OA (x,y,pen) or OI (a model name)."""
    if marker == "OA":
        return OA_ANSWER.fullmatch(text) is not None
    return IDENT_ANSWER.fullmatch(text) is not None and not NUMBER_ANSWER.fullmatch(text)


def describe_instructions(instructions: list[bytes], limit: int = 200) -> str:
    """Instructions as text for an error message, cut after ``limit`` characters."""
    text = b"".join(instructions).decode("ascii", "replace")
    return text if len(text) <= limit else f"{text[:limit]}... (+{len(text) - limit} characters)"

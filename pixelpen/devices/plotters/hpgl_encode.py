"""HP-GL/1 as HP 7475A-class plotters read it: pure functions from strokes and settings to exact bytes.

Instructions (7470A Interfacing and Programming Manual ch. 2-3; plotters.md §1.3) are a two-letter
mnemonic, integer parameters separated by commas, and a ``;``.  Everything here is absolute (``PA``
is the state after ``IN``): a stroke is ``PUx,y;PDx1,y1,x2,y2,...;`` with long ``PD`` lists split so
that no instruction exceeds ``max_length`` bytes, a single-point stroke is the zero-length vector
``PUx,y;PDx,y;`` (a dot).  Coordinates are whole plotter units within -32768..32767.

Device control (manual ch. 10) is ``ESC . letter`` with ``;``-separated parameters ended by ``:``;
the plotter acts on it when it arrives, outside the HP-GL buffer.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Final

import numpy as np

from pixelpen.errors import ConfigError
from pixelpen.vector.displaylist import DisplayList

COORD_MIN: Final = -32768
COORD_MAX: Final = 32767
"""HP-GL/1 parameter range (7470A manual, PA; plotters.md §1.1)."""
MAX_INSTRUCTION: Final = 120
"""Default longest instruction in bytes: far inside any plotter's buffer and the flow-control reserve."""
_MIN_INSTRUCTION = len("PD-32768,-32768;")

ESC: Final = b"\x1b"
PLOTTER_ON: Final = b"\x1b.("
"""ESC.( : plotter on (it ignores everything but this after ESC.) )."""
ABORT_GRAPHICS: Final = b"\x1b.K"
"""ESC.K : discard the buffered HP-GL (the vector being drawn finishes)."""
ASK_FREE: Final = b"\x1b.B"
"""ESC.B : free buffer bytes, answered at once."""
ASK_IO_ERROR: Final = b"\x1b.E"
"""ESC.E : the RS-232 error number (cleared by reading it), answered at once."""
ASK_STATUS: Final = b"\x1b.O"
"""ESC.O : extended status (8 buffer empty, 16 VIEW pressed, 32 paper lever raised), answered at once."""

SYNC_REQUEST: Final = b"OA;OE;"
"""Buffered output requests answered when execution reaches them: pen position, then the HP-GL error."""
IDENTIFY_REQUEST: Final = b"OS;OI;OE;"
"""Buffered status (read to clear its 'initialised' bit 8, set by IN), model identification (a 7475A answers
OI only after IN), then the HP-GL error."""
WHERE_REQUEST: Final = b"OS;OA;"
"""Status (bit 8: switched on or initialised since the last OS) and actual pen position after a fault."""
STATUS_INITIALISED: Final = 8
"""OS bit: the plotter was switched on or got IN since the last OS (plotters.md §1.4)."""
PEN_UP: Final = b"PU;"

HANDSHAKES: Final = ("escb", "xonxoff", "hardwire", "none")
_HANDSHAKE_SETUP: Final = {
    "escb": b"",
    "none": b"",
    # Xon/Xoff threshold 81 free bytes, no ENQ, Xon = DC1 (17); no intercharacter delay, Xoff = DC3 (19)
    "xonxoff": b"\x1b.I81;;17:\x1b.N;19:",
    # configuration byte bit 0: hardwire handshake (the plotter holds DTR low while its buffer is full)
    "hardwire": b"\x1b.@;1:",
}


def handshake_preamble(handshake: str) -> bytes:
    """Device control that switches the plotter on and sets up ``handshake`` (plotters.md §1.5)."""
    if handshake not in _HANDSHAKE_SETUP:
        raise ConfigError(f"handshake must be one of {', '.join(HANDSHAKES)}, got {handshake!r}")
    return PLOTTER_ON + b";" + _HANDSHAKE_SETUP[handshake]


def format_number(value: float) -> str:
    """An HP-GL decimal parameter: an integer when whole, else at most 2 decimals (``10``, ``12.5``)."""
    if not math.isfinite(value):
        raise ConfigError(f"HP-GL parameters must be finite numbers, got {value!r}")
    if float(value).is_integer():
        return str(int(value))
    return f"{value:.2f}".rstrip("0").rstrip(".")


def initialize(paper_size: int | None = None, velocity_cm_s: float | None = None) -> list[bytes]:
    """``IN;`` then optional ``PSn;`` (paper size) and ``VSv;`` (pen-down velocity, cm/s); IP/SC stay default."""
    out = [b"IN;"]
    if paper_size is not None:
        if not isinstance(paper_size, int) or isinstance(paper_size, bool) or paper_size < 0:
            raise ConfigError(f"PS takes a paper-size number >= 0, got {paper_size!r}")
        out.append(b"PS%d;" % paper_size)
    if velocity_cm_s is not None:
        out.append(velocity(velocity_cm_s))
    return out


def velocity(cm_s: float) -> bytes:
    """``VSv;``: pen-down velocity in cm/s for every pen."""
    if not (isinstance(cm_s, (int, float)) and math.isfinite(cm_s) and cm_s > 0):
        raise ConfigError(f"VS takes a velocity in cm/s > 0, got {cm_s!r}")
    return f"VS{format_number(cm_s)};".encode("ascii")


def select_pen(pen: int) -> bytes:
    """``SPn;``: take pen ``n`` from the carousel (0 puts the pen back)."""
    if not isinstance(pen, (int, np.integer)) or isinstance(pen, bool) or not 0 <= pen <= COORD_MAX:
        raise ConfigError(f"SP takes a pen number 0..{COORD_MAX}, got {pen!r}")
    return b"SP%d;" % int(pen)


def trailer(park: tuple[int, int] | None = None) -> list[bytes]:
    """End of a job: ``PU;SP0;`` (pen up, pen back in the carousel), then ``PUx,y;`` to the park position."""
    out = [PEN_UP, b"SP0;"]
    if park is not None:
        (x, y), = _whole_points(np.asarray([park]), "park position")
        out.append(b"PU%d,%d;" % (x, y))
    return out


def stroke(points: np.ndarray, *, index: int | None = None, max_length: int = MAX_INSTRUCTION) -> list[bytes]:
    """One stroke as absolute instructions: ``PUx0,y0;`` then ``PD`` lists of at most ``max_length`` bytes each.

    ``points`` is (N, 2) in whole plotter units; ``index`` names the stroke in errors.
    """
    if not isinstance(max_length, int) or max_length < _MIN_INSTRUCTION:
        raise ConfigError(f"max_length must be an integer >= {_MIN_INSTRUCTION} bytes, got {max_length!r}")
    what = "stroke" if index is None else f"stroke {index}"
    pts = _whole_points(points, what)
    if not len(pts):
        raise ConfigError(f"{what} has no points")
    head = b"PU%d,%d;" % (pts[0, 0], pts[0, 1])
    rest = pts[1:] if len(pts) > 1 else pts
    pairs = np.char.add(np.char.add(rest[:, 0].astype(str), ","), rest[:, 1].astype(str))
    # instruction = "PD" + pairs joined by "," + ";": each pair costs its length plus one separator byte
    cost = np.concatenate([[0], np.cumsum(np.char.str_len(pairs) + 1)])
    budget = max_length - 2
    out = [head]
    i = 0
    while i < len(pairs):
        j = int(np.searchsorted(cost, cost[i] + budget, side="right")) - 1
        out.append(b"PD" + ",".join(pairs[i:j].tolist()).encode("ascii") + b";")
        i = j
    return out


def program(
    dl: DisplayList,
    *,
    paper_size: int | None = None,
    velocity_cm_s: float | None = None,
    park: tuple[int, int] | None = None,
    max_length: int = MAX_INSTRUCTION,
) -> bytes:
    """A whole HP-GL file for a display list in whole plotter units: init, pens as needed, strokes, trailer."""
    out: list[bytes] = initialize(paper_size, velocity_cm_s)
    pen = None
    for i, pts in enumerate(dl.strokes()):
        if int(dl.pens[i]) != pen:
            pen = int(dl.pens[i])
            out.append(select_pen(pen))
        out += stroke(pts, index=i, max_length=max_length)
    out += trailer(park)
    return b"".join(out)


def _whole_points(points: Iterable, what: str) -> np.ndarray:
    """Points as (N, 2) int64, refusing non-finite, fractional or out-of-range values and naming the first."""
    arr = np.asarray(points)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ConfigError(f"{what}: expected (N, 2) points, got shape {arr.shape}")
    if arr.dtype.kind in "iu":
        bad_value = np.zeros(len(arr), dtype=bool)
    elif arr.dtype.kind == "f":
        bad_value = ~np.all(np.isfinite(arr) & (arr == np.round(arr)), axis=1)
    else:
        raise ConfigError(f"{what}: points must be numbers, got dtype {arr.dtype}")
    if bad_value.any():
        k = int(np.argmax(bad_value))
        raise ConfigError(f"{what}: point {k} ({arr[k, 0]}, {arr[k, 1]}) is not a whole number of plotter units")
    out_of_range = np.any((arr < COORD_MIN) | (arr > COORD_MAX), axis=1)
    if out_of_range.any():
        k = int(np.argmax(out_of_range))
        raise ConfigError(
            f"{what}: point {k} ({arr[k, 0]:g}, {arr[k, 1]:g}) is outside the HP-GL range {COORD_MIN}..{COORD_MAX}"
        )
    return arr.astype(np.int64)

"""The plot state file (version 2): what a later session needs to resume a plot, saved after every confirmation."""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from pixelpen.errors import ParseError
from pixelpen.vector.displaylist import DisplayList

STATE_VERSION = 2
_STATE_VERSIONS = (1, 2)
"""State file versions read (version 1 lacks ``sent`` and ``position_lost``)."""



def fingerprint(dl: DisplayList) -> str:
    """A hash of a display list's strokes and pens, to tell a state file's drawing from another."""
    h = hashlib.sha256()
    for arr in (np.round(dl.points, 6), dl.offsets, dl.pens):
        h.update(np.ascontiguousarray(arr).tobytes())
    return h.hexdigest()[:32]


@dataclass
class PlotState:
    """The resumable state of a plot, saved as JSON after every confirmation."""

    url: str
    fingerprint: str
    strokes: int
    confirmed: int
    sent: int | None = None
    """One past the last stroke whose bytes went out (None: unknown, every unconfirmed stroke is in doubt)."""
    position_lost: bool = False
    """The device said it lost its position; a resume needs ``position_confirmed``."""
    damaged: list[int] | None = None
    """[start, stop) of strokes the device reported it did not draw as sent; a resume draws them again."""
    missing: list[list[int]] | None = None
    """[stroke, x0, y0, x1, y1, ...]: pieces of strokes the device skipped; a resume draws them first."""
    reached: list[float] | None = None
    """[stroke, vertex(, x, y)]: the last point of the job the device acknowledged reaching (x, y: inside the
    segment after the vertex, where a resume had started); None: none since the last confirmation."""
    written: list[float] | None = None
    """[stroke, vertex(, x, y)]: the furthest place the bytes sent in the last run can draw to (None: unknown)."""
    lifts: list[int] | None = None
    """Unconfirmed strokes after which the pen was lifted in place (None: unknown)."""
    stopped_at: list[float] | None = None
    """[x, y, pen down 1/0/-1 unknown, tolerance(, held 1/0)]: where the device stopped, asked before the safe stop
    parked it (held: a hold stopped it mid-instruction, see DeviceWhere.held)."""
    start: list[float] | None = None
    """[stroke, x, y]: the pen position before that stroke's travel, the first stroke of the run (None: unknown)."""
    version: int = STATE_VERSION

    def save(self, path: Path) -> None:
        """Write the state atomically (temp file + rename), so a crash never leaves half a file."""
        tmp = path.with_name(path.name + ".tmp")
        with open(tmp, "w", encoding="utf-8") as fh:
            json.dump(asdict(self), fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)

    @classmethod
    def load(cls, path: Path) -> PlotState:
        """Read a state file; a ParseError names the file and the field that is wrong."""
        try:
            raw = Path(path).read_bytes()
        except OSError as exc:
            raise ParseError(f"cannot read plot state: {exc.strerror}", source=str(path)) from None
        try:
            data = json.loads(raw.decode("utf-8"))
        except UnicodeDecodeError as exc:
            raise ParseError(f"plot state is not UTF-8 text ({exc.reason})", source=str(path),
                             offset=exc.start) from None
        except json.JSONDecodeError as exc:
            raise ParseError(f"plot state is not JSON: {exc.msg}", source=str(path), line=exc.lineno,
                             column=exc.colno) from None
        except (RecursionError, ValueError) as exc:  # nesting too deep; an integer past Python's digit limit
            raise ParseError(f"plot state is not readable JSON: {type(exc).__name__}: {exc}"[:200],
                             source=str(path)) from None
        if not isinstance(data, dict) or data.get("version") not in _STATE_VERSIONS:
            raise ParseError(f"not a version-{STATE_VERSION} pixelpen plot state", source=str(path))
        try:
            state = cls(**{**data, "version": STATE_VERSION})
        except TypeError as exc:
            raise ParseError(f"plot state has wrong fields: {exc}", source=str(path)) from None
        if not (isinstance(state.strokes, int) and isinstance(state.confirmed, int)
                and 0 <= state.confirmed <= state.strokes):
            raise ParseError("plot state field 'confirmed' is out of range", source=str(path), token=state.confirmed)
        if state.sent is not None and not (
                isinstance(state.sent, int) and state.confirmed <= state.sent <= state.strokes):
            raise ParseError("plot state field 'sent' is out of range", source=str(path), token=state.sent)
        if state.damaged is not None and not (
            isinstance(state.damaged, list) and len(state.damaged) == 2
            and all(isinstance(v, int) for v in state.damaged)
            and 0 <= state.damaged[0] <= state.damaged[1] <= state.strokes
        ):
            raise ParseError("plot state field 'damaged' is not a [start, stop] stroke range", source=str(path),
                             token=state.damaged)
        if state.missing is not None and not (
            isinstance(state.missing, list) and all(
                isinstance(m, list) and len(m) >= 3 and len(m) % 2 == 1
                and all(isinstance(v, int) and not isinstance(v, bool) for v in m) and 0 <= m[0] < state.strokes
                for m in state.missing)
        ):
            raise ParseError("plot state field 'missing' is not a list of [stroke, x0, y0, ...]", source=str(path),
                             token=state.missing)
        for name in ("reached", "written"):
            place = getattr(state, name)
            if place is not None and not (
                isinstance(place, list) and len(place) in (2, 4)
                and all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in place[:2])
                and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                        for v in place[2:])
                and place[0] < state.strokes
            ):
                raise ParseError(f"plot state field {name!r} is not [stroke, vertex(, x, y)]", source=str(path),
                                 token=place)
        if state.lifts is not None and not (
            isinstance(state.lifts, list) and all(isinstance(v, int) and 0 <= v < state.strokes for v in state.lifts)
        ):
            raise ParseError("plot state field 'lifts' is not a list of stroke numbers", source=str(path),
                             token=state.lifts)
        if state.stopped_at is not None and not (
            isinstance(state.stopped_at, list) and len(state.stopped_at) in (4, 5)
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                    for v in state.stopped_at)
            and state.stopped_at[2] in (-1, 0, 1) and state.stopped_at[3] >= 0
            and state.stopped_at[4:] in ([], [0], [1])
        ):
            raise ParseError("plot state field 'stopped_at' is not [x, y, pen -1/0/1, tolerance(, held 0/1)]",
                             source=str(path),
                             token=state.stopped_at)
        if state.start is not None and not (
            isinstance(state.start, list) and len(state.start) == 3
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in state.start)
            and isinstance(state.start[0], int) and 0 <= state.start[0] <= state.strokes
        ):
            raise ParseError("plot state field 'start' is not [stroke, x, y]", source=str(path), token=state.start)
        if not isinstance(state.position_lost, bool):
            raise ParseError("plot state field 'position_lost' is not true or false", source=str(path),
                             token=state.position_lost)
        return state



def unfinished(path: Path) -> bool:
    """True when ``path`` holds the state of a job that did not finish (a resume may follow: ask the device first)."""
    if not path.exists():
        return False
    try:
        state = PlotState.load(path)
    except ParseError:
        return False  # plot(resume=True) reports it
    return state.confirmed < state.strokes or bool(state.missing)

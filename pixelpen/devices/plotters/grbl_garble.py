"""Which GRBL line lost a byte on the wire, and what it drew instead (:func:`explain_position`, :class:`Garble`).

GRBL has no line checksum and drops a byte >= 0x80 as an unknown real-time command, so a garbled line is the
line sent with one character missing (:func:`garbled_variants`).  The driver records each motion line it sends
(:class:`SentLeg`); a status report off the path is explained by the first of them whose variant puts the pen
there, and the resume draws from where that line left its leg.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pixelpen.devices.plotters.resume import near_segment

__all__ = ["Garble", "SentLeg", "explain_position", "garbled_variants", "words_of"]


@dataclass(frozen=True)
class SentLeg:
    """One motion line sent in a plot: it moves from ``start`` to ``end`` (device units) with the pen ``down``.

    ``stroke``/``vertex`` say what it reaches (vertex None: the travel to the stroke's first point); ``line`` is
    the G-code as sent.
    """

    stroke: int
    vertex: int | None
    line: str
    start: tuple[float, float]
    end: tuple[float, float]
    down: bool


_WORD = re.compile(r"([A-Z])(-?(?:[0-9]+\.?[0-9]*|\.[0-9]+))")


def words_of(line: str) -> dict[str, list[float]] | None:
    """The words of a G-code line as GRBL reads them (spaces ignored), None when GRBL would reject its syntax."""
    text = line.replace(" ", "")
    out: dict[str, list[float]] = {}
    pos = 0
    for m in _WORD.finditer(text):
        if m.start() != pos:
            return None
        out.setdefault(m[1], []).append(float(m[2]))
        pos = m.end()
    if pos != len(text) or any(len(v) > 1 for k, v in out.items() if k not in "GM"):
        return None
    return out


def garbled_variants(line: str) -> list[dict[str, list[float]]]:
    """The valid lines GRBL may have run instead of ``line`` when one of its bytes was dropped on the wire.

    A byte >= 0x80 is taken for an unknown real-time command and discarded (a bit flip of an ASCII byte),
    so what GRBL parses is ``line`` with one character missing; only the variants that still parse and mean
    something else are kept.
    """
    sent = words_of(line)
    seen: list[dict[str, list[float]]] = []
    for i in range(len(line)):
        words = words_of(line[:i] + line[i + 1:])
        if (words is not None and words != sent and words not in seen
                and set(words.get("G", [])) <= {0, 1, 4}
                and set(words.get("M", [])) <= {3, 4, 5}):
            seen.append(words)
    return seen


@dataclass(frozen=True)
class Garble:
    """A motion line that did not run as sent: ``leg`` as sent, ``target`` where GRBL took the pen instead.

    ``target`` None: the line drew nothing of its leg (GRBL rejected it, or it ran with the wrong pen).
    """

    leg: SentLeg
    target: tuple[float, float] | None

    def inked_to(self, stop: tuple[float, float], tolerance: float) -> tuple[float, float] | None:
        """The farthest point of the leg as sent that the changed line drew, or None.

        The pen ran straight from the leg's start towards ``target`` (and stopped at ``stop`` if that lies on the
        way).  When all it ran stayed within ``tolerance`` of the leg (a digit dropped after the point), it drew
        the leg that far.  None when it left the leg (that is a stray line, and the leg is drawn again from its
        start), got no farther than ``tolerance``, or the line drew nothing of its leg.
        """
        if self.target is None or not self.leg.down:
            return None
        a, b, v = (np.asarray(p, dtype=np.float64) for p in (self.leg.start, self.leg.end, self.target))
        length = float(np.hypot(*(b - a)))
        if length <= tolerance:
            return None
        unit = (b - a) / length
        wrong = v - a
        on_the_way = near_segment(np.asarray(stop, dtype=np.float64), a, v, tolerance)
        ran = 1.0 if on_the_way is None else on_the_way  # the share of start -> target run: all, unless it stopped
        off = abs(float(wrong[0] * unit[1] - wrong[1] * unit[0]))  # the target's distance from the leg's line
        if off * ran > tolerance:
            return None  # it left the leg: a stray line (its first stretch near the leg is drawn again)
        along = min(length, max(0.0, ran * float(wrong @ unit)))
        if along <= tolerance:
            return None
        point = a + along * unit
        return (float(point[0]), float(point[1]))


def explain_position(
    legs: list[SentLeg], position: tuple[float, float], pen_down: bool | None, tolerance: float,
    unit_mm: float, is_down: Callable[[float], bool], since: tuple[float, float] | None = None,
) -> Garble | None:
    """The first of ``legs`` whose line, with one byte dropped, puts the pen at ``position`` (pen ``pen_down``).

    A changed target moves the pen off the path until the next line's target (the explanation of a position off
    the path); a changed S value lifts or lowers the pen along this leg and the legs after it that set none (tried
    first for a position on the path with the wrong pen).  ``since``: where an earlier report found the pen on the
    path; the legs before the first one through it ran as sent.  Of several explanations the first is taken: a
    resume from too early a leg draws a leg twice, one from too late a leg would lose one.  None when no single
    dropped byte explains it.
    """
    q = np.asarray(position, dtype=np.float64)

    def on(a: tuple[float, float], b: tuple[float, float], p: np.ndarray = q) -> bool:
        return near_segment(p, np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64), tolerance) is not None

    if since is not None:
        seen = np.asarray(since, dtype=np.float64)
        legs = legs[next((i for i, leg in enumerate(legs) if on(leg.start, leg.end, seen)), 0):]

    def targets(leg: SentLeg) -> list[tuple[dict[str, list[float]], tuple[float, float]]]:
        out = []
        for words in garbled_variants(leg.line):
            x, y = (words[a][0] / unit_mm if a in words else e for a, e in zip("XY", leg.end, strict=True))
            out.append((words, (x, y)))
        return out

    variants = [targets(leg) for leg in legs]

    def moved() -> Garble | None:
        for i, leg in enumerate(legs):
            for _, (x, y) in variants[i]:
                if math.hypot(x - leg.end[0], y - leg.end[1]) > tolerance and (
                        on(leg.start, (x, y)) or (i + 1 < len(legs) and on((x, y), legs[i + 1].end))):
                    return Garble(leg, (x, y))
        return None

    def lifted() -> Garble | None:
        for i, leg in enumerate(legs):
            for words, (x, y) in variants[i]:
                down = False if 5 in words.get("M", []) else is_down(words["S"][0]) if "S" in words else leg.down
                if (x, y) == leg.end and down != leg.down and pen_down == down:
                    for later in legs[i:]:
                        if later is not leg and "S" in later.line:
                            break
                        if on(later.start, later.end) and later.down != down:
                            return Garble(leg, None)
        return None

    if any(on(leg.start, leg.end) for leg in legs):  # on the path with the wrong pen: an S value, else a target
        first = lifted()
        return first if first is not None else moved()
    return moved()

"""HP-GL labels: LB text drawn character by character, its size, direction, slant and character sets, and symbols.

Characters are drawn with pixelpen's stroke font in HP's character body: a cell 1.5 x the character
width by 2 x its height, the glyph centred in the width (7470A manual, SI/SR and LB).
``LabelInstructions`` has one method per instruction; ``LABELS`` is its part of the instruction table.
"""

from __future__ import annotations

import logging
import math
from functools import lru_cache
from typing import Final

import numpy as np

from pixelpen.sim.plotters.hpgl.machine import Machine
from pixelpen.sim.plotters.hpgl.models import ModelSpec
from pixelpen.sim.plotters.hpgl.params import Command, CommandTable, HPGLError, in_range
from pixelpen.sim.plotters.hpgl.parsing import ETX, Instruction, InstructionReader
from pixelpen.vector.font import text_extent, text_strokes

__all__ = ["LABELS", "LabelInstructions"]

log = logging.getLogger(__name__)


@lru_cache(maxsize=256)
def _glyph(char: str) -> tuple[np.ndarray, ...]:
    """Strokes of ``char`` at cap height 1, scaled so 'H' is 1 wide, centred on x = 0.5 (HP's character body)."""
    centre = text_extent(char, height=1.0).width / 2.0
    return tuple(
        np.column_stack([(p[:, 0] - centre) / _H_WIDTH + 0.5, p[:, 1]]) for p in text_strokes(char, height=1.0)
    )


def _h_width() -> float:
    """Width of 'H' in the stroke font at cap height 1 (HP's character width)."""
    pts = np.concatenate(text_strokes("H", height=1.0))
    return float(pts[:, 0].max() - pts[:, 0].min())


_H_WIDTH = _h_width()


class LabelInstructions:
    """The label instructions and SM symbols, acting on the plotter's Machine (and the reader's label terminator)."""

    def __init__(self, spec: ModelSpec, machine: Machine, reader: InstructionReader) -> None:
        self.spec = spec
        self.machine = machine
        self.reader = reader

    def _char_frame(self) -> tuple[float, float, float]:
        """Character width and height (logical plotter units) and the label direction (radians)."""
        m = self.machine
        g = m.g
        (p1x, p1y), (p2x, p2y) = g.p1, g.p2
        kind, a, b = g.char_size
        if kind == "abs":
            per_cm = 10.0 / self.spec.unit_mm
            w, h = a * per_cm, b * per_cm
        else:
            w, h = a / 100.0 * (p2x - p1x), b / 100.0 * (p2y - p1y)
        kind, run, rise = g.direction
        if kind == "rel":
            run, rise = run / 100.0 * (p2x - p1x), rise / 100.0 * (p2y - p1y)
        return w, h, math.atan2(rise, run)

    def _lb(self, item: Instruction) -> None:
        """LB: draw label text character by character (CR, LF, BS, SO/SI handled)."""
        m = self.machine
        w, h, theta = self._char_frame()
        c, s = math.cos(theta), math.sin(theta)
        advance = np.array([1.5 * w * c, 1.5 * w * s])  # character cell: 1.5 x width by 2 x height
        line = np.array([2.0 * h * s, -2.0 * h * c])  # one line down, perpendicular to the direction
        g = m.g
        paths: list[np.ndarray] = []
        flags: list[np.ndarray] = []
        pos = np.array(m.pos)
        for ch in item.text:
            code = ord(ch)
            if code == 13:
                pos = np.array(g.cr_point)
            elif code == 10:
                g.cr_point = tuple(np.array(g.cr_point) + line)
                pos = pos + line
            elif code == 8:
                pos = pos - advance
            elif code in (14, 15):
                g.alternate = code == 14
            elif code < 32 or code == 127:
                log.info("%s: label control character %r has no effect", self.spec.name, ch)
            else:
                if ch != " ":
                    pts, down = self._glyph_path(ch, pos, w, h, theta)
                    paths.append(pts)
                    flags.append(down)
                pos = pos + advance
        if paths:
            m.plan(np.concatenate(paths), np.concatenate(flags), dashed=False)
        m.pen_to(False)
        m.check_position(float(pos[0]), float(pos[1]))
        m.pos = (float(pos[0]), float(pos[1]))

    def _glyph_path(
        self, ch: str, origin: np.ndarray, w: float, h: float, theta: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """One character's strokes as a path with pen flags, its cell's lower-left corner at ``origin``."""
        m = self.machine
        c, s = math.cos(theta), math.sin(theta)
        slant = m.g.slant
        strokes = _glyph(ch)
        if not strokes:
            return np.zeros((0, 2)), np.zeros(0, dtype=bool)
        local = np.concatenate(strokes)
        u = local[:, 0] * w + local[:, 1] * h * slant
        v = local[:, 1] * h
        pts = np.column_stack([origin[0] + u * c - v * s, origin[1] + u * s + v * c])
        down = np.ones(len(pts), dtype=bool)
        down[np.cumsum([0] + [len(k) for k in strokes[:-1]])] = False  # pen up to each stroke's start
        return pts, down

    def symbol(self) -> None:
        """SM: the symbol character centred on the point just plotted."""
        m = self.machine
        w, h, theta = self._char_frame()
        c, s = math.cos(theta), math.sin(theta)
        centre = m.pos
        origin = np.array(centre) - np.array([(w / 2) * c - (h / 2) * s, (w / 2) * s + (h / 2) * c])
        down = m.pen_down
        pts, flags = self._glyph_path(m.g.symbol, origin, w, h, theta)
        if len(pts):
            m.plan(pts, flags, dashed=False)
        m.pen_to(False)
        m.travel(centre[0], centre[1], draw=False)
        if down:
            m.pen_to(True)

    def _dt(self, item: Instruction) -> None:
        """DT: the label terminator (none: ETX)."""
        self.reader.label_terminator = ord(item.text) if item.text else ETX

    def _sm(self, item: Instruction) -> None:
        """SM: the symbol drawn at each plotted point (none: off)."""
        m = self.machine
        m.g.symbol = item.text

    def _di(self, item: Instruction) -> None:
        """DI / DR: label direction, absolute or relative to P1-P2."""
        m = self.machine
        params = item.params
        if not params:
            m.g.direction = ("abs", 1.0, 0.0)
        else:
            run, rise = (in_range(v, -128, 127.9999, "direction") for v in params)
            if run == 0 and rise == 0:
                raise HPGLError(3, "run and rise cannot both be 0")
            m.g.direction = ("rel" if item.mnemonic == "DR" else "abs", run, rise)
        m.g.cr_point = m.pos

    def _si(self, item: Instruction) -> None:
        """SI / SR: character size, absolute (cm) or relative to P1-P2 (percent)."""
        m = self.machine
        params = item.params
        if item.mnemonic == "SI":
            if not params:
                m.g.char_size = ("abs", *m.default_char_cm(*m.default_p1p2()))
            else:
                w, h = (in_range(v, -128, 127.9999, "character size (cm)") for v in params)
                m.g.char_size = ("abs", w, h)
        else:
            w, h = (in_range(v, -128, 127.9999, "character size (%)") for v in params) if params else (0.75, 1.5)
            m.g.char_size = ("rel", w, h)

    def _sl(self, item: Instruction) -> None:
        """SL: character slant (tangent of the angle)."""
        m = self.machine
        params = item.params
        m.g.slant = in_range(params[0], -128, 127.9999, "slant") if params else 0.0

    def _cp(self, item: Instruction) -> None:
        """CP: character plot (move by spaces and lines; none: carriage return and line feed)."""
        m = self.machine
        params = item.params
        w, h, theta = self._char_frame()
        c, s = math.cos(theta), math.sin(theta)
        if not params:  # carriage return and line feed
            line = np.array([2.0 * h * s, -2.0 * h * c])
            m.g.cr_point = tuple(np.array(m.g.cr_point) + line)
            target = m.g.cr_point
        else:
            spaces, lines = (in_range(v, -128, 127.9999, "CP count") for v in params)
            dx = spaces * 1.5 * w
            dy = lines * 2.0 * h
            target = (m.pos[0] + dx * c - dy * s, m.pos[1] + dx * s + dy * c)
        down = m.pen_down
        m.pen_to(False)
        m.travel(*target, draw=False)
        if down:
            m.pen_to(True)

    def _charset(self, item: Instruction) -> None:
        """CA / CS: designate the alternate or standard character set."""
        m = self.machine
        params = item.params
        n = int(params[0]) if params else 0
        if not 0 <= n < self.spec.charsets:
            raise HPGLError(5, f"character set {n} unknown (0-{self.spec.charsets - 1})")
        if item.mnemonic == "CS":
            m.g.standard_set = n
        else:
            m.g.alternate_set = n
        if n:
            log.info("%s: character set %d is drawn with the standard glyphs", self.spec.name, n)

    def _select_set(self, item: Instruction) -> None:
        """SA / SS: select the alternate or standard set."""
        m = self.machine
        m.g.alternate = item.mnemonic == "SA"

    def _uc(self, item: Instruction) -> None:
        """User-defined character: pen control 99 (down) / -99 (up) and increments of w/4, h/8 (7470A UC grid)."""
        m = self.machine
        w, h, theta = self._char_frame()
        c, s = math.cos(theta), math.sin(theta)
        origin = m.pos
        x, y = origin
        down = False
        params = list(item.params)
        m.pen_to(False)
        i = 0
        while i < len(params):
            v = params[i]
            if abs(v) >= 99:
                down = v > 0
                i += 1
                continue
            if i + 1 >= len(params):
                raise HPGLError(2, "an X increment without its Y increment")
            du, dv = v * w / 4.0, params[i + 1] * h / 8.0
            x, y = x + du * c - dv * s, y + du * s + dv * c
            m.travel(x, y, draw=down, dashed=False)
            i += 2
        m.pen_to(False)
        advance = 1.5 * w
        m.travel(origin[0] + advance * c, origin[1] + advance * s, draw=False)
        if m.pen_down:
            m.pen_to(True)


LABELS: Final[CommandTable[LabelInstructions]] = {
    "LB": Command(None, LabelInstructions._lb),
    "DT": Command(None, LabelInstructions._dt),
    "SM": Command(None, LabelInstructions._sm),
    "DI": Command((0, 2), LabelInstructions._di),
    "DR": Command((0, 2), LabelInstructions._di),
    "SI": Command((0, 2), LabelInstructions._si),
    "SR": Command((0, 2), LabelInstructions._si),
    "SL": Command((0, 1), LabelInstructions._sl),
    "CP": Command((0, 2), LabelInstructions._cp),
    "CA": Command((0, 1), LabelInstructions._charset),
    "CS": Command((0, 1), LabelInstructions._charset),
    "SA": Command(None, LabelInstructions._select_set),
    "SS": Command(None, LabelInstructions._select_set),
    "UC": Command(None, LabelInstructions._uc),
}
"""Mnemonic -> (parameter counts, handler) for the label instructions."""

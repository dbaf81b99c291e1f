"""HP-GL instructions that set up and draw: setup, pens, vectors, arcs, circles, rectangles, wedges, fills, ticks.

``GraphicsInstructions`` has one method per instruction; ``GRAPHICS`` maps each mnemonic to its parameter
counts and that method (the plotter checks the count, error 2, then calls it).  A method raises
``HPGLError(code, why)`` to reject its instruction; the plotter logs it and goes on with the next one.
"""

from __future__ import annotations

import logging
import math
from typing import Final

import numpy as np

from pixelpen.geometry.hatch import hatch
from pixelpen.sim.plotters.hpgl.labels import LabelInstructions
from pixelpen.sim.plotters.hpgl.machine import DEFAULT_E_MASK, Machine, Status
from pixelpen.sim.plotters.hpgl.models import ModelSpec
from pixelpen.sim.plotters.hpgl.motion import Motion
from pixelpen.sim.plotters.hpgl.params import Command, CommandTable, HPGLError, coord, in_range
from pixelpen.sim.plotters.hpgl.parsing import ETX, Instruction, InstructionReader

__all__ = ["GRAPHICS", "MAX_FILL_LINES", "GraphicsInstructions"]

log = logging.getLogger(__name__)

MAX_FILL_LINES: Final = 50_000
"""A fill needing more hatch lines than this is refused with error 3 (spacing far too small)."""


def _chord_count(sweep_deg: float, chord: float) -> int:
    """Chords an arc of ``sweep_deg`` is drawn with at chord angle ``chord`` (HP-GL's tolerance reading)."""
    chord = abs(chord)
    if chord > 360:
        chord %= 360
    if chord > 180:
        chord = 360 - chord
    chord = max(chord, 0.5)  # assumption: 0 means the smoothest the plotter draws, taken as 0.5 degree
    return max(1, math.ceil(abs(sweep_deg) / chord - 1e-9))


def _chord_param(params: tuple[float, ...], index: int) -> float:
    """The chord-angle parameter at ``index`` (default 5 degrees)."""
    return in_range(params[index], -32768, 32767, "chord angle") if len(params) > index else 5.0


class GraphicsInstructions:
    """The drawing and setup instructions, acting on the plotter's Machine and Status."""

    def __init__(
        self,
        spec: ModelSpec,
        machine: Machine,
        status: Status,
        reader: InstructionReader,
        labels: LabelInstructions,
        pen_colours: dict[int, str],
    ) -> None:
        self.spec = spec
        self.machine = machine
        self.status = status
        self.reader = reader
        self.labels = labels
        self.pen_colours = pen_colours

    def _in(self, item: Instruction) -> None:
        """IN: initialize (pen up, RO 0, graphics defaults, errors and masks cleared)."""
        m = self.machine
        m.pen_down = False
        m.pen_to(False)
        m.rotation = 0
        m.pos = m.to_logical(*m.phys)
        m.g = m.default_graphics()
        self.reader.label_terminator = ETX
        self.status.p1p2_changed = False
        self.status.hpgl_error = 0
        self.status.error_flag = False
        self.status.initialized = True
        self.status.in_seen = True
        self.status.masks = (DEFAULT_E_MASK, 0, 0)

    def _df(self, item: Instruction) -> None:
        """DF: default graphics state (P1/P2 and the position stay)."""
        m = self.machine
        g = m.default_graphics()
        g.p1, g.p2 = m.g.p1, m.g.p2
        g.char_size = ("abs", *m.default_char_cm(*m.default_p1p2()))
        g.cr_point = m.pos
        m.g = g
        self.reader.label_terminator = ETX

    def _ip(self, item: Instruction) -> None:
        """IP: input P1 and P2 (none: the paper's defaults; two: P1 moves, P2 keeps the offset)."""
        m = self.machine
        params = item.params
        if not params:
            m.g.p1, m.g.p2 = m.default_p1p2()
        else:
            vals = [coord(v) for v in params]
            (o1x, o1y), (o2x, o2y) = m.g.p1, m.g.p2
            p1 = (vals[0], vals[1])
            p2 = (vals[2], vals[3]) if len(vals) == 4 else (p1[0] + o2x - o1x, p1[1] + o2y - o1y)
            # P1 and P2 may not coincide on an axis: the plotter moves P2 one unit off (HP-GL convention)
            p2 = (p2[0] + (p2[0] == p1[0]), p2[1] + (p2[1] == p1[1]))
            m.g.p1, m.g.p2 = p1, p2
        self.status.p1p2_changed = True

    def _sc(self, item: Instruction) -> None:
        """SC: scale user units onto P1-P2 (none: plotter units)."""
        m = self.machine
        params = item.params
        if not params:
            m.g.scale = None
            return
        xmin, xmax, ymin, ymax = (coord(v) for v in params)
        if xmin == xmax or ymin == ymax:
            raise HPGLError(3, "SC needs xmin != xmax and ymin != ymax")
        m.g.scale = (xmin, xmax, ymin, ymax)

    def _iw(self, item: Instruction) -> None:
        """IW: input the clipping window (none: the hard-clip limits)."""
        m = self.machine
        params = item.params
        w, h = m.logical_limits()
        if not params:
            m.g.window = (0.0, 0.0, float(w), float(h))
            return
        x0, y0, x1, y1 = (coord(v) for v in params)
        if x0 > x1 or y0 > y1:
            raise HPGLError(3, "IW needs the lower-left corner first")
        m.g.window = (max(x0, 0.0), max(y0, 0.0), min(x1, float(w)), min(y1, float(h)))

    def _ro(self, item: Instruction) -> None:
        """RO: rotate the coordinate system by 0 or 90 degrees."""
        m = self.machine
        params = item.params
        angle = params[0] if params else 0.0
        if angle not in (0.0, 90.0):
            raise HPGLError(3, "RO takes 0 or 90")
        if int(angle) == m.rotation:
            return
        m.rotation = int(angle)
        m.g.p1, m.g.p2 = m.default_p1p2()
        w, h = m.logical_limits()
        m.g.window = (0.0, 0.0, float(w), float(h))
        m.pos = m.g.cr_point = m.to_logical(*m.phys)
        self.status.p1p2_changed = True

    def _im(self, item: Instruction) -> None:
        """IM: input the e-, s- and p-masks."""
        params = item.params
        masks = [DEFAULT_E_MASK, 0, 0]
        for i, v in enumerate(params):
            masks[i] = int(in_range(v, 0, 255, "mask"))
        self.status.masks = (masks[0], masks[1], masks[2])

    def _ps(self, item: Instruction) -> None:
        """PS: paper size (0: A3/B, 4: A4/A)."""
        m = self.machine
        (size,) = item.params
        metric = m.paper.name in ("a4", "a3")
        names = {0: "a3" if metric else "tabloid", 4: "a4" if metric else "letter"}
        if int(size) not in names or names[int(size)] not in self.spec.papers:
            raise HPGLError(3, "PS takes 0 (A3/B) or 4 (A4/A)")
        m.load_paper(self.spec.papers[names[int(size)]])

    def _sp(self, item: Instruction) -> None:
        """SP: select a pen from the carousel (0: put it away)."""
        m = self.machine
        params = item.params
        pen = int(params[0]) if params else 0
        if not 0 <= pen <= self.spec.pens:
            raise HPGLError(3, f"pen {pen} is not a carousel stall (0-{self.spec.pens})")
        if pen == m.pen:
            return
        if pen and pen not in self.pen_colours:
            log.warning("%s: SP%d selects an empty stall: the plotter cannot tell and plots dry", self.spec.name, pen)
        m.pen_to(False)
        m.motions.append(Motion(self.spec.pen_change_s, m.phys, m.phys, pen=pen))
        m.pen = pen
        m.g.dash_pos = 0.0

    def _vs(self, item: Instruction) -> None:
        """VS: pen-down velocity for all pens or one (0.38 cm/s steps; the slower acceleration follows)."""
        m = self.machine
        params = item.params
        spec = self.spec
        if not params:
            m.g.velocity.clear()
            m.g.slow_accel = False
            return
        v = params[0]
        if v < 0 or v >= spec.vs_error_from:
            raise HPGLError(3, f"velocity {v:g} cm/s outside 0..{spec.vs_error_from:g}")
        # 0.38 cm/s steps, 0 meaning 0.38 (7470A manual, VS); the model's maximum caps it
        v = spec.max_velocity_cm_s if v >= spec.max_velocity_cm_s else max(0.38, round(v / 0.38) * 0.38)
        if len(params) == 2:
            pen = int(params[1])
            if not 1 <= pen <= spec.pens:
                raise HPGLError(3, f"VS pen {pen} is not a carousel stall (1-{spec.pens})")
            m.g.velocity[pen] = v
        else:
            for pen in range(spec.pens + 1):
                m.g.velocity[pen] = v
        m.g.slow_accel = True

    def _fs(self, item: Instruction) -> None:
        """FS: pen force (accepted, no visible effect)."""
        params = item.params
        if params:
            in_range(params[0], 1, 8, "force")
        log.info("%s: %s accepted (pen force has no visible effect in the simulator)", self.spec.name, item)

    def _pt(self, item: Instruction) -> None:
        """PT: pen thickness for solid fills (mm)."""
        m = self.machine
        params = item.params
        m.g.pen_thickness_mm = in_range(params[0], 0.1, 5.0, "pen thickness (mm)") if params else 0.3

    def _lt(self, item: Instruction) -> None:
        """LT: line type and pattern length (none: solid)."""
        m = self.machine
        params = item.params
        g = m.g
        if not params:
            g.line_type = None
        else:
            kind = int(in_range(params[0], 0, 6, "line type"))
            if len(params) == 2:
                length = params[1]
                if not 0 < length <= 127.9999:
                    raise HPGLError(3, f"pattern length {length:g} % outside 0..127.9999")
                g.pattern_pct = length
            g.line_type = kind
        g.dash_pos = 0.0

    def _pa(self, item: Instruction) -> None:
        """PA / PR: plot absolute or relative (a pair moves with the pen as it is)."""
        m = self.machine
        m.g.relative = item.mnemonic == "PR"
        if item.params:
            self._vector(item, m.pen_down)

    def _pu(self, item: Instruction) -> None:
        """PU / PD: pen up or down, then move through the pairs (a bare PD leaves a dot)."""
        m = self.machine
        m.pen_down = item.mnemonic == "PD"
        if not item.params:
            if not m.pen_down:
                m.g.dash_pos = 0.0
            lowered = m.pen_down and not m.phys_down
            m.pen_to(m.pen_down)
            if lowered:
                m.dot()  # a bare PD lowers the pen where it stands: the tip leaves a dot
            return
        self._vector(item, m.pen_down)

    def _vector(self, item: Instruction, draw: bool) -> None:
        """One X,Y pair of PA/PR/PU/PD: the move, then SM's symbol if one is set."""
        m = self.machine
        x, y = item.params
        if m.g.relative:
            dx, dy = m.user_delta(coord(x), coord(y))
            target = (m.pos[0] + dx, m.pos[1] + dy)
        else:
            target = m.user_to_plotter(coord(x), coord(y))
        if not draw:
            m.g.dash_pos = 0.0
        m.travel(*target, draw=draw)
        m.g.cr_point = m.pos
        if m.g.symbol:
            self.labels.symbol()

    def _arc_points(
        self, centre_user: tuple[float, float], radius: float, start_deg: float, sweep_deg: float, chord: float
    ) -> np.ndarray:
        """Chord end points (logical plotter units) of an arc given in user units, equal chords (7470A manual CI)."""
        m = self.machine
        n = _chord_count(sweep_deg, chord)
        theta = np.radians(start_deg + sweep_deg * np.arange(n + 1) / n)
        ux = centre_user[0] + radius * np.cos(theta)
        uy = centre_user[1] + radius * np.sin(theta)
        return np.array([m.user_to_plotter(float(a), float(b)) for a, b in zip(ux, uy, strict=True)])

    def _ci(self, item: Instruction) -> None:
        """CI: circle around the pen position (the pen returns to the centre)."""
        m = self.machine
        params = item.params
        radius = coord(params[0])
        chord = _chord_param(params, 1)
        centre_user = m.plotter_to_user(*m.pos)
        start = 180.0 if radius < 0 else 0.0
        points = self._arc_points(centre_user, abs(radius), start, 360.0, chord)
        for x, y in points:
            m.check_position(float(x), float(y))
        m.outline(points)

    def _aa(self, item: Instruction) -> None:
        """AA / AR: arc around an absolute or relative centre, drawn if the pen is down."""
        m = self.machine
        params = item.params
        cx, cy = coord(params[0]), coord(params[1])
        if item.mnemonic == "AR":
            ux, uy = m.plotter_to_user(*m.pos)
            cx, cy = ux + cx, uy + cy
        sweep = in_range(params[2], -32768, 32767, "arc angle")
        chord = _chord_param(params, 3)
        ux, uy = m.plotter_to_user(*m.pos)
        radius = math.hypot(ux - cx, uy - cy)
        start = math.degrees(math.atan2(uy - cy, ux - cx))
        points = self._arc_points((cx, cy), radius, start, sweep, chord)
        for x, y in points[1:]:
            m.travel(float(x), float(y), draw=m.pen_down)
        m.g.cr_point = m.pos

    def _rect_corner(self, item: Instruction) -> tuple[float, float]:
        """The opposite corner of EA/ER/RA/RR in logical plotter units."""
        m = self.machine
        x, y = (coord(v) for v in item.params)
        if item.mnemonic in ("ER", "RR"):
            dx, dy = m.user_delta(x, y)
            return m.pos[0] + dx, m.pos[1] + dy
        return m.user_to_plotter(x, y)

    def _ea(self, item: Instruction) -> None:
        """EA / ER: edge a rectangle (absolute or relative corner)."""
        m = self.machine
        x1, y1 = m.check_position(*self._rect_corner(item))
        x0, y0 = m.pos
        m.outline(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]]))

    def _ra(self, item: Instruction) -> None:
        """RA / RR: fill a rectangle with the FT pattern."""
        m = self.machine
        x1, y1 = m.check_position(*self._rect_corner(item))
        (x0, y0), down = m.pos, m.pen_down
        self._fill(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))
        m.restore_pen((x0, y0), down)

    def _wedge_ring(self, item: Instruction) -> np.ndarray:
        """The outline of EW/WG's wedge around the pen position."""
        m = self.machine
        params = item.params
        radius = coord(params[0])
        start = in_range(params[1], -32768, 32767, "start angle")
        sweep = in_range(params[2], -32768, 32767, "sweep angle")
        chord = _chord_param(params, 3)
        sweep = max(-360.0, min(360.0, sweep))
        centre_user = m.plotter_to_user(*m.pos)
        if radius < 0:
            radius, start = -radius, start + 180.0
        arc = self._arc_points(centre_user, radius, start, sweep, chord)
        ring = np.vstack([[m.pos], arc, [m.pos]]) if abs(sweep) < 360 else arc
        for x, y in ring:
            m.check_position(float(x), float(y))
        return ring

    def _ew(self, item: Instruction) -> None:
        """EW: edge a wedge."""
        self.machine.outline(self._wedge_ring(item))

    def _wg(self, item: Instruction) -> None:
        """WG: fill a wedge with the FT pattern."""
        m = self.machine
        ring = self._wedge_ring(item)
        pos, down = m.pos, m.pen_down
        self._fill(ring[:-1] if len(ring) > 3 and np.array_equal(ring[0], ring[-1]) else ring)
        m.restore_pen(pos, down)

    def _ft(self, item: Instruction) -> None:
        """FT: fill type, spacing and angle (none: solid bidirectional)."""
        m = self.machine
        params = item.params
        g = m.g
        if not params:
            g.fill_type, g.fill_spacing, g.fill_angle = 1, 0.0, 0.0
            return
        kind = int(in_range(params[0], 1, 4, "fill type"))
        spacing = in_range(params[1], 0, 32767, "fill spacing") if len(params) > 1 else g.fill_spacing
        angle = params[2] if len(params) > 2 else g.fill_angle
        g.fill_type, g.fill_spacing, g.fill_angle = kind, spacing, 45.0 * round(angle / 45.0) % 180.0

    def _fill(self, ring: np.ndarray) -> None:
        """Fill a polygon (logical plotter units) with the FT pattern: solid (PT spacing) or hatched."""
        m = self.machine
        g = m.g
        if g.fill_type in (1, 2):
            spacing = g.pen_thickness_mm / self.spec.unit_mm
        elif g.fill_spacing > 0:
            spacing = abs(m.user_delta(g.fill_spacing, 0.0)[0])
        else:
            spacing = 0.01 * m.p1p2_diagonal()
        extent = float(np.hypot(*(ring.max(axis=0) - ring.min(axis=0))))
        if spacing <= 0 or extent / spacing > MAX_FILL_LINES:
            raise HPGLError(3, f"fill spacing {spacing:.3g} plotter units is too fine for this area")
        angle = math.radians(g.fill_angle)
        lines = hatch(ring, spacing, angle, cross=g.fill_type == 4, join=g.fill_type == 1)
        if g.fill_type == 2:  # unidirectional: every stroke in the hatch direction
            d = np.array([math.cos(angle), math.sin(angle)])
            lines = [ln if float(np.dot(ln[-1] - ln[0], d)) >= 0 else ln[::-1] for ln in lines]
        m.pen_to(False)
        for line in lines:
            m.draw_path(line, dashed=False)
            m.pen_to(False)

    def _tl(self, item: Instruction) -> None:
        """TL: tick lengths (percent of P2-P1), positive and negative."""
        m = self.machine
        params = item.params
        if not params:
            m.g.ticks = (0.5, 0.5)
            return
        tp = in_range(params[0], -128, 127.9999, "tick length")
        tn = in_range(params[1], -128, 127.9999, "tick length") if len(params) == 2 else 0.0
        m.g.ticks = (tp, tn)

    def _xt(self, item: Instruction) -> None:
        """XT / YT: an X or Y tick at the pen position."""
        m = self.machine
        tp, tn = m.g.ticks
        (p1x, p1y), (p2x, p2y) = m.g.p1, m.g.p2
        x, y = m.pos
        if item.mnemonic == "XT":
            span = (p2y - p1y) / 100.0
            path = np.array([[x, y + tp * span], [x, y - tn * span]])
        else:
            span = (p2x - p1x) / 100.0
            path = np.array([[x + tp * span, y], [x - tn * span, y]])
        m.outline(path, dashed=False)

    def _dp(self, item: Instruction) -> None:
        """Digitize: no operator here, so the point is taken at once where the pen stands (documented)."""
        m = self.machine
        x, y = m.to_logical(*m.phys)
        self.status.digitized = (x, y, int(m.pen_down))

    def _dc(self, item: Instruction) -> None:
        """DC: digitize clear."""
        self.status.digitized = None


GRAPHICS: Final[CommandTable[GraphicsInstructions]] = {
    "IN": Command(None, GraphicsInstructions._in),
    "DF": Command(None, GraphicsInstructions._df),
    "IP": Command((0, 2, 4), GraphicsInstructions._ip),
    "SC": Command((0, 4), GraphicsInstructions._sc),
    "IW": Command((0, 4), GraphicsInstructions._iw),
    "RO": Command((0, 1), GraphicsInstructions._ro),
    "IM": Command((0, 1, 2, 3), GraphicsInstructions._im),
    "PS": Command((1,), GraphicsInstructions._ps),
    "SP": Command((0, 1), GraphicsInstructions._sp),
    "VS": Command((0, 1, 2), GraphicsInstructions._vs),
    "FS": Command((0, 1, 2), GraphicsInstructions._fs),
    "PT": Command((0, 1), GraphicsInstructions._pt),
    "LT": Command((0, 1, 2), GraphicsInstructions._lt),
    "PA": Command(None, GraphicsInstructions._pa),
    "PR": Command(None, GraphicsInstructions._pa),
    "PU": Command(None, GraphicsInstructions._pu),
    "PD": Command(None, GraphicsInstructions._pu),
    "CI": Command((1, 2), GraphicsInstructions._ci),
    "AA": Command((3, 4), GraphicsInstructions._aa),
    "AR": Command((3, 4), GraphicsInstructions._aa),
    "EA": Command((2,), GraphicsInstructions._ea),
    "ER": Command((2,), GraphicsInstructions._ea),
    "RA": Command((2,), GraphicsInstructions._ra),
    "RR": Command((2,), GraphicsInstructions._ra),
    "EW": Command((3, 4), GraphicsInstructions._ew),
    "WG": Command((3, 4), GraphicsInstructions._wg),
    "FT": Command((0, 1, 2, 3), GraphicsInstructions._ft),
    "TL": Command((0, 1, 2), GraphicsInstructions._tl),
    "XT": Command(None, GraphicsInstructions._xt),
    "YT": Command(None, GraphicsInstructions._xt),
    "DP": Command(None, GraphicsInstructions._dp),
    "DC": Command(None, GraphicsInstructions._dc),
}
"""Mnemonic -> (parameter counts, handler) for the setup and drawing instructions."""

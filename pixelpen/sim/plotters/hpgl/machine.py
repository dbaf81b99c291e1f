"""The plotter's mechanism and HP-GL graphics state: pen and position, coordinate systems, and motion planning.

``Machine`` holds what IN, DF and power-up reset (``Graphics``), where the pen is (logical: the current
coordinate system after RO; physical: plotter units as the paper is loaded) and the queue of timed
motions the instructions plan; the instruction classes change it through its methods and attributes.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from dataclasses import dataclass, field, fields
from typing import Final

import numpy as np

from pixelpen.geometry.clip import clip_segments
from pixelpen.geometry.dashes import dash_polylines
from pixelpen.sim.plotters.hpgl.models import ModelSpec, PaperSpec
from pixelpen.sim.plotters.hpgl.motion import Motion, axis_time, axis_times
from pixelpen.sim.plotters.hpgl.params import HPGLError

__all__ = ["DEFAULT_E_MASK", "LINE_PATTERNS", "Graphics", "Machine", "Status"]

log = logging.getLogger(__name__)

LINE_PATTERNS: Final[dict[int, tuple[float, ...]]] = {
    1: (0.0, 100.0),
    2: (50.0, 50.0),
    3: (70.0, 30.0),
    4: (80.0, 10.0, 0.0, 10.0),
    5: (70.0, 10.0, 10.0, 10.0),
    6: (50.0, 10.0, 10.0, 10.0, 10.0, 10.0),
}
"""LT patterns 1-6: pen-down/pen-up lengths in percent of the pattern length, starting pen down (0 = dot).

LT0 plots only a dot at each vector's end point.  The default pattern length is 4 % of the P1-P2 diagonal.
"""
MAX_DASHES_PER_VECTOR: Final = 10_000
"""Dash resolution limit: a pattern shorter than vector length / this is stretched (the pen cannot do better)."""
MAX_FILL_LINES: Final = 50_000
"""A fill needing more hatch lines than this is refused with error 3 (spacing far too small)."""
DEFAULT_E_MASK: Final = 223
"""IM default e-mask: every error but 6 (position overflow) sets the OS error bit (HP-GL/1 IM default)."""


@dataclass
class Graphics:
    """HP-GL state that IN and DF reset (positions in the current coordinate system's plotter units)."""

    p1: tuple[float, float]
    p2: tuple[float, float]
    window: tuple[float, float, float, float]
    scale: tuple[float, float, float, float] | None = None
    relative: bool = False
    line_type: int | None = None
    pattern_pct: float = 4.0
    dash_pos: float = 0.0
    velocity: dict[int, float] = field(default_factory=dict)
    slow_accel: bool = False
    pen_thickness_mm: float = 0.3
    fill_type: int = 1
    fill_spacing: float = 0.0
    fill_angle: float = 0.0
    char_size: tuple[str, float, float] = ("abs", 0.0, 0.0)
    direction: tuple[str, float, float] = ("abs", 1.0, 0.0)
    slant: float = 0.0
    standard_set: int = 0
    alternate_set: int = 0
    alternate: bool = False
    symbol: str = ""
    ticks: tuple[float, float] = (0.5, 0.5)
    cr_point: tuple[float, float] = (0.0, 0.0)


@dataclass
class Status:
    """What OS, OE and ESC.O report: the status flags, the last HP-GL error, the IM masks and the front panel."""

    hpgl_error: int = 0
    error_flag: bool = False
    initialized: bool = True
    """OS bit 8 is set at power-up."""
    p1p2_changed: bool = False
    digitized: tuple[float, float, int] | None = None
    in_seen: bool = False
    masks: tuple[int, int, int] = (DEFAULT_E_MASK, 0, 0)
    view: bool = False
    """The VIEW button holds plotting."""
    lever: bool = False
    """The paper lever is raised: plotting holds."""

    def power_up(self) -> None:
        """Every flag as at power-up."""
        for f in fields(self):
            setattr(self, f.name, f.default)

    def os_byte(self, pen_down: bool) -> int:
        """The OS status byte: 1 pen down, 2 P1/P2 changed, 4 digitized point, 8 initialized, 16 ready, 32 error."""
        return (
            int(pen_down)
            | (2 if self.p1p2_changed else 0)
            | (4 if self.digitized is not None else 0)
            | (8 if self.initialized else 0)
            | (0 if self.lever else 16)
            | (32 if self.error_flag else 0)
        )

    def clear_error(self) -> None:
        """IN and OE: no error pending, the OS error bit clear."""
        self.hpgl_error = 0
        self.error_flag = False

    def fault(self, code: int) -> None:
        """Record HP-GL error ``code``; the OS error bit follows the IM e-mask."""
        self.hpgl_error = code
        if self.masks[0] & (1 << (code - 1)):
            self.error_flag = True



class Machine:
    """The pen carriage and HP-GL's graphics state of one plotter (``power_up`` restores both)."""

    def __init__(self, spec: ModelSpec, paper: PaperSpec) -> None:
        self.spec = spec
        self.paper = paper
        self.power_up()

    def power_up(self) -> None:
        """Pen in its stall, carriage at the origin, graphics state defaulted (the loaded paper stays)."""
        self.motions: deque[Motion] = deque()
        """Planned motions not yet started by the mechanism."""
        self.rotation = 0
        self.hard_clip = self.paper.hard_clip
        self.phys: tuple[float, float] = (0.0, 0.0)
        """Where the carriage will be once the planned motions are done (physical plotter units)."""
        self.phys_down = False
        self.pen = 0
        self.pos: tuple[float, float] = (0.0, 0.0)
        """The logical pen position (current coordinate system; may run on past the hard-clip limits)."""
        self.pen_down = False
        """The commanded pen state (PD/PU), which OS and OA report."""
        self.g = self.default_graphics()

    def load_paper(self, paper: PaperSpec) -> None:
        """PS: another paper size (hard-clip limits, default P1/P2 and window follow)."""
        self.paper = paper
        self.hard_clip = paper.hard_clip
        self.g.p1, self.g.p2 = self.default_p1p2()
        w, h = self.logical_limits()
        self.g.window = (0.0, 0.0, float(w), float(h))

    def default_graphics(self) -> Graphics:
        """Graphics as IN sets them up for the current paper and rotation."""
        p1, p2 = self.default_p1p2()
        w, h = self.logical_limits()
        g = Graphics(p1=p1, p2=p2, window=(0.0, 0.0, float(w), float(h)))
        g.char_size = ("abs", *self.default_char_cm(p1, p2))
        g.cr_point = self.pos
        return g

    def default_p1p2(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """The paper's default P1 and P2 in the current coordinate system."""
        (ax, ay), (bx, by) = self.paper.p1, self.paper.p2
        if self.rotation == 90:
            w = self.hard_clip[0]
            # physical (x, y) -> logical (y, W - x); keep P1 lower-left, P2 upper-right
            return (float(ay), float(w - bx)), (float(by), float(w - ax))
        return (float(ax), float(ay)), (float(bx), float(by))

    def default_char_cm(self, p1: tuple[float, float], p2: tuple[float, float]) -> tuple[float, float]:
        """SI default: the size SR 0.75,1.5 gives with default P1/P2 (7470A manual, SR)."""
        cm = self.spec.unit_mm / 10.0
        return 0.0075 * abs(p2[0] - p1[0]) * cm, 0.015 * abs(p2[1] - p1[1]) * cm

    # -- coordinates -------------------------------------------------------------------------------

    def logical_limits(self) -> tuple[int, int]:
        """The hard-clip corner in the current coordinate system (RO 90 swaps the axes)."""
        w, h = self.hard_clip
        return (h, w) if self.rotation == 90 else (w, h)

    def to_phys(self, pts: np.ndarray) -> np.ndarray:
        """Logical plotter units (current RO) -> physical plotter units."""
        if self.rotation != 90:
            return pts
        out = np.empty_like(pts)
        out[..., 0] = self.hard_clip[0] - pts[..., 1]
        out[..., 1] = pts[..., 0]
        return out

    def to_logical(self, x: float, y: float) -> tuple[float, float]:
        """One physical point in logical plotter units."""
        if self.rotation != 90:
            return x, y
        return y, self.hard_clip[0] - x

    def user_to_plotter(self, x: float, y: float) -> tuple[float, float]:
        """User units (SC) -> logical plotter units."""
        sc = self.g.scale
        if sc is None:
            return x, y
        (p1x, p1y), (p2x, p2y) = self.g.p1, self.g.p2
        xmin, xmax, ymin, ymax = sc
        return p1x + (x - xmin) * (p2x - p1x) / (xmax - xmin), p1y + (y - ymin) * (p2y - p1y) / (ymax - ymin)

    def plotter_to_user(self, x: float, y: float) -> tuple[float, float]:
        """Logical plotter units -> user units (SC)."""
        sc = self.g.scale
        if sc is None:
            return x, y
        (p1x, p1y), (p2x, p2y) = self.g.p1, self.g.p2
        xmin, xmax, ymin, ymax = sc
        return xmin + (x - p1x) * (xmax - xmin) / (p2x - p1x), ymin + (y - p1y) * (ymax - ymin) / (p2y - p1y)

    def user_delta(self, dx: float, dy: float) -> tuple[float, float]:
        """A relative move in user units -> plotter units."""
        sc = self.g.scale
        if sc is None:
            return dx, dy
        (p1x, p1y), (p2x, p2y) = self.g.p1, self.g.p2
        xmin, xmax, ymin, ymax = sc
        return dx * (p2x - p1x) / (xmax - xmin), dy * (p2y - p1y) / (ymax - ymin)

    def check_position(self, x: float, y: float) -> tuple[float, float]:
        """HP-GL error 6 for a position outside the numeric range; the position otherwise."""
        if not (math.isfinite(x) and math.isfinite(y)) or max(abs(x), abs(y)) > 32768:
            raise HPGLError(6, f"position {x:.1f},{y:.1f} is outside the plotter's -32768..32767 range")
        return x, y

    def p1p2_diagonal(self) -> float:
        """Length of the P1-P2 diagonal (plotter units)."""
        (p1x, p1y), (p2x, p2y) = self.g.p1, self.g.p2
        return math.hypot(p2x - p1x, p2y - p1y)

    def phys_point(self, x: float, y: float) -> tuple[float, float]:
        """One logical point in physical plotter units (``_to_phys`` for a scalar pair)."""
        return (self.hard_clip[0] - y, x) if self.rotation == 90 else (x, y)

    def clip_window(self) -> tuple[float, float, float, float]:
        """IW window in physical plotter units, inside the hard-clip limits."""
        x0, y0, x1, y1 = self.g.window
        (ax, ay), (bx, by) = self.phys_point(x0, y0), self.phys_point(x1, y1)
        w, h = self.hard_clip
        return max(0.0, min(ax, bx)), max(0.0, min(ay, by)), min(float(w), max(ax, bx)), min(float(h), max(ay, by))

    # -- motion planning ----------------------------------------------------------------------------

    def speed(self, down: bool) -> tuple[float, float]:
        """(plotter units/s, plotter units/s²) for a pen-down or pen-up move."""
        spec, g = self.spec, self.g
        per_cm = 10.0 / spec.unit_mm
        if not down:
            return spec.max_velocity_cm_s * per_cm, spec.accel_cm_s2 * per_cm
        v = g.velocity.get(self.pen, spec.max_velocity_cm_s)
        a = spec.slow_accel_cm_s2 if g.slow_accel else spec.accel_cm_s2
        return v * per_cm, a * per_cm

    def pen_to(self, down: bool) -> None:
        """Lift or lower the pen if it is not there already (a timed motion)."""
        if self.phys_down != down:
            if down and not self.pen:
                log.warning("%s: pen down with no pen in the holder (select one with SP): nothing is inked",
                            self.spec.name)
            self.phys_down = down
            self.motions.append(Motion(self.spec.pen_lift_s, self.phys, self.phys))

    def dot(self) -> None:
        """Ink a dot where the pen stands (inside the clipping window), as a pen touching the paper does."""
        px, py = self.phys
        x0, y0, x1, y1 = self.clip_window()
        if x0 <= px <= x1 and y0 <= py <= y1:
            dot = np.array([[px, py, px, py]], dtype=np.float64)
            self.motions.append(Motion(0.0, self.phys, self.phys, draw=dot, pen=self.pen,
                                         width_mm=self.g.pen_thickness_mm))

    def travel(self, x: float, y: float, draw: bool, dashed: bool = True) -> None:
        """Plan the move from the current position to logical (x, y); ink it if ``draw``.

        The same as ``_plan`` with one point, in scalar arithmetic: single vectors are most of any plot.
        """
        if draw and dashed and self.g.line_type is not None:
            self.plan(np.array([[x, y]], dtype=np.float64), np.array([True]), dashed)
            return
        self.check_position(x, y)
        ax, ay = self.phys_point(*self.pos)
        bx, by = self.phys_point(x, y)
        w, h = self.hard_clip
        target = (min(max(bx, 0.0), float(w)), min(max(by, 0.0), float(h)))
        self.pen_to(draw)
        v, a = self.speed(draw)
        sx, sy = self.phys
        duration = max(axis_time(abs(target[0] - sx), v, a), axis_time(abs(target[1] - sy), v, a))
        ink = None
        if draw:
            x0, y0, x1, y1 = window = self.clip_window()
            seg = np.array([[ax, ay, bx, by]])
            if x0 <= min(ax, bx) and max(ax, bx) <= x1 and y0 <= min(ay, by) and max(ay, by) <= y1:
                ink = seg
            else:
                clipped, _ = clip_segments(seg, window, method="liang-barsky")
                ink = clipped if len(clipped) else None
        self.motions.append(
            Motion(duration, self.phys, target, draw=ink, pen=self.pen, width_mm=self.g.pen_thickness_mm,
                   velocity=v, accel=a)
        )
        self.phys = target
        self.pos = (x, y)

    def plan(self, points: np.ndarray, down: np.ndarray, dashed: bool = True) -> None:
        """Plan moves through logical ``points`` (K, 2) from the current position; move ``i`` inks if ``down[i]``.

        The pen is lowered or lifted before a move whose state differs.  It stops at the hard-clip limits
        (the physical move is clamped) while the logical position runs on; ink is clipped to the window.
        A point outside the numeric range ends the path there with error 6.
        """
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        down = np.asarray(down, dtype=bool).reshape(-1)
        bad = ~np.isfinite(pts).all(axis=1) | (np.abs(pts) > 32768).any(axis=1)
        if bad.any():
            k = int(np.argmax(bad))
            if k:
                self.plan(pts[:k], down[:k], dashed)
            self.check_position(float(pts[k, 0]), float(pts[k, 1]))
        if not len(pts):
            return
        phys = self.to_phys(np.vstack([self.pos, pts]))
        w, h = self.hard_clip
        clamped = np.column_stack([np.clip(phys[:, 0], 0.0, float(w)), np.clip(phys[:, 1], 0.0, float(h))])
        clamped[0] = self.phys
        (vd, ad), (vu, au) = self.speed(True), self.speed(False)
        dist = np.abs(np.diff(clamped, axis=0))
        durations = np.where(
            down,
            np.maximum(axis_times(dist[:, 0], vd, ad), axis_times(dist[:, 1], vd, ad)),
            np.maximum(axis_times(dist[:, 0], vu, au), axis_times(dist[:, 1], vu, au)),
        ).tolist()
        segs = np.hstack([phys[:-1], phys[1:]])
        inks: list[np.ndarray | None] = [None] * len(pts)
        drawn = np.flatnonzero(down)
        if len(drawn):
            for i, ink in zip(drawn.tolist(), self._inked(segs[drawn], dashed), strict=True):
                inks[i] = ink
        ends = [tuple(p) for p in clamped.tolist()]
        pen, width = self.pen, self.g.pen_thickness_mm
        append = self.motions.append
        for i, (duration, is_down) in enumerate(zip(durations, down.tolist(), strict=True)):
            self.pen_to(is_down)
            v, a = (vd, ad) if is_down else (vu, au)
            append(Motion(duration, ends[i], ends[i + 1], draw=inks[i], pen=pen, width_mm=width, velocity=v, accel=a))
        self.phys = ends[-1]
        self.pos = (float(pts[-1, 0]), float(pts[-1, 1]))

    def _inked(self, segs: np.ndarray, dashed: bool) -> list[np.ndarray | None]:
        """The inked pieces of each physical segment: line type applied (its pattern runs on), window-clipped."""
        g = self.g
        if not dashed or g.line_type is None:
            return self._clip(segs, list(range(len(segs))), len(segs))
        pieces, owners = [], []
        for i, seg in enumerate(segs):
            length = float(math.hypot(seg[2] - seg[0], seg[3] - seg[1]))
            if g.line_type == 0 or length == 0:
                piece = np.array([[seg[2], seg[3], seg[2], seg[3]]])  # LT0 or a zero-length vector: a dot
            else:
                period = max(g.pattern_pct / 100.0 * self.p1p2_diagonal(), length / MAX_DASHES_PER_VECTOR, 1e-9)
                pattern = np.asarray(LINE_PATTERNS[g.line_type]) / 100.0 * period
                piece = _pieces_to_segments(dash_polylines([seg.reshape(2, 2)], pattern.tolist(), offset=g.dash_pos))
                g.dash_pos = (g.dash_pos + length) % period
            pieces.append(piece)
            owners += [i] * len(piece)
        flat = np.concatenate(pieces) if pieces else np.zeros((0, 4))
        return self._clip(flat, owners, len(segs))

    def _clip(self, pieces: np.ndarray, owners: list[int], count: int) -> list[np.ndarray | None]:
        """Clip pieces to the window and group them by the segment (``owners``) each belongs to."""
        x0, y0, x1, y1 = self.clip_window()
        xs, ys = pieces[:, 0::2], pieces[:, 1::2]
        inside = (xs >= x0).all(axis=1) & (xs <= x1).all(axis=1) & (ys >= y0).all(axis=1) & (ys <= y1).all(axis=1)
        kept_rows = [pieces[inside]]
        kept_owners = [np.asarray(owners, dtype=np.int64)[inside]]
        crossing = np.flatnonzero(~inside)
        if len(crossing):
            clipped, index = clip_segments(pieces[crossing], (x0, y0, x1, y1), method="liang-barsky")
            kept_rows.append(clipped)
            kept_owners.append(np.asarray(owners, dtype=np.int64)[crossing[index]])
        rows = np.concatenate(kept_rows)
        who = np.concatenate(kept_owners)
        order = np.argsort(who, kind="stable")
        rows, who = rows[order], who[order]
        bounds = np.searchsorted(who, np.arange(count + 1))
        return [rows[bounds[i] : bounds[i + 1]] if bounds[i + 1] > bounds[i] else None for i in range(count)]

    def draw_path(self, points: np.ndarray, dashed: bool = True) -> None:
        """Pen up to the first logical point, then draw through the rest (pen left down)."""
        down = np.ones(len(points), dtype=bool)
        down[0] = False
        self.plan(points, down, dashed)
        self.pen_to(True)

    def restore_pen(self, pos: tuple[float, float], pen_down: bool) -> None:
        """After a shape: pen up, back to ``pos``, previous pen state (its dot, if down, as the device makes)."""
        self.pen_to(False)
        self.travel(pos[0], pos[1], draw=False)
        self.g.dash_pos = 0.0
        if pen_down:
            self.pen_to(True)

    def outline(self, points: np.ndarray, dashed: bool = True) -> None:
        """Draw a shape through ``points`` from where the pen stands, then return there with the pen as it was."""
        pos, down = self.pos, self.pen_down
        self.pen_to(False)
        self.draw_path(points, dashed)
        self.restore_pen(pos, down)


def _pieces_to_segments(polys: list[np.ndarray]) -> np.ndarray:
    """Dash pieces (polylines, a 1-point piece being a dot) -> (K, 4) segments."""
    out = []
    for p in polys:
        if len(p) == 1:
            out.append(np.hstack([p, p]))
        else:
            out.append(np.hstack([p[:-1], p[1:]]))
    return np.concatenate(out) if out else np.zeros((0, 4))

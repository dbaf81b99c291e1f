"""HP 7475A / 7550A / 7440A pen plotter simulators: HP-GL and RS-232 device control, buffer, handshakes, time, paper.

Written from HP's manuals, not from pixelpen's drivers (see ``/work/shared/reference/plotters.md`` §1 and
the HP 7470A Interfacing and Programming Manual, whose RS-232 chapter the 7475A shares):

* bytes go into the plotter's input buffer of its real size; HP-GL executes from it in clock time
  (each X,Y pair, label character or shape as soon as it is read, so a buffer fills and drains as on
  the device); output instructions (``OS``, ``OA`` ...) are answered when execution reaches them;
* ``ESC .`` device-control sequences act the moment they arrive, anywhere in the stream, even with the
  buffer full: ``ESC.B`` free bytes, ``ESC.E`` RS-232 error (cleared on read), ``ESC.O`` extended
  status, hardwire / Xon-Xoff / ENQ-ACK handshakes set by ``ESC.@``, ``ESC.H``/``ESC.I``, ``ESC.M``, ``ESC.N``;
* bytes that arrive with the buffer full are lost and set ``ESC.E`` error 16, exactly like the device;
* the pen moves at the ``VS`` velocity with the manual's accelerations (2 g, 0.5 g after ``VS`` with a
  parameter; 7470A manual, VS), as a rest-to-rest trapezoid per vector on each axis;
* paper: every pen-down stroke in physical plotter units (y up) with its pen, rendered by ``paper_image``.

Figures not in the manuals are marked ``assumption`` where they are defined.  Readings of the manuals
that a test relies on:

* a pen-down move is limited to the ``VS`` velocity on each axis ("for horizontal or vertical pen-down
  moves"), so a diagonal is no slower than its longer side; pen-up moves run at the model's maximum;
* LT patterns run on from one vector into the next until the pen lifts; LT0 dots each vector's end;
* the IM e-mask (default 223) decides whether an error sets the OS error bit: error 6 (position
  overflow) does so only after ``IM`` enables it; OE reports every error and clears it;
* ``ESC.)`` (plotter off): everything but ``ESC.(``/``ESC.Y`` is ignored until the plotter is on again;
* ``reserve_bug``: the last byte that would fill the buffer to the ESC.B figure is lost (ESC.E 16);
* ``DT;`` restores ETX; label text executes one character at a time; ``DP`` digitizes at once where the
  pen stands (there is no operator); character sets 1-4 are accepted and drawn with the standard glyphs;
* 7550A instructions beyond HP-GL/1 (``PG``, ``EP``, ``FP`` ...) are read and logged, with no effect;
* a bare ``PD;`` lowers the pen where it stands and leaves a dot (merged into a line then drawn from it);
* the 7475A takes ``PS`` (chiplotle3's 7475A list; vpype's ``hp7475a`` files begin ``IN;DF;PS4;``); an
  instruction a model lacks is error 1 (OE, the OS error bit) and the plot goes on with the next one.
"""

from __future__ import annotations

import logging
import math
import re
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from functools import lru_cache, partial
from pathlib import Path
from typing import Final

import numpy as np

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.display.picture import colour_hex, parse_colour
from pixelpen.errors import ConfigError, PixelpenError, URLError
from pixelpen.geometry.clip import clip_segments
from pixelpen.geometry.dashes import dash_polylines
from pixelpen.geometry.hatch import hatch
from pixelpen.sim.base import register_simulator
from pixelpen.sim.plotters.hpgl.parsing import (
    ETX,
    DeviceControl,
    DeviceControlReader,
    Instruction,
    InstructionReader,
)
from pixelpen.sim.plotters.sheet import paper_format, write_paper_svg
from pixelpen.vector.displaylist import DisplayList
from pixelpen.vector.font import text_extent, text_strokes

log = logging.getLogger(__name__)

G_CM_S2: Final = 980.0
"""One g in cm/s².  The 7470A manual (VS) gives the default acceleration as "2 g (980 cm/s²)"; 980 cm/s² is
one g, so one of the two figures is a misprint: the simulator takes 2 g, HP's specification figure."""
COORD_LIMIT: Final = 32767.9999
"""HP-GL/1 coordinate parameter range is -32768 ... 32767 (7470A manual, PA)."""
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


@dataclass(frozen=True)
class PaperSpec:
    """One paper size on one model: hard-clip limits and default P1/P2 in plotter units, and the sheet."""

    name: str
    hard_clip: tuple[int, int]
    """Upper-right hard-clip corner (the lower-left is 0,0), landscape as the paper is loaded."""
    p1: tuple[int, int]
    p2: tuple[int, int]
    page_mm: tuple[float, float]
    """Sheet width and height as loaded."""
    origin_mm: tuple[float, float] | None = None
    """Hard-clip origin measured from the sheet's lower-left corner; None centres the hard-clip area."""


@dataclass(frozen=True)
class ModelSpec:
    """What distinguishes one HP-GL plotter model from another in the simulator."""

    name: str
    ident: str
    unit_mm: float
    papers: Mapping[str, PaperSpec]
    default_paper: str
    pens: int
    buffer: int
    max_velocity_cm_s: float
    accel_cm_s2: float
    slow_accel_cm_s2: float
    vs_error_from: float
    """VS parameters below 0 or at/above this set error 3."""
    pen_lift_s: float
    pen_change_s: float
    mnemonics: frozenset[str]
    recognised: frozenset[str] = frozenset()
    """Mnemonics the model knows that the simulator reads and logs but gives no effect."""
    oi_needs_in: bool = False
    output_options: str = "0,1,0,0,1,0,0,0"
    """OO answer: the 7470A's (pen select, arcs and circles); assumed for the other models."""
    charsets: int = 5


_A4_PAGE, _A3_PAGE = (297.0, 210.0), (420.0, 297.0)
_LETTER_PAGE, _TABLOID_PAGE = (279.4, 215.9), (431.8, 279.4)

_HP7475A_PAPERS = {
    # plotters.md §1.2 (hard clip, default P1/P2 from the 7475A O&I manual p. 25); sheet origins from
    # vpype's 7475A profile (A4 origin 10 mm from the left, 206 mm from the top; A3 15 mm / 287 mm).
    "a4": PaperSpec("a4", (11040, 7721), (603, 521), (10603, 7721), _A4_PAGE, (10.0, 4.0)),
    "a3": PaperSpec("a3", (16158, 11040), (170, 602), (15370, 10602), _A3_PAGE, (15.0, 10.0)),
    "letter": PaperSpec("letter", (10365, 7962), (250, 596), (10250, 7796), _LETTER_PAGE),
    "tabloid": PaperSpec("tabloid", (16640, 10365), (522, 259), (15722, 10259), _TABLOID_PAGE),
}


def _corner_papers(limits: Mapping[str, tuple[int, int]], pages: Mapping[str, tuple[float, float]]) -> dict[str, PaperSpec]:
    """Assumption (no manual table at hand): default P1/P2 at the hard-clip corners."""
    return {name: PaperSpec(name, lim, (0, 0), lim, pages[name]) for name, lim in limits.items()}


_PAGES = {"a4": _A4_PAGE, "a3": _A3_PAGE, "letter": _LETTER_PAGE, "tabloid": _TABLOID_PAGE}
_COMMON_MNEMONICS = frozenset(
    ["AA", "AR", "CA", "CI", "CP", "CS", "DF", "DI", "DR", "DT", "EA", "ER", "EW", "FT", "IM", "IN", "IP", "IW", "LB", "LT", "OA", "OC", "OE", "OF", "OH", "OI", "OO", "OP", "OS", "OW", "PA", "PD", "PR", "PT", "PU", "RA", "RO", "RR", "SA", "SC", "SI", "SL", "SM", "SP", "SR", "SS", "TL", "UC", "VS", "WG", "XT", "YT"]
)
"""HP-GL/1 instructions the three models share (chiplotle3's 7475A whitelist, less digitizing and PS).

The 7475A's own list is chiplotle3's whole whitelist (``commands_7475A.py``), PS included: vpype's
``hp7475a`` device (written and used on 7475As) begins every file ``IN;DF;PS4;`` or ``PS0``."""

MODELS: Final[dict[str, ModelSpec]] = {
    "hp7475a": ModelSpec(
        name="hp7475a", ident="7475A", unit_mm=0.02488,  # 7475A manual p. 22 (plotters.md §1.1)
        papers=_HP7475A_PAPERS, default_paper="a4", pens=6,
        # plotters.md §1.5 ("≈1024 bytes (ask ESC.L)"), hpgl-buddy's 7475A profile ("documented buffer ~1024
        # bytes") and an owner's report (hpmuseum.org forum thread 21184: "buffer overrun! (up to 1024 Bytes)")
        buffer=1024,
        max_velocity_cm_s=38.1, accel_cm_s2=2 * G_CM_S2, slow_accel_cm_s2=0.5 * G_CM_S2,  # 7470A manual VS
        vs_error_from=97.0,
        pen_lift_s=0.05, pen_change_s=2.0,  # assumption: solenoid lift and carousel pen change
        mnemonics=_COMMON_MNEMONICS | {"DC", "DP", "OD", "PS"},
        oi_needs_in=True,  # plotters.md §1.3: a 7475A answers OI only after IN (chiplotle PR #3)
    ),
    "hp7550a": ModelSpec(
        name="hp7550a", ident="7550A", unit_mm=0.025,  # plotters.md §1.1: measured 0.025 mm
        papers=_corner_papers(
            {"a4": (10870, 7600), "a3": (15970, 10870), "letter": (10170, 7840), "tabloid": (16540, 10170)}, _PAGES
        ),
        default_paper="a4", pens=8,
        buffer=1024,  # assumption: ESC.L tells the real figure
        max_velocity_cm_s=80.0, accel_cm_s2=6 * G_CM_S2, slow_accel_cm_s2=2 * G_CM_S2,  # 7550A: 80 cm/s, 6 g
        vs_error_from=128.0,
        pen_lift_s=0.04, pen_change_s=1.5,  # assumption
        mnemonics=_COMMON_MNEMONICS | {"DC", "DP", "OD", "OT", "PS", "FS"},
        recognised=frozenset(
            (
                "AF AH AP BF BL CC CM CT CV DL DS EP ES FP GC IV KY LO NR OG OK OL PB PG PM RP UF WD"  # chiplotle3
            ).split()
        ),
    ),
    "hp7440a": ModelSpec(
        name="hp7440a", ident="7440A", unit_mm=0.025,  # assumption: the HP-GL nominal unit
        papers={
            "a4": replace(_HP7475A_PAPERS["a4"], origin_mm=None),  # plotters.md §1.2: same limits as the 7475A
            "letter": replace(_HP7475A_PAPERS["letter"]),  # assumption: the 7475A's letter figures
        },
        default_paper="a4", pens=8,
        buffer=1024,  # assumption
        max_velocity_cm_s=38.1, accel_cm_s2=2 * G_CM_S2, slow_accel_cm_s2=0.5 * G_CM_S2,  # assumption: as 7475A
        vs_error_from=97.0,
        pen_lift_s=0.05, pen_change_s=2.0,  # assumption
        mnemonics=_COMMON_MNEMONICS,
    ),
}
"""The simulated models; the dict key is the ``sim:`` model name."""

PAPER_ALIASES: Final = {"a": "letter", "b": "tabloid", "us-a": "letter", "us-b": "tabloid"}
DEFAULT_PEN_COLOURS: Final = ("#000000", "#d01010", "#108010", "#1030c0", "#8020a0", "#e07000", "#705020", "#00a0b0")
"""Assumption: a plausible carousel (black, red, green, blue, violet, orange, brown, aqua)."""
OPTIONS: Final = ("paper", "pens", "buffer", "reserve_bug")


# -- small geometry and time helpers ------------------------------------------------------------


def axis_time(distance: float, velocity: float, accel: float) -> float:
    """Seconds for a rest-to-rest move of ``distance`` limited by ``velocity`` and ``accel`` (trapezoid)."""
    if distance <= 0.0:
        return 0.0
    if distance * accel <= velocity * velocity:
        return 2.0 * math.sqrt(distance / accel)
    return distance / velocity + velocity / accel


def _axis_times(distance: np.ndarray, velocity: float, accel: float) -> np.ndarray:
    """``axis_time`` over an array of distances."""
    d = np.asarray(distance, dtype=np.float64)
    triangle = d * accel <= velocity * velocity
    return np.where(triangle, 2.0 * np.sqrt(np.maximum(d, 0.0) / accel), d / velocity + velocity / accel)


def axis_distance(t: float, distance: float, velocity: float, accel: float) -> float:
    """Distance covered ``t`` seconds into the rest-to-rest move of ``axis_time``."""
    total = axis_time(distance, velocity, accel)
    if t >= total:
        return distance
    if t <= 0.0:
        return 0.0
    ramp = min(velocity / accel, total / 2.0)
    if t <= ramp:
        return 0.5 * accel * t * t
    if t <= total - ramp:
        return 0.5 * accel * ramp * ramp + accel * ramp * (t - ramp)
    rest = total - t
    return distance - 0.5 * accel * rest * rest


class _Motion:
    """One thing the mechanism does in time: a move (maybe drawing), a pen lift/drop or a pen change."""

    __slots__ = ("accel", "draw", "duration", "end", "pen", "start", "velocity", "width_mm")

    def __init__(
        self,
        duration: float,
        start: tuple[float, float],
        end: tuple[float, float],
        draw: np.ndarray | None = None,
        pen: int | None = None,
        width_mm: float = 0.3,
        velocity: float = 1.0,
        accel: float = 1.0,
    ) -> None:
        self.duration = duration
        self.start = start
        self.end = end
        self.draw = draw
        self.pen = pen
        self.width_mm = width_mm
        self.velocity = velocity
        self.accel = accel

    def drawn_until(self, elapsed: float) -> np.ndarray | None:
        """The part of ``draw`` inked ``elapsed`` seconds into the move (for a power loss mid-vector)."""
        if self.draw is None or elapsed <= 0.0:
            return None
        (x0, y0), (x1, y1) = self.start, self.end
        dx, dy = x1 - x0, y1 - y0
        span = max(abs(dx), abs(dy))
        if span == 0.0:
            return self.draw
        frac = axis_distance(elapsed, span, self.velocity, self.accel) / span
        d2 = dx * dx + dy * dy
        seg = self.draw
        t0 = ((seg[:, 0] - x0) * dx + (seg[:, 1] - y0) * dy) / d2
        t1 = ((seg[:, 2] - x0) * dx + (seg[:, 3] - y0) * dy) / d2
        keep = np.minimum(t0, t1) <= frac
        seg, t0, t1 = seg[keep].copy(), t0[keep], t1[keep]
        cut = t1 > frac
        if np.any(cut):
            span_t = np.where(t1[cut] - t0[cut] == 0, 1.0, t1[cut] - t0[cut])
            k = ((frac - t0[cut]) / span_t)[:, None]
            seg[cut, 2:4] = seg[cut, 0:2] + k * (seg[cut, 2:4] - seg[cut, 0:2])
        return seg if len(seg) else None


@lru_cache(maxsize=256)
def _glyph(char: str) -> tuple[np.ndarray, ...]:
    """Strokes of ``char`` at cap height 1, scaled so 'H' is 1 wide, centred on x = 0.5 (HP's character body)."""
    centre = text_extent(char, height=1.0).width / 2.0
    return tuple(
        np.column_stack([(p[:, 0] - centre) / _H_WIDTH + 0.5, p[:, 1]]) for p in text_strokes(char, height=1.0)
    )


def _h_width() -> float:
    pts = np.concatenate(text_strokes("H", height=1.0))
    return float(pts[:, 0].max() - pts[:, 0].min())


_H_WIDTH = _h_width()


# -- state --------------------------------------------------------------------------------------


@dataclass
class _Graphics:
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
class _Link:
    """RS-232 configuration set by device control; power-up defaults (7470A manual ch. 10)."""

    hardwire: bool = False
    monitor: int = 0
    mode: int = 0  # 1: ESC.H, 2: ESC.I
    block: int = 80
    enq: int = 0
    ack: bytes = b""
    turnaround_s: float = 0.0
    trigger: int = 0
    echo: int = 0
    terminator: bytes = b"\r"
    initiator: bytes = b""
    char_delay_s: float = 0.0
    xoff: bytes = b""  # ESC.N second parameter: Xoff trigger (Xon/Xoff) or immediate response (ENQ/ACK)

    @property
    def xonxoff(self) -> bool:
        """Xon/Xoff is on when an Xoff character is set and no ENQ character is."""
        return bool(self.xoff) and self.enq == 0

    @property
    def xon_free(self) -> int:
        """Free bytes at which XON is sent again: 128, or one more than the threshold when that is larger."""
        return max(128, self.block + 1)


class _Output:
    """A reply waiting to go out: released at ``ready``, or when the output trigger byte arrives."""

    __slots__ = ("data", "echo", "needs_trigger", "ready", "reply")

    def __init__(self, ready: float, data: bytes, needs_trigger: bool, echo: bool, reply: bool) -> None:
        self.ready = ready
        self.data = data
        self.needs_trigger = needs_trigger
        self.echo = echo
        self.reply = reply


@dataclass
class PlotterStats:
    """Counters the benchmarks read."""

    bytes_received: int = 0
    bytes_overflowed: int = 0
    bytes_ignored: int = 0
    """Bytes dropped unread: plotter programmed off, waiting for the echo terminator, or powered down."""
    commands_executed: int = 0
    starved_time: float = 0.0
    """Seconds the mechanism stood idle with no complete instruction buffered, between two commands."""
    busy_time: float = 0.0
    """Seconds the mechanism spent moving, lifting, dropping or changing pens."""
    hpgl_errors: int = 0
    io_errors: int = 0


class HPGLPlotter:
    """A simulated HP-GL pen plotter speaking RS-232 (a :class:`~pixelpen.sim.base.WireDevice`).

    Create one with :func:`create` or through ``create_simulator("hp7475a", paper="a3")``.  Besides
    the WireDevice methods it offers the operator's controls (``press_view``, ``release_paper_lever``),
    the paper (``segments``, ``display_list``, ``paper_image``, ``save_paper``), the executed-command
    log and the error log, and ``stats``.
    """

    def __init__(
        self,
        spec: ModelSpec,
        *,
        paper: str | None = None,
        pen_colours: tuple[str, ...] | None = None,
        buffer: int | None = None,
        reserve_bug: bool | None = None,
        clock: Clock | None = None,
    ) -> None:
        self.spec = spec
        self.model = spec.name
        self.clock = clock if clock is not None else REAL_CLOCK
        if (paper or spec.default_paper) not in spec.papers:
            raise ConfigError(f"{spec.name}: no paper {paper!r}; this model takes {', '.join(spec.papers)}")
        self.paper = spec.papers[paper or spec.default_paper]
        colours = tuple(pen_colours) if pen_colours is not None else DEFAULT_PEN_COLOURS[: spec.pens]
        self.pen_colours: dict[int, str] = {i + 1: c for i, c in enumerate(colours)}
        self.buffer_size = int(buffer if buffer is not None else spec.buffer)
        self.reserve_bug = spec.name == "hp7475a" if reserve_bug is None else bool(reserve_bug)
        self.stats = PlotterStats()
        self.command_log: list[tuple[float, str]] = []
        """(time, command text) of every instruction executed, in order."""
        self.error_log: list[tuple[float, str, int, str]] = []
        """(time, "HP-GL" or "RS-232", error number, command) of every error the plotter raised."""
        self._segments: list[np.ndarray] = []
        self._segment_pens: list[int] = []
        self._segment_widths: list[float] = []
        self._segment_cache: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._now = self.clock.now()
        self._closed = False
        self._power_up()

    # -- power -----------------------------------------------------------------------------------

    def _power_up(self) -> None:
        """Everything as after switching on (the paper stays)."""
        self._dead = False
        self._on = True
        self._buf = bytearray()
        self._reader = InstructionReader(self.spec.mnemonics, self.spec.recognised)
        self._esc = DeviceControlReader()
        self._link = _Link()
        self._io_error = 0
        self._xoff_sent = False
        self._enq_pending = False
        self._await_echo = False
        self._outputs: deque[_Output] = deque()
        self._motions: deque[_Motion] = deque()
        self._active: _Motion | None = None
        self._active_start = self._now
        self._idle_since: float | None = None
        self._executed_any = False
        self._view = False
        self._lever = False
        self._rotation = 0
        self._hard_clip = self.paper.hard_clip
        self._phys = (0.0, 0.0)
        self._phys_down = False
        self._pen = 0
        self._pos = (0.0, 0.0)
        self._pen_down = False
        self._hpgl_error = 0
        self._error_flag = False
        self._initialized = True  # OS bit 8 is set at power-up
        self._p1p2_changed = False
        self._digitized: tuple[float, float, int] | None = None
        self._in_seen = False
        self._masks = (DEFAULT_E_MASK, 0, 0)
        self._g = self._default_graphics()
        self._set_specials()

    def _status(self) -> int:
        """The OS status byte: 1 pen down, 2 P1/P2 changed, 4 digitized point, 8 initialized, 16 ready, 32 error."""
        return (
            int(self._pen_down)
            | (2 if self._p1p2_changed else 0)
            | (4 if self._digitized is not None else 0)
            | (8 if self._initialized else 0)
            | (0 if self._lever else 16)
            | (32 if self._error_flag else 0)
        )

    def _default_graphics(self) -> _Graphics:
        p1, p2 = self._default_p1p2()
        w, h = self._logical_limits()
        g = _Graphics(p1=p1, p2=p2, window=(0.0, 0.0, float(w), float(h)))
        g.char_size = ("abs", *self._default_char_cm(p1, p2))
        g.cr_point = self._pos
        return g

    def _default_p1p2(self) -> tuple[tuple[float, float], tuple[float, float]]:
        (ax, ay), (bx, by) = self.paper.p1, self.paper.p2
        if self._rotation == 90:
            w = self._hard_clip[0]
            # physical (x, y) -> logical (y, W - x); keep P1 lower-left, P2 upper-right
            return (float(ay), float(w - bx)), (float(by), float(w - ax))
        return (float(ax), float(ay)), (float(bx), float(by))

    def _default_char_cm(self, p1: tuple[float, float], p2: tuple[float, float]) -> tuple[float, float]:
        """SI default: the size SR 0.75,1.5 gives with default P1/P2 (7470A manual, SR)."""
        cm = self.spec.unit_mm / 10.0
        return 0.0075 * abs(p2[0] - p1[0]) * cm, 0.015 * abs(p2[1] - p1[1]) * cm

    # -- WireDevice ------------------------------------------------------------------------------

    def receive(self, data: bytes) -> None:
        """Accept host bytes at the current device time (see the module docstring for what happens to them)."""
        data = bytes(data)
        if self._closed or self._dead:
            self.stats.bytes_ignored += len(data)
            if data:
                state = "closed" if self._closed else "powered down"
                log.debug("%s: %d byte(s) arrived while %s; ignored", self.model, len(data), state)
            return
        self.stats.bytes_received += len(data)
        i = 0
        while i < len(data):
            if self._await_echo:
                j = data.find(bytes([self._link.echo]), i)
                end = len(data) if j < 0 else j + 1
                self.stats.bytes_ignored += end - i
                self._await_echo = j < 0
                i = end
                continue
            if self._esc.active:
                seq, reprocess = self._esc.feed(data[i])
                if not reprocess:
                    i += 1
                if seq is not None:
                    self._device_control(seq)
                continue
            if not self._on:
                j = data.find(b"\x1b", i)
                end = len(data) if j < 0 else j
                self.stats.bytes_ignored += end - i
                if j >= 0:
                    self._esc.start()
                    end += 1
                i = end
                continue
            m = self._specials.search(data, i)
            j = len(data) if m is None else m.start()
            if j > i:
                self._store(data[i:j])
            i = j
            if m is not None:
                self._special(data[j])
                i += 1
        self._run(self._now)

    def take_output(self) -> bytes:
        """Bytes the plotter has sent by now (replies wait for their delays and the output trigger)."""
        out = bytearray()
        while self._outputs and not self._outputs[0].needs_trigger and self._outputs[0].ready <= self._now:
            item = self._outputs.popleft()
            out += item.data
            if item.echo and self._link.echo:
                self._await_echo = True
        return bytes(out)

    def advance_to(self, t: float) -> None:
        """Run the plotter up to clock time ``t`` (never backwards)."""
        if self._closed:
            return
        if self._dead:
            self._now = max(self._now, t)
            return
        self._run(t)

    @property
    def ready_to_receive(self) -> bool:
        """DTR as the plotter drives it: with hardwire handshake (ESC.@ bit 0) high while free >= block size."""
        if self._closed or self._dead:
            return False
        if not self._link.hardwire:
            return True
        return self.free_bytes >= self._link.block

    def next_event_time(self) -> float | None:
        """When the plotter's state next changes by itself: a move ends or a delayed reply goes out."""
        if self._closed or self._dead:
            return None
        times = []
        if self._active is not None:
            times.append(self._active_start + self._active.duration)
        times += [o.ready for o in self._outputs if not o.needs_trigger and o.ready > self._now]
        return min(times) if times else None

    def inject(self, fault: str) -> None:
        """Apply a fault now: 'power-loss', 'reset' (power-up), 'paper-lever' (raise it), 'pause-button' (VIEW)."""
        if fault == "power-loss":
            self._power_loss()
        elif fault == "reset":
            log.info("%s: reset (power-up) at t=%.3f", self.model, self._now)
            self._power_up()
        elif fault == "paper-lever":
            log.info("%s: paper lever raised at t=%.3f: plotting suspended", self.model, self._now)
            self._lever = True
        elif fault == "pause-button":
            self.press_view()
        else:
            raise ConfigError(f"unknown fault {fault!r}; known: power-loss, reset, paper-lever, pause-button")

    def close(self) -> None:
        """Stop the plotter; the paper stays readable."""
        self._closed = True

    # -- operator controls -----------------------------------------------------------------------

    def press_view(self) -> None:
        """Press the VIEW button: suspends plotting (ESC.O 16) or, pressed again, resumes it."""
        self._view = not self._view
        log.info("%s: VIEW %s at t=%.3f", self.model, "pressed: plotting suspended" if self._view else "released", self._now)
        if not self._view:
            self._run(self._now)

    def release_paper_lever(self) -> None:
        """Lower the paper lever again: plotting resumes where it stopped."""
        if self._lever:
            self._lever = False
            log.info("%s: paper lever lowered at t=%.3f: plotting resumes", self.model, self._now)
            self._run(self._now)

    # -- introspection ---------------------------------------------------------------------------

    @property
    def free_bytes(self) -> int:
        """Free buffer space as ESC.B reports it."""
        return self.buffer_size - len(self._buf)

    @property
    def buffered_bytes(self) -> int:
        """Bytes waiting in the input buffer."""
        return len(self._buf)

    @property
    def now(self) -> float:
        """The device time the plotter has run to."""
        return self._now

    @property
    def paused(self) -> bool:
        """True while VIEW or the raised paper lever holds plotting."""
        return self._view or self._lever

    @property
    def pen_position(self) -> tuple[float, float]:
        """Where the pen physically is (physical plotter units, after the moves planned so far)."""
        return self._phys

    @property
    def selected_pen(self) -> int:
        """The pen in the holder (0: none)."""
        return self._pen

    @property
    def hard_clip(self) -> tuple[int, int]:
        """Upper-right hard-clip corner in the current coordinate system (OH's last two numbers)."""
        return self._logical_limits()

    def segments(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every pen-down stroke so far: (N, 4) x0, y0, x1, y1 in physical plotter units, pens (N,), widths mm (N,)."""
        if self._segment_cache is None:
            if self._segments:
                counts = [len(s) for s in self._segments]
                self._segment_cache = (
                    np.concatenate(self._segments),
                    np.repeat(np.asarray(self._segment_pens, dtype=np.int32), counts),
                    np.repeat(np.asarray(self._segment_widths, dtype=np.float64), counts),
                )
            else:
                self._segment_cache = (np.zeros((0, 4)), np.zeros(0, np.int32), np.zeros(0))
        return self._segment_cache

    def display_list(self) -> DisplayList:
        """The paper as a DisplayList: touching same-pen segments joined into polylines, in plotter units."""
        seg, pens, _ = self.segments()
        if not len(seg):
            return DisplayList(unit_mm=self.spec.unit_mm, pen_colours=dict(self.pen_colours))
        breaks = np.ones(len(seg), dtype=bool)
        breaks[1:] = np.any(seg[1:, 0:2] != seg[:-1, 2:4], axis=1) | (pens[1:] != pens[:-1])
        starts = np.flatnonzero(breaks)
        ends = np.append(starts[1:], len(seg))
        # each polyline: its first start point, then every segment's end point
        lengths = ends - starts + 1
        offsets = np.concatenate([[0], np.cumsum(lengths)])
        points = np.empty((offsets[-1], 2))
        points[offsets[:-1]] = seg[starts, 0:2]
        rest = np.ones(offsets[-1], dtype=bool)
        rest[offsets[:-1]] = False
        points[rest] = seg[:, 2:4]
        return DisplayList(
            points, offsets, pens[starts], np.zeros(len(starts), np.int32),
            unit_mm=self.spec.unit_mm, pen_colours=dict(self.pen_colours),
        )

    def paper_image(self, dpi: float = 100.0) -> Canvas:  # noqa: F821 - raster canvas, imported lazily
        """Render the sheet at ``dpi``: white page of the paper size, every stroke in its pen's colour and width."""
        from pixelpen.raster.canvas import Canvas

        if not (isinstance(dpi, (int, float)) and math.isfinite(dpi) and 1 <= dpi <= 2400):
            raise ConfigError(f"paper_image dpi must be a number from 1 to 2400, got {dpi!r}")
        k = dpi / 25.4
        page_w, page_h = self.paper.page_mm
        width, height = max(1, round(page_w * k)), max(1, round(page_h * k))
        ox, oy = self._sheet_origin_mm()
        canvas = Canvas(width, height, "RGB")
        canvas.fill((255, 255, 255))
        seg, pens, widths = self.segments()
        if not len(seg):
            return canvas
        u = self.spec.unit_mm
        px = np.empty_like(seg)
        px[:, 0::2] = (ox + seg[:, 0::2] * u) * k
        px[:, 1::2] = height - (oy + seg[:, 1::2] * u) * k
        pix = np.floor(px).astype(np.int64)
        wpx = np.maximum(1, np.round(widths * k)).astype(np.int64)
        for pen in np.unique(pens):
            colour = self.pen_colours.get(int(pen))
            if colour is None:
                continue  # an empty stall plots dry (warned when the pen was selected)
            rgb = parse_colour(colour)
            mine = pens == pen
            for w in np.unique(wpx[mine]):
                sel = mine & (wpx == w)
                canvas.lines(pix[sel], rgb, width=int(w), cap="round")  # a felt tip is round
        return canvas

    def save_paper(self, path: str | Path, dpi: float = 100.0) -> None:
        """Write the sheet to ``path``: a PNG (``paper_image`` at ``dpi``) or a true-size SVG, by the extension."""
        if paper_format(path) == "png":
            self.paper_image(dpi).save(path)
            return
        dl = self.display_list()
        u = self.spec.unit_mm
        ox, oy = self._sheet_origin_mm()
        page_w, page_h = self.paper.page_mm
        strokes = [
            (int(pen), np.column_stack([ox + pts[:, 0] * u, page_h - (oy + pts[:, 1] * u)]))
            for pen, pts in ((dl.pens[i], dl.stroke(i)) for i in range(len(dl)))
            if int(pen) in self.pen_colours  # an empty stall plots dry
        ]
        widths = self.segments()[2]
        write_paper_svg(path, strokes, (page_w, page_h), self.pen_colours,
                        float(np.median(widths)) if len(widths) else 0.3)

    def _sheet_origin_mm(self) -> tuple[float, float]:
        if self.paper.origin_mm is not None:
            return self.paper.origin_mm
        u = self.spec.unit_mm
        return (
            (self.paper.page_mm[0] - self._hard_clip[0] * u) / 2,
            (self.paper.page_mm[1] - self._hard_clip[1] * u) / 2,
        )

    # -- receiving -------------------------------------------------------------------------------

    def _set_specials(self) -> None:
        """Bytes the receiver must catch before the buffer: ESC, the ENQ character and the output trigger."""
        special = {0x1B}
        if self._link.enq:
            special.add(self._link.enq)
        if self._link.trigger:
            special.add(self._link.trigger)
        self._specials = re.compile(b"[" + b"".join(re.escape(bytes([c])) for c in sorted(special)) + b"]")

    def _special(self, byte: int) -> None:
        if byte == 0x1B:
            self._esc.start()
        elif byte == self._link.enq and self._link.enq:
            self._enquiry()
        elif byte == self._link.trigger and self._link.trigger:
            for o in self._outputs:
                o.needs_trigger = False
                o.ready = max(o.ready, self._now)

    def _store(self, chunk: bytes) -> None:
        """Put HP-GL bytes into the buffer; zero-time instructions run meanwhile; the rest of a full buffer is lost."""
        limit = self.buffer_size - (1 if self.reserve_bug else 0)
        while chunk:
            room = limit - len(self._buf)
            if room > 0:
                self._buf += chunk[:room]
                chunk = chunk[room:]
                self._flow_check()
            before = len(self._buf)
            self._run(self._now)
            if chunk and len(self._buf) < before:
                continue
            if chunk:
                self._io_fault(16, f"buffer overflow: {len(chunk)} byte(s) lost")
                self.stats.bytes_overflowed += len(chunk)
                return

    def _flow_check(self) -> None:
        """Send XOFF/XON and pending ENQ acknowledgements as the free space crosses the thresholds."""
        free = self.free_bytes
        link = self._link
        if link.xonxoff:
            if not self._xoff_sent and free < link.block:
                self._xoff_sent = True
                self._send(link.xoff)
            elif self._xoff_sent and free >= link.xon_free:
                self._xoff_sent = False
                if link.ack:
                    self._send(link.ack)
                else:
                    log.warning("%s: Xon/Xoff on but no Xon character set (ESC.I third parameter)", self.model)
        if self._enq_pending and free >= link.block:
            self._enq_pending = False
            self._send_ack()

    def _enquiry(self) -> None:
        link = self._link
        if link.mode == 1 and link.xoff:  # ESC.N immediate response string goes out at once
            self._send(link.xoff)
        if self.free_bytes >= link.block:
            self._send_ack()
        else:
            self._enq_pending = True

    def _send_ack(self) -> None:
        link = self._link
        if link.mode == 1:
            self._queue(link.ack + link.terminator, trigger=True, echo=True, reply=False)
        else:
            self._queue(link.ack, trigger=False, echo=False, reply=False)

    def _send(self, data: bytes) -> None:
        """Flow-control characters: sent at once, no delays."""
        if data:
            self._outputs.append(_Output(self._now, data, False, False, False))

    def _queue(self, data: bytes, *, trigger: bool, echo: bool, reply: bool) -> None:
        link = self._link
        delay = link.turnaround_s + len(data) * link.char_delay_s
        self._outputs.append(_Output(self._now + delay, data, trigger and bool(link.trigger), echo, reply))

    def _reply(self, text: str, command: str) -> None:
        """Answer an output instruction (HP-GL or device control), unless an answer is still going out."""
        if any(o.reply and (o.needs_trigger or o.ready > self._now) for o in self._outputs):
            self._io_fault(10, f"output instruction {command} while another answer is still going out; ignored")
            return
        self._queue(self._link.initiator + text.encode("ascii") + self._link.terminator, trigger=True, echo=True, reply=True)

    def _io_fault(self, code: int, message: str) -> None:
        self._io_error = code
        self.stats.io_errors += 1
        self.error_log.append((self._now, "RS-232", code, message))
        log.warning("%s: RS-232 error %d at t=%.3f: %s", self.model, code, self._now, message)

    # -- device control --------------------------------------------------------------------------

    def _device_control(self, seq: DeviceControl) -> None:
        if seq.error:
            self._io_fault(seq.error, f"{seq}: {_DEVICE_CONTROL_ERRORS[seq.error]}")
            if seq.error == 11:
                return
        letter = seq.letter
        if not self._on and letter not in "(Y":
            return
        self.command_log.append((self._now, str(seq)))
        handler = getattr(self, "_dc_" + {"(": "on", ")": "off", "@": "config"}.get(letter, letter))
        handler(seq)

    def _dc_on(self, seq: DeviceControl) -> None:
        self._on = True

    def _dc_Y(self, seq: DeviceControl) -> None:
        self._on = True

    def _dc_off(self, seq: DeviceControl) -> None:
        self._on = False

    def _dc_Z(self, seq: DeviceControl) -> None:
        self._on = False

    def _dc_B(self, seq: DeviceControl) -> None:
        self._reply(str(self.free_bytes), str(seq))

    def _dc_L(self, seq: DeviceControl) -> None:
        self._reply(str(self.buffer_size), str(seq))

    def _dc_E(self, seq: DeviceControl) -> None:
        code, self._io_error = self._io_error, 0
        self._reply(str(code), str(seq))

    def _dc_O(self, seq: DeviceControl) -> None:
        status = (8 if not self._buf else 0) + (32 if self._lever else 16 if self._view else 0)
        self._reply(str(status), str(seq))

    def _dc_J(self, seq: DeviceControl) -> None:
        """Abort device-control work in progress: a pending ENQ acknowledgement, answers held for the trigger."""
        self._enq_pending = False
        self._outputs = deque(o for o in self._outputs if not o.needs_trigger)

    def _dc_K(self, seq: DeviceControl) -> None:
        dropped = len(self._buf)
        self._buf.clear()
        terminator = self._reader.label_terminator
        self._reader.reset()
        self._reader.label_terminator = terminator
        self._motions.clear()
        log.info("%s: ESC.K: graphics aborted, %d buffered byte(s) discarded", self.model, dropped)
        self._flow_check()

    def _dc_R(self, seq: DeviceControl) -> None:
        self._xoff_sent = False
        self._enq_pending = False
        self._await_echo = False

    def _dc_config(self, seq: DeviceControl) -> None:
        p = seq.params
        if p and p[0] is not None:
            log.warning("%s: ESC.@ first parameter %d (logical buffer size) is not simulated; ignored", self.model, p[0])
        config = p[1] if len(p) > 1 else None
        if config is None:
            config = 0
        if config > 255:
            self._io_fault(13, f"{seq}: configuration {config} out of range 0-255; defaulted")
            config = 0
        self._link.hardwire = bool(config & 1)
        self._link.monitor = config & 0b1100
        if self._link.monitor & 0b1000:
            log.warning("%s: monitor mode (ESC.@ bit 3) is not simulated; no echo to a terminal", self.model)

    def _handshake(self, seq: DeviceControl, mode: int) -> None:
        p = list(seq.params) + [None] * 2
        link = self._link
        block = p[0]
        link.block = 80 if block is None else block % 256
        enq = p[1] or 0
        if enq > 127:
            self._io_fault(13, f"{seq}: enquiry character {enq} out of range 0-127; defaulted")
            enq = 0
        link.enq = enq
        link.ack = self._ascii_string(seq, seq.params[2:])
        link.mode = mode
        self._set_specials()
        self._flow_check()

    def _dc_H(self, seq: DeviceControl) -> None:
        self._handshake(seq, 1)

    def _dc_I(self, seq: DeviceControl) -> None:
        self._handshake(seq, 2)

    def _ascii_string(self, seq: DeviceControl, values: tuple[int | None, ...]) -> bytes:
        """Up to 10 characters given as decimal codes; 0 ends the string; codes above 127 are range errors."""
        out = bytearray()
        for v in values:
            if v is None:
                continue
            if v == 0:
                break
            if v > 127:
                self._io_fault(13, f"{seq}: character code {v} out of range 0-127; ignored")
                continue
            out.append(v)
        return bytes(out[:10])

    def _dc_M(self, seq: DeviceControl) -> None:
        p = list(seq.params) + [None] * 6
        link = self._link
        delay = p[0] or 0
        if delay > 54612:
            self._io_fault(13, f"{seq}: turnaround delay {delay} out of range 0-54612; defaulted")
            delay = 0
        link.turnaround_s = ((delay * 1.1875) % 65536) / 1.2 / 1000.0  # 7470A manual p. 10-33
        chars = []
        for value in p[1:6]:
            if value is not None and value > 127:
                self._io_fault(13, f"{seq}: character code {value} out of range 0-127; defaulted")
                value = None
            chars.append(value or 0)
        link.trigger, link.echo = chars[0], chars[1]
        terminator = bytes(c for c in chars[2:4] if c)
        link.terminator = terminator if chars[2] else b"\r"
        link.initiator = bytes([chars[4]]) if chars[4] else b""
        self._set_specials()

    def _dc_N(self, seq: DeviceControl) -> None:
        p = list(seq.params) + [None]
        delay = p[0] or 0
        if delay > 65535:
            self._io_fault(13, f"{seq}: intercharacter delay {delay} out of range; defaulted")
            delay = 0
        self._link.char_delay_s = delay / 1000.0
        self._link.xoff = self._ascii_string(seq, seq.params[1:])
        self._flow_check()

    # -- the execution loop ----------------------------------------------------------------------

    def _run(self, t: float) -> None:
        """Execute buffered work up to time ``t``: start motions, complete those that end by ``t``."""
        while True:
            if self._active is None:
                if self.paused or self._dead:
                    break
                if not self._motions:
                    self._fetch()
                if not self._motions:
                    break
                self._active = self._motions.popleft()
                self._active_start = self._now
            end = self._active_start + self._active.duration
            if end > t:
                break
            self._now = end
            self._complete(self._active)
            self._active = None
        self._now = max(self._now, t)

    def _complete(self, motion: _Motion) -> None:
        self.stats.busy_time += motion.duration
        if motion.draw is not None and motion.pen in self.pen_colours:  # an empty stall plots dry
            self._ink(motion.draw, motion.pen, motion.width_mm)

    def _ink(self, segments: np.ndarray, pen: int, width_mm: float) -> None:
        last = self._segments[-1] if self._segments else None
        if (last is not None and len(last) == 1 and last[0, 0] == last[0, 2] and last[0, 1] == last[0, 3]
                and self._segment_pens[-1] == pen and np.array_equal(last[0, :2], segments[0, :2])):
            # the dot a bare PD left is the start of the line drawn from it: one mark, not two
            self._segments.pop()
            self._segment_pens.pop()
            self._segment_widths.pop()
        self._segments.append(segments)
        self._segment_pens.append(pen)
        self._segment_widths.append(width_mm)
        self._segment_cache = None

    def _fetch(self) -> None:
        """Read and execute instructions from the buffer until one produces motion or the buffer runs dry."""
        while not self._motions and self._buf:
            n, item = self._reader.read(self._buf)
            if n == 0 and item is None:
                if len(self._buf) < self.buffer_size - (1 if self.reserve_bug else 0):
                    break
                n, item = self._reader.read(self._buf, full=True)
            del self._buf[:n]
            if item is not None:
                if self._idle_since is not None and self._executed_any:
                    self.stats.starved_time += self._now - self._idle_since
                self._idle_since = None
                self._executed_any = True
                self._execute(item)
            self._flow_check()
        if not self._motions and self._idle_since is None:
            self._idle_since = self._now

    def _power_loss(self) -> None:
        if self._active is not None:
            partial_ink = self._active.drawn_until(self._now - self._active_start)
            if partial_ink is not None and self._active.pen in self.pen_colours:
                self._ink(partial_ink, self._active.pen, self._active.width_mm)
        log.warning(
            "%s: power lost at t=%.3f: %d buffered byte(s) and %d queued move(s) lost",
            self.model, self._now, len(self._buf), len(self._motions) + (self._active is not None),
        )
        self._power_up()
        self._dead = True

    # -- instruction dispatch ---------------------------------------------------------------------

    def _execute(self, item: Instruction) -> None:
        self.stats.commands_executed += 1
        self.command_log.append((self._now, str(item)))
        if item.error:
            self._hpgl_fault(item.error, item, _PARSE_ERRORS[item.error])
            return
        handler = _HANDLERS.get(item.mnemonic)
        if handler is None:
            log.warning("%s: %s is not simulated (the %s knows it); no effect", self.model, item, self.spec.ident)
            return
        try:
            handler(self, item)
        except _HPGLError as exc:
            self._hpgl_fault(exc.code, item, exc.message)
        except (PixelpenError, ValueError, ArithmeticError) as exc:
            self._hpgl_fault(3, item, f"cannot be executed: {exc}")

    def _hpgl_fault(self, code: int, item: Instruction, message: str) -> None:
        self._hpgl_error = code
        if self._masks[0] & (1 << (code - 1)):
            self._error_flag = True
        self.stats.hpgl_errors += 1
        self.error_log.append((self._now, "HP-GL", code, str(item)))
        log.warning("%s: HP-GL error %d at byte %d (%s): %s", self.model, code, item.offset, item, message)

    # -- coordinates -------------------------------------------------------------------------------

    def _logical_limits(self) -> tuple[int, int]:
        w, h = self._hard_clip
        return (h, w) if self._rotation == 90 else (w, h)

    def _to_phys(self, pts: np.ndarray) -> np.ndarray:
        """Logical plotter units (current RO) -> physical plotter units."""
        if self._rotation != 90:
            return pts
        out = np.empty_like(pts)
        out[..., 0] = self._hard_clip[0] - pts[..., 1]
        out[..., 1] = pts[..., 0]
        return out

    def _to_logical(self, x: float, y: float) -> tuple[float, float]:
        if self._rotation != 90:
            return x, y
        return y, self._hard_clip[0] - x

    def _user_to_plotter(self, x: float, y: float) -> tuple[float, float]:
        sc = self._g.scale
        if sc is None:
            return x, y
        (p1x, p1y), (p2x, p2y) = self._g.p1, self._g.p2
        xmin, xmax, ymin, ymax = sc
        return p1x + (x - xmin) * (p2x - p1x) / (xmax - xmin), p1y + (y - ymin) * (p2y - p1y) / (ymax - ymin)

    def _plotter_to_user(self, x: float, y: float) -> tuple[float, float]:
        sc = self._g.scale
        if sc is None:
            return x, y
        (p1x, p1y), (p2x, p2y) = self._g.p1, self._g.p2
        xmin, xmax, ymin, ymax = sc
        return xmin + (x - p1x) * (xmax - xmin) / (p2x - p1x), ymin + (y - p1y) * (ymax - ymin) / (p2y - p1y)

    def _user_delta(self, dx: float, dy: float) -> tuple[float, float]:
        sc = self._g.scale
        if sc is None:
            return dx, dy
        (p1x, p1y), (p2x, p2y) = self._g.p1, self._g.p2
        xmin, xmax, ymin, ymax = sc
        return dx * (p2x - p1x) / (xmax - xmin), dy * (p2y - p1y) / (ymax - ymin)

    def _check_position(self, x: float, y: float) -> tuple[float, float]:
        if not (math.isfinite(x) and math.isfinite(y)) or max(abs(x), abs(y)) > 32768:
            raise _HPGLError(6, f"position {x:.1f},{y:.1f} is outside the plotter's -32768..32767 range")
        return x, y

    def _p1p2_diagonal(self) -> float:
        (p1x, p1y), (p2x, p2y) = self._g.p1, self._g.p2
        return math.hypot(p2x - p1x, p2y - p1y)

    def _phys_point(self, x: float, y: float) -> tuple[float, float]:
        """One logical point in physical plotter units (``_to_phys`` for a scalar pair)."""
        return (self._hard_clip[0] - y, x) if self._rotation == 90 else (x, y)

    def _clip_window(self) -> tuple[float, float, float, float]:
        """IW window in physical plotter units, inside the hard-clip limits."""
        x0, y0, x1, y1 = self._g.window
        (ax, ay), (bx, by) = self._phys_point(x0, y0), self._phys_point(x1, y1)
        w, h = self._hard_clip
        return max(0.0, min(ax, bx)), max(0.0, min(ay, by)), min(float(w), max(ax, bx)), min(float(h), max(ay, by))

    # -- motion planning ----------------------------------------------------------------------------

    def _velocity(self, down: bool) -> tuple[float, float]:
        """(plotter units/s, plotter units/s²) for a pen-down or pen-up move."""
        spec, g = self.spec, self._g
        per_cm = 10.0 / spec.unit_mm
        if not down:
            return spec.max_velocity_cm_s * per_cm, spec.accel_cm_s2 * per_cm
        v = g.velocity.get(self._pen, spec.max_velocity_cm_s)
        a = spec.slow_accel_cm_s2 if g.slow_accel else spec.accel_cm_s2
        return v * per_cm, a * per_cm

    def _pen_to(self, down: bool) -> None:
        if self._phys_down != down:
            if down and not self._pen:
                log.warning("%s: pen down with no pen in the holder (select one with SP): nothing is inked", self.model)
            self._phys_down = down
            self._motions.append(_Motion(self.spec.pen_lift_s, self._phys, self._phys))

    def _dot(self) -> None:
        """Ink a dot where the pen stands (inside the clipping window), as a pen touching the paper does."""
        px, py = self._phys
        x0, y0, x1, y1 = self._clip_window()
        if x0 <= px <= x1 and y0 <= py <= y1:
            dot = np.array([[px, py, px, py]], dtype=np.float64)
            self._motions.append(_Motion(0.0, self._phys, self._phys, draw=dot, pen=self._pen,
                                         width_mm=self._g.pen_thickness_mm))

    def _travel(self, x: float, y: float, draw: bool, dashed: bool = True) -> None:
        """Plan the move from the current position to logical (x, y); ink it if ``draw``.

        The same as ``_plan`` with one point, in scalar arithmetic: single vectors are most of any plot.
        """
        if draw and dashed and self._g.line_type is not None:
            self._plan(np.array([[x, y]], dtype=np.float64), np.array([True]), dashed)
            return
        self._check_position(x, y)
        ax, ay = self._phys_point(*self._pos)
        bx, by = self._phys_point(x, y)
        w, h = self._hard_clip
        target = (min(max(bx, 0.0), float(w)), min(max(by, 0.0), float(h)))
        self._pen_to(draw)
        v, a = self._velocity(draw)
        sx, sy = self._phys
        duration = max(axis_time(abs(target[0] - sx), v, a), axis_time(abs(target[1] - sy), v, a))
        ink = None
        if draw:
            x0, y0, x1, y1 = window = self._clip_window()
            seg = np.array([[ax, ay, bx, by]])
            if x0 <= min(ax, bx) and max(ax, bx) <= x1 and y0 <= min(ay, by) and max(ay, by) <= y1:
                ink = seg
            else:
                clipped, _ = clip_segments(seg, window, method="liang-barsky")
                ink = clipped if len(clipped) else None
        self._motions.append(
            _Motion(duration, self._phys, target, draw=ink, pen=self._pen, width_mm=self._g.pen_thickness_mm, velocity=v, accel=a)
        )
        self._phys = target
        self._pos = (x, y)

    def _plan(self, points: np.ndarray, down: np.ndarray, dashed: bool = True) -> None:
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
                self._plan(pts[:k], down[:k], dashed)
            self._check_position(float(pts[k, 0]), float(pts[k, 1]))
        if not len(pts):
            return
        phys = self._to_phys(np.vstack([self._pos, pts]))
        w, h = self._hard_clip
        clamped = np.column_stack([np.clip(phys[:, 0], 0.0, float(w)), np.clip(phys[:, 1], 0.0, float(h))])
        clamped[0] = self._phys
        (vd, ad), (vu, au) = self._velocity(True), self._velocity(False)
        dist = np.abs(np.diff(clamped, axis=0))
        durations = np.where(
            down,
            np.maximum(_axis_times(dist[:, 0], vd, ad), _axis_times(dist[:, 1], vd, ad)),
            np.maximum(_axis_times(dist[:, 0], vu, au), _axis_times(dist[:, 1], vu, au)),
        ).tolist()
        segs = np.hstack([phys[:-1], phys[1:]])
        inks: list[np.ndarray | None] = [None] * len(pts)
        drawn = np.flatnonzero(down)
        if len(drawn):
            for i, ink in zip(drawn.tolist(), self._inked(segs[drawn], dashed)):
                inks[i] = ink
        ends = [tuple(p) for p in clamped.tolist()]
        pen, width = self._pen, self._g.pen_thickness_mm
        append = self._motions.append
        for i, (duration, is_down) in enumerate(zip(durations, down.tolist())):
            self._pen_to(is_down)
            v, a = (vd, ad) if is_down else (vu, au)
            append(_Motion(duration, ends[i], ends[i + 1], draw=inks[i], pen=pen, width_mm=width, velocity=v, accel=a))
        self._phys = ends[-1]
        self._pos = (float(pts[-1, 0]), float(pts[-1, 1]))

    def _inked(self, segs: np.ndarray, dashed: bool) -> list[np.ndarray | None]:
        """The inked pieces of each physical segment: line type applied (its pattern runs on), window-clipped."""
        g = self._g
        if not dashed or g.line_type is None:
            return self._clip(segs, list(range(len(segs))), len(segs))
        pieces, owners = [], []
        for i, seg in enumerate(segs):
            length = float(math.hypot(seg[2] - seg[0], seg[3] - seg[1]))
            if g.line_type == 0 or length == 0:
                piece = np.array([[seg[2], seg[3], seg[2], seg[3]]])  # LT0 or a zero-length vector: a dot
            else:
                period = max(g.pattern_pct / 100.0 * self._p1p2_diagonal(), length / MAX_DASHES_PER_VECTOR, 1e-9)
                pattern = np.asarray(LINE_PATTERNS[g.line_type]) / 100.0 * period
                piece = _pieces_to_segments(dash_polylines([seg.reshape(2, 2)], pattern, offset=g.dash_pos))
                g.dash_pos = (g.dash_pos + length) % period
            pieces.append(piece)
            owners += [i] * len(piece)
        flat = np.concatenate(pieces) if pieces else np.zeros((0, 4))
        return self._clip(flat, owners, len(segs))

    def _clip(self, pieces: np.ndarray, owners: list[int], count: int) -> list[np.ndarray | None]:
        """Clip pieces to the window and group them by the segment (``owners``) each belongs to."""
        x0, y0, x1, y1 = self._clip_window()
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

    def _draw_path(self, points: np.ndarray, dashed: bool = True) -> None:
        """Pen up to the first logical point, then draw through the rest (pen left down)."""
        down = np.ones(len(points), dtype=bool)
        down[0] = False
        self._plan(points, down, dashed)
        self._pen_to(True)

    def _restore_pen(self, pos: tuple[float, float], pen_down: bool) -> None:
        """After a shape: pen up, back to ``pos``, previous pen state (its dot, if down, as the device makes)."""
        self._pen_to(False)
        self._travel(pos[0], pos[1], draw=False)
        self._g.dash_pos = 0.0
        if pen_down:
            self._pen_to(True)


class _HPGLError(Exception):
    """An HP-GL error raised while executing an instruction (the instruction is ignored)."""

    def __init__(self, code: int, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


_DEVICE_CONTROL_ERRORS = {
    11: "no such device-control instruction",
    12: "invalid byte in the parameters (rest defaulted)",
    14: "too many parameters (extras ignored)",
}
_PARSE_ERRORS = {
    1: "instruction not recognised (illegal character sequence)",
    2: "wrong number of parameters",
    3: "bad parameter (a number too long, or an instruction cut off by a full buffer)",
}


def _pieces_to_segments(polys: list[np.ndarray]) -> np.ndarray:
    """Dash pieces (polylines, a 1-point piece being a dot) -> (K, 4) segments."""
    out = []
    for p in polys:
        if len(p) == 1:
            out.append(np.hstack([p, p]))
        else:
            out.append(np.hstack([p[:-1], p[1:]]))
    return np.concatenate(out) if out else np.zeros((0, 4))


# -- instruction handlers ----------------------------------------------------------------------------
#
# Each handler gets the plotter and the Instruction; it raises _HPGLError(code, why) to reject it.


def _count(item: Instruction, *allowed: int) -> tuple[float, ...]:
    if len(item.params) not in allowed:
        raise _HPGLError(2, f"takes {' or '.join(map(str, allowed))} parameter(s), got {len(item.params)}")
    return item.params


def _in_range(value: float, lo: float, hi: float, what: str) -> float:
    if not lo <= value <= hi:
        raise _HPGLError(3, f"{what} {value:g} is outside {lo:g}..{hi:g}")
    return value


def _coord(value: float) -> float:
    return _in_range(value, -32768.0, COORD_LIMIT, "coordinate")


def _h_in(p: HPGLPlotter, item: Instruction) -> None:
    p._pen_down = False
    p._pen_to(False)
    p._rotation = 0
    p._pos = p._to_logical(*p._phys)
    p._g = p._default_graphics()
    p._reader.label_terminator = ETX
    p._p1p2_changed = False
    p._hpgl_error = 0
    p._error_flag = False
    p._initialized = True
    p._in_seen = True
    p._masks = (DEFAULT_E_MASK, 0, 0)


def _h_df(p: HPGLPlotter, item: Instruction) -> None:
    g = p._default_graphics()
    g.p1, g.p2 = p._g.p1, p._g.p2
    g.char_size = ("abs", *p._default_char_cm(*p._default_p1p2()))
    g.cr_point = p._pos
    p._g = g
    p._reader.label_terminator = ETX


def _h_ip(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 2, 4)
    if not params:
        p._g.p1, p._g.p2 = p._default_p1p2()
    else:
        vals = [_coord(v) for v in params]
        (o1x, o1y), (o2x, o2y) = p._g.p1, p._g.p2
        p1 = (vals[0], vals[1])
        p2 = (vals[2], vals[3]) if len(vals) == 4 else (p1[0] + o2x - o1x, p1[1] + o2y - o1y)
        # P1 and P2 may not coincide on an axis: the plotter moves P2 one unit off (HP-GL convention)
        p2 = (p2[0] + (p2[0] == p1[0]), p2[1] + (p2[1] == p1[1]))
        p._g.p1, p._g.p2 = p1, p2
    p._p1p2_changed = True


def _h_sc(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 4)
    if not params:
        p._g.scale = None
        return
    xmin, xmax, ymin, ymax = (_coord(v) for v in params)
    if xmin == xmax or ymin == ymax:
        raise _HPGLError(3, "SC needs xmin != xmax and ymin != ymax")
    p._g.scale = (xmin, xmax, ymin, ymax)


def _h_iw(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 4)
    w, h = p._logical_limits()
    if not params:
        p._g.window = (0.0, 0.0, float(w), float(h))
        return
    x0, y0, x1, y1 = (_coord(v) for v in params)
    if x0 > x1 or y0 > y1:
        raise _HPGLError(3, "IW needs the lower-left corner first")
    p._g.window = (max(x0, 0.0), max(y0, 0.0), min(x1, float(w)), min(y1, float(h)))


def _h_ro(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 1)
    angle = params[0] if params else 0.0
    if angle not in (0.0, 90.0):
        raise _HPGLError(3, "RO takes 0 or 90")
    if int(angle) == p._rotation:
        return
    p._rotation = int(angle)
    p._g.p1, p._g.p2 = p._default_p1p2()
    w, h = p._logical_limits()
    p._g.window = (0.0, 0.0, float(w), float(h))
    p._pos = p._g.cr_point = p._to_logical(*p._phys)
    p._p1p2_changed = True


def _h_im(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 1, 2, 3)
    masks = [DEFAULT_E_MASK, 0, 0]
    for i, v in enumerate(params):
        masks[i] = int(_in_range(v, 0, 255, "mask"))
    p._masks = (masks[0], masks[1], masks[2])


def _h_ps(p: HPGLPlotter, item: Instruction) -> None:
    (size,) = _count(item, 1)
    metric = p.paper.name in ("a4", "a3")
    names = {0: "a3" if metric else "tabloid", 4: "a4" if metric else "letter"}
    if int(size) not in names or names[int(size)] not in p.spec.papers:
        raise _HPGLError(3, "PS takes 0 (A3/B) or 4 (A4/A)")
    p.paper = p.spec.papers[names[int(size)]]
    p._hard_clip = p.paper.hard_clip
    p._g.p1, p._g.p2 = p._default_p1p2()
    w, h = p._logical_limits()
    p._g.window = (0.0, 0.0, float(w), float(h))


def _h_sp(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 1)
    pen = int(params[0]) if params else 0
    if not 0 <= pen <= p.spec.pens:
        raise _HPGLError(3, f"pen {pen} is not a carousel stall (0-{p.spec.pens})")
    if pen == p._pen:
        return
    if pen and pen not in p.pen_colours:
        log.warning("%s: SP%d selects an empty stall: the plotter cannot tell and plots dry", p.model, pen)
    p._pen_to(False)
    p._motions.append(_Motion(p.spec.pen_change_s, p._phys, p._phys, pen=pen))
    p._pen = pen
    p._g.dash_pos = 0.0


def _h_vs(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 1, 2)
    spec = p.spec
    if not params:
        p._g.velocity.clear()
        p._g.slow_accel = False
        return
    v = params[0]
    if v < 0 or v >= spec.vs_error_from:
        raise _HPGLError(3, f"velocity {v:g} cm/s outside 0..{spec.vs_error_from:g}")
    # 0.38 cm/s steps, 0 meaning 0.38 (7470A manual, VS); the model's maximum caps it
    v = spec.max_velocity_cm_s if v >= spec.max_velocity_cm_s else max(0.38, round(v / 0.38) * 0.38)
    if len(params) == 2:
        pen = int(params[1])
        if not 1 <= pen <= spec.pens:
            raise _HPGLError(3, f"VS pen {pen} is not a carousel stall (1-{spec.pens})")
        p._g.velocity[pen] = v
    else:
        for pen in range(spec.pens + 1):
            p._g.velocity[pen] = v
    p._g.slow_accel = True


def _h_fs(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 1, 2)
    if params:
        _in_range(params[0], 1, 8, "force")
    log.info("%s: %s accepted (pen force has no visible effect in the simulator)", p.model, item)


def _h_pt(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 1)
    p._g.pen_thickness_mm = _in_range(params[0], 0.1, 5.0, "pen thickness (mm)") if params else 0.3


def _h_lt(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 1, 2)
    g = p._g
    if not params:
        g.line_type = None
    else:
        kind = int(_in_range(params[0], 0, 6, "line type"))
        if len(params) == 2:
            length = params[1]
            if not 0 < length <= 127.9999:
                raise _HPGLError(3, f"pattern length {length:g} % outside 0..127.9999")
            g.pattern_pct = length
        g.line_type = kind
    g.dash_pos = 0.0


def _h_pa(p: HPGLPlotter, item: Instruction) -> None:
    p._g.relative = item.mnemonic == "PR"
    if item.params:
        _vector(p, item, p._pen_down)


def _h_pu(p: HPGLPlotter, item: Instruction) -> None:
    p._pen_down = item.mnemonic == "PD"
    if not item.params:
        if not p._pen_down:
            p._g.dash_pos = 0.0
        lowered = p._pen_down and not p._phys_down
        p._pen_to(p._pen_down)
        if lowered:
            p._dot()  # a bare PD lowers the pen where it stands: the tip leaves a dot
        return
    _vector(p, item, p._pen_down)


def _vector(p: HPGLPlotter, item: Instruction, draw: bool) -> None:
    x, y = item.params
    if p._g.relative:
        dx, dy = p._user_delta(_coord(x), _coord(y))
        target = (p._pos[0] + dx, p._pos[1] + dy)
    else:
        target = p._user_to_plotter(_coord(x), _coord(y))
    if not draw:
        p._g.dash_pos = 0.0
    p._travel(*target, draw=draw)
    p._g.cr_point = p._pos
    if p._g.symbol:
        _symbol(p)


def _chord_count(sweep_deg: float, chord: float) -> int:
    chord = abs(chord)
    if chord > 360:
        chord %= 360
    if chord > 180:
        chord = 360 - chord
    chord = max(chord, 0.5)  # assumption: 0 means the smoothest the plotter draws, taken as 0.5 degree
    return max(1, math.ceil(abs(sweep_deg) / chord - 1e-9))


def _arc_points(
    p: HPGLPlotter, centre_user: tuple[float, float], radius: float, start_deg: float, sweep_deg: float, chord: float
) -> np.ndarray:
    """Chord end points (logical plotter units) of an arc given in user units, equal chords (7470A manual CI)."""
    n = _chord_count(sweep_deg, chord)
    theta = np.radians(start_deg + sweep_deg * np.arange(n + 1) / n)
    ux = centre_user[0] + radius * np.cos(theta)
    uy = centre_user[1] + radius * np.sin(theta)
    return np.array([p._user_to_plotter(float(a), float(b)) for a, b in zip(ux, uy)])


def _chord_param(params: tuple[float, ...], index: int) -> float:
    return _in_range(params[index], -32768, 32767, "chord angle") if len(params) > index else 5.0


def _h_ci(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 1, 2)
    radius = _coord(params[0])
    chord = _chord_param(params, 1)
    centre_user = p._plotter_to_user(*p._pos)
    start = 180.0 if radius < 0 else 0.0
    points = _arc_points(p, centre_user, abs(radius), start, 360.0, chord)
    for x, y in points:
        p._check_position(float(x), float(y))
    pos, down = p._pos, p._pen_down
    p._pen_to(False)
    p._draw_path(points)
    p._restore_pen(pos, down)


def _h_aa(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 3, 4)
    cx, cy = _coord(params[0]), _coord(params[1])
    if item.mnemonic == "AR":
        ux, uy = p._plotter_to_user(*p._pos)
        cx, cy = ux + cx, uy + cy
    sweep = _in_range(params[2], -32768, 32767, "arc angle")
    chord = _chord_param(params, 3)
    ux, uy = p._plotter_to_user(*p._pos)
    radius = math.hypot(ux - cx, uy - cy)
    start = math.degrees(math.atan2(uy - cy, ux - cx))
    points = _arc_points(p, (cx, cy), radius, start, sweep, chord)
    for x, y in points[1:]:
        p._travel(float(x), float(y), draw=p._pen_down)
    p._g.cr_point = p._pos


def _rect_corner(p: HPGLPlotter, item: Instruction) -> tuple[float, float]:
    x, y = (_coord(v) for v in _count(item, 2))
    if item.mnemonic in ("ER", "RR"):
        dx, dy = p._user_delta(x, y)
        return p._pos[0] + dx, p._pos[1] + dy
    return p._user_to_plotter(x, y)


def _h_ea(p: HPGLPlotter, item: Instruction) -> None:
    x1, y1 = p._check_position(*_rect_corner(p, item))
    (x0, y0), down = p._pos, p._pen_down
    ring = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]])
    p._pen_to(False)
    p._draw_path(ring)
    p._restore_pen((x0, y0), down)


def _h_ra(p: HPGLPlotter, item: Instruction) -> None:
    x1, y1 = p._check_position(*_rect_corner(p, item))
    (x0, y0), down = p._pos, p._pen_down
    _fill(p, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))
    p._restore_pen((x0, y0), down)


def _wedge_ring(p: HPGLPlotter, item: Instruction) -> np.ndarray:
    params = _count(item, 3, 4)
    radius = _coord(params[0])
    start = _in_range(params[1], -32768, 32767, "start angle")
    sweep = _in_range(params[2], -32768, 32767, "sweep angle")
    chord = _chord_param(params, 3)
    sweep = max(-360.0, min(360.0, sweep))
    centre_user = p._plotter_to_user(*p._pos)
    if radius < 0:
        radius, start = -radius, start + 180.0
    arc = _arc_points(p, centre_user, radius, start, sweep, chord)
    ring = np.vstack([[p._pos], arc, [p._pos]]) if abs(sweep) < 360 else arc
    for x, y in ring:
        p._check_position(float(x), float(y))
    return ring


def _h_ew(p: HPGLPlotter, item: Instruction) -> None:
    ring = _wedge_ring(p, item)
    pos, down = p._pos, p._pen_down
    p._pen_to(False)
    p._draw_path(ring)
    p._restore_pen(pos, down)


def _h_wg(p: HPGLPlotter, item: Instruction) -> None:
    ring = _wedge_ring(p, item)
    pos, down = p._pos, p._pen_down
    _fill(p, ring[:-1] if len(ring) > 3 and np.array_equal(ring[0], ring[-1]) else ring)
    p._restore_pen(pos, down)


def _h_ft(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 1, 2, 3)
    g = p._g
    if not params:
        g.fill_type, g.fill_spacing, g.fill_angle = 1, 0.0, 0.0
        return
    kind = int(_in_range(params[0], 1, 4, "fill type"))
    spacing = _in_range(params[1], 0, 32767, "fill spacing") if len(params) > 1 else g.fill_spacing
    angle = params[2] if len(params) > 2 else g.fill_angle
    g.fill_type, g.fill_spacing, g.fill_angle = kind, spacing, 45.0 * round(angle / 45.0) % 180.0


def _fill(p: HPGLPlotter, ring: np.ndarray) -> None:
    """Fill a polygon (logical plotter units) with the FT pattern: solid (PT spacing) or hatched."""
    g = p._g
    if g.fill_type in (1, 2):
        spacing = g.pen_thickness_mm / p.spec.unit_mm
    elif g.fill_spacing > 0:
        spacing = abs(p._user_delta(g.fill_spacing, 0.0)[0])
    else:
        spacing = 0.01 * p._p1p2_diagonal()
    extent = float(np.hypot(*(ring.max(axis=0) - ring.min(axis=0))))
    if spacing <= 0 or extent / spacing > MAX_FILL_LINES:
        raise _HPGLError(3, f"fill spacing {spacing:.3g} plotter units is too fine for this area")
    angle = math.radians(g.fill_angle)
    lines = hatch(ring, spacing, angle, cross=g.fill_type == 4, join=g.fill_type == 1)
    if g.fill_type == 2:  # unidirectional: every stroke in the hatch direction
        d = np.array([math.cos(angle), math.sin(angle)])
        lines = [ln if float(np.dot(ln[-1] - ln[0], d)) >= 0 else ln[::-1] for ln in lines]
    p._pen_to(False)
    for line in lines:
        p._draw_path(line, dashed=False)
        p._pen_to(False)


def _h_tl(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 1, 2)
    if not params:
        p._g.ticks = (0.5, 0.5)
        return
    tp = _in_range(params[0], -128, 127.9999, "tick length")
    tn = _in_range(params[1], -128, 127.9999, "tick length") if len(params) == 2 else 0.0
    p._g.ticks = (tp, tn)


def _h_xt(p: HPGLPlotter, item: Instruction) -> None:
    tp, tn = p._g.ticks
    (p1x, p1y), (p2x, p2y) = p._g.p1, p._g.p2
    x, y = p._pos
    if item.mnemonic == "XT":
        span = (p2y - p1y) / 100.0
        path = np.array([[x, y + tp * span], [x, y - tn * span]])
    else:
        span = (p2x - p1x) / 100.0
        path = np.array([[x + tp * span, y], [x - tn * span, y]])
    down = p._pen_down
    p._pen_to(False)
    p._draw_path(path, dashed=False)
    p._restore_pen((x, y), down)


# -- labels ------------------------------------------------------------------------------------------


def _char_frame(p: HPGLPlotter) -> tuple[float, float, float]:
    """Character width and height (logical plotter units) and the label direction (radians)."""
    g = p._g
    (p1x, p1y), (p2x, p2y) = g.p1, g.p2
    kind, a, b = g.char_size
    if kind == "abs":
        per_cm = 10.0 / p.spec.unit_mm
        w, h = a * per_cm, b * per_cm
    else:
        w, h = a / 100.0 * (p2x - p1x), b / 100.0 * (p2y - p1y)
    kind, run, rise = g.direction
    if kind == "rel":
        run, rise = run / 100.0 * (p2x - p1x), rise / 100.0 * (p2y - p1y)
    return w, h, math.atan2(rise, run)


def _h_label(p: HPGLPlotter, item: Instruction) -> None:
    w, h, theta = _char_frame(p)
    c, s = math.cos(theta), math.sin(theta)
    advance = np.array([1.5 * w * c, 1.5 * w * s])  # character cell: 1.5 x width by 2 x height
    line = np.array([2.0 * h * s, -2.0 * h * c])  # one line down, perpendicular to the direction
    g = p._g
    paths: list[np.ndarray] = []
    flags: list[np.ndarray] = []
    pos = np.array(p._pos)
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
            log.info("%s: label control character %r has no effect", p.model, ch)
        else:
            if ch != " ":
                pts, down = _glyph_path(p, ch, pos, w, h, theta)
                paths.append(pts)
                flags.append(down)
            pos = pos + advance
    if paths:
        p._plan(np.concatenate(paths), np.concatenate(flags), dashed=False)
    p._pen_to(False)
    p._check_position(float(pos[0]), float(pos[1]))
    p._pos = (float(pos[0]), float(pos[1]))


def _glyph_path(p: HPGLPlotter, ch: str, origin: np.ndarray, w: float, h: float, theta: float) -> tuple[np.ndarray, np.ndarray]:
    """One character's strokes as a path with pen flags, its cell's lower-left corner at ``origin``."""
    c, s = math.cos(theta), math.sin(theta)
    slant = p._g.slant
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


def _symbol(p: HPGLPlotter) -> None:
    """SM: the symbol character centred on the point just plotted."""
    w, h, theta = _char_frame(p)
    c, s = math.cos(theta), math.sin(theta)
    centre = p._pos
    origin = np.array(centre) - np.array([(w / 2) * c - (h / 2) * s, (w / 2) * s + (h / 2) * c])
    down = p._pen_down
    pts, flags = _glyph_path(p, p._g.symbol, origin, w, h, theta)
    if len(pts):
        p._plan(pts, flags, dashed=False)
    p._pen_to(False)
    p._travel(centre[0], centre[1], draw=False)
    if down:
        p._pen_to(True)


def _h_dt(p: HPGLPlotter, item: Instruction) -> None:
    p._reader.label_terminator = ord(item.text) if item.text else ETX


def _h_sm(p: HPGLPlotter, item: Instruction) -> None:
    p._g.symbol = item.text


def _h_di(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 2)
    if not params:
        p._g.direction = ("abs", 1.0, 0.0)
    else:
        run, rise = (_in_range(v, -128, 127.9999, "direction") for v in params)
        if run == 0 and rise == 0:
            raise _HPGLError(3, "run and rise cannot both be 0")
        p._g.direction = ("rel" if item.mnemonic == "DR" else "abs", run, rise)
    p._g.cr_point = p._pos


def _h_si(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 2)
    if item.mnemonic == "SI":
        if not params:
            p._g.char_size = ("abs", *p._default_char_cm(*p._default_p1p2()))
        else:
            w, h = (_in_range(v, -128, 127.9999, "character size (cm)") for v in params)
            p._g.char_size = ("abs", w, h)
    else:
        w, h = (_in_range(v, -128, 127.9999, "character size (%)") for v in params) if params else (0.75, 1.5)
        p._g.char_size = ("rel", w, h)


def _h_sl(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 1)
    p._g.slant = _in_range(params[0], -128, 127.9999, "slant") if params else 0.0


def _h_cp(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 2)
    w, h, theta = _char_frame(p)
    c, s = math.cos(theta), math.sin(theta)
    if not params:  # carriage return and line feed
        line = np.array([2.0 * h * s, -2.0 * h * c])
        p._g.cr_point = tuple(np.array(p._g.cr_point) + line)
        target = p._g.cr_point
    else:
        spaces, lines = (_in_range(v, -128, 127.9999, "CP count") for v in params)
        dx = spaces * 1.5 * w
        dy = lines * 2.0 * h
        target = (p._pos[0] + dx * c - dy * s, p._pos[1] + dx * s + dy * c)
    down = p._pen_down
    p._pen_to(False)
    p._travel(*target, draw=False)
    if down:
        p._pen_to(True)


def _h_charset(p: HPGLPlotter, item: Instruction) -> None:
    params = _count(item, 0, 1)
    n = int(params[0]) if params else 0
    if not 0 <= n < p.spec.charsets:
        raise _HPGLError(5, f"character set {n} unknown (0-{p.spec.charsets - 1})")
    if item.mnemonic == "CS":
        p._g.standard_set = n
    else:
        p._g.alternate_set = n
    if n:
        log.info("%s: character set %d is drawn with the standard glyphs", p.model, n)


def _h_select_set(p: HPGLPlotter, item: Instruction) -> None:
    p._g.alternate = item.mnemonic == "SA"


def _h_uc(p: HPGLPlotter, item: Instruction) -> None:
    """User-defined character: pen control 99 (down) / -99 (up) and increments of w/4, h/8 (7470A UC grid)."""
    w, h, theta = _char_frame(p)
    c, s = math.cos(theta), math.sin(theta)
    origin = p._pos
    x, y = origin
    down = False
    params = list(item.params)
    p._pen_to(False)
    i = 0
    while i < len(params):
        v = params[i]
        if abs(v) >= 99:
            down = v > 0
            i += 1
            continue
        if i + 1 >= len(params):
            raise _HPGLError(2, "an X increment without its Y increment")
        du, dv = v * w / 4.0, params[i + 1] * h / 8.0
        x, y = x + du * c - dv * s, y + du * s + dv * c
        p._travel(x, y, draw=down, dashed=False)
        i += 2
    p._pen_to(False)
    advance = 1.5 * w
    p._travel(origin[0] + advance * c, origin[1] + advance * s, draw=False)
    if p._pen_down:
        p._pen_to(True)


# -- digitizing and output -----------------------------------------------------------------------------


def _h_dp(p: HPGLPlotter, item: Instruction) -> None:
    """Digitize: no operator here, so the point is taken at once where the pen stands (documented)."""
    x, y = p._to_logical(*p._phys)
    p._digitized = (x, y, int(p._pen_down))


def _h_dc(p: HPGLPlotter, item: Instruction) -> None:
    p._digitized = None


def _fmt(v: float) -> str:
    return str(round(v))


def _fmt_user(v: float) -> str:
    if float(v).is_integer():
        return str(int(v))
    return f"{v:.4f}".rstrip("0").rstrip(".")


def _h_output(p: HPGLPlotter, item: Instruction) -> None:
    m = item.mnemonic
    g = p._g
    if m == "OI":
        if p.spec.oi_needs_in and not p._in_seen:
            log.warning("%s: OI before any IN: a 7475A does not answer it", p.model)
            return
        text = p.spec.ident
    elif m == "OS":
        text = str(p._status())
        p._initialized = False
    elif m == "OE":
        text = str(p._hpgl_error)
        p._hpgl_error = 0
        p._error_flag = False
    elif m == "OA":
        x, y = p._to_logical(*p._phys)
        text = f"{_fmt(x)},{_fmt(y)},{int(p._pen_down)}"
    elif m == "OC":
        x, y = p._pos
        if g.scale is not None:
            ux, uy = p._plotter_to_user(x, y)
            text = f"{_fmt_user(round(ux, 4))},{_fmt_user(round(uy, 4))},{int(p._pen_down)}"
        else:
            text = f"{_fmt(x)},{_fmt(y)},{int(p._pen_down)}"
    elif m == "OD":
        x, y, pen = p._digitized if p._digitized is not None else (*p._to_logical(*p._phys), int(p._pen_down))
        text = f"{_fmt(x)},{_fmt(y)},{pen}"
        p._digitized = None
    elif m == "OF":
        per_mm = 1.0 / p.spec.unit_mm
        text = f"{int(per_mm)},{int(per_mm)}"
    elif m == "OH":
        w, h = p._logical_limits()
        text = f"0,0,{w},{h}"
    elif m == "OO":
        text = p.spec.output_options
    elif m == "OP":
        (ax, ay), (bx, by) = g.p1, g.p2
        text = f"{_fmt(ax)},{_fmt(ay)},{_fmt(bx)},{_fmt(by)}"
        p._p1p2_changed = False
    elif m == "OW":
        text = ",".join(_fmt(v) for v in g.window)
    else:  # OT: carousel type 1 and a bit per loaded stall
        mask = sum(1 << (pen - 1) for pen in p.pen_colours if 1 <= pen <= p.spec.pens)
        text = f"1,{mask}"  # assumption: carousel type 1
    p._reply(text, str(item))

_HANDLERS: dict[str, Callable[[HPGLPlotter, Instruction], None]] = {
    "IN": _h_in, "DF": _h_df, "IP": _h_ip, "SC": _h_sc, "IW": _h_iw, "RO": _h_ro, "IM": _h_im, "PS": _h_ps,
    "SP": _h_sp, "VS": _h_vs, "FS": _h_fs, "PT": _h_pt, "LT": _h_lt,
    "PA": _h_pa, "PR": _h_pa, "PU": _h_pu, "PD": _h_pu,
    "CI": _h_ci, "AA": _h_aa, "AR": _h_aa, "EA": _h_ea, "ER": _h_ea, "RA": _h_ra, "RR": _h_ra,
    "EW": _h_ew, "WG": _h_wg, "FT": _h_ft, "TL": _h_tl, "XT": _h_xt, "YT": _h_xt,
    "LB": _h_label, "DT": _h_dt, "SM": _h_sm, "DI": _h_di, "DR": _h_di, "SI": _h_si, "SR": _h_si,
    "SL": _h_sl, "CP": _h_cp, "CA": _h_charset, "CS": _h_charset, "SA": _h_select_set, "SS": _h_select_set,
    "UC": _h_uc, "DP": _h_dp, "DC": _h_dc,
    **{m: _h_output for m in ("OA", "OC", "OD", "OE", "OF", "OH", "OI", "OO", "OP", "OS", "OT", "OW")},
}


# -- construction from URL options ---------------------------------------------------------------------


def _parse_bool(name: str, value: str) -> bool:
    v = value.strip().lower()
    if v in ("1", "true", "yes", "on"):
        return True
    if v in ("0", "false", "no", "off"):
        return False
    raise URLError(f"option {name}={value!r}: expected true/false (1/0, yes/no, on/off)")


def _parse_pens(value: str, stalls: int) -> tuple[str, ...]:
    names = [v.strip() for v in value.split(",")]
    if not value.strip() or any(not n for n in names):
        raise URLError(f"option pens={value!r}: expected comma-separated colours such as 'black,#ff0000,blue'")
    if len(names) > stalls:
        raise URLError(f"option pens={value!r}: {len(names)} colours for a {stalls}-pen carousel")
    out = []
    for n in names:
        try:
            out.append(colour_hex(parse_colour(n)))
        except ConfigError as exc:
            raise URLError(f"option pens={value!r}: {exc}") from None
    return tuple(out)


def create(model: str, /, *, clock: Clock | None = None, **options: str) -> HPGLPlotter:
    """Build the simulator of ``model`` (a key of MODELS) from URL options given as strings.

    Options: ``paper`` (a4, a3, letter/a, tabloid/b as the model has them), ``pens`` (comma-separated
    colours, one per loaded stall), ``buffer`` (input buffer bytes), ``reserve_bug`` (true/false: the
    7475A's overflow when filled to the exact ESC.B figure; default true on the 7475A).
    """
    spec = MODELS.get(model.lower())
    if spec is None:
        raise URLError(f"no HP-GL simulator for model {model!r}; known: {', '.join(MODELS)}")
    unknown = sorted(set(options) - set(OPTIONS))
    if unknown:
        raise URLError(f"{spec.name}: unknown option(s) {', '.join(unknown)}; known: {', '.join(OPTIONS)}")
    kwargs: dict[str, object] = {}
    if "paper" in options:
        name = options["paper"].strip().lower()
        name = PAPER_ALIASES.get(name, name)
        if name not in spec.papers:
            raise URLError(f"{spec.name}: option paper={options['paper']!r}; this model takes {', '.join(spec.papers)}")
        kwargs["paper"] = name
    if "pens" in options:
        kwargs["pen_colours"] = _parse_pens(options["pens"], spec.pens)
    if "buffer" in options:
        try:
            size = int(options["buffer"])
        except ValueError:
            raise URLError(f"{spec.name}: option buffer={options['buffer']!r} must be an integer") from None
        if not 16 <= size <= 1 << 20:
            raise URLError(f"{spec.name}: option buffer={size} must be 16 .. {1 << 20} bytes")
        kwargs["buffer"] = size
    if "reserve_bug" in options:
        kwargs["reserve_bug"] = _parse_bool("reserve_bug", options["reserve_bug"])
    return HPGLPlotter(spec, clock=clock, **kwargs)  # type: ignore[arg-type]


for _name in MODELS:
    register_simulator(_name, partial(create, _name))

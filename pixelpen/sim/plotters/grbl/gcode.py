"""GRBL 1.1 G-code block parser: words, modal groups and the documented error codes, without side effects.

Written from gnea/grbl ``doc/markdown/commands.md`` (modal groups, defaults) and
``doc/csv/error_codes_en_US.csv`` (error numbers).  :func:`parse_block` checks a pre-processed line
(upper case, no spaces or comments) against the parser state and returns either an error code or a
:class:`GBlock` with every target already in machine millimetres; executing it is the simulator's job.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

__all__ = [
    "MM_PER_INCH",
    "MOTION_CCW",
    "MOTION_CW",
    "MOTION_LINEAR",
    "MOTION_NONE",
    "MOTION_SEEK",
    "STATUS",
    "GBlock",
    "GcodeState",
    "Persistent",
    "parse_block",
    "read_float",
]

MM_PER_INCH = 25.4
MAX_INT_DIGITS = 8
MAX_LINE_NUMBER = 9_999_999  # docs: N must be within 1 - 9,999,999
MAX_TOOL_NUMBER = 255
N_COORDINATE_SYSTEM = 6
ARC_RADIUS_TOLERANCE = 0.005  # mm; and 0.1 % of the radius, never above 0.5 mm

MOTION_SEEK, MOTION_LINEAR, MOTION_CW, MOTION_CCW, MOTION_NONE = 0, 1, 2, 3, 80
PROBES = (382, 383, 384, 385)  # G38.2 .. G38.5

STATUS = {
    "expected_letter": 1, "bad_number": 2, "invalid_statement": 3, "negative_value": 4,
    "setting_disabled": 5, "step_pulse_min": 6, "not_idle": 8, "gcode_lock": 9,
    "soft_limit_needs_homing": 10, "overflow": 11, "max_step_rate": 12, "check_door": 13,
    "travel_exceeded": 15, "invalid_jog": 16, "unsupported": 20, "modal_group": 21,
    "undefined_feed": 22, "not_integer": 23, "axis_conflict": 24, "word_repeated": 25,
    "no_axis_words": 26, "invalid_line_number": 27, "value_word_missing": 28,
    "unsupported_coord_sys": 29, "g53_motion_mode": 30, "axis_words_exist": 31,
    "no_axis_words_in_plane": 32, "invalid_target": 33, "arc_radius": 34, "no_offsets_in_plane": 35,
    "unused_words": 36, "g43_axis": 37, "max_tool": 38,
}
"""GRBL 1.1 status codes by name (``error:N`` numbers from doc/csv/error_codes_en_US.csv)."""


@dataclass
class Persistent:
    """What GRBL keeps in EEPROM besides its $ settings: G54-G59, G28 and G30 positions (machine mm)."""

    coords: np.ndarray = field(default_factory=lambda: np.zeros((N_COORDINATE_SYSTEM, 3)))
    g28: np.ndarray = field(default_factory=lambda: np.zeros(3))
    g30: np.ndarray = field(default_factory=lambda: np.zeros(3))


@dataclass
class GcodeState:
    """The G-code parser's modal state and position, as ``$G`` and ``$#`` report it (reset by a soft reset)."""

    motion: int = MOTION_SEEK
    coord_select: int = 0
    plane: int = 0  # 0 G17, 1 G18, 2 G19
    inches: bool = False
    incremental: bool = False
    inverse_time: bool = False
    spindle: int = 5  # 3 M3, 4 M4, 5 M5
    flood: bool = False
    mist: bool = False
    tlo_dynamic: bool = False
    feed_rate: float = 0.0  # mm/min
    spindle_speed: float = 0.0
    tool: int = 0
    line_number: int = 0
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    coord_system: np.ndarray = field(default_factory=lambda: np.zeros(3))
    coord_offset: np.ndarray = field(default_factory=lambda: np.zeros(3))
    tool_length_offset: float = 0.0

    def wco(self) -> np.ndarray:
        """Work coordinate offset: active WCS + G92 + tool length offset (on Z)."""
        w = self.coord_system + self.coord_offset
        w = w.copy()
        w[2] += self.tool_length_offset
        return w

    def copy(self) -> GcodeState:
        """An independent copy (arrays included)."""
        return replace(
            self, position=self.position.copy(), coord_system=self.coord_system.copy(),
            coord_offset=self.coord_offset.copy(),
        )


@dataclass
class GBlock:
    """One parsed, error-checked block: the new modal state and what it asks the machine to do."""

    modal: GcodeState
    """Parser state after the block (position updated to the block's end)."""
    non_modal: str = ""  # "", "G4", "G10", "G28", "G30", "G28.1", "G30.1", "G53", "G92", "G92.1"
    motion_command: bool = False  # axis words execute the motion mode
    target: np.ndarray = field(default_factory=lambda: np.zeros(3))
    """End of the block's motion in machine mm (for G28/G30: the intermediate point)."""
    home: np.ndarray | None = None  # G28/G30 stored position (machine mm)
    arc_offset: np.ndarray | None = None  # arc centre minus start, machine mm
    arc_radius: float = 0.0
    clockwise: bool = False
    dwell: float = 0.0  # seconds
    g10_index: int = -1
    g10_values: np.ndarray | None = None
    feed: float = 0.0  # mm/min (inverse-time: 1/min)
    spindle_changed: bool = False
    speed_changed: bool = False
    coolant_changed: bool = False
    wco_changed: bool = False
    program_flow: int = 0  # 0 running, 1 M0 pause, 2 M2, 30 M30
    axis_words: int = 0
    jog: bool = False
    probe_no_error: bool = False


def read_float(line: str, i: int) -> tuple[float, int] | None:
    """GRBL's ``read_float``: optional sign, digits with one '.', at most 8 significant digits kept.

    Returns (value, index after the number) or None when no digit was read.
    """
    n = len(line)
    negative = False
    if i < n and line[i] in "+-":
        negative = line[i] == "-"
        i += 1
    intval, exp, ndigit, decimal = 0, 0, 0, False
    while i < n:
        c = line[i]
        if "0" <= c <= "9":
            ndigit += 1
            if ndigit <= MAX_INT_DIGITS:
                if decimal:
                    exp -= 1
                intval = intval * 10 + (ord(c) - 48)
            elif not decimal:
                exp += 1
        elif c == "." and not decimal:
            decimal = True
        else:
            break
        i += 1
    if not ndigit:
        return None
    value = float(intval) * (10.0 ** exp) if intval else 0.0
    return (-value if negative else value), i


_G_GROUP = {  # G integer -> modal group (GRBL numbering: 0 non-modal, 1 motion, 2 plane, ...)
    4: 0, 10: 0, 28: 0, 30: 0, 53: 0, 92: 0,
    0: 1, 1: 1, 2: 1, 3: 1, 38: 1, 80: 1,
    17: 2, 18: 2, 19: 2, 90: 3, 91: 3, 93: 5, 94: 5, 20: 6, 21: 6, 40: 7, 43: 8, 49: 8,
    54: 12, 55: 12, 56: 12, 57: 12, 58: 12, 59: 12, 61: 13,
}
_M_GROUP = {0: 4, 1: 4, 2: 4, 30: 4, 3: 7, 4: 7, 5: 7, 7: 8, 8: 8, 9: 8}
_VALUE_WORDS = "FIJKLNPRSTXYZ"


def parse_block(line: str, state: GcodeState, persistent: Persistent, *, jog: bool = False) -> GBlock | int:
    """Parse and check one pre-processed block (``$J=`` jog lines with ``jog=True``) as GRBL 1.1 does.

    Returns an error code (``error:N``) or the block; ``state`` and ``persistent`` are not changed.
    """
    new = state.copy()
    non_modal = ""
    axis_command = ""  # "", "motion", "non_modal", "tlo"
    command_groups: set[int] = set()
    words: dict[str, float] = {}
    axis_words = 0
    ijk_words = 0
    xyz = np.zeros(3)
    ijk = np.zeros(3)
    tlo_g43 = False
    program_flow = 0
    spindle = state.spindle
    flood, mist = state.flood, state.mist
    i = 3 if jog else 0
    if jog:
        new.motion = MOTION_LINEAR
        new.inverse_time = False
    n = len(line)
    while i < n:
        letter = line[i]
        if not ("A" <= letter <= "Z"):
            return STATUS["expected_letter"]
        got = read_float(line, i + 1)
        if got is None:
            return STATUS["bad_number"]
        value, i = got
        if letter in "GM" and not (0.0 <= value < 256.0):
            return STATUS["unsupported"]
        int_value = int(math.trunc(value))
        mantissa = int(round(100 * (value - int_value)))
        if letter == "G":
            if int_value not in _G_GROUP:
                return STATUS["unsupported"]
            group = _G_GROUP[int_value]
            if int_value in (10, 28, 30, 92):
                if mantissa == 0:
                    if axis_command:
                        return STATUS["axis_conflict"]
                    axis_command = "non_modal"
            if group == 0:
                if int_value in (28, 30, 92):
                    if mantissa not in (0, 10):
                        return STATUS["unsupported"]
                    non_modal = f"G{int_value}" + (".1" if mantissa == 10 else "")
                    mantissa = 0
                else:
                    non_modal = f"G{int_value}"
            elif group == 1:
                if int_value != 80:
                    if axis_command:
                        return STATUS["axis_conflict"]
                    axis_command = "motion"
                new.motion = int_value
                if int_value == 38:
                    if mantissa not in (20, 30, 40, 50):
                        return STATUS["unsupported"]
                    new.motion = 380 + mantissa // 10
                    mantissa = 0
            elif group == 2:
                new.plane = int_value - 17
            elif group == 3:
                if mantissa == 0:
                    new.incremental = int_value == 91
                else:
                    group = 4
                    if mantissa != 10 or int_value == 90:
                        return STATUS["unsupported"]
                    mantissa = 0
            elif group == 5:
                new.inverse_time = int_value == 93
            elif group == 6:
                new.inches = int_value == 20
            elif group == 8:
                if axis_command:
                    return STATUS["axis_conflict"]
                axis_command = "tlo"
                if int_value == 49:
                    new.tlo_dynamic = False
                elif mantissa == 10:
                    new.tlo_dynamic = True
                    tlo_g43 = True
                else:
                    return STATUS["unsupported"]
                mantissa = 0
            elif group == 12:
                new.coord_select = int_value - 54
            elif group == 13:
                if mantissa != 0:
                    return STATUS["unsupported"]
            if mantissa > 0:
                return STATUS["not_integer"]
            if group in command_groups:
                return STATUS["modal_group"]
            command_groups.add(group)
        elif letter == "M":
            if mantissa > 0:
                return STATUS["not_integer"]
            if int_value not in _M_GROUP:
                return STATUS["unsupported"]
            group = 100 + _M_GROUP[int_value]
            if int_value in (0, 2, 30):
                program_flow = 1 if int_value == 0 else int_value
            elif int_value in (3, 4, 5):
                spindle = int_value
            elif int_value == 8:
                flood = True
            elif int_value == 9:
                flood = mist = False
            # M1 (optional stop) is ignored; M7 needs ENABLE_M7, off in the default build: no effect
            if group in command_groups:
                return STATUS["modal_group"]
            command_groups.add(group)
        else:
            if letter not in _VALUE_WORDS:
                return STATUS["unsupported"]
            if letter == "T" and value > MAX_TOOL_NUMBER:
                return STATUS["max_tool"]
            if letter in words:
                return STATUS["word_repeated"]
            if letter in "FNPTS" and value < 0.0:
                return STATUS["negative_value"]
            words[letter] = value
            if letter in "XYZ":
                axis_words |= 1 << "XYZ".index(letter)
                xyz["XYZ".index(letter)] = value
            elif letter in "IJK":
                ijk_words |= 1 << "IJK".index(letter)
                ijk["IJK".index(letter)] = value

    # ---- error checking, in GRBL's order -------------------------------------------------------
    if axis_words and not axis_command:
        axis_command = "motion"
    if "N" in words and words["N"] > MAX_LINE_NUMBER:
        return STATUS["invalid_line_number"]
    feed = words.get("F", 0.0)
    if jog:
        if "F" not in words:
            return STATUS["undefined_feed"]
        if new.inches:
            feed *= MM_PER_INCH
    elif new.inverse_time:
        if axis_command == "motion" and new.motion not in (MOTION_NONE, MOTION_SEEK) and "F" not in words:
            return STATUS["undefined_feed"]
    elif not state.inverse_time:
        if "F" in words:
            if new.inches:
                feed *= MM_PER_INCH
        else:
            feed = state.feed_rate
    speed = words.get("S", state.spindle_speed)
    used = {"N", "F", "S", "T"} if not jog else {"N", "F"}
    dwell = 0.0
    if non_modal == "G4":
        if "P" not in words:
            return STATUS["value_word_missing"]
        dwell = words["P"]
        used.add("P")
    axis0, axis1, _ = ((0, 1, 2), (2, 0, 1), (1, 2, 0))[new.plane]
    if new.inches:
        xyz = xyz * MM_PER_INCH
    if axis_command == "tlo" and tlo_g43 and axis_words != 0b100:
        return STATUS["g43_axis"]
    block_coord = state.coord_system.copy()
    if 12 in command_groups and new.coord_select != state.coord_select:
        block_coord = persistent.coords[new.coord_select].copy()

    block = GBlock(modal=new, non_modal=non_modal, axis_words=axis_words, jog=jog, feed=feed)
    target = xyz.copy()
    if non_modal == "G10":
        if not axis_words:
            return STATUS["no_axis_words"]
        if "P" not in words or "L" not in words:
            return STATUS["value_word_missing"]
        p = int(math.trunc(words["P"]))
        if p > N_COORDINATE_SYSTEM:
            return STATUS["unsupported_coord_sys"]
        l_word = int(math.trunc(words["L"]))
        if l_word != 20:
            if l_word == 2:
                if "R" in words:
                    return STATUS["unsupported"]
            else:
                return STATUS["unsupported"]
        used |= {"L", "P"}
        index = p - 1 if p > 0 else new.coord_select
        values = persistent.coords[index].copy()
        for k in range(3):
            if axis_words & (1 << k):
                if l_word == 20:
                    values[k] = state.position[k] - state.coord_offset[k] - xyz[k]
                    if k == 2:
                        values[k] -= state.tool_length_offset
                else:
                    values[k] = xyz[k]
        block.g10_index, block.g10_values = index, values
    elif non_modal == "G92":
        if not axis_words:
            return STATUS["no_axis_words"]
        offset = state.coord_offset.copy()
        for k in range(3):
            if axis_words & (1 << k):
                offset[k] = state.position[k] - block_coord[k] - xyz[k]
                if k == 2:
                    offset[k] -= state.tool_length_offset
        new.coord_offset = offset
    else:
        if axis_command != "tlo" and axis_words:
            for k in range(3):
                if not axis_words & (1 << k):
                    target[k] = state.position[k]
                elif non_modal != "G53":
                    if not new.incremental:
                        target[k] += block_coord[k] + state.coord_offset[k]
                        if k == 2:
                            target[k] += state.tool_length_offset
                    else:
                        target[k] += state.position[k]
        if non_modal in ("G28", "G30"):
            home = (persistent.g28 if non_modal == "G28" else persistent.g30).copy()
            if axis_words:
                for k in range(3):
                    if not axis_words & (1 << k):
                        home[k] = state.position[k]
            else:
                axis_command = ""
            block.home = home
        elif non_modal == "G53" and new.motion not in (MOTION_SEEK, MOTION_LINEAR):
            return STATUS["g53_motion_mode"]

    if new.motion == MOTION_NONE:
        if axis_words:
            return STATUS["axis_words_exist"]
    elif axis_command == "motion":
        if new.motion == MOTION_SEEK:
            if not axis_words:
                axis_command = ""
        else:
            if feed == 0.0:
                return STATUS["undefined_feed"]
            if new.motion == MOTION_LINEAR:
                if not axis_words:
                    axis_command = ""
            elif new.motion in (MOTION_CW, MOTION_CCW):
                error = _check_arc(block, words, state, target, ijk, ijk_words, axis_words, (axis0, axis1), new, used)
                if error:
                    return error
            else:  # probing
                if not axis_words:
                    return STATUS["no_axis_words"]
                if np.array_equal(state.position, target):
                    return STATUS["invalid_target"]
                block.probe_no_error = new.motion in (383, 385)
    if axis_command:
        used |= {"X", "Y", "Z"}
    if set(words) - used:
        return STATUS["unused_words"]

    if jog:
        if command_groups - {0, 3, 6} or non_modal not in ("", "G53") or not axis_words:
            return STATUS["invalid_jog"]

    # ---- the block's effects on the parser state -----------------------------------------------
    block.motion_command = axis_command == "motion" and new.motion != MOTION_NONE
    block.target = target
    block.dwell = dwell
    block.program_flow = program_flow
    if jog:
        block.modal = state.copy()
        block.modal.position = target.copy()
        return block
    new.line_number = int(words.get("N", 0))
    new.feed_rate = feed
    block.speed_changed = speed != state.spindle_speed
    new.spindle_speed = speed
    new.tool = int(math.trunc(words.get("T", state.tool)))
    block.spindle_changed = spindle != state.spindle
    new.spindle = spindle
    block.coolant_changed = (flood, mist) != (state.flood, state.mist)
    new.flood, new.mist = flood, mist
    if axis_command == "tlo":
        new.tool_length_offset = xyz[2] if new.tlo_dynamic else 0.0
        block.wco_changed |= new.tool_length_offset != state.tool_length_offset
    if new.coord_select != state.coord_select:
        new.coord_system = block_coord
        block.wco_changed = True
    if block.g10_index == new.coord_select and block.g10_values is not None:
        new.coord_system = block.g10_values.copy()
        block.wco_changed = True
    if non_modal == "G92":
        block.wco_changed = True
    elif non_modal == "G92.1":
        new.coord_offset = np.zeros(3)
        block.wco_changed = True
    if non_modal in ("G28", "G30") and block.home is not None:
        new.position = block.home.copy()
    if block.motion_command and new.motion not in PROBES:
        new.position = target.copy()
    if program_flow in (2, 30):
        new.motion, new.plane, new.incremental, new.inverse_time = MOTION_LINEAR, 0, False, False
        new.coord_select, new.spindle, new.flood, new.mist = 0, 5, False, False
    return block


def _check_arc(
    block: GBlock, words: dict[str, float], state: GcodeState, target: np.ndarray, ijk: np.ndarray,
    ijk_words: int, axis_words: int, plane: tuple[int, int], new: GcodeState, used: set[str],
) -> int:
    """GRBL's G2/G3 checks (radius and centre-offset formats); fills the block's arc offset and radius."""
    a0, a1 = plane
    block.clockwise = new.motion == MOTION_CW
    if not axis_words:
        return STATUS["no_axis_words"]
    if not axis_words & ((1 << a0) | (1 << a1)):
        return STATUS["no_axis_words_in_plane"]
    x = target[a0] - state.position[a0]
    y = target[a1] - state.position[a1]
    offset = np.zeros(3)
    if "R" in words:
        used.add("R")
        if np.array_equal(state.position, target):
            return STATUS["invalid_target"]
        r = words["R"] * (MM_PER_INCH if new.inches else 1.0)
        h2 = 4.0 * r * r - x * x - y * y
        if h2 < 0:
            return STATUS["arc_radius"]
        h_x2_div_d = -math.sqrt(h2) / math.hypot(x, y)
        if new.motion == MOTION_CCW:
            h_x2_div_d = -h_x2_div_d
        if r < 0:
            h_x2_div_d = -h_x2_div_d
            r = -r
        offset[a0] = 0.5 * (x - y * h_x2_div_d)
        offset[a1] = 0.5 * (y + x * h_x2_div_d)
        block.arc_radius = r
    else:
        if not ijk_words & ((1 << a0) | (1 << a1)):
            return STATUS["no_offsets_in_plane"]
        used.update("IJK")
        offset = ijk * (MM_PER_INCH if new.inches else 1.0)
        target_r = math.hypot(x - offset[a0], y - offset[a1])
        radius = math.hypot(offset[a0], offset[a1])
        delta_r = abs(target_r - radius)
        if delta_r > ARC_RADIUS_TOLERANCE and (delta_r > 0.5 or delta_r > 0.001 * radius):
            return STATUS["invalid_target"]
        block.arc_radius = radius
    block.arc_offset = offset
    return 0


def arc_points(
    start: np.ndarray, target: np.ndarray, offset: np.ndarray, radius: float, plane: int,
    clockwise: bool, tolerance: float,
) -> np.ndarray:
    """Chord end points GRBL's ``mc_arc`` feeds the planner for an arc (the last one is the target).

    The segment count is floor(½·|θ|·r / √(tol·(2r − tol))), as in motion_control.c; points lie
    exactly on the circle (vectorised, no small-angle drift).  Returns (N, 3) machine mm, N >= 1.
    """
    a0, a1, al = ((0, 1, 2), (2, 0, 1), (1, 2, 0))[plane]
    c0 = start[a0] + offset[a0]
    c1 = start[a1] + offset[a1]
    r0, r1 = -offset[a0], -offset[a1]
    rt0, rt1 = target[a0] - c0, target[a1] - c1
    travel = math.atan2(r0 * rt1 - r1 * rt0, r0 * rt0 + r1 * rt1)
    eps = 5e-7
    if clockwise:
        if travel >= -eps:
            travel -= 2 * math.pi
    elif travel <= eps:
        travel += 2 * math.pi
    denom = math.sqrt(max(tolerance * (2 * radius - tolerance), 1e-30))
    segments = int(math.floor(abs(0.5 * travel * radius) / denom)) if radius > 0 else 0
    segments = min(segments, 100_000)
    if segments <= 1:
        return target.reshape(1, 3).copy()
    k = np.arange(1, segments)
    theta = math.atan2(r1, r0) + travel * k / segments
    pts = np.empty((segments, 3))
    pts[:-1, a0] = c0 + radius * np.cos(theta)
    pts[:-1, a1] = c1 + radius * np.sin(theta)
    pts[:-1, al] = start[al] + (target[al] - start[al]) * k / segments
    pts[-1] = target
    return pts

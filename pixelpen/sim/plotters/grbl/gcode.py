"""GRBL 1.1 G-code block parser, along ``gc_execute_line``'s own steps, without side effects.

Written from gnea/grbl ``doc/markdown/commands.md`` and ``doc/csv/error_codes_en_US.csv``, with the
structure of ``grbl/gcode.c``: STEP 1 initialises the block from the parser state, STEP 2 imports every
word (modal-group violations refused there), STEP 3 error-checks the block in the order of execution
(the numbered sub-steps [0] .. [21]), STEP 4 works out the parser state the block leaves (the controller
then executes the block in the same order).  :func:`parse_block` takes a pre-processed line (upper case,
no spaces or comments) and returns an error code or a :class:`GBlock` whose targets are machine mm.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from pixelpen.sim.plotters.grbl.arcs import arc_points
from pixelpen.sim.plotters.grbl.modal import (
    ARC_RADIUS_TOLERANCE,
    MAX_LINE_NUMBER,
    MAX_TOOL_NUMBER,
    MM_PER_INCH,
    MOTION_CCW,
    MOTION_CW,
    MOTION_LINEAR,
    MOTION_NONE,
    MOTION_SEEK,
    N_COORDINATE_SYSTEM,
    PROBES,
    STATUS,
    GBlock,
    GcodeState,
    Persistent,
    read_float,
)

__all__ = ["arc_points", "parse_block"]
"""The parser; the state and block types it uses (``GcodeState``, ``GBlock``, ``STATUS``...) import from here too."""

_G_GROUP = {  # G integer -> modal group (GRBL numbering: 0 non-modal, 1 motion, 2 plane, ...)
    4: 0, 10: 0, 28: 0, 30: 0, 53: 0, 92: 0,
    0: 1, 1: 1, 2: 1, 3: 1, 38: 1, 80: 1,
    17: 2, 18: 2, 19: 2, 90: 3, 91: 3, 93: 5, 94: 5, 20: 6, 21: 6, 40: 7, 43: 8, 49: 8,
    54: 12, 55: 12, 56: 12, 57: 12, 58: 12, 59: 12, 61: 13,
}
_M_GROUP = {0: 4, 1: 4, 2: 4, 30: 4, 3: 7, 4: 7, 5: 7, 7: 8, 8: 8, 9: 8}
_VALUE_WORDS = "FIJKLNPRSTXYZ"
_PLANE_AXES = ((0, 1, 2), (2, 0, 1), (1, 2, 0))
"""G17, G18, G19: (first, second, linear) axis of the plane."""


def parse_block(line: str, state: GcodeState, persistent: Persistent, *, jog: bool = False) -> GBlock | int:
    """Parse and check one pre-processed block (``$J=`` jog lines with ``jog=True``) as GRBL 1.1 does.

    Returns an error code (``error:N``) or the block; ``state`` and ``persistent`` are not changed.
    """
    return _BlockParser(line, state, persistent, jog).parse()


class _Refused(Exception):
    """A check failed: the block is answered with ``error:code``."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self.code = STATUS[name]


class _BlockParser:
    """One block through gc_execute_line's steps; each step one method, each failing check raises _Refused."""

    def __init__(self, line: str, state: GcodeState, persistent: Persistent, jog: bool) -> None:
        """STEP 1: initialise the block from the current modes (a jog is G1 in units per minute)."""
        self.line, self.state, self.persistent, self.jog = line, state, persistent, jog
        self.new = state.copy()
        self.block = GBlock(modal=self.new, jog=jog)
        self.non_modal = ""
        self.axis_command = ""  # "", "motion", "non_modal", "tlo"
        self.command_groups: set[int] = set()
        self.words: dict[str, float] = {}
        self.axis_words = 0
        self.ijk_words = 0
        self.xyz = np.zeros(3)
        self.ijk = np.zeros(3)
        self.tlo_g43 = False
        self.program_flow = 0
        self.spindle = state.spindle
        self.flood, self.mist = state.flood, state.mist
        self.feed = 0.0
        self.speed = state.spindle_speed
        self.dwell = 0.0
        self.used = {"N", "F", "S", "T"} if not jog else {"N", "F"}
        self.block_coord = state.coord_system.copy()
        self.target = np.zeros(3)
        if jog:
            self.new.motion = MOTION_LINEAR
            self.new.inverse_time = False

    def parse(self) -> GBlock | int:
        """Run STEPs 2 to 4: the checked block, or the error code of the first check that failed."""
        try:
            self.import_words()
            self.check()
        except _Refused as refused:
            return refused.code
        return self.update_state()

    # ---- STEP 2: import all g-code words -------------------------------------------------------------
    def import_words(self) -> None:
        """STEP 2: read every word; G and M commands join their modal group, value words are stored."""
        line, i = self.line, 3 if self.jog else 0
        while i < len(line):
            letter = line[i]
            if not ("A" <= letter <= "Z"):
                raise _Refused("expected_letter")
            got = read_float(line, i + 1)
            if got is None:
                raise _Refused("bad_number")
            value, i = got
            if letter in "GM" and not (0.0 <= value < 256.0):
                raise _Refused("unsupported")
            code = math.trunc(value)
            mantissa = round(100 * (value - code))
            if letter == "G":
                self._g_command(code, mantissa)
            elif letter == "M":
                self._m_command(code, mantissa)
            else:
                self._value_word(letter, value)

    def _claim_axis_words(self, kind: str) -> None:
        """A command that uses the block's axis words; a second one is error:24."""
        if self.axis_command:
            raise _Refused("axis_conflict")
        self.axis_command = kind

    def _g_command(self, code: int, mantissa: int) -> None:
        if code not in _G_GROUP:
            raise _Refused("unsupported")
        if code in (10, 28, 30, 92) and mantissa == 0:
            self._claim_axis_words("non_modal")
        group, mantissa = _G_COMMANDS[_G_GROUP[code]](self, code, mantissa)
        if mantissa > 0:
            raise _Refused("not_integer")
        self._join_group(group)

    def _join_group(self, group: int) -> None:
        """One command per modal group and block (error:21)."""
        if group in self.command_groups:
            raise _Refused("modal_group")
        self.command_groups.add(group)

    def _g_non_modal(self, code: int, mantissa: int) -> tuple[int, int]:
        """G4, G10, G28(.1), G30(.1), G53, G92(.1)."""
        if code in (28, 30, 92):
            if mantissa not in (0, 10):
                raise _Refused("unsupported")
            self.non_modal = f"G{code}" + (".1" if mantissa == 10 else "")
            return 0, 0
        self.non_modal = f"G{code}"
        return 0, mantissa

    def _g_motion(self, code: int, mantissa: int) -> tuple[int, int]:
        """G0, G1, G2, G3, G38.2-G38.5, G80."""
        if code != 80:
            self._claim_axis_words("motion")
        self.new.motion = code
        if code == 38:
            if mantissa not in (20, 30, 40, 50):
                raise _Refused("unsupported")
            self.new.motion = 380 + mantissa // 10
            mantissa = 0
        return 1, mantissa

    def _g_plane(self, code: int, mantissa: int) -> tuple[int, int]:
        """G17, G18, G19."""
        self.new.plane = code - 17
        return 2, mantissa

    def _g_distance(self, code: int, mantissa: int) -> tuple[int, int]:
        """G90, G91; G91.1 (arc distance, the only one GRBL has) is modal group 4."""
        if mantissa == 0:
            self.new.incremental = code == 91
            return 3, 0
        if mantissa != 10 or code == 90:
            raise _Refused("unsupported")
        return 4, 0

    def _g_feed_mode(self, code: int, mantissa: int) -> tuple[int, int]:
        """G93, G94."""
        self.new.inverse_time = code == 93
        return 5, mantissa

    def _g_units(self, code: int, mantissa: int) -> tuple[int, int]:
        """G20, G21."""
        self.new.inches = code == 20
        return 6, mantissa

    def _g_cutter(self, code: int, mantissa: int) -> tuple[int, int]:
        """G40 (cutter compensation off: already off)."""
        return 7, mantissa

    def _g_tool_length(self, code: int, mantissa: int) -> tuple[int, int]:
        """G43.1 (dynamic tool length offset), G49."""
        self._claim_axis_words("tlo")
        if code == 49:
            self.new.tlo_dynamic = False
        elif mantissa == 10:
            self.new.tlo_dynamic = True
            self.tlo_g43 = True
        else:
            raise _Refused("unsupported")
        return 8, 0

    def _g_coordinate_system(self, code: int, mantissa: int) -> tuple[int, int]:
        """G54 .. G59."""
        self.new.coord_select = code - 54
        return 12, mantissa

    def _g_path_control(self, code: int, mantissa: int) -> tuple[int, int]:
        """G61 (G61.1 and G64 are not supported)."""
        if mantissa != 0:
            raise _Refused("unsupported")
        return 13, mantissa

    def _m_command(self, code: int, mantissa: int) -> None:
        """M0, M1, M2, M30 (program flow), M3, M4, M5 (spindle), M7, M8, M9 (coolant)."""
        if mantissa > 0:
            raise _Refused("not_integer")
        if code not in _M_GROUP:
            raise _Refused("unsupported")
        if code in (0, 2, 30):
            self.program_flow = 1 if code == 0 else code
        elif code in (3, 4, 5):
            self.spindle = code
        elif code == 8:
            self.flood = True
        elif code == 9:
            self.flood = self.mist = False
        # M1 (optional stop) is ignored; M7 needs ENABLE_M7, off in the default build: no effect
        self._join_group(100 + _M_GROUP[code])

    def _value_word(self, letter: str, value: float) -> None:
        if letter not in _VALUE_WORDS:
            raise _Refused("unsupported")
        if letter == "T" and value > MAX_TOOL_NUMBER:
            raise _Refused("max_tool")
        if letter in self.words:
            raise _Refused("word_repeated")
        if letter in "FNPTS" and value < 0.0:
            raise _Refused("negative_value")
        self.words[letter] = value
        if letter in "XYZ":
            self.axis_words |= 1 << "XYZ".index(letter)
            self.xyz["XYZ".index(letter)] = value
        elif letter in "IJK":
            self.ijk_words |= 1 << "IJK".index(letter)
            self.ijk["IJK".index(letter)] = value

    # ---- STEP 3: error-check all commands and values -------------------------------------------------
    def check(self) -> None:
        """STEP 3: the checks in the order of execution; values end in machine mm (feed in mm/min)."""
        self._check_common()
        self._check_feed()
        self._check_dwell()
        self._check_units_and_plane()
        self._check_tool_length()
        self._check_coordinate_system()
        self._check_non_modal()
        self._check_motion()
        self._check_unused_words()
        self._check_jog()

    def _check_common(self) -> None:
        """[0] Axis words with no command use the motion mode; the line number is in range."""
        if self.axis_words and not self.axis_command:
            self.axis_command = "motion"
        if "N" in self.words and self.words["N"] > MAX_LINE_NUMBER:
            raise _Refused("invalid_line_number")

    def _check_feed(self) -> None:
        """[2] Feed rate mode, [3] feed rate (a jog needs its own F), [4] spindle speed."""
        words, new = self.words, self.new
        self.feed = words.get("F", 0.0)
        if self.jog:
            if "F" not in words:
                raise _Refused("undefined_feed")
            if new.inches:
                self.feed *= MM_PER_INCH
        elif new.inverse_time:
            if self.axis_command == "motion" and new.motion not in (MOTION_NONE, MOTION_SEEK) and "F" not in words:
                raise _Refused("undefined_feed")
        elif not self.state.inverse_time:
            if "F" not in words:
                self.feed = self.state.feed_rate
            elif new.inches:
                self.feed *= MM_PER_INCH
        self.speed = words.get("S", self.state.spindle_speed)

    def _check_dwell(self) -> None:
        """[10] G4 needs its P word (seconds)."""
        if self.non_modal == "G4":
            if "P" not in self.words:
                raise _Refused("value_word_missing")
            self.dwell = self.words["P"]
            self.used.add("P")

    def _check_units_and_plane(self) -> None:
        """[11] Active plane (taken where arcs need it), [12] length units: axis words to mm."""
        if self.new.inches:
            self.xyz = self.xyz * MM_PER_INCH

    def _check_tool_length(self) -> None:
        """[14] G43.1 takes a Z word and no other axis word."""
        if self.axis_command == "tlo" and self.tlo_g43 and self.axis_words != 0b100:
            raise _Refused("g43_axis")

    def _check_coordinate_system(self) -> None:
        """[15] A newly selected G54-G59 applies to this block's own targets."""
        if 12 in self.command_groups and self.new.coord_select != self.state.coord_select:
            self.block_coord = self.persistent.coords[self.new.coord_select].copy()

    def _check_non_modal(self) -> None:
        """[19] G10 coordinate data, G92 axis offsets, or the machine target (G28/G30 positions, G53)."""
        self.target = self.xyz.copy()
        if self.non_modal == "G10":
            self._check_g10()
        elif self.non_modal == "G92":
            self._check_g92()
        else:
            self._check_target()

    def _check_g10(self) -> None:
        """G10 L2/L20 Pn: the stored work coordinate system it writes."""
        words, state = self.words, self.state
        if not self.axis_words:
            raise _Refused("no_axis_words")
        if "P" not in words or "L" not in words:
            raise _Refused("value_word_missing")
        p = math.trunc(words["P"])
        if p > N_COORDINATE_SYSTEM:
            raise _Refused("unsupported_coord_sys")
        l_word = math.trunc(words["L"])
        if l_word not in (2, 20) or (l_word == 2 and "R" in words):
            raise _Refused("unsupported")
        self.used |= {"L", "P"}
        index = p - 1 if p > 0 else self.new.coord_select
        values = self.persistent.coords[index].copy()
        for k in self._given_axes():
            if l_word == 20:
                values[k] = state.position[k] - state.coord_offset[k] - self.xyz[k]
                if k == 2:
                    values[k] -= state.tool_length_offset
            else:
                values[k] = self.xyz[k]
        self.block.g10_index, self.block.g10_values = index, values

    def _check_g92(self) -> None:
        """G92: the offset that makes the current position read as the given coordinates."""
        state = self.state
        if not self.axis_words:
            raise _Refused("no_axis_words")
        offset = state.coord_offset.copy()
        for k in self._given_axes():
            offset[k] = state.position[k] - self.block_coord[k] - self.xyz[k]
            if k == 2:
                offset[k] -= state.tool_length_offset
        self.new.coord_offset = offset

    def _check_target(self) -> None:
        """The block's target in machine mm; G28/G30 fetch their stored position; G53 only with G0/G1."""
        if self.axis_command != "tlo" and self.axis_words:
            self._machine_target()
        if self.non_modal in ("G28", "G30"):
            home = (self.persistent.g28 if self.non_modal == "G28" else self.persistent.g30).copy()
            if self.axis_words:
                for k in range(3):
                    if not self.axis_words & (1 << k):
                        home[k] = self.state.position[k]
            else:
                self.axis_command = ""
            self.block.home = home
        elif self.non_modal == "G53" and self.new.motion not in (MOTION_SEEK, MOTION_LINEAR):
            raise _Refused("g53_motion_mode")

    def _machine_target(self) -> None:
        """Work (or G53 machine, or G91 incremental) axis words to machine mm; missing axes stay put."""
        state, target = self.state, self.target
        for k in range(3):
            if not self.axis_words & (1 << k):
                target[k] = state.position[k]
            elif self.non_modal == "G53":
                continue
            elif self.new.incremental:
                target[k] += state.position[k]
            else:
                target[k] += self.block_coord[k] + state.coord_offset[k]
                if k == 2:
                    target[k] += state.tool_length_offset

    def _given_axes(self) -> list[int]:
        """The axes (0 X, 1 Y, 2 Z) the block has words for."""
        return [k for k in range(3) if self.axis_words & (1 << k)]

    def _check_motion(self) -> None:
        """[20] Motion modes: G80 takes no axis words, G1-G3 and probes need a feed, arcs and probes a target."""
        motion = self.new.motion
        if motion == MOTION_NONE:
            if self.axis_words:
                raise _Refused("axis_words_exist")
            return
        if self.axis_command != "motion":
            return
        if motion != MOTION_SEEK and self.feed == 0.0:
            raise _Refused("undefined_feed")
        if motion in (MOTION_SEEK, MOTION_LINEAR):
            if not self.axis_words:
                self.axis_command = ""
        elif motion in (MOTION_CW, MOTION_CCW):
            self._check_arc()
        else:
            self._check_probe()

    def _check_arc(self) -> None:
        """G2/G3: the radius or centre-offset form; fills the block's arc offset and radius."""
        a0, a1, _ = _PLANE_AXES[self.new.plane]
        block, state = self.block, self.state
        block.clockwise = self.new.motion == MOTION_CW
        if not self.axis_words:
            raise _Refused("no_axis_words")
        if not self.axis_words & ((1 << a0) | (1 << a1)):
            raise _Refused("no_axis_words_in_plane")
        x = self.target[a0] - state.position[a0]
        y = self.target[a1] - state.position[a1]
        if "R" in self.words:
            self.used.add("R")
            block.arc_offset, block.arc_radius = self._arc_by_radius(x, y, a0, a1)
        else:
            if not self.ijk_words & ((1 << a0) | (1 << a1)):
                raise _Refused("no_offsets_in_plane")
            self.used.update("IJK")
            block.arc_offset, block.arc_radius = self._arc_by_offset(x, y, a0, a1)

    def _arc_by_radius(self, x: float, y: float, a0: int, a1: int) -> tuple[np.ndarray, float]:
        """R form: the centre on the side the sign of R and the direction choose."""
        if np.array_equal(self.state.position, self.target):
            raise _Refused("invalid_target")
        r = self.words["R"] * (MM_PER_INCH if self.new.inches else 1.0)
        h2 = 4.0 * r * r - x * x - y * y
        if h2 < 0:
            raise _Refused("arc_radius")
        h_x2_div_d = -math.sqrt(h2) / math.hypot(x, y)
        if self.new.motion == MOTION_CCW:
            h_x2_div_d = -h_x2_div_d
        if r < 0:
            h_x2_div_d = -h_x2_div_d
            r = -r
        offset = np.zeros(3)
        offset[a0] = 0.5 * (x - y * h_x2_div_d)
        offset[a1] = 0.5 * (y + x * h_x2_div_d)
        return offset, r

    def _arc_by_offset(self, x: float, y: float, a0: int, a1: int) -> tuple[np.ndarray, float]:
        """IJK form: start and end must lie on one circle (within GRBL's tolerance)."""
        offset = self.ijk * (MM_PER_INCH if self.new.inches else 1.0)
        target_r = math.hypot(x - offset[a0], y - offset[a1])
        radius = math.hypot(offset[a0], offset[a1])
        delta_r = abs(target_r - radius)
        if delta_r > ARC_RADIUS_TOLERANCE and (delta_r > 0.5 or delta_r > 0.001 * radius):
            raise _Refused("invalid_target")
        return offset, radius

    def _check_probe(self) -> None:
        """G38.x: axis words and a target other than here."""
        if not self.axis_words:
            raise _Refused("no_axis_words")
        if np.array_equal(self.state.position, self.target):
            raise _Refused("invalid_target")
        self.block.probe_no_error = self.new.motion in (383, 385)

    def _check_unused_words(self) -> None:
        """[0] Every value word was used by some command (error:36 otherwise)."""
        if self.axis_command:
            self.used |= {"X", "Y", "Z"}
        if set(self.words) - self.used:
            raise _Refused("unused_words")

    def _check_jog(self) -> None:
        """$J= takes only G20/G21, G90/G91, G53 and axis words (error:16)."""
        if self.jog and (self.command_groups - {0, 3, 6} or self.non_modal not in ("", "G53") or not self.axis_words):
            raise _Refused("invalid_jog")

    # ---- STEP 4: the parser state the block leaves ---------------------------------------------------
    def update_state(self) -> GBlock:
        """STEP 4: the block with the parser state it leaves, in the order of execution."""
        block = self.block
        block.non_modal, block.axis_words, block.feed = self.non_modal, self.axis_words, self.feed
        block.motion_command = self.axis_command == "motion" and self.new.motion != MOTION_NONE
        block.target = self.target
        block.dwell = self.dwell
        block.program_flow = self.program_flow
        if self.jog:
            block.modal = self.state.copy()
            block.modal.position = self.target.copy()
            return block
        self._update_modes()
        self._update_offsets()
        self._update_position()
        self._update_program_flow()
        return block

    def _update_modes(self) -> None:
        """[1]-[8] Line number, feed rate, spindle speed, tool, spindle and coolant state."""
        new, state, block = self.new, self.state, self.block
        new.line_number = int(self.words.get("N", 0))
        new.feed_rate = self.feed
        block.speed_changed = self.speed != state.spindle_speed
        new.spindle_speed = self.speed
        new.tool = math.trunc(self.words.get("T", state.tool))
        block.spindle_changed = self.spindle != state.spindle
        new.spindle = self.spindle
        block.coolant_changed = (self.flood, self.mist) != (state.flood, state.mist)
        new.flood, new.mist = self.flood, self.mist

    def _update_offsets(self) -> None:
        """[14] tool length offset, [15] coordinate system, [19] G10 into the active system, G92, G92.1."""
        new, state, block = self.new, self.state, self.block
        if self.axis_command == "tlo":
            new.tool_length_offset = self.xyz[2] if new.tlo_dynamic else 0.0
            block.wco_changed |= new.tool_length_offset != state.tool_length_offset
        if new.coord_select != state.coord_select:
            new.coord_system = self.block_coord
            block.wco_changed = True
        if block.g10_index == new.coord_select and block.g10_values is not None:
            new.coord_system = block.g10_values.copy()
            block.wco_changed = True
        if self.non_modal == "G92":
            block.wco_changed = True
        elif self.non_modal == "G92.1":
            new.coord_offset = np.zeros(3)
            block.wco_changed = True

    def _update_position(self) -> None:
        """[19] G28/G30 end at their stored position, [20] a motion (not a probe: that ends where it stops)."""
        if self.non_modal in ("G28", "G30") and self.block.home is not None:
            self.new.position = self.block.home.copy()
        if self.block.motion_command and self.new.motion not in PROBES:
            self.new.position = self.target.copy()

    def _update_program_flow(self) -> None:
        """[21] M2/M30 restore the default modes."""
        new = self.new
        if self.program_flow in (2, 30):
            new.motion, new.plane, new.incremental, new.inverse_time = MOTION_LINEAR, 0, False, False
            new.coord_select, new.spindle, new.flood, new.mist = 0, 5, False, False


_G_COMMANDS: dict[int, Callable[[_BlockParser, int, int], tuple[int, int]]] = {
    0: _BlockParser._g_non_modal,
    1: _BlockParser._g_motion,
    2: _BlockParser._g_plane,
    3: _BlockParser._g_distance,
    5: _BlockParser._g_feed_mode,
    6: _BlockParser._g_units,
    7: _BlockParser._g_cutter,
    8: _BlockParser._g_tool_length,
    12: _BlockParser._g_coordinate_system,
    13: _BlockParser._g_path_control,
}
"""Modal group -> the STEP 2 handler of its G commands (returns the group the command joins, the mantissa left)."""

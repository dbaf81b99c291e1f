"""The G-code parser's state, the checked block it produces, GRBL 1.1's status codes and number formats.

Written from gnea/grbl ``doc/markdown/commands.md`` (modal groups, defaults) and
``doc/csv/error_codes_en_US.csv`` (error numbers).  :mod:`~pixelpen.sim.plotters.grbl.gcode` fills these;
the controller executes them.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

__all__ = [
    "MM_PER_INCH",
    "MOTION_CCW",
    "MOTION_CW",
    "MOTION_LINEAR",
    "MOTION_NONE",
    "MOTION_SEEK",
    "PROBES",
    "STATUS",
    "GBlock",
    "GcodeState",
    "Persistent",
    "fmt_float",
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
        w: np.ndarray = (self.coord_system + self.coord_offset).copy()
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


def fmt_float(n: float, decimals: int) -> str:
    """GRBL's printFloat: sign, then the value rounded half-up to ``decimals`` places."""
    sign = "-" if n < 0 else ""
    n = abs(n) * (10 ** decimals) + 0.5
    digits = str(int(n))
    if decimals:
        digits = digits.rjust(decimals + 1, "0")
        return f"{sign}{digits[:-decimals]}.{digits[-decimals:]}"
    return sign + digits

"""GRBL 1.1 wire format: G-code for pen strokes, status reports, error and alarm codes, character counting.

Written from gnea/grbl ``doc/markdown/interface.md`` and ``commands.md`` and the code tables
``doc/csv/error_codes_en_US.csv`` / ``alarm_codes_en_US.csv`` (plotters.md §3).  Everything here is
pure: the driver (:mod:`pixelpen.devices.plotters.grbl`) moves the bytes.
"""

from __future__ import annotations

import math
import re
from collections import deque
from dataclasses import dataclass
from decimal import Decimal

import numpy as np

from pixelpen.errors import ConfigError, ParseError

__all__ = [
    "ALARM_CODES",
    "ERROR_CODES",
    "REALTIME_HOLD",
    "REALTIME_RESET",
    "REALTIME_RESUME",
    "REALTIME_STATUS",
    "CharacterCounter",
    "CoordinateFormat",
    "GrblStatus",
    "PathTrack",
    "PenMotion",
    "number",
    "parse_code",
    "parse_status",
    "parse_welcome",
    "stroke_lines",
]

REALTIME_STATUS = b"?"
REALTIME_HOLD = b"!"
REALTIME_RESUME = b"~"
REALTIME_RESET = b"\x18"
"""Real-time bytes (interface.md): act at once, are not buffered and take no newline."""

ERROR_CODES: dict[int, str] = {
    1: "Expected command letter: G-code words consist of a letter and a value; letter was not found",
    2: "Bad number format: missing the expected G-code word value or numeric value format is not valid",
    3: "Invalid statement: Grbl '$' system command was not recognized or supported",
    4: "Value < 0: negative value received for an expected positive value",
    5: "Setting disabled: homing cycle is not enabled via settings",
    6: "Value < 3 usec: minimum step pulse time must be greater than 3 usec",
    7: "EEPROM read fail: auto-restoring affected EEPROM to default values",
    8: "Not idle: Grbl '$' command cannot be used unless Grbl is IDLE",
    9: "G-code lock: G-code commands are locked out during alarm or jog state",
    10: "Homing not enabled: soft limits cannot be enabled without homing also enabled",
    11: "Line overflow: max characters per line exceeded; the line was not executed",
    12: "Step rate > 30kHz: '$' setting value causes the step rate to exceed the maximum supported",
    13: "Check Door: safety door detected as opened and door state initiated",
    14: "Line length exceeded: build info or startup line exceeded EEPROM line length limit",
    15: "Travel exceeded: jog target exceeds machine travel; jog command ignored",
    16: "Invalid jog command: jog command has no '=' or contains prohibited g-code",
    17: "Setting disabled: laser mode requires PWM output",
    20: "Unsupported command: unsupported or invalid g-code command found in block",
    21: "Modal group violation: more than one g-code command from same modal group found in block",
    22: "Undefined feed rate: feed rate has not yet been set or is undefined",
    23: "G-code command in block requires an integer value",
    24: "More than one g-code command that requires axis words found in block",
    25: "Repeated g-code word found in block",
    26: "No axis words found in block for g-code command or current modal state which requires them",
    27: "Line number value is invalid",
    28: "G-code command is missing a required value word",
    29: "G59.x work coordinate systems are not supported",
    30: "G53 only allowed with G0 and G1 motion modes",
    31: "Axis words found in block when no command or current modal state uses them",
    32: "G2 and G3 arcs require at least one in-plane axis word",
    33: "Motion command target is invalid",
    34: "Arc radius value is invalid",
    35: "G2 and G3 arcs require at least one in-plane offset word",
    36: "Unused value words found in block",
    37: "G43.1 dynamic tool length offset is not assigned to configured tool length axis",
    38: "Tool number greater than max supported value",
}
"""``error:N`` meanings (gnea/grbl doc/csv/error_codes_en_US.csv)."""

ALARM_CODES: dict[int, str] = {
    1: "Hard limit triggered; machine position is likely lost, re-homing is highly recommended",
    2: "Soft limit: G-code motion target exceeds machine travel; position retained, alarm may be safely unlocked",
    3: "Reset while in motion; machine position is likely lost, re-homing is highly recommended",
    4: "Probe fail: probe is not in the expected initial state before starting the probe cycle",
    5: "Probe fail: probe did not contact the workpiece within the programmed travel",
    6: "Homing fail: the active homing cycle was reset",
    7: "Homing fail: safety door was opened during homing cycle",
    8: "Homing fail: pull off travel failed to clear limit switch",
    9: "Homing fail: could not find limit switch within search distances",
    10: "Homing fail: on dual axis machines, could not find the second limit switch for self-squaring",
}
"""``ALARM:N`` meanings (gnea/grbl doc/csv/alarm_codes_en_US.csv; 10 from interface.md, 1.1g+)."""

STATES = ("Idle", "Run", "Hold", "Jog", "Alarm", "Door", "Check", "Home", "Sleep")
MAX_DIGITS = 12
"""Digits a number in a GRBL reply may have at most (GRBL prints at most 10 for a uint32, 3-4 decimals)."""
_WELCOME = re.compile(r"^Grbl ([0-9]{1,3})\.([0-9]{1,3})([a-z]?)\s*\[.*\]$", re.ASCII)
_UINT = re.compile(rf"[0-9]{{1,{MAX_DIGITS}}}", re.ASCII)
_DECIMAL = re.compile(
    rf"-?(?:[0-9]{{1,{MAX_DIGITS}}}(?:\.[0-9]{{0,{MAX_DIGITS}}})?|\.[0-9]{{1,{MAX_DIGITS}}})", re.ASCII,
)


@dataclass(frozen=True)
class GrblStatus:
    """One real-time status report (``<State|MPos:..|FS:..|...>``) as fields; absent fields are None."""

    state: str
    substate: int | None = None
    mpos: tuple[float, ...] | None = None
    wpos: tuple[float, ...] | None = None
    wco: tuple[float, ...] | None = None
    feed: float | None = None
    spindle: float | None = None
    planner_free: int | None = None
    """``Bf:`` first figure: free planner blocks (shown with $10 bit 2)."""
    rx_free: int | None = None
    """``Bf:`` second figure: free bytes in the serial RX buffer."""
    line_number: int | None = None
    pins: str | None = None
    overrides: tuple[int, int, int] | None = None
    accessories: str | None = None

    @property
    def held(self) -> bool:
        """True in a feed hold or safety-door state (the machine waits for a resume)."""
        return self.state in ("Hold", "Door")

    @property
    def busy(self) -> bool:
        """True while the machine moves or holds motion (Run, Jog, Home, Hold, Door)."""
        return self.state in ("Run", "Jog", "Home", "Hold", "Door")


def _numbers(text: str, field: str, kind: type = float) -> tuple:
    """Comma-separated ASCII numbers of a status field (ints for ``kind=int``); ParseError naming the field."""
    pattern = _UINT if kind is int else _DECIMAL
    parts = text.split(",")
    if not all(pattern.fullmatch(v) for v in parts):
        raise ParseError(f"status field {field} is not a list of numbers", source="grbl status report", token=text)
    return tuple(kind(v) for v in parts)


def parse_status(line: str) -> GrblStatus:
    """Parse a status report line (with or without its line ending); ParseError naming the bad field."""
    text = line.strip()
    if not (text.startswith("<") and text.endswith(">")) or len(text) < 3:
        raise ParseError("a status report is '<State|field:value|...>'", source="grbl status report", token=text)
    parts = text[1:-1].split("|")
    name, _, sub = parts[0].partition(":")
    if name not in STATES:
        raise ParseError(f"unknown machine state (known: {', '.join(STATES)})", source="grbl status report",
                         token=parts[0])
    if sub and not _UINT.fullmatch(sub):
        raise ParseError("state substate must be a number", source="grbl status report", token=parts[0])
    fields: dict[str, object] = {"state": name, "substate": int(sub) if sub else None}
    for part in parts[1:]:
        key, colon, value = part.partition(":")
        if not colon:
            raise ParseError("status field without ':'", source="grbl status report", token=part)
        if key in ("MPos", "WPos", "WCO"):
            nums = _numbers(value, key)
            if not 2 <= len(nums) <= 6:
                raise ParseError(f"{key} needs one number per axis (2 to 6)", source="grbl status report", token=part)
            fields[key.lower()] = nums
        elif key == "Bf":
            nums = _numbers(value, key, int)
            if len(nums) != 2:
                raise ParseError("Bf needs two numbers (blocks, bytes)", source="grbl status report", token=part)
            fields["planner_free"], fields["rx_free"] = nums
        elif key in ("FS", "F"):
            nums = _numbers(value, key)
            if len(nums) != (2 if key == "FS" else 1):
                raise ParseError(f"{key} has the wrong number of values", source="grbl status report", token=part)
            fields["feed"] = nums[0]
            fields["spindle"] = nums[1] if key == "FS" else None
        elif key == "Ln":
            fields["line_number"] = _numbers(value, key, int)[0]
        elif key == "Ov":
            nums = _numbers(value, key, int)
            if len(nums) != 3:
                raise ParseError("Ov needs three numbers (feed, rapid, spindle)", source="grbl status report",
                                 token=part)
            fields["overrides"] = nums
        elif key == "Pn":
            fields["pins"] = value
        elif key == "A":
            fields["accessories"] = value
        # other fields (build options of forks) are skipped: the report stays usable
    return GrblStatus(**fields)  # type: ignore[arg-type]


def parse_code(line: str) -> int:
    """The number of an ``error:N`` / ``ALARM:N`` line (ASCII digits only); ParseError otherwise."""
    text = line.strip().partition(":")[2].strip()
    if not _UINT.fullmatch(text):
        raise ParseError("expected a number after ':'", source="grbl", token=line)
    return int(text)


def parse_welcome(line: str) -> tuple[int, int, str] | None:
    """``Grbl 1.1h ['$' for help]`` -> (1, 1, 'h'); None for any other line."""
    m = _WELCOME.match(line.strip())
    return (int(m[1]), int(m[2]), m[3]) if m else None


class CoordinateFormat:
    """Device units -> millimetre text with a fixed number of decimals, exact for decimal unit sizes.

    A unit such as 0.001 mm is an exact decimal, so ``n`` units are written by integer arithmetic
    (n·unit·10^d is an integer): coordinates never drift, however many strokes follow.  Units that are
    not short decimals are rounded to ``max_decimals`` places, each coordinate on its own (absolute G90
    coordinates do not accumulate error).
    """

    def __init__(self, unit_mm: float, max_decimals: int = 6) -> None:
        if not (isinstance(unit_mm, (int, float)) and math.isfinite(unit_mm) and unit_mm > 0):
            raise ConfigError(f"unit size must be a positive number of millimetres, got {unit_mm!r}")
        exponent = Decimal(repr(float(unit_mm))).normalize().as_tuple().exponent
        decimals = max(0, -int(exponent))
        self.exact = decimals <= max_decimals
        self.decimals = decimals if self.exact else max_decimals
        self.unit_mm = float(unit_mm)
        self._scale = int(Decimal(repr(float(unit_mm))).scaleb(self.decimals)) if self.exact else 0

    def format(self, units: np.ndarray) -> np.ndarray:
        """Text of each value (integer device units) in mm, e.g. 12000 units of 0.001 mm -> '12.000'."""
        n = np.asarray(units)
        if self.exact:
            q = np.rint(n).astype(np.int64) * self._scale
        else:
            q = np.rint(np.asarray(n, dtype=np.float64) * self.unit_mm * 10**self.decimals).astype(np.int64)
        sign = np.where(q < 0, "-", "")
        a = np.abs(q)
        whole = np.char.mod("%d", a // 10**self.decimals)
        if self.decimals == 0:
            return np.char.add(sign, whole)
        frac = np.char.zfill(np.char.mod("%d", a % 10**self.decimals), self.decimals)
        return np.char.add(np.char.add(sign, whole), np.char.add(".", frac))


def number(value: float) -> str:
    """A G-code number without needless digits: 3000 -> '3000', 0.15 -> '0.15' (at most 4 decimals)."""
    text = f"{value:.4f}".rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text


@dataclass(frozen=True)
class PenMotion:
    """How the pen goes up and down: servo on the spindle PWM (``M3 S<n>`` / ``M5``) or the Z axis, plus dwells.

    Servo: ``up``/``down`` are S values (``up=None`` lifts with ``M5``, no pulses).  Z: they are work Z
    heights in mm.  Each pen move is followed by ``G4 P<dwell>``; GRBL runs a dwell only after the planner
    has emptied, so the ``ok`` of the lift's dwell means the stroke before it is on paper.
    """

    mode: str
    up: float | None
    down: float
    dwell_up: float
    dwell_down: float
    z_feed: float = 600.0

    def __post_init__(self) -> None:
        if self.mode not in ("servo", "z"):
            raise ConfigError(f"pen must be servo or z, got {self.mode!r}")
        if self.mode == "z" and self.up is None:
            raise ConfigError("a Z-axis pen needs a pen_up height")
        for name in ("dwell_up", "dwell_down"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0 <= value <= 60):
                raise ConfigError(f"pen {name} must be 0..60 seconds, got {value!r}")
        if self.mode == "servo" and not all(v is None or 0 <= v <= 100000 for v in (self.up, self.down)):
            raise ConfigError(f"servo S values must be >= 0, got up={self.up!r} down={self.down!r}")

    def up_lines(self) -> list[str]:
        """Lines that lift the pen and wait for it (the last one confirms what came before)."""
        if self.mode == "z":
            move = f"G0 Z{number(self.up)}"  # type: ignore[arg-type]
        elif self.up is None:
            move = "M5"
        else:
            move = f"M3 S{number(self.up)}"
        return [move, f"G4 P{number(self.dwell_up)}"]

    @property
    def joins(self) -> bool:
        """True for a servo pen: its moves and dwells share a line with the motion after them (GRBL runs a line's
        spindle word, then its ``G4``, then its motion), so the pen cannot rest between them."""
        return self.mode == "servo"

    def down_lines(self) -> list[str]:
        """Lines that lower the pen and wait for it."""
        if self.mode == "z":
            return [f"G1 Z{number(self.down)} F{number(self.z_feed)}", f"G4 P{number(self.dwell_down)}"]
        return [f"M3 S{number(self.down)}", f"G4 P{number(self.dwell_down)}"]

    @classmethod
    def parse_servo_command(cls, text: str, what: str) -> float | None:
        """S value of a profile's ``M3 S<n>`` / ``M4 S<n>`` line, None for ``M5``; ConfigError otherwise."""
        t = text.strip().upper()
        if t == "M5":
            return None
        m = re.fullmatch(r"M[34]\s*S(\d+(?:\.\d+)?)", t)
        if not m:
            raise ConfigError(f"profile servo {what} must be 'M3 S<n>', 'M4 S<n>' or 'M5', got {text!r}")
        return float(m[1])


def stroke_lines(
    points: np.ndarray, fmt: CoordinateFormat, pen: PenMotion, feed: float, lift_first: bool = False,
) -> list[str]:
    """G-code of one stroke: travel to its start, pen down, ``G1`` along it at ``feed`` mm/min, pen up.

    ``points`` are integer device units (N, 2), N >= 1; a one-point stroke is a dot (pen down and up).
    The ``F`` word rides on the stroke's first ``G1``.  A joining pen (servo, :attr:`PenMotion.joins`) puts its
    moves on the motion lines: ``lift_first`` prefixes the travel with the previous stroke's lift, the drop
    leads the first ``G1``, and the stroke ends with the pen down (its lift rides on the next travel, or is
    sent alone with :meth:`PenMotion.up_lines`).  Each line then runs whole or not at all, so GRBL never
    rests with the pen down at a stroke's start, nor lifted at its end before the next travel.
    """
    pts = np.asarray(points).reshape(-1, 2)
    if len(pts) == 0:
        raise ConfigError("a stroke needs at least one point")
    xs, ys = fmt.format(pts[:, 0]), fmt.format(pts[:, 1])
    xy = np.char.add(np.char.add("X", xs), np.char.add(" Y", ys))
    draws = np.char.add("G1 ", xy[1:]).tolist()
    if draws:
        draws[0] += f" F{number(feed)}"
    if not pen.joins:
        return [f"G0 {xy[0]}", *pen.down_lines(), *draws, *pen.up_lines()]
    lift = " ".join(pen.up_lines()) + " " if lift_first else ""
    drop = " ".join(pen.down_lines())
    return [f"{lift}G0 {xy[0]}", *([f"{drop} {draws[0]}", *draws[1:]] if draws else [drop])]


class CharacterCounter:
    """GRBL's character-counting flow control: bytes of unacknowledged lines against the RX buffer.

    A line may go when ``sum(len(l) + 1 for l in unacknowledged) + len(line) + 1 <= rx_buffer`` (the
    ``+ 1`` is each line's ``\\n``).  Every ``ok`` or ``error:N`` acknowledges the oldest line.  Written
    as a plain comparison: GRBL's ``stream.py`` computes ``sum(c_line) >= RX_BUFFER_SIZE-1 | s.inWaiting()``,
    where ``|`` binds before ``>=`` (plotters.md §3).
    """

    def __init__(self, rx_buffer: int = 128) -> None:
        if not (isinstance(rx_buffer, int) and rx_buffer >= 16):
            raise ConfigError(f"rx_buffer must be an integer >= 16 bytes, got {rx_buffer!r}")
        self.rx_buffer = rx_buffer
        self._lines: deque[tuple[str, object]] = deque()
        self.in_flight = 0
        """Bytes sent and not yet acknowledged."""

    def __len__(self) -> int:
        return len(self._lines)

    def fits(self, line: str) -> bool:
        """True when ``line`` (without its newline) can be sent now without overflowing the RX buffer."""
        return self.in_flight + len(line) + 1 <= self.rx_buffer

    def sent(self, line: str, tag: object = None) -> None:
        """Record a line written to the device (``tag`` comes back with its acknowledgement)."""
        if len(line) + 1 > self.rx_buffer:
            raise ConfigError(
                f"G-code line of {len(line) + 1} bytes cannot fit GRBL's {self.rx_buffer}-byte buffer: {line!r}")
        self._lines.append((line, tag))
        self.in_flight += len(line) + 1

    def acknowledged(self) -> tuple[str, object]:
        """The oldest unacknowledged line and its tag, now acknowledged; ParseError if none was pending."""
        if not self._lines:
            raise ParseError("GRBL acknowledged a line that was never sent", source="grbl")
        line, tag = self._lines.popleft()
        self.in_flight -= len(line) + 1
        return line, tag

    def oldest(self) -> str | None:
        """The line GRBL is working on (the oldest unacknowledged), or None."""
        return self._lines[0][0] if self._lines else None

    def clear(self) -> None:
        """Forget every pending line (after a soft reset flushed GRBL's buffers)."""
        self._lines.clear()
        self.in_flight = 0


class PathTrack:
    """The path the host sent and the device has not finished: legs (target, pen down while moving to it).

    GRBL runs lines in order along straight legs, so every status report's position must lie on this
    path and, strictly inside a leg, show that leg's pen state.  A byte dropped on the wire (GRBL takes any
    byte >= 0x80 for a real-time command) can leave a shorter but valid line (``X12.3`` -> ``X1.3``,
    ``M3 S500`` -> ``M3 S50``) that GRBL runs without an error; :meth:`check` is how the driver notices.
    """

    def __init__(self) -> None:
        self._points: list[tuple[float, float]] = []
        self._down: list[bool] = []
        self._first = 0
        """Number (since :meth:`start`) of the oldest point kept."""

    def __len__(self) -> int:
        return len(self._points)

    @property
    def end(self) -> tuple[float, float] | None:
        """Where the device will rest once it has run everything sent (None before :meth:`start`)."""
        return self._points[-1] if self._points else None

    def start(self, point: tuple[float, float]) -> None:
        """Forget the path: the device rests at ``point`` (device units), point number 0."""
        self._points, self._down, self._first = [point], [False], 0

    def append(self, point: tuple[float, float], pen_down: bool) -> int:
        """Add a leg to ``point``, drawn (``pen_down``) or travelled; returns the point's number."""
        self._points.append(point)
        self._down.append(pen_down)
        return self._first + len(self._points) - 1

    def done_until(self, number: int) -> None:
        """The device has reached point ``number``: forget the legs before it."""
        drop = min(number - self._first, len(self._points) - 1)
        if drop > 0:
            del self._points[:drop], self._down[:drop]
            self._first += drop

    def check(self, position: tuple[float, float], pen_down: bool | None, tolerance: float) -> str | None:
        """None when ``position`` lies on the path with a fitting pen state; otherwise why it does not."""
        if not self._points:
            return None
        q = np.asarray(position, dtype=np.float64)
        pts = np.asarray(self._points, dtype=np.float64)
        if len(pts) == 1:
            d = float(np.hypot(*(pts[0] - q)))
            return None if d <= tolerance else f"it is {d:.0f} units from where it rests"
        a, b = pts[:-1], pts[1:]
        ab = b - a
        length2 = np.einsum("ij,ij->i", ab, ab)
        t = np.clip(np.einsum("ij,ij->i", q - a, ab) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
        dist = np.hypot(*(a + t[:, None] * ab - q).T)
        near = dist <= tolerance
        if not near.any():
            return f"it is {float(dist.min()):.0f} units off the path sent"
        if pen_down is None:
            return None
        at_vertex = near & ((np.hypot(*(q - a).T) <= tolerance) | (np.hypot(*(q - b).T) <= tolerance))
        down = np.asarray(self._down[1:], dtype=bool)
        if not at_vertex.any() and not (down[near] == pen_down).any():  # the pen changes only at vertices
            return (f"the pen is {'down' if pen_down else 'up'} along a leg the host sent with the pen "
                    f"{'up' if pen_down else 'down'}")
        return None

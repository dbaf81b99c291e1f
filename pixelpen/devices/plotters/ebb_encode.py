"""EiBotBoard (AxiDraw) wire format: versions and feature gates, servo set-up, sliced moves, replies.

Written from evil-mad/EggBot ``docs/ebb.html`` (command reference, "Returned Errors", "Performance") and
plotters.md §2.  AxiDraw kinematics: motor1 = x + y, motor2 = x − y in steps (80 per mm per axis at 16×
microstepping); ``SM,ms,motor1,motor2``, ``XM,ms,x,y`` (the board mixes A+B / A−B itself) and
``LM,rate1,steps1,accel1,rate2,steps2,accel2`` (rate ≈ 85,899.35 × steps/s, accel added every 40 µs).
Everything here is pure: the driver (:mod:`pixelpen.devices.plotters.axidraw`) moves the bytes.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from pixelpen.errors import ConfigError, ParseError
from pixelpen.profiles.model import ServoSettings
from pixelpen.vector.motion import MotionLimits, Plan, plan

__all__ = [
    "EBB_USB_ID",
    "FEATURES",
    "SlicedMove",
    "move_commands",
    "parse_error",
    "parse_qc",
    "parse_qg",
    "parse_qm",
    "parse_qs",
    "parse_version_reply",
    "reply_shape",
    "servo_move_ms",
    "servo_positions",
    "servo_rate_commands",
    "slice_polyline",
    "step_deltas",
    "strip_name",
    "supports",
    "vplus_volts",
]

EBB_USB_ID = (0x04D8, 0xFD92)
"""USB vendor:product of the EiBotBoard (plotters.md §2.1)."""

FEATURES: dict[str, tuple[int, int, int]] = {
    "QB": (1, 9, 2), "ES": (2, 2, 7), "XM": (2, 3, 0), "QS": (2, 4, 3), "QM": (2, 4, 4), "QG": (2, 6, 2),
    "LM": (2, 7, 0), "QE": (2, 8, 0), "queued_EM": (3, 0, 0), "LM_signed_steps": (3, 0, 0), "SC_rates": (2, 6, 0),
}
"""Least firmware version of each command the driver uses (ebb.html "Firmware versions"; plotters.md §2.2)."""

TICK_S = 40e-6
"""The EBB's motion interrupt period (25 kHz)."""
MAX_STEP_RATE = 25000.0
"""Steps per second per motor at most (ebb.html SM: "The maximum speed is 25,000 steps/second")."""
LM_RATE_UNIT = 2**31 / 25000.0
"""LM rate per (step/s): the accumulator adds Rate every 40 µs and steps at 2³¹."""
SERVO_DEFAULT_UP, SERVO_DEFAULT_DOWN = 12000, 16000
"""SC,4 / SC,5 reset values (ebb.html SC), used when a profile states no servo range."""
SERVO_RATE_DEFAULT = 400
"""SC,11 / SC,12 pen raise and lower rate (pulse units per 24 ms servo frame): the firmware's own boot value
(EggBot ``RCServo2.c`` RCServo2_Init: ``g_servo2_rate_up = g_servo2_rate_down = 400``)."""
SERVO_FRAME_S = 0.024
"""The servo output's repetition period: 8 channels of 3 ms (ebb.html: move time = |Δpos| × 0.024 s / rate)."""

VPLUS_MIN_RAW = 250
"""Least ``QC`` V+ reading (10-bit) of a powered board: plotink's queryVoltage ("typical reading is about 300,
for 9 V input"; below 250 pyaxidraw warns that the power supply appears to be off)."""

_VERSION = re.compile(
    r"^(?:V,)?(EBB.*?Version\s+([0-9]{1,3})\.([0-9]{1,3})\.([0-9]{1,3}).*)$", re.IGNORECASE | re.ASCII,
)
_ERROR = re.compile(r"^(?:([A-Z0-9]{1,2}),)?!([0-9]{1,3})\s*Err:\s*(.*?)(?:OK)?$", re.IGNORECASE | re.ASCII)
_UINT = re.compile(r"[0-9]{1,10}", re.ASCII)
_INT = re.compile(r"[+-]?[0-9]{1,10}", re.ASCII)
_DATA_SHAPES = {"QM": "data", "QG": "data", "V": "data", "QB": "data_ok", "QS": "data_ok", "ES": "data_ok",
                "QE": "data_ok", "QP": "data_ok", "QC": "data_ok"}


def parse_version_reply(line: str) -> tuple[tuple[int, int, int], bool]:
    """``EBBv13_and_above EB Firmware Version 2.8.1`` -> ((2, 8, 1), False); a ``V,`` prefix means future syntax."""
    text = line.strip()
    m = _VERSION.match(text)
    if not m:
        raise ParseError("not an EBB version reply ('EBB... Firmware Version x.y.z')", source="ebb V", token=text)
    return (int(m[2]), int(m[3]), int(m[4])), text[:2].upper() == "V,"


def supports(version: tuple[int, int, int], feature: str) -> bool:
    """True when firmware ``version`` has ``feature`` (a key of :data:`FEATURES`)."""
    return version >= FEATURES[feature]


def servo_positions(servo: ServoSettings | None, up_percent: float | None = None,
                    down_percent: float | None = None) -> tuple[int, int]:
    """SC,4 (pen up) and SC,5 (pen down) pulse widths in 83.3 ns units from the profile's range and percentages.

    pyaxidraw's model (plotters.md §2.3): position = min + (max − min) × percent / 100, rounded; the EBB's
    reset values 12000 / 16000 when the profile gives no range.
    """
    if servo is None or servo.min is None or servo.max is None:
        if up_percent is not None or down_percent is not None:
            raise ConfigError("pen_up/pen_down percentages need a [servo] min and max in the profile")
        return SERVO_DEFAULT_UP, SERVO_DEFAULT_DOWN
    up = servo.up_percent if up_percent is None else up_percent
    down = servo.down_percent if down_percent is None else down_percent
    if up is None or down is None:
        raise ConfigError("profile [servo] needs up_percent and down_percent")
    for name, value in (("pen_up", up), ("pen_down", down)):
        if not (isinstance(value, (int, float)) and 0 <= value <= 100):
            raise ConfigError(f"{name} must be a percentage 0..100, got {value!r}")
    span = servo.max - servo.min
    positions = tuple(math.floor(servo.min + span * p / 100.0 + 0.5) for p in (up, down))
    if not all(1 <= p <= 65535 for p in positions):
        raise ConfigError(f"servo positions {positions} are outside SC's 1..65535")
    return positions  # type: ignore[return-value]


def servo_rate_commands(rate_up: int, rate_down: int) -> list[str]:
    """``SC,11`` (raise) and ``SC,12`` (lower) rates, as pyaxidraw's servo set-up sends them (fw >= 2.6.0)."""
    for name, rate in (("raise", rate_up), ("lower", rate_down)):
        if not (isinstance(rate, int) and 1 <= rate <= 65535):
            raise ConfigError(f"pen {name} rate must be an integer 1..65535 (SC,11/12), got {rate!r}")
    return [f"SC,11,{rate_up}", f"SC,12,{rate_down}"]


def servo_move_ms(start: int, end: int, rate: int) -> int:
    """Milliseconds the servo pulse takes from ``start`` to ``end`` at ``rate`` (|Δ| × 24 ms / rate, rounded up)."""
    return math.ceil(abs(end - start) * SERVO_FRAME_S * 1000.0 / rate - 1e-9)


@dataclass(frozen=True)
class SlicedMove:
    """A planned polyline cut into time slices: each slice's duration (ms), x/y steps and end speeds (mm/s)."""

    ms: np.ndarray
    steps: np.ndarray
    """(K, 2) integer x/y steps of each slice; they sum to the exact step difference end − start."""
    v0: np.ndarray
    v1: np.ndarray
    vertex: np.ndarray
    """Index of the last polyline vertex each slice has reached or passed by its end."""

    def __len__(self) -> int:
        return len(self.ms)


def step_deltas(positions: np.ndarray) -> np.ndarray:
    """Integer steps between consecutive positions (float steps), fractions carried: rint of the running position.

    Rounding each absolute position (never each difference) keeps the error below half a step at every
    point, and the deltas sum exactly to rint(last) − rint(first) however many tiny moves there are.
    """
    pos = np.rint(np.asarray(positions, dtype=np.float64)).astype(np.int64)
    return np.diff(pos, axis=0)


def _profile_at(blocks: Plan, k: np.ndarray, tau: np.ndarray, accel: float) -> tuple[np.ndarray, np.ndarray]:
    """Distance along block ``k`` (mm) and speed (mm/s) ``tau`` seconds after it starts (trapezoid profile)."""
    ta, tc = blocks.accel_time[k], blocks.cruise_time[k]
    ve, vp = blocks.entry[k], blocks.cruise[k]
    d1 = ve * ta + 0.5 * accel * ta * ta
    u = np.maximum(tau - ta - tc, 0.0)
    s = np.where(tau <= ta, ve * tau + 0.5 * accel * tau * tau,
                 np.where(tau <= ta + tc, d1 + vp * (tau - ta), d1 + vp * tc + vp * u - 0.5 * accel * u * u))
    v = np.where(tau <= ta, ve + accel * tau, np.where(tau <= ta + tc, vp, vp - accel * u))
    return np.clip(s, 0.0, blocks.length[k]), np.maximum(v, 0.0)


def slice_polyline(points_mm: np.ndarray, limits: MotionLimits, steps_per_mm: float, slice_s: float) -> SlicedMove:
    """Plan a polyline (mm) with the motion model and cut each straight block into equal slices of <= ``slice_s``.

    The polyline starts and ends at rest; corners are taken at the junction speeds of
    :func:`pixelpen.vector.motion.plan`.  Slices end exactly on every vertex (a slice never cuts a corner)
    and otherwise sample the trapezoidal speed profile, vectorised over all slices.  Positions become steps
    with the fractions carried (:func:`step_deltas`); durations are rounded the same way, at least 1 ms and
    never faster than 25,000 steps/s on either motor.
    """
    pts = np.asarray(points_mm, dtype=np.float64).reshape(-1, 2)
    blocks = plan(pts, limits)
    if len(blocks) == 0:
        return SlicedMove(
            np.zeros(0, np.int64), np.zeros((0, 2), np.int64), np.zeros(0), np.zeros(0), np.zeros(0, np.int64),
        )
    count = np.maximum(1, np.ceil(blocks.duration / slice_s - 1e-9).astype(np.int64))
    k = np.repeat(np.arange(len(blocks)), count)
    first = np.repeat(np.cumsum(count) - count, count)
    j = np.arange(len(k)) - first + 1
    tau1 = blocks.duration[k] * j / count[k]
    tau0 = blocks.duration[k] * (j - 1) / count[k]
    s1, v1 = _profile_at(blocks, k, tau1, limits.accel)
    _, v0 = _profile_at(blocks, k, tau0, limits.accel)
    unit = (blocks.end[k] - blocks.start[k]) / blocks.length[k][:, None]
    ends = blocks.start[k] + unit * s1[:, None]
    last = j == count[k]
    ends[last] = blocks.end[k[last]]
    steps = step_deltas(np.vstack([pts[:1], ends]) * steps_per_mm)
    t_end = np.concatenate([[0.0], np.cumsum(blocks.duration)])[k] + tau1
    ms = np.diff(np.rint(np.concatenate([[0.0], t_end]) * 1000.0).astype(np.int64))
    motor = np.abs(np.column_stack([steps[:, 0] + steps[:, 1], steps[:, 0] - steps[:, 1]])).max(axis=1)
    ms = np.maximum(np.maximum(ms, 1), np.ceil(motor * 1000.0 / MAX_STEP_RATE).astype(np.int64))
    block_end = np.flatnonzero(np.hypot(*np.diff(pts, axis=0).T) > 0) + 1  # blocks are the non-zero segments
    vertex = np.where(last, block_end[k], block_end[k] - 1)
    return SlicedMove(ms, steps, v0, v1, vertex)


def _lm_axis(steps: int, ticks: int, v0: float, v1: float) -> tuple[int, int]:
    """LM (rate, accel) for one motor: ``steps`` in ``ticks`` periods, speed changing linearly by the ratio v1/v0.

    Total accumulation r·n + a·n²/2 must reach |steps|·2³¹: with r = 2·S·2³¹·v0 / (n·(v0 + v1)) the end rate
    keeps the ratio v1/v0; accel is rounded up (plus one) so the axis finishes by the end of the slice and
    never stalls at a zero rate.
    """
    s = abs(int(steps))
    if s == 0:
        return 0, 0
    need = s * 2**31
    rate = round(2 * need * v0 / (ticks * (v0 + v1))) if v0 + v1 > 0 else round(need / ticks)
    accel = -((-2 * (need - rate * ticks)) // (ticks * ticks)) + 1
    return rate, accel


def move_commands(move: SlicedMove, mode: str, lm_signed_steps: bool = True) -> list[str]:
    """EBB commands for a sliced move: ``sm`` -> ``SM,ms,x+y,x−y``; ``xm`` -> ``XM,ms,x,y``; ``lm`` -> ``LM,...``.

    A slice without steps is a pause (``SM,ms,0,0``), which LM cannot express.  LM directions: firmware 3.0
    takes them from the sign of Steps (``lm_signed_steps``); before 3.0 the sign of Rate gives the direction,
    Steps is positive and Accel is negated with it (ebb.html LM version history and direction note).
    """
    if mode not in ("sm", "xm", "lm"):
        raise ConfigError(f"moves must be sm, xm or lm, got {mode!r}")
    if len(move) == 0:
        return []
    x, y = move.steps[:, 0], move.steps[:, 1]
    m1, m2 = x + y, x - y
    ms = move.ms
    if mode == "sm":
        return np.char.add(np.char.add(np.char.add("SM,", ms.astype(str)), np.char.add(",", m1.astype(str))),
                           np.char.add(",", m2.astype(str))).tolist()
    if mode == "xm":
        return np.char.add(np.char.add(np.char.add("XM,", ms.astype(str)), np.char.add(",", x.astype(str))),
                           np.char.add(",", y.astype(str))).tolist()
    out = []
    for i in range(len(ms)):  # per slice: integer LM parameters need exact big-integer arithmetic
        if m1[i] == 0 and m2[i] == 0:
            out.append(f"SM,{ms[i]},0,0")
            continue
        ticks = int(ms[i]) * 25
        fields = []
        for steps in (int(m1[i]), int(m2[i])):
            rate, accel = _lm_axis(steps, ticks, float(move.v0[i]), float(move.v1[i]))
            if lm_signed_steps or steps >= 0:
                fields.append(f"{rate},{steps},{accel}")
            else:
                fields.append(f"{-rate},{-steps},{-accel}")
        out.append("LM," + ",".join(fields))
    return out


def reply_shape(name: str) -> str:
    """How a command answers in legacy syntax: ``ack`` (OK), ``data`` (one line) or ``data_ok`` (line + OK)."""
    return _DATA_SHAPES.get(name.upper(), "ack")


def parse_error(line: str) -> tuple[int, str] | None:
    """An ``!N Err: text`` reply (legacy, maybe ending in OK; future ``NAME,!N Err: ...``) -> (N, text); else None."""
    m = _ERROR.match(line.strip())
    return (int(m[2]), m[3].strip()) if m else None


def strip_name(name: str, data: str) -> str:
    """A data reply without its ``NAME,`` prefix (future syntax always has it, legacy QM too)."""
    prefix = name.upper() + ","
    return data[len(prefix):] if data.upper().startswith(prefix) else data


def _fields(name: str, data: str, count: int, pattern: re.Pattern[str], what: str) -> tuple[int, ...]:
    """``count`` comma-separated ASCII integers of a ``name`` reply (with or without ``NAME,``)."""
    fields = [f.strip() for f in strip_name(name, data.strip()).split(",")]
    if len(fields) != count or not all(pattern.fullmatch(f) for f in fields):
        raise ParseError(f"{name} reply must be {what}", source=f"ebb {name}", token=data)
    return tuple(int(f) for f in fields)


def parse_qm(data: str) -> tuple[int, int, int, int]:
    """``QM`` data ``CommandStatus,Motor1,Motor2,FIFO`` (with or without ``QM,``) -> four integers."""
    return _fields("QM", data, 4, _UINT, "four numbers")  # type: ignore[return-value]


def parse_qs(data: str) -> tuple[int, int]:
    """``QS`` data ``steps1,steps2`` (signed global step counters) -> two integers."""
    return _fields("QS", data, 2, _INT, "two step counts")  # type: ignore[return-value]


def parse_qc(data: str) -> tuple[int, int]:
    """``QC`` data ``RA0,V+`` (10-bit readings: pen current sense, motor supply) -> two integers 0..1023."""
    values = _fields("QC", data, 2, _UINT, "two 10-bit readings")
    if not all(v <= 1023 for v in values):
        raise ParseError("QC readings are 10-bit (0..1023)", source="ebb QC", token=data)
    return values  # type: ignore[return-value]


def vplus_volts(raw: int) -> float:
    """Motor supply voltage of a ``QC`` V+ reading: raw/1023 x 3.3 V x 9.2 + 0.3 V (saxi's ebb.ts divider)."""
    return raw / 1023.0 * 3.3 * 9.2 + 0.3


def parse_qg(data: str) -> int:
    """``QG`` status byte (two hex digits, with or without ``QG,``) -> int."""
    text = strip_name("QG", data.strip())
    if not re.fullmatch(r"[0-9A-Fa-f]{1,2}", text, re.ASCII):
        raise ParseError("QG reply must be a hexadecimal byte", source="ebb QG", token=data)
    return int(text, 16)

"""Tablet (pen digitizer) semantics: position in mm, pressure through a curve, tilt in degrees, proximity, tools.

:class:`Tablet` handles Digitizers-page Digitizer (0x0D0001) and Pen (0x0D0002) applications, as
Microsoft's pen protocol and the kernel's hid-input map them:

* **Position** — absolute X/Y (Generic Desktop 0x30/0x31) as ``x``/``y`` normalised 0..1 over the
  logical range (clamped) and ``x_mm``/``y_mm`` in millimetres (clamped alike) from the physical range, unit and
  exponent (:func:`pixelpen.devices.hid.units.to_mm`, exact where the kernel's resolution rounds to
  whole counts per mm), or from the ``size`` option (``224x140``, ``8.8x5.5in``: the length the
  logical range spans).  Without either, mm are NaN and :meth:`Tablet.describe` says so.
* **Pressure** — Tip Pressure (0x0D0030) normalised over its logical range, then the
  ``pressure_range`` (``min:max`` fractions, as libinput's pressure range: at or below *min* is 0,
  at or above *max* is 1, linear between), then the ``pressure_curve``: ``linear``; a cubic Bézier
  ``x1:y1:x2:y2`` from (0, 0) through the control points (x1, y1), (x2, y2) to (1, 1), the form of
  GNOME's and xf86-input-wacom's ``PressureCurve`` (their 0..100 values divided by 100); or
  ``gamma:G`` (``p ** G``).  Every curve maps 0 to 0 and 1 to 1 and never decreases.  Devices send
  at most 65536 pressure levels through a table computed once with numpy.
* **Tilt** — X/Y Tilt (0x0D003D/3E) in degrees from their unit (degrees or radians, through
  :func:`~pixelpen.devices.hid.units.to_degrees`); without an angle unit the logical range is mapped
  to -64..64 degrees, as libinput's ``adjust_tilt`` does for Wacom pens.
* **Proximity and contact** — In Range (0x32) is proximity (a device without it is always in
  range); Tip Switch (0x42) or Eraser (0x45, the eraser end touching) is contact; Invert (0x3C) says
  the eraser end is the one near (``inverted``); ``eraser`` is Invert or Eraser.  Barrel Switch
  (0x44) and Secondary Barrel Switch (0x5A) give ``barrel``, in that order, for those the device has.
* **Tool** — Transducer Serial Number (0x5B) gives ``serial`` (None without the usage).

A :class:`~pixelpen.devices.hid.events.Pen` event is sent when anything it carries changes.  When the
pen leaves proximity one event says so (``in_range=False``, at the last in-range position, not
touching, no pressure, buttons up; devices often zero X/Y in that report), and out-of-range reports
give nothing more.  A report without X and Y (a pad's buttons in the same application) gives no events.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from pixelpen.devices.hid import units
from pixelpen.devices.hid.events import DeviceId, InputEvent, Pen
from pixelpen.devices.hid.fields import Field, ReportDescriptor, Values
from pixelpen.devices.hid.semantics import read_semantics_options
from pixelpen.errors import ConfigError, InvalidArgument
from pixelpen.options import OptionSpec
from pixelpen.urls import parse_size
from pixelpen.urls import to_mm as length_to_mm

__all__ = ["PositionAxis", "PressureCurve", "Tablet", "first_value", "position_axes", "size_option"]

GD_X, GD_Y = 0x00010030, 0x00010031
DG_TIP_PRESSURE, DG_IN_RANGE, DG_INVERT = 0x000D0030, 0x000D0032, 0x000D003C
DG_X_TILT, DG_Y_TILT = 0x000D003D, 0x000D003E
DG_TIP_SWITCH, DG_BARREL_SWITCH, DG_ERASER = 0x000D0042, 0x000D0044, 0x000D0045
DG_SECONDARY_BARREL_SWITCH, DG_TRANSDUCER_SERIAL = 0x000D005A, 0x000D005B
BARRELS = (DG_BARREL_SWITCH, DG_SECONDARY_BARREL_SWITCH)
"""The barrel switch usages, in the order of :attr:`Pen.barrel`."""
DEFAULT_TILT_DEGREES = 64.0
"""libinput's WACOM_MAX_DEGREES: a tilt axis without an angle unit spans -64..64 degrees."""
PRESSURE_TABLE_LIMIT = 65536
"""Pressure fields with at most this many logical values are mapped through a precomputed table."""
BISECTION_STEPS = 52
"""Bisection steps solving a Bézier curve's x(t) = p (52: t to the double's 2**-52)."""


def first_value(values: Values, usage: int) -> int | None:
    """A decoded usage's value, the first element where it repeats (None when the report lacks it)."""
    value = values.get((usage >> 16, usage & 0xFFFF))
    if isinstance(value, list):
        return value[0] if value else None
    return value


# -- the pressure curve ----------------------------------------------------------------------------------


class PressureCurve:
    """A monotonic map of 0..1 onto 0..1 with 0 -> 0 and 1 -> 1: linear, a cubic Bézier, or a gamma power."""

    def __init__(self, kind: str = "linear", points: Sequence[float] = (0.0, 0.0, 1.0, 1.0),
                 gamma: float = 1.0) -> None:
        if kind not in ("linear", "bezier", "gamma"):
            raise ConfigError(f"pressure curve {kind!r} is not valid: expected linear, bezier or gamma")
        points = tuple(float(p) for p in points)
        if len(points) != 4 or not all(math.isfinite(p) and 0.0 <= p <= 1.0 for p in points):
            raise ConfigError(f"pressure curve control points {points!r} are not valid: expected x1:y1:x2:y2, "
                              "each in [0, 1]")
        if not (math.isfinite(gamma) and gamma > 0.0):
            raise ConfigError(f"pressure curve gamma {gamma!r} is not valid: expected a finite number > 0")
        self.kind = kind
        self.points = points
        self.gamma = gamma

    def __repr__(self) -> str:
        if self.kind == "bezier":
            return f"PressureCurve('bezier', {self.points})"
        return f"PressureCurve('gamma', gamma={self.gamma:g})" if self.kind == "gamma" else "PressureCurve('linear')"

    def __call__(self, pressure: float) -> float:
        """The curve at one pressure in 0..1 (clamped)."""
        return float(self.batch(np.array([pressure], np.float64))[0])

    def batch(self, pressure: np.ndarray) -> np.ndarray:
        """The curve at many pressures at once (clamped to 0..1; float64)."""
        p = np.clip(np.asarray(pressure, np.float64), 0.0, 1.0)
        if self.kind == "gamma":
            return np.power(p, self.gamma)
        if self.kind == "linear":
            return p
        x1, y1, x2, y2 = self.points
        lo, hi = np.zeros_like(p), np.ones_like(p)
        for _ in range(BISECTION_STEPS):  # x(t) never decreases for control x in [0, 1]: bisection finds t
            mid = (lo + hi) / 2.0
            below = _bernstein(mid, x1, x2) < p
            lo = np.where(below, mid, lo)
            hi = np.where(below, hi, mid)
        out = _bernstein((lo + hi) / 2.0, y1, y2)
        out[p <= 0.0] = 0.0
        out[p >= 1.0] = 1.0
        return np.clip(out, 0.0, 1.0)


def _bernstein(t: np.ndarray, c1: float, c2: float) -> np.ndarray:
    """One coordinate of the cubic Bézier from 0 through ``c1``, ``c2`` to 1 at ``t``."""
    s = 1.0 - t
    return 3.0 * s * s * t * c1 + 3.0 * s * t * t * c2 + t * t * t


def _pressure_curve(text: str) -> PressureCurve:
    """The ``pressure_curve`` option: ``linear``, ``x1:y1:x2:y2`` or ``gamma:G``."""
    low = text.strip().lower()
    if low == "linear":
        return PressureCurve()
    if low.startswith("gamma:"):
        try:
            gamma = float(low[6:])
        except ValueError:
            raise ValueError(f"expected gamma:G with a number G, got {text!r}") from None
        return PressureCurve("gamma", gamma=gamma)
    try:
        points = [float(v) for v in low.split(":")]
    except ValueError:
        points = []
    if len(points) != 4:
        raise ValueError(f"expected linear, x1:y1:x2:y2 (a cubic Bézier) or gamma:G, got {text!r}")
    return PressureCurve("bezier", points)


def _pressure_range(text: str) -> tuple[float, float]:
    """The ``pressure_range`` option: ``min:max``, fractions with 0 <= min < max <= 1."""
    try:
        low, high = (float(v) for v in text.split(":"))
    except ValueError:
        raise ValueError(f"expected min:max fractions, got {text!r}") from None
    if not (0.0 <= low < high <= 1.0):
        raise ValueError(f"expected min:max with 0 <= min < max <= 1, got {text!r}")
    return low, high


def size_option(text: str) -> tuple[float, float]:
    """The ``size`` option: the active area as ``WxH`` in mm, or with a unit (``8.8x5.5in``), as mm."""
    try:
        size = parse_size(text, "mm")
    except InvalidArgument as exc:
        raise ValueError(str(exc)) from None
    if size.unit == "px":
        raise ValueError(f"expected a size in mm, cm or in, not pixels: {text!r}")
    return length_to_mm(size.width, size.unit), length_to_mm(size.height, size.unit)


# -- positions -------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PositionAxis:
    """An absolute X or Y field: its value normalised over the logical range and in mm."""

    field: Field
    length_mm: float | None = None
    """The length the logical range spans (the ``size`` option); None: from the field's unit."""

    @property
    def known(self) -> bool:
        """Whether positions in mm are known (a length unit or a given size)."""
        return self.length_mm is not None or self.field.unit in (units.UNIT_CM, units.UNIT_INCH)

    def fraction(self, raw: int) -> float:
        """The value over the logical range, 0 at the minimum and 1 at the maximum (not clamped)."""
        span = self.field.logical_max - self.field.logical_min
        return (raw - self.field.logical_min) / span if span else 0.0

    def normalised(self, raw: int) -> float:
        """The value over the logical range, clamped to 0..1."""
        return min(1.0, max(0.0, self.fraction(raw)))

    def mm(self, raw: int) -> float:
        """The position in mm (physical, from the unit; or along the given size), clamped to the surface as
        ``normalised`` is; NaN when unknown."""
        if self.length_mm is not None:
            return self.normalised(raw) * self.length_mm
        if not self.known:
            return math.nan
        return units.to_mm(self.field, min(max(raw, self.field.logical_min), self.field.logical_max))


def position_axes(fields: Sequence[Field], size: tuple[float, float] | None) -> tuple[PositionAxis | None, ...]:
    """X and Y of a set of fields (the first of each; None where missing), with the ``size`` option applied."""
    found: list[PositionAxis | None] = []
    for i, usage in enumerate((GD_X, GD_Y)):
        field = next((f for f in fields if usage in f.usages and not f.is_constant), None)
        found.append(None if field is None else PositionAxis(field, None if size is None else size[i]))
    return tuple(found)


# -- the tablet ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _PenPlan:
    """What one input report carries for a pen."""

    x: PositionAxis
    y: PositionAxis
    usages: frozenset[int]
    barrels: tuple[int, ...]
    pressure: Field | None
    pressure_table: list[float] | None
    """The pressure (range and curve applied) of every logical value from the minimum, when there are few enough."""
    tilt: tuple[Field | None, Field | None]


class Tablet:
    """A pen tablet or pen display: Pen events on change and on proximity in/out."""

    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("pressure_curve", _pressure_curve, PressureCurve(),
                   "pressure curve: linear, x1:y1:x2:y2 (a cubic Bézier, each 0..1) or gamma:G"),
        OptionSpec("pressure_range", _pressure_range, (0.0, 1.0),
                   "min:max fractions of the raw pressure mapped to 0..1 (below min: 0)"),
        OptionSpec("size", size_option, None,
                   "the active area WxH in mm (or with a unit: 8.8x5.5in), overriding the descriptor's"),
    )

    def __init__(self, descriptor: ReportDescriptor, device: DeviceId, **options: object) -> None:
        self.descriptor = descriptor
        self.device = device
        opts = read_semantics_options(self.OPTIONS, options, f"tablet semantics for {device}")
        self.curve: PressureCurve = opts["pressure_curve"]
        self.pressure_range: tuple[float, float] = opts["pressure_range"]
        self._plans: dict[int | None, _PenPlan] = {}
        for report_id, fields in descriptor.input_reports.items():
            plan = self._plan(fields, opts["size"])
            if plan is not None:
                self._plans[report_id] = plan
        self._last: Pen | None = None

    def _plan(self, fields: Sequence[Field], size: tuple[float, float] | None) -> _PenPlan | None:
        x, y = position_axes(fields, size)
        if x is None or y is None:
            return None
        present = [u for f in fields if not f.is_constant and not f.is_array for u in f.usages]

        def field_of(usage: int) -> Field | None:
            return next((f for f in fields if usage in f.usages and not f.is_constant), None)

        pressure = field_of(DG_TIP_PRESSURE)
        table = None
        if pressure is not None and 0 < pressure.logical_max - pressure.logical_min < PRESSURE_TABLE_LIMIT:
            span = pressure.logical_max - pressure.logical_min
            table = self._through_curve(np.arange(span + 1, dtype=np.float64) / span).tolist()
        return _PenPlan(x, y, frozenset(present), tuple(b for b in BARRELS if b in present), pressure, table,
                        (field_of(DG_X_TILT), field_of(DG_Y_TILT)))

    def describe(self) -> str:
        """What was found: the area, pressure levels, tilt, switches and the tool serial."""
        if not self._plans:
            return f"{self.device}: tablet without X/Y (no pen events)"
        plan = next(iter(self._plans.values()))
        if plan.x.known and plan.y.known:
            area = (f"{abs(plan.x.mm(plan.x.field.logical_max) - plan.x.mm(plan.x.field.logical_min)):.1f} x "
                    f"{abs(plan.y.mm(plan.y.field.logical_max) - plan.y.mm(plan.y.field.logical_min)):.1f} mm")
        else:
            area = "size unknown (give size=WxH)"
        parts = [f"{self.device}: tablet, {area}"]
        if plan.pressure is not None:
            parts.append(f"{plan.pressure.logical_max - plan.pressure.logical_min + 1} pressure levels "
                         f"({self.curve!r})")
        if plan.tilt[0] is not None or plan.tilt[1] is not None:
            parts.append("tilt")
        names = {DG_IN_RANGE: "in range", DG_TIP_SWITCH: "tip", DG_INVERT: "invert", DG_ERASER: "eraser",
                 DG_BARREL_SWITCH: "barrel", DG_SECONDARY_BARREL_SWITCH: "2nd barrel",
                 DG_TRANSDUCER_SERIAL: "serial"}
        parts.extend(name for usage, name in names.items() if usage in plan.usages)
        return ", ".join(parts)

    # -- reports -------------------------------------------------------------------------------------

    def feed(self, report: bytes, time: float) -> list[InputEvent]:
        """The events of one input report: a Pen event when the pen's state changed (or it left proximity)."""
        report_id = self.descriptor.report_id_of(report)
        values = self.descriptor.decode(report)  # the per-report compiled function, found by one lookup
        plan = self._plans.get(report_id)
        if plan is None:
            return []
        in_range = DG_IN_RANGE not in plan.usages or bool(first_value(values, DG_IN_RANGE))
        if not in_range:
            last = self._last
            if last is None or not last.in_range:
                return []
            self._last = Pen(time, self.device, x_mm=last.x_mm, y_mm=last.y_mm, x=last.x, y=last.y,
                             tilt_x=last.tilt_x, tilt_y=last.tilt_y, in_range=False,
                             barrel=(False,) * len(last.barrel), eraser=last.eraser, inverted=last.inverted,
                             serial=last.serial)
            return [self._last]
        pen = self._pen(plan, values, time)
        if self._last is not None and _state(pen) == _state(self._last):
            return []
        self._last = pen
        return [pen]

    def _pen(self, plan: _PenPlan, values: Values, time: float) -> Pen:
        raw_x = first_value(values, GD_X) or 0
        raw_y = first_value(values, GD_Y) or 0
        invert = bool(first_value(values, DG_INVERT))
        eraser = bool(first_value(values, DG_ERASER))
        serial = first_value(values, DG_TRANSDUCER_SERIAL) if DG_TRANSDUCER_SERIAL in plan.usages else None
        return Pen(time, self.device, x_mm=plan.x.mm(raw_x), y_mm=plan.y.mm(raw_y),
                   x=plan.x.normalised(raw_x), y=plan.y.normalised(raw_y),
                   pressure=self._pressure(plan, first_value(values, DG_TIP_PRESSURE)),
                   tilt_x=_tilt(plan.tilt[0], first_value(values, DG_X_TILT)),
                   tilt_y=_tilt(plan.tilt[1], first_value(values, DG_Y_TILT)),
                   in_range=True, touching=bool(first_value(values, DG_TIP_SWITCH)) or eraser,
                   barrel=tuple(bool(first_value(values, b)) for b in plan.barrels),
                   eraser=invert or eraser, inverted=invert, serial=serial)

    def pressure(self, field: Field, raw: int) -> float:
        """A raw pressure of ``field`` through the pressure range and curve (0..1)."""
        span = field.logical_max - field.logical_min
        if span <= 0:
            return 0.0
        return float(self._through_curve(np.array([(raw - field.logical_min) / span]))[0])

    def _through_curve(self, fraction: np.ndarray) -> np.ndarray:
        low, high = self.pressure_range
        return self.curve.batch(np.clip((fraction - low) / (high - low), 0.0, 1.0))

    def _pressure(self, plan: _PenPlan, raw: int | None) -> float:
        field = plan.pressure
        if field is None or raw is None:
            return 0.0
        if plan.pressure_table is None:
            return self.pressure(field, raw)
        return plan.pressure_table[min(len(plan.pressure_table) - 1, max(0, raw - field.logical_min))]


def _tilt(field: Field | None, raw: int | None) -> float:
    """A tilt in degrees: by the field's angle unit, else its logical range over libinput's -64..64."""
    if field is None or raw is None:
        return 0.0
    if field.unit in (units.UNIT_DEGREE, units.UNIT_RADIAN) and not field.physical_min == field.physical_max != 0:
        return units.to_degrees(field, raw)
    span = field.logical_max - field.logical_min
    return ((raw - field.logical_min) / span * 2.0 - 1.0) * DEFAULT_TILT_DEGREES if span else 0.0


def _state(pen: Pen) -> tuple[object, ...]:
    """What a Pen event says, without its time (NaN positions compare equal)."""
    return (repr(pen.x_mm), repr(pen.y_mm), pen.x, pen.y, pen.pressure, pen.tilt_x, pen.tilt_y, pen.in_range,
            pen.touching, pen.barrel, pen.eraser, pen.inverted, pen.serial)

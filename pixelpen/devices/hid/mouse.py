"""Mouse and trackball semantics: relative motion in counts and mm, wheels, buttons, acceleration.

:class:`Mouse` handles Generic Desktop Mouse and Pointer applications, relative (a mouse, a
trackball) or absolute (a virtual machine's tablet pointer):

* **Motion** — relative X/Y in counts (HID convention: +x right, +y towards the user, i.e. down
  on a screen) and in mm when the resolution is known: from the ``dpi`` option, else from the
  field's physical range, unit and exponent (:func:`pixelpen.devices.hid.units.to_mm`; exact, where
  the kernel's resolution formula rounds to whole counts per mm).  With an acceleration profile,
  ``dx``/``dy`` are the accelerated pointer counts (fractions carried to the next report, so no
  motion is lost) while ``dx_mm``/``dy_mm`` stay the physical motion of the ball.
* **Wheel** — Generic Desktop Wheel (vertical, + away from the user) and Consumer AC Pan
  (0x0C0238, horizontal, + right), in detents.  A hi-res wheel declares a Resolution Multiplier
  (0x00010048) in a feature report: :meth:`Mouse.output_reports` gives the feature report that sets
  it to its logical maximum (as the kernel's ``hidinput_change_resolution_multipliers`` does), and the
  wheels in the multiplier's logical collection (without one, every wheel of its application: HUT
  §4.3.1 "all controls in the report", the kernel's ``hid_apply_multiplier``) then report
  ``value / multiplier`` detents, the multiplier being the kernel's ``hid_calculate_multiplier``:
  ``(v - lmin) / (lmax - lmin) * (pmax - pmin) + pmin`` in integers, 0 and beyond ±255 taken as 1.
  ``hires=false`` leaves it at its minimum (usually 1).
* **Buttons** — Button page usages, press and release edges (1 left, 2 right, 3 middle, 4 side,
  5 extra as the kernel's BTN_LEFT..BTN_EXTRA).
* **Absolute pointers** — absolute X/Y give :class:`~pixelpen.devices.hid.events.Axis` events
  ``x`` and ``y``, normalised 0..1 over the logical range, when they change.

Acceleration profiles (option ``acceleration``), after libinput's (``src/filter-flat.c``,
``src/filter.c`` ``pointer_accel_profile_linear``), with ``speed`` in -1..1:

* ``none`` — counts as reported (the default);
* ``flat`` — a constant factor ``max(0.005, 1 + speed)``;
* ``adaptive`` — a factor from the pointer velocity *v* in 1000-dpi counts per ms: ``10 v + 0.3``
  below 0.07, 1 up to the threshold *T* = max(0.2, 0.4 − 0.25·speed), then
  ``incline · (v − T) + 1`` with incline 1.1 + 0.75·speed, capped at 2 + 1.5·speed; the factor of a
  report is Simpson's average over the previous and the current velocity, as libinput's
  ``calculate_acceleration_simpsons``.  The velocity is this report's distance over the time since
  the previous report (clamped to 0.125 ms..1 s; libinput averages over up to 16 trackers).

The accelerated ``dx``/``dy`` stay in the device's counts (libinput's output is in 1000-dpi units: multiply
by ``1000 / dpi`` to compare).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, ClassVar

from pixelpen.devices.hid import units
from pixelpen.devices.hid.events import Axis, Button, DeviceId, InputEvent, Motion, Wheel
from pixelpen.devices.hid.fields import Collection, CollectionKind, Field, ReportDescriptor, ReportKind, Values
from pixelpen.devices.hid.semantics import OutputReport, read_semantics_options
from pixelpen.errors import ConfigError, InvalidArgument
from pixelpen.options import OptionSpec, boolean, choice, number, positive

__all__ = ["AdaptiveProfile", "FlatProfile", "Mouse", "effective_multiplier"]

GD_X, GD_Y, GD_WHEEL, GD_RESOLUTION_MULTIPLIER = 0x00010030, 0x00010031, 0x00010038, 0x00010048
CONSUMER_AC_PAN = 0x000C0238
BUTTON_PAGE = 0x09
MM_PER_INCH = 25.4
MAX_MULTIPLIER = 255
"""The kernel takes a larger Resolution Multiplier as a broken descriptor and uses 1 ("no devices with > 255")."""
DEFAULT_DPI = 1000.0
"""libinput's DEFAULT_MOUSE_DPI: what velocities are normalised to, and the dpi assumed when none is known."""

BUTTON_NAMES = {1: "left", 2: "right", 3: "middle", 4: "side", 5: "extra", 6: "forward", 7: "back", 8: "task"}
"""Button-page usage -> name, in the kernel's order BTN_LEFT, BTN_RIGHT, BTN_MIDDLE, BTN_SIDE, ... BTN_TASK."""


class FlatProfile:
    """libinput's flat profile: one constant factor ``max(0.005, 1 + speed)`` whatever the velocity."""

    def __init__(self, speed: float = 0.0) -> None:
        _check_speed(speed)
        self.factor = max(0.005, 1.0 + speed)

    def __call__(self, velocity: float) -> float:
        """The factor (the same for every velocity)."""
        return self.factor


class AdaptiveProfile:
    """libinput's adaptive (linear) profile: slow motion decelerated, a plateau of 1, then a capped incline."""

    def __init__(self, speed: float = 0.0) -> None:
        _check_speed(speed)
        self.threshold = max(0.2, 0.4 - 0.25 * speed)
        """Counts per ms (at 1000 dpi) where acceleration starts."""
        self.max_factor = 2.0 + 1.5 * speed
        self.incline = 1.1 + 0.75 * speed

    def __call__(self, velocity: float) -> float:
        """The factor for a velocity in 1000-dpi counts per ms (non-decreasing, capped)."""
        if velocity < 0.07:
            factor = 10.0 * velocity + 0.3
        elif velocity < self.threshold:
            factor = 1.0
        else:
            factor = self.incline * (velocity - self.threshold) + 1.0
        return min(self.max_factor, factor)


def _check_speed(speed: float) -> None:
    if not (math.isfinite(speed) and -1.0 <= speed <= 1.0):
        raise ConfigError(f"option speed={speed!r} is not valid: expected a number in [-1, 1]")


def effective_multiplier(field: Field, value: int) -> int:
    """The kernel's ``hid_calculate_multiplier`` for a Resolution Multiplier field set to ``value``.

    ``(v - lmin) / (lmax - lmin) * (pmax - pmin) + pmin`` in C integer arithmetic (the division truncates
    towards zero); an empty logical range, 0 and anything beyond ±255 give 1, as the kernel has it.
    """
    span = field.logical_max - field.logical_min
    if span == 0:
        return 1
    offset = value - field.logical_min
    quotient = abs(offset) // abs(span) * (1 if (offset < 0) == (span < 0) else -1)
    multiplier = quotient * (field.physical_max - field.physical_min) + field.physical_min
    return multiplier if multiplier and -MAX_MULTIPLIER <= multiplier <= MAX_MULTIPLIER else 1


@dataclass(frozen=True)
class _Plan:
    """What one input report carries for a mouse: the keys of its values and their fields."""

    x: Field | None
    y: Field | None
    wheel: Field | None
    pan: Field | None
    buttons: tuple[int, ...]


def _first(value: int | list[int] | None) -> int:
    """A decoded value, the first element where a usage repeats (0 when absent)."""
    if value is None:
        return 0
    return value[0] if isinstance(value, list) else value


def _key(usage: int) -> tuple[int, int]:
    return usage >> 16, usage & 0xFFFF


def _scope(collection: Collection | None) -> Collection | None:
    """The collection a Resolution Multiplier applies to: the nearest logical one, else the outermost."""
    node = collection
    while node is not None and node.kind != CollectionKind.LOGICAL and node.parent is not None:
        node = node.parent
    return node


def _inside(field: Field, scope: Collection | None) -> bool:
    node = field.collection
    while node is not None:
        if node == scope:
            return True
        node = node.parent
    return scope is None


class Mouse:
    """A mouse, trackball or absolute pointer: Motion, Wheel, Button and (absolute) Axis events."""

    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("dpi", positive, None, "counts per inch of motion (overrides the descriptor's physical range)"),
        OptionSpec("acceleration", choice("none", "flat", "adaptive"), "none",
                   "pointer acceleration profile (libinput's flat or adaptive)"),
        OptionSpec("speed", number(-1.0, 1.0), 0.0, "pointer speed -1..1 for the flat and adaptive profiles"),
        OptionSpec("hires", boolean, True, "enable a hi-res wheel through its Resolution Multiplier feature"),
    )

    def __init__(self, descriptor: ReportDescriptor, device: DeviceId, **options: object) -> None:
        self.descriptor = descriptor
        self.device = device
        opts = read_semantics_options(self.OPTIONS, options, f"mouse semantics for {device}")
        if opts["acceleration"] == "none" and "speed" in opts.given:
            raise ConfigError(f"mouse semantics for {device}: option speed needs acceleration=flat or adaptive")
        self.profile: FlatProfile | AdaptiveProfile | None = None
        if opts["acceleration"] == "flat":
            self.profile = FlatProfile(opts["speed"])
        elif opts["acceleration"] == "adaptive":
            self.profile = AdaptiveProfile(opts["speed"])
        self.hires = bool(opts["hires"])
        self._plans = {rid: self._plan(fields) for rid, fields in descriptor.input_reports.items()}
        any_x = next((p.x for p in self._plans.values() if p.x is not None), None)
        any_y = next((p.y for p in self._plans.values() if p.y is not None), None)
        self.absolute = any_x is not None and not any_x.is_relative
        """Whether X/Y are absolute (an absolute pointer: Axis events instead of Motion)."""
        dpi = opts["dpi"]
        self.resolution = (dpi / MM_PER_INCH, dpi / MM_PER_INCH) if dpi is not None else (
            _resolution(any_x), _resolution(any_y))
        """Counts per mm along X and Y (None where unknown)."""
        self._multiplier_reports, self._multipliers = self._multiplier_setup()
        self._buttons: set[int] = set()
        self._remainder = [0.0, 0.0]
        self._last_time: float | None = None
        self._last_velocity = 0.0
        self._position: dict[str, int] = {}

    # -- setup ---------------------------------------------------------------------------------------

    @staticmethod
    def _plan(fields: Iterable[Field]) -> _Plan:
        found: dict[int, Field] = {}
        buttons: list[int] = []
        for f in fields:
            if f.is_constant:
                continue
            for usage in f.usages:
                found.setdefault(usage, f)
                if usage >> 16 == BUTTON_PAGE and usage & 0xFFFF and usage & 0xFFFF not in buttons:
                    buttons.append(usage & 0xFFFF)
        return _Plan(found.get(GD_X), found.get(GD_Y), found.get(GD_WHEEL), found.get(CONSUMER_AC_PAN),
                     tuple(buttons))

    def _multiplier_setup(self) -> tuple[list[OutputReport], dict[Field, int]]:
        """The feature reports that enable the hi-res wheels, and each wheel field's multiplier."""
        reports = []
        multipliers: dict[Field, int] = {}
        wheels = [f for p in self._plans.values() for f in (p.wheel, p.pan) if f is not None]
        for report_id, fields in self.descriptor.feature_reports.items():
            settings = [f for f in fields if GD_RESOLUTION_MULTIPLIER in f.usages and not f.is_constant]
            if not settings:
                continue
            for f in settings:
                value = f.logical_max if self.hires else f.logical_min
                scope = _scope(f.collection)
                for wheel in wheels:
                    if _inside(wheel, scope):
                        multipliers[wheel] = effective_multiplier(f, value)
            if self.hires:
                values = [f.logical_max for f in settings for _ in range(f.count)]
                payload = {_key(GD_RESOLUTION_MULTIPLIER): values[0] if len(values) == 1 else values}
                data = self.descriptor.encode(payload, report_id=report_id, kind=ReportKind.FEATURE)
                reports.append(OutputReport(ReportKind.FEATURE, report_id, data))
        return reports, multipliers

    def output_reports(self) -> list[OutputReport]:
        """The feature reports to send after opening: each Resolution Multiplier set to its maximum.

        Other fields of such a report are sent as 0 (the kernel reads the report first to keep them).
        """
        return list(self._multiplier_reports)

    def describe(self) -> str:
        """What was found: relative/absolute axes, resolution, wheels and their multipliers, buttons."""
        kind = "absolute pointer" if self.absolute else "relative mouse"
        res = f"{self.resolution[0] * MM_PER_INCH:.0f} dpi" if self.resolution[0] else "resolution unknown"
        wheel = next((p.wheel for p in self._plans.values() if p.wheel is not None), None)
        pan = next((p.pan for p in self._plans.values() if p.pan is not None), None)
        parts = [f"{self.device}: {kind}, {res}"]
        for name, f in (("wheel", wheel), ("AC pan", pan)):
            if f is not None:
                parts.append(f"{name} x1/{self._multipliers.get(f, 1)}")
        buttons = sorted({b for p in self._plans.values() for b in p.buttons})
        parts.append(f"{len(buttons)} buttons")
        if self.profile is not None:
            parts.append(f"{type(self.profile).__name__}")
        return ", ".join(parts)

    # -- reports -------------------------------------------------------------------------------------

    def feed(self, report: bytes, time: float) -> list[InputEvent]:
        """The events of one input report: Motion (or Axis x/y), Wheel, then Button edges."""
        report_id = self.descriptor.report_id_of(report)
        values = self.descriptor.decode(report)  # the per-report compiled function, found by one lookup
        plan = self._plans[report_id]
        events: list[InputEvent] = []
        if self.absolute:
            events.extend(self._absolute(plan, values, time))
        elif plan.x is not None or plan.y is not None:
            motion = self._motion(_first(values.get(_key(GD_X))), _first(values.get(_key(GD_Y))), time)
            if motion is not None:
                events.append(motion)
        vertical = self._detents(plan.wheel, values, GD_WHEEL)
        horizontal = self._detents(plan.pan, values, CONSUMER_AC_PAN)
        if vertical or horizontal:
            events.append(Wheel(time, self.device, vertical=vertical, horizontal=horizontal))
        for button in plan.buttons:
            pressed = bool(_first(values.get((BUTTON_PAGE, button))))
            if pressed != (button in self._buttons):
                (self._buttons.add if pressed else self._buttons.discard)(button)
                events.append(Button(time, self.device, button=button, pressed=pressed,
                                     name=BUTTON_NAMES.get(button, f"button{button}")))
        return events

    def _detents(self, field: Field | None, values: Values, usage: int) -> float:
        if field is None:
            return 0.0
        return _first(values.get(_key(usage))) / self._multipliers.get(field, 1)

    def _motion(self, dx: int, dy: int, time: float) -> Motion | None:
        if not dx and not dy:
            return None
        rx, ry = self.resolution
        dx_mm = dx / rx if rx else None
        dy_mm = dy / ry if ry else None
        out_x, out_y = dx, dy
        if self.profile is not None:
            factor = self._factor(dx, dy, time)
            fx = dx * factor + self._remainder[0]
            fy = dy * factor + self._remainder[1]
            out_x, out_y = round(fx), round(fy)
            self._remainder = [fx - out_x, fy - out_y]
        self._last_time = time
        return Motion(time, self.device, dx=out_x, dy=out_y, dx_mm=dx_mm, dy_mm=dy_mm)

    def _factor(self, dx: int, dy: int, time: float) -> float:
        """The acceleration factor of this motion (Simpson's average over the previous and this velocity)."""
        assert self.profile is not None
        dt_ms = 1000.0 if self._last_time is None else min(1000.0, max(0.125, (time - self._last_time) * 1000.0))
        dpi = self.resolution[0] * MM_PER_INCH if self.resolution[0] else DEFAULT_DPI
        velocity = math.hypot(dx, dy) * (DEFAULT_DPI / dpi) / dt_ms
        last, self._last_velocity = self._last_velocity, velocity
        return (self.profile(velocity) + self.profile(last) + 4.0 * self.profile((velocity + last) / 2.0)) / 6.0

    def _absolute(self, plan: _Plan, values: Values, time: float) -> list[InputEvent]:
        events: list[InputEvent] = []
        for name, field, usage in (("x", plan.x, GD_X), ("y", plan.y, GD_Y)):
            if field is None or _key(usage) not in values:
                continue
            raw = _first(values[_key(usage)])
            if self._position.get(name) == raw:
                continue
            self._position[name] = raw
            span = field.logical_max - field.logical_min
            value = min(1.0, max(0.0, (raw - field.logical_min) / span)) if span else 0.0
            events.append(Axis(time, self.device, axis=name, value=value, raw=raw))
        return events


def _resolution(field: Field | None) -> float | None:
    """Counts per mm of a length field from its physical range, unit and exponent (None when not a length).

    Exact, where the kernel's ``hidinput_calc_abs_res`` rounds to a whole number (400 cpi is 15.75/mm, not 16).
    """
    if field is None:
        return None
    try:
        mm_per_count = units.to_mm(field, 1) - units.to_mm(field, 0)
    except InvalidArgument:
        return None
    return 1.0 / mm_per_count if mm_per_count > 0 else None

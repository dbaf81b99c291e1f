"""Joystick and game pad semantics: calibrated axes with dead zones and response curves, hats, buttons.

:class:`Joystick` handles Generic Desktop Joystick, Game Pad and Multi-axis Controller applications.
Each report is processed in this order, and an event is sent only when its value changes (the
first report sends every axis, since nothing is known before it):

1. **Calibration** — each axis maps ``min .. centre .. max`` to -1..1 (sticks, twist, wheel,
   rudder) or ``min .. max`` to 0..1 (slider, dial, throttle, accelerator, brake), from its
   logical range unless the ``calibration`` option gives ``name=min:centre:max`` (or
   ``name=min:max`` for a 0..1 axis), entries separated by commas.  Values outside are clamped.
2. **Radial dead zone** (``radial_deadzone``, a fraction of full deflection) on the stick pairs
   named by ``sticks`` (``x:y,rx:ry`` by default; a DualShock-style pad has ``x:y,z:rz``): a
   magnitude *m* at or below *d* becomes 0, above it ``(min(m, 1) − d) / (1 − d)`` in the same
   direction, so the output stays inside the unit circle.
3. **Axial dead zone** (``deadzone``) per axis: ``|v| ≤ d`` gives 0, above it
   ``sign(v)·(|v| − d)/(1 − d)`` (0..1 axes: ``(v − d)/(1 − d)``).
4. **Response curve** (``curve``): ``linear``; ``power`` ``sign(v)·|v|^exponent``; ``cubic``
   ``(1 − w)·v + w·v³`` with ``w = cubic_weight``.  Every curve is odd, monotonic and keeps the range.

Hat switches (Generic Desktop 0x39) give one of 8 directions or ``centre``: a value outside the
logical range is the null state (centred); otherwise the angle comes from the physical range when
the unit is a rotation (English Rotation degrees 0x14 or SI Rotation radians 0x12, through
:func:`pixelpen.devices.hid.units.to_degrees`), else from the position count (4 positions: 90°
steps; 8 positions: 45°), clockwise from up, rounded to the nearest 45° — so 4- and 8-way hats, any
logical minimum and rotated ranges all work.  Buttons are Button page usages with edges.

Axes are indexed as SDL's Linux backend sees a HID joystick (for GameControllerDB mappings): in
the order of the kernel's ABS codes (X, Y, Z, Rx, Ry, Rz, Throttle/Slider, Rudder/Dial,
Wheel/Steering, Gas, Brake; a usage whose code is already taken gets no SDL index, as the kernel
drops it, though it still gives its own ``x2``-style events), buttons by usage number, hats in
descriptor order.  With the ``mapping`` option (an SDL GameControllerDB mapping string) the events
are the named gamepad's instead: ``Axis("leftx")``, ``Button(name="a")`` (press and release edges, as
for raw buttons), see :mod:`pixelpen.devices.hid.gamecontrollerdb`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from pixelpen.devices.hid import units
from pixelpen.devices.hid.events import Axis, Button, DeviceId, Hat, InputEvent
from pixelpen.devices.hid.fields import Field, ReportDescriptor, Values
from pixelpen.devices.hid.gamecontrollerdb import GamepadMapping, GamepadState, parse_mapping
from pixelpen.devices.hid.semantics import read_semantics_options
from pixelpen.errors import ConfigError
from pixelpen.options import OptionSpec, choice, number, positive

__all__ = ["AXES", "HAT_DIRECTIONS", "AxisCalibration", "Joystick", "JoystickState", "ResponseCurve",
           "axial_deadzone", "hat_direction", "radial_deadzone"]

GD_HAT_SWITCH = 0x00010039
BUTTON_PAGE = 0x09

AXES: dict[int, tuple[str, int, bool]] = {
    0x00010030: ("x", 0x00, True),
    0x00010031: ("y", 0x01, True),
    0x00010032: ("z", 0x02, True),
    0x00010033: ("rx", 0x03, True),
    0x00010034: ("ry", 0x04, True),
    0x00010035: ("rz", 0x05, True),
    0x00010036: ("slider", 0x06, False),
    0x00010037: ("dial", 0x07, False),
    0x00010038: ("wheel", 0x08, True),
    0x000200BA: ("rudder", 0x07, True),
    0x000200BB: ("throttle", 0x06, False),
    0x000200C4: ("accelerator", 0x09, False),
    0x000200C5: ("brake", 0x0A, False),
    0x000200C8: ("steering", 0x08, True),
}
"""Axis usage -> (name, the kernel's ABS code in hid-input.c, centred: -1..1 rather than 0..1)."""

HAT_DIRECTIONS: tuple[tuple[str, int, int, int], ...] = (
    ("centre", 0, 0, 0),
    ("up", 0, 1, 1), ("up-right", 1, 1, 3), ("right", 1, 0, 2), ("down-right", 1, -1, 6),
    ("down", 0, -1, 4), ("down-left", -1, -1, 12), ("left", -1, 0, 8), ("up-left", -1, 1, 9),
)
"""Hat direction 0 (centre) .. 8 (up-left, clockwise): name, dx, dy (y up), SDL's mask (1 up 2 right 4 down 8 left)."""

MAX_BUTTONS = 1024
"""Buttons kept per device (the Button page has 65535 usages; a descriptor asking for more is refused)."""


@dataclass(frozen=True)
class AxisCalibration:
    """Where an axis's raw values sit: ``minimum``, ``maximum``, and ``centre`` for a -1..1 axis (None: 0..1)."""

    minimum: float
    maximum: float
    centre: float | None = None

    def __post_init__(self) -> None:
        values = (self.minimum, self.maximum) if self.centre is None else (self.minimum, self.centre, self.maximum)
        increasing = all(a < b for a, b in itertools.pairwise(values))
        if not (all(math.isfinite(v) for v in values) and increasing):
            raise ConfigError(f"calibration {':'.join(f'{v:g}' for v in values)} is not valid: expected "
                              "increasing numbers min:max or min:centre:max")

    def normalise(self, raw: float) -> float:
        """-1..1 around the centre (0..1 from the minimum when there is no centre), clamped."""
        if self.centre is None:
            return min(1.0, max(0.0, (raw - self.minimum) / (self.maximum - self.minimum)))
        if raw < self.centre:
            return max(-1.0, (raw - self.centre) / (self.centre - self.minimum))
        return min(1.0, (raw - self.centre) / (self.maximum - self.centre))


def axial_deadzone(value: float, deadzone: float) -> float:
    """Zero within ``deadzone`` of rest, rescaled beyond so that full deflection stays full."""
    if deadzone <= 0.0:
        return value
    magnitude = abs(value)
    if magnitude <= deadzone:
        return 0.0
    return math.copysign((magnitude - deadzone) / (1.0 - deadzone), value)


def radial_deadzone(x: float, y: float, deadzone: float) -> tuple[float, float]:
    """A stick's dead zone on its magnitude: zero inside the circle, rescaled outside (direction kept, |v| ≤ 1).

    ``deadzone`` 0 turns it off: ``x, y`` come back as they are (a square gate's corners stay beyond 1).
    """
    if deadzone <= 0.0:
        return x, y
    magnitude = math.hypot(x, y)
    if magnitude <= deadzone:
        return 0.0, 0.0
    scale = (min(magnitude, 1.0) - deadzone) / (1.0 - deadzone) / magnitude
    return x * scale, y * scale


class ResponseCurve:
    """A monotonic odd curve on -1..1: ``linear``, ``power`` (``exponent``) or ``cubic`` (``cubic_weight``)."""

    def __init__(self, kind: str = "linear", exponent: float = 2.0, cubic_weight: float = 0.5) -> None:
        if kind not in ("linear", "power", "cubic"):
            raise ConfigError(f"option curve={kind!r} is not valid: expected linear, power or cubic")
        if not (math.isfinite(exponent) and exponent > 0):
            raise ConfigError(f"option exponent={exponent!r} is not valid: expected a finite number > 0")
        if not (0.0 <= cubic_weight <= 1.0):
            raise ConfigError(f"option cubic_weight={cubic_weight!r} is not valid: expected a number in [0, 1]")
        self.kind = kind
        self.exponent = exponent
        self.cubic_weight = cubic_weight

    def __call__(self, value: float) -> float:
        """The curve's output for ``value`` in -1..1."""
        if self.kind == "power":
            return math.copysign(abs(value) ** self.exponent, value)
        if self.kind == "cubic":
            return (1.0 - self.cubic_weight) * value + self.cubic_weight * value ** 3
        return value


def hat_direction(field: Field, value: int) -> int:
    """0 for centre (the null state: outside the logical range), else 1 (up) .. 8 (up-left) clockwise."""
    if not field.logical_min <= value <= field.logical_max:
        return 0
    if field.unit in (0x12, 0x14) and field.physical_max != field.physical_min:
        angle = units.to_degrees(field, value)
    else:
        angle = (value - field.logical_min) * 360.0 / (field.logical_max - field.logical_min + 1)
    return round(angle / 45.0) % 8 + 1


@dataclass(frozen=True)
class JoystickState:
    """A joystick's current state as SDL's joystick layer indexes it (what a gamepad mapping reads).

    ``axes`` -1..1 each (0..1 axes stretched to -1..1, as SDL reports a trigger at rest as its
    minimum), ``buttons`` pressed or not, ``hats`` as SDL masks (1 up, 2 right, 4 down, 8 left).
    """

    axes: tuple[float, ...]
    buttons: tuple[bool, ...]
    hats: tuple[int, ...]


@dataclass
class _Axis:
    name: str
    usage: int
    field: Field
    index: int
    """Which element of the usage's values (a usage that repeats decodes to a list)."""
    calibration: AxisCalibration


def _calibrations(text: str) -> dict[str, tuple[float, ...]]:
    """The ``calibration`` option: ``name=min:centre:max`` or ``name=min:max``, comma separated."""
    result: dict[str, tuple[float, ...]] = {}
    for entry in filter(None, (e.strip() for e in text.split(","))):
        name, sep, numbers = entry.partition("=")
        try:
            values = tuple(float(v) for v in numbers.split(":"))
        except ValueError:
            values = ()
        if not sep or len(values) not in (2, 3):
            raise ValueError(f"expected name=min:max or name=min:centre:max, got {entry!r}")
        result[name.strip().lower()] = values
    return result


def _pairs(text: str) -> tuple[tuple[str, str], ...]:
    """The ``sticks`` option: ``x:y,rx:ry`` pairs of axis names."""
    pairs = []
    for entry in filter(None, (e.strip() for e in text.split(","))):
        names = entry.lower().split(":")
        if len(names) != 2 or not all(names):
            raise ValueError(f"expected pairs of axis names such as x:y, got {entry!r}")
        pairs.append((names[0], names[1]))
    return tuple(pairs)


def _fraction(value: str) -> float:
    """A dead zone: a fraction in [0, 1)."""
    result = number(0.0, 1.0)(value)
    if result >= 1.0:
        raise ValueError("expected a fraction in [0, 1) (1 would leave no travel)")
    return result


def _mapping(value: str) -> GamepadMapping | None:
    return parse_mapping(value, source="option mapping") if value.strip() else None


class Joystick:
    """A joystick or game pad: Axis, Hat and Button events, only on change (or named gamepad events with a mapping)."""

    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("calibration", _calibrations, {}, "per-axis raw range: name=min:centre:max or name=min:max, ..."),
        OptionSpec("deadzone", _fraction, 0.0, "axial dead zone, a fraction of full deflection"),
        OptionSpec("radial_deadzone", _fraction, 0.0, "radial dead zone of the stick pairs"),
        OptionSpec("sticks", _pairs, (("x", "y"), ("rx", "ry")), "stick axis pairs for the radial dead zone"),
        OptionSpec("curve", choice("linear", "power", "cubic"), "linear", "response curve"),
        OptionSpec("exponent", positive, 2.0, "exponent of curve=power"),
        OptionSpec("cubic_weight", number(0.0, 1.0), 0.5, "weight of the cubic term of curve=cubic"),
        OptionSpec("mapping", _mapping, None, "an SDL GameControllerDB mapping string: named gamepad events"),
    )

    def __init__(self, descriptor: ReportDescriptor, device: DeviceId, **options: object) -> None:
        self.descriptor = descriptor
        self.device = device
        where = f"joystick semantics for {device}"
        opts = read_semantics_options(self.OPTIONS, options, where)
        for name, needs in (("exponent", "power"), ("cubic_weight", "cubic")):
            if name in opts.given and opts["curve"] != needs:
                raise ConfigError(f"{where}: option {name} needs curve={needs}")
        self.deadzone: float = opts["deadzone"]
        self.radial: float = opts["radial_deadzone"]
        self.curve = ResponseCurve(opts["curve"], opts["exponent"], opts["cubic_weight"])
        self.mapping: GamepadMapping | None = opts["mapping"]
        self._axes_by_report: dict[int | None, list[_Axis]] = {}
        self._hats_by_report: dict[int | None, list[tuple[int, Field, int]]] = {}
        self._buttons_by_report: dict[int | None, tuple[int, ...]] = {}
        self._build(opts["calibration"], where)
        known = {a.name for a in self.axes}
        self.sticks = tuple((a, b) for a, b in opts["sticks"] if a in known and b in known
                            and self._axis(a).calibration.centre is not None
                            and self._axis(b).calibration.centre is not None)
        """The stick pairs the radial dead zone applies to (those of ``sticks`` the device has, both -1..1)."""
        self._raw: dict[str, int] = {}
        self._values: dict[str, float] = {}
        self._hat_state = [0] * self.hat_count
        self._pressed: set[int] = set()
        self._gamepad = GamepadState.released()

    def _build(self, calibration: Mapping[str, tuple[float, ...]], where: str) -> None:
        axes: list[tuple[int, int, _Axis]] = []
        hats = 0
        seen: dict[str, int] = {}
        buttons: set[int] = set()
        order = 0
        for report_id, fields in self.descriptor.input_reports.items():
            report_buttons: list[int] = []
            repeats: dict[int, int] = {}  # per report: the decoder lists a repeated usage's values report-wide
            for f in fields:
                if f.is_constant:
                    continue
                for usage in (f.usages if f.is_array else f.usages[:f.count]):
                    if usage >> 16 == BUTTON_PAGE and usage & 0xFFFF:
                        report_buttons.append(usage & 0xFFFF)
                        continue
                    if f.is_array:
                        continue
                    index = repeats[usage] = repeats.get(usage, -1) + 1
                    if usage == GD_HAT_SWITCH:
                        self._hats_by_report.setdefault(report_id, []).append((hats, f, index))
                        hats += 1
                    elif usage in AXES and not f.is_relative:
                        base, code, centred = AXES[usage]
                        seen[base] = seen.get(base, 0) + 1
                        name = base if seen[base] == 1 else f"{base}{seen[base]}"
                        cal = self._calibration(name, f, centred, calibration, where)
                        axis = _Axis(name, usage, f, index, cal)
                        self._axes_by_report.setdefault(report_id, []).append(axis)
                        axes.append((code, order, axis))
                        order += 1
            self._buttons_by_report[report_id] = tuple(dict.fromkeys(report_buttons))
            buttons.update(report_buttons)
        if len(buttons) > MAX_BUTTONS:
            raise ConfigError(f"{where}: the descriptor declares {len(buttons)} buttons (at most {MAX_BUTTONS})")
        unknown = sorted(set(calibration) - set(seen) - {n for _, _, a in axes for n in (a.name,)})
        if unknown:
            raise ConfigError(f"{where}: option calibration names axes the device lacks: {', '.join(unknown)} "
                              f"(it has {', '.join(a.name for _, _, a in axes) or 'none'})")
        ordered = sorted(axes, key=lambda t: (t[0], t[1]))
        self.axes: tuple[_Axis, ...] = tuple(a for _, _, a in ordered)
        """The axes in SDL's order (by the kernel's ABS code)."""
        self.sdl_axes: tuple[_Axis, ...] = tuple(a for i, (code, _, a) in enumerate(ordered)
                                                 if i == 0 or ordered[i - 1][0] != code)
        """The axes SDL's Linux backend sees: the first per ABS code (the kernel ignores a usage whose code is
        taken, ``HID_STAT_DUP_DETECTED``; a second X, or Slider beside Throttle, has no SDL index)."""
        self.buttons: tuple[int, ...] = tuple(sorted(buttons))
        """Button-page usages in SDL's order (by usage number)."""
        self.hat_count = hats

    @staticmethod
    def _calibration(name: str, f: Field, centred: bool, given: Mapping[str, tuple[float, ...]],
                     where: str) -> AxisCalibration:
        values = given.get(name)
        try:
            if values is not None:
                return AxisCalibration(values[0], values[-1], values[1] if len(values) == 3 else None)
            if f.logical_max <= f.logical_min:
                raise ConfigError(f"the logical range {f.logical_min}..{f.logical_max} is empty")
            return AxisCalibration(f.logical_min, f.logical_max,
                                   (f.logical_min + f.logical_max) / 2 if centred else None)
        except ConfigError as exc:
            raise ConfigError(f"{where}: option calibration for axis {name}: {exc}") from None

    def _axis(self, name: str) -> _Axis:
        return next(a for a in self.axes if a.name == name)

    def describe(self) -> str:
        """The axes (with their ranges), hats and buttons found."""
        axes = ", ".join(f"{a.name} {a.calibration.minimum:g}..{a.calibration.maximum:g}" for a in self.axes)
        mapped = f", mapped as {self.mapping.name!r}" if self.mapping else ""
        return (f"{self.device}: joystick, axes [{axes}], {self.hat_count} hats, {len(self.buttons)} buttons"
                f"{mapped}")

    # -- reports -------------------------------------------------------------------------------------

    def feed(self, report: bytes, time: float) -> list[InputEvent]:
        """The events of one input report: changed axes, then hats, then button edges."""
        report_id = self.descriptor.report_id_of(report)
        values = self.descriptor.decode(report)  # the per-report compiled function, found by one lookup
        for axis in self._axes_by_report.get(report_id, ()):
            self._raw[axis.name] = _element(values, axis.usage, axis.index)
        changed = self._process()
        hats = []
        for hat, f, index in self._hats_by_report.get(report_id, ()):
            raw = values.get((GD_HAT_SWITCH >> 16, GD_HAT_SWITCH & 0xFFFF))
            direction = hat_direction(f, _element(values, GD_HAT_SWITCH, index)) if raw is not None else 0
            if direction != self._hat_state[hat]:
                self._hat_state[hat] = direction
                hats.append(hat)
        edges = []
        for button in self._buttons_by_report.get(report_id, ()):
            pressed = bool(_element(values, BUTTON_PAGE << 16 | button, 0))
            if pressed != (button in self._pressed):
                (self._pressed.add if pressed else self._pressed.discard)(button)
                edges.append(button)
        if self.mapping is not None:
            return self._gamepad_events(time)
        events: list[InputEvent] = [Axis(time, self.device, axis=name, value=self._values[name], raw=self._raw[name])
                                    for name in changed]
        for hat in hats:
            name, dx, dy, _ = HAT_DIRECTIONS[self._hat_state[hat]]
            events.append(Hat(time, self.device, hat=hat, direction=name, dx=dx, dy=dy))
        events.extend(Button(time, self.device, button=b, pressed=b in self._pressed, name=f"button{b}")
                      for b in edges)
        return events

    def _process(self) -> list[str]:
        """Calibrate, dead-zone and curve every axis with a value; the names whose value changed."""
        norm = {a.name: a.calibration.normalise(self._raw[a.name]) for a in self.axes if a.name in self._raw}
        for a, b in self.sticks:
            if a in norm and b in norm:
                norm[a], norm[b] = radial_deadzone(norm[a], norm[b], self.radial)
        changed = []
        for a in self.axes:
            if a.name not in norm:
                continue
            value = self.curve(axial_deadzone(norm[a.name], self.deadzone))
            if self._values.get(a.name) != value:
                self._values[a.name] = value
                changed.append(a.name)
        return changed

    def state(self) -> JoystickState:
        """The current state in SDL's indexing (axes not yet reported are at rest: centre, or minimum for 0..1)."""
        axes = []
        for a in self.sdl_axes:
            value = self._values.get(a.name, 0.0)
            axes.append(value if a.calibration.centre is not None else 2.0 * value - 1.0)
        return JoystickState(tuple(axes), tuple(b in self._pressed for b in self.buttons),
                             tuple(HAT_DIRECTIONS[d][3] for d in self._hat_state))

    def values(self) -> dict[str, float]:
        """The current processed value of every axis reported so far, by name."""
        return dict(self._values)

    def _gamepad_events(self, time: float) -> list[InputEvent]:
        assert self.mapping is not None
        new = self.mapping.apply(self.state())
        events: list[InputEvent] = [Axis(time, self.device, axis=name, value=value, raw=round(value * 32767))
                                    for name, value in new.axes.items() if self._gamepad.axes.get(name) != value]
        events.extend(Button(time, self.device, button=new.button_number(name), pressed=down, name=name)
                      for name, down in new.buttons.items() if self._gamepad.buttons.get(name, False) != down)
        self._gamepad = new
        return events


def _element(values: Values, usage: int, index: int) -> int:
    value = values.get((usage >> 16, usage & 0xFFFF), 0)
    if isinstance(value, list):
        return value[index] if index < len(value) else 0
    return value

"""One event model for every input device: timestamped events that carry the device's identity.

Device semantics (:mod:`pixelpen.devices.hid.mouse`, ``joystick``, ``tablet``, ``touch``,
``keyboard``, and the evdev mapping) turn decoded reports into these; the logical input devices
of :mod:`pixelpen.input` consume them.  Times are seconds on the injectable clock
(:mod:`pixelpen.clock`) of the link that read the report.  Every event is a frozen dataclass whose
fields are keyword-only after ``time`` and ``device``.
"""

from __future__ import annotations

from dataclasses import dataclass

from pixelpen.drivers.identity import DeviceId

__all__ = ["Axis", "Button", "Contact", "DeviceAdded", "DeviceId", "DeviceRemoved", "Hat", "InputEvent", "Key",
           "Motion", "Pen", "TouchFrame", "Wheel"]


@dataclass(frozen=True, slots=True)
class InputEvent:
    """The base of every event: when it happened and which device sent it."""

    time: float
    device: DeviceId


@dataclass(frozen=True, slots=True, kw_only=True)
class Motion(InputEvent):
    """Relative motion of a mouse or trackball, in counts and, when the resolution is known, in mm."""

    dx: int
    dy: int
    dx_mm: float | None = None
    dy_mm: float | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class Button(InputEvent):
    """A button pressed or released (``button`` is the Button page usage: 1 = primary)."""

    button: int
    pressed: bool
    name: str = ""


@dataclass(frozen=True, slots=True, kw_only=True)
class Wheel(InputEvent):
    """Wheel motion in detents (fractions with a hi-res wheel); ``horizontal`` is AC Pan / tilt."""

    vertical: float = 0.0
    horizontal: float = 0.0


@dataclass(frozen=True, slots=True, kw_only=True)
class Axis(InputEvent):
    """An absolute axis changed: ``value`` normalised (-1..1 for sticks, 0..1 for triggers), ``raw`` logical."""

    axis: str
    value: float
    raw: int


@dataclass(frozen=True, slots=True, kw_only=True)
class Hat(InputEvent):
    """A hat switch moved: one of 8 directions or ``centre``, with its unit vector (y up)."""

    hat: int
    direction: str
    dx: int
    dy: int


@dataclass(frozen=True, slots=True, kw_only=True)
class Key(InputEvent):
    """A key pressed or released: its Keyboard-page usage, name, the character by layout, modifiers held."""

    usage: int
    key: str
    pressed: bool
    char: str = ""
    modifiers: frozenset[str] = frozenset()


@dataclass(frozen=True, slots=True, kw_only=True)
class Pen(InputEvent):
    """A tablet pen's state: position (mm and 0..1), pressure, tilt, proximity, tip, buttons, eraser."""

    x_mm: float
    y_mm: float
    x: float
    y: float
    pressure: float = 0.0
    tilt_x: float = 0.0
    tilt_y: float = 0.0
    """Tilt in degrees (positive x: towards the right, positive y: towards the user)."""
    in_range: bool = True
    touching: bool = False
    barrel: tuple[bool, ...] = ()
    eraser: bool = False
    inverted: bool = False
    serial: int | None = None


@dataclass(frozen=True, slots=True)
class Contact:
    """One finger of a touch frame: its contact ID, position (mm and 0..1), tip and confidence."""

    contact_id: int
    x_mm: float
    y_mm: float
    x: float
    y: float
    touching: bool = True
    confidence: bool = True


@dataclass(frozen=True, slots=True, kw_only=True)
class TouchFrame(InputEvent):
    """All contacts of one scan of a touch screen (a hybrid-mode frame assembled from its reports)."""

    contacts: tuple[Contact, ...]


@dataclass(frozen=True, slots=True)
class DeviceAdded(InputEvent):
    """A device appeared (plugged in, or the first time it is seen)."""


@dataclass(frozen=True, slots=True)
class DeviceRemoved(InputEvent):
    """A device went away (unplugged during a read, or no longer enumerated)."""

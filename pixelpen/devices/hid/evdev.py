"""evdev semantics: the kernel's input events, frame by frame (SYN_REPORT), as pixelpen events.

:class:`EvdevSemantics` is fed one evdev event at a time (``feed_event(time, type, code, value)``, from
:class:`pixelpen.drivers.evdev.EvdevLink` or an evemu/libinput recording) and answers with the events of
each frame when its ``SYN_REPORT`` arrives, in this order:

* **Motion** — ``REL_X``/``REL_Y`` counts summed over the frame; mm from the ``dpi`` option (evdev does not
  report a relative resolution).
* **Wheel** — ``REL_WHEEL`` (+ away from the user) and ``REL_HWHEEL`` (+ right) in detents; where the frame
  holds ``REL_WHEEL_HI_RES``/``REL_HWHEEL_HI_RES`` those count instead, 120 to a detent (the kernel sends
  both, the low-resolution one only per whole detent).
* **Axis** — every other absolute axis that changed, normalised over its ``min..max``: -1..1, except the
  one-sided throttle, gas and brake (0..1); ``raw`` is the kernel's value.  Not sent for the axes a pen
  or touch device uses.
* **Hat** — ``ABS_HAT0X..ABS_HAT3Y`` (-1 left/up, +1 right/down) as one of 8 directions or centre (y up).
* **Pen** — a device with ``ABS_PRESSURE`` or a pen tool (``BTN_TOOL_PEN``/``RUBBER``/``BRUSH``/``PENCIL``/
  ``AIRBRUSH``) and no multi-touch axes: position in mm (the kernel's resolution is units/mm; NaN when 0)
  and 0..1, pressure 0..1, tilt in degrees (resolution units/radian; 0 resolution: the range over libinput's
  -64..64 degrees), ``in_range`` while a tool key is down (always, for a device without tool keys),
  ``touching`` ``BTN_TOUCH``, ``barrel`` ``BTN_STYLUS``/``STYLUS2``/``STYLUS3`` (those the device has,
  else the first two), ``eraser``/``inverted`` ``BTN_TOOL_RUBBER``, ``serial`` ``MSC_SERIAL``.  Sent when
  it changes; leaving proximity sends one event with ``in_range=False``.
* **TouchFrame** — multi-touch protocol B: ``ABS_MT_SLOT`` selects a slot, ``ABS_MT_TRACKING_ID`` >= 0
  starts a contact (its ID) and -1 ends it, ``ABS_MT_POSITION_X/Y`` move it; a frame holds the contacts
  touching and, once, each contact lifted (``touching=False``), as the HID touch screen does.  The
  single-touch emulation (``ABS_X``, ``BTN_TOUCH``, ``BTN_TOOL_FINGER``...) of such a device is ignored.
* **Button** — ``BTN_LEFT..BTN_TASK`` as buttons 1..8 (the mouse's names), ``BTN_0..BTN_9`` (buttons 1..10,
  ``misc``), joystick ``BTN_TRIGGER..`` (1..16) and gamepad ``BTN_SOUTH..BTN_THUMBR`` (the kernel's names
  a, b, c, x, y, z, tl, tr, tl2, tr2, select, start, mode, thumbl, thumbr).
* **Key** — the other ``KEY_*`` codes: the Keyboard-page usage the kernel maps to the code (its
  ``hid_keyboard`` table read backwards, lowest usage first), its name and character through
  :mod:`~pixelpen.devices.hid.keymaps` (option ``layout``) with Shift, AltGr, Caps Lock and Num Lock
  followed from the frames; codes no keyboard usage gives have usage 0 and the name ``key_<code>``.
  Autorepeat (value 2) is not an edge and gives nothing.

``SYN_DROPPED`` (the client fell behind and the kernel's buffer overflowed) discards the frame in progress
and every event up to and including the next ``SYN_REPORT``, as libevdev documents; the state read before
the drop is kept (a reader with the device at hand resyncs it from the kernel).  Codes are the kernel's
(``linux/input-event-codes.h``); python-evdev is not needed.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import astuple, dataclass, replace
from typing import Any, ClassVar

from pixelpen.devices.hid.events import (
    Axis,
    Button,
    Contact,
    DeviceId,
    Hat,
    InputEvent,
    Key,
    Motion,
    Pen,
    TouchFrame,
    Wheel,
)
from pixelpen.devices.hid.joystick import HAT_DIRECTIONS
from pixelpen.devices.hid.keymaps import MODIFIER_NAMES, Layout, key_name, layout
from pixelpen.devices.hid.mouse import BUTTON_NAMES, MM_PER_INCH
from pixelpen.devices.hid.semantics import read_semantics_options
from pixelpen.devices.hid.tablet import DEFAULT_TILT_DEGREES
from pixelpen.drivers.recordings.evemu import EV_ABS, EV_KEY, EV_MSC, EV_REL, EV_SYN, AbsInfo
from pixelpen.options import OptionSpec, positive, text

__all__ = ["ABS_NAMES", "KEY_USAGES", "REL_NAMES", "EvdevSemantics"]

SYN_REPORT, SYN_DROPPED = 0x00, 0x03
REL_X, REL_Y, REL_HWHEEL, REL_WHEEL, REL_WHEEL_HI_RES, REL_HWHEEL_HI_RES = 0x00, 0x01, 0x06, 0x08, 0x0B, 0x0C
ABS_X, ABS_Y, ABS_PRESSURE, ABS_DISTANCE, ABS_TILT_X, ABS_TILT_Y = 0x00, 0x01, 0x18, 0x19, 0x1A, 0x1B
ABS_HAT0X, ABS_HAT3Y = 0x10, 0x17
ABS_MT_SLOT, ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_TRACKING_ID = 0x2F, 0x35, 0x36, 0x39
MSC_SERIAL = 0x00
BTN_MISC, BTN_LEFT, BTN_JOYSTICK, BTN_GAMEPAD, BTN_DIGI = 0x100, 0x110, 0x120, 0x130, 0x140
BTN_TOOL_PEN, BTN_TOOL_RUBBER, BTN_TOOL_BRUSH, BTN_TOOL_PENCIL, BTN_TOOL_AIRBRUSH = 0x140, 0x141, 0x142, 0x143, 0x144
BTN_TOUCH, BTN_STYLUS, BTN_STYLUS2, BTN_STYLUS3 = 0x14A, 0x14B, 0x14C, 0x149
HI_RES_PER_DETENT = 120
"""REL_WHEEL_HI_RES units in one detent (the kernel's convention, ``input-event-codes.h``)."""

REL_NAMES: Mapping[int, str] = {0x00: "x", 0x01: "y", 0x02: "z", 0x03: "rx", 0x04: "ry", 0x05: "rz", 0x06: "hwheel",
                                0x07: "dial", 0x08: "wheel", 0x09: "misc", 0x0B: "wheel_hi_res",
                                0x0C: "hwheel_hi_res"}
"""REL code -> name (the kernel's REL_* in lower case)."""
ABS_NAMES: Mapping[int, str] = {
    0x00: "x", 0x01: "y", 0x02: "z", 0x03: "rx", 0x04: "ry", 0x05: "rz", 0x06: "throttle", 0x07: "rudder",
    0x08: "wheel", 0x09: "gas", 0x0A: "brake", **{0x10 + i: f"hat{i // 2}{'xy'[i % 2]}" for i in range(8)},
    0x18: "pressure", 0x19: "distance", 0x1A: "tilt_x", 0x1B: "tilt_y", 0x1C: "tool_width", 0x20: "volume",
    0x21: "profile", 0x28: "misc"}
"""ABS code -> name (the kernel's ABS_* in lower case); others are ``abs_0xNN``."""
ONE_SIDED = frozenset({0x06, 0x09, 0x0A})
"""Axes normalised to 0..1: ABS_THROTTLE, ABS_GAS, ABS_BRAKE."""
PEN_TOOLS = frozenset(range(BTN_TOOL_PEN, BTN_TOOL_AIRBRUSH + 1))
PEN_AXES = frozenset({ABS_X, ABS_Y, ABS_PRESSURE, ABS_DISTANCE, ABS_TILT_X, ABS_TILT_Y})
DIGITIZER_KEYS = frozenset(range(BTN_DIGI, BTN_DIGI + 0x10))
"""BTN_TOOL_PEN .. BTN_TOOL_QUADTAP, BTN_TOUCH, BTN_STYLUS*: pen and touch state, never Button or Key events."""
GAMEPAD_NAMES = ("a", "b", "c", "x", "y", "z", "tl", "tr", "tl2", "tr2", "select", "start", "mode", "thumbl",
                 "thumbr")
"""BTN_SOUTH (BTN_A) .. BTN_THUMBR, as the kernel names them."""


def _key_usages() -> dict[int, int]:
    """Linux key code -> the lowest Keyboard-page usage the kernel's ``hid_keyboard`` maps to it."""
    rows = (  # usage 0x04.. in order: the KEY_* code each gives (0: none)
        (0x04, (30, 48, 46, 32, 18, 33, 34, 35, 23, 36, 37, 38, 50, 49, 24, 25, 16, 19, 31, 20, 22, 47, 17, 45, 21,
                44, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 28, 1, 14, 15, 57, 12, 13, 26, 27, 43, 43, 39, 40, 41, 51, 52,
                53, 58, 59, 60, 61, 62, 63, 64, 65, 66, 67, 68, 87, 88, 99, 70, 119, 110, 102, 104, 111, 107, 109,
                106, 105, 108, 103, 69, 98, 55, 74, 78, 96, 79, 80, 81, 75, 76, 77, 71, 72, 73, 82, 83, 86, 127,
                116, 117, 183, 184, 185, 186, 187, 188, 189, 190, 191, 192, 193, 194, 134, 138, 130, 132, 128, 129,
                131, 137, 133, 135, 136, 113, 115, 114, 0, 0, 0, 121, 0, 89, 93, 124, 92, 94, 95, 0, 0, 0, 122, 123,
                90, 91, 85)),
        (0xE0, (29, 42, 56, 125, 97, 54, 100, 126)),
    )
    table: dict[int, int] = {}
    for start, codes in rows:
        for offset, code in enumerate(codes):
            if code:
                table.setdefault(code, start + offset)
    return table


KEY_USAGES: Mapping[int, int] = _key_usages()
"""Linux KEY_* code -> Keyboard-page usage ID (the kernel's ``hid_keyboard`` read backwards, lowest usage first)."""
_CAPS_LOCK, _NUM_LOCK, _RIGHT_ALT = 0x39, 0x53, 0xE6


def _button(code: int) -> tuple[int, str] | None:
    """(button number, name) for a BTN_* code that is a plain button, None for keys and pen/touch codes."""
    if BTN_LEFT <= code < BTN_LEFT + 8:
        number = code - BTN_LEFT + 1
        return number, BUTTON_NAMES[number]
    if BTN_MISC <= code < BTN_MISC + 10:
        return code - BTN_MISC + 1, f"misc{code - BTN_MISC}"
    if BTN_JOYSTICK <= code < BTN_JOYSTICK + 16:
        return code - BTN_JOYSTICK + 1, f"button{code - BTN_JOYSTICK + 1}"
    if BTN_GAMEPAD <= code < BTN_GAMEPAD + len(GAMEPAD_NAMES):
        return code - BTN_GAMEPAD + 1, GAMEPAD_NAMES[code - BTN_GAMEPAD]
    return None


def _normalised(info: AbsInfo | None, value: int, *, one_sided: bool) -> float:
    """``value`` over the axis range: 0..1 or -1..1, clamped (0 for an unknown or empty range)."""
    if info is None or info.max <= info.min:
        return 0.0
    fraction = min(1.0, max(0.0, (value - info.min) / (info.max - info.min)))
    return fraction if one_sided else 2.0 * fraction - 1.0


def _mm(info: AbsInfo | None, value: int) -> float:
    """A position in mm from the axis minimum (units/mm resolution; NaN when the resolution is unknown)."""
    return (value - info.min) / info.resolution if info is not None and info.resolution > 0 else math.nan


def _tilt(info: AbsInfo | None, value: int) -> float:
    """A tilt in degrees: by the resolution (units/radian), else the range mapped to libinput's -64..64."""
    if info is None:
        return 0.0
    if info.resolution > 0:
        return math.degrees(value / info.resolution)
    return _normalised(info, value, one_sided=False) * DEFAULT_TILT_DEGREES


@dataclass
class _Slot:
    """One multi-touch slot: the contact in it (-1: none) and its position."""

    tracking_id: int = -1
    x: int = 0
    y: int = 0


class EvdevSemantics:
    """An evdev device's events, frame by frame: Motion, Wheel, Axis, Hat, Pen, TouchFrame, Button, Key."""

    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("dpi", positive, None, "counts per inch of relative motion (gives Motion in mm)"),
        OptionSpec("layout", text, "us", "keyboard layout for the characters keys type (us, uk, de, fr)"),
    )

    def __init__(self, device: DeviceId, absinfo: Mapping[int, AbsInfo], *, keys: Iterable[int] = (),
                 **options: object) -> None:
        self.device = device
        self.absinfo = {code: AbsInfo(*info) for code, info in absinfo.items()}
        """ABS code -> its AbsInfo (python-evdev's AbsInfo is accepted too)."""
        opts = read_semantics_options(self.OPTIONS, options, f"evdev semantics for {device}")
        self.layout: Layout = layout(opts["layout"])
        self.resolution = opts["dpi"] / MM_PER_INCH if opts["dpi"] is not None else None
        keys = frozenset(keys)
        self.touch = ABS_MT_POSITION_X in self.absinfo or ABS_MT_SLOT in self.absinfo
        """Whether this is a multi-touch device (TouchFrame events)."""
        self.pen = not self.touch and (ABS_PRESSURE in self.absinfo or bool(keys & PEN_TOOLS))
        """Whether this is a pen (Pen events); a tool key seen later makes it one too."""
        self._barrels = tuple(b for b in (BTN_STYLUS, BTN_STYLUS2, BTN_STYLUS3) if b in keys) or (
            BTN_STYLUS, BTN_STYLUS2)
        self._has_tools = bool(keys & PEN_TOOLS)
        self._values = {code: info.value for code, info in self.absinfo.items()}
        self._keys: set[int] = set()
        self._locks: set[int] = set()
        """Caps Lock and Num Lock usages that are on (each press toggles)."""
        self._slot = self._values.get(ABS_MT_SLOT, 0)
        self._slots: dict[int, _Slot] = {}
        self._active: dict[int, Contact] = {}
        self._serial: int | None = None
        self._last_pen: Pen | None = None
        self._dropped = False
        self._clear_frame()

    def _clear_frame(self) -> None:
        self._rel: dict[int, int] = {}
        self._abs_changed: dict[int, int] = {}
        self._key_edges: list[tuple[int, bool]] = []
        self._mt_changed = False
        self._pen_changed = False

    def describe(self) -> str:
        """What the device was taken for: a pen, a touch device or other axes, and their ranges."""
        kind = "multi-touch" if self.touch else "pen" if self.pen else "evdev device"
        axes = ", ".join(f"{ABS_NAMES.get(c, f'abs_0x{c:02x}')} {a.min}..{a.max}"
                         + (f" ({a.resolution}/mm)" if a.resolution and c in (ABS_X, ABS_Y, ABS_MT_POSITION_X,
                                                                               ABS_MT_POSITION_Y) else "")
                         for c, a in self.absinfo.items())
        return f"{self.device}: {kind}" + (f", axes {axes}" if axes else "")

    # -- events --------------------------------------------------------------------------------------

    def feed_event(self, time: float, type: int, code: int, value: int) -> list[InputEvent]:
        """Take one evdev event; at SYN_REPORT, the frame's events (else none)."""
        if type == EV_SYN:
            if code == SYN_DROPPED:
                self._dropped = True
                self._clear_frame()
                return []
            if code != SYN_REPORT:
                return []
            if self._dropped:
                self._dropped = False
                self._clear_frame()
                return []
            events = self._frame(time)
            self._clear_frame()
            return events
        if self._dropped:
            return []
        if type == EV_REL:
            self._rel[code] = self._rel.get(code, 0) + value
        elif type == EV_ABS:
            self._abs(code, value)
        elif type == EV_KEY:
            self._key(code, value)
        elif type == EV_MSC and code == MSC_SERIAL:
            self._serial = value & 0xFFFFFFFF
            self._pen_changed = True
        return []

    def feed_events(self, events: Iterable[tuple[float, int, int, int]]) -> list[InputEvent]:
        """All the events of a batch of (time, type, code, value) evdev events."""
        out: list[InputEvent] = []
        for time, ev_type, code, value in events:
            out.extend(self.feed_event(time, ev_type, code, value))
        return out

    def _abs(self, code: int, value: int) -> None:
        if self.touch and code >= ABS_MT_SLOT:
            self._mt(code, value)
            return
        if self.touch and code in PEN_AXES:
            return
        self._values[code] = value
        if self.pen and code in PEN_AXES:
            self._pen_changed = True
        else:
            self._abs_changed[code] = value

    def _mt(self, code: int, value: int) -> None:
        if code == ABS_MT_SLOT:
            self._slot = value
            return
        slot = self._slots.setdefault(self._slot, _Slot())
        if code == ABS_MT_TRACKING_ID:
            slot.tracking_id = value
        elif code == ABS_MT_POSITION_X:
            slot.x = value
        elif code == ABS_MT_POSITION_Y:
            slot.y = value
        else:
            return
        self._mt_changed = True

    def _key(self, code: int, value: int) -> None:
        if value == 2:
            return
        pressed = bool(value)
        if pressed == (code in self._keys):
            return
        (self._keys.add if pressed else self._keys.discard)(code)
        if code in DIGITIZER_KEYS:
            if self.touch:
                return
            if code in PEN_TOOLS:
                self._has_tools = True
                self.pen = True
            self._pen_changed = True
            return
        usage = KEY_USAGES.get(code)
        if pressed and usage in (_CAPS_LOCK, _NUM_LOCK):
            self._locks ^= {usage}
        self._key_edges.append((code, pressed))

    # -- frames --------------------------------------------------------------------------------------

    def _frame(self, time: float) -> list[InputEvent]:
        events: list[InputEvent] = []
        dx, dy = self._rel.get(REL_X, 0), self._rel.get(REL_Y, 0)
        if dx or dy:
            res = self.resolution
            events.append(Motion(time, self.device, dx=dx, dy=dy, dx_mm=dx / res if res else None,
                                 dy_mm=dy / res if res else None))
        vertical = self._detents(REL_WHEEL, REL_WHEEL_HI_RES)
        horizontal = self._detents(REL_HWHEEL, REL_HWHEEL_HI_RES)
        if vertical or horizontal:
            events.append(Wheel(time, self.device, vertical=vertical, horizontal=horizontal))
        hats = sorted({(code - ABS_HAT0X) // 2 for code in self._abs_changed if ABS_HAT0X <= code <= ABS_HAT3Y})
        for code, value in self._abs_changed.items():
            if not ABS_HAT0X <= code <= ABS_HAT3Y:
                one_sided = code in ONE_SIDED
                events.append(Axis(time, self.device, axis=ABS_NAMES.get(code, f"abs_0x{code:02x}"),
                                   value=_normalised(self.absinfo.get(code), value, one_sided=one_sided), raw=value))
        for hat in hats:
            x = self._values.get(ABS_HAT0X + 2 * hat, 0)
            y = -self._values.get(ABS_HAT0X + 2 * hat + 1, 0)  # evdev: -1 is up; the Hat event has y up
            sx, sy = (x > 0) - (x < 0), (y > 0) - (y < 0)
            name = next(d[0] for d in HAT_DIRECTIONS if d[1] == sx and d[2] == sy)
            events.append(Hat(time, self.device, hat=hat, direction=name, dx=sx, dy=sy))
        if self._pen_changed and self.pen:
            pen = self._pen(time)
            if pen is not None:
                events.append(pen)
        if self._mt_changed:
            frame = self._touch_frame(time)
            if frame is not None:
                events.append(frame)
        events.extend(self._key_events(time))
        return events

    def _detents(self, low: int, high: int) -> float:
        if high in self._rel:
            return self._rel[high] / HI_RES_PER_DETENT
        return float(self._rel.get(low, 0))

    def _pen(self, time: float) -> Pen | None:
        in_range = not self._has_tools or bool(self._keys & PEN_TOOLS)
        last = self._last_pen
        if not in_range:
            if last is None or not last.in_range:
                return None
            self._last_pen = replace(last, time=time, in_range=False, touching=False, pressure=0.0,
                                     barrel=(False,) * len(last.barrel))
            return self._last_pen
        x, y = self._values.get(ABS_X, 0), self._values.get(ABS_Y, 0)
        ix, iy = self.absinfo.get(ABS_X), self.absinfo.get(ABS_Y)
        rubber = BTN_TOOL_RUBBER in self._keys
        pen = Pen(time, self.device, x_mm=_mm(ix, x), y_mm=_mm(iy, y),
                  x=_normalised(ix, x, one_sided=True), y=_normalised(iy, y, one_sided=True),
                  pressure=_normalised(self.absinfo.get(ABS_PRESSURE), self._values.get(ABS_PRESSURE, 0),
                                       one_sided=True),
                  tilt_x=_tilt(self.absinfo.get(ABS_TILT_X), self._values.get(ABS_TILT_X, 0)),
                  tilt_y=_tilt(self.absinfo.get(ABS_TILT_Y), self._values.get(ABS_TILT_Y, 0)),
                  in_range=True, touching=BTN_TOUCH in self._keys,
                  barrel=tuple(b in self._keys for b in self._barrels), eraser=rubber, inverted=rubber,
                  serial=self._serial)
        if last is not None and _state(last) == _state(pen):
            return None
        self._last_pen = pen
        return pen

    def _touch_frame(self, time: float) -> TouchFrame | None:
        ix, iy = self.absinfo.get(ABS_MT_POSITION_X), self.absinfo.get(ABS_MT_POSITION_Y)
        contacts = []
        current: dict[int, Contact] = {}
        for slot in self._slots.values():
            if slot.tracking_id < 0:
                continue
            contact = Contact(slot.tracking_id, _mm(ix, slot.x), _mm(iy, slot.y),
                              _normalised(ix, slot.x, one_sided=True), _normalised(iy, slot.y, one_sided=True))
            current[slot.tracking_id] = contact
            contacts.append(contact)
        contacts.extend(replace(c, touching=False) for cid, c in self._active.items() if cid not in current)
        self._active = current
        return TouchFrame(time, self.device, contacts=tuple(contacts)) if contacts else None

    def _key_events(self, time: float) -> list[InputEvent]:
        events: list[InputEvent] = []
        for code, pressed in self._key_edges:
            button = _button(code)
            if button is not None:
                events.append(Button(time, self.device, button=button[0], pressed=pressed, name=button[1]))
                continue
            usage = KEY_USAGES.get(code, 0)
            held = {KEY_USAGES[c] for c in self._keys if c in KEY_USAGES}
            modifiers = frozenset(MODIFIER_NAMES[u] for u in held if u in MODIFIER_NAMES)
            char = ""
            if pressed and usage:
                altgr = self.layout.altgr and _RIGHT_ALT in held
                char = self.layout.char(usage, shift="shift" in modifiers, altgr=altgr,
                                        caps_lock=_CAPS_LOCK in self._locks, num_lock=_NUM_LOCK in self._locks)
                if modifiers & {"ctrl", "gui"} or ("alt" in modifiers and not altgr):
                    char = ""
            events.append(Key(time, self.device, usage=usage, key=key_name(usage) if usage else f"key_{code}",
                              pressed=pressed, char=char, modifiers=modifiers))
        return events



def _state(pen: Pen) -> str:
    """What a Pen event says, without its time (NaN positions compare equal)."""
    return repr(astuple(replace(pen, time=0.0)))

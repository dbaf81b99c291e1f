"""Touch screen and touch pad semantics: Microsoft's multi-touch digitizer protocol, frames of contacts.

:class:`TouchScreen` handles Digitizers-page Touch Screen (0x0D0004) and Touch Pad (0x0D0005)
applications as Microsoft's "Windows 8 touch" / "precision touchpad" protocol and the kernel's
``hid-multitouch`` read them:

* **Slots** — each Finger (0x0D0022) collection of an input report is one slot (a device without
  Finger collections has one slot, its application's first of each usage): Tip Switch (0x42;
  In Range 0x32 where a device has no tip switch; else always touching), Confidence (0x47, absent:
  confident), Contact Identifier (0x51), X/Y (in mm and 0..1, as :class:`~pixelpen.devices.hid.tablet.PositionAxis`:
  from the physical range and unit, or the ``size`` option).
* **Frames** — Contact Count (0x54) says how many contacts the frame holds.  *Parallel mode*: one
  report carries them all (slots past the count are unused).  *Hybrid mode*: the first report of a
  frame carries the count, later ones 0, each up to its number of slots, and the frame is complete
  when the count is reached (the kernel's ``num_expected``/``num_received``).  A report with a
  nonzero count while a frame is incomplete (a report was lost) first closes the incomplete frame.
  A device without Contact Count has every report as one frame of all its slots.  The count is capped
  at the Contact Count Maximum (the feature 0x55, given through :meth:`TouchScreen.feed_feature`, else
  its logical maximum) and at :data:`MAX_CONTACTS`.
* **Contacts** — a :class:`~pixelpen.devices.hid.events.TouchFrame` holds the contacts touching and,
  once, each contact lifted (``touching=False``): reported with Tip Switch 0, or missing from a frame
  while it was touching (the kernel's "not seen means up").  A second report of an ID in one frame is
  ignored, as is a lift of a contact not touching.  A frame that holds nothing gives no event.
* **Buttons** — Button page usages outside the fingers (a click pad's button) give Button edges.
* **Modes** — the feature reports the host sets after opening (the kernel's ``mt_set_modes``):
  Input Mode (0x52; the first one only, as the kernel) to 2 "multi-input" for a touch screen or 3
  for a touch pad (option ``input_mode``), Surface Switch (0x57) and Button Switch (0x58) to 1,
  Latency Mode (0x60) to 0 (normal); :meth:`TouchScreen.output_reports` gives them, the reports'
  other fields 0.  Windows descriptors often put Input Mode in a separate Device Configuration
  (0x0D000E) application; :class:`DeviceConfiguration` gives its reports there.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, ClassVar

from pixelpen.devices.hid.codec import ReportDecoder
from pixelpen.devices.hid.events import Button, Contact, DeviceId, InputEvent, TouchFrame
from pixelpen.devices.hid.fields import Collection, Field, ReportDescriptor, ReportKind
from pixelpen.devices.hid.semantics import OutputReport, read_semantics_options
from pixelpen.devices.hid.tablet import PositionAxis, first_value, position_axes, size_option
from pixelpen.errors import ConfigError, InvalidArgument
from pixelpen.options import OptionSpec, choice

__all__ = ["INPUT_MODES", "MAX_CONTACTS", "DeviceConfiguration", "TouchScreen", "mode_reports"]

DG_TOUCH_PAD, DG_FINGER = 0x000D0005, 0x000D0022
DG_IN_RANGE, DG_TIP_SWITCH, DG_CONFIDENCE = 0x000D0032, 0x000D0042, 0x000D0047
DG_CONTACT_ID, DG_INPUT_MODE, DG_CONTACT_COUNT, DG_CONTACT_COUNT_MAX = 0x000D0051, 0x000D0052, 0x000D0054, 0x000D0055
DG_SURFACE_SWITCH, DG_BUTTON_SWITCH, DG_LATENCY_MODE = 0x000D0057, 0x000D0058, 0x000D0060
BUTTON_PAGE = 0x09
SLOT_USAGES = frozenset({0x00010030, 0x00010031, DG_IN_RANGE, DG_TIP_SWITCH, DG_CONFIDENCE, DG_CONTACT_ID})
"""The usages one finger's slot carries."""
MAX_CONTACTS = 256
"""Contacts one frame may hold at most, whatever the device claims (bounds the memory of an incomplete frame)."""
INPUT_MODES = {"mouse": 0, "single": 1, "multi": 2, "touchpad": 3}
"""Input Mode values (Microsoft: 0 mouse, 1 single-input, 2 multi-input; precision touchpads: 3)."""


def mode_reports(descriptor: ReportDescriptor, input_mode: int) -> list[OutputReport]:
    """The feature reports that set Input Mode, Surface/Button Switch and Latency Mode (the kernel's mt_set_modes)."""
    settings = {DG_SURFACE_SWITCH: 1, DG_BUTTON_SWITCH: 1, DG_LATENCY_MODE: 0}
    reports = []
    mode_found = False
    for report_id, fields in descriptor.feature_reports.items():
        payload: dict[tuple[int, int], int] = {}
        for f in fields:
            if f.is_constant or f.is_array:
                continue
            for usage in f.usages[:f.count]:
                if usage == DG_INPUT_MODE and not mode_found:
                    payload[usage >> 16, usage & 0xFFFF] = input_mode
                    mode_found = True
                elif usage in settings:
                    payload[usage >> 16, usage & 0xFFFF] = settings[usage]
        if payload:
            try:
                data = descriptor.encode(payload, report_id=report_id, kind=ReportKind.FEATURE)
            except InvalidArgument as exc:
                raise ConfigError(f"feature report {report_id} cannot hold the mode settings: {exc}") from None
            reports.append(OutputReport(ReportKind.FEATURE, report_id, data))
    return reports


def _input_mode(text: str) -> str:
    return choice("auto", *INPUT_MODES)(text)


@dataclass(frozen=True)
class _Slot:
    """Where one finger's values are among a report's elements (None: the slot lacks the usage)."""

    x: PositionAxis
    y: PositionAxis
    x_index: int
    y_index: int
    tip: int | None
    confidence: int | None
    contact_id: int | None


@dataclass(frozen=True)
class _TouchPlan:
    """One input report: its decoder, slots, the Contact Count's element and the buttons' elements."""

    decoder: ReportDecoder
    slots: tuple[_Slot, ...]
    count: int | None
    buttons: tuple[tuple[int, int], ...]
    """(button number, element index) of the Button page usages outside the fingers."""


def _finger_of(field: Field) -> Collection | None:
    """The Finger collection a field is in (else its application: a single-touch device without fingers)."""
    node = field.collection
    while node is not None:
        if node.usage == DG_FINGER:
            return node
        node = node.parent
    return field.collection.application if field.collection is not None else None


class TouchScreen:
    """A multi-touch screen or touch pad: TouchFrame events of contacts, Button events of a click pad."""

    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("size", size_option, None,
                   "the touch area WxH in mm (or with a unit: 8x5in), overriding the descriptor's"),
        OptionSpec("input_mode", _input_mode, "auto",
                   "the Input Mode feature value set after opening: auto (multi, touchpad for a touch pad), "
                   "mouse, single, multi or touchpad"),
    )

    def __init__(self, descriptor: ReportDescriptor, device: DeviceId, **options: object) -> None:
        self.descriptor = descriptor
        self.device = device
        where = f"touch semantics for {device}"
        opts = read_semantics_options(self.OPTIONS, options, where)
        self.touchpad = DG_TOUCH_PAD in descriptor.applications
        mode = opts["input_mode"]
        self.input_mode = INPUT_MODES["touchpad" if self.touchpad else "multi"] if mode == "auto" else INPUT_MODES[mode]
        self._plans: dict[int | None, _TouchPlan] = {}
        for report_id in descriptor.input_reports:
            plan = self._plan(descriptor.decoder(ReportKind.INPUT, report_id), opts["size"])
            if plan is not None:
                self._plans[report_id] = plan
        if not self._plans:
            raise ConfigError(f"{where}: no input report has a finger with X and Y")
        self.feature_report_ids: tuple[int | None, ...] = tuple(
            rid for rid, fields in descriptor.feature_reports.items()
            if any(DG_CONTACT_COUNT_MAX in f.usages for f in fields))
        """The feature reports holding Contact Count Maximum (read them and give them to :meth:`feed_feature`)."""
        limits = [f.logical_max for f in descriptor.fields_with(DG_CONTACT_COUNT_MAX, ReportKind.FEATURE)]
        self.max_contacts = max(1, min(MAX_CONTACTS, limits[0] if limits else MAX_CONTACTS))
        """The most contacts a frame holds: Contact Count Maximum (its logical maximum until the feature is read)."""
        try:
            self._mode_reports = mode_reports(descriptor, self.input_mode)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None
        self._active: dict[int, Contact] = {}
        self._pending: list[Contact] = []
        self._expected = 0
        self._buttons: set[int] = set()

    @staticmethod
    def _plan(decoder: ReportDecoder, size: tuple[float, float] | None) -> _TouchPlan | None:
        groups: dict[Collection | None, dict[int, int]] = {}
        fields: dict[Collection | None, list[Field]] = {}
        count = None
        buttons = []
        for index, e in enumerate(decoder.elements):
            if e.key is None:
                continue
            usage = e.key[0] << 16 | e.key[1]
            if usage in SLOT_USAGES:
                finger = _finger_of(e.field)
                groups.setdefault(finger, {}).setdefault(usage, index)
                fields.setdefault(finger, []).append(e.field)
            elif usage == DG_CONTACT_COUNT and count is None:
                count = index
            elif e.key[0] == BUTTON_PAGE and e.key[1]:
                buttons.append((e.key[1], index))
        slots = []
        for finger, at in groups.items():
            x, y = position_axes(fields[finger], size)
            if x is None or y is None:
                continue
            slots.append(_Slot(x, y, at[0x00010030], at[0x00010031], at.get(DG_TIP_SWITCH, at.get(DG_IN_RANGE)),
                               at.get(DG_CONFIDENCE), at.get(DG_CONTACT_ID)))
        if not slots:
            return None
        return _TouchPlan(decoder, tuple(slots), count, tuple(buttons))

    def output_reports(self) -> list[OutputReport]:
        """The feature reports to send after opening: Input Mode, Surface/Button Switch, Latency Mode."""
        return list(self._mode_reports)

    def feed_feature(self, report: bytes) -> None:
        """Take a feature report read from the device: its Contact Count Maximum caps the frames from now on."""
        value = first_value(self.descriptor.decode(report, ReportKind.FEATURE), DG_CONTACT_COUNT_MAX)
        if value is not None and value > 0:
            self.max_contacts = min(MAX_CONTACTS, value)

    def describe(self) -> str:
        """What was found: the kind, slots per report, contact count, area, buttons and modes."""
        plan = next(iter(self._plans.values()))
        slot = plan.slots[0]
        if slot.x.known and slot.y.known:
            lx, ly = slot.x.field, slot.y.field
            area = (f"{abs(slot.x.mm(lx.logical_max) - slot.x.mm(lx.logical_min)):.1f} x "
                    f"{abs(slot.y.mm(ly.logical_max) - slot.y.mm(ly.logical_min)):.1f} mm")
        else:
            area = "size unknown (give size=WxH)"
        frames = "contact count (hybrid/parallel)" if plan.count is not None else "no contact count"
        parts = [f"{self.device}: {'touch pad' if self.touchpad else 'touch screen'}, {area}",
                 f"{len(plan.slots)} slots per report", frames, f"up to {self.max_contacts} contacts"]
        buttons = {b for p in self._plans.values() for b, _ in p.buttons}
        if buttons:
            parts.append(f"{len(buttons)} buttons")
        if self._mode_reports:
            parts.append(f"input mode {self.input_mode}")
        return ", ".join(parts)

    # -- reports -------------------------------------------------------------------------------------

    def feed(self, report: bytes, time: float) -> list[InputEvent]:
        """The events of one input report: a TouchFrame when it completes a frame, then Button edges."""
        report_id = self.descriptor.report_id_of(report)
        plan = self._plans.get(report_id)
        if plan is None:
            self.descriptor.layout(ReportKind.INPUT, report_id)  # a ParseError for an ID the device lacks
            return []
        values = plan.decoder.values(report)
        contacts = [self._contact(i, slot, values) for i, slot in enumerate(plan.slots)]
        events: list[InputEvent] = []
        if plan.count is None:
            frame = self._frame(contacts, time)
            if frame is not None:
                events.append(frame)
        else:
            count = min(max(0, values[plan.count]), self.max_contacts)
            if count:
                if self._pending:
                    frame = self._frame(self._pending, time)
                    if frame is not None:
                        events.append(frame)
                self._pending, self._expected = [], count
            # count 0 outside a frame: a frame of nothing, which lifts every contact
            self._pending.extend(contacts[:max(0, self._expected - len(self._pending))])
            if len(self._pending) >= self._expected:
                frame = self._frame(self._pending, time)
                self._pending, self._expected = [], 0
                if frame is not None:
                    events.append(frame)
        for button, index in plan.buttons:
            pressed = bool(values[index])
            if pressed != (button in self._buttons):
                (self._buttons.add if pressed else self._buttons.discard)(button)
                events.append(Button(time, self.device, button=button, pressed=pressed,
                                     name="left" if button == 1 else f"button{button}"))
        return events

    @staticmethod
    def _contact(number: int, slot: _Slot, values: Sequence[int]) -> Contact:
        """Slot ``number``'s contact (its Contact Identifier, else the slot number)."""
        raw_x, raw_y = values[slot.x_index], values[slot.y_index]
        return Contact(values[slot.contact_id] if slot.contact_id is not None else number,
                       slot.x.mm(raw_x), slot.y.mm(raw_y), slot.x.normalised(raw_x), slot.y.normalised(raw_y),
                       touching=bool(values[slot.tip]) if slot.tip is not None else True,
                       confidence=bool(values[slot.confidence]) if slot.confidence is not None else True)

    def _frame(self, contacts: Sequence[Contact], time: float) -> TouchFrame | None:
        """Close a frame: touching contacts, each lift once (reported or not seen); the active set updated."""
        out: list[Contact] = []
        seen: set[int] = set()
        active: dict[int, Contact] = {}
        for c in contacts:
            if c.contact_id in seen:
                continue
            seen.add(c.contact_id)
            if c.touching:
                active[c.contact_id] = c
                out.append(c)
            elif c.contact_id in self._active:
                out.append(c)
        out.extend(replace(c, touching=False) for cid, c in self._active.items() if cid not in seen)
        self._active = active
        return TouchFrame(time, self.device, contacts=tuple(out)) if out else None

    @property
    def active(self) -> tuple[Contact, ...]:
        """The contacts touching after the last complete frame."""
        return tuple(self._active.values())


class DeviceConfiguration:
    """A Device Configuration (0x0D000E) application: no input, the mode feature reports to send after opening.

    It cannot see the touch application beside it, so ``input_mode=auto`` goes by its own features:
    touchpad (3) when it has the Surface Switch or Button Switch (the selective reporting only
    precision touch pads define), else multi-input (2).
    """

    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("input_mode", _input_mode, "auto",
                   "the Input Mode feature value set after opening: auto (touchpad with surface/button switches, "
                   "else multi), mouse, single, multi or touchpad"),
    )

    def __init__(self, descriptor: ReportDescriptor, device: DeviceId, **options: object) -> None:
        self.descriptor = descriptor
        self.device = device
        where = f"device configuration semantics for {device}"
        opts = read_semantics_options(self.OPTIONS, options, where)
        mode = opts["input_mode"]
        if mode == "auto":
            switches = any(descriptor.fields_with(u, ReportKind.FEATURE) for u in (DG_SURFACE_SWITCH, DG_BUTTON_SWITCH))
            mode = "touchpad" if switches else "multi"
        self.input_mode = INPUT_MODES[mode]
        try:
            self._reports = mode_reports(descriptor, self.input_mode)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None

    def feed(self, report: bytes, time: float) -> list[InputEvent]:
        """No events: the application has no input reports of its own."""
        return []

    def output_reports(self) -> list[OutputReport]:
        """The mode feature reports."""
        return list(self._reports)

    def describe(self) -> str:
        """The modes it sets."""
        return f"{self.device}: device configuration, input mode {self.input_mode}"

"""Device semantics: which class turns a device's decoded reports into events, chosen by its applications.

A :class:`Semantics` object is fed the input reports a device sends (``feed(report, time)``) and
returns :mod:`~pixelpen.devices.hid.events`.  :func:`semantics_for` picks the class from the usages
of the descriptor's top-level (application) collections through :data:`SEMANTICS`, a table of
``"module:Class"`` names imported on use (a keyboard never imports the joystick module).  A device
with several top-level applications (a keyboard with a Consumer Control collection, a mouse with a
keyboard for its extra keys) gets a :class:`CompositeSemantics` that routes each report by its
report ID to the application that declares it; reports of applications no class handles give no
events.

Options are keyword arguments, read against each class's ``OPTIONS`` specs
(:class:`pixelpen.options.OptionSpec`) by :func:`read_semantics_options`: values may be given as
text (as in a URL) or as Python values; unknown names and bad values raise ConfigError naming the
option.  A class may say which output or feature reports must be sent to the device after opening
(the mouse's Resolution Multiplier for a hi-res wheel); :func:`output_reports_of` asks for them.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, NamedTuple, Protocol, runtime_checkable

from pixelpen.devices.hid.events import DeviceId, InputEvent
from pixelpen.devices.hid.fields import Collection, ReportDescriptor, ReportKind, ReportLayout
from pixelpen.errors import ConfigError
from pixelpen.options import OptionSpec, OptionValues, check_known, read_options

__all__ = ["SEMANTICS", "CompositeSemantics", "OutputReport", "Semantics", "output_reports_of",
           "read_semantics_options", "semantics_class", "semantics_for"]

SEMANTICS: dict[int, str] = {
    0x00010001: "pixelpen.devices.hid.mouse:Mouse",  # Generic Desktop Pointer
    0x00010002: "pixelpen.devices.hid.mouse:Mouse",  # Generic Desktop Mouse
    0x00010004: "pixelpen.devices.hid.joystick:Joystick",  # Generic Desktop Joystick
    0x00010005: "pixelpen.devices.hid.joystick:Joystick",  # Generic Desktop Game Pad
    0x00010008: "pixelpen.devices.hid.joystick:Joystick",  # Generic Desktop Multi-axis Controller (3D mice)
    0x00010006: "pixelpen.devices.hid.keyboard:Keyboard",  # Generic Desktop Keyboard
    0x00010007: "pixelpen.devices.hid.keyboard:Keyboard",  # Generic Desktop Keypad
    0x000D0001: "pixelpen.devices.hid.tablet:Tablet",  # Digitizers Digitizer
    0x000D0002: "pixelpen.devices.hid.tablet:Tablet",  # Digitizers Pen
    0x000D0004: "pixelpen.devices.hid.touch:TouchScreen",  # Digitizers Touch Screen
    0x000D0005: "pixelpen.devices.hid.touch:TouchScreen",  # Digitizers Touch Pad
    0x000D000E: "pixelpen.devices.hid.touch:DeviceConfiguration",  # Digitizers Device Configuration (Input Mode)
}
"""Top-level application usage (``page << 16 | id``) -> the semantics class, as ``"module:Class"``."""


class OutputReport(NamedTuple):
    """A report the host should send the device: its kind, report ID (None: unnumbered) and bytes.

    ``data`` is the report as the encoder produces it (the report-ID byte first when numbered);
    the transport applies its own report-ID rules when it writes it.
    """

    kind: ReportKind
    report_id: int | None
    data: bytes


@runtime_checkable
class Semantics(Protocol):
    """Turns one device's input reports into events (one object per opened device; it keeps state).

    A class may also define ``output_reports() -> list[OutputReport]``: the reports to send after
    opening (see :func:`output_reports_of`).
    """

    def feed(self, report: bytes, time: float) -> list[InputEvent]:
        """The events one input report (as read, report-ID byte included when numbered) gives."""
        ...

    def describe(self) -> str:
        """A one-line human description of what this semantics understood of the device."""
        ...


def output_reports_of(semantics: Semantics) -> list[OutputReport]:
    """The reports ``semantics`` wants sent to the device after opening (none when it defines none)."""
    method = getattr(semantics, "output_reports", None)
    return list(method()) if callable(method) else []


def semantics_class(application: int) -> type[Any]:
    """The class :data:`SEMANTICS` names for a top-level application usage (its module imported now)."""
    try:
        target = SEMANTICS[application]
    except KeyError:
        raise ConfigError(f"no device semantics for the application usage {application:#010x} (known: "
                          f"{', '.join(f'{u:#010x}' for u in sorted(SEMANTICS))})") from None
    module, _, name = target.partition(":")
    cls: type[Any] = getattr(importlib.import_module(module), name)
    return cls


def semantics_for(descriptor: ReportDescriptor, device: DeviceId, **options: object) -> Semantics:
    """The semantics for a device: by its one top-level application, or a composite for several."""
    apps = [c for c in descriptor.collections if c.parent is None]
    if not apps:
        raise ConfigError(f"{device}: the report descriptor has no top-level collection, so its kind is unknown")
    if len(apps) == 1:
        semantics: Semantics = semantics_class(apps[0].usage)(descriptor, device, **options)
        return semantics
    return CompositeSemantics(descriptor, device, **options)


class CompositeSemantics:
    """Several top-level applications in one descriptor: each report goes to the application that declares it.

    Each supported application gets its own semantics, built on a descriptor holding only that
    application's fields; options go to the classes that declare them (an option no part declares is
    refused).  Reports of unsupported applications give no events.
    """

    def __init__(self, descriptor: ReportDescriptor, device: DeviceId, **options: object) -> None:
        self.descriptor = descriptor
        self.device = device
        self._routes: dict[int | None, list[Semantics]] = {}
        self._parts: list[tuple[Collection, Semantics]] = []
        self.unsupported: tuple[int, ...] = ()
        """Usages of the applications no semantics class handles (their reports give no events)."""
        unsupported = []
        classes = []
        for app in (c for c in descriptor.collections if c.parent is None):
            if app.usage in SEMANTICS:
                classes.append((app, semantics_class(app.usage)))
            else:
                unsupported.append(app.usage)
        self.unsupported = tuple(unsupported)
        if not classes:
            raise ConfigError(f"{device}: no device semantics for any of its applications "
                              f"({', '.join(f'{u:#010x}' for u in unsupported)})")
        declared = [getattr(cls, "OPTIONS", None) for _, cls in classes]
        if all(specs is not None for specs in declared):
            check_known({spec.name for specs in declared for spec in specs or ()}, options, str(device))
        for (app, cls), specs in zip(classes, declared, strict=True):
            names = None if specs is None else {spec.name for spec in specs}
            part: Semantics = cls(application_descriptor(descriptor, app), device,
                                  **{k: v for k, v in options.items() if names is None or k in names})
            self._parts.append((app, part))
            for report_id in _input_report_ids(descriptor, app):
                self._routes.setdefault(report_id, []).append(part)

    def feed(self, report: bytes, time: float) -> list[InputEvent]:
        """The events of the application that declares this report's ID (none for unsupported ones)."""
        report_id = self.descriptor.report_id_of(report)
        events: list[InputEvent] = []
        for part in self._routes.get(report_id, ()):
            events.extend(part.feed(report, time))
        return events

    def output_reports(self) -> list[OutputReport]:
        """Every part's reports to send after opening."""
        return [r for _, part in self._parts for r in output_reports_of(part)]

    def describe(self) -> str:
        """The parts, one after the other."""
        text = "; ".join(part.describe() for _, part in self._parts)
        if self.unsupported:
            text += f"; ignored applications {', '.join(f'{u:#010x}' for u in self.unsupported)}"
        return text

    @property
    def parts(self) -> tuple[Semantics, ...]:
        """The semantics of each supported application, in descriptor order."""
        return tuple(part for _, part in self._parts)


def application_descriptor(descriptor: ReportDescriptor, application: Collection) -> ReportDescriptor:
    """A descriptor holding only the fields inside one top-level collection (bit offsets unchanged)."""
    layouts = []
    for layout in descriptor.layouts.values():
        fields = tuple(f for f in layout.fields if f.collection is not None and f.collection.application == application)
        if fields:
            layouts.append(ReportLayout(layout.kind, layout.report_id, fields, layout.length))
    collections = tuple(c for c in descriptor.collections if c.application == application)
    return ReportDescriptor(descriptor.data, layouts, collections, descriptor.warnings)


def _input_report_ids(descriptor: ReportDescriptor, application: Collection) -> list[int | None]:
    """The input report IDs with a field inside ``application``."""
    return [rid for rid, fields in descriptor.input_reports.items()
            if any(f.collection is not None and f.collection.application == application for f in fields)]


def read_semantics_options(specs: Iterable[OptionSpec[Any]], options: Mapping[str, object], where: str) -> OptionValues:
    """Read keyword options against ``specs``; Python values are written as their URL text first.

    Numbers and booleans become their text; a mapping ``{"x": (0, 512, 1023)}`` becomes
    ``x=0:512:1023`` (entries joined by commas); a sequence becomes its items joined by ``:``.
    Unknown names and bad values raise ConfigError (URLError) naming ``where`` and the option.
    """
    return read_options(specs, {name: _as_text(value) for name, value in options.items()}, where)


def _as_text(value: object) -> str:
    """An option value's URL text (see :func:`read_semantics_options`)."""
    if isinstance(value, str):
        return value
    if isinstance(value, Mapping):
        return ",".join(f"{key}={_as_text(item)}" for key, item in value.items())
    if isinstance(value, Sequence):
        return ":".join(_as_text(item) for item in value)
    return str(value)

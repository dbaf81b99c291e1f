"""HID input devices: the report-descriptor parser, the compiled report codec, device semantics, events.

``parse_descriptor(data)`` returns a :class:`ReportDescriptor`; its ``decode(report)`` gives the
values of an input report keyed by ``(usage_page, usage_id)``.  Names are imported on first use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from pixelpen.devices.hid.descriptor import parse_descriptor
    from pixelpen.devices.hid.fields import Collection, Field, ReportDescriptor, ReportKind, ReportLayout

_LAZY = {"parse_descriptor": "pixelpen.devices.hid.descriptor"} | dict.fromkeys(
    ("Collection", "Field", "ReportDescriptor", "ReportKind", "ReportLayout"), "pixelpen.devices.hid.fields")


def __getattr__(name: str) -> object:
    """Import a lazily exported name's module on first access, then keep the name here."""
    if name not in _LAZY:
        raise AttributeError(f"module 'pixelpen.devices.hid' has no attribute {name!r}")
    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value
    return value


__all__ = ["Collection", "Field", "ReportDescriptor", "ReportKind", "ReportLayout", "parse_descriptor"]

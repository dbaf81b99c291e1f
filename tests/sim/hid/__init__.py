"""Tests of the simulated HID devices; ``hidtools_report`` decodes a report with hid-tools, the independent oracle."""

from __future__ import annotations

from typing import Any

import pytest


def hidtools_report(descriptor: bytes, report: bytes, kind: str = "input") -> dict[str | int, list[Any]]:
    """hid-tools' reading of ``report``: usage name, and 32-bit usage, -> the values of its fields in report order.

    Skips the test when hid-tools (GPL, a test-only oracle) is not installed.
    """
    hid = pytest.importorskip("hidtools.hid")
    parsed = hid.ReportDescriptor.from_bytes(list(descriptor))
    reports = getattr(parsed, f"{kind}_reports")
    rid = report[0] if -1 not in reports else -1
    values: dict[str | int, list[Any]] = {}
    for field in reports[rid].fields:
        if field.is_const:
            continue
        for key in (field.usage_name, field.usage):
            values.setdefault(key, []).extend(field.get_values(list(report)))
    return values

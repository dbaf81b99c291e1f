"""ReportDescriptor's report spaces: each numbered on its own, as the kernel's report_enum[type].numbered."""

from __future__ import annotations

from pixelpen.devices.hid import parse_descriptor
from pixelpen.devices.hid.fields import ReportKind

# A vendor device: an unnumbered 1-byte input report, then a Report ID item for feature report 1 only.
MIXED = bytes([
    0x06, 0x00, 0xFF,  # Usage Page (Vendor 0xFF00)
    0x09, 0x01,        # Usage (1)
    0xA1, 0x01,        # Collection (Application)
    0x09, 0x02,        #   Usage (2)
    0x15, 0x00,        #   Logical Minimum (0)
    0x26, 0xFF, 0x00,  #   Logical Maximum (255)
    0x75, 0x08,        #   Report Size (8)
    0x95, 0x01,        #   Report Count (1)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): the input space has no IDs
    0x85, 0x01,        #   Report ID (1)
    0x09, 0x03,        #   Usage (3)
    0xB1, 0x02,        #   Feature (Data, Variable, Absolute): feature report 1
    0xC0,              # End Collection
])


def test_an_unnumbered_input_space_beside_a_numbered_feature_space():
    d = parse_descriptor(MIXED)
    assert d.numbered and d.numbered_kinds == {ReportKind.FEATURE}
    assert list(d.input_reports) == [None] and list(d.feature_reports) == [1]
    assert d.report_id_of(b"\x07") is None
    assert d.decode(b"\x07") == {(0xFF00, 2): 7}  # the first byte is data, not an ID
    assert d.decode(b"\x01\x2a", ReportKind.FEATURE) == {(0xFF00, 3): 0x2A}


def test_a_report_that_is_not_bytes_is_refused_by_type():
    import numpy as np
    import pytest

    from pixelpen.errors import InvalidArgumentType

    d = parse_descriptor(MIXED)
    for bad in (None, 5, "abc", [7], np.zeros(1, np.uint8)):
        with pytest.raises(InvalidArgumentType, match="a report is bytes"):
            d.decode(bad)  # type: ignore[arg-type]

"""Smoke test of benchmarks/hid.py: a tiny run prints every table; its composite descriptor is what hid-tools reads."""

import pytest

from benchmarks.hid import END, LMAX, LMIN, PAGE, USAGE, composite_descriptor, item, main, signed
from pixelpen.devices.hid import parse_descriptor
from pixelpen.devices.hid.fields import ReportKind

pytest.importorskip("hidtools")


def test_items_are_encoded_as_hid_1_11_shows_them():
    # HID 1.11 Appendix B.2 (boot mouse): 05 01 Usage Page (Generic Desktop), 15 81 Logical Minimum (-127),
    # 25 7F Logical Maximum (127); a 2-byte Usage is 0A (AC Pan 0x0238: 0A 38 02); End Collection is C0
    assert item(PAGE, 0x01) == b"\x05\x01" and signed(LMIN, -127) == b"\x15\x81" and signed(LMAX, 127) == b"\x25\x7f"
    assert item(USAGE, 0x238, 2) == b"\x0a\x38\x02" and signed(LMAX, 255) == b"\x26\xff\x00" and item(END) == b"\xc0"


def test_the_composite_descriptor_has_the_same_reports_for_hid_tools_and_pixelpen():
    from hidtools.hid import ReportDescriptor

    data = composite_descriptor()
    assert 2200 <= len(data) <= 2400  # the size class of the 2.3 KB descriptor
    theirs = ReportDescriptor.from_bytes(list(data))
    ours = parse_descriptor(data)
    assert sorted(theirs.input_reports) == sorted(ours.input_reports) == [1, 4, 5, 6, 7, *range(64, 80)]
    assert sorted(theirs.feature_reports) == sorted(ours.feature_reports) == [2, 3, *range(16, 45)]
    for rid, report in theirs.input_reports.items():
        assert report.size == ours.layout(ReportKind.INPUT, rid).length


def test_a_tiny_run_prints_every_measurement(capsys):
    assert main(["--tiny"]) == 0
    out = capsys.readouterr().out
    assert "composite 2325 B" in out and "BOOT_MOUSE" in out and "NKRO_KEYBOARD" in out
    for goal in ("parse speedup, worst:", "reports/s per report, worst:", "batch reports/s, worst:",
                 "latency p99, worst:"):
        assert goal in out
    assert out.count("latency at 1000 Hz replay") == 7

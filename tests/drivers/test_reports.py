"""ReportLink: the shape the HID transports implement (hidapi-like: input, output, feature reports, descriptor)."""

from __future__ import annotations

import inspect

from pixelpen.drivers.reports import ReportLink

DESCRIPTOR = bytes.fromhex("05010902a101")  # Usage Page (Generic Desktop), Usage (Mouse), Collection (Application)


class FakeMouse:
    """The smallest ReportLink: queued input reports, one feature report, and what the host sent."""

    def __init__(self) -> None:
        self.inputs = [b"\x01\x00\x05\xfb"]
        self.sent: list[bytes] = []
        self.features = {2: b"\x02\x64"}

    @property
    def report_descriptor(self) -> bytes:
        return DESCRIPTOR

    def read_report(self, timeout: float | None = None) -> bytes | None:
        return self.inputs.pop(0) if self.inputs else None

    def write_report(self, report: bytes) -> None:
        self.sent.append(report)

    def get_feature(self, report_id: int) -> bytes:
        return self.features[report_id]

    def send_feature(self, report: bytes) -> None:
        self.features[report[0]] = report

    def close(self) -> None:
        pass


def test_a_minimal_device_satisfies_the_protocol_and_one_without_features_does_not():
    assert isinstance(FakeMouse(), ReportLink)

    class InputOnly:
        report_descriptor = DESCRIPTOR

        def read_report(self, timeout=None): ...

        def close(self): ...

    assert not isinstance(InputOnly(), ReportLink)


def test_the_methods_and_signatures_are_the_documented_ones():
    sig = {name: str(inspect.signature(getattr(ReportLink, name)))
           for name in ("read_report", "write_report", "get_feature", "send_feature", "close")}
    assert sig == {
        "read_report": "(self, timeout: 'float | None' = None) -> 'bytes | None'",
        "write_report": "(self, report: 'bytes') -> 'None'",
        "get_feature": "(self, report_id: 'int') -> 'bytes'",
        "send_feature": "(self, report: 'bytes') -> 'None'",
        "close": "(self) -> 'None'",
    }
    assert isinstance(ReportLink.report_descriptor, property)
    for name in sig:
        assert getattr(ReportLink, name).__doc__


def test_reports_carry_their_id_first():
    mouse = FakeMouse()
    mouse.send_feature(b"\x02\xc8")
    assert mouse.get_feature(2) == b"\x02\xc8"
    assert mouse.read_report(0) == b"\x01\x00\x05\xfb" and mouse.read_report(0) is None
    assert mouse.report_descriptor.startswith(b"\x05\x01")

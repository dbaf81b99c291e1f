"""The report link: what a HID input device's driver talks through (input, output and feature reports, descriptor).

Declared now, implemented by the HID transports of the issue after next (hidapi, hidraw, a
simulator), after cython-hidapi's ``read``/``write``/``send_feature_report``/``get_report_descriptor``.
A report is a whole byte string: when the descriptor numbers its reports (a Report ID item) the
first byte is the report ID; otherwise there is no ID byte at all.

* ``read_report(timeout)``: the next input report the device sent (its interrupt IN endpoint at its
  polling interval), oldest first, or None when ``timeout`` clock seconds passed with none (None
  waits without limit, 0 polls);
* ``write_report(report)``: an output report (keyboard LEDs, rumble) on the interrupt OUT endpoint
  or as SET_REPORT(Output);
* ``get_feature(report_id)`` / ``send_feature(report)``: GET_REPORT / SET_REPORT(Feature) on the
  control endpoint (settings such as resolution or the polling rate); ``get_feature`` returns the
  report as the descriptor lays it out: its ID byte first when numbered; an unnumbered device's only
  feature report (ID 0) without one;
* ``report_descriptor``: the HID report descriptor bytes, from which a driver learns the fields;
* ``close()``.

A device that went away raises :class:`~pixelpen.errors.Disconnected`; a timeout of a write raises
:class:`~pixelpen.errors.LinkTimeout`.  The simulator side is :class:`pixelpen.sim.base.ReportDevice`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable


@runtime_checkable
class ReportLink(Protocol):
    """A HID device as its driver sees it: input reports in, output and feature reports out, the descriptor."""

    @property
    def report_descriptor(self) -> bytes:
        """The device's HID report descriptor."""

    def read_report(self, timeout: float | None = None) -> bytes | None:
        """The next input report, or None when ``timeout`` clock seconds pass first (None: wait, 0: poll)."""

    def write_report(self, report: bytes) -> None:
        """Send an output report (report ID first when the device numbers its reports)."""

    def get_feature(self, report_id: int) -> bytes:
        """The feature report ``report_id`` as the device answers GET_REPORT (ID byte first when numbered)."""

    def send_feature(self, report: bytes) -> None:
        """Send a feature report (SET_REPORT; its ID byte first)."""

    def close(self) -> None:
        """Release the device; calling it again does nothing."""

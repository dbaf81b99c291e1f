"""InputDevice: one opened input device — its source (a report link and its semantics, or evdev) and its events.

An :class:`EventSource` answers ``read(timeout)`` with the events of the next report (``[]`` for a report that
gave none) or None when ``timeout`` clock seconds passed first; :class:`ReportSource` is the HID one (a
:class:`~pixelpen.drivers.reports.ReportLink` fed through :class:`~pixelpen.devices.hid.semantics.Semantics`,
the semantics' output and feature reports sent at open).  :class:`InputDevice` reads a source until events
come or the timeout passes; a device that went away (``Disconnected``) gives one
:class:`~pixelpen.devices.hid.events.DeviceRemoved` event, and reading after it raises ``Disconnected``.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from types import TracebackType
from typing import TYPE_CHECKING, Protocol, runtime_checkable

from pixelpen.clock import Clock
from pixelpen.devices.hid.events import DeviceId, DeviceRemoved, InputEvent
from pixelpen.devices.hid.fields import ReportKind
from pixelpen.devices.hid.semantics import Semantics, output_reports_of
from pixelpen.drivers.reports import ReportLink
from pixelpen.errors import Disconnected, InvalidArgument, PixelpenError

if TYPE_CHECKING:
    from pixelpen.display.base import Display

log = logging.getLogger(__name__)


@runtime_checkable
class EventSource(Protocol):
    """Where an InputDevice's events come from: one report (or evdev frame) at a time."""

    device_id: DeviceId
    clock: Clock

    def read(self, timeout: float | None) -> list[InputEvent] | None:
        """The events of the next report ([] when it gave none), or None when ``timeout`` seconds passed first.

        Raises ``Disconnected`` when the device went away.
        """
        ...

    def describe(self) -> str:
        """One line saying what the device is and how its reports are understood."""
        ...

    def close(self) -> None:
        """Release the device (idempotent)."""
        ...


class ReportSource:
    """A HID device: a report link read through its semantics; the semantics' output reports are sent at once."""

    def __init__(self, link: ReportLink, semantics: Semantics, device_id: DeviceId, *, clock: Clock) -> None:
        self.link = link
        self.semantics = semantics
        self.device_id = device_id
        self.clock = clock
        self.bus: object | None = None
        """The fake hidapi module a simulated or replayed device is plugged into (None for hardware)."""
        for report in output_reports_of(semantics):
            if report.kind is ReportKind.FEATURE:
                link.send_feature(report.data)
            else:
                link.write_report(report.data)

    def read(self, timeout: float | None) -> list[InputEvent] | None:
        """The events of the next input report, timed on the clock when it was read."""
        report = self.link.read_report(timeout)
        if report is None:
            return None
        return self.semantics.feed(report, self.clock.now())

    def describe(self) -> str:
        """The device and what its semantics understood."""
        return self.semantics.describe()

    def close(self) -> None:
        """Close the link."""
        self.link.close()


class InputDevice:
    """An opened input device: ``read(timeout)`` its events, ``events()`` as an iterator; a context manager."""

    def __init__(self, source: EventSource, *, url: str = "", display: Display | None = None) -> None:
        self.source = source
        self.url = url or str(source.device_id)
        self.clock = source.clock
        """The clock the source reads on (timeouts and event times)."""
        self.display = display
        """The display the logical devices over this device answer for unless they are given another."""
        self.closed = False
        self.removed = False
        """True once the device went away (its DeviceRemoved event was given)."""

    @property
    def device_id(self) -> DeviceId:
        """Who the device is."""
        return self.source.device_id

    def describe(self) -> str:
        """One line about the device."""
        return self.source.describe()

    def read(self, timeout: float | None = None) -> list[InputEvent]:
        """The events of the next report that gives any, waiting at most ``timeout`` clock seconds (None: no limit).

        Returns [] when the timeout passed; ``[DeviceRemoved]`` once when the device went away; after that,
        and after ``close()``, raises ``Disconnected``.
        """
        if timeout is not None and not timeout >= 0:
            raise InvalidArgument(f"{self.url}: read timeout must be >= 0 seconds or None, got {timeout!r}")
        self._check_usable()
        deadline = None if timeout is None else self.clock.now() + timeout
        while True:
            remaining = None if deadline is None else max(0.0, deadline - self.clock.now())
            try:
                events = self.source.read(remaining)
            except Disconnected as exc:
                log.info("%s: device removed: %s", self.url, exc)
                self.removed = True
                self._close_source()
                return [DeviceRemoved(self.clock.now(), self.device_id)]
            if events:
                return events
            if events is None:  # the timeout passed (a report that gave no events reads on)
                return []

    def events(self, timeout: float | None = None) -> Iterator[InputEvent]:
        """Every event as it comes; stops after ``timeout`` seconds without one, after DeviceRemoved, or at close."""
        while not self.closed and not self.removed:
            batch = self.read(timeout)
            if not batch:
                return
            yield from batch

    def _check_usable(self) -> None:
        if self.removed:
            raise Disconnected(f"{self.url}: the device was removed")
        if self.closed:
            raise Disconnected(f"{self.url}: the input device is closed")

    def _close_source(self) -> None:
        try:
            self.source.close()
        except PixelpenError as exc:  # closing a device that went away may fail; it is gone either way
            log.debug("%s: close after removal: %s", self.url, exc)

    def close(self) -> None:
        """Release the device (idempotent)."""
        if self.closed:
            return
        self.closed = True
        if not self.removed:
            self.source.close()

    def __enter__(self) -> InputDevice:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "removed" if self.removed else "closed" if self.closed else "open"
        return f"<InputDevice {self.url} {state}>"

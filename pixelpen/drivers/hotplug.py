"""HotplugMonitor: devices arriving and leaving, found by polling an enumeration, with identity stable across replug.

hidapi has no hotplug API (libusb/hidapi#299), so the monitor calls an enumeration function — ``lambda:
enumerate_hid(module=...)`` or anything returning items with a ``device_id`` (HidInfo, UsbHidInterface) or
DeviceIds — every ``interval`` seconds on its clock and reports the difference as :class:`Arrived` and
:class:`Left` records.

Identity: a device is known by ``DeviceId.key`` (bus, VID:PID, serial, interface), which survives unplugging
and plugging in again, while its ``path`` (``/dev/hidraw3`` -> ``/dev/hidraw5``) does not.  A replug shows as
``Left`` for the old path and ``Arrived`` for the new one with the same ``key`` — also when both happen
between two polls (the old handle is dead either way and must be reopened).  Two identical devices without a
serial number share a key; they are told apart by path, but which one came back after a replug cannot be known.
A replug between two polls that gets the same node back (the kernel reuses hidraw numbers) is invisible to
polling; a link open on the old node raises Disconnected on its next read all the same, so reopen then.

These are the drivers' own records: drivers must not import devices/, so the input layer (``pixelpen.input``)
turns them into ``pixelpen.devices.hid.events.DeviceAdded``/``DeviceRemoved`` events.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.identity import DeviceId
from pixelpen.errors import InvalidArgument

log = logging.getLogger(__name__)

MIN_INTERVAL = 0.01
"""Shortest polling interval accepted (an enumeration reads sysfs; faster polling only burns CPU)."""


@dataclass(frozen=True)
class Arrived:
    """A device appeared (or was present at the first poll): who it is, what the enumeration said, when."""

    device: DeviceId
    info: Any
    time: float


@dataclass(frozen=True)
class Left:
    """A device went away: who it was (its last path), when it was noticed."""

    device: DeviceId
    info: Any
    time: float


Change = Arrived | Left


def _device_id(item: Any) -> DeviceId:
    if isinstance(item, DeviceId):
        return item
    device = getattr(item, "device_id", None)
    if not isinstance(device, DeviceId):
        raise InvalidArgument(f"hotplug: the enumeration returned {type(item).__name__}, which has no device_id")
    return device


class HotplugMonitor:
    """Polls ``enumerate_fn`` and reports what arrived and left since the last poll (see the module docstring)."""

    def __init__(self, enumerate_fn: Callable[[], Iterable[Any]], *, clock: Clock | None = None,
                 interval: float = 0.5, match: Callable[[DeviceId], bool] | None = None,
                 report_present: bool = True) -> None:
        if not isinstance(interval, (int, float)) or not interval >= MIN_INTERVAL:
            raise InvalidArgument(f"hotplug: interval must be >= {MIN_INTERVAL} s, got {interval!r}")
        self._enumerate = enumerate_fn
        self.clock = clock if clock is not None else REAL_CLOCK
        self.interval = float(interval)
        self._match = match
        self._present: dict[tuple[str, str], tuple[DeviceId, Any]] | None = None if report_present else {}
        self._baseline = not report_present
        self._last_poll: float | None = None

    def devices(self) -> list[DeviceId]:
        """The devices present at the last poll, in enumeration order."""
        return [device for device, _ in (self._present or {}).values()]

    def find(self, key: str) -> DeviceId | None:
        """The present device with identity ``key`` (its current path), or None while it is away."""
        return next((d for d in self.devices() if d.key == key), None)

    def poll(self) -> list[Change]:
        """Enumerate now: Left records first (in the order they were known), then Arrived (in enumeration order).

        An enumeration that fails (OSError: a node vanished mid-scan) changes nothing and is retried next poll.
        """
        now = self.clock.now()
        self._last_poll = now
        try:
            items = list(self._enumerate())
        except OSError as exc:
            log.debug("hotplug: enumeration failed, trying again next poll: %s", exc)
            return []
        seen: dict[tuple[str, str], tuple[DeviceId, Any]] = {}
        for item in items:
            device = _device_id(item)
            if self._match is None or self._match(device):
                seen.setdefault((device.key, device.path), (device, item))
        if self._baseline:  # report_present=False: the first poll only learns what is there
            self._baseline = False
            self._present = seen
            return []
        before = self._present or {}
        self._present = seen
        left: list[Change] = [Left(d, info, now) for k, (d, info) in before.items() if k not in seen]
        arrived: list[Change] = [Arrived(d, info, now) for k, (d, info) in seen.items() if k not in before]
        return left + arrived

    def wait(self, timeout: float | None = None) -> list[Change]:
        """Poll every ``interval`` until something changes or ``timeout`` clock seconds pass (None: until a change).

        Sleeps on the clock between polls, so Ctrl-C interrupts it at once.
        """
        deadline = None if timeout is None else self.clock.now() + max(0.0, timeout)
        while True:
            if self._last_poll is not None:
                due = self._last_poll + self.interval
                if deadline is not None:
                    due = min(due, deadline)
                self.clock.sleep(due - self.clock.now())
            changes = self.poll()
            if changes or (deadline is not None and self.clock.now() >= deadline):
                return changes

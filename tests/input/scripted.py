"""A scripted event source for the logical-device tests: events handed out when a simulated clock reaches them."""

from __future__ import annotations

from collections.abc import Iterable

from pixelpen.clock import SimulatedClock
from pixelpen.devices.hid.events import DeviceId, InputEvent
from pixelpen.errors import Disconnected
from pixelpen.input.device import InputDevice

DEVICE = DeviceId("virtual", 0x1209, 0x0001, name="scripted")


class ScriptedSource:
    """Gives each event (one per read) once the clock reaches its time; Disconnected after ``unplug_at``."""

    def __init__(self, events: Iterable[InputEvent], clock: SimulatedClock, unplug_at: float | None = None) -> None:
        self.events = sorted(events, key=lambda e: e.time)
        self.clock = clock
        self.device_id = DEVICE
        self.unplug_at = unplug_at
        self.closed = 0

    def read(self, timeout: float | None) -> list[InputEvent] | None:
        now = self.clock.now()
        due = [self.unplug_at] if self.unplug_at is not None else []
        if self.events:
            due.append(self.events[0].time)
        if not due:
            if timeout is not None:
                self.clock.advance(timeout)
            return None
        wait = min(due) - now
        if wait > 0:
            if timeout is not None and wait > timeout:
                self.clock.advance(timeout)
                return None
            self.clock.advance(wait)
        if self.unplug_at is not None and self.clock.now() >= self.unplug_at:
            raise Disconnected("scripted device unplugged")
        return [self.events.pop(0)]

    def describe(self) -> str:
        return "scripted events"

    def close(self) -> None:
        self.closed += 1


def scripted(events: Iterable[InputEvent], unplug_at: float | None = None) -> InputDevice:
    """An InputDevice over scripted events on a new simulated clock at 0."""
    return InputDevice(ScriptedSource(events, SimulatedClock(), unplug_at))

"""GKS input modes over one event queue: request (wait for the trigger), sample (the measure now), event (queued).

An :class:`InputQueue` reads the raw events of its input devices and gives each to every attached
:class:`LogicalDevice`, which updates its *measure* (a position, a stroke, a number ...) and says whether the
event was its *trigger* (a button press, the pen lifted, Enter).  What happens at a trigger depends on the
logical device's mode (GKS 7.2):

* ``request`` — :meth:`InputQueue.request` waits (on the clock, at most ``timeout``) for the trigger of that
  one device and returns its measure; triggers of other request-mode devices are ignored meanwhile;
* ``sample`` — :meth:`InputQueue.sample` takes in what has arrived (without waiting) and returns the measure;
  triggers are ignored;
* ``event`` — each trigger puts a :class:`LogicalEvent` (time, device, measure) on the one queue, taken in
  order by :meth:`InputQueue.await_event`.

The queue is bounded (``capacity``, default :data:`QUEUE_CAPACITY`): as in GKS, an event arriving when it is
full is lost; losses are counted (``overflows``), logged once until reported, and reported by
:meth:`InputQueue.take_overflows`.  A device that went away puts a LogicalEvent with ``device`` None and the
DeviceRemoved as its value on the queue (it is never dropped) and is read no more.
"""

from __future__ import annotations

import logging
from abc import ABC, abstractmethod
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, ClassVar, Literal, TypeVar

from pixelpen.clock import Clock
from pixelpen.devices.hid.events import DeviceRemoved, InputEvent
from pixelpen.errors import ConfigError, InvalidArgument
from pixelpen.input.device import InputDevice

log = logging.getLogger(__name__)

Mode = Literal["request", "sample", "event"]
MODES: tuple[Mode, ...] = ("request", "sample", "event")
QUEUE_CAPACITY = 256
"""Logical events the queue holds by default (GKS leaves the size to the implementation)."""
MAX_CAPACITY = 1_000_000
"""The largest queue allowed (a queue nobody reads must not take unbounded memory)."""
POLL_SLICE = 0.01
"""Seconds one device is waited on at a time when several are read together."""


class LogicalDevice(ABC):
    """A GKS logical input device: a measure updated from raw events, a trigger, a mode."""

    kind: ClassVar[str] = "logical"

    def __init__(self, *, mode: Mode = "request") -> None:
        self.mode: Mode = _check_mode(mode)
        self.queue: InputQueue | None = None
        """The queue this device is attached to (None before ``InputQueue.attach``)."""

    @abstractmethod
    def handle(self, event: InputEvent) -> bool:
        """Update the measure from a raw event; True when the event is this device's trigger."""

    @abstractmethod
    def value(self) -> Any:
        """The current measure (what a trigger reports)."""

    def triggered(self) -> None:
        """Called after a trigger's measure was taken (a stroke or string starts afresh)."""

    def set_mode(self, mode: Mode) -> None:
        """Switch to ``request``, ``sample`` or ``event`` mode."""
        self.mode = _check_mode(mode)

    def request(self, timeout: float | None = None) -> Any:
        """Wait for this device's trigger and return its measure (None when ``timeout`` passed or input ended)."""
        return self._attached().request(self, timeout)

    def sample(self) -> Any:
        """The measure now, after taking in the events that have arrived."""
        return self._attached().sample(self)

    def _attached(self) -> InputQueue:
        if self.queue is None:
            raise ConfigError(f"{type(self).__name__} is not attached to an InputQueue (use queue.attach(device))")
        return self.queue


L = TypeVar("L", bound=LogicalDevice)


@dataclass(frozen=True)
class LogicalEvent:
    """A trigger in event mode: when, which logical device (None for a removed input device), the measure."""

    time: float
    device: LogicalDevice | None
    value: Any

    @property
    def kind(self) -> str:
        """The logical device's class (``locator``, ``stroke`` ...), or ``removed``."""
        return "removed" if self.device is None else self.device.kind


class InputQueue:
    """Raw events of some input devices dispatched to logical devices; the event queue of event mode."""

    def __init__(self, devices: Iterable[InputDevice] = (), *, capacity: int = QUEUE_CAPACITY,
                 clock: Clock | None = None) -> None:
        if isinstance(capacity, bool) or not isinstance(capacity, int) or not 1 <= capacity <= MAX_CAPACITY:
            raise InvalidArgument(f"queue capacity must be an integer in 1..{MAX_CAPACITY}, got {capacity!r}")
        self.devices: list[InputDevice] = list(devices)
        self.capacity = capacity
        self.clock = clock or (self.devices[0].clock if self.devices else None)
        self.logical: list[LogicalDevice] = []
        self.overflows = 0
        """Events lost because the queue was full, since the start."""
        self._unreported = 0
        self._events: deque[LogicalEvent] = deque()
        self._requesting: LogicalDevice | None = None
        self._answer: list[Any] = []

    def add_device(self, device: InputDevice) -> None:
        """Read another input device too."""
        self.devices.append(device)
        if self.clock is None:
            self.clock = device.clock

    def attach(self, logical: L, mode: Mode | None = None) -> L:
        """Give ``logical`` the raw events from now on (in ``mode`` if given) and return it."""
        if logical.queue is not None and logical.queue is not self:
            raise ConfigError(f"{type(logical).__name__} is attached to another InputQueue")
        if mode is not None:
            logical.set_mode(mode)
        logical.queue = self
        if logical not in self.logical:
            self.logical.append(logical)
        return logical

    def detach(self, logical: LogicalDevice) -> None:
        """Stop giving ``logical`` events; its queued events are removed."""
        if logical in self.logical:
            self.logical.remove(logical)
        logical.queue = None
        self.flush_events(logical)

    # -- reading -------------------------------------------------------------------------------------
    def pump(self, timeout: float | None = 0.0) -> bool:
        """Read the events that come within ``timeout`` seconds (0: those waiting) and dispatch them.

        True when anything was read; False on timeout or when no device is left to read.
        """
        live = [d for d in self.devices if not d.closed and not d.removed]
        if not live:
            return False
        if len(live) == 1:
            return self._dispatch(live[0], live[0].read(timeout))
        clock = self.clock or live[0].clock
        deadline = None if timeout is None else clock.now() + timeout
        while True:
            got = False
            for device in live:
                got = self._dispatch(device, device.read(0.0)) or got
            if got:
                return True
            remaining = None if deadline is None else deadline - clock.now()
            if remaining is not None and remaining <= 0:
                return False
            wait = POLL_SLICE if remaining is None else min(POLL_SLICE, remaining)
            if self._dispatch(live[0], live[0].read(wait)):
                return True

    def _dispatch(self, device: InputDevice, events: list[InputEvent]) -> bool:
        """Give each raw event to every attached logical device; queue the triggers of event-mode ones."""
        for event in events:
            if isinstance(event, DeviceRemoved):
                self._events.append(LogicalEvent(event.time, None, event))
                continue
            for logical in list(self.logical):
                if not logical.handle(event):
                    continue
                if logical.mode == "event":
                    self._put(LogicalEvent(event.time, logical, logical.value()))
                    logical.triggered()
                elif logical is self._requesting and not self._answer:
                    self._answer.append(logical.value())
                    logical.triggered()
        return bool(events)

    def _put(self, event: LogicalEvent) -> None:
        """Queue an event, or count it lost when the queue is full."""
        if len(self._events) < self.capacity:
            self._events.append(event)
            return
        if not self._unreported:
            log.warning("input queue overflow: %d events held; further events are lost until it is read",
                        self.capacity)
        self.overflows += 1
        self._unreported += 1

    # -- the three modes ---------------------------------------------------------------------------------
    def request(self, logical: LogicalDevice, timeout: float | None = None) -> Any:
        """Wait for ``logical``'s trigger and return its measure; None when ``timeout`` passed or input ended."""
        if logical.queue is not self:
            self.attach(logical)
        if logical.mode != "request":
            raise ConfigError(f"{type(logical).__name__} is in {logical.mode} mode; request needs request mode")
        deadline = self._deadline(timeout)
        self._requesting, self._answer = logical, []
        try:
            while not self._answer:
                remaining = self._remaining(deadline)
                if not self.pump(remaining) or (remaining == 0.0 and not self._answer):
                    break
            return self._answer[0] if self._answer else None
        finally:
            self._requesting, self._answer = None, []

    def sample(self, logical: LogicalDevice) -> Any:
        """Take in every raw event waiting (no waiting) and return ``logical``'s measure."""
        if logical.queue is not self:
            self.attach(logical)
        while self.pump(0.0):
            pass
        return logical.value()

    def await_event(self, timeout: float | None = None) -> LogicalEvent | None:
        """The oldest queued event, reading input for at most ``timeout`` seconds when none is queued."""
        deadline = self._deadline(timeout)
        while not self._events:
            remaining = self._remaining(deadline)
            if not self.pump(remaining) or (remaining == 0.0 and not self._events):
                break
        return self._events.popleft() if self._events else None

    def flush_events(self, logical: LogicalDevice | None = None) -> int:
        """Drop the queued events (of ``logical`` only, if given); return how many were dropped."""
        before = len(self._events)
        self._events = deque(e for e in self._events if logical is not None and e.device is not logical)
        return before - len(self._events)

    def take_overflows(self) -> int:
        """Events lost to a full queue since the last call (GKS's 'input queue has overflowed')."""
        lost, self._unreported = self._unreported, 0
        return lost

    def __len__(self) -> int:
        """Events waiting in the queue."""
        return len(self._events)

    def _deadline(self, timeout: float | None) -> float | None:
        """The clock time ``timeout`` seconds from now (None: no limit)."""
        if timeout is not None and not timeout >= 0:
            raise InvalidArgument(f"timeout must be >= 0 seconds or None, got {timeout!r}")
        return None if timeout is None or self.clock is None else self.clock.now() + timeout

    def _remaining(self, deadline: float | None) -> float | None:
        """Seconds left until ``deadline`` (None: no limit)."""
        return None if deadline is None or self.clock is None else max(0.0, deadline - self.clock.now())


def _check_mode(mode: object) -> Mode:
    """A mode name, or ConfigError listing them."""
    for known in MODES:
        if mode == known:
            return known
    raise ConfigError(f"input mode must be one of {', '.join(MODES)}, got {mode!r}")

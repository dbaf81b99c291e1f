"""Request, sample and event modes over one queue; the bounded queue's overflow; removed devices."""

from __future__ import annotations

import logging

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen import geometry as geo
from pixelpen.devices.hid.events import Button, Key, Motion
from pixelpen.errors import ConfigError, InvalidArgument
from pixelpen.input.choice import Choice
from pixelpen.input.locator import Locator
from pixelpen.input.queue import InputQueue
from tests.input.scripted import DEVICE, scripted

PIPELINE = geo.ViewingPipeline((0, 0, 100, 100), device_size=(100, 100), y_down=True)


def press(t: float, button: int = 1, pressed: bool = True) -> Button:
    return Button(t, DEVICE, button=button, pressed=pressed)


def test_request_waits_for_the_trigger_and_returns_the_measure_then() -> None:
    dev = scripted([Motion(0.1, DEVICE, dx=5, dy=0), press(0.2), Motion(0.3, DEVICE, dx=7, dy=0)])
    queue = InputQueue([dev])
    loc = queue.attach(Locator(PIPELINE))
    value = loc.request(timeout=1.0)
    assert (value.x, value.y) == (55.0, 50.0)  # after the first motion only
    assert dev.clock.now() == pytest.approx(0.2)
    assert loc.request(timeout=1.0) is None  # no second trigger: the timeout passes
    assert dev.clock.now() == pytest.approx(1.2)


def test_sample_takes_what_arrived_without_waiting() -> None:
    dev = scripted([Motion(0.0, DEVICE, dx=3, dy=0), Motion(0.0, DEVICE, dx=4, dy=0), Motion(5.0, DEVICE, dx=9,
                                                                                             dy=0)])
    queue = InputQueue([dev])
    loc = queue.attach(Locator(PIPELINE), mode="sample")
    assert loc.sample().x == 57.0
    assert dev.clock.now() == 0.0
    dev.clock.advance(5.0)
    assert loc.sample().x == 66.0


def test_event_mode_queues_every_trigger_in_order_across_devices() -> None:
    events = [press(0.1), Key(0.2, DEVICE, usage=0x1F, key="2", pressed=True, char="2"), press(0.3, 3)]
    queue = InputQueue([scripted(events)])
    loc = queue.attach(Locator(PIPELINE), mode="event")
    choice = queue.attach(Choice(), mode="event")
    got = [queue.await_event(1.0) for _ in range(5)]
    assert got[4] is None
    # button 1 triggers the locator, then the choice (in the order they were attached); button 3 only the choice
    assert [(e.kind, e.device, e.time) for e in got if e] == [
        ("locator", loc, 0.1), ("choice", choice, 0.1), ("choice", choice, 0.2), ("choice", choice, 0.3)]
    assert [e.value for e in got[1:4] if e] == [1, 2, 3]


def test_the_queue_is_bounded_and_counts_what_it_lost(caplog: pytest.LogCaptureFixture) -> None:
    queue = InputQueue([scripted([press(0.1 * k) for k in range(1, 6)])], capacity=3)
    choice = queue.attach(Choice(), mode="event")
    with caplog.at_level(logging.WARNING, logger="pixelpen.input.queue"):
        while queue.pump(1.0):
            pass
    assert len(queue) == 3 and queue.overflows == 2
    assert sum("overflow" in r.message for r in caplog.records) == 1  # reported once, not per event
    assert queue.take_overflows() == 2 and queue.take_overflows() == 0
    assert [queue.await_event(0).time for _ in range(3)] == pytest.approx([0.1, 0.2, 0.3])  # the oldest kept
    assert queue.await_event(0) is None
    assert choice.value() == 1


def test_request_ignores_other_devices_triggers_and_modes_are_checked() -> None:
    queue = InputQueue([scripted([Key(0.1, DEVICE, usage=0x1E, key="1", pressed=True, char="1"), press(0.2)])])
    loc, choice = queue.attach(Locator(PIPELINE)), queue.attach(Choice(keys={"9": 9}))
    assert loc.request(1.0) is not None
    assert len(queue) == 0
    choice.set_mode("event")
    with pytest.raises(ConfigError, match="event mode"):
        queue.request(choice, 0)
    with pytest.raises(ConfigError, match="input mode"):
        choice.set_mode("polled")  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="capacity"):
        InputQueue(capacity=0)


def test_a_removed_device_is_queued_and_ends_requests() -> None:
    queue = InputQueue([scripted([Motion(0.1, DEVICE, dx=1, dy=0)], unplug_at=0.5)])
    loc = queue.attach(Locator(PIPELINE))
    assert loc.request(timeout=None) is None  # the device went away: no trigger will come
    removed = queue.await_event(0)
    assert removed is not None and removed.kind == "removed" and removed.device is None


def test_a_logical_device_needs_its_queue() -> None:
    with pytest.raises(ConfigError, match="not attached"):
        Locator(PIPELINE).request(0)


def test_several_devices_feed_one_queue() -> None:
    from pixelpen.clock import SimulatedClock
    from pixelpen.input.device import InputDevice
    from tests.input.scripted import ScriptedSource

    clock = SimulatedClock()
    mouse = InputDevice(ScriptedSource([press(0.10), press(0.30)], clock))
    keyboard = InputDevice(ScriptedSource([Key(0.20, DEVICE, usage=0x20, key="3", pressed=True, char="3")], clock))
    queue = InputQueue([mouse, keyboard])
    queue.attach(Choice(), mode="event")
    got = []
    while (event := queue.await_event(1.0)) is not None:
        got.append((round(event.time, 6), event.value))
    assert got == [(0.1, 1), (0.2, 3), (0.3, 1)]


@given(st.lists(st.tuples(st.integers(1, 5), st.booleans()), max_size=60), st.integers(1, 8))
def test_queue_invariants(presses: list[tuple[int, bool]], capacity: int) -> None:
    """Every trigger is queued or counted lost; the queue never holds more than its capacity; order is kept."""
    events = [Button(0.01 * (k + 1), DEVICE, button=b, pressed=p) for k, (b, p) in enumerate(presses)]
    queue = InputQueue([scripted(events)], capacity=capacity)
    queue.attach(Choice(), mode="event")
    while queue.pump(1.0):
        assert len(queue) <= capacity
    triggers = sum(p for _, p in presses)
    assert len(queue) + queue.overflows == triggers
    kept = [queue.await_event(0) for _ in range(len(queue))]
    assert [e.value for e in kept if e] == [b for b, p in presses if p][:capacity]

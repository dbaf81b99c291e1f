"""InputDevice over real descriptors and simulated HID devices: hand-decoded reports, removal, output reports."""

from __future__ import annotations

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.devices.hid.events import Button, DeviceRemoved, Motion
from pixelpen.errors import Disconnected, InvalidArgument
from pixelpen.input.registry import open_report_device
from pixelpen.sim.hid.descriptors import BOOT_MOUSE, TRACKBALL
from pixelpen.sim.hid.device import HidSim
from tests.input.scripted import scripted


def boot_mouse(reports: list[tuple[float, bytes]], clock: SimulatedClock) -> HidSim:
    return HidSim.from_descriptor(BOOT_MOUSE, reports, clock=clock, model="mouse",
                                  info={"vendor_id": 0x1209, "product_id": 0x0001, "product_string": "test mouse"})


def test_reports_become_events_by_hand_decoding() -> None:
    clock = SimulatedClock()
    # byte 0 bit 0 = button 1; byte 1 X int8 = +5; byte 2 Y int8 0xFB = -5 (HID 1.11 B.2 layout)
    sim = boot_mouse([(0.010, bytes([0x01, 0x05, 0xFB])), (0.020, bytes([0x00, 0x00, 0x00]))], clock)
    with open_report_device(sim, clock=clock) as dev:
        first = dev.read(1.0)
        assert [type(e) for e in first] == [Motion, Button] or [type(e) for e in first] == [Button, Motion]
        motion = next(e for e in first if isinstance(e, Motion))
        assert (motion.dx, motion.dy) == (5, -5)
        assert next(e for e in first if isinstance(e, Button)).pressed
        second = dev.read(1.0)
        assert [(type(e), getattr(e, "pressed", None)) for e in second] == [(Button, False)]
        assert dev.read(0.5) == []  # nothing more: the timeout passes on the clock
        assert clock.now() == pytest.approx(0.52, abs=0.11)


def test_power_loss_gives_device_removed_once_then_disconnected() -> None:
    clock = SimulatedClock()
    sim = boot_mouse([(0.010, bytes([0x00, 0x01, 0x00]))], clock)
    dev = open_report_device(sim, clock=clock)
    assert dev.read(1.0)
    sim.inject("power-loss")
    removed = dev.read(1.0)
    assert len(removed) == 1 and isinstance(removed[0], DeviceRemoved)
    assert removed[0].device == dev.device_id
    assert dev.removed
    with pytest.raises(Disconnected, match="removed"):
        dev.read(0.1)
    dev.close()
    dev.close()  # idempotent


def test_events_iterator_stops_after_removal_and_at_timeout() -> None:
    from tests.input.scripted import DEVICE

    events = [Motion(0.1 * k, DEVICE, dx=k, dy=0) for k in range(1, 4)]
    assert [e.dx for e in scripted(events).events(timeout=1.0)] == [1, 2, 3]  # type: ignore[attr-defined]
    got = list(scripted(events, unplug_at=0.25).events())
    assert [type(e) for e in got] == [Motion, Motion, DeviceRemoved]


def test_semantics_output_reports_are_sent_at_open() -> None:
    clock = SimulatedClock()
    sim = HidSim.from_descriptor(TRACKBALL, [], clock=clock, model="trackball")
    with open_report_device(sim, clock=clock):
        # feature report 2: bits 0-1 wheel multiplier, bits 2-3 pan multiplier, each set to its logical
        # maximum 1 (the kernel's hid_setup_resolution_multiplier) -> 0b0101
        assert sim.get_feature(2) == bytes([0x02, 0x05])


def test_close_is_idempotent_and_closes_the_source_once() -> None:
    dev = scripted([])
    with dev:
        pass
    dev.close()
    assert dev.source.closed == 1  # type: ignore[attr-defined]
    with pytest.raises(Disconnected, match="closed"):
        dev.read(0)


def test_bad_timeout_is_refused() -> None:
    with pytest.raises(InvalidArgument, match="timeout"):
        scripted([]).read(-1)


def test_a_poll_reads_past_reports_that_give_no_events() -> None:
    clock = SimulatedClock()
    # an unchanged report (no buttons, no motion) gives no event; the one after it does
    sim = boot_mouse([(0.010, bytes([0x00, 0x00, 0x00])), (0.010, bytes([0x00, 0x02, 0x00]))], clock)
    with open_report_device(sim, clock=clock) as dev:
        clock.advance(0.05)
        events = dev.read(0)
    assert [(e.dx, e.dy) for e in events if isinstance(e, Motion)] == [(2, 0)]

"""HotplugMonitor over SimHidapi's enumeration: arrivals, removals, replug with the same DeviceId.key, waiting."""

from __future__ import annotations

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.drivers.hidapi import enumerate_hid
from pixelpen.drivers.hotplug import Arrived, HotplugMonitor, Left
from pixelpen.drivers.identity import DeviceId
from pixelpen.errors import InvalidArgument
from pixelpen.sim.hid.descriptors import BOOT_MOUSE
from pixelpen.sim.hid.device import HidSim
from pixelpen.sim.transports.hidapi import SimHidapi
from tests.drivers.test_hidapi import COMPOSITE


def mouse(clock, serial="M1"):
    return HidSim.from_descriptor(BOOT_MOUSE, clock=clock, model="mouse",
                                  info={"vendor_id": 0x1234, "product_id": 0x0001, "serial_number": serial})


def setup(report_present=True):
    clock = SimulatedClock()
    bus = SimHidapi([mouse(clock)])
    monitor = HotplugMonitor(lambda: enumerate_hid(module=bus), clock=clock, interval=0.5,
                             report_present=report_present)
    return clock, bus, monitor


def test_present_devices_arrive_at_the_first_poll_then_nothing_changes():
    _, _, monitor = setup()
    (first,) = monitor.poll()
    assert isinstance(first, Arrived) and first.device.key == "virtual:1234:0001:M1:0"
    assert first.info.path == "sim:mouse:0"
    assert monitor.poll() == []
    assert monitor.find("virtual:1234:0001:M1:0").path == "sim:mouse:0"


def test_without_report_present_the_first_poll_is_a_baseline():
    _, _, monitor = setup(report_present=False)
    assert monitor.poll() == [] and [d.path for d in monitor.devices()] == ["sim:mouse:0"]


def test_replug_keeps_the_key_and_changes_the_path():
    clock, bus, monitor = setup()
    monitor.poll()
    bus.unplug("sim:mouse:0")
    (left,) = monitor.poll()
    assert isinstance(left, Left) and left.device.path == "sim:mouse:0"
    assert monitor.find(left.device.key) is None
    bus.plug(mouse(clock))
    (back,) = monitor.poll()
    assert isinstance(back, Arrived) and back.device.key == left.device.key and back.device.path == "sim:mouse:1"


def test_replug_between_two_polls_is_a_leave_and_an_arrival():
    clock, bus, monitor = setup()
    monitor.poll()
    bus.unplug("sim:mouse:0")
    bus.plug(mouse(clock))
    changes = monitor.poll()
    assert [type(c) for c in changes] == [Left, Arrived]
    assert changes[0].device.key == changes[1].device.key
    assert (changes[0].device.path, changes[1].device.path) == ("sim:mouse:0", "sim:mouse:1")


def test_two_identical_devices_without_serial_are_told_apart_by_path():
    clock = SimulatedClock()
    bus = SimHidapi([mouse(clock, serial=""), mouse(clock, serial="")])
    monitor = HotplugMonitor(lambda: enumerate_hid(module=bus), clock=clock)
    changes = monitor.poll()
    assert len(changes) == 2 and changes[0].device.key == changes[1].device.key
    bus.unplug("sim:mouse:1")
    (left,) = monitor.poll()
    assert left.device.path == "sim:mouse:1"


def test_one_device_with_several_collections_is_one_arrival():
    clock = SimulatedClock()
    bus = SimHidapi([HidSim.from_descriptor(COMPOSITE, clock=clock, model="combo")])
    assert len(HotplugMonitor(lambda: enumerate_hid(module=bus), clock=clock).poll()) == 1


def test_match_filters_and_device_ids_are_accepted_directly():
    clock = SimulatedClock()
    ids = [DeviceId("usb", 1, 2, "A", path="p1"), DeviceId("usb", 3, 4, "B", path="p2")]
    monitor = HotplugMonitor(lambda: ids, clock=clock, match=lambda d: d.vendor_id == 3)
    assert [c.device.path for c in monitor.poll()] == ["p2"]


def test_a_failing_enumeration_changes_nothing():
    clock = SimulatedClock()
    results = [[DeviceId("usb", 1, 2, path="p")], OSError("sysfs node vanished"), []]

    def enumerate_fn():
        item = results.pop(0)
        if isinstance(item, Exception):
            raise item
        return item

    monitor = HotplugMonitor(enumerate_fn, clock=clock)
    assert len(monitor.poll()) == 1
    assert monitor.poll() == [] and len(monitor.devices()) == 1
    assert [type(c) for c in monitor.poll()] == [Left]


def test_items_without_a_device_id_are_refused():
    monitor = HotplugMonitor(lambda: [object()], clock=SimulatedClock())
    with pytest.raises(InvalidArgument, match="device_id"):
        monitor.poll()


def test_wait_polls_every_interval_until_a_change_or_the_timeout():
    clock, bus, monitor = setup()
    assert len(monitor.wait(0)) == 1
    assert monitor.wait(2.0) == [] and clock.now() == pytest.approx(2.0)
    polls = []
    original = monitor.poll

    def counting():
        polls.append(clock.now())
        if clock.now() >= 3.0 and bus.paths():
            bus.unplug("sim:mouse:0")
        return original()

    monitor.poll = counting
    (left,) = monitor.wait(None)
    assert isinstance(left, Left) and polls == pytest.approx([2.5, 3.0])


@pytest.mark.parametrize("interval", [0, -1, 0.001, float("nan"), "1"])
def test_bad_interval(interval):
    with pytest.raises(InvalidArgument, match="interval"):
        HotplugMonitor(list, interval=interval)

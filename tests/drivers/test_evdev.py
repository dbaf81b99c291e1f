"""EvdevLink: python-evdev's InputDevice API behind a fake (a pipe as the node), timeouts, grab, unplug, errors.

The real python-evdev against an emulated node is tests/drivers/test_umockdev_real.py.
"""

from __future__ import annotations

import errno
import os
import sys
import time
from collections import namedtuple
from types import SimpleNamespace

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.drivers.evdev import READ_SLICE, EvdevLink
from pixelpen.drivers.recordings.evemu import AbsInfo
from pixelpen.errors import ConfigError, Disconnected, InvalidArgument, LinkError

DeviceInfo = namedtuple("DeviceInfo", "bustype vendor product version")  # python-evdev's DeviceInfo fields
Event = namedtuple("Event", "type code value")


class FakeInputDevice:
    """python-evdev's InputDevice as EvdevLink uses it; readable when its pipe has a byte, events queued."""

    def __init__(self, path: str) -> None:
        if path == "/dev/input/missing":
            raise FileNotFoundError(errno.ENOENT, "No such file or directory", path)
        if path == "/dev/input/denied":
            raise PermissionError(errno.EACCES, "Permission denied", path)
        self.fd, self._w = os.pipe()
        self.info = DeviceInfo(0x05, 0x054C, 0x09CC, 0x8111)
        self.name, self.phys, self.uniq = "Wireless Controller", "aa:bb/input0", "a4:53:85:00:00:01"
        self.queue: list[Event] = []
        self.error: OSError | None = None
        self.grab_error: OSError | None = None
        self.grabbed = self.closed = False

    def capabilities(self, absinfo: bool = True) -> dict:
        return {0: [0, 1, 3], 1: [0x130, 0x131], 3: [(0, (128, 0, 255, 0, 15, 0)), (0x10, (0, -1, 1, 0, 0, 0))]}

    def input_props(self) -> list[int]:
        return []

    def send(self, *events: Event) -> None:
        self.queue += events
        os.write(self._w, b"x")

    def read(self):
        if self.error is not None:
            raise self.error
        os.read(self.fd, 1)
        out, self.queue = self.queue, []
        return iter(out)

    def grab(self) -> None:
        if self.grab_error is not None:
            raise self.grab_error
        self.grabbed = True

    def ungrab(self) -> None:
        self.grabbed = False

    def close(self) -> None:
        self.closed = True
        os.close(self.fd)
        os.close(self._w)


@pytest.fixture
def fake():
    made: list[FakeInputDevice] = []

    def make(path: str) -> FakeInputDevice:
        made.append(FakeInputDevice(path))
        return made[-1]

    return SimpleNamespace(module=SimpleNamespace(InputDevice=make), made=made)


def test_identity_capabilities_and_absinfo(fake):
    link = EvdevLink("/dev/input/event3", module=fake.module)
    assert (link.device_id.bus, link.device_id.vendor_id, link.device_id.product_id) == ("bluetooth", 0x054C, 0x09CC)
    assert (link.device_id.name, link.device_id.serial, link.device_id.path) == (
        "Wireless Controller", "a4:53:85:00:00:01", "/dev/input/event3")
    assert link.absinfo == {0: AbsInfo(128, 0, 255, 0, 15, 0), 0x10: AbsInfo(0, -1, 1, 0, 0, 0)}
    assert link.codes[1] == {0x130, 0x131} and link.codes[3] == {0, 0x10}
    assert link.version == 0x8111 and link.phys == "aa:bb/input0"


def test_events_stamped_with_the_links_clock(fake):
    clock = SimulatedClock(100.0)
    link = EvdevLink("/dev/input/event3", module=fake.module, clock=clock)
    fake.made[0].send(Event(1, 0x130, 1), Event(0, 0, 0))
    assert link.read_events(1.0) == [(100.0, 1, 0x130, 1), (100.0, 0, 0, 0)]


def test_timeout_returns_empty_and_zero_polls(fake):
    link = EvdevLink("/dev/input/event3", module=fake.module, clock=SimulatedClock())
    t0 = time.monotonic()
    assert link.read_events(0) == []
    assert link.read_events(0.05) == []  # real seconds, even on a simulated clock
    assert time.monotonic() - t0 < 5 * READ_SLICE
    with pytest.raises(InvalidArgument):
        link.read_events(-1)


def test_unplug_during_a_read_is_disconnected(fake):
    link = EvdevLink("/dev/input/event3", module=fake.module)
    fake.made[0].error = OSError(errno.ENODEV, "No such device")
    fake.made[0].send()
    with pytest.raises(Disconnected, match="went away: No such device"):
        link.read_events(1.0)


def test_other_read_errors_are_link_errors(fake):
    link = EvdevLink("/dev/input/event3", module=fake.module)
    fake.made[0].error = OSError(errno.EINVAL, "Invalid argument")
    fake.made[0].send()
    with pytest.raises(LinkError, match="read failed") as caught:
        link.read_events(1.0)
    assert not isinstance(caught.value, Disconnected)


def test_grab_and_close(fake):
    link = EvdevLink("/dev/input/event3", module=fake.module, grab=True)
    device = fake.made[0]
    assert device.grabbed and link.grabbed
    with link:
        pass
    assert device.closed and not device.grabbed
    link.close()  # again: nothing
    with pytest.raises(LinkError, match="closed"):
        link.read_events(0)


def test_grab_held_elsewhere_is_a_clear_error(fake):
    link = EvdevLink("/dev/input/event3", module=fake.module)
    fake.made[0].grab_error = OSError(errno.EBUSY, "Device or resource busy")
    with pytest.raises(LinkError, match="cannot grab"):
        link.grab()


def test_open_errors_say_what_to_do(fake):
    with pytest.raises(LinkError, match="does not exist"):
        EvdevLink("/dev/input/missing", module=fake.module)
    with pytest.raises(LinkError, match=r"'input' group.*SUBSYSTEM==\"input\""):
        EvdevLink("/dev/input/denied", module=fake.module)


def test_missing_python_evdev_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "evdev", None)  # import evdev now raises ImportError
    with pytest.raises(ConfigError, match=r"python-evdev: pip install 'pixelpen\[input\]'"):
        EvdevLink("/dev/input/event0")

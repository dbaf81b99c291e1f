"""Linux input event devices (``/dev/input/eventN``) through python-evdev: EvdevLink.

An alternative to hidraw for the devices the kernel already drives (its HID drivers, quirks and
multi-touch handling applied).  :class:`EvdevLink` opens a node with python-evdev (the ``input`` extra),
says who the device is (:attr:`EvdevLink.device_id` from ``EVIOCGID``/``EVIOCGNAME``/``PHYS``/``UNIQ``),
what it sends (:attr:`~EvdevLink.codes`, :attr:`~EvdevLink.absinfo`, :attr:`~EvdevLink.properties`) and
reads its events with a timeout: ``select`` in slices of at most :data:`READ_SLICE` seconds, so Ctrl-C is
seen within that time and ``read_events(None)`` waits forever in slices.  Each event is
``(time, type, code, value)`` with the time of the link's clock when it was read (the kernel's own
timestamp is on another clock); timeouts are real seconds.  ``grab=True`` takes the device for this
reader only (EVIOCGRAB: the desktop stops seeing it).  A device unplugged during a read (ENODEV) raises
:class:`~pixelpen.errors.Disconnected`.
"""

from __future__ import annotations

import errno
import os
import select
import time
from typing import Any

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.devnode import node_open_error, require_module
from pixelpen.drivers.identity import DeviceId
from pixelpen.drivers.recordings.evemu import EV_ABS, AbsInfo
from pixelpen.drivers.recordings.hidrecorder import BUS_NAMES
from pixelpen.errors import Disconnected, InvalidArgument, LinkError

__all__ = ["READ_SLICE", "EvdevLink"]

READ_SLICE = 0.1
"""Longest single wait in ``select``: a Ctrl-C is seen at most this long after it is pressed."""
_GONE = (errno.ENODEV, errno.EIO, errno.EBADF)


def _module(module: Any) -> Any:
    return module if module is not None else require_module(
        "evdev", needed_by="evdev input devices", install="'pixelpen[input]'", package="python-evdev")


class EvdevLink:
    """One opened input event device: identity, capabilities, and events read with timeouts."""

    def __init__(self, path: str, *, grab: bool = False, clock: Clock | None = None, module: Any = None) -> None:
        evdev = _module(module)
        self.path = path
        self.clock = clock or REAL_CLOCK
        try:
            self._device = evdev.InputDevice(path)
        except OSError as exc:
            raise node_open_error(path, exc, missing="is the device plugged in? (ls /dev/input/by-id/)",
                                  group="input", udev='SUBSYSTEM=="input", KERNEL=="event*"',
                                  what="evdev device") from None
        info = self._device.info
        capabilities = self._device.capabilities(absinfo=True)
        self.absinfo: dict[int, AbsInfo] = {code: AbsInfo(*info_) for code, info_ in capabilities.get(EV_ABS, [])}
        """ABS code -> its range, fuzz, flat and resolution, as the kernel reports them at opening."""
        self.codes: dict[int, frozenset[int]] = {
            ev_type: frozenset(c[0] if isinstance(c, tuple) else c for c in codes)
            for ev_type, codes in capabilities.items()}
        """Event type -> the codes the device sends."""
        self.properties = frozenset(self._device.input_props())
        """INPUT_PROP_* bits (1: direct, a touch screen or pen display)."""
        self.device_id = DeviceId(bus=BUS_NAMES.get(info.bustype, "unknown"), vendor_id=info.vendor,
                                  product_id=info.product, serial=self._device.uniq or "", name=self._device.name,
                                  path=path)
        self.version = info.version
        self.phys: str = self._device.phys or ""
        self._closed = False
        self.grabbed = False
        if grab:
            self.grab()

    def grab(self) -> None:
        """Take the device for this reader only (EVIOCGRAB); LinkError when another reader holds it."""
        try:
            self._device.grab()
        except OSError as exc:
            raise LinkError(f"{self.path}: cannot grab the device (another program holds it?): {exc}") from None
        self.grabbed = True

    def read_events(self, timeout: float | None = None) -> list[tuple[float, int, int, int]]:
        """The events waiting (oldest first), waiting up to ``timeout`` s for the first (None: forever, 0: poll)."""
        if timeout is not None and not timeout >= 0:
            raise InvalidArgument(f"timeout {timeout!r}: a number of seconds >= 0, or None")
        if self._closed:
            raise LinkError(f"{self.path}: the link is closed")
        deadline = None if timeout is None else time.monotonic() + timeout  # select waits real time
        while True:
            wait = READ_SLICE if deadline is None else max(0.0, min(READ_SLICE, deadline - time.monotonic()))
            try:
                ready, _, _ = select.select([self._device.fd], [], [], wait)
                if ready:
                    now = self.clock.now()
                    return [(now, e.type, e.code, e.value) for e in self._device.read()]
            except BlockingIOError:
                pass
            except OSError as exc:
                if exc.errno in _GONE:
                    raise Disconnected(f"{self.device_id} at {self.path} went away: {os.strerror(exc.errno)}") \
                        from None
                raise LinkError(f"{self.path}: read failed: {exc}") from None
            if deadline is not None and time.monotonic() >= deadline:
                return []

    def close(self) -> None:
        """Release the device (and the grab); calling it again does nothing."""
        if self._closed:
            return
        self._closed = True
        try:
            if self.grabbed:
                self._device.ungrab()
        except OSError:
            pass
        finally:
            self._device.close()

    def __enter__(self) -> EvdevLink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

"""Replay of a hid-recorder recording: a simulated HID device that sends the recorded reports at their recorded times.

The device (a :class:`~pixelpen.sim.hid.device.HidSim` built by ``HidSim.from_descriptor``) has the recorded
descriptor and identity and sends each report when the clock reaches its time after the device was made.
By default it runs on a simulated clock of its own: a host reading with timeouts moves that clock (its waits
are clock sleeps), so a recording replays as fast as the host reads it, with the recorded times in its
events.  With ``realtime=True`` it runs on the real clock and the reports come at the pace they were recorded.
"""

from __future__ import annotations

import math
import os
from typing import Any

from pixelpen.clock import REAL_CLOCK, Clock, SimulatedClock
from pixelpen.drivers.hidapi import BUS_NAMES as HIDAPI_BUS_NAMES
from pixelpen.drivers.hidapi import top_level_usages
from pixelpen.drivers.recordings.hidrecorder import HidRecording, read_hid_recording
from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.sim.hid.device import HidSim

_HIDAPI_BUS = {name: number for number, name in HIDAPI_BUS_NAMES.items()}


def replay_device(recording: HidRecording | str | os.PathLike[str], *, clock: Clock | None = None,
                  realtime: bool = False, device: int = 0, delay: float = 0.0) -> HidSim:
    """A HidSim sending ``recording``'s reports (a HidRecording, or device ``device`` of a hid-recorder file).

    ``clock``: by default a new simulated clock (the replay runs as fast as the host reads), or with
    ``realtime`` the real clock (the reports are paced as recorded); a clock given is used as it is, except
    that a simulated one with ``realtime`` is an InvalidArgument.  ``delay`` seconds pass before the first
    report: a hidraw reader gets only the reports sent after it opened the device, so a real-time replay
    opened a few milliseconds after it was made needs one (hid-replay waits for Enter before it injects).
    """
    if not (isinstance(delay, (int, float)) and 0 <= delay < math.inf):
        raise InvalidArgument(f"replay delay {delay!r}: a finite number of seconds >= 0")
    if isinstance(recording, (str, os.PathLike)):
        recordings = read_hid_recording(recording)
        if not 0 <= device < len(recordings):
            raise InvalidArgument(f"{recording}: no device {device} (the file holds {len(recordings)})")
        recording = recordings[device]
    if not isinstance(recording, HidRecording):
        raise InvalidArgumentType(f"replay_device() takes a HidRecording or a file, not {type(recording).__name__}")
    if clock is None:
        clock = REAL_CLOCK if realtime else SimulatedClock()
    elif realtime and isinstance(clock, SimulatedClock):
        raise InvalidArgument("a real-time replay needs a real clock, not a SimulatedClock")
    reports = recording.reports if not delay else [(t + delay, r) for t, r in recording.reports]
    return HidSim.from_descriptor(recording.descriptor, reports, clock=clock, model="replay",
                                  info=hidapi_info(recording))


def hidapi_info(recording: HidRecording) -> dict[str, Any]:
    """What hidapi's ``enumerate()`` would list for the recorded device (its first top-level collection's usage)."""
    device_id = recording.device_id
    usages = top_level_usages(recording.descriptor)
    page, usage = usages[0] if usages else (0, 0)
    return {"vendor_id": recording.vendor_id, "product_id": recording.product_id, "serial_number": "",
            "release_number": 0, "manufacturer_string": "", "product_string": recording.name,
            "usage_page": page, "usage": usage, "interface_number": device_id.interface,
            "bus_type": _HIDAPI_BUS.get(device_id.bus, 0)}

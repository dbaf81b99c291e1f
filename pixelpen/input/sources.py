"""The openers of the built-in input schemes: ``sim:``, ``hid:``, ``replay:``, ``evdev:`` and ``evemu:``.

* ``sim:MODEL?script=..`` — the simulator of MODEL (``pixelpen.sim.base.create_simulator``, options it declares
  go to it) behind the fake hidapi module (``pixelpen.sim.transports.hidapi.SimHidapi``) and the real
  ``HidapiLink``: the hardware's code path.  ``pixelpen.sim`` is imported by module name only.
* ``hid:PATH|VID:PID[:SERIAL][@IFACE]?backend=hidraw|hid`` — a real device through ``drivers.hidapi.open_hid``.
* ``replay:FILE?device=N&realtime=BOOL`` — a hid-recorder file (``drivers.recordings.hidrecorder``) played by
  ``pixelpen.sim.hid.replay.replay_device`` behind the same fake hidapi module as ``sim:``.
* ``evdev:/dev/input/eventN?grab=BOOL`` — python-evdev (``drivers.evdev.EvdevLink``) through ``devices.hid.evdev``.
* ``evemu:FILE?realtime=BOOL`` — an evemu recording played on the clock through the same evdev semantics.

A replay without a clock runs on a new simulated clock, as fast as it is read (``realtime=true``: the real one).

Every other URL option, and the keyword options of ``open_input``, go to the device semantics.
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from typing import Any

from pixelpen.clock import REAL_CLOCK, Clock, SimulatedClock
from pixelpen.devices.hid.events import DeviceId, InputEvent
from pixelpen.errors import ConfigError, URLError
from pixelpen.input.device import EventSource, ReportSource
from pixelpen.options import OptionSpec, boolean, choice, integer, number, read_options
from pixelpen.urls import DeviceURL

HID_OPTIONS: tuple[OptionSpec[Any], ...] = (
    OptionSpec("backend", choice("hidraw", "libusb", "hid"), "hidraw",
               "cython-hidapi backend: hidraw (the kernel's nodes) or libusb (alias hid)"),
)
"""Options of ``hid:`` URLs read here (the rest go to the semantics)."""
REPLAY_OPTIONS: tuple[OptionSpec[Any], ...] = (
    OptionSpec("device", integer(0), 0, "which device of a multi-device recording (its D: index)"),
    OptionSpec("realtime", boolean, False, "play at the recorded pace on a real clock (else as fast as possible)"),
    OptionSpec("delay", number(0.0, 3600.0), 0.1, "with realtime: seconds from opening to the first report (a "
               "reader opened later than the first report's time would miss it)"),
)
"""Options of ``replay:`` URLs read here."""
EVDEV_OPTIONS: tuple[OptionSpec[Any], ...] = (
    OptionSpec("grab", boolean, False, "take the device for this reader only (EVIOCGRAB: the desktop stops seeing it)"),
)
"""Options of ``evdev:`` URLs read here."""
EVEMU_OPTIONS: tuple[OptionSpec[Any], ...] = REPLAY_OPTIONS[1:2]
"""Options of ``evemu:`` URLs read here."""


def _split(url: DeviceURL, specs: Sequence[OptionSpec[Any]]) -> tuple[dict[str, Any], dict[str, str]]:
    """The URL's options read against ``specs``, and the others (for the semantics)."""
    names = {spec.name for spec in specs}
    own = read_options(specs, {k: v for k, v in url.options.items() if k in names}, str(url))
    return dict(own), {k: v for k, v in url.options.items() if k not in names}


def report_source(link: Any, device_id: DeviceId, *, clock: Clock, options: dict[str, Any],
                  where: str) -> ReportSource:
    """A ReportSource over an opened link: its descriptor parsed (quirks by VID/PID), the semantics chosen by it."""
    from pixelpen.devices.hid.descriptor import parse_descriptor
    from pixelpen.devices.hid.semantics import semantics_for

    try:
        descriptor = parse_descriptor(link.report_descriptor, vendor_id=device_id.vendor_id,
                                      product_id=device_id.product_id, source=where)
        semantics = semantics_for(descriptor, device_id, **options)
        return ReportSource(link, semantics, device_id, clock=clock)
    except BaseException:
        link.close()
        raise


def simulated_source(device: Any, *, clock: Clock, options: dict[str, Any], where: str) -> ReportSource:
    """A simulated ReportDevice reached as hardware is: the fake hidapi module and the real HidapiLink."""
    from pixelpen.drivers.hidapi import open_hid

    module = importlib.import_module("pixelpen.sim.transports.hidapi").SimHidapi([device], clock=clock)
    paths = module.paths()
    if not paths:
        raise ConfigError(f"{where}: the simulated device is not connected")
    link = open_hid(paths[0], module=module, clock=clock)
    source = report_source(link, link.device_id, clock=clock, options=options, where=where)
    source.bus = module
    return source


def open_sim(url: DeviceURL, *, clock: Clock | None, options: dict[str, Any]) -> EventSource:
    """``sim:MODEL?options``: the simulated model; the simulator's own options go to it, the rest to the semantics."""
    clock = clock or REAL_CLOCK
    sim_base = importlib.import_module("pixelpen.sim.base")
    model = url.target
    if not model:
        raise URLError(f"{url}: name a simulated input model, e.g. sim:tablet?script=signature")
    sim_names = {spec.name for spec in sim_base.simulator_options(model)} | {"id"}
    device = sim_base.create_simulator(model, clock=clock,
                                       **{k: v for k, v in url.options.items() if k in sim_names})
    if not isinstance(device, sim_base.ReportDevice):
        device.close()
        raise URLError(f"{url}: the {model} simulator is reached through {sim_base.reached_through(device)}, "
                       "not HID reports")
    semantics_options = {k: v for k, v in url.options.items() if k not in sim_names} | options
    return simulated_source(device, clock=clock, options=semantics_options, where=str(url))


def open_hid_source(url: DeviceURL, *, clock: Clock | None, options: dict[str, Any]) -> EventSource:
    """``hid:PATH`` or ``hid:VID:PID[:SERIAL]``: a real HID device through hidapi."""
    from pixelpen.drivers.hidapi import open_hid

    clock = clock or REAL_CLOCK
    own, rest = _split(url, HID_OPTIONS)
    link = open_hid(url.target, backend=own["backend"], clock=clock)
    return report_source(link, link.device_id, clock=clock, options=rest | options, where=str(url))


def open_replay(url: DeviceURL, *, clock: Clock | None, options: dict[str, Any]) -> EventSource:
    """``replay:FILE``: one device of a hid-recorder file, replayed on the clock."""
    from pixelpen.drivers.recordings.hidrecorder import read_hid_recording

    own, rest = _split(url, REPLAY_OPTIONS)
    recordings = read_hid_recording(url.target, source=url.target)
    clock = clock or (REAL_CLOCK if own["realtime"] else SimulatedClock())
    index = own["device"]
    if index >= len(recordings):
        raise URLError(f"{url}: device={index}, but the recording holds {len(recordings)} device(s)")
    replay = importlib.import_module("pixelpen.sim.hid.replay")
    device = replay.replay_device(recordings[index], clock=clock, realtime=own["realtime"],
                                  delay=own["delay"] if own["realtime"] else 0.0)
    return simulated_source(device, clock=clock, options=rest | options, where=str(url))


EV_KEY = 0x01
"""linux/input-event-codes.h: the key and button event type (the codes a recording declares for it)."""


class EvdevSource:
    """evdev events (a live node or a recording) grouped into SYN_REPORT frames by ``devices.hid.evdev``."""

    def __init__(self, reader: Any, semantics: Any, device_id: DeviceId, *, clock: Clock) -> None:
        self.reader = reader
        """Has ``read_events(timeout) -> [(time, type, code, value), ...]`` ([] on timeout) and ``close()``."""
        self.semantics = semantics
        self.device_id = device_id
        self.clock = clock

    def read(self, timeout: float | None) -> list[InputEvent] | None:
        """The events of the evdev events that came (frames end at SYN_REPORT), or None on timeout."""
        raw = self.reader.read_events(timeout)
        if not raw:
            return None
        events: list[InputEvent] = self.semantics.feed_events(raw)
        return events

    def describe(self) -> str:
        """What the semantics understood of the device."""
        return str(self.semantics.describe())

    def close(self) -> None:
        """Close the reader."""
        self.reader.close()


class RecordingReader:
    """The events of an evdev recording, each given when the clock reaches its time (relative to the first)."""

    def __init__(self, events: Sequence[tuple[float, int, int, int]], clock: Clock) -> None:
        self._events = events
        self._clock = clock
        self._next = 0
        self._origin = clock.now() - (events[0][0] if events else 0.0)
        self.closed = False

    def read_events(self, timeout: float | None) -> list[tuple[float, int, int, int]]:
        """The events due once the next is (waiting on the clock at most ``timeout``); [] on timeout or, at once
        when ``timeout`` is None, at the end of the recording (nothing more will come)."""
        if self._next >= len(self._events):
            if timeout is not None:
                self._clock.sleep(timeout)
            return []
        wait = self._origin + self._events[self._next][0] - self._clock.now()
        if wait > 0:
            if timeout is not None and wait > timeout:
                self._clock.sleep(timeout)
                return []
            self._clock.sleep(wait)
        now, due = self._clock.now(), []
        while self._next < len(self._events) and self._origin + self._events[self._next][0] <= now:
            t, type_, code, value = self._events[self._next]
            due.append((self._origin + t, type_, code, value))
            self._next += 1
        return due

    def close(self) -> None:
        """Nothing to release."""
        self.closed = True


def open_evdev(url: DeviceURL, *, clock: Clock | None, options: dict[str, Any]) -> EventSource:
    """``evdev:/dev/input/eventN``: a Linux input node through python-evdev."""
    from pixelpen.devices.hid.evdev import EvdevSemantics
    from pixelpen.drivers.evdev import EvdevLink

    own, rest = _split(url, EVDEV_OPTIONS)
    clock = clock or REAL_CLOCK
    link = EvdevLink(url.target, grab=own["grab"], clock=clock)
    try:
        semantics = EvdevSemantics(link.device_id, link.absinfo, keys=link.codes.get(EV_KEY, ()), **(rest | options))
    except BaseException:
        link.close()
        raise
    return EvdevSource(link, semantics, link.device_id, clock=clock)


def open_evemu(url: DeviceURL, *, clock: Clock | None, options: dict[str, Any]) -> EventSource:
    """``evemu:FILE``: an evemu recording replayed on the clock."""
    from pixelpen.devices.hid.evdev import EvdevSemantics
    from pixelpen.drivers.recordings.evemu import read_evemu

    own, rest = _split(url, EVEMU_OPTIONS)
    clock = clock or (REAL_CLOCK if own["realtime"] else SimulatedClock())
    recording = read_evemu(url.target, source=url.target)
    device_id = recording.device_id
    semantics = EvdevSemantics(device_id, recording.absinfo, keys=recording.codes.get(EV_KEY, ()),
                               **(rest | options))
    return EvdevSource(RecordingReader(recording.events, clock), semantics, device_id, clock=clock)

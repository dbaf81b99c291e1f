"""HidSim: a simulated HID device on the clock — its descriptor, its polling interval, its firmware, faults.

The host-facing side is ``pixelpen.sim.base.ReportDevice``: a transport fake (``pixelpen.sim.transports.
hidapi``, ``usbhid``) calls ``advance_to(clock.now())`` and ``take_reports()``, writes output reports and
gets/sends feature reports.  A model's ``Firmware`` (``pixelpen.sim.hid.models``) samples the scripted hand
when its interrupt endpoint is polled — one report per polling interval at most, as on USB: a firmware that
has several reports to send for one sample (a touch screen in hybrid mode) queues them and sends one per
interval.  ``HidSim.from_descriptor`` builds a device from a descriptor and timed reports (a recording).
``Layout`` is how a firmware packs a report: fields at bit offsets, little endian, two's complement where signed.

Faults: ``power-loss`` stops the reports (nothing more is sent; ``connected`` turns False, and the host
calls raise ``Disconnected`` as the host's own calls on a removed device fail); ``power-restore`` brings it
back as at power-up (LEDs off, multipliers reset, the polling phase restarted at that instant; the hand kept
moving meanwhile); ``reset`` is both at once.  ``close()`` unplugs it for good.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, ClassVar

from pixelpen.clock import Clock
from pixelpen.drivers.hidapi import numbered_reports as numbered
from pixelpen.errors import ConfigError, Disconnected, InvalidArgument, InvalidArgumentType, ProtocolError, quote_token
from pixelpen.sim.base import Fault, SimulatedDevice

HZ_RANGE = (1.0, 8000.0)
"""Polling rates accepted, reports per second: USB full speed polls every 1..255 ms (bInterval), high speed down to
every 125 µs microframe; below 1 Hz a device is not an input device any more."""

MAX_UNREAD_REPORTS = 65_536
"""Input reports kept for a host that does not read (the oldest are dropped and counted in ``dropped``)."""


@dataclass(frozen=True)
class Layout:
    """One report's layout as ``descriptors`` documents it: its length, report ID and fields by bit position.

    ``fields`` maps a name to (bit offset from bit 0 of byte 0, the ID byte included; size in bits; signed).
    """

    length: int
    report_id: int | None
    fields: Mapping[str, tuple[int, int, bool]]

    def pack(self, **values: int) -> bytes:
        """The report with ``values`` (fields not named are 0), little-endian, two's complement where signed."""
        word = 0 if self.report_id is None else self.report_id
        for name, value in values.items():
            offset, size, signed = self.fields[name]
            low, high = (-(1 << (size - 1)), (1 << (size - 1)) - 1) if signed else (0, (1 << size) - 1)
            if not low <= value <= high:
                raise InvalidArgument(f"field {name} = {value} does not fit {size} bits "
                                      f"({'signed' if signed else 'unsigned'})")
            word |= (value & ((1 << size) - 1)) << offset
        return word.to_bytes(self.length, "little")

    def value(self, report: bytes, name: str) -> int:
        """Field ``name`` of ``report`` (a host's output or feature report of this layout)."""
        offset, size, signed = self.fields[name]
        raw = (int.from_bytes(report, "little") >> offset) & ((1 << size) - 1)
        return raw - (1 << size) if signed and raw >> (size - 1) else raw


def layout(length: int, report_id: int | None, *fields: tuple[str, int] | tuple[str, int, bool]) -> Layout:
    """A Layout from its fields in report order: (name, bits[, signed]); a name starting with ``_`` is padding."""
    offset = 0 if report_id is None else 8
    table: dict[str, tuple[int, int, bool]] = {}
    for item in fields:
        name, size = item[0], item[1]
        if not name.startswith("_"):
            table[name] = (offset, size, len(item) > 2 and bool(item[2]))
        offset += size
    if offset != 8 * length:
        raise AssertionError(f"layout of {offset} bits is not {length} bytes")  # pragma: no cover - a typo here
    return Layout(length, report_id, MappingProxyType(table))


def clamp(value: float, low: int, high: int) -> int:
    """``value`` rounded to the nearest integer, limited to low..high (what a firmware's saturating maths does)."""
    return min(max(round(value), low), high)


def bit_set(bits: Sequence[bool]) -> int:
    """The integer whose bit i is ``bits[i]``."""
    return sum(1 << i for i, b in enumerate(bits) if b)


class Firmware:
    """A HID device's program: what it sends when polled, how it answers output and feature reports.

    This base is the generic device (``HidSim.from_descriptor``): it sends nothing by itself, keeps the last
    output report per report ID and answers GET_REPORT(Feature) with the last feature report the host set
    under that ID (a STALL, ProtocolError, for one never set).  Models override ``poll``/``busy`` and the
    report handlers.  Times are seconds since the device started (its script's time).
    """

    model: str = "hid"

    def __init__(self, descriptor: bytes) -> None:
        self.descriptor = bytes(descriptor)
        self.numbered = numbered(self.descriptor)
        """Reports start with their report ID byte."""
        self.outputs: dict[int, bytes] = {}
        """The last output report per report ID (0 for an unnumbered device), as the host wrote it."""
        self._features: dict[int, bytes] = {}

    def poll(self, t: float) -> list[bytes]:
        """The reports to queue when the endpoint is polled at ``t`` with nothing queued (empty: no change)."""
        return []

    def busy(self, t: float) -> bool:
        """True while the firmware may still have something to send at ``t`` or later (the hand is busy)."""
        return False

    def power_up(self, t: float) -> None:
        """Power-up state at ``t``: what was held in RAM (LEDs, feature settings, what was sent last) is gone."""
        self.outputs.clear()
        self._features.clear()

    def report_id(self, report: bytes, kind: str) -> int:
        """The report ID a host report carries (0 when unnumbered); ProtocolError for an empty one."""
        if not report:
            raise ProtocolError(f"empty {kind} report", device=self.model, command=kind)
        return report[0] if self.numbered else 0

    def output(self, report: bytes) -> None:
        """An output report from the host (SET_REPORT(Output) or the interrupt OUT endpoint)."""
        self.outputs[self.report_id(report, "output")] = report

    def feature(self, report_id: int) -> bytes:
        """GET_REPORT(Feature, report_id): the report, its ID byte first when numbered."""
        try:
            return self._features[report_id]
        except KeyError:
            raise self.stall("feature", report_id) from None

    def set_feature(self, report: bytes) -> None:
        """SET_REPORT(Feature): store it for ``feature``."""
        self._features[self.report_id(report, "feature")] = report

    def stall(self, kind: str, report_id: int) -> ProtocolError:
        """The error a request for a report the device does not have gives (the endpoint STALLs)."""
        return ProtocolError(f"no {kind} report with ID {report_id} (the device STALLs the request)",
                             device=self.model, command=f"{kind} {report_id}")


class _Poller:
    """Ticks of a polled interrupt endpoint: one report per interval, from what the firmware queued."""

    def __init__(self, firmware: Firmware, hz: float, origin: float, script_origin: float) -> None:
        self._firmware = firmware
        self.hz = hz
        self._origin = origin
        self._script_origin = script_origin
        self._tick = 1
        self._queue: deque[bytes] = deque()

    def next_time(self) -> float | None:
        """The next tick at which there may be a report (None: the firmware is idle for good)."""
        t = self._origin + self._tick / self.hz
        if self._queue or self._firmware.busy(t - self._script_origin):
            return t
        return None

    def fire(self, t: float) -> bytes | None:
        """The tick at ``t``: the report sent on it, if any."""
        self._tick += 1
        if not self._queue:
            self._queue.extend(self._firmware.poll(t - self._script_origin))
        return self._queue.popleft() if self._queue else None

    def restart(self, t: float) -> None:
        """Power-up at ``t``: nothing queued, the ticks counted from ``t``."""
        self._origin = t
        self._tick = 1
        self._queue.clear()


class _Timeline:
    """Reports at given times (seconds after the device started), read lazily from an iterable."""

    def __init__(self, reports: Iterable[tuple[float, bytes]], origin: float) -> None:
        self._reports: Iterator[tuple[float, bytes]] = iter(reports)
        self._origin = origin
        self._index = -1
        self._last = -math.inf
        self._next: tuple[float, bytes] | None = None
        self._load()

    def _load(self) -> None:
        """Look ahead one report, checking it (finite times, not decreasing, bytes)."""
        item = next(self._reports, None)
        self._index += 1
        if item is None:
            self._next = None
            return
        t, report = item
        if not isinstance(report, (bytes, bytearray, memoryview)):
            raise InvalidArgumentType(f"report {self._index}: expected bytes, found {type(report).__name__}")
        t = float(t)
        if not math.isfinite(t) or t < self._last:
            raise ConfigError(f"report {self._index} at {t} s comes before report {self._index - 1} at "
                              f"{self._last} s (times must be finite and not decreasing)")
        self._last = t
        self._next = (self._origin + t, bytes(report))

    def next_time(self) -> float | None:
        """Clock time of the next report (None: the recording is over)."""
        return None if self._next is None else self._next[0]

    def fire(self, t: float) -> bytes | None:
        """The report due at ``t``."""
        if self._next is None:
            return None
        report = self._next[1]
        self._load()
        return report

    def restart(self, t: float) -> None:
        """Power back at ``t``: the reports due while it was off are lost."""
        while self._next is not None and self._next[0] < t:
            self._load()


class HidSim(SimulatedDevice):
    """A simulated HID device: a ReportDevice whose firmware is polled every 1/hz s, or that plays timed reports."""

    FAULTS: ClassVar[frozenset[Fault]] = frozenset({Fault.POWER_LOSS, Fault.POWER_RESTORE, Fault.RESET})

    def __init__(self, firmware: Firmware, *, hz: float = 125.0, clock: Clock | None = None,
                 reports: Iterable[tuple[float, bytes]] | None = None, info: dict[str, Any] | None = None) -> None:
        super().__init__(clock)
        if not (isinstance(hz, (int, float)) and HZ_RANGE[0] <= hz <= HZ_RANGE[1]):
            raise ConfigError(f"{firmware.model}: polling rate hz={hz!r} outside {HZ_RANGE[0]:g}..{HZ_RANGE[1]:g}")
        self.model = firmware.model
        self.firmware = firmware
        """The model's program (its LEDs, multipliers, what it last sent)."""
        self.report_descriptor = firmware.descriptor
        self.hz = float(hz)
        """The polling rate in reports per second (one report per 1/hz s at most)."""
        self.info: dict[str, Any] = dict(info or {})
        """What hidapi's enumerate() lists for the device (ids, strings, usage page/usage, interface), no path."""
        self._origin = self._now
        self._schedule: _Poller | _Timeline
        if reports is None:
            self._schedule = _Poller(firmware, self.hz, self._now, self._origin)
        else:
            self._schedule = _Timeline(reports, self._now)
        self._powered = True
        self._sent: deque[tuple[float, bytes]] = deque()
        self.sent = 0
        """Input reports sent since the start."""
        self.dropped = 0
        """Input reports dropped because more than ``MAX_UNREAD_REPORTS`` were waiting unread."""

    @classmethod
    def from_descriptor(cls, descriptor: bytes, reports: Iterable[tuple[float, bytes]] = (), *,
                        clock: Clock | None = None, model: str = "hid",
                        info: dict[str, Any] | None = None) -> HidSim:
        """A device with any descriptor that sends ``reports`` — (seconds after its start, report bytes) — on the clock.

        Reports are read lazily (a long recording is not held in memory), with their ID byte first when the
        descriptor numbers its reports; times must not decrease.  Output reports are kept (``firmware.outputs``),
        a feature report set by the host is answered back.
        """
        if not isinstance(descriptor, (bytes, bytearray, memoryview)):
            raise InvalidArgumentType("from_descriptor() takes the descriptor as bytes, not "
                                      f"{type(descriptor).__name__}")
        firmware = Firmware(bytes(descriptor))
        firmware.model = model
        return cls(firmware, clock=clock, reports=reports, info=info)

    # ---- ReportDevice ----------------------------------------------------------------------------
    @property
    def connected(self) -> bool:
        """True while the device is plugged in and powered (False after ``close`` or a power loss)."""
        return self._powered and not self.closed

    def take_reports(self) -> list[bytes]:
        """The input reports sent since the last call, oldest first (the clock's present caught up first)."""
        return [report for _, report in self.take_timed_reports()]

    def take_timed_reports(self) -> list[tuple[float, bytes]]:
        """The same as ``take_reports`` with the clock time each report was sent at."""
        self._catch_up()
        out = list(self._sent)
        self._sent.clear()
        return out

    def write_report(self, report: bytes) -> None:
        """An output report from the host, ID byte first when numbered (Disconnected when unplugged or off)."""
        self._check_connected("write an output report")
        self.receive(report)

    def receive(self, data: bytes | bytearray | memoryview) -> None:
        """An output report as a whole: a fault injected ``at`` a byte count falls after the report reaching it."""
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise InvalidArgumentType(f"{self.model}: an output report is bytes, not {type(data).__name__}")
        if self.closed:
            return
        report = bytes(data)
        self._received += len(report)
        self._receive(report)
        while self._due and self._due[0][0] <= self._received:
            self._apply_fault(self._due.pop(0)[2])

    def get_feature(self, report_id: int) -> bytes:
        """GET_REPORT(Feature): the report, ID byte first when numbered; ProtocolError (STALL) for an unknown ID."""
        self._check_connected(f"get feature report {report_id}")
        self._catch_up()
        return self.firmware.feature(report_id)

    def send_feature(self, report: bytes) -> None:
        """SET_REPORT(Feature): ID byte first when numbered; ProtocolError (STALL) for one the device lacks."""
        self._check_connected("send a feature report")
        if not isinstance(report, (bytes, bytearray, memoryview)):
            raise InvalidArgumentType(f"{self.model}: send_feature() takes bytes, not {type(report).__name__}")
        self._catch_up()
        self.firmware.set_feature(bytes(report))

    def _check_connected(self, what: str) -> None:
        """Disconnected naming the device and the request when it is unplugged or without power."""
        if not self.connected:
            state = "unplugged" if self.closed else "without power"
            raise Disconnected(f"{self.model}: cannot {what}: the device is {state}")

    # ---- SimulatedDevice ---------------------------------------------------------------------------
    def _receive(self, data: bytes) -> None:
        self._catch_up()
        self.firmware.output(data)

    def _next_internal_event(self) -> float | None:
        return self._schedule.next_time() if self._powered else None

    def _handle_event(self, t: float) -> None:
        self._now = t
        report = self._schedule.fire(t)
        if report is not None:
            self.sent += 1
            if len(self._sent) >= MAX_UNREAD_REPORTS:
                self._sent.popleft()
                self.dropped += 1
            self._sent.append((t, report))

    def _apply_fault(self, fault: Fault) -> None:
        self._catch_up()
        if fault is Fault.POWER_LOSS:
            self._powered = False
            return
        if fault is Fault.POWER_RESTORE and self._powered:
            return
        self._powered = True
        self.firmware.power_up(self._now - self._origin)
        self._schedule.restart(self._now)

    def _shutdown(self) -> None:
        self._powered = False

    def __repr__(self) -> str:
        state = "connected" if self.connected else ("unplugged" if self.closed else "off")
        return f"<HidSim {self.model} {self.hz:g} Hz {state}, {self.sent} reports sent>"


def check_report(report: bytes, length: int, report_id: int | None, model: str, kind: str) -> None:
    """ProtocolError unless ``report`` is ``length`` bytes (ID included) starting with ``report_id`` (None: none)."""
    if len(report) != length or (report_id is not None and report[0] != report_id):
        expected = f"{length} bytes" + ("" if report_id is None else f" starting with report ID {report_id}")
        raise ProtocolError(f"{kind} report {quote_token(report.hex(' '))} is not {expected}",
                            device=model, command=kind)

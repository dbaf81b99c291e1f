"""SimHidapi: a module-like fake of cython-hidapi whose devices are ReportDevice simulators (``HidSim``).

``open_hid("sim:mouse:0", module=SimHidapi([sim]))`` runs the unchanged :class:`~pixelpen.drivers.hidapi.
HidapiLink` against a simulator.  The fake has the API of cython-hidapi 0.15 (``enumerate``, ``device()`` with
``open``/``open_path``/``read``/``write``/``get_feature_report``/``send_feature_report``/``get_input_report``/
``get_report_descriptor``/``set_nonblocking``/strings/``error``/``close``, ``version_str``) and what the hidraw
backend and the kernel do underneath:

* enumeration: one dict per top-level collection of the descriptor (usage page and usage as hidraw reads
  them from the descriptor), ids and strings from the simulator's ``info`` (hidapi's own key names), path
  ``sim:<model>:<n>`` (``n`` counts plugs, so a replugged device gets a new path), ``bus_type`` 5 (virtual);
* report IDs: ``write``/``send_feature_report`` take the report ID first, 0x00 for an unnumbered device,
  which is stripped before the device sees the report; a 0 on a numbered device, or a non-zero first byte on
  an unnumbered one, fails with ``Broken pipe`` as the device's STALL does; ``get_feature_report`` returns the
  ID first (0 for an unnumbered device); ``read`` returns the report as the device sent it (ID only when
  numbered), cut to ``max_length`` as hidraw does;
* readers: each open handle gets every report sent after it was opened (none from before), in a buffer
  like the backend's (``backend="hidraw"``: 63 reports, the arriving ones dropped when full; ``"libusb"``:
  32, the oldest dropped — ``BUFFERS``), so a slow reader loses reports as it would on Linux;
* time: a read takes the reports the device sent by ``clock.now()`` (``advance_to``, ``take_reports``); with
  none it waits for the device's next report or the timeout, whichever is first, with ``clock.sleep`` (a
  SimulatedClock jumps there at once).  ``read(n, 0)`` on a blocking handle waits forever as hidapi does —
  here it raises RuntimeError when no report will ever come instead of hanging the test;
* unplug (``unplug()``, the simulator's ``close()`` or a power loss): ``read`` raises ``OSError('read error')``
  with hidapi's "device disconnected" error text, other calls fail with "No such device", and the handle stays
  dead (a replugged device is opened again on its new path).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from pixelpen.clock import Clock, SimulatedClock
from pixelpen.drivers.hidapi import MAX_DESCRIPTOR, numbered_reports, top_level_usages
from pixelpen.errors import ConfigError, Disconnected, ProtocolError
from pixelpen.sim.base import ReportDevice, reached_through

BUS_VIRTUAL = 5
"""hidapi's HID_API_BUS_VIRTUAL (uhid and other virtual devices)."""
VERSION = "0.15.0"
_GONE = "No such device"
_READ_GONE = "hid_read_timeout: unexpected poll error (device disconnected)"
_STALL = "Broken pipe"
IDLE_LIMIT = 3600.0
"""Simulated seconds a handle may wait in a row on a device with nothing more to send before reads raise
RuntimeError: a host reading without timeout in slices (as HidapiLink does) would otherwise spin forever."""
MAX_WAITS = 1_000_000
"""Waits one read may make on the clock before the fake calls it a bug (never a hang)."""


def connected(device: ReportDevice) -> bool:
    """True while the simulated device is plugged in and powered (HidSim's ``connected``; else not closed)."""
    flag = getattr(device, "connected", None)
    return bool(flag) if flag is not None else not getattr(device, "closed", False)


BUFFERS = {"hidraw": (63, "newest"), "libusb": (32, "oldest")}
"""Input reports a reader's buffer holds and which are lost when it is full: hidraw's ring of
HIDRAW_BUFFER_SIZE 64 holds 63 and drops the arriving report (``hidraw_report_event``); hidapi's libusb
backend keeps 32 and drops the oldest (``read_callback``)."""


class ReportQueue:
    """The host's end of a simulated interrupt IN endpoint: reports in order, waits on the clock, unplug noticed.

    ``capacity`` bounds the reports held (None: the device's own bound), dropping the ``newest`` arriving or
    the ``oldest`` held (``dropped`` counts them).  ``pump`` moves what the device sent into the queue (by
    default this queue takes the device's reports itself; SimHidapi fans them out to every open handle).
    Shared by this fake and the pyusb one (``usbhid.py``).
    """

    def __init__(self, device: ReportDevice, clock: Clock | None = None, *, capacity: int | None = None,
                 drop: str = "newest", pump: Callable[[], None] | None = None) -> None:
        self.device = device
        self.clock = clock if clock is not None else device.clock
        self.capacity = capacity
        self.drop = drop
        self.dropped = 0
        """Reports lost because the buffer was full (a reader slower than the device)."""
        self.idle = 0.0
        """Simulated seconds waited in a row with nothing scheduled (see IDLE_LIMIT)."""
        self._pump = pump if pump is not None else self.pump
        self._queue: deque[bytes] = deque()

    def pump(self) -> None:
        """Take what the device sent up to the clock's present into this queue."""
        self.device.advance_to(self.clock.now())
        self.extend(self.device.take_reports())

    def extend(self, reports: Iterable[bytes]) -> None:
        """Reports arriving, in order, into the bounded buffer."""
        for report in reports:
            if self.capacity is not None and len(self._queue) >= self.capacity:
                self.dropped += 1
                if self.drop == "newest":
                    continue
                self._queue.popleft()
            self._queue.append(report)

    def take(self, wait: float | None) -> bytes | None:
        """The next report, waiting up to ``wait`` clock seconds (None: until one comes); Disconnected when unplugged.

        RuntimeError when ``wait`` is None and the device has nothing scheduled (the wait would never end).
        """
        deadline = None if wait is None else self.clock.now() + max(0.0, wait)
        for _ in range(MAX_WAITS):
            if not connected(self.device):
                raise Disconnected(f"{self.device.model}: the device was unplugged")
            self._pump()
            if self._queue:
                self.idle = 0.0
                return self._queue.popleft()
            now = self.clock.now()
            if deadline is not None and now >= deadline:
                return None
            due = self.device.next_event_time()
            if due is None and deadline is not None and isinstance(self.clock, SimulatedClock):
                self.idle += deadline - now
            if due is None and (deadline is None or self.idle > IDLE_LIMIT):
                self.idle = 0.0
                raise RuntimeError(f"{self.device.model}: a read without timeout would wait forever (the simulated "
                                   "device has nothing more to send); real hidapi would hang here")
            target = min(t for t in (due, deadline) if t is not None)
            self.clock.sleep(max(target - now, 0.0))
            if self.clock.now() <= now and target > now:
                return None  # a clock that does not move (an idle real-time device ends the wait)
        raise RuntimeError(f"{self.device.model}: read did not converge after {MAX_WAITS} waits")  # pragma: no cover


@dataclass
class _Slot:
    path: bytes
    device: ReportDevice
    clock: Clock
    numbered: bool
    """The device numbers its reports (its descriptor has a Report ID item): read once, at plug-in."""
    queues: list[ReportQueue] = field(default_factory=list)

    def pump(self, joining: ReportQueue | None = None) -> None:
        """What the device sent up to now goes to every open handle, as the kernel gives each reader every report.

        A handle ``joining`` now also gets the reports sent at this very instant (a replay's first report at the
        time the reader opens), none sent before.
        """
        now = self.clock.now()
        self.device.advance_to(now)
        timed = self.device.take_timed_reports()
        reports = [r for _, r in timed]
        for queue in self.queues:
            queue.extend(reports)
        if joining is not None:
            joining.extend(r for t, r in timed if t >= now)


class SimHidapi:
    """cython-hidapi's module API over simulated ReportDevices (see the module docstring)."""

    HID_API_VERSION_MAJOR = 0
    HID_API_VERSION_MINOR = 15
    HID_API_VERSION_PATCH = 0
    HID_API_MAX_REPORT_DESCRIPTOR_SIZE = MAX_DESCRIPTOR
    HID_API_BUS_UNKNOWN, HID_API_BUS_USB, HID_API_BUS_BLUETOOTH, HID_API_BUS_I2C, HID_API_BUS_SPI = 0, 1, 2, 3, 4
    HID_API_BUS_VIRTUAL = BUS_VIRTUAL

    def __init__(self, devices: Iterable[ReportDevice] = (), *, clock: Clock | None = None,
                 backend: str = "hidraw") -> None:
        if backend not in BUFFERS:
            raise ValueError(f"backend must be one of {', '.join(BUFFERS)}, got {backend!r}")
        self.clock = clock
        """The clock reads wait on (default: each device's own)."""
        self.backend = backend
        """Whose input buffer the handles have (``BUFFERS``): ``hidraw`` or ``libusb``."""
        self._slots: list[_Slot] = []
        self._plugs = 0
        for device in devices:
            self.plug(device)

    # ---- the simulated bus -------------------------------------------------------------------
    def plug(self, device: ReportDevice) -> str:
        """Plug a simulated device in; its new path (``sim:<model>:<n>``); ConfigError for a non-HID simulator."""
        if not isinstance(device, ReportDevice):
            raise ConfigError(f"the {getattr(device, 'model', type(device).__name__)} simulator is reached through "
                              f"{reached_through(device)}, not HID reports")
        path = f"sim:{device.model}:{self._plugs}"
        self._plugs += 1
        self._slots.append(_Slot(path.encode(), device, self.clock if self.clock is not None else device.clock,
                                 numbered_reports(device.report_descriptor)))
        return path

    def unplug(self, which: str | bytes | ReportDevice) -> None:
        """Pull a device out (by path or device): its simulator is closed, its open handles go dead."""
        slot = self._slot(which)
        self._slots.remove(slot)
        slot.device.close()

    def _slot(self, which: str | bytes | ReportDevice) -> _Slot:
        for slot in self._slots:
            if slot.device is which or slot.path == (which.encode() if isinstance(which, str) else which):
                return slot
        raise KeyError(f"no simulated HID device {which!r}; paths: {[s.path.decode() for s in self._slots]}")

    def paths(self) -> list[str]:
        """Paths of the devices plugged in now."""
        return [s.path.decode() for s in self._slots if connected(s.device)]

    # ---- cython-hidapi's module functions ------------------------------------------------------
    def enumerate(self, vendor_id: int = 0, product_id: int = 0) -> list[dict[str, Any]]:
        """One dict per top-level collection of each connected device (0 matches any ID), hidapi's keys."""
        out = []
        for slot in self._slots:
            if not connected(slot.device):
                continue
            entry = self._entry(slot)
            if vendor_id not in (0, entry["vendor_id"]) or product_id not in (0, entry["product_id"]):
                continue
            for page, usage in top_level_usages(slot.device.report_descriptor) or [(0, 0)]:
                out.append(entry | {"usage_page": page, "usage": usage})
        return out

    @staticmethod
    def _entry(slot: _Slot) -> dict[str, Any]:
        info = dict(getattr(slot.device, "info", None) or {})
        return {
            "path": slot.path,
            "vendor_id": int(info.get("vendor_id", 0)),
            "product_id": int(info.get("product_id", 0)),
            "serial_number": str(info.get("serial_number", "")),
            "release_number": int(info.get("release_number", 0x0100)),
            "manufacturer_string": str(info.get("manufacturer_string", "pixelpen")),
            "product_string": str(info.get("product_string", f"simulated {slot.device.model}")),
            "interface_number": int(info.get("interface_number", 0)),
            "bus_type": int(info.get("bus_type", BUS_VIRTUAL)),
        }

    def device(self) -> SimHidDevice:
        """A closed handle, as ``hid.device()`` makes one."""
        return SimHidDevice(self)

    @staticmethod
    def version_str() -> str:
        """The hidapi version this fake behaves as."""
        return VERSION


class SimHidDevice:
    """cython-hidapi's ``device`` over one simulated device."""

    def __init__(self, bus: SimHidapi) -> None:
        self._bus = bus
        self._slot: _Slot | None = None
        self._queue: ReportQueue | None = None
        self._nonblocking = False
        self._error = ""
        self._dead = False

    # ---- open / close -----------------------------------------------------------------------------
    def open(self, vendor_id: int = 0, product_id: int = 0, serial_number: str | None = None) -> None:
        """hid_open: the first enumerated device with these IDs (0: any) and serial; OSError('open failed')."""
        for entry in self._bus.enumerate(vendor_id, product_id):
            if serial_number is None or entry["serial_number"] == serial_number:
                self.open_path(entry["path"])
                return
        raise OSError("open failed")

    def open_path(self, path: bytes) -> None:
        """hid_open_path (the path as bytes, as cython-hidapi requires); OSError('open failed')."""
        if not isinstance(path, bytes):
            raise TypeError(f"Argument 'path' has incorrect type (expected bytes, got {type(path).__name__})")
        if self._slot is not None:
            raise RuntimeError("already open")
        for slot in self._bus._slots:
            if slot.path == path and connected(slot.device):
                capacity, drop = BUFFERS[self._bus.backend]
                self._slot = slot
                self._queue = ReportQueue(slot.device, slot.clock, capacity=capacity, drop=drop, pump=slot.pump)
                slot.pump(joining=self._queue)  # what was sent before the open goes to the readers open already
                slot.queues.append(self._queue)
                return
        raise OSError("open failed")

    def close(self) -> None:
        """Close the handle (idempotent)."""
        if self._slot is not None and self._queue is not None:
            self._slot.queues.remove(self._queue)
        self._slot = self._queue = None

    def set_nonblocking(self, v: int) -> int:
        """Non-blocking mode: ``read(n)`` without a timeout returns at once; 0 on success."""
        self._device()
        self._nonblocking = bool(v)
        return 0

    def error(self) -> str:
        """The last error of this handle, hidapi's words ('Success' when none)."""
        return self._error or "Success"

    # ---- reports --------------------------------------------------------------------------------
    def read(self, max_length: int, timeout_ms: int = 0) -> list[int]:
        """The next input report (cut to ``max_length``), [] after ``timeout_ms``; OSError('read error') when gone."""
        device = self._device()
        if max_length < 0:
            raise ValueError("max_length must not be negative")
        assert self._queue is not None
        wait = timeout_ms / 1000.0 if timeout_ms > 0 else (0.0 if self._nonblocking else None)
        try:
            report = self._queue.take(wait) if not self._dead else None
        except Disconnected:
            report = None
        if self._dead or not connected(device):
            self._dead = True
            self._error = _READ_GONE
            raise OSError("read error")
        self._error = ""
        return list(report[:max_length]) if report is not None else []

    def write(self, buff: Sequence[int] | bytes) -> int:
        """hid_write: report ID first (0 for an unnumbered device, stripped); bytes written, or -1 with error()."""
        device = self._device()
        data = bytes(buff)
        report = self._strip(data)
        if report is None:
            return -1
        return self._call(lambda: device.write_report(report), len(data))

    def send_feature_report(self, buff: Sequence[int] | bytes) -> int:
        """hid_send_feature_report: report ID first as for ``write``; bytes sent, or -1 with error()."""
        device = self._device()
        data = bytes(buff)
        report = self._strip(data)
        if report is None:
            return -1
        return self._call(lambda: device.send_feature(report), len(data))

    def get_feature_report(self, report_num: int, max_length: int) -> list[int]:
        """hid_get_feature_report: the report with its ID first (0 for an unnumbered device), up to ``max_length``."""
        device = self._device()
        if max_length < 0:
            raise ValueError("max_length must not be negative")
        numbered = self._open_slot().numbered
        if not numbered and report_num != 0:
            self._error = f"ioctl (GFEATURE): {_STALL}"
            raise OSError("read error")
        answer: list[bytes] = []
        if self._call(lambda: answer.append(device.get_feature(report_num)), 0, "ioctl (GFEATURE)") < 0:
            raise OSError("read error")
        data = answer[0] if numbered else bytes((0,)) + answer[0]
        return list(data[:max_length])

    def get_input_report(self, report_num: int, max_length: int) -> list[int]:
        """hid_get_input_report: simulated devices do not answer GET_REPORT(Input) (a STALL)."""
        self._device()
        self._error = f"ioctl (GINPUT): {_STALL}"
        raise OSError("read error")

    def get_report_descriptor(self) -> list[int]:
        """The device's report descriptor (hidapi >= 0.14)."""
        return list(self._device().report_descriptor[:MAX_DESCRIPTOR])

    # ---- strings ----------------------------------------------------------------------------------
    def get_manufacturer_string(self) -> str:
        """The manufacturer string the device was enumerated with."""
        return str(self._info()["manufacturer_string"])

    def get_product_string(self) -> str:
        """The product string the device was enumerated with."""
        return str(self._info()["product_string"])

    def get_serial_number_string(self) -> str:
        """The serial number string the device was enumerated with."""
        return str(self._info()["serial_number"])

    def get_indexed_string(self, index: int) -> str:
        """Not supported by hidraw (IOError, as hidapi's hidraw backend)."""
        self._device()
        self._error = "hid_get_indexed_string: not supported by hidraw"
        raise OSError("get indexed string error")

    # ---- helpers ----------------------------------------------------------------------------------
    def _open_slot(self) -> _Slot:
        if self._slot is None:
            raise ValueError("not open")
        return self._slot

    def _device(self) -> ReportDevice:
        return self._open_slot().device

    def _info(self) -> dict[str, Any]:
        return SimHidapi._entry(self._open_slot())

    def _strip(self, data: bytes) -> bytes | None:
        """The report the device receives for a hidapi buffer (ID rules); None with error() set when refused."""
        if not data:
            self._error = "Zero buffer/length"
            return None
        numbered = self._open_slot().numbered
        if numbered != (data[0] != 0):  # numbered: ID 1..255 first; unnumbered: 0x00 first
            self._error = _STALL
            return None
        return data if numbered else data[1:]

    def _call(self, action: Any, result: int, what: str = "") -> int:
        """Run a request on the device; ``result``, or -1 with error() in hidapi's words."""
        prefix = f"{what}: " if what else ""
        if self._dead or not connected(self._device()):
            self._dead = True
            self._error = prefix + _GONE
            return -1
        try:
            action()
        except Disconnected:
            self._dead = True
            self._error = prefix + _GONE
            return -1
        except ProtocolError:
            self._error = prefix + _STALL
            return -1
        self._error = ""
        return result


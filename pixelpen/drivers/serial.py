"""SerialLink: a Link over any pyserial port or URL (``/dev/ttyUSB0``, ``COM3``, ``rfc2217://``, ``sim://`` ...).

A serial stream is a byte stream plus what only a serial line has: the line signals (CTS and DSR
as the device drives them, RTS and DTR as the host does; :class:`SerialLines`) and software
XON/XOFF flow control, both here rather than on the base :class:`~pixelpen.drivers.stream.Link`.

Flow control (``flow``):

* ``"rtscts"``: pyserial's ``rtscts=True``; the OS (or the URL handler) holds output while CTS is low.
* ``"xonxoff"``: pyserial's ``xonxoff=True``, which an OS port turns into IXON/IXOFF: the kernel
  stops output on XOFF and strips XON/XOFF from the input.  URL handlers such as ``loop://``,
  ``socket://`` and ``rfc2217://`` do not act on the bytes themselves, so SerialLink *also* honours
  them in software (``soft_xonxoff``, on by default for ``xonxoff``): an XOFF in the input holds
  writes until XON, and both bytes are taken out of what ``read`` returns.  Where the OS already
  consumed them the software layer simply never sees one.  Either way XON/XOFF cannot appear in
  replies, which suits the text protocols (HP-GL, G-code) that use this handshake.
* ``"none"``: bytes go out regardless of the device's state.

URL handlers from plug-ins: a port URL ``X://...`` whose scheme pyserial does not know itself is
looked up in the entry-point group ``pixelpen.serial_handlers`` (``X = "package"``, a package of
pyserial ``protocol_X`` modules); the package is appended to ``serial.protocol_handler_packages``
before the port opens.  pixelpen's own ``sim://`` is registered so in ``pyproject.toml``, and third
parties register theirs the same way.  A handler from the group is handed the link's ``clock=`` when
one is given, and a link given none adopts the port's ``clock`` attribute when it has one: a
``sim://`` link times out in the simulator's time (a ``speed=fast`` simulation in simulated time).
An unknown scheme is refused naming the known ones.
"""

from __future__ import annotations

import functools
import importlib
import pkgutil
from importlib import metadata
from typing import Any, Final, Protocol, runtime_checkable

import serial
from serial.tools import list_ports

from pixelpen.clock import Clock
from pixelpen.drivers.stream import IDLE_POLL, Link
from pixelpen.errors import Disconnected, LinkError, LinkTimeout, PixelpenError

FLOWS = ("none", "rtscts", "xonxoff")
XON: Final = 0x11
"""DC1: the device may take more bytes."""
XOFF: Final = 0x13
"""DC3: the device asks the host to stop sending."""
SOFT_FLOW_CHUNK: Final = 64
"""Bytes sent between two looks for XOFF when software flow control is on."""
HANDLER_GROUP: Final = "pixelpen.serial_handlers"
"""Entry-point group of pyserial URL handler packages, by scheme (``sim = "pixelpen.sim.transports.urlhandler"``)."""


@runtime_checkable
class SerialLines(Protocol):
    """The line signals of a serial port: CTS and DSR as the device drives them, RTS and DTR as the host does."""

    @property
    def cts(self) -> bool:
        """Clear To Send (the device's hardware handshake)."""

    @property
    def dsr(self) -> bool:
        """Data Set Ready (the device is there)."""

    rts: bool
    """Request To Send, as the host drives it."""
    dtr: bool
    """Data Terminal Ready, as the host drives it (raising it resets an Arduino)."""


@functools.cache
def serial_handlers() -> dict[str, str]:
    """Scheme -> handler package, from the ``pixelpen.serial_handlers`` entry points (read once)."""
    return {entry.name.lower(): entry.value for entry in metadata.entry_points(group=HANDLER_GROUP)}


def url_scheme(url: str) -> str | None:
    """The scheme of a port URL (``rfc2217`` for ``rfc2217://host:port``), None for a device path."""
    head, sep, _ = url.partition("://")
    return head.lower() if sep else None


def pyserial_schemes() -> list[str]:
    """Schemes the packages in ``serial.protocol_handler_packages`` have handler modules for."""
    schemes = set()
    for package in serial.protocol_handler_packages:
        try:
            path = importlib.import_module(package).__path__
        except (ImportError, AttributeError):
            continue
        schemes |= {m.name[len("protocol_"):] for m in pkgutil.iter_modules(path) if m.name.startswith("protocol_")}
    return sorted(schemes)


def use_handler(url: str) -> bool:
    """Make pyserial able to open ``url``; True when its scheme's handler comes from the entry-point group.

    A scheme pyserial knows is left to it; one it does not is looked up in ``pixelpen.serial_handlers``
    and its package appended to ``serial.protocol_handler_packages``.  An unknown scheme raises
    LinkError naming the known ones.
    """
    scheme = url_scheme(url)
    if scheme is None:
        return False
    package = serial_handlers().get(scheme)
    if package is not None:
        if package not in serial.protocol_handler_packages:
            serial.protocol_handler_packages.append(package)
        return True
    known = pyserial_schemes()
    if scheme not in known:
        schemes = ", ".join(f"{s}://" for s in sorted(set(known) | set(serial_handlers())))
        raise LinkError(f"cannot open serial port {url!r}: no handler for {scheme}://; known schemes: {schemes}")
    return False


def known_ports() -> list[str]:
    """Device paths of the serial ports the OS lists now (empty if listing fails)."""
    try:
        return sorted(p.device for p in list_ports.comports())
    except Exception:  # noqa: BLE001  (listing is best effort: a broken sysfs entry must not hide the real error)
        return []


NO_WRITE_TIMEOUT = ("rfc2217://",)
"""pyserial URL schemes whose ports refuse write timeouts (pyserial's rfc2217 raises NotImplementedError):
their writes go to a socket and block until sent; the Link's own deadlines still bound XOFF holds."""


class SerialLink(Link):
    """A Link over a pyserial port or URL, mapping its failures onto pixelpen's LinkError family."""

    def __init__(
        self,
        url: str,
        baudrate: int = 9600,
        flow: str = "none",
        timeout: float | None = 2.0,
        write_timeout: float | None = 10.0,
        clock: Clock | None = None,
        *,
        soft_xonxoff: bool | None = None,
        **port_options: Any,
    ) -> None:
        if flow not in FLOWS:
            raise LinkError(f"{url}: flow must be one of {', '.join(FLOWS)}, got {flow!r}")
        plugin = isinstance(url, str) and use_handler(url)
        self._port_takes_write_timeout = not (isinstance(url, str) and url.lower().startswith(NO_WRITE_TIMEOUT))
        if clock is not None and plugin:
            port_options["clock"] = clock
        try:
            port = serial.serial_for_url(
                url,
                baudrate=baudrate,
                rtscts=flow == "rtscts",
                xonxoff=flow == "xonxoff",
                timeout=0,
                write_timeout=write_timeout if self._port_takes_write_timeout else None,
                **port_options,
            )
        except PixelpenError:
            raise
        except (serial.SerialException, OSError, ValueError) as exc:
            ports = known_ports()
            raise LinkError(
                f"cannot open serial port {url!r}: {exc}; known ports: {', '.join(ports) or 'none found'}"
            ) from exc
        self.port = port
        """The underlying pyserial object (``port.sim_device`` for sim:// URLs)."""
        if clock is None:
            clock = getattr(port, "clock", None)
        super().__init__(url, timeout=timeout, write_timeout=write_timeout, clock=clock)
        self.soft_xonxoff = (flow == "xonxoff") if soft_xonxoff is None else soft_xonxoff
        """Honour XON/XOFF in software: an XOFF in the input holds writes until XON; both are taken out."""
        self._held_off = False
        self._port_timeout: float | None = 0
        self._port_write_timeout: float | None = write_timeout if self._port_takes_write_timeout else None

    @property
    def baudrate(self) -> int:
        """Line speed (for sim:// URLs the URL's ``baud`` wins)."""
        return int(self.port.baudrate)

    @property
    def flow(self) -> str:
        """Handshake in force: none, rtscts or xonxoff."""
        return "rtscts" if self.port.rtscts else "xonxoff" if self.port.xonxoff else "none"

    @property
    def held_off(self) -> bool:
        """True while an XOFF from the device holds writes (software flow control)."""
        return self._held_off

    # -- software flow control --------------------------------------------------------------

    def _write_window(self, deadline: float | None, limit: float | None, sent: int, total: int) -> int:
        """With software flow control: wait while XOFF holds writes, then let a short chunk go."""
        if not self.soft_xonxoff:
            return total - sent
        self._pull(0.0)
        while self._held_off:
            remaining = self._remaining(deadline)
            if remaining is not None and remaining <= 0:
                raise LinkTimeout(f"{self.name}: write held off by XOFF for {limit}s; sent {sent} of {total} bytes")
            self._pull(IDLE_POLL if remaining is None else min(IDLE_POLL, remaining))
        return min(total - sent, SOFT_FLOW_CHUNK)

    def _filter_input(self, data: bytes) -> bytes:
        """With software flow control: act on XON/XOFF and take them out of the input."""
        if not self.soft_xonxoff or (XON not in data and XOFF not in data):
            return data
        kept = bytearray()
        for b in data:
            if b == XOFF:
                self._held_off = True
            elif b == XON:
                self._held_off = False
            else:
                kept.append(b)
        return bytes(kept)

    # -- primitives -------------------------------------------------------------------------

    def _read_raw(self, wait: float | None) -> bytes:
        try:
            n = self.port.in_waiting
            if not n:
                self._set_timeout(wait)
                first = self.port.read(1)
                if not first:
                    return b""
                n = self.port.in_waiting
                return first + (self._read_now(n) if n else b"")
            return self._read_now(n)
        except (serial.SerialException, OSError) as exc:
            raise self._lost(exc) from exc

    def _read_now(self, n: int) -> bytes:
        self._set_timeout(0)
        return self.port.read(n)

    def _set_write_timeout(self, wait: float | None) -> None:
        """Give the port ``wait`` as its write timeout (ports that take none block until the bytes are out)."""
        if self._port_takes_write_timeout and wait != self._port_write_timeout:
            self.port.write_timeout = wait
            self._port_write_timeout = wait

    def _write_raw(self, data: bytes, wait: float | None) -> int:
        self._set_write_timeout(wait)
        try:
            n = self.port.write(data)
        except serial.SerialTimeoutException as exc:
            raise LinkTimeout(f"{self.name}: write timed out after {wait}s ({len(data)} bytes pending)") from exc
        except (serial.SerialException, OSError) as exc:
            raise self._lost(exc) from exc
        return len(data) if n is None else int(n)

    def _reset_output_raw(self) -> None:
        try:
            self.port.reset_output_buffer()
        except (serial.SerialException, OSError) as exc:
            raise self._lost(exc) from exc

    def _raw_in_waiting(self) -> int:
        try:
            return int(self.port.in_waiting)
        except (serial.SerialException, OSError) as exc:
            raise self._lost(exc) from exc

    def _flush_raw(self, wait: float | None) -> None:
        self._set_write_timeout(wait)
        try:
            self.port.flush()
        except serial.SerialTimeoutException as exc:
            raise LinkTimeout(f"{self.name}: flush timed out after {wait}s") from exc
        except (serial.SerialException, OSError) as exc:
            raise self._lost(exc) from exc

    def _reset_input_raw(self) -> None:
        try:
            self.port.reset_input_buffer()
        except (serial.SerialException, OSError) as exc:
            raise self._lost(exc) from exc

    def _close_raw(self) -> None:
        try:
            self.port.close()
        except (serial.SerialException, OSError):
            self._log.debug("%s: error while closing ignored (port already gone)", self.name)

    def _set_timeout(self, wait: float | None) -> None:
        if wait != self._port_timeout:
            self.port.timeout = wait
            self._port_timeout = wait

    def _lost(self, exc: BaseException) -> LinkError:
        if isinstance(exc, LinkError) and not isinstance(exc, Disconnected):
            return exc
        return Disconnected(f"{self.name}: device disconnected or port failed: {exc}")

    # -- line signals (SerialLines) ---------------------------------------------------------

    @property
    def cts(self) -> bool:
        """Clear To Send as the device drives it."""
        self._check_open()
        return bool(self.port.cts)

    @property
    def dsr(self) -> bool:
        """Data Set Ready as the device drives it."""
        self._check_open()
        return bool(self.port.dsr)

    @property
    def rts(self) -> bool:
        """Request To Send as the host drives it."""
        return bool(self.port.rts)

    @rts.setter
    def rts(self, value: bool) -> None:
        self._check_open()
        self.port.rts = bool(value)

    @property
    def dtr(self) -> bool:
        """Data Terminal Ready as the host drives it."""
        return bool(self.port.dtr)

    @dtr.setter
    def dtr(self, value: bool) -> None:
        self._check_open()
        self.port.dtr = bool(value)

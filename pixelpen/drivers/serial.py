"""SerialLink: a Link over any pyserial port or URL (``/dev/ttyUSB0``, ``COM3``, ``rfc2217://``, ``sim://`` ...).

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

Importing this module registers the ``sim://`` URL handler (:mod:`pixelpen.sim.transports.urlhandler`), so
``SerialLink("sim://hp7475a?paper=a4")`` talks to the simulator through the same code path as to a
real plotter.  With no ``clock`` given, a ``sim://`` link adopts the simulator's clock, so timeouts of
a ``speed=fast`` simulation pass in simulated time; a given ``clock`` is handed to the simulator.
"""

from __future__ import annotations

from typing import Any

import serial
from serial.tools import list_ports

from pixelpen.clock import Clock
from pixelpen.drivers.stream import Link
from pixelpen.errors import Disconnected, LinkError, LinkTimeout, PixelpenError
from pixelpen.sim.transports import urlhandler as _sim_urlhandler  # noqa: F401  (registers sim://)

FLOWS = ("none", "rtscts", "xonxoff")


def known_ports() -> list[str]:
    """Device paths of the serial ports the OS lists now (empty if listing fails)."""
    try:
        return sorted(p.device for p in list_ports.comports())
    except Exception:  # listing is best effort: a broken sysfs entry must not hide the real error
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
        is_sim = isinstance(url, str) and url.lower().startswith("sim://")
        self._port_takes_write_timeout = not (isinstance(url, str) and url.lower().startswith(NO_WRITE_TIMEOUT))
        if clock is not None and is_sim:
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
        super().__init__(
            url,
            timeout=timeout,
            write_timeout=write_timeout,
            clock=clock,
            soft_xonxoff=(flow == "xonxoff") if soft_xonxoff is None else soft_xonxoff,
        )
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

    # -- control lines ----------------------------------------------------------------------

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

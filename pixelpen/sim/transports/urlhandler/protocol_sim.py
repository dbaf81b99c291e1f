"""pyserial ``sim://MODEL?options`` handler: a Serial whose far end is a simulator behind a SimPort.

URL: ``sim://MODEL[?key=value&...]`` (options as in :mod:`pixelpen.urls`: percent-decoded, keys
case-insensitive, a key given twice is an error).  Transport options (``baud``, ``flow``,
``speed``, ``tx_buffer`` and the faults, see :mod:`pixelpen.sim.transports.port`) configure the line;
every other option goes to the simulator factory: ``sim://hp7475a?paper=a4&baud=9600&flow=xonxoff``.

The URL describes the simulated line, so its ``baud`` and ``flow`` win over the constructor's
``baudrate``/``rtscts``/``xonxoff`` (which are set to match); without them the constructor's values
are used, and changing ``baudrate``/``rtscts``/``xonxoff`` on the open port reconfigures the line.
Extra constructor keywords: ``clock=`` (the clock the simulator runs on; wins over ``speed``) and
``device=`` (a ready-made StreamDevice instead of the factory).  ``inter_byte_timeout`` is ignored.

Closing the port stops only a device it built: a ``device=`` passed in, or a named instance
(``id=NAME``, closed by :func:`pixelpen.sim.base.forget_simulator`), outlives the port, so a
reconnect to it finds the same device with its state.

Errors are pyserial's and pixelpen's at once: a dropped link raises :class:`SimDisconnected`
(a ``SerialException`` and a :class:`~pixelpen.errors.Disconnected`), a write that does not fit
before ``write_timeout`` raises :class:`SimTimeout` (``SerialTimeoutException`` + ``LinkTimeout``).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from serial.serialutil import PortNotOpenError, SerialBase, SerialException, SerialTimeoutException

from pixelpen.clock import Clock
from pixelpen.errors import Disconnected, LinkError, LinkTimeout, URLError
from pixelpen.sim.base import StreamDevice, simulator_models
from pixelpen.sim.transports.port import SimPort, open_sim_port
from pixelpen.urls import parse_url


class SimDisconnected(SerialException, Disconnected):
    """The simulated link dropped (pyserial's and pixelpen's exception at once)."""


class SimTimeout(SerialTimeoutException, LinkTimeout):
    """A simulated write or drain did not finish in time."""


class SimPortError(SerialException, LinkError):
    """Any other failure of the simulated port."""


def parse_sim_url(url: str) -> tuple[str, dict[str, str]]:
    """Split ``sim://MODEL?options`` into the model name and its options."""
    if not isinstance(url, str) or not url.lower().startswith("sim://"):
        raise URLError(f"expected a URL like 'sim://hp7475a?paper=a4', got {url!r}")
    parsed = parse_url("sim:" + url[len("sim://") :])
    model = parsed.target.strip("/")
    if not model or "/" in model:
        raise URLError(
            f"{url!r}: expected 'sim://MODEL[?options]' with one model name; known models: "
            f"{', '.join(simulator_models()) or 'none'}"
        )
    return model, dict(parsed.options)


@contextmanager
def _as_serial_errors() -> Iterator[None]:
    """Re-raise SimPort errors as exceptions pyserial users and pixelpen both catch."""
    try:
        yield
    except Disconnected as exc:
        raise SimDisconnected(str(exc)) from exc
    except LinkTimeout as exc:
        raise SimTimeout(str(exc)) from exc
    except LinkError as exc:
        raise SimPortError(str(exc)) from exc


class Serial(SerialBase):
    """A pyserial port whose far end is a simulated device (see the module docstring)."""

    def __init__(
        self, *args: Any, clock: Clock | None = None, device: StreamDevice | None = None, **kwargs: Any
    ) -> None:
        self._sim_clock = clock
        self._given_device = device
        self._owns_device = False
        self.sim_port: SimPort | None = None
        super().__init__(*args, **kwargs)

    # -- opening and configuration ------------------------------------------------------------

    def open(self) -> None:
        """Build the simulator and its SimPort from the URL in ``port``."""
        if self.is_open:  # type: ignore[has-type]
            raise SerialException("Port is already open.")
        if self._port is None:
            raise SerialException("Port must be configured before it can be used.")
        model, options = parse_sim_url(self._port)
        port = open_sim_port(model, options, clock=self._sim_clock, device=self._given_device, source=self._port)
        if "baud" in options:  # the URL's line settings win over the constructor's (the port read them already)
            self._baudrate = port.baud
        if "flow" in options:
            self._rtscts = port.flow == "rtscts"
            self._xonxoff = port.flow == "xonxoff"
            self._dsrdtr = False
        self.sim_port = port
        self._owns_device = self._given_device is None and "id" not in options
        try:
            self._reconfigure_port()
        except BaseException:
            port.close(close_device=self._owns_device)
            self.sim_port = None
            raise
        self.is_open = True
        port.rts, port.dtr = bool(self._rts_state), bool(self._dtr_state)

    def _flow(self) -> str:
        if self._rtscts and self._xonxoff:
            raise SerialException("sim:// ports take one handshake: rtscts or xonxoff, not both")
        return "rtscts" if self._rtscts else "xonxoff" if self._xonxoff else "none"

    def _reconfigure_port(self) -> None:
        """Apply baudrate and handshake settings to the simulated line."""
        if not isinstance(self._baudrate, int) or self._baudrate <= 0:
            raise ValueError(f"invalid baudrate: {self._baudrate!r}")
        if self.sim_port is not None:
            self.sim_port.configure(baud=self._baudrate, flow=self._flow())

    def close(self) -> None:
        """Close the port, and stop the simulator if the port built it (results stay readable via ``sim_device``)."""
        if self.is_open:
            self.is_open = False
            if self.sim_port is not None:
                self.sim_port.close(close_device=self._owns_device)

    @property
    def sim_device(self) -> StreamDevice:
        """The simulated device behind this port (for tests and previews)."""
        if self.sim_port is None:
            raise PortNotOpenError()
        return self.sim_port.device

    @property
    def clock(self) -> Clock:
        """The clock the simulated line and device run on."""
        if self.sim_port is None:
            raise PortNotOpenError()
        return self.sim_port.clock

    def _open_port(self) -> SimPort:
        if not self.is_open or self.sim_port is None:
            raise PortNotOpenError()
        return self.sim_port

    # -- data ------------------------------------------------------------------------------

    @property
    def in_waiting(self) -> int:
        """Bytes received and not read."""
        port = self._open_port()
        with _as_serial_errors():
            return port.in_waiting

    @property
    def out_waiting(self) -> int:
        """Bytes written and not yet on the wire."""
        port = self._open_port()
        with _as_serial_errors():
            return port.out_waiting

    def read(self, size: int = 1) -> bytes:
        """Read ``size`` bytes, or fewer when ``timeout`` passes (None: wait for all)."""
        port = self._open_port()
        data = bytearray()
        start = port.clock.now()
        with _as_serial_errors():
            while len(data) < size:
                remaining = None if self._timeout is None else max(0.0, start + self._timeout - port.clock.now())
                chunk = port.read(size - len(data), remaining)
                if not chunk:
                    break
                data += chunk
        return bytes(data)

    def write(self, data: bytes) -> int:
        """Queue ``data`` for the wire; SimTimeout if it does not all fit before ``write_timeout``."""
        port = self._open_port()
        payload = bytes(memoryview(data))
        with _as_serial_errors():
            n = port.write(payload, self._write_timeout)
        if n < len(payload):
            raise SimTimeout(f"Write timeout: {n} of {len(payload)} bytes queued")
        return n

    def flush(self) -> None:
        """Wait until every written byte is on the wire (bounded by ``write_timeout``)."""
        port = self._open_port()
        with _as_serial_errors():
            if not port.drain(self._write_timeout):
                raise SimTimeout(f"flush timed out after {self._write_timeout}s with {port.out_waiting} bytes unsent")

    def reset_input_buffer(self) -> None:
        """Discard received bytes."""
        port = self._open_port()
        with _as_serial_errors():
            port.reset_input()

    def reset_output_buffer(self) -> None:
        """Discard bytes not yet sent."""
        port = self._open_port()
        with _as_serial_errors():
            port.reset_output()

    # -- lines -----------------------------------------------------------------------------

    def _update_rts_state(self) -> None:
        if self.sim_port is not None:
            self.sim_port.rts = bool(self._rts_state)

    def _update_dtr_state(self) -> None:
        if self.sim_port is not None:
            self.sim_port.dtr = bool(self._dtr_state)

    def _update_break_state(self) -> None:
        """A break condition has no effect on the simulators."""

    @property
    def cts(self) -> bool:
        """Clear To Send: the device's handshake line."""
        return self._open_port().cts

    @property
    def dsr(self) -> bool:
        """Data Set Ready: the cable is connected."""
        return self._open_port().dsr

    @property
    def ri(self) -> bool:
        """Ring Indicator: never."""
        self._open_port()
        return False

    @property
    def cd(self) -> bool:
        """Carrier Detect: the cable is connected."""
        return self._open_port().dsr

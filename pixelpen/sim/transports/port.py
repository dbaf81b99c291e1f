"""SimPort: the host-facing end of a simulated device's cable: baud-rate pacing, handshakes, faults, counters.

A :class:`SimPort` plays the host's UART and the cable in front of a
:class:`~pixelpen.sim.base.StreamDevice`.  The pyserial ``sim://`` handler, the pty bridge and the
pyusb printer-class backend all reach their device through one.

Timing.  Every byte takes ``10 / baud`` seconds on the wire (8N1: start + 8 data + stop bits) in
each direction, measured on the device's clock.  Host bytes wait in a transmit buffer
(``tx_buffer`` bytes, like the OS's tty buffer: a write blocks while it is full) and go out one
after another; device answers arrive at the host the same way.  With a
:class:`~pixelpen.clock.SimulatedClock` (``speed=fast``) a host that waits makes the clock jump to
the next thing that happens (next byte boundary, next device event, or its deadline), so a
ten-minute plot streams in milliseconds with exactly the same byte timing.

Flow control (``flow``) is what the host side obeys:

* ``none``: bytes go out back to back whatever the device's state (it overflows as the real one
  would);
* ``rtscts``: before each byte the transmitter samples the device's handshake line
  (``ready_to_receive``, wired to CTS) and holds while it is low;
* ``xonxoff``: the device sends XOFF (0x13) / XON (0x11) itself; on arrival they stop and restart
  the transmitter and are removed from the host's input, as a tty with IXON does.

Transport options (``baud``, ``flow``, ``speed``, ``tx_buffer``, ``out`` and the faults by host byte
count) are declared once as ``TRANSPORT_OPTIONS`` in :mod:`pixelpen.sim.transports.options`
(``pixelpen devices`` prints their help); a ``sim://`` URL splits them off and gives every other
option to the simulator factory.  Transport faults (``drop_after``, ``stall_after``, ``corrupt_at``)
act on the line; device faults (``power_loss_after``, ``paper_lever_after``, ``pause_after``) call
``device.inject`` once that many host bytes of this port were delivered.  The SimPort counts them,
not the device (``inject(fault, at=N)``): a device reached again by ``id=`` has counted the bytes of
earlier ports, and a fault a port did not reach (it dropped or closed first) must not fire on the next.
The default ``baud`` is the device's own line: its ``default_baud`` attribute when it has one (an EBB is
USB CDC and ignores the line coding: 12 Mbit/s, USB full speed; GRBL 115200), else 9600.

Counters (:meth:`SimPort.stats`): bytes each way, seconds each line was busy, seconds the
transmitter had data but was held off, and the elapsed time, from which a benchmark computes link
utilisation.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Final

from pixelpen.clock import REAL_CLOCK, Clock, SimulatedClock
from pixelpen.errors import ConfigError, Disconnected, LinkError, LinkTimeout, URLError
from pixelpen.sim.base import Fault, StreamDevice, create_simulator, is_stream_device, reached_through
from pixelpen.sim.transports.options import (  # re-exported: these lived here before the options had a module
    DEFAULT_BAUD,
    DEVICE_FAULTS,
    FLOWS,
    SPEEDS,
    TRANSPORT_OPTIONS,
    Faults,
    TransportOptions,
    line_baud,
    split_options,
)

__all__ = [
    "DEFAULT_BAUD", "DEVICE_FAULTS", "FLOWS", "SPEEDS", "TRANSPORT_OPTIONS", "Faults", "LinkStats", "SimPort",
    "TransportOptions", "line_baud", "open_sim_port", "split_options",
]

XON: Final = 0x11
XOFF: Final = 0x13
BITS_PER_BYTE: Final = 10
"""8N1 framing: one start bit, eight data bits, one stop bit."""

_REAL_MIN_SLEEP = 0.001  # real-time waits sleep at least this long (events between are caught up in order)
_REAL_MAX_SLEEP = 0.05  # ... and at most this long, so other threads' writes are noticed


@dataclass(frozen=True)
class LinkStats:
    """Traffic counters of a SimPort (times in clock seconds)."""

    bytes_sent: int
    """Host bytes that went out on the wire."""
    bytes_received: int
    """Device bytes that arrived at the host (XON/XOFF included)."""
    tx_busy: float
    """Seconds the host-to-device line carried a byte."""
    rx_busy: float
    """Seconds the device-to-host line carried a byte."""
    held_off: float
    """Seconds the transmitter had bytes to send but was held (handshake or stall)."""
    elapsed: float
    """Seconds since the port opened."""

    @property
    def utilisation(self) -> float:
        """Fraction of the elapsed time the host-to-device line was busy."""
        return self.tx_busy / self.elapsed if self.elapsed > 0 else 0.0


class SimPort:
    """The host end of a StreamDevice's serial line: paced, handshaken, fault-injecting (see module doc)."""

    def __init__(
        self,
        device: StreamDevice,
        *,
        baud: int | None = None,
        flow: str = "none",
        faults: Faults | None = None,
        tx_buffer: int = 4096,
        clock: Clock | None = None,
        out: str | None = None,
    ) -> None:
        if tx_buffer <= 0:
            raise LinkError(f"SimPort: tx_buffer must be positive, got {tx_buffer}")
        if out is not None and not callable(getattr(device, "save_paper", None)):
            raise LinkError(f"SimPort: out={out!r}, but {getattr(device, 'model', 'the device')} has no paper to save")
        self.device = device
        self.out = out
        """File the device's paper is written to when the port closes (None: not saved)."""
        self.clock: Clock = clock if clock is not None else getattr(device, "clock", REAL_CLOCK)
        self.faults = faults or Faults()
        self.tx_buffer = tx_buffer
        self.rts = True
        """Host RTS line (stored; the device protocol has no input for it)."""
        self.dtr = True
        """Host DTR line (stored; the device protocol has no input for it)."""
        self._lock = threading.RLock()
        self._simulated = isinstance(self.clock, SimulatedClock)
        self._t = self.clock.now()
        self._opened_at = self._t
        self._set_line(line_baud(device, baud), flow)
        # host -> device
        self._txq = bytearray()
        self._tx_byte: int | None = None
        self._tx_done_at = 0.0
        self._tx_start_at: float | None = None
        self._line_free_at = self._t
        self._held_since: float | None = None
        # device -> host
        self._rx_line = bytearray()
        self._rx_next_at = 0.0
        self._inbuf = bytearray()
        self._xoff = False
        # state and counters
        self._sent = 0
        self._received = 0
        self._tx_busy = 0.0
        self._rx_busy = 0.0
        self._held_time = 0.0
        self._dropped = False
        self._closed = False
        self._injections = self.faults.device_faults()
        self.device.advance_to(self._t)
        self._dev_next = self.device.next_event_time()
        self._after_count()

    # -- configuration ----------------------------------------------------------------------

    @property
    def baud(self) -> int:
        """Line speed in bits per second."""
        return self._baud

    @property
    def flow(self) -> str:
        """Host-side handshake: none, rtscts or xonxoff."""
        return self._flow

    def configure(self, *, baud: int | None = None, flow: str | None = None) -> None:
        """Change line speed or handshake (bytes already on the wire keep their timing)."""
        with self._lock:
            self._run_until(self.clock.now())
            self._set_line(baud or self._baud, flow or self._flow)

    def _set_line(self, baud: int, flow: str) -> None:
        if flow not in FLOWS:
            raise LinkError(f"SimPort: flow must be one of {', '.join(FLOWS)}, got {flow!r}")
        if baud <= 0:
            raise LinkError(f"SimPort: baud must be positive, got {baud}")
        self._baud, self._flow = int(baud), flow
        self.byte_time = BITS_PER_BYTE / self._baud
        if flow != "xonxoff":
            self._xoff = False

    # -- host operations --------------------------------------------------------------------

    def write(self, data: bytes, timeout: float | None = None) -> int:
        """Queue host bytes for the wire, blocking while the transmit buffer is full; return how many went in.

        ``timeout`` None waits until all fit; 0 takes what fits now.
        """
        data = bytes(data)
        accepted = 0

        def put() -> bool:
            nonlocal accepted
            space = self.tx_buffer - len(self._txq)
            if space > 0 and accepted < len(data):
                chunk = data[accepted : accepted + space]
                self._txq += chunk
                accepted += len(chunk)
                if self._tx_byte is None and self._tx_start_at is None and self._held_since is None:
                    self._tx_start_at = max(self._t, self._line_free_at)
            return accepted == len(data)

        self._wait_for(put, timeout)
        return accepted

    def read(self, size: int = 1, timeout: float | None = 0.0) -> bytes:
        """Return up to ``size`` bytes that arrived, waiting up to ``timeout`` for the first (None: forever)."""
        if not self._wait_for(lambda: bool(self._inbuf), timeout):
            return b""
        with self._lock:
            out = bytes(self._inbuf[:size])
            del self._inbuf[:size]
            return out

    def drain(self, timeout: float | None = None) -> bool:
        """Wait until every queued host byte went out on the wire; False if ``timeout`` passed first."""
        return self._wait_for(lambda: not self._txq and self._tx_byte is None, timeout)

    def poll(self) -> None:
        """Catch up with the clock: move bytes and run the device up to now."""
        with self._lock:
            self._run_until(self.clock.now())

    @property
    def in_waiting(self) -> int:
        """Device bytes that arrived at the host and were not read."""
        with self._lock:
            self._run_until(self.clock.now())
            self._check_alive()
            return len(self._inbuf)

    @property
    def out_waiting(self) -> int:
        """Host bytes not yet on the wire (queued or in flight)."""
        with self._lock:
            self._run_until(self.clock.now())
            self._check_alive()
            return len(self._txq) + (self._tx_byte is not None)

    @property
    def tx_space(self) -> int:
        """Bytes the transmit buffer can take now."""
        with self._lock:
            self._run_until(self.clock.now())
            return max(0, self.tx_buffer - len(self._txq))

    def reset_input(self) -> None:
        """Discard device bytes that arrived and were not read."""
        with self._lock:
            self._run_until(self.clock.now())
            self._inbuf.clear()

    def reset_output(self) -> None:
        """Discard host bytes still queued (a byte already on the wire completes)."""
        with self._lock:
            self._run_until(self.clock.now())
            self._txq.clear()
            if self._tx_byte is None:
                self._tx_start_at = None
                self._end_hold(self._t)

    @property
    def cts(self) -> bool:
        """Clear To Send: the device's handshake line (False once the link dropped)."""
        with self._lock:
            self._run_until(self.clock.now())
            return not self._dropped and not self._closed and bool(self.device.ready_to_receive)

    @property
    def dsr(self) -> bool:
        """Data Set Ready: True while the cable is connected."""
        return not self._dropped and not self._closed

    @property
    def dropped(self) -> bool:
        """True once the ``drop_after`` fault cut the link."""
        return self._dropped

    @property
    def closed(self) -> bool:
        """True once ``close()`` was called."""
        return self._closed

    def stats(self) -> LinkStats:
        """A snapshot of the traffic counters."""
        with self._lock:
            self._run_until(self.clock.now())
            held = self._held_time + (self._t - self._held_since if self._held_since is not None else 0.0)
            return LinkStats(
                bytes_sent=self._sent,
                bytes_received=self._received,
                tx_busy=self._tx_busy,
                rx_busy=self._rx_busy,
                held_off=held,
                elapsed=self._t - self._opened_at,
            )

    def next_event_time(self) -> float | None:
        """Clock time of the next byte boundary or device event (None: nothing will happen by itself)."""
        with self._lock:
            if not self._closed:
                self._dev_next = self.device.next_event_time()
            return self._next_event()

    def close(self, close_device: bool = True) -> None:
        """Stop the port (and the device, whose results stay readable), saving the paper to ``out``; idempotent."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            try:
                self.save_out()
            finally:
                if close_device:
                    self.device.close()

    def save_out(self) -> None:
        """Write the device's paper to ``out`` as it stands now (nothing when no ``out`` was given)."""
        if self.out is not None:
            with self._lock:
                try:
                    self.device.save_paper(self.out)  # type: ignore[attr-defined]
                except OSError as exc:
                    raise ConfigError(f"out={self.out}: cannot write the paper: {exc.strerror or exc}") from None

    def take_pending(self) -> bytes:
        """Everything the device said that the host has not read, arrived or still on the line, at once."""
        with self._lock:
            self._run_until(self.clock.now())
            self._collect()
            out = bytes(self._inbuf) + bytes(self._rx_line)
            self._inbuf.clear()
            self._rx_line.clear()
            return out

    def host_opened(self) -> None:
        """A program opened the port and raised DTR: a device with ``resets_on_dtr`` (an Arduino) reboots."""
        with self._lock:
            self._run_until(self.clock.now())
            if getattr(self.device, "resets_on_dtr", False):
                self.device.inject(Fault.RESET)
                self._dev_next = self.device.next_event_time()

    # -- waiting ----------------------------------------------------------------------------

    def _wait_for(self, ready: Callable[[], bool], timeout: float | None) -> bool:
        """Let clock time pass (jumping when simulated) until ``ready()`` or the timeout; raise if the link died."""
        deadline = None if timeout is None or math.isinf(timeout) else self.clock.now() + timeout

        def done() -> bool:
            return self._dropped or ready()

        while True:
            with self._lock:
                now = self.clock.now()
                self._run_until(now)
                self._check_alive()
                if ready():
                    return True
                if deadline is not None and now >= deadline:
                    return False
                if self._simulated:
                    # run the simulation ahead until ready (or the deadline), then move the clock there
                    hit = self._run_until(math.inf if deadline is None else deadline, done)
                    end = hit if hit is not None else deadline
                    if end is None:
                        raise LinkTimeout(
                            f"{self.device.model}: waiting forever: the simulated line and device are idle "
                            "and no timeout was given"
                        )
                    self.clock.advance(end - now)  # type: ignore[attr-defined]
                    continue
                nxt = self._next_event()
            target = deadline if nxt is None else (nxt if deadline is None else min(nxt, deadline))
            pause = _REAL_MAX_SLEEP if target is None else target - now
            self.clock.sleep(min(max(pause, _REAL_MIN_SLEEP), _REAL_MAX_SLEEP))

    def _check_alive(self) -> None:
        if self._closed:
            raise LinkError(f"{self.device.model}: simulated port is closed")
        if self._dropped:
            raise Disconnected(
                f"{self.device.model}: link dropped after {self._sent} host bytes (drop_after={self.faults.drop_after})"
            )

    # -- the event loop ---------------------------------------------------------------------

    def _next_event(self) -> float | None:
        e = self._tx_done_at if self._tx_byte is not None else self._tx_start_at
        if self._rx_line and (e is None or self._rx_next_at < e):
            e = self._rx_next_at
        dev = self._dev_next
        if dev is not None and dev > self._t and (e is None or dev < e):
            e = dev
        return e

    def _run_until(self, t: float, until: Callable[[], bool] | None = None) -> float | None:
        """Process every byte boundary and device event up to clock time ``t``, in time order.

        With ``until``, stop after the first event that makes it true and return that event's time.
        """
        if self._closed or t < self._t:
            return None
        self._dev_next = self.device.next_event_time()  # the device may have been touched from outside
        while True:
            e = self._next_event()
            if e is None or e > t:
                break
            if e > self._t:
                self._t = e
                self.device.advance_to(e)
                self._collect()
            if self._rx_line and self._rx_next_at <= e:
                self._arrive()
            elif self._tx_byte is not None and self._tx_done_at <= e:
                self._complete()
            elif self._tx_byte is None and self._tx_start_at is not None and self._tx_start_at <= e:
                self._tx_start_at = None
                self._try_start(e)
            if self._held_since is not None and self._tx_byte is None:
                self._try_start(e)
            if until is not None and until():
                return e
        if not math.isinf(t):
            self._t = t
            self.device.advance_to(t)
            self._collect()
            if self._held_since is not None and self._tx_byte is None:
                self._try_start(t)
        return None

    def _collect(self) -> None:
        """Put what the device sent into the line towards the host, stamped now."""
        out = self.device.take_output()
        if out and not self._dropped:
            if not self._rx_line:
                self._rx_next_at = self._t + self.byte_time
            self._rx_line += out
        self._dev_next = self.device.next_event_time()

    def _arrive(self) -> None:
        b = self._rx_line[0]
        del self._rx_line[0]
        self._received += 1
        self._rx_busy += self.byte_time
        if self._flow == "xonxoff" and b in (XON, XOFF):
            self._xoff = b == XOFF
        else:
            self._inbuf.append(b)
        if self._rx_line:
            self._rx_next_at += self.byte_time

    def _may_send(self) -> bool:
        if self._dropped:
            return False
        if self.faults.stall_after is not None and self._sent >= self.faults.stall_after:
            return False
        if self._flow == "rtscts":
            return bool(self.device.ready_to_receive)
        if self._flow == "xonxoff":
            return not self._xoff
        return True

    def _try_start(self, s: float) -> None:
        if not self._txq or self._tx_byte is not None:
            self._end_hold(s)
            return
        if not self._may_send():
            if self._held_since is None:
                self._held_since = s
            return
        self._end_hold(s)
        self._tx_byte = self._txq[0]
        del self._txq[0]
        self._tx_done_at = s + self.byte_time

    def _end_hold(self, s: float) -> None:
        if self._held_since is not None:
            self._held_time += s - self._held_since
            self._held_since = None

    def _complete(self) -> None:
        b = self._tx_byte
        assert b is not None
        if self.faults.corrupt_at == self._sent:
            b ^= 0xFF
        self._tx_byte = None
        self._line_free_at = self._tx_done_at
        self.device.receive(bytes((b,)))
        self._collect()
        self._sent += 1
        self._tx_busy += self.byte_time
        self._after_count()
        self._try_start(self._t)

    def _after_count(self) -> None:
        """Fire the faults due at the current host byte count."""
        while self._injections and self._injections[0][0] <= self._sent:
            _, fault = self._injections.pop(0)
            self.device.inject(fault)
            self._collect()
        if self.faults.drop_after is not None and self._sent >= self.faults.drop_after and not self._dropped:
            self._dropped = True
            self._txq.clear()
            self._rx_line.clear()
            self._end_hold(self._t)


def open_sim_port(
    model: str,
    options: Mapping[str, str],
    *,
    clock: Clock | None = None,
    device: StreamDevice | None = None,
    source: str | None = None,
) -> SimPort:
    """Build ``model``'s simulator (or take ``device``) behind a SimPort configured by URL ``options``.

    Transport options configure the port; the rest go to ``create_simulator(model, clock=..., **rest)``.
    An explicit ``clock`` wins over ``speed``.
    """
    transport, device_options = split_options(options, source or f"sim://{model}")
    if "clock" in device_options:
        raise URLError(f"{source or model}: unknown option 'clock' (set the simulator's time with speed=fast|real)")
    if device is None:
        device = create_simulator(model, clock=clock or transport.make_clock(), **device_options)
        if not is_stream_device(device):
            device.close()
            raise URLError(f"{source or model}: the {model} simulator is reached through {reached_through(device)}, "
                           "not a serial port")
    elif device_options:
        raise URLError(
            f"{source or model}: option(s) {', '.join(sorted(device_options))} are for a simulator factory, "
            "but a ready-made device was given"
        )
    return SimPort(
        device,
        baud=transport.baud,
        flow=transport.flow,
        faults=transport.faults,
        tx_buffer=transport.tx_buffer,
        clock=clock or getattr(device, "clock", None),
        out=transport.out,
    )

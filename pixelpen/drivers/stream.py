"""The one byte-moving interface every device driver uses: Link, with timeouts on an injectable clock.

A transport subclasses :class:`Link` and supplies four primitives (``_read_raw``, ``_write_raw``,
``_raw_in_waiting``, ``_close_raw``); the base class turns them into the driver-facing contract:

* ``write(data)`` sends every byte or raises (:class:`~pixelpen.errors.LinkTimeout` when the write
  timeout passes, :class:`~pixelpen.errors.Disconnected` when the device went away);
* ``read(size, timeout)`` returns 1..size bytes, or ``b""`` only when the timeout passed;
* ``read_until(terminator, timeout, max_size)`` returns one reply including its terminator, raises
  LinkTimeout naming the bytes received so far, and LinkError when ``max_size`` bytes came without
  the terminator (those bytes are consumed and carried on the exception as ``partial``);
* ``flush``, ``reset_input``, ``reset_output``, ``in_waiting``, ``close`` (and ``with``).

A stream only moves bytes: serial line signals (CTS/DSR/RTS/DTR) and software XON/XOFF flow control
belong to :class:`~pixelpen.drivers.serial.SerialLink`, which uses two hooks the base offers:
``_write_window`` (how many bytes may go now, waiting while the device holds writes) and
``_filter_input`` (bytes taken out of the input, such as XON/XOFF).  ``held_off`` tells a driver
whether the device's flow control holds writes now; a stream without flow control never is.
The panel bus and the HID report link are other kinds of transport (:mod:`pixelpen.drivers.bus`,
:mod:`pixelpen.drivers.reports`).

Timeouts: ``None`` means the link's default (``timeout`` / ``write_timeout``), ``0`` polls, and
``math.inf`` (or a default of None) waits without limit.  Every wait is measured on ``self.clock``,
so a link on a SimulatedClock times out in simulated time.  Wire traffic is logged at DEBUG on the
logger of the transport's module (``pixelpen.drivers.serial`` ...) as hex plus printable text.
"""

from __future__ import annotations

import logging
import math
from types import TracebackType
from typing import TypeVar

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.errors import InvalidArgument, LinkError, LinkTimeout

_L = TypeVar("_L", bound="Link")
IDLE_POLL = 0.01
"""Clock seconds a wait with no limit lets pass between two looks (a transport that returned early)."""


def printable(data: bytes) -> str:
    """Bytes as text: 0x20..0x7e as themselves, every other byte as ``.``."""
    return "".join(chr(b) if 0x20 <= b < 0x7F else "." for b in data)


def format_bytes(data: bytes, limit: int = 96) -> str:
    """Render bytes as hex plus printable text (``49 4e 3b |IN;|``), cut after ``limit`` bytes."""
    shown = data[:limit]
    text = printable(shown)
    more = f" ... (+{len(data) - limit} bytes)" if len(data) > limit else ""
    return f"{shown.hex(' ')} |{text}|{more}"


class Link:
    """Base of every transport: bytes in and out with timeouts measured on an injectable clock."""

    def __init__(
        self,
        name: str,
        *,
        timeout: float | None = 2.0,
        write_timeout: float | None = 10.0,
        clock: Clock | None = None,
    ) -> None:
        self.name = name
        self.timeout = timeout
        self.write_timeout = write_timeout
        self.clock: Clock = clock if clock is not None else REAL_CLOCK
        self._rx = bytearray()
        self._closed = False
        self._log = logging.getLogger(type(self).__module__)

    # -- primitives a transport supplies -------------------------------------------------------

    def _read_raw(self, wait: float | None) -> bytes:
        """Return bytes the device sent, waiting at most ``wait`` clock seconds for the first (None: forever)."""
        raise NotImplementedError

    def _write_raw(self, data: bytes, wait: float | None) -> int:
        """Send a prefix of ``data`` within ``wait`` clock seconds; return how many bytes went."""
        raise NotImplementedError

    def _raw_in_waiting(self) -> int:
        """Bytes the transport holds that ``_read_raw`` would return at once."""
        raise NotImplementedError

    def _close_raw(self) -> None:
        """Release the transport (called once)."""
        raise NotImplementedError

    def _flush_raw(self, wait: float | None) -> None:
        """Wait until written bytes have left the host (default: nothing is buffered)."""

    def _reset_input_raw(self) -> None:
        """Discard input the transport itself buffers (default: the base buffer is all there is)."""

    def _reset_output_raw(self) -> None:
        """Discard output the transport still holds unsent (default: it holds none)."""

    def _write_window(self, deadline: float | None, limit: float | None, sent: int, total: int) -> int:
        """How many of the ``total - sent`` bytes left may go now; flow control waits here until ``deadline``.

        ``limit`` is the write timeout in force (for the error message); the default lets every byte go.
        """
        return total - sent

    def _filter_input(self, data: bytes) -> bytes:
        """Bytes that arrived, less those the transport acts on itself (default: all are data)."""
        return data

    # -- the driver-facing contract ------------------------------------------------------------

    @property
    def closed(self) -> bool:
        """True once ``close()`` was called."""
        return self._closed

    @property
    def held_off(self) -> bool:
        """True while the device's flow control holds writes (a stream without flow control: never)."""
        return False

    def write(self, data: bytes, timeout: float | None = None) -> None:
        """Send all of ``data`` (LinkTimeout if ``timeout``/``write_timeout`` passes first)."""
        self._check_open()
        data = bytes(data)
        if not data:
            return
        limit = self.write_timeout if timeout is None else timeout
        deadline = self._deadline(limit)
        if self._log.isEnabledFor(logging.DEBUG):
            self._log.debug("%s > %s", self.name, format_bytes(data))
        sent = 0
        while sent < len(data):
            end = sent + self._write_window(deadline, limit, sent, len(data))
            remaining = self._remaining(deadline)
            if remaining is not None and remaining <= 0:
                raise LinkTimeout(f"{self.name}: write timed out after {limit}s; sent {sent} of {len(data)} bytes")
            started = self.clock.now()
            n = self._write_raw(data[sent:end], remaining)
            sent += n
            if n == 0:
                self._let_pass(started, remaining)

    def read(self, size: int = 1, timeout: float | None = None) -> bytes:
        """Return 1..``size`` bytes as soon as any arrive; ``b""`` only when ``timeout`` passed."""
        self._check_open()
        if size < 1:
            raise InvalidArgument(f"read size must be at least 1, got {size}")
        limit = self.timeout if timeout is None else timeout
        deadline = self._deadline(limit)
        if not self._rx:
            self._pull(0.0)
        while not self._rx:
            remaining = self._remaining(deadline)
            if remaining is not None and remaining <= 0:
                return b""
            self._pull(remaining)
        return self._take(min(size, len(self._rx)))

    def read_until(self, terminator: bytes = b"\r", timeout: float | None = None, max_size: int = 4096) -> bytes:
        """Return bytes up to and including ``terminator`` (LinkTimeout, or LinkError past ``max_size``)."""
        self._check_open()
        if not terminator:
            raise InvalidArgument("read_until needs a non-empty terminator")
        limit = self.timeout if timeout is None else timeout
        deadline = self._deadline(limit)
        searched = 0
        self._pull(0.0)
        while True:
            at = self._rx.find(terminator, searched)
            if at >= 0 and at + len(terminator) <= max_size:
                return self._take(at + len(terminator))
            if at >= 0 or len(self._rx) >= max_size:
                partial = self._take(max_size)
                exc = LinkError(
                    f"{self.name}: no {terminator!r} within {max_size} bytes (reply too long or garbled); "
                    f"received {format_bytes(partial, 48)}"
                )
                exc.partial = partial  # type: ignore[attr-defined]
                raise exc
            searched = max(0, len(self._rx) - len(terminator) + 1)
            remaining = self._remaining(deadline)
            if remaining is not None and remaining <= 0:
                exc = LinkTimeout(
                    f"{self.name}: no {terminator!r} within {limit}s; received so far "
                    f"{format_bytes(bytes(self._rx), 48) if self._rx else 'nothing'}"
                )
                exc.partial = bytes(self._rx)  # type: ignore[attr-defined]
                raise exc
            self._pull(remaining)

    @property
    def in_waiting(self) -> int:
        """Bytes that ``read`` would return without waiting."""
        self._check_open()
        return len(self._rx) + self._raw_in_waiting()

    def flush(self, timeout: float | None = None) -> None:
        """Wait until every written byte has left the host (bounded by the write timeout)."""
        self._check_open()
        limit = self.write_timeout if timeout is None else timeout
        self._flush_raw(None if limit is None or math.isinf(limit) else limit)

    def reset_output(self) -> None:
        """Discard bytes written but not yet sent, so that the next write (a stop command) goes out first."""
        self._check_open()
        self._reset_output_raw()

    def reset_input(self) -> None:
        """Discard every byte received and not yet read."""
        self._check_open()
        self._rx.clear()
        self._reset_input_raw()
        while self._raw_in_waiting():
            if not self._read_raw(0.0):
                break

    def close(self) -> None:
        """Release the transport; calling it again does nothing."""
        if not self._closed:
            self._closed = True
            self._close_raw()

    def __enter__(self: _L) -> _L:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name}{' closed' if self._closed else ''}>"

    # -- helpers -------------------------------------------------------------------------------

    def _check_open(self) -> None:
        if self._closed:
            raise LinkError(f"{self.name}: link is closed")

    def _deadline(self, limit: float | None) -> float | None:
        """Clock time at which a wait of ``limit`` seconds ends (None or infinity: never)."""
        return None if limit is None or math.isinf(limit) else self.clock.now() + limit

    def _remaining(self, deadline: float | None) -> float | None:
        return None if deadline is None else deadline - self.clock.now()

    def _let_pass(self, started: float, wait: float | None) -> None:
        """Make sure ``wait`` clock seconds passed since ``started`` (a transport that returned early)."""
        if wait is None:
            wait = IDLE_POLL
        rest = started + wait - self.clock.now()
        if rest > 0:
            self.clock.sleep(rest)

    def _pull(self, wait: float | None) -> None:
        """Move what the transport has (waiting up to ``wait``) into the input buffer, through ``_filter_input``."""
        started = self.clock.now()
        data = self._read_raw(wait)
        if not data:
            if wait is None or wait > 0:
                self._let_pass(started, wait)
            return
        if self._log.isEnabledFor(logging.DEBUG):
            self._log.debug("%s < %s", self.name, format_bytes(data))
        self._rx += self._filter_input(data)

    def _take(self, n: int) -> bytes:
        out = bytes(self._rx[:n])
        del self._rx[:n]
        return out

"""The panel bus: what a framebuffer panel's driver talks through (command and data bytes, D/C, chip select, reset).

After luma.core's serial interface: a driver calls ``bus.command(0x2A)``, ``bus.data(b"\\x00\\x00\\x00\\xef")``
and ``bus.data(pixels)`` and never sees which wire carries them.  Implementations: ``drivers.spi.SpiBus``
(Linux spidev), ``drivers.i2c.I2CBus`` (Linux i2c-dev or any smbus2-like adapter), the FT232H and MCP2221
bridges, and the recording and replay buses.

* ``command(*cmd)`` sends ALL its bytes as command bytes: on SPI one chip-select frame with D/C low
  throughout (SSD1306 parameters are command bytes), on I2C one transaction after control byte 0x00.
  A MIPI-DCS driver therefore sends ``command(0x2A)`` and then its parameters with ``data``.
* ``data(buf)`` sends bytes with D/C high (I2C: control byte 0x40), any length: the bus splits it into
  frames of at most ``max_transfer`` bytes itself (an I2C chunk repeats the control byte), so drivers
  never chunk.  Chip select is asserted for each frame and released after it.
* I2C (:class:`I2CPanelBus`): every call is a write transaction to ``address`` whose first byte is a
  control byte, :data:`I2C_COMMAND` or :data:`I2C_DATA`, as the SSD1306/SH1106 datasheets number them;
  bit 7 is Co (:data:`I2C_CONTINUATION`: one byte, then another control byte); the bus sends whole
  streams with Co clear.  An unacknowledged address raises :class:`~pixelpen.errors.LinkError`.
* ``max_transfer``: the most bytes one transfer moves (spidev's ``bufsiz``, 4096 by default; an I2C
  adapter's message size).  ``kind`` is ``"spi"`` or ``"i2c"``; ``clock_hz`` the configured bus clock
  (the bandwidth estimator's and the traces' figure); ``bytes_sent`` and ``transfers`` count what the
  host put on the wire (command, data and I2C control bytes; frames or transactions).
* ``reset(recovery)`` pulses the reset line (active low, :data:`RESET_PULSE`) where one is wired, then
  waits ``recovery`` seconds on the bus's clock; without a reset line it does nothing and a driver sends
  its software reset command.  Any OS or library fault is a ``LinkError`` naming the bus and operation;
  a closed bus refuses every call but ``close`` with ``LinkError``.

Wire time (:func:`spi_wire_seconds`, :func:`i2c_wire_seconds`) is the one model the bandwidth estimator,
the simulated transports and the panel simulators share: SPI moves a byte in 8 clocks; I2C in 9 (8 bits
and the ACK) plus 11 per transaction (START, the address byte with its ACK, STOP) and 10 per repeated
START (Sr and another address byte).  Gaps between transfers are not counted (panels.md §4).
:class:`FramedBus` is the implementations' common part: counters, the closed guard, the reset line,
command checks, fault wording and a close that releases everything even when one release fails.

The simulator side of the same wire is :class:`pixelpen.sim.base.BusDevice`.
"""

from __future__ import annotations

import abc
import contextlib
import math
from collections.abc import Callable, Iterable
from typing import ClassVar, Final, Protocol, runtime_checkable

from pixelpen.clock import Clock
from pixelpen.drivers.gpio import OutputLine, pulse_reset
from pixelpen.errors import ConfigError, InvalidArgument, InvalidArgumentType, LinkError

I2C_COMMAND: Final = 0x00
"""I2C control byte: command bytes follow (Co clear, D/C# clear)."""
I2C_DATA: Final = 0x40
"""I2C control byte: data bytes (display RAM) follow (Co clear, D/C# set)."""
I2C_CONTINUATION: Final = 0x80
"""Co, bit 7 of an I2C control byte: set, one byte follows and then another control byte."""
DEFAULT_MAX_TRANSFER: Final = 4096
"""Bytes per transfer when a bus names no limit (Linux spidev's default ``bufsiz``)."""
RESET_PULSE: Final = 10e-6
"""Seconds the reset line is held low: the longest minimum of the supported controllers (ST7789/ILI9341 tRW 10 µs)."""
RESET_RECOVERY: Final = 0.120
"""Default seconds to wait after the reset pulse: ST7789/ILI9341 tRT (120 ms, reset in sleep-out mode)."""
SPI_CLOCKS_PER_BYTE: Final = 8
"""SPI clocks per byte."""
I2C_CLOCKS_PER_BYTE: Final = 9
"""I2C clocks per byte: 8 data bits and the acknowledge."""
I2C_TRANSACTION_CLOCKS: Final = 11
"""I2C clocks per transaction beyond its payload: START (1), the address byte and its ACK (9), STOP (1)."""
I2C_RESTART_CLOCKS: Final = 10
"""I2C clocks of a repeated START within a transaction: Sr (1) and the next message's address byte (9)."""


def _positive_hz(clock_hz: float) -> float:
    if not 0 < clock_hz < math.inf:
        raise InvalidArgument(f"bus clock must be a number of Hz > 0, got {clock_hz!r}")
    return clock_hz


def spi_wire_seconds(nbytes: int, clock_hz: float) -> float:
    """Seconds ``nbytes`` take on SPI at ``clock_hz``: 8 clocks a byte (chip-select and D/C gaps not counted)."""
    return SPI_CLOCKS_PER_BYTE * nbytes / _positive_hz(clock_hz)


def i2c_wire_seconds(payload_bytes: int, clock_hz: float, transactions: int = 1, *, restarts: int = 0) -> float:
    """Seconds on I2C at ``clock_hz``: 9 clocks a payload byte, 11 a transaction, 10 a repeated START.

    ``payload_bytes`` counts what follows the address bytes (control bytes included): an SSD1306 frame
    ``[00 21 00 7F 22 00 07]``, ``[40 + 1024 bytes]`` is 1,032 bytes in 2 transactions, 9,310 clocks.
    """
    clocks = I2C_CLOCKS_PER_BYTE * payload_bytes + I2C_TRANSACTION_CLOCKS * transactions + I2C_RESTART_CLOCKS * restarts
    return clocks / _positive_hz(clock_hz)


def command_bytes(*cmd: int | bytes) -> bytes:
    """The bytes of ``PanelBus.command(*cmd)``: ints 0..255 and bytes-like arguments concatenated in order."""
    out = bytearray()
    for at, part in enumerate(cmd):
        if isinstance(part, bool) or not isinstance(part, int | bytes | bytearray | memoryview):
            raise InvalidArgumentType(f"command argument {at} must be an int 0..255 or bytes: {type(part).__name__}")
        if isinstance(part, int):
            if not 0 <= part <= 0xFF:
                raise InvalidArgument(f"command byte {at} is {part}, outside 0..255")
            out.append(part)
        else:
            out += part
    return bytes(out)


@runtime_checkable
class PanelBus(Protocol):
    """A panel controller's bus as its driver sees it: command bytes, data bytes, a reset, a transfer limit."""

    @property
    def max_transfer(self) -> int:
        """The most bytes one transfer moves; ``data`` chunks longer payloads itself."""

    @property
    def kind(self) -> str:
        """``"spi"`` or ``"i2c"``: which wire carries the bytes."""

    @property
    def clock_hz(self) -> float:
        """The configured bus clock in Hz (SCLK or SCL)."""

    @property
    def bytes_sent(self) -> int:
        """Bytes the host has put on the wire so far: command, data and I2C control bytes."""

    @property
    def transfers(self) -> int:
        """Chip-select frames (SPI) or transactions (I2C) sent so far."""

    def command(self, *cmd: int | bytes) -> None:
        """Send command bytes, all of them with D/C low (I2C: one transaction after control byte 0x00).

        ``command(0x11)``, ``command(0xA8, 0x3F)``, ``command(0x21, b"\\x00\\x7f")``: ints and byte strings
        are concatenated into one frame.
        """

    def data(self, data: bytes) -> None:
        """Send data bytes (D/C high; I2C control byte 0x40), any length, in chunks of at most ``max_transfer``."""

    def reset(self, recovery: float = RESET_RECOVERY) -> None:
        """Pulse the reset line low for :data:`RESET_PULSE`, then wait ``recovery`` s (nothing without a line)."""

    def close(self) -> None:
        """Release the bus (the panel keeps what it shows); calling it again does nothing."""


@runtime_checkable
class I2CPanelBus(PanelBus, Protocol):
    """A panel bus over I2C: every call is a write to ``address`` starting with a control byte."""

    @property
    def address(self) -> int:
        """The panel's 7-bit I2C address (SSD1306: 0x3C or 0x3D)."""


class FramedBus(abc.ABC):
    """What the PanelBus implementations share: counters, the closed guard, the reset line, an exception-safe close.

    A subclass implements ``command``/``data`` with :meth:`_command_frame`, :meth:`_data_chunks` and
    :meth:`_send`, and moves one frame in :meth:`_transfer`; :attr:`control_bytes` is what each frame
    carries before its payload (I2C: the control byte); :attr:`faults` are the exceptions of its library
    that mean a link fault (turned into LinkError).  ``closers`` release the adapter and lines beside
    ``reset`` (which the bus releases itself), in order.
    """

    kind: ClassVar[str]
    control_bytes: ClassVar[int] = 0
    faults: ClassVar[tuple[type[Exception], ...]] = (OSError,)

    def __init__(
        self,
        name: str,
        *,
        clock_hz: float,
        max_transfer: int,
        reset: OutputLine | None,
        clock: Clock,
        closers: Iterable[Callable[[], object]],
    ) -> None:
        if isinstance(clock_hz, bool) or not isinstance(clock_hz, int | float) or not 0 < clock_hz < math.inf:
            raise ConfigError(f"{name}: the {self.kind.upper()} clock must be a number of Hz > 0, got {clock_hz!r}")
        if isinstance(max_transfer, bool) or not isinstance(max_transfer, int) or max_transfer <= self.control_bytes:
            room = " (the control byte and one more)" if self.control_bytes else ""
            raise ConfigError(f"{name}: max_transfer must be at least {self.control_bytes + 1}{room}, "
                              f"got {max_transfer!r}")
        self.name = name
        self.clock_hz = float(clock_hz)
        self.max_transfer = max_transfer
        self.bytes_sent = 0
        """Bytes put on the wire: command, data and control bytes."""
        self.transfers = 0
        """Frames (SPI) or transactions (I2C) sent."""
        self._reset_line = reset
        self._clock = clock
        self._closers = [*closers, *([reset.close] if reset is not None else [])]
        self._closed = False

    @property
    def closed(self) -> bool:
        """True once ``close`` has run."""
        return self._closed

    def reset(self, recovery: float = RESET_RECOVERY) -> None:
        """Pulse the reset line low for RESET_PULSE and wait ``recovery`` s (nothing without a reset line)."""
        self._check_open()
        if self._reset_line is not None:
            pulse_reset(self._reset_line, self._clock, pulse=RESET_PULSE, recovery=recovery)

    def close(self) -> None:
        """Release the adapter and every line, each even when an earlier one fails (then LinkError); idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            with contextlib.ExitStack() as stack:
                for release in reversed(self._closers):  # the stack runs them last-in first
                    stack.callback(release)
        except self.faults as e:
            raise LinkError(f"{self.name}: closing failed: {e}") from e

    def _check_open(self) -> None:
        if self._closed:
            raise LinkError(f"{self.name}: the bus is closed")

    def _command_frame(self, *cmd: int | bytes) -> bytes:
        """The bytes of ``command(*cmd)``, refused when there are none or they overflow one transfer."""
        self._check_open()
        frame = command_bytes(*cmd)
        if not frame:
            raise InvalidArgument(f"{self.name}: command() needs at least one byte")
        if len(frame) + self.control_bytes > self.max_transfer:
            control = " and the control byte" if self.control_bytes else ""
            raise InvalidArgument(f"{self.name}: {len(frame)} command bytes{control} do not fit in one transfer "
                                  f"({self.max_transfer} bytes)")
        return frame

    def _data_chunks(self, data: bytes) -> list[memoryview]:
        """``data`` (any contiguous buffer) cut into frame payloads that fit ``max_transfer`` with the control bytes."""
        self._check_open()
        view = memoryview(data).cast("B")
        step = self.max_transfer - self.control_bytes
        return [view[at : at + step] for at in range(0, len(view), step)]

    def _send(self, frame: bytes | memoryview) -> None:
        """Move one frame and count it; a fault of the library becomes the LinkError of :meth:`_fault`."""
        self._check_open()
        try:
            self._transfer(frame)
        except self.faults as e:
            raise self._fault(len(frame), e) from e
        self.bytes_sent += len(frame)
        self.transfers += 1

    @abc.abstractmethod
    def _transfer(self, frame: bytes | memoryview) -> None:
        """Put one frame on the wire (one chip-select frame or one I2C transaction)."""

    def _fault(self, nbytes: int, error: Exception) -> LinkError:
        """The LinkError for a frame of ``nbytes`` that failed with ``error``."""
        return LinkError(f"{self.name}: write of {nbytes} bytes failed: {error}")


def check_spi_mode(name: str, mode: int) -> None:
    """ConfigError unless ``mode`` is an SPI mode (0..3: clock polarity and phase)."""
    if mode not in (0, 1, 2, 3):
        raise ConfigError(f"{name}: SPI mode must be 0, 1, 2 or 3, got {mode!r}")


class FourWireBus(FramedBus):
    """A 4-wire SPI panel bus: command frames with D/C low, data frames with D/C high (subclasses drive D/C)."""

    def command(self, *cmd: int | bytes) -> None:
        """Send all of ``cmd`` as one chip-select frame with D/C low."""
        frame = self._command_frame(*cmd)
        self._set_dc(False)
        self._send(frame)

    def data(self, data: bytes) -> None:
        """Send ``data`` (any bytes-like) with D/C high, in frames of at most ``max_transfer`` bytes."""
        chunks = self._data_chunks(data)
        if chunks:
            self._set_dc(True)
        for chunk in chunks:
            self._send(chunk)

    @abc.abstractmethod
    def _set_dc(self, level: bool) -> None:
        """Drive the D/C line (low: command, high: data)."""

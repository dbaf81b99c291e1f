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

The simulator side of the same wire is :class:`pixelpen.sim.base.BusDevice`.
"""

from __future__ import annotations

from typing import Final, Protocol, runtime_checkable

from pixelpen.errors import InvalidArgument, InvalidArgumentType

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

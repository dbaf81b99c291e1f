"""The panel bus: what a framebuffer panel's driver talks through (command and data bytes, D/C, chip select, reset).

Declared now, implemented by the panel transports of the next issue (spidev, I2C, FTDI, a simulator),
after luma.core's serial interface: a driver calls ``bus.command(0x2A, b"\\x00\\x00\\x00\\xef")`` and
``bus.data(pixels)`` and never sees which wire carries them.

* SPI (4-wire): the D/C line is low while command bytes are clocked out and high for data bytes;
  chip select is asserted for each ``command``/``data`` call (one frame, kept asserted across the
  chunks of a long call) and released after it.  A 3-wire (9-bit) bus sends D/C as a ninth bit.
* I2C (:class:`I2CPanelBus`): every call is a write transaction to ``address`` whose first byte is a
  control byte: :data:`I2C_COMMAND` (0x00: command bytes follow) or :data:`I2C_DATA` (0x40: data
  bytes follow), as the SSD1306/SH1106 datasheets number them.  Bit 7 of the control byte is Co
  (:data:`I2C_CONTINUATION`): with Co set only one byte follows before the next control byte; the
  bus sends whole streams with Co clear.  An unacknowledged address raises
  :class:`~pixelpen.errors.LinkError`.
* ``max_transfer``: the most bytes the bus moves in one transfer (spidev's ``bufsiz``, 4096 by
  default; an I2C adapter's message size).  ``data`` takes any length and splits it into chunks of
  at most ``max_transfer`` bytes itself (an I2C chunk repeats the control byte), so drivers never chunk.
* ``reset()`` pulses the panel's reset line (active low) where one is wired, with the datasheet's
  pulse and recovery times on the bus's clock; without a reset line it does nothing and a driver
  sends its software reset command.

The simulator side of the same wire is :class:`pixelpen.sim.base.BusDevice`.
"""

from __future__ import annotations

from typing import Final, Protocol, runtime_checkable

I2C_COMMAND: Final = 0x00
"""I2C control byte: command bytes follow (Co clear, D/C# clear)."""
I2C_DATA: Final = 0x40
"""I2C control byte: data bytes (display RAM) follow (Co clear, D/C# set)."""
I2C_CONTINUATION: Final = 0x80
"""Co, bit 7 of an I2C control byte: set, one byte follows and then another control byte."""
DEFAULT_MAX_TRANSFER: Final = 4096
"""Bytes per transfer when a bus names no limit (Linux spidev's default ``bufsiz``)."""


@runtime_checkable
class PanelBus(Protocol):
    """A panel controller's bus as its driver sees it: command bytes, data bytes, a reset, a transfer limit."""

    max_transfer: int
    """The most bytes one transfer moves; ``data`` chunks longer payloads itself."""

    def command(self, *cmd: int | bytes) -> None:
        """Send command bytes (D/C low; I2C control byte 0x00): ``command(0x11)``, ``command(0x2A, b"\\0\\0")``."""

    def data(self, data: bytes) -> None:
        """Send data bytes (D/C high; I2C control byte 0x40), any length, in chunks of at most ``max_transfer``."""

    def reset(self) -> None:
        """Pulse the reset line with the datasheet's timing (nothing when the panel has none wired)."""

    def close(self) -> None:
        """Release the bus (the panel keeps what it shows); calling it again does nothing."""


@runtime_checkable
class I2CPanelBus(PanelBus, Protocol):
    """A panel bus over I2C: every call is a write to ``address`` starting with a control byte."""

    address: int
    """The panel's 7-bit I2C address (SSD1306: 0x3C or 0x3D)."""

"""The 4-wire SPI panel bus over an FTDI FT232H (pyftdi MPSSE SPI), D/C and reset on the chip's GPIO pins.

pyftdi 0.57 facts (its ``spi.py``/``ftdi.py``): SCK, MOSI, MISO and CS0 are ADBUS0-3; GPIO bits 4-7 are
ADBUS4-7 and 8-15 ACBUS0-7 (FT232H), so ``dc=4`` is ADBUS4.  The MPSSE clock is 60 MHz / (2 (1 +
divisor)), at most 30 MHz; one ``SpiPort.write`` moves at most 0xFF00 bytes (``PAYLOAD_MAX_LENGTH``)
and is one chip-select frame.  Modes 0 and 2 are native, 1 and 3 emulated with 3-phase clocking.
Every GPIO write is a read-modify-write over USB (two round trips), so D/C is written only when it
changes.  Open with a URL (``ftdi://ftdi:232h/1``, pyftdi's scheme) or a ``usb.core.Device`` (what
``pixelpen.sim.transports.ftdi.Ft232hBackend.find()`` gives).
"""

from __future__ import annotations

import logging
from typing import Any, Final

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.bus import RESET_PULSE, RESET_RECOVERY, command_bytes
from pixelpen.drivers.gpio import pulse_reset
from pixelpen.errors import ConfigError, LinkError

log = logging.getLogger(__name__)

MAX_CLOCK_HZ: Final = 30_000_000
"""The FT232H's fastest SPI clock (60 MHz / 2)."""
MAX_TRANSFER: Final = 0xFF00
"""pyftdi's most bytes per SPI exchange."""
DEFAULT_URL: Final = "ftdi://ftdi:232h/1"
FIRST_GPIO: Final = 4
"""ADBUS0-3 carry SCK, MOSI, MISO and CS0."""
LAST_GPIO: Final = 15
_FAULTS: Final = (OSError, ValueError)
"""What pyftdi raises on a fault: FtdiError and SpiIOError (OSError), usb.core.USBError (OSError), ValueError."""


class _GpioPin:
    """One output bit of the controller's GPIO port as an OutputLine (for ``pulse_reset``)."""

    def __init__(self, bus: FtdiSpiBus, bit: int) -> None:
        self._bus = bus
        self._bit = bit

    def set(self, level: bool) -> None:
        """Drive the pin."""
        self._bus.set_pin(self._bit, level)

    def close(self) -> None:
        """Nothing to release: the bus owns the port."""


class FtdiSpiBus:
    """A PanelBus over pyftdi's SpiController: ``command`` one D/C-low frame, ``data`` D/C-high frames."""

    kind: Final = "spi"

    def __init__(
        self,
        controller: Any,
        *,
        dc: int = 4,
        rst: int | None = 5,
        clock_hz: float = MAX_CLOCK_HZ,
        mode: int = 0,
        cs: int = 0,
        max_transfer: int = MAX_TRANSFER,
        clock: Clock = REAL_CLOCK,
        name: str = "ftdi",
    ) -> None:
        _check_options(name, dc, rst, clock_hz, mode, max_transfer, cs)
        self.name = name
        self.max_transfer = max_transfer
        self.bytes_sent = 0
        self.transfers = 0
        self._controller = controller
        self._clock = clock
        self._closed = False
        self._dc_bit = 1 << dc
        self._mask = self._dc_bit | (1 << rst if rst is not None else 0)
        self._reset_line = _GpioPin(self, rst) if rst is not None else None
        if mode in (1, 3):
            log.warning("%s: SPI mode %d is emulated by pyftdi with 3-phase clocking and may be unreliable", name, mode)
        try:
            self._port = controller.get_port(cs=cs, freq=clock_hz, mode=mode)
            self._gpio = controller.get_gpio()
            self._gpio.set_direction(self._mask, self._mask)
            self._levels = self._mask & ~self._dc_bit  # reset released (high), D/C low
            self._gpio.write(self._levels)
            self.clock_hz = float(self._port.frequency)
        except _FAULTS as exc:
            raise LinkError(f"{name}: setting up SPI (cs {cs}, {clock_hz:g} Hz, mode {mode}) and GPIO failed: "
                            f"{exc}") from exc

    @classmethod
    def open(
        cls, target: Any = DEFAULT_URL, *, dc: int = 4, rst: int | None = 5, clock_hz: float = MAX_CLOCK_HZ,
        mode: int = 0, cs: int = 0, max_transfer: int = MAX_TRANSFER, clock: Clock = REAL_CLOCK,
    ) -> FtdiSpiBus:
        """Open an FT232H by pyftdi URL (``ftdi://ftdi:232h/1``) or ``usb.core.Device`` and configure MPSSE SPI."""
        name = target if isinstance(target, str) else "ftdi"
        _check_options(name, dc, rst, clock_hz, mode, max_transfer, cs)
        try:
            from pyftdi.spi import SpiController
            from pyftdi.usbtools import UsbToolsError
        except ImportError:
            raise ConfigError("the FT232H bus needs pyftdi: pip install pyftdi (or pixelpen[panels])") from None
        controller = SpiController(cs_count=cs + 1)
        try:
            controller.configure(target, frequency=clock_hz)
        except (*_FAULTS, UsbToolsError) as exc:
            raise LinkError(f"{name}: cannot open the FTDI device: {exc} (is it plugged in, and may this user "
                            "open it? see pyftdi's installation notes for the udev rule)") from exc
        return cls(controller, dc=dc, rst=rst, clock_hz=clock_hz, mode=mode, cs=cs, max_transfer=max_transfer,
                   clock=clock, name=name)

    def command(self, *cmd: int | bytes) -> None:
        """One chip-select frame of command bytes with D/C low."""
        payload = command_bytes(*cmd)
        if payload:
            self._set_dc(False)
            self._write(payload)

    def data(self, data: bytes) -> None:
        """Data bytes with D/C high, one frame per ``max_transfer`` bytes."""
        payload = bytes(data)
        if payload:
            self._set_dc(True)
            for start in range(0, len(payload), self.max_transfer):
                self._write(payload[start : start + self.max_transfer])

    def reset(self, recovery: float = RESET_RECOVERY) -> None:
        """Pulse the reset pin low for RESET_PULSE, then wait ``recovery`` s (nothing when no pin is wired)."""
        self._check_open()
        if self._reset_line is not None:
            pulse_reset(self._reset_line, self._clock, pulse=RESET_PULSE, recovery=recovery)

    def set_pin(self, bit: int, level: bool) -> None:
        """Drive one of the bus's GPIO output pins (D/C or reset)."""
        self._check_open()
        mask = 1 << bit
        if not mask & self._mask:
            raise ConfigError(f"{self.name}: GPIO {bit} is not one of this bus's output pins")
        levels = self._levels | mask if level else self._levels & ~mask
        if levels != self._levels:
            try:
                self._gpio.write(levels)
            except _FAULTS as exc:
                raise LinkError(f"{self.name}: setting GPIO {bit} {'high' if level else 'low'} failed: {exc}") from exc
            self._levels = levels

    def close(self) -> None:
        """Release the FTDI device (pins keep their levels: the panel keeps what it shows); idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            self._controller.close(freeze=True)
        except _FAULTS as exc:
            log.warning("%s: closing the FTDI device failed: %s", self.name, exc)

    def _check_open(self) -> None:
        if self._closed:
            raise LinkError(f"{self.name}: the bus is closed")

    def _set_dc(self, level: bool) -> None:
        self.set_pin(self._dc_bit.bit_length() - 1, level)

    def _write(self, payload: bytes) -> None:
        self._check_open()
        try:
            self._port.write(payload)
        except _FAULTS as exc:
            raise LinkError(f"{self.name}: SPI write of {len(payload)} bytes failed: {exc}") from exc
        self.bytes_sent += len(payload)
        self.transfers += 1


def _check_options(
    name: str, dc: int, rst: int | None, clock_hz: float, mode: int, max_transfer: int, cs: int
) -> None:
    if not 0 < clock_hz <= MAX_CLOCK_HZ:
        raise ConfigError(f"{name}: SPI clock {clock_hz:g} Hz is outside 0..30 MHz (the FT232H's limit, "
                          "60 MHz / 2)")
    if mode not in (0, 1, 2, 3):
        raise ConfigError(f"{name}: SPI mode must be 0, 1, 2 or 3, got {mode!r}")
    if not 1 <= max_transfer <= MAX_TRANSFER:
        raise ConfigError(f"{name}: max_transfer must be 1..{MAX_TRANSFER} (pyftdi's limit), got {max_transfer}")
    if not 0 <= cs <= 4:
        raise ConfigError(f"{name}: cs must be 0..4 (CS0-CS4 on ADBUS3-7), got {cs!r}")
    first = FIRST_GPIO + cs  # CS1.. take ADBUS4.. when used
    for option, pin in (("dc", dc), ("rst", rst)):
        if pin is not None and not first <= pin <= LAST_GPIO:
            raise ConfigError(f"{name}: {option}={pin} is not a free GPIO pin: use {first}..{LAST_GPIO} "
                              f"(ADBUS0-{first - 1} carry SPI and chip selects; 8-15 are ACBUS0-7)")
    if rst is not None and rst == dc:
        raise ConfigError(f"{name}: dc and rst are both GPIO {dc}")

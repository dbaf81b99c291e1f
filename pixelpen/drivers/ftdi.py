"""The 4-wire SPI panel bus over an FTDI FT232H (pyftdi MPSSE SPI), D/C and reset on the chip's GPIO pins.

pyftdi 0.57 facts (its ``spi.py``/``ftdi.py``): SCK, MOSI, MISO and CS0 are ADBUS0-3; GPIO bits 4-7 are
ADBUS4-7 and 8-15 ACBUS0-7 (FT232H), so ``dc=4`` is ADBUS4.  The MPSSE clock is 60 MHz / (2 (1 +
divisor)), at most 30 MHz; one ``SpiPort.write`` moves at most 0xFF00 bytes (``PAYLOAD_MAX_LENGTH``)
and is one chip-select frame.  Modes 0 and 2 are native, 1 and 3 emulated with 3-phase clocking.
Every GPIO write is a read-modify-write over USB (two round trips), so D/C is written only when it
changes.  ``clock_hz`` is the port's frequency as pyftdi keeps it: the request capped at 30 MHz (the chip
runs at the nearest divisor's, 7 MHz asked -> 7.5 MHz).  ``close`` freezes the port: the pins keep their
levels, so the panel keeps its picture.  Open with a URL (``ftdi://ftdi:232h/1``, pyftdi's scheme) or a
``usb.core.Device`` (what ``pixelpen.sim.transports.ftdi.Ft232hBackend.find()`` gives).
"""

from __future__ import annotations

import contextlib
import logging
from typing import Any, ClassVar, Final

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.bus import FourWireBus, check_spi_mode
from pixelpen.drivers.devnode import require_module
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


class FtdiSpiBus(FourWireBus):
    """A PanelBus over pyftdi's SpiController: ``command`` one D/C-low frame, ``data`` D/C-high frames."""

    kind: ClassVar[str] = "spi"
    faults: ClassVar[tuple[type[Exception], ...]] = (OSError, ValueError)
    """What pyftdi raises on a fault: FtdiError and SpiIOError (OSError), usb.core.USBError (OSError), ValueError."""

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
        super().__init__(name, clock_hz=clock_hz, max_transfer=max_transfer,
                         reset=_GpioPin(self, rst) if rst is not None else None, clock=clock,
                         closers=(lambda: controller.close(freeze=True),))
        self._dc = dc
        self._mask = 1 << dc | (1 << rst if rst is not None else 0)
        if mode in (1, 3):
            log.warning("%s: SPI mode %d is emulated by pyftdi with 3-phase clocking and may be unreliable", name, mode)
        try:
            self._port = controller.get_port(cs=cs, freq=clock_hz, mode=mode)
            self.clock_hz = float(self._port.frequency)
            self._gpio = controller.get_gpio()
            self._gpio.set_direction(self._mask, self._mask)
            self._levels = self._mask & ~(1 << dc)  # reset released (high), D/C low
            self._gpio.write(self._levels)
        except self.faults as exc:
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
        spi = require_module("pyftdi.spi", needed_by="FT232H panels", package="pyftdi",
                             install="pyftdi ('pixelpen[panels]')")
        from pyftdi.usbtools import UsbToolsError  # importable once pyftdi.spi is

        controller = spi.SpiController(cs_count=cs + 1)
        try:
            controller.configure(target, frequency=clock_hz)
        except (*cls.faults, UsbToolsError) as exc:
            raise LinkError(f"{name}: cannot open the FTDI device: {exc} (is it plugged in, and may this user "
                            "open it? see pyftdi's installation notes for the udev rule)") from exc
        try:
            return cls(controller, dc=dc, rst=rst, clock_hz=clock_hz, mode=mode, cs=cs, max_transfer=max_transfer,
                       clock=clock, name=name)
        except BaseException:
            with contextlib.suppress(*cls.faults):  # released again; the setup error is the one to report
                controller.close()
            raise

    def set_pin(self, bit: int, level: bool) -> None:
        """Drive one of the bus's GPIO output pins (D/C or reset); a write goes out only when the level changes."""
        self._check_open()
        mask = 1 << bit
        if not mask & self._mask:
            raise ConfigError(f"{self.name}: GPIO {bit} is not one of this bus's output pins")
        levels = self._levels | mask if level else self._levels & ~mask
        if levels != self._levels:
            try:
                self._gpio.write(levels)
            except self.faults as exc:
                raise LinkError(f"{self.name}: setting GPIO {bit} {'high' if level else 'low'} failed: {exc}") from exc
            self._levels = levels

    def _set_dc(self, level: bool) -> None:
        self.set_pin(self._dc, level)

    def _transfer(self, frame: bytes | memoryview) -> None:
        self._port.write(bytes(frame))

    def _fault(self, nbytes: int, error: Exception) -> LinkError:
        return LinkError(f"{self.name}: SPI write of {nbytes} bytes failed: {error}")


def _check_options(
    name: str, dc: int, rst: int | None, clock_hz: float, mode: int, max_transfer: int, cs: int
) -> None:
    if not 0 < clock_hz <= MAX_CLOCK_HZ:
        raise ConfigError(f"{name}: SPI clock {clock_hz:g} Hz is outside 0..30 MHz (the FT232H's limit, "
                          "60 MHz / 2)")
    check_spi_mode(name, mode)
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

"""The 4-wire SPI panel bus over Linux spidev: D/C and reset on GPIO lines, frames chunked to the driver's bufsiz.

``SpiBus`` takes anything with spidev.SpiDev's ``writebytes2``, ``max_speed_hz``, ``mode`` and ``close``
(the real ``spidev`` package, or ``sim.transports.spidev.SimSpiDev``).  D/C is written only when it
changes (a GPIO write costs microseconds on real hardware); each ``writebytes2`` call of at most
``max_transfer`` bytes is one chip-select frame, since spidev splits its argument by ``bufsiz``.
"""

from __future__ import annotations

import contextlib
import logging
from pathlib import Path
from typing import Any, ClassVar, Final

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.bus import DEFAULT_MAX_TRANSFER, FourWireBus, check_spi_mode
from pixelpen.drivers.devnode import node_open_error, require_module
from pixelpen.drivers.gpio import OutputLine, open_output_line
from pixelpen.errors import LinkError

log = logging.getLogger(__name__)

BUFSIZ_PATH: Final = Path("/sys/module/spidev/parameters/bufsiz")
"""The spidev module parameter: the most bytes of one transfer (4096 unless the kernel was told otherwise)."""
SPIDEV_MAX_BLOCK: Final = 65535
"""py-spidev splits ``writebytes2`` into blocks of at most this many bytes whatever ``bufsiz`` says."""
SPIDEV_DEFAULT_BUFSIZ: Final = DEFAULT_MAX_TRANSFER
"""spidev's ``bufsiz`` when the module parameter cannot be read."""


def spidev_bufsiz(path: Path | None = None) -> int:
    """The spidev driver's ``bufsiz`` (from BUFSIZ_PATH; capped as py-spidev caps it), or 4096 when unreadable."""
    try:
        value = int((path or BUFSIZ_PATH).read_text().strip())
    except (OSError, ValueError):
        return SPIDEV_DEFAULT_BUFSIZ
    return min(value, SPIDEV_MAX_BLOCK) if value > 0 else SPIDEV_DEFAULT_BUFSIZ


class SpiBus(FourWireBus):
    """A PanelBus on 4-wire SPI: ``command`` is one D/C-low frame, ``data`` D/C-high frames of <= ``max_transfer``."""

    kind: ClassVar[str] = "spi"

    def __init__(
        self,
        spi: Any,
        *,
        dc: OutputLine,
        reset: OutputLine | None = None,
        clock_hz: float,
        max_transfer: int | None = None,
        mode: int | None = None,
        clock: Clock = REAL_CLOCK,
        name: str = "spi",
    ) -> None:
        if mode is not None:
            check_spi_mode(name, mode)
        limit = spidev_bufsiz() if max_transfer is None else max_transfer
        super().__init__(name, clock_hz=clock_hz, max_transfer=limit, reset=reset, clock=clock,
                         closers=(spi.close, dc.close))
        self._spi: Any = spi
        self._dc = dc
        self._dc_level: bool | None = None
        try:
            if mode is not None:
                spi.mode = mode
            spi.max_speed_hz = int(clock_hz)
        except OSError as e:
            raise LinkError(f"{name}: setting mode {mode} and clock {int(clock_hz)} Hz failed: {e}") from e

    def _set_dc(self, level: bool) -> None:
        if self._dc_level is not level:
            self._dc_level = None  # unknown until the write succeeds
            self._dc.set(level)
            self._dc_level = level

    def _transfer(self, frame: bytes | memoryview) -> None:
        self._spi.writebytes2(frame)

    @classmethod
    def open(
        cls,
        bus: int,
        device: int,
        *,
        dc: int,
        rst: int | None = None,
        clock_hz: float,
        gpiochip: str = "/dev/gpiochip0",
        mode: int = 0,
        max_transfer: int | None = None,
        clock: Clock = REAL_CLOCK,
    ) -> SpiBus:
        """Open ``/dev/spidev<bus>.<device>`` with the spidev package and D/C (and reset) lines of ``gpiochip``."""
        node = f"/dev/spidev{bus}.{device}"
        spi = require_module("spidev", needed_by="SPI panels", install="spidev ('pixelpen[panels]')").SpiDev()
        try:
            spi.open(bus, device)
        except OSError as e:
            raise node_open_error(node, e, group="spi", udev='SUBSYSTEM=="spidev"',
                                  missing="enable SPI (Raspberry Pi: dtparam=spi=on in config.txt, or raspi-config) "
                                          "and check the bus and chip-select numbers") from e
        with contextlib.ExitStack() as undo:  # released again unless the bus is made
            undo.callback(spi.close)
            dc_line = open_output_line(gpiochip, dc, initial=False)
            undo.callback(dc_line.close)
            reset = None
            if rst is not None:
                reset = open_output_line(gpiochip, rst, initial=True)
                undo.callback(reset.close)
            opened = cls(spi, dc=dc_line, reset=reset, clock_hz=clock_hz, max_transfer=max_transfer, mode=mode,
                         clock=clock, name=f"spi {bus}.{device}")
            undo.pop_all()
        log.info("%s opened: %g Hz, mode %d, %d-byte transfers, D/C %s:%d", node, clock_hz, mode,
                 opened.max_transfer, gpiochip, dc)
        return opened

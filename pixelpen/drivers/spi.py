"""The 4-wire SPI panel bus over Linux spidev: D/C and reset on GPIO lines, frames chunked to the driver's bufsiz.

``SpiBus`` takes anything with spidev.SpiDev's ``writebytes2``, ``max_speed_hz``, ``mode`` and ``close``
(the real ``spidev`` package, or ``sim.transports.spidev.SimSpiDev``).  D/C is written only when it
changes (a GPIO write costs microseconds on real hardware); each ``writebytes2`` call of at most
``max_transfer`` bytes is one chip-select frame, since spidev splits its argument by ``bufsiz``.
"""

from __future__ import annotations

import importlib
import logging
from pathlib import Path
from typing import Any, Final

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.bus import RESET_PULSE, RESET_RECOVERY, command_bytes
from pixelpen.drivers.gpio import OutputLine, open_output_line, pulse_reset
from pixelpen.errors import ConfigError, InvalidArgument, LinkError

log = logging.getLogger(__name__)

BUFSIZ_PATH: Final = Path("/sys/module/spidev/parameters/bufsiz")
"""The spidev module parameter: the most bytes of one transfer (4096 unless the kernel was told otherwise)."""
SPIDEV_MAX_BLOCK: Final = 65535
"""py-spidev splits ``writebytes2`` into blocks of at most this many bytes whatever ``bufsiz`` says."""
SPIDEV_DEFAULT_BUFSIZ: Final = 4096
"""spidev's ``bufsiz`` when the module parameter cannot be read."""


def spidev_bufsiz(path: Path | None = None) -> int:
    """The spidev driver's ``bufsiz`` (from BUFSIZ_PATH; capped as py-spidev caps it), or 4096 when unreadable."""
    try:
        value = int((path or BUFSIZ_PATH).read_text().strip())
    except (OSError, ValueError):
        return SPIDEV_DEFAULT_BUFSIZ
    return min(value, SPIDEV_MAX_BLOCK) if value > 0 else SPIDEV_DEFAULT_BUFSIZ


class SpiBus:
    """A PanelBus on 4-wire SPI: ``command`` is one D/C-low frame, ``data`` D/C-high frames of <= ``max_transfer``."""

    kind: Final = "spi"

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
        if not clock_hz >= 1:
            raise ConfigError(f"{name}: the SPI clock must be at least 1 Hz, got {clock_hz!r}")
        if mode is not None and mode not in (0, 1, 2, 3):
            raise ConfigError(f"{name}: SPI mode must be 0, 1, 2 or 3, got {mode!r}")
        self.max_transfer = spidev_bufsiz() if max_transfer is None else max_transfer
        if self.max_transfer < 1:
            raise ConfigError(f"{name}: max_transfer must be at least 1, got {self.max_transfer}")
        self.name = name
        self.clock_hz = float(clock_hz)
        self.bytes_sent = 0
        self.transfers = 0
        self._spi: Any = spi
        self._dc = dc
        self._reset_line = reset
        self._clock = clock
        self._dc_level: bool | None = None
        self._closed = False
        try:
            if mode is not None:
                spi.mode = mode
            spi.max_speed_hz = int(clock_hz)
        except OSError as e:
            raise LinkError(f"{name}: setting mode {mode} and clock {int(clock_hz)} Hz failed: {e}") from e

    @property
    def closed(self) -> bool:
        """True once ``close`` has run."""
        return self._closed

    def command(self, *cmd: int | bytes) -> None:
        """Send all of ``cmd`` as one frame with D/C low."""
        frame = command_bytes(*cmd)
        if not frame:
            raise InvalidArgument(f"{self.name}: command() needs at least one byte")
        if len(frame) > self.max_transfer:
            raise InvalidArgument(f"{self.name}: a command of {len(frame)} bytes exceeds one transfer "
                                  f"({self.max_transfer} bytes)")
        self._set_dc(False)
        self._write(frame)

    def data(self, data: bytes) -> None:
        """Send ``data`` (any bytes-like) with D/C high, in frames of at most ``max_transfer`` bytes."""
        view = memoryview(data).cast("B")
        if not len(view):
            self._check_open()
            return
        self._set_dc(True)
        for at in range(0, len(view), self.max_transfer):
            self._write(view[at : at + self.max_transfer])

    def reset(self, recovery: float = RESET_RECOVERY) -> None:
        """Pulse the reset line low for RESET_PULSE and wait ``recovery`` s (nothing without a reset line)."""
        self._check_open()
        if self._reset_line is not None:
            pulse_reset(self._reset_line, self._clock, pulse=RESET_PULSE, recovery=recovery)

    def close(self) -> None:
        """Close spidev and release the D/C and reset lines (the panel keeps its picture)."""
        if self._closed:
            return
        self._closed = True
        self._spi.close()
        self._dc.close()
        if self._reset_line is not None:
            self._reset_line.close()

    def _check_open(self) -> None:
        if self._closed:
            raise LinkError(f"{self.name}: the bus is closed")

    def _set_dc(self, level: bool) -> None:
        self._check_open()
        if self._dc_level is not level:
            self._dc_level = None  # unknown until the write succeeds
            self._dc.set(level)
            self._dc_level = level

    def _write(self, frame: bytes | memoryview) -> None:
        try:
            self._spi.writebytes2(frame)
        except OSError as e:
            raise LinkError(f"{self.name}: write of {len(frame)} bytes failed: {e}") from e
        self.bytes_sent += len(frame)
        self.transfers += 1

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
        try:
            spidev = importlib.import_module("spidev")
        except ImportError:
            raise ConfigError("SPI panels need the spidev package: pip install spidev ('pixelpen[panels]')") from None
        spi = spidev.SpiDev()
        try:
            spi.open(bus, device)
        except FileNotFoundError:
            raise LinkError(f"{node} does not exist: enable SPI (Raspberry Pi: dtparam=spi=on in config.txt, "
                            f"or raspi-config) and check the bus and chip-select numbers") from None
        except PermissionError:
            raise LinkError(f"permission denied on {node}: add your user to the 'spi' group "
                            f"(sudo usermod -aG spi $USER, then log in again) or add a udev rule "
                            f'SUBSYSTEM=="spidev", GROUP="spi", MODE="0660"') from None
        except OSError as e:
            raise LinkError(f"{node}: cannot open: {e}") from e
        lines: list[OutputLine] = []
        try:
            lines.append(open_output_line(gpiochip, dc, initial=False))
            if rst is not None:
                lines.append(open_output_line(gpiochip, rst, initial=True))
            bus_ = cls(spi, dc=lines[0], reset=lines[1] if rst is not None else None, clock_hz=clock_hz,
                       max_transfer=max_transfer, mode=mode, clock=clock, name=f"spi {bus}.{device}")
        except BaseException:
            for line in lines:
                line.close()
            spi.close()
            raise
        log.info("%s opened: %g Hz, mode %d, %d-byte transfers, D/C %s:%d", node, clock_hz, mode,
                 bus_.max_transfer, gpiochip, dc)
        return bus_

"""The I2C panel bus (SSD1306 family): control byte 0x00 or 0x40 per transaction, over an smbus2-like ``i2c_rdwr``.

One ``command`` call is one write transaction ``[0x00, *cmd]``; ``data`` is transactions ``[0x40, chunk]``
of at most ``max_transfer`` bytes each, control byte included (Linux i2c-dev takes up to 8192 per message;
SMBus block writes would stop at 32).  The bus clock is the adapter's (the kernel's, on Linux): ``clock_hz``
records it for the bandwidth estimate.
"""

from __future__ import annotations

import errno
import importlib
import logging
from pathlib import Path
from typing import Any, Final

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.bus import DEFAULT_MAX_TRANSFER, I2C_COMMAND, I2C_DATA, RESET_PULSE, RESET_RECOVERY, command_bytes
from pixelpen.drivers.gpio import OutputLine, open_output_line, pulse_reset
from pixelpen.errors import ConfigError, InvalidArgument, LinkError

log = logging.getLogger(__name__)

NAK_ERRNOS: Final = frozenset({errno.ENXIO, errno.EREMOTEIO, errno.EIO})
"""What Linux I2C adapter drivers return when no device acknowledges the address."""
I2C_SYSFS: Final = Path("/sys/bus/i2c/devices")
"""Where Linux lists I2C adapters (``i2c-N``, with ``of_node`` on device-tree systems)."""
DEFAULT_CLOCK_HZ: Final = 400_000
"""Fast-mode I2C, the SSD1306's rated maximum (the adapter may run slower; see ``adapter_clock_hz``)."""


def adapter_clock_hz(bus_number: int, sysfs: Path | None = None) -> int | None:
    """The adapter's SCL frequency from its device-tree node (big-endian u32 ``clock-frequency``), if it has one."""
    try:
        raw = ((sysfs or I2C_SYSFS) / f"i2c-{bus_number}" / "of_node" / "clock-frequency").read_bytes()
    except OSError:
        return None
    return int.from_bytes(raw[:4], "big") if len(raw) >= 4 else None


class I2CBus:
    """A PanelBus on I2C at 7-bit ``address``: control byte 0x00 before commands, 0x40 before each data chunk."""

    kind: Final = "i2c"

    def __init__(
        self,
        adapter: Any,
        address: int,
        *,
        clock_hz: float = DEFAULT_CLOCK_HZ,
        max_transfer: int = DEFAULT_MAX_TRANSFER,
        reset: OutputLine | None = None,
        clock: Clock = REAL_CLOCK,
        name: str = "i2c",
    ) -> None:
        if not isinstance(address, int) or not 0x03 <= address <= 0x77:
            raise ConfigError(f"{name}: I2C address must be a 7-bit address 0x03..0x77, got {address!r}")
        if not clock_hz > 0:
            raise ConfigError(f"{name}: the I2C clock must be positive, got {clock_hz!r}")
        if max_transfer < 2:
            raise ConfigError(f"{name}: max_transfer must leave room for the control byte (>= 2), got {max_transfer}")
        self.address = address
        self.clock_hz = float(clock_hz)
        self.max_transfer = max_transfer
        self.name = name
        self.bytes_sent = 0
        self.transfers = 0
        self._adapter: Any = adapter
        self._reset_line = reset
        self._clock = clock
        self._closed = False
        self._message = importlib.import_module("smbus2").i2c_msg.write

    @property
    def closed(self) -> bool:
        """True once ``close`` has run."""
        return self._closed

    def command(self, *cmd: int | bytes) -> None:
        """Send all of ``cmd`` in one transaction after control byte 0x00."""
        payload = command_bytes(*cmd)
        if not payload:
            raise InvalidArgument(f"{self.name}: command() needs at least one byte")
        if len(payload) + 1 > self.max_transfer:
            raise InvalidArgument(f"{self.name}: a command of {len(payload)} bytes and its control byte exceed one "
                                  f"transfer ({self.max_transfer} bytes)")
        self._write(bytes([I2C_COMMAND]) + payload)

    def data(self, data: bytes) -> None:
        """Send ``data`` in transactions of control byte 0x40 and at most ``max_transfer - 1`` data bytes."""
        view = memoryview(data).cast("B")
        self._check_open()
        step = self.max_transfer - 1
        for at in range(0, len(view), step):
            self._write(bytes([I2C_DATA]) + view[at : at + step])

    def reset(self, recovery: float = RESET_RECOVERY) -> None:
        """Pulse the reset line where one is wired (many I2C modules have none: then nothing)."""
        self._check_open()
        if self._reset_line is not None:
            pulse_reset(self._reset_line, self._clock, pulse=RESET_PULSE, recovery=recovery)

    def close(self) -> None:
        """Close the adapter and release the reset line."""
        if self._closed:
            return
        self._closed = True
        self._adapter.close()
        if self._reset_line is not None:
            self._reset_line.close()

    def _check_open(self) -> None:
        if self._closed:
            raise LinkError(f"{self.name}: the bus is closed")

    def _write(self, payload: bytes) -> None:
        self._check_open()
        try:
            self._adapter.i2c_rdwr(self._message(self.address, payload))
        except OSError as e:
            if e.errno in NAK_ERRNOS:
                raise LinkError(f"{self.name}: no device acknowledged address 0x{self.address:02x}") from e
            raise LinkError(f"{self.name}: write of {len(payload)} bytes to 0x{self.address:02x} failed: {e}") from e
        self.bytes_sent += len(payload)
        self.transfers += 1

    @classmethod
    def open(
        cls,
        bus_number: int,
        address: int,
        *,
        clock_hz: float | None = None,
        max_transfer: int = DEFAULT_MAX_TRANSFER,
        rst: int | None = None,
        gpiochip: str = "/dev/gpiochip0",
        clock: Clock = REAL_CLOCK,
    ) -> I2CBus:
        """Open ``/dev/i2c-<bus_number>`` with smbus2; ``clock_hz`` defaults to the adapter's (else 400 kHz)."""
        node = f"/dev/i2c-{bus_number}"
        try:
            adapter = importlib.import_module("smbus2").SMBus(bus_number)
        except ImportError:
            raise ConfigError("I2C panels need the smbus2 package: pip install smbus2") from None
        except FileNotFoundError:
            raise LinkError(f"{node} does not exist: enable I2C (Raspberry Pi: dtparam=i2c_arm=on in config.txt, "
                            f"or raspi-config) or load the i2c-dev module (sudo modprobe i2c-dev)") from None
        except PermissionError:
            raise LinkError(f"permission denied on {node}: add your user to the 'i2c' group "
                            f"(sudo usermod -aG i2c $USER, then log in again) or add a udev rule "
                            f'SUBSYSTEM=="i2c-dev", GROUP="i2c", MODE="0660"') from None
        except OSError as e:
            raise LinkError(f"{node}: cannot open: {e}") from e
        hz = clock_hz if clock_hz is not None else adapter_clock_hz(bus_number) or DEFAULT_CLOCK_HZ
        reset: OutputLine | None = None
        try:
            if rst is not None:
                reset = open_output_line(gpiochip, rst, initial=True)
            bus = cls(adapter, address, clock_hz=hz, max_transfer=max_transfer, reset=reset, clock=clock,
                      name=f"i2c-{bus_number}")
        except BaseException:
            if reset is not None:
                reset.close()
            adapter.close()
            raise
        log.info("%s opened for address 0x%02x at %g Hz", node, address, hz)
        return bus

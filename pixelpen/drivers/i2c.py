"""The I2C panel bus (SSD1306 family): control byte 0x00 or 0x40 per transaction, over an smbus2-like ``i2c_rdwr``.

One ``command`` call is one write transaction ``[0x00, *cmd]``; ``data`` is transactions ``[0x40, chunk]``
of at most ``max_transfer`` bytes each, control byte included (Linux i2c-dev takes up to 8192 per message;
SMBus block writes would stop at 32).  The bus clock is the adapter's (the kernel's, on Linux): ``clock_hz``
records it for the bandwidth estimate.
"""

from __future__ import annotations

import contextlib
import errno
import importlib
import logging
from pathlib import Path
from typing import Any, ClassVar, Final

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.bus import DEFAULT_MAX_TRANSFER, I2C_COMMAND, I2C_DATA, FramedBus
from pixelpen.drivers.devnode import node_open_error, require_module
from pixelpen.drivers.gpio import OutputLine, open_output_line
from pixelpen.errors import ConfigError, LinkError
from pixelpen.options import I2C_ADDRESSES

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


class I2CBus(FramedBus):
    """A PanelBus on I2C at 7-bit ``address``: control byte 0x00 before commands, 0x40 before each data chunk."""

    kind: ClassVar[str] = "i2c"
    control_bytes: ClassVar[int] = 1

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
        if not isinstance(address, int) or address not in I2C_ADDRESSES:
            raise ConfigError(f"{name}: I2C address must be a 7-bit address 0x08..0x77, got {address!r}")
        super().__init__(name, clock_hz=clock_hz, max_transfer=max_transfer, reset=reset, clock=clock,
                         closers=(adapter.close,))
        self.address = address
        self._adapter: Any = adapter
        self._message = importlib.import_module("smbus2").i2c_msg.write

    def command(self, *cmd: int | bytes) -> None:
        """Send all of ``cmd`` in one transaction after control byte 0x00."""
        self._send(bytes([I2C_COMMAND]) + self._command_frame(*cmd))

    def data(self, data: bytes) -> None:
        """Send ``data`` in transactions of control byte 0x40 and at most ``max_transfer - 1`` data bytes."""
        for chunk in self._data_chunks(data):
            self._send(bytes([I2C_DATA]) + chunk)

    def _transfer(self, frame: bytes | memoryview) -> None:
        self._adapter.i2c_rdwr(self._message(self.address, frame))

    def _fault(self, nbytes: int, error: Exception) -> LinkError:
        if isinstance(error, OSError) and error.errno in NAK_ERRNOS:
            return LinkError(f"{self.name}: no device acknowledged address 0x{self.address:02x}")
        return LinkError(f"{self.name}: write of {nbytes} bytes to 0x{self.address:02x} failed: {error}")

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
        smbus2 = require_module("smbus2", needed_by="I2C panels", install="smbus2")
        try:
            adapter = smbus2.SMBus(bus_number)
        except OSError as e:
            raise node_open_error(node, e, group="i2c", udev='SUBSYSTEM=="i2c-dev"',
                                  missing="enable I2C (Raspberry Pi: dtparam=i2c_arm=on in config.txt, or "
                                          "raspi-config) or load the i2c-dev module (sudo modprobe i2c-dev)") from e
        hz = clock_hz if clock_hz is not None else adapter_clock_hz(bus_number) or DEFAULT_CLOCK_HZ
        with contextlib.ExitStack() as undo:  # released again unless the bus is made
            undo.callback(adapter.close)
            reset = None
            if rst is not None:
                reset = open_output_line(gpiochip, rst, initial=True)
                undo.callback(reset.close)
            bus = cls(adapter, address, clock_hz=hz, max_transfer=max_transfer, reset=reset, clock=clock,
                      name=f"i2c-{bus_number}")
            undo.pop_all()
        log.info("%s opened for address 0x%02x at %g Hz", node, address, hz)
        return bus

"""A simulated I2C bus as host code sees it: smbus2.SMBus's API (as luma and pixelpen use it) over BusDevices.

Each message is one addressed write (``device.i2c_write``) or read (``device.i2c_read``), offered to the
devices in turn until one acknowledges; no acknowledgement raises ``OSError(EREMOTEIO)`` as Linux i2c-dev
does, and the I2C_RDWR limits are the kernel's (at most 42 messages, 8192 bytes each: EINVAL).  With a
SimulatedClock each transaction advances the clock by its wire time, ``drivers.bus.i2c_wire_seconds``:
9 SCL periods per byte (8 bits + ACK, the address bytes included) plus one for each START or repeated
START and one for the STOP.
"""

from __future__ import annotations

import ctypes
import errno
from collections.abc import Sequence
from types import TracebackType
from typing import Final, Protocol

from pixelpen.clock import Clock, SimulatedClock
from pixelpen.drivers.bus import i2c_wire_seconds
from pixelpen.errors import InvalidArgument
from pixelpen.sim.base import BusDevice

I2C_M_RD: Final = 0x0001
"""The read flag of an i2c_msg (linux/i2c.h)."""
I2C_RDWR_MAX_MSGS: Final = 42
"""Most messages in one I2C_RDWR ioctl (I2C_RDWR_IOCTL_MAX_MSGS in drivers/i2c/i2c-dev.c)."""
I2C_RDWR_MAX_LEN: Final = 8192
"""Most bytes in one I2C_RDWR message (i2c-dev.c refuses longer with EINVAL)."""
I2C_SMBUS_BLOCK_MAX: Final = 32
"""Most data bytes of an SMBus block write (smbus2 refuses more with ValueError)."""


class I2CMessage(Protocol):
    """What i2c_rdwr reads of an smbus2.i2c_msg: address, flags, length and a ctypes char buffer."""

    addr: int
    flags: int
    len: int
    buf: ctypes._Pointer[ctypes.c_char]


class SimSMBus:
    """smbus2.SMBus stand-in: ``i2c_rdwr``, ``write_i2c_block_data``, ``write_byte_data``, ``write_byte``, ``close``."""

    def __init__(self, *devices: BusDevice, clock: Clock | None = None, clock_hz: float = 400_000) -> None:
        if not devices and clock is None:
            raise InvalidArgument("SimSMBus needs a device or a clock")
        if not clock_hz > 0:
            raise InvalidArgument(f"SimSMBus: clock_hz must be positive, got {clock_hz!r}")
        self.devices = devices
        self.clock = clock if clock is not None else devices[0].clock
        self.clock_hz = float(clock_hz)
        self.transactions = 0
        """I2C transactions (START ... STOP) that reached the wire, acknowledged or not."""
        self._open = True

    def __enter__(self) -> SimSMBus:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None) -> None:
        self.close()

    def open(self, bus: int | str) -> None:
        """Reopen after ``close`` (any bus number or path reaches the same devices)."""
        self._open = True

    def close(self) -> None:
        """Close the bus; later calls fail with EBADF."""
        self._open = False

    def i2c_rdwr(self, *i2c_msgs: I2CMessage) -> None:
        """One combined transaction: the messages with repeated STARTs, one STOP; reads fill their buffers."""
        if not 0 < len(i2c_msgs) <= I2C_RDWR_MAX_MSGS:
            raise OSError(errno.EINVAL, f"Invalid argument: {len(i2c_msgs)} messages (1..{I2C_RDWR_MAX_MSGS})")
        for msg in i2c_msgs:
            if msg.len > I2C_RDWR_MAX_LEN:
                raise OSError(errno.EINVAL, f"Invalid argument: message of {msg.len} bytes (most {I2C_RDWR_MAX_LEN})")
        self._transaction(
            [(msg.addr, b"", msg) if msg.flags & I2C_M_RD else (msg.addr, ctypes.string_at(msg.buf, msg.len), None)
             for msg in i2c_msgs]
        )

    def write_i2c_block_data(
        self, i2c_addr: int, register: int, data: Sequence[int], force: bool | None = None
    ) -> None:
        """SMBus I2C block write: one transaction of ``[register, *data]`` (at most 32 data bytes)."""
        if len(data) > I2C_SMBUS_BLOCK_MAX:
            raise ValueError(f"Data length cannot exceed {I2C_SMBUS_BLOCK_MAX} bytes")  # smbus2's own error type
        self._transaction([(i2c_addr, bytes([register, *data]), None)])

    def write_byte_data(self, i2c_addr: int, register: int, value: int, force: bool | None = None) -> None:
        """SMBus write byte data: one transaction ``[register, value]``."""
        self._transaction([(i2c_addr, bytes([register, value]), None)])

    def write_byte(self, i2c_addr: int, value: int, force: bool | None = None) -> None:
        """SMBus send byte: one transaction ``[value]``."""
        self._transaction([(i2c_addr, bytes([value]), None)])

    def _transaction(self, messages: Sequence[tuple[int, bytes, I2CMessage | None]]) -> None:
        """Run one START ... STOP: each message a write of its bytes, or a read into the i2c_msg given."""
        if not self._open:
            raise OSError(errno.EBADF, "Bad file descriptor")
        payload_bytes = sum(read_into.len if read_into is not None else len(payload)
                            for _, payload, read_into in messages)
        try:
            for address, payload, read_into in messages:
                if read_into is not None:
                    self._read(address, read_into)
                else:
                    self._deliver(address, payload)
        finally:
            self.transactions += 1
            if isinstance(self.clock, SimulatedClock):
                self.clock.advance(i2c_wire_seconds(payload_bytes, self.clock_hz, restarts=len(messages) - 1))

    def _deliver(self, address: int, payload: bytes) -> None:
        for device in self.devices:
            device.advance_to(self.clock.now())
            if device.i2c_write(address, payload):
                return
        raise _nak(address)

    def _read(self, address: int, msg: I2CMessage) -> None:
        for device in self.devices:
            device.advance_to(self.clock.now())
            answer = device.i2c_read(address, msg.len)
            if answer is not None:
                ctypes.memmove(msg.buf, bytes(answer[: msg.len]).ljust(msg.len, b"\xff"), msg.len)
                return
        raise _nak(address)


def _nak(address: int) -> OSError:
    return OSError(errno.EREMOTEIO, f"Remote I/O error (no acknowledgement from address 0x{address:02x})")

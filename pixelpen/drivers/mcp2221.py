"""An I2C adapter for the Microchip MCP2221A USB-I2C bridge over hidapi, with smbus2's ``i2c_rdwr``.

Facts (MCP2221A datasheet, section 3.1 "HID commands"; Adafruit Blinka's ``mcp2221.py``; Linux
``hid-mcp2221.c``).  Every command is one 64-byte HID output report (hidapi: a report ID 0 in front)
answered by one 64-byte input report whose byte 0 echoes the command and byte 1 is 0x00 when it
completed:

* ``0x10`` status / set parameters: byte 2 = 0x10 cancels the I2C transfer in progress (reply
  byte 2: 0x10 marked for cancellation, 0x11 already idle), byte 3 = 0x20 sets the I2C clock with
  byte 4 = 12 MHz / clock - 3 (reply byte 3: 0x20 taken, 0x21 refused while a transfer runs).
  The reply's byte 8 is the I2C engine's state (0x00 idle), byte 20 bit 6 is set when the last
  address was not acknowledged.
* ``0x90`` I2C write (``0x94`` without STOP, ``0x92`` repeated START): bytes 1-2 the transfer's
  total length (little-endian), byte 3 the address << 1, bytes 4.. up to 60 data bytes; a longer
  transfer is sent as several such reports, each repeating the header.  Reply byte 1 = 0x01 when
  the engine is still busy with the previous chunk (send it again), byte 2 the engine state.
* ``0x91`` I2C read (``0x93`` repeated START) asks for a length; ``0x40`` fetches the data (reply
  byte 1 0x41 while not ready, byte 3 the count, bytes 4.. up to 60 bytes).

A busy reply makes the adapter send the same chunk again (up to 50 times, 1 ms apart, as Blinka
does); a fatal engine state or an address NAK cancels the transfer and raises LinkError (errno
EREMOTEIO for a NAK, as Linux i2c-dev reports one).  A 1,025-byte SSD1306 data write takes 18 write
reports (17 x 60 + 5) plus a status report before and one after: at ~1 ms per USB full-speed report
round trip, about 20 ms.
"""

from __future__ import annotations

import ctypes
import errno
import logging
from collections.abc import Callable, Sequence
from typing import Any, Final, Protocol

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.errors import ConfigError, InvalidArgument, LinkError, LinkTimeout

log = logging.getLogger(__name__)

VID: Final = 0x04D8
PID: Final = 0x00DD
REPORT_SIZE: Final = 64
"""Bytes of every HID report the chip sends and receives."""
MAX_CHUNK: Final = 60
"""Data bytes in one I2C write report (64 minus the 4-byte header)."""
MAX_LENGTH: Final = 0xFFFF
"""Bytes in one I2C transfer (a 16-bit length)."""
BASE_CLOCK: Final = 12_000_000
"""The chip's 12 MHz I2C clock base: divider = BASE_CLOCK // clock_hz - 3."""
MAX_CLOCK_HZ: Final = 400_000
MIN_CLOCK_HZ: Final = BASE_CLOCK // (255 + 3) + 1
"""The slowest clock whose divider fits a byte (46,512 Hz)."""

CMD_STATUS: Final = 0x10
CMD_READ_DATA: Final = 0x40
CMD_WRITE: Final = 0x90
CMD_WRITE_REPEATED_START: Final = 0x92
CMD_WRITE_NO_STOP: Final = 0x94
CMD_READ: Final = 0x91
CMD_READ_REPEATED_START: Final = 0x93
CANCEL: Final = 0x10
SET_SPEED: Final = 0x20
SPEED_REFUSED: Final = 0x21

STATE_IDLE: Final = 0x00
STATE_WRITING_NO_STOP: Final = 0x45
FATAL_STATES: Final = {0x12: "START timeout", 0x23: "address timeout", 0x25: "address not acknowledged",
                       0x44: "data write timeout", 0x52: "data read timeout", 0x62: "STOP timeout"}
"""Engine states a transfer does not recover from (Blinka's list from Microchip's C driver)."""
STATUS_STATE: Final = 8
STATUS_NAK: Final = 20
NAK_BIT: Final = 0x40
RETRIES: Final = 50
"""Attempts of a busy chunk or a status poll before giving up (Blinka's MCP2221_RETRY_MAX)."""
RETRY_WAIT: Final = 0.001
I2C_M_RD: Final = 0x0001


class HidDevice(Protocol):
    """What the adapter uses of cython-hidapi's ``hid.device``."""

    def write(self, buff: Sequence[int] | bytes) -> int:
        """Send one output report (report ID first)."""

    def read(self, max_length: int, timeout_ms: int = 0) -> list[int]:
        """One input report, or an empty list when none came within ``timeout_ms``."""

    def close(self) -> None:
        """Release the device."""


class MCP2221:
    """smbus2-like I2C adapter (``i2c_rdwr``) over an MCP2221A reached through a hidapi device."""

    def __init__(
        self, hid_device: HidDevice, *, clock_hz: float = MAX_CLOCK_HZ, timeout: float = 0.5,
        clock: Clock = REAL_CLOCK, name: str = "mcp2221",
    ) -> None:
        self.hid = hid_device
        self.name = name
        self.timeout = timeout
        self.clock = clock
        self.reports = 0
        """Output reports sent so far (all commands)."""
        self._closed = False
        self.clock_hz = float(clock_hz)
        self.set_clock(clock_hz)

    @classmethod
    def open(
        cls, vid: int = VID, pid: int = PID, serial: str | None = None, clock_hz: float = MAX_CLOCK_HZ,
        **options: Any,
    ) -> MCP2221:
        """Open the first (or the ``serial``-numbered) MCP2221A through hidapi and set its I2C clock."""
        try:
            import hid
        except ImportError:
            raise ConfigError("the MCP2221A needs hidapi: pip install hidapi (the module is named 'hid')") from None
        device = hid.device()
        try:
            device.open(vid, pid, serial)
        except OSError as exc:
            which = f"{vid:04x}:{pid:04x}" + (f" serial {serial}" if serial else "")
            raise LinkError(f"mcp2221: cannot open USB HID device {which}: {exc} (is it plugged in, and may this "
                            "user open its /dev/hidraw node?)") from None
        return cls(device, clock_hz=clock_hz, **options)

    def set_clock(self, clock_hz: float) -> None:
        """Set the I2C clock (46.5 kHz .. 400 kHz), cancelling a stuck transfer first if the chip refuses."""
        if not MIN_CLOCK_HZ <= clock_hz <= MAX_CLOCK_HZ:
            raise ConfigError(f"{self.name}: I2C clock {clock_hz:g} Hz is outside {MIN_CLOCK_HZ}..{MAX_CLOCK_HZ} Hz")
        divider = int(BASE_CLOCK // clock_hz) - 3
        for _ in range(2):
            reply = self._transfer(bytes((CMD_STATUS, 0, 0, SET_SPEED, divider)), "set the I2C clock")
            if reply[3] != SPEED_REFUSED:
                self.clock_hz = BASE_CLOCK / (divider + 3)
                return
            self.cancel()
        raise LinkError(f"{self.name}: the chip refused the I2C clock while a transfer runs (cancel did not help)")

    def status(self) -> bytes:
        """The 64-byte status report (engine state at byte 8, address NAK at byte 20 bit 6)."""
        return self._transfer(bytes((CMD_STATUS,)), "read the I2C status")

    def cancel(self) -> None:
        """Cancel the I2C transfer in progress and release the bus."""
        reply = self._transfer(bytes((CMD_STATUS, 0, CANCEL)), "cancel the I2C transfer")
        if reply[2] == CANCEL:
            self.clock.sleep(RETRY_WAIT)  # releasing the bus takes "a few hundred microseconds"

    def i2c_rdwr(self, *msgs: Any) -> None:
        """Run smbus2 ``i2c_msg`` messages in order: writes, and reads filled in place (repeated START between)."""
        for i, msg in enumerate(msgs):
            address, flags, length = int(msg.addr), int(msg.flags), int(msg.len)
            follows_write = i > 0 and not int(msgs[i - 1].flags) & I2C_M_RD
            if flags & I2C_M_RD:
                data = self.read(address, length, repeated_start=follows_write)
                ctypes.memmove(msg.buf, data, len(data))
            else:
                next_reads = i + 1 < len(msgs) and int(msgs[i + 1].flags) & I2C_M_RD
                self.write(address, bytes(msg), stop=not next_reads)

    def write(self, address: int, payload: bytes, *, stop: bool = True) -> None:
        """One I2C write transaction of up to 65,535 bytes, in reports of 60; LinkError (EREMOTEIO) on a NAK."""
        self._check(address, len(payload))
        command = CMD_WRITE if stop else CMD_WRITE_NO_STOP
        self._make_idle()
        header = bytes((command, len(payload) & 0xFF, len(payload) >> 8, address << 1))
        for start in range(0, max(len(payload), 1), MAX_CHUNK):
            self._retry(
                header + payload[start : start + MAX_CHUNK], f"write {len(payload)} bytes to {address:#04x}",
                lambda reply: reply[1] == 0, address, "write",
                f"I2C engine stayed busy writing to {address:#04x} at byte {start}",
            )
        self._wait_idle(address, "write", ok_no_stop=not stop)

    def read(self, address: int, length: int, *, repeated_start: bool = False) -> bytes:
        """One I2C read transaction of ``length`` bytes; LinkError (EREMOTEIO) on a NAK."""
        self._check(address, length)
        if not repeated_start:
            self._make_idle()
        command = CMD_READ_REPEATED_START if repeated_start else CMD_READ
        reply = self._transfer(bytes((command, length & 0xFF, length >> 8, (address << 1) | 1)),
                               f"read {length} bytes from {address:#04x}")
        if reply[1] != 0:
            self.cancel()
            raise LinkError(f"{self.name}: the chip refused to read from {address:#04x} (engine state "
                            f"{reply[2]:#04x})")
        out = bytearray()
        while len(out) < length:
            reply = self._retry(
                bytes((CMD_READ_DATA,)), f"fetch read data from {address:#04x}",
                lambda reply: reply[1] == 0 and 0 < reply[3] <= MAX_CHUNK, address, "read",
                f"no read data from {address:#04x} after {len(out)} of {length} bytes",
            )
            out += reply[4 : 4 + reply[3]]
        return bytes(out[:length])

    def close(self) -> None:
        """Release the HID device; idempotent."""
        if not self._closed:
            self._closed = True
            self.hid.close()

    def __enter__(self) -> MCP2221:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- helpers ---------------------------------------------------------------------------------

    def _check(self, address: int, length: int) -> None:
        if not 0 <= address <= 0x7F:
            raise InvalidArgument(f"{self.name}: I2C address {address:#x} is not a 7-bit address")
        if not 0 <= length <= MAX_LENGTH:
            raise InvalidArgument(f"{self.name}: an I2C transfer moves 0..{MAX_LENGTH} bytes, got {length}")

    def _make_idle(self) -> None:
        if self.status()[STATUS_STATE] != STATE_IDLE:
            self.cancel()

    def _check_state(self, state: int, address: int, what: str) -> None:
        """LinkError (and a cancel) when the engine reports a state it does not recover from."""
        if state in FATAL_STATES:
            self.cancel()
            if state == 0x25:
                raise LinkError(errno.EREMOTEIO, f"{self.name}: no device acknowledged address {address:#04x}")
            raise LinkError(errno.EIO, f"{self.name}: I2C {what} at {address:#04x} failed: {FATAL_STATES[state]}")

    def _retry(
        self, report: bytes, what: str, done: Callable[[bytes], bool], address: int, op: str, failure: str
    ) -> bytes:
        """Send ``report`` until its answer is ``done`` (RETRIES tries); a fatal state or none: cancel, LinkError."""
        for _ in range(RETRIES):
            reply = self._transfer(report, what)
            if done(reply):
                return reply
            self._check_state(reply[2], address, op)
            self.clock.sleep(RETRY_WAIT)
        self.cancel()
        raise LinkError(f"{self.name}: {failure}")

    def _wait_idle(self, address: int, what: str, ok_no_stop: bool) -> None:
        """Poll the status until the engine is idle (or holds the bus without STOP); NAK and fatal states raise."""
        state = STATE_IDLE
        for _ in range(RETRIES):
            status = self.status()
            state = status[STATUS_STATE]
            if status[STATUS_NAK] & NAK_BIT:
                self.cancel()
                raise LinkError(errno.EREMOTEIO, f"{self.name}: no device acknowledged address {address:#04x}")
            self._check_state(state, address, what)
            if state == STATE_IDLE or (ok_no_stop and state == STATE_WRITING_NO_STOP):
                return
            self.clock.sleep(RETRY_WAIT)
        self.cancel()
        raise LinkError(f"{self.name}: I2C {what} at {address:#04x} did not finish (engine state {state:#04x})")

    def _transfer(self, report: bytes, what: str) -> bytes:
        """Send one output report and read its 64-byte answer (LinkTimeout when none comes in time)."""
        if self._closed:
            raise LinkError(f"{self.name}: the adapter is closed")
        try:
            self.hid.write(b"\x00" + report + bytes(REPORT_SIZE - len(report)))
            self.reports += 1
            reply = bytes(self.hid.read(REPORT_SIZE, max(1, int(self.timeout * 1000))))
        except (OSError, ValueError) as exc:
            raise LinkError(f"{self.name}: cannot {what}: {exc}") from None
        if not reply:
            raise LinkTimeout(f"{self.name}: no answer within {self.timeout:g} s to {what}")
        if len(reply) < REPORT_SIZE or reply[0] != report[0]:
            raise LinkError(f"{self.name}: bad answer to {what} (command {report[0]:#04x}): {reply[:8].hex(' ')}")
        return reply

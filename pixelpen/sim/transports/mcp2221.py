"""A fake cython-hidapi ``hid.device`` that is an MCP2221A USB-I2C bridge in front of a BusDevice.

Speaks the HID command set of the MCP2221A datasheet (section 3.1) that an I2C host uses: every
write is one 64-byte output report (report ID 0 first, as hidapi wants) and most commands queue one
64-byte input report for ``read``:

* ``0x10`` status / set parameters: cancel (byte 2 = 0x10; reply byte 2 0x10 cancelled, 0x11 idle
  already), set the I2C clock (byte 3 = 0x20, byte 4 = 12 MHz / clock - 3; reply byte 3 0x20, or 0x21
  while a transfer runs); the reply carries the engine state (byte 8), the requested and sent
  lengths (9-12), the clock divider (14), the address (16) and the address-NAK flag (byte 20, bit 6).
* ``0x90``/``0x92``/``0x94`` I2C write (STOP / repeated START / no STOP): the chunks of one transfer
  (each report repeats the length and address header; up to 60 data bytes) are collected and the
  whole payload goes to ``device.i2c_write(address, payload)`` when the last one arrives; a False
  answer sets the NAK flag and state 0x25.  A chunk sent while the engine still clocks out the
  previous one is refused with byte 1 = 0x01 (busy) and the engine state in byte 2.
* ``0x91``/``0x93`` I2C read asks ``device.i2c_read(address, length)`` (None: NAK) and ``0x40``
  hands the bytes out 60 at a time (byte 2 0x55 read complete / 0x54 partial, byte 3 the count);
  after a NAK byte 2 is 0x25.
* ``0x70`` reset: no reply; the chip re-enumerates, so this handle is closed (open it again).
* GPIO, SRAM and flash commands (0x50, 0x51, 0x60, 0x61, 0xB0, 0xB1) are answered "done" with
  zeros and change nothing; any other command byte gets no reply (a host read times out).

Time: one report costs :data:`REPORT_SECONDS` (a USB full-speed interrupt exchange: the output
report goes out in one 1 ms frame, the answer comes back on the next IN poll), and a write chunk
keeps the engine busy for its I2C wire time: 9 clocks per byte (plus the address byte and START/STOP
on the first and last chunk) at the configured clock.  On a SimulatedClock the fake advances the
clock by the report time; a ``read`` that finds nothing waits its timeout there.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from typing import Final

from pixelpen.clock import Clock, SimulatedClock
from pixelpen.drivers.bus import I2C_CLOCKS_PER_BYTE, I2C_RESTART_CLOCKS, I2C_TRANSACTION_CLOCKS, i2c_wire_seconds
from pixelpen.sim.base import BusDevice
from pixelpen.sim.transports.boundedlog import BoundedLog

REPORT_SIZE: Final = 64
REPORT_SECONDS: Final = 0.001
"""One report's USB round trip (output report in one full-speed frame, answer on the next IN poll)."""
VID: Final = 0x04D8
PID: Final = 0x00DD
MAX_CHUNK: Final = 60
REPORT_LOG: Final = 10_000
"""Output reports ``reports`` keeps (a 128x64 SSD1306 frame is 20: the last 500 frames)."""
BASE_CLOCK: Final = 12_000_000
IDLE: Final = 0x00
ADDRESS_NAK: Final = 0x25
PARTIAL_DATA: Final = 0x41
WRITING_NO_STOP: Final = 0x45
READ_PARTIAL: Final = 0x54
READ_COMPLETE: Final = 0x55
NAK_BIT: Final = 0x40
_WRITES: Final = {0x90: True, 0x92: True, 0x94: False}  # command -> ends with STOP
_READS: Final = (0x91, 0x93)
_INERT: Final = (0x50, 0x51, 0x60, 0x61, 0xB0, 0xB1)


class SimMCP2221:
    """cython-hidapi's ``hid.device`` API (open, write, read, strings, close) for a simulated MCP2221A."""

    def __init__(
        self,
        device: BusDevice,
        *,
        clock: Clock | None = None,
        serial_number: str = "0001234567",
        path: bytes = b"sim-mcp2221",
    ) -> None:
        self.device = device
        self.clock = clock if clock is not None else device.clock
        self.serial_number = serial_number
        self.path = path
        self.reports: BoundedLog[bytes] = BoundedLog(REPORT_LOG)
        """The last REPORT_LOG output reports received (64 bytes each, report ID stripped; ``reports.dropped``:
        older ones), for tests."""
        self.divider = BASE_CLOCK // 100_000 - 3  # power-on default: 100 kHz
        self._open = False
        self._nonblocking = False
        self._replies: deque[bytes] = deque()
        self._reset_engine()

    # -- hid.device API ------------------------------------------------------------------------

    def open(self, vendor_id: int = 0, product_id: int = 0, serial_number: str | None = None) -> None:
        """Open by USB ids (0 matches any) and serial number, as hidapi does; OSError when they do not match."""
        if (vendor_id not in (0, VID) or product_id not in (0, PID)
                or serial_number not in (None, self.serial_number)):
            raise OSError("open failed")
        self._open = True

    def open_path(self, path: bytes | str) -> None:
        """Open by hidapi path (this fake's ``path``)."""
        if (path.encode() if isinstance(path, str) else bytes(path)) != self.path:
            raise OSError("open failed")
        self._open = True

    def close(self) -> None:
        """Close the handle (reopen with ``open``)."""
        self._open = False
        self._replies.clear()

    def set_nonblocking(self, v: int | bool) -> int:
        """Make ``read`` without a timeout return at once (it does anyway: a fake never blocks)."""
        self._nonblocking = bool(v)
        return 0

    def get_manufacturer_string(self) -> str:
        """The USB manufacturer string."""
        return "Microchip Technology Inc."

    def get_product_string(self) -> str:
        """The USB product string."""
        return "MCP2221 USB-I2C/UART Combo"

    def get_serial_number_string(self) -> str:
        """The USB serial number string."""
        return self.serial_number

    def error(self) -> str:
        """hidapi's last error text (none here)."""
        return ""

    def write(self, buff: Sequence[int] | bytes) -> int:
        """One output report: the report ID (0) and up to 64 bytes; returns the bytes written."""
        self._check_open()
        data = bytes(buff)
        if not data or data[0] != 0 or len(data) > REPORT_SIZE + 1:
            raise OSError(f"hid write failed: the MCP2221A takes report ID 0 and 64 bytes, got {len(data)} bytes")
        report = data[1:] + bytes(REPORT_SIZE + 1 - len(data))
        self.reports.append(report)
        if isinstance(self.clock, SimulatedClock):
            self.clock.advance(REPORT_SECONDS)
        self.device.advance_to(self.clock.now())
        self._command(report)
        return len(data)

    def read(self, max_length: int, timeout_ms: int = 0) -> list[int]:
        """The next input report (at most ``max_length`` bytes), or [] after ``timeout_ms`` with none."""
        self._check_open()
        if self._replies:
            return list(self._replies.popleft()[:max_length])
        if timeout_ms > 0 and isinstance(self.clock, SimulatedClock):
            self.clock.advance(timeout_ms / 1000.0)
        return []

    # -- the chip ------------------------------------------------------------------------------

    @property
    def clock_hz(self) -> float:
        """The I2C clock the divider gives."""
        return BASE_CLOCK / (self.divider + 3)

    def _check_open(self) -> None:
        if not self._open:
            raise ValueError("not open")

    def _reset_engine(self) -> None:
        self.state = IDLE
        self.nak = False
        self._command_byte = 0
        self._address = 0
        self._length = 0
        self._payload = bytearray()
        self._read_data = bytearray()
        self._busy_until = 0.0

    def _command(self, report: bytes) -> None:
        cmd = report[0]
        if cmd == 0x10:
            self._reply(self._status(report))
        elif cmd in _WRITES:
            self._reply(self._write(report))
        elif cmd in _READS:
            self._reply(self._start_read(report))
        elif cmd == 0x40:
            self._reply(self._fetch())
        elif cmd == 0x70:
            self._reset_engine()
            self.divider = BASE_CLOCK // 100_000 - 3
            self.close()
        elif cmd in _INERT:
            self._reply(bytes((cmd, 0)))

    def _reply(self, head: bytes) -> None:
        self._replies.append(head + bytes(REPORT_SIZE - len(head)))

    def _transfer_running(self) -> bool:
        settled = (IDLE, WRITING_NO_STOP, ADDRESS_NAK, READ_COMPLETE)
        return self.state not in settled or self.clock.now() < self._busy_until

    def _status(self, report: bytes) -> bytes:
        out = bytearray(REPORT_SIZE)
        out[0] = 0x10
        if report[2] == 0x10:
            out[2] = 0x10 if self.state != IDLE or self._payload else 0x11
            self._reset_engine()
        if report[3] == 0x20:
            if self._transfer_running():
                out[3] = 0x21
            else:
                self.divider = report[4]
                out[3], out[4] = 0x20, report[4]
        out[8] = self.state
        out[9], out[10] = self._length & 0xFF, self._length >> 8
        out[11], out[12] = len(self._payload) & 0xFF, len(self._payload) >> 8
        out[14] = self.divider
        out[16] = self._address << 1
        out[20] = NAK_BIT if self.nak else 0
        out[22] = out[23] = 1  # SCL and SDA idle high
        return bytes(out)

    def _write(self, report: bytes) -> bytes:
        cmd, length, address = report[0], report[1] | report[2] << 8, report[3] >> 1
        now = self.clock.now()
        continuing = self.state == PARTIAL_DATA and (cmd, address, length) == (self._command_byte, self._address,
                                                                               self._length)
        if self.state == ADDRESS_NAK or now < self._busy_until or (self.state == PARTIAL_DATA and not continuing):
            return bytes((cmd, 0x01, self.state))
        if not continuing:
            self._command_byte, self._address, self._length = cmd, address, length
            self._payload = bytearray()
            self.nak = False
        chunk = report[4 : 4 + min(MAX_CHUNK, length - len(self._payload))]
        self._payload += chunk
        start = 0 if continuing else I2C_RESTART_CLOCKS  # START and the address byte, as a repeated START's
        stop = I2C_TRANSACTION_CLOCKS - I2C_RESTART_CLOCKS if len(self._payload) == length else 0
        self._busy_until = now + (I2C_CLOCKS_PER_BYTE * len(chunk) + start + stop) / self.clock_hz
        if len(self._payload) < length:
            self.state = PARTIAL_DATA
        elif self.device.i2c_write(address, bytes(self._payload)):
            self.state = IDLE if _WRITES[cmd] else WRITING_NO_STOP
        else:
            self.state, self.nak = ADDRESS_NAK, True
        if len(self._payload) == length:
            self._payload = bytearray()
        return bytes((cmd, 0x00, self.state))

    def _start_read(self, report: bytes) -> bytes:
        cmd, length, address = report[0], report[1] | report[2] << 8, report[3] >> 1
        if self._transfer_running() and self.state != WRITING_NO_STOP:
            return bytes((cmd, 0x01, self.state))
        self._command_byte, self._address, self._length = cmd, address, length
        answer = self.device.i2c_read(address, length)
        self.nak = answer is None
        self._read_data = bytearray(answer[:length].ljust(length, b"\xff")) if answer is not None else bytearray()
        self.state = ADDRESS_NAK if answer is None else READ_PARTIAL
        self._busy_until = self.clock.now() + i2c_wire_seconds(length, self.clock_hz)
        return bytes((cmd, 0x00, self.state))

    def _fetch(self) -> bytes:
        if self.clock.now() < self._busy_until:
            return bytes((0x40, PARTIAL_DATA, self.state, 0))  # the bytes are still being clocked in
        if self.state == ADDRESS_NAK:
            return bytes((0x40, 0x00, ADDRESS_NAK, 0))
        if self.state != READ_PARTIAL:
            return bytes((0x40, 0x00, self.state, 0))
        chunk = bytes(self._read_data[:MAX_CHUNK])
        del self._read_data[:MAX_CHUNK]
        self.state = READ_PARTIAL if self._read_data else IDLE
        return bytes((0x40, 0x00, READ_PARTIAL if self._read_data else READ_COMPLETE, len(chunk))) + chunk

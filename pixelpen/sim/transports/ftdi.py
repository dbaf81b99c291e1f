"""A pyusb backend presenting an FTDI FT232H (MPSSE) to pyftdi, its SPI bytes going to a BusDevice.

``Ft232hBackend(device).find()`` is a ``usb.core.Device`` that ``pyftdi.spi.SpiController().configure(...)``
accepts in place of a URL (pyftdi's supported way to open a device found by the caller; no global
state).  For ``ftdi://`` URLs pyftdi's ``UsbTools`` loads the modules named in ``UsbTools.BACKENDS``
and calls their ``get_backend()`` (what pyftdi's own virtual test backend relies on):
:func:`use_for_urls` does that for the duration of a ``with``.

The device (USB 2.0 high speed, VID 0403 PID 6014 bcdDevice 0x0900, one interface of class 0xFF with
bulk IN 0x81 and bulk OUT 0x02 of 512 bytes) answers, written from FTDI's AN_108 (MPSSE command set)
and the FT232H datasheet rather than from pyftdi:

* vendor requests (type 0x40, index = port 1): reset (0; value 0 reset, 1 purge RX, 2 purge TX), modem
  control (1), flow control (2), baud rate (3), data characteristics (4), event and error characters
  (6, 7), latency timer (9), bit mode (0x0B: value = mode << 8 | direction; 0x02 MPSSE); type 0xC0:
  modem status (5, 2 bytes), latency (0x0A), pins (0x0C); an EEPROM read (0x90) answers 0xFFFF (blank);
* MPSSE on bulk OUT (commands may span bulk transfers): 0x80/0x82 set ADBUS/ACBUS value + direction,
  0x81/0x83 read them, 0x84/0x85 loopback on/off, 0x86 clock divisor, 0x87 send immediate, 0x8A/0x8B
  divide-by-5 off/on, 0x8C/0x8D 3-phase clocking on/off, 0x8E/0x8F clock without data, 0x96/0x97 adaptive
  clocking on/off, 0x9E drive-only-zero; data shifting 0x10-0x3F by AN_108's bit fields (bit 0 -ve
  write edge, bit 1 bits not bytes, bit 3 LSB first, bit 4 write TDI, bit 5 read TDO; bit 2 -ve read
  edge): written bytes go to the device, read bytes are the device's MISO bytes (loopback: the written
  ones; a read-only shift sends the device zeros); TMS commands (bit 6) and any other opcode are
  answered 0xFA and the opcode, as the chip reports a bad command;
* bulk IN: packets of at most 512 bytes, each starting with the two modem-status bytes 0x32 0x60;
  with nothing to send, the two status bytes alone once the latency timer has run out.

Chip select is ADBUS3 (active low): bytes shifted while it is low form one frame, delivered as
``device.spi_transfer(frame, dc=level)`` when it rises, ``dc`` being the level of the D/C pin
(``dc``, GPIO bit 4 = ADBUS4 by default; bits 8-15 are ACBUS0-7).  A D/C change inside a frame
delivers the part before it as its own frame; a read delivers the frame so far at once (MISO is
needed now).  Bytes shifted with chip select high reach nothing (``unselected_bytes``).  The reset
pin (``rst``, default bit 5) drives ``device.set_line("reset", level)``.  LSB-first bytes are
bit-reversed so the device always sees what it would clock in MSB first; bit-mode shifts deliver
their partial byte as one byte.

Time (advanced on a SimulatedClock): every bulk transfer costs the host a 125 us high-speed
microframe plus its bytes at 40 MB/s.  Shifting costs 8 clock periods a byte (x 1.5 with 3-phase
clocking) at the MPSSE clock, 60 MHz (or 12 MHz with divide-by-5) / ((1 + divisor) * 2); every byte
of the MPSSE stream is counted so as it arrives (a command's own few bytes too: a small
overestimate), plus the clocks of reads and of 0x8E/0x8F.  The engine shifts while USB brings the
next bytes: a bulk OUT waits only while the 1 KiB FIFO is full, a bulk IN with answers waits until
the engine has produced them.  A long SPI write is therefore shift-bound, as on the chip.
"""

from __future__ import annotations

import contextlib
import errno
import sys
import types
from collections.abc import Iterator
from typing import Any, Final

import usb.core

from pixelpen.clock import Clock, SimulatedClock
from pixelpen.errors import Disconnected
from pixelpen.sim.base import BusDevice
from pixelpen.sim.transports.boundedlog import BoundedLog
from pixelpen.sim.transports.usbbackend import SPEED_HIGH, SimUsbBackend, fill

VID: Final = 0x0403
PID: Final = 0x6014
BCD_DEVICE: Final = 0x0900
EP_IN: Final = 0x81
EP_OUT: Final = 0x02
MAX_PACKET: Final = 512
MODEM_STATUS: Final = b"\x32\x60"
"""Modem status bytes heading every bulk IN packet (CTS/DSR set; transmitter holding and shift registers empty)."""
MICROFRAME: Final = 125e-6
FIFO_SIZE: Final = 1024
"""The FT232H's TX FIFO (host to chip)."""
USB_BYTES_PER_S: Final = 40e6
CS_BIT: Final = 0x08
BAD_COMMAND: Final = 0xFA
MPSSE_MODE: Final = 0x02
COMMAND_LOG: Final = 100_000
"""MPSSE opcodes ``commands`` keeps (luma sends a 240x240 RGB565 frame in about 190: the last 500 frames)."""
CONTROL_LOG: Final = 1_000
"""Vendor requests ``control`` keeps (pyftdi sends 16 when it opens the chip)."""
_REVERSED: Final = bytes(int(f"{b:08b}"[::-1], 2) for b in range(256))
_ONE_PARAM: Final = {0x8E: 1, 0x8F: 2, 0x86: 2, 0x80: 2, 0x82: 2, 0x9E: 2}  # opcode -> parameter bytes
_NO_PARAM: Final = frozenset((0x81, 0x83, 0x84, 0x85, 0x87, 0x88, 0x89, 0x8A, 0x8B, 0x8C, 0x8D, 0x96, 0x97))
_STRINGS: Final = {1: "FTDI", 2: "Single RS232-HS"}


class Ft232hBackend(SimUsbBackend):
    """pyusb IBackend for one simulated FT232H whose MPSSE SPI drives ``device`` (see the module docstring)."""

    def __init__(
        self, device: BusDevice, *, dc: int = 4, rst: int | None = 5, clock: Clock | None = None,
        serial_number: str = "FTSIM001", bus: int = 1, address: int = 3,
    ) -> None:
        super().__init__(
            kind="pixelpen-ft232h", vid=VID, pid=PID, bcd_device=BCD_DEVICE, speed=SPEED_HIGH,
            strings={**_STRINGS, 3: serial_number}, interface=(0xFF, 0xFF, 0xFF), interface_string=2,
            endpoints=(EP_IN, EP_OUT), max_packet=MAX_PACKET, self_powered=False, bus=bus, address=address,
        )
        self.device = device
        self.clock = clock if clock is not None else device.clock
        self.dc_bit = 1 << dc
        self.rst_bit = 1 << rst if rst is not None else 0
        self.commands: BoundedLog[int] = BoundedLog(COMMAND_LOG)
        """The last COMMAND_LOG MPSSE opcodes executed, in order (``commands.dropped``: older ones), for tests."""
        self.control: BoundedLog[tuple[int, int, int, int]] = BoundedLog(CONTROL_LOG)
        """The last CONTROL_LOG vendor control requests: (bmRequestType, bRequest, wValue, wIndex)."""
        self.unselected_bytes = 0
        self.bitmode = 0
        self.latency_ms = 16
        self.divisor = 0
        self.divide_by_5 = True
        self.three_phase = False
        self.adaptive = False
        self.loopback = False
        self.pins = 0  # ADBUS | ACBUS << 8 output levels
        self.direction = 0
        self._pending = bytearray()
        self._engine_until = 0.0
        self._in = bytearray()
        self._frame = bytearray()
        self._frame_dc = False
        self._closed = False

    def find(self) -> usb.core.Device:
        """The simulated FT232H as a pyusb Device, for ``SpiController().configure(device)``."""
        found = usb.core.find(idVendor=VID, idProduct=PID, backend=self)
        if not isinstance(found, usb.core.Device):
            raise Disconnected("simulated FT232H: unplugged (close() was called)")
        return found

    @property
    def mpsse_clock_hz(self) -> float:
        """The shift clock the divisor and divide-by-5 setting give."""
        base = 12e6 if self.divide_by_5 else 60e6
        return base / ((1 + self.divisor) * 2)

    def close(self) -> None:
        """Unplug: every later request fails with "No such device"."""
        self._closed = True

    def enumerate_devices(self) -> list[Any]:
        """The one simulated device, until it is unplugged."""
        return [] if self._closed else [self._ident]

    def reset_device(self, dev_handle: Any) -> None:
        """USB reset: back to the power-on state."""
        self._check_present()
        self._reset_chip()

    # -- control transfers --------------------------------------------------------------------

    def ctrl_transfer(
        self, dev_handle: Any, bmRequestType: int, bRequest: int, wValue: int, wIndex: int, data: Any, timeout: int
    ) -> int:
        """Standard GET_DESCRIPTOR/GET_STATUS/GET_CONFIGURATION and the FTDI vendor requests; a microframe each."""
        self._check_present()
        self._spend(MICROFRAME)
        return super().ctrl_transfer(dev_handle, bmRequestType, bRequest, wValue, wIndex, data, timeout)

    def _request(self, request_type: int, request: int, value: int, index: int) -> bytes | None:
        """The FTDI vendor requests: OUT (0x40) ones act, IN (0xC0) ones answer."""
        if request_type == 0x40:
            self.control.append((request_type, request, value, index))
            return b"" if self._vendor_out(request, value) else None
        if request_type == 0xC0:
            self.control.append((request_type, request, value, index))
            return {0x05: MODEM_STATUS, 0x0A: bytes((self.latency_ms,)), 0x0C: bytes((self.pins & 0xFF,)),
                    0x90: b"\xff\xff"}.get(request)
        return None

    def _vendor_out(self, request: int, value: int) -> bool:
        """Apply a vendor OUT request; False for one the chip does not know."""
        if request == 0x00:
            if value == 0:
                self._reset_chip()
            elif value == 1:
                self._pending.clear()  # purge RX: host-to-chip bytes not yet executed
            elif value == 2:
                self._in.clear()  # purge TX: chip-to-host bytes not yet read
        elif request == 0x09:
            self.latency_ms = max(1, value & 0xFF)
        elif request == 0x0B:
            self.bitmode = value >> 8
            if self.bitmode == MPSSE_MODE:
                self.direction = (self.direction & 0xFF00) | (value & 0xFF)
        return request in (0x00, 0x01, 0x02, 0x03, 0x04, 0x06, 0x07, 0x09, 0x0B)

    def _reset_chip(self) -> None:
        self._pending.clear()
        self._in.clear()
        self.bitmode = 0

    # -- bulk transfers -----------------------------------------------------------------------

    def bulk_write(self, dev_handle: Any, ep: int, intf: int, data: Any, timeout: int) -> int:
        """Bulk OUT: MPSSE commands (in other bit modes the bytes are dropped)."""
        self._check_endpoint(ep, EP_OUT, intf)
        payload = bytes(data)
        self._spend(MICROFRAME + len(payload) / USB_BYTES_PER_S)
        backlog = self._engine_until - self.clock.now() - FIFO_SIZE * 8 / self.mpsse_clock_hz
        self._spend(backlog)  # the 1 KiB FIFO is full until the engine has shifted enough out
        if self.bitmode == MPSSE_MODE:
            self._shift_for(self._byte_seconds * len(payload))  # counted as it arrives: see the module docstring
            self._pending += payload
            self._run()
        return len(payload)

    def bulk_read(self, dev_handle: Any, ep: int, intf: int, buff: Any, timeout: int) -> int:
        """Bulk IN: packets of 512 bytes, each headed by the two modem-status bytes."""
        self._check_endpoint(ep, EP_IN, intf)
        if len(buff) < 2:
            raise usb.core.USBError("Overflow: buffer smaller than the modem status", -8, errno.EOVERFLOW)
        if not self._in:
            self._spend(self.latency_ms / 1000.0)
        else:
            self._spend(self._engine_until - self.clock.now())  # answers exist once the engine got there
        out = bytearray()
        while len(out) + 2 <= len(buff):
            take = min(MAX_PACKET - 2, len(buff) - len(out) - 2, len(self._in))
            out += MODEM_STATUS + self._in[:take]
            del self._in[:take]
            if not self._in:
                break
        self._spend(MICROFRAME)
        return fill(buff, bytes(out))

    # -- the MPSSE engine ---------------------------------------------------------------------

    def _run(self) -> None:
        """Execute every complete command in the pending bytes."""
        pending = self._pending
        at = 0
        while at < len(pending):
            op = pending[at]
            size = self._command_size(op, pending, at)
            if size is None:
                break  # wait for the rest of the command
            self._execute(op, bytes(pending[at + 1 : at + size]))
            at += size
        del pending[:at]

    @staticmethod
    def _command_size(op: int, buf: bytearray, at: int) -> int | None:
        """Bytes of the command at ``at`` (opcode included), or None when they have not all arrived."""
        avail = len(buf) - at
        if 0x10 <= op <= 0x3F:
            if op & 0x02:  # bit mode: length byte (+ one data byte when writing)
                size = 2 + (1 if op & 0x10 else 0)
            elif avail < 3:
                return None
            else:
                length = buf[at + 1] | buf[at + 2] << 8
                size = 3 + (length + 1 if op & 0x10 else 0)
        elif op in _ONE_PARAM:
            size = 1 + _ONE_PARAM[op]
        else:
            size = 1
        return size if avail >= size else None

    def _execute(self, op: int, args: bytes) -> None:
        self.commands.append(op)
        if 0x10 <= op <= 0x3F:
            self._shift(op, args)
        elif op in (0x80, 0x82):
            self._set_pins(op, args[0], args[1])
        elif op in (0x81, 0x83):
            self._in.append((self.pins >> (0 if op == 0x81 else 8)) & 0xFF)
        elif op == 0x86:
            self.divisor = args[0] | args[1] << 8
        elif op in (0x84, 0x85):
            self.loopback = op == 0x84
        elif op in (0x8A, 0x8B):
            self.divide_by_5 = op == 0x8B
        elif op in (0x8C, 0x8D):
            self.three_phase = op == 0x8C
        elif op in (0x96, 0x97):
            self.adaptive = op == 0x96
        elif op in (0x8E, 0x8F):
            count = args[0] + 1 if op == 0x8E else 8 * ((args[0] | args[1] << 8) + 1)
            self._shift_for(count / self.mpsse_clock_hz)
        elif op in _NO_PARAM or op == 0x9E:
            pass  # send immediate, wait-on-I/O, drive-zero: nothing to simulate
        else:
            self._in += bytes((BAD_COMMAND, op))

    def _shift(self, op: int, args: bytes) -> None:
        """A data-shifting command: bytes (or bits) out to the frame, MISO bytes back when it reads."""
        writes, reads, bits, lsb = bool(op & 0x10), bool(op & 0x20), bool(op & 0x02), bool(op & 0x08)
        if bits:
            count = 1
            out = args[1:2] if writes else b"\x00"
        else:
            count = (args[0] | args[1] << 8) + 1
            out = args[2:] if writes else bytes(count)
        if lsb:
            out = out.translate(_REVERSED)
        if not writes:
            self._shift_for(self._byte_seconds * count)  # a read-only shift's clocks are not in the stream
        miso = bytes(len(out))
        if self.pins & CS_BIT:
            self.unselected_bytes += len(out)
        else:
            self._frame += out
            if reads:
                miso = self._deliver()[-len(out) :].rjust(len(out), b"\x00")
        if reads:
            back = out if self.loopback else miso
            self._in += back.translate(_REVERSED) if lsb else back

    def _set_pins(self, op: int, value: int, direction: int) -> None:
        shift = 0 if op == 0x80 else 8
        mask = 0xFF << shift
        before = self.pins
        self.direction = (self.direction & ~mask) | (direction << shift)
        self.pins = (self.pins & ~mask) | ((value & direction) << shift)
        changed = before ^ self.pins
        if changed & self.dc_bit and self._frame:
            self._deliver()  # D/C moved inside a frame: what went before is its own transfer
        if changed & CS_BIT and self.pins & CS_BIT:
            self._deliver()
        self._frame_dc = bool(self.pins & self.dc_bit)
        if self.rst_bit and changed & self.rst_bit:
            self.device.set_line("reset", bool(self.pins & self.rst_bit))

    def _deliver(self) -> bytes:
        """Hand the frame collected so far to the device; its MISO bytes."""
        if not self._frame:
            return b""
        frame, self._frame = bytes(self._frame), bytearray()
        self.device.advance_to(self.clock.now())
        return bytes(self.device.spi_transfer(frame, dc=self._frame_dc))

    # -- helpers ------------------------------------------------------------------------------

    @property
    def _byte_seconds(self) -> float:
        return 8 * (1.5 if self.three_phase else 1.0) / self.mpsse_clock_hz

    def _shift_for(self, seconds: float) -> None:
        """Queue ``seconds`` of clocking on the MPSSE engine (it runs while USB brings the next bytes)."""
        self._engine_until = max(self._engine_until, self.clock.now()) + seconds

    def _spend(self, seconds: float) -> None:
        if isinstance(self.clock, SimulatedClock):
            self.clock.advance(seconds)

    def _absence(self) -> str | None:
        return "it may have been disconnected" if self._closed else None


@contextlib.contextmanager
def use_for_urls(backend: Ft232hBackend) -> Iterator[None]:
    """Within the ``with``, pyftdi's ``ftdi://`` URLs find ``backend``'s FT232H (UsbTools.BACKENDS swapped)."""
    from pyftdi.usbtools import UsbTools

    name = f"pixelpen_sim_ft232h_{id(backend):x}"
    module = types.ModuleType(name)
    module.get_backend = lambda *args, **kwargs: backend  # type: ignore[attr-defined]
    saved = UsbTools.BACKENDS
    sys.modules[name] = module
    UsbTools.BACKENDS = (name,)
    UsbTools.flush_cache()
    try:
        yield
    finally:
        UsbTools.BACKENDS = saved
        UsbTools.flush_cache()
        del sys.modules[name]

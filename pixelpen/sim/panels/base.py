"""PanelSim: the bus front shared by the panel simulators (4-wire SPI, I2C control bytes, RESET), bus time, events.

Bus time (``BusStats.bus_seconds``) is ``drivers.bus``'s wire-time model, the one the simulated transports
advance a SimulatedClock by: SPI 8 clocks per byte; I2C per write transaction 1 START + 9 clocks per byte
(the address byte included: 8 bits + ACK) + 1 STOP.  An SSD1306 frame over I2C at 400 kHz
(``[00 21 00 7F 22 00 07]``, ``[40 + 1024 bytes]``: 1,032 bytes after the addresses) is 9,310 clocks = 23.3 ms.
The bus calls take bytes-like values only (``WireBytes``): an int would be ``bytes(n)``, n NUL bytes.
Also what the simulators' registrations share: ``register_panel_simulators``.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, fields
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from pixelpen.clock import Clock
from pixelpen.drivers.bus import i2c_wire_seconds, spi_wire_seconds
from pixelpen.errors import ConfigError, InvalidArgument, InvalidArgumentType, ProtocolError, quote_token
from pixelpen.options import I2C_ADDRESSES, OptionSpec, OptionValues, read_options
from pixelpen.sim.base import Fault, SimulatedDevice, register_simulator

log = logging.getLogger(__name__)

WireBytes = bytes | bytearray | memoryview | NDArray[np.uint8]
"""What the bus calls take (numpy arrays of other dtypes, ints, str and sequences are refused)."""

EVENT_LOG_LIMIT = 10_000
"""Events a simulator keeps (the latest); older ones are dropped and counted in ``events_dropped``."""


@dataclass
class BusStats:
    """What crossed the bus since construction or ``reset_stats()``."""

    bytes: int = 0
    """All bytes on the wire: command and data bytes, I2C address and control bytes."""
    command_bytes: int = 0
    """Bytes with D/C low (I2C: after a command control byte)."""
    data_bytes: int = 0
    """Bytes with D/C high (I2C: after a data control byte)."""
    transfers: int = 0
    """SPI chip-select frames and acknowledged I2C write transactions."""
    bus_seconds: float = 0.0
    """Wire time at the configured clock (see the module doc)."""
    frames: int = 0
    """Completed RAM writes (full or partial), as the controller counts them."""


@dataclass(frozen=True)
class PanelEvent:
    """Something the controller would flag (it has no error reply on a write-only bus)."""

    time: float
    """Clock time of the byte."""
    offset: int
    """Index of the byte in the stream of command and data bytes the controller received since construction
    (I2C addresses and control bytes are not counted); -1 when not tied to a byte."""
    command: int | None
    """The command byte concerned, None when none is."""
    message: str


class PanelSim(SimulatedDevice):
    """A panel controller behind a bus (``BusDevice``): framing, I2C control bytes, RESET, statistics, events.

    ``command(b)``/``data(b)`` are SPI frames with D/C low/high (``spi_transfer``), each its own chip-select
    frame unless the caller holds ``chip_select(True)``.  ``i2c_write(address, payload)``: the SSD1306-family
    control-byte protocol (``Co D/C 000000``: Co=0 the rest is one stream, Co=1 one byte then another control
    byte); only parts built with ``i2c_address`` answer.  RESET low holds the chip (writes are flagged and
    ignored); the rising edge resets it.

    A subclass sets ``model`` and implements the hooks:

    * ``_panel_command(code)`` — one byte received with D/C low (SSD1306 parameters arrive this way too);
    * ``_panel_data(data)`` — bytes received with D/C high (any split: one call per frame or I2C segment);
    * ``_panel_reset()`` — the hardware reset (RES# rising edge, ``Fault.RESET``): registers to reset values;
    * ``_panel_power_loss()`` — power lost and back (default: ``_panel_reset()``; RAM may be lost too);
    * ``_panel_select(active)`` — chip select changed (default: nothing);
    * ``glass()`` and ``gram``.

    and reports with ``_report(command, message, at=0)`` (``at``: index of the byte in the current hook
    call's bytes, None: no byte), counts finished RAM writes with ``_count_frame()``, and reads ``in_reset``,
    ``clock_hz``.
    """

    FAULTS: ClassVar[frozenset[Fault]] = frozenset({Fault.RESET, Fault.POWER_LOSS})
    INPUT_LINES: ClassVar[tuple[str, ...]] = ("reset", "backlight")
    """Lines ``set_line`` accepts."""
    OUTPUT_LINES: ClassVar[tuple[str, ...]] = ("te",)
    """Lines ``line`` reads (the base: all low)."""

    def __init__(self, *, clock: Clock | None = None, clock_hz: float, strict: bool = False,
                 i2c_address: int | None = None, i2c_clock_hz: float | None = None,
                 spi_limit_hz: float | None = None, i2c_limit_hz: float | None = None) -> None:
        super().__init__(clock)
        if not 0 < clock_hz < math.inf or (i2c_clock_hz is not None and not 0 < i2c_clock_hz < math.inf):
            raise InvalidArgument(f"bus clock must be a positive number of Hz, got clock_hz={clock_hz!r}, "
                                  f"i2c_clock_hz={i2c_clock_hz!r}")
        if i2c_address is not None and i2c_address not in I2C_ADDRESSES:
            shown = f"0x{i2c_address:02x}" if isinstance(i2c_address, int) else quote_token(i2c_address)
            raise ConfigError(f"{self.model}: I2C address {shown} is not a 7-bit address 0x08..0x77 "
                              "(0x00..0x07 and 0x78..0x7f are reserved)")
        self.clock_hz = float(clock_hz)
        """SPI clock in Hz, used for bus time."""
        self.i2c_clock_hz = float(i2c_clock_hz if i2c_clock_hz is not None else clock_hz)
        """I2C clock in Hz, used for bus time."""
        self.i2c_address = i2c_address
        """7-bit I2C address the part acknowledges (None: not an I2C part)."""
        self.strict = strict
        self.stats = BusStats()
        self._events: deque[PanelEvent] = deque(maxlen=EVENT_LOG_LIMIT)
        self.events_dropped = 0
        """Events no longer in ``events`` (the log keeps the latest ``EVENT_LOG_LIMIT``)."""
        self.lines: dict[str, bool] = {name: True for name in self.INPUT_LINES}
        """Levels of the input lines (all high at power-up: RES# released, backlight on)."""
        self._limits = {"spi": spi_limit_hz, "i2c": i2c_limit_hz}
        self._held = False
        self._dc = False
        self._position = 0
        """Command and data bytes received so far (the next byte's offset)."""
        self._chunk_start = 0

    # ---- the bus side ------------------------------------------------------------------------------
    @property
    def in_reset(self) -> bool:
        """True while RES# is held low."""
        return not self.lines["reset"]

    @property
    def events(self) -> list[PanelEvent]:
        """What the controller flagged, oldest first: the latest ``EVENT_LOG_LIMIT`` (see ``events_dropped``)."""
        return list(self._events)

    @property
    def event_count(self) -> int:
        """Every event flagged since construction, the dropped ones included (no copy of the log)."""
        return len(self._events) + self.events_dropped

    def command(self, data: WireBytes) -> None:
        """Bytes with D/C low, one chip-select frame (unless chip select is held)."""
        self._spi(wire_bytes(data, "command"), dc=False)

    def data(self, data: WireBytes) -> None:
        """Bytes with D/C high, one chip-select frame (unless chip select is held)."""
        self._spi(wire_bytes(data, "data"), dc=True)

    def chip_select(self, active: bool) -> None:
        """Assert (True) or release (False) chip select: transfers in between form one frame."""
        if self._closed or active == self._held:
            return
        self._catch_up()
        self._held = active
        if active:
            self.stats.transfers += 1
        self._panel_select(active)

    def spi_transfer(self, data: WireBytes, *, dc: bool) -> bytes:
        """One frame of ``data`` with D/C at ``dc`` (in the held frame when chip select is held); MISO zeros."""
        return self._spi(wire_bytes(data, "spi_transfer"), dc=dc)

    def i2c_write(self, address: int, payload: WireBytes) -> bool:
        """One write transaction (control bytes included); False (NAK) for another address or a non-I2C part."""
        payload = wire_bytes(payload, "i2c_write")
        if self._closed or self.i2c_address is None or address != self.i2c_address:
            return False
        self._catch_up()
        self._check_clock("i2c", self.i2c_clock_hz)
        self.stats.transfers += 1
        self.stats.bytes += 1 + len(payload)
        self.stats.bus_seconds += i2c_wire_seconds(len(payload), self.i2c_clock_hz)
        self._i2c_payload(payload)
        return True

    def i2c_read(self, address: int, length: int) -> bytes | None:
        """None: a write-only panel does not acknowledge reads."""
        return None

    def set_line(self, name: str, level: bool) -> None:
        """Drive ``"reset"`` (RES#, active low: the rising edge resets the chip) or ``"backlight"``."""
        if name not in self.lines:
            raise InvalidArgument(f"{self.model}: no input line {name!r}; lines: {', '.join(self.INPUT_LINES)}")
        self._catch_up()
        rising = level and not self.lines[name]
        self.lines[name] = bool(level)
        if name == "reset" and rising and not self._closed:
            self._panel_reset()

    def line(self, name: str) -> bool:
        """The level of an output line (the base drives none: low)."""
        if name not in self.OUTPUT_LINES:
            raise InvalidArgument(f"{self.model}: no output line {name!r}; lines: {', '.join(self.OUTPUT_LINES)}")
        return False

    def reset(self) -> None:
        """A RES# pulse: low, then high."""
        self.set_line("reset", False)
        self.set_line("reset", True)

    def reset_stats(self) -> None:
        """Start the bus statistics again from zero (the event log stays)."""
        for field in fields(BusStats):
            setattr(self.stats, field.name, field.default)

    # ---- for subclasses ----------------------------------------------------------------------------
    def _report(self, command: int | None, message: str, at: int | None = 0) -> None:
        """Log what the controller would flag (``strict``: raise ProtocolError); a negative command is none."""
        code = None if command is None or command < 0 else command
        event = PanelEvent(self._now, -1 if at is None else self._chunk_start + at, code, message)
        if len(self._events) == self._events.maxlen:
            self.events_dropped += 1
        self._events.append(event)
        log.debug("%s: %s (byte %d)", self.model, message, event.offset)
        if self.strict:
            raise ProtocolError(f"{self.model}: {message} (byte {event.offset})", command=code, device=self.model)

    def _count_frame(self) -> None:
        """One RAM write (full or partial) finished."""
        self.stats.frames += 1

    def _panel_select(self, active: bool) -> None:
        """Chip select changed; by default nothing."""

    def _panel_command(self, code: int) -> None:
        """One byte with D/C low."""
        raise NotImplementedError

    def _panel_data(self, data: bytes) -> None:
        """Bytes with D/C high."""
        raise NotImplementedError

    def _panel_reset(self) -> None:
        """The hardware reset."""
        raise NotImplementedError

    def _panel_power_loss(self) -> None:
        """Power lost and restored; by default a hardware reset."""
        self._panel_reset()

    # ---- the SimulatedDevice side ------------------------------------------------------------------
    def _spi(self, data: bytes, *, dc: bool) -> bytes:
        """One SPI frame of ``data`` (already bytes); MISO zeros."""
        if self._closed:
            return bytes(len(data))
        self._catch_up()
        self._check_clock("spi", self.clock_hz)
        framed = not self._held
        if framed:
            self.stats.transfers += 1
            self._panel_select(True)
        self.stats.bytes += len(data)
        self.stats.bus_seconds += spi_wire_seconds(len(data), self.clock_hz)
        self._bus_bytes(data, dc)
        if framed:
            self._panel_select(False)
        return bytes(len(data))

    def _bus_bytes(self, data: bytes, dc: bool) -> None:
        if dc:
            self.stats.data_bytes += len(data)
        else:
            self.stats.command_bytes += len(data)
        self._dc = dc
        self.receive(data)  # splits where a fault injected at a byte count falls due

    def _receive(self, data: bytes) -> None:
        self._chunk_start = self._position
        self._position += len(data)
        if self.in_reset:
            self._report(None, f"{len(data)} byte(s) written while RES# is low: ignored")
        elif self._dc:
            self._panel_data(data)
        else:
            for i, code in enumerate(data):
                self._chunk_start = self._position - len(data) + i
                self._panel_command(code)

    def _i2c_payload(self, payload: bytes) -> None:
        """Split a write after the address into command and data bytes by its control bytes."""
        i = 0
        while i < len(payload):
            control = payload[i]
            dc = bool(control & 0x40)
            if control & 0x3F:
                self._report(None, f"I2C control byte 0x{control:02X} has low bits set (expected Co D/C 000000)")
            if control & 0x80:  # Co=1: one byte, then another control byte
                body = payload[i + 1:i + 2]
                i += 2
            else:  # Co=0: the rest of the transaction is one stream
                body = payload[i + 1:]
                i = len(payload)
            if body:
                self._bus_bytes(body, dc)
            elif control & 0x80:
                self._report(None, f"I2C transaction ended after control byte 0x{control:02X}")

    def _check_clock(self, bus: str, hz: float) -> None:
        limit = self._limits[bus]
        if limit is not None and hz > limit:
            self._limits[bus] = None  # once
            self._report(None, f"{bus.upper()} clock {hz / 1e6:g} MHz is faster than the {self.model} datasheet "
                               f"allows ({limit / 1e6:g} MHz)", at=None)

    def _next_internal_event(self) -> float | None:
        return None

    def _handle_event(self, t: float) -> None:
        self._now = t

    def _apply_fault(self, fault: Fault) -> None:
        self._catch_up()  # a fault happens at the clock's present, not when the bus last moved device time
        if fault is Fault.POWER_LOSS:
            self._panel_power_loss()
        else:
            self._panel_reset()


_CALLS = {"command": ("data", "command({})", b"\x2c"), "data": ("data", "data({})", b"\x00\xff"),
          "spi_transfer": ("data", "spi_transfer({}, dc=False)", b"\x2c"),
          "i2c_write": ("payload", "i2c_write(0x3c, {})", b"\x00\xae")}
"""The bus calls taking bytes: the argument's name, a call with a bytes literal, the literal's default bytes."""


def wire_bytes(value: object, call: str) -> bytes:
    """``value`` as bus bytes: bytes, bytearray, memoryview or a numpy uint8 array; InvalidArgumentType otherwise.

    An int is refused rather than read as ``bytes(n)`` (n zero bytes): ``command(0x2C)`` would send 44 NOPs.
    """
    if isinstance(value, bytes | bytearray | memoryview):
        return bytes(value)
    if isinstance(value, np.ndarray) and value.dtype == np.uint8:
        return value.tobytes()
    argument, template, example = _CALLS[call]
    if isinstance(value, np.ndarray):
        found = f"a numpy array of {value.dtype}"
    else:
        found = f"{type(value).__name__} {quote_token(value)}"
        if type(value) is int and 0 <= value <= 0xFF:
            example = bytes([value]) if call != "i2c_write" else b"\x00" + bytes([value])
    literal = "b'" + "".join(f"\\x{b:02x}" for b in example) + "'"
    raise InvalidArgumentType(f"{call}() takes bytes as {argument}, e.g. {template.format(literal)}, found {found}")


PanelBuilder = Callable[[str, OptionValues, Clock | None], PanelSim]
"""Makes a model's simulator from its URL options as read (``read_options``) and the clock."""


def register_panel_simulators(models: Iterable[str], build: PanelBuilder, options: Sequence[OptionSpec[Any]]) -> None:
    """Register each of ``models`` for ``create_simulator`` and ``sim:`` URLs: options read against ``options``,
    then ``build(model, values, clock)``."""
    specs = tuple(options)
    for model in models:
        register_simulator(model, _panel_factory(model, build, specs), specs)


def _panel_factory(model: str, build: PanelBuilder, specs: tuple[OptionSpec[Any], ...]) -> Callable[..., PanelSim]:
    def create(clock: Clock | None = None, **options: str) -> PanelSim:
        """Simulator factory for ``sim:MODEL?...`` URLs."""
        return build(model, read_options(specs, options, f"sim:{model}"), clock)
    return create

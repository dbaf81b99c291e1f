"""A simulated panel's SPI wiring as host code sees it: a spidev.SpiDev stand-in, D/C/reset/TE lines, an RPi.GPIO shim.

Every SpiDev call that moves bytes is one chip-select frame handed to ``device.spi_transfer(chunk, dc=...)``
with D/C at the D/C line's level, chunked as py-spidev 3.8 chunks (``writebytes2``/``xfer3`` by ``bufsiz``).
With a SimulatedClock each frame advances the clock by its wire time (``drivers.bus.spi_wire_seconds``:
8 SCLK periods per byte at the frame's speed), so simulated frame rates are the bus's.
"""

from __future__ import annotations

import errno
from collections.abc import Iterable, Mapping, Sequence
from typing import Final

from pixelpen.clock import Clock, SimulatedClock
from pixelpen.drivers.bus import spi_wire_seconds
from pixelpen.errors import InvalidArgument, InvalidArgumentType
from pixelpen.sim.base import BusDevice

SPIDEV_MAXPATH: Final = 4096
"""py-spidev's limit for ``writebytes``/``xfer``/``xfer2``/``readbytes`` (``SPIDEV_MAXPATH``)."""
XFER3_MAX_BLOCK: Final = 65535
"""py-spidev never splits ``writebytes2``/``xfer3`` into blocks larger than this, whatever ``bufsiz`` says."""
POLL_INTERVAL: Final = 20e-6
"""How often a TE wait looks at the simulated chip's line (seconds of clock time)."""
LUMA_PINS: Final[Mapping[int, str]] = {24: "dc", 25: "reset"}
"""luma.core.interface.serial.spi's default BCM pins: gpio_DC=24, gpio_RST=25."""


def _closed() -> OSError:
    return OSError(errno.EBADF, "Bad file descriptor")


class _Frames:
    """The wire between the fakes and the chip: one frame per call, wire time on a SimulatedClock."""

    def __init__(self, device: BusDevice, clock: Clock) -> None:
        self.device = device
        self.clock = clock
        self.dc = False

    def transfer(self, data: bytes, speed_hz: int) -> bytes:
        self.device.advance_to(self.clock.now())
        miso = self.device.spi_transfer(data, dc=self.dc)
        if isinstance(self.clock, SimulatedClock) and speed_hz > 0:
            self.clock.advance(spi_wire_seconds(len(data), speed_hz))
        return miso


class SimOutputLine:
    """An OutputLine wired to a chip input: ``"dc"`` feeds the SPI frames, any other name ``device.set_line``."""

    def __init__(self, frames: _Frames, name: str) -> None:
        self._frames = frames
        self.name = name
        self.level: bool | None = None
        """The last level set (None: never driven)."""
        self.writes = 0
        """How many times ``set`` was called (a GPIO write costs time on real hardware)."""

    def set(self, level: bool) -> None:
        """Drive the line."""
        self.level = bool(level)
        self.writes += 1
        if self.name == "dc":
            self._frames.dc = self.level
        else:
            self._frames.device.advance_to(self._frames.clock.now())
            self._frames.device.set_line(self.name, self.level)

    def close(self) -> None:
        """Release the line (the chip keeps the last level, as a real line keeps its pull)."""


class SimInputLine:
    """An InputLine reading a chip output (``device.line(name)``, e.g. ``"te"``), polled on the clock."""

    def __init__(self, frames: _Frames, name: str) -> None:
        self._frames = frames
        self.name = name

    def get(self) -> bool:
        """The line's level now."""
        self._frames.device.advance_to(self._frames.clock.now())
        return bool(self._frames.device.line(self.name))

    def wait_edge(self, rising: bool, timeout: float) -> bool:
        """Wait up to ``timeout`` seconds of clock time for the next rising (or falling) edge; False on timeout."""
        clock, device = self._frames.clock, self._frames.device
        deadline = clock.now() + timeout
        previous = self.get()
        while (now := clock.now()) < deadline:
            step = min(POLL_INTERVAL, deadline - now)
            due = device.next_event_time()
            if due is not None and now < due < now + step:
                step = due - now
            clock.sleep(step)
            level = self.get()
            if level != previous and level == rising:
                return True
            previous = level
        return False

    def close(self) -> None:
        """Release the line."""


class SimSpiDev:
    """spidev.SpiDev's API (py-spidev 3.8) in front of a simulated chip; errors as spidev raises them."""

    def __init__(self, frames: _Frames, *, bufsiz: int, default_speed_hz: int) -> None:
        self._frames = frames
        self._block = min(bufsiz, XFER3_MAX_BLOCK)
        self._default_speed_hz = default_speed_hz
        self._open = False
        self._mode = 0
        self._max_speed_hz = 0
        self.bits_per_word = 0
        """As spidev: 0 until opened (8 bits per word after ``open``)."""
        self.no_cs = False
        """Stored only (luma's gpio_cs_spi sets it); frames are still the calls."""
        self.opened: tuple[int, int] | str | None = None
        """What ``open``/``open_path`` was given last (None: never opened)."""

    def open(self, bus: int, device: int) -> None:
        """Connect to /dev/spidev<bus>.<device> (any numbers reach the simulated chip)."""
        self._connect((bus, device))

    def open_path(self, path: str) -> None:
        """Connect by device path."""
        self._connect(path)

    def _connect(self, where: tuple[int, int] | str) -> None:
        self._open, self.opened = True, where
        self._max_speed_hz, self.bits_per_word, self._mode = self._default_speed_hz, 8, 0

    def close(self) -> None:
        """Disconnect; attributes read 0 again as spidev's do."""
        self._open = False
        self._max_speed_hz = self.bits_per_word = self._mode = 0

    @property
    def max_speed_hz(self) -> int:
        """SCLK frequency in Hz (an integer, as spidev insists)."""
        return self._max_speed_hz

    @max_speed_hz.setter
    def max_speed_hz(self, value: int) -> None:
        if not isinstance(value, int):
            raise InvalidArgumentType("The max_speed_hz attribute must be an integer")
        if not self._open:
            raise _closed()
        self._max_speed_hz = value

    @property
    def mode(self) -> int:
        """SPI mode, CPOL|CPHA (0-3)."""
        return self._mode

    @mode.setter
    def mode(self, value: int) -> None:
        if not isinstance(value, int) or not 0 <= value <= 3:
            raise InvalidArgumentType("The mode attribute must be an integer between 0 and 3")
        if not self._open:
            raise _closed()
        self._mode = value

    def writebytes(self, values: Sequence[int]) -> None:
        """Write up to 4096 bytes in one frame."""
        self._frame(_small(values))

    def writebytes2(self, values: object) -> None:
        """Write any number of bytes (a buffer or a sequence), one frame per ``bufsiz`` block."""
        data = _any(values)
        for at in range(0, len(data), self._block):
            self._frame(data[at : at + self._block])

    def xfer(
        self, values: Sequence[int], speed_hz: int = 0, delay_usecs: int = 0, bits_per_word: int = 0
    ) -> list[int]:
        """Exchange up to 4096 bytes in one frame; returns what the chip sent on MISO."""
        return list(self._frame(_small(values), speed_hz))

    xfer2 = xfer

    def xfer3(
        self, values: Sequence[int], speed_hz: int = 0, delay_usecs: int = 0, bits_per_word: int = 0
    ) -> list[int]:
        """Exchange any number of bytes, one frame per ``bufsiz`` block (CS drops between ioctls as spidev's do)."""
        data = _any(values)
        if not data:  # xfer3 reads its argument as a sequence even when it is a buffer
            raise InvalidArgumentType("Empty argument list.")
        miso = bytearray()
        for at in range(0, len(data), self._block):
            miso += self._frame(data[at : at + self._block], speed_hz)
        return list(miso)

    def readbytes(self, length: int) -> list[int]:
        """Read ``length`` bytes (clamped to 1..4096 as spidev does), clocking out zeros."""
        return list(self._frame(bytes(min(max(length, 1), SPIDEV_MAXPATH))))

    def _frame(self, data: bytes, speed_hz: int = 0) -> bytes:
        if not self._open:
            raise _closed()
        return self._frames.transfer(data, speed_hz or self._max_speed_hz)


def _small(values: Sequence[int]) -> bytes:
    """A writebytes/xfer argument as spidev checks it: 1..4096 integers, each truncated to 8 bits."""
    if not values:
        raise InvalidArgumentType("Empty argument list.")
    if len(values) > SPIDEV_MAXPATH:
        raise OverflowError(f"Argument list size exceeds {SPIDEV_MAXPATH} bytes.")  # spidev's own error type
    return _any(values)


def _any(values: object) -> bytes:
    """A writebytes2/xfer3 argument as spidev reads it: any buffer (even empty), else a non-empty integer sequence."""
    try:
        return memoryview(values).cast("B").tobytes()  # type: ignore[arg-type]
    except TypeError:
        pass
    if not isinstance(values, Iterable):
        raise InvalidArgumentType(f"expected a sequence or a buffer, got {type(values).__name__}")
    out = bytearray()
    for value in values:
        if not isinstance(value, int):
            raise InvalidArgumentType(f"Non-Int/Long value in arguments: {value!r}.")
        out.append(value & 0xFF)
    if not out:
        raise InvalidArgumentType("Empty argument list.")
    return bytes(out)


class SimGpio:
    """RPi.GPIO's module API over the wiring's lines, for clients (luma) that take a ``gpio=`` object.

    Pins are whatever numbers the client uses (``setmode`` is recorded, not translated); ``pins`` names
    each wired one: ``"dc"``, ``"reset"``, ``"te"`` (input), or any chip line name (``"backlight"``).
    """

    BOARD: Final = 10
    BCM: Final = 11
    OUT: Final = 0
    IN: Final = 1
    LOW: Final = 0
    HIGH: Final = 1
    PUD_OFF: Final = 20
    PUD_DOWN: Final = 21
    PUD_UP: Final = 22
    RISING: Final = 31
    FALLING: Final = 32
    BOTH: Final = 33

    def __init__(self, wiring: SimSpiWiring, pins: Mapping[int, str]) -> None:
        self._wiring = wiring
        self._pins = dict(pins)
        self.mode: int | None = None
        """What ``setmode`` was given (None: never called)."""
        self.directions: dict[int, int] = {}
        """Pins set up so far, with their direction (OUT or IN)."""
        self.levels: dict[int, int] = {}
        """The last level written to each output pin (wired or not)."""

    def setmode(self, mode: int) -> None:
        """Choose pin numbering (BCM or BOARD)."""
        if mode not in (self.BCM, self.BOARD):
            raise InvalidArgument(f"setmode: {mode!r} is neither GPIO.BCM nor GPIO.BOARD")
        self.mode = mode

    def getmode(self) -> int | None:
        """The numbering chosen with ``setmode``."""
        return self.mode

    def setwarnings(self, flag: bool) -> None:
        """Accepted and ignored (there are no warnings to give)."""

    def setup(
        self, channel: int | Sequence[int], direction: int, pull_up_down: int = PUD_OFF, initial: int = -1
    ) -> None:
        """Set pins up as outputs (optionally at ``initial``) or inputs."""
        if direction not in (self.OUT, self.IN):
            raise InvalidArgument(f"setup: direction {direction!r} is neither GPIO.OUT nor GPIO.IN")
        for pin in _channels(channel):
            self.directions[pin] = direction
            if direction == self.OUT and initial != -1:
                self.output(pin, initial)

    def output(self, channel: int | Sequence[int], value: int | bool | Sequence[int | bool]) -> None:
        """Drive output pins (one value, or one per channel)."""
        pins = _channels(channel)
        values = list(value) if isinstance(value, Sequence) else [value] * len(pins)
        if len(values) != len(pins):
            raise InvalidArgument(f"output: {len(pins)} channels but {len(values)} values")
        for pin, level in zip(pins, values, strict=True):
            if self.directions.get(pin) != self.OUT:
                raise InvalidArgument(f"output: GPIO channel {pin} has not been set up as an OUTPUT")
            self.levels[pin] = int(bool(level))
            line = self._wiring.output_line(self._pins[pin]) if pin in self._pins else None
            if line is not None:
                line.set(bool(level))

    def input(self, channel: int) -> int:
        """Read a pin: the chip's line for a wired input (``"te"``), else the last level written."""
        if channel not in self.directions:
            raise InvalidArgument(f"input: GPIO channel {channel} has not been set up")
        if self._pins.get(channel) == "te":
            return int(self._wiring.te.get())
        return self.levels.get(channel, self.LOW)

    def wait_for_edge(self, channel: int, edge: int, timeout: int | None = None) -> int | None:
        """Wait for a rising or falling edge on the wired TE pin; ``timeout`` in ms; the channel, or None."""
        if self._pins.get(channel) != "te" or edge not in (self.RISING, self.FALLING):
            raise InvalidArgument(
                f"wait_for_edge: channel {channel} is not the TE pin, or edge {edge} is neither RISING nor FALLING"
            )
        seconds = 3600.0 if timeout is None else timeout / 1000
        return channel if self._wiring.te.wait_edge(edge == self.RISING, seconds) else None

    def cleanup(self, channel: int | Sequence[int] | None = None) -> None:
        """Forget the pins' setup (all of them without an argument); the chip keeps its line levels."""
        for pin in list(self.directions) if channel is None else _channels(channel):
            self.directions.pop(pin, None)


def _channels(channel: int | Sequence[int]) -> list[int]:
    return [channel] if isinstance(channel, int) else list(channel)


class SimSpiWiring:
    """A chip on an SPI bus with its GPIO lines: ``spidev``, ``dc``, ``reset``, ``te``, ``gpio_module``.

    ``spidev`` comes open (as /dev/spidev0.0; a client's own ``open`` reconnects it, as luma's does).
    ``clock`` defaults to the device's; ``max_speed_hz`` is what ``spidev.open`` reads back before
    the host sets a speed (the device tree's spi-max-frequency); ``pins`` maps RPi.GPIO pin numbers to
    line names for ``gpio_module`` (default: luma's DC=24, RST=25).
    """

    def __init__(
        self,
        device: BusDevice,
        *,
        clock: Clock | None = None,
        bufsiz: int = SPIDEV_MAXPATH,
        max_speed_hz: int = 125_000_000,
        pins: Mapping[int, str] = LUMA_PINS,
    ) -> None:
        if bufsiz < 1 or max_speed_hz < 1:
            raise InvalidArgument(f"SimSpiWiring: bufsiz ({bufsiz}) and max_speed_hz ({max_speed_hz}) must be positive")
        self.device = device
        self.bufsiz = bufsiz
        self._frames = _Frames(device, clock if clock is not None else device.clock)
        self.spidev = SimSpiDev(self._frames, bufsiz=bufsiz, default_speed_hz=max_speed_hz)
        self.spidev.open(0, 0)
        self.dc = SimOutputLine(self._frames, "dc")
        self.reset = SimOutputLine(self._frames, "reset")
        self.te = SimInputLine(self._frames, "te")
        self._outputs = {"dc": self.dc, "reset": self.reset}
        self.gpio_module = SimGpio(self, pins)

    @property
    def clock(self) -> Clock:
        """The clock frames and TE waits run on."""
        return self._frames.clock

    def output_line(self, name: str) -> SimOutputLine:
        """The OutputLine wired to the chip's input ``name`` (``"dc"``, ``"reset"``, ``"backlight"``...)."""
        if name not in self._outputs:
            self._outputs[name] = SimOutputLine(self._frames, name)
        return self._outputs[name]

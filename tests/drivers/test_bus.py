"""PanelBus and I2CPanelBus (the shape every panel transport implements), the wire-time model and FramedBus."""

from __future__ import annotations

import inspect
import math

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.drivers import bus
from pixelpen.drivers.bus import I2C_COMMAND, I2C_CONTINUATION, I2C_DATA, I2CPanelBus, PanelBus
from pixelpen.errors import ConfigError, InvalidArgument, LinkError


class RecordingBus:
    """The smallest PanelBus: it remembers (D/C, bytes) frames, chunked at ``max_transfer``."""

    max_transfer = 4
    kind = "spi"
    clock_hz = 1e6

    def __init__(self) -> None:
        self.frames: list[tuple[bool, bytes]] = []
        self.resets = 0
        self.bytes_sent = self.transfers = 0

    def command(self, *cmd: int | bytes) -> None:
        self.frames.append((False, b"".join(bytes([c]) if isinstance(c, int) else c for c in cmd)))

    def data(self, data: bytes) -> None:
        for at in range(0, len(data), self.max_transfer):
            self.frames.append((True, data[at : at + self.max_transfer]))

    def reset(self, recovery: float = bus.RESET_RECOVERY) -> None:
        self.resets += 1

    def close(self) -> None:
        pass


class I2CBus(RecordingBus):
    address = 0x3C


def test_a_minimal_bus_satisfies_the_protocol_and_half_a_bus_does_not():
    assert isinstance(RecordingBus(), PanelBus) and not isinstance(RecordingBus(), I2CPanelBus)
    assert isinstance(I2CBus(), I2CPanelBus) and isinstance(I2CBus(), PanelBus)

    class NoReset:
        max_transfer = 4
        kind = "spi"
        clock_hz = 1e6
        bytes_sent = transfers = 0

        def command(self, *cmd): ...

        def data(self, data): ...

        def close(self): ...

    assert not isinstance(NoReset(), PanelBus)

    class NoCounters(RecordingBus):
        def __init__(self) -> None:
            pass

    assert not isinstance(NoCounters(), PanelBus)


def test_the_methods_and_signatures_are_the_documented_ones():
    members = {name for name in dir(PanelBus) if not name.startswith("_")}
    assert {"command", "data", "reset", "close"} <= members
    assert str(inspect.signature(PanelBus.command)) == "(self, *cmd: 'int | bytes') -> 'None'"
    assert str(inspect.signature(PanelBus.data)) == "(self, data: 'bytes') -> 'None'"
    assert str(inspect.signature(PanelBus.reset)) == "(self, recovery: 'float' = 0.12) -> 'None'"
    fields = {"max_transfer": "int", "kind": "str", "clock_hz": "float", "bytes_sent": "int", "transfers": "int"}
    for name, kind in fields.items():  # read-only properties: a plain attribute or a property satisfies them
        assert isinstance(getattr(PanelBus, name), property)
        assert getattr(PanelBus, name).fget.__annotations__ == {"return": kind}
    assert I2CPanelBus.address.fget.__annotations__ == {"return": "int"}
    for name in ("command", "data", "reset", "close"):
        assert getattr(PanelBus, name).__doc__


def test_i2c_control_bytes_are_the_datasheet_values():
    # SSD1306 datasheet 8.1.5.2: control byte = Co, D/C#, then six zeros
    assert (I2C_COMMAND, I2C_DATA, I2C_CONTINUATION) == (0x00, 0x40, 0x80)
    assert bus.DEFAULT_MAX_TRANSFER == 4096


def test_reset_timing_covers_the_datasheet_minimums():
    # reset pulse: ST7789 and ILI9341 tRW >= 10 us, SSD1306 >= 3 us; recovery: ST7789/ILI9341 tRT 120 ms
    assert bus.RESET_PULSE >= 10e-6 and bus.RESET_RECOVERY == 0.120


def test_a_driver_uses_the_bus_without_knowing_the_wire():
    b = RecordingBus()
    b.reset()
    b.command(0x2A, b"\x00\x00\x00\xef")
    b.data(bytes(range(10)))
    assert b.resets == 1
    assert b.frames[0] == (False, b"\x2a\x00\x00\x00\xef")
    assert [len(d) for dc, d in b.frames[1:] if dc] == [4, 4, 2]


def test_spi_wire_time_is_eight_clocks_a_byte():
    # panels.md §4: ST7789 240x240 RGB565 = 115,200 pixel bytes at 62.5 MHz: 115200 * 8 / 62.5e6 = 14.7456 ms
    assert bus.spi_wire_seconds(115_200, 62.5e6) == pytest.approx(14.7456e-3)
    assert bus.spi_wire_seconds(0, 1e6) == 0.0


def test_i2c_wire_time_counts_bytes_transactions_and_repeated_starts():
    # SSD1306 frame: [00 21 00 7F 22 00 07] + [40 + 1024]: 1,032 bytes, 2 transactions;
    # per transaction START 1 + address 8+ACK + STOP 1 = 11 clocks: 9 * 1032 + 22 = 9,310 clocks = 23.275 ms
    assert bus.i2c_wire_seconds(1032, 400e3, 2) == pytest.approx(9310 / 400e3)
    # a register read: START, addr+W, reg, Sr, addr+R, 2 bytes, STOP = 1 + 9 + 9 + 1 + 9 + 18 + 1 = 48 clocks
    assert bus.i2c_wire_seconds(3, 100e3, restarts=1) == pytest.approx(48 / 100e3)


@pytest.mark.parametrize("hz", [0, -1.0, math.inf, math.nan])
def test_wire_time_refuses_a_clock_that_is_not_a_frequency(hz):
    with pytest.raises(InvalidArgument, match="bus clock"):
        bus.spi_wire_seconds(1, hz)
    with pytest.raises(InvalidArgument, match="bus clock"):
        bus.i2c_wire_seconds(1, hz)


class ListBus(bus.FramedBus):
    """The smallest FramedBus: it keeps the frames it is given; ``fail`` makes the next transfer raise."""

    kind = "spi"

    def __init__(self, max_transfer: int = 4, **kw) -> None:
        super().__init__("list", clock_hz=1e6, max_transfer=max_transfer, reset=kw.pop("reset", None),
                         clock=SimulatedClock(), closers=kw.pop("closers", ()))
        self.frames: list[bytes] = []
        self.fail: Exception | None = None

    def command(self, *cmd: int | bytes) -> None:
        self._send(self._command_frame(*cmd))

    def data(self, data: bytes) -> None:
        for chunk in self._data_chunks(data):
            self._send(chunk)

    def _transfer(self, frame) -> None:
        if self.fail is not None:
            raise self.fail
        self.frames.append(bytes(frame))


def test_a_framed_bus_counts_what_reached_the_wire_only():
    b = ListBus()
    assert isinstance(b, PanelBus)
    b.command(0x2A, b"\x00\x01")
    b.data(bytes(range(10)))
    assert b.frames == [b"\x2a\x00\x01", b"\x00\x01\x02\x03", b"\x04\x05\x06\x07", b"\x08\x09"]
    assert (b.bytes_sent, b.transfers) == (13, 4)
    b.fail = OSError(5, "Input/output error")
    with pytest.raises(LinkError, match=r"^list: write of 4 bytes failed: \[Errno 5\]"):
        b.data(bytes(8))
    b.fail = ValueError("not a link fault")
    with pytest.raises(ValueError):  # only the library's faults become LinkError
        b.data(b"\x00")
    assert (b.bytes_sent, b.transfers) == (13, 4)


def test_a_framed_bus_refuses_bad_settings_and_empty_or_oversized_commands():
    with pytest.raises(ConfigError, match="max_transfer must be at least 1"):
        ListBus(max_transfer=0)
    with pytest.raises(ConfigError, match="clock"):
        bus.FramedBus.__init__(ListBus(), "x", clock_hz=0, max_transfer=4, reset=None, clock=SimulatedClock(),
                               closers=())
    b = ListBus()
    with pytest.raises(InvalidArgument, match="at least one byte"):
        b.command()
    with pytest.raises(InvalidArgument, match=r"5 command bytes do not fit in one transfer \(4 bytes\)"):
        b.command(1, 2, 3, 4, 5)
    with pytest.raises(TypeError):
        bus.FramedBus("abstract", clock_hz=1, max_transfer=1, reset=None, clock=SimulatedClock(), closers=())


def test_close_releases_everything_even_when_a_release_fails():
    released = []

    def failing():
        released.append("adapter")
        raise OSError(5, "Input/output error")

    class Line:
        def set(self, level):
            pass

        def close(self):
            released.append("reset")

    b = ListBus(reset=Line(), closers=(failing, lambda: released.append("dc")))
    with pytest.raises(LinkError, match=r"^list: closing failed: \[Errno 5\]"):
        b.close()
    assert released == ["adapter", "dc", "reset"] and b.closed
    b.close()  # once only
    assert released == ["adapter", "dc", "reset"]
    for call in (lambda: b.command(1), lambda: b.data(b""), b.reset):
        with pytest.raises(LinkError, match="list: the bus is closed"):
            call()

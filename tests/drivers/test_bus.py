"""PanelBus and I2CPanelBus: the shape every panel transport implements."""

from __future__ import annotations

import inspect

from pixelpen.drivers import bus
from pixelpen.drivers.bus import I2C_COMMAND, I2C_CONTINUATION, I2C_DATA, I2CPanelBus, PanelBus


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

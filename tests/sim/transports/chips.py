"""A recording BusDevice for bus tests: it keeps every SPI frame, I2C transaction and line change with its time."""

from __future__ import annotations

from collections.abc import Callable

from pixelpen.clock import Clock, SimulatedClock
from pixelpen.sim.base import Fault


class RecordingChip:
    """A chip that acknowledges ``addresses``, answers MISO with ``miso`` and drives TE from ``te(t)``."""

    model = "recorder"

    def __init__(
        self,
        clock: Clock | None = None,
        *,
        addresses: tuple[int, ...] = (0x3C,),
        miso: bytes = b"",
        te: Callable[[float], bool] = lambda t: False,
        reads: bytes = b"",
    ) -> None:
        self.clock = clock if clock is not None else SimulatedClock()
        self.addresses = addresses
        self.miso = miso
        self.te = te
        self.reads = reads
        self.frames: list[tuple[bool, bytes]] = []
        self.frame_times: list[float] = []
        self.writes: list[tuple[int, bytes]] = []
        self.line_changes: list[tuple[str, bool, float]] = []
        self.advanced_to = 0.0

    def spi_transfer(self, data: bytes, *, dc: bool) -> bytes:
        self.frames.append((dc, bytes(data)))
        self.frame_times.append(self.clock.now())
        return (self.miso * (len(data) // max(len(self.miso), 1) + 1))[: len(data)] if self.miso else bytes(len(data))

    def i2c_write(self, address: int, data: bytes) -> bool:
        if address not in self.addresses:
            return False
        self.writes.append((address, bytes(data)))
        return True

    def i2c_read(self, address: int, length: int) -> bytes | None:
        return self.reads[:length] if address in self.addresses else None

    def set_line(self, name: str, level: bool) -> None:
        self.line_changes.append((name, level, self.clock.now()))

    def line(self, name: str) -> bool:
        return name == "te" and self.te(self.clock.now())

    def advance_to(self, t: float) -> None:
        self.advanced_to = max(self.advanced_to, t)

    def next_event_time(self) -> float | None:
        return None

    def inject(self, fault: Fault | str, at: int | None = None) -> None:
        pass

    def close(self) -> None:
        pass

    def data_bytes(self) -> bytes:
        """All D/C-high bytes in order."""
        return b"".join(chunk for dc, chunk in self.frames if dc)

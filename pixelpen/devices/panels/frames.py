"""Frame statistics of a panel display: one frame (FrameStats), the totals since open and the recent frames."""

from __future__ import annotations

import dataclasses
from collections import deque

HISTORY = 1000
"""Frames kept in :attr:`PanelStats.history` (the oldest are dropped first): at 60 fps the last 16 seconds."""


@dataclasses.dataclass
class FrameStats:
    """One frame sent: bytes handed to the bus, windows, host and bus seconds, and whether it was full."""

    bytes: int = 0
    windows: int = 0
    host_seconds: float = 0.0
    bus_seconds: float = 0.0
    full: bool = False


@dataclasses.dataclass
class PanelStats:
    """Totals since open: frames (full ones too), windows, bytes, host seconds and bus seconds.

    ``bytes`` counts the command, parameter and pixel bytes the driver handed to the bus (I2C control and
    address bytes are the bus's: ``display.bus.bytes_sent``).  A frame is timed once: ``host_seconds`` is
    the processor time before its first bus call (trimming, planning, packing every window), ``bus_seconds``
    the display clock's time from there to its last bus call (on a SimulatedClock the simulated wire time).
    """

    frames: int = 0
    full_frames: int = 0
    windows: int = 0
    bytes: int = 0
    host_seconds: float = 0.0
    bus_seconds: float = 0.0
    history: deque[FrameStats] = dataclasses.field(default_factory=lambda: deque(maxlen=HISTORY))
    """The last :data:`HISTORY` frames, oldest first."""

    @property
    def last(self) -> FrameStats:
        """The latest frame (an empty FrameStats before the first)."""
        return self.history[-1] if self.history else FrameStats()

    @property
    def host_seconds_per_frame(self) -> float:
        """Average host seconds of one frame (0 before the first)."""
        return self.host_seconds / self.frames if self.frames else 0.0

    def add(self, frame: FrameStats) -> None:
        """Count one finished frame."""
        self.frames += 1
        self.full_frames += frame.full
        self.windows += frame.windows
        self.bytes += frame.bytes
        self.host_seconds += frame.host_seconds
        self.bus_seconds += frame.bus_seconds
        self.history.append(frame)

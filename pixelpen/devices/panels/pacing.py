"""Frame pacing (frames coalesce, never queue) and the bus bandwidth limit of a panel refresh.

Wire time is :mod:`pixelpen.drivers.bus`'s model (``spi_wire_seconds``, ``i2c_wire_seconds``: 8 SPI clocks
a byte; 9 I2C clocks a byte plus 11 a transaction).  Gaps between transfers (chip select, D/C changes, the
host's own time) are not counted: the estimate is the bus's upper limit, panels.md §4.
"""

from __future__ import annotations

import collections
import math
from typing import NamedTuple

from pixelpen.clock import Clock
from pixelpen.drivers.bus import i2c_wire_seconds, spi_wire_seconds
from pixelpen.errors import ConfigError

FPS_WINDOW = 60
"""Frames the achieved frame rate is measured over."""

__all__ = ["BandwidthEstimate", "FramePacer", "bus_limit_fps", "check_fps", "estimate_bandwidth"]


class BandwidthEstimate(NamedTuple):
    """One frame on one bus: bytes, transfers, wire seconds and the frame rate the wire allows."""

    frame_bytes: int
    transfers: int
    seconds: float
    max_fps: float


def _check_bus(kind: str, clock_hz: float, frame_bytes: int, transfers: int) -> None:
    """ConfigError for a bus or frame no estimate can use."""
    if kind not in ("spi", "i2c"):
        raise ConfigError(f"bus kind must be 'spi' or 'i2c', got {kind!r}")
    if not (isinstance(clock_hz, (int, float)) and 0 < clock_hz < math.inf):
        raise ConfigError(f"bus clock must be a number of Hz > 0, got {clock_hz!r}")
    for name, value in (("frame_bytes", frame_bytes), ("transfers", transfers)):
        if not (isinstance(value, int) and value >= 0):
            raise ConfigError(f"{name} must be an integer >= 0, got {value!r}")


def estimate_bandwidth(kind: str, clock_hz: float, frame_bytes: int, transfers: int = 1) -> BandwidthEstimate:
    """Wire time and frame-rate limit of ``frame_bytes`` in ``transfers`` transfers on a ``kind`` bus."""
    _check_bus(kind, clock_hz, frame_bytes, transfers)
    if kind == "spi":
        seconds = spi_wire_seconds(frame_bytes, clock_hz)
    else:
        seconds = i2c_wire_seconds(frame_bytes, clock_hz, transfers)
    return BandwidthEstimate(frame_bytes, transfers, seconds, math.inf if seconds == 0 else 1.0 / seconds)


def bus_limit_fps(kind: str, clock_hz: float, frame_bytes: int, transfers: int = 1) -> float:
    """The most frames per second a ``kind`` bus at ``clock_hz`` carries when each frame is ``frame_bytes``."""
    return estimate_bandwidth(kind, clock_hz, frame_bytes, transfers).max_fps


def _hz(clock_hz: float) -> str:
    """A clock as people write it: 62.5 MHz, 400 kHz."""
    for unit, scale in (("MHz", 1e6), ("kHz", 1e3)):
        if clock_hz >= scale:
            return f"{clock_hz / scale:.4g} {unit}"
    return f"{clock_hz:.4g} Hz"


def check_fps(fps: float, *, kind: str, clock_hz: float, frame_bytes: int, transfers: int = 1,
              what: str = "the panel") -> BandwidthEstimate:
    """The estimate, or ConfigError when ``fps`` full frames per second cannot fit the bus.

    ``what`` names the panel and format in the message: "requested 120 fps but ST7789 240x240 RGB565 over SPI
    at 32 MHz can do at most 34.7 fps (115,211 bytes per frame)".
    """
    if not (isinstance(fps, (int, float)) and 0 < fps < math.inf):
        raise ConfigError(f"requested frame rate must be a number of frames per second > 0, got {fps!r}")
    estimate = estimate_bandwidth(kind, clock_hz, frame_bytes, transfers)
    if fps > estimate.max_fps:
        raise ConfigError(f"requested {fps:g} fps but {what} over {kind.upper()} at {_hz(clock_hz)} can do at most "
                          f"{math.floor(estimate.max_fps * 10) / 10:.1f} fps ({frame_bytes:,} bytes per frame)")
    return estimate


class FramePacer:
    """Decides when the next frame goes out at ``target_fps`` (None: whenever asked); frames coalesce.

    A display keeps accumulating damage while :meth:`frame_due` is False and sends one frame, the latest
    state, when it turns True, then calls :meth:`sent`.  A frame sent late does not make the next ones come
    sooner: the slots it missed are skipped (counted in :attr:`skipped`), so nothing queues.
    """

    def __init__(self, clock: Clock, target_fps: float | None) -> None:
        if target_fps is not None and not (isinstance(target_fps, (int, float)) and 0 < target_fps < math.inf):
            raise ConfigError(f"target fps must be a number > 0 or None, got {target_fps!r}")
        self.clock = clock
        self.target_fps = None if target_fps is None else float(target_fps)
        self.frames = 0
        """Frames sent."""
        self.skipped = 0
        """Frame slots missed because a frame came late."""
        self._due = clock.now()
        self._sent_at: collections.deque[float] = collections.deque(maxlen=FPS_WINDOW)

    @property
    def interval(self) -> float:
        """Seconds between frames (0 when unpaced)."""
        return 0.0 if self.target_fps is None else 1.0 / self.target_fps

    def seconds_until_due(self) -> float:
        """Seconds until the next frame may go out (0 when it is due)."""
        return max(self._due - self.clock.now(), 0.0)

    def frame_due(self) -> bool:
        """True when a frame may be sent now."""
        return self.clock.now() >= self._due

    def wait(self) -> None:
        """Sleep on the clock until the next frame is due (returns at once when it is)."""
        self.clock.sleep(self.seconds_until_due())

    def sent(self) -> None:
        """Record that a frame went out now; the next is due one interval after the slot this one filled."""
        now = self.clock.now()
        self.frames += 1
        self._sent_at.append(now)
        interval = self.interval
        if interval == 0.0:
            self._due = now
            return
        missed = max(math.floor((now - self._due) / interval), 0)
        self.skipped += missed
        self._due += (missed + 1) * interval

    @property
    def achieved_fps(self) -> float:
        """Frames per second over the last :data:`FPS_WINDOW` frames sent (0 before two frames)."""
        if len(self._sent_at) < 2 or self._sent_at[-1] == self._sent_at[0]:
            return 0.0
        return (len(self._sent_at) - 1) / (self._sent_at[-1] - self._sent_at[0])

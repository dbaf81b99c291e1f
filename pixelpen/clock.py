"""One injectable source of time for everything that waits: real time, or simulated time for sims and tests."""

from __future__ import annotations

import threading
import time


class Clock:
    """Real time: ``now()`` is a monotonic clock in seconds, ``sleep()`` really sleeps."""

    def now(self) -> float:
        """Seconds on a monotonic scale."""
        return time.monotonic()

    def sleep(self, seconds: float) -> None:
        """Wait ``seconds`` (no-op for zero or negative)."""
        if seconds > 0:
            time.sleep(seconds)


class SimulatedClock(Clock):
    """Simulated time: ``sleep()`` advances the clock at once, so a long plot is tested in milliseconds."""

    def __init__(self, start: float = 0.0) -> None:
        self._now = float(start)
        self._lock = threading.Lock()

    def now(self) -> float:
        with self._lock:
            return self._now

    def sleep(self, seconds: float) -> None:
        self.advance(seconds)

    def advance(self, seconds: float) -> None:
        """Move simulated time forward by ``seconds``."""
        if seconds > 0:
            with self._lock:
                self._now += seconds


REAL_CLOCK = Clock()
"""The default clock, shared by everything not given one."""

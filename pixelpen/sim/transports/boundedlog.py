"""BoundedLog: a simulator's record of what it received, keeping the newest entries and counting the rest.

A ``collections.deque(maxlen=N)`` whose ``dropped`` counts the entries ``append`` pushed out, so a long
session (``pixelpen show`` for hours) holds at most N of them.  It reads like a list: slices give lists and
``del log[:]`` empties it (tests inspect and clear these logs).
"""

from __future__ import annotations

from collections import deque
from typing import SupportsIndex, TypeVar, overload

T = TypeVar("T")


class BoundedLog(deque[T]):
    """The newest ``maxlen`` entries appended, oldest first; ``dropped`` older ones were discarded."""

    def __init__(self, maxlen: int) -> None:
        super().__init__(maxlen=maxlen)
        self.dropped = 0
        """Entries discarded because the log was full."""

    def append(self, item: T) -> None:
        """Add ``item`` at the end, discarding (and counting) the oldest entry when the log is full."""
        if len(self) == self.maxlen:
            self.dropped += 1
        super().append(item)

    @overload
    def __getitem__(self, index: SupportsIndex, /) -> T: ...

    @overload
    def __getitem__(self, index: slice, /) -> list[T]: ...

    def __getitem__(self, index: SupportsIndex | slice, /) -> T | list[T]:
        """An entry, or a list of the entries a slice selects."""
        if isinstance(index, slice):
            return list(self)[index]
        return super().__getitem__(index)

    def __delitem__(self, index: SupportsIndex | slice, /) -> None:
        """Remove an entry, or the entries a slice selects (``dropped`` is unchanged)."""
        if not isinstance(index, slice):
            super().__delitem__(index)
            return
        gone = set(range(len(self))[index])
        keep = [item for i, item in enumerate(self) if i not in gone]
        self.clear()
        self.extend(keep)

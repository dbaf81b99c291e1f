"""BoundedLog: the newest entries of a simulator's log, a count of the dropped ones, list-like reading."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.sim.transports.boundedlog import BoundedLog


def test_a_full_log_drops_the_oldest_entries_and_counts_them():
    log: BoundedLog[int] = BoundedLog(3)
    for i in range(5):
        log.append(i)
    assert list(log) == [2, 3, 4] and log.dropped == 2 and log.maxlen == 3


def test_it_reads_like_a_list():
    log: BoundedLog[str] = BoundedLog(10)
    for word in "abcdef":
        log.append(word)
    assert log[0] == "a" and log[-1] == "f"
    assert log[:3] == ["a", "b", "c"] and log[1:5:2] == ["b", "d"] and log[4:] == ["e", "f"]
    assert log.index("d") == 3 and log.count("a") == 1
    with pytest.raises(IndexError):
        log[6]


def test_deleting_slices_and_entries():
    log: BoundedLog[int] = BoundedLog(4)
    for i in range(6):
        log.append(i)
    del log[1:3]
    assert list(log) == [2, 5] and log.dropped == 2
    del log[0]
    assert list(log) == [5]
    del log[:]
    assert list(log) == [] and log.dropped == 2  # emptying it on purpose drops nothing
    log.append(9)
    assert log[:] == [9]


@given(st.integers(1, 8), st.lists(st.integers(), max_size=40))
def test_it_keeps_what_the_tail_of_a_list_keeps(size, items):
    log: BoundedLog[int] = BoundedLog(size)
    for item in items:
        log.append(item)
    assert list(log) == items[max(0, len(items) - size) :]
    assert log.dropped == max(0, len(items) - size)

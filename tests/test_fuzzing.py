"""The fuzzing harness itself: it must see crashes, hangs and runaway memory, and pass clean errors."""

from __future__ import annotations

import time

import pytest

from pixelpen.errors import ParseError
from tests.fuzzing import campaign, mutants


def _strict(data: bytes) -> None:
    if b"\x00" in data:
        raise ParseError("NUL byte", source="t", offset=data.index(b"\x00"))


def test_clean_errors_pass_and_are_counted():
    result = campaign("strict", _strict, [b"abc"], 200, tokens=(b"\x00",))
    result.check()
    assert result.rejected > 0 and result.accepted > 0 and result.cases == 200


def test_a_crash_is_reported_with_its_input():
    def crashy(data: bytes) -> None:
        if b"\x00" in data:
            raise IndexError("boom")

    result = campaign("crashy", crashy, [b"abc"], 100, tokens=(b"\x00",))
    with pytest.raises(AssertionError, match=r"(?s)crash.*IndexError"):
        result.check()


def test_a_hang_is_cut_short():
    def hangs(data: bytes) -> None:
        if len(data) > 3:
            time.sleep(10)

    result = campaign("hangs", hangs, [b"abcd"], 1, seconds_per_case=0.05)
    assert [f.kind for f in result.failures] == ["hang"]


def test_runaway_memory_is_reported():
    result = campaign("memory", lambda data: bytearray(64 * 2**20), [b"x"], 1, memory_mb=16)
    assert [f.kind for f in result.failures] == ["memory"]


def test_mutants_are_seeded():
    assert list(mutants([b"hello world"], 50, seed=3)) == list(mutants([b"hello world"], 50, seed=3))
    assert list(mutants([b"hello world"], 50, seed=3)) != list(mutants([b"hello world"], 50, seed=4))

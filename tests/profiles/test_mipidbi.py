"""The panel-mipi-dbi firmware format: the kernel's example bytes, its validation rules, round trips, fuzzing."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError, ParseError
from pixelpen.profiles import mipidbi
from pixelpen.profiles.mipidbi import read_mipi_dbi, write_mipi_dbi
from pixelpen.profiles.panel import InitStep, load_panel_profile
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign

HEADER = b"MIPI DBI" + bytes(7) + b"\x01"
"""15-byte magic padded with NULs, version 1 (struct panel_mipi_dbi_config)."""
EXAMPLE = HEADER + bytes.fromhex("1100" "000178" "b103012c2d" "2900")
"""The example of the driver's comment: command 0x11, sleep 120 ms, 0xb1 0x01 0x2c 0x2d, command 0x29."""


def test_kernel_example():
    assert read_mipi_dbi(EXAMPLE) == [InitStep(0x11, b"", 120), InitStep(0xB1, b"\x01\x2c\x2d"), InitStep(0x29)]
    assert write_mipi_dbi(read_mipi_dbi(EXAMPLE)) == EXAMPLE


def test_long_delays_split_into_255_ms_sleeps():
    assert write_mipi_dbi([InitStep(0x11, b"", 600)]) == HEADER + bytes.fromhex("1100 0001ff 0001ff 00015a")
    assert write_mipi_dbi([InitStep(0x01, b"", 255)]) == HEADER + bytes.fromhex("0100 0001ff")
    assert write_mipi_dbi([InitStep(0x29, b"", 5.2)]) == HEADER + bytes.fromhex("2900 000106")  # rounded up
    assert read_mipi_dbi(HEADER + bytes.fromhex("1100 0001ff 0001ff 00015a")) == [InitStep(0x11, b"", 600)]


def test_leading_sleep_and_nops():
    steps = read_mipi_dbi(HEADER + bytes.fromhex("000114 0100"))
    assert steps == [InitStep(0x00, b"", 20), InitStep(0x01)]
    assert write_mipi_dbi(steps) == HEADER + bytes.fromhex("000114 0100")
    nop = HEADER + bytes.fromhex("0000 0002aabb")  # NOP without and with two parameters: commands, not sleeps
    assert read_mipi_dbi(nop) == [InitStep(0), InitStep(0, b"\xaa\xbb")]
    with pytest.raises(ConfigError, match="reads it as a sleep"):
        write_mipi_dbi([InitStep(0x00, b"\x05")])
    with pytest.raises(ConfigError, match="at least one command"):
        write_mipi_dbi([])


@pytest.mark.parametrize(("data", "offset", "message"), [
    (HEADER + b"\x11", 17, "too small"),
    (HEADER[:10], 10, "too small"),
    (b"MIPI DBJ" + bytes(7) + b"\x01\x11\x00", 0, "bad magic"),
    (b"MIPI DBI" + bytes(6) + b"\x20\x01\x11\x00", 0, "bad magic"),
    (b"MIPI DBI" + bytes(7) + b"\x02\x11\x00", 15, "version 2 is not supported"),
    (HEADER + bytes.fromhex("1100 b103012c"), 18, "0xb1 declares 3 parameters but only 2"),
    (HEADER + bytes.fromhex("1100 29"), 18, "stray byte"),
])
def test_malformed(data, offset, message):
    with pytest.raises(ParseError, match=message) as err:
        read_mipi_dbi(data, source="panel.bin")
    assert err.value.offset == offset and "panel.bin" in str(err.value)


def test_limits(monkeypatch):
    monkeypatch.setattr(mipidbi, "MAX_BYTES", 20)
    with pytest.raises(ParseError, match="larger than the 20 allowed"):
        read_mipi_dbi(EXAMPLE)
    monkeypatch.setattr(mipidbi, "MAX_BYTES", 1 << 16)
    with pytest.raises(ParseError, match="add up to more than"):
        read_mipi_dbi(HEADER + b"\x11\x00" + b"\x00\x01\xff" * 40)
    with pytest.raises(ParseError, match="more than 512 commands"):
        read_mipi_dbi(HEADER + b"\x29\x00" * 513)


def test_builtin_tables_round_trip():
    for name in ("ili9341_240x320", "st7789_240x240", "st7735_80x160"):
        steps = list(load_panel_profile(name).init)
        assert read_mipi_dbi(write_mipi_dbi(steps)) == steps


step = st.builds(
    InitStep,
    st.integers(0, 255),
    st.binary(max_size=20),
    st.integers(0, 2000).map(float),
).filter(lambda s: not (s.command == 0 and len(s.params) == 1))


@settings(max_examples=200, deadline=None)
@given(st.lists(step, min_size=1, max_size=20))
def test_round_trip_property(steps):
    data = write_mipi_dbi(steps)
    assert data[:16] == HEADER
    assert read_mipi_dbi(data) == steps


def test_fuzz():
    seeds = [EXAMPLE, write_mipi_dbi(load_panel_profile("ili9341_240x320").init)]
    campaign("panel-mipi-dbi", read_mipi_dbi, seeds, QUICK_CASES, seed=3).check()


@pytest.mark.slow
def test_fuzz_long():
    seeds = [EXAMPLE, write_mipi_dbi(load_panel_profile("ili9341_240x320").init)]
    campaign("panel-mipi-dbi", read_mipi_dbi, seeds, SLOW_CASES, seed=4).check()

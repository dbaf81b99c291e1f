"""EBB command-line parsing: names, parameter rules (!4-!7), checksums (CU,54) and versions."""

from __future__ import annotations

import pytest

from pixelpen.sim.plotters.ebb.params import (
    EbbError,
    ParamSpec,
    checksum,
    parse_params,
    parse_version,
    split_name,
)

SM = (ParamSpec("u32"), ParamSpec("i32"), ParamSpec("i32", False), ParamSpec("u2", False))


@pytest.mark.parametrize("line, name, rest", [
    ("SM,1,2", "SM", ",1,2"), ("v", "V", ""), ("V,1", "V", ",1"), ("qg", "QG", ""), ("S2,1", "S2", ",1"),
    ("ZZZ", "ZZ", "Z"), ("", "", ""),
])
def test_split_name(line, name, rest):
    assert split_name(line) == (name, rest)


def test_parse_params_values_and_optional():
    assert parse_params(",1000,250,-766", SM, True) == [1000, 250, -766, None]
    assert parse_params(",10,5", SM, True) == [10, 5, None, None]
    assert parse_params(",10,5,", SM, True) == [10, 5, None, None]  # a trailing comma is harmless


# The examples of ebb.html "Returned Errors": SM,100 / SM,100A / TP,-1 / SM,1,1,1,0,0
@pytest.mark.parametrize("rest, specs, code, text", [
    (",100", SM, 4, "!4 Err: Missing parameter(s)"),
    (",100A", SM, 5, "!5 Err: Need comma next, found: 'A'"),
    (",-1", (ParamSpec("u16", False),), 6, "!6 Err: Invalid parameter value"),
    (",1,1,1,0,0", SM, 7, "!7 Err: Extra parameter"),
    (",1,2,3,4", SM, 6, "!6 Err: Invalid parameter value"),  # Clear is 0..3
    (",4294967296,1", SM, 6, "!6 Err: Invalid parameter value"),  # beyond 32 bits
    (",,1", SM, 6, "!6 Err: Invalid parameter value"),
    (",1.5,1", SM, 5, "!5 Err: Need comma next, found: '.'"),
])
def test_parse_errors(rest, specs, code, text):
    with pytest.raises(EbbError) as info:
        parse_params(rest, specs, True)
    assert (info.value.code, info.value.text) == (code, text)


def test_firmware_2_spelling():
    with pytest.raises(EbbError, match="Invalid paramter value"):
        parse_params(",-1", (ParamSpec("u16"),), False)


def test_checksum_examples_from_the_docs():
    assert checksum("SM,1000,1000,1000") == 153
    assert checksum("CU,54,0") == 119


def test_parse_version():
    assert parse_version("3.0.2") == (3, 0, 2) and parse_version("2.8.1") < (3, 0, 0)
    with pytest.raises(ValueError):
        parse_version("3.0")

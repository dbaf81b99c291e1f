"""Fuzzed report descriptors: truncated, oversized, deeply nested, random and mutated bytes give a ParseError
or a descriptor, never another exception, a hang or unbounded memory."""

from __future__ import annotations

import contextlib
import random

import pytest

from pixelpen.devices.hid import parse_descriptor
from pixelpen.devices.hid.descriptor import MAX_COLLECTION_DEPTH, MAX_DESCRIPTOR_SIZE
from pixelpen.devices.hid.dump import descriptor_dict, dump_descriptor
from pixelpen.errors import ParseError
from pixelpen.sim.hid.descriptors import DESCRIPTORS
from tests.devices.hid.test_descriptor import BOOT_KEYBOARD, BOOT_MOUSE, MS_WHEEL_MOUSE
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign

SEEDS = [*DESCRIPTORS.values(), BOOT_KEYBOARD, BOOT_MOUSE, MS_WHEEL_MOUSE]

TOKENS = (
    bytes([0xA4] * 6), bytes([0xB4] * 2), bytes([0xA1, 0x00] * 300), bytes([0xC0] * 3),   # stacks and nesting
    bytes([0x27, 0xFF, 0xFF, 0xFF, 0xFF]), bytes([0x17, 0x00, 0x00, 0x00, 0x80]),       # extreme limits
    bytes([0x76, 0x00, 0x01, 0x96, 0x00, 0x30]), bytes([0x19, 0x00, 0x2B, 0xFF, 0xFF, 0xFF, 0xFF]),
    bytes([0x85, 0x00]), bytes([0x86, 0xFF, 0xFF]), bytes([0xFE, 0xFF, 0x01]), bytes([0xA9, 0x01]),
    bytes([0x0B, 0xFF, 0xFF, 0xFF, 0xFF]), bytes([0x81, 0x00]), bytes([0xB1, 0x02]), bytes(8),
)
"""Items that stress the parser's limits, inserted by the mutator."""


def target(data: bytes) -> None:
    """Parse, then dump as text and as data, as ``pixelpen hid dump`` does."""
    d = parse_descriptor(data)
    dump_descriptor(d)
    descriptor_dict(d)


def test_every_truncation_of_every_seed_is_a_clean_outcome():
    for seed in SEEDS:
        for cut in range(len(seed)):
            try:
                parse_descriptor(seed[:cut])
            except ParseError as exc:
                assert exc.offset is not None and 0 <= exc.offset <= cut


def test_oversized_and_deeply_nested_descriptors_are_errors():
    with pytest.raises(ParseError):
        parse_descriptor(BOOT_MOUSE * (MAX_DESCRIPTOR_SIZE // len(BOOT_MOUSE) + 1))
    depth = MAX_COLLECTION_DEPTH + 1
    with pytest.raises(ParseError) as err:
        parse_descriptor(bytes([0xA1, 0x01] * depth + [0xC0] * depth))
    assert "nested" in err.value.message
    with pytest.raises(ParseError):
        parse_descriptor(bytes([0xA1, 0x01] * 2000))   # 4000 bytes of opened collections


def test_random_bytes_quick():
    rng = random.Random(11)
    for _ in range(QUICK_CASES):
        data = bytes(rng.randrange(256) for _ in range(rng.randint(1, 300)))
        with contextlib.suppress(ParseError):
            target(data)


def test_mutated_descriptors_quick():
    result = campaign("hid descriptors", target, SEEDS, QUICK_CASES, seed=1, allowed=(ParseError,), tokens=TOKENS,
                      seconds_per_case=2.0, memory_mb=64)
    result.check()


@pytest.mark.slow
def test_mutated_descriptors_long_campaign():
    result = campaign("hid descriptors", target, SEEDS, SLOW_CASES * 5, seed=2, allowed=(ParseError,),
                      tokens=TOKENS, seconds_per_case=2.0, memory_mb=64)
    print(result.summary())
    result.check()


@pytest.mark.slow
def test_random_bytes_long_campaign():
    rng = random.Random(12)
    for _ in range(SLOW_CASES * 5):
        data = bytes(rng.randrange(256) for _ in range(rng.randint(1, MAX_DESCRIPTOR_SIZE + 64)))
        with contextlib.suppress(ParseError):
            target(data)

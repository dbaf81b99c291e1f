"""Choice numbers from buttons, keys and hats."""

from __future__ import annotations

import pytest

from pixelpen.devices.hid.events import Button, Hat, Key
from pixelpen.errors import InvalidArgument
from pixelpen.input.choice import Choice
from tests.input.scripted import DEVICE


def key(char: str, usage: int, pressed: bool = True) -> Key:
    return Key(0.0, DEVICE, usage=usage, key=char, pressed=pressed, char=char)


def test_buttons_are_their_own_numbers_by_default_and_releases_do_nothing() -> None:
    c = Choice()
    assert c.value() is None
    assert c.handle(Button(0.0, DEVICE, button=4, pressed=True)) and c.value() == 4
    assert not c.handle(Button(0.0, DEVICE, button=4, pressed=False)) and c.value() == 4


def test_digit_keys_and_mapped_keys_and_hats() -> None:
    c = Choice()
    assert c.handle(key("7", 0x24)) and c.value() == 7  # HUT: keyboard 7 is 0x24
    assert not c.handle(key("q", 0x14))
    mapped = Choice(buttons={2: 1}, keys={"F1": 5}, hats={"up": 2})
    assert not mapped.handle(Button(0.0, DEVICE, button=1, pressed=True))
    assert mapped.handle(Button(0.0, DEVICE, button=2, pressed=True)) and mapped.value() == 1
    assert mapped.handle(Key(0.0, DEVICE, usage=0x3A, key="F1", pressed=True)) and mapped.value() == 5
    assert mapped.handle(Hat(0.0, DEVICE, hat=0, direction="up", dx=0, dy=1)) and mapped.value() == 2
    assert not mapped.handle(Hat(0.0, DEVICE, hat=0, direction="centre", dx=0, dy=0))


def test_choices_are_positive_integers() -> None:
    with pytest.raises(InvalidArgument, match="positive"):
        Choice(buttons={1: 0})

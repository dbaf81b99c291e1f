"""String input editing sequences, with the Keyboard-page usages of HID Usage Tables 1.4 §10 written out."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.devices.hid.events import Key
from pixelpen.errors import InvalidArgument
from pixelpen.input.queue import InputQueue
from pixelpen.input.string import StringInput
from tests.input.scripted import DEVICE, scripted

# HUT 1.4 Keyboard/Keypad page: a 0x04 .. z 0x1D, Return 0x28, Escape 0x29, Backspace 0x2A, Space 0x2C,
# Home 0x4A, Delete Forward 0x4C, End 0x4D, Right Arrow 0x4F, Left Arrow 0x50, Keypad Enter 0x58
USAGE = {**{chr(ord("a") + i): 0x04 + i for i in range(26)}, " ": 0x2C}
NAMED = {"enter": 0x28, "esc": 0x29, "bs": 0x2A, "home": 0x4A, "del": 0x4C, "end": 0x4D, "right": 0x4F,
         "left": 0x50, "kpenter": 0x58}


def keys(*strokes: str, t0: float = 0.0) -> list[Key]:
    """Presses (and releases) for each stroke: a named key in <>, else the characters typed."""
    out: list[Key] = []
    for stroke in strokes:
        items = [(NAMED[stroke[1:-1]], "")] if stroke.startswith("<") else [(USAGE[c.lower()], c) for c in stroke]
        for usage, char in items:
            t = t0 + 0.01 * len(out)
            out.append(Key(t, DEVICE, usage=usage, key=char or "named", pressed=True, char=char))
            out.append(Key(t + 0.001, DEVICE, usage=usage, key=char or "named", pressed=False, char=char))
    return out


def typed(*strokes: str, **options: object) -> StringInput:
    device = StringInput(**options)  # type: ignore[arg-type]
    for key in keys(*strokes):
        device.handle(key)
    return device


@pytest.mark.parametrize(("strokes", "text", "cursor"), [
    (("hello",), "hello", 5),
    (("helo", "<left>", "l"), "hello", 4),
    (("world", "<home>", "hello "), "hello world", 6),
    (("abc", "<bs>", "<bs>"), "a", 1),
    (("abc", "<home>", "<del>"), "bc", 0),
    (("abc", "<left>", "<left>", "<bs>"), "bc", 0),
    (("abc", "<end>", "<del>", "<right>"), "abc", 3),  # nothing after the cursor to delete or pass
    (("abc", "<home>", "<bs>", "<left>"), "abc", 0),  # nothing before it
    (("abc", "<esc>", "x"), "x", 1),
    (("Hi there",), "Hi there", 8),
])
def test_editing_sequences(strokes: tuple[str, ...], text: str, cursor: int) -> None:
    device = typed(*strokes)
    assert (device.text, device.cursor) == (text, cursor)


def test_the_buffer_is_bounded() -> None:
    assert typed("abcdef", max_length=4).text == "abcd"


def test_enter_triggers_and_the_next_line_starts_from_initial() -> None:
    queue = InputQueue([scripted(keys("ab", "<enter>", "cd", "<kpenter>", t0=0.1))])
    line = queue.attach(StringInput(initial=">"))
    assert line.request(1.0) == ">ab"
    assert line.request(1.0) == ">cd"
    assert line.request(1.0) is None


def test_bad_limits_are_refused() -> None:
    with pytest.raises(InvalidArgument, match="max_length"):
        StringInput(max_length=0)
    with pytest.raises(InvalidArgument, match="initial"):
        StringInput(initial="toolong", max_length=3)


def test_a_simulated_keyboard_types_edits_and_enters_a_line() -> None:
    from pixelpen.clock import SimulatedClock
    from pixelpen.input.registry import open_report_device
    from pixelpen.sim.base import create_simulator

    clock = SimulatedClock()
    keyboard = create_simulator("keyboard", clock=clock, script="typing:Ab\bc\x1bXy\n")  # \b Backspace, \x1b Esc
    with open_report_device(keyboard, clock=clock) as device:
        line = InputQueue([device]).attach(StringInput())
        assert line.request(5.0) == "Xy"


@given(st.lists(st.sampled_from(["a", "Z", " ", "<bs>", "<del>", "<left>", "<right>", "<home>", "<end>", "<esc>"]),
                max_size=80), st.integers(1, 12))
def test_editing_invariants(strokes: list[str], limit: int) -> None:
    """The cursor stays inside the text, the text inside the limit, and only typed characters appear."""
    device = StringInput(max_length=limit)
    for key in keys(*strokes):
        device.handle(key)
        assert 0 <= device.cursor <= len(device.text) <= limit
    assert set(device.text) <= {"a", "Z", " "}

"""The string device: keyboard text with editing; Enter is the trigger.

Keys are known by their Keyboard-page usage (HID Usage Tables §10, the same on every layout): Backspace
(0x2A) deletes before the cursor, Delete Forward (0x4C) at it, Left/Right arrows (0x50/0x4F) move it, Home
(0x4A) and End (0x4D) go to the ends, Escape (0x29) clears the line, Enter (0x28, keypad 0x58) triggers.
Any other press that types a character (the Key event's ``char``, by layout) inserts it at the cursor,
while the text is shorter than ``max_length``.  After a trigger the next line starts from ``initial``.
"""

from __future__ import annotations

from pixelpen.devices.hid.events import InputEvent, Key
from pixelpen.errors import InvalidArgument
from pixelpen.input.queue import LogicalDevice, Mode

ENTER, ESCAPE, BACKSPACE, HOME, DELETE, END, RIGHT, LEFT, KEYPAD_ENTER = (
    0x28, 0x29, 0x2A, 0x4A, 0x4C, 0x4D, 0x4F, 0x50, 0x58)
KEYBOARD_PAGE = 0x07
MAX_LENGTH = 65_536
"""The longest string buffer allowed."""


class StringInput(LogicalDevice):
    """A line of text typed and edited on a keyboard."""

    kind = "string"

    def __init__(self, *, initial: str = "", max_length: int = 256, mode: Mode = "request") -> None:
        super().__init__(mode=mode)
        if isinstance(max_length, bool) or not isinstance(max_length, int) or not 1 <= max_length <= MAX_LENGTH:
            raise InvalidArgument(f"max_length must be an integer in 1..{MAX_LENGTH}, got {max_length!r}")
        if not isinstance(initial, str) or len(initial) > max_length:
            raise InvalidArgument(f"the initial string must be text of at most {max_length} characters")
        self.initial = initial
        self.max_length = max_length
        self.text = initial
        self.cursor = len(initial)
        """Insertion point: characters before it."""
        self._done: str | None = None

    def value(self) -> str:
        """The line (the finished one right after Enter)."""
        return self.text if self._done is None else self._done

    def handle(self, event: InputEvent) -> bool:
        """Edit the line; True at Enter."""
        if not isinstance(event, Key) or not event.pressed:
            return False
        self._done = None
        usage = event.usage & 0xFFFF if event.usage >> 16 in (0, KEYBOARD_PAGE) else -1
        text, at = self.text, self.cursor
        if usage in (ENTER, KEYPAD_ENTER):
            self._done = text
            return True
        if usage == BACKSPACE:
            if at:
                self.text, self.cursor = text[:at - 1] + text[at:], at - 1
        elif usage == DELETE:
            self.text = text[:at] + text[at + 1:]
        elif usage == LEFT:
            self.cursor = max(0, at - 1)
        elif usage == RIGHT:
            self.cursor = min(len(text), at + 1)
        elif usage == HOME:
            self.cursor = 0
        elif usage == END:
            self.cursor = len(text)
        elif usage == ESCAPE:
            self.text, self.cursor = "", 0
        elif event.char and event.char.isprintable() and len(text) < self.max_length:
            self.text, self.cursor = text[:at] + event.char + text[at:], at + len(event.char)
        return False

    def triggered(self) -> None:
        """Start the next line from ``initial``."""
        self.text, self.cursor = self.initial, len(self.initial)

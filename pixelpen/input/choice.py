"""The choice device: buttons and keys to choice numbers (GKS: a positive integer, or no choice).

A press of a mapped button or key is the trigger and its number the measure.  ``buttons`` maps Button-page
usages to choices (default: each button is its own number), ``keys`` maps key names or the characters they
type to choices (default: the digits 1..9); a hat switch's directions map through ``hats`` (direction name
-> choice).  Unmapped presses are ignored.
"""

from __future__ import annotations

from collections.abc import Mapping

from pixelpen.devices.hid.events import Button, Hat, InputEvent, Key
from pixelpen.errors import InvalidArgument
from pixelpen.input.queue import LogicalDevice, Mode

DIGITS = {str(n): n for n in range(1, 10)}
"""The default key map: the digit keys 1..9."""


class Choice(LogicalDevice):
    """Choice numbers from button presses, key presses and hat directions."""

    kind = "choice"

    def __init__(self, *, buttons: Mapping[int, int] | None = None, keys: Mapping[str, int] | None = None,
                 hats: Mapping[str, int] | None = None, mode: Mode = "request") -> None:
        super().__init__(mode=mode)
        for name, table in (("buttons", buttons), ("keys", keys), ("hats", hats)):
            if table is not None and any(isinstance(c, bool) or not isinstance(c, int) or c < 1
                                         for c in table.values()):
                raise InvalidArgument(f"choice {name} map to positive integers, got {dict(table)!r}")
        self.buttons = None if buttons is None else dict(buttons)
        self.keys = DIGITS if keys is None else dict(keys)
        self.hats = dict(hats or {})
        self.current: int | None = None
        """The last choice made (None: none yet)."""

    def value(self) -> int | None:
        """The last choice."""
        return self.current

    def handle(self, event: InputEvent) -> bool:
        """A mapped press sets the choice and triggers."""
        choice: int | None = None
        if isinstance(event, Button) and event.pressed:
            choice = event.button if self.buttons is None else self.buttons.get(event.button)
        elif isinstance(event, Key) and event.pressed:
            choice = self.keys.get(event.key, self.keys.get(event.char) if event.char else None)
        elif isinstance(event, Hat):
            choice = self.hats.get(event.direction)
        if choice is None:
            return False
        self.current = choice
        return True

"""Logical input devices (GKS): locator, stroke, valuator, choice, pick and string over HID and evdev sources.

``open_input(url)`` opens an :class:`~pixelpen.input.device.InputDevice` (``sim:tablet?script=signature``,
``hid:046d:c52b``, ``evdev:/dev/input/event3``, ``replay:FILE``, ``evemu:FILE``); an
:class:`~pixelpen.input.queue.InputQueue` runs the logical devices over it in request, sample or event
mode, answering in the world coordinates of the display they are bound to.  See ``docs/input.md``.
"""

from __future__ import annotations

from pixelpen.input.registry import open_input

__all__ = ["open_input"]

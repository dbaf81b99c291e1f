"""The URL registry: device modules register their schemes; ``open(url)`` finds the display for a URL.

Built-in device modules live in ``pixelpen.devices`` and register themselves when imported; the
registry imports them on the first lookup.  Third-party packages add schemes through the entry-point
group ``pixelpen.displays`` (``scheme = "package.module:DisplayClass"``).
"""

from __future__ import annotations

import importlib
import logging
import pkgutil
from collections.abc import Callable
from importlib import metadata
from typing import TYPE_CHECKING, TypeVar

from pixelpen.errors import URLError
from pixelpen.urls import DeviceURL, parse_url

if TYPE_CHECKING:
    from pixelpen.display.base import Display

log = logging.getLogger(__name__)

_DISPLAYS: dict[str, type[Display]] = {}
_loaded = False
D = TypeVar("D", bound=type)


def register_display(*schemes: str) -> Callable[[D], D]:
    """Class decorator: make a Display subclass the handler of the given URL schemes."""

    def decorate(cls: D) -> D:
        for scheme in schemes:
            key = scheme.lower()
            if key in _DISPLAYS and _DISPLAYS[key] is not cls:
                raise URLError(f"scheme {key!r} is already registered by {_DISPLAYS[key].__name__}")
            _DISPLAYS[key] = cls  # type: ignore[assignment]
        cls.schemes = tuple(s.lower() for s in schemes)  # type: ignore[attr-defined]
        return cls

    return decorate


def _load() -> None:
    """Import the built-in device modules and third-party entry points once."""
    global _loaded
    if _loaded:
        return
    _loaded = True
    from pixelpen import devices

    for info in pkgutil.walk_packages(devices.__path__, f"{devices.__name__}."):
        if not info.name.rpartition(".")[2].startswith("_"):
            importlib.import_module(info.name)
    for entry in metadata.entry_points(group="pixelpen.displays"):
        try:
            register_display(entry.name)(entry.load())
        except Exception as exc:  # a broken plug-in must not break pixelpen; say which one
            log.warning("display plug-in %s (%s) failed to load: %s", entry.name, entry.value, exc)


def known_schemes() -> dict[str, type[Display]]:
    """All registered schemes and their display classes."""
    _load()
    return dict(sorted(_DISPLAYS.items()))


def display_class(scheme: str) -> type[Display]:
    """The display class registered for ``scheme``; URLError listing the known schemes otherwise."""
    _load()
    try:
        return _DISPLAYS[scheme.lower()]
    except KeyError:
        raise URLError(f"unknown scheme {scheme!r}; known schemes: {', '.join(sorted(_DISPLAYS))}") from None


def open_display(url: str | DeviceURL, **kwargs: object) -> Display:
    """Create and open the display a URL names (``pixelpen.open``)."""
    parsed = url if isinstance(url, DeviceURL) else parse_url(url)
    if parsed.scheme == "sim":
        model, _, _ = parsed.target.partition("?")
        cls = display_class(model)
        if not getattr(cls, "simulated", False):
            raise URLError(f"{parsed}: there is no simulator for {model!r}")
    else:
        cls = display_class(parsed.scheme)
    display = cls.from_url(parsed, **kwargs)
    display.open()
    return display

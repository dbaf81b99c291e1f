"""The URL registry: a table of schemes and their display classes; ``open(url)`` finds the display for a URL.

Built-in schemes are listed in :data:`BUILTIN_DISPLAYS` as ``"package.module:Class"`` and only the
module of the scheme asked for is imported (``png:`` loads no plotter, pyserial or simulator).
Third-party packages add schemes through the entry-point group ``pixelpen.displays`` (same
``scheme = "package.module:DisplayClass"`` shape), loaded on the first use of their scheme; a broken
plug-in is logged as a warning naming it.  ``register_display`` registers a class at run time (tests,
code that builds displays itself).  ``sim:MODEL`` opens the display class of MODEL, which must be
``simulated``.
"""

from __future__ import annotations

import importlib
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, TypeVar

from pixelpen.errors import URLError
from pixelpen.urls import DeviceURL, parse_url

if TYPE_CHECKING:
    from importlib import metadata

    from pixelpen.display.base import Display

log = logging.getLogger(__name__)

BUILTIN_DISPLAYS: dict[str, str] = {
    "png": "pixelpen.devices.files.png:PngFileDisplay",
    "svg": "pixelpen.devices.files.svg:SvgFileDisplay",
    "hp7475a": "pixelpen.devices.plotters.hpgl:HP7475A",
    "hp7550a": "pixelpen.devices.plotters.hpgl:HP7550A",
    "hp7440a": "pixelpen.devices.plotters.hpgl:HP7440A",
    "grbl": "pixelpen.devices.plotters.grbl:GrblPlotter",
    "axidraw": "pixelpen.devices.plotters.axidraw:AxiDrawPlotter",
    "ssd1306": "pixelpen.devices.panels.ssd1306:SSD1306Display",
    "sh1106": "pixelpen.devices.panels.ssd1306:SH1106Display",
    "ssd1309": "pixelpen.devices.panels.ssd1306:SSD1309Display",
    "st7789": "pixelpen.devices.panels.mipidcs:ST7789Display",
    "ili9341": "pixelpen.devices.panels.mipidcs:ILI9341Display",
    "st7735": "pixelpen.devices.panels.mipidcs:ST7735Display",
    "fbdev": "pixelpen.devices.panels.fbdev:FramebufferDisplay",
}
"""Scheme -> ``"module:Class"`` of its display (only that module is imported, on the scheme's first use)."""

ENTRY_POINT_GROUP = "pixelpen.displays"
"""Third-party displays: ``scheme = "package.module:DisplayClass"`` in this entry-point group."""

_DISPLAYS: dict[str, type[Display]] = {}
_FAILED: dict[str, str] = {}
"""Plug-in schemes whose entry point failed to load -> why (said again when the scheme is asked for)."""
D = TypeVar("D", bound="type[Display]")


def register_display(*schemes: str) -> Callable[[D], D]:
    """Class decorator: make a Display subclass the handler of the given URL schemes."""

    def decorate(cls: D) -> D:
        for scheme in schemes:
            key = scheme.lower()
            if key in _DISPLAYS and _DISPLAYS[key] is not cls:
                raise URLError(f"scheme {key!r} is already registered by {_DISPLAYS[key].__name__}")
            _DISPLAYS[key] = cls
        cls.schemes = tuple(s.lower() for s in schemes)
        return cls

    return decorate


def _import_class(target: str) -> type:
    """The class a ``"package.module:Class"`` reference names (importing its module)."""
    module_name, _, class_name = target.partition(":")
    return getattr(importlib.import_module(module_name), class_name)  # type: ignore[no-any-return]


def _load_builtin(scheme: str) -> None:
    """Import the module of a built-in scheme; its class is registered under the scheme."""
    cls = _import_class(BUILTIN_DISPLAYS[scheme])
    if _DISPLAYS.get(scheme) is not cls:
        register_display(*vars(cls).get("schemes", ()), scheme)(cls)


def _load_entry_point(entry: metadata.EntryPoint) -> None:
    """Register a plug-in's display; a broken one is logged as a warning naming it and remembered."""
    from pixelpen.display.base import Display

    scheme = entry.name.lower()
    try:
        cls = entry.load()
        if not (isinstance(cls, type) and issubclass(cls, Display)):
            raise TypeError(f"{cls!r} is not a Display subclass")
        register_display(scheme)(cls)
    except Exception as exc:  # noqa: BLE001 - a broken plug-in must not break pixelpen; say which one
        _FAILED[scheme] = f"display plug-in {entry.name} ({entry.value}) failed to load: {exc}"
        log.warning("%s", _FAILED[scheme])


def _entry_points() -> list[metadata.EntryPoint]:
    """The third-party displays declared in the ``pixelpen.displays`` group."""
    from importlib import metadata

    return list(metadata.entry_points(group=ENTRY_POINT_GROUP))


def known_schemes() -> dict[str, type[Display]]:
    """All schemes and their display classes (imports every built-in and plug-in display, for listings)."""
    for scheme in BUILTIN_DISPLAYS:
        if scheme not in _DISPLAYS:
            _load_builtin(scheme)
    for entry in _entry_points():
        if entry.name.lower() not in _DISPLAYS and entry.name.lower() not in _FAILED:
            _load_entry_point(entry)
    return dict(sorted(_DISPLAYS.items()))


def display_class(scheme: str) -> type[Display]:
    """The display class of ``scheme``, importing only its module; URLError listing the known schemes otherwise."""
    key = scheme.lower()
    if key not in _DISPLAYS:
        if key in BUILTIN_DISPLAYS:
            _load_builtin(key)
        elif key not in _FAILED:
            for entry in _entry_points():
                if entry.name.lower() == key:
                    _load_entry_point(entry)
                    break
    try:
        return _DISPLAYS[key]
    except KeyError:
        if key in _FAILED:
            raise URLError(_FAILED[key]) from None
        raise URLError(f"unknown scheme {scheme!r}; known schemes: {', '.join(scheme_names())}") from None


def scheme_names() -> list[str]:
    """Names of all schemes: built in, registered and from entry points (none imported)."""
    return sorted(set(BUILTIN_DISPLAYS) | set(_DISPLAYS) | {e.name.lower() for e in _entry_points()})


def display_for(url: DeviceURL) -> type[Display]:
    """The display class a parsed URL names: its scheme's, or for ``sim:MODEL`` the simulated MODEL's."""
    if url.scheme != "sim":
        return display_class(url.scheme)
    model, _, _ = url.target.partition("?")
    cls = display_class(model)
    if not cls.simulated:
        raise URLError(f"{url}: there is no simulator for {model!r}")
    return cls


def open_display(url: str | DeviceURL, **kwargs: object) -> Display:
    """Create and open the display a URL names (``pixelpen.open``)."""
    parsed = url if isinstance(url, DeviceURL) else parse_url(url)
    display = display_for(parsed).from_url(parsed, **kwargs)
    display.open()
    return display

"""The input URL registry: a table of schemes and their source openers; ``open_input(url)`` opens a device.

Built-in schemes are listed in :data:`BUILTIN_INPUTS` as ``"package.module:opener"`` and only the module of
the scheme asked for is imported (``hid:`` loads no evdev, ``evdev:`` no hidapi, and nothing here imports a
simulator: ``sim:`` and ``replay:`` reach ``pixelpen.sim`` by module name inside their opener).  Third-party
packages add schemes through the entry-point group ``pixelpen.inputs`` (same ``scheme =
"package.module:opener"`` shape), loaded on the first use of their scheme; a broken plug-in is logged as a
warning naming it.  ``register_input`` registers an opener at run time.  An opener is called as
``opener(url, clock=clock, options=options)`` and returns an :class:`~pixelpen.input.device.EventSource`.
"""

from __future__ import annotations

import importlib
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

from pixelpen.clock import Clock
from pixelpen.errors import URLError
from pixelpen.urls import DeviceURL, parse_url

if TYPE_CHECKING:
    from importlib import metadata

    from pixelpen.display.base import Display
    from pixelpen.input.device import EventSource, InputDevice

log = logging.getLogger(__name__)


class InputOpener(Protocol):
    """Opens the event source a parsed URL names on ``clock`` (None: the scheme's default: the real clock, or for a
    replay not in real time a simulated one) with the keyword options given to ``open_input``."""

    def __call__(self, url: DeviceURL, *, clock: Clock | None, options: dict[str, Any]) -> EventSource: ...


BUILTIN_INPUTS: dict[str, str] = {
    "sim": "pixelpen.input.sources:open_sim",
    "hid": "pixelpen.input.sources:open_hid_source",
    "replay": "pixelpen.input.sources:open_replay",
    "evdev": "pixelpen.input.sources:open_evdev",
    "evemu": "pixelpen.input.sources:open_evemu",
}
"""Scheme -> ``"module:opener"`` of its source (only that module is imported, on the scheme's first use)."""

ENTRY_POINT_GROUP = "pixelpen.inputs"
"""Third-party input sources: ``scheme = "package.module:opener"`` in this entry-point group."""

_OPENERS: dict[str, InputOpener] = {}
_FAILED: dict[str, str] = {}
"""Plug-in schemes whose entry point failed to load -> why (said again when the scheme is asked for)."""


def register_input(*schemes: str) -> Callable[[InputOpener], InputOpener]:
    """Decorator: make an opener the handler of the given input URL schemes."""

    def decorate(opener: InputOpener) -> InputOpener:
        for scheme in schemes:
            key = scheme.lower()
            if key in _OPENERS and _OPENERS[key] is not opener:
                raise URLError(f"input scheme {key!r} is already registered by {_OPENERS[key]!r}")
            _OPENERS[key] = opener
        return opener

    return decorate


def _import_opener(target: str) -> InputOpener:
    """The opener a ``"package.module:function"`` reference names (importing its module)."""
    module_name, _, name = target.partition(":")
    opener: InputOpener = getattr(importlib.import_module(module_name), name)
    return opener


def _load_entry_point(entry: metadata.EntryPoint) -> None:
    """Register a plug-in's opener; a broken one is logged as a warning naming it and remembered."""
    scheme = entry.name.lower()
    try:
        opener = entry.load()
        if not callable(opener):
            raise TypeError(f"{opener!r} is not callable")
        register_input(scheme)(opener)
    except Exception as exc:  # noqa: BLE001 - a broken plug-in must not break pixelpen; say which one
        _FAILED[scheme] = f"input plug-in {entry.name} ({entry.value}) failed to load: {exc}"
        log.warning("%s", _FAILED[scheme])


def _entry_points() -> list[metadata.EntryPoint]:
    """The third-party input sources declared in the ``pixelpen.inputs`` group."""
    from importlib import metadata

    return list(metadata.entry_points(group=ENTRY_POINT_GROUP))


def input_scheme_names() -> list[str]:
    """Names of all input schemes: built in, registered and from entry points (none imported)."""
    return sorted(set(BUILTIN_INPUTS) | set(_OPENERS) | {e.name.lower() for e in _entry_points()})


def input_opener(scheme: str) -> InputOpener:
    """The opener of ``scheme``, importing only its module; URLError listing the known schemes otherwise."""
    key = scheme.lower()
    if key not in _OPENERS:
        if key in BUILTIN_INPUTS:
            register_input(key)(_import_opener(BUILTIN_INPUTS[key]))
        elif key not in _FAILED:
            for entry in _entry_points():
                if entry.name.lower() == key:
                    _load_entry_point(entry)
                    break
    try:
        return _OPENERS[key]
    except KeyError:
        if key in _FAILED:
            raise URLError(_FAILED[key]) from None
        raise URLError(f"unknown input scheme {scheme!r}; known: {', '.join(input_scheme_names())}") from None


def open_input(url: str | DeviceURL, *, display: Display | None = None, clock: Clock | None = None,
               **options: Any) -> InputDevice:
    """Open the input device a URL names (``pixelpen.open_input``), bound to ``display``, timed by ``clock``.

    Without a clock, live and simulated devices run on the real clock, replays (unless ``realtime=true``) on a
    new simulated clock, as fast as they are read (``device.clock``).

    ``options`` (Python values or their URL text) go to the device semantics with the URL's own options.
    """
    from pixelpen.input.device import InputDevice

    parsed = url if isinstance(url, DeviceURL) else parse_url(url)
    source = input_opener(parsed.scheme)(parsed, clock=clock, options=dict(options))
    return InputDevice(source, url=str(parsed), display=display)


def open_report_device(device: Any, *, display: Display | None = None, clock: Clock | None = None,
                       **options: Any) -> InputDevice:
    """An InputDevice over a simulated ReportDevice (a ``HidSim``), reached through the fake hidapi module.

    The path ``sim:`` and ``replay:`` URLs take, for simulators built in code (tests, the pytest plugin);
    ``clock`` defaults to the device's own.
    """
    from pixelpen.input.device import InputDevice
    from pixelpen.input.sources import simulated_source

    source = simulated_source(device, clock=clock or device.clock, options=dict(options),
                              where=f"simulated {device.model}")
    return InputDevice(source, display=display)

"""Tests of the display registry: the built-in table, lazy loading, plug-ins through entry points, ``sim:`` URLs."""

import importlib
import json
import logging
import pkgutil
import subprocess
import sys
import textwrap
from importlib import metadata

import pytest

from pixelpen import devices
from pixelpen.display import registry
from pixelpen.display.base import Display
from pixelpen.errors import URLError
from pixelpen.urls import parse_url


def _modules_after(code: str) -> dict[str, bool]:
    """Run ``code`` in a fresh interpreter and say which modules of interest it imported."""
    probe = textwrap.dedent(f"""
        import json, sys
        {code}
        names = ["serial", "pixelpen.sim", "pixelpen.devices.plotters", "numpy", "PIL"]
        print(json.dumps({{name: name in sys.modules for name in names}}))
    """)
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    return json.loads(out.splitlines()[-1])


def test_opening_png_imports_neither_pyserial_nor_any_simulator_or_plotter(tmp_path):
    loaded = _modules_after(f"import pixelpen; pixelpen.open({str(tmp_path / 'x.png')!r}.join(['png:', ''])).close()")
    assert loaded["numpy"] and not loaded["serial"] and not loaded["pixelpen.sim"]
    assert not loaded["pixelpen.devices.plotters"]


def test_import_pixelpen_is_light_until_a_name_needs_the_drawing_modules():
    assert _modules_after("import pixelpen") == dict.fromkeys(
        ["serial", "pixelpen.sim", "pixelpen.devices.plotters", "numpy", "PIL"], False)
    loaded = _modules_after("from pixelpen import Circle, Display")
    assert loaded["numpy"] and not loaded["serial"]


def test_every_display_a_devices_module_registers_is_in_the_builtin_table():
    for info in pkgutil.walk_packages(devices.__path__, f"{devices.__name__}."):
        importlib.import_module(info.name)
    found = {}
    for scheme, target in registry.BUILTIN_DISPLAYS.items():
        module, _, name = target.partition(":")
        found[scheme] = getattr(importlib.import_module(module), name)
        assert issubclass(found[scheme], Display) and scheme in found[scheme].schemes
    assert registry.known_schemes().items() >= found.items()
    registered = {s: c for s, c in registry._DISPLAYS.items() if c.__module__.startswith("pixelpen.devices.")}
    assert registered == found  # a scheme registered by a devices module but missing from the table fails here


def test_display_class_and_sim_urls():
    png = registry.display_class("PNG")
    assert png.__name__ == "PngFileDisplay"
    assert registry.display_for(parse_url("sim:hp7475a?speed=fast")) is registry.display_class("hp7475a")
    with pytest.raises(URLError, match="there is no simulator for 'png'"):
        registry.display_for(parse_url("sim:png"))
    with pytest.raises(URLError, match=r"unknown scheme 'nope'; known schemes: .*axidraw.*png.*svg"):
        registry.display_class("nope")


@pytest.fixture
def plugins(monkeypatch, tmp_path):
    """A fresh registry whose entry-point group holds the plug-ins the test adds (a list of (scheme, target))."""
    monkeypatch.setattr(registry, "_DISPLAYS", dict(registry._DISPLAYS))
    monkeypatch.setattr(registry, "_FAILED", {})
    nested = tmp_path / "plugpkg" / "sub"
    nested.mkdir(parents=True)
    (tmp_path / "plugpkg" / "__init__.py").write_text("")
    (nested / "__init__.py").write_text("")
    (nested / "disp.py").write_text(textwrap.dedent("""
        from tests.display.test_base import RecordingDisplay

        class PluginDisplay(RecordingDisplay):
            '''A display a third-party package adds.'''

        NotADisplay = int
    """))
    monkeypatch.syspath_prepend(str(tmp_path))
    entries: list[tuple[str, str]] = []
    monkeypatch.setattr(registry, "_entry_points", lambda: [
        metadata.EntryPoint(name, target, registry.ENTRY_POINT_GROUP) for name, target in entries])
    yield entries
    for name in ("plugpkg", "plugpkg.sub", "plugpkg.sub.disp"):
        sys.modules.pop(name, None)


def test_a_plugin_in_a_nested_package_loads_on_first_use_of_its_scheme(plugins):
    plugins.append(("plug", "plugpkg.sub.disp:PluginDisplay"))
    assert "plug" in registry.scheme_names() and "plugpkg.sub.disp" not in sys.modules
    cls = registry.display_class("plug")
    assert cls.__name__ == "PluginDisplay" and cls.schemes == ("plug",)
    assert registry.known_schemes()["plug"] is cls


def test_a_broken_plugin_warns_naming_itself_and_its_scheme_says_why(plugins, caplog):
    plugins.extend([("gone", "plugpkg.missing:Nothing"), ("notone", "plugpkg.sub.disp:NotADisplay")])
    with caplog.at_level(logging.WARNING, logger="pixelpen.display.registry"):
        schemes = registry.known_schemes()
    assert "gone" not in schemes and "notone" not in schemes and "png" in schemes
    assert "display plug-in gone (plugpkg.missing:Nothing) failed to load" in caplog.text
    assert "display plug-in notone (plugpkg.sub.disp:NotADisplay) failed to load" in caplog.text
    with pytest.raises(URLError, match=r"display plug-in gone \(plugpkg.missing:Nothing\) failed to load"):
        registry.display_class("gone")


def test_register_display_refuses_a_second_class_for_a_scheme(plugins):
    class Other(registry.display_class("png")):
        pass

    with pytest.raises(URLError, match="already registered by PngFileDisplay"):
        registry.register_display("png")(Other)

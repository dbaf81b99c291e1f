"""Modules that moved in the redesign stay importable under their old names, as the same module objects."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

from pixelpen._moved import MOVED


@pytest.mark.parametrize("old", sorted(MOVED))
def test_old_name_is_the_new_module(old: str) -> None:
    with pytest.warns(DeprecationWarning, match=f"{old} moved to {MOVED[old]}"):
        module = importlib.import_module(old) if old not in sys.modules else _fresh(old)
    assert module is importlib.import_module(MOVED[old])


def _fresh(old: str):
    del sys.modules[old]
    return importlib.import_module(old)


def test_old_names_work_in_a_new_interpreter_with_from_imports() -> None:
    code = ("import warnings; warnings.simplefilter('ignore')\n"
            "from pixelpen.vector.profiles import load_profile\n"
            "from pixelpen.devices.plotter import PlotterDisplay\n"
            "import pixelpen.sim.urlhandler.protocol_sim as p\n"
            "import pixelpen.profiles, pixelpen.devices.plotters.base as base\n"
            "print(load_profile is pixelpen.profiles.load_profile, PlotterDisplay is base.PlotterDisplay, p.__name__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["True", "True", "pixelpen.sim.transports.urlhandler.protocol_sim"]


def test_unmoved_names_are_not_found_by_the_alias_finder() -> None:
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("pixelpen.devices.no_such_module")

"""Module paths from before the redesign, still importable: each old name loads its module's new home."""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import warnings
from types import ModuleType

MOVED = {
    "pixelpen.vector.profiles": "pixelpen.profiles.model",
    "pixelpen.vector.hatch": "pixelpen.geometry.hatch",
    "pixelpen.vector.build": "pixelpen.display.vectorize",
    "pixelpen.devices.plotter": "pixelpen.devices.plotters.base",
    "pixelpen.devices.hpgl": "pixelpen.devices.plotters.hpgl",
    "pixelpen.devices.hpgl_encode": "pixelpen.devices.plotters.hpgl_encode",
    "pixelpen.devices.grbl": "pixelpen.devices.plotters.grbl",
    "pixelpen.devices.grbl_encode": "pixelpen.devices.plotters.grbl_encode",
    "pixelpen.devices.axidraw": "pixelpen.devices.plotters.axidraw",
    "pixelpen.devices.ebb_encode": "pixelpen.devices.plotters.ebb_encode",
    "pixelpen.devices.pngfile": "pixelpen.devices.files.png",
    "pixelpen.devices.svgfile": "pixelpen.devices.files.svg",
    "pixelpen.drivers.link": "pixelpen.drivers.stream",
    "pixelpen.sim.transport": "pixelpen.sim.transports.port",
    "pixelpen.sim.urlhandler": "pixelpen.sim.transports.urlhandler",
    "pixelpen.sim.urlhandler.protocol_sim": "pixelpen.sim.transports.urlhandler.protocol_sim",
    "pixelpen.sim.pty": "pixelpen.sim.transports.pty",
    "pixelpen.sim.usbbackend": "pixelpen.sim.transports.usbbackend",
    "pixelpen.sim.plotter": "pixelpen.sim.plotters.sheet",
    "pixelpen.sim.hpgl": "pixelpen.sim.plotters.hpgl.plotter",
    "pixelpen.sim.hpgl_parse": "pixelpen.sim.plotters.hpgl.parsing",
    "pixelpen.sim.grbl": "pixelpen.sim.plotters.grbl.controller",
    "pixelpen.sim.grbl_gcode": "pixelpen.sim.plotters.grbl.gcode",
    "pixelpen.sim.grbl_planner": "pixelpen.sim.plotters.grbl.planner",
    "pixelpen.sim.ebb": "pixelpen.sim.plotters.ebb.board",
    "pixelpen.sim.ebb_motion": "pixelpen.sim.plotters.ebb.motion",
    "pixelpen.sim.ebb_params": "pixelpen.sim.plotters.ebb.params",
}
"""Old dotted module name -> the module that holds its code now (docs/architecture.md, 'Where modules moved')."""


class _MovedLoader(importlib.abc.Loader):
    """Loads an old name by importing the new module and registering it under the old name too."""

    def __init__(self, new: str) -> None:
        self.new = new

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        """Use the default (throw-away) module; exec_module swaps in the real one."""
        return None

    def exec_module(self, module: ModuleType) -> None:
        """Point the old name at the new module, with a DeprecationWarning naming both."""
        warnings.warn(f"{module.__name__} moved to {self.new}; import it from there", DeprecationWarning,
                      stacklevel=2)
        sys.modules[module.__name__] = importlib.import_module(self.new)


class MovedFinder(importlib.abc.MetaPathFinder):
    """Finds the old names in MOVED (first on sys.meta_path, so a moved package's children load only once)."""

    def find_spec(
        self, fullname: str, path: object = None, target: object = None
    ) -> importlib.machinery.ModuleSpec | None:
        """A spec loading the moved module for an old name; None for every other name."""
        new = MOVED.get(fullname)
        return None if new is None else importlib.machinery.ModuleSpec(fullname, _MovedLoader(new))


def install() -> None:
    """Make the old names importable (once per interpreter)."""
    if not any(isinstance(finder, MovedFinder) for finder in sys.meta_path):
        sys.meta_path.insert(0, MovedFinder())

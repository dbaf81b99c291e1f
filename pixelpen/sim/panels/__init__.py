"""Panel simulators that decode the real wire: SSD1306 family, MIPI-DCS TFTs, the Linux framebuffer.

Names are imported on first use, so ``import pixelpen.sim.panels`` loads no simulator.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "PanelSim": "pixelpen.sim.panels.base",
    "BusStats": "pixelpen.sim.panels.base",
    "PanelEvent": "pixelpen.sim.panels.base",
    "SSD1306Sim": "pixelpen.sim.panels.ssd1306",
    "MipiDcsSim": "pixelpen.sim.panels.mipidcs",
    "FbdevSim": "pixelpen.sim.panels.fbdev",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    """The exported class ``name``, importing its module on first use."""
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(_EXPORTS[name]), name)

"""AxiDraw / EiBotBoard simulator: the EBB command set over USB CDC, its motion FIFO, servo pen and paper.

Written from evil-mad/EggBot ``docs/ebb.html`` (firmware v3.0+) and ``docs/ebb2.html``, with machine
figures from ``plotters.md`` §2.  Models "axidraw" and "ebb"; URL options (``OPTIONS``):

=======================  ========================================================================
``model=v3``             (alias ``machine``) AxiDraw travel (mm): v2/v3/se_a4 300x218, a3/se_a3 430x297, xlx 595x218,
                         minikit 160x101.6, se_a1 864x594, se_a2 594x432, b6 190x140
``firmware=3.0.2``       version reported by ``V`` and gating the commands (plotters.md §2.2)
``syntax=legacy``        response syntax at boot; ``future`` is what ``CU,10,1`` selects (fw >= 3.0)
``pen_colour=C``         ink colour of the rendered paper (default black)
``pen_width=MM``         line width of the rendered paper (default 0.3)
``contact=17944``        servo pulse width (83.3 ns units) below which the pen touches the paper
=======================  ========================================================================

The board is built in layers, one concern per module:

* ``machine.py`` — ``EbbMachine``: the state after UserInit, the motion FIFO and engine on the clock, ink;
* ``parser.py`` — ``EbbParser``: USB bytes into lines, dispatch through the table, replies, flow control;
* ``commands.py`` — ``COMMANDS``: name -> (first firmware, parameter specs, handler method);
* ``motion_commands.py``, ``pen_commands.py``, ``query_commands.py``, ``config_commands.py``: the handlers;
* ``pen.py`` (the servo and where the pen meets the paper), ``ports.py`` (the PIC's pins), ``motion.py``
  (the step accumulator and servo slew), ``params.py`` (parameter parsing, error texts, checksums);
* this module: ``EbbSimulator``, the faults, the URL options and the factories.

The motor enables (RE0, RC1, active low) and microstep selects (MS1 RE2, MS2 RE1, MS3 RA6) are port pins:
EBB_Init drives them high (disabled, 1/16), EM/ES/PO and the CU,61 timeout change them, and PI, I and QE
read them.  Faults: ``Fault.POWER_LOSS`` (V+ falls to 0 V: motors unpowered, ``QC`` reads 0, QG bit 6 once
below a ``CU,60`` threshold), ``POWER_RESTORE``, ``PAUSE_BUTTON`` (PRG: ``QB`` reads 1), ``RESET`` (reboot).
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from pixelpen import options as opt
from pixelpen.clock import Clock
from pixelpen.errors import ConfigError, URLError
from pixelpen.sim.base import Fault, register_simulator
from pixelpen.sim.plotters.ebb.commands import COMMANDS
from pixelpen.sim.plotters.ebb.config_commands import ConfigCommands
from pixelpen.sim.plotters.ebb.machine import SUPPLY_VOLTS, TRAVEL_MM
from pixelpen.sim.plotters.ebb.motion_commands import MotionCommands
from pixelpen.sim.plotters.ebb.params import parse_version
from pixelpen.sim.plotters.ebb.pen import CONTACT_DEFAULT
from pixelpen.sim.plotters.ebb.pen_commands import PenCommands
from pixelpen.sim.plotters.ebb.query_commands import QueryCommands
from pixelpen.sim.plotters.sheet import Sheet

if TYPE_CHECKING:
    from pixelpen.raster.canvas import Canvas

__all__ = ["OPTIONS", "TRAVEL_MM", "EbbSimulator", "create"]

POWERED_VOLTS = 6.0
"""Below this V+ the motors do not hold the carriage."""


class EbbSimulator(MotionCommands, PenCommands, QueryCommands, ConfigCommands):
    """An EiBotBoard (AxiDraw) seen from its USB serial port (a StreamDevice)."""

    COMMANDS = COMMANDS
    FAULTS: ClassVar[frozenset[Fault]] = frozenset({Fault.POWER_LOSS, Fault.POWER_RESTORE, Fault.PAUSE_BUTTON,
                                                    Fault.RESET})
    default_baud = 12_000_000
    """USB CDC ignores the line coding: bytes move at USB full speed (12 Mbit/s), not at a baud rate."""

    # ---- public extras ---------------------------------------------------------------------------
    @property
    def step_position(self) -> tuple[int, int]:
        """Global motor step counters (what QS reports) at the current clock time."""
        self._catch_up()
        return self._steps_now(self._now)

    @property
    def position_mm(self) -> np.ndarray:
        """Carriage position on the paper (mm, x right, y down) at the current clock time."""
        self._catch_up()
        return self._xy_at(self._now)

    @property
    def pen_up(self) -> bool:
        """Commanded pen state (what QP reports): True when up."""
        return self._pen.commanded_up

    @property
    def paper(self) -> Sheet:
        """The sheet, with the executing move inked up to the current clock time."""
        self._catch_up()
        self._split_ink(self._now)
        return self._paper

    def push_carriage_home(self) -> None:
        """The operator pushes the carriage by hand to the home corner (0, 0) with the motors unpowered, pen up.

        A physical act: the board does not see it, its step counters stay as they were (a motion command it
        runs meanwhile counts steps the unpowered motors do not make).  Refused while powered motors hold
        the carriage, or with the pen on the paper.
        """
        self._catch_up()
        if self._vplus >= POWERED_VOLTS and any(self._motors_enabled(self._now)):
            raise ConfigError(f"{self.model}: the energised motors hold the carriage: switch them off (EM,0,0) first")
        if self._pen.touches(self._now):
            raise ConfigError(f"{self.model}: lift the pen before pushing the carriage (it would draw)")
        self._xy = np.zeros(2)

    @property
    def syntax(self) -> str:
        """Current response syntax: 'legacy' or 'future'."""
        return "future" if self._future else "legacy"

    def paper_image(self, dpi: float = 96.0) -> Canvas:
        """The paper with everything drawn so far, as an RGB Canvas."""
        return self.paper.paper_image(dpi)

    def save_paper(self, path: str | Path, dpi: float = 96.0) -> None:
        """Render the paper to an image file."""
        self.paper.save_paper(path, dpi)

    # ---- faults ----------------------------------------------------------------------------------
    def _apply_fault(self, fault: Fault) -> None:
        """Power loss and restore of V+, the PRG (pause) button, or a reboot, at the current clock time."""
        self._catch_up()
        self.log.append((self._now, f"<{fault.value}>"))
        if fault is Fault.POWER_LOSS:
            self._split_ink(self._now)
            self._vplus = 0.0
            if self._power_threshold and self._fw3:
                self._power_lost_flag = True
        elif fault is Fault.POWER_RESTORE:
            self._split_ink(self._now)
            self._vplus = SUPPLY_VOLTS
        elif fault is Fault.PAUSE_BUTTON:
            self._button = True
        elif fault is Fault.RESET:
            self._stop_motion()
            self._dead = False
            self._init_state(power_up=True)


# ---- URL options and the factories ------------------------------------------------------------------

def _machine(value: str) -> str:
    """An AxiDraw model name of TRAVEL_MM ('-' may stand for '_', any case)."""
    name = value.strip().lower().replace("-", "_")
    if name not in TRAVEL_MM:
        raise ValueError(f"expected one of {', '.join(TRAVEL_MM)}")
    return name


def _firmware(value: str) -> str:
    """A firmware version like 3.0.2."""
    parse_version(value)
    return value.strip()


OPTIONS: tuple[opt.OptionSpec[Any], ...] = (
    opt.OptionSpec("model", _machine, "v3", "AxiDraw model (alias machine): its travel in mm, "
                   + ", ".join(f"{k} {w:g}x{h:g}" for k, (w, h) in TRAVEL_MM.items())),
    opt.OptionSpec("firmware", _firmware, "3.0.2", "firmware version V reports; it gates the commands"),
    opt.OptionSpec("syntax", opt.choice("legacy", "future"), "legacy",
                   "response syntax at boot (future: what CU,10,1 selects, fw >= 3.0)"),
    opt.OptionSpec("pen_colour", opt.colour, "black", "ink colour of the rendered paper"),
    opt.OptionSpec("pen_width", opt.positive, 0.3, "line width of the rendered paper, mm"),
    opt.OptionSpec("contact", opt.integer(1, 65535), CONTACT_DEFAULT,
                   "servo pulse width (83.3 ns units) below which the pen touches the paper"),
)
"""The URL options of ``sim:axidraw`` and ``sim:ebb`` (``machine`` is accepted as an alias of ``model``)."""


def create(sim_model: str, /, clock: Clock | None = None, **options: str) -> EbbSimulator:
    """The simulator for ``sim:axidraw?...`` / ``sim:ebb?...`` URLs (``sim_model``: "axidraw" or "ebb")."""
    where = f"sim:{sim_model}"
    if "machine" in options and "model" in options:
        raise URLError(f"{where}: give the AxiDraw model once (model= or its alias machine=)")
    if "machine" in options:  # alias: create_simulator's own first parameter is called model
        options = {("model" if k == "machine" else k): v for k, v in options.items()}
    values = dict(opt.read_options(OPTIONS, options, where))
    machine = values.pop("model")
    try:
        return EbbSimulator(clock, model=sim_model, machine=machine, **values)
    except (ConfigError, ValueError) as exc:
        raise URLError(f"{where}: {exc}") from None


register_simulator("axidraw", functools.partial(create, "axidraw"), OPTIONS)
register_simulator("ebb", functools.partial(create, "ebb"), OPTIONS)

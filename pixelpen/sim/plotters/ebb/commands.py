"""The EBB command table: name -> (first firmware with the command, parameter specs, handler method).

One row per command of ebb.html (v3.0) / ebb2.html (2.x).  The parser (``parser.EbbParser``) looks the
name up, answers ``!8 Err: Unknown command`` for a name that is missing or newer than the firmware,
parses the parameters by the specs (``params.parse_params``: !4 .. !7) and calls the handler with the
command's name and the values (None for an optional parameter left out).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, NamedTuple

from pixelpen.sim.plotters.ebb.config_commands import ConfigCommands as Cfg
from pixelpen.sim.plotters.ebb.motion_commands import MotionCommands as Mot
from pixelpen.sim.plotters.ebb.params import ParamSpec
from pixelpen.sim.plotters.ebb.pen_commands import PenCommands as Pen
from pixelpen.sim.plotters.ebb.query_commands import QueryCommands as Qry

__all__ = ["COMMANDS", "CommandEntry", "Handler"]

Handler = Callable[[Any, str, list[Any]], None]
"""A handler method: (the board, the command's name as received, the parsed parameter values)."""


class CommandEntry(NamedTuple):
    """One command: the first firmware version that has it, its parameters, and the method that runs it."""

    since: tuple[int, int, int]
    params: tuple[ParamSpec, ...]
    handler: Handler


P = ParamSpec
_OPT = False
_I32, _U32, _DIR = P("i32"), P("u32"), P("u1")
_CLEAR = P("u2", _OPT)
"""The optional last parameter of the moves: which step accumulators to clear first (bit 0: axis 1)."""

COMMANDS: Mapping[str, CommandEntry] = {
    "A": CommandEntry((2, 2, 3), (), Cfg.cmd_A),
    "AC": CommandEntry((2, 2, 3), (P("u8"), _DIR), Cfg.cmd_AC),
    "BL": CommandEntry((1, 9, 5), (), Cfg.cmd_BL),
    "C": CommandEntry((0, 0, 0), (P("u8"),) * 5, Cfg.cmd_C),
    "CK": CommandEntry((0, 0, 0), (P("u8"), P("i8"), P("u16"), P("i16"), P("u32"), P("i32"), P("char"), P("uchar")),
                       Cfg.cmd_CK),
    "CS": CommandEntry((2, 4, 3), (), Mot.cmd_CS),
    "CU": CommandEntry((0, 0, 0), (P("u16"), P("i16")), Cfg.cmd_CU),
    "EM": CommandEntry((0, 0, 0), (P("u5"), P("u5", _OPT)), Mot.cmd_EM),
    "ES": CommandEntry((2, 2, 7), (P("u1", _OPT),), Mot.cmd_ES),
    "HM": CommandEntry((2, 6, 2), (_U32, P("i32", _OPT), P("i32", _OPT)), Mot.cmd_HM),
    "I": CommandEntry((0, 0, 0), (), Cfg.cmd_I),
    "L3": CommandEntry((3, 0, 0), (_I32,) * 8 + (_CLEAR,), Mot.cmd_L3),
    "LM": CommandEntry((2, 7, 0), (_I32,) * 6 + (_CLEAR,), Mot.cmd_LM),
    "LT": CommandEntry((2, 7, 0), (_U32,) + (_I32,) * 4 + (_CLEAR,), Mot.cmd_LT),
    "MR": CommandEntry((0, 0, 0), (P("u4095"),), Cfg.cmd_MR),
    "MW": CommandEntry((0, 0, 0), (P("u4095"), P("u8")), Cfg.cmd_MW),
    "ND": CommandEntry((1, 9, 5), (), Qry.cmd_ND),
    "NI": CommandEntry((1, 9, 5), (), Qry.cmd_NI),
    "O": CommandEntry((0, 0, 0), (P("u8"),) + (P("u8", _OPT),) * 4, Cfg.cmd_O),
    "PD": CommandEntry((0, 0, 0), (P("port"), P("u3"), _DIR), Cfg.cmd_PD),
    "PI": CommandEntry((0, 0, 0), (P("port"), P("u3")), Cfg.cmd_PI),
    "PO": CommandEntry((0, 0, 0), (P("port"), P("u3"), _DIR), Cfg.cmd_PO),
    "QB": CommandEntry((1, 9, 2), (), Qry.cmd_QB),
    "QC": CommandEntry((2, 2, 3), (), Qry.cmd_QC),
    "QE": CommandEntry((2, 8, 0), (), Qry.cmd_QE),
    "QG": CommandEntry((2, 6, 2), (), Qry.cmd_QG),
    "QL": CommandEntry((1, 9, 2), (P("u31", _OPT),), Qry.cmd_QL),
    "QM": CommandEntry((2, 4, 4), (), Qry.cmd_QM),
    "QN": CommandEntry((1, 9, 2), (), Qry.cmd_QN),
    "QP": CommandEntry((1, 9, 0), (), Qry.cmd_QP),
    "QR": CommandEntry((2, 6, 0), (), Qry.cmd_QR),
    "QS": CommandEntry((2, 4, 3), (), Qry.cmd_QS),
    "QT": CommandEntry((2, 5, 4), (), Qry.cmd_QT),
    "QU": CommandEntry((3, 0, 0), (P("u16"),), Qry.cmd_QU),
    "R": CommandEntry((0, 0, 0), (), Cfg.cmd_R),
    "RB": CommandEntry((2, 5, 4), (), Cfg.cmd_RB),
    "S2": CommandEntry((2, 2, 0), (P("u16"), P("u24"), P("u16", _OPT), P("u16", _OPT)), Pen.cmd_S2),
    "SC": CommandEntry((0, 0, 0), (P("u8"), P("u16")), Pen.cmd_SC),
    "SE": CommandEntry((2, 1, 0), (P("u8"), P("u10", _OPT), P("u1", _OPT)), Pen.cmd_SE),
    "SL": CommandEntry((1, 9, 2), (P("u8"), P("u31", _OPT)), Qry.cmd_SL),
    "SM": CommandEntry((0, 0, 0), (_U32, _I32, P("i32", _OPT), _CLEAR), Mot.cmd_SM),
    "SN": CommandEntry((1, 9, 5), (_U32,), Qry.cmd_SN),
    "SP": CommandEntry((0, 0, 0), (P("u8"), P("u16", _OPT), P("u3", _OPT)), Pen.cmd_SP),
    "SR": CommandEntry((2, 6, 0), (_U32, P("u1", _OPT)), Pen.cmd_SR),
    "ST": CommandEntry((2, 5, 5), (P("text", _OPT),), Qry.cmd_ST),
    "T3": CommandEntry((3, 0, 0), (_U32,) + (_I32,) * 6 + (_CLEAR,), Mot.cmd_T3),
    "TD": CommandEntry((3, 0, 1), (_U32,) + (_I32,) * 8 + (_CLEAR,), Mot.cmd_TD),
    "TP": CommandEntry((1, 9, 0), (P("u16", _OPT),), Pen.cmd_TP),
    "TR": CommandEntry((3, 0, 0), (_U32, _I32, P("i32", _OPT), _CLEAR), Mot.cmd_TR),
    "V": CommandEntry((0, 0, 0), (), Qry.cmd_V),
    "XM": CommandEntry((2, 3, 0), (P("u32"), _I32, _I32, _CLEAR), Mot.cmd_XM),
}
"""Every command the simulated board knows, by its (upper-case) name."""

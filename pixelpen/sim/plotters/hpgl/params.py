"""HP-GL execution errors, parameter checks, and the shape of the instruction tables (mnemonic -> counts, handler)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Final, Generic, TypeVar

from pixelpen.sim.plotters.hpgl.parsing import Instruction

__all__ = ["COORD_LIMIT", "Command", "CommandTable", "HPGLError", "coord", "in_range"]

COORD_LIMIT: Final = 32767.9999
"""HP-GL/1 coordinate parameter range is -32768 ... 32767 (7470A manual, PA)."""

PARSE_ERRORS: Final = {
    1: "instruction not recognised (illegal character sequence)",
    2: "wrong number of parameters",
    3: "bad parameter (a number too long, or an instruction cut off by a full buffer)",
}
"""What the syntax-decided HP-GL errors (``Instruction.error``) mean."""

Owner = TypeVar("Owner")


class HPGLError(Exception):
    """An HP-GL error raised while executing an instruction (the instruction is ignored)."""

    def __init__(self, code: int, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


@dataclass(frozen=True)
class Command(Generic[Owner]):
    """One instruction of a table: the parameter counts it takes (None: any, or the parser decides) and its handler.

    ``handler`` is a method of the class that owns the state the instruction changes, called with the
    instruction once its parameter count is checked (a count not in ``counts`` is error 2).
    """

    counts: tuple[int, ...] | None
    handler: Callable[[Owner, Instruction], None]

    def check(self, item: Instruction) -> None:
        """Raise error 2 when ``item`` has a parameter count this instruction does not take."""
        if self.counts is not None and len(item.params) not in self.counts:
            allowed = " or ".join(map(str, self.counts))
            raise HPGLError(2, f"takes {allowed} parameter(s), got {len(item.params)}")


CommandTable = Mapping[str, Command[Owner]]
"""Mnemonic -> Command: one instruction class's part of the plotter's instruction set."""


def in_range(value: float, lo: float, hi: float, what: str) -> float:
    """``value`` if it lies in [lo, hi]; HP-GL error 3 naming ``what`` otherwise."""
    if not lo <= value <= hi:
        raise HPGLError(3, f"{what} {value:g} is outside {lo:g}..{hi:g}")
    return value


def coord(value: float) -> float:
    """A coordinate parameter in the HP-GL/1 range (error 3 otherwise)."""
    return in_range(value, -32768.0, COORD_LIMIT, "coordinate")

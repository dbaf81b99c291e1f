"""The ``$`` command table: every documented command has an entry, and its checks run in system.c's order."""

from __future__ import annotations

import re

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.sim.plotters.grbl.controller import GrblSimulator
from pixelpen.sim.plotters.grbl.reports import HELP
from pixelpen.sim.plotters.grbl.system import SETTING, SYSTEM_COMMANDS, SystemCommand
from tests.sim.fakes import DeviceRig


class Rig(DeviceRig):
    """A GRBL simulator on a simulated clock, past its welcome line."""

    def __init__(self) -> None:
        clock = SimulatedClock()
        super().__init__(GrblSimulator(clock), clock)
        self.dev.take_output()


def test_every_command_of_the_help_line_has_a_table_entry():
    # [HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]: the letter after '$' names it
    letters = {word[1] for word in re.findall(rb"\$[^ \]]+", HELP) for word in [word.decode()] if word[1] != "x"}
    assert letters | {"R"} == set(SYSTEM_COMMANDS)  # $RST= is in commands.md, not on the help line
    for command in [*SYSTEM_COMMANDS.values(), SETTING]:
        assert isinstance(command, SystemCommand)
        assert getattr(GrblSimulator, command.handler.__name__) is command.handler


@pytest.mark.parametrize(("line", "reply"), [
    ("$SLP", b"ok\r\n[MSG:Sleeping]\r\n"),
    ("$SLPX", b"error:3\r\n"),
    ("$RST", b"error:3\r\n"),
    ("$RST=x", b"error:3\r\n"),
    ("$I=pixelpen", b"ok\r\n"),
    ("$Ix", b"error:3\r\n"),
    ("$GG", b"error:3\r\n"),
    ("$J", b"error:3\r\n"),
    ("$Q", b"error:2\r\n"),
    ("$1", b"error:3\r\n"),
    ("$1=x", b"error:2\r\n"),
    ("$1=2x", b"error:3\r\n"),
    ("$300=1", b"error:3\r\n"),
    ("$N0=G0", b"ok\r\n"),
    ("$N0=G5", b"error:20\r\n"),
])
def test_syntax_of_what_follows_the_letter(line, reply):
    assert Rig().send(line + "\n") == reply


def test_state_is_checked_before_the_setting_and_the_setting_before_the_syntax():
    rig = Rig()
    assert rig.send("$H\n") == b"error:5\r\n"  # homing disabled ($22=0)
    assert rig.send("$Hx\n") == b"error:5\r\n"  # ... checked before the syntax
    rig.send("G1 X100 F100\n")
    rig.run(0.5)
    assert rig.send("$#x\n") == b"error:8\r\n"  # not idle: before the syntax
    assert rig.send("$$x\n") == b"error:3\r\n"  # $$ checks its syntax first, its state itself
    assert rig.send("$$\n") == b"error:8\r\n"
    assert rig.send("$G\n").startswith(b"[GC:G1 ")  # any state
    assert rig.send("$N0=G0\n") == b"error:8\r\n"


def test_jog_runs_in_idle_and_jog_only():
    rig = Rig()
    assert rig.send("$J=G91 X5 F500\n") == b"ok\r\n"
    assert rig.send("$J=G91 X5 F500\n") == b"ok\r\n"  # while jogging
    rig.until_idle()
    rig.send("G1 X100 F100\n")
    rig.run(0.5)
    assert rig.send("$J=G91 X5 F500\n") == b"error:8\r\n"

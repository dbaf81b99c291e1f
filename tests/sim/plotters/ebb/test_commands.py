"""The EBB command table: one row per command, each naming a firmware version, its parameters and a handler."""

from __future__ import annotations

import inspect

from pixelpen.clock import SimulatedClock
from pixelpen.sim.plotters.ebb.board import EbbSimulator
from pixelpen.sim.plotters.ebb.commands import COMMANDS, CommandEntry
from pixelpen.sim.plotters.ebb.params import ParamSpec
from tests.sim.fakes import DeviceRig

EBB_HTML_COMMANDS = {
    "A", "AC", "BL", "C", "CK", "CS", "CU", "EM", "ES", "HM", "I", "L3", "LM", "LT", "MR", "MW", "ND", "NI", "O",
    "PD", "PI", "PO", "QB", "QC", "QE", "QG", "QL", "QM", "QN", "QP", "QR", "QS", "QT", "QU", "R", "RB", "S2", "SC",
    "SE", "SL", "SM", "SN", "SP", "SR", "ST", "T3", "TD", "TP", "TR", "V", "XM",
}
"""The commands of ebb.html v3.0 this simulator models (the 2.x-only ones it leaves out are not listed)."""


def test_the_table_has_one_entry_per_documented_command():
    assert set(COMMANDS) == EBB_HTML_COMMANDS
    assert all(name == name.upper() and 1 <= len(name) <= 2 for name in COMMANDS)


def test_each_entry_names_a_version_its_parameters_and_a_method_of_the_board():
    for name, entry in COMMANDS.items():
        assert isinstance(entry, CommandEntry)
        assert len(entry.since) == 3 and entry.since <= (3, 0, 1), name
        assert all(isinstance(p, ParamSpec) for p in entry.params), name
        assert entry.handler.__name__ == f"cmd_{name}", name  # one method per command, named for it
        assert getattr(EbbSimulator, entry.handler.__name__) is entry.handler, name
        assert list(inspect.signature(entry.handler).parameters) == ["self", "name", "v"], name


def test_required_parameters_come_before_optional_ones():
    for name, entry in COMMANDS.items():
        flags = [p.required for p in entry.params]
        assert flags == sorted(flags, reverse=True), name


def test_the_board_dispatches_through_its_table():
    assert EbbSimulator.COMMANDS is COMMANDS


def test_a_command_newer_than_the_firmware_is_unknown():
    for name, entry in COMMANDS.items():
        if entry.since == (0, 0, 0):
            continue
        major, minor, patch = entry.since
        older = f"{major}.{minor}.{patch - 1}" if patch else f"{major}.{minor - 1}.9" if minor else "1.9.0"
        clock = SimulatedClock()
        rig = DeviceRig(EbbSimulator(clock, firmware=older), clock)
        assert b"!8 Err: Unknown command" in rig.send(f"{name}\r"), (name, older)

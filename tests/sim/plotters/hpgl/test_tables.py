"""The HP-GL simulator's seams: instruction and device-control tables, the SimulatedDevice base, the option specs."""

from __future__ import annotations

import inspect

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError, URLError
from pixelpen.options import OptionSpec
from pixelpen.sim.base import Fault, SimulatedDevice, create_simulator
from pixelpen.sim.plotters.hpgl.instructions import GraphicsInstructions
from pixelpen.sim.plotters.hpgl.labels import LabelInstructions
from pixelpen.sim.plotters.hpgl.models import MODELS
from pixelpen.sim.plotters.hpgl.output import INTERFACE_CONTROL, Interface, OutputInstructions
from pixelpen.sim.plotters.hpgl.params import Command, HPGLError
from pixelpen.sim.plotters.hpgl.parsing import DEVICE_CONTROL_LETTERS, SYNTAX, Instruction
from pixelpen.sim.plotters.hpgl.plotter import _PLOTTER_CONTROL, COMMANDS, OPTIONS, HPGLPlotter, create

ESC = b"\x1b"


def test_every_instruction_a_model_knows_has_one_table_entry_with_a_method_of_its_instruction_class():
    owners = (GraphicsInstructions, LabelInstructions, OutputInstructions)
    for spec in MODELS.values():
        assert spec.mnemonics <= set(COMMANDS), spec.name
    assert set(COMMANDS) <= set(SYNTAX)
    for mnemonic, command in COMMANDS.items():
        assert isinstance(command, Command)
        owner = command.handler.__qualname__.split(".")[0]
        assert owner in {cls.__name__ for cls in owners}, mnemonic
        assert list(inspect.signature(command.handler).parameters) == ["self", "item"], mnemonic


def test_a_table_count_refuses_other_parameter_counts_with_error_2():
    command = COMMANDS["IP"]
    assert command.counts == (0, 2, 4)
    command.check(Instruction("IP", (1.0, 2.0)))
    with pytest.raises(HPGLError) as info:
        command.check(Instruction("IP", (1.0, 2.0, 3.0)))
    assert info.value.code == 2 and "0 or 2 or 4" in info.value.message
    COMMANDS["PA"].check(Instruction("PA", (1.0,) * 9))  # pairs: the parser decides


def test_device_control_letters_are_split_between_the_plotter_and_its_interface():
    assert set(_PLOTTER_CONTROL) | set(INTERFACE_CONTROL) == set(DEVICE_CONTROL_LETTERS)
    assert not set(_PLOTTER_CONTROL) & set(INTERFACE_CONTROL)
    assert all(h.__qualname__.startswith(f"{Interface.__name__}.") for h in INTERFACE_CONTROL.values())
    assert all(h.__qualname__.startswith(f"{HPGLPlotter.__name__}.") for h in _PLOTTER_CONTROL.values())


def test_the_plotter_is_a_simulated_device_with_the_hp_faults():
    plotter = create("hp7475a", clock=SimulatedClock(0.0))
    assert isinstance(plotter, SimulatedDevice)
    assert {Fault.POWER_LOSS, Fault.RESET, Fault.PAPER_LEVER, Fault.PAUSE_BUTTON} == HPGLPlotter.FAULTS
    with pytest.raises(ConfigError, match="unknown fault 'power-restore'; known: paper-lever, pause-button"):
        plotter.inject(Fault.POWER_RESTORE)
    plotter.inject("pause-button")
    assert plotter.paused
    plotter.inject(Fault.PAUSE_BUTTON)
    assert not plotter.paused


def test_a_fault_at_a_byte_count_falls_between_the_bytes_around_it():
    clock = SimulatedClock(0.0)
    plotter = create("hp7475a", clock=clock)
    stream = b"IN;OI;" + ESC + b".B"
    plotter.inject(Fault.POWER_LOSS, at=3)  # after "IN;": the rest arrives at a plotter without power
    plotter.receive(stream)
    assert plotter.take_output() == b"" and plotter.stats.bytes_ignored == len(stream) - 3
    plotter.inject("reset")
    plotter.inject(Fault.PAPER_LEVER, at=len(stream) + 3)
    plotter.receive(b"OS;" + ESC + b".O")
    assert plotter.take_output() == b"24\r40\r"  # OS before the lever went up; ESC.O after: empty + lever


def test_options_are_declared_as_specs_per_model_with_its_defaults():
    assert set(OPTIONS) == set(MODELS)
    for name, specs in OPTIONS.items():
        assert all(isinstance(s, OptionSpec) for s in specs)
        assert [s.name for s in specs] == ["paper", "pens", "buffer", "reserve_bug"]
        defaults = {s.name: s.default for s in specs}
        assert defaults["paper"] == MODELS[name].default_paper and defaults["buffer"] == MODELS[name].buffer
        assert defaults["reserve_bug"] is (name == "hp7475a") and len(defaults["pens"]) == MODELS[name].pens
    plotter = create_simulator("hp7440a", paper="Letter", pens="black, #00f", buffer="64", reserve_bug="on")
    assert isinstance(plotter, HPGLPlotter)
    assert plotter.paper.name == "letter" and plotter.pen_colours == {1: "#000000", 2: "#0000ff"}
    assert plotter.buffer_size == 64 and plotter.reserve_bug


@pytest.mark.parametrize("option, value, why", [
    ("paper", "a3", "this model takes a4, letter"),
    ("pens", ",", "expected comma-separated colours"),
    ("buffer", "8", r"expected an integer in \[16, "),
    ("reserve_bug", "maybe", "expected true/false"),
])
def test_bad_option_values_are_named_with_the_url_and_the_option(option, value, why):
    with pytest.raises(URLError, match=rf"^sim:hp7440a: option {option}='{value}' is not valid: {why}"):
        create_simulator("hp7440a", **{option: value})

"""Tests of the simulator registry: models, unknown names, and named instances reached again by id."""

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.errors import URLError
from pixelpen.sim.base import create_simulator, forget_simulator, named_simulator, simulator_models


def test_builtin_models_are_registered():
    assert {"hp7475a", "grbl", "axidraw"} <= set(simulator_models())


def test_unknown_model_lists_the_known_ones():
    with pytest.raises(URLError, match="hp7475a"):
        create_simulator("hp9999")


def test_an_id_reaches_the_same_instance_until_forgotten():
    clock = SimulatedClock()
    first = create_simulator("hp7475a", clock=clock, id="t-same")
    try:
        assert create_simulator("hp7475a", id="t-same") is first
        assert named_simulator("t-same") is first
        with pytest.raises(URLError, match="is a"):
            create_simulator("grbl", id="t-same")
    finally:
        forget_simulator("t-same")
    with pytest.raises(KeyError, match="t-same"):
        named_simulator("t-same")
    assert create_simulator("hp7475a", clock=clock, id="t-same") is not first
    forget_simulator("t-same")


def test_the_transport_test_fakes_are_simulated_stream_devices():
    from pixelpen.sim.base import Fault, SimulatedDevice, StreamDevice
    from tests.sim.fakes import EchoDevice, ScriptedDevice

    clock = SimulatedClock()
    echo, scripted = EchoDevice(clock), ScriptedDevice({b"?": b"!"}, clock)
    for device in (echo, scripted):
        assert isinstance(device, SimulatedDevice) and isinstance(device, StreamDevice)
    scripted.receive(b"a?")
    assert scripted.take_output() == b"!"
    echo.inject("power-loss", at=2)  # the base splits the input at the second byte
    echo.receive(b"abc")
    assert echo.faults == [(Fault.POWER_LOSS.value, 2)]

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

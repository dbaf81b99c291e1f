"""The simulator base: registry (models, ids, lazy imports), SimulatedDevice (events, faults at a byte count, close)."""

import subprocess
import sys

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError, InvalidArgumentType, URLError
from pixelpen.sim.base import (
    BUILTIN_SIMULATORS,
    Fault,
    SimulatedDevice,
    StreamDevice,
    create_simulator,
    forget_simulator,
    named_simulator,
    simulator_models,
)


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


# ---- SimulatedDevice, Fault and the lazy registry ----------------------------------------------------


class Recorder(SimulatedDevice):
    """A device that logs what reaches it and has one timed event: an echo of each chunk 1 s later."""

    model = "recorder"
    FAULTS = frozenset({Fault.POWER_LOSS, Fault.RESET})

    def __init__(self, clock=None):
        super().__init__(clock)
        self.log: list[tuple[float, str, bytes | Fault]] = []
        self.due: list[tuple[float, bytes]] = []

    def _receive(self, data: bytes) -> None:
        self.log.append((self._now, "rx", data))
        self.due.append((self._now + 1.0, data))

    def _next_internal_event(self):
        return self.due[0][0] if self.due else None

    def _handle_event(self, t: float) -> None:
        self._now = t
        _, data = self.due.pop(0)
        self._emit(data.upper())

    def _apply_fault(self, fault: Fault) -> None:
        self.log.append((self._now, "fault", fault))


def test_a_fault_at_a_byte_count_splits_the_input_exactly_there() -> None:
    dev = Recorder(SimulatedClock())
    dev.inject(Fault.POWER_LOSS, at=5)
    dev.inject("reset", at=7)
    dev.receive(b"abc")
    dev.receive(b"defghij")
    assert [(kind, what) for _, kind, what in dev.log] == [
        ("rx", b"abc"), ("rx", b"de"), ("fault", Fault.POWER_LOSS), ("rx", b"fg"), ("fault", Fault.RESET),
        ("rx", b"hij")]


def test_a_fault_at_a_count_already_passed_applies_at_once() -> None:
    dev = Recorder(SimulatedClock())
    dev.receive(b"abcdef")
    dev.inject(Fault.RESET, at=3)
    assert dev.log[-1][1:] == ("fault", Fault.RESET)


@pytest.mark.parametrize("data", [bytearray(b"ab"), memoryview(b"xab")[1:]])
def test_bytes_like_input_is_taken_as_its_bytes(data) -> None:
    dev = Recorder(SimulatedClock())
    dev.receive(data)
    assert dev.log == [(0.0, "rx", b"ab")] and type(dev.log[0][2]) is bytes


@pytest.mark.parametrize("data, name", [(5, "int"), ("abc", "str"), ([0x41, 0x42], "list"), (None, "NoneType")])
def test_input_that_is_not_bytes_like_is_refused_naming_it(data, name) -> None:
    dev = Recorder(SimulatedClock())
    message = f"recorder: receive\\(\\) takes bytes, bytearray or memoryview, not {name}"
    with pytest.raises(InvalidArgumentType, match=message):
        dev.receive(data)  # receive(5) once sent five NUL bytes
    assert dev.log == []


def test_unknown_and_unmodelled_faults_are_refused_naming_the_known() -> None:
    dev = Recorder(SimulatedClock())
    with pytest.raises(ConfigError, match="unknown fault 'lightning'; known: power-loss, "):
        dev.inject("lightning")
    with pytest.raises(ConfigError, match="recorder: unknown fault 'paper-lever'; known: power-loss, reset"):
        dev.inject(Fault.PAPER_LEVER)
    assert Fault.of("pause-button") is Fault.PAUSE_BUTTON and Fault.of(Fault.RESET) is Fault.RESET


def test_the_event_loop_runs_events_in_time_order_up_to_t_and_no_further() -> None:
    clock = SimulatedClock()
    dev = Recorder(clock)
    dev.receive(b"a")
    dev.advance_to(0.5)
    assert dev.take_output() == b"" and dev.next_event_time() == 1.0
    dev.receive(b"b")  # at 0.5: due at 1.5
    dev.advance_to(1.2)
    assert dev.take_output() == b"A" and dev.next_event_time() == 1.5
    dev.advance_to(10.0)
    assert dev.take_output() == b"B" and dev.next_event_time() is None and dev._now == 10.0


def test_a_closed_device_ignores_bytes_time_and_has_no_events() -> None:
    dev = Recorder(SimulatedClock())
    dev.receive(b"a")
    dev.close()
    dev.close()
    dev.receive(b"b")
    dev.advance_to(5.0)
    assert dev.closed and dev.take_output() == b"" and dev.next_event_time() is None
    assert [what for _, _, what in dev.log] == [b"a"]
    assert isinstance(dev, StreamDevice)


def test_creating_one_simulator_imports_only_its_own_room() -> None:
    code = ("import sys\nfrom pixelpen.sim.base import create_simulator\ncreate_simulator('grbl')\n"
            "print(sorted({m.split('.')[3] for m in sys.modules if m.startswith('pixelpen.sim.plotters.')}))\n"
            "print('pixelpen.devices' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0] == "['grbl', 'sheet']" and out[1] == "False"  # its package and the shared paper sheet


def test_every_builtin_model_is_listed_without_importing_it() -> None:
    code = ("import sys\nfrom pixelpen.sim.base import simulator_models\nprint(simulator_models())\n"
            "print(any(m.startswith('pixelpen.sim.plotters') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0] == repr(sorted(BUILTIN_SIMULATORS)) and out[1] == "False"


def test_a_simulator_registers_the_url_options_it_reads() -> None:
    from pixelpen.options import OptionSpec, positive
    from pixelpen.sim.base import register_simulator, simulator_options

    spec = OptionSpec("speed", positive, 1.0, "mm/s")
    register_simulator("probe-with-options", lambda **kw: Recorder(), (spec,))

    def factory(**kw):
        return Recorder()

    factory.OPTIONS = (spec,)  # type: ignore[attr-defined]
    register_simulator("probe-with-attribute", factory)
    assert simulator_options("probe-with-options") == (spec,) == simulator_options("probe-with-attribute")
    assert {s.name for s in simulator_options("grbl")} >= {"rx_buffer", "planner", "pen"}
    assert {s.name for s in simulator_options("hp7550a")} >= {"buffer"}

"""Tests of the plugin's input fixtures: a user's test file using sim_input and replay_input, run by pytester.

Expected values are hand-packed reports (boot mouse: HID 1.11 Appendix B.2) and the scripts' geometry.
"""

from importlib import metadata

import numpy  # noqa: F401 - imported before pytester's in-process runs, which restore sys.modules after each
import pytest

import pixelpen.pytest_plugin  # noqa: F401
from pixelpen.sim.base import simulator_models

pytest_plugins = ["pytester"]
simulator_models()  # load the simulator registry once, outside the inner runs

USER_TESTS = '''
import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.devices.hid.events import Button, DeviceRemoved, Key, Motion, Pen, TouchFrame
from pixelpen.drivers.recordings.hidrecorder import HidRecording
from pixelpen.errors import ConfigError
from pixelpen.sim.hid.descriptors import BOOT_MOUSE

# two boot mouse reports (HID 1.11 B.2): left button, X +5, Y -3; then release, X -2, Y 0
REPORTS = [(0.0, bytes([0x01, 0x05, 0xFD])), (0.25, bytes([0x00, 0xFE, 0x00]))]


def everything(device, timeout=1.0):
    """The application under test: it reads every event until the device is quiet."""
    return list(device.events(timeout))


def test_a_tablet_signs_on_a_simulated_clock(sim_input):
    device = sim_input("tablet", script="signature")
    assert isinstance(device.clock, SimulatedClock)
    pens = [e for e in everything(device) if isinstance(e, Pen)]
    downs = sum(1 for a, b in zip(pens, pens[1:]) if b.touching and not a.touching)
    assert downs == 4  # three words and the underline
    assert all(0 < e.pressure <= 1 for e in pens if e.touching)
    assert all(0 <= e.x_mm <= 224 and 0 <= e.y_mm <= 140 for e in pens)
    assert not pens[-1].in_range
    assert sim_input.simulator(device).model == "tablet"


def test_a_keyboard_types_and_shows_its_leds(sim_input):
    device = sim_input("keyboard", script="typing:Hi!")
    typed = "".join(e.char for e in everything(device) if isinstance(e, Key) and e.pressed)
    assert typed == "Hi!"
    sim = sim_input.simulator(device)
    sim.write_report(bytes([0x02]))  # the host lights Caps Lock
    assert sim.firmware.leds == {"caps_lock"}


def test_options_reach_the_simulator_and_bad_ones_name_themselves(sim_input):
    device = sim_input("touchscreen", script="pinch", fingers=3, hz=200)
    frames = [e for e in everything(device) if isinstance(e, TouchFrame)]
    assert max(len(f.contacts) for f in frames) == 3
    assert sim_input.simulator(device).hz == 200
    with pytest.raises(ConfigError, match="fingers"):
        sim_input("touchscreen", fingers=11)
    with pytest.raises(pytest.UsageError, match="'id'"):
        sim_input("mouse", id="mine")


def test_a_descriptor_and_its_reports(sim_input):
    device = sim_input(BOOT_MOUSE, reports=REPORTS)
    events = everything(device)
    assert [(e.dx, e.dy) for e in events if isinstance(e, Motion)] == [(5, -3), (-2, 0)]
    assert [(e.button, e.pressed) for e in events if isinstance(e, Button)] == [(1, True), (1, False)]
    assert [e.time for e in events if isinstance(e, Motion)] == pytest.approx([0.0, 0.25])


def test_a_recording_object(sim_input):
    recording = HidRecording("pen mouse", "", 3, 0x1209, 0x0001, BOOT_MOUSE, REPORTS)
    events = everything(sim_input(recording))
    assert [(e.dx, e.dy) for e in events if isinstance(e, Motion)] == [(5, -3), (-2, 0)]


def test_a_hid_recorder_file(replay_input, tmp_path):
    path = tmp_path / "mouse.hid"
    path.write_text("N: pen mouse\\nI: 3 1209 0001\\nR: 50 " + BOOT_MOUSE.hex(" ") + "\\n"
                    "E: 000000.000000 3 01 05 fd\\nE: 000000.250000 3 00 fe 00\\n")
    events = everything(replay_input(path))
    assert [(e.dx, e.dy) for e in events if isinstance(e, Motion)] == [(5, -3), (-2, 0)]


def test_a_power_loss_is_a_removed_device(sim_input):
    device = sim_input("mouse", script="circle", repeat=True)
    assert device.read(1.0)
    sim_input.simulator(device).inject("power-loss")
    events = everything(device)
    assert isinstance(events[-1], DeviceRemoved)


def test_several_devices_in_one_test(sim_input):
    a, b = sim_input("mouse"), sim_input("mouse")
    assert sim_input.simulator(a) is not sim_input.simulator(b)
    assert a.read(1.0) and b.read(1.0)
'''


def _plugin_args() -> list[str]:
    """Load the plugin by module name unless its entry point is installed (then pytest loads it by itself)."""
    installed = any(ep.name == "pixelpen" for ep in metadata.entry_points(group="pytest11"))
    quiet = ["-p", "no:cacheprovider", "-p", "no:benchmark", "-W", "ignore::pytest.PytestAssertRewriteWarning"]
    return quiet + ([] if installed else ["-p", "pixelpen.pytest_plugin"])


def test_input_fixtures_in_a_user_test_file(pytester: pytest.Pytester) -> None:
    pytester.makepyfile(test_user=USER_TESTS)
    result = pytester.runpytest(*_plugin_args())
    result.assert_outcomes(passed=8)


def test_sim_input_refuses_what_it_cannot_simulate() -> None:
    from pixelpen.pytest_plugin import SimInput

    factory = SimInput()
    with pytest.raises(pytest.UsageError, match="model name, descriptor bytes or a HidRecording"):
        factory(42)  # type: ignore[arg-type]
    with pytest.raises(LookupError, match="not opened by sim_input"):
        factory.simulator(object())  # type: ignore[arg-type]
    factory.finish()


def test_devices_are_closed_and_simulators_forgotten_when_the_test_ends() -> None:
    from pixelpen.pytest_plugin import SimInput
    from pixelpen.sim.base import named_simulator

    factory = SimInput()
    device = factory("joystick")
    sim = factory.simulator(device)
    names = list(factory._named)
    factory.finish()
    assert device.closed and sim.closed
    with pytest.raises(KeyError):
        named_simulator(names[0])

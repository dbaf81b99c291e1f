"""The input URL registry: schemes by module name, sim: and replay: through the real HidapiLink, errors."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import ClassVar

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.devices.hid.events import Button, Motion, Pen
from pixelpen.errors import URLError
from pixelpen.input import open_input, registry
from pixelpen.input.registry import BUILTIN_INPUTS, input_opener, input_scheme_names, register_input
from pixelpen.sim.hid.descriptors import BOOT_MOUSE


def test_builtin_schemes_are_listed_without_importing_them() -> None:
    assert {"sim", "hid", "replay", "evdev", "evemu"} <= set(input_scheme_names())
    assert all(target.startswith("pixelpen.input.") for target in BUILTIN_INPUTS.values())


def test_importing_the_registry_imports_no_simulator_and_no_numpy() -> None:
    code = ("import sys, pixelpen, pixelpen.input.registry; "
            "print(any(m.startswith('pixelpen.sim') for m in sys.modules), 'numpy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


def test_unknown_scheme_lists_the_known() -> None:
    with pytest.raises(URLError, match=r"unknown input scheme 'nope'.*evdev.*sim"):
        input_opener("nope")


def test_register_input_refuses_a_second_owner(monkeypatch: pytest.MonkeyPatch) -> None:
    def opener(url, *, clock, options):  # type: ignore[no-untyped-def]
        raise AssertionError

    monkeypatch.setattr(registry, "_OPENERS", dict(registry._OPENERS))  # the scheme leaves with the test
    register_input("test-scheme-x")(opener)
    assert input_opener("test-scheme-x") is opener
    with pytest.raises(URLError, match="already registered"):
        register_input("test-scheme-x")(lambda url, *, clock, options: None)  # type: ignore[arg-type,misc]


def test_sim_url_opens_the_model_with_its_options_and_semantics_options() -> None:
    clock = SimulatedClock()
    with open_input("sim:tablet?script=signature&pressure_curve=gamma:2", clock=clock) as dev:
        assert dev.device_id.path.startswith("sim:tablet:")
        pens = [e for e in dev.events(timeout=1.0) if isinstance(e, Pen)]
    assert len(pens) > 100 and any(p.touching for p in pens)
    assert all(0.0 <= p.x <= 1.0 and 0.0 <= p.y <= 1.0 for p in pens)


def test_sim_url_refuses_an_option_nobody_declares() -> None:
    with pytest.raises(URLError, match="papr"):
        open_input("sim:trackball?papr=a4", clock=SimulatedClock())


RECORDING = f"""\
# a boot mouse (HID 1.11 B.2) written by hand: two reports
R: 50 {BOOT_MOUSE.hex(" ")}
N: hand mouse
I: 3 1209 0001
E: 000000.000000 3 01 05 fb
E: 000000.010000 3 00 fd 02
"""


def test_replay_url_plays_a_hid_recorder_file(tmp_path: Path) -> None:
    path = tmp_path / "mouse.hid"
    path.write_text(RECORDING)
    with open_input(f"replay:{path}") as dev:
        events = list(dev.events(timeout=1.0))
    motions = [(e.dx, e.dy) for e in events if isinstance(e, Motion)]
    buttons = [(e.button, e.pressed) for e in events if isinstance(e, Button)]
    assert motions == [(5, -5), (-3, 2)]  # 0xfb = -5, 0xfd = -3 (int8)
    assert buttons == [(1, True), (1, False)]


def test_replay_url_plays_the_reports_after_the_first(tmp_path: Path) -> None:
    path = tmp_path / "mouse.hid"
    path.write_text(RECORDING)
    with open_input(f"replay:{path}") as dev:
        events = list(dev.events(timeout=1.0))
        assert dev.clock.now() == pytest.approx(1.01)  # the replay's own simulated clock: last report, then 1 s
    assert [(e.dx, e.dy) for e in events if isinstance(e, Motion)][-1] == (-3, 2)  # 0xfd = -3 (int8)


def test_a_realtime_replay_keeps_its_first_report(tmp_path: Path) -> None:
    path = tmp_path / "mouse.hid"
    path.write_text(RECORDING)
    with open_input(f"replay:{path}?realtime=true&delay=0.05") as dev:  # the real clock: opening takes time
        events = list(dev.events(timeout=0.3))
    assert [(e.dx, e.dy) for e in events if isinstance(e, Motion)] == [(5, -5), (-3, 2)]


@pytest.mark.parametrize(("model", "reach"), [("hp7475a", "a byte stream"), ("st7789", "a panel bus")])
def test_a_simulator_without_hid_reports_is_no_input_device(model: str, reach: str) -> None:
    with pytest.raises(URLError, match=f"reached through {reach}"):
        open_input(f"sim:{model}")


def test_replay_url_names_a_missing_device_index(tmp_path: Path) -> None:
    path = tmp_path / "mouse.hid"
    path.write_text(RECORDING)
    with pytest.raises(URLError, match=r"device=3.*1 device"):
        open_input(f"replay:{path}?device=3")


EVEMU = """\
# EVEMU 1.3
N: hand pen
I: 0003 056a 0001 0100
P: 00 00 00 00 00 00 00 00
B: 00 0b 00 00 00 00 00 00 00
B: 03 03 00 00 01 00 00 00 00
A: 00 0 1000 0 0 10
A: 01 0 500 0 0 10
A: 18 0 1023 0 0 0
E: 0.000000 0003 0000 0500
E: 0.000000 0003 0001 0250
E: 0.000000 0000 0000 0000
E: 0.500000 0003 0018 0341
E: 0.500000 0000 0000 0000
"""


def test_evemu_url_plays_the_recording_on_a_simulated_clock(tmp_path: Path) -> None:
    path = tmp_path / "pen.evemu"
    path.write_text(EVEMU)
    with open_input(f"evemu:{path}") as dev:
        pens = [e for e in dev.events(timeout=1.0) if isinstance(e, Pen)]
        assert dev.clock.now() == pytest.approx(1.5)  # the last event at 0.5 s, then the 1 s timeout
    # ABS_X 500 of 0..1000 at 10 units/mm, ABS_Y 250 of 0..500; pressure 341 of 0..1023 = 1/3
    assert [(p.x, p.y, p.x_mm, p.y_mm) for p in pens[:1]] == [(0.5, 0.5, 50.0, 25.0)]
    assert [p.time for p in pens] == [0.0, 0.5] and pens[-1].pressure == pytest.approx(1 / 3)


class FakeEvdevLink:
    """Stands in for drivers.evdev.EvdevLink: a pen node with one frame waiting."""

    opened: ClassVar[list[FakeEvdevLink]] = []

    def __init__(self, path: str, *, grab: bool = False, clock: object = None) -> None:
        from pixelpen.devices.hid.events import DeviceId
        from pixelpen.drivers.recordings.evemu import AbsInfo

        self.path, self.grabbed, self.closed = path, grab, False
        self.device_id = DeviceId("usb", 0x056A, 0x0001, name="fake pen", path=path)
        self.absinfo = {0x00: AbsInfo(0, 0, 1000, 0, 0, 10), 0x01: AbsInfo(0, 0, 500, 0, 0, 10),
                        0x18: AbsInfo(0, 0, 1023, 0, 0, 0)}
        self.codes = {0x01: frozenset({0x140, 0x14A})}  # BTN_TOOL_PEN, BTN_TOUCH
        self.frames = [[(0.0, 1, 0x140, 1), (0.0, 3, 0x00, 250), (0.0, 3, 0x01, 125), (0.0, 0, 0, 0)]]
        FakeEvdevLink.opened.append(self)

    def read_events(self, timeout: float | None = None) -> list[tuple[float, int, int, int]]:
        return self.frames.pop(0) if self.frames else []

    def close(self) -> None:
        self.closed = True


def test_evdev_url_reads_a_node_through_the_evdev_semantics(monkeypatch: pytest.MonkeyPatch) -> None:
    import pixelpen.drivers.evdev

    monkeypatch.setattr(pixelpen.drivers.evdev, "EvdevLink", FakeEvdevLink)
    with open_input("evdev:/dev/input/event7?grab=true", clock=SimulatedClock()) as dev:
        (pen,) = dev.read(0)
        assert dev.read(0) == []
    link = FakeEvdevLink.opened[-1]
    assert (link.path, link.grabbed, link.closed) == ("/dev/input/event7", True, True)
    assert isinstance(pen, Pen) and (pen.x, pen.y, pen.x_mm, pen.y_mm) == (0.25, 0.25, 25.0, 12.5)
    with pytest.raises(URLError, match="colour"):
        open_input("evdev:/dev/input/event7?colour=red")

"""The simulated models: hid-tools (not pixelpen's decoder) reads what each firmware sends, and it must be the hand.

Expected values come from the script's hand at each report's time and the resolutions hid-tools reads from the
descriptors (logical over physical range), never from the firmware's own constants.
"""

from __future__ import annotations

import itertools
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError, Disconnected, ProtocolError
from pixelpen.sim.base import BUILTIN_SIMULATORS, ReportDevice, create_simulator, simulator_options
from pixelpen.sim.hid import descriptors, models
from pixelpen.sim.hid.device import HidSim
from pixelpen.sim.hid.motion import Hand, Script
from tests.sim.hid import hidtools_report

MODELS = ("mouse", "trackball", "joystick", "gamepad", "tablet", "touchscreen", "keyboard")


def run(model: str, seconds: float, **options: Any) -> tuple[HidSim, list[tuple[float, dict[str | int, list[Any]]]]]:
    """The simulator of ``model`` after ``seconds`` on a simulated clock from 0, and its reports read by hid-tools."""
    clock = SimulatedClock()
    sim = create_simulator(model, clock=clock, **{k: str(v) for k, v in options.items()})
    assert isinstance(sim, HidSim)
    clock.advance(seconds)
    return sim, [(t, hidtools_report(sim.report_descriptor, r)) for t, r in sim.take_timed_reports()]


def field(descriptor: bytes, name: str, kind: str = "input_reports") -> Any:
    """hid-tools' field of usage ``name`` (the test skipped without hid-tools)."""
    hid = pytest.importorskip("hidtools.hid")
    rd = hid.ReportDescriptor.from_bytes(list(descriptor))
    return next(f for r in getattr(rd, kind).values() for f in r.fields if f.usage_name == name)


def per_mm(descriptor: bytes, name: str, exponent: int, unit_mm: float) -> float:
    """Logical counts per mm of an axis: logical range over physical range x 10^exponent units of ``unit_mm`` mm."""
    f = field(descriptor, name)
    return (f.logical_max - f.logical_min) / ((f.physical_max - f.physical_min) * 10.0**exponent * unit_mm)


def test_every_model_is_built_in_and_is_a_report_device() -> None:
    for model in MODELS:
        assert BUILTIN_SIMULATORS[model] == "pixelpen.sim.hid.models"
        sim = create_simulator(model, clock=SimulatedClock())
        assert isinstance(sim, ReportDevice) and isinstance(sim, HidSim) and sim.model == model
        assert {"script", "hz", "period", "repeat"} <= {s.name for s in simulator_options(model)}
        assert sim.info["vendor_id"] == 0x1209 and sim.info["product_string"]


def test_mouse_deltas_add_up_to_the_hand_s_path_at_its_cpi_and_pen_down_is_button_1() -> None:
    sim, reports = run("mouse", 3.0, script="circle", cpi=1000)
    script = sim.firmware.script  # type: ignore[attr-defined]
    counts_per_mm = 1000 / 25.4
    start = script.at(0.0)
    x = y = 0
    assert len(reports) > 200
    for t, v in reports:
        x, y = x + v["X"][0], y + v["Y"][0]
        hand = script.at(t)
        assert abs(x - (hand.x - start.x) * counts_per_mm) <= 1.0
        assert abs(y - (hand.y - start.y) * counts_per_mm) <= 1.0
        assert v["B1"] == [int(hand.pressure > 0)] and v["B2"] == v["B3"] == [0]
    assert reports[-1][1]["B1"] == [0]  # the release


def test_mouse_carries_motion_beyond_127_counts_into_the_next_reports() -> None:
    sim, reports = run("mouse", 1.5, script="line", period=0.05, cpi=4000)  # 60 mm in 50 ms at 157 counts/mm
    script = sim.firmware.script  # type: ignore[attr-defined]
    assert [v["X"][0] for _, v in reports[5:60]] == [127] * 55
    total = sum(v["X"][0] for _, v in reports)
    assert total == round(script.at(1.0).x * 4000 / 25.4) - round(script.at(0.0).x * 4000 / 25.4)


def test_trackball_counts_at_the_400_cpi_its_descriptor_states() -> None:
    cpi = per_mm(descriptors.TRACKBALL, "X", -2, 25.4) * 25.4
    assert cpi == pytest.approx(400.0)
    sim, reports = run("trackball", 2.0, script="line")
    script = sim.firmware.script  # type: ignore[attr-defined]
    x = sum(v["X"][0] for _, v in reports)
    assert x == pytest.approx((script.at(1.0).x - script.at(0.0).x) * cpi / 25.4, abs=1.0)
    assert all(v["Y"] == [0] and v["Wheel"] == [0] for _, v in reports)


def test_trackball_wheel_counts_detents_until_the_host_sets_the_resolution_multiplier() -> None:
    sim, reports = run("trackball", 3.0, script="scroll")
    assert sum(v["Wheel"][0] for _, v in reports) == 5 and sum(v["AC Pan"][0] for _, v in reports) == 5
    assert sim.get_feature(2) == b"\x02\x00"

    clock = SimulatedClock()
    sim = create_simulator("trackball", clock=clock, script="scroll", period="2")
    sim.send_feature(b"\x02\x05")  # both multipliers at logical 1: physical 8 counts per detent
    assert hidtools_report(descriptors.TRACKBALL, sim.get_feature(2), "feature")["Resolution Multiplier"] == [1]
    clock.advance(4.0)
    wheel = [hidtools_report(descriptors.TRACKBALL, r) for r in sim.take_reports()]
    assert sum(v["Wheel"][0] for v in wheel) == 40 and sum(v["AC Pan"][0] for v in wheel) == 40
    assert len([v for v in wheel if v["Wheel"][0]]) > 5  # hi-res: many small steps


def test_trackball_refuses_a_multiplier_outside_its_logical_range_and_unknown_features() -> None:
    sim = create_simulator("trackball", clock=SimulatedClock())
    with pytest.raises(ProtocolError, match="outside its logical range"):
        sim.send_feature(b"\x02\x02")
    with pytest.raises(ProtocolError, match="STALL"):
        sim.get_feature(1)
    with pytest.raises(ProtocolError, match="not 2 bytes"):
        sim.send_feature(b"\x02\x01\x00")


def test_trackball_multipliers_reset_at_power_up() -> None:
    sim = create_simulator("trackball", clock=SimulatedClock())
    sim.send_feature(b"\x02\x01")
    sim.inject("reset")
    assert sim.get_feature(2) == b"\x02\x00"


def test_joystick_reports_the_hand_s_axes_hat_and_buttons() -> None:
    sim, reports = run("joystick", 4.0, script="sweep")
    script = sim.firmware.script  # type: ignore[attr-defined]
    hats = set()
    for t, v in reports:
        hand = script.at(t)
        assert v["X"][0] == pytest.approx(127 * hand.axes["x"], abs=0.5)
        assert v["Y"][0] == pytest.approx(127 * hand.axes["y"], abs=0.5)
        assert v["Throttle"][0] == pytest.approx(-127 + 254 * hand.axes["throttle"], abs=0.5)
        assert v["Hat switch"] == [8 if hand.hat is None else hand.hat]
        assert [v[f"B{i}"][0] for i in range(1, 5)] == [int(i in hand.buttons) for i in range(1, 5)]
        hats.add(v["Hat switch"][0])
    assert hats == set(range(9))


def test_gamepad_sticks_centre_at_0x80_and_reach_both_ends() -> None:
    sim, reports = run("gamepad", 4.0, script="sweep")
    script = sim.firmware.script  # type: ignore[attr-defined]
    for t, v in reports:
        hand = script.at(t)
        for usage, axis in (("X", "x"), ("Y", "y"), ("Z", "z"), ("Rz", "rz")):
            assert (v[usage][0] - 128) / 127.5 == pytest.approx(hand.axes[axis], abs=1 / 127.5)
        assert v["Rx"][0] == pytest.approx(255 * hand.axes["rx"], abs=0.5)
        assert [v[f"B{i}"][0] for i in range(1, 15)] == [int(i in hand.buttons) for i in range(1, 15)]
    xs = [v["X"][0] for _, v in reports]
    assert min(xs) == 0 and max(xs) >= 254
    assert {b for _, v in reports for b in range(1, 15) if v[f"B{b}"] == [1]} == set(range(1, 15))
    _, centred = run("gamepad", 3.0, script="orbit")
    assert [centred[-1][1][a] for a in ("X", "Y", "Z", "Rz")] == [[128]] * 4


def test_tablet_reports_position_pressure_tilt_and_proximity_of_the_signature() -> None:
    res_x = per_mm(descriptors.PEN_TABLET, "X", -3, 10.0)  # cm, exponent -3 (the descriptor's nibble 0x0D)
    res_y = per_mm(descriptors.PEN_TABLET, "Y", -3, 10.0)
    assert res_x == pytest.approx(200.0) and res_y == pytest.approx(200.0)
    levels = field(descriptors.PEN_TABLET, "Tip Pressure").logical_max
    sim, reports = run("tablet", 6.0, script="signature", serial=12345)
    script = sim.firmware.script  # type: ignore[attr-defined]
    touching = 0
    for t, v in reports[:-1]:
        hand = script.at(t)
        assert v["In Range"] == [1] and hand.in_range
        assert v["X"][0] == pytest.approx(hand.x * res_x, abs=0.5)
        assert v["Y"][0] == pytest.approx(hand.y * res_y, abs=0.5)
        assert v["Tip Switch"] == [int(hand.pressure > 0)]
        assert v["Tip Pressure"][0] == pytest.approx(hand.pressure * levels, abs=0.5)
        assert v["X Tilt"][0] == pytest.approx(hand.tilt_x, abs=0.5)
        assert v["Y Tilt"][0] == pytest.approx(hand.tilt_y, abs=0.5)
        assert v["Transducer Serial Number"] == [12345] and v["Eraser"] == v["Invert"] == [0]
        touching += v["Tip Switch"][0]
    assert touching > 300
    assert reports[-1][1]["In Range"] == [0] and reports[-1][1]["Tip Pressure"] == [0]  # leaving proximity
    assert sim.next_event_time() is None  # nothing more once away


def test_tablet_eraser_end_reports_invert_in_range_and_eraser_touching() -> None:
    _, reports = run("tablet", 2.0, script="line", tool="eraser")
    assert all(v["Invert"] == [1] and v["Tip Switch"] == [0] for _, v in reports[:-1])
    assert any(v["Eraser"] == [1] and v["Tip Pressure"][0] > 0 for _, v in reports)


def test_tablet_barrel_buttons_are_the_hand_s_buttons_1_and_2() -> None:
    script = Script("hold", 0.5, lambda t: Hand(x=10, y=10, in_range=True, buttons=frozenset({1, 2})))
    firmware = models.Tablet(descriptors.PEN_TABLET, script, tool="pen", serial=1)
    (report,) = firmware.poll(0.1)
    v = hidtools_report(descriptors.PEN_TABLET, report)
    assert (v["Barrel Switch"], v["Secondary Barrel Switch"], v["Tip Switch"]) == ([1], [1], [0])


Decoded = list[tuple[float, dict[str | int, list[Any]]]]
"""Reports read by hid-tools with their times."""


def frames(reports: Decoded) -> list[tuple[float, list[tuple[int, int, int, int]]]]:
    """Touch reports grouped into frames by their contact count (hybrid mode): (first report's time, contacts)."""
    out: list[tuple[float, list[tuple[int, int, int, int]]]] = []
    expected = 0
    for t, v in reports:
        slots = list(zip(v["Tip Switch"], v["Contact Id"], v["X"], v["Y"], strict=True))
        if v["Contact Count"][0]:
            assert expected == 0, "a new frame began before the last was complete"
            expected = v["Contact Count"][0]
            out.append((t, []))
            scan = v["Scan Time"]
        else:
            assert v["Scan Time"] == scan, "a frame's reports share its scan time"
        take = min(expected, 2)
        out[-1][1].extend(slots[:take])
        expected -= take
    assert expected == 0
    return out


def test_touchscreen_frames_are_the_fingers_of_the_pinch_and_then_their_lift() -> None:
    res = per_mm(descriptors.TOUCHSCREEN, "X", -2, 10.0)
    assert res == pytest.approx(16.0)
    sim, reports = run("touchscreen", 3.0, script="pinch", fingers=2)
    script = sim.firmware.script  # type: ignore[attr-defined]
    got = frames(reports)
    for t, contacts in got[:-1]:
        hand = script.at(t)
        assert [(tip, cid) for tip, cid, _, _ in contacts] == [(1, cid) for cid, _, _ in hand.contacts]
        for (_, _, x, y), (_, hx, hy) in zip(contacts, hand.contacts, strict=True):
            assert x == pytest.approx(hx * res, abs=0.5) and y == pytest.approx(hy * res, abs=0.5)
    assert [(tip, cid) for tip, cid, _, _ in got[-1][1]] == [(0, 0), (0, 1)]  # lifted, at their last places
    assert got[-1][1][0][2:] == got[-2][1][0][2:]


def test_touchscreen_hybrid_mode_sends_one_report_per_interval_count_in_the_first() -> None:
    sim, reports = run("touchscreen", 0.6, script="pinch", fingers=5, hz=100)
    times = [t for t, _ in reports]
    assert times == pytest.approx([k / 100 for k in range(1, len(times) + 1)])  # one per polling interval
    counts = [v["Contact Count"][0] for _, v in reports]
    assert counts[:6] == [5, 0, 0, 5, 0, 0]
    got = frames(reports)
    script = sim.firmware.script  # type: ignore[attr-defined]
    t, contacts = got[0]
    assert [cid for _, cid, _, _ in contacts] == [cid for cid, _, _ in script.at(t).contacts] == [0, 1, 2, 3, 4]


def test_touchscreen_honours_contact_count_maximum_and_input_mode() -> None:
    clock = SimulatedClock()
    sim = create_simulator("touchscreen", clock=clock, script="pinch", fingers="5")
    assert hidtools_report(descriptors.TOUCHSCREEN, sim.get_feature(2), "feature")["Contact Max"] == [10]
    assert sim.get_feature(3) == b"\x03\x02"
    sim.send_feature(b"\x02\x03")
    clock.advance(0.2)
    got = frames([(0.0, hidtools_report(descriptors.TOUCHSCREEN, r)) for r in sim.take_reports()])
    assert {tuple(cid for _, cid, _, _ in c) for _, c in got} == {(0, 1, 2)}
    sim.send_feature(b"\x03\x01")  # single-input: the first contact only
    clock.advance(0.2)
    got = frames([(0.0, hidtools_report(descriptors.TOUCHSCREEN, r)) for r in sim.take_reports()])
    assert {tuple(cid for tip, cid, _, _ in c if tip) for _, c in got} == {(0,)}
    sim.send_feature(b"\x03\x00")  # mouse mode: this collection says nothing more after the lift
    clock.advance(0.2)
    assert len(sim.take_reports()) <= 1
    with pytest.raises(ProtocolError, match="Input Mode 5"):
        sim.send_feature(b"\x03\x05")
    with pytest.raises(ProtocolError, match="Contact Count Maximum 0"):
        sim.send_feature(b"\x02\x00")
    with pytest.raises(ProtocolError, match="STALL"):
        sim.get_feature(1)
    sim.inject("reset")
    assert sim.get_feature(2) == b"\x02\x0a" and sim.get_feature(3) == b"\x03\x02"


def test_touchscreen_takes_a_pen_down_hand_as_one_finger() -> None:
    _, reports = run("touchscreen", 2.0, script="line")
    got = frames(reports)
    assert got and all([cid for _, cid, _, _ in c] == [0] for _, c in got)


def test_touchscreen_power_up_mode_option() -> None:
    _, reports = run("touchscreen", 1.0, script="pinch", mode="mouse")
    assert reports == []


def keys_of(v: dict[str | int, list[Any]]) -> set[int]:
    """Keyboard usages down in a decoded boot report (modifiers as 0xE0..0xE7)."""
    mods = {0xE0 + i for i, name in enumerate(("LeftControl", "LeftShift", "LeftAlt", "Left GUI", "RightControl",
                                               "RightShift", "RightAlt", "Right GUI")) if v[name] == [1]}
    return mods | {k for k in v["Keyboard"] if k}


def test_keyboard_boot_reports_are_the_keys_the_typist_holds() -> None:
    sim, reports = run("keyboard", 3.0, script="typing:Hi!")
    script = sim.firmware.script  # type: ignore[attr-defined]
    for t, v in reports:
        assert keys_of(v) == set(script.at(t).keys)
    pressed = [keys_of(v) for _, v in reports]
    # H = Shift + 0x0B, i = 0x0C, ! = Shift + 0x1E (HID Usage Tables §10)
    assert {0xE1, 0x0B} in pressed and {0x0C} in pressed and {0xE1, 0x1E} in pressed
    assert pressed[-1] == set()


def test_keyboard_nkro_reports_every_key_in_its_bitmap() -> None:
    sim, reports = run("keyboard", 2.0, script="typing:a1", protocol="nkro")
    assert sim.report_descriptor == descriptors.NKRO_KEYBOARD
    script = sim.firmware.script  # type: ignore[attr-defined]
    for t, v in reports:
        down = {u & 0xFF for u in range(0x70000, 0x700E8) if v.get(u) == [1]}
        assert down == set(script.at(t).keys)
    assert len(reports) == 4


def test_a_boot_keyboard_with_seven_keys_down_reports_error_roll_over() -> None:
    chord = Script("chord", 0.5, lambda t: Hand(keys=frozenset({0xE0, *range(0x04, 0x0B)})))
    firmware = models.Keyboard(descriptors.BOOT_KEYBOARD, chord, nkro=False)
    (report,) = firmware.poll(0.1)
    v = hidtools_report(descriptors.BOOT_KEYBOARD, report)
    assert v["Keyboard"] == [0x01] * 6 and v["LeftControl"] == [1]
    nkro = models.Keyboard(descriptors.NKRO_KEYBOARD, chord, nkro=True)
    (report,) = nkro.poll(0.1)
    bitmap = hidtools_report(descriptors.NKRO_KEYBOARD, report)
    assert {u & 0xFF for u in range(0x70004, 0x70098) if bitmap[u] == [1]} == set(range(0x04, 0x0B))


def test_keyboard_leds_follow_the_output_report_until_power_is_lost() -> None:
    sim = create_simulator("keyboard", clock=SimulatedClock(), script="idle")
    sim.write_report(b"\x03")
    assert sim.firmware.leds == {"num_lock", "caps_lock"}
    with pytest.raises(ProtocolError, match="output report"):
        sim.write_report(b"\x03\x00")
    sim.inject("power-loss")
    with pytest.raises(Disconnected):
        sim.write_report(b"\x01")
    sim.inject("power-restore")
    assert sim.firmware.leds == frozenset()
    nkro = create_simulator("keyboard", clock=SimulatedClock(), script="idle", protocol="nkro")
    nkro.write_report(b"\x01\x14")
    assert nkro.firmware.leds == {"scroll_lock", "kana"}
    with pytest.raises(ProtocolError, match="report ID 1"):
        nkro.write_report(b"\x02\x14")


def test_a_mouse_does_not_jump_for_the_motion_made_while_it_was_off() -> None:
    clock = SimulatedClock()
    sim = create_simulator("mouse", clock=clock, script="circle", repeat="true")
    clock.advance(0.2)
    sim.inject("power-loss")
    clock.advance(0.5)
    sim.take_reports()
    sim.inject("power-restore")
    clock.advance(0.1)
    after = [hidtools_report(descriptors.BOOT_MOUSE, r) for r in sim.take_reports()]
    normal = max(abs(v["X"][0]) + abs(v["Y"][0]) for v in after)
    assert 0 < normal < 30  # a circle of 18 mm radius in 2 s: at most 14 counts per axis per 8 ms at 800 cpi


def test_polling_rate_option_sets_the_interval() -> None:
    _, reports = run("joystick", 1.0, script="sweep", hz=1000)
    times = [t for t, _ in reports]
    assert len(times) > 500 and min(b - a for a, b in itertools.pairwise(times)) == pytest.approx(0.001)


@pytest.mark.parametrize(("model", "options", "match"), [
    ("mouse", {"script": "wiggle"}, "option script='wiggle' is not valid"),
    ("mouse", {"script": "typing"}, "option script='typing' is not valid"),
    ("mouse", {"script": "sweep"}, "option script='sweep' does not apply to a mouse"),
    ("keyboard", {"script": "circle"}, "does not apply to a keyboard"),
    ("keyboard", {"script": "typing:caf\u00e9"}, "option script='typing:caf\u00e9': typing: character"),
    ("mouse", {"hz": "0"}, "option hz='0' is not valid"),
    ("mouse", {"hz": "9000"}, "option hz='9000' is not valid"),
    ("tablet", {"script": "signature", "period": "2"}, "option period does not apply to script=signature"),
    ("tablet", {"script": "line", "repeat": "yes"}, "option repeat does not apply to script=line"),
    ("tablet", {"tool": "brush"}, "option tool='brush' is not valid"),
    ("tablet", {"serial": "-1"}, "option serial='-1' is not valid"),
    ("touchscreen", {"contacts": "11"}, "option contacts='11' is not valid"),
    ("mouse", {"cpii": "400"}, "unknown option.*cpii.*did you mean 'cpi'"),
    ("joystick", {"cpi": "400"}, "unknown option"),
])
def test_bad_options_raise_config_error_naming_the_option(model: str, options: dict[str, str], match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        create_simulator(model, clock=SimulatedClock(), **options)


def test_layout_refuses_a_value_that_does_not_fit_its_field() -> None:
    with pytest.raises(Exception, match="does not fit 8 bits"):
        models.MOUSE_IN.pack(x=128)
    assert models.MOUSE_IN.pack(buttons=5, x=-1, y=2) == bytes([0x05, 0xFF, 0x02])
    assert models.MOUSE_IN.value(bytes([0x05, 0xFF, 0x02]), "x") == -1


def test_scripts_default_per_model_and_follow_the_surface() -> None:
    defaults = {m: next(s.default for s in simulator_options(m) if s.name == "script") for m in MODELS}
    assert defaults == {"mouse": "circle", "trackball": "circle", "joystick": "sweep", "gamepad": "sweep",
                        "tablet": "signature", "touchscreen": "pinch", "keyboard": "typing:hello"}


@settings(max_examples=60, deadline=None)
@given(x=st.integers(0, 44800), y=st.integers(0, 28000), pressure=st.integers(0, 8191),
       tilt=st.tuples(st.integers(-64, 63), st.integers(-64, 63)), serial=st.integers(0, 2**31 - 1),
       switches=st.lists(st.booleans(), min_size=6, max_size=6))
def test_the_tablet_layout_packs_what_hid_tools_reads(x: int, y: int, pressure: int, tilt: tuple[int, int],
                                                       serial: int, switches: list[bool]) -> None:
    names = ("tip", "barrel", "invert", "eraser", "barrel2", "in_range")
    report = models.TABLET_IN.pack(x=x, y=y, pressure=pressure, tilt_x=tilt[0], tilt_y=tilt[1], serial=serial,
                                   **dict(zip(names, map(int, switches), strict=True)))
    v = hidtools_report(descriptors.PEN_TABLET, report)
    assert (v["X"], v["Y"], v["Tip Pressure"], v["X Tilt"], v["Y Tilt"]) == ([x], [y], [pressure], [tilt[0]],
                                                                             [tilt[1]])
    assert v["Transducer Serial Number"] == [serial]
    usages = ("Tip Switch", "Barrel Switch", "Invert", "Eraser", "Secondary Barrel Switch", "In Range")
    assert [v[u][0] for u in usages] == [int(s) for s in switches]


@settings(max_examples=60, deadline=None)
@given(sticks=st.lists(st.integers(0, 255), min_size=6, max_size=6), hat=st.integers(0, 8),
       buttons=st.integers(0, 2**14 - 1))
def test_the_gamepad_layout_packs_what_hid_tools_reads(sticks: list[int], hat: int, buttons: int) -> None:
    names = ("x", "y", "z", "rz", "rx", "ry")
    report = models.GAMEPAD_IN.pack(hat=hat, buttons=buttons, **dict(zip(names, sticks, strict=True)))
    v = hidtools_report(descriptors.GAMEPAD, report)
    assert [v[u][0] for u in ("X", "Y", "Z", "Rz", "Rx", "Ry")] == sticks
    assert v["Hat switch"] == [hat]
    assert [v[f"B{i}"][0] for i in range(1, 15)] == [buttons >> (i - 1) & 1 for i in range(1, 15)]


def hidtools_decode(descriptor: bytes, report: bytes) -> dict[tuple[int, int], Any]:
    """hid-tools' reading of an input report in the shape of pixelpen's ``descriptor.decode`` (the issue's contract):
    (page, id) -> the value, a list where the usage repeats; an array's reported usages -> 1."""
    hid = pytest.importorskip("hidtools.hid")
    reports = hid.ReportDescriptor.from_bytes(list(descriptor)).input_reports
    out: dict[tuple[int, int], list[int]] = {}
    arrays: dict[tuple[int, int], int] = {}
    for f in reports[report[0] if -1 not in reports else -1].fields:
        if f.is_const:
            continue
        values = f.get_values(list(report))
        if f.is_array:
            for v in values:
                index = v - f.logical_min
                if 0 <= index < len(f.usages) and f.usages[index] & 0xFFFF:
                    arrays[(f.usages[index] >> 16, f.usages[index] & 0xFFFF)] = 1
        else:
            out.setdefault((f.usage >> 16, f.usage & 0xFFFF), []).extend(values)
    return {**{k: v[0] if len(v) == 1 else v for k, v in out.items()}, **arrays}


@pytest.mark.parametrize(("model", "options"), [
    ("mouse", {"script": "circle"}), ("trackball", {"script": "scroll"}), ("joystick", {"script": "sweep"}),
    ("gamepad", {"script": "sweep"}), ("tablet", {"script": "signature"}),
    ("touchscreen", {"script": "pinch", "fingers": 5}), ("keyboard", {"script": "typing:Hello, World!"}),
    ("keyboard", {"script": "typing:NKRO 42", "protocol": "nkro"}),
])
def test_pixelpens_decoder_reads_every_simulated_report_as_hid_tools_does(model: str, options: dict[str, Any]) -> None:
    from pixelpen.devices.hid import parse_descriptor  # the decoder under test: the simulators are its witness

    clock = SimulatedClock()
    sim = create_simulator(model, clock=clock, **{k: str(v) for k, v in options.items()})
    clock.advance(6.0)
    reports = sim.take_reports()
    descriptor = parse_descriptor(sim.report_descriptor)
    assert len(reports) > 5
    for report in reports:
        assert descriptor.decode(report) == hidtools_decode(sim.report_descriptor, report), report.hex(" ")

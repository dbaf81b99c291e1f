"""evdev semantics: kernel event frames (codes from python-evdev's ecodes) to events, values worked out by hand."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.devices.hid import keymaps
from pixelpen.devices.hid.evdev import ABS_NAMES, KEY_USAGES, REL_NAMES, EvdevSemantics
from pixelpen.devices.hid.events import Axis, Button, Hat, Key, Motion, Pen, TouchFrame, Wheel
from pixelpen.drivers.identity import DeviceId
from pixelpen.drivers.recordings.evemu import AbsInfo
from pixelpen.errors import ConfigError

evdev = pytest.importorskip("evdev", reason="python-evdev (the input extra) is the oracle for the kernel's codes")
e = evdev.ecodes
DEV = DeviceId("usb", 0x046D, 0xC077, name="test")
SYN = (e.EV_SYN, e.SYN_REPORT, 0)


def feed(sem: EvdevSemantics, *events: tuple[int, int, int], time: float = 1.0) -> list:
    return sem.feed_events([(time, *ev) for ev in events])


def test_names_are_the_kernels_in_lower_case():
    for code, name in REL_NAMES.items():
        assert e.REL[code].lower() == f"rel_{name}"
    for code, name in ABS_NAMES.items():
        kernel = e.ABS[code]
        kernel = kernel if isinstance(kernel, str) else kernel[0]
        assert kernel.lower() == f"abs_{name}", code


def test_key_codes_map_to_the_keyboard_usage_of_the_same_key():
    # independent check: python-evdev's KEY_ name against the HID usage table's name (keymaps)
    same = {"KEY_A": "a", "KEY_Z": "z", "KEY_1": "1", "KEY_0": "0", "KEY_ENTER": "enter", "KEY_ESC": "escape",
            "KEY_BACKSPACE": "backspace", "KEY_TAB": "tab", "KEY_SPACE": "space", "KEY_F1": "f1", "KEY_F12": "f12",
            "KEY_F24": "f24", "KEY_LEFTCTRL": "left_ctrl", "KEY_RIGHTMETA": "right_gui", "KEY_KP0": "kp_0",
            "KEY_KPENTER": "kp_enter", "KEY_CAPSLOCK": "caps_lock", "KEY_NUMLOCK": "num_lock", "KEY_UP": "up",
            "KEY_DELETE": "delete", "KEY_102ND": "non_us_backslash", "KEY_BACKSLASH": "backslash",
            "KEY_SEMICOLON": "semicolon", "KEY_GRAVE": "grave", "KEY_SYSRQ": "print_screen", "KEY_MUTE": "mute"}
    for kernel, name in same.items():
        assert keymaps.key_name(KEY_USAGES[getattr(e, kernel)]) == name, kernel
    # the one key two usages map to: Backslash (0x31) and Non-US # (0x32) -> KEY_BACKSLASH; lowest wins
    assert KEY_USAGES[e.KEY_BACKSLASH] == 0x31


def test_mouse_frame_motion_wheel_and_buttons_in_order():
    sem = EvdevSemantics(DEV, {}, dpi=1000)
    assert feed(sem, (e.EV_REL, e.REL_X, 5), (e.EV_REL, e.REL_Y, -3)) == []  # nothing before SYN_REPORT
    out = feed(sem, (e.EV_REL, e.REL_WHEEL, 1), (e.EV_KEY, e.BTN_LEFT, 1), SYN)
    assert out == [Motion(1.0, DEV, dx=5, dy=-3, dx_mm=pytest.approx(0.127), dy_mm=pytest.approx(-0.0762)),
                   Wheel(1.0, DEV, vertical=1.0), Button(1.0, DEV, button=1, pressed=True, name="left")]
    assert feed(sem, (e.EV_KEY, e.BTN_LEFT, 1), SYN) == []  # no edge
    assert feed(sem, (e.EV_KEY, e.BTN_SIDE, 1), (e.EV_KEY, e.BTN_LEFT, 0), SYN) == [
        Button(1.0, DEV, button=4, pressed=True, name="side"), Button(1.0, DEV, button=1, pressed=False, name="left")]


def test_hi_res_wheel_counts_instead_of_the_detent_events():
    sem = EvdevSemantics(DEV, {})
    # the kernel sends 120ths; the low-resolution event only once a detent is complete
    assert feed(sem, (e.EV_REL, e.REL_WHEEL_HI_RES, 30), SYN) == [Wheel(1.0, DEV, vertical=0.25)]
    out = feed(sem, (e.EV_REL, e.REL_WHEEL, 1), (e.EV_REL, e.REL_WHEEL_HI_RES, 90),
               (e.EV_REL, e.REL_HWHEEL, -1), SYN)
    assert out == [Wheel(1.0, DEV, vertical=0.75, horizontal=-1.0)]
    assert feed(sem, (e.EV_REL, e.REL_HWHEEL_HI_RES, 60), SYN) == [Wheel(1.0, DEV, horizontal=0.5)]


def test_joystick_axes_normalised_and_hats_to_directions():
    axes = {e.ABS_X: AbsInfo(0, 0, 255, 0, 15, 0), e.ABS_GAS: AbsInfo(0, 0, 1023, 0, 0, 0),
            e.ABS_HAT0X: AbsInfo(0, -1, 1, 0, 0, 0), e.ABS_HAT0Y: AbsInfo(0, -1, 1, 0, 0, 0)}
    sem = EvdevSemantics(DEV, axes)
    out = feed(sem, (e.EV_ABS, e.ABS_X, 255), (e.EV_ABS, e.ABS_GAS, 256), (e.EV_ABS, e.ABS_HAT0Y, -1),
               (e.EV_KEY, e.BTN_SOUTH, 1), SYN)
    assert out == [Axis(1.0, DEV, axis="x", value=1.0, raw=255), Axis(1.0, DEV, axis="gas", value=256 / 1023, raw=256),
                   Hat(1.0, DEV, hat=0, direction="up", dx=0, dy=1), Button(1.0, DEV, button=1, pressed=True, name="a")]
    assert feed(sem, (e.EV_ABS, e.ABS_HAT0X, -1), SYN) == [Hat(1.0, DEV, hat=0, direction="up-left", dx=-1, dy=1)]
    assert feed(sem, (e.EV_ABS, e.ABS_HAT0X, 0), (e.EV_ABS, e.ABS_HAT0Y, 1), SYN) == [
        Hat(1.0, DEV, hat=0, direction="down", dx=0, dy=-1)]
    assert feed(sem, (e.EV_ABS, e.ABS_HAT0Y, 0), SYN) == [Hat(1.0, DEV, hat=0, direction="centre", dx=0, dy=0)]
    assert feed(sem, (e.EV_ABS, e.ABS_X, 0), SYN)[0].value == -1.0


PEN_AXES = {e.ABS_X: AbsInfo(0, 0, 15200, 4, 0, 100), e.ABS_Y: AbsInfo(0, 0, 9500, 4, 0, 100),
            e.ABS_PRESSURE: AbsInfo(0, 0, 4095, 0, 0, 0), e.ABS_TILT_X: AbsInfo(0, -64, 63, 0, 0, 57),
            e.ABS_TILT_Y: AbsInfo(0, -64, 63, 0, 0, 0)}


def test_pen_position_in_mm_pressure_tilt_and_proximity():
    sem = EvdevSemantics(DEV, PEN_AXES, keys={e.BTN_TOOL_PEN, e.BTN_TOOL_RUBBER, e.BTN_TOUCH, e.BTN_STYLUS})
    assert sem.pen and not sem.touch
    out = feed(sem, (e.EV_KEY, e.BTN_TOOL_PEN, 1), (e.EV_ABS, e.ABS_X, 7600), (e.EV_ABS, e.ABS_Y, 4750),
               (e.EV_ABS, e.ABS_TILT_X, 57), (e.EV_ABS, e.ABS_TILT_Y, 63), (e.EV_MSC, e.MSC_SERIAL, 0x1234), SYN)
    (pen,) = out
    assert isinstance(pen, Pen)
    assert (pen.x_mm, pen.y_mm) == (76.0, 47.5)  # 7600 units / 100 units per mm
    assert (pen.x, pen.y) == (0.5, 0.5)
    assert pen.tilt_x == pytest.approx(math.degrees(1.0))  # 57 units at 57 units/radian: 1 rad
    assert pen.tilt_y == pytest.approx(64.0)  # no resolution: -64..63 over libinput's -64..64 degrees
    assert pen.in_range and not pen.touching and pen.barrel == (False,) and pen.serial == 0x1234
    (down,) = feed(sem, (e.EV_KEY, e.BTN_TOUCH, 1), (e.EV_ABS, e.ABS_PRESSURE, 4095), (e.EV_KEY, e.BTN_STYLUS, 1),
                   SYN, time=2.0)
    assert down.touching and down.pressure == 1.0 and down.barrel == (True,) and down.time == 2.0
    assert feed(sem, (e.EV_ABS, e.ABS_X, 7600), SYN) == []  # nothing changed
    (away,) = feed(sem, (e.EV_KEY, e.BTN_TOUCH, 0), (e.EV_KEY, e.BTN_STYLUS, 0), (e.EV_ABS, e.ABS_PRESSURE, 0),
                   (e.EV_KEY, e.BTN_TOOL_PEN, 0), SYN)
    assert not away.in_range and away.x_mm == 76.0 and away.barrel == (False,)
    assert feed(sem, (e.EV_ABS, e.ABS_X, 100), SYN) == []  # out of range: nothing more
    (rubber,) = feed(sem, (e.EV_KEY, e.BTN_TOOL_RUBBER, 1), SYN)
    assert rubber.in_range and rubber.eraser and rubber.inverted and rubber.x_mm == 1.0


def test_pen_without_resolution_has_nan_mm():
    sem = EvdevSemantics(DEV, {e.ABS_X: AbsInfo(0, 0, 1000, 0, 0, 0), e.ABS_Y: AbsInfo(0, 0, 1000, 0, 0, 0),
                               e.ABS_PRESSURE: AbsInfo(0, 0, 255, 0, 0, 0)})
    (pen,) = feed(sem, (e.EV_ABS, e.ABS_X, 250), SYN)
    assert math.isnan(pen.x_mm) and pen.x == 0.25 and pen.in_range  # no tool keys: always in range
    assert feed(sem, (e.EV_ABS, e.ABS_Y, 0), SYN) == []  # NaN positions still compare equal: no change


MT = {e.ABS_MT_SLOT: AbsInfo(0, 0, 9, 0, 0, 0), e.ABS_MT_POSITION_X: AbsInfo(0, 0, 4095, 0, 0, 40),
      e.ABS_MT_POSITION_Y: AbsInfo(0, 0, 2047, 0, 0, 40), e.ABS_MT_TRACKING_ID: AbsInfo(0, -1, 65535, 0, 0, 0),
      e.ABS_X: AbsInfo(0, 0, 4095, 0, 0, 40), e.ABS_Y: AbsInfo(0, 0, 2047, 0, 0, 40)}


def test_multitouch_protocol_b_frames_with_lifts_once():
    sem = EvdevSemantics(DEV, MT)
    assert sem.touch and not sem.pen
    (frame,) = feed(sem, (e.EV_ABS, e.ABS_MT_SLOT, 0), (e.EV_ABS, e.ABS_MT_TRACKING_ID, 7),
                    (e.EV_ABS, e.ABS_MT_POSITION_X, 400), (e.EV_ABS, e.ABS_MT_POSITION_Y, 200),
                    (e.EV_ABS, e.ABS_MT_SLOT, 1), (e.EV_ABS, e.ABS_MT_TRACKING_ID, 8),
                    (e.EV_ABS, e.ABS_MT_POSITION_X, 800), (e.EV_ABS, e.ABS_MT_POSITION_Y, 2047),
                    (e.EV_KEY, e.BTN_TOUCH, 1), (e.EV_KEY, e.BTN_TOOL_DOUBLETAP, 1),
                    (e.EV_ABS, e.ABS_X, 400), (e.EV_ABS, e.ABS_Y, 200), SYN)
    assert isinstance(frame, TouchFrame)
    assert [(c.contact_id, c.x_mm, c.y_mm, c.touching) for c in frame.contacts] == [
        (7, 10.0, 5.0, True), (8, 20.0, 2047 / 40, True)]
    assert frame.contacts[1].y == 1.0
    # slot 1 stays selected: its contact moves; slot 0's is lifted
    (frame,) = feed(sem, (e.EV_ABS, e.ABS_MT_POSITION_X, 840), (e.EV_ABS, e.ABS_MT_SLOT, 0),
                    (e.EV_ABS, e.ABS_MT_TRACKING_ID, -1), SYN)
    assert [(c.contact_id, c.x_mm, c.touching) for c in frame.contacts] == [(8, 21.0, True), (7, 10.0, False)]
    (frame,) = feed(sem, (e.EV_ABS, e.ABS_MT_SLOT, 1), (e.EV_ABS, e.ABS_MT_TRACKING_ID, -1), SYN)
    assert [(c.contact_id, c.touching) for c in frame.contacts] == [(8, False)]
    assert feed(sem, (e.EV_KEY, e.BTN_TOUCH, 0), SYN) == []  # the emulated single touch gives nothing


def test_syn_dropped_discards_until_the_next_report():
    sem = EvdevSemantics(DEV, {})
    feed(sem, (e.EV_REL, e.REL_X, 5))
    assert sem.feed_event(1.0, e.EV_SYN, e.SYN_DROPPED, 0) == []
    assert feed(sem, (e.EV_REL, e.REL_X, 9), (e.EV_KEY, e.BTN_LEFT, 1), SYN) == []  # up to and with SYN_REPORT
    assert feed(sem, (e.EV_REL, e.REL_X, 2), SYN) == [Motion(1.0, DEV, dx=2, dy=0)]


def test_keys_give_usage_name_character_and_modifiers():
    sem = EvdevSemantics(DEV, {}, layout="us")
    (press,) = feed(sem, (e.EV_MSC, e.MSC_SCAN, 0x70004), (e.EV_KEY, e.KEY_A, 1), SYN)
    assert press == Key(1.0, DEV, usage=0x04, key="a", pressed=True, char="a")
    assert feed(sem, (e.EV_KEY, e.KEY_A, 2), SYN) == []  # autorepeat
    (release,) = feed(sem, (e.EV_KEY, e.KEY_A, 0), SYN)
    assert release.pressed is False and release.char == ""
    out = feed(sem, (e.EV_KEY, e.KEY_LEFTSHIFT, 1), (e.EV_KEY, e.KEY_2, 1), SYN)
    assert [(k.key, k.char, k.modifiers) for k in out] == [("left_shift", "", frozenset({"shift"})),
                                                           ("2", "@", frozenset({"shift"}))]
    feed(sem, (e.EV_KEY, e.KEY_LEFTSHIFT, 0), (e.EV_KEY, e.KEY_2, 0), SYN)
    feed(sem, (e.EV_KEY, e.KEY_CAPSLOCK, 1), (e.EV_KEY, e.KEY_CAPSLOCK, 0), SYN)
    assert feed(sem, (e.EV_KEY, e.KEY_Q, 1), SYN)[0].char == "Q"  # Caps Lock on
    q_up, ctrl = feed(sem, (e.EV_KEY, e.KEY_Q, 0), (e.EV_KEY, e.KEY_LEFTCTRL, 1), SYN)
    assert (q_up.key, q_up.pressed, ctrl.key, ctrl.modifiers) == ("q", False, "left_ctrl", frozenset({"ctrl"}))
    assert feed(sem, (e.EV_KEY, e.KEY_C, 1), SYN)[0].char == ""  # Ctrl+C types nothing
    (media,) = feed(sem, (e.EV_KEY, e.KEY_PLAYPAUSE, 1), SYN)
    assert (media.usage, media.key) == (0, f"key_{e.KEY_PLAYPAUSE}")


def test_german_altgr_and_keypad_with_num_lock():
    sem = EvdevSemantics(DEV, {}, layout="de")
    out = feed(sem, (e.EV_KEY, e.KEY_RIGHTALT, 1), (e.EV_KEY, e.KEY_Q, 1), SYN)
    assert out[-1].char == "@"  # AltGr+Q on the German layout
    feed(sem, (e.EV_KEY, e.KEY_RIGHTALT, 0), (e.EV_KEY, e.KEY_Q, 0), SYN)
    assert feed(sem, (e.EV_KEY, e.KEY_KP1, 1), SYN)[0].char == ""  # Num Lock off
    feed(sem, (e.EV_KEY, e.KEY_KP1, 0), (e.EV_KEY, e.KEY_NUMLOCK, 1), (e.EV_KEY, e.KEY_NUMLOCK, 0), SYN)
    assert feed(sem, (e.EV_KEY, e.KEY_KP1, 1), SYN)[0].char == "1"


def test_button_ranges_joystick_and_misc():
    sem = EvdevSemantics(DEV, {})
    out = feed(sem, (e.EV_KEY, e.BTN_TRIGGER, 1), (e.EV_KEY, e.BTN_0 + 3, 1), (e.EV_KEY, e.BTN_THUMBR, 1), SYN)
    assert [(b.button, b.name) for b in out] == [(1, "button1"), (4, "misc3"), (15, "thumbr")]


def test_options_are_checked():
    with pytest.raises(ConfigError, match="unknown option"):
        EvdevSemantics(DEV, {}, speed=1)
    with pytest.raises(ConfigError, match="layout"):
        EvdevSemantics(DEV, {}, layout="klingon")
    assert "pen" in EvdevSemantics(DEV, PEN_AXES).describe()
    assert "100/mm" in EvdevSemantics(DEV, PEN_AXES).describe()


def test_python_evdev_absinfo_is_accepted():
    sem = EvdevSemantics(DEV, {e.ABS_X: evdev.AbsInfo(5, 0, 10, 0, 0, 0)})
    assert sem.absinfo[e.ABS_X] == AbsInfo(5, 0, 10, 0, 0, 0)


@settings(max_examples=150, deadline=None)
@given(st.sampled_from([{}, PEN_AXES, MT]),
       st.lists(st.tuples(st.sampled_from([0, 1, 2, 3, 4]), st.integers(0, 0x2FF), st.integers(-(2**31), 2**31 - 1)),
                max_size=60))
def test_any_event_stream_gives_events_only_at_syn_report_and_never_fails(axes, stream):
    sem = EvdevSemantics(DEV, axes)
    for ev_type, code, value in stream:
        out = sem.feed_event(0.0, ev_type, code, value)
        assert not out or (ev_type, code) == (e.EV_SYN, e.SYN_REPORT)

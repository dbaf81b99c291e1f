"""The simulated HID models' firmware, and their registration: ``sim:mouse`` … ``sim:keyboard``.

Each model's firmware samples the scripted hand (``motion``) when its interrupt endpoint is polled and packs
its input report bit by bit from the layout ``descriptors`` documents for its descriptor — each ``device.Layout``
below is that documentation written as bit offsets.  Nothing here reads the descriptor bytes or imports
``pixelpen.devices``: the firmware is independent of pixelpen's decoder, so a simulated device checks that decoder.

Rules every model follows (the scripts speak of a hand, a pen and a surface in mm):

* pointers (``mouse``, ``trackball``) count the hand's motion at their resolution and send deltas, carrying what
  one report cannot hold into the next; a pen-down hand (pressure > 0) holds button 1 (a drag);
* absolute devices (``joystick``, ``gamepad``, ``keyboard``) send a report when what they sense changed;
* the ``tablet`` streams while the pen is in range and sends one report as it leaves;
* the ``touchscreen`` streams while touched and sends one more frame reporting the lifted contacts; a pen-down
  hand without contacts is one finger (id 0);
* output and feature reports the host sends are honoured (keyboard LEDs, the trackball's wheel multipliers, the
  touch screen's Contact Count Maximum and Input Mode) and forgotten at a power loss.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from pixelpen.clock import Clock
from pixelpen.errors import ConfigError, ProtocolError
from pixelpen.options import OptionSpec, OptionValues, boolean, choice, integer, number, positive, read_options
from pixelpen.sim.base import register_simulator
from pixelpen.sim.hid import descriptors, motion
from pixelpen.sim.hid.device import HZ_RANGE, Firmware, HidSim, Layout, bit_set, check_report, clamp, layout
from pixelpen.sim.hid.motion import Hand, Script

# ---- the report layouts of descriptors.py ------------------------------------------------------------

MOUSE_IN = layout(3, None, ("buttons", 3), ("_pad", 5), ("x", 8, True), ("y", 8, True))
TRACKBALL_IN = layout(8, 1, ("buttons", 5), ("_pad", 3), ("x", 16, True), ("y", 16, True), ("wheel", 8, True),
                      ("pan", 8, True))
TRACKBALL_FEATURE = layout(2, 2, ("wheel_multiplier", 2), ("pan_multiplier", 2), ("_pad", 4))
JOYSTICK_IN = layout(4, None, ("x", 8, True), ("y", 8, True), ("throttle", 8, True), ("hat", 4), ("buttons", 4))
GAMEPAD_IN = layout(10, 1, ("x", 8), ("y", 8), ("z", 8), ("rz", 8), ("hat", 4), ("buttons", 14), ("_pad", 6),
                    ("rx", 8), ("ry", 8))
TABLET_IN = layout(14, 2, ("tip", 1), ("barrel", 1), ("invert", 1), ("eraser", 1), ("barrel2", 1), ("in_range", 1),
                   ("_pad", 2), ("x", 16), ("y", 16), ("pressure", 16), ("tilt_x", 8, True), ("tilt_y", 8, True),
                   ("serial", 32))
TOUCH_IN = layout(16, 1, *(item for slot in (0, 1) for item in (
    (f"tip{slot}", 1), (f"confidence{slot}", 1), (f"_pad{slot}", 6), (f"id{slot}", 8), (f"x{slot}", 16),
    (f"y{slot}", 16))), ("scan_time", 16), ("count", 8))
TOUCH_MAX_FEATURE = layout(2, 2, ("contacts", 8))
TOUCH_MODE_FEATURE = layout(2, 3, ("mode", 8))
BOOT_KEYBOARD_IN = layout(8, None, ("modifiers", 8), ("_reserved", 8), *((f"key{i}", 8) for i in range(6)))
NKRO_KEYBOARD_IN = layout(21, 1, ("modifiers", 8), *((f"key_{u:02x}", 1) for u in range(0x98)))
BOOT_KEYBOARD_OUT = layout(1, None, ("leds", 5), ("_pad", 3))
NKRO_KEYBOARD_OUT = layout(2, 1, ("leds", 5), ("_pad", 3))

# ---- firmware ----------------------------------------------------------------------------------------


class ScriptedFirmware(Firmware):
    """A model's program: it samples the hand at each poll (``sample``) and answers its own feature reports."""

    def __init__(self, descriptor: bytes, script: Script) -> None:
        super().__init__(descriptor)
        self.script = script
        self.last: bytes | None = None
        """The input report sent last (None before the first and after a power-up)."""
        self.power_up(0.0)

    def poll(self, t: float) -> list[bytes]:
        """The reports for the hand at ``t``."""
        return self.sample(self.script.at(t), t)

    def busy(self, t: float) -> bool:
        """True until the script has ended and its last state was polled."""
        return not self.script.finished(t)

    def power_up(self, t: float) -> None:
        """Forget what was sent and set; count motion from the hand at ``t``."""
        super().power_up(t)
        self.last = None
        self.start(self.script.at(t))

    def start(self, hand: Hand) -> None:
        """Take the hand at power-up as the reference for relative motion (absolute devices need none)."""

    def sample(self, hand: Hand, t: float) -> list[bytes]:
        """The reports to send for ``hand`` at ``t`` (none when nothing changed)."""
        raise NotImplementedError  # pragma: no cover - every model defines it

    def changed(self, report: bytes) -> list[bytes]:
        """``[report]`` when it differs from the last one sent, else none (the endpoint NAKs the poll)."""
        if report == self.last:
            return []
        self.last = report
        return [report]


class Counter:
    """Counts sent along one relative axis: each report carries the counts the hand moved since, within its range."""

    def __init__(self) -> None:
        self.sent = 0

    def step(self, target: int, low: int, high: int) -> int:
        """The delta towards ``target`` counts that fits low..high (the rest waits for the next report)."""
        delta = min(max(target - self.sent, low), high)
        self.sent += delta
        return delta


class RelativePointer(ScriptedFirmware):
    """What mouse and trackball share: X/Y counts at ``counts_per_mm``, buttons, a pen-down hand holding button 1."""

    LAYOUT: ClassVar[Layout]
    BUTTONS: ClassVar[int]
    RANGE: ClassVar[tuple[int, int]]
    counts_per_mm: float

    def start(self, hand: Hand) -> None:
        self.x, self.y = Counter(), Counter()
        self.x.sent, self.y.sent = self.counts(hand)

    def busy(self, t: float) -> bool:
        """True until the script has ended and the motion it made has all been sent (a report holds only so much)."""
        return super().busy(t) or self.pending(self.script.at(t))

    def pending(self, hand: Hand) -> bool:
        """True while counts towards ``hand`` wait for a report."""
        return self.counts(hand) != (self.x.sent, self.y.sent)

    def counts(self, hand: Hand) -> tuple[int, int]:
        """The hand's position in counts."""
        return round(hand.x * self.counts_per_mm), round(hand.y * self.counts_per_mm)

    def buttons(self, hand: Hand) -> int:
        """The button bits the hand holds (bit 0 button 1)."""
        held = set(hand.buttons) | ({1} if hand.pressure > 0 else set())
        return bit_set([b + 1 in held for b in range(self.BUTTONS)])

    def sample(self, hand: Hand, t: float) -> list[bytes]:
        tx, ty = self.counts(hand)
        fields = {"buttons": self.buttons(hand), "x": self.x.step(tx, *self.RANGE), "y": self.y.step(ty, *self.RANGE),
                  **self.scroll(hand)}
        report = self.LAYOUT.pack(**fields)
        held_before = 0 if self.last is None else self.LAYOUT.value(self.last, "buttons")
        if report == self.LAYOUT.pack(buttons=held_before):
            return []  # no motion, no button change: the endpoint NAKs
        self.last = report
        return [report]

    def scroll(self, hand: Hand) -> dict[str, int]:
        """Wheel fields of the report (a boot mouse has none)."""
        return {}


class Mouse(RelativePointer):
    """The HID 1.11 boot mouse: three buttons, int8 X/Y deltas at ``cpi`` counts per inch."""

    model = "mouse"
    LAYOUT = MOUSE_IN
    BUTTONS = 3
    RANGE = (-127, 127)

    def __init__(self, descriptor: bytes, script: Script, *, cpi: int) -> None:
        self.counts_per_mm = cpi / 25.4
        super().__init__(descriptor, script)


class Trackball(RelativePointer):
    """Five buttons, int16 X/Y at the 400 counts per inch its descriptor states, wheel and AC Pan with multipliers.

    Feature report 2 holds each wheel's Resolution Multiplier (logical 0..1 = physical 1..8): at 1 the wheel
    sends 8 counts per detent.  Both are 0 at power-up (the host sets them, as Windows and Linux do).
    """

    model = "trackball"
    LAYOUT = TRACKBALL_IN
    BUTTONS = 5
    RANGE = (-32000, 32000)
    counts_per_mm = 400 / 25.4

    def start(self, hand: Hand) -> None:
        super().start(hand)
        self.multipliers = {"wheel": 0, "pan": 0}
        """The Resolution Multiplier fields as set by the host (logical 0..1)."""
        self.wheel, self.pan = Counter(), Counter()
        self.wheel.sent, self.pan.sent = round(hand.wheel), round(hand.pan)

    def scale(self, axis: str) -> int:
        """Counts per detent of ``axis`` (the multiplier's physical value: logical 0..1 -> 1..8)."""
        return 1 + 7 * self.multipliers[axis]

    def pending(self, hand: Hand) -> bool:
        return super().pending(hand) or (round(hand.wheel * self.scale("wheel")), round(hand.pan * self.scale("pan"))) \
            != (self.wheel.sent, self.pan.sent)

    def scroll(self, hand: Hand) -> dict[str, int]:
        return {"wheel": self.wheel.step(round(hand.wheel * self.scale("wheel")), -127, 127),
                "pan": self.pan.step(round(hand.pan * self.scale("pan")), -127, 127)}

    def feature(self, report_id: int) -> bytes:
        if report_id != 2:
            raise self.stall("feature", report_id)
        return TRACKBALL_FEATURE.pack(wheel_multiplier=self.multipliers["wheel"],
                                      pan_multiplier=self.multipliers["pan"])

    def set_feature(self, report: bytes) -> None:
        if self.report_id(report, "feature") != 2:
            raise self.stall("feature", report[0])
        check_report(report, TRACKBALL_FEATURE.length, 2, self.model, "feature")
        new = {axis: TRACKBALL_FEATURE.value(report, f"{axis}_multiplier") for axis in ("wheel", "pan")}
        bad = {axis: v for axis, v in new.items() if v > 1}
        if bad:
            raise ProtocolError(f"Resolution Multiplier {bad} outside its logical range 0..1 (the device STALLs)",
                                device=self.model, command="feature 2")
        for axis, counter in (("wheel", self.wheel), ("pan", self.pan)):
            counter.sent = counter.sent * (1 + 7 * new[axis]) // self.scale(axis)  # the sent detents, rescaled
        self.multipliers = new


class Joystick(ScriptedFirmware):
    """HID 1.11 Appendix E.10 joystick: int8 X/Y, throttle, an 8-way hat (8 = centred) and four buttons."""

    model = "joystick"

    def sample(self, hand: Hand, t: float) -> list[bytes]:
        axes = hand.axes
        return self.changed(JOYSTICK_IN.pack(
            x=clamp(127 * axes.get("x", 0.0), -127, 127), y=clamp(127 * axes.get("y", 0.0), -127, 127),
            throttle=clamp(-127 + 254 * axes.get("throttle", 0.0), -127, 127),
            hat=8 if hand.hat is None else hand.hat, buttons=bit_set([b in hand.buttons for b in range(1, 5)])))


class Gamepad(ScriptedFirmware):
    """A DualShock-style pad: sticks uint8 centred at 0x80, the d-pad hat, 14 buttons, triggers uint8."""

    model = "gamepad"

    def sample(self, hand: Hand, t: float) -> list[bytes]:
        axes = hand.axes
        sticks = {name: min(max(math.floor(128 + 127.5 * axes.get(name, 0.0)), 0), 255)
                  for name in ("x", "y", "z", "rz")}
        return self.changed(GAMEPAD_IN.pack(
            **sticks, hat=8 if hand.hat is None else hand.hat,
            buttons=bit_set([b in hand.buttons for b in range(1, 15)]),
            rx=clamp(255 * axes.get("rx", 0.0), 0, 255), ry=clamp(255 * axes.get("ry", 0.0), 0, 255)))


class Tablet(ScriptedFirmware):
    """A pen tablet, 224 x 140 mm at 200 counts/mm, 8192 pressure levels, tilt in degrees, the pen's serial.

    With ``tool="eraser"`` the pen is held the other way up: Invert while in range, Eraser (not Tip Switch)
    while touching, as Microsoft's pen protocol has it.  Barrel switches are the hand's buttons 1 and 2.
    """

    model = "tablet"
    COUNTS_PER_MM = 200
    SIZE = (44800, 28000)

    def __init__(self, descriptor: bytes, script: Script, *, tool: str, serial: int) -> None:
        self.eraser = tool == "eraser"
        self.serial = serial
        super().__init__(descriptor, script)

    def sample(self, hand: Hand, t: float) -> list[bytes]:
        near = hand.in_range
        touching = near and hand.pressure > 0
        if not near and (self.last is None or not TABLET_IN.value(self.last, "in_range")):
            return []
        report = TABLET_IN.pack(
            tip=touching and not self.eraser, barrel=near and 1 in hand.buttons, invert=near and self.eraser,
            eraser=touching and self.eraser, barrel2=near and 2 in hand.buttons, in_range=near,
            x=clamp(hand.x * self.COUNTS_PER_MM, 0, self.SIZE[0]),
            y=clamp(hand.y * self.COUNTS_PER_MM, 0, self.SIZE[1]),
            pressure=clamp(8191 * hand.pressure, 0, 8191) if touching else 0,
            tilt_x=clamp(hand.tilt_x, -64, 63), tilt_y=clamp(hand.tilt_y, -64, 63), serial=self.serial)
        self.last = report
        return [report]


INPUT_MODES = {"mouse": 0, "single": 1, "multi": 2}
"""Input Mode feature values (Microsoft's touch protocol): 0 mouse, 1 single-input, 2 multi-input."""


class TouchScreen(ScriptedFirmware):
    """A multitouch screen, 200 x 125 mm at 16 counts/mm, two contacts per report, hybrid mode beyond two.

    A frame is the contacts down at a poll plus those lifted since the last frame (Tip Switch 0, at their last
    place); it takes ceil(n / 2) reports, one per polling interval, the frame's contact count in the first and 0
    in the others, all with the frame's scan time (100 µs counts, wrapping at 65536).  Feature 2 (Contact Count
    Maximum) limits the contacts tracked (lowest ids first); feature 3 (Input Mode) 2 reports all contacts,
    1 the first only, 0 (mouse) none — the screen has no mouse collection to send on.
    """

    model = "touchscreen"
    COUNTS_PER_MM = 16
    SIZE = (3200, 2000)

    def __init__(self, descriptor: bytes, script: Script, *, contacts: int, mode: str) -> None:
        self.max_contacts = contacts
        self.power_up_mode = INPUT_MODES[mode]
        super().__init__(descriptor, script)

    def start(self, hand: Hand) -> None:
        self.contact_max = self.max_contacts
        """Contact Count Maximum (feature 2) as reported or set by the host."""
        self.mode = self.power_up_mode
        """Input Mode (feature 3)."""
        self.down: dict[int, tuple[float, float]] = {}
        """Contacts reported touching in the last frame, by id: their position in mm."""

    def contacts(self, hand: Hand) -> list[tuple[int, float, float]]:
        """The contacts this frame reports touching, as the mode and Contact Count Maximum allow."""
        contacts = list(hand.contacts) or ([(0, hand.x, hand.y)] if hand.pressure > 0 else [])
        if self.mode == 0:
            return []
        if self.mode == 1:
            return contacts[:1]
        return sorted(contacts)[:self.contact_max]

    def sample(self, hand: Hand, t: float) -> list[bytes]:
        touching = self.contacts(hand)
        ids = {c[0] for c in touching}
        lifted = [(i, x, y) for i, (x, y) in sorted(self.down.items()) if i not in ids]
        self.down = {i: (x, y) for i, x, y in touching}
        frame = [(True, c) for c in touching] + [(False, c) for c in lifted]
        scan = int(t * 10_000) % 65_536
        reports = []
        for first in range(0, len(frame), 2):
            fields = {"scan_time": scan, "count": len(frame) if first == 0 else 0}
            for slot, (tip, (cid, x, y)) in enumerate(frame[first:first + 2]):
                fields.update({f"tip{slot}": tip, f"confidence{slot}": 1, f"id{slot}": min(max(cid, 0), 127),
                               f"x{slot}": clamp(x * self.COUNTS_PER_MM, 0, self.SIZE[0]),
                               f"y{slot}": clamp(y * self.COUNTS_PER_MM, 0, self.SIZE[1])})
            reports.append(TOUCH_IN.pack(**fields))
        if reports:
            self.last = reports[-1]
        return reports

    def feature(self, report_id: int) -> bytes:
        if report_id == 2:
            return TOUCH_MAX_FEATURE.pack(contacts=self.contact_max)
        if report_id == 3:
            return TOUCH_MODE_FEATURE.pack(mode=self.mode)
        raise self.stall("feature", report_id)

    def set_feature(self, report: bytes) -> None:
        rid = self.report_id(report, "feature")
        if rid not in (2, 3):
            raise self.stall("feature", rid)
        check_report(report, 2, rid, self.model, "feature")
        value = report[1]
        if rid == 2:
            if not 1 <= value <= 10:
                raise ProtocolError(f"Contact Count Maximum {value} outside 1..10 (the device STALLs)",
                                    device=self.model, command="feature 2")
            self.contact_max = value
        else:
            if value not in INPUT_MODES.values():
                raise ProtocolError(f"Input Mode {value} is not 0 (mouse), 1 (single) or 2 (multi) (the device STALLs)",
                                    device=self.model, command="feature 3")
            self.mode = value


LED_NAMES = ("num_lock", "caps_lock", "scroll_lock", "compose", "kana")
"""The LED usages 1..5 (page 0x08) in output report bit order."""

ERROR_ROLL_OVER = 0x01
"""The usage a boot keyboard reports in all six slots when more than six keys are down."""


class Keyboard(ScriptedFirmware):
    """A keyboard: boot protocol (8-byte report, six keys) or N-key rollover (a bitmap of 152 usages).

    The LED output report is honoured: ``leds`` is what the LEDs show (Caps Lock does not change what the
    keys send: the host applies it).
    """

    model = "keyboard"

    def __init__(self, descriptor: bytes, script: Script, *, nkro: bool) -> None:
        self.nkro = nkro
        self.led_bits = 0
        """The LED output report's bits (bit 0 Num Lock … bit 4 Kana), 0 at power-up."""
        super().__init__(descriptor, script)

    @property
    def leds(self) -> frozenset[str]:
        """The LEDs lit: names from ``LED_NAMES``."""
        return frozenset(name for i, name in enumerate(LED_NAMES) if self.led_bits >> i & 1)

    def start(self, hand: Hand) -> None:
        self.led_bits = 0

    def sample(self, hand: Hand, t: float) -> list[bytes]:
        modifiers = bit_set([0xE0 + i in hand.keys for i in range(8)])
        keys = sorted(k for k in hand.keys if k < 0xE0)
        if self.nkro:
            return self.changed(NKRO_KEYBOARD_IN.pack(modifiers=modifiers,
                                                      **{f"key_{k:02x}": 1 for k in keys if 0x04 <= k < 0x98}))
        keys = [k for k in keys if 0x04 <= k <= 0x65]
        if len(keys) > 6:
            keys = [ERROR_ROLL_OVER] * 6
        return self.changed(BOOT_KEYBOARD_IN.pack(modifiers=modifiers, **{f"key{i}": k for i, k in enumerate(keys)}))

    def output(self, report: bytes) -> None:
        out = NKRO_KEYBOARD_OUT if self.nkro else BOOT_KEYBOARD_OUT
        check_report(report, out.length, out.report_id, self.model, "output")
        super().output(report)
        self.led_bits = out.value(report, "leds")


# ---- scripts from options ----------------------------------------------------------------------------

SCRIPTS = ("line", "circle", "signature", "sweep", "orbit", "pinch", "scroll", "typing", "idle")
"""Script names the ``script=`` option takes (``typing:TEXT`` with the text to type)."""

PERIODS = {"line": 1.0, "circle": 2.0, "sweep": 3.0, "orbit": 2.0, "pinch": 1.5, "scroll": 1.0}
"""Default seconds for one run of the scripts that take ``period=``."""

REPEATABLE = frozenset({"circle", "sweep", "orbit"})
"""Scripts that can run forever (``repeat=true``)."""


def script_option(value: str) -> str:
    """A ``script=`` value: one of ``SCRIPTS``, ``typing:TEXT`` with a text."""
    name, sep, text = value.partition(":")
    if name not in SCRIPTS:
        raise ValueError(f"expected one of {', '.join(s + (':TEXT' if s == 'typing' else '') for s in SCRIPTS)}")
    if (name == "typing") != bool(sep):
        raise ValueError("typing takes its text as typing:TEXT; the other scripts take none")
    if sep and not text:
        raise ValueError("typing:TEXT needs a text to type")
    return value


@dataclass(frozen=True)
class Model:
    """One simulated model: its firmware, descriptor, the scripts it takes, its surface and its enumeration."""

    name: str
    build: Callable[[bytes, Script, OptionValues], ScriptedFirmware]
    """The firmware from the descriptor, the script and the options (a keyboard's protocol picks its descriptor)."""
    descriptor: bytes
    scripts: tuple[str, ...]
    script: str
    """The default script."""
    hz: float
    """The default polling rate."""
    surface: tuple[float, float]
    """Width and height in mm the scripts move over (the sensing area of absolute devices)."""
    product_id: int
    product: str
    usage: tuple[int, int]
    """The top-level application's usage page and usage (what hidapi's enumerate() lists)."""
    options: tuple[OptionSpec[Any], ...] = ()
    """The options of this model beyond the ones every model reads (``specs``)."""
    buttons: int = motion.SWEEP_BUTTONS
    """Buttons the ``sweep`` script presses in turn."""

    def specs(self) -> tuple[OptionSpec[Any], ...]:
        """Every option the model reads."""
        return (OptionSpec("script", script_option, self.script,
                           f"hand motion: {', '.join(s + (':TEXT' if s == 'typing' else '') for s in self.scripts)}"),
                OptionSpec("hz", number(*HZ_RANGE), self.hz, "polling rate: reports per second at most"),
                OptionSpec("period", positive, None, "seconds one run of the script takes (default: the script's)"),
                OptionSpec("repeat", boolean, False, "run the script forever (circle, sweep, orbit)"),
                *self.options)


def build_script(model: Model, values: OptionValues, where: str) -> Script:
    """The Script the ``script``, ``period``, ``repeat`` (and model) options describe; ConfigError naming the option."""
    name, _, text = values["script"].partition(":")
    if name not in model.scripts:
        raise ConfigError(f"{where}: option script={values['script']!r} does not apply to a {model.name}; it takes "
                          f"{', '.join(model.scripts)}")
    period = values["period"]
    if period is not None and name not in PERIODS:
        raise ConfigError(f"{where}: option period does not apply to script={name} (only to {', '.join(PERIODS)})")
    if values["repeat"] and name not in REPEATABLE:
        raise ConfigError(f"{where}: option repeat does not apply to script={name} (only to "
                          f"{', '.join(sorted(REPEATABLE))})")
    seconds = PERIODS.get(name, 1.0) if period is None else period
    w, h = model.surface
    repeat = values["repeat"]
    try:
        if name == "line":
            return motion.line((0.2 * w, 0.5 * h), (0.8 * w, 0.5 * h), seconds, pen=True)
        if name == "circle":
            return motion.circle((0.5 * w, 0.5 * h), 0.3 * min(w, h), seconds, pen=True, repeat=repeat)
        if name == "signature":
            return motion.signature((0.1 * w, 0.6 * h), 0.8 * w)
        if name == "sweep":
            return motion.sweep(seconds, buttons=model.buttons, repeat=repeat)
        if name == "orbit":
            return motion.orbit(seconds, repeat=repeat)
        if name == "pinch":
            return motion.pinch((0.5 * w, 0.5 * h), 0.6 * min(w, h), seconds, fingers=values["fingers"])
        if name == "scroll":
            return motion.scroll(5.0, seconds)
        if name == "typing":
            return motion.typing(text, rate=values["rate"])
        return motion.idle()
    except ConfigError as exc:
        raise ConfigError(f"{where}: option script={values['script']!r}: {exc}") from None


POINTER_SCRIPTS = ("line", "circle", "signature", "idle")
STICK_SCRIPTS = ("sweep", "orbit", "idle")

VENDOR_ID = 0x1209
"""pid.codes, the open-source USB vendor ID; its product IDs 0x0001..0x0010 are set aside for testing."""

MODELS: dict[str, Model] = {m.name: m for m in (
    Model("mouse", lambda d, s, v: Mouse(d, s, cpi=v["cpi"]), descriptors.BOOT_MOUSE, POINTER_SCRIPTS,
          "circle", 125.0, (100.0, 60.0), 0x0001, "Simulated boot mouse", (0x01, 0x02),
          (OptionSpec("cpi", integer(100, 32_000), 800, "resolution in counts per inch"),)),
    Model("trackball", lambda d, s, v: Trackball(d, s), descriptors.TRACKBALL,
          (*POINTER_SCRIPTS[:-1], "scroll", "idle"), "circle", 125.0, (100.0, 60.0), 0x0002, "Simulated trackball",
          (0x01, 0x02)),
    Model("joystick", lambda d, s, v: Joystick(d, s), descriptors.JOYSTICK, STICK_SCRIPTS, "sweep", 125.0,
          (0.0, 0.0), 0x0003, "Simulated joystick", (0x01, 0x04)),
    Model("gamepad", lambda d, s, v: Gamepad(d, s), descriptors.GAMEPAD, STICK_SCRIPTS, "sweep", 250.0,
          (0.0, 0.0), 0x0004, "Simulated game pad", (0x01, 0x05), buttons=14),
    Model("tablet", lambda d, s, v: Tablet(d, s, tool=v["tool"], serial=v["serial"]), descriptors.PEN_TABLET,
          POINTER_SCRIPTS, "signature", 200.0, (224.0, 140.0), 0x0005, "Simulated pen tablet", (0x0D, 0x01),
          (OptionSpec("tool", choice("pen", "eraser"), "pen", "which end of the pen the hand uses"),
           OptionSpec("serial", integer(0, 0x7FFF_FFFF), 0x5A5A17, "the pen's transducer serial number"))),
    Model("touchscreen", lambda d, s, v: TouchScreen(d, s, contacts=v["contacts"], mode=v["mode"]),
          descriptors.TOUCHSCREEN, (*POINTER_SCRIPTS[:-1], "pinch", "idle"), "pinch", 100.0, (200.0, 125.0), 0x0006,
          "Simulated touch screen", (0x0D, 0x04),
          (OptionSpec("fingers", integer(1, 10), 2, "fingers of the pinch script"),
           OptionSpec("contacts", integer(1, 10), 10, "Contact Count Maximum at power-up"),
           OptionSpec("mode", choice(*INPUT_MODES), "multi", "Input Mode at power-up: mouse, single or multi"))),
    Model("keyboard", lambda d, s, v: Keyboard(descriptors.NKRO_KEYBOARD if v["protocol"] == "nkro" else d, s,
                                               nkro=v["protocol"] == "nkro"), descriptors.BOOT_KEYBOARD,
          ("typing", "idle"), "typing:hello", 125.0, (0.0, 0.0), 0x0007, "Simulated keyboard", (0x01, 0x06),
          (OptionSpec("protocol", choice("boot", "nkro"), "boot", "boot (six keys) or nkro (a bitmap of every key)"),
           OptionSpec("rate", positive, 10.0, "typing speed in keys per second"))),
)}
"""The simulated models by name (``sim:NAME`` and ``create_simulator(NAME)``)."""


def create(name: str, clock: Clock | None = None, **options: str) -> HidSim:
    """The simulator of model ``name`` with URL options (``Model.specs``) on ``clock``."""
    model = MODELS[name]
    where = f"sim:{name}"
    values = read_options(model.specs(), options, where)
    firmware = model.build(model.descriptor, build_script(model, values, where), values)
    info = {"vendor_id": VENDOR_ID, "product_id": model.product_id, "serial_number": f"SIM-{name.upper()}",
            "release_number": 0x0100, "manufacturer_string": "pixelpen", "product_string": model.product,
            "usage_page": model.usage[0], "usage": model.usage[1], "interface_number": 0, "bus_type": 1}
    return HidSim(firmware, hz=values["hz"], clock=clock, info=info)


def _factory(name: str) -> Callable[..., HidSim]:
    def factory(clock: Clock | None = None, **options: str) -> HidSim:
        return create(name, clock, **options)
    factory.__doc__ = f"Simulator factory for ``sim:{name}?...`` URLs (options: ``MODELS[{name!r}].specs()``)."
    return factory


for _name, _model in MODELS.items():
    register_simulator(_name, _factory(_name), _model.specs())

"""Scripted hand motion on the clock: lines, circles, a signature, joystick sweeps, pinches, typing a text.

A ``Script`` is a pure function of the time since it started (seconds) to a ``Hand`` — where the hand is,
what it presses — so the same script gives the same hand at the same time on every run (deterministic,
no random numbers).  Lengths are millimetres on the device's surface (x right, y down), angles degrees,
pressure 0..1, joystick axes -1..1 (triggers and throttle 0..1).  The simulated firmware
(``pixelpen.sim.hid.models``) samples the hand at its polling interval and packs what it sees.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

from pixelpen.errors import ConfigError, quote_token

END_GRACE = 0.1
"""Seconds a script keeps running past its end, so every firmware polls its final state at least once."""

MAX_TEXT = 10_000
"""Characters ``typing`` accepts (a script is held in memory whole)."""

_NO_AXES: Mapping[str, float] = MappingProxyType({})


@dataclass(frozen=True)
class Hand:
    """Where the hand is at one instant and what it holds down: what every model's firmware samples."""

    x: float = 0.0
    """Pointer, pen or first finger position in mm (right positive)."""
    y: float = 0.0
    """In mm, down positive (towards the user)."""
    pressure: float = 0.0
    """Pen tip pressure 0..1 (0: hovering or away)."""
    in_range: bool = False
    """The pen is near enough for the tablet to sense it."""
    tilt_x: float = 0.0
    """Pen tilt in degrees, right positive."""
    tilt_y: float = 0.0
    """Pen tilt in degrees, towards the user positive."""
    buttons: frozenset[int] = frozenset()
    """Buttons held, numbered from 1 (a pen's barrel buttons are 1 and 2)."""
    wheel: float = 0.0
    """Wheel detents turned since the start (up/away positive)."""
    pan: float = 0.0
    """Horizontal scroll detents since the start (right positive)."""
    axes: Mapping[str, float] = field(default_factory=lambda: _NO_AXES)
    """Joystick/game pad axes by name: x, y, z, rz (-1..1), throttle, rx, ry (0..1)."""
    hat: int | None = None
    """Hat direction 0..7 (0 north, clockwise in 45° steps), None when centred."""
    contacts: tuple[tuple[int, float, float], ...] = ()
    """Fingers down on a touch screen: (contact id, x mm, y mm)."""
    keys: frozenset[int] = frozenset()
    """Keyboard usages held (page 0x07), modifiers 0xE0..0xE7 included."""


@dataclass(frozen=True)
class Script:
    """A hand motion: ``at(t)`` is the hand ``t`` seconds after the start; finite unless ``repeat``."""

    name: str
    duration: float
    """Seconds one run of the motion takes (> 0)."""
    shape: Callable[[float], Hand]
    """The hand at 0 <= t <= duration."""
    repeat: bool = False
    """Start over at the end (the script never finishes)."""

    def at(self, t: float) -> Hand:
        """The hand at ``t`` seconds (before 0: as at 0; past the end: as at the end, or again from 0 if repeating)."""
        if t <= 0.0:
            return self.shape(0.0)
        if self.repeat:
            return self.shape(math.fmod(t, self.duration))
        return self.shape(min(t, self.duration))

    def finished(self, t: float) -> bool:
        """True once the script has ended and its final state had ``END_GRACE`` to be polled."""
        return not self.repeat and t > self.duration + END_GRACE


def _smooth(u: float) -> float:
    """Smoothstep 0..1 (zero velocity at both ends): a hand starts and stops gently."""
    u = min(max(u, 0.0), 1.0)
    return u * u * (3.0 - 2.0 * u)


def line(start: tuple[float, float], end: tuple[float, float], duration: float, *, pen: bool = False,
         button: int | None = None) -> Script:
    """A straight stroke from ``start`` to ``end`` in ``duration`` s (eased), the pen down (pressure 0.6) if ``pen``.

    The pen is in range during the stroke and lifts away at its end; ``button`` is held during the stroke.
    """
    _check_duration(duration)
    (x0, y0), (x1, y1) = start, end
    held = frozenset() if button is None else frozenset({button})

    def shape(t: float) -> Hand:
        s = _smooth(t / duration)
        down = t < duration
        return Hand(x=x0 + (x1 - x0) * s, y=y0 + (y1 - y0) * s, pressure=0.6 if pen and down else 0.0,
                    in_range=pen and down, buttons=held if down else frozenset(),
                    contacts=((0, x0 + (x1 - x0) * s, y0 + (y1 - y0) * s),) if down else ())

    return Script("line", duration, shape)


def circle(centre: tuple[float, float], radius: float, period: float, *, turns: float = 1.0, pen: bool = False,
           repeat: bool = False) -> Script:
    """``turns`` times round a circle clockwise from 12 o'clock at constant speed, ``period`` s per turn.

    With ``pen`` the pen is down (pressure 0.5) and in range throughout; the contact (touch) is one finger.
    """
    _check_duration(period)
    cx, cy = centre
    duration = period * turns

    def shape(t: float) -> Hand:
        a = 2.0 * math.pi * t / period
        x, y = cx + radius * math.sin(a), cy - radius * math.cos(a)
        down = repeat or t < duration
        return Hand(x=x, y=y, pressure=0.5 if pen and down else 0.0, in_range=pen and down,
                    contacts=((0, x, y),) if down else ())

    return Script("circle", duration, shape, repeat=repeat)


SIGNATURE_WORDS = ((0.03, 1.3, 5), (0.48, 0.9, 3), (0.82, 0.7, 2))
"""The signature's words: (start as a fraction of the width, seconds of writing, loops); the loops overhang a
word's ends by their radius (under 3 % of the width), so the first starts and the last ends 3 % inside."""
SIGNATURE_GAP = 0.25
"""Seconds the pen hovers (in range, no pressure) between words."""
SIGNATURE_LEAD = 0.2
"""Seconds the pen hovers before the first word (proximity comes before contact)."""


def signature(origin: tuple[float, float], width: float) -> Script:
    """A handwriting-like signature ``width`` mm wide from ``origin`` (its left end on the baseline).

    Three cursive words of loops (a prolate cycloid whose loop height swells and fades), then a flourish
    underline; the pen hovers in range between words (pen-up gaps), pressure rises and falls over each word
    with a ripple per loop, the tilt sways a little.  Deterministic: the same path on every run.
    """
    if width <= 0:
        raise ConfigError(f"signature width must be > 0 mm, got {width}")
    ox, oy = origin
    height = width * 0.12
    segments: list[tuple[float, float, Callable[[float], Hand]]] = []
    t = SIGNATURE_LEAD
    for k, (start, seconds, loops) in enumerate(SIGNATURE_WORDS):
        end_frac = SIGNATURE_WORDS[k + 1][0] - 0.04 if k + 1 < len(SIGNATURE_WORDS) else 0.97
        segments.append((t, seconds, _word(ox + start * width, ox + end_frac * width, oy, height, loops)))
        t += seconds + SIGNATURE_GAP
    flourish = 0.5
    segments.append((t, flourish, _flourish(ox, ox + width, oy + height * 0.5)))
    duration = t + flourish + SIGNATURE_GAP

    def shape(now: float) -> Hand:
        hover_x, hover_y = ox, oy
        for begin, seconds, stroke in segments:
            if now < begin:
                return Hand(x=hover_x, y=hover_y - 2.0, in_range=True, tilt_x=30.0, tilt_y=-20.0)
            if now <= begin + seconds:
                return stroke((now - begin) / seconds)
            end = stroke(1.0)
            hover_x, hover_y = end.x, end.y
        return Hand(x=hover_x, y=hover_y - 2.0, in_range=False, tilt_x=30.0, tilt_y=-20.0)

    return Script("signature", duration, shape)


def _word(x0: float, x1: float, baseline: float, height: float, loops: int) -> Callable[[float], Hand]:
    """One cursive word of ``loops`` loops between x0 and x1, as a function of its progress u in 0..1."""
    span = x1 - x0
    radius = span / (2.0 * math.pi * loops) * 1.6

    def at(u: float) -> Hand:
        phase = 2.0 * math.pi * loops * u
        swell = math.sin(math.pi * u) ** 0.5
        x = x0 + span * u - radius * math.sin(phase)
        y = baseline - height * swell * 0.5 * (1.0 - math.cos(phase))
        pressure = 0.15 + 0.65 * math.sin(math.pi * u) ** 0.6 + 0.1 * math.sin(phase)
        return Hand(x=x, y=y, pressure=min(max(pressure, 0.05), 1.0), in_range=True,
                    tilt_x=30.0 + 6.0 * math.sin(math.pi * u), tilt_y=-20.0 + 4.0 * math.cos(phase))

    return at


def _flourish(x0: float, x1: float, y: float) -> Callable[[float], Hand]:
    """The underline: a shallow arc left to right, pressure fading out."""

    def at(u: float) -> Hand:
        return Hand(x=x0 + (x1 - x0) * u, y=y + 2.0 * math.sin(math.pi * u), pressure=max(0.7 * (1.0 - u), 0.05),
                    in_range=True, tilt_x=36.0, tilt_y=-18.0)

    return at


SWEEP_BUTTONS = 4
"""Buttons ``sweep`` presses in turn (a game pad's sweep uses its own count)."""


def sweep(period: float, *, buttons: int = SWEEP_BUTTONS, repeat: bool = False) -> Script:
    """A joystick exercise over ``period`` s: the stick to every edge, the hat round its 8 directions, each button.

    x follows a triangle wave -1..1..-1 (one cycle), y the same at twice the rate; z/rz (a second stick) a
    circle; throttle, rx and ry ramp 0..1; the hat steps centre, 0..7 in ninths of the period, the buttons
    are pressed one at a time in ``buttons`` equal slots.
    """
    _check_duration(period)
    if buttons < 1:
        raise ConfigError(f"sweep needs at least 1 button, got {buttons}")

    def shape(t: float) -> Hand:
        u = min(t / period, 1.0)
        step = min(int(u * 9), 8)
        a = 2.0 * math.pi * u
        axes = {"x": _triangle(u), "y": _triangle(2.0 * u), "z": math.sin(a), "rz": -math.cos(a),
                "throttle": u, "rx": u, "ry": 1.0 - u}
        return Hand(axes=MappingProxyType(axes), hat=None if step == 0 else step - 1,
                    buttons=frozenset({min(int(u * buttons), buttons - 1) + 1}) if u < 1.0 else frozenset())

    return Script("sweep", period, shape, repeat=repeat)


def orbit(period: float, *, turns: float = 1.0, repeat: bool = False) -> Script:
    """The stick pushed to its edge and taken round clockwise from north, ``period`` s per turn, then let go.

    x = sin, y = -cos of the angle (y negative is forward); the second stick (z, rz) mirrors it.
    """
    _check_duration(period)
    duration = period * turns

    def shape(t: float) -> Hand:
        if not repeat and t >= duration:
            return Hand(axes=MappingProxyType({"x": 0.0, "y": 0.0, "z": 0.0, "rz": 0.0}))
        a = 2.0 * math.pi * t / period
        return Hand(axes=MappingProxyType({"x": math.sin(a), "y": -math.cos(a), "z": -math.sin(a),
                                           "rz": -math.cos(a)}))

    return Script("orbit", duration, shape, repeat=repeat)


def _triangle(u: float) -> float:
    """A triangle wave of period 1: -1 at u = 0, +1 at 0.5, -1 at 1."""
    f = u - math.floor(u)
    return 4.0 * f - 1.0 if f < 0.5 else 3.0 - 4.0 * f


def pinch(centre: tuple[float, float], spread: float, period: float, *, fingers: int = 2) -> Script:
    """``fingers`` fingers on a circle round ``centre``: it opens from 20 % to ``spread`` mm across and closes.

    Contact ids 0..fingers-1; all lift at the end.  Two fingers make the classic pinch/zoom gesture.
    """
    _check_duration(period)
    if not 1 <= fingers <= 10:
        raise ConfigError(f"pinch takes 1..10 fingers, got {fingers}")
    cx, cy = centre

    def shape(t: float) -> Hand:
        if t >= period:
            return Hand()
        radius = spread * (0.1 + 0.4 * math.sin(math.pi * t / period))
        return Hand(contacts=tuple((i, cx + radius * math.cos(2.0 * math.pi * i / fingers),
                                    cy + radius * math.sin(2.0 * math.pi * i / fingers)) for i in range(fingers)))

    return Script("pinch", period, shape)


def scroll(detents: float, period: float) -> Script:
    """The wheel turned ``detents`` up over the first half of ``period``, then panned the same to the right."""
    _check_duration(period)

    def shape(t: float) -> Hand:
        u = t / period
        return Hand(wheel=detents * _smooth(2.0 * u), pan=detents * _smooth(2.0 * u - 1.0))

    return Script("scroll", period, shape)


def idle() -> Script:
    """Nothing happens (the hand is off the device)."""
    return Script("idle", 1e-3, lambda t: Hand())


# ---- typing ----------------------------------------------------------------------------------------

LEFT_SHIFT = 0xE1
"""Keyboard usage of Left Shift."""

_UNSHIFTED = {**{chr(ord("a") + i): 0x04 + i for i in range(26)},
              **{str(d): 0x1E + (d - 1) % 10 for d in range(10)},
              "\n": 0x28, "\x1b": 0x29, "\b": 0x2A, "\t": 0x2B, " ": 0x2C, "-": 0x2D, "=": 0x2E, "[": 0x2F,
              "]": 0x30, "\\": 0x31, ";": 0x33, "'": 0x34, "`": 0x35, ",": 0x36, ".": 0x37, "/": 0x38}
"""US layout: character -> keyboard usage without Shift (HID Usage Tables §10)."""
_SHIFTED = {**{chr(ord("A") + i): 0x04 + i for i in range(26)},
            **dict(zip("!@#$%^&*()", range(0x1E, 0x28), strict=True)),
            "_": 0x2D, "+": 0x2E, "{": 0x2F, "}": 0x30, "|": 0x31, ":": 0x33, '"': 0x34, "~": 0x35, "<": 0x36,
            ">": 0x37, "?": 0x38}
"""US layout: character -> keyboard usage typed with Shift."""


def key_strokes(text: str) -> list[tuple[int, bool]]:
    """The (usage, shifted) key strokes that type ``text`` on a US keyboard; ConfigError naming a character it lacks."""
    if len(text) > MAX_TEXT:
        raise ConfigError(f"typing takes at most {MAX_TEXT} characters, got {len(text)}")
    strokes = []
    for i, ch in enumerate(text):
        if ch in _UNSHIFTED:
            strokes.append((_UNSHIFTED[ch], False))
        elif ch in _SHIFTED:
            strokes.append((_SHIFTED[ch], True))
        else:
            raise ConfigError(f"typing: character {quote_token(ch)} at position {i} has no key on a US keyboard")
    return strokes


def typing(text: str, *, rate: float = 10.0, hold: float = 0.05) -> Script:
    """Type ``text`` at ``rate`` keys per second, each key held ``hold`` s (Shift pressed around shifted ones).

    Shift goes down 10 ms before its key and up 10 ms after it, as a typist's would; repeated keys are released
    between strokes because ``hold`` is shorter than the interval (refused otherwise).
    """
    if not math.isfinite(rate) or rate <= 0:
        raise ConfigError(f"typing rate must be > 0 keys/s, got {rate}")
    interval = 1.0 / rate
    if not 0 < hold < interval - 0.02:
        raise ConfigError(f"typing: a key held {hold} s must be released before the next one ({interval:.3f} s on)")
    strokes = key_strokes(text)
    duration = max(len(strokes), 1) * interval

    def shape(t: float) -> Hand:
        k = int(t / interval)
        if k >= len(strokes):
            return Hand()
        usage, shifted = strokes[k]
        offset = t - k * interval
        keys = set()
        if shifted and offset < hold + 0.02:
            keys.add(LEFT_SHIFT)
        if (0.01 if shifted else 0.0) <= offset < (0.01 if shifted else 0.0) + hold:
            keys.add(usage)
        return Hand(keys=frozenset(keys))

    return Script("typing", duration, shape)


def _check_duration(seconds: float) -> None:
    """Refuse a period or duration that is not a positive finite number of seconds."""
    if not (math.isfinite(seconds) and seconds > 0):
        raise ConfigError(f"a motion's duration must be > 0 s, got {seconds}")


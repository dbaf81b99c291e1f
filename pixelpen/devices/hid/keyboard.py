"""Keyboard semantics: boot and report protocol, key arrays and NKRO bitmaps, modifiers, names, characters, LEDs.

:class:`Keyboard` handles Generic Desktop Keyboard (0x010006) and Keypad (0x010007) applications:

* **Reports** — whatever the descriptor declares (report protocol): key arrays (the boot layout's
  six usages) and bitmaps (one variable bit per usage, N-key rollover) over the Keyboard page, the
  modifier bits 0xE0..0xE7.  With ``protocol=boot`` the reports are read as the fixed 8-byte boot
  report of HID 1.11 Appendix B.1 (modifiers, a reserved byte, six key usages) whatever the
  descriptor says, for a device the host put in the boot protocol (SET_PROTOCOL 0).
* **ErrorRollOver** — an array reporting usage 0x01 (too many keys down) is ignored, as the kernel's
  ``hid_input_field`` ignores the field ("Ignore report if ErrorRollOver"): its keys stay as they
  were, while the report's other fields (the modifier bits) still count.  Usages 0x00..0x03 are
  never keys.
* **Events** — one :class:`~pixelpen.devices.hid.events.Key` per change: modifiers first (by usage),
  then releases, then presses in report order.  ``key`` is the usage's name
  (:func:`pixelpen.devices.hid.keymaps.key_name`), ``char`` the character the press types on the
  layout (option ``layout``, :meth:`Keyboard.set_layout`; "" on release, for keys that type nothing,
  and while Ctrl, Alt or GUI is held — Right Alt is AltGr on layouts with AltGr), ``modifiers`` the
  modifiers held (``ctrl``, ``shift``, ``alt``, ``altgr``, ``gui``) and the locks on (``caps_lock``,
  ``num_lock``, ``scroll_lock``).  Key repeat is not generated here.
* **Dead keys** — with ``dead_keys=true`` a dead key types nothing and the next key that types
  composes with it (:func:`~pixelpen.devices.hid.keymaps.compose`: "â", the dead key's own
  character before Space, else both characters, so ``char`` may then hold two); otherwise a dead key
  types its spacing character at once.
* **Locks** — Caps Lock, Num Lock and Scroll Lock toggle on their key's press (the host keeps lock
  state, as the kernel does); the Locking Caps/Num/Scroll Lock keys (0x82..0x84) are on while held.
  :meth:`Keyboard.led_report` encodes the LED output report (LED page 0x08: Num Lock, Caps Lock,
  Scroll Lock, Compose, Kana) through the descriptor's encoder; :meth:`Keyboard.output_reports`
  gives it for the state at opening, and :attr:`Keyboard.leds_changed` says when a lock key changed
  the state since the last LED report was made.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from pixelpen.devices.hid.codec import ReportDecoder, ReportEncoder, array_usage
from pixelpen.devices.hid.events import DeviceId, InputEvent, Key
from pixelpen.devices.hid.fields import MAIN_CONSTANT, MAIN_VARIABLE, Field, ReportDescriptor, ReportKind, ReportLayout
from pixelpen.devices.hid.keymaps import LAYOUTS, MODIFIER_NAMES, Layout, compose, key_name, layout
from pixelpen.devices.hid.semantics import OutputReport, read_semantics_options
from pixelpen.errors import ConfigError, InvalidArgument
from pixelpen.options import OptionSpec, boolean, choice

__all__ = ["BOOT_INPUT", "BOOT_LEDS", "LEDS", "Keyboard"]

KEYBOARD_PAGE, LED_PAGE = 0x07, 0x08
ERROR_ROLL_OVER = 0x01
FIRST_KEY = 0x04
"""Usages 0x00..0x03 are "no event", ErrorRollOver, POSTFail and ErrorUndefined: never keys."""
CAPS_LOCK, SCROLL_LOCK, NUM_LOCK = 0x39, 0x47, 0x53
LOCKING_KEYS = {0x82: "caps_lock", 0x83: "num_lock", 0x84: "scroll_lock"}
TOGGLES = {CAPS_LOCK: "caps_lock", NUM_LOCK: "num_lock", SCROLL_LOCK: "scroll_lock"}
LEDS = ("num_lock", "caps_lock", "scroll_lock", "compose", "kana")
"""The LED page's usages 0x01..0x05, in order."""
RIGHT_ALT = 0xE6


def _boot_field(kind: ReportKind, page: int, usages: range, offset: int, size: int, count: int, lmax: int,
                flags: int) -> Field:
    return Field(kind, None, page, tuple(page << 16 | u for u in usages), offset, size, count, 0, lmax, 0, 0, 0, 0,
                 flags)


BOOT_INPUT = ReportLayout(ReportKind.INPUT, None, (
    _boot_field(ReportKind.INPUT, KEYBOARD_PAGE, range(0xE0, 0xE8), 0, 1, 8, 1, MAIN_VARIABLE),
    _boot_field(ReportKind.INPUT, 0, range(0), 8, 8, 1, 0, MAIN_CONSTANT),
    _boot_field(ReportKind.INPUT, KEYBOARD_PAGE, range(0x100), 16, 8, 6, 255, 0),
), 8)
"""The boot keyboard input report (HID 1.11 B.1): modifier bits, a reserved byte, six key usages (0..255 taken)."""
BOOT_LEDS = ReportLayout(ReportKind.OUTPUT, None, (
    _boot_field(ReportKind.OUTPUT, LED_PAGE, range(1, 6), 0, 1, 5, 1, MAIN_VARIABLE),
    _boot_field(ReportKind.OUTPUT, 0, range(0), 5, 3, 1, 0, MAIN_CONSTANT),
), 1)
"""The boot keyboard LED output report: Num Lock, Caps Lock, Scroll Lock, Compose, Kana bits, 3 bits padding."""


ROLLED_OVER = -1
"""What an array element reporting ErrorRollOver gives in a plan's table."""


@dataclass(frozen=True)
class _KeyPlan:
    """One input report: its decoder, its Keyboard-page variables and arrays, as element indices."""

    decoder: ReportDecoder
    variables: tuple[tuple[int, int], ...]
    """(element index, usage ID) of each Keyboard-page variable (modifier bits, a bitmap's bits)."""
    arrays: tuple[tuple[tuple[int, ...], dict[int, int]], ...]
    """Each Keyboard-page array: its elements' indices, and logical value -> the key usage ID it reports
    (:data:`ROLLED_OVER` for ErrorRollOver; values reporting no key are absent)."""


def _plan(decoder: ReportDecoder) -> _KeyPlan | None:
    variables = []
    arrays: dict[Field, list[int]] = {}
    for index, e in enumerate(decoder.elements):
        if e.key is not None:
            if e.key[0] == KEYBOARD_PAGE and e.key[1] >= FIRST_KEY:
                variables.append((index, e.key[1]))
        elif e.field.is_array and any(u >> 16 == KEYBOARD_PAGE for u in e.field.usages):
            arrays.setdefault(e.field, []).append(index)
    if not variables and not arrays:
        return None
    tables = []
    for f, indices in arrays.items():
        table = {}
        for value in range(f.logical_min, min(f.logical_max, f.logical_min + len(f.usages) - 1) + 1):
            key = array_usage(f, value, decoder.variable_keys)  # the codec's rule for what an array reports
            if key is not None and key[0] == KEYBOARD_PAGE and (key[1] >= FIRST_KEY or key[1] == ERROR_ROLL_OVER):
                table[value] = ROLLED_OVER if key[1] == ERROR_ROLL_OVER else key[1]
        tables.append((tuple(indices), table))
    return _KeyPlan(decoder, tuple(variables), tuple(tables))


def _layout_name(text: str) -> str:
    return choice(*LAYOUTS)(text)


class Keyboard:
    """A keyboard or keypad: Key events with names and characters by layout, lock state and LED reports."""

    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("layout", _layout_name, "us", f"layout for characters: {', '.join(LAYOUTS)}"),
        OptionSpec("num_lock", boolean, False, "Num Lock on at opening"),
        OptionSpec("dead_keys", boolean, False,
                   "compose dead keys with the next character (^ then a: â); else they type their own character"),
        OptionSpec("protocol", choice("report", "boot"), "report",
                   "report: the descriptor's reports; boot: fixed 8-byte boot reports (after SET_PROTOCOL 0)"),
    )

    def __init__(self, descriptor: ReportDescriptor, device: DeviceId, **options: object) -> None:
        self.descriptor = descriptor
        self.device = device
        where = f"keyboard semantics for {device}"
        opts = read_semantics_options(self.OPTIONS, options, where)
        self.layout: Layout = layout(opts["layout"])
        self.dead_keys = bool(opts["dead_keys"])
        self._dead = ""
        self.boot = opts["protocol"] == "boot"
        self._boot_plan = _plan(ReportDecoder(BOOT_INPUT)) if self.boot else None
        self._plans: dict[int | None, _KeyPlan] = {}
        for report_id in descriptor.input_reports:
            plan = _plan(descriptor.decoder(ReportKind.INPUT, report_id))
            if plan is not None:
                self._plans[report_id] = plan
        if not self._plans and not self.boot:
            raise ConfigError(f"{where}: no input report has Keyboard-page usages")
        self._led_encoder, self._led_report_id = self._leds()
        self.locks = {"caps_lock": False, "num_lock": bool(opts["num_lock"]), "scroll_lock": False}
        """Lock state kept by the host: caps_lock, num_lock, scroll_lock."""
        self.leds_changed = False
        """Whether a lock key changed the lock state since the last :meth:`led_report`."""
        self._modifiers: set[int] = set()
        self._keys: dict[int, None] = {}
        self._array_keys: dict[tuple[int | None, int], list[int]] = {}
        self._down: list[int] = []

    def _leds(self) -> tuple[ReportEncoder | None, int | None]:
        """The encoder of the LED output report (the first output report with LED-page usages)."""
        if self.boot:
            return ReportEncoder(BOOT_LEDS), None
        for report_id, fields in self.descriptor.output_reports.items():
            if any(u >> 16 == LED_PAGE for f in fields if not f.is_constant for u in f.usages):
                return self.descriptor.encoder(ReportKind.OUTPUT, report_id), report_id
        return None, None

    def set_layout(self, name: str) -> None:
        """Type characters by another layout from now on (``us``, ``uk``, ``de``, ``fr``); drops a pending dead key."""
        self.layout = layout(name)
        self._dead = ""

    def led_report(self, *, num_lock: bool | None = None, caps_lock: bool | None = None,
                   scroll_lock: bool | None = None, compose: bool = False, kana: bool = False) -> OutputReport:
        """The LED output report: each lock LED as given, else as the lock state; LEDs the device lacks are left out."""
        if self._led_encoder is None:
            raise InvalidArgument(f"{self.device}: the keyboard has no LED output report")
        state = {"num_lock": num_lock, "caps_lock": caps_lock, "scroll_lock": scroll_lock,
                 "compose": compose, "kana": kana}
        values = {(LED_PAGE, i + 1): int(self.locks[name] if state[name] is None else bool(state[name]))
                  for i, name in enumerate(LEDS)}
        self.leds_changed = False
        return OutputReport(ReportKind.OUTPUT, self._led_report_id, self._led_encoder.encode(values))

    def output_reports(self) -> list[OutputReport]:
        """The LED report for the lock state at opening (none for a keyboard without LEDs)."""
        return [self.led_report()] if self._led_encoder is not None else []

    def describe(self) -> str:
        """What was found: the protocol, arrays or bitmap, LEDs and the layout."""
        kinds: set[str] = set()
        for plan in ([self._boot_plan] if self._boot_plan is not None else self._plans.values()):
            kinds.update(f"{len(indices)}-key array" for indices, _ in plan.arrays)
            keys = sum(1 for _, usage in plan.variables if usage not in MODIFIER_NAMES)
            if keys:
                kinds.add(f"{keys}-key bitmap")
        leds = "LEDs" if self._led_encoder is not None else "no LEDs"
        protocol = "boot protocol" if self.boot else "report protocol"
        return (f"{self.device}: keyboard, {protocol}, {', '.join(sorted(kinds))}, {leds}, "
                f"layout {self.layout.name}")

    @property
    def pressed(self) -> tuple[str, ...]:
        """The names of the keys down now (modifiers first)."""
        return tuple(key_name(u) for u in (*sorted(self._modifiers), *self._keys))

    # -- reports -------------------------------------------------------------------------------------

    def feed(self, report: bytes, time: float) -> list[InputEvent]:
        """The events of one input report: modifier changes, releases, then presses."""
        plan, report_id = self._boot_plan, None
        if plan is None:
            report_id = self.descriptor.report_id_of(report)
            if report_id not in self._plans:
                self.descriptor.layout(ReportKind.INPUT, report_id)  # a ParseError for an ID the device lacks
                return []
            plan = self._plans[report_id]
        values = plan.decoder.values(report)
        down = [usage for index, usage in plan.variables if values[index]]
        for number, (indices, table) in enumerate(plan.arrays):
            reported = [table[v] for v in (values[i] for i in indices) if v in table]
            if ROLLED_OVER not in reported:  # else the kernel ignores the field: its keys stay as they were
                self._array_keys[report_id, number] = reported
            down.extend(self._array_keys.get((report_id, number), ()))
        if down == self._down:
            return []
        self._down = down
        modifiers = {u for u in down if u in MODIFIER_NAMES}
        keys = dict.fromkeys(u for u in down if u not in MODIFIER_NAMES)
        events: list[InputEvent] = []
        for usage in sorted(modifiers ^ self._modifiers):
            pressed = usage in modifiers
            (self._modifiers.add if pressed else self._modifiers.discard)(usage)
            events.append(self._key(time, usage, pressed, self._held()))
        held = self._held()
        for usage in [u for u in self._keys if u not in keys]:
            del self._keys[usage]
            if usage in LOCKING_KEYS and self._lock(LOCKING_KEYS[usage], False):
                held = self._held()
            events.append(self._key(time, usage, False, held))
        for usage in [u for u in keys if u not in self._keys]:
            self._keys[usage] = None
            lock = TOGGLES.get(usage)
            if (lock is not None and self._lock(lock, not self.locks[lock])) or (
                    usage in LOCKING_KEYS and self._lock(LOCKING_KEYS[usage], True)):
                held = self._held()
            events.append(self._key(time, usage, True, held))
        return events

    def _lock(self, name: str, on: bool) -> bool:
        """Set a lock; whether it changed."""
        if self.locks[name] == on:
            return False
        self.locks[name] = on
        self.leds_changed = True
        return True

    def _held(self) -> frozenset[str]:
        """The modifiers held and the locks on."""
        held = {MODIFIER_NAMES[u] for u in self._modifiers}
        if RIGHT_ALT in self._modifiers and self.layout.altgr:
            held.add("altgr")
            if 0xE2 not in self._modifiers:
                held.discard("alt")
        held.update(name for name, on in self.locks.items() if on)
        return frozenset(held)

    def _key(self, time: float, usage: int, pressed: bool, held: frozenset[str]) -> Key:
        char = ""
        if pressed and usage not in MODIFIER_NAMES and not held & {"ctrl", "alt", "gui"}:
            state = {"shift": "shift" in held, "altgr": "altgr" in held, "caps_lock": self.locks["caps_lock"]}
            char = self.layout.char(usage, num_lock=self.locks["num_lock"], **state)
            if self.dead_keys and char:
                if self._dead:
                    char, self._dead = compose(self._dead, char), ""
                elif (usage, self.layout.level(usage, **state)) in self.layout.dead:
                    char, self._dead = "", char
        return Key(time, self.device, usage=usage, key=key_name(usage), pressed=pressed, char=char, modifiers=held)

"""The plotter's RS-232 side: replies with their delays and output trigger, handshakes, ESC. device control, OA...OW.

``Interface`` holds what device control configures (7470A manual ch. 10: ``ESC.@`` hardwire, ``ESC.H``/``ESC.I``
ENQ/ACK and Xon/Xoff, ``ESC.M`` turnaround delay, output trigger, echo terminator, reply terminator and
initiator, ``ESC.N`` intercharacter delay and Xoff) and the queue of bytes going out; ``INTERFACE_CONTROL``
maps its device-control letters to its methods.  ``OutputInstructions`` answers the HP-GL output
instructions (``OUTPUTS`` is its part of the instruction table).
"""

from __future__ import annotations

import logging
import re
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Final

from pixelpen.sim.plotters.hpgl.machine import Machine, Status
from pixelpen.sim.plotters.hpgl.models import ModelSpec
from pixelpen.sim.plotters.hpgl.params import Command, CommandTable
from pixelpen.sim.plotters.hpgl.parsing import ESC, DeviceControl, Instruction

__all__ = ["DEVICE_CONTROL_ERRORS", "INTERFACE_CONTROL", "OUTPUTS", "Interface", "Link", "OutputInstructions"]

log = logging.getLogger(__name__)

DEVICE_CONTROL_ERRORS: Final = {
    11: "no such device-control instruction",
    12: "invalid byte in the parameters (rest defaulted)",
    14: "too many parameters (extras ignored)",
}
"""What the RS-232 errors a device-control sequence raises while it is read mean."""


@dataclass
class Link:
    """RS-232 configuration set by device control; power-up defaults (7470A manual ch. 10)."""

    hardwire: bool = False
    monitor: int = 0
    mode: int = 0  # 1: ESC.H, 2: ESC.I
    block: int = 80
    enq: int = 0
    ack: bytes = b""
    turnaround_s: float = 0.0
    trigger: int = 0
    echo: int = 0
    terminator: bytes = b"\r"
    initiator: bytes = b""
    char_delay_s: float = 0.0
    xoff: bytes = b""  # ESC.N second parameter: Xoff trigger (Xon/Xoff) or immediate response (ENQ/ACK)

    @property
    def xonxoff(self) -> bool:
        """Xon/Xoff is on when an Xoff character is set and no ENQ character is."""
        return bool(self.xoff) and self.enq == 0

    @property
    def xon_free(self) -> int:
        """Free bytes at which XON is sent again: 128, or one more than the threshold when that is larger."""
        return max(128, self.block + 1)


class _Output:
    """A reply waiting to go out: released at ``ready``, or when the output trigger byte arrives."""

    __slots__ = ("data", "echo", "needs_trigger", "ready", "reply")

    def __init__(self, ready: float, data: bytes, needs_trigger: bool, echo: bool, reply: bool) -> None:
        self.ready = ready
        self.data = data
        self.needs_trigger = needs_trigger
        self.echo = echo
        self.reply = reply


class Interface:
    """The RS-232 interface of one plotter: link configuration, flow control, error ESC.E and the output queue.

    ``now`` gives the device time, ``free`` the free buffer bytes, and ``report(code, message)`` records
    an RS-232 error in the plotter's log and counters.
    """

    def __init__(self, model: str, now: Callable[[], float], free: Callable[[], int],
                 report: Callable[[int, str], None]) -> None:
        self.model = model
        self._now = now
        self._free = free
        self._report = report
        self.power_up()

    def power_up(self) -> None:
        """Power-up defaults: link configuration, no error, nothing going out."""
        self.link = Link()
        self.io_error = 0
        self._xoff_sent = False
        self._enq_pending = False
        self.await_echo = False
        """True after a reply went out while the echo terminator is awaited (bytes are ignored until it comes)."""
        self._outputs: deque[_Output] = deque()
        self._set_specials()

    # -- the receiving side --------------------------------------------------------------------------

    def _set_specials(self) -> None:
        """Bytes the receiver must catch before the buffer: ESC, the ENQ character and the output trigger."""
        special = {ESC}
        if self.link.enq:
            special.add(self.link.enq)
        if self.link.trigger:
            special.add(self.link.trigger)
        self.specials = re.compile(b"[" + b"".join(re.escape(bytes([c])) for c in sorted(special)) + b"]")

    def special(self, byte: int) -> None:
        """The ENQ character or the output trigger arrived (ESC is the plotter's)."""
        if byte == self.link.enq and self.link.enq:
            self._enquiry()
        elif byte == self.link.trigger and self.link.trigger:
            now = self._now()
            for o in self._outputs:
                o.needs_trigger = False
                o.ready = max(o.ready, now)

    def flow_check(self) -> None:
        """Send XOFF/XON and pending ENQ acknowledgements as the free space crosses the thresholds."""
        free = self._free()
        link = self.link
        if link.xonxoff:
            if not self._xoff_sent and free < link.block:
                self._xoff_sent = True
                self._send(link.xoff)
            elif self._xoff_sent and free >= link.xon_free:
                self._xoff_sent = False
                if link.ack:
                    self._send(link.ack)
                else:
                    log.warning("%s: Xon/Xoff on but no Xon character set (ESC.I third parameter)", self.model)
        if self._enq_pending and free >= link.block:
            self._enq_pending = False
            self._send_ack()

    def _enquiry(self) -> None:
        """The ENQ character arrived: acknowledge now if there is room, else once there is."""
        link = self.link
        if link.mode == 1 and link.xoff:  # ESC.N immediate response string goes out at once
            self._send(link.xoff)
        if self._free() >= link.block:
            self._send_ack()
        else:
            self._enq_pending = True

    # -- the sending side ----------------------------------------------------------------------------

    def _send_ack(self) -> None:
        """The ENQ acknowledgement (echoed with the terminator in ESC.H mode)."""
        link = self.link
        if link.mode == 1:
            self._queue(link.ack + link.terminator, trigger=True, echo=True, reply=False)
        else:
            self._queue(link.ack, trigger=False, echo=False, reply=False)

    def _send(self, data: bytes) -> None:
        """Flow-control characters: sent at once, no delays."""
        if data:
            self._outputs.append(_Output(self._now(), data, False, False, False))

    def _queue(self, data: bytes, *, trigger: bool, echo: bool, reply: bool) -> None:
        """A reply or acknowledgement, due after the turnaround and intercharacter delays."""
        link = self.link
        delay = link.turnaround_s + len(data) * link.char_delay_s
        self._outputs.append(_Output(self._now() + delay, data, trigger and bool(link.trigger), echo, reply))

    def reply(self, text: str, command: str) -> None:
        """Answer an output instruction (HP-GL or device control), unless an answer is still going out."""
        now = self._now()
        if any(o.reply and (o.needs_trigger or o.ready > now) for o in self._outputs):
            self.io_fault(10, f"output instruction {command} while another answer is still going out; ignored")
            return
        self._queue(self.link.initiator + text.encode("ascii") + self.link.terminator, trigger=True, echo=True,
                    reply=True)

    def io_fault(self, code: int, message: str) -> None:
        """Raise RS-232 error ``code`` (what ESC.E reports next)."""
        self.io_error = code
        self._report(code, message)

    def take(self) -> bytes:
        """The bytes due by now (their delays run out, no trigger awaited), in order; an echoed one awaits its echo."""
        now = self._now()
        out = bytearray()
        while self._outputs and not self._outputs[0].needs_trigger and self._outputs[0].ready <= now:
            item = self._outputs.popleft()
            out += item.data
            if item.echo and self.link.echo:
                self.await_echo = True
        return bytes(out)

    def next_ready(self) -> float | None:
        """When the next delayed byte string falls due (None: nothing delayed)."""
        now = self._now()
        times = [o.ready for o in self._outputs if not o.needs_trigger and o.ready > now]
        return min(times) if times else None

    # -- device control ------------------------------------------------------------------------------

    def _esc_e(self, seq: DeviceControl) -> None:
        """ESC.E: the RS-232 error, cleared by reading it."""
        code, self.io_error = self.io_error, 0
        self.reply(str(code), str(seq))

    def _esc_j(self, seq: DeviceControl) -> None:
        """ESC.J: abort device-control work in progress: a pending ENQ acknowledgement, answers held for the trigger."""
        self._enq_pending = False
        self._outputs = deque(o for o in self._outputs if not o.needs_trigger)

    def _esc_r(self, seq: DeviceControl) -> None:
        """ESC.R: reset the handshake state (no Xoff sent, no ENQ pending, no echo awaited)."""
        self._xoff_sent = False
        self._enq_pending = False
        self.await_echo = False

    def _esc_config(self, seq: DeviceControl) -> None:
        """ESC.@: hardwire handshake and monitor mode (the logical buffer size is not simulated)."""
        p = seq.params
        if p and p[0] is not None:
            log.warning("%s: ESC.@ first parameter %d (logical buffer size) is not simulated; ignored",
                        self.model, p[0])
        config = p[1] if len(p) > 1 else None
        if config is None:
            config = 0
        if config > 255:
            self.io_fault(13, f"{seq}: configuration {config} out of range 0-255; defaulted")
            config = 0
        self.link.hardwire = bool(config & 1)
        self.link.monitor = config & 0b1100
        if self.link.monitor & 0b1000:
            log.warning("%s: monitor mode (ESC.@ bit 3) is not simulated; no echo to a terminal", self.model)

    def _handshake(self, seq: DeviceControl, mode: int) -> None:
        """ESC.H/ESC.I: block size, ENQ character and acknowledgement string."""
        p = [*seq.params, None, None]
        link = self.link
        block = p[0]
        link.block = 80 if block is None else block % 256
        enq = p[1] or 0
        if enq > 127:
            self.io_fault(13, f"{seq}: enquiry character {enq} out of range 0-127; defaulted")
            enq = 0
        link.enq = enq
        link.ack = self._ascii_string(seq, seq.params[2:])
        link.mode = mode
        self._set_specials()
        self.flow_check()

    def _esc_h(self, seq: DeviceControl) -> None:
        """ESC.H: handshake mode 1 (ENQ/ACK with an echoed acknowledgement)."""
        self._handshake(seq, 1)

    def _esc_i(self, seq: DeviceControl) -> None:
        """ESC.I: handshake mode 2 (ENQ/ACK or Xon/Xoff)."""
        self._handshake(seq, 2)

    def _ascii_string(self, seq: DeviceControl, values: tuple[int | None, ...]) -> bytes:
        """Up to 10 characters given as decimal codes; 0 ends the string; codes above 127 are range errors."""
        out = bytearray()
        for v in values:
            if v is None:
                continue
            if v == 0:
                break
            if v > 127:
                self.io_fault(13, f"{seq}: character code {v} out of range 0-127; ignored")
                continue
            out.append(v)
        return bytes(out[:10])

    def _esc_m(self, seq: DeviceControl) -> None:
        """ESC.M: turnaround delay, output trigger, echo terminator, reply terminator and initiator."""
        p = [*seq.params, *[None] * 6]
        link = self.link
        delay = p[0] or 0
        if delay > 54612:
            self.io_fault(13, f"{seq}: turnaround delay {delay} out of range 0-54612; defaulted")
            delay = 0
        link.turnaround_s = ((delay * 1.1875) % 65536) / 1.2 / 1000.0  # 7470A manual p. 10-33
        chars = []
        for value in p[1:6]:
            if value is not None and value > 127:
                self.io_fault(13, f"{seq}: character code {value} out of range 0-127; defaulted")
                value = None
            chars.append(value or 0)
        link.trigger, link.echo = chars[0], chars[1]
        terminator = bytes(c for c in chars[2:4] if c)
        link.terminator = terminator if chars[2] else b"\r"
        link.initiator = bytes([chars[4]]) if chars[4] else b""
        self._set_specials()

    def _esc_n(self, seq: DeviceControl) -> None:
        """ESC.N: intercharacter delay and the Xoff character (or the immediate ENQ response)."""
        p = [*seq.params, None]
        delay = p[0] or 0
        if delay > 65535:
            self.io_fault(13, f"{seq}: intercharacter delay {delay} out of range; defaulted")
            delay = 0
        self.link.char_delay_s = delay / 1000.0
        self.link.xoff = self._ascii_string(seq, seq.params[1:])
        self.flow_check()


INTERFACE_CONTROL: Final[dict[str, Callable[[Interface, DeviceControl], None]]] = {
    "E": Interface._esc_e, "J": Interface._esc_j, "R": Interface._esc_r, "@": Interface._esc_config,
    "H": Interface._esc_h, "I": Interface._esc_i, "M": Interface._esc_m, "N": Interface._esc_n,
}
"""Device-control letter -> handler for the sequences that configure or query the interface itself."""


def _fmt(v: float) -> str:
    """An integer answer field."""
    return str(round(v))


def _fmt_user(v: float) -> str:
    """A user-unit answer field (at most 4 decimals, no trailing zeros)."""
    if float(v).is_integer():
        return str(int(v))
    return f"{v:.4f}".rstrip("0").rstrip(".")


class OutputInstructions:
    """The HP-GL output instructions: each answers through the interface (after everything before it executed)."""

    def __init__(self, spec: ModelSpec, machine: Machine, status: Status, interface: Interface,
                 pen_colours: dict[int, str]) -> None:
        self.spec = spec
        self.machine = machine
        self.status = status
        self.interface = interface
        self.pen_colours = pen_colours

    def _answer(self, item: Instruction, text: str) -> None:
        """Reply to ``item`` with ``text``."""
        self.interface.reply(text, str(item))

    def _here(self) -> str:
        """Where the pen physically is, in the current coordinate system, and the pen state: OA's answer."""
        m = self.machine
        x, y = m.to_logical(*m.phys)
        return f"{_fmt(x)},{_fmt(y)},{int(m.pen_down)}"

    def _oi(self, item: Instruction) -> None:
        """OI: the model's identification (a 7475A answers only after IN)."""
        if self.spec.oi_needs_in and not self.status.in_seen:
            log.warning("%s: OI before any IN: a 7475A does not answer it", self.spec.name)
            return
        self._answer(item, self.spec.ident)

    def _os(self, item: Instruction) -> None:
        """OS: the status byte (reading it clears the 'initialized' bit)."""
        text = str(self.status.os_byte(self.machine.pen_down))
        self.status.initialized = False
        self._answer(item, text)

    def _oe(self, item: Instruction) -> None:
        """OE: the last HP-GL error, cleared with the OS error bit."""
        text = str(self.status.hpgl_error)
        self.status.clear_error()
        self._answer(item, text)

    def _oa(self, item: Instruction) -> None:
        """OA: the actual pen position (plotter units) and state."""
        self._answer(item, self._here())

    def _oc(self, item: Instruction) -> None:
        """OC: the commanded position, in user units while SC scales."""
        m = self.machine
        x, y = m.pos
        if m.g.scale is not None:
            ux, uy = m.plotter_to_user(x, y)
            self._answer(item, f"{_fmt_user(round(ux, 4))},{_fmt_user(round(uy, 4))},{int(m.pen_down)}")
        else:
            self._answer(item, f"{_fmt(x)},{_fmt(y)},{int(m.pen_down)}")

    def _od(self, item: Instruction) -> None:
        """OD: the digitized point (where the pen stands when none was digitized), then forgotten."""
        digitized = self.status.digitized
        if digitized is None:
            text = self._here()
        else:
            x, y, pen = digitized
            text = f"{_fmt(x)},{_fmt(y)},{pen}"
        self.status.digitized = None
        self._answer(item, text)

    def _of(self, item: Instruction) -> None:
        """OF: plotter units per millimetre."""
        per_mm = 1.0 / self.spec.unit_mm
        self._answer(item, f"{int(per_mm)},{int(per_mm)}")

    def _oh(self, item: Instruction) -> None:
        """OH: the hard-clip limits in the current coordinate system."""
        w, h = self.machine.logical_limits()
        self._answer(item, f"0,0,{w},{h}")

    def _oo(self, item: Instruction) -> None:
        """OO: the model's output options."""
        self._answer(item, self.spec.output_options)

    def _op(self, item: Instruction) -> None:
        """OP: P1 and P2 (reading them clears the 'P1/P2 changed' bit)."""
        (ax, ay), (bx, by) = self.machine.g.p1, self.machine.g.p2
        self.status.p1p2_changed = False
        self._answer(item, f"{_fmt(ax)},{_fmt(ay)},{_fmt(bx)},{_fmt(by)}")

    def _ow(self, item: Instruction) -> None:
        """OW: the IW window."""
        self._answer(item, ",".join(_fmt(v) for v in self.machine.g.window))

    def _ot(self, item: Instruction) -> None:
        """OT: carousel type 1 and a bit per loaded stall."""
        mask = sum(1 << (pen - 1) for pen in self.pen_colours if 1 <= pen <= self.spec.pens)
        self._answer(item, f"1,{mask}")  # assumption: carousel type 1


OUTPUTS: Final[CommandTable[OutputInstructions]] = {
    "OA": Command(None, OutputInstructions._oa), "OC": Command(None, OutputInstructions._oc),
    "OD": Command(None, OutputInstructions._od), "OE": Command(None, OutputInstructions._oe),
    "OF": Command(None, OutputInstructions._of), "OH": Command(None, OutputInstructions._oh),
    "OI": Command(None, OutputInstructions._oi), "OO": Command(None, OutputInstructions._oo),
    "OP": Command(None, OutputInstructions._op), "OS": Command(None, OutputInstructions._os),
    "OT": Command(None, OutputInstructions._ot), "OW": Command(None, OutputInstructions._ow),
}
"""Mnemonic -> (parameter counts, handler) for the output instructions."""

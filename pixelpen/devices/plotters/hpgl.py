"""HP 7475A / 7550A / 7440A HP-GL pen plotters: URL schemes, flow control, confirmed plotting, device errors.

``hp7475a:PORT?options`` (likewise ``hp7550a``, ``hp7440a``) where PORT is a serial device
(``/dev/ttyUSB0``, ``COM3``), any pyserial URL (``[rfc2217://host:4000?logging=debug]`` in brackets
when it has a query), ``usb:VID:PID`` or ``usb:auto`` for a USB printer-class (USB-parallel)
adapter, or ``auto`` to find the plotter by asking every serial port ``IN;OI;``.  ``sim:hp7475a``
plots on the simulator through the same code.

Flow control (option ``handshake``, plotters.md §1.5):

* ``escb`` (default): software checking.  ``ESC.B`` answers the free bytes F of the input buffer at
  the moment the query arrives, i.e. after every byte written before it.  With W the HP-GL bytes
  written so far and W_q those written before the query, the host may write an instruction of L
  bytes only while ``L <= F - (W - W_q) - reserve``: the buffer then never holds more than its
  size minus ``reserve`` (default 128: a real 7475A overflows when filled to the exact figure).
  The plotter is never starved while the host has data: the host writes until the room falls to
  ``LOW_WATER`` bytes, sends ``ESC.B`` behind that data and then writes the rest of the room, so
  the answer returns while data is still on the wire and fresh room is known before the old runs
  out.  A query that finds too little room is repeated after ``POLL_S`` seconds, the gap doubling
  up to ``MAX_POLL_S`` while the plotter takes nothing (a pen change); meanwhile the buffer still
  holds its size minus the reserve minus one instruction, far more than the plotter draws in
  MAX_POLL_S.
* ``xonxoff``: ``ESC.(;ESC.I81;;17:ESC.N;19:`` makes the plotter send XOFF (DC3) below 81 free
  bytes and XON (DC1) at 128; the link holds writes while XOFF is in force (software flow control).
* ``hardwire``: ``ESC.@;1:`` makes the plotter hold DTR low while it is full; the link runs RTS/CTS.
* ``none``: no flow control (for plotters fed slower than they draw; overflows otherwise).

With ``xonxoff`` and ``hardwire`` the plotter's handshake holds every byte, queries included, so a
pause longer than ``stall`` with a full buffer counts as a stall there; ``escb`` asks ESC.O instead.
Writes there go out in chunks of ``WRITE_CHUNK`` bytes, each allowed ``stall`` seconds: the limit is on
the plotter taking nothing, not on the time a long stroke needs at the line's speed.

Connecting sends ``ESC.(`` and ``ESC.K`` (before any byte that enters the buffer: a connection that
broke mid-instruction may have left half a number there), the handshake preamble, ``IN;`` with
``PSn;`` and ``VSv;`` where asked for, and ``OS;OI;OE;``; OS clears the status bit 8 that IN set
(so that a later OS showing it means the plotter was switched on again), the OI answer (the model)
ends any stale answers of an earlier connection, OE checks the setup, then ``ESC.E`` and ``ESC.B``
start the job.

After a fault, before that handshake (``_where``): ``ESC.(``, then ``ESC.B`` every ``MAX_POLL_S``
until its answer has not changed for ``SETTLE_S`` plus the longest time one instruction of the
strokes in doubt can take (the plotter has executed every complete instruction it received and
finished moving; answers of the old connection that arrive meanwhile are read and dropped), then
``ESC.K`` (drops a half-received instruction; nothing is moving any more) and ``OS;OA;``: OA is
the pen position and state, OS bit 8 set means the plotter was switched off and on (its buffer and
what it was drawing are lost: the position is reported lost).  At each sync point the OA answer
must be the end of the last stroke sent before it; another position is a fault (a corrupted
coordinate or a skipped instruction).

Confirmation and errors: with ``escb`` an ESC.B answer confirms every stroke whose last byte lies
``CONFIRM_MARGIN`` bytes before what the plotter has taken from its buffer; after every
``sync_strokes`` strokes or ``sync_bytes`` bytes (at pen-up) the driver sends ``PU;OA;OE;`` and ``ESC.E``.  OA and OE are buffered output instructions, answered when
execution reaches them, so their answers confirm every stroke before them; the answers are read as
they arrive, never waited for while there is data to send.  A non-zero OE (HP-GL error) or ESC.E
(RS-232 error) raises :class:`~pixelpen.errors.ProtocolError` with the code, its meaning and the
instructions sent since the previous sync point.  Replies are told apart by form: OA answers
``x,y,pen``, OE follows its OA at once, and numbers arriving otherwise answer the ``ESC`` queries in
the order they were sent.  When nothing moves for ``PAUSE_CHECK_S`` the driver asks ``ESC.O``: VIEW
(16) or the raised paper lever (32) is a pause and waits without limit; no progress for ``stall``
seconds otherwise is a fault (LinkTimeout).  Ctrl-C and close send ``ESC.K`` then ``PU;SP0;`` and
the park move.
"""

from __future__ import annotations

import logging
import math
import re
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from pixelpen.devices.plotters import hpgl_encode as enc
from pixelpen.devices.plotters.base import DeviceWhere, PlotterDisplay
from pixelpen.display.registry import register_display
from pixelpen.drivers import discovery
from pixelpen.drivers.serial import SerialLink
from pixelpen.drivers.stream import Link
from pixelpen.drivers.usbprinter import UsbPrinterLink
from pixelpen.errors import ConfigError, LinkError, LinkTimeout, ProtocolError, URLError
from pixelpen.profiles.model import DeviceProfile
from pixelpen.urls import Options, parse_bool
from pixelpen.vector.displaylist import DisplayList

log = logging.getLogger(__name__)

HPGL_ERRORS: dict[int, str] = {
    0: "no error",
    1: "instruction not recognised",
    2: "wrong number of parameters",
    3: "bad parameter value",
    5: "unknown character set",
    6: "position overflow",
    8: "vector received while the pinch wheels are raised",
}
"""OE error numbers (plotters.md §1.4)."""
IO_ERRORS: dict[int, str] = {
    0: "no error",
    10: "output instruction received while another output was in progress",
    11: "invalid byte after ESC .",
    12: "invalid byte inside a device-control instruction",
    13: "device-control parameter out of range",
    14: "too many device-control parameters",
    15: "framing, parity or overrun error",
    16: "input buffer overflow",
}
"""ESC.E RS-232 error numbers (plotters.md §1.4)."""
ERROR_OUTPUT_BUSY = 10
"""ESC.E 10: an output request arrived while an answer was going out and was ignored (a link hiccup, not a drawing error)."""
STATUS_VIEW = 16
STATUS_PAPER_LEVER = 32
"""ESC.O bits that mean the plotter pauses on the operator's word (plotters.md §1.4)."""

POLL_S = 0.05
"""Seconds before asking ESC.B again after an answer that found too little room (see ``_wait``)."""
LOW_WATER = 2 * enc.MAX_INSTRUCTION
"""Room (bytes) at which ESC.B is asked behind the data written so far (escb)."""
MAX_POLL_S = 0.25
"""Longest gap between ESC.B queries while waiting; the plotter still holds buffer-size minus reserve bytes."""
PAUSE_CHECK_S = 1.0
"""Seconds without progress after which the driver asks ESC.O whether the plotter is paused."""
CONFIRM_MARGIN = 2 * enc.MAX_INSTRUCTION
"""Bytes the plotter must have taken from its buffer beyond a stroke's last byte before ESC.B confirms the stroke
(the instruction being drawn and one read ahead; the simulator reads one instruction at a time)."""
SETTLE_S = 2.0
"""Seconds ESC.B must stay unchanged, beyond one instruction's drawing time, before the plotter counts as settled."""
QUIET_S = 0.2
"""Seconds the answers of the settle queries are given to arrive before the position is asked."""
SAFE_WAIT_S = 10.0
"""Longest wait for the safe-stop sequence to be executed before closing."""
DISCOVERY_TIMEOUT_S = 0.5
WRITE_CHUNK = 512
"""Bytes written at a time under xonxoff/hardwire; each chunk must be taken within ``stall`` seconds."""
_MAX_REPLY = 256
MAX_OE = 31
"""Largest number taken as an OE answer (HP-GL/1 error numbers are 0..8)."""
_OA = re.compile(r"\s*-?\d+\s*,\s*-?\d+\s*,\s*\d+\s*")
_NUMBER = re.compile(r"\s*-?\d+\s*")
_IDENT = re.compile(r"[0-9A-Za-z][0-9A-Za-z\- ]*")
_STRIP = bytes((0x00, 0x0A, 0x11, 0x13))  # NUL, LF, XON, XOFF never belong to an answer


def _handshake(text: str) -> str:
    if text not in enc.HANDSHAKES:
        raise ValueError(f"expected one of {', '.join(enc.HANDSHAKES)}")
    return text


def _count(minimum: int) -> Callable[[str], int]:
    def convert(text: str) -> int:
        value = int(text)
        if value < minimum:
            raise ValueError(f"expected an integer >= {minimum}")
        return value

    return convert


def _positive(text: str) -> float:
    value = float(text)
    if not (math.isfinite(value) and value > 0):
        raise ValueError("expected a number > 0")
    return value


_FLOW_OF = {"escb": "none", "none": "none", "xonxoff": "xonxoff", "hardwire": "rtscts"}


@dataclass
class _SyncPoint:
    """Output requests in the stream: answered once the plotter has executed everything before them."""

    confirms: int | None
    """Strokes < confirms are on paper when the answers come (None: the connect handshake)."""
    instructions: list[bytes]
    """HP-GL sent since the previous sync point (what an error here was caused by)."""
    first_stroke: int
    marker: str = "OA"
    """The answer before OE: ``OA`` (x,y,pen) or ``OI`` (the model name)."""
    seen: str | None = None
    """The marker's answer once it came."""
    expect: tuple[int, int] | None = None
    """Where OA must find the pen (the end of the last stroke before the sync point; None: not checked)."""


@dataclass
class _Query:
    """An ESC query waiting for its immediate answer."""

    kind: str
    deadline: float
    written: int
    """HP-GL bytes written before the query (ESC.B's answer describes the buffer after them)."""
    sent: int
    """All bytes written before and including the query."""
    sync: _SyncPoint | None = None
    """For ESC.E: the sync point whose bytes it covers."""


@dataclass
class _Wire:
    """Protocol state of one connection (replaced on every connect)."""

    rx: bytearray = field(default_factory=bytearray)
    syncs: deque[_SyncPoint] = field(default_factory=deque)
    queries: deque[_Query] = field(default_factory=deque)
    window: list[bytes] = field(default_factory=list)
    window_first: int = 0
    strokes_sent: int = 0
    last_point: tuple[int, int] | None = None
    """End of the last stroke sent (where the next sync point's OA must find the pen)."""
    size: int | None = None
    """The plotter's buffer size (ESC.B on the empty buffer after the connect handshake; escb only)."""
    ends: deque[tuple[int, int]] = field(default_factory=deque)
    """(HP-GL bytes written up to a stroke's end, strokes done then) not yet confirmed by ESC.B."""
    since_sync_strokes: int = 0
    since_sync_bytes: int = 0
    written: int = 0
    """HP-GL bytes written (they take buffer space)."""
    sent: int = 0
    """Every byte written, device control included."""
    delivered: int = 0
    """Bytes known to have reached the plotter (those before an answered ESC query)."""
    free: tuple[int, int] | None = None
    """Last ESC.B answer and the HP-GL bytes written before its query."""
    mark: int | None = None
    """written-before-query + free of the last ESC.B: grows exactly as the plotter consumes bytes."""
    free_answers: int = 0
    """ESC.B answers received."""
    status: int = 0
    """Last ESC.O answer."""
    progress_at: float = 0.0
    last_free_ask: float = -math.inf
    last_status_ask: float = -math.inf
    received_any: bool = False
    connecting: bool = False


class HPGLDisplay(PlotterDisplay):
    """An HP-GL plotter on RS-232, rfc2217:// or a USB printer-class adapter (see the module docstring)."""

    reports_position = True
    lifts_after_each_stroke = False  # PUx,y lifts and travels in one instruction; a bare PU; only at sync points
    rests_pen_down_at_start = False  # PD always comes with the vectors it draws
    ident: ClassVar[str] = ""
    """What the model answers to OI."""
    max_velocity_cm_s: ClassVar[float] = 38.1
    """Top pen speed (VS maximum); a profile asking for less gets ``VS``."""
    knows_ps: ClassVar[bool] = False
    """True when the model takes ``PS`` (paper size)."""
    mnemonics: ClassVar[frozenset[str]] = frozenset(
        ["AA", "AR", "CA", "CI", "CP", "CS", "DF", "DI", "DR", "DT", "EA", "ER", "EW", "FT", "IM", "IN", "IP", "IW", "LB", "LT", "OA", "OC", "OE", "OF", "OH", "OI", "OO", "OP", "OS", "OW", "PA", "PD", "PR", "PT", "PU", "RA", "RO", "RR", "SA", "SC", "SI", "SL", "SM", "SP", "SR", "SS", "TL", "UC", "VS", "WG", "XT", "YT"]
    )
    """HP-GL instructions the model knows (the HP-GL/1 set; an error 1 names a sent one outside it)."""
    url_options = {
        **PlotterDisplay.url_options,
        "handshake": "flow control: escb (ESC.B polling, default), xonxoff, hardwire or none",
        "reserve": "bytes kept free in the plotter's buffer with handshake=escb; default 128",
        "sync_strokes": "strokes between two confirmations (OA/OE); default 16",
        "sync_bytes": "bytes between two confirmations (OA/OE); default 512",
        "velocity": "pen-down velocity in cm/s (VS); default the profile's, if below the model's top speed",
        "ps": "send PS (paper size) after IN: true or false; default true where the model knows PS",
        "stall": "seconds without progress (and no pause) before a plot counts as stalled; default 60",
    }

    def __init__(
        self,
        port: str,
        *,
        handshake: str = "escb",
        reserve: int = 128,
        sync_strokes: int = 16,
        sync_bytes: int = 512,
        velocity: float | None = None,
        ps: bool | None = None,
        stall: float = 60.0,
        flow: str | None = None,
        usb_backend: Any = None,
        **kwargs: Any,
    ) -> None:
        if handshake not in enc.HANDSHAKES:
            raise ConfigError(f"handshake must be one of {', '.join(enc.HANDSHAKES)}, got {handshake!r}")
        wanted = _FLOW_OF[handshake]
        if flow is not None and handshake in ("xonxoff", "hardwire") and flow != wanted:
            raise ConfigError(f"handshake={handshake} needs flow={wanted}, got flow={flow}")
        if reserve < 0 or sync_strokes < 1 or sync_bytes < 1 or not stall > 0:
            raise ConfigError("reserve must be >= 0, sync_strokes and sync_bytes >= 1 and stall > 0")
        super().__init__(port, flow=flow or wanted, **kwargs)
        self.handshake = handshake
        self.reserve = reserve
        self.sync_strokes = sync_strokes
        self.sync_bytes = sync_bytes
        self.stall_s = float(stall)
        top = self.max_velocity_cm_s
        profile_cm_s = self.profile.pen_down.speed / 10.0
        self.velocity_cm_s = velocity if velocity is not None else (profile_cm_s if profile_cm_s < top else None)
        if self.velocity_cm_s is not None and not 0 < self.velocity_cm_s <= top:
            raise ConfigError(f"{self.profile.name}: velocity {self.velocity_cm_s:g} cm/s is outside 0..{top:g}")
        self.send_ps = self.knows_ps if ps is None else ps
        self.usb_backend = usb_backend
        self.model_reply: str | None = None
        """What the plotter answered to OI at the last connect."""
        self._found_port: str | None = None
        self._wire = _Wire()

    @classmethod
    def family_options(cls, options: Options, profile: DeviceProfile) -> dict[str, object]:
        """Constructor keywords from the HP-GL options of a URL (see ``url_options``)."""
        return {
            "handshake": options.get("handshake", _handshake, "escb"),
            "reserve": options.get("reserve", _count(0), 128),
            "sync_strokes": options.get("sync_strokes", _count(1), 16),
            "sync_bytes": options.get("sync_bytes", _count(1), 512),
            "velocity": options.get("velocity", _positive, None),
            "ps": options.get("ps", parse_bool, None),
            "stall": options.get("stall", _positive, 60.0),
        }

    @classmethod
    def simulator_options(cls, sim_options: dict[str, str], options: Options, profile: DeviceProfile) -> dict[str, str]:
        """The simulator gets the profile's own name of the paper (``ansi_a`` is the profile's alias of ``a``)."""
        out = dict(sim_options)
        if "paper" in out:
            out["paper"] = profile.paper(out["paper"]).name
        return out

    # -- links -------------------------------------------------------------------------------
    def _make_link(self) -> Link:
        if self._link_factory is not None:
            return self._link_factory()
        if self.port.lower().startswith("usb:"):
            return self._usb_link()
        if self.port.lower() == "auto":
            return self._discover()
        return super()._make_link()

    def _usb_link(self) -> Link:
        spec = self.port[4:]
        vid = pid = None
        if spec.lower() != "auto":
            parts = spec.split(":")
            try:
                vid, pid = (int(p, 16) for p in parts)
            except ValueError:
                raise URLError(f"{self.port!r}: expected usb:VID:PID in hex (usb:067b:2305) or usb:auto") from None
        return UsbPrinterLink(vid, pid, backend=self.usb_backend, timeout=self.timeout)

    def _discover(self) -> Link:
        """The serial port whose device answers OI with this model (the last one found is tried first)."""
        ports = [d.path for d in discovery.list_serial_ports()]
        if self._found_port in ports:
            ports.remove(self._found_port)
            ports.insert(0, self._found_port)
        tried = []
        for path in ports:
            try:
                link = SerialLink(path, baudrate=self.baudrate, flow=self.flow, timeout=self.timeout)
            except LinkError as exc:
                tried.append(f"{path}: {exc}")
                continue
            who = discovery.identify(link, "hpgl", DISCOVERY_TIMEOUT_S)
            if who is not None and who.model.strip().upper() == self.ident:
                self._found_port = path
                log.info("%s: found on %s", self.ident, path)
                return link
            link.close()
            tried.append(f"{path}: {'answered ' + repr(who.model) if who else 'no HP-GL answer'}")
        raise LinkError(
            f"auto: no serial port answered OI with {self.ident} at {self.baudrate} baud "
            f"({'; '.join(tried) or 'no serial ports found'})"
        )

    # -- the device core ---------------------------------------------------------------------
    def _connect(self) -> None:
        """Plotter on, abort leftovers, handshake, IN (PS, VS), OI/OE, ESC.E and ESC.B (see the module docstring)."""
        link = self._require_link()
        self._wire = w = _Wire(progress_at=self.clock.now(), connecting=True)
        link.reset_input()
        # ESC.K before the preamble's ';': half a number left in the buffer would be completed and executed
        self._write(enc.PLOTTER_ON + enc.ABORT_GRAPHICS + enc.handshake_preamble(self.handshake), graphics=False)
        paper_size = self.paper.set_ps if self.send_ps else None
        w.window = enc.initialize(paper_size, self.velocity_cm_s)
        point = _SyncPoint(None, w.window, 0, marker="OI")
        w.syncs.append(point)
        self._write(b"".join(w.window) + enc.IDENTIFY_REQUEST, graphics=True)
        w.window.append(enc.IDENTIFY_REQUEST)
        self._wait(lambda: not w.syncs, "waiting for the answer to IN;OI;OE;")
        w.connecting = False
        w.window, w.window_first = [], 0
        self.model_reply = point.seen
        if point.seen is not None and point.seen.strip().upper() != self.ident:
            log.warning("%s: the plotter says it is a %s", self.profile.name, point.seen)
        self._ask("E")
        if self.handshake == "escb":
            self._ask("B")
        self._wait(lambda: not w.queries, "waiting for ESC.E / ESC.B answers")
        if w.free is not None:
            w.size = w.free[0]  # everything before OI was executed: the buffer is empty
        if self.handshake == "escb" and self._room() < enc.MAX_INSTRUCTION:
            free = w.free[0] if w.free else 0
            raise ConfigError(
                f"{self.profile.name}: reserve={self.reserve} leaves no room in a buffer with {free} free bytes"
            )

    def _device_points(self, dl: DisplayList) -> np.ndarray:
        """Device points of a whole job, refused before anything is sent if one is outside HP-GL's range."""
        pts = super()._device_points(dl)
        bad = np.any((pts < enc.COORD_MIN) | (pts > enc.COORD_MAX), axis=1)
        if bad.any():
            k = int(dl.offsets.searchsorted(int(np.argmax(bad)), side="right")) - 1
            enc.stroke(pts[dl.offsets[k] : dl.offsets[k + 1]], index=k)  # raises, naming stroke and point
        return pts

    def _send_stroke(self, index: int, points: np.ndarray, pen: int) -> None:
        w = self._wire
        instructions = enc.stroke(points, index=index)
        if w.strokes_sent != index:  # a resumed job starts a new window at its first stroke
            w.window_first = index
        self._send(instructions)
        w.strokes_sent = index + 1
        w.last_point = (int(points[-1, 0]), int(points[-1, 1]))
        if w.size is not None:
            w.ends.append((w.written, index + 1))
        w.since_sync_strokes += 1
        w.since_sync_bytes += sum(len(i) for i in instructions)
        if w.since_sync_strokes >= self.sync_strokes or w.since_sync_bytes >= self.sync_bytes:
            self._sync()

    def _poll(self) -> None:
        self._pump()
        self._check_overdue()

    def _drain(self) -> None:
        w = self._wire
        if w.window:
            self._sync()
        self._wait(lambda: not w.syncs and not w.queries, "waiting for the plotter to finish", poll=MAX_POLL_S)

    def _select_pen(self, pen: int) -> None:
        if self._wire.strokes_sent:
            self._lifted_in_place(self._wire.strokes_sent - 1)  # SP lifts the pen where it stands
        self._send([enc.select_pen(pen)])

    def _device_paused(self) -> bool:
        self._pump()
        if self._wire.status & (STATUS_VIEW | STATUS_PAPER_LEVER):
            self._ask_status_if_due(self.clock.now())
        return bool(self._wire.status & (STATUS_VIEW | STATUS_PAPER_LEVER))

    def _make_safe(self) -> None:
        """Drop host-queued bytes, ESC.K (drop buffered graphics), ``PU;SP0;`` and park, then wait (bounded) until they ran."""
        link = self.link
        if link is None or link.closed:
            return
        try:
            link.reset_output()  # bytes still queued on the host would reach the plotter after the abort
            link.write(enc.ABORT_GRAPHICS, timeout=self._limit(link, self.timeout))
            self._wire = _Wire(progress_at=self.clock.now())
            link.write(b"".join(enc.trailer(self.paper.park)) + b"OI;", timeout=self._limit(link, self.timeout))
            self.pen = None
            deadline = self.clock.now() + SAFE_WAIT_S
            while self.clock.now() < deadline:
                line = link.read_until(b"\r", timeout=deadline - self.clock.now(), max_size=_MAX_REPLY)
                if _is_marker("OI", _clean(line)):
                    return
        except Exception as exc:  # leaving the plotter safe is best effort; say why it may not be
            log.warning("%s: safe stop may be incomplete: %s", self.profile.name, exc)

    # -- after a fault: where the plotter stopped ---------------------------------------------
    def _where(self) -> DeviceWhere:
        """Let the plotter finish what the old connection left, drop a half instruction, ask OS and OA (module docstring)."""
        link = self._require_link()
        link.reset_input()
        self._wire = _Wire(progress_at=self.clock.now(), connecting=True)
        self._write(enc.PLOTTER_ON, graphics=False)
        self._settle(SETTLE_S + self._instruction_time_s())
        link.read(4096, timeout=QUIET_S)  # answers still on their way (late ones of the settle queries)
        link.reset_input()
        self._write(enc.ABORT_GRAPHICS + enc.WHERE_REQUEST, graphics=False)
        status = None
        while not _OA.fullmatch(text := self._answer(None, "OS;OA;")):
            status = text if _NUMBER.fullmatch(text) else None  # OS answers just before OA; a late number first
        if status is None:
            raise LinkError(f"{self._name()}: OA answered {text!r} without the OS answer before it")
        x, y, pen = (int(v) for v in text.split(","))
        if int(status) & enc.STATUS_INITIALISED:
            return DeviceWhere(
                (x, y), bool(pen), position_lost=True,
                detail=f"the plotter was switched off or reset (OS {int(status)}: initialised since the job began), "
                "so what it had received but not drawn is lost",
            )
        return DeviceWhere((x, y), bool(pen), detail=f"OA {x},{y},{pen}")

    def _settle(self, hold_s: float) -> None:
        """Ask ESC.B until its answer stays the same for ``hold_s`` seconds (waiting as long as VIEW or the lever holds)."""
        last, since = None, self.clock.now()
        after_output = False
        while True:
            self._write(enc.ASK_FREE, graphics=False)
            while True:  # answers of the old connection's buffered requests may come first
                text = self._answer(None, "ESC.B")
                if _OA.fullmatch(text) or (_IDENT.fullmatch(text) and not _NUMBER.fullmatch(text)):
                    after_output = True  # an OA or OI answer: the OE answer follows it
                elif after_output and int(text) <= MAX_OE:
                    after_output = False
                else:
                    break
            now = self.clock.now()
            if text != last:
                last, since = text, now
            elif now - since >= hold_s:
                self._write(enc.ASK_STATUS, graphics=False)
                if not int(self._answer(_NUMBER, "ESC.O")) & (STATUS_VIEW | STATUS_PAPER_LEVER):
                    self._pause_changed(False)
                    return
                self._pause_changed(True)
                since = now
            self.clock.sleep(MAX_POLL_S)

    def _answer(self, form: re.Pattern[str] | None, what: str) -> str:
        """The next non-empty answer line, which must match ``form`` (None: an OA, OI or number)."""
        link = self._require_link()
        while True:
            try:
                line = _clean(link.read_until(b"\r", timeout=self.timeout, max_size=_MAX_REPLY))
            except LinkTimeout:
                raise LinkTimeout(f"{self._name()}: no answer to {what}; is the plotter switched on?") from None
            if not line:
                continue
            ok = _OA.fullmatch(line) or _NUMBER.fullmatch(line) or _IDENT.fullmatch(line) if form is None else form.fullmatch(line)
            if not ok:
                raise LinkError(f"{self._name()}: expected the {what} answer, got {line!r}")
            return line

    def _instruction_time_s(self) -> float:
        """Longest time one instruction of the strokes in doubt can take to draw (the whole job's when unknown)."""
        speed_mm_s = 10.0 * (self.velocity_cm_s or self.max_velocity_cm_s)
        job = self._job
        if job is None or not len(job):
            x0, x1 = self.paper.x_range
            y0, y1 = self.paper.y_range
            diagonal = math.hypot(x1 - x0, y1 - y0) * self.profile.unit_mm
            return diagonal * enc.MAX_INSTRUCTION / len("PD0,0,") / speed_mm_s
        lo, hi = job.offsets[self.confirmed], job.offsets[min(len(job), max(self.confirmed + 1, self._sent_end))]
        pts = job.points[lo:hi]
        longest = float(np.hypot(*np.diff(pts, axis=0).T).sum()) if len(pts) > 1 else 0.0
        return longest * job.unit_mm / speed_mm_s

    # -- manual control ----------------------------------------------------------------------
    def _manual_pen(self, down: bool) -> None:
        self._run_now([b"PD;" if down else enc.PEN_UP])

    def _manual_pen_state(self) -> bool | None:
        return self._run_now([]).split(",")[2] != "0"

    def _manual_home(self) -> None:
        x, y = self.paper.park if self.paper.park is not None else (0, 0)
        self._run_now([enc.PEN_UP, b"PU%d,%d;" % (x, y)])

    def _manual_motors_off(self) -> None:
        raise ConfigError(
            f"{self.profile.name}: HP-GL plotters have no motors-off command (the pen carriage is held while the "
            "plotter is on); switch the plotter off to move it by hand"
        )

    def _run_now(self, instructions: list[bytes]) -> str:
        """Send instructions and ``OA;OE;``, wait until the plotter has executed them; return the OA answer."""
        w = self._wire
        point = _SyncPoint(None, list(instructions), w.strokes_sent)
        w.syncs.append(point)
        self._send([*instructions, enc.SYNC_REQUEST])
        self._wait(lambda: point not in w.syncs, "waiting for the plotter to move", poll=MAX_POLL_S)
        assert point.seen is not None
        return point.seen

    # -- streaming ---------------------------------------------------------------------------
    def _send(self, instructions: list[bytes]) -> None:
        """Write HP-GL instructions under the handshake, recording them in the current sync window."""
        w = self._wire
        w.window.extend(instructions)
        if self.handshake != "escb":
            self._write(b"".join(instructions), graphics=True)
            return
        i = 0
        while i < len(instructions):
            room = self._room()
            # write down to the low-water mark, ask ESC.B behind that data, then write the rest of the room:
            # the answer comes back while the rest is still on the wire
            limit = room - LOW_WATER if room > LOW_WATER and not self._asking("B") else room
            j, size = i, 0
            while j < len(instructions) and size + len(instructions[j]) <= (limit if j > i else room):
                size += len(instructions[j])
                j += 1
            if j == i:
                self._wait_for_room(len(instructions[i]))
                continue
            self._write(b"".join(instructions[i:j]), graphics=True)
            i = j
            if self._room() <= LOW_WATER and not self._asking("B"):
                self._ask("B")

    def _wait_for_room(self, need: int) -> None:
        self._wait(lambda: self._room() >= need, "waiting for room in the plotter's buffer", poll=POLL_S, backoff=True)

    def _sync(self) -> None:
        """``PU;OA;OE;`` and ``ESC.E``: confirm every stroke so far and check both error registers."""
        w = self._wire
        point = _SyncPoint(w.strokes_sent, w.window, w.window_first, expect=w.last_point)
        w.syncs.append(point)
        if w.strokes_sent:
            self._lifted_in_place(w.strokes_sent - 1)  # the PU; below
        self._send([enc.PEN_UP, enc.SYNC_REQUEST])
        w.window, w.window_first = [], w.strokes_sent
        w.since_sync_strokes = w.since_sync_bytes = 0
        self._ask("E", sync=point)

    def _room(self) -> int:
        """HP-GL bytes the host may write now without eating into the reserve (escb)."""
        w = self._wire
        if w.free is None:
            return 0
        free, written_then = w.free
        return free - (w.written - written_then) - self.reserve

    def _write(self, data: bytes, *, graphics: bool) -> None:
        link = self._require_link()
        # with a device-driven handshake a write may rightly wait as long as the plotter is busy
        # (stall_s per chunk: a stall is no chunk taken for that long, however long the whole stroke takes)
        held = self.handshake in ("xonxoff", "hardwire")
        step = WRITE_CHUNK if held else max(1, len(data))
        for at in range(0, len(data), step):
            chunk = data[at:at + step]
            link.write(chunk, timeout=self._limit(link, self.stall_s) if held else None)
            self._wire.sent += len(chunk)
            if graphics:
                self._wire.written += len(chunk)
            if held:
                self._wire.progress_at = self.clock.now()  # the handshake let it through: the plotter is taking bytes

    def _ask(self, kind: str, *, sync: _SyncPoint | None = None) -> None:
        """Send ``ESC.<kind>`` and expect its immediate answer (deadline: time for the bytes ahead + timeout)."""
        w = self._wire
        ahead = w.sent - w.delivered + 3
        limit = self.timeout + ahead * 10.0 / max(1, self.baudrate)
        if self.handshake in ("xonxoff", "hardwire"):
            limit += self.stall_s  # bytes ahead of the query wait for the plotter to take them
        data = {"B": enc.ASK_FREE, "E": enc.ASK_IO_ERROR, "O": enc.ASK_STATUS}[kind]
        self._write(data, graphics=False)
        now = self.clock.now()
        w.queries.append(_Query(kind, now + limit, w.written, w.sent, sync))
        if kind == "B":
            w.last_free_ask = now
        elif kind == "O":
            w.last_status_ask = now

    def _asking(self, kind: str) -> bool:
        return any(q.kind == kind for q in self._wire.queries)

    def _ask_status_if_due(self, now: float) -> None:
        link = self._require_link()
        if not self._asking("O") and now - self._wire.last_status_ask >= PAUSE_CHECK_S / 2 and not link.held_off:
            self._ask("O")

    # -- waiting and reading -----------------------------------------------------------------
    def _wait(
        self, done: Callable[[], bool], what: str, *, poll: float | None = None, backoff: bool = False
    ) -> None:
        """Read answers until ``done()``; a paused plotter is waited for, one that stopped for ``stall`` s is a fault.

        With ``poll`` ESC.B is asked every ``poll`` seconds; with ``backoff`` the gap doubles (up to
        MAX_POLL_S) after an answer showing the plotter took nothing since the one before (a pen change),
        and is ``poll`` again after one showing it took bytes.
        """
        w = self._wire
        announced = False
        interval, answers, mark = poll, w.free_answers, w.mark
        while True:
            self._pump()
            if done():
                if announced:
                    log.info("%s: plotting resumed", self.profile.name)
                    self._pause_changed(False)
                return
            now = self.clock.now()
            self._check_overdue(now)
            paused = bool(w.status & (STATUS_VIEW | STATUS_PAPER_LEVER))
            if paused:
                if not announced:
                    why = "the paper lever is raised" if w.status & STATUS_PAPER_LEVER else "VIEW is pressed"
                    log.info("%s: paused (%s); waiting", self.profile.name, why)
                    announced = True
                    self._pause_changed(True)
                w.progress_at = now
            elif now - w.progress_at > self.stall_s:
                raise LinkTimeout(
                    f"{self._name()}: {what}: the plotter made no progress for {self.stall_s:g} s and is not paused "
                    f"(ESC.O answered {w.status})"
                )
            if paused or now - w.progress_at >= PAUSE_CHECK_S:
                self._ask_status_if_due(now)
            slice_s = PAUSE_CHECK_S / 2
            if interval is not None and not paused:
                if backoff and poll is not None and w.free_answers != answers:
                    interval = poll if w.mark != mark else min(2 * interval, MAX_POLL_S)
                    answers, mark = w.free_answers, w.mark
                if not self._asking("B") and not self._held():
                    due = w.last_free_ask + interval
                    if now >= due:
                        self._ask("B")
                    else:
                        slice_s = min(slice_s, due - now)
            self._pump(slice_s)

    def _held(self) -> bool:
        link = self.link
        return link is not None and link.held_off

    def _pump(self, wait: float = 0.0) -> int:
        """Act on every complete answer that arrived, waiting up to ``wait`` s for one; return how many."""
        link = self._require_link()
        w = self._wire
        deadline = self.clock.now() + wait
        handled = 0
        while True:
            remaining = 0.0 if handled else max(0.0, deadline - self.clock.now())
            data = link.read(4096, timeout=remaining)
            if not data:
                return handled
            w.rx += data
            while (end := w.rx.find(b"\r")) >= 0:
                if end > _MAX_REPLY:
                    raise LinkError(f"{self._name()}: answer longer than {_MAX_REPLY} bytes: {bytes(w.rx[:40])!r}...")
                line = bytes(w.rx[:end])
                del w.rx[: end + 1]
                self._on_answer(_clean(line))
                handled += 1
            if len(w.rx) > _MAX_REPLY:
                raise LinkError(f"{self._name()}: answer longer than {_MAX_REPLY} bytes: {bytes(w.rx[:40])!r}...")

    def _on_answer(self, text: str) -> None:
        """Match one answer line to the request it answers (see the module docstring)."""
        if not text:
            return
        w = self._wire
        w.received_any = True
        head = w.syncs[0] if w.syncs else None
        if head is not None and head.seen is not None:
            if not (_NUMBER.fullmatch(text) and 0 <= int(text) <= MAX_OE):
                raise LinkError(
                    f"{self._name()}: expected the OE answer after {head.marker}, got {text!r} "
                    "(the OE request was lost or garbled on the way)"
                )
            self._on_oe(head, int(text))
            return
        if head is not None and _is_marker(head.marker, text):
            head.seen = text
            if head.expect is not None:
                x, y, _ = (int(v) for v in text.split(","))
                if (x, y) != head.expect:
                    self._mark_damaged(range(head.first_stroke, head.confirms or head.first_stroke))
                    raise LinkError(
                        f"{self._name()}: OA found the pen at {x},{y} after {_strokes(head)}, not at "
                        f"{head.expect[0]},{head.expect[1]} where they end (an instruction was corrupted or lost)"
                    )
            return
        if _NUMBER.fullmatch(text) and w.queries:
            self._on_query_answer(w.queries.popleft(), int(text))
            return
        if w.connecting:  # answers to requests of an earlier connection, sent before our ESC.K
            log.debug("%s: stale answer %r before the connect handshake; ignored", self._name(), text)
            return
        expected = [f"{head.marker} answer" if head else None] + [f"ESC.{q.kind} answer" for q in list(w.queries)[:1]]
        raise LinkError(
            f"{self._name()}: unexpected answer {text!r} (expected {' or '.join(e for e in expected if e) or 'nothing'})"
        )

    def _on_oe(self, point: _SyncPoint, code: int) -> None:
        w = self._wire
        w.syncs.popleft()
        if code:
            strokes = "the setup instructions" if point.confirms is None else _strokes(point)
            if point.confirms is not None:
                self._mark_damaged(range(point.first_stroke, point.confirms))
            raise ProtocolError(
                f"HP-GL error {code} ({HPGL_ERRORS.get(code, 'unknown error')}) in {strokes}",
                code=code, command=self._culprit(point.instructions, code), device=self.profile.name,
            )
        w.progress_at = self.clock.now()
        w.status = 0
        if point.confirms is not None:
            self._confirm(point.confirms)

    def _on_query_answer(self, q: _Query, value: int) -> None:
        w = self._wire
        w.delivered = max(w.delivered, q.sent)
        if q.kind == "B":
            if not 0 <= value <= 1 << 20:
                raise LinkError(f"{self._name()}: ESC.B answered {value}, not a buffer size")
            mark = q.written + value
            if w.mark is None or mark > w.mark:
                w.progress_at = self.clock.now()
                w.status = 0
            w.mark = mark
            w.free = (value, q.written)
            w.free_answers += 1
            if w.size is not None:  # the plotter took every byte before mark - size from its buffer
                while w.ends and w.ends[0][0] + CONFIRM_MARGIN <= mark - w.size:
                    self._confirm(w.ends.popleft()[1])
        elif q.kind == "E":
            if value not in IO_ERRORS:
                raise LinkError(f"{self._name()}: ESC.E answered {value}, not an RS-232 error number")
            if value == ERROR_OUTPUT_BUSY:
                # one of our requests collided with an answer going out and was ignored: answers are out of step
                raise LinkError(f"{self._name()}: ESC.E answered {value} ({IO_ERRORS[value]}); a request was lost")
            if value and q.sync is None:
                log.warning("%s: the plotter held RS-232 error %d (%s) from before; cleared",
                            self.profile.name, value, IO_ERRORS[value])
            elif value and q.sync is not None:
                if q.sync.confirms is not None:
                    self._mark_damaged(range(q.sync.first_stroke, q.sync.confirms))
                raise ProtocolError(
                    f"RS-232 error {value} ({IO_ERRORS[value]}) while receiving {_strokes(q.sync)}",
                    code=value, command=_describe(q.sync.instructions), device=self.profile.name,
                )
        else:
            w.status = value

    def _check_overdue(self, now: float | None = None) -> None:
        w = self._wire
        now = self.clock.now() if now is None else now
        if w.queries and now > w.queries[0].deadline:
            q = w.queries[0]
            hint = "" if w.received_any else (
                f"; nothing was received since connecting: is the plotter on, cabled and set to {self.baudrate} 8N1?"
            )
            raise LinkTimeout(f"{self._name()}: no answer to ESC.{q.kind} in time{hint}")

    # -- helpers -----------------------------------------------------------------------------
    def _culprit(self, instructions: list[bytes], code: int) -> str:
        """The instruction an HP-GL error points at: one this model does not know (error 1), else all sent."""
        if code == 1:
            unknown = [i for i in instructions if i[:2].decode("ascii", "replace").upper() not in self.mnemonics]
            if len(unknown) == 1:
                return unknown[0].decode("ascii", "replace")
        return _describe(instructions)

    @staticmethod
    def _limit(link: Link, seconds: float) -> float | None:
        """A write timeout for ``link``: None where the link takes none (its ``write_timeout`` is None)."""
        return None if link.write_timeout is None else seconds

    def _require_link(self) -> Link:
        if self.link is None:
            raise LinkError(f"{self.profile.name}: not connected")
        return self.link

    def _name(self) -> str:
        return f"{self.profile.name} on {self.link.name if self.link else self.port}"


def _clean(line: bytes) -> str:
    return line.translate(None, _STRIP).decode("ascii", "replace").strip()


def _is_marker(marker: str, text: str) -> bool:
    if marker == "OA":
        return _OA.fullmatch(text) is not None
    return _IDENT.fullmatch(text) is not None and not _NUMBER.fullmatch(text)


def _strokes(point: _SyncPoint) -> str:
    """Which strokes a sync point covers, for messages."""
    last = (point.confirms or 0) - 1
    if last < point.first_stroke:
        return "the instructions after the last stroke"
    return f"stroke {last}" if last == point.first_stroke else f"strokes {point.first_stroke}..{last}"


def _describe(instructions: list[bytes], limit: int = 200) -> str:
    """Instructions as text for an error message, cut after ``limit`` characters."""
    text = b"".join(instructions).decode("ascii", "replace")
    return text if len(text) <= limit else f"{text[:limit]}... (+{len(text) - limit} characters)"


@register_display("hp7475a")
class HP7475A(HPGLDisplay):
    """HP 7475A six-pen A4/A3 plotter (0.02488 mm units)."""

    profile_name = "hp7475a"
    family = "hp7475a"
    ident = "7475A"
    mnemonics = HPGLDisplay.mnemonics | {"DC", "DP", "OD", "PS"}
    """PS included: chiplotle3's 7475A instruction list has it and the simulator takes it (not sent unless ps=true)."""


@register_display("hp7550a")
class HP7550A(HPGLDisplay):
    """HP 7550A eight-pen plotter with sheet feeder (0.025 mm units); takes PS."""

    profile_name = "hp7550a"
    family = "hp7550a"
    ident = "7550A"
    max_velocity_cm_s = 80.0
    knows_ps = True
    mnemonics = HPGLDisplay.mnemonics | {"DC", "DP", "OD", "OT", "PS", "FS"}


@register_display("hp7440a")
class HP7440A(HPGLDisplay):
    """HP 7440A ColorPro eight-pen A4 plotter."""

    profile_name = "hp7440a"
    family = "hp7440a"
    ident = "7440A"

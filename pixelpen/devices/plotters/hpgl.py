"""HP 7475A / 7550A / 7440A HP-GL pen plotters: URL schemes, flow control, confirmed plotting, device errors.

``hp7475a:PORT?options`` (likewise ``hp7550a``, ``hp7440a``) where PORT is a serial device
(``/dev/ttyUSB0``, ``COM3``), any pyserial URL (``[rfc2217://host:4000?logging=debug]`` in brackets
when it has a query), ``usb:VID:PID`` or ``usb:auto`` for a USB printer-class (USB-parallel)
adapter, or ``auto`` to find the plotter by asking every serial port ``IN;OI;``.  ``sim:hp7475a``
plots on the simulator through the same code.


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


Checkpoints (option ``verify``, default ``instruction``): every instruction of a stroke (SP, the PU travel,
each PD list) is followed by ``OA;OE;``.  HP-GL executes on after an erroneous instruction, so a garbled byte
costs one instruction at most, and its checkpoint tells what of it ran (a PD list stops at the pair before a
bad one, a Y that lost digits is drawn to first): only the missing piece is drawn again, nothing twice.  An
error whose OA shows the instruction ran whole (a garbled terminator) is logged and the plot goes on.  The
answers also prove how far the plotter got: after a power cut (the plotter restarts at home with the same
coordinates) a confirmed resume continues from the last acknowledged point; only the one instruction under
way at the cut may be partly drawn again, which the plotter cannot tell.  ``verify=sync`` checks only at sync
points (fewer bytes; a damaged stretch is drawn again whole).

Streaming, flow control (option ``handshake``), confirmation and the device's errors:
:mod:`~pixelpen.devices.plotters.hpgl_stream`.
"""

from __future__ import annotations

import logging
import math
import re
from typing import Any, ClassVar

import numpy as np

from pixelpen.devices.plotters import hpgl_encode as enc
from pixelpen.devices.plotters.base import DeviceWhere
from pixelpen.devices.plotters.hpgl_replies import (
    HPGL_ERRORS,
    IDENT_ANSWER,
    IO_ERRORS,
    MAX_OE,
    MAX_REPLY,
    NUMBER_ANSWER,
    OA_ANSWER,
    STATUS_PAPER_LEVER,
    STATUS_VIEW,
    clean,
    is_marker,
)
from pixelpen.devices.plotters.hpgl_stream import MAX_POLL_S, Check, HPGLStream, SyncPoint, Wire
from pixelpen.display.registry import register_display
from pixelpen.drivers import discovery
from pixelpen.drivers.serial import SerialLink
from pixelpen.drivers.stream import Link
from pixelpen.drivers.usbprinter import UsbPrinterLink
from pixelpen.errors import ConfigError, LinkError, LinkTimeout, URLError
from pixelpen.options import OptionSpec, OptionValues, boolean, choice, integer, positive
from pixelpen.profiles.model import DeviceProfile
from pixelpen.vector.displaylist import DisplayList

__all__ = ["HP7440A", "HP7475A", "HP7550A", "HPGL_ERRORS", "IO_ERRORS", "HPGLDisplay"]

log = logging.getLogger(__name__)

SETTLE_S = 2.0
"""Seconds ESC.B must stay unchanged, beyond one instruction's drawing time, before the plotter counts as settled."""
QUIET_S = 0.2
"""Seconds the answers of the settle queries are given to arrive before the position is asked."""
SAFE_WAIT_S = 10.0
"""Longest wait for the safe-stop sequence to be executed before closing."""
DISCOVERY_TIMEOUT_S = 0.5

VERIFY = ("instruction", "sync")
"""How closely the plot is checked (option ``verify``)."""

_FLOW_OF = {"escb": "none", "none": "none", "xonxoff": "xonxoff", "hardwire": "rtscts"}


class HPGLDisplay(HPGLStream):
    """An HP-GL plotter on RS-232, rfc2217:// or a USB printer-class adapter (see the module docstring)."""

    reports_position = True
    restarts_at_home = True  # power-up: pen at 0,0 and the same absolute coordinates (IN, default P1/P2)
    lifts_after_each_stroke = False  # PUx,y lifts and travels in one instruction; a bare PU; only at sync points
    rests_pen_down_at_start = False  # PD always comes with the vectors it draws
    ident: ClassVar[str] = ""
    """What the model answers to OI."""
    max_velocity_cm_s: ClassVar[float] = 38.1
    """Top pen speed (VS maximum); a profile asking for less gets ``VS``."""
    knows_ps: ClassVar[bool] = False
    """True when the model takes ``PS`` (paper size)."""
    mnemonics: ClassVar[frozenset[str]] = frozenset({
        "AA", "AR", "CA", "CI", "CP", "CS", "DF", "DI", "DR", "DT", "EA", "ER", "EW", "FT", "IM", "IN", "IP",
        "IW", "LB", "LT", "OA", "OC", "OE", "OF", "OH", "OI", "OO", "OP", "OS", "OW", "PA", "PD", "PR", "PT",
        "PU", "RA", "RO", "RR", "SA", "SC", "SI", "SL", "SM", "SP", "SR", "SS", "TL", "UC", "VS", "WG", "XT",
        "YT",
    })
    """HP-GL instructions the model knows (the HP-GL/1 set; an error 1 names a sent one outside it)."""
    OPTIONS = (
        *HPGLStream.OPTIONS,
        OptionSpec("handshake", choice(*enc.HANDSHAKES), "escb",
                   "flow control: escb (ESC.B polling), xonxoff, hardwire or none"),
        OptionSpec("reserve", integer(0), 128, "bytes kept free in the plotter's buffer with handshake=escb"),
        OptionSpec("sync_strokes", integer(1), 16, "strokes between two confirmations (OA/OE)"),
        OptionSpec("sync_bytes", integer(1), 512, "bytes between two confirmations (OA/OE)"),
        OptionSpec("velocity", positive, None,
                   "pen-down velocity in cm/s (VS); default the profile's, if below the model's top speed"),
        OptionSpec("ps", boolean, None,
                   "send PS (paper size) after IN: true or false; default true where the model knows PS"),
        OptionSpec("stall", positive, 60.0, "seconds without progress (and no pause) before a plot counts as stalled"),
        OptionSpec("verify", choice(*VERIFY), "instruction",
                   "instruction: OA;OE; after every instruction, so a garbled one costs only what it missed; "
                   "sync: only at sync points (fewer bytes; a damaged stretch is drawn again whole)"),
    )

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
        verify: str = "instruction",
        flow: str | None = None,
        usb_backend: Any = None,
        **kwargs: Any,
    ) -> None:
        if handshake not in enc.HANDSHAKES:
            raise ConfigError(f"handshake must be one of {', '.join(enc.HANDSHAKES)}, got {handshake!r}")
        wanted = _FLOW_OF[handshake]
        if flow is not None and handshake in ("xonxoff", "hardwire") and flow != wanted:
            raise ConfigError(f"handshake={handshake} needs flow={wanted}, got flow={flow}")
        if verify not in VERIFY:
            raise ConfigError(f"verify must be one of {', '.join(VERIFY)}, got {verify!r}")
        if reserve < 0 or sync_strokes < 1 or sync_bytes < 1 or not stall > 0:
            raise ConfigError("reserve must be >= 0, sync_strokes and sync_bytes >= 1 and stall > 0")
        super().__init__(port, flow=flow or wanted, **kwargs)
        self.handshake = handshake
        self.reserve = reserve
        self.sync_strokes = sync_strokes
        self.sync_bytes = sync_bytes
        self.stall_s = float(stall)
        self.verify = verify
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
        self._wire = Wire()

    @classmethod
    def family_options(cls, options: OptionValues, profile: DeviceProfile) -> dict[str, Any]:
        """Constructor keywords from the HP-GL options of a URL (see ``OPTIONS``)."""
        return {name: options[name] for name in ("handshake", "reserve", "sync_strokes", "sync_bytes", "velocity", "ps",
                                                 "stall", "verify")}

    @classmethod
    def simulator_options(
        cls, sim_options: dict[str, str], options: OptionValues, profile: DeviceProfile,
    ) -> dict[str, str]:
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
        self._wire = w = Wire(progress_at=self.clock.now(), connecting=True)
        link.reset_input()
        # ESC.K before the preamble's ';': half a number left in the buffer would be completed and executed
        self._write(enc.PLOTTER_ON + enc.ABORT_GRAPHICS + enc.handshake_preamble(self.handshake), graphics=False)
        paper_size = self.paper.set_ps if self.send_ps else None
        w.window = enc.initialize(paper_size, self.velocity_cm_s)
        point = SyncPoint(None, w.window, 0, marker="OI")
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
        if self.verify == "instruction":
            if w.pending_pen is not None:
                w.pending_pen.stroke, w.pending_pen = index, None
            self._send_checked(_checks(index, points, instructions))
        else:
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
        if self.verify == "instruction":
            self._wire.pending_pen = check = Check("SP", None)
            self._send_checked([(enc.select_pen(pen), check)])
        else:
            self._send([enc.select_pen(pen)])

    def _device_paused(self) -> bool:
        self._pump()
        if self._wire.status & (STATUS_VIEW | STATUS_PAPER_LEVER):
            self._ask_status_if_due(self.clock.now())
        return bool(self._wire.status & (STATUS_VIEW | STATUS_PAPER_LEVER))

    def _make_safe(self) -> None:
        """Drop host-queued bytes, ESC.K (buffered graphics), ``PU;SP0;`` and park; wait (bounded) until they ran."""
        link = self.link
        if link is None or link.closed:
            return
        try:
            link.reset_output()  # bytes still queued on the host would reach the plotter after the abort
            link.write(enc.ABORT_GRAPHICS, timeout=self._limit(link, self.timeout))
            self._wire = Wire(progress_at=self.clock.now())
            link.write(b"".join(enc.trailer(self.paper.park)) + b"OI;", timeout=self._limit(link, self.timeout))
            self.pen = None
            deadline = self.clock.now() + SAFE_WAIT_S
            while self.clock.now() < deadline:
                line = link.read_until(b"\r", timeout=deadline - self.clock.now(), max_size=MAX_REPLY)
                if is_marker("OI", clean(line)):
                    return
        except Exception as exc:  # noqa: BLE001  (leaving the plotter safe is best effort; say why it may not be)
            log.warning("%s: safe stop may be incomplete: %s", self.profile.name, exc)

    # -- after a fault: where the plotter stopped ---------------------------------------------
    def _where(self) -> DeviceWhere:
        """Let the plotter finish what the old connection left, drop a half instruction, ask OS and OA."""
        link = self._require_link()
        link.reset_input()
        pending = [p.check for p in self._wire.syncs if p.check is not None and p.check.kind != "SP"]
        self._wire = Wire(progress_at=self.clock.now(), connecting=True)
        self._write(enc.PLOTTER_ON, graphics=False)
        self._settle(SETTLE_S + self._instruction_time_s(), pending)
        link.read(4096, timeout=QUIET_S)  # answers still on their way (late ones of the settle queries)
        link.reset_input()
        self._write(enc.ABORT_GRAPHICS + enc.WHERE_REQUEST, graphics=False)
        status = None
        while not OA_ANSWER.fullmatch(text := self._answer(None, "OS;OA;")):
            status = text if NUMBER_ANSWER.fullmatch(text) else None  # OS answers just before OA; a late number first
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

    def _settle(self, hold_s: float, pending: list[Check]) -> None:
        """Ask ESC.B until its answer stays the same for ``hold_s`` s (waiting as long as VIEW or the lever holds).

        Late OA answers of the old connection's checkpoints (``pending``, in order) prove how far it drew.
        """
        last, since = None, self.clock.now()
        after_output = False
        while True:
            self._write(enc.ASK_FREE, graphics=False)
            while True:  # answers of the old connection's buffered requests may come first
                text = self._answer(None, "ESC.B")
                if OA_ANSWER.fullmatch(text):
                    after_output = True  # the OE answer follows it
                    self._late_checkpoint(pending, text)
                elif IDENT_ANSWER.fullmatch(text) and not NUMBER_ANSWER.fullmatch(text):
                    after_output = True  # an OI answer: the OE answer follows it
                elif after_output and int(text) <= MAX_OE:
                    after_output = False
                else:
                    break
            now = self.clock.now()
            if text != last:
                last, since = text, now
            elif now - since >= hold_s:
                self._write(enc.ASK_STATUS, graphics=False)
                if not int(self._answer(NUMBER_ANSWER, "ESC.O")) & (STATUS_VIEW | STATUS_PAPER_LEVER):
                    self._pause_changed(False)
                    return
                self._pause_changed(True)
                since = now
            self.clock.sleep(MAX_POLL_S)

    def _late_checkpoint(self, pending: list[Check], text: str) -> None:
        """An OA answer after a fault: the first pending checkpoint it fits ran (none earlier can be later)."""
        x, y, pen = (int(v) for v in text.split(","))
        for i, check in enumerate(pending):
            pts = check.points
            if pts is not None and check.stroke is not None and (x, y) == (int(pts[check.hi, 0]), int(
                    pts[check.hi, 1])) and bool(pen) == (check.kind == "PD"):
                self._acknowledged(check.stroke, check.hi)
                del pending[: i + 1]
                return

    def _answer(self, form: re.Pattern[str] | None, what: str) -> str:
        """The next non-empty answer line, which must match ``form`` (None: an OA, OI or number)."""
        link = self._require_link()
        while True:
            try:
                line = clean(link.read_until(b"\r", timeout=self.timeout, max_size=MAX_REPLY))
            except LinkTimeout:
                raise LinkTimeout(f"{self._name()}: no answer to {what}; is the plotter switched on?") from None
            if not line:
                continue
            if form is None:
                ok = OA_ANSWER.fullmatch(line) or NUMBER_ANSWER.fullmatch(line) or IDENT_ANSWER.fullmatch(line)
            else:
                ok = form.fullmatch(line)
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
        point = SyncPoint(None, list(instructions), w.strokes_sent)
        w.syncs.append(point)
        self._send([*instructions, enc.SYNC_REQUEST])
        self._wait(lambda: point not in w.syncs, "waiting for the plotter to move", poll=MAX_POLL_S)
        assert point.seen is not None
        return point.seen




def _checks(index: int, points: np.ndarray, instructions: list[bytes]) -> list[tuple[bytes, Check]]:
    """Each instruction of stroke ``index`` (``PUx,y;`` then PD lists) with what its checkpoint must find."""
    out = [(instructions[0], Check("PU", index, points))]
    k = 1
    for n, instruction in enumerate(instructions[1:], 2):
        pairs = (instruction.count(b",") + 1) // 2
        lo, hi = (0, 0) if len(points) == 1 else (k, k + pairs - 1)
        out.append((instruction, Check("PD", index, points, lo, hi, last=n == len(instructions))))
        k += pairs
    return out


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


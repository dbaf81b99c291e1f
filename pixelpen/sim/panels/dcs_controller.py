"""The MIPI-DCS command interpreter: bytes with D/CX in, controller state, frame memory and flagged misuse out.

One dispatch table (:mod:`dcs_commands`) maps a command byte to its parameter count and action. Any
command byte ends the previous command: missing parameters are flagged and the truncated command is
not carried out; parameters past the count are flagged and ignored. Chip select does not end a command
(RAMWR goes on across CS toggles until the next D/CX=0 byte), data with no command taking it is flagged,
a command sooner than the datasheet's wait after RESX, SWRESET, SLPIN or SLPOUT is flagged with the
measured gap (and carried out). Writes in sleep-in are legal (the memory works, ST7789VW SLPIN) and are
not flagged; the glass stays blank until SLPOUT and DISPON.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from pixelpen.sim.panels.dcs_commands import STREAM, Command, FrameTiming, Model
from pixelpen.sim.panels.dcs_glass import ScanOut
from pixelpen.sim.panels.dcs_memory import MV, FrameMemory
from pixelpen.sim.panels.dcs_pixels import FORMAT_18, decode, decode_tail

Flag = Callable[[int | None, str], None]
"""Report what the controller would flag: (the command byte it concerns, negative or None for none; message)."""

EDGE_EPSILON = 1e-9
"""TE edges closer than this (seconds) to the present count as past (no event loop on rounding)."""

_UNKNOWN = Command(-1, "unknown", 0, 0, "nop")
_NONE = Command(-1, "none", 0, 0, "nop")


class DcsController:
    """A controller's registers, modes and frame memory, driven byte by byte at clock times."""

    def __init__(self, model: Model, flag: Flag, count_frame: Callable[[], None], *,
                 ram: tuple[int, int] | None = None, seed: int = 0) -> None:
        self.model = model
        self._flag = flag
        self._count_frame = count_frame
        """Called when a RAMWR/WRMEMC reaches its window's last pixel, or ends early having written some."""
        cols, rows = ram if ram is not None else (model.cols, model.rows)
        self.memory = FrameMemory(cols, rows, seed=seed)
        """The frame memory (a module may strap a smaller one: ST7735 GM 011 is 128x160)."""
        self.hardware_reset(0.0)

    # ---- reset -------------------------------------------------------------------------------------
    def hardware_reset(self, t: float) -> None:
        """RESX: every register to its H/W reset value (MADCTL 0, 18-bit); the memory keeps its contents."""
        self.madctl_raw = 0
        self.pixel_format = FORMAT_18
        self._software_reset(t, self.model.waits.reset, "RESX")

    def _software_reset(self, t: float, wait: float, cause: str) -> None:
        self.registers: dict[int, bytes] = dict(self.model.reset_registers)
        self.sleeping = True
        self.display_on = False
        self.inverted = False
        self.idle = False
        self.partial = False
        self.partial_rows = (0, self.memory.rows - 1)
        self.scroll_area = (0, self.memory.rows, 0)
        self.scroll_start = 0
        self.scrolling = False
        self.tearing: int | None = None
        """TEON's TEM (0: V-blank only, 1: V and H blanking), None after TEOFF."""
        self.gamma = 1
        self._apply_madctl()
        self.memory.reset_window()
        self._command: Command = _NONE
        self._params = bytearray()
        self._complained = False
        self._carry = b""
        self._written = 0
        self._wrapped = False
        self._may_continue = False
        self._ready = (t, wait, cause)
        self._wait_flagged = False
        self._sleep_toggle = (t, cause)
        self._scan_start = t

    def settle(self) -> None:
        """Forget the waits still running: a panel powered long before the host program starts."""
        self._ready = (-math.inf, 0.0, "power-on")
        self._sleep_toggle = (-math.inf, "power-on")

    # ---- the bus side ------------------------------------------------------------------------------
    def command(self, code: int, t: float) -> None:
        """A D/CX=0 byte at time ``t``: ends the command in progress, then starts (or carries out) this one."""
        self._finish(t)
        command = self.model.commands.get(code)
        complained = command is None
        if command is None:
            self._flag(code, f"undefined command 0x{code:02X} (treated as NOP; its data too)")
            command = _UNKNOWN
        elif command.action != "nop":
            self._check_wait(command, t)
        self._command, self._params, self._complained = command, bytearray(), complained
        if command.action in ("ramwr", "wrmemc"):
            self._start_write(command)
        elif command.most == 0:
            self._run(command, b"", t)

    def data(self, data: bytes, t: float) -> None:
        """D/CX=1 bytes at time ``t``: parameters of the command in progress, or pixels after RAMWR/WRMEMC."""
        if not data:
            return
        command = self._command
        if command.most == STREAM:
            self._pixels(data)
        elif command.action == "read":
            return  # the host clocks the read's data phase; a write-only wiring reads zeros
        elif command.most == 0:
            self._complain(command, f"{len(data)} data byte(s) with no command taking parameters")
        else:
            room = command.most - len(self._params)
            self._params += data[:room]
            if len(data) > room:
                self._complain(command, f"{command.name} takes {command.most} parameter byte(s); "
                                        f"{len(data) - room} extra ignored")
            if room > 0 and len(self._params) == command.most:
                self._run(command, bytes(self._params), t)

    def _finish(self, t: float) -> None:
        """End the command in progress (the next command byte arrived)."""
        command = self._command
        if command.most == STREAM:
            self._end_write(command)
        elif command.least <= len(self._params) < command.most:
            self._run(command, bytes(self._params), t)
        elif len(self._params) < command.least:
            self._flag(command.code, f"{command.name} truncated: {len(self._params)} of {command.least} "
                                     "parameter byte(s) before the next command; not carried out")
        self._command = _NONE

    def _complain(self, command: Command, message: str) -> None:
        if not self._complained:
            self._complained = True
            self._flag(command.code, message)

    def _check_wait(self, command: Command, t: float) -> None:
        """Flag the first command inside a wait (the wait's later commands are the same mistake)."""
        since, wait, cause = self._ready
        if t - since < wait and not self._wait_flagged:
            self._wait_flagged = True
            self._too_soon(command, t - since, cause, wait)
        since, cause = self._sleep_toggle
        if command.action in ("slpin", "slpout") and t - since < self.model.waits.sleep_toggle:
            self._too_soon(command, t - since, cause, self.model.waits.sleep_toggle)

    def _too_soon(self, command: Command, gap: float, cause: str, wait: float) -> None:
        self._flag(command.code, f"{command.name} {gap * 1e3:.3f} ms after {cause} "
                                 f"(datasheet: wait {wait * 1e3:g} ms; carried out)")

    # ---- pixel writes -----------------------------------------------------------------------------
    def _start_write(self, command: Command) -> None:
        if command.action == "ramwr":
            self.memory.next_pixel = 0
        elif not self._may_continue:
            self._flag(command.code, "WRMEMC with no RAMWR since the window was set: writes continue "
                                     "from an undefined address (here: where the counter stands)")
        if self.memory.window_pixels() == 0:
            m = self.memory
            self._flag(command.code, f"{command.name} into an empty window (columns {m.xs}..{m.xe}, "
                                     f"rows {m.ys}..{m.ye}): start past end, nothing is written")
        elif self.memory.window_outside():
            across, down = self.memory.logical_size()
            m = self.memory
            self._flag(command.code, f"{command.name} window columns {m.xs}..{m.xe}, rows {m.ys}..{m.ye} "
                                     f"exceeds the memory's {across}x{down} (MV={int(bool(m.madctl & MV))}): "
                                     "pixels outside are ignored")
        self._carry = b""
        self._written = 0
        self._wrapped = False

    def _pixels(self, data: bytes) -> None:
        data = self._carry + data
        pixels, used = decode(self.pixel_format, data)
        self._carry = data[used:]
        self._store(pixels)

    def _store(self, pixels: np.ndarray) -> None:
        result = self.memory.write(pixels)
        self._written += len(pixels)
        if len(pixels) and self.memory.window_pixels() and self.memory.next_pixel == 0:  # last pixel in: a frame
            self._written = 0
            self._count_frame()
        if result.wrapped and not self._wrapped:
            self._wrapped = True
            self._flag(self._command.code, f"{self._command.name} ran past the window's "
                                           f"{self.memory.window_pixels()} pixels: wrapped to its start")

    def _end_write(self, command: Command) -> None:
        if self._carry:
            self._store(decode_tail(self.pixel_format, self._carry))
            self._flag(command.code, f"{command.name} ended inside a pixel: {len(self._carry)} byte(s) of a "
                                     f"{self.pixel_format.group_bytes}-byte {self.pixel_format.name} group")
            self._carry = b""
        if self._written:
            self._count_frame()
        self._may_continue = True

    # ---- carrying out commands --------------------------------------------------------------------
    def _run(self, command: Command, params: bytes, t: float) -> None:
        getattr(self, "_do_" + command.action)(command, params, t)

    def _do_nop(self, command: Command, params: bytes, t: float) -> None:
        pass

    def _do_read(self, command: Command, params: bytes, t: float) -> None:
        pass

    def _do_register(self, command: Command, params: bytes, t: float) -> None:
        self.registers[command.code] = params
        self._apply_madctl()  # LCMCTRL / interface control exchange MADCTL bits

    def _do_swreset(self, command: Command, params: bytes, t: float) -> None:
        self._software_reset(t, self.model.waits.swreset, "SWRESET")

    def _do_slpin(self, command: Command, params: bytes, t: float) -> None:
        self.sleeping = True
        self._ready, self._wait_flagged = (t, self.model.waits.slpin, "SLPIN"), False
        self._sleep_toggle = (t, "SLPIN")

    def _do_slpout(self, command: Command, params: bytes, t: float) -> None:
        if self.sleeping:
            self._scan_start = t
        self.sleeping = False
        self._ready, self._wait_flagged = (t, self.model.waits.slpout, "SLPOUT"), False
        self._sleep_toggle = (t, "SLPOUT")

    def _do_ptlon(self, command: Command, params: bytes, t: float) -> None:
        self.partial, self.scrolling = True, False

    def _do_noron(self, command: Command, params: bytes, t: float) -> None:
        self.partial, self.scrolling = False, False

    def _do_invoff(self, command: Command, params: bytes, t: float) -> None:
        self.inverted = False

    def _do_invon(self, command: Command, params: bytes, t: float) -> None:
        self.inverted = True

    def _do_gamset(self, command: Command, params: bytes, t: float) -> None:
        if params[0] in (1, 2, 4, 8):
            self.gamma = params[0]
        else:
            self._flag(command.code, f"GAMSET 0x{params[0]:02X} is not a curve (01h, 02h, 04h, 08h): ignored")

    def _do_dispoff(self, command: Command, params: bytes, t: float) -> None:
        self.display_on = False

    def _do_dispon(self, command: Command, params: bytes, t: float) -> None:
        self.display_on = True

    def _do_caset(self, command: Command, params: bytes, t: float) -> None:
        self.memory.xs, self.memory.xe = self._range(command, params)
        self._may_continue = False

    def _do_raset(self, command: Command, params: bytes, t: float) -> None:
        self.memory.ys, self.memory.ye = self._range(command, params)
        self._may_continue = False

    def _range(self, command: Command, params: bytes) -> tuple[int, int]:
        start, end = int.from_bytes(params[0:2], "big"), int.from_bytes(params[2:4], "big")
        if start > end:
            self._flag(command.code, f"{command.name} start {start} > end {end} (datasheet: start <= end)")
        return start, end

    def _do_ptlar(self, command: Command, params: bytes, t: float) -> None:
        self.partial_rows = (int.from_bytes(params[0:2], "big"), int.from_bytes(params[2:4], "big"))

    def _do_vscrdef(self, command: Command, params: bytes, t: float) -> None:
        tfa, vsa, bfa = (int.from_bytes(params[i:i + 2], "big") for i in (0, 2, 4))
        if tfa + vsa + bfa != self.memory.rows:
            self._flag(command.code, f"VSCRDEF TFA {tfa} + VSA {vsa} + BFA {bfa} != {self.memory.rows} "
                                     "(scrolling undefined; not scrolled)")
        self.scroll_area = (tfa, vsa, bfa)

    def _do_vscsad(self, command: Command, params: bytes, t: float) -> None:
        self.scroll_start = int.from_bytes(params[0:2], "big")
        self.scrolling = True

    def _do_teoff(self, command: Command, params: bytes, t: float) -> None:
        self.tearing = None

    def _do_teon(self, command: Command, params: bytes, t: float) -> None:
        self.tearing = params[0] & 1

    def _do_madctl(self, command: Command, params: bytes, t: float) -> None:
        self.madctl_raw = params[0]
        self._apply_madctl()

    def _do_idmoff(self, command: Command, params: bytes, t: float) -> None:
        self.idle = False

    def _do_idmon(self, command: Command, params: bytes, t: float) -> None:
        self.idle = True

    def _do_colmod(self, command: Command, params: bytes, t: float) -> None:
        fmt = self.model.formats.get(params[0] & 0x07)
        if fmt is None:
            self._flag(command.code, f"COLMOD 0x{params[0]:02X}: interface format {params[0] & 7:03b} is not "
                                     f"one of this serial interface's; kept {self.pixel_format.name}")
        else:
            self.pixel_format = fmt

    def _apply_madctl(self) -> None:
        bits, _ = self.model.madctl_xor(self.registers)
        self.memory.madctl = self.madctl_raw ^ bits

    # ---- what the glass and the TE pin show -------------------------------------------------------
    def scan_out(self, *, in_reset: bool) -> ScanOut:
        """The state the glass is drawn from."""
        _, invert = self.model.madctl_xor(self.registers)
        tfa, vsa, bfa = self.scroll_area
        scroll = None
        if self.scrolling and tfa + vsa + bfa == self.memory.rows and vsa > 0:
            scroll = (tfa, vsa, self.scroll_start)
        return ScanOut(
            showing=self.display_on and not self.sleeping and not in_reset,
            inverted=self.inverted != invert,
            bgr=bool(self.memory.madctl & 0x08),
            idle=self.idle,
            partial=self.partial_rows if self.partial else None,
            scroll=scroll,
        )

    def frame_timing(self) -> FrameTiming:
        """Seconds per refresh and of V-blank, from the frame-rate registers."""
        return self.model.frame_timing(self.registers)

    def tearing_line(self, t: float) -> bool:
        """TE output at ``t``: high during each frame's V-blank after TEON, low in sleep or after TEOFF."""
        if self.tearing is None or self.sleeping:
            return False
        timing = self.frame_timing()
        phase = (t - self._scan_start) % timing.period
        return phase >= timing.period - timing.blanking

    def next_tearing_edge(self, t: float) -> float | None:
        """When the TE output next changes after ``t`` (None while it stays low)."""
        if self.tearing is None or self.sleeping:
            return None
        timing = self.frame_timing()
        frame = math.floor((t - self._scan_start) / timing.period)
        for k in (frame, frame + 1, frame + 2):
            end = self._scan_start + (k + 1) * timing.period
            for edge in (end - timing.blanking, end):
                if edge > t + EDGE_EPSILON:
                    return edge
        return None  # pragma: no cover - two frames always hold an edge

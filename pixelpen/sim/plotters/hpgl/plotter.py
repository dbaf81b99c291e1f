"""HP 7475A / 7550A / 7440A pen plotter simulators: HP-GL and RS-232 device control, buffer, handshakes, time, paper.

This module ties the package together (``HPGLPlotter``, ``create``, the instruction table ``COMMANDS``):
``models`` (the models and papers), ``parsing`` (HP-GL and ``ESC .`` syntax), ``machine`` (pen,
coordinate systems, graphics state, motion planning), ``motion`` (move timing), ``instructions`` and
``labels`` (one method per instruction), ``output`` (replies, handshakes, device control, OA...OW) and
``drawing`` (the ink on the sheet).

Written from HP's manuals, not from pixelpen's drivers (see ``/work/shared/reference/plotters.md`` §1 and
the HP 7470A Interfacing and Programming Manual, whose RS-232 chapter the 7475A shares):

* bytes go into the plotter's input buffer of its real size; HP-GL executes from it in clock time
  (each X,Y pair, label character or shape as soon as it is read, so a buffer fills and drains as on
  the device); output instructions (``OS``, ``OA`` ...) are answered when execution reaches them;
* ``ESC .`` device-control sequences act the moment they arrive, anywhere in the stream, even with the
  buffer full: ``ESC.B`` free bytes, ``ESC.E`` RS-232 error (cleared on read), ``ESC.O`` extended
  status, hardwire / Xon-Xoff / ENQ-ACK handshakes set by ``ESC.@``, ``ESC.H``/``ESC.I``, ``ESC.M``, ``ESC.N``;
* bytes that arrive with the buffer full are lost and set ``ESC.E`` error 16, exactly like the device;
* the pen moves at the ``VS`` velocity with the manual's accelerations (2 g, 0.5 g after ``VS`` with a
  parameter; 7470A manual, VS), as a rest-to-rest trapezoid per vector on each axis;
* paper: every pen-down stroke in physical plotter units (y up) with its pen, rendered by ``paper_image``.

Figures not in the manuals are marked ``assumption`` where they are defined.  Readings of the manuals
that a test relies on:

* a pen-down move is limited to the ``VS`` velocity on each axis ("for horizontal or vertical pen-down
  moves"), so a diagonal is no slower than its longer side; pen-up moves run at the model's maximum;
* LT patterns run on from one vector into the next until the pen lifts; LT0 dots each vector's end;
* the IM e-mask (default 223) decides whether an error sets the OS error bit: error 6 (position
  overflow) does so only after ``IM`` enables it; OE reports every error and clears it;
* ``ESC.)`` (plotter off): everything but ``ESC.(``/``ESC.Y`` is ignored until the plotter is on again;
* ``reserve_bug``: the last byte that would fill the buffer to the ESC.B figure is lost (ESC.E 16);
* ``DT;`` restores ETX; label text executes one character at a time; ``DP`` digitizes at once where the
  pen stands (there is no operator); character sets 1-4 are accepted and drawn with the standard glyphs;
* 7550A instructions beyond HP-GL/1 (``PG``, ``EP``, ``FP`` ...) are read and logged, with no effect;
* a bare ``PD;`` lowers the pen where it stands and leaves a dot (merged into a line then drawn from it);
* the 7475A takes ``PS`` (chiplotle3's 7475A list; vpype's ``hp7475a`` files begin ``IN;DF;PS4;``); an
  instruction a model lacks is error 1 (OE, the OS error bit) and the plot goes on with the next one.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Final

import numpy as np

from pixelpen.clock import Clock
from pixelpen.colour import colour_hex, parse_colour
from pixelpen.errors import ConfigError, PixelpenError, URLError
from pixelpen.options import OptionSpec, boolean, integer, read_options
from pixelpen.sim.base import Fault, SimulatedDevice, register_simulator
from pixelpen.sim.plotters.hpgl.drawing import Drawing
from pixelpen.sim.plotters.hpgl.instructions import GRAPHICS, MAX_FILL_LINES, GraphicsInstructions
from pixelpen.sim.plotters.hpgl.labels import LABELS, LabelInstructions
from pixelpen.sim.plotters.hpgl.machine import DEFAULT_E_MASK, LINE_PATTERNS, MAX_DASHES_PER_VECTOR, Machine, Status
from pixelpen.sim.plotters.hpgl.models import DEFAULT_PEN_COLOURS, G_CM_S2, MODELS, PAPER_ALIASES, ModelSpec, PaperSpec
from pixelpen.sim.plotters.hpgl.motion import Motion, axis_distance, axis_time
from pixelpen.sim.plotters.hpgl.output import (
    DEVICE_CONTROL_ERRORS,
    INTERFACE_CONTROL,
    OUTPUTS,
    Interface,
    OutputInstructions,
)
from pixelpen.sim.plotters.hpgl.params import COORD_LIMIT, PARSE_ERRORS, Command, CommandTable, HPGLError
from pixelpen.sim.plotters.hpgl.parsing import ESC, DeviceControl, DeviceControlReader, Instruction, InstructionReader
from pixelpen.sim.plotters.sheet import WireStats
from pixelpen.vector.displaylist import DisplayList

if TYPE_CHECKING:
    from pixelpen.raster.canvas import Canvas

__all__ = [
    "COMMANDS", "COORD_LIMIT", "DEFAULT_E_MASK", "DEFAULT_PEN_COLOURS", "G_CM_S2", "LINE_PATTERNS",
    "MAX_DASHES_PER_VECTOR", "MAX_FILL_LINES", "MODELS", "OPTIONS", "PAPER_ALIASES",
    "HPGLPlotter", "ModelSpec", "PaperSpec", "PlotterStats", "axis_distance", "axis_time", "create", "option_specs",
]

log = logging.getLogger(__name__)

COMMANDS: Final[Mapping[str, Command[Any]]] = {**GRAPHICS, **LABELS, **OUTPUTS}
"""The whole HP-GL instruction table: mnemonic -> (parameter counts, handler method of its instruction class)."""


@dataclass
class PlotterStats(WireStats):
    """Counters the benchmarks read: the shared wire counters and the HP-GL plotter's own."""

    bytes_overflowed: int = 0
    bytes_ignored: int = 0
    """Bytes dropped unread: plotter programmed off, waiting for the echo terminator, or powered down."""
    hpgl_errors: int = 0
    io_errors: int = 0


class HPGLPlotter(SimulatedDevice):
    """A simulated HP-GL pen plotter speaking RS-232 (a :class:`~pixelpen.sim.base.StreamDevice`).

    Create one with :func:`create` or through ``create_simulator("hp7475a", paper="a3")``.  Besides
    the StreamDevice methods it offers the operator's controls (``press_view``, ``release_paper_lever``),
    the paper (``segments``, ``display_list``, ``paper_image``, ``save_paper``), the executed-command
    log and the error log, and ``stats``.  Instructions run through ``COMMANDS``: the plotter checks
    the parameter count and calls the handler on the instruction class that owns what it changes.
    """

    FAULTS: ClassVar[frozenset[Fault]] = frozenset(
        {Fault.POWER_LOSS, Fault.RESET, Fault.PAPER_LEVER, Fault.PAUSE_BUTTON}
    )

    def __init__(
        self,
        spec: ModelSpec,
        *,
        paper: str | None = None,
        pen_colours: tuple[str, ...] | None = None,
        buffer: int | None = None,
        reserve_bug: bool | None = None,
        clock: Clock | None = None,
    ) -> None:
        super().__init__(clock)
        self.spec = spec
        self.model = spec.name
        if (paper or spec.default_paper) not in spec.papers:
            raise ConfigError(f"{spec.name}: no paper {paper!r}; this model takes {', '.join(spec.papers)}")
        colours = tuple(pen_colours) if pen_colours is not None else DEFAULT_PEN_COLOURS[: spec.pens]
        self.pen_colours: dict[int, str] = {i + 1: c for i, c in enumerate(colours)}
        self.buffer_size = int(buffer if buffer is not None else spec.buffer)
        self.reserve_bug = spec.name == "hp7475a" if reserve_bug is None else bool(reserve_bug)
        self.stats = PlotterStats()
        self.command_log: list[tuple[float, str]] = []
        """(time, command text) of every instruction executed, in order."""
        self.error_log: list[tuple[float, str, int, str]] = []
        """(time, "HP-GL" or "RS-232", error number, command) of every error the plotter raised."""
        self._drawing = Drawing(spec.unit_mm, self.pen_colours)
        self._machine = Machine(spec, spec.papers[paper or spec.default_paper])
        self._status = Status()
        self._reader = InstructionReader(spec.mnemonics, spec.recognised)
        self._esc = DeviceControlReader()
        self._buf = bytearray()
        self._interface = Interface(spec.name, lambda: self._now, lambda: self.free_bytes, self._io_fault)
        labels = LabelInstructions(spec, self._machine, self._reader)
        graphics = GraphicsInstructions(spec, self._machine, self._status, self._reader, labels, self.pen_colours)
        outputs = OutputInstructions(spec, self._machine, self._status, self._interface, self.pen_colours)
        self._commands = {**_bind(graphics, GRAPHICS), **_bind(labels, LABELS), **_bind(outputs, OUTPUTS)}
        self._power_up()

    # -- power -----------------------------------------------------------------------------------

    def _power_up(self) -> None:
        """Everything as after switching on (the paper stays)."""
        self._dead = False
        self._on = True
        self._buf.clear()
        self._reader.reset()
        self._reader.offset = 0
        self._esc = DeviceControlReader()
        self._interface.power_up()
        self._active: Motion | None = None
        self._active_start = self._now
        self._idle_since: float | None = None
        self._executed_any = False
        self._status.power_up()
        self._machine.power_up()

    def _power_loss(self) -> None:
        """Power fails: the move under way is inked as far as it got, then everything is lost until reset."""
        if self._active is not None:
            partial_ink = self._active.drawn_until(self._now - self._active_start)
            if partial_ink is not None and self._active.pen in self.pen_colours:
                self._drawing.ink(partial_ink, self._active.pen, self._active.width_mm)
        log.warning(
            "%s: power lost at t=%.3f: %d buffered byte(s) and %d queued move(s) lost",
            self.model, self._now, len(self._buf), len(self._machine.motions) + (self._active is not None),
        )
        self._power_up()
        self._dead = True

    # -- SimulatedDevice -------------------------------------------------------------------------

    def _receive(self, data: bytes) -> None:
        """Host bytes at the current device time (see the module docstring for what happens to them)."""
        if self._dead:
            self._ignore(data)
            return
        self.stats.bytes_received += len(data)
        port = self._interface
        i = 0
        while i < len(data):
            if port.await_echo:
                j = data.find(bytes([port.link.echo]), i)
                end = len(data) if j < 0 else j + 1
                self.stats.bytes_ignored += end - i
                port.await_echo = j < 0
                i = end
                continue
            if self._esc.active:
                seq, reprocess = self._esc.feed(data[i])
                if not reprocess:
                    i += 1
                if seq is not None:
                    self._device_control(seq)
                continue
            if not self._on:
                j = data.find(b"\x1b", i)
                end = len(data) if j < 0 else j
                self.stats.bytes_ignored += end - i
                if j >= 0:
                    self._esc.start()
                    end += 1
                i = end
                continue
            m = port.specials.search(data, i)
            j = len(data) if m is None else m.start()
            if j > i:
                self._store(data[i:j])
            i = j
            if m is not None:
                if data[j] == ESC:
                    self._esc.start()
                else:
                    port.special(data[j])
                i += 1
        self.advance_to(self._now)

    def _ignore(self, data: bytes) -> None:
        """Bytes that arrive while the plotter is closed or powered down: counted, dropped."""
        self.stats.bytes_ignored += len(data)
        if data:
            state = "closed" if self._closed else "powered down"
            log.debug("%s: %d byte(s) arrived while %s; ignored", self.model, len(data), state)

    def take_output(self) -> bytes:
        """Bytes the plotter has sent by now (replies wait for their delays and the output trigger)."""
        self._emit(self._interface.take())
        return super().take_output()

    @property
    def ready_to_receive(self) -> bool:
        """DTR as the plotter drives it: with hardwire handshake (ESC.@ bit 0) high while free >= block size."""
        if self._closed or self._dead:
            return False
        if not self._interface.link.hardwire:
            return True
        return self.free_bytes >= self._interface.link.block

    def _next_internal_event(self) -> float | None:
        """When a move ends or a delayed reply goes out (None while powered down or idle)."""
        if self._dead:
            return None
        times = []
        if self._active is not None:
            times.append(self._active_start + self._active.duration)
        ready = self._interface.next_ready()
        if ready is not None:
            times.append(ready)
        return min(times) if times else None

    def _service(self) -> None:
        """Start the next motion when the mechanism is free, executing buffered instructions to get one."""
        if self._active is not None or self.paused or self._dead:
            return
        motions = self._machine.motions
        if not motions:
            self._fetch()
        if motions:
            self._active = motions.popleft()
            self._active_start = self._now

    def _handle_event(self, t: float) -> None:
        """Time ``t``: the motion under way ends now, or a delayed reply falls due."""
        self._now = t
        motion = self._active
        if motion is not None and self._active_start + motion.duration <= t:
            self._active = None
            self.stats.moving_time += motion.duration
            if motion.draw is not None and motion.pen in self.pen_colours:  # an empty stall plots dry
                self._drawing.ink(motion.draw, motion.pen, motion.width_mm)

    def _apply_fault(self, fault: Fault) -> None:
        """Power loss, reset (power-up), the paper lever raised, or the VIEW button."""
        if fault is Fault.POWER_LOSS:
            self._power_loss()
        elif fault is Fault.RESET:
            log.info("%s: reset (power-up) at t=%.3f", self.model, self._now)
            self._power_up()
        elif fault is Fault.PAPER_LEVER:
            log.info("%s: paper lever raised at t=%.3f: plotting suspended", self.model, self._now)
            self._status.lever = True
        else:
            self.press_view()

    # -- operator controls -----------------------------------------------------------------------

    def press_view(self) -> None:
        """Press the VIEW button: suspends plotting (ESC.O 16) or, pressed again, resumes it."""
        status = self._status
        status.view = not status.view
        log.info("%s: VIEW %s at t=%.3f", self.model, "pressed: plotting suspended" if status.view else "released",
                 self._now)
        if not status.view:
            self.advance_to(self._now)

    def release_paper_lever(self) -> None:
        """Lower the paper lever again: plotting resumes where it stopped."""
        if self._status.lever:
            self._status.lever = False
            log.info("%s: paper lever lowered at t=%.3f: plotting resumes", self.model, self._now)
            self.advance_to(self._now)

    # -- introspection ---------------------------------------------------------------------------

    @property
    def free_bytes(self) -> int:
        """Free buffer space as ESC.B reports it."""
        return self.buffer_size - len(self._buf)

    @property
    def buffered_bytes(self) -> int:
        """Bytes waiting in the input buffer."""
        return len(self._buf)

    @property
    def now(self) -> float:
        """The device time the plotter has run to."""
        return self._now

    @property
    def paused(self) -> bool:
        """True while VIEW or the raised paper lever holds plotting."""
        return self._status.view or self._status.lever

    @property
    def pen_down(self) -> bool:
        """The commanded pen state (PD/PU), as OS and OA report it."""
        return self._machine.pen_down

    @property
    def lever_raised(self) -> bool:
        """True while the paper lever is up."""
        return self._status.lever

    @property
    def paper(self) -> PaperSpec:
        """The paper loaded (PS changes it)."""
        return self._machine.paper

    @property
    def pen_position(self) -> tuple[float, float]:
        """Where the pen physically is (physical plotter units, after the moves planned so far)."""
        return self._machine.phys

    @property
    def selected_pen(self) -> int:
        """The pen in the holder (0: none)."""
        return self._machine.pen

    @property
    def hard_clip(self) -> tuple[int, int]:
        """Upper-right hard-clip corner in the current coordinate system (OH's last two numbers)."""
        return self._machine.logical_limits()

    def segments(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every pen-down stroke so far: (N, 4) x0, y0, x1, y1 in physical plotter units, pens (N,), widths mm (N,)."""
        return self._drawing.segments()

    def display_list(self) -> DisplayList:
        """The paper as a DisplayList: touching same-pen segments joined into polylines, in plotter units."""
        return self._drawing.display_list()

    def paper_image(self, dpi: float = 100.0) -> Canvas:
        """Render the sheet at ``dpi``: white page of the paper size, every stroke in its pen's colour and width."""
        return self._drawing.paper_image(self._machine.paper, self._machine.hard_clip, dpi)

    def save_paper(self, path: str | Path, dpi: float = 100.0) -> None:
        """Write the sheet to ``path``: a PNG (``paper_image`` at ``dpi``) or a true-size SVG, by the extension."""
        self._drawing.save_paper(path, self._machine.paper, self._machine.hard_clip, dpi)

    # -- the buffer and the parser ---------------------------------------------------------------

    def _store(self, chunk: bytes) -> None:
        """Put HP-GL bytes into the buffer; zero-time instructions run meanwhile; the rest of a full buffer is lost."""
        limit = self.buffer_size - (1 if self.reserve_bug else 0)
        while chunk:
            room = limit - len(self._buf)
            if room > 0:
                self._buf += chunk[:room]
                chunk = chunk[room:]
                self._interface.flow_check()
            before = len(self._buf)
            self.advance_to(self._now)
            if chunk and len(self._buf) < before:
                continue
            if chunk:
                self._interface.io_fault(16, f"buffer overflow: {len(chunk)} byte(s) lost")
                self.stats.bytes_overflowed += len(chunk)
                return

    def _fetch(self) -> None:
        """Read and execute instructions from the buffer until one produces motion or the buffer runs dry."""
        motions = self._machine.motions
        while not motions and self._buf:
            n, item = self._reader.read(self._buf)
            if n == 0 and item is None:
                if len(self._buf) < self.buffer_size - (1 if self.reserve_bug else 0):
                    break
                n, item = self._reader.read(self._buf, full=True)
            del self._buf[:n]
            if item is not None:
                if self._idle_since is not None and self._executed_any:
                    self.stats.starved_time += self._now - self._idle_since
                self._idle_since = None
                self._executed_any = True
                self._execute(item)
            self._interface.flow_check()
        if not motions and self._idle_since is None:
            self._idle_since = self._now

    def _execute(self, item: Instruction) -> None:
        """Run one instruction through the command table (errors as the plotter reports them)."""
        self.stats.commands_executed += 1
        self.command_log.append((self._now, str(item)))
        if item.error:
            self._hpgl_fault(item.error, item, PARSE_ERRORS[item.error])
            return
        entry = self._commands.get(item.mnemonic)
        if entry is None:
            log.warning("%s: %s is not simulated (the %s knows it); no effect", self.model, item, self.spec.ident)
            return
        command, handler = entry
        try:
            command.check(item)
            handler(item)
        except HPGLError as exc:
            self._hpgl_fault(exc.code, item, exc.message)
        except (PixelpenError, ValueError, ArithmeticError) as exc:
            self._hpgl_fault(3, item, f"cannot be executed: {exc}")

    def _hpgl_fault(self, code: int, item: Instruction, message: str) -> None:
        """An HP-GL error: the status (OE, the OS error bit by the e-mask), the log and the counters."""
        self._status.fault(code)
        self.stats.hpgl_errors += 1
        self.error_log.append((self._now, "HP-GL", code, str(item)))
        log.warning("%s: HP-GL error %d at byte %d (%s): %s", self.model, code, item.offset, item, message)

    def _io_fault(self, code: int, message: str) -> None:
        """An RS-232 error, as the interface reports it: logged and counted."""
        self.stats.io_errors += 1
        self.error_log.append((self._now, "RS-232", code, message))
        log.warning("%s: RS-232 error %d at t=%.3f: %s", self.model, code, self._now, message)

    # -- device control --------------------------------------------------------------------------

    def _device_control(self, seq: DeviceControl) -> None:
        """Act on an ``ESC .`` sequence the moment it is complete (only ESC.( and ESC.Y while programmed off)."""
        if seq.error:
            self._interface.io_fault(seq.error, f"{seq}: {DEVICE_CONTROL_ERRORS[seq.error]}")
            if seq.error == 11:
                return
        letter = seq.letter
        if not self._on and letter not in "(Y":
            return
        self.command_log.append((self._now, str(seq)))
        own = _PLOTTER_CONTROL.get(letter)
        if own is not None:
            own(self, seq)
        else:
            INTERFACE_CONTROL[letter](self._interface, seq)

    def _esc_on(self, seq: DeviceControl) -> None:
        """ESC.( and ESC.Y: plotter on."""
        self._on = True

    def _esc_off(self, seq: DeviceControl) -> None:
        """ESC.) and ESC.Z: plotter off (everything but ESC.( and ESC.Y is ignored)."""
        self._on = False

    def _esc_b(self, seq: DeviceControl) -> None:
        """ESC.B: free buffer bytes."""
        self._interface.reply(str(self.free_bytes), str(seq))

    def _esc_l(self, seq: DeviceControl) -> None:
        """ESC.L: the buffer size."""
        self._interface.reply(str(self.buffer_size), str(seq))

    def _esc_o(self, seq: DeviceControl) -> None:
        """ESC.O: extended status (8 buffer empty, 16 VIEW, 32 paper lever raised)."""
        status = (8 if not self._buf else 0) + (32 if self._status.lever else 16 if self._status.view else 0)
        self._interface.reply(str(status), str(seq))

    def _esc_k(self, seq: DeviceControl) -> None:
        """ESC.K: abort graphics: the buffer and the planned moves are discarded (the label terminator stays)."""
        dropped = len(self._buf)
        self._buf.clear()
        terminator = self._reader.label_terminator
        self._reader.reset()
        self._reader.label_terminator = terminator
        self._machine.motions.clear()
        log.info("%s: ESC.K: graphics aborted, %d buffered byte(s) discarded", self.model, dropped)
        self._interface.flow_check()


_PLOTTER_CONTROL: Final[dict[str, Callable[[HPGLPlotter, DeviceControl], None]]] = {
    "(": HPGLPlotter._esc_on, "Y": HPGLPlotter._esc_on, ")": HPGLPlotter._esc_off, "Z": HPGLPlotter._esc_off,
    "B": HPGLPlotter._esc_b, "L": HPGLPlotter._esc_l, "O": HPGLPlotter._esc_o, "K": HPGLPlotter._esc_k,
}
"""Device-control letter -> handler for the sequences about the buffer and the plotter (the rest: the interface's)."""


def _bind(owner: Any, table: CommandTable[Any]) -> dict[str, tuple[Command[Any], Callable[[Instruction], None]]]:
    """A table's handlers bound to the instruction-class instance that owns them."""
    return {mnemonic: (command, partial(command.handler, owner)) for mnemonic, command in table.items()}


# -- construction from URL options ---------------------------------------------------------------------


def _paper_reader(spec: ModelSpec) -> Callable[[str], str]:
    """The ``paper`` option's converter for one model (names and aliases it takes)."""
    def convert(value: str) -> str:
        name = value.strip().lower()
        name = PAPER_ALIASES.get(name, name)
        if name not in spec.papers:
            raise ValueError(f"this model takes {', '.join(spec.papers)}")
        return name

    return convert


def _pens_reader(stalls: int) -> Callable[[str], tuple[str, ...]]:
    """The ``pens`` option's converter for a carousel of ``stalls``."""
    def convert(value: str) -> tuple[str, ...]:
        names = [v.strip() for v in value.split(",")]
        if not value.strip() or any(not n for n in names):
            raise ValueError("expected comma-separated colours such as 'black,#ff0000,blue'")
        if len(names) > stalls:
            raise ValueError(f"{len(names)} colours for a {stalls}-pen carousel")
        return tuple(colour_hex(parse_colour(n)) for n in names)

    return convert


def option_specs(spec: ModelSpec) -> tuple[OptionSpec[Any], ...]:
    """The URL options of one model's simulator, with that model's defaults."""
    return (
        OptionSpec("paper", _paper_reader(spec), spec.default_paper,
                   f"paper loaded: {', '.join(spec.papers)} (a = letter, b = tabloid)"),
        OptionSpec("pens", _pens_reader(spec.pens), DEFAULT_PEN_COLOURS[: spec.pens],
                   f"comma-separated colours, one per loaded stall (up to {spec.pens})"),
        OptionSpec("buffer", integer(16, 1 << 20), spec.buffer, "input buffer size in bytes"),
        OptionSpec("reserve_bug", boolean, spec.name == "hp7475a",
                   "the 7475A's overflow when the buffer is filled to the exact ESC.B figure"),
    )


OPTIONS: Final[dict[str, tuple[OptionSpec[Any], ...]]] = {name: option_specs(spec) for name, spec in MODELS.items()}
"""Model -> the specs of its ``sim:`` URL options (``pixelpen devices`` prints them)."""


def create(model: str, /, *, clock: Clock | None = None, **options: str) -> HPGLPlotter:
    """Build the simulator of ``model`` (a key of MODELS) from URL options given as strings (see ``OPTIONS``)."""
    spec = MODELS.get(model.lower())
    if spec is None:
        raise URLError(f"no HP-GL simulator for model {model!r}; known: {', '.join(MODELS)}")
    values = read_options(OPTIONS[spec.name], options, f"sim:{spec.name}")
    return HPGLPlotter(spec, clock=clock, paper=values["paper"], pen_colours=values["pens"], buffer=values["buffer"],
                       reserve_bug=values["reserve_bug"])


def _factory(model: str) -> Callable[..., HPGLPlotter]:
    """The registered factory of ``model``."""
    return partial(create, model)


for _name in MODELS:
    register_simulator(_name, _factory(_name), OPTIONS[_name])

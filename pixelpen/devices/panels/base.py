"""PanelDisplay: a raster display on a panel controller behind a bus: init, partial refresh, pacing, safe close.

A frame is the canvas's damage trimmed to the pixels that differ from what the panel last received (a
shadow copy of the sent frame in the wire's units, ``packing``: RGB565 values on an RGB565 panel, converted only
inside the damage, compared by ``trim.trim_damage``), whose cut is sent as it is (at most ``windows.MAX_WINDOWS``
windows, or their bounding window when that costs fewer bytes; more are planned by
``windows.plan_windows``), each window as the controller's window commands (MIPI: CASET or RASET left out
when the window before it in the frame set the same columns or rows) and its pixels packed natively.  The
next frame is full after open, ``reset()``, a rotation change, a bus fault or an interruption (Ctrl-C) in
the middle of a frame.  A frame that is the last one shifted vertically is scrolled by the controller
(``scrolling.HardwareScroll``: MIPI VSCRDEF/VSCSAD, SSD1306 the display start line), then only its new rows
are sent.  ``fps=`` (or
``refresh(target_fps)``) paces frames with a FramePacer: drawing between due frames only accumulates damage, so
frames coalesce, never queue.
"""

from __future__ import annotations

import contextlib
import logging
import time
from abc import abstractmethod
from collections.abc import Callable, Iterator
from dataclasses import fields
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from pixelpen.clock import REAL_CLOCK, Clock, SimulatedClock
from pixelpen.devices.panels.frames import FrameStats, PanelStats
from pixelpen.devices.panels.packing import keep_windows, pack_windows, to_units, update_units
from pixelpen.devices.panels.scrolling import HardwareScroll
from pixelpen.devices.panels.trim import trim_damage
from pixelpen.devices.panels.windows import MAX_WINDOWS, WindowCost, window_cost
from pixelpen.devices.panels.wiring import Interface, Pins, Wiring, open_wiring, parse_target, sim_wiring
from pixelpen.display.base import Deferral
from pixelpen.display.capabilities import Capabilities, ColourModel
from pixelpen.display.kinds import RasterDisplay
from pixelpen.drivers.bus import PanelBus
from pixelpen.errors import ConfigError, InvalidArgument, LinkError, URLError
from pixelpen.options import OptionSpec, OptionValues, boolean, choice, integer, pixels, positive, text
from pixelpen.profiles.panel import InitStep, PanelProfile, load_panel_profile, panel_profile_for
from pixelpen.raster.canvas import Canvas
from pixelpen.raster.damage import Rect
from pixelpen.sim.base import BusDevice, create_simulator
from pixelpen.sim.base import simulator_options as simulator_specs
from pixelpen.urls import DeviceURL

if TYPE_CHECKING:
    from pixelpen.devices.panels.pacing import FramePacer
    from pixelpen.drivers.bustrace import BusTrace

log = logging.getLogger(__name__)

TE_TIMEOUT = 0.05
"""Seconds to wait for the tearing-effect pulse before sending anyway (three frames at 60 Hz)."""
PIXEL_PITCH_MM = 0.2
"""Millimetres per pixel when a profile says nothing (the world window of ``Display`` is in millimetres)."""


def rotation_degrees(value: str) -> int:
    """0, 90, 180 or 270."""
    return int(choice("0", "90", "180", "270")(value))


class PanelDisplay(RasterDisplay):
    """A panel module (profile) on a bus: a subclass gives the controller's init, window and scan-out commands."""

    simulated: ClassVar[bool] = True
    controller: ClassVar[str] = ""
    """The profile controller (and simulator model) of the class."""
    default_size: ClassVar[tuple[int, int]] = (0, 0)
    """The module a URL without ``size`` or ``profile`` gets."""
    interfaces: ClassVar[tuple[Interface, ...]] = ("spi",)
    """Buses the controller is driven over (the first is a ``sim:`` URL's unless it sets ``dc``)."""
    canvas_mode: ClassVar[str] = "RGB"
    display_on: ClassVar[int] = 0x29
    """The init table's display-on command: sent after the first full frame, so nothing stale flashes."""
    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("size", pixels, None, "module size WxH at rotation 0 (picks the built-in profile)"),
        OptionSpec("profile", text, None, "a built-in panel profile name or a panel profile TOML file"),
        OptionSpec("rotation", rotation_degrees, 0, "0, 90, 180 or 270 degrees clockwise on the glass"),
        OptionSpec("hz", positive, None, "bus clock in Hz; default the profile's for the bus"),
        OptionSpec("dc", integer(0), None, "D/C line: GPIO offset on gpiochip (FT232H: ADBUS pin)"),
        OptionSpec("rst", integer(0), None,
                   "reset line (active low): GPIO offset; without it only the init table resets (MIPI: SWRESET)"),
        OptionSpec("bl", integer(0), None, "backlight line: GPIO offset (on while open)"),
        OptionSpec("te", integer(0), None, "tearing-effect input line: GPIO offset; frames start at its pulse"),
        OptionSpec("gpiochip", text, "/dev/gpiochip0", "GPIO character device of dc, rst, bl and te"),
        OptionSpec("fps", positive, None, "target frames per second: frames coalesce; refused above the bus limit"),
        OptionSpec("invert", boolean, None, "invert the colours; default the profile's"),
        OptionSpec("persist", boolean, True, "leave the picture on the glass at close (false: display off)"),
        OptionSpec("refresh", choice("partial", "full"), "partial", "send only what changed, or every frame whole"),
    )

    def __init__(
        self,
        wiring: Wiring | Callable[[], Wiring],
        *,
        profile: PanelProfile,
        rotation: int = 0,
        fps: float | None = None,
        invert: bool | None = None,
        persist: bool = True,
        refresh: str = "partial",
        clock: Clock = REAL_CLOCK,
        background: object = "black",
        deferral: Deferral = "asap",
        simulator: BusDevice | None = None,
    ) -> None:
        if profile.controller not in self.compatible_controllers():
            raise ConfigError(f"{type(self).__name__} drives {', '.join(self.compatible_controllers())}, "
                              f"not the {profile.controller} of profile {profile.name}")
        if refresh not in ("partial", "full"):
            raise ConfigError(f"refresh must be 'partial' or 'full', got {refresh!r}")
        self.profile = profile
        self.rotation = self._check_rotation(rotation)
        self.persist = persist
        self.refresh_mode = refresh
        self.invert = profile.invert if invert is None else invert
        self.clock, self.target_fps = clock, fps
        self.stats = PanelStats()
        self._wiring_source = wiring
        self._wiring: Wiring | None = wiring if isinstance(wiring, Wiring) else None
        self._simulator = simulator if simulator is not None or not isinstance(wiring, Wiring) else wiring.simulator
        self._shadow: np.ndarray | None = None
        self._units: np.ndarray | None = None
        """The frame in the shadow's units when they are a conversion (``packing.to_units``), kept between frames;
        None when the native frame is its own units."""
        self._full = True
        self._pacer: FramePacer | None = None
        self._force = False
        self._frame = FrameStats()
        self._cost: WindowCost | None = None
        self._scroll = HardwareScroll(self._send_step)
        super().__init__(self._capabilities(), mode=self.canvas_mode, background=background, deferral=deferral)

    # -- construction from URLs -------------------------------------------------------------------
    @classmethod
    def compatible_controllers(cls) -> tuple[str, ...]:
        """Profile controllers this class drives."""
        return (cls.controller,)

    @classmethod
    def from_url(cls, url: DeviceURL, **kwargs: Any) -> PanelDisplay:
        """``MODEL:TARGET?options`` on hardware, ``sim:MODEL?options`` on the simulated chip (see docs/panels.md)."""
        where = str(url)
        sim_options: dict[str, str] | None = None
        if url.scheme == "sim":
            url, sim_options = cls.split_sim_url(url)
        opts = cls.read_url_options(url)
        model = url.scheme
        try:
            profile = cls._profile(opts)
            rotation = cls._rotation(opts, profile, given="rotation" in url.options)
            keywords = cls.controller_options(opts, profile)
        except URLError:
            raise
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None
        clock: Clock = kwargs.pop("clock", None) or (SimulatedClock() if sim_options is not None else REAL_CLOCK)
        device: BusDevice | None = None
        if sim_options is not None:
            interface: Interface = "spi" if opts["dc"] is not None and "spi" in cls.interfaces else cls.interfaces[0]
            pins = cls._pins(opts, profile, interface)
            held = rotation if _turned(opts["size"], profile) else 0
            try:
                options = cls.simulator_options(model, sim_options, opts, profile, pins, held=held)
            except ConfigError as exc:
                raise ConfigError(f"{where}: {exc}") from None
            sim = _bus_device(create_simulator(model, clock=clock, **options), where)
            device = sim
            wiring: Wiring | Callable[[], Wiring] = lambda: sim_wiring(sim, interface, pins, clock=clock)
        else:
            target = parse_target(url.target, where)
            if target.interface not in cls.interfaces:
                raise URLError(f"{where}: a {cls.controller} is not driven over {target.interface}")
            pins = cls._pins(opts, profile, target.interface)
            wiring = lambda: open_wiring(target, pins, clock=clock, where=where)  # opened by open()
        return cls(wiring, profile=profile, rotation=rotation, fps=opts["fps"], invert=opts["invert"],
                   persist=opts["persist"], refresh=opts["refresh"], clock=clock, simulator=device, **keywords,
                   **kwargs)

    @classmethod
    def _profile(cls, opts: OptionValues) -> PanelProfile:
        """The profile named by ``profile=``, else the built-in one of ``size=`` (else the class's default size)."""
        if opts["profile"] is not None:
            profile = load_panel_profile(opts["profile"])
            if opts["size"] is not None and opts["size"] not in (profile.size, profile.size[::-1]):
                raise ConfigError(f"size={opts['size'][0]}x{opts['size'][1]} disagrees with profile {profile.name} "
                                  f"({profile.size[0]}x{profile.size[1]})")
            return profile
        return panel_profile_for(cls.controller, opts["size"] or cls.default_size)

    @classmethod
    def _rotation(cls, opts: OptionValues, profile: PanelProfile, *, given: bool) -> int:
        """``rotation=``; a ``size`` turned from the module's (320x240 on a 240x320) means rotation 90, and
        with ``rotation=`` given too the two must agree (90 or 270)."""
        rotation = int(opts["rotation"])
        if not _turned(opts["size"], profile):
            return rotation
        if not given:
            return 90
        if rotation % 180 == 0:
            w, h = opts["size"]
            raise ConfigError(f"size={w}x{h} is the {h}x{w} module turned (rotation 90 or 270), "
                              f"but rotation={rotation}")
        return rotation

    @classmethod
    def _pins(cls, opts: OptionValues, profile: PanelProfile, interface: Interface) -> Pins:
        hz = opts["hz"] if opts["hz"] is not None else profile.bus_clock(interface)
        profile.check_clock(interface, hz)
        return Pins(dc=opts["dc"], rst=opts["rst"], bl=opts["bl"], te=opts["te"], gpiochip=opts["gpiochip"], hz=hz,
                    addr=opts.get("addr") or profile.i2c_address or 0x3C)

    @classmethod
    def controller_options(cls, opts: OptionValues, profile: PanelProfile) -> dict[str, Any]:
        """Constructor keywords from the controller's own URL options (the base has none)."""
        return {}

    @classmethod
    def simulator_options(cls, model: str, sim_options: dict[str, str], opts: OptionValues, profile: PanelProfile,
                          pins: Pins, *, held: int = 0) -> dict[str, str]:
        """Options for the simulator of a ``sim:`` URL: as given, with the module's own (rotation 0) size held
        turned by ``held`` degrees (a turned ``size``: the glass is as big as the canvas) and the bus clock (when
        the simulator counts bus time at a clock of its own: its ``hz`` option)."""
        out = dict(sim_options)
        names = {spec.name for spec in simulator_specs(model)}
        w, h = profile.size
        if held % 180 and "turn" in names:
            w, h = h, w
            out.setdefault("turn", str(held))
        out["size"] = f"{w}x{h}"
        if "hz" in names:
            out.setdefault("hz", f"{pins.hz:g}")
        return out

    # -- what a controller implements --------------------------------------------------------------
    @property
    @abstractmethod
    def pixel_format(self) -> str:
        """The ``raster.formats`` name of the pixels on the wire."""

    @abstractmethod
    def _window_size(self) -> tuple[int, int]:
        """(width, height) of the controller window space at the current rotation (the native frame)."""

    @abstractmethod
    def _setup(self) -> None:
        """Send the settings of the options after the init table: scan direction, inversion, colour depth..."""

    @abstractmethod
    def _write_windows(self, windows: list[Rect], packed: list[bytes]) -> None:
        """Send a frame's windows in order: each one's window commands (those the window before it in the frame
        set may be left out: the controller still holds them), then its pixels (already packed)."""

    @abstractmethod
    def _power(self, on: bool) -> None:
        """Display on or off (the RAM keeps its picture)."""

    def _soft_turn(self) -> int:
        """Degrees of the rotation done by turning the picture in software (the controller does the rest)."""
        return 0

    # -- life cycle ---------------------------------------------------------------------------------
    @property
    def wiring(self) -> Wiring:
        """The open bus and lines (LinkError-free access only while open)."""
        if self._wiring is None:
            raise ConfigError(f"{type(self).__name__} is not open")
        return self._wiring

    @property
    def bus(self) -> PanelBus | None:
        """The panel bus (None until the display is opened on hardware)."""
        return None if self._wiring is None else self._wiring.bus

    @property
    def simulator(self) -> BusDevice | None:
        """The simulated chip of a ``sim:`` display (None on hardware); it stays readable after close."""
        return self._simulator

    @contextlib.contextmanager
    def recording(self) -> Iterator[BusTrace]:
        """Record every bus call of the block (``drivers.bustrace.RecordingBus`` wraps the bus meanwhile): a
        ``BusTrace`` whose ``events`` are the reset pulses and command (``C``) and data (``D``) frames, filled
        in when the block ends."""
        import io

        from pixelpen.drivers.bustrace import BusTrace, RecordingBus, parse_bus_trace

        wiring = self.wiring
        inner = wiring.bus
        text = io.StringIO()
        trace = BusTrace()
        wiring.bus = RecordingBus(inner, text, url=self.profile.name, clock=self.clock)
        try:
            yield trace
        finally:
            wiring.bus = inner
            parsed = parse_bus_trace(text.getvalue().splitlines(keepends=True), source=self.profile.name)
            for name in (f.name for f in fields(trace)):
                setattr(trace, name, getattr(parsed, name))

    def power(self, on: bool) -> None:
        """Display on or off; the RAM keeps the picture."""
        self._require_open()
        self._power(on)

    def _open_device(self) -> None:
        if self._wiring is None:
            source = self._wiring_source
            self._wiring = source if isinstance(source, Wiring) else source()
        self.stats = PanelStats()
        self._full = True
        bus = self._wiring.bus
        self._cost = window_cost(self.profile.controller, pixel_format=self.pixel_format,
                                 bus_kind=bus.kind, max_transfer=bus.max_transfer)
        try:
            self._pacer = None
            if self.target_fps is not None:
                self.check_fps(self.target_fps)
            self._initialise()
            self._start_pacer()
        except BaseException:
            self._wiring.close(backlight_on=False)
            self._wiring = None
            raise

    def _initialise(self) -> None:
        """Reset, the init table up to display-on, the option settings, a full frame, then display-on (unpaced)."""
        pacer, self._pacer = self._pacer, None
        try:
            self._bring_up()
        finally:
            self._pacer = pacer

    def _bring_up(self) -> None:
        self.wiring.bus.reset()
        steps = list(self.profile.init)
        on_at = max((i for i, s in enumerate(steps) if s.command == self.display_on), default=None)
        before, after = (steps, []) if on_at is None else (steps[:on_at], steps[on_at:])
        self._run_steps(before)
        self._setup()
        self._full = True
        self._show(self.canvas)
        self.canvas.clear_damage()
        self._run_steps(after)

    def _run_steps(self, steps: list[InitStep]) -> None:
        for step in steps:
            self._send_step(step)
            if step.delay_ms:
                self.clock.sleep(step.delay_ms / 1000.0)

    def _send_step(self, step: InitStep) -> None:
        """One init-table step: MIPI sends the command byte, then its parameters as data."""
        self._command(step.command)
        if step.params:
            self._data(step.params)

    def close(self) -> None:
        """Send the frame still held back by pacing, leave the picture (``persist``) or turn it off, release."""
        self._force = True
        try:
            super().close()
        finally:
            self._force = False

    def _close_device(self) -> None:
        wiring = self._wiring
        self._pacer = None
        if wiring is None:
            return
        try:
            if not self.persist:
                self._power(False)
        except LinkError as exc:  # closing must release the bus even when the panel cannot be reached
            log.warning("%s: could not turn the display off: %s", self.profile.name, exc)
        finally:
            self._wiring = None
            wiring.close(backlight_on=self.persist)

    def reset(self) -> None:
        """Reset the controller and initialise it again; the canvas is sent whole."""
        self._require_open()
        self._initialise()

    def rotate(self, degrees: int) -> None:
        """Turn the picture to ``degrees`` (0/90/180/270 clockwise): the canvas is kept when its size stays,
        otherwise a new one of the turned size is started; the next frame is full."""
        degrees = self._check_rotation(degrees)
        self.rotation = degrees
        caps = self._capabilities()
        if caps.size != self.capabilities.size:
            self.capabilities = caps
            self.canvas = Canvas(int(caps.size[0]), int(caps.size[1]), self.canvas_mode)
            self.canvas.fill(self.background)
            self.window(0.0, 0.0, *caps.size_mm)
        self._shadow = None
        self._full = True
        if self.is_open:
            self._setup()
            self.flush()

    def _check_rotation(self, degrees: int) -> int:
        if degrees not in (0, 90, 180, 270):
            raise InvalidArgument(f"rotation must be 0, 90, 180 or 270 degrees, got {degrees!r}")
        return int(degrees)

    def _capabilities(self) -> Capabilities:
        """Size and model at the current rotation."""
        w, h = self.profile.size[::-1] if self.rotation % 180 else self.profile.size
        fmt = self.pixel_format
        colour: ColourModel = "mono" if self.canvas_mode == "1" else "rgb666" if fmt == "rgb666" else "rgb565"
        return Capabilities(model=self.profile.name, category="output", kind="raster", size=(float(w), float(h)),
                            unit_mm=PIXEL_PITCH_MM, colour_model=colour, y_down=True, can_erase=True,
                            limits={"controller": self.profile.controller, "rotation": self.rotation})

    # -- pacing ------------------------------------------------------------------------------------------
    def _start_pacer(self) -> None:
        """A pacer for ``target_fps`` whose first slot follows the frame just sent."""
        self._pacer = None
        if self.target_fps is not None:
            from pixelpen.devices.panels.pacing import FramePacer

            self._pacer = FramePacer(self.clock, self.target_fps)
            self._pacer.sent()

    def check_fps(self, fps: float) -> None:
        """ConfigError when ``fps`` full frames a second cannot pass the configured bus at its clock."""
        from pixelpen.devices.panels.pacing import check_fps

        w, h = self._window_size()
        frame = self.cost.window(Rect(0, 0, w, h))
        bus = self.wiring.bus
        check_fps(fps, kind=bus.kind, clock_hz=bus.clock_hz,
                  frame_bytes=frame.bytes, transfers=frame.transfers, what=self._describe())

    @property
    def cost(self) -> WindowCost:
        """The controller's window cost model on the open bus (``windows.window_cost``)."""
        if self._cost is None:
            raise ConfigError(f"{type(self).__name__} is not open")
        return self._cost

    def _describe(self) -> str:
        w, h = self.profile.size
        return f"{self.profile.controller.upper()} {w}x{h} {self.pixel_format.removesuffix('be').upper()}"

    def _present(self) -> None:
        if self._pacer is not None and not self._force and not self._pacer.frame_due():
            return  # frames coalesce: the damage stays until a frame is due
        super()._present()

    def refresh(self, target_fps: float | None = None) -> bool:
        """Render what is pending and send it as one frame, first waiting for the next frame time of
        ``target_fps`` (default: the ``fps`` option; neither: at once).  True when anything was sent."""
        self._require_open()
        if target_fps is not None and target_fps != self.target_fps:
            self.check_fps(target_fps)
            self.target_fps = target_fps
            self._start_pacer()
        if self._pacer is not None:
            self._pacer.wait()
        before = self.stats.frames
        self._force = True
        try:
            self.flush()
        finally:
            self._force = False
        return self.stats.frames > before

    # -- frames ------------------------------------------------------------------------------------
    def _native(self, array: np.ndarray) -> np.ndarray:
        """The canvas array as the controller's window space sees it (a view turned by the software rotation)."""
        turn = self._soft_turn()
        return np.rot90(array, -(turn // 90)) if turn else array

    def _native_rect(self, r: Rect, width: int, height: int) -> Rect:
        """A canvas rectangle in window space (``width`` x ``height`` is the canvas size)."""
        turn = self._soft_turn()
        if turn == 90:
            return Rect(height - r.y1, r.x0, height - r.y0, r.x1)
        if turn == 180:
            return Rect(width - r.x1, height - r.y1, width - r.x0, height - r.y0)
        if turn == 270:
            return Rect(r.y0, width - r.x1, r.y1, width - r.x0)
        return r

    def _show(self, canvas: Canvas) -> None:
        """Send the damaged (or, when due, every) pixel of ``canvas``; a fault or interruption makes the next full.

        Host work first (scroll, trim, plan, pack every window, update the shadow), then the bus calls: the frame
        is timed once, host seconds up to the first bus call, bus seconds (the display's clock) from there."""
        started = time.perf_counter()
        frame = self._frame = FrameStats(full=self._full or self.refresh_mode == "full")
        cost, fmt = self.cost, self.pixel_format
        native = self._native(canvas.array)
        height, width = native.shape[:2]
        shadow = self._shadow
        if frame.full or shadow is None or shadow.shape[:2] != (height, width):
            rects = [Rect(0, 0, width, height)]
            frame.full = True
            self._units = to_units(native, fmt)
            units = native if self._units is None else self._units
            shadow = self._shadow = np.empty_like(units)
        else:
            damage = canvas.damage()
            if self._soft_turn():
                damage = [self._native_rect(r, canvas.width, canvas.height) for r in damage]
            damage = self._scroll.detect(native, damage, shadow, self._units)
            native, damage = self._scroll.to_ram(native, damage)
            if self._units is None:
                units = native
            else:
                units = self._units
                update_units(units, native, damage)
            rects = trim_damage(damage, units, shadow, cost)
        if not rects and not self._scroll.pending:
            return
        if frame.full or not rects:
            windows = rects
        elif len(rects) <= MAX_WINDOWS:  # trim's cut is already planned by the cost model
            windows = cost.cut_or_bounding(rects)
        else:
            windows = cost.plan(rects, width=width, height=height)
        self._full = True  # until the last window is out
        packed = pack_windows(units.view(np.bool_) if self.canvas_mode == "1" else units, windows, fmt,
                              cost.align[1] if fmt == "mono-pages" else 1)
        keep_windows(shadow, units, windows)
        frame.host_seconds = time.perf_counter() - started
        self._wait_te()
        on_bus = self.clock.now()
        self._scroll.start_frame(frame.full)
        self._write_windows(windows, packed)
        frame.bus_seconds = self.clock.now() - on_bus
        self._full = False
        if self._pacer is not None:
            self._pacer.sent()
        frame.windows = len(windows)
        self.stats.add(frame)

    def _wait_te(self) -> None:
        """Start at the tearing-effect pulse when a TE line is wired (a missing pulse is logged, not fatal)."""
        te = self.wiring.te
        if te is not None and not te.wait_edge(True, TE_TIMEOUT):
            log.debug("%s: no TE pulse within %g s; sending anyway", self.profile.name, TE_TIMEOUT)

    # -- the bus, counted -------------------------------------------------------------------------
    def _command(self, *cmd: int | bytes) -> None:
        """``bus.command`` with the bytes counted in the frame's statistics once the bus has taken them."""
        self.wiring.bus.command(*cmd)
        self._frame.bytes += sum(1 if isinstance(c, int) else len(c) for c in cmd)

    def _data(self, data: bytes) -> None:
        """``bus.data`` with the bytes counted once the bus has taken them."""
        self.wiring.bus.data(data)
        self._frame.bytes += len(data)


def _turned(size: tuple[int, int] | None, profile: PanelProfile) -> bool:
    """True when ``size`` is the profile's module turned a quarter (320x240 for a 240x320; never a square)."""
    return size is not None and size != profile.size and size == profile.size[::-1]


def _bus_device(device: object, where: str) -> BusDevice:
    """The simulator as a BusDevice (a stream simulator behind a panel scheme is a URLError)."""
    if not isinstance(device, BusDevice):
        raise URLError(f"{where}: the simulator {type(device).__name__} is not a panel (bus) device")
    return device

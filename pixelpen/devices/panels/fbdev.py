"""The ``fbdev:`` display: a Linux framebuffer (``fbdev:/dev/fb0``) or its simulator (``sim:fbdev?size=320x240``).

Only the damaged rectangles are packed and written.  Double buffered (pan between two pages), the hidden
page is a frame behind, so it gets this frame's damage and the previous frame's; then a vertical blank
(FBIO_WAITFORVSYNC where the driver has it) and the pan show it.  The first frame after opening is full.
Closing leaves the last frame on the screen (``persist=false``: cleared to black), unmaps and closes.
The geometry is the device's, so the framebuffer is opened when the display is built.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.devices.panels.frames import FrameStats, PanelStats
from pixelpen.display.capabilities import Capabilities, ColourModel
from pixelpen.display.kinds import RasterDisplay
from pixelpen.display.registry import register_display
from pixelpen.drivers.fbdev import DeviceNode, Framebuffer, FramebufferDevice
from pixelpen.errors import InvalidArgumentType, URLError
from pixelpen.options import OptionSpec, boolean, colour
from pixelpen.raster.canvas import Canvas
from pixelpen.raster.damage import DEFAULT_MERGE_COST, Rect, merge_rects
from pixelpen.urls import DeviceURL

if TYPE_CHECKING:
    from pixelpen.sim.panels.fbdev import FbdevSim

DEFAULT_DPI = 96.0
"""Pixel density assumed when the driver does not report the screen's size in millimetres."""


@register_display("fbdev")
class FramebufferDisplay(RasterDisplay):
    """Draws on a Linux framebuffer: ``fbdev:/dev/fb0?double=true&vsync=true&persist=true``."""

    OPTIONS: ClassVar[tuple[OptionSpec[Any], ...]] = (
        OptionSpec("double", boolean, True, "double buffering by panning, where the driver allows it"),
        OptionSpec("vsync", boolean, True, "show frames at a vertical blank (FBIO_WAITFORVSYNC, where supported)"),
        OptionSpec("persist", boolean, True, "leave the last frame on the screen at close (false: clear it to black)"),
        OptionSpec("background", colour, "black", "background colour, a name or #rrggbb"),
    )
    simulated: ClassVar[bool] = True
    SIM_SHARED: ClassVar[frozenset[str]] = frozenset({"vsync"})

    def __init__(
        self, device: str | Callable[[], FramebufferDevice] = "/dev/fb0", *, double_buffer: bool = True,
        vsync: bool = True, persist: bool = True, background: object = "black", simulator: FbdevSim | None = None,
    ) -> None:
        if isinstance(device, str):
            path = device
            self._opener: Callable[[], FramebufferDevice] = lambda: DeviceNode(path)
        elif callable(device):
            self._opener = device
        else:
            raise InvalidArgumentType(f"device must be a node path or a callable opening a framebuffer node, got "
                                      f"{type(device).__name__}")
        self.double_buffer = double_buffer
        self.vsync = vsync
        self.persist = persist
        self.simulator = simulator
        """The simulator behind a ``sim:fbdev`` display (None on hardware)."""
        self.framebuffer = Framebuffer(self._opener(), double_buffer=double_buffer)
        fb = self.framebuffer
        mm = fb.size_mm
        unit_mm = mm[0] / fb.width if mm else 25.4 / DEFAULT_DPI
        model: ColourModel = "grey" if fb.layout.grey else "rgb565" if fb.layout.bits_per_pixel == 16 else "rgb888"
        caps = Capabilities(
            model="fbdev", category="output", kind="raster", size=(float(fb.width), float(fb.height)),
            unit_mm=unit_mm, colour_model=model, y_down=True, can_erase=True, tolerance=0.25,
            limits={"device": fb.name, "bits_per_pixel": fb.layout.bits_per_pixel, "line_length": fb.line_length,
                    "buffering": fb.buffering},
        )
        super().__init__(caps, mode="RGB", background=background)
        self._previous: list[Rect] = []
        """What the last frame changed: the hidden page still lacks it (double buffering)."""
        self._full = True
        self.clock = simulator.clock if simulator is not None else REAL_CLOCK
        self.stats = PanelStats()
        """Totals since open, as panels keep them: ``bytes`` are pixel bytes stored (padding excluded),
        ``windows`` rectangles written, ``host_seconds`` packing and storing, ``bus_seconds`` clock time in the
        vertical-blank wait and the pan."""

    @classmethod
    def from_url(cls, url: DeviceURL, **kwargs: object) -> FramebufferDisplay:
        """``fbdev:/dev/fbN?options`` for hardware, ``sim:fbdev?options`` (plus the simulator's) for the simulator.

        ``clock=`` (a keyword) is the simulator's clock.
        """
        clock = kwargs.pop("clock", None)
        if kwargs:
            raise URLError(f"{url}: unknown keyword(s) {', '.join(sorted(kwargs))}")
        if url.scheme != "sim":
            options = cls.read_url_options(url)
            return cls(url.target or "/dev/fb0", **cls._keywords(options))
        from pixelpen.sim.base import create_simulator
        from pixelpen.sim.panels.fbdev import FbdevSim

        own, sim_options = cls.split_sim_url(url)
        options = cls.read_url_options(own)
        if clock is not None and not isinstance(clock, Clock):
            raise InvalidArgumentType(f"clock must be a pixelpen.clock.Clock, got {type(clock).__name__}")
        sim = create_simulator("fbdev", clock=clock, **sim_options)
        if not isinstance(sim, FbdevSim):
            raise URLError(f"{url}: the fbdev simulator registered is a {type(sim).__name__}, not an FbdevSim")
        return cls(sim.open, simulator=sim, **cls._keywords(options))

    @staticmethod
    def _keywords(options: Any) -> dict[str, Any]:
        return {"double_buffer": options["double"], "vsync": options["vsync"], "persist": options["persist"],
                "background": options["background"]}

    # -- life cycle --------------------------------------------------------------------------------
    def _open_device(self) -> None:
        if self.framebuffer.closed:
            self.framebuffer = Framebuffer(self._opener(), double_buffer=self.double_buffer)
        self._full = True
        self._previous = []
        self._present()

    def _close_device(self) -> None:
        fb = self.framebuffer
        try:
            if not self.persist and not fb.closed:
                fb.memory[...] = 0
        finally:
            fb.close()

    # -- frames ------------------------------------------------------------------------------------
    def _show(self, canvas: Canvas) -> None:
        fb = self.framebuffer
        full = self._full
        rects = [Rect(0, 0, canvas.width, canvas.height)] if full else canvas.damage()
        if not rects:
            return
        self._full = True  # until this frame is done: one cut short (a fault, Ctrl-C) is followed by a full one
        bpp = fb.layout.bytes_per_pixel
        started = time.perf_counter()
        waits = [0.0, 0.0]  # clock seconds, wall seconds in the vertical-blank wait and the pan
        writes = merge_rects(rects + self._previous, DEFAULT_MERGE_COST, bpp) if fb.double_buffered else rects
        if self.vsync and not fb.double_buffered:
            self._timed(fb.wait_for_vsync, waits)
        for r in writes:
            fb.write(canvas.array[r.y0:r.y1, r.x0:r.x1], r.x0, r.y0)
        self._timed(lambda: fb.flip(vsync=self.vsync), waits)
        self._previous = rects
        self._full = False
        self.stats.add(FrameStats(bytes=sum(r.area for r in writes) * bpp, windows=len(writes), full=full,
                                  host_seconds=max(time.perf_counter() - started - waits[1], 0.0),
                                  bus_seconds=waits[0]))

    def _timed(self, step: Callable[[], object], waits: list[float]) -> None:
        """Run ``step``, adding the clock time (device time on a SimulatedClock) and wall time it took to ``waits``."""
        t0, perf = self.clock.now(), time.perf_counter()
        step()
        waits[0] += self.clock.now() - t0
        waits[1] += time.perf_counter() - perf

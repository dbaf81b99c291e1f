"""A panel URL's target and pin options -> an open bus: ``i2c:N``, ``spi:B.D``, ``ftdi://...``, ``mcp2221:[serial]``.

A ``sim:MODEL`` URL is wired the same way over the simulated transports (``SimSpiWiring``, ``SimSMBus``):
the display's driver code then runs the very SpiBus/I2CBus it runs on hardware.  GPIO options are line
offsets on ``gpiochip`` (the Linux GPIO character device); on an FT232H they are ADBUS pin numbers.
"""

from __future__ import annotations

import contextlib
import logging
from dataclasses import dataclass
from typing import Any, Literal

from pixelpen.clock import Clock
from pixelpen.drivers.bus import PanelBus
from pixelpen.drivers.gpio import InputLine, OutputLine
from pixelpen.errors import ConfigError, URLError
from pixelpen.sim.base import BusDevice

log = logging.getLogger(__name__)

Interface = Literal["spi", "i2c"]


@dataclass(frozen=True)
class Pins:
    """The wiring options of a panel URL: GPIO line offsets, the GPIO chip, the bus clock, the I2C address."""

    dc: int | None = None
    rst: int | None = None
    bl: int | None = None
    te: int | None = None
    gpiochip: str = "/dev/gpiochip0"
    hz: float = 10_000_000.0
    addr: int = 0x3C


@dataclass(frozen=True)
class Target:
    """A parsed panel target: which bus and where (``spi`` bus/device, ``i2c`` bus number, a bridge URL or serial)."""

    kind: Literal["spi", "i2c", "ftdi", "mcp2221"]
    bus: int = 0
    device: int = 0
    where: str = ""

    @property
    def interface(self) -> Interface:
        """The wire this target carries: "spi" (spidev, FT232H) or "i2c" (i2c-dev, MCP2221A)."""
        return "spi" if self.kind in ("spi", "ftdi") else "i2c"


class Wiring:
    """An open panel bus with the GPIO lines beside it (TE in, backlight out) and, for ``sim:``, the simulator."""

    def __init__(self, bus: PanelBus, *, te: InputLine | None = None, backlight: OutputLine | None = None,
                 simulator: BusDevice | None = None, closers: tuple[Any, ...] = ()) -> None:
        self.bus = bus
        self.te = te
        self.backlight = backlight
        self.simulator = simulator
        self._closers = closers
        self._closed = False

    def close(self, *, backlight_on: bool = True) -> None:
        """Release the bus and the lines; the backlight is left as ``backlight_on`` says (idempotent).  Every
        part is closed even when another fails (the first failure is raised after)."""
        if self._closed:
            return
        self._closed = True
        with contextlib.ExitStack() as stack:
            for extra in reversed(self._closers):
                stack.callback(extra.close)
            stack.callback(self.bus.close)
            for line in (self.backlight, self.te):
                if line is not None:
                    stack.callback(line.close)
            if self.backlight is not None:
                self.backlight.set(backlight_on)


def parse_target(target: str, where: str) -> Target:
    """``spi:B.D``, ``i2c:N``, ``ftdi://...`` or ``mcp2221:[serial]``; anything else is a URLError naming ``where``."""
    kind, sep, rest = target.partition(":")
    kind = kind.lower()
    bus, dot, device = rest.partition(".")
    if kind == "spi" and sep and dot and _is_number(bus) and _is_number(device):
        return Target("spi", int(bus), int(device))
    if kind == "i2c" and sep and _is_number(rest):
        return Target("i2c", int(rest))
    if kind == "ftdi" and rest.startswith("//"):
        return Target("ftdi", where=target)
    if kind == "mcp2221" and sep:
        return Target("mcp2221", where=rest)
    raise URLError(f"{where}: panel target {target!r} is not one of spi:BUS.DEVICE (spi:0.0), i2c:BUS (i2c:1), "
                   "ftdi://ftdi:232h/1 or mcp2221:[SERIAL]")


def _is_number(text: str) -> bool:
    return text.isascii() and text.isdigit() and len(text) <= 6


UNWIRED = {"ftdi": ("te", "bl"), "mcp2221": ("rst", "te", "bl")}
"""Pin options a bridge has no line for: the FT232H's SPI carries D/C and reset on its GPIO only; the MCP2221A
is I2C alone."""


def open_wiring(target: Target, pins: Pins, *, clock: Clock, where: str) -> Wiring:
    """Open the hardware bus ``target`` names with ``pins`` (lines are released again if anything fails).

    A pin option the target cannot wire (:data:`UNWIRED`) is a ConfigError naming it.
    """
    given = [name for name in UNWIRED.get(target.kind, ()) if getattr(pins, name) is not None]
    if given:
        raise ConfigError(f"{where}: {', '.join(f'{name}=' for name in given)} cannot be wired on {target.kind} "
                          f"(it has no line for {' or '.join(given)}); leave it out")
    if target.interface == "spi" and pins.dc is None:
        raise ConfigError(f"{where}: a 4-wire SPI panel needs its D/C line: add dc=N (the GPIO offset)")
    if target.kind == "spi":
        from pixelpen.drivers.spi import SpiBus

        bus: PanelBus = SpiBus.open(target.bus, target.device, dc=pins.dc or 0, rst=pins.rst, clock_hz=pins.hz,
                                    gpiochip=pins.gpiochip, clock=clock)
        return _with_lines(bus, pins, clock)
    if target.kind == "i2c":
        from pixelpen.drivers.i2c import I2CBus

        return _with_lines(I2CBus.open(target.bus, pins.addr, clock_hz=pins.hz, rst=pins.rst, gpiochip=pins.gpiochip,
                                       clock=clock), pins, clock)
    if target.kind == "mcp2221":
        from pixelpen.drivers.i2c import I2CBus
        from pixelpen.drivers.mcp2221 import MCP2221

        adapter = MCP2221.open(serial=target.where or None, clock_hz=pins.hz, clock=clock)
        try:
            return Wiring(I2CBus(adapter, pins.addr, clock_hz=pins.hz, clock=clock,
                                 name=f"mcp2221 {target.where}".rstrip()))
        except BaseException:
            adapter.close()
            raise
    from pixelpen.drivers.ftdi import MAX_CLOCK_HZ, FtdiSpiBus

    hz = min(pins.hz, MAX_CLOCK_HZ)
    if hz < pins.hz:
        log.info("%s: the FT232H clocks SPI at %g MHz at most, not %g", where, hz / 1e6, pins.hz / 1e6)
    return Wiring(FtdiSpiBus.open(target.where, dc=pins.dc or 0, rst=pins.rst, clock_hz=hz, clock=clock))


def _with_lines(bus: PanelBus, pins: Pins, clock: Clock) -> Wiring:
    """The bus plus its backlight and TE lines from ``gpiochip`` (the bus is closed again if a line fails)."""
    from pixelpen.drivers.gpio import open_input_line, open_output_line

    te: InputLine | None = None
    backlight: OutputLine | None = None
    try:
        if pins.te is not None:
            te = open_input_line(pins.gpiochip, pins.te, edge="rising", clock=clock)
        if pins.bl is not None:
            backlight = open_output_line(pins.gpiochip, pins.bl, initial=True)
    except BaseException:
        if te is not None:
            te.close()
        bus.close()
        raise
    return Wiring(bus, te=te, backlight=backlight)


def sim_wiring(device: BusDevice, interface: Interface, pins: Pins, *, clock: Clock) -> Wiring:
    """The simulated chip behind the same SpiBus/I2CBus classes as hardware (TE wired when ``pins.te`` is set)."""
    if interface == "spi":
        from pixelpen.drivers.spi import SpiBus
        from pixelpen.sim.transports.spidev import SimSpiWiring

        wires = SimSpiWiring(device, clock=clock)
        bus: PanelBus = SpiBus(wires.spidev, dc=wires.dc, reset=wires.reset if pins.rst is not None else None,
                               clock_hz=pins.hz, max_transfer=wires.bufsiz, clock=clock, name=f"sim {device.model}")
        backlight = wires.output_line("backlight") if pins.bl is not None else None
        return Wiring(bus, te=wires.te if pins.te is not None else None, backlight=backlight, simulator=device)
    from pixelpen.drivers.i2c import I2CBus
    from pixelpen.sim.transports.i2cdev import SimSMBus

    adapter = SimSMBus(device, clock=clock, clock_hz=pins.hz)
    return Wiring(I2CBus(adapter, pins.addr, clock_hz=pins.hz, clock=clock, name=f"sim {device.model}"),
                  simulator=device)


"""GPIO lines a panel needs beside its bus (D/C, reset, backlight out; TE in), over the Linux GPIO character device.

``open_output_line``/``open_input_line`` request one line of a chip (``/dev/gpiochipN``, by offset) through
libgpiod v2's Python binding (``gpiod`` 2.x, imported on first use); the protocols are what buses and
simulators share, so a simulated line (``sim.transports.spidev``) stands in for a real one.
"""

from __future__ import annotations

import errno
import logging
from types import ModuleType
from typing import Any, Final, Protocol, runtime_checkable

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.drivers.devnode import node_open_error, require_module
from pixelpen.errors import ConfigError, InvalidArgument, LinkError

log = logging.getLogger(__name__)

EDGES: Final = ("rising", "falling", "both")
"""Edge-detection choices of ``open_input_line``."""


@runtime_checkable
class OutputLine(Protocol):
    """A GPIO output: ``set(True)`` drives it high (the physical level; reset is active low on the glass)."""

    def set(self, level: bool) -> None:
        """Drive the line high (True) or low (False)."""

    def close(self) -> None:
        """Release the line (it keeps its last level); calling it again does nothing."""


@runtime_checkable
class InputLine(Protocol):
    """A GPIO input with edge detection (a panel's TE output)."""

    def get(self) -> bool:
        """The line's level now."""

    def wait_edge(self, rising: bool, timeout: float) -> bool:
        """Wait up to ``timeout`` seconds for the next rising (or falling) edge after the call; False on timeout."""

    def close(self) -> None:
        """Release the line; calling it again does nothing."""


def _gpiod() -> ModuleType:
    return require_module("gpiod", needed_by="GPIO lines", package="the gpiod package (libgpiod v2 bindings)",
                          install="'gpiod>=2.1' (or pip install 'pixelpen[panels]')")


def _request(chip: str, offset: int, settings: Any, consumer: str) -> Any:
    """A gpiod LineRequest for one line, with the OS's refusals explained."""
    if not isinstance(offset, int) or isinstance(offset, bool) or offset < 0:
        raise InvalidArgument(f"GPIO line offset must be a non-negative integer, got {offset!r}")
    gpiod = _gpiod()
    where = f"GPIO line {offset} of {chip}"
    try:
        return gpiod.request_lines(chip, consumer=consumer, config={offset: settings})
    except (FileNotFoundError, PermissionError) as e:
        raise node_open_error(chip, e, what=f"GPIO line {offset}", missing="gpiodetect lists the GPIO chips",
                              group="gpio", udev='SUBSYSTEM=="gpio", KERNEL=="gpiochip*"') from e
    except ValueError as e:
        raise InvalidArgument(f"{where}: {e}") from None
    except OSError as e:
        if e.errno == errno.EBUSY:
            raise LinkError(f"{where} is in use by another program or driver (gpioinfo shows its consumer)") from e
        if e.errno == errno.EINVAL:
            raise LinkError(f"{where}: the chip refused the request (no such line?): {e}") from e
        if e.errno in (errno.ENODEV, errno.ENOTTY):
            raise LinkError(f"{where}: {chip} is not a GPIO character device") from e
        raise LinkError(f"{where}: cannot request the line: {e}") from e


class GpiodOutputLine:
    """An OutputLine on one requested gpiod line."""

    def __init__(self, request: Any, offset: int, value: Any, name: str) -> None:
        self._request: Any = request
        self._offset = offset
        self._value = value
        self.name = name

    def set(self, level: bool) -> None:
        """Drive the line high (True) or low (False)."""
        if self._request is None:
            raise LinkError(f"{self.name}: the line is closed")
        try:
            self._request.set_value(self._offset, self._value.ACTIVE if level else self._value.INACTIVE)
        except OSError as e:
            raise LinkError(f"{self.name}: setting the line {'high' if level else 'low'} failed: {e}") from e

    def close(self) -> None:
        """Release the line (the kernel keeps its last level)."""
        request, self._request = self._request, None
        if request is not None:
            request.release()


class GpiodInputLine:
    """An InputLine on one requested gpiod line with edge detection; timeouts are measured on ``clock``."""

    def __init__(self, request: Any, offset: int, gpiod: ModuleType, edge: str, name: str, clock: Clock) -> None:
        self._request: Any = request
        self._offset = offset
        self._gpiod = gpiod
        self._edge = edge
        self._clock = clock
        self.name = name

    def _live(self) -> Any:
        if self._request is None:
            raise LinkError(f"{self.name}: the line is closed")
        return self._request

    def get(self) -> bool:
        """The line's level now."""
        try:
            return bool(self._live().get_value(self._offset) == self._gpiod.line.Value.ACTIVE)
        except OSError as e:
            raise LinkError(f"{self.name}: reading the line failed: {e}") from e

    def wait_edge(self, rising: bool, timeout: float) -> bool:
        """Wait for the next edge of the kind asked (edges queued before the call are dropped); False on timeout."""
        wanted = "rising" if rising else "falling"
        if self._edge not in (wanted, "both"):
            raise InvalidArgument(f"{self.name}: opened with edge={self._edge!r}, so {wanted} edges are not reported")
        kind = self._gpiod.EdgeEvent.Type.RISING_EDGE if rising else self._gpiod.EdgeEvent.Type.FALLING_EDGE
        request = self._live()
        try:
            while request.wait_edge_events(0):  # stale: they happened before the call
                request.read_edge_events()
            deadline = self._clock.now() + timeout
            while (left := deadline - self._clock.now()) > 0:
                if not request.wait_edge_events(left):
                    return False
                if any(event.event_type == kind for event in request.read_edge_events()):
                    return True
        except OSError as e:
            raise LinkError(f"{self.name}: waiting for an edge failed: {e}") from e
        return False

    def close(self) -> None:
        """Release the line."""
        request, self._request = self._request, None
        if request is not None:
            request.release()


def open_output_line(chip: str, offset: int, *, initial: bool, consumer: str = "pixelpen") -> GpiodOutputLine:
    """Request line ``offset`` of ``chip`` (``/dev/gpiochip0``) as an output starting at ``initial``."""
    gpiod = _gpiod()
    value = gpiod.line.Value
    settings = gpiod.LineSettings(
        direction=gpiod.line.Direction.OUTPUT, output_value=value.ACTIVE if initial else value.INACTIVE
    )
    request = _request(chip, offset, settings, consumer)
    log.debug("GPIO %s:%d requested as an output, initially %s", chip, offset, "high" if initial else "low")
    return GpiodOutputLine(request, offset, value, f"GPIO {chip}:{offset}")


def open_input_line(
    chip: str, offset: int, *, edge: str = "rising", consumer: str = "pixelpen", clock: Clock = REAL_CLOCK
) -> GpiodInputLine:
    """Request line ``offset`` of ``chip`` as an input reporting ``edge`` ("rising", "falling" or "both") edges."""
    if edge not in EDGES:
        raise ConfigError(f"GPIO edge must be one of {', '.join(EDGES)}, got {edge!r}")
    gpiod = _gpiod()
    settings = gpiod.LineSettings(
        direction=gpiod.line.Direction.INPUT, edge_detection=getattr(gpiod.line.Edge, edge.upper())
    )
    request = _request(chip, offset, settings, consumer)
    log.debug("GPIO %s:%d requested as an input with %s edges", chip, offset, edge)
    return GpiodInputLine(request, offset, gpiod, edge, f"GPIO {chip}:{offset}", clock)


def pulse_reset(line: OutputLine, clock: Clock, *, pulse: float, recovery: float) -> None:
    """Hold an active-low reset line low for ``pulse`` s, release it, and wait ``recovery`` s on ``clock``."""
    line.set(False)
    clock.sleep(pulse)
    line.set(True)
    clock.sleep(recovery)

"""Immediate manual control of a plotter (pen up/down/toggle, home, motors off) on the family's hooks."""

from __future__ import annotations

from pixelpen.devices.plotters.family import PlotterFamily
from pixelpen.drivers.stream import Link
from pixelpen.errors import ConfigError, PixelpenError


class ManualControl(PlotterFamily):
    """The manual actions behind ``pixelpen pen``; a family implements the ``_manual_*`` hooks it supports."""

    link: Link | None
    _left_as_set: bool
    """The last thing done was a manual action: closing leaves the pen and carriage where the user put them."""

    def pen_up(self) -> None:
        """Raise the pen now."""
        self._manual("pen up")._manual_pen(False)

    def pen_down(self) -> None:
        """Lower the pen now."""
        self._manual("pen down")._manual_pen(True)

    def toggle_pen(self) -> None:
        """Raise the pen if it is down, lower it if it is up."""
        down = self._manual("pen toggle")._manual_pen_state()
        if down is None:
            raise ConfigError(f"{self.profile.name}: cannot tell whether the pen is up or down; use pen up or pen down")
        self._manual_pen(not down)

    def go_home(self) -> None:
        """Pen up and travel to the home (park) position now."""
        self._manual("home")._manual_home()

    def motors_off(self) -> None:
        """De-energise the motors now (the carriage can then be moved by hand)."""
        self._manual("motors off")._manual_motors_off()

    def _manual(self, what: str) -> ManualControl:
        if self.link is None:
            raise PixelpenError(f"{self.profile.name} is not open ({what})")
        self._left_as_set = True
        return self

    def _manual_pen(self, down: bool) -> None:
        """Move the pen down or up now and wait until it is there."""
        raise ConfigError(f"{self.profile.name}: pen {'down' if down else 'up'} is not supported by this driver")

    def _manual_pen_state(self) -> bool | None:
        """Whether the pen is down now (None: the device cannot tell)."""
        return None

    def _manual_home(self) -> None:
        """Pen up and travel home now, waiting until there."""
        raise ConfigError(f"{self.profile.name}: home is not supported by this driver")

    def _manual_motors_off(self) -> None:
        """De-energise the motors now."""
        raise ConfigError(f"{self.profile.name}: motors off is not supported by this driver")

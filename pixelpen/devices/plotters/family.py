"""What a plotter family implements: the device core :class:`~pixelpen.devices.plotters.base.PlotterDisplay` drives.

A plotter family (HPGL, GRBL, EBB) subclasses :class:`PlotterDisplay` and implements the device core:

* ``_connect()`` — handshake and initialise the device on ``self.link`` (called on every (re)connect);
* ``_send_stroke(index, points, pen)`` — encode one stroke (integer device units, pen down along it,
  pen up at its end) and stream it with the family's flow control; it may block while the device's
  buffer is full, and must call ``self._confirm(k)`` whenever the device confirms strokes < k done;
* ``_poll()`` — read whatever the device has said without blocking (confirmations, errors);
* ``_drain()`` — wait until every stroke sent is confirmed;
* ``_select_pen(pen)`` — take pen ``pen`` (multi-pen devices; single-pen devices never get it);
* ``_device_paused()`` — True while the device's own pause (button, VIEW, paper lever) holds;
* ``_make_safe()`` — best effort, never raising: stop motion, pen up, park, motors off;

Reporting to the base (optional, see :mod:`~pixelpen.devices.plotters.base`): ``self._mark_damaged(strokes)``
(drawn again whole), ``self._mark_missing(stroke, points)`` (exactly that piece drawn again),
``self._acknowledged(stroke, k)`` (the device said it reached point k), ``self._written_to(stroke, k)`` (bytes
up to point k start going out), ``self._lifted_in_place(stroke)``;

and, with safe defaults (here; the ``_manual_*`` ones in :mod:`~pixelpen.devices.plotters.manual`):

* ``_where()`` — on a fresh link, before ``_connect()``: let the device finish (or discard) what the
  old connection left, then report a :class:`DeviceWhere` (default: position unknown);
* ``_rehomed()`` — after a lost position the user re-homed and confirmed: take where the device stands as
  home (default: nothing; the EBB clears its step counters);
* ``_manual_pen(down)``, ``_manual_pen_state()``, ``_manual_home()``, ``_manual_motors_off()`` —
  immediate manual control behind :meth:`PlotterDisplay.pen_up` and friends (default: ConfigError).
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from pixelpen.devices.plotters.resume import DeviceWhere
from pixelpen.profiles.model import DeviceProfile


class PlotterFamily(ABC):
    """The device core of a plotter family (abstract) and the hooks it may override (safe defaults)."""

    profile: DeviceProfile

    @abstractmethod
    def _connect(self) -> None:
        """Handshake and initialise the device on ``self.link``."""

    @abstractmethod
    def _send_stroke(self, index: int, points: np.ndarray, pen: int) -> None:
        """Stream one stroke (pen down along it, up at its end) with the family's flow control."""

    @abstractmethod
    def _poll(self) -> None:
        """Read what the device said without blocking; confirm strokes, raise its errors."""

    @abstractmethod
    def _drain(self) -> None:
        """Wait until every stroke sent is confirmed on paper."""

    @abstractmethod
    def _select_pen(self, pen: int) -> None:
        """Take pen ``pen`` from the carousel."""

    @abstractmethod
    def _device_paused(self) -> bool:
        """True while the device's own pause holds (button, VIEW, paper lever)."""

    @abstractmethod
    def _make_safe(self) -> None:
        """Stop, pen up, park, motors off — best effort on ``self.link``."""

    def _where(self) -> DeviceWhere:
        """On a fresh link before ``_connect()``: let the device settle, say where it is (if ``reports_position``)."""
        return DeviceWhere(None, None, position_lost=True,
                           detail=f"the {self.profile.name} driver cannot ask where it stopped")

    def _pen_position(self) -> tuple[float, float] | None:
        """Where the pen will be once everything sent has run (device units), the next travel's start; None: unknown."""
        return None

    def _rehomed(self) -> None:
        """The user re-homed the device after it lost its position: take where it stands as home (default: nothing)."""

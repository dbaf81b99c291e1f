"""pyserial URL handlers for simulated devices: importing this package makes ``sim://MODEL?options`` work.

Importing ``pixelpen.sim.transports.urlhandler`` appends this package to ``serial.protocol_handler_packages``;
from then on every ``serial.serial_for_url("sim://hp7475a?...")`` in the process opens the simulator (see
:mod:`pixelpen.sim.transports.urlhandler.protocol_sim` for the URL).  pixelpen's own
:class:`~pixelpen.drivers.serial.SerialLink` needs no import: it finds this package by the scheme ``sim``
in the entry-point group ``pixelpen.serial_handlers`` (``pyproject.toml``), as it finds third parties' handlers.

A third-party program that uses pyserial enables it with one line before it opens the port::

    import pixelpen.sim.transports.urlhandler          # or:
    serial.protocol_handler_packages.append("pixelpen.sim.transports.urlhandler")

and must open the port with ``serial.serial_for_url(url)`` (``serial.Serial(url)`` knows no URLs).
A program that cannot be changed can be given a pty path instead (:mod:`pixelpen.sim.transports.pty`).
"""

from __future__ import annotations

import serial

if __name__ not in serial.protocol_handler_packages:
    serial.protocol_handler_packages.append(__name__)

"""The ``pen`` command: move a plotter by hand - ``pixelpen pen up|down|toggle|home|motors-off --to URL``.

Each action opens the plotter, does one thing and closes it again, leaving the pen where the action put it
(``down`` leaves it down, to set the pen height against the paper).  ``home`` lifts the pen and drives to the
profile's home position; ``motors-off`` releases the steppers so the carriage can be pushed by hand.  What a
plotter cannot do (an HP-GL plotter has no motors-off) is an error naming the plotter and the action.
"""

from __future__ import annotations

import argparse
import sys

from pixelpen.errors import ConfigError

ACTIONS = {
    "up": ("pen_up", "pen up"),
    "down": ("pen_down", "pen down"),
    "toggle": ("toggle_pen", "pen toggled"),
    "home": ("go_home", "pen up, at home"),
    "motors-off": ("motors_off", "motors off"),
}
"""Action name -> (PlotterDisplay method, what is reported when it is done)."""


def run_pen(args: argparse.Namespace) -> int:
    """Do one manual action on the plotter at --to."""
    from pixelpen.devices.plotters.job import plotter_for

    method_name, done = ACTIONS[args.action]
    display = plotter_for(args.to)
    if not callable(getattr(display, method_name, None)):
        raise ConfigError(f"{display.profile.name} cannot do 'pen {args.action}'")
    with display:
        getattr(display, method_name)()
    print(f"{display.profile.name}: {done}", file=sys.stderr)
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``pixelpen pen`` to the ``pixelpen`` parser."""
    p = subparsers.add_parser(
        "pen", help="move the pen or the carriage by hand: up, down, toggle, home, motors-off",
        description="Open the plotter at URL, do one action and close it: up, down (left down, to set the pen "
                    "height), toggle, home (pen up, back to the home position), motors-off (push the carriage by "
                    "hand). Exit status: 0 done, 2 error.")
    p.add_argument("action", choices=list(ACTIONS), metavar="ACTION", help=", ".join(ACTIONS))
    p.add_argument("--to", required=True, metavar="URL", help="plotter URL: axidraw:auto, grbl:/dev/ttyUSB0, "
                   "sim:axidraw?id=NAME ... (default: the configuration file's)")
    p.set_defaults(func=run_pen)

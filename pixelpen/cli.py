"""The ``pixelpen`` command line: builds the argparse tree from the command modules and runs one."""

from __future__ import annotations

import argparse
import logging
import sys
from typing import Sequence

from . import __version__
from .errors import PixelpenError


def build_parser() -> argparse.ArgumentParser:
    """The parser with every subcommand registered."""
    from .commands import core, plot, sim, vector

    parser = argparse.ArgumentParser(prog="pixelpen", description="Draw on plotters, panels and files; simulate them.")
    parser.add_argument("--version", action="version", version=f"pixelpen {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="-v for progress details, -vv for wire traffic")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    core.register(sub)
    vector.register(sub)
    plot.register(sub)
    sim.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; errors print one clear line to stderr and give exit status 2."""
    parser = build_parser()
    args = parser.parse_args(argv)
    level = {0: logging.WARNING, 1: logging.INFO}.get(args.verbose, logging.DEBUG)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    try:
        return int(args.func(args) or 0)
    except PixelpenError as exc:
        print(f"pixelpen {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into `head` and the like: stop quietly
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print(f"pixelpen {args.command}: interrupted; devices were left safe", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())

"""The ``pixelpen`` command line: builds the argparse tree from the command modules and runs one.

Messages: warnings print as ``warning: TEXT`` (a warning repeated word for word prints once, and a count of
the repeats follows at the end), progress details with ``-v``; ``-vv`` prints every record with its level and
logger name, and the wire traffic.  A mistyped command or option gets the usage of the command it was given
to and the nearest known spelling.  Defaults come from the user configuration file (:mod:`pixelpen.config`).
"""

from __future__ import annotations

import argparse
import difflib
import logging
import sys
from collections.abc import Sequence
from typing import Any

from pixelpen import __version__
from pixelpen.config import drop_configured, load_config
from pixelpen.errors import PixelpenError

SHOWN_CHARS = 80
"""Characters of a repeated warning quoted in the count of its repeats."""


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors name the nearest known spelling of a mistyped choice or option."""

    def _check_value(self, action: argparse.Action, value: Any) -> None:
        try:
            super()._check_value(action, value)
        except argparse.ArgumentError as exc:
            if action.choices is None:
                raise
            raise argparse.ArgumentError(action, str(exc).partition(": ")[2] + _did_you_mean(
                str(value), [str(c) for c in action.choices])) from None

    def unrecognized(self, extras: Sequence[str]) -> None:
        """Exit with this parser's usage and the arguments it did not know, with the nearest option names."""
        known = [s for a in self._actions for s in a.option_strings]
        hints = [_did_you_mean(arg.partition("=")[0], known).strip() for arg in extras if arg.startswith("-")]
        self.error(f"unrecognized arguments: {' '.join(extras)}" + "".join(f" {h}" for h in hints if h))


def _did_you_mean(word: str, choices: Sequence[str]) -> str:
    close = difflib.get_close_matches(word, choices, n=1, cutoff=0.6)
    return f" (did you mean {close[0]}?)" if close else ""


def build_parser() -> Parser:
    """The parser with every subcommand registered (``parser.commands`` maps names to their parsers)."""
    from pixelpen.commands import core, hid, pen, plot, record, render, show, sim, udev, vector

    parser = Parser(prog="pixelpen", description="Draw on plotters, panels and files; simulate them.")
    parser.add_argument("--version", action="version", version=f"pixelpen {__version__}")
    parser.add_argument(
        "-v", "--verbose", action="count", default=0, help="-v for progress details, -vv for wire traffic"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    core.register(sub)
    vector.register(sub)
    plot.register(sub)
    pen.register(sub)
    sim.register(sub)
    show.register(sub)
    render.register(sub)
    hid.register(sub)
    udev.register(sub)
    record.register(sub)
    parser.commands = dict(sub.choices)  # type: ignore[attr-defined]
    return parser


class UserFormatter(logging.Formatter):
    """Plain lines for the user: the message, with ``warning:`` or ``error:`` in front where it is one."""

    def format(self, record: logging.LogRecord) -> str:
        text = record.getMessage()
        if record.exc_info:
            text += ": " + str(record.exc_info[1])
        return f"{record.levelname.lower()}: {text}" if record.levelno >= logging.WARNING else text


class RepeatFilter(logging.Filter):
    """Let a message through once; count its word-for-word repeats for :meth:`summary`."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: dict[tuple[int, str], int] = {}

    def filter(self, record: logging.LogRecord) -> bool:
        key = (record.levelno, record.getMessage())
        self.seen[key] = self.seen.get(key, 0) + 1
        return self.seen[key] == 1

    def summary(self) -> list[str]:
        """One line per message that was repeated: how often, and its start."""
        lines = []
        for (_, text), count in self.seen.items():
            if count > 1:
                shown = text if len(text) <= SHOWN_CHARS else text[: SHOWN_CHARS - 3] + "..."
                lines.append(f"({count - 1} more of: {shown})")
        return lines


def _log_handler(verbose: int) -> tuple[logging.Handler, RepeatFilter | None]:
    """A stderr handler for ``pixelpen`` records at the verbosity asked for."""
    handler = logging.StreamHandler(sys.stderr)
    if verbose >= 2:
        handler.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
        return handler, None
    handler.setFormatter(UserFormatter())
    repeats = RepeatFilter()
    handler.addFilter(repeats)
    return handler, repeats


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; errors print one clear line to stderr and give exit status 2."""
    parser = build_parser()
    try:
        appended = load_config().apply(parser.commands)  # type: ignore[attr-defined]
    except PixelpenError as exc:
        print(f"pixelpen: error in the configuration file: {exc}", file=sys.stderr)
        return 2
    try:
        args, extras = parser.parse_known_args(argv)
        if extras:
            parser.commands[args.command].unrecognized(extras)  # type: ignore[attr-defined]
    except SystemExit as exc:  # argparse printed the usage (or --help, --version)
        return 0 if exc.code is None else exc.code if isinstance(exc.code, int) else 2
    drop_configured(args, appended.get(args.command, {}))
    logger = logging.getLogger("pixelpen")
    handler, repeats = _log_handler(args.verbose)
    old_level = logger.level
    logger.setLevel({0: logging.WARNING, 1: logging.INFO}.get(args.verbose, logging.DEBUG))
    logger.addHandler(handler)
    try:
        return int(args.func(args) or 0)
    except BrokenPipeError:  # output piped into `head` and the like: stop quietly
        sys.stderr.close()
        return 0
    except (PixelpenError, OSError) as exc:  # pixelpen's, file and port errors: one line, exit status 2
        print(f"pixelpen {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"pixelpen {args.command}: interrupted; devices were left safe", file=sys.stderr)
        return 130
    finally:
        logger.removeHandler(handler)
        logger.setLevel(old_level)
        if repeats is not None and not sys.stderr.closed:
            for line in repeats.summary():
                print(line, file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())

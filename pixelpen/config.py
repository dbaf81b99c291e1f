"""The user configuration file: default device and options of the ``pixelpen`` commands (TOML).

The file is ``$PIXELPEN_CONFIG`` when that is set (an empty value means no file), else
``$XDG_CONFIG_HOME/pixelpen/config.toml``, else ``~/.config/pixelpen/config.toml``; a missing default file
is no configuration, a missing ``$PIXELPEN_CONFIG`` file is an error::

    to = "axidraw:auto"        # a key at the top: every command with that option (plot --to, pen --to)

    [plot]                     # a key in [COMMAND]: that command only, and it wins over the top
    margin = 10
    center = true
    optimize-time = 2

Keys are the long option names without ``--`` (``optimize-time`` or ``optimize_time``); a switch takes
``true``/``false`` (``optimize = false`` is ``--no-optimize``), an option a value of its type (numbers may be
TOML numbers or strings), an option taking several values a list.  The command line wins over the file; a
repeatable option given on the command line replaces the file's list.  An unknown key, a key of the wrong
type or a value the option refuses is a ParseError naming the file and the key.

Limits: the file is read up to ``MAX_CONFIG_BYTES``; tables nest one level (``[COMMAND]``) only.
"""

from __future__ import annotations

import argparse
import difflib
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pixelpen.errors import ParseError
from pixelpen.tomltext import read_toml

MAX_CONFIG_BYTES = 1 << 20
"""Largest configuration file read (1 MiB); a larger one is a ParseError."""
MAX_CONFIG_DEPTH = 32
"""Deepest nesting of arrays and inline tables read (options need 1); deeper is a ParseError."""
ENV_VAR = "PIXELPEN_CONFIG"
"""Environment variable naming the configuration file ('' for none)."""


def config_path(environ: Mapping[str, str] | None = None) -> tuple[Path | None, bool]:
    """The configuration file to read and whether it must exist (named by ``$PIXELPEN_CONFIG``)."""
    env = os.environ if environ is None else environ
    if ENV_VAR in env:
        return (Path(env[ENV_VAR]) if env[ENV_VAR] else None), True
    base = env.get("XDG_CONFIG_HOME") or str(Path(env.get("HOME") or Path.home()) / ".config")
    return Path(base) / "pixelpen" / "config.toml", False


@dataclass
class UserConfig:
    """The values of a configuration file: ``common`` at the top, ``sections`` per command."""

    source: str = ""
    common: dict[str, Any] = field(default_factory=dict)
    sections: dict[str, dict[str, Any]] = field(default_factory=dict)

    def apply(self, commands: Mapping[str, argparse.ArgumentParser]) -> dict[str, dict[str, int]]:
        """Set the commands' defaults from the file (ParseError for a bad key); the configured list lengths.

        A required option the file supplies stops being required.  The result maps each command to the
        number of values its repeatable options got from the file, for :func:`drop_configured`.
        """
        for name in self.sections:
            if name not in commands:
                raise self.error(f"[{name}]", "no such command" + _suggest(name, commands, "["))
        for key in self.common:
            if not any(_action(parser, key) for parser in commands.values()):
                known = sorted({_key(a) for p in commands.values() for a in _options(p)})
                raise self.error(key, "no command has this option" + _suggest(key, known))
        appended: dict[str, dict[str, int]] = {}
        for name, parser in commands.items():
            values = {k: v for k, v in self.common.items() if _action(parser, k)}
            section = self.sections.get(name, {})
            for key in section:
                if _action(parser, key) is None:
                    raise self.error(f"[{name}] {key}", f"'pixelpen {name}' has no option --{_dashed(key)}"
                                      + _suggest(_dashed(key), [_key(a) for a in _options(parser)]))
            values.update(section)
            defaults = {}
            for key, value in values.items():
                action = _action(parser, key)
                assert action is not None
                where = f"[{name}] {key}" if key in section else key
                defaults[action.dest] = self._convert(action, value, where)
                action.required = False
                if isinstance(action, argparse._AppendAction):
                    appended.setdefault(name, {})[action.dest] = len(defaults[action.dest])
            parser.set_defaults(**defaults)
        return appended

    def _convert(self, action: argparse.Action, value: Any, where: str) -> Any:
        """``value`` as the option's parsed value (ParseError naming ``where`` when it does not fit)."""
        flag = isinstance(action, (argparse._StoreTrueAction, argparse._StoreFalseAction,
                                   argparse.BooleanOptionalAction))
        if flag:
            if not isinstance(value, bool):
                raise self.error(where, "expected true or false", value)
            return not value if isinstance(action, argparse._StoreFalseAction) else value
        if not isinstance(action, (argparse._StoreAction, argparse._AppendAction)):
            raise self.error(where, "this option cannot be configured")
        many = isinstance(action, argparse._AppendAction) or action.nargs in ("+", "*") or isinstance(action.nargs, int)
        if many:
            items = value if isinstance(value, list) else [value]
            return [self._scalar(action, item, where) for item in items]
        if isinstance(value, list):
            raise self.error(where, "expected one value, not a list", value)
        return self._scalar(action, value, where)

    def _scalar(self, action: argparse.Action, value: Any, where: str) -> Any:
        if isinstance(value, bool) or not isinstance(value, (str, int, float)):
            raise self.error(where, "expected a string or a number", value)
        text = str(value)
        try:
            result = action.type(text) if callable(action.type) else text
        except (argparse.ArgumentTypeError, ValueError, TypeError, OverflowError) as exc:
            raise self.error(where, str(exc) or "bad value", value) from None
        if action.choices is not None and result not in action.choices:
            raise self.error(where, "expected one of " + ", ".join(map(str, action.choices)), value)
        return result

    def error(self, key: str, message: str, value: object = None) -> ParseError:
        """The ParseError for a bad ``key`` of this file, naming the file, the key and the value."""
        return ParseError(f"{key}: {message}", source=self.source, token=value)


def drop_configured(args: argparse.Namespace, appended: Mapping[str, int]) -> None:
    """Make a repeatable option given on the command line replace the file's values instead of adding to them."""
    for dest, count in appended.items():
        values = getattr(args, dest, None)
        if isinstance(values, list) and len(values) > count:
            setattr(args, dest, values[count:])


def load_config(path: Path | None = None, *, required: bool = False) -> UserConfig:
    """Read a configuration file (default: :func:`config_path`); an empty UserConfig when there is none."""
    if path is None:
        path, required = config_path()
    if path is None:
        return UserConfig()
    source = str(path)
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_CONFIG_BYTES + 1)
    except FileNotFoundError:
        if required:
            raise ParseError(f"no such file (named by ${ENV_VAR})", source=source) from None
        return UserConfig(source)
    except OSError as exc:
        raise ParseError(f"cannot read the configuration: {exc.strerror or exc}", source=source) from None
    if len(data) > MAX_CONFIG_BYTES:
        raise ParseError(f"a configuration file is at most {MAX_CONFIG_BYTES} bytes", source=source)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ParseError("not UTF-8 text", source=source, offset=exc.start) from None
    table = read_toml(text, source, max_depth=MAX_CONFIG_DEPTH)
    config = UserConfig(source)
    for key, value in table.items():
        if isinstance(value, dict):
            for inner, item in value.items():
                if isinstance(item, dict):
                    raise config.error(f"[{key}] {inner}", "a [COMMAND] section holds options, not tables")
            config.sections[key] = dict(value)
        else:
            config.common[key] = value
    return config


def _dashed(key: str) -> str:
    return key.replace("_", "-")


def _key(action: argparse.Action) -> str:
    long = [s for s in action.option_strings if s.startswith("--")]
    return (long[0] if long else action.option_strings[0]).lstrip("-")


def _options(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """The parser's configurable options (not positionals, help or version)."""
    skip = (argparse._HelpAction, argparse._VersionAction)
    return [a for a in parser._actions if a.option_strings and not isinstance(a, skip)]


def _action(parser: argparse.ArgumentParser, key: str) -> argparse.Action | None:
    """The option ``--KEY`` of ``parser`` (underscores or dashes alike)."""
    wanted = "--" + _dashed(key)
    for action in _options(parser):
        boolean = isinstance(action, argparse.BooleanOptionalAction)
        names = action.option_strings[:1] if boolean else action.option_strings
        if wanted in names:
            return action
    return None


def _suggest(word: str, choices: Any, prefix: str = "") -> str:
    close = difflib.get_close_matches(word, list(choices), n=1)
    return f" (did you mean {prefix}{close[0]}{']' if prefix == '[' else ''}?)" if close else ""

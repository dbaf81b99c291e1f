"""URL options declared once: ``OptionSpec(name, convert, default, help)``, the shared converters, one reader.

Every display, simulator and transport lists its options as specs.  The same specs read a URL's
options (``read_options``: unknown names refused with the known ones and a "did you mean", bad values
named with the option and the URL), and document them (``pixelpen devices`` prints ``describe``).
A converter takes the option's text and returns its value or raises ``ValueError`` saying what it
expected; the reader turns that into a ``URLError`` naming the URL and the option.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from pixelpen.colour import parse_colour
from pixelpen.errors import ConfigError, PixelpenError, URLError, quote_token
from pixelpen.urls import parse_size

T = TypeVar("T")
Converter = Callable[[str], T]

_NESTED_PORT_OPTIONS = frozenset({"logging", "timeout", "baudrate"})
"""pyserial URL options that, found among a device URL's own, mean the port URL was not bracketed."""


@dataclass(frozen=True)
class OptionSpec(Generic[T]):
    """One URL option: its name, how its text becomes a value, the value when it is absent, and a help line."""

    name: str
    convert: Converter[T]
    default: T
    help: str

    def read(self, raw: str, where: str) -> T:
        """Convert ``raw``; a bad value raises URLError naming ``where``, the option and what was expected."""
        try:
            return self.convert(raw)
        except (ValueError, TypeError, ConfigError) as exc:
            raise URLError(f"{where}: option {self.name}={quote_token(raw)} is not valid: {exc}") from None


class OptionValues(Mapping[str, Any]):
    """The options of one URL read against their specs: every spec's value, and which were given."""

    def __init__(self, values: dict[str, Any], given: frozenset[str]) -> None:
        self._values = values
        self.given = given
        """Names the URL set explicitly (the others hold their defaults)."""

    def __getitem__(self, name: str) -> Any:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)


def read_options(specs: Iterable[OptionSpec[Any]], options: Mapping[str, str], where: str) -> OptionValues:
    """Read ``options`` (name -> text) against ``specs``; unknown names or bad values raise URLError naming where."""
    by_name = {spec.name: spec for spec in specs}
    check_known(by_name, options, where)
    values = {name: spec.read(str(options[name]), where) if name in options else spec.default
              for name, spec in by_name.items()}
    return OptionValues(values, frozenset(options))


def check_known(known: Iterable[str], options: Iterable[str], where: str, *, kind: str = "option",
                error: type[PixelpenError] = URLError) -> None:
    """Refuse names not in ``known`` (URL options, or the keys of a dict argument: ``kind="key"``), listing the
    known ones and the closest match."""
    names = sorted(set(known))
    unknown = sorted(set(options) - set(names))
    if not unknown:
        return
    import difflib  # only an error needs it

    hint = ""
    close = difflib.get_close_matches(unknown[0], names, n=1)
    if close:
        hint = f" (did you mean {close[0]!r}?)"
    elif _NESTED_PORT_OPTIONS & set(unknown) or "://" in where:
        hint = " (options of a nested port URL go inside brackets: scheme:[rfc2217://host:port?logging=debug])"
    raise error(f"{where}: unknown {kind}(s) {', '.join(unknown)}; known: {', '.join(names) or 'none'}{hint}")


def describe(specs: Iterable[OptionSpec[Any]]) -> list[tuple[str, str]]:
    """(name, help with the default) pairs for documentation, in declaration order."""
    rows = []
    for spec in specs:
        value = spec.default
        if type(value) in (tuple, list):  # a tuple subclass (urls.Size) prints its own URL form
            value = ",".join(str(v) for v in value)
        default = "" if value is None or value == "" else f" (default {value})"
        rows.append((spec.name, spec.help + default))
    return rows


# -- converters ---------------------------------------------------------------------------------------


def text(value: str) -> str:
    """Any text, as given."""
    return value


def boolean(value: str) -> bool:
    """1/0, true/false, yes/no, on/off."""
    low = value.strip().lower()
    if low in {"1", "true", "yes", "on"}:
        return True
    if low in {"0", "false", "no", "off"}:
        return False
    raise ValueError(f"expected true/false, got {quote_token(value)}")


def integer(minimum: int | None = None, maximum: int | None = None) -> Converter[int]:
    """A converter to an integer in [minimum, maximum] (either bound optional)."""

    def convert(value: str) -> int:
        stripped = value.strip()
        if not stripped.lstrip("+-").isascii() or not stripped.lstrip("+-").isdigit() or len(stripped) > 20:
            raise ValueError(_expected("an integer", minimum, maximum))
        number = int(stripped)
        if (minimum is not None and number < minimum) or (maximum is not None and number > maximum):
            raise ValueError(_expected("an integer", minimum, maximum))
        return number

    return convert


def number(minimum: float | None = None, maximum: float | None = None, *, above: bool = False) -> Converter[float]:
    """A converter to a finite number in [minimum, maximum]; ``above=True`` excludes the minimum itself."""

    def convert(value: str) -> float:
        try:
            result = float(value)
        except ValueError:
            result = math.nan
        low_ok = minimum is None or (result > minimum if above else result >= minimum)
        if not (math.isfinite(result) and low_ok and (maximum is None or result <= maximum)):
            raise ValueError(_expected("a finite number", minimum, maximum, above=above))
        return result

    return convert


positive = number(0.0, above=True)
"""A finite number > 0."""

non_negative = number(0.0)
"""A finite number >= 0."""


def choice(*allowed: str) -> Converter[str]:
    """A converter to one of ``allowed`` (case-insensitive; returns the allowed spelling)."""
    lookup = {a.lower(): a for a in allowed}

    def convert(value: str) -> str:
        try:
            return lookup[value.strip().lower()]
        except KeyError:
            raise ValueError(f"expected one of {', '.join(allowed)}") from None

    return convert


I2C_ADDRESSES = range(0x08, 0x78)
"""The 7-bit I2C addresses a device may have (0x00..0x07 and 0x78..0x7f are reserved)."""


def pixels(value: str) -> tuple[int, int]:
    """A size in whole pixels, ``WxH`` (``128x64``)."""
    size = parse_size(value)  # its InvalidArgument is a ValueError: the option reader names the option
    if size.unit != "px" or size.width != int(size.width) or size.height != int(size.height):
        raise ValueError(f"expected WIDTHxHEIGHT in whole pixels, got {quote_token(value)}")
    return int(size.width), int(size.height)


def i2c_address(value: str) -> int:
    """A 7-bit I2C address 0x08..0x77, decimal or 0x hex (``0x3c``)."""
    try:
        address = int(value.strip(), 0)
    except ValueError:
        raise ValueError("expected an I2C address such as 0x3c") from None
    if address not in I2C_ADDRESSES:
        raise ValueError("expected a 7-bit I2C address 0x08..0x77 (0x00..0x07 and 0x78..0x7f are reserved)")
    return address


def colour(value: str) -> str:
    """A colour name or #rrggbb form (checked; returned as given)."""
    parse_colour(value)
    return value


def _expected(what: str, minimum: float | None, maximum: float | None, *, above: bool = False) -> str:
    """'expected an integer >= 1' and the like."""
    if minimum is not None and maximum is not None:
        return f"expected {what} in {'(' if above else '['}{minimum:g}, {maximum:g}]"
    if minimum is not None:
        return f"expected {what} {'>' if above else '>='} {minimum:g}"
    if maximum is not None:
        return f"expected {what} <= {maximum:g}"
    return f"expected {what}"

"""The device URL grammar, parsed in one place.

    URL     := scheme ":" target [ "?" options ]
    target  := "[" nested-url "]" | text-without-"?"
    options := key "=" value { "&" key "=" value }     (a bare key means "true")

The scheme names a device model, a file type or ``sim``.  A target that is itself a URL
with its own query (a pyserial URL such as ``rfc2217://host:4000?logging=debug``) is
enclosed in square brackets, so the two queries never mix::

    hp7475a:[rfc2217://plotter-host:4000?logging=debug]?paper=a3
    hp7475a:/dev/ttyUSB0?baud=9600&paper=a4
    sim:hp7475a?paper=a4
    png:out/scene.png?size=800x600

Brackets nest, so ``[socket://[::1]:4000]`` keeps its IPv6 brackets.  Values are
percent-decoded (as UTF-8; an undecodable byte is an error naming the option).  A target without
brackets ends at the first ``?``.

Limits: a URL of at most :data:`MAX_URL` characters; sizes of at most :data:`MAX_SIZE` in any unit;
file names (:func:`check_path`) without NUL, at most :data:`MAX_NAME` bytes per component and
:data:`MAX_PATH` bytes in all (module attributes, read at call time).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple, TypeVar
from urllib.parse import quote, unquote

from pixelpen.errors import ConfigError, InvalidArgument, URLError, quote_token

T = TypeVar("T")

MAX_URL = 65536
"""Characters of a device URL."""
MAX_SIZE = 1e7
"""Largest width or height a size option may give (in its own unit)."""
MAX_NAME = 255
"""Bytes of one file-name component (NAME_MAX of Linux, macOS and Windows)."""
MAX_PATH = 4096
"""Bytes of a whole file name (PATH_MAX of Linux)."""


@dataclass(frozen=True)
class DeviceURL:
    """A parsed device URL: scheme, target and the options given after ``?``."""

    scheme: str
    target: str
    options: Mapping[str, str] = field(default_factory=dict)
    text: str = ""

    def __str__(self) -> str:
        return self.text or format_url(self.scheme, self.target, self.options)


def parse_url(url: str) -> DeviceURL:
    """Split ``scheme:target?options`` into its parts (see the module docstring)."""
    if not isinstance(url, str) or not url:
        raise URLError(f"a device URL must be a non-empty string like 'svg:out.svg', got {quote_token(url)}")
    if len(url) > MAX_URL:
        raise URLError(f"a device URL of {len(url)} characters is longer than {MAX_URL}: {quote_token(url)}")
    try:
        url.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise URLError(f"{quote_token(url)}: character {exc.start} is a lone surrogate, not text") from None
    scheme, sep, rest = url.partition(":")
    if not sep or not scheme:
        raise URLError(f"{url!r}: expected 'scheme:target', e.g. 'png:out.png' or 'sim:hp7475a'")
    if not scheme.replace("-", "").replace("_", "").replace(".", "").isalnum():
        raise URLError(f"{url!r}: scheme {scheme!r} may hold only letters, digits, '-', '_' and '.'")
    scheme = scheme.lower()
    if rest.startswith("["):
        end = _matching_bracket(rest, url)
        target, tail = rest[1:end], rest[end + 1 :]
        if tail and not tail.startswith("?"):
            raise URLError(f"{url!r}: after ']' expected '?options' or the end, found {tail!r}")
        query = tail[1:]
    else:
        raw_target, _, query = rest.partition("?")
        target = _decode(raw_target, "the target", url)
    return DeviceURL(scheme, target, _parse_query(query, url), url)


def _matching_bracket(rest: str, url: str) -> int:
    depth = 0
    for i, ch in enumerate(rest):
        if ch == "[":
            depth += 1
        elif ch == "]":
            depth -= 1
            if depth == 0:
                return i
    raise URLError(f"{url!r}: '[' at the start of the target has no matching ']'")


def _parse_query(query: str, url: str) -> dict[str, str]:
    options: dict[str, str] = {}
    if not query:
        return options
    for part in query.split("&"):
        if not part:
            continue
        key, eq, value = part.partition("=")
        key = _decode(key, f"option name {key!r}", url).strip().lower()
        if not key:
            raise URLError(f"{url!r}: empty option name in {part!r}")
        if key in options:
            raise URLError(f"{url!r}: option {key!r} given twice")
        options[key] = _decode(value, f"option {key!r}", url) if eq else "true"
    return options


def _decode(text: str, what: str, url: str) -> str:
    """Percent-decode ``text`` as UTF-8; an undecodable byte is a URLError naming ``what``."""
    try:
        return unquote(text, errors="strict")
    except UnicodeDecodeError as exc:
        raise URLError(
            f"{quote_token(url)}: {what} holds percent-encoded bytes that are not UTF-8 ({exc.reason})"
        ) from None


def check_path(path: str | os.PathLike[str], what: str) -> Path:
    """``path`` as a Path, or a ConfigError naming ``what`` when no file system could take the name.

    Refused: NUL characters, a component longer than MAX_NAME bytes, a name longer than MAX_PATH bytes,
    characters that cannot be encoded for the file system.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise ConfigError(f"{what} must be a file name, got {type(path).__name__}")
    text = os.fspath(path)
    if not isinstance(text, str):
        raise ConfigError(f"{what} must be a text file name, got {type(text).__name__}")
    if not text:
        raise ConfigError(f"{what} is empty: give a file name")
    if "\x00" in text:
        raise ConfigError(f"{what} {quote_token(text)} contains a NUL character at index {text.index(chr(0))}")
    try:
        encoded = os.fsencode(text)
    except UnicodeEncodeError as exc:
        raise ConfigError(f"{what} {quote_token(text)} cannot be encoded for the file system: {exc.reason}") from None
    if len(encoded) > MAX_PATH:
        raise ConfigError(f"{what} is {len(encoded)} bytes long, more than the {MAX_PATH} a file system takes")
    longest = max(encoded.replace(b"\\", b"/").split(b"/"), key=len)
    if len(longest) > MAX_NAME:
        raise ConfigError(f"{what} has a component of {len(longest)} bytes, more than the {MAX_NAME} a file system "
                          f"takes: {quote_token(longest.decode(errors='replace'))}")
    return Path(text)


def format_url(scheme: str, target: str, options: Mapping[str, object] | None = None) -> str:
    """Build a URL string that :func:`parse_url` reads back to the same parts."""
    if ("?" in target or target.startswith("[")) and _balanced(target):
        text = f"{scheme}:[{target}]"
    else:
        text = f"{scheme}:" + quote(target, safe="/:@.-_~,=+;!$'()*\\ ")
    if options:
        text += "?" + "&".join(f"{quote(str(k))}={quote(str(v), safe='/:.,-_x')}" for k, v in options.items())
    return text


def _balanced(text: str) -> bool:
    """True when ``[text]`` reads back as one bracketed target (brackets nest and close within it)."""
    depth = 0
    for ch in text:
        depth += (ch == "[") - (ch == "]")
        if depth < 0:
            return False
    return depth == 0


_MM_PER = {"mm": 1.0, "cm": 10.0, "in": 25.4, "pt": 25.4 / 72, "px": 25.4 / 96}
PAPER_MM = {
    "a5": (148.0, 210.0), "a4": (210.0, 297.0), "a3": (297.0, 420.0), "a2": (420.0, 594.0),
    "letter": (215.9, 279.4), "a": (215.9, 279.4), "tabloid": (279.4, 431.8), "b": (279.4, 431.8),
}


class Size(NamedTuple):
    """A width and height in a unit, as ``parse_size`` reads them; prints in the URL form (``210x297mm``)."""

    width: float
    height: float
    unit: str

    def __str__(self) -> str:
        return f"{self.width:g}x{self.height:g}{'' if self.unit == 'px' else self.unit}"

    def mm(self) -> tuple[float, float]:
        """Width and height in millimetres."""
        return to_mm(self.width, self.unit), to_mm(self.height, self.unit)


def parse_size(text: str, default_unit: str = "px") -> Size:
    """Read ``WxH[unit]`` (``800x600``, ``210x297mm``) or a paper name (``a4``) as (w, h, unit)."""
    low = text.strip().lower()
    if low in PAPER_MM:
        w, h = PAPER_MM[low]
        return Size(w, h, "mm")
    unit = default_unit
    for u in _MM_PER:
        if low.endswith(u):
            unit, low = u, low[: -len(u)]
            break
    w_text, sep, h_text = low.partition("x")
    if not sep:
        raise InvalidArgument(f"expected WIDTHxHEIGHT[unit] or a paper name ({', '.join(PAPER_MM)}), got {text!r}")
    try:
        w, h = float(w_text), float(h_text)
    except ValueError:
        raise InvalidArgument(f"expected WIDTHxHEIGHT[unit] with numbers for WIDTH and HEIGHT, got {text!r}") from None
    if not (0 < w <= MAX_SIZE and 0 < h <= MAX_SIZE):
        raise InvalidArgument(f"size must be positive and at most {MAX_SIZE:g}, got {text!r}")
    return Size(w, h, unit)


def to_mm(value: float, unit: str) -> float:
    """Convert a length in ``unit`` (mm, cm, in, pt, px at 96 dpi) to millimetres."""
    return value * _MM_PER[unit]

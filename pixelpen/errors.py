"""The one exception hierarchy of pixelpen: every error a user can meet derives from PixelpenError."""

from __future__ import annotations

import reprlib
from pathlib import Path

TOKEN_CHARS = 120
"""Characters of a quoted token an error message shows at most (the token itself is kept whole on the error)."""


class _TokenRepr(reprlib.Repr):
    """reprlib with integers too long to print (Python refuses 4300 digits) shown by their size."""

    def repr_int(self, x: int, level: int) -> str:
        if x.bit_length() > 1000:
            return f"<integer of about {int(x.bit_length() * 0.30103) + 1} digits>"
        return super().repr_int(x, level)


_QUOTE = _TokenRepr()
_QUOTE.maxlevel = 3
_QUOTE.maxstring = _QUOTE.maxother = TOKEN_CHARS
_QUOTE.maxlist = _QUOTE.maxtuple = _QUOTE.maxdict = _QUOTE.maxset = 6


def quote_token(value: object, limit: int = TOKEN_CHARS) -> str:
    """A short repr of ``value`` for an error message: depth, length and size bounded, never recursing deeply."""
    text = _QUOTE.repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


class PixelpenError(Exception):
    """Base of every error pixelpen raises on purpose."""


class ConfigError(PixelpenError, ValueError):
    """A setting, option or profile value is missing, unknown or out of range."""


class InvalidArgument(PixelpenError, ValueError):
    """An argument of a library call has a bad value (NaN or inf, out of range, a degenerate rectangle)."""


class InvalidArgumentType(PixelpenError, TypeError):
    """An argument of a library call has the wrong type."""


class URLError(ConfigError):
    """A device URL could not be understood (unknown scheme, bad option, bad target)."""


class ParseError(PixelpenError, ValueError):
    """Input text or bytes are malformed; says where (source, line/column or byte offset) and what."""

    def __init__(
        self,
        message: str,
        *,
        source: str | None = None,
        line: int | None = None,
        column: int | None = None,
        offset: int | None = None,
        token: object = None,
    ) -> None:
        self.message = message
        self.source = source
        self.line = line
        self.column = column
        self.offset = offset
        self.token = token
        super().__init__(self._format())

    def _format(self) -> str:
        where = []
        if self.source:
            where.append(str(self.source))
        if self.line is not None:
            where.append(f"line {self.line}" + (f", column {self.column}" if self.column is not None else ""))
        if self.offset is not None:
            where.append(f"byte offset {self.offset}")
        text = self.message
        if self.token is not None:
            text += f" (found {quote_token(self.token)})"
        return f"{': '.join([', '.join(where), text]) if where else text}"


class ProtocolError(PixelpenError):
    """A device answered with an error: carries the device's own code and the command that caused it."""

    def __init__(self, message: str, *, code: object = None, command: object = None, device: str | None = None) -> None:
        self.code = code
        self.command = command
        self.device = device
        parts = [message]
        if code is not None:
            parts.append(f"device code {code}")
        if command is not None:
            parts.append(f"command {command!r}")
        prefix = f"{device}: " if device else ""
        super().__init__(prefix + "; ".join(parts))


class LinkError(PixelpenError, OSError):
    """The transport failed: timeout, disconnect, a port that cannot be opened."""


class LinkTimeout(LinkError, TimeoutError):
    """A read or write did not complete within its timeout."""


class Disconnected(LinkError, ConnectionError):
    """The device went away (unplugged, link dropped, power lost)."""


class TraceMismatch(LinkError):
    """A replayed trace diverged from what the program sent: says at which byte."""


class PlotInterrupted(PixelpenError):
    """A plot stopped on a fault; ``resume_from`` is the first stroke the device did not confirm."""

    def __init__(
        self, message: str, *, resume_from: int, state_file: Path | None, cause: BaseException | None = None
    ) -> None:
        self.resume_from = resume_from
        self.state_file = state_file
        self.cause = cause
        where = f"; state saved to {state_file} (plot again with --resume)" if state_file else ""
        super().__init__(f"{message}; {resume_from} strokes were confirmed{where}")


class DeviceFault(PlotInterrupted, ProtocolError):
    """The device reported an error during a plot: a ProtocolError (``code``, ``command``) the plot resumes from."""

    def __init__(self, error: ProtocolError, *, resume_from: int, state_file: Path | None) -> None:
        PlotInterrupted.__init__(self, f"plot stopped by a device error: {error}", resume_from=resume_from,
                                 state_file=state_file, cause=error)
        self.code, self.command, self.device = error.code, error.command, error.device


class PositionUnknown(PixelpenError):
    """Where the device stopped cannot be told; ``resume_from`` is where a confirmed resume restarts."""

    def __init__(self, message: str, *, resume_from: int, strokes: range) -> None:
        self.resume_from = resume_from
        self.strokes = strokes
        super().__init__(message)

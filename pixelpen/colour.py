"""Colour values: every CSS/SVG colour name and the #rgb, #rrggbb and rgb()/hsl() forms, read into (r, g, b)."""

from __future__ import annotations

from numbers import Integral

from PIL import ImageColor

from pixelpen.errors import ConfigError, quote_token

RGB = tuple[int, int, int]

NAMED_COLOURS: dict[str, RGB] = {name: ImageColor.getrgb(value)[:3] for name, value in ImageColor.colormap.items()}
"""The 148 CSS Color Module Level 3 names (SVG 1.1's keywords), from Pillow's table, not a hand-kept list."""

_MAX_TEXT = 64
"""Longer colour text is refused before parsing (the longest valid form, ``hsl(...)`` with spaces, is far shorter)."""


def parse_colour(colour: object) -> RGB:
    """Read a CSS colour name, ``#rgb``/``#rrggbb``, ``rgb()``/``hsl()`` text or an (r, g, b) tuple of 0-255."""
    if isinstance(colour, str):
        text = colour.strip().lower()
        if len(text) <= _MAX_TEXT:
            try:
                value = ImageColor.getrgb(text)
            except ValueError:
                pass
            else:
                if len(value) == 3:
                    return (int(value[0]), int(value[1]), int(value[2]))
        raise ConfigError(
            f"unknown colour {quote_token(colour)}: use a CSS colour name (such as 'red' or 'steelblue'), "
            "#rgb, #rrggbb or rgb(r, g, b)"
        )
    if isinstance(colour, (tuple, list)) and len(colour) == 3 and all(_is_byte(c) for c in colour):
        return (int(colour[0]), int(colour[1]), int(colour[2]))
    raise ConfigError(f"colour must be a name, '#rrggbb' or (r, g, b) in 0..255, got {quote_token(colour)}")


def _is_byte(value: object) -> bool:
    """An integer (numpy's too, not a bool) in 0..255."""
    return isinstance(value, Integral) and not isinstance(value, bool) and 0 <= int(value) <= 255


def colour_hex(rgb: RGB) -> str:
    """Format an (r, g, b) colour as ``#rrggbb``."""
    return "#{:02x}{:02x}{:02x}".format(*rgb)

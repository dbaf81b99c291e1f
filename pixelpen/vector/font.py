"""Single-stroke vector text with the Hershey fonts: glyph strokes laid out, aligned, slanted and rotated."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from functools import cache, lru_cache
from importlib import resources
from typing import NamedTuple

import numpy as np

from pixelpen import geometry as geo
from pixelpen.errors import ConfigError, ParseError

log = logging.getLogger(__name__)

FONT_FILE = "hershey.txt"
_ALIGNS = ("left", "center", "right")
_VALIGNS = ("bottom", "baseline", "middle", "top")


@dataclass(frozen=True)
class Glyph:
    """One glyph in font units (x right, y down as in Hershey's data): side bearings and strokes."""

    left: int
    right: int
    points: np.ndarray
    """(P, 2) vertices of all strokes, concatenated."""
    offsets: np.ndarray
    """Stroke ``i`` is ``points[offsets[i]:offsets[i+1]]``."""


@dataclass(frozen=True)
class Font:
    """A Hershey font: glyphs by character, and its cap line, baseline and descender line in font units."""

    name: str
    description: str
    cap: int
    base: int
    bottom: int
    glyphs: dict[str, Glyph]

    @property
    def cap_height(self) -> int:
        """Height of a capital letter in font units."""
        return self.base - self.cap


class TextExtent(NamedTuple):
    """The layout box of a text: width and height in world units and its corners in world coordinates."""

    width: float
    height: float
    corners: np.ndarray
    """(4, 2) bottom-left, bottom-right, top-right, top-left of the box after alignment, rotation, placement."""


def decode_glyph(code: str, source: str = "glyph", line: int | None = None) -> Glyph:
    """Decode one glyph in the Hershey character-pair encoding (``ord(c) - ord('R')``, ``" R"`` = pen up)."""
    if len(code) < 2 or len(code) % 2:
        raise ParseError(
            "a Hershey glyph needs an even number (>= 2) of characters", source=source, line=line, token=code
        )
    if not all(" " <= ch <= "~" for ch in code):
        raise ParseError("a Hershey glyph holds printable ASCII characters only", source=source, line=line, token=code)
    vals = np.frombuffer(code.encode("ascii"), dtype=np.uint8).astype(np.int64) - ord("R")
    pairs = vals.reshape(-1, 2)
    left, right = int(pairs[0, 0]), int(pairs[0, 1])
    body = pairs[1:]
    pen_up = (body[:, 0] == ord(" ") - ord("R")) & (body[:, 1] == 0)
    if len(body) and (pen_up[0] or pen_up[-1]):
        raise ParseError("a Hershey glyph cannot start or end with a pen-up", source=source, line=line, token=code)
    breaks = np.flatnonzero(pen_up)
    if np.any(np.diff(breaks) == 1):
        raise ParseError("a Hershey glyph has two pen-ups in a row", source=source, line=line, token=code)
    points = body[~pen_up].astype(np.float64)
    # stroke starts: index into points after removing the pen-up pairs
    starts = breaks - np.arange(len(breaks))
    offsets = np.concatenate([[0], starts, [len(points)]]).astype(np.int64) if len(points) else np.zeros(1, np.int64)
    points.setflags(write=False)
    return Glyph(left, right, points, offsets)


def parse_fonts(text: str, source: str = FONT_FILE, first_line: int = 1) -> dict[str, Font]:
    """Read pixelpen's font file (see ``pixelpen/data/fonts/README.md``) into fonts by name."""
    fonts: dict[str, Font] = {}
    current: dict | None = None
    for number, raw in enumerate(text.splitlines(), start=first_line):
        line = raw.rstrip()
        if not line or line.startswith("#"):
            continue
        if line.startswith("font "):
            parts = line.split(" ", 5)
            if len(parts) < 5:
                raise ParseError(
                    "a font line reads 'font NAME cap=C base=B bottom=D DESCRIPTION'",
                    source=source,
                    line=number,
                    token=line,
                )
            metrics = {}
            for item in parts[2:5]:
                key, _, value = item.partition("=")
                try:
                    metrics[key] = int(value)
                except ValueError:
                    raise ParseError(
                        f"font metric {key!r} must be an integer", source=source, line=number, token=item
                    ) from None
            if set(metrics) != {"cap", "base", "bottom"} or not metrics["cap"] < metrics["base"] <= metrics["bottom"]:
                raise ParseError("a font needs cap < base <= bottom", source=source, line=number, token=line)
            current = {"name": parts[1], "description": parts[5] if len(parts) > 5 else "", **metrics, "glyphs": {}}
            if parts[1] in fonts:
                raise ParseError(f"font {parts[1]!r} is defined twice", source=source, line=number)
            fonts[parts[1]] = current  # type: ignore[assignment]
            continue
        if current is None:
            raise ParseError("a glyph line before any 'font' line", source=source, line=number, token=line)
        hexcode, sep, code = line.partition(" ")
        try:
            char = chr(int(hexcode, 16))
        except (ValueError, OverflowError):
            raise ParseError(
                "a glyph line starts with a hex code point", source=source, line=number, token=hexcode
            ) from None
        if not sep:
            raise ParseError("a glyph line reads 'XXXX GLYPH'", source=source, line=number, token=line)
        current["glyphs"][char] = decode_glyph(code, source, number)
    out = {}
    for name, f in fonts.items():
        data: dict = f  # type: ignore[assignment]
        if not data["glyphs"]:
            raise ParseError(f"font {name!r} has no glyphs", source=source)
        out[name] = Font(**data)
    return out


SHIPPED_SOURCE = f"pixelpen/data/fonts/{FONT_FILE}"


@lru_cache(maxsize=1)
def _shipped_sections() -> dict[str, tuple[int, str]]:
    """The shipped file split into fonts: name -> (first line number, text), so fonts are decoded on demand."""
    shipped = resources.files("pixelpen").joinpath("data").joinpath("fonts").joinpath(FONT_FILE)
    lines = shipped.read_text(encoding="ascii").splitlines()
    starts = [i for i, line in enumerate(lines) if line.startswith("font ")]
    return {
        lines[a].split(" ", 2)[1]: (a + 1, "\n".join(lines[a:b]))
        for a, b in zip(starts, [*starts[1:], len(lines)], strict=False)
    }


def font_names() -> list[str]:
    """Names of the shipped fonts (``futural`` first: the default Roman simplex)."""
    return list(_shipped_sections())


@cache
def load_font(name: str) -> Font:
    """The shipped font called ``name`` (ConfigError naming the available fonts otherwise)."""
    sections = _shipped_sections()
    if name not in sections:
        raise ConfigError(f"unknown font {name!r}; fonts: {', '.join(sections)}")
    first_line, text = sections[name]
    return parse_fonts(text, SHIPPED_SOURCE, first_line)[name]


def _replacement(font: Font) -> Glyph:
    """A box with both diagonals from baseline to cap line, drawn for characters the font lacks."""
    half = font.cap_height // 3
    c, b = font.cap, font.base
    box = [[-half, b], [half, b], [half, c], [-half, c], [-half, b], [half, c]]
    pts = np.array([*box, [half, b], [-half, c]], dtype=np.float64)
    return Glyph(-half - 4, half + 4, pts, np.array([0, 6, 8], dtype=np.int64))


class _Layout(NamedTuple):
    glyphs: list[Glyph]
    pen_x: np.ndarray  # x of each glyph's origin (left bearing at 0), font units x spacing, before alignment
    line_of: np.ndarray  # line index of each glyph
    line_widths: np.ndarray  # font units x spacing


def _layout(text: str, font: Font, spacing: float) -> _Layout:
    """Place glyphs along lines in font units; unknown characters become a box, with one warning per call."""
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    glyphs: list[Glyph] = []
    line_of: list[int] = []
    widths = np.zeros(len(lines))
    missing: set[str] = set()
    for i, line in enumerate(lines):
        for ch in line:
            g = font.glyphs.get(ch)
            if g is None:
                missing.add(ch)
                g = _replacement(font)
            glyphs.append(g)
            line_of.append(i)
    if missing:
        log.warning(
            "font %s has no glyph for %s; drawn as a box",
            font.name,
            ", ".join(f"{c!r} (U+{ord(c):04X})" for c in sorted(missing)),
        )
    advance = np.array([g.right - g.left for g in glyphs], dtype=np.float64) * spacing
    line_arr = np.array(line_of, dtype=np.int64)
    pen_x = np.zeros(len(glyphs))
    if glyphs:
        total = np.cumsum(advance)
        line_first = np.searchsorted(line_arr, np.arange(len(lines)))
        before = np.concatenate([[0.0], total])[line_first]  # advance consumed before each line starts
        pen_x = total - advance - before[line_arr]
        widths = np.bincount(line_arr, weights=advance, minlength=len(lines)).astype(np.float64)
    return _Layout(glyphs, pen_x, line_arr, widths)


def _check(height: float, align: str, valign: str, spacing: float, line_spacing: float) -> None:
    if not (math.isfinite(height) and height > 0):
        raise ConfigError(f"text height must be > 0, got {height!r}")
    if align not in _ALIGNS:
        raise ConfigError(f"text align must be one of {', '.join(_ALIGNS)}, got {align!r}")
    if valign not in _VALIGNS:
        raise ConfigError(f"text valign must be one of {', '.join(_VALIGNS)}, got {valign!r}")
    if not (math.isfinite(spacing) and spacing > 0):
        raise ConfigError(f"character spacing must be > 0, got {spacing!r}")
    if not (math.isfinite(line_spacing) and line_spacing > 0):
        raise ConfigError(f"line spacing must be > 0, got {line_spacing!r}")


def _frame(
    layout: _Layout, font: Font, height: float, align: str, valign: str, line_spacing: float
) -> tuple[float, np.ndarray, float]:
    """Scale (world units per font unit), per-line x shift (font units) and the y shift of the first baseline."""
    scale = height / font.cap_height
    n_lines = len(layout.line_widths)
    x_shift = {"left": 0.0, "center": -0.5, "right": -1.0}[align] * layout.line_widths
    lead = line_spacing * height  # baseline to baseline, world units
    descent = (font.bottom - font.base) * scale
    y_shift = {
        "baseline": 0.0,
        "top": -height,
        "middle": -(height - (n_lines - 1) * lead) / 2,
        "bottom": (n_lines - 1) * lead + descent,
    }[valign]
    return scale, x_shift, y_shift


def text_strokes(
    text: str,
    *,
    position: tuple[float, float] = (0.0, 0.0),
    height: float = 5.0,
    angle: float = 0.0,
    slant: float = 0.0,
    align: str = "left",
    valign: str = "baseline",
    font: str = "futural",
    spacing: float = 1.0,
    line_spacing: float = 1.6,
) -> list[np.ndarray]:
    """Strokes of ``text`` in world units (y up): ``height`` = cap height, ``angle``/``slant`` in radians.

    Like HP-GL's LB with SI (size), DI (direction) and SL (slant): ``slant`` leans glyphs by ``tan(slant)``,
    ``spacing`` multiplies each character's advance, ``line_spacing`` is the baseline-to-baseline distance
    in cap heights for lines split at ``"\\n"``. ``align`` places each line's left end, centre or right end at
    ``position``; ``valign`` places the first line's baseline (``baseline``) or cap line (``top``), the last
    line's descender line (``bottom``), or the middle between first cap line and last baseline (``middle``).
    """
    _check(height, align, valign, spacing, line_spacing)
    f = load_font(font)
    layout = _layout(text, f, spacing)
    if not layout.glyphs:
        return []
    scale, x_shift, y_shift = _frame(layout, f, height, align, valign, line_spacing)
    counts = np.array([len(g.points) for g in layout.glyphs], dtype=np.int64)
    if not counts.sum():
        return []
    pts = np.concatenate([g.points for g in layout.glyphs])
    owner = np.repeat(np.arange(len(layout.glyphs)), counts)
    lefts = np.array([g.left for g in layout.glyphs], dtype=np.float64)
    # glyph points relative to their line's baseline (font units to world units, y flipped up), slanted there
    along = (pts[:, 0] - lefts[owner] + layout.pen_x[owner] + x_shift[layout.line_of[owner]]) * scale
    above = -(pts[:, 1] - f.base) * scale
    local = geo.apply(geo.shear(shx=math.tan(slant)), np.column_stack([along, above]))
    local[:, 1] += -layout.line_of[owner] * line_spacing * height + y_shift
    world = geo.apply(geo.place(position, angle), local)
    point_base = np.concatenate([[0], np.cumsum(counts)[:-1]])
    cuts = np.concatenate(
        [g.offsets[1:-1] + b for g, b in zip(layout.glyphs, point_base, strict=False)] + [point_base[1:]]
    )
    return [s for s in np.split(world, np.unique(cuts)) if len(s)]


def text_extent(
    text: str,
    *,
    position: tuple[float, float] = (0.0, 0.0),
    height: float = 5.0,
    angle: float = 0.0,
    slant: float = 0.0,
    align: str = "left",
    valign: str = "baseline",
    font: str = "futural",
    spacing: float = 1.0,
    line_spacing: float = 1.6,
) -> TextExtent:
    """The layout box of ``text`` as ``text_strokes`` would place it: advance widths by cap line to descender line.

    The box spans the widest line's advances and, vertically, from the first line's cap line to the last
    line's descender line; ``slant`` does not lean the box.
    """
    _check(height, align, valign, spacing, line_spacing)
    f = load_font(font)
    layout = _layout(text, f, spacing)
    scale, x_shift, y_shift = _frame(layout, f, height, align, valign, line_spacing)
    n_lines = len(layout.line_widths)
    x0 = float(np.min(x_shift)) * scale
    x1 = float(np.max(x_shift + layout.line_widths)) * scale
    top = height + y_shift
    bottom = y_shift - (n_lines - 1) * line_spacing * height - (f.bottom - f.base) * scale
    local = np.array([[x0, bottom], [x1, bottom], [x1, top], [x0, top]])
    return TextExtent(x1 - x0, top - bottom, geo.apply(geo.place(position, angle), local))

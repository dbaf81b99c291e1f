"""The HP-GL plotter models the simulator knows: papers (hard-clip limits, default P1/P2, sheet) and machine figures."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Final

__all__ = ["DEFAULT_PEN_COLOURS", "G_CM_S2", "MODELS", "PAPER_ALIASES", "ModelSpec", "PaperSpec"]

G_CM_S2: Final = 980.0
"""One g in cm/s².  The 7470A manual (VS) gives the default acceleration as "2 g (980 cm/s²)"; 980 cm/s² is
one g, so one of the two figures is a misprint: the simulator takes 2 g, HP's specification figure."""


@dataclass(frozen=True)
class PaperSpec:
    """One paper size on one model: hard-clip limits and default P1/P2 in plotter units, and the sheet."""

    name: str
    hard_clip: tuple[int, int]
    """Upper-right hard-clip corner (the lower-left is 0,0), landscape as the paper is loaded."""
    p1: tuple[int, int]
    p2: tuple[int, int]
    page_mm: tuple[float, float]
    """Sheet width and height as loaded."""
    origin_mm: tuple[float, float] | None = None
    """Hard-clip origin measured from the sheet's lower-left corner; None centres the hard-clip area."""


@dataclass(frozen=True)
class ModelSpec:
    """What distinguishes one HP-GL plotter model from another in the simulator."""

    name: str
    ident: str
    unit_mm: float
    papers: Mapping[str, PaperSpec]
    default_paper: str
    pens: int
    buffer: int
    max_velocity_cm_s: float
    accel_cm_s2: float
    slow_accel_cm_s2: float
    vs_error_from: float
    """VS parameters below 0 or at/above this set error 3."""
    pen_lift_s: float
    pen_change_s: float
    mnemonics: frozenset[str]
    recognised: frozenset[str] = frozenset()
    """Mnemonics the model knows that the simulator reads and logs but gives no effect."""
    oi_needs_in: bool = False
    output_options: str = "0,1,0,0,1,0,0,0"
    """OO answer: the 7470A's (pen select, arcs and circles); assumed for the other models."""
    charsets: int = 5


_A4_PAGE, _A3_PAGE = (297.0, 210.0), (420.0, 297.0)
_LETTER_PAGE, _TABLOID_PAGE = (279.4, 215.9), (431.8, 279.4)

_HP7475A_PAPERS = {
    # plotters.md §1.2 (hard clip, default P1/P2 from the 7475A O&I manual p. 25); sheet origins from
    # vpype's 7475A profile (A4 origin 10 mm from the left, 206 mm from the top; A3 15 mm / 287 mm).
    "a4": PaperSpec("a4", (11040, 7721), (603, 521), (10603, 7721), _A4_PAGE, (10.0, 4.0)),
    "a3": PaperSpec("a3", (16158, 11040), (170, 602), (15370, 10602), _A3_PAGE, (15.0, 10.0)),
    "letter": PaperSpec("letter", (10365, 7962), (250, 596), (10250, 7796), _LETTER_PAGE),
    "tabloid": PaperSpec("tabloid", (16640, 10365), (522, 259), (15722, 10259), _TABLOID_PAGE),
}


def _corner_papers(
    limits: Mapping[str, tuple[int, int]], pages: Mapping[str, tuple[float, float]]
) -> dict[str, PaperSpec]:
    """Assumption (no manual table at hand): default P1/P2 at the hard-clip corners."""
    return {name: PaperSpec(name, lim, (0, 0), lim, pages[name]) for name, lim in limits.items()}


_PAGES = {"a4": _A4_PAGE, "a3": _A3_PAGE, "letter": _LETTER_PAGE, "tabloid": _TABLOID_PAGE}
_COMMON_MNEMONICS = frozenset({
    "AA", "AR", "CA", "CI", "CP", "CS", "DF", "DI", "DR", "DT", "EA", "ER", "EW", "FT", "IM", "IN", "IP", "IW", "LB",
    "LT", "OA", "OC", "OE", "OF", "OH", "OI", "OO", "OP", "OS", "OW", "PA", "PD", "PR", "PT", "PU", "RA", "RO", "RR",
    "SA", "SC", "SI", "SL", "SM", "SP", "SR", "SS", "TL", "UC", "VS", "WG", "XT", "YT"
})
"""HP-GL/1 instructions the three models share (chiplotle3's 7475A whitelist, less digitizing and PS).

The 7475A's own list is chiplotle3's whole whitelist (``commands_7475A.py``), PS included: vpype's
``hp7475a`` device (written and used on 7475As) begins every file ``IN;DF;PS4;`` or ``PS0``."""

MODELS: Final[dict[str, ModelSpec]] = {
    "hp7475a": ModelSpec(
        name="hp7475a", ident="7475A", unit_mm=0.02488,  # 7475A manual p. 22 (plotters.md §1.1)
        papers=_HP7475A_PAPERS, default_paper="a4", pens=6,
        # plotters.md §1.5 ("≈1024 bytes (ask ESC.L)"), hpgl-buddy's 7475A profile ("documented buffer ~1024
        # bytes") and an owner's report (hpmuseum.org forum thread 21184: "buffer overrun! (up to 1024 Bytes)")
        buffer=1024,
        max_velocity_cm_s=38.1, accel_cm_s2=2 * G_CM_S2, slow_accel_cm_s2=0.5 * G_CM_S2,  # 7470A manual VS
        vs_error_from=97.0,
        pen_lift_s=0.05, pen_change_s=2.0,  # assumption: solenoid lift and carousel pen change
        mnemonics=_COMMON_MNEMONICS | {"DC", "DP", "OD", "PS"},
        oi_needs_in=True,  # plotters.md §1.3: a 7475A answers OI only after IN (chiplotle PR #3)
    ),
    "hp7550a": ModelSpec(
        name="hp7550a", ident="7550A", unit_mm=0.025,  # plotters.md §1.1: measured 0.025 mm
        papers=_corner_papers(
            {"a4": (10870, 7600), "a3": (15970, 10870), "letter": (10170, 7840), "tabloid": (16540, 10170)}, _PAGES
        ),
        default_paper="a4", pens=8,
        buffer=1024,  # assumption: ESC.L tells the real figure
        max_velocity_cm_s=80.0, accel_cm_s2=6 * G_CM_S2, slow_accel_cm_s2=2 * G_CM_S2,  # 7550A: 80 cm/s, 6 g
        vs_error_from=128.0,
        pen_lift_s=0.04, pen_change_s=1.5,  # assumption
        mnemonics=_COMMON_MNEMONICS | {"DC", "DP", "OD", "OT", "PS", "FS"},
        recognised=frozenset({  # chiplotle3
            "AF", "AH", "AP", "BF", "BL", "CC", "CM", "CT", "CV", "DL", "DS", "EP", "ES", "FP", "GC", "IV", "KY", "LO",
            "NR", "OG", "OK", "OL", "PB", "PG", "PM", "RP", "UF", "WD",
        }),
    ),
    "hp7440a": ModelSpec(
        name="hp7440a", ident="7440A", unit_mm=0.025,  # assumption: the HP-GL nominal unit
        papers={
            "a4": replace(_HP7475A_PAPERS["a4"], origin_mm=None),  # plotters.md §1.2: same limits as the 7475A
            "letter": replace(_HP7475A_PAPERS["letter"]),  # assumption: the 7475A's letter figures
        },
        default_paper="a4", pens=8,
        buffer=1024,  # assumption
        max_velocity_cm_s=38.1, accel_cm_s2=2 * G_CM_S2, slow_accel_cm_s2=0.5 * G_CM_S2,  # assumption: as 7475A
        vs_error_from=97.0,
        pen_lift_s=0.05, pen_change_s=2.0,  # assumption
        mnemonics=_COMMON_MNEMONICS,
    ),
}
"""The simulated models; the dict key is the ``sim:`` model name."""

PAPER_ALIASES: Final = {"a": "letter", "b": "tabloid", "us-a": "letter", "us-b": "tabloid"}
DEFAULT_PEN_COLOURS: Final = ("#000000", "#d01010", "#108010", "#1030c0", "#8020a0", "#e07000", "#705020", "#00a0b0")
"""Assumption: a plausible carousel (black, red, green, blue, violet, orange, brown, aqua)."""

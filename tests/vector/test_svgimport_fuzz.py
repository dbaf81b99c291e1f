"""Seeded mutation fuzzing of SVG import: each mutant imports or fails with a PixelpenError, fast, in bounded memory."""

import logging

import pytest

from pixelpen.errors import PixelpenError
from pixelpen.vector.svgimport import read_svg
from tests.fuzzing import QUICK_CASES, SLOW_CASES, TOKENS, campaign

NS = (
    'xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" '
    'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape"'
)

SEEDS = [
    f"""<svg {NS} width="297mm" height="210mm" viewBox="0 0 297 210">
<g inkscape:groupmode="layer" inkscape:label="outline" transform="translate(150,50) rotate(30)">
<rect x="-20" y="-10" width="40" height="20" rx="3" stroke="#ff0000" fill="none"/>
<circle cx="10" cy="5" r="8" stroke="#00ff00" fill="none"/></g>
<g inkscape:groupmode="layer" inkscape:label="detail" style="stroke:#0000ff;fill:none">
<ellipse cx="40" cy="40" rx="20" ry="9" transform="skewX(20)"/>
<line x1="0" y1="0" x2="10mm" y2="1in"/><polyline points="0,0 10,5 20,-5"/><polygon points="0,0 10,0 5,8"/>
</g></svg>""".encode(),
    f"""<svg {NS} width="8.5in" height="11in" viewBox="0 0 850 1100" preserveAspectRatio="xMinYMax slice">
<defs><path id="a" d="M0 0 L8 0 A4 4 0 0 1 8 8 L0 8 z" stroke="black" fill="none"/>
<g id="b"><use href="#a" x="10"/><use xlink:href="#a" transform="scale(2)"/></g></defs>
<use href="#b" x="100" y="100"/><use href="#b" transform="matrix(0.5 0.2 -0.2 0.5 300 300)"/>
</svg>""".encode(),
    f"""<svg {NS} width="100mm" height="100mm" viewBox="-50 -50 100 100">
<style>.st0 {{ stroke: #336699; fill: none }} /* pens */</style>
<path class="st0" d="M 1 2 H 20 V 15 h -5 v 3 L 3 18 l -2 -4 z M0 0 C 5 20 25 -20 30 0 S 50 20 60 0
Q 10 10 20 30 T 40 30 q 5 -10 10 0 t 10 0 A 20 10 30 0 1 50 50 a 5 8 -20 1 1 10 5 Z"/>
<g transform="scale(-1,1) translate(5 5)">\
<g transform="rotate(45 10 10)"><path class="st0" d="m1-1.5.5.5-2e1 3"/></g></g>
<text x="0" y="0">hi</text></svg>""".encode(),
]

SVG_TOKENS = (
    *TOKENS,
    b"<g>" * 400,
    b"</g>" * 50,
    b'<use href="#a"/>',
    b'<use href="#b"/>' * 20,
    b'<g id="a">',
    b'id="b"',
    b'transform="matrix(1e308 0 0 1e308 1e308 0)"',
    b'transform="rotate(NaN)"',
    b"scale(1e200)",
    b"9" * 2000,
    b'points="' + b"1" * 2000 + b'"',
    b' d="M0 0 Q"',
    b' r="1e9"',
    b' rx="-1"',
    b"NaN",
    b"1e-320",
    b"/*",
    b"{",
    b"A 1e9 1e9 0 1 1",
    b'viewBox="0 0 0 0"',
    b'width="0"',
    b"<!DOCTYPE svg [<!ENTITY a 'aaaa'>]>",
    b"&a;",
    b'style="display:none"',
)


def read(data: bytes) -> None:
    read_svg(data, tolerance=0.05)


@pytest.fixture(autouse=True)
def _quiet():
    logging.getLogger("pixelpen.vector.svgimport").setLevel(logging.ERROR)
    yield
    logging.getLogger("pixelpen.vector.svgimport").setLevel(logging.NOTSET)


def test_seeds_are_valid_drawings():
    for seed in SEEDS:
        assert len(read_svg(seed)) >= 3


def test_svg_fuzz_quick():
    campaign("svg", read, SEEDS, QUICK_CASES, seed=1, tokens=SVG_TOKENS, allowed=(PixelpenError,)).check()


@pytest.mark.slow
def test_svg_fuzz_slow():
    result = campaign("svg", read, SEEDS, SLOW_CASES, seed=2, tokens=SVG_TOKENS, allowed=(PixelpenError,))
    print(result.summary())
    result.check()

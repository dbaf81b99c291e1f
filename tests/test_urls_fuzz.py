"""Fuzzing the URL grammar: seeded mutations of valid device URLs, parsed, read as options and formatted back."""

from __future__ import annotations

import contextlib

from pixelpen.errors import PixelpenError
from pixelpen.options import OptionSpec, boolean
from pixelpen.urls import check_path, format_url, parse_size, parse_url
from tests.fuzzing import campaign, depths

SEEDS = [
    url.encode() for url in (
        "hp7475a:[rfc2217://plotter-host:4000?logging=debug]?paper=a3",
        "hp7475a:/dev/ttyUSB0?baud=9600&paper=a4&flow=xonxoff",
        "sim:hp7475a?paper=a4&pens=black,red",
        "png:out/scene.png?size=800x600&dpi=96&mode=RGB",
        "svg:out%20dir/a.svg?size=210x297mm&pen_width=0.3",
        "axidraw:[socket://[::1]:4000]?model=v3",
        "sim://grbl?speed=fast&id=bench",
    )
]


def parse_and_read(data: bytes) -> None:
    """The fuzz target: parse, read every option as size, bool and path, and check the URL formats back to itself."""
    url = parse_url(data.decode("utf-8", errors="surrogateescape"))
    for key, raw in url.options.items():
        for convert in (parse_size, boolean):
            with contextlib.suppress(PixelpenError):
                OptionSpec(key, convert, None, "").read(raw, str(url))
    if url.target:
        with contextlib.suppress(PixelpenError):
            check_path(url.target, "the target")
    again = parse_url(format_url(url.scheme, url.target, url.options))
    assert (again.scheme, again.target, dict(again.options)) == (url.scheme, url.target, dict(url.options))


def test_the_seeds_are_valid_urls():
    for seed in SEEDS:
        parse_and_read(seed)


@depths()
def test_url_fuzz(cases, seed):
    campaign("urls", parse_and_read, SEEDS, cases, seed=seed).check()

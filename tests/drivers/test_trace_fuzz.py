"""Fuzzing the trace reader: seeded mutations of valid traces, read from a byte stream and replayed as a device."""

from __future__ import annotations

import io

from pixelpen.drivers.trace import ReplayLink, format_chunk, format_header, read_trace
from tests.fuzzing import campaign, depths


def _seeds() -> list[bytes]:
    """A hand-written trace, and one as the writer formats it (long chunk split, comments, settings)."""
    hand = (
        "#pixelpen-trace 1 url=sim%3A%2F%2Fhp7475a%3Fpaper%3Da4 baudrate=9600 flow=xonxoff\n"
        "# a comment line\n"
        "\n"
        "0.000000 > 49 4E 3b  # IN;\n"
        "0.010000 > 4f493b\n"
        "0.041667 < 37 34 37 35 41 0d  # 7475A.\n"
    )
    lines = [format_header("sim://grbl?speed=fast", {"baudrate": 115200, "flow": "none"}), "# recorded by pixelpen"]
    lines += format_chunk(0.0, ">", b"$X\n") + format_chunk(0.5, "<", b"ok\r\n")
    lines += format_chunk(1.25, ">", bytes(range(256)) * 20) + format_chunk(2.0, "<", b"ok\r\n" * 3)
    return [hand.encode(), ("\n".join(lines) + "\n").encode()]


SEEDS = _seeds()


def read_and_replay(data: bytes) -> None:
    """The fuzz target: read a trace from an open text stream, and stand it up as a replay device."""
    trace = read_trace(io.TextIOWrapper(io.BytesIO(data), encoding="utf-8", newline=""))
    link = ReplayLink(trace)
    link.close()


def test_the_seeds_are_valid_traces():
    for seed in SEEDS:
        read_and_replay(seed)


@depths()
def test_trace_reader_fuzz(cases, seed):
    campaign("traces", read_and_replay, SEEDS, cases, seed=seed).check()

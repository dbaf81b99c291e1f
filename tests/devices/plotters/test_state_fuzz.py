"""Fuzzing the plot state file: seeded mutations of valid state files, read back; only a ParseError may come out."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pixelpen.devices.plotters.state import PlotState
from pixelpen.errors import ParseError
from tests.fuzzing import campaign, depths

SEEDS = [
    json.dumps(fields).encode() for fields in (
        {"url": "sim:grbl?speed=fast", "fingerprint": "ab12", "strokes": 24, "confirmed": 11, "version": 2,
         "sent": 14, "stopped_at": [125434.0, 161407.0, 0, 19.2, 1], "reached": [11, 0], "lifts": [11, 12]},
        {"url": "hp7475a:/dev/ttyUSB0", "fingerprint": "f", "strokes": 5, "confirmed": 2, "version": 2,
         "missing": [[2, 0, 0, 5, 5]], "written": [3, 1, 3.5, 4.0], "start": [2, -400.0, 3000.0],
         "damaged": [2, 4], "position_lost": False},
        {"url": "x", "fingerprint": "f", "strokes": 5, "confirmed": 2, "version": 1},
    )
]


def reader(path: Path):
    """The fuzz target: write the bytes as a state file and load it."""

    def load(data: bytes) -> None:
        path.write_bytes(data)
        PlotState.load(path)

    return load


def test_the_seeds_are_valid_state_files(tmp_path):
    for seed in SEEDS:
        reader(tmp_path / "s.json")(seed)


@depths()
def test_state_fuzz(tmp_path, cases, seed):
    campaign("plot state", reader(tmp_path / "s.json"), SEEDS, cases, seed=seed).check()


@pytest.mark.parametrize(("data", "message"), [
    (b'{"url": "\xff"}', "not UTF-8 text"),
    (b"[" * 100_000, "not readable JSON: RecursionError"),
    (b'{"strokes": ' + b"9" * 5000 + b"}", "not readable JSON: ValueError"),
])
def test_unreadable_state_files_are_parse_errors_naming_the_file(tmp_path, data, message):
    """Found by the campaign: invalid UTF-8 escaped as UnicodeDecodeError; deep nesting and huge integers too."""
    path = tmp_path / "s.json"
    path.write_bytes(data)
    with pytest.raises(ParseError, match=message) as info:
        PlotState.load(path)
    assert str(path) in str(info.value)

"""Fuzzing the profile readers: seeded mutations of the built-in profiles and a vpype configuration."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from pixelpen.profiles import load_profile, load_vpype_config
from pixelpen.profiles.model import MAX_PAPERS, MAX_PENS
from tests.fuzzing import campaign, depths
from tests.profiles.test_model import VPYPE

SEEDS = [
    entry.read_bytes() for entry in sorted(resources.files("pixelpen").joinpath("data", "profiles").iterdir(),
                                           key=lambda e: e.name) if entry.name.endswith(".toml")
] + [VPYPE.encode()]
BASE = load_profile("hp7475a")


def reader(path: Path):
    """The fuzz target: the bytes as a pixelpen profile, then as a vpype configuration; what is read is bounded."""

    def read(data: bytes) -> None:
        path.write_bytes(data)
        profiles = []
        try:
            profiles.append(load_profile(path))
        finally:  # a file one reader refuses still goes through the other
            profiles += load_vpype_config(path, base=BASE).values()
        for profile in profiles:
            assert 1 <= profile.pens <= MAX_PENS and len(profile.papers) <= MAX_PAPERS
            for name in profile.papers:
                profile.paper(name)

    return read


def test_the_seeds_are_valid(tmp_path):
    path = tmp_path / "seed.toml"
    for seed in SEEDS[:-1]:
        path.write_bytes(seed)
        assert load_profile(path).pens >= 1
    path.write_bytes(SEEDS[-1])
    assert set(load_vpype_config(path)) == {"hp7475a", "roland"}


@depths()
def test_profile_reader_fuzz(tmp_path, cases, seed):
    campaign("profiles", reader(tmp_path / "p.toml"), SEEDS, cases, seed=seed).check()

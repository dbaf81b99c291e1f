"""docs/profiles.md documents every key the profile reader knows, and its example profile loads."""

import re
from pathlib import Path

from pixelpen.profiles import toml as profiles

DOC = (Path(__file__).resolve().parents[1] / "docs" / "profiles.md").read_text(encoding="utf-8")


def documented(section):
    """The keys in the first column of the table under the heading that starts with ``section``."""
    part = DOC.split(f"## {section}", 1)[1].split("\n## ", 1)[0]
    return {key for row in re.findall(r"^\| (.+?) \|", part, re.M) for key in re.findall(r"`([a-z_0-9]+)`", row)}


def test_every_key_of_the_reader_is_documented():
    tables = {"pen_down", "pen_up", "paper", "link", "servo"}
    assert set(profiles._PROFILE_KEYS) - tables == documented("Top level")
    assert set(profiles._MOTION_KEYS) == documented("`[pen_down]`")
    assert set(profiles._PAPER_KEYS) == documented("`[paper.NAME]`")
    assert set(profiles._LINK_KEYS) == documented("`[link]`")
    assert set(profiles._SERVO_KEYS) == documented("`[servo]`")


def test_the_example_profile_loads(tmp_path):
    (example,) = re.findall(r"```toml\n(.*?)```", DOC, re.S)
    path = tmp_path / "myplotter.toml"
    path.write_text(example)
    profile = profiles.load_profile(path)
    assert profile.name == "myplotter" and profile.paper().size_mm == (420.0, 297.0)
    assert profile.pen_down.speed == 40.0 and profile.servo.down_command == "M3 S30"
    svg = tmp_path / "drawing.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="420mm" height="297mm" viewBox="0 0 420 297">'
                   '<path d="M10,20 L50,20" stroke="black" fill="none"/></svg>')
    from pixelpen.cli import main

    # the doc's dry run: the drawing laid on this profile's A3 sheet, nothing opened (there is no /dev/ttyUSB0)
    assert main(["plot", str(svg), "--to", f"grbl:/dev/ttyUSB0?profile={path}", "--dry-run"]) == 0

"""Tests of device profiles: the built-in TOML files, strict validation, user files and vpype's device format."""

from __future__ import annotations

import pytest

from pixelpen.errors import ConfigError, ParseError
from pixelpen.profiles import MotionLimits, builtin_profiles, load_profile, load_vpype_config, parse_length_mm

MINIMAL = """
name = "mine"
unit_mm = 0.025
[pen_down]
speed = 100.0
accel = 1000.0
[pen_up]
speed = 200.0
accel = 2000.0
"""


def write(tmp_path, text, name="p.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_builtins_are_all_there():
    names = set(builtin_profiles())
    assert {"hp7475a", "hp7550a", "hp7440a", "axidraw_v3", "axidraw_se_a3", "axidraw_minikit", "grbl"} <= names


def test_hp7475a_values_from_the_reference():
    p = load_profile("hp7475a")
    assert p.unit_mm == 0.02488 and p.pens == 6 and p.protocol == "hpgl"
    assert (p.paper("a4").x_range, p.paper("a4").y_range) == ((0, 11040), (0, 7721))
    assert (p.paper("a3").x_range, p.paper("a3").y_range) == ((0, 16158), (0, 11040))
    assert p.paper("letter").name == "a" and p.paper("TABLOID").x_range == (0, 16640)
    assert p.paper().name == "a4" and p.paper("a4").park == (11040, 7721) and p.paper("a4").set_ps == 4
    assert p.y_up and p.origin == "lower-left"
    assert (p.link.baudrate, p.link.xonxoff, p.link.rtscts) == (9600, True, False)


def test_hp7550a_unit_and_limits():
    p = load_profile("hp7550a")
    assert p.unit_mm == 0.025 and p.pens == 8
    assert p.paper("a3").x_range == (0, 15970) and p.paper("b").y_range == (0, 10170)


def test_axidraw_travel_and_motion():
    p = load_profile("axidraw_v3")
    travel = p.paper("travel")
    assert p.steps_per_mm == 80.0 and p.unit_mm * 80 == pytest.approx(1.0)
    assert travel.width_units * p.unit_mm == pytest.approx(300.0)
    assert travel.height_units * p.unit_mm == pytest.approx(218.0)
    assert p.pen_down == MotionLimits(50.0, 200.0, 0.127) and p.pen_up == MotionLimits(200.0, 400.0, 0.0)
    assert (p.pen_lift_s, p.pen_drop_s) == (0.12, 0.12)
    assert (p.servo.min, p.servo.max, p.servo.up_percent, p.servo.down_percent) == (9855, 27831, 60.0, 30.0)
    assert (p.link.usb_vid, p.link.usb_pid) == (0x04D8, 0xFD92)
    assert load_profile("axidraw_minikit").paper().width_units * p.unit_mm == pytest.approx(160.0)
    assert load_profile("AxiDraw-SE-A3").paper().height_units * p.unit_mm == pytest.approx(297.0)


def test_unknown_paper_and_profile_names():
    with pytest.raises(ConfigError, match="unknown paper 'a0'"):
        load_profile("hp7440a").paper("a0")
    with pytest.raises(ConfigError, match=r"unknown device profile 'hp9999'.*hp7475a"):
        load_profile("hp9999")


def test_user_file_by_path(tmp_path):
    path = write(tmp_path, 'pens = 2\npen_colours = ["#FF0000", "#00ff00"]\n' + MINIMAL)
    p = load_profile(path)
    assert p.name == "mine" and p.source == str(path) and p.pen_colours == {1: "#ff0000", 2: "#00ff00"}
    assert p.pen_up.speed == 200.0 and p.pen_down.cornering == 0.0 and p.papers == {}
    assert load_profile(str(path)).name == "mine"
    with pytest.raises(ConfigError, match="default_paper"):
        load_profile(path).paper()


def test_missing_file(tmp_path):
    with pytest.raises(ConfigError, match="does not exist"):
        load_profile(tmp_path / "nope.toml")


def test_malformed_toml_names_file_and_line(tmp_path):
    path = write(tmp_path, MINIMAL + "\nspeed = = 3\n")
    with pytest.raises(ParseError) as info:
        load_profile(path)
    assert info.value.source == str(path) and info.value.line == 11
    assert str(path) in str(info.value)


def test_truncated_toml(tmp_path):
    path = write(tmp_path, MINIMAL[: MINIMAL.index("[pen_up]") + 4])
    with pytest.raises(ParseError) as info:
        load_profile(path)
    assert info.value.source == str(path)


def test_not_utf8(tmp_path):
    path = tmp_path / "bin.toml"
    path.write_bytes(b'name = "\xff\xfe"\n')
    with pytest.raises(ParseError, match="UTF-8"):
        load_profile(path)


@pytest.mark.parametrize("extra, key", [
    ("bogus = 1\n", "'bogus'"),
    ("[pen_down]\n", None),  # redefining a table is a TOML error
])
def test_unknown_top_level_key(tmp_path, extra, key):
    path = write(tmp_path, extra + MINIMAL)
    with pytest.raises((ConfigError, ParseError)) as info:
        load_profile(path)
    assert str(path) in str(info.value)
    if key:
        assert f"unknown key {key}" in str(info.value)


@pytest.mark.parametrize("old, new, key", [
    ("speed = 100.0", "sped = 100.0", "pen_down.sped"),
    ("speed = 100.0", 'speed = "fast"', "pen_down.speed"),
    ("speed = 100.0", "speed = true", "pen_down.speed"),
    ("accel = 2000.0", "accel = -5.0", "pen_up.accel"),
    ("accel = 2000.0", "accel = inf", "pen_up.accel"),
    ("unit_mm = 0.025", "unit_mm = 0", "unit_mm"),
    ("unit_mm = 0.025", "unit_mm = 1e400", "unit_mm"),  # oversized: overflows to inf
    ("unit_mm = 0.025", "", "unit_mm"),
    ('name = "mine"', "name = 3", "name"),
    ("[pen_up]\nspeed = 200.0\naccel = 2000.0", "", "pen_up"),
])
def test_wrong_values_name_file_and_key(tmp_path, old, new, key):
    path = write(tmp_path, MINIMAL.replace(old, new))
    with pytest.raises(ConfigError) as info:
        load_profile(path)
    message = str(info.value)
    assert str(path) in message and key in message


@pytest.mark.parametrize("extra, key", [
    ('pens = 1\npen_colours = ["#000000", "#ffffff"]\n', "pen_colours"),
    ('pen_colours = ["black"]\n', "pen_colours"),
    ("pens = 0\n", "pens"),
    ('default_paper = "a4"\n', "default_paper"),
    ('origin = "middle"\n', "origin"),
    ("home = [1]\n", "home"),
    ("[paper.a4]\nx_range = [0, 10]\n", "paper.a4.y_range"),
    ("[paper.a4]\nx_range = [10, 0]\ny_range = [0, 10]\n", "paper.a4.x_range"),
    ("[paper.a4]\nx_range = [0, 10]\ny_range = [0, 10]\nsize = 3\n", "paper.a4.size"),
    ('[link]\nparity = "X"\n', "link.parity"),
    ("[link]\nbaudrate = 9600.5\n", "link.baudrate"),
    ("[servo]\nup_percent = 150\n", "servo.up_percent"),
    ("paper = 3\n", "paper"),
])
def test_bad_sections_name_the_key(tmp_path, extra, key):
    path = write(tmp_path, MINIMAL + "\n" + extra if extra.startswith("[") else extra + MINIMAL)
    with pytest.raises(ConfigError) as info:
        load_profile(path)
    assert f"'{key}'" in str(info.value) and str(path) in str(info.value)


VPYPE = """
[pen_config.rgb]
layers = [{ layer_id = 1, name = "red", color = "red" }]

[device.hp7475a]
name = "hp7475a"
plotter_unit_length = "0.02488mm"
pen_count = 6

[[device.hp7475a.paper]]
name = "a4"
aka_names = ["A4"]
info = "The plotter must be configured in Metric mode."
paper_size = ["297mm", "210mm"]
x_range = [0, 11040]
y_range = [0, 7721]
y_axis_up = true
origin_location = ["10mm", "206mm"]
final_pu_params = "11040,7721"
set_ps = 4

[[device.hp7475a.paper]]
name = "b"
aka_names = ["ansi_b", "tabloid"]
paper_size = ["17in", "11in"]
x_range = [0, 16640]
y_range = [0, 10365]
y_axis_up = true
origin_location = ["15mm", "287mm"]
final_pu_params = "0,10365"
set_ps = 0

[device.roland]
name = "Roland DXY"
plotter_unit_length = "0.025mm"
pen_count = 8

[[device.roland.paper]]
name = "flex"
y_axis_up = false
origin_location = [0, 0]
origin_location_reference = "botleft"
"""


def test_vpype_device_config(tmp_path):
    devices = load_vpype_config(write(tmp_path, VPYPE, "vpype.toml"))
    assert set(devices) == {"hp7475a", "roland"}
    hp = devices["hp7475a"]
    assert hp.unit_mm == pytest.approx(0.02488) and hp.pens == 6 and hp.protocol == "hpgl"
    a4 = hp.paper("A4")
    assert a4.x_range == (0, 11040) and a4.y_range == (0, 7721) and a4.y_up is True
    assert a4.size_mm == pytest.approx((297.0, 210.0)) and a4.origin_mm == pytest.approx((10.0, 206.0))
    assert a4.park == (11040, 7721) and a4.set_ps == 4 and "Metric" in a4.info
    assert hp.paper("tabloid").size_mm == pytest.approx((431.8, 279.4))
    roland = devices["roland"]
    assert roland.unit_mm == 0.025 and roland.description == "Roland DXY" and roland.y_up is False
    flex = roland.paper("flex")
    assert flex.origin_reference == "botleft" and flex.x_range == (-32768, 32767) and flex.origin_mm == (0.0, 0.0)
    # motion limits, which vpype does not state, come from the base profile
    assert hp.pen_down == load_profile("hp7475a").pen_down


@pytest.mark.parametrize("old, new, key", [
    ('set_ps = 4', 'set_ps = 4\nbogus = 1', "device.hp7475a.paper[0].bogus"),
    ('origin_location = ["10mm", "206mm"]', 'origin_location = ["10mm", "206mmmm"]',
     "device.hp7475a.paper[0].origin_location"),
    ('x_range = [0, 11040]', 'x_range = [0, "11040"]', "device.hp7475a.paper[0].x_range"),
    ('final_pu_params = "11040,7721"', 'final_pu_params = "here"', "device.hp7475a.paper[0].final_pu_params"),
    ('plotter_unit_length = "0.02488mm"', 'plotter_unit_length = "small"', "device.hp7475a.plotter_unit_length"),
    ('pen_count = 8', 'pen_count = 8\ncolour = "red"', "device.roland.colour"),
    ('y_axis_up = false\n', '', "device.roland.paper[0].y_axis_up"),
])
def test_vpype_config_errors_name_file_and_key(tmp_path, old, new, key):
    assert old in VPYPE
    path = write(tmp_path, VPYPE.replace(old, new, 1), "vpype.toml")
    with pytest.raises(ConfigError) as info:
        load_vpype_config(path)
    assert key in str(info.value) and str(path) in str(info.value)


def test_vpype_config_malformed_and_empty(tmp_path):
    with pytest.raises(ParseError):
        load_vpype_config(write(tmp_path, "[device.x\n", "bad.toml"))
    assert load_vpype_config(write(tmp_path, "", "empty.toml")) == {}


def test_vpype_unit_key_alias(tmp_path):
    text = '[device.x]\nunit = "0.1mm"\n'
    assert load_vpype_config(write(tmp_path, text, "u.toml"))["x"].unit_mm == pytest.approx(0.1)


def test_parse_length():
    assert parse_length_mm("297mm") == 297.0
    assert parse_length_mm("11in") == pytest.approx(279.4)
    assert parse_length_mm(" 1.5 cm ") == pytest.approx(15.0)
    assert parse_length_mm(96) == pytest.approx(25.4)  # vpype: bare numbers are CSS pixels
    for bad in ("mm", "12 parsecs", "", None, "1e", [1]):
        with pytest.raises(ValueError):
            parse_length_mm(bad)


def test_profiles_built_in_code_are_checked_too():
    from pixelpen.profiles.model import DeviceProfile

    limits = MotionLimits(10, 100)
    assert DeviceProfile("x", 0.1, limits, limits).pens == 1
    for bad in ({"unit_mm": 0}, {"pens": 0}, {"pen_lift_s": -1}, {"pen_up": (10, 100)}):
        kwargs = {"name": "x", "unit_mm": 0.1, "pen_down": limits, "pen_up": limits, **bad}
        with pytest.raises(ConfigError, match="profile 'x'"):
            DeviceProfile(**kwargs)


def test_vpype_config_with_a_given_base_profile(tmp_path):
    base = load_profile("grbl")
    devices = load_vpype_config(write(tmp_path, VPYPE, "vpype.toml"), base=base)
    assert devices["hp7475a"].pen_up == base.pen_up and devices["hp7475a"].unit_mm == pytest.approx(0.02488)


@pytest.mark.parametrize("extra", [
    "x = " + "[" * 1000 + "]" * 1000 + "\n",  # tomllib recursed into RecursionError
    "x = " + "{a = " * 1000 + "1" + "}" * 1000 + "\n",
])
def test_deep_nesting_is_a_parse_error_with_its_line(tmp_path, extra):
    path = write(tmp_path, MINIMAL + extra)
    with pytest.raises(ParseError, match="nested more than 32 deep") as info:
        load_profile(path)
    assert info.value.line == MINIMAL.count("\n") + 1 and str(path) in str(info.value)


def test_brackets_in_strings_and_comments_do_not_nest(tmp_path):
    text = MINIMAL.replace('name = "mine"', 'name = "[[[[' + "[" * 100 + '"  # ' + "{" * 100)
    assert load_profile(write(tmp_path, text)).name.startswith("[[[[")


def test_an_integer_past_pythons_digit_limit_is_a_parse_error(tmp_path):
    path = write(tmp_path, MINIMAL.replace("unit_mm = 0.025", "unit_mm = " + "9" * 5000))
    with pytest.raises(ParseError, match="4300") as info:  # tomllib raised a bare ValueError
        load_profile(path)
    assert info.value.line == 3


@pytest.mark.parametrize("old, new, key", [
    ("speed = 100.0", "speed = " + "9" * 400, "pen_down.speed"),  # float() raised OverflowError
    ("unit_mm = 0.025", "unit_mm = 1e-300", "unit_mm"),
    ('name = "mine"', 'name = "mine"\npens = 1000000000000', "pens"),  # hung open() building 10^12 pens
    ('name = "mine"', 'name = "mine"\nhome = [1e300, 0]', "home"),
    ("", "[paper.a4]\nx_range = [0, " + "9" * 400 + "]\ny_range = [0, 1]", "paper.a4.x_range"),
])
def test_out_of_range_numbers_name_file_and_key(tmp_path, old, new, key):
    path = write(tmp_path, MINIMAL.replace(old, new, 1) if old else MINIMAL + new)
    with pytest.raises(ConfigError) as info:
        load_profile(path)
    assert f"'{key}'" in str(info.value) and str(path) in str(info.value)
    assert len(str(info.value)) < 400  # the 400-digit value is shown by its size


def test_profile_limits_are_overridable(tmp_path, monkeypatch):
    from pixelpen.profiles import model as profiles

    path = write(tmp_path, "pens = 12\n" + MINIMAL)
    assert load_profile(path).pens == 12
    monkeypatch.setattr(profiles, "MAX_PENS", 8)
    with pytest.raises(ConfigError, match=r"1..8"):
        load_profile(path)
    monkeypatch.setattr(profiles, "MAX_BYTES", 50)
    with pytest.raises(ParseError, match="larger than the 50"):
        load_profile(path)


def test_profiles_built_in_code_refuse_too_many_pens():
    from dataclasses import replace

    with pytest.raises(ConfigError, match="pens"):
        replace(load_profile("hp7475a"), pens=10**12)


def test_bad_profile_names_are_config_errors():
    with pytest.raises(ConfigError, match="NUL"):
        load_profile("my\x00profile.toml")


def test_vpype_numbers_out_of_range(tmp_path):
    base = VPYPE.split("[device.roland]")[0]
    for old, new, key in [
        ('plotter_unit_length = "0.02488mm"', 'plotter_unit_length = "1e400mm"', "device.hp7475a.plotter_unit_length"),
        (
            'final_pu_params = "11040,7721"',
            f'final_pu_params = "{"9" * 5000},1"',
            "device.hp7475a.paper[0].final_pu_params",
        ),
        ("pen_count = 6", "pen_count = 1000000000000", "device.hp7475a.pen_count"),
    ]:
        path = write(tmp_path, base.replace(old, new), "vpype.toml")
        with pytest.raises(ConfigError) as info:
            load_vpype_config(path)
        assert f"'{key}'" in str(info.value), str(info.value)


def test_the_readers_still_import_from_model_as_before_the_split():
    from pixelpen.profiles import model, toml, vpype

    assert model.load_profile is toml.load_profile and model.builtin_profiles is toml.builtin_profiles
    assert model.load_vpype_config is vpype.load_vpype_config and model.parse_length_mm is vpype.parse_length_mm
    with pytest.raises(AttributeError):
        model.no_such_name  # noqa: B018 (the attribute access is the test)


def test_motion_limits_are_profile_data_re_exported_by_the_motion_model():
    from pixelpen.profiles import model
    from pixelpen.vector import motion

    assert motion.MotionLimits is model.MotionLimits is MotionLimits


def test_parse_length_mm_raises_invalid_argument():
    from pixelpen.errors import InvalidArgument

    with pytest.raises(InvalidArgument, match="not a length"):
        parse_length_mm("12 parsecs")

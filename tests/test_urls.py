"""Tests of the device URL grammar."""

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.errors import ConfigError, URLError
from pixelpen.options import OptionSpec, boolean, positive, read_options
from pixelpen.options import text as any_text
from pixelpen.urls import Size, check_path, format_url, parse_size, parse_url, to_mm


def _read(url, *specs):
    """The options of a parsed URL read against ``specs`` the way every display reads them."""
    return read_options(specs, url.options, str(url))


def test_plain_target_and_options():
    u = parse_url("hp7475a:/dev/ttyUSB0?baud=9600&paper=a4")
    assert (u.scheme, u.target, dict(u.options)) == ("hp7475a", "/dev/ttyUSB0", {"baud": "9600", "paper": "a4"})


def test_nested_url_keeps_its_own_query_inside_brackets():
    u = parse_url("hp7475a:[rfc2217://plotter:4000?logging=debug]?paper=a3")
    assert u.target == "rfc2217://plotter:4000?logging=debug"
    assert dict(u.options) == {"paper": "a3"}


def test_nested_brackets_for_ipv6():
    u = parse_url("grbl:[socket://[::1]:4000]")
    assert u.target == "socket://[::1]:4000" and not u.options


def test_scheme_is_case_insensitive_and_bare_option_is_true():
    u = parse_url("SIM:hp7475a?fast")
    assert u.scheme == "sim" and u.options["fast"] == "true"


@pytest.mark.parametrize(
    "bad, words",
    [
        ("", "non-empty"),
        ("nocolon", "scheme:target"),
        (":x", "scheme:target"),
        ("a b:x", "letters"),
        ("x:[unclosed", "no matching"),
        ("x:[a]junk", "after ']'"),
        ("x:t?a=1&a=2", "twice"),
        ("x:t?=1", "empty option"),
    ],
)
def test_malformed_urls_say_what_is_wrong(bad, words):
    with pytest.raises(URLError, match=words):
        parse_url(bad)


def test_unknown_option_lists_known_and_hints_brackets():
    u = parse_url("hp7475a:rfc2217://h:1?logging=debug")
    with pytest.raises(URLError) as err:
        _read(u, OptionSpec("paper", any_text, None, ""), OptionSpec("baud", any_text, None, ""))
    text = str(err.value)
    assert "logging" in text and "paper" in text and "brackets" in text


def test_option_conversion_errors_name_the_option():
    dpi = OptionSpec("dpi", positive, 96.0, "")
    with pytest.raises(URLError, match=r"png:x\.png\?dpi=abc: option dpi='abc' is not valid"):
        _read(parse_url("png:x.png?dpi=abc"), dpi)
    assert _read(parse_url("png:x.png"), dpi)["dpi"] == 96.0


text = st.text(st.characters(codec="utf-8", exclude_characters="\x00"), min_size=1, max_size=20)


@settings(max_examples=200, deadline=None)
@given(
    target=st.one_of(text, st.just("rfc2217://h:1?x=1&y=2"), st.just("socket://[::1]:9")),
    options=st.dictionaries(st.text("abcxyz_", min_size=1, max_size=6), text, max_size=3),
)
def test_format_then_parse_round_trips(target, options):
    u = parse_url(format_url("svg", target, options))
    assert u.scheme == "svg" and u.target == target and dict(u.options) == options


def test_sizes_and_units():
    assert parse_size("800x600") == (800.0, 600.0, "px")
    assert parse_size("210x297mm") == (210.0, 297.0, "mm")
    assert parse_size("A3") == (297.0, 420.0, "mm")
    assert to_mm(1.0, "in") == 25.4 and to_mm(96, "px") == pytest.approx(25.4)
    for bad in ("800", "0x5", "axb", "-1x2"):
        with pytest.raises(ValueError):
            parse_size(bad)
    assert boolean("On") is True and boolean("0") is False
    with pytest.raises(ValueError):
        boolean("maybe")
    assert str(parse_size("800x600")) == "800x600" and str(parse_size("a4")) == "210x297mm"
    assert Size(1, 2, "in").mm() == (25.4, 50.8)


@pytest.mark.parametrize("target", ["[", "]", "a]b?c", "[x?", "x?]", "[a][b]?q"])
def test_unbalanced_brackets_round_trip_percent_encoded(target):
    assert parse_url(format_url("png", target, {"size": "1x1"})).target == target


@pytest.mark.parametrize("url, words", [
    ("png:a.png?mode=%ff", "option 'mode' holds percent-encoded bytes that are not UTF-8"),
    ("png:a.png?%c3=1", "option name"),
    ("png:a%ff.png", "the target"),
    ("png:a\udcff.png", "lone surrogate"),
    ("png:" + "a" * 70_000, "longer than"),
])
def test_undecodable_urls_are_url_errors(url, words):
    with pytest.raises(URLError, match=words):
        parse_url(url)


@pytest.mark.parametrize("text", ["4x1e999", "1e999x1", "nanx4", "4x0", "1e8x1"])
def test_sizes_must_be_finite_positive_and_bounded(text):
    with pytest.raises(ValueError, match="size"):
        parse_size(text)
    url = parse_url(f"png:a.png?size={text}")
    with pytest.raises(URLError, match=f"option size='{text}'"):
        _read(url, OptionSpec("size", parse_size, None, ""))


@pytest.mark.parametrize("name, words", [
    ("a\x00b.png", "NUL character at index 1"),
    ("x" * 256 + ".png", "component of 260 bytes"),
    ("/".join(["dir"] * 1100), "more than the 4096"),
    ("", "empty"),
    (3, "must be a file name"),
])
def test_file_names_no_file_system_takes_are_config_errors_naming_the_option(name, words):
    with pytest.raises(ConfigError, match=words) as info:
        check_path(name, "png file name")
    assert str(info.value).startswith("png file name")


def test_ordinary_file_names_pass():
    assert str(check_path("out/é scène.png", "x")) == "out/é scène.png"
    assert str(check_path("d/" + "x" * 255, "x")).endswith("x" * 255)

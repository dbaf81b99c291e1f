"""Panel profiles: the built-in modules against datasheet/driver byte sequences and RAM placement, strict TOML."""

from __future__ import annotations

import logging
from importlib import resources

import pytest

from pixelpen.errors import ConfigError, ParseError
from pixelpen.profiles import panel
from pixelpen.profiles.panel import (
    InitStep,
    builtin_panel_profiles,
    load_panel_profile,
    panel_profile_for,
    read_panel_profile,
)
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign

MINIMAL = """
name = "mine"
controller = "st7789"
size = [240, 240]
ram_size = [240, 320]
clock_hz = { spi = 40_000_000 }
init = [ { command = 0x01, delay_ms = 150 }, { command = 0x11, delay_ms = 120 }, { command = 0x29 } ]
[rotation.0]
offset = [0, 80]
madctl = 0xC0
[rotation.90]
offset = [80, 0]
madctl = 0xA0
[rotation.180]
madctl = 0x00
[rotation.270]
madctl = 0x60
"""

KERNEL_EXAMPLE = b"MIPI DBI" + bytes(7) + b"\x01" + bytes.fromhex("1100 000178 b103012c2d 2900")
"""The byte sequence of the example in drivers/gpu/drm/tiny/panel-mipi-dbi.c's comment, typed from it."""


def flat(steps: tuple[InitStep, ...]) -> bytes:
    """An SSD1306 init table as the command bytes on the wire (parameters are command bytes too)."""
    return b"".join(bytes([s.command]) + s.params for s in steps)


def test_builtin_names():
    assert set(builtin_panel_profiles()) == {
        "ssd1306_128x64", "ssd1306_128x32", "ssd1306_96x16", "ssd1306_64x48", "sh1106_128x64", "ssd1309_128x64",
        "st7789_240x240", "st7789_240x320", "st7789_135x240", "st7789_240x280", "st7789_170x320",
        "ili9341_240x320", "st7735_128x160", "st7735_80x160",
    }


def test_ssd1306_init_is_lumas_sequence():
    # panels.md §1: luma init bytes, contrast CF, then AF; luma's per-size multiplex/clock/COM pins settings.
    luma = bytes.fromhex("AE D5 80 A8 3F D3 00 40 8D 14 20 00 A1 C8 DA 12 D9 F1 DB 40 A4 A6 81 CF AF")
    assert flat(load_panel_profile("ssd1306_128x64").init) == luma
    assert flat(load_panel_profile("ssd1306_128x32").init) == luma.replace(b"\xa8\x3f", b"\xa8\x1f").replace(
        b"\xda\x12", b"\xda\x02")
    assert flat(load_panel_profile("ssd1306_96x16").init) == luma.replace(b"\xd5\x80", b"\xd5\x60").replace(
        b"\xa8\x3f", b"\xa8\x0f").replace(b"\xda\x12", b"\xda\x02")
    assert flat(load_panel_profile("ssd1306_64x48").init) == luma.replace(b"\xa8\x3f", b"\xa8\x2f")
    p = load_panel_profile("ssd1306_128x64")
    assert p.init[-1] == InitStep(0xAF, b"", 100.0)  # datasheet: 100 ms for SEG/COM after display on
    assert flat(p.init).index(b"\x8d\x14") < flat(p.init).index(b"\xaf")  # charge pump before AF


class Capture:
    """A luma serial interface that records what the device sends."""

    def __init__(self):
        self.sent = []

    def command(self, *cmd):
        self.sent.append(("c", bytes(cmd)))

    def data(self, data):
        self.sent.append(("d", bytes(data)))

    def cleanup(self):
        pass


@pytest.mark.parametrize("size", [(128, 64), (128, 32), (96, 16), (64, 48)])
def test_ssd1306_init_and_column_start_equal_luma_oled(size):
    device = pytest.importorskip("luma.oled.device")
    capture = Capture()
    device.ssd1306(serial_interface=capture, width=size[0], height=size[1])
    commands = [v for k, v in capture.sent if k == "c"]
    init, contrast, window, display_on = commands  # luma: init, contrast, the clearing frame's window, AF
    p = load_panel_profile(f"ssd1306_{size[0]}x{size[1]}")
    assert flat(p.init) == init + contrast + display_on
    assert window[:2] == bytes([0x21, p.column_offset]) and window[2] == p.column_offset + size[0] - 1


def test_oled_fields():
    assert [load_panel_profile(n).column_offset for n in ("ssd1306_64x48", "ssd1306_96x16", "sh1106_128x64")] == [
        32, 0, 2]
    p = load_panel_profile("sh1106_128x64")
    assert p.ram_size == (132, 64) and b"\x20" not in bytes(s.command for s in p.init)  # page addressing only
    for p in builtin_panel_profiles().values():
        if p.oled:
            assert p.i2c_address == 0x3C and p.pixel_format == "mono-pages" and p.bytes_per_pixel == 0.125
            assert p.bus_clock("i2c") == 400_000
    g0, g180 = load_panel_profile("ssd1306_128x64").geometry(0), load_panel_profile("ssd1306_128x64").geometry(180)
    assert (g0.segment_remap, g0.com_reverse) == (True, True) and (g180.segment_remap, g180.com_reverse) == (False,
                                                                                                          False)
    with pytest.raises(ConfigError, match="0 or 180"):
        load_panel_profile("ssd1306_128x64").geometry(90)


def test_st7789_init_and_delays():
    p = load_panel_profile("st7789_240x240")
    assert [(s.command, s.params) for s in p.init] == [
        (0x01, b""), (0x11, b""), (0x3A, b"\x55"), (0x36, b"\xc0"), (0x21, b""), (0x13, b""), (0x29, b"")]
    delays = {s.command: s.delay_ms for s in p.init}
    assert delays[0x01] == 150 and delays[0x11] == 120 >= 5
    assert p.bus_clock("spi") == 62_500_000 and p.invert and not p.bgr and p.te
    with pytest.raises(ConfigError, match="not driven over i2c"):
        p.bus_clock("i2c")


def test_ili9341_init_is_adafruits_table():
    # Adafruit_ILI9341 initcmd (also luma.lcd), typed from the library source.
    adafruit = [
        (0xEF, "03 80 02"), (0xCF, "00 C1 30"), (0xED, "64 03 12 81"), (0xE8, "85 00 78"), (0xCB, "39 2C 00 34 02"),
        (0xF7, "20"), (0xEA, "00 00"), (0xC0, "23"), (0xC1, "10"), (0xC5, "3E 28"), (0xC7, "86"), (0x36, "48"),
        (0x37, "00"), (0x3A, "55"), (0xB1, "00 18"), (0xB6, "08 82 27"), (0xF2, "00"), (0x26, "01"),
        (0xE0, "0F 31 2B 0C 0E 08 4E F1 37 07 10 03 0E 09 00"), (0xE1, "00 0E 14 03 11 07 31 C1 48 08 0F 0C 31 36 0F"),
        (0x11, ""), (0x29, ""),
    ]
    p = load_panel_profile("ili9341_240x320")
    assert [(s.command, s.params) for s in p.init[1:]] == [(c, bytes.fromhex(h)) for c, h in adafruit]
    assert p.init[0] == InitStep(0x01, b"", 150.0)
    assert {s.command: s.delay_ms for s in p.init}[0x11] == 120
    assert [p.geometry(r).madctl for r in (0, 90, 180, 270)] == [0x48, 0x28, 0x88, 0xE8]  # Adafruit, with BGR
    assert (p.geometry(90).width, p.geometry(90).height) == (320, 240)
    assert p.max_clock_hz["spi"] == 10_000_000


class FakeGPIO:
    """Just enough of RPi.GPIO for luma.lcd's backlight handling."""

    OUT, BCM, HIGH, LOW = 0, 11, 1, 0

    def setmode(self, *args):
        pass

    def setup(self, *args, **kwargs):
        pass

    def output(self, *args):
        pass

    def cleanup(self, *args):
        pass


def test_ili9341_table_equals_luma_lcd():
    device = pytest.importorskip("luma.lcd.device")
    capture = Capture()
    device.ili9341(serial_interface=capture, gpio=FakeGPIO())
    sent, pairs = capture.sent, []
    for i, (kind, value) in enumerate(sent):
        if kind == "c":
            params = sent[i + 1][1] if i + 1 < len(sent) and sent[i + 1][0] == "d" else b""
            pairs.append((value[0], params))
    luma = pairs[: [c for c, _ in pairs].index(0x11) + 1]
    ours = [(s.command, s.params) for s in load_panel_profile("ili9341_240x320").init]
    # luma differs on purpose in MADCTL (its 320x240 default) and COLMOD (18-bit 0x46), sends no SWRESET and
    # no VSCRSADD; everything else, undocumented EFh..EAh included, is the same table in the same order.
    differ = {0x01, 0x36, 0x37, 0x3A}
    assert [p for p in luma if p[0] not in differ] == [p for p in ours if p[0] not in differ and p[0] != 0x29]


def test_st7735_tables():
    black, mini = load_panel_profile("st7735_128x160"), load_panel_profile("st7735_80x160")
    assert [s.command for s in black.init] == [0x01, 0x11, 0xB1, 0xB2, 0xB3, 0xB4, 0xC0, 0xC1, 0xC2, 0xC3, 0xC4,
                                               0xC5, 0x20, 0x3A, 0xE0, 0xE1, 0x13, 0x29]  # Adafruit Rcmd1 + Rcmd3
    assert black.init[1].delay_ms == 500 and black.init[-1].delay_ms == 100
    assert black.geometry(0).madctl == 0xC0  # black tab: RGB filter
    assert mini.bgr and mini.invert and 0x21 in [s.command for s in mini.init]
    assert (mini.geometry(0).x_offset, mini.geometry(0).y_offset) == (26, 1)
    assert (mini.geometry(90).x_offset, mini.geometry(90).y_offset) == (1, 26)


# Where each module's glass sits in its controller's RAM (physical column, row ranges at MADCTL = 0), from the
# modules' descriptions (Adafruit, TFT_eSPI, Pimoroni): the oracle for the per-rotation offsets and MADCTL.
PLACEMENT = {
    "st7789_240x240": (range(240), range(240)),
    "st7789_240x320": (range(240), range(320)),
    "st7789_135x240": (range(52, 187), range(40, 280)),
    "st7789_240x280": (range(240), range(20, 300)),
    "st7789_170x320": (range(35, 205), range(320)),
    "ili9341_240x320": (range(240), range(320)),
    "st7735_128x160": (range(128), range(160)),
    "st7735_80x160": (range(26, 106), range(1, 161)),
}


def physical(madctl: int, c: int, p: int, ram: tuple[int, int]) -> tuple[int, int]:
    """Datasheet address mapping (ST7789VW Fig. 33): (column counter, page counter) -> physical (column, row)."""
    col, row = (p, c) if madctl & 0x20 else (c, p)
    if madctl & 0x40:
        col = ram[0] - 1 - col
    if madctl & 0x80:
        row = ram[1] - 1 - row
    return col, row


@pytest.mark.parametrize("name", sorted(PLACEMENT))
@pytest.mark.parametrize("rotation", [0, 90, 180, 270])
def test_offsets_put_the_window_on_the_glass(name, rotation):
    p = load_panel_profile(name)
    g = p.geometry(rotation)
    cols, rows = PLACEMENT[name]
    corners = [(g.x_offset + dx, g.y_offset + dy) for dx in (0, g.width - 1) for dy in (0, g.height - 1)]
    hit = {physical(g.madctl, c, r, p.ram_size) for c, r in corners}
    assert hit == {(x, y) for x in (cols[0], cols[-1]) for y in (rows[0], rows[-1])}


def test_st7789_240x240_row_80_whenever_my_is_set():
    p = load_panel_profile("st7789_240x240")
    for r in (0, 90, 180, 270):
        g = p.geometry(r)
        moved = g.x_offset if g.madctl & 0x20 else g.y_offset  # MV: the row offset is on the column counter
        assert moved == (80 if g.madctl & 0x80 else 0)


def test_profile_for_and_names():
    assert panel_profile_for("st7789", (240, 240)).name == "st7789_240x240"
    assert panel_profile_for("ili9341", (320, 240)).name == "ili9341_240x320"
    assert load_panel_profile("ili9341_320x240").name == "ili9341_240x320"
    assert load_panel_profile("ST7789-240x240").name == "st7789_240x240"
    with pytest.raises(ConfigError, match=r"known sizes: 135x240, 170x320, 240x240, 240x280, 240x320"):
        panel_profile_for("st7789", (128, 128))
    with pytest.raises(ConfigError, match="no built-in panel profile for controller"):
        panel_profile_for("ssd1351", (128, 128))
    with pytest.raises(ConfigError, match="unknown panel profile 'nope'"):
        load_panel_profile("nope")


def write(tmp_path, text, name="p.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_user_file(tmp_path):
    p = load_panel_profile(write(tmp_path, MINIMAL))
    assert p.name == "mine" and p.pixel_format == "rgb565be" and p.geometry(0).y_offset == 80
    assert p.source.endswith("p.toml") and p.max_clock_hz == {}
    with pytest.raises(TypeError):
        p.clock_hz["spi"] = 1  # type: ignore[index]
    with pytest.raises(ConfigError, match="does not exist"):
        load_panel_profile(tmp_path / "missing.toml")


@pytest.mark.parametrize(("change", "message"), [
    (("madctl = 0x60", "madctl = 0x60\nofset = [1, 1]"), "unknown key 'rotation.270.ofset'"),
    (("{ command = 0x29 }", "{ command = 0x29, dly = 1 }"), "unknown key 'init.2.dly'|unknown key 'init\\[2\\].dly'"),
    (('name = "mine"', 'name = "mine"\ncolour = "x"'), "unknown key 'colour'"),
    (("size = [240, 240]", 'size = "240x240"'), "key 'size': expected a \\[width, height\\]"),
    (("size = [240, 240]", "size = [240, 0]"), "key 'size'"),
    (("delay_ms = 150", "delay_ms = 20000"), "key 'init\\[0\\].delay_ms'"),
    (("delay_ms = 150", "delay_ms = true"), "key 'init\\[0\\].delay_ms'"),
    (("{ command = 0x29 }", "{ command = 0x129 }"), "key 'init\\[2\\].command'"),
    (("{ command = 0x29 }", "{ command = 0x29, params = [256] }"), "key 'init\\[2\\].params'"),
    (('controller = "st7789"', 'controller = "st7790"'), "key 'controller'"),
    (("clock_hz = { spi = 40_000_000 }", "clock_hz = { spi = 40_000_000, usb = 1 }"), "unknown key 'clock_hz.usb'"),
    (("clock_hz = { spi = 40_000_000 }", "clock_hz = { spi = -1 }"), "key 'clock_hz.spi'"),
    (("[rotation.270]\nmadctl = 0x60", "[rotation.45]\nmadctl = 0x60"), "unknown key 'rotation.45'"),
    (("[rotation.270]\nmadctl = 0x60", ""), "needs rotations 0, 90, 180 and 270"),
    (("madctl = 0x60", "madctl = 0x68"), "BGR comes from bgr"),
    (("offset = [0, 80]", "offset = [0, 81]"), "does not fit the 240x320 RAM"),
    (('name = "mine"', 'name = "Mine!"'), "key 'name'"),
    (('name = "mine"\n', ""), "missing key 'name'"),
    (("init = [", "pixel_format = \"mono-pages\"\ninit = ["), "pixel_format must be rgb565be or rgb666"),
    (("{ command = 0x29 }", "{ command = 0x3A, params = [0x66] }"), "COLMOD 0x66, which is not rgb565be"),
    (("{ command = 0x29 }", "{ command = 0x21 }"), "INVON but invert is false"),
    (("{ command = 0x11, delay_ms = 120 }", "{ command = 0x11 }"), "0x11 needs >= 5 ms before the next command"),
    (("[rotation.0]", "[oled]\nmultiplex = 64\n[rotation.0]"), "multiplex: SSD1306-family settings"),
    (("clock_hz", "i2c_address = 0x3C\nclock_hz"), "i2c_address: SSD1306-family settings, not for a st7789"),
])
def test_strict_reading_names_key_and_file(tmp_path, change, message):
    old, new = change
    assert old in MINIMAL
    path = write(tmp_path, MINIMAL.replace(old, new, 1))
    with pytest.raises(ConfigError, match=message) as err:
        load_panel_profile(path)
    assert "p.toml" in str(err.value)


OLED = """
name = "oled"
controller = "ssd1306"
size = [128, 32]
ram_size = [128, 64]
clock_hz = { i2c = 400_000 }
init = [ { command = 0xA8, params = [0x1F] }, { command = 0xDA, params = [0x02] }, { command = 0x8D, params = [0x14] } ]
[oled]
multiplex = 32
com_pins = 0x02
charge_pump = true
"""


@pytest.mark.parametrize(("old", "new", "message"), [
    ("multiplex = 32", "multiplex = 16", "multiplex must be 32..64"),
    ("params = [0x1F]", "params = [0x3F]", "0xa8 3f disagrees"),
    ("params = [0x14]", "params = [0x10]", "0x8d 10 disagrees"),
    ("com_pins = 0x02", "com_pins = 0x05", "com_pins must be the DAh parameter"),
    ("size = [128, 32]", "size = [128, 30]", "whole pages"),
    ("charge_pump = true", "charge_pump = true\n[rotation.0]\nmadctl = 0", "not a rotation table"),
    ("clock_hz", "i2c_address = 0x80\nclock_hz", "key 'i2c_address'"),
])
def test_oled_checks(tmp_path, old, new, message):
    assert load_panel_profile(write(tmp_path, OLED)).multiplex == 32
    with pytest.raises(ConfigError, match=message):
        load_panel_profile(write(tmp_path, OLED.replace(old, new, 1)))


def test_limits(tmp_path, monkeypatch):
    monkeypatch.setattr(panel, "MAX_INIT_STEPS", 2)
    with pytest.raises(ConfigError, match="at most 2 steps"):
        load_panel_profile(write(tmp_path, MINIMAL))
    monkeypatch.setattr(panel, "MAX_INIT_STEPS", 512)
    monkeypatch.setattr(panel, "MAX_PARAMS", 2)
    with pytest.raises(ConfigError, match=r"init\[2\].params"):
        load_panel_profile(write(tmp_path, MINIMAL.replace("{ command = 0x29 }", "{ command = 0x29, params = [1,2,3] }",
                                                           1)))
    monkeypatch.setattr(panel, "MAX_BYTES", 100)
    with pytest.raises(ParseError, match="larger than the 100 allowed"):
        load_panel_profile(write(tmp_path, MINIMAL))
    with pytest.raises(ParseError, match="larger than the 100 allowed"):
        read_panel_profile(MINIMAL, "text")
    monkeypatch.setattr(panel, "MAX_BYTES", 1 << 20)
    with pytest.raises(ParseError, match="nested more than"):
        read_panel_profile(MINIMAL + "x = " + "[" * 20 + "]" * 20, "text")
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b"name = '\xff'")
    with pytest.raises(ParseError, match="not UTF-8"):
        load_panel_profile(bad)


def test_init_step_checks():
    for bad in (dict(command=256), dict(command=True), dict(command=1, params=[1]), dict(command=1, delay_ms=-1),
                dict(command=1, delay_ms=float("nan")), dict(command=1, params=bytes(256))):
        with pytest.raises(ConfigError):
            InitStep(**bad)


def test_init_file(tmp_path):
    (tmp_path / "panel.bin").write_bytes(KERNEL_EXAMPLE)
    text = MINIMAL.replace(
        "init = [ { command = 0x01, delay_ms = 150 }, { command = 0x11, delay_ms = 120 }, { command = 0x29 } ]",
        'init_file = "panel.bin"')
    p = load_panel_profile(write(tmp_path, text))
    assert p.init == (InitStep(0x11, b"", 120.0), InitStep(0xB1, b"\x01\x2c\x2d"), InitStep(0x29))
    with pytest.raises(ConfigError, match="exactly one of them"):
        load_panel_profile(write(tmp_path, MINIMAL.replace("init = [", 'init_file = "panel.bin"\ninit = [')))
    with pytest.raises(ConfigError, match="key 'init_file': expected an existing"):
        load_panel_profile(write(tmp_path, text.replace("panel.bin", "other.bin")))
    with pytest.raises(ConfigError, match="absolute name"):
        read_panel_profile(text, "text")
    (tmp_path / "panel.bin").write_bytes(KERNEL_EXAMPLE[:20])
    with pytest.raises(ParseError, match=r"panel\.bin, byte offset 18"):
        load_panel_profile(write(tmp_path, text))


def test_clock_check_warns_never_refuses(caplog):
    p = load_panel_profile("ili9341_240x320")
    with caplog.at_level(logging.WARNING, logger="pixelpen.profiles.panel"):
        assert p.check_clock("spi", 10e6) and not caplog.records
        assert not p.check_clock("spi", 40e6)
    assert "above the ili9341 datasheet limit of 10 MHz" in caplog.text


SEEDS = [e.read_bytes() for e in sorted(resources.files("pixelpen").joinpath("data", "panels").iterdir(),
                                        key=lambda e: e.name) if e.name.endswith(".toml")] + [MINIMAL.encode()]


def read_bytes(data: bytes) -> None:
    """Fuzz target: the bytes as profile text (undecodable bytes replaced)."""
    read_panel_profile(data.decode("utf-8", "replace"), "fuzz")


def test_fuzz_profiles():
    campaign("panel profiles", read_bytes, SEEDS, QUICK_CASES, seed=10).check()


@pytest.mark.slow
def test_fuzz_profiles_long():
    campaign("panel profiles", read_bytes, SEEDS, SLOW_CASES, seed=11).check()

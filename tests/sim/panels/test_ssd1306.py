"""The SSD1306-family simulator against the datasheets: init and frame sequences, pointer rules, scan-out, fuzz.

Oracles: luma.oled's init/frame byte sequences (panels.md §1), a scalar reference of the GDDRAM pointer
written from SSD1306 Rev 1.1 §10.1.3 (hypothesis), a per-pixel packer written from §8.7 (bit 0 = top row),
PIL's transposes for the segment remap / COM direction, and the datasheet's reset values and parameter counts.
"""

from __future__ import annotations

import random

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image, ImageDraw

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError, ProtocolError, URLError
from pixelpen.sim.base import Fault, create_simulator
from pixelpen.sim.panels.ssd1306 import SSD1306Sim
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign

LUMA_INIT = bytes.fromhex("AE D5 80 A8 3F D3 00 40 8D 14 20 00 A1 C8 DA 12 D9 F1 DB 40 A4 A6 81 CF AF")
FRAME = bytes.fromhex("21 00 7F 22 00 07")


def picture(width: int = 128, height: int = 64, seed: int = 1) -> Image.Image:
    """A mode "1" test image with text, lines and random dots (asymmetric in both axes)."""
    image = Image.new("1", (width, height))
    draw = ImageDraw.Draw(image)
    draw.rectangle((0, 0, width - 1, height - 1), outline=1)
    draw.text((3, 2), "Hi 42", fill=1)
    draw.line((0, 0, width // 2, height - 5), fill=1)
    rng = random.Random(seed)
    for _ in range(40):
        draw.point((rng.randrange(width), rng.randrange(height)), fill=1)
    return image


def pack(image: Image.Image) -> bytes:
    """GDDRAM bytes for an image, page by page, column by column: bit b of page p is row 8p + b (§8.7)."""
    width, height = image.size
    out = bytearray()
    for page in range(height // 8):
        for x in range(width):
            out.append(sum(1 << b for b in range(8) if image.getpixel((x, 8 * page + b))))
    return bytes(out)


def bits(glass: Image.Image) -> np.ndarray:
    return np.asarray(glass, dtype=bool)


def luma_module(width: int = 128, height: int = 64, **kwargs: object) -> SSD1306Sim:
    sim = SSD1306Sim(width, height, clock=SimulatedClock(), **kwargs)  # type: ignore[arg-type]
    settings_ = {64: (0x3F, 0x12), 32: (0x1F, 0x02), 48: (0x2F, 0x12), 16: (0x0F, 0x02)}[height]
    init = bytearray(LUMA_INIT)
    init[4], init[15] = settings_
    sim.i2c_write(0x3C, b"\x00" + bytes(init))
    return sim


def show(sim: SSD1306Sim, image: Image.Image, colstart: int = 0) -> None:
    width, height = image.size
    sim.i2c_write(0x3C, b"\x00" + bytes([0x21, colstart, colstart + width - 1, 0x22, 0, height // 8 - 1]))
    sim.i2c_write(0x3C, b"\x40" + pack(image))


# ---- luma's sequences ---------------------------------------------------------------------------------------

def test_luma_init_then_a_frame_shows_the_image():
    sim = luma_module()
    image = picture()
    sim.i2c_write(0x3C, b"\x00" + FRAME)
    sim.i2c_write(0x3C, b"\x40" + pack(image))
    assert sim.events == []
    assert sim.glass().mode == "1" and sim.glass().size == (128, 64)
    assert np.array_equal(bits(sim.glass()), bits(image))
    assert sim.gram.shape == (8, 128) and bytes(sim.gram.tobytes()) == pack(image)


@pytest.mark.parametrize(("width", "height", "colstart"), [(128, 32, 0), (64, 48, 32), (96, 16, 0)])
def test_smaller_modules_show_their_window(width, height, colstart):
    sim = luma_module(width, height)
    image = picture(width, height)
    show(sim, image, colstart)
    assert sim.events == []
    assert np.array_equal(bits(sim.glass()), bits(image))


def test_spi_command_and_data_give_the_same_glass_as_i2c():
    sim = SSD1306Sim()
    sim.command(LUMA_INIT)
    sim.command(FRAME)
    sim.data(pack(picture()))
    assert np.array_equal(bits(sim.glass()), bits(picture())) and sim.events == []
    assert sim.stats.command_bytes == len(LUMA_INIT) + 6 and sim.stats.data_bytes == 1024


def i2c_styles(stream: list[tuple[bool, bytes]]) -> dict[str, list[bytes]]:
    """(is_data, bytes) runs as luma (0x00/0x40 streams), Adafruit (0x80 per command) and displayio (pairs)."""
    luma = [(b"\x40" if d else b"\x00") + run for d, run in stream]
    adafruit = [b for d, run in stream for b in ([b"\x40" + run] if d else [bytes([0x80, c]) for c in run])]
    pairs = [b"".join(bytes([0xC0 if d else 0x80, c]) for d, run in stream for c in run)]
    return {"luma": luma, "adafruit": adafruit, "displayio": pairs}


def test_the_three_i2c_producer_styles_give_identical_gddram():
    stream = [(False, LUMA_INIT + FRAME), (True, pack(picture(seed=3)))]
    grams = []
    for payloads in i2c_styles(stream).values():
        sim = SSD1306Sim()
        for payload in payloads:
            assert sim.i2c_write(0x3C, payload)
        assert sim.events == []
        grams.append(sim.gram.copy())
    assert all(np.array_equal(grams[0], g) for g in grams)
    assert bytes(grams[0].tobytes()) == pack(picture(seed=3))


def test_i2c_address_and_bus_time():
    sim = SSD1306Sim(address=0x3D, clock_hz=400e3)
    assert not sim.i2c_write(0x3C, b"\x00\xaf")
    sim.i2c_write(0x3D, b"\x00" + FRAME)
    sim.i2c_write(0x3D, b"\x40" + bytes(1024))
    assert round(sim.stats.bus_seconds * 1e3, 1) == 23.3  # panels.md §4
    spi = SSD1306Sim()
    spi.command(FRAME)
    spi.data(bytes(1024))
    assert spi.stats.bus_seconds == pytest.approx(8 * 1030 / 10e6)  # 0.82 ms at 10 MHz


# ---- the pointer rules (scalar reference from §10.1.3) -------------------------------------------------------

class Reference:
    """GDDRAM and pointer per the datasheet text, one byte at a time."""

    def __init__(self) -> None:
        self.ram: list[list[int | None]] = [[None] * 128 for _ in range(8)]
        self.mode = 2
        self.cs, self.ce, self.ps, self.pe = 0, 127, 0, 7
        self.col = self.page = 0

    def command(self, cmd: list[int]) -> None:
        c = cmd[0]
        if c == 0x20 and cmd[1] != 3:
            self.mode = cmd[1]
        elif c == 0x21:
            self.cs, self.ce, self.col = cmd[1], cmd[2], cmd[1]
        elif c == 0x22:
            self.ps, self.pe, self.page = cmd[1], cmd[2], cmd[1]
        elif 0xB0 <= c <= 0xB7:
            self.page = c - 0xB0
        elif c <= 0x0F:
            self.col = (self.col & 0xF0) | c
        elif c <= 0x17:
            self.col = (self.col & 0x0F) | (c - 0x10) << 4

    def data(self, byte: int) -> None:
        self.ram[self.page][self.col] = byte
        if self.mode == 2:  # page: column +1, back to 0 after the last column, same page
            self.col = 0 if self.col == 127 else self.col + 1
        elif self.mode == 0:  # horizontal: column +1; at the end column: start column, next page (wrapping)
            if self.col == self.ce:
                self.col = self.cs
                self.page = self.ps if self.page == self.pe else self.page + 1
            else:
                self.col += 1
        else:  # vertical: page +1; at the end page: start page, next column (wrapping)
            if self.page == self.pe:
                self.page = self.ps
                self.col = self.cs if self.col == self.ce else self.col + 1
            else:
                self.page += 1


window = st.tuples(st.integers(0, 127), st.integers(0, 127)).map(sorted)
pages = st.tuples(st.integers(0, 7), st.integers(0, 7)).map(sorted)
step = st.one_of(
    st.tuples(st.just("mode"), st.integers(0, 2)),
    st.tuples(st.just("cols"), window),
    st.tuples(st.just("pages"), pages),
    st.tuples(st.just("page"), st.integers(0, 7)),
    st.tuples(st.just("column"), st.integers(0, 127)),
    st.tuples(st.just("data"), st.binary(min_size=1, max_size=2100)),
)


@settings(max_examples=120, deadline=None)
@given(st.lists(step, min_size=1, max_size=12))
def test_pointer_rules_match_the_datasheet_in_every_mode(steps):
    sim, ref = SSD1306Sim(), Reference()
    for kind, value in steps:
        if kind == "data":
            sim.data(value)
            for b in value:
                ref.data(b)
            continue
        if kind in ("column", "page") and ref.mode != 2:
            continue  # page-mode commands; outside page mode they may leave the window (undefined)
        if kind == "column":
            cmds = [[value & 0x0F], [0x10 | value >> 4]]
        elif kind == "page":
            cmds = [[0xB0 + value]]
        elif kind == "mode" and value != 2:  # into horizontal/vertical: the window puts the pointer in it
            cmds = [[0x20, value], [0x21, ref.cs, ref.ce], [0x22, ref.ps, ref.pe]]
        else:
            cmds = [[{"mode": 0x20, "cols": 0x21, "pages": 0x22}[kind], *([value] if kind == "mode" else value)]]
        for cmd in cmds:
            sim.command(bytes(cmd))
            ref.command(cmd)
    written = np.array([[b is not None for b in row] for row in ref.ram])
    expected = np.array([[b or 0 for b in row] for row in ref.ram], dtype=np.uint8)
    assert np.array_equal(sim.gram[written], expected[written])
    assert sim.events == []


def test_horizontal_window_wraps_to_its_start_and_vertical_mode_goes_down_first():
    sim = SSD1306Sim()
    sim.command(bytes([0x20, 0x00, 0x21, 10, 11, 0x22, 2, 3]))
    sim.data(bytes([1, 2, 3, 4, 5]))  # (10,2) (11,2) (10,3) (11,3) then back to (10,2)
    assert sim.gram[2, 10] == 5 and sim.gram[2, 11] == 2 and sim.gram[3, 10] == 3 and sim.gram[3, 11] == 4
    sim.command(bytes([0x20, 0x01, 0x21, 0, 1, 0x22, 0, 1]))
    sim.data(bytes([7, 8, 9]))  # (0,0) (0,1) (1,0)
    assert (sim.gram[0, 0], sim.gram[1, 0], sim.gram[0, 1]) == (7, 8, 9)


def walk_outside_window(mode: int, window: tuple[int, int, int, int], column: int, page: int,
                        data: bytes) -> tuple[np.ndarray, tuple[int, int]]:
    """GDDRAM (unwritten cells -1) and the pointer after ``data`` at (column, page), one byte at a time by the
    documented rule for a pointer outside its window or a window with start > end: horizontal — column +1
    (wrapping at the RAM edge), at the end column back to the start column and the next page (after the end
    page the start page); vertical — the same with pages first."""
    cs, ce, ps, pe = window
    ram = np.full((8, 128), -1)
    for byte in data:
        ram[page, column] = byte
        if mode == 0:
            if column == ce:
                column, page = cs, (ps if page == pe else (page + 1) % 8)
            else:
                column = (column + 1) % 128
        elif page == pe:
            column, page = (cs if column == ce else (column + 1) % 128), ps
        else:
            page = (page + 1) % 8
    return ram, (column, page)


@pytest.mark.parametrize(("mode", "window", "column", "page"), [
    (0, (10, 20, 2, 3), 100, 6),  # horizontal, the pointer right of and below its window (moved by nibbles/B6)
    (0, (100, 20, 5, 2), 3, 0),  # horizontal, both starts past their ends
    (1, (10, 20, 2, 3), 0, 7),  # vertical, the pointer outside
    (1, (64, 1, 6, 6), 127, 1),  # vertical, a one-page window with start column > end column
])
@pytest.mark.parametrize("n", [1, 700, 5000, 100_003])
def test_a_pointer_outside_its_window_walks_as_the_byte_by_byte_rule_for_any_length(mode, window, column, page, n):
    cs, ce, ps, pe = window
    data = bytes(np.random.default_rng(n).integers(0, 256, n, dtype=np.uint8))
    sim = SSD1306Sim()
    sim.command(bytes([0x20, mode, 0x21, cs, ce, 0x22, ps, pe]))
    sim.command(bytes([0xB0 + page, column & 0x0F, 0x10 | column >> 4]))  # B0-B7 and nibbles move it in any mode
    sim.data(data)
    ram, pointer = walk_outside_window(mode, window, column, page, data)
    written = ram >= 0
    assert np.array_equal(sim.gram[written], ram[written])
    assert (sim.column, sim.page) == pointer
    sim.data(b"\xa5")  # and the next byte lands where the rule says
    assert sim.gram[pointer[1], pointer[0]] == 0xA5


def test_page_mode_nibbles_and_page_start():
    sim = SSD1306Sim()
    sim.command(bytes([0xB5, 0x0A, 0x17]))  # column 0x7A on page 5
    sim.data(bytes(range(1, 9)))  # 7A..7F then wraps to column 0 of the same page
    assert list(sim.gram[5, 0x7A:]) == [1, 2, 3, 4, 5, 6] and list(sim.gram[5, :2]) == [7, 8]


def test_a_half_set_column_may_pass_the_ram_until_its_other_nibble_arrives():
    sim = SSD1306Sim(variant="sh1106")
    sim.command(bytes([0xB0, 0x03, 0x18]))  # column 0x83 = 131, the last one
    sim.data(b"\x01")  # the pointer wraps to column 0
    sim.command(bytes([0x18, 0x0F, 0x11]))  # 0x80, then 0x8F (past 131), then 0x1F
    sim.data(b"\x02")
    assert sim.gram[0, 131] == 1 and sim.gram[0, 0x1F] == 2 and sim.events == []
    sim.command(bytes([0x0F, 0x18]))  # 0x8F
    sim.data(b"\x03")
    assert "past the 132 RAM columns" in sim.events[-1].message and sim.gram[0, 0x8F - 132] == 3


# ---- SH1106 ---------------------------------------------------------------------------------------------------

def test_sh1106_page_mode_with_column_offset_2():
    sim = SSD1306Sim(variant="sh1106")
    assert sim.gram.shape == (8, 132)
    sim.command(bytes.fromhex("AE A8 3F D3 00 40 A1 C8 DA 12 A6 A4 81 7F AF"))
    image = picture()
    data = pack(image)
    for page in range(8):
        sim.command(bytes([0xB0 + page, 0x02, 0x10]))  # luma: B0+p, low nibble 2, high nibble 0
        sim.data(data[128 * page:128 * (page + 1)])
    assert sim.events == []
    assert np.array_equal(bits(sim.glass()), bits(image))


def test_sh1106_has_no_addressing_mode_or_window_commands():
    sim = SSD1306Sim(variant="sh1106")
    sim.command(bytes([0x20, 0x21, 0x22]))
    assert [e.command for e in sim.events] == [0x20, 0x21, 0x22]
    assert all("prohibited" in e.message for e in sim.events)


# ---- scan-out: what the glass shows ---------------------------------------------------------------------------

def test_segment_remap_and_com_direction_mirror_and_flip_the_glass():
    image = picture()
    cases = {b"\xa1\xc8": image, b"\xa0\xc8": image.transpose(Image.Transpose.FLIP_LEFT_RIGHT),
             b"\xa1\xc0": image.transpose(Image.Transpose.FLIP_TOP_BOTTOM),
             b"\xa0\xc0": image.transpose(Image.Transpose.ROTATE_180)}
    for commands, expected in cases.items():
        sim = luma_module()
        show(sim, image)
        sim.command(commands)
        assert np.array_equal(bits(sim.glass()), bits(expected)), commands.hex()
        assert bytes(sim.gram.tobytes()) == pack(image)  # scan-out never changes RAM


@pytest.mark.parametrize("lines", [1, 8, 37, 63])
def test_start_line_and_offset_roll_the_rows_with_multiplex_64(lines):
    image = picture()
    expected = np.roll(bits(image), -lines, axis=0)  # glass row y shows RAM row (y + lines) mod 64
    for command in (bytes([0x40 + lines]), bytes([0xD3, lines])):
        sim = luma_module()
        show(sim, image)
        sim.command(command)
        assert np.array_equal(bits(sim.glass()), expected)


def test_multiplex_48_drives_only_48_rows():
    sim = luma_module()
    image = picture()
    show(sim, image)
    sim.command(bytes([0xA8, 47]))  # C8 scans COM47..COM0: on this module (mounted for A1/C8) the lower 48 rows
    glass = bits(sim.glass())
    assert np.array_equal(glass[16:], bits(image)[:48]) and not glass[:16].any()


def test_com_pins_mismatch_interleaves_rows():
    sim = luma_module()
    image = picture()
    show(sim, image)
    sim.command(bytes([0xDA, 0x02]))  # sequential on a module wired for alternative: every row still shown once
    glass = bits(sim.glass())
    assert not np.array_equal(glass, bits(image))
    rows = {bytes(r) for r in np.packbits(bits(image), axis=1)}
    assert {bytes(r) for r in np.packbits(glass, axis=1)} == rows
    sim.command(bytes([0xDA, 0x12]))
    assert np.array_equal(bits(sim.glass()), bits(image))


def test_invert_entire_on_display_off_and_contrast():
    sim = luma_module()
    image = picture()
    show(sim, image)
    sim.command(b"\xa7")
    assert np.array_equal(bits(sim.glass()), ~bits(image))
    sim.command(b"\xa6\xa5")
    assert bits(sim.glass()).all()
    sim.command(b"\xa4\xae")
    assert not bits(sim.glass()).any()
    sim.command(b"\xaf\x81\x00")
    shaded = np.asarray(sim.glass(shaded=True))
    assert set(np.unique(shaded)) == {0, 1}  # 255 * (0 + 1) / 256 rounds to 1
    sim.command(b"\x81\xff")
    assert np.array_equal(np.asarray(sim.glass(shaded=True)) == 255, bits(image))


def test_display_on_without_charge_pump_is_flagged_and_dark():
    sim = SSD1306Sim()
    sim.command(bytes([0xA5, 0xAF]))
    assert [e.command for e in sim.events] == [0xAF] and "charge pump" in sim.events[0].message
    assert not bits(sim.glass()).any()
    sim.command(bytes([0x8D, 0x14]))
    assert bits(sim.glass()).all()
    external = SSD1306Sim(variant="ssd1309")
    external.command(bytes([0xA5, 0xAF]))
    assert external.events == [] and bits(external.glass()).all()


def test_reset_values_and_what_reset_keeps():
    sim = luma_module()
    show(sim, picture())
    sim.reset()
    assert (sim.contrast, sim.multiplex, sim.mode, sim.display_on, sim.segment_remap) == (0x7F, 64, 2, False, False)
    assert bytes(sim.gram.tobytes()) == pack(picture())  # RES# keeps GDDRAM
    sim.inject(Fault.POWER_LOSS)
    assert bytes(sim.gram.tobytes()) != pack(picture())  # power loss does not


# ---- parameters, scrolling, malformed input ------------------------------------------------------------------

def test_parameter_counts_of_scroll_commands():
    sim = SSD1306Sim()
    sim.command(bytes.fromhex("26 00 00 00 07 00 FF  29 00 00 00 07 01  A3 00 40  2F"))
    assert sim.scrolling and sim.events == [] and sim.scroll == (0x29, bytes([0, 0, 0, 7, 1]))
    assert sim.scroll_area == (0, 0x40)
    sim.data(b"\x01")
    assert "scrolling is active" in sim.events[-1].message
    sim.command(b"\x2e\x8d\x14\xaf")
    assert not sim.scrolling and sim.display_on


def test_frame_rate_of_luma_settings_and_of_reset():
    sim = luma_module()
    assert round(sim.frame_rate, 1) == 87.6  # panels.md §1: D5 80, D9 F1 at the typical 370 kHz
    sim.reset()
    assert round(sim.frame_rate) == 107  # K = 54 at reset: within the 96-118 Hz of panels.md


def scrolling(commands: bytes, steps: int) -> SSD1306Sim:
    """A luma module showing ``picture()`` that ran ``commands`` then 2Fh, ``steps`` scroll steps of 2 frames."""
    sim = luma_module()
    show(sim, picture())
    sim.command(commands + b"\x2f")
    sim.clock.advance((steps * 2 + 0.5) / sim.frame_rate)  # type: ignore[attr-defined]
    return sim


@pytest.mark.parametrize(("code", "sign"), [(0x26, 1), (0x27, -1)])
def test_continuous_horizontal_scroll_moves_the_pages_and_2e_leaves_ram_moved(code, sign):
    sim = scrolling(bytes([code, 0x00, 0x02, 0x07, 0x05, 0x00, 0xFF]), 3)  # pages 2..5, a step every 2 frames
    expected = bits(picture()).copy()
    expected[16:48] = np.roll(expected[16:48], 3 * sign, axis=1)
    assert np.array_equal(bits(sim.glass()), expected)
    assert bytes(sim.gram.tobytes()) == pack(picture())
    sim.command(b"\x2e")
    assert np.array_equal(bits(sim.glass()), expected)
    assert bytes(sim.gram.tobytes()) == pack(Image.fromarray(expected))


def test_vertical_and_horizontal_scroll_in_the_a3_area():
    sim = scrolling(bytes.fromhex("A3 00 40 29 00 00 07 07 01"), 2)
    expected = np.roll(np.roll(bits(picture()), 2, axis=1), -2, axis=0)
    assert np.array_equal(bits(sim.glass()), expected)


def test_flagged_commands():
    sim = SSD1306Sim()
    sim.command(bytes([0x20, 0x03, 0xA8, 0x05, 0xD9, 0x00, 0x2F, 0xFF, 0x18]))
    assert [e.command for e in sim.events] == [0x20, 0xA8, 0xD9, 0x2F, 0xFF, 0x18]
    assert sim.mode == 2 and sim.multiplex == 64
    sim.command(b"\x81")
    sim.data(b"\x01")
    assert "truncated: 0 of 1" in sim.events[-1].message and sim.contrast == 0x7F


def test_strict_raises_protocol_error():
    sim = SSD1306Sim(strict=True)
    with pytest.raises(ProtocolError, match="0xFF"):
        sim.command(b"\xff")


def test_faster_than_the_datasheet_clock_is_reported():
    sim = SSD1306Sim(clock_hz=1e6)
    sim.i2c_write(0x3C, b"\x00\xe3")
    sim.command(b"\xe3")
    assert [e.message.split(" ")[0] for e in sim.events] == ["I2C"]


def test_frames_count_data_ended_by_a_command():
    sim = SSD1306Sim()
    for _ in range(3):
        sim.command(FRAME)
        sim.data(bytes(1024))
    assert sim.stats.frames == 2  # the third ends with the next command
    sim.command(b"\xe3")
    assert sim.stats.frames == 3


@pytest.mark.parametrize("address", ["0x07", "0x78", "0x7f", "0x100", "-1"])
def test_the_address_option_is_a_non_reserved_7_bit_address(address):
    with pytest.raises(URLError, match=rf"sim:ssd1306: option address='{address}' is not valid: .*0x08\.\.0x77"):
        create_simulator("ssd1306", address=address)
    with pytest.raises(ConfigError, match=r"ssd1309: I2C address 0x78 is not a 7-bit address 0x08\.\.0x77"):
        SSD1306Sim(variant="ssd1309", address=0x78)
    assert create_simulator("sh1106", address="0x08").i2c_address == 0x08
    assert create_simulator("ssd1306", address="0x77").i2c_address == 0x77


def test_registry_and_options():
    sim = create_simulator("ssd1306", size="128x32", address="0x3d", hz="1000000")
    assert isinstance(sim, SSD1306Sim) and (sim.width, sim.height, sim.i2c_address) == (128, 32, 0x3D)
    sh = create_simulator("sh1106")
    assert sh.model == "sh1106" and sh.colstart == 2
    assert create_simulator("ssd1309").external_vcc
    with pytest.raises((ConfigError, URLError)):
        create_simulator("ssd1306", size="128x65")
    with pytest.raises((ConfigError, URLError)):
        create_simulator("ssd1306", colour="red")
    with pytest.raises(ConfigError):
        SSD1306Sim(200, 64)


# ---- fuzz --------------------------------------------------------------------------------------------------

SEEDS = [b"\x00" + LUMA_INIT, b"\x00" + FRAME + b"\x40" + bytes(range(256)) * 4,
         bytes.fromhex("80AE80D58080C0FF00B00210"), bytes.fromhex("00 26 00 00 00 07 00 FF 2F 40 A5")]


def replay(variant: str, data: bytes) -> SSD1306Sim:
    """The bytes as I2C transactions split at every 0x3C byte, then as alternating SPI command/data frames."""
    sim = SSD1306Sim(variant=variant, clock=SimulatedClock())
    for chunk in data.split(b"\x3c"):
        sim.i2c_write(0x3C, chunk)
    for i in range(0, len(data), 7):
        sim.spi_transfer(data[i:i + 7], dc=bool(i % 2))
    sim.glass()
    return sim


@pytest.mark.parametrize("variant", ["ssd1306", "sh1106", "ssd1309"])
def test_fuzzed_streams_never_crash(variant):
    result = campaign(f"ssd1306-{variant}", lambda data: replay(variant, data), SEEDS, QUICK_CASES // 3, seed=7,
                      seconds_per_case=2.0)
    result.check()
    rng = random.Random(5)
    noise = bytes(rng.randrange(256) for _ in range(3000))
    sim = replay(variant, noise)
    assert sim.events and all(e.message and e.offset >= -1 for e in sim.events)


@pytest.mark.slow
@pytest.mark.parametrize("variant", ["ssd1306", "sh1106", "ssd1309"])
def test_fuzz_campaign(variant):
    campaign(f"ssd1306-{variant}-slow", lambda data: replay(variant, data), SEEDS, SLOW_CASES, seed=11).check()

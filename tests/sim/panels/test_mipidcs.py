"""The MIPI-DCS simulator against the datasheets: address mapping, pixel formats, init tables, delays, glass, fuzz.

Oracles: the ST7789VW/ILI9341/ST7735 datasheet text (MADCTL worked examples, COLMOD bit layouts, waits),
a scalar reference of the address counters written from ST7789VW §8.12, byte sequences of Adafruit's and
luma's init tables, the module makers' published offsets (Adafruit, TFT_eSPI, Pimoroni) with PIL's
rotations for the expected glass.
"""

from __future__ import annotations

import random

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError, ProtocolError, URLError
from pixelpen.sim.base import Fault, create_simulator
from pixelpen.sim.panels.mipidcs import MipiDcsSim
from tests.fuzzing import QUICK_CASES, SLOW_CASES, campaign


def make(model: str = "st7789", width: int = 240, height: int = 240, **options: object) -> MipiDcsSim:
    """A simulator on a simulated clock, one second after power-on (past every power-up wait)."""
    clock = SimulatedClock()
    sim = MipiDcsSim(model, width, height, clock=clock, **options)  # type: ignore[arg-type]
    clock.advance(1.0)
    return sim


def later(sim: MipiDcsSim, seconds: float) -> None:
    sim.clock.advance(seconds)  # type: ignore[attr-defined]


def send(sim: MipiDcsSim, code: int, *params: int) -> None:
    sim.command(bytes([code]))
    if params:
        sim.data(bytes(params))


def awake(sim: MipiDcsSim, *, madctl: int = 0, colmod: int = 0x66, invert: bool = True) -> MipiDcsSim:
    """SLPOUT, the datasheet's waits, MADCTL, COLMOD, INVON, DISPON."""
    send(sim, 0x11)
    later(sim, 0.120)
    send(sim, 0x36, madctl)
    send(sim, 0x3A, colmod)
    send(sim, 0x21 if invert else 0x20)
    send(sim, 0x29)
    return sim


def window(sim: MipiDcsSim, xs: int, xe: int, ys: int, ye: int) -> None:
    send(sim, 0x2A, xs >> 8, xs & 0xFF, xe >> 8, xe & 0xFF)
    send(sim, 0x2B, ys >> 8, ys & 0xFF, ye >> 8, ye & 0xFF)


def rgb666(pixels: object) -> bytes:
    """(n, 3) 6-bit components as 18-bit serial bytes (component in the top six bits)."""
    return (np.asarray(pixels, dtype=np.uint8) << 2).tobytes()


def index_colours(n: int) -> np.ndarray:
    """Pixel i coloured with i's 18 bits (6 per component), so a gram cell tells which pixel landed there."""
    i = np.arange(n)
    return np.stack([(i >> 12) & 63, (i >> 6) & 63, i & 63], axis=1).astype(np.uint8)


def gram_index(sim: MipiDcsSim, row: int, col: int) -> int:
    r, g, b = (int(v) for v in sim.gram[row, col])
    return r << 12 | g << 6 | b


def messages(sim: MipiDcsSim) -> list[str]:
    return [event.message for event in sim.events]


def upright(image: Image.Image, sim: MipiDcsSim) -> bool:
    """The glass shows ``image`` as it is (tests that reason in memory order hold ST77xx modules ``turn=180``)."""
    return np.array_equal(np.asarray(sim.glass()), np.asarray(image))


# ---- address mapping: ST7789VW Fig. 33 / §8.12 ------------------------------------------------------------

# (MADCTL, (row, col) of pixel 0, pixel 1 and the first pixel of the second counter line), 240x320 memory:
# MV=0: c runs over columns 0..239; MV=1: c runs over 0..319 and lands on rows.
WORKED = [
    (0x00, (0, 0), (0, 1), (1, 0)),
    (0x80, (319, 0), (319, 1), (318, 0)),        # MY: page order bottom to top
    (0x40, (0, 239), (0, 238), (1, 239)),        # MX: column order right to left
    (0xC0, (319, 239), (319, 238), (318, 239)),
    (0x20, (0, 0), (1, 0), (0, 1)),              # MV: row/column exchange
    (0xA0, (319, 0), (318, 0), (319, 1)),
    (0x60, (0, 239), (1, 239), (0, 238)),
    (0xE0, (319, 239), (318, 239), (319, 238)),
]


@pytest.mark.parametrize("madctl, first, second, next_line", WORKED)
def test_madctl_worked_examples_over_the_whole_memory(madctl, first, second, next_line):
    sim = awake(make("st7789", 240, 320), madctl=madctl)
    across, down = (320, 240) if madctl & 0x20 else (240, 320)
    window(sim, 0, across - 1, 0, down - 1)
    send(sim, 0x2C)
    sim.data(rgb666(index_colours(across * down)))
    assert gram_index(sim, *first) == 0
    assert gram_index(sim, *second) == 1
    assert gram_index(sim, *next_line) == across
    flat = sim.gram[..., 0].astype(np.int64) << 12 | sim.gram[..., 1].astype(np.int64) << 6 | sim.gram[..., 2]
    assert sorted(flat.ravel().tolist()) == list(range(240 * 320))  # every pixel landed exactly once


def reference_cells(madctl: int, xs: int, xe: int, ys: int, ye: int, n: int, cols: int = 240, rows: int = 320):
    """ST7789VW §8.12 as a loop: c over XS..XE first, then p; after (XE, YE) both return to (XS, YS)."""
    cells: list[tuple[int, int] | None] = []
    c, p = xs, ys
    for _ in range(n):
        col, row = (p, c) if madctl & 0x20 else (c, p)
        if col < cols and row < rows:
            cells.append((rows - 1 - row if madctl & 0x80 else row, cols - 1 - col if madctl & 0x40 else col))
        else:
            cells.append(None)  # "data of out of range will be ignored"
        c += 1
        if c > xe:
            c, p = xs, p + 1
            if p > ye:
                p = ys
    return cells


@settings(max_examples=60, deadline=None)
@given(madctl=st.sampled_from([m for m, *_ in WORKED]), xs=st.integers(0, 330), w=st.integers(1, 40),
       ys=st.integers(0, 330), h=st.integers(1, 40), extra=st.integers(-30, 60), pieces=st.integers(1, 4))
def test_window_writes_match_the_scalar_reference(madctl, xs, w, ys, h, extra, pieces):
    sim = awake(make("st7789", 240, 320), madctl=madctl)
    xe, ye = xs + w - 1, ys + h - 1
    n = max(1, w * h + extra)
    window(sim, xs, xe, ys, ye)
    before = sim.gram.copy()
    colours = np.random.default_rng(n).integers(0, 64, (n, 3), dtype=np.uint8)
    send(sim, 0x2C)
    data = rgb666(colours)
    cut = sorted(random.Random(n).sample(range(len(data) + 1), pieces - 1)) if pieces > 1 else []
    for a, b in zip([0, *cut], [*cut, len(data)], strict=True):
        sim.data(data[a:b])  # one chip-select frame each: RAMWR goes on across them
    send(sim, 0x00)
    expected = before
    for k, cell in enumerate(reference_cells(madctl, xs, xe, ys, ye, n)):
        if cell is not None:
            expected[cell] = colours[k]
    assert np.array_equal(sim.gram, expected)


@pytest.mark.parametrize("model, code, params, cell", [
    ("st7789", 0xC0, (0x2C ^ 0x08,), (0, 239)),        # LCMCTRL XMX (reset value 2Ch): MX exchanged
    ("st7789", 0xC0, (0x2C ^ 0x40,), (319, 0)),        # XMY
    ("ili9341", 0xF6, (0x01 | 0x80, 0, 0), (319, 0)),  # interface control MY_EOR
    ("ili9341", 0xF6, (0x01 | 0x40, 0, 0), (0, 239)),  # MX_EOR
])
def test_lcmctrl_and_interface_control_exchange_madctl_bits(model, code, params, cell):
    sim = awake(make(model, 240, 320))
    send(sim, code, *params)
    window(sim, 0, 0, 0, 0)
    send(sim, 0x2C, *rgb666([[7, 7, 7]]))
    assert sim.gram[cell][0] == 7 and sim.events == []


def test_gamset_takes_only_the_four_curves():
    sim = awake(make("st7789", 240, 320))
    send(sim, 0x26, 0x03)
    assert messages(sim) == ["GAMSET 0x03 is not a curve (01h, 02h, 04h, 08h): ignored"]


def test_wrmemc_continues_after_the_last_pixel_written():
    sim = awake(make("st7789", 240, 320))
    window(sim, 10, 13, 20, 21)
    send(sim, 0x2C, *rgb666([[1, 1, 1], [2, 2, 2], [3, 3, 3]]))
    send(sim, 0x3C, *rgb666([[4, 4, 4], [5, 5, 5]]))
    assert [int(sim.gram[20, c, 0]) for c in range(10, 14)] == [1, 2, 3, 4]
    assert int(sim.gram[21, 10, 0]) == 5


def test_ramwr_goes_on_across_held_and_released_chip_select_and_empty_data_phases():
    sim = awake(make("st7789", 240, 320))
    window(sim, 0, 4, 0, 0)
    send(sim, 0x2C)
    sim.chip_select(True)
    sim.data(rgb666([[1, 1, 1]]))
    assert sim.spi_transfer(rgb666([[2, 2, 2], [3, 3, 3]]), dc=True) == bytes(6)  # write-only: MISO zeros
    sim.chip_select(False)
    sim.data(b"")
    sim.data(rgb666([[4, 4, 4]])[:2])  # a pixel split across frames
    sim.data(rgb666([[4, 4, 4]])[2:] + rgb666([[5, 5, 5]]))
    assert [int(sim.gram[0, c, 0]) for c in range(5)] == [1, 2, 3, 4, 5]
    assert sim.events == [] and sim.stats.frames == 1


def test_a_read_command_s_data_phase_is_not_flagged():
    sim = awake(make("st7789", 240, 320))
    send(sim, 0x04)
    assert sim.spi_transfer(bytes(4), dc=True) == bytes(4)
    assert sim.events == []


def test_an_oversized_write_keeps_the_last_window_s_worth_and_reports_the_wrap_once():
    sim = awake(make("st7789", 240, 320))
    window(sim, 0, 239, 0, 319)
    frames = np.random.default_rng(3).integers(0, 64, (3 * 320 * 240, 3), dtype=np.uint8)
    send(sim, 0x2C, *rgb666(frames[:10]))
    sim.data(rgb666(frames[10:]))
    assert np.array_equal(sim.gram.reshape(-1, 3), frames[2 * 320 * 240:])
    assert sum("wrapped" in m for m in messages(sim)) == 1


def test_overrun_wraps_to_the_window_start_and_is_reported():
    sim = awake(make("st7789", 240, 320))
    window(sim, 0, 1, 0, 0)
    send(sim, 0x2C, *rgb666([[1, 1, 1], [2, 2, 2], [3, 3, 3]]))
    assert sim.gram[0, 0, 0] == 3 and sim.gram[0, 1, 0] == 2
    assert any("wrapped" in m for m in messages(sim))


# ---- pixel formats: COLMOD ---------------------------------------------------------------------------------

@pytest.mark.parametrize("colmod, data, expected", [
    (0x55, bytes([0xF8, 0x00, 0x07, 0xE0, 0x00, 0x1F, 0x84, 0x10]),
     [(63, 0, 0), (0, 63, 0), (0, 0, 63), (33, 32, 33)]),           # RRRRRGGG GGGBBBBB, r6 = r5<<1 | r5>>4
    (0x66, bytes([0xFC, 0x80, 0x04, 0xFF, 0x03, 0x83]), [(63, 32, 1), (63, 0, 32)]),   # top six bits
    (0x53, bytes([0xF0, 0x0F, 0x84]), [(63, 0, 0), (63, 34, 17)]),   # RRRRGGGG BBBBRRRR GGGGBBBB, r6 = r4<<2|r4>>2
    (0x77, bytes([0x04, 0x08, 0x0C]), [(1, 2, 3)]),                  # ST7789 "16M truncated": 3 bytes, top bits
])
def test_colmod_serial_formats_decode_as_the_datasheet_draws_them(colmod, data, expected):
    sim = awake(make("st7789", 240, 320), colmod=colmod)
    window(sim, 0, len(expected) - 1, 0, 0)
    send(sim, 0x2C, *data)
    assert [tuple(int(v) for v in sim.gram[0, c]) for c in range(len(expected))] == expected


def test_a_12_bit_write_ending_after_one_pixel_of_a_pair_stores_it_and_reports_the_half_group():
    sim = awake(make("st7789", 240, 320), colmod=0x03)
    window(sim, 0, 1, 0, 0)
    send(sim, 0x2C, 0x12, 0x30)
    send(sim, 0x00)
    assert tuple(int(v) for v in sim.gram[0, 0]) == (4, 8, 12)
    assert any("inside a pixel" in m for m in messages(sim))


def test_ili9341_reads_luma_s_colmod_46_as_18_bit_and_refuses_12_bit_on_its_serial_interface():
    sim = awake(make("ili9341", 320, 240), colmod=0x46)
    window(sim, 0, 0, 0, 0)
    send(sim, 0x2C, 0x40, 0x80, 0xC0)
    assert tuple(int(v) for v in sim.gram[0, 0]) == (16, 32, 48)
    send(sim, 0x3A, 0x53)
    assert any("COLMOD 0x53" in m for m in messages(sim))
    assert sim.state.pixel_format.bits == 18


# ---- init tables ---------------------------------------------------------------------------------------------

ADAFRUIT_ST7789 = [  # Adafruit_ST7789.cpp generic_st7789: (command, params, delay ms)
    (0x01, (), 150), (0x11, (), 10), (0x3A, (0x55,), 10), (0x36, (0x08,), 0), (0x2A, (0, 0, 0, 240), 0),
    (0x2B, (0, 0, 320 >> 8, 320 & 0xFF), 0), (0x21, (), 10), (0x13, (), 10), (0x29, (), 10),
]
LUMA_ST7789 = [  # luma.lcd 2.13 st7789.__init__, no delays
    (0x36, (0x70,)), (0x3A, (0x06,)), (0xB2, (0x0C, 0x0C, 0x00, 0x33, 0x33)), (0xB7, (0x35,)), (0xBB, (0x19,)),
    (0xC0, (0x2C,)), (0xC2, (0x01,)), (0xC3, (0x12,)), (0xC4, (0x20,)), (0xC6, (0x0F,)), (0xD0, (0xA4, 0xA1)),
    (0xE0, (0xD0, 0x04, 0x0D, 0x11, 0x13, 0x2B, 0x3F, 0x54, 0x4C, 0x18, 0x0D, 0x0B, 0x1F, 0x23)),
    (0xE1, (0xD0, 0x04, 0x0C, 0x11, 0x13, 0x2C, 0x3F, 0x44, 0x51, 0x2F, 0x1F, 0x1F, 0x20, 0x23)),
    (0x21, ()), (0x11, ()), (0x29, ()),
]
LUMA_ILI9341 = [  # luma.lcd 2.13 ili9341.__init__ (Adafruit's table with the undocumented EF and extended ones)
    (0xEF, (0x03, 0x80, 0x02)), (0xCF, (0x00, 0xC1, 0x30)), (0xED, (0x64, 0x03, 0x12, 0x81)),
    (0xE8, (0x85, 0x00, 0x78)), (0xCB, (0x39, 0x2C, 0x00, 0x34, 0x02)), (0xF7, (0x20,)), (0xEA, (0x00, 0x00)),
    (0xC0, (0x23,)), (0xC1, (0x10,)), (0xC5, (0x3E, 0x28)), (0xC7, (0x86,)), (0x36, (0x28,)), (0x3A, (0x46,)),
    (0xB1, (0x00, 0x18)), (0xB6, (0x08, 0x82, 0x27)), (0xF2, (0x00,)), (0x26, (0x01,)),
    (0xE0, (0x0F, 0x31, 0x2B, 0x0C, 0x0E, 0x08, 0x4E, 0xF1, 0x37, 0x07, 0x10, 0x03, 0x0E, 0x09, 0x00)),
    (0xE1, (0x00, 0x0E, 0x14, 0x03, 0x11, 0x07, 0x31, 0xC1, 0x48, 0x08, 0x0F, 0x0C, 0x31, 0x36, 0x0F)),
    (0x11, ()),
]


def test_adafruit_st7789_init_is_clean_and_leaves_the_datasheet_state():
    sim = make("st7789", 240, 320)
    for code, params, delay in ADAFRUIT_ST7789:
        send(sim, code, *params)
        later(sim, delay / 1000)
    assert sim.events == []
    state = sim.state
    assert (state.sleeping, state.display_on, state.inverted, state.partial) == (False, True, True, False)
    assert (state.madctl, state.pixel_format.bits, state.window) == (0x08, 16, (0, 240, 0, 320))


def test_luma_st7789_init_is_flagged_for_dispon_straight_after_slpout():
    sim = make("st7789", 240, 240)
    for code, params in LUMA_ST7789:
        send(sim, code, *params)
    assert [(e.command, e.message.split(" ms")[0]) for e in sim.events] == [(0x29, "DISPON 0.000")]
    assert "after SLPOUT (datasheet: wait 5 ms" in sim.events[0].message
    state = sim.state
    assert (state.madctl, state.pixel_format.bits, state.inverted, state.display_on) == (0x70, 18, True, True)
    assert state.frame_rate == pytest.approx(10e6 / (344 * 490))  # FRCTRL2 0Fh: "60 Hz"


def test_luma_ili9341_init_accepts_every_command_with_its_count():
    sim = make("ili9341", 320, 240)
    for code, params in LUMA_ILI9341:
        send(sim, code, *params)
    later(sim, 0.120)
    send(sim, 0x29)
    assert sim.events == []
    assert (sim.state.madctl, sim.state.pixel_format.bits) == (0x28, 18)
    assert sim.state.frame_rate == pytest.approx(615e3 / (24 * 324))  # FRMCTR1 RTNA 18h: 24 clocks, "79 Hz"


# ---- what the controller flags ------------------------------------------------------------------------------

def test_a_truncated_caset_is_reported_and_not_carried_out():
    sim = awake(make("st7789", 240, 320))
    window(sim, 5, 6, 7, 8)
    send(sim, 0x2A, 0, 1)
    send(sim, 0x2C)
    assert sim.state.window == (5, 6, 7, 8)
    assert [e.command for e in sim.events] == [0x2A] and "truncated: 2 of 4" in sim.events[0].message


def test_extra_parameters_unknown_commands_and_stray_data_are_reported_once_each():
    sim = awake(make("st7789", 240, 320))
    send(sim, 0x36, 0x00, 0x11, 0x22)
    send(sim, 0x29, 0x01)
    sim.data(b"\x02")
    send(sim, 0xF3, 0x01)
    assert [e.command for e in sim.events] == [0x36, 0x29, 0xF3]
    assert "2 extra" in sim.events[0].message and "undefined command 0xF3" in sim.events[2].message
    assert sim.state.madctl == 0x00


def test_data_before_any_command_and_zero_length_data_phases():
    sim = make("st7789", 240, 320)
    sim.data(b"")
    assert sim.events == []
    sim.data(b"\x01\x02")
    assert messages(sim) == ["2 data byte(s) with no command taking parameters"]


def test_start_after_end_and_windows_past_the_memory_are_reported_and_ignore_the_outside():
    sim = awake(make("st7789", 240, 320))
    window(sim, 9, 3, 0, 0)
    assert "start 9 > end 3" in messages(sim)[0]
    before = sim.gram.copy()
    send(sim, 0x2C, *rgb666([[1, 2, 3]] * 4))
    assert np.array_equal(sim.gram, before)
    window(sim, 238, 241, 0, 0)
    send(sim, 0x2C, *rgb666([[9, 9, 9]] * 4))
    assert sim.gram[0, 238, 0] == 9 and sim.gram[0, 239, 0] == 9
    assert any("exceeds the memory's 240x320" in m for m in messages(sim))


def test_strict_mode_raises_what_the_controller_would_flag():
    sim = awake(make("st7789", 240, 240, strict=True))
    with pytest.raises(ProtocolError, match="0xF3"):
        send(sim, 0xF3)


@pytest.mark.parametrize("model, first, gap_ms, then, flagged", [
    ("st7789", 0x01, 1.0, 0x36, "MADCTL 1.000 ms after SWRESET (datasheet: wait 5 ms"),
    ("st7789", 0x01, 6.0, 0x36, None),
    ("st7789", 0x01, 10.0, 0x11, "SLPOUT 10.000 ms after SWRESET (datasheet: wait 120 ms"),
    ("st7789", 0x10, 130.0, 0x11, None),
    ("ili9341", 0x11, 2.5, 0x29, "DISPON 2.500 ms after SLPOUT (datasheet: wait 5 ms"),
    ("st7735", 0x11, 50.0, 0x29, "DISPON 50.000 ms after SLPOUT (datasheet: wait 120 ms"),
    ("st7735", 0x01, 100.0, 0x3A, "COLMOD 100.000 ms after SWRESET (datasheet: wait 120 ms"),
])
def test_commands_sooner_than_the_datasheet_wait_are_reported_with_the_gap(model, first, gap_ms, then, flagged):
    sim = make(model, *((128, 160) if model == "st7735" else (240, 320)))
    send(sim, first)
    later(sim, gap_ms / 1000)
    send(sim, then, *((0x55,) if then in (0x36, 0x3A) else ()))
    if flagged is None:
        assert messages(sim) == []
    else:
        assert len(sim.events) == 1 and sim.events[0].command == then and messages(sim)[0].startswith(flagged)


def test_a_new_simulator_is_a_panel_powered_long_ago_and_a_power_cut_or_resx_restarts_the_waits():
    clock = SimulatedClock()
    sim = MipiDcsSim("st7789", 240, 240, clock=clock)
    send(sim, 0x11)
    assert sim.events == []
    later(sim, 0.2)
    sim.inject(Fault.POWER_LOSS)
    send(sim, 0x11)
    assert messages(sim) == ["SLPOUT 0.000 ms after RESX (datasheet: wait 5 ms; carried out)",
                             "SLPOUT 0.000 ms after RESX (datasheet: wait 120 ms; carried out)"]
    later(sim, 0.2)
    sim.reset()
    later(sim, 0.006)
    send(sim, 0x11)
    assert messages(sim)[2:] == ["SLPOUT 6.000 ms after RESX (datasheet: wait 120 ms; carried out)"]


def test_slpin_within_120_ms_of_slpout_is_reported():
    sim = make("st7789", 240, 320)
    send(sim, 0x11)
    later(sim, 0.050)
    send(sim, 0x10)
    assert messages(sim) == ["SLPIN 50.000 ms after SLPOUT (datasheet: wait 120 ms; carried out)"]


def test_writes_in_sleep_reach_the_memory_unflagged_while_the_glass_stays_blank():
    sim = make("st7789", 240, 240)
    window(sim, 0, 0, 0, 0)
    send(sim, 0x2C, 0xFC, 0xFC, 0xFC)
    assert tuple(sim.gram[0, 0]) == (63, 63, 63) and sim.events == []
    assert not np.asarray(sim.glass()).any()


# ---- glass ------------------------------------------------------------------------------------------------

def scene(width: int, height: int, seed: int = 1) -> Image.Image:
    """Random colours already on the 6-bit grid (so every format carries them exactly)."""
    values = np.random.default_rng(seed).integers(0, 64, (height, width, 3), dtype=np.uint8)
    return Image.fromarray((values << 2) | (values >> 4), "RGB")


def draw(sim: MipiDcsSim, image: Image.Image, madctl: int, x0: int, y0: int) -> None:
    """Send ``image`` the way a maker's driver does: MADCTL, CASET x0.., RASET y0.., RAMWR 18-bit."""
    send(sim, 0x36, madctl)
    window(sim, x0, x0 + image.width - 1, y0, y0 + image.height - 1)
    send(sim, 0x2C)
    sim.data(image.tobytes())
    send(sim, 0x00)


# (model, module size, MADCTL, CASET/RASET start, the turn that shows the image upright); the offsets are the
# makers'. Adafruit's rotation 0 is upright, TFT_eSPI's rotation 0 (MADCTL 0 on ST77xx) is Adafruit's 2.
R180 = Image.Transpose.ROTATE_180
MAKERS = [
    ("st7789", (240, 240), 0xC0, (0, 80), None),       # Adafruit rotation 0 (rowstart 80)
    ("st7789", (240, 240), 0x00, (0, 0), R180),        # Adafruit rotation 2, TFT_eSPI rotation 0
    ("st7789", (135, 240), 0xC0, (53, 40), None),      # TFT_eSPI rotation 2
    ("st7789", (135, 240), 0x00, (52, 40), R180),      # TFT_eSPI rotation 0
    ("st7789", (240, 135), 0xA0, (40, 52), None),      # Adafruit rotation 1 (MY|MV)
    ("st7789", (240, 135), 0x70, (40, 53), R180),      # Pimoroni 240x135, MADCTL 70h
    ("st7789", (240, 280), 0xC0, (0, 20), None),       # TFT_eSPI rotation 2 (rowstart 20)
    ("st7789", (170, 320), 0x00, (35, 0), R180),       # TFT_eSPI rotation 0 (colstart 35)
    ("st7789", (320, 240), 0xA0, (0, 0), None),        # Adafruit rotation 1
    ("st7789", (320, 240), 0x60, (0, 0), R180),        # TFT_eSPI rotation 1 (MX|MV)
    ("ili9341", (240, 320), 0x48, (0, 0), None),       # Adafruit rotation 0 (MX|BGR)
    ("ili9341", (320, 240), 0x28, (0, 0), None),       # Adafruit rotation 1, luma's default
    ("ili9341", (320, 240), 0xE8, (0, 0), R180),       # Adafruit rotation 3
    ("st7735", (128, 160), 0xC0, (0, 0), None),        # Adafruit black tab rotation 0 (128x160 memory)
    ("st7735", (128, 160), 0x00, (0, 0), R180),        # Adafruit black tab rotation 2
    ("st7735", (80, 160), 0xC8, (26, 1), None),        # TFT_eSPI GREENTAB160x80 rotation 0
]


@pytest.mark.parametrize("model, size, madctl, start, turned", MAKERS)
def test_the_makers_rotations_and_offsets_put_the_image_on_the_glass(model, size, madctl, start, turned):
    sim = awake(make(model, *size), invert=model == "st7789" or size == (80, 160))
    image = scene(*size)
    draw(sim, image if turned is None else image.transpose(turned), madctl, *start)
    assert sim.events == []
    assert sim.glass().size == size
    assert upright(image, sim)


def test_a_green_tab_st7735_is_a_132x162_memory_at_column_2_row_1_with_bgr_filters():
    sim = awake(make("st7735", 128, 160, ram=(132, 162), offset=(2, 1), bgr=True), invert=False)
    image = scene(128, 160)
    draw(sim, image, 0xC8, 2, 1)  # Adafruit INITR_GREENTAB rotation 0: MX|MY|BGR, colstart 2, rowstart 1
    assert upright(image, sim) and sim.gram.shape == (162, 132, 3)


def test_ips_glass_is_inverted_without_invon_and_bgr_swaps_on_the_way_to_the_glass():
    sim = awake(make("st7789", 240, 240), invert=False)
    draw(sim, Image.new("RGB", (240, 240), (252, 0, 0)), 0x00, 0, 0)
    assert sim.glass().getpixel((5, 5)) == (0, 255, 255)
    send(sim, 0x21)
    send(sim, 0x36, 0x08)
    assert sim.glass().getpixel((5, 5)) == (0, 0, 255)
    assert tuple(sim.gram[5, 5]) == (63, 0, 0)  # the memory is unchanged


def test_display_off_sleep_and_reset_blank_the_glass_and_display_on_restores_it():
    sim = awake(make("st7789", 240, 240, turn=180))
    image = scene(240, 240)
    draw(sim, image, 0x00, 0, 0)
    send(sim, 0x28)
    assert not np.asarray(sim.glass()).any()
    send(sim, 0x29)
    assert upright(image, sim)
    sim.set_line("reset", False)
    assert not np.asarray(sim.glass()).any()
    sim.set_line("reset", True)
    assert not np.asarray(sim.glass()).any() and sim.state.sleeping and sim.state.madctl == 0
    assert tuple(sim.gram[0, 0]) == tuple(np.asarray(image)[0, 0] >> 2)  # RESX keeps the memory


def test_idle_mode_keeps_the_top_bit_and_partial_mode_blanks_outside_ptlar():
    sim = awake(make("st7789", 240, 240, turn=180))
    image = scene(240, 240)
    draw(sim, image, 0x00, 0, 0)
    send(sim, 0x39)
    assert np.array_equal(np.asarray(sim.glass()), np.where(np.asarray(image) >= 128, 255, 0))
    send(sim, 0x38)
    send(sim, 0x30, 0, 10, 0, 19)
    send(sim, 0x12)
    glass = np.asarray(sim.glass())
    assert not glass[:10].any() and not glass[20:].any() and np.array_equal(glass[10:20], np.asarray(image)[10:20])
    send(sim, 0x13)
    assert upright(image, sim)


def test_vertical_scrolling_shows_the_memory_from_vsp():
    sim = awake(make("st7789", 240, 320, turn=180))
    image = scene(240, 320)
    draw(sim, image, 0x00, 0, 0)
    send(sim, 0x33, 0, 10, 0x01, 0x2C, 0, 10)  # TFA 10, VSA 300, BFA 10
    send(sim, 0x37, 0, 13)
    rows = np.asarray(image)
    glass = np.asarray(sim.glass())
    assert np.array_equal(glass[:10], rows[:10]) and np.array_equal(glass[310:], rows[310:])
    assert np.array_equal(glass[10], rows[13]) and np.array_equal(glass[306], rows[10 + (296 + 3) % 300])
    send(sim, 0x13)
    assert upright(image, sim)


def test_offset_option_moves_the_glass_window():
    sim = awake(make("st7789", 100, 50, offset=(7, 9), turn=180))
    image = scene(100, 50)
    draw(sim, image, 0x00, 7, 9)
    assert upright(image, sim)


# ---- TE line -------------------------------------------------------------------------------------------

def test_te_is_high_in_each_frames_v_blank_after_teon_only():
    sim = make("st7789", 240, 240)
    send(sim, 0x11)
    start = sim.clock.now()
    later(sim, 0.120)
    assert not sim.line("te")
    send(sim, 0x35, 0x00)
    period, blank = 344 * 490 / 10e6, 24 * 490 / 10e6  # FRCTRL2 0Fh, porches 0Ch+0Ch: 16.856 ms, 1.176 ms
    frames = 20
    for phase, high in [(0.5 * blank, False), (period - 0.5 * blank, True), (period - 1.5 * blank, False)]:
        t = start + frames * period + phase
        later(sim, t - sim.clock.now())
        assert sim.line("te") is high
        frames += 1
    send(sim, 0x34)
    assert not sim.line("te")


def test_te_unwired_stays_low():
    sim = awake(make("st7789", 240, 240, te=False))
    send(sim, 0x35, 0x00)
    for _ in range(50):
        later(sim, 0.001)
        assert not sim.line("te")


def test_an_injected_reset_happens_at_the_clocks_present_not_at_the_last_bus_byte():
    sim = make()  # its clock is 1 s on, the device's time still at power-on (no bus traffic yet)
    later(sim, 0.5)
    sim.inject(Fault.RESET)
    later(sim, 0.006)
    send(sim, 0x11)
    assert messages(sim) == ["SLPOUT 6.000 ms after RESX (datasheet: wait 120 ms; carried out)"]


# ---- bus statistics, faults, registry ---------------------------------------------------------------------

def test_bus_time_is_eight_clocks_per_byte_and_frames_count_finished_writes():
    sim = awake(make("st7789", 240, 240, clock_hz=32e6))
    sim.reset_stats()
    draw(sim, scene(240, 240), 0x00, 0, 0)
    stats = sim.stats
    assert stats.data_bytes == 1 + 4 + 4 + 240 * 240 * 3 and stats.command_bytes == 5
    assert stats.bus_seconds == pytest.approx(8 * stats.bytes / 32e6)
    assert stats.frames == 1


def test_power_loss_and_reset_faults():
    sim = awake(make("st7789", 240, 240))
    draw(sim, scene(240, 240), 0x00, 0, 0)
    sim.inject(Fault.RESET)
    assert sim.state.sleeping and not np.asarray(sim.glass()).any()
    sim.inject(Fault.POWER_LOSS)
    assert not np.asarray(sim.glass()).any()


def test_registry_options():
    sim = create_simulator("st7789", size="135x240", hz="40e6", strict="false")
    assert isinstance(sim, MipiDcsSim) and sim.glass().size == (135, 240) and sim.clock_hz == 40e6
    sim = create_simulator("st7735", size="128x160", offset="0,0")
    assert sim.glass().size == (128, 160)
    with pytest.raises(URLError):
        create_simulator("ili9341", size="320x240", offset="1")
    with pytest.raises(URLError, match="unknown option"):
        create_simulator("st7789", bgr="true")  # the display's option name; the glass's is panel_bgr


@pytest.mark.parametrize(("model", "table_bgr"), [("st7789", False), ("ili9341", True), ("st7735", False)])
def test_panel_bgr_sets_the_glass_filters_and_a_sim_url_reaches_it_beside_the_display_s_bgr(model, table_bgr):
    assert create_simulator(model).module.bgr is table_bgr  # the module table: ILI9341 modules are BGR
    assert create_simulator(model, panel_bgr=str(not table_bgr)).module.bgr is not table_bgr
    import pixelpen
    from pixelpen.devices.panels.mipidcs import MipiDcsDisplay

    display = pixelpen.open(f"sim:{model}?panel_bgr={str(not table_bgr).lower()}&bgr=true")
    try:
        assert isinstance(display, MipiDcsDisplay) and isinstance(display.simulator, MipiDcsSim)
        assert display.simulator.module.bgr is not table_bgr  # the simulator's wiring ...
        assert display.bgr is True  # ... and the display's MADCTL bit, each its own option
    finally:
        display.close()
    with pytest.raises(ConfigError):
        MipiDcsSim("st7796", 320, 480)


def test_glass_bigger_than_the_memory_is_refused():
    with pytest.raises(ConfigError, match="240x320"):
        MipiDcsSim("st7789", 241, 320)


# ---- fuzz ------------------------------------------------------------------------------------------------

def frames_of(items: list[tuple[int, tuple[int, ...]]]) -> bytes:
    """A stream of records ``[dc << 7 | length][bytes]``: the fuzz input format (bit flips change D/C and lengths)."""
    out = bytearray()
    for code, params in items:
        out += bytes([1, code])
        for i in range(0, len(params), 127):
            chunk = params[i:i + 127]
            out += bytes([0x80 | len(chunk), *chunk])
    return bytes(out)


def replay(model: str, stream: bytes) -> MipiDcsSim:
    sim = make(model, *((128, 160) if model == "st7735" else (240, 240)))
    i = 0
    while i < len(stream):
        head, i = stream[i], i + 1
        body, i = stream[i:i + (head & 0x7F)], i + (head & 0x7F)
        (sim.data if head & 0x80 else sim.command)(body)
        later(sim, 0.0001 * (head & 3))
    sim.glass()
    return sim


SEEDS = [
    frames_of([(c, p) for c, p, _ in ADAFRUIT_ST7789] + [(0x2C, tuple(range(200)))]),
    frames_of([*LUMA_ST7789, (0x2A, (0, 0, 0, 239)), (0x2B, (0, 0, 0, 239)), (0x2C, tuple(range(255)) * 3)]),
    frames_of([*LUMA_ILI9341, (0x33, (0, 0, 1, 0x40, 0, 0)), (0x37, (0, 5)), (0x3C, tuple(range(90)))]),
]


@pytest.mark.slow
@pytest.mark.parametrize("model", ["st7789", "ili9341", "st7735"])
def test_fuzz_campaign(model):
    campaign(f"mipidcs-{model}", lambda data: replay(model, data), SEEDS, SLOW_CASES, seed=11).check()


@pytest.mark.parametrize("model", ["st7789", "ili9341", "st7735"])
def test_fuzzed_streams_never_crash_and_are_reported(model):
    result = campaign(f"mipidcs-{model}", lambda data: replay(model, data), SEEDS, QUICK_CASES // 3, seed=10)
    result.check()
    sim = replay(model, bytes([1, 0xF3, 0x82, 1, 2]) + SEEDS[0][:37])
    assert sim.events and all(e.message for e in sim.events)

"""Hardware vertical scrolling on MIPI-DCS panels: VSCRDEF/VSCSAD bytes from the datasheets (ST7789VW §8.14,
ILI9341 8.2.33/8.2.38: TFA, VSA, BFA and VSP as big-endian 16-bit), only the new rows on the wire, a frame that
merely resembles a shift still shown right, MV-set rotations, faults, resets and rotation changes, and a property
test: after every frame of random drawing with scrolls mixed in the simulated glass equals the canvas."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pixelpen.clock import SimulatedClock
from pixelpen.devices.panels.base import PanelDisplay
from pixelpen.devices.panels.mipidcs import ILI9341Display, ST7789Display
from pixelpen.devices.panels.scrolling import (
    HardwareScroll,
    ScrollArea,
    best_shift,
    frame_rows,
    mipi_scroll_area,
    row_hashes,
)
from pixelpen.devices.panels.wiring import Wiring
from pixelpen.errors import LinkError
from pixelpen.profiles.panel import load_panel_profile
from tests.devices.panels.test_base import StubBus, windows
from tests.devices.panels.test_mipidcs import after
from tests.devices.panels.test_refresh_property import apply, expected_glass, glass, open_panel, operations

VSCRDEF, VSCSAD, RAMWR = 0x33, 0x37, 0x2C


def noise(rng: np.random.Generator, height: int, width: int) -> np.ndarray:
    """Random RGB rows (every row differs from every other, also at RGB565 depth)."""
    return rng.integers(0, 256, (height, width, 3), dtype=np.uint8)


def scrolled(display: PanelDisplay, dy: int, rng: np.random.Generator) -> np.ndarray:
    """The canvas moved up by ``dy`` rows (down for dy < 0), new random rows coming into view."""
    now = display.canvas.array
    fresh = noise(rng, abs(dy), now.shape[1])
    return np.concatenate([now[dy:], fresh]) if dy > 0 else np.concatenate([fresh, now[:dy]])


def scroll(display: PanelDisplay, dy: int, rng: np.random.Generator) -> None:
    display.canvas.blit(scrolled(display, dy, rng), 0, 0)
    display.flush()


def stub(profile: str, cls: type[ST7789Display] = ST7789Display, **kwargs: Any) -> tuple[ST7789Display, StubBus]:
    bus = StubBus()
    display = cls(Wiring(bus), profile=load_panel_profile(profile), clock=SimulatedClock(), **kwargs)
    display.open()
    return display, bus


# (profile, rotation, VSCRDEF TFA VSA BFA, VSCSAD after scrolling up 2 rows): the glass's rows in the memory at
# MADCTL 0 (MY set: RASET counts from the bottom, so the ring turns the other way, VSP = TFA + (-2 mod VSA))
AREAS = [
    ("st7789_240x240", 180, "00 00 00 f0 00 50", "00 02"),
    ("st7789_240x240", 0, "00 00 00 f0 00 50", "00 ee"),
    ("st7789_135x240", 180, "00 28 00 f0 00 28", "00 2a"),
    ("st7789_135x240", 0, "00 28 00 f0 00 28", "01 16"),
    ("st7789_240x280", 0, "00 14 01 18 00 14", "01 2a"),
    ("ili9341_240x320", 0, "00 00 01 40 00 00", "00 02"),
    ("ili9341_240x320", 180, "00 00 01 40 00 00", "01 3e"),
]


@pytest.mark.parametrize(("profile", "rotation", "vscrdef", "vscsad"), AREAS)
def test_vscrdef_and_vscsad_bytes(profile: str, rotation: int, vscrdef: str, vscsad: str) -> None:
    cls = ILI9341Display if profile.startswith("ili") else ST7789Display
    display, bus = stub(profile, cls, rotation=rotation)
    rng = np.random.default_rng(1)
    display.canvas.blit(noise(rng, *display.canvas.array.shape[:2]), 0, 0)
    display.flush()
    bus.take()
    scroll(display, 2, rng)
    log = bus.take()
    assert after(log, VSCRDEF) == [bytes.fromhex(vscrdef)]
    assert after(log, VSCSAD) == [bytes.fromhex(vscsad)]
    tfa, vsa, bfa = (int(vscrdef.replace(" ", "")[i:i + 4], 16) for i in (0, 4, 8))
    assert tfa + vsa + bfa == 320  # the ST7789/ILI9341 frame memory's rows


def test_a_scroll_sends_only_the_new_rows() -> None:
    display, bus = stub("st7789_240x240", rotation=180)
    rng = np.random.default_rng(2)
    display.canvas.blit(noise(rng, 240, 240), 0, 0)
    display.flush()
    sent = display.stats.bytes
    scroll(display, 3, rng)
    first = display.stats.bytes - sent
    assert first == (1 + 6) + (1 + 2) + 11 + 3 * 240 * 2  # VSCRDEF, VSCSAD, one window of the 3 new rows
    for dy in (5, 1, 7):
        sent = display.stats.bytes
        bus.take()
        scroll(display, dy, rng)
        assert display.stats.bytes - sent == (1 + 2) + 11 + dy * 240 * 2  # VSCSAD only: the area is kept
        assert [w[4] for w in windows(bus.log)] == [dy * 480]


def test_a_window_across_the_ring_end_is_split_and_the_glass_is_right() -> None:
    display = open_panel("st7789", "240x240", 180)
    rng = np.random.default_rng(3)
    display.canvas.blit(noise(rng, 240, 240), 0, 0)
    display.flush()
    scroll(display, 100, rng)  # the new rows 140..239 live at ring rows 240..339 -> 0..99: no wrap yet
    assert (glass(display) == expected_glass(display)).all()
    bus = display.bus
    assert bus is not None
    for dy in (90, 30, -50):  # offset 190, then 220: rows 210..239 wrap to 190..239, 0..9; then down
        counted, sent = display.stats.bytes, bus.bytes_sent
        scroll(display, dy, rng)
        assert (glass(display) == expected_glass(display)).all(), dy
        assert display.stats.bytes - counted == bus.bytes_sent - sent  # a split window is counted as sent
    assert display.simulator is not None and not display.simulator.events


def test_a_frame_that_merely_resembles_a_shift_is_still_shown_right() -> None:
    display = open_panel("st7789", "240x240", 0)
    rng = np.random.default_rng(4)
    display.canvas.blit(noise(rng, 240, 240), 0, 0)
    display.flush()
    picture = scrolled(display, 2, rng)
    picture[120, 77] ^= 0x80  # one pixel inside the shifted band differs
    before = display.stats.bytes
    display.canvas.blit(picture, 0, 0)
    display.flush()
    assert (glass(display) == expected_glass(display)).all()
    assert display.stats.bytes - before == (1 + 6) + (1 + 2) + (11 + 2 * 240 * 2) + (11 + 2)


def test_no_scroll_for_a_frame_that_is_not_a_shift() -> None:
    display, bus = stub("st7789_240x240", rotation=180)
    rng = np.random.default_rng(5)
    display.canvas.blit(noise(rng, 240, 240), 0, 0)
    display.flush()
    bus.take()
    display.canvas.blit(noise(rng, 240, 240), 0, 0)
    display.flush()
    assert not after(bus.log, VSCSAD) and not after(bus.log, VSCRDEF)


@pytest.mark.parametrize("rotation", [90, 270])
def test_mv_set_rotations_do_not_scroll_and_stay_right(rotation: int) -> None:
    display = open_panel("st7789", "240x240", rotation)
    bus = display.bus
    assert bus is not None
    rng = np.random.default_rng(6)
    display.canvas.blit(noise(rng, 240, 240), 0, 0)
    display.flush()
    with display.recording() as trace:
        for dy in (2, 2, -3):
            scroll(display, dy, rng)
            assert (glass(display) == expected_glass(display)).all()
    commands = [e.data for e in trace.events if e.op == "C"]
    assert commands and not [c for c in commands if c[:1] in (b"\x33", b"\x37")]
    assert display.stats.last.bytes > 200 * 240 * 2  # the rows really were rewritten


def test_hardware_scroll_off_sends_no_scroll_commands() -> None:
    display, bus = stub("st7789_240x240", rotation=180, hardware_scroll=False)
    rng = np.random.default_rng(7)
    display.canvas.blit(noise(rng, 240, 240), 0, 0)
    display.flush()
    scroll(display, 2, rng)
    assert not after(bus.log, VSCSAD) and not after(bus.log, VSCRDEF)


def test_hardware_scroll_is_a_url_option() -> None:
    display = open_panel("st7789", "240x240", 180, "&hardware_scroll=off")
    assert isinstance(display, ST7789Display)
    assert not display._scroll.enabled
    display.close()


@pytest.mark.parametrize("event", ["fault", "reset", "rotate"])
def test_the_scroll_is_undone_by_the_next_full_frame(event: str) -> None:
    display = open_panel("st7789", "240x240", 0)
    rng = np.random.default_rng(8)
    display.canvas.blit(noise(rng, 240, 240), 0, 0)
    display.flush()
    scroll(display, 7, rng)
    assert isinstance(display, ST7789Display) and display._scroll.offset == 7
    bus = display.bus
    assert bus is not None
    if event == "fault":
        real = bus.data

        def failing(data: bytes) -> None:
            bus.data = real  # type: ignore[method-assign]
            raise LinkError("injected")

        bus.data = failing  # type: ignore[method-assign]
        with pytest.raises(LinkError):
            scroll(display, 4, rng)  # VSCSAD's parameters are lost: the controller's offset is unknown
        display.canvas.lines([[3, 3, 9, 3]], (255, 0, 0))
        display.flush()
    elif event == "reset":
        display.reset()
    else:
        display.rotate(90)
    assert display.stats.last.full
    assert display._scroll.offset == 0
    assert (glass(display) == expected_glass(display)).all()
    scroll(display, 5, rng)
    assert (glass(display) == expected_glass(display)).all()


def test_ring_rows_match_a_brute_force_mapping() -> None:
    scroller = HardwareScroll(lambda step: None)
    scroller.area = ScrollArea(0, 10, 0)
    for offset in range(10):
        scroller.offset = offset
        for y0 in range(10):
            for y1 in range(y0 + 1, 11):
                pieces = scroller.rows(y0, y1)
                flat = [r for a, b in pieces for r in range(a, b)]
                assert flat == [(y + offset) % 10 for y in range(y0, y1)]
                assert len(pieces) <= 2


def test_scroll_area_start_and_steps() -> None:
    area = mipi_scroll_area(320, 80, 240, reversed=True)
    assert (area.top, area.rows, area.bottom) == (0, 240, 80)
    assert area.start(2) == 238
    assert [(s.command, s.params.hex()) for s in area.steps(2)] == [(0x33, "000000f00050"), (0x37, "00ee")]
    assert mipi_scroll_area(320, 20, 280, reversed=False).start(5) == 25


def test_best_shift_against_a_brute_force_search() -> None:
    rng = np.random.default_rng(9)
    for _ in range(50):
        height = int(rng.integers(4, 40))
        old = rng.integers(0, 4, (height, 3), dtype=np.uint8)  # few values: many repeated rows
        d = int(rng.integers(0, height))
        new = np.roll(old, -d, axis=0)
        new[rng.integers(0, height, int(rng.integers(0, 3)))] = 9
        got = best_shift(row_hashes(frame_rows(new)), row_hashes(frame_rows(old)))
        same = [int(np.count_nonzero((new == np.roll(old, -k, axis=0)).all(axis=1))) for k in range(height)]
        if d and 2 * (height - same[d]) <= height - same[0]:  # a hint that pays is taken as it is
            assert best_shift(row_hashes(frame_rows(new)), row_hashes(frame_rows(old)), d) == d
        if got:  # the shift found keeps as many rows as any and at least halves the changed rows
            assert same[got] >= max(same[1:]) or same[got] == max(same[k] for k in range(1, height))
            assert 2 * (height - same[got]) <= height - same[0]


def test_row_hashes_are_equal_for_equal_rows_only() -> None:
    rows = frame_rows(np.array([[[1, 2, 3], [4, 5, 6]], [[1, 2, 3], [4, 5, 6]], [[1, 2, 3], [4, 5, 7]]], np.uint8))
    h = row_hashes(rows)
    assert h[0] == h[1] != h[2]


def after_scroll(display: PanelDisplay) -> int:
    """The ring offset of a MIPI display's hardware scroll."""
    assert isinstance(display, ST7789Display | ILI9341Display) or hasattr(display, "_scroll")
    return int(display._scroll.offset)


def play(display: PanelDisplay, kind: str, arg: Any, rng: np.random.Generator, shift: Any, fresh: Any, flip: int,
         dot: Any) -> bool:
    """One step of a scroll sequence: a scroll by ``shift`` (``flip`` xor-ed into one pixel when touched), drawing
    operations, a rotation (``fresh`` pixels after it) or a bus fault at the arg-th data transfer of a 3-row
    scroll, then a dot of ``dot``; True when a scroll left the hardware scroll's offset away from 0."""
    h = display.canvas.array.shape[0]
    if kind == "scroll":
        dy, touch = arg
        dy = max(-h + 1, min(h - 1, dy))
        picture = shift(display, dy, rng)
        if touch:  # a change inside the shifted band too
            picture[int(rng.integers(0, h)), int(rng.integers(0, picture.shape[1]))] ^= flip
        display.canvas.blit(picture, 0, 0)
        display.flush()
        return bool(after_scroll(display))
    if kind == "draw":
        for op in arg:
            apply(display, op)
            display.flush()
    elif kind == "rotate":
        display.rotate(arg)
        display.canvas.blit(fresh(rng, *display.canvas.array.shape[:2]), 0, 0)
        display.flush()
    else:
        bus = display.bus
        assert bus is not None
        real, calls = bus.data, {"n": 0}

        def failing(data: bytes) -> None:
            calls["n"] += 1
            if calls["n"] == arg:
                raise LinkError("injected")
            real(data)

        bus.data = failing  # type: ignore[method-assign]
        try:
            display.canvas.blit(shift(display, 3, rng), 0, 0)
            display.flush()
        except LinkError:
            pass
        finally:
            bus.data = real  # type: ignore[method-assign]
        display.canvas.lines([[0, 0, 1, 0]], dot)
        display.flush()
    return False


SCROLL_PANELS = [("st7789", "240x240"), ("st7789", "135x240"), ("ili9341", "240x320"), ("st7735", "80x160")]


@st.composite
def scroll_sequences(draw: Any, width: int, height: int, mono: bool = False) -> list[tuple[str, Any]]:
    """Drawing operations (as the refresh property test's) with scrolls, rotations and bus faults mixed in."""
    out: list[tuple[str, Any]] = []
    for _ in range(draw(st.integers(1, 8))):
        kind = draw(st.sampled_from(["scroll", "scroll", "scroll", "draw", "rotate", "fault"]))
        if kind == "scroll":
            dy = draw(st.one_of(st.integers(-9, 9), st.integers(-height + 1, height - 1)).filter(bool))
            out.append(("scroll", (dy, draw(st.booleans()))))
        elif kind == "draw":
            out.append(("draw", draw(operations(width, height, mono))))
        elif kind == "rotate":
            out.append(("rotate", draw(st.sampled_from([0, 90, 180, 270]))))
        else:
            out.append(("fault", draw(st.integers(1, 3))))
    return out


@pytest.mark.parametrize(("model", "size"), SCROLL_PANELS)
def test_glass_equals_canvas_after_every_frame_with_scrolls(model: str, size: str) -> None:
    display = open_panel(model, size, 180)
    width, height = display.canvas.size
    rng = np.random.default_rng(10)
    scrolls = {"n": 0}
    display.canvas.blit(noise(rng, height, width), 0, 0)  # rows that differ, so that shifts are found
    display.flush()

    @settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow], database=None,
              derandomize=True)
    @given(scroll_sequences(width, height))
    def frames(ops: list[tuple[str, Any]]) -> None:
        for kind, arg in ops:
            scrolls["n"] += play(display, kind, arg, rng, scrolled, noise, 0xFF, (1, 2, 3))
            assert (glass(display) == expected_glass(display)).all(), (kind, arg)

    frames()
    assert scrolls["n"] > 0  # the hardware scroll really was used
    assert display.simulator is not None
    # injected faults truncate commands; a scroll area that is not the memory's rows would be flagged like this
    assert not [e for e in display.simulator.events if "TFA" in e.message]
    display.close()


def test_rgb666_scrolls_too_and_the_glass_is_right() -> None:
    display = open_panel("st7789", "240x240", 0, "&colour=rgb666")
    rng = np.random.default_rng(11)
    display.canvas.blit(noise(rng, 240, 240), 0, 0)
    display.flush()
    before = display.stats.bytes
    scroll(display, 4, rng)
    assert display.stats.bytes - before == (1 + 6) + (1 + 2) + 11 + 4 * 240 * 3
    for dy in (-6, 120, 7):
        scroll(display, dy, rng)
        assert (glass(display) == expected_glass(display)).all(), dy


def test_after_frames_that_are_no_shift_a_scroll_is_found_again_within_max_skip_frames() -> None:
    from pixelpen.devices.panels.scrolling import MAX_SKIP

    display, bus = stub("st7789_240x240", rotation=180)
    rng = np.random.default_rng(12)
    for _ in range(20):  # video: every frame new, checked one frame in a few
        display.canvas.blit(noise(rng, 240, 240), 0, 0)
        display.flush()
    bus.take()
    for _ in range(MAX_SKIP + 2):
        scroll(display, 2, rng)
        assert (display.stats.last.bytes < 240 * 240) == bool(after(bus.log, VSCSAD))
    assert after(bus.log, VSCSAD)
    sent = display.stats.bytes
    scroll(display, 2, rng)
    assert display.stats.bytes - sent == 3 + 11 + 2 * 480  # steady: every frame scrolls


@pytest.mark.parametrize("extra", ["", "&colour=rgb666"])
def test_a_ring_rotation_is_a_scroll_with_no_pixels(extra: str) -> None:
    display = open_panel("st7789", "240x240", 180, extra)
    rng = np.random.default_rng(13)
    picture = noise(rng, 240, 240)
    display.canvas.blit(picture, 0, 0)
    display.flush()
    before = display.stats.bytes
    display.canvas.blit(np.roll(picture, -9, axis=0), 0, 0)  # the rows leaving the top come back at the bottom
    display.flush()
    assert display.stats.bytes - before == (1 + 6) + (1 + 2)  # VSCRDEF and VSCSAD, no window
    assert (glass(display) == expected_glass(display)).all()

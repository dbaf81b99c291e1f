"""PanelDisplay's frame loop against a recording stub bus: init order, trimmed partial frames, full refresh after
faults, interruptions and rotation, pacing that coalesces, the bandwidth check, safe close."""

from __future__ import annotations

import numpy as np
import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.devices.panels.mipidcs import ST7789Display
from pixelpen.devices.panels.wiring import Wiring
from pixelpen.errors import ConfigError, InvalidArgument, LinkError
from pixelpen.profiles.panel import load_panel_profile


class StubBus:
    """A PanelBus that records ("C"|"D"|"R"|"X", bytes) and can fail the n-th data call once."""

    def __init__(self, kind: str = "spi", clock_hz: float = 62.5e6, max_transfer: int = 4096) -> None:
        self.kind = kind
        self.clock_hz = clock_hz
        self.max_transfer = max_transfer
        self.bytes_sent = 0
        self.transfers = 0
        self.log: list[tuple[str, bytes]] = []
        self.fail_data_call: int | None = None
        self.interrupt_data_call: int | None = None
        self.data_calls = 0

    def command(self, *cmd: int | bytes) -> None:
        self.log.append(("C", b"".join(bytes([c]) if isinstance(c, int) else bytes(c) for c in cmd)))

    def data(self, data: bytes) -> None:
        self.data_calls += 1
        if self.data_calls == self.fail_data_call:
            self.fail_data_call = None
            raise LinkError("stub: write failed")
        if self.data_calls == self.interrupt_data_call:
            self.interrupt_data_call = None
            raise KeyboardInterrupt
        self.log.append(("D", bytes(data)))

    def reset(self, recovery: float = 0.12) -> None:
        self.log.append(("R", b""))

    def close(self) -> None:
        self.log.append(("X", b""))

    def take(self) -> list[tuple[str, bytes]]:
        """The log so far, cleared."""
        out, self.log = self.log, []
        return out


def windows(log: list[tuple[str, bytes]]) -> list[tuple[int, int, int, int, int]]:
    """(xs, xe, ys, ye, pixel bytes) of each RAMWR window in a MIPI log (datasheet: 16-bit BE), with the columns
    and rows of the last CASET and RASET (a window repeating one leaves it out)."""
    out, kept = [], {0x2A: (0, 0), 0x2B: (0, 0)}
    for i, (kind, payload) in enumerate(log):
        if kind == "C" and payload in (b"\x2a", b"\x2b"):
            p = log[i + 1][1]
            kept[payload[0]] = (p[0] << 8 | p[1], p[2] << 8 | p[3])
        if kind == "C" and payload == b"\x2c":
            out.append((*kept[0x2A], *kept[0x2B], len(log[i + 1][1])))
    return out


def st7789(bus: StubBus, **kwargs: object) -> ST7789Display:
    clock = SimulatedClock()
    return ST7789Display(Wiring(bus), profile=load_panel_profile("st7789_240x240"), clock=clock, **kwargs)


def test_open_resets_runs_the_table_with_its_delays_then_a_full_frame_before_dispon() -> None:
    bus = StubBus()
    display = st7789(bus)
    display.open()
    log = bus.take()
    assert log[0] == ("R", b"")
    commands = [p for k, p in log if k == "C"]
    # Adafruit/datasheet order: SWRESET, SLPOUT, COLMOD, MADCTL, INVON, NORON; then the driver's settings; then
    # the window and DISPON last, so no stale RAM is ever shown.
    assert commands[:6] == [b"\x01", b"\x11", b"\x3a", b"\x36", b"\x21", b"\x13"]
    assert commands[-4:] == [b"\x2a", b"\x2b", b"\x2c", b"\x29"]
    assert windows(log) == [(0, 239, 80, 319, 240 * 240 * 2)]  # rotation 0 = MX|MY: rows +80 (Adafruit)
    # SWRESET 150 + SLPOUT 120 + COLMOD 10 + INVON 10 + NORON 10 + DISPON 10 ms, all on the simulated clock
    assert display.clock.now() == pytest.approx(0.310)
    assert display.stats.frames == 1 and display.stats.full_frames == 1


def test_a_drawn_rectangle_is_one_window_of_its_pixels_in_rgb565_big_endian() -> None:
    bus = StubBus()
    display = st7789(bus)
    display.open()
    bus.take()
    display.canvas.blit(np.full((3, 5, 3), (0x12, 0x34, 0x56), dtype=np.uint8), 10, 20)
    display.flush()
    log = bus.take()
    assert windows(log) == [(10, 14, 100, 102, 30)]
    # RGB565 of (0x12, 0x34, 0x56) by the datasheet: R5=0x02, G6=0x0D, B5=0x0A -> 0x11AA, sent MSB first
    assert log[-1] == ("D", b"\x11\xaa" * 15)
    assert display.stats.last.bytes == 11 + 30 and display.stats.last.windows == 1


def test_redrawing_the_same_pixels_sends_nothing() -> None:
    bus = StubBus()
    display = st7789(bus)
    display.open()
    display.canvas.circles([[50, 50]], [8], (255, 255, 255), fill=True)
    display.flush()
    bus.take()
    frames = display.stats.frames
    display.canvas.circles([[50, 50]], [8], (255, 255, 255), fill=True)
    display.flush()
    assert bus.take() == [] and display.stats.frames == frames


@pytest.mark.parametrize("failure", ["link", "interrupt"])
def test_a_frame_broken_midway_is_followed_by_a_full_frame(failure: str) -> None:
    bus = StubBus()
    display = st7789(bus)
    display.open()
    bus.take()
    display.canvas.lines([[0, 0, 100, 0], [0, 200, 100, 200]], (255, 0, 0))
    if failure == "link":
        bus.fail_data_call = bus.data_calls + 3  # the first window's pixels
        with pytest.raises(LinkError):
            display.flush()
    else:
        bus.interrupt_data_call = bus.data_calls + 3
        with pytest.raises(KeyboardInterrupt):
            display.flush()
    bus.take()
    display.canvas.lines([[5, 5, 6, 5]], (0, 255, 0))
    display.flush()
    assert windows(bus.take()) == [(0, 239, 80, 319, 115200)]
    assert display.stats.last.full


def test_rotation_change_resends_madctl_and_the_whole_frame() -> None:
    bus = StubBus()
    display = st7789(bus)
    display.open()
    bus.take()
    display.rotate(90)
    log = bus.take()
    madctl = [log[i + 1][1] for i, (k, p) in enumerate(log) if k == "C" and p == b"\x36"]
    assert madctl == [b"\xa0"]  # MY|MV (Adafruit setRotation(1)), profile bgr=false
    assert windows(log) == [(80, 319, 0, 239, 115200)]  # MV: columns span the 320 side, +80 (Adafruit colstart)
    with pytest.raises(InvalidArgument):
        display.rotate(45)


def test_frames_coalesce_under_fps_pacing() -> None:
    bus = StubBus()
    display = st7789(bus, fps=10)
    display.open()
    bus.take()
    for x in range(5):  # five draws before the next frame is due: nothing goes out
        display.canvas.lines([[x * 10, 5, x * 10 + 3, 5]], (255, 255, 0))
        display.flush()
    assert bus.take() == []
    assert display.refresh()
    # open ended at 0.310 s (the init delays) with a frame just sent; the next slot is 0.1 s later
    assert display.clock.now() == pytest.approx(0.410, abs=1e-9)
    sent = windows(bus.take())
    assert sum(w[4] for w in sent) == 5 * 4 * 2  # all five strokes in one frame
    assert display.stats.frames == 2


def test_an_impossible_fps_is_refused_naming_the_limit() -> None:
    bus = StubBus(clock_hz=32e6)
    display = st7789(bus, fps=120)
    with pytest.raises(ConfigError, match=r"requested 120 fps but ST7789 240x240 RGB565 over SPI at 32 MHz can do "
                                          r"at most 34.7 fps \(115,211 bytes per frame\)"):
        display.open()
    assert bus.log[-1] == ("X", b"")  # the bus was released


@pytest.mark.parametrize(("persist", "last_commands"), [(True, []), (False, [b"\x28"])])
def test_close_leaves_the_picture_or_turns_the_display_off(persist: bool, last_commands: list[bytes]) -> None:
    bus = StubBus()
    display = st7789(bus, persist=persist)
    display.open()
    bus.take()
    display.close()
    log = bus.take()
    assert log[-1] == ("X", b"")
    assert [p for k, p in log[:-1] if k == "C"] == last_commands


def test_close_sends_the_frame_pacing_held_back() -> None:
    bus = StubBus()
    display = st7789(bus, fps=1)
    display.open()
    bus.take()
    display.canvas.lines([[0, 0, 9, 0]], (255, 255, 255))
    display.flush()
    assert bus.log == []
    display.close()
    assert windows(bus.take()) == [(0, 9, 80, 80, 20)]


def test_stats_count_the_bytes_given_to_the_bus() -> None:
    bus = StubBus()
    display = st7789(bus)
    display.open()
    bus.take()
    display.canvas.lines([[0, 0, 50, 50], [100, 10, 200, 10]], (9, 9, 9))
    display.flush()
    assert display.stats.last.bytes == sum(len(p) for _, p in bus.take())
    assert display.stats.host_seconds_per_frame > 0


def test_every_option_is_documented() -> None:
    from pathlib import Path

    from pixelpen.devices.panels.ssd1306 import SSD1306Display

    text = (Path(__file__).parents[3] / "docs" / "panels.md").read_text(encoding="utf-8")
    for cls in (ST7789Display, SSD1306Display):
        for spec in cls.OPTIONS:
            assert f"| `{spec.name}` |" in text, spec.name


def test_close_releases_the_bus_even_when_display_off_fails() -> None:
    bus = StubBus()
    display = st7789(bus, persist=False)
    display.open()

    def broken(*cmd: int | bytes) -> None:
        raise LinkError("stub: unplugged")

    bus.command = broken  # type: ignore[method-assign]
    display.close()
    assert bus.log[-1] == ("X", b"") and not display.is_open


# -- sim: URLs: a turned size is a rotation, the address reaches the chip, a closed display opens again ------------
def _glass_equals_canvas(display: object) -> None:
    """The simulated glass shows the canvas as it is (RGB565 depth), pixel for pixel and of the same size."""
    from tests.devices.panels.test_refresh_property import glass, reduce_depth

    canvas = reduce_depth(np.asarray(display.canvas.to_image().convert("RGB")), display)  # type: ignore[attr-defined]
    assert glass(display).shape == canvas.shape  # type: ignore[arg-type]
    assert np.array_equal(glass(display), canvas)  # type: ignore[arg-type]


@pytest.mark.parametrize(("url", "canvas_size"), [
    ("sim:ili9341?size=320x240", (320, 240)),
    ("sim:st7789?size=240x135", (240, 135)),
    ("sim:st7735?size=160x128", (160, 128)),
    ("sim:ili9341?size=320x240&rotation=270", (320, 240)),
])
def test_a_size_turned_from_the_module_is_a_quarter_rotation_and_the_glass_is_the_canvas(
        url: str, canvas_size: tuple[int, int]) -> None:
    import pixelpen

    with pixelpen.open(url) as display:
        assert display.rotation == (270 if "rotation=270" in url else 90)
        assert display.canvas.size == canvas_size
        w, h = canvas_size
        display.canvas.array[: h // 3, : w // 4] = (255, 0, 0)  # a red block at the top left, a green one lower right
        display.canvas.array[h // 2:, w // 2:] = (0, 255, 0)
        display.canvas.mark_damaged()
        display.flush()
        _glass_equals_canvas(display)


def test_a_turned_size_with_rotation_0_or_180_is_refused() -> None:
    import pixelpen

    with pytest.raises(ConfigError, match=r"size=320x240 is the 240x320 module turned.*rotation=180"):
        pixelpen.open("sim:ili9341?size=320x240&rotation=180")


def test_the_module_size_with_a_rotation_turns_the_picture_on_the_upright_glass() -> None:
    import pixelpen

    with pixelpen.open("sim:ili9341?size=240x320&rotation=90") as display:
        assert display.canvas.size == (320, 240)
        assert display.simulator.glass().size == (240, 320)  # type: ignore[union-attr]


@pytest.mark.parametrize("address", [0x3C, 0x3D])
def test_the_displays_i2c_address_is_the_simulators(address: int) -> None:
    import pixelpen

    with pixelpen.open(f"sim:ssd1306?addr=0x{address:02x}") as display:
        sim = display.simulator
        assert sim is not None
        assert sim.i2c_write(address, b"\x00\xa5")  # the chip acknowledges the display's address
        assert not sim.i2c_write(0x3C + 0x3D - address, b"\x00\xa5")


def test_a_simulator_address_disagreeing_with_addr_is_refused() -> None:
    import pixelpen

    with pytest.raises(ConfigError, match=r"address=0x3c .*disagrees with the display's addr=0x3d"):
        pixelpen.open("sim:ssd1306?addr=0x3d&address=0x3c")


@pytest.mark.parametrize("url", ["sim:st7789", "sim:ssd1306"])
def test_a_closed_sim_display_opens_again_and_draws_on_the_same_simulator(url: str) -> None:
    import pixelpen

    display = pixelpen.open(url)
    sim = display.simulator
    display.close()
    display.open()
    assert display.simulator is sim
    h = display.canvas.height
    display.canvas.array[: h // 2] = 1 if display.canvas_mode == "1" else (255, 255, 255)
    display.canvas.mark_damaged()
    display.flush()
    display.close()
    picture = np.asarray(sim.glass().convert("L"))  # type: ignore[union-attr]
    assert picture[: h // 2].min() > 200 and picture[h // 2:].max() == 0


def test_stats_history_keeps_the_recent_frames_bounded() -> None:
    from pixelpen.devices.panels.frames import HISTORY

    bus = StubBus()
    display = st7789(bus)
    display.open()
    assert [f.full for f in display.stats.history] == [True]  # the first frame of the initialisation
    for i in range(HISTORY + 5):
        display.canvas.blit(np.full((1, 1, 3), 255 * (i % 2), np.uint8), 7, 9)
        display.flush()
    history = display.stats.history
    assert len(history) == HISTORY and history[-1] is display.stats.last
    assert all(f.bytes == 11 + 2 and f.windows == 1 and not f.full for f in history)  # one pixel, one window


def test_recording_traces_the_frames_of_the_block_and_restores_the_bus() -> None:
    bus = StubBus()
    display = st7789(bus)
    display.open()
    with display.recording() as trace:
        display.canvas.blit(np.full((1, 2, 3), 255, np.uint8), 3, 4)
        display.flush()
    assert display.bus is not None and display.bus is bus
    # CASET 3..4, RASET 4..4 (+80 rows at rotation 0 on the 240x240 ST7789: 84), RAMWR, two white RGB565 pixels
    assert [(e.op, e.data.hex()) for e in trace.events] == [
        ("C", "2a"), ("D", "00030004"), ("C", "2b"), ("D", "00540054"), ("C", "2c"), ("D", "ffffffff")]

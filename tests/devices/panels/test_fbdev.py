"""The fbdev: display on the simulated framebuffer: damage-only writes, both pages kept right, glass = canvas.

Oracles: the canvas itself for 24/32 bpp (lossless), and for RGB565 the canvas quantised by fb.h's rule (the top
5/6/5 bits, read back by repeating them), written here; bytes written counted from the rectangles drawn.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pixelpen
from pixelpen.clock import SimulatedClock
from pixelpen.devices.panels.fbdev import FramebufferDisplay
from pixelpen.display.picture import Polyline, Style
from pixelpen.errors import LinkError, URLError
from pixelpen.options import describe
from pixelpen.sim.panels.fbdev import FbdevSim


def rgb565_seen(rgb: np.ndarray) -> np.ndarray:
    """What an RGB565 screen shows for 8-bit RGB: 5/6/5 top bits, widened by repeating them."""
    r, g, b = (rgb[..., i].astype(np.uint16) for i in range(3))
    r5, g6, b5 = r >> 3, g >> 2, b >> 3
    return np.dstack([(r5 << 3) | (r5 >> 2), (g6 << 2) | (g6 >> 4), (b5 << 3) | (b5 >> 2)]).astype(np.uint8)


def marked_sim(width: int, height: int, bpp: int, **options) -> FbdevSim:
    """A simulator whose memory is all 0xA5, so bytes nobody should write (padding) are seen to stay."""
    sim = FbdevSim(width, height, bpp, clock=SimulatedClock(), **options)
    sim.map(sim.fix["smem_len"])[:] = b"\xa5" * sim.fix["smem_len"]
    return sim


def padding(sim: FbdevSim) -> np.ndarray:
    return sim.gram[:, sim.width * sim.var["bits_per_pixel"] // 8:]


def test_a_picture_drawn_by_url_shows_on_the_glass():
    with pixelpen.open("sim:fbdev?size=40x30&bpp=16&stride=128") as d:
        d.window(0, 0, 40, 30)
        d.draw(Polyline([[0, 15], [40, 15]], Style(colour="red")))
        glass = np.asarray(d.simulator.glass())
        lit = np.flatnonzero((glass[..., 0] > 128).any(axis=1)).tolist()
        assert lit and all(13 <= y <= 16 for y in lit) and not glass[..., 1:].any()
        assert np.array_equal(glass, rgb565_seen(d.canvas.array))
        assert d.framebuffer.line_length == 128 and d.simulator.fix["line_length"] == 128


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    bpp=st.sampled_from([16, 24, 32]), bgr=st.booleans(), double=st.booleans(),
    pad=st.integers(0, 3).map(lambda k: 64 * k),
    frames=st.lists(st.lists(st.tuples(st.integers(0, 30), st.integers(0, 20), st.integers(1, 12),
                                       st.integers(1, 12), st.integers(0, 255 ** 3)), max_size=4),
                    min_size=1, max_size=5),
)
def test_glass_equals_the_canvas_after_every_frame(bpp, bgr, double, pad, frames):
    width, height = 31, 21
    sim = marked_sim(width, height, bpp, bgr=bgr, stride=-(-width * bpp // 8 // 64) * 64 + pad)
    display = FramebufferDisplay(sim.open, simulator=sim, double_buffer=double).open()
    seen = rgb565_seen if bpp == 16 else (lambda a: a)
    for rects in frames:
        for x, y, w, h, c in rects:
            block = np.empty((min(h, height - y), min(w, width - x), 3), dtype=np.uint8)
            block[...] = (c >> 16 & 255, c >> 8 & 255, c & 255)
            display.canvas.blit(block, x, y)
        display.flush()
        assert np.array_equal(np.asarray(sim.glass()), seen(display.canvas.array))
        assert (padding(sim) == 0xA5).all()
    assert display.framebuffer.double_buffered == double
    display.close()
    assert np.array_equal(np.asarray(sim.glass()), seen(display.canvas.array))  # close leaves the last frame


def test_only_damage_is_written_and_the_hidden_page_catches_up():
    sim = marked_sim(64, 48, 16)
    display = FramebufferDisplay(sim.open, simulator=sim).open()
    assert display.framebuffer.double_buffered and display.stats.bytes == 64 * 48 * 2  # the first frame: full
    assert (sim.stats.pans, sim.var["yoffset"]) == (2, 48)  # the set-up pan to page 0, then the first frame's
    display.canvas.blit(np.full((4, 5, 3), 200, dtype=np.uint8), 0, 0)
    display.flush()  # the hidden page lacks the first frame too: written whole again
    assert display.stats.bytes == 2 * 64 * 48 * 2 and sim.var["yoffset"] == 0
    display.canvas.blit(np.full((3, 6, 3), 90, dtype=np.uint8), 58, 45)
    display.flush()  # this frame's block and the last frame's, far apart: two rectangles
    assert display.stats.bytes == 2 * 64 * 48 * 2 + (4 * 5 + 3 * 6) * 2 and sim.var["yoffset"] == 48
    display.flush()  # nothing changed: nothing written, no pan
    assert display.stats.frames == 3 and display.stats.full_frames == 1 and sim.stats.pans == 4
    assert display.stats.last.windows == 2 and display.stats.last.bytes == (4 * 5 + 3 * 6) * 2
    assert np.array_equal(np.asarray(sim.glass()), rgb565_seen(display.canvas.array))


def test_single_buffering_writes_just_the_damage():
    sim = marked_sim(64, 48, 32, virtual_height=48)
    display = FramebufferDisplay(sim.open, simulator=sim).open()
    assert not display.framebuffer.double_buffered and "yres_virtual = 48" in display.framebuffer.buffering
    start = display.stats.bytes
    display.canvas.blit(np.full((4, 5, 3), 7, dtype=np.uint8), 10, 20)
    display.flush()
    assert display.stats.bytes - start == 4 * 5 * 4 and sim.stats.pans == 0
    assert np.array_equal(np.asarray(sim.glass()), display.canvas.array)


def test_a_failed_pan_is_a_link_error_and_the_next_frame_is_full():
    sim = marked_sim(16, 8, 32)
    display = FramebufferDisplay(sim.open, simulator=sim).open()
    display.canvas.blit(np.full((2, 2, 3), 255, dtype=np.uint8), 3, 3)
    display.flush()  # shown by a pan to yoffset 0
    display.canvas.blit(np.full((2, 2, 3), 99, dtype=np.uint8), 9, 1)
    sim.fix["ypanstep"] = 3  # the driver now refuses yoffset 8: EINVAL
    with pytest.raises(LinkError, match="FBIOPAN_DISPLAY to yoffset 8 failed"):
        display.flush()
    sim.fix["ypanstep"] = 1
    before = display.stats.bytes
    display.flush()  # the damage was kept, and the frame is sent whole
    assert display.stats.bytes - before == 16 * 8 * 4
    assert np.array_equal(np.asarray(sim.glass()), display.canvas.array)


def test_vsync_is_waited_for_when_the_driver_has_it():
    clock = SimulatedClock()
    with pixelpen.open("sim:fbdev?size=16x8&bpp=32", clock=clock) as d:
        d.canvas.blit(np.full((2, 2, 3), 255, dtype=np.uint8), 0, 0)
        d.flush()
        assert d.simulator.stats.vsync_waits == 2 and clock.now() == pytest.approx(2 / 60)
        assert d.stats.bus_seconds == pytest.approx(2 / 60)  # the waits, in simulated time
    with pixelpen.open("sim:fbdev?size=16x8&bpp=32&vsync=false&double=false") as d:
        assert not d.simulator.vsync and not d.framebuffer.double_buffered and d.simulator.stats.vsync_waits == 0


def test_persist_false_clears_the_screen_and_a_display_reopens():
    sim = marked_sim(16, 8, 24)
    display = FramebufferDisplay(sim.open, simulator=sim, persist=False, background="white").open()
    assert np.asarray(sim.glass()).min() == 255
    display.close()
    assert not np.asarray(sim.glass()).any() and display.framebuffer.closed
    display.open()
    assert np.asarray(sim.glass()).min() == 255 and not display.framebuffer.closed


def test_options_and_errors():
    assert [name for name, _ in describe(FramebufferDisplay.OPTIONS)] == ["double", "vsync", "persist", "background"]
    with pytest.raises(URLError, match=r"unknown option\(s\) rotation"):
        pixelpen.open("fbdev:/dev/fb0?rotation=90")
    with pytest.raises(LinkError, match=r"no-such-fb does not exist: load a framebuffer driver"):
        pixelpen.open("fbdev:/tmp/no-such-fb")
    with pytest.raises(URLError, match=r"sim:fbdev: .*stride 10 is shorter"):
        pixelpen.open("sim:fbdev?size=16x8&stride=10")

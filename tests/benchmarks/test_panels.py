"""Smoke test of benchmarks/panels.py: every workload for a few frames, the bytes against panels.md; never timed."""

import pytest

from benchmarks.panels import PANELS, WORKLOADS, format_table, ideal_bytes, main, run_workload, simulated_full_frames
from pixelpen.sim.base import simulator_models

pytestmark = pytest.mark.filterwarnings("ignore:Image.Image.getdata is deprecated:DeprecationWarning")  # luma.oled's


@pytest.mark.parametrize("workload", list(WORKLOADS))
def test_every_workload_runs_on_both_libraries(workload):
    rows = [run_workload(PANELS[name], workload, frames=3) for name in ("ssd1306", "st7789")]
    # panels.md 9: luma sends 6 + 1024 bytes a SSD1306 frame and 3 + 172,808 a ST7789 frame (RGB666, always full)
    assert [r.luma_bytes for r in rows] == [1030, 172_811]
    for r in rows:
        assert 0 < r.pixelpen_bytes <= r.luma_bytes
        # a TFT scroll whose incoming rows are blank is the controller's scroll alone: VSCRDEF (7 bytes, once) and
        # VSCSAD (3) a frame, no window
        assert r.windows >= 1 or (workload == "scroll" and r.pixelpen_bytes * 3 == 7 + 3 * 3)
    assert len(format_table(rows)) == 2 + len(rows)


def test_full_video_frames_are_a_whole_rgb565_window():
    row = run_workload(PANELS["st7789"], "video", frames=2)
    # panels.md 4: a full ST7789 240x240 RGB565 frame is 115,211 bytes, 67.8 fps at 62.5 MHz
    assert row.pixelpen_bytes == 115_211 and row.limit_fps == pytest.approx(67.8, abs=0.05)


def test_the_ideal_counts_changed_native_pixels_and_a_window_per_region():
    import numpy as np

    panel = PANELS["st7789"]
    before = np.zeros((240, 240, 3), np.uint8)
    after = before.copy()
    after[10:30, 10:30] = 255  # one 20x20 region: 800 bytes of RGB565 and 11 window bytes (panels.md 4: 811)
    after[100, 100] = (4, 2, 4)  # below RGB565's resolution: no change on the wire
    assert ideal_bytes(before, after, panel) == 811
    mono = PANELS["ssd1306"]
    dots = np.zeros((64, 128), np.uint8)
    lit = dots.copy()
    lit[0, 0] = lit[7, 0] = lit[8, 5] = 1  # two page bytes change (column 0 page 0, column 5 page 1): 2 regions
    assert ideal_bytes(dots, lit, mono) == 2 + 2 * 6


@pytest.mark.skipif("st7789" not in simulator_models(), reason="the ST7789 simulator is not registered")
def test_the_whole_benchmark_prints_its_table(capsys):
    assert main(["--frames", "2", "--panels", "ssd1306", "--workloads", "cursor"]) == 0
    out = capsys.readouterr().out
    assert "ssd1306  cursor" in out and "full frames, sim:st7789" in out and "% (goal >= 95 % on host + bus: " in out
    assert "bus time alone " in out and "host + bus time " in out


@pytest.mark.skipif("st7789" not in simulator_models(), reason="the ST7789 simulator is not registered")
def test_the_full_frame_goal_counts_the_host_time_as_well_as_the_bus_time():
    full = simulated_full_frames(3)
    # panels.md 4: 115,211 bytes a frame at 62.5 MHz: 67.8 fps, all the simulated clock holds; host time adds to it
    assert full.limit_fps == pytest.approx(67.8, abs=0.05) and full.bus_fps == pytest.approx(67.8, abs=0.05)
    assert 0 < full.host_bus_fps < full.bus_fps


def test_the_cursor_and_clock_workloads_are_the_demo_animations():
    import numpy as np

    from pixelpen.animation import START_SECONDS

    start, steps = WORKLOADS["cursor"](PANELS["st7789"], 2)
    assert (start[5:25, 5:25] == 255).all()  # the 20x20 white cursor at (5, 5), then (3, 2) a frame
    (x0, y0, restored), (x1, y1, square) = steps[0]
    assert (x0, y0, x1, y1) == (5, 5, 8, 7) and square.shape == (20, 20, 3) and (square == 255).all()
    np.testing.assert_array_equal(restored, WORKLOADS["video"](PANELS["st7789"], 0)[0][5:25, 5:25])
    start, steps = WORKLOADS["clock"](PANELS["ssd1306"], 3)
    assert START_SECONDS == 12 * 3600 + 34 * 60 + 50 and len(steps) == 3
    assert all(len(patches) == 1 and patches[0][:2] == ((128 - 50) // 2, (64 - 13) // 2) for patches in steps)

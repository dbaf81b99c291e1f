"""Tests of the panel demo animation: the cursor's bounce, the clock's digits and the frames sent."""

import numpy as np
import pytest

from pixelpen.animation import ClockFace, Cursor, PanelAnimation
from pixelpen.errors import InvalidArgument
from tests.commands.test_sim import RecordingPanel


def paste(frame, patches):
    for x, y, pixels in patches:
        frame[y:y + pixels.shape[0], x:x + pixels.shape[1]] = pixels


def test_the_cursor_steps_back_from_an_edge_it_would_cross():
    # a 30x26 frame and a 20x20 cursor: x in 0..10, y in 0..6; from (5, 5) at (3, 2) a frame (worked by hand)
    cursor = Cursor(np.zeros((26, 30), np.uint8), 20, 1)
    seen = [(cursor.x, cursor.y)]
    for _ in range(6):
        cursor.move()
        seen.append((cursor.x, cursor.y))
    # x: 5 8 (11) 5 2 (-1) 5 8 (11) 5; y: 5 (7) 3 1 (-1) 3 5 (7) 3 1
    assert seen == [(5, 5), (8, 3), (5, 1), (2, 3), (5, 5), (8, 3), (5, 1)]


def test_each_frame_is_the_background_with_one_square_on_it():
    rng = np.random.default_rng(7)
    background = rng.integers(0, 255, (40, 52, 3), dtype=np.uint8)
    cursor = Cursor(background, 6, (1, 2, 3), velocity=(5, 3))
    frame = background.copy()
    paste(frame, [cursor.drawn()])
    for _ in range(100):  # bounces off every edge
        old = (cursor.x, cursor.y)
        patches = cursor.move()
        assert len(patches) == 2 and patches[0][:2] == old
        paste(frame, patches)
        expected = background.copy()
        expected[cursor.y:cursor.y + 6, cursor.x:cursor.x + 6] = (1, 2, 3)
        np.testing.assert_array_equal(frame, expected)
        assert 0 <= cursor.x <= 52 - 6 and 0 <= cursor.y <= 40 - 6


def test_a_cursor_larger_than_the_frame_is_refused():
    with pytest.raises(InvalidArgument, match="cursor side 30 does not fit a 40x20 frame"):
        Cursor(np.zeros((20, 40), np.uint8), 30, 1)


def test_the_clock_changes_its_last_digit_each_second_and_carries():
    face = ClockFace(np.zeros((64, 128), np.uint8), 10, 1, 0, place="centre", seconds=12 * 3600 + 59 * 60 + 58)
    ticks = [face.tick() for _ in range(3)]  # 12:59:58, 12:59:59, 13:00:00
    (x, y, first), (_, _, second), (_, _, third) = ticks
    assert (x, y) == ((128 - 50) // 2, (64 - 13) // 2) and first.shape == (13, 50)
    assert set(np.unique(first)) == {0, 1}  # ink on paper, nothing between
    columns = np.nonzero((first != second).any(axis=0))[0]
    # eight characters in about 40 columns: 8 -> 9 changes only the last one, 12:59:59 -> 13:00:00 the hours too
    assert columns.min() > 40 * 7 // 8 - 2
    assert np.nonzero((second != third).any(axis=0))[0].min() < 40 // 4


def test_the_clock_sits_bottom_right_in_the_frames_pixels():
    face = ClockFace(np.zeros((240, 320, 3), np.uint8), 15, (255, 160, 0), (0, 0, 32))
    x, y, patch = face.tick()
    assert (x, y) == (320 - 75, 240 - 20) and patch.shape == (20, 75, 3) and patch.dtype == np.uint8
    assert {tuple(c) for c in patch.reshape(-1, 3)} == {(255, 160, 0), (0, 0, 32)}


@pytest.mark.parametrize("mode, ink", [("RGB", (255, 160, 0)), ("1", 1)])
def test_the_animation_sends_a_frame_a_step_over_what_was_shown(mode, ink):
    display = RecordingPanel(120, 72, mode)
    rng = np.random.default_rng(3)
    shown = rng.integers(0, 2, display.canvas.array.shape, dtype=np.uint8) * (1 if mode == "1" else 100)
    display.canvas.blit(shown, 0, 0)
    animation = PanelAnimation(display)
    side, (cw, ch) = 72 // 12, animation.clock.size  # a twelfth of the short side
    assert side == 6 and (cw, ch) == (50, 13)  # the clock: 10 px digits at least
    for k in range(20):
        animation.step()
        assert len(display.pictures) == k + 1 and animation.frames == k + 1
        picture = display.pictures[-1]
        x, y = 5 + 3 * k, 5 + 2 * k  # a fortieth of 120 is 3, a sixtieth of 72 rounds below 2: (3, 2)
        assert (picture[y:y + side, x:x + side] == np.asarray(ink, np.uint8)).all()
        outside = picture.copy()
        outside[y:y + side, x:x + side] = shown[y:y + side, x:x + side]
        outside[72 - ch:, 120 - cw:] = shown[72 - ch:, 120 - cw:]
        np.testing.assert_array_equal(outside, shown)

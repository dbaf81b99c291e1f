"""The input part of ``pixelpen demo`` (``commands.core.input_demo``; here until tests/commands/test_core.py has it)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from PIL import Image as PILImage

from pixelpen.commands.core import SIGNATURE_TOLERANCE_MM, input_demo
from pixelpen.drivers.recordings.hidrecorder import read_hid_recording
from pixelpen.scene import reference_scene


def test_input_demo_smooths_a_replayed_signature_and_picks_over_the_scene(tmp_path: Path) -> None:
    result = input_demo(tmp_path)
    # the signature script writes three words and a flourish, each a pen-down stroke (sim/hid/motion.py)
    assert result.strokes == 4
    assert 0 < result.max_error_mm <= SIGNATURE_TOLERANCE_MM
    assert result.control_points < result.stroke_points  # smoothing, not interpolation
    (tablet,) = read_hid_recording(tmp_path / result.signature_recording)
    assert len(tablet.reports) == result.signature_reports and tablet.vendor_id == 0x1209
    glass = np.asarray(PILImage.open(tmp_path / result.signature_glass).convert("RGB"))
    assert ((glass[..., 1] > 150) & (glass[..., 2] > 150) & (glass[..., 0] < 100)).sum() > 300  # cyan ink
    # the echo moved in small frames: far less than a full 240 x 240 RGB565 frame each
    assert result.echo_frames > 50 and result.echo_bytes_per_frame < 0.01 * 240 * 240 * 2
    paper = np.asarray(PILImage.open(tmp_path / result.signature_paper).convert("L"))
    assert (paper < 128).mean() > 0.001
    items = {i.name for i in reference_scene().items if hasattr(i, "name")} | {
        f"{type(i).__name__.lower()} {k}" for k, i in enumerate(reference_scene().items)}
    assert result.picked and set(result.picked) <= items and set(result.hovered) <= items
    assert set(result.picked) <= set(result.hovered)
    assert json.loads((tmp_path / "input.json").read_text())["strokes"] == 4

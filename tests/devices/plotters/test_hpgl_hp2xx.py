"""HP-GL from pixelpen renders in Debian's hp2xx (an independent reader) as on the simulator's paper."""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest

import pixelpen
from pixelpen.clock import SimulatedClock
from pixelpen.devices.plotters import hpgl_encode as enc
from pixelpen.drivers.stream import Link
from pixelpen.sim.base import create_simulator
from pixelpen.sim.transports.port import open_sim_port
from pixelpen.vector.displaylist import DisplayList

HP2XX = shutil.which("hp2xx")
pytestmark = pytest.mark.skipif(HP2XX is None, reason="hp2xx is not on PATH (Debian: apt-get install hp2xx)")
UNIT = 0.02488
_INSTRUCTION = re.compile(r"(SP|PU|PD|PA)([-0-9.,]*);")


class TapLink(Link):
    """A Link onto a SimPort that keeps every byte the host sent."""

    def __init__(self, port) -> None:
        super().__init__("tap", timeout=8.0, clock=port.clock)
        self.port = port
        self.sent = bytearray()

    def _read_raw(self, wait):
        return self.port.read(4096, wait)

    def _write_raw(self, data, wait):
        n = self.port.write(data, wait)
        self.sent += data[:n]
        return n

    def _raw_in_waiting(self):
        return self.port.in_waiting

    def _close_raw(self):
        self.port.close(close_device=False)


def _drawing() -> DisplayList:
    """Polylines (no dots: hp2xx drops zero-length vectors) with two pens, one long enough to be split."""
    theta = np.linspace(0, 2 * np.pi, 90)
    circle = np.column_stack([5000 + 1200 * np.cos(theta), 4000 + 1200 * np.sin(theta)]).round()
    zigzag = np.column_stack([np.arange(300, 3300, 150), np.where(np.arange(20) % 2, 900, 400)])
    box = np.array([[600, 5000], [2600, 5000], [2600, 6500], [600, 6500], [600, 5000]])
    return DisplayList.from_polylines([box, circle, zigzag], pens=[1, 2, 1], unit_mm=UNIT)


def _hp2xx_segments(hpgl: bytes, tmp_path) -> tuple[np.ndarray, np.ndarray]:
    """hp2xx -m hpgl -t re-emits absolute PU/PD (true size, shifted to a 0,0 bounding box): read its vectors."""
    src = tmp_path / "in.hpgl"
    src.write_bytes(hpgl)
    out = subprocess.run(
        [HP2XX, "-q", "-t", "-m", "hpgl", "-f", "-", str(src)], capture_output=True, timeout=30, check=False
    )
    assert out.returncode == 0, out.stderr.decode(errors="replace")
    segments, pens = [], []
    pen, pos = 0, None
    for mnemonic, params in _INSTRUCTION.findall(out.stdout.decode("ascii")):
        values = [float(v) for v in params.split(",") if v]
        if mnemonic == "SP":
            pen = int(values[0]) if values else 0
        for x, y in zip(values[0::2], values[1::2], strict=False):
            if mnemonic == "PD" and pos is not None:
                segments.append((*pos, x, y))
                pens.append(pen)
            if mnemonic in ("PU", "PD"):
                pos = (x, y)
    return np.array(segments), np.array(pens)


def _at_origin(segments: np.ndarray) -> np.ndarray:
    lo = segments.reshape(-1, 2).min(axis=0)
    return segments - np.tile(lo, 2)


def _length(segments: np.ndarray) -> float:
    return float(np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1]).sum())


def _plot_on_simulator(dl: DisplayList) -> tuple[bytes, np.ndarray, np.ndarray]:
    clock = SimulatedClock()
    device = create_simulator("hp7475a", clock=clock)
    tap = TapLink(open_sim_port("hp7475a", {}, clock=clock, device=device))
    with pixelpen.open("sim:hp7475a?sync_strokes=1", link_factory=lambda: tap) as display:
        display.plot(dl)
    seg, pens, _ = device.segments()
    return bytes(tap.sent), seg, pens


def test_the_wire_bytes_render_the_same_in_hp2xx(tmp_path):
    wire, paper, paper_pens = _plot_on_simulator(_drawing())
    assert b"PD" in wire and wire.count(b"\x1b.") > 3  # device control and output requests are in there too
    theirs, their_pens = _hp2xx_segments(wire, tmp_path)
    assert theirs.shape == paper.shape
    assert np.allclose(_at_origin(theirs), _at_origin(paper), atol=1e-3)
    assert np.array_equal(their_pens, paper_pens)
    assert _length(theirs) == pytest.approx(_length(paper), rel=1e-9)


def test_an_hpgl_file_from_the_encoder_renders_like_the_display_list(tmp_path):
    dl = _drawing()
    theirs, their_pens = _hp2xx_segments(enc.program(dl, max_length=40), tmp_path)
    assert np.allclose(_at_origin(theirs), _at_origin(dl.segments()), atol=1e-3)
    assert np.array_equal(their_pens, np.repeat(dl.pens, np.diff(dl.offsets) - 1))

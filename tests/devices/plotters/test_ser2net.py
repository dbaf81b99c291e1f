"""A real ser2net bridging RFC 2217 on loopback to the simulated 7475A behind a pty: it plots as on a local port."""

from __future__ import annotations

import shutil
import socket
import subprocess
import time

import numpy as np
import pytest

import pixelpen
from pixelpen.clock import SimulatedClock
from pixelpen.sim.base import create_simulator
from pixelpen.sim.transports.pty import PtyBridge
from pixelpen.vector.displaylist import DisplayList

SER2NET = shutil.which("ser2net")
pytestmark = pytest.mark.skipif(SER2NET is None, reason="ser2net is not on PATH (Debian: apt-get install ser2net)")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_listening(port: int, proc: subprocess.Popen, seconds: float = 5.0) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
            return True
        except OSError:
            time.sleep(0.05)
    return False


@pytest.fixture
def ser2net_plotter(tmp_path):
    """(rfc2217 port, simulated plotter): ser2net on 127.0.0.1 in front of a PtyBridge; always stopped after."""
    clock = SimulatedClock()
    device = create_simulator("hp7475a", clock=clock)
    bridge = PtyBridge(device, clock=clock)
    port = _free_port()
    config = tmp_path / "ser2net.yaml"
    config.write_text(
        "%YAML 1.1\n---\n"
        "connection: &plotter\n"
        f"  accepter: telnet(rfc2217),tcp,127.0.0.1,{port}\n"
        f"  connector: serialdev,{bridge.path},9600n81,local\n"
    )
    try:
        proc = subprocess.Popen(
            [SER2NET, "-n", "-u", "-c", str(config), "-P", str(tmp_path / "ser2net.pid")],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        )
    except OSError as exc:
        bridge.close()
        pytest.skip(f"ser2net cannot be run here: {exc}")
    try:
        if not _wait_listening(port, proc):
            proc.kill()
            output = proc.communicate(timeout=5)[0].decode(errors="replace").strip()
            pytest.skip(f"ser2net did not start listening on 127.0.0.1:{port}: {output or 'no output'}")
        yield port, device
    finally:
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout=5)
        if proc.stdout is not None:
            proc.stdout.close()
        bridge.close()


def test_plotting_through_ser2net_rfc2217(ser2net_plotter):
    port, device = ser2net_plotter
    sq = np.array([[1000, 1000], [3000, 1000], [3000, 3000], [1000, 3000], [1000, 1000]], float)
    tri = np.array([[4000, 1000], [6000, 1000], [5000, 2500], [4000, 1000]], float)
    dl = DisplayList.from_polylines([sq, tri], pens=[1, 2], unit_mm=0.02488)
    # a pty has no modem lines, so ser2net does not acknowledge SET_CONTROL: pyserial's ign_set_control
    url = f"hp7475a:[rfc2217://127.0.0.1:{port}?ign_set_control&timeout=3]"
    with pixelpen.open(url) as display:
        display.plot(dl)
        assert display.confirmed == 2 and display.model_reply == "7475A"
    seg, pens, _ = device.segments()
    assert np.array_equal(seg[:, :2], np.vstack([sq[:-1], tri[:-1]]))
    assert np.array_equal(seg[:, 2:], np.vstack([sq[1:], tri[1:]]))
    assert list(pens) == [1] * 4 + [2] * 3
    assert device.error_log == [] and device.selected_pen == 0  # pen back in the carousel on close

"""PtyBridge: a program that opens a pty path by name talks to the simulated device."""

from __future__ import annotations

import os

import pytest
import serial

from pixelpen.clock import REAL_CLOCK, SimulatedClock
from pixelpen.sim.transports.port import Faults
from pixelpen.sim.transports.pty import PtyBridge
from tests.sim.fakes import EchoDevice

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX ptys")


def read_exactly(port: serial.Serial, n: int) -> bytes:
    got = bytearray()
    while len(got) < n:
        chunk = port.read(n - len(got))
        if not chunk:
            break
        got += chunk
    return bytes(got)


def wait_for(condition, seconds: float = 10.0) -> None:
    """Poll ``condition`` (the bridge thread acts on its own time) until it holds."""
    import time

    deadline = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < deadline, "the bridge never got there"
        time.sleep(0.005)


def test_pyserial_opens_the_path_and_talks_to_the_device():
    device = EchoDevice(REAL_CLOCK)
    with PtyBridge(device, baud=115200) as bridge:
        assert bridge.path.startswith("/dev/")
        with serial.Serial(bridge.path, timeout=2) as port:
            port.write(b"IN;\r")
            assert read_exactly(port, 3) == b"OK\r"
        assert device.lines == [b"IN;"]
    assert not bridge.running and device.closed


def test_fast_clock_paces_960_bytes_in_one_simulated_second():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=4096, drain_rate=1e6)
    with PtyBridge(device, baud=9600) as bridge, serial.Serial(bridge.path, timeout=5) as port:
        port.write(b"A" * 959 + b"\r")
        assert read_exactly(port, 3) == b"OK\r"
        stats = bridge.port.stats()
    assert stats.bytes_sent == 960
    assert stats.tx_busy == pytest.approx(1.0)
    assert clock.now() >= 1.0


def test_handshake_is_applied_by_the_bridge():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=16, drain_rate=500, ready_free=4)
    payload = bytes(range(0x20, 0x7F)) * 3 + b"\r"
    with PtyBridge(device, flow="rtscts", baud=9600) as bridge, serial.Serial(bridge.path, timeout=10) as port:
        port.write(payload)
        assert read_exactly(port, 3) == b"OK\r"
    assert bytes(device.received) == payload
    assert device.overflowed == 0 and device.arrived_while_busy == 0


def test_drop_hangs_up_the_pty():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=100)
    with PtyBridge(device, faults=Faults(drop_after=4)) as bridge, serial.Serial(bridge.path, timeout=5) as port:
        port.write(b"0123456789")
        with pytest.raises(serial.SerialException):
            for _ in range(50):
                port.read(1)
        assert bridge.error is not None
    assert bytes(device.received) == b"0123"


def test_close_is_clean_and_idempotent():
    bridge = PtyBridge(EchoDevice(SimulatedClock()))
    path = bridge.path
    bridge.close()
    bridge.close()
    assert not bridge.running
    with pytest.raises(OSError):
        os.open(path, os.O_RDWR | os.O_NOCTTY)


class FailingDevice(EchoDevice):
    """A simulator with a bug: it raises on the first byte."""

    def receive(self, data: bytes) -> None:
        raise ValueError("simulator bug")


def test_a_failing_simulator_hangs_up_instead_of_leaving_the_program_waiting():
    with PtyBridge(FailingDevice(SimulatedClock())) as bridge, serial.Serial(bridge.path, timeout=5) as port:
        port.write(b"x")
        with pytest.raises(serial.SerialException):
            for _ in range(50):
                port.read(1)
        assert isinstance(bridge.error, ValueError)


def test_grbl_greets_each_program_that_opens_the_port_and_forgets_its_position():
    # an Arduino resets when the port opens (DTR): the banner comes then, not at power-up into the void
    from pixelpen.sim.plotters.grbl.controller import WELCOME, GrblSimulator

    device = GrblSimulator(SimulatedClock())
    with PtyBridge(device) as bridge:
        with serial.Serial(bridge.path, timeout=5) as port:
            assert read_exactly(port, len(WELCOME)) == WELCOME
            port.write(b"G0 X5 Y5\n")
            assert port.read_until(b"ok\r\n").endswith(b"ok\r\n")
        wait_for(lambda: not bridge.program_connected)
        with serial.Serial(bridge.path, timeout=5) as port:
            assert read_exactly(port, len(WELCOME)) == WELCOME  # once, not a stale one first
            port.write(b"?")
            assert b"MPos:0.000,0.000" in port.read_until(b">")
        assert bridge.opens == 2


def test_a_usb_device_is_not_reset_by_opening_and_not_paced():
    from pixelpen.sim.plotters.ebb.board import EbbSimulator

    device = EbbSimulator(SimulatedClock())
    with PtyBridge(device) as bridge:
        assert bridge.port.baud == 12_000_000
        with serial.Serial(bridge.path, timeout=5) as port:
            port.write(b"QS\r")
            assert read_exactly(port, 9) == b"0,0\n\rOK\r\n"  # nothing said on open before it
            port.timeout = 0.2
            assert port.read(1) == b""


def test_out_is_saved_each_time_the_program_closes_the_port(tmp_path):
    from pixelpen.sim.plotters.grbl.controller import GrblSimulator

    out = tmp_path / "paper.png"
    device = GrblSimulator(SimulatedClock())
    with PtyBridge(device, out=str(out)) as bridge:
        with serial.Serial(bridge.path, timeout=5) as port:
            port.write(b"M3 S900\nG1 X20 Y20 F6000\nM5\nG4 P0\n")
            for _ in range(4):
                assert port.read_until(b"ok\r\n").endswith(b"ok\r\n")
        wait_for(out.exists)

"""SerialLink: opening by URL, error mapping, software XON/XOFF, simulated clocks."""

from __future__ import annotations

import os

import pytest
from serial.tools import list_ports_common

from pixelpen.clock import REAL_CLOCK, SimulatedClock
from pixelpen.drivers import serial as serial_link
from pixelpen.drivers.serial import SerialLink
from pixelpen.errors import Disconnected, LinkError, LinkTimeout, URLError
from pixelpen.sim.transports.port import Faults
from pixelpen.sim.transports.pty import PtyBridge
from tests.sim.fakes import XOFF, XON, EchoDevice


def test_open_failure_names_the_port_and_the_known_ports(monkeypatch):
    fake = list_ports_common.ListPortInfo("/dev/ttyFAKE7", skip_link_detection=True)
    monkeypatch.setattr(serial_link.list_ports, "comports", lambda: [fake])
    with pytest.raises(LinkError) as info:
        SerialLink("/dev/ttyNOPE0")
    text = str(info.value)
    assert "/dev/ttyNOPE0" in text and "/dev/ttyFAKE7" in text


def test_unknown_url_scheme_is_a_link_error():
    with pytest.raises(LinkError, match="nosuch://x"):
        SerialLink("nosuch://x")


def test_bad_flow_is_refused():
    with pytest.raises(LinkError, match="flow"):
        SerialLink("loop://", flow="dtrdsr")


def test_sim_url_errors_stay_url_errors():
    with pytest.raises(URLError):
        SerialLink("sim://echo?baud=nine", device=EchoDevice(SimulatedClock()))


def test_software_xoff_holds_writes_until_xon():
    link = SerialLink("loop://", flow="xonxoff", timeout=0.05)
    assert link.soft_xonxoff
    link.port.write(bytes([XOFF]))  # the "device" says stop
    with pytest.raises(LinkTimeout, match="XOFF"):
        link.write(b"abc", timeout=0.05)
    assert link.held_off
    link.port.write(bytes([XON]) + b"ok")
    link.write(b"abc", timeout=1.0)
    assert not link.held_off
    got = bytearray()
    while len(got) < 5:
        chunk = link.read(5)
        assert chunk
        got += chunk
    assert bytes(got) == b"okabc"  # flow bytes never reach the reader
    link.close()


def test_flow_bytes_are_data_without_xonxoff():
    link = SerialLink("loop://", timeout=0.05)
    assert not link.soft_xonxoff
    link.port.write(bytes([XOFF, XON]))
    assert link.read(2) + link.read(2) == bytes([XOFF, XON])
    link.close()


def test_sim_link_adopts_the_simulator_clock():
    clock = SimulatedClock()
    link = SerialLink("sim://echo?baud=9600", device=EchoDevice(clock), timeout=4.0)
    assert link.clock is clock
    assert link.read(1) == b""
    assert clock.now() == pytest.approx(4.0)  # a 4 s timeout passed in simulated time
    assert (link.baudrate, link.flow) == (9600, "none")


def test_given_clock_reaches_the_simulator(monkeypatch):
    from pixelpen.sim import base

    seen = []
    monkeypatch.setitem(base._REGISTRY, "echo-test", lambda clock=None, **o: seen.append(clock) or EchoDevice(clock))
    mine = SimulatedClock()
    link = SerialLink("sim://echo-test", clock=mine)
    assert seen == [mine] and link.clock is mine
    link.close()


def test_dropped_sim_link_raises_disconnected():
    clock = SimulatedClock()
    link = SerialLink("sim://echo?drop_after=2", device=EchoDevice(clock, buffer_size=100), timeout=1.0)
    link.write(b"abcdef")
    with pytest.raises(Disconnected):
        link.read_until(b"\r")


def test_stalled_sim_device_makes_write_time_out():
    clock = SimulatedClock()
    link = SerialLink("sim://echo?stall_after=1&tx_buffer=8", device=EchoDevice(clock), write_timeout=0.5)
    with pytest.raises(LinkTimeout, match="timed out"):
        link.write(b"x" * 64)
    assert clock.now() == pytest.approx(0.5)


def test_xonxoff_through_sim_flow_protects_the_device():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=16, drain_rate=200, xonxoff=True)
    link = SerialLink("sim://echo", flow="xonxoff", device=device, timeout=2.0, write_timeout=30)
    payload = bytes(range(0x20, 0x7F)) + b"\r"
    link.write(payload)
    assert link.read_until(b"\r") == b"OK\r"
    assert device.overflowed == 0 and bytes(device.received) == payload


def test_control_lines_over_sim():
    clock = SimulatedClock()
    link = SerialLink("sim://echo", device=EchoDevice(clock))
    assert link.cts and link.dsr
    link.rts = False
    link.dtr = False
    assert link.port.sim_port.rts is False and link.port.sim_port.dtr is False
    assert link.rts is False and link.dtr is False
    link.close()


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX ptys")
def test_unplugged_os_port_raises_disconnected():
    device = EchoDevice(REAL_CLOCK, buffer_size=100)
    with PtyBridge(device, baud=115200, faults=Faults(drop_after=3)) as bridge:
        link = SerialLink(bridge.path, timeout=2.0)
        link.write(b"abcdef")
        with pytest.raises(Disconnected, match=bridge.path):
            link.read_until(b"\r")
        link.close()


def test_rfc2217_ports_get_no_port_write_timeout(monkeypatch):
    """pyserial's rfc2217 handler refuses write timeouts: SerialLink must not hand it one."""
    import serial

    from pixelpen.drivers import serial as serial_mod

    seen = {}

    class Port:
        baudrate, rtscts, xonxoff, in_waiting = 9600, False, False, 0

        @property
        def write_timeout(self):
            return None

        @write_timeout.setter
        def write_timeout(self, value):
            raise NotImplementedError("write_timeout is currently not supported")

        def write(self, data):
            return len(data)

        def flush(self):
            pass

        def reset_output_buffer(self):
            seen["reset_output"] = True

        def close(self):
            pass

    def fake_for_url(url, **kwargs):
        seen.update(kwargs)
        return Port()

    monkeypatch.setattr(serial, "serial_for_url", fake_for_url)
    link = serial_mod.SerialLink("rfc2217://127.0.0.1:1", write_timeout=5.0)
    assert seen["write_timeout"] is None and link.write_timeout == 5.0
    link.write(b"IN;")  # would raise NotImplementedError if the link set the port's write timeout
    link.flush()
    link.reset_output()
    assert seen["reset_output"] is True  # queued bytes are dropped at the port
    link.close()


def test_an_unknown_scheme_names_the_known_ones():
    with pytest.raises(LinkError, match=r"no handler for nosuch://; known schemes: .*loop://.*sim://"):
        SerialLink("nosuch://x")


def test_a_scheme_pyserial_does_not_know_is_found_in_the_entry_point_group(tmp_path, monkeypatch):
    import serial

    package = tmp_path / "thirdparty_handlers"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "protocol_echoloop.py").write_text(
        "from serial.urlhandler.protocol_loop import Serial as Loop\n"
        "class Serial(Loop):\n"
        "    def __init__(self, *args, clock=None, **kwargs):\n"
        "        self.clock = clock\n"
        "        super().__init__(*args, **kwargs)\n"
        "    def from_url(self, url):\n"
        "        return super().from_url('loop://')\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(serial, "protocol_handler_packages", list(serial.protocol_handler_packages))
    monkeypatch.setattr(serial_link, "serial_handlers", lambda: {"echoloop": "thirdparty_handlers"})
    clock = SimulatedClock()
    link = SerialLink("echoloop://anything", clock=clock, timeout=0.5)
    assert "thirdparty_handlers" in serial.protocol_handler_packages
    assert link.port.clock is clock  # a handler from the group is handed the link's clock
    link.write(b"hi")
    assert link.read(2) == b"hi"
    link.close()


def test_sim_is_registered_in_the_entry_point_group_and_pyserial_schemes_stay_pyserials():
    assert serial_link.serial_handlers()["sim"] == "pixelpen.sim.transports.urlhandler"
    assert serial_link.url_scheme("RFC2217://host:1") == "rfc2217" and serial_link.url_scheme("/dev/ttyS0") is None
    assert not serial_link.use_handler("loop://") and not serial_link.use_handler("/dev/ttyS0")

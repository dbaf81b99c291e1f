"""The pyserial sim:// URL handler: what pyserial users call works against a simulated device."""

from __future__ import annotations

import numpy as np
import pytest
import serial

import pixelpen.sim.transports.urlhandler  # noqa: F401  (registers sim://)
from pixelpen.clock import SimulatedClock
from pixelpen.errors import Disconnected, LinkTimeout, URLError
from pixelpen.sim import base
from pixelpen.sim.transports.urlhandler.protocol_sim import SimDisconnected, SimTimeout, parse_sim_url
from tests.sim.fakes import EchoDevice


def open_echo(url: str = "sim://echo", **kw):
    clock = SimulatedClock()
    device = EchoDevice(clock, **{k: kw.pop(k) for k in list(kw) if k in ("buffer_size", "drain_rate", "ready_free")})
    return serial.serial_for_url(url, device=device, **kw), device, clock


def test_importing_registers_the_handler_package():
    assert "pixelpen.sim.transports.urlhandler" in serial.protocol_handler_packages


def test_write_read_with_timeout():
    port, device, clock = open_echo(timeout=1.0)
    assert port.is_open and port.write(b"PA0,0;\r") == len(b"PA0,0;\r")
    assert port.read(3) == b"OK\r"
    assert device.lines == [b"PA0,0;"]
    assert port.read(1) == b""  # timeout passes in simulated time
    assert port.sim_device is device and port.clock is clock
    port.close()
    assert not device.closed and not port.is_open  # the port did not build it, so it does not stop it


def test_read_waits_for_all_requested_bytes_until_timeout():
    port, device, clock = open_echo(timeout=0.5)
    device.say(b"abc")
    assert port.read(10) == b"abc"
    assert clock.now() == pytest.approx(0.5)


def test_in_waiting_and_reset_input_buffer():
    port, device, clock = open_echo(timeout=0)
    device.say(b"12345")
    port.sim_port.poll()
    clock.advance(1)
    assert port.in_waiting == 5
    port.reset_input_buffer()
    assert port.in_waiting == 0 and port.read(5) == b""


def test_url_baud_and_flow_set_the_serial_attributes():
    port, _, _ = open_echo("sim://echo?baud=19200&flow=rtscts")
    assert port.baudrate == 19200 and port.rtscts and not port.xonxoff
    assert port.sim_port.baud == 19200 and port.sim_port.flow == "rtscts"
    port.close()


def test_constructor_settings_apply_without_url_options_and_reconfigure():
    port, _, _ = open_echo(baudrate=4800, xonxoff=True)
    assert port.sim_port.baud == 4800 and port.sim_port.flow == "xonxoff"
    port.baudrate = 115200
    port.xonxoff = False
    port.rtscts = True
    assert port.sim_port.baud == 115200 and port.sim_port.flow == "rtscts"


def test_control_lines():
    port, _device, clock = open_echo(buffer_size=4, ready_free=4, drain_rate=10)
    assert port.cts and port.dsr and port.cd and not port.ri
    port.rts = False
    port.dtr = False
    assert port.sim_port.rts is False and port.sim_port.dtr is False
    port.write(b"ab")
    clock.advance(0.01)
    assert not port.cts


def test_rtscts_via_url_protects_a_slow_device():
    port, device, _ = open_echo("sim://echo?flow=rtscts", buffer_size=16, drain_rate=200, write_timeout=30)
    port.write(b"x" * 100 + b"\r")
    port.flush()
    assert device.overflowed == 0 and device.arrived_while_busy == 0


def test_drop_raises_both_serial_and_pixelpen_disconnect():
    port, device, _ = open_echo("sim://echo?drop_after=3", buffer_size=100, timeout=1)
    port.write(b"abcdef")
    with pytest.raises(SimDisconnected) as info:
        port.read(1)
    assert isinstance(info.value, serial.SerialException) and isinstance(info.value, Disconnected)
    assert bytes(device.received) == b"abc"


def test_write_timeout_raises_serial_timeout():
    port, _, clock = open_echo("sim://echo?stall_after=0&tx_buffer=4", write_timeout=0.25)
    with pytest.raises(SimTimeout) as info:
        port.write(b"0123456789")
    assert isinstance(info.value, serial.SerialTimeoutException) and isinstance(info.value, LinkTimeout)
    assert clock.now() == pytest.approx(0.25)


def test_blocking_read_of_an_idle_fast_simulation_raises_instead_of_hanging():
    port, _, _ = open_echo(timeout=None)
    with pytest.raises(SimTimeout):
        port.read(1)


def test_closed_port_refuses_io():
    port, _, _ = open_echo()
    port.close()
    with pytest.raises(serial.PortNotOpenError):
        port.write(b"x")
    with pytest.raises(serial.PortNotOpenError):
        port.read(1)


def test_port_stops_a_device_it_built(monkeypatch):
    made = []
    monkeypatch.setitem(base._REGISTRY, "echo-test", lambda clock=None, **o: made.append(EchoDevice(clock)) or made[-1])
    port = serial.serial_for_url("sim://echo-test?speed=fast")
    port.close()
    assert made[0].closed


def test_named_instance_survives_a_port_close(monkeypatch):
    monkeypatch.setattr(base, "_NAMED", {})
    port = serial.serial_for_url("sim://axidraw?id=X&speed=fast", timeout=1.0)
    port.write(b"SL,42\r")
    assert port.read(4) == b"OK\r\n"
    port.close()
    again = serial.serial_for_url("sim://axidraw?id=X&speed=fast", timeout=1.0)
    assert again.sim_device is port.sim_device
    again.write(b"QL\r")
    assert again.read(8) == b"42\r\nOK\r\n"  # still answering, variable kept
    again.close()
    device = again.sim_device
    base.forget_simulator("X")  # closes it: a stopped board reads nothing
    device.receive(b"V\r")
    assert device.take_output() == b""


def test_factory_receives_device_options_and_the_clock(monkeypatch):
    made = {}

    def factory(clock=None, **options):
        made.update(options, clock=clock)
        return EchoDevice(clock)

    monkeypatch.setitem(base._REGISTRY, "echo-test", factory)
    port = serial.serial_for_url("sim://echo-test?speed=fast&paper=a4&baud=2400&pens=6", timeout=0.1)
    assert made["paper"] == "a4" and made["pens"] == "6"
    assert "baud" not in made and "speed" not in made
    assert isinstance(made["clock"], SimulatedClock)
    assert port.baudrate == 2400
    port.close()


def test_explicit_clock_wins_over_speed(monkeypatch):
    clocks = []
    monkeypatch.setitem(base._REGISTRY, "echo-test", lambda clock=None, **o: clocks.append(clock) or EchoDevice(clock))
    mine = SimulatedClock(100.0)
    port = serial.serial_for_url("sim://echo-test?speed=real", clock=mine)
    assert clocks == [mine] and port.clock is mine


def test_parse_sim_url():
    assert parse_sim_url("sim://hp7475a?paper=a4&baud=9600") == ("hp7475a", {"paper": "a4", "baud": "9600"})
    assert parse_sim_url("SIM://grbl/") == ("grbl", {})


@pytest.mark.parametrize("url", ["sim://", "sim://a/b", "sim://x?baud=1&baud=2", "socket://x", "sim:hp7475a"])
def test_bad_sim_urls(url):
    with pytest.raises(URLError):
        parse_sim_url(url)


def test_unknown_model_lists_known_ones(monkeypatch):
    monkeypatch.setitem(base._REGISTRY, "echo-test", EchoDevice)
    with pytest.raises(URLError, match="echo-test"):
        serial.serial_for_url("sim://no-such-plotter")


@pytest.mark.parametrize(("model", "reach"), [("tablet", "open_input('sim:tablet')"), ("st7789", "a panel bus")])
def test_a_simulator_without_a_byte_stream_is_no_serial_port(model, reach):
    with pytest.raises(URLError, match=r"not a serial port") as caught:
        serial.serial_for_url(f"sim://{model}")
    assert reach in str(caught.value)


def test_bad_transport_option_is_a_url_error():
    with pytest.raises(URLError, match="flow"):
        open_echo("sim://echo?flow=sideways")


def test_out_option_saves_the_sheet_when_the_program_closes_the_port(tmp_path):
    from PIL import Image

    out = tmp_path / "sheet.png"
    with serial.serial_for_url(f"sim://hp7475a?speed=fast&out={out}", timeout=30) as port:
        port.write(b"IN;SP1;PU1000,1000;PD5000,1000;PU;OA;")
        assert port.read_until(b"\r") == b"5000,1000,0\r"
        assert not out.exists()
    img = np.asarray(Image.open(out).convert("L"))
    rows = np.flatnonzero((img < 128).any(axis=1))
    # the line is y = 1000 units above the 7475A A4 origin (206 mm from the top): 206 - 24.88 mm at 100 dpi
    assert len(rows) and abs(rows.mean() - (206 - 1000 * 0.02488) * 100 / 25.4) < 2


def test_pixelpen_open_passes_out_through_to_the_simulator(tmp_path):
    import xml.etree.ElementTree as ET

    import pixelpen
    from pixelpen.vector.displaylist import DisplayList

    out = tmp_path / "grbl.svg"
    plotter = pixelpen.open(f"sim:grbl?speed=fast&out={out}")
    u = plotter.profile.unit_mm
    plotter.plot(DisplayList.from_polylines([np.array([[10.0, 10.0], [60.0, 10.0]]) / u], unit_mm=u))
    plotter.close()
    paths = [p.get("d") for p in ET.parse(out).getroot().iter("{http://www.w3.org/2000/svg}path")]
    assert paths == ["M10,200 60,200"]

"""SimPort: baud-rate pacing, handshakes, fault injection and counters, in simulated time."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.clock import REAL_CLOCK, SimulatedClock
from pixelpen.errors import Disconnected, LinkError, LinkTimeout, URLError
from pixelpen.sim.transports.options import Faults, split_options
from pixelpen.sim.transports.port import SimPort, open_sim_port
from tests.sim.fakes import XOFF, XON, EchoDevice

TEXT = bytes(range(0x20, 0x7F)) * 2 + b"\r"  # 191 printable bytes and one line end


def port_for(device: EchoDevice, **kw) -> SimPort:
    return SimPort(device, clock=device.clock, **kw)


def test_960_bytes_at_9600_baud_take_one_second():
    clock = SimulatedClock()
    port = port_for(EchoDevice(clock, buffer_size=4096, drain_rate=1e6))
    assert port.write(b"x" * 960) == 960
    assert port.drain(timeout=10)
    # 8N1: 10 bits per byte; 960 * 10 / 9600 = 1.0 s
    assert clock.now() == pytest.approx(1.0, abs=1e-9)
    stats = port.stats()
    assert stats.bytes_sent == 960
    assert stats.tx_busy == pytest.approx(1.0)
    assert stats.utilisation == pytest.approx(1.0)


@settings(max_examples=25, deadline=None)
@given(baud=st.sampled_from([300, 1200, 2400, 4800, 9600, 19200, 38400, 115200]), n=st.integers(1, 300))
def test_drain_time_is_ten_bits_per_byte(baud, n):
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=10_000, drain_rate=1e9)
    port = port_for(device, baud=baud)
    port.write(b"a" * n)
    assert port.drain(timeout=1e6)
    assert clock.now() == pytest.approx(n * 10 / baud, rel=1e-9)
    assert bytes(device.received) == b"a" * n


def test_answers_arrive_paced_and_complete():
    clock = SimulatedClock()
    device = EchoDevice(clock)
    port = port_for(device, baud=1200)
    device.say(b"HELLO\r")
    got = bytearray()
    while len(got) < 6:
        got += port.read(6, timeout=1.0)
    assert bytes(got) == b"HELLO\r"
    assert clock.now() == pytest.approx(6 * 10 / 1200)
    assert port.stats().bytes_received == 6


def test_reply_to_a_line_comes_after_the_device_executes_it():
    clock = SimulatedClock()
    device = EchoDevice(clock, drain_rate=1000)
    port = port_for(device, baud=9600)
    port.write(b"AB\r")
    reply = bytearray()
    while len(reply) < 3:
        chunk = port.read(3, timeout=1.0)
        assert chunk, "no reply within a second"
        reply += chunk
    assert bytes(reply) == b"OK\r"
    assert device.lines == [b"AB"]
    # last byte on the wire at 3 byte-times, executed 1 ms later, reply takes 3 byte-times
    assert clock.now() == pytest.approx(3 * 10 / 9600 + 0.001 + 3 * 10 / 9600)


def test_rtscts_never_sends_while_the_device_is_busy():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=16, drain_rate=100, ready_free=4)
    port = port_for(device, flow="rtscts")
    port.write(TEXT)
    assert port.drain(timeout=60)
    assert device.arrived_while_busy == 0
    assert device.overflowed == 0
    assert bytes(device.received) == TEXT
    assert port.stats().held_off > 0


def test_no_handshake_overflows_a_slow_device():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=16, drain_rate=100)
    port = port_for(device, flow="none")
    port.write(TEXT)
    assert port.drain(timeout=60)
    assert device.overflowed > 0
    assert port.stats().held_off == 0


def test_xonxoff_holds_the_transmitter_and_hides_the_flow_bytes():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=16, drain_rate=100, xonxoff=True, xoff_free=4, xon_free=12)
    port = port_for(device, flow="xonxoff")
    port.write(TEXT)
    assert port.drain(timeout=60)
    assert device.overflowed == 0
    assert bytes(device.received) == TEXT
    reply = port.read(100, timeout=5)
    assert reply == b"OK\r"[: len(reply)] and reply
    assert port.stats().bytes_received > len(reply)  # XON/XOFF came over the wire but were consumed


def test_xon_xoff_bytes_pass_through_without_xonxoff_flow():
    clock = SimulatedClock()
    device = EchoDevice(clock)
    port = port_for(device, flow="none")
    device.say(bytes([XOFF, 0x41, XON]))
    got = bytearray()
    while len(got) < 3:
        got += port.read(3, timeout=1)
    assert bytes(got) == bytes([XOFF, 0x41, XON])


def test_write_blocks_when_the_transmit_buffer_is_full():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=10_000)
    port = port_for(device, tx_buffer=10)
    assert port.write(b"0123456789abcdef", timeout=0) == 10
    assert port.out_waiting == 10
    assert port.write(b"abcdef", timeout=1.0) == 6  # space frees as bytes go out
    assert port.drain(timeout=1)
    assert bytes(device.received) == b"0123456789abcdef"


def test_drop_after_disconnects_the_host_side():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=100)
    port = port_for(device, faults=Faults(drop_after=5))
    port.write(b"0123456789")
    with pytest.raises(Disconnected, match="dropped after 5"):
        port.drain(timeout=1)
    assert bytes(device.received) == b"01234"
    with pytest.raises(Disconnected):
        port.read(1, timeout=0)
    with pytest.raises(Disconnected):
        port.write(b"x")
    assert not port.cts and not port.dsr


def test_stall_after_blocks_writes_until_their_timeout():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=100)
    port = port_for(device, faults=Faults(stall_after=5), tx_buffer=8)
    accepted = port.write(b"0123456789abcdefghij", timeout=0.5)
    assert accepted == 5 + 8  # five went to the device, eight fill the buffer, the rest waits
    assert clock.now() == pytest.approx(0.5)
    assert bytes(device.received) == b"01234"
    assert not port.drain(timeout=0.2)


def test_corrupt_at_inverts_exactly_that_byte():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=100)
    port = port_for(device, faults=Faults(corrupt_at=2))
    port.write(b"abcdef")
    port.drain(timeout=1)
    assert bytes(device.received) == b"ab" + bytes([ord("c") ^ 0xFF]) + b"def"


@pytest.mark.parametrize(
    "option, fault",
    [("power_loss_after", "power-loss"), ("paper_lever_after", "paper-lever"), ("pause_after", "pause-button")],
)
def test_device_faults_fire_at_their_byte_count(option, fault):
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=100)
    port = port_for(device, faults=Faults(**{option: 3}))
    port.write(b"abcdef")
    port.drain(timeout=1)
    assert device.faults == [(fault, 3)]


def test_fault_at_zero_fires_at_once():
    device = EchoDevice(SimulatedClock())
    port_for(device, faults=Faults(pause_after=0))
    assert device.faults == [("pause-button", 0)]


def test_waiting_forever_on_an_idle_simulation_raises_instead_of_hanging():
    port = port_for(EchoDevice(SimulatedClock()))
    with pytest.raises(LinkTimeout, match="forever"):
        port.read(1, timeout=None)


def test_timeout_with_nothing_to_do_jumps_simulated_time():
    clock = SimulatedClock()
    port = port_for(EchoDevice(clock))
    assert port.read(1, timeout=3.0) == b""
    assert clock.now() == pytest.approx(3.0)


def test_real_clock_round_trip():
    device = EchoDevice(REAL_CLOCK)
    port = SimPort(device, baud=115200, clock=REAL_CLOCK)
    port.write(b"PING\r")
    got = bytearray()
    for _ in range(100):
        got += port.read(3, timeout=0.05)
        if len(got) >= 3:
            break
    assert bytes(got) == b"OK\r"


def test_reset_output_discards_queued_bytes():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=100)
    port = port_for(device, baud=1200)
    port.write(b"0123456789")
    port.reset_output()
    assert port.drain(timeout=1)
    assert len(device.received) <= 1


def test_reset_input_discards_arrived_bytes():
    clock = SimulatedClock()
    device = EchoDevice(clock)
    port = port_for(device)
    device.say(b"junk")
    port.poll()  # the port takes the device's output now; it arrives over the next 4 byte-times
    clock.advance(1)
    assert port.in_waiting == 4
    port.reset_input()
    assert port.in_waiting == 0


def test_cts_follows_the_device_ready_line():
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=4, ready_free=4, drain_rate=10)
    port = port_for(device, flow="none")
    assert port.cts
    port.write(b"ab")
    clock.advance(2 * 10 / 9600)
    assert not port.cts  # 2 of 4 bytes used: fewer than 4 free
    clock.advance(1.0)
    assert port.cts


def test_close_closes_the_device_once():
    device = EchoDevice(SimulatedClock())
    port = port_for(device)
    port.close()
    port.close()
    assert device.closed and port.closed


def test_open_sim_port_refuses_device_options_for_a_ready_device():
    with pytest.raises(URLError, match="paper"):
        open_sim_port("echo", {"paper": "a4"}, device=EchoDevice(SimulatedClock()))


def test_the_default_line_speed_is_the_devices_own():
    from pixelpen.sim.base import create_simulator

    clock = SimulatedClock()
    assert port_for(EchoDevice(clock)).baud == 9600  # no default_baud: an RS-232 plotter's 9600
    for model, baud in (("axidraw", 12_000_000), ("grbl", 115200), ("hp7475a", 9600)):
        device = create_simulator(model, clock=clock)
        assert SimPort(device, clock=clock).baud == baud, model
        assert SimPort(device, clock=clock, baud=4800).baud == 4800
    assert split_options({})[0].baud is None


def test_out_saves_the_paper_when_the_port_closes(tmp_path):
    import xml.etree.ElementTree as ET

    from pixelpen.sim.base import create_simulator

    clock = SimulatedClock()
    out = tmp_path / "sheet.svg"
    transport, _ = split_options({"out": str(out)})
    device = create_simulator("grbl", clock=clock)
    port = SimPort(device, clock=clock, out=transport.out)
    port.write(b"G0 X10 Y20\nM3 S50\nG1 X50 Y20 F6000\nM5\n")  # the grbl profile: S50 lowers the pen
    port.drain()
    clock.advance(5.0)
    port.poll()
    assert not out.exists()
    port.close()
    paths = [p.get("d") for p in ET.parse(out).getroot().iter("{http://www.w3.org/2000/svg}path")]
    assert paths == ["M10,190 50,190"]  # machine y up -> SVG y down on the 210 mm sheet


def test_out_needs_a_device_with_paper():
    with pytest.raises(LinkError, match="no paper"):
        SimPort(EchoDevice(SimulatedClock()), out="x.png")


def test_an_unwritable_out_file_is_a_clear_error(tmp_path):
    from pixelpen.errors import ConfigError
    from pixelpen.sim.base import create_simulator

    clock = SimulatedClock()
    port = SimPort(create_simulator("grbl", clock=clock), clock=clock, out=str(tmp_path / "no" / "such" / "dir.png"))
    with pytest.raises(ConfigError, match="cannot write the paper"):
        port.close()


@pytest.mark.parametrize("url", ["sim:hp7475a?model=x", "sim://hp7475a?model=x", "sim:hp7475a?clock=1", "sim://grbl?clock=1"])
def test_options_named_like_factory_parameters_are_unknown_options(url):
    import pixelpen
    from pixelpen.errors import URLError

    with pytest.raises(URLError, match="unknown option"):
        if url.startswith("sim://"):
            import serial

            import pixelpen.sim.transports.urlhandler

            serial.serial_for_url(url, timeout=1).close()
        else:
            pixelpen.open(url).close()

"""The Link contract against every transport: loop://, sim:// (real, fast), a pty, the pyusb backend, recording."""

from __future__ import annotations

import io
import logging
import os
from collections.abc import Callable
from dataclasses import dataclass

import pytest

from pixelpen.clock import REAL_CLOCK, SimulatedClock
from pixelpen.drivers.serial import SerialLines, SerialLink
from pixelpen.drivers.stream import Link, format_bytes
from pixelpen.drivers.trace import RecordingLink
from pixelpen.drivers.usbprinter import UsbPrinterLink
from pixelpen.errors import LinkError, LinkTimeout
from pixelpen.sim.transports.pty import PtyBridge
from pixelpen.sim.transports.usbbackend import PrinterClassBackend
from tests.sim.fakes import EchoDevice

SHORT = 0.05


@dataclass
class Rig:
    """A link under test, what its far end answers to a line, and a way to make the far end talk."""

    link: Link
    reply_to: Callable[[bytes], bytes]
    say: Callable[[bytes], None]
    logger: str


def _echo_rig(link: SerialLink | UsbPrinterLink, device: EchoDevice, logger: str) -> Rig:
    return Rig(link, lambda line: b"OK\r", device.say, logger)


def make_loop() -> Rig:
    link = SerialLink("loop://", timeout=SHORT)
    return Rig(link, lambda line: line, link.port.write, "pixelpen.drivers.serial")


def make_sim(fast: bool) -> Rig:
    clock = SimulatedClock() if fast else REAL_CLOCK
    device = EchoDevice(clock, buffer_size=256)
    link = SerialLink("sim://echo?baud=115200", device=device, timeout=SHORT if not fast else 1.0)
    return _echo_rig(link, device, "pixelpen.drivers.serial")


def make_pty() -> Rig:
    device = EchoDevice(REAL_CLOCK, buffer_size=256)
    bridge = PtyBridge(device, baud=115200)
    link = SerialLink(bridge.path, timeout=0.5)
    original = link._close_raw

    def close_both() -> None:
        original()
        bridge.close()

    link._close_raw = close_both  # type: ignore[method-assign]
    return _echo_rig(link, device, "pixelpen.drivers.serial")


def make_usb() -> Rig:
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=256)
    link = UsbPrinterLink(backend=PrinterClassBackend(device, clock=clock), timeout=1.0)
    return _echo_rig(link, device, "pixelpen.drivers.usbprinter")


def make_recording() -> Rig:
    rig = make_sim(fast=True)
    return Rig(RecordingLink(rig.link, io.StringIO()), rig.reply_to, rig.say, "pixelpen.drivers.trace")


RIGS = {
    "loop": make_loop,
    "sim-real": lambda: make_sim(False),
    "sim-fast": lambda: make_sim(True),
    "usb": make_usb,
    "recording": make_recording,
}
if hasattr(os, "openpty"):
    RIGS["pty"] = make_pty


@pytest.fixture(params=sorted(RIGS))
def rig(request):
    r = RIGS[request.param]()
    yield r
    r.link.close()


def wait_for_input(link: Link, n: int) -> None:
    for _ in range(200):
        if link.in_waiting >= n:
            return
        link.clock.sleep(0.005)
    raise AssertionError(f"{link.name}: {n} bytes never arrived (in_waiting {link.in_waiting})")


def test_write_then_read_until_reply(rig):
    rig.link.write(b"PU0,0;\r")
    assert rig.link.read_until(b"\r", timeout=2.0) == rig.reply_to(b"PU0,0;\r")


def test_read_returns_empty_only_on_timeout(rig):
    assert rig.link.read(5, timeout=SHORT) == b""
    rig.say(b"xy")
    got = rig.link.read(5, timeout=2.0)
    assert got and b"xy".startswith(got)


def test_read_until_timeout_names_the_partial_bytes(rig):
    rig.say(b"7475")
    wait_for_input(rig.link, 4)
    with pytest.raises(LinkTimeout, match="7475") as info:
        rig.link.read_until(b"\r", timeout=SHORT)
    assert info.value.partial == b"7475"
    rig.say(b"A\r")
    assert rig.link.read_until(b"\r", timeout=2.0) == b"7475A\r"  # nothing was lost


def test_read_until_refuses_replies_longer_than_max_size(rig):
    rig.say(b"0123456789ABCDEF\r")
    wait_for_input(rig.link, 17)
    with pytest.raises(LinkError, match="within 8 bytes") as info:
        rig.link.read_until(b"\r", timeout=2.0, max_size=8)
    assert info.value.partial == b"01234567"


def test_in_waiting_and_reset_input(rig):
    assert rig.link.in_waiting == 0
    rig.say(b"junk")
    wait_for_input(rig.link, 4)
    rig.link.reset_input()
    assert rig.link.in_waiting == 0
    assert rig.link.read(1, timeout=SHORT) == b""


def test_flush_returns_once_bytes_left(rig):
    rig.link.write(b"abc\r")
    rig.link.flush()
    assert rig.link.read_until(b"\r", timeout=2.0) == rig.reply_to(b"abc\r")


def test_close_is_idempotent_and_final(rig):
    with rig.link as link:
        assert isinstance(link.name, str) and link.name
    assert rig.link.closed
    rig.link.close()
    with pytest.raises(LinkError, match="closed"):
        rig.link.write(b"x")
    with pytest.raises(LinkError, match="closed"):
        rig.link.read(1)


def test_wire_traffic_is_logged_as_hex_and_text(rig, caplog):
    with caplog.at_level(logging.DEBUG, logger=rig.logger):
        rig.link.write(b"IN;\r")
        rig.link.read_until(b"\r", timeout=2.0)
    records = [r for r in caplog.records if r.name == rig.logger]
    assert any("49 4e 3b 0d |IN;.|" in r.getMessage() for r in records)
    assert any(" < " in r.getMessage() for r in records)


def test_bad_arguments():
    link = make_loop().link
    with pytest.raises(ValueError):
        link.read(0)
    with pytest.raises(ValueError):
        link.read_until(b"")
    link.close()


def test_format_bytes_shows_hex_and_printable():
    assert format_bytes(b"IN;\x03") == "49 4e 3b 03 |IN;.|"
    assert format_bytes(b"x" * 10, limit=4) == "78 78 78 78 |xxxx| ... (+6 bytes)"


def test_line_signals_belong_to_the_serial_link_not_the_stream():
    usb = make_usb().link
    assert not isinstance(usb, SerialLines) and not hasattr(usb, "cts") and not hasattr(usb, "soft_xonxoff")
    assert not usb.held_off  # a stream without flow control is never held off
    recording = RecordingLink(usb, io.StringIO())
    with pytest.raises(LinkError, match="no serial line signals"):
        assert recording.cts
    with pytest.raises(LinkError, match="no serial line signals"):
        recording.rts = True
    recording.close()
    serial_link = make_loop().link
    assert isinstance(serial_link, SerialLines) and isinstance(RecordingLink(serial_link, io.StringIO()), SerialLines)
    serial_link.close()
    assert not any(hasattr(Link, name) for name in ("cts", "dsr", "rts", "dtr", "soft_xonxoff"))

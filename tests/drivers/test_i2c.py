"""I2CBus: control bytes and transactions for SSD1306 streams, chunking, NAKs and other faults, counters, open()."""

from __future__ import annotations

import errno

import pytest
import smbus2
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.drivers import i2c as i2c_module
from pixelpen.drivers.bus import I2CPanelBus, PanelBus
from pixelpen.drivers.i2c import I2CBus, adapter_clock_hz
from pixelpen.errors import ConfigError, InvalidArgument, LinkError
from pixelpen.sim.transports.i2cdev import SimSMBus
from tests.sim.transports.chips import RecordingChip
from tests.sim.transports.test_i2cdev import smbus_opens


def wired(**kw) -> tuple[RecordingChip, I2CBus]:
    chip = RecordingChip(addresses=(0x3C,))
    return chip, I2CBus(SimSMBus(chip), kw.pop("address", 0x3C), name="i2c-1", **kw)


def test_i2cbus_is_an_i2c_panel_bus():
    _, bus = wired()
    assert isinstance(bus, PanelBus) and isinstance(bus, I2CPanelBus)
    assert (bus.kind, bus.clock_hz, bus.max_transfer, bus.address) == ("i2c", 400_000, 4096, 0x3C)


def test_ssd1306_init_commands_are_one_transaction_after_control_byte_00():
    # SSD1306 datasheet 8.1.5.2: control byte 0x00 (Co=0, D/C#=0), then command bytes: AE, D5 80
    chip, bus = wired()
    bus.command(0xAE, 0xD5, 0x80)
    assert chip.writes == [(0x3C, b"\x00\xae\xd5\x80")]
    assert (bus.bytes_sent, bus.transfers) == (4, 1)


def test_a_full_ssd1306_frame_is_one_data_transaction():
    chip, bus = wired()
    bus.command(0x21, 0, 127, 0x22, 0, 7)
    bus.data(bytes(range(256)) * 4)
    assert chip.writes == [(0x3C, b"\x00\x21\x00\x7f\x22\x00\x07"), (0x3C, b"\x40" + bytes(range(256)) * 4)]
    assert (bus.bytes_sent, bus.transfers) == (7 + 1025, 2)  # panels.md §9: 1032 bytes in 2 transactions


@settings(max_examples=80, deadline=None)
@given(length=st.integers(0, 10_000), max_transfer=st.integers(2, 5000))
def test_data_chunks_repeat_the_control_byte_and_keep_the_bytes(length, max_transfer):
    chip, bus = wired(max_transfer=max_transfer)
    payload = bytes((i * 31 + length) % 256 for i in range(length))
    bus.data(payload)
    assert all(p[0] == 0x40 and 2 <= len(p) <= max_transfer for _, p in chip.writes)
    assert b"".join(p[1:] for _, p in chip.writes) == payload
    assert len(chip.writes) == -(-length // (max_transfer - 1))
    assert (bus.bytes_sent, bus.transfers) == (length + len(chip.writes), len(chip.writes))


def test_messages_are_real_smbus2_writes():
    seen = []

    class Adapter:
        def i2c_rdwr(self, *msgs):
            seen.extend(msgs)

        def close(self):
            pass

    bus = I2CBus(Adapter(), 0x3D)
    bus.data(b"\x01\x02")
    (msg,) = seen
    assert isinstance(msg, smbus2.i2c_msg)
    assert (msg.addr, msg.flags, bytes(msg)) == (0x3D, 0, b"\x40\x01\x02")


def test_no_acknowledgement_names_the_bus_and_address():
    chip = RecordingChip(addresses=(0x3D,))
    bus = I2CBus(SimSMBus(chip), 0x3C, name="i2c-1")
    with pytest.raises(LinkError, match=r"^i2c-1: no device acknowledged address 0x3c$"):
        bus.command(0xAE)
    assert (bus.bytes_sent, bus.transfers) == (0, 0)


@pytest.mark.parametrize("code", [errno.ENXIO, errno.EREMOTEIO, errno.EIO])
def test_every_errno_linux_adapters_use_for_a_nak_is_a_nak(code):
    class Adapter:
        def i2c_rdwr(self, *msgs):
            raise OSError(code, "nak")

        def close(self):
            pass

    with pytest.raises(LinkError, match="no device acknowledged address 0x3c"):
        I2CBus(Adapter(), 0x3C).data(b"\x00")


def test_other_faults_name_the_write():
    _, bus = wired(max_transfer=9000)  # i2c-dev refuses messages over 8192 bytes with EINVAL
    with pytest.raises(LinkError, match=r"i2c-1: write of 9000 bytes to 0x3c failed: \[Errno 22\]"):
        bus.data(bytes(10_000))


def test_bad_arguments_are_refused():
    for address in (0x00, 0x78, 0x3C0, "0x3c"):
        with pytest.raises(ConfigError, match="7-bit"):
            wired(address=address)
    with pytest.raises(ConfigError, match="control byte"):
        wired(max_transfer=1)
    _, bus = wired(max_transfer=4)
    with pytest.raises(InvalidArgument, match="do not fit in one transfer"):
        bus.command(1, 2, 3, 4)
    with pytest.raises(InvalidArgument, match="at least one byte"):
        bus.command()


def test_a_closed_bus_refuses_and_closes_its_adapter_once():
    chip = RecordingChip()
    adapter = SimSMBus(chip)
    bus = I2CBus(adapter, 0x3C)
    bus.close()
    bus.close()
    for call in (lambda: bus.command(0xAF), lambda: bus.data(b""), bus.reset):
        with pytest.raises(LinkError, match="closed"):
            call()
    with pytest.raises(OSError):
        adapter.write_byte(0x3C, 0)


def test_reset_line_is_optional():
    chip, bus = wired()
    bus.reset()
    assert chip.clock.now() == 0.0

    class Line:
        def __init__(self):
            self.levels = []

        def set(self, level):
            self.levels.append(level)

        def close(self):
            pass

    line = Line()
    bus = I2CBus(SimSMBus(chip), 0x3C, reset=line, clock=chip.clock)
    bus.reset(recovery=0.001)
    assert line.levels == [False, True] and chip.clock.now() == pytest.approx(0.001 + 10e-6)


def test_the_adapter_clock_comes_from_the_device_tree(tmp_path, monkeypatch):
    node = tmp_path / "i2c-1" / "of_node"
    node.mkdir(parents=True)
    (node / "clock-frequency").write_bytes((100_000).to_bytes(4, "big"))  # Raspberry Pi's default i2c_arm rate
    assert adapter_clock_hz(1, tmp_path) == 100_000 and adapter_clock_hz(2, tmp_path) is None
    monkeypatch.setattr(i2c_module, "I2C_SYSFS", tmp_path)
    opened = smbus_opens(monkeypatch, RecordingChip())
    bus = I2CBus.open(1, 0x3C)
    assert opened == [1] and bus.clock_hz == 100_000 and bus.name == "i2c-1"
    assert I2CBus.open(1, 0x3C, clock_hz=1e6).clock_hz == 1e6
    assert I2CBus.open(2, 0x3C).clock_hz == 400_000


@pytest.mark.parametrize(
    ("error", "words"),
    [
        (FileNotFoundError(errno.ENOENT, "No such file"), ["/dev/i2c-1 does not exist", "modprobe i2c-dev"]),
        (PermissionError(errno.EACCES, "Permission denied"),
         ["permission denied on /dev/i2c-1", "'i2c' group", 'SUBSYSTEM=="i2c-dev", GROUP="i2c", MODE="0660"']),
    ],
)
def test_open_failures_say_which_node_and_what_to_do(monkeypatch, error, words):
    def smbus(number):
        raise error

    monkeypatch.setattr(smbus2, "SMBus", smbus)
    with pytest.raises(LinkError) as caught:
        I2CBus.open(1, 0x3C)
    assert all(word in str(caught.value) for word in words), str(caught.value)


def test_open_with_the_real_smbus2_names_the_missing_node():
    with pytest.raises(LinkError, match="/dev/i2c-99 does not exist"):
        I2CBus.open(99, 0x3C)


def test_end_to_end_an_ssd1306_simulator_shows_what_the_bus_sent():
    import numpy as np

    from pixelpen.clock import SimulatedClock

    SSD1306Sim = pytest.importorskip("pixelpen.sim.panels.ssd1306", reason="the SSD1306 simulator (H1)").SSD1306Sim
    clock = SimulatedClock()
    sim = SSD1306Sim(128, 64, clock=clock)
    bus = I2CBus(SimSMBus(sim, clock_hz=400_000), 0x3C, clock=clock, name="i2c-1")
    # SSD1306 application note's initialisation: display off, clock, multiplex 64, offset 0, start line 0,
    # charge pump on, horizontal addressing, segment remap, COM scan down, COM pins 12h, contrast, pre-charge,
    # VCOMH, resume from RAM, normal (not inverted), display on
    bus.command(0xAE, 0xD5, 0x80, 0xA8, 0x3F, 0xD3, 0x00, 0x40, 0x8D, 0x14, 0x20, 0x00, 0xA1, 0xC8, 0xDA, 0x12,
                0x81, 0xCF, 0xD9, 0xF1, 0xDB, 0x40, 0xA4, 0xA6, 0xAF)
    bus.command(0x21, 0, 127, 0x22, 0, 7)  # the whole 128x8-page window
    page = bytes([0xFF] * 64 + [0x00] * 64)  # RAM columns 0..63 lit in every page
    start = clock.now()
    bus.data(page * 8)
    assert clock.now() - start == pytest.approx((1 + 9 * (1 + 1025) + 1) / 400e3)  # one transaction, 23.1 ms
    assert sim.events == []
    lit = np.asarray(sim.glass()).astype(bool)
    assert lit.shape == (64, 128)
    assert lit.sum() == 64 * 64 and np.all(lit.all(axis=0) | ~lit.any(axis=0))  # half the glass, whole columns
    assert sim.stats.transfers == bus.transfers == 3
    assert sim.stats.bytes == bus.bytes_sent + bus.transfers  # the simulator also counts each address byte


def test_a_failing_adapter_close_still_releases_the_reset_line_and_is_a_link_error():
    released = []

    class Adapter:
        def i2c_rdwr(self, *msgs):
            pass

        def close(self):
            raise OSError(errno.EBADF, "Bad file descriptor")

    class Line:
        def set(self, level):
            pass

        def close(self):
            released.append("reset")

    bus = I2CBus(Adapter(), 0x3C, reset=Line(), name="i2c-1")
    with pytest.raises(LinkError, match=r"i2c-1: closing failed: \[Errno 9\]"):
        bus.close()
    assert released == ["reset"] and bus.closed


def test_open_closes_the_adapter_when_the_reset_line_cannot_be_had(monkeypatch):
    adapter = SimSMBus(RecordingChip())
    monkeypatch.setattr(smbus2, "SMBus", lambda number: adapter)

    def no_line(chip, offset, *, initial):
        raise LinkError(f"GPIO line {offset}: permission denied on {chip}")

    monkeypatch.setattr(i2c_module, "open_output_line", no_line)
    with pytest.raises(LinkError, match="GPIO line 4"):
        I2CBus.open(1, 0x3C, rst=4)
    with pytest.raises(OSError, match="Bad file descriptor"):
        adapter.write_byte(0x3C, 0)  # closed again

"""Bus traces: recording a PanelBus session, replaying it chunking-independently, and the reader's refusals."""

from __future__ import annotations

import io

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.drivers.bus import PanelBus, command_bytes
from pixelpen.drivers.bustrace import RecordingBus, ReplayBus, parse_bus_trace, read_bus_trace
from pixelpen.drivers.trace import read_trace
from pixelpen.errors import LinkError, ParseError, TraceMismatch
from tests.fuzzing import campaign, depths


class StubBus:
    """A PanelBus that notes every call and advances a simulated clock 1 us per byte."""

    def __init__(self, *, kind: str = "spi", max_transfer: int = 4096, address: int | None = None) -> None:
        self.kind = kind
        self.clock_hz = 62_500_000 if kind == "spi" else 400_000
        self.max_transfer = max_transfer
        if address is not None:
            self.address = address
        self.clock = SimulatedClock()
        self.bytes_sent = 0
        self.transfers = 0
        self.calls: list[tuple[str, bytes]] = []
        self.closed = False
        self.fail_next = False

    def command(self, *cmd: int | bytes) -> None:
        self._note("C", command_bytes(*cmd))

    def data(self, data: bytes) -> None:
        self._note("D", bytes(data))

    def reset(self, recovery: float = 0.120) -> None:
        self._note("R", b"")
        self.clock.advance(recovery)

    def close(self) -> None:
        self.closed = True

    def _note(self, what: str, payload: bytes) -> None:
        if self.fail_next:
            self.fail_next = False
            raise LinkError("stub: write failed")
        self.calls.append((what, payload))
        self.bytes_sent += len(payload)
        self.transfers += bool(payload)
        self.clock.advance(1e-6 * len(payload))


def record(session, **bus_options) -> tuple[str, StubBus]:
    stub = StubBus(**bus_options)
    out = io.StringIO()
    bus = RecordingBus(stub, out, url="st7789:spi:0.0?dc=25")
    assert isinstance(bus, PanelBus)
    session(bus)
    bus.close()
    return out.getvalue(), stub


def mipi_session(bus) -> None:
    bus.reset()
    bus.command(0x01)
    bus.command(0x2A)
    bus.data(b"\x00\x00\x00\xef")
    bus.command(0x2C)
    bus.data(bytes(range(256)) * 20)  # 5120 bytes: two frames at max_transfer 4096


def test_recording_writes_the_documented_lines():
    text, stub = record(mipi_session)
    lines = text.splitlines()
    assert lines[0] == ("#pixelpen-trace 1 url=st7789%3Aspi%3A0.0%3Fdc%3D25 kind=bus bus=spi clock_hz=62500000 "
                        "max_transfer=4096")
    assert lines[1] == "0.000000 R"
    assert lines[2] == "0.120000 C 01"
    assert lines[3] == "0.120001 C 2a"
    assert lines[4] == "0.120002 D 00 00 00 ef"
    assert lines[5] == "0.120006 C 2c"
    assert lines[6] == "0.120007 D " + " ".join(f"{b:02x}" for b in bytes(range(256)) * 16)
    assert lines[7] == "0.120007 D " + " ".join(f"{b:02x}" for b in bytes(range(256)) * 4)
    assert len(lines) == 8
    assert stub.closed
    assert [c[0] for c in stub.calls] == ["R", "C", "C", "D", "C", "D"]


def test_a_frame_longer_than_a_line_continues_on_plus_lines():
    text, _ = record(lambda bus: bus.data(bytes(5000)), max_transfer=0xFF00)
    lines = text.splitlines()[1:]
    assert [line.split()[1] for line in lines] == ["D", "+"]
    assert len(lines[0].split()) - 2 == 4096 and len(lines[1].split()) - 2 == 904


def test_i2c_settings_are_recorded():
    text, _ = record(lambda bus: bus.command(0xAE), kind="i2c", address=0x3C)
    trace = read_bus_trace(io.StringIO(text))
    assert (trace.bus, trace.address, trace.clock_hz, trace.max_transfer) == ("i2c", 0x3C, 400_000, 4096)
    assert "address=0x3c" in text.splitlines()[0]


def test_the_recorder_shows_the_wrapped_bus_settings_and_counters():
    stub = StubBus(max_transfer=32)
    bus = RecordingBus(stub, io.StringIO())
    bus.command(0x2A, b"\x00\x01")
    bus.data(bytes(40))
    assert (bus.kind, bus.clock_hz, bus.max_transfer) == ("spi", 62_500_000, 32)
    assert (bus.bytes_sent, bus.transfers) == (43, 2)


def test_a_fractional_clock_is_written_in_full():
    stub = StubBus()
    stub.clock_hz = 1_234_567.5
    out = io.StringIO()
    RecordingBus(stub, out).close()
    assert "clock_hz=1234567.5 " in out.getvalue()
    assert read_bus_trace(io.StringIO(out.getvalue())).clock_hz == 1_234_567.5


def test_a_failed_call_is_a_comment_and_not_a_frame():
    def session(bus):
        bus.command(0x11)
        bus.inner.fail_next = True
        with pytest.raises(LinkError):
            bus.data(b"\x01\x02")
        bus.command(0x29)

    text, _ = record(session)
    assert "# error during data of 2 bytes 01 02: LinkError: stub: write failed" in text
    assert read_bus_trace(io.StringIO(text)).stream("D") == b""


def test_replay_accepts_the_recorded_session_and_other_chunkings():
    text, _ = record(mipi_session)
    replay = ReplayBus(read_bus_trace(io.StringIO(text)))
    mipi_session(replay)
    replay.check_complete()
    assert replay.bytes_sent == 4 + 5120 + 3 and replay.kind == "spi" and replay.clock_hz == 62_500_000

    other = ReplayBus(read_bus_trace(io.StringIO(text)))
    other.reset()
    other.command(0x01, 0x2A)  # two recorded command frames in one call
    other.data(b"\x00\x00")
    other.data(b"\x00\xef")
    other.command(b"\x2c")
    pixels = bytes(range(256)) * 20
    for i in range(0, len(pixels), 1000):
        other.data(pixels[i : i + 1000])
    other.check_complete()


def test_replay_names_the_first_wrong_byte():
    text, _ = record(mipi_session)
    replay = ReplayBus(read_bus_trace(io.StringIO(text)), name="replay")
    replay.reset()
    replay.command(0x01, 0x2A)
    replay.data(b"\x00\x00")
    pixels = bytearray(bytes(range(256)) * 20)
    with pytest.raises(TraceMismatch) as info:
        replay.data(b"\x00\xee")
    exc = info.value
    assert (exc.offset, exc.level, exc.expected, exc.found, exc.line) == (3, "D", b"\xef", b"\xee", 5)
    assert "byte offset 3 of the D stream (trace line 5)" in str(exc)

    replay = ReplayBus(read_bus_trace(io.StringIO(text)))
    mipi_session_until_pixels(replay)
    pixels[4500] ^= 0xFF
    with pytest.raises(TraceMismatch) as info:
        replay.data(bytes(pixels))
    assert (info.value.offset, info.value.line) == (4 + 4500, 8)
    assert info.value.expected[:1] == bytes([4500 % 256])


def mipi_session_until_pixels(bus) -> None:
    bus.reset()
    bus.command(0x01)
    bus.command(0x2A)
    bus.data(b"\x00\x00\x00\xef")
    bus.command(0x2C)


def test_replay_refuses_the_wrong_level_a_missing_reset_and_extra_bytes():
    text, _ = record(mipi_session)
    replay = ReplayBus(read_bus_trace(io.StringIO(text)))
    with pytest.raises(TraceMismatch, match="expected a reset pulse, found command"):
        replay.command(0x01)

    replay = ReplayBus(read_bus_trace(io.StringIO(text)))
    replay.reset()
    replay.command(0x01)
    with pytest.raises(TraceMismatch) as info:
        replay.data(b"\x2a")  # the trace has 0x2A as a command
    assert info.value.level == "C" and info.value.offset == 1 and "found data (D/C high) bytes 2a" in str(info.value)

    replay = ReplayBus(read_bus_trace(io.StringIO(text)))
    mipi_session(replay)
    with pytest.raises(TraceMismatch, match="expected the end of the trace"):
        replay.command(0x29)
    with pytest.raises(TraceMismatch, match="expected the end of the trace, found a reset"):
        replay.reset()


def test_check_complete_reports_an_unfinished_program():
    text, _ = record(mipi_session)
    replay = ReplayBus(read_bus_trace(io.StringIO(text)))
    mipi_session_until_pixels(replay)
    replay.data(b"\x00\x01")
    with pytest.raises(TraceMismatch) as info:
        replay.check_complete()
    assert info.value.offset == 6 and info.value.expected[:2] == b"\x02\x03"
    replay.close()
    with pytest.raises(LinkError):
        replay.command(0x00)


def test_a_reset_where_bytes_are_expected_is_a_mismatch():
    trace = "#pixelpen-trace 1 kind=bus bus=spi url=\n0 C 01 02\n0.1 R\n"
    replay = ReplayBus(parse_bus_trace(io.StringIO(trace)))
    replay.command(0x01)
    with pytest.raises(TraceMismatch, match=r"expected command \(D/C low\) bytes 02, found a reset pulse"):
        replay.reset()


def test_a_hand_written_trace_replays(tmp_path):
    path = tmp_path / "s.trace"
    path.write_text("#pixelpen-trace 1 kind=bus bus=i2c address=0x3d url=ssd1306%3Ai2c%3A1\n"
                    "# init\n\n0.0 C ae d5 80\n0.001 C a8\n0.001 + 3f  # multiplex\n0.002 D FF\n")
    replay = ReplayBus(path)
    assert isinstance(replay, PanelBus)
    assert replay.address == 0x3D and replay.kind == "i2c"
    replay.command(0xAE, 0xD5, 0x80, 0xA8, 0x3F)
    replay.data(b"\xff")
    replay.check_complete()


def test_stream_traces_stay_version_one_traces_and_are_not_bus_traces():
    stream = "#pixelpen-trace 1 url=sim%3A%2F%2Fhp7475a\n0.0 > 49 4e\n"
    assert read_trace(io.StringIO(stream)).sent() == b"IN"
    with pytest.raises(ParseError, match="not a bus trace"):
        read_bus_trace(io.StringIO(stream))


BAD = [
    ("", 1, "empty file"),
    ("#pixelpen-trace 2 kind=bus bus=spi url=\n", 1, "version 2"),
    ("#pixelpen-trace 1 kind=bus url=\n", 1, "bus must be"),
    ("#pixelpen-trace 1 kind=bus bus=usb url=\n", 1, "bus=usb"),
    ("#pixelpen-trace 1 kind=bus bus=spi\n", 1, "lacks url"),
    ("#pixelpen-trace 1 kind=bus bus=spi clock_hz=fast url=\n", 1, "'fast'"),
    ("#pixelpen-trace 1 kind=bus bus=spi max_transfer=0 url=\n", 1, "at least 1"),
    ("#pixelpen-trace 1 kind=bus bus=i2c address=0x80 url=\n", 1, "7-bit"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.1 X 00\n", 2, "'X'"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.1 C\n", 2, "at least one byte"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.1 C 0\n", 2, "odd number"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.1 C zz\n", 2, "'zz'"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.1 R 00\n", 2, "no bytes"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.1 + 00\n", 2, "no C or D frame"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.1 R\n0.2 + 00\n", 3, "no C or D frame"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.2 C 00\n0.1 C 00\n", 3, "backwards"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n-1 C 00\n", 2, "'-1'"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n1e3 C 00\n", 2, "'1e3'"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n" + "9" * 16 + " C 00\n", 2, "15 digits"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.1\n", 2, "cut short"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.1 C 00", 2, "truncated"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.1 D " + "00" * 4097 + "\n", 2, "at most 4096 bytes"),
    ("#pixelpen-trace 1 kind=bus bus=spi url=\n0.1 D " + "00 " * 30000 + "\n", 2, "longer than 65536"),
]


@pytest.mark.parametrize(("text", "line", "words"), BAD)
def test_malformed_traces_name_the_line_and_token(text, line, words):
    with pytest.raises(ParseError) as info:
        read_bus_trace(io.StringIO(text))
    assert info.value.line == line
    assert words in str(info.value)


def test_max_bytes_bounds_what_a_reader_takes():
    text = "#pixelpen-trace 1 kind=bus bus=spi url=\n" + "0 D 00 01 02 03\n" * 4
    assert len(parse_bus_trace(io.StringIO(text), max_bytes=16).stream("D")) == 16
    with pytest.raises(ParseError, match="more than 15 bytes") as info:
        parse_bus_trace(io.StringIO(text), max_bytes=15)
    assert info.value.line == 5


def test_unreadable_and_non_utf8_files(tmp_path):
    with pytest.raises(ParseError, match="cannot read trace"):
        read_bus_trace(tmp_path / "missing.trace")
    bad = tmp_path / "bad.trace"
    bad.write_bytes(b"#pixelpen-trace 1 kind=bus bus=spi url=\n0 C \xff\n")
    with pytest.raises(ParseError, match="UTF-8"):
        read_bus_trace(bad)


def _seeds() -> list[bytes]:
    text, _ = record(mipi_session)
    hand = ("#pixelpen-trace 1 kind=bus bus=i2c address=0x3c clock_hz=400000 max_transfer=32 url=x\n"
            "# comment\n\n0.0 R\n0.1 C ae d5 80  # display off\n0.1 + a8 3f\n0.2 D ff 00\n0.2 + 01\n")
    return [text.encode(), hand.encode()]


def read_and_replay(data: bytes) -> None:
    """The fuzz target: read from a byte stream, replay the trace's own frames, check it is complete."""
    trace = read_bus_trace(io.TextIOWrapper(io.BytesIO(data), encoding="utf-8", newline=""))
    replay = ReplayBus(trace)
    level = ""
    for event in trace.events:
        if event.op == "R":
            replay.reset()
        else:
            level = event.op if event.op != "+" else level
            (replay.command if level == "C" else replay.data)(event.data)
    replay.check_complete()


@depths(3, 4)
def test_bus_trace_reader_fuzz(cases, seed):
    campaign("bus traces", read_and_replay, _seeds(), cases, seed=seed).check()

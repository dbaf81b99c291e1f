"""Traces: the text format, recording a session, replaying it, and refusing malformed files."""

from __future__ import annotations

import io

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.clock import SimulatedClock
from pixelpen.drivers.serial import SerialLink
from pixelpen.drivers.trace import (
    MAX_CHUNK,
    MAX_LINE,
    RecordingLink,
    ReplayLink,
    Trace,
    TraceChunk,
    TraceWriter,
    format_chunk,
    format_header,
    format_line,
    parse_header,
    parse_trace,
    read_trace,
    read_trace_text,
    write_trace,
)
from pixelpen.errors import Disconnected, InvalidArgument, LinkError, LinkTimeout, ParseError, TraceMismatch
from tests.sim.fakes import EchoDevice

HAND_WRITTEN = (
    "#pixelpen-trace 1 url=sim%3A%2F%2Fhp7475a%3Fpaper%3Da4 baudrate=9600 flow=xonxoff\n"
    "# a comment line\n"
    "\n"
    "0.000000 > 49 4E 3b  # IN;\n"
    "0.010000 > 4f493b\n"
    "0.041667 < 37 34 37 35 41 0d  # 7475A.\n"
)


def lines(text: str) -> list[str]:
    return text.splitlines(keepends=True)


def test_hand_written_trace_parses():
    trace = parse_trace(lines(HAND_WRITTEN))
    assert trace.url == "sim://hp7475a?paper=a4"
    assert trace.settings == {"baudrate": "9600", "flow": "xonxoff"}
    assert [(c.time, c.direction, c.data, c.line) for c in trace.chunks] == [
        (0.0, ">", b"IN;", 4),
        (0.01, ">", b"OI;", 5),
        (0.041667, "<", b"7475A\r", 6),
    ]
    assert trace.sent() == b"IN;OI;" and trace.received() == b"7475A\r"


def record_session(path) -> EchoDevice:
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=64)
    with RecordingLink(SerialLink("sim://echo?baud=9600", device=device, timeout=1.0), path) as link:
        link.write(b"IN;\r")
        assert link.read_until(b"\r") == b"OK\r"
        link.write(b"PU0,0;\rPD10,10;\r")
        assert link.read_until(b"\r") == b"OK\r"
        assert link.read_until(b"\r") == b"OK\r"
    return device


def test_record_then_replay_the_same_program(tmp_path):
    path = tmp_path / "session.trace"
    record_session(path)
    trace = read_trace(path)
    assert trace.url == "sim://echo?baud=9600"
    assert trace.settings["baudrate"] == "9600"
    assert trace.sent() == b"IN;\rPU0,0;\rPD10,10;\r"
    assert trace.received() == b"OK\rOK\rOK\r"
    times = [c.time for c in trace.chunks]
    assert times == sorted(times) and times[-1] > 0

    link = ReplayLink(path, timeout=1.0)
    link.write(b"IN;\r")
    assert link.read_until(b"\r") == b"OK\r"
    for byte in b"PU0,0;\rPD10,10;\r":  # different chunking from the recording
        link.write(bytes([byte]))
    assert link.read_until(b"\r") + link.read_until(b"\r") == b"OK\rOK\r"
    link.check_complete()


def test_reply_waits_for_the_bytes_that_preceded_it():
    trace = parse_trace(lines(HAND_WRITTEN))
    link = ReplayLink(trace, timeout=0.5)
    link.write(b"IN;OI")
    assert link.read(10) == b""  # the device answered only after the final ';'
    link.write(b";")
    assert link.read_until(b"\r") == b"7475A\r"


def test_diverging_byte_names_offset_expected_found_and_line():
    link = ReplayLink(parse_trace(lines(HAND_WRITTEN)))
    link.write(b"IN;O")
    with pytest.raises(TraceMismatch) as info:
        link.write(b"X;")
    exc = info.value
    assert exc.offset == 4 and exc.line == 5
    assert exc.expected.startswith(b"I;") and exc.found == b"X;"
    assert "byte offset 4" in str(exc) and "line 5" in str(exc)


def test_sending_past_the_end_of_the_trace_is_a_mismatch():
    link = ReplayLink(parse_trace(lines(HAND_WRITTEN)))
    link.write(b"IN;OI;")
    with pytest.raises(TraceMismatch, match="more than the trace holds") as info:
        link.write(b"SP1;")
    assert info.value.offset == 6


def test_check_complete_reports_a_program_that_stopped_early():
    link = ReplayLink(parse_trace(lines(HAND_WRITTEN)))
    link.write(b"IN;")
    with pytest.raises(TraceMismatch, match="stopped after 3 of 6") as info:
        link.check_complete()
    assert info.value.line == 5


def test_replay_timeouts_pass_in_simulated_time():
    link = ReplayLink(parse_trace(lines(HAND_WRITTEN)), timeout=30.0)
    with pytest.raises(LinkTimeout):
        link.read_until(b"\r")
    assert link.clock.now() == pytest.approx(30.0)


def test_recording_flushes_every_chunk_before_close(tmp_path):
    path = tmp_path / "live.trace"
    clock = SimulatedClock()
    link = RecordingLink(SerialLink("sim://echo", device=EchoDevice(clock), timeout=1.0), path)
    link.write(b"IN;\r")
    on_disk = path.read_text()
    assert "> 49 4e 3b 0d" in on_disk and on_disk.endswith("\n")
    link.close()
    link.close()


def test_recording_notes_a_failed_operation(tmp_path):
    path = tmp_path / "fail.trace"
    clock = SimulatedClock()
    device = EchoDevice(clock, buffer_size=100)
    link = RecordingLink(SerialLink("sim://echo?drop_after=2", device=device, timeout=1.0), path)
    link.write(b"abcdef")
    with pytest.raises(Disconnected):
        link.read_until(b"\r")
    text = path.read_text()
    assert "# error during read: Disconnected" in text
    read_trace(path)  # the comment keeps the file valid


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(st.sampled_from(">>><"), st.binary(min_size=1, max_size=3 * MAX_CHUNK // 2)),
        max_size=8,
    ),
    st.dictionaries(
        st.from_regex(r"[a-z][a-z0-9_]{0,8}", fullmatch=True).filter(lambda k: k != "url"),
        st.text(max_size=12),
        max_size=3,
    ),
    st.text(max_size=30),
)
def test_write_then_read_gives_the_same_streams(chunks, settings_, url):
    trace = Trace(url, settings_, [TraceChunk(i * 0.001, d, data) for i, (d, data) in enumerate(chunks)])
    buf = io.StringIO()
    write_trace(trace, buf)
    back = parse_trace(lines(buf.getvalue()))
    assert back.url == url and back.settings == settings_
    assert back.sent() == trace.sent() and back.received() == trace.received()
    assert all(len(c.data) <= MAX_CHUNK for c in back.chunks)


HEADER = "#pixelpen-trace 1 url=\n"


@pytest.mark.parametrize(
    "text, line, word",
    [
        ("", 1, "empty"),
        ("0.0 > 41\n", 1, "header"),
        ("#pixelpen-trace\n", 1, "version"),
        ("#pixelpen-trace 2 url=\n", 1, "version 2"),
        ("#pixelpen-trace 1 baudrate=9600\n", 1, "url"),
        ("#pixelpen-trace 1 url= flow\n", 1, "key=value"),
        ("#pixelpen-trace 1 url= a=1 a=2\n", 1, "twice"),
        (HEADER + "0.0 ^ 41\n", 2, "direction"),
        (HEADER + "0.0 > 4\n", 2, "odd number"),
        (HEADER + "0.0 > zz\n", 2, "hexadecimal"),
        (HEADER + "0.0 >\n", 2, "SECONDS"),
        (HEADER + "-1 > 41\n", 2, "non-negative"),
        (HEADER + "nan > 41\n", 2, "non-negative"),
        (HEADER + "inf > 41\n", 2, "non-negative"),
        (HEADER + "1e3 > 41\n", 2, "decimal"),
        (HEADER + "1.0 > 41\n0.5 < 42\n", 3, "backwards"),
        (HEADER + "0.0 > 41 4", 2, "odd number"),
        (HEADER + "0.0 > 41", 2, "truncated"),
    ],
)
def test_malformed_and_truncated_traces(text, line, word):
    with pytest.raises(ParseError, match=word) as info:
        parse_trace(lines(text), "t.trace")
    assert info.value.line == line and info.value.source == "t.trace"


def test_oversized_trace_is_refused():
    text = HEADER + "".join(f"0.0 > {'41' * 100}\n" for _ in range(11))
    with pytest.raises(ParseError, match="more than 1000 bytes") as info:
        parse_trace(lines(text), max_bytes=1000)
    assert info.value.line == 12


def test_overlong_line_is_refused_without_reading_it_whole():
    text = HEADER + "0.0 > " + "41" * MAX_LINE + "\n"
    with pytest.raises(ParseError, match="longer than") as info:
        read_trace(io.StringIO(text))
    assert info.value.line == 2


def test_non_utf8_file_is_a_parse_error(tmp_path):
    path = tmp_path / "bad.trace"
    path.write_bytes(HEADER.encode() + b"0.0 > 41  # \xff\xfe\n")
    with pytest.raises(ParseError, match="UTF-8"):
        read_trace(path)


def test_header_refuses_bad_setting_names():
    with pytest.raises(ValueError):
        format_header("x", {"has space": 1})


@pytest.mark.parametrize("text, line, word", [
    ("#pixelpen-trace \u00b2 url=\n", 1, "version"),  # '²'.isdigit() is True, int('²') raises ValueError
    ("#pixelpen-trace \u0661 url=\n", 1, "version"),  # Arabic-Indic digit one: int() reads it as 1
    ("#pixelpen-trace 1 url=\n" + "9" * 400 + " > 41\n", 2, "timestamp"),  # float() of it is inf
    ("#pixelpen-trace 1 url=\n" + "1" * 16 + ".5 > 41\n", 2, "at most 15 digits"),
])
def test_non_ascii_versions_and_endless_timestamps_are_refused(text, line, word):
    with pytest.raises(ParseError, match=word) as info:
        parse_trace(lines(text))
    assert info.value.line == line


def test_a_long_fraction_is_still_a_finite_time():
    trace = parse_trace(lines("#pixelpen-trace 1 url=\n0." + "9" * 400 + " > 41\n"))
    assert trace.chunks[0].time == 1.0


def test_unreadable_trace_files_are_parse_errors(tmp_path):
    with pytest.raises(ParseError, match="NUL"):
        read_trace("a\x00b.trace")
    with pytest.raises(ParseError, match="cannot read trace"):
        read_trace(tmp_path / "missing.trace")
    with pytest.raises(ParseError, match="UTF-8"):  # an open binary-backed stream, not only a path
        read_trace(io.TextIOWrapper(io.BytesIO(b"#pixelpen-trace 1 url=\n0.0 > \xff\n"), encoding="utf-8"))


def test_a_trace_file_name_no_file_system_takes_is_refused_before_opening(tmp_path):
    from pixelpen.errors import ConfigError

    with pytest.raises(ConfigError, match=r"trace file.*NUL"):
        TraceWriter(str(tmp_path / "a\x00b"), "sim://x")
    with pytest.raises(ConfigError, match=r"trace file.*255"):
        TraceWriter(tmp_path / ("x" * 300), "sim://x")


BUS_TRACE = "#pixelpen-trace 1 url=st7789%3Aspi%3A0.0 kind=bus bus=spi clock_hz=62500000\n0.000000 R\n0.1 C 01\n"


def test_a_bus_trace_is_refused_with_a_pointer_to_the_bus_reader(tmp_path):
    path = tmp_path / "panel.trace"
    path.write_text(BUS_TRACE)
    for source in (path, io.StringIO(BUS_TRACE)):
        with pytest.raises(ParseError, match=r"kind=bus.*pixelpen\.drivers\.bustrace\.read_bus_trace") as info:
            read_trace(source)
        assert info.value.line == 1  # refused at the header, not at the first 'R' line
    with pytest.raises(ParseError, match="read_bus_trace"):
        parse_trace(lines(BUS_TRACE))


def test_parse_header_reads_the_settings_of_any_kind():
    header = parse_header("#pixelpen-trace 1 url=st7789%3Aspi%3A0.0 kind=bus bus=spi", "h.trace")
    assert header.url == "st7789:spi:0.0" and header.settings == {"kind": "bus", "bus": "spi"}
    assert header.chunks == [] and header.source == "h.trace"


def test_read_trace_text_hands_the_lines_and_the_name_to_the_parser(tmp_path):
    path = tmp_path / "any.txt"
    path.write_text("one\ntwo\n")
    assert read_trace_text(path, lambda got, name: (list(got), name)) == (["one\n", "two\n"], str(path))
    assert read_trace_text(io.StringIO("x" * (MAX_LINE + 5)), lambda got, _: [len(t) for t in got]) == [MAX_LINE + 1, 4]
    with pytest.raises(ParseError, match="cannot read trace"):
        read_trace_text(tmp_path / "missing", lambda got, _: list(got))


def test_trace_writer_line_appends_lines_as_they_are_and_refuses_newlines():
    out = io.StringIO()
    writer = TraceWriter(out, "sim://x")
    writer.line("0.000000 R")
    with pytest.raises(InvalidArgument, match="no newline"):
        writer.line("0.1 C 01\n0.2 C 02")
    writer.close()
    assert out.getvalue() == "#pixelpen-trace 1 url=sim%3A%2F%2Fx\n0.000000 R\n"
    with pytest.raises(LinkError, match="closed"):
        writer.line("0.2 R")


def test_format_line_and_long_chunks_split_at_4096_bytes():
    assert format_line(0.25, "R") == "0.250000 R"  # no bytes: no trailing space
    assert format_line(-1.0, "C", b"\x2a\x00") == "0.000000 C 2a 00"  # a clock that went back stamps 0
    lines_ = format_chunk(2.5, ">", b"A" * 4096 + b"BC")
    assert lines_ == ["2.500000 > " + " ".join(["41"] * 4096) + "  # " + "A" * 4096, "2.500000 > 42 43  # BC"]

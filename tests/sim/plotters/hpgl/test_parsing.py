"""HP-GL and device-control syntax readers: the manual's syntax rules, streaming, malformed and oversized input."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pixelpen.sim.plotters.hpgl.parsing import (
    SYNTAX,
    DeviceControl,
    DeviceControlReader,
    InstructionReader,
    parse_hpgl,
)


def summary(data: bytes) -> list[tuple[str, tuple[float, ...], str, int]]:
    return [(i.mnemonic, i.params, i.text, i.error) for i in parse_hpgl(data)]


def test_producer_stream_without_separators():
    # plotters.md §1.3: MS-Windows drivers omit separators; the first letter of a mnemonic ends the previous one
    assert summary(b"INCA2IP0,0,10300,7650DI0,1SP2") == [
        ("IN", (), "", 0),
        ("CA", (2.0,), "", 0),
        ("IP", (0.0, 0.0, 10300.0, 7650.0), "", 0),
        ("DI", (0.0, 1.0), "", 0),
        ("SP", (2.0,), "", 0),
    ]


def test_semicolons_spaces_case_and_signs_are_separators():
    # 7470A manual p. 1-6: commas, spaces or a +/- sign separate parameters; mnemonics upper or lower case
    with_semicolons = summary(b"IN;SP1;PA100,200;PD300,400;")
    assert summary(b"in sp1 pa100 200 pd 300 , 400;") == with_semicolons
    assert summary(b"PA10-20+30-40;") == [("PA", (10.0, -20.0), "", 0), ("PA", (30.0, -40.0), "", 0)]
    assert summary(b"SI.5,1.25;") == [("SI", (0.5, 1.25), "", 0)]


def test_coordinate_lists_arrive_one_pair_at_a_time():
    assert summary(b"PD1,2,3,4,5,6;PU;") == [
        ("PD", (1.0, 2.0), "", 0), ("PD", (3.0, 4.0), "", 0), ("PD", (5.0, 6.0), "", 0), ("PU", (), "", 0),
    ]


def test_odd_coordinate_count_is_error_2_after_the_complete_pairs():
    # 7470A manual, PU/PD: "An odd number of parameters will set an error condition, but all X,Y pairs
    # which precede the unmatched parameter will be plotted."
    assert summary(b"PD1,2,3;") == [("PD", (1.0, 2.0), "", 0), ("PD", (3.0,), "", 2)]


def test_label_runs_to_etx_and_dt_changes_the_terminator():
    assert summary(b"LBHello, world;\x03PA1,2;") == [("LB", (), "Hello, world;", 0), ("PA", (1.0, 2.0), "", 0)]
    assert summary(b"DT#LBab#LBc\x03#") == [("DT", (), "#", 0), ("LB", (), "ab", 0), ("LB", (), "c\x03", 0)]
    # DT; restores ETX
    assert summary(b"DT#;DT;LBx\x03") == [("DT", (), "#", 0), ("DT", (), "", 0), ("LB", (), "x", 0)]


def test_unknown_mnemonic_is_error_1_and_its_parameters_are_skipped():
    assert summary(b"ZZ12,34;SP1;") == [("ZZ", (), "", 1), ("SP", (1.0,), "", 0)]
    assert summary(b"QQ5PA1,2") == [("QQ", (), "", 1), ("PA", (1.0, 2.0), "", 0)]


def test_model_instruction_sets_decide_what_is_unknown():
    assert parse_hpgl(b"OT;", known={"OI"})[0].error == 1
    assert parse_hpgl(b"OT;", known={"OT"})[0].error == 0
    # recognised-but-unsimulated mnemonics are read (not error 1) with their parameters
    assert summary(b"OT;") == [("OT", (), "", 0)]
    items = parse_hpgl(b"PG1;SP1;", known={"SP"}, recognised={"PG"})
    assert [(i.mnemonic, i.error) for i in items] == [("PG", 0), ("SP", 0)]


def test_wrong_parameter_count_and_illegal_characters():
    assert summary(b"SP1,2;")[0][3] == 2
    assert summary(b"SC1,2,3,4,5;")[0][3] == 2
    assert summary(b"PA10,#;SP1;") == [("PA", (), "", 1), ("SP", (1.0,), "", 0)]
    assert summary(b"\x7fSP1;")[0][3] == 1
    assert summary(b"P1SP2;")[0][3] == 1


def test_instruction_without_parameters_executes_without_terminator():
    reader = InstructionReader(SYNTAX)
    n, item = reader.read(b"OS")
    assert (n, item.mnemonic, item.error) == (2, "OS", 0)


def test_incomplete_instruction_waits_then_is_refused_when_the_buffer_is_full():
    reader = InstructionReader(SYNTAX)
    assert reader.read(b"PA10,2") == (0, None)  # "2" may continue
    assert reader.read(b"SC1,2,3") == (0, None)
    n, item = reader.read(b"SC1,2,3", full=True)
    assert n == 7 and item.error == 3


def test_number_longer_than_any_plotter_accepts_is_error_3():
    items = parse_hpgl(b"PA" + b"1" * 40 + b",5;SP1;")
    assert items[0].error == 3 and (items[-1].mnemonic, items[-1].params) == ("SP", (1.0,))


def test_offsets_point_at_each_instruction():
    items = parse_hpgl(b"IN;  SP1;ZZ;")
    assert [(i.mnemonic, i.offset) for i in items] == [("IN", 0), ("SP", 5), ("ZZ", 9)]


valid_instruction = st.one_of(
    st.sampled_from([b"IN;", b"DF;", b"SP1;", b"PU;", b"PD;", b"OS;", b"OI;", b"SC;", b"LT;", b"CI50;"]),
    st.builds(lambda a, b: b"PA%d,%d;" % (a, b), st.integers(-3000, 3000), st.integers(-3000, 3000)),
    st.builds(lambda xs: b"PD" + b",".join(b"%d" % x for x in xs) + b";",
              st.lists(st.integers(-99, 99), min_size=2, max_size=8).filter(lambda v: len(v) % 2 == 0)),
    st.builds(lambda t: b"LB" + t + b"\x03", st.text("ABCxyz 012,;.", max_size=12).map(str.encode)),
)


@settings(max_examples=60, deadline=None)
@given(st.lists(valid_instruction, min_size=1, max_size=12), st.data())
def test_any_chunking_reads_the_same_instructions(parts, data):
    stream = b"".join(parts)
    whole = summary(stream)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=6)))
    reader = InstructionReader(SYNTAX)
    buf = bytearray()
    got: list[tuple[str, tuple[float, ...], str, int]] = []

    def take(full: bool) -> bool:
        continuing = reader.in_label  # a later run of the same label's text
        n, item = reader.read(buf, full=full)
        if n == 0 and item is None:
            return False
        del buf[:n]
        if item is not None:
            if continuing and item.mnemonic == "LB" and got and got[-1][0] == "LB":
                m = got.pop()
                got.append((m[0], m[1], m[2] + item.text, m[3]))
            else:
                got.append((item.mnemonic, item.params, item.text, item.error))
        return True

    for a, b in zip([0, *cuts], [*cuts, len(stream)], strict=True):
        buf += stream[a:b]
        while take(False):
            pass
    while buf:  # what a complete stream leaves: an instruction ended only by the end of data
        take(True)
    assert got == whole


@settings(max_examples=150, deadline=None)
@given(st.binary(max_size=300))
def test_random_bytes_never_raise_and_always_progress(data):
    reader = InstructionReader(SYNTAX)
    buf = bytearray(data)
    steps = 0
    while buf:
        n, item = reader.read(buf, full=True)
        assert n > 0 or item is not None
        assert n <= len(buf)
        del buf[:n]
        if item is not None:
            assert item.error in (0, 1, 2, 3)
        steps += 1
        assert steps <= len(data) + 1


# -- device control ---------------------------------------------------------------------------


def feed_all(data: bytes) -> list[tuple[DeviceControl | None, bool]]:
    reader = DeviceControlReader()
    out = []
    for b in data:
        if not reader.active:
            assert b == 0x1B, "test streams start every sequence with ESC"
            reader.start()
            continue
        out.append(reader.feed(b))
    return out


def last_sequence(data: bytes) -> DeviceControl:
    seqs = [s for s, _ in feed_all(data) if s is not None]
    assert len(seqs) == 1
    return seqs[0]


def test_the_real_preamble_reads_as_the_manual_describes():
    # plotters.md §1.5: ESC.(;ESC.I81;;17:ESC.N;19:  -> on; Xoff threshold 81, no ENQ, Xon DC1; Xoff DC3
    assert last_sequence(b"\x1b.(") == DeviceControl("(")
    assert last_sequence(b"\x1b.I81;;17:") == DeviceControl("I", (81, None, 17))
    assert last_sequence(b"\x1b.N;19:") == DeviceControl("N", (None, 19))
    assert last_sequence(b"\x1b.@;1:") == DeviceControl("@", (None, 1))
    assert last_sequence(b"\x1b.M:") == DeviceControl("M", ())
    assert str(DeviceControl("I", (81, None, 17))) == "ESC.I81;;17:"


def test_device_control_errors():
    assert last_sequence(b"\x1b.X").error == 11  # ESC.E 11: bad byte after ESC .
    results = feed_all(b"\x1b.M100;A")
    seq, reprocess = results[-1]
    assert seq == DeviceControl("M", (100,), 12) and reprocess  # 12: bad byte, rest defaulted; 'A' is data
    assert last_sequence(b"\x1b.@1;2;3:").error == 14  # 14: too many parameters, extras ignored
    assert last_sequence(b"\x1b.@1;2;3:").params == (1, 2)


def test_esc_not_followed_by_dot_is_data():
    (seq, reprocess), = feed_all(b"\x1bA")
    assert seq is None and reprocess


@settings(max_examples=100, deadline=None)
@given(st.binary(max_size=60))
def test_device_control_reader_survives_random_bytes(data):
    reader = DeviceControlReader()
    reader.start()
    for b in data:
        if not reader.active:
            reader.start()
        seq, _ = reader.feed(b)
        if seq is not None:
            assert seq.error in (0, 11, 12, 14)
            assert all(p is None or p >= 0 for p in seq.params)


@pytest.mark.parametrize("mnemonic", sorted(SYNTAX))
def test_every_known_mnemonic_reads_with_a_terminator(mnemonic):
    kind = SYNTAX[mnemonic].kind.value
    data = mnemonic.encode() + {"label": b"x\x03", "char": b"#;"}.get(kind, b";")
    items = parse_hpgl(data)
    assert items and items[0].mnemonic == mnemonic and items[0].error == 0

"""The parser's item loop: its prefix tables, the alternative-set tables of a delimiter, the report records it
keeps and the ReportDescriptor it makes itself, each checked against an independent reading of the bytes."""

from __future__ import annotations

import pytest

from pixelpen.devices.hid import descriptor as hid_descriptor
from pixelpen.devices.hid.fields import ReportDescriptor, ReportKind
from pixelpen.devices.hid.items import ITEM_NAMES, MAIN, s32, scan, tokenize
from pixelpen.errors import ParseError
from tests.devices.hid.test_descriptor import APP, END, X, Y, error_of, one_field, parse

IN, OUT, FEAT = ReportKind.INPUT, ReportKind.OUTPUT, ReportKind.FEATURE
VAR8 = [0x15, 0x00, 0x25, 0x01, 0x75, 0x08, 0x95, 0x01]  # 0..1, 8 bits, one element


def test_the_prefix_tables_agree_with_the_item_names():
    """Every one-data-byte prefix reads its branch at once; every other short one through the wide table, and
    both tables name the same branch as the HID item type and tag do."""
    branch_of_name = {"Usage": hid_descriptor._USAGE, "Report Count": hid_descriptor._COUNT,
                      "Input": hid_descriptor._FIELD, "Output": hid_descriptor._FIELD,
                      "Feature": hid_descriptor._FIELD, "Collection": hid_descriptor._COLLECTION,
                      "End Collection": hid_descriptor._END, "Usage Page": hid_descriptor._PAGE}
    for prefix in range(256):
        wide = hid_descriptor._WIDE_OPS[prefix]
        first = hid_descriptor._OPS[prefix]
        if prefix >= 0xF0:
            assert first == wide == hid_descriptor._LONG
            continue
        assert first == (wide if prefix & 3 == 1 else hid_descriptor._WIDE)
        name = ITEM_NAMES.get(((prefix >> 2) & 3, prefix >> 4))
        if name in branch_of_name and prefix != 0x0B:
            assert wide == branch_of_name[name], hex(prefix)
        if (prefix >> 2) & 3 == MAIN and wide == hid_descriptor._FIELD:
            assert hid_descriptor._KINDS[prefix] is {8: IN, 9: OUT, 11: FEAT}[prefix >> 4]


@pytest.mark.parametrize("usage", [[0x08], [0x09, 0x35], [0x0A, 0x35, 0x00], [0x0B, 0x35, 0x00, 0x01, 0x00],
                                   [0x19, 0x35, 0x29, 0x36], [0x1A, 0x35, 0x00, 0x2A, 0x36, 0x00]])
def test_usages_of_any_size_in_a_second_alternative_set_are_ignored_until_the_main_item(usage):
    body = [0x09, 0x30, 0xA9, 0x01, 0x09, 0x31, 0xA9, 0x00, 0xA9, 0x01, *usage, 0xA9, 0x00]
    d = parse(APP, VAR8, [0x95, 0x02], body, [0x81, 0x02], [0x09, 0x32, 0x81, 0x02], END)
    first, second = d.input_reports[None]
    assert first.usages == (X, Y)                 # the second set (any item size) was ignored
    assert second.usages == (0x00010032,) * 2     # the tables are the plain ones again after the Main item


@pytest.mark.parametrize("items, lo, hi, error", [
    # a 4-byte maximum read unsigned (the minimum was 0), then a negative minimum: compared as an s32
    ([0x15, 0x00, 0x27, 0x00, 0x00, 0x00, 0x80, 0x15, 0xFF], -1, s32(0x80000000), True),
    ([0x15, 0x00, 0x27, 0xFF, 0xFF, 0xFF, 0x7F, 0x15, 0xFF], -1, 0x7FFFFFFF, False),
    # a maximum read signed (the minimum was negative), then a minimum of 0: compared unsigned
    ([0x15, 0xFF, 0x25, 0xFF, 0x15, 0x00], 0, 0xFFFFFFFF, False),
    ([0x15, 0xFF, 0x25, 0xFE, 0x15, 0x00], 0, 0xFFFFFFFE, False),
])
def test_the_logical_range_is_compared_as_the_kernel_stores_it(items, lo, hi, error):
    body = [*items, 0x09, 0x30, 0x75, 0x20, 0x95, 0x01]
    if error:
        err = error_of(APP, body, [0x81, 0x02], END)
        assert err.offset == len(APP) + len(body)
        assert err.message == f"Logical Maximum {hi} is below Logical Minimum {lo}"
    else:
        f = one_field(body, [0x81, 0x02])
        assert (f.logical_min, f.logical_max) == (lo, hi)


@pytest.mark.parametrize("items, pmin, pmax", [
    ([0x35, 0x00, 0x47, 0x00, 0x00, 0x00, 0x80, 0x35, 0xFF], -1, s32(0x80000000)),
    ([0x35, 0xFF, 0x45, 0xFE, 0x35, 0x00], 0, 0xFFFFFFFE),
])
def test_the_physical_maximum_is_kept_as_the_kernel_stores_it(items, pmin, pmax):
    f = one_field(VAR8, items, [0x09, 0x30, 0x81, 0x02])
    assert (f.physical_min, f.physical_max) == (pmin, pmax)


def test_padding_does_not_count_towards_the_kernels_256_fields():
    body = [0x09, 0x30, 0x81, 0x02, 0x81, 0x03] * 300   # a field with a usage, then padding, 300 times
    d = parse(APP, [0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01], body, END)
    fields = d.input_reports[None]
    assert sum(1 for f in fields if f.usages) == 256 and sum(1 for f in fields if not f.usages) == 300
    assert sum("dropped" in w for w in d.warnings) == 44
    assert d.layout(IN, None).length == 600 // 8   # every field's bits count, kept or dropped


# Reports first named in an interleaved order: feature 2, input 1, output 1, input 2, then input 1 again.
ORDER = bytes([*APP, *VAR8, 0x85, 0x02, 0x09, 0x30, 0xB1, 0x02, 0x85, 0x01, 0x09, 0x31, 0x81, 0x02,
               0x09, 0x32, 0x91, 0x02, 0x85, 0x02, 0x09, 0x33, 0x81, 0x02, 0x85, 0x01, 0x09, 0x34, 0x81, 0x02, *END])


@pytest.mark.parametrize("data", [ORDER, bytes([*APP, *VAR8, 0x09, 0x30, 0x81, 0x02, 0x85, 0x03, 0x09, 0x31,
                                                0x81, 0x02, 0x09, 0x32, 0xB1, 0x02, *END])])
def test_reports_are_listed_in_the_order_the_descriptor_first_names_them(data):
    """The order and the fields of the reports against one read from the items themselves (tokenize)."""
    order: list[tuple[ReportKind, int | None]] = []
    usages: dict[tuple[ReportKind, int | None], list[int]] = {}
    rid: int | None = None
    pending: list[int] = []
    for it in tokenize(data):
        if it.name == "Report ID":
            rid = it.value
        elif it.name == "Usage":
            pending.append(0x00010000 | it.value)
        elif it.name in ("Input", "Output", "Feature"):
            kind = {"Input": IN, "Output": OUT, "Feature": FEAT}[it.name]
            key = (kind, rid)
            if key not in usages:
                order.append(key)
                usages[key] = []
            usages[key] += pending
            pending = []
        elif it.type == MAIN:  # a collection takes the usages before it
            pending = []
    numbered = {kind for kind, r in order if r is not None}
    order = [(kind, 0 if r is None and kind in numbered else r) for kind, r in order]
    d = parse_descriptor_of(data)
    assert list(d.layouts) == order
    for kind, space in ((IN, d.input_reports), (OUT, d.output_reports), (FEAT, d.feature_reports)):
        assert list(space) == [r for k, r in order if k is kind]
        for r, fields in space.items():
            assert [u for f in fields for u in f.usages] == usages[kind, None if r == 0 else r]
            assert fields == list(d.layouts[kind, r].fields)
            assert all(f is g for f, g in zip(fields, d.layouts[kind, r].fields, strict=True))


def parse_descriptor_of(data: bytes) -> ReportDescriptor:
    """The parser's descriptor, checked to equal one the public constructor makes of its layouts."""
    d = hid_descriptor.parse_descriptor(data)
    spaces = (d.input_reports, d.output_reports, d.feature_reports)
    public = ReportDescriptor(data, list(d.layouts.values()), d.collections, d.warnings)
    assert (public.input_reports, public.output_reports, public.feature_reports) == spaces
    assert (public.numbered, public.numbered_kinds) == (d.numbered, d.numbered_kinds)
    return d


def test_a_report_0_beside_numbered_ones_keeps_its_place_and_the_other_spaces_are_untouched():
    data = bytes([*APP, *VAR8, 0x09, 0x30, 0x81, 0x02, 0x09, 0x31, 0xB1, 0x02, 0x85, 0x05, 0x09, 0x32, 0x81, 0x02,
                  0x85, 0x01, 0x09, 0x33, 0x81, 0x02, *END])
    d = parse_descriptor_of(data)
    assert list(d.input_reports) == [0, 5, 1] and list(d.feature_reports) == [None]
    assert [f.bit_offset for f in d.input_reports[0]] == [8]      # read with an ID byte 0
    assert d.input_reports[0][0].report_id == 0 and d.feature_reports[None][0].bit_offset == 0
    assert d.numbered_kinds == {IN} and d.decode(b"\x00\x01") == {(1, 0x30): 1}


def test_an_error_after_an_item_cut_short_later_names_the_cut_item():
    """The loop reads past the end from its zero padding; the truncation found by scan is raised first."""
    data = bytes([*APP, 0x15, 0x05, 0x25, 0x01, 0x09, 0x30, 0x81, 0x02, 0x27, 0x01])
    with pytest.raises(ParseError) as err:
        scan(data)
    assert error_of(list(data)).message == err.value.message

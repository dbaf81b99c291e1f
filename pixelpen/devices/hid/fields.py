"""What a parsed HID report descriptor holds: fields, collections, and the three report spaces.

A :class:`Field` is one Input/Output/Feature main item as the kernel's ``hid_field`` sees it:
``count`` elements of ``bit_size`` bits starting at ``bit_offset``, counted from the first bit of
the report as read from the device (the report-ID byte included when the descriptor numbers its
reports).  Usages are full 32-bit values, ``page << 16 | id``.  The parser
(:mod:`pixelpen.devices.hid.descriptor`) builds these; the codec (:mod:`pixelpen.devices.hid.codec`)
compiles them into decoders and encoders.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from pixelpen.errors import InvalidArgumentType, ParseError

if TYPE_CHECKING:
    from pixelpen.devices.hid.codec import ReportDecoder, ReportEncoder  # codec imports this module

MAIN_CONSTANT = 0x001
MAIN_VARIABLE = 0x002
MAIN_RELATIVE = 0x004
MAIN_WRAP = 0x008
MAIN_NONLINEAR = 0x010
MAIN_NO_PREFERRED = 0x020
MAIN_NULL_STATE = 0x040
MAIN_VOLATILE = 0x080
MAIN_BUFFERED_BYTES = 0x100
"""The data bits of an Input/Output/Feature item (HID 1.11 §6.2.2.5); Volatile is not defined for Input."""


class ReportKind(enum.Enum):
    """The three report spaces; report IDs are numbered separately in each."""

    INPUT = "input"
    OUTPUT = "output"
    FEATURE = "feature"

    __hash__ = object.__hash__  # members are singletons: Enum's hash of the name is a Python call per dict lookup


_INPUT, _OUTPUT, _FEATURE = ReportKind


class CollectionKind(enum.IntEnum):
    """The Collection item's type byte (HID 1.11 §6.2.2.6); 0x80..0xFF are vendor-defined."""

    PHYSICAL = 0
    APPLICATION = 1
    LOGICAL = 2
    REPORT = 3
    NAMED_ARRAY = 4
    USAGE_SWITCH = 5
    USAGE_MODIFIER = 6


# Collection, Field and ReportLayout are read-only by contract but not frozen: a frozen dataclass's __init__ costs
# ~4x more, and the parser builds one per main item and per report.
@dataclass(slots=True, eq=True, unsafe_hash=True)
class Collection:
    """A Collection ... End Collection: its type byte, its usage, where it starts, and its parent (read-only)."""

    kind: int
    usage: int
    offset: int
    parent: Collection | None = None

    @property
    def usage_page(self) -> int:
        """The page of the collection's usage."""
        return self.usage >> 16

    @property
    def application(self) -> Collection:
        """The outermost collection this one is inside (itself when it has no parent)."""
        node = self
        while node.parent is not None:
            node = node.parent
        return node


@dataclass(slots=True, eq=True, unsafe_hash=True)
class Field:
    """One main item: ``count`` elements of ``bit_size`` bits at ``bit_offset`` in its report (read-only)."""

    kind: ReportKind
    report_id: int | None
    usage_page: int
    usages: tuple[int, ...]
    bit_offset: int
    bit_size: int
    count: int
    logical_min: int
    logical_max: int
    physical_min: int
    physical_max: int
    unit: int
    unit_exponent: int
    flags: int
    collection: Collection | None = None
    offset: int = 0
    """Byte offset in the descriptor of the main item that made this field."""
    extra: dict[str, object] = field(default_factory=dict, compare=False, hash=False)
    """Local items kept for the dump (designators, strings, delimiters), by name."""

    @property
    def is_constant(self) -> bool:
        """Padding or a constant value (data bit 0)."""
        return bool(self.flags & MAIN_CONSTANT)

    @property
    def is_array(self) -> bool:
        """An array: each element reports one of ``usages`` by index (data bit 1 clear)."""
        return not self.flags & MAIN_VARIABLE

    @property
    def is_relative(self) -> bool:
        """Values are changes since the last report (data bit 2)."""
        return bool(self.flags & MAIN_RELATIVE)

    @property
    def has_null_state(self) -> bool:
        """Out-of-range values mean "no value" (data bit 6; a hat switch's centre)."""
        return bool(self.flags & MAIN_NULL_STATE)

    @property
    def is_signed(self) -> bool:
        """Elements are two's complement (the kernel's rule: when the logical minimum is negative)."""
        return self.logical_min < 0

    @property
    def bit_end(self) -> int:
        """The first bit after the field."""
        return self.bit_offset + self.bit_size * self.count

    def usage_ids(self) -> tuple[tuple[int, int], ...]:
        """``(usage_page, usage_id)`` per element (for an array, per usage it can report)."""
        return tuple((u >> 16, u & 0xFFFF) for u in self.usages)


@dataclass(slots=True, eq=True, unsafe_hash=True)
class ReportLayout:
    """One report of one kind: its ID (None when unnumbered), its fields and its length in bytes (read-only)."""

    kind: ReportKind
    report_id: int | None
    fields: tuple[Field, ...]
    length: int
    """Bytes on the wire, the ID byte included when numbered (the last field's end rounded up)."""


Values = dict[tuple[int, int], "int | list[int]"]
"""A decoded report: ``(usage_page, usage_id)`` -> logical value (a list where a usage repeats)."""


_T = TypeVar("_T")


class _Once(Generic[_T]):
    """A method run on the first read of its attribute, its result then stored as the attribute itself
    (``functools.cached_property`` without the lock that Python 3.11 takes on every first read)."""

    def __init__(self, function: Callable[[Any], _T]) -> None:
        self.function = function
        self.name = function.__name__
        self.__doc__ = function.__doc__

    def __get__(self, instance: object, owner: type | None = None) -> _T:
        if instance is None:
            return self  # type: ignore[return-value]  # the class's attribute: this descriptor, for help()
        value = instance.__dict__[self.name] = self.function(instance)
        return value


class ReportDescriptor:
    """A parsed report descriptor: the input, output and feature reports and their fields."""

    # slots, set by both constructors; __dict__ holds the codec's caches, made on first use
    __slots__ = ("__dict__", "collections", "data", "feature_reports", "input_reports", "layouts", "numbered",
                 "numbered_kinds", "output_reports", "warnings")

    data: bytes
    collections: tuple[Collection, ...]
    layouts: dict[tuple[ReportKind, int | None], ReportLayout]
    """Every report's layout by (kind, report ID), in the order the descriptor first names them."""
    warnings: tuple[str, ...]
    input_reports: dict[int | None, list[Field]]
    """The input reports' fields by report ID (None when the space does not number its reports)."""
    output_reports: dict[int | None, list[Field]]
    """The output reports' fields by report ID."""
    feature_reports: dict[int | None, list[Field]]
    """The feature reports' fields by report ID."""
    numbered_kinds: frozenset[ReportKind]
    """The report spaces whose reports start with an ID byte (the kernel numbers each space on its own)."""
    numbered: bool
    """Whether any report starts with a report-ID byte (the descriptor has a Report ID item)."""

    def __init__(self, data: bytes, layouts: Sequence[ReportLayout], collections: tuple[Collection, ...],
                 warnings: tuple[str, ...] = ()) -> None:
        """A descriptor of the reports ``layouts`` (the parser makes its own with :meth:`parsed`)."""
        self.data = bytes(data)
        self.collections = collections
        self.warnings = warnings
        self.layouts = {(r.kind, r.report_id): r for r in layouts}
        spaces: dict[ReportKind, dict[int | None, list[Field]]] = {_INPUT: {}, _OUTPUT: {}, _FEATURE: {}}
        for r in layouts:
            spaces[r.kind][r.report_id] = list(r.fields)
        self.input_reports, self.output_reports, self.feature_reports = spaces.values()
        self.numbered_kinds = frozenset(r.kind for r in layouts if r.report_id is not None)
        self.numbered = bool(self.numbered_kinds)

    @classmethod
    def parsed(cls, data: bytes, spaces: Mapping[ReportKind, dict[int | None, list[Field]]],
               layouts: dict[tuple[ReportKind, int | None], ReportLayout], collections: tuple[Collection, ...],
               warnings: tuple[str, ...], numbered_kinds: frozenset[ReportKind]) -> ReportDescriptor:
        """The parser's descriptor, of its three report spaces and its layouts as it made them."""
        self = cls.__new__(cls)
        self.data, self.collections, self.warnings, self.layouts = data, collections, warnings, layouts
        self.input_reports, self.output_reports, self.feature_reports = spaces[_INPUT], spaces[_OUTPUT], \
            spaces[_FEATURE]
        self.numbered_kinds, self.numbered = numbered_kinds, bool(numbered_kinds)
        return self

    # the codec's caches, made on first use (most descriptors parsed are decoded in one space, if at all)
    @_Once
    def _decoders(self) -> dict[tuple[ReportKind, int | None], ReportDecoder]:
        return {}

    @_Once
    def _encoders(self) -> dict[tuple[ReportKind, int | None], ReportEncoder]:
        return {}

    @_Once
    def _decode_functions(self) -> dict[ReportKind, dict[int | None, Callable[[bytes], Values]]]:
        return {_INPUT: {}, _OUTPUT: {}, _FEATURE: {}}

    def __repr__(self) -> str:
        counts = ", ".join(f"{k.value} {sorted(map(str, s))}" for k, s in
                           ((ReportKind.INPUT, self.input_reports), (ReportKind.OUTPUT, self.output_reports),
                            (ReportKind.FEATURE, self.feature_reports)) if s)
        return f"<ReportDescriptor {len(self.data)} bytes: {counts or 'no reports'}>"

    def layout(self, kind: ReportKind, report_id: int | None) -> ReportLayout:
        """The layout of one report; a ParseError names the report when the descriptor has none such."""
        try:
            return self.layouts[kind, report_id]
        except KeyError:
            known = sorted(str(rid) for (k, rid) in self.layouts if k is kind)
            raise ParseError(f"the descriptor has no {kind.value} report {report_id} (it has: "
                             f"{', '.join(known) or 'none'})", offset=0, token=report_id) from None

    def report_id_of(self, report: bytes, kind: ReportKind = ReportKind.INPUT) -> int | None:
        """The report ID a report read from the device carries (None when reports are unnumbered)."""
        if kind not in self.numbered_kinds:
            return None
        if not report:
            raise ParseError(f"an empty {kind.value} report has no report-ID byte", offset=0)
        return report[0]

    def decoder(self, kind: ReportKind = ReportKind.INPUT, report_id: int | None = None) -> ReportDecoder:
        """The compiled decoder of one report (built once, then reused)."""
        from pixelpen.devices.hid.codec import ReportDecoder

        key = (kind, report_id)
        if key not in self._decoders:
            self._decoders[key] = ReportDecoder(self.layout(kind, report_id))
        return self._decoders[key]

    def encoder(self, kind: ReportKind = ReportKind.INPUT, report_id: int | None = None) -> ReportEncoder:
        """The compiled encoder of one report (built once, then reused)."""
        from pixelpen.devices.hid.codec import ReportEncoder

        key = (kind, report_id)
        if key not in self._encoders:
            self._encoders[key] = ReportEncoder(self.layout(kind, report_id))
        return self._encoders[key]

    def decode(self, report: bytes, kind: ReportKind = ReportKind.INPUT) -> Values:
        """The values of one report as read from the device, keyed by ``(usage_page, usage_id)``."""
        if not isinstance(report, (bytes, bytearray, memoryview)):
            raise InvalidArgumentType(f"a report is bytes, not {type(report).__name__} (bytes(row) for a numpy row)")
        functions = self._decode_functions[kind]  # the hot path: one dict lookup per report once compiled
        function = functions.get(report[0] if report and kind in self.numbered_kinds else None)
        if function is None:
            rid = self.report_id_of(report, kind)
            function = functions[rid] = self.decoder(kind, rid).decode
        return function(report)

    def encode(self, values: Mapping[tuple[int, int], int | Sequence[int]], *, report_id: int | None = None,
               kind: ReportKind = ReportKind.INPUT) -> bytes:
        """One report from values keyed like :meth:`decode`'s (missing ones are 0 / no usage)."""
        return self.encoder(kind, report_id).encode(values)

    def fields_with(self, usage: int, kind: ReportKind = ReportKind.INPUT) -> list[Field]:
        """Every field of ``kind`` that carries the 32-bit ``usage``."""
        return [f for (k, _), r in self.layouts.items() if k is kind for f in r.fields if usage in f.usages]

    @property
    def applications(self) -> tuple[int, ...]:
        """The usages of the top-level collections (``0x00010002`` for a mouse)."""
        return tuple(c.usage for c in self.collections if c.parent is None)

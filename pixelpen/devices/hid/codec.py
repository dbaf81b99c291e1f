"""The report codec: a report layout compiled once into a decoder and an encoder of its reports.

:class:`ReportDecoder` writes Python source specialised to one :class:`~pixelpen.devices.hid.fields.ReportLayout`
(one ``int.from_bytes`` of the report, then a shift and a mask per element, two's complement where the
logical minimum is negative, a lookup table per array element) and compiles it once; decoding a report is
then one call of that function.  ``decode_batch`` decodes many reports at once with numpy.

Rules, after the kernel's ``hid_report_raw_event`` and ``hid_input_field`` (drivers/hid/hid-core.c):

* a numbered report (the descriptor has a Report ID item) starts with its ID byte, counted in the layout's
  bit offsets; a report with another ID raises :class:`~pixelpen.errors.ParseError` naming both IDs;
* a short report is zero-padded to the layout's length (the kernel's ``memset``) with a
  :class:`ShortReportWarning`, or raises ParseError naming the report ID, the expected and the found
  length when ``strict=True``; an empty report always raises; bytes past the layout's length are ignored
  (the kernel reads only ``report->size`` bits);
* variables give their logical value (two's complement when ``logical_min < 0``; out-of-range values, a
  hat switch's null state for one, are given as read: ``Field.has_null_state`` tells what they mean);
  a usage carried by several elements gives a list of their values in layout order; constant fields are
  skipped, as are elements without a usage;
* arrays give ``usage: 1`` for every usage an element reports: value ``v`` reports ``usages[v - logical_min]``
  when ``logical_min <= v <= logical_max`` and the index is in the list (the kernel's test), except usage
  ID 0 ("reserved"/"no event" on every page, a keyboard's empty slot), which reports nothing, and a usage
  that is also one of the report's variables (the variable's value is kept).  The kernel's ErrorRollOver
  (0x00070001) is reported like any usage: semantics decide what it means.

Limits: elements wider than 64 bits are decoded whole by ``decode`` and given by ``decode_batch`` as their
little-endian bytes (an (N, bytes) uint8 matrix); reports are at most the kernel's 16384 bytes (the parser's
limit; the codec checks it again).
"""

from __future__ import annotations

import warnings
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from pixelpen.devices.hid.fields import Field, ReportLayout, Values
from pixelpen.errors import InvalidArgument, InvalidArgumentType, ParseError

MAX_REPORT_BYTES = 16384
"""The kernel's HID_MAX_BUFFER_SIZE: the longest report a layout may describe."""
WHOLE_INT_BYTES = 64
"""Reports up to this length are read with one int.from_bytes; longer ones field by field (bounded work)."""
ARRAY_TABLE_BITS = 12
"""Array elements up to this many bits decode through a lookup table of every raw value."""
MAX_COMPILED_ELEMENTS = 1024
"""Reports with more elements are decoded by a loop over a plan, not compiled source (bounded build time and memory)."""
BITMAP_MIN_BITS = 16
"""A report with at least this many one-bit variables decodes them by their set bits (a keyboard's NKRO bitmap)."""
BOOL = np.dtype(bool)  # a batch's one-bit columns: they stack with any integer column, not with a wide field's bytes
Key = tuple[int, int]


class ShortReportWarning(UserWarning):
    """A report shorter than its layout was zero-padded, as the kernel does."""


@dataclass(frozen=True, slots=True)
class Element:
    """One element of a non-constant field: where its bits are and what it means."""

    field: Field
    index: int
    bit_offset: int
    bit_size: int
    key: Key | None
    """The variable's usage as ``(page, id)``; None for an array element or a variable without usage."""

    @property
    def signed(self) -> bool:
        """Two's complement (the kernel's rule, ``Field.is_signed``)."""
        return self.field.is_signed


def elements(layout: ReportLayout) -> tuple[Element, ...]:
    """The elements of a layout's non-constant fields in layout order (``ReportDecoder.values`` order)."""
    out = []
    for f in layout.fields:
        if f.is_constant or f.bit_size <= 0:
            continue
        for i in range(f.count):
            key = None
            if not f.is_array and f.usages:
                u = f.usages[min(i, len(f.usages) - 1)]
                key = (u >> 16, u & 0xFFFF)
            out.append(Element(f, i, f.bit_offset + i * f.bit_size, f.bit_size, key))
    return tuple(out)


def array_table(f: Field, skip: frozenset[Key] = frozenset()) -> tuple[Key | None, ...]:
    """For every raw value of one array element (its bits, unsigned), the usage it reports or None."""
    size = f.bit_size
    table: list[Key | None] = []
    for raw in range(1 << size):
        value = raw - (1 << size) if f.logical_min < 0 and raw >> (size - 1) else raw
        table.append(array_usage(f, value, skip))
    return tuple(table)


def array_usage(f: Field, value: int, skip: frozenset[Key] = frozenset()) -> Key | None:
    """The usage an array element with logical ``value`` reports, or None (out of range, usage ID 0, skipped)."""
    if not f.logical_min <= value <= f.logical_max:
        return None
    index = value - f.logical_min
    if index >= len(f.usages):
        return None
    u = f.usages[index]
    key = (u >> 16, u & 0xFFFF)
    return None if key[1] == 0 or key in skip else key


def _check_layout(layout: ReportLayout) -> None:
    if not isinstance(layout, ReportLayout):
        raise InvalidArgumentType(f"a ReportLayout is needed, not {type(layout).__name__}")
    if not 0 < layout.length <= MAX_REPORT_BYTES:
        raise InvalidArgument(f"report {layout.report_id}: length {layout.length} bytes is outside "
                              f"1..{MAX_REPORT_BYTES}")
    for f in layout.fields:
        if f.bit_end > 8 * layout.length:
            raise InvalidArgument(f"report {layout.report_id}: field at bit {f.bit_offset} ({f.count} x {f.bit_size} "
                                  f"bits) ends past the report's {layout.length} bytes")


class _Source:
    """Python source being written for one compiled function, with its constants."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.names: dict[str, object] = {}

    def const(self, value: object) -> str:
        name = f"_c{len(self.names)}"
        self.names[name] = value
        return name

    def compile(self, name: str, filename: str) -> Callable[..., object]:
        namespace = dict(self.names)
        exec(compile("\n".join(self.lines), filename, "exec"), namespace)  # our own generated source
        fn = namespace[name]
        assert callable(fn)
        return fn


class ReportDecoder:
    """A report layout compiled into a decoding function (built once); ``decode`` is that function."""

    decode: Callable[[bytes], Values]
    """The values of one report keyed by ``(usage_page, usage_id)`` (see the module docstring for the rules)."""
    values: Callable[[bytes], list[int]]
    """The logical value of every element of :attr:`elements` in order (arrays: the raw value, not the usage)."""

    def __init__(self, layout: ReportLayout, *, strict: bool = False) -> None:
        _check_layout(layout)
        self.layout = layout
        self.strict = strict
        self.report_id = layout.report_id
        self.length = layout.length
        self.elements = elements(layout)
        self.variable_keys = frozenset(e.key for e in self.elements if e.key is not None)
        self._repeats = Counter(e.key for e in self.elements if e.key is not None)
        self._tables: dict[Field, str] = {}
        if len(self.elements) > MAX_COMPILED_ELEMENTS:
            self.source = None
            self._plan = [self._step(e) for e in self.elements]
            self.decode = self._decode_by_plan
            self.values = self._values_by_plan
            return
        self.source = self._decode_source()
        self.decode = self.source.compile("decode", f"<hid decoder report {layout.report_id}>")  # type: ignore[assignment]
        self.values = self._values_source().compile("values", f"<hid values report {layout.report_id}>")  # type: ignore[assignment]

    def __repr__(self) -> str:
        return (f"<ReportDecoder {self.layout.kind.value} report {self.report_id}: {self.length} bytes, "
                f"{len(self.elements)} elements>")

    # -- the compiled per-report functions --------------------------------------------------------------

    def _expr(self, e: Element, whole: bool, signed: bool | None = None) -> str:
        """The expression of one element's value (``v`` the report as an int, or ``r`` its bytes); signed as its
        field unless told."""
        if whole:
            shift, word = e.bit_offset, "v"
        else:
            first, last = e.bit_offset // 8, (e.bit_offset + e.bit_size - 1) // 8
            shift, word = e.bit_offset - 8 * first, f"_from(r[{first}:{last + 1}], 'little')"
        mask = (1 << e.bit_size) - 1
        bits = f"({word} >> {shift} & {mask})" if shift else f"({word} & {mask})"
        if e.signed if signed is None else signed:
            half = 1 << (e.bit_size - 1)
            return f"(({bits} ^ {half}) - {half})"
        return bits

    def _prologue(self, src: _Source) -> bool:
        whole = self.length <= WHOLE_INT_BYTES
        fit = src.const(self._fit)
        test = f"len(r) != {self.length}"
        if self.report_id is not None:
            test += f" or r[0] != {self.report_id}"
        src.lines += [f"    if {test}:", f"        r = {fit}(r)"]
        if whole:
            src.lines.append("    v = _from(r, 'little')")
        src.names["_from"] = int.from_bytes
        return whole

    def _decode_source(self) -> _Source:
        src = _Source()
        src.lines.append("def decode(r):")
        whole = self._prologue(src)
        bitmap = self._bitmap()
        in_bitmap = {e.bit_offset for e in bitmap}
        lists: dict[Key, list[str]] = {}
        arrays: list[str] = []
        skip = self.variable_keys
        for e in self.elements:
            if e.key is not None and e.bit_offset not in in_bitmap:
                lists.setdefault(e.key, []).append(self._expr(e, whole))
            elif e.field.is_array:
                arrays.append(self._array_statement(src, e, whole, skip))
        items = []
        for key, exprs in lists.items():
            items.append(f"{key!r}: {exprs[0] if len(exprs) == 1 else '[' + ', '.join(exprs) + ']'}")
        body = "{" + ", ".join(items) + "}"
        if not arrays and not bitmap:
            src.lines.append(f"    return {body}")
            return src
        if bitmap:
            self._bitmap_statements(src, bitmap, whole)
            if items:
                src.lines.append(f"    d.update({body})")
        else:
            src.lines.append(f"    d = {body}")
        src.lines += arrays
        if arrays:
            src.lines.append("    d.pop(None, None)")
        src.lines.append("    return d")
        return src

    def _bitmap(self) -> list[Element]:
        """The one-bit unsigned variables of distinct usages, when there are at least BITMAP_MIN_BITS of them."""
        bitmap = [e for e in self.elements if e.key is not None and e.bit_size == 1 and not e.signed
                  and self._repeats[e.key] == 1]
        return bitmap if len(bitmap) >= BITMAP_MIN_BITS else []

    def _bitmap_statements(self, src: _Source, bitmap: list[Element], whole: bool) -> None:
        """``d`` as every one-bit variable at 0, then a 1 for each set bit (a keyboard's NKRO bitmap: its cost
        follows the keys pressed, not the keys it has)."""
        first = 0 if whole else bitmap[0].bit_offset // 8
        last = max(e.bit_offset for e in bitmap) // 8
        base = 8 * first
        keys: list[Key | None] = [None] * (8 * (last - first + 1))
        mask = 0
        for e in bitmap:
            keys[e.bit_offset - base] = e.key
            mask |= 1 << (e.bit_offset - base)
        word = "v" if whole else f"_from(r[{first}:{last + 1}], 'little')"
        zero, table = src.const(dict.fromkeys((e.key for e in bitmap), 0)), src.const(tuple(keys))
        src.lines += [f"    d = {zero}.copy()", f"    b = {word} & {mask}", "    while b:",
                      "        low = b & -b", f"        d[{table}[low.bit_length() - 1]] = 1", "        b ^= low"]

    def _array_statement(self, src: _Source, e: Element, whole: bool, skip: frozenset[Key]) -> str:
        """``d[usage] = 1`` for one array element (None as the key of "nothing", popped at the end)."""
        f = e.field
        if f.bit_size <= ARRAY_TABLE_BITS:
            if f not in self._tables:  # one table per field, shared by its elements
                self._tables[f] = src.const(array_table(f, skip))
            return f"    d[{self._tables[f]}[{self._expr(e, whole, signed=False)}]] = 1"
        usage = src.const(lambda value, f=f: array_usage(f, value, skip))
        return f"    d[{usage}({self._expr(e, whole)})] = 1"

    def _values_source(self) -> _Source:
        src = _Source()
        src.lines.append("def values(r):")
        whole = self._prologue(src)
        src.lines.append("    return [" + ", ".join(self._expr(e, whole) for e in self.elements) + "]")
        return src

    # -- reports too large to compile: one loop over a plan -------------------------------------------------

    def _step(self, e: Element) -> tuple[int, int, int, int, int, Key | None, Callable[[int], Key | None] | None]:
        """One element as (first byte, end byte, shift, mask, sign bit or 0, variable key, array usage of a value)."""
        first, last = e.bit_offset // 8, (e.bit_offset + e.bit_size - 1) // 8
        f = e.field
        usage_of = None if e.key is not None or not f.is_array else (
            lambda value, f=f: array_usage(f, value, self.variable_keys))
        half = 1 << (e.bit_size - 1) if e.signed else 0
        return first, last + 1, e.bit_offset - 8 * first, (1 << e.bit_size) - 1, half, e.key, usage_of

    def _values_by_plan(self, report: bytes) -> list[int]:
        if len(report) != self.length or (self.report_id is not None and report[0] != self.report_id):
            report = self._fit(report)
        out = []
        for first, end, shift, mask, half, _, _ in self._plan:
            value = int.from_bytes(report[first:end], "little") >> shift & mask
            out.append((value ^ half) - half if half else value)
        return out

    def _decode_by_plan(self, report: bytes) -> Values:
        values = self._values_by_plan(report)
        d: Values = {}
        for value, (_, _, _, _, _, key, usage_of) in zip(values, self._plan, strict=True):
            if key is not None:
                if self._repeats[key] == 1:
                    d[key] = value
                else:
                    d.setdefault(key, []).append(value)  # type: ignore[union-attr]
            elif usage_of is not None and (usage := usage_of(value)) is not None:
                d[usage] = 1
        return d

    def _fit(self, report: bytes) -> bytes:
        """A report checked for its ID and brought to the layout's length (the kernel's rules)."""
        rid = self.report_id
        if not isinstance(report, (bytes, bytearray, memoryview)):
            raise InvalidArgumentType(f"a report is bytes, not {type(report).__name__}")
        report = bytes(report)
        if not report:
            raise ParseError(f"an empty {self.layout.kind.value} report (report {rid} is {self.length} bytes)",
                             offset=0)
        if rid is not None and report[0] != rid:
            raise ParseError(f"{self.layout.kind.value} report {report[0]} given to the decoder of report {rid}",
                             offset=0, token=report[0])
        if len(report) >= self.length:
            return report[:self.length]
        message = (f"{self.layout.kind.value} report {rid} is too short: {len(report)} bytes, "
                   f"expected {self.length}")
        if self.strict:
            raise ParseError(message, offset=len(report))
        warnings.warn(message + " (zero-padded as the kernel does)", ShortReportWarning, stacklevel=3)
        return report + bytes(self.length - len(report))

    # -- batches ------------------------------------------------------------------------------------------

    def batch_array(self, reports: np.ndarray | bytes | bytearray | memoryview) -> np.ndarray:
        """Reports as an (N, length) uint8 array, checked like single reports (IDs, short and long rows)."""
        if isinstance(reports, (bytes, bytearray, memoryview)):
            data = np.frombuffer(bytes(reports), np.uint8)
            if data.size % self.length:
                raise ParseError(f"{data.size} bytes are not a whole number of {self.length}-byte reports "
                                 f"(report {self.report_id})", offset=data.size - data.size % self.length)
            arr = data.reshape(-1, self.length)
        elif isinstance(reports, np.ndarray):
            if reports.ndim != 2 or reports.dtype != np.uint8:
                raise InvalidArgument(f"a batch is an (N, length) uint8 array, not {reports.ndim}-d {reports.dtype}")
            arr = reports
        else:
            raise InvalidArgumentType(f"a batch is a uint8 array or bytes, not {type(reports).__name__}")
        n, width = arr.shape
        if width == 0 and n:
            raise ParseError(f"empty {self.layout.kind.value} reports (report {self.report_id})", offset=0)
        if width < self.length and n:
            message = (f"{self.layout.kind.value} reports {self.report_id} are too short: {width} bytes, "
                       f"expected {self.length}")
            if self.strict:
                raise ParseError(message, offset=width)
            warnings.warn(message + " (zero-padded as the kernel does)", ShortReportWarning, stacklevel=3)
            arr = np.concatenate([arr, np.zeros((n, self.length - width), np.uint8)], axis=1)
        if self.report_id is not None and n:
            bad = np.flatnonzero(arr[:, 0] != self.report_id)
            if bad.size:
                row = int(bad[0])
                raise ParseError(f"row {row}: {self.layout.kind.value} report {arr[row, 0]} given to the decoder "
                                 f"of report {self.report_id}", offset=row * width, token=int(arr[row, 0]))
        arr = arr[:, :self.length]
        return arr if arr.strides[1] == 1 else np.ascontiguousarray(arr)

    def _window(self, arr: np.ndarray, first: int, last: int) -> tuple[np.ndarray, int]:
        """The narrowest little-endian word (1, 2, 4 or 8 bytes) holding bytes ``first..last`` of every row, and
        how many bytes before ``first`` it starts; rows too short for it are read zero-padded (a copy)."""
        need = last - first + 1
        width = next(w for w in (1, 2, 4, 8) if w >= need)
        start = max(0, min(first, arr.shape[1] - width))
        if start + width < last + 1 or start + width > arr.shape[1]:
            wide = np.zeros((arr.shape[0], first + width), np.uint8)
            wide[:, :arr.shape[1] - first] = arr[:, first:]
            return wide[:, :width].view(f"<u{width}")[:, 0], 0
        return arr[:, start:start + width].view(f"<u{width}")[:, 0], first - start

    def _element_batch(self, arr: np.ndarray, e: Element, raw: bool = False) -> np.ndarray:
        """One element's values over a batch: bool for one unsigned bit (a button, a key), int64 (uint64 for 64-bit
        unsigned), bytes beyond 64 bits; with ``raw`` its bits unsigned in any integer dtype (an array's table
        index)."""
        first, shift, size = e.bit_offset // 8, e.bit_offset % 8, e.bit_size
        last = (e.bit_offset + size - 1) // 8
        signed = e.signed and not raw
        if size > 64:
            bits = np.unpackbits(arr[:, first:last + 1], axis=1, bitorder="little")[:, shift:shift + size]
            return np.packbits(bits, axis=1, bitorder="little")  # wider than 64 bits: little-endian bytes
        if last - first + 1 > 8:  # 58..64 bits not byte-aligned: two words
            low, high = self._element_batch(arr, _part(e, 0, 64 - shift), raw=True), arr[:, last]
            value = low.astype(np.uint64) | (high.astype(np.uint64) << np.uint64(64 - shift))
            value = value & np.uint64((1 << size) - 1) if size < 64 else value
            return _sign_extend(value, size) if signed else (value if size == 64 else value.view(np.int64))
        if shift == 0 and size in (8, 16, 32, 64):
            dtype = np.dtype(f"<{'i' if signed else 'u'}{size // 8}")
            column = arr[:, first:first + size // 8].view(dtype)[:, 0]
            return column if size == 64 or raw else column.astype(np.int64)
        word, before = self._window(arr, first, last)
        value = word >> (shift + 8 * before) if shift + before else word  # Python ints keep the word's dtype
        if size < 8 * word.itemsize:
            value = value & ((1 << size) - 1)
        if raw:
            return value
        if size == 1 and not signed:
            return value.astype(bool)
        if signed:
            return _sign_extend(value.astype(np.uint64), size)
        return value.astype(np.int64) if size < 64 else value

    def decode_batch(self, reports: np.ndarray | bytes | bytearray | memoryview) -> dict[Key, np.ndarray]:
        """Many reports at once: ``(page, id)`` -> an (N,) array per variable usage ((N, k) when it repeats k
        times, columns in layout order); for array usages an (N,) bool array "reported in this row" for every
        usage some row reports.  Row ``i`` agrees with ``decode(reports[i])``; see :meth:`array_usages_batch`
        for the arrays' usages element by element."""
        arr = self.batch_array(reports)
        bitmap = self._bitmap_batch(arr)
        columns: dict[Key, list[np.ndarray]] = {}
        for e in self.elements:
            if e.key is not None:  # (elements start at distinct bits: a bitmap bit's offset is its alone)
                column = bitmap.get(e.bit_offset)
                columns.setdefault(e.key, []).append(self._element_batch(arr, e) if column is None else column)
        out: dict[Key, np.ndarray] = {}
        for key, cols in columns.items():
            if len(cols) > 1 and (len({c.ndim for c in cols}) > 1 or len({c.dtype for c in cols} - {BOOL}) > 1):
                raise InvalidArgument(f"report {self.report_id}: usage {_name(key)} repeats in elements of different "
                                      "widths (one over 64 bits, or 64-bit unsigned beside narrower): decode these "
                                      "reports one by one")
            out[key] = cols[0] if len(cols) == 1 else np.stack(cols, axis=1)
        out.update(self._array_presence(arr))
        return out

    def _bitmap_batch(self, arr: np.ndarray) -> dict[int, np.ndarray]:
        """:meth:`_bitmap`'s bits by bit offset, bool as :meth:`_element_batch` gives them, when they fill a quarter
        of their bytes: eight shifts over the bytes transposed, each column a contiguous row (4x unpackbits')."""
        offsets = [e.bit_offset for e in self._bitmap()]
        first, last = min(offsets, default=0) // 8, max(offsets, default=0) // 8
        if not offsets or 8 * (last - first + 1) > 4 * len(offsets):
            return {}
        octets = np.ascontiguousarray(arr[:, first:last + 1].T)
        planes = np.empty((8, *octets.shape), np.uint8)
        for k, plane in enumerate(planes):
            np.bitwise_and(np.right_shift(octets, k, out=plane), 1, out=plane)
        bits = planes.view(bool)
        return {o: bits[o % 8, o // 8 - first] for o in offsets}

    def _array_indices(self, arr: np.ndarray) -> tuple[list[Key], list[np.ndarray]]:
        """Every usage the arrays can report, and per array element an (N,) array of 1 + its index in them (0: none)."""
        index: dict[Key, int] = {}
        luts: dict[Field, np.ndarray] = {}
        cols = []
        for e in self.elements:
            if e.key is not None or not e.field.is_array:
                continue
            f = e.field
            if f.bit_size > 64:
                raise InvalidArgument(f"report {self.report_id}: the array at bit {f.bit_offset} has elements of "
                                      f"{f.bit_size} bits; batches decode arrays of up to 64 (decode one by one)")
            if f.bit_size <= ARRAY_TABLE_BITS:  # a table over every raw value of the element's bits, one per field
                if f not in luts:
                    luts[f] = np.array([0 if k is None else 1 + index.setdefault(k, len(index))
                                        for k in array_table(f, self.variable_keys)], np.int32)
                cols.append(luts[f][self._element_batch(arr, e, raw=True)])
                continue
            possible = [array_usage(f, f.logical_min + i, self.variable_keys) for i in range(len(f.usages))]
            lut = np.array([0 if k is None else 1 + index.setdefault(k, len(index)) for k in possible] + [0], np.int32)
            value = self._element_batch(arr, e)
            pos = value - f.logical_min
            valid = (value >= f.logical_min) & (value <= f.logical_max) & (pos < len(possible))
            cols.append(lut[np.where(valid, pos, len(possible))])
        return list(index), cols

    def _array_presence(self, arr: np.ndarray) -> dict[Key, np.ndarray]:
        """An (N,) bool "reported in this row" per usage some row's arrays report: the rows of one (usages + 1, N)
        matrix, each element marking its usage's row at its column in one scatter (row 0 takes "none"), so the
        cost follows the elements and the memory the usages reported, not the usages the arrays could report."""
        keys, cols = self._array_indices(arr)
        if not cols:
            return {}
        n = arr.shape[0]
        seen = np.sum([np.bincount(col, minlength=len(keys) + 1) for col in cols], axis=0)  # 2x a scatter's speed
        present = np.flatnonzero(seen[1:])
        row_start = np.zeros(len(keys) + 1, np.intp)
        row_start[present + 1] = np.arange(1, len(present) + 1) * n
        matrix = np.zeros((len(present) + 1, n), bool)
        cells, rows, where = matrix.reshape(-1), np.arange(n), np.empty(n, np.intp)
        for col in cols:
            np.add(row_start[col], rows, out=where)
            cells[where] = True
        return {keys[i]: matrix[j] for j, i in enumerate(present.tolist(), 1)}

    def array_usages_batch(self, reports: np.ndarray | bytes | bytearray | memoryview) -> np.ndarray:
        """An (N, array elements) int64 matrix of the 32-bit usage each array element reports (0: none)."""
        arr = self.batch_array(reports)
        keys, cols = self._array_indices(arr)
        usages = np.array([0] + [p << 16 | u for p, u in keys], np.int64)
        return usages[np.stack(cols, axis=1)] if cols else np.zeros((arr.shape[0], 0), np.int64)


def _part(e: Element, start: int, size: int) -> Element:
    """``size`` bits of an element from its bit ``start``, unsigned."""
    f = e.field
    part = Field(f.kind, f.report_id, f.usage_page, (), e.bit_offset + start, size, 1, 0, 0, 0, 0, 0, 0, f.flags)
    return Element(part, 0, e.bit_offset + start, size, None)


def _sign_extend(value: np.ndarray, size: int) -> np.ndarray:
    """uint64 values of ``size`` bits as two's complement int64."""
    if size < 64:
        half = np.uint64(1 << (size - 1))
        value = (value ^ half) - half
    return value.view(np.int64)


class ReportEncoder:
    """A report layout turned into reports from values keyed like ReportDecoder.decode's."""

    def __init__(self, layout: ReportLayout) -> None:
        _check_layout(layout)
        self.layout = layout
        self.report_id = layout.report_id
        self.length = layout.length
        self.elements = elements(layout)
        self._by_key: dict[Key, list[Element]] = {}
        self._arrays: list[tuple[Field, list[Element], dict[Key, int], int | None]] = []
        for e in self.elements:
            if e.key is not None:
                self._by_key.setdefault(e.key, []).append(e)
        variable_keys = frozenset(self._by_key)
        for f in layout.fields:
            if f.is_array and not f.is_constant and f.bit_size > 0:
                slots = [e for e in self.elements if e.field is f]
                codes: dict[Key, int] = {}
                for i in range(len(f.usages)):
                    k = array_usage(f, f.logical_min + i, variable_keys)
                    if k is not None:
                        codes.setdefault(k, f.logical_min + i)
                self._arrays.append((f, slots, codes, _empty_value(f)))

    def __repr__(self) -> str:
        return f"<ReportEncoder {self.layout.kind.value} report {self.report_id}: {self.length} bytes>"

    def encode(self, values: Mapping[Key, int | Sequence[int]]) -> bytes:
        """One report: variables from their keys (an int for every element of a repeated usage, or a sequence
        per element; missing ones 0), arrays from the keys with a true value; the ID byte first when numbered."""
        word = 0 if self.report_id is None else self.report_id
        for key, elems in self._by_key.items():
            given = values.get(key, 0)
            if isinstance(given, (int, np.integer)):
                per = [int(given)] * len(elems)
            else:
                per = [int(x) for x in given]
                if len(per) != len(elems):
                    raise InvalidArgument(f"report {self.report_id}: usage {_name(key)} has {len(elems)} elements, "
                                          f"{len(per)} values were given")
            for e, value in zip(elems, per, strict=True):
                word |= _bits(e, value, key, self.report_id) << e.bit_offset
        for f, slots, codes, empty in self._arrays:
            wanted = [codes[k] for k, v in values.items() if k in codes and v]
            if len(wanted) > len(slots):
                raise InvalidArgument(f"report {self.report_id}: {len(wanted)} usages for an array of {len(slots)} "
                                      f"elements (field at bit {f.bit_offset})")
            if len(wanted) < len(slots):
                if empty is None:
                    raise InvalidArgument(f"report {self.report_id}: the array at bit {f.bit_offset} has no value "
                                          f"meaning \"no usage\", so all its {len(slots)} elements need a usage")
                wanted += [empty] * (len(slots) - len(wanted))
            for e, value in zip(slots, wanted, strict=True):
                word |= (value & ((1 << e.bit_size) - 1)) << e.bit_offset
        return word.to_bytes(self.length, "little")


def _name(key: Key) -> str:
    return f"0x{key[0]:04x}:0x{key[1]:04x}"


def _bits(e: Element, value: int, key: Key, report_id: int | None) -> int:
    """A value as an element's bits; InvalidArgument when it does not fit."""
    size = e.bit_size
    low, high = (-(1 << (size - 1)), (1 << (size - 1)) - 1) if e.signed else (0, (1 << size) - 1)
    if not low <= value <= high:
        raise InvalidArgument(f"report {report_id}: usage {_name(key)} value {value} does not fit "
                              f"{'signed ' if e.signed else ''}{size} bits ({low}..{high})")
    return value & ((1 << size) - 1)


def _empty_value(f: Field) -> int | None:
    """The value an unused array element gets: the index of usage ID 0 when listed, else an out-of-range one."""
    for i, u in enumerate(f.usages):
        if u & 0xFFFF == 0 and f.logical_min + i <= f.logical_max:
            return f.logical_min + i
    size = f.bit_size
    low, high = (-(1 << (size - 1)), (1 << (size - 1)) - 1) if f.logical_min < 0 else (0, (1 << size) - 1)
    top = min(f.logical_max, f.logical_min + len(f.usages) - 1)
    for candidate in (0, top + 1, f.logical_min - 1, high, low):
        if low <= candidate <= high and not f.logical_min <= candidate <= top:
            return candidate
    return None

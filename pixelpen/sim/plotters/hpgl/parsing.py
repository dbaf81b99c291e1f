"""HP-GL/1 and RS-232 device-control syntax as HP's plotters read it: streaming readers for the plotter simulators.

HP-GL (7470A Interfacing and Programming Manual p. 1-6, "HP-GL Syntax"): a two-letter mnemonic, upper
or lower case, then parameters separated by commas or spaces or by a ``+``/``-`` sign, ended by a
semicolon or by the first letter of the next mnemonic (``INCA2IP0,0,10300,7650DI0,1SP2`` is valid).
``LB`` text runs to the label terminator (ETX unless ``DT`` changed it).  Instructions without
parameters execute even if no terminator follows.

Device control (manual ch. 10): ``ESC . letter``, parameters as decimal numbers separated by ``;``
and ended by ``:``; acted on when received, never stored in the buffer.

The readers hold no device state beyond what the syntax needs; the simulator executes what they return.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Collection
from dataclasses import dataclass

ETX = 0x03
ESC = 0x1B

INSTRUCTION_SEPARATORS = frozenset(b" ,;\t\r\n\x00")
"""Bytes skipped between instructions (7470A manual: commas and spaces may surround a mnemonic)."""
PARAMETER_SEPARATORS = frozenset(b" ,\t\r\n")
"""Bytes separating numbers inside a parameter list (a sign also starts a new number)."""

MAX_NUMBER_CHARS = 32
"""A number token longer than this is refused as a bad parameter (error 3) instead of being waited for."""

_NUMBER = re.compile(rb"[+-]?(?:\d+(?:\.\d*)?|\.\d+)")
_NUMBER_START = frozenset(b"+-.0123456789")
_LETTERS = frozenset(b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz")


class Kind(enum.Enum):
    """How an instruction's parameter field is read."""

    NONE = "none"  # no parameters: executes as soon as the mnemonic is complete
    NUMBERS = "numbers"  # a list of numbers up to the terminator
    PAIRS = "pairs"  # X,Y pairs, each executed as soon as it is read (PA, PD, PU, PR)
    LABEL = "label"  # text up to the label terminator (LB)
    CHAR = "char"  # one character (DT, SM)


@dataclass(frozen=True)
class Syntax:
    """Parameter syntax of one mnemonic: its kind and the most numbers it takes."""

    kind: Kind
    max_params: int = 0


def _numbers(n: int) -> Syntax:
    return Syntax(Kind.NUMBERS, n)


SYNTAX: dict[str, Syntax] = {
    # setup and status
    "IN": Syntax(Kind.NONE), "DF": Syntax(Kind.NONE), "IP": _numbers(4), "SC": _numbers(4), "IW": _numbers(4),
    "RO": _numbers(1), "IM": _numbers(3), "PS": _numbers(1),
    # pens and vectors
    "SP": _numbers(1), "VS": _numbers(2), "FS": _numbers(2), "PT": _numbers(1), "LT": _numbers(2),
    "PA": Syntax(Kind.PAIRS), "PR": Syntax(Kind.PAIRS), "PU": Syntax(Kind.PAIRS), "PD": Syntax(Kind.PAIRS),
    # shapes
    "CI": _numbers(2), "AA": _numbers(4), "AR": _numbers(4), "EA": _numbers(2), "ER": _numbers(2),
    "RA": _numbers(2), "RR": _numbers(2), "EW": _numbers(4), "WG": _numbers(4), "FT": _numbers(3),
    "XT": Syntax(Kind.NONE), "YT": Syntax(Kind.NONE), "TL": _numbers(2),
    # labels
    "LB": Syntax(Kind.LABEL), "DT": Syntax(Kind.CHAR), "SM": Syntax(Kind.CHAR), "DI": _numbers(2),
    "DR": _numbers(2), "SI": _numbers(2), "SR": _numbers(2), "SL": _numbers(1), "CP": _numbers(2),
    "CA": _numbers(1), "CS": _numbers(1), "SA": Syntax(Kind.NONE), "SS": Syntax(Kind.NONE), "UC": _numbers(250),
    # digitizing
    "DC": Syntax(Kind.NONE), "DP": Syntax(Kind.NONE),
    # output (buffered)
    "OA": Syntax(Kind.NONE), "OC": Syntax(Kind.NONE), "OD": Syntax(Kind.NONE), "OE": Syntax(Kind.NONE),
    "OF": Syntax(Kind.NONE), "OH": Syntax(Kind.NONE), "OI": Syntax(Kind.NONE), "OO": Syntax(Kind.NONE),
    "OP": Syntax(Kind.NONE), "OS": Syntax(Kind.NONE), "OT": Syntax(Kind.NONE), "OW": Syntax(Kind.NONE),
}
"""The HP-GL/1 mnemonics the simulators know, with their parameter syntax."""

GENERIC = _numbers(250)
"""Syntax of a mnemonic a model recognises but the simulator gives no effect (read, logged, skipped)."""


@dataclass(frozen=True)
class Instruction:
    """One executable item read from the HP-GL stream.

    ``params`` are the numbers read; ``text`` is label text (LB: one character per item) or the character
    of DT/SM; ``error`` is an HP-GL error the syntax alone decides (1 unknown instruction or illegal
    character, 2 wrong parameter count, 3 bad parameter), 0 otherwise; ``offset`` is the stream byte
    offset of its first byte.  A PA/PD/PU/PR with several pairs arrives as one Instruction per pair.
    """

    mnemonic: str
    params: tuple[float, ...] = ()
    text: str = ""
    error: int = 0
    offset: int = 0

    def __str__(self) -> str:
        if self.text:
            return self.mnemonic + self.text.encode("unicode_escape").decode("ascii")
        return self.mnemonic + ",".join(_format_number(p) for p in self.params)


def _format_number(value: float) -> str:
    return str(int(value)) if float(value).is_integer() else f"{value:.4f}".rstrip("0")


class _Need(Exception):
    """More bytes are needed before the item at the read position can be decided."""


class _Bad(Exception):
    """The item at the read position is malformed: ``code`` is its HP-GL error, ``end`` where it stops."""

    def __init__(self, code: int, end: int) -> None:
        super().__init__(code)
        self.code = code
        self.end = end


class InstructionReader:
    """Reads HP-GL instructions one at a time from the front of a byte buffer, as the plotter's parser does.

    ``read(data)`` returns ``(consumed, instruction)``: the caller drops ``consumed`` bytes from the
    front of its buffer and executes ``instruction`` (None when only separators or skipped bytes were
    consumed).  ``(0, None)`` means the front of the buffer is an incomplete item: wait for more bytes.
    With ``full=True`` (the buffer cannot take another byte) an incomplete item is declared bad
    instead, so a stream that never terminates an instruction cannot wedge the buffer.

    ``known`` is the model's instruction set; ``recognised`` are mnemonics it accepts without the
    simulator modelling them.  ``label_terminator`` is set by the executor when DT executes.
    """

    def __init__(self, known: Collection[str], recognised: Collection[str] = ()) -> None:
        self.known = frozenset(m.upper() for m in known)
        self.recognised = frozenset(m.upper() for m in recognised) - self.known
        self.label_terminator = ETX
        self.offset = 0
        self._pairs: str | None = None  # mnemonic whose X,Y pairs are being read
        self._label = False
        self._skip_error = 0  # >0: discarding up to the next terminator after a bad instruction

    def reset(self) -> None:
        """Forget any partly read instruction and restore the ETX label terminator (IN, DF, ESC.K, power-up)."""
        self._pairs = None
        self._label = False
        self._skip_error = 0
        self.label_terminator = ETX

    @property
    def in_label(self) -> bool:
        """True while label text is being read (bytes are text up to the terminator)."""
        return self._label

    def read(self, data: bytes | bytearray, full: bool = False) -> tuple[int, Instruction | None]:
        """Read the next item from the front of ``data``; see the class docstring."""
        n, item = self._read(data, full)
        self.offset += n
        return n, item

    def _read(self, data: bytes | bytearray, full: bool) -> tuple[int, Instruction | None]:
        if not data:
            return 0, None
        if self._skip_error:
            n = self._skip(data)
            if n or self._skip_error:
                return n, None
        if self._label:
            return self._label_text(data)
        if self._pairs is not None:
            return self._next_pair(data, full)
        i = 0
        while i < len(data) and data[i] in INSTRUCTION_SEPARATORS:
            i += 1
        if i:
            return i, None
        return self._instruction(data, full)

    # -- plain instructions -------------------------------------------------------------------

    def _instruction(self, data: bytes | bytearray, full: bool) -> tuple[int, Instruction | None]:
        first = data[0]
        if first not in _LETTERS:
            shown = f"\\x{first:02x}" if not 0x20 < first < 0x7F else chr(first)
            return 1, Instruction(shown, error=1, offset=self.offset)
        if len(data) < 2:
            return (1, Instruction(chr(first).upper(), error=1, offset=self.offset)) if full else (0, None)
        if data[1] not in _LETTERS:
            return 1, Instruction(chr(first).upper(), error=1, offset=self.offset)
        mnemonic = bytes(data[:2]).decode("ascii").upper()
        if mnemonic in self.known:
            syntax = SYNTAX.get(mnemonic, GENERIC)
        elif mnemonic in self.recognised:
            syntax = GENERIC
        else:
            self._skip_error = 1
            return 2 + self._skip(data[2:]), Instruction(mnemonic, error=1, offset=self.offset)
        if syntax.kind is Kind.PAIRS:
            self._pairs = mnemonic
            n, item = self._next_pair(data[2:], full, first_pair=True)
            if n == 0 and item is None:
                self._pairs = None
                return 0, None
            return 2 + n, item
        if syntax.kind is Kind.LABEL:
            self._label = True
            n, item = self._label_text(data[2:], start=True)
            return 2 + n, item
        if syntax.kind is Kind.CHAR:
            return self._char(mnemonic, data, full)
        return self._numbers(mnemonic, syntax, data, full)

    def _numbers(
        self, mnemonic: str, syntax: Syntax, data: bytes | bytearray, full: bool
    ) -> tuple[int, Instruction | None]:
        try:
            params, end = self._number_list(data, 2, syntax.max_params)
        except _Need:
            if syntax.kind is Kind.NONE and not _has_number_ahead(data, 2):
                return 2, Instruction(mnemonic, offset=self.offset)
            if not full:
                return 0, None
            self._skip_error = 3
            return len(data), Instruction(mnemonic, error=3, offset=self.offset)
        except _Bad as bad:
            self._skip_error = bad.code
            return bad.end, Instruction(mnemonic, error=bad.code, offset=self.offset)
        error = 2 if len(params) > syntax.max_params else 0
        return end, Instruction(mnemonic, tuple(params[: syntax.max_params]), error=error, offset=self.offset)

    def _number_list(self, data: bytes | bytearray, i: int, limit: int) -> tuple[list[float], int]:
        """Numbers from ``i`` to the terminator; returns them and the index after a ``;`` (before a letter)."""
        params: list[float] = []
        while True:
            while i < len(data) and data[i] in PARAMETER_SEPARATORS:
                i += 1
            if i >= len(data):
                raise _Need
            c = data[i]
            if c == 0x3B:  # ';'
                return params, i + 1
            if c in _LETTERS or c == ESC:
                return params, i
            value, i = _number(data, i)
            params.append(value)
            if len(params) > limit + 1:
                raise _Bad(2, i)

    def _char(self, mnemonic: str, data: bytes | bytearray, full: bool) -> tuple[int, Instruction | None]:
        if len(data) < 3:
            return (2, Instruction(mnemonic, error=2, offset=self.offset)) if full else (0, None)
        c = data[2]
        if c == 0x3B:
            return 3, Instruction(mnemonic, offset=self.offset)
        if mnemonic == "DT" and c in (0x00, 0x0A, ESC):
            return 3, Instruction(mnemonic, error=3, offset=self.offset)
        if mnemonic == "SM" and not 0x20 < c < 0x7F:
            return 3, Instruction(mnemonic, error=3, offset=self.offset)
        return 3, Instruction(mnemonic, text=chr(c), offset=self.offset)

    # -- streamed forms: pairs and label text -------------------------------------------------

    def _next_pair(
        self, data: bytes | bytearray, full: bool, first_pair: bool = False
    ) -> tuple[int, Instruction | None]:
        mnemonic = self._pairs
        assert mnemonic is not None
        i = 0
        while i < len(data) and data[i] in PARAMETER_SEPARATORS:
            i += 1
        if i >= len(data):
            if first_pair and full:  # a full buffer ends the bare mnemonic
                self._pairs = None
                return i, Instruction(mnemonic, offset=self.offset)
            return (i, None) if i and not first_pair else (0, None)
        c = data[i]
        if c == 0x3B or c in _LETTERS or c == ESC:
            self._pairs = None
            end = i + 1 if c == 0x3B else i
            return end, (Instruction(mnemonic, offset=self.offset) if first_pair else None)
        try:
            x, i = _number(data, i)
            while i < len(data) and data[i] in PARAMETER_SEPARATORS:
                i += 1
            if i >= len(data):
                raise _Need
            c = data[i]
            if c == 0x3B or c in _LETTERS or c == ESC:
                self._pairs = None
                return (i + 1 if c == 0x3B else i), Instruction(mnemonic, (x,), error=2, offset=self.offset)
            y, i = _number(data, i)
            while i < len(data) and data[i] in PARAMETER_SEPARATORS:
                i += 1
            if i < len(data) and data[i] == 0x3B:  # the terminator leaves the buffer with the last pair
                self._pairs = None
                i += 1
            elif i < len(data) and (data[i] in _LETTERS or data[i] == ESC):
                self._pairs = None
        except _Need:
            if not full:
                return 0, None
            self._pairs = None
            self._skip_error = 3
            return len(data), Instruction(mnemonic, error=3, offset=self.offset)
        except _Bad as bad:
            self._pairs = None
            self._skip_error = bad.code
            return bad.end, Instruction(mnemonic, error=bad.code, offset=self.offset)
        return i, Instruction(mnemonic, (x, y), offset=self.offset)

    def _label_text(self, data: bytes | bytearray, start: bool = False) -> tuple[int, Instruction | None]:
        """Label text one character at a time (the plotter draws each as it reads it); the terminator ends it."""
        if not data:
            return 0, (Instruction("LB", offset=self.offset) if start else None)
        if data[0] == self.label_terminator:
            self._label = False
            return 1, (Instruction("LB", offset=self.offset) if start else None)
        if len(data) > 1 and data[1] == self.label_terminator:
            self._label = False
            return 2, Instruction("LB", text=chr(data[0]), offset=self.offset)
        return 1, Instruction("LB", text=chr(data[0]), offset=self.offset)

    def _skip(self, data: bytes | bytearray) -> int:
        """Discard the rest of a bad instruction: up to and including ``;``, or up to a letter or ESC."""
        for i, c in enumerate(data):
            if c == 0x3B:
                self._skip_error = 0
                return i + 1
            if c in _LETTERS or c == ESC:
                self._skip_error = 0
                return i
        return len(data)


def _has_number_ahead(data: bytes | bytearray, i: int) -> bool:
    while i < len(data) and data[i] in PARAMETER_SEPARATORS:
        i += 1
    return i < len(data) and data[i] in _NUMBER_START


def _number(data: bytes | bytearray, i: int) -> tuple[float, int]:
    """The number starting at ``i`` and the index after it; _Need if it may still continue, _Bad if illegal."""
    m = _NUMBER.match(data, i)
    if m is None:
        if data[i] in b"+-." and i + 1 >= len(data):
            raise _Need
        if data[i] in b"+-" and i + 2 >= len(data) and data[i + 1] == 0x2E:
            raise _Need
        raise _Bad(1, i + 1)
    end = m.end()
    if end - i > MAX_NUMBER_CHARS:
        raise _Bad(3, end)
    if end >= len(data):
        if end - i >= MAX_NUMBER_CHARS:
            raise _Bad(3, end)
        raise _Need
    return float(m.group()), end


def parse_hpgl(
    data: bytes, known: Collection[str] | None = None, recognised: Collection[str] = ()
) -> list[Instruction]:
    """Read a complete HP-GL byte string into Instructions (label terminator changes by DT are followed).

    Device-control sequences are not HP-GL and must not be in ``data``.  The end of the data ends the
    last instruction, as a ``;`` would.  A label comes back as one LB instruction with all its text.
    """
    reader = InstructionReader(SYNTAX if known is None else known, recognised)
    buf = bytes(data)
    out: list[Instruction] = []
    ended = False
    while buf:
        continuing = reader.in_label
        n, item = reader.read(buf)
        if n == 0 and item is None:
            if not ended:
                buf, ended = buf + b";", True
                continue
            n, item = reader.read(buf, full=True)
        buf = buf[n:]
        if item is not None:
            if continuing and item.mnemonic == "LB" and out and out[-1].mnemonic == "LB":
                item = _joined(out.pop(), item)
            out.append(item)
            if item.mnemonic == "DT" and not item.error:
                reader.label_terminator = ord(item.text) if item.text else ETX
    return out


def _joined(first: Instruction, more: Instruction) -> Instruction:
    """One LB instruction from two consecutive runs of the same label."""
    return Instruction("LB", text=first.text + more.text, offset=first.offset)


# -- device control ---------------------------------------------------------------------------

DEVICE_CONTROL_LETTERS = "@BEHIJKLMNOR()YZ"
"""Letters that may follow ``ESC .`` (7470A manual p. 10-23)."""
DEVICE_CONTROL_MAX_PARAMS = {"@": 2, "H": 12, "I": 12, "M": 6, "N": 11}
"""Letters that take parameters, with how many (block size, ENQ, up to 10 ACK characters for H/I)."""


@dataclass(frozen=True)
class DeviceControl:
    """A complete ``ESC . letter [params] :`` sequence: ``params`` None where a parameter was left out.

    ``error`` is the RS-232 error it raised while being read (0; 11 bad letter; 12 bad byte inside the
    parameters, which ended the sequence with the rest defaulted; 14 too many parameters, extras ignored).
    """

    letter: str
    params: tuple[int | None, ...] = ()
    error: int = 0

    def __str__(self) -> str:
        body = ";".join("" if p is None else str(p) for p in self.params)
        return f"ESC.{self.letter}{body + ':' if self.letter in DEVICE_CONTROL_MAX_PARAMS else ''}"


class DeviceControlReader:
    """Byte-at-a-time reader of ``ESC .`` sequences, fed only while a sequence is open.

    ``start()`` is called on ESC; ``feed(byte)`` returns ``(sequence or None, reprocess)`` where
    ``reprocess`` says the byte did not belong to the sequence and must be handled as ordinary data.
    """

    def __init__(self) -> None:
        self.active = False
        self._stage = 0  # 0: after ESC, 1: after '.', 2: in parameters
        self._letter = ""
        self._params: list[int | None] = []
        self._digits = ""
        self._too_many = False

    def start(self) -> None:
        """An ESC arrived: begin a sequence (a sequence already open is abandoned)."""
        self.active = True
        self._stage = 0
        self._letter = ""
        self._params = []
        self._digits = ""
        self._too_many = False

    def feed(self, byte: int) -> tuple[DeviceControl | None, bool]:
        """Advance the open sequence by one byte (see the class docstring)."""
        if self._stage == 0:
            if byte == 0x2E:
                self._stage = 1
                return None, False
            self.active = False
            return None, True  # ESC not followed by '.': the byte is data
        if self._stage == 1:
            letter = chr(byte)
            if letter not in DEVICE_CONTROL_LETTERS:
                self.active = False
                return DeviceControl(letter if 0x20 < byte < 0x7F else f"\\x{byte:02x}", error=11), False
            if letter not in DEVICE_CONTROL_MAX_PARAMS:
                self.active = False
                return DeviceControl(letter), False
            self._letter = letter
            self._stage = 2
            return None, False
        if 0x30 <= byte <= 0x39:
            if len(self._digits) < 10:
                self._digits += chr(byte)
            return None, False
        if byte in (0x3B, 0x3A):  # ';' ends a parameter, ':' the sequence
            self._push()
            if byte == 0x3B:
                return None, False
            return self._finish(0), False
        if byte in (0x20,):  # spaces inside the parameter list are ignored
            return None, False
        if self._digits:
            self._push()
        self.active = False
        return self._finish(12), True

    def _push(self) -> None:
        value = int(self._digits) if self._digits else None
        self._digits = ""
        if len(self._params) < DEVICE_CONTROL_MAX_PARAMS[self._letter]:
            self._params.append(value)
        else:
            self._too_many = True

    def _finish(self, error: int) -> DeviceControl:
        self.active = False
        if not error and self._too_many:
            error = 14
        params = list(self._params)
        while params and params[-1] is None:
            params.pop()
        return DeviceControl(self._letter, tuple(params), error)

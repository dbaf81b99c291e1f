"""The EBB's USB side: bytes into command lines, dispatch through the command table, replies in both syntaxes.

Commands are ``\\r`` (or ``\\n``) terminated, case-insensitive, at most 255 characters (longer:
``!3 Err: RX Buffer overrun``).  A motion command that does not fit the FIFO blocks the USB parser, its
reply held back until it fits; while the parser is blocked the board reads only one more 64-byte USB
packet (``ready_to_receive`` goes low).  Replies in legacy syntax after an error: the error line ends in
``OK\\r\\n`` on fw >= 3.0 (ebb.html, "Returned Errors") and in ``\\r\\n`` before.  The parser itself takes
no time.
"""

from __future__ import annotations

import logging

from pixelpen.sim.plotters.ebb.machine import EbbMachine, MotionCommand
from pixelpen.sim.plotters.ebb.params import EbbError, ascii_digits, checksum, error_text, parse_params, split_name

__all__ = ["RX_BUF_SIZE", "USB_PACKET", "EbbParser"]

log = logging.getLogger("pixelpen.sim.plotters.ebb.board")
"""One logger for the whole board (its messages name the board, not the module that noticed)."""

RX_BUF_SIZE = 256
"""A command may be at most 255 characters plus its terminator."""
USB_PACKET = 64
"""Bytes the board buffers while its parser is blocked."""


class EbbParser(EbbMachine):
    """ProcessIO: host bytes into command lines, each parsed by its table entry and run by its handler."""

    @property
    def ready_to_receive(self) -> bool:
        """USB flow control: False once a blocked parser has a full 64-byte packet waiting."""
        return len(self._inbox) - self._inpos < USB_PACKET

    def _receive(self, data: bytes) -> None:
        """Host bytes over USB (never lost: a blocked board just stops reading them)."""
        self._catch_up()
        self.stats.bytes_received += len(data)
        self._inbox += data
        self._service()

    def _service(self) -> None:
        """Read USB bytes into commands and run them until the parser blocks."""
        while not self._dead:
            if self._blocked:
                if not self._fifo_has_room():
                    return
                cmd, reply = self._blocked.popleft()
                self._enqueue(cmd)
                self._emit(reply)
                continue
            if self._inpos >= len(self._inbox):
                self._inbox.clear()
                self._inpos = 0
                return
            c = self._inbox[self._inpos]
            self._inpos += 1
            self._byte(c)

    def _byte(self, c: int) -> None:
        if c in (0x0D, 0x0A):
            if self._in_cr:
                return
            self._in_cr = True
            line = self._line.decode("latin-1")
            self._line.clear()
            self._command(line)
        elif c == 0x08 and self._line:
            del self._line[-1]
            self._emit(b" \b")
        elif c >= 0x20:
            self._in_cr = False
            self._line.append(c)
            if len(self._line) >= RX_BUF_SIZE:
                self._line.clear()
                self._emit((error_text(3, self._fw3) + self._ending(error=True)).encode())
                log.warning("%s: command longer than %d bytes: !3 RX buffer overrun", self.model, RX_BUF_SIZE - 1)

    def _command(self, line: str) -> None:
        """Parse one command line and run it (or hold its reply while the FIFO is full)."""
        self.stats.commands_executed += 1
        self.log.append((self._now, line))
        if self._checksums:
            checked = self._strip_checksum(line)
            if checked is None:
                return
            line = checked
        name, rest = split_name(line) if line else ("\r", "")
        entry = self.COMMANDS.get(name)
        prefix = (name + ",") if self._future else ""
        if entry is None or self.version < entry.since:
            if len(name) == 1:
                text = f"!8 Err: Unknown command '{name}:{ord(name):02X}'"
            else:
                text = f"!8 Err: Unknown command '{name}:{ord(name[0]):02X}{ord(name[1]):02X}'"
            self._emit((prefix + text + self._ending(error=True)).encode())
            # a lone '#' is how drivers flush a half-received command (pixelpen's AxiDraw sends it on every
            # connect): the board answers it as unknown like any other, but it is expected, not a fault
            (log.debug if line == "#" else log.warning)("%s: unknown command %r", self.model, line)
            return
        try:
            values = parse_params(rest, entry.params, self._fw3)
            entry.handler(self, name, values)
        except EbbError as exc:
            self._emit((prefix + exc.text + self._ending(error=True)).encode())
            log.warning("%s: %r -> %s", self.model, line, exc.text)

    def _strip_checksum(self, line: str) -> str | None:
        cut = line.rfind(",")
        prefix = (split_name(line)[0] + ",") if self._future else ""
        if cut < 0 or not ascii_digits(line[cut + 1:]) or len(line) - cut - 1 > 3:
            self._emit((prefix + "!10 Err: No checksum found but required" + self._ending(error=True)).encode())
            return None
        expected = checksum(line[:cut])
        if int(line[cut + 1:]) != expected:
            text = f"!9 Err: Checksum incorrect, expected {expected}"
            self._emit((prefix + text + self._ending(error=True)).encode())
            return None
        return line[:cut]

    # ---- replies and the motion queue ------------------------------------------------------------
    def _ending(self, kind: str = "ok", error: bool = False) -> str:
        """print_line_ending: future '\\n'; legacy 'OK\\r\\n' (ack on), '\\r\\n' or '\\n\\r'."""
        if self._future:
            return "\n"
        if error:
            return ("OK\r\n" if self._ack else "\r\n") if self._fw3 else "\r\n"
        if kind == "ok":
            return ("OK" if self._ack else "") + "\r\n"
        return "\n\r" if kind == "rev" else "\r\n"

    def _reply(self, name: str, data: str | None = None, kind: str = "ok", legacy: str | None = None) -> None:
        """Answer in the current syntax: future ``NAME[,data]\\n``; legacy ``legacy`` or data + ending."""
        if self._future:
            self._emit(((name if data is None else f"{name},{data}") + "\n").encode())
        elif legacy is not None:
            self._emit(legacy.encode())
        elif data is None:
            self._emit(self._ending(kind).encode())
        else:
            self._emit((data + self._ending(kind)).encode())

    def _invalid(self) -> EbbError:
        """The !6 error (invalid parameter value) in this firmware's spelling, to raise."""
        return EbbError(6, error_text(6, self._fw3))

    def _fifo_has_room(self) -> bool:
        return len(self._fifo) < self._fifo_size or (self._exec is None and not self._fifo)

    def _enqueue(self, cmd: MotionCommand) -> None:
        self._fifo.append(cmd)
        self._start_next(self._now)

    def _queue(self, name: str, cmd: MotionCommand, reply: bool = True) -> None:
        """A motion-queue command: run it now if it fits, else block the parser, holding back its reply."""
        text = ((name + "\n") if self._future else self._ending("ok")) if reply else ""
        if not self._blocked and self._fifo_has_room():
            self._enqueue(cmd)
            self._emit(text.encode())
        else:
            self._blocked.append((cmd, text.encode()))

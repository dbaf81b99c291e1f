"""Tiny StreamDevices for transport tests: an echo-ish line device with a small buffer, and a scripted responder."""

from __future__ import annotations

from pixelpen.clock import Clock
from pixelpen.sim.base import Fault, SimulatedDevice

XON, XOFF = 0x11, 0x13


class EchoDevice(SimulatedDevice):
    """Line device: ``buffer_size`` bytes of input, drained at ``drain_rate`` bytes/s, answers ``reply`` per line.

    It records everything a transport test wants to check: every byte that arrived (``received``),
    bytes lost to a full buffer (``overflowed``), bytes that arrived while its handshake line was low
    (``arrived_while_busy``), executed bytes and lines, and the faults injected with the byte count
    at which each came.  With ``xonxoff`` it sends XOFF when free space falls to ``xoff_free`` and XON
    when it is back to ``xon_free``.
    """

    model = "echo"
    FAULTS = frozenset(Fault)

    def __init__(
        self,
        clock: Clock | None = None,
        *,
        buffer_size: int = 16,
        drain_rate: float = 1000.0,
        ready_free: int = 4,
        reply: bytes = b"OK\r",
        xonxoff: bool = False,
        xoff_free: int = 4,
        xon_free: int = 12,
        **options: str,
    ) -> None:
        super().__init__(clock)
        self.buffer_size = int(buffer_size)
        self.drain_interval = 1.0 / float(drain_rate)
        self.ready_free = ready_free
        self.reply = reply
        self.xonxoff = xonxoff
        self.xoff_free, self.xon_free = xoff_free, xon_free
        self.options = options
        self.buffer = bytearray()
        self.received = bytearray()
        self.executed = bytearray()
        self.lines: list[bytes] = []
        self.overflowed = 0
        self.arrived_while_busy = 0
        self.faults: list[tuple[str, int]] = []
        self._line = bytearray()
        self._next_drain: float | None = None
        self._xoff_sent = False

    @property
    def free(self) -> int:
        return self.buffer_size - len(self.buffer)

    @property
    def ready_to_receive(self) -> bool:
        return self.free >= self.ready_free

    def _receive(self, data: bytes) -> None:
        for b in data:
            self.received.append(b)
            if not self.ready_to_receive:
                self.arrived_while_busy += 1
            if len(self.buffer) >= self.buffer_size:
                self.overflowed += 1
                continue
            self.buffer.append(b)
            if self._next_drain is None:
                self._next_drain = self._now + self.drain_interval
            if self.xonxoff and not self._xoff_sent and self.free <= self.xoff_free:
                self._emit(bytes([XOFF]))
                self._xoff_sent = True

    def _next_internal_event(self) -> float | None:
        return self._next_drain

    def _handle_event(self, t: float) -> None:
        """Execute one byte from the buffer (a line end answers ``reply``)."""
        self._now = t
        b = self.buffer.pop(0)
        self.executed.append(b)
        if b in b"\r\n":
            if self._line:
                self.lines.append(bytes(self._line))
                self._emit(self.reply)
            self._line.clear()
        else:
            self._line.append(b)
        self._next_drain = self._now + self.drain_interval if self.buffer else None
        if self.xonxoff and self._xoff_sent and self.free >= self.xon_free:
            self._emit(bytes([XON]))
            self._xoff_sent = False

    def _apply_fault(self, fault: Fault) -> None:
        self.faults.append((fault.value, len(self.received)))

    def _ignore(self, data: bytes) -> None:
        self.received += data  # a closed echo device still shows what reached it

    def say(self, data: bytes) -> None:
        """Make the device send ``data`` unprompted (tests of the device-to-host direction)."""
        self._emit(data)


class ScriptedDevice(SimulatedDevice):
    """A StreamDevice that answers fixed requests: when its input ends with a key, it sends the value."""

    model = "scripted"
    FAULTS = frozenset(Fault)

    def __init__(self, replies: dict[bytes, bytes], clock: Clock | None = None) -> None:
        super().__init__(clock)
        self.replies = replies
        self.received = bytearray()
        self.faults: list[str] = []

    def _receive(self, data: bytes) -> None:
        self.received += data
        for request, reply in self.replies.items():
            if self.received.endswith(request):
                self._emit(reply)

    def _next_internal_event(self) -> float | None:
        return None

    def _handle_event(self, t: float) -> None:
        """Never called: nothing is ever scheduled."""

    def _apply_fault(self, fault: Fault) -> None:
        self.faults.append(fault.value)


class DeviceRig:
    """A simulator on a simulated clock, driven byte-exactly: send bytes, run time, settle."""

    def __init__(self, dev, clock) -> None:
        self.dev, self.clock = dev, clock

    def send(self, data: bytes | str) -> bytes:
        """Feed host bytes; return what the device answered at once."""
        self.dev.receive(data.encode() if isinstance(data, str) else data)
        return self.dev.take_output()

    def run(self, seconds: float) -> bytes:
        """Let ``seconds`` of clock time pass; return what the device said meanwhile."""
        self.clock.advance(seconds)
        self.dev.advance_to(self.clock.now())
        return self.dev.take_output()

    def until_idle(self, limit: int = 100_000) -> bytes:
        """Jump from event to event until the device has nothing scheduled; return its output."""
        out = b""
        for _ in range(limit):
            te = self.dev.next_event_time()
            if te is None:
                return out + self.dev.take_output()
            self.clock.advance(te - self.clock.now())
            self.dev.advance_to(te)
            out += self.dev.take_output()
        raise AssertionError("simulator did not settle")

"""PtyBridge: a pseudo-terminal whose far end is a simulated device, so any program can open it by path.

``PtyBridge(device)`` opens a pty pair (raw mode), and a background thread copies bytes between
the master side and the device through a :class:`~pixelpen.sim.transports.port.SimPort`, which paces
them at ``baud`` and applies ``flow`` and the faults.  ``bridge.path`` (``/dev/pts/N``) opens with
``serial.Serial(path)``, ``screen``, or any plotting program that wants a tty.

A pty carries no modem lines, so the bridge plays the host's UART itself: with ``flow="rtscts"``
or ``"xonxoff"`` it holds its transmitter as the device asks (consuming XON/XOFF) and simply stops
reading the pty while its transmit buffer is full, so the program's writes block as they would on
a port with handshake; the program needs no flow-control setting of its own.  With a
SimulatedClock the bridge lets simulated time jump to the device's next event whenever the program
is quiet, so a simulated plot finishes as fast as the CPU allows.  ``drop_after`` closes the
master side: the program sees the hang-up (EIO) an unplugged USB adapter causes.

The bridge keeps no slave descriptor of its own, so it sees the program open and close the port (the
master reports a hang-up while no slave is open).  While nobody has the port open the device's output
goes nowhere, as on a cable with nothing at its end (what it says the moment a program opens the port
reaches the program).  Each open raises DTR: a device with
``resets_on_dtr`` (GRBL on an Arduino) reboots and greets the program with its banner.  Each close
saves the paper to ``out`` when one was given.
"""

from __future__ import annotations

import contextlib
import logging
import os
import select
import threading
from types import TracebackType

from pixelpen.clock import Clock, SimulatedClock
from pixelpen.errors import Disconnected, LinkError, PixelpenError
from pixelpen.sim.base import StreamDevice
from pixelpen.sim.transports.options import Faults
from pixelpen.sim.transports.port import SimPort

_log = logging.getLogger(__name__)
_MAX_IDLE = 0.05  # seconds the bridge sleeps at most before looking at the clock again
_QUIET = 0.002  # real seconds of silence after which a simulated clock may jump


class PtyBridge:
    """A pty pair whose master end feeds a StreamDevice through a SimPort (see the module docstring)."""

    def __init__(
        self,
        device: StreamDevice,
        *,
        flow: str = "none",
        baud: int | None = None,
        faults: Faults | None = None,
        tx_buffer: int = 4096,
        clock: Clock | None = None,
        out: str | None = None,
    ) -> None:
        self.port = SimPort(device, baud=baud, flow=flow, faults=faults, tx_buffer=tx_buffer, clock=clock, out=out)
        self.device = device
        self.error: BaseException | None = None
        """The exception that stopped the bridge thread, if any (Disconnected after ``drop_after``)."""
        try:
            import tty

            self._master, self._slave = os.openpty()
        except (ImportError, AttributeError) as exc:
            self.port.close()
            raise LinkError(f"PtyBridge needs POSIX pseudo-terminals: {exc}") from exc
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.path = os.ttyname(self._slave)
        """Path of the slave side, for the program to open."""
        os.close(self._slave)  # the program's open and close show as the master's hang-up clearing and returning
        self._slave = -1
        self.opens = 0
        """How many times a program opened the port."""
        self._host_open = False
        self._wake_r, self._wake_w = os.pipe()
        self._stop = threading.Event()
        self._fd_lock = threading.Lock()
        self._closed = False
        self._thread = threading.Thread(target=self._run, name=f"PtyBridge {self.path}", daemon=True)
        self._thread.start()

    @property
    def program_connected(self) -> bool:
        """True while the bridge sees a program holding the port open (a close and reopen within one pass,
        about 50 ms, count as one session)."""
        return self._host_open

    @property
    def running(self) -> bool:
        """True while the bridge thread copies bytes."""
        return self._thread.is_alive()

    def close(self) -> None:
        """Stop the thread, close the pty and the device; idempotent."""
        if self._closed:
            return
        self._closed = True
        self._stop.set()
        os.write(self._wake_w, b"x")
        self._thread.join(timeout=5.0)
        self._close_pty()
        for fd in (self._wake_r, self._wake_w):
            os.close(fd)
        self.port.close()

    def __enter__(self) -> PtyBridge:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def _close_pty(self) -> None:
        with self._fd_lock:
            for name in ("_master", "_slave"):
                fd = getattr(self, name)
                if fd >= 0:
                    os.close(fd)
                    setattr(self, name, -1)

    def _run(self) -> None:
        try:
            self._pump()
        except Disconnected as exc:
            self.error = exc
            _log.info("%s: %s; hanging up the pty", self.path, exc)
            self._close_pty()
        except Exception as exc:  # noqa: BLE001 - a failing device or pty stops the bridge; the owner finds it in .error
            self.error = exc
            _log.error("%s: bridge stopped: %s: %s; hanging up the pty", self.path, type(exc).__name__, exc)
            self._close_pty()

    def _program_present(self) -> bool:
        """Whether a program has the slave open now; notes opens (DTR reset) and closes (paper saved)."""
        hangup = select.poll()
        hangup.register(self._master, select.POLLHUP)
        present = not hangup.poll(0)
        if present and not self._host_open:
            self.opens += 1
            self.port.host_opened()
        elif self._host_open and not present:
            try:
                self.port.save_out()
            except PixelpenError as exc:  # the bridge serves on; the owner's own save reports it again
                _log.error("%s: %s", self.path, exc)
        self._host_open = present
        return present

    def _pump(self) -> None:
        port, clock = self.port, self.port.clock
        simulated = isinstance(clock, SimulatedClock)
        to_program = bytearray()
        fast_forward = False  # simulated clock: the program has been quiet, so jump from event to event
        while not self._stop.is_set():
            pending = b"" if self._host_open else port.take_pending()  # taken first: nothing said meanwhile is lost
            if not self._program_present():  # nobody at the end of the cable: what the device says is gone
                to_program.clear()
                self._stop.wait(_MAX_IDLE)
                continue
            to_program += pending
            incoming = port.read(65536, 0.0)
            if incoming:
                to_program += incoming
                fast_forward = False  # give the program real time to react to what it gets
            if to_program:
                with contextlib.suppress(BlockingIOError):
                    del to_program[: os.write(self._master, to_program)]
            space = port.tx_space
            nxt = port.next_event_time()
            now = clock.now()
            if simulated:
                wait = 0.0 if fast_forward and nxt is not None else _QUIET
            else:
                wait = _MAX_IDLE if nxt is None else min(max(nxt - now, 0.0005), _MAX_IDLE)
            readers = [self._wake_r] + ([self._master] if space > 0 else [])
            writers = [self._master] if to_program else []
            readable, _, _ = select.select(readers, writers, [], wait)
            if self._master in readable:
                try:
                    data = os.read(self._master, space)
                except (BlockingIOError, OSError):  # EIO: the program closed the port meanwhile
                    data = b""
                if data:
                    port.write(data, 0.0)
                    fast_forward = False
                    continue
            if simulated and not readable and nxt is not None:
                clock.advance(nxt - now)  # type: ignore[attr-defined]
                fast_forward = True

"""Keys typed while a command runs, read by a thread: ``p`` or space toggles a pause, Enter answers a prompt."""

from __future__ import annotations

import os
import select
import threading
from collections.abc import Callable
from typing import Any

PAUSE_KEYS = b"p "
ENTER_KEYS = b"\r\n"


class KeyControl:
    """Keys typed while a plot runs, read from ``fd`` by a thread: ``p`` or space toggles a pause, Enter answers.

    A terminal is put in cbreak mode (keys arrive without Enter, Ctrl-C still interrupts) and restored by
    :meth:`close`.  The pause is only a request: the plotter stops at its next pen-up.
    """

    def __init__(self, fd: int, on_toggle: Callable[[bool], None] | None = None) -> None:
        self.fd = fd
        self.on_toggle = on_toggle
        self.paused = False
        self.eof = False
        self._enters = 0
        self._typed = threading.Condition()
        self._stop = threading.Event()
        self._saved: list[Any] | None = None
        if os.isatty(fd):
            import termios
            import tty

            self._saved = termios.tcgetattr(fd)
            tty.setcbreak(fd)
        self._thread = threading.Thread(target=self._run, name="pixelpen plot keys", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            ready, _, _ = select.select([self.fd], [], [], 0.1)
            if not ready:
                continue
            try:
                data = os.read(self.fd, 64)
            except OSError:
                data = b""
            if not data:
                with self._typed:
                    self.eof = True
                    self._typed.notify_all()
                return
            for byte in data:
                if byte in PAUSE_KEYS:
                    self.paused = not self.paused
                    if self.on_toggle is not None:
                        self.on_toggle(self.paused)
                elif byte in ENTER_KEYS:
                    with self._typed:
                        self._enters += 1
                        self._typed.notify_all()

    def pause_requested(self) -> bool:
        """True while the operator wants the plot paused."""
        return self.paused

    def wait_enter(self) -> bool:
        """Wait for Enter typed from now on (an earlier one does not count); False when the input ended instead."""
        with self._typed:
            before = self._enters
            while self._enters == before and not self.eof:
                self._typed.wait(0.1)  # with a timeout, so that Ctrl-C gets through
            return self._enters != before

    def close(self) -> None:
        """Stop reading and restore the terminal."""
        self._stop.set()
        self._thread.join(timeout=1.0)
        if self._saved is not None:
            import termios

            termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)
            self._saved = None

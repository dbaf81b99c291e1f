"""The live view: a local web page that shows a simulator's paper or glass as it changes, its counters beside it.

Standard library only: ``http.server.ThreadingHTTPServer`` serves ``/`` (one page, inline script and style),
``/frame.png`` (the latest frame), ``/stats.json`` and ``/events`` (server-sent events: one JSON message
``{"frame": N, "stats": {...}}`` whenever the frame or the counters change).  The view runs on wall time
(a person watches it) and is bounded: loopback unless a remote host is allowed, at most ``max_clients``
event streams, at most ``max_fps`` frames encoded a second however fast the device draws (changes coalesce).
"""

from __future__ import annotations

import contextlib
import html
import io
import ipaddress
import itertools
import json
import logging
import socket
import threading
from collections.abc import Generator
from dataclasses import asdict, dataclass, is_dataclass
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any, Protocol, cast, runtime_checkable
from urllib.parse import urlsplit

from PIL import Image

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.errors import ConfigError

__all__ = ["Frame", "PanelSource", "PlotterSource", "ViewServer", "ViewSource", "is_loopback", "source_for"]

log = logging.getLogger(__name__)

MAX_CLIENTS = 8
"""Event streams served at once by default (one per open page); more are answered 503."""
MAX_FPS = 10.0
"""Frames encoded a second at most by default."""
KEEPALIVE_S = 5.0
"""Seconds between comment lines on a quiet event stream (a closed page is noticed at the next one)."""
PLOTTER_DPI = 72.0
"""Resolution of a plotter's paper in the view (an A3 sheet is 1191 x 842 pixels)."""

Stats = dict[str, int | float | str]


@runtime_checkable
class ViewSource(Protocol):
    """What the live view shows: a picture that changes, and counters by name.

    ``version()`` is called on every tick of the view (up to ``max_fps`` times a second) and must be cheap:
    an int that differs from the previous call's whenever the picture may have changed (a counter or a
    fingerprint).  ``picture()`` is called only after such a change.  ``stats()`` returns JSON-ready numbers.
    All three are called from the view's own threads, so a source guards a device another thread drives.
    """

    title: str

    def version(self) -> int:
        """A cheap token of the picture's state (see the class doc)."""

    def picture(self) -> Image.Image:
        """What the device shows now."""

    def stats(self) -> Stats:
        """The device's counters (bytes, transfers, seconds, ...) by name."""


def _counters(stats: object) -> Stats:
    """A dataclass of counters as a dict of plain numbers (an empty dict for anything else)."""
    if not is_dataclass(stats) or isinstance(stats, type):
        return {}
    return {k: v for k, v in asdict(stats).items() if isinstance(v, (int, float, str))}


class PlotterSource:
    """A plotter simulator's paper (``paper_image(dpi)``) and its wire counters (``stats``) as a ViewSource.

    The version is a fingerprint of the counters and of the ink (a Sheet's strokes, or the HP-GL
    plotter's ``segments()``), so the paper is rendered only when something was drawn.  ``lock`` is held
    around every look at the device (the pty bridge drives it from another thread).
    """

    def __init__(self, device: Any, *, lock: threading.Lock | threading.RLock | None = None,
                 dpi: float = PLOTTER_DPI) -> None:
        self.device = device
        self.title = f"{device.model} paper"
        self.dpi = dpi
        self._lock = lock if lock is not None else threading.Lock()

    def _ink(self) -> tuple[int, ...]:
        """How much ink is on the paper: strokes and points, or HP-GL segments."""
        paper: Any = getattr(self.device, "paper", None)
        if callable(getattr(paper, "strokes", None)):
            strokes = paper.strokes()
            return (len(strokes), sum(len(points) for _, points in strokes), int(paper.pen_is_down))
        segments = getattr(self.device, "segments", None)
        return (len(segments()[0]),) if callable(segments) else ()

    def version(self) -> int:
        """A hash of the counters and the amount of ink."""
        with self._lock:
            return hash((tuple(_counters(self.device.stats).values()), self._ink()))

    def picture(self) -> Image.Image:
        """The paper rendered at ``dpi``."""
        with self._lock:
            canvas = self.device.paper_image(self.dpi)
        return cast(Image.Image, canvas.to_image())

    def stats(self) -> Stats:
        """The simulator's ``stats`` counters (WireStats, or the HP-GL PlotterStats)."""
        with self._lock:
            return _counters(getattr(self.device, "stats", None))


class PanelSource:
    """A panel simulator's ``glass()``, its ``stats`` (BusStats) and ``events`` count as a ViewSource.

    A panel is small, so the version is a hash of the glass itself (whatever changed it: bus bytes, a
    reset, the end of a sleep-out delay); the glass taken for it is kept for ``picture``.
    """

    def __init__(self, device: Any, *, lock: threading.Lock | threading.RLock | None = None) -> None:
        self.device = device
        self.title = f"{device.model} glass"
        self._lock = lock if lock is not None else threading.Lock()
        self._glass: Image.Image | None = None

    def version(self) -> int:
        """A hash of what the glass shows."""
        with self._lock:
            glass = self.device.glass()
        self._glass = glass
        return hash((glass.mode, glass.size, glass.tobytes()))

    def picture(self) -> Image.Image:
        """The glass seen by the last ``version()`` call (taken now if there was none)."""
        if self._glass is None:
            self.version()
        return cast(Image.Image, self._glass)

    def stats(self) -> Stats:
        """BusStats (bytes, transfers, bus_seconds, frames, ...), ``events``: how many the controller flagged.

        ``events`` counts the kept log and ``events_dropped`` (shown too when the device counts drops: a
        panel simulator keeps only the latest ``EVENT_LOG_LIMIT``).  A framebuffer simulator has its own
        counters (ioctls, pans, ...) and no event log.
        """
        with self._lock:
            out = _counters(getattr(self.device, "stats", None))
            dropped = getattr(self.device, "events_dropped", None)
            count = getattr(self.device, "event_count", None)  # a PanelSim's, without copying its log
            if count is None and getattr(self.device, "events", None) is not None:
                count = len(self.device.events) + (dropped or 0)
            if count is not None:
                out["events"] = count
            if dropped is not None:
                out["events_dropped"] = dropped
        return out


def source_for(device: Any, *, lock: threading.Lock | threading.RLock | None = None) -> ViewSource:
    """The ViewSource of a simulator: its glass (a panel), or its paper (a plotter); ConfigError otherwise."""
    if callable(getattr(device, "glass", None)):
        return PanelSource(device, lock=lock)
    if callable(getattr(device, "paper_image", None)):
        return PlotterSource(device, lock=lock)
    raise ConfigError(f"{getattr(device, 'model', device)!r}: nothing to view (neither glass() nor paper_image())")


def is_loopback(host: str) -> bool:
    """True for ``localhost`` and loopback addresses (127.0.0.0/8, ::1)."""
    name = host.strip("[]").lower()
    if name == "localhost":
        return True
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return False


@dataclass(frozen=True)
class Frame:
    """One encoded picture: its number (1, 2, ... in order of change), PNG bytes and size in pixels."""

    number: int
    png: bytes
    size: tuple[int, int]


def encode_png(picture: Image.Image) -> bytes:
    """``picture`` as PNG bytes (fast compression: frames are many and local)."""
    buf = io.BytesIO()
    image = picture if picture.mode in ("1", "L", "RGB", "RGBA") else picture.convert("RGB")
    image.save(buf, format="PNG", compress_level=1)
    return buf.getvalue()


class ViewServer:
    """The live-view web server of one ViewSource (see the module doc); ``start()`` serves, ``close()`` stops.

    ``poll()`` looks at the source once (the server's own thread calls it ``max_fps`` times a second):
    a new frame is encoded when the version changed and the last encode is at least ``1/max_fps``
    seconds old on ``clock``; otherwise the change waits for a later tick, so a burst of changes costs
    one encode.  A host that is not a loopback address is refused unless ``allow_remote``; so are
    requests from other machines and requests naming another host (DNS rebinding) when it is not.
    """

    def __init__(self, source: ViewSource, *, host: str = "127.0.0.1", port: int = 0, allow_remote: bool = False,
                 max_clients: int = MAX_CLIENTS, max_fps: float = MAX_FPS, clock: Clock = REAL_CLOCK) -> None:
        if not is_loopback(host) and not allow_remote:
            raise ConfigError(f"live view: {host} is not a loopback address, so the page would be open to the "
                              f"network; give the host explicitly to allow it (pixelpen sim ... --host {host})")
        if not (isinstance(max_clients, int) and max_clients >= 1):
            raise ConfigError(f"live view: max_clients must be a positive integer, got {max_clients!r}")
        if not (isinstance(max_fps, (int, float)) and 0 < max_fps <= 1000):
            raise ConfigError(f"live view: max_fps must be in (0, 1000], got {max_fps!r}")
        self.source = source
        self.allow_remote = allow_remote
        self.max_clients = max_clients
        self.max_fps = float(max_fps)
        self.clock = clock
        self._poll_lock = threading.Lock()
        self._changed = threading.Condition()
        self._version: int | None = None
        self._encoded_at = 0.0
        self._frame: Frame | None = None
        self._stats: Stats | None = None
        self._sequence = 0
        self._clients = 0
        self._closed = threading.Event()
        self._threads: list[threading.Thread] = []
        try:
            self._httpd = _HTTPServer((host, port), _Handler, self)
        except OSError as exc:
            raise ConfigError(f"live view: cannot listen on {host}:{port}: {exc.strerror or exc}") from None
        self.host = host
        self.port = int(self._httpd.server_address[1])

    @property
    def url(self) -> str:
        """The page's address."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    @property
    def clients(self) -> int:
        """Event streams being served now."""
        with self._changed:
            return self._clients

    @property
    def closed(self) -> bool:
        """True once ``close`` was called."""
        return self._closed.is_set()

    # ---- the picture and counters ----------------------------------------------------------------
    def poll(self) -> int:
        """Look at the source once (see the class doc); returns the current frame number."""
        with self._poll_lock:
            version = self.source.version()
            frame = self._frame
            now = self.clock.now()
            if version != self._version and (frame is None or now - self._encoded_at >= 1.0 / self.max_fps):
                picture = self.source.picture()
                png = encode_png(picture)
                self._version, self._encoded_at = version, now
                if frame is None or png != frame.png:
                    frame = Frame(frame.number + 1 if frame else 1, png, picture.size)
            stats = self.source.stats()
            if frame is not self._frame or stats != self._stats:
                with self._changed:
                    self._frame, self._stats = frame, stats
                    self._sequence += 1
                    self._changed.notify_all()
            return cast(Frame, frame).number  # the first poll always encodes

    def frame(self) -> Frame:
        """The latest frame (polling the source first if none was encoded yet)."""
        if self._frame is None:
            self.poll()
        return cast(Frame, self._frame)

    def stats(self) -> Stats:
        """The latest counters (polling the source first if they were never read)."""
        if self._stats is None:
            self.poll()
        return dict(cast(Stats, self._stats))

    def updates(self, timeout: float = KEEPALIVE_S) -> Generator[dict[str, Any] | None, None, None]:
        """The messages of one event stream: the state now, then each change (None after ``timeout`` quiet seconds).

        Ends when the server closes.  The caller counts as a client while it iterates; ConfigError when
        ``max_clients`` are being served already.
        """
        with self._changed:
            if self._clients >= self.max_clients:
                raise ConfigError(f"live view {self.url}: at most {self.max_clients} pages may watch at once")
            self._clients += 1
        try:
            self.frame()
            seen = -1
            while not self.closed:
                with self._changed:
                    if self._sequence == seen:
                        self._changed.wait(timeout)
                    if self.closed:
                        return
                    if self._sequence == seen:
                        message = None
                    else:
                        seen = self._sequence
                        message = {"frame": cast(Frame, self._frame).number, "stats": self._stats}
                yield message
        finally:
            with self._changed:
                self._clients -= 1
                self._changed.notify_all()

    def page(self) -> bytes:
        """The HTML page (inline script and style, no other assets)."""
        return PAGE.replace("{{TITLE}}", html.escape(self.source.title)).encode()

    # ---- running -----------------------------------------------------------------------------------
    def start(self) -> ViewServer:
        """Serve in background threads: the HTTP server and the ticker that polls the source."""
        if self._threads:
            return self
        self.poll()
        self._threads = [threading.Thread(target=self._httpd.serve_forever, kwargs={"poll_interval": 0.1},
                                          name="view-http", daemon=True),
                         threading.Thread(target=self._tick, name="view-poll", daemon=True)]
        for thread in self._threads:
            thread.start()
        log.info("live view of %s on %s", self.source.title, self.url)
        return self

    def _tick(self) -> None:
        """Poll the source ``max_fps`` times a second until closed."""
        while not self._closed.wait(1.0 / self.max_fps):
            self.poll()

    def close(self, timeout: float = 5.0) -> None:
        """Stop serving: event streams end, the listening socket closes, the threads are joined (idempotent)."""
        if self._closed.is_set():
            return
        self._closed.set()
        with self._changed:
            self._changed.notify_all()
        if self._threads:
            self._httpd.shutdown()
        self._httpd.server_close()
        for thread in self._threads:
            thread.join(timeout)
        with self._changed:
            self._changed.wait_for(lambda: self._clients == 0, timeout)

    def __enter__(self) -> ViewServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- who may ask -------------------------------------------------------------------------------
    def refusal(self, peer: str, host_header: str | None) -> str | None:
        """Why a request from ``peer`` naming ``host_header`` is refused (None: it is served)."""
        if self.allow_remote:
            return None
        if not is_loopback(peer):
            return f"live view: {peer} is another machine; this view serves {self.host} only"
        if host_header:
            name = urlsplit(f"//{host_header}").hostname or ""
            if not is_loopback(name) and name != self.host:
                return f"live view: the request names host {name!r}; this view serves {self.host} only"
        return None


class _HTTPServer(ThreadingHTTPServer):
    """The HTTP server, knowing its ViewServer."""

    daemon_threads = True

    def __init__(self, address: tuple[str, int], handler: type[BaseHTTPRequestHandler], view: ViewServer) -> None:
        self.view = view
        if ":" in address[0]:
            self.address_family = socket.AF_INET6
        super().__init__(address, handler)


class _Handler(BaseHTTPRequestHandler):
    """GET /, /frame.png, /stats.json, /events; anything else 404 (other methods 501, from the base class)."""

    server_version = "pixelpen-view"

    @property
    def view(self) -> ViewServer:
        return cast(_HTTPServer, self.server).view

    def log_message(self, format: str, *args: Any) -> None:
        log.debug("%s %s", self.address_string(), format % args)

    def do_GET(self) -> None:
        """Answer one GET."""
        refusal = self.view.refusal(self.client_address[0], self.headers.get("Host"))
        if refusal is not None:
            self._send(HTTPStatus.FORBIDDEN, "text/plain; charset=utf-8", refusal.encode())
            return
        path = urlsplit(self.path).path
        if path == "/":
            self._send(HTTPStatus.OK, "text/html; charset=utf-8", self.view.page())
        elif path == "/frame.png":
            frame = self.view.frame()
            self._send(HTTPStatus.OK, "image/png", frame.png, {"X-Frame": str(frame.number)})
        elif path == "/stats.json":
            self._send(HTTPStatus.OK, "application/json", json.dumps(self.view.stats()).encode())
        elif path == "/events":
            self._stream()
        else:
            self._send(HTTPStatus.NOT_FOUND, "text/plain; charset=utf-8", f"no page {path!r}".encode())

    def _send(self, status: HTTPStatus, kind: str, body: bytes, headers: dict[str, str] | None = None) -> None:
        self.send_response(status)
        self.send_header("Content-Type", kind)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("Content-Security-Policy", CSP)
        for name, value in (headers or {}).items():
            self.send_header(name, value)
        self.end_headers()
        self.wfile.write(body)

    def _stream(self) -> None:
        """The event stream: one ``data:`` JSON message per change, a comment line when quiet."""
        messages = self.view.updates()
        try:
            first = next(messages)
        except ConfigError as exc:
            self._send(HTTPStatus.SERVICE_UNAVAILABLE, "text/plain; charset=utf-8", str(exc).encode())
            return
        except StopIteration:  # closed meanwhile
            self._send(HTTPStatus.SERVICE_UNAVAILABLE, "text/plain; charset=utf-8", b"live view: closed")
            return
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        with contextlib.closing(messages), contextlib.suppress(BrokenPipeError, ConnectionResetError):
            for message in itertools.chain([first], messages):
                line = ": quiet\n\n" if message is None else f"data: {json.dumps(message)}\n\n"
                self.wfile.write(line.encode())
                self.wfile.flush()


CSP = ("default-src 'none'; img-src 'self'; connect-src 'self'; script-src 'unsafe-inline'; "
       "style-src 'unsafe-inline'")
"""The page loads nothing from anywhere else."""

PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{{TITLE}} · pixelpen</title>
<style>
body { font: 14px system-ui, sans-serif; margin: 1em; display: flex; gap: 2em; align-items: flex-start; }
#frame { image-rendering: pixelated; border: 1px solid #888; max-width: 80vw; background: #222; }
table { border-collapse: collapse; } th { text-align: left; padding-right: 1em; font-weight: normal; color: #555; }
td { font-family: monospace; text-align: right; } #status { color: #888; }
</style></head>
<body><img id="frame" alt="{{TITLE}}" data-frame="0">
<div><h1 style="font-size: 1.2em">{{TITLE}}</h1><table id="stats"></table><p id="status">connecting</p></div>
<script>
"use strict";
const img = document.getElementById("frame"), table = document.getElementById("stats");
const status = document.getElementById("status");
let wanted = 0, loading = false;
function load() {
  if (loading || wanted === Number(img.dataset.frame)) return;
  loading = true;
  const n = wanted, next = new Image();
  next.onload = () => {
    img.src = next.src; img.dataset.frame = String(n); loading = false;
    const zoom = Math.max(1, Math.floor(Math.min(640 / next.naturalWidth, 480 / next.naturalHeight)));
    img.style.width = (next.naturalWidth * zoom) + "px";
    load();
  };
  next.onerror = () => { loading = false; };
  next.src = "/frame.png?n=" + n;
}
function show(stats) {
  table.replaceChildren(...Object.entries(stats).map(([name, value]) => {
    const row = document.createElement("tr"), th = document.createElement("th"), td = document.createElement("td");
    th.textContent = name;
    td.textContent = typeof value === "number" && !Number.isInteger(value) ? value.toFixed(3) : String(value);
    row.append(th, td);
    return row;
  }));
}
const events = new EventSource("/events");
events.onopen = () => { status.textContent = "live"; };
events.onerror = () => { status.textContent = "disconnected (retrying)"; };
events.onmessage = (e) => { const m = JSON.parse(e.data); show(m.stats); wanted = m.frame; load(); };
</script></body></html>
"""
"""The page: the frame, scaled up by whole pixels for small panels, and the counters beside it."""

"""The live view server: its pages over real HTTP on an ephemeral port, its limits, shutdown and the device adapters."""

from __future__ import annotations

import http.client
import io
import json
import threading
import urllib.error
import urllib.request
from dataclasses import asdict, dataclass

import numpy as np
import pytest
from PIL import Image

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError
from pixelpen.sim.base import create_simulator
from pixelpen.sim.panels.base import BusStats
from pixelpen.sim.view import PanelSource, PlotterSource, ViewServer, ViewSource, is_loopback, source_for


class StubSource:
    """A picture the test sets, a version it bumps, counters it sets; counts the pictures taken."""

    title = "stub <glass>"

    def __init__(self, picture: Image.Image) -> None:
        self._picture = picture
        self._version = 0
        self.counters: dict[str, int | float | str] = {"bytes": 0, "transfers": 0}
        self.pictures_taken = 0

    def show(self, picture: Image.Image) -> None:
        self._picture = picture
        self._version += 1

    def version(self) -> int:
        return self._version

    def picture(self) -> Image.Image:
        self.pictures_taken += 1
        return self._picture

    def stats(self) -> dict[str, int | float | str]:
        return dict(self.counters)


def pattern(seed: int, size: tuple[int, int] = (24, 16)) -> Image.Image:
    """A random RGB picture (every pixel matters to the comparison)."""
    rng = np.random.default_rng(seed)
    return Image.fromarray(rng.integers(0, 256, (size[1], size[0], 3), dtype=np.uint8), "RGB")


def pixels(image: Image.Image) -> np.ndarray:
    return np.asarray(image.convert("RGB"))


def get(url: str, timeout: float = 10) -> tuple[int, dict[str, str], bytes]:
    try:
        with urllib.request.urlopen(url, timeout=timeout) as reply:
            return reply.status, dict(reply.headers), reply.read()
    except urllib.error.HTTPError as exc:
        return exc.code, dict(exc.headers), exc.read()


def read_event(stream: io.BufferedIOBase) -> dict | None:
    """The next SSE message's JSON (None for a keep-alive comment), read line by line as the format says."""
    lines = []
    while (line := stream.readline()) not in (b"\n", b""):
        lines.append(line.decode().rstrip("\n"))
    data = [line[len("data: "):] for line in lines if line.startswith("data: ")]
    return json.loads("\n".join(data)) if data else None


def next_message(stream: io.BufferedIOBase) -> dict:
    for _ in range(20):  # keep-alive comments come every few seconds on a quiet stream
        message = read_event(stream)
        if message is not None:
            return message
    raise AssertionError("no message on the event stream")


@pytest.fixture
def served():
    source = StubSource(pattern(1))
    with ViewServer(source, max_fps=50) as view:
        yield source, view


def test_the_stub_is_a_view_source():
    assert isinstance(StubSource(pattern(0)), ViewSource)


def test_the_page_is_one_self_contained_html_document(served):
    _, view = served
    status, headers, body = get(view.url)
    assert status == 200 and headers["Content-Type"].startswith("text/html")
    page = body.decode()
    assert page.startswith("<!DOCTYPE html>") and "stub &lt;glass&gt;" in page  # the title, escaped
    assert '<img id="frame"' in page and 'new EventSource("/events")' in page
    assert "http://" not in page and "https://" not in page and "<link" not in page and "src=\"http" not in page
    assert "default-src 'none'" in headers["Content-Security-Policy"]


def test_the_frame_is_the_sources_picture_as_png(served):
    _, view = served
    status, headers, body = get(view.url + "frame.png?n=1")
    assert status == 200 and headers["Content-Type"] == "image/png" and headers["X-Frame"] == "1"
    image = Image.open(io.BytesIO(body))
    assert image.format == "PNG" and image.size == (24, 16)
    np.testing.assert_array_equal(pixels(image), pixels(pattern(1)))


def test_stats_json_is_the_sources_counters(served):
    source, view = served
    source.counters.update(bytes=1234, bus_seconds=0.5)
    view.poll()
    status, headers, body = get(view.url + "stats.json")
    assert status == 200 and headers["Content-Type"] == "application/json"
    assert json.loads(body) == {"bytes": 1234, "transfers": 0, "bus_seconds": 0.5}


def test_the_event_stream_announces_a_changed_picture(served):
    source, view = served
    with urllib.request.urlopen(view.url + "events", timeout=10) as stream:
        assert stream.headers["Content-Type"] == "text/event-stream"
        assert next_message(stream) == {"frame": 1, "stats": {"bytes": 0, "transfers": 0}}
        source.counters["bytes"] = 99
        source.show(pattern(2))
        assert next_message(stream) == {"frame": 2, "stats": {"bytes": 99, "transfers": 0}}
    status, headers, body = get(view.url + "frame.png?n=2")
    assert status == 200 and headers["X-Frame"] == "2"
    np.testing.assert_array_equal(pixels(Image.open(io.BytesIO(body))), pixels(pattern(2)))


def test_changes_coalesce_into_at_most_one_encode_per_interval():
    clock = SimulatedClock()
    source = StubSource(pattern(1))
    view = ViewServer(source, max_fps=10, clock=clock)
    try:
        assert view.poll() == 1 and source.pictures_taken == 1
        for seed in range(2, 7):  # five changes within one tenth of a second: nothing encoded yet
            source.show(pattern(seed))
            assert view.poll() == 1
        clock.advance(0.099)
        assert view.poll() == 1 and source.pictures_taken == 1
        clock.advance(0.001)
        assert view.poll() == 2 and source.pictures_taken == 2  # only the last picture is encoded
        np.testing.assert_array_equal(pixels(Image.open(io.BytesIO(view.frame().png))), pixels(pattern(6)))
        clock.advance(1.0)
        assert view.poll() == 2 and source.pictures_taken == 2  # no change, no encode
    finally:
        view.close()


def test_a_change_that_leaves_the_picture_alike_is_no_new_frame():
    clock = SimulatedClock()
    source = StubSource(pattern(1))
    view = ViewServer(source, clock=clock)
    try:
        view.poll()
        source.show(pattern(1))
        clock.advance(1.0)
        assert view.poll() == 1 and source.pictures_taken == 2
    finally:
        view.close()


def test_new_counters_alone_are_a_message_with_the_same_frame():
    source = StubSource(pattern(1))
    view = ViewServer(source)
    try:
        messages = view.updates(timeout=0.01)
        assert next(messages) == {"frame": 1, "stats": {"bytes": 0, "transfers": 0}}
        assert next(messages) is None  # quiet: a keep-alive
        source.counters["transfers"] = 7
        view.poll()
        assert next(messages) == {"frame": 1, "stats": {"bytes": 0, "transfers": 7}}
        messages.close()
        assert view.clients == 0
    finally:
        view.close()


def test_event_streams_are_limited():
    view = ViewServer(StubSource(pattern(1)), max_clients=1).start()
    try:
        with urllib.request.urlopen(view.url + "events", timeout=10) as stream:
            next_message(stream)
            status, _, body = get(view.url + "events")
            assert status == 503 and b"at most 1 pages may watch at once" in body
            with pytest.raises(ConfigError, match="may watch at once"):
                next(view.updates())
            assert get(view.url + "frame.png")[0] == 200  # the pictures are still served
    finally:
        view.close()


@pytest.mark.parametrize("kwargs, needle", [
    ({"max_clients": 0}, "max_clients"),
    ({"max_fps": 0}, "max_fps"),
    ({"max_fps": float("nan")}, "max_fps"),
    ({"host": "0.0.0.0"}, "0.0.0.0 is not a loopback address"),
    ({"host": "192.0.2.1", "allow_remote": True}, "cannot listen on 192.0.2.1"),
])
def test_bad_settings_are_refused_naming_them(kwargs, needle):
    with pytest.raises(ConfigError, match=needle):
        ViewServer(StubSource(pattern(1)), **kwargs)


def test_an_explicit_remote_host_is_served():
    view = ViewServer(StubSource(pattern(1)), host="0.0.0.0", allow_remote=True).start()
    try:
        assert view.url == f"http://0.0.0.0:{view.port}/"
        assert get(f"http://127.0.0.1:{view.port}/stats.json")[0] == 200
        assert view.refusal("192.0.2.7", "pixelpen.example") is None
    finally:
        view.close()


def test_other_machines_and_other_host_names_are_refused(served):
    _, view = served
    assert "192.0.2.7 is another machine" in view.refusal("192.0.2.7", None)
    assert view.refusal("127.0.0.1", f"localhost:{view.port}") is None
    assert view.refusal("::1", f"[::1]:{view.port}") is None
    connection = http.client.HTTPConnection("127.0.0.1", view.port, timeout=10)
    connection.request("GET", "/frame.png", headers={"Host": "attacker.example"})
    reply = connection.getresponse()
    assert reply.status == 403 and b"names host 'attacker.example'" in reply.read()
    connection.close()


def test_unknown_pages_and_methods(served):
    _, view = served
    status, _, body = get(view.url + "nothing")
    assert status == 404 and b"'/nothing'" in body
    request = urllib.request.Request(view.url + "stats.json", data=b"{}", method="POST")
    with pytest.raises(urllib.error.HTTPError) as err:
        urllib.request.urlopen(request, timeout=10)
    assert err.value.code == 501


def test_close_ends_the_streams_and_the_listening_socket():
    view = ViewServer(StubSource(pattern(1))).start()
    stream = urllib.request.urlopen(view.url + "events", timeout=10)
    next_message(stream)
    assert view.clients == 1
    closer = threading.Thread(target=view.close)
    closer.start()
    closer.join(10)
    assert not closer.is_alive() and view.closed and view.clients == 0
    assert stream.read() == b""  # the stream ended
    stream.close()
    with pytest.raises(urllib.error.URLError):
        urllib.request.urlopen(view.url, timeout=5)
    view.close()  # idempotent


def test_loopback_names():
    assert all(is_loopback(h) for h in ("localhost", "127.0.0.1", "127.8.9.1", "::1", "[::1]", "LOCALHOST"))
    assert not any(is_loopback(h) for h in ("0.0.0.0", "192.0.2.1", "::", "example.com", ""))


# ---- the adapters ---------------------------------------------------------------------------------

def test_a_plotters_paper_and_counters():
    device = create_simulator("hp7475a")
    source = source_for(device)
    assert isinstance(source, PlotterSource) and source.title == "hp7475a paper"
    before = source.version()
    assert source.version() == before  # nothing happened
    device.receive(b"IN;SP1;PU1000,1000;PD3000,1000,3000,3000;PU;")
    device.advance_to(device.clock.now() + 30)
    assert source.version() != before
    assert source.stats() == asdict(device.stats) and source.stats()["commands_executed"] > 0
    picture = source.picture()
    assert picture.size == (842, 595)  # A4 landscape at 72 dpi
    dark = pixels(picture).min(axis=2) < 128
    assert dark.any() and dark.mean() < 0.01  # the two strokes, on white paper


def test_a_sheet_plotters_version_follows_its_ink():
    device = create_simulator("grbl")
    source = source_for(device)
    before = source.version()
    device.paper.pen_down(np.array([10.0, 10.0]))
    assert source.version() != before
    touched = source.version()
    device.paper.line_to(np.array([[20.0, 10.0]]))
    assert source.version() != touched


class StubPanel:
    """A panel simulator's public surface: model, glass(), stats, events."""

    model = "st7789"

    def __init__(self) -> None:
        self.image = Image.new("RGB", (8, 4))
        self.stats = BusStats()
        self.events: list[str] = []

    def glass(self) -> Image.Image:
        return self.image.copy()


def test_a_panels_glass_and_counters():
    panel = StubPanel()
    lock = threading.Lock()
    source = source_for(panel, lock=lock)
    assert isinstance(source, PanelSource) and source.title == "st7789 glass"
    first = source.version()
    assert source.version() == first
    panel.image.putpixel((3, 2), (255, 0, 0))
    assert source.version() != first
    np.testing.assert_array_equal(pixels(source.picture()), pixels(panel.image))
    panel.stats.bytes, panel.stats.bus_seconds, panel.stats.frames = 80, 1e-5, 1
    panel.events.append("RAMWR before SLPOUT")
    assert source.stats() == {"bytes": 80, "command_bytes": 0, "data_bytes": 0, "transfers": 0,
                              "bus_seconds": 1e-5, "frames": 1, "events": 1}


class StubPanelWithDrops(StubPanel):
    """A panel whose bounded event log counts what it dropped (as PanelSim does)."""

    events_dropped = 0


def test_a_panels_event_count_includes_the_dropped_ones():
    panel = StubPanelWithDrops()
    panel.events.extend(["RAMWR before SLPOUT"] * 3)
    panel.events_dropped = 7  # the log kept the latest 3 of 10
    stats = source_for(panel).stats()
    assert stats["events"] == 10 and stats["events_dropped"] == 7


def test_a_panel_simulators_event_count_goes_past_its_log():
    device = create_simulator("st7789")
    device.command(b"\xee" * 10_005)  # 10,005 undefined commands: one event each, the log keeps 10,000
    stats = source_for(device).stats()
    assert stats["events"] == 10_005 and stats["events_dropped"] == 5


def test_a_panels_picture_before_any_version_is_the_glass():
    panel = StubPanel()
    panel.image.putpixel((0, 0), (1, 2, 3))
    np.testing.assert_array_equal(pixels(PanelSource(panel).picture()), pixels(panel.image))


def test_a_device_with_nothing_to_show_is_refused():
    class Modem:
        model = "modem"

    with pytest.raises(ConfigError, match="'modem': nothing to view"):
        source_for(Modem())


def test_the_source_lock_is_held_while_the_device_is_looked_at():
    panel = StubPanel()
    lock = threading.Lock()
    seen = []
    original = panel.glass
    panel.glass = lambda: (seen.append(lock.locked()), original())[1]
    PanelSource(panel, lock=lock).version()
    assert seen == [True]


@pytest.mark.parametrize("host, url_host", [("localhost", "localhost"), ("::1", "[::1]")])
def test_any_loopback_name_is_served(host, url_host):
    try:
        view = ViewServer(StubSource(pattern(1)), host=host).start()
    except ConfigError as exc:
        pytest.skip(f"this machine has no {host}: {exc}")
    try:
        assert view.url == f"http://{url_host}:{view.port}/"
        status, _, body = get(view.url + "stats.json")
        assert status == 200 and json.loads(body) == {"bytes": 0, "transfers": 0}
    finally:
        view.close()


def test_a_framebuffer_without_an_event_log_shows_its_own_counters():
    @dataclass
    class FbdevStats:
        ioctls: int = 3
        pans: int = 1

    class Framebuffer:
        model = "fbdev"
        stats = FbdevStats()

        def glass(self) -> Image.Image:
            return Image.new("RGB", (4, 4))

    assert source_for(Framebuffer()).stats() == {"ioctls": 3, "pans": 1}


def test_a_port_in_use_is_named():
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(ConfigError, match=f"cannot listen on 127.0.0.1:{port}"):
            ViewServer(StubSource(pattern(1)), port=port)


def test_a_closed_view_has_no_more_updates():
    view = ViewServer(StubSource(pattern(1)))
    view.close()
    assert list(view.updates()) == [] and view.clients == 0

"""HP 7475A / 7550A / 7440A driver against the simulators: wire bytes, paper, flow control, errors, pause, faults."""

from __future__ import annotations

import logging
import os
import re
from dataclasses import replace
from itertools import pairwise

import numpy as np
import pytest

import pixelpen
from pixelpen.clock import SimulatedClock
from pixelpen.devices.plotters.base import PlotInterrupted, PlotState, PositionUnknown
from pixelpen.devices.plotters.hpgl import HP7440A, HP7475A, HP7550A, HPGLDisplay
from pixelpen.display.registry import known_schemes
from pixelpen.drivers import discovery
from pixelpen.drivers.stream import Link
from pixelpen.errors import ConfigError, LinkError, LinkTimeout, PixelpenError, ProtocolError, URLError
from pixelpen.profiles.model import load_profile
from pixelpen.sim.base import create_simulator, forget_simulator, named_simulator
from pixelpen.sim.transports.port import open_sim_port
from pixelpen.urls import parse_url
from pixelpen.vector.displaylist import DisplayList

UNIT = 0.02488  # HP 7475A plotter unit in mm (7475A manual p. 22)
ESC_QUERY = re.compile(rb"\x1b\.[BEO]")


class PortLink(Link):
    """A Link straight onto a SimPort: records what the host sent, and leaves the plotter on when closed."""

    def __init__(self, port, mangle=None) -> None:
        super().__init__("simport", timeout=8.0, clock=port.clock)
        self.port = port
        self.sent = bytearray()
        self.mangle = mangle

    def _read_raw(self, wait):
        data = self.port.read(4096, wait)
        return self.mangle(data) if self.mangle and data else data

    def _write_raw(self, data, wait):
        n = self.port.write(data, wait)
        self.sent += data[:n]
        return n

    def _raw_in_waiting(self):
        return self.port.in_waiting

    def _flush_raw(self, wait):
        self.port.drain(wait)

    def _close_raw(self):
        self.port.close(close_device=False)


class Rig:
    """One simulated plotter that outlives its links, a display on it, and every link the display opened."""

    def __init__(self, model="hp7475a", options="", first_link=None, clock=None, mangle=None, sim=None, **kw):
        self.clock = clock or SimulatedClock()
        self.device = create_simulator(model, clock=self.clock, **(sim or {}))
        self.links: list[PortLink] = []

        def factory():
            faults = first_link if first_link and not self.links else {}
            link = PortLink(open_sim_port(model, faults, clock=self.clock, device=self.device), mangle)
            self.links.append(link)
            return link

        self.display = pixelpen.open(f"sim:{model}?{options}", link_factory=factory, **kw)

    @property
    def sent(self) -> bytes:
        return b"".join(bytes(link.sent) for link in self.links)

    def paper(self, dpi: float = 40) -> np.ndarray:
        return self.device.paper_image(dpi).to_rgb()


def square(x0, y0, size=2000):
    return np.array([[x0, y0], [x0 + size, y0], [x0 + size, y0 + size], [x0, y0 + size], [x0, y0]], float)


def drawing(n=12, seed=1, pens=(1,)):
    rng = np.random.default_rng(seed)
    polys = [rng.integers(200, 7500, (int(rng.integers(2, 8)), 2)).astype(float) for _ in range(n)]
    return DisplayList.from_polylines(polys, pens=[pens[i % len(pens)] for i in range(n)], unit_mm=UNIT)


def graphics(wire: bytes) -> bytes:
    """The host's bytes without the ESC.B/E/O queries (their number depends on timing)."""
    return ESC_QUERY.sub(b"", wire)


# -- schemes, profiles, URLs ----------------------------------------------------------------------


def test_schemes_are_registered_with_their_profiles():
    schemes = known_schemes()
    assert schemes["hp7475a"] is HP7475A and schemes["hp7550a"] is HP7550A and schemes["hp7440a"] is HP7440A
    assert load_profile(HP7475A.profile_name).unit_mm == 0.02488  # 7475A manual p. 22
    assert load_profile(HP7550A.profile_name).unit_mm == 0.025  # measured (vpype#848)


def test_hardware_url_keeps_a_bracketed_pyserial_url_and_picks_the_flow():
    url = parse_url("hp7475a:[rfc2217://plotter:4000?logging=debug]?handshake=xonxoff&reserve=200&paper=a3")
    d = HP7475A.from_url(url)
    assert d.port == "rfc2217://plotter:4000?logging=debug" and d.paper.name == "a3"
    assert (d.handshake, d.flow, d.reserve) == ("xonxoff", "xonxoff", 200)
    assert HP7475A.from_url(parse_url("hp7475a:/dev/ttyUSB0")).flow == "none"  # escb needs no link handshake
    assert HP7475A.from_url(parse_url("hp7475a:COM3?handshake=hardwire")).flow == "rtscts"


@pytest.mark.parametrize(
    "options, message",
    [
        ("handshake=enq", "handshake='enq' is not valid"),
        ("reserve=-1", "reserve='-1' is not valid"),
        ("sync_strokes=0", "sync_strokes='0' is not valid"),
        ("velocity=fast", "velocity='fast' is not valid"),
        ("ps=maybe", "ps='maybe' is not valid"),
        ("colour=red", "unknown option"),
    ],
)
def test_bad_url_options_are_named(options, message):
    with pytest.raises(URLError, match=message):
        HP7475A.from_url(parse_url(f"hp7475a:/dev/ttyUSB0?{options}"))


def test_conflicting_flow_and_out_of_range_velocity():
    with pytest.raises(ConfigError, match="handshake=xonxoff needs flow=xonxoff"):
        HP7475A.from_url(parse_url("hp7475a:/dev/ttyUSB0?handshake=xonxoff&flow=none"))
    with pytest.raises(ConfigError, match=r"velocity 50 cm/s is outside 0\.\.38\.1"):
        HP7475A.from_url(parse_url("hp7475a:/dev/ttyUSB0?velocity=50"))


def test_a_reserve_as_large_as_the_buffer_is_refused_on_connect():
    with pytest.raises(ConfigError, match="reserve=2000 leaves no room in a buffer with 1024 free bytes"):
        Rig(options="reserve=2000")


def test_sim_urls_name_papers_as_the_profile_does():
    d = pixelpen.open("sim:hp7475a?paper=ansi_a&speed=fast")  # the profile's alias of its paper "a" (US letter)
    assert d.paper.name == "a" and d.link.port.sim_device.paper.name == "letter"
    d.close()


def test_bad_usb_target():
    d = HP7475A.from_url(parse_url("hp7475a:usb:plotter"))
    with pytest.raises(URLError, match="usb:VID:PID"):
        d.open()


# -- wire bytes -------------------------------------------------------------------------------------


def test_wire_bytes_of_a_square_are_exact():
    rig = Rig()
    with rig.display as d:
        d.plot(DisplayList.from_polylines([square(1000, 1000)], pens=1, unit_mm=UNIT))
    # as below (verify=sync), with the OA;OE; checkpoint of verify=instruction behind every instruction
    assert graphics(rig.sent) == (
        b"\x1b.(\x1b.K\x1b.(;IN;OS;OI;OE;"
        b"SP1;OA;OE;PU1000,1000;OA;OE;PD3000,1000,3000,3000,1000,3000,1000,1000;OA;OE;PU;OA;OE;"
        b"\x1b.KPU;SP0;PU11040,7721;OI;"
    )
    assert rig.device.error_log == [] and rig.device.selected_pen == 0


def test_wire_bytes_of_a_square_are_exact_with_checks_at_sync_points_only():
    rig = Rig(options="verify=sync")
    with rig.display as d:
        d.plot(DisplayList.from_polylines([square(1000, 1000)], pens=1, unit_mm=UNIT))
    # ESC.( plotter on, ESC.K abort leftovers, ESC.(; (the escb preamble); IN, OS (clears its bit 8, so that
    # a later OS can tell a power cycle), OI/OE to identify and check; pen 1; the square; PU;OA;OE; to confirm it;
    # on close ESC.K, PU;SP0;, the A4 park position
    # and OI; to see them done.
    assert graphics(rig.sent) == (
        b"\x1b.(\x1b.K\x1b.(;IN;OS;OI;OE;"
        b"SP1;PU1000,1000;PD3000,1000,3000,3000,1000,3000,1000,1000;PU;OA;OE;"
        b"\x1b.KPU;SP0;PU11040,7721;OI;"
    )
    assert rig.device.error_log == [] and rig.device.selected_pen == 0
    assert d.model_reply == "7475A"


def test_velocity_and_paper_size_go_after_in():
    rig = Rig("hp7550a", "velocity=20&verify=sync")
    with rig.display as d:
        d.plot(DisplayList.from_polylines([square(500, 500)], pens=3, unit_mm=0.025))
    assert graphics(rig.sent).startswith(b"\x1b.(\x1b.K\x1b.(;IN;PS4;VS20;OS;OI;OE;SP3;PU500,500;")
    assert rig.device.error_log == [] and rig.display.model_reply == "7550A"


def test_a_slower_profile_asks_for_its_speed():
    slow = load_profile("hp7475a")
    slow = replace(slow, pen_down=replace(slow.pen_down, speed=150.0))
    d = HP7475A("/dev/null", profile=slow)
    assert d.velocity_cm_s == 15.0
    assert HP7475A("/dev/null", profile=load_profile("hp7475a")).velocity_cm_s is None


def test_pens_are_selected_when_they_change_and_land_on_paper_in_order():
    rig = Rig(options="sync_strokes=1")
    dl = DisplayList.from_polylines([square(500, 500), square(3000, 500), square(5500, 500)], pens=[2, 2, 5],
                                    unit_mm=UNIT)
    with rig.display as d:
        d.plot(dl)
    wire = graphics(rig.sent)
    assert wire.count(b"SP2;") == 1 and wire.count(b"SP5;") == 1 and wire.index(b"SP2;") < wire.index(b"SP5;")
    seg, pens, _ = rig.device.segments()
    assert list(pens) == [2] * 8 + [5] * 4
    assert np.array_equal(seg[:4, :2], square(500, 500)[:4])


def test_ps_on_a_7475a_is_sent_when_asked_for_and_taken():
    rig = Rig(options="ps=true")  # chiplotle3's 7475A instruction list has PS; vpype's hp7475a files start IN;DF;PS4;
    assert b"IN;PS4;OS;OI;OE;" in graphics(rig.sent) and rig.device.error_log == []
    assert "PS" in HP7475A.mnemonics and not HP7475A.knows_ps  # known, but not sent unless asked for
    rig.display.close()


def test_a_point_outside_the_hpgl_range_is_refused_before_anything_is_sent():
    rig = Rig()
    before = len(rig.sent)
    dl = DisplayList.from_polylines([square(0, 0), np.array([[0, 0], [5000, 40000.0]])], pens=1, unit_mm=UNIT)
    with pytest.raises(ConfigError, match=r"stroke 1: point 1 \(5000, 40000\) is outside the HP-GL range"):
        rig.display.plot(dl)
    assert len(rig.sent) == before and rig.device.segments()[0].shape == (0, 4)


# -- the paper ---------------------------------------------------------------------------------------


def _expected_pixels(points_units: np.ndarray, dpi: float, origin_mm=(10.0, 4.0), page_mm=(297.0, 210.0)) -> np.ndarray:
    """Pixel (column, row) of plotter-unit points on an A4 7475A sheet, from the profile's geometry alone.

    vpype's 7475A A4 origin is 10 mm from the left and 206 mm from the top of the 210 mm sheet (4 mm up).
    """
    k = dpi / 25.4
    x = (origin_mm[0] + points_units[:, 0] * UNIT) * k
    y = page_mm[1] * k - (origin_mm[1] + points_units[:, 1] * UNIT) * k
    return np.column_stack([x, y])


def _ink(rgb: np.ndarray) -> np.ndarray:
    rows, cols = np.nonzero(rgb.sum(axis=2) < 3 * 200)
    return np.column_stack([cols + 0.5, rows + 0.5])


def test_square_ends_up_on_the_paper_where_the_profile_says():
    rig = Rig(options="paper=a4")
    dpi = 50.0
    sq = square(2000, 1500, size=4000)
    with rig.display as d:
        d.plot(DisplayList.from_polylines([sq], pens=1, unit_mm=UNIT))
    ink = _ink(rig.paper(dpi))
    corners = _expected_pixels(sq, dpi)
    # independent rendering: sample the expected outline densely
    t = np.linspace(0, 1, 200)[:, None]
    outline = np.concatenate([a + t * (b - a) for a, b in pairwise(corners)])
    d_ink = np.min(np.hypot(*(ink[:, None, :] - outline[None, :, :]).transpose(2, 0, 1)), axis=1)
    d_outline = np.min(np.hypot(*(outline[:, None, :] - ink[None, :, :]).transpose(2, 0, 1)), axis=1)
    assert len(ink) > 100
    assert d_ink.max() <= 1.5, "ink where the square is not"
    assert d_outline.max() <= 1.5, "part of the square is missing"


# -- flow control --------------------------------------------------------------------------------------


def _watch_buffer(device) -> list[int]:
    seen: list[int] = []
    receive = device.receive

    def spy(data):
        receive(data)
        seen.append(device.buffered_bytes)

    device.receive = spy
    return seen


def test_escb_never_overflows_and_keeps_the_reserve():
    rig = Rig(options="reserve=128")
    levels = _watch_buffer(rig.device)
    dl = drawing(n=30, seed=3)
    with rig.display as d:
        d.plot(dl)
    assert rig.device.stats.bytes_overflowed == 0 and rig.device.stats.io_errors == 0
    assert rig.device.error_log == []
    assert max(levels) > 1024 - 128 - 2 * 120  # the buffer was really used ...
    assert max(levels) <= 1024 - 128  # ... and never filled into the reserve
    assert d.confirmed == len(dl)


def test_sending_everything_overflows_and_is_reported():
    rig = None
    with pytest.raises(ProtocolError) as info:
        rig = Rig(options="handshake=none")
        rig.display.plot(drawing(n=40, seed=3))
    assert info.value.code == 16 and "buffer overflow" in str(info.value)
    assert info.value.command.startswith("PU")


@pytest.mark.parametrize("handshake, preamble", [
    ("xonxoff", b"\x1b.(;\x1b.I81;;17:\x1b.N;19:"),
    ("hardwire", b"\x1b.(;\x1b.@;1:"),
])
def test_device_handshakes_plot_without_overflow(handshake, preamble):
    clock = SimulatedClock()
    device = create_simulator("hp7475a", clock=clock)
    port_flow = {"xonxoff": "xonxoff", "hardwire": "rtscts"}[handshake]
    links = []

    def factory():
        links.append(PortLink(open_sim_port("hp7475a", {"flow": port_flow}, clock=clock, device=device)))
        return links[-1]

    d = pixelpen.open(f"sim:hp7475a?handshake={handshake}", link_factory=factory)
    dl = drawing(n=40, seed=3)
    d.plot(dl)
    d.close()
    assert bytes(links[0].sent).startswith(b"\x1b.(\x1b.K" + preamble + b"IN;")
    assert device.stats.bytes_overflowed == 0 and device.error_log == []
    assert len(device.segments()[0]) == len(dl.segments())


@pytest.mark.parametrize("handshake", ["xonxoff", "hardwire"])
def test_a_stroke_longer_than_the_stall_limit_on_the_wire_plots_completely(handshake):
    # ~60 KB of PD coordinates: over a minute at 9600 baud, longer than stall=60 s; the plotter is progressing
    n = 6000
    stroke = np.column_stack([1000 + np.arange(n), 1000 + 10 * (np.arange(n) % 2)]).astype(float)
    dl = DisplayList.from_polylines([stroke], pens=1, unit_mm=UNIT)
    ident = f"long-stroke-{handshake}"
    try:
        with pixelpen.open(f"sim:hp7475a?speed=fast&handshake={handshake}&id={ident}") as d:
            d.plot(dl)
            device = named_simulator(ident)
            assert d.link.port.sim_port.stats().bytes_sent * 10.0 / 9600 > d.stall_s
        assert device.error_log == [] and device.stats.bytes_overflowed == 0
        assert len(device.segments()[0]) == len(dl.segments()) == n - 1
    finally:
        forget_simulator(ident)


def test_escb_does_not_starve_a_plotter_that_is_slower_than_the_link():
    rig = Rig()
    big = [square(300, 300, 7000), square(600, 600, 6000), square(900, 900, 5000)]
    with rig.display as d:
        d.plot(DisplayList.from_polylines(big, pens=1, unit_mm=UNIT))
    # simulated seconds idle with nothing to execute: the connect handshake's round trip (OS/OI/OE answers,
    # ESC.E and ESC.B at 9600 baud) is all of it
    assert rig.device.stats.starved_time < 0.06


def test_escb_keeps_a_fast_plotter_about_as_busy_as_hardware_handshake():
    theta = np.linspace(0, 2 * np.pi, 300)
    circle = np.column_stack([5000 + 1500 * np.cos(theta), 4000 + 1500 * np.sin(theta)]).round()
    dl = DisplayList.from_polylines([circle], pens=1, unit_mm=UNIT)
    durations = {}
    for handshake, flow in (("escb", "none"), ("hardwire", "rtscts")):
        clock = SimulatedClock()
        device = create_simulator("hp7475a", clock=clock)
        port = open_sim_port("hp7475a", {"flow": flow}, clock=clock, device=device)
        d = pixelpen.open(f"sim:hp7475a?handshake={handshake}", link_factory=lambda port=port: PortLink(port))
        start = clock.now()
        d.plot(dl)
        durations[handshake] = clock.now() - start
        d.close()
    # the circle is link-bound (tiny vectors); ESC.B polling may cost its query bytes, not idle gaps
    assert durations["escb"] <= 1.05 * durations["hardwire"]


# -- confirmation and errors ---------------------------------------------------------------------------


def test_progress_is_confirmed_only_for_strokes_on_paper():
    rig = Rig(options="sync_strokes=2")
    dl = drawing(n=9)
    seen = []

    def check(progress):
        # every stroke the driver calls confirmed is on the simulated paper already
        inked = len(rig.device.segments()[0])
        assert inked >= len(dl.select(np.arange(len(dl)) < progress.strokes_done).segments())
        seen.append(progress.strokes_done)

    rig.display.on_progress = check
    rig.display.plot(dl)
    rig.display.close()
    assert seen == sorted(seen) and seen[-1] == 9 and {2, 4, 6, 8} <= set(seen)


def _stream_offset(wire: bytes, needle: bytes) -> int:
    at = wire.find(needle)
    assert at >= 0
    return at


def test_a_corrupted_byte_is_reported_with_the_instructions_it_hit():
    dl = DisplayList.from_polylines([square(500, 500), square(3000, 500), square(5500, 500)], pens=1, unit_mm=UNIT)
    clean = Rig(options="sync_strokes=1&verify=sync")
    clean.display.plot(dl)
    clean.display.close()
    target = b"PD7500,500"  # stroke 2's first vector; corrupt its '7'
    offset = _stream_offset(clean.sent, target) + 2
    rig = Rig(options="sync_strokes=1&verify=sync", first_link={"corrupt_at": str(offset)})
    with pytest.raises(ProtocolError) as info:
        rig.display.plot(dl)
    err = info.value
    assert err.code in (1, 2, 3) and "stroke 2" in str(err)
    assert err.command.startswith("PU5500,500;PD7500,500,") and err.command.endswith("PU;OA;OE;")
    assert err.device == "hp7475a"


class _Mangler:
    """Replace the first answer after ``after`` answers with ``text`` (a garbled or oversized reply)."""

    def __init__(self, after: int, text: bytes) -> None:
        self.after, self.text, self.count, self.done = after, text, 0, False

    def __call__(self, data: bytes) -> bytes:
        out = bytearray()
        for b in data:
            if not self.done and self.count == self.after:
                if b == 0x0D:
                    out += self.text
                    self.done = True
                    self.count += 1
                continue
            out.append(b)
            self.count += b == 0x0D
        return bytes(out)


@pytest.mark.parametrize(
    "text, message",
    [
        (b"1,2;3\r", "unexpected answer '1,2;3'"),
        (b"7" * 300 + b"\r", "answer longer than 256 bytes"),
        (b"7" * 300, "answer longer than 256 bytes"),
        (b"99999999\r", "not a buffer size|not an RS-232 error|expected the OE answer"),
        (b"\r", "answer"),  # a lost answer: the next one answers the wrong question
    ],
)
def test_garbled_answers_interrupt_the_plot(text, message):
    rig = Rig(mangle=_Mangler(5, text), options="sync_strokes=1")
    with pytest.raises((PlotInterrupted, LinkError)) as info:
        rig.display.plot(drawing(n=6))
    cause = info.value.cause if isinstance(info.value, PlotInterrupted) else info.value
    assert isinstance(cause, LinkError) and re.search(message, str(cause))


def test_an_ignored_output_request_interrupts_rather_than_fails():
    # ESC.E 10: a request met an answer on its way out and the plotter ignored it; the exchange is out of
    # step, which a reconnect mends, so it is a link fault (PlotInterrupted), not a drawing error
    from pixelpen.devices.plotters.hpgl_stream import Query as _Query

    rig = Rig()
    d = rig.display
    d._wire.queries.append(_Query("E", d.clock.now() + 10, 0, 0, None))
    rig.links[-1].mangle = lambda data: b"10\r"
    with pytest.raises(PlotInterrupted) as info:
        d.plot(drawing(n=2))
    assert isinstance(info.value.cause, LinkError) and "a request was lost" in str(info.value.cause)


def test_a_dead_plotter_is_a_clear_timeout():
    clock = SimulatedClock()
    device = create_simulator("hp7475a", clock=clock)
    device.inject("power-loss")
    with pytest.raises(LinkTimeout, match="nothing was received since connecting: is the plotter on"):
        pixelpen.open(
            "sim:hp7475a", link_factory=lambda: PortLink(open_sim_port("hp7475a", {}, clock=clock, device=device))
        )


def test_a_plotter_that_stops_moving_is_a_stall():
    rig = Rig(options="velocity=0.38&stall=3")  # 0.38 cm/s: the 20 cm line below takes a minute
    with pytest.raises(PlotInterrupted) as info:
        rig.display.plot(DisplayList.from_polylines([np.array([[0, 0], [8000, 0]], float)], pens=1, unit_mm=UNIT))
    assert "no progress for 3 s and is not paused" in str(info.value.cause)


# -- pause, paper lever, Ctrl-C ------------------------------------------------------------------------


class Operator(SimulatedClock):
    """Simulated time with a person at the plotter: undoes a pause ``after`` seconds after it began."""

    def __init__(self, after: float = 5.0) -> None:
        super().__init__()
        self.after = after
        self.device = None
        self.events: list[tuple[str, float]] = []
        self._since: float | None = None

    def advance(self, seconds: float) -> None:
        super().advance(seconds)
        dev = self.device
        if dev is None or not dev.paused:
            return
        if self._since is None:
            self._since = self.now()
            self.events.append(("paused", self.now()))
        elif self.now() - self._since >= self.after:
            self.events.append(("resumed", self.now()))
            self._since = None
            if dev.lever_raised:
                dev.release_paper_lever()
            else:
                dev.press_view()


@pytest.mark.parametrize("fault, why", [("paper_lever_after", "paper lever is raised"),
                                        ("pause_after", "VIEW is pressed")])
def test_a_pause_at_the_plotter_is_waited_for_not_a_fault(fault, why, caplog):
    dl = drawing(n=10)
    reference = Rig()
    reference.display.plot(dl)
    reference.display.close()
    clock = Operator(after=70.0)  # longer than the stall limit: a pause must never count as a stall
    rig = Rig(clock=clock, first_link={fault: "400"})
    clock.device = rig.device
    with caplog.at_level(logging.INFO, logger="pixelpen.devices.plotters.hpgl"):
        rig.display.plot(dl)
        rig.display.close()
    assert [e for e, _ in clock.events] == ["paused", "resumed"]
    assert any(why in r.getMessage() for r in caplog.records)
    assert np.array_equal(rig.paper(), reference.paper())


def test_a_pause_asked_by_the_host_holds_with_the_pen_up_and_everything_confirmed():
    rig = Rig(options="sync_strokes=4")
    dl = drawing(n=8)
    calls, seen = [], []

    def pause_requested():
        calls.append(rig.clock.now())
        if len(calls) == 4:  # before stroke 3: pause for the next ten looks
            return True
        if 4 < len(calls) <= 14:
            seen.append((rig.display.confirmed, rig.device.pen_down, rig.device.buffered_bytes))
            return True
        return False

    rig.display.pause_requested = pause_requested
    rig.display.plot(dl)
    rig.display.close()
    assert seen and all(s == (3, False, 0) for s in seen)  # drained: strokes 0..2 confirmed, pen up, idle
    assert rig.display.confirmed == 8 and len(rig.device.segments()[0]) == len(dl.segments())


def test_ctrl_c_aborts_then_stores_the_pen():
    rig = Rig(options="sync_strokes=1")

    def interrupt(progress):
        if progress.strokes_done == 2:
            raise KeyboardInterrupt

    rig.display.on_progress = interrupt
    with pytest.raises(KeyboardInterrupt):
        rig.display.plot(drawing(n=10))
    wire = graphics(rig.sent)
    tail = wire[wire.rindex(b"\x1b.K"):]
    assert tail == b"\x1b.KPU;SP0;PU11040,7721;OI;"
    dev = rig.device
    assert dev.selected_pen == 0 and not dev.pen_down and dev.buffered_bytes == 0
    assert dev.next_event_time() is None  # idle
    assert rig.display.confirmed == 2


# -- faults and resuming --------------------------------------------------------------------------------


def _plot_through_faults(dl: DisplayList, fault: dict[str, str], options: str = "sync_strokes=3", **kw):
    """Plot with a fault on the first link, power the plotter on again if it lost it, resume (confirming if asked)."""
    rig = Rig(first_link=fault, options=options, **kw)
    interruptions, asked = 0, []
    try:
        rig.display.plot(dl)
    except (PlotInterrupted, ProtocolError) as exc:
        interruptions += 1
        assert 0 <= getattr(exc, "resume_from", 0) <= len(dl)
        if "power_loss_after" in fault:
            rig.device.inject("reset")  # the operator switches it on again
        try:
            rig.display.resume_after_fault()
        except PositionUnknown as unknown:
            asked.append(unknown)
            rig.display.resume_after_fault(position_confirmed=True)
    rig.display.close()
    return rig, interruptions, asked


def _segments(device) -> list[tuple]:
    """The sheet as a sorted list of (x0, y0, x1, y1, pen): a multiset, so a line drawn twice shows."""
    seg, pens, _ = device.segments()
    return sorted((*map(float, s), int(p)) for s, p in zip(seg, pens, strict=True))


def _reference(dl: DisplayList, options: str = "sync_strokes=3") -> tuple[list[tuple], int]:
    rig = Rig(options=options)
    rig.display.plot(dl)
    rig.display.close()
    return _segments(rig.device), len(rig.links[0].sent)


def test_a_drop_or_stall_anywhere_resumes_drawing_every_segment_exactly_once():
    # the drawing has no closed strokes and no revisited points: every fault point has one reading
    dl = drawing(n=10, seed=5, pens=(1, 2, 3))
    expected, total = _reference(dl)
    rng = np.random.default_rng(2026)
    for kind in ("drop_after", "stall_after"):
        for at in rng.integers(40, total - 40, size=5):
            rig, n, asked = _plot_through_faults(dl, {kind: str(int(at))})
            assert (n, asked) == (1, []), f"{kind}={at}"
            assert _segments(rig.device) == expected, f"{kind}={at}: a segment is missing or drawn twice"
            assert rig.display.confirmed == len(dl)


def test_a_stroke_cut_mid_way_is_finished_from_where_the_pen_stopped():
    zigzag = np.array([[500 + 400 * i, 1000 + 3000 * (i % 2)] for i in range(14)], float)
    dl = DisplayList.from_polylines([square(200, 200, 200), zigzag], pens=1, unit_mm=UNIT)
    expected, total = _reference(dl, "sync_strokes=1")
    rig, n, asked = _plot_through_faults(dl, {"drop_after": str(total - 160)}, "sync_strokes=1")
    assert (n, asked) == (1, []) and _segments(rig.device) == expected
    resumed = graphics(bytes(rig.links[1].sent))
    first_pu = re.search(rb"(?<=;)PU(\d+),(\d+);(?:OA;OE;)?PD", resumed)
    assert first_pu and (int(first_pu[1]), int(first_pu[2])) != (500, 1000)  # not the stroke's start again
    assert [int(first_pu[1]), int(first_pu[2])] in zigzag[1:].astype(int).tolist()  # a vertex the pen reached


def test_a_power_loss_asks_for_confirmation_and_then_loses_nothing():
    # the plotter forgets its buffer: which of the unconfirmed strokes it drew is unknowable, so the driver
    # asks; confirmed, it redraws from the last confirmed stroke: every reference segment is there, and every
    # other mark is a reference segment again or a part of one (the vector cut by the power loss)
    dl = drawing(n=10, seed=5, pens=(1, 2, 3))
    expected, total = _reference(dl)
    ref = np.array([s[:4] for s in expected])
    for at in np.random.default_rng(7).integers(200, total - 40, size=3):
        rig, n, asked = _plot_through_faults(dl, {"power_loss_after": str(int(at))})
        assert n == 1 and len(asked) == 1 and rig.display.confirmed == len(dl)
        message = str(asked[0])
        assert "switched off or reset" in message and "position_confirmed=True" in message
        assert "--confirm-position" in message and f"stroke {asked[0].resume_from}" in message
        have = _segments(rig.device)
        assert all(have.count(s) >= 1 for s in expected)
        for s in have:
            same_pen = ref[[e[4] == s[4] for e in expected]]
            dist = _on_segment(np.array([s[:2], s[2:4]]), same_pen)
            assert (dist.max(axis=0) < 1e-6).any(), f"power_loss_after={at}: stray mark {s}"


def _on_segment(p: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """Distance of points p (K, 2) from segments seg (M, 4), as (K, M)."""
    a, b = seg[None, :, :2], seg[None, :, 2:]
    d = b - a
    t = np.clip(((p[:, None, :] - a) * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-12), 0, 1)
    return np.hypot(*(a + t[..., None] * d - p[:, None, :]).transpose(2, 0, 1))


def test_a_garbled_answer_interrupts_and_the_resume_draws_each_segment_once():
    dl = drawing(n=8, seed=3)
    expected, _ = _reference(dl, "sync_strokes=2")
    rig = Rig(options="sync_strokes=2", mangle=_Mangler(6, b"1,2;3\r"))
    with pytest.raises(PlotInterrupted) as info:
        rig.display.plot(dl)
    assert isinstance(info.value.cause, LinkError)
    rig.links[-1].mangle = None
    rig.display.resume_after_fault()
    rig.display.close()
    assert _segments(rig.device) == expected


def test_a_wrong_position_at_a_confirmation_is_a_fault_and_the_strokes_are_redrawn():
    dl = drawing(n=6, seed=2)
    expected, _ = _reference(dl, "sync_strokes=2&verify=sync")
    oa = re.compile(rb"-?\d+,-?\d+,\d\r")
    line, answers = bytearray(), []

    def wrong_oa(data: bytes) -> bytes:  # the second OA answer reports another place (as after a corrupted PD)
        if answers.count(True) >= 2:
            return data
        out = bytearray()
        for byte in data:
            line.append(byte)
            if byte == 0x0D:
                answers.append(oa.fullmatch(line) is not None)
                out += b"1,1,0\r" if answers.count(True) == 2 and answers[-1] else line
                line.clear()
        return bytes(out)

    rig = Rig(options="sync_strokes=2&verify=sync", mangle=wrong_oa)
    with pytest.raises(PlotInterrupted, match=r"OA found the pen at 1,1 after strokes 2\.\.3"):
        rig.display.plot(dl)
    rig.display.resume_after_fault()
    rig.display.close()
    have = _segments(rig.device)
    assert all(s in have for s in expected)  # nothing lost: strokes 2..3 drawn again (twice, not lost)
    assert len(have) - len(expected) == sum(len(dl.stroke(i)) - 1 for i in (2, 3))


def test_resume_from_the_state_file_in_a_new_session(tmp_path):
    dl = drawing(n=10, seed=7)
    expected, total = _reference(dl, "")
    state = tmp_path / "plot.json"
    drop = total - 40  # late: while the last strokes are being drawn
    first = Rig(first_link={"drop_after": str(drop)}, options=f"sync_strokes=2&state={state}")
    with pytest.raises(PlotInterrupted) as info:
        first.display.plot(dl)
    saved = PlotState.load(state)
    assert saved.confirmed == info.value.resume_from and 0 < saved.confirmed < len(dl)
    assert saved.sent == len(dl) and not saved.position_lost  # every stroke went out before the drop
    # a new session (new display, same plotter and paper) asks the plotter before its handshake
    second_links = []

    def factory():
        second_links.append(PortLink(open_sim_port("hp7475a", {}, clock=first.clock, device=first.device)))
        return second_links[-1]

    d = pixelpen.open(f"sim:hp7475a?state={state}", link_factory=factory)
    d.plot(dl, resume=True)
    d.close()
    assert _segments(first.device) == expected
    assert graphics(bytes(second_links[0].sent)).startswith(b"\x1b.(\x1b.KOS;OA;")  # asked where, before IN


def test_resume_with_a_missing_state_file_is_refused_naming_it(tmp_path):
    missing = tmp_path / "nope.json"
    rig = Rig(options=f"state={missing}")
    with pytest.raises(ConfigError, match=f"{re.escape(str(missing))}: no plot state to resume"):
        rig.display.plot(drawing(n=2), resume=True)
    assert not missing.exists()


def test_a_fault_message_names_the_plotter_once():
    rig = Rig(first_link={"drop_after": "300"})
    with pytest.raises(PlotInterrupted) as info:
        rig.display.plot(drawing(n=6))
    text = str(info.value)
    assert text.count("hp7475a") == 1 and text.startswith("plot interrupted: ")


# -- pause confirmation and manual control -------------------------------------------------------------


def test_on_pause_reports_a_pause_only_once_the_plotter_is_idle_with_the_pen_up():
    dl = drawing(n=8)
    expected, total = _reference(dl, "sync_strokes=4")
    seen = []
    rig = None

    def on_pause(paused):
        dev = rig.device
        seen.append((paused, dev.paused, dev.pen_down))
        if paused:
            dev.press_view()  # the operator lets it go on

    rig = Rig(first_link={"pause_after": str(total // 2)}, options="sync_strokes=4", on_pause=on_pause)
    rig.display.plot(dl)
    rig.display.close()
    # VIEW lifts the pen and stops the plotter: True once it stopped, False once it goes on
    assert seen == [(True, True, False), (False, False, False)]
    assert _segments(rig.device) == expected


def test_a_host_pause_is_confirmed_after_the_plotter_drained():
    rig = Rig(options="sync_strokes=4")
    states, asks = [], []

    def pause_requested():
        asks.append(1)
        return 3 <= len(asks) <= 5

    rig.display.pause_requested = pause_requested
    rig.display.on_pause = lambda paused: states.append((paused, rig.device.buffered_bytes, rig.device.pen_down))
    rig.display.plot(drawing(n=6))
    rig.display.close()
    assert states == [(True, 0, False), (False, 0, False)]


def test_manual_pen_home_and_no_motors_off():
    rig = Rig()
    d = rig.display
    d.pen_down()
    assert rig.device.pen_down
    d.toggle_pen()
    assert not rig.device.pen_down
    d.toggle_pen()
    assert rig.device.pen_down
    d.pen_up()
    d.go_home()
    assert not rig.device.pen_down and rig.device.pen_position == tuple(float(v) for v in d.paper.park)
    with pytest.raises(ConfigError, match="HP-GL plotters have no motors-off command"):
        d.motors_off()
    d.close()
    with pytest.raises(PixelpenError, match="not open"):
        d.pen_up()


# -- other links ----------------------------------------------------------------------------------------


def test_usb_printer_class_adapter():
    from pixelpen.sim.transports.usbbackend import PrinterClassBackend

    clock = SimulatedClock()
    device = create_simulator("hp7475a", clock=clock)
    backend = PrinterClassBackend(device, clock=clock)
    dl = DisplayList.from_polylines([square(1000, 1000)], pens=1, unit_mm=UNIT)
    for target in ("usb:067b:2305", "usb:auto"):
        with pixelpen.open(f"hp7475a:{target}", usb_backend=backend) as d:
            d.plot(dl)
    assert len(device.segments()[0]) == 8 and device.error_log == []  # the square twice


def test_auto_finds_the_port_that_answers_oi(monkeypatch):
    from pixelpen.sim.transports.pty import PtyBridge

    clock = SimulatedClock()
    device = create_simulator("hp7475a", clock=clock)
    bridge = PtyBridge(device, clock=clock)
    master, slave = os.openpty()  # a port where nothing answers
    try:
        silent = os.ttyname(slave)
        ports = [discovery.DiscoveredDevice("serial", p, "test") for p in (silent, bridge.path)]
        monkeypatch.setattr(discovery, "list_serial_ports", lambda: ports)
        with pixelpen.open("hp7475a:auto?timeout=2") as d:
            assert d._found_port == bridge.path
            d.plot(DisplayList.from_polylines([square(1000, 1000)], pens=1, unit_mm=UNIT))
        assert len(device.segments()[0]) == 4
        monkeypatch.setattr(discovery, "list_serial_ports", lambda: ports[:1])
        with pytest.raises(LinkError, match="no serial port answered OI with 7475A"):
            pixelpen.open("hp7475a:auto?timeout=2")
    finally:
        bridge.close()
        os.close(master)
        os.close(slave)


def test_model_classes_state_what_the_simulators_answer():
    for cls, model in ((HP7475A, "hp7475a"), (HP7550A, "hp7550a"), (HP7440A, "hp7440a")):
        rig = Rig(model)
        assert rig.display.model_reply == cls.ident
        assert isinstance(rig.display, HPGLDisplay)
        rig.display.close()


def test_escb_answers_confirm_strokes_the_plotter_has_drawn_between_sync_points():
    dl = drawing(n=12, seed=9)
    per_stroke = [len(dl.stroke(i)) - 1 for i in range(len(dl))]
    seen = []
    rig = None

    def progress(p):
        seen.append((p.strokes_done, len(rig.device.segments()[0]), rig.display._wire.syncs.__len__()))

    rig = Rig(options="sync_strokes=100&sync_bytes=100000", on_progress=progress)
    rig.display.plot(dl)
    rig.display.close()
    early = [s for s in seen if s[0] < len(dl)]
    assert len(early) >= 3  # confirmed as the plotter took the bytes, long before the one sync point at the end
    for done, inked, _ in seen:  # never ahead of the paper: every confirmed stroke is fully inked
        assert inked >= sum(per_stroke[:done])

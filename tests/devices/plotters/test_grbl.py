"""The GRBL driver against a scripted GRBL (flow control, errors, alarms) and the GRBL simulator (end to end)."""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass

import numpy as np
import pytest

import pixelpen
from pixelpen.clock import SimulatedClock
from pixelpen.devices.plotters.base import PlotInterrupted, PositionUnknown
from pixelpen.devices.plotters.grbl import GrblPlotter
from pixelpen.drivers.serial import SerialLink
from pixelpen.drivers.stream import Link
from pixelpen.errors import ConfigError, LinkTimeout, ProtocolError, URLError
from pixelpen.profiles.model import load_profile
from pixelpen.sim.base import create_simulator
from pixelpen.sim.plotters.sheet import Sheet
from pixelpen.vector.displaylist import DisplayList

WELCOME = b"\r\nGrbl 1.1h ['$' for help]\r\n"
PROFILE = load_profile("grbl")
MM = 1000  # device units per millimetre (unit 0.001 mm)
SIM_OPTIONS = {"size": "297x210", "pen": "servo-inverted", "pen_threshold": "275"}
"""What ``sim:grbl`` builds for the grbl profile (S50 down, S500 up, A4 landscape travel)."""


class FakeGrbl(Link):
    """A scripted GRBL 1.1 (interface.md): a 128-byte RX buffer, one line parsed per ``line_time``, ``ok`` each.

    A line "runs" when parsed: status reports show the last X/Y target and the last ``M3 S`` value.

    Records every byte written, the fullest the RX buffer got and any overflow; ``error_for(line)`` may
    return an error code for a line, ``alarm_at`` names a line number at which ``ALARM:1`` is sent.
    """

    def __init__(self, clock, *, rx_buffer=128, line_time=0.003, welcome=WELCOME, error_for=None, alarm_at=None,
                 lose=None):
        super().__init__("fake-grbl", timeout=2.0, clock=clock)
        self.rx_size = rx_buffer
        self.line_time = line_time
        self.error_for = error_for or (lambda line: None)
        self.alarm_at = alarm_at
        self.lose = lose or (lambda line: False)
        self.welcome = welcome
        self.rx = bytearray()
        self.out = bytearray(welcome)
        self.written = bytearray()
        self.lines: list[str] = []
        self.position = [0.0, 0.0]
        self.spindle = 0.0
        self.max_fill = 0
        self.overflowed = 0
        self._busy_until: float | None = None

    def _advance(self) -> None:
        now = self.clock.now()
        while b"\n" in self.rx:
            if self._busy_until is None:
                self._busy_until = now + self.line_time
            if self._busy_until > now:
                return
            line, _, rest = bytes(self.rx).partition(b"\n")
            self.rx = bytearray(rest)
            text = line.decode().strip()
            if self.lose(text):  # garbled on the wire: GRBL never saw a line, so it never answers
                self._busy_until = self._busy_until + self.line_time if b"\n" in self.rx else None
                continue
            self.lines.append(text)
            for axis, value in re.findall(r"([XY])(-?[0-9.]+)", text):
                self.position["XY".index(axis)] = float(value)
            if m := re.match(r"M3 S([0-9.]+)$", text):
                self.spindle = float(m[1])
            code = self.error_for(text)
            if self.alarm_at is not None and len(self.lines) == self.alarm_at:
                self.out += b"ALARM:1\r\n"
            self.out += b"ok\r\n" if code is None else f"error:{code}\r\n".encode()
            self._busy_until = self._busy_until + self.line_time if b"\n" in self.rx else None

    def _write_raw(self, data, wait):
        self._advance()
        for b in data:
            self.written.append(b)
            if b == ord("?"):
                state = "Run" if self.rx else "Idle"
                x, y = self.position
                self.out += f"<{state}|MPos:{x:.3f},{y:.3f},0.000|FS:0,{self.spindle:g}>\r\n".encode()
            elif b in (0x18, ord("!"), ord("~")):
                if b == 0x18:
                    self.rx.clear()
                    self.out += self.welcome
            elif len(self.rx) >= self.rx_size:
                self.overflowed += 1
            else:
                self.rx.append(b)
                self.max_fill = max(self.max_fill, len(self.rx))
        return len(data)

    def _read_raw(self, wait):
        self._advance()
        if not self.out and wait and self._busy_until is not None:
            step = self._busy_until - self.clock.now()
            if wait is None or step <= wait:
                self.clock.sleep(max(step, 0.0))
                self._advance()
        out, self.out = bytes(self.out), bytearray()
        return out

    def _raw_in_waiting(self):
        self._advance()
        return len(self.out)

    def _close_raw(self):
        pass

    def gcode(self) -> bytes:
        """Everything written except the real-time bytes (``?``, ``!``, ``~``, Ctrl-X)."""
        return bytes(b for b in self.written if b not in b"?!~\x18")


def fake_plotter(clock=None, **fake_kwargs) -> tuple[GrblPlotter, FakeGrbl]:
    clock = clock or SimulatedClock()
    plotter_kwargs = {k: fake_kwargs.pop(k) for k in ("stream",) if k in fake_kwargs}
    fake = FakeGrbl(clock, **fake_kwargs)
    plotter = GrblPlotter("fake", profile=PROFILE, clock=clock, link_factory=lambda: fake, **plotter_kwargs)
    plotter.open()
    return plotter, fake


def squares(n: int, side_mm: float = 10.0, at=(20.0, 20.0), step_mm: float = 3.0) -> DisplayList:
    base = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], float) * side_mm
    polys = [(base + np.array(at) + i * step_mm) * MM for i in range(n)]
    return DisplayList.from_polylines(polys, unit_mm=PROFILE.unit_mm)


def sim_plotter(dev, clock, url_extra="", **kwargs) -> GrblPlotter:
    """A driver whose every (re)connection reaches the simulator ``dev`` (faults only on the first link)."""
    urls = iter([f"sim://grbl?baud=115200{url_extra}"])

    def factory():
        url = next(urls, "sim://grbl?baud=115200")
        return SerialLink(url, baudrate=115200, clock=clock, device=dev)

    plotter = GrblPlotter("sim://grbl", profile=PROFILE, clock=clock, link_factory=factory, **kwargs)
    plotter.open()
    return plotter


def new_sim(clock=None):
    clock = clock or SimulatedClock()
    return create_simulator("grbl", clock=clock, **SIM_OPTIONS), clock


def render(strokes_mm, dpi=50) -> np.ndarray:
    """Independent rendering of the expected ink: the strokes drawn on a fresh simulator sheet."""
    paper = Sheet(297.0, 210.0, y_down=False)
    for pts in strokes_mm:
        paper.pen_down(pts[0])
        paper.line_to(pts)
        paper.pen_up()
    return paper.paper_image(dpi).array


# -- connecting --------------------------------------------------------------------------------------
def test_connect_sends_units_and_pen_up_once():
    plotter, fake = fake_plotter()
    assert plotter.version == (1, 1, "h")
    assert fake.gcode() == b"G21 G90\nM3 S500\nG4 P0.15\n"
    plotter.close()


def test_old_grbl_is_refused():
    with pytest.raises(ProtocolError, match=r"0\.9j"):
        fake_plotter(welcome=b"\r\nGrbl 0.9j ['$' for help]\r\n")


def test_silent_port_times_out():
    clock = SimulatedClock()
    fake = FakeGrbl(clock, welcome=b"")
    fake._write_raw = lambda data, wait: len(data)  # swallows everything: no GRBL there
    plotter = GrblPlotter("fake", profile=PROFILE, clock=clock, link_factory=lambda: fake)
    with pytest.raises(LinkTimeout):
        plotter.open()


def test_alarm_locked_grbl_needs_permission_to_unlock():
    dev, clock = new_sim()
    dev.settings[22] = 1.0  # homing enabled: GRBL boots alarm-locked
    dev.inject("reset")
    with pytest.raises(ProtocolError, match=r"unlock=true") as info:
        sim_plotter(dev, clock)
    assert info.value.code == "Alarm"
    assert not any(line == "$X" for _, line in dev.log)
    plotter = sim_plotter(dev, clock, unlock=True)
    assert any(line == "$X" for _, line in dev.log)
    assert dev.state == "Idle"
    plotter.close()


# -- byte-exact strokes ------------------------------------------------------------------------------
def test_unit_square_bytes():
    plotter, fake = fake_plotter()
    before = len(fake.gcode())
    plotter.plot(squares(1, at=(0.0, 0.0)))
    # the servo's drop and dwell lead the first G1 and the lift goes alone at the end of the job: GRBL runs a
    # line's spindle word, then its G4, then its motion (gcode.c order of execution), each line whole or not at all
    assert fake.gcode()[before:] == (
        b"G0 X0.000 Y0.000\nM3 S50 G4 P0.15 G1 X10.000 Y0.000 F3000\nG1 X10.000 Y10.000\n"
        b"G1 X0.000 Y10.000\nG1 X0.000 Y0.000\nM3 S500 G4 P0.15\n"
    )
    plotter.close()
    assert fake.gcode().endswith(b"M3 S500\nG4 P0.15\nM5\n")


def test_the_lift_rides_on_the_next_travel():
    plotter, fake = fake_plotter()
    before = len(fake.gcode())
    plotter.plot(squares(2, at=(0.0, 0.0), side_mm=1.0, step_mm=5.0))
    lines = fake.gcode()[before:].decode().splitlines()
    assert lines[5] == "M3 S500 G4 P0.15 G0 X5.000 Y5.000"  # stroke 0's lift, its dwell, then the travel to stroke 1
    assert lines[-1] == "M3 S500 G4 P0.15" and plotter.confirmed == 2
    plotter.close()


def test_pen_options_from_the_url():
    url = pixelpen.display.registry.parse_url("grbl:/dev/null?pen=z&pen_up=5&pen_down=-0.2&dwell=0.05&feed=1500")
    plotter = GrblPlotter.from_url(url)
    assert plotter.pen_motion.up_lines() == ["G0 Z5", "G4 P0.05"]
    assert plotter.pen_motion.down_lines() == ["G1 Z-0.2 F600", "G4 P0.05"]
    assert plotter.feed == 1500.0
    url = pixelpen.display.registry.parse_url("grbl:/dev/null?pen_up=off&pen_down=120&stream=wait")
    plotter = GrblPlotter.from_url(url)
    assert plotter.pen_motion.up_lines() == ["M5", "G4 P0.15"] and plotter.stream == "wait"


@pytest.mark.parametrize("query", ["stream=fast", "pen=laser", "pen_down=off", "dwell=-1", "feed=0", "rx_buffer=8",
                                   "colour=red"])
def test_bad_url_options_are_refused(query):
    with pytest.raises((URLError, ConfigError)):
        GrblPlotter.from_url(pixelpen.display.registry.parse_url(f"grbl:/dev/null?{query}"))


# -- flow control --------------------------------------------------------------------------------------
def test_character_counting_fills_but_never_overflows_the_rx_buffer():
    plotter, fake = fake_plotter()
    plotter.plot(squares(12))
    assert fake.overflowed == 0
    assert 100 < fake.max_fill <= 128  # the buffer is really used: several lines in flight
    plotter.close()


def test_send_and_wait_keeps_one_line_in_flight():
    plotter, fake = fake_plotter(stream="wait")
    plotter.plot(squares(3))
    longest = max(len(line) + 1 for line in fake.lines)
    assert fake.max_fill <= longest
    plotter.close()


def test_counting_against_the_simulators_rx_buffer():
    dev, clock = new_sim()
    low = []
    receive = dev.receive

    def watch(data):
        receive(data)
        low.append(dev.rx_free)

    dev.receive = watch
    plotter = sim_plotter(dev, clock)
    plotter.plot(squares(8))
    plotter.close()
    assert dev.overflowed == 0
    assert min(low) < 64  # most of GRBL's 128 bytes were in use at times


def test_both_streaming_modes_plot_the_same_paper():
    images = []
    for stream in ("counting", "wait"):
        dev, clock = new_sim()
        plotter = sim_plotter(dev, clock, stream=stream)
        plotter.plot(squares(4))
        plotter.close()
        images.append(dev.paper_image(50).array)
    assert np.array_equal(images[0], images[1])
    assert (images[0] != 255).any()


# -- errors and alarms -----------------------------------------------------------------------------------
def test_error_reply_names_the_line_and_its_meaning():
    plotter, _fake = fake_plotter(error_for=lambda line: 22 if "G1 X30.000 Y20.000" in line else None)
    with pytest.raises(ProtocolError) as info:
        plotter.plot(squares(1))
    err = info.value
    assert err.code == 22 and err.command == "M3 S50 G4 P0.15 G1 X30.000 Y20.000 F3000"
    assert "Undefined feed rate" in str(err) and "G1 X30.000 Y20.000 F3000" in str(err)
    plotter.abort()


def test_alarm_names_its_meaning_and_the_line_being_run():
    plotter, _fake = fake_plotter(alarm_at=6)
    with pytest.raises(ProtocolError) as info:
        plotter.plot(squares(1))
    assert info.value.code == "ALARM:1" and "Hard limit" in str(info.value)
    assert info.value.command is not None and info.value.command.startswith("G")
    plotter.abort()


def test_a_line_lost_on_the_wire_interrupts_instead_of_hanging():
    plotter, _fake = fake_plotter(lose=lambda line: line == "G1 X30.000 Y30.000")
    with pytest.raises(PlotInterrupted) as info:
        plotter.plot(squares(2))
    assert isinstance(info.value.cause, LinkTimeout) and "never acknowledged" in str(info.value.cause)
    plotter.abort()


def test_garbled_status_report_is_a_parse_error():
    plotter, fake = fake_plotter()
    fake.out += b"<Idle|MPos:0.000,zero,0.000|FS:0,0>\r\n"
    with pytest.raises(pixelpen.ParseError):
        plotter.query_status()


# -- end to end through sim:grbl --------------------------------------------------------------------------
def test_square_lands_where_it_should_on_the_simulated_paper():
    with pixelpen.open("sim:grbl?speed=fast") as plotter:
        dev = plotter.link.port.sim_device
        plotter.plot(squares(1, at=(20.0, 30.0)))
        assert [line for _, line in dev.log][-6:] == [
            "G0X20.000Y30.000", "M3S50G4P0.15G1X30.000Y30.000F3000", "G1X30.000Y40.000",
            "G1X20.000Y40.000", "G1X20.000Y30.000", "M3S500G4P0.15"]
    expected = render([np.array([[20, 30], [30, 30], [30, 40], [20, 40], [20, 30]], float)])
    assert np.array_equal(dev.paper_image(50).array, expected)


def test_drawing_a_picture_puts_ink_at_its_world_coordinates():
    with pixelpen.open("sim:grbl?speed=fast") as plotter:
        dev = plotter.link.port.sim_device
        plotter.draw(pixelpen.Polyline([(50, 60), (90, 60), (90, 100)]))
    (_, ink), = dev.paper.strokes()
    assert np.allclose(ink, [[50, 60], [90, 60], [90, 100]], atol=0.01)


def test_z_axis_pen_draws_the_same_square():
    with pixelpen.open("sim:grbl?speed=fast&pen=z&pen_up=3&pen_down=0") as plotter:
        dev = plotter.link.port.sim_device
        plotter.plot(squares(1, at=(20.0, 30.0)))
        assert [line for _, line in dev.log][-9:-6] == ["G0X20.000Y30.000", "G1Z0F600", "G4P0"]
    ink = [s for _, s in dev.paper.strokes()]
    expected = render([np.array([[20, 30], [30, 30], [30, 40], [20, 40], [20, 30]], float)])
    assert np.array_equal(render(ink), expected)


def test_auto_port_finds_an_arduino(monkeypatch):
    from pixelpen.devices.plotters import grbl
    from pixelpen.drivers.discovery import DiscoveredDevice
    from pixelpen.errors import LinkError

    ports = [DiscoveredDevice("serial", "/dev/ttyS0", "ttyS0"),
             DiscoveredDevice("serial", "/dev/ttyACM0", "Arduino Uno", 0x2341, 0x0043, model="grbl")]
    monkeypatch.setattr(grbl, "list_serial_ports", lambda: ports)
    assert grbl.find_grbl_port() == "/dev/ttyACM0"
    monkeypatch.setattr(grbl, "list_serial_ports", lambda: ports[:1])
    with pytest.raises(LinkError, match="ttyS0"):
        grbl.find_grbl_port()


def test_confirmation_means_on_paper():
    dev, clock = new_sim()
    seen = []

    def check(progress):
        seen.append((progress.strokes_done, len(dev.paper.strokes()), dev.paper.pen_is_down))

    plotter = sim_plotter(dev, clock, on_progress=check)
    plotter.plot(squares(5))
    plotter.close()
    assert [done for done, _, _ in seen] == [1, 2, 3, 4, 5]
    assert all(strokes == done and not down for done, strokes, down in seen)


def test_ctrl_c_leaves_the_pen_up_and_the_machine_idle():
    dev, clock = new_sim()

    def interrupt(progress):
        if progress.strokes_done == 2:
            raise KeyboardInterrupt

    plotter = sim_plotter(dev, clock, on_progress=interrupt)
    with pytest.raises(KeyboardInterrupt):
        plotter.plot(squares(10))
    assert dev.state == "Idle" and not dev.paper.pen_is_down
    dev.receive(b"?")
    status = dev.take_output().decode()
    assert re.search(r"\|FS:0,0\b", status), status  # no motion, spindle (servo PWM) off
    assert len(dev.paper.strokes()) < 10
    plotter.close()


def test_feed_hold_pauses_and_cycle_start_resumes():
    """The hold button mid-plot pauses GRBL (on_pause hears it once it has stopped); cycle start (``~``) resumes."""

    class Operator(SimulatedClock):
        """Simulated time with an operator who presses cycle start three seconds into a hold."""

        def advance(self, seconds):
            super().advance(seconds)
            if dev.state.startswith("Hold") and self.now() > held_since[0] + 3.0:
                dev.receive(b"~")
            elif dev.state.startswith("Hold") and held_since[0] == float("inf"):
                held_since[0] = self.now()

    held_since = [float("inf")]
    clock = Operator()
    dev, _ = new_sim(clock)
    paused = []
    plotter = sim_plotter(dev, clock, url_extra="&pause_after=200", on_pause=lambda p: paused.append((p, dev.state)))
    plotter.plot(squares(4))
    plotter.close()
    assert held_since[0] < float("inf")
    assert paused[0] == (True, "Hold:0") and paused[-1][0] is False  # told once the machine had stopped
    assert ink_account(intended(squares(4)), drawn(dev)) == InkAccount(0, 0, 0)


# -- resuming: compared as segment sets with the intended drawing -------------------------------------------
@dataclass
class InkAccount:
    """What a sheet holds against the intended drawing: segments lost, doubled, and stray pieces."""

    lost: int
    doubled: int
    stray: int


def ink_account(intended: list[np.ndarray], drawn: list[np.ndarray], tol: float = 0.05) -> InkAccount:
    """Segment-set comparison (mm): every drawn piece is credited to the intended segment it lies on.

    A piece lies on a segment when both its ends are within ``tol`` of it; among several (at a corner) it runs
    along the one most parallel to it, in its drawing direction.  A segment is lost when a stretch longer than
    ``tol`` is not covered, doubled when its pieces overlap by more than ``tol``; a piece on none is stray.
    """
    ref = np.array([np.r_[a, b] for p in intended for a, b in itertools.pairwise(p) if np.hypot(*(b - a)) > 1e-9])
    a, d = ref[:, :2], ref[:, 2:] - ref[:, :2]
    length = np.hypot(*d.T)
    spans: list[list[tuple[float, float]]] = [[] for _ in ref]
    stray = 0
    for piece in drawn:
        for p0, p1 in itertools.pairwise(piece):
            if np.hypot(*(p1 - p0)) <= 1e-9:
                continue
            far, ts = np.zeros(len(ref)), []
            for q in (p0, p1):
                t = np.clip(((q - a) * d).sum(1) / length**2, 0.0, 1.0)
                far = np.maximum(far, np.hypot(*(a + t[:, None] * d - q).T))
                ts.append(t * length)
            near = np.flatnonzero(far <= tol)
            if not len(near):
                stray += 1
                continue
            k = int(near[np.argmax((d[near] / length[near, None]) @ ((p1 - p0) / np.hypot(*(p1 - p0))))])
            spans[k].append(tuple(sorted((ts[0][k], ts[1][k]))))
    lost = doubled = 0
    for k, pieces in enumerate(spans):
        reach = total = covered = gap = 0.0
        for t0, t1 in sorted(pieces):
            total += t1 - t0
            gap = max(gap, t0 - reach)
            covered += max(0.0, t1 - max(t0, reach))
            reach = max(reach, t1)
        lost += max(gap, length[k] - reach) > tol
        doubled += total - covered > tol
    return InkAccount(lost, doubled, stray)


def test_ink_account_sees_lost_doubled_and_stray_segments():
    square = np.array([[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]], float)
    assert ink_account([square], [square]) == InkAccount(0, 0, 0)
    assert ink_account([square], [square[:3], square[2:]]) == InkAccount(0, 0, 0)  # resumed at a vertex
    assert ink_account([square], [np.array([[0, 0], [4, 0]]), np.array([[4, 0], [10, 0], [10, 10], [0, 10], [0, 0]])]) \
        == InkAccount(0, 0, 0)  # resumed inside a segment
    assert ink_account([square], [square[:3]]) == InkAccount(2, 0, 0)
    assert ink_account([square], [square, square[:2]]) == InkAccount(0, 1, 0)  # a segment drawn twice
    assert ink_account([square], [square, np.array([[5, 5], [6, 6]])]) == InkAccount(0, 0, 1)
    spike = np.array([[0, 0], [10, 0], [0, 0.1]])  # an acute corner: the way back is credited to its own segment
    assert ink_account([spike], [spike]) == InkAccount(0, 0, 0)


OPEN_STROKES = [[[20, 20], [45, 22], [30, 40]], [[50, 20], [52, 48], [60, 30], [70, 45]], [[25, 60], [60, 62]],
                [[100, 25], [120, 40]], [[40, 70], [41, 80], [48, 72]]]
CLOSED_STROKE = [[80, 20], [90, 20], [90, 30], [80, 30], [80, 20]]
"""Its start and end are the same point: seen there, the position alone cannot tell before from after."""


def drawing_mm(strokes) -> DisplayList:
    return DisplayList.from_polylines([np.array(p, float) * MM for p in strokes], unit_mm=PROFILE.unit_mm)


RESUME_DRAWING = drawing_mm([*OPEN_STROKES[:3], CLOSED_STROKE, *OPEN_STROKES[3:]])
"""Open polylines, a closed square and a few acute corners, 6 strokes."""


def intended(dl: DisplayList) -> list[np.ndarray]:
    """The drawing's polylines in mm (the sheet's frame: the grbl profile's paper starts at 0,0)."""
    return [dl.points[dl.offsets[i]:dl.offsets[i + 1]] * dl.unit_mm for i in range(len(dl))]


def drawn(dev) -> list[np.ndarray]:
    return [pts for _, pts in dev.paper.strokes()]


def fault_points(seed: int, n: int, total: int) -> list[int]:
    return np.random.default_rng(seed).integers(40, total - 10, size=n).tolist()


def plotted_bytes(dl: DisplayList) -> int:
    dev, clock = new_sim()
    plotter = sim_plotter(dev, clock)
    plotter.plot(dl)
    plotter.close()
    assert ink_account(intended(dl), drawn(dev)) == InkAccount(0, 0, 0)  # the uninterrupted plot is the drawing
    return dev.stats.bytes_received


@pytest.mark.parametrize("strokes", [pytest.param(OPEN_STROKES, id="open"),
                                     pytest.param([*OPEN_STROKES[:3], CLOSED_STROKE, *OPEN_STROKES[3:]], id="closed")])
@pytest.mark.parametrize("fault", ["drop_after", "stall_after"])
def test_resume_after_a_link_fault_draws_every_segment_once(fault, strokes):
    """Drop or stall anywhere: the resume asks GRBL where it stopped and continues exactly there.

    A closed stroke seen at its start/end is told apart because a servo pen never rests down at a stroke's
    start nor lifted at its end (its moves share lines with the motion: ``stroke_lines``).
    """
    dl = drawing_mm(strokes)
    points = fault_points(7 if fault == "drop_after" else 11, 8, plotted_bytes(dl))
    interrupted = 0
    for at in points:
        dev, clock = new_sim()
        plotter = sim_plotter(dev, clock, url_extra=f"&{fault}={at}", timeout=0.5)
        try:
            plotter.plot(dl)
        except PlotInterrupted as exc:
            interrupted += 1
            assert exc.resume_from == plotter.confirmed
            plotter.resume_after_fault()
        plotter.close()
        assert plotter.confirmed == len(dl)
        assert ink_account(intended(dl), drawn(dev)) == InkAccount(0, 0, 0), f"{fault}={at}"
    assert interrupted >= 6


def test_a_corrupted_byte_is_caught_and_nothing_is_lost():
    """GRBL drops a byte >= 0x80 (an inverted one): a rejected line, a wrong target or a wrong pen value.

    The plot stops (a device error, an off-path status report or missing acknowledgements) and the
    resume draws from where the device left the path: nothing is lost or drawn twice, and the place is found
    without asking.  A wrong target draws its wrong leg before any report can show it (GRBL has no checksum), so
    a stray piece may stay; it is at most one per fault.  Besides 8 random bytes: 450 (a leg lost when the first
    explanation was taken without the last report on the path), 255, 351 and 591 (a stroke drawn twice when GRBL
    was held with the pen lifted at a stroke's end, or with the pen down just past a stroke's start).
    """
    points = [*fault_points(13, 8, plotted_bytes(RESUME_DRAWING)), 450, 255, 351, 591]
    caught = 0
    for at in points:
        dev, clock = new_sim()
        plotter = sim_plotter(dev, clock, url_extra=f"&corrupt_at={at}", timeout=0.5)
        try:
            plotter.plot(RESUME_DRAWING)
        except PlotInterrupted:
            caught += 1
            plotter.resume_after_fault()
        plotter.close()
        account = ink_account(intended(RESUME_DRAWING), drawn(dev))
        assert account.lost == 0 and account.doubled == 0 and account.stray <= 1, f"corrupt_at={at}: {account}"
    assert caught >= 5


def test_power_loss_asks_and_homing_lets_it_go_on_without_losing_a_segment():
    """A reboot loses GRBL's position: the resume refuses to guess; after $H and a confirmation it goes on."""
    dev, clock = new_sim()
    dev.settings[22] = 1.0  # homing enabled: after power-up GRBL waits alarm-locked for $H
    total = plotted_bytes(RESUME_DRAWING)
    plotter = sim_plotter(dev, clock, url_extra=f"&power_loss_after={total // 2}", timeout=0.5, unlock=True)
    with pytest.raises(PlotInterrupted):
        plotter.plot(RESUME_DRAWING)
    before = len(drawn(dev))
    with pytest.raises(PositionUnknown, match="restarted"):
        plotter.resume_after_fault()
    assert len(drawn(dev)) == before  # nothing was drawn at a guessed place
    plotter.go_home()  # $H: the machine knows where it is again
    plotter.resume_after_fault(position_confirmed=True)
    plotter.close()
    account = ink_account(intended(RESUME_DRAWING), drawn(dev))
    assert account.lost == 0 and account.stray == 0, account  # strokes since the last confirmation are redrawn


def test_manual_pen_home_and_motors_off():
    """``pixelpen pen ...``: servo S values as the profile says, G0 home without homing switches, $SLP: motors off."""
    dev, clock = new_sim()
    plotter = sim_plotter(dev, clock)
    plotter.pen_down()
    assert dev.paper.pen_is_down  # M3 S50: below the inverted servo's threshold 275, the pen touches
    plotter.toggle_pen()
    assert not dev.paper.pen_is_down
    plotter.plot(drawing_mm([[[20, 20], [30, 25]]]))
    plotter.go_home()
    assert np.allclose(dev.machine_position()[:2], [0.0, 0.0]) and not dev.paper.pen_is_down
    plotter.motors_off()
    assert dev.state == "Sleep"  # commands.md $SLP: steppers, spindle and coolant off until a reset
    plotter.close()
    with pytest.raises(ProtocolError, match=r"alarm-locked"):  # woken by the reset: it must be homed first
        sim_plotter(dev, clock)


def test_the_pause_is_told_once_the_hold_is_complete_and_a_release_then_resumes():
    """on_pause(True) comes at Hold:0: a cycle start sent then resumes (GRBL ignores one during Hold:1)."""
    dev, clock = new_sim()
    states = []

    def operator(paused):
        if paused:
            states.append(dev.state)
            assert dev.state == "Hold:0"  # (told at Hold:1, the cycle start below would be ignored: a hang)
            dev.receive(b"~")  # as soon as the driver says it has paused

    plotter = sim_plotter(dev, clock, url_extra="&pause_after=200", on_pause=operator)
    plotter.plot(squares(4))
    plotter.close()
    assert states == ["Hold:0"]
    assert ink_account(intended(squares(4)), drawn(dev)) == InkAccount(0, 0, 0)


def host_bytes(dl: DisplayList) -> bytes:
    """Every byte the driver sends GRBL in an uninterrupted plot of ``dl`` (the fault offsets count these)."""
    dev, clock = new_sim()
    got = bytearray()
    receive = dev.receive
    dev.receive = lambda data: (got.extend(data), receive(data))[1]
    plotter = sim_plotter(dev, clock)
    plotter.plot(dl)
    plotter.close()
    return bytes(got)


@pytest.mark.parametrize(("line", "byte", "stray"), [
    pytest.param(b"G1 X60.000 Y30.000", 4, 1, id="target-digit"),  # X0.000: a wrong leg, caught off the path
    pytest.param(b"G1 X60.000 Y30.000", 0, 0, id="letter"),  # '1 X60...': error:1, the leg never runs
    pytest.param(b"G1 X60.000 Y30.000", 18, 0, id="newline"),  # joined with the next line: rejected both
    pytest.param(b"G1 X60.000 Y30.000", 13, 1, id="y-digit"),  # Y3.000: a wrong leg the other way
    # P015: a 15 s dwell before the travel; GRBL answers the resume's $$ with that travel still queued
    pytest.param(b"M3 S500 G4 P0.15 G0 X50.000 Y20.000", 13, 0, id="dwell"),
])
def test_a_dropped_byte_is_located_and_redrawn_from_the_line_it_spoiled(line, byte, stray):
    """A byte GRBL drops (corrupt_at: inverted, >= 0x80) spoils one line: the resume starts at that line's start.

    Nothing is lost or drawn twice; a wrong target draws its wrong leg until a status report shows it (at most
    one stray piece, GRBL has no checksum); a rejected line draws nothing wrong.
    """
    dl = drawing_mm(OPEN_STROKES[:3])
    at = host_bytes(dl).index(line) + byte
    dev, clock = new_sim()
    plotter = sim_plotter(dev, clock, url_extra=f"&corrupt_at={at}", timeout=0.5)
    with pytest.raises((PlotInterrupted, ProtocolError)):
        plotter.plot(dl)
    plotter.resume_after_fault()  # located: no PositionUnknown
    plotter.close()
    account = ink_account(intended(dl), drawn(dev))
    assert (account.lost, account.doubled) == (0, 0) and account.stray <= stray, account

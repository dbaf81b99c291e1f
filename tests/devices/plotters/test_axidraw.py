"""The AxiDraw driver against a scripted EiBotBoard (bytes, replies, errors) and the EBB simulator (end to end)."""

from __future__ import annotations

import numpy as np
import pytest

import pixelpen
from pixelpen.clock import SimulatedClock
from pixelpen.devices.plotters.axidraw import AxiDrawPlotter
from pixelpen.devices.plotters.base import PlotInterrupted, PositionUnknown
from pixelpen.devices.plotters.ebb_stream import RETRIES
from pixelpen.drivers.serial import SerialLink
from pixelpen.drivers.stream import Link
from pixelpen.errors import ConfigError, LinkError, ProtocolError, URLError
from pixelpen.profiles.model import load_profile
from pixelpen.sim.base import create_simulator
from pixelpen.sim.plotters.sheet import Sheet
from pixelpen.urls import parse_url
from pixelpen.vector.displaylist import DisplayList
from tests.devices.plotters.test_grbl import CLOSED_STROKE, OPEN_STROKES, InkAccount, ink_account

PROFILE = load_profile("axidraw_v3")
STEPS = 80  # device units (motor steps at 16x) per millimetre
CONNECT = b"#\rV\rQM\rEM,1,1\rSC,4,20641\rSC,5,15248\rSC,11,400\rSC,12,400\rSP,1,324\rQC\r"
"""Connection by hand from ebb.html and the axidraw_v3 profile: flush, version, idle check, 16x stepping,
servo up = 9855 + 17976 x 60 % = 20641, down = 9855 + 17976 x 30 % = 15248, the raise and lower rates as
pyaxidraw's servo set-up sends them (SC,11 / SC,12, fw >= 2.6.0) at the firmware's boot value 400, pen up
with a delay covering the slew (|20641 - 15248| x 24 ms / 400 = 323.6 -> 324 ms, longer than the profile's
120 ms), then the motor supply check pyaxidraw makes before plotting (QC)."""
PEN_MS = 324
GATE = "SM,1,0,0"
"""The two 1 ms pauses before every pen-down, whose supply checks certify the travel before the pen goes down."""
VPLUS_9V = 293
"""QC's V+ reading of a 9 V supply: (9 − 0.3) / 9.2 / 3.3 x 1023 (saxi's divider formula, inverted)."""


def legacy_reply(cmd: str, version: str) -> bytes:
    """What a legacy-syntax EBB answers (ebb.html "Response (legacy mode; default)")."""
    name = cmd.split(",")[0].upper()
    if name == "V":
        return f"EBBv13_and_above EB Firmware Version {version}\r\n".encode()
    if name == "QM":
        return b"QM,0,0,0,0\n\r"
    if name == "QG":
        return b"10\r\n"
    if name == "QB":
        return b"0\r\nOK\r\n"
    if name == "QS":
        return b"0,0\n\rOK\r\n"
    if name == "QC":
        return f"0394,{VPLUS_9V:04d}\r\nOK\r\n".encode()
    if name == "QE":
        return b"16,16\r\nOK\r\n"
    if name == "QP":
        return b"1\n\rOK\r\n"
    if name in ("SM", "XM", "LM", "SP", "SC", "EM", "CU", "SR"):
        return b"OK\r\n"
    return f"!8 Err: Unknown command '{name}:{ord(name[0]):02X}'OK\r\n".encode()


def future_reply(cmd: str, version: str) -> bytes:
    """The same board after ``CU,10,1`` (future syntax: every reply is ``NAME[,data]\\n``)."""
    name = cmd.split(",")[0].upper()
    legacy = legacy_reply(cmd, version).decode()
    if name == "V":
        return f"V,{legacy.strip()}\n".encode()
    if legacy.startswith("!"):
        return f"{name},{legacy[:-4]}\n".encode()
    data = legacy.replace("OK\r\n", "").strip().removeprefix("QM,")
    return (f"{name},{data}\n" if data else f"{name}\n").encode()


class FakeEbb(Link):
    """An EiBotBoard scripted from ebb.html: answers each ``\\r``-terminated command at once, records them."""

    def __init__(self, clock, version="2.8.1", reply=legacy_reply, override=None):
        super().__init__("fake-ebb", timeout=1.0, clock=clock)
        self.version = version
        self.reply = reply
        self.override = override or (lambda cmd: None)
        self.written = bytearray()
        self.commands: list[str] = []
        self.out = bytearray()
        self._line = bytearray()

    def _write_raw(self, data, wait):
        for b in data:
            self.written.append(b)
            if b == 0x0D:
                cmd = self._line.decode()
                self._line.clear()
                self.commands.append(cmd)
                special = self.override(cmd)
                self.out += special if special is not None else self.reply(cmd, self.version)
            else:
                self._line.append(b)
        return len(data)

    def _read_raw(self, wait):
        out, self.out = bytes(self.out), bytearray()
        return out

    def _raw_in_waiting(self):
        return len(self.out)

    def _close_raw(self):
        pass


def fake_plotter(version="2.8.1", reply=legacy_reply, override=None, **kwargs):
    clock = SimulatedClock()
    fake = FakeEbb(clock, version, reply, override)
    plotter = AxiDrawPlotter("fake", profile=PROFILE, clock=clock, link_factory=lambda: fake, **kwargs)
    plotter.open()
    return plotter, fake


def motion(commands: list[str]) -> np.ndarray:
    """Carriage path (x, y steps) after each SM: x = (m1 + m2) / 2, y = (m1 − m2) / 2 (AxiDraw mixing)."""
    m = np.array([[int(v) for v in c.split(",")[2:4]] for c in commands if c.startswith("SM")])
    return np.cumsum(np.column_stack([(m[:, 0] + m[:, 1]) // 2, (m[:, 0] - m[:, 1]) // 2]), axis=0)


def squares(n, side_mm=10.0, at=(20.0, 20.0), step_mm=3.0) -> DisplayList:
    base = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], float) * side_mm
    return DisplayList.from_polylines([(base + np.array(at) + i * step_mm) * STEPS for i in range(n)],
                                      unit_mm=PROFILE.unit_mm)


# -- connecting ---------------------------------------------------------------------------------------------
def test_connect_bytes():
    plotter, fake = fake_plotter()
    assert bytes(fake.written) == CONNECT
    assert plotter.version == (2, 8, 1) and not plotter.future_syntax
    plotter.close()


def test_future_syntax_board_is_understood():
    plotter, fake = fake_plotter(version="3.0.2", reply=future_reply)
    assert plotter.future_syntax
    plotter.plot(squares(1))
    plotter.close()
    assert fake.commands[-1] == "EM,0,0"


def test_servo_rates_only_from_firmware_2_6_0_and_pen_delays_cover_the_slew():
    """Before 2.6.0 no SC,11/12 and the profile's 120 ms; a faster rate shortens the delay to the profile's."""
    plotter, fake = fake_plotter(version="2.5.3")
    assert not any(c.startswith(("SC,11", "SC,12")) for c in fake.commands) and "SP,1,120" in fake.commands
    plotter.close()
    plotter, fake = fake_plotter(pen_rate_up=5393, pen_rate_down=1000)
    assert fake.commands[6:10] == ["SC,11,5393", "SC,12,1000", "SP,1,120", "QC"]  # 24 ms < 120 ms lift
    plotter.plot(DisplayList.from_polylines([np.array([[0, 0], [80, 0]])], unit_mm=PROFILE.unit_mm))
    assert "SP,0,130" in fake.commands  # lowering at 1000: ceil(5393 x 24 / 1000) = 130 ms > 120 ms
    plotter.close()
    with pytest.raises(ConfigError, match="SC,11/12"):
        AxiDrawPlotter("fake", profile=PROFILE, pen_rate_up=0)


def test_old_firmware_and_missing_features_are_refused():
    with pytest.raises(ProtocolError, match=r"2\.4\.4"):
        fake_plotter(version="2.4.0")
    with pytest.raises(ConfigError, match=r"2\.7\.0"):
        fake_plotter(version="2.6.5", moves="lm")
    plotter, _fake = fake_plotter(version="2.6.5", moves="xm")
    plotter.close()


def test_model_option_picks_the_profile_and_the_simulator():
    plotter = AxiDrawPlotter.from_url(parse_url("axidraw:/dev/null?model=se_a3&moves=xm&pen_up=70&pen_down=20"))
    assert plotter.profile.name == "axidraw_se_a3" and plotter.moves == "xm"
    assert (plotter.servo_up, plotter.servo_down) == (round(9855 + 17976 * 0.7), round(9855 + 17976 * 0.2))
    sim = AxiDrawPlotter.from_url(parse_url("sim:axidraw?model=minikit&speed=fast"))
    assert sim.profile.name == "axidraw_minikit" and "model=minikit" in sim.port


def test_sim_urls_run_the_link_at_usb_speed_unless_baud_is_given():
    with pixelpen.open("sim:axidraw?speed=fast") as plotter:
        assert plotter.link.port.sim_port.baud == 12_000_000
    assert "baud=12000000" in AxiDrawPlotter.from_url(parse_url("sim:axidraw?speed=fast")).port
    with pixelpen.open("sim:axidraw?speed=fast&baud=115200") as plotter:
        assert plotter.link.port.sim_port.baud == 115200


@pytest.mark.parametrize("query", ["model=a2", "moves=hm", "pen_up=101", "pen_down=-5", "feed=3"])
def test_bad_url_options_are_refused(query):
    with pytest.raises(URLError):
        AxiDrawPlotter.from_url(parse_url(f"axidraw:/dev/null?{query}"))


def test_auto_port_finds_the_eibotboard(monkeypatch):
    from pixelpen.devices.plotters import axidraw
    from pixelpen.drivers.discovery import DiscoveredDevice
    from pixelpen.errors import LinkError

    ports = [DiscoveredDevice("serial", "/dev/ttyUSB0", "FT232R", 0x0403, 0x6001),
             DiscoveredDevice("serial", "/dev/ttyACM3", "EiBotBoard", 0x04D8, 0xFD92)]
    monkeypatch.setattr(axidraw, "list_serial_ports", lambda: ports)
    assert axidraw.find_ebb_port() == "/dev/ttyACM3"
    monkeypatch.setattr(axidraw, "list_serial_ports", lambda: ports[:1])
    with pytest.raises(LinkError, match=r"04D8:FD92.*ttyUSB0"):
        axidraw.find_ebb_port()


# -- byte-level moves -----------------------------------------------------------------------------------------
def test_ten_millimetre_line_is_800_steps_on_both_motors():
    plotter, fake = fake_plotter()
    start = len(fake.commands)
    plotter.plot(DisplayList.from_polylines([np.array([[0, 0], [800, 0]])], unit_mm=PROFILE.unit_mm))
    sent = [c for c in fake.commands[start:] if not c.startswith("Q") and c != GATE]
    assert sent[0] == f"SP,0,{PEN_MS}" and sent[-1] == f"SP,1,{PEN_MS}"
    moves = [tuple(int(v) for v in c.split(",")[1:]) for c in sent[1:-1]]
    assert all(m1 == m2 for _, m1, m2 in moves)             # pure +x: both motors turn alike
    assert sum(m1 for _, m1, _ in moves) == 800              # 10 mm x 80 steps/mm
    assert all(ms >= 1 for ms, _, _ in moves)
    plotter.close()


def test_unit_square_and_pen_lift_sequence():
    plotter, fake = fake_plotter()
    start = len(fake.commands)
    plotter.plot(squares(1, at=(5.0, 3.0)))
    sent = [c for c in fake.commands[start:] if not c.startswith("Q")]
    down, up = sent.index(f"SP,0,{PEN_MS}"), sent.index(f"SP,1,{PEN_MS}")
    travel, stroke = sent[:down], sent[down + 1:up]
    assert motion(travel)[-1].tolist() == [400, 240]          # pen-up travel from home to (5 mm, 3 mm)
    path = motion(stroke) + [400, 240]  # noqa: RUF005  (an array: the offset added to every point)
    corners = {(1200, 240), (1200, 1040), (400, 1040), (400, 240)}
    assert corners <= {tuple(p) for p in path.tolist()}       # every corner is reached exactly
    on_edge = np.isin(path[:, 0], [400, 1200]) | np.isin(path[:, 1], [240, 1040])
    assert on_edge.all()                                      # and no slice cuts across the square
    plotter.close()
    park = [c for c in fake.commands if c.startswith("SM")]
    assert motion(park)[-1].tolist() == [0, 0]                # parked at home after the job
    assert fake.commands[-1] == "EM,0,0"


def test_xm_sends_the_axes_unmixed():
    plotter, fake = fake_plotter(moves="xm")
    plotter.plot(DisplayList.from_polylines([np.array([[0, 0], [0, 800]])], unit_mm=PROFILE.unit_mm))
    xms = [tuple(int(v) for v in c.split(",")[2:]) for c in fake.commands if c.startswith("XM")]
    assert all(a == 0 for a, _ in xms) and sum(b for _, b in xms) == 800
    plotter.close()


def test_error_reply_names_the_command():
    """A command the board refuses every time it is sent (1 + RETRIES times) stops the plot, naming it."""
    first_sm = []

    def reject(cmd):
        if cmd.startswith("SM") and cmd != GATE and (not first_sm or cmd == first_sm[0]):
            first_sm.append(cmd)
            return b"!6 Err: Invalid parameter valueOK\r\n"
        return None

    plotter, _fake = fake_plotter(override=reject)
    with pytest.raises(ProtocolError) as info:
        plotter.plot(squares(1))
    assert info.value.code == 6 and info.value.command == first_sm[0] and len(first_sm) == 1 + RETRIES
    assert first_sm[0] in str(info.value) and "Invalid parameter value" in str(info.value)
    plotter.abort()


def test_a_refused_command_is_sent_again_in_its_place_and_nothing_runs_before_it():
    """One garbled command: nothing behind it was written yet (WINDOW), so the same command goes out again."""
    clean, clean_fake = fake_plotter()
    clean.plot(squares(2))
    clean.close()
    written: list[str] = []
    refused: list[int] = []

    def reject_some(cmd):
        written.append(cmd)
        if len(written) in (40, 90, 91, 200) and cmd.startswith(("SM", "SP")) and (len(written) - 1) not in refused:
            refused.append(len(written) - 1)
            return b"!8 Err: Unknown command 'S\xc2:53C2'OK\r\n"
        return None

    plotter, fake = fake_plotter(override=reject_some)
    plotter.plot(squares(2))
    plotter.close()
    assert len(refused) >= 2 and plotter.confirmed == 2
    again = list(fake.commands)
    for i in reversed(refused):  # sent again right after the supply check written with it; else the clean run's bytes
        assert again[i + 1 : i + 3] == ["QC", again[i]]
        del again[i + 2]
    assert again == clean_fake.commands


def test_button_is_read_with_qb_before_firmware_2_6_2():
    presses = iter([b"1\r\nOK\r\n", b"0\r\nOK\r\n", b"1\r\nOK\r\n"])
    plotter, fake = fake_plotter(version="2.5.3", override=lambda cmd: next(presses) if cmd == "QB" else None)
    states = []
    for _ in range(3):
        states.append(plotter._device_paused())
        plotter.clock.sleep(0.06)
    plotter._poll()
    assert plotter.paused is False and states[1] is True  # pressed: paused; pressed again: resumed
    assert fake.commands.count("QB") == 3 and "QG" not in fake.commands
    plotter.close()


def test_garbled_reply_is_a_resumable_link_fault():
    plotter, _fake = fake_plotter(override=lambda cmd: b"KO\r\n" if cmd.startswith("SP,0") else None)
    with pytest.raises(PlotInterrupted) as info:
        plotter.plot(squares(1))
    assert isinstance(info.value.cause, pixelpen.ParseError) and "'KO'" in str(info.value.cause)
    plotter.abort()


# -- end to end through sim:axidraw ------------------------------------------------------------------------------
def new_sim(clock=None):
    clock = clock or SimulatedClock()
    return create_simulator("axidraw", clock=clock), clock


def sim_plotter(dev, clock, url_extra="", **kwargs) -> AxiDrawPlotter:
    urls = iter([f"sim://axidraw?baud=1000000{url_extra}"])

    def factory():
        return SerialLink(next(urls, "sim://axidraw?baud=1000000"), clock=clock, device=dev)

    plotter = AxiDrawPlotter("sim://axidraw", profile=PROFILE, clock=clock, link_factory=factory, **kwargs)
    plotter.open()
    return plotter


def inked(paper: Sheet) -> list[np.ndarray]:
    """The strokes on the sheet."""
    return [s for _, s in paper.strokes()]


def render(strokes, width=300.0, height=218.0, dpi=50) -> np.ndarray:
    paper = Sheet(width, height, y_down=True)
    for pts in strokes:
        paper.pen_down(pts[0])
        paper.line_to(pts)
        paper.pen_up()
    return paper.paper_image(dpi).array


def test_square_lands_where_it_should_on_the_simulated_paper():
    with pixelpen.open("sim:axidraw?speed=fast") as plotter:
        dev = plotter.link.port.sim_device
        plotter.plot(squares(1, at=(20.0, 30.0)))
    expected = render([np.array([[20, 30], [30, 30], [30, 40], [20, 40], [20, 30]], float)])
    assert np.array_equal(render(inked(dev.paper)), expected)
    assert np.allclose(dev.position_mm, 0.0) and dev.pen_up


def test_board_in_future_syntax_draws_the_same_paper():
    images = []
    for syntax in ("legacy", "future"):
        clock = SimulatedClock()
        dev = create_simulator("axidraw", clock=clock, syntax=syntax)
        plotter = sim_plotter(dev, clock)
        assert plotter.future_syntax == (syntax == "future")
        plotter.plot(squares(1, side_mm=3.0, at=(3.0, 3.0)))
        plotter.close()
        images.append(dev.paper_image(50).array)
    assert np.array_equal(images[0], images[1])


def test_sm_and_xm_draw_the_same_paper():
    images = []
    for moves in ("sm", "xm"):
        dev, clock = new_sim()
        plotter = sim_plotter(dev, clock, moves=moves)
        plotter.plot(squares(2, side_mm=3.0))
        plotter.close()
        images.append(dev.paper_image(50).array)
    assert np.array_equal(images[0], images[1])


def test_lm_moves_draw_the_square():
    dev, clock = new_sim()
    plotter = sim_plotter(dev, clock, moves="lm")
    plotter.plot(squares(1, side_mm=3.0))
    plotter.close()
    expected = render([np.array([[20, 20], [23, 20], [23, 23], [20, 23], [20, 20]], float)])
    assert np.array_equal(render(inked(dev.paper)), expected)


def test_confirmation_means_on_paper():
    dev, clock = new_sim()
    seen = []

    def check(progress):
        seen.append((progress.strokes_done, len(inked(dev.paper)), dev.paper.pen_is_down))

    plotter = sim_plotter(dev, clock, on_progress=check)
    plotter.plot(squares(3, side_mm=2.0))
    plotter.close()
    assert [done for done, _, _ in seen] == [1, 2, 3]
    # never early: a stroke is confirmed only once it is on paper (and its V+ check came back good)
    assert all(strokes >= done for done, strokes, _ in seen)


def test_ctrl_c_leaves_the_pen_up_and_the_motors_on_for_a_resume():
    dev, clock = new_sim()

    def interrupt(progress):
        raise KeyboardInterrupt

    plotter = sim_plotter(dev, clock, on_progress=interrupt)
    with pytest.raises(KeyboardInterrupt):
        plotter.plot(squares(4, side_mm=2.0))
    assert dev.pen_up and not dev.paper.pen_is_down
    # still energised at 1/16 (ebb.html QE): the step counters keep the position, as pyaxidraw's pause
    dev.receive(b"QE\r")
    assert dev.take_output() == b"16,16\r\nOK\r\n"
    dev.receive(b"QM\r")
    assert dev.take_output() == b"QM,0,0,0,0\n\r"  # nothing moving or queued
    plotter.close()


def test_button_pauses_at_pen_up_and_a_second_press_resumes():
    pen_while_paused: list[bool] = []
    pressed_again: list[float] = []

    def operator():
        """pause_requested hook, asked before every stroke and every 50 ms while paused: presses PRG after 2 s."""
        if not plotter.paused:
            return False
        pen_while_paused.append(dev.pen_up)
        if len(pen_while_paused) > 40 and not pressed_again:  # 40 x 50 ms
            pressed_again.append(clock.now())
            dev.inject("pause-button")
        return False

    dev, clock = new_sim()
    plotter = sim_plotter(dev, clock, url_extra="&pause_after=400", pause_requested=operator)
    plotter.plot(squares(3, side_mm=2.0))
    plotter.close()
    assert pressed_again and len(pen_while_paused) > 40
    assert all(pen_while_paused[1:])  # once the stroke in hand is finished the plot waits with the pen up
    drawing = squares(3, side_mm=2.0)
    want = [drawing.points[drawing.offsets[i]:drawing.offsets[i + 1]] / STEPS for i in range(len(drawing))]
    assert ink_account(want, inked(dev.paper)) == InkAccount(0, 0, 0)


# -- resuming: compared as segment sets with the intended drawing -------------------------------------------


def drawing_mm(strokes) -> DisplayList:
    return DisplayList.from_polylines([np.array(p, float) * STEPS for p in strokes], unit_mm=PROFILE.unit_mm)


def intended(strokes) -> list[np.ndarray]:
    """The polylines in mm as the sheet has them (the axidraw profile's paper starts at the home corner)."""
    return [np.array(p, float) for p in strokes]


def plotted_bytes(strokes) -> int:
    dev, clock = new_sim()
    plotter = sim_plotter(dev, clock)
    plotter.plot(drawing_mm(strokes))
    plotter.close()
    assert ink_account(intended(strokes), inked(dev.paper)) == InkAccount(0, 0, 0)  # uninterrupted: the drawing
    return dev.stats.bytes_received


def fault_points(seed: int, n: int, total: int, start: int = 100) -> list[int]:
    return np.random.default_rng(seed).integers(start, total - 10, size=n).tolist()


@pytest.mark.parametrize("strokes", [pytest.param(OPEN_STROKES, id="open"),
                                     pytest.param([*OPEN_STROKES[:3], CLOSED_STROKE, *OPEN_STROKES[3:]], id="closed")])
@pytest.mark.parametrize("fault", ["drop_after", "stall_after"])
def test_resume_after_a_link_fault_draws_every_segment_once(fault, strokes):
    """Drop or stall anywhere (mid-slice, a travel, the first from home, a loop): the resume goes on exactly."""
    total = plotted_bytes(strokes)
    points = fault_points(3 if fault == "drop_after" else 5, 6, total)
    interrupted = 0
    for at in points:
        dev, clock = new_sim()
        plotter = sim_plotter(dev, clock, url_extra=f"&{fault}={at}")
        try:
            plotter.plot(drawing_mm(strokes))
        except PlotInterrupted as exc:
            interrupted += 1
            assert exc.resume_from == plotter.confirmed
            plotter.resume_after_fault()
        plotter.close()
        assert plotter.confirmed == len(strokes)
        assert ink_account(intended(strokes), inked(dev.paper)) == InkAccount(0, 0, 0), f"{fault}={at}"
    assert interrupted >= 5


def test_a_corrupted_byte_is_refused_sent_again_and_every_segment_is_drawn_once(caplog):
    """The EBB refuses a garbled command (!8, !5 ...); nothing behind it has been written, so it goes out again."""
    strokes = OPEN_STROKES
    points = fault_points(17, 6, plotted_bytes(strokes))
    refused = 0
    for at in points:
        dev, clock = new_sim()
        plotter = sim_plotter(dev, clock, url_extra=f"&corrupt_at={at}")
        caplog.clear()
        try:
            plotter.plot(drawing_mm(strokes))
        except PlotInterrupted:  # a garbled terminator joins two commands: no answer, resumed from the counters
            plotter.resume_after_fault()
        refused += any("sending it again" in r.getMessage() for r in caplog.records)
        plotter.close()
        assert ink_account(intended(strokes), inked(dev.paper)) == InkAccount(0, 0, 0), f"corrupt_at={at}"
    assert refused >= 4


def test_motor_power_loss_stops_the_plot_and_the_resume_asks():
    """V+ gone: the motors stop while the EBB keeps counting steps; QC notices it at the next check."""
    strokes = OPEN_STROKES
    total = plotted_bytes(strokes)
    dev, clock = new_sim()
    plotter = sim_plotter(dev, clock, url_extra=f"&power_loss_after={total // 2}")
    with pytest.raises(PlotInterrupted, match="motor power") as info:
        plotter.plot(drawing_mm(strokes))
    assert plotter.confirmed < len(strokes) and "V+" in str(info.value.cause)
    dev.inject("power-restore")
    before = len(inked(dev.paper))
    with pytest.raises(PositionUnknown, match="motor supply"):
        plotter.resume_after_fault()
    assert len(inked(dev.paper)) == before  # nothing drawn at a guessed place
    plotter.close()


def test_no_motor_power_at_connect_is_refused():
    """pyaxidraw checks QC before plotting: a board without its supply is not plotted on."""
    dev, clock = new_sim()
    dev.inject("power-loss")
    with pytest.raises(LinkError, match="motor power"):
        sim_plotter(dev, clock)


def test_manual_pen_home_and_motors_off():
    dev, clock = new_sim()
    plotter = sim_plotter(dev, clock)
    plotter.pen_down()
    assert not dev.pen_up
    plotter.toggle_pen()
    assert dev.pen_up
    plotter.plot(drawing_mm([[[20, 20], [30, 25]]]))
    plotter.go_home()
    assert np.allclose(dev.position_mm, [0.0, 0.0]) and dev.pen_up
    plotter.motors_off()
    dev.receive(b"QE\r")
    assert dev.take_output() == b"0,0\r\nOK\r\n"  # both motors off (ebb.html QE)
    plotter.close()


def test_after_a_motor_power_loss_a_confirmed_resume_plots_from_the_pushed_home():
    """Pen up, supply off, carriage pushed home, supply on, confirmed: the stale step counters are not trusted."""
    strokes = OPEN_STROKES
    dev, clock = new_sim()
    plotter = sim_plotter(dev, clock, url_extra=f"&power_loss_after={plotted_bytes(strokes) // 2}")
    with pytest.raises(PlotInterrupted, match="motor power"):
        plotter.plot(drawing_mm(strokes))
    dev.inject("power-restore")
    with pytest.raises(PositionUnknown):
        plotter.resume_after_fault()
    plotter.pen_up()
    dev.inject("power-loss")  # the operator switches the supply off to push the carriage home by hand
    dev.push_carriage_home()  # a physical act: the board's step counters still say where it thinks it is
    dev.inject("power-restore")
    plotter.resume_after_fault(position_confirmed=True)
    plotter.close()
    assert ink_account(intended(strokes), inked(dev.paper)) == InkAccount(0, 0, 0)


def test_a_power_loss_anywhere_is_placed_exactly_and_the_confirmed_resume_draws_only_what_is_missing():
    """Travel, pen moves or mid-slice: a supply check behind every queued command places the cut, the pen never
    goes down where a travel stopped short, and after re-homing exactly the rest is drawn (segment sets)."""
    strokes = [*OPEN_STROKES[:3], CLOSED_STROKE]
    total = plotted_bytes(strokes)
    for at in fault_points(23, 5, total, start=total // 8):
        dev, clock = new_sim()
        plotter = sim_plotter(dev, clock, url_extra=f"&power_loss_after={at}")
        with pytest.raises(PlotInterrupted, match="motor power"):
            plotter.plot(drawing_mm(strokes))
        assert ink_account(intended(strokes), inked(dev.paper)).stray == 0, f"power_loss_after={at}: a stray dot"
        dev.inject("power-restore")
        with pytest.raises(PositionUnknown, match="last ran powered to"):
            plotter.resume_after_fault()
        plotter.pen_up()
        plotter.motors_off()
        dev.push_carriage_home()
        plotter.resume_after_fault(position_confirmed=True)
        plotter.close()
        assert ink_account(intended(strokes), inked(dev.paper)) == InkAccount(0, 0, 0), f"power_loss_after={at}"

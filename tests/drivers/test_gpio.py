"""GPIO lines over gpiod 2.x: calls checked against the installed gpiod's own signatures, edges, and the refusals."""

from __future__ import annotations

import errno
import inspect
import sys
import types

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.drivers.gpio import InputLine, OutputLine, open_input_line, open_output_line, pulse_reset
from pixelpen.errors import ConfigError, InvalidArgument, LinkError

gpiod = pytest.importorskip("gpiod")


def edge(rising: bool, offset: int = 25):
    kind = gpiod.EdgeEvent.Type.RISING_EDGE if rising else gpiod.EdgeEvent.Type.FALLING_EDGE
    return gpiod.EdgeEvent(kind.value, 0, offset, 1, 1)


class FakeRequest:
    """A gpiod.LineRequest stand-in: every call is bound to the real method's signature before it is noted."""

    def __init__(self, clock: SimulatedClock, queued: list, arrivals: list[tuple[float, list]]) -> None:
        self.calls: list[tuple[str, tuple]] = []
        self.clock = clock
        self.queued = queued
        self.arrivals = arrivals
        self.values: dict[int, object] = {}
        self.fail: OSError | None = None

    def _call(self, name: str, *args):
        inspect.signature(getattr(gpiod.LineRequest, name)).bind(self, *args)
        self.calls.append((name, args))
        if self.fail is not None:
            raise self.fail

    def set_value(self, line, value):
        self._call("set_value", line, value)
        assert isinstance(value, gpiod.line.Value)
        self.values[line] = value

    def get_value(self, line):
        self._call("get_value", line)
        return self.values.get(line, gpiod.line.Value.INACTIVE)

    def wait_edge_events(self, timeout=None):
        self._call("wait_edge_events", timeout)
        if self.queued:
            return True
        if timeout and self.arrivals and self.arrivals[0][0] <= self.clock.now() + timeout:
            at, events = self.arrivals.pop(0)
            self.clock.advance(at - self.clock.now())
            self.queued.extend(events)
            return True
        self.clock.advance(timeout or 0)
        return False

    def read_edge_events(self, max_events=None):
        self._call("read_edge_events")
        events, self.queued[:] = list(self.queued), []
        return events

    def release(self):
        self._call("release")


@pytest.fixture
def fake(monkeypatch):
    """A gpiod module whose request_lines is checked against the real one; the real enums and settings."""
    module = types.ModuleType("gpiod")
    module.line, module.LineSettings, module.EdgeEvent = gpiod.line, gpiod.LineSettings, gpiod.EdgeEvent
    module.clock = SimulatedClock()
    module.requests, module.error = [], None
    module.queued, module.arrivals = [], []

    def request_lines(*args, **kwargs):
        bound = inspect.signature(gpiod.request_lines).bind(*args, **kwargs)
        if module.error is not None:
            raise module.error
        request = FakeRequest(module.clock, module.queued, module.arrivals)
        module.requests.append((bound.arguments, request))
        return request

    module.request_lines = request_lines
    monkeypatch.setitem(sys.modules, "gpiod", module)
    return module


def test_an_output_line_is_requested_as_gpiod_documents_and_driven(fake):
    line = open_output_line("/dev/gpiochip0", 25, initial=True, consumer="panel")
    assert isinstance(line, OutputLine)
    (arguments, request), = fake.requests
    assert arguments["path"] == "/dev/gpiochip0" and arguments["consumer"] == "panel"
    settings = arguments["config"][25]
    assert settings.direction == gpiod.line.Direction.OUTPUT and settings.output_value == gpiod.line.Value.ACTIVE
    line.set(False)
    line.set(True)
    value = gpiod.line.Value
    assert request.calls == [("set_value", (25, value.INACTIVE)), ("set_value", (25, value.ACTIVE))]
    line.close()
    line.close()
    assert request.calls[-1] == ("release", ()) and request.calls.count(("release", ())) == 1
    with pytest.raises(LinkError, match="closed"):
        line.set(True)


def test_an_output_starting_low(fake):
    open_output_line("/dev/gpiochip4", 7, initial=False)
    assert fake.requests[0][0]["config"][7].output_value == gpiod.line.Value.INACTIVE


def test_an_input_line_reads_and_waits_for_the_next_edge(fake):
    line = open_input_line("/dev/gpiochip0", 24, edge="both", clock=fake.clock)
    assert isinstance(line, InputLine)
    settings = fake.requests[0][0]["config"][24]
    assert settings.direction == gpiod.line.Direction.INPUT and settings.edge_detection == gpiod.line.Edge.BOTH
    assert line.get() is False
    fake.queued.append(edge(True))  # an edge from before the call: stale, dropped
    fake.arrivals.extend([(0.004, [edge(False)]), (0.010, [edge(True)])])
    assert line.wait_edge(True, 0.1)
    assert fake.clock.now() == pytest.approx(0.010)
    assert not line.wait_edge(True, 0.02)
    assert fake.clock.now() == pytest.approx(0.030)


def test_waiting_for_an_edge_the_line_does_not_report_is_refused(fake):
    line = open_input_line("/dev/gpiochip0", 24)
    assert fake.requests[0][0]["config"][24].edge_detection == gpiod.line.Edge.RISING
    with pytest.raises(InvalidArgument, match="falling"):
        line.wait_edge(False, 0.1)
    with pytest.raises(ConfigError, match="rising, falling, both"):
        open_input_line("/dev/gpiochip0", 24, edge="up")


@pytest.mark.parametrize(
    ("error", "words"),
    [
        (FileNotFoundError(errno.ENOENT, "No such file or directory"), ["/dev/gpiochip3 does not exist", "gpiodetect"]),
        (PermissionError(errno.EACCES, "Permission denied"), ["permission denied on /dev/gpiochip3", "gpio", "udev"]),
        (OSError(errno.EBUSY, "Device or resource busy"), ["line 5 of /dev/gpiochip3 is in use", "gpioinfo"]),
        (OSError(errno.EINVAL, "Invalid argument"), ["refused", "no such line"]),
        (OSError(errno.EIO, "I/O error"), ["cannot request", "I/O error"]),
    ],
)
def test_request_failures_say_what_to_do(fake, error, words):
    fake.error = error
    with pytest.raises(LinkError) as caught:
        open_output_line("/dev/gpiochip3", 5, initial=False)
    assert all(word in str(caught.value) for word in words), str(caught.value)


def test_a_line_fault_is_a_link_error(fake):
    line = open_output_line("/dev/gpiochip0", 25, initial=False)
    fake.requests[0][1].fail = OSError(errno.EIO, "I/O error")
    with pytest.raises(LinkError, match="setting the line high failed"):
        line.set(True)


def test_missing_package_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "gpiod", None)
    with pytest.raises(ConfigError, match="pip install"):
        open_output_line("/dev/gpiochip0", 25, initial=False)


def test_bad_offsets_are_refused_before_gpiod_is_asked(fake):
    for offset in (-1, "25", True):
        with pytest.raises(InvalidArgument, match="offset"):
            open_output_line("/dev/gpiochip0", offset, initial=False)
    assert fake.requests == []


def test_the_real_gpiod_on_a_missing_chip_and_on_a_non_gpio_device():
    with pytest.raises(LinkError, match="/dev/gpiochip99 does not exist"):
        open_output_line("/dev/gpiochip99", 1, initial=False)
    with pytest.raises(LinkError, match="not a GPIO character device"):
        open_input_line("/dev/null", 1)


def test_a_reset_pulse_is_low_then_high_with_the_waits_on_the_clock():
    clock = SimulatedClock()
    seen = []

    class Line:
        def set(self, level):
            seen.append((level, clock.now()))

        def close(self):
            pass

    pulse_reset(Line(), clock, pulse=10e-6, recovery=0.120)
    assert seen == [(False, 0.0), (True, pytest.approx(10e-6))]
    assert clock.now() == pytest.approx(0.120 + 10e-6)

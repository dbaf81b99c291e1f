"""HidSim: polling interval, timed reports, the unread bound, output/feature reports, faults, errors."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError, Disconnected, InvalidArgumentType, ProtocolError
from pixelpen.sim.base import Fault, ReportDevice
from pixelpen.sim.hid import descriptors, device
from pixelpen.sim.hid.device import Firmware, HidSim, check_report, numbered


class Counting(Firmware):
    """A firmware that has ``burst`` reports to send at every poll until ``until`` s: the poll time in ms, and k."""

    model = "counting"

    def __init__(self, burst: int = 1, until: float = 1.0) -> None:
        super().__init__(descriptors.BOOT_MOUSE)
        self.burst, self.until = burst, until
        self.polls: list[float] = []
        self.powered_up: list[float] = []

    def poll(self, t: float) -> list[bytes]:
        self.polls.append(t)
        return [bytes([round(t * 1000) % 256, k, 0]) for k in range(self.burst)]

    def busy(self, t: float) -> bool:
        return t <= self.until

    def power_up(self, t: float) -> None:
        super().power_up(t)
        self.powered_up.append(t)


def test_numbered_finds_a_report_id_item_and_skips_long_item_data() -> None:
    assert not numbered(descriptors.BOOT_MOUSE) and not numbered(descriptors.BOOT_KEYBOARD)
    assert numbered(descriptors.TRACKBALL) and numbered(descriptors.NKRO_KEYBOARD)
    assert not numbered(bytes([0xFE, 0x02, 0xF0, 0x85, 0x01, 0xC0]))  # 0x85 inside a long item's data
    assert not numbered(bytes([0x26, 0x85]))  # inside a 2-byte Logical Maximum's data (truncated item)
    assert numbered(bytes([0x05, 0x01, 0x85, 0x07]))


def test_a_polled_device_sends_at_most_one_report_per_interval() -> None:
    clock = SimulatedClock()
    sim = HidSim(Counting(), hz=100.0, clock=clock)
    clock.advance(0.5)
    timed = sim.take_timed_reports()
    assert [t for t, _ in timed] == pytest.approx([k / 100 for k in range(1, 51)])
    assert sim.sent == 50 and sim.take_reports() == []


def test_several_reports_for_one_sample_go_out_one_per_interval() -> None:
    clock = SimulatedClock()
    firmware = Counting(burst=3)
    sim = HidSim(firmware, hz=1000.0, clock=clock)
    clock.advance(0.006)
    reports = sim.take_reports()
    assert [r[1] for r in reports] == [0, 1, 2, 0, 1, 2]  # hybrid mode: a sample's reports on consecutive ticks
    assert firmware.polls == pytest.approx([0.001, 0.004])  # the hand is sampled when the queue is empty


def test_an_idle_firmware_schedules_nothing() -> None:
    clock = SimulatedClock()
    sim = HidSim(Counting(until=0.05), hz=100.0, clock=clock)
    clock.advance(10.0)
    assert len(sim.take_reports()) == 5
    assert sim.next_event_time() is None


@pytest.mark.parametrize("hz", [0.5, 8001, float("nan"), "100"])
def test_polling_rates_outside_the_usb_range_are_refused_naming_hz(hz: object) -> None:
    with pytest.raises(ConfigError, match="hz="):
        HidSim(Counting(), hz=hz)  # type: ignore[arg-type]


def test_the_unread_reports_are_bounded_and_the_dropped_counted(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(device, "MAX_UNREAD_REPORTS", 8)
    clock = SimulatedClock()
    sim = HidSim(Counting(until=10.0), hz=1000.0, clock=clock)
    clock.advance(0.02)
    reports = sim.take_reports()
    assert len(reports) == 8 and sim.dropped == 12
    assert [r[0] for r in reports] == list(range(13, 21))  # the newest kept


def test_from_descriptor_plays_timed_reports_lazily_on_the_clock() -> None:
    pulled: list[int] = []

    def recording() -> Iterator[tuple[float, bytes]]:
        for k in range(3):
            pulled.append(k)
            yield 0.5 * k, bytes([k, 0, 0])

    clock = SimulatedClock(100.0)
    sim = HidSim.from_descriptor(descriptors.BOOT_MOUSE, recording(), clock=clock, model="replay")
    assert isinstance(sim, ReportDevice) and sim.model == "replay"
    assert pulled == [0]  # one report looked ahead
    clock.advance(0.6)
    assert sim.take_timed_reports() == [(100.0, bytes([0, 0, 0])), (100.5, bytes([1, 0, 0]))]
    clock.advance(10.0)
    assert sim.take_reports() == [bytes([2, 0, 0])] and sim.next_event_time() is None


def test_from_descriptor_refuses_time_going_backwards_and_non_bytes() -> None:
    clock = SimulatedClock()
    sim = HidSim.from_descriptor(descriptors.BOOT_MOUSE, [(1.0, b"\0\0\0"), (0.5, b"\0\0\0")], clock=clock)
    clock.advance(2.0)
    with pytest.raises(ConfigError, match=r"report 1 at 0\.5 s comes before report 0"):
        sim.take_reports()
    with pytest.raises(InvalidArgumentType, match="report 0"):
        HidSim.from_descriptor(descriptors.BOOT_MOUSE, [(0.0, "abc")])  # type: ignore[list-item]
    with pytest.raises(InvalidArgumentType, match="descriptor"):
        HidSim.from_descriptor("05 01")  # type: ignore[arg-type]


def test_the_generic_firmware_keeps_outputs_and_echoes_features() -> None:
    sim = HidSim.from_descriptor(descriptors.NKRO_KEYBOARD, clock=SimulatedClock())
    sim.write_report(b"\x01\x02")
    assert sim.firmware.outputs == {1: b"\x01\x02"}
    with pytest.raises(ProtocolError, match=r"no feature report with ID 4.*STALL"):
        sim.get_feature(4)
    sim.send_feature(b"\x04\x09")
    assert sim.get_feature(4) == b"\x04\x09"
    with pytest.raises(ProtocolError, match="empty output report"):
        sim.write_report(b"")
    with pytest.raises(InvalidArgumentType):
        sim.send_feature([4, 9])  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentType):
        sim.write_report("\x01\x02")  # type: ignore[arg-type]


def test_power_loss_stops_reports_and_host_calls_fail_until_power_returns() -> None:
    clock = SimulatedClock()
    firmware = Counting(until=10.0)
    sim = HidSim(firmware, hz=100.0, clock=clock)
    sim.write_report(b"\x01\x00\x00")
    clock.advance(0.1)
    sim.inject("power-loss")
    assert not sim.connected and "off" in repr(sim)
    assert len(sim.take_reports()) == 10  # what was sent before stays readable
    clock.advance(1.0)
    assert sim.take_reports() == [] and sim.next_event_time() is None
    for call in (lambda: sim.write_report(b"\0"), lambda: sim.get_feature(1), lambda: sim.send_feature(b"\0")):
        with pytest.raises(Disconnected, match="without power"):
            call()
    sim.inject(Fault.POWER_RESTORE)
    assert sim.connected and firmware.outputs == {} and firmware.powered_up == [pytest.approx(1.1)]
    clock.advance(0.05)
    assert [t for t, _ in sim.take_timed_reports()] == pytest.approx([1.11, 1.12, 1.13, 1.14, 1.15])


def test_power_restore_while_powered_does_nothing_and_reset_restarts() -> None:
    clock = SimulatedClock()
    firmware = Counting(until=10.0)
    sim = HidSim(firmware, hz=100.0, clock=clock)
    clock.advance(0.015)
    sim.inject("power-restore")
    assert firmware.powered_up == []
    sim.inject("reset")
    assert firmware.powered_up == [pytest.approx(0.015)]
    clock.advance(0.01)
    assert [t for t, _ in sim.take_timed_reports()] == pytest.approx([0.01, 0.025])


def test_a_recording_loses_the_reports_due_while_the_power_was_off() -> None:
    clock = SimulatedClock()
    sim = HidSim.from_descriptor(descriptors.BOOT_MOUSE, [(0.1 * k, bytes([k, 0, 0])) for k in range(10)],
                                 clock=clock)
    clock.advance(0.25)
    sim.inject("power-loss")
    clock.advance(0.4)
    sim.inject("power-restore")
    clock.advance(1.0)
    assert [r[0] for r in sim.take_reports()] == [0, 1, 2, 7, 8, 9]


def test_a_fault_due_at_a_byte_count_falls_after_the_whole_report_reaching_it() -> None:
    sim = HidSim.from_descriptor(descriptors.NKRO_KEYBOARD, clock=SimulatedClock())
    sim.inject("power-loss", at=3)
    sim.write_report(b"\x01\x02")
    assert sim.connected
    sim.write_report(b"\x01\x04")  # bytes 3-4: the report is taken whole, then the power goes
    assert sim.firmware.outputs == {1: b"\x01\x04"} and not sim.connected


def test_unknown_faults_are_refused_naming_the_known_ones() -> None:
    sim = HidSim(Counting(), clock=SimulatedClock())
    with pytest.raises(ConfigError, match="power-loss, power-restore, reset"):
        sim.inject("paper-lever")


def test_close_unplugs_for_good() -> None:
    clock = SimulatedClock()
    sim = HidSim(Counting(until=10.0), hz=100.0, clock=clock)
    sim.close()
    sim.close()
    clock.advance(1.0)
    assert sim.take_reports() == [] and not sim.connected and "unplugged" in repr(sim)
    with pytest.raises(Disconnected, match="unplugged"):
        sim.get_feature(0)
    sim.receive(b"\x00")  # bytes after close are dropped
    sim.inject("power-restore")
    assert not sim.connected


def test_check_report_names_the_expected_length_and_id() -> None:
    check_report(b"\x02\x01", 2, 2, "m", "feature")
    with pytest.raises(ProtocolError, match=r"feature report '02' is not 2 bytes starting with report ID 2"):
        check_report(b"\x02", 2, 2, "m", "feature")
    with pytest.raises(ProtocolError, match=r"is not 1 bytes; "):
        check_report(b"\x01\x02", 1, None, "m", "output")

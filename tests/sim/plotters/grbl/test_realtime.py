"""The real-time byte table: GRBL 1.1's CMD_* bytes, which act in a critical alarm, and the overrides."""

from __future__ import annotations

from pixelpen.clock import SimulatedClock
from pixelpen.sim.plotters.grbl.controller import GrblSimulator
from pixelpen.sim.plotters.grbl.realtime import ASCII_REALTIME, REALTIME, RT_STATUS
from tests.sim.fakes import DeviceRig

CMD_BYTES = {0x18, ord("?"), ord("~"), ord("!"), 0x84, 0x85, *range(0x90, 0x98), *range(0x99, 0x9F), 0xA0}
"""config.h of GRBL 1.1h: the real-time commands of a default build (no mist toggle: M7 is off)."""


class Rig(DeviceRig):
    def __init__(self) -> None:
        clock = SimulatedClock()
        super().__init__(GrblSimulator(clock), clock)
        self.dev.take_output()


def test_the_table_holds_grbls_real_time_bytes():
    assert set(REALTIME) == CMD_BYTES
    assert set(ASCII_REALTIME) == {0x18, ord("?"), ord("~"), ord("!")}
    assert {b for b, c in REALTIME.items() if c.always} == {0x18, RT_STATUS}
    for command in REALTIME.values():
        assert getattr(GrblSimulator, command.handler.__name__) is command.handler


def test_overrides_step_and_clamp():
    rig = Rig()
    rig.send(bytes([0x91] * 15 + [0x93] * 3))
    assert rig.dev.feed_ovr == 200.0
    rig.send(bytes([0x92] * 30))
    assert rig.dev.feed_ovr == 10.0
    rig.send(bytes([0x90, 0x97, 0x9B, 0x9D]))
    assert (rig.dev.feed_ovr, rig.dev.rapid_ovr, rig.dev.spindle_ovr) == (100.0, 25.0, 89.0)
    rig.send(bytes([0x99, 0x95]))
    assert (rig.dev.rapid_ovr, rig.dev.spindle_ovr) == (100.0, 100.0)


def test_only_reset_and_status_act_in_a_critical_alarm():
    rig = Rig()
    rig.send("$22=1\n$20=1\n$X\nG0 X-5\n")  # outside travel: ALARM:2, reset required
    assert b"ALARM:2" in rig.dev.take_output() or rig.dev.state == "Alarm"
    rig.send(bytes([0x91]))
    assert rig.dev.feed_ovr == 100.0
    assert rig.send(b"?") == b""  # no status in a critical alarm
    assert b"Grbl 1.1h" in rig.send(b"\x18")
    assert rig.send(b"?").startswith(b"<Alarm|")


def test_unknown_extended_bytes_are_logged_and_dropped():
    rig = Rig()
    assert rig.send(bytes([0x98, 0xA1, 0xFF])) == b""
    assert [label for _, label in rig.dev.log[-3:]] == ["0x98", "0xA1", "0xFF"]

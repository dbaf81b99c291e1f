"""The EBB's PIC port pins: PORTA..E latches and directions, the motor enables and the microstep selects.

From ``HardwareProfile_EBB_V13_and_above.h`` and ebb.c: UserInit makes every pin an input with its latch
low; EBB_Init then drives MS1..MS3 and both motor enables high (1/16 stepping, drivers disabled), and
step/dir (RD4..7), pen (RB4), servo power (RA3) and engraver (RB3) low; RCServo2_Init makes the servo
pulse pin RB1 a low output.  EM writes the microstep selects and enables, PO/PD/O/C write latches and
directions, PI/I and QE read them.
"""

from __future__ import annotations

__all__ = ["ENABLE_PINS", "MS_LEVELS", "MS_MICROSTEPS", "MS_PINS", "PORT_NAMES", "SERVO_POWER_PIN", "Ports"]

PORT_NAMES = "ABCDE"
"""The ports I, O and C read and write, in their order."""
ENABLE_PINS = (("E", 0), ("C", 1))
"""Motor 1 and 2 driver enables, active low (HardwareProfile_EBB_V13_and_above.h: Enable1IO RE0, Enable2IO RC1)."""
MS_PINS = (("E", 2), ("E", 1), ("A", 6))
"""Microstep selects MS1, MS2, MS3 (RE2, RE1, RA6), shared by both drivers."""
MS_LEVELS = {1: (1, 1, 1), 2: (1, 1, 0), 3: (0, 1, 0), 4: (1, 0, 0), 5: (0, 0, 0)}
"""EM mode -> MS1..MS3 levels (ebb.c, COMMAND_EM): 1 = 1/16 ... 5 = full step."""
MS_MICROSTEPS = {(0, 0, 0): 1, (1, 0, 0): 2, (0, 1, 0): 4, (1, 1, 0): 8}
"""MS1..MS3 levels -> microsteps as QE decodes them (parse_QE_packet); anything else reads 16."""
SERVO_POWER_PIN = ("A", 3)
"""RCServoPowerIO (LATA3): high while the pen servo is powered."""
_TRIS_AT_BOOT = {"A": 0xF7, "B": 0xE5, "C": 0xFF, "D": 0x03, "E": 0xFF}


class Ports:
    """PORTA..E latches and directions (1 = input); inputs on port B read high (weak pull-ups)."""

    def __init__(self) -> None:
        self.lat = dict.fromkeys(PORT_NAMES, 0)
        self.tris = dict(_TRIS_AT_BOOT)
        for port, pin in MS_PINS + ENABLE_PINS:
            self.drive(port, pin, 1)

    def read(self, port: str) -> int:
        """Digital value of every pin of ``port``."""
        pulled = 0xFF if port == "B" else 0x00
        return (self.lat[port] & ~self.tris[port] | pulled & self.tris[port]) & 0xFF

    def pin(self, port: str, pin: int) -> int:
        """Digital value of one pin."""
        return (self.read(port) >> pin) & 1

    def set_latch(self, port: str, pin: int, value: int) -> None:
        """Write one output latch (the pin follows only while it is an output)."""
        bit = 1 << pin
        self.lat[port] = (self.lat[port] | bit) if value else (self.lat[port] & ~bit)

    def set_direction(self, port: str, pin: int, is_input: int) -> None:
        """Make ``pin`` an input (1) or an output (0), as PD does."""
        bit = 1 << pin
        self.tris[port] = (self.tris[port] | bit) if is_input else (self.tris[port] & ~bit)

    def drive(self, port: str, pin: int, value: int) -> None:
        """Make ``pin`` an output at ``value``."""
        self.set_latch(port, pin, value)
        self.tris[port] &= ~(1 << pin)

    def microsteps(self) -> int:
        """Stepping the MS1..MS3 pins select (QE's decoding)."""
        levels = (self.pin(*MS_PINS[0]), self.pin(*MS_PINS[1]), self.pin(*MS_PINS[2]))
        return MS_MICROSTEPS.get(levels, 16)

    def select_microsteps(self, mode: int) -> None:
        """Latch the MS1..MS3 levels of EM mode ``mode`` (1 = 1/16 ... 5 = full step)."""
        for (port, pin), level in zip(MS_PINS, MS_LEVELS[mode], strict=True):
            self.set_latch(port, pin, level)

    def set_enables(self, *states: bool | None) -> None:
        """Latch the motor enable pins (active low); None leaves a motor as it is."""
        for (port, pin), on in zip(ENABLE_PINS, states, strict=False):
            if on is not None:
                self.set_latch(port, pin, 0 if on else 1)

    def enables(self) -> list[bool]:
        """Motor 1 and 2 enables as the pins read (True: the driver is on)."""
        return [self.pin(port, pin) == 0 for port, pin in ENABLE_PINS]

"""The pen-lift servo and where the pen meets the paper: SC,4/SC,5 positions, slew rates, servo power.

The pen is mechanical: the servo pulse slews at the SC,11/12 or S2 rate and the pen touches the paper
while the pulse is below the contact position (on an AxiDraw a larger pulse raises the pen), whatever
SC,4/SC,5 say.  Power-on state (EggBot ``EBB_firmware/app.X/source/RCServo2.c``, RCServo2_Init, lines
214-222 at 3.0.3): SC,4 / SC,5 = 22565 / 15302 (firmware >= 2.6.0; 12000 / 16000 before), SC,11 / SC,12
rates 400 / 400, and a queued pen-up that parks the pulse at the boot SC,4 while servo power (RA3,
RCServoPowerIO) stays off.  So the pen rests up until a command powers the servo, and that first move
slews from the boot SC,4 (whatever SC,4 has been set to since) at the commanded rate.
"""

from __future__ import annotations

from pixelpen.sim.plotters.ebb.motion import ServoTrack

__all__ = [
    "CONTACT_DEFAULT", "SERVO_BOOT", "SERVO_BOOT_OLD", "SERVO_RANGE", "SERVO_RATE_BOOT", "SERVO_TIMEOUT_MS", "PenServo",
]

SERVO_BOOT = (22565, 15302)
"""SC,4 (up) / SC,5 (down) at boot since firmware 2.6.0 (RCServo2_Init; ebb.html still says 12000 / 16000)."""
SERVO_BOOT_OLD = (12000, 16000)
"""SC,4 / SC,5 at boot before firmware 2.6.0."""
SERVO_RANGE = (9855, 27831)
"""pyaxidraw's servo range (0.82 .. 2.32 ms): pen height 0 % .. 100 %, a larger pulse raising the pen."""
CONTACT_DEFAULT = round(SERVO_RANGE[0] + 0.45 * (SERVO_RANGE[1] - SERVO_RANGE[0]))
"""Pulse width at which the pen meets the paper (17944): 45 % of SERVO_RANGE, midway between pyaxidraw's
30 % (down, 15248) and 60 % (up, 20641) defaults, and between saxi's 15700 (down) and 28000 (up)."""
SERVO_RATE_BOOT = 400
"""SC,11 / SC,12 at boot: pulse units per 24 ms frame (RCServo2_Init: g_servo2_rate_up = g_servo2_rate_down = 400)."""
SERVO_TIMEOUT_MS = 60000
"""SR's default servo power timeout (UBW.c: RCSERVO_POWEROFF_DEFAULT_MS = 60 s)."""


class PenServo:
    """The RC servo on RB1 (RP4) that lifts the pen; ``contact`` is the pulse at which the pen meets the paper."""

    def __init__(self, positions: tuple[int, int], contact: int) -> None:
        self.up_position, self.down_position = positions
        """SC,4 (pen up) and SC,5 (pen down) pulse widths, units of 83.3 ns."""
        self.boot_pulse = positions[0]
        """The pulse RCServo2_Init parks the channel at (the boot SC,4): where the first move starts."""
        self.rate_up = self.rate_down = SERVO_RATE_BOOT
        """SC,11 / SC,12 slew rates (0: move at once)."""
        self.track: ServoTrack | None = None
        """The pulse over time; None while servo power has been off since boot (the pen rests up)."""
        self.commanded_up = True
        """The pen state QP reports (what was commanded, not where the pen is)."""
        self.power_until: float | None = None
        self.timeout_ms = SERVO_TIMEOUT_MS
        self.always_on = False
        self.contact = contact

    def touches(self, t: float) -> bool:
        """Whether the pen touches the paper at ``t``: the servo's pulse is below the contact position."""
        return self.track is not None and self.track.position(t) < self.contact

    def contact_change(self, t0: float, t1: float) -> float | None:
        """When the pen meets or leaves the paper strictly between ``t0`` and ``t1`` (None: it does not)."""
        if self.track is None:
            return None
        tc = self.track.crossing(self.contact)
        return tc if tc is not None and t0 < tc < t1 else None

    def slew(self, t: float, target: float, rate: float) -> None:
        """Power the servo and slew it to ``target`` (its first move starts from the boot pulse)."""
        if self.track is None:
            self.track = ServoTrack(self.boot_pulse, t)
        self.track.move(t, target, rate)
        self.power_until = None if self.timeout_ms == 0 else t + self.timeout_ms / 1000.0
        self.always_on = self.timeout_ms == 0

    def command(self, up: bool | None) -> tuple[int, int]:
        """SP/TP: set the commanded state (None toggles it); the (target pulse, rate) to slew to."""
        self.commanded_up = (not self.commanded_up) if up is None else up
        if self.commanded_up:
            return self.up_position, self.rate_up
        return self.down_position, self.rate_down

    def configure(self, param: int, value: int) -> None:
        """SC,4 / SC,5 positions and SC,10 / SC,11 / SC,12 rates (other SC parameters change nothing here)."""
        if param == 4:
            self.up_position = value
        elif param == 5:
            self.down_position = value
        elif param == 10:
            self.rate_up = self.rate_down = value
        elif param == 11:
            self.rate_up = value
        elif param == 12:
            self.rate_down = value

    def set_power(self, now: float, timeout_ms: int, state: int | None) -> None:
        """SR: the power timeout, and servo power switched on (1) or off (0) now if ``state`` is given."""
        self.timeout_ms = timeout_ms
        if state is not None:
            if state:
                self.power_until = None if timeout_ms == 0 else now + timeout_ms / 1000.0
                self.always_on = timeout_ms == 0
            else:
                self.power_until = now
                self.always_on = False

    def powered(self, now: float) -> bool:
        """QR: whether the servo is powered at ``now``."""
        return self.always_on or (self.power_until is not None and now < self.power_until)

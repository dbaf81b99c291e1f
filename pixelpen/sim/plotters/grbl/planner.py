"""GRBL-style look-ahead planner and its clock: trapezoid blocks, junction-deviation cornering, feed hold.

Written from the GRBL 1.1 settings documentation ($11 junction deviation, $110-$112 maximum rates,
$120-$122 accelerations) and the classic planner it describes: every block accelerates at the
acceleration its direction allows (each axis' limit divided by that axis' share of the unit vector),
cruises at its nominal speed, and the entry speed of each junction is the smallest of the neighbours'
nominal speeds and the junction-deviation limit v² = a·δ·sin(θ/2)/(1 − sin(θ/2)).  A reverse pass
lets every block stop by the end of the queue and a forward pass keeps accelerations possible; the
executing block keeps the speed it really has.  Times are continuous (no step quantisation).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np

__all__ = ["AxisLimits", "Block", "Planner", "Profile"]

MINIMUM_FEED_RATE = 1.0  # mm/min, GRBL's floor on a block's nominal speed
_COS_STRAIGHT = 0.999999  # cos of the angle between unit vectors: a reversal / straight-through junction
_EPS = 1e-12


@dataclass(frozen=True)
class AxisLimits:
    """Per-axis machine limits: maximum rates (mm/min), accelerations (mm/s²) and junction deviation (mm)."""

    max_rate: tuple[float, float, float]
    accel: tuple[float, float, float]
    junction_deviation: float


def limit_by_axis(values: tuple[float, float, float], unit: np.ndarray) -> float:
    """GRBL's limit_value_by_axis_maximum: the largest scalar whose per-axis share stays within ``values``."""
    limit = math.inf
    for v, u in zip(values, unit, strict=True):
        if abs(u) > _EPS:
            limit = min(limit, abs(v / u))
    return limit


@dataclass
class Profile:
    """Speed over one stretch of a block: ramp v0 -> vp, cruise, ramp vp -> v1, all at ``accel``.

    ``distance`` is the length the profile covers (less than the block's remainder for a hold that
    stops inside the block).  Speeds mm/s, times s.
    """

    v0: float
    vp: float
    v1: float
    accel: float
    t1: float
    t2: float
    t3: float
    distance: float

    @property
    def duration(self) -> float:
        """Total seconds of the three phases."""
        return self.t1 + self.t2 + self.t3

    def at(self, t: float) -> tuple[float, float]:
        """(distance covered, speed) ``t`` seconds into the profile (clamped to its ends)."""
        t = min(max(t, 0.0), self.duration)
        a = self.accel
        up = 1.0 if self.vp >= self.v0 else -1.0
        if t <= self.t1:
            return self.v0 * t + 0.5 * up * a * t * t, self.v0 + up * a * t
        d1 = 0.5 * (self.v0 + self.vp) * self.t1
        t -= self.t1
        if t <= self.t2:
            return d1 + self.vp * t, self.vp
        t -= self.t2
        d2 = self.vp * self.t2
        return min(d1 + d2 + self.vp * t - 0.5 * a * t * t, self.distance), self.vp - a * t

    @classmethod
    def trapezoid(cls, v0: float, vn: float, v1: float, accel: float, length: float) -> Profile:
        """The fastest profile over ``length`` entering at v0, cruising at most vn and leaving at v1.

        When the block is too short to slow from v0 to v1 it decelerates all the way and leaves faster
        than v1 (the entry speed is fixed: the carriage cannot lose speed faster than ``accel``).
        """
        a = max(accel, _EPS)
        length = max(length, 0.0)
        v0, vn = max(v0, 0.0), max(vn, _EPS)
        v1 = min(max(v1, 0.0), vn)  # a block never leaves above its cruise speed
        if v0 * v0 - 2 * a * length > v1 * v1:  # cannot slow down enough: decelerate throughout
            v_end = math.sqrt(max(v0 * v0 - 2 * a * length, 0.0))
            return cls(v0, v0, v_end, a, 0.0, 0.0, (v0 - v_end) / a, length)
        v1 = min(v1, math.sqrt(v0 * v0 + 2 * a * length))
        # entering above the cruise speed (an override lowered it): slow down to it first
        vp = min(vn, math.sqrt(max((2 * a * length + v0 * v0 + v1 * v1) / 2.0, 0.0))) if v0 <= vn else vn
        vp = max(vp, v1)
        d1 = abs(vp * vp - v0 * v0) / (2 * a)
        d3 = (vp * vp - v1 * v1) / (2 * a)
        d2 = max(length - d1 - d3, 0.0)
        t2 = d2 / vp if vp > _EPS else 0.0
        return cls(v0, vp, v1, a, abs(vp - v0) / a, t2, (vp - v1) / a, length)

    @classmethod
    def stop(cls, v0: float, accel: float, length: float) -> Profile:
        """Decelerate from v0 as hard as allowed: stops after v0²/2a, or leaves ``length`` still moving."""
        a = max(accel, _EPS)
        d = v0 * v0 / (2 * a)
        if d <= length:
            return cls(v0, v0, 0.0, a, 0.0, 0.0, v0 / a, d)
        v_end = math.sqrt(max(v0 * v0 - 2 * a * length, 0.0))
        return cls(v0, v0, v_end, a, 0.0, 0.0, (v0 - v_end) / a, length)


@dataclass
class Block:
    """One straight move in the planner (machine mm) with what the machine must do during it."""

    start: np.ndarray
    target: np.ndarray
    rapid: bool = False
    jog: bool = False
    feed: float = 0.0  # mm/min (ignored for rapids)
    data: object = None  # the simulator's per-block payload (spindle state, tags)
    length: float = field(init=False)
    unit: np.ndarray = field(init=False)
    accel: float = field(init=False, default=0.0)
    rapid_rate: float = field(init=False, default=0.0)  # mm/min
    nominal: float = field(init=False, default=0.0)  # mm/s
    max_junction: float = field(init=False, default=0.0)  # mm/s
    max_entry: float = field(init=False, default=0.0)  # mm/s
    entry: float = field(init=False, default=0.0)  # planned entry speed, mm/s

    def __post_init__(self) -> None:
        delta = self.target - self.start
        self.length = float(np.linalg.norm(delta))
        self.unit = delta / self.length if self.length > 0 else np.zeros(3)

    def point(self, s: float) -> np.ndarray:
        """Machine position ``s`` mm into the block."""
        return self.start + self.unit * min(max(s, 0.0), self.length)


class Planner:
    """The queue of planned blocks and the one executing, timed on a continuous clock.

    ``capacity`` usable blocks (GRBL's BLOCK_BUFFER_SIZE − 1).  The executing block is ``blocks[0]``
    while ``running``; ``anchor`` = (time, distance into the block, speed) where its current profile
    starts.  ``limits()`` and ``overrides()`` are read whenever speeds are (re)computed.
    """

    def __init__(
        self,
        capacity: int,
        limits: Callable[[], AxisLimits],
        overrides: Callable[[], tuple[float, float]] = lambda: (100.0, 100.0),
    ) -> None:
        self.capacity = int(capacity)
        self.limits = limits
        self.overrides = overrides
        self.blocks: deque[Block] = deque()
        self.running = False
        self.holding = False  # a hold (feed hold, door, jog cancel) is decelerating or complete
        self.anchor_t = 0.0
        self.anchor_s = 0.0
        self.anchor_v = 0.0
        self.profile: Profile | None = None
        self._prev_unit: np.ndarray | None = None
        self._prev_nominal = 0.0

    # ---- queue -----------------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.blocks)

    def __iter__(self) -> Iterator[Block]:
        return iter(self.blocks)

    @property
    def available(self) -> int:
        """Free planner blocks (what ``Bf:`` reports first)."""
        return self.capacity - len(self.blocks)

    @property
    def full(self) -> bool:
        """True when no block can be added."""
        return len(self.blocks) >= self.capacity

    def add(self, block: Block, now: float) -> bool:
        """Queue a block (False, nothing queued, if it has zero length); replans the look-ahead."""
        if block.length <= 0.0:
            return False
        lim = self.limits()
        block.accel = limit_by_axis(lim.accel, block.unit)
        block.rapid_rate = limit_by_axis(lim.max_rate, block.unit)
        self._set_nominal(block)
        if not self.blocks:
            block.max_junction = 0.0
            block.entry = 0.0
        else:
            assert self._prev_unit is not None
            block.max_junction = self._junction_speed(self._prev_unit, block.unit, lim)
        block.max_entry = min(block.max_junction, block.nominal, self._prev_nominal if self.blocks else 0.0)
        self._prev_unit = block.unit
        self._prev_nominal = block.nominal
        self.blocks.append(block)
        self.replan(now)
        return True

    def _set_nominal(self, block: Block) -> None:
        feed_ovr, rapid_ovr = self.overrides()
        if block.rapid:
            rate = block.rapid_rate * rapid_ovr / 100.0
        else:
            rate = block.feed * (1.0 if block.jog else feed_ovr / 100.0)
            rate = min(rate, block.rapid_rate)
        block.nominal = max(rate, MINIMUM_FEED_RATE) / 60.0

    @staticmethod
    def _junction_speed(prev_unit: np.ndarray, unit: np.ndarray, lim: AxisLimits) -> float:
        cos_theta = -float(np.dot(prev_unit, unit))
        if cos_theta > _COS_STRAIGHT:  # full reversal
            return 0.0
        if cos_theta < -_COS_STRAIGHT:  # straight on
            return math.inf
        junction = unit - prev_unit
        norm = float(np.linalg.norm(junction))
        accel = limit_by_axis(lim.accel, junction / norm) if norm > _EPS else min(lim.accel)
        sin_half = math.sqrt(0.5 * (1.0 - cos_theta))
        return math.sqrt(max(accel * lim.junction_deviation * sin_half / (1.0 - sin_half), 0.0))

    def refresh_speeds(self, now: float) -> None:
        """Recompute nominal speeds after an override change, then replan."""
        prev_nominal = None
        for b in self.blocks:
            self._set_nominal(b)
            if prev_nominal is not None:
                b.max_entry = min(b.max_junction, b.nominal, prev_nominal)
            prev_nominal = b.nominal
        if self.blocks:
            self._prev_nominal = self.blocks[-1].nominal
        self.replan(now)

    # ---- planning ------------------------------------------------------------------------------
    def replan(self, now: float) -> None:
        """Reverse and forward passes over the queue; re-anchor the executing block at ``now``.

        The first block's entry is fixed: it is executing (its real speed), held, or starts from rest.
        """
        blocks = self.blocks
        if not blocks:
            return
        moving = self.running and not self.holding
        if moving:
            self._reanchor(now)
        exit_sq = 0.0
        for i in range(len(blocks) - 1, 0, -1):
            b = blocks[i]
            b.entry = math.sqrt(min(b.max_entry ** 2, exit_sq + 2 * b.accel * b.length))
            exit_sq = b.entry ** 2
        started = self.running or self.holding
        v_prev = self.anchor_v if moving else 0.0
        len_prev = blocks[0].length - (self.anchor_s if started else 0.0)
        blocks[0].entry = v_prev
        for i in range(1, len(blocks)):
            reach = math.sqrt(v_prev * v_prev + 2 * blocks[i - 1].accel * max(len_prev, 0.0))
            blocks[i].entry = min(blocks[i].entry, reach)
            v_prev, len_prev = blocks[i].entry, blocks[i].length
        if moving:
            self.profile = self._profile_for(0, self.anchor_v, blocks[0].length - self.anchor_s)

    def _exit_speed(self, i: int) -> float:
        return self.blocks[i + 1].entry if i + 1 < len(self.blocks) else 0.0

    def _profile_for(self, i: int, v0: float, length: float) -> Profile:
        b = self.blocks[i]
        return Profile.trapezoid(v0, b.nominal, self._exit_speed(i), b.accel, length)

    def _reanchor(self, now: float) -> None:
        if self.profile is None:
            return
        ds, v = self.profile.at(now - self.anchor_t)
        self.anchor_s += ds
        self.anchor_v = v
        self.anchor_t = now

    # ---- execution -----------------------------------------------------------------------------
    def start(self, now: float) -> bool:
        """Begin (or resume after a completed hold) executing the queue from rest at ``now``."""
        self.holding = False
        if not self.blocks:
            self.running = False
            return False
        self.running = True
        self.anchor_t = now
        self.anchor_v = 0.0
        self.profile = None
        self.replan(now)
        return True

    def hold(self, now: float) -> None:
        """Start decelerating to a stop (feed hold): the queue stays, resume with :meth:`start`."""
        if not self.running or self.holding:
            self.holding = True
            return
        self._reanchor(now)
        b = self.blocks[0]
        self.holding = True
        self.profile = Profile.stop(self.anchor_v, b.accel, b.length - self.anchor_s)

    def next_event(self) -> float | None:
        """Clock time the executing profile ends (block complete, or the hold has stopped)."""
        if self.profile is None or not (self.running or self.holding) or not self.blocks:
            return None
        if self.holding and self.anchor_v == 0.0 and self.profile.duration == 0.0:
            return None
        return self.anchor_t + self.profile.duration

    def stopped(self) -> bool:
        """True when nothing moves (idle queue, or a hold that has come to rest)."""
        return self.next_event() is None

    def step(self) -> tuple[str, Block | None]:
        """Complete the profile that ends at :meth:`next_event`: ('block', done block) or ('held', None)."""
        assert self.profile is not None and self.blocks
        t_end = self.anchor_t + self.profile.duration
        b = self.blocks[0]
        covered = self.anchor_s + self.profile.distance
        if self.holding and self.profile.v1 <= 0.0 and covered < b.length - 1e-9:
            self.anchor_s = covered
            self.anchor_v = 0.0
            self.anchor_t = t_end
            self.profile = Profile(0.0, 0.0, 0.0, b.accel, 0.0, 0.0, 0.0, 0.0)
            self.running = False
            return "held", None
        exit_v = self.profile.v1
        self.blocks.popleft()
        self.anchor_t = t_end
        self.anchor_s = 0.0
        self.anchor_v = exit_v
        if not self.blocks:
            self.profile = None
            self.running = False
            self.anchor_v = 0.0
            return "block", b
        nxt = self.blocks[0]
        if self.holding:
            self.profile = Profile.stop(exit_v, nxt.accel, nxt.length)
        else:
            self.profile = self._profile_for(0, exit_v, nxt.length)
        return "block", b

    def position(self, now: float) -> np.ndarray | None:
        """Machine position of the executing block at ``now`` (None when no block is under way)."""
        if not self.blocks or self.profile is None:
            return None
        ds, _ = self.profile.at(now - self.anchor_t)
        return self.blocks[0].point(self.anchor_s + ds)

    def progress(self, now: float) -> float:
        """Distance (mm) into the executing block at ``now``."""
        if not self.blocks or self.profile is None:
            return 0.0
        return self.anchor_s + self.profile.at(now - self.anchor_t)[0]

    def speed(self, now: float) -> float:
        """Current speed in mm/s."""
        if not self.blocks or self.profile is None or not (self.running or self.holding):
            return 0.0
        return max(self.profile.at(now - self.anchor_t)[1], 0.0)

    def clear(self) -> None:
        """Forget every block (reset, jog cancel)."""
        self.blocks.clear()
        self.running = False
        self.holding = False
        self.profile = None
        self.anchor_s = 0.0
        self.anchor_v = 0.0
        self._prev_unit = None
        self._prev_nominal = 0.0

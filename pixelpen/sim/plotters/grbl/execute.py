"""Executing a checked G-code block: gc_execute_line's STEP 4 on the machine, in GRBL's order of execution.

The parser (:mod:`~pixelpen.sim.plotters.grbl.gcode`) has checked the block and worked out the parser
state it leaves; here each numbered sub-step that acts on the machine is one generator method: [4]
spindle speed, [7] spindle, [8] coolant, [10] dwell, [14]/[15]/[19] offsets, [19] G28/G30, [20] motion
(lines, arcs as ``mc_arc`` chords, probes), [21] program flow.  A method yields what it waits for (planner
room, a buffer sync, the end of a hold, a dwell's end) and returns a status code.
"""

from __future__ import annotations

from collections.abc import Generator

import numpy as np

from pixelpen.sim.plotters.grbl.arcs import arc_points
from pixelpen.sim.plotters.grbl.gcode import parse_block
from pixelpen.sim.plotters.grbl.machine import RESUMED, ROOM, SYNC, GrblMachine, MovePayload, Wait
from pixelpen.sim.plotters.grbl.modal import (
    MOTION_CCW,
    MOTION_CW,
    MOTION_SEEK,
    PROBES,
    STATUS,
    GBlock,
    GcodeState,
    fmt_float,
)
from pixelpen.sim.plotters.grbl.planner import Block

__all__ = ["BlockExecution"]

Task = Generator[Wait, None, int]
"""A step of a line: yields what it waits for, returns a status code (0 ok, -1 answered already)."""


class BlockExecution(GrblMachine):
    """gc_execute_line for the simulator: parse, check, then execute STEP 4's sub-steps one method each."""

    def _gcode(self, line: str, jog: bool = False) -> Task:
        """gc_execute_line: STEPs 1-3 in the parser, then STEP 4's sub-steps in GRBL's order."""
        block = parse_block(line, self.gc, self.persistent, jog=jog)
        if isinstance(block, int):
            return block
        if jog:
            return (yield from self._jog(block))
        yield from self._execute_spindle_speed(block)
        old = self.gc
        self.gc = block.modal.copy()
        self.gc.position = old.position.copy()
        yield from self._execute_spindle(block)
        yield from self._execute_coolant(block)
        yield from self._execute_dwell(block)
        yield from self._execute_offsets(block, old)
        code = yield from self._execute_predefined_position(block, old)
        if not code:
            code = yield from self._execute_motion(block, old)
        if code:
            return code
        self.gc.position = block.modal.position.copy()
        yield from self._execute_program_flow(block)
        return 0

    def _execute_spindle_speed(self, block: GBlock) -> Generator[Wait, None, None]:
        """[4] A new S with the spindle on takes effect in sync with motion (a laser-mode cut carries its own)."""
        new = block.modal
        is_cut = new.motion in (1, MOTION_CW, MOTION_CCW)
        laser_motion = self._flag(32) and block.motion_command and is_cut and bool(block.axis_words)
        if block.speed_changed and self.gc.spindle != 5 and not laser_motion:
            yield from self._spindle_sync(self.gc.spindle, new.spindle_speed)

    def _execute_spindle(self, block: GBlock) -> Generator[Wait, None, None]:
        """[7] M3/M4/M5, synchronised with motion."""
        if block.spindle_changed:
            yield from self._spindle_sync(block.modal.spindle, block.modal.spindle_speed)

    def _execute_coolant(self, block: GBlock) -> Generator[Wait, None, None]:
        """[8] M8/M9, synchronised with motion."""
        if block.coolant_changed and not self._check:
            yield SYNC
            self._flood, self._mist = block.modal.flood, block.modal.mist

    def _execute_dwell(self, block: GBlock) -> Generator[Wait, None, None]:
        """[10] G4: wait for the planner to empty, then P seconds."""
        if block.non_modal == "G4" and not self._check:
            yield SYNC
            yield self._now + block.dwell

    def _execute_offsets(self, block: GBlock, old: GcodeState) -> Generator[Wait, None, None]:
        """[14] [15] [19] A changed work offset syncs the buffer; G10 stores a system; G28.1/G30.1 store here."""
        if block.wco_changed:
            yield SYNC  # FORCE_BUFFER_SYNC_DURING_WCO_CHANGE
            self._wco_counter = 0
        if block.g10_index >= 0 and block.g10_values is not None:
            self.persistent.coords[block.g10_index] = block.g10_values.copy()
        if block.non_modal in ("G28.1", "G30.1"):
            target = self.persistent.g28 if block.non_modal == "G28.1" else self.persistent.g30
            target[:] = old.position

    def _execute_predefined_position(self, block: GBlock, old: GcodeState) -> Task:
        """[19] G28/G30: rapid to the intermediate point (if axis words), then to the stored position."""
        if block.non_modal not in ("G28", "G30") or block.home is None:
            return 0
        rapid = self._payload(rapid=True)
        if block.axis_words:
            code = yield from self._line_motion(old.position, block.target, rapid=True, payload=rapid)
            if code:
                return code
        start = block.target if block.axis_words else old.position
        return (yield from self._line_motion(start, block.home, rapid=True, payload=rapid))

    def _execute_motion(self, block: GBlock, old: GcodeState) -> Task:
        """[20] The motion mode: a probe, an arc as chords, or a straight line."""
        if not block.motion_command:
            return 0
        new, start = block.modal, old.position
        if new.motion in PROBES:
            code = yield from self._probe(block, start)
            if not code:
                new.position = self._mpos.copy()
            return code
        if new.motion in (MOTION_CW, MOTION_CCW):
            return (yield from self._arc(block, start))
        rapid = new.motion == MOTION_SEEK
        feed = block.feed
        if new.inverse_time and not rapid:
            feed = block.feed * float(np.linalg.norm(block.target - start))
        return (yield from self._line_motion(start, block.target, rapid=rapid, feed=feed,
                                             payload=self._payload(rapid=rapid, laser_on=not rapid)))

    def _arc(self, block: GBlock, start: np.ndarray) -> Task:
        """mc_arc: the chords GRBL cuts the arc into, one planner block each."""
        new = block.modal
        assert block.arc_offset is not None
        pts = arc_points(start, block.target, block.arc_offset, block.arc_radius, new.plane,
                         block.clockwise, self.settings[12])
        feed = block.feed
        if new.inverse_time:
            feed = block.feed * self._arc_length(start, pts)
        payload = self._payload(rapid=False, laser_on=True)
        prev = start
        for p in pts:
            code = yield from self._line_motion(prev, p, rapid=False, feed=feed, payload=payload)
            if code:
                return code
            prev = p
        return 0

    def _execute_program_flow(self, block: GBlock) -> Generator[Wait, None, None]:
        """[21] M0 pauses until cycle start; M2/M30 end the program (default modes, spindle and coolant off)."""
        if block.program_flow == 1:
            yield SYNC
            if not self._check:
                self._hold = "m0"
                yield RESUMED
        elif block.program_flow in (2, 30):
            yield SYNC
            if not self._check:
                self.gc.coord_system = self.persistent.coords[0].copy()
                self._wco_counter = 0
                self._spindle_state = 5
                self._flood = self._mist = False
                self._pen_update()
            self._emit(b"[MSG:Pgm End]\r\n")

    @staticmethod
    def _arc_length(start: np.ndarray, pts: np.ndarray) -> float:
        path = np.vstack([start[None, :], pts])
        return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())

    def _probe(self, block: GBlock, start: np.ndarray) -> Generator[Wait, None, int]:
        """G38.x: a plotter has no probe, so the move always completes without contact."""
        yield SYNC
        if self._check:
            return 0
        payload = self._payload(rapid=False)
        code = yield from self._line_motion(start, block.target, rapid=False, feed=block.feed, payload=payload)
        if code:
            return code
        yield SYNC
        self.gc.position = self._mpos.copy()
        pos = ",".join(fmt_float(v, 3) for v in self._mpos)
        self._emit(f"[PRB:{pos}:0]\r\n".encode())
        if not block.probe_no_error:
            self._emit(b"ALARM:5\r\n")
            self._alarm = True
        return 0

    def _jog(self, block: GBlock) -> Generator[Wait, None, int]:
        """jog_execute: soft limits give error:15 instead of an alarm; the jog runs in the Jog state."""
        if self._flag(20) and self._outside_travel(block.target):
            return STATUS["travel_exceeded"]
        yield ROOM
        payload = MovePayload(self.gc.spindle, self.gc.spindle_speed, float(self.gc.wco()[2]), False)
        b = Block(self.gc.position.copy(), block.target.copy(), jog=True, feed=block.feed, data=payload)
        if self.planner.add(b, self._now):
            self._jogging = True
        self.gc.position = block.target.copy()
        return 0

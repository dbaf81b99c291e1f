"""GRBL 1.1h pen-plotter simulator (model ``grbl``), one concern per module, from the wire down.

``controller``  ``GrblSimulator`` (serial RX buffer, line protocol, faults), ``OPTIONS`` and ``create``
``system``      the ``$`` command table and its handlers; ``settings``: the ``$n`` settings and their checks
``realtime``    the real-time byte table (``?``, ``!``, ``~``, 0x18, overrides, door, jog cancel)
``execute``     executing a checked block (gc_execute_line STEP 4); ``gcode``: parsing it (STEPs 1-3)
``modal``       the parser state, the checked block, status codes, GRBL's number formats
``reports``     the welcome and help lines, status report, ``$G``, ``$#``
``machine``     motion on the clock, holds, soft limits, homing, machine state, pen and paper
``planner``     GRBL's look-ahead planner timing; ``arcs``: ``mc_arc``'s chords
"""

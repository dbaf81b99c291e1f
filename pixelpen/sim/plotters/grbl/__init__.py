"""The GRBL 1.1 simulator: real-time bytes, G-code parsing, the planner and the machine."""
